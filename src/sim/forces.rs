//! Member forces: applying the explicit ones every step, reading all of them back, and the
//! equilibrium residual computed from them independently of the solver.

use super::{MemberForces, Residual, Simulation};
use crate::structure::{ActuatorTarget, CableLaw, JointKind};
use rapier3d_f64::prelude::*;

type Wrench = (Vector, Vector); // (force, moment about the world origin)

/// A member whose force follows from its length: a spring (pushes and pulls) or an elastic
/// cable (pulls only).
pub(super) struct ElasticMember {
    pub(super) a: usize,
    pub(super) b: usize,
    pub(super) stiffness_n_per_m: f64,
    pub(super) rest_length_m: f64,
    pub(super) tension_only: bool,
}

impl ElasticMember {
    /// Whether the member carries force at length `l` [m] (a cable goes slack when not
    /// stretched).
    pub(super) fn engaged(&self, l: f64) -> bool {
        !self.tension_only || l > self.rest_length_m
    }

    /// Tension at length `l` [m]: k (l - l0), at least 0 for a cable [N].
    pub(super) fn tension_n(&self, l: f64) -> f64 {
        let t = self.stiffness_n_per_m * (l - self.rest_length_m);
        if self.tension_only {
            t.max(0.0)
        } else {
            t
        }
    }
}

