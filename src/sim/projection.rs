//! Position projection of loop closures that lie inside one multibody.
//!
//! A closed planar loop (furet2018's crossed four-bar) stays inside its multibody and is closed
//! by an impulse joint (a planar pin). rapier holds such a joint only at the velocity level: its
//! anchors drift apart by an offset that grows with the time step and with every jump of an
//! actuator (3.7e-5 m measured on furet2018, FINDINGS.md). After each step this module moves
//! the multibody's free coordinates q (Gauss-Newton on the closure gap g(q), its Jacobian from
//! the links' columns of rapier's body Jacobians, as for the projected groups below) until every such loop is closed to
//! round-off, then removes the velocity component that would open it again
//! (qdot -= J^+ J qdot). The joints that are cut between multibodies keep rapier's treatment.
//!
//! Groups of plain bodies with many coordinates (a long chain of X modules cut into plain
//! bodies, `build::LOOPED_MULTIBODY_MAX_LINKS`) take a sparse Jacobian, assembled member by
//! member, and a band Cholesky of J J^T kept across the iterations (`least_squares.rs`): the
//! cost of a step grows with the members, not with their cube. Such a group that is rigid (its
//! Jacobian at full column rank, as an X chain at its commands) goes back to where it was last
//! closed, with no velocity and no solve, while nothing has opened a row there
//! ([`Jacobian::rigid`]).

use super::data::Data;
use super::model::{GroupTree, InternalClosure, Model, ProjectedGroup};
use crate::structure::JointKind;
use rapier3d_f64::prelude::*;

/// The chord method keeps its Jacobian while each iteration shrinks the largest gap at least
/// by this factor.
const CHORD_CONTRACTION: f64 = 0.1;

/// A sparse group's gap below this fraction of the tolerance is round-off already: the
/// polishing step (see [`close_rows`]) is skipped. Measured on a 10-X chain at rest: the third
/// Gauss-Newton step leaves 1.8e-15 m against a tolerance of 5e-14 m, and the polishing step
/// (three band solves) left 1.8e-15 m.
const POLISHED_FRACTION: f64 = 0.1;

/// Gauss-Newton iterations at most per step.
const MAX_ITERATIONS: usize = 20;

/// The projection stops when the largest gap is below this fraction of the structure's size.
pub(super) const GAP_TOLERANCE_FRACTION: f64 = 1e-14;

/// Singular values of the closure Jacobian below this fraction of the largest are treated as
/// zero (redundant closure rows).
pub(super) const SVD_RELATIVE_TOLERANCE: f64 = 1e-10;

/// The minimum-norm least-squares solution of `a x = b` for the projection (redundant closure
/// rows dropped by [`SVD_RELATIVE_TOLERANCE`]).
fn min_norm_solve(a: &nalgebra::DMatrix<f64>, b: &nalgebra::DVector<f64>) -> Option<nalgebra::DVector<f64>> {
    super::least_squares::min_norm_solve(a, b, SVD_RELATIVE_TOLERANCE)
}

/// A group's closure Jacobian (rows x coordinates): dense for small groups and groups with
/// multibodies, sparse for large groups of plain bodies ([`SPARSE_MIN_COORDINATES`]).
pub(super) enum Jacobian {
    Dense(nalgebra::DMatrix<f64>),
    /// With its factorization, which the Gauss-Newton step and the velocity projection share.
    Sparse(Box<super::least_squares::SparseLeastSquares>),
}

/// Groups of plain bodies with at least this many coordinates take the sparse Jacobian and
/// factorization: a dense solve grows as the cube of the coordinates (a chain of 20
/// furet2018 X modules has 360), the sparse one as the coordinates times the band squared.
const SPARSE_MIN_COORDINATES: usize = 48;

impl Jacobian {
    fn nrows(&self) -> usize {
        match self {
            Jacobian::Dense(j) => j.nrows(),
            Jacobian::Sparse(j) => j.matrix().nrows(),
        }
    }

    fn mul(&self, u: &nalgebra::DVector<f64>) -> nalgebra::DVector<f64> {
        match self {
            Jacobian::Dense(j) => j * u,
            Jacobian::Sparse(j) => j.matrix().mul(u),
        }
    }

    /// A sparse Jacobian factorized; one with redundant rows becomes dense (whose solve drops
    /// them).
    pub(super) fn sparse(j: super::least_squares::SparseRows) -> Self {
        match super::least_squares::SparseLeastSquares::new(j) {
            Ok(f) => Jacobian::Sparse(Box::new(f)),
            Err(j) => Jacobian::Dense(j.to_dense()),
        }
    }

    /// The minimum-norm least-squares solution of `J x = b`.
    fn solve(&self, b: &nalgebra::DVector<f64>) -> Option<nalgebra::DVector<f64>> {
        match self {
            Jacobian::Dense(j) => min_norm_solve(j, b),
            Jacobian::Sparse(j) => j.solve(b),
        }
    }

    /// A Gauss-Newton step: [`Self::solve`], without the sparse solve's refinement (the next
    /// iteration corrects what the step leaves).
    fn step(&self, b: &nalgebra::DVector<f64>) -> Option<nalgebra::DVector<f64>> {
        match self {
            Jacobian::Dense(j) => min_norm_solve(j, b),
            Jacobian::Sparse(j) => j.solve_refined(b, 0),
        }
    }

    /// Whether the group is rigid: a sparse Jacobian is factorized at full rank, so at least as
    /// many rows as coordinates means full column rank: no motion keeps every row closed, the
    /// closed configurations are isolated points, and the only velocity left by the projection
    /// is zero.
    pub(super) fn rigid(&self) -> bool {
        matches!(self, Jacobian::Sparse(j) if j.matrix().nrows() >= j.matrix().ncols)
    }
}

