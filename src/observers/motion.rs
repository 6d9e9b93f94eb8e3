//! A motion run's natural frequencies, measured from the simulation: the coordinate of each
//! named joint sampled at every tick of the motion, and its frequency measured one of two ways
//! (`[[motion.frequencies]] measure`), then corrected for symplectic Euler's dispersion:
//! - "cosine" (the default): fitted with c + A cos(w t + p) over the whole motion (least
//!   squares: a start frequency from the crossings of the mean, then Gauss-Newton on c,
//!   A cos p, -A sin p and w). Exact for a linear oscillator; at large amplitude the motion's
//!   harmonics (3 w, 5 w, ...) bias the fit over a record that is no whole number of periods:
//!   1e-6 relative at 0.3 rad for a pendulum, a fit of the exact solution shows the same.
//! - "period": the mean period between the interpolated zero crossings of the rate (the
//!   turning points) over every full period of the record. The rate is the difference of
//!   consecutive samples, the velocity of the half step between them; a parabola through three
//!   rates about each crossing finds it to third order in dt. Unbiased at any amplitude: what
//!   remains is the integrator's own second-order error.
//!
//! rapier steps velocities, then positions (symplectic Euler). On a linear oscillator
//! q'' = -w^2 q that step map has eigenvalues e^(+-i theta) with cos theta = 1 - (w dt)^2 / 2, so
//! the samples are exactly c + A cos(theta k + p): the fit finds w_d = theta / dt, and
//! w = (2 / dt) sin(w_d dt / 2) undoes the dispersion exactly for a linear system. Uncorrected,
//! w_d is larger than w by about (w dt)^2 / 24 relative. What remains after the correction is the
//! system's own nonlinearity (a frequency shift growing with the amplitude squared) and any
//! damping.

use super::{Made, ModeAtStart, MotionStarted, Note, Observer, Setup, Tick};
use crate::mechanisms::Values;
use crate::report::{FrequencyReport, ScenarioReport};
use crate::settings::{FrequencyMeasure, FrequencyPrediction, FrequencySignal, Motion};
use crate::snapshot::Snapshot;
use crate::structure::Structure;

/// How a frequency is measured with `measure = "cosine"`, as the report states it.
pub const METHOD: &str = "least-squares fit of c + A cos(w t + p) over every tick of the motion, \
    w corrected for symplectic Euler's dispersion: w = (2/dt) sin(w_d dt/2)";
/// How a frequency is measured with `measure = "period"`, as the report states it.
/// The period measure of a motion judged extrapolated over the time step: nothing corrected.
pub const PERIOD_METHOD_EXTRAPOLATED: &str = "period: mean period 2 pi / w_d between interpolated zero \
    crossings of the rate (the turning points) over every full period of the motion extrapolated over \
    the time step (fourth order: no dispersion to correct)";

pub const PERIOD_METHOD: &str = "period: mean period 2 pi / w_d between interpolated zero crossings of \
    the rate (the turning points) over every full period of the motion, w corrected for symplectic \
    Euler's dispersion: w = (2/dt) sin(w_d dt/2)";

/// How the frequencies are measured from a motion judged extrapolated over the time step
/// (`run/levels.rs`): its dispersion is gone with its h^2 term, so nothing is corrected.
pub const METHOD_EXTRAPOLATED: &str = "least-squares fit of c + A cos(w t + p) over every tick of \
    the motion extrapolated over the time step (fourth order: no dispersion to correct)";

/// omega(A) - omega(0) over omega(A) - omega(A/2) where the amplitude's shift is c A^2.
const AMPLITUDE_SHIFT_FACTOR: f64 = 4.0 / 3.0;

/// A measured frequency's error bar, relative, and its parts.
struct ErrorBar {
    /// The measure's own error over the record.
    measure: Option<f64>,
    /// The frequency at half the amplitude \[rad/s\] and the amplitude's shift (signed).
    shift: Option<(f64, f64)>,
    /// The parts' sum; None where nothing was measured.
    total: Option<f64>,
    /// What it leaves out.
    leaves_out: Vec<String>,
}

