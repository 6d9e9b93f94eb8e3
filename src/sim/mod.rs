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
mod capstan;
mod certificate;
mod closure_rest;
mod constrained_modes;
mod constrained_sensitivity;
mod continuation;
mod damping;
mod data;
mod drive;
mod forces;
mod group_tree;
mod joint_coordinates;
mod joint_data;
mod joint_modes;
pub(crate) mod least_squares;
mod levels;
mod model;
pub mod modes;
mod path;
mod projection;
mod relaxation;
mod restart;
mod rotation;
pub mod sensitivity;
mod servo;
pub mod sparse_sensitivity;
mod tree;

pub use build::LOOPED_MULTIBODY_MAX_LINKS;
pub use certificate::CertifyError;
pub use model::{Model, SimError};

use crate::structure::Structure;
use data::Data;
use rapier3d_f64::prelude::*;

use crate::settings::SimSettings;
use crate::snapshot::{BodyPose, MemberForces, Snapshot};

/// A simulation: the immutable [`Model`] the build returned beside the state that steps. The
/// state is split by concept, and each file's functions take what they read and what they
/// write: `data::Data` (rapier's sets, the inputs and the tick: what every concept reads and
/// moves), the static relaxation's state (`relaxation/`), the kind of path the steps take
/// (`path.rs`), the physical drive (`drive.rs`), the projected groups' kept Jacobians and rigid
/// rests (`projection.rs`) and the looped multibodies' closure rests (`closure_rest.rs`). This
/// type orders them through a step (after MuJoCo's `mj_step(m, d)`).
pub struct Simulation {
    /// What is simulated: written by the build only.
    model: Model,
    data: Data,
    relaxation: relaxation::Relaxation,
    path: path::Path,
    drive: drive::Drive,
    projection: projection::Projection,
    closure_rests: closure_rest::ClosureRests,
    rotation: rotation::FreeRotation,
    schedule: damping::Schedule,
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

    /// Characteristic length of the structure \[m\], for speeds and tolerances.
    pub fn length_scale_m(&self) -> f64 {
        self.model.length_scale_m
    }

    /// Builds rapier sets for `structure`. The structure must have passed `validate`.
    pub fn new(structure: &Structure, settings: &SimSettings) -> Result<Self, SimError> {
        structure.validate().map_err(|e| SimError::Build(e.to_string()))?;
        let (model, data) = build::build(structure, settings)?;
        let mut sim = Simulation {
            model,
            data,
            relaxation: relaxation::Relaxation::default(),
            path: path::Path::default(),
            drive: drive::Drive::default(),
            projection: projection::Projection::default(),
            closure_rests: closure_rest::ClosureRests::default(),
            rotation: rotation::FreeRotation::default(),
            schedule: damping::Schedule::default(),
        };
        let commands = sim.data.commands.clone();
        sim.set_commands(&commands);
        sim.set_relaxation(true);
        Ok(sim)
    }

    /// Sets rapier's PGS iterations per substep from now on.
    pub fn set_pgs_iterations(&mut self, n: usize) {
        self.data.params.num_internal_pgs_iterations = n.max(1);
    }

    /// Turns the static relaxation on (where the settings ask for it and it applies) or off.
    pub fn set_relaxation(&mut self, on: bool) {
        let m = &self.model;
        self.relaxation.on = on && !self.path.physical && m.settings.relaxation && m.relaxation_applies;
    }

    /// Whether the static relaxation runs before each step.
    pub fn relaxing(&self) -> bool {
        self.relaxation.on
    }

    pub fn tick(&self) -> u64 {
        self.data.tick
    }

    /// From now on only the physical dynamics: the static relaxation and the Newton damping
    /// schedule off for good, every scheduled joint's damping back to the structure's value.
    /// Velocities are left as they are (a motion run starts from them).
    pub fn end_acceleration(&mut self) {
        self.path.physical = true;
        self.relaxation.on = false;
        self.data.restore_scheduled_damping(&self.model);
        // Plain free bodies turn by the implicit midpoint rule from now on (`rotation.rs`).
        self.rotation.on = true;
        self.data.end_gyroscopic_forces(&self.model);
    }