/// Gauss-Newton onto a constraint manifold of `ndof` coordinates: `rows` evaluates the
/// constraint rows [m]; `jacobian(sim, rows)` their derivatives by the coordinates at the
/// current state (rows x ndof); `displace` moves every coordinate by a step; `start`, a sparse
/// Jacobian kept from an earlier call, is tried first (the chord test replaces it when it
/// contracts too little). Iterates until every row is within `tolerance_fraction` of the
/// structure's size (at most [`MAX_ITERATIONS`]), or gives up when the first step shrinks the
/// largest row by less than `max_first_contraction`.
// Eight inputs, each its own: the rows, their Jacobian and the step as three closures, a kept
// Jacobian and the two stopping thresholds its callers pass on; a struct would only rename them.
#[allow(clippy::too_many_arguments)]
pub(super) fn close_rows(
    m: &Model,
    sim: &mut Data,
    rows: &dyn Fn(&Data) -> Vec<f64>,
    jacobian: &dyn Fn(&mut Data, &[f64]) -> Jacobian,
    displace: &dyn Fn(&mut Data, &[f64]),
    start: Option<Jacobian>,
    tolerance_fraction: f64,
    max_first_contraction: f64,
) -> Closing {
    let tol = tolerance_fraction * m.length_scale_m;
    let mut jac: Option<Jacobian> = start;
    let mut formed = false;
    let (mut previous, mut polished) = (f64::INFINITY, false);
    let mut first_contraction = 0.0;
    for k in 0..MAX_ITERATIONS {
        let g0 = rows(sim);
        if g0.is_empty() {
            break;
        }
        let gap = largest_abs(&g0);
        if k == 1 {
            first_contraction = gap / previous;
            if first_contraction > max_first_contraction {
                break;
            }
        }
        // A sparse group takes one step more once within the tolerance: along a chain of a
        // hundred links the gaps left at the tolerance move its far end by 5e-12 m from step to
        // step, ten times the settle's speed threshold; one step more leaves round-off.
        // Exactly closed with no Jacobian yet (a structure as drawn) or, for a sparse one,
        // within [`POLISHED_FRACTION`] of the tolerance: nothing left to polish.
        let sparse = matches!(jac, Some(Jacobian::Sparse(_)));
        if (jac.is_none() && gap == 0.0) || (sparse && gap <= tol && (polished || gap <= POLISHED_FRACTION * tol)) {
            break;
        }
        // A sparse Jacobian and its factorization are kept while they shrink the gap by at
        // least [`CHORD_CONTRACTION`] per iteration (the chord method: after a step each
        // iteration shrinks the gap by about the gap over the structure's size, 1e-4 to 1e-6,
        // in as many iterations as Newton's method with one factorization instead of three
        // or four); a dense one is evaluated at every iterate.
        if jac.is_none() || !sparse || (gap > tol && gap > CHORD_CONTRACTION * previous) {
            jac = Some(jacobian(sim, &g0));
            formed = true;
        }
        previous = gap;
        let Some(j) = jac.as_ref() else { break };
        if gap <= tol {
            // A loose tolerance is not polished.
            if !matches!(j, Jacobian::Sparse(_)) || tolerance_fraction > GAP_TOLERANCE_FRACTION {
                break;
            }
            polished = true;
        }
        // The polishing step refined: it leaves the round-off of the gap, not of the solve.
        let b = -nalgebra::DVector::from_vec(g0);
        let Some(dq) = (if polished { j.solve(&b) } else { j.step(&b) }) else { break };
        displace(sim, dq.as_slice());
    }
    let left = largest_abs(&rows(sim));
    Closing { jacobian: jac, formed, left, first_contraction }
}

/// What [`close_rows`] leaves: the last Jacobian, whether that call formed it, the largest row
/// left [m], and the first contraction: the largest row after the first Gauss-Newton step over
/// the largest before it (0 when no step was taken). A small first contraction says the start
/// was well inside the iteration's region of convergence (see `continuation.rs`).
pub(super) struct Closing {
    pub jacobian: Option<Jacobian>,
    pub formed: bool,
    pub left: f64,
    pub first_contraction: f64,
}

/// What a projection leaves: the largest row [m] and the largest first contraction over the
/// groups ([`Closing`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Projected {
    pub left: f64,
    pub first_contraction: f64,
}

impl Projected {
    fn max(self, other: Projected) -> Projected {
        Projected {
            left: self.left.max(other.left),
            first_contraction: self.first_contraction.max(other.first_contraction),
        }
    }
}

/// The largest magnitude among `rows` (0 for none).
pub(super) fn largest_abs(rows: &[f64]) -> f64 {
    rows.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

/// A body's first-order motion per unit of one coordinate: velocity `v` of the point `at`
/// and angular velocity `w`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Twist {
    pub v: Vector,
    pub w: Vector,
    pub at: Vector,
}

impl Twist {
    /// The motion of the body's point `p`.
    fn of_point(&self, p: Vector) -> Vector {
        self.v + self.w.cross(p - self.at)
    }
}

/// A joint's geometry at the current poses ([`Simulation::joint_frame`]): its rows' rates
/// are linear in its two bodies' twists, with these as coefficients. The sparse Jacobian forms
/// it once per joint for its twelve unit twists.
pub(super) struct JointFrame {
    parent: usize,
    child: usize,
    /// The anchor as carried by each body [m].
    anchor_on_parent: Vector,
    anchor_on_child: Vector,
    axes: JointAxes,
    /// The structure's size, which scales angular rows to lengths [m].
    scale: f64,
}

/// The axes a joint's angular rows (or, for a planar pin, its in-plane rows) are taken along.
pub(super) enum JointAxes {
    /// The in-plane pair of the plane's normal (parent's frame).
    PlanarPin { pair: [Vector; 2] },
    /// The axis as carried by the parent and by the child, the pair across the parent's, and
    /// whether the angle about it is locked (an actuated joint off the tree).
    Revolute { ap: Vector, ac: Vector, pair: [Vector; 2], locked: bool },
    /// The first axis as carried by the parent, the second by the child.
    Universal { a1: Vector, a2: Vector },
    /// A point joint: the anchor gap alone.
    Point,
}

impl JointFrame {
    /// The rates of the joint's rows for the bodies' twists (`None`: the body stays). Exact to
    /// first order at a closed joint; the terms that multiply a gap are dropped.
    fn row_rates(&self, twist: &dyn Fn(usize) -> Option<Twist>, out: &mut Vec<f64>) {
        let point_rate = |b: usize, p: Vector| twist(b).map_or(Vector::ZERO, |t| t.of_point(p));
        let spin = |b: usize| twist(b).map_or(Vector::ZERO, |t| t.w);
        let gap_rate = point_rate(self.child, self.anchor_on_child) - point_rate(self.parent, self.anchor_on_parent);
        let (wp, wc) = (spin(self.parent), spin(self.child));
        let scale = self.scale;
        match &self.axes {
            JointAxes::PlanarPin { pair } => {
                for t in pair {
                    out.push(gap_rate.dot(*t));
                }
            }
            JointAxes::Revolute { ap, ac, pair, locked } => {
                out.extend([gap_rate.x, gap_rate.y, gap_rate.z]);
                for t in pair {
                    out.push((wc.cross(*ac).dot(*t) + ac.dot(wp.cross(*t))) * scale);
                }
                if *locked {
                    out.push((wc - wp).dot(*ap) * scale);
                }
            }
            JointAxes::Universal { a1, a2 } => {
                out.extend([gap_rate.x, gap_rate.y, gap_rate.z]);
                out.push((wp.cross(*a1).dot(*a2) + a1.dot(wc.cross(*a2))) * scale);
            }
            JointAxes::Point => out.extend([gap_rate.x, gap_rate.y, gap_rate.z]),
        }
    }
}

