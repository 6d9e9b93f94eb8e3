//! The state that steps (MuJoCo's `mjData`): rapier's sets and pipeline, the inputs set from
//! outside the step (commands, cable lengths, probe loads, locked coordinates) and the tick.
//! Every concept reads it and moves it; [`Model`] says what it simulates, and its functions
//! take the model beside it.

use super::model::{Model, SimError};
use crate::settings::DEFAULT_JOINT_GAP_FRACTION;
use crate::snapshot::{BodyPose, Snapshot};
use crate::structure::ActuatorTarget;
use rapier3d_f64::prelude::*;
use std::cmp::Ordering;

pub(super) struct Data {
    pub(super) pipeline: PhysicsPipeline,
    pub(super) params: IntegrationParameters,
    pub(super) islands: IslandManager,
    pub(super) broad_phase: BroadPhaseBvh,
    pub(super) narrow_phase: NarrowPhase,
    pub(super) bodies: RigidBodySet,
    pub(super) colliders: ColliderSet,
    pub(super) impulse_joints: ImpulseJointSet,
    pub(super) multibody_joints: MultibodyJointSet,
    pub(super) soft_bodies: SoftBodySet,
    pub(super) ccd: CCDSolver,
    /// Every member's current rest length, member order \[m\]: a spring's, a cable's
    /// unstretched (commanded) length; 0 for a strut.
    pub(super) rest_lengths: Vec<f64>,
    /// Per member, a cable with friction's share of its unstretched length in each segment
    /// \[m\] (`capstan.rs`); empty for every other member.
    pub(super) material: Vec<Vec<f64>>,
    /// Per member, whether each inner node of a cable with friction is at its bound (slips).
    pub(super) at_bound: Vec<Vec<bool>>,
    /// Current actuator commands, in actuator order.
    pub(super) commands: Vec<f64>,
    /// External loads [N] and [N m] applied to bodies (probes), world frame, about the body's
    /// centre of mass.
    pub(super) probe_loads: Vec<([f64; 3], [f64; 3])>,
    pub(super) tick: u64,
    /// For each actuated joint off the multibody tree: the coordinate it is locked at, from
    /// its drawn configuration [rad or m] (`build::locked_joint`); 0 for every other joint.
    pub(super) locked_coordinates: Vec<f64>,
    /// Counts the changes of what the projection's rows depend on besides the bodies' poses
    /// (a locked coordinate, a cable's length, a fixed body's place) and of the state set from
    /// outside the step (an actuated multibody coordinate, a perturbation, a restart): the
    /// rests recorded before such a change are not returned to after it.
    pub(super) constraint_inputs: u64,
    /// Per body, a plain free body's angular momentum as physical motion carries it
    /// (`rotation.rs`); None until then.
    pub(super) kept_momenta: Vec<Option<super::rotation::KeptMomentum>>,
}

/// One multibody's actuated moves per increment of a command jump: (degree of freedom,
/// displacement per increment).
pub(super) type MultibodyMoves = Vec<(MultibodyIndex, Vec<(usize, f64)>)>;

/// (joint, displacement to its command) of every actuated multibody link, and (joint, locked
/// coordinate now, command) of every actuated joint locked off the tree.
type ActuatorMoves = (Vec<(usize, f64)>, Vec<(usize, f64, f64)>);

impl Data {
    /// Moves the coordinate of joint `j` (a revolute's angle [rad], a prismatic's slide [m])
    /// by `displacement` and sets its rate to `rate` [rad/s or m/s], the bodies beyond it
    /// carried along; the other coordinates and rates stay. Only a joint that is a free
    /// (not actuated) link of a multibody has such a coordinate here.
    pub(super) fn set_joint_motion(
        &mut self,
        m: &Model,
        j: usize,
        displacement: f64,
        rate: f64,
    ) -> Result<(), SimError> {
        if m.actuated[j] {
            let name = &m.structure.joints[j].name;
            return Err(SimError::Refused(format!("joint '{name}' is actuated: its coordinate is commanded")));
        }
        self.constraint_inputs += 1;
        self.move_joint(m, j, displacement, Some(rate))
    }

