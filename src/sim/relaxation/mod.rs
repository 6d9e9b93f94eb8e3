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
//! rho from the centre of mass (`assemble.rs`, as 6x6 blocks per pair of coupled bodies). Up
//! to [`DENSE_MAX_BODIES`] free bodies it takes a saddle-free Newton step dx = |H|^-1 f
//! (`dense.rs`, in the mass-weighted modes: each mode of stiffness lambda moves by its
//! force over |lambda|; modes softer than [`SOFT_MODE_RATIO`] of the stiffest, such as a free
//! rotation of the whole structure, are left to the dynamics); above, the Levenberg-Marquardt
//! step dx = (H + mu M)^-1 f from a sparse Cholesky factorization (`sparse.rs`, bodies in
//! reverse Cuthill-McKee order, `ordering.rs`; the free rigid motions removed). The shift is
//! raised until E decreases (Armijo, `energy.rs`), and every body's velocity is zeroed
//! (kinetic damping). Then the ordinary rapier step follows. Without a step (no stiffness at
//! all, as a body in free fall) the velocities stay.
//!
//! - The equilibrium stays the dynamics' own: at an equilibrium f = 0 and the step is zero,
//!   and the settle loop turns the relaxation off once the motion has stopped, so that its
//!   quiet window and residual check are plain rapier steps.
//! - Unstable equilibria are not stabilised: every accepted step lowers E, and along a mode of
//!   negative stiffness the step |lambda|^-1 f (sparse: (lambda + mu)^-1 f, mu raised until
//!   H + mu M factorizes, so lambda + mu > 0) points away from the equilibrium (the force
//!   there pushes away), so the state leaves it as the dynamics would.

mod assemble;
mod dense;
mod line_search;
mod lowest_modes;
mod modal_solve;
mod sparse;

use super::data::Data;
use super::model::Model;
use crate::structure::{BodyKind, Structure};
pub(crate) use modal_solve::ModalSolve;
use nalgebra::DVector;

/// Mass-weighted modes whose stiffness (as |omega^2|) is below this fraction of the stiffest
/// are not stepped by the dense step (a near-free motion: its Newton step would amplify
/// round-off); the sparse step's shift never falls below it.
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
/// A step in the energy's round-off (its predicted decrease below [`ENERGY_ROUND_OFF`] of the
/// energy's scale) is taken only while the largest generalized force component has fallen
/// below this fraction of its value at the last step (Newton's quadratic regime), or, once it
/// stalls, where the step itself lowers the force to this fraction and the force stands above
/// its own round-off ([`FORCE_ROUND_OFF`]). A force in its round-off is noise: a step would
/// move the soft modes by that noise over their stiffness at every tick, so the structure
/// would never be seen at rest (a 1000-strut prism: 1e-14 m per step, above the 1e-12 m/s
/// speed test). A force above it is not, though the energy cannot see it: the energy's
/// round-off is that of a sum over every member, and on a 150-strut prism with heavy cables
/// (13,000 members) a force of 6e-6 N along a stiff mode lowers the energy by 1.6e-12 J, what
/// the sum of 1.6 J resolves.
const STALL_RATIO: f64 = 0.5;
/// Relative round-off of the generalized force, as a fraction of the largest member tension or
/// constant load: a sum of a few terms of that size, each to 1e-16, leaves 1e-14 of it; 1e-12
/// leaves room for the thousands of terms of a heavy cable's beads.
const FORCE_ROUND_OFF: f64 = 1e-12;
/// Largest translation of a body in one step, as a fraction of the structure's size.
const MAX_STEP_FRACTION: f64 = 0.25;
/// Largest rotation of a body in one step [rad].
const MAX_STEP_ROTATION_RAD: f64 = 0.5;
/// Free bodies up to which the step is dense (the Hessian's eigendecomposition: the exact
/// saddle-free step, twist errors 2e-16 to 4e-16 rad on the 3- to 8-strut prisms against up
/// to 4e-15 sparse); above, the sparse Cholesky step. Per relaxation step on n-strut prisms
/// (n - 1 free bodies), dense against sparse: 0.05 against 0.04 ms at n = 6, 0.12 against
/// 0.05 ms at n = 8, 0.28 against 0.07 ms at n = 12, 50 against 1 ms at n = 64
/// (BENCHMARKS.md).
const DENSE_MAX_BODIES: usize = 8;