/// Fewest samples a fit is made from.
const MIN_FIT_SAMPLES: usize = 16;
/// Fewest crossings of the mean (a full period) for a start frequency.
const MIN_CROSSINGS: usize = 3;
/// Most Gauss-Newton iterations of the fit.
const MAX_FIT_ITERATIONS: usize = 50;
/// The fit has converged when an iteration changes w by less than this fraction of it.
const FIT_CONVERGED: f64 = 1e-15;

/// c + A cos(w t + p) fitted to samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CosineFit {
    pub offset: f64,
    pub amplitude: f64,
    pub omega_rad_per_s: f64,
    /// The phase at t = 0 \[rad\].
    pub phase_rad: f64,
    /// rms of the samples' residual from the fit.
    pub rms_residual: f64,
}

/// The start frequency from the crossings of the mean `mean`: pi per half period, None with
/// fewer than [`MIN_CROSSINGS`].
fn crossing_frequency(t: &[f64], q: &[f64], mean: f64) -> Option<f64> {
    let mut crossings = Vec::new();
    for i in 1..q.len() {
        let (a, b) = (q[i - 1] - mean, q[i] - mean);
        if (a < 0.0) != (b < 0.0) {
            crossings.push(t[i - 1] + (t[i] - t[i - 1]) * a / (a - b));
        }
    }
    if crossings.len() < MIN_CROSSINGS {
        return None;
    }
    let span = crossings[crossings.len() - 1] - crossings[0];
    (span > 0.0).then(|| std::f64::consts::PI * (crossings.len() - 1) as f64 / span)
}

/// The zero crossings of the rate of the samples (t, q): the times of the turning points [s].
/// The rates of consecutive half steps are differences of the samples; each crossing is the
/// root of the parabola through three of them about it (the two either side and the next),
/// refined by Newton from the straight line's root: third order in dt for any oscillation.
fn rate_crossings(t: &[f64], q: &[f64]) -> Vec<f64> {
    let rates: Vec<(f64, f64)> =
        t.windows(2).zip(q.windows(2)).map(|(t, q)| (0.5 * (t[0] + t[1]), (q[1] - q[0]) / (t[1] - t[0]))).collect();
    let mut crossings = Vec::new();
    for i in 1..rates.len() {
        let ((ta, a), (tb, b)) = (rates[i - 1], rates[i]);
        if (a < 0.0) == (b < 0.0) {
            continue;
        }
        let line = ta + (tb - ta) * a / (a - b);
        let third = if i + 1 < rates.len() {
            rates[i + 1]
        } else if i >= 2 {
            rates[i - 2]
        } else {
            (tb, b)
        };
        crossings.push(parabola_root([(ta, a), (tb, b), third], line).unwrap_or(line));
    }
    crossings
}

/// Newton steps on the root of the parabola through three rates.
const ROOT_NEWTON_STEPS: usize = 4;

/// The root near `x0` of the parabola through the three points `p` (Newton's divided
/// differences), if it stays between the first two; None for three points that are no parabola.
fn parabola_root(p: [(f64, f64); 3], x0: f64) -> Option<f64> {
    let [(x1, y1), (x2, y2), (x3, y3)] = p;
    let d12 = (y2 - y1) / (x2 - x1);
    let d23 = (y3 - y2) / (x3 - x2);
    let d123 = (d23 - d12) / (x3 - x1);
    if !d123.is_finite() {
        return None;
    }
    let mut x = x0;
    for _ in 0..ROOT_NEWTON_STEPS {
        let f = y1 + d12 * (x - x1) + d123 * (x - x1) * (x - x2);
        let df = d12 + d123 * (2.0 * x - x1 - x2);
        x -= f / df;
    }
    (x.is_finite() && (x - x1) * (x - x2) <= 0.0).then_some(x)
}

