//! The `tensegrity` command line, a thin shell over the library (after ripgrep's `flags`):
//! `args.rs` the grammar, one file per command, `signals.rs` the signals and the command's
//! thread, and here the one place that prints errors and maps outcomes to exit codes.
//!
//! Adding a subcommand: a variant in `args.rs`, its file here (a function returning
//! `Result<Outcome, CliError>`), and one line in `dispatch`.

mod args;
mod attribute;
mod bench;
mod certify;
mod check;
mod equilibrium;
mod export;
mod figure;
mod findings;
mod fit;
mod import;
mod list;
mod merge;
mod modes;
mod run;
mod sensitivity;
mod signals;
mod solve;
mod sweep;

use crate::report::{EXIT_BAD_INPUT, EXIT_FAIL, EXIT_PASS};
use crate::scenario::{self, Override, Scenario};
use args::{Cli, Command};
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Exit code of a command that panicked (Rust's own for a panic in main).
const EXIT_INTERNAL_ERROR: u8 = 101;

/// How a command ended when it ran to its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Every check passed (exit 0).
    Pass,
    /// A check failed, a settle timed out, a run diverged or was interrupted (exit 1).
    Fail,
}

impl Outcome {
    /// Pass when `passed`, else Fail.
    pub fn from_passed(passed: bool) -> Outcome {
        if passed {
            Outcome::Pass
        } else {
            Outcome::Fail
        }
    }
}

/// The error of one of the library's seams (a scenario, an output, a run, an import, ...),
/// kept as its own kind until `exit_code` prints it.
pub type Cause = Box<dyn std::error::Error + Send + Sync>;

/// Why a command stopped before its end.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad input: a malformed scenario or flag, an unknown name, an output that would destroy
    /// an input (exit 2). One error per problem found.
    #[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\nerror: "))]
    BadInput(Vec<Cause>),
    /// The work failed: an output could not be written (exit 1).
    #[error("{0}")]
    Failed(Cause),
}

/// Bad input with one error (a message is an error too).
pub fn bad_input(error: impl Into<Cause>) -> CliError {
    CliError::BadInput(vec![error.into()])
}

/// A failure with one error (a message is an error too).
pub fn failed(error: impl Into<Cause>) -> CliError {
    CliError::Failed(error.into())
}

/// The binary's `main`: parse the arguments, run the command on its own thread, print its
/// error (the only place that does) and exit with its code.
pub fn main() -> ExitCode {
    signals::install_handlers();
    let cli = Cli::parse();
    ExitCode::from(signals::run_stoppable(move || exit_code(dispatch(cli))))
}

/// The exit code of a command's result, printing its error.
fn exit_code(result: Result<Outcome, CliError>) -> u8 {
    let code = match result {
        Ok(Outcome::Pass) => EXIT_PASS,
        Ok(Outcome::Fail) => EXIT_FAIL,
        Err(e) => {
            eprintln!("error: {e}");
            match e {
                CliError::BadInput(_) => EXIT_BAD_INPUT,
                CliError::Failed(_) => EXIT_FAIL,
            }
        }
    };
    code as u8
}

