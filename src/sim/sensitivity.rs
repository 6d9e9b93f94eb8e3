//! What an equilibrium's sensitivities need of the simulation (`run/sensitivity.rs` puts them
//! together): the free coordinates q of a settled state, the generalized forces Q(q) on them
//! (zero at an equilibrium), the tangent stiffness K = -dQ/dq and the mass matrix M in the same
//! coordinates, a move along them, and a state carried over to the same structure built with
//! other parameters. By the implicit function theorem on Q(q(p), p) = 0,
//! dq/dp = K^-1 dQ/dp (one linear solve per parameter, where differences of settles need a
//! settle per step), and for a mass-normalised mode phi,
//! d omega^2 / dp = phi^T (dK/dp - omega^2 dM/dp) phi (the derivative of the generalized
//! eigenvalue, Nelson 1976).
//!
//! The coordinates are the modal analysis's (`modes.rs`, `joint_modes.rs`): six per free body
//! (translation of the centre of mass, small rotation about it, world frame) where there are
//! no joints, else the free joints' coordinates of joint trees rooted on fixed bodies. Q is
//! exact (member forces, torsion springs and constant loads projected on the coordinates,
//! `forces.rs`), and K its central difference extrapolated over h and 2 h (Richardson, error
//! O(h^4) and round-off eps |Q| / h: about 1e-13 of K). A structure held by loops or taut
//! inextensible cables has the constrained analysis's coordinates and its Lagrangian
//! (`constrained_sensitivity.rs`): Q = -dL/dq with the constraint forces held, K = d2L/dq2, and
//! the constraints g(q) and G = dg/dq beside them.

use super::constrained_modes::Constraints;
use super::data::Data;
use super::model::Model;
use super::modes::ModesError;
use crate::structure::{BodyKind, JointKind};
use nalgebra::{DMatrix, DVector};
use rapier3d_f64::prelude::*;

/// Finite-difference step of an angular coordinate [rad] (extrapolated over h and 2 h).
const STEP_RAD: f64 = 1e-3;
/// Finite-difference step of a linear coordinate, a fraction of the structure's size.
const STEP_FRACTION: f64 = 1e-3;

/// The free coordinates of an equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub enum EquilibriumCoordinates {
    /// Six per free body (structure indices; no joints): dx, dy, dz \[m\] of the centre of
    /// mass, then a small rotation rx, ry, rz \[rad\] about it.
    Bodies(Vec<usize>),
    /// The free joints' coordinates (structure indices of revolute \[rad\] and prismatic
    /// \[m\] joints).
    Joints(Vec<usize>),
    /// A structure held by loops or taut inextensible cables: the constrained analysis's
    /// coordinates, constraints and constraint forces at the settled state.
    Constrained(Box<ConstrainedCoordinates>),
}

/// The coordinates of a structure held by constraints, and their names.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstrainedCoordinates {
    pub constraints: Constraints,
    /// A joint's name (`JOINT.axis1`, `.axis2` for a universal joint's two), or `BODY.x` ..
    /// `BODY.rz` for a plain free body.
    pub names: Vec<String>,
}

