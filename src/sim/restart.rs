//! Restarting a built simulation from another placement of its structure, instead of building
//! the rapier sets again (a grid without continuation starts every point from the scenario's
//! start state: the same structure, its joints at other coordinates).
//!
//! Only structures whose every joint is a revolute or prismatic multibody link qualify (no
//! loop closures, no ropes, no plain free bodies): their placement is their joint coordinates.
//! The restarted state is checked against the new structure (every node, centre of mass and
//! inertia tensor); anything else, or a failed check, asks the caller to build afresh.

use super::data::Data;
use super::model::Model;
use crate::structure::{JointKind, Structure};
use rapier3d_f64::prelude::*;

/// Largest distance between a restarted node (or centre of mass) and the new structure's,
/// relative to the structure's size: round-off of the joint transforms, far below any
/// checked tolerance (1e-9).
const PLACEMENT_TOLERANCE: f64 = 1e-12;

/// A node placing a revolute joint's child must lie at least this far from the joint's axis,
/// relative to the structure's size, for its angle about the axis to be well defined.
const OFF_AXIS_FRACTION: f64 = 1e-3;

impl Structure {
    /// Whether `other` is this structure in another placement: the same bodies, members,
    /// joints, actuators, loads and parameters; only node positions, centres of mass, joint
    /// axes and initial coordinates (all of the initial configuration) may differ.
    pub fn same_but_placement(&self, other: &Structure) -> bool {
        let same_body = |a: &crate::structure::Body, b: &crate::structure::Body| {
            a.name == b.name
                && a.kind == b.kind
                && match (a.inertia, b.inertia) {
                    (Some(i), Some(j)) => i.mass_kg == j.mass_kg,
                    (None, None) => true,
                    _ => false,
                }
        };
        let same_node = |a: &crate::structure::Node, b: &crate::structure::Node| a.name == b.name && a.body == b.body;
        let same_joint = |a: &crate::structure::Joint, b: &crate::structure::Joint| {
            let kind = match (&a.kind, &b.kind) {
                (JointKind::Revolute { .. }, JointKind::Revolute { .. })
                | (JointKind::Prismatic { .. }, JointKind::Prismatic { .. }) => true,
                (k, l) => k == l,
            };
            kind && a.name == b.name
                && a.parent == b.parent
                && a.child == b.child
                && a.anchor == b.anchor
                && a.torsion_spring == b.torsion_spring
                && a.damping == b.damping
        };
        fn all<T>(a: &[T], b: &[T], same: impl Fn(&T, &T) -> bool) -> bool {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same(x, y))
        }
        self.name == other.name
            && self.gravity == other.gravity
            && self.members == other.members
            && self.actuators == other.actuators
            && self.loads == other.loads
            && self.node_loads == other.node_loads
            && self.supports == other.supports
            && all(&self.bodies, &other.bodies, same_body)
            && all(&self.nodes, &other.nodes, same_node)
            && all(&self.joints, &other.joints, same_joint)
    }
}

