//! Static relaxation (`sim.relaxation`, default on where it applies), a settling strategy for
//! structures of free bodies held by springs and elastic cables, with gravity and constant
//! external loads: no joints and no inextensible cables.
//!
//! Such a structure has a potential energy E (the members' 1/2 k (l - l0)^2, tension-only for
//! cables, and the work of the constant loads), and its static equilibria are the stationary
//! points of E. Before every step the relaxation assembles, for the six coordinates of each
//! free body (a translation of its centre of mass and a small rotation about it, world frame),
//! the generalized force f = -grad E and the exact Hessian H of E from the force laws:
//! per member J^T K_m J with K_m = k e e^T + (t / l)(1 - e e^T) (the tangent stiffness of a
//! member of tension t, length l, unit e) and J the Jacobian of a node's position, plus the
//! geometric term of the rotations, (F . rho) 1 - sym(F rho^T) for a node force F at the arm
//! rho from the centre of mass. It then takes a saddle-free Newton step
//! dx = |H|^-1 f (in the mass-weighted modes: each mode of stiffness lambda moves by its
//! force over |lambda|; modes softer than [`SOFT_MODE_RATIO`] of the stiffest, such as a free
//! rotation of the whole structure, are left to the dynamics), shortened until E decreases
//! (Armijo), and zeroes every body's velocity (kinetic damping). Then the ordinary rapier step
//! follows. Without a step (no stiffness at all, as a body in free fall) the velocities stay.
//!
//! - The equilibrium stays the dynamics' own: at an equilibrium f = 0 and the step is zero,
//!   and the settle loop turns the relaxation off once the motion has stopped, so that its
//!   quiet window and residual check are plain rapier steps.
//! - Unstable equilibria are not stabilised: every accepted step lowers E, and along a mode of
//!   negative stiffness the step |lambda|^-1 f points away from the equilibrium (the force
//!   there pushes away), so the state leaves it as the dynamics would.

use super::Simulation;
use crate::structure::{CableLaw, Structure};
use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen, Vector3};
use rapier3d_f64::prelude::*;
use std::ops::AddAssign;

/// Mass-weighted modes whose stiffness (as |omega^2|) is below this fraction of the stiffest
/// are not stepped (a near-free motion: its Newton step would amplify round-off).
const SOFT_MODE_RATIO: f64 = 1e-9;
/// Sufficient decrease of the line search (Armijo's constant).
const ARMIJO: f64 = 1e-4;
/// Trials (each with a larger shift) before the step is given up for this tick (the dynamics
/// then move alone).
const MAX_TRIALS: usize = 40;
/// Factor by which the shift grows after a rejected trial.
const SHIFT_GROWTH: f64 = 10.0;
/// Factor by which the shift shrinks after an accepted step.
const SHIFT_DECAY: f64 = 0.25;
/// Shift (as a fraction of the stiffest mode) taken first after a rejected unshifted trial;
/// below it the shift drops to zero (the pure Newton step, quadratic convergence).
const MIN_SHIFT_RATIO: f64 = 1e-8;
/// Relative round-off of the energy: a predicted decrease below this fraction of the energy's
/// scale cannot be checked against the computed energies and is accepted (Newton's regime).
const ENERGY_ROUND_OFF: f64 = 1e-12;
/// Largest translation of a body in one step, as a fraction of the structure's size.
const MAX_STEP_FRACTION: f64 = 0.25;
/// Largest rotation of a body in one step [rad].
const MAX_STEP_ROTATION_RAD: f64 = 0.5;

/// Whether the relaxation can settle `s`: free bodies held only by springs and elastic cables
/// (no joints, no inextensible cables), and at least one free body.
pub(super) fn applies(s: &Structure) -> bool {
    s.joints.is_empty()
        && s.cables.iter().all(|c| matches!(c.law, CableLaw::Elastic { .. }))
        && s.bodies.iter().any(|b| b.kind == crate::structure::BodyKind::Free)
}

fn v3(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

fn cross_matrix(r: Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -r.z, r.y, r.z, 0.0, -r.x, -r.y, r.x, 0.0)
}

