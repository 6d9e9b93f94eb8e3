//! `[structure]`: the bodies, members, joints and actuators of a `mechanism = "custom"` file,
//! built into a [`Structure`].

use super::error::{finite, positive_value, Ctx, ScenarioError};
use super::number::Num;
use super::raw::RawMemberGroup;
use super::raw::{RawActuator, RawBody, RawJoint, RawMember, RawStructure, Xyz};
use crate::structure::{
    Actuator, ActuatorTarget, BodyKind, CableLaw, Inertia, Joint, JointKind, Member, MemberKind, Structure,
    TorsionSpring, DEFAULT_TENDON_RADIUS_M,
};
use std::collections::{HashMap, HashSet};
use toml::Spanned;

/// Smallest size used for a body's default inertia [m].
const MIN_BODY_SIZE_M: f64 = 1e-3;

/// Strut radius when the file gives none [m].
const DEFAULT_STRUT_RADIUS_M: f64 = 0.01;

/// Builds the structure of a `[structure]` table; every bad reference, zero-length member or
/// massless free body is an error at its place in the file.
pub(super) fn structure_from_file(ctx: &Ctx, raw: &Spanned<RawStructure>) -> Result<Structure, ScenarioError> {
    let r = raw.get_ref();
    let mut s = Structure { name: "custom".into(), ..Default::default() };
    if let Some(g) = &r.gravity {
        s.gravity = xyz(ctx, g, "gravity")?;
    }
    if r.bodies.is_empty() {
        return Err(ctx.err(raw, "[structure] needs at least one body ([[structure.bodies]])"));
    }
    let mut body_names: HashSet<&str> = HashSet::new();
    let mut node_names: HashSet<&str> = HashSet::new();
    for b in &r.bodies {
        if !body_names.insert(b.name.get_ref()) {
            return Err(ctx.err(&b.name, format!("duplicate body name '{}'", b.name.get_ref())));
        }
        add_body(ctx, &mut s, b, &r.struts, &mut node_names)?;
    }
    // Names of members, joints and actuator symbols: unique, checked with every other name
    // of the file (`names.rs`).
    // Each part refers only to the parts built before it.
    let struts = r.struts.iter().map(|m| strut(ctx, &s, m)).collect::<Result<Vec<_>, _>>()?;
    let springs = r.springs.iter().map(|m| spring(ctx, &s, m)).collect::<Result<Vec<_>, _>>()?;
    let cables = r.cables.iter().map(|m| cable(ctx, &s, m)).collect::<Result<Vec<_>, _>>()?;
    s.members = [struts, springs, cables].concat();
    add_member_groups(ctx, &mut s, r)?;
    s.joints = r.joints.iter().map(|j| joint(ctx, &s, j)).collect::<Result<_, _>>()?;
    s.actuators = r.actuators.iter().map(|a| actuator(ctx, &s, a)).collect::<Result<_, _>>()?;
    s.node_loads = r.loads.iter().map(|l| node_load(ctx, &s, l)).collect::<Result<_, _>>()?;
    s.validate().map_err(|e| structure_error_at(ctx, raw, e))?;
    lump_members(ctx, &mut s, r)?;
    for n in &r.masses {
        add_node_mass(ctx, &mut s, n)?;
    }
    let (points, mut supported) = (crate::structure::lumped::point_masses(&s), vec![false; s.nodes.len()]);
    for support in &r.supports {
        let support = node_support(ctx, &s, support, &points, &mut supported)?;
        s.supports.push(support);
    }
    Ok(s)
}

/// Builds the elastic struts (`EA`, or `E` with `area`), then the heavy cables (`density`
/// with `segments`), of point masses (`structure/lumped.rs`); a key that a member's kind
/// cannot take is an error at the key.
fn lump_members(ctx: &Ctx, s: &mut Structure, r: &RawStructure) -> Result<(), ScenarioError> {
    let mut lumping = crate::structure::lumped::Lumping::new(s);
    for m in r.springs.iter() {
        refuse_keys(ctx, m, "spring", &[("density", &m.density), ("segments", &m.segments)])?;
    }
    for (i, m) in r.struts.iter().enumerate() {
        refuse_keys(ctx, m, "strut", &[("segments", &m.segments)])?;
        if let Some(k) = &m.stiffness {
            return Err(ctx.err(k, "a strut's stiffness is EA / L: give EA (N), or E (Pa) with area (m^2)"));
        }
        if let Some(d) = &m.density {
            strut_density_builds(ctx, s, m, d)?;
        }
        let rest = match &m.length {
            Some(l) => Some((l, positive_value(ctx, l, "length (m)")?)),
            None => None,
        };
        match (axial_stiffness(ctx, m)?, rest) {
            (Some((at, ea)), rest) => {
                crate::structure::lumped::make_strut_elastic(s, i, ea, rest.map(|r| r.1), &mut lumping)
                    .map_err(|e| ctx.err(at, e.to_string()))?
            }
            (None, Some((at, _))) => return Err(ctx.err(
                at,
                "a rigid strut keeps its drawn length: length is an elastic strut's rest length (give EA, or E with area, to prestress the bar)",
            )),
            (None, None) => {}
        }
    }
    let first_cable = r.struts.len() + r.springs.len();
    for (j, m) in r.cables.iter().enumerate() {
        refuse_keys(ctx, m, "cable", &[("EA", &m.ea), ("E", &m.youngs_modulus), ("area", &m.area)])?;
        match (&m.density, &m.segments) {
            (None, None) => {}
            (None, Some(n)) => {
                return Err(ctx.err(n, "segments means nothing without density: a heavy cable's mass per metre (kg/m)"))
            }
            (Some(d), None) => {
                return Err(ctx.err(
                    d,
                    format!(
                    "a heavy cable needs segments: how many elastic segments between beads it is built of (1 to {})",
                    crate::structure::lumped::MAX_CABLE_SEGMENTS
                ),
                ))
            }
            (Some(d), Some(n)) => {
                let density = positive_value(ctx, d, "density (kg/m)")?;
                let count = segment_count(ctx, n)?;
                crate::structure::lumped::hang_beads(s, first_cable + j, density, count, &mut lumping)
                    .map_err(|e| ctx.err(d, e.to_string()))?;
            }
        }
    }
    Ok(())
}

