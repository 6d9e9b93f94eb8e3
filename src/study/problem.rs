//! A fit's statement: the parameters to fit, the measurements (read from a CSV at
//! `file:LINE:COL`), the scenario at given parameter values and why a fit has no result. The
//! solver (`fit.rs`) and the trajectory's outputs (`fit_trajectory.rs`) both read it; neither
//! imports the other's statement.

use crate::scenario::{Override, Scenario, ScenarioError};
use std::path::{Path, PathBuf};

/// A parameter to fit, with its optional box bounds (in its own unit).
#[derive(Clone, Debug, PartialEq)]
pub struct FitParameter {
    pub name: String,
    pub low: Option<f64>,
    pub high: Option<f64>,
}

/// A measured output at a settle point (from 0, as a run numbers them).
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Where it was read (`measured.csv:3`), for errors.
    pub at: String,
    pub point: usize,
    pub output: String,
    pub value: f64,
    /// Its standard deviation, in the output's unit; None: unweighted.
    pub sigma: Option<f64>,
    /// The time since the motion's start \[s\] of a trajectory row (`fit_trajectory.rs`: the
    /// output is a column of the motion's table); None: the settled state at `point`.
    pub time_s: Option<f64>,
}

/// What to fit: the scenario (its file and text, parsed again at each evaluation with its
/// `--set` flags and the fitted parameters), the parameters and the measurements.
#[derive(Clone, Debug)]
pub struct FitProblem {
    pub file: PathBuf,
    pub source: String,
    pub overrides: Vec<Override>,
    pub parameters: Vec<FitParameter>,
    pub measurements: Vec<Measurement>,
}

/// Why a fit has no result.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The scenario at some parameters does not parse (bad input).
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The data or the parameters named are wrong (bad input).
    #[error("{0}")]
    BadInput(String),
    /// A parameter reached its bound, or ran away (bad input: the data want it elsewhere).
    #[error("{0}")]
    Stopped(String),
    /// A settle or its sensitivities failed.
    #[error("{0}")]
    Failed(String),
}

impl FitError {
    /// Whether the error is the input's (exit 2) rather than the run's (exit 1).
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, FitError::Failed(_))
    }
}

/// The scenario parsed with the fitted parameters at `p` (as `--set NAME=VALUE`).
pub(crate) fn scenario_at(problem: &FitProblem, p: &[f64]) -> Result<Scenario, FitError> {
    let mut overrides = problem.overrides.clone();
    overrides.extend(
        problem.parameters.iter().zip(p).map(|(f, v)| Override { name: f.name.clone(), value: format!("{v:?}") }),
    );
    Ok(crate::scenario::parse_with(&problem.file, &problem.source, &overrides)?)
}

/// Largest measurement file read \[bytes\].
pub const MAX_DATA_BYTES: u64 = 16 << 20;
/// Most measurement rows a fit takes, from a file or from Python (`tt.fit`'s DataFrame is
/// bounded as the file is: refused before its rows are copied).
pub const MAX_DATA_ROWS: usize = 100_000;
/// The data's columns, the last two optional: `t_s`, a trajectory row's time since the
/// motion's start (`fit_trajectory.rs`).
pub const DATA_COLUMNS: [&str; 5] = ["point", "output", "value", "sigma", "t_s"];

/// The error past [`MAX_DATA_ROWS`], the file's and Python's alike.
pub fn too_many_rows() -> String {
    format!("more than {MAX_DATA_ROWS} measurement rows: at most {MAX_DATA_ROWS} (fit fewer, or average repeated rows)")
}