impl Data {
    /// Whether the placement of this structure is its joint coordinates alone.
    pub(super) fn restartable(&self, m: &Model) -> bool {
        let s = &m.structure;
        m.hidden_links.is_empty()
            && m.internal_closures.is_empty()
            && m.projected_groups.is_empty()
            && m.ropes.iter().all(Option::is_none)
            && m.joint_impulse.iter().all(Option::is_none)
            && s.joints
                .iter()
                .zip(&m.joint_links)
                .all(|(j, l)| l.is_some() && matches!(j.kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. }))
            && s.unjointed_free_bodies().is_empty()
    }

    /// Turns every free joint, parents first, so that a node of its child lands where `s`
    /// has it, stops every body, and checks that the state reproduces `s`.
    pub(super) fn place_free_joints(&mut self, m: &Model, s: &Structure) -> bool {
        let mut order: Vec<usize> = (0..s.joints.len()).filter(|j| !m.actuated[*j]).collect();
        order.sort_by_key(|&j| m.tree.depth(s.joints[j].child));
        for j in order {
            if !self.place_free_joint(m, j, s) {
                return false;
            }
        }
        for link in m.joint_links.iter().flatten() {
            if let Some((mb, _)) = self.multibody_joints.get_mut(link.multibody_joint) {
                mb.generalized_velocity_mut().fill(0.0);
            }
        }
        self.zero_body_velocities(m);
        self.reproduces(m, s)
    }

    /// Moves free joint `j` so that a node of its child body (off the axis, for a revolute)
    /// lands where `s` places it; false when the child has no such node.
    fn place_free_joint(&mut self, m: &Model, j: usize, s: &Structure) -> bool {
        let Some(motion) = self.joint_motion(m, j) else { return false };
        let child = m.structure.joints[j].child;
        let off_axis = |x: Vector| (x - motion.anchor).reject_from_normalized(motion.axis);
        let scale = m.length_scale_m;
        let node = (0..m.structure.nodes.len()).find(|&n| {
            m.structure.nodes[n].body == child
                && (!motion.revolute
                    || off_axis(Vector::from(self.node_position(m, n))).length() > OFF_AXIS_FRACTION * scale)
        });
        let Some(n) = node else { return false };
        let (now, wanted) = (Vector::from(self.node_position(m, n)), Vector::from(s.nodes[n].position));
        let displacement = if motion.revolute {
            let (a, b) = (off_axis(now), off_axis(wanted));
            motion.axis.dot(a.cross(b)).atan2(a.dot(b))
        } else {
            (wanted - now).dot(motion.axis)
        };
        let Some((m, dof)) = self.dof_of(m, j) else { return false };
        let Some(mb) = self.multibody_joints.get_multibody_mut(m) else { return false };
        let mut disp = vec![0.0; mb.ndofs()];
        disp[dof] = displacement;
        mb.apply_displacements(&disp);
        mb.forward_kinematics(&self.bodies, true);
        mb.update_rigid_bodies(&mut self.bodies, true);
        true
    }

    /// Whether every node, free body's centre of mass and inertia tensor is where `s` has it.
    fn reproduces(&self, m: &Model, s: &Structure) -> bool {
        let tol = PLACEMENT_TOLERANCE * m.length_scale_m;
        let close = |a: Vector, b: [f64; 3]| (a - Vector::from(b)).length() <= tol;
        let nodes = (0..s.nodes.len()).all(|i| close(Vector::from(self.node_position(m, i)), s.nodes[i].position));
        let bodies = (0..s.bodies.len()).filter(|b| m.is_free(*b)).all(|b| {
            let (Some(now), Some(then)) = (m.structure.bodies[b].inertia, s.bodies[b].inertia) else {
                return false;
            };
            let rotation = self.bodies[m.handles[b]].position().rotation;
            // The inertia tensor now, R diag(I) R^T, against the new structure's diag(I').
            let scale = then.principal_kg_m2.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            let axes = [Vector::X, Vector::Y, Vector::Z];
            let tensor_ok = axes.iter().enumerate().all(|(r, er)| {
                axes.iter().enumerate().all(|(c, ec)| {
                    let (lr, lc) = (rotation.inverse() * *er, rotation.inverse() * *ec);
                    let p = now.principal_kg_m2;
                    let value = p[0] * lr.x * lc.x + p[1] * lr.y * lc.y + p[2] * lr.z * lc.z;
                    let wanted = if r == c { then.principal_kg_m2[r] } else { 0.0 };
                    (value - wanted).abs() <= PLACEMENT_TOLERANCE * scale
                })
            });
            close(self.world_com(m, b), then.com) && tensor_ok
        });
        nodes && bodies
    }
}

#[cfg(test)]
mod tests {
    use crate::structure::Structure;

    /// A structure differs from a re-placed copy of itself only in placement, and from a copy
    /// with another spring stiffness in more.
    #[test]
    fn placement_is_told_apart_from_parameters() {
        let mut s = Structure::default();
        let base = s.add_body("base", crate::structure::BodyKind::Fixed, None);
        let a = s.add_node("A", base, [0.0, 0.0, 0.0]);
        let b = s.add_node("B", base, [1.0, 0.0, 0.0]);
        s.members.push(crate::structure::Member::spring(
            "K",
            [a, b],
            100.0,
            0.0,
            crate::structure::DEFAULT_TENDON_RADIUS_M,
        ));
        let mut moved = s.clone();
        moved.nodes[1].position = [0.0, 1.0, 0.0];
        assert!(s.same_but_placement(&moved));
        let mut stiffer = s.clone();
        stiffer.members[0].law = crate::structure::Law::Spring { stiffness_n_per_m: 200.0, rest_length_m: 0.0 };
        assert!(!s.same_but_placement(&stiffer));
    }
}
