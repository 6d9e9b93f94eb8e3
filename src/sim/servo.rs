//! Servos: an actuated revolute joint with a torsion spring ([`Structure::servo_of`]) is a
//! position controller of finite stiffness. Its command is the spring's rest angle; the joint
//! is a free degree of freedom that turns against the spring (torque -k (q - command)), as a
//! servo of stiffness k sags under load by load / k. The spring is rapier's force-based
//! position motor on the joint (`build.rs`), its target moved with every command.
//!
//! [`Structure::servo_of`]: crate::structure::Structure::servo_of

use super::data::Data;
use super::model::Model;
use rapier3d_f64::prelude::*;

/// The free axis of a revolute joint (rapier's `RevoluteJoint` frees `AngX`).
const REVOLUTE_AXIS: JointAxis = JointAxis::AngX;

impl Data {
    /// Joint `j`'s torsion spring now: its stiffness [N m/rad] and rest angle \[rad\], a servo's
    /// rest angle being its command. None without a spring.
    pub(super) fn torsion_spring_now(&self, m: &Model, j: usize) -> Option<(f64, f64)> {
        let t = m.structure.joints[j].torsion_spring.as_ref()?;
        let rest = m.structure.servo_of(j).map_or(t.rest_angle_rad, |a| self.commands[a]);
        Some((t.stiffness_nm_per_rad, rest))
    }

    /// Moves every servo's spring to its command: the target of its joint's motor, counted from
    /// the joint's drawn coordinate as the joint's own coordinates are.
    pub(super) fn apply_servo_commands(&mut self, m: &Model) {
        for (j, joint) in m.structure.joints.iter().enumerate() {
            let (Some(a), Some(t)) = (m.structure.servo_of(j), &joint.torsion_spring) else { continue };
            let target = self.commands[a] - joint.initial_coordinate;
            let k = t.stiffness_nm_per_rad;
            if let Some(link) = m.joint_links[j] {
                if let Some(l) =
                    self.multibody_joints.get_mut(link.multibody_joint).and_then(|(mb, id)| mb.link_mut(id))
                {
                    l.joint.data.set_motor_position(REVOLUTE_AXIS, target, k, 0.0);
                }
            } else if let Some(h) = m.joint_impulse[j] {
                if let Some(ij) = self.impulse_joints.get_mut(h, true) {
                    ij.data.set_motor_position(REVOLUTE_AXIS, target, k, 0.0);
                }
            }
            self.constraint_inputs += 1;
        }
    }
}
