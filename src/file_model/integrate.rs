//! Dormand-Prince 5(4) with adaptive steps (Dormand & Prince 1980, "A family of embedded
//! Runge-Kutta formulae", J. Comp. Appl. Math. 6; coefficients and step control as in Hairer,
//! Norsett & Wanner, "Solving Ordinary Differential Equations I", 2nd ed., section II.4 and
//! II.5, code DOPRI5): the fifth-order solution is propagated (local extrapolation), the
//! embedded fourth-order one estimates the local error, first same as last (6 evaluations per
//! step). Every sample time is landed on exactly (the step is shortened to it), so no
//! interpolation error is added to the samples.
//!
//! Error control (Hairer II.4, Eq. 4.10-4.11): a step is accepted when
//! err = sqrt(mean_i (e_i / (atol + rtol max(|y_i|, |y_new_i|)))^2) <= 1, e the difference of
//! the two embedded solutions; the next step is h min(FAC_MAX, max(FAC_MIN, SAFETY err^(-1/5))).

use std::sync::atomic::{AtomicBool, Ordering};

/// Safety factor of the step-size update (Hairer II.4, Eq. 4.13).
const SAFETY: f64 = 0.9;
/// Smallest and largest factor by which one step may change the next.
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 10.0;
/// Steps between two looks at the cancel flag.
const CANCEL_POLL_STEPS: usize = 1000;

// Butcher tableau of DOPRI5 (Hairer, Table 5.2).
const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
/// Fifth-order weights (the last row of A; the seventh stage is the next step's first).
const B5: [f64; 7] = [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0];
/// Fifth-order minus fourth-order weights (the error estimate).
const E: [f64; 7] =
    [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];

/// The integrator's error control and limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Relative tolerance on each component per step.
    pub rtol: f64,
    /// Absolute tolerance on each component per step (in the component's unit: m, rad, m/s,
    /// rad/s).
    pub atol: f64,
    /// Largest number of steps (accepted and rejected) over the whole integration.
    pub max_steps: usize,
}

impl Default for Tolerance {
    /// rtol 1e-10, atol 1e-12, ten million steps.
    fn default() -> Self {
        Tolerance { rtol: 1e-10, atol: 1e-12, max_steps: 10_000_000 }
    }
}

/// Counts of an integration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    pub accepted: usize,
    pub rejected: usize,
    /// Evaluations of the right-hand side.
    pub evaluations: usize,
}

/// Why an integration stopped.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IntegrateError {
    #[error("the sample times must be finite and non-decreasing, from the start time on")]
    Times,
    #[error("the right-hand side is not defined (not finite) at t = {0} s")]
    NotFinite(f64),
    #[error("the step size fell below round-off at t = {0} s")]
    StepTooSmall(f64),
    #[error("more than {0} steps")]
    TooManySteps(usize),
    #[error("interrupted")]
    Interrupted,
    #[error("bad tolerances (rtol and atol must be positive and finite)")]
    Tolerance,
}

/// The state at each of `times` of y' = f(t, y), y(t0) = y0. `f(t, y, dy)` writes y' into
/// `dy` and returns false where it is not defined. `cancel` is looked at every
/// `CANCEL_POLL_STEPS` steps.
pub fn dopri5(
    mut f: impl FnMut(f64, &[f64], &mut [f64]) -> bool,
    t0: f64,
    y0: &[f64],
    times: &[f64],
    tol: &Tolerance,
    cancel: Option<&AtomicBool>,
) -> Result<(Vec<Vec<f64>>, Stats), IntegrateError> {
    if times.windows(2).any(|w| w[1] < w[0]) || times.first().is_some_and(|t| *t < t0) {
        return Err(IntegrateError::Times);
    }
    let span = times.last().map_or(0.0, |e| e - t0);
    let mut d = Dopri5::start(&mut f, t0, y0, span, tol)?;
    let mut out = Vec::with_capacity(times.len());
    for &target in times {
        out.push(d.advance(&mut f, target, cancel)?.to_vec());
    }
    Ok((out, d.stats()))
}

/// The right-hand side y' = f(t, y) as [`dopri5`] takes it.
pub type Rhs<'a> = dyn FnMut(f64, &[f64], &mut [f64]) -> bool + 'a;