    /// Releases every joint's and body's damping (sets it to zero) from now on: a free
    /// vibration of the undamped structure after a settle that used its damping.
    pub fn release_damping(&mut self) {
        self.data.release_damping(&self.model);
    }

    /// Whether the last step took a settle accelerator (the static relaxation, or the Newton
    /// schedule quenching a joint's velocity and setting its damping): the step was no part of
    /// a physical path.
    pub fn last_step_accelerated(&self) -> bool {
        self.path.last_step_accelerated
    }

    /// Steps taken with a settle accelerator so far (a rebuilt simulation starts at 0).
    pub fn accelerated_steps(&self) -> u64 {
        self.path.accelerated_steps
    }

    /// Moves the coordinate of joint `j` (a revolute's angle \[rad\], a prismatic's slide \[m\])
    /// by `displacement` and sets its rate to `rate` [rad/s or m/s], the bodies beyond it
    /// carried along; the other coordinates and rates stay. Only a joint that is a free
    /// (not actuated) link of a multibody has such a coordinate here.
    pub fn set_joint_motion(&mut self, j: usize, displacement: f64, rate: f64) -> Result<(), SimError> {
        self.data.set_joint_motion(&self.model, j, displacement, rate)
    }

    /// Sets a free body's angular velocity [rad/s] (world frame); Err for a multibody link,
    /// whose velocity is its joints' rates.
    pub fn set_body_spin(&mut self, body: usize, angular_velocity: [f64; 3]) -> Result<(), SimError> {
        self.data.set_body_spin(&self.model, body, angular_velocity)
    }

    /// Continues the tick count of a previous simulation (after a rebuild between points).
    pub fn set_tick(&mut self, tick: u64) {
        self.data.tick = tick;
    }

    pub fn time_s(&self) -> f64 {
        self.data.time_s(&self.model)
    }

    pub fn commands(&self) -> &[f64] {
        &self.data.commands
    }

    /// Sets every actuator's command (in structure order: m for lengths, rad for angles) and
    /// moves the actuated joints there at once.
    pub fn set_commands(&mut self, values: &[f64]) {
        assert_eq!(values.len(), self.model.structure.actuators.len(), "one command per actuator");
        self.data.commands.copy_from_slice(values);
        self.data.apply_cable_commands(&self.model);
        self.data.apply_servo_commands(&self.model);
        self.apply_joint_commands();
        self.data.move_fixed_nodes(&self.model);
        self.schedule = damping::Schedule::default();
    }

    /// Applies a constant external wrench (world frame, about the centre of mass) to a body
    /// from now on; zeros remove it.
    pub fn set_probe_load(&mut self, body: usize, force_n: [f64; 3], torque_nm: [f64; 3]) {
        self.data.probe_loads[body] = (force_n, torque_nm);
    }

    /// Advances one time step. Fails if the state is no longer finite or leaves the box.
    pub fn step(&mut self) -> Result<(), SimError> {
        let (m, d) = (&self.model, &mut self.data);
        let mut accelerated = false;
        if self.relaxation.on {
            self.relaxation.relax(m, d);
            accelerated = true;
        }
        if m.has_friction {
            d.slide_cables(m);
        }
        d.apply_member_forces(m);
        let mut scheduled = false;
        if m.settings.newton_damping && !self.path.physical && !self.schedule.stalled {
            if let Some(force) = d.schedule_damping(m) {
                (accelerated, scheduled) = (true, true);
                if self.schedule.stalls(force) {
                    d.restore_scheduled_damping(m);
                }
            }
        }
        self.path.note_step(accelerated);
        let turned = if self.rotation.on { d.free_rotations(m) } else { Vec::new() };
        d.step_rapier(m);
        d.turn_free_bodies(m, &turned);
        self.closure_rests.project_internal_closures(m, d);
        self.projection.project_groups(m, d);
        d.tick += 1;
        d.check_divergence(m, scheduled)
    }

    /// The state now, with the equilibrium residual.
    pub fn snapshot(&self) -> Snapshot {
        self.snapshot_with(true)
    }

    /// The state now; the residual only when `with_residual` (see
    /// [`Simulation::member_forces_with`]).
    pub fn snapshot_with(&self, with_residual: bool) -> Snapshot {
        self.data.snapshot_with(&self.model, with_residual)
    }

