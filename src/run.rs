//! Running one scenario: scenario -> model -> simulation -> observers -> report.

use crate::mechanisms::{self, Mechanism, Prediction, Values};
use crate::observers::compare::{self, Compare};
use crate::observers::interference::Interference;
use crate::observers::record::Recorder;
use crate::observers::slack::SlackTracker;
use crate::observers::{Observer, Tick};
use crate::report::{PointReport, ProbeReport, ScenarioReport, SettleSummary};
use crate::scenario::{Actuation, Scenario};
use crate::sim::settle::SettleDetector;
use crate::sim::{SimError, Simulation, Snapshot};
use crate::verdict;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

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
}

#[derive(Debug, thiserror::Error)]
enum Stop {
    #[error("{0}")]
    Sim(#[from] SimError),
    #[error("interrupted at tick {0}")]
    Interrupted(u64),
    #[error("{0}")]
    Model(String),
}

struct Runner<'a> {
    mech: Box<dyn Mechanism>,
    sc: &'a Scenario,
    sim: Simulation,
    compare: Compare,
    slack: SlackTracker,
    interference: Option<Interference>,
    recorder: Option<Recorder>,
    cancel: Option<&'a AtomicBool>,
    steps: u64,
    /// The analytic ghost nodes for the last inputs (recordings only).
    ghost: Option<(Values, Option<Vec<[f64; 3]>>)>,
}

/// Result of one settle.
struct Settled {
    settled: bool,
    steps: u64,
    final_speed: f64,
    snapshot: Snapshot,
    simulated: Values,
}

