//! The Newton damping schedule (`sim.newton_damping = true`), a settling strategy.
//!
//! Joint damping is implicit in rapier's multibody step: from rest, with damping c, effective
//! inertia I and the explicit generalized force tau(q) of the loads, one step of length dt moves
//! a coordinate by dq = dt^2 tau / (I + dt c). With I + dt c = dt^2 k, k = -dtau/dq the tangent
//! stiffness, that is Newton's step tau / k. A fixed c fits one stiffness only: too little
//! overshoots (and can jump to another equilibrium branch), too much creeps (BENCHMARKS.md's
//! scan on ji2014).
//!
//! Before every step the schedule takes each damped revolute or prismatic multibody joint
//! (not actuated), computes its generalized force tau and tangent stiffness k from the force
//! laws (springs, elastic cables, gravity and external loads on the bodies it carries, its own
//! torsion spring; every other coordinate held), and where k > 0 it quenches the joint's
//! velocity (kinetic damping, as in dynamic relaxation) and sets the damping that makes the
//! step Newton's; where the bodies are too heavy for that (dt^2 k < I, no damping reaches
//! Newton's point from rest), it sets instead the velocity from which the undamped step does,
//! if that step is at most 0.5 rad (0.25 of the structure's size). Where k <= 0 (near an unstable equilibrium) the joint keeps the structure's
//! damping and its momentum: it moves away as the dynamics say. Velocity and damping are zero
//! at rest, so the equilibrium is the same as with any fixed damping; only the path to it
//! changes.

use super::data::Data;
use super::model::Model;
use crate::structure::JointKind;
use rapier3d_f64::prelude::*;

/// The damping [N m s/rad or N s/m] that makes rapier's implicit step from rest Newton's:
/// I + dt c = dt^2 k. When even the undamped step falls short of Newton's point
/// (dt^2 k < I), 0.
fn newton_damping(dt: f64, stiffness: f64, inertia: f64) -> f64 {
    (dt * stiffness - inertia / dt).max(0.0)
}

/// Largest Newton step taken by a start velocity (below), revolute [rad].
const MAX_NEWTON_TURN_RAD: f64 = 0.5;
/// Largest Newton step taken by a start velocity, prismatic, as a fraction of the structure's
/// size.
const MAX_NEWTON_SLIDE_FRACTION: f64 = 0.25;

/// The joint velocity [rad/s or m/s] from which rapier's undamped implicit step reaches
/// Newton's point tau / k when damping cannot (dt^2 k < I: from rest the step would fall short,
/// by dt^2 k / I of the way, and creep): dq = dt v + dt^2 tau / I = tau / k. 0 (rest, the
/// damping does what it can) where damping can, or where tau / k is longer than `max_step`
/// (a nearly flat stiffness, whose Newton point the linear model does not reach: on ji2014's
/// grid a start velocity there diverged, measured).
fn newton_velocity(dt: f64, force: f64, stiffness: f64, inertia: f64, max_step: f64) -> f64 {
    if dt * dt * stiffness >= inertia || (force / stiffness).abs() > max_step {
        0.0
    } else {
        force / (stiffness * dt) - dt * force / inertia
    }
}

/// Steps over which the schedule must lower the largest generalized force of the joints it
/// drives by [`STALL_PROGRESS`], or stop ([`Schedule`]); Newton's steps lower it by orders of
/// magnitude in tens of steps (the shipped files' scheduled points take 6 to 62).
const STALL_WINDOW_STEPS: u32 = 200;
/// The fraction of its value at a window's start below which the force must have fallen by the
/// window's end.
const STALL_PROGRESS: f64 = 0.1;
/// A force below this fraction of the first one the schedule saw at the point is round-off: no
/// stall is read there.
const STALL_FLOOR_RATIO: f64 = 1e-6;

