//! The lowest modes of a large structure of free bodies (`sim::modes` above
//! [`crate::structure::DENSE_MODAL_MAX_FREE_BODIES`] free bodies): shift-invert subspace
//! iteration with Rayleigh-Ritz on the sparse stiffness the relaxation assembles.
//!
//! The generalized problem H x = omega^2 M x becomes the standard A y = omega^2 y with
//! A = L^-1 H L^-T, L the Cholesky factor of each body's 6x6 mass block (block diagonal), so A
//! keeps H's block pattern; y = L^T x. The free rigid motions the relaxation knows
//! (`rigid_groups`: a strut's spin about its axis, the turn about a held strut's line, the six
//! motions of an unanchored group) are taken out where they are null vectors of A (|A y| below
//! [`DEFLATION_RATIO`] of the largest omega^2): reported as rigid modes with their Rayleigh
//! quotients, and every iterate is kept orthogonal to them. The rest: a block of
//! `count + max(GUARD, count)` vectors, each iteration Y = (A - sigma 1)^-1 X (the sparse Cholesky of
//! `sparse.rs`, bodies in reverse Cuthill-McKee order, sigma a small negative shift lowered
//! until the factorization exists), orthonormalized, then the Rayleigh-Ritz pairs of A itself
//! in span(Y); done when each of the lowest `count` Ritz pairs has |A x - theta x| below
//! [`RESIDUAL_RATIO`] of |theta| (so |theta - omega^2| is below that fraction of it, and in
//! practice its square). Golub & Van Loan, Matrix Computations, 4th ed., sections 8.2.4 and
//! 8.7.2 (orthogonal iteration, the symmetric-definite problem); Saad, Numerical Methods for
//! Large Eigenvalue Problems, 2nd ed., section 5.2 (subspace iteration with Rayleigh-Ritz). A
//! block method finds each of a pair of (nearly) equal frequencies, which a single-vector
//! Lanczos would not.

use super::super::data::Data;
use super::super::model::Model;
use super::assemble::{Dofs, System};
use super::sparse::{csc, ordered_columns, rigid_motions, Motion};
use crate::eigen::EigenError;
use crate::sim::modes::{Lowest, ModesError};
use crate::structure::MAX_SPARSE_MODAL_COUNT;
use nalgebra::{DMatrix, DVector, Matrix6, SymmetricEigen, Vector3, Vector6};
use nalgebra_sparse::factorization::{CscCholesky, CscSymbolicCholesky};
use nalgebra_sparse::CscMatrix;
use std::sync::atomic::{AtomicBool, Ordering};

/// A known rigid motion y (unit, mass-weighted) is taken out where |A y| is below this
/// fraction of the largest omega^2: a null vector of A to round-off and the settled state's
/// residual (a strut's spin has |A y| of the residual torque over its inertia).
const DEFLATION_RATIO: f64 = 1e-9;
/// A Ritz pair (theta, x) of the lowest `count` is converged where |A x - theta x| is below
/// this fraction of |theta| (or of the largest omega^2 times [`ZERO_FLOOR_RATIO`], for a mode
/// at zero): then |theta - omega^2| <= |A x - theta x| is too.
const RESIDUAL_RATIO: f64 = 1e-9;
/// The residual's floor for modes at zero, as a fraction of the largest omega^2 (the
/// round-off of A x).
const ZERO_FLOOR_RATIO: f64 = 1e-13;
/// The shift sigma, first at minus this fraction of the largest omega^2 (below every
/// non-negative mode, above the round-off of the rigid ones); ten times further down each time
/// A - sigma 1 has no Cholesky factorization (an unstable direction).
const SHIFT_RATIO: f64 = 1e-10;
/// Vectors in the block beyond the `count` wanted, at least (as many as `count` above it): the
/// convergence of mode j goes as ((omega_j^2 - sigma) / (omega_{block + 1}^2 - sigma))^2 per
/// iteration. Measured on the 1000-strut bench prism: the lowest 200 took 29.6 s with 20
/// guard vectors, 14.7 s with 200.
const GUARD: usize = 20;
/// Iterations of the subspace iteration before it gives up.
const MAX_ITERATIONS: usize = 400;
/// Lanczos steps for the largest omega^2 (the rigid-mode threshold is a fraction of it: a few
/// digits suffice, and the extreme Ritz value has them after a few tens of steps).
const LANCZOS_STEPS: usize = 60;