/// The frequency 2 pi / T [rad/s] of the samples (t, q) from their mean period T between zero
/// crossings of the rate over every full period of the record (an even number of half periods,
/// so that an asymmetric oscillation's unequal halves count alike); None without a full period.
pub fn period_frequency(t: &[f64], q: &[f64]) -> Option<f64> {
    if t.len() != q.len() || t.len() < MIN_FIT_SAMPLES {
        return None;
    }
    let c = rate_crossings(t, q);
    let periods = c.len().saturating_sub(1) / 2;
    if periods == 0 {
        return None;
    }
    let period_s = (c[2 * periods] - c[0]) / periods as f64;
    (period_s > 0.0).then(|| 2.0 * std::f64::consts::PI / period_s)
}

/// Least squares of c + a cos(w s) + b sin(w s) (s = t - `mid`) on `q`, from the start `x`
/// = (c, a, b, w): Gauss-Newton with the w column scaled by `half` (the half-span of s).
fn gauss_newton(s: &[f64], q: &[f64], mut x: [f64; 4], half: f64) -> Option<[f64; 4]> {
    for _ in 0..MAX_FIT_ITERATIONS {
        let mut jtj = nalgebra::Matrix4::<f64>::zeros();
        let mut jtr = nalgebra::Vector4::<f64>::zeros();
        for (si, qi) in s.iter().zip(q) {
            let (sn, cs) = (x[3] * si).sin_cos();
            let r = qi - (x[0] + x[1] * cs + x[2] * sn);
            let j = nalgebra::Vector4::new(1.0, cs, sn, si / half * (-x[1] * sn + x[2] * cs));
            jtj += j * j.transpose();
            jtr += j * r;
        }
        let d = jtj.lu().solve(&jtr)?;
        x = [x[0] + d[0], x[1] + d[1], x[2] + d[2], x[3] + d[3] / half];
        if (d[3] / half).abs() <= FIT_CONVERGED * x[3].abs() {
            return Some(x);
        }
    }
    Some(x)
}

/// Least squares of c + a cos(w s) + b sin(w s) on `q` at a fixed `w`: (c, a, b).
fn linear_at(s: &[f64], q: &[f64], w: f64) -> Option<[f64; 3]> {
    let mut jtj = nalgebra::Matrix3::<f64>::zeros();
    let mut jtr = nalgebra::Vector3::<f64>::zeros();
    for (si, qi) in s.iter().zip(q) {
        let (sn, cs) = (w * si).sin_cos();
        let j = nalgebra::Vector3::new(1.0, cs, sn);
        jtj += j * j.transpose();
        jtr += j * *qi;
    }
    let x = jtj.lu().solve(&jtr)?;
    Some([x[0], x[1], x[2]])
}

/// Fits c + A cos(w t + p) to the samples (t, q); None with too few samples or crossings.
pub fn fit_cosine(t: &[f64], q: &[f64]) -> Option<CosineFit> {
    if t.len() != q.len() || t.len() < MIN_FIT_SAMPLES {
        return None;
    }
    let mean = q.iter().sum::<f64>() / q.len() as f64;
    let w0 = crossing_frequency(t, q, mean)?;
    let (first, last) = (t[0], t[t.len() - 1]);
    let mid = 0.5 * (first + last);
    let half = 0.5 * (last - first);
    let s: Vec<f64> = t.iter().map(|ti| ti - mid).collect();
    let centred: Vec<f64> = q.iter().map(|qi| qi - mean).collect();
    let [c0, a0, b0] = linear_at(&s, &centred, w0)?;
    let x = gauss_newton(&s, &centred, [c0, a0, b0, w0], half)?;
    let [c, a, b, w] = x;
    if !(w.is_finite() && w > 0.0) {
        return None;
    }
    let residual = s.iter().zip(&centred).map(|(si, qi)| {
        let (sn, cs) = (w * si).sin_cos();
        let r = qi - (c + a * cs + b * sn);
        r * r
    });
    let rms_residual = (residual.sum::<f64>() / q.len() as f64).sqrt();
    // a cos(w s) + b sin(w s) = A cos(w s + p') with A = hypot(a, b), p' = atan2(-b, a); at
    // t = 0, s = -mid.
    let phase = (-b).atan2(a) - w * mid;
    Some(CosineFit {
        offset: mean + c,
        amplitude: a.hypot(b),
        omega_rad_per_s: w,
        phase_rad: crate::mechanisms::wrap_angle(phase),
        rms_residual,
    })
}

