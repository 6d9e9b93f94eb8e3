//! What the run is judged on: `[[checks]]`, `[stability]`, `[probe]` and `[workspace]`.

use super::error::{finite, positive_value, Ctx, ScenarioError};
use super::number::expr_error;
use super::raw::{RawCheck, RawExpectedStability, RawProbe, RawStability, RawWorkspace};
use super::{Actuation, ExpectedStability};
use crate::file_model::expr::Expr;
use crate::mechanisms::{Mechanism, Values};
use crate::settings::{Check, JointProbe, Probe};
use crate::structure::{ActuatorTarget, JointKind, Structure};
use toml::Spanned;

/// `[[checks]]`: each a quantity of the mechanism, with a tolerance > 0; a quantity that only
/// the stiffness probe measures needs `[probe]` (`has_probe`).
pub(super) fn checks(
    ctx: &Ctx,
    m: &dyn Mechanism,
    raw: &[RawCheck],
    has_probe: bool,
) -> Result<Vec<Check>, ScenarioError> {
    let probed = m.stiffness_probe().map(|p| p.analytic);
    let mut checks = Vec::new();
    for c in raw {
        if !has_probe && probed.as_deref() == Some(c.quantity.get_ref().as_str()) {
            return Err(ctx.err(
                &c.quantity,
                format!(
                    "quantity '{}' is measured by the stiffness probe: add a [probe] section",
                    c.quantity.get_ref()
                ),
            ));
        }
        let q = m.quantities().iter().find(|q| q.symbol == c.quantity.get_ref()).ok_or_else(|| {
            let known: Vec<_> = m.quantities().iter().map(|q| q.symbol).collect();
            ctx.err(
                &c.quantity,
                format!("unknown quantity '{}' (expected one of: {})", c.quantity.get_ref(), known.join(", ")),
            )
        })?;
        let tol = positive_value(ctx, &c.tolerance, "tolerance")?;
        checks.push(Check { quantity: q.symbol.into(), kind: q.kind, unit: q.unit.into(), tolerance: tol });
    }
    Ok(checks)
}

/// `[stability]`: the perturbation of every free coordinate, in (0, 1) (rad or m).
pub(super) fn stability(ctx: &Ctx, raw: &Option<RawStability>) -> Result<Option<f64>, ScenarioError> {
    let Some(s) = raw else { return Ok(None) };
    let x = finite(ctx, &s.perturbation, "stability.perturbation")?;
    if !(x > 0.0 && x < 1.0) {
        return Err(ctx.err(&s.perturbation, format!("stability.perturbation must be in (0, 1) (rad or m), got {x}")));
    }
    Ok(Some(x))
}

/// `[stability] expect`: "stable" or "unstable" for every settle point (one entry), or a list
/// with one entry per point of `points` or `grid` (a schedule settles once, after its last
/// waypoint). Empty when the scenario does not say.
pub(super) fn expected_stability(
    ctx: &Ctx,
    raw: &Option<RawStability>,
    actuation: &Actuation,
    has_energy: bool,
) -> Result<ExpectedStability, ScenarioError> {
    let Some(e) = raw.as_ref().and_then(|s| s.expect.as_ref()) else { return Ok(ExpectedStability::Unsaid) };
    let word = |w: &String| match w.as_str() {
        "stable" => Ok(true),
        "unstable" => Ok(false),
        other => Err(ctx.err(
            e,
            format!("stability.expect must be \"stable\", \"unstable\" or \"energy\" (or a list), got \"{other}\""),
        )),
    };
    match e.get_ref() {
        RawExpectedStability::All(w) if w == "energy" => match has_energy {
            true => Ok(ExpectedStability::FromEnergy),
            false => Err(ctx
                .err(e, "stability.expect = \"energy\" needs an [energy] section (its minima are the stable points)")),
        },
        RawExpectedStability::All(w) => Ok(ExpectedStability::Listed(vec![word(w)?])),
        RawExpectedStability::PerPoint(list) => {
            let points = match actuation {
                Actuation::Points { points, .. } => points.len(),
                Actuation::Schedule { .. } => 1,
            };
            if list.len() != points {
                return Err(ctx.err(
                    e,
                    format!("stability.expect lists {} stabilities for {points} settle point(s): give one per point, or one word for all", list.len()),
                ));
            }
            Ok(ExpectedStability::Listed(list.iter().map(word).collect::<Result<_, _>>()?))
        }
    }
}

