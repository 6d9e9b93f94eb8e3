//! `tensegrity fit S.toml --data measured.csv --param NAME[=LOW:HIGH] ...`: the scenario's
//! named parameters fitted to the measurements (`study::fit`, which `tt.fit` calls too), as a
//! table and, with `--json FILE` (`-`: standard output, the table then going to standard
//! error), as JSON. The data's errors are located at `FILE:LINE:COL`, the parameters' at their
//! flag.

use super::{bad_input, check_outputs, failed, signals, CliError, Outcome};
use crate::scenario::Override;
use crate::study::{FitError, FitProblem};
use std::path::Path;

pub fn fit(
    scenario: &Path,
    overrides: &[Override],
    data: &Path,
    params: &[String],
    json: Option<&Path>,
) -> Result<Outcome, CliError> {
    let outputs: Vec<(String, std::path::PathBuf)> =
        json.map(|j| ("--json".to_string(), j.to_path_buf())).into_iter().collect();
    check_outputs(&[scenario.to_path_buf(), data.to_path_buf()], &outputs)?;
    // `--data -` reads standard input, as every other input does; the scenario cannot be
    // read there too.
    if super::is_stdio(scenario) && super::is_stdio(data) {
        return Err(bad_input("the scenario - and --data -: only one of them can read standard input"));
    }
    let source = crate::input::read_text(scenario, crate::scenario::MAX_SCENARIO_BYTES, true)
        .map_err(|e| bad_input(format!("{}: the scenario file: {e}", scenario.display())))?;
    crate::scenario::parse_with(scenario, &source, overrides).map_err(bad_input)?;
    let parameters = params.iter().map(|p| crate::study::parse_parameter(p)).collect::<Result<Vec<_>, _>>();
    let measurements = crate::study::read_measurements("--data", data, true);
    let (parameters, measurements) = (parameters.map_err(cli_error)?, measurements.map_err(cli_error)?);
    let problem =
        FitProblem { file: scenario.to_path_buf(), source, overrides: overrides.to_vec(), parameters, measurements };
    let report = crate::study::fit(&problem, Some(&signals::CANCEL)).map_err(cli_error)?;
    super::print_report(&report.to_table(), json.is_some_and(super::is_stdio), json, &report)?;
    Ok(Outcome::from_passed(true))
}

/// A fit's error as the CLI's: bad input (exit 2) or a failure (exit 1).
fn cli_error(e: FitError) -> CliError {
    if e.is_bad_input() {
        bad_input(e.to_string())
    } else {
        failed(e.to_string())
    }
}