/// The frequency of the samples (t, q) by `measure` [rad/s]: the cosine fit's, or the mean
/// period's; None where it finds none.
pub fn frequency_by(measure: FrequencyMeasure, t: &[f64], q: &[f64]) -> Option<f64> {
    match measure {
        FrequencyMeasure::Cosine => fit_cosine(t, q).map(|f| f.omega_rad_per_s),
        FrequencyMeasure::Period => period_frequency(t, q),
    }
}

/// The frequency of a linear oscillator whose symplectic Euler samples at step `dt_s` turn at
/// `measured` rad/s: (2 / dt) sin(w_d dt / 2). NaN beyond the step's stability (w_d dt > pi).
pub fn corrected_for_symplectic_euler(measured_rad_per_s: f64, dt_s: f64) -> f64 {
    let theta = measured_rad_per_s * dt_s;
    if theta > std::f64::consts::PI {
        return f64::NAN;
    }
    2.0 / dt_s * (0.5 * theta).sin()
}

/// Samples each frequency's joint coordinate at every tick of the motion.
pub struct MotionObserver {
    frequencies: Vec<FrequencyPrediction>,
    /// Per frequency: the motion's times and the joint's coordinate there.
    samples: Vec<(Vec<f64>, Vec<f64>)>,
    /// Per frequency, in a motion judged extrapolated: the coordinate in the state one level
    /// rougher at each tick (Richardson's value from h and h/2), for the frequency's estimate of
    /// the simulation's own error.
    rougher: Vec<Vec<f64>>,
    /// Per frequency: the times and coordinates of the motion again at half its amplitude
    /// (`run/amplitude.rs`); empty where it was not run.
    half: Vec<(Vec<f64>, Vec<f64>)>,
    /// The parameters, inputs and analytic quantities of the motion (for the predictions).
    at: Option<(Values, Values, Values)>,
    /// The structure's own modes at the motion's start that frequencies are fitted to.
    modes: Vec<ModeAtStart>,
    /// The motion's time step \[s\], for the dispersion's correction.
    dt_s: f64,
    /// The motion is judged extrapolated over the time step (no dispersion to correct): what
    /// divides a difference from the rougher state into the judged error
    /// (`MotionStarted::estimate_divisor`).
    estimate_divisor: Option<f64>,
}

impl MotionObserver {
    pub fn new(m: &Motion) -> Self {
        MotionObserver {
            frequencies: m.frequencies.clone(),
            samples: vec![(Vec::new(), Vec::new()); m.frequencies.len()],
            rougher: vec![Vec::new(); m.frequencies.len()],
            half: vec![(Vec::new(), Vec::new()); m.frequencies.len()],
            at: None,
            modes: Vec::new(),
            dt_s: f64::NAN,
            estimate_divisor: None,
        }
    }

    /// Frequency `k`'s coordinate in `snap`: its joint's, or its mode's modal coordinate; NaN
    /// where there is none.
    fn signal(&self, k: usize, snap: &Snapshot, structure: &Structure) -> f64 {
        let q = match self.frequencies[k].signal {
            FrequencySignal::Joint(ref c) => snap.joint_coordinate(structure, c.index),
            FrequencySignal::Mode(i) => self.mode(i).map(|m| m.projector.coordinate(snap)),
        };
        q.unwrap_or(f64::NAN)
    }

    fn mode(&self, index: usize) -> Option<&ModeAtStart> {
        self.modes.iter().find(|m| m.index == index)
    }

    /// The modal analysis's frequency of `f`'s mode, if it is fitted to one.
    fn modal(&self, f: &FrequencyPrediction) -> Option<f64> {
        match f.signal {
            FrequencySignal::Mode(i) => self.mode(i).map(|m| m.omega_rad_per_s),
            FrequencySignal::Joint(_) => None,
        }
    }

    /// The prediction of `f`: its formula (over the parameters, inputs, analytic quantities
    /// and the energy model's solved equilibrium `solved`), or the modal analysis's frequency
    /// of its mode.
    fn predicted(&self, f: &FrequencyPrediction, solved: &Values) -> f64 {
        let formula = self.at.as_ref().and_then(|(p, i, a)| f.predicted(p, i, a, solved));
        formula.or_else(|| self.modal(f)).unwrap_or(f64::NAN)
    }

