//! `tensegrity fit`: named parameters of a scenario fitted to measured outputs (rows: settle
//! point, output, value, sigma) by Levenberg-Marquardt on the weighted residuals
//! r_i = (y_i(p) - measured_i) / sigma_i. Each evaluation parses the scenario again with the
//! parameters set as `--set NAME=VALUE` sets them (derived parameters follow), settles every
//! measured point afresh and takes the Jacobian dy_i/dp_j from the sensitivities there
//! (`run::sensitivity`, the implicit function theorem): no difference of settles.
//!
//! At the optimum, the weighted Jacobian's singular values (its columns scaled by each
//! parameter's value, so that the ratio is free of units) tell what the data identify: below
//! [`UNIDENTIFIABLE_RATIO`] of the largest, the right singular vector is a combination the
//! data do not see, and the parameters in it get an infinite interval (as MuJoCo's sysid
//! reports them). The covariance is (J^T J)^-1 over the other directions; scaled by the
//! reduced chi^2 only when no measurement states its sigma (each then weighs 1).

use super::problem::{close_names, scenario_at, FitError, FitProblem, Measurement};
use super::sensitivity::{point_of, SensitivityRunError};
use crate::report::fit::{Combination, FitReport, FitResidual, FittedParameter};
use crate::report::sensitivity::SensitivityReport;
use crate::scenario::Scenario;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Levenberg-Marquardt iterations (accepted steps) at most.
pub const MAX_ITERATIONS: usize = 50;
/// Converged when every parameter's step is below this fraction of its value.
pub const STEP_TOLERANCE: f64 = 1e-10;
/// Converged when a step lowers chi^2 by less than this fraction of it.
pub const COST_TOLERANCE: f64 = 1e-14;
/// Converged when a Gauss-Newton step from the iterate would lower chi^2 by less than this
/// (times the reduced chi^2 when no row states its sigma): the optimum is then within
/// sqrt(1e-6) = 1e-3 standard errors of the iterate along every identified direction, and the
/// Jacobian in hand is the optimum's to that order. Checked before each step, with the
/// Jacobian the last evaluation gave: it saves the step that would only confirm.
pub const DECREMENT_TOLERANCE: f64 = 1e-6;
/// A singular value of the weighted, value-scaled Jacobian below this fraction of the largest
/// is a direction the data do not identify.
pub const UNIDENTIFIABLE_RATIO: f64 = 1e-6;
/// A parameter is named in an unidentifiable combination when its weight in the singular
/// vector is above this.
pub const COMBINATION_FLOOR: f64 = 0.05;
/// The 95 % two-sided normal quantile: an interval is value -+ this many sigma.
pub const INTERVAL_Z_95: f64 = 1.959_963_984_540_054;
/// A parameter without bounds has run away when it moved by more than this many times its
/// initial value (or 1 at 0).
pub const RUNAWAY_RATIO: f64 = 1e6;
/// The first damping lambda of (J^T J + lambda diag(J^T J)) dp = -J^T r.
const INITIAL_DAMPING: f64 = 1e-3;
/// The damping's factor on a rejected step (and its divisor on an accepted one).
const DAMPING_FACTOR: f64 = 10.0;
/// No step lowers chi^2 once the damping exceeds this.
const MAX_DAMPING: f64 = 1e12;
/// The floor of diag(J^T J) in the damping, a fraction of its largest entry (a parameter
/// that moves nothing still gets a damped, finite step).
const DIAGONAL_FLOOR: f64 = 1e-12;

/// The model's outputs at the measurements and their derivatives by the fitted parameters.
struct Evaluation {
    model: DVector<f64>,
    jacobian: DMatrix<f64>,
}

/// The state of the iterations: parameters, evaluation there, weighted residuals, chi^2.
struct Iterate {
    p: DVector<f64>,
    eval: Evaluation,
    r: DVector<f64>,
    cost: f64,
}

