//! What the run is judged on: `[[checks]]`, `[stability]`, `[probe]` and `[workspace]`.

use super::error::{finite, positive_value, Ctx, ScenarioError};
use super::raw::{RawCheck, RawExpectedStability, RawProbe, RawStability, RawWorkspace};
use super::Actuation;
use crate::mechanisms::Mechanism;
use crate::settings::{Check, Probe};

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
) -> Result<Vec<bool>, ScenarioError> {
    let Some(e) = raw.as_ref().and_then(|s| s.expect.as_ref()) else { return Ok(Vec::new()) };
    let word = |w: &String| match w.as_str() {
        "stable" => Ok(true),
        "unstable" => Ok(false),
        other => Err(ctx.err(e, format!("stability.expect must be \"stable\" or \"unstable\", got \"{other}\""))),
    };
    match e.get_ref() {
        RawExpectedStability::All(w) => Ok(vec![word(w)?]),
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
            list.iter().map(word).collect()
        }
    }
}

/// `[probe]`: a torque > 0 N m and a tolerance > 0, for a mechanism that has a stiffness probe.
pub(super) fn probe(ctx: &Ctx, m: &dyn Mechanism, raw: &Option<RawProbe>) -> Result<Option<Probe>, ScenarioError> {
    let Some(p) = raw else { return Ok(None) };
    if m.stiffness_probe().is_none() {
        return Err(ctx.err(&p.torque, format!("{} has no stiffness probe", m.name())));
    }
    let t = finite(ctx, &p.torque, "probe.torque")?;
    if t <= 0.0 {
        return Err(ctx.err(&p.torque, format!("probe.torque must be > 0 N m, got {t}")));
    }
    let tol = positive_value(ctx, &p.tolerance, "probe.tolerance")?;
    Ok(Some(Probe { torque_nm: t, tolerance: tol }))
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
