//! Bounded work: a scenario that `check` accepts finishes in a bounded number of steps. The
//! limits are documented in the README ("Limits"); each error names the key that sets the count.

use super::error::{Ctx, ScenarioError};
use super::raw::RawScenario;
use super::{Actuation, MAX_POINTS};
use crate::settings::{SettleCriteria, SimSettings};

/// Most steps one settle may take (`settle.max_time / sim.dt`): at the 10-50 us a step of this
/// testbed's structures take, 2 to 10 minutes.
pub const MAX_STEPS_PER_SETTLE: f64 = 1e7;

/// Most steps one run may take (settle points times the steps per settle, plus a schedule's
/// ticks): hours at most.
pub const MAX_STEPS_PER_RUN: f64 = 1e9;

/// The step counts of `sim`, `settle` and `actuation` within the limits; points of a list within
/// [`MAX_POINTS`]; waypoints at least one time step apart.
pub(super) fn bounds(
    ctx: &Ctx,
    raw: &RawScenario,
    sim: &SimSettings,
    settle: &SettleCriteria,
    actuation: &Actuation,
) -> Result<(), ScenarioError> {
    let act = raw.actuation.get_ref();
    let at_settle = || match (&raw.settle.max_time, &raw.sim.dt) {
        (Some(t), _) => ctx.err(t, ""),
        (None, Some(dt)) => ctx.err(dt, ""),
        (None, None) => ctx.err(&raw.actuation, ""),
    };
    let located = |e: ScenarioError, message: String| ScenarioError { message, ..e };
    let per_settle = (settle.max_time_s / sim.dt_s).ceil();
    if per_settle.is_nan() || per_settle > MAX_STEPS_PER_SETTLE {
        return Err(located(
            at_settle(),
            format!(
                "settle.max_time / sim.dt = {} / {} s is {per_settle:e} steps per settle; at most {MAX_STEPS_PER_SETTLE:e}",
                settle.max_time_s, sim.dt_s
            ),
        ));
    }
    let (settles, schedule_steps) = match actuation {
        Actuation::Points { points, .. } => {
            if points.len() > MAX_POINTS {
                let list = act.points.as_ref().map(|l| ctx.err(&l[MAX_POINTS], "")).unwrap_or_else(at_settle);
                return Err(located(list, format!("{} points; at most {MAX_POINTS}", points.len())));
            }
            (points.len() as f64, 0.0)
        }
        Actuation::Schedule { waypoints } => {
            let list = act.waypoints.as_deref().unwrap_or_default();
            for (k, w) in waypoints.windows(2).enumerate() {
                if w[1].0 - w[0].0 < sim.dt_s {
                    return Err(ctx.err(
                        &list[k + 1],
                        format!(
                            "waypoint at t = {} s follows the one at {} s by less than sim.dt = {} s: it would never be reached",
                            w[1].0, w[0].0, sim.dt_s
                        ),
                    ));
                }
            }
            let last = waypoints.last().map_or(0.0, |w| w.0);
            let ticks = (last / sim.dt_s).ceil();
            if ticks.is_nan() || ticks > MAX_STEPS_PER_SETTLE {
                return Err(ctx.err(
                    &list[list.len() - 1],
                    format!("the last waypoint at t = {last} s is {ticks:e} time steps away; at most {MAX_STEPS_PER_SETTLE:e}"),
                ));
            }
            (1.0, ticks)
        }
    };
    let total = settles * per_settle + schedule_steps;
    if total > MAX_STEPS_PER_RUN {
        return Err(located(
            ctx.err(&raw.actuation, ""),
            format!(
                "{settles} settle point(s) of up to {per_settle:e} steps each make {total:e} steps; at most {MAX_STEPS_PER_RUN:e} per run (fewer points, or a shorter settle.max_time)"
            ),
        ));
    }
    Ok(())
}
