//! Trees of joints that carry bodies, along which generalized forces are found by recursion:
//! a tree joint's reaction is whatever the bodies it carries receive, so only the turns (or
//! slide) it allows are left to balance.
//!
//! Two trees: the multibody links' (fixed at build; the damping schedule and restarts walk it),
//! and the reaction fit's (`forces.rs`), which adds each sparse projected group's spanning
//! tree (`group_tree.rs`) over its impulse joints. With the group's tree joints carried by
//! recursion, the fit is left with the loops' reactions in the tree's joint coordinates: at a
//! 10-X chain cut into plain bodies, 20 free turns instead of 180 body coordinates.

use super::data::Data;
use super::forces::Wrench;
use super::model::{Hang, Model, Tree};
use crate::structure::Structure;

impl Tree {
    /// The tree of `hangs` (body, hang) over a structure's bodies and joints.
    fn new(s: &Structure, hangs: impl IntoIterator<Item = (usize, Hang)>, has_group_links: bool) -> Tree {
        let (nb, nj) = (s.bodies.len(), s.joints.len());
        let mut hang = vec![None; nb];
        let mut carried = vec![None; nj];
        for (b, h) in hangs {
            hang[b] = Some(h);
            carried[h.joint] = Some(b);
        }
        let depth = depths(&hang);
        let mut by_depth: Vec<(usize, usize)> = (0..nb).map(|b| (depth[b], b)).collect();
        by_depth.sort_unstable_by(|a, b| b.cmp(a));
        let order = by_depth.into_iter().map(|(_, b)| b).collect();
        Tree { hang, carried, depth, order, has_group_links }
    }

    pub(super) fn hang(&self, b: usize) -> Option<Hang> {
        self.hang[b]
    }

    /// The body joint `j` carries, if it is in the tree.
    pub(super) fn carried(&self, j: usize) -> Option<usize> {
        self.carried[j]
    }

    /// Number of joints between body `b` and the root of its tree.
    pub(super) fn depth(&self, b: usize) -> usize {
        self.depth[b]
    }

    pub(super) fn has_group_links(&self) -> bool {
        self.has_group_links
    }

    /// Whether body `b` is `ancestor` or hangs below it.
    pub(super) fn descends_from(&self, mut b: usize, ancestor: usize) -> bool {
        for _ in 0..=self.hang.len() {
            if b == ancestor {
                return true;
            }
            match self.hang[b] {
                Some(h) => b = h.parent,
                None => return false,
            }
        }
        false
    }

    /// For every body, the sum of the wrenches (force, moment about the world origin) of it and
    /// of every body hanging from it: each body's sum handed to its parent, deepest bodies
    /// first (one pass, where a search of every body's descendants for each joint grew with
    /// the cube of a chain's length).
    pub(super) fn subtree_wrenches(&self, wrench: &[Wrench]) -> Vec<Wrench> {
        let mut sums = wrench.to_vec();
        for &b in &self.order {
            if let Some(h) = self.hang[b] {
                let w = sums[b];
                sums[h.parent].0 += w.0;
                sums[h.parent].1 += w.1;
            }
        }
        sums
    }
}

/// Each body's number of hangs to its root, each branch walked once (walking up from every
/// body grows with the square of a chain's length). Bounded by the bodies: a cycle (never
/// built) cannot hang the walk.
fn depths(hang: &[Option<Hang>]) -> Vec<usize> {
    let mut depth: Vec<Option<usize>> = vec![None; hang.len()];
    let mut below = Vec::new();
    for b in 0..hang.len() {
        let mut x = b;
        let base = loop {
            if let Some(d) = depth[x] {
                break d;
            }
            match hang[x] {
                Some(h) if below.len() < hang.len() => {
                    below.push(x);
                    x = h.parent;
                }
                _ => {
                    depth[x] = Some(0);
                    break 0;
                }
            }
        };
        for (k, &y) in below.iter().rev().enumerate() {
            depth[y] = Some(base + k + 1);
        }
        below.clear();
    }
    depth.into_iter().map(|d| d.unwrap_or(0)).collect()
}

impl Data {
    /// The tree of the multibody links: the joint each body hangs from.
    pub(super) fn link_tree(&self, m: &Model) -> Tree {
        Tree::new(&m.structure, self.link_hangs(m), false)
    }

    /// Each multibody link's child, hung from its parent.
    fn link_hangs(&self, m: &Model) -> Vec<(usize, Hang)> {
        let s = &m.structure;
        let links = s.joints.iter().enumerate().filter(|(j, _)| m.joint_links[*j].is_some());
        links.map(|(j, joint)| (joint.child, Hang { joint: j, parent: joint.parent })).collect()
    }

