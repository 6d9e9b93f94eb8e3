//! Minimum-norm least squares for the projection's Gauss-Newton steps and the fit of
//! loop-closure reactions: a Householder QR when the matrix has full rank (the usual case),
//! an SVD with a rank cut otherwise.
//!
//! Measured on mohr2011's static workspace (15 x 15 closure Jacobians and reaction fits,
//! every step): the SVDs took 13 % of all instructions of a settle, the QR path a small
//! fraction of that, with the same results to round-off (tests unchanged).

use nalgebra::{DMatrix, DVector};

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
