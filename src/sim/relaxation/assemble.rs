//! The relaxation's linear system: the free bodies' coordinates, the generalized force
//! f = -grad E and the Hessian H of the potential energy as 6x6 blocks (one per pair of
//! coupled bodies), assembled from the force laws.

use super::super::data::Data;
use super::super::model::Model;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x6, Matrix6, Vector3};
use rapier3d_f64::prelude::*;
use std::ops::AddAssign;

pub(super) fn v3(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

pub(super) fn cross_matrix(r: Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -r.z, r.y, r.z, 0.0, -r.x, -r.y, r.x, 0.0)
}

/// The free bodies' coordinates: for each structure body its block index, if free.
pub(super) struct Dofs {
    pub(super) index: Vec<Option<usize>>,
    /// Centre of mass of each free body, in block order [m].
    pub(super) com: Vec<Vector>,
    /// Mass [kg] and mean principal moment of inertia [kg m^2] of each free body.
    pub(super) scale: Vec<(f64, f64)>,
    /// Which coordinates (six per block) a support holds (`Structure::supports`): they take
    /// no force and no step.
    pub(super) held: Vec<bool>,
}

impl Dofs {
    /// Number of free bodies (blocks of six coordinates).
    pub(super) fn blocks(&self) -> usize {
        self.com.len()
    }

    /// 1 / sqrt(mass or inertia) of each coordinate (the mass weighting).
    pub(super) fn weight(&self) -> DVector<f64> {
        DVector::from_fn(6 * self.blocks(), |r, _| {
            let (mass, inertia) = self.scale[r / 6];
            1.0 / if r % 6 < 3 { mass } else { inertia }.sqrt()
        })
    }

    /// Zeroes the held coordinates' entries of `f` (the supports take those forces).
    pub(super) fn hold(&self, f: &mut DVector<f64>) {
        for (r, _) in self.held.iter().enumerate().filter(|(_, h)| **h) {
            f[r] = 0.0;
        }
    }

    /// Takes the held coordinates out of the Hessian's blocks: their rows and columns zeroed,
    /// and each given a stiffness alone on the diagonal, at the largest mass-weighted diagonal
    /// entry of the rest (inside the spectrum, so no shift or floor moves; with no force on it,
    /// its step is zero).
    fn hold_blocks(&self, blocks: &mut Vec<(usize, usize, Matrix6<f64>)>) {
        let mut diagonal = DVector::<f64>::zeros(self.held.len());
        for (i, k, block) in blocks.iter() {
            if i == k {
                for r in 0..6 {
                    diagonal[6 * i + r] += block[(r, r)];
                }
            }
        }
        let weight = self.weight();
        let top = diagonal.iter().zip(weight.iter()).fold(0.0_f64, |t, (d, w)| t.max(d * w * w));
        let top = if top > 0.0 { top } else { 1.0 };
        for (i, k, block) in blocks.iter_mut() {
            for r in 0..6 {
                if self.held[6 * *i + r] {
                    block.row_mut(r).fill(0.0);
                }
                if self.held[6 * *k + r] {
                    block.column_mut(r).fill(0.0);
                }
            }
        }
        for (c, _) in self.held.iter().enumerate().filter(|(_, h)| **h) {
            let mut block = Matrix6::zeros();
            block[(c % 6, c % 6)] = top / (weight[c] * weight[c]);
            blocks.push((c / 6, c / 6, block));
        }
    }

    /// Pairs of (structure body, block) of the free bodies.
    pub(super) fn free(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.index.iter().enumerate().filter_map(|(b, i)| i.map(|i| (b, i)))
    }
}

/// The generalized force and the Hessian's blocks (row block, column block, 6x6; repeated
/// pairs add up, and both (i, k) and (k, i) are listed).
pub(super) struct System {
    pub(super) force: DVector<f64>,
    /// The largest member tension or constant load [N]: the scale of the force's round-off.
    pub(super) force_scale_n: f64,
    pub(super) blocks: Vec<(usize, usize, Matrix6<f64>)>,
}

impl System {
    /// The Hessian as a dense matrix, symmetrized.
    pub(super) fn dense(&self) -> DMatrix<f64> {
        let n = self.force.len();
        let mut h = DMatrix::zeros(n, n);
        for (i, k, block) in &self.blocks {
            h.fixed_view_mut::<6, 6>(6 * i, 6 * k).add_assign(block);
        }
        0.5 * (&h + h.transpose())
    }
}