    /// The reaction fit's tree: the multibody links, and each sparse projected group's
    /// spanning tree over its impulse joints (but a joint with a torsion spring, whose torque
    /// the fit does not read, which stays a fitted closure).
    pub(super) fn fit_tree(&self, m: &Model) -> Tree {
        let s = &m.structure;
        let mut hangs = self.link_hangs(m);
        let links = hangs.len();
        for g in &m.projected_groups {
            for link in g.tree.iter().flat_map(|t| t.links()) {
                let joint = &s.joints[link.joint];
                let body = g.bodies[link.body];
                let other = if joint.child == body { joint.parent } else { joint.child };
                if joint.torsion_spring.is_none() {
                    hangs.push((body, Hang { joint: link.joint, parent: other }));
                }
            }
        }
        let has_group_links = hangs.len() > links;
        Tree::new(s, hangs, has_group_links)
    }
}

#[cfg(test)]
mod tests {
    use crate::settings::SimSettings;
    use crate::sim::joint_coordinates::tests::four_bar_chain;
    use crate::sim::Simulation;
    use crate::structure::{Actuator, ActuatorTarget, Structure};

    /// Joints of one module of `four_bar_chain`: left, right, top left, top right (the pin).
    const JOINTS_PER_MODULE: usize = 4;

    /// Modules of the test chain.
    const MODULES: usize = 5;

    /// The last module's top-left joint, drawn from the top bar to the left bar: the group's
    /// tree reaches the top bar only through it, so it runs it backwards.
    const FLIPPED: usize = (MODULES - 1) * JOINTS_PER_MODULE + 2;

    /// A 5-module four-bar chain under gravity with one joint of each module locked by an
    /// actuator (so rigid): the left joint of the first four, [`FLIPPED`] of the last.
    fn locked_four_bar_chain() -> Structure {
        let mut s = four_bar_chain(MODULES);
        s.gravity = [0.0, -9.81, 0.0];
        let flipped = &mut s.joints[FLIPPED];
        std::mem::swap(&mut flipped.parent, &mut flipped.child);
        let locked = (0..MODULES - 1).map(|k| k * JOINTS_PER_MODULE).chain([FLIPPED]);
        for (k, j) in locked.enumerate() {
            s.actuators.push(Actuator { symbol: format!("q{k}"), target: ActuatorTarget::Joint(j) });
        }
        s
    }

    /// The fit of the loop reactions in the joint coordinates of the group's tree, with the
    /// tree joints' reactions by recursion, finds what the fit over every body's six
    /// coordinates finds: on the locked chain as drawn (an equilibrium: the actuators hold
    /// gravity) both residuals are below 1e-12 N m (measured 5e-14) and the five actuator
    /// torques (4 to 33 N m) agree within 1e-10 N m (measured 3e-14), the backwards-run
    /// joint's sign included (flipped, it is off by 8 N m).
    #[test]
    fn the_fit_in_joint_coordinates_finds_the_torques_of_the_fit_in_body_coordinates() {
        let mut sim = Simulation::new(&locked_four_bar_chain(), &SimSettings::default()).expect("builds");
        assert!(sim.model.fit_tree.has_group_links(), "the chain is cut into plain bodies with a tree");
        let backwards =
            sim.model.fit_tree.carried(FLIPPED).is_some_and(|b| b != sim.model.structure.joints[FLIPPED].child);
        assert!(backwards, "the flipped joint is run backwards");
        let in_joints = sim.member_forces();
        sim.model.fit_tree = sim.data.link_tree(&sim.model);
        let in_bodies = sim.member_forces();
        for forces in [&in_joints, &in_bodies] {
            let r = forces.residual.as_ref().expect("fitted");
            assert!(r.max_force_n.max(r.max_torque_nm) <= 1e-12, "residual {r:?}");
        }
        for (a, b) in in_joints.actuator_force.iter().zip(&in_bodies.actuator_force) {
            assert!(b.abs() >= 1.0 && (a - b).abs() <= 1e-10, "joint coordinates {a} N m, bodies {b} N m");
        }
    }

    /// Off equilibrium both fits say so: without the actuators the chain is a mechanism that
    /// gravity moves, and both residuals are above 1 N m.
    #[test]
    fn a_mechanism_under_gravity_leaves_a_residual_in_both_fits() {
        let mut s = locked_four_bar_chain();
        s.actuators.clear();
        let mut sim = Simulation::new(&s, &SimSettings::default()).expect("builds");
        let in_joints = sim.member_forces().residual.expect("fitted");
        sim.model.fit_tree = sim.data.link_tree(&sim.model);
        let in_bodies = sim.member_forces().residual.expect("fitted");
        for r in [in_joints, in_bodies] {
            assert!(r.max_force_n.max(r.max_torque_nm) >= 1.0, "residual {r:?}");
        }
    }
}