/// The lowest modes: omega^2 ascending, each shape x (six coordinates per free body, in block
/// order) mass-normalised (x^T M x = 1); the known rigid motions that were taken out among
/// them.
pub(in crate::sim) struct LowestModes {
    pub(in crate::sim) modes: Vec<(f64, DVector<f64>)>,
    /// The largest omega^2 (Lanczos' estimate) [rad^2/s^2].
    pub(in crate::sim) largest: f64,
}

/// The mass-weighted stiffness A in factor order and what maps it back.
pub(super) struct Weighted {
    pub(super) matrix: CscMatrix<f64>,
    diagonal: Vec<usize>,
    /// Factor position of each block.
    pub(super) position: Vec<usize>,
    /// L^-1 of each block's mass, in block order.
    pub(super) inverse_factor: Vec<Matrix6<f64>>,
}

impl Data {
    /// The lowest modes beyond the known rigid motions, as many as `wanted` asks, and those
    /// (module docs). `mass`: each free body's 6x6 mass block, in the relaxation's block order.
    pub(in crate::sim) fn lowest_modes(
        &self,
        m: &Model,
        mass: &[Matrix6<f64>],
        turning: &[bool],
        wanted: Lowest,
        cancel: Option<&AtomicBool>,
    ) -> Result<LowestModes, ModesError> {
        let dofs = self.relaxation_dofs(m);
        let system = self.relaxation_system(m, &dofs);
        let weighted = weighted_stiffness(&dofs, &system, mass)?;
        let n = weighted.matrix.nrows();
        let largest = largest_magnitude(&weighted.matrix, cancel)?;
        let factors = weighted.factors();
        let weigh = |i: usize, u: &Vector3<f64>, w: &Vector3<f64>| {
            factors[i].transpose() * Vector6::new(u.x, u.y, u.z, w.x, w.y, w.z)
        };
        let motions = rigid_motions(&dofs, m.length_scale_m, &weighted.position, &self.rigid_groups(m, &dofs), &weigh);
        // A point mass's turns are taken out as rigid motions and not reported (`modes.rs`).
        let mut turns_at = vec![false; n];
        for (i, &p) in weighted.position.iter().enumerate() {
            for r in 0..6 {
                turns_at[6 * p + r] = turning[6 * i + r];
            }
        }
        let mut rigid: Vec<Motion> = Vec::new();
        let mut out = Vec::new();
        let mut product = SparseProduct::new(n);
        for motion in motions {
            let (norm, quotient) = product.norm_and_quotient(&weighted.matrix, &motion);
            if norm <= DEFLATION_RATIO * largest {
                if !motion.0.iter().all(|&(r, _)| turns_at[r]) {
                    let mut y = DVector::zeros(n);
                    for &(r, x) in &motion.0 {
                        y[r] = x;
                    }
                    out.push((quotient, y));
                }
                rigid.push(motion);
            }
        }
        let through = wanted.through.map_or(0, |i| (i + 1).saturating_sub(out.len()));
        let want = wanted.count.max(through).min(n - rigid.len());
        if want > MAX_SPARSE_MODAL_COUNT {
            let through = wanted.through.map_or(want, |i| i + 1);
            return Err(ModesError::TooManyWanted { wanted: want, rigid: out.len(), through });
        }
        let (ritz, _) = subspace_iteration(&weighted, &rigid, want, largest, cancel)?;
        out.extend(ritz);
        let mut modes: Vec<(f64, DVector<f64>)> = out.into_iter().map(|(l, y)| (l, weighted.shape(&y))).collect();
        modes.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(LowestModes { modes, largest })
    }
}