    /// The frequency of the samples `(t, q)` by `f`'s measure [rad/s] (NaN where it finds none);
    /// the cosine measure takes their fit from `fit` (made once where the report needs it too).
    fn measured(f: &FrequencyPrediction, t: &[f64], q: &[f64], fit: impl FnOnce() -> Option<CosineFit>) -> f64 {
        match f.measure {
            FrequencyMeasure::Cosine => fit().map_or(f64::NAN, |x| x.omega_rad_per_s),
            FrequencyMeasure::Period => period_frequency(t, q).unwrap_or(f64::NAN),
        }
    }

    /// In a motion judged extrapolated: the estimate of the simulation's own error in the
    /// measured frequency, relative: the same measure on the state one level rougher differs by
    /// the levels' estimate divisor times the finer one's error (`observers::Rougher`).
    fn estimate(&self, f: &FrequencyPrediction, t: &[f64], rougher: &[f64], measured: f64) -> Option<f64> {
        let divisor = self.estimate_divisor.filter(|_| rougher.len() == t.len())?;
        let rough = frequency_by(f.measure, t, rougher).unwrap_or(f64::NAN);
        Some((measured - rough).abs() / measured.abs() / divisor)
    }

    /// The measure's own error over the record, relative: the largest difference between the
    /// same measure on either half of the record and on the whole (an error falling as 1/T to
    /// 1/T^2 with the record's length T gives 1 to 3 times the whole's); None where a half
    /// holds nothing to measure.
    fn measure_error(f: &FrequencyPrediction, t: &[f64], q: &[f64], measured: f64) -> Option<f64> {
        let mid = t.len() / 2;
        let mut spread = 0.0f64;
        for (th, qh) in [(&t[..mid], &q[..mid]), (&t[mid..], &q[mid..])] {
            let w = frequency_by(f.measure, th, qh).unwrap_or(f64::NAN);
            if !w.is_finite() {
                return None;
            }
            spread = spread.max((w - measured).abs());
        }
        Some(spread / measured.abs())
    }

    /// The frequency at half the amplitude (corrected as `corrected` is) and the amplitude's own
    /// shift of `corrected`, relative and signed: with omega(A) = omega(0) + c A^2,
    /// 4/3 (omega(A) - omega(A/2)) / omega(A); None where the motion did not run again.
    fn amplitude_shift(&self, f: &FrequencyPrediction, k: usize, corrected: f64) -> Option<(f64, f64)> {
        if f.at_amplitude {
            return None;
        }
        let (t, q) = &self.half[k];
        // Not run, or stopped before its end (a divergence): no shift.
        if t.is_empty() || t.len() != self.samples[k].0.len() {
            return None;
        }
        let measured = frequency_by(f.measure, t, q).unwrap_or(f64::NAN);
        let half = if self.estimate_divisor.is_some() {
            measured
        } else {
            corrected_for_symplectic_euler(measured, self.dt_s)
        };
        half.is_finite().then(|| (half, AMPLITUDE_SHIFT_FACTOR * (corrected - half) / corrected.abs()))
    }

    /// The measured frequency's error bar: the simulation's error, the measure's and the
    /// amplitude's shift, and what it leaves out.
    fn error_bar(&self, f: &FrequencyPrediction, k: usize, simulation: Option<f64>, corrected: f64) -> ErrorBar {
        let (t, q) = &self.samples[k];
        let measure = corrected.is_finite().then(|| Self::measure_error(f, t, q, corrected)).flatten();
        let shift = self.amplitude_shift(f, k, corrected);
        let mut leaves_out = Vec::new();
        if simulation.is_none() {
            leaves_out.push("the simulation's own error (a motion not extrapolated over the time step)".to_string());
        }
        if measure.is_none() {
            leaves_out.push("the measure's own error (a half of the record has nothing to measure)".to_string());
        }
        if shift.is_none() && !f.at_amplitude {
            leaves_out.push(
                "the amplitude's shift (a driven or spun motion, one released from a drawing that is no equilibrium, or nothing measured at half the amplitude)"
                    .to_string(),
            );
        }
        let parts = [simulation, measure, shift.map(|s| s.1.abs())];
        let total = corrected.is_finite().then(|| parts.iter().flatten().sum());
        ErrorBar { measure, shift, total, leaves_out }
    }

