//! A sparse projected group's spanning tree, along which a Gauss-Newton step moves its bodies.
//!
//! The projection's coordinates are each plain body's translation and rotation about its centre
//! of mass (`projection.rs`). Moving every body by its own first-order twist is exact to first
//! order only: when a joint near the base of a long chain turns by an angle a, a body at a
//! distance r beyond it should follow an arc, and the straight step leaves it off by about
//! r a^2 / 2. Along a chain of X modules, where r and the accumulated angle both grow with
//! the modules, that made the first step of a command jump shrink the gap less the longer the
//! chain (measured on 0.05 rad jumps: 0.16 of it left at 5 X, 0.44 at 10 X, 1.0 at 15 X).
//!
//! Here each body instead moves with its tree parent and then turns about the joint that links
//! them by its twist relative to the parent (the anchor moving by the relative velocity of the
//! anchor point): the same first-order motion, with the arcs of every upstream joint kept. The
//! tree runs over the group's joints that hold a point (spherical, revolute, universal) from
//! the bodies joined to fixed ones; a body it does not reach moves by its own twist.

use super::data::Data;
use super::model::{GroupTree, Link, Model};
use crate::structure::JointKind;
use rapier3d_f64::prelude::*;

impl GroupTree {
    /// The links, parents before children.
    pub(super) fn links(&self) -> &[Link] {
        &self.links
    }

    /// The breadth-first tree over `joints` (structure indices) of the plain `bodies`
    /// (structure indices), from the bodies joined to fixed ones.
    pub(super) fn of(m: &Model, bodies: &[usize], joints: &[usize]) -> GroupTree {
        let s = &m.structure;
        let mut position = vec![None; s.bodies.len()];
        for (i, &b) in bodies.iter().enumerate() {
            position[b] = Some(i);
        }
        let holds_a_point = |j: usize| {
            matches!(s.joints[j].kind, JointKind::Spherical | JointKind::Revolute { .. } | JointKind::Universal { .. })
        };
        // Each group body's point-holding joints to other group bodies, with the other body.
        let mut joints_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); bodies.len()];
        let mut links: Vec<Link> = Vec::new();
        let mut reached = vec![false; bodies.len()];
        for &j in joints.iter().filter(|&&j| holds_a_point(j)) {
            match (position[s.joints[j].parent], position[s.joints[j].child]) {
                (Some(a), Some(b)) => {
                    joints_of[a].push((j, b));
                    joints_of[b].push((j, a));
                }
                // Roots: bodies joined to a fixed one (the other end is not in the group).
                (Some(b), None) | (None, Some(b)) if !reached[b] => {
                    reached[b] = true;
                    links.push(Link { body: b, parent: None, joint: j });
                }
                _ => {}
            }
        }
        let mut next = 0;
        while next < links.len() {
            let from = links[next].body;
            next += 1;
            for &(joint, other) in &joints_of[from] {
                if !reached[other] {
                    reached[other] = true;
                    links.push(Link { body: other, parent: Some(from), joint });
                }
            }
        }
        GroupTree { links }
    }

    /// Moves the group's `bodies` by `dq` (per body: translation of the centre of mass [m],
    /// rotation vector times `scale` [m]), each along the tree: with its parent, then about the
    /// joint's anchor by its twist relative to the parent. Bodies off the tree move by their
    /// own twist.
    pub(super) fn displace(&self, m: &Model, sim: &mut Data, bodies: &[usize], dq: &[f64], scale: f64) {
        let twist = |i: usize| {
            let q = &dq[6 * i..6 * i + 6];
            (Vector::new(q[0], q[1], q[2]), Vector::new(q[3], q[4], q[5]) / scale)
        };
        let com: Vec<Vector> = bodies.iter().map(|&b| sim.world_com(m, b)).collect();
        let rate_at = |i: usize, p: Vector| {
            let (v, w) = twist(i);
            v + w.cross(p - com[i])
        };
        // Each body's displacement (world), parents first: every anchor read before any move.
        let mut delta: Vec<Option<Pose>> = vec![None; bodies.len()];
        for link in &self.links {
            let a = sim.node_position(m, m.structure.joints[link.joint].anchor);
            let a = Vector::new(a[0], a[1], a[2]);
            let (carried, w_parent, rate_parent) = match link.parent {
                Some(p) => (delta[p].unwrap_or(Pose::IDENTITY), twist(p).1, rate_at(p, a)),
                None => (Pose::IDENTITY, Vector::ZERO, Vector::ZERO),
            };
            let relative = turn_about(a, rate_at(link.body, a) - rate_parent, twist(link.body).1 - w_parent);
            delta[link.body] = Some(carried * relative);
        }
        for (i, &b) in bodies.iter().enumerate() {
            let d = delta[i].unwrap_or_else(|| {
                let (v, w) = twist(i);
                turn_about(com[i], v, w)
            });
            let h = m.handles[b];
            let moved = d * *sim.bodies[h].position();
            sim.bodies[h].set_position(moved, true);
        }
    }
}

/// The displacement that turns by the rotation vector `r` [rad] about `point` and then moves
/// `point` by `t` [m].
pub(super) fn turn_about(point: Vector, t: Vector, r: Vector) -> Pose {
    Pose::from_translation(point + t)
        * Pose::from_rotation(Rotation::from_scaled_axis(r))
        * Pose::from_translation(-point)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter turn about z through (1, 0, 0), then a move by (0, 0, 2) m: the origin lands at
    /// (1, -1, 2) within 1e-15 m, and the point turned about stays put but for the move.
    #[test]
    fn a_turn_about_a_point_keeps_that_point_and_swings_the_rest_on_an_arc() {
        let d = turn_about(
            Vector::new(1.0, 0.0, 0.0),
            Vector::new(0.0, 0.0, 2.0),
            Vector::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let origin = d.transform_point(Vector::ZERO);
        assert!((origin - Vector::new(1.0, -1.0, 2.0)).length() <= 1e-15, "{origin:?}");
        let pivot = d.transform_point(Vector::new(1.0, 0.0, 0.0));
        assert!((pivot - Vector::new(1.0, 0.0, 2.0)).length() <= 1e-15, "{pivot:?}");
    }
}