impl Data {
    /// The loop-closing joints whose two bodies are links of the same multibody.
    pub(super) fn find_internal_closures(&self, m: &Model) -> Vec<InternalClosure> {
        let mut out = Vec::new();
        for (j, joint) in m.structure.joints.iter().enumerate() {
            if m.joint_impulse[j].is_none() || !matches!(joint.kind, JointKind::PlanarPin { .. }) {
                continue;
            }
            let link = |b: usize| self.multibody_joints.rigid_body_link(m.handles[b]).map(|l| l.multibody);
            if let (Some(a), Some(b)) = (link(joint.parent), link(joint.child)) {
                if a == b {
                    out.push(InternalClosure { joint: j, multibody: a });
                }
            }
        }
        out
    }

    /// The free coordinates of a multibody: every degree of freedom of a link that no actuator
    /// sets.
    pub(super) fn free_dofs(&self, multibody: MultibodyIndex) -> Vec<usize> {
        self.multibody_joints.get_multibody(multibody).map_or_else(Vec::new, |mb| {
            mb.links()
                .filter(|l| !l.joint().kinematic)
                .flat_map(|l| l.assembly_id()..l.assembly_id() + l.joint().ndofs())
                .collect()
        })
    }

    /// Moves the multibody's coordinates by `disp` and places its bodies there.
    pub(super) fn displace(&mut self, multibody: MultibodyIndex, disp: &[f64]) {
        if let Some(mb) = self.multibody_joints.get_multibody_mut(multibody) {
            mb.apply_displacements(disp);
            mb.forward_kinematics(&self.bodies, false);
            mb.update_rigid_bodies(&mut self.bodies, true);
        }
    }
}

/// A cable within this fraction of the structure's size of its length counts as taut.
const TAUT_TOLERANCE_FRACTION: f64 = 1e-12;

impl Data {
    /// A rope cable is taut when stretched to its length (within round-off) or when rapier's
    /// rope pulled in the last step.
    pub(super) fn cable_is_taut(&self, m: &Model, c: usize) -> bool {
        let cable = &m.structure.members[c];
        let l =
            crate::structure::distance(self.node_position(m, cable.ends().0), self.node_position(m, cable.ends().1));
        let inv_h = m.settings.substeps as f64 / m.settings.dt_s;
        let impulse =
            m.ropes[c].and_then(|h| self.impulse_joints.get(h)).map_or(0.0, |j| j.data.limits[0].impulse.abs() * inv_h);
        l >= self.rest_lengths[c] - TAUT_TOLERANCE_FRACTION * m.length_scale_m || impulse > 0.0
    }

    /// For every cable: whether it is taut and held at its length by a group's projection (its
    /// tension is then fitted from the equilibrium, not read from rapier's impulse).
    pub(super) fn cables_held_by_projection(&self, m: &Model) -> Vec<bool> {
        let mut held = vec![false; m.structure.members.len()];
        for g in &m.projected_groups {
            for c in self.projected_taut_cables(m, g).unwrap_or_default() {
                held[c] = true;
            }
        }
        held
    }

    /// The taut cables of group `g` when the projection closes it now, else None. A group with
    /// multibodies (mohr2011's legs) is closed only while every one of its cables is taut: with
    /// a cable slack its end-effector has a free motion that rapier's step and the projection
    /// then hold still together short of the equilibrium (measured on gravity_hanging.toml's
    /// (1, 1, 3): at rest 5e-3 N m from it), so the group is left to rapier alone until the
    /// cables are taut again.
    pub(super) fn projected_taut_cables(&self, m: &Model, g: &ProjectedGroup) -> Option<Vec<usize>> {
        let taut: Vec<usize> = g.cables.iter().copied().filter(|&c| self.cable_is_taut(m, c)).collect();
        (g.multibodies.is_empty() || taut.len() == g.cables.len()).then_some(taut)
    }

    /// Groups of free bodies whose every constraint the projection handles. A group that
    /// touches an actuated joint other than a revolute (which the projection holds at its
    /// command), a joint kind without projection rows, or a multibody with a
    /// loop inside (closed by [`Self::project_internal_closures`]) is left to rapier alone.
    pub(super) fn find_projected_groups(&self, m: &Model) -> Vec<ProjectedGroup> {
        let s = &m.structure;
        let multibody_of = |b: usize| self.multibody_of(m, b);
        let looped: Vec<MultibodyIndex> = m.internal_closures.iter().map(|c| c.multibody).collect();
        let plain = |b: usize| m.is_free(b) && multibody_of(b).is_none();
        let fixed = |b: usize| self.is_fixed_body(m, b);
        let mut parent = self.constrained_together(m);
        let find = find_root;
        let mut groups: Vec<(usize, ProjectedGroup, bool)> = Vec::new();
        let group_of = |root: usize, groups: &mut Vec<(usize, ProjectedGroup, bool)>| -> usize {
            if let Some(i) = groups.iter().position(|g| g.0 == root) {
                i
            } else {
                groups.push((root, ProjectedGroup::default(), true));
                groups.len() - 1
            }
        };
        let movable = |b: usize| if fixed(b) { None } else { Some(b) };
        for (j, joint) in s.joints.iter().enumerate() {
            if m.joint_impulse[j].is_none() {
                continue;
            }
            let Some(b) = movable(joint.child).or(movable(joint.parent)) else { continue };
            let root = find(&mut parent, b);
            let g = group_of(root, &mut groups);
            groups[g].1.joints.push(j);
            let supported = matches!(
                joint.kind,
                JointKind::Spherical
                    | JointKind::Revolute { .. }
                    | JointKind::Universal { .. }
                    | JointKind::PlanarPin { .. }
            );
            // An actuated revolute off the tree is locked at its command: one row more.
            let actuated_ok = !m.actuated[j] || matches!(joint.kind, JointKind::Revolute { .. });
            groups[g].2 &= supported && actuated_ok;
        }
        for (c, cable) in s.members.iter().enumerate() {
            if m.ropes[c].is_none() {
                continue;
            }
            let (a, b) = (s.nodes[cable.ends().0].body, s.nodes[cable.ends().1].body);
            let Some(m) = movable(a).or(movable(b)) else { continue };
            let root = find(&mut parent, m);
            let g = group_of(root, &mut groups);
            groups[g].1.cables.push(c);
        }
        for (b, _) in s.bodies.iter().enumerate() {
            if fixed(b) {
                continue;
            }
            let root = find(&mut parent, b);
            if let Some(g) = groups.iter_mut().find(|g| g.0 == root) {
                if plain(b) {
                    g.1.bodies.push(b);
                } else if let Some(m) = multibody_of(b) {
                    g.2 &= !looped.contains(&m);
                    if !g.1.multibodies.contains(&m) {
                        g.1.multibodies.push(m);
                    }
                } else {
                    g.2 = false;
                }
            }
        }
        groups
            .into_iter()
            .filter(|(_, g, ok)| *ok && !(g.bodies.is_empty() && g.multibodies.is_empty()))
            .map(|(_, mut g, _)| {
                if g.multibodies.is_empty() && 6 * g.bodies.len() >= SPARSE_MIN_COORDINATES {
                    self.order_joints_by_band(m, &mut g);
                    g.tree = Some(GroupTree::of(m, &g.bodies, &g.joints));
                }
                g
            })
            .collect()
    }

