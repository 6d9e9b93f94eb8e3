//! Running one scenario: scenario -> model -> simulation -> observers -> report.
//!
//! `runner.rs` holds the running state and the one step every phase goes through,
//! `settle.rs` the settle loop, `point.rs` one settle point (branch, stability, probe,
//! read-out) (the pass policy is `report::verdict`), `motion.rs` a motion run, whose motion is
//! one value (`judged.rs`) over its levels (`levels.rs`). The studies that drive many runs
//! (fits, sensitivities, sweeps) live above, in `study/`.

mod amplitude;
mod equilibrium;
mod judged;
mod levels;
mod motion;
mod point;
mod runner;
pub(crate) mod sensitivity;
mod settle;
mod settled;
mod topologies;

use crate::mechanisms::{Mechanism, ModelError};
use crate::observers::record::{RecordTarget, Recording};
use crate::observers::{self, ObserverError, Setup};
use crate::report::{PointReport, ProbeReport, ScenarioReport, SettleSummary, WorkspaceAgreement};
use crate::scenario::{Actuation, Scenario};
use crate::sim::{SimError, Simulation};
use runner::Runner;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

pub use equilibrium::{equilibrium, EquilibriumRunError};
pub use levels::{judged_nodes_after, CommandsAt, MAX_LEVELS, MIN_LEVELS};
pub use point::NO_BRANCH;
pub use settle::SettleDetector;
pub use settled::{modes, settle_at, settle_first_point, ModesRunError, SettledState};
pub use topologies::rebuilt;

use stoppable::{interruptible, Halted};

/// How a run is observed beyond the comparison.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Record to this `.rrd` file (overrides the scenario's `[record]`).
    pub record: Option<PathBuf>,
    /// Set from a signal handler: the run stops at the next tick and reports what it has.
    pub cancel: Option<&'a AtomicBool>,
    /// Stream live to a rerun viewer at this address ("" for rerun's default) instead of a file.
    pub connect: Option<String>,
    /// Record every N-th tick only (0 or 1: every tick).
    pub record_every: u64,
    /// Leave the findings out of the report (a sweep's blocks: the summary has none).
    pub skip_findings: bool,
    /// Every tick as a row of a table: a CSV or Arrow IPC file, or kept in memory
    /// (`observers::table`).
    pub table: Option<crate::observers::table::TableTarget>,
    /// A model outside the file (the Python package's callables), compared as the file's
    /// predictions are (`observers::external`).
    pub external: Option<crate::observers::external::External>,
    /// The settle alone, watched by no observer: a study that reads the settled state (modes,
    /// sensitivities, fits) has no use for the checks, the interference (every pair of members,
    /// every tick: most of a 1000-strut prism's settle) or a recording.
    pub bare: bool,
    /// At each settle point, a proof of the equilibrium there (`crate::certify`): the point
    /// report's `certificate`.
    pub certify: bool,
}

