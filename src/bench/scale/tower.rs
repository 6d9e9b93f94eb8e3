//! The tower family of `tensegrity bench --scale`: towers of m stacked 4-strut prisms designed
//! by the force density method (Schek, "The force density method for form finding and
//! computation of general networks", 1974; Tibert & Pellegrino 2003, Sec. 2.2).
//!
//! Geometry (drawn, then made an equilibrium): stage s is a prism of radius `RADIUS_M` and
//! height `HEIGHT_M`, its top polygon turned by the prism's twist pi/2 + pi/n from its bottom
//! one; stage s + 1 stands `PITCH_M` higher, so that its bottom polygon lies
//! `OVERLAP_M` below stage s's top polygon, turned by pi/n from it. Members: per stage n
//! struts, its two polygons and n side cables (the prism's); between stages, each top node of
//! stage s is tied by two saddle members to the two nearest bottom nodes of stage s + 1 and
//! by a vertical member each from its bottom and top nodes to the ones of stage s + 1 straight
//! above. Strut 1 of stage 1 is held.
//!
//! Force densities q (tension / length) that make the drawn shape an equilibrium solve
//! A q = 0, A the equilibrium matrix (at every free node i, sum over members (i, j) of
//! q (x_j - x_i) = 0). The design takes the one nearest (least squares) to a target pattern
//! (the prism's self-stress in each stage, `SADDLE_Q` and the saddles' balance in the
//! verticals): q = q_t - A^T (A A^T)^-1 A q_t, with A A^T banded (members only join a stage
//! to the next), factored by a banded Cholesky. In this geometry the projection leaves the
//! stage-to-stage members without force (measured: |q| below 1e-15 of the cables'; no
//! equilibrium of the drawn shape loads them, as a prism's twist mechanism takes any axial
//! pull), so they are springs (pushing and pulling) at their drawn length: they tie the
//! stages together with two-sided stiffness while every stage holds its own prestress (a
//! regular prism's self-stress is super-stable, so the tower is stable). Stage cables must
//! stay in tension; the densities are scaled so that the most strained cable is stretched
//! `MAX_CABLE_STRAIN`, and rest lengths follow: l0 = l (1 - q / k). Each case starts with every free strut moved by
//! [`PERTURBATION_M`] in a fixed pseudo-random direction; the error is the largest node
//! distance from the design after the best rigid alignment.

use super::{Case, Measure};
use crate::settings::SimSettings;
use crate::sim::least_squares::{SparseLeastSquares, SparseRows};
use crate::structure::{BodyKind, CableLaw, Inertia, Member, Structure, Vec3, DEFAULT_TENDON_RADIUS_M};
use std::f64::consts::{FRAC_PI_2, PI};

/// Struts per stage: with 4, every stage-to-stage cable lies in a vertical plane through the
/// axis or in a mirrored pair about one (the next stage's nodes sit straight above or pi/n to
/// either side), so the links exert no torque about the axis. With 3 the vertical cables
/// would be 30 degrees off and the only equilibrium leaves every link slack.
pub const N: usize = 4;
/// Stage counts of the family (4 struts each: 4 .. 1000 struts).
pub const STAGES: [usize; 9] = [1, 2, 4, 8, 16, 32, 64, 128, 250];
/// Radius of the polygons [m].
const RADIUS_M: f64 = 1.0;
/// Height of one stage [m].
const HEIGHT_M: f64 = 1.5;
/// How far a stage's bottom polygon lies below the previous stage's top polygon [m].
const OVERLAP_M: f64 = 0.3;
/// Rise from one stage to the next [m].
const PITCH_M: f64 = HEIGHT_M - OVERLAP_M;
/// Target force density of the saddle cables, relative to the prisms' side cables.
const SADDLE_Q: f64 = 1.0;
/// Strain of the most strained cable in the design.
const MAX_CABLE_STRAIN: f64 = 0.1;
/// Smallest cable force density allowed in the design, relative to the largest.
const MIN_CABLE_Q_RATIO: f64 = 1e-3;
/// Cable stiffness [N/m], strut mass [kg].
const CABLE_STIFFNESS_N_PER_M: f64 = 100.0;
const STRUT_MASS_KG: f64 = 1.0;
/// Time step [s] and body damping [1/s] (the prisms').
const DT_S: f64 = 0.005;
const BODY_DAMPING_PER_S: f64 = 2.0;
/// Displacement of each free strut in the start \[m\].
pub const PERTURBATION_M: f64 = 0.02;

