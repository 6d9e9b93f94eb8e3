//! Krawczyk's test over growing boxes, and the certificate it gives (module docs of
//! `certify`). The unknowns are every coordinate but the gauge's (`Problem::gauge`), held at 0.

use super::enclosure::{gradient_and_hessian, node_positions, IntervalMatrix};
use super::inertia::{inertia, preconditioned_inertia, Inertia};
use super::{Certificate, Problem, Proof, Stability};
use crate::interval::Interval;
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Float Newton steps that move the box's centre from the settled state onto the equilibrium.
const NEWTON_STEPS: usize = 4;
/// A stiffness eigenvalue below this fraction of the largest |eigenvalue| is a zero mode: no
/// unique equilibrium to prove.
const ZERO_MODE_RATIO: f64 = 1e-10;
/// The first box's radius over the Newton step's size (scaled, m), and its floor as a
/// fraction of the structure's size.
const FIRST_BOX_OVER_STEP: f64 = 4.0;
const FIRST_BOX_FLOOR_RATIO: f64 = 1e-12;
/// The box grows by this factor while the test passes, up to the structure's size.
const GROWTH: f64 = 4.0;
/// Bisections (in log) between the last box that passed and the first that failed.
const BISECTIONS: usize = 5;

/// The unknowns (every coordinate but the gauge's), their scales, the float centre (all
/// coordinates) and Y over the unknowns.
struct System<'a> {
    problem: &'a Problem,
    free: Vec<usize>,
    scales: Vec<f64>,
    center: DVector<f64>,
    y: DMatrix<f64>,
    yf: Vec<Interval>,
}

/// The certificate of `problem`'s equilibrium near its settled state (q = 0).
pub fn certify(problem: &Problem) -> Certificate {
    let n = problem.size();
    let (f0, _) = gradient_and_hessian(problem, &vec![Interval::ZERO; n]);
    let free = problem.unknowns();
    let residual = free.iter().fold(0.0_f64, |m, &i| m.max(f0[i].mag()));
    let mut certificate = Certificate { coordinates: n, residual, proof: None, reason: None, boxes: 0 };
    if free.is_empty() {
        certificate.reason = Some("no free coordinate: nothing moves".into());
        return certificate;
    }
    let all_scales = problem.scales();
    let scales: Vec<f64> = free.iter().map(|&i| all_scales[i]).collect();
    let (center, y, eigen) = match centre(problem, &free, &scales) {
        Ok(c) => c,
        Err(why) => {
            certificate.reason = Some(why);
            return certificate;
        }
    };
    let (fc, _) = gradient_and_hessian(problem, &center.iter().map(|&c| Interval::point(c)).collect::<Vec<_>>());
    let m = free.len();
    let yf: Vec<Interval> = (0..m).map(|i| (0..m).fold(Interval::ZERO, |s, k| s + fc[free[k]] * y[(i, k)])).collect();
    let system = System { problem, free, scales, center, y, yf };
    search(&system, &mut certificate, &eigen, problem.gauge().map(|g| problem.coordinate_names()[g].clone()));
    certificate
}

/// The largest box that passes (grown by fours, then bisected), and the proof from it and from
/// the smallest that passed (the tightest enclosure).
fn search(s: &System, certificate: &mut Certificate, eigen: &DVector<f64>, held: Option<String>) {
    let step = s.yf.iter().zip(&s.scales).fold(0.0_f64, |m, (v, sc)| m.max(v.mag() * sc));
    let first = (FIRST_BOX_OVER_STEP * step).max(FIRST_BOX_FLOOR_RATIO * s.problem.length_m);
    let (mut rho, mut smallest, mut largest, mut failed) = (first, None, None, None);
    while rho <= s.problem.length_m {
        certificate.boxes += 1;
        match test(s, rho) {
            Some(k) => {
                smallest = smallest.or(Some(k));
                largest = Some(rho);
            }
            None => {
                failed = Some(rho);
                break;
            }
        }
        rho *= GROWTH;
    }
    let (Some(mut passed), Some((k, _))) = (largest, smallest) else {
        certificate.reason = Some(format!(
            "Krawczyk's test fails on the smallest box ({first:.1e} m): no equilibrium is proven near the settled state (its residual {:.1e})",
            certificate.residual
        ));
        return;
    };
    if let Some(mut fail) = failed {
        for _ in 0..BISECTIONS {
            let mid = (passed * fail).sqrt();
            certificate.boxes += 1;
            match test(s, mid) {
                Some(_) => passed = mid,
                None => fail = mid,
            }
        }
    }
    let mut proof = proof(s, passed, &k, eigen);
    proof.held_coordinate = held;
    certificate.proof = Some(proof);
}

