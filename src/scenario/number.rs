//! A number or an expression of the file's parameters (`r = 0.5`, `h = "2*r"`), where a
//! scenario takes a number: `[params]` entries and the numbers of a custom `[structure]`
//! (node coordinates, gravity, masses, inertias, radii, stiffnesses, lengths, a strut's EA, a
//! heavy cable's density and segments, joint axes,
//! torsion springs, damping, initial coordinates).
//!
//! Parameters are evaluated in the order their expressions need (a cycle is an error), then
//! the structure's expressions with every parameter's value. An error inside an expression
//! names its `file:LINE:COL` inside the string.

use super::error::{Ctx, ScenarioError};
use super::raw::{Placement, RawBody, RawJoint, RawStructure, Xyz};
use crate::file_model::expr::{Expr, ExprError};
use crate::file_model::params::{Cycle, ParamTable};
use crate::mechanisms::Values;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use toml::Spanned;

/// A number, or an expression of the parameters not evaluated yet.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Num {
    Value(f64),
    Expr(String),
}

impl Num {
    /// The value (NaN for an expression not evaluated yet, which the finite-number checks
    /// then reject).
    pub(super) fn value(&self) -> f64 {
        match self {
            Num::Value(x) => *x,
            Num::Expr(_) => f64::NAN,
        }
    }
}

struct NumVisitor;

