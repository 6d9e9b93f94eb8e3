//! The command line for scripts: `--set NAME=VALUE`, `-` as the scenario and as an output,
//! and exit codes that say whether every scenario ended as it declares.

use crate::common::tensegrity;
use std::io::Write;
use std::process::{Command, Stdio};

/// The shipped pinned bar swept over k1 (a file's own structure and model).
const PINNED_SWEEP: &str = "scenarios/custom/pinned_bar_sweep.toml";

/// Runs the binary with `stdin` as its standard input: (exit code, stdout, stderr).
fn tensegrity_with_stdin(args: &[&str], stdin: &str) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    child.stdin.take().unwrap().write_all(stdin.as_bytes()).unwrap();
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The JSON report of one run written to standard output.
fn report_on_stdout(args: &[&str]) -> (i32, serde_json::Value, String) {
    let (code, out, err) = tensegrity(args);
    let v = serde_json::from_str(&out).unwrap_or_else(|e| panic!("stdout is not the JSON report ({e}): {out}{err}"));
    (code, v, err)
}

#[test]
fn set_replaces_a_parameter_and_the_report_has_its_value() {
    let (code, v, err) = report_on_stdout(&["run", "scenarios/ji2014/quick.toml", "--set", "K1=150", "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["scenarios"][0]["params"]["K1"].as_f64(), Some(150.0));
    // The table went to standard error, off the report.
    assert!(err.contains("PASS"), "{err}");
}

#[test]
fn set_of_a_parameter_as_an_expression_is_evaluated_with_the_others() {
    let (code, out, err) = tensegrity(&["list", PINNED_SWEEP, "--set", "q0=pi/8"]);
    assert_eq!(code, 0, "{err}");
    // The "parameter values" lines read `q0 = VALUE`.
    let value: f64 = out
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>())
        .find(|w| w.len() == 3 && w[0] == "q0" && w[1] == "=")
        .map(|w| w[2].parse().unwrap())
        .expect("q0's value is listed");
    assert!((value - std::f64::consts::PI / 8.0).abs() <= 1e-15, "q0 = {value}");
    // The file's unit stays with the new value.
    assert!(out.contains("q0           [rad]"), "{out}");
}

#[test]
fn set_of_a_setting_changes_the_run_and_a_bad_value_is_an_error_at_its_flag() {
    let (code, v, err) =
        report_on_stdout(&["run", "scenarios/ji2014/quick.toml", "--set", "sim.dt=0.002", "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    let steps = v["scenarios"][0]["settle"]["steps"].as_f64().unwrap();
    let sim_time = v["scenarios"][0]["settle"]["sim_time_s"].as_f64().unwrap();
    assert!((sim_time - steps * 0.002).abs() <= 1e-9 * sim_time.max(1.0), "{sim_time} s in {steps} steps");
    let (code, _, err) = tensegrity(&["check", "scenarios/ji2014/quick.toml", "--set", "sim.dt=-1"]);
    assert_eq!(code, 2);
    assert!(err.starts_with("error: --set sim.dt=-1:1:"), "{err}");
    assert!(err.contains("must be > 0, got -1"), "{err}");
}

#[test]
fn set_of_a_name_the_scenario_does_not_have_is_an_error_never_ignored() {
    for (file, flag) in [
        (PINNED_SWEEP, "stiffness=3"),
        ("scenarios/ji2014/quick.toml", "K9=3"),
        ("scenarios/ji2014/quick.toml", "sim.step=1"),
        ("scenarios/ji2014/quick.toml", "settle.speed=1"),
        ("scenarios/ji2014/quick.toml", "K1"),
    ] {
        let (code, _, err) = tensegrity(&["check", file, "--set", flag]);
        assert_eq!(code, 2, "--set {flag} on {file}: {err}");
        assert!(err.contains("--set"), "--set {flag}: {err}");
    }
}

#[test]
fn a_scenario_from_standard_input_runs_as_its_file_does() {
    let text = std::fs::read_to_string("scenarios/ji2014/quick.toml").unwrap();
    let (code, out, err) = tensegrity_with_stdin(&["run", "-", "--json", "-"], &text);
    assert_eq!(code, 0, "{err}");
    let from_stdin: serde_json::Value = serde_json::from_str(&out).unwrap();
    let (_, from_file, _) = report_on_stdout(&["run", "scenarios/ji2014/quick.toml", "--json", "-"]);
    let settled = |v: &serde_json::Value| v["scenarios"][0]["points"][0]["simulated"].clone();
    assert_eq!(settled(&from_stdin), settled(&from_file));
    let (code, _, err) = tensegrity_with_stdin(&["check", "-", "-"], &text);
    assert_eq!(code, 2, "standard input named twice: {err}");
}

#[test]
fn an_error_in_a_scenario_from_standard_input_is_located_in_it() {
    let text = std::fs::read_to_string("scenarios/ji2014/quick.toml").unwrap();
    let line = text.lines().position(|l| l.starts_with("mechanism")).unwrap() + 1;
    let bad = text.replacen("mechanism = \"ji2014\"", "mechanism = \"nope\"", 1);
    let (code, _, err) = tensegrity_with_stdin(&["check", "-"], &bad);
    assert_eq!(code, 2);
    assert!(err.starts_with(&format!("error: -:{line}:")), "{err}");
}

#[test]
fn a_declared_failure_that_happens_exits_0_and_the_report_keeps_the_physics_verdict() {
    let file = "scenarios/mohr2011/straight_struts.toml";
    let (code, v, err) = report_on_stdout(&["run", file, "--json", "-"]);
    assert_eq!(code, 0, "ended as declared: {err}");
    assert_eq!(v["scenarios"][0]["passed"], false);
    assert_eq!(v["scenarios"][0]["as_expected"], true);
    let (code, _, _) = tensegrity(&["run", file, "--fail-on-declared"]);
    assert_eq!(code, 1, "the physics' verdict with --fail-on-declared");
}

#[test]
fn a_declared_failure_that_does_not_happen_exits_1() {
    // The demonstration declares that the two straight struts pass through each other; with the
    // interference check made informative it no longer fails as declared.
    let text = std::fs::read_to_string("scenarios/mohr2011/straight_struts.toml").unwrap();
    let quiet = text.replacen("[interference]", "[interference]\ninformative = true", 1);
    assert_ne!(quiet, text, "the scenario has an [interference] table");
    let (code, out, err) = tensegrity_with_stdin(&["run", "-"], &quiet);
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("NOT as expected"), "{out}");
}

#[test]
fn sweep_writes_its_csv_to_standard_output_and_its_summary_off_it() {
    let (code, out, err) = tensegrity(&["sweep", PINNED_SWEEP, "--out", "-", "--set", "k2=35"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("index,grid_points,"), "{out}");
    assert!(err.contains("PASS"), "{err}");
}
