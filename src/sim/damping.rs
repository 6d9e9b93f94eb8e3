//! The secant damping schedule (`sim.secant_damping = true`), a settling strategy.
//!
//! Joint damping is implicit in rapier's multibody step: with damping c, inertia I and the
//! explicit generalized force tau(q) of the springs, one step of length dt moves a coordinate by
//! dq = dt (I v + dt tau) / (I + dt c). With c = dt k, k = -dtau/dq the local stiffness, and
//! dt^2 k >> I, that is nearly Newton's step tau / k; the momentum term I v is what is left, and
//! the schedule accounts for it too. A fixed c fits one
//! stiffness only: too little overshoots (and can jump to another equilibrium branch), too much
//! creeps (BENCHMARKS.md's scan on ji2014).
//!
//! The schedule estimates k for every damped revolute or prismatic multibody joint from the
//! simulation itself, by the secant of its generalized force over its coordinate between two
//! steps (the last estimate when the joint hardly moved), and sets before each step the damping
//! that makes the step Newton's, its momentum included (`newton_damping`). With no estimate
//! (the first step after a start) or a stiffness that is not positive (an unstable region) the
//! joint keeps the structure's damping. Damping is zero at rest, so the equilibrium is the same
//! as with any fixed damping; only the path to it changes.

use super::Simulation;
use crate::structure::JointKind;
use rapier3d_f64::prelude::*;

/// The damping that makes rapier's implicit step a Newton step. One step moves the coordinate
/// by dt v' with (I + dt c) v' = p, p = I v + dt tau the momentum after the impulse of the
/// force; Newton's step is s = tau / k. Equal when c = (dt p / s - I) / dt, which is at least 0
/// when p carries the coordinate at least as far as s. When p points away from Newton's point
/// (momentum left from the last step, against the force), no damping reaches it and the best
/// is to stop: [`STOP_DAMPING_FACTOR`] times the scale I / dt + dt k. When p falls short even
/// undamped, 0.
fn newton_damping(dt: f64, stiffness: f64, inertia: f64, velocity: f64, force: f64) -> f64 {
    let newton_step = force / stiffness;
    let momentum = inertia * velocity + dt * force;
    if momentum * newton_step <= 0.0 {
        return STOP_DAMPING_FACTOR * (inertia / dt + dt * stiffness);
    }
    ((dt * momentum / newton_step - inertia) / dt).max(0.0)
}

/// Damping, relative to the scale I / dt + dt k, that stops a joint within one step (its
/// velocity falls by this factor).
const STOP_DAMPING_FACTOR: f64 = 1e6;

/// A coordinate change below this [rad or m] gives no secant (round-off would dominate).
const SECANT_MIN_STEP: f64 = 1e-12;

/// The last step's coordinate and generalized force of one damped joint.
#[derive(Clone, Copy, Debug)]
pub(super) struct SecantPoint {
    coordinate: f64,
    force: f64,
    /// The stiffness estimate used for the step from here [N m/rad or N/m].
    stiffness: Option<f64>,
    /// The joint's effective inertia [kg m^2 or kg], every other coordinate free (0: not yet
    /// known; rapier's mass data are current only after the first step).
    inertia: f64,
}

