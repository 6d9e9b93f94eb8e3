//! Position projection of loop closures that lie inside one multibody.
//!
//! A closed planar loop (furet2018's crossed four-bar) stays inside its multibody and is closed
//! by an impulse joint (a planar pin). rapier holds such a joint only at the velocity level: its
//! anchors drift apart by an offset that grows with the time step and with every jump of an
//! actuator (3.7e-5 m measured on furet2018, FINDINGS.md). After each step this module moves
//! the multibody's free coordinates q (Gauss-Newton on the closure gap g(q), Jacobian by finite
//! differences of the multibody's own forward kinematics) until every such loop is closed to
//! round-off, then removes the velocity component that would open it again
//! (qdot -= J^+ J qdot). The joints that are cut between multibodies keep rapier's treatment.

use super::Simulation;
use crate::structure::JointKind;
use rapier3d_f64::prelude::*;

/// Gauss-Newton iterations at most per step.
const MAX_ITERATIONS: usize = 20;

/// The projection stops when the largest gap is below this fraction of the structure's size.
const GAP_TOLERANCE_FRACTION: f64 = 1e-14;

/// Finite-difference step of a free coordinate (rad or m).
const FD_STEP: f64 = 1e-7;

/// Singular values of the closure Jacobian below this fraction of the largest are treated as
/// zero (redundant closure rows).
const SVD_RELATIVE_TOLERANCE: f64 = 1e-10;

/// The minimum-norm least-squares solution x of `a x = b`, singular values below
/// [`SVD_RELATIVE_TOLERANCE`] of the largest dropped (redundant rows).
fn min_norm_solve(a: &nalgebra::DMatrix<f64>, b: &nalgebra::DVector<f64>) -> Option<nalgebra::DVector<f64>> {
    let svd = a.clone().svd(true, true);
    let cut = SVD_RELATIVE_TOLERANCE * svd.singular_values.max();
    svd.solve(b, cut).ok()
}

/// Gauss-Newton onto a constraint manifold of `ndof` coordinates: `rows` evaluates the
/// constraint rows [m]; `probe(sim, k, h)` evaluates them with coordinate k moved by h and puts
/// the state back (each caller restores in its own exact way); `displace` moves every coordinate
/// by a step. Iterates until every row is within [`GAP_TOLERANCE_FRACTION`] of the structure's
/// size (at most [`MAX_ITERATIONS`]); returns the Jacobian at the last point (forward
/// differences) and the largest row left.
fn close_rows(
    sim: &mut Simulation,
    ndof: usize,
    rows: &dyn Fn(&Simulation) -> Vec<f64>,
    probe: &dyn Fn(&mut Simulation, usize, f64) -> Vec<f64>,
    displace: &dyn Fn(&mut Simulation, &[f64]),
) -> (nalgebra::DMatrix<f64>, f64) {
    let largest = |g: &[f64]| g.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let tol = GAP_TOLERANCE_FRACTION * sim.length_scale_m;
    let mut jac = nalgebra::DMatrix::<f64>::zeros(0, ndof);
    for _ in 0..MAX_ITERATIONS {
        let g0 = rows(sim);
        if g0.is_empty() {
            break;
        }
        jac = nalgebra::DMatrix::<f64>::zeros(g0.len(), ndof);
        for k in 0..ndof {
            for (row, (gi, g0i)) in probe(sim, k, FD_STEP).iter().zip(&g0).enumerate() {
                jac[(row, k)] = (gi - g0i) / FD_STEP;
            }
        }
        if largest(&g0) <= tol {
            break;
        }
        let Some(dq) = min_norm_solve(&jac, &-nalgebra::DVector::from_vec(g0)) else { break };
        displace(sim, dq.as_slice());
    }
    let left = largest(&rows(sim));
    (jac, left)
}

/// A loop-closing joint inside one multibody: the rows of its gap that the projection zeroes.
#[derive(Clone, Debug)]
pub(super) struct InternalClosure {
    joint: usize,
    multibody: MultibodyIndex,
}

impl Simulation {
    /// The loop-closing joints whose two bodies are links of the same multibody.
    pub(super) fn find_internal_closures(&self) -> Vec<InternalClosure> {
        let mut out = Vec::new();
        for (j, joint) in self.structure.joints.iter().enumerate() {
            if self.joint_impulse[j].is_none() || !matches!(joint.kind, JointKind::PlanarPin { .. }) {
                continue;
            }
            let link = |b: usize| self.multibody_joints.rigid_body_link(self.handles[b]).map(|l| l.multibody);
            if let (Some(a), Some(b)) = (link(joint.parent), link(joint.child)) {
                if a == b {
                    out.push(InternalClosure { joint: j, multibody: a });
                }
            }
        }
        out
    }