/// A strut's `density` gives its body its mass ([`body_mass`]): the body must be free and
/// carry the strut's two nodes alone; otherwise an error at the key.
fn strut_density_builds(ctx: &Ctx, s: &Structure, m: &RawMember, d: &Spanned<Num>) -> Result<(), ScenarioError> {
    let (a, b) = (node(ctx, s, &m.a)?, node(ctx, s, &m.b)?);
    let body = s.nodes[a].body;
    let nodes = s.nodes.iter().filter(|n| n.body == body).count();
    let why = if s.nodes[b].body != body {
        "its nodes are on two bodies"
    } else if s.bodies[body].kind == BodyKind::Fixed {
        "its body is fixed"
    } else if nodes != 2 {
        "its body carries other nodes (state the body's mass)"
    } else {
        return Ok(());
    };
    Err(ctx.err(
        d,
        format!(
            "strut '{}': density gives the strut's own body the mass density x length, and {why}",
            m.name.get_ref()
        ),
    ))
}

/// `keys` given on a member of kind `what`, which cannot take them: an error at the first.
fn refuse_keys(
    ctx: &Ctx,
    m: &RawMember,
    what: &str,
    keys: &[(&str, &Option<Spanned<Num>>)],
) -> Result<(), ScenarioError> {
    let Some((key, v)) = keys.iter().find_map(|(k, v)| v.as_ref().map(|v| (k, v))) else { return Ok(()) };
    let meaning = match *key {
        "EA" | "E" | "area" => "a strut's axial stiffness",
        "density" => "a strut's or a heavy cable's mass",
        _ => "a heavy cable's count of segments",
    };
    Err(ctx.err(v, format!("{key}: {} '{}' is a {what}; {key} states {meaning}", what, m.name.get_ref())))
}

/// A strut's axial stiffness E A [N] from `EA`, or from `E` [Pa] and `area` [m^2], with the key
/// it is read at; None for a rigid strut.
fn axial_stiffness<'a>(ctx: &Ctx, m: &'a RawMember) -> Result<Option<(&'a Spanned<Num>, f64)>, ScenarioError> {
    match (&m.ea, &m.youngs_modulus, &m.area) {
        (None, None, None) => Ok(None),
        (Some(ea), None, None) => Ok(Some((ea, positive_value(ctx, ea, "EA (N)")?))),
        (Some(_), Some(e), _) => Err(ctx.err(e, "E: the member states EA already (give EA, or E with area)")),
        (Some(_), None, Some(a)) => Err(ctx.err(a, "area: the member states EA already (give EA, or E with area)")),
        (None, Some(e), Some(a)) => {
            let ea = positive_value(ctx, e, "E (Pa)")? * positive_value(ctx, a, "area (m^2)")?;
            if !ea.is_finite() {
                return Err(ctx.err(e, format!("E times area is {ea} N: not finite")));
            }
            Ok(Some((e, ea)))
        }
        (None, Some(e), None) => Err(ctx.err(e, "E needs area, the strut's cross-section (m^2)")),
        (None, None, Some(a)) => Err(ctx.err(a, "area needs E, Young's modulus (Pa), or give EA (N)")),
    }
}

/// A heavy cable's segment count: a whole number from 1 to the bound.
fn segment_count(ctx: &Ctx, n: &Spanned<Num>) -> Result<usize, ScenarioError> {
    let x = finite(ctx, n, "segments")?;
    let max = crate::structure::lumped::MAX_CABLE_SEGMENTS;
    if x.fract() != 0.0 || !(1.0..=max as f64).contains(&x) {
        return Err(ctx.err(n, format!("segments must be a whole number from 1 to {max}, got {x}")));
    }
    Ok(x as usize)
}