impl Runner<'_> {
    fn observe(&self, snap: &Snapshot) -> Values {
        self.mech.observe(&self.sc.params, &self.sim.structure, snap)
    }

    /// Records an event in the recording, if any (formatted only then).
    fn emit(&mut self, text: impl std::fmt::Display) {
        let tick = self.sim.tick();
        if let Some(r) = self.recorder.as_mut() {
            r.event(tick, &text.to_string());
        }
    }

    /// Computes the equilibrium residual of `snap`, the simulation's current state, where the
    /// tick left it out, and records it.
    fn add_residual(&mut self, snap: &mut Snapshot) {
        if snap.forces.residual.is_some() {
            return;
        }
        snap.forces = self.sim.member_forces();
        if let (Some(rec), Some(r)) = (self.recorder.as_mut(), &snap.forces.residual) {
            rec.residual(snap.tick, r);
        }
    }

    /// One step followed by every observer.
    fn step(&mut self, inputs: &Values, prediction: &Prediction) -> Result<(Snapshot, Values), Stop> {
        if self.cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
            return Err(Stop::Interrupted(self.sim.tick()));
        }
        self.sim.step()?;
        self.steps += 1;
        // The residual (a least-squares fit, the costliest read-out) is left out here: the
        // settle loop computes it once the motion has stopped, and only those ticks carry it
        // (into the recording too).
        let snap = self.sim.snapshot_with(false);
        let simulated = self.observe(&snap);
        // The ghost overlay is only drawn in recordings, and only recomputed when the inputs
        // change.
        if self.recorder.is_some() && self.ghost.as_ref().is_none_or(|(i, _)| i != inputs) {
            self.ghost = Some((inputs.clone(), self.mech.analytic_nodes(&self.sc.params, inputs)));
        }
        let ghost = self.ghost.as_ref().and_then(|(_, g)| g.clone());
        let tick = Tick {
            structure: &self.sim.structure,
            snapshot: &snap,
            inputs,
            prediction,
            simulated: &simulated,
            ghost_nodes: ghost.as_deref(),
        };
        self.compare.tick(&tick);
        self.slack.tick(&tick);
        if let Some(i) = self.interference.as_mut() {
            i.tick(&tick);
        }
        if let Some(r) = self.recorder.as_mut() {
            r.tick(&tick);
            if let Some(i) = &self.interference {
                if let Some(c) = i.last_min_clearance_m {
                    r.scalar(snap.tick, "interference/min_clearance_m", c);
                }
                for (a, b, c) in &i.new_violations {
                    r.event(snap.tick, &format!("interference: {a} / {b} clearance {c:.3e} m"));
                }
            }
            for (cable, slack) in &self.slack.changes {
                r.event(snap.tick, &format!("cable {cable} went {}", if *slack { "slack" } else { "taut" }));
            }
        }
        Ok((snap, simulated))
    }

    /// Steps until the speed stays below the threshold for the window and the residual passes,
    /// or until the settle time runs out (a failure, never a pass).
    fn settle(&mut self, inputs: &Values, prediction: &Prediction) -> Result<Settled, Stop> {
        let criteria = self.sc.settle.clone();
        let dt = self.sc.sim.dt_s;
        let max_steps = (criteria.max_time_s / dt).ceil() as u64;
        let mut detector = SettleDetector::new();
        let mut last = None;
        // Two phases when the scenario asks: approach with few PGS iterations, then finish
        // with the full count once the motion has nearly stopped.
        let mut approaching = self.sc.sim.approach_pgs_iterations.is_some();
        if let Some(n) = self.sc.sim.approach_pgs_iterations {
            self.sim.set_pgs_iterations(n);
        }
        let switch_speed = criteria.speed_tol_m_per_s * APPROACH_SWITCH_SPEED_FACTOR;
        for k in 1..=max_steps {
            let (mut snap, simulated) = self.step(inputs, prediction)?;
            let quiet = detector.update(&snap, dt, &criteria);
            if approaching && detector.last_speed <= switch_speed {
                approaching = false;
                self.sim.set_pgs_iterations(self.sc.sim.pgs_iterations);
                detector.reset();
                continue;
            }
            let quiet = quiet && !approaching;
            if quiet {
                self.add_residual(&mut snap);
            }
            if quiet && SettleDetector::residual_ok(&snap, &criteria) {
                return Ok(Settled {
                    settled: true,
                    steps: k,
                    final_speed: detector.last_speed,
                    snapshot: snap,
                    simulated,
                });
            }
            last = Some((snap, simulated));
        }
        let (snapshot, simulated) = match last {
            // The last state is the simulation's current one: its residual can still be had.
            Some((mut snap, simulated)) => {
                self.add_residual(&mut snap);
                (snap, simulated)
            }
            None => {
                let s = self.sim.snapshot();
                let v = self.observe(&s);
                (s, v)
            }
        };
        self.sim.set_pgs_iterations(self.sc.sim.pgs_iterations);
        Ok(Settled { settled: false, steps: max_steps, final_speed: detector.last_speed, snapshot, simulated })
    }

    /// Perturbs every free coordinate and settles again: stable if it comes back.
    fn classify(
        &mut self,
        inputs: &Values,
        prediction: &Prediction,
        before: &Snapshot,
        delta: f64,
    ) -> Result<bool, Stop> {
        self.sim.perturb_free_coordinates(delta);
        self.emit(format_args!("perturbed every free coordinate by {delta}"));
        let after = self.settle(inputs, prediction)?;
        let moved = before
            .nodes
            .iter()
            .zip(&after.snapshot.nodes)
            .map(|(a, b)| crate::structure::distance(*a, *b))
            .fold(0.0, f64::max);
        // Back within a small fraction of the perturbation: the same equilibrium.
        let back = after.settled && moved < RETURN_FRACTION * delta * self.sim.length_scale_m;
        self.emit(format_args!(
            "after the perturbation: {} {} steps, largest node displacement from before {moved:.3e} m",
            if after.settled { "settled in" } else { "did NOT settle in" },
            after.steps
        ));
        Ok(back)
    }

    /// Stiffness by the probe: +tau and -tau on the probe body, K = 2 tau / (q+ - q-).
    fn probe(&mut self, inputs: &Values, prediction: &Prediction, torque: f64) -> Result<Option<f64>, Stop> {
        let Some(spec) = self.mech.stiffness_probe() else {
            return Ok(None);
        };
        let body = self
            .sim
            .structure
            .body_id(&spec.body)
            .ok_or_else(|| Stop::Model(format!("probe body '{}' not found", spec.body)))?;
        let axis = spec.torque_axis;
        let mut q = [0.0; 2];
        for (i, sign) in [1.0, -1.0].iter().enumerate() {
            let t = [axis[0] * torque * sign, axis[1] * torque * sign, axis[2] * torque * sign];
            self.sim.set_probe_load(body, [0.0; 3], t);
            self.emit(format_args!("stiffness probe: torque {:+e} N m", torque * sign));
            let s = self.settle(inputs, prediction)?;
            if !s.settled {
                self.sim.set_probe_load(body, [0.0; 3], [0.0; 3]);
                return Ok(None);
            }
            q[i] = s.simulated[&spec.coordinate];
        }
        self.sim.set_probe_load(body, [0.0; 3], [0.0; 3]);
        self.settle(inputs, prediction)?;
        Ok(Some(2.0 * torque / mechanisms::wrap_angle(q[0] - q[1])))
    }
}

