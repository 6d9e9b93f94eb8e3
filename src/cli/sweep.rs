//! `tensegrity sweep`: every grid point settled in parallel, its CSV, summary and figure.

use super::{check_outputs, load_one, signals, write_atomic, CliError, Outcome};
use crate::scenario::Override;
use crate::study::sweep::SweepSummary;
use std::path::{Path, PathBuf};

/// What a sweep writes: its CSV, its JSON summary, its figure (against axis `x`).
pub struct Outputs {
    pub csv: Option<PathBuf>,
    pub json: Option<PathBuf>,
    pub figure: Option<PathBuf>,
    pub x: Option<String>,
    /// `--certify`: a proof of the equilibrium at each point.
    pub certify: bool,
}

/// The scenario, every point certified with `--certify`; refused (exit 2) where its points
/// cannot be (`certify::refuse_uncertifiable`), with the flag or the file's `[certify]`.
fn certified_or_not(
    sc: crate::scenario::Scenario,
    path: &Path,
    flag: bool,
) -> Result<crate::scenario::Scenario, CliError> {
    let sc = if flag { sc.certified() } else { sc };
    if sc.certify {
        super::certify::refuse_uncertifiable(&sc, path)?;
    }
    Ok(sc)
}

/// Refuses outputs that mean nothing or would destroy data, before any work: a figure that is no
/// .png or .svg, an output over the scenario, and the CSV and the JSON both on standard output
/// (mixed, neither could be read).
fn check_sweep_outputs(path: &Path, o: &Outputs) -> Result<(), CliError> {
    if let Some(f) =
        o.figure.as_deref().filter(|f| !matches!(f.extension().and_then(|e| e.to_str()), Some("png" | "svg")))
    {
        return Err(super::bad_input(format!("--figure {}: give a .png or .svg file", f.display())));
    }
    let mut outputs: Vec<(String, PathBuf)> = [("--out", &o.csv), ("--json", &o.json), ("--figure", &o.figure)]
        .into_iter()
        .filter_map(|(what, p)| p.clone().map(|p| (what.to_string(), p)))
        .collect();
    if let Some(csv) = o.csv.as_deref().filter(|p| !super::is_stdio(p)) {
        outputs.push(("the CSV of an interrupted sweep".into(), partial_path(csv)));
    }
    check_outputs(&[path.to_path_buf()], &outputs)?;
    if [&o.csv, &o.json].into_iter().all(|p| p.as_deref().is_some_and(super::is_stdio)) {
        return Err(super::bad_input(
            "--out - and --json - both write to standard output: give one of them a file, so that the other is alone there",
        ));
    }
    Ok(())
}

pub fn sweep(
    path: &Path,
    overrides: &[Override],
    o: &Outputs,
    jobs: usize,
    shard: Option<&str>,
) -> Result<Outcome, CliError> {
    let sc = certified_or_not(load_one(path, overrides)?, path, o.certify)?;
    check_sweep_outputs(path, o)?;
    check_axis(&sc, o.x.as_deref())?;
    let jobs = capped_jobs(jobs);
    // From here on every block stops at its next tick on a signal and the outputs are written.
    signals::stops_itself_from_now();
    let shard = shard.map(crate::study::sweep::parse_shard).transpose().map_err(super::bad_input)?;
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} points, {per_sec}, {eta} left")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    // Off a terminal the bar is hidden: a line on standard error at the first block and at
    // each further tenth of the points instead (a job's log; what an interrupting script waits for).
    let plain = !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let lines_said = std::sync::atomic::AtomicUsize::new(0);
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        let line = done * 10 / total.max(1) + 1;
        if plain && lines_said.fetch_max(line, std::sync::atomic::Ordering::SeqCst) < line {
            eprintln!("{done}/{total} points");
        }
    };
    let result = crate::study::sweep::sweep(&sc, jobs, shard, Some(&signals::CANCEL), &progress);
    bar.finish_and_clear();
    let (rows, summary) = result.map_err(super::bad_input)?;
    // With the CSV or the summary on standard output, the human lines go to standard error.
    let on_stdout = [&o.csv, &o.json].into_iter().flatten().any(|p| super::is_stdio(p));
    let say: Say = if on_stdout { say_on_stderr } else { say_on_stdout };
    print_summary(&summary, say)?;
    let is_angle = |q: &str| sc.is_angle(q);
    let csv_text = || crate::study::sweep::to_csv(&rows, &is_angle, &crate::study::sweep::fingerprint(&sc));
    if signals::cancelled() {
        return interrupted(o.csv.as_deref(), rows.len(), &csv_text(), say);
    }
    if let Some(csv) = &o.csv {
        write_atomic(csv, &csv_text())?;
    }
    if let Some(f) = &o.figure {
        let measured: Vec<String> = sc
            .probe
            .iter()
            .filter(|p| p.tolerance.is_none())
            .filter_map(|p| p.joint.as_ref().map(|j| j.quantity()))
            .collect();
        let titled = (summary.scenario.as_str(), o.x.as_deref());
        if let Some(dir) = f.parent().filter(|d| !d.as_os_str().is_empty()) {
            crate::output::create_dir(dir).map_err(super::failed)?;
        }
        crate::figures::sweep::draw(&rows, titled, &measured, &is_angle, f).map_err(super::failed)?;
    }
    if let Some(j) = &o.json {
        write_atomic(j, &serde_json::to_string_pretty(&summary).unwrap_or_default())?;
    }
    if let Some(min) = summary.min_agreement_percent {
        say(&format!("required agreement {min:.2} %"))?;
    }
    if !summary.disagreements.is_empty() {
        say(&format!(
            "{} point(s) did not settle, are out of tolerance or lost their prestress",
            summary.disagreements.len()
        ))?;
    }
    let passed = summary.passed && !signals::cancelled();
    say(if passed { "PASS" } else { "FAIL" })?;
    Ok(Outcome::from_passed(passed))
}