/// Dormand-Prince 5(4) that is advanced sample by sample ([`Dopri5::advance`]), the
/// right-hand side handed in at each call: the same steps, to the bit, as [`dopri5`] over all
/// the samples at once (which is this, in a loop).
#[derive(Clone, Debug)]
pub struct Dopri5 {
    t: f64,
    y: Vec<f64>,
    /// The next step's size [in t's unit].
    h: f64,
    s: Stepper,
}

impl Dopri5 {
    /// Starts at (t0, y0); `span` is how far the samples will reach beyond t0 (the first step
    /// is no longer).
    pub fn start(f: &mut Rhs, t0: f64, y0: &[f64], span: f64, tol: &Tolerance) -> Result<Self, IntegrateError> {
        if !(tol.rtol > 0.0 && tol.atol > 0.0 && tol.rtol.is_finite() && tol.atol.is_finite()) {
            return Err(IntegrateError::Tolerance);
        }
        if !t0.is_finite() || !span.is_finite() {
            return Err(IntegrateError::Times);
        }
        let mut s = Stepper::new(y0.len(), *tol);
        let mut k0 = std::mem::take(&mut s.k[0]);
        eval(f, t0, y0, &mut k0, &mut s.stats)?;
        s.k[0] = k0;
        let h = s.initial_step(y0, span);
        Ok(Dopri5 { t: t0, y: y0.to_vec(), h, s })
    }

    /// Counts so far.
    pub fn stats(&self) -> Stats {
        self.s.stats
    }

    /// The state at `target` (not before the last sample); `cancel` is looked at every
    /// `CANCEL_POLL_STEPS` steps.
    pub fn advance(&mut self, f: &mut Rhs, target: f64, cancel: Option<&AtomicBool>) -> Result<&[f64], IntegrateError> {
        if !target.is_finite() || target < self.t {
            return Err(IntegrateError::Times);
        }
        let s = &mut self.s;
        while self.t < target {
            let steps = s.stats.accepted + s.stats.rejected;
            if steps.is_multiple_of(CANCEL_POLL_STEPS) && cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
                return Err(IntegrateError::Interrupted);
            }
            if steps >= s.tol.max_steps {
                return Err(IntegrateError::TooManySteps(s.tol.max_steps));
            }
            // Land exactly on the target (a step that would end within round-off of it too).
            let (t, h) = (self.t, self.h);
            let last = t + h >= target - f64::EPSILON * target.abs().max(1.0);
            let step = if last { target - t } else { h };
            if step <= f64::EPSILON * t.abs().max(1.0) * 4.0 && !last {
                return Err(IntegrateError::StepTooSmall(t));
            }
            let (err, y_new) = s.trial(f, t, &self.y, step)?;
            let factor = (SAFETY * err.powf(-0.2)).clamp(FAC_MIN, FAC_MAX);
            if err <= 1.0 {
                s.stats.accepted += 1;
                self.t = if last { target } else { t + step };
                self.y = y_new;
                s.k.swap(0, 6);
                // A step shortened to land on a sample says nothing about the next one.
                self.h = if last { h.max(step * factor) } else { step * factor };
            } else {
                s.stats.rejected += 1;
                self.h = step * factor.min(1.0);
            }
        }
        Ok(&self.y)
    }
}

/// `f` at (t, y) into `dy`, counted; Err where it is not defined or not finite.
fn eval(f: &mut Rhs, t: f64, y: &[f64], dy: &mut [f64], stats: &mut Stats) -> Result<(), IntegrateError> {
    stats.evaluations += 1;
    if f(t, y, dy) && dy.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(IntegrateError::NotFinite(t))
    }
}

/// The stages and counts of an integration.
#[derive(Clone, Debug)]
struct Stepper {
    k: Vec<Vec<f64>>,
    tol: Tolerance,
    stats: Stats,
}

impl Stepper {
    fn new(n: usize, tol: Tolerance) -> Self {
        Stepper { k: vec![vec![0.0; n]; 7], tol, stats: Stats::default() }
    }

    /// Error scale of component i (Hairer II.4, Eq. 4.10).
    fn scale(&self, a: f64, b: f64) -> f64 {
        self.tol.atol + self.tol.rtol * a.abs().max(b.abs())
    }

    /// A first step from the size of y and y' (Hairer II.4, "starting step size", its first
    /// two stages), at most the whole span.
    fn initial_step(&self, y: &[f64], span: f64) -> f64 {
        let n = y.len().max(1) as f64;
        let norm =
            |v: &[f64]| (v.iter().zip(y).map(|(x, yi)| (x / self.scale(*yi, *yi)).powi(2)).sum::<f64>() / n).sqrt();
        let (d0, d1) = (norm(y), norm(&self.k[0]));
        let h = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        if span > 0.0 {
            h.min(span)
        } else {
            h
        }
    }