/// What a member is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Strut,
    Polygon,
    Side,
    Saddle,
    Vertical,
}

impl Kind {
    /// A stage's own cable (the stage-to-stage members are springs).
    pub fn is_cable(self) -> bool {
        matches!(self, Kind::Polygon | Kind::Side)
    }
}

/// The drawn tower: node positions, members (kind, node a, node b), the held nodes.
#[derive(Clone, Debug)]
pub struct Design {
    pub stages: usize,
    pub nodes: Vec<Vec3>,
    pub members: Vec<(Kind, usize, usize)>,
    pub fixed: Vec<bool>,
    /// Force densities [N/m], one per member (after [`force_densities`]).
    pub q: Vec<f64>,
}

fn bottom(s: usize, i: usize) -> usize {
    2 * N * s + i % N
}

fn top(s: usize, i: usize) -> usize {
    2 * N * s + N + i % N
}

/// The drawn geometry and members of an m-stage tower (no force densities yet).
pub fn geometry(stages: usize) -> Design {
    let twist = FRAC_PI_2 + PI / N as f64;
    let turn = twist + PI / N as f64; // stage-to-stage turn of the bottom polygons
    let mut nodes = Vec::new();
    for s in 0..stages {
        let z = s as f64 * PITCH_M;
        for (angle0, dz) in [(s as f64 * turn, 0.0), (s as f64 * turn + twist, HEIGHT_M)] {
            for i in 0..N {
                let a = angle0 + 2.0 * PI * i as f64 / N as f64;
                nodes.push([RADIUS_M * a.cos(), RADIUS_M * a.sin(), z + dz]);
            }
        }
    }
    // The node of stage s + 1 nearest above node i of stage s: its turn, wrapped to the
    // nearest multiple of the polygon angle.
    let sector = 2.0 * PI / N as f64;
    let shift = (N as f64 - (turn / sector).round()).rem_euclid(N as f64) as usize;
    let mut members = Vec::new();
    for s in 0..stages {
        for i in 0..N {
            members.push((Kind::Strut, bottom(s, i), top(s, i)));
            members.push((Kind::Polygon, bottom(s, i), bottom(s, i + 1)));
            members.push((Kind::Polygon, top(s, i), top(s, i + 1)));
            members.push((Kind::Side, bottom(s, i + 1), top(s, i)));
            if s + 1 < stages {
                // Bottom node i of stage s + 1 sits pi/n past top node i of stage s.
                members.push((Kind::Saddle, top(s, i), bottom(s + 1, i)));
                members.push((Kind::Saddle, top(s, i), bottom(s + 1, i + N - 1)));
                members.push((Kind::Vertical, top(s, i), top(s + 1, i + shift)));
                members.push((Kind::Vertical, bottom(s, i), bottom(s + 1, i + shift)));
            }
        }
    }
    let mut fixed = vec![false; nodes.len()];
    fixed[bottom(0, 0)] = true;
    fixed[top(0, 0)] = true;
    Design { stages, nodes, members, fixed, q: Vec::new() }
}

/// The target pattern: the prism's self-stress (side 1, polygons 1 / (2 sin(pi/n)), struts
/// -1), saddles [`SADDLE_Q`], verticals the saddles' vertical pull over theirs.
fn target_q(d: &Design) -> Vec<f64> {
    let polygon = 1.0 / (2.0 * (PI / N as f64).sin());
    d.members
        .iter()
        .map(|(kind, _, _)| match kind {
            Kind::Strut => -1.0,
            Kind::Polygon => polygon,
            Kind::Side => 1.0,
            Kind::Saddle => SADDLE_Q,
            Kind::Vertical => SADDLE_Q * OVERLAP_M / PITCH_M,
        })
        .collect()
}

