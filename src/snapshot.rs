//! What the simulation hands out at a tick: node positions, body poses, member forces and the
//! equilibrium residual, as plain data. Mechanisms and observers read these; they never see
//! the simulator's rapier sets.

use crate::structure::{JointKind, Structure};
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// The unit vector along `a` (zero stays zero).
pub fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if n > 0.0 {
        a.map(|x| x / n)
    } else {
        a
    }
}

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
    /// World position of every node, in structure order \[m\].
    pub nodes: Vec<[f64; 3]>,
    pub body_poses: Vec<BodyPose>,
    pub forces: MemberForces,
    /// Actuator commands, in structure order (m or rad).
    pub actuator_values: Vec<f64>,
    /// Kinetic energy of the free bodies \[J\].
    pub kinetic_energy_j: f64,
}

impl Snapshot {
    /// The force of the spring, cable or elastic strut `name` of structure `s` \[N\] (tension
    /// positive); None for a rigid strut, which has no law of its own.
    pub fn member_force_n(&self, s: &crate::structure::Structure, name: &str) -> Option<f64> {
        let i = s.member_id(name)?;
        (!s.members[i].is_rigid_strut()).then(|| self.forces.force_n.get(i).copied())?
    }

    /// A body's pose since the build (bodies are built at the identity).
    fn pose(&self, body: usize) -> Option<Isometry3<f64>> {
        let p = self.body_poses.get(body)?;
        let [x, y, z, w] = p.rotation_xyzw;
        let r = UnitQuaternion::new_normalize(Quaternion::new(w, x, y, z));
        Some(Isometry3::from_parts(Translation3::from(Vector3::from(p.translation)), r))
    }

    /// The rotation of `child` relative to `parent` about the unit `axis` (parent frame) since
    /// the build \[rad\], as the simulator counts a torsion spring's angle.
    pub fn joint_angle(&self, parent: usize, child: usize, axis: [f64; 3]) -> Option<f64> {
        let rel = self.pose(parent)?.rotation.inverse() * self.pose(child)?.rotation;
        let s = rel.i * axis[0] + rel.j * axis[1] + rel.k * axis[2];
        Some(2.0 * s.atan2(rel.w))
    }

    /// The displacement of `child` relative to `parent` at `anchor` (its place at the build),
    /// along the unit `axis` (parent frame) since the build \[m\].
    pub fn joint_slide(&self, parent: usize, child: usize, anchor: [f64; 3], axis: [f64; 3]) -> Option<f64> {
        let (p, c) = (self.pose(parent)?, self.pose(child)?);
        let a = Point3::from(anchor);
        let d = p.inverse_transform_vector(&(c.transform_point(&a) - p.transform_point(&a)));
        Some(d.dot(&Vector3::from(axis)))
    }

    /// The coordinate of joint `j` of `s`: a revolute joint's angle \[rad\] or a prismatic
    /// joint's slide \[m\], counted from its initial coordinate; None for other kinds.
    pub fn joint_coordinate(&self, s: &Structure, j: usize) -> Option<f64> {
        let joint = s.joints.get(j)?;
        let q = match joint.kind {
            JointKind::Revolute { axis } => self.joint_angle(joint.parent, joint.child, unit(axis))?,
            JointKind::Prismatic { axis } => {
                let anchor = s.nodes.get(joint.anchor)?.position;
                self.joint_slide(joint.parent, joint.child, anchor, unit(axis))?
            }
            _ => return None,
        };
        Some(joint.initial_coordinate + q)
    }

    /// The axis of a revolute or prismatic joint `j` of `s` in the world (turned with its
    /// parent), a unit vector.
    pub fn joint_axis_world(&self, s: &Structure, j: usize) -> Option<[f64; 3]> {
        let joint = s.joints.get(j)?;
        let axis = match joint.kind {
            JointKind::Revolute { axis } | JointKind::Prismatic { axis } => unit(axis),
            _ => return None,
        };
        let w = self.pose(joint.parent)?.rotation * Vector3::from(axis);
        Some([w.x, w.y, w.z])
    }

    /// The force or torque of the actuator driven by `symbol` along its axis [N or N m].
    pub fn actuator_force(&self, s: &crate::structure::Structure, symbol: &str) -> Option<f64> {
        self.forces.actuator_force.get(s.actuator_id(symbol)?).copied()
    }
}

/// Forces in every member at one instant. Tension is positive.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MemberForces {
    /// Each member's force \[N\], in member order: a spring's k (l - l0), a cable's tension
    /// (0 when slack), 0 for a strut (rigid through its body, it has no law of its own).
    pub force_n: Vec<f64>,
    /// Each member's length, the sum of its segments' \[m\].
    pub length_m: Vec<f64>,
    /// Each member's rest length now \[m\]: a spring's, a cable's unstretched (commanded)
    /// length; NaN for a strut.
    pub rest_length_m: Vec<f64>,
    /// Whether each member is a slack cable (every segment slack).
    pub slack: Vec<bool>,
    /// Each clustered cable's tension in each of its segments, in path order \[N\]: one value
    /// without friction, each its own with it (`force_n` is then its last segment's, at the
    /// end b where a winch reels); empty for a straight member.
    pub segment_force_n: Vec<Vec<f64>>,
    /// Each cable with friction's inner nodes: whether each is at its friction bound (slips
    /// if pulled further); empty for every other member.
    pub at_friction_bound: Vec<Vec<bool>>,
    /// Force \[N\] or torque [N m] each actuator exerts along its joint axis (or the cable
    /// tension for a winch), in actuator order.
    pub actuator_force: Vec<f64>,
    /// None when the snapshot was taken without it (see `Simulation::member_forces_with`).
    pub residual: Option<Residual>,
}

