//! Past the rigid strut and the massless cable: members built of point masses.
//!
//! - **An elastic strut** (a bar of axial stiffness EA): its body, which carries the strut's two
//!   nodes and nothing else, becomes two point masses of half its mass each, one at each node,
//!   and the strut a member that pushes and pulls with the stiffness EA / L
//!   ([`Law::ElasticStrut`]): the lumped-mass bar of structural dynamics. Its axial frequency is
//!   omega = sqrt(k (1/m_a + 1/m_b)) = 2 sqrt(EA / (m L)) with its ends free (the continuous
//!   bar's is pi sqrt(EA / (m L))); its inertia about its middle is m L^2 / 4 (a uniform rigid
//!   bar's m L^2 / 12), and it does not spin about its axis.
//! - **A heavy cable** (linear density rho, n segments): n elastic segments of stiffness n k and
//!   unstretched length L0 / n between n - 1 beads of mass rho L0 / n each, drawn at equal
//!   steps of arc length along its drawn path; the half segments at its ends, rho L0 / (2 n)
//!   each, rest on the end nodes' bodies (taken by a fixed body, added to a point mass). rho is
//!   per unstretched metre, so the cable's mass, rho L0, does not change as it stretches. A
//!   clustered cable's segment that spans an inner node is itself clustered through it, with
//!   that node's friction: the cable slides there within the segment.
//!
//! Both are made of members and free bodies the simulator already has, so the settle, the
//! modes, the motion, the sensitivities, interference, the table and the recording read them as
//! they read any spring, cable and body. A point mass is a free body with one node at its centre
//! of mass, so no member turns it: the modal analysis leaves its three turns out (`sim/modes.rs`).

use super::{distance, BodyKind, Inertia, Law, MemberId, Structure, Vec3};

/// The most segments a heavy cable may be built of.
pub const MAX_CABLE_SEGMENTS: usize = 1000;

/// Why a member cannot be built of point masses; the message names it and says what would do.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{0}")]
pub struct LumpError(pub String);

/// A point mass of `mass_kg` at `com`. No member turns it, so its turning is no mode and
/// its moments only need to be in the simulation's range (`scenario/physical.rs`, scaled by the
/// structure's extent): those of a free body of the structure's size `size_m` without stated
/// inertia, m size^2 / 12 about every axis [kg m^2].
fn bead_inertia(mass_kg: f64, com: Vec3, size_m: f64) -> Inertia {
    Inertia { mass_kg, com, principal_kg_m2: [mass_kg * size_m * size_m / 12.0; 3] }
}

/// What rewriting a structure's members carries from one to the next: the structure's extent
/// (the scale of the point masses' moments) and every name the structure has, bodies', nodes'
/// and members' alike, so that each new name is checked in constant time (a search of the
/// lists per name had made `check` of a 1000-strut prism with heavy cables take 2.8 s).
pub struct Lumping {
    /// The drawn structure's extent ([`super::extent_m`]) \[m\].
    pub size_m: f64,
    names: std::collections::HashSet<String>,
}

impl Lumping {
    /// The extent and the names of `s` as drawn.
    pub fn new(s: &Structure) -> Lumping {
        let bodies = s.bodies.iter().map(|b| b.name.clone());
        let names =
            bodies.chain(s.nodes.iter().map(|n| n.name.clone())).chain(s.members.iter().map(|m| m.name.clone()));
        Lumping { size_m: super::extent_m(s), names: names.collect() }
    }

    /// Takes `name` for a new part; false where the structure has it already.
    fn claim(&mut self, name: &str) -> bool {
        self.names.insert(name.to_string())
    }
}

/// Which bodies are point masses (free, with one node, at the centre of mass), in one pass
/// over the nodes: [`is_point_mass`] for every body, linear in the structure's size (a body
/// at a time had made `check` of a 1000-strut prism with heavy cables, 29,000 bodies, take 3 s).
pub fn point_masses(s: &Structure) -> Vec<bool> {
    let mut only: Vec<Option<usize>> = vec![None; s.bodies.len()];
    let mut count = vec![0usize; s.bodies.len()];
    for (n, node) in s.nodes.iter().enumerate() {
        count[node.body] += 1;
        only[node.body] = Some(n);
    }
    (0..s.bodies.len()).map(|b| count[b] == 1 && only[b].is_some_and(|n| at_centre(s, b, n))).collect()
}

