//! Actuating a node directly: a node of a fixed body moved along a direction by an input
//! (`[[structure.actuators]] node = "U", direction = [0, 1, 0]`), followed tick by tick by a
//! quasi-static prediction, its holding force read from the members.

use crate::common;

use common::{node, run_file};
use std::path::Path;
use tensegrity_testbed::scenario;
use tensegrity_testbed::sim::Simulation;

const FILE: &str = "scenarios/custom/pinned_bar_moved_anchor.toml";
/// The file's a, b, k1, k2 [m, m, N/m, N/m].
const A_M: f64 = 0.8;
const B_M: f64 = 0.6;
const K1: f64 = 50.0;
const K2: f64 = 30.0;

/// At the last waypoint (u = 0.1 m) the anchor sits at (0, a + u) to round-off and the bar at
/// q = atan2(k1 (a + u), k2 b) within 1e-9 rad; along the way (800 ticks) the quasi-static
/// prediction is followed within 1e-9 rad at every tick under the Newton damping schedule (a
/// custom structure's default), and within 5e-3 rad (but not 1e-4: the damped bar lags the
/// moving anchor) by the plain dynamics.
#[test]
fn the_moved_anchor_carries_the_equilibrium_along() {
    let r = run_file(FILE);
    assert!(r.passed, "{:?}", r.failures);
    let u = node(&r, "U");
    assert!((u[1] - (A_M + 0.1)).abs() <= 1e-15 && u[0] == 0.0, "U at {u:?}");
    let p = node(&r, "P");
    let want = (K1 * (A_M + 0.1)).atan2(K2 * B_M);
    assert!((p[1].atan2(p[0]) - want).abs() <= 1e-9, "q = {}, want {want}", p[1].atan2(p[0]));
    let q = r.model_checks.iter().find(|c| c.name == "q").unwrap();
    assert!(q.ticks_compared >= 800, "{q:?}");
    assert!(q.transient_max_error <= 1e-9, "transient {}", q.transient_max_error);
    let text =
        std::fs::read_to_string(FILE).unwrap().replacen("[settle]", "[sim]\nnewton_damping = false\n\n[settle]", 1);
    let sc = scenario::parse(Path::new("plain.toml"), &text).unwrap();
    let plain = tensegrity_testbed::run::run(&sc, &Default::default());
    let q = plain.model_checks.iter().find(|c| c.name == "q").unwrap();
    assert!(plain.passed && q.transient_max_error <= 5e-3 && q.transient_max_error > 1e-4, "{q:?}");
}

/// The moved node's actuator force is what holds its body against the members, along the
/// direction: with U at rest at (0, a + u), minus the y component of spring s1's pull on U,
/// k1 (P.y - U.y) (zero free length), within 1e-12 N.
#[test]
fn the_moved_node_reports_its_holding_force() {
    let sc = scenario::load(Path::new(FILE)).unwrap();
    let s = sc.custom.as_ref().unwrap().structure.clone();
    let mut sim = Simulation::new(&s, &sc.sim).unwrap();
    sim.set_commands(&[0.25]);
    let snap = sim.snapshot();
    let (pu, pp) = (sim.node_position(s.node_id("U").unwrap()), sim.node_position(s.node_id("P").unwrap()));
    assert!((pu[1] - (A_M + 0.25)).abs() <= 1e-15, "U at {pu:?}");
    let holding = snap.actuator_force(&s, "u").unwrap();
    let pull_y = K1 * (pp[1] - pu[1]);
    assert!((holding + pull_y).abs() <= 1e-12, "holding {holding} N, pull {pull_y} N");
}

/// Bad moved nodes are errors at the entry: a node of a free body, a direction without a
/// node, a zero direction.
#[test]
fn bad_moved_nodes_are_located() {
    let text = std::fs::read_to_string(FILE).unwrap();
    let cases = [
        ("node = \"U\"", "node = \"P\"", "\"u\"\nnode", "must lie on a fixed body"),
        ("direction = [0, 1, 0]", "direction = [0, 0, 0]", "[0, 0, 0]\n\n[[quantities", "direction must not be zero"),
        ("node = \"U\"\n", "joint = \"pin\"\n", "[0, 1, 0]\n\n[[quantities", "direction goes with node"),
    ];
    for (from, to, at, msg) in cases {
        common::error_at(&text.replacen(from, to, 1), at, 0, msg);
    }
}