/// A structure error at the entry it names (a joint, a member, an actuator or a body), else at
/// the `[structure]` table.
fn structure_error_at(ctx: &Ctx, raw: &Spanned<RawStructure>, e: crate::structure::StructureError) -> ScenarioError {
    use crate::structure::StructureError as E;
    let r = raw.get_ref();
    let (what, name) = match &e {
        E::Invalid { what, name, .. } | E::ZeroLength { what, name } | E::DanglingReference { what, name, .. } => {
            (*what, name.as_str())
        }
        E::NoMass(name) | E::Duplicate(name) => ("body", name.as_str()),
    };
    let members = |list: &[RawMember]| list.iter().find(|m| m.name.get_ref() == name).map(|m| m.name.span());
    let span = match what {
        "joint" => r.joints.iter().find(|j| j.name.get_ref() == name).map(|j| j.name.span()),
        "strut" => members(&r.struts),
        "spring" => members(&r.springs),
        "cable" => members(&r.cables),
        "actuator" => r.actuators.iter().find(|a| a.symbol.get_ref() == name).map(|a| a.symbol.span()),
        _ => r.bodies.iter().find(|b| b.name.get_ref() == name).map(|b| b.name.span()),
    };
    let message = format!("the structure is not valid: {e}");
    match span {
        Some(sp) => ctx.err_at(sp.start, message),
        None => ctx.err(raw, message),
    }
}

/// Three finite numbers (the parameters' expressions already evaluated).
fn xyz(ctx: &Ctx, v: &Xyz, what: &str) -> Result<[f64; 3], ScenarioError> {
    let a: Vec<f64> = v.get_ref().iter().map(|c| c.get_ref().value()).collect();
    match a.as_slice() {
        &[x, y, z] if [x, y, z].iter().all(|c| c.is_finite() && c.abs() <= MAX_COORDINATE_M) => Ok([x, y, z]),
        a => Err(ctx.err(
            v,
            format!("{what} must be three finite numbers of magnitude at most {MAX_COORDINATE_M:e}, got {a:?}"),
        )),
    }
}

/// Largest magnitude of a coordinate, gravity or inertia component the file may give: beyond
/// it products of two such numbers leave f64's range for the simulation's sums of squares.
const MAX_COORDINATE_M: f64 = 1e6;

/// Adds a body (at least one node, a mass if free) and its nodes (names unique in the
/// structure) to `s`.
/// A body and its nodes; `node_names` holds every node name declared so far (a set: a file of
/// many nodes is checked in time linear in them).
fn add_body<'r>(
    ctx: &Ctx,
    s: &mut Structure,
    b: &'r RawBody,
    struts: &[RawMember],
    node_names: &mut HashSet<&'r str>,
) -> Result<(), ScenarioError> {
    if b.nodes.is_empty() {
        return Err(ctx.err(
            &b.name,
            format!("body '{}' needs at least one node (nodes = {{ N1 = [x, y, z] }})", b.name.get_ref()),
        ));
    }
    let mut pts = Vec::new();
    for (n, p) in &b.nodes {
        pts.push((n, xyz(ctx, p, "a node's coordinates")?));
    }
    let fixed = b.fixed.unwrap_or(false);
    let inertia = if fixed {
        None
    } else {
        let points: Vec<[f64; 3]> = pts.iter().map(|(_, p)| *p).collect();
        Some(inertia(ctx, b, &points, struts)?)
    };
    let id = s.add_body(b.name.get_ref(), if fixed { BodyKind::Fixed } else { BodyKind::Free }, inertia);
    for (n, p) in pts {
        if !node_names.insert(n.get_ref()) {
            return Err(ctx.err(n, format!("duplicate node name '{}'", n.get_ref())));
        }
        s.add_node(n.get_ref(), id, p);
    }
    Ok(())
}

/// The strut of `struts` that states a `density` and whose two nodes are on body `b`.
fn strut_with_density<'a>(b: &RawBody, struts: &'a [RawMember]) -> Option<(&'a RawMember, &'a Spanned<Num>)> {
    let holds = |n: &Spanned<String>| b.nodes.keys().any(|k| k.get_ref() == n.get_ref());
    let m = struts.iter().find(|m| m.density.is_some() && holds(&m.a) && holds(&m.b))?;
    Some((m, m.density.as_ref()?))
}

/// The mass of free body `b` with nodes at `pts` \[kg\]: its `mass`, or a strut's `density`
/// times its drawn length where the body is that strut's alone; and where the number stands.
fn body_mass<'a>(
    ctx: &Ctx,
    b: &'a RawBody,
    pts: &[[f64; 3]],
    struts: &'a [RawMember],
) -> Result<(f64, &'a Spanned<Num>), ScenarioError> {
    match (&b.mass, strut_with_density(b, struts)) {
        (_, Some((strut, d))) if b.nodes.len() != 2 => Err(ctx.err(
            d,
            format!(
                "strut '{}': density gives the strut's own body the mass density x length, and its body carries other nodes (state the body's mass)",
                strut.name.get_ref()
            ),
        )),
        (Some(m), None) => Ok((finite(ctx, m, "mass")?, m)),
        (None, Some((_, d))) => {
            let rho = positive_value(ctx, d, "a strut's density (kg per m)")?;
            Ok((rho * crate::structure::distance(pts[0], pts[1]), d))
        }
        (Some(_), Some((strut, d))) => Err(ctx.err(
            d,
            format!(
                "strut '{}' states its density, which gives its body '{}' the mass density x length, and the body states its mass: state one",
                strut.name.get_ref(),
                b.name.get_ref()
            ),
        )),
        (None, None) => Err(ctx.err(
            &b.name,
            format!(
                "free body '{}' needs a mass > 0 kg (mass = ..., or its strut's density = ... kg/m), or fixed = true",
                b.name.get_ref()
            ),
        )),
    }
}