/// The mass-weighted modes of the Hessian at the current state, and the generalized force in
/// them.
struct Modes {
    eig: SymmetricEigen<f64, nalgebra::Dyn>,
    /// 1 / sqrt(mass or inertia) of each coordinate.
    weight: DVector<f64>,
    /// The generalized force, mass-weighted.
    force: DVector<f64>,
    /// The largest |omega^2| [1/s^2].
    stiffest: f64,
}

impl Modes {
    fn new(dofs: &Dofs, h: &DMatrix<f64>, f: &DVector<f64>) -> Self {
        let n = f.len();
        let weight = DVector::from_fn(n, |r, _| {
            let (mass, inertia) = dofs.scale[r / 6];
            1.0 / if r % 6 < 3 { mass } else { inertia }.sqrt()
        });
        let a = DMatrix::from_fn(n, n, |r, c| weight[r] * 0.5 * (h[(r, c)] + h[(c, r)]) * weight[c]);
        let eig = SymmetricEigen::new(a);
        let stiffest = eig.eigenvalues.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        Modes { eig, force: f.component_mul(&weight), weight, stiffest }
    }

    /// The saddle-free Newton step, shifted: each mode of stiffness lambda moves by its force
    /// over |lambda| + shift (shift as a fraction of the stiffest mode); soft modes stay.
    fn step(&self, shift: f64) -> DVector<f64> {
        let mut y = DVector::zeros(self.force.len());
        for (k, lambda) in self.eig.eigenvalues.iter().enumerate() {
            if lambda.abs() > SOFT_MODE_RATIO * self.stiffest {
                let mode = self.eig.eigenvectors.column(k);
                y += mode * (mode.dot(&self.force) / (lambda.abs() + shift * self.stiffest));
            }
        }
        y.component_mul(&self.weight)
    }
}

/// The free bodies' coordinates: for each structure body its block index, if free.
struct Dofs {
    index: Vec<Option<usize>>,
    /// Centre of mass of each free body, in block order [m].
    com: Vec<Vector>,
    /// Mass [kg] and mean principal moment of inertia [kg m^2] of each free body.
    scale: Vec<(f64, f64)>,
}

impl Simulation {
    fn relaxation_dofs(&self) -> Dofs {
        let s = &self.model.structure;
        let mut dofs = Dofs { index: vec![None; s.bodies.len()], com: Vec::new(), scale: Vec::new() };
        for b in (0..s.bodies.len()).filter(|b| self.is_free(*b)) {
            let inertia = s.bodies[b].inertia.expect("free bodies have inertia");
            dofs.index[b] = Some(dofs.com.len());
            dofs.com.push(self.world_com(b));
            let p = inertia.principal_kg_m2;
            dofs.scale.push((inertia.mass_kg, ((p[0] + p[1] + p[2]) / 3.0).max(f64::MIN_POSITIVE)));
        }
        dofs
    }

    /// Constant loads on body `b` (gravity, external and probe loads): force [N], torque [N m].
    fn constant_load(&self, b: usize) -> (Vector3<f64>, Vector3<f64>) {
        let s = &self.model.structure;
        let g = Vector3::from(s.gravity);
        let mass = s.bodies[b].inertia.map_or(0.0, |i| i.mass_kg);
        let (probe_f, probe_t) = self.probe_loads[b];
        let f = g * mass + Vector3::from(probe_f) + Vector3::from(self.model.external_loads[b]);
        (f, Vector3::from(probe_t))
    }