    /// The gap rows of one closure: the anchor as carried by the child minus as carried by the
    /// parent, in the plane normal to the pin axis (two rows) [m].
    fn closure_rows(&self, c: &InternalClosure, out: &mut Vec<f64>) {
        let j = &self.structure.joints[c.joint];
        let a = self.structure.nodes[j.anchor].position;
        let a = Vector::new(a[0], a[1], a[2]);
        let parent = self.bodies[self.handles[j.parent]].position();
        let child = self.bodies[self.handles[j.child]].position();
        let gap = child.transform_point(a) - parent.transform_point(a);
        let JointKind::PlanarPin { axis } = j.kind else { return };
        let n = (parent.rotation * Vector::new(axis[0], axis[1], axis[2])).normalize();
        for t in super::forces::orthogonal_pair(n) {
            out.push(gap.dot(t));
        }
    }

    fn closure_gaps(&self, closures: &[InternalClosure], multibody: MultibodyIndex) -> Vec<f64> {
        let mut rows = Vec::new();
        for c in closures.iter().filter(|c| c.multibody == multibody) {
            self.closure_rows(c, &mut rows);
        }
        rows
    }

    /// Moves the multibody's coordinates by `disp` and places its bodies there.
    fn displace(&mut self, multibody: MultibodyIndex, disp: &[f64]) {
        if let Some(mb) = self.multibody_joints.get_multibody_mut(multibody) {
            mb.apply_displacements(disp);
            mb.forward_kinematics(&self.bodies, false);
            mb.update_rigid_bodies(&mut self.bodies, true);
        }
    }

    /// Closes every loop inside a multibody to round-off and projects the velocities onto the
    /// closures' tangent space. Returns the largest gap left [m].
    pub(super) fn project_internal_closures(&mut self) -> f64 {
        let closures = std::mem::take(&mut self.internal_closures);
        let mut largest = 0.0_f64;
        let mut multibodies: Vec<MultibodyIndex> = Vec::new();
        for c in &closures {
            if !multibodies.contains(&c.multibody) {
                multibodies.push(c.multibody);
            }
        }
        for &mb_index in &multibodies {
            let Some(mb) = self.multibody_joints.get_multibody(mb_index) else { continue };
            let ndofs = mb.ndofs();
            // The free coordinates: every degree of freedom of a link that no actuator sets.
            let free: Vec<usize> = mb
                .links()
                .filter(|l| !l.joint().kinematic)
                .flat_map(|l| l.assembly_id()..l.assembly_id() + l.joint().ndofs())
                .collect();
            if free.is_empty() {
                continue;
            }
            // Coordinates of the projection: the free degrees of freedom, in order.
            let displace_free = |sim: &mut Simulation, dq: &[f64]| {
                let mut disp = vec![0.0; ndofs];
                for (d, &dof) in dq.iter().zip(&free) {
                    disp[dof] = *d;
                }
                sim.displace(mb_index, &disp);
            };
            let gaps = |sim: &Simulation| sim.closure_gaps(&closures, mb_index);
            // A probe moves one free coordinate and back.
            let probe = |sim: &mut Simulation, k: usize, h: f64| {
                let mut dq = vec![0.0; free.len()];
                dq[k] = h;
                displace_free(sim, &dq);
                let g = gaps(sim);
                dq[k] = -h;
                displace_free(sim, &dq);
                g
            };
            let (jac, left) = close_rows(self, free.len(), &gaps, &probe, &displace_free);
            largest = largest.max(left);
            // Velocities: remove the part that opens the loops, qdot -= J^+ (J qdot).
            if jac.nrows() > 0 {
                if let Some(mb) = self.multibody_joints.get_multibody_mut(mb_index) {
                    let v = nalgebra::DVector::from_iterator(
                        free.len(),
                        free.iter().map(|&d| mb.generalized_velocity()[d]),
                    );
                    let jv = &jac * &v;
                    if let Some(dv) = min_norm_solve(&jac, &jv) {
                        let mut gv = mb.generalized_velocity_mut();
                        for (col, &dof) in free.iter().enumerate() {
                            gv[dof] -= dv[col];
                        }
                    }
                }
            }
        }
        self.internal_closures = closures;
        largest
    }
}