/// Free-coordinate index of each node (None: held).
fn free_index(d: &Design) -> (Vec<Option<usize>>, usize) {
    let mut next = 0;
    let idx = d
        .fixed
        .iter()
        .map(|&f| {
            (!f).then(|| {
                next += 1;
                next - 1
            })
        })
        .collect();
    (idx, next)
}

/// The member's column of A: (node, x_other - x_node) at each free end.
fn column(d: &Design, a: usize, b: usize, idx: &[Option<usize>]) -> Vec<(usize, Vec3)> {
    let (pa, pb) = (d.nodes[a], d.nodes[b]);
    let ab = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
    let mut out = Vec::new();
    if let Some(i) = idx[a] {
        out.push((i, ab));
    }
    if let Some(j) = idx[b] {
        out.push((j, [-ab[0], -ab[1], -ab[2]]));
    }
    out
}

/// The largest force imbalance sum q (x_j - x_i) over the free nodes [N].
pub fn node_residual(d: &Design, q: &[f64]) -> f64 {
    let (idx, n) = free_index(d);
    let mut f = vec![[0.0; 3]; n];
    for ((_, a, b), qm) in d.members.iter().zip(q) {
        for (i, v) in column(d, *a, *b, &idx) {
            for k in 0..3 {
                f[i][k] += qm * v[k];
            }
        }
    }
    f.iter().map(|v| crate::structure::norm(*v)).fold(0.0, f64::max)
}

/// Regularisation of A A^T, relative to its largest diagonal entry: A has a null row space
/// (the rotation about the held strut's axis stretches no member), along which A q has no
/// component; the shift keeps the factorization positive definite.
const REGULARISATION: f64 = 1e-12;
/// Passes of the projection (each removes the residual A q that the last one left).
const PROJECTION_PASSES: usize = 3;

/// Why the tower has no design.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TowerError {
    /// A A^T cannot be factored.
    #[error("A A^T is singular: the tower has too few members")]
    Singular,
    /// The projection of the force densities gave a number that is not finite.
    #[error("the force density projection is not finite")]
    NotFinite,
    /// A cable's force density is too small a share of the largest.
    #[error("the design leaves a cable at force density {least} of the largest {largest}")]
    SlackCable { least: f64, largest: f64 },
}

/// A (free node coordinates x members) from the members' columns, with A A^T + shift factored
/// (`sim::least_squares`: a band Cholesky, the nodes numbered stage by stage).
fn normal_matrix(cols: &[Vec<(usize, Vec3)>], n: usize) -> Result<SparseLeastSquares, TowerError> {
    let mut entries = Vec::new();
    for (m, c) in cols.iter().enumerate() {
        for (i, u) in c {
            entries.extend((0..3).map(|k| (3 * i + k, m, u[k])));
        }
    }
    SparseLeastSquares::regularised(SparseRows::new(3 * n, cols.len(), &entries), REGULARISATION)
        .map_err(|_| TowerError::Singular)
}

/// The force densities nearest the target pattern that make the drawn shape an equilibrium,
/// scaled so the most strained cable is stretched `MAX_CABLE_STRAIN` [N/m].
pub fn force_densities(d: &Design) -> Result<Vec<f64>, TowerError> {
    let (idx, n) = free_index(d);
    let cols: Vec<Vec<(usize, Vec3)>> = d.members.iter().map(|(_, a, b)| column(d, *a, *b, &idx)).collect();
    let a = normal_matrix(&cols, n)?;
    let mut q = nalgebra::DVector::from_vec(target_q(d));
    // Each pass takes off A^T (A A^T + shift)^-1 A q: the part of q that A q sees.
    for _ in 0..PROJECTION_PASSES {
        let aq = a.matrix().mul(&q);
        let off = a.solve_refined(&aq, 0).ok_or(TowerError::NotFinite)?;
        q -= off;
    }
    let cable_q = d.members.iter().zip(&q).filter(|((k, _, _), _)| k.is_cable()).map(|(_, q)| *q);
    let (lo, hi) = cable_q.fold((f64::INFINITY, 0.0f64), |(lo, hi), q| (lo.min(q), hi.max(q)));
    if lo < MIN_CABLE_Q_RATIO * hi {
        return Err(TowerError::SlackCable { least: lo, largest: hi });
    }
    let scale = MAX_CABLE_STRAIN * CABLE_STIFFNESS_N_PER_M / hi;
    Ok(q.iter().map(|q| q * scale).collect())
}

