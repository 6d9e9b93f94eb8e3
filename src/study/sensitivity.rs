//! `tensegrity sensitivity`: a scenario's point settled afresh, and its sensitivities to every
//! parameter there (the analysis of a settled state, `run::sensitivity`: the implicit function
//! theorem, no settle).
//!
//! With `check`, each derivative is also measured by differences of settles: the state settled
//! afresh at p +- h and p +- 2 h, extrapolated the same way, the frequencies from the modes of
//! each settled state.

use crate::mechanisms::Values;
use crate::report::sensitivity::{check_error, OutputValue, ParameterSensitivity, SensitivityReport};
use crate::run::sensitivity::{analyse, linearize, unused_row, Analysis, Outputs};
use crate::run::{settle_at, RunError, SettledState};
use crate::scenario::Scenario;
use crate::sim::sensitivity::derivative_from_samples;
use crate::sim::Simulation;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

pub use crate::run::sensitivity::SensitivityRunError;

/// The scenario and inputs of point `point` (from 0, as a run numbers its points; a schedule's
/// one point is its first waypoint): a sweep over a topology or a motion over several points
/// is one scenario per part, their points in order. None past the last point.
pub fn point_of(sc: &Scenario, point: usize) -> Option<(&Scenario, Values)> {
    if sc.topologies.is_empty() {
        let inputs = match &sc.actuation {
            crate::scenario::Actuation::Points { points, .. } => points.get(point)?,
            crate::scenario::Actuation::Schedule { .. } => (point == 0).then(|| sc.actuation.first_inputs())?,
        };
        return Some((sc, inputs.clone()));
    }
    let mut parts = sc.topologies.iter().flat_map(|t| t.actuation.all_inputs().into_iter().map(move |i| (t, i)));
    parts.nth(point).map(|(t, i)| (t, i.clone()))
}

/// The sensitivities of `sc` at point `point` (from 0; see [`point_of`]), settled as `run`
/// settles it afresh there (`check`: also by differences of settles), named by `file`;
/// [`SensitivityRunError::NoPoint`] past the last point.
pub fn sensitivity(
    sc: &Scenario,
    file: &str,
    point: usize,
    check: bool,
    cancel: Option<&AtomicBool>,
) -> Result<SensitivityReport, SensitivityRunError> {
    sensitivity_to(sc, file, (point, None), check, cancel)
}

/// [`sensitivity`] at (`point`, `only`): with `only`, the rows of those parameters alone (a
/// fit's fitted ones: a file's other parameters and helpers cost no steps); without, every
/// parameter but the derived ones, which the report lists apart.
pub fn sensitivity_to(
    sc: &Scenario,
    file: &str,
    (point, only): (usize, Option<&[String]>),
    check: bool,
    cancel: Option<&AtomicBool>,
) -> Result<SensitivityReport, SensitivityRunError> {
    let (sc, inputs) = point_of(sc, point).ok_or(SensitivityRunError::NoPoint(point))?;
    let params = sc.params_at(&inputs);
    // What the analysis refuses is the structure's, known before the settle.
    let structure = sc.mechanism().build(&params, &inputs, &sc.start).map_err(RunError::from)?;
    let mut drawn = Simulation::new(&structure, &sc.sim).map_err(RunError::from)?;
    drawn.equilibrium_coordinates().map_err(SensitivityRunError::Refused)?;
    let mut state = settle_at(sc, &inputs, params.clone(), cancel)?;
    let wall = Instant::now();
    let Analysis { out, lin, listed, base } = analyse(sc, &mut state.sim, &params, inputs)?;
    let mut parameters = Vec::new();
    // Only what something reads gets steps: a file's thousands of unread parameters cost
    // nothing (3,000 had taken 142 s, each resolving the file's structure four times).
    let unread: std::collections::HashSet<String> = sc.unread_params().into_iter().collect();
    let derived = |name: &String| sc.param_table.is_derived(name);
    let asked = |name: &String| only.map_or(!derived(name), |o| o.contains(name));
    for (name, &value) in params.iter().filter(|(name, _)| asked(name)) {
        if cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
            return Err(RunError::Interrupted(state.sim.tick()).into());
        }
        parameters.push(match unread.contains(name) {
            true => unused_row(name, value, lin.size(), base.len()),
            false => out.parameter(&state.sim, &params, name, value, &lin, &listed),
        });
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let free = out.free_outputs(&mut state.sim, &params, &lin, &base);
    let outputs: Vec<OutputValue> = base
        .iter()
        .zip(free)
        .map(|((name, value), free)| OutputValue { name: name.clone(), value: *value, free })
        .collect();
    let check_wall = Instant::now();
    if check {
        for p in parameters.iter_mut().filter(|p| p.error.is_none() && p.switch.is_none() && !p.unused) {
            check_by_settles(&out, p, &params, &listed, &outputs, cancel)?;
        }
    }
    Ok(SensitivityReport {
        name: sc.name.clone(),
        file: file.to_string(),
        point,
        inputs: out.inputs.clone(),
        settled: state.settled,
        settle_steps: state.steps,
        coordinates: out.coordinates.names(state.sim.structure()),
        outputs,
        parameters,
        derived: if only.is_none() { params.keys().filter(|n| derived(n)).cloned().collect() } else { Vec::new() },
        wall_s,
        check_wall_s: check.then(|| check_wall.elapsed().as_secs_f64()),
    })
}

/// The check of `row` by differences of settles at the parameter's steps: the same
/// outputs, the frequencies from the modes of each settled state.
fn check_by_settles(
    out: &Outputs,
    row: &mut ParameterSensitivity,
    params: &Values,
    listed: &[usize],
    outputs: &[OutputValue],
    cancel: Option<&AtomicBool>,
) -> Result<(), SensitivityRunError> {
    let base: Vec<(String, f64)> = outputs.iter().map(|o| (o.name.clone(), o.value)).collect();
    let mut y = Vec::new();
    let (sc, samples) = out.samples(params, &row.name, row.value, row.step).map_err(SensitivityRunError::Check)?;
    for (moved, inputs) in samples {
        let SettledState { mut sim, .. } = settle_at(&sc, &inputs, moved.clone(), cancel)?;
        let mut sample = out.sample(&sim, &moved);
        let coordinates = sim.equilibrium_coordinates().map_err(SensitivityRunError::Refused)?;
        let lin = linearize(&mut sim, &coordinates)?;
        sample.extend(listed.iter().map(|&i| (lin.mode_name(i), lin.modes[i].omega())));
        y.push(out.offsets(&sample, &base));
    }
    let check = derivative_from_samples(y[0].clone(), y[1].clone(), y[2].clone(), y[3].clone(), row.step);
    let errors = outputs.iter().zip(&row.derivatives).zip(check.iter()).filter(|((o, _), _)| !o.free);
    row.max_check_error =
        Some(errors.map(|((o, d), c)| check_error(*d, *c, o.value, row.value, row.step)).fold(0.0, f64::max));
    row.check = Some(check.iter().copied().collect());
    Ok(())
}
