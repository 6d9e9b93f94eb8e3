//! The modal analysis of a structure held by constraints: joints that close loops and taut
//! inextensible cables, reduced to the tangent space of those constraints (as Chrono's
//! constrained modal assembly treats its joints).
//!
//! Coordinates q: every free (not actuated) degree of freedom of the multibodies (the joint
//! trees: rad, or m for a prismatic joint) and six per free body outside them (translation of
//! the centre of mass [m], small rotation about it [rad], world axes). Constraints g(q) = 0:
//! the rows of every joint that closes a loop (`projection::joint_rows`: anchor gap [m],
//! angular rows times the structure's size [m]) and the stretch l - l0 [m] of every taut
//! inextensible cable (a slack one contributes nothing: while slack it exerts no force). At
//! the settled state, with V the potential energy (`joint_modes.rs`: elastic members, torsion
//! springs, constant loads):
//! - G = dg/dq and grad V by central differences at steps h and 2 h (h = [`STEP_RAD`] rad or
//!   [`STEP_FRACTION`] of the structure's size), extrapolated: (4 D(h) - D(2h)) / 3, error
//!   O(h^4) (every derivative below is taken so). V keeps each elastic member on the branch of
//!   its law it is on at the state (a taut cable's k (l - l0)^2 / 2 on both sides of its rest
//!   length, a slack one's 0): the one-sided stiffness the small vibration feels, with no
//!   difference crossing a kink (they had: cut steps near the kink, and a cable stretched less
//!   than the least step read its slack side: a base-pinned prism at t0 = 0.2 N, k = 1e4 N/m,
//!   had omega^2 = -104.6 where it is +1.956);
//! - the constraint forces lambda from the equilibrium grad V + G^T lambda = 0 (least
//!   squares; a taut cable's lambda is its tension [N], a loop's its joint reaction);
//! - K = d2L/dq2, the Hessian of the Lagrangian L = V + lambda . g with lambda held (the
//!   potential's stiffness plus the geometric stiffness sum lambda_i d2g_i/dq2 of the
//!   constraint forces: a cable's T d2l/dq2, a loop reaction times the closure's curvature),
//!   by central second differences;
//! - M = sum over bodies J_b^T diag(m 1, R I R^T) J_b, J_b each body's centre-of-mass and
//!   rotation Jacobian by central differences; the hidden bodies that split a universal
//!   joint into two revolute links have no mass (`build.rs`), so M is the structure's own;
//! - N, a basis of null(G) (the right singular vectors of G whose singular value is below
//!   [`NULL_SPACE_RATIO`] of the largest), and the reduced problem
//!   (N^T K N) v = omega^2 (N^T M N) v. Each mode's coordinates are N v.
//!
//! At an equilibrium the reduced Hessian does not depend on how q charts the configurations
//! (a chart's second-order terms multiply grad L = 0), which is why the lambda term is needed:
//! without it the frequencies of a prestressed structure are wrong (a pendulum held by a taut
//! cable has all its stiffness there). A structure whose constraints leave no motion (rank G =
//! the coordinates: furet2018's X modules at their actuators' commands, manriquez2019's
//! platform on both cables) has no mode.

use super::data::Data;
use super::model::Model;
use super::modes::{ModesError, StructureMode, StructureModes, ZERO_MODE_RATIO};
use crate::structure::{BodyKind, JointKind};
use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3};
use rapier3d_f64::prelude::*;
use std::sync::atomic::AtomicBool;

/// Finite-difference step of an angular coordinate [rad]: every derivative is taken at steps
/// h and 2 h and extrapolated (Richardson, [`richardson`]: error O(h^4), about 1e-12), so the
/// step can be large enough that round-off, eps L / h^2 in a second difference, stays near
/// 1e-10 of the stiffness.
const STEP_RAD: f64 = 1e-3;
/// Finite-difference step of a linear coordinate, a fraction of the structure's size.
const STEP_FRACTION: f64 = 1e-3;
/// The second, coarser step of the Richardson extrapolation, as a multiple of the first.
pub(super) const COARSE_STEP_RATIO: f64 = 2.0;
/// Singular values of G below this fraction of the largest span its null space: G by central
/// differences carries an error of about h^2 = 1e-8 of its entries, far below this, and the
/// constraints of the shipped structures have singular values above 1e-3 of the largest.
pub const NULL_SPACE_RATIO: f64 = 1e-6;