/// The inertia of a free body with nodes at `pts`: its mass > 0 kg ([`body_mass`]), the
/// centre of mass at the nodes' mean, the principal moments as given (each > 0) or isotropic
/// from the body's size (a strut's body: m L^2 / 12, a thin bar's about its middle).
fn inertia(ctx: &Ctx, b: &RawBody, pts: &[[f64; 3]], struts: &[RawMember]) -> Result<Inertia, ScenarioError> {
    let (mass, m) = body_mass(ctx, b, pts, struts)?;
    let (lo, hi) = super::physical::BODY_MASS_KG;
    if !(lo..=hi).contains(&mass) {
        return Err(
            ctx.err(m, format!("mass must lie in [{lo:e}, {hi:e}] kg (what the simulation handles), got {mass}"))
        );
    }
    let n = pts.len() as f64;
    let com = [0, 1, 2].map(|k| pts.iter().map(|p| p[k]).sum::<f64>() / n);
    let size = pts
        .iter()
        .flat_map(|a| pts.iter().map(move |b| crate::structure::distance(*a, *b)))
        .fold(MIN_BODY_SIZE_M, f64::max);
    let principal = match &b.inertia {
        Some(i) => {
            let v = xyz(ctx, i, "inertia")?;
            if v.iter().any(|x| *x <= 0.0) {
                return Err(ctx.err(i, "inertia must be three moments > 0 kg m^2"));
            }
            v
        }
        None => [mass * size * size / 12.0; 3],
    };
    Ok(Inertia { mass_kg: mass, com, principal_kg_m2: principal })
}

/// A point load: a finite force at a node of a free body (on a fixed body the support would
/// take it whole, so it is refused there).
fn node_load(ctx: &Ctx, s: &Structure, l: &super::raw::RawLoad) -> Result<crate::structure::NodeLoad, ScenarioError> {
    let n = node(ctx, s, &l.node)?;
    let body = &s.bodies[s.nodes[n].body];
    if body.kind == BodyKind::Fixed {
        return Err(ctx.err(
            &l.node,
            format!(
                "node '{}' is on fixed body '{}': its support would take the load whole",
                l.node.get_ref(),
                body.name
            ),
        ));
    }
    Ok(crate::structure::NodeLoad { node: n, force_n: xyz(ctx, &l.force, "a load's force")? })
}

/// Adds a node's mass to its body, which must be a point mass (its moments grow with it, as
/// a heavy cable's end does); on a rigid body the mass would move its centre and tilt its
/// principal axes, so it is refused there.
fn add_node_mass(ctx: &Ctx, s: &mut Structure, n: &super::raw::RawNodeMass) -> Result<(), ScenarioError> {
    let node = node(ctx, s, &n.node)?;
    let mass = positive_value(ctx, &n.mass, "a node's mass (kg)")?;
    let body = s.nodes[node].body;
    if !crate::structure::lumped::is_point_mass(s, body) {
        return Err(ctx.err(
            &n.node,
            format!(
                "node '{}' is on body '{}', which is not a point mass (a one-node free body, an elastic strut's end): add the mass to that body's mass",
                n.node.get_ref(),
                s.bodies[body].name
            ),
        ));
    }
    let inertia = s.bodies[body].inertia.as_mut().expect("a point mass is free");
    let grown = (inertia.mass_kg + mass) / inertia.mass_kg;
    inertia.mass_kg += mass;
    inertia.principal_kg_m2 = inertia.principal_kg_m2.map(|m| m * grown);
    Ok(())
}

/// A support in some directions: at a node of a point mass (a rigid body's node would need
/// its turns held too), each of x, y and z named at most once, one support per node
/// (`points`: which bodies are point masses; `supported`: the nodes that have one so far).
fn node_support(
    ctx: &Ctx,
    s: &Structure,
    r: &super::raw::RawSupport,
    points: &[bool],
    supported: &mut [bool],
) -> Result<crate::structure::NodeSupport, ScenarioError> {
    let node = node(ctx, s, &r.node)?;
    let body = s.nodes[node].body;
    if !points[body] {
        let why = if s.bodies[body].kind == BodyKind::Fixed {
            "is fixed: it is held in every direction already"
        } else {
            "is not a point mass (a one-node free body, an elastic strut's end): a support in some directions holds a node's translations, and a rigid body's node would turn about it"
        };
        return Err(
            ctx.err(&r.node, format!("node '{}' is on body '{}', which {why}", r.node.get_ref(), s.bodies[body].name))
        );
    }
    if std::mem::replace(&mut supported[node], true) {
        return Err(ctx.err(&r.node, format!("node '{}' has a support already", r.node.get_ref())));
    }
    let mut held = [false; 3];
    for axis in r.fixed.get_ref() {
        let Some(i) = ["x", "y", "z"].iter().position(|a| a == axis) else {
            return Err(ctx.err(&r.fixed, format!("'{axis}' is not a direction: fixed lists \"x\", \"y\" and \"z\"")));
        };
        if std::mem::replace(&mut held[i], true) {
            return Err(ctx.err(&r.fixed, format!("'{axis}' is listed twice")));
        }
    }
    if !held.contains(&true) {
        return Err(
            ctx.err(&r.fixed, "fixed lists no direction: name at least one of \"x\", \"y\" and \"z\"".to_string())
        );
    }
    Ok(crate::structure::NodeSupport { node, held })
}

