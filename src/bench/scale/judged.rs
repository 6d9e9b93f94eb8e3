//! The judged motion of `tensegrity bench --scale --motion --peer` (issue 45): the testbed's
//! motion as its checks judge it, extrapolated over the time step (`run::levels`: h, h/2 and
//! h/4, fourth order), beside MuJoCo's RK4 and Euler at equal stepping time.
//!
//! Besides the free-body families of [`super::motion`], three structures of the dynamic
//! tutorial, each started away from its equilibrium so that it moves at once:
//!
//! - `pendulum`: the pinned bar between two springs of `pinned_bar_large_amplitude.toml`, drawn
//!   0.5 rad from its equilibrium atan2(k1 a, k2 b);
//! - `rocker`: the pinned strut between two springs of natural length of
//!   `rocker_frequency_curve.toml` (k1 = 40 N/m), drawn 0.3 rad from its equilibrium phi*, a
//!   root with no closed form ([`rocker_equilibrium`]);
//! - `spin`: a free rigid body of principal moments 1, 2, 3 kg m^2 spinning at
//!   (0.2, 4, 0.2) rad/s, near its unstable intermediate axis, with no force on it;
//! - `cart`: the pendulum on a driven cart of `cart_pendulum_driven.toml`, its cart following
//!   x(t) = A sin(w t / 2)^4 ([`SlideDrive`]) at a stroke and rate that swing the bar within
//!   the motion (A = 0.3 m, w = 5 rad/s), from rest.
//!
//! The joints' damping is released, as the bodies' is: the motion is the dynamics' own.

use super::{Case, Measure};
use crate::bench::BenchError;
use crate::settings::SimSettings;
use crate::sim::Simulation;
use crate::structure::{BodyKind, Inertia, Structure, Vec3};
use std::time::Instant;

/// The families of this file.
pub const FAMILIES: [&str; 4] = ["pendulum", "rocker", "spin", "cart"];

/// The pinned bar's file, drawn 0.5 rad (its `A`) past its equilibrium.
const PENDULUM: &str = include_str!("../../../scenarios/custom/pinned_bar_large_amplitude.toml");
/// The rocker's file.
const ROCKER: &str = include_str!("../../../scenarios/custom/rocker_frequency_curve.toml");
/// The rocker's start away from its equilibrium \[rad\] (the dynamic tutorial's).
const ROCKER_AMPLITUDE_RAD: f64 = 0.3;
/// The rocker's first spring's stiffness \[N/m\] (the file's default, inside its sweep).
const ROCKER_K1_N_PER_M: f64 = 40.0;
/// The driven cart's file.
const CART: &str = include_str!("../../../scenarios/custom/cart_pendulum_driven.toml");
/// Its drive: the stroke \[m\] and rate \[rad/s\] of x(t) = A sin(w t / 2)^4.
const CART_STROKE_M: f64 = 0.3;
const CART_RAD_PER_S: f64 = 5.0;

/// A slide actuator following x(t) = stroke sin(w t / 2)^4 (at rest at t = 0: zero rate and
/// acceleration), the body it carries, and the slide's axis (world).
#[derive(Clone, Debug)]
pub struct SlideDrive {
    pub body: String,
    pub axis: Vec3,
    pub stroke_m: f64,
    pub rad_per_s: f64,
}

impl SlideDrive {
    /// The actuator commands (the one slide's) at motion time `t_s` \[m\].
    pub fn commands_at(&self, t_s: f64) -> Vec<f64> {
        vec![self.stroke_m * (0.5 * self.rad_per_s * t_s).sin().powi(4)]
    }
}

/// The spinning body's principal moments \[kg m^2\] and mass \[kg\].
const SPIN_MOMENTS_KG_M2: Vec3 = [1.0, 2.0, 3.0];
const SPIN_MASS_KG: f64 = 1.0;
/// Its angular velocity at the start [rad/s]: mostly about the intermediate axis.
const SPIN_RAD_PER_S: Vec3 = [0.2, 4.0, 0.2];
/// Its nodes' distance from the centre of mass \[m\] (what the error measures).
const SPIN_ARM_M: f64 = 1.0;

