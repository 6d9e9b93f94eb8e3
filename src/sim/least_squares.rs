//! Minimum-norm least squares for the projection's Gauss-Newton steps and the fit of
//! loop-closure reactions: a Householder QR when the matrix has full rank (the usual case),
//! an SVD with a rank cut otherwise.
//!
//! Measured on mohr2011's static workspace (15 x 15 closure Jacobians and reaction fits,
//! every step): the SVDs took 13 % of all instructions of a settle, the QR path a small
//! fraction of that, with the same results to round-off (tests unchanged).

use nalgebra::{DMatrix, DVector};
use std::cmp::Ordering;

/// The QR path is taken when every diagonal entry of R is above this fraction of the
/// largest: a proxy for a condition number below 1e8 (QR is backward stable, so the solution
/// is then accurate to about 1e-8 relative at worst, to round-off in the usual case).
const QR_RELATIVE_PIVOT: f64 = 1e-8;

/// The minimum-norm least-squares solution x of `a x = b`. Full rank: by QR (of `a` when it
/// has at least as many rows as columns, of `a^T` otherwise). Rank deficient or badly
/// conditioned: by SVD, singular values below `svd_relative_tolerance` of the largest dropped
/// (redundant rows or columns). None when the SVD fails.
pub(super) fn min_norm_solve(a: &DMatrix<f64>, b: &DVector<f64>, svd_relative_tolerance: f64) -> Option<DVector<f64>> {
    let tall = a.nrows() >= a.ncols();
    let qr = if tall { a.clone().qr() } else { a.transpose().qr() };
    let r = qr.r();
    let d = r.diagonal();
    let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), x| (lo.min(x.abs()), hi.max(x.abs())));
    if !d.is_empty() && lo > QR_RELATIVE_PIVOT * hi {
        if tall {
            // a = Q R: x = R^-1 Q^T b (the least-squares solution, unique at full column rank).
            let mut qtb = b.clone();
            qr.q_tr_mul(&mut qtb);
            return r.solve_upper_triangular(&qtb.rows(0, r.nrows()).into_owned());
        }
        // a^T = Q R, so a a^T = R^T R: x = a^T (R^T R)^-1 b, the minimum-norm solution at full
        // row rank (Q is never formed).
        let y = r.transpose().solve_lower_triangular(b)?;
        return r.solve_upper_triangular(&y).map(|z| a.transpose() * z);
    }
    let svd = a.clone().svd(true, true);
    let cut = svd_relative_tolerance * svd.singular_values.max();
    svd.solve(b, cut).ok()
}

/// A sparse matrix by rows (compressed: every row's (column, value) entries in one vector,
/// row i at `entries[start[i]..start[i + 1]]`; a vector per row was a third of the allocations
/// of a 5-X chain's settle).
#[derive(Clone, Debug)]
pub(crate) struct SparseRows {
    pub(crate) ncols: usize,
    start: Vec<usize>,
    entries: Vec<(usize, f64)>,
}

impl SparseRows {
    /// The matrix of `nrows` x `ncols` with these (row, column, value) entries; entries at the
    /// same place add up (in the order given).
    pub(crate) fn new(nrows: usize, ncols: usize, entries: &[(usize, usize, f64)]) -> Self {
        let mut m = Self::grouped(nrows, ncols, entries.iter().map(|&(r, c, x)| (r, (c, x))));
        let mut kept = 0;
        let mut row_start = 0;
        for r in 0..nrows {
            let (from, to) = (row_start, m.start[r + 1]);
            row_start = to;
            m.start[r] = kept;
            let row = &mut m.entries[from..to];
            row.sort_by_key(|e| e.0);
            for k in from..to {
                let e = m.entries[k];
                if kept > m.start[r] && m.entries[kept - 1].0 == e.0 {
                    m.entries[kept - 1].1 += e.1;
                } else {
                    m.entries[kept] = e;
                    kept += 1;
                }
            }
        }
        m.start[nrows] = kept;
        m.entries.truncate(kept);
        m
    }