/// Whether body `b` is a point mass: free, with one node, at its centre of mass.
pub fn is_point_mass(s: &Structure, b: usize) -> bool {
    let mut nodes = (0..s.nodes.len()).filter(|&n| s.nodes[n].body == b);
    matches!((nodes.next(), nodes.next()), (Some(n), None) if at_centre(s, b, n))
}

/// Whether node `n` is at the centre of mass of the free body `b`.
fn at_centre(s: &Structure, b: usize, n: usize) -> bool {
    let free = s.bodies[b].kind == BodyKind::Free;
    free && s.bodies[b].inertia.is_some_and(|i| i.com == s.nodes[n].position)
}

/// The step's stability limit on omega dt: the symplectic Euler step of an undamped oscillator
/// grows without bound beyond it.
pub const STABLE_OMEGA_DT: f64 = 2.0;

/// The fastest a point mass can vibrate on the members that hold it, by Gershgorin's bound on
/// M^-1 K: omega^2 <= 2 sum k / m over its members \[rad/s\], with the point mass that gives
/// it; None without a point mass held by an elastic member. For the beaded string and for an
/// elastic strut's ends the bound is the discretisation's own highest frequency to within its
/// last mode's sine (2 sqrt(k / m)). A point mass that supports hold in every direction does
/// not move and is left out.
pub fn fastest_point_mass(s: &Structure) -> Option<(f64, usize)> {
    let mut held = vec![0.0; s.bodies.len()];
    for m in &s.members {
        let Some(k) = m.stiffness_n_per_m() else { continue };
        for n in &m.path {
            held[s.nodes[*n].body] += k;
        }
    }
    let points = point_masses(s);
    let supported = s.held_translations();
    (0..s.bodies.len())
        .filter(|&b| held[b] > 0.0 && points[b] && supported[b] != [true; 3])
        .map(|b| ((2.0 * held[b] / s.bodies[b].inertia.map_or(f64::NAN, |i| i.mass_kg)).sqrt(), b))
        .max_by(|x, y| x.0.total_cmp(&y.0))
}

/// Makes strut `strut` elastic with axial stiffness `ea_n` = E A \[N\]: its body's mass halved
/// onto two point masses at its nodes, the strut pushing and pulling with EA / L0 about its
/// rest length L0, `rest_length_m` where given (a prestressed bar), else its drawn length.
pub fn make_strut_elastic(
    s: &mut Structure,
    strut: MemberId,
    ea_n: f64,
    rest_length_m: Option<f64>,
    lumping: &mut Lumping,
) -> Result<(), LumpError> {
    let name = s.members[strut].name.clone();
    let (a, b) = s.members[strut].ends();
    let body = s.nodes[a].body;
    let whose = s.bodies[body].name.clone();
    let refuse = |why: String| Err(LumpError(format!("elastic strut '{name}': {why}")));
    if s.nodes[b].body != body {
        return refuse("its two nodes lie on two bodies; an elastic strut's body carries its two nodes".into());
    }
    let Some(inertia) = s.bodies[body].inertia.filter(|_| s.bodies[body].kind == BodyKind::Free) else {
        return refuse(format!(
            "its body '{whose}' is fixed; an elastic strut's body is free (its mass is the strut's)"
        ));
    };
    if s.nodes.iter().enumerate().any(|(n, node)| node.body == body && n != a && n != b) {
        return refuse(format!(
            "its body '{whose}' carries other nodes; an elastic strut's body carries its two nodes alone"
        ));
    }
    if let Some(j) = s.joints.iter().find(|j| j.parent == body || j.child == body) {
        return refuse(format!(
            "joint '{}' holds its body '{whose}'; an elastic strut's ends are held by members",
            j.name
        ));
    }
    if s.loads.iter().any(|l| l.body == body) {
        return refuse(format!("a load acts on its body '{whose}'"));
    }
    let half = 0.5 * inertia.mass_kg;
    let length = distance(s.nodes[a].position, s.nodes[b].position);
    let end_b = format!("{whose}_{}", s.nodes[b].name);
    if !lumping.claim(&end_b) {
        return refuse(format!("its end body would be named '{end_b}', a name the structure already has"));
    }
    let size_m = lumping.size_m;
    s.bodies[body].inertia = Some(bead_inertia(half, s.nodes[a].position, size_m));
    let new = s.add_body(&end_b, BodyKind::Free, Some(bead_inertia(half, s.nodes[b].position, size_m)));
    s.nodes[b].body = new;
    let rest = rest_length_m.unwrap_or(length);
    s.members[strut].law = Law::ElasticStrut { stiffness_n_per_m: ea_n / rest, rest_length_m: rest };
    Ok(())
}

