//! The scale families of `tensegrity bench --scale` (src/bench/scale/): each family's closed
//! form is an equilibrium of the testbed's force laws, and small members of each family settle
//! to it from their perturbed starts.

use tensegrity_testbed::bench::scale::{self, furet, icosahedron, prism, spine, tower, Case, ScaleCase, DEFAULT_CAPS};
use tensegrity_testbed::mechanisms::furet2018::analytic::{self, Params};
use tensegrity_testbed::settings::SimSettings;
use tensegrity_testbed::sim::Simulation;
use tensegrity_testbed::structure::Structure;

/// Largest residual force or torque [N, N m] of `s` as drawn, its actuators at `commands`.
fn residual_as_drawn(s: &Structure, settings: &SimSettings, commands: &[f64]) -> f64 {
    let mut sim = Simulation::new(s, settings).expect("the structure builds");
    if !commands.is_empty() {
        sim.set_commands(commands);
    }
    let r = sim.snapshot().forces.residual.expect("a residual is computed");
    r.max_force_n.max(r.max_torque_nm)
}

/// The case's structure redrawn at its closed form: its residual as drawn.
fn assert_equilibrium(name: &str, s: &Structure, case: &Case) {
    let r = residual_as_drawn(s, &case.settings, &case.commands);
    assert!(r <= 1e-9, "{name}: residual {r:e} as drawn at the closed form");
}

/// Prisms of 3, 4 and 7 struts drawn at the twist pi/2 + pi/n with the rest lengths of the
/// force densities side : polygon = 1 : 1 / (2 sin(pi/n)) carry no residual force above 1e-9 N.
#[test]
fn a_prism_drawn_at_its_closed_form_twist_is_an_equilibrium() {
    for n in [3, 4, 7] {
        let s = prism(n, std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / n as f64);
        assert_equilibrium(&format!("prism {n}"), &s, &prism::case(n));
    }
}

/// The icosahedron drawn as the expanded octahedron (pairs L/2 apart, cables sqrt(6)/4 L)
/// carries no residual above 1e-9 N, and its drawn cable / strut length ratio is sqrt(6)/4
/// within 1e-15.
#[test]
fn the_expanded_octahedron_is_the_icosahedrons_equilibrium() {
    let s = icosahedron::icosahedron(0.5 * icosahedron::STRUT_LENGTH_M);
    assert_equilibrium("icosahedron", &s, &icosahedron::case());
    for (_, c) in s.members_of(tensegrity_testbed::structure::MemberKind::Cable) {
        let (a, b) = c.ends();
        let l = tensegrity_testbed::structure::distance(s.nodes[a].position, s.nodes[b].position);
        let ratio = l / icosahedron::STRUT_LENGTH_M;
        assert!((ratio - icosahedron::cable_to_strut_ratio()).abs() <= 1e-15, "{}: {ratio}", c.name);
    }
}

/// The force density design of towers of 1 to 5 stages: sum q (x_j - x_i) vanishes at every
/// free node within 1e-9 N, every stage cable is in tension and every strut in compression,
/// and the stage-to-stage members carry no force (|q| below 1e-12 of the largest).
#[test]
fn the_tower_force_densities_balance_every_free_node() {
    for m in 1..=5 {
        let d = tower::design(m).unwrap();
        let r = tower::node_residual(&d, &d.q);
        assert!(r <= 1e-9, "{m} stages: node residual {r:e} N");
        let largest = d.q.iter().fold(0.0f64, |a, q| a.max(q.abs()));
        for ((kind, a, b), q) in d.members.iter().zip(&d.q) {
            match kind {
                tower::Kind::Strut => assert!(*q < 0.0, "{m} stages: strut {a}-{b} q = {q}"),
                k if k.is_cable() => assert!(*q > 0.0, "{m} stages: cable {a}-{b} q = {q}"),
                _ => assert!(q.abs() <= 1e-12 * largest, "{m} stages: link {a}-{b} q = {q}"),
            }
        }
    }
}

