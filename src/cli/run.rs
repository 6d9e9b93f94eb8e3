//! `tensegrity run`: scenario files headless, with their report, recordings and tables.

use super::{check_outputs, load_all, signals, write_atomic, CliError, Outcome};
use crate::report::Report;
use crate::run::{run as run_scenario, RunOptions};
use crate::scenario::{Override, Scenario};
use std::path::{Path, PathBuf};

/// What a run writes besides its table on stdout.
pub struct Outputs {
    pub json: Option<PathBuf>,
    pub record: Option<PathBuf>,
    pub connect: Option<String>,
    pub record_every: u64,
    pub table: Option<PathBuf>,
    /// `--certify`: a proof of the equilibrium at each settle point.
    pub certify: bool,
}

/// The file of one scenario's output: `base` itself, or with several scenarios
/// `STEM-<scenario>.EXT` (the scenario's name with every character but `[A-Za-z0-9_-]` as `_`;
/// EXT `base`'s own, which says the table's format, or `extension` where it has none).
fn per_scenario(base: &Path, name: &str, several: bool, extension: &str) -> PathBuf {
    if !several {
        return base.to_path_buf();
    }
    let stem = base.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "run".into());
    let safe: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect();
    let extension = base.extension().map_or(extension.to_string(), |e| e.to_string_lossy().to_string());
    base.with_file_name(format!("{stem}-{safe}.{extension}"))
}

impl Outputs {
    fn record_path(&self, sc: &Scenario, several: bool) -> Option<PathBuf> {
        self.record.as_deref().map(|r| per_scenario(r, &sc.name, several, "rrd"))
    }

    fn table_path(&self, sc: &Scenario, several: bool) -> Option<PathBuf> {
        self.table.as_deref().map(|t| per_scenario(t, &sc.name, several, "csv"))
    }

    /// Every file the run will write, named for the error that refuses it.
    fn files(&self, scenarios: &[Scenario]) -> Vec<(String, PathBuf)> {
        let several = scenarios.len() > 1;
        let mut out: Vec<(String, PathBuf)> = self.json.iter().map(|j| ("--json".to_string(), j.clone())).collect();
        if self.connect.is_none() {
            for sc in scenarios {
                if let Some(r) = self.record_path(sc, several).or_else(|| sc.record.clone()) {
                    out.push((format!("the recording of scenario '{}' ({})", sc.name, sc.file.display()), r));
                }
            }
        }
        for sc in scenarios {
            if let Some(t) = self.table_path(sc, several) {
                out.push((format!("the table of scenario '{}' ({})", sc.name, sc.file.display()), t));
            }
        }
        out
    }
}

/// Runs the scenarios. The exit code says whether every scenario ended as it declares (a
/// declared failure that happened passes), or with `fail_on_declared` whether every check
/// passed.
pub fn run(
    paths: &[PathBuf],
    overrides: &[Override],
    o: &Outputs,
    fail_on_declared: bool,
) -> Result<Outcome, CliError> {
    let scenarios = load_all(paths, overrides)?;
    super::check_recording_path(o.record.as_deref())?;
    if let Some(t) = o.table.as_deref().filter(|t| !crate::observers::table::is_table_file(t)) {
        return Err(super::bad_input(format!(
            "--table {}: give a file ending in .csv, or .arrow, .feather or .ipc for Arrow IPC",
            t.display()
        )));
    }
    check_outputs(paths, &o.files(&scenarios))?;
    for (sc, path) in scenarios.iter().zip(paths).filter(|(sc, _)| o.certify || sc.certify) {
        super::certify::refuse_uncertifiable(sc, path)?;
    }
    // From here on each run stops at its next tick on a signal and the reports are written.
    signals::stops_itself_from_now();
    let several = scenarios.len() > 1;
    let mut report = Report { scenarios: vec![] };
    for sc in &scenarios {
        if signals::cancelled() {
            eprintln!("interrupted: {} scenario(s) not run", scenarios.len() - report.scenarios.len());
            break;
        }
        let opts = RunOptions {
            record: o.record_path(sc, several),
            cancel: Some(&signals::CANCEL),
            connect: o.connect.clone(),
            record_every: o.record_every,
            skip_findings: false,
            table: o.table_path(sc, several).map(Into::into),
            external: None,
            bare: false,
            certify: o.certify,
        };
        // A panic inside one scenario fails that scenario, with its message; the batch goes on.
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_scenario(sc, &opts)))
            .unwrap_or_else(|payload| crate::run::panicked(sc, payload.as_ref()));
        for w in &r.warnings {
            eprintln!("note: {w}");
        }
        report.scenarios.push(r);
    }
    // With the JSON report on standard output the table goes to standard error.
    match o.json.as_deref().filter(|j| super::is_stdio(j)) {
        Some(_) => eprint!("{}", report.to_table()),
        None => super::print_out(&report.to_table())?,
    }
    if let Some(j) = &o.json {
        write_atomic(j, &report.to_json()).map_err(|e| super::failed(format!("the JSON report: {e}")))?;
    }
    let ended_well = if fail_on_declared { report.passed() } else { report.as_declared() };
    Ok(Outcome::from_passed(ended_well && !signals::cancelled()))
}