/// The id of a declared node.
fn node(ctx: &Ctx, s: &Structure, n: &Spanned<String>) -> Result<usize, ScenarioError> {
    s.node_id(n.get_ref()).ok_or_else(|| unknown_node(ctx, n))
}

/// The error of a node name no body declares.
fn unknown_node(ctx: &Ctx, n: &Spanned<String>) -> ScenarioError {
    ctx.err(n, format!("unknown node '{}' (nodes are declared in the bodies' nodes tables)", n.get_ref()))
}

/// The id of a declared body.
fn body(ctx: &Ctx, s: &Structure, n: &Spanned<String>) -> Result<usize, ScenarioError> {
    s.body_id(n.get_ref()).ok_or_else(|| ctx.err(n, format!("unknown body '{}'", n.get_ref())))
}

/// A member's two nodes and the distance between them (> 0); `through` is a cable's alone.
fn ends(ctx: &Ctx, s: &Structure, m: &RawMember, what: &str) -> Result<(usize, usize, f64), ScenarioError> {
    if let Some(t) = &m.through {
        return Err(ctx.err(
            t,
            format!("through: only a cable runs through inner nodes, and '{}' is a {what}", m.name.get_ref()),
        ));
    }
    if let Some(f) = &m.friction {
        let message =
            format!("friction: only a cable has friction at inner nodes, and '{}' is a {what}", m.name.get_ref());
        return Err(ctx.err(f, message));
    }
    let (a, b) = (node(ctx, s, &m.a)?, node(ctx, s, &m.b)?);
    let l = crate::structure::distance(s.nodes[a].position, s.nodes[b].position);
    if l <= 0.0 {
        return Err(ctx.err(&m.name, format!("{what} '{}' has zero length: its nodes coincide", m.name.get_ref())));
    }
    Ok((a, b, l))
}

/// A strut, with its radius > 0 (default [`DEFAULT_STRUT_RADIUS_M`]).
fn strut(ctx: &Ctx, s: &Structure, m: &RawMember) -> Result<Member, ScenarioError> {
    let (a, b, _) = ends(ctx, s, m, "strut")?;
    let radius = match &m.radius {
        Some(v) => positive_value(ctx, v, "radius (m)")?,
        None => DEFAULT_STRUT_RADIUS_M,
    };
    Ok(Member::strut(m.name.get_ref().clone(), a, b, radius))
}

/// A spring: its stiffness > 0, or a bar's axial stiffness `EA` (or `E` with `area`) over its
/// free length (one of the two required), and free length >= 0 (default: the initial
/// distance).
fn spring(ctx: &Ctx, s: &Structure, m: &RawMember) -> Result<Member, ScenarioError> {
    let (a, b, l) = ends(ctx, s, m, "spring")?;
    let rest = spring_rest_length(ctx, m, l)?;
    let stiffness = match (&m.stiffness, axial_stiffness(ctx, m)?) {
        (Some(k), None) => positive_value(ctx, k, "stiffness (N/m)")?,
        (None, Some((_, ea))) if rest > 0.0 => ea / rest,
        (None, Some((at, _))) => return Err(ctx.err(at, "EA / L0 needs a free length L0 > 0")),
        (Some(_), Some((at, _))) => {
            return Err(
                ctx.err(at, "the spring states its stiffness already (give stiffness, or EA for a bar's EA / L0)")
            )
        }
        (None, None) => return Err(ctx.err(&m.name, "a spring needs a stiffness (N/m), or a bar's EA (N) for EA / L0")),
    };
    Ok(Member::spring(m.name.get_ref().clone(), [a, b], stiffness, rest, tendon_radius(ctx, m)?))
}

/// A spring's free length: `length` (>= 0), or the drawn distance `drawn_m`.
fn spring_rest_length(ctx: &Ctx, m: &RawMember, drawn_m: f64) -> Result<f64, ScenarioError> {
    Ok(match &m.length {
        Some(v) => {
            let x = finite(ctx, v, "length (m)")?;
            if x < 0.0 {
                return Err(ctx.err(v, format!("a spring's free length must be >= 0 m, got {x}")));
            }
            x
        }
        None => drawn_m,
    })
}