/// Towers of 1 to 3 stages, drawn as designed with the rest lengths from the force densities,
/// carry no residual above 1e-9 N in the testbed's force laws.
#[test]
fn a_tower_drawn_as_designed_is_an_equilibrium() {
    for m in 1..=3 {
        let d = tower::design(m).unwrap();
        assert_equilibrium(&format!("tower {m}"), &tower::structure(&d, 0.0), &tower::case(m).unwrap());
    }
}

/// Chains of 1 to 3 furet2018 X modules drawn at the commanded theta carry no residual above
/// 1e-9 N, and their drawn end point is Eq. 2's within 1e-12 m.
#[test]
fn a_furet_chain_drawn_at_its_commands_is_an_equilibrium_at_eq2() {
    let p = Params::PAPER;
    for n in 1..=3 {
        let thetas = vec![furet::THETA_RAD; n];
        let (s, ends) = furet::chain(&p, &thetas);
        assert_equilibrium(&format!("furet {n}"), &s, &furet::case(n));
        let (x, y) = analytic::direct_kinematics_n(&p, &thetas);
        let e = s.nodes[ends[n - 1]].position;
        assert!((e[0] - x).hypot(e[1] - y) <= 1e-12, "furet {n}: drawn end point {e:?}, Eq. 2 ({x}, {y})");
    }
}

fn assert_settles(c: &ScaleCase, tolerance: f64) {
    let what = format!("{} {}", c.family, c.size);
    assert!(c.settled, "{what}: not settled ({:?})", c.note);
    assert!(c.steps <= 50, "{what}: {} steps", c.steps);
    assert!(c.error <= tolerance, "{what}: error {:e} {}", c.error, c.error_unit);
    assert!(c.residual <= 1e-9, "{what}: residual {:e}", c.residual);
}

/// Small members of every family settle from their perturbed starts in at most 50 steps
/// (measured 11 to 19) to the closed form within 1e-9 (m, or rad for the prisms' twist;
/// measured 1e-16 to 1e-14).
#[test]
fn small_members_of_every_family_settle_to_their_closed_form() {
    for (family, max_struts) in [("prism", 4), ("icosahedron", 6), ("tower", 8), ("furet", 10), ("spine", 20)] {
        let cases = scale::cases(family, max_struts).unwrap();
        assert!(!cases.is_empty(), "{family}: no case up to {max_struts} struts");
        for case in cases {
            assert_settles(&scale::run_case(&case, &DEFAULT_CAPS).unwrap(), 1e-9);
        }
    }
}

/// Spines of 1 to 4 vertebrae drawn as designed carry no residual above 1e-9 N (the saddle
/// tension and the vertical springs' V = T (2 c - h) / l_s balance every vertebra), and the
/// vertical springs' tension is 10 N x 0.2 / sqrt(0.54) within 1e-12.
#[test]
fn a_spine_drawn_as_designed_is_an_equilibrium() {
    assert!((spine::vertical_tension_n() - 10.0 * 0.2 / 0.54f64.sqrt()).abs() <= 1e-12);
    for m in 1..=4 {
        assert_equilibrium(&format!("spine {m}"), &spine::spine(m, 0.0), &spine::case(m));
    }
}

/// Chains of 10, 30 and 100 furet2018 X modules (30, 90 and 300 links: cut into plain bodies
/// held by impulse joints, the actuated ones locked at their commands, closed by the sparse
/// projection with its kept factorization) settle from their perturbed starts within 50 steps
/// (measured 11 to 18) to Eq. 2's chained direct kinematics within 1e-12 m (measured 1.7e-14
/// to 2.2e-13), with every residual force and torque below 1e-9.
#[test]
fn long_x_chains_settle_to_eq2_within_1e_12_m() {
    for n in [10, 30, 100] {
        assert_settles(&scale::run_case(&furet::case(n), &DEFAULT_CAPS).unwrap(), 1e-12);
    }
}

