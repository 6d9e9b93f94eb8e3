//! A motion run against the file's Lagrangian model (`[energy.trajectory]`): the `[energy]`
//! coordinates measured at every tick of the motion, the model's equations of motion
//! integrated beside them (Dormand-Prince 5(4), `file_model::integrate`), advanced tick by tick
//! as the motion runs ([`Tracker`]), and the two compared at every tick. Every compared tick's
//! simulated value, model value and error go to the per-tick table and the recording
//! ([`Row`]); the largest and rms error to the report.
//!
//! The model starts where `[energy.trajectory] start` says:
//! - `"samples"` (the default): from the simulation's own samples, so that nothing is assumed
//!   of how it was displaced. rapier steps velocities, then positions (symplectic Euler): its
//!   samples q_k are those of the leapfrog scheme, whose rates live at the half steps,
//!   (q_{k+1} - q_k) / dt = q'(t_k + dt/2) + O(dt^2). The model therefore starts at
//!   t_{3/2} = 1.5 dt, between the first two samples of the motion (ticks 1 and 2), with
//!   q(t_{3/2}) = (q_1 + q_2) / 2 - (q_3 - 2 q_2 + q_1) / 8 (Taylor, error O(dt^3)) and
//!   q'(t_{3/2}) = (q_2 - q_1) / dt (error O(dt^2)), and is compared from tick 2 on (the values of ticks 2 and 3 are known at tick 3). The
//!   leapfrog's own global error is O(dt^2), so the whole comparison falls as dt^2 where the
//!   model is right (`tests/it/motion.rs` shows it over three time steps at 0.5 rad), and stays
//!   where it is when it is not.
//! - `"stated"`: from the file's initial condition at t = 0, the paper's claim: the coordinates
//!   measured on the state the motion starts from (the settled or drawn equilibrium with
//!   `[motion]`'s displacement, before any step) and `[motion]`'s rate along them, compared
//!   from tick 1 on. Against it the simulation's first step (a full symplectic Euler step from
//!   rest, not the leapfrog's half step) shows: the error is first order in dt.

use crate::file_model::dynamics::{TrajectoryStart, TrajectoryStepper};
use crate::file_model::energy_model::EnergySpec;
use crate::file_model::integrate::Tolerance;
use crate::file_model::spec::ErrorClass;
use crate::mechanisms::wrap_angle;
use crate::observers::motion::{corrected_for_symplectic_euler, frequency_by};
use crate::report::{LagrangianCoordinateReport, LagrangianReport};
use crate::settings::FrequencyMeasure;
use std::sync::atomic::AtomicBool;

/// The integrator and its error control, and its start from the samples, as the report
/// states them.
pub const METHOD: &str = "Dormand-Prince 5(4), rtol 1e-10, atol 1e-12, started at 1.5 dt from the \
    first three samples of the motion (leapfrog half-step rates), compared from tick 2";

/// The same, started from the file's initial condition.
pub const METHOD_STATED: &str = "Dormand-Prince 5(4), rtol 1e-10, atol 1e-12, started at t = 0 from \
    the file's initial condition (the coordinates of the start state with [motion]'s displacement, \
    [motion]'s rate), compared from tick 1";

/// Samples the model's start is read from: ticks 1, 2 and 3 of the motion.
const START_SAMPLES: usize = 3;

/// The motion's first sample compared with the model, from the samples' start (tick 2).
const FIRST_COMPARED_FROM_SAMPLES: usize = 1;

/// The model's start at t_{3/2} from the first three samples (module docs): (time, q, q').
fn start(series: &[Vec<f64>], times: &[f64]) -> (f64, Vec<f64>, Vec<f64>) {
    let dt = times[1] - times[0];
    let q = series.iter().map(|s| 0.5 * (s[0] + s[1]) - (s[2] - 2.0 * s[1] + s[0]) / 8.0).collect();
    let v = series.iter().map(|s| (s[1] - s[0]) / dt).collect();
    (0.5 * (times[0] + times[1]), q, v)
}

