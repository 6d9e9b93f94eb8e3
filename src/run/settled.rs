//! A scenario's structure settled at its first point, for analyses of the settled state
//! (`tensegrity modes`): the run's own start and settle loop (the same accelerators and
//! criteria as `run`), and the simulation handed back instead of a report.

use super::{start_at, RunError, RunOptions};
use crate::mechanisms::Values;
use crate::report::modes::{ConstraintsReport, ModeReport, ModesReport};
use crate::scenario::Scenario;
use crate::sim::modes::{Constraints, ModesError, StructureModes, NODES_LISTED, ZERO_MODE_RATIO};
use crate::sim::Simulation;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// The simulation at its settled state.
pub struct SettledState {
    pub sim: Simulation,
    /// Whether the settle criteria were met (else the state is where the settle time ran out).
    pub settled: bool,
    /// Steps taken.
    pub steps: u64,
}

/// Settles `sc` at its first point (a schedule: its first waypoint) as `run` does (without a
/// recording, so with nothing to warn of).
pub fn settle_first_point(sc: &Scenario, cancel: Option<&AtomicBool>) -> Result<SettledState, RunError> {
    let inputs = sc.actuation.first_inputs().clone();
    settle_at(sc, &inputs, sc.params_at(&inputs), cancel)
}

/// Settles `sc` at `inputs` with every parameter at `params` (its value at the point, or
/// another: a difference of settles over a parameter), as `run` settles a point.
pub fn settle_at(
    sc: &Scenario,
    inputs: &Values,
    params: Values,
    cancel: Option<&AtomicBool>,
) -> Result<SettledState, RunError> {
    let opts = RunOptions { cancel, skip_findings: true, bare: true, ..RunOptions::default() };
    let mut runner = start_at(sc.mechanism(), sc, &opts, &mut Vec::new(), inputs, params)?;
    let prediction = runner.mech.predict(&runner.params, inputs)?;
    let settled = runner.settle(inputs, &prediction)?;
    Ok(SettledState { sim: runner.sim, settled: settled.settled, steps: settled.steps })
}

