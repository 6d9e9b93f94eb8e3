//! `[[fidelity]]`: the idealizations of a paper's model that the file can relax, each with its
//! physical data (`structure/fidelity.rs`). A run and every study use the ideal structure;
//! `tensegrity attribute` runs the file's checks under each relaxation alone and under all of
//! them together (`study/attribution.rs`). Every relaxation is applied to the first point's
//! structure here, alone and together, so a member that does not exist, a structure that cannot
//! take it, missing data and a step too long for its point masses are errors at its table.
//!
//! ```toml
//! [[fidelity]]
//! name = "elastic cables"         # the share's name in the report (default: the assumption)
//! relax = "inextensible cables"   # or "rigid struts", "massless cables"
//! members = ["cable 1"]           # default: every member the assumption holds for
//! EA = 1.6e5                      # N; or E (Pa) with area (m^2)
//! source = "steel wire rope, 1 mm: E = 200 GPa (assumed, catalogue)"
//! ```
//!
//! `relax = "no gravity"` with `gravity = [0, -9.81, 0]` gives the structure the gravity a
//! prototype feels (a planar mechanism built upright).

use super::error::{Ctx, ScenarioError};
use super::raw::RawScenario;
use super::Actuation;
use crate::mechanisms::{Mechanism, Values};
use crate::structure::fidelity::{self, Assumption, Relaxation};
use crate::structure::{lumped, Structure};
use serde::Deserialize;
use toml::Spanned;

/// One `[[fidelity]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRelaxation {
    name: Option<Spanned<String>>,
    relax: Spanned<String>,
    members: Option<Spanned<Vec<String>>>,
    #[serde(rename = "EA")]
    ea: Option<Spanned<f64>>,
    #[serde(rename = "E")]
    youngs_modulus: Option<Spanned<f64>>,
    area: Option<Spanned<f64>>,
    density: Option<Spanned<f64>>,
    segments: Option<Spanned<i64>>,
    gravity: Option<Spanned<[f64; 3]>>,
    set: Option<Spanned<std::collections::BTreeMap<String, f64>>>,
    /// Where the data come from (the paper's prototype, a catalogue): for the reader.
    #[allow(dead_code)]
    source: Option<String>,
}

/// What the relaxations are checked against: the first point's structure, the commands that
/// place it, the step, and whether the winches move without a rebuild.
pub(super) struct FirstPoint<'a> {
    pub structure: &'a Structure,
    pub commands: Values,
    pub dt_s: f64,
    /// Every parameter's value (what a "parameter values" relaxation may set).
    pub params: Values,
    /// The points are carried by continuation or followed in time (or a motion runs), so a
    /// winch moves a cable after its build.
    pub winches_move: bool,
}

impl FirstPoint<'_> {
    /// The first point's `structure` built at `commands` in the scenario's sections `s` (with a
    /// `motion` or not).
    pub fn new<'a>(structure: &'a Structure, commands: Values, s: &super::Sections, motion: bool) -> FirstPoint<'a> {
        let winches_move = motion
            || match &s.actuation {
                Actuation::Points { points, continuation } => *continuation && points.len() > 1,
                Actuation::Schedule { .. } => true,
            };
        FirstPoint { structure, commands, dt_s: s.sim.dt_s, params: s.params.clone(), winches_move }
    }
}

/// The file's relaxations, each applied alone and all together to the first point's structure.
pub(super) fn fidelity(ctx: &Ctx, raw: &RawScenario, first: &FirstPoint) -> Result<Vec<Relaxation>, ScenarioError> {
    let mut list: Vec<Relaxation> = Vec::new();
    for r in &raw.fidelity {
        let relaxation = relaxation(ctx, r)?;
        if let Some(same) = list.iter().find(|o| o.name == relaxation.name) {
            return Err(ctx.err(r, format!("a relaxation named '{}' is listed twice: name each one", same.name)));
        }
        let structural = relaxation.assumption != Assumption::ParameterValues;
        if structural && list.iter().any(|o| o.assumption == relaxation.assumption && o.members == relaxation.members) {
            return Err(ctx.err(&r.get_ref().relax, "this assumption is relaxed twice for the same members"));
        }
        list.push(relaxation);
    }
    for (i, (r, raw_r)) in list.iter().zip(&raw.fidelity).enumerate() {
        if let Some(name) = r.params.keys().find(|k| !first.params.contains_key(*k)) {
            let at = raw_r.get_ref().set.as_ref().expect("a parameter relaxation has its set");
            return Err(ctx.err(at, format!("'{}': set: '{name}' is not a parameter of this scenario", r.name)));
        }
        if first.winches_move && fidelity::releases_winch(first.structure, r) {
            return Err(ctx.err(raw_r, format!("'{}': a heavy cable is built at its winch's length and the winch no longer moves it, but this run moves the winch after the build (continuation, waypoints or a motion): set continuation = false, or relax another cable", r.name)));
        }
        let set: Vec<&Relaxation> = fidelity::with_base(&list, i).into_iter().map(|j| &list[j]).collect();
        applies(ctx, raw_r, first, &set)?;
    }
    if list.len() > 1 {
        applies(ctx, &raw.fidelity[0], first, &list.iter().collect::<Vec<_>>())?;
    }
    Ok(list)
}