impl EquilibriumCoordinates {
    /// How many coordinates.
    pub fn len(&self) -> usize {
        match self {
            EquilibriumCoordinates::Bodies(b) => 6 * b.len(),
            EquilibriumCoordinates::Joints(j) => j.len(),
            EquilibriumCoordinates::Constrained(c) => c.names.len(),
        }
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Each coordinate's name: `BODY.x` .. `BODY.rz`, or the joint's name.
    pub fn names(&self, s: &crate::structure::Structure) -> Vec<String> {
        match self {
            EquilibriumCoordinates::Bodies(b) => b
                .iter()
                .flat_map(|&b| ["x", "y", "z", "rx", "ry", "rz"].map(|c| format!("{}.{c}", s.bodies[b].name)))
                .collect(),
            EquilibriumCoordinates::Joints(j) => j.iter().map(|&j| s.joints[j].name.clone()).collect(),
            EquilibriumCoordinates::Constrained(c) => c.names.clone(),
        }
    }

    /// The constraints, for a structure held by them.
    pub fn constraints(&self) -> Option<&Constraints> {
        match self {
            EquilibriumCoordinates::Constrained(c) => Some(&c.constraints),
            _ => None,
        }
    }

    /// The same coordinates with the constraint forces `lambda` (one per constraint row).
    pub fn with_multipliers(&self, lambda: &[f64]) -> Self {
        let mut out = self.clone();
        if let EquilibriumCoordinates::Constrained(c) = &mut out {
            c.constraints.multipliers = lambda.to_vec();
        }
        out
    }
}

/// Why a state has no sensitivities.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    /// What the modal analysis refuses too.
    #[error(transparent)]
    Modes(#[from] ModesError),
}

/// The derivative at 0 of a function sampled at -2 h, -h, h, 2 h: the central difference
/// extrapolated over h and 2 h, (8 (f(h) - f(-h)) - (f(2h) - f(-2h))) / (12 h), error O(h^4).
pub fn derivative_from_samples<T>(minus2: T, minus: T, plus: T, plus2: T, h: f64) -> T
where
    T: std::ops::Sub<Output = T> + std::ops::Mul<f64, Output = T>,
{
    ((plus - minus) * 8.0 - (plus2 - minus2)) * (1.0 / (12.0 * h))
}

/// [`derivative_from_samples`] with its error estimate, element by element, for samples that
/// are 0 at the point itself (offsets from it): its truncation, the difference from the central
/// difference at h over the same samples ((plus - minus) / (2 h), whose O(h^2) error bounds the
/// five-point stencil's O(h^4) from above), and its samples' own noise sigma (a finite
/// difference's round-off inside each sample) through the stencil, `NOISE_SIGMAS` of it.
/// sigma is read from the fourth difference of the five values -2 h ... 2 h, which a smooth
/// function makes h^4 times its fourth derivative (negligible at these steps) and independent
/// noise sigma sqrt(1 + 16 + 16 + 1); the stencil turns it into sigma sqrt(130) / (12 h).
pub fn derivative_and_estimate(
    minus2: &DVector<f64>,
    minus: &DVector<f64>,
    plus: &DVector<f64>,
    plus2: &DVector<f64>,
    h: f64,
) -> (DVector<f64>, DVector<f64>) {
    let five = derivative_from_samples(minus2.clone(), minus.clone(), plus.clone(), plus2.clone(), h);
    let three = (plus - minus) / (2.0 * h);
    let fourth = minus2 - minus * 4.0 - plus * 4.0 + plus2;
    let noise = fourth.abs() * (NOISE_SIGMAS * 130f64.sqrt() / (34f64.sqrt() * 12.0 * h));
    let estimate = (&five - three).abs() + noise;
    (five, estimate)
}

/// How many of the samples' noise sigmas a derivative's estimate carries.
const NOISE_SIGMAS: f64 = 2.0;

impl Data {
    /// The free coordinates of the current structure, or why it has none that this analysis
    /// takes.
    pub(super) fn equilibrium_coordinates(&mut self, m: &Model) -> Result<EquilibriumCoordinates, SensitivityError> {
        let s = &m.structure;
        if !s.bodies.iter().any(|b| b.kind == BodyKind::Free) {
            return Err(ModesError::NoFreeBody.into());
        }
        if let Some(c) = s.members.iter().find(|c| c.has_friction()) {
            return Err(ModesError::Friction(c.name.clone()).into());
        }
        if m.is_constrained() {
            let (constraints, _) = self.constraints_here(m)?;
            let names = self.modal_coordinate_names(m, &constraints.coordinates);
            return Ok(EquilibriumCoordinates::Constrained(Box::new(ConstrainedCoordinates { constraints, names })));
        }
        if let Some(support) = s.supports.first() {
            return Err(ModesError::Supported(s.nodes[support.node].name.clone()).into());
        }
        if s.joints.is_empty() {
            return Ok(EquilibriumCoordinates::Bodies((0..s.bodies.len()).filter(|b| m.is_free(*b)).collect()));
        }
        Ok(EquilibriumCoordinates::Joints(self.modal_joints(m)?))
    }

    /// The generalized forces Q on the coordinates now [N or N m]: -dV/dq, V the potential
    /// energy of the members, torsion springs and constant loads.
    pub(super) fn generalized_forces(&mut self, m: &Model, c: &EquilibriumCoordinates) -> DVector<f64> {
        if let Some(c) = c.constraints() {
            return self.lagrangian_forces(m, c);
        }
        let q = self.free_coordinate_forces(m);
        debug_assert_eq!(q.len(), c.len(), "the tree's free coordinates are the analysis's");
        DVector::from_vec(q)
    }