/// A chain of 5 X modules is cut into plain bodies (15 links) and is rigid at its commands
/// (its 90 coordinates meet 90 joint rows). Settled, a further plain step leaves its end point
/// where it was to the last bit: the projection puts every body back at its closed
/// configuration and stops it. A new command (theta 0.1 to 0.12 rad) is not undone by that:
/// after it the end point is within 1e-12 m of Eq. 2 at the new theta (0.1 m away from the old).
#[test]
fn a_rigid_cut_chain_rests_exactly_and_follows_a_new_command() {
    let (n, p) = (5, Params::PAPER);
    let case = furet::case(n);
    let mut sim = scale::settle(&case.start, &case.settings, &case.commands, &DEFAULT_CAPS).unwrap().sim;
    let end = case.target[0].0;
    let rested = sim.node_position(end);
    sim.step().unwrap();
    assert_eq!(sim.node_position(end), rested, "a rigid chain at rest does not move");
    let theta = 0.12;
    sim.set_commands(&vec![analytic::base_joint_angle_a(&p, theta); n]);
    for _ in 0..3 {
        sim.step().unwrap();
    }
    let (x, y) = analytic::direct_kinematics_n(&p, &vec![theta; n]);
    let moved = scale::max_distance(&[sim.node_position(end)], &[[x, y, 0.0]]);
    let from_old = scale::max_distance(&[rested], &[[x, y, 0.0]]);
    assert!(moved <= 1e-12, "{moved:.3e} m from Eq. 2 at the new command");
    assert!(from_old > 0.01, "the new command moves the end point ({from_old:.3e} m)");
}

/// A settled 5-X chain cut into plain bodies follows a command jump on its assembly mode
/// whether the projection takes the jump at once or in increments (`sim/continuation.rs`): a
/// jump of 0.05 rad (first contraction 0.16, taken at once) and one of 0.35 rad (taken in
/// increments) each leave the end point within 1e-12 m of Eq. 2 at the new theta.
#[test]
fn a_cut_chain_follows_small_and_large_command_jumps_on_its_assembly_mode() {
    let (n, p) = (5, Params::PAPER);
    let case = furet::case(n);
    let end = case.target[0].0;
    for theta in [0.15, 0.45] {
        let mut sim = scale::settle(&case.start, &case.settings, &case.commands, &DEFAULT_CAPS).unwrap().sim;
        sim.set_commands(&vec![analytic::base_joint_angle_a(&p, theta); n]);
        sim.step().unwrap();
        let (x, y) = analytic::direct_kinematics_n(&p, &vec![theta; n]);
        let error = scale::max_distance(&[sim.node_position(end)], &[[x, y, 0.0]]);
        assert!(error <= 1e-12, "theta {theta}: {error:.3e} m from Eq. 2");
    }
}

/// A settled 2-X chain (one multibody whose loops close inside it) goes back to its loops'
/// rest after every step (`sim/closure_rest.rs`): ten more steps leave every node where it
/// was to the bit, its end point within 1e-12 m of Eq. 2.
#[test]
fn a_settled_looped_multibody_stays_at_its_closure_rest_to_the_bit() {
    let case = furet::case(2);
    let mut sim = scale::settle(&case.start, &case.settings, &case.commands, &DEFAULT_CAPS).unwrap().sim;
    let settled = sim.node_positions();
    for _ in 0..10 {
        sim.step().unwrap();
    }
    assert_eq!(sim.node_positions(), settled, "the nodes moved at rest");
    let (end, target) = case.target[0];
    let error = scale::max_distance(&[sim.node_position(end)], &[target]);
    assert!(error <= 1e-12, "{error:.3e} m from Eq. 2");
}