    /// Member forces and the equilibrium residual now.
    pub fn member_forces(&self) -> MemberForces {
        self.data.member_forces(&self.model)
    }

    /// Member forces now; the equilibrium residual only when `with_residual` (its fit is most
    /// of a snapshot's cost on a chain of plain bodies).
    pub fn member_forces_with(&self, with_residual: bool) -> MemberForces {
        self.data.member_forces_with(&self.model, with_residual)
    }

    /// Kinetic energy of every moving body \[J\].
    pub fn kinetic_energy_j(&self) -> f64 {
        self.data.kinetic_energy_j(&self.model)
    }

    /// Distance between a joint's anchor as carried by its parent and by its child \[m\].
    pub fn joint_gap_m(&self, joint: usize) -> f64 {
        self.data.joint_gap_m(&self.model, joint)
    }

    /// World position of a node \[m\].
    pub fn node_position(&self, node: usize) -> [f64; 3] {
        self.data.node_position(&self.model, node)
    }

    /// World position of every node \[m\].
    pub fn node_positions(&self) -> Vec<[f64; 3]> {
        self.data.node_positions(&self.model)
    }

    pub fn body_pose(&self, body: usize) -> BodyPose {
        self.data.body_pose(&self.model, body)
    }

    /// Bodies that move (not fixed).
    pub fn is_free(&self, body: usize) -> bool {
        self.model.is_free(body)
    }

    /// Whether a free body moves as a plain rigid body (not a link of a multibody): rapier
    /// integrates its rotation at first order (its gyroscopic term explicitly).
    pub fn has_plain_free_bodies(&self) -> bool {
        self.data.has_plain_free_bodies(&self.model)
    }

    /// Displaces every free joint coordinate of every multibody by `delta` (rad or m) and zeroes
    /// the velocities: the perturbation used to classify an equilibrium.
    pub fn perturb_free_coordinates(&mut self, delta: f64) {
        self.data.perturb_free_coordinates(&self.model, delta);
    }

    /// From now on every actuated joint is driven through the solver
    /// ([`Simulation::drive_commands`]); Err naming a joint actuator that is not a multibody
    /// link of its own (a loop's closing joint) or an actuator that moves a fixed node.
    pub fn drive_physically(&mut self) -> Result<(), SimError> {
        self.drive.start(&self.model, &mut self.data)
    }

    /// Sets every actuator's command for the end of the next step: cable lengths at once, each
    /// driven joint's motor to the secant rate that reaches its command in one step.
    pub fn drive_commands(&mut self, values: &[f64]) {
        self.drive.commands(&self.model, &mut self.data, values);
    }

    /// The structure's natural modes at its current state: over six coordinates per free body,
    /// or reduced to the joints' coordinates where there are joints (`joint_modes.rs`).
    pub fn modes(&mut self) -> Result<modes::StructureModes, modes::ModesError> {
        self.data.modes(&self.model, None, modes::Solver::BySize(modes::Lowest::default()))
    }

    /// [`Simulation::modes`] by the dense eigenproblem (every mode) whatever the number of
    /// free bodies: what the sparse solver of large structures is checked against.
    pub fn modes_dense(&mut self) -> Result<modes::StructureModes, modes::ModesError> {
        self.data.modes(&self.model, None, modes::Solver::Dense)
    }

    /// [`Simulation::modes`], as many as `lowest` asks of the sparse solver, the eigenproblem
    /// stopped when `cancel` is raised (`EigenError::Interrupted`).
    pub fn modes_until(
        &mut self,
        lowest: modes::Lowest,
        cancel: Option<&std::sync::atomic::AtomicBool>,
    ) -> Result<modes::StructureModes, modes::ModesError> {
        self.data.modes(&self.model, cancel, modes::Solver::BySize(lowest))
    }

    /// The free coordinates of the current state's sensitivities, or why it has none
    /// (`sensitivity.rs`).
    pub fn equilibrium_coordinates(
        &mut self,
    ) -> Result<sensitivity::EquilibriumCoordinates, sensitivity::SensitivityError> {
        self.data.equilibrium_coordinates(&self.model)
    }

