//! `tensegrity modes S.toml`: the structure's natural frequencies and mode shapes at its
//! settled state (settled first as `run` settles its first point; `sim::modes`), as a table,
//! as JSON with `--json FILE` (`-`: standard output, the table then going to standard error),
//! and animated in a rerun recording with `--record FILE.rrd`.

use super::{bad_input, check_outputs, failed, load_one, signals, CliError, Outcome};
use crate::run::ModesRunError;
use crate::sim::modes::StructureModes;
use crate::structure::MemberKind;
use std::path::{Path, PathBuf};

pub fn modes(
    scenario: &Path,
    overrides: &[crate::scenario::Override],
    json: Option<&Path>,
    record: Option<&Path>,
    count: usize,
) -> Result<Outcome, CliError> {
    let sc = load_one(scenario, overrides)?;
    super::check_recording_path(record)?;
    let outputs: Vec<(String, PathBuf)> = [("--json", json), ("--record", record)]
        .into_iter()
        .filter_map(|(flag, p)| p.map(|p| (flag.to_string(), p.to_path_buf())))
        .collect();
    check_outputs(&[scenario.to_path_buf()], &outputs)?;
    let (report, state, analysis) =
        crate::run::modes(&sc, &scenario.display().to_string(), count, Some(&signals::CANCEL)).map_err(
            |e| match e {
                ModesRunError::Refused(_) => bad_input(format!("{}: {e}", scenario.display())),
                _ => failed(format!("{}: {e}", scenario.display())),
            },
        )?;
    // With `--json -` standard output is the JSON alone: the table goes to standard error.
    super::print_report(&report.to_table(), json.is_some_and(super::is_stdio), json, &report)?;
    if let Some(r) = record {
        record_modes(r, &state.sim, &analysis).map_err(failed)?;
    }
    Ok(Outcome::from_passed(state.settled))
}

/// The non-rigid modes animated at their frequencies (`observers::modes_record`).
fn record_modes(
    path: &Path,
    sim: &crate::sim::Simulation,
    analysis: &StructureModes,
) -> Result<(), crate::observers::record::RecordError> {
    use crate::observers::modes_record::{DrawnMode, DrawnStructure};
    let s = sim.structure();
    let segments = |kind| s.members_of(kind).flat_map(|(_, m)| m.segments()).collect();
    let drawn = DrawnStructure {
        nodes: (0..s.nodes.len()).map(|n| sim.node_position(n)).collect(),
        struts: segments(MemberKind::Strut),
        springs: segments(MemberKind::Spring),
        cables: segments(MemberKind::Cable),
    };
    let modes: Vec<DrawnMode> = analysis
        .modes
        .iter()
        .filter(|m| !m.rigid)
        .map(|m| DrawnMode { omega: m.omega(), node_motion: m.node_motion.clone() })
        .collect();
    crate::observers::modes_record::record_modes(path, &drawn, &modes)
}
