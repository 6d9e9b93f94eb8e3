//! The prestress an import gives a structure: the drawn structure's own self-stress (member
//! forces in equilibrium at every node with no load: cables in tension, struts in
//! compression), scaled so that the least cable tension is a stated one, set by each elastic
//! cable's rest length (drawn length less tension / stiffness). The drawn state is then an
//! equilibrium and the structure settles where it was drawn, prestressed.
//!
//! The self-stress is found in the null space of the equilibrium matrix (one column per
//! member: its unit vector at its two nodes, one row per coordinate of a node not on a fixed
//! anchor; a node on a strut counts even when its body is held) as the projection of a uniform
//! stress (cables +1, struts -1) on it (Pellegrino 1993, "Structural computations with the
//! singular value decomposition of the equilibrium matrix").

use super::draft::{Draft, DraftError};
use crate::structure::{distance, Vec3};
use nalgebra::DMatrix;
use std::cmp::Ordering;

/// Singular values of the equilibrium matrix below this share of the largest are its null
/// space's (a drawing given to 9 digits or more; the decomposition's own error is ~1e-16).
const NULL_SPACE_FRACTION: f64 = 1e-9;
/// A cable whose share of the stress is below this fraction of the largest member force
/// counts as carrying none: no self-stress keeps every cable taut.
const TAUT_FRACTION: f64 = 1e-6;

/// What an import did to prestress the structure, in a sentence.
pub struct Chosen {
    pub sentence: String,
    /// The least and largest cable tension at the drawn state \[N\].
    pub least_n: f64,
    pub largest_n: f64,
}

/// The drawn structure's self-stress: one tension per cable \[N\] in `draft.cables` order, the
/// least of them 1 (struts in compression), or None when no self-stress keeps every cable in
/// tension.
pub fn self_stress(draft: &Draft) -> Option<Vec<f64>> {
    let nodes: Vec<(&str, Vec3)> =
        draft.bodies.iter().flat_map(|b| b.nodes.iter().map(|(n, p)| (n.as_str(), *p))).collect();
    let index = |n: &str| nodes.iter().position(|(m, _)| *m == n);
    let on_strut = |n: &str| draft.struts.iter().any(|s| s.a == n || s.b == n);
    let anchored: Vec<[bool; 3]> = nodes
        .iter()
        .map(|(n, _)| [draft.bodies.iter().any(|b| b.fixed && b.nodes.iter().any(|(m, _)| m == n)) && !on_strut(n); 3])
        .collect();
    let cables: Vec<Vec<usize>> =
        draft.cables.iter().map(|c| c.path().map(index).collect::<Option<Vec<_>>>()).collect::<Option<_>>()?;
    let struts: Vec<Vec<usize>> =
        draft.struts.iter().map(|s| Some(vec![index(&s.a)?, index(&s.b)?])).collect::<Option<_>>()?;
    let positions: Vec<Vec3> = nodes.iter().map(|(_, p)| *p).collect();
    self_stress_of(&positions, &anchored, &cables, &struts)
}

/// A drawing's self-stress: node positions \[m\], which of each node's coordinates are
/// anchored (held, and on no strut: no row of the equilibrium matrix), the tension members and the struts by their paths
/// of nodes. A clustered cable's column is the sum of its segments' (one tension in every
/// segment: the clustering of Moored and Bruhns). One tension per tension member, the least of
/// them 1 (struts in compression), or None when no self-stress keeps every tension member in
/// tension.
pub fn self_stress_of<P: AsRef<[usize]>>(
    positions: &[Vec3],
    anchored: &[[bool; 3]],
    tension: &[P],
    struts: &[P],
) -> Option<Vec<f64>> {
    // One row per coordinate that no support holds (a roller holds some of a node's three).
    let mut row = vec![[None; 3]; positions.len()];
    let mut rows = 0;
    for (n, held) in anchored.iter().enumerate() {
        for k in (0..3).filter(|&k| !held[k]) {
            row[n][k] = Some(rows);
            rows += 1;
        }
    }
    let members: Vec<&[usize]> = tension.iter().chain(struts).map(|p| p.as_ref()).collect();
    let mut a = DMatrix::<f64>::zeros(rows, members.len());
    for (j, path) in members.iter().enumerate() {
        for segment in path.windows(2) {
            let (na, nb) = (segment[0], segment[1]);
            let (pa, pb) = (positions[na], positions[nb]);
            let l = distance(pa, pb);
            for (n, sign) in [(na, 1.0), (nb, -1.0)] {
                for k in 0..3 {
                    if let Some(r) = row[n][k] {
                        a[(r, j)] += sign * (pb[k] - pa[k]) / l;
                    }
                }
            }
        }
    }
    let stress = projected_uniform_stress(&a, tension.len())?;
    let largest = stress.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let cables = &stress[..tension.len()];
    let least = cables.iter().copied().fold(f64::INFINITY, f64::min);
    // Unordered (a NaN) counts as not taut.
    if least.partial_cmp(&(TAUT_FRACTION * largest)).is_none_or(Ordering::is_le) {
        return None;
    }
    Some(cables.iter().map(|t| t / least).collect())
}

