//! `[prestress]`: when a structure counts as having lost its self-stress, and whether that
//! fails the run or warns. A custom structure with cables is judged without the section too
//! ([`Prestress::DEFAULT`]: it fails when every cable is slack at a settle point).

use super::error::{finite, Ctx, ScenarioError};
use super::raw::RawPrestress;
use crate::settings::{OnLoss, Prestress};
use crate::structure::Structure;
use toml::Spanned;

/// The prestress judgement of a scenario: the section's, the default for a custom structure
/// with cables, or none (a built-in mechanism without the section, a structure without cables).
pub(super) fn prestress(
    ctx: &Ctx,
    raw: &Option<Spanned<RawPrestress>>,
    first: &Structure,
    custom: bool,
) -> Result<Option<Prestress>, ScenarioError> {
    let Some(section) = raw else {
        return Ok((custom && !first.cables.is_empty()).then_some(Prestress::DEFAULT));
    };
    if first.cables.is_empty() {
        return Err(ctx.err(section, "[prestress] judges the cables' tension, and this structure has no cables"));
    }
    let p = section.get_ref();
    let on_loss = match p.on_loss.as_ref().map(|s| (s, s.get_ref().as_str())) {
        None | Some((_, "fail")) => OnLoss::Fail,
        Some((_, "warn")) => OnLoss::Warn,
        Some((s, other)) => {
            return Err(ctx.err(s, format!("prestress.on_loss must be \"fail\" or \"warn\", got '{other}'")))
        }
    };
    let min_fraction = p.min_fraction.as_ref().map(|f| fraction(ctx, f, first)).transpose()?;
    Ok(Some(Prestress { min_fraction, on_loss }))
}

/// `min_fraction`: in (0, 1], of a drawn self-stress that is not zero.
fn fraction(ctx: &Ctx, f: &Spanned<f64>, first: &Structure) -> Result<f64, ScenarioError> {
    let x = finite(ctx, f, "prestress.min_fraction")?;
    if !(x > 0.0 && x <= 1.0) {
        return Err(ctx.err(f, format!("prestress.min_fraction must lie in (0, 1], got {x}")));
    }
    let drawn = first.drawn_cable_tension_n();
    if drawn.is_nan() || drawn <= 0.0 {
        return Err(ctx.err(
            f,
            "prestress.min_fraction is a share of the cables' tension at the drawn state, and they carry none \
             there (no elastic cable is drawn longer than its rest length)",
        ));
    }
    Ok(x)
}