/// Runs the command.
fn dispatch(cli: Cli) -> Result<Outcome, CliError> {
    match cli.command {
        Command::Run { scenarios, json, record, connect, record_every, table, set, fail_on_declared, certify } => {
            let outputs = run::Outputs { json, record, connect, record_every, table, certify };
            run::run(&scenarios, &overrides(&set)?, &outputs, fail_on_declared)
        }
        Command::Check { scenarios, set } => check::check(&scenarios, &overrides(&set)?),
        Command::List { scenario, set } => list::list(scenario.as_deref(), &overrides(&set)?),
        Command::Sweep { scenario, out, json, jobs, shard, figure, x, certify, set } => {
            let outputs = sweep::Outputs { csv: out, json, figure, x, certify };
            sweep::sweep(&scenario, &overrides(&set)?, &outputs, jobs, shard.as_deref())
        }
        Command::Merge { csvs, out, partial } => merge::merge(&csvs, &out, partial),
        Command::Figure { name, out, list } => figure::figure(name.as_deref(), &out, list),
        Command::Solve { mechanism, query, set, json } => solve::solve(&mechanism, &query, &set, json),
        Command::Findings { mechanism, set, json } => findings::findings(&mechanism, &set, json),
        Command::Import { format } => import::import(format),
        Command::Export { format } => export::export(format),
        Command::Equilibrium { scenario, json, set } => {
            equilibrium::equilibrium(&scenario, &overrides(&set)?, json.as_deref())
        }
        Command::Modes { scenario, json, record, count, set } => {
            modes::modes(&scenario, &overrides(&set)?, json.as_deref(), record.as_deref(), count)
        }
        Command::Sensitivity { scenario, json, csv, point, check, params, set } => {
            let outputs = (json.as_deref(), csv.as_deref());
            sensitivity::sensitivity(&scenario, &overrides(&set)?, outputs, (point, &params), check)
        }
        Command::Certify { scenario, json, point, set } => {
            certify::certify(&scenario, &overrides(&set)?, json.as_deref(), point)
        }
        Command::Attribute { scenario, json, csv, figure, set } => {
            attribute::attribute(&scenario, &overrides(&set)?, json.as_deref(), csv.as_deref(), figure.as_deref())
        }
        Command::Fit { scenario, data, params, json, set } => {
            fit::fit(&scenario, &overrides(&set)?, &data, &params, json.as_deref())
        }
        bench @ Command::Bench { .. } => bench::bench(bench),
    }
}

/// The `--set NAME=VALUE` flags of a scenario command.
fn overrides(flags: &args::SetArgs) -> Result<Vec<Override>, CliError> {
    let list: Vec<Override> =
        flags.set.iter().map(|f| Override::parse(f).map_err(bad_input)).collect::<Result<_, _>>()?;
    for (k, o) in list.iter().enumerate() {
        if let Some(twice) = list[k + 1..].iter().find(|t| t.name == o.name) {
            return Err(bad_input(format!(
                "--set {}={} and --set {}={}: '{}' is set twice (give each name once)",
                o.name, o.value, twice.name, twice.value, o.name
            )));
        }
    }
    Ok(list)
}

/// A recording's file must end in `.rrd` (rerun's format).
fn check_recording_path(record: Option<&Path>) -> Result<(), CliError> {
    match record.filter(|r| r.extension().and_then(|e| e.to_str()) != Some("rrd")) {
        Some(r) => Err(bad_input(format!("--record {} must end in .rrd", r.display()))),
        None => Ok(()),
    }
}

/// Loads and validates every scenario (`-`: standard input, once) with the overrides: all of
/// them, or every error found.
fn load_all(paths: &[PathBuf], overrides: &[Override]) -> Result<Vec<Scenario>, CliError> {
    if paths.iter().filter(|p| is_stdio(p)).count() > 1 {
        return Err(bad_input("standard input (-) can be read once: name it as one scenario"));
    }
    let (mut list, mut errors) = (Vec::new(), Vec::new());
    for p in paths {
        match scenario::load_with(p, overrides) {
            Ok(s) => list.push(s),
            Err(e) => errors.push(e.into()),
        }
    }
    if errors.is_empty() {
        Ok(list)
    } else {
        Err(CliError::BadInput(errors))
    }
}

/// Loads and validates one scenario (`-`: standard input) with the overrides.
fn load_one(path: &Path, overrides: &[Override]) -> Result<Scenario, CliError> {
    scenario::load_with(path, overrides).map_err(bad_input)
}

/// Whether a path is `-`: standard input as a scenario, standard output as an output.
fn is_stdio(path: &Path) -> bool {
    path == Path::new(scenario::STDIN)
}