/// Most integrator steps (accepted and rejected) of the Lagrangian model a compared tick of
/// the motion, on average: the shipped models take about one; a model whose kinetic energy is
/// scaled by 1e-9 (about 5e5 rad/s against a 1 ms step) had taken some 50,000 a tick, running
/// for a minute to the integrator's limit of ten million.
pub const MAX_MODEL_STEPS_PER_TICK: usize = 10_000;

/// Why a motion was not compared with the Lagrangian model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LagrangianError {
    /// Too few ticks of motion to read the start from.
    #[error("{ticks} tick(s) of motion: at least {needed} are needed")]
    TooFewTicks { ticks: usize, needed: usize },
    /// The model's integration failed.
    #[error("the Lagrangian model cannot be integrated: {0}")]
    NotIntegrable(crate::file_model::dynamics::DynamicsError),
    /// The model's integration took more steps than the motion's ticks bound.
    #[error("the Lagrangian model took {steps} integrator steps over {ticks} tick(s) of the motion, more than {MAX_MODEL_STEPS_PER_TICK} a tick: it is stiff against the motion (its fastest rate far beyond what the motion's step resolves), and an explicit integrator would take minutes; check the model's kinetic and potential energies' scales")]
    Stiff { steps: usize, ticks: usize },
    /// The file's initial condition cannot be stated in the model's coordinates.
    #[error("no stated start: {0}")]
    NoStatedStart(String),
}

/// The file's initial condition in the model's coordinates, (q(0), q'(0)), or why there is none.
pub type StatedStart = Result<(Vec<f64>, Vec<f64>), LagrangianError>;

/// One tick of the motion against the model: the simulated coordinates (angles unwrapped,
/// continuous through +-pi), and where the tick is compared the model's coordinates and the
/// errors (in each coordinate's class), in the order of `[[energy.coordinates]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The motion's sample, from 0 (tick 1 of the motion).
    pub index: usize,
    pub simulated: Vec<f64>,
    /// (model, error) where compared; None at a tick the model does not reach (the samples
    /// it starts from) or when it could not be integrated.
    pub compared: Option<(Vec<f64>, Vec<f64>)>,
}

/// The comparison as the motion runs: each tick's coordinates pushed ([`Tracker::push`]) hand
/// back the rows that are then known, every sample's exactly once and in order.
///
/// The model's integration is bounded by the motion: at most [`MAX_MODEL_STEPS_PER_TICK`]
/// steps a compared tick on average (the shipped models take one), so that a model stiff
/// against the motion is named within a tick or two instead of integrating for minutes to the
/// integrator's own limit.
#[derive(Clone, Debug)]
pub struct Tracker {
    start: TrajectoryStart,
    /// How each trajectory's frequency is measured.
    measure: FrequencyMeasure,
    classes: Vec<ErrorClass>,
    /// How far the motion reaches beyond its start [s] (the integrator's first step is no longer).
    span_s: f64,
    /// Every symbol's value at the motion's first tick (its parameters and inputs).
    values: Vec<f64>,
    /// The stated start, handed in before the motion's first tick.
    stated: Option<StatedStart>,
    times: Vec<f64>,
    /// Per coordinate, its simulated value at every tick (angles unwrapped).
    series: Vec<Vec<f64>>,
    /// Per coordinate, the model's value at every compared tick.
    model: Vec<Vec<f64>>,
    first_compared: usize,
    /// The model's start: the motion's time [s], q and q'.
    origin: Option<(f64, Vec<f64>, Vec<f64>)>,
    stepper: Option<TrajectoryStepper>,
    error: Option<LagrangianError>,
    /// Samples handed back as rows so far.
    handed: usize,
    /// The motion is judged extrapolated over the time step (`run/levels.rs`): its frequency
    /// has no dispersion to correct.
    extrapolated: bool,
}

impl Tracker {
    /// The comparison of the model of `energy` from `start`, over a motion of `span_s` \[s\],
    /// each trajectory's frequency by `measure`.
    pub fn new(energy: &EnergySpec, (start, measure): (TrajectoryStart, FrequencyMeasure), span_s: f64) -> Self {
        let n = energy.coordinates.len();
        Tracker {
            start,
            measure,
            classes: energy.coordinates.iter().map(|c| c.class).collect(),
            span_s,
            values: Vec::new(),
            stated: None,
            times: Vec::new(),
            series: vec![Vec::new(); n],
            model: vec![Vec::new(); n],
            first_compared: match start {
                TrajectoryStart::Samples => FIRST_COMPARED_FROM_SAMPLES,
                TrajectoryStart::Stated => 0,
            },
            origin: None,
            stepper: None,
            error: None,
            handed: 0,
            extrapolated: false,
        }
    }