/// A cable: elastic with a stiffness > 0, else inextensible; its length > 0 (default: the
/// initial distance).
fn cable(ctx: &Ctx, s: &Structure, m: &RawMember) -> Result<Member, ScenarioError> {
    let (path, l) = cable_path(ctx, s, m)?;
    let law = match &m.stiffness {
        Some(k) => CableLaw::Elastic { stiffness_n_per_m: positive_value(ctx, k, "stiffness (N/m)")? },
        None => CableLaw::Inextensible,
    };
    let length = match &m.length {
        Some(v) => positive_value(ctx, v, "length (m)")?,
        None => l,
    };
    let friction = cable_friction(ctx, m, path.len() - 2)?;
    Ok(Member::cable(m.name.get_ref().clone(), path, law, length, tendon_radius(ctx, m)?).with_friction(friction))
}

/// `friction`: one finite coefficient >= 0 per inner node of the cable (`inner` of them).
fn cable_friction(ctx: &Ctx, m: &RawMember, inner: usize) -> Result<Vec<f64>, ScenarioError> {
    let Some(f) = &m.friction else { return Ok(Vec::new()) };
    let name = m.name.get_ref();
    if f.get_ref().len() != inner {
        let message = format!("friction: cable '{name}' runs through {inner} inner node(s) and friction gives {} coefficient(s): one per node of `through`", f.get_ref().len());
        return Err(ctx.err(f, message));
    }
    let mut out = Vec::new();
    for mu in f.get_ref() {
        let x = finite(ctx, mu, "a friction coefficient")?;
        if x < 0.0 {
            return Err(ctx.err(mu, format!("a friction coefficient must be >= 0, got {x}")));
        }
        out.push(x);
    }
    Ok(out)
}

/// A cable's path, `a`, the nodes it runs `through`, then `b`, and its drawn length: each
/// segment longer than zero (no node twice in a row; a ring may end where it starts).
fn cable_path(ctx: &Ctx, s: &Structure, m: &RawMember) -> Result<(Vec<usize>, f64), ScenarioError> {
    let name = m.name.get_ref();
    let inner = m.through.as_ref().map_or(&[][..], |t| &t.get_ref()[..]);
    if let (Some(t), true) = (&m.through, inner.is_empty()) {
        return Err(
            ctx.err(t, format!("through: cable '{name}' names no inner node (leave the key out for a straight cable)"))
        );
    }
    let spanned: Vec<&Spanned<String>> = std::iter::once(&m.a).chain(inner).chain([&m.b]).collect();
    // One index of the node names for the whole path: a lookup per node would scan every node,
    // and a cable over many pulleys would take time in the square of its nodes.
    let mut ids: HashMap<&str, usize> = HashMap::with_capacity(s.nodes.len());
    for (k, n) in s.nodes.iter().enumerate() {
        ids.entry(n.name.as_str()).or_insert(k);
    }
    let path = spanned
        .iter()
        .map(|n| ids.get(n.get_ref().as_str()).copied().ok_or_else(|| unknown_node(ctx, n)))
        .collect::<Result<Vec<_>, _>>()?;
    let mut length = 0.0;
    for (k, w) in path.windows(2).enumerate() {
        let segment = crate::structure::distance(s.nodes[w[0]].position, s.nodes[w[1]].position);
        if w[0] == w[1] && !inner.is_empty() {
            let message = format!("cable '{name}' runs through node '{}' twice in a row", spanned[k + 1].get_ref());
            return Err(ctx.err(spanned[k + 1], message));
        }
        if segment <= 0.0 {
            let what = if inner.is_empty() { "zero length" } else { "a segment of zero length" };
            return Err(ctx.err(&m.name, format!("cable '{name}' has {what}: its nodes coincide")));
        }
        length += segment;
    }
    if !inner.is_empty() && m.stiffness.is_none() {
        return Err(ctx.err(&m.name, format!("cable '{name}' is clustered (through): it needs a stiffness (N/m); an inextensible clustered cable is not modelled")));
    }
    Ok((path, length))
}

/// A cable's or spring's radius > 0 (default [`DEFAULT_TENDON_RADIUS_M`]), for interference.
fn tendon_radius(ctx: &Ctx, m: &RawMember) -> Result<f64, ScenarioError> {
    match &m.radius {
        Some(v) => positive_value(ctx, v, "radius (m)"),
        None => Ok(DEFAULT_TENDON_RADIUS_M),
    }
}

/// A joint between two declared bodies at a declared node, with its optional torsion spring
/// (revolute joints) and damping >= 0.
fn joint(ctx: &Ctx, s: &Structure, j: &RawJoint) -> Result<Joint, ScenarioError> {
    let kind = joint_kind(ctx, j)?;
    meaningful_keys(ctx, j, &kind)?;
    let (parent, child, at) = (body(ctx, s, &j.parent)?, body(ctx, s, &j.child)?, node(ctx, s, &j.at)?);
    let torsion_spring = match &j.torsion_stiffness {
        Some(k) => Some(TorsionSpring {
            stiffness_nm_per_rad: positive_value(ctx, k, "torsion_stiffness (N m/rad)")?,
            rest_angle_rad: match &j.torsion_rest {
                Some(v) => finite(ctx, v, "torsion_rest")?,
                None => 0.0,
            },
        }),
        None => None,
    };
    let damping = match &j.damping {
        Some(v) => {
            let x = finite(ctx, v, "damping")?;
            if x < 0.0 {
                return Err(ctx.err(v, format!("damping must be >= 0, got {x}")));
            }
            x
        }
        None => 0.0,
    };
    Ok(Joint {
        name: j.name.get_ref().clone(),
        kind,
        parent,
        child,
        anchor: at,
        initial_coordinate: match &j.initial_coordinate {
            Some(v) => finite(ctx, v, "initial_coordinate")?,
            None => 0.0,
        },
        torsion_spring,
        damping,
    })
}

