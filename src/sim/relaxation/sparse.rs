//! The sparse step (large structures): the Levenberg-Marquardt step dx = (H + mu M)^-1 f with
//! a sparse Cholesky factorization of the mass-weighted Hessian (nalgebra-sparse), the bodies
//! in reverse Cuthill-McKee order.
//!
//! It keeps the dense step's guarantees without the Hessian's modes: a shift mu for which the
//! factorization fails (H + mu M not positive definite) is a rejected trial and is raised, so
//! every mode of negative stiffness lambda moves by its force over lambda + mu > 0, away from
//! the unstable equilibrium as the force pushes, and the line search accepts only steps that
//! lower the energy. The shift never falls below [`SOFT_MODE_RATIO`] of the stiffest mode, so
//! a near-free motion (the turn of a prism about its held strut) moves by its round-off force
//! over that floor at most; the six rigid motions of a group of bodies that no member ties to
//! a fixed body are exact zero modes and are removed from the force and the step (the dense
//! step leaves them out as soft modes).

use super::assemble::{cross_matrix, v3, Dofs, System};
use super::{StepSolver, SOFT_MODE_RATIO};
use crate::ordering::reverse_cuthill_mckee;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};
use nalgebra_sparse::factorization::{CscCholesky, CscSymbolicCholesky};
use nalgebra_sparse::CscMatrix;
use std::collections::BTreeMap;

/// The mass-weighted Hessian in factor order, ready to be shifted and factorized.
pub(super) struct ShiftedCholesky {
    /// Factor position of each free body (block).
    position: Vec<usize>,
    /// W H W (W = M^-1/2), rows and columns in factor order.
    matrix: CscMatrix<f64>,
    /// Index in `matrix`'s values of each diagonal entry.
    diagonal: Vec<usize>,
    symbolic: CscSymbolicCholesky,
    /// 1 / sqrt(mass or inertia) of each coordinate, in block order.
    weight: DVector<f64>,
    /// W f in factor order, the free rigid motions removed.
    force: DVector<f64>,
    /// Orthonormal rigid motions of the groups and bodies that keep their anchors in place,
    /// mass-weighted, in factor order.
    rigid: Vec<Motion>,
    /// Gershgorin's bound on the largest |omega^2| [1/s^2].
    stiffest: f64,
}

impl ShiftedCholesky {
    /// `groups`: the free bodies' groups and their anchors ([`Simulation::rigid_groups`]);
    /// `length_m`: the structure's size.
    pub(super) fn new(dofs: &Dofs, system: &System, groups: &[(Vec<usize>, Vec<Vector3<f64>>)], length_m: f64) -> Self {
        let n = dofs.blocks();
        let weight = dofs.weight();
        // W H W, symmetrized.
        let (position, columns) = ordered_columns(system, n, |i, k, block| {
            Ok(Matrix6::from_fn(|r, c| weight[6 * i + r] * block[(r, c)] * weight[6 * k + c]) * 0.5)
        })
        .unwrap_or_else(|never: std::convert::Infallible| match never {});
        let (matrix, diagonal) = csc(&columns);
        let stiffest =
            (0..6 * n).map(|c| matrix.col(c).values().iter().map(|x| x.abs()).sum::<f64>()).fold(0.0_f64, f64::max);
        let symbolic = CscSymbolicCholesky::factor(matrix.pattern().clone());
        let weigh = |i: usize, u: &Vector3<f64>, w: &Vector3<f64>| {
            let (mass, inertia) = dofs.scale[i];
            let (u, w) = (u * mass.sqrt(), w * inertia.sqrt());
            Vector6::new(u.x, u.y, u.z, w.x, w.y, w.z)
        };
        let rigid = rigid_motions(dofs, length_m, &position, groups, &weigh);
        let mut force = DVector::zeros(6 * n);
        for i in 0..n {
            for r in 0..6 {
                force[6 * position[i] + r] = system.force[6 * i + r] * weight[6 * i + r];
            }
        }
        remove(&rigid, &mut force);
        ShiftedCholesky { position, matrix, diagonal, symbolic, weight, force, rigid, stiffest }
    }

    /// The shift mu [1/s^2] of the step at `shift` (a fraction of the stiffest mode).
    pub(super) fn mu(&self, shift: f64) -> f64 {
        shift.max(SOFT_MODE_RATIO) * self.stiffest
    }
}

