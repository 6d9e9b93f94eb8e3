//! The relaxation's line search: the energy after a trial step, and the limits of a step.

use super::super::data::Data;
use super::super::model::Model;
use super::assemble::{v3, Dofs};
use super::{MAX_STEP_FRACTION, MAX_STEP_ROTATION_RAD};
use nalgebra::{DVector, Vector3};
use rapier3d_f64::prelude::*;
use std::ops::AddAssign;

impl Data {
    /// Node position after moving every free body by `alpha` times `step` [m].
    fn moved_node(&self, m: &Model, dofs: &Dofs, step: &DVector<f64>, alpha: f64, node: usize) -> Vector3<f64> {
        let p = Vector3::from(self.node_position(m, node));
        let Some(i) = dofs.index[m.structure.nodes[node].body] else { return p };
        let c = v3(dofs.com[i]);
        let u = step.fixed_rows::<3>(6 * i) * alpha;
        let theta = step.fixed_rows::<3>(6 * i + 3) * alpha;
        let rotation = nalgebra::Rotation3::new(theta);
        c + u + rotation * (p - c)
    }

    /// Energy after moving by `alpha` times `step`, less the energy now [J], and the energy's
    /// scale (the sum of the magnitudes of its terms) [J].
    pub(super) fn relaxation_energy_change(
        &self,
        m: &Model,
        dofs: &Dofs,
        step: &DVector<f64>,
        alpha: f64,
    ) -> (f64, f64) {
        let s = &m.structure;
        let (mut change, mut scale) = (0.0, 0.0);
        for (i, member) in s.members_by_kind() {
            let Some(law) = self.elastic_law(m, i) else { continue };
            let now = law.energy_j(member.length_at(|n| self.node_position(m, n)));
            let then = law.energy_j(member.length_at(|n| self.moved_node(m, dofs, step, alpha, n).into()));
            change += then - now;
            scale += now.abs() + then.abs();
        }
        for &(node, force) in &m.node_loads {
            let work =
                force.dot(&(self.moved_node(m, dofs, step, alpha, node) - Vector3::from(self.node_position(m, node))));
            change -= work;
            scale += work.abs() + force.norm() * m.length_scale_m;
        }
        for (b, i) in dofs.free() {
            let (force, torque) = self.constant_load(m, b);
            let work = (force.dot(&step.fixed_rows::<3>(6 * i)) + torque.dot(&step.fixed_rows::<3>(6 * i + 3))) * alpha;
            change -= work;
            scale += work.abs() + force.norm() * m.length_scale_m;
        }
        (change, scale)
    }

    /// The largest generalized force component (N, N m) after moving by `alpha` times `step`:
    /// the merit of a step whose energy change is below the energy's round-off.
    pub(super) fn relaxation_force_after(&self, m: &Model, dofs: &Dofs, step: &DVector<f64>, alpha: f64) -> f64 {
        let s = &m.structure;
        let mut f = DVector::zeros(6 * dofs.blocks());
        let mut push = |node: usize, p: Vector3<f64>, force: Vector3<f64>| {
            let Some(i) = dofs.index[s.nodes[node].body] else { return };
            let com = v3(dofs.com[i]) + step.fixed_rows::<3>(6 * i) * alpha;
            f.fixed_rows_mut::<3>(6 * i).add_assign(&force);
            f.fixed_rows_mut::<3>(6 * i + 3).add_assign(&((p - com).cross(&force)));
        };
        for (i, member) in s.members_by_kind() {
            let Some(law) = self.elastic_law(m, i) else { continue };
            let at: Vec<Vector3<f64>> = member.path.iter().map(|&n| self.moved_node(m, dofs, step, alpha, n)).collect();
            let l = member.length_at(|n| self.moved_node(m, dofs, step, alpha, n).into());
            if l <= 0.0 || !law.engaged(l) {
                continue;
            }
            let t = law.tension_n(l);
            for (w, pair) in at.windows(2).enumerate() {
                let pull = (pair[1] - pair[0]).normalize() * t;
                push(member.path[w], pair[0], pull);
                push(member.path[w + 1], pair[1], -pull);
            }
        }
        for &(node, force) in &m.node_loads {
            push(node, self.moved_node(m, dofs, step, alpha, node), force);
        }
        for (b, i) in dofs.free() {
            let (force, torque) = self.constant_load(m, b);
            f.fixed_rows_mut::<3>(6 * i).add_assign(&force);
            f.fixed_rows_mut::<3>(6 * i + 3).add_assign(&torque);
        }
        dofs.hold(&mut f);
        f.amax()
    }

    /// The largest fraction (at most 1) of `step` that keeps every body within the step limits.
    pub(super) fn relaxation_step_limit(&self, m: &Model, dofs: &Dofs, step: &DVector<f64>) -> f64 {
        let max_shift = MAX_STEP_FRACTION * m.length_scale_m;
        (0..dofs.blocks()).fold(1.0_f64, |alpha, i| {
            let shift = step.fixed_rows::<3>(6 * i).norm();
            let turn = step.fixed_rows::<3>(6 * i + 3).norm();
            alpha.min(max_shift / shift.max(f64::MIN_POSITIVE)).min(MAX_STEP_ROTATION_RAD / turn.max(f64::MIN_POSITIVE))
        })
    }

    /// Moves every free body by `alpha` times `step` (translation of the centre of mass, then
    /// rotation about it).
    pub(super) fn move_bodies(&mut self, m: &Model, dofs: &Dofs, step: &DVector<f64>, alpha: f64) {
        for (b, i) in dofs.free() {
            let u = step.fixed_rows::<3>(6 * i) * alpha;
            let theta = step.fixed_rows::<3>(6 * i + 3) * alpha;
            let com = dofs.com[i];
            let turn = Rotation::from_scaled_axis(Vector::new(theta.x, theta.y, theta.z));
            let h = m.handles[b];
            let pose = *self.bodies[h].position();
            let moved = Pose::from_translation(com + Vector::new(u.x, u.y, u.z))
                * Pose::from_rotation(turn)
                * Pose::from_translation(-com)
                * pose;
            self.bodies[h].set_position(moved, true);
        }
    }
}
