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

/// An actuated revolute joint with a torsion spring is a servo: its command is the spring's
/// rest angle and the joint turns against it. A 1 kg, 1 m bar on a servo of 50 N m/rad under
/// gravity settles where the spring holds its weight, k (q - c) = -m g (L / 2) cos q (solved
/// here by Newton's method), within 1e-9 rad at the commands 0 and 0.3 rad.
#[test]
fn a_servo_holds_its_load_by_its_spring_about_its_command() {
    const K_NM_PER_RAD: f64 = 50.0;
    const WEIGHT_MOMENT_NM: f64 = 1.0 * 9.81 * 0.5;
    let text = super::common::PINNED_STRUT
        .replace("points = [ {} ]", "points = [ { c = 0.0 }, { c = 0.3 } ]")
        .replace("gravity = [0.0, 0.0, 0.0]", "gravity = [0.0, -9.81, 0.0]")
        .replace("[[structure.springs]]\nname = \"k\"\na = \"Q\"\nb = \"S\"\nstiffness = 10.0\nlength = 0.5\n", "")
        .replace(
            "damping = 0.5\n",
            "damping = 0.5\ntorsion_stiffness = 50.0\n[[structure.actuators]]\nsymbol = \"c\"\njoint = \"pin\"\n",
        );
    let sc = tensegrity_testbed::scenario::parse(std::path::Path::new("servo.toml"), &text).expect("valid");
    let report = tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default());
    assert_eq!(report.points.len(), 2, "{}", report.verdict_line());
    for (point, command) in report.points.iter().zip([0.0_f64, 0.3]) {
        assert!(point.settled, "command {command}");
        let q = point.simulated["Q.y"].atan2(point.simulated["Q.x"]);
        let mut expected = command;
        for _ in 0..50 {
            let (f, df) = (
                K_NM_PER_RAD * (expected - command) + WEIGHT_MOMENT_NM * expected.cos(),
                K_NM_PER_RAD - WEIGHT_MOMENT_NM * expected.sin(),
            );
            expected -= f / df;
        }
        eprintln!("command {command} rad: settled at {q} rad, the balance's root {expected} rad");
        assert!((q - expected).abs() <= 1e-9, "command {command}: {q} against {expected}");
    }
}

/// F6 of issue 60: a strut hanging from the ground on a ball joint that states no damping is
/// damped by `body_damping` as a free body is (rapier damps a multibody link through its degrees
/// of freedom only: it had swung for the whole 30 s). Drawn 37 degrees off the vertical, it
/// settles hanging straight down, its tip within 1e-9 m of (0, 0, -1).
#[test]
fn a_strut_on_an_undamped_ball_joint_settles_under_body_damping() {
    let text = r#"name = "strut on a ball joint"
mechanism = "custom"
[sim]
dt = 0.002
body_damping = 5.0
[settle]
speed_tol = 1e-10
residual_force_tol = 1e-8
residual_torque_tol = 1e-8
max_time = 30.0
[actuation]
points = [ {} ]
[structure]
gravity = [0, 0, -9.81]
[[structure.bodies]]
name = "ground"
fixed = true
nodes = { O = [0, 0, 0] }
[[structure.bodies]]
name = "bar"
mass = 1.0
nodes = { B = [0, 0, 0], T = [0.6, 0, -0.8] }
[[structure.joints]]
name = "ball"
kind = "spherical"
parent = "ground"
child = "bar"
at = "B"
[[structure.struts]]
name = "bar"
a = "B"
b = "T"
[expect]
verdict = "pass"
"#;
    let sc = tensegrity_testbed::scenario::parse(std::path::Path::new("ball.toml"), text).expect("valid");
    let report = tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default());
    assert!(report.passed && report.points[0].settled, "{}", report.verdict_line());
    let tip = crate::common::node(&report, "T");
    let off = tip[0].hypot(tip[1]).hypot(tip[2] + 1.0);
    assert!(off <= 1e-9, "tip at {tip:?} ({off:e} m from straight down)");
}

