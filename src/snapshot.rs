//! What the simulation hands out at a tick: node positions, body poses, member forces and the
//! equilibrium residual, as plain data. Mechanisms and observers read these; they never see
//! the simulator's rapier sets.

/// Pose of a body as translation and rotation (unit quaternion `[x, y, z, w]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyPose {
    pub translation: [f64; 3],
    pub rotation_xyzw: [f64; 4],
}

/// One tick's state, handed to every observer.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub tick: u64,
    pub time_s: f64,
    /// World position of every node, in structure order [m].
    pub nodes: Vec<[f64; 3]>,
    pub body_poses: Vec<BodyPose>,
    pub forces: MemberForces,
    /// Actuator commands, in structure order (m or rad).
    pub actuator_values: Vec<f64>,
    /// Kinetic energy of the free bodies [J].
    pub kinetic_energy_j: f64,
}

impl Snapshot {
    /// The force of the spring or cable `name` of structure `s` [N] (tension positive).
    pub fn member_force_n(&self, s: &crate::structure::Structure, name: &str) -> Option<f64> {
        match s.spring_id(name) {
            Some(i) => self.forces.spring_force_n.get(i).copied(),
            None => self.forces.cable_tension_n.get(s.cable_id(name)?).copied(),
        }
    }

    /// The force or torque of the actuator driven by `symbol` along its axis [N or N m].
    pub fn actuator_force(&self, s: &crate::structure::Structure, symbol: &str) -> Option<f64> {
        self.forces.actuator_force.get(s.actuator_id(symbol)?).copied()
    }
}

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
    /// None when the snapshot was taken without it (see [`Simulation::member_forces_with`]).
    pub residual: Option<Residual>,
}

/// Equilibrium residual: the generalized forces of member forces, gravity and probe loads on
/// every free coordinate (a joint's free axes, summed over the subtree it carries). Zero at an
/// exact equilibrium. Computed from the force laws, not from the solver; the reactions of
/// loop-closing joints, which no force law gives, are fitted by least squares.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Residual {
    /// Largest residual force on a translational coordinate [N].
    pub max_force_n: f64,
    /// Largest residual torque on a rotational coordinate [N m].
    pub max_torque_nm: f64,
}