impl Visitor<'_> for NumVisitor {
    type Value = Num;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or an expression string")
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Num, E> {
        Ok(Num::Value(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Num, E> {
        Ok(Num::Value(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Num, E> {
        Ok(Num::Value(v as f64))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Num, E> {
        Ok(Num::Expr(v.to_string()))
    }
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Num, D::Error> {
        d.deserialize_any(NumVisitor)
    }
}

/// One `[params]` entry: `r = 0.5`, `h = "2*r"`, or `r = { value = 0.5, unit = "m",
/// description = "..." }` (value a number or an expression).
#[derive(Clone, Debug)]
pub(super) struct RawParam {
    pub(super) value: Num,
    /// Where the value lies in the table form (the plain form: the entry's own span).
    pub(super) value_span: Option<std::ops::Range<usize>>,
    pub(super) unit: Option<String>,
    pub(super) description: Option<String>,
}

struct ParamVisitor;

impl<'de> Visitor<'de> for ParamVisitor {
    type Value = RawParam;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number, an expression string, or a table { value, unit, description }")
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<RawParam, E> {
        Ok(RawParam::plain(Num::Value(v)))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<RawParam, E> {
        Ok(RawParam::plain(Num::Value(v as f64)))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<RawParam, E> {
        Ok(RawParam::plain(Num::Value(v as f64)))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<RawParam, E> {
        Ok(RawParam::plain(Num::Expr(v.to_string())))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawParam, A::Error> {
        let mut p = RawParam { value: Num::Value(f64::NAN), value_span: None, unit: None, description: None };
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                "value" => {
                    let v: Spanned<Num> = map.next_value()?;
                    p.value_span = Some(v.span());
                    p.value = v.into_inner();
                }
                "unit" => p.unit = Some(map.next_value()?),
                "description" => p.description = Some(map.next_value()?),
                other => {
                    return Err(de::Error::unknown_field(other, &["value", "unit", "description"]));
                }
            }
        }
        if p.value_span.is_none() {
            return Err(de::Error::missing_field("value"));
        }
        Ok(p)
    }
}

impl RawParam {
    fn plain(value: Num) -> Self {
        RawParam { value, value_span: None, unit: None, description: None }
    }
}

impl<'de> Deserialize<'de> for RawParam {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<RawParam, D::Error> {
        d.deserialize_any(ParamVisitor)
    }
}

pub(super) type ParamMap = BTreeMap<Spanned<String>, Spanned<RawParam>>;

/// A scenario error for an expression error inside the string value that starts at byte
/// `value_start` of the file (its opening quote or quotes).
pub(super) fn expr_error(ctx: &Ctx, value_start: usize, e: &ExprError, what: &str) -> ScenarioError {
    let rest = &ctx.source[value_start.min(ctx.source.len())..];
    let quotes = if rest.starts_with("\"\"\"") || rest.starts_with("'''") { 3 } else { 1 };
    // Escapes in the string shift the offset; never land inside a character.
    let mut at = (value_start + quotes + e.offset).min(ctx.source.len());
    while !ctx.source.is_char_boundary(at) {
        at -= 1;
    }
    ctx.err_at(at, format!("{what}: {}", e.message))
}

/// Where a parameter's value starts in the file.
pub(super) fn param_start(p: &Spanned<RawParam>) -> usize {
    p.get_ref().value_span.as_ref().map_or(p.span().start, |s| s.start)
}

/// The file's `[params]` as a table, each expression compiled against the parameter names
/// (a parameter that names itself through others is an error at it).
pub(super) fn param_table(ctx: &Ctx, raw: &ParamMap) -> Result<ParamTable, ScenarioError> {
    let names: Vec<&str> = raw.keys().map(|k| k.get_ref().as_str()).collect();
    let mut definitions = Vec::new();
    for (k, p) in raw {
        definitions.push(match &p.get_ref().value {
            Num::Value(x) => Ok(*x),
            Num::Expr(text) => Err(Expr::compile(text, &names)
                .map_err(|e| expr_error(ctx, param_start(p), &e, &format!("parameter '{}'", k.get_ref())))?),
        });
    }
    ParamTable::new(names.iter().map(|n| n.to_string()).collect(), definitions).map_err(|Cycle(i)| {
        let (k, p) = raw.iter().nth(i).expect("a cycle names a parameter");
        ctx.err_at(param_start(p), format!("parameter '{}' depends on itself through other parameters", k.get_ref()))
    })
}

/// Every `[params]` entry's value, each expression evaluated with the values of the
/// parameters it names, and each finite.
pub(super) fn param_values(ctx: &Ctx, raw: &ParamMap) -> Result<Values, ScenarioError> {
    let values = param_table(ctx, raw)?.evaluate(&Values::new());
    // The numbers given first, then the expressions: a NaN given (`--set r=nan`) is reported
    // where it is given, not at a parameter computed from it.
    let given = raw.iter().filter(|(_, p)| matches!(p.get_ref().value, Num::Value(_)));
    for (k, p) in given.chain(raw.iter().filter(|(_, p)| matches!(p.get_ref().value, Num::Expr(_)))) {
        let x = values[k.get_ref()];
        if !x.is_finite() {
            return Err(
                ctx.err_at(param_start(p), format!("parameter '{}' must be a finite number, got {x}", k.get_ref()))
            );
        }
    }
    Ok(values)
}

/// The value of a number or expression of the parameters `params`.
pub(super) fn evaluate(ctx: &Ctx, v: &Spanned<Num>, params: &Values, what: &str) -> Result<f64, ScenarioError> {
    match v.get_ref() {
        Num::Value(x) => Ok(*x),
        Num::Expr(text) => {
            let names: Vec<&str> = params.keys().map(String::as_str).collect();
            let values: Vec<f64> = params.values().copied().collect();
            let e = Expr::compile(text, &names).map_err(|e| expr_error(ctx, v.span().start, &e, what))?;
            Ok(e.eval(&values))
        }
    }
}

/// Replaces every expression of a custom `[structure]` by its value with `params`.
pub(super) fn resolve_structure(ctx: &Ctx, s: &mut RawStructure, params: &Values) -> Result<(), ScenarioError> {
    let mut resolve = |v: &mut Spanned<Num>, what: &str| -> Result<(), ScenarioError> {
        let x = evaluate(ctx, v, params, what)?;
        *v = Spanned::new(v.span(), Num::Value(x));
        Ok(())
    };
    if let Some(g) = &mut s.gravity {
        resolve_xyz(ctx, g, "gravity", &mut resolve)?;
    }
    for l in &mut s.loads {
        resolve_xyz(ctx, &mut l.force, "a load's force", &mut resolve)?;
    }
    for n in &mut s.masses {
        resolve(&mut n.mass, "a node's mass")?;
    }
    for b in &mut s.bodies {
        resolve_body(ctx, b, &mut resolve)?;
    }
    for m in s.struts.iter_mut().chain(s.springs.iter_mut()).chain(s.cables.iter_mut()) {
        resolve_member(&mut m.radius, &mut m.stiffness, &mut m.length, &mut resolve)?;
        for mu in m.friction.iter_mut().flat_map(|f| f.get_mut().iter_mut()) {
            resolve(mu, "friction")?;
        }
        let lumped = [(&mut m.ea, "EA"), (&mut m.youngs_modulus, "E"), (&mut m.area, "area")];
        for (v, what) in lumped.into_iter().chain([(&mut m.density, "density"), (&mut m.segments, "segments")]) {
            if let Some(v) = v {
                resolve(v, what)?;
            }
        }
    }
    for g in s.strut_groups.iter_mut().chain(s.spring_groups.iter_mut()).chain(s.cable_groups.iter_mut()) {
        resolve_member(&mut g.radius, &mut g.stiffness, &mut g.length, &mut resolve)?;
    }
    for j in &mut s.joints {
        resolve_joint(ctx, j, &mut resolve)?;
    }
    for a in &mut s.actuators {
        if let Some(d) = &mut a.direction {
            resolve_xyz(ctx, d, "direction", &mut resolve)?;
            if let Some(pl) = &mut a.placement {
                let (turn, _) = resolve_placement(ctx, pl, &mut resolve)?;
                place(d, turn, [0.0; 3]);
            }
        }
    }
    Ok(())
}

/// A rotation (unit axis, angle [rad]) and an offset [m].
type Turn = Option<([f64; 3], f64)>;

/// A generated copy's rotation and offset, evaluated.
fn resolve_placement(ctx: &Ctx, pl: &mut Placement, resolve: &mut Resolve) -> Result<(Turn, [f64; 3]), ScenarioError> {
    let mut turn = None;
    if let Some(r) = &mut pl.rotate {
        resolve_xyz(ctx, &mut r.axis, "rotate.axis", resolve)?;
        resolve(&mut r.angle, "rotate.angle")?;
        let axis = values(&r.axis);
        let square = axis.iter().map(|c| c * c).sum::<f64>();
        if square.is_nan() || square <= 0.0 {
            return Err(ctx.err(&r.axis, format!("rotate.axis is {axis:?}: a direction, not zero")));
        }
        turn = Some((axis, r.angle.get_ref().value()));
    }
    let mut offset = [0.0; 3];
    if let Some(o) = &mut pl.offset {
        resolve_xyz(ctx, o, "offset", resolve)?;
        offset = values(o);
    }
    Ok((turn, offset))
}

/// The three numbers of a resolved triple (NaN where one is missing, which the checks refuse).
fn values(v: &Xyz) -> [f64; 3] {
    std::array::from_fn(|i| v.get_ref().get(i).map_or(f64::NAN, |c| c.get_ref().value()))
}

/// A resolved point or vector turned and then offset.
fn place(v: &mut Xyz, turn: Turn, offset: [f64; 3]) {
    let p = values(v);
    let p = turn.map_or(p, |(axis, angle)| crate::structure::rotated(p, axis, angle));
    for (c, x) in v.get_mut().iter_mut().zip(p.iter().zip(offset).map(|(a, b)| a + b)) {
        *c = Spanned::new(c.span(), Num::Value(x));
    }
}

type Resolve<'a> = dyn FnMut(&mut Spanned<Num>, &str) -> Result<(), ScenarioError> + 'a;

/// Resolves a triple's three numbers; a list of another length is refused as such (it had
/// been reported with NaN for a missing component).
fn resolve_xyz(ctx: &Ctx, v: &mut Xyz, what: &str, resolve: &mut Resolve) -> Result<(), ScenarioError> {
    v.get_mut().iter_mut().try_for_each(|c| resolve(c, what))?;
    let n = v.get_ref().len();
    if n != 3 {
        return Err(ctx.err(v, format!("{what} must be three finite numbers [x, y, z], got {n} of them")));
    }
    Ok(())
}

fn resolve_body(ctx: &Ctx, b: &mut RawBody, resolve: &mut Resolve) -> Result<(), ScenarioError> {
    if let Some(m) = &mut b.mass {
        resolve(m, "mass")?;
    }
    if let Some(i) = &mut b.inertia {
        resolve_xyz(ctx, i, "inertia", resolve)?;
    }
    for (name, p) in &mut b.nodes {
        resolve_xyz(ctx, p, &format!("a coordinate of node '{}'", name.get_ref()), resolve)?;
    }
    if let Some(pl) = &mut b.placement {
        let (turn, offset) = resolve_placement(ctx, pl, resolve)?;
        b.nodes.values_mut().for_each(|p| place(p, turn, offset));
    }
    Ok(())
}

/// A member's (or a member group's) radius, stiffness and length.
fn resolve_member(
    radius: &mut Option<Spanned<Num>>,
    stiffness: &mut Option<Spanned<Num>>,
    length: &mut Option<Spanned<Num>>,
    resolve: &mut Resolve,
) -> Result<(), ScenarioError> {
    for (v, what) in [(radius, "radius"), (stiffness, "stiffness"), (length, "length")] {
        if let Some(v) = v {
            resolve(v, what)?;
        }
    }
    Ok(())
}

fn resolve_joint(ctx: &Ctx, j: &mut RawJoint, resolve: &mut Resolve) -> Result<(), ScenarioError> {
    let turn = match &mut j.placement {
        Some(pl) => resolve_placement(ctx, pl, resolve)?.0,
        None => None,
    };
    for (v, what) in [(&mut j.axis, "axis"), (&mut j.axis2, "axis2")] {
        if let Some(v) = v {
            resolve_xyz(ctx, v, what, resolve)?;
            place(v, turn, [0.0; 3]);
        }
    }
    let fields = [
        (&mut j.torsion_stiffness, "torsion_stiffness"),
        (&mut j.torsion_rest, "torsion_rest"),
        (&mut j.damping, "damping"),
        (&mut j.initial_coordinate, "initial_coordinate"),
    ];
    for (v, what) in fields {
        if let Some(v) = v {
            resolve(v, what)?;
        }
    }
    Ok(())
}
