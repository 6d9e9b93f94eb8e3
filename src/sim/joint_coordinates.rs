//! A command jump of a sparse group closed in the joint coordinates of its tree
//! (`group_tree.rs`).
//!
//! The projection's own coordinates are six per plain body (`projection.rs`): a 10-X chain
//! has 180, its Jacobian 210 rows, and a jump took two factorizations of that size and eight
//! solves (0.2 ms of a 0.66 ms settle). Here each tree link's joint instead contributes the
//! turns it allows: one about a revolute's axis, two about a universal's axes, three about a
//! spherical's anchor. A turn of link L moves L's body and every body beyond it about L's
//! anchor, so every tree joint stays closed to round-off and the coordinates left are the
//! loops' (30 for a 10-X chain). The rows are the group's own, unchanged; a member's rows move
//! only with the links on the tree path between its two bodies (to first order the links
//! above both turn the member as a whole, which leaves its rows at a closed joint unchanged).
//!
//! This is the relative-coordinate form of the same closure: on a rigid group the
//! configuration that closes every row is isolated, so Gauss-Newton in these coordinates and
//! in the bodies' lands on the same one, to round-off. It is used only where it applies
//! exactly: every body on the tree and every tree joint closed at the start (a group at rest),
//! with the jump's first-contraction test unchanged (`continuation.rs`).

use super::data::Data;
use super::model::{GroupTree, Model, ProjectedGroup};
use super::projection::{
    close_rows, largest_abs, Closing, Jacobian, KeptJacobian, Member, Projected, RigidRest, Twist,
    GAP_TOLERANCE_FRACTION,
};
use crate::structure::JointKind;
use rapier3d_f64::prelude::*;

/// A tree link's joint coordinates: its anchor [m] and the unit axes it turns about (world,
/// the first `count` of `all`).
struct LinkAxes {
    anchor: Vector,
    all: [Vector; 3],
    count: usize,
    /// The index of its first coordinate.
    first: usize,
}

impl LinkAxes {
    fn axes(&self) -> &[Vector] {
        &self.all[..self.count]
    }
}

impl Data {
    /// Closes group `g` (its `taut` cables held) in its tree's joint coordinates, when every
    /// one of its bodies is on the tree and every tree joint is closed; None (nothing moved)
    /// otherwise. A rigid group is stopped and its `rest` recorded; any other is handed on to
    /// [`Self::project_group`] once closed, for its velocities.
    pub(super) fn close_in_joint_coordinates(
        &mut self,
        m: &Model,
        g: &ProjectedGroup,
        taut: &[usize],
        kept: &mut Option<KeptJacobian>,
        rest: &mut Option<RigidRest>,
        max_first_contraction: f64,
    ) -> Option<Projected> {
        let tree = g.tree.as_ref()?;
        let tol = GAP_TOLERANCE_FRACTION * m.length_scale_m;
        if !g.multibodies.is_empty() || tree.links().len() != g.bodies.len() || !self.tree_joints_closed(m, tree, tol) {
            return None;
        }
        let on_tree = self.tree_joint_flags(m, tree);
        let rows = |sim: &Data| sim.loop_rows(m, g, taut, &on_tree);
        let jacobian =
            |sim: &mut Data, g0: &[f64]| Jacobian::sparse(sim.joint_jacobian(m, g, taut, tree, &on_tree, g0.len()));
        let displace = |sim: &mut Data, dq: &[f64]| sim.turn_links(m, g, tree, dq);
        let Closing { jacobian: jac, first_contraction, .. } =
            close_rows(m, self, &rows, &jacobian, &displace, None, GAP_TOLERANCE_FRACTION, max_first_contraction);
        // Every row, the tree joints' included, for the verdict.
        let left = largest_abs(&self.group_rows(m, g, taut));
        let closed = left <= tol && first_contraction <= max_first_contraction;
        if closed && jac.as_ref().is_some_and(Jacobian::rigid) {
            self.stop_bodies(m, &g.bodies);
            *rest = Some(self.rigid_rest(m, g, taut, left));
        } else if closed {
            let p = self.project_group(m, g, taut, kept, rest, GAP_TOLERANCE_FRACTION, f64::INFINITY);
            return Some(Projected { left: p.left, first_contraction });
        }
        Some(Projected { left, first_contraction })
    }

