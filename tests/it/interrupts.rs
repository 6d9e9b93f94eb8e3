//! Interrupted runs and panics: a run killed with SIGINT or SIGTERM stops at the next tick,
//! writes its report (atomically, never truncating the previous file) and exits non-zero; a
//! panic in one scenario of a batch fails that scenario and the batch goes on.

use super::common::{runs_its_command, send_signal, wait_for, HANG_GUARD_S};
use std::io::BufRead;
use std::process::{Command, Stdio};
use std::time::Duration;

fn out_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("tensegrity-int-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn interrupt_with(signal: &str) {
    let dir = out_dir(signal);
    let json = dir.join("report.json");
    std::fs::write(&json, "previous report").unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["run", "scenarios/mohr2011/workspace_sweep.toml", "scenarios/ji2014/quick.toml", "--json"])
        .arg(&json)
        .arg("--table")
        .arg(dir.join("table.csv"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    let _reap = KillIfFailing(child.id());
    // The event: the first scenario's table (written as it ticks) has rows on disk.
    wait_for("table rows of the first scenario", || bytes_of(&dir, "table") > 0);
    send_signal(signal, child.id());
    let out = wait_guarded(child);
    assert_eq!(out.status.code(), Some(1), "{signal}: non-zero exit");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("interrupted: 1 scenario(s) not run"), "{err}");
    let text = std::fs::read_to_string(&json).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).expect("a complete JSON report replaced the old file");
    let scenarios = v["scenarios"].as_array().unwrap();
    assert_eq!(scenarios.len(), 1, "the batch stopped after the interrupted scenario");
    let err = scenarios[0]["error"].as_str().unwrap();
    assert!(err.contains("interrupted at tick"), "{err}");
    assert_eq!(scenarios[0]["passed"], false);
    // Stopped early: fewer settled points than the grid's (WORKSPACE_POINTS).
    let settled = scenarios[0]["points"].as_array().map_or(0, |p| p.len());
    assert!(settled < WORKSPACE_POINTS, "{settled} of {WORKSPACE_POINTS} points settled");
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Kills process `.0` when the test fails before it is reaped (a failed wait for its event).
struct KillIfFailing(u32);

impl Drop for KillIfFailing {
    fn drop(&mut self) {
        if std::thread::panicking() {
            let _ = Command::new("kill").args(["-KILL", &self.0.to_string()]).status();
        }
    }
}

/// The points of scenarios/mohr2011/workspace_sweep.toml's grid.
const WORKSPACE_POINTS: usize = 474;

/// The bytes of the files in `dir` whose names contain `stem` (their partial files too).
fn bytes_of(dir: &std::path::Path, stem: &str) -> u64 {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(stem))
        .filter_map(|e| e.metadata().ok())
        .map(|m| m.len())
        .sum()
}

/// The child's output once it ends; fails the test (killing it) after the hang guard.
fn wait_guarded(child: std::process::Child) -> std::process::Output {
    let pid = child.id();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(child.wait_with_output()));
    let Ok(out) = rx.recv_timeout(Duration::from_secs(HANG_GUARD_S)) else {
        send_signal("KILL", pid);
        panic!("process {pid} did not stop within the {HANG_GUARD_S} s hang guard");
    };
    out.expect("the child's output")
}

#[test]
fn sigint_stops_the_run_writes_the_report_and_exits_1() {
    interrupt_with("INT");
}

#[test]
fn sigterm_stops_the_run_writes_the_report_and_exits_1() {
    interrupt_with("TERM");
}

#[test]
fn a_panic_fails_its_scenario_and_the_batch_goes_on() {
    let dir = out_dir("panic");
    let json = dir.join("report.json");
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["run", "scenarios/ji2014/quick.toml", "scenarios/mohr2011/quick.toml", "--json"])
        .arg(&json)
        .env(tensegrity_testbed::run::INJECT_PANIC_VAR, "ji2014-quick")
        .output()
        .expect("binary runs");
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let s = v["scenarios"].as_array().unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(s[0]["passed"], false);
    assert!(s[0]["error"].as_str().unwrap().starts_with("panicked: injected"), "{}", s[0]["error"]);
    assert_eq!(s[1]["passed"], true, "the batch went on");
}

/// A sweep stopped by SIGINT or SIGTERM writes the rows it has beside `--out`, to
/// `NAME.partial.csv` (a complete CSV, never a truncated one), leaves the earlier `--out` as it
/// was, says where, and exits 1 (issue 30's signals class too).
#[test]
fn an_interrupted_sweep_writes_the_rows_it_has() {
    for signal in ["-INT", "-TERM"] {
        interrupted_sweep(signal);
    }
}