    fn report(&self, f: &FrequencyPrediction, k: usize, solved: &Values) -> FrequencyReport {
        let (t, q) = &self.samples[k];
        let rougher = &self.rougher[k];
        let predicted = self.predicted(f, solved);
        // With a formula and a mode, the modal analysis is a third value judged against it.
        let modal = self.modal(f).filter(|_| f.formula.is_some());
        let modal_error = modal.map(|w| (w - predicted).abs() / predicted.abs());
        let fit = fit_cosine(t, q);
        let measured = Self::measured(f, t, q, || fit);
        let extrapolated = self.estimate_divisor.is_some();
        let method = match (f.measure, extrapolated) {
            (FrequencyMeasure::Cosine, false) => METHOD,
            (FrequencyMeasure::Cosine, true) => METHOD_EXTRAPOLATED,
            (FrequencyMeasure::Period, false) => PERIOD_METHOD,
            (FrequencyMeasure::Period, true) => PERIOD_METHOD_EXTRAPOLATED,
        };
        let corrected = if extrapolated { measured } else { corrected_for_symplectic_euler(measured, self.dt_s) };
        let error = (corrected - predicted).abs() / predicted.abs();
        let simulation_error = self.estimate(f, t, rougher, measured);
        let bar = self.error_bar(f, k, simulation_error, corrected);
        FrequencyReport {
            name: f.name.clone(),
            coordinate: f.signal.label(),
            measure: f.measure.label().into(),
            predicted_rad_per_s: predicted,
            measured_rad_per_s: measured,
            corrected_rad_per_s: corrected,
            error,
            uncorrected_error: (measured - predicted).abs() / predicted.abs(),
            modal_rad_per_s: modal,
            modal_error,
            simulation_error,
            measure_error: bar.measure,
            half_amplitude_rad_per_s: bar.shift.map(|s| s.0),
            amplitude_shift: bar.shift.map(|s| s.1),
            error_bar: bar.total,
            error_bar_leaves_out: bar.leaves_out,
            tolerance: f.tolerance,
            passed: error <= f.tolerance && modal_error.is_none_or(|e| e <= f.tolerance),
            fit_offset: fit.map_or(f64::NAN, |x| x.offset),
            fit_amplitude: fit.map_or(f64::NAN, |x| x.amplitude),
            fit_rms_residual: fit.map_or(f64::NAN, |x| x.rms_residual),
            samples: t.len(),
            method: method.into(),
        }
    }
}

/// The warning of a frequency whose tolerance is below its error bar, naming the largest part
/// and what resolves it.
fn unresolved(f: &FrequencyReport) -> Option<String> {
    let bar = f.error_bar.filter(|&e| f.tolerance < e)?;
    let parts = [
        (f.simulation_error, "simulation error estimate", "a finer time step"),
        (f.measure_error, "measure's own error", measure_remedy(&f.measure)),
        (f.amplitude_shift.map(f64::abs), "amplitude's shift", "a smaller amplitude"),
    ];
    let (largest, what, remedy) =
        parts
            .iter()
            .filter_map(|&(e, w, r)| Some((e?, w, r)))
            .fold((0.0, "", ""), |a, b| if b.0 > a.0 { b } else { a });
    Some(format!(
        "frequency:{}: tolerance {:.1e} below what this run resolves (its error bar {bar:.1e}, mostly the {what} {largest:.1e}): {remedy} resolves it",
        f.name, f.tolerance
    ))
}

/// What resolves a measure's own error: a cosine fit's bias (harmonics over a record that is
/// no whole number of periods) goes with the period measure; the period measure's with a
/// longer record.
fn measure_remedy(measure: &str) -> &'static str {
    match measure {
        "cosine" => "measure = \"period\" (or a longer record, duration_s)",
        _ => "a longer record (duration_s)",
    }
}