/// One generalized coordinate of the constrained analysis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModalCoordinate {
    /// Degree of freedom `dof` of a multibody [rad, or m for a prismatic joint].
    Link { multibody: MultibodyIndex, dof: usize, linear: bool },
    /// A free body outside the multibodies: translation of its centre of mass along world
    /// axis `axis` (0..3) \[m\], or rotation about it about world axis `axis - 3` (3..6) \[rad\].
    Body { body: usize, axis: usize },
}

impl ModalCoordinate {
    pub(super) fn linear(&self) -> bool {
        match self {
            ModalCoordinate::Link { linear, .. } => *linear,
            ModalCoordinate::Body { axis, .. } => *axis < 3,
        }
    }
}

/// The constraints the analysis was reduced by, and what it found of them.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraints {
    /// The generalized coordinates q.
    pub coordinates: Vec<ModalCoordinate>,
    /// The joints that close loops (structure indices), whose rows are constraints.
    pub closures: Vec<usize>,
    /// The taut inextensible cables (structure indices): one row each.
    pub taut_cables: Vec<usize>,
    /// The inextensible cables left out as slack.
    pub slack_cables: Vec<usize>,
    /// Constraint rows (loop rows, then one per taut cable).
    pub rows: usize,
    /// The rank of G: the coordinates less this are the degrees of freedom.
    pub rank: usize,
    /// The constraint forces lambda, one per row (a taut cable's tension \[N\] in the last
    /// `taut_cables.len()`).
    pub multipliers: Vec<f64>,
    /// The reduced Hessian's own error as an omega^2 \[rad^2/s^2\] (`zero_floor`): a mode
    /// below it is rigid (0 before the Hessian is taken).
    pub zero_floor: f64,
}

impl Constraints {
    /// The degrees of freedom left: coordinates less the rank of G.
    pub fn degrees_of_freedom(&self) -> usize {
        self.coordinates.len() - self.rank
    }
}

/// The state the analysis moves away from and back to: each multibody's link joints and each
/// plain body's pose.
pub(super) struct Saved {
    multibodies: Vec<(MultibodyIndex, Vec<MultibodyJoint>)>,
    poses: Vec<(usize, Pose)>,
}

impl Data {
    /// The analysis's coordinates: the multibodies' free degrees of freedom, then six per free
    /// body outside them (three per point mass).
    pub(super) fn modal_coordinates(&self, m: &Model) -> Vec<ModalCoordinate> {
        let s = &m.structure;
        let free: Vec<usize> = (0..s.bodies.len()).filter(|b| m.is_free(*b)).collect();
        let mut multibodies: Vec<MultibodyIndex> = Vec::new();
        for &b in &free {
            if let Some(mb) = self.multibody_of(m, b).filter(|mb| !multibodies.contains(mb)) {
                multibodies.push(mb);
            }
        }
        let mut out = Vec::new();
        for &mb in &multibodies {
            let linear = self.prismatic_dofs(m, mb);
            for dof in self.free_dofs(mb) {
                out.push(ModalCoordinate::Link { multibody: mb, dof, linear: linear.contains(&dof) });
            }
        }
        for &b in free.iter().filter(|&&b| self.multibody_of(m, b).is_none()) {
            // A point mass's turns move nothing (`modes.rs`, `turning_coordinates`): its three
            // translations alone (their tiny inertia had set the reduced Hessian's error floor,
            // as an omega^2, above every mode of a bead beside a joint tree).
            let axes = if m.point_masses[b] { 3 } else { 6 };
            out.extend((0..axes).map(|axis| ModalCoordinate::Body { body: b, axis }));
        }
        out
    }

