//! `tensegrity equilibrium`: the equilibrium matrix of the structure settled at its first
//! point, its subspaces and the supports' reactions (`structure::equilibrium`), and, where the
//! file states point loads, the linear analysis about the structure settled without them beside
//! the exact settle under them (`structure::linear`).

use super::settled::{settle_first_point, SettledState};
use super::RunError;
use crate::report::equilibrium::{EquilibriumReport, LinearReport};
use crate::scenario::Scenario;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Why `tensegrity equilibrium` gives no matrix.
#[derive(Debug, thiserror::Error)]
pub enum EquilibriumRunError {
    /// The settle to the first point stopped.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The structure is not pin-jointed, or too large (bad input).
    #[error(transparent)]
    Refused(#[from] crate::structure::equilibrium::EquilibriumError),
}

/// The equilibrium matrix of `sc`'s structure at its first point, settled as `run` settles it,
/// and its subspaces (`structure::equilibrium`).
pub fn equilibrium(
    sc: &Scenario,
    file: &str,
    cancel: Option<&AtomicBool>,
) -> Result<(EquilibriumReport, SettledState), EquilibriumRunError> {
    if let Some(c) = &sc.custom {
        // Refused before the settle, as the analysis would be.
        crate::structure::equilibrium::check(&c.structure)?;
    }
    let state = settle_first_point(sc, cancel)?;
    let wall = Instant::now();
    let s = state.sim.structure();
    let positions = state.sim.node_positions();
    let e = crate::structure::equilibrium::equilibrium_matrix(s, &positions)?;
    let report = EquilibriumReport {
        name: sc.name.clone(),
        file: file.to_string(),
        settled: state.settled,
        settle_steps: state.steps,
        rows: e.shape.0,
        free_nodes: e.nodes.len(),
        held_coordinates: 3 * e.nodes.len() - e.shape.0,
        columns: e.shape.1,
        all_singular_values: e.all_singular_values,
        rank: e.rank,
        self_stress_states: e.self_stress.len(),
        mechanisms: e.mechanism_count,
        rank_tolerance: crate::structure::equilibrium::RANK_TOLERANCE,
        singular_values: e.singular_values.clone(),
        self_stress: e.self_stress.iter().map(|t| self_stress_row(s, &e.members, t)).collect(),
        reactions_n: reactions(s, &positions, &state.sim.member_forces()),
        mechanism_shapes: e
            .mechanisms
            .iter()
            .map(|d| e.node_displacements(d).into_iter().map(|(n, x)| (s.nodes[n].name.clone(), x)).collect())
            .collect(),
        linear: None,
        linear_refused: None,
        wall_s: 0.0,
    };
    let report = with_linear(sc, report, &state, cancel)?;
    Ok((EquilibriumReport { wall_s: wall.elapsed().as_secs_f64(), ..report }, state))
}

/// `report` with the linear analysis beside the exact settle `loaded`, where the structure has
/// point loads: about the structure settled without them, or why it has none.
fn with_linear(
    sc: &Scenario,
    report: EquilibriumReport,
    loaded: &SettledState,
    cancel: Option<&AtomicBool>,
) -> Result<EquilibriumReport, EquilibriumRunError> {
    let s = loaded.sim.structure();
    let Some(custom) = sc.custom.as_ref().filter(|_| !s.node_loads.is_empty()) else { return Ok(report) };
    let mut reference_sc = sc.clone();
    reference_sc.custom = Some(custom.without_point_loads());
    let reference = settle_first_point(&reference_sc, cancel)?;
    let (before, after) = (reference.sim.node_positions(), loaded.sim.node_positions());
    let (t0, t) = (reference.sim.member_forces(), loaded.sim.member_forces());
    let tension = |m: usize| t0.force_n[m];
    match crate::structure::linear::linear_analysis(s, &before, &tension, &s.node_loads) {
        Err(why) => Ok(EquilibriumReport { linear_refused: Some(why.to_string()), ..report }),
        Ok(linear) => {
            let moved = |n: usize| [0, 1, 2].map(|x| after[n][x] - before[n][x]);
            let linear = LinearReport {
                reference_settled: reference.settled,
                reference_settle_steps: reference.steps,
                displacements_m: linear
                    .displacements_m
                    .iter()
                    .map(|&(n, d)| (s.nodes[n].name.clone(), moved(n), d))
                    .collect(),
                forces_n: linear.forces_n.iter().map(|&(m, f)| (s.members[m].name.clone(), t.force_n[m], f)).collect(),
            };
            Ok(EquilibriumReport { linear: Some(linear), ..report })
        }
    }
}

/// The reaction at each support \[N\], the force it exerts on the structure: at a node on a
/// fixed body that members reach, minus the pull of every segment that ends there (tension t
/// along the unit vector from the support to the segment's other node); at a support in some
/// directions (a point mass), minus the pulls, the point loads and the weight there, along the
/// held directions (the others are zero: nothing holds them).
fn reactions(
    s: &crate::structure::Structure,
    positions: &[[f64; 3]],
    forces: &crate::snapshot::MemberForces,
) -> Vec<(String, [f64; 3])> {
    use crate::structure::BodyKind;
    use nalgebra::Vector3;
    let held = s.held_translations();
    let fixed = |n: usize| s.bodies[s.nodes[n].body].kind == BodyKind::Fixed;
    let supported = |n: usize| held[s.nodes[n].body].contains(&true);
    let mut at: std::collections::BTreeMap<usize, Vector3<f64>> = Default::default();
    for (k, member) in s.members.iter().enumerate() {
        for (seg, (a, b)) in member.segments().enumerate() {
            let t = forces.segment_force_n[k].get(seg).copied().unwrap_or(forces.force_n[k]);
            for (support, other) in [(a, b), (b, a)] {
                if !(fixed(support) && !fixed(other) || supported(support)) {
                    continue;
                }
                let e = (Vector3::from(positions[other]) - Vector3::from(positions[support])).normalize();
                *at.entry(support).or_insert_with(Vector3::zeros) -= e * t;
            }
        }
    }
    for support in &s.supports {
        let r = at.entry(support.node).or_insert_with(Vector3::zeros);
        let body = s.nodes[support.node].body;
        *r -= Vector3::from(s.gravity) * s.bodies[body].inertia.map_or(0.0, |i| i.mass_kg);
        for load in s.node_loads.iter().filter(|l| l.node == support.node) {
            *r -= Vector3::from(load.force_n);
        }
        for (x, h) in held[body].iter().enumerate() {
            if !h {
                r[x] = 0.0;
            }
        }
    }
    at.into_iter().map(|(n, r)| (s.nodes[n].name.clone(), [r.x, r.y, r.z])).collect()
}

/// A self-stress state per member, scaled so that its largest magnitude is 1 and its cables'
/// tensions sum to a positive number (a tensegrity's cables pull).
fn self_stress_row(
    s: &crate::structure::Structure,
    members: &[usize],
    t: &nalgebra::DVector<f64>,
) -> Vec<(String, f64)> {
    let cables: f64 = members
        .iter()
        .zip(t.iter())
        .filter(|(k, _)| s.members[**k].kind() == crate::structure::MemberKind::Cable)
        .map(|(_, x)| x)
        .sum();
    let sign = if cables < 0.0 { -1.0 } else { 1.0 };
    let scale = sign / t.amax();
    members.iter().zip(t.iter()).map(|(&k, x)| (s.members[k].name.clone(), x * scale)).collect()
}
