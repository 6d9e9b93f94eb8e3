//! The same simulation at another time step, and the start of a motion at a half step.
//!
//! rapier steps semi-implicit Euler: v(n+1) = v(n) + h a(x(n)), x(n+1) = x(n) + h v(n+1). Read
//! with the velocities at the half steps, that is the leapfrog (Stormer-Verlet) scheme, which is
//! symmetric: its global error at the tick times is an even series in h (h^2, h^4, ...). It
//! starts there only when the velocity it starts from is the one half a step before the start,
//! v(-h/2) = v(0) - h/2 a(x(0)); from v(0) itself the error is first order (the pinned bar at
//! 0.5 rad: 4.3e-3 rad at h = 1e-3 s). `Simulation::start_at_half_step` takes the velocity back
//! by half of what one step adds to it, with the step itself measuring a(x(0)) on a copy.
//!
//! Copies at h / 2, h / 4, ... (`Simulation::at_time_step`) from the same state are what a
//! Richardson extrapolation over the step combines (`run/levels.rs`).

use super::data::Data;
use super::model::Model;
use nalgebra::DVector;
use rapier3d_f64::prelude::*;

impl Clone for Data {
    /// The same state with a new pipeline (rapier's pipeline holds only work buffers).
    fn clone(&self) -> Self {
        Data {
            pipeline: PhysicsPipeline::new(),
            params: self.params,
            islands: self.islands.clone(),
            broad_phase: self.broad_phase.clone(),
            narrow_phase: self.narrow_phase.clone(),
            bodies: self.bodies.clone(),
            colliders: self.colliders.clone(),
            impulse_joints: self.impulse_joints.clone(),
            multibody_joints: self.multibody_joints.clone(),
            soft_bodies: self.soft_bodies.clone(),
            ccd: self.ccd.clone(),
            rest_lengths: self.rest_lengths.clone(),
            material: self.material.clone(),
            at_bound: self.at_bound.clone(),
            commands: self.commands.clone(),
            probe_loads: self.probe_loads.clone(),
            tick: self.tick,
            locked_coordinates: self.locked_coordinates.clone(),
            constraint_inputs: self.constraint_inputs,
            kept_momenta: self.kept_momenta.clone(),
        }
    }
}

/// Every velocity the step integrates: each multibody's generalized velocities and each plain
/// free body's linear velocity and angular momentum (world frame: what a step's kick changes by
/// the torques' impulse, whatever the body's turn, `rotation.rs`).
struct Velocities {
    multibodies: Vec<(MultibodyIndex, DVector<f64>)>,
    bodies: Vec<(usize, Vector, Vector)>,
}

impl Data {
    /// Whether any free body is a plain rigid body, not a multibody link.
    pub(super) fn has_plain_free_bodies(&self, m: &Model) -> bool {
        m.handles.iter().enumerate().any(|(b, &h)| m.is_free(b) && self.multibody_joints.rigid_body_link(h).is_none())
    }

    fn velocities(&self, m: &Model) -> Velocities {
        let mut multibodies: Vec<(MultibodyIndex, DVector<f64>)> = Vec::new();
        let mut bodies = Vec::new();
        for (b, &h) in m.handles.iter().enumerate() {
            if !m.is_free(b) {
                continue;
            }
            match self.multibody_joints.rigid_body_link(h) {
                Some(link) if multibodies.iter().all(|(i, _)| *i != link.multibody) => {
                    if let Some(mb) = self.multibody_joints.get_multibody(link.multibody) {
                        multibodies.push((link.multibody, mb.generalized_velocity().clone_owned()));
                    }
                }
                Some(_) => {}
                None => bodies.push((b, self.bodies[h].linvel(), self.angular_momentum(m, b))),
            }
        }
        Velocities { multibodies, bodies }
    }

    /// Sets every velocity of `v`.
    fn set_velocities(&mut self, m: &Model, v: &Velocities) {
        for (index, u) in &v.multibodies {
            if let Some(mb) = self.multibody_joints.get_multibody_mut(*index) {
                mb.generalized_velocity_mut().copy_from(u);
            }
        }
        for &(b, lin, momentum) in &v.bodies {
            self.bodies[m.handles[b]].set_linvel(lin, true);
            self.set_angular_momentum(m, b, momentum);
        }
    }
}

impl Velocities {
    /// v0 - (v1 - v0) / 2, componentwise: `self` is v0, `after` is v1.
    fn half_step_back(&self, after: &Velocities) -> Velocities {
        let back = |v0: f64, v1: f64| v0 - 0.5 * (v1 - v0);
        let multibodies = self
            .multibodies
            .iter()
            .map(|(i, u0)| {
                let u1 = after.multibodies.iter().find(|(j, _)| j == i).map_or(u0, |(_, u)| u);
                (*i, u0.zip_map(u1, back))
            })
            .collect();
        let bodies = self
            .bodies
            .iter()
            .map(|&(b, l0, a0)| {
                let (l1, a1) = after.bodies.iter().find(|x| x.0 == b).map_or((l0, a0), |x| (x.1, x.2));
                let vec = |x: Vector, y: Vector| Vector::new(back(x.x, y.x), back(x.y, y.y), back(x.z, y.z));
                (b, vec(l0, l1), vec(a0, a1))
            })
            .collect();
        Velocities { multibodies, bodies }
    }
}

impl Data {
    /// Takes every velocity back by half of what one step adds to it: `after` is the state one
    /// step on from this one (a trial step of a copy).
    pub(super) fn half_step_back(&mut self, m: &Model, after: &Data) {
        let (before, after) = (self.velocities(m), after.velocities(m));
        self.set_velocities(m, &before.half_step_back(&after));
    }
}