    /// Puts a sparse group's joints in reverse Cuthill-McKee order over the bodies they share,
    /// so that the rows coupled in J J^T sit close together: the band Cholesky's cost grows as
    /// the band squared. Measured on a chain of 10 furet2018 X modules cut into plain bodies:
    /// the band of its 180 rows went from 27 in the structure's order to 17, and a settle from
    /// 2.7 to 2.4 ms.
    fn order_joints_by_band(&self, m: &Model, g: &mut ProjectedGroup) {
        let s = &m.structure;
        let mut members_of_body: Vec<Vec<usize>> = vec![Vec::new(); s.bodies.len()];
        for (k, &j) in g.joints.iter().enumerate() {
            for b in [s.joints[j].parent, s.joints[j].child] {
                if !self.is_fixed_body(m, b) {
                    members_of_body[b].push(k);
                }
            }
        }
        let neighbours: Vec<Vec<usize>> = g
            .joints
            .iter()
            .enumerate()
            .map(|(k, &j)| {
                let mut n: Vec<usize> = [s.joints[j].parent, s.joints[j].child]
                    .iter()
                    .flat_map(|&b| members_of_body[b].iter().copied())
                    .filter(|&m| m != k)
                    .collect();
                n.sort_unstable();
                n.dedup();
                n
            })
            .collect();
        let position = crate::ordering::reverse_cuthill_mckee(&neighbours);
        let mut ordered = g.joints.clone();
        for (k, &j) in g.joints.iter().enumerate() {
            ordered[position[k]] = j;
        }
        g.joints = ordered;
    }

    /// The multibody that body `b` is a link of, if any.
    pub(super) fn multibody_of(&self, m: &Model, b: usize) -> Option<MultibodyIndex> {
        self.multibody_joints.rigid_body_link(m.handles[b]).map(|l| l.multibody)
    }

    fn is_fixed_body(&self, m: &Model, b: usize) -> bool {
        m.structure.bodies[b].kind == crate::structure::BodyKind::Fixed
    }

    /// A union-find forest (each body's parent, [`find_root`]) over the bodies joined by an
    /// impulse joint, a rope cable or a common multibody; fixed bodies join nothing.
    fn constrained_together(&self, m: &Model) -> Vec<usize> {
        let s = &m.structure;
        let n = s.bodies.len();
        let mut edges: Vec<(usize, usize)> = Vec::new();
        for (j, joint) in s.joints.iter().enumerate() {
            if m.joint_impulse[j].is_some() {
                edges.push((joint.parent, joint.child));
            }
        }
        for (c, cable) in s.members.iter().enumerate() {
            if m.ropes[c].is_some() {
                edges.push((s.nodes[cable.ends().0].body, s.nodes[cable.ends().1].body));
            }
        }
        // The links of one multibody move together: one group.
        for a in 0..n {
            for b in a + 1..n {
                if self.multibody_of(m, a).is_some() && self.multibody_of(m, a) == self.multibody_of(m, b) {
                    edges.push((a, b));
                }
            }
        }
        let mut parent: Vec<usize> = (0..n).collect();
        for &(a, b) in &edges {
            if !self.is_fixed_body(m, a) && !self.is_fixed_body(m, b) {
                let (ra, rb) = (find_root(&mut parent, a), find_root(&mut parent, b));
                parent[ra] = rb;
            }
        }
        parent
    }

    /// The constraint rows of one joint: its anchor gap (for a planar pin only the two
    /// components across its axis) and its angular rows. Lengths in m; angular rows
    /// (dimensionless) times the structure's size, so that every row is a length.
    pub(super) fn joint_rows(&self, m: &Model, j: usize, out: &mut Vec<f64>) {
        let s = &m.structure;
        let scale = m.length_scale_m;
        let pose = |b: usize| *self.bodies[m.handles[b]].position();
        let vec3 = |a: [f64; 3]| Vector::new(a[0], a[1], a[2]);
        let joint = &s.joints[j];
        let (pp, pc) = (pose(joint.parent), pose(joint.child));
        let a = vec3(s.nodes[joint.anchor].position);
        let gap = pc.transform_point(a) - pp.transform_point(a);
        let before = out.len();
        match joint.kind {
            JointKind::PlanarPin { axis } => {
                let n = (pp.rotation * vec3(axis)).normalize();
                for t in super::forces::orthogonal_pair(n) {
                    out.push(gap.dot(t));
                }
            }
            JointKind::Revolute { axis } => {
                out.extend([gap.x, gap.y, gap.z]);
                let ap = (pp.rotation * vec3(axis)).normalize();
                let ac = (pc.rotation * vec3(axis)).normalize();
                for t in super::forces::orthogonal_pair(ap) {
                    out.push(ac.dot(t) * scale);
                }
                // An actuated joint locked off the tree: its angle at the command.
                if let Some(target) = self.locked_angle(m, j) {
                    out.push(self.lock_row(m, j, pp.rotation, pc.rotation, target));
                }
            }
            JointKind::Universal { axis1, axis2 } => {
                out.extend([gap.x, gap.y, gap.z]);
                let a1 = pp.rotation * vec3(axis1).normalize();
                let a2 = pc.rotation * vec3(axis2).normalize();
                out.push((a1.dot(a2) - vec3(axis1).normalize().dot(vec3(axis2).normalize())) * scale);
            }
            _ => out.extend([gap.x, gap.y, gap.z]),
        }
        debug_assert_eq!(out.len() - before, self.joint_row_count(m, j), "joint_row_count matches joint_rows");
    }

    /// The row of revolute joint `j` locked at `target` [rad] (its parent's and child's
    /// rotations `pp`, `pc`): the angle's offset, wrapped to (-pi, pi], times the structure's
    /// size.
    pub(super) fn lock_row(&self, m: &Model, j: usize, pp: Rotation, pc: Rotation, target: f64) -> f64 {
        let JointKind::Revolute { axis } = m.structure.joints[j].kind else { return 0.0 };
        let off = super::forces::relative_angle(pp, pc, Vector::new(axis[0], axis[1], axis[2])) - target;
        off.sin().atan2(off.cos()) * m.length_scale_m
    }

    /// The constraint rows of a projected group: each joint's ([`Self::joint_rows`]), then the
    /// stretch of each cable in `taut` [m].
    pub(super) fn group_rows(&self, m: &Model, g: &ProjectedGroup, taut: &[usize]) -> Vec<f64> {
        let mut out = Vec::new();
        for &j in &g.joints {
            self.joint_rows(m, j, &mut out);
        }
        self.cable_rows(m, taut, &mut out);
        out
    }

    /// The stretch of each cable in `taut` [m].
    pub(super) fn cable_rows(&self, m: &Model, taut: &[usize], out: &mut Vec<f64>) {
        let s = &m.structure;
        for &c in taut {
            let cable = &s.members[c];
            let (pa, pb) = (self.node_position(m, cable.ends().0), self.node_position(m, cable.ends().1));
            out.push(crate::structure::distance(pa, pb) - self.rest_lengths[c]);
        }
    }

