//! Actuation followed at its real speed in a motion run (`[motion] inputs`, `[actuation]
//! waypoints`): the shipped pendulum on a driven cart
//! (`scenarios/custom/cart_pendulum_driven.toml`) against its exact equation of motion,
//! theta'' = -(g / Leq) sin(theta) - (x''(t) / Leq) cos(theta), integrated here.

use super::common::error_at;
use std::path::Path;
use tensegrity_testbed::report::{PathKind, ScenarioReport};
use tensegrity_testbed::run::{self, RunOptions};
use tensegrity_testbed::scenario;

const SHIPPED: &str = "scenarios/custom/cart_pendulum_driven.toml";
const GRAVITY_M_PER_S2: f64 = 9.81;
/// The bar's equivalent simple pendulum, I_pivot / (m L / 2) = 2 L / 3 with L = 1 m.
const LEQ_M: f64 = 2.0 / 3.0;
/// The drive's frequency [rad/s].
const DRIVE_RAD_PER_S: f64 = 2.5;
/// The exact equation's integrator step (RK4: its error ~ (h w)^4, far below the simulator's).
const RK4_STEP_S: f64 = 1e-5;

/// The shipped file's text with each (from, to) replaced once (each `from` must be there).
fn variant(edits: &[(&str, &str)]) -> String {
    super::common::edited(SHIPPED, edits)
}

/// Runs `text` writing its per-tick table: the report and, for every tick of the motion,
/// (motion time [s], theta [rad]).
fn swing(text: &str, name: &str) -> (ScenarioReport, Vec<(f64, f64)>) {
    let (report, cols) = super::common::table_columns(text, name, &["motion_time_s", "model:theta"]);
    let rows = cols[0].iter().zip(&cols[1]).filter(|(t, _)| t.is_finite()).map(|(t, q)| (*t, *q)).collect();
    (report, rows)
}

/// The cart's acceleration x''(t) for x = a sin(w t / 2)^4 = a (3/8 - cos(w t)/2 + cos(2 w t)/8).
fn cart_acceleration(a: f64, t: f64) -> f64 {
    let w = DRIVE_RAD_PER_S;
    a * w * w / 2.0 * ((w * t).cos() - (2.0 * w * t).cos())
}

/// theta and its rate at each of `times` (ascending), from rest at t = 0, by RK4.
fn exact_swing(a: f64, times: &[f64]) -> Vec<f64> {
    let f = |t: f64, y: [f64; 2]| {
        [y[1], -(GRAVITY_M_PER_S2 / LEQ_M) * y[0].sin() - cart_acceleration(a, t) / LEQ_M * y[0].cos()]
    };
    let mut y = [0.0, 0.0];
    let mut t = 0.0;
    let mut out = Vec::with_capacity(times.len());
    for &target in times {
        while t < target - 1e-15 {
            let h = RK4_STEP_S.min(target - t);
            let k1 = f(t, y);
            let k2 = f(t + h / 2.0, [y[0] + h / 2.0 * k1[0], y[1] + h / 2.0 * k1[1]]);
            let k3 = f(t + h / 2.0, [y[0] + h / 2.0 * k2[0], y[1] + h / 2.0 * k2[1]]);
            let k4 = f(t + h, [y[0] + h * k3[0], y[1] + h * k3[1]]);
            for i in 0..2 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += h;
        }
        out.push(y[0]);
    }
    out
}

/// The shipped scenario passes, its path physical, the drive named in the report, the cart
/// exactly on its path and the swing within the linear closed form's tolerance.
#[test]
fn the_shipped_driven_cart_passes_with_a_physical_path() {
    let sc = scenario::load(Path::new(SHIPPED)).expect("valid");
    let report = run::run(&sc, &RunOptions::default());
    assert!(report.passed, "{}", report.verdict_line());
    assert_eq!(report.path, PathKind::Physical);
    let m = report.motion.as_ref().expect("a motion");
    assert_eq!(m.steps_taken, 10_000);
    assert!(m.driven.as_deref().is_some_and(|d| d.contains("followed physically")), "{:?}", m.driven);
    let err = |name: &str| report.model_checks.iter().find(|c| c.name == name).unwrap().max_error;
    eprintln!("linear forced swing {:e} rad, cart {:e} m", err("linear forced swing"), err("cart on its path"));
    assert!(err("linear forced swing") <= 1e-5);
    assert!(err("cart on its path") <= 1e-12);
}