/// Whether the schedule still drives the joints at this point (the actuators' commands: a new
/// point starts afresh). Each joint's Newton step holds the others (a Jacobi iteration on the
/// joints' coordinates): where the joints are coupled more strongly than each is held (a chain
/// of sliders under a spring across their axes) it does not converge, and the settle would
/// never end or blow up (a bead on three sliders: 6000 steps, 11 J of kinetic energy left,
/// where the physical dynamics settle in 5.6 s). So when the largest generalized force has not
/// fallen to [`STALL_PROGRESS`] of itself over [`STALL_WINDOW_STEPS`] steps the schedule stops,
/// the joints' damping back to the structure's: the physical dynamics finish the settle.
#[derive(Clone, Default)]
pub(super) struct Schedule {
    /// Set once the schedule has stalled: it drives nothing from then on.
    pub(super) stalled: bool,
    first_force: Option<f64>,
    window_start: f64,
    steps: u32,
}

impl Schedule {
    /// Notes the largest generalized force of a step the schedule drove; whether it has
    /// stalled now.
    pub(super) fn stalls(&mut self, force: f64) -> bool {
        let first = *self.first_force.get_or_insert(force);
        if self.steps == 0 {
            self.window_start = force;
        }
        self.steps += 1;
        if self.steps == STALL_WINDOW_STEPS {
            self.steps = 0;
            self.stalled = force > STALL_PROGRESS * self.window_start && force > STALL_FLOOR_RATIO * first;
        }
        self.stalled
    }
}

/// One joint's load for the coming step.
#[derive(Clone, Copy, Debug, PartialEq)]
struct JointLoad {
    /// Generalized force of the applied loads [N m or N].
    force: f64,
    /// Tangent stiffness -d(force)/dq, every other coordinate held [N m/rad or N/m].
    stiffness: f64,
    /// Inertia of the bodies the joint carries about (along) its axis, every other coordinate
    /// held [kg m^2 or kg].
    inertia: f64,
}

/// How the bodies a joint carries move with its coordinate: a point x moves by `rate(x)` per
/// unit coordinate, and that rate changes by `rate_change(x)` per unit coordinate.
pub(super) struct JointMotion {
    /// The joint's axis in the world, unit.
    pub(super) axis: Vector,
    /// The joint's anchor in the world [m].
    pub(super) anchor: Vector,
    /// Revolute (turns about the axis) or prismatic (slides along it).
    pub(super) revolute: bool,
}

impl JointMotion {
    fn rate(&self, x: Vector) -> Vector {
        if self.revolute {
            self.axis.cross(x - self.anchor)
        } else {
            self.axis
        }
    }

    fn rate_change(&self, x: Vector) -> Vector {
        if self.revolute {
            self.axis.cross(self.rate(x))
        } else {
            Vector::ZERO
        }
    }

    /// Stiffness contribution -d(rate(x) . F)/dq of a force F at a carried point x that does
    /// not depend on the coordinate (gravity, external loads).
    fn constant_force_stiffness(&self, x: Vector, f: Vector) -> f64 {
        -self.rate_change(x).dot(f)
    }

    /// Stiffness contribution of a tension member of tension `t` [N], force-law slope
    /// `slope` [N/m] and length `l` [m] along `unit` (from the carried end x towards the
    /// held one), when only the end x moves: the carried end feels F = t unit, and
    /// dF/dq = -(slope unit unit^T + t / l (1 - unit unit^T)) rate(x).
    fn member_stiffness(&self, x: Vector, unit: Vector, t: f64, slope: f64, l: f64) -> f64 {
        let r = self.rate(x);
        let along = unit.dot(r);
        -self.rate_change(x).dot(unit * t) + slope * along * along + t / l * (r.length_squared() - along * along)
    }
}