/// Fits `problem` (see the module): the estimates, covariance, intervals, residuals and
/// unidentifiable combinations; stopped by `cancel`.
pub fn fit(problem: &FitProblem, cancel: Option<&AtomicBool>) -> Result<FitReport, FitError> {
    let start = Instant::now();
    let weights = validate(problem)?;
    let sc = crate::scenario::parse_with(&problem.file, &problem.source, &problem.overrides)?;
    let initial = initial_values(problem, &sc)?;
    let cancelled = || cancel.is_some_and(|c| c.load(Ordering::SeqCst));
    let model = &mut |p: &[f64]| evaluate(problem, p, cancel);
    let (it, iterations, stopped) = iterate(problem, &initial, &weights, model, &cancelled)?;
    let mut report = report(problem, &sc.name, &initial, &it, &weights, iterations, stopped);
    report.wall_s = start.elapsed().as_secs_f64();
    Ok(report)
}

/// The model's outputs and Jacobian at the parameters.
type Model<'a> = &'a mut dyn FnMut(&[f64]) -> Result<Evaluation, FitError>;

/// Levenberg-Marquardt from `initial` on `model` against `problem`'s measurements weighted by
/// `weights`: the optimum, the accepted steps and why they stopped. A step whose evaluation
/// fails (a settle that does not come) is rejected as one that raises chi^2, unless
/// `cancelled`.
fn iterate(
    problem: &FitProblem,
    initial: &DVector<f64>,
    weights: &DVector<f64>,
    model: Model,
    cancelled: &dyn Fn() -> bool,
) -> Result<(Iterate, usize, String), FitError> {
    let mut at = |p: &DVector<f64>| -> Result<Iterate, FitError> {
        let eval = model(p.as_slice())?;
        let r = (&eval.model - measured(problem)).component_mul(weights);
        let it = Iterate { p: p.clone(), cost: r.norm_squared(), eval, r };
        representable(problem, weights, &it)?;
        Ok(it)
    };
    let mut it = at(initial)?;
    let (mut lambda, mut iterations) = (INITIAL_DAMPING, 0);
    let stopped = loop {
        if iterations == MAX_ITERATIONS {
            break format!("the iteration cap, {MAX_ITERATIONS}");
        }
        if it.cost == 0.0 {
            break "chi^2 = 0".to_string();
        }
        let j = weighted(&it.eval.jacobian, weights);
        let decrement = decrement(&j, &it.r, it.p.as_slice());
        if decrement <= DECREMENT_TOLERANCE * noise_scale(problem, it.cost) {
            break format!("the optimum: a Gauss-Newton step would lower chi^2 by {decrement:.1e}");
        }
        let step = lm_step(&j, &it.r, lambda);
        let trial = bounded(problem, initial, &(&it.p + &step))?;
        // A parameter already at its bound that the step wants past it: the data want it
        // beyond (without this, the rejected steps would stop the fit there in silence).
        let pinned: DVector<f64> =
            DVector::from_fn(trial.len(), |k, _| if trial[k] == it.p[k] { (&it.p + &step)[k] } else { trial[k] });
        at_bound(problem, &pinned, &trial)?;
        let next = match at(&trial) {
            Ok(next) if next.cost < it.cost => next,
            Err(e) if !e.is_bad_input() && !cancelled() => {
                lambda *= DAMPING_FACTOR;
                if lambda > MAX_DAMPING {
                    return Err(e);
                }
                continue;
            }
            Err(e) => return Err(e),
            Ok(_) => {
                lambda *= DAMPING_FACTOR;
                if lambda > MAX_DAMPING {
                    break "no step lowers chi^2".to_string();
                }
                continue;
            }
        };
        iterations += 1;
        lambda /= DAMPING_FACTOR;
        let small_step = (0..trial.len()).all(|k| (trial[k] - it.p[k]).abs() <= STEP_TOLERANCE * trial[k].abs());
        let small_gain = it.cost - next.cost <= COST_TOLERANCE * it.cost;
        at_bound(problem, &(&it.p + &step), &trial)?;
        it = next;
        if small_step || small_gain {
            break if small_step { "the step tolerance" } else { "the chi^2 tolerance" }.to_string();
        }
    };
    Ok((it, iterations, stopped))
}