/// The cases of `family` (one each).
pub fn cases(family: &str) -> Result<Vec<Case>, BenchError> {
    let case = match family {
        "pendulum" => from_file(
            "pendulum",
            PENDULUM,
            &[(
                "P = [\"L*cos(q_star)\", \"L*sin(q_star)\", 0]",
                "P = [\"L*cos(q_star + A)\", \"L*sin(q_star + A)\", 0]",
            )],
        )?,
        "rocker" => {
            let phi = rocker_equilibrium(ROCKER_K1_N_PER_M) + ROCKER_AMPLITUDE_RAD;
            let k1 = format!("k1 = {{ value = {ROCKER_K1_N_PER_M:?}");
            let edits = [
                ("grid = { k1 = { from = 10.0, to = 80.0, count = 8 } }", "points = [ {} ]".to_string()),
                ("phi0 = { value = \"pi/4\"", format!("phi0 = {{ value = {phi:?}")),
                ("k1 = { value = 40.0", k1),
            ];
            let edits: Vec<(&str, &str)> = edits.iter().map(|(a, b)| (*a, b.as_str())).collect();
            from_file("rocker", ROCKER, &edits)?
        }
        "spin" => spin(),
        "cart" => {
            let (a, w) = (format!("A = {{ value = {CART_STROKE_M:?}"), format!("w = {{ value = {CART_RAD_PER_S:?}"));
            let mut case =
                from_file("cart", CART, &[("A = { value = 0.01", a.as_str()), ("w = { value = 2.5", w.as_str())])?;
            let body = case.start.bodies.iter().position(|b| b.name == "cart");
            let body =
                body.ok_or_else(|| BenchError::Case("cart: the shipped file no longer has body 'cart'".into()))?;
            let drive = SlideDrive {
                body: case.start.bodies[body].name.clone(),
                axis: [1.0, 0.0, 0.0],
                stroke_m: CART_STROKE_M,
                rad_per_s: CART_RAD_PER_S,
            };
            case.drive = Some(drive);
            case
        }
        _ => return Err(BenchError::Case(format!("no judged-motion family '{family}'"))),
    };
    Ok(vec![case])
}

/// A case built from a shipped scenario's text with `edits` (each replaced once), its joints
/// undamped.
fn from_file(family: &'static str, text: &str, edits: &[(&str, &str)]) -> Result<Case, BenchError> {
    let mut text = text.to_string();
    for (from, to) in edits {
        if !text.contains(from) {
            return Err(BenchError::Case(format!("{family}: the shipped file no longer has '{from}'")));
        }
        text = text.replacen(from, to, 1);
    }
    let path = std::path::Path::new(family);
    let sc = crate::scenario::parse(path, &text).map_err(|e| BenchError::Case(format!("{family}: {e}")))?;
    let (mut start, _) = crate::export::first_structure(&sc).map_err(|e| BenchError::Case(format!("{family}: {e}")))?;
    start.joints.iter_mut().for_each(|j| j.damping = 0.0);
    Ok(Case {
        family,
        size: 1,
        start,
        settings: sc.sim.clone(),
        commands: Vec::new(),
        target: Vec::new(),
        measure: Measure::Absolute,
        spin: None,
        drive: None,
    })
}

/// The free rigid body, its six nodes at +-[`SPIN_ARM_M`] along its principal axes.
fn spin() -> Case {
    let mut s = Structure { name: "spin".into(), gravity: [0.0; 3], ..Default::default() };
    let inertia = Inertia { mass_kg: SPIN_MASS_KG, com: [0.0; 3], principal_kg_m2: SPIN_MOMENTS_KG_M2 };
    let body = s.add_body("body", BodyKind::Free, Some(inertia));
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        for sign in [1.0, -1.0] {
            let mut p = [0.0; 3];
            p[axis] = sign * SPIN_ARM_M;
            s.add_node(&format!("{name}{}", if sign > 0.0 { "+" } else { "-" }), body, p);
        }
    }
    Case {
        family: "spin",
        size: 1,
        start: s,
        settings: SimSettings::default(),
        commands: Vec::new(),
        target: Vec::new(),
        measure: Measure::Absolute,
        spin: Some((body, SPIN_RAD_PER_S)),
        drive: None,
    }
}

