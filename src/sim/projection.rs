//! Position projection of loop closures that lie inside one multibody.
//!
//! A closed planar loop (furet2018's crossed four-bar) stays inside its multibody and is closed
//! by an impulse joint (a planar pin). rapier holds such a joint only at the velocity level: its
//! anchors drift apart by an offset that grows with the time step and with every jump of an
//! actuator (3.7e-5 m measured on furet2018, FINDINGS.md). After each step this module moves
//! the multibody's free coordinates q (Gauss-Newton on the closure gap g(q), Jacobian by finite
//! differences of the multibody's own forward kinematics) until every such loop is closed to
//! round-off, then removes the velocity component that would open it again
//! (qdot -= J^+ J qdot). The joints that are cut between multibodies keep rapier's treatment.

use super::Simulation;
use crate::structure::JointKind;
use rapier3d_f64::prelude::*;

/// Gauss-Newton iterations at most per step.
const MAX_ITERATIONS: usize = 20;

/// The projection stops when the largest gap is below this fraction of the structure's size.
const GAP_TOLERANCE_FRACTION: f64 = 1e-14;

/// Finite-difference step of a free coordinate (rad or m).
const FD_STEP: f64 = 1e-7;

/// Singular values of the closure Jacobian below this fraction of the largest are treated as
/// zero (redundant closure rows).
const SVD_RELATIVE_TOLERANCE: f64 = 1e-10;

/// A loop-closing joint inside one multibody: the rows of its gap that the projection zeroes.
#[derive(Clone, Debug)]
pub(super) struct InternalClosure {
    joint: usize,
    multibody: MultibodyIndex,
}

impl Simulation {
    /// The loop-closing joints whose two bodies are links of the same multibody.
    pub(super) fn find_internal_closures(&self) -> Vec<InternalClosure> {
        let mut out = Vec::new();
        for (j, joint) in self.structure.joints.iter().enumerate() {
            if self.joint_impulse[j].is_none() || !matches!(joint.kind, JointKind::PlanarPin { .. }) {
                continue;
            }
            let link = |b: usize| self.multibody_joints.rigid_body_link(self.handles[b]).map(|l| l.multibody);
            if let (Some(a), Some(b)) = (link(joint.parent), link(joint.child)) {
                if a == b {
                    out.push(InternalClosure { joint: j, multibody: a });
                }
            }
        }
        out
    }

    /// The gap rows of one closure: the anchor as carried by the child minus as carried by the
    /// parent, in the plane normal to the pin axis (two rows) [m].
    fn closure_rows(&self, c: &InternalClosure, out: &mut Vec<f64>) {
        let j = &self.structure.joints[c.joint];
        let a = self.structure.nodes[j.anchor].position;
        let a = Vector::new(a[0], a[1], a[2]);
        let parent = self.bodies[self.handles[j.parent]].position();
        let child = self.bodies[self.handles[j.child]].position();
        let gap = child.transform_point(a) - parent.transform_point(a);
        let JointKind::PlanarPin { axis } = j.kind else { return };
        let n = (parent.rotation * Vector::new(axis[0], axis[1], axis[2])).normalize();
        for t in super::forces::orthogonal_pair(n) {
            out.push(gap.dot(t));
        }
    }

    fn closure_gaps(&self, closures: &[InternalClosure], multibody: MultibodyIndex) -> Vec<f64> {
        let mut rows = Vec::new();
        for c in closures.iter().filter(|c| c.multibody == multibody) {
            self.closure_rows(c, &mut rows);
        }
        rows
    }

    /// Moves the multibody's coordinates by `disp` and places its bodies there.
    fn displace(&mut self, multibody: MultibodyIndex, disp: &[f64]) {
        if let Some(mb) = self.multibody_joints.get_multibody_mut(multibody) {
            mb.apply_displacements(disp);
            mb.forward_kinematics(&self.bodies, false);
            mb.update_rigid_bodies(&mut self.bodies, true);
        }
    }

    /// Closes every loop inside a multibody to round-off and projects the velocities onto the
    /// closures' tangent space. Returns the largest gap left [m].
    pub(super) fn project_internal_closures(&mut self) -> f64 {
        let closures = std::mem::take(&mut self.internal_closures);
        let mut largest = 0.0_f64;
        let mut multibodies: Vec<MultibodyIndex> = Vec::new();
        for c in &closures {
            if !multibodies.contains(&c.multibody) {
                multibodies.push(c.multibody);
            }
        }
        for &mb_index in &multibodies {
            let Some(mb) = self.multibody_joints.get_multibody(mb_index) else { continue };
            let ndofs = mb.ndofs();
            // The free coordinates: every degree of freedom of a link that no actuator sets.
            let free: Vec<usize> = mb
                .links()
                .filter(|l| !l.joint().kinematic)
                .flat_map(|l| l.assembly_id()..l.assembly_id() + l.joint().ndofs())
                .collect();
            if free.is_empty() {
                continue;
            }
            let tol = GAP_TOLERANCE_FRACTION * self.length_scale_m;
            let mut jac = nalgebra::DMatrix::<f64>::zeros(0, free.len());
            let mut disp = vec![0.0; ndofs];
            for _ in 0..MAX_ITERATIONS {
                let g0 = self.closure_gaps(&closures, mb_index);
                let gmax = g0.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                // Jacobian by forward differences of the multibody's own kinematics.
                jac = nalgebra::DMatrix::<f64>::zeros(g0.len(), free.len());
                for (col, &dof) in free.iter().enumerate() {
                    disp.fill(0.0);
                    disp[dof] = FD_STEP;
                    self.displace(mb_index, &disp);
                    let g = self.closure_gaps(&closures, mb_index);
                    disp[dof] = -FD_STEP;
                    self.displace(mb_index, &disp);
                    for (row, (gi, g0i)) in g.iter().zip(&g0).enumerate() {
                        jac[(row, col)] = (gi - g0i) / FD_STEP;
                    }
                }
                if gmax <= tol {
                    break;
                }
                let svd = jac.clone().svd(true, true);
                let cut = SVD_RELATIVE_TOLERANCE * svd.singular_values.max();
                let Ok(step) = svd.solve(&-nalgebra::DVector::from_vec(g0), cut) else { break };
                disp.fill(0.0);
                for (col, &dof) in free.iter().enumerate() {
                    disp[dof] = step[col];
                }
                self.displace(mb_index, &disp);
            }
            let left = self.closure_gaps(&closures, mb_index).iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            largest = largest.max(left);
            // Velocities: remove the part that opens the loops, qdot -= J^+ (J qdot).
            if jac.nrows() > 0 {
                if let Some(mb) = self.multibody_joints.get_multibody_mut(mb_index) {
                    let v = nalgebra::DVector::from_iterator(
                        free.len(),
                        free.iter().map(|&d| mb.generalized_velocity()[d]),
                    );
                    let jv = &jac * &v;
                    let svd = jac.clone().svd(true, true);
                    let cut = SVD_RELATIVE_TOLERANCE * svd.singular_values.max();
                    if let Ok(dv) = svd.solve(&jv, cut) {
                        let mut gv = mb.generalized_velocity_mut();
                        for (col, &dof) in free.iter().enumerate() {
                            gv[dof] -= dv[col];
                        }
                    }
                }
            }
        }
        self.internal_closures = closures;
        largest
    }
}
