//! A free rigid body spinning torque-free (`[motion] spin`): unequal principal moments
//! (1, 2, 3 kg m^2 along the world axes), no members, no gravity, started at
//! w0 = (0.3, 0.2, 4.0) rad/s: a spin about the largest axis with a small wobble. Its
//! orientation is read from six nodes at +-1 m on the body's axes; the exact motion is Euler's
//! equations with R' = R [w]x, integrated here by RK4.

use std::path::Path;
use tensegrity_testbed::report::PathKind;
use tensegrity_testbed::run::{self, RunOptions};
use tensegrity_testbed::scenario;

/// Principal moments of inertia [kg m^2], along the world axes at the start.
const INERTIA: [f64; 3] = [1.0, 2.0, 3.0];
/// The start's angular velocity [rad/s] (world frame = body frame at the start).
const W0: [f64; 3] = [0.3, 0.2, 4.0];
/// Simulated time [s]: about 20 turns of the spin.
const DURATION_S: f64 = 32.0;
/// The exact equations' RK4 step [s].
const RK4_STEP_S: f64 = 1e-4;

type M3 = [[f64; 3]; 3];

fn scenario_text(dt: f64) -> String {
    scenario_text_with(dt, "")
}

/// [`scenario_text`] with `motion` added to its `[motion]` section (`extrapolate = false`).
fn scenario_text_with(dt: f64, motion: &str) -> String {
    format!(
        r#"name = "torque-free spin"
mechanism = "custom"

[sim]
dt = {dt}

[actuation]
points = [ {{}} ]

[structure]

[[structure.bodies]]
name = "top"
mass = 1.0
inertia = [{}, {}, {}]
nodes = {{ XP = [1, 0, 0], XM = [-1, 0, 0], YP = [0, 1, 0], YM = [0, -1, 0], ZP = [0, 0, 1], ZM = [0, 0, -1] }}

[motion]
duration_s = {DURATION_S}
start = "drawn"
spin = {{ body = "top", angular_velocity = [{}, {}, {}] }}
{motion}
"#,
        INERTIA[0], INERTIA[1], INERTIA[2], W0[0], W0[1], W0[2]
    )
}

/// Per tick of the motion: (time [s], the body's rotation R (columns: its axes in the world),
/// kinetic energy [J]).
fn spin_table(dt: f64, motion: &str) -> Vec<(f64, M3, f64)> {
    let tag = motion.len();
    let path = std::env::temp_dir().join(format!("tensegrity-spin-{}-{dt}-{tag}.csv", std::process::id()));
    let _ = std::fs::remove_file(&path);
    let sc = scenario::parse(Path::new("spin.toml"), &scenario_text_with(dt, motion)).expect("valid");
    let report = run::run(&sc, &RunOptions { table: Some(path.clone().into()), ..Default::default() });
    assert!(report.error.is_none(), "{:?}", report.error);
    assert_eq!(report.path, PathKind::Physical);
    let start = report.motion.as_ref().and_then(|m| m.coordinate.clone());
    assert_eq!(start.as_deref(), Some("body 'top' spun at [0.3, 0.2, 4.0] rad/s"));
    let csv = std::fs::read_to_string(&path).expect("the table");
    let _ = std::fs::remove_file(&path);
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |c: &str| header.iter().position(|h| *h == c).unwrap_or_else(|| panic!("column {c}"));
    let t = col("motion_time_s");
    let e = col("kinetic_energy_j");
    let axes: Vec<[usize; 6]> = ["X", "Y", "Z"]
        .iter()
        .map(|a| {
            let c = |s: &str, k: &str| col(&format!("node:{a}{s}.{k}"));
            [c("P", "x"), c("P", "y"), c("P", "z"), c("M", "x"), c("M", "y"), c("M", "z")]
        })
        .collect();
    lines
        .filter_map(|l| {
            let cells: Vec<f64> = l.split(',').map(|c| c.parse::<f64>().unwrap_or(f64::NAN)).collect();
            if !cells[t].is_finite() {
                return None;
            }
            let mut r = [[0.0; 3]; 3];
            for (j, a) in axes.iter().enumerate() {
                for i in 0..3 {
                    r[i][j] = (cells[a[i]] - cells[a[i + 3]]) / 2.0;
                }
            }
            Some((cells[t], r, cells[e]))
        })
        .collect()
}

