//! A motion run (`[motion]`): its start state (the drawn one, read out as it is, or the
//! settled one, reached with the scenario's settle accelerators), then every accelerator off
//! for good, the named coordinate displaced and given its rate, and the physical dynamics for
//! the stated time. The observers judge it tick by tick; nothing here settles it.

use super::amplitude::HalfAmplitude;
use super::judged::{commands_at, JudgedMotion};
use super::levels::{run_alone, Levels, MAX_LEVELS, MIN_LEVELS};
use super::runner::Runner;
use super::settle::SettleDetector;
use super::{point, RunError};
use crate::eigen::EigenError;
use crate::mechanisms::Values;
use crate::observers::{ModeAtStart, MotionStarted};
use crate::report::{ExtrapolationReport, MotionReport, PointReport, ScenarioReport};
use crate::scenario::Scenario;
use crate::settings::{Drive, FrequencySignal, Motion, MotionStart, DEFAULT_TARGET_ERROR};
use crate::sim::modes::{modal_projector, ModesError};
use crate::snapshot::Snapshot;

/// What the report says of a motion before it runs.
fn planned(m: &Motion, dt_s: f64) -> MotionReport {
    MotionReport {
        start: m.start,
        duration_s: m.duration_s,
        dt_s,
        steps: m.steps,
        steps_taken: 0,
        start_tick: 0,
        coordinate: m
            .coordinate
            .as_ref()
            .map(|(c, ..)| c.joint.clone())
            .or(m.mode.map(|(i, _)| format!("mode {}", i + 1)))
            .or(m.spin.as_ref().map(|(_, name, w)| format!("body '{name}' spun at {w:?} rad/s"))),
        displacement: m.coordinate.as_ref().map(|(_, d, _)| *d).or(m.mode.map(|(_, a)| a)).unwrap_or(0.0),
        rate: m.coordinate.as_ref().map_or(0.0, |(.., r)| *r),
        accelerated_steps: 0,
        undamped: m.undamped,
        frequencies: vec![],
        lagrangian: None,
        driven: m.drive.as_ref().map(driven_text),
        integration: String::new(),
        extrapolation: None,
    }
}

/// What the run itself learns of a motion as it runs (the observers add theirs at the end).
#[derive(Default)]
struct Ran {
    start_tick: u64,
    steps_taken: u64,
    accelerated_steps: u64,
    integration: String,
    extrapolation: Option<ExtrapolationReport>,
}

/// Runs the motion of `m`: the start point, then the physical dynamics for its steps; its
/// report (`report.motion`) is assembled here, from what was planned and what ran.
pub(super) fn run_motion(
    runner: &mut Runner,
    sc: &Scenario,
    m: &Motion,
    report: &mut ScenarioReport,
    probe_errors: &mut Vec<f64>,
) -> Result<(), RunError> {
    let mut ran = Ran::default();
    let result = start_and_step(runner, sc, m, report, probe_errors, &mut ran);
    let extrapolation = ran.extrapolation.take();
    // A stated target the most levels could not meet is warned of; the default aim is
    // reported (`target_met`) without a warning: on a vibration of 1e-5 m, 1e-9 of it is
    // below the positions' own round-off.
    let missed = extrapolation.as_ref().filter(|x| !x.target_met && m.target_error.is_some());
    report.warnings.extend(missed.map(missed_target));
    report.motion = Some(MotionReport {
        start_tick: ran.start_tick,
        steps_taken: ran.steps_taken,
        accelerated_steps: ran.accelerated_steps,
        integration: ran.integration,
        extrapolation,
        ..planned(m, sc.sim.dt_s)
    });
    result
}

