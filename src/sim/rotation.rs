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
//!
//! The turn itself is added as an increment with its rounding carried to the next step (Kahan's
//! compensated sum): R(n+1) = R(n) + (exp(dt w*) - 1) R(n)   (2),
//! with exp(dt w*) - 1 formed without cancellation (its scalar part -2 sin^2(|dt w*| / 4)). Made
//! as exp(dt w*) R(n) and normalised, each step rounds the rotation by about 1e-16 rad, which a
//! spin of 2000 steps in 0.5 s (dt = 1 ms judged, its finest level) sums to 8e-15 m; compensated,
//! 1.4e-15, the extrapolation's own truncation.
//!
//! L is carried from step to step as the body's state ([`KeptMomentum`]), the kick added to it
//! as an increment, L(n+1) = L(n) + I_w(R(n)) (w' - w), rather than made again from the angular
//! velocity each step: the round trip L -> w -> L through the rotated inertia rounds |L| by about
//! 1e-16 a step with a bias, which a torque-free spin turned into an angle error growing with
//! the step count (1.2e-12 m after 0.5 s judged at dt = 1 ms, 4.9e-12 at 0.25 ms; kept, 9.6e-15
//! and 2.0e-14: round-off without a trend). A velocity or a pose set from outside the step (a
//! spin, a half-step start, a restart, a projection) is seen as other than the kept one, and L
//! is made from the velocity once (the carried rounding of (2) is dropped with a new pose).

use super::data::Data;
use super::model::Model;
use rapier3d_f64::prelude::*;

/// The norm of a turned rotation may leave 1 by this much before it is normalised: (2) keeps
/// it to round-off, a random walk of about 1e-16 a step.
const NORM_SLACK: f64 = 1e-12;

/// Most fixed-point iterations of (1); each contracts by about |w| dt.
const MAX_MIDPOINT_ITERATIONS: usize = 50;
/// The iteration of (1) has converged when w* changes by less than this fraction of |w*|.
const MIDPOINT_TOLERANCE: f64 = 1e-15;

/// Whether plain free bodies turn by (1) (physical motion) or by rapier's own update.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct FreeRotation {
    pub(super) on: bool,
}

/// A plain free body's world angular momentum as (1) carried it \[kg m^2/s\], with the angular
/// velocity (world) \[rad/s\] and the rotation it was last set to: while the body's are still
/// those, L is this, not made again from the velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct KeptMomentum {
    angvel: Vector,
    momentum: Vector,
    /// The rotation (2) reached and the rounding it carries to the next step's sum (x, y, z, w).
    rotation: Rotation,
    carry: [f64; 4],
}

/// A plain free body at a step's start: its index, rotation, angular velocity and world angular
/// momentum.
pub(super) struct FreeBodyStart {
    body: usize,
    rotation: Rotation,
    angvel: Vector,
    momentum: Vector,
    /// The rounding (2) carries into this step's sum (zero after a rotation set from outside).
    carry: [f64; 4],
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

/// (1) and (2): the rotation a body with rotation `r0` and constant angular momentum `l` reaches
/// after `dt_s`, and the rounding carried on; `carry` is what the step before carried.
fn midpoint_turn(
    r0: Rotation,
    frame: Rotation,
    inertia: Vector,
    l: Vector,
    dt_s: f64,
    carry: [f64; 4],
) -> (Rotation, [f64; 4]) {
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
    let turn = w * dt_s;
    let angle = turn.length();
    if angle == 0.0 {
        return (r0, carry);
    }
    let (axis, half_sin, quarter_sin) = (turn / angle, (0.5 * angle).sin(), (0.25 * angle).sin());
    let less_one =
        Rotation::from_xyzw(axis.x * half_sin, axis.y * half_sin, axis.z * half_sin, -2.0 * quarter_sin * quarter_sin);
    let increment = less_one * r0;
    let (q, dq) = ([r0.x, r0.y, r0.z, r0.w], [increment.x, increment.y, increment.z, increment.w]);
    let (mut sum, mut rounding) = ([0.0; 4], [0.0; 4]);
    for k in 0..4 {
        let y = dq[k] - carry[k];
        sum[k] = q[k] + y;
        rounding[k] = (sum[k] - q[k]) - y;
    }
    let r1 = Rotation::from_xyzw(sum[0], sum[1], sum[2], sum[3]);
    let norm = r1.length();
    if (norm - 1.0).abs() <= NORM_SLACK {
        return (r1, rounding);
    }
    (r1 / norm, rounding.map(|c| c / norm))
}

impl Data {
    /// The plain free bodies (free, no multibody link) at the step's start.
    pub(super) fn free_rotations(&self, m: &Model) -> Vec<FreeBodyStart> {
        (0..m.handles.len())
            .filter(|&b| m.is_free(b) && self.multibody_joints.rigid_body_link(m.handles[b]).is_none())
            .map(|b| {
                let rb = &self.bodies[m.handles[b]];
                FreeBodyStart {
                    body: b,
                    rotation: rb.position().rotation,
                    angvel: rb.angvel(),
                    momentum: self.angular_momentum(m, b),
                    carry: self.carry(m, b),
                }
            })
            .collect()
    }

    /// Turns rapier's gyroscopic term off on every plain free body (its rotation is (1)'s), and
    /// has rapier compute its mass properties now (it does so lazily, in a step: a motion from
    /// the drawn state reads them before its first step).
    pub(super) fn end_gyroscopic_forces(&mut self, m: &Model) {
        for start in self.free_rotations(m) {
            let rb = &mut self.bodies[m.handles[start.body]];
            rb.enable_gyroscopic_forces(false);
            rb.recompute_mass_properties_from_colliders(&self.colliders);
        }
    }

