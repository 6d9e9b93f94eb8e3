//! The simulator: turns a [`Structure`] into rapier sets, drives its actuators, steps it and
//! reads member forces and equilibrium residuals.
//!
//! Modelling choices (see `../shared/notes/rapier-parry-rerun-0.36.md` for the measurements
//! behind them):
//! - Free bodies hung from the ground or from an actuator by a tree of joints are rapier
//!   *multibody* links (reduced coordinates): the joint constraints hold exactly, with no
//!   solver offset. A joint that would close a loop becomes an impulse joint.
//! - Position-controlled joint actuators are ideal: each is a kinematic degree of freedom of a
//!   multibody, set exactly to the commanded coordinate; the bodies beyond it stay dynamic.
//!   Their force is read from the balance of everything they carry.
//! - Springs and elastic cables are explicit forces computed from the current geometry, so
//!   their force law is exact at rest: F = k (l - l0), tension-only for cables.
//! - Inextensible cables are rapier rope joints; their tension is read from the limit impulse.
//! - Torsion springs are force-based joint motors; joint damping is multibody DOF damping
//!   (implicit, and zero at rest, so it does not move the equilibrium).

mod build;
mod closure_rest;
mod continuation;
mod damping;
mod drive;
mod forces;
mod group_tree;
mod joint_coordinates;
mod joint_modes;
pub(crate) mod least_squares;
pub mod modes;
mod projection;
mod relaxation;
mod restart;
mod tree;

pub use build::LOOPED_MULTIBODY_MAX_LINKS;

use crate::structure::{ActuatorTarget, BodyKind, Structure};
use rapier3d_f64::prelude::*;

use crate::settings::{SimSettings, DEFAULT_JOINT_GAP_FRACTION};
use crate::snapshot::{BodyPose, MemberForces, Residual, Snapshot};

#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SimError {
    #[error("the structure cannot be simulated: {0}")]
    Build(String),
    #[error("simulation diverged at tick {tick} (t = {time_s:.6} s): {what}")]
    Diverged { tick: u64, time_s: f64, what: String },
    /// A request the built structure cannot carry out (a coordinate it does not have, a body
    /// that is not free, an actuator that cannot be driven physically).
    #[error("the simulator cannot do this: {0}")]
    Refused(String),
}

/// Where a free body sits in a multibody, so its joint coordinates can be read and perturbed.
#[derive(Clone, Copy, Debug)]
struct LinkRef {
    multibody_joint: MultibodyJointHandle,
}

/// What a simulation is built from and keeps for its whole life (MuJoCo's `mjModel`): the
/// structure and settings, and how the build mapped them onto rapier (handles, multibody
/// links, loop closures, rope joints, the link tree, constant loads). Only the build writes it.
pub struct Model {
    pub structure: Structure,
    pub settings: SimSettings,
    /// rapier handle of each structure body.
    handles: Vec<RigidBodyHandle>,
    /// For each joint: whether an actuator sets its coordinate (a kinematic multibody degree
    /// of freedom).
    actuated: Vec<bool>,
    /// For each joint: the multibody link it made, if any.
    joint_links: Vec<Option<LinkRef>>,
    /// First halves of universal joints split into two multibody revolutes.
    hidden_links: Vec<LinkRef>,
    /// For each joint: the impulse joint it made, if any (loop closures).
    joint_impulse: Vec<Option<ImpulseJointHandle>>,
    /// Loop closures inside one multibody, closed by position projection after each step.
    internal_closures: Vec<projection::InternalClosure>,
    /// Groups of free bodies (plain bodies and multibodies) whose joints and taut cables are
    /// closed by position projection.
    projected_groups: Vec<projection::ProjectedGroup>,
    /// For each inextensible cable: its rope joint.
    cable_ropes: Vec<Option<ImpulseJointHandle>>,
    /// The joint each body hangs from in the multibody forest (fixed at build).
    tree: tree::Tree,
    /// The reaction fit's tree: the multibody forest and the sparse groups' spanning trees
    /// (`tree.rs`).
    fit_tree: tree::Tree,
    /// The structure's constant external forces, summed per body [N].
    external_loads: Vec<[f64; 3]>,
    /// Characteristic length of the structure [m], for speeds and tolerances.
    pub length_scale_m: f64,
    /// Whether the static relaxation applies to this structure (`relaxation/`).
    relaxation_applies: bool,
}

