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

use super::projection::{ProjectedGroup, GAP_TOLERANCE_FRACTION, RIGID_REST_FRACTION, SVD_RELATIVE_TOLERANCE};
use super::Simulation;
use rapier3d_f64::prelude::*;

/// Where a looped multibody's loops were last closed, at the generation of the constraint
/// inputs then; `joints` once a second closing at that generation found them rigid.
pub(super) struct ClosureRest {
    multibody: MultibodyIndex,
    generation: u64,
    /// Every link's joint there, and the largest row left [m].
    joints: Option<(Vec<MultibodyJoint>, f64)>,
}

impl Simulation {
    /// Puts multibody `m` back at its rest and stops it, when one is recorded at the current
    /// generation and every joint coordinate is within [`RIGID_REST_FRACTION`] of the
    /// structure's size of it (angles times the size); the largest row left there [m], or None.
    pub(super) fn back_to_closure_rest(&mut self, m: MultibodyIndex) -> Option<f64> {
        let scale = self.model.length_scale_m;
        let rest = self.closure_rests.iter().find(|r| r.multibody == m && r.generation == self.constraint_inputs)?;
        let (joints, left) = rest.joints.as_ref()?;
        let mb = self.multibody_joints.get_multibody_mut(m)?;
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
        mb.forward_kinematics(&self.bodies, false);
        mb.update_rigid_bodies(&mut self.bodies, true);
        mb.generalized_velocity_mut().fill(0.0);
        Some(*left)
    }

    /// Notes that the loops of multibody `m` (group `g`) closed to `left` [m]; on the second
    /// closing at the same generation, records the rest when they are rigid.
    pub(super) fn note_closure_closed(&mut self, m: MultibodyIndex, g: &ProjectedGroup, left: f64) {
        let generation = self.constraint_inputs;
        let again = self.closure_rests.iter().any(|r| r.multibody == m && r.generation == generation);
        self.closure_rests.retain(|r| r.multibody != m);
        if left > GAP_TOLERANCE_FRACTION * self.model.length_scale_m {
            return;
        }
        let joints = (again && self.loops_are_rigid(g))
            .then(|| self.multibody_joints.get_multibody(m).map(|mb| (mb.links().map(|l| *l.joint()).collect(), left)))
            .flatten();
        self.closure_rests.push(ClosureRest { multibody: m, generation, joints });
    }

    /// Whether the loops of a multibody's group leave none of its free coordinates a motion:
    /// at least as many rows as coordinates and every singular value of their Jacobian above
    /// [`SVD_RELATIVE_TOLERANCE`] of the largest (the projection's own cut for redundant rows).
    fn loops_are_rigid(&self, g: &ProjectedGroup) -> bool {
        let jacobian = self.group_jacobian_dense(g);
        if jacobian.nrows() < jacobian.ncols() || jacobian.ncols() == 0 {
            return false;
        }
        let sv = jacobian.singular_values();
        let largest = sv.max();
        sv.iter().all(|&s| s > SVD_RELATIVE_TOLERANCE * largest)
    }
}
