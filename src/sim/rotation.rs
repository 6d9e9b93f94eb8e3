//! A plain free body's rotation in physical motion, second order: the implicit midpoint rule on
//! its angular momentum.
//!
//! rapier integrates a free body's gyroscopic term w x I w explicitly, rescaled to keep |L|
//! (`rigid_body::gyroscopic_corrected_angvel`): first order in the time step (a torque-free spin
//! over 32 s drifted 0.038 rad at 1 ms, order 1.43), which Richardson's rule over the step
//! cannot cancel. In physical motion ([`FreeRotation::on`], from `end_acceleration`) every
//! plain free body (not a multibody link) has rapier's gyroscopic term off, and after each step
//! its rotation is made again from the step's start R(n) and its world angular momentum after
//! the step's kick, L = I_w(R(n)) w' (rapier's own kick of the torques, w' its angular velocity
//! after the step; one step of rapier's, not substepped): torque-free over the step, L is
//! constant and the body turns by
//!   R(n+1) = exp(dt w*) R(n),  w* = I_w(R_mid)^-1 L,  R_mid = exp(dt w* / 2) R(n)   (1)
//! (the implicit midpoint rule on SO(3), solved by fixed-point iteration: symmetric in time, so
//! second order, and with the translation's leapfrog the whole step's error is even in dt). The
//! centre of mass stays where rapier's step put it, and the stored angular velocity becomes
//! I_w(R(n+1))^-1 L, so that the next kick adds the torque's impulse to L.

use super::{Data, Model};
use rapier3d_f64::prelude::*;

/// Most fixed-point iterations of (1); each contracts by about |w| dt.
const MAX_MIDPOINT_ITERATIONS: usize = 50;
/// The iteration of (1) has converged when w* changes by less than this fraction of |w*|.
const MIDPOINT_TOLERANCE: f64 = 1e-15;

/// Whether plain free bodies turn by (1) (physical motion) or by rapier's own update.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct FreeRotation {
    pub(super) on: bool,
}

/// A body's world angular momentum with rotation `r`, principal frame `frame` in the body,
/// principal moments `inertia`, angular velocity `w` (world).
pub(super) fn momentum(r: Rotation, frame: Rotation, inertia: Vector, w: Vector) -> Vector {
    let axes = r * frame;
    axes * (inertia * (axes.inverse() * w))
}

/// The angular velocity (world) of a body with rotation `r` and world angular momentum `l`.
pub(super) fn angvel(r: Rotation, frame: Rotation, inertia: Vector, l: Vector) -> Vector {
    let axes = r * frame;
    axes * ((axes.inverse() * l) / inertia)
}

/// (1): the rotation a body with rotation `r0` and constant angular momentum `l` reaches after
/// `dt_s`.
fn midpoint_turn(r0: Rotation, frame: Rotation, inertia: Vector, l: Vector, dt_s: f64) -> Rotation {
    let mut w = angvel(r0, frame, inertia, l);
    for _ in 0..MAX_MIDPOINT_ITERATIONS {
        let mid = Rotation::from_scaled_axis(w * (0.5 * dt_s)) * r0;
        let next = angvel(mid, frame, inertia, l);
        let change = (next - w).length();
        w = next;
        if change <= MIDPOINT_TOLERANCE * w.length() {
            break;
        }
    }
    (Rotation::from_scaled_axis(w * dt_s) * r0).normalize()
}

impl Data {
    /// The plain free bodies (free, no multibody link): their index and rotation now.
    pub(super) fn free_rotations(&self, m: &Model) -> Vec<(usize, Rotation)> {
        (0..m.handles.len())
            .filter(|&b| m.is_free(b) && self.multibody_joints.rigid_body_link(m.handles[b]).is_none())
            .map(|b| (b, self.bodies[m.handles[b]].position().rotation))
            .collect()
    }

    /// Turns rapier's gyroscopic term off on every plain free body (its rotation is (1)'s), and
    /// has rapier compute its mass properties now (it does so lazily, in a step: a motion from
    /// the drawn state reads them before its first step).
    pub(super) fn end_gyroscopic_forces(&mut self, m: &Model) {
        for (b, _) in self.free_rotations(m) {
            let rb = &mut self.bodies[m.handles[b]];
            rb.enable_gyroscopic_forces(false);
            rb.recompute_mass_properties_from_colliders(&self.colliders);
        }
    }

    /// After a step of rapier's: each body of `before` (its index and rotation at the step's
    /// start) turned by (1) instead, about its centre of mass, its angular velocity that of the
    /// same momentum at the new rotation.
    pub(super) fn turn_free_bodies(&mut self, m: &Model, before: &[(usize, Rotation)]) {
        let dt_s = self.params.dt;
        for &(b, r0) in before {
            let rb = &mut self.bodies[m.handles[b]];
            let props = rb.mass_properties().local_mprops;
            let (frame, inertia) = (props.principal_inertia_local_frame, props.principal_inertia());
            let l = momentum(r0, frame, inertia, rb.angvel());
            let r1 = midpoint_turn(r0, frame, inertia, l, dt_s);
            let com = rb.center_of_mass();
            let origin = com - r1 * props.local_com;
            rb.set_position(Pose::from_parts(origin, r1), true);
            rb.set_angvel(angvel(r1, frame, inertia, l), true);
        }
    }
}

impl Data {
    /// Body `b`'s world angular momentum now.
    pub(super) fn angular_momentum(&self, m: &Model, b: usize) -> Vector {
        let rb = &self.bodies[m.handles[b]];
        let props = rb.mass_properties().local_mprops;
        momentum(rb.position().rotation, props.principal_inertia_local_frame, props.principal_inertia(), rb.angvel())
    }

    /// Sets body `b`'s angular velocity to that of world angular momentum `l` at its rotation now.
    pub(super) fn set_angular_momentum(&mut self, m: &Model, b: usize, l: Vector) {
        let rb = &mut self.bodies[m.handles[b]];
        let props = rb.mass_properties().local_mprops;
        let w = angvel(rb.position().rotation, props.principal_inertia_local_frame, props.principal_inertia(), l);
        rb.set_angvel(w, true);
    }
}
