//! Member forces: applying the explicit ones every step, reading all of them back, and the
//! equilibrium residual computed from them independently of the solver.

use super::Simulation;
use crate::structure::{ActuatorTarget, CableLaw, JointKind};
use rapier3d_f64::prelude::*;

/// Forces in every member at one instant. Tension is positive.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MemberForces {
    /// Spring force k (l - l0) [N], in structure order.
    pub spring_force_n: Vec<f64>,
    pub spring_length_m: Vec<f64>,
    /// Cable tension [N] (0 when slack).
    pub cable_tension_n: Vec<f64>,
    pub cable_length_m: Vec<f64>,
    /// Unstretched (commanded) cable length [m].
    pub cable_rest_length_m: Vec<f64>,
    pub cable_slack: Vec<bool>,
    /// Force [N] or torque [N m] each actuator exerts along its joint axis (or the cable
    /// tension for a winch), in actuator order.
    pub actuator_force: Vec<f64>,
    pub residual: Residual,
}

/// Equilibrium residual: the generalized forces of member forces, gravity and probe loads on
/// every free coordinate (a joint's free axes, summed over the subtree it carries). Zero at an
/// exact equilibrium. Computed from the force laws, not from the solver.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Residual {
    /// Largest residual force on a translational coordinate [N].
    pub max_force_n: f64,
    /// Largest residual torque on a rotational coordinate [N m].
    pub max_torque_nm: f64,
    /// Free coordinates that could not be checked (subtrees closed by loop joints).
    pub unchecked_coordinates: usize,
}

type Wrench = (Vector, Vector); // (force, moment about the world origin)