/// Why a run stopped early, or failed after its end: the report's `error`, each kind kept as
/// its own until the report is printed or written.
#[derive(Clone, Debug, thiserror::Error)]
pub enum RunError {
    /// The simulator refused or diverged.
    #[error("{0}")]
    Sim(#[from] SimError),
    /// The cancel flag was raised (a signal, Ctrl-C).
    #[error("interrupted at tick {0}")]
    Interrupted(u64),
    /// The mechanism's model gave no result.
    #[error("{0}")]
    Model(#[from] ModelError),
    /// The structure's modes at a motion's start could not be computed.
    #[error("{0}")]
    Modes(#[from] crate::sim::modes::ModesError),
    /// An observer could not start, or could not write what carries the verdict.
    #[error("{0}")]
    Observer(Arc<ObserverError>),
    /// The paper's equations (findings) were not checked.
    #[error("{0} while checking the paper's equations (findings)")]
    Findings(Halted),
    /// The run panicked (its message).
    #[error("panicked: {0}")]
    Panicked(String),
    /// A point settled on an analytically unstable branch the scenario does not start on.
    #[error("point {index} settled on the analytically unstable branch '{branch}'")]
    UnstableBranch { index: usize, branch: String },
    /// The run of one topology of a topology sweep (`note`: the parameters that rebuilt it).
    #[error("{note}: {source}")]
    Topology { note: String, source: crate::report::ReportedError },
}

impl From<ObserverError> for RunError {
    fn from(e: ObserverError) -> Self {
        RunError::Observer(Arc::new(e))
    }
}

/// The report keeps the error as its own kind.
impl From<RunError> for crate::report::ReportedError {
    fn from(e: RunError) -> Self {
        crate::report::ReportedError::new(e)
    }
}

/// The report of a scenario whose run panicked: failed, with the panic's message.
pub fn panicked(sc: &Scenario, payload: &(dyn std::any::Any + Send)) -> ScenarioReport {
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    let mut report = ScenarioReport { error: Some(RunError::Panicked(msg).into()), ..empty_report(sc) };
    conclude(&mut report, sc);
    report
}

/// The report of `sc` before anything has run: not passed, no points, no findings (the one
/// place a run's report is made; every phase then fills in its part).
fn empty_report(sc: &Scenario) -> ScenarioReport {
    ScenarioReport {
        name: sc.name.clone(),
        file: sc.file.display().to_string(),
        mechanism: sc.mechanism.clone(),
        expect: sc.expect.clone(),
        params: sc.params.clone(),
        skipped_points: sc.skipped_points.len(),
        unseen_params: sc.unseen_params.clone(),
        ..ScenarioReport::default()
    }
}

/// Work on a thread of its own, waited for one poll at a time (`crate::stoppable`).
pub use crate::stoppable;

/// Test hook: a run of the scenario named by this variable panics (to test that a panic in one
/// scenario of a batch fails that scenario and the batch goes on).
pub const INJECT_PANIC_VAR: &str = "TENSEGRITY_INJECT_PANIC";

/// Runs a validated scenario. Bad model input found late (for example a structure the
/// simulator cannot build) is reported in `error` with `passed = false`.
pub fn run(sc: &Scenario, opts: &RunOptions) -> ScenarioReport {
    if std::env::var(INJECT_PANIC_VAR).is_ok_and(|n| n == sc.name) {
        panic!("injected by {INJECT_PANIC_VAR} (test hook)");
    }
    if !sc.topologies.is_empty() {
        return topologies::run_topologies(sc, opts);
    }
    let mech = sc.mechanism();
    let mut report = empty_report(sc);
    if !opts.skip_findings {
        let of = sc.clone();
        match interruptible(opts.cancel, move || of.mechanism().findings(&of.params)) {
            Ok(f) => report.findings = f.into_iter().map(Into::into).collect(),
            Err(halted) => {
                report.error = Some(RunError::Findings(halted).into());
                conclude(&mut report, sc);
                return report;
            }
        }
    }
    // Wall time counts the simulation, not the findings computed above.
    let wall = Instant::now();
    let mut runner = match start(mech, sc, opts, &mut report.warnings) {
        Ok(r) => r,
        Err(e) => {
            report.error = Some(e.into());
            conclude(&mut report, sc);
            return report;
        }
    };
    let mut probe_errors: Vec<f64> = Vec::new();
    let ran = match &sc.motion {
        Some(m) => motion::run_motion(&mut runner, sc, m, &mut report, &mut probe_errors),
        None => run_actuation(&mut runner, sc, &mut report, &mut probe_errors),
    };
    if let Err(e) = ran {
        runner.emit(format_args!("run stopped: {e}"));
        report.error = Some(e.into());
    }
    finish(&mut runner, &mut report, &probe_errors, wall);
    report
}

/// The simulation at the first point, and the observers of the run (what the run goes on
/// without goes into `warnings`).
fn start<'a>(
    mech: Box<dyn Mechanism>,
    sc: &'a Scenario,
    opts: &RunOptions<'a>,
    warnings: &mut Vec<String>,
) -> Result<Runner<'a>, RunError> {
    let first_inputs = sc.actuation.first_inputs();
    start_at(mech, sc, opts, warnings, first_inputs, sc.params_at(first_inputs))
}

/// [`start`] at the inputs `first_inputs` with the parameters `params`.
fn start_at<'a>(
    mech: Box<dyn Mechanism>,
    sc: &'a Scenario,
    opts: &RunOptions<'a>,
    warnings: &mut Vec<String>,
    first_inputs: &crate::mechanisms::Values,
    params: crate::mechanisms::Values,
) -> Result<Runner<'a>, RunError> {
    let structure = mech.build(&params, first_inputs, &sc.start)?;
    let sim = Simulation::new(&structure, &sc.sim)?;
    let observers = if opts.bare { vec![] } else { observed(&sim, sc, opts, mech.length_scale(&params), warnings)? };
    let mut runner = Runner::new(mech, sc, sim, observers, opts.cancel, params);
    runner.certify = opts.certify || sc.certify;
    // The first point's commands (a no-op where the build already placed them).
    runner.command(first_inputs);
    Ok(runner)
}