    /// After a step of rapier's: each body of `before` (at the step's start) turned by (1)
    /// instead, about its centre of mass, with its momentum at the start plus the step's kick,
    /// its angular velocity that of the same momentum at the new rotation.
    pub(super) fn turn_free_bodies(&mut self, m: &Model, before: &[FreeBodyStart]) {
        let dt_s = self.params.dt;
        for start in before {
            let rb = &mut self.bodies[m.handles[start.body]];
            let props = rb.mass_properties().local_mprops;
            let (frame, inertia) = (props.principal_inertia_local_frame, props.principal_inertia());
            let kick = momentum(start.rotation, frame, inertia, rb.angvel() - start.angvel);
            let l = start.momentum + kick;
            let (r1, carry) = midpoint_turn(start.rotation, frame, inertia, l, dt_s, start.carry);
            let com = rb.center_of_mass();
            let origin = com - r1 * props.local_com;
            rb.set_position(Pose::from_parts(origin, r1), true);
            let w = angvel(r1, frame, inertia, l);
            rb.set_angvel(w, true);
            self.kept_momenta[start.body] = Some(KeptMomentum { angvel: w, momentum: l, rotation: r1, carry });
        }
    }
}

impl Data {
    /// The rounding (2) carries into body `b`'s next turn: the kept one while its rotation is the
    /// one kept with it, none after a pose set from outside the step.
    fn carry(&self, m: &Model, b: usize) -> [f64; 4] {
        let rotation = self.bodies[m.handles[b]].position().rotation;
        self.kept_momenta[b].filter(|k| k.rotation == rotation).map_or([0.0; 4], |k| k.carry)
    }

    /// Body `b`'s world angular momentum now: the kept one while its rotation and angular
    /// velocity are those kept with it (nothing outside the step has set either since).
    pub(super) fn angular_momentum(&self, m: &Model, b: usize) -> Vector {
        let rb = &self.bodies[m.handles[b]];
        match self.kept_momenta[b] {
            Some(kept) if kept.angvel == rb.angvel() && kept.rotation == rb.position().rotation => kept.momentum,
            _ => {
                let props = rb.mass_properties().local_mprops;
                momentum(
                    rb.position().rotation,
                    props.principal_inertia_local_frame,
                    props.principal_inertia(),
                    rb.angvel(),
                )
            }
        }
    }

    /// Sets body `b`'s angular velocity to that of world angular momentum `l` at its rotation now,
    /// and keeps `l`.
    pub(super) fn set_angular_momentum(&mut self, m: &Model, b: usize, l: Vector) {
        let rb = &mut self.bodies[m.handles[b]];
        let props = rb.mass_properties().local_mprops;
        let rotation = rb.position().rotation;
        let w = angvel(rotation, props.principal_inertia_local_frame, props.principal_inertia(), l);
        rb.set_angvel(w, true);
        let carry = self.carry(m, b);
        self.kept_momenta[b] = Some(KeptMomentum { angvel: w, momentum: l, rotation, carry });
    }
}

#[cfg(test)]
mod tests {
    use super::super::Simulation;
    use crate::settings::SimSettings;
    use crate::structure::{BodyKind, Inertia, Structure};

    /// A free body of principal moments 1, 2, 3 kg m^2 spun at w0 [rad/s], on the physical path.
    fn spinning(w0: [f64; 3], dt_s: f64) -> Simulation {
        let mut s = Structure { name: "spin".into(), gravity: [0.0; 3], ..Default::default() };
        let inertia = Inertia { mass_kg: 1.0, com: [0.0; 3], principal_kg_m2: [1.0, 2.0, 3.0] };
        let body = s.add_body("top", BodyKind::Free, Some(inertia));
        s.add_node("tip", body, [1.0, 0.0, 0.0]);
        let settings = SimSettings {
            dt_s,
            body_damping_per_s: 0.0,
            relaxation: false,
            newton_damping: false,
            ..Default::default()
        };
        let mut sim = Simulation::new(&s, &settings).expect("builds");
        sim.end_acceleration();
        sim.set_body_spin(body, w0).expect("spins");
        sim
    }

    /// Torque-free, the step keeps the body's angular momentum to round-off: over 32 s at
    /// dt = 1 ms (32000 steps, the spin of tests/it/free_spin.rs) L moves by less than 1e-13 of
    /// |L| (measured 0: it is carried, not remade). The kinetic energy L . I_w^-1 L / 2 at the
    /// midpoint rule's rotations deviates at second order in dt with no drift, within 1e-8
    /// (measured 4.4e-9; the judged motion, extrapolated, keeps it to 1e-9: free_spin.rs).
    #[test]
    fn a_torque_free_spin_keeps_its_momentum_and_energy() {
        let mut sim = spinning([0.3, 0.2, 4.0], 1e-3);
        sim.start_at_half_step().expect("half step");
        let l0 = sim.data.angular_momentum(&sim.model, 0);
        let e0 = sim.kinetic_energy_j();
        let mut de: f64 = 0.0;
        for _ in 0..32_000 {
            sim.step().expect("steps");
            de = de.max(((sim.kinetic_energy_j() - e0) / e0).abs());
        }
        let l1 = sim.data.angular_momentum(&sim.model, 0);
        let dl = (l1 - l0).length() / l0.length();
        assert!(dl <= 1e-13 && de <= 1e-8, "L moved by {dl:e} of |L|, the energy by {de:e}");
    }
}
