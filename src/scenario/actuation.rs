//! `[actuation]`: the inputs to settle at (a grid or explicit points) or to follow in time
//! (waypoints), each set in the mechanism's own inputs or in one of its alternative sets. A
//! grid or a point may also set parameters (a sweep over parameters): its values then hold
//! those parameters beside the inputs, and every parameter that depends on them follows.

use super::error::{finite, value_at, values, Ctx, ScenarioError};
use super::mechanism::{too_many_sets, MAX_PARAMETER_SETS};
use super::params::params_at;
use super::raw::{RawActuation, RawRange, SpannedMap};
use super::{Actuation, MAX_POINTS};
use crate::file_model::params::ParamTable;
use crate::mechanisms::{Mechanism, ModelError, Values};
use std::collections::BTreeMap;
use toml::Spanned;

/// `actuation.grid`: a range per input.
type Grid = BTreeMap<Spanned<String>, Spanned<RawRange>>;

/// The end of a grid point's error when the point could be dropped instead.
const SKIP_HINT: &str = " (or set actuation.skip_outside = true to drop such points)";

/// `[actuation]`: exactly one of grid, points and waypoints, with the options that go with it;
/// also the grid points dropped by `skip_outside`, with the reason.
pub(super) fn actuation(
    ctx: &Ctx,
    m: &dyn Mechanism,
    table: &ParamTable,
    params: &Values,
    raw: &Spanned<RawActuation>,
) -> Result<(Actuation, Vec<(Values, String)>), ScenarioError> {
    let act = raw.get_ref();
    let given = [act.grid.is_some(), act.points.is_some(), act.waypoints.is_some()].iter().filter(|b| **b).count();
    if given != 1 {
        return Err(ctx.err(raw, "actuation needs exactly one of: grid, points, waypoints"));
    }
    let mut skipped_points = Vec::new();
    if act.skip_outside.is_some() && act.grid.is_none() {
        return Err(ctx.err(raw, "skip_outside applies to a grid only"));
    }
    let inputs = InputSets::new(m, table, params);
    let continuation = act.continuation.unwrap_or(true);
    let actuation = if let Some(g) = &act.grid {
        let skip = act.skip_outside.unwrap_or(false);
        Actuation::Points { points: grid(ctx, &inputs, g, raw, skip, &mut skipped_points)?, continuation }
    } else if let Some(list) = &act.points {
        Actuation::Points { points: points(ctx, &inputs, list, raw)?, continuation }
    } else {
        Actuation::Schedule { waypoints: waypoints(ctx, &inputs, act.waypoints.as_ref().unwrap(), raw)? }
    };
    if act.continuation.is_some() && matches!(actuation, Actuation::Schedule { .. }) {
        return Err(ctx.err(raw, "continuation applies to grid and points, not to waypoints"));
    }
    Ok((actuation, skipped_points))
}

/// The input symbols a mechanism accepts, with what checking a set of inputs needs; and the
/// parameters a point may set as well (a sweep over parameters).
struct InputSets<'a> {
    m: &'a dyn Mechanism,
    /// The file's parameters, to evaluate again at a point that sets some.
    table: &'a ParamTable,
    /// Every parameter's value in the scenario.
    params: &'a Values,
    /// The mechanism's own inputs.
    native: Vec<&'static str>,
    /// The accepted sets of input symbols: the mechanism's inputs, or one of its alternatives.
    sets: Vec<Vec<&'static str>>,
    /// The accepted sets as the messages name them.
    expected: String,
}

impl<'a> InputSets<'a> {
    /// The sets `m` accepts, to be checked against `params`.
    fn new(m: &'a dyn Mechanism, table: &'a ParamTable, params: &'a Values) -> Self {
        let native: Vec<&'static str> = m.inputs().iter().map(|i| i.symbol).collect();
        let mut sets = vec![native.clone()];
        sets.extend(m.alternative_inputs().iter().map(|s| s.to_vec()));
        let mut expected = sets.iter().map(|s| s.join(", ")).collect::<Vec<_>>().join("; or ");
        if !params.is_empty() {
            let names: Vec<&str> = params.keys().map(String::as_str).collect();
            expected = format!("{expected}; and any parameter: {}", names.join(", "));
        }
        InputSets { m, table, params, native, sets, expected }
    }

    /// Whether `key` names a parameter (an input of the same name is the input).
    fn is_param(&self, key: &str) -> bool {
        self.params.contains_key(key) && !self.sets.iter().any(|s| s.contains(&key))
    }