impl Data {
    /// The free bodies' coordinates and the metric of the step's shift: each rigid body's mass
    /// and mean moment of inertia, and for a point mass (a bead, an elastic strut's end) the
    /// largest free body's mass. A point mass's own mass would make the metric as stiff as
    /// its lightest bead: a bead of 0.1 g on a segment of 1000 N/m against a prism's soft
    /// modes of 1e-3 N/m on 1 kg struts puts them 1e-10 below the stiffest, under the step's
    /// floor ([`super::SOFT_MODE_RATIO`]), and the settle crawls at 13 % a step. Statics does
    /// not depend on the masses, only the path does.
    pub(super) fn relaxation_dofs(&self, m: &Model) -> Dofs {
        let s = &m.structure;
        let mut dofs = Dofs { index: vec![None; s.bodies.len()], com: Vec::new(), scale: Vec::new(), held: Vec::new() };
        let free: Vec<usize> = (0..s.bodies.len()).filter(|b| m.is_free(*b)).collect();
        let inertia = |b: usize| s.bodies[b].inertia.expect("free bodies have inertia");
        let heaviest = free.iter().map(|&b| inertia(b).mass_kg).fold(0.0, f64::max);
        for b in free {
            let inertia = inertia(b);
            dofs.index[b] = Some(dofs.com.len());
            dofs.com.push(self.world_com(m, b));
            let p = inertia.principal_kg_m2;
            let mass_kg = if m.point_masses[b] { heaviest } else { inertia.mass_kg };
            dofs.scale.push((mass_kg, ((p[0] + p[1] + p[2]) / 3.0).max(f64::MIN_POSITIVE)));
            dofs.held.extend(m.held_translations[b].iter().chain(&[false; 3]));
        }
        dofs
    }

    /// Constant loads on body `b` (gravity, external and probe loads): force [N], torque [N m].
    pub(in crate::sim) fn constant_load(&self, m: &Model, b: usize) -> (Vector3<f64>, Vector3<f64>) {
        let s = &m.structure;
        let g = Vector3::from(s.gravity);
        let mass = s.bodies[b].inertia.map_or(0.0, |i| i.mass_kg);
        let (probe_f, probe_t) = self.probe_loads[b];
        let f = g * mass + Vector3::from(probe_f) + Vector3::from(m.external_loads[b]);
        (f, Vector3::from(probe_t))
    }