/// The growth exponent is the slope of ln(wall) against ln(struts): wall = 1e-6 struts^2.5
/// gives 2.5 within 1e-12.
#[test]
fn the_growth_exponent_is_the_log_log_slope() {
    let case = |struts: usize| ScaleCase {
        family: "synthetic",
        size: struts,
        struts,
        cables: 0,
        springs: 0,
        joints: 0,
        settled: true,
        steps: 1,
        wall_s: 1e-6 * (struts as f64).powf(2.5),
        rss_before_kib: None,
        peak_rss_kib: None,
        error: 0.0,
        error_unit: "m",
        residual: 0.0,
        note: None,
        settled_nodes: Vec::new(),
    };
    let cases: Vec<ScaleCase> = [3, 10, 100, 300, 1000].into_iter().map(case).collect();
    let e = scale::growth_exponent(&cases).unwrap();
    assert!((e - 2.5).abs() <= 1e-12, "exponent {e}");
}

/// The aligned distance ignores a rigid motion: a set turned by 0.7 rad about (1, 2, 3) and
/// moved by (4, -5, 6) m is 0 m (within 1e-12) from the original, and a node moved by 1e-3 m
/// reads below 1e-3 m and above 0.
#[test]
fn the_aligned_distance_ignores_rigid_motions() {
    let pts = icosahedron::icosahedron(0.5).nodes.iter().map(|n| n.position).collect::<Vec<_>>();
    let r = nalgebra::Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(nalgebra::Vector3::new(1.0, 2.0, 3.0)),
        0.7,
    );
    let moved: Vec<[f64; 3]> =
        pts.iter().map(|p| (r * nalgebra::Vector3::from(*p) + nalgebra::Vector3::new(4.0, -5.0, 6.0)).into()).collect();
    assert!(scale::aligned_distance(&moved, &pts) <= 1e-12);
    let mut bent = pts.clone();
    bent[3][0] += 1e-3;
    let d = scale::aligned_distance(&bent, &pts);
    assert!(d > 0.0 && d < 1e-3, "{d}");
}

use crate::common;

/// Every family's members up to 6 struts go through MuJoCo in the same run
/// (`benches/peers/mujoco/scale_peer.py` on the testbed's MJCF export): MuJoCo settles every
/// one, with no export warning, within 1e-5 of the closed form (measured 4e-14 rad to 7e-7 m),
/// and the testbed's error is below a tenth of MuJoCo's on each (measured 1e-2 to 5e-10).
#[test]
fn mujoco_settles_the_small_members_side_by_side() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let dir = std::env::temp_dir().join(format!("tensegrity-test-scale-peer-{}", std::process::id()));
    let command = [py, "benches/peers/mujoco/scale_peer.py".to_string()];
    let out = scale::peer::compare(&scale::FAMILIES, 6, &DEFAULT_CAPS, &command, &dir, &|line| eprintln!("{line}"));
    let _ = std::fs::remove_dir_all(&dir);
    let (reports, rows) = out.unwrap();
    // Every family reports; the spine's smallest member has 8 struts, so it has no row here.
    assert_eq!(reports.len(), scale::FAMILIES.len());
    assert_eq!(rows.len(), 6, "prisms 3, 4, 6, the icosahedron, a 1-stage tower, a 1-module chain");
    for r in &rows {
        let what = format!("{} {}", r.family, r.size);
        assert!(r.testbed_settled && r.peer_settled, "{what}: settled {} / {}", r.testbed_settled, r.peer_settled);
        assert!(r.peer_notes.is_empty(), "{what}: {:?}", r.peer_notes);
        assert!(r.peer_error <= 1e-5, "{what}: MuJoCo error {:e} {}", r.peer_error, r.error_unit);
        assert!(r.ratio_error <= 0.1, "{what}: testbed / MuJoCo error {:e}", r.ratio_error);
    }
}