    /// The degrees of freedom of multibody `mb` that prismatic joints own (lengths).
    fn prismatic_dofs(&self, m: &Model, mb: MultibodyIndex) -> Vec<usize> {
        let s = &m.structure;
        let prismatic = s
            .joints
            .iter()
            .enumerate()
            .filter(|(j, joint)| m.joint_links[*j].is_some() && matches!(joint.kind, JointKind::Prismatic { .. }));
        prismatic
            .filter_map(|(_, joint)| self.multibody_joints.rigid_body_link(m.handles[joint.child]))
            .filter(|link| link.multibody == mb)
            .filter_map(|link| self.multibody_joints.get_multibody(mb)?.link(link.id).map(|l| l.assembly_id()))
            .collect()
    }

    /// The joints that close loops, or the first whose kind has no constraint rows.
    pub(super) fn modal_closures(&self, m: &Model) -> Result<Vec<usize>, ModesError> {
        let s = &m.structure;
        let closures: Vec<usize> = (0..s.joints.len()).filter(|&j| m.joint_impulse[j].is_some()).collect();
        let rowless = |j: &&usize| {
            !matches!(
                s.joints[**j].kind,
                JointKind::Spherical
                    | JointKind::Revolute { .. }
                    | JointKind::Universal { .. }
                    | JointKind::PlanarPin { .. }
            )
        };
        match closures.iter().find(rowless) {
            Some(&j) => Err(ModesError::Loop(s.joints[j].name.clone())),
            None => Ok(closures),
        }
    }

    pub(super) fn save_modal_state(&self, m: &Model, coordinates: &[ModalCoordinate]) -> Saved {
        let mut saved = Saved { multibodies: Vec::new(), poses: Vec::new() };
        for c in coordinates {
            match *c {
                ModalCoordinate::Link { multibody, .. } if !saved.multibodies.iter().any(|x| x.0 == multibody) => {
                    if let Some(mb) = self.multibody_joints.get_multibody(multibody) {
                        saved.multibodies.push((multibody, mb.links().map(|l| *l.joint()).collect()));
                    }
                }
                ModalCoordinate::Body { body, axis: 0 } => {
                    saved.poses.push((body, *self.bodies[m.handles[body]].position()));
                }
                _ => {}
            }
        }
        saved
    }

    /// Puts every coordinate back where [`Self::save_modal_state`] read it, to the bit.
    pub(super) fn restore_modal_state(&mut self, m: &Model, saved: &Saved) {
        for (index, joints) in &saved.multibodies {
            let Some(mb) = self.multibody_joints.get_multibody_mut(*index) else { continue };
            for (i, joint) in joints.iter().enumerate() {
                if let Some(link) = mb.link_mut(i) {
                    link.joint = *joint;
                }
            }
            mb.forward_kinematics(&self.bodies, false);
            mb.update_rigid_bodies(&mut self.bodies, true);
        }
        for (b, pose) in &saved.poses {
            self.bodies[m.handles[*b]].set_position(*pose, true);
        }
    }

    /// Moves the coordinates: each (index into `coordinates`, displacement [rad or m]).
    pub(super) fn move_coordinates(&mut self, m: &Model, coordinates: &[ModalCoordinate], moves: &[(usize, f64)]) {
        for &(k, d) in moves {
            match coordinates[k] {
                ModalCoordinate::Link { multibody, dof, .. } => {
                    let Some(n) = self.multibody_joints.get_multibody(multibody).map(|mb| mb.ndofs()) else { continue };
                    let mut disp = vec![0.0; n];
                    disp[dof] = d;
                    self.displace(multibody, &disp);
                }
                ModalCoordinate::Body { body, axis } => {
                    let mut q = [Vector::ZERO; 2];
                    q[axis / 3][axis % 3] = d;
                    self.nudge(m, body, q[0], q[1]);
                }
            }
        }
    }

    /// The finite-difference step of each coordinate: [`STEP_RAD`] or [`STEP_FRACTION`] of
    /// the structure's size (either moves a node by at most that fraction of the size).
    pub(super) fn modal_steps(&self, m: &Model, coordinates: &[ModalCoordinate]) -> Vec<f64> {
        coordinates.iter().map(|c| if c.linear() { STEP_FRACTION * m.length_scale_m } else { STEP_RAD }).collect()
    }

