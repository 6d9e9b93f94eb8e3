//! The file's dynamic model: a kinetic energy T(q, q') in the `[energy]` coordinates q and
//! their rates q' (`NAME_dot`) beside the potential V(q). From its derivatives (forward, exact to round-off):
//! - the mass matrix M(q) = d2T/dq'2 (T must be a quadratic form in the rates, so M does not
//!   depend on them);
//! - the linearised natural frequencies and mode shapes at a stationary point q*: the
//!   generalized symmetric eigenproblem K v = omega^2 M v, K = d2V/dq2 at q*;
//! - the Lagrangian equations of motion d/dt(dT/dq') - dT/dq + dV/dq = 0, that is
//!   M q'' = dT/dq - (d2T/dq' dq) q' - dV/dq  (1)
//!   (d/dt (dT/dq') = M q'' + (d2T/dq' dq) q', the term written (dM/dt) q' in the issue),
//!   integrated by Dormand-Prince 5(4) ([`super::integrate`]).

use super::energy_model::EnergySpec;
use super::expr::Expr;
use super::integrate::{Dopri5, IntegrateError, Stats, Tolerance};
use super::spec::ModelSpec;
use crate::eigen::{modes, EigenError, Mode};
use crate::mechanisms::Values;
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::AtomicBool;

/// The suffix naming a coordinate's rate (`q` -> `q_dot`).
pub const RATE_SUFFIX: &str = "_dot";
/// The prefix naming the potential's second derivatives at the solved equilibrium in a
/// formula (`V_q_r` = d2V/dq dr there).
pub const STIFFNESS_PREFIX: &str = "V_";
/// The prefix naming the mass matrix's entries there (`M_q_r` = d2T/dq' dr').
pub const MASS_PREFIX: &str = "M_";

/// A `[[energy.frequencies]]` entry: a closed form of the parameters and inputs predicting the
/// natural frequency of one mode of the file's dynamic model [rad/s].
#[derive(Clone, Debug)]
pub struct FrequencyPrediction {
    pub name: String,
    /// Compiled against the model's closed-form symbols, then [`EnergySpec::solved_names`].
    pub formula: Expr,
    /// The formula reads the solved equilibrium (known only once the model is solved at a
    /// settle point, so not checked at the file's points beforehand).
    pub solved: bool,
    /// The mode, counted from 0 in ascending omega (the file counts from 1).
    pub mode: usize,
    /// On |omega - predicted| / |predicted|.
    pub tolerance: f64,
}

/// The compiled kinetic energy and its derivatives. Compiled against the model's symbols,
/// then the coordinates (at `EnergySpec::first_coordinate`), then the rates (at `first_rate`).
#[derive(Clone, Debug)]
pub struct Dynamics {
    pub kinetic: Expr,
    /// d2T/dq'_i dq'_j, row-major n x n.
    pub mass: Vec<Expr>,
    /// dT/dq_i.
    pub kinetic_gradient: Vec<Expr>,
    /// d2T/dq'_i dq_j, row-major n x n.
    pub mixed: Vec<Expr>,
    pub first_rate: usize,
    pub frequencies: Vec<FrequencyPrediction>,
    /// `[energy.trajectory]`: a motion run compared with the Lagrangian equations, tick by tick.
    pub trajectory: Option<TrajectoryCheck>,
}

/// The tolerances of a motion against the Lagrangian model, per coordinate and in its class,
/// and where the model starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajectoryCheck {
    /// On the largest error over the motion's ticks [m or rad].
    pub tolerance: f64,
    /// On the rms error over them, if given.
    pub rms_tolerance: Option<f64>,
    pub start: TrajectoryStart,
    /// How the simulated and the model's frequencies are measured from their trajectories.
    pub measure: FrequencyMeasure,
}

