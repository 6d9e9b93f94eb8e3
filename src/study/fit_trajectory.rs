//! The trajectory rows of a fit: a measurement with a time `t_s` is a value of the scenario's
//! motion at that time since the motion's start (a column of the per-tick table, as `run
//! --table` names it: `joint:pin.angle`, `node:A.x`, a file quantity), read off the judged
//! trajectory (`[motion]`: extrapolated over the step, its error about 1e-9 of the motion) at
//! the tick whose `motion_time_s` is `t_s`. The model is one run at the fitted parameters; its
//! Jacobian the central differences of runs at each parameter +- h, +- 2 h (h = 1e-3 of the
//! value, as the sensitivities step), extrapolated: error O(h^4), and the trajectory's own
//! error over h, about 1e-6 of the derivative. The runs go in parallel, one a core, as
//! MuJoCo's sysid differences its rollouts.

use super::problem::{close_names, scenario_at, FitError, FitProblem, Measurement};
use crate::observers::table::{Batched, MemoryTable, TableTarget};
use crate::run::sensitivity::parameter_step;
use crate::sim::sensitivity::derivative_from_samples;
use arrow_array::{Array, Float64Array};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;

/// The samples of each derivative, in steps: -2 h, -h, h, 2 h.
const SAMPLES: [f64; 4] = [-2.0, -1.0, 1.0, 2.0];
/// A measured time is a tick's when it is within this fraction of the time step of it.
const TICK_TIME_FRACTION: f64 = 1e-6;

/// The model's values at the trajectory rows `rows` (each with its time) and their
/// derivatives by the fitted parameters at `p`.
pub(super) fn trajectory_evaluation(
    problem: &FitProblem,
    rows: &[&Measurement],
    p: &[f64],
    cancel: Option<&AtomicBool>,
) -> Result<(DVector<f64>, DMatrix<f64>), FitError> {
    let n = p.len();
    // The parameters of each run: the fit's, then each parameter's four samples.
    let mut sets: Vec<Vec<f64>> = vec![p.to_vec()];
    for j in 0..n {
        for s in SAMPLES {
            let mut q = p.to_vec();
            q[j] += s * parameter_step(p[j]);
            sets.push(q);
        }
    }
    let runs: Vec<Result<DVector<f64>, FitError>> =
        sets.par_iter().map(|q| run_at(problem, q, cancel).and_then(|t| values(problem, &t, rows))).collect();
    let mut runs = runs.into_iter().collect::<Result<Vec<_>, _>>()?.into_iter();
    let model = runs.next().expect("the run at the fit's parameters");
    let mut jacobian = DMatrix::zeros(rows.len(), n);
    for (j, &value) in p.iter().enumerate() {
        let y: Vec<DVector<f64>> = runs.by_ref().take(SAMPLES.len()).collect();
        let d = derivative_from_samples(y[0].clone(), y[1].clone(), y[2].clone(), y[3].clone(), parameter_step(value));
        jacobian.set_column(j, &d);
    }
    Ok((model, jacobian))
}

/// The scenario's run at the fitted parameters `p`, its per-tick table kept.
fn run_at(problem: &FitProblem, p: &[f64], cancel: Option<&AtomicBool>) -> Result<Batched, FitError> {
    let sc = scenario_at(problem, p)?;
    let file = problem.file.display();
    if sc.motion.is_none() {
        return Err(FitError::BadInput(format!(
            "{file}: the data's t_s column reads a motion, and the scenario has no [motion]"
        )));
    }
    let kept = MemoryTable::default();
    let opts = crate::run::RunOptions { cancel, table: Some(TableTarget::Memory(kept.clone())), ..Default::default() };
    let report = crate::run::run(&sc, &opts);
    if let Some(e) = &report.error {
        return Err(FitError::Failed(format!("{file} at {p:?}: {e}")));
    }
    kept.take().ok_or_else(|| FitError::Failed(format!("{file} at {p:?}: the motion ran no tick")))
}

/// Each row's value in the table `t`: its output's column at the tick of its time.
fn values(problem: &FitProblem, t: &Batched, rows: &[&Measurement]) -> Result<DVector<f64>, FitError> {
    let (schema, batches) = t;
    let column = |name: &str| -> Vec<f64> {
        let Ok(k) = schema.index_of(name) else { return Vec::new() };
        let mut out = Vec::new();
        for b in batches {
            let Some(c) = b.column(k).as_any().downcast_ref::<Float64Array>() else { continue };
            out.extend((0..c.len()).map(|i| if c.is_null(i) { f64::NAN } else { c.value(i) }));
        }
        out
    };
    let times = column("motion_time_s");
    // Each output's column once, however many rows read it.
    let mut columns: std::collections::BTreeMap<&str, Vec<f64>> = std::collections::BTreeMap::new();
    let dt_s = times.windows(2).map(|w| w[1] - w[0]).find(|d| d.is_finite() && *d > 0.0).unwrap_or(f64::INFINITY);
    let mut out = DVector::zeros(rows.len());
    for (i, x) in rows.iter().enumerate() {
        let t_s = x.time_s.expect("a trajectory row has a time");
        let Some(tick) = times.iter().position(|&m| (m - t_s).abs() <= TICK_TIME_FRACTION * dt_s) else {
            return Err(FitError::BadInput(format!(
                "{}: t_s = {t_s} is not the time of a tick of the motion of {} (every {dt_s} s from 0 to {} s)",
                x.at,
                problem.file.display(),
                times.iter().copied().filter(|m| m.is_finite()).fold(0.0, f64::max)
            )));
        };
        let values = columns.entry(x.output.as_str()).or_insert_with(|| column(&x.output));
        if values.is_empty() {
            let names: Vec<&str> = schema.fields().iter().map(|f| f.name().as_str()).collect();
            return Err(FitError::BadInput(format!(
                "{}: output '{}' is no column of the motion's table{} (see `tensegrity run --table`)",
                x.at,
                x.output,
                close_names(&x.output, names.into_iter())
            )));
        }
        out[i] = values[tick];
    }
    Ok(out)
}