/// At a stroke of 0.3 m (swings of about 0.5 rad, where the linear form fails) the simulated
/// theta follows the nonlinear equation tick by tick within an error falling as dt^2.
#[test]
fn the_driven_swing_matches_the_exact_equation_with_an_error_falling_as_dt_squared() {
    let steps = [4e-3, 2e-3, 1e-3];
    let errors_of = |extrapolate: bool| -> Vec<f64> { steps.iter().map(|dt| swing_error(*dt, extrapolate)).collect() };
    let (stepped, extrapolated) = (errors_of(false), errors_of(true));
    let p = super::common::fitted_order(&steps, &stepped);
    eprintln!("driven swing against the exact equation at dt {steps:?}: {stepped:?} rad (order {p:.3}); extrapolated {extrapolated:?}");
    assert!((p - 2.0).abs() <= 0.1, "order {p}: {stepped:?}");
    assert!(stepped[2] <= 1e-3, "{stepped:?}");
    for e in &extrapolated {
        assert!(*e <= 1e-10, "extrapolated {extrapolated:?}");
    }
}

/// The largest error of the simulated swing at a stroke of 0.3 m against the exact equation,
/// at time step `dt_s`, the motion extrapolated over the step or rapier's steps alone [rad].
fn swing_error(dt_s: f64, extrapolate: bool) -> f64 {
    let stroke_m = 0.3;
    let text = variant(&[
        ("[sim]\ndt = 1e-3", &format!("[sim]\ndt = {dt_s}")),
        ("A = { value = 0.01", &format!("A = {{ value = {stroke_m}")),
        ("duration_s = 10.0", &format!("duration_s = 4.0\nextrapolate = {extrapolate}")),
        ("tolerance = 1e-5 ", "tolerance = 1.0 "),
    ]);
    let (report, rows) = swing(&text, &format!("{dt_s}-{extrapolate}"));
    assert!(report.error.is_none(), "{:?}", report.error);
    let times: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let exact = exact_swing(stroke_m, &times);
    let largest = exact.iter().fold(0.0_f64, |m, q| m.max(q.abs()));
    assert!(largest > 0.4, "the swing reaches {largest} rad");
    rows.iter().zip(&exact).map(|(r, q)| (r.1 - q).abs()).fold(0.0, f64::max)
}

/// Waypoints are followed at their speed too: a ramp of 0.1 m in 1 s starts the cart at
/// v = 0.1 m/s at once, an impulse that sets the bar swinging at theta' = -v / Leq, so
/// theta = -(v / (Leq w0)) sin(w0 t) until the ramp ends (small angles: 0.039 rad; met within
/// 1.2e-5 rad, 3e-4 of it, the linearisation's and the step's error).
#[test]
fn waypoints_are_followed_at_their_real_speed() {
    let text = variant(&[
        ("points = [ { x = 0.0 } ]", "waypoints = [ { t = 0.0, x = 0.0 }, { t = 1.0, x = 0.1 } ]"),
        ("inputs = { x = \"A*sin(w*t/2)^4\" }\n", ""),
        ("duration_s = 10.0", "duration_s = 0.8"),
        ("tolerance = 1e-5 ", "tolerance = 1.0 "),
        ("tolerance = 1e-12 ", "tolerance = 1.0 "),
    ]);
    let (report, rows) = swing(&text, "ramp");
    assert_eq!(report.path, PathKind::Physical);
    let (v, w0) = (0.1, (GRAVITY_M_PER_S2 / LEQ_M).sqrt());
    let amplitude = v / (LEQ_M * w0);
    let e = rows.iter().map(|(t, q)| (q + amplitude * (w0 * t).sin()).abs()).fold(0.0, f64::max);
    eprintln!("ramp: swing amplitude {amplitude:e} rad, largest error {e:e} rad");
    assert!(e <= 1e-3 * amplitude, "error {e} of {amplitude}");
}

/// Bad drives are located.
#[test]
fn bad_drives_are_located() {
    let text = variant(&[("inputs = { x = \"A*sin(w*t/2)^4\" }", "inputs = { y = \"A*t\" }")]);
    error_at(&text, "y = \"A*t\"", 0, "unknown input 'y'");
    let text = variant(&[("inputs = { x = \"A*sin(w*t/2)^4\" }", "inputs = { x = \"A*s\" }")]);
    error_at(&text, "\"A*s\"", 3, "motion input 'x'");
    let text = variant(&[("points = [ { x = 0.0 } ]", "waypoints = [ { t = 0.0, x = 0.0 }, { t = 1.0, x = 0.1 } ]")]);
    error_at(&text, "inputs = {", 9, "not both");
    let moved = variant(&[
        ("joint = \"slide\"", "node = \"Z\"\ndirection = [1, 0, 0]"),
        ("[[structure.bodies]]\nname = \"cart\"", "[[structure.bodies]]\nname = \"anchor\"\nfixed = true\nnodes = { Z = [0, 1, 0] }\n\n[[structure.bodies]]\nname = \"cart\""),
    ]);
    error_at(&moved, "inputs = {", 9, "moves a fixed node");
}
