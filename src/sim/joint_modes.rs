//! The modal analysis of a jointed structure, reduced to its joints' coordinates: the free
//! (not actuated) revolute and prismatic joints of trees rooted on fixed bodies, the actuated
//! ones held at their commands. With q those coordinates at the settled state,
//! - K = d2V/dq2, V the potential energy (elastic members, torsion springs, constant loads such
//!   as gravity), by central second differences of V over joint displacements of
//!   [`STEP_RAD`] rad or [`STEP_FRACTION`] of the structure's length (error O(h^2) and round-off
//!   eps V / h^2: about 1e-8 relative on the shipped structures);
//! - M = sum over bodies J_b^T diag(m 1, R I R^T) J_b, J_b the 6 x n Jacobian of the body's
//!   centre of mass and rotation by central first differences (error O(h^2));
//! - K v = omega^2 M v (`eigen::modes`). Each mode's shape is also given per moving body
//!   (J_b v, mass-normalised against the bodies' block mass), so that the modal coordinate and
//!   the drawing are the same as for free bodies (`modes.rs`).
//!
//! Loops closed by joints, free bodies outside the trees and joints of more than one
//! coordinate are refused, by name.

use super::data::Data;
use super::model::Model;
use super::modes::{ModesError, StructureMode, StructureModes, ZERO_MODE_RATIO};
use crate::structure::JointKind;
use nalgebra::{DMatrix, DVector, Quaternion, UnitQuaternion, Vector3};