/// The mutable state that steps (MuJoCo's `mjData`): rapier's sets and pipeline, the current
/// commands, cable lengths and probe loads, and the tick; [`Model`] says what it simulates.
pub struct Simulation {
    model: Model,
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    islands: IslandManager,
    broad_phase: BroadPhaseBvh,
    narrow_phase: NarrowPhase,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    ccd: CCDSolver,
    /// Current unstretched cable lengths [m].
    cable_lengths: Vec<f64>,
    /// Current actuator commands, in actuator order.
    commands: Vec<f64>,
    /// External loads [N] and [N m] applied to bodies (probes), world frame, about the body's
    /// centre of mass.
    probe_loads: Vec<([f64; 3], [f64; 3])>,
    tick: u64,
    /// Whether the static relaxation runs before each step (the settings' choice where it
    /// applies; the settle loop turns it off for its quiet window).
    relaxing: bool,
    /// The relaxation's current shift, a fraction of the stiffest mode (`relaxation/`).
    relaxation_shift: f64,
    /// The largest generalized force component at the relaxation's last step, for its test of
    /// a round-off stall (`relaxation/mod.rs`).
    relaxation_last_force: f64,
    /// Only the physical dynamics from now on ([`Simulation::end_acceleration`]): no static
    /// relaxation, no Newton damping schedule, every joint's damping as stated.
    physical: bool,
    /// Whether the last step took a settle accelerator (the relaxation or the Newton schedule).
    last_step_accelerated: bool,
    /// Steps taken with a settle accelerator.
    accelerated_steps: u64,
    /// Whether the actuated joints are driven through the solver (`drive.rs`) rather than set.
    driven: bool,
    /// For each actuated joint off the multibody tree: the coordinate it is locked at, from
    /// its drawn configuration [rad or m] (`build::locked_joint`); 0 for every other joint.
    locked_coordinates: Vec<f64>,
    /// Each projected group's Jacobian kept from its last projection (`projection.rs`).
    kept_jacobians: Vec<Option<projection::KeptJacobian>>,
    /// Each projected group's rigid rest, where it was last closed (`projection.rs`).
    rigid_rests: Vec<Option<projection::RigidRest>>,
    /// Each looped multibody's rest, where its loops were last closed (`closure_rest.rs`).
    closure_rests: Vec<closure_rest::ClosureRest>,
    /// Counts the changes of what the projection's rows depend on besides the bodies' poses
    /// (a locked coordinate, a cable's length, a fixed body's place) and of the state set from
    /// outside the step (an actuated multibody coordinate, a perturbation, a restart): the
    /// rests recorded before such a change are not returned to after it.
    constraint_inputs: u64,
}

impl Simulation {
    /// What this simulation simulates: the structure, settings and build plan.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The structure being simulated.
    pub fn structure(&self) -> &Structure {
        &self.model.structure
    }

    /// Characteristic length of the structure [m], for speeds and tolerances.
    pub fn length_scale_m(&self) -> f64 {
        self.model.length_scale_m
    }

    /// Builds rapier sets for `structure`. The structure must have passed `validate`.
    pub fn new(structure: &Structure, settings: &SimSettings) -> Result<Self, SimError> {
        structure.validate().map_err(|e| SimError::Build(e.to_string()))?;
        build::build(structure, settings)
    }

    /// Sets rapier's PGS iterations per substep from now on.
    pub fn set_pgs_iterations(&mut self, n: usize) {
        self.params.num_internal_pgs_iterations = n.max(1);
    }

