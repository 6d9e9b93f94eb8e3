//! `tensegrity certify S.toml`: a proof of the settled equilibrium at the first point or
//! `--point N` (`study::certify`), as a table, and as JSON with `--json FILE` (`-`: standard
//! output, the table then going to standard error).

use super::{bad_input, check_outputs, failed, load_one, signals, CliError, Outcome};
use crate::study::certify::CertifyRunError;
use std::path::Path;

pub fn certify(
    scenario: &Path,
    overrides: &[crate::scenario::Override],
    json: Option<&Path>,
    point: usize,
) -> Result<Outcome, CliError> {
    let sc = load_one(scenario, overrides)?;
    let outputs: Vec<(String, std::path::PathBuf)> =
        json.map(|j| ("--json".to_string(), j.to_path_buf())).into_iter().collect();
    check_outputs(&[scenario.to_path_buf()], &outputs)?;
    let file = scenario.display().to_string();
    let report = crate::study::certify::certify(&sc, &file, point, Some(&signals::CANCEL)).map_err(|e| match e {
        CertifyRunError::Refused(_) | CertifyRunError::Motion => bad_input(format!("{}: {e}", scenario.display())),
        CertifyRunError::NoPoint(_) => bad_input(format!("--point {point}: {e}")),
        CertifyRunError::Run(_) => failed(format!("{}: {e}", scenario.display())),
    })?;
    super::print_report(&report.to_table(), json.is_some_and(super::is_stdio), json, &report)?;
    Ok(Outcome::from_passed(report.settled && report.proven()))
}

/// Refuses (exit 2, naming `--certify` and the file) a scenario whose settle points cannot be
/// certified (`study::certify::certifiable`: a motion, a structure outside the proof's domain),
/// before anything runs: `run` and `sweep` with `--certify` or a file's `[certify]`.
pub(super) fn refuse_uncertifiable(sc: &crate::scenario::Scenario, path: &Path) -> Result<(), CliError> {
    crate::study::certify::certifiable(sc, 0).map_err(|e| bad_input(format!("--certify: {}: {e}", path.display())))
}