    /// Moves joint `j`'s coordinate by `displacement` (rad or m), the bodies beyond it along,
    /// and sets its rate (rad/s or m/s) where one is given; Err where the joint has no degree of
    /// freedom of its own in a multibody (a loop's closing joint).
    pub(super) fn move_joint(
        &mut self,
        m: &Model,
        j: usize,
        displacement: f64,
        rate: Option<f64>,
    ) -> Result<(), SimError> {
        let name = &m.structure.joints[j].name;
        let Some(link) = m.joint_links[j] else {
            return Err(SimError::Refused(format!("joint '{name}' closes a loop: it has no coordinate of its own")));
        };
        let Some((mb, link_id)) = self.multibody_joints.get_mut(link.multibody_joint) else {
            return Err(SimError::Refused(format!("joint '{name}' has no multibody link")));
        };
        // The degree-of-freedom indices hold from the build, which settled every root.
        let Some(start) = mb.link(link_id).map(|l| l.assembly_id()).filter(|s| *s < mb.ndofs()) else {
            return Err(SimError::Refused(format!(
                "joint '{name}' has no degree of freedom of its own in its multibody"
            )));
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
    pub(super) fn set_body_spin(&mut self, m: &Model, body: usize, angular_velocity: [f64; 3]) -> Result<(), SimError> {
        let h = m.handles[body];
        if !m.is_free(body) || self.multibody_joints.rigid_body_link(h).is_some() {
            let name = &m.structure.bodies[body].name;
            return Err(SimError::Refused(format!("body '{name}' is not a free body of its own")));
        }
        let [x, y, z] = angular_velocity;
        self.bodies[h].set_angvel(Vector::new(x, y, z), true);
        Ok(())
    }

    /// Sets every cable-length actuator's cable to its command: an elastic cable's rest length,
    /// an inextensible one's rope limit.
    pub(super) fn apply_cable_commands(&mut self, m: &Model) {
        for (i, a) in m.structure.actuators.iter().enumerate() {
            if let ActuatorTarget::CableLength(c) = a.target {
                self.rest_lengths[c] = self.commands[i];
                self.reel(c, self.commands[i]);
                self.constraint_inputs += 1;
                if let Some(h) = m.ropes[c] {
                    if let Some(j) = self.impulse_joints.get_mut(h, true) {
                        j.data.set_limits(JointAxis::LinX, [0.0, self.commands[i]]);
                    }
                }
            }
        }
    }

    /// Places every fixed body that carries a moved node at the sum of its actuators'
    /// displacements (bodies are built at the identity: their drawn place).
    pub(super) fn move_fixed_nodes(&mut self, m: &Model) {
        let s = &m.structure;
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
                self.bodies[m.handles[b]].set_position(Pose::from_translation(o), true);
                self.constraint_inputs += 1;
            }
        }
    }

    /// Where the Newton schedule drove the step (`scheduled`), its velocities are an
    /// accelerator's, not motion: a heavy body's start velocity toward its Newton point (a
    /// 1000 kg block 0.1 m from it at dt = 1 ms: 100 m/s, 5e6 J) is no blow-up, so the
    /// kinetic energy is not held to the limit then; positions still are.
    pub(super) fn check_divergence(&self, m: &Model, scheduled: bool) -> Result<(), SimError> {
        let limit = m.settings.bounding_box_m;
        // Not finite, then energy, then outside the box: a blow-up is named for what it is.
        let mut outside = None;
        for (i, n) in m.structure.nodes.iter().enumerate() {
            let p = self.node_position(m, i);
            if p.iter().any(|c| !c.is_finite()) {
                return Err(self.diverged(m, format!("node '{}' position is not finite", n.name)));
            }
            if outside.is_none() && p.iter().any(|c| c.abs() > limit) {
                outside = Some((i, p));
            }
        }
        let energy = self.kinetic_energy_j(m);
        if !energy.is_finite() || (energy > m.settings.max_kinetic_energy_j && !scheduled) {
            return Err(self.diverged(
                m,
                format!(
                    "kinetic energy {energy:.3e} J exceeds the limit {:.3e} J (sim.max_kinetic_energy)",
                    m.settings.max_kinetic_energy_j
                ),
            ));
        }
        if let Some((i, p)) = outside {
            return Err(self.diverged(
                m,
                format!(
                    "node '{}' left the bounding box of half-size {limit} m (at [{:.3e}, {:.3e}, {:.3e}])",
                    m.structure.nodes[i].name, p[0], p[1], p[2]
                ),
            ));
        }
        let gap_limit = m.settings.max_joint_gap_m.unwrap_or(DEFAULT_JOINT_GAP_FRACTION * m.length_scale_m);
        for (j, joint) in m.structure.joints.iter().enumerate() {
            if m.joint_impulse[j].is_none() {
                continue;
            }
            let gap = self.joint_gap_m(m, j);
            if gap.partial_cmp(&gap_limit).is_none_or(Ordering::is_gt) {
                return Err(self.diverged(m, format!(
                    "joint '{}' came apart: its anchors are {gap:.3e} m apart (limit {gap_limit:.3e} m, sim.max_joint_gap)",
                    joint.name
                )));
            }
        }
        Ok(())
    }