/// How a motion's frequency is measured from the sampled coordinate (`[[motion.frequencies]]
/// measure`); either is then corrected for symplectic Euler's dispersion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrequencyMeasure {
    /// A least-squares fit of c + A cos(w t + p) over every tick: exact for a linear
    /// oscillator, biased at large amplitude (the harmonics of a nonlinear motion pull the fit).
    #[default]
    Cosine,
    /// The mean period between interpolated zero crossings of the rate over every full period
    /// of the record: unbiased at any amplitude.
    Period,
}

impl FrequencyMeasure {
    /// As the file and the report name it.
    pub fn label(self) -> &'static str {
        match self {
            FrequencyMeasure::Cosine => "cosine",
            FrequencyMeasure::Period => "period",
        }
    }
}

/// Where the Lagrangian model of `[energy.trajectory]` starts (`start = "..."`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TrajectoryStart {
    /// From the simulation's own first three samples, at t = 1.5 dt (the leapfrog's
    /// half-step rates): nothing is assumed of how the motion was started.
    #[default]
    Samples,
    /// From the file's initial condition at t = 0: the coordinates of the state the motion
    /// starts from (the settled or drawn equilibrium with `[motion]`'s displacement), and
    /// `[motion]`'s rate along them. The paper's claim, as it states it.
    Stated,
}

impl TrajectoryStart {
    /// The names a file writes.
    pub const NAMES: &'static [&'static str] = &["samples", "stated"];

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "samples" => Some(TrajectoryStart::Samples),
            "stated" => Some(TrajectoryStart::Stated),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            TrajectoryStart::Samples => "samples",
            TrajectoryStart::Stated => "stated",
        }
    }
}

/// The coordinates and rates of a trajectory at its sample times.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    /// The sample times \[s\].
    pub times: Vec<f64>,
    /// q at each sample, in the order of `[[energy.coordinates]]` (m or rad).
    pub coordinates: Vec<Vec<f64>>,
    /// q' at each sample (m/s or rad/s).
    pub rates: Vec<Vec<f64>>,
    pub stats: Stats,
}

/// Why the model cannot be integrated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    #[error("the file states no kinetic energy ([energy] kinetic)")]
    NoKinetic,
    #[error("expected {0} initial coordinates and rates, got {1} and {2}")]
    Size(usize, usize, usize),
    #[error("the kinetic energy's mass matrix is not positive definite at q = {0:?}")]
    MassNotPositiveDefinite(Vec<f64>),
    #[error(transparent)]
    Integrate(#[from] IntegrateError),
}

/// The names a formula over the model's solved equilibrium reads (a frequency formula: a
/// paper's omega(k) = sqrt(V''(phi*(k)) / I) where phi* has no closed form): each coordinate,
/// its value at the stationary point the dynamics landed on; `V_a_b`, the potential's second
/// derivative in coordinates a and b there; with a kinetic energy (`kinetic`) `M_a_b`, the
/// mass matrix's entry.
pub fn solved_names(coordinates: &[super::energy_model::Coordinate], kinetic: bool) -> Vec<String> {
    let names: Vec<&str> = coordinates.iter().map(|c| c.name.as_str()).collect();
    let pairs = |prefix: &str| {
        names.iter().flat_map(|a| names.iter().map(move |b| format!("{prefix}{a}_{b}"))).collect::<Vec<_>>()
    };
    let mut out: Vec<String> = names.iter().map(|n| n.to_string()).collect();
    out.extend(pairs(STIFFNESS_PREFIX));
    if kinetic {
        out.extend(pairs(MASS_PREFIX));
    }
    out
}

impl EnergySpec {
    /// The slice length the dynamic model's expressions are evaluated with.
    pub fn values_len(&self) -> usize {
        self.first_coordinate + 2 * self.coordinates.len()
    }

    fn matrix(&self, exprs: &[Expr], values: &[f64]) -> DMatrix<f64> {
        let n = self.coordinates.len();
        DMatrix::from_fn(n, n, |i, j| exprs[i * n + j].eval(values))
    }