/// Whether the relaxation can settle `s`: free bodies held only by springs and elastic cables
/// (no joints, no inextensible cables), and at least one free body.
pub(super) fn applies(s: &Structure) -> bool {
    s.joints.is_empty()
        && !s.members.iter().any(|c| c.is_inextensible_cable() || c.has_friction())
        && s.bodies.iter().any(|b| b.kind == BodyKind::Free)
}

/// A solver of the shifted step: the step at `shift` (a fraction of the stiffest mode), or
/// `None` where that shift gives none (the sparse factorization of an indefinite matrix).
trait StepSolver {
    fn step(&mut self, shift: f64) -> Option<DVector<f64>>;
}

/// The next shift after a rejected trial.
fn raised(shift: f64) -> f64 {
    if shift == 0.0 {
        MIN_SHIFT_RATIO
    } else {
        shift * SHIFT_GROWTH
    }
}

/// The tangent stiffness of the free bodies at the current state (`sim::modes` reads it): the
/// dense, symmetrized Hessian of the potential energy (N/m, N, N m/rad) over six coordinates
/// per free body (translation of the centre of mass, then a small rotation about it, world
/// frame), blocks in the order of [`Data::free_blocks`].
pub(super) struct Tangent {
    pub(super) hessian: nalgebra::DMatrix<f64>,
}

/// The static relaxation's state: whether it runs before each step, its current shift and
/// the largest force at its last step.
pub(super) struct Relaxation {
    /// Whether the static relaxation runs before each step (the settings' choice where it
    /// applies; the settle loop turns it off for its quiet window).
    pub(super) on: bool,
    /// The current shift, a fraction of the stiffest mode.
    shift: f64,
    /// The largest generalized force component at the last step, for the test of a round-off
    /// stall.
    last_force: f64,
}

impl Default for Relaxation {
    fn default() -> Self {
        Relaxation { on: false, shift: 0.0, last_force: f64::INFINITY }
    }
}

impl Relaxation {
    /// One relaxation step (before the member forces are applied): the shifted Newton step on
    /// the energy, its shift raised until the energy decreases (Levenberg-Marquardt), then
    /// every free body at rest. Without a step (no stiffness, as a body in free fall, or no
    /// decrease found) the velocities stay: the dynamics move alone.
    #[inline(never)]
    pub(super) fn relax(&mut self, m: &Model, d: &mut Data) {
        let dofs = d.relaxation_dofs(m);
        let system = d.relaxation_system(m, &dofs);
        let f = &system.force;
        let last_force = std::mem::replace(&mut self.last_force, f.amax());
        let stalled = f.amax() > STALL_RATIO * last_force;
        let mut solver = d.relaxation_solver(m, &dofs, &system);
        let mut shift = self.shift;
        for trial in 1..=MAX_TRIALS {
            let Some(step) = solver.step(shift) else {
                shift = raised(shift);
                continue;
            };
            let predicted = f.dot(&step);
            if predicted.is_nan() || predicted <= 0.0 {
                break;
            }
            // A step beyond the limits is a rejected trial (the shift shortens the soft modes'
            // steps first, where a common factor would shorten the stiff ones' as much); the
            // last trial is cut to the limits instead.
            let alpha = d.relaxation_step_limit(m, &dofs, &step);
            if alpha < 1.0 && trial < MAX_TRIALS {
                shift = raised(shift);
                continue;
            }
            let (change, scale) = d.relaxation_energy_change(m, &dofs, &step, alpha);
            let round_off = alpha * predicted <= ENERGY_ROUND_OFF * scale;
            if round_off && stalled && !self.halves(m, d, &dofs, &system, &step, alpha) {
                break;
            }
            if change <= -ARMIJO * alpha * predicted || round_off {
                d.move_bodies(m, &dofs, &step, alpha);
                d.zero_body_velocities(m);
                let next = shift * SHIFT_DECAY;
                self.shift = if next < MIN_SHIFT_RATIO { 0.0 } else { next };
                break;
            }
            shift = raised(shift);
        }
    }