/// Plain free bodies (not multibody links) held by impulse joints and inextensible cables to
/// each other or to fixed bodies: a group whose constraints the projection can close.
///
/// rapier holds these constraints at the velocity level too; under a steady load (gravity on
/// manriquez2019's platform) the position offset it leaves grows like dt^2 and shrank only
/// slowly with PGS iterations (3e-5 rad at dt = 2 ms). After each step the group's body poses
/// are moved (Gauss-Newton, minimum norm, rotations scaled by the structure's size) until every
/// joint's anchor gap and angular rows and every taut cable's stretch vanish to round-off; the
/// velocities lose the components that would open a joint or stretch a taut cable. Member
/// forces are still read from rapier (cable tensions from the rope impulses).
#[derive(Clone, Debug, Default)]
pub(super) struct PlainGroup {
    /// Structure body indices of the group's free plain bodies.
    bodies: Vec<usize>,
    /// Impulse joints (structure indices) between the group's bodies or to fixed bodies.
    joints: Vec<usize>,
    /// Inextensible cables with a rope joint.
    cables: Vec<usize>,
}

/// A cable within this fraction of the structure's size of its length counts as taut.
const TAUT_TOLERANCE_FRACTION: f64 = 1e-12;

impl Simulation {
    /// A rope cable is taut when stretched to its length (within round-off) or when rapier's
    /// rope pulled in the last step.
    fn cable_is_taut(&self, c: usize) -> bool {
        let cable = &self.structure.cables[c];
        let l = crate::structure::distance(self.node_position(cable.a), self.node_position(cable.b));
        let inv_h = self.settings.substeps as f64 / self.settings.dt_s;
        let impulse = self.cable_ropes[c]
            .and_then(|h| self.impulse_joints.get(h))
            .map_or(0.0, |j| j.data.limits[0].impulse.abs() * inv_h);
        l >= self.cable_lengths[c] - TAUT_TOLERANCE_FRACTION * self.length_scale_m || impulse > 0.0
    }

    /// Whether cable `c` is taut and held at its length by the plain-group projection (its
    /// tension is then fitted from the equilibrium, not read from rapier's impulse).
    pub(super) fn cable_held_by_projection(&self, c: usize) -> bool {
        self.plain_groups.iter().any(|g| g.cables.contains(&c)) && self.cable_is_taut(c)
    }