    /// The constraint rows g(q) [m]: each closure's, then each taut cable's stretch.
    pub(super) fn constraint_rows(&self, m: &Model, closures: &[usize], taut: &[usize]) -> Vec<f64> {
        let mut out = Vec::new();
        for &j in closures {
            self.joint_rows(m, j, &mut out);
        }
        self.cable_rows(m, taut, &mut out);
        out
    }
}

/// What the first pass of differences finds: grad V [N or N m] and G.
pub(super) struct FirstDerivatives {
    pub(super) gradient: DVector<f64>,
    pub(super) jacobian: DMatrix<f64>,
}

/// The pieces of the constrained analysis that the second pass needs.
pub(super) struct Setup<'a> {
    pub(super) coordinates: &'a [ModalCoordinate],
    closures: &'a [usize],
    taut: &'a [usize],
    steps: Vec<f64>,
    /// Each body's centre of mass at the state analysed (the loads' reference).
    com: Vec<Vector3<f64>>,
    saved: Saved,
    /// Each member's branch at the state analysed (`Data::engaged_members`).
    engaged: Vec<bool>,
}

impl Data {
    /// L = V + lambda . g with the coordinates moved by `moves`, the state restored after.
    fn lagrangian_moved(&mut self, m: &Model, setup: &Setup, lambda: &DVector<f64>, moves: &[(usize, f64)]) -> f64 {
        self.move_coordinates(m, setup.coordinates, moves);
        let v = self.potential_energy_about(m, Some(&setup.com), &setup.engaged);
        let g = self.constraint_rows(m, setup.closures, setup.taut);
        self.restore_modal_state(m, &setup.saved);
        v + g.iter().zip(lambda.iter()).map(|(a, b)| a * b).sum::<f64>()
    }

    /// grad V and G = dg/dq by central differences.
    fn first_derivatives(&mut self, m: &Model, setup: &Setup, ratio: f64) -> FirstDerivatives {
        let n = setup.coordinates.len();
        let rows = self.constraint_rows(m, setup.closures, setup.taut).len();
        let mut out = FirstDerivatives { gradient: DVector::zeros(n), jacobian: DMatrix::zeros(rows, n) };
        for k in 0..n {
            let h = ratio * setup.steps[k];
            let at = |sim: &mut Data, d: f64| {
                sim.move_coordinates(m, setup.coordinates, &[(k, d)]);
                let v = sim.potential_energy_about(m, Some(&setup.com), &setup.engaged);
                let g = sim.constraint_rows(m, setup.closures, setup.taut);
                sim.restore_modal_state(m, &setup.saved);
                (v, g)
            };
            let ((vp, gp), (vm, gm)) = (at(self, h), at(self, -h));
            out.gradient[k] = (vp - vm) / (2.0 * h);
            for r in 0..rows {
                out.jacobian[(r, k)] = (gp[r] - gm[r]) / (2.0 * h);
            }
        }
        out
    }

    /// K = d2L/dq2 (lambda held) by central second differences, symmetrised.
    pub(super) fn lagrangian_hessian(
        &mut self,
        m: &Model,
        setup: &Setup,
        lambda: &DVector<f64>,
        ratio: f64,
    ) -> DMatrix<f64> {
        let n = setup.coordinates.len();
        let h: Vec<f64> = setup.steps.iter().map(|h| ratio * h).collect();
        let l0 = self.lagrangian_moved(m, setup, lambda, &[]);
        let mut k = DMatrix::zeros(n, n);
        for a in 0..n {
            let (ha, at) =
                (h[a], |sim: &mut Data, moves: &[(usize, f64)]| sim.lagrangian_moved(m, setup, lambda, moves));
            k[(a, a)] = (at(self, &[(a, ha)]) - 2.0 * l0 + at(self, &[(a, -ha)])) / (ha * ha);
            for b in 0..a {
                let hb = h[b];
                let pp = at(self, &[(a, ha), (b, hb)]);
                let pm = at(self, &[(a, ha), (b, -hb)]);
                let mp = at(self, &[(a, -ha), (b, hb)]);
                let mm = at(self, &[(a, -ha), (b, -hb)]);
                k[(a, b)] = (pp - pm - mp + mm) / (4.0 * ha * hb);
            }
        }
        // Sequential moves of rotations do not commute: the antisymmetric part is theirs.
        let lower = k.clone();
        let upper = lower.transpose();
        &lower + &upper - DMatrix::from_diagonal(&lower.diagonal())
    }