/// Finite-difference step of a revolute coordinate [rad].
const STEP_RAD: f64 = 1e-4;
/// Finite-difference step of a prismatic coordinate, a fraction of the structure's length.
const STEP_FRACTION: f64 = 1e-4;
impl Data {
    /// The joints whose coordinates are the analysis's, or why the structure is refused.
    pub(super) fn modal_joints(&self, m: &Model) -> Result<Vec<usize>, ModesError> {
        let s = &m.structure;
        // A joint that closes a loop is an impulse joint, no link of a multibody.
        for (j, joint) in s.joints.iter().enumerate() {
            if m.joint_links[j].is_none() {
                return Err(ModesError::Loop(joint.name.clone()));
            }
        }
        if let Some(&b) = s.unjointed_free_bodies().first() {
            return Err(ModesError::Unjointed(s.bodies[b].name.clone()));
        }
        let free: Vec<usize> = (0..s.joints.len()).filter(|j| !m.actuated[*j]).collect();
        if let Some(&j) = free
            .iter()
            .find(|&&j| !matches!(s.joints[j].kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. }))
        {
            return Err(ModesError::JointKind(s.joints[j].name.clone()));
        }
        Ok(free)
    }

    /// The finite-difference step of joint `j`'s coordinate.
    fn modal_step(&self, m: &Model, j: usize) -> f64 {
        match m.structure.joints[j].kind {
            JointKind::Prismatic { .. } => STEP_FRACTION * m.length_scale_m,
            _ => STEP_RAD,
        }
    }

    /// Moves joint `j`'s coordinate by `d` (rad or m), the bodies beyond it along.
    /// [`Simulation::modal_joints`] admits only joints that are links of a multibody, so the
    /// move cannot fail here.
    pub(super) fn displace_joint(&mut self, m: &Model, j: usize, d: f64) {
        let _ = self.move_joint(m, j, d, None);
    }

    /// Whether each member (structure order) is engaged now: an elastic member taut, or a
    /// two-sided spring; false for every other. The branches a modal analysis's energy keeps.
    pub(super) fn engaged_members(&self, m: &Model) -> Vec<bool> {
        let s = &m.structure;
        let mut engaged = vec![false; s.members.len()];
        for (i, member) in s.members_by_kind() {
            if let Some(law) = self.elastic_law(m, i) {
                engaged[i] = law.engaged(member.length_at(|n| self.node_position(m, n)));
            }
        }
        engaged
    }

    /// The potential energy now [J]: elastic members (each on its branch `engaged`, so that a
    /// difference that would cross a cable's kink reads the cable's stiffness where it is),
    /// torsion springs, and the work of the constant loads (gravity, external loads) on the
    /// centres of mass, taken from each body's centre of mass at `reference` (indexed by body;
    /// None: the world origin), which keeps the large constant -f . x_ref out of the sum and its
    /// round-off out of second differences.
    pub(super) fn potential_energy_about(
        &self,
        m: &Model,
        reference: Option<&[Vector3<f64>]>,
        engaged: &[bool],
    ) -> f64 {
        let s = &m.structure;
        let mut e = 0.0;
        for (i, member) in s.members_by_kind() {
            if let Some(law) = self.elastic_law(m, i) {
                e += law.energy_on_branch_j(member.length_at(|n| self.node_position(m, n)), engaged[i]);
            }
        }
        let snap = self.snapshot_with(m, false);
        for j in 0..s.joints.len() {
            if let (Some((k, rest)), Some(q)) = (self.torsion_spring_now(m, j), snap.joint_coordinate(s, j)) {
                e += 0.5 * k * (q - rest).powi(2);
            }
        }
        for b in (0..s.bodies.len()).filter(|b| m.is_free(*b)) {
            let (f, _) = self.constant_load(m, b);
            let com = self.world_com(m, b);
            let r = reference.map_or_else(Vector3::zeros, |r| r[b]);
            e -= f.x * (com.x - r.x) + f.y * (com.y - r.y) + f.z * (com.z - r.z);
        }
        for &(node, f) in &m.node_loads {
            let p = Vector3::from(self.node_position(m, node));
            let r = reference.map_or_else(Vector3::zeros, |r| r[s.nodes[node].body]);
            e -= f.dot(&(p - r));
        }
        e
    }

    /// V (on the branches `engaged`) with the coordinates `joints` moved by `d`, the state
    /// restored after.
    fn energy_moved(&mut self, m: &Model, engaged: &[bool], moves: &[(usize, f64)]) -> f64 {
        moves.iter().for_each(|&(j, d)| self.displace_joint(m, j, d));
        let e = self.potential_energy_about(m, None, engaged);
        moves.iter().rev().for_each(|&(j, d)| self.displace_joint(m, j, -d));
        e
    }

    /// K = d2V/dq2 by central second differences.
    fn joint_stiffness(&mut self, m: &Model, joints: &[usize]) -> DMatrix<f64> {
        let n = joints.len();
        let h: Vec<f64> = joints.iter().map(|&j| self.modal_step(m, j)).collect();
        let engaged = self.engaged_members(m);
        let e0 = self.potential_energy_about(m, None, &engaged);
        let mut k = DMatrix::zeros(n, n);
        for a in 0..n {
            let (ja, ha) = (joints[a], h[a]);
            k[(a, a)] = (self.energy_moved(m, &engaged, &[(ja, ha)]) - 2.0 * e0
                + self.energy_moved(m, &engaged, &[(ja, -ha)]))
                / (ha * ha);
            for b in 0..a {
                let (jb, hb) = (joints[b], h[b]);
                let pp = self.energy_moved(m, &engaged, &[(ja, ha), (jb, hb)]);
                let pm = self.energy_moved(m, &engaged, &[(ja, ha), (jb, -hb)]);
                let mp = self.energy_moved(m, &engaged, &[(ja, -ha), (jb, hb)]);
                let mm = self.energy_moved(m, &engaged, &[(ja, -ha), (jb, -hb)]);
                k[(a, b)] = (pp - pm - mp + mm) / (4.0 * ha * hb);
                k[(b, a)] = k[(a, b)];
            }
        }
        k
    }

    /// Each moving body's centre of mass and rotation (as a quaternion) now.
    pub(super) fn body_states(&self, m: &Model, bodies: &[usize]) -> Vec<(Vector3<f64>, UnitQuaternion<f64>)> {
        bodies
            .iter()
            .map(|&b| {
                let q = self.body_pose(m, b).rotation_xyzw;
                let com = self.world_com(m, b);
                (
                    Vector3::new(com.x, com.y, com.z),
                    UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
                )
            })
            .collect()
    }

    /// J (6 per moving body x n): the bodies' centre-of-mass velocity and angular velocity per
    /// unit rate of each coordinate, by central differences.
    pub(super) fn body_jacobian(&mut self, m: &Model, joints: &[usize], bodies: &[usize]) -> DMatrix<f64> {
        let mut jac = DMatrix::zeros(6 * bodies.len(), joints.len());
        for (c, &j) in joints.iter().enumerate() {
            let h = self.modal_step(m, j);
            self.displace_joint(m, j, h);
            let plus = self.body_states(m, bodies);
            self.displace_joint(m, j, -2.0 * h);
            let minus = self.body_states(m, bodies);
            self.displace_joint(m, j, h);
            for (i, ((xp, rp), (xm, rm))) in plus.iter().zip(&minus).enumerate() {
                let dx = (xp - xm) / (2.0 * h);
                let dtheta = (rp * rm.inverse()).scaled_axis() / (2.0 * h);
                jac.view_mut((6 * i, c), (3, 1)).copy_from(&dx);
                jac.view_mut((6 * i + 3, c), (3, 1)).copy_from(&dtheta);
            }
        }
        jac
    }

    /// The modes of a jointed structure in its free joints' coordinates (module docs).
    pub(super) fn joint_modes(
        &mut self,
        m: &Model,
        cancel: Option<&std::sync::atomic::AtomicBool>,
    ) -> Result<StructureModes, ModesError> {
        let joints = self.modal_joints(m)?;
        if joints.is_empty() {
            return Err(ModesError::NoFreeBody);
        }
        let s = &m.structure;
        let bodies: Vec<usize> = (0..s.bodies.len()).filter(|b| m.is_free(*b)).collect();
        let stiffness = self.joint_stiffness(m, &joints);
        let jac = self.body_jacobian(m, &joints, &bodies);
        let body_mass = self.mass_matrix(m, &bodies);
        let mass = jac.transpose() * &body_mass * &jac;
        let eigen = crate::eigen::modes_until(
            &(0.5 * (&stiffness + stiffness.transpose())),
            &(0.5 * (&mass + mass.transpose())),
            cancel,
        )?;
        let largest = eigen.iter().fold(0.0f64, |m, e| m.max(e.omega_squared.abs()));
        let com: Vec<_> = self.body_states(m, &bodies).iter().map(|(c, _)| *c).collect();
        let modes: Vec<StructureMode> = eigen
            .into_iter()
            .map(|e| {
                let shape: Vec<f64> = (&jac * DVector::from_column_slice(e.shape.as_slice())).iter().copied().collect();
                StructureMode {
                    omega_squared: e.omega_squared,
                    rigid: e.omega_squared.abs() <= ZERO_MODE_RATIO * largest,
                    node_motion: self.node_motion(m, &bodies, &com, &shape),
                    shape,
                    joint_shape: e.shape.iter().copied().collect(),
                }
            })
            .collect();
        let rigid = modes.iter().filter(|m| m.rigid).count();
        let poses = bodies.iter().map(|b| self.body_pose(m, *b)).collect();
        let mass = super::modes::diagonal_blocks(&body_mass);
        Ok(StructureModes {
            bodies,
            joints,
            poses,
            mass,
            modes,
            rigid,
            constraints: None,
            lowest_of: None,
            left_out: 0,
        })
    }
}