/// A bead on three chained prismatic slides (x, y, z, the first two on 1 mg links), held by a
/// stiff spring along the slides' diagonal and two soft ones: each joint's Newton step with the
/// others held is a Jacobi iteration that the diagonal coupling makes diverge (F2 of issue 60:
/// 6000 accelerated steps and 11 J of kinetic energy left). The schedule now stops once it has
/// not lowered the joints' largest force to 0.1 of itself over 200 steps, and the joints'
/// damping finishes the
/// settle: it settles where the physical dynamics alone do, within 1e-9 m.
fn slider_chain(newton_damping: bool) -> String {
    let head =
        common::one_point_head("a bead on three slides").replace("gravity = [0, 0, 0]", "gravity = [0, 0, -9.81]");
    head + &format!("[sim]\nnewton_damping = {newton_damping}\n\n")
        + r#"[[structure.bodies]]
name = "ground"
fixed = true
nodes = { A = [0.6, 0.6, 0.6], B = [1, 0.3, -1], C = [0, -1, 1], O = [0, 0, 0] }

[[structure.bodies]]
name = "sx"
mass = 1e-6
inertia = [1e-8, 1e-8, 1e-8]
nodes = { S = [0, 0, 0] }

[[structure.bodies]]
name = "sy"
mass = 1e-6
inertia = [1e-8, 1e-8, 1e-8]
nodes = { S2 = [0, 0, 0] }

[[structure.bodies]]
name = "bead"
mass = 0.5
inertia = [1e-2, 1e-2, 1e-2]
nodes = { P = [0, 0, 0] }

[[structure.joints]]
name = "slide_x"
kind = "prismatic"
parent = "ground"
child = "sx"
at = "O"
axis = [1, 0, 0]
damping = 5.0

[[structure.joints]]
name = "slide_y"
kind = "prismatic"
parent = "sx"
child = "sy"
at = "S"
axis = [0, 1, 0]
damping = 5.0

[[structure.joints]]
name = "slide_z"
kind = "prismatic"
parent = "sy"
child = "bead"
at = "S2"
axis = [0, 0, 1]
damping = 5.0

[[structure.springs]]
name = "diagonal"
a = "A"
b = "P"
stiffness = 2000.0
length = 0.5

[[structure.springs]]
name = "right"
a = "B"
b = "P"
stiffness = 10.0
length = 0.5

[[structure.springs]]
name = "back"
a = "C"
b = "P"
stiffness = 10.0
length = 0.5
"#
}

#[test]
fn a_newton_schedule_that_does_not_converge_hands_the_settle_to_the_dynamics() {
    let settle = |newton: bool| {
        let sc = scenario::parse(Path::new("slides.toml"), &slider_chain(newton)).expect("valid");
        run(&sc, &RunOptions::default())
    };
    let (scheduled, physical) = (settle(true), settle(false));
    assert!(scheduled.points[0].settled, "{}", scheduled.verdict_line());
    let (p, q) = (node(&scheduled, "P"), node(&physical, "P"));
    assert!((0..3).all(|k| (p[k] - q[k]).abs() <= 1e-9), "{p:?} against {q:?}");
}

/// A 1000 kg block on a slide, 0.1 m from where its spring (1e4 N/m) holds it, at dt = 1 ms:
/// too heavy for damping to make the step Newton's, so the schedule starts it at 100 m/s,
/// 5e6 J, which the divergence guard (1e6 J) had read as a blow-up at tick 1 (F3 of issue 60).
/// A scheduled step's velocities are the accelerator's: the block settles at x = -0.1 m within
/// 1e-9 m.
#[test]
fn a_heavy_bodys_newton_start_velocity_is_no_divergence() {
    let text = common::one_point_head("a heavy block on a slide")
        + r#"[sim]
dt = 0.001

[[structure.bodies]]
name = "ground"
fixed = true
nodes = { A = [-1, 0, 0], O = [0, 0, 0] }

[[structure.bodies]]
name = "block"
mass = 1000.0
inertia = [100, 100, 100]
nodes = { P = [0, 0, 0] }

[[structure.joints]]
name = "slide"
kind = "prismatic"
parent = "ground"
child = "block"
at = "O"
axis = [1, 0, 0]
damping = 10.0

[[structure.springs]]
name = "spring"
a = "A"
b = "P"
stiffness = 1e4
length = 0.9
"#;
    let sc = scenario::parse(Path::new("block.toml"), &text).expect("valid");
    let report = run(&sc, &RunOptions::default());
    assert!(report.points[0].settled, "{}", report.verdict_line());
    assert!((node(&report, "P")[0] + 0.1).abs() <= 1e-9, "{:?}", node(&report, "P"));
}
