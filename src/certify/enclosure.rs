//! The equilibrium equations of a [`Problem`] over a box of its coordinates, in interval
//! arithmetic: enclosures of the gradient F = dV/dq and the Hessian J = d2V/dq2 of the
//! potential energy V at every point of the box.
//!
//! V = sum over members of k (l - l0)^2 / 2 (a cable's only where l > l0: max(l - l0, 0)), minus
//! each constant force's work: a free body's force at its centre of mass (gravity, loads),
//! F . c, and a node load's, F . p. A node on a free body sits at p = c0 + dx + C(phi) rho0,
//! C(phi) rho = rho + (phi x rho + (phi x (phi x rho)) / 2) / (1 + |phi|^2 / 4) (the Cayley
//! rotation of angle 2 atan(|phi| / 2) about phi: rational, so +, -, *, / and sqrt enclose all
//! of it), phi = sum alpha_j e_j over the body's kept rotation directions. For a member between
//! nodes a and b, d = p_b - p_a, g = dV/dd = t d / l with t = k (l - l0), and
//! H = d2V/dd2 = k' d d^T / l^2 + (t / l) (1 - d d^T / l^2), k' = k where the member is taut,
//! [0, k] across a cable's slack kink; the chain rule through each node's Jacobian and Hessian.

#![allow(clippy::needless_range_loop)] // index loops that follow the chain rule's formulas

use super::jet::Jet;
use super::{Node, Problem};
use crate::interval::Interval;

/// A dense interval matrix, n x n, row-major.
#[derive(Clone, Debug)]
pub struct IntervalMatrix {
    pub n: usize,
    pub entries: Vec<Interval>,
}

impl IntervalMatrix {
    pub fn zeros(n: usize) -> Self {
        IntervalMatrix { n, entries: vec![Interval::ZERO; n * n] }
    }

    pub fn at(&self, i: usize, j: usize) -> Interval {
        self.entries[i * self.n + j]
    }

    fn add_to(&mut self, i: usize, j: usize, x: Interval) {
        let e = &mut self.entries[i * self.n + j];
        *e = *e + x;
    }
}

/// A node's position over the box: each component's enclosure, its derivatives by its body's
/// coordinates (from `first`, `count` of them) and their second derivatives.
struct NodeJets {
    first: usize,
    count: usize,
    p: [Jet; 3],
}

/// The position jets of `node` over `x`; for a fixed node, Err with its position (it has no
/// derivatives).
fn node_jets(problem: &Problem, node: &Node, x: &[Interval]) -> Result<NodeJets, [Interval; 3]> {
    let (block, arm) = match node {
        Node::Fixed(p) => return Err(p.map(Interval::point)),
        Node::OnBlock { block, arm } => (&problem.blocks[*block], arm),
    };
    let n = 3 + block.rotations.len();
    let var = |i: usize| Jet::variable(n, i, x[block.first + i]);
    let constant = |c: f64| Jet::constant(n, Interval::point(c));
    let mut phi = [constant(0.0), constant(0.0), constant(0.0)];
    for (j, e) in block.rotations.iter().enumerate() {
        for k in 0..3 {
            phi[k] = phi[k].add(&var(3 + j).scale(Interval::point(e[k])));
        }
    }
    let rho = arm.map(constant);
    let cross = |a: &[Jet; 3], b: &[Jet; 3]| {
        [
            a[1].mul(&b[2]).sub(&a[2].mul(&b[1])),
            a[2].mul(&b[0]).sub(&a[0].mul(&b[2])),
            a[0].mul(&b[1]).sub(&a[1].mul(&b[0])),
        ]
    };
    let u = cross(&phi, &rho);
    let w = cross(&phi, &u);
    let s = phi[0].mul(&phi[0]).add(&phi[1].mul(&phi[1])).add(&phi[2].mul(&phi[2]));
    let inverse = constant(1.0).add(&s.scale(Interval::point(0.25))).recip();
    let p = std::array::from_fn(|k| {
        let turned = u[k].add(&w[k].scale(Interval::point(0.5))).mul(&inverse);
        constant(block.com[k]).add(&var(k)).add(&rho[k]).add(&turned)
    });
    Ok(NodeJets { first: block.first, count: n, p })
}

