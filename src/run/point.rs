//! One settle point: settle, say which analytic branch the state lies on, test its stability by
//! perturbation, probe its stiffness, and read it out into a [`PointReport`] with the
//! observers.

use super::runner::Runner;
use super::RunError;
use crate::file_model::energy_model::Kind;
use crate::mechanisms::{self, Mechanism, ModelError, Prediction, Values};
use crate::observers::compare;
use crate::observers::SettlePoint;
use crate::report::{PointReport, ScenarioReport};
use crate::scenario::Scenario;
use crate::settings::Probe;
use crate::snapshot::Snapshot;

impl Runner<'_> {
    /// Perturbs every free coordinate and settles again: stable if it comes back.
    fn classify(
        &mut self,
        inputs: &Values,
        prediction: &Prediction,
        before: &Snapshot,
        delta: f64,
    ) -> Result<bool, RunError> {
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
        let back = after.settled && moved < RETURN_FRACTION * delta * self.sim.length_scale_m();
        self.emit(format_args!(
            "after the perturbation: {} {} steps, largest node displacement from before {moved:.3e} m",
            if after.settled { "settled in" } else { "did NOT settle in" },
            after.steps
        ));
        Ok(back)
    }

    /// Stiffness by the probe: +load and -load, K = 2 load / (q+ - q-); with the name of
    /// the quantity it is reported as. The mechanism's probe: a torque on its probe body; a
    /// joint probe: equal and opposite torques (forces) on the joint's child and parent about
    /// (along) its axis, q the joint's coordinate.
    fn probe(
        &mut self,
        inputs: &Values,
        prediction: &Prediction,
        p: &Probe,
    ) -> Result<Option<(String, f64)>, RunError> {
        let (quantity, loads, read): (String, Vec<ProbeLoad>, Reading) = match &p.joint {
            Some(j) => {
                let s = self.sim.structure();
                let joint = &s.joints[j.index];
                let axis = self.sim.snapshot_with(false).joint_axis_world(s, j.index).ok_or_else(|| {
                    RunError::Model(ModelError::no_solution(format!("probe joint '{}' has no axis", j.joint)))
                })?;
                let mut loads = vec![(joint.child, axis, j.prismatic)];
                if s.bodies[joint.parent].kind == crate::structure::BodyKind::Free {
                    loads.push((joint.parent, axis.map(|a| -a), j.prismatic));
                }
                (j.quantity(), loads, Reading::Joint(j.index, j.prismatic))
            }
            None => {
                let Some(spec) = self.mech.stiffness_probe() else {
                    return Ok(None);
                };
                let body = self.sim.structure().body_id(&spec.body).ok_or_else(|| {
                    RunError::Model(ModelError::no_solution(format!("probe body '{}' not found", spec.body)))
                })?;
                (spec.analytic, vec![(body, spec.torque_axis, false)], Reading::Quantity(spec.coordinate))
            }
        };
        let mut q = [0.0; 2];
        for (i, sign) in [1.0, -1.0].iter().enumerate() {
            for &(body, axis, force) in &loads {
                let l = axis.map(|a| a * p.torque_nm * sign);
                let (f, t) = if force { (l, [0.0; 3]) } else { ([0.0; 3], l) };
                self.sim.set_probe_load(body, f, t);
            }
            self.emit(format_args!("stiffness probe: load {:+e}", p.torque_nm * sign));
            let s = self.settle(inputs, prediction)?;
            if !s.settled {
                loads.iter().for_each(|&(b, ..)| self.sim.set_probe_load(b, [0.0; 3], [0.0; 3]));
                return Ok(None);
            }
            q[i] = match &read {
                Reading::Quantity(c) => s.simulated[c],
                Reading::Joint(j, _) => s.snapshot.joint_coordinate(self.sim.structure(), *j).unwrap_or(f64::NAN),
            };
        }
        loads.iter().for_each(|&(b, ..)| self.sim.set_probe_load(b, [0.0; 3], [0.0; 3]));
        self.settle(inputs, prediction)?;
        let dq = match read {
            Reading::Joint(_, true) => q[0] - q[1],
            _ => mechanisms::wrap_angle(q[0] - q[1]),
        };
        Ok(Some((quantity, 2.0 * p.torque_nm / dq)))
    }
}

