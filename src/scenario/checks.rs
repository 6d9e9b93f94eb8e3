//! What the run is judged on: `[[checks]]`, `[stability]`, `[probe]` and `[workspace]`.

use super::error::{finite, positive_value, Ctx, ScenarioError};
use super::raw::{RawCheck, RawProbe, RawStability, RawWorkspace};
use crate::mechanisms::Mechanism;
use crate::settings::{Check, Probe};

/// `[[checks]]`: each a quantity of the mechanism, with a tolerance > 0.
pub(super) fn checks(ctx: &Ctx, m: &dyn Mechanism, raw: &[RawCheck]) -> Result<Vec<Check>, ScenarioError> {
    let mut checks = Vec::new();
    for c in raw {
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