/// The box of scaled radius `rho` (m) around the centre: the unknowns' intervals, the gauge's
/// coordinate held at 0.
fn boxed(s: &System, rho: f64) -> Vec<Interval> {
    let mut x: Vec<Interval> = s.center.iter().map(|&c| Interval::point(c)).collect();
    for (i, &c) in s.free.iter().enumerate() {
        x[c] = Interval::around(s.center[c], rho / s.scales[i]);
    }
    x
}

/// J(x) restricted to the unknowns.
fn reduced(j: &IntervalMatrix, free: &[usize]) -> IntervalMatrix {
    let m = free.len();
    IntervalMatrix { n: m, entries: (0..m * m).map(|e| j.at(free[e / m], free[e % m])).collect() }
}

/// The float centre, Y and the float eigenvalues ([`centre`]).
type Centre = (DVector<f64>, DMatrix<f64>, DVector<f64>);

/// The float Newton centre, Y = J(centre)^-1 over the unknowns and the scaled stiffness's
/// float eigenvalues at the settled state; Err with the reason where it is singular.
fn centre(problem: &Problem, free: &[usize], scales: &[f64]) -> Result<Centre, String> {
    let n = problem.size();
    let m = free.len();
    let float_at = |x: &DVector<f64>| {
        let (f, j) = gradient_and_hessian(problem, &x.iter().map(|&c| Interval::point(c)).collect::<Vec<_>>());
        let j = reduced(&j, free);
        let jm = DMatrix::from_fn(m, m, |r, c| 0.5 * (j.at(r, c).mid() + j.at(c, r).mid()));
        (DVector::from_iterator(m, free.iter().map(|&i| f[i].mid())), jm)
    };
    let mut x = DVector::zeros(n);
    let mut here = float_at(&x);
    let scaled = DMatrix::from_fn(m, m, |r, c| here.1[(r, c)] / (scales[r] * scales[c]));
    let eigen = SymmetricEigen::new(scaled).eigenvalues;
    let largest = eigen.amax();
    let smallest = eigen.iter().fold(f64::INFINITY, |a, l| a.min(l.abs()));
    if smallest.is_nan() || smallest <= ZERO_MODE_RATIO * largest {
        return Err(format!(
            "the stiffness has a zero mode (|eigenvalue| {smallest:.1e} N/m against the largest {largest:.1e}): a mechanism or a free rigid motion, along which equilibria are not isolated"
        ));
    }
    for _ in 0..NEWTON_STEPS {
        let (f, j) = here;
        let Some(dx) = j.lu().solve(&(-f)) else { return Err("the stiffness at the Newton centre is singular".into()) };
        for (k, &i) in free.iter().enumerate() {
            x[i] += dx[k];
        }
        here = float_at(&x);
    }
    let y = here.1.try_inverse().ok_or("the stiffness at the Newton centre is singular")?;
    Ok((x, y, eigen))
}

/// Krawczyk's test on the box of scaled radius `rho`: K(X) over the unknowns and J(X) (over
/// them too) where K(X) lies in X's interior.
fn test(s: &System, rho: f64) -> Option<(Vec<Interval>, IntervalMatrix)> {
    let x = boxed(s, rho);
    let (_, j) = gradient_and_hessian(s.problem, &x);
    let j = reduced(&j, &s.free);
    let m = s.free.len();
    // M = Y J(X) over J's nonzero entries.
    let mut prod = vec![Interval::ZERO; m * m];
    for k in 0..m {
        for c in 0..m {
            let e = j.at(k, c);
            if e == Interval::ZERO {
                continue;
            }
            for i in 0..m {
                prod[i * m + c] = prod[i * m + c] + e * s.y[(i, k)];
            }
        }
    }
    let offset: Vec<Interval> = s.free.iter().map(|&c| x[c] - Interval::point(s.center[c])).collect();
    let mut k = Vec::with_capacity(m);
    for i in 0..m {
        let mut sum = Interval::point(s.center[s.free[i]]) - s.yf[i];
        for c in 0..m {
            let a = if i == c { Interval::point(1.0) - prod[i * m + c] } else { -prod[i * m + c] };
            sum = sum + a * offset[c];
        }
        if !sum.inside(x[s.free[i]]) {
            return None;
        }
        k.push(sum);
    }
    Some((k, j))
}

