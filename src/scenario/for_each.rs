//! `for` on `[[quantities]]`, `[[predictions]]` and `[[equations]]`: one entry written for
//! every index of a range or every member of a group, each judged on its own (a prediction
//! over a group fails by its element's name, `NAME[i]` or `NAME[member]`). Aggregates
//! (`sum(i in 0..n, ...)`, `min`, `max`) and integer templates are filled in every model
//! expression, with or without `for` (`pattern.rs`).

use super::error::{Ctx, ScenarioError};
use super::number::expr_error;
use super::pattern::{bindings, spanned_expr, spanned_name, Binding, Env, Groups, MAX_PATTERN_COUNT};
use super::raw::{For, RawEquation, RawPrediction, RawQuantity, RawScenario, RawStructure};
use toml::Spanned;

/// The member kinds a `for` may run over, besides the file's member groups.
const KINDS: [&str; 3] = ["struts", "springs", "cables"];

/// Fills the model's entries with the parameters of `env` (whose values decide the ranges).
pub(super) fn expand_model(ctx: &Ctx, raw: &mut RawScenario, env: &Env) -> Result<(), ScenarioError> {
    let groups = match &raw.structure {
        Some(s) => member_groups(ctx, s.get_ref())?,
        None => Groups::new(),
    };
    let env = env.clone();
    raw.quantities = expand(ctx, &env, &groups, std::mem::take(&mut raw.quantities), quantity)?;
    raw.predictions = expand(ctx, &env, &groups, std::mem::take(&mut raw.predictions), prediction)?;
    raw.equations = expand(ctx, &env, &groups, std::mem::take(&mut raw.equations), equation)?;
    if let Some(e) = &mut raw.energy {
        e.potential = spanned_expr(ctx, &e.potential, &env, &groups)?;
        e.kinetic = e.kinetic.as_ref().map(|k| spanned_expr(ctx, k, &env, &groups)).transpose()?;
        for c in &mut e.coordinates {
            c.measured = spanned_expr(ctx, &c.measured, &env, &groups)?;
        }
    }
    Ok(())
}

/// An entry that may carry a `for`.
trait Looped {
    fn over(&mut self) -> Option<For>;
}

macro_rules! looped {
    ($($t:ty),*) => {$(
        impl Looped for $t {
            fn over(&mut self) -> Option<For> {
                self.over.take()
            }
        }
    )*};
}
looped!(RawQuantity, RawPrediction, RawEquation);

/// Every entry filled once, or once for each binding of its `for`.
fn expand<T: Looped>(
    ctx: &Ctx,
    env: &Env,
    groups: &Groups,
    entries: Vec<T>,
    fill: fn(&Element, &T) -> Result<T, ScenarioError>,
) -> Result<Vec<T>, ScenarioError> {
    let mut out = Vec::new();
    for mut e in entries {
        match e.over() {
            None => out.push(fill(&Element { ctx, env, groups, tag: None }, &e)?),
            Some(over) => {
                let envs = loop_envs(ctx, env, groups, &over)?;
                if out.len() + envs.len() > MAX_PATTERN_COUNT as usize {
                    return Err(ctx.err(&over, format!("the loops make more than {MAX_PATTERN_COUNT} entries in all")));
                }
                for (inner, tag) in envs {
                    out.push(fill(&Element { ctx, env: &inner, groups, tag: Some(&tag) }, &e)?);
                }
            }
        }
    }
    Ok(out)
}

/// The environments of a `for` and each one's tag (the index or the member's name).
fn loop_envs<'a>(
    ctx: &Ctx,
    env: &Env<'a>,
    groups: &Groups,
    over: &For,
) -> Result<Vec<(Env<'a>, String)>, ScenarioError> {
    let (var, range) = match over.get_ref().iter().collect::<Vec<_>>().as_slice() {
        [(var, range)] => ((*var).clone(), (*range).clone()),
        _ => return Err(ctx.err(over, "for takes one loop variable: for = { i = \"0..n\" } or { c = \"cables\" }")),
    };
    let envs = bindings(env, &var, range.get_ref(), groups)
        .map_err(|e| expr_error(ctx, range.span().start, &e, &format!("the range of '{var}'")))?;
    Ok(envs
        .into_iter()
        .map(|e| {
            let tag = match e.vars.last() {
                Some((_, Binding::Index(v))) => v.to_string(),
                Some((_, Binding::Member(m))) => m.clone(),
                None => String::new(),
            };
            (e, tag)
        })
        .collect())
}

