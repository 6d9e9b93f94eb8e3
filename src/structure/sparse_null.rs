//! The null spaces of an equilibrium matrix too large for the dense SVD (`equilibrium.rs`): a
//! 1000-strut prism's A is 5994 by 4999, whose dense SVD would take minutes and hundreds of MB.
//!
//! The null space of a sparse A (m by n) is that of its Gram matrix G = A^T A (n by n, as
//! sparse as the members' sharing of nodes). Its eigenvectors of least eigenvalue are found by
//! shift-invert subspace iteration: the sparse Cholesky factor of G + sigma 1 (unknowns in
//! reverse Cuthill-McKee order, `crate::ordering`), sigma = `SHIFT_RATIO` of the largest
//! eigenvalue, applied to a block of vectors, orthonormalised and rotated by Rayleigh-Ritz, until
//! the lowest of them converge. Each vector's singular value is read as |A x| (not from G,
//! whose eigenvalues square it and lose the small ones to round-off: |A x| of a null vector is
//! the round-off of A, 1e-16 of its largest singular value): those below
//! [`super::equilibrium::RANK_TOLERANCE`] of the largest are the null space. While the whole
//! converged block is null the block doubles (up to [`MAX_BLOCK`]), so the count is that of the
//! matrix, with the smallest nonzero singular value found beside it.

use super::equilibrium::{EquilibriumError, RANK_TOLERANCE};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::{CooMatrix, CscMatrix};

/// The shift of the factorization, a fraction of G's largest eigenvalue: G + sigma 1 is then
/// factored at a condition of 1e10, well within double precision; eigenvalues of G below the
/// shift (singular values of A below 1e-5 of the largest) converge more slowly, not wrongly,
/// since each is judged by |A x|.
const SHIFT_RATIO: f64 = 1e-10;
/// The first block of vectors; it doubles while the converged ones are all null.
const FIRST_BLOCK: usize = 16;
/// The largest block (a null space larger than this less `GUARD` is refused).
pub const MAX_BLOCK: usize = 512;
/// Vectors of the block beyond those whose convergence is required (they speed it).
const GUARD: usize = 4;
/// The largest null space computed.
pub const MAX_NULL: usize = MAX_BLOCK - GUARD;
/// Iterations of the subspace iteration before it is given up.
const MAX_ITERATIONS: usize = 200;
/// Power iterations for the largest eigenvalue of G.
const POWER_ITERATIONS: usize = 60;
/// A Ritz pair has converged when its residual |G x - theta x| is below this fraction of G's
/// largest eigenvalue.
const RESIDUAL_RATIO: f64 = 1e-12;

/// The null space of a sparse matrix and what bounds it.
pub struct SparseNull {
    /// An orthonormal basis of the null space.
    pub basis: Vec<DVector<f64>>,
    /// The largest singular value (power iteration on A^T A).
    pub largest: f64,
    /// The smallest singular value above the tolerance, where the block reached one.
    pub smallest_nonzero: Option<f64>,
}

/// The null space of `a`, its unknowns coupled as `neighbours` (the columns of `a` that share a
/// row).
pub fn null_space(a: &CscMatrix<f64>, neighbours: &[Vec<usize>]) -> Result<SparseNull, EquilibriumError> {
    let n = a.ncols();
    let position = crate::ordering::reverse_cuthill_mckee(neighbours);
    let gram = permuted(&(&a.transpose() * a), &position);
    let lambda_max = largest_eigenvalue(&gram);
    let largest = lambda_max.sqrt();
    let factor = shifted_factor(&gram, SHIFT_RATIO * lambda_max)?;
    let mut block = FIRST_BLOCK.min(n);
    loop {
        let (vectors, converged) = lowest_vectors(&gram, &factor, block, lambda_max)?;
        let singular: Vec<f64> =
            (0..converged).map(|c| (a * &unpermuted(&vectors.column(c).into_owned(), &position)).norm()).collect();
        let null = singular.iter().filter(|&&s| s <= RANK_TOLERANCE * largest).count();
        if null < converged || block == n {
            let basis = (0..null).map(|c| unpermuted(&vectors.column(c).into_owned(), &position)).collect();
            let smallest_nonzero = singular.iter().copied().filter(|&s| s > RANK_TOLERANCE * largest).reduce(f64::min);
            return Ok(SparseNull { basis: orthonormal_basis(basis), largest, smallest_nonzero });
        }
        if block >= MAX_BLOCK {
            return Err(EquilibriumError(format!(
                "its equilibrium matrix has more than {MAX_NULL} null vectors: the sparse analysis computes at most that many"
            )));
        }
        block = (2 * block).min(n).min(MAX_BLOCK);
    }
}