    /// Groups of plain free bodies whose every constraint the projection handles. A group that
    /// touches a multibody link, an actuated joint or a joint kind without projection rows is
    /// left to rapier alone.
    pub(super) fn find_plain_groups(&self) -> Vec<PlainGroup> {
        let s = &self.structure;
        let n = s.bodies.len();
        let plain = |b: usize| self.is_free(b) && self.multibody_joints.rigid_body_link(self.handles[b]).is_none();
        let fixed = |b: usize| s.bodies[b].kind == crate::structure::BodyKind::Fixed;
        // Union-find over bodies joined by a constraint.
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut edges: Vec<(usize, usize)> = Vec::new();
        for (j, joint) in s.joints.iter().enumerate() {
            if self.joint_impulse[j].is_some() {
                edges.push((joint.parent, joint.child));
            }
        }
        for (c, cable) in s.cables.iter().enumerate() {
            if self.cable_ropes[c].is_some() {
                edges.push((s.nodes[cable.a].body, s.nodes[cable.b].body));
            }
        }
        for &(a, b) in &edges {
            if !fixed(a) && !fixed(b) {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra] = rb;
            }
        }
        let mut groups: Vec<(usize, PlainGroup, bool)> = Vec::new();
        let group_of = |root: usize, groups: &mut Vec<(usize, PlainGroup, bool)>| -> usize {
            if let Some(i) = groups.iter().position(|g| g.0 == root) {
                i
            } else {
                groups.push((root, PlainGroup::default(), true));
                groups.len() - 1
            }
        };
        let movable = |b: usize| if fixed(b) { None } else { Some(b) };
        for (j, joint) in s.joints.iter().enumerate() {
            if self.joint_impulse[j].is_none() {
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
            groups[g].2 &= supported && !self.actuated[j];
        }
        for (c, cable) in s.cables.iter().enumerate() {
            if self.cable_ropes[c].is_none() {
                continue;
            }
            let (a, b) = (s.nodes[cable.a].body, s.nodes[cable.b].body);
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
                g.1.bodies.push(b);
                g.2 &= plain(b);
            }
        }
        groups.into_iter().filter(|(_, g, ok)| *ok && !g.bodies.is_empty()).map(|(_, g, _)| g).collect()
    }

    /// The constraint rows of a plain group: joint anchor gaps and angular rows, then the
    /// stretch of each cable in `taut`. Lengths in m; angular rows (dimensionless) times the
    /// structure's size, so that every row is a length.
    fn plain_rows(&self, g: &PlainGroup, taut: &[usize], out: &mut Vec<f64>) {
        let s = &self.structure;
        let scale = self.length_scale_m;
        let pose = |b: usize| *self.bodies[self.handles[b]].position();
        let vec3 = |a: [f64; 3]| Vector::new(a[0], a[1], a[2]);
        for &j in &g.joints {
            let joint = &s.joints[j];
            let (pp, pc) = (pose(joint.parent), pose(joint.child));
            let a = vec3(s.nodes[joint.anchor].position);
            let gap = pc.transform_point(a) - pp.transform_point(a);
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
                }
                JointKind::Universal { axis1, axis2 } => {
                    out.extend([gap.x, gap.y, gap.z]);
                    let a1 = pp.rotation * vec3(axis1).normalize();
                    let a2 = pc.rotation * vec3(axis2).normalize();
                    out.push((a1.dot(a2) - vec3(axis1).normalize().dot(vec3(axis2).normalize())) * scale);
                }
                _ => out.extend([gap.x, gap.y, gap.z]),
            }
        }
        for &c in taut {
            let cable = &s.cables[c];
            let (pa, pb) = (self.node_position(cable.a), self.node_position(cable.b));
            out.push(crate::structure::distance(pa, pb) - self.cable_lengths[c]);
        }
    }

    /// Moves body `b` by a translation `t` [m] and a rotation `r` [rad, rotation vector] about
    /// its centre of mass.
    fn nudge(&mut self, b: usize, t: Vector, r: Vector) {
        let com = self.world_com(b);
        let h = self.handles[b];
        let pose = *self.bodies[h].position();
        let moved = Pose::from_translation(com + t)
            * Pose::from_rotation(Rotation::from_scaled_axis(r))
            * Pose::from_translation(-com)
            * pose;
        self.bodies[h].set_position(moved, true);
    }

    /// Closes every plain group's joints and taut cables to round-off and projects the bodies'
    /// velocities. Returns the largest row left [m].
    pub(super) fn project_plain_groups(&mut self) -> f64 {
        let groups = std::mem::take(&mut self.plain_groups);
        let scale = self.length_scale_m;
        let mut largest = 0.0_f64;
        for g in &groups {
            let taut: Vec<usize> = g.cables.iter().copied().filter(|&c| self.cable_is_taut(c)).collect();
            let ndof = 6 * g.bodies.len();
            // Coordinates of the projection: per body a translation [m] and a rotation vector
            // times the structure's size [m], about the centre of mass.
            let nudge_all = |sim: &mut Simulation, dq: &[f64]| {
                for (i, &b) in g.bodies.iter().enumerate() {
                    let q = &dq[6 * i..6 * i + 6];
                    sim.nudge(b, Vector::new(q[0], q[1], q[2]), Vector::new(q[3], q[4], q[5]) / scale);
                }
            };
            let rows = |sim: &Simulation| {
                let mut out = Vec::new();
                sim.plain_rows(g, &taut, &mut out);
                out
            };
            // A probe nudges one body along one coordinate and restores its pose exactly.
            let probe = |sim: &mut Simulation, k: usize, h: f64| {
                let b = g.bodies[k / 6];
                let saved = *sim.bodies[sim.handles[b]].position();
                let mut q = [0.0; 6];
                q[k % 6] = h;
                sim.nudge(b, Vector::new(q[0], q[1], q[2]), Vector::new(q[3], q[4], q[5]) / scale);
                let out = rows(sim);
                sim.bodies[sim.handles[b]].set_position(saved, true);
                out
            };
            let (jac, left) = close_rows(self, ndof, &rows, &probe, &nudge_all);
            largest = largest.max(left);
            if jac.nrows() == 0 {
                continue;
            }
            // Velocities u = [v, w L] per body: remove J^+ (J u) over every row, taut cables
            // included (they were just held at their length: a cable goes slack when rapier's
            // rope stops pulling, and is then no longer taut here).
            let u = nalgebra::DVector::from_iterator(
                ndof,
                g.bodies.iter().flat_map(|&b| {
                    let rb = &self.bodies[self.handles[b]];
                    let (v, w) = (rb.linvel(), rb.angvel() * scale);
                    [v.x, v.y, v.z, w.x, w.y, w.z]
                }),
            );
            if let Some(du) = min_norm_solve(&jac, &(&jac * &u)) {
                for (i, &b) in g.bodies.iter().enumerate() {
                    let rb = &mut self.bodies[self.handles[b]];
                    let v = rb.linvel() - Vector::new(du[6 * i], du[6 * i + 1], du[6 * i + 2]);
                    let w = rb.angvel() - Vector::new(du[6 * i + 3], du[6 * i + 4], du[6 * i + 5]) / scale;
                    rb.set_linvel(v, true);
                    rb.set_angvel(w, true);
                }
            }
        }
        self.plain_groups = groups;
        largest
    }
}