    /// Turns the static relaxation on (where the settings ask for it and it applies) or off.
    pub fn set_relaxation(&mut self, on: bool) {
        self.relaxing = on && !self.physical && self.model.settings.relaxation && self.model.relaxation_applies;
    }

    /// Whether the static relaxation runs before each step.
    pub fn relaxing(&self) -> bool {
        self.relaxing
    }

    pub fn tick(&self) -> u64 {
        self.tick
    }

    /// From now on only the physical dynamics: the static relaxation and the Newton damping
    /// schedule off for good, every scheduled joint's damping back to the structure's value.
    /// Velocities are left as they are (a motion run starts from them).
    pub fn end_acceleration(&mut self) {
        self.physical = true;
        self.relaxing = false;
        for j in 0..self.model.structure.joints.len() {
            if let (Some(link), true) = (self.model.joint_links[j], self.scheduled(j)) {
                let damping = self.model.structure.joints[j].damping;
                build::set_link_damping(&mut self.multibody_joints, link.multibody_joint, damping);
            }
        }
    }

    /// Releases every joint's and body's damping (sets it to zero) from now on: a free
    /// vibration of the undamped structure after a settle that used its damping.
    pub fn release_damping(&mut self) {
        for link in self.model.joint_links.iter().flatten() {
            build::set_link_damping(&mut self.multibody_joints, link.multibody_joint, 0.0);
        }
        for h in &self.model.handles {
            let body = &mut self.bodies[*h];
            body.set_linear_damping(0.0);
            body.set_angular_damping(0.0);
        }
    }

    /// Whether the last step took a settle accelerator (the static relaxation, or the Newton
    /// schedule quenching a joint's velocity and setting its damping): the step was no part of
    /// a physical path.
    pub fn last_step_accelerated(&self) -> bool {
        self.last_step_accelerated
    }

    /// Steps taken with a settle accelerator so far (a rebuilt simulation starts at 0).
    pub fn accelerated_steps(&self) -> u64 {
        self.accelerated_steps
    }

    /// Moves the coordinate of joint `j` (a revolute's angle [rad], a prismatic's slide [m])
    /// by `displacement` and sets its rate to `rate` [rad/s or m/s], the bodies beyond it
    /// carried along; the other coordinates and rates stay. Only a joint that is a free
    /// (not actuated) link of a multibody has such a coordinate here.
    pub fn set_joint_motion(&mut self, j: usize, displacement: f64, rate: f64) -> Result<(), SimError> {
        if self.model.actuated[j] {
            let name = &self.model.structure.joints[j].name;
            return Err(SimError::Refused(format!("joint '{name}' is actuated: its coordinate is commanded")));
        }
        self.constraint_inputs += 1;
        self.move_joint(j, displacement, Some(rate))
    }

    /// Moves joint `j`'s coordinate by `displacement` (rad or m), the bodies beyond it along,
    /// and sets its rate (rad/s or m/s) where one is given; Err where the joint has no degree of
    /// freedom of its own in a multibody (a loop's closing joint).
    pub(super) fn move_joint(&mut self, j: usize, displacement: f64, rate: Option<f64>) -> Result<(), SimError> {
        let name = &self.model.structure.joints[j].name;
        let Some(link) = self.model.joint_links[j] else {
            return Err(SimError::Refused(format!("joint '{name}' closes a loop: it has no coordinate of its own")));
        };
        let Some((mb, link_id)) = self.multibody_joints.get_mut(link.multibody_joint) else {
            return Err(SimError::Refused(format!("joint '{name}' has no multibody link")));
        };
        // The degree-of-freedom indices hold from the build, which settled every root.
        let Some(start) = mb.link(link_id).map(|l| l.assembly_id()).filter(|s| *s < mb.ndofs()) else {
            return Err(SimError::Refused(format!("joint '{name}' has no degree of freedom of its own in its multibody")));
        };
        let mut disp = vec![0.0; mb.ndofs()];
        disp[start] = displacement;
        mb.apply_displacements(&disp);
        mb.forward_kinematics(&self.bodies, true);
        mb.update_rigid_bodies(&mut self.bodies, true);
        if let Some(rate) = rate {
            mb.generalized_velocity_mut()[start] = rate;
        }
        Ok(())
    }