    /// The set a table of keys belongs to: the first that contains its first input key.
    fn set_of(&self, keys: &[&str]) -> Vec<&'static str> {
        let inputs: Vec<&str> = keys.iter().copied().filter(|k| !self.is_param(k)).collect();
        self.sets.iter().find(|s| inputs.iter().any(|k| s.contains(k))).cloned().unwrap_or_else(|| self.native.clone())
    }

    /// A point's parameters, checked by the mechanism, and its inputs converted to the
    /// mechanism's own when they are in another set (`input_syms`); its parameter entries
    /// kept beside them.
    fn convert(&self, input_syms: &[&str], point: &Values) -> Result<Values, ModelError> {
        let params = params_at(self.table, self.params, point);
        self.m.validate_params(&params)?;
        let (set, mut inputs): (Values, Values) =
            point.iter().map(|(k, v)| (k.clone(), *v)).partition(|(k, _)| self.is_param(k));
        if input_syms != self.native {
            inputs = self.m.convert_inputs(&params, &inputs)?;
        }
        inputs.extend(set);
        Ok(inputs)
    }

    /// A converted point's inputs checked against its parameters.
    fn validate(&self, point: &Values) -> Result<(), ModelError> {
        self.m.validate_inputs(&params_at(self.table, self.params, point), point)
    }

    /// One point or waypoint (`allow_t`: with its time `t`, kept as given): the symbols of one
    /// accepted set, all of them and no other, finite, converted to the mechanism's inputs and
    /// checked against the parameters; a point (not a waypoint) may set parameters too.
    fn check(&self, ctx: &Ctx, point: &Spanned<SpannedMap>, allow_t: bool) -> Result<Values, ScenarioError> {
        let map = point.get_ref();
        let keys: Vec<&str> = map.keys().map(|k| k.get_ref().as_str()).filter(|k| *k != "t").collect();
        let input_syms = self.set_of(&keys);
        for k in map.keys() {
            let key = k.get_ref().as_str();
            if self.is_param(key) && allow_t {
                return Err(ctx.err(
                    k,
                    format!("parameter '{key}' cannot follow waypoints (a parameter changes the structure): sweep it with actuation.grid or actuation.points"),
                ));
            }
            if !(input_syms.contains(&key) || self.is_param(key) || (allow_t && key == "t")) {
                return Err(ctx.err(
                    k,
                    format!(
                        "unknown input '{key}' (expected {}{})",
                        self.expected,
                        if allow_t { ", and t" } else { "" }
                    ),
                ));
            }
        }
        if let Some(s) = input_syms.iter().find(|s| !map.keys().any(|k| k.get_ref() == **s)) {
            return Err(ctx.err(point, format!("missing input '{s}' (expected {})", self.expected)));
        }
        let rejected = |e: ModelError| {
            let at = e.symbol().and_then(|sym| value_at(map, sym)).unwrap_or(point.span().start);
            ctx.err_at(at, e.to_string())
        };
        let mut vals = values(ctx, map)?;
        let t = vals.remove("t");
        vals = self.convert(&input_syms, &vals).map_err(rejected)?;
        self.validate(&vals).map_err(rejected)?;
        if let Some(t) = t {
            vals.insert("t".into(), t);
        }
        Ok(vals)
    }
}

/// `actuation.grid`: every point of the grid over one accepted input set, converted to the
/// mechanism's inputs and checked; with `skip`, a point outside the mechanism's domain goes to
/// `skipped` instead, but at least one must remain.
fn grid(
    ctx: &Ctx,
    inputs: &InputSets,
    grid: &Grid,
    whole: &Spanned<RawActuation>,
    skip: bool,
    skipped: &mut Vec<(Values, String)>,
) -> Result<Vec<Values>, ScenarioError> {
    let keys: Vec<&str> = grid.keys().map(|k| k.get_ref().as_str()).collect();
    let input_syms = inputs.set_of(&keys);
    let known = |k: &str| input_syms.contains(&k) || inputs.is_param(k);
    if let Some(k) = grid.keys().find(|k| !known(k.get_ref())) {
        return Err(
            ctx.err(k, format!("unknown input '{}' in actuation.grid (expected {})", k.get_ref(), inputs.expected))
        );
    }
    // The parameters first: the inputs vary fastest, so that continuation follows them at one
    // set of parameters (a new set rebuilds the structure).
    let mut axes: Vec<(String, Vec<f64>)> = Vec::new();
    for (k, r) in grid.iter().filter(|(k, _)| inputs.is_param(k.get_ref())) {
        axes.push((k.get_ref().clone(), axis(ctx, r.get_ref())?));
    }
    let sets: usize = axes.iter().map(|(_, v)| v.len()).product();
    if sets > MAX_PARAMETER_SETS {
        return Err(too_many_sets(ctx, whole, &sets.to_string()));
    }
    for s in &input_syms {
        let (_, r) = grid
            .iter()
            .find(|(k, _)| k.get_ref() == s)
            .ok_or_else(|| ctx.err(whole, format!("actuation.grid is missing input '{s}'")))?;
        axes.push((s.to_string(), axis(ctx, r.get_ref())?));
    }
    let total: usize = axes.iter().map(|(_, v)| v.len()).product();
    if total > MAX_POINTS {
        return Err(ctx.err(whole, format!("the grid has {total} points; at most {MAX_POINTS}")));
    }
    let points = product(&axes);
    let convert = |p: &Values| inputs.convert(&input_syms, p).map(Some);
    let points = grid_pass(ctx, grid, points, skip, skipped, "", convert)?;
    let check = |p: &Values| inputs.validate(p).map(|()| None);
    let kept = grid_pass(ctx, grid, points, skip, skipped, SKIP_HINT, check)?;
    if kept.is_empty() {
        return Err(
            ctx.err(whole, format!("every grid point is outside the mechanism's domain ({} skipped)", skipped.len()))
        );
    }
    Ok(kept)
}

