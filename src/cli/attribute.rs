//! `tensegrity attribute S.toml`: what each `[[fidelity]]` relaxation costs the file's model
//! (`study::attribution`), as a table, and with `--json FILE`, `--csv FILE` (either `-`:
//! standard output, the table then going to standard error) and `--figure FILE.svg|png` (one
//! bar per compared value, split by relaxation).

use super::{bad_input, check_outputs, failed, load_one, signals, write_atomic, CliError, Outcome};
use crate::study::attribution::AttributionError;
use std::path::{Path, PathBuf};

pub fn attribute(
    scenario: &Path,
    overrides: &[crate::scenario::Override],
    json: Option<&Path>,
    csv: Option<&Path>,
    figure: Option<&Path>,
) -> Result<Outcome, CliError> {
    if json.is_some_and(super::is_stdio) && csv.is_some_and(super::is_stdio) {
        return Err(bad_input("--json - and --csv -: only one of them can write to standard output"));
    }
    let format = figure.map(|f| {
        crate::figures::Format::of(f)
            .ok_or_else(|| bad_input(format!("--figure {}: the file ends in .svg or .png", f.display())))
    });
    let format = format.transpose()?;
    let outputs: Vec<(String, PathBuf)> = [("--json", json), ("--csv", csv), ("--figure", figure)]
        .into_iter()
        .filter_map(|(flag, p)| p.map(|p| (flag.to_string(), p.to_path_buf())))
        .collect();
    check_outputs(&[scenario.to_path_buf()], &outputs)?;
    let sc = load_one(scenario, overrides)?;
    let report = crate::study::attribution::attribute(&sc, Some(&signals::CANCEL)).map_err(|e| match e {
        AttributionError::NoRelaxation | AttributionError::Level { .. } => {
            bad_input(format!("{}: {e}", scenario.display()))
        }
        AttributionError::Cancelled => failed(format!("{}: {e}", scenario.display())),
    })?;
    let to_stderr = json.is_some_and(super::is_stdio) || csv.is_some_and(super::is_stdio);
    super::print_report(&report.to_table(), to_stderr, json, &report)?;
    if let Some(c) = csv {
        write_atomic(c, &report.to_csv())?;
    }
    if let (Some(f), Some(format)) = (figure, format) {
        crate::figures::attribution::write(&report, &[(f.to_path_buf(), format)])
            .map_err(|e| failed(format!("--figure {}: {e}", f.display())))?;
    }
    let ran = report.levels.iter().all(|l| l.error.is_none());
    Ok(Outcome::from_passed(ran))
}