    /// Sets a free body's angular velocity [rad/s] (world frame); Err for a multibody link,
    /// whose velocity is its joints' rates.
    pub fn set_body_spin(&mut self, body: usize, angular_velocity: [f64; 3]) -> Result<(), SimError> {
        let h = self.model.handles[body];
        if !self.is_free(body) || self.multibody_joints.rigid_body_link(h).is_some() {
            let name = &self.model.structure.bodies[body].name;
            return Err(SimError::Refused(format!("body '{name}' is not a free body of its own")));
        }
        let [x, y, z] = angular_velocity;
        self.bodies[h].set_angvel(Vector::new(x, y, z), true);
        Ok(())
    }

    /// Continues the tick count of a previous simulation (after a rebuild between points).
    pub fn set_tick(&mut self, tick: u64) {
        self.tick = tick;
    }

    pub fn time_s(&self) -> f64 {
        self.tick as f64 * self.model.settings.dt_s
    }

    pub fn commands(&self) -> &[f64] {
        &self.commands
    }

    /// Sets every actuator's command (in structure order: m for lengths, rad for angles) and
    /// moves the actuated joints there at once.
    pub fn set_commands(&mut self, values: &[f64]) {
        assert_eq!(values.len(), self.model.structure.actuators.len(), "one command per actuator");
        self.commands.copy_from_slice(values);
        self.apply_cable_commands();
        self.apply_joint_commands();
        self.move_fixed_nodes();
    }

    /// Sets every cable-length actuator's cable to its command: an elastic cable's rest length,
    /// an inextensible one's rope limit.
    fn apply_cable_commands(&mut self) {
        for (i, a) in self.model.structure.actuators.iter().enumerate() {
            if let ActuatorTarget::CableLength(c) = a.target {
                self.cable_lengths[c] = self.commands[i];
                self.constraint_inputs += 1;
                if let Some(h) = self.model.cable_ropes[c] {
                    if let Some(j) = self.impulse_joints.get_mut(h, true) {
                        j.data.set_limits(JointAxis::LinX, [0.0, self.commands[i]]);
                    }
                }
            }
        }
    }

    /// Places every fixed body that carries a moved node at the sum of its actuators'
    /// displacements (bodies are built at the identity: their drawn place).
    fn move_fixed_nodes(&mut self) {
        let s = &self.model.structure;
        let mut offsets: Vec<Option<Vector>> = vec![None; s.bodies.len()];
        for (a, command) in s.actuators.iter().zip(&self.commands) {
            if let ActuatorTarget::FixedNode { node, direction } = a.target {
                let d = Vector::new(direction[0], direction[1], direction[2]) * *command;
                let o = offsets[s.nodes[node].body].get_or_insert(Vector::ZERO);
                *o += d;
            }
        }
        for (b, offset) in offsets.into_iter().enumerate() {
            if let Some(o) = offset {
                self.bodies[self.model.handles[b]].set_position(Pose::from_translation(o), true);
                self.constraint_inputs += 1;
            }
        }
    }

    /// Applies a constant external wrench (world frame, about the centre of mass) to a body
    /// from now on; zeros remove it.
    pub fn set_probe_load(&mut self, body: usize, force_n: [f64; 3], torque_nm: [f64; 3]) {
        self.probe_loads[body] = (force_n, torque_nm);
    }