    /// Whether a step in the energy's round-off, taken after the force stalled, is taken all
    /// the same: the force stands above its own round-off ([`FORCE_ROUND_OFF`] of the largest
    /// tension or load) and the step lowers it to [`STALL_RATIO`] of itself.
    fn halves(
        &self,
        m: &Model,
        d: &Data,
        dofs: &assemble::Dofs,
        system: &assemble::System,
        step: &DVector<f64>,
        alpha: f64,
    ) -> bool {
        let now = system.force.amax();
        now > FORCE_ROUND_OFF * system.force_scale_n
            && d.relaxation_force_after(m, dofs, step, alpha) <= STALL_RATIO * now
    }
}

impl Data {
    /// The Hessian the relaxation assembles, at the current state.
    pub(super) fn tangent_stiffness(&self, m: &Model) -> Tangent {
        let dofs = self.relaxation_dofs(m);
        Tangent { hessian: self.relaxation_system(m, &dofs).dense() }
    }

    /// The free bodies in the order of the relaxation's blocks: each block's structure body
    /// and centre of mass [m].
    pub(super) fn free_blocks(&self, m: &Model) -> (Vec<usize>, Vec<nalgebra::Vector3<f64>>) {
        let dofs = self.relaxation_dofs(m);
        let mut bodies = vec![0; dofs.blocks()];
        for (b, i) in dofs.free() {
            bodies[i] = b;
        }
        (bodies, dofs.com.iter().map(|c| assemble::v3(*c)).collect())
    }

    /// Moves every free body by `step` (six coordinates per body, in the order of
    /// [`Simulation::tangent_stiffness`]'s blocks: translation of the centre of mass, then a
    /// rotation about it).
    pub(super) fn displace_free_bodies(&mut self, m: &Model, step: &nalgebra::DVector<f64>) {
        let dofs = self.relaxation_dofs(m);
        self.move_bodies(m, &dofs, step, 1.0);
    }

