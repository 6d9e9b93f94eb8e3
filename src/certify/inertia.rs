//! The inertia of every symmetric matrix in an interval matrix: interval LDL^T without
//! pivoting (Gaussian elimination in interval arithmetic encloses the elimination of each
//! member matrix). Where no pivot's enclosure holds 0, each member matrix has the pivots'
//! signs as its inertia (Sylvester's law of inertia): all positive proves it positive definite,
//! k negative proves k negative eigenvalues. A pivot that holds 0 proves nothing. Golub & Van
//! Loan, Matrix Computations, 4th ed., section 4.1 (LDL^T); Alefeld & Mayer, "The Cholesky
//! method for interval data", Linear Algebra Appl. 194 (1993).

#![allow(clippy::needless_range_loop)] // index loops that follow the elimination's formulas

use super::enclosure::IntervalMatrix;
use crate::interval::Interval;
use nalgebra::DMatrix;

/// What the pivots prove.
#[derive(Clone, Debug, PartialEq)]
pub enum Inertia {
    /// Every member matrix has `negative` negative eigenvalues and no zero one.
    Proven { negative: usize },
    /// Pivot `at` (from 0) holds 0: nothing is proven.
    Unproven { at: usize },
}

/// The inertia of the symmetric matrices in `a` (its lower triangle read, each entry the hull
/// of (i, j) and (j, i)).
pub fn inertia(a: &IntervalMatrix) -> Inertia {
    let n = a.n;
    let mut w: Vec<Vec<Interval>> = (0..n).map(|i| (0..=i).map(|j| a.at(i, j).hull(a.at(j, i))).collect()).collect();
    let mut negative = 0;
    for k in 0..n {
        let d = w[k][k];
        if d.contains(0.0) || !d.lo.is_finite() || !d.hi.is_finite() {
            return Inertia::Unproven { at: k };
        }
        if d.hi < 0.0 {
            negative += 1;
        }
        let column: Vec<Interval> = (k + 1..n).map(|i| w[i][k] / d).collect();
        for (ii, i) in (k + 1..n).enumerate() {
            let l = column[ii];
            for j in k + 1..=i {
                let update = l * w[j][k];
                w[i][j] = w[i][j] - update;
            }
        }
    }
    Inertia::Proven { negative }
}