/// The rocker's equilibrium angle phi* \[rad\] at first-spring stiffness `k1`: the root of
/// V'(phi) near pi/4, V = k1 (|P - U| - l1)^2 / 2 + k2 (|P - V| - l2)^2 / 2 with P = L (cos phi,
/// sin phi), U = (0, a), V = (b, 0) (the file's numbers), by Newton's method on central
/// differences of V.
pub fn rocker_equilibrium(k1: f64) -> f64 {
    const STEP_RAD: f64 = 1e-5;
    const ITERATIONS: usize = 50;
    let (l, a, b, l1, l2, k2) = (1.0, 0.8, 0.6, 0.5, 0.4, 30.0);
    let v = |phi: f64| {
        let (x, y) = (l * phi.cos(), l * phi.sin());
        0.5 * k1 * ((x * x + (y - a).powi(2)).sqrt() - l1).powi(2)
            + 0.5 * k2 * (((x - b).powi(2) + y * y).sqrt() - l2).powi(2)
    };
    let mut phi = std::f64::consts::FRAC_PI_4;
    for _ in 0..ITERATIONS {
        let (vp, vm, v0) = (v(phi + STEP_RAD), v(phi - STEP_RAD), v(phi));
        let d1 = (vp - vm) / (2.0 * STEP_RAD);
        let d2 = (vp - 2.0 * v0 + vm) / (STEP_RAD * STEP_RAD);
        phi -= d1 / d2;
    }
    phi
}

/// The judged motion of `case` over `levels` levels (`run::MIN_LEVELS`: fourth order) for
/// `duration_s` at time step `dt`, repeated until the runs add up to
/// [`super::MIN_CASE_WALL_S`]: the judged node positions at the end, the ticks and the median
/// wall time of the steps of all the levels.
pub fn judged_run(case: &Case, dt: f64, duration_s: f64, levels: usize) -> Result<(Vec<Vec3>, u64, f64), BenchError> {
    let (positions, ticks, first) = judged_run_once(case, dt, duration_s, levels)?;
    let wall = super::median_wall(first, || Ok(judged_run_once(case, dt, duration_s, levels)?.2))?;
    Ok((positions, ticks, wall))
}

/// One judged run: as [`judged_run`], its own wall time.
fn judged_run_once(case: &Case, dt: f64, duration_s: f64, levels: usize) -> Result<(Vec<Vec3>, u64, f64), BenchError> {
    let mut sim = physical(case, dt)?;
    let ticks = (duration_s / dt).round() as u64;
    let start = Instant::now();
    let commands = |t: f64| case.drive.as_ref().map(|d| d.commands_at(t)).unwrap_or_default();
    let driven: Option<&dyn Fn(f64) -> Vec<f64>> = case.drive.as_ref().map(|_| &commands as _);
    let positions = crate::run::judged_nodes_after(&mut sim, ticks, levels, driven)?;
    Ok((positions, ticks, start.elapsed().as_secs_f64()))
}

/// The case's simulation at `dt`, undamped, on the physical path, spun if the case says so.
pub fn physical(case: &Case, dt: f64) -> Result<Simulation, BenchError> {
    let settings = SimSettings {
        dt_s: dt,
        body_damping_per_s: 0.0,
        relaxation: false,
        newton_damping: false,
        ..case.settings.clone()
    };
    let mut sim = Simulation::new(&case.start, &settings)?;
    sim.end_acceleration();
    if !case.commands.is_empty() {
        sim.set_commands(&case.commands);
    }
    if let Some((body, w)) = case.spin {
        sim.set_body_spin(body, w)?;
    }
    if case.drive.is_some() {
        sim.drive_physically()?;
    }
    Ok(sim)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rocker's phi* at k1 = 40 N/m is a stationary point of its potential: the spring
    /// torques about the pin cancel there within 1e-9 N m.
    #[test]
    fn the_rocker_equilibrium_balances_the_spring_torques() {
        let phi = rocker_equilibrium(ROCKER_K1_N_PER_M);
        let p = [phi.cos(), phi.sin()];
        let torque = |anchor: [f64; 2], k: f64, l0: f64| {
            let d = [anchor[0] - p[0], anchor[1] - p[1]];
            let len = d[0].hypot(d[1]);
            let f = k * (len - l0) / len;
            p[0] * f * d[1] - p[1] * f * d[0]
        };
        let total = torque([0.0, 0.8], ROCKER_K1_N_PER_M, 0.5) + torque([0.6, 0.0], 30.0, 0.4);
        assert!(total.abs() <= 1e-9, "torque {total} N m at phi* = {phi}");
    }
}