    /// J (6 per moving body x coordinates): the centre-of-mass velocity and angular velocity
    /// of each body that `states` reads, per unit rate of each coordinate, by central
    /// differences.
    fn coordinate_body_jacobian(
        &mut self,
        m: &Model,
        setup: &Setup,
        states: &dyn Fn(&Data) -> Vec<BodyState>,
        ratio: f64,
    ) -> DMatrix<f64> {
        let count = states(self).len();
        let mut jac = DMatrix::zeros(6 * count, setup.coordinates.len());
        for (c, &step) in setup.steps.iter().enumerate() {
            let h = ratio * step;
            self.move_coordinates(m, setup.coordinates, &[(c, h)]);
            let plus = states(self);
            self.restore_modal_state(m, &setup.saved);
            self.move_coordinates(m, setup.coordinates, &[(c, -h)]);
            let minus = states(self);
            self.restore_modal_state(m, &setup.saved);
            for (i, ((xp, rp), (xm, rm))) in plus.iter().zip(&minus).enumerate() {
                jac.view_mut((6 * i, c), (3, 1)).copy_from(&((xp - xm) / (2.0 * h)));
                jac.view_mut((6 * i + 3, c), (3, 1)).copy_from(&((rp * rm.inverse()).scaled_axis() / (2.0 * h)));
            }
        }
        jac
    }
}

/// A body's centre of mass [m] and rotation.
type BodyState = (Vector3<f64>, UnitQuaternion<f64>);

/// Richardson's extrapolation of central differences at steps h and [`COARSE_STEP_RATIO`] h:
/// the h^2 term of their error cancels.
pub(super) fn richardson(fine: &DMatrix<f64>, coarse: &DMatrix<f64>) -> DMatrix<f64> {
    let r2 = COARSE_STEP_RATIO * COARSE_STEP_RATIO;
    (fine * r2 - coarse) / (r2 - 1.0)
}

/// A basis of null(G) (coordinates x its dimension) and the rank of G: the right singular
/// vectors whose singular value is at most [`NULL_SPACE_RATIO`] of the largest. G is padded
/// with zero rows to at least square, so that the SVD gives every right singular vector.
pub(crate) fn null_space(g: &DMatrix<f64>, n: usize) -> (DMatrix<f64>, usize) {
    if g.nrows() == 0 {
        return (DMatrix::identity(n, n), 0);
    }
    let mut padded = DMatrix::zeros(g.nrows().max(n), n);
    padded.view_mut((0, 0), (g.nrows(), n)).copy_from(g);
    let svd = padded.svd(false, true);
    let v_t = svd.v_t.expect("the SVD was asked for V^T");
    let largest = svd.singular_values.max();
    let null: Vec<usize> =
        (0..n).filter(|&i| svd.singular_values[i] <= NULL_SPACE_RATIO * largest || largest == 0.0).collect();
    let mut basis = DMatrix::zeros(n, null.len());
    for (c, &i) in null.iter().enumerate() {
        basis.set_column(c, &v_t.row(i).transpose());
    }
    (basis, n - null.len())
}

/// How far the reduced problem's omega^2 may be off through the Hessian's error `error`
/// (its difference between the two steps) on null(G) spanned by `basis`:
/// |N^T E N|_2 / lambda_min(N^T M N) \[rad^2/s^2\]. A rigid motion (a bar's spin about its own
/// axis on a ball joint) differences to an omega^2 of about this size instead of 0: 2.6e-8
/// rad^2/s^2 there, 1.4e-9 of the largest, against a floor of 1e-7.
pub(crate) fn zero_floor(error: &DMatrix<f64>, basis: &DMatrix<f64>, reduced_mass: &DMatrix<f64>) -> f64 {
    if basis.ncols() == 0 {
        return 0.0;
    }
    let reduced_error = basis.transpose() * error * basis;
    let largest_error = reduced_error.singular_values().max();
    let lightest = reduced_mass.clone().symmetric_eigenvalues().min();
    if lightest > 0.0 {
        largest_error / lightest
    } else {
        0.0
    }
}

