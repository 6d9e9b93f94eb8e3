//! The spine family of `tensegrity bench --scale`: a tensegrity spine of m + 1 stacked
//! tetrahedral vertebrae (the Tetraspine's), the lowest held, joined by cables and springs.
//!
//! Vertebra i is one rigid body centred on the z axis at z = i h ([`PITCH_M`]): four legs from
//! its centre to two upper tips (+-a, 0, +c) and two lower tips (0, +-a, -c) (`REACH_M`,
//! `RISE_M`), so the tips span a tetrahedron. With h < 2 c the vertebrae overlap: each upper
//! tip of vertebra i is joined to both lower tips of vertebra i + 1 by a saddle cable, which
//! pushes them apart, and each tip to the same tip of the next vertebra by a vertical spring,
//! which pulls them together.
//!
//! The closed form is the drawn geometry, from its symmetry: at every interface the four
//! saddle cables carry a tension T and the four vertical springs V = T (2 c - h) / l_s (l_s the
//! saddle length). Then the forces one interface puts on a vertebra add up to zero: the
//! vertical components balance by the choice of V, and the saddles' horizontal components at
//! a lower tip (0, s a) add up to a pull toward the axis, which has no moment about the
//! centre; the vertical forces sit in pairs at +-a and cancel their moments. So every vertebra
//! is in equilibrium at the drawn pose whatever the number of vertebrae, with rest lengths
//! l_s - T / k and h - V / k. The start moves every free vertebra by [`PERTURBATION_M`] in a
//! fixed pseudo-random direction; the error is the largest node distance from the design (the
//! lowest vertebra is held, so no alignment).

use super::{Case, Measure};
use crate::settings::SimSettings;
use crate::structure::{BodyKind, CableLaw, Inertia, Member, Structure, Vec3, DEFAULT_TENDON_RADIUS_M};

/// Free vertebrae of the family. 249 (1000 struts) was measured too and did not settle within
/// 20000 steps: its residual stayed at 1.2e-9 N against the 1e-9 N criterion, its error at
/// 1.6e-3 m (BENCHMARKS.md); from 64 vertebrae the error grows as the column softens.
pub const VERTEBRAE: [usize; 8] = [1, 2, 4, 8, 16, 32, 64, 128];
/// Horizontal reach a of a tip from the vertebra's axis [m].
const REACH_M: f64 = 0.5;
/// Height c of the tips above (upper) and below (lower) the vertebra's centre [m].
const RISE_M: f64 = 0.4;
/// Distance h between the centres of consecutive vertebrae \[m\] (less than 2 c: they overlap).
pub const PITCH_M: f64 = 0.6;
/// Tension T of every saddle cable at the design [N].
const SADDLE_TENSION_N: f64 = 10.0;
/// Stiffness of the cables and springs [N/m].
const STIFFNESS_N_PER_M: f64 = 200.0;
/// Mass of a vertebra [kg].
const VERTEBRA_MASS_KG: f64 = 0.2;
/// Time step [s] and body damping [1/s] (the tower's).
const DT_S: f64 = 0.005;
const BODY_DAMPING_PER_S: f64 = 2.0;
/// Displacement of every free vertebra in the start \[m\].
pub const PERTURBATION_M: f64 = 0.02;

/// Vertebra i's centre and tips (upper +a, upper -a, lower +a, lower -a), displaced by `shift`.
fn vertebra(i: usize, shift: Vec3) -> [Vec3; 5] {
    let z = i as f64 * PITCH_M;
    let (a, c) = (REACH_M, RISE_M);
    [[0.0, 0.0, z], [a, 0.0, z + c], [-a, 0.0, z + c], [0.0, a, z - c], [0.0, -a, z - c]]
        .map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]])
}

/// The length of a saddle cable at the design (an upper tip to a lower tip of the next) \[m\].
pub fn saddle_length_m() -> f64 {
    let d = 2.0 * RISE_M - PITCH_M;
    (2.0 * REACH_M * REACH_M + d * d).sqrt()
}

/// The tension of every vertical spring at the design \[N\]: V = T (2 c - h) / l_s.
pub fn vertical_tension_n() -> f64 {
    SADDLE_TENSION_N * (2.0 * RISE_M - PITCH_M) / saddle_length_m()
}

/// The spine of `free` vertebrae above the held one, each moved by `perturbation_m`.
pub fn spine(free: usize, perturbation_m: f64) -> Structure {
    let mut s = Structure { name: format!("{free}-vertebra spine"), ..Default::default() };
    let mut directions = crate::bench::FixedDirections::new(0x5eed_5eed_5eed_5eed);
    let leg = (RISE_M * RISE_M + REACH_M * REACH_M).sqrt();
    let mut tips: Vec<[usize; 4]> = Vec::with_capacity(free + 1);
    for i in 0..=free {
        let shift = if i == 0 { [0.0; 3] } else { directions.next_unit().map(|x| x * perturbation_m) };
        let p = vertebra(i, shift);
        let inertia = Inertia {
            mass_kg: VERTEBRA_MASS_KG,
            com: p[0],
            // Isotropic: four legs of length `leg` about the centre, m leg^2 / 3 each way.
            principal_kg_m2: [VERTEBRA_MASS_KG * leg * leg / 3.0; 3],
        };
        let kind = if i == 0 { BodyKind::Fixed } else { BodyKind::Free };
        let body = s.add_body(&format!("vertebra{i}"), kind, (i > 0).then_some(inertia));
        let centre = s.add_node(&format!("v{i}c"), body, p[0]);
        let names = ["u+", "u-", "l+", "l-"];
        let t = [1, 2, 3, 4].map(|k| s.add_node(&format!("v{i}{}", names[k - 1]), body, p[k]));
        for (k, &tip) in t.iter().enumerate() {
            s.members.push(Member::strut(format!("v{i} leg {}", names[k]), centre, tip, 0.01));
        }
        tips.push(t);
    }
    let k = STIFFNESS_N_PER_M;
    let (saddle, vertical) = (saddle_length_m(), vertical_tension_n());
    for i in 0..free {
        let (below, above) = (tips[i], tips[i + 1]);
        for (u, l) in [(0, 2), (0, 3), (1, 2), (1, 3)] {
            let law = CableLaw::Elastic { stiffness_n_per_m: k };
            let rest = saddle - SADDLE_TENSION_N / k;
            let (a, b) = (below[u], above[l]);
            s.members.push(Member::cable(format!("saddle {i}:{u}{l}"), vec![a, b], law, rest, 0.001));
        }
        for t in 0..4 {
            s.members.push(Member::spring(
                format!("vertical {i}:{t}"),
                [below[t], above[t]],
                k,
                PITCH_M - vertical / k,
                DEFAULT_TENDON_RADIUS_M,
            ));
        }
    }
    s
}

/// The spine of `free` vertebrae: perturbed start, the design as target.
pub fn case(free: usize) -> Case {
    let design = spine(free, 0.0);
    Case {
        family: "spine",
        size: free,
        start: spine(free, PERTURBATION_M),
        settings: SimSettings { dt_s: DT_S, body_damping_per_s: BODY_DAMPING_PER_S, ..Default::default() },
        commands: Vec::new(),
        target: design.nodes.iter().enumerate().map(|(i, n)| (i, n.position)).collect(),
        measure: Measure::Absolute,
        spin: None,
        drive: None,
    }
}