/// `g` with its rows and columns moved to `position`.
fn permuted(g: &CscMatrix<f64>, position: &[usize]) -> CscMatrix<f64> {
    let mut coo = CooMatrix::new(g.nrows(), g.ncols());
    for (r, c, v) in g.triplet_iter() {
        coo.push(position[r], position[c], *v);
    }
    CscMatrix::from(&coo)
}

/// The vector of unknowns in their own order from `x` in the factor's.
fn unpermuted(x: &DVector<f64>, position: &[usize]) -> DVector<f64> {
    DVector::from_fn(x.len(), |i, _| x[position[i]])
}

/// The largest eigenvalue of the symmetric positive semi-definite `g` (power iteration from a
/// fixed start, then 10 % above, as an upper scale).
fn largest_eigenvalue(g: &CscMatrix<f64>) -> f64 {
    let mut x = DVector::from_fn(g.nrows(), |i, _| 1.0 + (i % 7) as f64 * 0.1);
    let mut lambda = 0.0;
    for _ in 0..POWER_ITERATIONS {
        x /= x.norm();
        let y = g * &x;
        lambda = x.dot(&y);
        x = y;
    }
    lambda.max(f64::MIN_POSITIVE)
}

/// The Cholesky factor of g + sigma 1.
fn shifted_factor(g: &CscMatrix<f64>, sigma: f64) -> Result<CscCholesky<f64>, EquilibriumError> {
    let mut coo = CooMatrix::new(g.nrows(), g.ncols());
    for (r, c, v) in g.triplet_iter() {
        coo.push(r, c, *v);
    }
    for i in 0..g.nrows() {
        coo.push(i, i, sigma);
    }
    CscCholesky::factor(&CscMatrix::from(&coo))
        .map_err(|e| EquilibriumError(format!("the sparse factorization of its Gram matrix failed: {e:?}")))
}

/// The lowest `block - GUARD` (all, for a block of the whole size) eigenvectors of `g`, as
/// columns in ascending order, and how many converged.
fn lowest_vectors(
    g: &CscMatrix<f64>,
    factor: &CscCholesky<f64>,
    block: usize,
    lambda_max: f64,
) -> Result<(DMatrix<f64>, usize), EquilibriumError> {
    let n = g.nrows();
    let want = if block == n { n } else { block - GUARD.min(block - 1) };
    let mut x = DMatrix::from_fn(n, block, |r, c| ((r * 7919 + c * 104_729) % 1000) as f64 / 1000.0 - 0.5);
    for _ in 0..MAX_ITERATIONS {
        let q = factor.solve(&x).qr().q();
        let gq = g * &q;
        let h = q.transpose() * &gq;
        let eig = SymmetricEigen::new(0.5 * (&h + h.transpose()));
        let mut order: Vec<usize> = (0..block).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let s = DMatrix::from_fn(block, block, |r, c| eig.eigenvectors[(r, order[c])]);
        x = &q * &s;
        let gx = gq * &s;
        let residual = |c: usize| (gx.column(c) - x.column(c) * eig.eigenvalues[order[c]]).norm();
        if (0..want).all(|c| residual(c) <= RESIDUAL_RATIO * lambda_max) {
            return Ok((x, want));
        }
    }
    Err(EquilibriumError(format!("the sparse null-space iteration did not converge in {MAX_ITERATIONS} iterations")))
}

/// An orthonormal basis of `vectors` (they are nearly so already: Ritz vectors).
fn orthonormal_basis(vectors: Vec<DVector<f64>>) -> Vec<DVector<f64>> {
    if vectors.is_empty() {
        return vectors;
    }
    let q = DMatrix::from_columns(&vectors).qr().q();
    q.column_iter().map(|c| c.into_owned()).collect()
}