/// The observers of a run of `sc` on `sim` (`observers::KINDS`).
fn observed(
    sim: &Simulation,
    sc: &Scenario,
    opts: &RunOptions,
    length_scale_m: f64,
    warnings: &mut Vec<String>,
) -> Result<Vec<Box<dyn crate::observers::Observer>>, RunError> {
    let target = match (&opts.connect, opts.record.clone().or_else(|| sc.record.clone())) {
        (Some(url), _) => Some(RecordTarget::Live(url.clone())),
        (None, Some(path)) => Some(RecordTarget::File(path)),
        (None, None) => None,
    };
    Ok(observers::observers(
        Setup {
            structure: sim.structure(),
            checks: &sc.checks,
            length_scale_m,
            interference: &sc.interference,
            model: sc.model.as_ref(),
            recording: target.map(|target| Recording {
                target,
                every: opts.record_every.max(1),
                scenario: &sc.source,
                file_model: sc.model.is_some(),
            }),
            table: opts.table.clone(),
            motion: sc.motion.as_ref(),
            external: opts.external.clone(),
        },
        warnings,
    )?)
}

/// The report's summaries and verdict once the run is over; then the observers write what
/// carries the verdict (a recording that cannot be written fails the run).
fn finish(runner: &mut Runner, report: &mut ScenarioReport, probe_errors: &[f64], wall: Instant) {
    let sc = runner.sc;
    for o in &mut runner.observers {
        o.finish(report);
    }
    report.workspace = WorkspaceAgreement::from_points(&report.points).map(|mut w| {
        w.min_agreement_percent = sc.min_agreement_percent;
        w
    });
    report.accelerated_steps = runner.accelerated_steps;
    // A motion run's path is its motion's; any other run's is every step's.
    let physical = match &report.motion {
        Some(m) => m.steps_taken > 0 && m.accelerated_steps == 0,
        None => runner.steps > 0 && runner.accelerated_steps == 0,
    };
    report.path = if physical { crate::report::PathKind::Physical } else { crate::report::PathKind::Accelerated };
    report.settle = SettleSummary {
        settled: !report.points.is_empty() && report.points.iter().all(|p| p.settled),
        steps: runner.steps,
        sim_time_s: runner.sim.time_s(),
        wall_s: wall.elapsed().as_secs_f64(),
    };
    report.stiffness_probe =
        sc.probe.as_ref().map(|p| probe_report(runner.mech.as_ref(), p, &report.points, probe_errors));
    report.prestress = sc.prestress.as_ref().map(|p| {
        crate::report::PrestressReport::of(
            p,
            runner.sim.structure().count_of(crate::structure::MemberKind::Cable),
            &report.points,
        )
    });
    conclude(report, sc);
    let tick = runner.sim.tick();
    let mut failed = None;
    let mut warnings = Vec::new();
    for o in &mut runner.observers {
        if let Err(e) = o.close(tick, report, &mut warnings) {
            failed.get_or_insert(RunError::from(e));
        }
    }
    report.warnings.extend(warnings);
    if let Some(e) = failed {
        report.error.get_or_insert(e.into());
        conclude(report, sc);
    }
}