/// The weighted residuals, chi^2 and the weighted Jacobian's J^T J at `it` within what a float
/// holds; past it (a sigma of 1e-300 overflows chi^2 to infinity, after which no step is taken
/// and the interval came out of zero width around the start value) the fit stops as bad input,
/// naming the row that weighs most: its sigma, and the figures that overflowed.
fn representable(problem: &FitProblem, weights: &DVector<f64>, it: &Iterate) -> Result<(), FitError> {
    let j = weighted(&it.eval.jacobian, weights);
    let normal = j.transpose() * &j;
    if it.cost.is_finite() && normal.iter().all(|v| v.is_finite()) {
        return Ok(());
    }
    // Each row's weight in chi^2 and in J^T J (infinite where it overflowed, NaN taken so).
    let weight = |i: usize| {
        let w = it.r[i].powi(2) + j.row(i).norm_squared();
        if w.is_nan() {
            f64::INFINITY
        } else {
            w
        }
    };
    let i = (0..it.r.len()).max_by(|&a, &b| weight(a).total_cmp(&weight(b))).expect("validated: rows");
    let x = &problem.measurements[i];
    Err(FitError::BadInput(format!(
        "{}: sigma {:e} of {} weighs the fit past what a float holds (its weighted residual (model - measured)/sigma is {:e}, chi^2 {:e}): the estimate and its interval would mean nothing; state sigma in the output's unit, no smaller than the model resolves (every sigma scaled by one factor moves no estimate)",
        x.at,
        1.0 / weights[i],
        x.output,
        it.r[i],
        it.cost
    )))
}

/// What chi^2 is measured in: 1 when the rows state their sigmas, the reduced chi^2
/// `cost` / (rows - parameters) when none does (each row then weighs 1).
fn noise_scale(problem: &FitProblem, cost: f64) -> f64 {
    let (m, n) = (problem.measurements.len(), problem.parameters.len());
    if problem.measurements.iter().all(|x| x.sigma.is_none()) {
        cost / (m - n) as f64
    } else {
        1.0
    }
}

/// How much a Gauss-Newton step from here would lower chi^2 (the Newton decrement): the
/// squared norm of the weighted residuals `r` projected on the identified column space of the
/// weighted Jacobian `j` (its columns scaled by |p| to tell the identified directions as
/// [`covariance`] tells them).
fn decrement(j: &DMatrix<f64>, r: &DVector<f64>, p: &[f64]) -> f64 {
    let scale = DVector::from_iterator(p.len(), p.iter().map(|&v| if v == 0.0 { 1.0 } else { v.abs() }));
    let svd = (j * DMatrix::from_diagonal(&scale)).svd(true, false);
    let u = svd.u.expect("asked for U");
    let largest = svd.singular_values.max();
    (0..svd.singular_values.len())
        .filter(|&k| svd.singular_values[k] > UNIDENTIFIABLE_RATIO * largest)
        .map(|k| u.column(k).dot(r).powi(2))
        .sum()
}

/// The data checked (finite values, positive sigmas given on every row or on none, at least
/// as many rows as parameters, each parameter once), and each row's weight 1/sigma.
fn validate(problem: &FitProblem) -> Result<DVector<f64>, FitError> {
    let bad = |s: String| Err(FitError::BadInput(s));
    let (m, n) = (problem.measurements.len(), problem.parameters.len());
    if n == 0 {
        return bad("no parameter to fit: name one with --param NAME[=LOW:HIGH]".into());
    }
    for (k, f) in problem.parameters.iter().enumerate() {
        if problem.parameters[..k].iter().any(|g| g.name == f.name) {
            return bad(format!("--param {}: named twice", f.name));
        }
        if let Some(v) = [f.low, f.high].into_iter().flatten().find(|v| !v.is_finite()) {
            return bad(format!("--param {}: the bound {v} is not a finite number", f.name));
        }
        if let (Some(lo), Some(hi)) = (f.low, f.high) {
            if lo >= hi {
                return bad(format!("--param {}={lo}:{hi}: the low bound must be below the high one", f.name));
            }
        }
    }
    let with_sigma = problem.measurements.iter().filter(|x| x.sigma.is_some()).count();
    for x in &problem.measurements {
        if !x.value.is_finite() {
            return bad(format!("{}: the measured value of {} is {} (not a finite number)", x.at, x.output, x.value));
        }
        match x.sigma {
            Some(s) if !(s.is_finite() && s > 0.0) => {
                return bad(format!("{}: sigma of {} is {s}: a positive finite number", x.at, x.output));
            }
            None if with_sigma > 0 => {
                return bad(format!(
                    "{}: no sigma for {}, where other rows state one: give every row its sigma or none",
                    x.at, x.output
                ));
            }
            _ => {}
        }
    }
    if m < n || (with_sigma == 0 && m == n) {
        let why = if with_sigma == 0 {
            " (without sigmas the noise is estimated from the residuals: more rows than parameters)"
        } else {
            ""
        };
        return bad(format!("{m} measurements for {n} fitted parameters: too few{why}"));
    }
    Ok(DVector::from_iterator(m, problem.measurements.iter().map(|x| 1.0 / x.sigma.unwrap_or(1.0))))
}

