//! `[params]` and `[start]`: named numbers the mechanism declares.

use super::error::{known_keys, value_at, values, Ctx, ScenarioError};
use super::number::{param_values, ParamMap};
use super::raw::SpannedMap;
use crate::mechanisms::{self, Mechanism, Values};

/// Parameters: known symbols, each a finite number or an expression of the others, in the
/// mechanism's unit where the file names one, then the mechanism's own ranges; the result
/// holds every parameter, the missing ones at the mechanism's defaults.
pub(super) fn params(ctx: &Ctx, m: &dyn Mechanism, raw: &ParamMap) -> Result<Values, ScenarioError> {
    let known: Vec<_> = m.params().iter().map(|p| p.symbol).collect();
    known_keys(ctx, raw, &known, "parameter", m.name())?;
    for (k, p) in raw {
        let spec = m.params().iter().find(|s| s.symbol == k.get_ref());
        if let (Some(unit), Some(spec)) = (&p.get_ref().unit, spec) {
            if unit != spec.unit {
                return Err(ctx.err(
                    p,
                    format!("parameter '{}' is in {} (unit = \"{}\"), not {unit}", spec.symbol, spec.unit, spec.unit),
                ));
            }
        }
    }
    let given = param_values(ctx, raw)?;
    let params = mechanisms::with_defaults(m, &given);
    if let Err(e) = m.validate_params(&params) {
        let at = e.symbol().and_then(|sym| value_at(raw, sym)).unwrap_or(0);
        return Err(ctx.err_at(at, e.to_string()));
    }
    Ok(params)
}

/// The start of the free coordinates: known keys, finite.
pub(super) fn start(ctx: &Ctx, m: &dyn Mechanism, raw: &SpannedMap) -> Result<Values, ScenarioError> {
    let known: Vec<_> = m.start_keys().iter().map(|(key, _)| *key).collect();
    known_keys(ctx, raw, &known, "start key", m.name())?;
    values(ctx, raw)
}