    /// Whether every tree joint's rows but a locked angle's are within `tol` [m]: the rows no
    /// joint coordinate moves.
    fn tree_joints_closed(&self, m: &Model, tree: &GroupTree, tol: f64) -> bool {
        let mut rows = Vec::new();
        tree.links().iter().all(|link| {
            rows.clear();
            self.joint_rows(m, link.joint, &mut rows);
            if self.locked_angle(m, link.joint).is_some() {
                rows.pop();
            }
            largest_abs(&rows) <= tol
        })
    }

    /// For each structure joint: whether it is one of the tree's links.
    fn tree_joint_flags(&self, m: &Model, tree: &GroupTree) -> Vec<bool> {
        let mut on_tree = vec![false; m.structure.joints.len()];
        for link in tree.links() {
            on_tree[link.joint] = true;
        }
        on_tree
    }

    /// The rows the joint coordinates leave to close, in the group's member order: every row
    /// of a joint off the tree, a tree joint's locked angle, each taut cable's stretch. A
    /// turn keeps every other row of a tree joint as it was (closed: the jump starts from a
    /// group whose tree joints are closed), so they are not evaluated while it closes.
    fn loop_rows(&self, m: &Model, g: &ProjectedGroup, taut: &[usize], on_tree: &[bool]) -> Vec<f64> {
        let s = &m.structure;
        let rotation = |b: usize| self.bodies[m.handles[b]].position().rotation;
        let mut out = Vec::new();
        for &j in &g.joints {
            if !on_tree[j] {
                self.joint_rows(m, j, &mut out);
            } else if let Some(target) = self.locked_angle(m, j) {
                out.push(self.lock_row(m, j, rotation(s.joints[j].parent), rotation(s.joints[j].child), target));
            }
        }
        self.cable_rows(m, taut, &mut out);
        out
    }

    /// Each tree link's anchor and axes at the current poses, in link order.
    fn link_axes(&self, m: &Model, tree: &GroupTree) -> Vec<LinkAxes> {
        let s = &m.structure;
        let rotation = |b: usize| self.bodies[m.handles[b]].position().rotation;
        let vec3 = |a: [f64; 3]| Vector::new(a[0], a[1], a[2]);
        let mut first = 0;
        tree.links()
            .iter()
            .map(|link| {
                let joint = &s.joints[link.joint];
                let (all, count) = match joint.kind {
                    JointKind::Revolute { axis } => ([(rotation(joint.parent) * vec3(axis)).normalize(); 3], 1),
                    JointKind::Universal { axis1, axis2 } => {
                        let a1 = (rotation(joint.parent) * vec3(axis1)).normalize();
                        ([a1, (rotation(joint.child) * vec3(axis2)).normalize(), a1], 2)
                    }
                    _ => ([Vector::X, Vector::Y, Vector::Z], 3),
                };
                let la = LinkAxes { anchor: vec3(self.node_position(m, joint.anchor)), all, count, first };
                first += count;
                la
            })
            .collect()
    }

    /// Turns every link's subtree by its coordinates in `dq` (angle times the structure's size
    /// [m]) about its anchor, parents first: each body moves with its parent, then turns.
    fn turn_links(&mut self, m: &Model, g: &ProjectedGroup, tree: &GroupTree, dq: &[f64]) {
        let scale = m.length_scale_m;
        let axes = self.link_axes(m, tree);
        let mut delta: Vec<Pose> = vec![Pose::IDENTITY; g.bodies.len()];
        for (link, la) in tree.links().iter().zip(&axes) {
            let turn = la.axes().iter().enumerate().fold(Vector::ZERO, |r, (k, a)| r + *a * (dq[la.first + k] / scale));
            let carried = link.parent.map_or(Pose::IDENTITY, |p| delta[p]);
            delta[link.body] = carried * super::group_tree::turn_about(la.anchor, Vector::ZERO, turn);
        }
        for (&b, d) in g.bodies.iter().zip(delta) {
            let h = m.handles[b];
            let moved = d * *self.bodies[h].position();
            self.bodies[h].set_position(moved, true);
        }
    }