/// The designed tower: geometry and force densities.
pub fn design(stages: usize) -> Result<Design, TowerError> {
    let mut d = geometry(stages);
    d.q = force_densities(&d)?;
    Ok(d)
}

/// A fixed pseudo-random unit vector per strut.
fn directions(count: usize) -> Vec<Vec3> {
    let mut d = crate::bench::FixedDirections::new(0x9e37_79b9_7f4a_7c15);
    (0..count).map(|_| d.next_unit()).collect()
}

/// The tower as a structure, every free strut moved by `perturbation_m`; rest lengths from
/// the design's force densities.
pub fn structure(d: &Design, perturbation_m: f64) -> Structure {
    let mut s = Structure { name: format!("{}-stage tower", d.stages), ..Default::default() };
    let dirs = directions(d.stages * N);
    let mut node_of = vec![usize::MAX; d.nodes.len()];
    let struts = d.members.iter().filter(|(k, _, _)| *k == Kind::Strut);
    for (k, (_, a, b)) in struts.enumerate() {
        let held = d.fixed[*a];
        let shift = if held { [0.0; 3] } else { dirs[k].map(|x| x * perturbation_m) };
        let (pa, pb) = ([0, 1, 2].map(|i| d.nodes[*a][i] + shift[i]), [0, 1, 2].map(|i| d.nodes[*b][i] + shift[i]));
        let length = crate::structure::distance(pa, pb);
        let inertia = Inertia {
            mass_kg: STRUT_MASS_KG,
            com: [0, 1, 2].map(|i| 0.5 * (pa[i] + pb[i])),
            // Isotropic: a slender rod's transverse moment about every axis.
            principal_kg_m2: [STRUT_MASS_KG * length * length / 12.0; 3],
        };
        let body = s.add_body(
            &format!("strut{k}"),
            if held { BodyKind::Fixed } else { BodyKind::Free },
            (!held).then_some(inertia),
        );
        node_of[*a] = s.add_node(&format!("n{a}"), body, pa);
        node_of[*b] = s.add_node(&format!("n{b}"), body, pb);
        s.members.push(Member::strut(format!("strut{k}"), node_of[*a], node_of[*b], 0.01));
    }
    let k = CABLE_STIFFNESS_N_PER_M;
    for (m, ((kind, a, b), q)) in d.members.iter().zip(&d.q).enumerate() {
        let l = crate::structure::distance(d.nodes[*a], d.nodes[*b]);
        let (name, a, b, rest) = (format!("{kind:?}{m}").to_lowercase(), node_of[*a], node_of[*b], l * (1.0 - q / k));
        match kind {
            Kind::Strut => {}
            Kind::Polygon | Kind::Side => {
                let law = CableLaw::Elastic { stiffness_n_per_m: k };
                s.members.push(Member::cable(name, vec![a, b], law, rest, 0.001));
            }
            Kind::Saddle | Kind::Vertical => {
                s.members.push(Member::spring(name, [a, b], k, rest, DEFAULT_TENDON_RADIUS_M))
            }
        }
    }
    s
}

/// The m-stage tower's case: perturbed start, the design as target (node indices of the
/// structure: each strut's nodes in strut order).
pub fn case(stages: usize) -> Result<Case, TowerError> {
    let d = design(stages)?;
    let start = structure(&d, PERTURBATION_M);
    let drawn = structure(&d, 0.0);
    Ok(Case {
        family: "tower",
        size: stages,
        settings: SimSettings { dt_s: DT_S, body_damping_per_s: BODY_DAMPING_PER_S, ..Default::default() },
        commands: Vec::new(),
        target: drawn.nodes.iter().enumerate().map(|(i, n)| (i, n.position)).collect(),
        measure: Measure::Aligned,
        spin: None,
        drive: None,
        start,
    })
}
