//! Member forces: applying the explicit ones every step, reading all of them back, and the
//! equilibrium residual computed from them independently of the solver.

use super::data::Data;
use super::least_squares::SparseRows;
use super::model::{Model, Tree};
use crate::snapshot::{MemberForces, Residual};
use crate::structure::{ActuatorTarget, ElasticLaw, JointKind, MemberKind};
use rapier3d_f64::prelude::*;

/// (force, moment about the world origin)
pub(super) type Wrench = (Vector, Vector);

fn v(a: [f64; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

impl Data {
    /// Puts the explicit forces (springs, elastic cables, probes) on the bodies for the next step.
    pub(super) fn apply_member_forces(&mut self, m: &Model) {
        let n = m.structure.bodies.len();
        for b in 0..n {
            let rb = &mut self.bodies[m.handles[b]];
            rb.reset_forces(false);
            rb.reset_torques(false);
        }
        for (i, _) in m.structure.members_by_kind() {
            if let Some(law) = self.elastic_law(m, i) {
                self.add_member_load(m, i, &law);
            }
        }
        for b in 0..n {
            let (mut f, t) = self.probe_loads[b];
            for (fk, e) in f.iter_mut().zip(m.external_loads[b]) {
                *fk += e;
            }
            if m.is_free(b) && (f != [0.0; 3] || t != [0.0; 3]) {
                let rb = &mut self.bodies[m.handles[b]];
                rb.add_force(v(f), false);
                rb.add_torque(v(t), false);
            }
        }
        for &(node, force) in &m.node_loads {
            let b = m.structure.nodes[node].body;
            let arm = v(self.node_position(m, node)) - self.world_com(m, b);
            let f = Vector::new(force.x, force.y, force.z);
            let rb = &mut self.bodies[m.handles[b]];
            rb.add_force(f, false);
            rb.add_torque(arm.cross(f), false);
        }
    }

    /// Member `i`'s law if its force follows from its length (a spring, or an elastic cable
    /// at its current rest length).
    pub(super) fn elastic_law(&self, m: &Model, i: usize) -> Option<ElasticLaw> {
        m.structure.members[i].elastic_law(self.rest_lengths[i])
    }

    /// Puts the tension of member `i` on the bodies of its path's nodes, each segment pulling
    /// its two ends, as a force at the centre of mass plus its moment, with the centre of mass
    /// taken from the current pose: rapier's cached world centre of mass is stale before the
    /// first step, which gave a spurious kick of |c x F| there.
    fn add_member_load(&mut self, m: &Model, i: usize, law: &ElasticLaw) {
        let member = &m.structure.members[i];
        // The path's length sets the tension: a straight member's is its one segment's.
        let path_m = member.is_clustered().then(|| self.member_length_m(m, i));
        let segment_laws = self.segment_laws(m, i);
        for (k, (a, b)) in member.segments().enumerate() {
            let (pa, pb) = (v(self.node_position(m, a)), v(self.node_position(m, b)));
            let d = pb - pa;
            let l = d.length();
            // A cable with friction: each segment its own tension (`capstan.rs`).
            let t = match &segment_laws {
                Some(laws) => laws[k].tension_n(l),
                None => law.tension_n(path_m.unwrap_or(l)),
            };
            if l > 0.0 && t != 0.0 {
                let f = d / l * t;
                for (node, f, p) in [(a, f, pa), (b, -f, pb)] {
                    let body = m.structure.nodes[node].body;
                    if m.is_free(body) {
                        let com = self.world_com(m, body);
                        let rb = &mut self.bodies[m.handles[body]];
                        rb.add_force(f, false);
                        rb.add_torque((p - com).cross(f), false);
                    }
                }
            }
        }
    }

    /// Member `i`'s length now, the sum of its segments' \[m\].
    pub(super) fn member_length_m(&self, m: &Model, i: usize) -> f64 {
        m.structure.members[i].length_at(|n| self.node_position(m, n))
    }

    /// Torque of joint `j`'s torsion spring at the joint's current angle [N m]: -k (q - q_rest),
    /// q counted as the structure's coordinates are (initial coordinate plus the rotation since
    /// the build). Zero without a spring or off a revolute joint.
    pub(super) fn torsion_spring_torque(&self, m: &Model, j: usize) -> f64 {
        let joint = &m.structure.joints[j];
        let (Some((k, rest)), JointKind::Revolute { axis }) = (self.torsion_spring_now(m, j), &joint.kind) else {
            return 0.0;
        };
        let parent_rot = self.bodies[m.handles[joint.parent]].position().rotation;
        let child_rot = self.bodies[m.handles[joint.child]].position().rotation;
        let q = joint.initial_coordinate + relative_angle(parent_rot, child_rot, v(*axis));
        -k * (q - rest)
    }

    /// World position of a free body's centre of mass, from its current pose [m].
    pub(super) fn world_com(&self, m: &Model, body: usize) -> Vector {
        let local = m.structure.bodies[body].inertia.map_or([0.0; 3], |i| i.com);
        self.bodies[m.handles[body]].position().transform_point(v(local))
    }

    /// Reads every member force and computes the equilibrium residual.
    pub fn member_forces(&self, m: &Model) -> MemberForces {
        self.member_forces_with(m, true)
    }

    /// Whether the member forces themselves need the fit of the loop-closure reactions: a
    /// joint actuator's force where loops close, or a cable held by the projection (`held`).
    fn forces_need_closure_fit(&self, m: &Model, held: &[bool]) -> bool {
        let closures = m.joint_impulse.iter().any(Option::is_some);
        let joint_actuators = m.structure.actuators.iter().any(|a| matches!(a.target, ActuatorTarget::Joint(_)));
        (closures && joint_actuators) || held.contains(&true)
    }

    /// Reads every member force; the equilibrium residual (a least-squares fit of the loop
    /// reactions, the costliest part) only when `with_residual` or when the forces need the fit.
    pub fn member_forces_with(&self, m: &Model, with_residual: bool) -> MemberForces {
        // Cables held at their length by the projection: their tension is fitted, not read.
        let held = self.cables_held_by_projection(m);
        let (mut out, mut wrench) = self.member_loads(m, &held);
        self.add_body_loads(m, &mut wrench);
        // Loop-closing joints carry reactions that no force law gives. They are the unknowns of
        // a least-squares fit: the reactions that best balance every free coordinate. At an
        // equilibrium the fit is exact and the residual is zero; the fitted reactions are
        // added to the bodies' loads.
        let fit = with_residual || self.forces_need_closure_fit(m, &held);
        let closure_reaction = if fit {
            self.fit_closure_reactions(m, &held, &mut wrench, &mut out)
        } else {
            vec![(Vector::ZERO, Vector::ZERO); m.structure.joints.len()]
        };
        if fit {
            out.residual = Some(self.residual_of(m, &held, &wrench, &out));
        }
        out.actuator_force = self.actuator_forces(m, &wrench, &closure_reaction, &out);
        out
    }

    /// Spring and cable forces at the current pose, and the wrench they put on each body
    /// (force, moment about the world origin).
    fn member_loads(&self, m: &Model, held: &[bool]) -> (MemberForces, Vec<Wrench>) {
        let s = &m.structure;
        let mut wrench: Vec<Wrench> = vec![(Vector::ZERO, Vector::ZERO); s.bodies.len()];
        // Member i at its current length l pulls both ends of every segment with
        // `tension_at(l)` (a cable with friction, each segment with its own law); returns
        // (l, tension, each segment's tension if it has more than one).
        let mut pull = |i: usize, tension_at: &dyn Fn(f64) -> f64| -> (f64, f64, Vec<f64>) {
            // The path's length sets the tension: a straight member's is its one segment's.
            let path_m = s.members[i].is_clustered().then(|| self.member_length_m(m, i));
            let (mut l, mut tension) = (0.0, 0.0);
            let segment_laws = self.segment_laws(m, i);
            let mut segments = Vec::new();
            for (k, (a, b)) in s.members[i].segments().enumerate() {
                let (pa, pb) = (v(self.node_position(m, a)), v(self.node_position(m, b)));
                let d = pb - pa;
                let segment = d.length();
                l = path_m.unwrap_or(segment);
                tension = match &segment_laws {
                    Some(laws) => laws[k].tension_n(segment),
                    None => tension_at(l),
                };
                if s.members[i].is_clustered() {
                    segments.push(tension);
                }
                if segment > 0.0 {
                    let f = d / segment * tension;
                    for (node, f, p) in [(a, f, pa), (b, -f, pb)] {
                        let w = &mut wrench[s.nodes[node].body];
                        w.0 += f;
                        w.1 += p.cross(f);
                    }
                }
            }
            (l, tension, segments)
        };
        let count = s.members.len();
        let mut out = MemberForces {
            force_n: vec![0.0; count],
            length_m: vec![0.0; count],
            rest_length_m: self.rest_lengths.clone(),
            slack: vec![false; count],
            segment_force_n: vec![Vec::new(); count],
            at_friction_bound: self.at_bound.clone(),
            ..MemberForces::default()
        };
        let inv_h = m.settings.substeps as f64 / m.settings.dt_s;
        for (i, member) in s.members_by_kind() {
            let (l, force, segments) = match (member.kind(), self.elastic_law(m, i)) {
                (MemberKind::Strut, None) => (self.member_length_m(m, i), 0.0, Vec::new()),
                (_, Some(law)) => pull(i, &|l| law.tension_n(l)),
                // Held at its length by the projection: its tension is fitted later.
                (_, None) if held[i] => pull(i, &|_| 0.0),
                (_, None) => {
                    let rope = m.ropes[i]
                        .and_then(|h| self.impulse_joints.get(h))
                        .map(|j| j.data.limits[0].impulse.abs() * inv_h)
                        .unwrap_or(0.0);
                    pull(i, &|_| rope)
                }
            };
            out.force_n[i] = force;
            out.length_m[i] = l;
            let taut = force > 0.0 || segments.iter().any(|&t| t > 0.0);
            out.slack[i] = member.kind() == MemberKind::Cable && !taut;
            out.segment_force_n[i] = segments;
        }
        (out, wrench)
    }

    /// Adds gravity, the probe loads and the constant external loads of every free body.
    fn add_body_loads(&self, m: &Model, wrench: &mut [Wrench]) {
        let s = &m.structure;
        let g = v(s.gravity);
        for (b, body) in s.bodies.iter().enumerate() {
            if m.is_free(b) {
                if let Some(i) = body.inertia {
                    let com = self.bodies[m.handles[b]].position().transform_point(v(i.com));
                    let f = g * i.mass_kg;
                    wrench[b].0 += f;
                    wrench[b].1 += com.cross(f);
                }
                let (mut pf, pt) = self.probe_loads[b];
                for (fk, e) in pf.iter_mut().zip(m.external_loads[b]) {
                    *fk += e;
                }
                let com = self.world_com(m, b);
                wrench[b].0 += v(pf);
                wrench[b].1 += com.cross(v(pf)) + v(pt);
            }
        }
        for &(node, force) in &m.node_loads {
            let b = m.structure.nodes[node].body;
            let f = Vector::new(force.x, force.y, force.z);
            wrench[b].0 += f;
            wrench[b].1 += v(self.node_position(m, node)).cross(f);
        }
    }

    /// Fits the reactions of the loop-closing joints and the tensions of the held cables by
    /// least squares, adds them to `wrench` and `out`, and returns each closing joint's
    /// reaction on its child (force, moment about the anchor).
    fn fit_closure_reactions(
        &self,
        m: &Model,
        held: &[bool],
        wrench: &mut [Wrench],
        out: &mut MemberForces,
    ) -> Vec<Wrench> {
        let mut closure_loads = self.closure_unit_loads(m);
        closure_loads.extend(self.projected_cable_unit_loads(m, held));
        let mut closure_reaction = vec![(Vector::ZERO, Vector::ZERO); m.structure.joints.len()];
        let Some(lambda) = self.closure_magnitudes(m, &closure_loads, wrench) else {
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
                    out.force_n[c] = lambda[k];
                    out.slack[c] = lambda[k] <= 0.0;
                }
            }
        }
        closure_reaction
    }

    /// The magnitudes of the unit closure loads that best balance every free coordinate
    /// against `wrench` (least squares, minimum norm; torques divided by the structure's size);
    /// None when there is nothing to fit. The coordinates are the fit tree's (`tree.rs`): the
    /// tree joints' turns and the free roots' six. Without multibody links each load moves only
    /// the coordinates on the tree path between its two bodies, and large fits, or fits on a
    /// group's tree, take the sparse solve.
    fn closure_magnitudes(
        &self,
        m: &Model,
        closure_loads: &[ClosureComponent],
        wrench: &[Wrench],
    ) -> Option<nalgebra::DVector<f64>> {
        let tree = &m.fit_tree;
        let scale = m.length_scale_m;
        let base = self.coordinate_forces(m, tree, wrench, true);
        if closure_loads.is_empty() || base.is_empty() {
            return None;
        }
        let scaled = |c: &CoordinateForce| if c.is_torque { c.value / scale } else { c.value };
        let r0 = nalgebra::DVector::<f64>::from_iterator(base.len(), base.iter().map(scaled));
        let no_links = m.joint_links.iter().all(Option::is_none);
        if no_links && (closure_loads.len() >= SPARSE_MIN_CLOSURE_LOADS || tree.has_group_links()) {
            let g = self.tree_closure_matrix(m, tree, closure_loads, base.len());
            if let Some(lambda) = super::least_squares::sparse_min_norm_solve(g, &(-&r0)) {
                return Some(lambda);
            }
        }
        let nb = m.structure.bodies.len();
        let mut g = nalgebra::DMatrix::<f64>::zeros(base.len(), closure_loads.len());
        for (k, load) in closure_loads.iter().enumerate() {
            let mut loads = vec![(Vector::ZERO, Vector::ZERO); nb];
            for &(b, l) in &load.loads {
                loads[b].0 += l.0;
                loads[b].1 += l.1;
            }
            for (r, c) in self.coordinate_forces(m, tree, &loads, false).iter().enumerate() {
                g[(r, k)] = scaled(c);
            }
        }
        super::least_squares::min_norm_solve(&g, &(-r0), CLOSURE_SVD_RELATIVE_TOLERANCE)
    }

    /// The closure loads' generalized forces on the coordinates of `tree` as a sparse matrix
    /// (coordinates x loads, torques divided by the structure's size), in the order of
    /// [`Self::coordinate_forces`]. Every closure load is balanced (a reaction and its
    /// opposite, or a tension pulling two nodes together), so it adds nothing above the point
    /// where the tree paths up from its two bodies meet: it moves only the coordinates on the
    /// path between them, and a free root's where a path ends at one. Without tree joints each
    /// load moves the six coordinates of each of its two bodies.
    fn tree_closure_matrix(
        &self,
        m: &Model,
        tree: &Tree,
        closure_loads: &[ClosureComponent],
        rows: usize,
    ) -> SparseRows {
        let scale = m.length_scale_m;
        let (joint_row, root_row) = self.coordinate_rows(m, tree);
        let free = |b: usize| m.is_free(b).then_some(b);
        let (mut entries, mut values) = (Vec::new(), Vec::new());
        for (k, load) in closure_loads.iter().enumerate() {
            let mut side = load.loads.map(|(b, w)| (free(b), w));
            loop {
                let i = match (side[0].0, side[1].0) {
                    (Some(a), Some(b)) if a == b => break,
                    (Some(a), Some(b)) => usize::from(tree.depth(a) < tree.depth(b)),
                    (Some(_), None) => 0,
                    (None, Some(_)) => 1,
                    (None, None) => break,
                };
                let (Some(b), w) = side[i] else { break };
                values.clear();
                let (first, up) = match tree.hang(b) {
                    Some(h) => {
                        if joint_row[h.joint].is_some() {
                            self.joint_coordinate_forces(m, h.joint, w, &mut values);
                        }
                        (joint_row[h.joint], free(h.parent))
                    }
                    None => {
                        self.root_coordinate_forces(m, b, w, &mut values);
                        (root_row[b], None)
                    }
                };
                if let Some(first) = first {
                    let scaled = values.iter().map(|c| if c.is_torque { c.value / scale } else { c.value });
                    entries.extend(scaled.enumerate().map(|(r, x)| (first + r, k, x)));
                }
                side[i].0 = up;
            }
        }
        debug_assert!(joint_row.iter().chain(&root_row).flatten().all(|&r| r < rows), "rows as coordinate_forces");
        SparseRows::new(rows, closure_loads.len(), &entries)
    }

    /// The first row of each tree joint's free coordinates (joint order) and of each free
    /// root's six (body order), as [`Self::coordinate_forces`] lists them.
    fn coordinate_rows(&self, m: &Model, tree: &Tree) -> (Vec<Option<usize>>, Vec<Option<usize>>) {
        let s = &m.structure;
        let mut next = 0;
        let mut at = |count: usize| {
            next += count;
            Some(next - count)
        };
        let joint_row = (0..s.joints.len())
            .map(|j| match tree.carried(j).filter(|_| !m.actuated[j]) {
                Some(_) => at(s.joints[j].kind.coordinate_count()),
                None => None,
            })
            .collect();
        let root_row =
            (0..s.bodies.len()).map(|b| (m.is_free(b) && tree.hang(b).is_none()).then(|| at(6)).flatten()).collect();
        (joint_row, root_row)
    }

    /// The largest generalized force left on a free coordinate once every load is on the
    /// bodies, and a held cable's push (a negative fitted tension: no equilibrium).
    fn residual_of(&self, m: &Model, held: &[bool], wrench: &[Wrench], out: &MemberForces) -> Residual {
        let s = &m.structure;
        let mut residual = Residual::default();
        for (c, cable) in s.members_of(MemberKind::Cable) {
            if cable.is_inextensible_cable() && held[c] {
                residual.max_force_n = residual.max_force_n.max((-out.force_n[c]).max(0.0));
            }
        }
        let forces = self.coordinate_forces(m, &m.fit_tree, wrench, true);
        let held = self.held_rows(m, &m.fit_tree, forces.len());
        for (_, c) in forces.into_iter().enumerate().filter(|(r, _)| !held[*r]) {
            if c.is_torque {
                residual.max_torque_nm = residual.max_torque_nm.max(c.value.abs());
            } else {
                residual.max_force_n = residual.max_force_n.max(c.value.abs());
            }
        }
        residual
    }

    /// Whether each row of [`Self::coordinate_forces`] is held by a support (a free root's
    /// translation along a held axis): the support takes its force, as its reaction.
    fn held_rows(&self, m: &Model, tree: &Tree, rows: usize) -> Vec<bool> {
        let (_, root_row) = self.coordinate_rows(m, tree);
        let mut held = vec![false; rows];
        for (row, axes) in root_row.iter().zip(&m.held_translations) {
            let Some(r) = *row else { continue };
            (0..3).filter(|&x| axes[x]).for_each(|x| held[r + x] = true);
        }
        held
    }

    /// Each actuator's force along its joint axis (or its cable's tension): minus the load of
    /// everything the actuated joint carries, or the fitted reaction of a joint locked off the
    /// fit tree.
    fn actuator_forces(
        &self,
        m: &Model,
        wrench: &[Wrench],
        closure_reaction: &[Wrench],
        out: &MemberForces,
    ) -> Vec<f64> {
        let s = &m.structure;
        let tree = &m.fit_tree;
        let subtree = tree.subtree_wrenches(wrench);
        let along = |joint: &crate::structure::Joint, force: Vector, moment: Vector| {
            let parent_rot = self.bodies[m.handles[joint.parent]].position().rotation;
            match &joint.kind {
                JointKind::Revolute { axis } => moment.dot((parent_rot * v(*axis)).normalize()),
                JointKind::Prismatic { axis } => force.dot((parent_rot * v(*axis)).normalize()),
                _ => f64::NAN,
            }
        };
        s.actuators
            .iter()
            .map(|a| match a.target {
                ActuatorTarget::CableLength(c) => out.force_n[c],
                // The force that holds the moved body against its members, along the direction.
                ActuatorTarget::FixedNode { node, direction } => -wrench[s.nodes[node].body].0.dot(v(direction)),
                ActuatorTarget::Joint(j) if m.joint_impulse[j].is_some() && tree.carried(j).is_none() => {
                    let (f, m) = closure_reaction[j];
                    along(&s.joints[j], f, m)
                }
                // A tree joint: the reaction on its child balances what the carried side
                // receives (the child's side, or the parent's where a group's tree runs the
                // joint backwards).
                ActuatorTarget::Joint(j) => {
                    let joint = &s.joints[j];
                    let carried = tree.carried(j).unwrap_or(joint.child);
                    let w = subtree[carried];
                    let on_carried = along(joint, w.0, about(w, v(self.node_position(m, joint.anchor))));
                    if carried == joint.child {
                        -on_carried
                    } else {
                        on_carried
                    }
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

impl Data {
    /// Every free coordinate's generalized force for the loads now, in the link tree's order:
    /// the free joints' in joint order, then six per free root (`sensitivity.rs`).
    pub(super) fn free_coordinate_forces(&self, m: &Model) -> Vec<f64> {
        let held = vec![false; m.structure.members.len()];
        let (_, mut wrench) = self.member_loads(m, &held);
        self.add_body_loads(m, &mut wrench);
        self.coordinate_forces(m, &m.tree, &wrench, true).into_iter().map(|f| f.value).collect()
    }

    /// Generalized force on every free coordinate of `tree` for the body loads `wrench`
    /// (force, moment about the world origin), torsion springs included when `with_springs`:
    /// each tree joint's turns (slide) in joint order, then all six coordinates of each free
    /// root in body order.
    fn coordinate_forces(&self, m: &Model, tree: &Tree, wrench: &[Wrench], with_springs: bool) -> Vec<CoordinateForce> {
        let s = &m.structure;
        let subtree = tree.subtree_wrenches(wrench);
        let mut out = Vec::new();
        for j in 0..s.joints.len() {
            // Only the free coordinates: an actuated joint's coordinate is set, not balanced.
            let Some(b) = tree.carried(j).filter(|_| !m.actuated[j]) else { continue };
            let first = out.len();
            self.joint_coordinate_forces(m, j, subtree[b], &mut out);
            // A torsion spring on this joint is a generalized force on its coordinate.
            if with_springs && matches!(s.joints[j].kind, JointKind::Revolute { .. }) {
                out[first].value += self.torsion_spring_torque(m, j);
            }
        }
        for (b, &w) in subtree.iter().enumerate() {
            if m.is_free(b) && tree.hang(b).is_none() {
                self.root_coordinate_forces(m, b, w, &mut out);
            }
        }
        out
    }

    /// The generalized forces on joint `j`'s coordinates of the wrench `w` its carried
    /// bodies receive: the moment about its anchor along each axis it turns about, or the
    /// force along its slide.
    fn joint_coordinate_forces(&self, m: &Model, j: usize, w: Wrench, out: &mut Vec<CoordinateForce>) {
        let joint = &m.structure.joints[j];
        let torque = |value: f64| CoordinateForce { value, is_torque: true };
        let rotation = |b: usize| self.bodies[m.handles[b]].position().rotation;
        let moment = about(w, v(self.node_position(m, joint.anchor)));
        match &joint.kind {
            JointKind::Revolute { axis } => {
                out.push(torque(moment.dot((rotation(joint.parent) * v(*axis)).normalize())))
            }
            JointKind::Prismatic { axis } => out.push(CoordinateForce {
                value: w.0.dot((rotation(joint.parent) * v(*axis)).normalize()),
                is_torque: false,
            }),
            JointKind::Universal { axis1, axis2 } => {
                out.push(torque(moment.dot((rotation(joint.parent) * v(*axis1)).normalize())));
                out.push(torque(moment.dot((rotation(joint.child) * v(*axis2)).normalize())));
            }
            JointKind::Spherical => out.extend([torque(moment.x), torque(moment.y), torque(moment.z)]),
            JointKind::Fixed | JointKind::PlanarPin { .. } => {}
        }
    }

    /// A free root's six generalized forces of the wrench `w` on it and what hangs from it:
    /// the force, then the moment about its centre of mass.
    fn root_coordinate_forces(&self, m: &Model, b: usize, w: Wrench, out: &mut Vec<CoordinateForce>) {
        let force = |value: f64| CoordinateForce { value, is_torque: false };
        let torque = |value: f64| CoordinateForce { value, is_torque: true };
        let moment = about(w, self.world_com(m, b));
        out.extend([force(w.0.x), force(w.0.y), force(w.0.z), torque(moment.x), torque(moment.y), torque(moment.z)]);
    }

    /// For every inextensible cable held at its length by the projection: the body loads of a
    /// unit tension (pulling its two nodes together).
    fn projected_cable_unit_loads(&self, m: &Model, held: &[bool]) -> Vec<ClosureComponent> {
        let s = &m.structure;
        let mut out = Vec::new();
        // Only a straight cable is inextensible (a clustered one has a stiffness).
        for (c, cable) in s.members_of(MemberKind::Cable) {
            if !held[c] {
                continue;
            }
            let (a, b) = cable.ends();
            let (pa, pb) = (v(self.node_position(m, a)), v(self.node_position(m, b)));
            let d = (pb - pa).normalize();
            let (ba, bb) = (s.nodes[a].body, s.nodes[b].body);
            let w = [(ba, (d, pa.cross(d))), (bb, (-d, -pb.cross(d)))];
            out.push(ClosureComponent { member: ClosureMember::Cable(c), force: d, moment: Vector::ZERO, loads: w });
        }
        out
    }

    /// For every reaction component of every loop-closing joint: the body loads of a unit
    /// reaction (child +, parent -), world frame.
    fn closure_unit_loads(&self, m: &Model) -> Vec<ClosureComponent> {
        let s = &m.structure;
        let axes = [Vector::X, Vector::Y, Vector::Z];
        let mut out = Vec::new();
        for (j, joint) in s.joints.iter().enumerate() {
            // A joint of the fit tree carries its reaction by recursion (`tree.rs`).
            if m.joint_impulse[j].is_none() || m.fit_tree.carried(j).is_some() {
                continue;
            }
            let anchor = v(self.node_position(m, joint.anchor));
            let parent_rot = self.bodies[m.handles[joint.parent]].position().rotation;
            let child_rot = self.bodies[m.handles[joint.child]].position().rotation;
            // Directions the joint transmits: forces, then moments.
            let (forces, moments): (Vec<Vector>, Vec<Vector>) = match &joint.kind {
                JointKind::Spherical => (axes.to_vec(), vec![]),
                // An actuated (locked) revolute also carries the torque about its axis.
                JointKind::Revolute { axis } if m.actuated[j] => (axes.to_vec(), axes.to_vec()),
                JointKind::Prismatic { .. } if m.actuated[j] => (axes.to_vec(), axes.to_vec()),
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

/// The moment of wrench `w` (force, moment about the world origin) about point `p`.
fn about(w: Wrench, p: Vector) -> Vector {
    w.1 - p.cross(w.0)
}

/// Two unit vectors orthogonal to `a` and to each other.
pub(super) fn orthogonal_pair(a: Vector) -> [Vector; 2] {
    let helper = if a.x.abs() < 0.9 { Vector::X } else { Vector::Y };
    let u = a.cross(helper).normalize();
    [u, a.cross(u)]
}