/// The CSC matrix of `columns` (row block -> 6x6 block, per column block) and the index of
/// each diagonal entry among its values.
/// One column of 6 x 6 blocks: row block -> block.
pub(super) type ColumnBlocks = BTreeMap<usize, Matrix6<f64>>;

/// The blocks of `system` weighted by `weigh(i, k, block)` (half of each: the block and its
/// transpose are both added) in reverse Cuthill-McKee order: each block's position in that
/// order, and the column blocks (row block -> block, the diagonal always present).
pub(super) fn ordered_columns<E>(
    system: &System,
    n: usize,
    mut weigh: impl FnMut(usize, usize, &Matrix6<f64>) -> Result<Matrix6<f64>, E>,
) -> Result<(Vec<usize>, Vec<ColumnBlocks>), E> {
    let mut neighbours = vec![Vec::new(); n];
    for &(i, k, _) in system.blocks.iter().filter(|(i, k, _)| i != k) {
        neighbours[i].push(k);
    }
    let position = reverse_cuthill_mckee(&neighbours);
    let mut columns: Vec<ColumnBlocks> = vec![BTreeMap::new(); n];
    for (k, column) in columns.iter_mut().enumerate() {
        column.insert(k, Matrix6::zeros());
    }
    for (i, k, block) in &system.blocks {
        let weighted = weigh(*i, *k, block)?;
        *columns[position[*k]].entry(position[*i]).or_insert_with(Matrix6::zeros) += weighted;
        *columns[position[*i]].entry(position[*k]).or_insert_with(Matrix6::zeros) += weighted.transpose();
    }
    Ok((position, columns))
}

pub(super) fn csc(columns: &[BTreeMap<usize, Matrix6<f64>>]) -> (CscMatrix<f64>, Vec<usize>) {
    let n = 6 * columns.len();
    let (mut offsets, mut rows, mut values, mut diagonal) = (vec![0], Vec::new(), Vec::new(), vec![0; n]);
    for (k, column) in columns.iter().enumerate() {
        for c in 0..6 {
            for (&i, block) in column {
                for r in 0..6 {
                    if i == k && r == c {
                        diagonal[6 * k + c] = values.len();
                    }
                    rows.push(6 * i + r);
                    values.push(block[(r, c)]);
                }
            }
            offsets.push(rows.len());
        }
    }
    let matrix = CscMatrix::try_from_csc_data(n, n, offsets, rows, values).expect("sorted, in-range rows");
    (matrix, diagonal)
}

/// Eigenvalues of the normal matrix of a group's anchor constraints below this fraction of the
/// largest (at least 1, lengths in the structure's size) leave a rigid motion free: singular
/// values below 1e-6 of the largest, well above the normal matrix's round-off (1e-16 of its
/// largest eigenvalue, 1e-8 in singular values). A rigid motion left with less than this
/// fraction of its norm once the ones before are removed is not new.
const RIGID_RANK_RATIO: f64 = 1e-12;

/// A motion in the mass-weighted coordinates, in factor order, by its nonzero entries.
pub(super) struct Motion(pub(super) Vec<(usize, f64)>);

impl Motion {
    fn dot(&self, v: &DVector<f64>) -> f64 {
        self.0.iter().map(|&(r, x)| x * v[r]).sum()
    }
}

/// The mass-weighted coordinates of block i's translation u [m] and turn w [rad].
pub(super) type Weigh<'a> = dyn Fn(usize, &Vector3<f64>, &Vector3<f64>) -> Vector6<f64> + 'a;

