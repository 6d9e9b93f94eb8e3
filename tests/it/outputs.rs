//! Outputs never destroy data: an output on an input, two outputs on one path, or an output
//! that is not a regular file are refused before anything runs (exit 2); a write that fails
//! (a full disk) leaves the previous file intact and no temporary file behind (exit 1); sweeps
//! and merges exit like `run`.

use crate::common;

use common::tensegrity;
use std::path::{Path, PathBuf};

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tensegrity-out-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Files in `d` whose name says they are temporary.
fn partials(d: &Path) -> Vec<String> {
    std::fs::read_dir(d)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.contains("partial"))
        .collect()
}

/// A copy of a quick shipped scenario in `d` (so that overwriting it would be seen).
fn scenario_copy(d: &Path) -> (PathBuf, String) {
    let text = std::fs::read_to_string("scenarios/ji2014/quick.toml").unwrap();
    let p = d.join("quick.toml");
    std::fs::write(&p, &text).unwrap();
    (p, text)
}

#[test]
fn an_output_on_an_input_is_refused_and_the_input_kept() {
    let d = dir("input");
    let (s, text) = scenario_copy(&d);
    let s = s.to_str().unwrap();
    for args in [vec!["run", s, "--json", s], vec!["sweep", s, "--out", s], vec!["sweep", s, "--json", s]] {
        let (code, _, err) = tensegrity(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("is the input"), "{err}");
        assert_eq!(std::fs::read_to_string(s).unwrap(), text, "{args:?} left the scenario as it was");
    }
    // The same file named another way is the same file.
    let other = d.join(".").join("quick.toml");
    let (code, _, err) = tensegrity(&["run", s, "--json", other.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn two_outputs_on_one_path_are_refused() {
    let d = dir("twice");
    let (s, _) = scenario_copy(&d);
    let s = s.to_str().unwrap();
    let f = d.join("out.rrd");
    let f = f.to_str().unwrap();
    let (code, _, err) = tensegrity(&["run", s, "--json", f, "--record", f]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("both write"), "{err}");
    let csv = d.join("out.csv");
    let csv = csv.to_str().unwrap();
    let (code, _, err) = tensegrity(&["sweep", s, "--out", csv, "--json", csv]);
    assert_eq!(code, 2, "{err}");
    // Two scenarios whose names sanitise to one recording name ("a b" and "a_b").
    let text = std::fs::read_to_string(s).unwrap();
    let (a, b) = (d.join("a.toml"), d.join("b.toml"));
    std::fs::write(&a, text.replacen("name = \"ji2014-quick\"", "name = \"a b\"", 1)).unwrap();
    std::fs::write(&b, text.replacen("name = \"ji2014-quick\"", "name = \"a_b\"", 1)).unwrap();
    let rec = d.join("rec").join("run.rrd");
    let (code, _, err) =
        tensegrity(&["run", a.to_str().unwrap(), b.to_str().unwrap(), "--record", rec.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("both write"), "{err}");
    assert!(!rec.parent().unwrap().join("run-a_b.rrd").exists(), "nothing ran");
}

#[test]
fn only_regular_files_are_replaced() {
    let d = dir("special");
    let (s, _) = scenario_copy(&d);
    let s = s.to_str().unwrap();
    // A directory, the null device and a link to it: refused, left as they are.
    let sub = d.join("adir");
    std::fs::create_dir_all(&sub).unwrap();
    let link = d.join("null-link.json");
    std::os::unix::fs::symlink("/dev/null", &link).unwrap();
    for target in [sub.to_str().unwrap(), "/dev/null", link.to_str().unwrap()] {
        let (code, _, err) = tensegrity(&["run", s, "--json", target]);
        assert_eq!(code, 2, "{target}: {err}");
        assert!(err.contains("not a regular file"), "{err}");
    }
    assert!(sub.is_dir());
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device());
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert!(partials(&d).is_empty(), "{:?}", partials(&d));
}

/// Four runs writing one report at once: each writes through its own temporary file, so every
/// one succeeds and the report is one complete JSON document.
#[test]
fn concurrent_runs_to_one_report_all_succeed() {
    let d = dir("concurrent");
    let (s, _) = scenario_copy(&d);
    let json = d.join("report.json");
    let children: Vec<_> = (0..4)
        .map(|_| {
            std::process::Command::new(env!("CARGO_BIN_EXE_tensegrity"))
                .args(["run", s.to_str().unwrap(), "--json", json.to_str().unwrap()])
                .stdout(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert_eq!(c.wait().unwrap().code(), Some(0));
    }
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["scenarios"].as_array().unwrap().len(), 1);
    assert!(partials(&d).is_empty(), "{:?}", partials(&d));
}

/// A report that does not fit on a full disk (a 16 KiB tmpfs): exit 1, the previous report
/// intact, no temporary file left. Needs root for the mount (CI runs as root).
#[test]
fn a_full_disk_keeps_the_previous_report() {
    let d = dir("full");
    let mnt = d.join("small");
    std::fs::create_dir_all(&mnt).unwrap();
    let mounted = std::process::Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=16k", "tmpfs", mnt.to_str().unwrap()])
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        crate::common::skip("outputs: a report on a full disk", "cannot mount a tmpfs here (needs root)");
        return;
    }
    let json = mnt.join("report.json");
    std::fs::write(&json, "previous report").unwrap();
    // ji2014 grid's report is far larger than 16 KiB.
    let (code, _, err) = tensegrity(&[
        "run",
        "scenarios/ji2014/quick.toml",
        "scenarios/ji2014/grid.toml",
        "--json",
        json.to_str().unwrap(),
    ]);
    let kept = std::fs::read_to_string(&json).unwrap();
    let left = partials(&mnt);
    let _ = std::process::Command::new("umount").arg(&mnt).status();
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("No space left"), "{err}");
    assert_eq!(kept, "previous report");
    assert!(left.is_empty(), "{left:?}");
}

/// `sweep` fails (exit 1) when no point settles, and passes a workspace sweep on its agreement;
/// the summary says which.
#[test]
fn a_sweep_where_no_point_settles_exits_1() {
    let d = dir("sweep");
    let text = std::fs::read_to_string("scenarios/ji2014/quick.toml").unwrap();
    // A settle time far too short for any point.
    let s = d.join("short.toml");
    std::fs::write(&s, text.replace("[settle]", "[settle]\nmax_time = 0.05").replace("max_time = 60.0\n", "")).unwrap();
    let json = d.join("summary.json");
    let (code, out, err) = tensegrity(&["sweep", s.to_str().unwrap(), "--json", json.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("FAIL"), "{out}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["passed"], false);
    assert_eq!(v["settled"], 0);
    let (code, out, err) = tensegrity(&["sweep", "scenarios/ji2014/quick.toml"]);
    assert_eq!(code, 0, "{out}{err}");
}

/// `merge` refuses a set of shards with one left out (exit 2, the missing points named) unless
/// told `--partial`.
#[test]
fn a_merge_with_a_shard_missing_fails_unless_partial() {
    let d = dir("merge");
    let mut shards = Vec::new();
    for k in 1..=3 {
        let p = d.join(format!("s{k}.csv"));
        let (code, _, err) = tensegrity(&[
            "sweep",
            "scenarios/ji2014/quick.toml",
            "--shard",
            &format!("{k}/3"),
            "--out",
            p.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        shards.push(p.to_str().unwrap().to_string());
    }
    let out = d.join("merged.csv");
    let (code, _, err) = tensegrity(&["merge", &shards[0], &shards[2], "--out", out.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("missing"), "{err}");
    assert!(!out.exists());
    let (code, _, err) = tensegrity(&["merge", &shards[0], &shards[2], "--out", out.to_str().unwrap(), "--partial"]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = tensegrity(&["merge", &shards[0], &shards[1], &shards[2], "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
}

/// A workspace sweep passes on its agreement, as `run` judges it: mohr2011's 7 x 7 slices agree
/// at 96.10 % (74 of 77), which passes the file's 90 % and fails a required 99 % (exit 1, the
/// summary giving both numbers).
#[test]
fn a_workspace_sweep_below_its_agreement_threshold_exits_1() {
    let d = dir("agreement");
    let text = std::fs::read_to_string("scenarios/mohr2011/workspace_grid_small.toml").unwrap();
    let (code, out, err) = tensegrity(&["sweep", "scenarios/mohr2011/workspace_grid_small.toml"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("workspace agreement 96.10 %"), "{out}");
    let strict = d.join("strict.toml");
    std::fs::write(&strict, text.replace("min_agreement_percent = 90.0", "min_agreement_percent = 99.0")).unwrap();
    let json = d.join("summary.json");
    let (code, out, err) = tensegrity(&["sweep", strict.to_str().unwrap(), "--json", json.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["min_agreement_percent"], 99.0);
    assert!((v["workspace"]["agreement_percent"].as_f64().unwrap() - 96.10).abs() < 0.01);
    assert_eq!(v["passed"], false);
}