/// An interrupted sweep: the rows that ran go beside `--out`, to a file named as partial (for
/// `merge --partial` or a later run), never over an earlier complete CSV; the summary and the
/// figure are not written. Exit 1.
fn interrupted(csv: Option<&Path>, rows: usize, text: &str, say: Say) -> Result<Outcome, CliError> {
    match csv.filter(|p| !super::is_stdio(p)) {
        Some(p) => {
            let partial = partial_path(p);
            write_atomic(&partial, text)?;
            say(&format!(
                "interrupted: the {rows} point(s) that ran are in {} (merge --partial reads it); {} was not written",
                partial.display(),
                p.display()
            ))?;
        }
        None => say("interrupted: no CSV written")?,
    }
    Ok(Outcome::from_passed(false))
}

/// `out/s.csv` -> `out/s.partial.csv`.
pub fn partial_path(p: &Path) -> PathBuf {
    let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = p.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    p.with_file_name(format!("{stem}.partial{ext}"))
}

/// The summary's lines: points, settled, within tolerance, wall time; agreement; stops.
fn print_summary(summary: &SweepSummary, say: Say) -> Result<(), CliError> {
    say(&format!(
        "{}: {} point(s), {} settled, {} within tolerance, {:.2} s wall on {} job(s){}",
        summary.scenario,
        summary.points,
        summary.settled,
        summary.within_tolerance,
        summary.wall_s,
        summary.jobs,
        summary.shard.as_ref().map(|s| format!(", shard {s}")).unwrap_or_default()
    ))?;
    if let Some(w) = &summary.workspace {
        say(&format!("workspace agreement {:.2} % ({} of {} points)", w.agreement_percent, w.agree, w.points))?;
    }
    for e in &summary.errors {
        say(&format!("stopped: {e}"))?;
    }
    Ok(())
}

/// Where the sweep's human lines go: standard output, or standard error when a CSV or the
/// summary is there.
type Say = fn(&str) -> Result<(), CliError>;

fn say_on_stderr(line: &str) -> Result<(), CliError> {
    eprintln!("{line}");
    Ok(())
}

fn say_on_stdout(line: &str) -> Result<(), CliError> {
    super::print_out(&format!("{line}\n"))
}

/// `--x`, before any point is settled: an input or a swept parameter of the scenario's points.
fn check_axis(sc: &crate::scenario::Scenario, x: Option<&str>) -> Result<(), CliError> {
    let Some(x) = x else { return Ok(()) };
    let axes: Vec<&String> = sc.actuation.first_inputs().keys().collect();
    if axes.iter().any(|a| *a == x) {
        return Ok(());
    }
    let axes = axes.iter().map(|a| a.as_str()).collect::<Vec<_>>().join(", ");
    Err(super::bad_input(format!("--x {x}: not an axis of this sweep (its inputs and swept parameters: {axes})")))
}

/// `--jobs`, at least 1 and at most the machine's threads (lowered with a note on stderr).
fn capped_jobs(jobs: usize) -> usize {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    if jobs > threads {
        eprintln!("note: --jobs {jobs} lowered to {threads}, the threads of this machine");
    }
    jobs.clamp(1, threads)
}