    /// The generalized forces on the coordinates `c` now [N or N m] (zero at an equilibrium;
    /// with constraints, -dL/dq with their forces held).
    pub fn generalized_forces(&mut self, c: &sensitivity::EquilibriumCoordinates) -> nalgebra::DVector<f64> {
        self.data.generalized_forces(&self.model, c)
    }

    /// The tangent stiffness K = -dQ/dq in the coordinates `c` now.
    pub fn equilibrium_stiffness(&mut self, c: &sensitivity::EquilibriumCoordinates) -> nalgebra::DMatrix<f64> {
        self.data.equilibrium_stiffness(&self.model, c)
    }

    /// [`Simulation::equilibrium_stiffness`] and the size of its error (zero but where
    /// constraints make K a second difference of the Lagrangian).
    pub fn equilibrium_stiffness_and_error(
        &mut self,
        c: &sensitivity::EquilibriumCoordinates,
    ) -> (nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>) {
        self.data.equilibrium_stiffness_and_error(&self.model, c)
    }

    /// The lowest `count` modes beyond the rigid ones of a structure of free bodies in the
    /// free bodies' coordinates `bodies`, and the solver of K x = r over its modes that are not
    /// rigid: the sensitivities of a structure too large for a dense K
    /// (`sparse_sensitivity.rs`).
    pub fn sparse_linearization(
        &mut self,
        bodies: &[usize],
        count: usize,
    ) -> Result<sparse_sensitivity::SparseModes, modes::ModesError> {
        self.data.sparse_linearization(&self.model, bodies, count)
    }

    /// phi^T (K - omega^2 M) phi in free bodies' coordinates `c` now, from the forces along
    /// phi (`sparse_sensitivity.rs`).
    pub fn modal_curvature(
        &mut self,
        c: &sensitivity::EquilibriumCoordinates,
        phi: &nalgebra::DVector<f64>,
        omega_squared: f64,
    ) -> f64 {
        self.data.modal_curvature(&self.model, c, phi, omega_squared)
    }

    /// The current state as equilibrium equations for a proof (`sim/certificate.rs`), or why
    /// the structure has none.
    pub fn equilibrium_problem(&self) -> Result<crate::certify::Problem, CertifyError> {
        self.data.equilibrium_problem(&self.model)
    }

    /// The mass matrix in the coordinates `c` now.
    pub fn equilibrium_mass(&mut self, c: &sensitivity::EquilibriumCoordinates) -> nalgebra::DMatrix<f64> {
        self.data.equilibrium_mass(&self.model, c)
    }

    /// The constraints g(q) of the coordinates `c` now \[m\] (none without constraints).
    pub fn constraint_values(&self, c: &sensitivity::EquilibriumCoordinates) -> nalgebra::DVector<f64> {
        self.data.equilibrium_constraint_values(&self.model, c)
    }

    /// G = dg/dq of the coordinates `c` now (no rows without constraints).
    pub fn constraint_jacobian(&mut self, c: &sensitivity::EquilibriumCoordinates) -> nalgebra::DMatrix<f64> {
        self.data.equilibrium_constraint_jacobian(&self.model, c)
    }

    /// Moves the coordinates `c` by `dq` (m or rad).
    pub fn displace_coordinates(&mut self, c: &sensitivity::EquilibriumCoordinates, dq: &[f64]) {
        self.data.displace_coordinates(&self.model, c, dq)
    }

    /// Puts this structure, the same as `from`'s built with other parameters (and commanded
    /// before), in `from`'s configuration, coordinate by coordinate of `c`.
    pub fn take_configuration(&mut self, from: &Simulation, c: &sensitivity::EquilibriumCoordinates) {
        self.data.take_configuration(&self.model, &from.data, c)
    }

    /// Displaces the structure along mode `index` (from 0) of `analysis` (made at the current
    /// state) so that its largest node displacement is `amplitude_m`; returns the modal
    /// coordinate reached (the mass-normalised amplitude).
    pub fn displace_along_mode(&mut self, analysis: &modes::StructureModes, index: usize, amplitude_m: f64) -> f64 {
        self.data.displace_along_mode(&self.model, analysis, index, amplitude_m)
    }

