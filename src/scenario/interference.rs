//! `[interference]`: which strut pairs must keep clear of each other, and by how much.

use super::error::{finite, Ctx, ScenarioError};
use super::raw::{RawActuation, RawInterference};
use super::Actuation;
use crate::mechanisms::{Mechanism, Values};
use crate::settings::InterferenceSettings;
use toml::Spanned;

/// `[interference]`: a finite threshold below a margin > 0 (default: the mechanism's length
/// scale), and exclusions that name struts of the structure built at the first point (an error
/// building it is one at `[actuation]`).
pub(super) fn interference(
    ctx: &Ctx,
    raw: &Option<Spanned<RawInterference>>,
    m: &dyn Mechanism,
    params: &Values,
    start: &Values,
    actuation: &Actuation,
    raw_actuation: &Spanned<RawActuation>,
) -> Result<Option<InterferenceSettings>, ScenarioError> {
    let Some(i) = raw else { return Ok(None) };
    let threshold = match &i.get_ref().threshold {
        None => 0.0,
        Some(t) => finite(ctx, t, "interference.threshold")?,
    };
    let margin = match &i.get_ref().margin {
        None => m.length_scale(params),
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
    let exclude = i.get_ref().exclude.iter().map(|e| e.get_ref().clone()).collect();
    // Strut names are checked against the built structure.
    let settings = InterferenceSettings {
        threshold_m: threshold,
        margin_m: margin,
        informative: i.get_ref().informative.unwrap_or(false),
        exclude,
    };
    let structure =
        m.build(params, first_inputs(actuation), start).map_err(|e| ctx.err(raw_actuation, e.to_string()))?;
    if let Err(e) = settings.check_strut_names(&structure) {
        return Err(ctx.err(i, e));
    }
    Ok(Some(settings))
}

/// The inputs of the first point or waypoint.
fn first_inputs(actuation: &Actuation) -> &Values {
    match actuation {
        Actuation::Points { points, .. } => &points[0],
        Actuation::Schedule { waypoints } => &waypoints[0].1,
    }
}