/// `NAME`, `NAME=LOW:HIGH`, `NAME=LOW:` or `NAME=:HIGH` (the CLI's `--param`) as a parameter
/// to fit.
pub fn parse_parameter(flag: &str) -> Result<FitParameter, FitError> {
    let (name, bounds) = flag.split_once('=').map_or((flag, None), |(n, b)| (n, Some(b)));
    let bad = |why: &str| {
        FitError::BadInput(format!("--param {flag}: {why} (NAME, or NAME=LOW:HIGH with either bound left out)"))
    };
    if name.trim().is_empty() {
        return Err(bad("no parameter name"));
    }
    let Some(bounds) = bounds else {
        return Ok(FitParameter { name: name.trim().to_string(), low: None, high: None });
    };
    let (lo, hi) = bounds.split_once(':').ok_or_else(|| bad("the bounds are LOW:HIGH"))?;
    let number = |s: &str| -> Result<Option<f64>, FitError> {
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

/// The measurements of the CSV file `path` (at most [`MAX_DATA_BYTES`]; `-` is standard
/// input when `stdin` allows it), as [`measurements_from_csv`] reads them; `what` names the
/// file in an error it cannot be read with (`--data`, `data`).
pub fn read_measurements(what: &str, path: &Path, stdin: bool) -> Result<Vec<Measurement>, FitError> {
    let text = crate::input::read_text(path, MAX_DATA_BYTES, stdin)
        .map_err(|e| FitError::BadInput(format!("{what} {}: {e}", path.display())))?;
    measurements_from_csv(&path.display().to_string(), &text)
}

/// The measurements of a CSV with a header naming [`DATA_COLUMNS`] (sigma optional, in any
/// order, each once; a UTF-8 byte-order mark before it is skipped), each row's errors at
/// `file:LINE:COL`.
pub fn measurements_from_csv(file: &str, text: &str) -> Result<Vec<Measurement>, FitError> {
    let bad = |s: String| FitError::BadInput(s);
    // A byte-order mark (a spreadsheet's UTF-8 export) is no part of the first column's name.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(bad(format!("{file}:1:1: no header: the columns are {}", DATA_COLUMNS.join(","))));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut index = [None; 5];
    for (k, name) in names.iter().enumerate() {
        let Some(c) = DATA_COLUMNS.iter().position(|c| c == name) else {
            return Err(bad(format!(
                "{file}:1:{}: the column '{name}' names nothing: the columns are {} (sigma and t_s optional)",
                column_at(header, k),
                DATA_COLUMNS.join(",")
            )));
        };
        if let Some(first) = index[c] {
            return Err(bad(format!(
                "{file}:1:{}: the column '{name}' is named twice (also at column {}): which of the two to read is not said",
                column_at(header, k),
                column_at(header, first)
            )));
        }
        index[c] = Some(k);
    }
    if let Some(c) = (0..3).find(|&c| index[c].is_none()) {
        return Err(bad(format!("{file}:1:1: no column '{}' in the header '{header}'", DATA_COLUMNS[c])));
    }
    let mut rows = Vec::new();
    for (n, line) in lines {
        if rows.len() == MAX_DATA_ROWS {
            return Err(bad(format!("{file}:{}:1: {}", n + 1, too_many_rows())));
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            let what = format!("{} cells where the header has {}", cells.len(), names.len());
            return Err(bad(format!("{file}:{}:1: {what}", n + 1)));
        }
        let at = |c: usize| {
            (
                cells[index[c].expect("checked")],
                format!("{file}:{}:{}", n + 1, column_at(line, index[c].expect("checked"))),
            )
        };
        let number = |c: usize| -> Result<f64, FitError> {
            let (cell, at) = at(c);
            cell.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(format!("{at}: {} '{cell}' is not a finite number", DATA_COLUMNS[c])))
        };
        let (point_cell, point_at) = at(0);
        let point = point_cell
            .parse::<usize>()
            .map_err(|_| bad(format!("{point_at}: point '{point_cell}' is not a point number (from 0)")))?;
        let sigma = match index[3] {
            Some(k) if !cells[k].is_empty() => Some(number(3)?),
            _ => None,
        };
        let time_s = match index[4] {
            Some(k) if !cells[k].is_empty() => Some(number(4)?),
            _ => None,
        };
        let output = at(1).0.to_string();
        let at = format!("{file}:{}", n + 1);
        rows.push(Measurement { at, point, output, value: number(2)?, sigma, time_s });
    }
    Ok(rows)
}

/// The column (from 1) where cell `k` of a comma-separated `line` starts.
fn column_at(line: &str, k: usize) -> usize {
    line.match_indices(',').nth(k.wrapping_sub(1)).map_or(1, |(i, _)| i + 2)
}

/// The names of `known` within [`CLOSE_EDITS`] edits of `name` (or sharing its part before
/// the dot), as ", close names: a, b", or "".
pub(crate) fn close_names<'a>(name: &str, known: impl Iterator<Item = &'a str>) -> String {
    let stem = name.split('.').next().unwrap_or(name);
    let close: Vec<&str> = known
        .filter(|k| edits(name, k) <= CLOSE_EDITS || (name.contains('.') && k.split('.').next() == Some(stem)))
        .take(CLOSE_LISTED)
        .collect();
    if close.is_empty() {
        String::new()
    } else {
        format!(", close names: {}", close.join(", "))
    }
}

/// Names this many edits apart are close.
const CLOSE_EDITS: usize = 2;
/// Close names listed at most.
const CLOSE_LISTED: usize = 8;

/// The Levenshtein distance of `a` and `b` (characters inserted, removed or replaced).
fn edits(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (row[j + 1] + 1).min(row[j] + 1).min(diagonal + usize::from(ca != cb));
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}