/// The approach phase of a settle ends when the speed falls below the settle threshold times
/// this factor (for a 1e-12 m/s threshold: 1e-6 m/s).
const APPROACH_SWITCH_SPEED_FACTOR: f64 = 1e6;

/// A perturbed equilibrium counts as returned when every node is back within this fraction of
/// the perturbation (times the structure's length).
const RETURN_FRACTION: f64 = 1e-2;

/// A settled state lies on an analytic branch when every compared quantity is within this
/// normalised distance of it (lengths / length scale, angles in rad); farther from every
/// branch it lies on none of them, whatever the nearest is called.
const BRANCH_MATCH_DISTANCE: f64 = 1e-3;

/// Which analytic branch a simulated state lies on (nearest in the compared quantities, and
/// within [`BRANCH_MATCH_DISTANCE`]): its label and analytic stability. A state on none of
/// them is labelled so, with the nearest named.
fn branch_of(
    mech: &dyn Mechanism,
    sc: &Scenario,
    prediction: &Prediction,
    simulated: &Values,
) -> (String, Option<bool>) {
    let scale = mech.length_scale(&sc.params);
    let mut best: Option<(f64, &mechanisms::Solution)> = None;
    for b in &prediction.branches {
        let mut d: f64 = 0.0;
        for q in mech.quantities() {
            if let (Some(a), Some(s)) = (b.values.get(q.symbol), simulated.get(q.symbol)) {
                if q.kind != mechanisms::QuantityKind::Magnitude {
                    d = d.max(compare::error(q.kind, *a, *s, scale).1);
                }
            }
        }
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, b));
        }
    }
    match best {
        Some((d, b)) if d <= BRANCH_MATCH_DISTANCE => (b.label.clone(), b.stable),
        Some((_, b)) => (format!("{NO_BRANCH} (nearest: {})", b.label), None),
        None => ("unknown".into(), None),
    }
}

/// The label of a settled state that lies on none of the analytic branches.
pub const NO_BRANCH: &str = "none of the analytic branches";

/// The report of a scenario whose run panicked: failed, with the panic's message.
pub fn panicked(sc: &Scenario, payload: &(dyn std::any::Any + Send)) -> ScenarioReport {
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    let mut report = ScenarioReport { error: Some(format!("panicked: {msg}")), ..empty_report(sc) };
    conclude(&mut report, sc);
    report
}

/// The verdict of a finished report: its failures (the one pass policy, [`verdict::failures`]),
/// whether it passed, and whether that is what the scenario declares.
fn conclude(report: &mut ScenarioReport, sc: &Scenario) {
    report.failures = verdict::failures(report, sc.min_agreement_percent);
    report.passed = report.failures.is_empty();
    report.as_expected = sc.expect.as_ref().map(|e| e.met_by(&report.failures));
}

/// The report of `sc` before anything has run: not passed, no points, no findings.
fn empty_report(sc: &Scenario) -> ScenarioReport {
    ScenarioReport {
        name: sc.name.clone(),
        file: sc.file.display().to_string(),
        mechanism: sc.mechanism.clone(),
        passed: false,
        failures: vec![],
        expect: sc.expect.clone(),
        as_expected: None,
        params: sc.params.clone(),
        settle: SettleSummary::default(),
        checks: vec![],
        points: vec![],
        stiffness_probe: None,
        slack_intervals: vec![],
        workspace: None,
        skipped_points: sc.skipped_points.len(),
        interference: None,
        findings: vec![],
        trajectory_ranges: Default::default(),
        error: None,
    }
}

