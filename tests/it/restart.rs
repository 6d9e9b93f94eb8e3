//! Restart in place: a built simulation restarted from another placement of its structure
//! (the next point of a grid without continuation) moves as a fresh build of that placement.

use tensegrity_testbed::mechanisms::{self, Values};
use tensegrity_testbed::settings::SimSettings;
use tensegrity_testbed::sim::Simulation;
use tensegrity_testbed::structure::Structure;

fn values(pairs: &[(&str, f64)]) -> Values {
    pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

/// ji2014 (scenarios/ji2014/grid.toml's parameters) built at actuator inputs (L3, theta1),
/// from the default start 0.5 rad off the stable root.
fn ji2014(given: &[(&str, f64)], l3: f64, theta1: f64) -> Structure {
    let m = mechanisms::find("ji2014").unwrap();
    let params = mechanisms::with_defaults(m.as_ref(), &values(given));
    m.build(&params, &values(&[("L3", l3), ("theta1", theta1)]), &Values::new()).unwrap()
}

fn settings() -> SimSettings {
    SimSettings { dt_s: 0.15, newton_damping: true, ..Default::default() }
}

/// Every node after each of 8 steps, restarted against fresh, agree within 1e-12 m (L = 1 m),
/// and the restarted start is the fresh one within 1e-12 m, for a new L3 and a new theta1.
#[test]
fn restarted_simulation_follows_a_fresh_build_within_1e_12_m() {
    let params = [("K1", 200.0), ("K2", 100.0), ("c_D1", 80.0)];
    let mut restarted = Simulation::new(&ji2014(&params, 0.4, 0.3), &settings()).unwrap();
    for _ in 0..4 {
        restarted.step().unwrap();
    }
    let next = ji2014(&params, 1.6, 2.2);
    assert!(restarted.restart_from(&next), "ji2014 at other inputs is the same structure placed anew");
    let mut fresh = Simulation::new(&next, &settings()).unwrap();
    let largest_gap = |a: &Simulation, b: &Simulation| {
        (0..next.nodes.len())
            .map(|i| tensegrity_testbed::structure::distance(a.node_position(i), b.node_position(i)))
            .fold(0.0, f64::max)
    };
    assert!(largest_gap(&restarted, &fresh) <= 1e-12, "start: {:e} m", largest_gap(&restarted, &fresh));
    assert_eq!(restarted.commands(), fresh.commands());
    for step in 1..=8 {
        restarted.step().unwrap();
        fresh.step().unwrap();
        let gap = largest_gap(&restarted, &fresh);
        assert!(gap <= 1e-12, "step {step}: nodes {gap:e} m apart");
    }
}

/// Another spring stiffness is another structure: no restart, the caller builds afresh.
#[test]
fn other_parameters_are_not_restarted() {
    let mut sim = Simulation::new(&ji2014(&[("K1", 200.0)], 0.4, 0.3), &settings()).unwrap();
    assert!(!sim.restart_from(&ji2014(&[("K1", 150.0)], 0.4, 0.3)));
}

/// mohr2011's end-effector is a plain body on cables: its placement is not a set of joint
/// coordinates, so it is not restarted.
#[test]
fn structures_with_plain_free_bodies_are_not_restarted() {
    use tensegrity_testbed::scenario::{self, Actuation};
    let sc = scenario::load(std::path::Path::new("scenarios/mohr2011/static_workspace.toml")).unwrap();
    let Actuation::Points { points, .. } = &sc.actuation else { panic!("a grid of points") };
    let m = sc.mechanism();
    let params = mechanisms::with_defaults(m.as_ref(), &sc.params);
    let s = m.build(&params, &points[0], &sc.start).unwrap();
    let mut sim = Simulation::new(&s, &sc.sim).unwrap();
    assert!(!sim.restart_from(&s));
}