/// The start point, the motion started (`judged.rs`) and told to the observers, then its
/// steps; what ran goes into `ran`.
fn start_and_step(
    runner: &mut Runner,
    sc: &Scenario,
    m: &Motion,
    report: &mut ScenarioReport,
    probe_errors: &mut Vec<f64>,
    ran: &mut Ran,
) -> Result<(), RunError> {
    let mut inputs = sc.actuation.first_inputs().clone();
    match m.start {
        MotionStart::Settled => point::settle_point(runner, sc, 0, &inputs, report, probe_errors)?,
        MotionStart::Drawn => start_point(runner, sc, &inputs, report)?,
    }
    if m.start == MotionStart::Settled && !report.points.last().is_some_and(|p| p.settled) {
        runner.emit("the start did not settle: no motion");
        return Ok(());
    }
    let equilibrium = runner.sim.snapshot_with(false);
    runner.sim.end_acceleration();
    if m.undamped {
        runner.sim.release_damping();
    }
    // The same motion at half the amplitude, run after this one (`amplitude.rs`).
    let at_equilibrium = report.points.last().is_some_and(|p| p.settled);
    let mut half = HalfAmplitude::wanted(&runner.sim, m, at_equilibrium);
    // The modes at the start state itself, before the coordinate's displacement moves it.
    let modes = start_modes(runner, m, half.as_mut())?;
    if let Some((c, displacement, rate)) = &m.coordinate {
        runner.sim.set_joint_motion(c.index, *displacement, *rate)?;
        if let Some(h) = half.as_mut() {
            h.set_joint_motion(c.index, *displacement, *rate)?;
        }
    }
    if let Some((body, _, w)) = &m.spin {
        runner.sim.set_body_spin(*body, *w)?;
    }
    runner.show_motion_start(&equilibrium, &inputs)?;
    ran.start_tick = runner.sim.tick();
    let accelerated_before = runner.accelerated_steps;
    runner.emit(format_args!("motion: {} steps of physical dynamics, every settle accelerator off", m.steps));
    if m.drive.is_some() {
        runner.sim.drive_physically()?;
    }
    let levels = judged_levels(runner, m)?;
    ran.integration = integration_text(levels);
    let motion = JudgedMotion::start(&mut runner.sim, levels, m.drive.clone())?;
    let started = MotionStarted { modes: &modes, dt_s: motion.dt_s(), estimate_divisor: motion.estimate_divisor() };
    for o in runner.observers.iter_mut() {
        o.motion_start(&started);
    }
    runner.motion = Some(motion);
    let mut prediction = runner.mech.predict(&runner.params, &inputs).map_err(RunError::Model)?;
    let mut result = Ok(());
    for k in 1..=m.steps {
        // A driven motion's commands at the end of this step, t = k dt after its start.
        if let Some(driven) = runner.motion.as_ref().and_then(|j| j.inputs_after(&runner.params, k)) {
            inputs = driven;
            runner.drive(&inputs);
            prediction = runner.mech.predict(&runner.params, &inputs).map_err(RunError::Model)?;
        }
        result = runner.step(&inputs, &prediction).map(|_| ());
        if result.is_err() {
            break;
        }
        ran.steps_taken += 1;
    }
    ran.accelerated_steps = runner.accelerated_steps - accelerated_before;
    let judged = runner.motion.take().and_then(JudgedMotion::into_levels);
    ran.extrapolation = judged.map(|l| extrapolation_report(l, m));
    match (result, half) {
        (Ok(()), Some(half)) => run_half_amplitude(runner, half, (ran.steps_taken, levels), report),
        (result, _) => result,
    }
}

/// The motion again at half its amplitude, over its `steps` judged over `levels`
/// (`amplitude.rs`). Its stop (a divergence) leaves the run standing, with a warning; an
/// interruption stops the run.
fn run_half_amplitude(
    runner: &mut Runner,
    half: HalfAmplitude,
    (steps, levels): (u64, Option<usize>),
    report: &mut ScenarioReport,
) -> Result<(), RunError> {
    runner.emit(format_args!("the motion again at half its amplitude, alone: {steps} steps"));
    match half.run(runner, steps, levels) {
        Err(RunError::Interrupted(tick)) => Err(RunError::Interrupted(tick)),
        // The motion itself ran: its frequencies stand, their error bars say what is missing.
        Err(e) => {
            report.warnings.push(format!(
                "motion: the same motion at half its amplitude stopped ({e}): the frequencies' error bars leave out the amplitude's shift"
            ));
            Ok(())
        }
        Ok(()) => Ok(()),
    }
}

/// The warning of a stated target that the most levels did not meet.
fn missed_target(x: &ExtrapolationReport) -> String {
    format!(
        "motion: the judged node positions' error estimate {:.1e} m is above the target, {:.0e} of the amplitude {:.3e} m, at the most levels ({}, order {}): a smaller sim.dt meets it",
        x.node_estimate_m(),
        x.target_error,
        x.amplitude_m,
        x.steps_s.len(),
        x.order
    )
}