/// What the eigenvector-preconditioned Gershgorin test proves of the symmetric matrices in
/// `a`, for when elimination does not (an ill-conditioned stiffness: stiff along the cables,
/// soft across them, blows the pivots' enclosures up). Split A = mid + E with |E| at most the
/// radii, |E|_2 <= rho, rho their largest row sum. With V the float eigenvectors of mid, B =
/// V^T mid V is nearly diagonal; where V is proven nonsingular (|1 - V^T V|_inf < 1) and each
/// Gershgorin disc of B lies off 0 by at least gap, every eigenvalue of mid is at least
/// gap / sigma_max(V)^2 from 0 (Ostrowski: lambda_k(V^T mid V) = theta_k lambda_k(mid),
/// theta_k in [sigma_min^2, sigma_max^2], sigma_max^2 at most |V^T V|_inf) with B's inertia;
/// where that exceeds rho, every A has mid's inertia (Weyl), and a positive definite one has
/// lambda_min >= min_i (B_ii - r_i) / sigma_max^2 - rho. The products are float matrix
/// products with their rounding bounded a priori, |fl(X Y) - X Y| <= gamma_n |X| |Y|,
/// gamma_n = n u / (1 - n u) (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed.,
/// section 3.5), folded into the discs. Returns the inertia and that bound.
pub fn preconditioned_inertia(a: &IntervalMatrix) -> (Inertia, f64) {
    let n = a.n;
    let sym = |r: usize, c: usize| a.at(r, c).hull(a.at(c, r));
    let mid = DMatrix::from_fn(n, n, |r, c| sym(r, c).mid());
    let rho = (0..n)
        .map(|r| (0..n).fold(Interval::ZERO, |s, c| s + Interval::point(sym(r, c).rad())).hi)
        .fold(0.0_f64, f64::max);
    let v = nalgebra::SymmetricEigen::new(mid.clone()).eigenvectors;
    let abs_v = v.abs();
    let gamma = rounding_factor(2 * n);
    let gram = v.transpose() * &v;
    let gram_error = (abs_v.transpose() * &abs_v) * gamma;
    let b = v.transpose() * (&mid * &v);
    let b_error = (abs_v.transpose() * (mid.abs() * &abs_v)) * gamma;
    let (mut gram_norm, mut off_identity) = (0.0_f64, 0.0_f64);
    for r in 0..n {
        let row = (0..n).fold(Interval::ZERO, |s, c| s + Interval::point(gram[(r, c)].abs() + gram_error[(r, c)]));
        let identity = |c: usize| if r == c { 1.0 } else { 0.0 };
        let off = (0..n).fold(Interval::ZERO, |s, c| {
            s + Interval::point((gram[(r, c)] - identity(c)).abs()) + Interval::point(gram_error[(r, c)])
        });
        gram_norm = gram_norm.max(row.hi);
        off_identity = off_identity.max(off.hi);
    }
    if off_identity >= 1.0 {
        return (Inertia::Unproven { at: 0 }, 0.0);
    }
    let (mut negative, mut gap, mut lowest) = (0, f64::INFINITY, f64::INFINITY);
    for r in 0..n {
        let radius = (0..n).fold(Interval::point(b_error[(r, r)]), |s, c| {
            if c == r {
                s
            } else {
                s + Interval::point(b[(r, c)].abs()) + Interval::point(b_error[(r, c)])
            }
        });
        let disc = Interval::point(b[(r, r)]) + Interval::new(-radius.hi, radius.hi);
        if disc.contains(0.0) {
            return (Inertia::Unproven { at: r }, 0.0);
        }
        negative += usize::from(disc.hi < 0.0);
        gap = gap.min(disc.mig());
        lowest = lowest.min(disc.lo);
    }
    let scale = |x: f64| (Interval::point(x) / Interval::point(gram_norm)).lo;
    if scale(gap) <= rho {
        return (Inertia::Unproven { at: n }, 0.0);
    }
    let bound = if negative == 0 { (Interval::point(scale(lowest)) - Interval::point(rho)).lo.max(0.0) } else { 0.0 };
    (Inertia::Proven { negative }, bound)
}

/// An upper bound of gamma_k = k u / (1 - k u), u the unit roundoff, with room for the
/// rounding of the bound's own float products (doubled).
fn rounding_factor(k: usize) -> f64 {
    let ku = k as f64 * f64::EPSILON / 2.0;
    2.0 * ku / (1.0 - ku)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matrix(rows: &[&[f64]], r: f64) -> IntervalMatrix {
        let n = rows.len();
        IntervalMatrix { n, entries: rows.iter().flat_map(|row| row.iter().map(|&x| Interval::around(x, r))).collect() }
    }

    /// diag(2, -3, 5) turned by a rotation keeps its inertia (one negative eigenvalue); within
    /// 1e-3 of each entry too; at 1.5 (past the smallest |eigenvalue|, 2) nothing is proven; a
    /// singular matrix is never proven definite.
    #[test]
    fn the_pivots_prove_the_inertia_or_nothing() {
        let (c, s) = (0.6_f64, 0.8_f64);
        // Q diag(2, -3, 5) Q^T with Q a rotation in the (0, 1) plane.
        let a = [
            [2.0 * c * c - 3.0 * s * s, (2.0 + 3.0) * c * s, 0.0],
            [(2.0 + 3.0) * c * s, 2.0 * s * s - 3.0 * c * c, 0.0],
            [0.0, 0.0, 5.0],
        ];
        let rows: Vec<&[f64]> = a.iter().map(|r| &r[..]).collect();
        assert_eq!(inertia(&matrix(&rows, 0.0)), Inertia::Proven { negative: 1 });
        assert_eq!(inertia(&matrix(&rows, 1e-3)), Inertia::Proven { negative: 1 });
        assert!(matches!(inertia(&matrix(&rows, 1.5)), Inertia::Unproven { .. }));
        let singular: [&[f64]; 2] = [&[1.0, 1.0], &[1.0, 1.0]];
        assert!(matches!(inertia(&matrix(&singular, 0.0)), Inertia::Unproven { at: 1 }));
    }
}