/// Each fitted parameter's value in the scenario, within its bounds; an unknown name refused
/// with the parameters the scenario has.
fn initial_values(problem: &FitProblem, sc: &Scenario) -> Result<DVector<f64>, FitError> {
    let params = sc.params_at(sc.actuation.first_inputs());
    let mut p = Vec::new();
    for f in &problem.parameters {
        if sc.actuation.first_inputs().contains_key(&f.name) {
            return Err(FitError::BadInput(format!(
                "--param {}: the scenario's [actuation] sets '{}' at every point: it cannot be fitted",
                f.name, f.name
            )));
        }
        let Some(&v) = params.get(&f.name) else {
            let known: Vec<&str> = sc.params.keys().map(String::as_str).collect();
            let close = close_names(&f.name, known.iter().copied());
            return Err(FitError::BadInput(format!(
                "--param {}: the scenario has no parameter '{}'{close} (its parameters: {})",
                f.name,
                f.name,
                known.join(", ")
            )));
        };
        p.push(v.clamp(f.low.unwrap_or(f64::NEG_INFINITY), f.high.unwrap_or(f64::INFINITY)));
    }
    Ok(DVector::from_vec(p))
}

/// The measured values.
fn measured(problem: &FitProblem) -> DVector<f64> {
    DVector::from_iterator(problem.measurements.len(), problem.measurements.iter().map(|x| x.value))
}

/// The Jacobian's rows each times its weight.
fn weighted(j: &DMatrix<f64>, w: &DVector<f64>) -> DMatrix<f64> {
    let mut j = j.clone();
    for (i, mut row) in j.row_iter_mut().enumerate() {
        row *= w[i];
    }
    j
}

/// The Levenberg-Marquardt step: (J^T J + lambda D) dp = -J^T r, D = diag(J^T J) with a
/// floor, solved by the SVD (a direction the data do not see gets no step).
fn lm_step(j: &DMatrix<f64>, r: &DVector<f64>, lambda: f64) -> DVector<f64> {
    let mut a = j.transpose() * j;
    let g = j.transpose() * r;
    let largest = a.diagonal().amax().max(f64::MIN_POSITIVE);
    for k in 0..a.ncols() {
        a[(k, k)] += lambda * a[(k, k)].max(DIAGONAL_FLOOR * largest);
    }
    let n = a.ncols();
    a.svd(true, true).solve(&(-g), 0.0).unwrap_or_else(|_| DVector::zeros(n))
}

/// `p` within each parameter's bounds; a parameter without bounds that moved by more than
/// [`RUNAWAY_RATIO`] of its initial value is stopped and named.
fn bounded(problem: &FitProblem, initial: &DVector<f64>, p: &DVector<f64>) -> Result<DVector<f64>, FitError> {
    let mut out = p.clone();
    for (k, f) in problem.parameters.iter().enumerate() {
        out[k] = p[k].clamp(f.low.unwrap_or(f64::NEG_INFINITY), f.high.unwrap_or(f64::INFINITY));
        let scale = if initial[k] == 0.0 { 1.0 } else { initial[k].abs() };
        if !out[k].is_finite() || (out[k] - initial[k]).abs() > RUNAWAY_RATIO * scale {
            return Err(FitError::Stopped(format!(
                "{} ran away from {} to {:e}: the data do not hold it; bound it with --param {}=LOW:HIGH or fit fewer parameters",
                f.name, initial[k], p[k], f.name
            )));
        }
    }
    Ok(out)
}