    /// Node Jacobian J = [1, -[rho]x] of the node's block, if its body is free.
    fn node_jacobian(&self, m: &Model, dofs: &Dofs, node: usize, p: Vector3<f64>) -> Option<(usize, Matrix3x6<f64>)> {
        let i = dofs.index[m.structure.nodes[node].body]?;
        let rho = p - v3(dofs.com[i]);
        let mut j = Matrix3x6::zeros();
        j.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
        j.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-cross_matrix(rho)));
        Some((i, j))
    }

    /// The generalized force f = -grad E and the Hessian H of the energy, six coordinates per
    /// free body (translation, then rotation): per member J^T K_m J with
    /// K_m = k e e^T + (t / l)(1 - e e^T), plus the rotations' geometric term
    /// (F . rho) 1 - sym(F rho^T) of a node force F at the arm rho.
    pub(super) fn relaxation_system(&self, m: &Model, dofs: &Dofs) -> System {
        let s = &m.structure;
        let mut f = DVector::zeros(6 * dofs.blocks());
        let mut blocks = Vec::new();
        let mut force_scale_n = 0.0_f64;
        for (i, member) in s.members_by_kind() {
            let Some(law) = self.elastic_law(m, i) else { continue };
            let at: Vec<Vector3<f64>> = member.path.iter().map(|&n| Vector3::from(self.node_position(m, n))).collect();
            let l = member.length_at(|n| self.node_position(m, n));
            if l <= 0.0 || !law.engaged(l) {
                continue;
            }
            let t = law.tension_n(l);
            force_scale_n = force_scale_n.max(t.abs());
            // Each segment's direction and length; each path node's dl/dx: the directions of the
            // segments leaving it less those arriving.
            let segments: Vec<(Vector3<f64>, f64)> =
                at.windows(2).map(|w| ((w[1] - w[0]) / (w[1] - w[0]).norm(), (w[1] - w[0]).norm())).collect();
            let mut gradient = vec![Vector3::zeros(); at.len()];
            for (s, (e, _)) in segments.iter().enumerate() {
                gradient[s] += e;
                gradient[s + 1] -= e;
            }
            let ends: Vec<_> = (0..at.len())
                .map(|x| (self.node_jacobian(m, dofs, member.path[x], at[x]), at[x], gradient[x] * t))
                .collect();
            for (x, (jx, px, fx)) in ends.iter().enumerate() {
                let Some((i, ji)) = jx else { continue };
                f.fixed_rows_mut::<6>(6 * i).add_assign(&(ji.transpose() * fx));
                blocks.push((*i, *i, turning_stiffness(fx, &(px - v3(dofs.com[*i])))));
                for (y, (jy, _, _)) in ends.iter().enumerate() {
                    let Some((k, jk)) = jy else { continue };
                    let kxy = path_stiffness(&segments, &gradient, law.stiffness_n_per_m, t, x, y);
                    blocks.push((*i, *k, ji.transpose() * kxy * jk));
                }
            }
        }
        for &(node, force) in &m.node_loads {
            let p = Vector3::from(self.node_position(m, node));
            let Some((i, ji)) = self.node_jacobian(m, dofs, node, p) else { continue };
            force_scale_n = force_scale_n.max(force.norm());
            f.fixed_rows_mut::<6>(6 * i).add_assign(&(ji.transpose() * force));
            blocks.push((i, i, turning_stiffness(&force, &(p - v3(dofs.com[i])))));
        }
        for (b, i) in dofs.free() {
            let (force, torque) = self.constant_load(m, b);
            force_scale_n = force_scale_n.max(force.norm());
            f.fixed_rows_mut::<3>(6 * i).add_assign(&force);
            f.fixed_rows_mut::<3>(6 * i + 3).add_assign(&torque);
        }
        if dofs.held.contains(&true) {
            dofs.hold(&mut f);
            dofs.hold_blocks(&mut blocks);
        }
        System { force: f, force_scale_n, blocks }
    }

    /// Every free body alone, with its own nodes that members hold and its centre of mass as
    /// anchors [m] (a turn about a line off the centre of mass is not free in these
    /// coordinates: it moves the nodes at second order, and the loads at first); then the
    /// groups of free bodies joined by members (slack or not), each with its anchors: the
    /// nodes on bodies that are not free with a member to the group. A group moves rigidly at no cost in energy
    /// wherever that motion keeps its anchors in place (six motions without anchors, the turns
    /// about a single anchor, the turn about a line of anchors, as a prism's held strut, or a
    /// strut's spin about its axis). Blocks and anchors, per group.
    pub(super) fn rigid_groups(&self, m: &Model, dofs: &Dofs) -> Vec<(Vec<usize>, Vec<Vector3<f64>>)> {
        let s = &m.structure;
        let n = dofs.blocks();
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut anchors_of = vec![Vec::new(); n];
        let mut own_nodes = vec![Vec::new(); n];
        let ends = s.members_with_law().flat_map(|(_, m)| m.segments());
        for (a, b) in ends {
            for node in [a, b] {
                if let Some(i) = dofs.index[s.nodes[node].body] {
                    own_nodes[i].push(node);
                }
            }
            match (dofs.index[s.nodes[a].body], dofs.index[s.nodes[b].body]) {
                (Some(i), Some(k)) => {
                    let (ri, rk) = (root(&mut parent, i), root(&mut parent, k));
                    parent[ri] = rk;
                }
                (Some(i), None) => anchors_of[i].push(b),
                (None, Some(k)) => anchors_of[k].push(a),
                (None, None) => {}
            }
        }
        // A support holds its node in place (in some directions: the group's rigid motions
        // that keep it are fewer, which only leaves more to the shift).
        for support in &s.supports {
            if let Some(i) = dofs.index[s.nodes[support.node].body] {
                anchors_of[i].push(support.node);
            }
        }
        let mut groups: std::collections::BTreeMap<usize, (Vec<usize>, Vec<usize>)> = Default::default();
        for (i, anchors) in anchors_of.into_iter().enumerate() {
            let group = groups.entry(root(&mut parent, i)).or_default();
            group.0.push(i);
            group.1.extend(anchors);
        }
        let place = |mut nodes: Vec<usize>| {
            nodes.sort_unstable();
            nodes.dedup();
            nodes.into_iter().map(|a| Vector3::from(self.node_position(m, a))).collect::<Vec<_>>()
        };
        let bodies = own_nodes.into_iter().enumerate().map(|(i, nodes)| {
            let mut anchors = place(nodes);
            anchors.push(v3(dofs.com[i]));
            (vec![i], anchors)
        });
        let groups: Vec<_> = groups.into_values().map(|(blocks, anchors)| (blocks, place(anchors))).collect();
        bodies.chain(groups).collect()
    }
}

/// The geometric stiffness of a body's small rotation under a force `fx` at the arm `rho` from
/// its centre of mass (a member's pull at a node, a point load): the 6x6 block with
/// (F . rho) 1 - sym(F rho^T) in its rotation part.
fn turning_stiffness(fx: &Vector3<f64>, rho: &Vector3<f64>) -> Matrix6<f64> {
    let mut geo = Matrix6::zeros();
    geo.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(Matrix3::identity() * fx.dot(rho) - (fx * rho.transpose() + rho * fx.transpose()) * 0.5));
    geo
}

/// The block (x, y) of a path member's stiffness d2E/dx dy, x and y indices along its path:
/// k g_x g_y^T (g the path length's gradient, the material term) plus each segment's
/// geometric term (t / l_s)(1 - e e^T), added where x and y are the same end of it and
/// subtracted where they are its two ends. A two-node member's K_m = k e e^T + (t / l)(1 - e e^T)
/// and its opposite, to the bit.
fn path_stiffness(
    segments: &[(Vector3<f64>, f64)],
    gradient: &[Vector3<f64>],
    k: f64,
    t: f64,
    x: usize,
    y: usize,
) -> Matrix3<f64> {
    let mut block = gradient[x] * gradient[y].transpose() * k;
    for (s, (e, l)) in segments.iter().enumerate() {
        let ends = [s, s + 1];
        if !ends.contains(&x) || !ends.contains(&y) {
            continue;
        }
        let geometric = (Matrix3::identity() - e * e.transpose()) * (t / l);
        if x == y {
            block += geometric;
        } else {
            block -= geometric;
        }
    }
    block
}
