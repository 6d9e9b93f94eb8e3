//! The icosahedron of `tensegrity bench --scale`: the 6-strut tensegrity icosahedron (the
//! expanded octahedron), as `scenarios/custom/icosahedron6.toml` draws it.
//!
//! Six struts of length L in three parallel pairs along x, y and z, and 24 cables joining each
//! node to its four nearest nodes on the other pairs. By symmetry its equilibrium is the
//! expanded octahedron: the pairs L/2 apart and every cable sqrt(6)/4 L long (the closed-form
//! cable / strut length ratio; a cable from (0, -L/4, -L/2) to (-L/2, 0, -L/4) is
//! sqrt(1/4 + 1/16 + 1/16) L). The start is drawn with the pairs [`START_SEPARATION_M`]
//! apart, strut a1-a2 held; the error is the largest node distance from the closed form after
//! the best rigid alignment.

use super::{Case, Measure};
use crate::settings::SimSettings;
use crate::structure::{BodyKind, CableLaw, Inertia, Member, Structure, Vec3};

/// Strut length L \[m\].
pub const STRUT_LENGTH_M: f64 = 1.0;
/// The pairs' separation in the start (the shipped scenario's) \[m\].
pub const START_SEPARATION_M: f64 = 0.45;
/// Cable stiffness [N/m] and rest length [m] (the shipped scenario's).
const CABLE_STIFFNESS_N_PER_M: f64 = 100.0;
const CABLE_REST_LENGTH_M: f64 = 0.5;
/// Mass of each free strut [kg].
const STRUT_MASS_KG: f64 = 0.5;
/// Time step [s] and body damping [1/s] (the shipped scenario's).
const DT_S: f64 = 0.002;
const BODY_DAMPING_PER_S: f64 = 8.0;

/// The closed-form cable length over the strut length, sqrt(6)/4.
pub fn cable_to_strut_ratio() -> f64 {
    6f64.sqrt() / 4.0
}

/// The 12 nodes (a1..a4, b1..b4, c1..c4) with the pairs `d` apart [m].
fn nodes(d: f64) -> [(&'static str, Vec3); 12] {
    let (h, e) = (0.5 * STRUT_LENGTH_M, 0.5 * d);
    [
        ("a1", [0.0, -e, -h]),
        ("a2", [0.0, -e, h]),
        ("a3", [0.0, e, -h]),
        ("a4", [0.0, e, h]),
        ("b1", [-h, 0.0, -e]),
        ("b2", [h, 0.0, -e]),
        ("b3", [-h, 0.0, e]),
        ("b4", [h, 0.0, e]),
        ("c1", [-e, -h, 0.0]),
        ("c2", [-e, h, 0.0]),
        ("c3", [e, -h, 0.0]),
        ("c4", [e, h, 0.0]),
    ]
}

/// The 24 cables, as node indices of [`nodes`] (each node to its four nearest on the other
/// pairs: the shipped scenario's groups ab, bc, ca).
const CABLES: [(usize, usize); 24] = [
    (0, 4),
    (0, 5),
    (1, 6),
    (1, 7),
    (2, 4),
    (2, 5),
    (3, 6),
    (3, 7),
    (4, 8),
    (4, 9),
    (5, 10),
    (5, 11),
    (6, 8),
    (6, 9),
    (7, 10),
    (7, 11),
    (8, 0),
    (8, 1),
    (9, 2),
    (9, 3),
    (10, 0),
    (10, 1),
    (11, 2),
    (11, 3),
];

/// The icosahedron drawn with its pairs `separation_m` apart, strut a1-a2 held.
pub fn icosahedron(separation_m: f64) -> Structure {
    let mut s = Structure { name: "6-strut icosahedron".into(), ..Default::default() };
    let ns = nodes(separation_m);
    for k in 0..6 {
        let (a, b) = (ns[2 * k], ns[2 * k + 1]);
        let com = [0, 1, 2].map(|i| 0.5 * (a.1[i] + b.1[i]));
        let inertia = Inertia {
            mass_kg: STRUT_MASS_KG,
            com,
            // Isotropic: a slender rod's transverse moment about every axis.
            principal_kg_m2: [STRUT_MASS_KG * STRUT_LENGTH_M * STRUT_LENGTH_M / 12.0; 3],
        };
        let kind = if k == 0 { BodyKind::Fixed } else { BodyKind::Free };
        let body = s.add_body(&format!("{}{}", a.0, b.0), kind, (k > 0).then_some(inertia));
        let (na, nb) = (s.add_node(a.0, body, a.1), s.add_node(b.0, body, b.1));
        s.members.push(Member::strut(format!("strut {}-{}", a.0, b.0), na, nb, 0.01));
    }
    // Nodes were added pairwise in the order of `nodes`, so node indices are those of `CABLES`.
    for (a, b) in CABLES {
        let law = CableLaw::Elastic { stiffness_n_per_m: CABLE_STIFFNESS_N_PER_M };
        let name = format!("{}-{}", ns[a].0, ns[b].0);
        s.members.push(Member::cable(name, vec![a, b], law, CABLE_REST_LENGTH_M, 0.001));
    }
    s
}

/// The case: drawn at [`START_SEPARATION_M`], compared with the expanded octahedron.
pub fn case() -> Case {
    let design = nodes(0.5 * STRUT_LENGTH_M);
    Case {
        family: "icosahedron",
        size: 6,
        start: icosahedron(START_SEPARATION_M),
        settings: SimSettings { dt_s: DT_S, body_damping_per_s: BODY_DAMPING_PER_S, ..Default::default() },
        commands: Vec::new(),
        target: design.iter().enumerate().map(|(i, (_, p))| (i, *p)).collect(),
        measure: Measure::Aligned,
        spin: None,
        drive: None,
    }
}