/// What the report says of a motion judged over `l`.
fn extrapolation_report(l: Levels, m: &Motion) -> ExtrapolationReport {
    let target_error = m.target_error.unwrap_or(DEFAULT_TARGET_ERROR);
    ExtrapolationReport {
        steps_s: l.steps_s(),
        order: l.order(),
        amplitude_m: l.amplitude_m,
        target_error,
        target_met: l.meets(target_error),
        not_smooth_from_tick: l.rough_from_tick,
        largest_estimate: l.largest,
    }
}

/// The levels a motion is judged over: the steps from its start are the leapfrog scheme from
/// the stated start (`sim/levels.rs`), second order at the tick times; extrapolated over the
/// step, by default, fourth order over [`MIN_LEVELS`] (`levels.rs`), or the fewest that meet a
/// stated target. None: not extrapolated.
fn judged_levels(runner: &mut Runner, m: &Motion) -> Result<Option<usize>, RunError> {
    if !m.extrapolated() {
        return Ok(None);
    }
    let Some(target) = m.target_error else { return Ok(Some(MIN_LEVELS)) };
    let (count, tried) = levels_for_target(runner, m, target)?;
    for line in tried {
        runner.emit(line);
    }
    Ok(Some(count))
}

/// The fewest levels ([`MIN_LEVELS`] to [`MAX_LEVELS`]) whose judged motion meets `target` (its
/// largest node estimate at most `target` times its amplitude), found by running the motion's
/// levels alone from the runner's state, no observer watching; [`MAX_LEVELS`] if none does
/// (the report then says the target was not met); with a line on each count tried.
fn levels_for_target(runner: &Runner, m: &Motion, target: f64) -> Result<(usize, Vec<String>), RunError> {
    let structure = runner.sim.structure();
    let (mech, params) = (runner.mech.as_ref(), &runner.params);
    let commands = m.drive.as_ref().map(|d| move |t| commands_at(mech, params, structure, d, t));
    let driven = commands.as_ref().map(|c| c as &dyn Fn(f64) -> Vec<f64>);
    let nodes = |s: &Snapshot| crate::observers::table::estimated_columns(structure, s);
    let mut tried = Vec::new();
    for count in MIN_LEVELS..MAX_LEVELS {
        let mut sim = runner.sim.at_time_step(runner.sim.model().settings.dt_s);
        let Some(levels) = run_alone(&mut sim, (m.steps, count), driven, Some(&nodes), runner.cancel, None)? else {
            return Err(RunError::Interrupted(runner.sim.tick()));
        };
        tried.push(format!(
            "target_error {target:e}: {count} levels estimate {:.3e} m over an amplitude of {:.3e} m",
            levels.node_estimate_m(),
            levels.amplitude_m
        ));
        if levels.meets(target) {
            return Ok((count, tried));
        }
    }
    Ok((MAX_LEVELS, tried))
}

/// How a motion's judged trajectory is made: extrapolated over `levels` levels, or not.
fn integration_text(levels: Option<usize>) -> String {
    let Some(count) = levels else {
        return "rapier's steps from a half step (leapfrog: second order at the tick times)".into();
    };
    let steps: Vec<String> = (1..count).map(|i| format!("h/{}", 1u32 << i)).collect();
    let (last, rest) = steps.split_last().expect("three levels or more");
    let order = match 2 * (count - 1) {
        4 => "fourth".to_string(),
        6 => "sixth".to_string(),
        8 => "eighth".to_string(),
        n => format!("order {n}"),
    };
    format!(
        "extrapolated over the time step: the motion at h, {} and {last}, each rapier's steps from a half step (leapfrog), combined by Richardson's rule ({order} order), its error estimated from the {}",
        rest.join(", "),
        if count == MIN_LEVELS { "three".to_string() } else { format!("{count} levels") }
    )
}

