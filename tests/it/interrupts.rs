//! Interrupted runs and panics: a run killed with SIGINT or SIGTERM stops at the next tick,
//! writes its report (atomically, never truncating the previous file) and exits non-zero; a
//! panic in one scenario of a batch fails that scenario and the batch goes on.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn out_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("tensegrity-int-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn interrupt_with(signal: &str) {
    let dir = out_dir(signal);
    let json = dir.join("report.json");
    std::fs::write(&json, "previous report").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["run", "scenarios/mohr2011/workspace_sweep.toml", "scenarios/ji2014/quick.toml", "--json"])
        .arg(&json)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    std::thread::sleep(Duration::from_millis(1500));
    let killed = Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let start = Instant::now();
    let status = child.wait().expect("exits");
    // It stops at the next tick: well within a second of the signal.
    assert!(start.elapsed() < Duration::from_secs(5), "took {:?} to stop", start.elapsed());
    assert_eq!(status.code(), Some(1), "{signal}: non-zero exit");
    let text = std::fs::read_to_string(&json).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).expect("a complete JSON report replaced the old file");
    let scenarios = v["scenarios"].as_array().unwrap();
    assert_eq!(scenarios.len(), 1, "the batch stopped after the interrupted scenario");
    let err = scenarios[0]["error"].as_str().unwrap();
    assert!(err.contains("interrupted at tick"), "{err}");
    assert_eq!(scenarios[0]["passed"], false);
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
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
    let child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["sweep", "scenarios/mohr2011/workspace_sweep.toml", "--jobs", "2", "--out"])
        .arg(&csv)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    std::thread::sleep(Duration::from_millis(2500));
    assert!(Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap().success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), "previous", "the earlier CSV stays");
    let partial = dir.join("sweep.partial.csv");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains(&format!("are in {} (merge --partial reads it)", partial.display())), "{said}");
    let text = std::fs::read_to_string(&partial).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("index,"), "a sweep CSV");
    let rows: Vec<&str> = lines.collect();
    assert!(!rows.is_empty() && rows.len() < 474, "{} rows", rows.len());
    assert!(rows.iter().all(|r| r.split(',').count() > 10), "no truncated row");
}

/// Sends `signal` to a command `after` its start; returns its exit code, stderr and how long it
/// took to stop after the signal.
fn signal_after(args: &[&str], signal: &str, after: Duration) -> (Option<i32>, String, Duration) {
    let child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    std::thread::sleep(after);
    let killed = Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let start = Instant::now();
    let out = child.wait_with_output().expect("exits");
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned(), start.elapsed())
}

/// Parsing and validating (`check` of a million-point grid, about a second) stops on SIGTERM
/// within half a second, exit 1.
#[test]
fn sigterm_stops_check_while_it_validates() {
    let dir = out_dir("check");
    let text = std::fs::read_to_string("scenarios/ji2014/grid.toml").unwrap();
    let big = dir.join("big.toml");
    let grid =
        "grid = { L3 = { from = 0.2, to = 2.0, count = 1000 }, theta1 = { from = 0.0, to = 3.14159, count = 1000 } }";
    let line = text.lines().find(|l| l.starts_with("grid =")).expect("a grid line");
    std::fs::write(&big, text.replace(line, grid)).unwrap();
    let (code, err, took) = signal_after(&["check", big.to_str().unwrap()], "TERM", Duration::from_millis(300));
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(took < Duration::from_millis(500), "took {took:?}");
}

/// Drawing a figure (manriquez2019 Fig. 6-7, about 2 s of dynamics) stops on SIGINT within half
/// a second, exit 1, and leaves neither a figure nor a temporary file.
#[test]
fn sigint_stops_a_figure_and_leaves_no_file() {
    let dir = out_dir("figure");
    let (code, err, took) = signal_after(
        &["figure", "manriquez2019-fig6", "--out", dir.to_str().unwrap()],
        "INT",
        Duration::from_millis(500),
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(took < Duration::from_millis(500), "took {took:?}");
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