/// `[probe]`: a load > 0 (a torque in N m, or a force in N for a prismatic joint) and a
/// tolerance > 0; on a named joint of `first` (the structure at the first point) with its
/// predicted stiffness, or the mechanism's own stiffness probe.
pub(super) fn probe(
    ctx: &Ctx,
    m: &dyn Mechanism,
    raw: &Option<Spanned<RawProbe>>,
    first: &Structure,
    params: &Values,
) -> Result<Option<Probe>, ScenarioError> {
    let Some(section) = raw else { return Ok(None) };
    let p = section.get_ref();
    let tol = p.tolerance.as_ref().map(|t| positive_value(ctx, t, "probe.tolerance")).transpose()?;
    let Some(name) = &p.joint else {
        if let Some(e) = &p.expected {
            return Err(
                ctx.err(e, "expected goes with joint = \"name\" (the mechanism's probe compares with its model)")
            );
        }
        let Some(torque) = p.torque.as_ref() else {
            return Err(ctx.err(section, "[probe] needs torque = N m"));
        };
        if m.stiffness_probe().is_none() {
            return Err(ctx.err(
                torque,
                format!(
                    "{} has no stiffness probe of its own: probe a joint (joint = \"name\", expected = \"...\")",
                    m.name()
                ),
            ));
        }
        if tol.is_none() {
            return Err(ctx.err(torque, "the mechanism's probe is compared with its model: give probe.tolerance"));
        }
        return Ok(Some(Probe { torque_nm: load(ctx, torque, "torque", "N m")?, joint: None, tolerance: tol }));
    };
    match (&p.expected, &p.tolerance) {
        (Some(e), None) => return Err(ctx.err(e, "probe.expected needs probe.tolerance (on the relative error)")),
        (None, Some(t)) => {
            return Err(
                ctx.err(t, "probe.tolerance goes with probe.expected: without a closed form the probe only measures")
            )
        }
        _ => {}
    }
    let joint = joint_probe(ctx, m, p, name, first, params)?;
    let (given, what, unit) = match (joint.prismatic, &p.torque, &p.force) {
        (false, Some(t), None) => (t, "torque", "N m"),
        (true, None, Some(f)) => (f, "force", "N"),
        (false, ..) => return Err(ctx.err(name, "a revolute joint is probed with torque = N m (and no force)")),
        (true, ..) => return Err(ctx.err(name, "a prismatic joint is probed with force = N (and no torque)")),
    };
    Ok(Some(Probe { torque_nm: load(ctx, given, what, unit)?, joint: Some(joint), tolerance: tol }))
}

/// A probe load: finite and > 0.
fn load(ctx: &Ctx, v: &Spanned<f64>, what: &str, unit: &str) -> Result<f64, ScenarioError> {
    let x = finite(ctx, v, &format!("probe.{what}"))?;
    if x <= 0.0 {
        return Err(ctx.err(v, format!("probe.{what} must be > 0 {unit}, got {x}")));
    }
    Ok(x)
}

/// The probed joint (revolute or prismatic, not driven by an actuator) and its predicted
/// stiffness, compiled against the parameters and inputs.
fn joint_probe(
    ctx: &Ctx,
    m: &dyn Mechanism,
    p: &RawProbe,
    name: &Spanned<String>,
    s: &Structure,
    params: &Values,
) -> Result<JointProbe, ScenarioError> {
    let index = s.joints.iter().position(|j| &j.name == name.get_ref()).ok_or_else(|| {
        let names: Vec<&str> = s.joints.iter().map(|j| j.name.as_str()).collect();
        ctx.err(name, format!("unknown joint '{}' (the structure's joints: {})", name.get_ref(), names.join(", ")))
    })?;
    let prismatic = match s.joints[index].kind {
        JointKind::Revolute { .. } => false,
        JointKind::Prismatic { .. } => true,
        _ => return Err(ctx.err(name, "only a revolute or prismatic joint can be probed (one coordinate)")),
    };
    if s.actuators.iter().any(|a| a.target == ActuatorTarget::Joint(index)) {
        return Err(
            ctx.err(name, "an actuated joint is held by its command: probe a joint the structure is free to turn")
        );
    }
    let mut symbols: Vec<String> = params.keys().cloned().collect();
    symbols.extend(m.inputs().iter().map(|i| i.symbol.to_string()));
    let names: Vec<&str> = symbols.iter().map(String::as_str).collect();
    let expr = p
        .expected
        .as_ref()
        .map(|e| {
            Expr::compile(e.get_ref(), &names)
                .map_err(|err| expr_error(ctx, e.span().start, &err, "probe.expected (parameters and inputs)"))
        })
        .transpose()?;
    Ok(JointProbe { joint: name.get_ref().clone(), index, prismatic, expected: expr, symbols })
}

/// A joint probe's expected stiffness at every settle point of `actuation`: a finite number,
/// not zero (the relative error against NaN, an infinity or zero cannot pass or fail). An
/// error at `expected` naming the point.
pub(super) fn probe_expected(
    ctx: &Ctx,
    raw: &Option<Spanned<RawProbe>>,
    probe: Option<&Probe>,
    at_point: &dyn Fn(&Values) -> Values,
    actuation: &Actuation,
) -> Result<(), ScenarioError> {
    let (Some(j), Some(e)) =
        (probe.and_then(|p| p.joint.as_ref()), raw.as_ref().and_then(|r| r.get_ref().expected.as_ref()))
    else {
        return Ok(());
    };
    let points = actuation.all_inputs();
    for p in points {
        let Some(k) = j.predicted(&at_point(p), p) else { return Ok(()) };
        if !k.is_finite() || k == 0.0 {
            return Err(ctx.err(e, format!("probe.expected is {k} at the point {p:?}: a stiffness compared by its relative error is finite and not zero")));
        }
    }
    Ok(())
}

/// `[workspace]`: the agreement percentage a workspace sweep passes on, in [0, 100].
pub(super) fn workspace(ctx: &Ctx, raw: &Option<RawWorkspace>) -> Result<Option<f64>, ScenarioError> {
    let Some(w) = raw else { return Ok(None) };
    let x = finite(ctx, &w.min_agreement_percent, "workspace.min_agreement_percent")?;
    if !(0.0..=100.0).contains(&x) {
        return Err(
            ctx.err(&w.min_agreement_percent, format!("workspace.min_agreement_percent must lie in [0, 100], got {x}"))
        );
    }
    Ok(Some(x))
}
