//! `[[structure.repeat]]`: a sub-structure written once and generated for every index of a
//! range (an n-strut prism for any n). Each copy's strings have their `{i}` templates filled
//! (`pattern.rs`), its expressions see `i`, and its nodes are placed by the copy's rotation and
//! offset when the numbers are resolved (`number.rs`). The copies are appended to the
//! structure's own lists, so everything after reads one structure.

use super::error::{Ctx, ScenarioError};
use super::number::{expr_error, Num};
use super::pattern::{bindings, spanned_name, Env, Groups, MAX_PATTERN_COUNT};
use super::raw::{
    Placement, RawActuator, RawBody, RawJoint, RawMember, RawMemberGroup, RawRepeat, RawRotate, RawStructure,
};
use std::collections::BTreeMap;
use toml::Spanned;

/// A part of the file whose strings are filled for one copy.
trait Instantiate: Sized {
    fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError>;
}

impl Instantiate for Spanned<String> {
    fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError> {
        spanned_name(ctx, self, env)
    }
}

impl Instantiate for Spanned<Num> {
    fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError> {
        match self.get_ref() {
            Num::Value(_) => Ok(self.clone()),
            Num::Expr(text) => {
                let filled = super::pattern::fill_expr(text, env, &Groups::new())
                    .map_err(|e| expr_error(ctx, self.span().start, &e, "an expression"))?;
                Ok(Spanned::new(self.span(), Num::Expr(filled)))
            }
        }
    }
}

impl<T: Instantiate> Instantiate for Option<T> {
    fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError> {
        self.as_ref().map(|v| v.instantiate(ctx, env)).transpose()
    }
}

impl<T: Instantiate> Instantiate for Vec<T> {
    fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError> {
        self.iter().map(|v| v.instantiate(ctx, env)).collect()
    }
}

impl<T: Instantiate> Instantiate for Spanned<Vec<T>> {
    fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError> {
        Ok(Spanned::new(self.span(), self.get_ref().instantiate(ctx, env)?))
    }
}

/// Implements [`Instantiate`] for a table: `fill` fields have their templates filled, `keep`
/// fields are copied.
macro_rules! instantiate_table {
    ($t:ident { $($fill:ident),* } keep { $($keep:ident),* }) => {
        impl Instantiate for $t {
            fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError> {
                Ok($t { $($fill: self.$fill.instantiate(ctx, env)?,)* $($keep: self.$keep.clone(),)* })
            }
        }
    };
}

instantiate_table!(RawMember {
    name, a, b, radius, stiffness, length, through, friction, ea, youngs_modulus, area, density, segments
} keep {});
instantiate_table!(RawMemberGroup { name, pairs, names, radius, stiffness, length } keep {});
instantiate_table!(RawJoint {
    name, kind, parent, child, at, axis, axis2, torsion_stiffness, torsion_rest, damping, initial_coordinate
} keep { placement });
instantiate_table!(RawActuator { symbol, joint, cable, node, direction } keep { placement });
instantiate_table!(RawRotate { axis, angle } keep {});

impl Instantiate for RawBody {
    fn instantiate(&self, ctx: &Ctx, env: &Env) -> Result<Self, ScenarioError> {
        let mut nodes = BTreeMap::new();
        for (name, p) in &self.nodes {
            let name = name.instantiate(ctx, env)?;
            if nodes.contains_key(&name) {
                return Err(ctx.err(&name, format!("the template gives node '{}' twice in one body", name.get_ref())));
            }
            nodes.insert(name, p.instantiate(ctx, env)?);
        }
        Ok(RawBody {
            name: self.name.instantiate(ctx, env)?,
            fixed: self.fixed,
            mass: self.mass.instantiate(ctx, env)?,
            inertia: self.inertia.instantiate(ctx, env)?,
            nodes,
            placement: self.placement.clone(),
        })
    }
}

/// Appends every `[[structure.repeat]]` copy to the structure's lists, with the parameters'
/// values of `env` (which decide the ranges).
pub(super) fn expand(ctx: &Ctx, s: &mut RawStructure, env: &Env) -> Result<(), ScenarioError> {
    let mut total = 0;
    for r in std::mem::take(&mut s.repeat) {
        let envs = copies(ctx, &r, env)?;
        total += envs.len();
        if total > MAX_PATTERN_COUNT as usize {
            return Err(ctx.err(&r.over, format!("the repeats make more than {MAX_PATTERN_COUNT} copies in all")));
        }
        for env in envs {
            add_copy(ctx, s, &r, &env)?;
        }
    }
    Ok(())
}

/// One environment per index of the repeat's range.
fn copies<'a>(ctx: &Ctx, r: &RawRepeat, env: &Env<'a>) -> Result<Vec<Env<'a>>, ScenarioError> {
    let over = r.over.get_ref();
    let (var, range) = match over.iter().collect::<Vec<_>>().as_slice() {
        [(var, range)] => (var.as_str(), *range),
        _ => return Err(ctx.err(&r.over, "for takes one loop variable and its range: for = { i = \"0..n\" }")),
    };
    bindings(env, var, range.get_ref(), &Groups::new())
        .map_err(|e| expr_error(ctx, range.span().start, &e, &format!("the range of '{var}'")))
}

/// One copy of a repeat's parts, filled with `env` and placed.
fn add_copy(ctx: &Ctx, s: &mut RawStructure, r: &RawRepeat, env: &Env) -> Result<(), ScenarioError> {
    let placement = Placement { rotate: r.rotate.instantiate(ctx, env)?, offset: r.offset.instantiate(ctx, env)? };
    let placed = (placement.rotate.is_some() || placement.offset.is_some()).then_some(placement);
    for b in &r.bodies {
        let mut b = b.instantiate(ctx, env)?;
        b.placement = placed.clone();
        s.bodies.push(b);
    }
    for j in &r.joints {
        let mut j = j.instantiate(ctx, env)?;
        j.placement = placed.clone();
        s.joints.push(j);
    }
    for a in &r.actuators {
        let mut a = a.instantiate(ctx, env)?;
        a.placement = placed.clone();
        s.actuators.push(a);
    }
    s.struts.extend(r.struts.instantiate(ctx, env)?);
    s.springs.extend(r.springs.instantiate(ctx, env)?);
    s.cables.extend(r.cables.instantiate(ctx, env)?);
    s.strut_groups.extend(r.strut_groups.instantiate(ctx, env)?);
    s.spring_groups.extend(r.spring_groups.instantiate(ctx, env)?);
    s.cable_groups.extend(r.cable_groups.instantiate(ctx, env)?);
    Ok(())
}