    /// Kinetic energy of every moving body [J].
    pub(super) fn kinetic_energy_j(&self, m: &Model) -> f64 {
        (0..m.structure.bodies.len()).filter(|b| m.is_free(*b)).map(|b| self.body_kinetic_energy_j(m, b)).sum()
    }

    /// Body `b`'s kinetic energy now [J]: (m |v|^2 + w . I_w w) / 2. A multibody link's v and
    /// w are its multibody's generalized velocity through the link's body Jacobian (both of
    /// the step's end), not the body's own velocities, which rapier writes from the
    /// multibody at the next step's start: read after a step, they are the step's start's, a
    /// step behind the positions.
    fn body_kinetic_energy_j(&self, m: &Model, b: usize) -> f64 {
        let rb = &self.bodies[m.handles[b]];
        let link = self.multibody_joints.rigid_body_link(m.handles[b]);
        let linked = link.and_then(|l| Some((l.id, self.multibody_joints.get_multibody(l.multibody)?)));
        let Some((id, mb)) = linked else {
            // A plain body: w . L with its angular momentum at its rotation now (rapier's own
            // kinetic energy reads a world inertia it updated before the step's turn).
            return 0.5 * (rb.mass() * rb.linvel().length_squared() + rb.angvel().dot(self.angular_momentum(m, b)));
        };
        let twist = mb.body_jacobian(id) * mb.generalized_velocity();
        let (v, w) = (Vector::new(twist[0], twist[1], twist[2]), Vector::new(twist[3], twist[4], twist[5]));
        let props = rb.mass_properties().local_mprops;
        let l = super::rotation::momentum(
            rb.position().rotation,
            props.principal_inertia_local_frame,
            props.principal_inertia(),
            w,
        );
        0.5 * (rb.mass() * v.length_squared() + w.dot(l))
    }

    /// Distance between a joint's anchor as carried by its parent and by its child [m].
    pub(super) fn joint_gap_m(&self, m: &Model, joint: usize) -> f64 {
        let j = &m.structure.joints[joint];
        let a = m.structure.nodes[j.anchor].position;
        let a = Vector::new(a[0], a[1], a[2]);
        let p = self.bodies[m.handles[j.parent]].position().transform_point(a);
        let c = self.bodies[m.handles[j.child]].position().transform_point(a);
        (p - c).length()
    }

    pub(super) fn diverged(&self, m: &Model, what: String) -> SimError {
        SimError::Diverged { tick: self.tick, time_s: self.time_s(m), what }
    }

    /// World position of a node [m].
    pub(super) fn node_position(&self, m: &Model, node: usize) -> [f64; 3] {
        let n = &m.structure.nodes[node];
        let pose = self.bodies[m.handles[n.body]].position();
        let p = pose.transform_point(Vector::new(n.position[0], n.position[1], n.position[2]));
        [p.x, p.y, p.z]
    }

    /// World position of every node [m].
    pub(super) fn node_positions(&self, m: &Model) -> Vec<[f64; 3]> {
        (0..m.structure.nodes.len()).map(|i| self.node_position(m, i)).collect()
    }

