//! The dense step (small structures): the saddle-free Newton step in the mass-weighted modes
//! of the Hessian, from its symmetric eigendecomposition.

use super::assemble::{Dofs, System};
use super::{StepSolver, SOFT_MODE_RATIO};
use nalgebra::{DVector, SymmetricEigen};

/// The mass-weighted modes of the Hessian at the current state, and the generalized force in
/// them.
pub(super) struct Modes {
    eig: SymmetricEigen<f64, nalgebra::Dyn>,
    /// 1 / sqrt(mass or inertia) of each coordinate.
    weight: DVector<f64>,
    /// The generalized force, mass-weighted.
    force: DVector<f64>,
    /// The largest |omega^2| [1/s^2].
    stiffest: f64,
}

impl Modes {
    pub(super) fn new(dofs: &Dofs, system: &System) -> Self {
        let weight = dofs.weight();
        let h = system.dense();
        let n = weight.len();
        let a = nalgebra::DMatrix::from_fn(n, n, |r, c| weight[r] * h[(r, c)] * weight[c]);
        let eig = SymmetricEigen::new(a);
        let stiffest = eig.eigenvalues.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        Modes { eig, force: system.force.component_mul(&weight), weight, stiffest }
    }
}

impl StepSolver for Modes {
    /// The saddle-free Newton step, shifted: each mode of stiffness lambda moves by its force
    /// over |lambda| + shift (shift as a fraction of the stiffest mode); modes softer than
    /// [`SOFT_MODE_RATIO`] of the stiffest stay.
    fn step(&mut self, shift: f64) -> Option<DVector<f64>> {
        let mut y = DVector::zeros(self.force.len());
        for (k, lambda) in self.eig.eigenvalues.iter().enumerate() {
            if lambda.abs() > SOFT_MODE_RATIO * self.stiffest {
                let mode = self.eig.eigenvectors.column(k);
                y += mode * (mode.dot(&self.force) / (lambda.abs() + shift * self.stiffest));
            }
        }
        Some(y.component_mul(&self.weight))
    }
}