    /// Advances one time step. Fails if the state is no longer finite or leaves the box.
    pub fn step(&mut self) -> Result<(), SimError> {
        let mut accelerated = false;
        if self.relaxing {
            self.relax();
            accelerated = true;
        }
        self.apply_member_forces();
        if self.model.settings.newton_damping && !self.physical {
            accelerated |= self.schedule_damping();
        }
        self.last_step_accelerated = accelerated;
        self.accelerated_steps += u64::from(accelerated);
        let gravity = Vector::new(
            self.model.structure.gravity[0],
            self.model.structure.gravity[1],
            self.model.structure.gravity[2],
        );
        self.pipeline.step(
            gravity,
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
        self.project_internal_closures();
        self.project_groups();
        self.tick += 1;
        self.check_divergence()
    }

    fn check_divergence(&self) -> Result<(), SimError> {
        let limit = self.model.settings.bounding_box_m;
        // Not finite, then energy, then outside the box: a blow-up is named for what it is.
        let mut outside = None;
        for (i, n) in self.model.structure.nodes.iter().enumerate() {
            let p = self.node_position(i);
            if p.iter().any(|c| !c.is_finite()) {
                return Err(self.diverged(format!("node '{}' position is not finite", n.name)));
            }
            if outside.is_none() && p.iter().any(|c| c.abs() > limit) {
                outside = Some((i, p));
            }
        }
        let energy = self.kinetic_energy_j();
        if !energy.is_finite() || energy > self.model.settings.max_kinetic_energy_j {
            return Err(self.diverged(format!(
                "kinetic energy {energy:.3e} J exceeds the limit {:.3e} J (sim.max_kinetic_energy)",
                self.model.settings.max_kinetic_energy_j
            )));
        }
        if let Some((i, p)) = outside {
            return Err(self.diverged(format!(
                "node '{}' left the bounding box of half-size {limit} m (at [{:.3e}, {:.3e}, {:.3e}])",
                self.model.structure.nodes[i].name, p[0], p[1], p[2]
            )));
        }
        let gap_limit =
            self.model.settings.max_joint_gap_m.unwrap_or(DEFAULT_JOINT_GAP_FRACTION * self.model.length_scale_m);
        for (j, joint) in self.model.structure.joints.iter().enumerate() {
            if self.model.joint_impulse[j].is_none() {
                continue;
            }
            let gap = self.joint_gap_m(j);
            if !(gap <= gap_limit) {
                return Err(self.diverged(format!(
                    "joint '{}' came apart: its anchors are {gap:.3e} m apart (limit {gap_limit:.3e} m, sim.max_joint_gap)",
                    joint.name
                )));
            }
        }
        Ok(())
    }

    /// Kinetic energy of every moving body [J].
    pub fn kinetic_energy_j(&self) -> f64 {
        (0..self.model.structure.bodies.len())
            .filter(|b| self.is_free(*b))
            .map(|b| self.bodies[self.model.handles[b]].kinetic_energy())
            .sum()
    }

    /// Distance between a joint's anchor as carried by its parent and by its child [m].
    pub fn joint_gap_m(&self, joint: usize) -> f64 {
        let j = &self.model.structure.joints[joint];
        let a = self.model.structure.nodes[j.anchor].position;
        let a = Vector::new(a[0], a[1], a[2]);
        let p = self.bodies[self.model.handles[j.parent]].position().transform_point(a);
        let c = self.bodies[self.model.handles[j.child]].position().transform_point(a);
        (p - c).length()
    }

    fn diverged(&self, what: String) -> SimError {
        SimError::Diverged { tick: self.tick, time_s: self.time_s(), what }
    }

    /// World position of a node [m].
    pub fn node_position(&self, node: usize) -> [f64; 3] {
        let n = &self.model.structure.nodes[node];
        let pose = self.bodies[self.model.handles[n.body]].position();
        let p = pose.transform_point(Vector::new(n.position[0], n.position[1], n.position[2]));
        [p.x, p.y, p.z]
    }

    /// World position of every node [m].
    pub fn node_positions(&self) -> Vec<[f64; 3]> {
        (0..self.model.structure.nodes.len()).map(|i| self.node_position(i)).collect()
    }

    pub fn body_pose(&self, body: usize) -> BodyPose {
        let pose = self.bodies[self.model.handles[body]].position();
        let q = pose.rotation;
        BodyPose {
            translation: [pose.translation.x, pose.translation.y, pose.translation.z],
            rotation_xyzw: [q.x, q.y, q.z, q.w],
        }
    }

    /// Bodies that move (not fixed).
    pub fn is_free(&self, body: usize) -> bool {
        self.model.structure.bodies[body].kind == BodyKind::Free
    }

    /// The state now, with the equilibrium residual.
    pub fn snapshot(&self) -> Snapshot {
        self.snapshot_with(true)
    }

    /// The state now; the residual only when `with_residual` (see
    /// [`Simulation::member_forces_with`]).
    pub fn snapshot_with(&self, with_residual: bool) -> Snapshot {
        Snapshot {
            tick: self.tick,
            time_s: self.time_s(),
            nodes: self.node_positions(),
            body_poses: (0..self.model.structure.bodies.len()).map(|b| self.body_pose(b)).collect(),
            forces: self.member_forces_with(with_residual),
            actuator_values: self.commands.clone(),
            kinetic_energy_j: self.kinetic_energy_j(),
        }
    }

    /// Displaces every free joint coordinate of every multibody by `delta` (rad or m) and zeroes
    /// the velocities: the perturbation used to classify an equilibrium.
    pub fn perturb_free_coordinates(&mut self, delta: f64) {
        self.constraint_inputs += 1;
        let mut touched = Vec::new();
        let free_links = self
            .model
            .joint_links
            .iter()
            .zip(&self.model.actuated)
            .filter(|(_, a)| !**a)
            .filter_map(|(l, _)| l.as_ref());
        for link in free_links.chain(self.model.hidden_links.iter()) {
            if let Some((mb, link_id)) = self.multibody_joints.get_mut(link.multibody_joint) {
                let assembly = mb.link(link_id).map(|l| (l.assembly_id(), l.joint().ndofs()));
                if let Some((start, n)) = assembly {
                    let mut disp = vec![0.0; mb.ndofs()];
                    for d in disp.iter_mut().skip(start).take(n) {
                        *d = delta;
                    }
                    mb.apply_displacements(&disp);
                    touched.push(link.multibody_joint);
                }
            }
        }
        for h in touched {
            if let Some((mb, _)) = self.multibody_joints.get_mut(h) {
                mb.forward_kinematics(&self.bodies, true);
                mb.update_rigid_bodies(&mut self.bodies, true);
                mb.generalized_velocity_mut().fill(0.0);
            }
        }
        // Plain free bodies (not multibody links): shift by delta times the structure's size
        // along a fixed oblique direction and turn by delta about an oblique axis through the
        // centre of mass.
        let shift = Vector::new(1.0, 2.0, 3.0).normalize() * (delta * self.model.length_scale_m);
        let turn = Rotation::from_axis_angle(Vector::new(3.0, -1.0, 2.0).normalize(), delta);
        for b in 0..self.model.structure.bodies.len() {
            let h = self.model.handles[b];
            if self.is_free(b) && self.multibody_joints.rigid_body_link(h).is_none() {
                let com = self.world_com(b);
                let pose = *self.bodies[h].position();
                let moved = Pose::from_translation(com + shift)
                    * Pose::from_rotation(turn)
                    * Pose::from_translation(-com)
                    * pose;
                self.bodies[h].set_position(moved, true);
            }
        }
        self.zero_body_velocities();
    }

    /// Sets every free body's linear and angular velocity to zero (multibody links as well:
    /// their generalized velocities are the caller's).
    fn zero_body_velocities(&mut self) {
        let free: Vec<usize> = (0..self.model.handles.len()).filter(|&b| self.is_free(b)).collect();
        self.stop_bodies(&free);
    }

    /// Sets the linear and angular velocity of each of `bodies` (structure indices) to zero.
    fn stop_bodies(&mut self, bodies: &[usize]) {
        for &b in bodies {
            let rb = &mut self.bodies[self.model.handles[b]];
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
    }

    /// Sets every actuated joint's coordinate to its command, with zero velocity (ideal
    /// position control), and moves the bodies beyond it along. Where loops close inside a
    /// multibody, the move is made in increments of at most [`MAX_CLOSED_LOOP_INCREMENT`], each
    /// followed by the closure projection, so that the loops follow the actuators continuously
    /// and stay on their assembly mode.
    fn apply_joint_commands(&mut self) {
        let (moves, locks) = self.actuator_moves();
        // The moves that loops must follow: the links' where loops close inside a multibody,
        // the locked joints' where the projection closes their groups.
        let locks_projected = !self.model.projected_groups.is_empty() && !locks.is_empty();
        let mut largest = 0.0_f64;
        if !self.model.internal_closures.is_empty() {
            largest = moves.iter().fold(largest, |m, (_, d)| m.max(d.abs()));
        }
        if locks_projected {
            largest = locks.iter().fold(largest, |m, (_, from, to)| m.max((to - from).abs()));
        }
        let increments = ((largest / MAX_CLOSED_LOOP_INCREMENT).ceil() as usize).max(1);
        // Joints locked off the tree alone, in groups of plain bodies: at once where the
        // projection's convergence allows (`continuation.rs`).
        let at_once = locks_projected && increments > 1 && moves.is_empty() && self.projected_groups_are_plain();
        if at_once && self.jump_locked_commands_at_once(&locks) {
            return;
        }
        // The multibodies moved (their degree-of-freedom indices hold from the build, which
        // settled every root).
        let mut multibodies: Vec<MultibodyIndex> = Vec::new();
        for &(j, _) in &moves {
            if let Some((m, _)) = self.dof_of(j) {
                if !multibodies.contains(&m) {
                    multibodies.push(m);
                }
            }
        }
        // Each multibody's moves at once: (degree of freedom, displacement per increment).
        let steps: Vec<(MultibodyIndex, Vec<(usize, f64)>)> = multibodies
            .iter()
            .map(|&m| {
                let dofs = moves
                    .iter()
                    .filter_map(|&(j, total)| {
                        let (mj, dof) = self.dof_of(j)?;
                        (mj == m).then_some((dof, total / increments as f64))
                    })
                    .collect();
                (m, dofs)
            })
            .collect();
        for i in 1..=increments {
            let part = i as f64 / increments as f64;
            for &(j, from, to) in &locks {
                self.lock_joint_at(j, from + (to - from) * part);
            }
            for (m, dofs) in &steps {
                let Some(mb) = self.multibody_joints.get_multibody_mut(*m) else { continue };
                let mut disp = vec![0.0; mb.ndofs()];
                for &(dof, d) in dofs {
                    disp[dof] = d;
                }
                mb.apply_displacements(&disp);
                self.constraint_inputs += 1;
                for &(dof, _) in dofs {
                    mb.generalized_velocity_mut()[dof] = 0.0;
                }
                mb.forward_kinematics(&self.bodies, true);
                mb.update_rigid_bodies(&mut self.bodies, true);
            }
            self.project_internal_closures();
            if locks_projected {
                // The increments before the last only keep the loops on their branch.
                let last = i == increments;
                let tolerance = if last { projection::GAP_TOLERANCE_FRACTION } else { INCREMENT_GAP_FRACTION };
                self.project_groups_to(tolerance, f64::INFINITY);
            }
        }
    }

    /// (joint, displacement to its command) of every actuated multibody link, and (joint,
    /// locked coordinate now, command) of every actuated joint locked off the tree.
    #[allow(clippy::type_complexity)]
    fn actuator_moves(&self) -> (Vec<(usize, f64)>, Vec<(usize, f64, f64)>) {
        let mut moves: Vec<(usize, f64)> = Vec::new();
        let mut locks: Vec<(usize, f64, f64)> = Vec::new();
        for j in 0..self.model.structure.joints.len() {
            if !self.model.actuated[j] {
                continue;
            }
            if let Some(h) = self.model.joint_impulse[j] {
                let target = self.joint_command(j) - self.model.structure.joints[j].initial_coordinate;
                let from = if self.impulse_joints.get(h).is_some() { self.locked_coordinates[j] } else { target };
                locks.push((j, from, target));
                continue;
            }
            let Some(link) = self.model.joint_links[j] else { continue };
            let target = self.joint_command(j) - self.model.structure.joints[j].initial_coordinate;
            let Some((mb, link_id)) = self.multibody_joints.get(link.multibody_joint) else { continue };
            let Some(current) = mb.link(link_id).map(|l| l.joint().coords()[joint_free_axis(&l.joint().data)]) else {
                continue;
            };
            moves.push((j, target - current));
        }
        (moves, locks)
    }

    /// Locks actuated joint `j`, off the multibody tree, at coordinate `q` from its drawn
    /// configuration [rad or m].
    fn lock_joint_at(&mut self, j: usize, q: f64) {
        let Some(h) = self.model.joint_impulse[j] else { return };
        if let Some(joint) = self.impulse_joints.get_mut(h, true) {
            joint.data = build::locked_joint(&self.model.structure, &self.model.structure.joints[j], q);
            self.locked_coordinates[j] = q;
            self.constraint_inputs += 1;
        }
    }

    /// Joint `j`'s first degree of freedom in its multibody: (multibody, index), if a link.
    /// The index can shift when forward kinematics re-roots the multibody: read it after.
    pub(super) fn dof_of(&self, j: usize) -> Option<(MultibodyIndex, usize)> {
        let link = self.model.joint_links[j]?;
        let (mb, id) = self.multibody_joints.get(link.multibody_joint)?;
        let index =
            self.multibody_joints.rigid_body_link(self.model.handles[self.model.structure.joints[j].child])?.multibody;
        Some((index, mb.link(id)?.assembly_id()))
    }

    fn joint_command(&self, joint: usize) -> f64 {
        self.model
            .structure
            .actuators
            .iter()
            .position(|a| a.target == ActuatorTarget::Joint(joint))
            .map(|i| self.commands[i])
            .unwrap_or(self.model.structure.joints[joint].initial_coordinate)
    }
}

/// Largest move of an actuated coordinate (rad or m) between two closure projections when an
/// actuator command jumps: small enough that the projection, started from the previous
/// configuration, lands on the same assembly mode of each loop.
const MAX_CLOSED_LOOP_INCREMENT: f64 = 0.01;

/// The projected groups close their joints to this fraction of the structure's size at the
/// increments of a command jump before the last: enough to follow the branch (an increment
/// moves a chain's joints by up to 5e-2 of its size), a third of the Gauss-Newton iterations
/// of closing to round-off (measured on a chain of 10 furet2018 X modules cut into plain
/// bodies); the last increment closes to round-off. Loops inside a multibody close to
/// round-off at every increment: loosened, the furet2018 scenarios' transients moved (ticks of
/// closest approach) for 2 to 6 % of an 8-X chain's settle.
const INCREMENT_GAP_FRACTION: f64 = 1e-6;

/// Index (0..6: linear x, y, z, angular x, y, z) of the single free axis of a one-degree-of-
/// freedom joint, where its coordinate lives in `MultibodyJoint::coords`.
fn joint_free_axis(data: &GenericJoint) -> usize {
    let locked = data.locked_axes.bits();
    (0..6).find(|k| locked & (1 << k) == 0).unwrap_or(0)
}