    /// The rates of [`Self::group_rows`] (same order and scaling) when each body moves with
    /// its twist (`None`: the body stays). Exact to first order at a closed joint; the terms
    /// that multiply a gap are dropped (the gap is round-off once projected).
    fn group_row_rates(
        &self,
        m: &Model,
        g: &ProjectedGroup,
        taut: &[usize],
        twist: &dyn Fn(usize) -> Option<Twist>,
        out: &mut Vec<f64>,
    ) {
        for &j in &g.joints {
            self.joint_row_rates(m, j, twist, out);
        }
        for &c in taut {
            self.cable_row_rate(m, c, twist, out);
        }
    }

    /// The number of [`Self::joint_rows`] of joint `j`.
    pub(super) fn joint_row_count(&self, m: &Model, j: usize) -> usize {
        match m.structure.joints[j].kind {
            JointKind::PlanarPin { .. } => 2,
            JointKind::Revolute { .. } => 5 + usize::from(self.locked_angle(m, j).is_some()),
            JointKind::Universal { .. } => 4,
            _ => 3,
        }
    }

    /// The rates of [`Self::joint_rows`] of joint `j` for the bodies' twists.
    fn joint_row_rates(&self, m: &Model, j: usize, twist: &dyn Fn(usize) -> Option<Twist>, out: &mut Vec<f64>) {
        let s = &m.structure;
        // Neither body moves: zero rates (the multibody Jacobian's columns above the joint).
        if twist(s.joints[j].parent).is_none() && twist(s.joints[j].child).is_none() {
            out.extend(std::iter::repeat_n(0.0, self.joint_row_count(m, j)));
            return;
        }
        self.joint_frame(m, j).row_rates(twist, out);
    }

    /// Joint `j`'s geometry at the current poses, which its rows' rates are linear in.
    pub(super) fn joint_frame(&self, m: &Model, j: usize) -> JointFrame {
        let s = &m.structure;
        let pose = |b: usize| *self.bodies[m.handles[b]].position();
        let vec3 = |a: [f64; 3]| Vector::new(a[0], a[1], a[2]);
        let joint = &s.joints[j];
        let (pp, pc) = (pose(joint.parent), pose(joint.child));
        let a = vec3(s.nodes[joint.anchor].position);
        let axes = match joint.kind {
            JointKind::PlanarPin { axis } => {
                let n = (pp.rotation * vec3(axis)).normalize();
                JointAxes::PlanarPin { pair: super::forces::orthogonal_pair(n) }
            }
            JointKind::Revolute { axis } => {
                let ap = (pp.rotation * vec3(axis)).normalize();
                let ac = (pc.rotation * vec3(axis)).normalize();
                let pair = super::forces::orthogonal_pair(ap);
                JointAxes::Revolute { ap, ac, pair, locked: self.locked_angle(m, j).is_some() }
            }
            JointKind::Universal { axis1, axis2 } => JointAxes::Universal {
                a1: pp.rotation * vec3(axis1).normalize(),
                a2: pc.rotation * vec3(axis2).normalize(),
            },
            _ => JointAxes::Point,
        };
        JointFrame {
            parent: joint.parent,
            child: joint.child,
            anchor_on_parent: pp.transform_point(a),
            anchor_on_child: pc.transform_point(a),
            axes,
            scale: m.length_scale_m,
        }
    }

    /// The rate of a taut cable's stretch for the bodies' twists.
    fn cable_row_rate(&self, m: &Model, c: usize, twist: &dyn Fn(usize) -> Option<Twist>, out: &mut Vec<f64>) {
        let s = &m.structure;
        let vec3 = |a: [f64; 3]| Vector::new(a[0], a[1], a[2]);
        let point_rate = |b: usize, p: Vector| twist(b).map_or(Vector::ZERO, |t| t.of_point(p));
        let cable = &s.members[c];
        let (pa, pb) = (vec3(self.node_position(m, cable.ends().0)), vec3(self.node_position(m, cable.ends().1)));
        let d = pb - pa;
        let l = d.length();
        let rate = point_rate(s.nodes[cable.ends().1].body, pb) - point_rate(s.nodes[cable.ends().0].body, pa);
        out.push(if l > 0.0 { rate.dot(d / l) } else { 0.0 });
    }

    /// The commanded angle of an actuated revolute joint off the tree, locked there
    /// (`build::locked_joint`, relative to the drawn pose) [rad]; None for any other joint.
    pub(super) fn locked_angle(&self, m: &Model, j: usize) -> Option<f64> {
        let revolute = matches!(m.structure.joints[j].kind, JointKind::Revolute { .. });
        (m.actuated[j] && revolute && m.joint_impulse[j].is_some()).then(|| self.locked_coordinates[j])
    }

    /// Moves body `b` by a translation `t` [m] and a rotation `r` [rad, rotation vector] about
    /// its centre of mass.
    pub(super) fn nudge(&mut self, m: &Model, b: usize, t: Vector, r: Vector) {
        let com = self.world_com(m, b);
        let h = m.handles[b];
        let pose = *self.bodies[h].position();
        let moved = super::group_tree::turn_about(com, t, r) * pose;
        self.bodies[h].set_position(moved, true);
    }

