//! What the sensitivities of a large structure of free bodies need (above
//! [`crate::structure::DENSE_MODAL_MAX_FREE_BODIES`] free bodies, where `tensegrity modes`
//! turns sparse): no dense K. The modes are `tensegrity modes`' own (the relaxation's exact
//! Hessian, every rigid mode and the lowest others, `relaxation/lowest_modes.rs`), K^+ r comes
//! from them and a sparse factorization (`relaxation/modal_solve.rs`), and a mode's curvature
//! phi^T K phi at a parameter's sample from the forces along phi alone.
//!
//! The dense K of differenced forces had cost four force evaluations per coordinate at every
//! sample, and its round-off, over a thin strut's small moment about its axis, had put spin
//! modes among the frequencies (a 300-strut prism: mode 1 at omega = -9e-3 rad/s, where
//! `tensegrity modes` finds it rigid, and the lowest others 0.7 % off).

use super::data::Data;
use super::model::Model;
use super::modes::{Lowest, ModesError, Solver};
use super::relaxation::ModalSolve;
use super::sensitivity::{derivative_from_samples, EquilibriumCoordinates};
use crate::eigen::Mode;
use nalgebra::{DVector, Matrix6};

/// The lowest modes of a large structure of free bodies (in the coordinates' order,
/// mass-normalised), which of them are rigid, and K^+ r (`SparseLinearization`).
pub type SparseModes = (Vec<Mode>, Vec<bool>, SparseLinearization);

/// K^+ r of a large structure of free bodies, in its coordinates' order.
pub struct SparseLinearization {
    solve: ModalSolve,
    /// For each block of the modal analysis, the coordinates' block (the bodies' order).
    order: Vec<usize>,
}

impl SparseLinearization {
    /// x = K^+ r over the modes that are not rigid, r and x in the coordinates' order.
    pub fn solve(&self, r: &DVector<f64>) -> Result<DVector<f64>, crate::eigen::EigenError> {
        let mut blocks = DVector::zeros(r.len());
        for (i, &c) in self.order.iter().enumerate() {
            blocks.fixed_rows_mut::<6>(6 * i).copy_from(&r.fixed_rows::<6>(6 * c));
        }
        Ok(self.to_coordinates(&self.solve.solve(&blocks)?))
    }

    /// The number of coordinates.
    pub fn size(&self) -> usize {
        6 * self.order.len()
    }

    /// A vector in the modal analysis's block order, in the coordinates' order.
    fn to_coordinates(&self, x: &DVector<f64>) -> DVector<f64> {
        to_coordinates(&self.order, x)
    }
}

/// A vector of blocks in `order` (the coordinates' block of each), in the coordinates' order.
fn to_coordinates(order: &[usize], x: &DVector<f64>) -> DVector<f64> {
    let mut out = DVector::zeros(x.len());
    for (i, &c) in order.iter().enumerate() {
        out.fixed_rows_mut::<6>(6 * c).copy_from(&x.fixed_rows::<6>(6 * i));
    }
    out
}

impl Data {
    /// The lowest `count` modes beyond the rigid ones in the free bodies' coordinates `bodies`
    /// (module docs), and the solver of K x = r.
    pub(super) fn sparse_linearization(
        &mut self,
        m: &Model,
        bodies: &[usize],
        count: usize,
    ) -> Result<SparseModes, ModesError> {
        let analysis = self.modes(m, None, Solver::BySize(Lowest { count, through: None }))?;
        let order: Vec<usize> = analysis
            .bodies
            .iter()
            .map(|b| bodies.iter().position(|c| c == b).expect("the analysis's bodies are the coordinates'"))
            .collect();
        let known: Vec<(f64, DVector<f64>, bool)> = analysis
            .modes
            .iter()
            .map(|mode| (mode.omega_squared, DVector::from_column_slice(&mode.shape), mode.rigid))
            .collect();
        let solve = self.modal_solve(m, &analysis.mass, &known)?;
        let modes =
            known.iter().map(|(w2, x, _)| Mode { omega_squared: *w2, shape: to_coordinates(&order, x) }).collect();
        let rigid = known.iter().map(|(_, _, rigid)| *rigid).collect();
        Ok((modes, rigid, SparseLinearization { solve, order }))
    }

    /// phi^T (K - omega^2 M) phi in free bodies' coordinates `c` now: phi^T K phi =
    /// -d/ds phi . Q(q + s phi), a central difference extrapolated over s and 2 s (four force
    /// evaluations), s moving no coordinate by more than its own step (a rotation's second
    /// order, the small rotations taken one after the other, leaves the first derivative
    /// alone); M from each body's block.
    pub(super) fn modal_curvature(
        &mut self,
        m: &Model,
        c: &EquilibriumCoordinates,
        phi: &DVector<f64>,
        w2: f64,
    ) -> f64 {
        let EquilibriumCoordinates::Bodies(bodies) = c else { unreachable!("free bodies' coordinates only") };
        let mass: f64 = self
            .mass_blocks(m, bodies)
            .iter()
            .enumerate()
            .map(|(i, block): (usize, &Matrix6<f64>)| {
                let v = phi.fixed_rows::<6>(6 * i);
                v.dot(&(block * v))
            })
            .sum();
        let s = (0..c.len())
            .filter(|&i| phi[i] != 0.0)
            .map(|i| self.coordinate_step(m, c, i) / phi[i].abs())
            .fold(f64::INFINITY, f64::min);
        if !s.is_finite() {
            return 0.0;
        }
        let start: Vec<_> = bodies.iter().map(|&b| (m.handles[b], *self.bodies[m.handles[b]].position())).collect();
        let mut at = |d: f64| {
            let step: Vec<f64> = phi.iter().map(|v| d * v).collect();
            self.displace_coordinates(m, c, &step);
            let q = self.generalized_forces(m, c).dot(phi);
            for (h, pose) in &start {
                self.bodies[*h].set_position(*pose, true);
            }
            q
        };
        let (m2, m1, p1, p2) = (at(-2.0 * s), at(-s), at(s), at(2.0 * s));
        -derivative_from_samples(m2, m1, p1, p2, s) - w2 * mass
    }
}
