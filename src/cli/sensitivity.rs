//! `tensegrity sensitivity S.toml`: how the settled state's outputs move with every parameter
//! (`study::sensitivity`), as a table, as JSON with `--json FILE` and as CSV with `--csv FILE`
//! (either `-`: standard output, the table then going to standard error), at the first point
//! or `--point N`; `--check` also measures every derivative by differences of settles.

use super::{bad_input, check_outputs, failed, load_one, signals, write_atomic, CliError, Outcome};
use crate::study::SensitivityRunError;
use std::path::{Path, PathBuf};

pub fn sensitivity(
    scenario: &Path,
    overrides: &[crate::scenario::Override],
    (json, csv): (Option<&Path>, Option<&Path>),
    (point, params): (usize, &[String]),
    check: bool,
) -> Result<Outcome, CliError> {
    let sc = load_one(scenario, overrides)?;
    if let Some(name) = params.iter().find(|p| !sc.params.contains_key(*p)) {
        let known: Vec<&str> = sc.params.keys().map(String::as_str).collect();
        return Err(bad_input(format!("--param {name}: not a parameter of the scenario ({})", known.join(", "))));
    }
    if json.is_some_and(super::is_stdio) && csv.is_some_and(super::is_stdio) {
        return Err(bad_input("--json - and --csv -: only one of them can write to standard output"));
    }
    let outputs: Vec<(String, PathBuf)> = [("--json", json), ("--csv", csv)]
        .into_iter()
        .filter_map(|(flag, p)| p.map(|p| (flag.to_string(), p.to_path_buf())))
        .collect();
    check_outputs(&[scenario.to_path_buf()], &outputs)?;
    if crate::study::sensitivity_point_of(&sc, point).is_none() {
        return Err(bad_input(format!("--point {point}: {}", SensitivityRunError::NoPoint(point))));
    }
    let only = (!params.is_empty()).then_some(params);
    let file = scenario.display().to_string();
    let report = crate::study::sensitivity::sensitivity_to(&sc, &file, (point, only), check, Some(&signals::CANCEL))
        .map_err(|e| match e {
            SensitivityRunError::Refused(_) => bad_input(format!("{}: {e}", scenario.display())),
            _ => failed(format!("{}: {e}", scenario.display())),
        })?;
    // With `--json -` or `--csv -` standard output is that file alone: the table goes to
    // standard error.
    let to_stderr = json.is_some_and(super::is_stdio) || csv.is_some_and(super::is_stdio);
    super::print_report(&report.to_table(), to_stderr, json, &report)?;
    if let Some(c) = csv {
        write_atomic(c, &report.to_csv())?;
    }
    let failed_parameter = report.parameters.iter().any(|p| p.error.is_some());
    Ok(Outcome::from_passed(report.settled && !failed_parameter))
}