    /// The matrix whose row k holds the items keyed k, in the order given.
    fn grouped(nrows: usize, ncols: usize, items: impl Iterator<Item = (usize, (usize, f64))> + Clone) -> Self {
        let mut start = vec![0_usize; nrows + 1];
        for (k, _) in items.clone() {
            start[k + 1] += 1;
        }
        for k in 0..nrows {
            start[k + 1] += start[k];
        }
        let mut next = start.clone();
        let mut entries = vec![(0, 0.0); start[nrows]];
        for (k, x) in items {
            entries[next[k]] = x;
            next[k] += 1;
        }
        SparseRows { ncols, start, entries }
    }

    pub(crate) fn nrows(&self) -> usize {
        self.start.len() - 1
    }

    /// Row i's (column, value) entries, columns in order.
    fn row(&self, i: usize) -> &[(usize, f64)] {
        &self.entries[self.start[i]..self.start[i + 1]]
    }

    fn rows(&self) -> impl Iterator<Item = &[(usize, f64)]> + Clone + '_ {
        (0..self.nrows()).map(|i| self.row(i))
    }

    /// A x.
    pub(crate) fn mul(&self, x: &DVector<f64>) -> DVector<f64> {
        DVector::from_iterator(self.nrows(), self.rows().map(|row| row.iter().map(|&(c, v)| v * x[c]).sum()))
    }

    /// A^T y.
    fn tr_mul(&self, y: &DVector<f64>) -> DVector<f64> {
        let mut x = DVector::zeros(self.ncols);
        for (row, &yr) in self.rows().zip(y.iter()) {
            for &(c, v) in row {
                x[c] += v * yr;
            }
        }
        x
    }

    /// A^T: each column's (row, value) entries, rows in order.
    fn transpose(&self) -> SparseRows {
        let entries = self.rows().enumerate().flat_map(|(r, row)| row.iter().map(move |&(c, v)| (c, (r, v))));
        Self::grouped(self.ncols, self.nrows(), entries)
    }

    pub(super) fn to_dense(&self) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.nrows(), self.ncols);
        for (r, row) in self.rows().enumerate() {
            for &(c, v) in row {
                m[(r, c)] += v;
            }
        }
        m
    }
}

/// The Cholesky factor L of the Gram matrix M M^T of a sparse M, in band storage: rows i and
/// k of M that share a column couple, and the band is the largest |i - k| among them (a chain
/// whose members are listed in order keeps a band of about one link's rows), so factorizing
/// costs rows x band^2 where a dense factorization costs rows^3. Within the band only each
/// row's profile is worked on: L[i][k] is zero left of the first row that row i couples with
/// (no fill reaches there), and those zeros are left out of every sum.
struct BandCholesky {
    band: usize,
    /// L[i][i - d] at `i * (band + 1) + d`, d = 0 ..= band.
    l: Vec<f64>,
    /// Row i's first coupled row: L[i][k] = 0 for k < `first[i]`.
    first: Vec<usize>,
    /// Column k's last row below the diagonal that is not zero (k itself when none).
    last: Vec<usize>,
}

impl BandCholesky {
    /// The factor of M M^T + shift x its largest diagonal entry; None when that is not
    /// positive definite (a redundant row of M, unshifted).
    fn of_gram(m: &SparseRows, shift: f64) -> Option<Self> {
        let n = m.nrows();
        let by_column = m.transpose();
        let band = by_column.rows().map(|rs| rs.last().map_or(0, |l| l.0) - rs.first().map_or(0, |f| f.0)).max()?;
        let w = band + 1;
        let mut l = vec![0.0; n * w];
        let mut first: Vec<usize> = (0..n).collect();
        for rs in by_column.rows() {
            for (a, &(i, vi)) in rs.iter().enumerate() {
                first[i] = first[i].min(rs[0].0);
                let row = &mut l[i * w..i * w + w];
                for &(k, vk) in &rs[..=a] {
                    row[i - k] += vi * vk;
                }
            }
        }
        let mut last: Vec<usize> = (0..n).collect();
        for (i, &f) in first.iter().enumerate() {
            for x in &mut last[f..i] {
                *x = (*x).max(i);
            }
        }
        let largest = (0..n).map(|i| l[i * w]).fold(0.0_f64, f64::max);
        for i in 0..n {
            l[i * w] += shift * largest;
        }
        // Row by row (Cholesky-Banachiewicz): row i holds L[i][i - b] at b = 0 ..= band, and
        // L[i][j] takes the dot of rows i and j over the columns left of j where both can be
        // nonzero, k = j - 1 down to the later of their first columns.
        for i in 0..n {
            let fi = first[i];
            let (above, rest) = l.split_at_mut(i * w);
            let row_i = &mut rest[..w];
            for j in fi..i {
                let (off, reach) = (i - j, j - fi.max(first[j]));
                let row_j = &above[j * w..j * w + w];
                let dot: f64 = row_i[off + 1..=off + reach].iter().zip(&row_j[1..=reach]).map(|(a, b)| a * b).sum();
                row_i[off] = (row_i[off] - dot) / row_j[0];
            }
            let d = row_i[0] - row_i[1..=i - fi].iter().map(|x| x * x).sum::<f64>();
            // Unordered (a NaN) counts as a failed pivot.
            if d.partial_cmp(&(PIVOT_FLOOR * largest)).is_none_or(Ordering::is_le) {
                return None;
            }
            row_i[0] = d.sqrt();
        }
        Some(BandCholesky { band, l, first, last })
    }