/// Why a modal analysis gave no report.
#[derive(Debug, thiserror::Error)]
pub enum ModesRunError {
    /// The settle to the first point stopped (divergence, interruption, a model error).
    #[error(transparent)]
    Run(#[from] RunError),
    /// The structure's modes are not computed, by name (bad input).
    #[error(transparent)]
    Refused(ModesError),
    /// The eigenproblem itself failed.
    #[error(transparent)]
    Eigen(ModesError),
}

/// The modal analysis of `sc` at its first point, settled as `run` settles it: the report
/// `tensegrity modes` prints (and `tensegrity_testbed.modes` returns), named by `file`; the
/// settled state and the analysis with it (for a recording of the modes). Above
/// `DENSE_MODAL_MAX_FREE_BODIES` free bodies the lowest `count` non-rigid modes.
pub fn modes(
    sc: &Scenario,
    file: &str,
    count: usize,
    cancel: Option<&AtomicBool>,
) -> Result<(ModesReport, SettledState, StructureModes), ModesRunError> {
    if let Some(c) = &sc.custom {
        // Refused before the settle: the analysis that follows it would not be made.
        crate::sim::modes::check_modal_size(&c.structure).map_err(ModesRunError::Refused)?;
    }
    let mut state = settle_first_point(sc, cancel)?;
    let wall = Instant::now();
    let lowest = crate::sim::modes::Lowest { count, through: None };
    let analysis = state.sim.modes_until(lowest, cancel).map_err(|e| match e {
        ModesError::Eigen(crate::eigen::EigenError::Interrupted) => RunError::Interrupted(state.sim.tick()).into(),
        ModesError::Eigen(_) => ModesRunError::Eigen(e),
        _ => ModesRunError::Refused(e),
    })?;
    let structure = state.sim.structure();
    let report = ModesReport {
        name: sc.name.clone(),
        file: file.to_string(),
        settled: state.settled,
        settle_steps: state.steps,
        free_bodies: analysis.bodies.len(),
        coordinates: match &analysis.constraints {
            Some(c) => c.coordinates.len(),
            None if analysis.joints.is_empty() => 6 * analysis.bodies.len() - analysis.left_out,
            None => analysis.joints.len(),
        },
        joint_coordinates: analysis.joints.iter().map(|j| structure.joints[*j].name.clone()).collect(),
        constraints: analysis.constraints.as_ref().map(|c| constraints_report(c, structure)),
        rigid_modes: analysis.rigid,
        zero_mode_ratio: ZERO_MODE_RATIO,
        modes: rows(&analysis, &structure.nodes, &mechanisms(&state.sim, &analysis)),
        lowest_of: analysis.lowest_of,
        wall_s: wall.elapsed().as_secs_f64(),
    };
    Ok((report, state, analysis))
}

/// What the constrained analysis was reduced by, by name.
fn constraints_report(c: &Constraints, s: &crate::structure::Structure) -> ConstraintsReport {
    let loop_rows = c.multipliers.len() - c.taut_cables.len();
    ConstraintsReport {
        rows: c.rows,
        rank: c.rank,
        degrees_of_freedom: c.degrees_of_freedom(),
        loop_closures: c.closures.iter().map(|&j| s.joints[j].name.clone()).collect(),
        taut_cables: c
            .taut_cables
            .iter()
            .zip(&c.multipliers[loop_rows..])
            .map(|(&k, t)| (s.members[k].name.clone(), *t))
            .collect(),
        slack_cables: c.slack_cables.iter().map(|&k| s.members[k].name.clone()).collect(),
        zero_floor_rad2_per_s2: c.zero_floor,
    }
}

/// Below this share of a mode's stiffness omega^2 in the members' stretching, the mode is a
/// mechanism stiffened by the prestress: a mode that stretches members has nearly all of it
/// there, an infinitesimal mechanism about the tension over the stiffness (its strain).
const MECHANISM_STRETCH_SHARE: f64 = 0.5;

/// Which modes are mechanisms stiffened by the prestress (`ModeReport::mechanism`): their
/// stretching energy sum k e^2 over the elastic members that pull or push (e the first-order
/// elongation of the mass-normalised shape) below [`MECHANISM_STRETCH_SHARE`] of omega^2. Only
/// for free bodies on members: where joints carry the bodies, torsion springs store energy that
/// no member's stretch shows.
fn mechanisms(sim: &Simulation, analysis: &StructureModes) -> Vec<bool> {
    let s = sim.structure();
    if !s.joints.is_empty() || analysis.constraints.is_some() {
        return vec![false; analysis.modes.len()];
    }
    let forces = sim.member_forces();
    let at: Vec<nalgebra::Vector3<f64>> = (0..s.nodes.len()).map(|n| sim.node_position(n).into()).collect();
    let stretch = |mode: &crate::sim::modes::StructureMode| -> f64 {
        let d = |n: usize| nalgebra::Vector3::from(mode.node_motion[n]);
        s.members
            .iter()
            .enumerate()
            .filter_map(|(k, member)| {
                let stiffness = member.stiffness_n_per_m()?;
                let pulling = member.kind() != crate::structure::MemberKind::Cable || forces.force_n[k] > 0.0;
                let e: f64 = member.segments().map(|(p, q)| (at[q] - at[p]).normalize().dot(&(d(q) - d(p)))).sum();
                pulling.then_some(stiffness * e * e)
            })
            .sum()
    };
    let share = |mode: &crate::sim::modes::StructureMode| stretch(mode) / mode.omega_squared.abs();
    analysis.modes.iter().map(|mode| !mode.rigid && share(mode) < MECHANISM_STRETCH_SHARE).collect()
}

/// One report row per mode.
fn rows(analysis: &StructureModes, nodes: &[crate::structure::Node], mechanism: &[bool]) -> Vec<ModeReport> {
    analysis
        .modes
        .iter()
        .enumerate()
        .map(|(i, m)| ModeReport {
            index: i + 1,
            omega_squared: m.omega_squared,
            omega_rad_per_s: m.omega(),
            frequency_hz: m.omega() / std::f64::consts::TAU,
            rigid: m.rigid,
            mechanism: mechanism[i],
            largest_moving: m
                .largest_moving(NODES_LISTED)
                .into_iter()
                .map(|(n, d)| (nodes[n].name.clone(), d))
                .collect(),
            node_displacements_m: if m.rigid {
                Vec::new()
            } else {
                nodes.iter().zip(&m.node_motion).map(|(n, d)| (n.name.clone(), *d)).collect()
            },
        })
        .collect()
}
