//! `tensegrity modes S.toml`: the structure's natural frequencies and mode shapes at its
//! settled state (settled first as `run` settles its first point; `sim::modes`), as a table,
//! as JSON with `--json FILE` (`-`: standard output, the table then going to standard error),
//! and animated in a rerun recording with `--record FILE.rrd`.

use super::{bad_input, check_outputs, failed, load_one, signals, write_atomic, CliError, Outcome};
use crate::report::modes::{ConstraintsReport, ModeReport, ModesReport};
use crate::sim::modes::{Constraints, ModesError, StructureModes, NODES_LISTED, ZERO_MODE_RATIO};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub fn modes(
    scenario: &Path,
    overrides: &[crate::scenario::Override],
    json: Option<&Path>,
    record: Option<&Path>,
) -> Result<Outcome, CliError> {
    let sc = load_one(scenario, overrides)?;
    super::check_recording_path(record)?;
    let outputs: Vec<(String, PathBuf)> = [("--json", json), ("--record", record)]
        .into_iter()
        .filter_map(|(flag, p)| p.map(|p| (flag.to_string(), p.to_path_buf())))
        .collect();
    check_outputs(&[scenario.to_path_buf()], &outputs)?;
    let mut state = crate::run::settle_first_point(&sc, Some(&signals::CANCEL))
        .map_err(|e| failed(format!("{}: {e}", scenario.display())))?;
    let wall = Instant::now();
    let analysis = state.sim.modes().map_err(|e| match e {
        ModesError::Eigen(_) => failed(format!("{}: {e}", scenario.display())),
        _ => bad_input(format!("{}: {e}", scenario.display())),
    })?;
    let report = ModesReport {
        name: sc.name.clone(),
        file: scenario.display().to_string(),
        settled: state.settled,
        settle_steps: state.steps,
        free_bodies: analysis.bodies.len(),
        coordinates: match &analysis.constraints {
            Some(c) => c.coordinates.len(),
            None if analysis.joints.is_empty() => 6 * analysis.bodies.len(),
            None => analysis.joints.len(),
        },
        joint_coordinates: analysis.joints.iter().map(|j| state.sim.structure().joints[*j].name.clone()).collect(),
        constraints: analysis.constraints.as_ref().map(|c| constraints_report(c, state.sim.structure())),
        rigid_modes: analysis.rigid,
        zero_mode_ratio: ZERO_MODE_RATIO,
        modes: rows(&analysis, &state.sim.structure().nodes),
        wall_s: wall.elapsed().as_secs_f64(),
    };
    // With `--json -` standard output is the JSON alone: the table goes to standard error.
    if json.is_some_and(super::is_stdio) {
        eprint!("{}", report.to_table());
    } else {
        print!("{}", report.to_table());
    }
    if let Some(j) = json {
        write_atomic(j, &serde_json::to_string_pretty(&report).expect("report serialises"))?;
    }
    if let Some(r) = record {
        record_modes(r, &state.sim, &analysis).map_err(failed)?;
    }
    Ok(Outcome::from_passed(state.settled))
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
            .map(|(&k, t)| (s.cables[k].name.clone(), *t))
            .collect(),
        slack_cables: c.slack_cables.iter().map(|&k| s.cables[k].name.clone()).collect(),
    }
}

/// The non-rigid modes animated at their frequencies (`observers::modes_record`).
fn record_modes(
    path: &Path,
    sim: &crate::sim::Simulation,
    analysis: &StructureModes,
) -> Result<(), crate::observers::record::RecordError> {
    use crate::observers::modes_record::{DrawnMode, DrawnStructure};
    let s = sim.structure();
    let drawn = DrawnStructure {
        nodes: (0..s.nodes.len()).map(|n| sim.node_position(n)).collect(),
        struts: s.struts.iter().map(|m| (m.a, m.b)).collect(),
        springs: s.springs.iter().map(|m| (m.a, m.b)).collect(),
        cables: s.cables.iter().map(|m| (m.a, m.b)).collect(),
    };
    let modes: Vec<DrawnMode> = analysis
        .modes
        .iter()
        .filter(|m| !m.rigid)
        .map(|m| DrawnMode { omega: m.omega(), node_motion: m.node_motion.clone() })
        .collect();
    crate::observers::modes_record::record_modes(path, &drawn, &modes)
}

/// One report row per mode.
fn rows(analysis: &StructureModes, nodes: &[crate::structure::Node]) -> Vec<ModeReport> {
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
            largest_moving: m
                .largest_moving(NODES_LISTED)
                .into_iter()
                .map(|(n, d)| (nodes[n].name.clone(), d))
                .collect(),
        })
        .collect()
}