    /// The finite-difference step of coordinate `i`.
    pub(super) fn coordinate_step(&self, m: &Model, c: &EquilibriumCoordinates, i: usize) -> f64 {
        let linear = match c {
            EquilibriumCoordinates::Bodies(_) => i % 6 < 3,
            EquilibriumCoordinates::Joints(j) => matches!(m.structure.joints[j[i]].kind, JointKind::Prismatic { .. }),
            EquilibriumCoordinates::Constrained(c) => c.constraints.coordinates[i].linear(),
        };
        if linear {
            STEP_FRACTION * m.length_scale_m
        } else {
            STEP_RAD
        }
    }

    /// Moves coordinate `i` by `d` (m or rad), the bodies beyond a joint along.
    pub(super) fn displace_coordinate(&mut self, m: &Model, c: &EquilibriumCoordinates, i: usize, d: f64) {
        match c {
            EquilibriumCoordinates::Joints(j) => self.displace_joint(m, j[i], d),
            EquilibriumCoordinates::Constrained(c) => self.move_coordinates(m, &c.constraints.coordinates, &[(i, d)]),
            EquilibriumCoordinates::Bodies(b) => {
                let h = m.handles[b[i / 6]];
                let com = self.world_com(m, b[i / 6]);
                let mut axis = Vector::ZERO;
                axis[i % 3] = 1.0;
                let pose = *self.bodies[h].position();
                let moved = if i % 6 < 3 {
                    Pose::from_translation(axis * d) * pose
                } else {
                    Pose::from_translation(com)
                        * Pose::from_rotation(Rotation::from_axis_angle(axis, d))
                        * Pose::from_translation(-com)
                        * pose
                };
                self.bodies[h].set_position(moved, true);
            }
        }
    }

    /// Moves every coordinate by `dq` (m or rad), in order.
    pub(super) fn displace_coordinates(&mut self, m: &Model, c: &EquilibriumCoordinates, dq: &[f64]) {
        for (i, d) in dq.iter().enumerate().filter(|(_, d)| **d != 0.0) {
            self.displace_coordinate(m, c, i, *d);
        }
    }

    /// K = -dQ/dq now: each column a central difference extrapolated over h and 2 h, the
    /// state restored after each move.
    pub(super) fn equilibrium_stiffness(&mut self, m: &Model, c: &EquilibriumCoordinates) -> DMatrix<f64> {
        self.equilibrium_stiffness_and_error(m, c).0
    }

    /// [`Self::equilibrium_stiffness`] and the size of its error: with constraints, the
    /// difference of the second differences at h and 2 h (`constrained_modes::zero_floor`);
    /// zero otherwise (K there is the difference of exact forces, about 1e-13 of K).
    pub(super) fn equilibrium_stiffness_and_error(
        &mut self,
        m: &Model,
        c: &EquilibriumCoordinates,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        if let Some(c) = c.constraints() {
            return self.lagrangian_stiffness(m, c);
        }
        let k = self.forces_stiffness(m, c);
        let zero = DMatrix::zeros(k.nrows(), k.ncols());
        (k, zero)
    }

    /// K = -dQ/dq of the exact generalized forces Q.
    fn forces_stiffness(&mut self, m: &Model, c: &EquilibriumCoordinates) -> DMatrix<f64> {
        let n = c.len();
        let mut k = DMatrix::zeros(n, n);
        for i in 0..n {
            let h = self.coordinate_step(m, c, i);
            let mut at = |d: f64| {
                self.displace_coordinate(m, c, i, d);
                let q = self.generalized_forces(m, c);
                self.displace_coordinate(m, c, i, -d);
                q
            };
            let (m2, m1, p1, p2) = (at(-2.0 * h), at(-h), at(h), at(2.0 * h));
            k.set_column(i, &-derivative_from_samples(m2, m1, p1, p2, h));
        }
        k
    }

