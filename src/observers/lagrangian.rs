//! A motion run against the file's Lagrangian model (`[energy.trajectory]`): the `[energy]`
//! coordinates measured at every tick of the motion, the model's equations of motion
//! integrated beside them (Dormand-Prince 5(4), `file_model::integrate`) from the same start,
//! and the two compared tick by tick.
//!
//! The start is read from the simulation's own samples, so that nothing is assumed of how it
//! was displaced. rapier steps velocities, then positions (symplectic Euler): its samples q_k
//! are those of the leapfrog scheme, whose rates live at the half steps, (q_{k+1} - q_k) / dt =
//! q'(t_k + dt/2) + O(dt^2). The model therefore starts at t_{3/2} = 1.5 dt, between the first
//! two samples of the motion (ticks 1 and 2), with
//!   q(t_{3/2})  = (q_1 + q_2) / 2 - (q_3 - 2 q_2 + q_1) / 8   (Taylor, error O(dt^3)),
//!   q'(t_{3/2}) = (q_2 - q_1) / dt                            (error O(dt^2)),
//! and is compared from tick 2 on. The leapfrog's own global error is O(dt^2), so the whole
//! comparison falls as dt^2 where the model is right (`tests/it/motion.rs` shows it over three
//! time steps at 0.5 rad), and stays where it is when it is not.

use crate::file_model::energy_model::EnergySpec;
use crate::file_model::integrate::Tolerance;
use crate::file_model::spec::ErrorClass;
use crate::mechanisms::wrap_angle;
use crate::observers::motion::{corrected_for_symplectic_euler, fit_cosine};
use crate::report::{LagrangianCoordinateReport, LagrangianReport};

/// The integrator and its error control, as the report states them.
pub const METHOD: &str = "Dormand-Prince 5(4), rtol 1e-10, atol 1e-12, started at 1.5 dt from the \
    first three samples of the motion (leapfrog half-step rates), compared from tick 2";

/// Samples the model's start is read from: ticks 1, 2 and 3 of the motion.
const START_SAMPLES: usize = 3;

/// The measured `[energy]` coordinates at every tick of a motion.
#[derive(Clone, Debug, Default)]
pub struct Samples {
    /// The motion's time at each tick [s].
    pub times: Vec<f64>,
    /// The coordinates at each tick, in the order of `[[energy.coordinates]]`.
    pub coordinates: Vec<Vec<f64>>,
    /// The motion is judged extrapolated over the time step (`run/levels.rs`): its frequency has
    /// no dispersion to correct.
    pub extrapolated: bool,
}

impl Samples {
    /// Coordinate `i` at every tick, angles unwrapped (continuous through +-pi).
    fn series(&self, i: usize, class: ErrorClass) -> Vec<f64> {
        let mut out: Vec<f64> = Vec::with_capacity(self.times.len());
        for q in self.coordinates.iter().map(|c| c[i]) {
            let next = match (class, out.last()) {
                (ErrorClass::Angle, Some(prev)) => prev + wrap_angle(q - prev),
                _ => q,
            };
            out.push(next);
        }
        out
    }
}

/// The model's start at t_{3/2} from the first three samples (module docs): (time, q, q').
fn start(series: &[Vec<f64>], times: &[f64]) -> (f64, Vec<f64>, Vec<f64>) {
    let dt = times[1] - times[0];
    let q = series.iter().map(|s| 0.5 * (s[0] + s[1]) - (s[2] - 2.0 * s[1] + s[0]) / 8.0).collect();
    let v = series.iter().map(|s| (s[1] - s[0]) / dt).collect();
    (0.5 * (times[0] + times[1]), q, v)
}

/// Why a motion was not compared with the Lagrangian model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LagrangianError {
    /// Too few ticks of motion to read the start from.
    #[error("{ticks} tick(s) of motion: at least {needed} are needed")]
    TooFewTicks { ticks: usize, needed: usize },
    /// The model's integration failed.
    #[error("the Lagrangian model cannot be integrated: {0}")]
    NotIntegrable(crate::file_model::dynamics::DynamicsError),
}