    /// One trial step of size h from (t, y): the error norm and the fifth-order solution
    /// (the stages k[1..=6] are left for the next step: k[6] = f(t + h, y_new)).
    fn trial(&mut self, f: &mut Rhs, t: f64, y: &[f64], h: f64) -> Result<(f64, Vec<f64>), IntegrateError> {
        let n = y.len();
        let mut tmp = vec![0.0; n];
        for stage in 1..7 {
            for i in 0..n {
                tmp[i] = y[i] + h * (0..stage).map(|j| A[stage][j] * self.k[j][i]).sum::<f64>();
            }
            let mut dy = std::mem::take(&mut self.k[stage]);
            eval(f, t + C[stage] * h, &tmp, &mut dy, &mut self.stats)?;
            self.k[stage] = dy;
        }
        // The sixth row of A is B5, so tmp is the fifth-order solution.
        debug_assert_eq!(A[6][..6], B5[..6]);
        let mut sum = 0.0;
        for i in 0..n {
            let e = h * (0..7).map(|j| E[j] * self.k[j][i]).sum::<f64>();
            sum += (e / self.scale(y[i], tmp[i])).powi(2);
        }
        Ok(((sum / n.max(1) as f64).sqrt(), tmp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_decay_is_followed_within_the_tolerance() {
        let times: Vec<f64> = (1..=10).map(|i| i as f64 * 0.5).collect();
        let tol = Tolerance { rtol: 1e-12, atol: 1e-14, ..Tolerance::default() };
        let (ys, stats) = dopri5(
            |_, y, dy| {
                dy[0] = -y[0];
                true
            },
            0.0,
            &[1.0],
            &times,
            &tol,
            None,
        )
        .unwrap();
        for (t, y) in times.iter().zip(&ys) {
            assert!((y[0] - (-t).exp()).abs() < 1e-11, "t {t}: {} vs {}", y[0], (-t).exp());
        }
        assert!(stats.accepted > 0);
    }

    #[test]
    fn the_error_falls_as_the_fifth_power_of_a_fixed_step() {
        // With a loose tolerance the steps are not limited by it: force them by sample times.
        let err = |n: usize| {
            let times: Vec<f64> = (1..=n).map(|i| i as f64 / n as f64).collect();
            let tol = Tolerance { rtol: 1.0, atol: 1.0, ..Tolerance::default() };
            let (ys, _) = dopri5(
                |_, y, dy| {
                    dy[0] = y[1];
                    dy[1] = -y[0];
                    true
                },
                0.0,
                &[1.0, 0.0],
                &times,
                &tol,
                None,
            )
            .unwrap();
            (ys[n - 1][0] - 1f64.cos()).abs()
        };
        let order = (err(10) / err(20)).log2();
        assert!(order > 4.5 && order < 6.5, "observed order {order}");
    }

    /// Advanced sample by sample, the integrator takes the steps it takes over all the samples
    /// at once: the same states, to the bit, and the same counts.
    #[test]
    fn advancing_sample_by_sample_is_the_batch_integration_to_the_bit() {
        let mut pendulum = |_: f64, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1];
            dy[1] = -263.0 * y[0].sin();
            true
        };
        let times: Vec<f64> = (1..=500).map(|k| k as f64 * 1e-3).collect();
        let (y0, tol) = ([0.5, 0.0], Tolerance::default());
        let (batch, stats) = dopri5(&mut pendulum, 0.0, &y0, &times, &tol, None).unwrap();
        let mut d = Dopri5::start(&mut pendulum, 0.0, &y0, times[times.len() - 1], &tol).unwrap();
        for (t, y) in times.iter().zip(&batch) {
            assert_eq!(d.advance(&mut pendulum, *t, None).unwrap(), y.as_slice(), "t {t}");
        }
        assert_eq!(d.stats(), stats);
        assert_eq!(d.advance(&mut pendulum, 0.1, None).unwrap_err(), IntegrateError::Times);
    }

    #[test]
    fn decreasing_times_are_refused() {
        let r = dopri5(|_, _, _| true, 0.0, &[0.0], &[1.0, 0.5], &Tolerance::default(), None);
        assert_eq!(r.unwrap_err(), IntegrateError::Times);
    }
}
