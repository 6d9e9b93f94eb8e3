//! `tensegrity export`: a scenario's structure in another simulator's format.

use super::args::ExportFormat;
use super::{bad_input, load_one, write_output, CliError, Outcome};
use crate::export::{mjcf::ActuatorMode, scenario_mjcf, validate_mjcf_options};

pub fn export(format: ExportFormat) -> Result<Outcome, CliError> {
    let ExportFormat::Mjcf { scenario, out, actuators, kp, cable_damping, set } = format;
    let sc = load_one(&scenario, &super::overrides(&set)?)?;
    validate_mjcf_options(kp, cable_damping).map_err(bad_input)?;
    let mode = if actuators == "position" { ActuatorMode::Position } else { ActuatorMode::Mocap };
    let mjcf =
        scenario_mjcf(&sc, mode, kp, cable_damping).map_err(|e| bad_input(format!("{}: {e}", scenario.display())))?;
    for w in &mjcf.warnings {
        eprintln!("warning: not exported: {w}");
    }
    write_output(out.as_deref(), &[scenario], &mjcf.xml)
}