/// Integrates the model of `energy` (its parameters and inputs in `values`) beside the
/// `samples` and compares them; `tolerances` = (max, rms) per coordinate. Err with the reason
/// when there are too few samples or the model cannot be integrated.
pub fn compare(
    energy: &EnergySpec,
    values: &[f64],
    samples: &Samples,
    (tolerance, rms_tolerance): (f64, Option<f64>),
) -> Result<LagrangianReport, LagrangianError> {
    let n = samples.times.len();
    if n < START_SAMPLES + 1 {
        return Err(LagrangianError::TooFewTicks { ticks: n, needed: START_SAMPLES + 1 });
    }
    let series: Vec<Vec<f64>> =
        energy.coordinates.iter().enumerate().map(|(i, c)| samples.series(i, c.class)).collect();
    let (t0, q0, v0) = start(&series, &samples.times);
    let dt = samples.times[1] - samples.times[0];
    let compared = &samples.times[1..];
    let shifted: Vec<f64> = compared.iter().map(|t| t - t0).collect();
    let mut work = values.to_vec();
    work.resize(energy.values_len(), 0.0);
    let model = energy
        .integrate(&work, &q0, &v0, &shifted, &Tolerance::default(), None)
        .map_err(LagrangianError::NotIntegrable)?;
    let coordinates = energy
        .coordinates
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let simulated = &series[i][1..];
            let predicted: Vec<f64> = model.coordinates.iter().map(|q| q[i]).collect();
            let dispersion_dt = (!samples.extrapolated).then_some(dt);
            coordinate_report(
                &c.name,
                c.class,
                compared,
                simulated,
                &predicted,
                dispersion_dt,
                (tolerance, rms_tolerance),
            )
        })
        .collect();
    Ok(LagrangianReport {
        method: METHOD.into(),
        start_time_s: t0,
        start_coordinates: q0,
        start_rates: v0,
        integrator_steps: model.stats.accepted,
        error: None,
        coordinates,
    })
}

/// One coordinate's comparison: the largest and rms error over the ticks, and the frequency
/// fitted to each trajectory (the simulation's corrected for the dispersion of its steps at
/// `dispersion_dt_s`, where it was not extrapolated).
fn coordinate_report(
    name: &str,
    class: ErrorClass,
    times: &[f64],
    simulated: &[f64],
    model: &[f64],
    dispersion_dt_s: Option<f64>,
    (tolerance, rms_tolerance): (f64, Option<f64>),
) -> LagrangianCoordinateReport {
    let errors: Vec<f64> = simulated.iter().zip(model).map(|(s, m)| class.error(*m, *s)).collect();
    let max_error = errors.iter().copied().fold(0.0, f64::max);
    let max_error = if errors.iter().any(|e| e.is_nan()) { f64::INFINITY } else { max_error };
    let rms_error = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    let model_omega = fit_cosine(times, model).map_or(f64::NAN, |f| f.omega_rad_per_s);
    let measured = fit_cosine(times, simulated).map_or(f64::NAN, |f| f.omega_rad_per_s);
    LagrangianCoordinateReport {
        name: name.into(),
        class: class.name().into(),
        max_error,
        rms_error,
        tolerance,
        rms_tolerance,
        passed: max_error <= tolerance && rms_tolerance.is_none_or(|t| rms_error <= t),
        ticks_compared: times.len(),
        model_omega_rad_per_s: model_omega,
        simulated_omega_rad_per_s: dispersion_dt_s.map_or(measured, |dt| corrected_for_symplectic_euler(measured, dt)),
    }
}

/// The report of a comparison that could not be made (`why`): every coordinate fails.
pub fn not_compared(
    energy: &EnergySpec,
    why: LagrangianError,
    (tolerance, rms_tolerance): (f64, Option<f64>),
) -> LagrangianReport {
    let coordinates = energy
        .coordinates
        .iter()
        .map(|c| LagrangianCoordinateReport {
            name: c.name.clone(),
            class: c.class.name().into(),
            max_error: f64::INFINITY,
            rms_error: f64::INFINITY,
            tolerance,
            rms_tolerance,
            passed: false,
            ticks_compared: 0,
            model_omega_rad_per_s: f64::NAN,
            simulated_omega_rad_per_s: f64::NAN,
        })
        .collect();
    LagrangianReport {
        method: METHOD.into(),
        start_time_s: f64::NAN,
        start_coordinates: vec![],
        start_rates: vec![],
        integrator_steps: 0,
        error: Some(crate::report::ReportedError::new(why)),
        coordinates,
    }
}