fn v(a: [f64; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

impl Simulation {
    /// Puts the explicit forces (springs, elastic cables, probes) on the bodies for the next step.
    pub(super) fn apply_member_forces(&mut self) {
        let n = self.structure.bodies.len();
        for b in 0..n {
            let rb = &mut self.bodies[self.handles[b]];
            rb.reset_forces(false);
            rb.reset_torques(false);
        }
        let mut loads: Vec<(usize, Vector, Vector)> = Vec::new();
        for sp in &self.structure.springs {
            let (pa, pb) = (v(self.node_position(sp.a)), v(self.node_position(sp.b)));
            let d = pb - pa;
            let l = d.length();
            if l > 0.0 {
                let f = d / l * (sp.stiffness_n_per_m * (l - sp.rest_length_m));
                loads.push((self.structure.nodes[sp.a].body, f, pa));
                loads.push((self.structure.nodes[sp.b].body, -f, pb));
            }
        }
        for (c, cable) in self.structure.cables.iter().enumerate() {
            if let CableLaw::Elastic { stiffness_n_per_m } = cable.law {
                let (pa, pb) = (v(self.node_position(cable.a)), v(self.node_position(cable.b)));
                let d = pb - pa;
                let l = d.length();
                let t = (stiffness_n_per_m * (l - self.cable_lengths[c])).max(0.0);
                if l > 0.0 && t > 0.0 {
                    let f = d / l * t;
                    loads.push((self.structure.nodes[cable.a].body, f, pa));
                    loads.push((self.structure.nodes[cable.b].body, -f, pb));
                }
            }
        }
        // Force at the centre of mass plus its moment, with the centre of mass taken from the
        // current pose: rapier's cached world centre of mass is stale before the first step,
        // which gave a spurious kick of |c x F| there.
        for (body, f, p) in loads {
            if self.is_free(body) {
                let com = self.world_com(body);
                let rb = &mut self.bodies[self.handles[body]];
                rb.add_force(f, false);
                rb.add_torque((p - com).cross(f), false);
            }
        }
        for b in 0..n {
            let (f, t) = self.probe_loads[b];
            if self.is_free(b) && (f != [0.0; 3] || t != [0.0; 3]) {
                let rb = &mut self.bodies[self.handles[b]];
                rb.add_force(v(f), false);
                rb.add_torque(v(t), false);
            }
        }
    }

    /// World position of a free body's centre of mass, from its current pose [m].
    fn world_com(&self, body: usize) -> Vector {
        let local = self.structure.bodies[body].inertia.map_or([0.0; 3], |i| i.com);
        self.bodies[self.handles[body]].position().transform_point(v(local))
    }

    /// Reads every member force and computes the equilibrium residual.
    pub fn member_forces(&self) -> MemberForces {
        let s = &self.structure;
        let nb = s.bodies.len();
        let mut wrench: Vec<Wrench> = vec![(Vector::ZERO, Vector::ZERO); nb];
        let push = |w: &mut Vec<Wrench>, body: usize, f: Vector, p: Vector| {
            w[body].0 += f;
            w[body].1 += p.cross(f);
        };
        let mut out = MemberForces::default();
        for sp in &s.springs {
            let (pa, pb) = (v(self.node_position(sp.a)), v(self.node_position(sp.b)));
            let d = pb - pa;
            let l = d.length();
            let force = sp.stiffness_n_per_m * (l - sp.rest_length_m);
            out.spring_force_n.push(force);
            out.spring_length_m.push(l);
            if l > 0.0 {
                let f = d / l * force;
                push(&mut wrench, s.nodes[sp.a].body, f, pa);
                push(&mut wrench, s.nodes[sp.b].body, -f, pb);
            }
        }
        let inv_h = self.settings.substeps as f64 / self.settings.dt_s;
        for (c, cable) in s.cables.iter().enumerate() {
            let (pa, pb) = (v(self.node_position(cable.a)), v(self.node_position(cable.b)));
            let d = pb - pa;
            let l = d.length();
            let rest = self.cable_lengths[c];
            let tension = match cable.law {
                CableLaw::Elastic { stiffness_n_per_m } => (stiffness_n_per_m * (l - rest)).max(0.0),
                CableLaw::Inextensible => self.cable_ropes[c]
                    .and_then(|h| self.impulse_joints.get(h))
                    .map(|j| j.data.limits[0].impulse.abs() * inv_h)
                    .unwrap_or(0.0),
            };
            out.cable_tension_n.push(tension);
            out.cable_length_m.push(l);
            out.cable_rest_length_m.push(rest);
            out.cable_slack.push(tension <= 0.0);
            if l > 0.0 {
                let f = d / l * tension;
                push(&mut wrench, s.nodes[cable.a].body, f, pa);
                push(&mut wrench, s.nodes[cable.b].body, -f, pb);
            }
        }
        let g = v(s.gravity);
        for (b, body) in s.bodies.iter().enumerate() {
            if self.is_free(b) {
                if let Some(i) = body.inertia {
                    let com = self.bodies[self.handles[b]].position().transform_point(v(i.com));
                    let f = g * i.mass_kg;
                    wrench[b].0 += f;
                    wrench[b].1 += com.cross(f);
                }
                let (pf, pt) = self.probe_loads[b];
                let com = self.world_com(b);
                wrench[b].0 += v(pf);
                wrench[b].1 += com.cross(v(pf)) + v(pt);
            }
        }

        // Tree of joints (multibody links and actuator drives): parent of each body.
        let mut parent_joint: Vec<Option<usize>> = vec![None; nb];
        for (j, joint) in s.joints.iter().enumerate() {
            if self.joint_links[j].is_some() || self.driving_joint[joint.child] == Some(j) {
                parent_joint[joint.child] = Some(j);
            }
        }
        // Bodies touched by a loop-closing impulse joint: their reactions are unknown.
        let mut in_loop = vec![false; nb];
        for (j, joint) in s.joints.iter().enumerate() {
            if self.joint_impulse[j].is_some() {
                in_loop[joint.parent] = true;
                in_loop[joint.child] = true;
            }
        }
        let descends_from = |mut b: usize, ancestor: usize| -> bool {
            for _ in 0..=nb {
                if b == ancestor {
                    return true;
                }
                match parent_joint[b] {
                    Some(j) => b = s.joints[j].parent,
                    None => return false,
                }
            }
            false
        };
        let subtree_wrench = |root: usize| -> (Wrench, bool) {
            let mut w = (Vector::ZERO, Vector::ZERO);
            let mut loop_free = true;
            for b in 0..nb {
                if descends_from(b, root) {
                    w.0 += wrench[b].0;
                    w.1 += wrench[b].1;
                    loop_free &= !in_loop[b];
                }
            }
            (w, loop_free)
        };
        let about = |w: Wrench, p: Vector| -> Vector { w.1 - p.cross(w.0) };

        let mut residual = Residual::default();
        for (j, joint) in s.joints.iter().enumerate() {
            if self.joint_links[j].is_none() {
                continue;
            }
            let (w, ok) = subtree_wrench(joint.child);
            let ndofs = match joint.kind {
                JointKind::Fixed => 0,
                JointKind::Revolute { .. } | JointKind::Prismatic { .. } => 1,
                JointKind::Universal { .. } => 2,
                JointKind::Spherical => 3,
            };
            if !ok {
                residual.unchecked_coordinates += ndofs;
                continue;
            }
            let anchor = v(self.node_position(joint.anchor));
            let parent_rot = self.bodies[self.handles[joint.parent]].position().rotation;
            let child_rot = self.bodies[self.handles[joint.child]].position().rotation;
            let m = about(w, anchor);
            match &joint.kind {
                JointKind::Revolute { axis } => {
                    let a = (parent_rot * v(*axis)).normalize();
                    // A torsion spring on this joint is a generalized force on its coordinate.
                    let spring = joint.torsion_spring.as_ref().map_or(0.0, |t| {
                        let q = joint.initial_coordinate + relative_angle(parent_rot, child_rot, v(*axis));
                        -t.stiffness_nm_per_rad * (q - t.rest_angle_rad)
                    });
                    residual.max_torque_nm = residual.max_torque_nm.max((m.dot(a) + spring).abs());
                }
                JointKind::Prismatic { axis } => {
                    let a = (parent_rot * v(*axis)).normalize();
                    residual.max_force_n = residual.max_force_n.max(w.0.dot(a).abs());
                }
                JointKind::Universal { axis1, axis2 } => {
                    let a1 = (parent_rot * v(*axis1)).normalize();
                    let a2 = (child_rot * v(*axis2)).normalize();
                    residual.max_torque_nm = residual.max_torque_nm.max(m.dot(a1).abs()).max(m.dot(a2).abs());
                }
                JointKind::Spherical => {
                    residual.max_torque_nm = residual.max_torque_nm.max(m.length());
                }
                JointKind::Fixed => {}
            }
        }
        // Free bodies with no parent joint: all six coordinates.
        for b in 0..nb {
            if self.is_free(b) && parent_joint[b].is_none() {
                let (w, ok) = subtree_wrench(b);
                if !ok {
                    residual.unchecked_coordinates += 6;
                    continue;
                }
                let com = self.world_com(b);
                residual.max_force_n = residual.max_force_n.max(w.0.length());
                residual.max_torque_nm = residual.max_torque_nm.max(about(w, com).length());
            }
        }
        out.residual = residual;

        // Actuator forces: minus the load of everything the actuated joint carries.
        for a in &s.actuators {
            let f = match a.target {
                ActuatorTarget::CableLength(c) => out.cable_tension_n[c],
                ActuatorTarget::Joint(j) => {
                    let joint = &s.joints[j];
                    let (w, _) = subtree_wrench(joint.child);
                    let anchor = v(self.node_position(joint.anchor));
                    let parent_rot = self.bodies[self.handles[joint.parent]].position().rotation;
                    match &joint.kind {
                        JointKind::Revolute { axis } => -about(w, anchor).dot((parent_rot * v(*axis)).normalize()),
                        JointKind::Prismatic { axis } => -w.0.dot((parent_rot * v(*axis)).normalize()),
                        _ => f64::NAN,
                    }
                }
            };
            out.actuator_force.push(f);
        }
        out
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