    /// The mass matrix in the coordinates: the free bodies' own, or J^T M J through the
    /// joints (`joint_modes.rs`).
    pub(super) fn equilibrium_mass(&mut self, m: &Model, c: &EquilibriumCoordinates) -> DMatrix<f64> {
        match c {
            EquilibriumCoordinates::Bodies(b) => self.mass_matrix(m, b),
            EquilibriumCoordinates::Constrained(c) => self.constrained_mass(m, &c.constraints),
            EquilibriumCoordinates::Joints(_) => {
                let bodies: Vec<usize> = (0..m.structure.bodies.len()).filter(|b| m.is_free(*b)).collect();
                let jac = self.equilibrium_jacobian(m, c, &bodies);
                jac.transpose() * self.mass_matrix(m, &bodies) * jac
            }
        }
    }

    /// J (6 per body of `bodies` x the coordinates): each body's centre-of-mass velocity and
    /// angular velocity per unit rate of each coordinate, by central differences extrapolated
    /// over h and 2 h (`joint_modes.rs` takes one step: error h^2, 1e-8 of M).
    fn equilibrium_jacobian(&mut self, m: &Model, c: &EquilibriumCoordinates, bodies: &[usize]) -> DMatrix<f64> {
        let start = self.body_states(m, bodies);
        let mut jac = DMatrix::zeros(6 * bodies.len(), c.len());
        for i in 0..c.len() {
            let h = self.coordinate_step(m, c, i);
            let mut at = |d: f64| {
                self.displace_coordinate(m, c, i, d);
                let moved = self.body_states(m, bodies);
                self.displace_coordinate(m, c, i, -d);
                let mut v = DVector::zeros(6 * bodies.len());
                for (k, ((x, r), (x0, r0))) in moved.iter().zip(&start).enumerate() {
                    v.fixed_rows_mut::<3>(6 * k).copy_from(&(x - x0));
                    v.fixed_rows_mut::<3>(6 * k + 3).copy_from(&(r * r0.inverse()).scaled_axis());
                }
                v
            };
            let (m2, m1, p1, p2) = (at(-2.0 * h), at(-h), at(h), at(2.0 * h));
            jac.set_column(i, &derivative_from_samples(m2, m1, p1, p2, h));
        }
        jac
    }

    /// Puts this structure (the same one as `from`'s, built with other parameters) in the
    /// configuration of `from`, coordinate by coordinate: each free joint's coordinate from its
    /// drawn configuration, each plain free body's displacement from its drawn pose. The
    /// commands are this simulation's own (set before).
    pub(super) fn take_configuration(&mut self, m: &Model, from: &Data, c: &EquilibriumCoordinates) {
        match c {
            EquilibriumCoordinates::Constrained(c) => self.take_constrained_configuration(m, from, &c.constraints),
            EquilibriumCoordinates::Bodies(b) => {
                for &b in b {
                    let pose = *from.bodies[m.handles[b]].position();
                    self.bodies[m.handles[b]].set_position(pose, true);
                }
            }
            EquilibriumCoordinates::Joints(j) => {
                for &j in j {
                    if let (Some(to), Some(target)) = (self.link_coordinate(m, j), from.link_coordinate(m, j)) {
                        self.displace_joint(m, j, target - to);
                    }
                }
            }
        }
        self.zero_body_velocities(m);
    }

    /// The constraints g(q) now (none without constraints) [m].
    pub(super) fn equilibrium_constraint_values(&self, m: &Model, c: &EquilibriumCoordinates) -> DVector<f64> {
        c.constraints().map_or_else(|| DVector::zeros(0), |c| self.constraint_values(m, c))
    }

    /// G = dg/dq now (no rows without constraints).
    pub(super) fn equilibrium_constraint_jacobian(&mut self, m: &Model, c: &EquilibriumCoordinates) -> DMatrix<f64> {
        match c.constraints() {
            Some(k) => self.constraint_jacobian(m, k),
            None => DMatrix::zeros(0, c.len()),
        }
    }

    /// Joint `j`'s coordinate in its multibody, from its drawn configuration (rad or m).
    fn link_coordinate(&self, m: &Model, j: usize) -> Option<f64> {
        let link = m.joint_links[j]?;
        let (mb, id) = self.multibody_joints.get(link.multibody_joint)?;
        let l = mb.link(id)?;
        Some(l.joint().coords()[super::joint_data::joint_free_axis(&l.joint().data)])
    }
}