/// How a probe reads its coordinate: a quantity the mechanism observes, or a joint's
/// coordinate (prismatic: a slide, not wrapped).
enum Reading {
    Quantity(String),
    Joint(usize, bool),
}

/// One load of a stiffness probe: the body, the direction (world) and whether it is a force
/// (a torque if not).
type ProbeLoad = (usize, [f64; 3], bool);

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
    params: &Values,
    prediction: &Prediction,
    simulated: &Values,
) -> (String, Option<bool>) {
    let scale = mech.length_scale(params);
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

/// The warnings of the file's predictions of a sensitivity whose tolerance is below that
/// sensitivity's error estimate at point `index` (relative to its value for a relative check).
fn unresolved_sensitivities(sc: &Scenario, index: usize, values: &Values, estimates: &Values) -> Vec<String> {
    let Some(model) = sc.model.as_ref() else { return vec![] };
    let mut out = Vec::new();
    for p in &model.predictions {
        let name = &model.symbols[p.symbol].name;
        let (Some(&v), Some(&e)) = (values.get(name), estimates.get(name)) else { continue };
        let resolved = match p.class {
            crate::file_model::spec::ErrorClass::Relative => e / v.abs(),
            _ => e,
        };
        if p.tolerance < resolved {
            out.push(format!(
                "prediction:{}: tolerance {:.1e} below what the sensitivity {name} resolves at point {index} (its estimate {resolved:.1e}): a tolerance above it, or a parameter step the analysis resolves better",
                p.name, p.tolerance
            ));
        }
    }
    out
}

/// Settles the point `index` at `inputs` and adds its report.
pub(super) fn settle_point(
    runner: &mut Runner,
    sc: &Scenario,
    index: usize,
    inputs: &Values,
    report: &mut ScenarioReport,
    probe_errors: &mut Vec<f64>,
) -> Result<(), RunError> {
    let prediction = runner.mech.predict(&runner.params, inputs).map_err(RunError::Model)?;
    let s = runner.settle(inputs, &prediction)?;
    let final_energy = runner.sim.kinetic_energy_j();
    say_settled(runner, sc, index, &s, final_energy);
    let measured = measured_point(runner, sc, (index, inputs), &s.snapshot, final_energy);
    let mut simulated = s.simulated.clone();
    // The file's [[sensitivities]] at the settled state, before anything moves it.
    if s.settled && sc.model.as_ref().is_some_and(|m| !m.sensitivities.is_empty()) {
        let params = runner.params.clone();
        match super::sensitivity::file_sensitivities(sc, &mut runner.sim, &params, inputs) {
            Ok((values, estimates)) => {
                report.warnings.extend(unresolved_sensitivities(sc, index, &values, &estimates));
                simulated.extend(values);
            }
            Err(e) => report.warnings.push(format!("point {index}: [[sensitivities]] not computed: {e}")),
        }
    }
    // The proof of the equilibrium, also before anything moves the state.
    let certificate = (runner.certify && s.settled).then(|| certificate_here(runner));
    let (branch, analytic_stable, mut landed) = landed_branch(runner, sc, index, &prediction, &simulated, report);
    let stable = match sc.stability_perturbation {
        Some(d) if s.settled => Some(runner.classify(inputs, &prediction, &s.snapshot, d)?),
        _ => None,
    };
    if let Some(st) = stable {
        runner.emit(format_args!("point {index}: equilibrium is {}", if st { "stable" } else { "unstable" }));
    }
    let mut errors = Values::new();
    if let (Some(p), true) = (&sc.probe, s.settled) {
        probe_point(runner, inputs, &prediction, p, (&mut landed, &mut simulated, &mut errors), probe_errors)?;
    }
    let slack_agrees = slack_agreement(runner, index, &prediction, &measured.slack_cables);
    let outside = prediction.expected_slack.as_ref().is_some_and(|e| !e.is_empty());
    let mut point = PointReport {
        settled: s.settled,
        steps: s.steps,
        final_speed_m_per_s: s.final_speed,
        branch,
        stable,
        analytic_stable,
        expected_stable: sc.expected_stable(index),
        expected_slack: prediction.expected_slack.clone(),
        slack_agrees,
        // Outside the analytic model's validity the analytic point is no equilibrium: report
        // the distance from it instead of checking against it.
        distance_from_analytic_m: outside.then(|| distance_m(runner.mech.as_ref(), &landed, &simulated)),
        errors,
        paper: runner
            .mech
            .paper_values(&runner.params, inputs)
            .map(|(source, values)| crate::report::PaperValues { source, values }),
        analytic: landed,
        simulated,
        certificate,
        // The observers fill in the tolerances, the clearance, the interference and the energy.
        ..measured
    };
    observe_point(runner, &s.snapshot, outside, &mut point);
    // The file's model fills its predictions in above.
    if let Some(proof) = point.certificate.as_mut().and_then(|c| c.proof.as_mut()) {
        proof.judge_model(&point.analytic);
    }
    if sc.expected_stability == crate::scenario::ExpectedStability::FromEnergy {
        point.expected_stable = energy_stability(&point);
    }
    runner.hand_out_notes();
    report.points.push(point);
    Ok(())
}

/// The certificate of the settled state (`crate::certify`), or the reason there is none.
fn certificate_here(runner: &Runner) -> crate::certify::Certificate {
    match runner.sim.equilibrium_problem() {
        Ok(problem) => crate::certify::certify(&problem),
        Err(e) => crate::certify::Certificate::refused(e.to_string()),
    }
}

/// The report of the point `(index, inputs)` with what every point reads off its state the
/// same way: the residual, the kinetic energy [J], the slack cables and the self-stress kept.
/// The rest is the caller's.
pub(super) fn measured_point(
    runner: &Runner,
    sc: &Scenario,
    (index, inputs): (usize, &Values),
    snapshot: &Snapshot,
    kinetic_energy_j: f64,
) -> PointReport {
    let slack_cables = slack_cables(runner, snapshot);
    let prestress_fraction = prestress_fraction(runner, snapshot);
    let cables = runner.sim.structure().count_of(crate::structure::MemberKind::Cable);
    let prestress_lost = sc.prestress.as_ref().map(|p| p.lost(cables, slack_cables.len(), prestress_fraction));
    let residual = snapshot.forces.residual;
    PointReport {
        index,
        inputs: inputs.clone(),
        residual_force_n: residual.map_or(f64::NAN, |r| r.max_force_n),
        residual_torque_nm: residual.map_or(f64::NAN, |r| r.max_torque_nm),
        final_kinetic_energy_j: kinetic_energy_j,
        slack_cables,
        slipping: slipping_nodes(runner.sim.structure(), snapshot),
        prestress_fraction,
        prestress_lost,
        ..PointReport::default()
    }
}

/// Every observer fills in what it measures at a settle point (`outside_model`: outside the
/// analytic model's validity).
pub(super) fn observe_point(runner: &mut Runner, snapshot: &Snapshot, outside_model: bool, point: &mut PointReport) {
    let seen = SettlePoint { structure: runner.sim.structure(), snapshot, params: &runner.params, outside_model };
    for o in runner.observers.iter_mut() {
        o.settle_point(&seen, point, &mut runner.notes);
    }
}

/// The analytic branch the settled state landed on: its label, its stability and its values
/// (the settled state is compared with them). Landing on an analytically unstable branch is
/// a failure unless the scenario deliberately starts there.
fn landed_branch(
    runner: &mut Runner,
    sc: &Scenario,
    index: usize,
    prediction: &Prediction,
    simulated: &Values,
    report: &mut ScenarioReport,
) -> (String, Option<bool>, Values) {
    let (branch, analytic_stable) = branch_of(runner.mech.as_ref(), &runner.params, prediction, simulated);
    let landed = prediction
        .branches
        .iter()
        .find(|b| b.label == branch)
        .map(|b| b.values.clone())
        .unwrap_or_else(|| prediction.expected.clone());
    let wanted_unstable = runner.mech.starts_on_unstable_branch(&sc.start);
    if analytic_stable == Some(false) && !wanted_unstable {
        runner.emit(format_args!("point {index}: landed on the analytically unstable branch '{branch}'"));
        report.error.get_or_insert(RunError::UnstableBranch { index, branch: branch.clone() }.into());
    }
    (branch, analytic_stable, landed)
}

/// The event of a settle: settled after so many steps, or not, with what was left moving.
fn say_settled(runner: &mut Runner, sc: &Scenario, index: usize, s: &super::settle::Settled, final_energy: f64) {
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
}

/// The stiffness probe at a settled point: the measured stiffness among the simulated values,
/// a joint probe's prediction among the analytic ones, and the relative error in `errors`
/// (the point's) and `probe_errors`.
fn probe_point(
    runner: &mut Runner,
    inputs: &Values,
    prediction: &Prediction,
    p: &Probe,
    (landed, simulated, errors): (&mut Values, &mut Values, &mut Values),
    probe_errors: &mut Vec<f64>,
) -> Result<(), RunError> {
    if let Some((quantity, k)) = runner.probe(inputs, prediction, p)? {
        if let Some(k) = p.joint.as_ref().and_then(|j| j.predicted(&runner.params, inputs)) {
            landed.insert(quantity.clone(), k);
        }
        if let Some(ka) = landed.get(&quantity) {
            // A prediction that is not a number (NaN) cannot pass: its error is infinite.
            let e = ((k - ka) / ka).abs();
            let e = if e.is_nan() { f64::INFINITY } else { e };
            probe_errors.push(e);
            errors.insert(quantity.clone(), e);
        }
        simulated.insert(quantity, k);
    }
    Ok(())
}

/// Whether the slack cables are the analytic model's (None where it says nothing), said when
/// they are not.
fn slack_agreement(
    runner: &mut Runner,
    index: usize,
    prediction: &Prediction,
    slack_cables: &[String],
) -> Option<bool> {
    let agrees = prediction.expected_slack.as_ref().map(|e| {
        let mut e = e.clone();
        e.sort();
        let mut got = slack_cables.to_vec();
        got.sort();
        e == got
    });
    if agrees == Some(false) {
        runner.emit(format_args!(
            "point {index}: slack cables {slack_cables:?} differ from the analytic {:?}",
            prediction.expected_slack
        ));
    }
    agrees
}

/// The stability the energy model gives the stationary point the dynamics landed on: a
/// minimum is stable, a maximum or a saddle unstable, a degenerate point undecided.
fn energy_stability(point: &PointReport) -> Option<bool> {
    let e = point.energy.as_ref()?;
    match e.stationary.get(e.landed?)?.kind.as_str() {
        k if k == Kind::Minimum.name() => Some(true),
        k if k == Kind::Maximum.name() || k == Kind::Saddle.name() => Some(false),
        _ => None,
    }
}

/// The cables' total tension in `snap` over their total tension at the drawn state (None
/// without a drawn tension).
pub(super) fn prestress_fraction(runner: &Runner, snap: &Snapshot) -> Option<f64> {
    let drawn = runner.sim.structure().drawn_cable_tension_n();
    (drawn > 0.0).then(|| cable_forces(runner.sim.structure(), snap).sum::<f64>() / drawn)
}

/// The inner nodes where a cable with friction is at its bound in `snap` ("CABLE at NODE").
fn slipping_nodes(s: &crate::structure::Structure, snap: &Snapshot) -> Vec<String> {
    let mut out = Vec::new();
    for (i, flags) in snap.forces.at_friction_bound.iter().enumerate() {
        for (j, _) in flags.iter().enumerate().filter(|(_, slips)| **slips) {
            let member = &s.members[i];
            out.push(format!("{} at {}", member.name, s.nodes[member.path[j + 1]].name));
        }
    }
    out
}

/// Every cable's tension in `snap` \[N\], in their order.
fn cable_forces<'a>(s: &'a crate::structure::Structure, snap: &'a Snapshot) -> impl Iterator<Item = f64> + 'a {
    s.members_of(crate::structure::MemberKind::Cable).map(|(i, _)| snap.forces.force_n[i])
}

/// The cables slack in `snap`, by name.
pub(super) fn slack_cables(runner: &Runner, snap: &Snapshot) -> Vec<String> {
    let s = runner.sim.structure();
    s.members_of(crate::structure::MemberKind::Cable)
        .filter(|(i, _)| snap.forces.slack[*i])
        .map(|(_, c)| c.name.clone())
        .collect()
}

/// Euclidean distance of the simulated lengths from the analytic ones [m].
fn distance_m(mech: &dyn Mechanism, analytic: &Values, simulated: &Values) -> f64 {
    mech.quantities()
        .iter()
        .filter(|q| q.kind == mechanisms::QuantityKind::Length)
        .filter_map(|q| Some(simulated.get(q.symbol)? - analytic.get(q.symbol)?))
        .map(|d| d * d)
        .sum::<f64>()
        .sqrt()
}