    /// (M M^T)^-1 b.
    fn solve(&self, b: &DVector<f64>) -> DVector<f64> {
        let (n, w) = (b.len(), self.band + 1);
        let l = &self.l[..n * w];
        let mut y: Vec<f64> = b.iter().copied().collect();
        // Forward: L y = b, row i's band L[i][i - d] (d = 1 ..= band) against y[i - d].
        for i in 0..n {
            let row = &l[i * w..i * w + w];
            let reach = i - self.first[i];
            let dot: f64 = row[1..=reach].iter().zip(y[i - reach..i].iter().rev()).map(|(a, b)| a * b).sum();
            y[i] = (y[i] - dot) / row[0];
        }
        // Backward: L^T x = y, column i of L below the diagonal is L[i + d][d].
        for i in (0..n).rev() {
            let reach = self.last[i] - i;
            let dot: f64 = (1..=reach).map(|d| l[(i + d) * w + d] * y[i + d]).sum();
            y[i] = (y[i] - dot) / l[i * w];
        }
        DVector::from_vec(y)
    }
}

/// A pivot of the band Cholesky below this fraction of the Gram matrix's largest diagonal
/// entry means a redundant row (the factorization is refused): pivots are squares of singular
/// values, so this is a condition number of about 1e7 of M.
const PIVOT_FLOOR: f64 = 1e-14;

/// Rounds of iterative refinement after the normal equations' first solution: each solves the
/// normal equations again for what the last solution leaves of `a x = b`, which takes back
/// the accuracy that forming the normal matrix loses (its condition is the square of a's).
const REFINEMENT_ROUNDS: usize = 2;

/// Refinement stops once what a solution leaves of `a x = b` is below this fraction of `b`:
/// the round-off of forming the residual, so a further round changes nothing.
const REFINED_FRACTION: f64 = 1e-15;

/// A sparse `a` ready to give minimum-norm least-squares solutions of `a x = b` at full rank:
/// the band Cholesky factor of its normal matrix (a a^T when `a` has fewer rows than columns,
/// x = a^T y; a^T a otherwise), each solve followed by at most [`REFINEMENT_ROUNDS`] of
/// refinement (fewer once the residual is round-off, [`REFINED_FRACTION`]).
pub(crate) struct SparseLeastSquares {
    a: SparseRows,
    /// a^T when `a` is tall (its normal matrix a^T a is the Gram matrix of a^T).
    at: Option<SparseRows>,
    factor: BandCholesky,
}

impl SparseLeastSquares {
    /// `a` back when the normal matrix is not positive definite (a redundant row or column):
    /// the caller then takes the dense [`min_norm_solve`], which drops it.
    pub(crate) fn new(a: SparseRows) -> Result<Self, SparseRows> {
        let at = (a.nrows() > a.ncols).then(|| a.transpose());
        match BandCholesky::of_gram(at.as_ref().unwrap_or(&a), 0.0) {
            Some(factor) => Ok(SparseLeastSquares { a, at, factor }),
            None => Err(a),
        }
    }