    /// Closes the group's joints and its `taut` cables to round-off (Gauss-Newton in its
    /// coordinates, the Jacobian from the bodies' twists) and removes the velocities that would
    /// open them. A sparse Jacobian is `kept` for the next call ([`KeptJacobian`]).
    // The group, its taut cables, the two kept states it reads and updates, and the two stopping
    // thresholds of `close_rows` that its callers pass on: eight with `self`, each its own.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn project_group(
        &mut self,
        m: &Model,
        g: &ProjectedGroup,
        taut: &[usize],
        kept: &mut Option<KeptJacobian>,
        rest: &mut Option<RigidRest>,
        tolerance_fraction: f64,
        max_first_contraction: f64,
    ) -> Projected {
        if let Some(left) = self.back_to_rigid_rest(m, g, taut, rest.as_ref()) {
            return Projected { left, first_contraction: 0.0 };
        }
        *rest = None;
        let coords = GroupCoordinates::of(m, self, g);
        // The body Jacobians at the current coordinates (the Jacobian below reads them).
        for &m in &g.multibodies {
            if let Some(mb) = self.multibody_joints.get_multibody_mut(m) {
                mb.forward_kinematics(&self.bodies, false);
            }
        }
        let rows = |sim: &Data| sim.group_rows(m, g, taut);
        let (start, start_poses) = match kept.take().filter(|k| k.taut == taut) {
            Some(k) => (Some(k.jacobian), Some(k.poses)),
            None => (None, None),
        };
        // Where the last sparse Jacobian was formed: the poses a kept one is judged by.
        let formed_at = std::cell::RefCell::new(start_poses);
        let jacobian = |sim: &mut Data, g0: &[f64]| {
            let j = coords.jacobian(m, sim, g, taut, g0.len());
            if matches!(j, Jacobian::Sparse(_)) {
                *formed_at.borrow_mut() = Some(sim.group_poses(m, g));
            }
            j
        };
        let displace = |sim: &mut Data, dq: &[f64]| coords.displace(m, sim, g, dq);
        let Closing { jacobian: jac, formed, left, first_contraction } =
            close_rows(m, self, &rows, &jacobian, &displace, start, tolerance_fraction, max_first_contraction);
        let u = coords.velocities(m, self, g);
        let moving = u.iter().any(|&x| x != 0.0);
        // A Jacobian kept from an earlier call serves the velocities only where the bodies are
        // back where it was formed (at rest); otherwise they take one formed here.
        let stale = |sim: &Data| {
            let at = formed_at.borrow();
            !at.as_ref().is_some_and(|p| sim.poses_within(m, g, p, KEPT_POSE_TOLERANCE_FRACTION))
        };
        let jac = match jac {
            Some(j) if matches!(j, Jacobian::Sparse(_)) && !formed && moving && stale(self) => {
                let g0 = rows(self);
                Some(jacobian(self, &g0))
            }
            j => j,
        };
        if let Some(jac) = jac.filter(|j| j.nrows() > 0) {
            // Remove J^+ (J u) from the velocities u over every row, taut cables included (they
            // were just held at their length: a cable goes slack when rapier's rope stops
            // pulling, and is then no longer taut here). A rigid group keeps none: J^+ J = I.
            if moving && jac.rigid() {
                self.stop_bodies(m, &g.bodies);
            } else if moving {
                if let Some(du) = jac.solve(&jac.mul(&u)) {
                    coords.remove_velocities(m, self, g, &du);
                }
            }
            if let (Jacobian::Sparse(_), Some(poses)) = (&jac, formed_at.take()) {
                let closed_to_round_off =
                    tolerance_fraction <= GAP_TOLERANCE_FRACTION && left <= GAP_TOLERANCE_FRACTION * m.length_scale_m;
                *rest = (jac.rigid() && closed_to_round_off).then(|| self.rigid_rest(m, g, taut, left));
                *kept = Some(KeptJacobian { jacobian: jac, poses, taut: taut.to_vec() });
            }
        }
        Projected { left, first_contraction }
    }

    /// A rigid group that rapier's step moved by less than [`RIGID_REST_FRACTION`] of the
    /// structure's size from where it was last closed to round-off goes back there when every
    /// row is still closed there (no command moved it since): the configuration is isolated,
    /// so it is where Gauss-Newton from the stepped poses converges, without its solves; and
    /// it keeps no velocity. Closed there means to round-off, whatever the caller's tolerance;
    /// the rows are evaluated again only when their other inputs have changed since
    /// ([`RigidRest`]). Returns the largest row left, or None (nothing changed) when the
    /// projection must run.
    fn back_to_rigid_rest(
        &mut self,
        m: &Model,
        g: &ProjectedGroup,
        taut: &[usize],
        rest: Option<&RigidRest>,
    ) -> Option<f64> {
        let rest = rest.filter(|r| r.taut == taut)?;
        if !self.poses_within(m, g, &rest.poses, RIGID_REST_FRACTION) {
            return None;
        }
        // The rows there are known while their other inputs are unchanged.
        let known = rest.generation == self.constraint_inputs;
        let stepped = (!known).then(|| self.group_poses(m, g));
        self.set_group_poses(m, g, &rest.poses);
        let left = if known { rest.left } else { largest_abs(&self.group_rows(m, g, taut)) };
        if left > GAP_TOLERANCE_FRACTION * m.length_scale_m {
            if let Some(stepped) = stepped {
                self.set_group_poses(m, g, &stepped);
            }
            return None;
        }
        self.stop_bodies(m, &g.bodies);
        Some(left)
    }

    /// The group's rest at its current poses, closed there to `left` [m].
    pub(super) fn rigid_rest(&self, m: &Model, g: &ProjectedGroup, taut: &[usize], left: f64) -> RigidRest {
        RigidRest { poses: self.group_poses(m, g), taut: taut.to_vec(), left, generation: self.constraint_inputs }
    }

    /// The dense Jacobian of group `g`'s rows (no taut cables) by its coordinates, at the
    /// current poses and body Jacobians.
    pub(super) fn group_jacobian_dense(&self, m: &Model, g: &ProjectedGroup) -> nalgebra::DMatrix<f64> {
        let rows = g.joints.iter().map(|&j| self.joint_row_count(m, j)).sum();
        match GroupCoordinates::of(m, self, g).jacobian(m, self, g, &[], rows) {
            Jacobian::Dense(j) => j,
            Jacobian::Sparse(j) => j.matrix().to_dense(),
        }
    }

    /// The pose and velocities of every plain body of the projected groups.
    pub(super) fn projected_states(&self, m: &Model) -> Vec<(usize, Pose, Vector, Vector)> {
        let bodies = m.projected_groups.iter().flat_map(|g| g.bodies.iter().copied());
        bodies
            .map(|b| {
                let rb = &self.bodies[m.handles[b]];
                (b, *rb.position(), rb.linvel(), rb.angvel())
            })
            .collect()
    }

    /// Puts the bodies back as [`Self::projected_states`] read them. A Jacobian kept since is
    /// kept: formed where they started (or earlier), it is judged by where it was formed.
    pub(super) fn restore_projected_states(&mut self, m: &Model, states: Vec<(usize, Pose, Vector, Vector)>) {
        for (b, pose, v, w) in states {
            let rb = &mut self.bodies[m.handles[b]];
            rb.set_position(pose, true);
            rb.set_linvel(v, true);
            rb.set_angvel(w, true);
        }
    }

    pub(super) fn set_group_poses(&mut self, m: &Model, g: &ProjectedGroup, poses: &[Pose]) {
        for (&b, p) in g.bodies.iter().zip(poses) {
            self.bodies[m.handles[b]].set_position(*p, true);
        }
    }

    /// The poses of the group's plain bodies.
    pub(super) fn group_poses(&self, m: &Model, g: &ProjectedGroup) -> Vec<Pose> {
        g.bodies.iter().map(|&b| *self.bodies[m.handles[b]].position()).collect()
    }

    /// Whether every plain body of the group is within `fraction` of the structure's size of
    /// its pose in `poses` (rotations times the size).
    fn poses_within(&self, m: &Model, g: &ProjectedGroup, poses: &[Pose], fraction: f64) -> bool {
        let (scale, tol) = (m.length_scale_m, fraction * m.length_scale_m);
        g.bodies.iter().zip(poses).all(|(&b, p)| {
            let now = self.bodies[m.handles[b]].position();
            let turn = (now.rotation * p.rotation.inverse()).to_scaled_axis().length();
            (now.translation - p.translation).length() <= tol && turn * scale <= tol
        })
    }
}