/// The probe over the run: the stiffness measured at each point, and with a closed form its
/// largest relative error (`probe_errors`, one per point) against the tolerance.
fn probe_report(
    mech: &dyn Mechanism,
    p: &crate::settings::Probe,
    points: &[PointReport],
    probe_errors: &[f64],
) -> ProbeReport {
    let max = probe_errors.iter().copied().fold(0.0, f64::max);
    let complete = !probe_errors.is_empty() && probe_errors.len() == points.len();
    let quantity = match &p.joint {
        Some(j) => j.quantity(),
        None => mech.stiffness_probe().map(|s| s.analytic).unwrap_or_default(),
    };
    let measured = points.iter().map(|q| q.simulated.get(&quantity).copied().unwrap_or(f64::NAN)).collect();
    let max_rel_error = p.tolerance.map(|_| if complete { max } else { f64::INFINITY });
    ProbeReport {
        torque_nm: p.torque_nm,
        tolerance: p.tolerance,
        passed: p.tolerance.is_none_or(|t| max_rel_error.is_some_and(|e| e <= t)),
        max_rel_error,
        quantity,
        measured,
    }
}

/// Settles every point in turn, or follows the waypoints tick by tick and settles at the last.
fn run_actuation(
    runner: &mut Runner,
    sc: &Scenario,
    report: &mut ScenarioReport,
    probe_errors: &mut Vec<f64>,
) -> Result<(), RunError> {
    match &sc.actuation {
        Actuation::Points { points, continuation } => {
            for (i, inputs) in points.iter().enumerate() {
                let params = sc.params_at(inputs);
                if i > 0 && params != runner.params {
                    // Other parameters (a sweep over them): another structure, built afresh.
                    let s = runner.mech.build(&params, inputs, &sc.start).map_err(RunError::Model)?;
                    let tick = runner.sim.tick();
                    runner.sim = Simulation::new(&s, &sc.sim)?;
                    runner.sim.set_tick(tick);
                    runner.params = params;
                    runner.command(inputs);
                    runner.emit(format_args!("point {i}: parameters and inputs {inputs:?}"));
                } else if i > 0 {
                    if *continuation {
                        runner.command(inputs);
                    } else {
                        let s = runner.mech.build(&runner.params, inputs, &sc.start).map_err(RunError::Model)?;
                        // The same structure placed anew: restarted in place where it can be
                        // (no rebuild of the rapier sets), else built afresh.
                        if !runner.sim.restart_from(&s) {
                            let tick = runner.sim.tick();
                            runner.sim = Simulation::new(&s, &sc.sim)?;
                            runner.sim.set_tick(tick);
                        }
                    }
                    runner.emit(format_args!("point {i}: inputs {inputs:?}"));
                }
                point::settle_point(runner, sc, i, inputs, report, probe_errors)?;
            }
        }
        Actuation::Schedule { waypoints } => {
            let end = waypoints.last().unwrap().0;
            let dt = sc.sim.dt_s;
            loop {
                let t = runner.sim.time_s() + dt;
                if t > end + 0.5 * dt {
                    break;
                }
                let inputs = interpolate(waypoints, t);
                runner.command(&inputs);
                let prediction = runner.mech.predict(&runner.params, &inputs).map_err(RunError::Model)?;
                let (_, simulated) = runner.step(&inputs, &prediction)?;
                for (q, v) in simulated {
                    report
                        .trajectory_ranges
                        .entry(q)
                        .and_modify(|r| r.include(v))
                        .or_insert_with(|| crate::report::QuantityRange::of(v));
                }
            }
            let inputs = waypoints.last().unwrap().1.clone();
            runner.emit("schedule done: settling at the last waypoint");
            point::settle_point(runner, sc, 0, &inputs, report, probe_errors)?;
        }
    }
    Ok(())
}

pub use crate::settings::interpolate;

/// The verdict of a finished report: its failures (the one pass policy, `report::verdict::failures`),
/// whether it passed, and whether that is what the scenario declares.
fn conclude(report: &mut ScenarioReport, sc: &Scenario) {
    report.failures = crate::report::verdict::failures(report, sc.min_agreement_percent);
    report.passed = report.failures.is_empty();
    report.as_expected = sc.expect.as_ref().map(|e| e.met_by(&report.failures));
}