/// Test hook: a run of the scenario named by this variable panics (to test that a panic in one
/// scenario of a batch fails that scenario and the batch goes on).
pub const INJECT_PANIC_VAR: &str = "TENSEGRITY_INJECT_PANIC";

/// Runs a validated scenario. Bad model input found late (for example a structure the
/// simulator cannot build) is reported in `error` with `passed = false`.
pub fn run(sc: &Scenario, opts: &RunOptions) -> ScenarioReport {
    if std::env::var(INJECT_PANIC_VAR).is_ok_and(|n| n == sc.name) {
        panic!("injected by {INJECT_PANIC_VAR} (test hook)");
    }
    let mech = sc.mechanism();
    let mut report = ScenarioReport {
        findings: if opts.skip_findings {
            Vec::new()
        } else {
            mech.findings(&sc.params).into_iter().map(Into::into).collect()
        },
        ..empty_report(sc)
    };
    // Wall time counts the simulation, not the findings computed above.
    let wall = Instant::now();
    let first_inputs = match &sc.actuation {
        Actuation::Points { points, .. } => points[0].clone(),
        Actuation::Schedule { waypoints } => waypoints[0].1.clone(),
    };
    let sim = match mech
        .build(&sc.params, &first_inputs, &sc.start)
        .and_then(|s| Simulation::new(&s, &sc.sim).map_err(|e| e.to_string()))
    {
        Ok(mut s) => {
            // The first point's commands (a no-op where the build already placed them).
            s.set_commands(&mech.commands(&sc.params, &first_inputs));
            s
        }
        Err(e) => {
            report.error = Some(e);
            conclude(&mut report, sc);
            return report;
        }
    };
    let interference = match sc.interference.as_ref().map(|i| Interference::new(&sim.structure, i)) {
        None => None,
        Some(Ok(i)) => Some(i),
        Some(Err(e)) => {
            report.error = Some(e);
            conclude(&mut report, sc);
            return report;
        }
    };
    let record_path = opts.record.clone().or_else(|| sc.record.clone());
    let every = opts.record_every.max(1);
    let recorder = match opts
        .connect
        .as_deref()
        .map(|url| Recorder::connect(url, "tensegrity-testbed", every))
        .or_else(|| record_path.as_ref().map(|p| Recorder::create(p, "tensegrity-testbed", every).map(Some)))
    {
        None => None,
        Some(Ok(r)) => r,
        Some(Err(e)) => {
            report.error = Some(e.to_string());
            conclude(&mut report, sc);
            return report;
        }
    };
    let length_scale = mech.length_scale(&sc.params);
    let mut runner = Runner {
        compare: Compare::new(&sc.checks, length_scale),
        slack: SlackTracker::new(),
        interference,
        mech,
        sc,
        sim,
        recorder,
        cancel: opts.cancel,
        steps: 0,
        ghost: None,
    };
    if let Some(r) = runner.recorder.as_mut() {
        r.document("scenario", &sc.source);
    }
    let mut probe_errors: Vec<f64> = Vec::new();
    let outcome = run_actuation(&mut runner, sc, &mut report, &mut probe_errors);
    if let Err(e) = outcome {
        report.error = Some(e.to_string());
        runner.emit(format_args!("run stopped: {e}"));
    }

    report.checks = runner.compare.reports();
    report.slack_intervals = runner.slack.intervals();
    report.workspace = crate::report::WorkspaceAgreement::from_points(&report.points).map(|mut w| {
        w.min_agreement_percent = sc.min_agreement_percent;
        w
    });
    report.interference = runner.interference.as_ref().map(Interference::report);
    report.settle = SettleSummary {
        settled: !report.points.is_empty() && report.points.iter().all(|p| p.settled),
        steps: runner.steps,
        sim_time_s: runner.sim.time_s(),
        wall_s: wall.elapsed().as_secs_f64(),
    };
    if let Some(p) = &sc.probe {
        let max = probe_errors.iter().copied().fold(0.0, f64::max);
        let complete = !probe_errors.is_empty() && probe_errors.len() == report.points.len();
        report.stiffness_probe = Some(ProbeReport {
            torque_nm: p.torque_nm,
            tolerance: p.tolerance,
            max_rel_error: if complete { max } else { f64::INFINITY },
            passed: complete && max <= p.tolerance,
        });
    }
    conclude(&mut report, sc);
    if let Some(r) = runner.recorder.take() {
        let mut r = r;
        r.document("report", &serde_json::to_string_pretty(&report).unwrap_or_default());
        r.event(runner.sim.tick(), if report.passed { "run passed" } else { "run FAILED" });
        if let Err(e) = r.finish() {
            report.error.get_or_insert(e.to_string());
            conclude(&mut report, sc);
        }
    }
    report
}

