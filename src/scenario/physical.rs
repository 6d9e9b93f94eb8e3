//! What the simulation could not do with the structure, found at `check` time: the structure
//! of the first point built once and its sizes checked (extent, masses, moments of inertia,
//! nodes inside the bounding box), so that a run never fails late on something the file set.

use super::error::{Ctx, ScenarioError};
use super::raw::RawScenario;
use crate::mechanisms::{Mechanism, Values};
use crate::settings::SimSettings;
use crate::structure::{BodyKind, Structure};

/// Smallest and largest extent of a structure the f64 simulation handles [m]: below, the
/// settle tolerances (1e-10 m/s, 1e-14 of the size) reach round-off; above, node coordinates
/// lose the digits the checks compare.
pub const STRUCTURE_EXTENT_M: (f64, f64) = (1e-4, 1e5);

/// Smallest and largest mass of a free body [kg], and the same range for a moment of inertia
/// [kg m^2] scaled by the extent squared: outside it, the mass matrix's condition leaves f64.
pub const BODY_MASS_KG: (f64, f64) = (1e-9, 1e9);

/// The structure at the first point of the scenario: within the sizes above, every node inside
/// `sim.bounding_box`. Errors are located at the key that sets the value: the bounding box
/// when the file gives it, else the parameter farthest from 1 in order of magnitude (or the
/// structure, or the mechanism).
pub(super) fn physical(
    ctx: &Ctx,
    raw: &RawScenario,
    m: &dyn Mechanism,
    s: &Structure,
    sim: &SimSettings,
) -> Result<(), ScenarioError> {
    // The parameter most likely to set a size: the one farthest from 1 in order of magnitude.
    // (A parameter given as an expression counts as order 0.)
    let extreme = raw.params.iter().max_by(|a, b| {
        let order = |p: &super::number::RawParam| match p.value {
            super::number::Num::Value(v) => v.abs().ln().abs(),
            super::number::Num::Expr(_) => 0.0,
        };
        order(a.1.get_ref()).total_cmp(&order(b.1.get_ref()))
    });
    let at_model = |message: String| {
        let e = match (extreme.map(|(k, _)| k), &raw.structure) {
            (Some(k), _) => ctx.err(k, ""),
            (None, Some(st)) => ctx.err(st, ""),
            (None, None) => ctx.err(&raw.mechanism, ""),
        };
        ScenarioError { message, ..e }
    };
    let size = crate::structure::extent_m(s);
    let (lo, hi) = STRUCTURE_EXTENT_M;
    if !(lo..=hi).contains(&size) {
        return Err(at_model(format!(
            "{}'s structure is {size:e} m across; the simulation handles {lo:e} to {hi:e} m",
            m.name()
        )));
    }
    masses(ctx, raw, s, size, &at_model)?;
    point_mass_step(ctx, raw, s, sim, &at_model)?;
    let half = sim.bounding_box_m;
    if let Some(n) = s.nodes.iter().find(|n| n.position.iter().any(|c| c.abs() > half)) {
        let message = format!(
            "node '{}' at {:?} m lies outside sim.bounding_box = {half} m (the box every node must stay in): enlarge the box",
            n.name, n.position
        );
        return Err(match &raw.sim.bounding_box {
            Some(b) => ctx.err(b, message),
            None => at_model(message),
        });
    }
    Ok(())
}

/// Every free body's mass and moments in the simulation's range, scaled by the extent
/// `size_m`; an error at the body's `mass` or `inertia` key where the file declares it by name.
fn masses(
    ctx: &Ctx,
    raw: &RawScenario,
    s: &Structure,
    size: f64,
    at_model: &dyn Fn(String) -> ScenarioError,
) -> Result<(), ScenarioError> {
    for b in s.bodies.iter().filter(|b| b.kind == BodyKind::Free) {
        let Some(i) = &b.inertia else { continue };
        let (lo, hi) = BODY_MASS_KG;
        let scale = size * size;
        let moments_ok = i.principal_kg_m2.iter().all(|j| (lo * scale..=hi * scale).contains(j));
        if !(lo..=hi).contains(&i.mass_kg) || !moments_ok {
            let message = format!(
                "body '{}' has mass {:e} kg and moments {:?} kg m^2; the simulation handles masses of {lo:e} to {hi:e} kg and moments of that times the extent squared ({scale:e} m^2)",
                b.name, i.mass_kg, i.principal_kg_m2
            );
            // At the body's mass (or inertia, or name) where the file declares it by that name;
            // a built-in mechanism's, a repeated or a generated body at the model.
            let declared =
                raw.structure.as_ref().and_then(|st| st.get_ref().bodies.iter().find(|r| *r.name.get_ref() == b.name));
            return Err(match declared {
                Some(r) if !moments_ok && r.inertia.is_some() => ctx.err(r.inertia.as_ref().unwrap(), message),
                Some(r) => match &r.mass {
                    Some(mass) => ctx.err(mass, message),
                    None => ctx.err(&r.name, message),
                },
                None => at_model(message),
            });
        }
    }
    Ok(())
}

/// The step `sim.dt` against the fastest point mass (`structure::lumped`): an error at
/// `sim.dt` past the step's stability limit.
fn point_mass_step(
    ctx: &Ctx,
    raw: &RawScenario,
    s: &Structure,
    sim: &SimSettings,
    at_model: &dyn Fn(String) -> ScenarioError,
) -> Result<(), ScenarioError> {
    if let Some((omega, b)) = crate::structure::lumped::fastest_point_mass(s) {
        let limit = crate::structure::lumped::STABLE_OMEGA_DT;
        if omega * sim.dt_s >= limit {
            let message = format!(
                "point mass '{}' vibrates up to {omega:.4e} rad/s on its members (2 sum k / m), and omega dt = {:.3} with sim.dt = {} s: the step is unstable from {limit}; make sim.dt smaller than {:.3e} s, or the members softer",
                s.bodies[b].name,
                omega * sim.dt_s,
                sim.dt_s,
                limit / omega
            );
            return Err(match &raw.sim.dt {
                Some(dt) => ctx.err(dt, message),
                None => at_model(message),
            });
        }
    }
    Ok(())
}

/// The structure at the first point (or waypoint) of a validated actuation.
pub(super) fn first_structure(
    ctx: &Ctx,
    raw: &RawScenario,
    m: &dyn Mechanism,
    params: &Values,
    start: &Values,
    first_inputs: &Values,
) -> Result<Structure, ScenarioError> {
    m.build(params, first_inputs, start).map_err(|e| ctx.err(&raw.actuation, e.to_string()))
}