impl Weighted {
    /// L of each block's mass, in block order (the inverse of `inverse_factor`).
    pub(super) fn factors(&self) -> Vec<Matrix6<f64>> {
        self.inverse_factor.iter().map(|l| l.try_inverse().expect("a Cholesky factor's inverse")).collect()
    }

    /// x = L^-T y in block order.
    pub(super) fn shape(&self, y: &DVector<f64>) -> DVector<f64> {
        let mut x = DVector::zeros(y.len());
        for (i, &p) in self.position.iter().enumerate() {
            let block = self.inverse_factor[i].transpose() * y.fixed_rows::<6>(6 * p);
            x.fixed_rows_mut::<6>(6 * i).copy_from(&block);
        }
        x
    }
}

/// A y for a sparse y (a rigid motion: a strut's spin has six entries), in a scratch vector
/// whose touched rows are cleared after each product: the deflation test costs the columns of
/// y's entries, not a product with a dense vector per motion (about one per body).
struct SparseProduct {
    scratch: Vec<f64>,
    touched: Vec<usize>,
}

impl SparseProduct {
    fn new(n: usize) -> Self {
        SparseProduct { scratch: vec![0.0; n], touched: Vec::new() }
    }

    /// |A y| and y^T A y.
    fn norm_and_quotient(&mut self, a: &CscMatrix<f64>, y: &Motion) -> (f64, f64) {
        for &(c, x) in &y.0 {
            let column = a.col(c);
            for (&r, &v) in column.row_indices().iter().zip(column.values()) {
                if self.scratch[r] == 0.0 {
                    self.touched.push(r);
                }
                self.scratch[r] += v * x;
            }
        }
        let quotient: f64 = y.0.iter().map(|&(r, x)| x * self.scratch[r]).sum();
        let mut squared = 0.0;
        self.touched.sort_unstable();
        self.touched.dedup();
        for &r in &self.touched {
            squared += self.scratch[r] * self.scratch[r];
            self.scratch[r] = 0.0;
        }
        self.touched.clear();
        (squared.sqrt(), quotient)
    }
}

/// A = L^-1 H L^-T in factor order, symmetrized as `System::dense` is.
pub(super) fn weighted_stiffness(dofs: &Dofs, system: &System, mass: &[Matrix6<f64>]) -> Result<Weighted, EigenError> {
    let n = dofs.blocks();
    let mut inverse_factor = Vec::with_capacity(n);
    for block in mass {
        let l = block.cholesky().ok_or(EigenError::MassNotPositiveDefinite)?.l();
        inverse_factor.push(l.try_inverse().ok_or(EigenError::MassNotPositiveDefinite)?);
    }
    let (position, columns) = ordered_columns(system, n, |i, k, block| {
        if !block.iter().all(|x| x.is_finite()) {
            return Err(EigenError::NotFinite);
        }
        Ok(inverse_factor[i] * block * inverse_factor[k].transpose() * 0.5)
    })?;
    let (matrix, diagonal) = csc(&columns);
    Ok(Weighted { matrix, diagonal, position, inverse_factor })
}

/// Raised `cancel`: [`EigenError::Interrupted`].
fn check(cancel: Option<&AtomicBool>) -> Result<(), EigenError> {
    match cancel {
        Some(c) if c.load(Ordering::SeqCst) => Err(EigenError::Interrupted),
        _ => Ok(()),
    }
}

/// A deterministic start vector: a fixed pseudo-random sequence (an LCG), entries in [-1, 1).
fn start_vector(n: usize, seed: u64) -> DVector<f64> {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    DVector::from_fn(n, |_, _| {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    })
}