/// The projection's own state: each projected group's Jacobian kept from its last projection
/// and its rigid rest, where it was last closed.
#[derive(Default)]
pub(super) struct Projection {
    kept_jacobians: Vec<Option<KeptJacobian>>,
    rigid_rests: Vec<Option<RigidRest>>,
}

impl Projection {
    /// Closes every projected group's joints and taut cables to round-off and projects the
    /// velocities of its bodies and multibodies. Returns the largest row left [m].
    pub(super) fn project_groups(&mut self, m: &Model, d: &mut Data) -> f64 {
        self.project_groups_to(m, d, GAP_TOLERANCE_FRACTION, f64::INFINITY).left
    }

    /// [`Self::project_groups`] to rows within `tolerance_fraction` of the structure's size;
    /// a group gives up once its first Gauss-Newton step shrinks its largest row by less than
    /// `max_first_contraction` ([`close_rows`]).
    pub(super) fn project_groups_to(
        &mut self,
        m: &Model,
        d: &mut Data,
        tolerance_fraction: f64,
        max_first_contraction: f64,
    ) -> Projected {
        self.project_groups_with(m, d, tolerance_fraction, max_first_contraction, false)
    }

    /// [`Self::project_groups_to`]; with `in_joint_coordinates`, a group that can be closed in
    /// its tree's joint coordinates is (`joint_coordinates.rs`).
    pub(super) fn project_groups_with(
        &mut self,
        m: &Model,
        d: &mut Data,
        tolerance_fraction: f64,
        max_first_contraction: f64,
        in_joint_coordinates: bool,
    ) -> Projected {
        let groups = &m.projected_groups;
        self.kept_jacobians.resize_with(groups.len(), || None);
        self.rigid_rests.resize_with(groups.len(), || None);
        let mut largest = Projected::default();
        for ((g, kept), rest) in groups.iter().zip(self.kept_jacobians.iter_mut()).zip(self.rigid_rests.iter_mut()) {
            let Some(taut) = d.projected_taut_cables(m, g) else { continue };
            let joint_closed = if in_joint_coordinates {
                d.close_in_joint_coordinates(m, g, &taut, kept, rest, max_first_contraction)
            } else {
                None
            };
            let p = match joint_closed {
                Some(p) => p,
                None => d.project_group(m, g, &taut, kept, rest, tolerance_fraction, max_first_contraction),
            };
            largest = largest.max(p);
        }
        largest
    }
}

/// A sparse group's Jacobian with its factorization, kept from one projection to the next: at
/// rest rapier's step opens the joints of a long chain by 1e-5 to 1e-3 of its size, and the
/// kept factorization closes them again in the chord iterations of [`close_rows`] without a
/// new one (the factorization was 30 % of a 10-module X chain's settle).
pub(super) struct KeptJacobian {
    jacobian: Jacobian,
    /// The group's plain bodies' poses where it was formed.
    poses: Vec<Pose>,
    /// The taut cables whose rows it has.
    taut: Vec<usize>,
}

/// Where a rigid group ([`Jacobian::rigid`]) was last closed to round-off: its plain bodies'
/// poses, the taut cables whose rows it closed, the largest row left there [m], and the
/// generation of the rows' other inputs then (`constraint_inputs` in `mod.rs`: locked
/// coordinates, cable lengths, fixed bodies' places). While that generation holds, the rows at
/// these poses are what they were: a function of the poses and those inputs.
pub(super) struct RigidRest {
    poses: Vec<Pose>,
    taut: Vec<usize>,
    left: f64,
    generation: u64,
}

/// A rigid group goes back to where it was last closed only from within this fraction of the
/// structure's size of it: well inside the moves that Gauss-Newton follows on one assembly
/// mode (a command jump's increments move a chain's joints by up to 5e-2 of its size), and
/// ten times the 1.5e-3 that rapier's step moves a 10-X chain at rest.
pub(super) const RIGID_REST_FRACTION: f64 = 1e-2;

/// A kept Jacobian removes the velocities only while every body is back within this fraction
/// of the structure's size of where it was formed: the velocities it leaves across the joints
/// are then this fraction of the velocities themselves (at rest, round-off), where one formed
/// a step of motion before would leave the step's displacement over the size.
const KEPT_POSE_TOLERANCE_FRACTION: f64 = 1e-10;

/// The coordinates of a projected group: per plain body a translation [m] and a rotation
/// vector times the structure's size [m], about the centre of mass; then each multibody's free
/// coordinates [m or rad].
struct GroupCoordinates {
    /// Six per plain body.
    n_plain: usize,
    /// Each multibody with its free degrees of freedom.
    multibodies: Vec<(MultibodyIndex, Vec<usize>)>,
    /// The structure's size [m], which scales rotations to lengths.
    scale: f64,
}

impl GroupCoordinates {
    /// The free coordinates, read from the multibodies' links (their indices hold from the
    /// build, which settled every root: `build.rs`).
    fn of(m: &Model, sim: &Data, g: &ProjectedGroup) -> Self {
        GroupCoordinates {
            n_plain: 6 * g.bodies.len(),
            multibodies: g.multibodies.iter().map(|&m| (m, sim.free_dofs(m))).collect(),
            scale: m.length_scale_m,
        }
    }

    fn count(&self) -> usize {
        self.n_plain + self.multibodies.iter().map(|(_, d)| d.len()).sum::<usize>()
    }

    /// The multibody and its degree of freedom behind coordinate k >= n_plain.
    fn multibody_dof(&self, k: usize) -> (MultibodyIndex, usize) {
        let mut k = k - self.n_plain;
        for (m, dofs) in &self.multibodies {
            if k < dofs.len() {
                return (*m, dofs[k]);
            }
            k -= dofs.len();
        }
        unreachable!("coordinate index within the group's count")
    }

    /// Moves every coordinate by `dq`.
    fn displace(&self, m: &Model, sim: &mut Data, g: &ProjectedGroup, dq: &[f64]) {
        if let Some(tree) = &g.tree {
            tree.displace(m, sim, &g.bodies, &dq[..self.n_plain], self.scale);
        } else {
            for (i, &b) in g.bodies.iter().enumerate() {
                let q = &dq[6 * i..6 * i + 6];
                sim.nudge(m, b, Vector::new(q[0], q[1], q[2]), Vector::new(q[3], q[4], q[5]) / self.scale);
            }
        }
        let mut k = self.n_plain;
        for (m, dofs) in &self.multibodies {
            let Some(mb) = sim.multibody_joints.get_multibody(*m) else { continue };
            let mut disp = vec![0.0; mb.ndofs()];
            for &dof in dofs {
                disp[dof] = dq[k];
                k += 1;
            }
            sim.displace(*m, &disp);
        }
    }