/// Builds cable `cable` of `segments` elastic segments between beads, its linear density
/// `density_kg_per_m` \[kg per unstretched m\]: the segments are named `{cable}_s1` ..
/// `{cable}_s{n}` from its node `a`, the beads (a body and a node each) `{cable}_b1` ..
/// `{cable}_b{n-1}`, drawn at equal steps of arc length along the drawn path. A clustered
/// cable's segment that spans an inner node runs through it (a clustered segment, with that
/// node's friction): the cable slides there within a segment's length.
pub fn hang_beads(
    s: &mut Structure,
    cable: MemberId,
    density_kg_per_m: f64,
    segments: usize,
    lumping: &mut Lumping,
) -> Result<(), LumpError> {
    hang_beads_with(s, cable, (density_kg_per_m, segments), EndShare::PointMassesOnly, lumping)
}

/// Where a heavy cable's end share of its mass (rho L0 / (2 n)) goes when the end is a node of
/// a rigid free body, which a point added off its centre of mass would give products of
/// inertia that its principal moments cannot hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndShare {
    /// Refused, naming the body (a file's own heavy cable: make that strut elastic).
    PointMassesOnly,
    /// Its weight as a point load at that node (a relaxation of a paper's massless cable,
    /// `structure/fidelity.rs`): the statics are those of the share resting there; its inertia,
    /// rho L0 / (2 n), is left out of the motion.
    NodeLoad,
}

/// [`hang_beads`] with (`density_kg_per_m`, `segments`) and the end share's place `share`.
pub fn hang_beads_with(
    s: &mut Structure,
    cable: MemberId,
    (density_kg_per_m, segments): (f64, usize),
    share: EndShare,
    lumping: &mut Lumping,
) -> Result<(), LumpError> {
    let member = s.members[cable].clone();
    let name = &member.name;
    let refuse = |why: String| Err(LumpError(format!("heavy cable '{name}': {why}")));
    let (Law::Cable { length_m, .. }, Some(k)) = (&member.law, member.stiffness_n_per_m()) else {
        return refuse("it needs a stiffness (N/m): an inextensible heavy cable is not modelled".into());
    };
    if !(1..=MAX_CABLE_SEGMENTS).contains(&segments) {
        return refuse(format!("segments is {segments}: from 1 to {MAX_CABLE_SEGMENTS}"));
    }
    if s.actuators.iter().any(|a| a.target == super::ActuatorTarget::CableLength(cable)) {
        return refuse("a winch drives it: a heavy cable's length is not actuated".into());
    }
    let (l0, n) = (*length_m, segments as f64);
    let end_mass = density_kg_per_m * l0 / (2.0 * n);
    let (a, b) = member.ends();
    let rigid_end = |s: &Structure, end: usize| {
        let body = s.nodes[end].body;
        s.bodies[body].kind == BodyKind::Free && !is_point_mass(s, body)
    };
    let loaded = [a, b].map(|end| share == EndShare::NodeLoad && rigid_end(s, end));
    for (end, moved) in [a, b].into_iter().zip(loaded) {
        let body = s.nodes[end].body;
        if rigid_end(s, end) && !moved {
            return refuse(format!(
                "it ends on node '{}' of free body '{}', which is not a point mass: its end's share of the cable's mass ({end_mass:e} kg) has no place there (make that strut elastic, or hang the cable from a fixed body)",
                s.nodes[end].name, s.bodies[body].name
            ));
        }
    }
    let drawn: Vec<Vec3> = member.path.iter().map(|&p| s.nodes[p].position).collect();
    let places = bead_places(&drawn, segments).map_err(|inner| {
        LumpError(format!(
            "heavy cable '{name}': with {segments} segments a bead would sit on its inner node '{}' (within {BEAD_NODE_CLEARANCE} of a segment): choose a count that puts none there",
            s.nodes[member.path[inner]].name
        ))
    })?;
    let names: Vec<String> = (1..segments).map(|i| format!("{name}_b{i}")).collect();
    let members: Vec<String> = (1..=segments).map(|k| format!("{name}_s{k}")).collect();
    if let Some(b) = names.iter().chain(&members).find(|b| !lumping.claim(b)) {
        return refuse(format!("it would name a part '{b}', a name the structure already has"));
    }
    let size_m = lumping.size_m;
    for (end, load) in [a, b].into_iter().zip(loaded) {
        rest_end_share(s, end, end_mass, load);
    }
    let mut beads = vec![a];
    for (bead, (at, _)) in names.iter().zip(&places) {
        let body = s.add_body(bead, BodyKind::Free, Some(bead_inertia(density_kg_per_m * l0 / n, *at, size_m)));
        beads.push(s.add_node(bead, body, *at));
    }
    beads.push(b);
    let law = super::CableLaw::Elastic { stiffness_n_per_m: k * n };
    // The leg (path segment) of each bead, the ends' first and last: the inner nodes between
    // bead j and bead j + 1 are those that start the legs after bead j's, up to bead j + 1's.
    let legs: Vec<usize> =
        std::iter::once(0).chain(places.iter().map(|(_, leg)| *leg)).chain([drawn.len() - 2]).collect();
    for (j, segment_name) in members.into_iter().enumerate() {
        let inner = legs[j] + 1..=legs[j + 1];
        let path: Vec<usize> =
            std::iter::once(beads[j]).chain(inner.clone().map(|v| member.path[v])).chain([beads[j + 1]]).collect();
        let mut segment = super::Member::cable(segment_name, path, law.clone(), l0 / n, member.radius_m);
        if !member.friction.is_empty() {
            segment.friction = inner.map(|v| member.friction[v - 1]).collect();
        }
        if j == 0 {
            s.members[cable] = segment;
        } else {
            s.members.push(segment);
        }
    }
    Ok(())
}

