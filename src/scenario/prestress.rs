//! `[prestress]`: when a structure counts as having lost its self-stress, and whether that
//! fails the run or warns. A custom structure with cables is judged without the section too
//! ([`Prestress::DEFAULT`]: it fails when every cable is slack at a settle point).
//!
//! `least_tension = "t0"` [N] prestresses a custom structure with its drawn self-stress (the
//! member forces in equilibrium at every node with no load, from the null space of the
//! equilibrium matrix: `import::self_stress`), scaled so that the least cable tension is t0:
//! each elastic cable's and spring's rest length set to its drawn length less its tension over
//! its stiffness (what the file gives as `length` is replaced). The drawn state is then an
//! equilibrium; t0 an expression of the parameters makes the prestress an axis to sweep
//! (natural frequencies against prestress).

use super::error::{finite, Ctx, ScenarioError};
use super::raw::{RawPrestress, RawScenario};
use crate::mechanisms::Values;
use crate::settings::{OnLoss, Prestress};
use crate::structure::{BodyKind, JointKind, Law, MemberKind, Structure};
use toml::Spanned;

/// The prestress judgement of a scenario: the section's, the default for a custom structure
/// with cables, or none (a built-in mechanism without the section, a structure without cables).
pub(super) fn prestress(
    ctx: &Ctx,
    raw: &Option<Spanned<RawPrestress>>,
    first: &Structure,
    custom: bool,
) -> Result<Option<Prestress>, ScenarioError> {
    let has_cables = first.members_of(MemberKind::Cable).next().is_some();
    let Some(section) = raw else {
        return Ok((custom && has_cables).then_some(Prestress::DEFAULT));
    };
    if !has_cables {
        return Err(ctx.err(section, "[prestress] judges the cables' tension, and this structure has no cables"));
    }
    let p = section.get_ref();
    let on_loss = match p.on_loss.as_ref().map(|s| (s, s.get_ref().as_str())) {
        None | Some((_, "fail")) => OnLoss::Fail,
        Some((_, "warn")) => OnLoss::Warn,
        Some((s, other)) => {
            return Err(ctx.err(s, format!("prestress.on_loss must be \"fail\" or \"warn\", got '{other}'")))
        }
    };
    let min_fraction = p.min_fraction.as_ref().map(|f| fraction(ctx, f, first)).transpose()?;
    Ok(Some(Prestress { min_fraction, on_loss }))
}

/// `min_fraction`: in (0, 1], of a drawn self-stress that is not zero.
fn fraction(ctx: &Ctx, f: &Spanned<f64>, first: &Structure) -> Result<f64, ScenarioError> {
    let x = finite(ctx, f, "prestress.min_fraction")?;
    if !(x > 0.0 && x <= 1.0) {
        return Err(ctx.err(f, format!("prestress.min_fraction must lie in (0, 1], got {x}")));
    }
    let drawn = first.drawn_cable_tension_n();
    if drawn.is_nan() || drawn <= 0.0 {
        return Err(ctx.err(
            f,
            "prestress.min_fraction is a share of the cables' tension at the drawn state, and they carry none \
             there (no elastic cable is drawn longer than its rest length)",
        ));
    }
    Ok(x)
}