/// The command line: an unknown family is bad input (exit 2, named in the message), and
/// `--json` lists each family's cases up to `--max-struts`.
#[test]
fn bench_scale_cli_selects_families_and_sizes() {
    let (code, _, err) = common::tensegrity(&["bench", "--scale", "--family", "cube"]);
    assert_eq!(code, 2);
    assert!(err.contains("no scale family 'cube'"), "{err}");
    let (code, out, _) = common::tensegrity(&["bench", "--scale", "--family", "prism", "--max-struts", "4", "--json"]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let cases = v["scale"][0]["cases"].as_array().unwrap();
    let struts: Vec<u64> = cases.iter().map(|c| c["struts"].as_u64().unwrap()).collect();
    assert_eq!(struts, [3, 4]);
    assert!(cases.iter().all(|c| c["settled"] == true && c["error_unit"] == "rad"));
    // Memory: the peak resident set of a case is at least the one before it.
    let kib = |c: &serde_json::Value, k: &str| c[k].as_u64().unwrap();
    assert!(cases.iter().all(|c| kib(c, "peak_rss_kib") >= kib(c, "rss_before_kib")), "{out}");
}

/// Physical motion beside MuJoCo (`bench --scale --motion --peer`; without `--peer`, or with a
/// family that has constraints, it is bad input): the 3- and 4-strut prisms
/// move undamped for 0.5 s; against MuJoCo's RK4 at 5e-5 s both sides' errors halve with the
/// time step (first order: each ratio within 1.8-2.2, measured 1.99-2.03), the testbed's
/// within 5 % of MuJoCo's at every step (both are semi-implicit Euler on the same equations
/// of motion; measured equal to 3 digits), and the cost at the testbed's error at 1 ms is
/// found within MuJoCo's runs. The judged motion is fourth order against the same reference.
#[test]
fn motion_beside_mujoco_converges_at_first_order_on_both_sides() {
    let (code, _, err) = common::tensegrity(&["bench", "--scale", "--motion", "--family", "prism"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--motion needs --peer"), "{err}");
    let (code, _, err) = common::tensegrity(&["bench", "--scale", "--motion", "--peer", "--family", "furet"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--motion covers the families whose equations MuJoCo shares"), "{err}");
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let dir = std::env::temp_dir().join(format!("tensegrity-test-scale-motion-{}", std::process::id()));
    let command = [py, "benches/peers/mujoco/scale_peer.py".to_string()];
    let out = scale::motion::compare(&["prism"], 4, &command, &dir, &|line| eprintln!("{line}"));
    let _ = std::fs::remove_dir_all(&dir);
    let cases = out.unwrap();
    assert_eq!(cases.len(), 2, "prisms 3 and 4");
    for c in &cases {
        for side in [&c.testbed, &c.peer] {
            for w in side.windows(2) {
                let ratio = w[0].error_m / w[1].error_m;
                assert!((1.8..=2.2).contains(&ratio), "prism {}: error ratio {ratio} at dt {}", c.size, w[1].dt_s);
            }
        }
        for (a, b) in c.testbed.iter().zip(&c.peer) {
            assert!(
                (a.error_m / b.error_m - 1.0).abs() <= 0.05,
                "prism {}: {} against {}",
                c.size,
                a.error_m,
                b.error_m
            );
        }
        assert!(c.ratio_at_equal_error.is_some_and(|r| r > 0.0), "prism {}: {:?}", c.size, c.ratio_at_equal_error);
        // The judged motion (extrapolated over the step) against the same reference: fourth
        // order (measured 6.35e-9, 3.97e-10, 2.48e-11, 1.57e-12 m for prism 3 at dt = 4, 2, 1,
        // 0.5 ms: order 4.0), and MuJoCo's RK4 and Euler runs there to compare it with.
        let steps: Vec<f64> = c.judged.iter().map(|r| r.dt_s).collect();
        let errors: Vec<f64> = c.judged.iter().map(|r| r.error_m).collect();
        let order = common::fitted_order(&steps, &errors);
        assert!(order >= 3.5, "prism {}: judged order {order}: {errors:?}", c.size);
        assert_eq!(c.peer_rk4.len(), scale::motion::INTEGRATOR_DT_S.len(), "prism {}", c.size);
        assert_eq!(c.peer_euler.len(), scale::motion::INTEGRATOR_DT_S.len(), "prism {}", c.size);
    }
}