/// Keys of a joint that mean nothing with its other keys are refused, naming both: an axis its
/// kind has not (`axis2` on a planar pin), a rest angle of no torsion spring.
fn meaningful_keys(ctx: &Ctx, j: &RawJoint, kind: &JointKind) -> Result<(), ScenarioError> {
    let k = j.kind.get_ref();
    if let Some(a2) = j.axis2.as_ref().filter(|_| !matches!(kind, JointKind::Universal { .. })) {
        return Err(ctx.err(
            a2,
            format!("axis2 means nothing on a {k} joint (kind = \"{k}\"): only a universal joint has a second axis"),
        ));
    }
    if let Some(a) = j.axis.as_ref().filter(|_| matches!(kind, JointKind::Spherical | JointKind::Fixed)) {
        return Err(ctx.err(a, format!("axis means nothing on a {k} joint (kind = \"{k}\"): it has no axis")));
    }
    if let (Some(rest), None) = (&j.torsion_rest, &j.torsion_stiffness) {
        return Err(ctx.err(
            rest,
            "torsion_rest means nothing without torsion_stiffness: it is the rest angle of that torsion spring",
        ));
    }
    Ok(())
}

/// A joint's kind, with the axes it needs.
fn joint_kind(ctx: &Ctx, j: &RawJoint) -> Result<JointKind, ScenarioError> {
    Ok(match j.kind.get_ref().as_str() {
        "revolute" => JointKind::Revolute { axis: axis(ctx, j, &j.axis, "axis")? },
        "prismatic" => JointKind::Prismatic { axis: axis(ctx, j, &j.axis, "axis")? },
        "spherical" => JointKind::Spherical,
        "universal" => {
            JointKind::Universal { axis1: axis(ctx, j, &j.axis, "axis")?, axis2: axis(ctx, j, &j.axis2, "axis2")? }
        }
        "fixed" => JointKind::Fixed,
        "planar_pin" => JointKind::PlanarPin { axis: axis(ctx, j, &j.axis, "axis")? },
        other => {
            return Err(ctx.err(
                &j.kind,
                format!("unknown joint kind '{other}' (expected revolute, prismatic, spherical, universal, fixed or planar_pin)"),
            ))
        }
    })
}

/// A joint's axis `what`: required by its kind, three finite numbers, not zero.
fn axis(ctx: &Ctx, j: &RawJoint, v: &Option<Xyz>, what: &str) -> Result<[f64; 3], ScenarioError> {
    let v =
        v.as_ref().ok_or_else(|| ctx.err(&j.kind, format!("a {} joint needs {what} = [x, y, z]", j.kind.get_ref())))?;
    let a = xyz(ctx, v, what)?;
    if a.iter().all(|c| *c == 0.0) {
        return Err(ctx.err(v, format!("{what} must not be zero")));
    }
    Ok(a)
}

/// An actuator driving exactly one declared joint or cable.
fn actuator(ctx: &Ctx, s: &Structure, a: &RawActuator) -> Result<Actuator, ScenarioError> {
    let find = |name: &Spanned<String>, list: Vec<&String>, what: &str| {
        list.iter()
            .position(|x| *x == name.get_ref())
            .ok_or_else(|| ctx.err(name, format!("unknown {what} '{}'", name.get_ref())))
    };
    if let (Some(d), None) = (&a.direction, &a.node) {
        return Err(ctx.err(d, "direction goes with node = \"name\" (a moved node)"));
    }
    let target = match (&a.joint, &a.cable, &a.node) {
        (Some(j), None, None) => ActuatorTarget::Joint(find(j, s.joints.iter().map(|x| &x.name).collect(), "joint")?),
        (None, Some(c), None) => {
            let cables: Vec<(usize, &String)> = s.members_of(MemberKind::Cable).map(|(i, m)| (i, &m.name)).collect();
            let k = find(c, cables.iter().map(|x| x.1).collect(), "cable")?;
            ActuatorTarget::CableLength(cables[k].0)
        }
        (None, None, Some(n)) => {
            let d = a.direction.as_ref().ok_or_else(|| {
                ctx.err(n, "a moved node needs direction = [x, y, z] (the command moves it along it, m)")
            })?;
            let v = xyz(ctx, d, "direction")?;
            let norm = crate::structure::norm(v);
            if norm == 0.0 {
                return Err(ctx.err(d, "direction must not be zero"));
            }
            ActuatorTarget::FixedNode { node: node(ctx, s, n)?, direction: v.map(|x| x / norm) }
        }
        _ => return Err(ctx.err(
            &a.symbol,
            "an actuator drives exactly one of: joint = \"name\", cable = \"name\", node = \"name\" (with direction)",
        )),
    };
    Ok(Actuator { symbol: a.symbol.get_ref().clone(), target })
}