    /// `values` with the coordinates set to `q` and the rates to `v`.
    pub fn set_state(&self, values: &mut [f64], q: &[f64], v: &[f64]) {
        let (f, n) = (self.first_coordinate, self.coordinates.len());
        values[f..f + n].copy_from_slice(q);
        values[f + n..f + 2 * n].copy_from_slice(v);
    }

    /// The names a formula over the model's solved equilibrium reads ([`solved_names`]).
    pub fn solved_names(&self) -> Vec<String> {
        solved_names(&self.coordinates, self.dynamics.is_some())
    }

    /// The values of [`EnergySpec::solved_names`] at the stationary point `q`, with the
    /// parameters and inputs in `values` (of [`EnergySpec::values_len`]).
    pub fn solved_values(&self, values: &mut [f64], q: &[f64]) -> Vec<f64> {
        self.set_state(values, q, &vec![0.0; q.len()]);
        let mut out = q.to_vec();
        out.extend(self.hessian.iter().map(|h| h.eval(values)));
        if let Some(d) = &self.dynamics {
            out.extend(d.mass.iter().map(|m| m.eval(values)));
        }
        out
    }

    /// The mass matrix M(q) at the coordinates in `values` (None without a kinetic energy).
    pub fn mass_at(&self, values: &[f64]) -> Option<DMatrix<f64>> {
        Some(self.matrix(&self.dynamics.as_ref()?.mass, values))
    }

    /// The linearised modes at the coordinates `q` (a stationary point): K v = omega^2 M v,
    /// omega ascending, shapes mass-normalised (None without a kinetic energy).
    pub fn modes_at(&self, values: &mut [f64], q: &[f64]) -> Option<Result<Vec<Mode>, EigenError>> {
        self.dynamics.as_ref()?;
        let zero = vec![0.0; q.len()];
        self.set_state(values, q, &zero);
        let k = self.matrix(&self.hessian, values);
        Some(modes(&k, &self.mass_at(values)?))
    }

    /// q'' from Eq. (1) at the state in `values` (None where M is singular).
    pub fn acceleration(&self, values: &[f64]) -> Option<DVector<f64>> {
        let d = self.dynamics.as_ref()?;
        let n = self.coordinates.len();
        let rates = DVector::from_fn(n, |i, _| values[d.first_rate + i]);
        let dt_dq = DVector::from_fn(n, |i, _| d.kinetic_gradient[i].eval(values));
        let dv_dq = DVector::from_fn(n, |i, _| self.gradient[i].eval(values));
        let rhs = dt_dq - self.matrix(&d.mixed, values) * rates - dv_dq;
        self.matrix(&d.mass, values).cholesky().map(|c| c.solve(&rhs))
    }

    /// The trajectory from (q0, v0) at t = 0, sampled at `times` (s, non-decreasing, from 0),
    /// with the closed forms (parameters, inputs) in `values` (at least the model's symbols).
    pub fn integrate(
        &self,
        values: &[f64],
        q0: &[f64],
        v0: &[f64],
        times: &[f64],
        tol: &Tolerance,
        cancel: Option<&AtomicBool>,
    ) -> Result<Trajectory, DynamicsError> {
        if times.windows(2).any(|w| w[1] < w[0]) || times.first().is_some_and(|t| *t < 0.0) {
            return Err(IntegrateError::Times.into());
        }
        let span = times.last().copied().unwrap_or(0.0);
        let mut stepper = self.start_trajectory(values, q0, v0, span, tol)?;
        let mut out = Trajectory { times: times.to_vec(), ..Trajectory::default() };
        for &t in times {
            let (q, v) = stepper.advance(self, t, cancel)?;
            out.coordinates.push(q.to_vec());
            out.rates.push(v.to_vec());
        }
        out.stats = stepper.stats();
        Ok(out)
    }