/// An accepted step that a bound cut short stops the fit, naming the parameter: the data
/// want it beyond its bound.
fn at_bound(problem: &FitProblem, wanted: &DVector<f64>, taken: &DVector<f64>) -> Result<(), FitError> {
    match (0..wanted.len()).find(|&k| wanted[k] != taken[k]) {
        None => Ok(()),
        Some(k) => Err(FitError::Stopped(format!(
            "{} ran into its bound {} (the step wanted {:e}): the data want it beyond --param {}={}:{}",
            problem.parameters[k].name,
            taken[k],
            wanted[k],
            problem.parameters[k].name,
            problem.parameters[k].low.map_or(String::new(), |v| v.to_string()),
            problem.parameters[k].high.map_or(String::new(), |v| v.to_string()),
        ))),
    }
}

/// The model at `p`: each measured point settled afresh, its outputs and their derivatives.
fn evaluate(problem: &FitProblem, p: &[f64], cancel: Option<&AtomicBool>) -> Result<Evaluation, FitError> {
    let sc = scenario_at(problem, p)?;
    let file = problem.file.display().to_string();
    let (m, n) = (problem.measurements.len(), problem.parameters.len());
    // Each measured point once, settled in parallel (one a core); the first failure in the
    // data's order is the one reported.
    let mut first: BTreeMap<usize, &Measurement> = BTreeMap::new();
    for x in problem.measurements.iter().filter(|x| x.time_s.is_none()) {
        first.entry(x.point).or_insert(x);
    }
    let fitted: Vec<String> = problem.parameters.iter().map(|f| f.name.clone()).collect();
    let settled: Vec<(usize, Result<SensitivityReport, FitError>)> =
        first.par_iter().map(|(&point, x)| (point, settled_point(&sc, (&file, &fitted), x, p, cancel))).collect();
    let mut reports: BTreeMap<usize, Result<SensitivityReport, FitError>> = settled.into_iter().collect();
    if let Some(x) = problem.measurements.iter().find(|x| x.time_s.is_none() && reports[&x.point].is_err()) {
        return Err(reports.remove(&x.point).expect("a point settled").expect_err("a failure"));
    }
    let reports: BTreeMap<usize, SensitivityReport> =
        reports.into_iter().map(|(k, r)| (k, r.expect("no failure"))).collect();
    let mut eval = Evaluation { model: DVector::zeros(m), jacobian: DMatrix::zeros(m, n) };
    let timed: Vec<usize> = (0..m).filter(|&i| problem.measurements[i].time_s.is_some()).collect();
    if !timed.is_empty() {
        let rows: Vec<&Measurement> = timed.iter().map(|&i| &problem.measurements[i]).collect();
        let (model, jacobian) = super::fit_trajectory::trajectory_evaluation(problem, &rows, p, cancel)?;
        for (k, &i) in timed.iter().enumerate() {
            eval.model[i] = model[k];
            eval.jacobian.set_row(i, &jacobian.row(k));
        }
    }
    for (i, x) in problem.measurements.iter().enumerate().filter(|(_, x)| x.time_s.is_none()) {
        let r = &reports[&x.point];
        let Some(k) = r.outputs.iter().position(|o| o.name == x.output) else {
            let close = close_names(&x.output, r.outputs.iter().map(|o| o.name.as_str()));
            return Err(FitError::BadInput(format!(
                "{}: output '{}' names nothing at point {}{close} (see `tensegrity sensitivity --point {}`)",
                x.at, x.output, x.point, x.point
            )));
        };
        eval.model[i] = r.outputs[k].value;
        for (j, f) in problem.parameters.iter().enumerate() {
            let row = r.parameters.iter().find(|q| q.name == f.name);
            let row = row.ok_or_else(|| {
                FitError::BadInput(format!("--param {}: not a parameter at point {}", f.name, x.point))
            })?;
            if let Some(e) = &row.error {
                return Err(FitError::Failed(format!("d {}/d {}: {e}", x.output, f.name)));
            }
            if let Some(why) = &row.switch {
                return Err(FitError::BadInput(format!(
                    "--param {}: a switch at point {} ({why}): the fit needs its derivative; start it off the switch with --set {}=VALUE",
                    f.name, x.point, f.name
                )));
            }
            eval.jacobian[(i, j)] = row.derivatives[k];
        }
    }
    Ok(eval)
}