impl Data {
    /// The joints the schedule drives: damped, free, revolute or prismatic multibody links.
    pub(super) fn scheduled(&self, m: &Model, j: usize) -> bool {
        let joint = &m.structure.joints[j];
        m.joint_links[j].is_some()
            && !m.actuated[j]
            && joint.damping > 0.0
            && matches!(joint.kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. })
    }

    /// Joint `j`'s generalized force, tangent stiffness and inertia for the coming step (after
    /// the member forces are applied).
    /// Joint `j`'s axis and anchor as its parent now carries them, if revolute or prismatic.
    pub(super) fn joint_motion(&self, m: &Model, j: usize) -> Option<JointMotion> {
        let s = &m.structure;
        let joint = &s.joints[j];
        let (axis, revolute) = match joint.kind {
            JointKind::Revolute { axis } => (axis, true),
            JointKind::Prismatic { axis } => (axis, false),
            _ => return None,
        };
        let parent = self.bodies[m.handles[joint.parent]].position();
        Some(JointMotion {
            axis: (parent.rotation * Vector::from(axis)).normalize(),
            anchor: parent.transform_point(Vector::from(s.nodes[joint.anchor].position)),
            revolute,
        })
    }

    fn joint_load(&self, m: &Model, j: usize) -> JointLoad {
        let tree = &m.tree;
        let s = &m.structure;
        let joint = &s.joints[j];
        let motion = self.joint_motion(m, j).expect("scheduled joints are revolute or prismatic");
        let revolute = motion.revolute;
        let carried = |b: usize| m.is_free(b) && tree.descends_from(b, joint.child);
        let g = Vector::new(s.gravity[0], s.gravity[1], s.gravity[2]);
        let mut load = JointLoad { force: 0.0, stiffness: 0.0, inertia: 0.0 };
        // Loads on the carried bodies as rapier will apply them (member forces were put on the
        // bodies as a force at the centre of mass plus its moment): their generalized force.
        for b in (0..s.bodies.len()).filter(|b| carried(*b)) {
            let rb = &self.bodies[m.handles[b]];
            // From the current pose: rapier's cached centre of mass is stale before the first step.
            let com = self.world_com(m, b);
            // The structure's mass: rapier's is zero until the first step has computed the
            // bodies' mass properties (measured: a weight on a slide kicked 8.8 mm up by the
            // first Newton step, which a cable with friction then remembers).
            let mass = s.bodies[b].inertia.map_or(0.0, |i| i.mass_kg);
            let gravity = g * mass * rb.gravity_scale();
            let f = rb.user_force() + gravity;
            load.force += motion.rate(com).dot(f) + if revolute { motion.axis.dot(rb.user_torque()) } else { 0.0 };
            // Forces that do not change with the coordinate: gravity and the external loads.
            let (probe, _) = self.probe_loads[b];
            let e = m.external_loads[b];
            let constant = gravity + Vector::new(probe[0] + e[0], probe[1] + e[1], probe[2] + e[2]);
            load.stiffness += motion.constant_force_stiffness(com, constant);
            let inertia = s.bodies[b].inertia.expect("free bodies have inertia");
            load.inertia += if revolute {
                let u = rb.position().rotation.inverse() * motion.axis;
                let p = inertia.principal_kg_m2;
                p[0] * u.x * u.x
                    + p[1] * u.y * u.y
                    + p[2] * u.z * u.z
                    + inertia.mass_kg * motion.axis.cross(com - motion.anchor).length_squared()
            } else {
                inertia.mass_kg
            };
        }
        // Point loads on carried nodes: constant forces at points that move with the coordinate.
        for &(node, force) in m.node_loads.iter().filter(|(n, _)| carried(s.nodes[*n].body)) {
            let at = Vector::from(self.node_position(m, node));
            load.stiffness += motion.constant_force_stiffness(at, Vector::new(force.x, force.y, force.z));
        }
        // Springs and elastic cables with one end of a segment carried: their force changes
        // with the coordinate (a segment with both ends carried moves rigidly and adds nothing).
        // A clustered cable's segments are taken each with the whole cable's tension and
        // stiffness: an estimate for the schedule, which is no part of a physical path.
        for (i, member) in s.members_by_kind() {
            let Some(law) = self.elastic_law(m, i) else { continue };
            let segment_laws = self.segment_laws(m, i);
            for (k, (a, b)) in member.segments().enumerate() {
                let (a_carried, b_carried) = (carried(s.nodes[a].body), carried(s.nodes[b].body));
                if a_carried == b_carried {
                    continue;
                }
                let (x, other) = if a_carried { (a, b) } else { (b, a) };
                let (px, po) = (Vector::from(self.node_position(m, x)), Vector::from(self.node_position(m, other)));
                let d = po - px;
                let l = d.length();
                // The whole path's length (a straight member's is this segment's); a cable with
                // friction: the segment's own law (held at its node).
                let (law, length) = match &segment_laws {
                    Some(laws) => (laws[k], l),
                    None if member.is_clustered() => (law, self.member_length_m(m, i)),
                    None => (law, l),
                };
                if l <= 0.0 || !law.engaged(length) {
                    continue;
                }
                load.stiffness += motion.member_stiffness(px, d / l, law.tension_n(length), law.stiffness_n_per_m, l);
            }
        }
        if let (Some(t), true) = (&joint.torsion_spring, revolute) {
            load.force += self.torsion_spring_torque(m, j);
            load.stiffness += t.stiffness_nm_per_rad;
        }
        load
    }

    /// Sets every scheduled joint's velocity and damping for the coming step (after the loads
    /// are applied). Whether it set any (a joint with k > 0: its velocity quenched or set, its
    /// damping not the structure's; the step is then no part of a physical path), with the
    /// largest generalized force among those joints [N m or N].
    pub(super) fn schedule_damping(&mut self, m: &Model) -> Option<f64> {
        let dt = m.settings.dt_s;
        let mut acted: Option<f64> = None;
        for j in 0..m.structure.joints.len() {
            if !self.scheduled(m, j) {
                continue;
            }
            let Some((mb_index, dof)) = self.dof_of(m, j) else { continue };
            let load = self.joint_load(m, j);
            let mut damping = super::joint_data::link_damping(&m.structure, j, m.settings.body_damping_per_s);
            if load.stiffness > 0.0 && load.inertia > 0.0 {
                acted = Some(acted.unwrap_or(0.0).max(load.force.abs()));
                damping = newton_damping(dt, load.stiffness, load.inertia);
                let max_step = match m.structure.joints[j].kind {
                    JointKind::Revolute { .. } => MAX_NEWTON_TURN_RAD,
                    _ => MAX_NEWTON_SLIDE_FRACTION * m.length_scale_m,
                };
                let velocity = newton_velocity(dt, load.force, load.stiffness, load.inertia, max_step);
                if let Some(mb) = self.multibody_joints.get_multibody_mut(mb_index) {
                    mb.generalized_velocity_mut()[dof] = velocity;
                }
            }
            if let Some(link) = m.joint_links[j] {
                super::joint_data::set_link_damping(&mut self.multibody_joints, link.multibody_joint, damping);
            }
        }
        acted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// rapier's implicit step: (I + dt c) v' = I v + dt tau, dq = dt v'.
    fn step(dt: f64, c: f64, inertia: f64, v: f64, tau: f64) -> f64 {
        dt * (inertia * v + dt * tau) / (inertia + dt * c)
    }

    /// From rest the scheduled damping makes the step Newton's tau / k to round-off.
    #[test]
    fn scheduled_damping_turns_the_step_into_newtons() {
        let (dt, k, inertia) = (0.15, 200.0, 2.0 / 3.0);
        for tau in [-12.0, 5.6e-7, 40.0] {
            let c = newton_damping(dt, k, inertia);
            let dq = step(dt, c, inertia, 0.0, tau);
            assert!((dq - tau / k).abs() <= 1e-15 * (tau / k).abs(), "tau {tau}: step {dq} against {}", tau / k);
        }
    }

    /// Stiffness too small to reach Newton's point even undamped: no damping at all.
    #[test]
    fn short_step_gets_no_damping() {
        // With dt^2 k / I < 1 an undamped step from rest falls short of tau / k.
        let (dt, k, inertia) = (0.01, 200.0, 2.0 / 3.0);
        assert_eq!(newton_damping(dt, k, inertia), 0.0);
    }

    /// Where damping cannot make the step Newton's (dt^2 k < I), the velocity set before the
    /// undamped step does: the step lands on tau / k to round-off; where damping can, or the
    /// step is beyond the limit, the joint starts from rest.
    #[test]
    fn a_short_step_starts_with_the_velocity_that_reaches_newtons_point() {
        let (dt, k, inertia) = (0.005, 100.0, 0.37);
        for tau in [-3.0, 2.5e-9, 12.0] {
            let v = newton_velocity(dt, tau, k, inertia, MAX_NEWTON_TURN_RAD);
            let dq = step(dt, newton_damping(dt, k, inertia), inertia, v, tau);
            assert!((dq - tau / k).abs() <= 1e-15 * (tau / k).abs(), "tau {tau}: step {dq} against {}", tau / k);
        }
        assert_eq!(newton_velocity(0.15, 4.0, 200.0, 2.0 / 3.0, MAX_NEWTON_TURN_RAD), 0.0);
        // A Newton step longer than the limit (200 rad here) is not taken.
        assert_eq!(newton_velocity(dt, 2e4, k, inertia, MAX_NEWTON_TURN_RAD), 0.0);
    }

    /// A pendulum of mass m at radius r under gravity: tau = -m g r sin q about the pivot, so
    /// the tangent stiffness is m g r cos q (to round-off).
    #[test]
    fn gravity_stiffness_of_a_pendulum_is_m_g_r_cos_q() {
        let motion = JointMotion { axis: Vector::Z, anchor: Vector::ZERO, revolute: true };
        let (m, g, r) = (2.0, 9.81, 0.7);
        for q in [0.0, 0.4, 2.0] {
            // q from the hanging position (straight down), counter-clockwise about z.
            let bob = Vector::new(r * q.sin(), -r * q.cos(), 0.0);
            let k = motion.constant_force_stiffness(bob, Vector::new(0.0, -m * g, 0.0));
            let expected = m * g * r * q.cos();
            assert!((k - expected).abs() <= 1e-12 * m * g * r, "q {q}: {k} against {expected}");
        }
    }

    /// The tangent stiffness of a zero-free-length spring on a revolute joint matches the
    /// central difference of its generalized force to 1e-8 relative.
    #[test]
    fn member_stiffness_is_the_derivative_of_the_generalized_force() {
        let motion = JointMotion { axis: Vector::Z, anchor: Vector::new(0.3, -0.2, 0.0), revolute: true };
        let held = Vector::new(-1.0, 0.5, 0.0);
        let (k, rest) = (200.0, 0.25);
        // The carried node at angle q about the anchor, radius 0.8 m.
        let node = |q: f64| motion.anchor + Vector::new(0.8 * q.cos(), 0.8 * q.sin(), 0.0);
        let tau = |q: f64| {
            let x = node(q);
            let d = held - x;
            let l = d.length();
            motion.rate(x).dot(d / l * k * (l - rest))
        };
        let q = 0.7;
        let h = 1e-5;
        let numeric = -(tau(q + h) - tau(q - h)) / (2.0 * h);
        let x = node(q);
        let d = held - x;
        let l = d.length();
        let analytic = motion.member_stiffness(x, d / l, k * (l - rest), k, l);
        assert!((analytic - numeric).abs() <= 1e-8 * numeric.abs(), "{analytic} against {numeric}");
    }
}