    pub(super) fn body_pose(&self, m: &Model, body: usize) -> BodyPose {
        let pose = self.bodies[m.handles[body]].position();
        let q = pose.rotation;
        BodyPose {
            translation: [pose.translation.x, pose.translation.y, pose.translation.z],
            rotation_xyzw: [q.x, q.y, q.z, q.w],
        }
    }

    /// The state now; the residual only when `with_residual` (see
    /// [`Simulation::member_forces_with`]).
    pub(super) fn snapshot_with(&self, m: &Model, with_residual: bool) -> Snapshot {
        Snapshot {
            tick: self.tick,
            time_s: self.time_s(m),
            nodes: self.node_positions(m),
            body_poses: (0..m.structure.bodies.len()).map(|b| self.body_pose(m, b)).collect(),
            forces: self.member_forces_with(m, with_residual),
            actuator_values: self.commands.clone(),
            kinetic_energy_j: self.kinetic_energy_j(m),
        }
    }

    /// Displaces every free joint coordinate of every multibody by `delta` (rad or m) and zeroes
    /// the velocities: the perturbation used to classify an equilibrium.
    pub(super) fn perturb_free_coordinates(&mut self, m: &Model, delta: f64) {
        self.constraint_inputs += 1;
        let mut touched = Vec::new();
        let free_links = m.joint_links.iter().zip(&m.actuated).filter(|(_, a)| !**a).filter_map(|(l, _)| l.as_ref());
        for link in free_links.chain(m.hidden_links.iter()) {
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
        let shift = Vector::new(1.0, 2.0, 3.0).normalize() * (delta * m.length_scale_m);
        let turn = Rotation::from_axis_angle(Vector::new(3.0, -1.0, 2.0).normalize(), delta);
        for b in 0..m.structure.bodies.len() {
            let h = m.handles[b];
            if m.is_free(b) && self.multibody_joints.rigid_body_link(h).is_none() {
                let com = self.world_com(m, b);
                let pose = *self.bodies[h].position();
                let moved = Pose::from_translation(com + shift)
                    * Pose::from_rotation(turn)
                    * Pose::from_translation(-com)
                    * pose;
                self.bodies[h].set_position(moved, true);
            }
        }
        self.zero_body_velocities(m);
    }

    /// Sets every free body's linear and angular velocity to zero (multibody links as well:
    /// their generalized velocities are the caller's).
    pub(super) fn zero_body_velocities(&mut self, m: &Model) {
        let free: Vec<usize> = (0..m.handles.len()).filter(|&b| m.is_free(b)).collect();
        self.stop_bodies(m, &free);
    }

    /// Sets the linear and angular velocity of each of `bodies` (structure indices) to zero.
    pub(super) fn stop_bodies(&mut self, m: &Model, bodies: &[usize]) {
        for &b in bodies {
            let rb = &mut self.bodies[m.handles[b]];
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
    }

    /// (joint, displacement to its command) of every actuated multibody link, and (joint,
    /// locked coordinate now, command) of every actuated joint locked off the tree.
    pub(super) fn actuator_moves(&self, m: &Model) -> ActuatorMoves {
        let mut moves: Vec<(usize, f64)> = Vec::new();
        let mut locks: Vec<(usize, f64, f64)> = Vec::new();
        for j in 0..m.structure.joints.len() {
            if !m.actuated[j] {
                continue;
            }
            if let Some(h) = m.joint_impulse[j] {
                let target = self.joint_command(m, j) - m.structure.joints[j].initial_coordinate;
                let from = if self.impulse_joints.get(h).is_some() { self.locked_coordinates[j] } else { target };
                locks.push((j, from, target));
                continue;
            }
            let Some(link) = m.joint_links[j] else { continue };
            let target = self.joint_command(m, j) - m.structure.joints[j].initial_coordinate;
            let Some((mb, link_id)) = self.multibody_joints.get(link.multibody_joint) else { continue };
            let Some(current) =
                mb.link(link_id).map(|l| l.joint().coords()[super::joint_data::joint_free_axis(&l.joint().data)])
            else {
                continue;
            };
            moves.push((j, target - current));
        }
        (moves, locks)
    }

    /// Locks actuated joint `j`, off the multibody tree, at coordinate `q` from its drawn
    /// configuration [rad or m].
    pub(super) fn lock_joint_at(&mut self, m: &Model, j: usize, q: f64) {
        let Some(h) = m.joint_impulse[j] else { return };
        if let Some(joint) = self.impulse_joints.get_mut(h, true) {
            joint.data = super::joint_data::locked_joint(&m.structure, &m.structure.joints[j], q);
            self.locked_coordinates[j] = q;
            self.constraint_inputs += 1;
        }
    }

    /// Joint `j`'s first degree of freedom in its multibody: (multibody, index), if a link.
    /// The index can shift when forward kinematics re-roots the multibody: read it after.
    pub(super) fn dof_of(&self, m: &Model, j: usize) -> Option<(MultibodyIndex, usize)> {
        let link = m.joint_links[j]?;
        let (mb, id) = self.multibody_joints.get(link.multibody_joint)?;
        let index = self.multibody_joints.rigid_body_link(m.handles[m.structure.joints[j].child])?.multibody;
        Some((index, mb.link(id)?.assembly_id()))
    }

    pub(super) fn joint_command(&self, m: &Model, joint: usize) -> f64 {
        m.structure
            .actuators
            .iter()
            .position(|a| a.target == ActuatorTarget::Joint(joint))
            .map(|i| self.commands[i])
            .unwrap_or(m.structure.joints[joint].initial_coordinate)
    }

    pub(super) fn time_s(&self, m: &Model) -> f64 {
        self.tick as f64 * m.settings.dt_s
    }

    /// rapier's step under the structure's gravity.
    pub(super) fn step_rapier(&mut self, m: &Model) {
        let [gx, gy, gz] = m.structure.gravity;
        self.pipeline.step(
            Vector::new(gx, gy, gz),
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
    }

    /// Every joint that the Newton schedule damped back to the structure's damping.
    pub(super) fn restore_scheduled_damping(&mut self, m: &Model) {
        for j in 0..m.structure.joints.len() {
            if let (Some(link), true) = (m.joint_links[j], self.scheduled(m, j)) {
                let damping = super::joint_data::link_damping(&m.structure, j, m.settings.body_damping_per_s);
                super::joint_data::set_link_damping(&mut self.multibody_joints, link.multibody_joint, damping);
            }
        }
    }

    /// Sets every joint's and body's damping to zero, the hidden first links of split universal
    /// joints included (`build.rs` gives them the joint's damping: left on, an undamped motion
    /// of mohr2011 lost 13 % of its energy per second and its lowest pair of modes measured
    /// 1.3e-4 high).
    pub(super) fn release_damping(&mut self, m: &Model) {
        for link in m.joint_links.iter().flatten().chain(m.hidden_links.iter()) {
            super::joint_data::set_link_damping(&mut self.multibody_joints, link.multibody_joint, 0.0);
        }
        for h in &m.handles {
            let body = &mut self.bodies[*h];
            body.set_linear_damping(0.0);
            body.set_angular_damping(0.0);
        }
    }

    /// The actuated multibody moves (`moves`: joint, displacement to its command) grouped by
    /// multibody, each cut into `increments` equal parts. The degree-of-freedom indices hold
    /// from the build, which settled every root.
    pub(super) fn multibody_moves(&self, m: &Model, moves: &[(usize, f64)], increments: usize) -> MultibodyMoves {
        let mut multibodies: Vec<MultibodyIndex> = Vec::new();
        for &(j, _) in moves {
            if let Some((index, _)) = self.dof_of(m, j) {
                if !multibodies.contains(&index) {
                    multibodies.push(index);
                }
            }
        }
        multibodies
            .iter()
            .map(|&index| {
                let dofs = moves
                    .iter()
                    .filter_map(|&(j, total)| {
                        let (mj, dof) = self.dof_of(m, j)?;
                        (mj == index).then_some((dof, total / increments as f64))
                    })
                    .collect();
                (index, dofs)
            })
            .collect()
    }

    /// Moves each multibody's actuated degrees of freedom by one increment of `steps`, with
    /// zero rate, and places its bodies there.
    pub(super) fn move_multibodies(&mut self, steps: &MultibodyMoves) {
        for (index, dofs) in steps {
            let Some(mb) = self.multibody_joints.get_multibody_mut(*index) else { continue };
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
    }
}
