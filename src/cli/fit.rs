//! `tensegrity fit S.toml --data measured.csv --param NAME[=LOW:HIGH] ...`: the scenario's
//! named parameters fitted to the measurements (`run::fit`), as a table and, with `--json
//! FILE` (`-`: standard output, the table then going to standard error), as JSON. The data's
//! errors are located at `FILE:LINE:COL`, the parameters' at their flag.

use super::{bad_input, check_outputs, failed, signals, write_atomic, CliError, Outcome};
use crate::run::{FitParameter, FitProblem, Measurement};
use crate::scenario::Override;
use std::path::Path;

/// Largest measurement file read \[bytes\].
pub const MAX_DATA_BYTES: u64 = 16 << 20;
/// The data's columns, the last one optional.
const COLUMNS: [&str; 4] = ["point", "output", "value", "sigma"];

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
    let source = crate::input::read_text(scenario, crate::scenario::MAX_SCENARIO_BYTES, true)
        .map_err(|e| bad_input(format!("{}: the scenario file: {e}", scenario.display())))?;
    crate::scenario::parse_with(scenario, &source, overrides).map_err(bad_input)?;
    let parameters = params.iter().map(|p| parameter(p)).collect::<Result<Vec<_>, _>>()?;
    let text = crate::input::read_text(data, MAX_DATA_BYTES, false)
        .map_err(|e| bad_input(format!("--data {}: {e}", data.display())))?;
    let measurements = measurements(&data.display().to_string(), &text)?;
    let problem =
        FitProblem { file: scenario.to_path_buf(), source, overrides: overrides.to_vec(), parameters, measurements };
    let report = crate::run::fit(&problem, Some(&signals::CANCEL)).map_err(|e| {
        if e.is_bad_input() {
            bad_input(e.to_string())
        } else {
            failed(e.to_string())
        }
    })?;
    if json.is_some_and(super::is_stdio) {
        eprint!("{}", report.to_table());
    } else {
        print!("{}", report.to_table());
    }
    if let Some(j) = json {
        write_atomic(j, &serde_json::to_string_pretty(&report).expect("report serialises"))?;
    }
    Ok(Outcome::from_passed(true))
}

/// `--param NAME`, `NAME=LOW:HIGH`, `NAME=LOW:` or `NAME=:HIGH`.
fn parameter(flag: &str) -> Result<FitParameter, CliError> {
    let (name, bounds) = flag.split_once('=').map_or((flag, None), |(n, b)| (n, Some(b)));
    let bad =
        |why: &str| bad_input(format!("--param {flag}: {why} (NAME, or NAME=LOW:HIGH with either bound left out)"));
    if name.trim().is_empty() {
        return Err(bad("no parameter name"));
    }
    let Some(bounds) = bounds else {
        return Ok(FitParameter { name: name.trim().to_string(), low: None, high: None });
    };
    let (lo, hi) = bounds.split_once(':').ok_or_else(|| bad("the bounds are LOW:HIGH"))?;
    let number = |s: &str| -> Result<Option<f64>, CliError> {
        if s.trim().is_empty() {
            return Ok(None);
        }
        match s.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(bad(&format!("the bound '{s}' is not a finite number"))),
        }
    };
    Ok(FitParameter { name: name.trim().to_string(), low: number(lo)?, high: number(hi)? })
}

/// The measurements of a CSV with a header naming [`COLUMNS`] (sigma optional, in any
/// order), each row's errors at `file:LINE:COL`.
fn measurements(file: &str, text: &str) -> Result<Vec<Measurement>, CliError> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(bad_input(format!("{file}:1:1: no header: the columns are {}", COLUMNS.join(","))));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut index = [None; 4];
    for (k, name) in names.iter().enumerate() {
        let Some(c) = COLUMNS.iter().position(|c| c == name) else {
            return Err(bad_input(format!(
                "{file}:1:{}: the column '{name}' names nothing: the columns are {} (sigma optional)",
                column_at(header, k),
                COLUMNS.join(",")
            )));
        };
        index[c] = Some(k);
    }
    if let Some(c) = (0..3).find(|&c| index[c].is_none()) {
        return Err(bad_input(format!("{file}:1:1: no column '{}' in the header '{header}'", COLUMNS[c])));
    }
    let mut rows = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            let what = format!("{} cells where the header has {}", cells.len(), names.len());
            return Err(bad_input(format!("{file}:{}:1: {what}", n + 1)));
        }
        let at = |c: usize| {
            (
                cells[index[c].expect("checked")],
                format!("{file}:{}:{}", n + 1, column_at(line, index[c].expect("checked"))),
            )
        };
        let number = |c: usize| -> Result<f64, CliError> {
            let (cell, at) = at(c);
            cell.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad_input(format!("{at}: {} '{cell}' is not a finite number", COLUMNS[c])))
        };
        let (point_cell, point_at) = at(0);
        let point = point_cell
            .parse::<usize>()
            .map_err(|_| bad_input(format!("{point_at}: point '{point_cell}' is not a point number (from 0)")))?;
        let sigma = match index[3] {
            Some(k) if !cells[k].is_empty() => Some(number(3)?),
            _ => None,
        };
        let output = at(1).0.to_string();
        rows.push(Measurement { at: format!("{file}:{}", n + 1), point, output, value: number(2)?, sigma });
    }
    Ok(rows)
}

/// The column (from 1) where cell `k` of a comma-separated `line` starts.
fn column_at(line: &str, k: usize) -> usize {
    line.match_indices(',').nth(k.wrapping_sub(1)).map_or(1, |(i, _)| i + 2)
}