    /// The model's motion from (q0, v0) at t = 0, to be advanced sample by sample
    /// ([`TrajectoryStepper::advance`]) up to `span` \[s\]: the same steps, to the bit, as
    /// [`EnergySpec::integrate`] over every sample at once.
    pub fn start_trajectory(
        &self,
        values: &[f64],
        q0: &[f64],
        v0: &[f64],
        span: f64,
        tol: &Tolerance,
    ) -> Result<TrajectoryStepper, DynamicsError> {
        self.dynamics.as_ref().ok_or(DynamicsError::NoKinetic)?;
        let n = self.coordinates.len();
        if q0.len() != n || v0.len() != n {
            return Err(DynamicsError::Size(n, q0.len(), v0.len()));
        }
        let mut work = values.to_vec();
        work.resize(self.values_len(), 0.0);
        self.set_state(&mut work, q0, v0);
        if !self.mass_at(&work).is_some_and(|m| crate::eigen::is_positive_definite(&m)) {
            return Err(DynamicsError::MassNotPositiveDefinite(q0.to_vec()));
        }
        let y0: Vec<f64> = q0.iter().chain(v0).copied().collect();
        let dopri = Dopri5::start(&mut self.rhs(&mut work), 0.0, &y0, span, tol)?;
        Ok(TrajectoryStepper { work, dopri })
    }

    /// The right-hand side of Eq. (1) as a first-order system y = (q, q'), evaluated in `work`.
    fn rhs<'a>(&'a self, work: &'a mut [f64]) -> impl FnMut(f64, &[f64], &mut [f64]) -> bool + 'a {
        let n = self.coordinates.len();
        move |_t: f64, y: &[f64], dy: &mut [f64]| {
            self.set_state(work, &y[..n], &y[n..]);
            let Some(a) = self.acceleration(work) else { return false };
            dy[..n].copy_from_slice(&y[n..]);
            dy[n..].copy_from_slice(a.as_slice());
            true
        }
    }
}

/// The model's motion between two samples: the integrator and the symbols' values it
/// evaluates the model with.
#[derive(Clone, Debug)]
pub struct TrajectoryStepper {
    work: Vec<f64>,
    dopri: Dopri5,
}

impl TrajectoryStepper {
    /// (q, q') at `t` [s since the start], not before the last sample.
    pub fn advance(
        &mut self,
        energy: &EnergySpec,
        t: f64,
        cancel: Option<&AtomicBool>,
    ) -> Result<(&[f64], &[f64]), DynamicsError> {
        let n = energy.coordinates.len();
        let y = self.dopri.advance(&mut energy.rhs(&mut self.work), t, cancel)?;
        Ok((&y[..n], &y[n..]))
    }

    /// Counts so far.
    pub fn stats(&self) -> Stats {
        self.dopri.stats()
    }
}

/// Where a trajectory starts (t = 0), in the order of `[[energy.coordinates]]`.
#[derive(Clone, Copy, Debug)]
pub struct InitialState<'a> {
    /// q(0) [m or rad].
    pub coordinates: &'a [f64],
    /// q'(0) [m/s or rad/s].
    pub rates: &'a [f64],
}

/// The file's dynamic model integrated from `start` at t = 0 and sampled at `times` \[s\]: the
/// parameters (`params`, a swept set; one absent keeps the scenario's value) and inputs held
/// at their values. The comparison with a simulated motion calls this.
pub fn integrate(
    spec: &ModelSpec,
    inputs: &Values,
    params: &Values,
    start: InitialState,
    times: &[f64],
    tol: &Tolerance,
    cancel: Option<&AtomicBool>,
) -> Result<Trajectory, DynamicsError> {
    let energy = spec.energy.as_ref().ok_or(DynamicsError::NoKinetic)?;
    let values = spec.values(inputs, params, |_| f64::NAN);
    energy.integrate(&values, start.coordinates, start.rates, times, tol, cancel)
}