/// The constraint forces lambda of grad V + G^T lambda = 0 (least squares, minimum norm).
pub(super) fn multipliers(first: &FirstDerivatives) -> DVector<f64> {
    least_squares(&first.jacobian.transpose(), &(-&first.gradient))
}

/// The least-squares, least-norm x of a x = b, singular values of a below
/// [`NULL_SPACE_RATIO`] of the largest left out; zeros where a has no rows or columns.
pub(crate) fn least_squares(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return DVector::zeros(a.ncols());
    }
    let svd = a.clone().svd(true, true);
    let tol = NULL_SPACE_RATIO * svd.singular_values.max();
    svd.solve(b, tol).unwrap_or_else(|_| DVector::zeros(a.ncols()))
}

impl Data {
    /// The modes of a structure held by loops and taut inextensible cables (module docs).
    pub(super) fn constrained_modes(
        &mut self,
        m: &Model,
        cancel: Option<&AtomicBool>,
    ) -> Result<StructureModes, ModesError> {
        let s = &m.structure;
        let (mut constraints, first) = self.constraints_here(m)?;
        let (coordinates, closures, taut) = (&constraints.coordinates, &constraints.closures, &constraints.taut_cables);
        let bodies: Vec<usize> = (0..s.bodies.len()).filter(|&b| s.bodies[b].kind == BodyKind::Free).collect();
        let setup = self.constrained_setup(m, coordinates, closures, taut);
        let lambda = DVector::from_column_slice(&constraints.multipliers);
        let (stiffness, error) = self.lagrangian_stiffness_and_error(m, &setup, &lambda);
        let mass = self.coordinate_mass(m, &setup, &bodies);
        let jac = mass.1;
        let body_mass = self.mass_matrix(m, &bodies);
        let (basis, _) = null_space(&first.jacobian, coordinates.len());
        let reduced_mass = basis.transpose() * &mass.0 * &basis;
        let reduced_stiffness = basis.transpose() * &stiffness * &basis;
        // No motion left (rank G = the coordinates): no mode.
        let eigen = if basis.ncols() == 0 {
            vec![]
        } else {
            let symmetric = |a: &DMatrix<f64>| 0.5 * (a + a.transpose());
            crate::eigen::modes_until(&symmetric(&reduced_stiffness), &symmetric(&reduced_mass), cancel)?
        };
        let largest = eigen.iter().fold(0.0f64, |l, e| l.max(e.omega_squared.abs()));
        constraints.zero_floor = zero_floor(&error, &basis, &reduced_mass);
        let threshold = (ZERO_MODE_RATIO * largest).max(constraints.zero_floor);
        let com: Vec<_> = self.body_states(m, &bodies).iter().map(|(c, _)| *c).collect();
        let modes: Vec<StructureMode> = eigen
            .into_iter()
            .map(|e| {
                let q = &basis * e.shape;
                let shape: Vec<f64> = (&jac * &q).iter().copied().collect();
                StructureMode {
                    omega_squared: e.omega_squared,
                    rigid: e.omega_squared.abs() <= threshold,
                    node_motion: self.node_motion(m, &bodies, &com, &shape),
                    shape,
                    joint_shape: q.iter().copied().collect(),
                }
            })
            .collect();
        let rigid = modes.iter().filter(|x| x.rigid).count();
        let poses = bodies.iter().map(|b| self.body_pose(m, *b)).collect();
        Ok(StructureModes {
            bodies,
            joints: vec![],
            poses,
            mass: super::modes::diagonal_blocks(&body_mass),
            modes,
            rigid,
            constraints: Some(constraints),
            lowest_of: None,
            left_out: 0,
        })
    }