    /// The Jacobian of the group's [`Self::loop_rows`] (`rows` of them) by the joint
    /// coordinates: each member's rows by the coordinates of the links on the tree path between
    /// its two bodies (a locked tree joint's: its own link's turn).
    fn joint_jacobian(
        &self,
        m: &Model,
        g: &ProjectedGroup,
        taut: &[usize],
        tree: &GroupTree,
        on_tree: &[bool],
        rows: usize,
    ) -> super::least_squares::SparseRows {
        let s = &m.structure;
        let scale = m.length_scale_m;
        let axes = self.link_axes(m, tree);
        let path = TreePaths::of(m, g, tree);
        // Each member with its two bodies and its rows' count; of a tree joint only the last
        // row (its lock) is kept.
        let joints = g.joints.iter().filter(|&&j| !on_tree[j] || self.locked_angle(m, j).is_some()).map(|&j| {
            let joint = &s.joints[j];
            let count = if on_tree[j] { 1 } else { self.joint_row_count(m, j) };
            (Member::Joint(self.joint_frame(m, j)), [joint.parent, joint.child], count)
        });
        let cables = taut.iter().map(|&c| {
            (Member::Cable(c), [s.nodes[s.members[c].ends().0].body, s.nodes[s.members[c].ends().1].body], 1)
        });
        let (mut entries, mut first_row, mut block) = (Vec::new(), 0, Vec::new());
        for (member, [a, b], count) in joints.chain(cables) {
            for (link, moved) in path.between(a, b) {
                let la = &axes[link];
                for (k, axis) in la.axes().iter().enumerate() {
                    let t = Twist { v: Vector::ZERO, w: *axis / scale, at: la.anchor };
                    block.clear();
                    member.row_rates(m, self, &|x| (x == moved).then_some(t), &mut block);
                    let kept = &block[block.len() - count..];
                    entries.extend(kept.iter().enumerate().map(|(r, &x)| (first_row + r, la.first + k, x)));
                }
            }
            first_row += count;
        }
        debug_assert_eq!(first_row, rows, "one block of rows per member");
        let coordinates = axes.last().map_or(0, |la| la.first + la.count);
        super::least_squares::SparseRows::new(rows, coordinates, &entries)
    }
}

/// The tree's links by body, with their parents and depths, for the paths between bodies.
struct TreePaths {
    /// Each structure body's link (None: a fixed body, above every root).
    link_of: Vec<Option<usize>>,
    /// Each link's parent link and its depth (roots 0).
    parent: Vec<Option<usize>>,
    depth: Vec<usize>,
}

impl TreePaths {
    fn of(m: &Model, g: &ProjectedGroup, tree: &GroupTree) -> Self {
        let links = tree.links();
        let mut link_of_group_body = vec![0; g.bodies.len()];
        for (l, link) in links.iter().enumerate() {
            link_of_group_body[link.body] = l;
        }
        let mut link_of = vec![None; m.structure.bodies.len()];
        let (mut parent, mut depth) = (Vec::new(), Vec::new());
        for link in links {
            let p = link.parent.map(|p| link_of_group_body[p]);
            link_of[g.bodies[link.body]] = Some(parent.len());
            depth.push(p.map_or(0, |p: usize| depth[p] + 1));
            parent.push(p);
        }
        TreePaths { link_of, parent, depth }
    }