    /// Notes that the motion is judged extrapolated over the time step.
    pub fn note_extrapolated(&mut self) {
        self.extrapolated = true;
    }

    /// Where the model starts.
    pub fn start(&self) -> TrajectoryStart {
        self.start
    }

    /// The file's initial condition (q(0), q'(0)) in the model's coordinates, or why there is
    /// none; used when the model starts from it.
    pub fn set_stated(&mut self, stated: StatedStart) {
        self.stated = Some(stated);
    }

    /// One tick of the motion: every symbol's value `v` there and the measured coordinates,
    /// its time \[s\]. The rows known now; the model's integration to them stops on `cancel`.
    pub fn push(
        &mut self,
        energy: &EnergySpec,
        (v, measured): (&[f64], &[f64]),
        time_s: f64,
        cancel: Option<&AtomicBool>,
    ) -> Vec<Row> {
        if self.values.is_empty() {
            self.values = v.to_vec();
            self.values.resize(energy.values_len(), 0.0);
        }
        self.times.push(time_s);
        for ((s, q), class) in self.series.iter_mut().zip(measured).zip(&self.classes) {
            let next = match (class, s.last()) {
                (ErrorClass::Angle, Some(prev)) => prev + wrap_angle(q - prev),
                _ => *q,
            };
            s.push(next);
        }
        if self.origin.is_none() && self.error.is_none() {
            self.begin(energy);
        }
        self.rows(energy, cancel)
    }

    /// Starts the model once its start is known: the stated one at the first tick, the
    /// samples' at the third.
    fn begin(&mut self, energy: &EnergySpec) {
        let origin = match self.start {
            TrajectoryStart::Samples if self.times.len() < START_SAMPLES => return,
            TrajectoryStart::Samples => start(&self.series, &self.times),
            TrajectoryStart::Stated => {
                let unseen = || Err(LagrangianError::NoStatedStart("the motion's start was not seen".into()));
                match self.stated.clone().unwrap_or_else(unseen) {
                    Ok((q, v)) => (0.0, q, v),
                    Err(e) => {
                        self.error = Some(e);
                        return;
                    }
                }
            }
        };
        let (t0, q0, v0) = &origin;
        match energy.start_trajectory(&self.values, q0, v0, self.span_s - t0, &Tolerance::default()) {
            Ok(s) => self.stepper = Some(s),
            Err(e) => self.error = Some(LagrangianError::NotIntegrable(e)),
        }
        self.origin = Some(origin);
    }

    /// The rows of the samples not handed back yet that are known now: before the first
    /// compared one, uncompared; after, the model advanced to them.
    fn rows(&mut self, energy: &EnergySpec, cancel: Option<&AtomicBool>) -> Vec<Row> {
        let mut out = Vec::new();
        while self.handed < self.times.len() {
            let i = self.handed;
            let compared = if i < self.first_compared || self.error.is_some() {
                None
            } else {
                let (Some(stepper), Some((t0, ..))) = (self.stepper.as_mut(), &self.origin) else { break };
                let advanced = stepper.advance(energy, self.times[i] - t0, cancel).map(|(q, _)| q.to_vec());
                let (stats, ticks) = (stepper.stats(), i + 1 - self.first_compared);
                let steps = stats.accepted + stats.rejected;
                match advanced {
                    Ok(_) if steps > MAX_MODEL_STEPS_PER_TICK * ticks => {
                        self.error = Some(LagrangianError::Stiff { steps, ticks });
                        None
                    }
                    Ok(q) => Some(q),
                    Err(e) => {
                        self.error = Some(LagrangianError::NotIntegrable(e));
                        None
                    }
                }
            };
            out.push(self.row(i, compared));
            self.handed += 1;
        }
        out
    }

