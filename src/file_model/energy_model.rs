//! An energy model stated in a scenario file (`[energy]`): a potential-energy expression in
//! named coordinates. Its stationary points are found by Newton's method on its
//! gradient and Hessian (forward derivatives, no finite differences), from the settled state and from a scan, and
//! each is classified by the Hessian's eigenvalues (nalgebra `SymmetricEigen`).

use super::expr::Expr;
use super::spec::ErrorClass;
use crate::mechanisms::wrap_angle;
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Largest number of Newton steps from one start.
const MAX_NEWTON_STEPS: usize = 100;
/// Newton has converged when its step is below this, relative to max(1, |x|).
const NEWTON_STEP_TOL: f64 = 1e-14;
/// Newton steps taken after convergence to polish the point to round-off.
const POLISH_STEPS: usize = 2;
/// Two stationary points closer than this (largest coordinate difference) are one.
const SAME_POINT_TOL: f64 = 1e-8;
/// An eigenvalue below this fraction of the largest |eigenvalue| counts as zero.
const ZERO_EIGENVALUE_REL: f64 = 1e-12;

/// A coordinate of the energy.
#[derive(Clone, Debug)]
pub struct Coordinate {
    pub name: String,
    /// How the coordinate is read from the simulated state.
    pub measured: Expr,
    /// Angle coordinates are compared wrapped.
    pub class: ErrorClass,
    /// Extra Newton starts: (from, to, count).
    pub scan: Option<(f64, f64, usize)>,
}

/// The compiled energy model. Its expressions are compiled against the model's symbols
/// followed by the coordinates (at `first_coordinate..`).
#[derive(Clone, Debug)]
pub struct EnergySpec {
    pub potential: Expr,
    pub gradient: Vec<Expr>,
    /// Row-major, `n x n`.
    pub hessian: Vec<Expr>,
    pub coordinates: Vec<Coordinate>,
    pub first_coordinate: usize,
    /// On the distance from the settled coordinates to the stationary point they landed on.
    pub tolerance: f64,
    /// The kinetic energy and what it gives (`[energy] kinetic`), if the file states one.
    pub dynamics: Option<super::dynamics::Dynamics>,
}

/// How a stationary point is classified by the Hessian's eigenvalues.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Minimum,
    Maximum,
    Saddle,
    /// An eigenvalue is zero (to round-off): the second-order test says nothing.
    Degenerate,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Minimum => "minimum",
            Kind::Maximum => "maximum",
            Kind::Saddle => "saddle",
            Kind::Degenerate => "degenerate",
        }
    }

    fn of(eigenvalues: &[f64]) -> Kind {
        let scale = eigenvalues.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        if eigenvalues.iter().any(|e| e.abs() <= ZERO_EIGENVALUE_REL * scale) || scale == 0.0 {
            Kind::Degenerate
        } else if eigenvalues.iter().all(|e| *e > 0.0) {
            Kind::Minimum
        } else if eigenvalues.iter().all(|e| *e < 0.0) {
            Kind::Maximum
        } else {
            Kind::Saddle
        }
    }
}

/// A stationary point of the potential.
#[derive(Clone, Debug, PartialEq)]
pub struct Stationary {
    pub coordinates: Vec<f64>,
    pub energy: f64,
    /// The Hessian's eigenvalues, ascending (the stiffnesses along its eigenvectors).
    pub eigenvalues: Vec<f64>,
    pub kind: Kind,
}

impl EnergySpec {
    fn n(&self) -> usize {
        self.coordinates.len()
    }

    /// `values` with the coordinates set to `x`.
    fn at(&self, values: &mut [f64], x: &[f64]) {
        values[self.first_coordinate..self.first_coordinate + x.len()].copy_from_slice(x);
    }

    fn gradient_at(&self, values: &[f64]) -> DVector<f64> {
        DVector::from_iterator(self.n(), self.gradient.iter().map(|g| g.eval(values)))
    }

    fn hessian_at(&self, values: &[f64]) -> DMatrix<f64> {
        let n = self.n();
        DMatrix::from_fn(n, n, |i, j| self.hessian[i * n + j].eval(values))
    }

    /// The coordinates as measured in the state `values` (the model's symbols).
    pub fn measured(&self, values: &[f64]) -> Vec<f64> {
        self.coordinates.iter().map(|c| c.measured.eval(values)).collect()
    }

    /// The largest coordinate difference, angles wrapped.
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.coordinates.iter().zip(a.iter().zip(b)).fold(0.0, |m, (c, (x, y))| {
            let d = if c.class == ErrorClass::Angle { wrap_angle(x - y) } else { x - y };
            m.max(d.abs())
        })
    }

    /// The stationary point Newton's method reaches from `x0`, if it converges.
    fn newton(&self, values: &mut [f64], x0: &[f64]) -> Option<Vec<f64>> {
        let mut x = DVector::from_column_slice(x0);
        let mut converged = None;
        for step in 0..MAX_NEWTON_STEPS {
            self.at(values, x.as_slice());
            let dx = self.hessian_at(values).lu().solve(&self.gradient_at(values))?;
            x -= &dx;
            if !x.iter().all(|v| v.is_finite()) {
                return None;
            }
            let small = dx.amax() <= NEWTON_STEP_TOL * x.amax().max(1.0);
            match converged {
                None if small => converged = Some(step),
                Some(at) if step >= at + POLISH_STEPS => break,
                _ => {}
            }
        }
        converged.map(|_| self.wrapped(x.as_slice()))
    }

    /// Angle coordinates wrapped to (-pi, pi].
    fn wrapped(&self, x: &[f64]) -> Vec<f64> {
        self.coordinates
            .iter()
            .zip(x)
            .map(|(c, v)| if c.class == ErrorClass::Angle { wrap_angle(*v) } else { *v })
            .collect()
    }

    /// The Newton starts: `first`, then the grid of every coordinate's scan (a coordinate
    /// without one stays at its value in `first`).
    fn starts(&self, first: &[f64]) -> Vec<Vec<f64>> {
        let mut out = vec![first.to_vec()];
        let mut grid = vec![first.to_vec()];
        for (i, c) in self.coordinates.iter().enumerate() {
            if let Some((from, to, count)) = c.scan {
                let step = if count > 1 { (to - from) / (count - 1) as f64 } else { 0.0 };
                grid = grid
                    .iter()
                    .flat_map(|p| {
                        (0..count).map(move |k| {
                            let mut q = p.clone();
                            q[i] = from + step * k as f64;
                            q
                        })
                    })
                    .collect();
            }
        }
        if self.coordinates.iter().any(|c| c.scan.is_some()) {
            out.extend(grid);
        }
        out
    }

    /// Every stationary point reached from `first` and from the scan, with the parameters and
    /// inputs in `values` (the model's symbols followed by room for the coordinates).
    pub fn stationary_points(&self, values: &mut [f64], first: &[f64]) -> Vec<Stationary> {
        let mut found: Vec<Stationary> = Vec::new();
        for start in self.starts(first) {
            let Some(x) = self.newton(values, &start) else { continue };
            if found.iter().any(|s| self.distance(&s.coordinates, &x) <= SAME_POINT_TOL) {
                continue;
            }
            self.at(values, &x);
            let eigen = SymmetricEigen::new(self.hessian_at(values));
            let mut eigenvalues: Vec<f64> = eigen.eigenvalues.iter().copied().collect();
            eigenvalues.sort_by(f64::total_cmp);
            let kind = Kind::of(&eigenvalues);
            found.push(Stationary { energy: self.potential.eval(values), coordinates: x, eigenvalues, kind });
        }
        found
    }
}
