//! The Newton damping schedule (`sim.newton_damping`) on a joint whose bodies are too heavy for
//! damping alone to make rapier's step Newton's (dt^2 k < I): the joint starts each step with
//! the velocity that lands the undamped step on Newton's point, and a pinned strut held by two
//! springs settles in tens of steps on the plain dynamics' equilibrium.

use crate::common;
use common::node;
use std::path::Path;
use tensegrity_testbed::report::ScenarioReport;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

/// A strut pinned to the ground by a revolute joint about z at its foot (damping 0.5), its tip
/// held by two springs to fixed points: one coordinate, its stiffness of the order of the
/// springs' 50-80 N/m times 1 m^2 against an inertia about the pin of about 0.3 kg m^2, so
/// dt^2 k / I is of the order of 1e-2 at dt = 0.005 s.
fn pinned_strut(newton_damping: bool) -> String {
    format!(
        r#"name = "pinned strut with two springs"
mechanism = "custom"
[sim]
dt = 0.005
newton_damping = {newton_damping}
[settle]
speed_tol = 1e-12
window = 10
residual_force_tol = 1e-9
residual_torque_tol = 1e-9
max_time = 100.0
[actuation]
points = [ {{}} ]
[structure]
[[structure.bodies]]
name = "ground"
fixed = true
nodes = {{ O = [0.0, 0.0, 0.0], L = [-1.0, 1.0, 0.0], R = [1.0, 1.2, 0.0] }}
[[structure.bodies]]
name = "strut"
mass = 1.0
inertia = [0.1, 0.1, 0.01]
nodes = {{ P = [0.0, 0.0, 0.0], Q = [0.3, 1.0, 0.0] }}
[[structure.struts]]
name = "strut"
a = "P"
b = "Q"
[[structure.springs]]
name = "left"
a = "L"
b = "Q"
stiffness = 50.0
length = 0.5
[[structure.springs]]
name = "right"
a = "Q"
b = "R"
stiffness = 80.0
length = 0.6
[[structure.joints]]
name = "pin"
kind = "revolute"
parent = "ground"
child = "strut"
at = "O"
axis = [0.0, 0.0, 1.0]
damping = 0.5
"#
    )
}

fn run_text(text: &str) -> ScenarioReport {
    let sc = scenario::parse(Path::new("pinned.toml"), text).expect("scenario is valid");
    run(&sc, &RunOptions::default())
}

/// Steps of the pinned strut to settle with the schedule, at most (measured 14: 4 moving and
/// the 10-step quiet window; 2155 before the short-step velocity, 6538 without the schedule).
const PINNED_MAX_STEPS: u64 = 50;

/// With the schedule the pinned strut settles in at most 50 steps (the plain dynamics: over
/// 1000), its tip within 1e-9 m of where the plain dynamics put it, residual below 1e-9.
#[test]
fn a_heavy_pinned_strut_settles_in_tens_of_steps_on_the_dynamics_own_equilibrium() {
    let fast = run_text(&pinned_strut(true));
    let plain = run_text(&pinned_strut(false));
    assert!(fast.passed && plain.passed, "{:?} {:?}", fast.error, plain.error);
    assert!(fast.settle.steps <= PINNED_MAX_STEPS, "scheduled: {} steps", fast.settle.steps);
    assert!(plain.settle.steps > 20 * PINNED_MAX_STEPS, "plain: {} steps", plain.settle.steps);
    let (q_fast, q_plain) = (node(&fast, "Q"), node(&plain, "Q"));
    for k in 0..3 {
        assert!((q_fast[k] - q_plain[k]).abs() <= 1e-9, "Q[{k}]: {} scheduled, {} plain", q_fast[k], q_plain[k]);
    }
    assert!(fast.points[0].residual_force_n <= 1e-9, "residual {} N", fast.points[0].residual_force_n);
}