/// The compact member groups (`strut_groups`, `spring_groups`, `cable_groups`): each pair of a
/// group becomes one member with the group's properties, checked as a member of its own table
/// would be; errors point at the pair (or the property) at fault.
fn add_member_groups(ctx: &Ctx, s: &mut Structure, r: &RawStructure) -> Result<(), ScenarioError> {
    for g in &r.strut_groups {
        for m in group_members(ctx, g)? {
            let st = strut(ctx, s, &m)?;
            s.members.push(st);
        }
    }
    for g in &r.spring_groups {
        for m in group_members(ctx, g)? {
            let sp = spring(ctx, s, &m)?;
            s.members.push(sp);
        }
    }
    for g in &r.cable_groups {
        for m in group_members(ctx, g)? {
            let c = cable(ctx, s, &m)?;
            s.members.push(c);
        }
    }
    Ok(())
}

/// A group's members as if each had its own table: the name (given, or "<group>:<a>-<b>")
/// located at its pair.
pub(super) fn group_members(ctx: &Ctx, g: &RawMemberGroup) -> Result<Vec<RawMember>, ScenarioError> {
    if g.name.get_ref().trim().is_empty() {
        return Err(ctx.err(&g.name, "a member group's name must not be empty"));
    }
    let pairs = g.pairs.get_ref();
    if pairs.is_empty() {
        return Err(ctx.err(&g.pairs, "pairs must list at least one pair of nodes, e.g. [[\"A\", \"B\"]]"));
    }
    if let Some(names) = &g.names {
        if names.get_ref().len() != pairs.len() {
            return Err(ctx.err(
                names,
                format!(
                    "names has {} entries for {} pairs: give one name per pair",
                    names.get_ref().len(),
                    pairs.len()
                ),
            ));
        }
    }
    let mut out = Vec::new();
    for (i, pair) in pairs.iter().enumerate() {
        let [a, b] = pair.get_ref().as_slice() else {
            return Err(
                ctx.err(pair, format!("a pair is two node names [\"A\", \"B\"], got {} names", pair.get_ref().len()))
            );
        };
        let name = match &g.names {
            Some(names) => names.get_ref()[i].clone(),
            None => toml::Spanned::new(pair.span(), format!("{}:{}-{}", g.name.get_ref(), a.get_ref(), b.get_ref())),
        };
        out.push(RawMember {
            name,
            a: a.clone(),
            b: b.clone(),
            radius: g.radius.clone(),
            stiffness: g.stiffness.clone(),
            length: g.length.clone(),
            through: None,
            friction: None,
            ea: None,
            youngs_modulus: None,
            area: None,
            density: None,
            segments: None,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use crate::structure::NODE_NAMES_COMPARED;

    /// A file whose cable runs from T through `n` pulley nodes P0..P{n-1} to W.
    fn pulleys(n: usize) -> String {
        let nodes: Vec<String> =
            (0..n).map(|i| format!("P{i} = [{}, {}, 0]", i as f64 * 1e-3, 1.0 + (i % 2) as f64 * 0.1)).collect();
        let through: Vec<String> = (0..n).map(|i| format!("\"P{i}\"")).collect();
        format!(
            "name = \"pulleys\"\nmechanism = \"custom\"\n[actuation]\npoints = [{{ L = 1e3 }}]\n\
             [[structure.bodies]]\nname = \"ground\"\nfixed = true\nnodes = {{ W = [-0.8, 1.2, 0], {} }}\n\
             [[structure.bodies]]\nname = \"link\"\nmass = 0.5\nnodes = {{ A = [0, 0, 0], T = [1, 0.3, 0] }}\n\
             [[structure.joints]]\nname = \"pin\"\nkind = \"revolute\"\nparent = \"ground\"\nchild = \"link\"\nat = \"A\"\naxis = [0, 0, 1]\n\
             [[structure.cables]]\nname = \"lift\"\na = \"T\"\nthrough = [{}]\nb = \"W\"\nstiffness = 5000.0\n\
             [[structure.actuators]]\nsymbol = \"L\"\ncable = \"lift\"\n",
            nodes.join(", "),
            through.join(", ")
        )
    }

    /// Checking a cable over 4,000 pulleys compares a number of node names linear in the nodes
    /// (at most 20 per node): it used to scan every node for each node of the path and for
    /// each node declared (a duplicate check), some 16 million comparisons.
    #[test]
    fn a_clustered_cable_is_checked_in_work_linear_in_its_nodes() {
        let n = 4_000;
        let text = pulleys(n);
        NODE_NAMES_COMPARED.with(|c| c.set(0));
        let parsed = crate::scenario::parse(std::path::Path::new("pulleys.toml"), &text);
        assert!(parsed.is_ok(), "{:?}", parsed.err().map(|e| e.to_string()));
        let compared = NODE_NAMES_COMPARED.with(|c| c.get());
        assert!(compared <= 20 * n, "{compared} node names compared for a cable over {n} pulleys");
    }
}