/// A name filled for one element: its template, or `NAME[tag]` when it has none.
fn element_name(
    ctx: &Ctx,
    name: &Spanned<String>,
    env: &Env,
    tag: Option<&str>,
) -> Result<Spanned<String>, ScenarioError> {
    let filled = spanned_name(ctx, name, env)?;
    match tag {
        Some(t) if filled.get_ref() == name.get_ref() => {
            Ok(Spanned::new(name.span(), format!("{}[{t}]", name.get_ref())))
        }
        _ => Ok(filled),
    }
}

/// A quantity's name filled for one element: its template, or `NAME_TAG` when it has none,
/// the tag's other characters as `_` (a quantity is a symbol: `strut_to_cable_strut_a3_a4`).
fn quantity_name(
    ctx: &Ctx,
    name: &Spanned<String>,
    env: &Env,
    tag: Option<&str>,
) -> Result<Spanned<String>, ScenarioError> {
    let filled = spanned_name(ctx, name, env)?;
    match tag {
        Some(t) if filled.get_ref() == name.get_ref() => {
            let t: String = t.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
            Ok(Spanned::new(name.span(), format!("{}_{t}", name.get_ref())))
        }
        _ => Ok(filled),
    }
}

/// What fills one element of a looped entry: the file, the loop's environment, the groups and
/// the element's tag (None without a loop).
struct Element<'e, 'a> {
    ctx: &'e Ctx<'e>,
    env: &'e Env<'a>,
    groups: &'e Groups,
    tag: Option<&'e str>,
}

impl Element<'_, '_> {
    fn expr(&self, s: &Spanned<String>) -> Result<Spanned<String>, ScenarioError> {
        spanned_expr(self.ctx, s, self.env, self.groups)
    }
}

fn quantity(e: &Element, q: &RawQuantity) -> Result<RawQuantity, ScenarioError> {
    Ok(RawQuantity {
        over: None,
        name: quantity_name(e.ctx, &q.name, e.env, e.tag)?,
        expr: e.expr(&q.expr)?,
        unit: q.unit.clone(),
    })
}

fn prediction(e: &Element, p: &RawPrediction) -> Result<RawPrediction, ScenarioError> {
    // A quantity written without a template is the looped quantity of the same tag.
    let quantity = quantity_name(e.ctx, &p.quantity, e.env, e.tag)?;
    let name = p.name.as_ref().map(|n| element_name(e.ctx, n, e.env, e.tag)).transpose()?;
    Ok(RawPrediction {
        over: None,
        quantity,
        name,
        formula: e.expr(&p.formula)?,
        class: p.class.clone(),
        tolerance: p.tolerance.clone(),
        rms_tolerance: p.rms_tolerance.clone(),
    })
}

fn equation(e: &Element, q: &RawEquation) -> Result<RawEquation, ScenarioError> {
    Ok(RawEquation {
        over: None,
        name: element_name(e.ctx, &q.name, e.env, e.tag)?,
        residual: e.expr(&q.residual)?,
        tolerance: q.tolerance.clone(),
    })
}

/// The groups a `for` may name: every member of a kind, and each member group's members.
fn member_groups(ctx: &Ctx, s: &RawStructure) -> Result<Groups, ScenarioError> {
    let mut groups = Groups::new();
    let lists = [(&s.struts, &s.strut_groups), (&s.springs, &s.spring_groups), (&s.cables, &s.cable_groups)];
    for (kind, (members, member_groups)) in KINDS.iter().zip(lists) {
        let mut all: Vec<String> = members.iter().map(|m| m.name.get_ref().clone()).collect();
        for g in member_groups {
            let names: Vec<String> =
                super::structure::group_members(ctx, g)?.into_iter().map(|m| m.name.into_inner()).collect();
            all.extend(names.iter().cloned());
            groups.push((g.name.get_ref().clone(), names));
        }
        groups.push((kind.to_string(), all));
    }
    Ok(groups)
}