    /// Sample `i`'s row, the model's coordinates `model` there (kept) if compared.
    fn row(&mut self, i: usize, model: Option<Vec<f64>>) -> Row {
        let simulated: Vec<f64> = self.series.iter().map(|s| s[i]).collect();
        let compared = model.map(|m| {
            for (kept, q) in self.model.iter_mut().zip(&m) {
                kept.push(*q);
            }
            let errors = self.classes.iter().zip(&m).zip(&simulated).map(|((c, m), s)| c.error(*m, *s)).collect();
            (m, errors)
        });
        Row { index: i, simulated, compared }
    }

    /// The rows still held back when the motion ends (too few ticks to start from): uncompared.
    pub fn flush(&mut self) -> Vec<Row> {
        let rest: Vec<usize> = (self.handed..self.times.len()).collect();
        self.handed = self.times.len();
        rest.into_iter().map(|i| self.row(i, None)).collect()
    }

    /// The report of the comparison; `tolerances` = (max, rms) per coordinate.
    pub fn report(&self, energy: &EnergySpec, tolerances: (f64, Option<f64>)) -> LagrangianReport {
        let n = self.times.len();
        let needed = match self.start {
            TrajectoryStart::Samples => START_SAMPLES + 1,
            TrajectoryStart::Stated => 1,
        };
        if n < needed {
            return not_compared(energy, self.start, LagrangianError::TooFewTicks { ticks: n, needed }, tolerances);
        }
        let (Some((t0, q0, v0)), None, Some(stepper)) = (&self.origin, &self.error, &self.stepper) else {
            let why = self.error.clone().unwrap_or(LagrangianError::TooFewTicks { ticks: n, needed });
            return not_compared(energy, self.start, why, tolerances);
        };
        // The motion's time step [s]: its first sample is at t = dt.
        let dt = if n > 1 { self.times[1] - self.times[0] } else { self.times[0] };
        let compared = &self.times[self.first_compared..];
        let coordinates = energy
            .coordinates
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let simulated = &self.series[i][self.first_compared..];
                let dispersion_dt = (!self.extrapolated).then_some(dt);
                let series = (compared, simulated, self.model[i].as_slice());
                coordinate_report(&c.name, c.class, series, (self.measure, dispersion_dt), tolerances)
            })
            .collect();
        LagrangianReport {
            method: method(self.start).into(),
            start: self.start.name().into(),
            start_time_s: *t0,
            start_coordinates: q0.clone(),
            start_rates: v0.clone(),
            integrator_steps: stepper.stats().accepted,
            error: None,
            measure: (self.measure == FrequencyMeasure::Period).then(|| self.measure.label().to_string()),
            coordinates,
        }
    }
}

/// The method as the report states it, for a start.
fn method(start: TrajectoryStart) -> &'static str {
    match start {
        TrajectoryStart::Samples => METHOD,
        TrajectoryStart::Stated => METHOD_STATED,
    }
}

/// One coordinate's comparison: the largest and rms error over the ticks, and the frequency
/// fitted to each trajectory (the simulation's corrected for the dispersion of its steps at
/// `dispersion_dt_s`, where it was not extrapolated).
fn coordinate_report(
    name: &str,
    class: ErrorClass,
    (times, simulated, model): (&[f64], &[f64], &[f64]),
    (measure, dispersion_dt_s): (FrequencyMeasure, Option<f64>),
    (tolerance, rms_tolerance): (f64, Option<f64>),
) -> LagrangianCoordinateReport {
    let errors: Vec<f64> = simulated.iter().zip(model).map(|(s, m)| class.error(*m, *s)).collect();
    let max_error = errors.iter().copied().fold(0.0, f64::max);
    let max_error = if errors.iter().any(|e| e.is_nan()) { f64::INFINITY } else { max_error };
    let rms_error = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    let omega = |q: &[f64]| frequency_by(measure, times, q);
    let (model_omega, measured) = (omega(model).unwrap_or(f64::NAN), omega(simulated).unwrap_or(f64::NAN));
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
    start: TrajectoryStart,
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
        method: method(start).into(),
        start: start.name().into(),
        start_time_s: f64::NAN,
        start_coordinates: vec![],
        start_rates: vec![],
        integrator_steps: 0,
        error: Some(crate::report::ReportedError::new(why)),
        measure: None,
        coordinates,
    }
}