/// The sensitivities to the `fitted` parameters at measurement `x`'s point of `sc` (at their
/// values `p`), settled afresh; a point the scenario has not, or a structure the sensitivities refuse, is
/// bad input.
fn settled_point(
    sc: &Scenario,
    (file, fitted): (&str, &[String]),
    x: &Measurement,
    p: &[f64],
    cancel: Option<&AtomicBool>,
) -> Result<SensitivityReport, FitError> {
    if point_of(sc, x.point).is_none() {
        return Err(FitError::BadInput(format!("{}: the scenario has no point {} (from 0)", x.at, x.point)));
    }
    let r =
        super::sensitivity::sensitivity_to(sc, file, (x.point, Some(fitted)), false, cancel).map_err(|e| match e {
            SensitivityRunError::Refused(_) => FitError::BadInput(format!("{file}: {e}")),
            _ => FitError::Failed(format!("{file} at point {}: {e}", x.point)),
        })?;
    if !r.settled {
        return Err(FitError::Failed(format!("{file}: point {} did not settle at {p:?}", x.point)));
    }
    Ok(r)
}

/// The report at the optimum `it`: intervals from the covariance, residuals, combinations.
fn report(
    problem: &FitProblem,
    name: &str,
    initial: &DVector<f64>,
    it: &Iterate,
    weights: &DVector<f64>,
    iterations: usize,
    stopped: String,
) -> FitReport {
    let (m, n) = (problem.measurements.len(), problem.parameters.len());
    let scaled = problem.measurements.iter().all(|x| x.sigma.is_none());
    let dof = m - n;
    let factor = if scaled { it.cost / dof as f64 } else { 1.0 };
    let names: Vec<String> = problem.parameters.iter().map(|f| f.name.clone()).collect();
    let (covariance, unidentifiable) =
        covariance(&weighted(&it.eval.jacobian, weights), it.p.as_slice(), &names, factor);
    let parameters = (0..n)
        .map(|k| {
            let sigma = covariance[(k, k)].sqrt();
            let (value, half) = (it.p[k], INTERVAL_Z_95 * sigma);
            FittedParameter {
                name: names[k].clone(),
                initial: initial[k],
                value,
                sigma,
                low: value - half,
                high: value + half,
            }
        })
        .collect();
    let residuals = problem
        .measurements
        .iter()
        .enumerate()
        .map(|(i, x)| FitResidual {
            point: x.point,
            time_s: x.time_s,
            output: x.output.clone(),
            measured: x.value,
            model: it.eval.model[i],
            sigma: 1.0 / weights[i],
            weighted: it.r[i],
        })
        .collect();
    FitReport {
        name: name.to_string(),
        file: problem.file.display().to_string(),
        parameters,
        covariance: covariance.row_iter().map(|r| r.iter().copied().collect()).collect(),
        covariance_scaled: scaled,
        residuals,
        chi2: it.cost,
        degrees_of_freedom: dof,
        iterations,
        stopped,
        unidentifiable,
        wall_s: 0.0,
    }
}