fn interrupted_sweep(signal: &str) {
    let dir = out_dir(&format!("sweep{signal}"));
    let csv = dir.join("sweep.csv");
    std::fs::write(&csv, "previous").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["sweep", "scenarios/mohr2011/workspace_sweep.toml", "--jobs", "2", "--out"])
        .arg(&csv)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    let _reap = KillIfFailing(child.id());
    // The event: the sweep's first progress line ("N/474 points"), said when a block is done.
    let lines = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut said = Vec::new();
        for line in lines.map_while(Result::ok) {
            if line.ends_with(" points") && said.iter().all(|l: &String| !l.ends_with(" points")) {
                let _ = tx.send(());
            }
            said.push(line);
        }
        said
    });
    let first = rx.recv_timeout(Duration::from_secs(HANG_GUARD_S));
    assert!(first.is_ok(), "no progress line within the {HANG_GUARD_S} s hang guard");
    send_signal(signal.trim_start_matches('-'), child.id());
    let out = wait_guarded(child);
    let err = reader.join().unwrap().join("\n");
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), "previous", "the earlier CSV stays");
    let partial = dir.join("sweep.partial.csv");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains(&format!("are in {} (merge --partial reads it)", partial.display())), "{said}");
    let text = std::fs::read_to_string(&partial).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("index,"), "a sweep CSV");
    let rows: Vec<&str> = lines.collect();
    // At least the block the progress line counted, fewer than the whole sweep's.
    assert!(!rows.is_empty() && rows.len() < WORKSPACE_POINTS, "{} rows", rows.len());
    assert!(said.contains(&format!("the {} point(s) that ran", rows.len())), "{said}");
    assert!(rows.iter().all(|r| r.split(',').count() > 10), "no truncated row");
}

/// Sends `signal` to a command as soon as it runs its command (its handlers installed, its
/// command's thread started: `common::runs_its_command`); returns its exit code, stdout and
/// stderr.
fn signal_once_running(args: &[&str], signal: &str) -> (Option<i32>, String, String) {
    let child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    let pid = child.id();
    let _reap = KillIfFailing(pid);
    wait_for("command's thread", || runs_its_command(pid));
    send_signal(signal, pid);
    let out = wait_guarded(child);
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code(), text(&out.stdout), text(&out.stderr))
}

/// Parsing and validating (`check` of a million-point grid, about a second) stops on SIGTERM,
/// exit 1, "interrupted", before it says the file is ok.
#[test]
fn sigterm_stops_check_while_it_validates() {
    let dir = out_dir("check");
    let text = std::fs::read_to_string("scenarios/ji2014/grid.toml").unwrap();
    let big = dir.join("big.toml");
    let grid =
        "grid = { L3 = { from = 0.2, to = 2.0, count = 1000 }, theta1 = { from = 0.0, to = 3.14159, count = 1000 } }";
    let line = text.lines().find(|l| l.starts_with("grid =")).expect("a grid line");
    std::fs::write(&big, text.replace(line, grid)).unwrap();
    let (code, out, err) = signal_once_running(&["check", big.to_str().unwrap()], "TERM");
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(!out.contains(": ok ("), "stopped before the end of the validation: {out}");
}

/// Drawing a figure (manriquez2019 Fig. 6-7, about 2 s of dynamics) stops on SIGINT, exit 1,
/// "interrupted", and leaves neither a figure nor a temporary file.
#[test]
fn sigint_stops_a_figure_and_leaves_no_file() {
    let dir = out_dir("figure");
    let (code, out, err) =
        signal_once_running(&["figure", "manriquez2019-fig6", "--out", dir.to_str().unwrap()], "INT");
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("interrupted") && !out.contains("wrote"), "{out}{err}");
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()).map(|e| e.file_name()).collect();
    assert!(left.is_empty(), "{left:?}");
}

/// A run interrupted while it checks the paper's equations (before its first tick) stops at once
/// too: the report says where it stopped.
#[test]
fn an_interrupted_findings_phase_is_reported() {
    let flag = std::sync::atomic::AtomicBool::new(true);
    let sc = tensegrity_testbed::scenario::load(std::path::Path::new("scenarios/mohr2011/quick.toml")).unwrap();
    let r = tensegrity_testbed::run::run(
        &sc,
        &tensegrity_testbed::run::RunOptions { cancel: Some(&flag), ..Default::default() },
    );
    let err = r.error.as_ref().map(|e| e.to_string()).unwrap_or_default();
    assert!(err.contains("interrupted while checking the paper's equations"), "{err}");
    assert!(!r.passed);
}

/// Attribution (mohr2011's levels with elastic cables, about 11 s) stops on SIGINT within the
/// hang guard, exit 1, "interrupted", and writes neither its CSV nor a temporary file.
#[test]
fn sigint_stops_an_attribution_and_leaves_no_file() {
    let dir = out_dir("attribute");
    let csv = dir.join("shares.csv");
    let args = ["attribute", "scenarios/mohr2011/cable_attribution.toml", "--csv", csv.to_str().unwrap()];
    let (code, out, err) = signal_once_running(&args, "INT");
    assert_eq!(code, Some(1), "{out}{err}");
    assert!(err.contains("interrupted") || err.contains("stopped by a signal"), "{err}");
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()).map(|e| e.file_name()).collect();
    assert!(left.is_empty(), "{left:?}");
}