    /// The step solver for the structure's size: dense up to [`DENSE_MAX_BODIES`] free
    /// bodies, sparse above.
    fn relaxation_solver(&self, m: &Model, dofs: &assemble::Dofs, system: &assemble::System) -> Box<dyn StepSolver> {
        if dofs.blocks() <= DENSE_MAX_BODIES {
            Box::new(dense::Modes::new(dofs, system))
        } else {
            Box::new(sparse::ShiftedCholesky::new(dofs, system, &self.rigid_groups(m, dofs), m.length_scale_m))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::assemble::cross_matrix;
    use super::*;
    use crate::sim::Simulation;
    use nalgebra::{DMatrix, Vector3};

    /// Two free bodies hung from a fixed triangle by cables stretched to 1.6 times their rest
    /// length, joined by a spring compressed to 0.8 times its free length, with gravity.
    fn hung_bodies() -> Simulation {
        Simulation::new(&hung_structure(), &crate::settings::SimSettings::default()).unwrap()
    }

    fn hung_structure() -> Structure {
        use crate::structure::{BodyKind, CableLaw, Inertia, Member};
        let mut s = Structure { gravity: [0.0, 0.0, -9.81], ..Default::default() };
        let ground = s.add_body("ground", BodyKind::Fixed, None);
        let fixed = [("g0", [0.0, 0.0, 2.0]), ("g1", [1.0, 0.0, 2.0]), ("g2", [0.0, 1.0, 2.0])]
            .map(|(name, p)| s.add_node(name, ground, p));
        let inertia = |com| Inertia { mass_kg: 0.7, com, principal_kg_m2: [0.05, 0.08, 0.03] };
        // Centres of mass off the line of each body's two nodes: no free spin.
        let one = s.add_body("one", BodyKind::Free, Some(inertia([0.6, 0.35, 1.2])));
        let two = s.add_body("two", BodyKind::Free, Some(inertia([0.15, 0.1, 1.25])));
        let (p, q) = (s.add_node("p", one, [0.3, 0.2, 1.0]), s.add_node("q", one, [0.8, 0.6, 1.4]));
        let (r, u) = (s.add_node("r", two, [-0.2, 0.5, 0.8]), s.add_node("u", two, [0.4, -0.3, 1.6]));
        let length =
            |s: &Structure, a: usize, b: usize| crate::structure::distance(s.nodes[a].position, s.nodes[b].position);
        for (a, b) in [(fixed[0], p), (fixed[1], p), (fixed[2], q), (fixed[0], r), (fixed[1], u), (fixed[2], u), (q, r)]
        {
            let law = CableLaw::Elastic { stiffness_n_per_m: 150.0 };
            let length_m = length(&s, a, b) / 1.6;
            s.members.push(Member::cable(format!("c{a}{b}"), vec![a, b], law, length_m, 0.001));
        }
        let rest_length_m = length(&s, p, u) / 0.8;
        s.members.push(Member::spring("s", [p, u], 80.0, rest_length_m, 0.001));
        s
    }

    /// Away from equilibrium (tension, compression and gravity), f is minus the gradient of
    /// the energy and H its Hessian in the bodies' coordinates: central differences of the energy agree within 1e-6 of the largest
    /// entry (step 1e-4 m or rad).
    #[test]
    fn force_and_hessian_are_the_derivatives_of_the_energy() {
        assert_derivatives_of_the_energy(&hung_bodies());
    }

    /// The same with a clustered cable added, from the triangle's g0 through q (body one) and
    /// r (body two) to g2, stretched to 1.3 times its rest length: its material term couples
    /// all four nodes (k g g^T), its geometric term each segment's two.
    #[test]
    fn a_clustered_cables_force_and_hessian_are_the_derivatives_of_its_energy() {
        use crate::structure::{CableLaw, Member};
        let mut s = hung_structure();
        let id = |name: &str| s.node_id(name).unwrap();
        let path = vec![id("g0"), id("q"), id("r"), id("g2")];
        let drawn = Member::cable("clustered", path.clone(), CableLaw::Inextensible, 1.0, 0.001)
            .length_at(|n| s.nodes[n].position);
        let law = CableLaw::Elastic { stiffness_n_per_m: 120.0 };
        s.members.push(Member::cable("clustered", path, law, drawn / 1.3, 0.001));
        assert_derivatives_of_the_energy(&Simulation::new(&s, &crate::settings::SimSettings::default()).unwrap());
    }

    /// The same with point loads: one at node q of body one, off its centre of mass (its
    /// work turns the body: the rotations' geometric term), one at node r of body two.
    #[test]
    fn a_point_loads_force_and_hessian_are_the_derivatives_of_its_work() {
        use crate::structure::NodeLoad;
        let mut s = hung_structure();
        let id = |name: &str| s.node_id(name).unwrap();
        let (q, r) = (id("q"), id("r"));
        s.node_loads.push(NodeLoad { node: q, force_n: [3.0, -1.5, 2.0] });
        s.node_loads.push(NodeLoad { node: r, force_n: [-0.5, 4.0, -2.5] });
        assert_derivatives_of_the_energy(&Simulation::new(&s, &crate::settings::SimSettings::default()).unwrap());
    }

    fn assert_derivatives_of_the_energy(sim: &Simulation) {
        let dofs = sim.data.relaxation_dofs(&sim.model);
        let system = sim.data.relaxation_system(&sim.model, &dofs);
        let (h, f) = (system.dense(), system.force);
        let n = f.len();
        let step = 1e-4;
        let energy = |d: &DVector<f64>| sim.data.relaxation_energy_change(&sim.model, &dofs, d, 1.0).0;
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
                let h = h[(i, j)];
                assert!((h - second).abs() <= 1e-6 * largest_h, "H[{i},{j}] = {h} against {second}");
            }
        }
    }