/// A motion run measures its frequencies (`observers::KINDS`).
pub(super) fn make(setup: &Setup, _warnings: &mut Vec<String>) -> Made {
    Ok(setup.motion.map(|m| Box::new(MotionObserver::new(m)) as Box<dyn Observer>))
}

impl Observer for MotionObserver {
    fn tick(&mut self, t: &Tick, _notes: &mut Vec<Note>) {
        let Some(time_s) = t.motion_time_s else { return };
        if self.at.is_none() {
            self.at = Some((t.params.clone(), t.inputs.clone(), t.prediction.expected.clone()));
        }
        for k in 0..self.frequencies.len() {
            let q = self.signal(k, t.snapshot, t.structure);
            let rough = t.rougher.map(|r| self.signal(k, r.state, t.structure));
            let (ts, qs) = &mut self.samples[k];
            ts.push(time_s);
            qs.push(q);
            self.rougher[k].extend(rough);
        }
    }

    fn half_amplitude_tick(&mut self, time_s: f64, state: &Snapshot, structure: &Structure) {
        for k in 0..self.frequencies.len() {
            let q = self.signal(k, state, structure);
            let (ts, qs) = &mut self.half[k];
            ts.push(time_s);
            qs.push(q);
        }
    }

    fn motion_start(&mut self, start: &MotionStarted) {
        self.modes = start.modes.to_vec();
        self.dt_s = start.dt_s;
        self.estimate_divisor = start.estimate_divisor;
    }

