//! Actuation followed at its real speed (a motion run's waypoints or input functions): each
//! actuated joint, a kinematic degree of freedom while settling (set to its command, its rate
//! zeroed: no reaction on the rest), becomes a dynamic degree of freedom of its multibody held
//! to the commanded path by a rigid velocity motor in rapier's solver. Before each step its
//! target rate is the secant (q_cmd(t + dt) - q) / dt, so the step lands the coordinate on the
//! command, and the solver's impulse on that degree of freedom acts through the multibody's
//! full inverse mass matrix: the bodies it carries feel the prescribed acceleration (a cart's
//! acceleration swings its pendulum). Cable-length commands stay as they are (their forces are
//! computed from the geometry, so a changing length acts physically); an actuated joint that
//! closes a loop (locked off the tree, `build::locked_joint`) has no such degree of freedom and is
//! refused.

use super::data::Data;
use super::model::{Model, SimError};
use crate::structure::ActuatorTarget;
use rapier3d_f64::prelude::*;

/// The rigid motor's damping: infinite, so that rapier's motor coefficients give a hard
/// velocity constraint (erp 0, cfm 1 / (dt * damping) = 0).
const RIGID_MOTOR_DAMPING: f64 = f64::INFINITY;

/// The six joint axes in rapier's coordinate order (linear x, y, z, angular x, y, z).
const AXES: [JointAxis; 6] =
    [JointAxis::LinX, JointAxis::LinY, JointAxis::LinZ, JointAxis::AngX, JointAxis::AngY, JointAxis::AngZ];

/// Whether the actuated joints are driven through the solver rather than set.
#[derive(Clone, Default)]
pub(super) struct Drive {
    driven: bool,
}

impl Drive {
    /// From now on every actuated joint is driven through the solver ([`Drive::commands`]);
    /// Err naming a joint actuator that is not a multibody link of its own (a loop's closing
    /// joint) or an actuator that moves a fixed node.
    pub(super) fn start(&mut self, m: &Model, d: &mut Data) -> Result<(), SimError> {
        let s = &m.structure;
        for a in &s.actuators {
            let j = match a.target {
                // A servo's joint is free already; its command moves the spring.
                ActuatorTarget::Joint(j) if s.servo_of(j).is_some() => continue,
                ActuatorTarget::Joint(j) => j,
                ActuatorTarget::CableLength(_) => continue,
                ActuatorTarget::FixedNode { .. } => {
                    let what = format!("actuator '{}' moves a fixed node: it cannot be followed physically", a.symbol);
                    return Err(SimError::Refused(what));
                }
            };
            let name = &s.joints[j].name;
            let refused = || {
                SimError::Refused(format!("actuated joint '{name}' closes a loop (locked at its command off the multibody tree): it cannot be driven physically"))
            };
            let link = m.joint_links[j].ok_or_else(refused)?;
            let (mb, id) = d.multibody_joints.get_mut(link.multibody_joint).ok_or_else(refused)?;
            let l = mb.link_mut(id).ok_or_else(refused)?;
            let axis = AXES[super::joint_data::joint_free_axis(&l.joint.data)];
            l.joint.kinematic = false;
            l.joint.data.set_motor(axis, 0.0, 0.0, 0.0, RIGID_MOTOR_DAMPING);
        }
        self.driven = true;
        Ok(())
    }

    /// Sets every actuator's command for the end of the next step: cable lengths at once, each
    /// driven joint's motor to the secant rate that reaches its command in one step.
    pub(super) fn commands(&self, m: &Model, d: &mut Data, values: &[f64]) {
        assert!(self.driven, "drive_physically first");
        assert_eq!(values.len(), m.structure.actuators.len(), "one command per actuator");
        d.commands.copy_from_slice(values);
        d.apply_cable_commands(m);
        d.apply_servo_commands(m);
        let dt = m.settings.dt_s;
        for (a, command) in m.structure.actuators.iter().zip(values) {
            let ActuatorTarget::Joint(j) = a.target else { continue };
            let Some(link) = m.joint_links[j].filter(|_| m.structure.servo_of(j).is_none()) else { continue };
            let target = command - m.structure.joints[j].initial_coordinate;
            let Some((mb, id)) = d.multibody_joints.get_mut(link.multibody_joint) else { continue };
            let Some(l) = mb.link_mut(id) else { continue };
            let k = super::joint_data::joint_free_axis(&l.joint.data);
            let rate = (target - l.joint.coords()[k]) / dt;
            l.joint.data.set_motor_velocity(AXES[k], rate, RIGID_MOTOR_DAMPING);
        }
    }
}