/// A heavy cable's end share `end_mass` \[kg\] at node `end`: added to a point mass, taken by a
/// fixed body, or (`load`: a rigid body's node) a point load of its weight there.
fn rest_end_share(s: &mut Structure, end: usize, end_mass: f64, load: bool) {
    if load {
        s.node_loads.push(super::NodeLoad { node: end, force_n: s.gravity.map(|g| g * end_mass) });
        return;
    }
    let body = s.nodes[end].body;
    let free = s.bodies[body].kind == BodyKind::Free;
    if let Some(i) = s.bodies[body].inertia.as_mut().filter(|_| free) {
        let grown = (i.mass_kg + end_mass) / i.mass_kg;
        i.mass_kg += end_mass;
        i.principal_kg_m2 = i.principal_kg_m2.map(|m| m * grown);
    }
}

/// How close (as a fraction of a segment's drawn length) a bead may come to a clustered
/// cable's inner node: closer, the segment through that node would have a leg of almost no
/// length, whose direction its first slide would turn over.
pub const BEAD_NODE_CLEARANCE: f64 = 1e-3;

/// The places of the `segments - 1` beads on the drawn path `points`, at equal steps of arc
/// length, each with the leg (index of the path's segment) it lies on; `Err(v)` where one
/// falls within [`BEAD_NODE_CLEARANCE`] of a segment from inner node `v`.
fn bead_places(points: &[Vec3], segments: usize) -> Result<Vec<(Vec3, usize)>, usize> {
    let mut arc = vec![0.0];
    for w in points.windows(2) {
        arc.push(arc[arc.len() - 1] + distance(w[0], w[1]));
    }
    // Arc length as a fraction of the whole: a straight cable's beads are at j / n exactly.
    let total = arc[arc.len() - 1];
    let arc: Vec<f64> = arc.iter().map(|x| x / total).collect();
    let n = segments as f64;
    let mut places = Vec::new();
    for j in 1..segments {
        let t = j as f64 / n;
        if let Some(v) = (1..points.len() - 1).find(|&v| (arc[v] - t).abs() < BEAD_NODE_CLEARANCE / n) {
            return Err(v);
        }
        let leg = (0..points.len() - 1).rev().find(|&i| arc[i] <= t).unwrap_or(0);
        let f = (t - arc[leg]) / (arc[leg + 1] - arc[leg]);
        let (p, q) = (points[leg], points[leg + 1]);
        places.push(([0, 1, 2].map(|c| p[c] + f * (q[c] - p[c])), leg));
    }
    Ok(places)
}