fn run_actuation(
    runner: &mut Runner,
    sc: &Scenario,
    report: &mut ScenarioReport,
    probe_errors: &mut Vec<f64>,
) -> Result<(), Stop> {
    match &sc.actuation {
        Actuation::Points { points, continuation } => {
            for (i, inputs) in points.iter().enumerate() {
                if i > 0 {
                    if *continuation {
                        let cmds = runner.mech.commands(&sc.params, inputs);
                        runner.sim.set_commands(&cmds);
                    } else {
                        let s = runner.mech.build(&sc.params, inputs, &sc.start).map_err(Stop::Model)?;
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
                settle_point(runner, sc, i, inputs, report, probe_errors)?;
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
                let cmds = runner.mech.commands(&sc.params, &inputs);
                runner.sim.set_commands(&cmds);
                let prediction = runner.mech.predict(&sc.params, &inputs).map_err(Stop::Model)?;
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
            settle_point(runner, sc, 0, &inputs, report, probe_errors)?;
        }
    }
    Ok(())
}

/// Linear interpolation of the waypoints at time `t`, held at the last.
pub fn interpolate(waypoints: &[(f64, Values)], t: f64) -> Values {
    if t <= waypoints[0].0 {
        return waypoints[0].1.clone();
    }
    for w in waypoints.windows(2) {
        let ((t0, a), (t1, b)) = (&w[0], &w[1]);
        if t <= *t1 {
            let s = (t - t0) / (t1 - t0);
            return a.iter().map(|(k, x)| (k.clone(), x + (b[k] - x) * s)).collect();
        }
    }
    waypoints.last().unwrap().1.clone()
}

fn settle_point(
    runner: &mut Runner,
    sc: &Scenario,
    index: usize,
    inputs: &Values,
    report: &mut ScenarioReport,
    probe_errors: &mut Vec<f64>,
) -> Result<(), Stop> {
    let prediction = runner.mech.predict(&sc.params, inputs).map_err(Stop::Model)?;
    let s = runner.settle(inputs, &prediction)?;
    let final_energy = runner.sim.kinetic_energy_j();
    if s.settled {
        runner.emit(format_args!("point {index} settled after {} steps", s.steps));
    } else {
        runner.emit(format_args!(
            "point {index} did NOT settle in {} s (kinetic energy {final_energy:.3e} J, speed {:.3e} m/s, residual {:.3e} N, {:.3e} N m)",
            sc.settle.max_time_s,
            s.final_speed,
            s.snapshot.forces.residual.map_or(f64::NAN, |r| r.max_force_n),
            s.snapshot.forces.residual.map_or(f64::NAN, |r| r.max_torque_nm)
        ));
    }
    let mut simulated = s.simulated.clone();
    let (branch, analytic_stable) = branch_of(runner.mech.as_ref(), sc, &prediction, &simulated);
    // The settled state is compared with the branch it landed on; landing on an analytically
    // unstable branch is a failure unless the scenario deliberately starts there.
    let landed = prediction
        .branches
        .iter()
        .find(|b| b.label == branch)
        .map(|b| b.values.clone())
        .unwrap_or_else(|| prediction.expected.clone());
    let wanted_unstable = sc.start.get("at_unstable_root").is_some_and(|f| *f != 0.0);
    if analytic_stable == Some(false) && !wanted_unstable {
        runner.emit(format_args!("point {index}: landed on the analytically unstable branch '{branch}'"));
        report.error.get_or_insert(format!("point {index} settled on the analytically unstable branch '{branch}'"));
    }
    let stable = match sc.stability_perturbation {
        Some(d) if s.settled => Some(runner.classify(inputs, &prediction, &s.snapshot, d)?),
        _ => None,
    };
    if let Some(st) = stable {
        runner.emit(format_args!("point {index}: equilibrium is {}", if st { "stable" } else { "unstable" }));
    }
    if let (Some(p), true) = (&sc.probe, s.settled) {
        if let Some(k) = runner.probe(inputs, &prediction, p.torque_nm)? {
            simulated.insert("K".into(), k);
            if let Some(ka) = landed.get("K") {
                probe_errors.push(((k - ka) / ka).abs());
            }
        }
    }
    let slack_cables: Vec<String> = runner
        .sim
        .structure
        .cables
        .iter()
        .zip(&s.snapshot.forces.cable_slack)
        .filter(|(_, sl)| **sl)
        .map(|(c, _)| c.name.clone())
        .collect();
    let slack_agrees = prediction.expected_slack.as_ref().map(|e| {
        let mut e = e.clone();
        e.sort();
        let mut got = slack_cables.clone();
        got.sort();
        e == got
    });
    let outside = prediction.expected_slack.as_ref().is_some_and(|e| !e.is_empty());
    // Outside the analytic model's validity the analytic point is no equilibrium: report the
    // distance from it instead of checking against it.
    let distance_from_analytic_m = outside.then(|| {
        runner
            .mech
            .quantities()
            .iter()
            .filter(|q| q.kind == mechanisms::QuantityKind::Length)
            .filter_map(|q| Some(simulated.get(q.symbol)? - landed.get(q.symbol)?))
            .map(|d| d * d)
            .sum::<f64>()
            .sqrt()
    });
    if slack_agrees == Some(false) {
        runner.emit(format_args!(
            "point {index}: slack cables {slack_cables:?} differ from the analytic {:?}",
            prediction.expected_slack
        ));
    }
    if outside {
        runner.compare.outside_point();
    } else {
        runner.compare.settle_point(&landed, &simulated, s.settled);
    }
    let (min_clearance_m, interference_free) = match (&runner.interference, &sc.interference) {
        (Some(i), Some(set)) => {
            let c = i.measure(&runner.sim.structure, &s.snapshot.nodes).iter().map(|p| p.clearance_m).reduce(f64::min);
            (c, Some(c.is_none_or(|c| c >= set.threshold_m)))
        }
        _ => (None, None),
    };
    // Every check at this point: (quantity, normalised error, tolerance); a missing value fails.
    let scale = runner.mech.length_scale(&sc.params);
    let point_checks: Vec<(&str, f64, f64)> = sc
        .checks
        .iter()
        .map(|c| {
            let e = match (landed.get(&c.quantity), simulated.get(&c.quantity)) {
                (Some(a), Some(b)) => compare::error(c.kind, *a, *b, scale).1,
                _ => f64::INFINITY,
            };
            (c.quantity.as_str(), e, c.tolerance)
        })
        .collect();
    if s.settled && !outside {
        for (q, e, tol) in point_checks.iter().filter(|(_, e, tol)| !(e <= tol)) {
            runner.emit(format_args!("point {index}: check {q} failed: error {e:.3e} > tolerance {tol:.1e}"));
        }
    }
    let within_tolerance = s.settled && !outside && point_checks.iter().all(|(_, e, tol)| e <= tol);
    report.points.push(PointReport {
        index,
        inputs: inputs.clone(),
        analytic: landed,
        simulated,
        settled: s.settled,
        steps: s.steps,
        residual_force_n: s.snapshot.forces.residual.map_or(f64::NAN, |r| r.max_force_n),
        residual_torque_nm: s.snapshot.forces.residual.map_or(f64::NAN, |r| r.max_torque_nm),
        final_speed_m_per_s: s.final_speed,
        final_kinetic_energy_j: final_energy,
        branch,
        stable,
        analytic_stable,
        slack_cables,
        expected_slack: prediction.expected_slack.clone(),
        slack_agrees,
        distance_from_analytic_m,
        within_tolerance,
        min_clearance_m,
        interference_free,
        paper: runner
            .mech
            .paper_values(&sc.params, inputs)
            .map(|(source, values)| crate::report::PaperValues { source, values }),
    });
    Ok(())
}