    /// The links on the tree path between bodies `a` and `b` (structure indices), each with
    /// the one of the two that it moves.
    fn between(&self, a: usize, b: usize) -> Vec<(usize, usize)> {
        let (mut la, mut lb) = (self.link_of[a], self.link_of[b]);
        let mut out = Vec::new();
        let depth = |l: Option<usize>| l.map_or(-1, |l| self.depth[l] as i64);
        while la != lb {
            if depth(la) >= depth(lb) {
                let l = la.expect("a link is deeper than a fixed body");
                out.push((l, a));
                la = self.parent[l];
            } else {
                let l = lb.expect("a link is deeper than a fixed body");
                out.push((l, b));
                lb = self.parent[l];
            }
        }
        out
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::Data;
    use crate::settings::SimSettings;
    use crate::sim::Simulation;
    use crate::structure::{BodyKind, Inertia, Joint, JointKind, Structure};

    /// Step of the central differences, in coordinates (angle times the structure's size) [m].
    const STEP_M: f64 = 1e-6;

    /// A chain of `n` four-bar loops in the plane z = 0 on a fixed base: module k has a left
    /// and a right bar standing on the body below (leaning, so that no two are parallel) and a
    /// top bar across them, joined by revolute joints about z but for a planar pin that closes
    /// the loop. Its 3 n links are past the looped multibody's limit, so it is cut into plain
    /// bodies with a tree.
    pub(in crate::sim) fn four_bar_chain(n: usize) -> Structure {
        let mut s = Structure { name: "four-bar chain".into(), gravity: [0.0; 3], ..Default::default() };
        let base = s.add_body("base", BodyKind::Fixed, None);
        let (mut below, mut left, mut right) = (base, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        let (mut a, mut b) = (s.add_node("A0", base, left), s.add_node("B0", base, right));
        let revolute = |name: String, parent, child, anchor| Joint {
            name,
            kind: JointKind::Revolute { axis: [0.0, 0.0, 1.0] },
            parent,
            child,
            anchor,
            initial_coordinate: 0.0,
            torsion_spring: None,
            damping: 0.0,
        };
        for k in 1..=n {
            let (top_left, top_right) = ([left[0] + 0.1, left[1] + 1.0, 0.0], [right[0] + 0.3, right[1] + 1.1, 0.0]);
            let bar = |p: [f64; 3], q: [f64; 3]| {
                let com = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, 0.0];
                Some(Inertia { mass_kg: 1.0, com, principal_kg_m2: [0.1; 3] })
            };
            let l = s.add_body(&format!("L{k}"), BodyKind::Free, bar(left, top_left));
            let r = s.add_body(&format!("R{k}"), BodyKind::Free, bar(right, top_right));
            let t = s.add_body(&format!("T{k}"), BodyKind::Free, bar(top_left, top_right));
            let (c, d) = (s.add_node(&format!("C{k}"), t, top_left), s.add_node(&format!("D{k}"), t, top_right));
            s.joints.push(revolute(format!("left{k}"), below, l, a));
            s.joints.push(revolute(format!("right{k}"), below, r, b));
            s.joints.push(revolute(format!("top left{k}"), l, t, c));
            // The loop closes at a planar pin, as a mechanism's loops are drawn.
            let pin = JointKind::PlanarPin { axis: [0.0, 0.0, 1.0] };
            s.joints.push(Joint { kind: pin, ..revolute(format!("top right{k}"), r, t, d) });
            (below, left, right, a, b) = (t, top_left, top_right, c, d);
        }
        s
    }

    /// The joint-coordinate Jacobian of a 3-module four-bar chain cut into plain bodies is the
    /// derivative of its loop rows as `turn_links` moves it: central differences agree with
    /// every entry within 1e-8 (measured 1.9e-10; entries are of order 1, and a link left off
    /// a path would be off by that much). The tree joints' rows, which the jump leaves out, do
    /// not move with any turn: their central differences are at most 1e-8 too (measured 0).
    #[test]
    fn the_joint_jacobian_is_the_derivative_of_the_rows_along_the_tree() {
        let mut sim = Simulation::new(&four_bar_chain(3), &SimSettings::default()).expect("builds");
        let g = sim.model.projected_groups.first().cloned().expect("the chain is one projected group");
        let tree = g.tree.clone().expect("a sparse group has a tree");
        let taut = sim.data.projected_taut_cables(&sim.model, &g).expect("no slack cable");
        let on_tree = sim.data.tree_joint_flags(&sim.model, &tree);
        let rows = |d: &Data| d.loop_rows(&sim.model, &g, &taut, &on_tree);
        let jacobian =
            sim.data.joint_jacobian(&sim.model, &g, &taut, &tree, &on_tree, rows(&sim.data).len()).to_dense();
        assert_eq!(jacobian.ncols(), 9, "one turn per revolute link of 9 bodies");
        let mut left_out = Vec::new();
        let mut first = 0;
        for &j in &g.joints {
            let count = sim.data.joint_row_count(&sim.model, j);
            if on_tree[j] {
                left_out.extend(first..first + count - usize::from(sim.data.locked_angle(&sim.model, j).is_some()));
            }
            first += count;
        }
        assert!(!left_out.is_empty(), "the tree joints' rows");
        let start = sim.data.group_poses(&sim.model, &g);
        let (mut worst, mut worst_left_out) = (0.0_f64, 0.0_f64);
        for k in 0..jacobian.ncols() {
            let mut moved = |h: f64| {
                let mut dq = vec![0.0; jacobian.ncols()];
                dq[k] = h;
                sim.data.turn_links(&sim.model, &g, &tree, &dq);
                let r = (rows(&sim.data), sim.data.group_rows(&sim.model, &g, &taut));
                sim.data.set_group_poses(&sim.model, &g, &start);
                r
            };
            let (plus, minus) = (moved(STEP_M), moved(-STEP_M));
            for r in 0..jacobian.nrows() {
                let difference = (plus.0[r] - minus.0[r]) / (2.0 * STEP_M);
                worst = worst.max((difference - jacobian[(r, k)]).abs());
            }
            for &r in &left_out {
                worst_left_out = worst_left_out.max(((plus.1[r] - minus.1[r]) / (2.0 * STEP_M)).abs());
            }
        }
        assert!(worst <= 1e-8, "largest difference from the central differences {worst:.2e}");
        assert!(worst_left_out <= 1e-8, "largest rate of a tree joint's row {worst_left_out:.2e}");
    }
}