fn mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn transpose(a: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[j][i];
        }
    }
    c
}

/// The angle of the rotation R [rad].
fn angle(r: &M3) -> f64 {
    let axis = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    f64::atan2(axis.iter().map(|x| x * x).sum::<f64>().sqrt() / 2.0, (r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0)
}

/// The rotation vector of R (its axis times its angle) [rad].
fn log(r: &M3) -> [f64; 3] {
    let axis = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    let s = axis.iter().map(|x| x * x).sum::<f64>().sqrt();
    let a = angle(r);
    if s == 0.0 {
        return [0.0; 3];
    }
    axis.map(|x| x / s * a)
}

/// The exact orientation at each of `times` (ascending): Euler's equations
/// I1 w1' = (I2 - I3) w2 w3 (and cyclic) in the body frame, R' = R [w]x, by RK4.
fn exact(times: &[f64]) -> Vec<M3> {
    type State = ([f64; 3], M3);
    let f = |(w, r): &State| -> State {
        let [i1, i2, i3] = INERTIA;
        let dw = [(i2 - i3) * w[1] * w[2] / i1, (i3 - i1) * w[2] * w[0] / i2, (i1 - i2) * w[0] * w[1] / i3];
        let skew = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
        (dw, mul(r, &skew))
    };
    let add = |(w, r): &State, (dw, dr): &State, h: f64| -> State {
        let mut r2 = *r;
        for i in 0..3 {
            for j in 0..3 {
                r2[i][j] += h * dr[i][j];
            }
        }
        ([w[0] + h * dw[0], w[1] + h * dw[1], w[2] + h * dw[2]], r2)
    };
    let mut y: State = (W0, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    let mut t = 0.0;
    let mut out = Vec::with_capacity(times.len());
    for &target in times {
        while t < target - 1e-12 {
            let h = RK4_STEP_S.min(target - t);
            let k1 = f(&y);
            let k2 = f(&add(&y, &k1, h / 2.0));
            let k3 = f(&add(&y, &k2, h / 2.0));
            let k4 = f(&add(&y, &k3, h));
            let sum = add(&add(&add(&k1, &k2, 2.0), &k3, 2.0), &k4, 1.0);
            y = add(&y, &sum, h / 6.0);
            t += h;
        }
        out.push(y.1);
    }
    out
}

/// L in the world frame at the middle of three consecutive poses 2 dt apart (second order):
/// w = log(R_{n+1} R_{n-1}^T) / (2 dt), L = R_n I R_n^T w.
fn momentum(r_prev: &M3, r: &M3, r_next: &M3, dt: f64) -> [f64; 3] {
    let w = log(&mul(r_next, &transpose(r_prev))).map(|x| x / (2.0 * dt));
    let body = mul(&transpose(r), &[[w[0], 0.0, 0.0], [w[1], 0.0, 0.0], [w[2], 0.0, 0.0]]);
    let lb = [INERTIA[0] * body[0][0], INERTIA[1] * body[1][0], INERTIA[2] * body[2][0]];
    [0, 1, 2].map(|i| (0..3).map(|k| r[i][k] * lb[k]).sum())
}

/// At each dt: the largest orientation error against the exact motion [rad], the drift of L
/// over the motion (largest component relative to |L|) and of the kinetic energy (relative).
fn spin_errors(steps: &[f64], motion: &str) -> Vec<(f64, f64, f64)> {
    steps
        .iter()
        .map(|&dt| {
            let rows = spin_table(dt, motion);
            assert_eq!(rows.len() as f64, (DURATION_S / dt).round());
            let times: Vec<f64> = rows.iter().map(|r| r.0).collect();
            let exact = exact(&times);
            let e = rows.iter().zip(&exact).map(|(r, x)| angle(&mul(&transpose(x), &r.1))).fold(0.0, f64::max);
            let n = rows.len();
            let l0 = momentum(&rows[0].1, &rows[1].1, &rows[2].1, dt);
            let l1 = momentum(&rows[n - 3].1, &rows[n - 2].1, &rows[n - 1].1, dt);
            let l_norm = l0.iter().map(|x| x * x).sum::<f64>().sqrt();
            let l_drift = (0..3).map(|i| (l1[i] - l0[i]).abs()).fold(0.0, f64::max) / l_norm;
            let energy = rows.iter().map(|r| ((r.2 - rows[0].2) / rows[0].2).abs()).fold(0.0, f64::max);
            eprintln!("dt {dt} {motion}: orientation error {e:.3e} rad; L drift {l_drift:.3e}; energy {energy:.3e}");
            (e, l_drift, energy)
        })
        .collect()
}

/// A free body's rotation in physical motion is the implicit midpoint rule on its angular
/// momentum (`sim/rotation.rs`), symmetric in time: with rapier's steps alone the orientation
/// error against the exact motion over 32 s (about 20 turns) falls at second order (measured
/// at dt = 4, 2, 1 ms below), where rapier's own explicit gyroscopic term had given 0.275,
/// 0.0908, 0.0378 rad (order 1.43) with an energy drift of 1.2e-3 (now 5.40e-4, 1.35e-4,
/// 3.38e-5 rad: order 2.000); the kinetic energy and L
/// deviate at second order with no drift. Extrapolated over the step (the default), fourth order:
/// 3.9e-8 and 3.2e-9 rad at 4 and 2 ms, at 1 ms the exact reference's own RK4 floor (4.5e-9),
/// the kinetic energy kept to round-off.
#[test]
fn a_free_body_spins_torque_free_at_second_order_and_extrapolated_at_fourth() {
    let steps = [4e-3, 2e-3, 1e-3];
    let plain = spin_errors(&steps, "extrapolate = false");
    let e: Vec<f64> = plain.iter().map(|x| x.0).collect();
    let p = super::common::fitted_order(&steps, &e);
    eprintln!("rapier's steps and the midpoint rotation: orientation errors {e:?}, order {p:.3}");
    assert!((p - 2.0).abs() <= 0.1, "order {p}: {e:?}");
    // L and the kinetic energy as read at the ticks (from half-step velocities) are off at
    // second order too, no drift: 1.8e-6 and 5.9e-8 at 4 ms, a quarter of that at each halving.
    for (dt, (_, l, k)) in steps.iter().zip(&plain) {
        assert!(*l <= 2e-6 && *k <= 6e-8, "dt {dt}: L drift {l:e}, energy {k:e}");
    }
    assert!(plain.windows(2).all(|w| w[1].1 < w[0].1 / 3.5 && w[1].2 < w[0].2 / 3.5), "{plain:?}");
    let extrapolated = spin_errors(&steps, "");
    let (coarse, fine) = (extrapolated[0].0, extrapolated[1].0);
    assert!(coarse <= 1e-7 && coarse / fine >= 10.0, "extrapolated: {coarse:e} and {fine:e} rad (order 4: ratio 16)");
    // At the issue's dt = 1 ms: below 1e-7 rad (at the reference's own floor), and the kinetic
    // energy of the judged motion kept to 1e-9 (L as the step carries it: `sim/rotation.rs`).
    let (at_1ms, _, energy) = extrapolated[2];
    assert!(at_1ms <= 1e-7 && energy <= 1e-9, "at 1 ms: {at_1ms:e} rad, energy {energy:e}");
}

/// Bad spins are located.
#[test]
fn bad_spins_are_located() {
    let text = scenario_text(1e-3);
    let bad = text.replace("body = \"top\"", "body = \"tip\"");
    super::common::error_at(&bad, "\"tip\"", 0, "unknown body 'tip'");
    let bad = text.replace("angular_velocity = [0.3, 0.2, 4]", "angular_velocity = [0.3, 0.2]");
    super::common::error_at(&bad, "[0.3, 0.2]", 0, "angular_velocity is [wx, wy, wz]");
}