/// The largest |omega^2|: the extreme Ritz values of [`LANCZOS_STEPS`] Lanczos steps on A
/// (fully reorthogonalized), at least the largest |diagonal entry|.
pub(super) fn largest_magnitude(a: &CscMatrix<f64>, cancel: Option<&AtomicBool>) -> Result<f64, EigenError> {
    let n = a.nrows();
    let steps = LANCZOS_STEPS.min(n);
    let mut basis: Vec<DVector<f64>> = vec![start_vector(n, 1).normalize()];
    let (mut alpha, mut beta) = (Vec::new(), Vec::new());
    for j in 0..steps {
        check(cancel)?;
        let mut w = a * &basis[j];
        alpha.push(basis[j].dot(&w));
        for _ in 0..2 {
            for v in &basis {
                w.axpy(-v.dot(&w), v, 1.0);
            }
        }
        let norm = w.norm();
        if j + 1 == steps || norm <= f64::EPSILON * alpha.iter().fold(0.0_f64, |m, x| m.max(x.abs())) {
            break;
        }
        beta.push(norm);
        basis.push(w / norm);
    }
    let k = alpha.len();
    let t = DMatrix::from_fn(k, k, |r, c| match r.abs_diff(c) {
        0 => alpha[r],
        1 => beta[r.min(c)],
        _ => 0.0,
    });
    let ritz = SymmetricEigen::new(t).eigenvalues.amax();
    let diagonal = (0..n).map(|c| a.get_entry(c, c).map_or(0.0, |e| e.into_value().abs())).fold(0.0, f64::max);
    Ok(ritz.max(diagonal))
}

/// Removes from each column of `x` its components along the orthonormal `rigid` (each by its
/// nonzero entries: a strut's spin has six).
fn deflate(x: &mut DMatrix<f64>, rigid: &[Motion]) {
    for mut column in x.column_iter_mut() {
        for r in rigid {
            let along: f64 = r.0.iter().map(|&(i, v)| v * column[i]).sum();
            for &(i, v) in &r.0 {
                column[i] -= along * v;
            }
        }
    }
}

/// The Cholesky factor of A - sigma 1, sigma lowered until it exists.
pub(super) fn shifted_factor(w: &Weighted, largest: f64) -> Result<CscCholesky<f64>, EigenError> {
    let symbolic = CscSymbolicCholesky::factor(w.matrix.pattern().clone());
    let mut sigma = -SHIFT_RATIO * largest.max(f64::MIN_POSITIVE);
    for _ in 0..40 {
        let mut values = w.matrix.values().to_vec();
        for &d in &w.diagonal {
            values[d] -= sigma;
        }
        if let Ok(factor) = CscCholesky::factor_numerical(symbolic.clone(), &values) {
            return Ok(factor);
        }
        sigma *= 10.0;
    }
    Err(EigenError::NotFinite)
}

/// Eigenpairs (omega^2, mass-weighted vector y).
type Pairs = Vec<(f64, DVector<f64>)>;

