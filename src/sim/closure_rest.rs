//! A looped multibody's rigid rest: the joints where its loops were last closed to round-off,
//! when those loops leave its free coordinates no motion.
//!
//! A chain of two X modules is one multibody whose loops close inside it (`projection.rs`,
//! internal closures). At rest rapier's step moves its passive joints a little every step, and
//! the projection took Gauss-Newton back (a dense Jacobian from the multibody's body
//! Jacobians and forward kinematics each iteration: 23 % of a 2-X settle). Where the loops'
//! Jacobian has full column rank, the closed configuration is isolated: Gauss-Newton from
//! the stepped joints converges back to it, so the multibody is put back there directly, every
//! link's joint as it was to the bit, and stopped. This is the rigid rest of a group of plain
//! bodies (`RigidRest` in `projection.rs`) for the multibody's own coordinates.
//!
//! The rest is recorded on the second closing at the same generation of the constraint inputs
//! (a structure at rest, not one whose commands change every tick), and is used while that
//! generation holds and the joints are within [`super::projection::RIGID_REST_FRACTION`] of it.

use super::data::Data;
use super::model::Model;
use super::model::ProjectedGroup;
use super::projection::{GAP_TOLERANCE_FRACTION, RIGID_REST_FRACTION, SVD_RELATIVE_TOLERANCE};
use rapier3d_f64::prelude::*;

/// Where a looped multibody's loops were last closed, at the generation of the constraint
/// inputs then; `joints` once a second closing at that generation found them rigid.
pub(super) struct ClosureRest {
    multibody: MultibodyIndex,
    generation: u64,
    /// Every link's joint there, and the largest row left [m].
    joints: Option<(Vec<MultibodyJoint>, f64)>,
}

/// Every looped multibody's closure rest.
#[derive(Default)]
pub(super) struct ClosureRests {
    rests: Vec<ClosureRest>,
}

impl ClosureRests {
    /// Closes every loop inside a multibody to round-off and projects the velocities onto the
    /// closures' tangent space, putting a multibody back at its rest where it has one. Returns
    /// the largest gap left [m].
    pub(super) fn project_internal_closures(&mut self, m: &Model, d: &mut Data) -> f64 {
        let mut largest = 0.0_f64;
        let mut multibodies: Vec<MultibodyIndex> = Vec::new();
        for c in &m.internal_closures {
            if !multibodies.contains(&c.multibody) {
                multibodies.push(c.multibody);
            }
        }
        for &index in &multibodies {
            if d.free_dofs(index).is_empty() {
                continue;
            }
            if let Some(left) = self.back_to_closure_rest(m, d, index) {
                largest = largest.max(left);
                continue;
            }
            // The loops of one multibody: a group of its free coordinates alone.
            let joints = m.internal_closures.iter().filter(|c| c.multibody == index).map(|c| c.joint).collect();
            let g = ProjectedGroup { multibodies: vec![index], joints, ..Default::default() };
            let p = d.project_group(m, &g, &[], &mut None, &mut None, GAP_TOLERANCE_FRACTION, f64::INFINITY);
            largest = largest.max(p.left);
            self.note_closure_closed(m, d, index, &g, p.left);
        }
        largest
    }

    /// Puts multibody `index` back at its rest and stops it, when one is recorded at the
    /// current generation and every joint coordinate is within [`RIGID_REST_FRACTION`] of the
    /// structure's size of it (angles times the size); the largest row left there [m], or None.
    fn back_to_closure_rest(&mut self, m: &Model, d: &mut Data, index: MultibodyIndex) -> Option<f64> {
        let scale = m.length_scale_m;
        let rest = self.rests.iter().find(|r| r.multibody == index && r.generation == d.constraint_inputs)?;
        let (joints, left) = rest.joints.as_ref()?;
        let mb = d.multibody_joints.get_multibody_mut(index)?;
        let near = mb.links().zip(joints).all(|(link, then)| {
            let (now, then) = (link.joint().coords(), then.coords());
            (0..6).all(|k| (now[k] - then[k]).abs() * if k < 3 { 1.0 } else { scale } <= RIGID_REST_FRACTION * scale)
        });
        if !near {
            return None;
        }
        for (i, joint) in joints.iter().enumerate() {
            mb.link_mut(i)?.joint = *joint;
        }
        mb.forward_kinematics(&d.bodies, false);
        mb.update_rigid_bodies(&mut d.bodies, true);
        mb.generalized_velocity_mut().fill(0.0);
        Some(*left)
    }

    /// Notes that the loops of multibody `index` (group `g`) closed to `left` [m]; on the
    /// second closing at the same generation, records the rest when they are rigid.
    fn note_closure_closed(&mut self, m: &Model, d: &Data, index: MultibodyIndex, g: &ProjectedGroup, left: f64) {
        let generation = d.constraint_inputs;
        let again = self.rests.iter().any(|r| r.multibody == index && r.generation == generation);
        self.rests.retain(|r| r.multibody != index);
        if left > GAP_TOLERANCE_FRACTION * m.length_scale_m {
            return;
        }
        let joints = (again && d.loops_are_rigid(m, g))
            .then(|| d.multibody_joints.get_multibody(index).map(|mb| (mb.links().map(|l| *l.joint()).collect(), left)))
            .flatten();
        self.rests.push(ClosureRest { multibody: index, generation, joints });
    }
}

impl Data {
    /// Whether the loops of a multibody's group leave none of its free coordinates a motion:
    /// at least as many rows as coordinates and every singular value of their Jacobian above
    /// [`SVD_RELATIVE_TOLERANCE`] of the largest (the projection's own cut for redundant rows).
    fn loops_are_rigid(&self, m: &Model, g: &ProjectedGroup) -> bool {
        let jacobian = self.group_jacobian_dense(m, g);
        if jacobian.nrows() < jacobian.ncols() || jacobian.ncols() == 0 {
            return false;
        }
        let sv = jacobian.singular_values();
        let largest = sv.max();
        sv.iter().all(|&s| s > SVD_RELATIVE_TOLERANCE * largest)
    }
}