impl Simulation {
    /// The joints the schedule drives: damped, free, revolute or prismatic multibody links.
    fn scheduled(&self, j: usize) -> bool {
        let joint = &self.structure.joints[j];
        self.joint_links[j].is_some()
            && !self.actuated[j]
            && joint.damping > 0.0
            && matches!(joint.kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. })
    }

    /// Joint `j`'s coordinate [rad or m] and the generalized force [N m or N] of the loads
    /// applied for the coming step (member forces, external loads and gravity on every body it
    /// carries, and its own torsion spring).
    fn coordinate_and_force(&self, j: usize, tree: &super::forces::Tree) -> SecantPoint {
        let s = &self.structure;
        let joint = &s.joints[j];
        let parent = *self.bodies[self.handles[joint.parent]].position();
        let child = *self.bodies[self.handles[joint.child]].position();
        let anchor_local = {
            let a = s.nodes[joint.anchor].position;
            Vector::new(a[0], a[1], a[2])
        };
        let anchor = parent.transform_point(anchor_local);
        let g = Vector::new(s.gravity[0], s.gravity[1], s.gravity[2]);
        let (mut force, mut moment) = (Vector::ZERO, Vector::ZERO);
        for b in 0..s.bodies.len() {
            if !self.is_free(b) || !tree.descends_from(s, b, joint.child) {
                continue;
            }
            let rb = &self.bodies[self.handles[b]];
            let com = rb.center_of_mass();
            let f = rb.user_force() + g * rb.mass() * rb.gravity_scale();
            force += f;
            moment += (com - anchor).cross(f) + rb.user_torque();
        }
        match joint.kind {
            JointKind::Revolute { axis } => {
                let a = Vector::new(axis[0], axis[1], axis[2]);
                let coordinate = super::forces::relative_angle(parent.rotation, child.rotation, a);
                // The joint's own torsion spring (a rapier motor, not a user force).
                let spring = joint.torsion_spring.as_ref().map_or(0.0, |t| {
                    -t.stiffness_nm_per_rad * (joint.initial_coordinate + coordinate - t.rest_angle_rad)
                });
                let force = moment.dot((parent.rotation * a).normalize()) + spring;
                SecantPoint { coordinate, force, stiffness: None, inertia: 0.0 }
            }
            JointKind::Prismatic { axis } => {
                let a = (parent.rotation * Vector::new(axis[0], axis[1], axis[2])).normalize();
                let coordinate = (child.transform_point(anchor_local) - anchor).dot(a);
                SecantPoint { coordinate, force: force.dot(a), stiffness: None, inertia: 0.0 }
            }
            _ => SecantPoint { coordinate: 0.0, force: 0.0, stiffness: None, inertia: 0.0 },
        }
    }

    /// The joint's degree of freedom in its multibody: (multibody, index), if a link.
    fn dof_of(&self, j: usize) -> Option<(MultibodyIndex, usize)> {
        let link = self.joint_links[j]?;
        let (mb, id) = self.multibody_joints.get(link.multibody_joint)?;
        let index = self.multibody_joints.rigid_body_link(self.handles[self.structure.joints[j].child])?.multibody;
        Some((index, mb.link(id)?.assembly_id()))
    }

    /// Sets every scheduled joint's damping for the coming step (after the loads are applied).
    pub(super) fn schedule_damping(&mut self) {
        let dt = self.settings.dt_s;
        let tree = self.link_tree();
        for j in 0..self.structure.joints.len() {
            if !self.scheduled(j) {
                continue;
            }
            let Some((mb_index, dof)) = self.dof_of(j) else { continue };
            let mut now = self.coordinate_and_force(j, &tree);
            let mut damping = self.structure.joints[j].damping;
            now.stiffness = match self.secant[j] {
                // A new start: no estimate yet, the structure's damping for this step.
                None => None,
                Some(last) => {
                    now.inertia = last.inertia;
                    if now.inertia <= 0.0 {
                        if let Some(mb) = self.multibody_joints.get_multibody_mut(mb_index) {
                            let inv = mb.dof_inverse_inertia(&self.bodies)[dof];
                            now.inertia = if inv > 0.0 { 1.0 / inv } else { 0.0 };
                        }
                    }
                    // The secant, or the last estimate when the joint hardly moved.
                    let dq = now.coordinate - last.coordinate;
                    if dq.abs() > SECANT_MIN_STEP {
                        Some(-(now.force - last.force) / dq)
                    } else {
                        last.stiffness
                    }
                }
            };
            if let Some(k) = now.stiffness.filter(|k| *k > 0.0) {
                damping = newton_damping(dt, k, now.inertia, self.dof_velocity(mb_index, dof), now.force);
            }
            self.secant[j] = Some(now);
            if let Some(link) = self.joint_links[j] {
                super::build::set_link_damping(&mut self.multibody_joints, link.multibody_joint, damping);
            }
        }
    }

    fn dof_velocity(&self, multibody: MultibodyIndex, dof: usize) -> f64 {
        self.multibody_joints.get_multibody(multibody).map_or(0.0, |mb| mb.generalized_velocity()[dof])
    }

    /// Forgets the secant history (a new start: the next step uses the structure's damping).
    pub(super) fn reset_secant(&mut self) {
        self.secant.iter_mut().for_each(|s| *s = None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// rapier's implicit step: (I + dt c) v' = I v + dt tau, dq = dt v'.
    fn step(dt: f64, c: f64, inertia: f64, v: f64, tau: f64) -> f64 {
        dt * (inertia * v + dt * tau) / (inertia + dt * c)
    }

    /// From rest, and with momentum along the force, the scheduled damping makes the step
    /// Newton's tau / k to round-off.
    #[test]
    fn scheduled_damping_turns_the_step_into_newtons() {
        let (dt, k, inertia) = (0.15, 200.0, 2.0 / 3.0);
        for (v, tau) in [(0.0, -12.0), (-0.05, -12.0), (0.3, 40.0)] {
            let c = newton_damping(dt, k, inertia, v, tau);
            let dq = step(dt, c, inertia, v, tau);
            assert!((dq - tau / k).abs() < 1e-15, "v {v}, tau {tau}: step {dq} against {}", tau / k);
        }
    }

    /// Momentum against the force (left over from the last step): the damping stops the joint,
    /// the step is at most 1e-6 of what the momentum alone would carry.
    #[test]
    fn momentum_against_the_force_is_stopped() {
        let (dt, k, inertia) = (0.15, 200.0, 2.0 / 3.0);
        let (v, tau) = (-4.8e-4, 5.6e-7);
        let c = newton_damping(dt, k, inertia, v, tau);
        let dq = step(dt, c, inertia, v, tau);
        let coasting = step(dt, 0.0, inertia, v, tau);
        assert!(dq.abs() <= 1e-6 * coasting.abs(), "step {dq:e} against {coasting:e} undamped");
    }

    /// Momentum too small to reach Newton's point even undamped: no damping at all.
    #[test]
    fn short_momentum_gets_no_damping() {
        // With dt^2 k / I < 1 an undamped step from rest falls short of tau / k.
        let (dt, k, inertia) = (0.01, 200.0, 2.0 / 3.0);
        assert_eq!(newton_damping(dt, k, inertia, 0.0, -12.0), 0.0);
    }
}