/// The lowest `want` eigenpairs of A orthogonal to `rigid` (module docs), with the
/// iterations taken.
fn subspace_iteration(
    w: &Weighted,
    rigid: &[Motion],
    want: usize,
    largest: f64,
    cancel: Option<&AtomicBool>,
) -> Result<(Pairs, usize), EigenError> {
    let n = w.matrix.nrows();
    let block = (want + GUARD.max(want)).min(n - rigid.len());
    if want == 0 || block == 0 {
        return Ok((Vec::new(), 0));
    }
    let factor = shifted_factor(w, largest)?;
    let mut x = DMatrix::from_fn(n, block, |_, _| 0.0);
    for c in 0..block {
        x.set_column(c, &start_vector(n, 2 + c as u64));
    }
    for iteration in 1..=MAX_ITERATIONS {
        check(cancel)?;
        deflate(&mut x, rigid);
        factor.solve_mut(&mut x);
        deflate(&mut x, rigid);
        let q = orthonormal(x);
        let aq = &w.matrix * &q;
        let g = q.transpose() * &aq;
        let eig = SymmetricEigen::new(0.5 * (&g + g.transpose()));
        let mut order: Vec<usize> = (0..block).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let s = DMatrix::from_fn(block, block, |r, c| eig.eigenvectors[(r, order[c])]);
        let theta: Vec<f64> = order.iter().map(|&c| eig.eigenvalues[c]).collect();
        x = &q * &s;
        let ax = aq * &s;
        let converged = (0..want).all(|j| {
            let residual = (ax.column(j) - x.column(j) * theta[j]).norm();
            residual <= RESIDUAL_RATIO * theta[j].abs() + ZERO_FLOOR_RATIO * largest
        });
        if converged {
            let pairs = (0..want).map(|j| (theta[j], x.column(j).into_owned())).collect();
            return Ok((pairs, iteration));
        }
    }
    Err(EigenError::NotConverged(MAX_ITERATIONS))
}

/// An orthonormal basis of the columns of `x` (Householder QR).
fn orthonormal(x: DMatrix<f64>) -> DMatrix<f64> {
    x.qr().q()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The free-free chain: A = tridiag(-1, 2, -1) with 1 at both ends of the diagonal (n unit
    /// masses, unit springs, no support), eigenvalues 2 - 2 cos(k pi / n) = 4 sin^2(k pi / 2n),
    /// k = 0 .. n - 1, the zero one along (1, ..., 1). With that vector taken out, the lowest
    /// ten found are k = 1 .. 10 within 1e-10 relative (the lowest, 2.7e-5, is 7e-6 of the
    /// largest: round-off of A x over it, 1.5e-11), their vectors orthogonal to it, and the shift-invert
    /// iteration stops at a raised cancel flag.
    #[test]
    fn the_lowest_modes_of_a_free_chain_are_the_closed_form() {
        let n = 600;
        let mut columns: Vec<std::collections::BTreeMap<usize, Matrix6<f64>>> = vec![Default::default(); n / 6];
        let mut entry = |r: usize, c: usize, x: f64| {
            let block = columns[c / 6].entry(r / 6).or_insert_with(Matrix6::zeros);
            block[(r % 6, c % 6)] += x;
        };
        for i in 0..n {
            entry(i, i, if i == 0 || i == n - 1 { 1.0 } else { 2.0 });
            if i + 1 < n {
                entry(i, i + 1, -1.0);
                entry(i + 1, i, -1.0);
            }
        }
        let (matrix, diagonal) = csc(&columns);
        let weighted = Weighted {
            matrix,
            diagonal,
            position: (0..n / 6).collect(),
            inverse_factor: vec![Matrix6::identity(); n / 6],
        };
        let largest = largest_magnitude(&weighted.matrix, None).unwrap();
        assert!((largest - 4.0).abs() <= 1e-3, "largest {largest}");
        let rigid = vec![Motion((0..n).map(|i| (i, 1.0 / (n as f64).sqrt())).collect())];
        let (pairs, _) = subspace_iteration(&weighted, &rigid, 10, largest, None).unwrap();
        for (k, (theta, x)) in pairs.iter().enumerate() {
            let exact = (2.0 * ((k + 1) as f64 * std::f64::consts::PI / (2 * n) as f64).sin()).powi(2);
            assert!(((theta - exact) / exact).abs() <= 1e-10, "mode {}: {theta} against {exact}", k + 1);
            assert!(x.sum().abs() <= 1e-12 * (n as f64).sqrt(), "mode {} has a rigid component", k + 1);
        }
        let raised = AtomicBool::new(true);
        let stopped = subspace_iteration(&weighted, &rigid, 10, largest, Some(&raised));
        assert_eq!(stopped.unwrap_err(), EigenError::Interrupted);
    }
}
