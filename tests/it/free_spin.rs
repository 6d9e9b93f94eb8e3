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
"#,
        INERTIA[0], INERTIA[1], INERTIA[2], W0[0], W0[1], W0[2]
    )
}

/// Per tick of the motion: (time [s], the body's rotation R (columns: its axes in the world),
/// kinetic energy [J]).
fn spin_table(dt: f64) -> Vec<(f64, M3, f64)> {
    let path = std::env::temp_dir().join(format!("tensegrity-spin-{}-{dt}.csv", std::process::id()));
    let _ = std::fs::remove_file(&path);
    let sc = scenario::parse(Path::new("spin.toml"), &scenario_text(dt)).expect("valid");
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

/// |L| in the world frame from consecutive poses: rapier turns the body by exp(w dt) with the
/// step's world angular velocity w, so w = log(R_{n+1} R_n^T) / dt, and L = R_n I R_n^T w.
fn momentum(r0: &M3, r1: &M3, dt: f64) -> [f64; 3] {
    let w = log(&mul(r1, &transpose(r0))).map(|x| x / dt);
    let body = mul(&transpose(r0), &[[w[0], 0.0, 0.0], [w[1], 0.0, 0.0], [w[2], 0.0, 0.0]]);
    let lb = [INERTIA[0] * body[0][0], INERTIA[1] * body[1][0], INERTIA[2] * body[2][0]];
    [0, 1, 2].map(|i| (0..3).map(|k| r0[i][k] * lb[k]).sum())
}

/// Orientation error against the exact motion at three dt, with the drift of L (its size, and
/// its largest component relative to |L|) and of the kinetic energy over the 32 s (about 20
/// turns). Measured at dt = 4, 2, 1 ms: orientation 0.275, 0.0908, 0.0378 rad (order 1.43); L's
/// direction 2.5e-2, 9.1e-3, 3.9e-3; |L| 8.9e-7, 6.8e-8, 7.0e-9; energy 1.18e-2, 3.18e-3,
/// 1.20e-3 (a steady drift, not an oscillation).
#[test]
fn a_free_body_spins_torque_free_within_the_measured_error() {
    let steps = [4e-3, 2e-3, 1e-3];
    let mut errors = Vec::new();
    let mut drifts = Vec::new();
    let mut sizes = Vec::new();
    for dt in steps {
        let rows = spin_table(dt);
        assert_eq!(rows.len() as f64, (DURATION_S / dt).round());
        let times: Vec<f64> = rows.iter().map(|r| r.0).collect();
        let exact = exact(&times);
        let e = rows.iter().zip(&exact).map(|(r, x)| angle(&mul(&transpose(x), &r.1))).fold(0.0, f64::max);
        let l0 = momentum(&rows[0].1, &rows[1].1, dt);
        let n = rows.len();
        let l1 = momentum(&rows[n - 2].1, &rows[n - 1].1, dt);
        let l_norm = l0.iter().map(|x| x * x).sum::<f64>().sqrt();
        let l_drift = (0..3).map(|i| (l1[i] - l0[i]).abs()).fold(0.0, f64::max) / l_norm;
        let l_size = (l1.iter().map(|x| x * x).sum::<f64>().sqrt() - l_norm).abs() / l_norm;
        let (k0, k1) = (rows[0].2, rows[n - 1].2);
        let energy_drift = ((k1 - k0) / k0).abs();
        let energy_spread = rows.iter().map(|r| ((r.2 - k0) / k0).abs()).fold(0.0, f64::max);
        eprintln!(
            "dt {dt}: orientation error {e:.3e} rad; L drift {l_drift:.3e} (relative, largest component); energy drift {energy_drift:.3e}, largest deviation {energy_spread:.3e}"
        );
        errors.push(e);
        drifts.push((l_drift, energy_drift));
        sizes.push(l_size);
    }
    let p = super::common::fitted_order(&steps, &errors);
    eprintln!("torque-free spin: orientation errors {errors:?} rad at dt {steps:?}, order {p:.3}; drifts (L, energy) {drifts:?}; |L| {sizes:?}");
    // A regression pin, not a property: rapier integrates the gyroscopic term explicitly (first
    // order, rescaled to |L|), which the measured order 1.43 and the 0.038 rad at 1 ms reflect;
    // no closed form gives them. Issue 45 asks for the free body's rotation without this drift.
    assert!((p - 1.43).abs() <= 0.1, "order {p}: {errors:?}");
    assert!(errors[2] <= 0.04, "{errors:?}");
    // |L| is kept (rapier rescales the explicit gyroscopic update to the momentum's size); its
    // direction and the energy drift, less at each smaller dt.
    assert!(sizes[2] <= 1e-8, "|L| {sizes:?}");
    assert!(drifts[2].0 <= 4e-3 && drifts[2].1 <= 1.3e-3, "{drifts:?}");
    assert!(drifts.windows(2).all(|d| d[1].0 < d[0].0 / 2.0 && d[1].1 < d[0].1 / 2.0), "{drifts:?}");
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