/// F and J of `problem` over the box `x` (module docs).
pub fn gradient_and_hessian(problem: &Problem, x: &[Interval]) -> (Vec<Interval>, IntervalMatrix) {
    let n = x.len();
    let mut f = vec![Interval::ZERO; n];
    let mut j = IntervalMatrix::zeros(n);
    for (b, force) in problem.blocks.iter().zip(&problem.forces) {
        for k in 0..3 {
            f[b.first + k] = f[b.first + k] - Interval::point(force[k]);
        }
    }
    for (node, load) in &problem.node_loads {
        if let Ok(nj) = node_jets(problem, &problem.nodes[*node], x) {
            let load = load.map(Interval::point);
            for i in 0..nj.count {
                for k in 0..3 {
                    f[nj.first + i] = f[nj.first + i] - nj.p[k].g[i] * load[k];
                    for l in 0..nj.count {
                        j.add_to(nj.first + i, nj.first + l, -(nj.p[k].h[i][l] * load[k]));
                    }
                }
            }
        }
    }
    for m in &problem.members {
        add_member(problem, m, x, &mut f, &mut j);
    }
    (f, j)
}

/// One end of a member: its position, and its jets where it moves (`sign` +1 for b, -1 for a).
type End = (Result<NodeJets, [Interval; 3]>, f64);

/// A member's gradient and Hessian terms.
fn add_member(problem: &Problem, m: &super::Spring, x: &[Interval], f: &mut [Interval], j: &mut IntervalMatrix) {
    let ends: [End; 2] =
        [(node_jets(problem, &problem.nodes[m.a], x), -1.0), (node_jets(problem, &problem.nodes[m.b], x), 1.0)];
    let position = |e: &End| match &e.0 {
        Ok(nj) => nj.p.map(|c| c.v),
        Err(p) => *p,
    };
    let (pa, pb) = (position(&ends[0]), position(&ends[1]));
    let d: [Interval; 3] = std::array::from_fn(|k| pb[k] - pa[k]);
    let l2 = d[0].square() + d[1].square() + d[2].square();
    let l = l2.sqrt();
    let stretch = l - Interval::point(m.rest_m);
    let (t, k_taut) = if m.tension_only {
        let k = Interval::point(m.stiffness_n_per_m);
        let k_taut = if stretch.lo > 0.0 {
            k
        } else if stretch.hi < 0.0 {
            Interval::ZERO
        } else {
            Interval::new(0.0, m.stiffness_n_per_m)
        };
        ((stretch * m.stiffness_n_per_m).positive_part(), k_taut)
    } else {
        (stretch * m.stiffness_n_per_m, Interval::point(m.stiffness_n_per_m))
    };
    let t_over_l = t / l;
    let g: [Interval; 3] = std::array::from_fn(|k| t_over_l * d[k]);
    let h: [[Interval; 3]; 3] = std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let ddt = d[r] * d[c] / l2;
            let identity = if r == c { Interval::point(1.0) } else { Interval::ZERO };
            k_taut * ddt + t_over_l * (identity - ddt)
        })
    });
    for (e, sign) in &ends {
        let Ok(nj) = e else { continue };
        for i in 0..nj.count {
            for k in 0..3 {
                f[nj.first + i] = f[nj.first + i] + nj.p[k].g[i] * g[k] * *sign;
                for l in 0..nj.count {
                    j.add_to(nj.first + i, nj.first + l, g[k] * nj.p[k].h[i][l] * *sign);
                }
            }
        }
        for (e2, sign2) in &ends {
            let Ok(nj2) = e2 else { continue };
            for i in 0..nj.count {
                for l in 0..nj2.count {
                    let mut s = Interval::ZERO;
                    for r in 0..3 {
                        for c in 0..3 {
                            s = s + nj.p[r].g[i] * h[r][c] * nj2.p[c].g[l];
                        }
                    }
                    j.add_to(nj.first + i, nj2.first + l, s * (*sign * *sign2));
                }
            }
        }
    }
}

/// Each node's position enclosure over the box.
pub fn node_positions(problem: &Problem, x: &[Interval]) -> Vec<[Interval; 3]> {
    problem
        .nodes
        .iter()
        .map(|node| match node_jets(problem, node, x) {
            Ok(nj) => nj.p.map(|c| c.v),
            Err(p) => p,
        })
        .collect()
}