/// The uniform stress (the first `cables` members +1, the rest -1) projected on the null
/// space of `a` (None: no null space), from its singular value decomposition (zero rows added
/// so that every right singular vector is computed).
fn projected_uniform_stress(a: &DMatrix<f64>, cables: usize) -> Option<Vec<f64>> {
    let m = a.ncols();
    let mut padded = DMatrix::<f64>::zeros(a.nrows().max(m), m);
    padded.view_mut((0, 0), (a.nrows(), m)).copy_from(a);
    let svd = padded.svd(false, true);
    let v_t = svd.v_t?;
    let top = svd.singular_values.iter().copied().fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
    let uniform: Vec<f64> = (0..m).map(|j| if j < cables { 1.0 } else { -1.0 }).collect();
    let mut t = vec![0.0; m];
    let mut found = false;
    for (i, sigma) in svd.singular_values.iter().enumerate() {
        if *sigma > NULL_SPACE_FRACTION * top {
            continue;
        }
        found = true;
        let v = v_t.row(i);
        let c: f64 = v.iter().zip(&uniform).map(|(x, u)| x * u).sum();
        t.iter_mut().zip(v.iter()).for_each(|(t, x)| *t += c * x);
    }
    found.then_some(t)
}

/// The rest length \[m\] that gives a member of stiffness `stiffness_n_per_m` drawn `drawn_m`
/// long the tension `tension_n`, drawn - tension / stiffness; None where it is not positive
/// (the member cannot carry that tension at that length). Shared with the scenario's
/// `[prestress]`.
pub fn rest_length_for(tension_n: f64, stiffness_n_per_m: f64, drawn_m: f64) -> Option<f64> {
    let rest = drawn_m - tension_n / stiffness_n_per_m;
    (rest > 0.0).then_some(rest)
}

/// Prestresses `draft` with its self-stress scaled so that the least cable tension is
/// `least_n` \[N\]: each elastic cable's rest length set to its drawn length less its tension
/// over its stiffness. None when there is no such self-stress (nothing changed); an error
/// naming the cable when a tension leaves it no rest length.
pub fn prestress(draft: &mut Draft, least_n: f64) -> Result<Option<Chosen>, DraftError> {
    let Some(stress) = self_stress(draft) else { return Ok(None) };
    let drawn: Vec<f64> = draft.cables.iter().map(|c| draft.drawn_length(c).unwrap_or_default()).collect();
    for ((c, t), drawn) in draft.cables.iter_mut().zip(&stress).zip(drawn) {
        let Some(k) = c.stiffness_n_per_m else { continue };
        let tension = t * least_n;
        c.length_m = rest_length_for(tension, k, drawn).ok_or_else(|| DraftError::SelfStressNoRest {
            cable: c.name.clone(),
            tension_n: tension,
            stiffness_n_per_m: k,
            drawn_m: drawn,
        })?;
    }
    let largest = stress.iter().copied().fold(0.0, f64::max) * least_n;
    let sentence = format!(
        "prestress: the drawn structure's self-stress, its least cable tension {least_n} N (largest {largest:.6} N), \
         set by each cable's rest length (drawn - tension / stiffness): the drawn state is an equilibrium"
    );
    Ok(Some(Chosen { sentence, least_n, largest_n: largest }))
}