/// The first structure with `set` applied: an error at `at` where it cannot take them, or where
/// the step is too long for the point masses they make.
fn applies(
    ctx: &Ctx,
    at: &Spanned<RawRelaxation>,
    first: &FirstPoint,
    set: &[&Relaxation],
) -> Result<(), ScenarioError> {
    let mut s = first.structure.clone();
    fidelity::relax(&mut s, set, &first.commands).map_err(|e| ctx.err(at, e.to_string()))?;
    if let Some((omega, b)) = lumped::fastest_point_mass(&s) {
        if omega * first.dt_s >= lumped::STABLE_OMEGA_DT {
            return Err(ctx.err(at, format!(
                "relaxed, point mass '{}' vibrates up to {omega:.4e} rad/s on its members (2 sum k / m): the step sim.dt = {} s is unstable from omega dt = {}; make sim.dt smaller than {:.3e} s",
                s.bodies[b].name, first.dt_s, lumped::STABLE_OMEGA_DT, lumped::STABLE_OMEGA_DT / omega
            )));
        }
    }
    Ok(())
}

/// One table read: its assumption, members and data, each datum positive and finite.
fn relaxation(ctx: &Ctx, r: &Spanned<RawRelaxation>) -> Result<Relaxation, ScenarioError> {
    let raw = r.get_ref();
    let assumption = Assumption::from_label(raw.relax.get_ref()).ok_or_else(|| {
        let known: Vec<_> = Assumption::ALL.iter().map(|(_, l)| format!("\"{l}\"")).collect();
        ctx.err(&raw.relax, format!("unknown assumption '{}': relax one of {}", raw.relax.get_ref(), known.join(", ")))
    })?;
    let positive = |v: &Option<Spanned<f64>>, key: &str| -> Result<Option<f64>, ScenarioError> {
        match v {
            Some(x) if !(x.get_ref().is_finite() && *x.get_ref() > 0.0) => {
                Err(ctx.err(x, format!("{key} must be a finite number above 0, got {}", x.get_ref())))
            }
            v => Ok(v.as_ref().map(|x| *x.get_ref())),
        }
    };
    let ea = match (positive(&raw.ea, "EA")?, positive(&raw.youngs_modulus, "E")?, positive(&raw.area, "area")?) {
        (Some(_), Some(_), _) => return Err(ctx.err(r, "give EA, or E with area, not both")),
        (ea, Some(e), Some(a)) => ea.or(Some(e * a)),
        (_, Some(_), None) | (_, None, Some(_)) => return Err(ctx.err(r, "E and area go together (EA = E area)")),
        (ea, None, None) => ea,
    };
    let density = positive(&raw.density, "density")?;
    let segments = segments(ctx, raw)?;
    let needs: &[(&str, bool)] = match assumption {
        Assumption::InextensibleCables => &[("EA (N), or E (Pa) with area (m^2)", ea.is_some())],
        Assumption::RigidStruts => &[("EA (N), or E (Pa) with area (m^2)", ea.is_some())],
        Assumption::MasslessCables => &[("density (kg/m)", density.is_some()), ("segments", raw.segments.is_some())],
        Assumption::NoGravity => &[("gravity = [x, y, z] (m/s^2)", raw.gravity.is_some())],
        Assumption::ParameterValues => &[("set = { NAME = VALUE, ... }", raw.set.is_some())],
    };
    if let Some((what, _)) = needs.iter().find(|(_, given)| !given) {
        return Err(ctx.err(r, format!("relaxing {} needs {what}", assumption.label())));
    }
    let name = raw.name.as_ref().map_or(assumption.label().to_string(), |n| n.get_ref().clone());
    if name.trim().is_empty() {
        return Err(ctx.err(raw.name.as_ref().unwrap(), "name must not be empty"));
    }
    let members = raw.members.as_ref().map(|m| m.get_ref().clone()).unwrap_or_default();
    let gravity = raw.gravity.as_ref().map(|g| *g.get_ref());
    if let Some(g) = raw.gravity.as_ref().filter(|g| g.get_ref().iter().any(|x| !x.is_finite())) {
        return Err(ctx.err(g, "gravity must be three finite numbers (m/s^2)"));
    }
    if let (Assumption::NoGravity | Assumption::ParameterValues, Some(m)) = (assumption, &raw.members) {
        return Err(ctx.err(m, format!("\"{}\" acts on the whole structure: it takes no members", assumption.label())));
    }
    let params = raw.set.as_ref().filter(|_| assumption == Assumption::ParameterValues);
    if let Some((name, x)) = params.and_then(|p| p.get_ref().iter().find(|(_, x)| !x.is_finite())) {
        return Err(ctx.err(params.unwrap(), format!("set: {name} = {x}: a parameter's value is a finite number")));
    }
    let params = params.map(|p| p.get_ref().clone()).unwrap_or_default();
    let gravity_m_per_s2 = gravity.filter(|_| assumption == Assumption::NoGravity);
    Ok(Relaxation {
        name,
        assumption,
        members,
        ea_n: ea,
        density_kg_per_m: density,
        segments,
        gravity_m_per_s2,
        params,
    })
}

/// A heavy cable's segment count, 1 to [`lumped::MAX_CABLE_SEGMENTS`] (1 where not given).
fn segments(ctx: &Ctx, raw: &RawRelaxation) -> Result<usize, ScenarioError> {
    let Some(n) = &raw.segments else { return Ok(1) };
    let max = lumped::MAX_CABLE_SEGMENTS;
    match usize::try_from(*n.get_ref()) {
        Ok(k) if (1..=max).contains(&k) => Ok(k),
        _ => Err(ctx.err(n, format!("segments must be 1 to {max}, got {}", n.get_ref()))),
    }
}

/// The mechanism `inner` with the relaxations `set` applied to every structure it builds.
pub fn relaxed(inner: Box<dyn Mechanism>, set: Vec<Relaxation>) -> Box<dyn Mechanism> {
    Box::new(crate::mechanisms::relaxed::Relaxed::new(inner, set))
}