/// The values of one grid axis: `count` evenly spaced from `from` to `to` (just `from` when
/// `count` is 1).
fn axis(ctx: &Ctx, r: &RawRange) -> Result<Vec<f64>, ScenarioError> {
    let (a, b) = (finite(ctx, &r.from, "from")?, finite(ctx, &r.to, "to")?);
    let n = *r.count.get_ref();
    if !(1..=MAX_POINTS as i64).contains(&n) {
        return Err(ctx.err(&r.count, format!("count must be a whole number from 1 to {MAX_POINTS}, got {n}")));
    }
    if n > 1 && a == b {
        return Err(ctx.err(&r.to, "from and to are equal but count > 1: give count = 1 or a range"));
    }
    Ok((0..n).map(|i| if n == 1 { a } else { a + (b - a) * i as f64 / (n - 1) as f64 }).collect())
}

/// Every combination of the axes' values, row-major in the axes' order.
fn product(axes: &[(String, Vec<f64>)]) -> Vec<Values> {
    let mut points = vec![Values::new()];
    for (sym, vals) in axes {
        points = points
            .into_iter()
            .flat_map(|p| {
                vals.iter().map(move |v| {
                    let mut q = p.clone();
                    q.insert(sym.clone(), *v);
                    q
                })
            })
            .collect();
    }
    points
}

/// One pass over the grid points: `step` gives a point's new form (`None`: the point as it
/// is) or rejects it with a [`ModelError`]. A rejected point goes to `skipped` with `skip`;
/// without, it is an error at that symbol's range, naming the point, followed by `hint`.
fn grid_pass(
    ctx: &Ctx,
    grid: &Grid,
    points: Vec<Values>,
    skip: bool,
    skipped: &mut Vec<(Values, String)>,
    hint: &str,
    step: impl Fn(&Values) -> Result<Option<Values>, ModelError>,
) -> Result<Vec<Values>, ScenarioError> {
    let mut kept = Vec::new();
    for p in points {
        match step(&p) {
            Ok(q) => kept.push(q.unwrap_or(p)),
            Err(e) if skip => skipped.push((p, e.to_string())),
            Err(e) => {
                let at = e.symbol().and_then(|sym| value_at(grid, sym)).unwrap_or(0);
                return Err(ctx.err_at(at, format!("grid point {:?}: {e}{hint}", p)));
            }
        }
    }
    Ok(kept)
}

/// `actuation.points`: at least one, each a full set of inputs.
fn points(
    ctx: &Ctx,
    inputs: &InputSets,
    list: &[Spanned<SpannedMap>],
    whole: &Spanned<RawActuation>,
) -> Result<Vec<Values>, ScenarioError> {
    if list.is_empty() {
        return Err(ctx.err(whole, "actuation.points is empty: give at least one point"));
    }
    if list.len() > MAX_POINTS {
        return Err(
            ctx.err(&list[MAX_POINTS], format!("actuation.points has {} points; at most {MAX_POINTS}", list.len()))
        );
    }
    list.iter().map(|p| inputs.check(ctx, p, false)).collect()
}

/// `actuation.waypoints`: at least one, each at a time `t` >= 0 s after the one before, with a
/// full set of inputs.
fn waypoints(
    ctx: &Ctx,
    inputs: &InputSets,
    list: &[Spanned<SpannedMap>],
    whole: &Spanned<RawActuation>,
) -> Result<Vec<(f64, Values)>, ScenarioError> {
    if list.is_empty() {
        return Err(ctx.err(whole, "actuation.waypoints is empty: give at least one waypoint"));
    }
    let mut waypoints = Vec::new();
    let mut last_t = f64::NEG_INFINITY;
    for w in list {
        let (tk, tv) = w
            .get_ref()
            .iter()
            .find(|(k, _)| k.get_ref() == "t")
            .ok_or_else(|| ctx.err(w, "waypoint needs a time t (s)"))?;
        let t = finite(ctx, tv, "t")?;
        if t < 0.0 {
            return Err(ctx.err(tk, format!("waypoint time must be >= 0 s, got {t}")));
        }
        if t <= last_t {
            return Err(
                ctx.err(tv, format!("waypoints must be sorted by strictly increasing t: {t} s follows {last_t} s"))
            );
        }
        last_t = t;
        let mut vals = inputs.check(ctx, w, true)?;
        vals.remove("t");
        waypoints.push((t, vals));
    }
    Ok(waypoints)
}
