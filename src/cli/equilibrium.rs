//! `tensegrity equilibrium S.toml`: the equilibrium matrix of a pin-jointed structure at its
//! settled state and its SVD (`structure::equilibrium`), as a table and as JSON with
//! `--json FILE` (`-`: standard output, the table then going to standard error).

use super::{bad_input, check_outputs, failed, load_one, signals, CliError, Outcome};
use crate::run::EquilibriumRunError;
use std::path::{Path, PathBuf};

pub fn equilibrium(
    scenario: &Path,
    overrides: &[crate::scenario::Override],
    json: Option<&Path>,
) -> Result<Outcome, CliError> {
    let sc = load_one(scenario, overrides)?;
    let outputs: Vec<(String, PathBuf)> = json.map(|p| ("--json".to_string(), p.to_path_buf())).into_iter().collect();
    check_outputs(&[scenario.to_path_buf()], &outputs)?;
    let (report, state) = crate::run::equilibrium(&sc, &scenario.display().to_string(), Some(&signals::CANCEL))
        .map_err(|e| match e {
            EquilibriumRunError::Refused(_) => bad_input(format!("{}: {e}", scenario.display())),
            EquilibriumRunError::Run(_) => failed(format!("{}: {e}", scenario.display())),
        })?;
    super::print_report(&report.to_table(), json.is_some_and(super::is_stdio), json, &report)?;
    Ok(Outcome::from_passed(state.settled))
}
