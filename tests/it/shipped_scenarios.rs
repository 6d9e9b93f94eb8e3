//! Every file under `scenarios/` is a regression test: it runs to the verdict its `[expect]`
//! declares, and its report's numbers (settled values, errors, steps, branches, stability,
//! findings; not wall times) match the stored baseline in `tests/baselines/` within
//! [`ABS_TOL`] + [`REL_TOL`] x |value| (integers such as steps and ticks exactly).
//!
//! Refresh the baselines after a change that moves a number on purpose (and say why in the
//! commit; the diff of `tests/baselines/` shows what moved):
//!
//! ```text
//! TENSEGRITY_BLESS=1 cargo test --release --test it shipped_scenarios
//! ```

use rayon::prelude::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use tensegrity_testbed::{run, scenario};

/// Absolute part of the tolerance on a baseline number (errors near round-off may move by
/// this much without counting as moved).
const ABS_TOL: f64 = 1e-12;
/// Relative part of the tolerance on a baseline number.
const REL_TOL: f64 = 1e-9;
/// Differences listed per scenario before the rest is counted.
const MAX_LISTED: usize = 12;
/// Set to 1 to write the baselines from this run instead of comparing with them.
const BLESS_VAR: &str = "TENSEGRITY_BLESS";

/// Every file under `dir` (at any depth) whose name ends in `.ext`, sorted.
fn files_under(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(d) = pending.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                pending.push(path);
            } else if path.extension().is_some_and(|e| e == ext) {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Every scenario file under `scenarios/`, at any depth.
fn shipped_scenarios() -> Vec<PathBuf> {
    files_under(Path::new("scenarios"), "toml")
}

/// `scenarios/ji2014/grid.toml` -> `tests/baselines/ji2014/grid.json` (the same path below
/// `tests/baselines/`, at any depth).
fn baseline_path(scenario: &Path) -> PathBuf {
    let relative = scenario.strip_prefix("scenarios").expect("a scenario under scenarios/");
    Path::new("tests/baselines").join(relative).with_extension("json")
}

/// The report without what differs from run to run (wall times).
fn comparable(report: &tensegrity_testbed::report::ScenarioReport) -> Value {
    fn strip(v: &mut Value) {
        match v {
            Value::Object(m) => {
                m.remove("wall_s");
                m.values_mut().for_each(strip);
            }
            Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v = serde_json::to_value(report).expect("report serialises");
    strip(&mut v);
    v
}

/// Significant digits a baseline keeps: rounding there moves a number by at most 5e-13 of
/// itself, far inside [`REL_TOL`].
const BASELINE_DIGITS: usize = 12;

/// `v` with every non-integer number rounded to [`BASELINE_DIGITS`] significant digits.
fn rounded(v: &Value) -> Value {
    match v {
        Value::Number(n) if n.is_f64() => {
            let x: f64 = format!("{:.*e}", BASELINE_DIGITS - 1, n.as_f64().unwrap()).parse().unwrap();
            serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
        }
        Value::Array(a) => Value::Array(a.iter().map(rounded).collect()),
        Value::Object(m) => Value::Object(m.iter().map(|(k, x)| (k.clone(), rounded(x))).collect()),
        other => other.clone(),
    }
}

/// The baseline file: one line per top-level key, and one line per element of a top-level
/// array (a settle point, a slack interval, a finding), so that a diff of the baselines names
/// the points that moved.
fn baseline_text(report: &Value) -> String {
    let compact = |v: &Value| serde_json::to_string(v).unwrap();
    let Value::Object(m) = rounded(report) else { panic!("a report is an object") };
    let mut lines = Vec::new();
    for (k, v) in &m {
        match v {
            Value::Array(a) if !a.is_empty() => {
                let items: Vec<String> = a.iter().map(|e| format!("    {}", compact(e))).collect();
                lines.push(format!("  {}: [\n{}\n  ]", compact(&Value::from(k.as_str())), items.join(",\n")));
            }
            _ => lines.push(format!("  {}: {}", compact(&Value::from(k.as_str())), compact(v))),
        }
    }
    format!("{{\n{}\n}}\n", lines.join(",\n"))
}

fn numbers_agree(a: &serde_json::Number, b: &serde_json::Number) -> bool {
    match (a.as_i64().or(a.as_u64().map(|u| u as i64)), b.as_i64().or(b.as_u64().map(|u| u as i64))) {
        (Some(x), Some(y)) if !a.is_f64() && !b.is_f64() => x == y,
        _ => {
            let (x, y) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            (x - y).abs() <= ABS_TOL + REL_TOL * x.abs().max(y.abs())
        }
    }
}

/// Every place where `got` differs from `want`, as `path: want -> got`.
fn differences(path: &str, want: &Value, got: &Value, out: &mut Vec<String>) {
    match (want, got) {
        (Value::Number(a), Value::Number(b)) if numbers_agree(a, b) => {}
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                differences(&format!("{path}[{i}]"), x, y, out);
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            for k in keys {
                let (x, y) = (a.get(k).unwrap_or(&Value::Null), b.get(k).unwrap_or(&Value::Null));
                differences(&format!("{path}.{k}"), x, y, out);
            }
        }
        (a, b) if a == b => {}
        (a, b) => out.push(format!("{path}: {a} -> {b}")),
    }
}

/// Runs one shipped scenario; what is wrong with it, if anything.
fn check(file: &Path, bless: bool) -> Vec<String> {
    let name = file.display();
    let sc = match scenario::load(file) {
        Ok(sc) => sc,
        Err(e) => return vec![format!("{name}: does not load: {e}")],
    };
    if sc.expect.is_none() {
        return vec![format!(
            "{name}: declares no [expect] verdict (verdict = \"pass\", or \"fail\" with failing = [...])"
        )];
    }
    let start = std::time::Instant::now();
    let report = run::run(&sc, &run::RunOptions::default());
    eprintln!("{name}: {} in {:.1} s", report.verdict_line(), start.elapsed().as_secs_f64());
    let mut problems = Vec::new();
    if report.as_expected != Some(true) {
        problems.push(format!("{name}: {}", report.verdict_line()));
    }
    let got = comparable(&report);
    let path = baseline_path(file);
    if bless {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, baseline_text(&got)).unwrap();
        return problems;
    }
    let want: Value = match std::fs::read_to_string(&path) {
        Ok(text) => serde_json::from_str(&text).expect("baseline is JSON"),
        Err(_) => {
            problems.push(format!(
                "{name}: no baseline {} (run {BLESS_VAR}=1 cargo test --release --test it shipped_scenarios)",
                path.display()
            ));
            return problems;
        }
    };
    let mut diffs = Vec::new();
    differences("report", &want, &got, &mut diffs);
    if !diffs.is_empty() {
        let n = diffs.len();
        diffs.truncate(MAX_LISTED);
        problems.push(format!(
            "{name}: {n} number(s) moved from {} (tolerance {ABS_TOL:e} + {REL_TOL:e} x |value|):\n    {}{}",
            path.display(),
            diffs.join("\n    "),
            if n > MAX_LISTED { format!("\n    ... and {} more", n - MAX_LISTED) } else { String::new() }
        ));
    }
    problems
}

#[test]
fn every_shipped_scenario_meets_its_declared_verdict_and_its_baseline_numbers() {
    let bless = std::env::var(BLESS_VAR).is_ok_and(|v| v == "1");
    let files = shipped_scenarios();
    let problems: Vec<String> = files.par_iter().flat_map(|f| check(f, bless)).collect();
    assert!(problems.is_empty(), "{} problem(s):\n{}", problems.len(), problems.join("\n"));
}

#[test]
fn the_baselines_are_exactly_the_shipped_scenarios() {
    // Every scenario has its baseline (a missing one fails the test above too, unless blessed)
    // and every baseline its scenario: a scenario removed or renamed leaves no stale baseline.
    let scenarios: Vec<PathBuf> = shipped_scenarios().iter().map(|f| baseline_path(f)).collect();
    let baselines = files_under(Path::new("tests/baselines"), "json");
    let orphans: Vec<&PathBuf> = baselines.iter().filter(|b| !scenarios.contains(b)).collect();
    let missing: Vec<&PathBuf> = scenarios.iter().filter(|s| !baselines.contains(s)).collect();
    assert!(orphans.is_empty(), "baselines without a scenario: {orphans:?}");
    assert!(missing.is_empty(), "scenarios without a baseline: {missing:?}");
    assert!(!scenarios.is_empty());
}

#[test]
fn a_baseline_number_that_moves_beyond_the_tolerance_is_reported() {
    let want: Value = serde_json::json!({"steps": 6, "error": 1.0e-13, "x": 0.5, "label": "a"});
    let same: Value = serde_json::json!({"steps": 6, "error": 1.5e-13, "x": 0.5 + 1e-10, "label": "a"});
    let mut out = Vec::new();
    differences("r", &want, &same, &mut out);
    assert!(out.is_empty(), "{out:?}");
    let moved: Value = serde_json::json!({"steps": 7, "error": 3.0e-12, "x": 0.5 + 1e-8, "label": "b"});
    differences("r", &want, &moved, &mut out);
    assert_eq!(out.len(), 4, "{out:?}");
}