    /// The sparse step solves (H + mu M) dx = f (M the masses and mean inertias): against a
    /// dense solve of the same system, within 1e-10 of the step's size, at two shifts that
    /// make it positive definite; at one that does not, there is no step.
    #[test]
    fn the_sparse_step_solves_the_shifted_newton_system() {
        let sim = hung_bodies();
        let dofs = sim.data.relaxation_dofs(&sim.model);
        let system = sim.data.relaxation_system(&sim.model, &dofs);
        let mut solver = sparse::ShiftedCholesky::new(&dofs, &system, &sim.data.rigid_groups(&sim.model, &dofs), 1.0);
        let mass = dofs.weight().map(|w| 1.0 / (w * w));
        // The mass-weighted Hessian's lowest mode is -267 1/s^2 (the compressed spring, the
        // cables' geometric stiffness), the Gershgorin bound 2249 1/s^2: a shift of 0.1 of it
        // leaves H + mu M indefinite, and there is no step.
        assert!(solver.step(0.1).is_none(), "indefinite at mu = {}", solver.mu(0.1));
        for shift in [1.0, 0.2] {
            let dx = solver.step(shift).expect("positive definite at this shift");
            let shifted = system.dense() + DMatrix::from_diagonal(&(&mass * solver.mu(shift)));
            let expected = shifted.cholesky().expect("positive definite").solve(&system.force);
            assert!((&dx - &expected).amax() <= 1e-10 * expected.amax(), "shift {shift}: {dx} against {expected}");
        }
    }

    /// A free group (no member to a fixed body) has six rigid motions: the sparse step has no
    /// component along them, so a body in free fall under gravity gets no step (f has only
    /// the rigid component) and the dynamics move it.
    #[test]
    fn the_sparse_step_leaves_the_rigid_motions_of_a_free_group_alone() {
        use crate::structure::{Inertia, Member};
        let mut s = Structure { gravity: [0.0, 0.0, -9.81], ..Default::default() };
        let inertia = |com| Inertia { mass_kg: 0.5, com, principal_kg_m2: [0.02, 0.03, 0.04] };
        let one = s.add_body("one", BodyKind::Free, Some(inertia([0.0, 0.0, 0.0])));
        let two = s.add_body("two", BodyKind::Free, Some(inertia([1.0, 0.2, 0.1])));
        let (p, q) = (s.add_node("p", one, [0.1, 0.0, 0.0]), s.add_node("q", two, [0.9, 0.2, 0.3]));
        s.members.push(Member::spring("s", [p, q], 50.0, 0.5, 0.001));
        let sim = Simulation::new(&s, &crate::settings::SimSettings::default()).unwrap();
        let dofs = sim.data.relaxation_dofs(&sim.model);
        let groups = sim.data.rigid_groups(&sim.model, &dofs);
        assert_eq!(groups.last(), Some(&(vec![0, 1], vec![])));
        let system = sim.data.relaxation_system(&sim.model, &dofs);
        let mut solver = sparse::ShiftedCholesky::new(&dofs, &system, &sim.data.rigid_groups(&sim.model, &dofs), 1.0);
        let dx = solver.step(1.0).expect("positive definite at the Gershgorin bound");
        // Mass-weighted momentum of the step: sum m_i u_i (the rigid translation's component).
        let momentum: Vector3<f64> = (0..2).map(|i| dx.fixed_rows::<3>(6 * i) * dofs.scale[i].0).sum();
        assert!(momentum.norm() <= 1e-12 * dx.amax(), "momentum {momentum}");
        // The spring's stretch is still relaxed: the step is not zero.
        assert!(dx.amax() > 1e-3, "step {dx}");
    }

    /// The cross-product matrix reproduces r x v.
    #[test]
    fn cross_matrix_is_the_cross_product() {
        let (r, x) = (Vector3::new(0.3, -1.2, 2.0), Vector3::new(-0.7, 0.4, 1.1));
        assert!((cross_matrix(r) * x - r.cross(&x)).norm() <= 1e-15);
    }
}