    /// The regularised minimum-norm solutions x = a^T (a a^T + shift d I)^-1 b of any `a`, d
    /// the largest diagonal entry of a a^T: where `a` has dependent rows (a null space of
    /// a^T), the shift keeps the factorization positive definite and leaves out what no x
    /// reaches. `a` back when even the shifted matrix is not positive definite.
    pub(crate) fn regularised(a: SparseRows, shift: f64) -> Result<Self, SparseRows> {
        match BandCholesky::of_gram(&a, shift) {
            Some(factor) => Ok(SparseLeastSquares { a, at: None, factor }),
            None => Err(a),
        }
    }

    pub(crate) fn matrix(&self) -> &SparseRows {
        &self.a
    }

    fn solve_once(&self, r: &DVector<f64>) -> DVector<f64> {
        match &self.at {
            None => self.a.tr_mul(&self.factor.solve(r)),
            Some(at) => self.factor.solve(&at.mul(r)),
        }
    }

    /// The solution, refined.
    pub(crate) fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        self.solve_refined(b, REFINEMENT_ROUNDS)
    }

    /// The solution with `rounds` of refinement (none for a step of an iteration that
    /// corrects itself, such as the projection's Gauss-Newton steps).
    pub(crate) fn solve_refined(&self, b: &DVector<f64>, rounds: usize) -> Option<DVector<f64>> {
        let mut x = self.solve_once(b);
        let floor = REFINED_FRACTION * b.amax();
        for _ in 0..rounds {
            let r = b - self.a.mul(&x);
            if r.amax() <= floor {
                break;
            }
            x += self.solve_once(&r);
        }
        x.iter().all(|v| v.is_finite()).then_some(x)
    }
}

/// The minimum-norm least-squares solution of the sparse `a x = b` at full rank
/// ([`SparseLeastSquares`]); None at a redundant row or column.
pub(super) fn sparse_min_norm_solve(a: SparseRows, b: &DVector<f64>) -> Option<DVector<f64>> {
    SparseLeastSquares::new(a).ok()?.solve(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Full-rank square, tall (least squares) and wide (minimum norm) systems against the SVD.
    #[test]
    fn qr_path_matches_the_svd_solution_to_round_off() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, -1.0, 0.2, -0.7, 2.0]);
        let b = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let tall = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
        let bt = DVector::from_vec(vec![1.0, 2.0, 2.0, 4.0]);
        let wide = tall.transpose();
        let bw = DVector::from_vec(vec![1.0, -1.0]);
        for (a, b) in [(&a, &b), (&tall, &bt), (&wide, &bw)] {
            let x = min_norm_solve(a, b, 1e-12).expect("full rank");
            let svd = a.clone().svd(true, true).solve(b, 1e-12).expect("svd");
            assert!((&x - &svd).amax() < 1e-13, "QR {x} against SVD {svd}");
        }
    }

    /// The sparse path gives the dense minimum-norm solution: square, tall and wide systems.
    #[test]
    fn sparse_path_matches_the_dense_solution_to_round_off() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.0, 1.0, 3.0, -1.0, 0.0, -0.7, 2.0]);
        let tall = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
        let wide = tall.transpose();
        for m in [a, tall, wide] {
            let b = DVector::from_fn(m.nrows(), |i, _| 1.0 - 0.7 * i as f64);
            let entries: Vec<_> = (0..m.nrows())
                .flat_map(|r| (0..m.ncols()).map(move |c| (r, c)))
                .map(|(r, c)| (r, c, m[(r, c)]))
                .collect();
            let x = sparse_min_norm_solve(SparseRows::new(m.nrows(), m.ncols(), &entries), &b).expect("full rank");
            let dense = min_norm_solve(&m, &b, 1e-12).expect("full rank");
            assert!((&x - &dense).amax() < 1e-13, "sparse {x} against dense {dense}");
        }
    }

    /// Two equal rows (a redundant constraint): the SVD path drops the zero singular value and
    /// returns the minimum-norm solution.
    #[test]
    fn redundant_rows_fall_back_to_the_svd_minimum_norm() {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let b = DVector::from_vec(vec![2.0, 2.0]);
        let x = min_norm_solve(&a, &b, 1e-10).expect("svd");
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14, "x = {x}");
    }
}
