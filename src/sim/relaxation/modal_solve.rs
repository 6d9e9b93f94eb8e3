//! K^+ r of a large structure of free bodies (above
//! [`crate::structure::DENSE_MODAL_MAX_FREE_BODIES`]): the static response to a load r over
//! the modes that are not rigid, x = sum of phi (phi^T r) / omega^2 (phi mass-normalised), as
//! the dense sensitivity takes it from every mode, here without the dense eigenproblem. The
//! sensitivities' dq/dp = K^-1 dQ/dp (`run/sensitivity.rs`) on the exact Hessian H that the
//! relaxation assembles, the stiffness of `tensegrity modes` (`lowest_modes.rs`).
//!
//! The lowest modes are known (the modal analysis's: every rigid mode and the lowest others).
//! Their part of x is taken from them exactly; the rest, in the mass-weighted coordinates
//! y = L^T x (A = L^-1 H L^-T, b = L^-1 r), solves A y = P b on the complement of those modes
//! (P the projector off them) by iterative refinement on the sparse Cholesky factor of
//! A - sigma 1 (sigma the small negative shift of the modal analysis):
//! y <- y + P (A - sigma 1)^-1 P (b - A y). Each mode of the complement converges as
//! |sigma| / (omega^2 - sigma) per iteration (sigma is 1e-10 of the largest omega^2: one or two
//! iterations), to [`SOLVE_RESIDUAL_RATIO`] of |b|. Golub & Van Loan, Matrix Computations,
//! 4th ed., section 3.5.3 (iterative refinement).

use super::super::data::Data;
use super::super::model::Model;
use super::lowest_modes::{largest_magnitude, shifted_factor, weighted_stiffness, Weighted};
use crate::eigen::EigenError;
use nalgebra::{DMatrix, DVector, Matrix6};
use nalgebra_sparse::factorization::CscCholesky;

/// The refinement stops when |P (b - A y)| is below this fraction of |b|.
const SOLVE_RESIDUAL_RATIO: f64 = 1e-13;
/// Refinement steps before the solve is given up (each mode of the complement gains about ten
/// digits a step).
const MAX_REFINEMENTS: usize = 30;

/// What solves K x = r over the modes that are not rigid (module docs), factorized once.
pub(crate) struct ModalSolve {
    weighted: Weighted,
    factor: CscCholesky<f64>,
    /// L of each block's mass, in block order.
    mass_factor: Vec<Matrix6<f64>>,
    /// The known modes: omega^2, x (block order, mass-normalised), y = L^T x (factor order),
    /// and whether rigid.
    known: Vec<(f64, DVector<f64>, DVector<f64>, bool)>,
}

impl Data {
    /// The solver of K x = r at the current state; `mass`: each free body's mass block, and
    /// `known` the modal analysis's modes there (omega^2, mass-normalised shape in block
    /// order, rigid), all in the relaxation's block order.
    pub(in crate::sim) fn modal_solve(
        &self,
        m: &Model,
        mass: &[Matrix6<f64>],
        known: &[(f64, DVector<f64>, bool)],
    ) -> Result<ModalSolve, EigenError> {
        let dofs = self.relaxation_dofs(m);
        let system = self.relaxation_system(m, &dofs);
        let weighted = weighted_stiffness(&dofs, &system, mass)?;
        let largest = largest_magnitude(&weighted.matrix, None)?;
        let factor = shifted_factor(&weighted, largest)?;
        let mass_factor = weighted.factors();
        let mut solve = ModalSolve { weighted, factor, mass_factor, known: Vec::new() };
        solve.known = known.iter().map(|(w2, x, rigid)| (*w2, x.clone(), solve.weigh_shape(x), *rigid)).collect();
        Ok(solve)
    }
}

impl ModalSolve {
    /// x = K^+ r (block order): the known modes' part, then the refined rest (module docs).
    pub(in crate::sim) fn solve(&self, r: &DVector<f64>) -> Result<DVector<f64>, EigenError> {
        let mut x = DVector::zeros(r.len());
        for (w2, shape, _, rigid) in &self.known {
            if !rigid {
                x += shape * (shape.dot(r) / w2);
            }
        }
        let b = self.off_known(self.weigh_force(r));
        let tolerance = SOLVE_RESIDUAL_RATIO * b.norm();
        let mut y = DVector::zeros(b.len());
        let mut residual = b.clone();
        for _ in 0..MAX_REFINEMENTS {
            if residual.norm() <= tolerance {
                return Ok(x + self.weighted.shape(&y));
            }
            let mut d = DMatrix::from_column_slice(residual.len(), 1, residual.as_slice());
            self.factor.solve_mut(&mut d);
            y += self.off_known(d.column(0).into_owned());
            residual = self.off_known(&b - &self.weighted.matrix * &y);
        }
        Err(EigenError::NotConverged(MAX_REFINEMENTS))
    }

    /// v less its components along the known modes (orthonormal in the weighted coordinates).
    fn off_known(&self, mut v: DVector<f64>) -> DVector<f64> {
        for (_, _, y, _) in &self.known {
            v.axpy(-y.dot(&v), y, 1.0);
        }
        v
    }

    /// y = L^T x in factor order, for x in block order.
    fn weigh_shape(&self, x: &DVector<f64>) -> DVector<f64> {
        let mut y = DVector::zeros(x.len());
        for (i, &p) in self.weighted.position.iter().enumerate() {
            y.fixed_rows_mut::<6>(6 * p).copy_from(&(self.mass_factor[i].transpose() * x.fixed_rows::<6>(6 * i)));
        }
        y
    }

    /// b = L^-1 r in factor order, for r in block order.
    fn weigh_force(&self, r: &DVector<f64>) -> DVector<f64> {
        let mut b = DVector::zeros(r.len());
        for (i, &p) in self.weighted.position.iter().enumerate() {
            b.fixed_rows_mut::<6>(6 * p).copy_from(&(self.weighted.inverse_factor[i] * r.fixed_rows::<6>(6 * i)));
        }
        b
    }
}
