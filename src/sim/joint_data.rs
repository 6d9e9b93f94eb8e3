//! A structure's joint as rapier joint data: the joint's frames and free axes, its lock at a
//! commanded coordinate off the tree, and a multibody link's damping. The build makes the
//! joints from these (`build.rs`); the state changes them through the same functions when a
//! command or a damping changes (`data.rs`, `damping.rs`), so a joint is described in one place.

use crate::structure::{Joint, JointKind, Structure, Vec3};
use rapier3d_f64::prelude::*;

/// A structure vector as rapier's.
pub(super) fn v(a: Vec3) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

/// The free axis of a revolute or prismatic joint in rapier's joint frame.
pub(super) fn free_axis_of(kind: &JointKind) -> JointAxis {
    match kind {
        JointKind::Prismatic { .. } => JointAxis::LinX,
        _ => JointAxis::AngX,
    }
}

/// An actuated revolute or prismatic joint off the multibody tree, held at coordinate `q`
/// [rad or m] from its drawn configuration: its free axis locked (an equality in rapier's
/// solver) and its first frame turned or slid by `q` along that axis. Equal limits [q, q], the
/// lock used before, are enforced one side at a time: measured on a chain of 10 furet2018 X
/// modules cut into plain bodies, rapier's step at rest opened the locks by 3e-3 to 3e-2 (rows
/// scaled to metres), and the projection then took 5 to 7 iterations a step.
pub(super) fn locked_joint(s: &Structure, joint: &Joint, q: f64) -> GenericJoint {
    let mut data = generic_joint(s, joint);
    let axis = free_axis_of(&joint.kind);
    let offset = match axis {
        JointAxis::LinX => Pose::from_translation(Vector::X * q),
        _ => Pose::from_rotation(Rotation::from_scaled_axis(Vector::X * q)),
    };
    let frame1 = data.local_frame1;
    data.set_local_frame1(frame1 * offset);
    data.lock_axes(axis.into());
    data
}

/// Sets the damping of every degree of freedom of a multibody link [N s/m or N m s/rad].
pub(super) fn set_link_damping(set: &mut MultibodyJointSet, link: MultibodyJointHandle, damping: f64) {
    if let Some((mb, link_id)) = set.get_mut(link) {
        let (start, ndofs) = {
            let l = mb.link(link_id).expect("link just inserted");
            (l.assembly_id(), l.joint().ndofs())
        };
        for k in start..start + ndofs {
            mb.damping_mut()[k] = damping;
        }
    }
}

/// Index (0..6: linear x, y, z, angular x, y, z) of the single free axis of a one-degree-of-
/// freedom joint, where its coordinate lives in `MultibodyJoint::coords`.
pub(super) fn joint_free_axis(data: &GenericJoint) -> usize {
    let locked = data.locked_axes.bits();
    (0..6).find(|k| locked & (1 << k) == 0).unwrap_or(0)
}

/// The rapier joint for a structure joint, with both local frames equal to the world frame of
/// the initial configuration (every body starts at the identity pose).
pub(super) fn generic_joint(s: &Structure, joint: &Joint) -> GenericJoint {
    let anchor = v(s.nodes[joint.anchor].position);
    match &joint.kind {
        JointKind::Revolute { axis } => {
            let mut b = RevoluteJointBuilder::new(v(*axis).normalize()).local_anchor1(anchor).local_anchor2(anchor);
            if let Some(t) = &joint.torsion_spring {
                b = b.motor_model(MotorModel::ForceBased).motor_position(
                    t.rest_angle_rad - joint.initial_coordinate,
                    t.stiffness_nm_per_rad,
                    0.0,
                );
            }
            b.build().into()
        }
        JointKind::Prismatic { axis } => {
            PrismaticJointBuilder::new(v(*axis).normalize()).local_anchor1(anchor).local_anchor2(anchor).build().into()
        }
        JointKind::Spherical => SphericalJointBuilder::new().local_anchor1(anchor).local_anchor2(anchor).build().into(),
        JointKind::Universal { axis1, axis2 } => {
            // Frame: x along axis1, y along axis2 (made orthogonal), z = x cross y is locked.
            let x = v(*axis1).normalize();
            let y = (v(*axis2) - x * x.dot(v(*axis2))).normalize();
            let z = x.cross(y);
            let rot = Rotation::from_mat3(&glam_mat3(x, y, z));
            let frame = Pose::from_parts(anchor, rot);
            GenericJointBuilder::new(JointAxesMask::LIN_AXES | JointAxesMask::ANG_Z)
                .local_frame1(frame)
                .local_frame2(frame)
                .build()
        }
        JointKind::Fixed => FixedJointBuilder::new().local_anchor1(anchor).local_anchor2(anchor).build().into(),
        JointKind::PlanarPin { axis } => {
            // Frame: x along the axis (free), y and z locked.
            let x = v(*axis).normalize();
            let helper = if x.x.abs() < 0.9 { Vector::X } else { Vector::Y };
            let y = x.cross(helper).normalize();
            let z = x.cross(y);
            let frame = Pose::from_parts(anchor, Rotation::from_mat3(&glam_mat3(x, y, z)));
            GenericJointBuilder::new(JointAxesMask::LIN_Y | JointAxesMask::LIN_Z)
                .local_frame1(frame)
                .local_frame2(frame)
                .build()
        }
    }
}

fn glam_mat3(x: Vector, y: Vector, z: Vector) -> rapier3d_f64::glamx::DMat3 {
    rapier3d_f64::glamx::DMat3::from_cols(x, y, z)
}

/// The damping of joint `j`'s multibody link [N m s/rad, or N s/m]: the joint's own, except
/// for an undamped ball joint that hangs a body from a fixed one, which takes the bodies'
/// damping rate `body_damping_per_s` [1/s] times the child's largest moment of inertia about
/// the anchor. rapier damps a multibody link through its degrees of freedom only, never through
/// the body's own damping, so a strut hanging on an undamped ball joint had swung for ever under
/// `body_damping` (F6 of issue 60). Other links keep the joint's damping (every shipped
/// mechanism states it; applying the rate to all of them moved four seed baselines).
pub(super) fn link_damping(s: &Structure, j: usize, body_damping_per_s: f64) -> f64 {
    let joint = &s.joints[j];
    let hanging = matches!(joint.kind, JointKind::Spherical)
        && joint.damping == 0.0
        && s.bodies[joint.parent].kind == crate::structure::BodyKind::Fixed;
    let Some(i) = s.bodies[joint.child].inertia.filter(|_| hanging && body_damping_per_s > 0.0) else {
        return joint.damping;
    };
    let d = nalgebra::Vector3::from(i.com) - nalgebra::Vector3::from(s.nodes[joint.anchor].position);
    let about_anchor = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::from(i.principal_kg_m2))
        + i.mass_kg * (nalgebra::Matrix3::identity() * d.norm_squared() - d * d.transpose());
    body_damping_per_s * about_anchor.diagonal().max()
}