/// Refuses outputs that would destroy data (`output::check_outputs`), before anything runs;
/// standard input and output destroy nothing.
fn check_outputs(inputs: &[PathBuf], outputs: &[(String, PathBuf)]) -> Result<(), CliError> {
    let inputs: Vec<PathBuf> = inputs.iter().filter(|p| !is_stdio(p)).cloned().collect();
    let outputs: Vec<(String, PathBuf)> = outputs.iter().filter(|(_, p)| !is_stdio(p)).cloned().collect();
    crate::output::check_outputs(&inputs, &outputs).map_err(bad_input)
}

/// Writes `text` to `path` through a unique temporary file and a rename (`output`), or to
/// standard output for `-`.
fn write_atomic(path: &Path, text: &str) -> Result<(), CliError> {
    if is_stdio(path) {
        return print_out(text);
    }
    crate::output::write_atomic(path, text.as_bytes()).map_err(failed)
}

/// Writes `text` to `out` (never over an input), or to stdout without `out`.
fn write_output(out: Option<&Path>, inputs: &[PathBuf], text: &str) -> Result<Outcome, CliError> {
    let Some(o) = out.filter(|o| !is_stdio(o)) else {
        print_out(text)?;
        return Ok(Outcome::Pass);
    };
    check_outputs(inputs, &[("--out".into(), o.to_path_buf())])?;
    write_atomic(o, text)?;
    Ok(Outcome::Pass)
}

/// Writes `text` to standard output, all of it: a closed or full standard output fails the
/// command (exit 1) with its message, never a panic and never a silent exit 0. (A pipe closed
/// by its reader ends the process as it ends any Unix filter: `signals::install_handlers`.)
/// A report's table and, with `--json FILE`, the report itself: the table on standard output,
/// or on standard error where `table_to_stderr` (a `-` output holds standard output).
pub fn print_report(
    table: &str,
    table_to_stderr: bool,
    json: Option<&Path>,
    report: &impl serde::Serialize,
) -> Result<(), CliError> {
    if table_to_stderr {
        eprint!("{table}");
    } else {
        print_out(table)?;
    }
    if let Some(j) = json {
        write_atomic(j, &serde_json::to_string_pretty(report).expect("report serialises"))?;
    }
    Ok(())
}

pub fn print_out(text: &str) -> Result<(), CliError> {
    use std::io::Write;
    if stdout_closed() {
        return Err(failed("standard output is closed: nothing written"));
    }
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| failed(format!("writing to standard output: {e}")))
}

/// Whether the process started with its standard output closed (`>&-`), as
/// [`record_stdout_at_start`] saw it before Rust's runtime put /dev/null in its place: writes
/// would then vanish. A /dev/null the caller opened (`> /dev/null`, Python's
/// `subprocess.DEVNULL`, read-write like the runtime's) is a place the caller chose.
fn stdout_closed() -> bool {
    STDOUT_CLOSED_AT_START.load(std::sync::atomic::Ordering::Relaxed)
}

static STDOUT_CLOSED_AT_START: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Runs before `main` (an ELF constructor, before Rust's runtime opens /dev/null on a closed
/// standard descriptor): records whether standard output is closed.
#[cfg_attr(not(target_os = "linux"), allow(dead_code))]
extern "C" fn record_stdout_at_start() {
    // SAFETY: fcntl reads the descriptor's flags, changing nothing.
    let closed = unsafe { libc::fcntl(libc::STDOUT_FILENO, libc::F_GETFD) } < 0;
    STDOUT_CLOSED_AT_START.store(closed, std::sync::atomic::Ordering::Relaxed);
}

/// (ELF only: elsewhere standard output is never taken for closed.)
#[cfg(target_os = "linux")]
#[used]
#[link_section = ".init_array"]
static RECORD_STDOUT_AT_START: extern "C" fn() = record_stdout_at_start;