    /// Puts the simulation at rest in the start state of `s`, the same structure in another
    /// placement (see [`Structure::same_but_placement`]), with the actuator commands `s` was
    /// built with, and forgets the probe loads. Returns false when `s` does not qualify or the
    /// restarted state does not reproduce it; the simulation must then be built afresh.
    pub fn restart_from(&mut self, s: &Structure) -> bool {
        if !self.data.restartable(&self.model) || !self.model.structure.same_but_placement(s) {
            return false;
        }
        self.data.probe_loads.iter_mut().for_each(|p| *p = ([0.0; 3], [0.0; 3]));
        self.data.constraint_inputs += 1;
        // The actuators to the commands `s` was built at, as for any new command.
        self.set_commands(&s.initial_commands());
        self.data.place_free_joints(&self.model, s)
    }

    /// This simulation's state, stepped from now on at `dt_s` \[s\]: the same structure and
    /// settings but the time step, the same bodies, joints, inputs and tick (`levels.rs`). The
    /// projection's kept Jacobians and rests start afresh (they are caches of the state).
    pub fn at_time_step(&self, dt_s: f64) -> Simulation {
        let mut data = self.data.clone();
        data.params.dt = dt_s;
        Simulation {
            model: self.model.at_time_step(dt_s),
            data,
            relaxation: relaxation::Relaxation::default(),
            path: self.path.clone(),
            drive: self.drive.clone(),
            projection: projection::Projection::default(),
            closure_rests: closure_rest::ClosureRests::default(),
            rotation: self.rotation,
            schedule: self.schedule.clone(),
        }
    }

    /// Starts the dynamics from now at a half step: every velocity taken back by half of what
    /// one step from here adds to it (measured on a copy), so that the steps that follow are
    /// the leapfrog scheme from the present state, second order at the tick times
    /// (`levels.rs`). For physical motion ([`Simulation::end_acceleration`] first); Err where
    /// the trial step diverges.
    pub fn start_at_half_step(&mut self) -> Result<(), SimError> {
        let mut trial = self.at_time_step(self.model.settings.dt_s);
        trial.step()?;
        self.data.half_step_back(&self.model, &trial.data);
        Ok(())
    }

    /// Sets every actuated joint's coordinate to its command, with zero velocity (ideal
    /// position control), and moves the bodies beyond it along. Where loops close inside a
    /// multibody, the move is made in increments of at most [`MAX_CLOSED_LOOP_INCREMENT`], each
    /// followed by the closure projection, so that the loops follow the actuators continuously
    /// and stay on their assembly mode.
    fn apply_joint_commands(&mut self) {
        let (m, d) = (&self.model, &mut self.data);
        let (moves, locks) = d.actuator_moves(m);
        // The moves that loops must follow: the links' where loops close inside a multibody,
        // the locked joints' where the projection closes their groups.
        let locks_projected = !m.projected_groups.is_empty() && !locks.is_empty();
        let mut largest = 0.0_f64;
        if !m.internal_closures.is_empty() {
            largest = moves.iter().fold(largest, |l, (_, x)| l.max(x.abs()));
        }
        if locks_projected {
            largest = locks.iter().fold(largest, |l, (_, from, to)| l.max((to - from).abs()));
        }
        let increments = ((largest / MAX_CLOSED_LOOP_INCREMENT).ceil() as usize).max(1);
        // Joints locked off the tree alone, in groups of plain bodies: at once where the
        // projection's convergence allows (`continuation.rs`).
        let at_once = locks_projected && increments > 1 && moves.is_empty() && m.projected_groups_are_plain();
        if at_once && self.projection.jump_locked_commands_at_once(m, d, &locks) {
            return;
        }
        let steps = d.multibody_moves(m, &moves, increments);
        for i in 1..=increments {
            let part = i as f64 / increments as f64;
            for &(j, from, to) in &locks {
                d.lock_joint_at(m, j, from + (to - from) * part);
            }
            d.move_multibodies(&steps);
            self.closure_rests.project_internal_closures(m, d);
            if locks_projected {
                // The increments before the last only keep the loops on their branch.
                let last = i == increments;
                let tolerance = if last { projection::GAP_TOLERANCE_FRACTION } else { INCREMENT_GAP_FRACTION };
                self.projection.project_groups_to(m, d, tolerance, f64::INFINITY);
            }
        }
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