/// What the report says of a motion's drive.
fn driven_text(d: &Drive) -> String {
    let how = match d {
        Drive::Waypoints(w) => format!("{} waypoints", w.len()),
        Drive::Functions { functions, .. } => {
            functions.iter().map(|(n, e)| format!("{n} = {}", e.text())).collect::<Vec<_>>().join(", ")
        }
    };
    format!(
        "{how}, followed physically: each actuated joint a dynamic degree of freedom held to its command by a rigid velocity motor (rate (q(t + dt) - q) / dt), its reaction on the bodies it carries through the solver"
    )
}

/// The structure's own modes at the start that the motion needs (its displacement along one,
/// the frequencies fitted to them), analysed before the displacement, which follows.
fn start_modes(
    runner: &mut Runner,
    m: &Motion,
    half: Option<&mut HalfAmplitude>,
) -> Result<Vec<ModeAtStart>, RunError> {
    let fitted = m.frequencies.iter().filter_map(|f| match f.signal {
        FrequencySignal::Mode(i) => Some(i),
        FrequencySignal::Joint(_) => None,
    });
    let mut wanted: Vec<usize> = fitted.chain(m.mode.map(|(i, _)| i)).collect();
    wanted.sort_unstable();
    wanted.dedup();
    if wanted.is_empty() {
        return Ok(vec![]);
    }
    let through = wanted.last().copied();
    let lowest = crate::sim::modes::Lowest { through, ..Default::default() };
    let analysis = match runner.sim.modes_until(lowest, runner.cancel) {
        Err(ModesError::Eigen(EigenError::Interrupted)) => return Err(RunError::Interrupted(runner.sim.tick())),
        analysis => analysis?,
    };
    if let Some(&i) = wanted.iter().find(|&&i| i >= analysis.modes.len()) {
        let (computed, total) = (analysis.modes.len(), analysis.lowest_of.unwrap_or(analysis.modes.len()));
        return Err(ModesError::NotComputed { mode: i + 1, computed, total }.into());
    }
    if let Some(&i) = wanted.iter().find(|&&i| analysis.modes[i].rigid) {
        let (omega_squared, rigid) = (analysis.modes[i].omega_squared, analysis.rigid);
        return Err(ModesError::RigidMode { mode: i + 1, omega_squared, rigid }.into());
    }
    let modes: Vec<ModeAtStart> = wanted
        .iter()
        .map(|&index| ModeAtStart {
            index,
            omega_rad_per_s: analysis.modes[index].omega(),
            projector: modal_projector(runner.sim.structure(), &analysis, index),
        })
        .collect();
    if let Some((index, amplitude_m)) = m.mode {
        let eta = runner.sim.displace_along_mode(&analysis, index, amplitude_m);
        if let Some(h) = half {
            h.displace_along_mode(&analysis, index, amplitude_m);
        }
        runner.emit(format_args!(
            "start displaced along mode {} (omega {:.9} rad/s): largest node displacement {amplitude_m:e} m, modal coordinate {eta:.6e}",
            index + 1,
            analysis.modes[index].omega()
        ));
    }
    Ok(modes)
}

/// The drawn state as the motion's start point (no step taken): at rest, so an equilibrium
/// exactly when its residual meets the settle tolerances (then `settled`); the settle-point
/// judgments of the file (checks, equations, energy) are made there.
fn start_point(
    runner: &mut Runner,
    sc: &Scenario,
    inputs: &Values,
    report: &mut ScenarioReport,
) -> Result<(), RunError> {
    let prediction = runner.mech.predict(&runner.params, inputs).map_err(RunError::Model)?;
    let snapshot = runner.sim.snapshot();
    let simulated = runner.observe(&snapshot);
    let settled = SettleDetector::residual_ok(&snapshot, &sc.settle);
    let measured = point::measured_point(runner, sc, (0, inputs), &snapshot, runner.sim.kinetic_energy_j());
    let mut point = PointReport {
        analytic: prediction.expected.clone(),
        simulated,
        settled,
        branch: "the drawn state".into(),
        ..measured
    };
    point::observe_point(runner, &snapshot, false, &mut point);
    runner.emit(format_args!(
        "start: the drawn state, {} (residual {:.3e} N, {:.3e} N m)",
        if settled { "an equilibrium" } else { "not an equilibrium" },
        point.residual_force_n,
        point.residual_torque_nm
    ));
    report.points.push(point);
    Ok(())
}
