//! `[interference]`: the interference checks, on in every scenario unless this section turns
//! them off; which member pairs must keep clear of each other, and by how much.

use super::error::{finite, Ctx, ScenarioError};
use super::raw::RawInterference;
use crate::mechanisms::{Mechanism, Values};
use crate::settings::InterferenceSettings;
use crate::structure::Structure;
use toml::Spanned;

/// `[interference]`: on by default (struts, cables and springs); a finite threshold below a
/// margin > 0 (default: the mechanism's length scale), and exclusions that name members of
/// `structure` (the one built at the first point).
pub(super) fn interference(
    ctx: &Ctx,
    raw: &Option<Spanned<RawInterference>>,
    m: &dyn Mechanism,
    params: &Values,
    structure: &Structure,
) -> Result<InterferenceSettings, ScenarioError> {
    let default_margin = m.length_scale(params);
    let Some(i) = raw else { return Ok(InterferenceSettings::default_on(default_margin)) };
    let threshold = match &i.get_ref().threshold {
        None => 0.0,
        Some(t) => {
            let x = finite(ctx, t, "interference.threshold")?;
            // A negative threshold would let members pass through each other by that much
            // unseen: every overlap shallower than it would pass.
            if x < 0.0 {
                let message = format!("interference.threshold must be >= 0 m (a clearance below it violates), got {x}");
                return Err(ctx.err(t, message));
            }
            x
        }
    };
    let margin = match &i.get_ref().margin {
        None => default_margin,
        Some(t) => {
            let x = finite(ctx, t, "interference.margin")?;
            if x <= 0.0 {
                return Err(ctx.err(t, format!("interference.margin must be > 0 m, got {x}")));
            }
            x
        }
    };
    if threshold >= margin {
        return Err(ctx
            .err(i, format!("interference.threshold ({threshold} m) must be below interference.margin ({margin} m)")));
    }
    let exclude: Vec<(String, String)> = i.get_ref().exclude.iter().map(|e| e.get_ref().clone()).collect();
    let settings = InterferenceSettings {
        enabled: i.get_ref().enabled.unwrap_or(true),
        tendons: i.get_ref().tendons.unwrap_or(true),
        threshold_m: threshold,
        margin_m: margin,
        informative: i.get_ref().informative.unwrap_or(false),
        exclude,
    };
    // Member names are checked against the built structure.
    if let Err(e) = settings.check_member_names(structure) {
        let named = |p: &Spanned<(String, String)>| {
            let (a, b) = p.get_ref();
            *a == e.name || *b == e.name
        };
        let at = i.get_ref().exclude.iter().find(|p| named(p));
        return Err(match at {
            Some(p) => ctx.err(p, e.to_string()),
            None => ctx.err(i, e.to_string()),
        });
    }
    Ok(settings)
}