    /// The constraints of the current state (every joint that closes a loop, every taut
    /// inextensible cable; a slack one left out) with their forces lambda from the
    /// equilibrium, and the first derivatives they were found from.
    pub(super) fn constraints_here(&mut self, m: &Model) -> Result<(Constraints, FirstDerivatives), ModesError> {
        let s = &m.structure;
        let closures = self.modal_closures(m)?;
        let inextensible = s.members.iter().enumerate().filter(|(_, c)| c.is_inextensible_cable()).map(|(c, _)| c);
        let (taut, slack): (Vec<usize>, Vec<usize>) = inextensible.partition(|&c| self.cable_is_taut(m, c));
        let coordinates = self.modal_coordinates(m);
        if coordinates.is_empty() {
            return Err(ModesError::NoFreeBody);
        }
        let setup = self.constrained_setup(m, &coordinates, &closures, &taut);
        let first = self.first_derivatives_extrapolated(m, &setup);
        let lambda = multipliers(&first);
        let rank = null_space(&first.jacobian, coordinates.len()).1;
        let constraints = Constraints {
            rows: first.jacobian.nrows(),
            rank,
            multipliers: lambda.iter().copied().collect(),
            coordinates,
            closures,
            taut_cables: taut,
            slack_cables: slack,
            zero_floor: 0.0,
        };
        Ok((constraints, first))
    }

    /// K = d2L/dq2 (lambda held), extrapolated over h and 2 h, and its difference between the
    /// two steps: the size of its error (round-off grows as 1/h^2 in a second difference, so
    /// the finer step's dominates the difference).
    pub(super) fn lagrangian_stiffness_and_error(
        &mut self,
        m: &Model,
        setup: &Setup,
        lambda: &DVector<f64>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let fine = self.lagrangian_hessian(m, setup, lambda, 1.0);
        let coarse = self.lagrangian_hessian(m, setup, lambda, COARSE_STEP_RATIO);
        (richardson(&fine, &coarse), fine - coarse)
    }

    /// What the differences of the constrained analysis need at the current state.
    pub(super) fn constrained_setup<'a>(
        &self,
        m: &Model,
        coordinates: &'a [ModalCoordinate],
        closures: &'a [usize],
        taut: &'a [usize],
    ) -> Setup<'a> {
        let s = &m.structure;
        Setup {
            coordinates,
            closures,
            taut,
            steps: self.modal_steps(m, coordinates),
            com: (0..s.bodies.len()).map(|b| self.world_com(m, b)).map(|c| Vector3::new(c.x, c.y, c.z)).collect(),
            saved: self.save_modal_state(m, coordinates),
            engaged: self.engaged_members(m),
        }
    }

    /// grad V and G at steps h and 2 h, extrapolated.
    pub(super) fn first_derivatives_extrapolated(&mut self, m: &Model, setup: &Setup) -> FirstDerivatives {
        let (fine, coarse) =
            (self.first_derivatives(m, setup, 1.0), self.first_derivatives(m, setup, COARSE_STEP_RATIO));
        let column = |v: &DVector<f64>| DMatrix::from_column_slice(v.len(), 1, v.as_slice());
        FirstDerivatives {
            gradient: richardson(&column(&fine.gradient), &column(&coarse.gradient)).column(0).into_owned(),
            jacobian: richardson(&fine.jacobian, &coarse.jacobian),
        }
    }

    /// The mass matrix in the coordinates, J^T M_b J over the structure's free bodies (the
    /// hidden bodies of universal joints have no mass), with their J (for the modes' shapes).
    pub(super) fn coordinate_mass(
        &mut self,
        m: &Model,
        setup: &Setup,
        bodies: &[usize],
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let own = |sim: &Data| sim.body_states(m, bodies);
        let jac = richardson(
            &self.coordinate_body_jacobian(m, setup, &own, 1.0),
            &self.coordinate_body_jacobian(m, setup, &own, COARSE_STEP_RATIO),
        );
        let mass = jac.transpose() * self.mass_matrix(m, bodies) * &jac;
        (mass, jac)
    }

    /// Moves the constrained analysis's coordinates by `dq` (its mode's `joint_shape` times a
    /// modal amplitude).
    pub(super) fn displace_constrained(&mut self, m: &Model, constraints: &Constraints, dq: &[f64]) {
        let moves: Vec<(usize, f64)> = dq.iter().copied().enumerate().collect();
        self.move_coordinates(m, &constraints.coordinates, &moves);
    }
}