    /// The Jacobian of the group's `rows` rows from each coordinate's twists of the bodies it
    /// moves: a plain body's unit translation or rotation about its centre of mass, a
    /// multibody link's column of rapier's body Jacobian (centre-of-mass velocity and angular
    /// velocity).
    fn jacobian(&self, m: &Model, sim: &Data, g: &ProjectedGroup, taut: &[usize], rows: usize) -> Jacobian {
        if self.multibodies.is_empty() && self.n_plain >= SPARSE_MIN_COORDINATES {
            return Jacobian::sparse(self.sparse_jacobian(m, sim, g, taut, rows));
        }
        let ndof = self.count();
        let mut jac = nalgebra::DMatrix::<f64>::zeros(rows, ndof);
        let mut twists: Vec<Option<Twist>> = vec![None; m.structure.bodies.len()];
        for k in 0..ndof {
            twists.iter_mut().for_each(|t| *t = None);
            if k < self.n_plain {
                let b = g.bodies[k / 6];
                twists[b] = Some(self.unit_twist(m, sim, b, k % 6));
            } else {
                let (index, dof) = self.multibody_dof(k);
                let Some(mb) = sim.multibody_joints.get_multibody(index) else { continue };
                for (b, twist) in twists.iter_mut().enumerate() {
                    let h = m.handles[b];
                    let Some(link) = sim.multibody_joints.rigid_body_link(h).filter(|l| l.multibody == index) else {
                        continue;
                    };
                    let col = mb.body_jacobian(link.id).column(dof);
                    // A link the coordinate does not move (not below it in the tree).
                    if col.iter().all(|&x| x == 0.0) {
                        continue;
                    }
                    *twist = Some(Twist {
                        v: Vector::new(col[0], col[1], col[2]),
                        w: Vector::new(col[3], col[4], col[5]),
                        at: sim.bodies[h].center_of_mass(),
                    });
                }
            }
            let mut column = Vec::with_capacity(rows);
            sim.group_row_rates(m, g, taut, &|b| twists[b], &mut column);
            for (r, x) in column.into_iter().enumerate() {
                jac[(r, k)] = x;
            }
        }
        Jacobian::Dense(jac)
    }

    /// Plain body `b`'s motion per unit of its coordinate `k` (0..3 translation [m], 3..6
    /// rotation times the structure's size [m]) about its centre of mass.
    fn unit_twist(&self, m: &Model, sim: &Data, b: usize, k: usize) -> Twist {
        let mut q = [Vector::ZERO; 2];
        q[k / 3][k % 3] = 1.0;
        Twist { v: q[0], w: q[1] / self.scale, at: sim.world_com(m, b) }
    }

    /// The Jacobian of a group of plain bodies, member by member: each joint's or cable's rows
    /// depend only on the coordinates of its two bodies (twelve columns at most), so it costs
    /// in proportion to the members where the dense one costs rows times coordinates.
    fn sparse_jacobian(
        &self,
        m: &Model,
        sim: &Data,
        g: &ProjectedGroup,
        taut: &[usize],
        rows: usize,
    ) -> super::least_squares::SparseRows {
        let s = &m.structure;
        let mut position = vec![None; s.bodies.len()];
        for (i, &b) in g.bodies.iter().enumerate() {
            position[b] = Some(i);
        }
        // Each member's rows for a twist of one body: a joint's or a cable's.
        let joints =
            g.joints.iter().map(|&j| (Member::Joint(sim.joint_frame(m, j)), [s.joints[j].parent, s.joints[j].child]));
        let cables = taut
            .iter()
            .map(|&c| (Member::Cable(c), [s.nodes[s.members[c].ends().0].body, s.nodes[s.members[c].ends().1].body]));
        // At most two bodies' six twists per row.
        let (mut entries, mut first_row, mut block) = (Vec::with_capacity(12 * rows), 0, Vec::new());
        for (member, bodies) in joints.chain(cables) {
            let mut count = 0;
            for (b, i) in bodies.into_iter().filter_map(|b| position[b].map(|i| (b, i))) {
                for k in 0..6 {
                    let t = self.unit_twist(m, sim, b, k);
                    block.clear();
                    member.row_rates(m, sim, &|x| (x == b).then_some(t), &mut block);
                    entries.extend(block.iter().enumerate().map(|(r, &x)| (first_row + r, 6 * i + k, x)));
                    count = block.len();
                }
            }
            first_row += count;
        }
        debug_assert_eq!(first_row, rows, "one block of rows per member");
        super::least_squares::SparseRows::new(rows, self.n_plain, &entries)
    }

    /// The velocities in these coordinates: u = [v, w L] per plain body, then the
    /// multibodies' free generalized velocities.
    fn velocities(&self, m: &Model, sim: &Data, g: &ProjectedGroup) -> nalgebra::DVector<f64> {
        let ndof = self.count();
        let mut u = nalgebra::DVector::<f64>::zeros(ndof);
        for (i, &b) in g.bodies.iter().enumerate() {
            let rb = &sim.bodies[m.handles[b]];
            let (v, w) = (rb.linvel(), rb.angvel() * self.scale);
            for (r, x) in [v.x, v.y, v.z, w.x, w.y, w.z].into_iter().enumerate() {
                u[6 * i + r] = x;
            }
        }
        for k in self.n_plain..ndof {
            let (m, dof) = self.multibody_dof(k);
            u[k] = sim.multibody_joints.get_multibody(m).map_or(0.0, |mb| mb.generalized_velocity()[dof]);
        }
        u
    }

    /// Subtracts `du` (in these coordinates) from the bodies' and multibodies' velocities.
    fn remove_velocities(&self, m: &Model, sim: &mut Data, g: &ProjectedGroup, du: &nalgebra::DVector<f64>) {
        for (i, &b) in g.bodies.iter().enumerate() {
            let rb = &mut sim.bodies[m.handles[b]];
            let v = rb.linvel() - Vector::new(du[6 * i], du[6 * i + 1], du[6 * i + 2]);
            let w = rb.angvel() - Vector::new(du[6 * i + 3], du[6 * i + 4], du[6 * i + 5]) / self.scale;
            rb.set_linvel(v, true);
            rb.set_angvel(w, true);
        }
        for k in self.n_plain..self.count() {
            let (m, dof) = self.multibody_dof(k);
            if let Some(mb) = sim.multibody_joints.get_multibody_mut(m) {
                mb.generalized_velocity_mut()[dof] -= du[k];
            }
        }
    }
}

/// A member whose rows a projected group closes: a joint (its geometry at the current poses)
/// or a taut cable.
pub(super) enum Member {
    Joint(JointFrame),
    Cable(usize),
}

impl Member {
    pub(super) fn row_rates(&self, m: &Model, sim: &Data, twist: &dyn Fn(usize) -> Option<Twist>, out: &mut Vec<f64>) {
        match self {
            Member::Joint(frame) => frame.row_rates(twist, out),
            Member::Cable(c) => sim.cable_row_rate(m, *c, twist, out),
        }
    }
}

/// The root of `x` in the union-find forest `p`, halving the path on the way.
pub(super) fn find_root(p: &mut [usize], mut x: usize) -> usize {
    while p[x] != x {
        p[x] = p[p[x]];
        x = p[x];
    }
    x
}
