//! The generalized symmetric eigenproblem K v = lambda M v of a stiffness K and a positive
//! definite mass matrix M (both symmetric): the natural frequencies omega = sqrt(lambda) and
//! mode shapes of a linearised conservative system (M q'' + K q = 0). Used by the file's
//! dynamic model (`file_model::dynamics`) and the structure's own modal analysis
//! (`sim::modes`). Plain nalgebra: Cholesky M = L L^T, then the standard symmetric problem
//! (L^-1 K L^-T) y = lambda y, v = L^-T y (Golub & Van Loan, Matrix Computations, 4th ed.,
//! section 8.7.2).

use crate::stoppable::{interruptible, Halted};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use std::sync::atomic::AtomicBool;

/// One mode: its eigenvalue lambda = omega^2 [rad^2/s^2] and its shape, normalised so that
/// v^T M v = 1 (mass-normalised).
#[derive(Clone, Debug)]
pub struct Mode {
    pub omega_squared: f64,
    pub shape: DVector<f64>,
}

impl Mode {
    /// omega [rad/s]: sqrt(lambda), or minus sqrt(-lambda) where lambda < 0 (an unstable
    /// direction: its growth rate, signed so that it cannot be mistaken for a frequency).
    pub fn omega(&self) -> f64 {
        self.omega_squared.signum() * self.omega_squared.abs().sqrt()
    }
}

/// Why the eigenproblem has no solution.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EigenError {
    #[error("the mass matrix is not positive definite (Cholesky failed)")]
    MassNotPositiveDefinite,
    #[error("the matrices are not square and of one size ({0}x{1} and {2}x{3})")]
    Shape(usize, usize, usize, usize),
    #[error("a matrix entry is not finite")]
    NotFinite,
    /// The iterative solver of large problems (`sim::modes`) did not converge.
    #[error("the lowest modes did not converge in {0} iterations")]
    NotConverged(usize),
    /// The cancel flag was raised while the problem was solved.
    #[error("interrupted")]
    Interrupted,
}

/// [`modes`] on a thread of its own, waited for with `cancel` looked at every
/// [`crate::stoppable::POLL_S`]: [`EigenError::Interrupted`] once it is raised (a dense problem of
/// a few thousand coordinates takes tens of seconds, which a signal had waited for).
pub fn modes_until(k: &DMatrix<f64>, m: &DMatrix<f64>, cancel: Option<&AtomicBool>) -> Result<Vec<Mode>, EigenError> {
    if cancel.is_none() {
        return modes(k, m);
    }
    let (k, m) = (k.clone(), m.clone());
    match interruptible(cancel, move || modes(&k, &m)) {
        Ok(result) => result,
        Err(Halted::Interrupted) => Err(EigenError::Interrupted),
        Err(Halted::Panicked) => panic!("the eigenproblem's thread panicked"),
    }
}

/// The modes of K v = lambda M v, lambda ascending.
pub fn modes(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Result<Vec<Mode>, EigenError> {
    let n = k.nrows();
    if k.ncols() != n || m.nrows() != n || m.ncols() != n {
        return Err(EigenError::Shape(k.nrows(), k.ncols(), m.nrows(), m.ncols()));
    }
    if !k.iter().chain(m.iter()).all(|x| x.is_finite()) {
        return Err(EigenError::NotFinite);
    }
    let l = m.clone().cholesky().ok_or(EigenError::MassNotPositiveDefinite)?.l();
    // A = L^-1 K L^-T, symmetrised against round-off.
    let x = l.solve_lower_triangular(k).ok_or(EigenError::MassNotPositiveDefinite)?;
    let a = l.solve_lower_triangular(&x.transpose()).ok_or(EigenError::MassNotPositiveDefinite)?;
    let a = (&a + a.transpose()) * 0.5;
    let eigen = SymmetricEigen::new(a);
    let lt = l.transpose();
    let mut out: Vec<Mode> = (0..n)
        .map(|i| {
            let y = eigen.eigenvectors.column(i).into_owned();
            let shape = lt.solve_upper_triangular(&y).unwrap_or(y);
            Mode { omega_squared: eigen.eigenvalues[i], shape }
        })
        .collect();
    out.sort_by(|a, b| a.omega_squared.total_cmp(&b.omega_squared));
    Ok(out)
}

/// Whether a symmetric matrix is positive definite (its Cholesky factorization exists).
pub fn is_positive_definite(m: &DMatrix<f64>) -> bool {
    m.iter().all(|x| x.is_finite()) && m.clone().cholesky().is_some()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_masses_three_springs_have_the_textbook_frequencies() {
        // m = 2 kg each, springs k = 50 N/m wall-mass-mass-wall: omega^2 = k/m and 3k/m.
        let k = DMatrix::from_row_slice(2, 2, &[100.0, -50.0, -50.0, 100.0]);
        let m = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 2.0]);
        let modes = modes(&k, &m).unwrap();
        assert!((modes[0].omega_squared - 25.0).abs() < 1e-12);
        assert!((modes[1].omega_squared - 75.0).abs() < 1e-12);
        // Mass-normalised: v^T M v = 1.
        let v = &modes[0].shape;
        assert!(((v.transpose() * &m * v)[0] - 1.0).abs() < 1e-14);
    }

    #[test]
    fn a_raised_cancel_flag_stops_the_eigenproblem() {
        let k = DMatrix::from_row_slice(2, 2, &[100.0, -50.0, -50.0, 100.0]);
        let m = DMatrix::identity(2, 2);
        let raised = AtomicBool::new(true);
        assert_eq!(modes_until(&k, &m, Some(&raised)).unwrap_err(), EigenError::Interrupted);
        let lowered = AtomicBool::new(false);
        let solved = modes_until(&k, &m, Some(&lowered)).unwrap();
        assert!((solved[0].omega_squared - 50.0).abs() < 1e-12);
    }

    #[test]
    fn a_mass_matrix_that_is_not_positive_definite_is_refused() {
        let k = DMatrix::identity(2, 2);
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
        assert_eq!(modes(&k, &m).unwrap_err(), EigenError::MassNotPositiveDefinite);
    }
}