/// The rigid motions of each group that keep its anchors in place, mass-weighted (`weigh` of
/// each body's translation and turn: W^-1 times the motion for the step, L^T for the modes),
/// orthonormal, in factor order. A rigid motion is a twist (t, w): body i's centre
/// of mass moves by t + w x (c_i - c) and turns by w; an anchor a stays where
/// t + w x (a - c) = 0, and the free twists are the null space of those constraints. Each
/// motion is made orthogonal to those before it that move its bodies, on its bodies' entries
/// alone (a group's after its bodies': the supports stay the groups').
pub(super) fn rigid_motions(
    dofs: &Dofs,
    length_m: f64,
    position: &[usize],
    groups: &[(Vec<usize>, Vec<Vector3<f64>>)],
    weigh: &Weigh<'_>,
) -> Vec<Motion> {
    let mut basis: Vec<Motion> = Vec::new();
    // For each factor block, the motions that move it.
    let mut moving: Vec<Vec<usize>> = vec![Vec::new(); dofs.blocks()];
    for (blocks, anchors) in groups {
        let points: Vec<Vector3<f64>> =
            if anchors.is_empty() { blocks.iter().map(|&i| v3(dofs.com[i])).collect() } else { anchors.clone() };
        let centre = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
        // Entries of the group's blocks: factor row -> place in the local vector.
        let local: std::collections::BTreeMap<usize, usize> = blocks
            .iter()
            .enumerate()
            .flat_map(|(k, &i)| (0..6).map(move |r| (6 * position[i] + r, 6 * k + r)))
            .collect();
        let mut earlier: Vec<usize> = blocks.iter().flat_map(|&i| moving[position[i]].iter().copied()).collect();
        earlier.sort_unstable();
        earlier.dedup();
        for (t, w) in free_twists(anchors, centre, length_m) {
            let mut motion = DVector::zeros(6 * blocks.len());
            for (k, &i) in blocks.iter().enumerate() {
                let u = t + w.cross(&(v3(dofs.com[i]) - centre));
                motion.fixed_rows_mut::<6>(6 * k).copy_from(&weigh(i, &u, &w));
            }
            let before = motion.norm();
            for &m in &earlier {
                let along: f64 = basis[m].0.iter().map(|&(r, x)| x * motion[local[&r]]).sum();
                for &(r, x) in &basis[m].0 {
                    motion[local[&r]] -= along * x;
                }
            }
            let norm = motion.norm();
            if norm > RIGID_RANK_RATIO.sqrt() * before {
                let entries = local.iter().map(|(&r, &l)| (r, motion[l] / norm)).filter(|(_, x)| *x != 0.0);
                earlier.push(basis.len());
                for &i in blocks {
                    moving[position[i]].push(basis.len());
                }
                basis.push(Motion(entries.collect()));
            }
        }
    }
    basis
}

/// The twists (t, w) [m, rad] about `centre` that keep every anchor in place: the null space
/// of the constraints t + w x (a - centre) = 0, lengths in `length_m` for the rank test.
fn free_twists(anchors: &[Vector3<f64>], centre: Vector3<f64>, length_m: f64) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let mut constraints = DMatrix::zeros(3 * anchors.len(), 6);
    for (k, a) in anchors.iter().enumerate() {
        constraints.fixed_view_mut::<3, 3>(3 * k, 0).copy_from(&Matrix3::identity());
        constraints.fixed_view_mut::<3, 3>(3 * k, 3).copy_from(&(-cross_matrix((a - centre) / length_m)));
    }
    let eig = SymmetricEigen::new(constraints.transpose() * &constraints);
    let largest = eig.eigenvalues.amax().max(1.0);
    (0..6)
        .filter(|&j| eig.eigenvalues[j].abs() <= RIGID_RANK_RATIO * largest)
        .map(|j| {
            let twist = eig.eigenvectors.column(j);
            (Vector3::new(twist[0], twist[1], twist[2]), Vector3::new(twist[3], twist[4], twist[5]) / length_m)
        })
        .collect()
}

/// Removes from `v` its components along the orthonormal `basis`.
fn remove(basis: &[Motion], v: &mut DVector<f64>) {
    for b in basis {
        let along = b.dot(v);
        for &(r, x) in &b.0 {
            v[r] -= along * x;
        }
    }
}

impl StepSolver for ShiftedCholesky {
    /// The step (H + mu M)^-1 f with mu = max(shift, [`SOFT_MODE_RATIO`]) times the stiffest
    /// mode; `None` where H + mu M is not positive definite.
    fn step(&mut self, shift: f64) -> Option<DVector<f64>> {
        let mu = self.mu(shift);
        let mut values = self.matrix.values().to_vec();
        for &d in &self.diagonal {
            values[d] += mu;
        }
        // A fresh factorization each trial: a failed one leaves the workspace dirty.
        let factor = CscCholesky::factor_numerical(self.symbolic.clone(), &values).ok()?;
        let mut y = DMatrix::from_column_slice(self.force.len(), 1, self.force.as_slice());
        factor.solve_mut(&mut y);
        let mut y = y.column(0).into_owned();
        remove(&self.rigid, &mut y);
        let mut dx = DVector::zeros(y.len());
        for (i, &p) in self.position.iter().enumerate() {
            for r in 0..6 {
                dx[6 * i + r] = y[6 * p + r] * self.weight[6 * i + r];
            }
        }
        dx.iter().all(|x| x.is_finite()).then_some(dx)
    }
}