    fn finish(&mut self, report: &mut ScenarioReport) {
        let Some(m) = report.motion.as_mut() else { return };
        // The energy model's solved equilibrium at the motion's start point, if the file has one.
        let solved = report.points.last().and_then(|p| p.energy.as_ref()).map(|e| e.solved.clone()).unwrap_or_default();
        m.frequencies = (0..self.frequencies.len()).map(|k| self.report(&self.frequencies[k], k, &solved)).collect();
        report.warnings.extend(m.frequencies.iter().filter_map(unresolved));
        report.warnings.extend(m.frequencies.iter().filter(|f| !f.measured_rad_per_s.is_finite()).map(|f| {
            format!(
                "frequency:{}: nothing measured: the cosine fit needs three crossings of the signal's mean, the period measure a full period between turning points, and the record holds {:.2} predicted periods ({} samples over {:.3} s): a longer duration_s measures it",
                f.name,
                m.duration_s * f.predicted_rad_per_s / std::f64::consts::TAU,
                f.samples,
                m.duration_s
            )
        }));
        if let Some(p) = report.points.last_mut() {
            p.frequencies = m.frequencies.clone();
            p.within_tolerance &= p.frequencies.iter().all(|f| f.passed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples of an exact cosine give back its frequency, amplitude, offset and phase to
    /// round-off.
    #[test]
    fn a_cosine_is_fitted_to_round_off() {
        let (c, a, w, p) = (0.4182, 1e-3, 16.2, 0.7);
        let t: Vec<f64> = (1..=2000).map(|k| k as f64 * 1e-3).collect();
        let q: Vec<f64> = t.iter().map(|t| c + a * (w * t + p).cos()).collect();
        let fit = fit_cosine(&t, &q).expect("a fit");
        assert!((fit.omega_rad_per_s - w).abs() <= 1e-12 * w, "{fit:?}");
        assert!((fit.amplitude - a).abs() <= 1e-12 * a, "{fit:?}");
        assert!((fit.offset - c).abs() <= 1e-15, "{fit:?}");
        assert!(crate::mechanisms::wrap_angle(fit.phase_rad - p).abs() <= 1e-9, "{fit:?}");
    }

    /// The symplectic Euler map of x'' = -w^2 x turns by theta per step with
    /// cos theta = 1 - (w dt)^2 / 2: the correction gives w back to round-off.
    #[test]
    fn the_dispersion_correction_inverts_the_step_maps_rotation() {
        let (w, dt): (f64, f64) = (18.8, 1e-3);
        let theta = (1.0 - (w * dt) * (w * dt) / 2.0).acos();
        let corrected = corrected_for_symplectic_euler(theta / dt, dt);
        assert!((corrected - w).abs() <= 1e-12 * w, "{corrected}");
    }

    /// Samples of the exact pendulum q'' = -w0^2 sin q released at `a` rad, every `dt_s` over
    /// `duration_s` (classical Runge-Kutta at a step 100 times finer: 1e-15 relative).
    fn pendulum(w0: f64, a: f64, dt_s: f64, duration_s: f64) -> (Vec<f64>, Vec<f64>) {
        const SUBSTEPS: usize = 100;
        let h = dt_s / SUBSTEPS as f64;
        let f = |q: f64, v: f64| (v, -w0 * w0 * q.sin());
        let (mut q, mut v) = (a, 0.0);
        let (mut ts, mut qs) = (Vec::new(), Vec::new());
        for k in 1..=(duration_s / dt_s).round() as usize {
            for _ in 0..SUBSTEPS {
                let k1 = f(q, v);
                let k2 = f(q + 0.5 * h * k1.0, v + 0.5 * h * k1.1);
                let k3 = f(q + 0.5 * h * k2.0, v + 0.5 * h * k2.1);
                let k4 = f(q + h * k3.0, v + h * k3.1);
                q += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
                v += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            }
            ts.push(k as f64 * dt_s);
            qs.push(q);
        }
        (ts, qs)
    }

    /// The exact pendulum, w0 AGM(1, cos(a/2)), sampled as `pinned_bar_large_amplitude.toml`
    /// samples it (w0 = 16.22 rad/s, every 1 ms over 4 s): the period measure meets it within
    /// 1e-8 (measured 1.6e-11 at 0.5 rad, 6.4e-10 at 0.3 rad: the interpolation of the
    /// crossings), the cosine fit is 2.01e-7 high at 0.5 rad and 3.05e-7 low at 0.3 rad: its
    /// bias, the motion's harmonics pulling a fit over a record that is no whole number of
    /// periods, of a size and sign that depend on where the record ends.
    #[test]
    fn the_cosine_fit_is_biased_at_large_amplitude_and_the_period_is_not() {
        let w0 = 16.222840269;
        for (a, bias) in [(0.5_f64, 2.01e-7), (0.3, -3.05e-7)] {
            let (mut x, mut y) = (1.0_f64, (0.5 * a).cos());
            for _ in 0..8 {
                (x, y) = (0.5 * (x + y), (x * y).sqrt());
            }
            let exact = w0 * x;
            let (t, q) = pendulum(w0, a, 1e-3, 4.0);
            let period = (period_frequency(&t, &q).expect("periods") - exact) / exact;
            let cosine = (fit_cosine(&t, &q).expect("a fit").omega_rad_per_s - exact) / exact;
            assert!(period.abs() <= 1e-8, "a {a}: period {period:e}");
            assert!((cosine - bias).abs() <= 0.05 * bias.abs(), "a {a}: cosine {cosine:e}");
        }
    }

    /// An asymmetric oscillation (a second harmonic makes its two half periods unequal): the
    /// period measure counts whole periods only, so its frequency is exact to the interpolation
    /// (1e-9 here), whatever the phase; with fewer than one full period it gives none.
    #[test]
    fn the_period_measure_counts_whole_periods_of_an_asymmetric_oscillation() {
        let (w, dt) = (9.3, 1e-3);
        for phase in [0.0, 0.4, 2.0] {
            let t: Vec<f64> = (1..=3000).map(|k| k as f64 * dt).collect();
            let q: Vec<f64> = t.iter().map(|t| (w * t).cos() + 0.1 * (2.0 * w * t + phase).cos()).collect();
            let measured = period_frequency(&t, &q).expect("whole periods");
            assert!((measured - w).abs() <= 1e-9 * w, "phase {phase}: {measured}");
        }
        let t: Vec<f64> = (1..=500).map(|k| k as f64 * dt).collect();
        let q: Vec<f64> = t.iter().map(|t| (w * t).cos()).collect();
        assert_eq!(period_frequency(&t, &q), None, "half a period (0.5 s of a 0.68 s period)");
    }
}