/// `[prestress] least_tension`: `s`'s elastic cables and springs given the rest lengths of its
/// drawn self-stress with that least tension (module docs), at the parameters `params`. An error
/// where the drawing has no self-stress that keeps every cable and spring in tension, or where a
/// tension leaves a member no rest length.
pub(super) fn set_self_stress(
    ctx: &Ctx,
    raw: &RawScenario,
    s: &mut Structure,
    params: &Values,
) -> Result<(), ScenarioError> {
    let Some(t) = raw.prestress.as_ref().and_then(|p| p.get_ref().least_tension.as_ref()) else { return Ok(()) };
    let least_n = super::number::evaluate(ctx, t, params, "prestress.least_tension")?;
    if !(least_n.is_finite() && least_n > 0.0) {
        return Err(ctx.err(t, format!("prestress.least_tension is {least_n} N: a tension is finite and > 0")));
    }
    let on_strut = |n: usize| s.members_of(MemberKind::Strut).any(|(_, m)| m.path.contains(&n));
    // A node is held where it lies on a fixed body (and on no strut, whose force the balance
    // there reads), or where a joint pins it to a fixed body: the joint's reaction holds it
    // (F4 of issue 60: a strut pinned at its foot had counted as free there, and the drawing
    // had seemed to have no self-stress).
    let fixed = |b: usize| s.bodies[b].kind == BodyKind::Fixed;
    let at_anchor = |j: &crate::structure::Joint, n: usize| {
        j.anchor == n || (j.child == s.nodes[n].body && s.nodes[j.anchor].position == s.nodes[n].position)
    };
    let pinned = |n: usize| {
        s.joints.iter().any(|j| fixed(j.parent) && at_anchor(j, n) && !matches!(j.kind, JointKind::Prismatic { .. }))
    };
    // A support in some directions holds those of its node's coordinates.
    let held = s.held_translations();
    let anchored: Vec<[bool; 3]> = (0..s.nodes.len())
        .map(|n| {
            let whole = (fixed(s.nodes[n].body) && !on_strut(n)) || pinned(n);
            [0, 1, 2].map(|k| whole || held[s.nodes[n].body][k])
        })
        .collect();
    let positions: Vec<_> = s.nodes.iter().map(|n| n.position).collect();
    // Cables first, then springs: the order of `self_stress_of`'s tensions.
    let tensioned: Vec<usize> = [MemberKind::Cable, MemberKind::Spring]
        .into_iter()
        .flat_map(|k| s.members_of(k).map(|(i, _)| i).collect::<Vec<_>>())
        .collect();
    let tension: Vec<&[usize]> = tensioned.iter().map(|&i| &s.members[i].path[..]).collect();
    let struts: Vec<&[usize]> = s.members_of(MemberKind::Strut).map(|(_, m)| &m.path[..]).collect();
    let stress = crate::import::self_stress::self_stress_of(&positions, &anchored, &tension, &struts).ok_or_else(|| {
        ctx.err(t, "prestress.least_tension: the drawn structure has no self-stress that keeps every cable and spring in tension (no load-free equilibrium of its members: check the drawing)")
    })?;
    for (&i, share) in tensioned.iter().zip(&stress) {
        let m = &mut s.members[i];
        let drawn = m.length_at(|n| positions[n]);
        let Some(stiffness_n_per_m) = m.stiffness_n_per_m() else { continue };
        let rest = rest_length(ctx, t, &m.name, least_n * share, stiffness_n_per_m, drawn)?;
        match &mut m.law {
            Law::Cable { length_m, .. } => *length_m = rest,
            Law::Spring { rest_length_m, .. } => *rest_length_m = rest,
            Law::Strut | Law::ElasticStrut { .. } => {}
        }
    }
    Ok(())
}

/// The rest length [m] that gives a member drawn `drawn_m` long `tension_n` [N]: positive.
fn rest_length(
    ctx: &Ctx,
    at: &toml::Spanned<super::number::Num>,
    name: &str,
    tension_n: f64,
    stiffness_n_per_m: f64,
    drawn_m: f64,
) -> Result<f64, ScenarioError> {
    if let Some(rest) = crate::import::self_stress::rest_length_for(tension_n, stiffness_n_per_m, drawn_m) {
        return Ok(rest);
    }
    let rest = drawn_m - tension_n / stiffness_n_per_m;
    Err(ctx.err(
        at,
        format!(
            "prestress.least_tension: member '{name}' would carry {tension_n:.6} N at stiffness {stiffness_n_per_m} N/m, more than its drawn length {drawn_m:.6} m allows (its rest length {rest:.6} m): a smaller tension or a stiffer member"
        ),
    ))
}