/// The proof: the largest box's sizes (scaled radius `rho`), the enclosure K from the smallest
/// box that passed (it holds the same equilibrium), the nodes over K and the stability over J(K)
/// (tighter than the box K came from, which the elimination of an ill-conditioned stiffness
/// needs).
fn proof(s: &System, rho: f64, k: &[Interval], eigen: &DVector<f64>) -> Proof {
    let mut tight: Vec<Interval> = s.center.iter().map(|&c| Interval::point(c)).collect();
    for (i, &c) in s.free.iter().enumerate() {
        tight[c] = k[i];
    }
    let j = reduced(&gradient_and_hessian(s.problem, &tight).1, &s.free);
    let node_enclosures = s.problem.node_names.iter().cloned().zip(node_positions(s.problem, &tight)).collect();
    let x = boxed(s, rho);
    let node_radius_m = node_positions(s.problem, &x).iter().flatten().fold(0.0_f64, |m, c| m.max(c.rad()));
    let enclosure_radius_m = k.iter().zip(&s.scales).fold(0.0_f64, |m, (c, sc)| m.max(c.rad() * sc));
    let settled_offset_m = k.iter().zip(&s.scales).fold(0.0_f64, |m, (c, sc)| m.max(c.mag() * sc));
    Proof {
        radius_m: rho,
        radius_rad: s.problem.blocks.iter().any(|b| !b.rotations.is_empty()).then(|| rho / s.problem.length_m),
        node_radius_m,
        enclosure_radius_m,
        settled_offset_m,
        held_coordinate: None,
        stability: stability(&j, &s.scales, eigen),
        node_enclosures,
        model: None,
    }
}

/// The stability that J proves, in scaled coordinates (`inertia.rs`).
fn stability(j: &IntervalMatrix, scales: &[f64], eigen: &DVector<f64>) -> Stability {
    let n = j.n;
    let scaled = |shift: f64| IntervalMatrix {
        n,
        entries: (0..n * n)
            .map(|e| {
                let (r, c) = (e / n, e % n);
                let v = j.at(r, c) / Interval::point(scales[r]) / Interval::point(scales[c]);
                if r == c {
                    v - Interval::point(shift)
                } else {
                    v
                }
            })
            .collect(),
    };
    match inertia(&scaled(0.0)) {
        Inertia::Unproven { at } => match preconditioned_inertia(&scaled(0.0)) {
            (Inertia::Proven { negative: 0 }, bound) => Stability::Stable { smallest_eigenvalue_at_least_n_per_m: bound },
            (Inertia::Proven { negative }, _) => Stability::Unstable { index: negative },
            (Inertia::Unproven { .. }, _) => Stability::Unproven {
                why: format!(
                    "the stiffness over the box may hold a singular matrix (elimination: pivot {} of {n} holds 0; the preconditioned Gershgorin discs hold 0 too)",
                    at + 1
                ),
            },
        },
        Inertia::Proven { negative } if negative > 0 => Stability::Unstable { index: negative },
        Inertia::Proven { .. } => {
            let smallest = eigen.min();
            let bound = [0.999, 0.9, 0.5]
                .iter()
                .map(|f| f * smallest)
                .find(|&sh| sh > 0.0 && inertia(&scaled(sh)) == Inertia::Proven { negative: 0 })
                .unwrap_or(0.0);
            Stability::Stable { smallest_eigenvalue_at_least_n_per_m: bound }
        }
    }
}

/// Whether the box of scaled radius `radius_m` around the problem's state (q = 0) provably
/// holds no equilibrium: some component of F's enclosure over it excludes 0.
pub fn excludes_equilibrium(problem: &Problem, radius_m: f64) -> bool {
    let scales = problem.scales();
    let x: Vec<Interval> = scales.iter().map(|s| Interval::around(0.0, radius_m / s)).collect();
    let (f, _) = gradient_and_hessian(problem, &x);
    f.iter().any(|c| !c.contains(0.0))
}

/// The stiffness at the settled state (q = 0) over the unknowns (the gauge's coordinate left
/// out), coordinates scaled to m as the stability's bound is (rotations as arcs at the
/// structure's size), symmetrized float midpoints \[N/m\]: what an independent verified
/// eigenvalue bound can check the certificate's stability against. Each unknown's name beside.
pub fn reduced_stiffness(problem: &Problem) -> (Vec<String>, Vec<Vec<f64>>) {
    let free = problem.unknowns();
    let (scales, names) = (problem.scales(), problem.coordinate_names());
    let (_, j) = gradient_and_hessian(problem, &vec![Interval::ZERO; problem.size()]);
    let matrix = free
        .iter()
        .map(|&r| free.iter().map(|&c| 0.5 * (j.at(r, c).mid() + j.at(c, r).mid()) / (scales[r] * scales[c])).collect())
        .collect();
    (free.iter().map(|&i| names[i].clone()).collect(), matrix)
}
