//! `[actuation]`: the inputs to settle at (a grid or explicit points) or to follow in time
//! (waypoints), each set in the mechanism's own inputs or in one of its alternative sets.

use super::error::{finite, value_at, values, Ctx, ScenarioError};
use super::raw::{RawActuation, RawRange, SpannedMap};
use super::{Actuation, MAX_POINTS};
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
    let inputs = InputSets::new(m, params);
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

/// The input symbols a mechanism accepts, with what checking a set of inputs needs.
struct InputSets<'a> {
    m: &'a dyn Mechanism,
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
    fn new(m: &'a dyn Mechanism, params: &'a Values) -> Self {
        let native: Vec<&'static str> = m.inputs().iter().map(|i| i.symbol).collect();
        let mut sets = vec![native.clone()];
        sets.extend(m.alternative_inputs().iter().map(|s| s.to_vec()));
        let expected = sets.iter().map(|s| s.join(", ")).collect::<Vec<_>>().join("; or ");
        InputSets { m, params, native, sets, expected }
    }

    /// The set a table of keys belongs to: the first that contains its first key.
    fn set_of(&self, keys: &[&str]) -> Vec<&'static str> {
        self.sets.iter().find(|s| keys.iter().any(|k| s.contains(k))).cloned().unwrap_or_else(|| self.native.clone())
    }

    /// One point or waypoint (`allow_t`: with its time `t`, kept as given): the symbols of one
    /// accepted set, all of them and no other, finite, converted to the mechanism's inputs and
    /// checked against the parameters.
    fn check(&self, ctx: &Ctx, point: &Spanned<SpannedMap>, allow_t: bool) -> Result<Values, ScenarioError> {
        let map = point.get_ref();
        let keys: Vec<&str> = map.keys().map(|k| k.get_ref().as_str()).filter(|k| *k != "t").collect();
        let input_syms = self.set_of(&keys);
        for k in map.keys() {
            if !(input_syms.contains(&k.get_ref().as_str()) || (allow_t && k.get_ref() == "t")) {
                return Err(ctx.err(
                    k,
                    format!(
                        "unknown input '{}' (expected {}{})",
                        k.get_ref(),
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
        if input_syms != self.native {
            vals = self.m.convert_inputs(self.params, &vals).map_err(rejected)?;
        }
        if let Some(t) = t {
            vals.insert("t".into(), t);
        }
        self.m.validate_inputs(self.params, &vals).map_err(rejected)?;
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
    if let Some(k) = grid.keys().find(|k| !input_syms.contains(&k.get_ref().as_str())) {
        return Err(
            ctx.err(k, format!("unknown input '{}' in actuation.grid (expected {})", k.get_ref(), inputs.expected))
        );
    }
    let mut axes: Vec<(String, Vec<f64>)> = Vec::new();
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
    let mut points = product(&axes);
    if input_syms != inputs.native {
        let convert = |p: &Values| inputs.m.convert_inputs(inputs.params, p).map(Some);
        points = grid_pass(ctx, grid, points, skip, skipped, "", convert)?;
    }
    let check = |p: &Values| inputs.m.validate_inputs(inputs.params, p).map(|()| None);
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