fn v(a: [f64; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

impl Simulation {
    /// Puts the explicit forces (springs, elastic cables, probes) on the bodies for the next step.
    pub(super) fn apply_member_forces(&mut self) {
        let n = self.model.structure.bodies.len();
        for b in 0..n {
            let rb = &mut self.bodies[self.model.handles[b]];
            rb.reset_forces(false);
            rb.reset_torques(false);
        }
        for i in 0..self.model.structure.springs.len() + self.model.structure.cables.len() {
            if let Some(m) = self.elastic_member(i) {
                self.add_member_load(&m);
            }
        }
        for b in 0..n {
            let (mut f, t) = self.probe_loads[b];
            for k in 0..3 {
                f[k] += self.model.external_loads[b][k];
            }
            if self.is_free(b) && (f != [0.0; 3] || t != [0.0; 3]) {
                let rb = &mut self.bodies[self.model.handles[b]];
                rb.add_force(v(f), false);
                rb.add_torque(v(t), false);
            }
        }
    }

    /// Member `i` of the springs followed by the cables, if its force follows from its length
    /// (a spring, or an elastic cable at its current rest length).
    pub(super) fn elastic_member(&self, i: usize) -> Option<ElasticMember> {
        let s = &self.model.structure;
        if let Some(sp) = s.springs.get(i) {
            return Some(ElasticMember {
                a: sp.a,
                b: sp.b,
                stiffness_n_per_m: sp.stiffness_n_per_m,
                rest_length_m: sp.rest_length_m,
                tension_only: false,
            });
        }
        let c = i - s.springs.len();
        match s.cables.get(c)?.law {
            CableLaw::Elastic { stiffness_n_per_m } => Some(ElasticMember {
                a: s.cables[c].a,
                b: s.cables[c].b,
                stiffness_n_per_m,
                rest_length_m: self.cable_lengths[c],
                tension_only: true,
            }),
            CableLaw::Inextensible => None,
        }
    }

    /// Puts the tension of member `m` on the bodies of its two nodes, each as a force at the
    /// centre of mass plus its moment, with the centre of mass taken from the current pose:
    /// rapier's cached world centre of mass is stale before the first step, which gave a
    /// spurious kick of |c x F| there.
    fn add_member_load(&mut self, m: &ElasticMember) {
        let (a, b) = (m.a, m.b);
        let (pa, pb) = (v(self.node_position(a)), v(self.node_position(b)));
        let d = pb - pa;
        let l = d.length();
        let t = m.tension_n(l);
        if l > 0.0 && t != 0.0 {
            let f = d / l * t;
            for (node, f, p) in [(a, f, pa), (b, -f, pb)] {
                let body = self.model.structure.nodes[node].body;
                if self.is_free(body) {
                    let com = self.world_com(body);
                    let rb = &mut self.bodies[self.model.handles[body]];
                    rb.add_force(f, false);
                    rb.add_torque((p - com).cross(f), false);
                }
            }
        }
    }

    /// Torque of joint `j`'s torsion spring at the joint's current angle [N m]: -k (q - q_rest),
    /// q counted as the structure's coordinates are (initial coordinate plus the rotation since
    /// the build). Zero without a spring or off a revolute joint.
    pub(super) fn torsion_spring_torque(&self, j: usize) -> f64 {
        let joint = &self.model.structure.joints[j];
        let (Some(t), JointKind::Revolute { axis }) = (&joint.torsion_spring, &joint.kind) else { return 0.0 };
        let parent_rot = self.bodies[self.model.handles[joint.parent]].position().rotation;
        let child_rot = self.bodies[self.model.handles[joint.child]].position().rotation;
        let q = joint.initial_coordinate + relative_angle(parent_rot, child_rot, v(*axis));
        -t.stiffness_nm_per_rad * (q - t.rest_angle_rad)
    }

    /// World position of a free body's centre of mass, from its current pose [m].
    pub(super) fn world_com(&self, body: usize) -> Vector {
        let local = self.model.structure.bodies[body].inertia.map_or([0.0; 3], |i| i.com);
        self.bodies[self.model.handles[body]].position().transform_point(v(local))
    }

    /// Reads every member force and computes the equilibrium residual.
    pub fn member_forces(&self) -> MemberForces {
        self.member_forces_with(true)
    }

    /// Whether the member forces themselves need the fit of the loop-closure reactions: a
    /// joint actuator's force where loops close, or a cable held by the projection (`held`).
    fn forces_need_closure_fit(&self, held: &[bool]) -> bool {
        let closures = self.model.joint_impulse.iter().any(Option::is_some);
        let joint_actuators =
            self.model.structure.actuators.iter().any(|a| matches!(a.target, ActuatorTarget::Joint(_)));
        (closures && joint_actuators) || held.contains(&true)
    }

    /// Reads every member force; the equilibrium residual (a least-squares fit of the loop
    /// reactions, the costliest part) only when `with_residual` or when the forces need the fit.
    pub fn member_forces_with(&self, with_residual: bool) -> MemberForces {
        // Cables held at their length by the projection: their tension is fitted, not read.
        let held = self.cables_held_by_projection();
        let (mut out, mut wrench) = self.member_loads(&held);
        self.add_body_loads(&mut wrench);
        // Loop-closing joints carry reactions that no force law gives. They are the unknowns of
        // a least-squares fit: the reactions that best balance every free coordinate. At an
        // equilibrium the fit is exact and the residual is zero; the fitted reactions are
        // added to the bodies' loads.
        let fit = with_residual || self.forces_need_closure_fit(&held);
        let closure_reaction = if fit {
            self.fit_closure_reactions(&held, &mut wrench, &mut out)
        } else {
            vec![(Vector::ZERO, Vector::ZERO); self.model.structure.joints.len()]
        };
        if fit {
            out.residual = Some(self.residual_of(&held, &wrench, &out));
        }
        out.actuator_force = self.actuator_forces(&wrench, &closure_reaction, &out);
        out
    }

    /// Spring and cable forces at the current pose, and the wrench they put on each body
    /// (force, moment about the world origin).
    fn member_loads(&self, held: &[bool]) -> (MemberForces, Vec<Wrench>) {
        let s = &self.model.structure;
        let mut wrench: Vec<Wrench> = vec![(Vector::ZERO, Vector::ZERO); s.bodies.len()];
        // The member from node a to node b at its current length l pulls both ends with
        // `tension_at(l)`; returns (l, tension).
        let mut pull = |a: usize, b: usize, tension_at: &dyn Fn(f64) -> f64| -> (f64, f64) {
            let (pa, pb) = (v(self.node_position(a)), v(self.node_position(b)));
            let d = pb - pa;
            let l = d.length();
            let tension = tension_at(l);
            if l > 0.0 {
                let f = d / l * tension;
                for (node, f, p) in [(a, f, pa), (b, -f, pb)] {
                    let w = &mut wrench[s.nodes[node].body];
                    w.0 += f;
                    w.1 += p.cross(f);
                }
            }
            (l, tension)
        };
        let mut out = MemberForces::default();
        for (i, sp) in s.springs.iter().enumerate() {
            let m = self.elastic_member(i).expect("a spring is elastic");
            let (l, force) = pull(sp.a, sp.b, &|l| m.tension_n(l));
            out.spring_force_n.push(force);
            out.spring_length_m.push(l);
        }
        let inv_h = self.model.settings.substeps as f64 / self.model.settings.dt_s;
        for (c, cable) in s.cables.iter().enumerate() {
            let (l, tension) = match self.elastic_member(s.springs.len() + c) {
                Some(m) => pull(cable.a, cable.b, &|l| m.tension_n(l)),
                // Held at its length by the projection: its tension is fitted later.
                None if held[c] => pull(cable.a, cable.b, &|_| 0.0),
                None => {
                    let rope = self.model.cable_ropes[c]
                        .and_then(|h| self.impulse_joints.get(h))
                        .map(|j| j.data.limits[0].impulse.abs() * inv_h)
                        .unwrap_or(0.0);
                    pull(cable.a, cable.b, &|_| rope)
                }
            };
            out.cable_tension_n.push(tension);
            out.cable_length_m.push(l);
            out.cable_rest_length_m.push(self.cable_lengths[c]);
            out.cable_slack.push(tension <= 0.0);
        }
        (out, wrench)
    }

    /// Adds gravity, the probe loads and the constant external loads of every free body.
    fn add_body_loads(&self, wrench: &mut [Wrench]) {
        let s = &self.model.structure;
        let g = v(s.gravity);
        for (b, body) in s.bodies.iter().enumerate() {
            if self.is_free(b) {
                if let Some(i) = body.inertia {
                    let com = self.bodies[self.model.handles[b]].position().transform_point(v(i.com));
                    let f = g * i.mass_kg;
                    wrench[b].0 += f;
                    wrench[b].1 += com.cross(f);
                }
                let (mut pf, pt) = self.probe_loads[b];
                for k in 0..3 {
                    pf[k] += self.model.external_loads[b][k];
                }
                let com = self.world_com(b);
                wrench[b].0 += v(pf);
                wrench[b].1 += com.cross(v(pf)) + v(pt);
            }
        }
    }

    /// Fits the reactions of the loop-closing joints and the tensions of the held cables by
    /// least squares, adds them to `wrench` and `out`, and returns each closing joint's
    /// reaction on its child (force, moment about the anchor).
    fn fit_closure_reactions(&self, held: &[bool], wrench: &mut [Wrench], out: &mut MemberForces) -> Vec<Wrench> {
        let mut closure_loads = self.closure_unit_loads();
        closure_loads.extend(self.projected_cable_unit_loads(held));
        let mut closure_reaction = vec![(Vector::ZERO, Vector::ZERO); self.model.structure.joints.len()];
        let Some(lambda) = self.closure_magnitudes(&closure_loads, wrench) else {
            return closure_reaction;
        };
        for (k, load) in closure_loads.iter().enumerate() {
            for &(b, l) in &load.loads {
                wrench[b].0 += l.0 * lambda[k];
                wrench[b].1 += l.1 * lambda[k];
            }
            match load.member {
                ClosureMember::Joint(j) => {
                    closure_reaction[j].0 += load.force * lambda[k];
                    closure_reaction[j].1 += load.moment * lambda[k];
                }
                ClosureMember::Cable(c) => {
                    out.cable_tension_n[c] = lambda[k];
                    out.cable_slack[c] = lambda[k] <= 0.0;
                }
            }
        }
        closure_reaction
    }

    /// The magnitudes of the unit closure loads that best balance every free coordinate
    /// against `wrench` (least squares, minimum norm; torques divided by the structure's size);
    /// None when there is nothing to fit. Without multibody links each load moves only the
    /// coordinates of its own two bodies, and large fits take the sparse solve.
    fn closure_magnitudes(
        &self,
        closure_loads: &[ClosureComponent],
        wrench: &[Wrench],
    ) -> Option<nalgebra::DVector<f64>> {
        let tree = &self.model.tree;
        let scale = self.model.length_scale_m;
        let base = self.coordinate_forces(tree, wrench, true);
        if closure_loads.is_empty() || base.is_empty() {
            return None;
        }
        let scaled = |c: &CoordinateForce| if c.is_torque { c.value / scale } else { c.value };
        let r0 = nalgebra::DVector::<f64>::from_iterator(base.len(), base.iter().map(scaled));
        let no_links = self.model.joint_links.iter().all(Option::is_none);
        if no_links && closure_loads.len() >= SPARSE_MIN_CLOSURE_LOADS {
            let g = self.plain_closure_matrix(closure_loads, base.len());
            if let Some(lambda) = super::least_squares::sparse_min_norm_solve(g, &(-&r0)) {
                return Some(lambda);
            }
        }
        let nb = self.model.structure.bodies.len();
        let mut g = nalgebra::DMatrix::<f64>::zeros(base.len(), closure_loads.len());
        for (k, load) in closure_loads.iter().enumerate() {
            let mut loads = vec![(Vector::ZERO, Vector::ZERO); nb];
            for &(b, l) in &load.loads {
                loads[b].0 += l.0;
                loads[b].1 += l.1;
            }
            for (r, c) in self.coordinate_forces(tree, &loads, false).iter().enumerate() {
                g[(r, k)] = scaled(c);
            }
        }
        super::least_squares::min_norm_solve(&g, &(-r0), CLOSURE_SVD_RELATIVE_TOLERANCE)
    }

    /// The closure loads' generalized forces as a sparse matrix (coordinates x loads) where every
    /// free body is a plain body: six coordinates per free body in body order, as
    /// [`Self::coordinate_forces`] lists them (force, then moment about the centre of mass
    /// divided by the structure's size).
    fn plain_closure_matrix(
        &self,
        closure_loads: &[ClosureComponent],
        rows: usize,
    ) -> super::least_squares::SparseRows {
        let s = &self.model.structure;
        let mut first_row = vec![None; s.bodies.len()];
        let mut next = 0;
        for (b, r) in first_row.iter_mut().enumerate() {
            if self.is_free(b) {
                *r = Some(next);
                next += 6;
            }
        }
        let coms: Vec<Vector> = (0..s.bodies.len()).map(|b| self.world_com(b)).collect();
        let mut entries = Vec::new();
        for (k, load) in closure_loads.iter().enumerate() {
            for &(b, (f, m)) in &load.loads {
                let Some(r) = first_row[b] else { continue };
                let m = (m - coms[b].cross(f)) / self.model.length_scale_m;
                for (i, x) in [f.x, f.y, f.z, m.x, m.y, m.z].into_iter().enumerate() {
                    entries.push((r + i, k, x));
                }
            }
        }
        super::least_squares::SparseRows::new(rows, closure_loads.len(), &entries)
    }

    /// The largest generalized force left on a free coordinate once every load is on the
    /// bodies, and a held cable's push (a negative fitted tension: no equilibrium).
    fn residual_of(&self, held: &[bool], wrench: &[Wrench], out: &MemberForces) -> Residual {
        let s = &self.model.structure;
        let mut residual = Residual::default();
        for (c, cable) in s.cables.iter().enumerate() {
            if matches!(cable.law, CableLaw::Inextensible) && held[c] {
                residual.max_force_n = residual.max_force_n.max((-out.cable_tension_n[c]).max(0.0));
            }
        }
        for c in self.coordinate_forces(&self.model.tree, wrench, true) {
            if c.is_torque {
                residual.max_torque_nm = residual.max_torque_nm.max(c.value.abs());
            } else {
                residual.max_force_n = residual.max_force_n.max(c.value.abs());
            }
        }
        residual
    }

    /// Each actuator's force along its joint axis (or its cable's tension): minus the load of
    /// everything the actuated joint carries, or the fitted reaction of a joint locked off the
    /// tree.
    fn actuator_forces(&self, wrench: &[Wrench], closure_reaction: &[Wrench], out: &MemberForces) -> Vec<f64> {
        let s = &self.model.structure;
        let subtree = self.model.tree.subtree_wrenches(s, wrench);
        let about = |w: Wrench, p: Vector| -> Vector { w.1 - p.cross(w.0) };
        let along = |joint: &crate::structure::Joint, force: Vector, moment: Vector| {
            let parent_rot = self.bodies[self.model.handles[joint.parent]].position().rotation;
            match &joint.kind {
                JointKind::Revolute { axis } => moment.dot((parent_rot * v(*axis)).normalize()),
                JointKind::Prismatic { axis } => force.dot((parent_rot * v(*axis)).normalize()),
                _ => f64::NAN,
            }
        };
        s.actuators
            .iter()
            .map(|a| match a.target {
                ActuatorTarget::CableLength(c) => out.cable_tension_n[c],
                // The force that holds the moved body against its members, along the direction.
                ActuatorTarget::FixedNode { node, direction } => -wrench[s.nodes[node].body].0.dot(v(direction)),
                ActuatorTarget::Joint(j) if self.model.joint_impulse[j].is_some() => {
                    let (f, m) = closure_reaction[j];
                    along(&s.joints[j], f, m)
                }
                ActuatorTarget::Joint(j) => {
                    let joint = &s.joints[j];
                    let w = subtree[joint.child];
                    let anchor = v(self.node_position(joint.anchor));
                    -along(joint, w.0, about(w, anchor))
                }
            })
            .collect()
    }
}

/// Rotation angle of the child relative to the parent about `axis` (both bodies start at the
/// identity pose, so the relative rotation is parent^-1 child) [rad].
pub(crate) fn relative_angle(parent: Rotation, child: Rotation, axis: Vector) -> f64 {
    let rel = parent.inverse() * child;
    let axis = axis.normalize();
    let s = Vector::new(rel.x, rel.y, rel.z).dot(axis);
    2.0 * s.atan2(rel.w)
}

/// Fits of at least this many closure loads, on structures without multibody links, take the
/// sparse solve (`least_squares::sparse_min_norm_solve`): a dense one grows as the cube of the
/// loads (a chain of 20 furet2018 X modules cut into plain bodies has 340).
const SPARSE_MIN_CLOSURE_LOADS: usize = 48;

/// Singular values below this fraction of the largest are treated as zero when fitting the
/// reactions of loop-closing joints (redundant closures).
const CLOSURE_SVD_RELATIVE_TOLERANCE: f64 = 1e-12;

/// What carries an unknown reaction: a loop-closing joint, or an inextensible cable held at its
/// length by the projection (its tension).
#[derive(Clone, Copy, Debug)]
enum ClosureMember {
    Joint(usize),
    Cable(usize),
}

/// One unknown reaction component of a loop-closing joint: a unit force or moment on the child
/// (and its opposite on the parent), as body loads; or the unit tension of a held cable.
struct ClosureComponent {
    member: ClosureMember,
    force: Vector,
    moment: Vector,
    /// The two bodies it loads and their wrenches (force, moment about the world origin).
    loads: [(usize, Wrench); 2],
}

/// One free coordinate's generalized force: a force [N] or a torque [N m].
#[derive(Clone, Copy, Debug)]
struct CoordinateForce {
    value: f64,
    is_torque: bool,
}

/// The tree of joints that carry bodies (multibody links and actuator drives).
#[derive(Clone, Debug, Default)]
pub(super) struct Tree {
    /// The joint each body hangs from, if any.
    parent_joint: Vec<Option<usize>>,
}

impl Tree {
    pub(super) fn descends_from(&self, s: &crate::structure::Structure, mut b: usize, ancestor: usize) -> bool {
        for _ in 0..=self.parent_joint.len() {
            if b == ancestor {
                return true;
            }
            match self.parent_joint[b] {
                Some(j) => b = s.joints[j].parent,
                None => return false,
            }
        }
        false
    }

    /// Number of joints between body `b` and the root of its tree.
    pub(super) fn depth(&self, s: &crate::structure::Structure, mut b: usize) -> usize {
        let mut depth = 0;
        while let (Some(j), true) = (self.parent_joint[b], depth < self.parent_joint.len()) {
            depth += 1;
            b = s.joints[j].parent;
        }
        depth
    }

    /// For every body, the sum of the wrenches of it and of every body hanging from it: each
    /// body's sum handed to its parent, deepest bodies first (one pass, where a search of every
    /// body's descendants for each joint grew with the cube of a chain's length).
    fn subtree_wrenches(&self, s: &crate::structure::Structure, wrench: &[Wrench]) -> Vec<Wrench> {
        let mut order: Vec<(usize, usize)> = (0..wrench.len()).map(|b| (self.depth(s, b), b)).collect();
        order.sort_unstable_by(|a, b| b.cmp(a));
        let mut sums = wrench.to_vec();
        for (_, b) in order {
            if let Some(j) = self.parent_joint[b] {
                let (w, p) = (sums[b], s.joints[j].parent);
                sums[p].0 += w.0;
                sums[p].1 += w.1;
            }
        }
        sums
    }
}

impl Simulation {
    /// The tree of the multibody links: the joint each body hangs from.
    pub(super) fn link_tree(&self) -> Tree {
        let s = &self.model.structure;
        let mut parent_joint: Vec<Option<usize>> = vec![None; s.bodies.len()];
        for (j, joint) in s.joints.iter().enumerate() {
            if self.model.joint_links[j].is_some() {
                parent_joint[joint.child] = Some(j);
            }
        }
        Tree { parent_joint }
    }

    /// Generalized force on every free coordinate for the body loads `wrench` (force, moment
    /// about the world origin), torsion springs included when `with_springs`.
    fn coordinate_forces(&self, tree: &Tree, wrench: &[Wrench], with_springs: bool) -> Vec<CoordinateForce> {
        let s = &self.model.structure;
        let about = |w: Wrench, p: Vector| -> Vector { w.1 - p.cross(w.0) };
        let force = |value: f64| CoordinateForce { value, is_torque: false };
        let torque = |value: f64| CoordinateForce { value, is_torque: true };
        let subtree = tree.subtree_wrenches(s, wrench);
        let mut out = Vec::new();
        for (j, joint) in s.joints.iter().enumerate() {
            // Only the free coordinates: an actuated joint's coordinate is set, not balanced.
            if self.model.joint_links[j].is_none() || self.model.actuated[j] {
                continue;
            }
            let w = subtree[joint.child];
            let anchor = v(self.node_position(joint.anchor));
            let parent_rot = self.bodies[self.model.handles[joint.parent]].position().rotation;
            let child_rot = self.bodies[self.model.handles[joint.child]].position().rotation;
            let m = about(w, anchor);
            match &joint.kind {
                JointKind::Revolute { axis } => {
                    let a = (parent_rot * v(*axis)).normalize();
                    // A torsion spring on this joint is a generalized force on its coordinate.
                    let spring = if with_springs { self.torsion_spring_torque(j) } else { 0.0 };
                    out.push(torque(m.dot(a) + spring));
                }
                JointKind::Prismatic { axis } => {
                    out.push(force(w.0.dot((parent_rot * v(*axis)).normalize())));
                }
                JointKind::Universal { axis1, axis2 } => {
                    out.push(torque(m.dot((parent_rot * v(*axis1)).normalize())));
                    out.push(torque(m.dot((child_rot * v(*axis2)).normalize())));
                }
                JointKind::Spherical => {
                    out.extend([torque(m.x), torque(m.y), torque(m.z)]);
                }
                JointKind::Fixed | JointKind::PlanarPin { .. } => {}
            }
        }
        // Free bodies with no parent joint: all six coordinates.
        for b in 0..s.bodies.len() {
            if self.is_free(b) && tree.parent_joint[b].is_none() {
                let w = subtree[b];
                let m = about(w, self.world_com(b));
                out.extend([force(w.0.x), force(w.0.y), force(w.0.z), torque(m.x), torque(m.y), torque(m.z)]);
            }
        }
        out
    }

    /// For every inextensible cable held at its length by the projection: the body loads of a
    /// unit tension (pulling its two nodes together).
    fn projected_cable_unit_loads(&self, held: &[bool]) -> Vec<ClosureComponent> {
        let s = &self.model.structure;
        let mut out = Vec::new();
        for (c, cable) in s.cables.iter().enumerate() {
            if !held[c] {
                continue;
            }
            let (pa, pb) = (v(self.node_position(cable.a)), v(self.node_position(cable.b)));
            let d = (pb - pa).normalize();
            let (ba, bb) = (s.nodes[cable.a].body, s.nodes[cable.b].body);
            let w = [(ba, (d, pa.cross(d))), (bb, (-d, -pb.cross(d)))];
            out.push(ClosureComponent { member: ClosureMember::Cable(c), force: d, moment: Vector::ZERO, loads: w });
        }
        out
    }

    /// For every reaction component of every loop-closing joint: the body loads of a unit
    /// reaction (child +, parent -), world frame.
    fn closure_unit_loads(&self) -> Vec<ClosureComponent> {
        let s = &self.model.structure;
        let axes = [Vector::X, Vector::Y, Vector::Z];
        let mut out = Vec::new();
        for (j, joint) in s.joints.iter().enumerate() {
            if self.model.joint_impulse[j].is_none() {
                continue;
            }
            let anchor = v(self.node_position(joint.anchor));
            let parent_rot = self.bodies[self.model.handles[joint.parent]].position().rotation;
            let child_rot = self.bodies[self.model.handles[joint.child]].position().rotation;
            // Directions the joint transmits: forces, then moments.
            let (forces, moments): (Vec<Vector>, Vec<Vector>) = match &joint.kind {
                JointKind::Spherical => (axes.to_vec(), vec![]),
                // An actuated (locked) revolute also carries the torque about its axis.
                JointKind::Revolute { axis } if self.model.actuated[j] => (axes.to_vec(), axes.to_vec()),
                JointKind::Prismatic { .. } if self.model.actuated[j] => (axes.to_vec(), axes.to_vec()),
                JointKind::Revolute { axis } => {
                    let a = (parent_rot * v(*axis)).normalize();
                    (axes.to_vec(), orthogonal_pair(a).to_vec())
                }
                JointKind::Prismatic { axis } => {
                    let a = (parent_rot * v(*axis)).normalize();
                    (orthogonal_pair(a).to_vec(), axes.to_vec())
                }
                JointKind::Universal { axis1, axis2 } => {
                    let a1 = (parent_rot * v(*axis1)).normalize();
                    let a2 = (child_rot * v(*axis2)).normalize();
                    (axes.to_vec(), vec![a1.cross(a2).normalize()])
                }
                JointKind::Fixed => (axes.to_vec(), axes.to_vec()),
                JointKind::PlanarPin { axis } => {
                    let a = (parent_rot * v(*axis)).normalize();
                    (orthogonal_pair(a).to_vec(), vec![])
                }
            };
            for f in forces {
                let w = [(joint.child, (f, anchor.cross(f))), (joint.parent, (-f, -anchor.cross(f)))];
                out.push(ClosureComponent {
                    member: ClosureMember::Joint(j),
                    force: f,
                    moment: Vector::ZERO,
                    loads: w,
                });
            }
            for m in moments {
                let w = [(joint.child, (Vector::ZERO, m)), (joint.parent, (Vector::ZERO, -m))];
                out.push(ClosureComponent {
                    member: ClosureMember::Joint(j),
                    force: Vector::ZERO,
                    moment: m,
                    loads: w,
                });
            }
        }
        out
    }
}

/// Two unit vectors orthogonal to `a` and to each other.
pub(super) fn orthogonal_pair(a: Vector) -> [Vector; 2] {
    let helper = if a.x.abs() < 0.9 { Vector::X } else { Vector::Y };
    let u = a.cross(helper).normalize();
    [u, a.cross(u)]
}