/// Equilibrium residual: the generalized forces of member forces, gravity and probe loads on
/// every free coordinate (a joint's free axes, summed over the subtree it carries). Zero at an
/// exact equilibrium. Computed from the force laws, not from the solver; the reactions of
/// loop-closing joints, which no force law gives, are fitted by least squares.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Residual {
    /// Largest residual force on a translational coordinate \[N\].
    pub max_force_n: f64,
    /// Largest residual torque on a rotational coordinate [N m].
    pub max_torque_nm: f64,
}

/// Reads one mode's coordinate off a snapshot: eta = v^T M (x - x0), v the mass-normalised
/// shape, M the mass matrix and x0 the poses at the analysed state, x - x0 per free body the
/// displacement of its centre of mass and the rotation vector of R R0^T. Exact for a motion
/// along the mode at small amplitude; the other modes, M-orthogonal to it, do not enter. Made
/// by `sim::modes::modal_projector`.
#[derive(Clone, Debug)]
pub struct ModalProjector {
    /// The free bodies, by structure index.
    pub bodies: Vec<usize>,
    /// Their poses at the analysed state.
    pub start: Vec<BodyPose>,
    /// Each body's centre of mass in its own frame \[m\].
    pub com_local: Vec<[f64; 3]>,
    /// M v: six per free body (translation, rotation).
    pub weights: Vec<f64>,
}

fn pose_rotation(p: &BodyPose) -> UnitQuaternion<f64> {
    let q = p.rotation_xyzw;
    UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2]))
}

fn pose_com(p: &BodyPose, local: &[f64; 3]) -> Vector3<f64> {
    Vector3::from(p.translation) + pose_rotation(p) * Vector3::from(*local)
}

impl ModalProjector {
    /// The modal coordinate in the state `snap`.
    pub fn coordinate(&self, snap: &Snapshot) -> f64 {
        let mut eta = 0.0;
        for (i, b) in self.bodies.iter().enumerate() {
            let (now, start) = (&snap.body_poses[*b], &self.start[i]);
            let du = pose_com(now, &self.com_local[i]) - pose_com(start, &self.com_local[i]);
            let dtheta = (pose_rotation(now) * pose_rotation(start).inverse()).scaled_axis();
            let w = &self.weights[6 * i..6 * i + 6];
            eta += w[0] * du.x + w[1] * du.y + w[2] * du.z + w[3] * dtheta.x + w[4] * dtheta.y + w[5] * dtheta.z;
        }
        eta
    }
}

/// The divisor of the difference between an extrapolated value of order `order` and the one a
/// level coarser (T(h/2, h/4) - T(h, h/2) at order 4) that estimates the finer one's error, for a
/// scheme whose error is even in h: 2^order - 1 (15 at order 4).
pub fn richardson_estimate_divisor(order: i32) -> f64 {
    2f64.powi(order) - 1.0
}

/// One Richardson step over the time step: from the same motion at step h (`coarse`) and h / 2
/// (`fine`), a method whose error is c h^p + ... gives fine + (fine - coarse) / (2^p - 1),
/// which cancels the h^p term. Every number of the state is combined so: node positions,
/// body translations and rotations (each quaternion taken on `fine`'s side of the sphere, the
/// result normalised), member forces and lengths, actuator forces, the kinetic energy. The
/// tick, time, commands and the cables' slack are `fine`'s.
pub fn richardson(coarse: &Snapshot, fine: &Snapshot, order: i32) -> Snapshot {
    let r = 1.0 / (2f64.powi(order) - 1.0);
    let x = |c: f64, f: f64| f + (f - c) * r;
    let v = |c: &[f64], f: &[f64]| -> Vec<f64> { c.iter().zip(f).map(|(c, f)| x(*c, *f)).collect() };
    let p3 = |c: &[f64; 3], f: &[f64; 3]| [x(c[0], f[0]), x(c[1], f[1]), x(c[2], f[2])];
    let pose = |c: &BodyPose, f: &BodyPose| {
        let (qc, qf) = (c.rotation_xyzw, f.rotation_xyzw);
        let side = if (0..4).map(|k| qc[k] * qf[k]).sum::<f64>() < 0.0 { -1.0 } else { 1.0 };
        let q: Vec<f64> = (0..4).map(|k| x(side * qc[k], qf[k])).collect();
        let n = q.iter().map(|a| a * a).sum::<f64>().sqrt();
        BodyPose {
            translation: p3(&c.translation, &f.translation),
            rotation_xyzw: [q[0] / n, q[1] / n, q[2] / n, q[3] / n],
        }
    };
    let (cf, ff) = (&coarse.forces, &fine.forces);
    Snapshot {
        tick: fine.tick,
        time_s: fine.time_s,
        nodes: coarse.nodes.iter().zip(&fine.nodes).map(|(c, f)| p3(c, f)).collect(),
        body_poses: coarse.body_poses.iter().zip(&fine.body_poses).map(|(c, f)| pose(c, f)).collect(),
        forces: MemberForces {
            force_n: v(&cf.force_n, &ff.force_n),
            length_m: v(&cf.length_m, &ff.length_m),
            rest_length_m: ff.rest_length_m.clone(),
            slack: ff.slack.clone(),
            segment_force_n: cf.segment_force_n.iter().zip(&ff.segment_force_n).map(|(c, f)| v(c, f)).collect(),
            at_friction_bound: ff.at_friction_bound.clone(),
            actuator_force: v(&cf.actuator_force, &ff.actuator_force),
            residual: None,
        },
        actuator_values: fine.actuator_values.clone(),
        kinetic_energy_j: x(coarse.kinetic_energy_j, fine.kinetic_energy_j),
    }
}