/// (J^T J)^-1 times `factor` over the identifiable directions of the weighted Jacobian `j`
/// (its columns scaled by |p| for the singular values' ratio), infinite on the rows and
/// columns of the parameters in an unidentifiable combination; and those combinations.
fn covariance(j: &DMatrix<f64>, p: &[f64], names: &[String], factor: f64) -> (DMatrix<f64>, Vec<Combination>) {
    let n = p.len();
    let scale = DVector::from_iterator(n, p.iter().map(|&v| if v == 0.0 { 1.0 } else { v.abs() }));
    let js = j * DMatrix::from_diagonal(&scale);
    let svd = js.svd(false, true);
    let v_t = svd.v_t.expect("asked for V^T");
    let largest = svd.singular_values.max();
    let mut cov = DMatrix::zeros(n, n);
    let mut combinations = Vec::new();
    let mut unseen = vec![false; n];
    for (k, &s) in svd.singular_values.iter().enumerate() {
        let v = v_t.row(k).transpose();
        if s > UNIDENTIFIABLE_RATIO * largest {
            cov += &v * v.transpose() / (s * s);
            continue;
        }
        let sign = if v[v.iamax()] < 0.0 { -1.0 } else { 1.0 };
        let weights: Vec<(String, f64)> =
            (0..n).filter(|&q| v[q].abs() > COMBINATION_FLOOR).map(|q| (names[q].clone(), sign * v[q])).collect();
        (0..n).filter(|&q| v[q].abs() > COMBINATION_FLOOR).for_each(|q| unseen[q] = true);
        combinations.push(Combination { weights, ratio: if largest > 0.0 { s / largest } else { 0.0 } });
    }
    let mut cov = DMatrix::from_diagonal(&scale) * cov * DMatrix::from_diagonal(&scale) * factor;
    for q in (0..n).filter(|&q| unseen[q]) {
        cov.row_mut(q).fill(f64::INFINITY);
        cov.column_mut(q).fill(f64::INFINITY);
    }
    (cov, combinations)
}

/// A standard normal number drawn from `state` (splitmix64, then Box-Muller): synthetic
/// measurement noise that is the same for a seed on every machine (the fit's experiments and
/// tests draw their noise with it).
pub fn standard_normal(state: &mut u64) -> f64 {
    let mut uniform = || {
        *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let (u, v) = (uniform().max(f64::MIN_POSITIVE), uniform());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::problem::FitParameter;
    use std::path::PathBuf;

    /// The seeds of the coverage check, and the noise on each of the line's points.
    const SEEDS: u64 = 200;
    const POINTS: usize = 10;
    const NOISE: f64 = 0.01;

    /// A line y = p0 + p1 t at t = 0 .. 0.9 measured with Gaussian noise of sigma NOISE
    /// (truth p = (2, 0.5)), fitted over 200 seeds: each 95 % interval holds the truth in
    /// 0.95 -+ 0.033 of the 400 intervals (three binomial standard deviations, the draws
    /// fixed by the seeds), and each fit converges in at most 6 steps (the model is linear:
    /// each step leaves about the damping's share of the error, 1e-3 falling tenfold a step).
    #[test]
    fn intervals_of_a_line_hold_the_truth_in_95_percent_of_fits() {
        let truth = [2.0, 0.5];
        let t: Vec<f64> = (0..POINTS).map(|i| 0.1 * i as f64).collect();
        let mut held = 0;
        for seed in 0..SEEDS {
            let mut state = seed;
            let measurements = t
                .iter()
                .map(|&ti| Measurement {
                    at: String::new(),
                    point: 0,
                    output: "y".into(),
                    value: truth[0] + truth[1] * ti + NOISE * standard_normal(&mut state),
                    sigma: Some(NOISE),
                    time_s: None,
                })
                .collect();
            let parameters =
                ["p0", "p1"].iter().map(|n| FitParameter { name: n.to_string(), low: None, high: None }).collect();
            let problem = FitProblem {
                file: PathBuf::from("line"),
                source: String::new(),
                overrides: Vec::new(),
                parameters,
                measurements,
            };
            let weights = validate(&problem).expect("valid");
            let initial = DVector::from_vec(vec![1.0, 1.0]);
            let model = &mut |p: &[f64]| {
                Ok(Evaluation {
                    model: DVector::from_iterator(POINTS, t.iter().map(|ti| p[0] + p[1] * ti)),
                    jacobian: DMatrix::from_fn(POINTS, 2, |i, j| if j == 0 { 1.0 } else { t[i] }),
                })
            };
            let (it, iterations, stopped) = iterate(&problem, &initial, &weights, model, &|| false).expect("a fit");
            assert!(iterations <= 6, "seed {seed}: {iterations} steps ({stopped})");
            let r = report(&problem, "line", &initial, &it, &weights, iterations, stopped);
            held += r.parameters.iter().zip(truth).filter(|(p, v)| p.low <= *v && *v <= p.high).count();
        }
        let fraction = held as f64 / (2 * SEEDS) as f64;
        assert!((fraction - 0.95).abs() <= 0.033, "{held} of {} intervals hold the truth", 2 * SEEDS);
    }
}