    /// The generalized force f = -grad E and the Hessian H of the energy, six coordinates per
    /// free body (translation, then rotation).
    fn relaxation_system(&self, dofs: &Dofs) -> (DMatrix<f64>, DVector<f64>) {
        let s = &self.model.structure;
        let n = 6 * dofs.com.len();
        let mut h = DMatrix::zeros(n, n);
        let mut f = DVector::zeros(n);
        // Node Jacobian J = [1, -[rho]x] of the node's block, if its body is free.
        let jacobian = |node: usize, p: Vector3<f64>| -> Option<(usize, nalgebra::Matrix3x6<f64>)> {
            let i = dofs.index[s.nodes[node].body]?;
            let rho = p - v3(dofs.com[i]);
            let mut j = nalgebra::Matrix3x6::zeros();
            j.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
            j.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-cross_matrix(rho)));
            Some((i, j))
        };
        for m in (0..s.springs.len() + s.cables.len()).filter_map(|i| self.elastic_member(i)) {
            let (pa, pb) = (Vector3::from(self.node_position(m.a)), Vector3::from(self.node_position(m.b)));
            let d = pb - pa;
            let l = d.norm();
            if l <= 0.0 || !m.engaged(l) {
                continue;
            }
            let (t, e) = (m.tension_n(l), d / l);
            let km = e * e.transpose() * m.stiffness_n_per_m + (Matrix3::identity() - e * e.transpose()) * (t / l);
            let ends = [(jacobian(m.a, pa), pa, e * t), (jacobian(m.b, pb), pb, -e * t)];
            for (x, (jx, px, fx)) in ends.iter().enumerate() {
                let Some((i, ji)) = jx else { continue };
                let rho = px - v3(dofs.com[*i]);
                f.fixed_rows_mut::<6>(6 * i).add_assign(&(ji.transpose() * fx));
                // Geometric term of the rotation: (F . rho) 1 - sym(F rho^T).
                let geo = Matrix3::identity() * fx.dot(&rho) - (fx * rho.transpose() + rho * fx.transpose()) * 0.5;
                h.fixed_view_mut::<3, 3>(6 * i + 3, 6 * i + 3).add_assign(&geo);
                for (y, (jy, _, _)) in ends.iter().enumerate() {
                    let Some((k, jk)) = jy else { continue };
                    let sign = if x == y { 1.0 } else { -1.0 };
                    let block = ji.transpose() * km * jk * sign;
                    h.fixed_view_mut::<6, 6>(6 * i, 6 * k).add_assign(&block);
                }
            }
        }
        for (b, i) in dofs.index.iter().enumerate().filter_map(|(b, i)| i.map(|i| (b, i))) {
            let (force, torque) = self.constant_load(b);
            f.fixed_rows_mut::<3>(6 * i).add_assign(&force);
            f.fixed_rows_mut::<3>(6 * i + 3).add_assign(&torque);
        }
        (h, f)
    }

    /// Node position after moving every free body by `alpha` times `step` [m].
    fn moved_node(&self, dofs: &Dofs, step: &DVector<f64>, alpha: f64, node: usize) -> Vector3<f64> {
        let p = Vector3::from(self.node_position(node));
        let Some(i) = dofs.index[self.model.structure.nodes[node].body] else { return p };
        let c = v3(dofs.com[i]);
        let u = step.fixed_rows::<3>(6 * i) * alpha;
        let theta = step.fixed_rows::<3>(6 * i + 3) * alpha;
        let rotation = nalgebra::Rotation3::new(theta);
        c + u + rotation * (p - c)
    }

    /// Energy after moving by `alpha` times `step`, less the energy now [J], and the energy's
    /// scale (the sum of the magnitudes of its terms) [J].
    fn relaxation_energy_change(&self, dofs: &Dofs, step: &DVector<f64>, alpha: f64) -> (f64, f64) {
        let s = &self.model.structure;
        let (mut change, mut scale) = (0.0, 0.0);
        for m in (0..s.springs.len() + s.cables.len()).filter_map(|i| self.elastic_member(i)) {
            let energy = |pa: Vector3<f64>, pb: Vector3<f64>| {
                let l = (pb - pa).norm();
                if m.engaged(l) {
                    0.5 * m.stiffness_n_per_m * (l - m.rest_length_m).powi(2)
                } else {
                    0.0
                }
            };
            let now = energy(Vector3::from(self.node_position(m.a)), Vector3::from(self.node_position(m.b)));
            let then = energy(self.moved_node(dofs, step, alpha, m.a), self.moved_node(dofs, step, alpha, m.b));
            change += then - now;
            scale += now.abs() + then.abs();
        }
        for (b, i) in dofs.index.iter().enumerate().filter_map(|(b, i)| i.map(|i| (b, i))) {
            let (force, torque) = self.constant_load(b);
            let work = (force.dot(&step.fixed_rows::<3>(6 * i)) + torque.dot(&step.fixed_rows::<3>(6 * i + 3))) * alpha;
            change -= work;
            scale += work.abs() + force.norm() * self.model.length_scale_m;
        }
        (change, scale)
    }

    /// The largest fraction (at most 1) of `step` that keeps every body within the step limits.
    fn relaxation_step_limit(&self, dofs: &Dofs, step: &DVector<f64>) -> f64 {
        let max_shift = MAX_STEP_FRACTION * self.model.length_scale_m;
        (0..dofs.com.len()).fold(1.0_f64, |alpha, i| {
            let shift = step.fixed_rows::<3>(6 * i).norm();
            let turn = step.fixed_rows::<3>(6 * i + 3).norm();
            alpha.min(max_shift / shift.max(f64::MIN_POSITIVE)).min(MAX_STEP_ROTATION_RAD / turn.max(f64::MIN_POSITIVE))
        })
    }

    /// One relaxation step (before the member forces are applied): the shifted Newton step on
    /// the energy, its shift raised until the energy decreases (Levenberg-Marquardt), then
    /// every free body at rest. Without a step (no stiffness, as a body in free fall, or no
    /// decrease found) the velocities stay: the dynamics move alone.
    #[inline(never)]
    pub(super) fn relax(&mut self) {
        let dofs = self.relaxation_dofs();
        let (h, f) = self.relaxation_system(&dofs);
        let modes = Modes::new(&dofs, &h, &f);
        let mut shift = self.relaxation_shift;
        for trial in 1..=MAX_TRIALS {
            let step = modes.step(shift);
            let predicted = f.dot(&step);
            if predicted.is_nan() || predicted <= 0.0 {
                break;
            }
            // A step beyond the limits is a rejected trial (the shift shortens the soft modes'
            // steps first, where a common factor would shorten the stiff ones' as much); the
            // last trial is cut to the limits instead.
            let alpha = self.relaxation_step_limit(&dofs, &step);
            if alpha < 1.0 && trial < MAX_TRIALS {
                shift = if shift == 0.0 { MIN_SHIFT_RATIO } else { shift * SHIFT_GROWTH };
                continue;
            }
            let (change, scale) = self.relaxation_energy_change(&dofs, &step, alpha);
            let round_off = alpha * predicted <= ENERGY_ROUND_OFF * scale;
            if change <= -ARMIJO * alpha * predicted || round_off {
                self.move_bodies(&dofs, &step, alpha);
                self.zero_body_velocities();
                let next = shift * SHIFT_DECAY;
                self.relaxation_shift = if next < MIN_SHIFT_RATIO { 0.0 } else { next };
                break;
            }
            shift = if shift == 0.0 { MIN_SHIFT_RATIO } else { shift * SHIFT_GROWTH };
        }
    }

    /// Moves every free body by `alpha` times `step` (translation of the centre of mass, then
    /// rotation about it).
    fn move_bodies(&mut self, dofs: &Dofs, step: &DVector<f64>, alpha: f64) {
        for (b, i) in dofs.index.iter().enumerate().filter_map(|(b, i)| i.map(|i| (b, i))) {
            let u = step.fixed_rows::<3>(6 * i) * alpha;
            let theta = step.fixed_rows::<3>(6 * i + 3) * alpha;
            let com = dofs.com[i];
            let turn = Rotation::from_scaled_axis(Vector::new(theta.x, theta.y, theta.z));
            let h = self.model.handles[b];
            let pose = *self.bodies[h].position();
            let moved = Pose::from_translation(com + Vector::new(u.x, u.y, u.z))
                * Pose::from_rotation(turn)
                * Pose::from_translation(-com)
                * pose;
            self.bodies[h].set_position(moved, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two free bodies hung from a fixed triangle by cables stretched to 1.6 times their rest
    /// length, joined by a spring compressed to 0.8 times its free length, with gravity.
    fn hung_bodies() -> Simulation {
        use crate::structure::{BodyKind, Cable, Inertia, Spring};
        let mut s = Structure { gravity: [0.0, 0.0, -9.81], ..Default::default() };
        let ground = s.add_body("ground", BodyKind::Fixed, None);
        let fixed = [("g0", [0.0, 0.0, 2.0]), ("g1", [1.0, 0.0, 2.0]), ("g2", [0.0, 1.0, 2.0])]
            .map(|(name, p)| s.add_node(name, ground, p));
        let inertia = |com| Inertia { mass_kg: 0.7, com, principal_kg_m2: [0.05, 0.08, 0.03] };
        let one = s.add_body("one", BodyKind::Free, Some(inertia([0.55, 0.4, 1.2])));
        let two = s.add_body("two", BodyKind::Free, Some(inertia([0.1, 0.1, 1.2])));
        let (p, q) = (s.add_node("p", one, [0.3, 0.2, 1.0]), s.add_node("q", one, [0.8, 0.6, 1.4]));
        let (r, u) = (s.add_node("r", two, [-0.2, 0.5, 0.8]), s.add_node("u", two, [0.4, -0.3, 1.6]));
        let length =
            |s: &Structure, a: usize, b: usize| crate::structure::distance(s.nodes[a].position, s.nodes[b].position);
        for (a, b) in [(fixed[0], p), (fixed[1], p), (fixed[2], q), (fixed[0], r), (fixed[1], u), (fixed[2], u), (q, r)]
        {
            let law = CableLaw::Elastic { stiffness_n_per_m: 150.0 };
            let length_m = length(&s, a, b) / 1.6;
            s.cables.push(Cable { name: format!("c{a}{b}"), a, b, law, length_m, radius_m: 0.001 });
        }
        let rest_length_m = length(&s, p, u) / 0.8;
        s.springs.push(Spring {
            name: "s".into(),
            a: p,
            b: u,
            stiffness_n_per_m: 80.0,
            rest_length_m,
            radius_m: 0.001,
        });
        Simulation::new(&s, &crate::settings::SimSettings::default()).unwrap()
    }

    /// Away from equilibrium (tension, compression and gravity), f is minus the gradient of
    /// the energy and H its Hessian in the bodies' coordinates: central differences of the energy agree within 1e-6 of the largest
    /// entry (step 1e-4 m or rad).
    #[test]
    fn force_and_hessian_are_the_derivatives_of_the_energy() {
        let sim = hung_bodies();
        let dofs = sim.relaxation_dofs();
        let (h, f) = sim.relaxation_system(&dofs);
        let n = f.len();
        let step = 1e-4;
        let energy = |d: &DVector<f64>| sim.relaxation_energy_change(&dofs, d, 1.0).0;
        let unit = |i: usize| DVector::from_fn(n, |r, _| if r == i { step } else { 0.0 });
        let largest_f = f.amax();
        let largest_h = h.amax();
        for i in 0..n {
            let grad = (energy(&unit(i)) - energy(&-unit(i))) / (2.0 * step);
            assert!((grad + f[i]).abs() <= 1e-6 * largest_f, "f[{i}] = {} against {}", f[i], -grad);
            for j in 0..n {
                let (ei, ej) = (unit(i), unit(j));
                let second = (energy(&(&ei + &ej)) - energy(&(&ei - &ej)) - energy(&(&ej - &ei))
                    + energy(&(-&ei - &ej)))
                    / (4.0 * step * step);
                let sym = 0.5 * (h[(i, j)] + h[(j, i)]);
                assert!((sym - second).abs() <= 1e-6 * largest_h, "H[{i},{j}] = {sym} against {second}");
            }
        }
    }

    /// The cross-product matrix reproduces r x v.
    #[test]
    fn cross_matrix_is_the_cross_product() {
        let (r, x) = (Vector3::new(0.3, -1.2, 2.0), Vector3::new(-0.7, 0.4, 1.1));
        assert!((cross_matrix(r) * x - r.cross(&x)).norm() <= 1e-15);
    }
}
