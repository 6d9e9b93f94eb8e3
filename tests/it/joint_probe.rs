//! A stiffness probe on a named joint of any structure (`[probe] joint = "pin"`): equal and
//! opposite loads about the joint's axis, its coordinate measured, dload/dq compared with the
//! file's closed form.

use crate::common;

use std::path::Path;
use tensegrity_testbed::report::verdict::Failure;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

const FILE: &str = "scenarios/custom/pinned_bar_sweep.toml";

/// The pinned bar's stiffness about the pin, measured at each of the nine k1 values, is the
/// energy's V''(q) = L hypot(k1 a, k2 b) (L = 1 m, a = 0.8 m, b = 0.6 m, k2 = 30 N/m) within
/// 1e-6 relative.
#[test]
fn the_probe_measures_the_joint_stiffness_of_the_energy() {
    let sc = scenario::load(Path::new(FILE)).unwrap();
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?}", r.failures);
    let probe = r.stiffness_probe.as_ref().unwrap();
    assert!(probe.passed && probe.max_rel_error.unwrap() <= 1e-6, "{probe:?}");
    assert_eq!(probe.quantity, "pin.stiffness");
    for p in &r.points {
        let k = p.simulated["pin.stiffness"];
        let want = (p.inputs["k1"] * 0.8).hypot(30.0 * 0.6);
        assert!(((k - want) / want).abs() <= 1e-6, "k1 = {}: {k} N m/rad, want {want}", p.inputs["k1"]);
        assert_eq!(p.analytic["pin.stiffness"], want);
    }
}

/// A prediction off by a factor of two fails the run on `probe` (and nothing else).
#[test]
fn a_wrong_stiffness_fails_the_probe() {
    let text = std::fs::read_to_string(FILE).unwrap().replace("\"L*hypot(k1*a, k2*b)\"", "\"2*L*hypot(k1*a, k2*b)\"");
    let text = text.replace("count = 9", "count = 2");
    let sc = scenario::parse(Path::new("wrong.toml"), &text).unwrap();
    let r = run(&sc, &RunOptions::default());
    assert_eq!(r.failures, vec![Failure::Probe]);
    let e = r.stiffness_probe.unwrap().max_rel_error.unwrap();
    assert!((e - 0.5).abs() <= 1e-6, "relative error {e}");
}

/// The pinned bar with no closed form: `[probe]` without `expected` and `tolerance`.
fn measuring_only(count: usize) -> String {
    let text = std::fs::read_to_string(FILE).unwrap().replace("count = 9", &format!("count = {count}"));
    text.replace("expected = \"L*hypot(k1*a, k2*b)\"\ntolerance = 1e-6\n", "")
}

/// A probe without a closed form only measures: the stiffness about the pin at k1 = 10 and
/// 90 N/m is reported (in the points and the probe's report, against V''(q) = L hypot(k1 a,
/// k2 b) within 1e-6 relative), no analytic value, no verdict from it (the run passes, and a
/// prediction off by a factor 2 would have failed it); the table says "measured only".
#[test]
fn a_probe_without_a_closed_form_only_measures() {
    let text = measuring_only(2);
    let sc = scenario::parse(Path::new("measure.toml"), &text).unwrap();
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?}", r.failures);
    let probe = r.stiffness_probe.as_ref().unwrap();
    assert_eq!((probe.tolerance, probe.max_rel_error, probe.passed), (None, None, true));
    assert_eq!(probe.measured.len(), 2);
    for (p, k) in r.points.iter().zip(&probe.measured) {
        let want = (p.inputs["k1"] * 0.8).hypot(30.0 * 0.6);
        assert!(((k - want) / want).abs() <= 1e-6, "k1 = {}: {k} N m/rad, want {want}", p.inputs["k1"]);
        assert_eq!(p.simulated["pin.stiffness"], *k);
        assert!(!p.analytic.contains_key("pin.stiffness"));
    }
    let table = tensegrity_testbed::report::Report { scenarios: vec![r] }.to_table();
    assert!(table.contains("stiffness probe pin.stiffness (+-0.001): measured only (no closed form)"), "{table}");
    // `tolerance` without `expected`, and `expected` without `tolerance`, are located errors.
    let with_tol = text.replace("torque = 1e-3\n", "torque = 1e-3\ntolerance = 1e-6\n");
    common::error_at(&with_tol, "1e-6\n\n[[quantities]]", 0, "probe.tolerance goes with probe.expected");
    let with_expected = text.replace("torque = 1e-3\n", "torque = 1e-3\nexpected = \"k1\"\n");
    common::error_at(&with_expected, "expected = \"k1\"", 11, "probe.expected needs probe.tolerance");
    let expect_probe = text.replace("verdict = \"pass\"", "verdict = \"fail\"\nfailing = [\"probe\"]");
    common::error_at(&expect_probe, "\"probe\"]", 0, "that compares (expected and tolerance)");
}

/// An expected stiffness that is not a number (here sqrt(-1)) or zero cannot pass or fail: it
/// is bad input at `expected`, found at read for every settle point.
#[test]
fn a_stiffness_that_is_not_a_number_is_refused_at_read() {
    for (expected, value) in [("sqrt(-1)", "NaN"), ("0*k1", "0"), ("1/(k1-10)", "inf")] {
        let text =
            std::fs::read_to_string(FILE).unwrap().replace("\"L*hypot(k1*a, k2*b)\"", &format!("\"{expected}\""));
        let text = text.replace("count = 9", "count = 2");
        let e = scenario::parse(Path::new("nan.toml"), &text).unwrap_err();
        let at = text.find(&format!("\"{expected}\"")).unwrap();
        assert_eq!((e.line, e.col), common::line_col(&text, at), "{e}");
        assert!(e.message.starts_with(&format!("probe.expected is {value} at the point")), "{e}");
    }
}

/// Bad joint probes are errors at the key at fault: an unknown joint (the joints are listed),
/// a force on a revolute joint, an expected value for the mechanism's own probe, an
/// expression with an unknown symbol.
#[test]
fn bad_joint_probes_are_located() {
    let text = std::fs::read_to_string(FILE).unwrap();
    let cases = [
        (
            "joint = \"pin\"\ntorque",
            "joint = \"hinge\"\ntorque",
            "\"hinge\"",
            "unknown joint 'hinge' (the structure's joints: pin)",
        ),
        ("torque = 1e-3", "force = 1e-3", "\"pin\"\nforce", "a revolute joint is probed with torque"),
        ("joint = \"pin\"\ntorque", "torque", "\"L*hypot", "expected goes with joint"),
        ("\"L*hypot(k1*a, k2*b)\"", "\"L*hypot(k1*a, k3*b)\"", "k3*b", "unknown symbol 'k3'"),
    ];
    for (from, to, at, msg) in cases {
        common::error_at(&text.replacen(from, to, 1), at, 0, msg);
    }
}

/// `[stability] expect = "energy"`: each settled point must be as stable as the energy model
/// classifies the stationary point the dynamics landed on. The bar's minima agree with the
/// perturbation test; with the potential's sign turned the landed point is the energy's
/// maximum, so the perturbation (which finds it stable) disagrees and the run fails on
/// `stability` (and on `energy`: the dynamics is not on a minimum).
#[test]
fn stability_is_expected_from_the_energy_model() {
    let text = std::fs::read_to_string(FILE).unwrap().replace("count = 9", "count = 2");
    let sc = scenario::parse(Path::new("energy.toml"), &text).unwrap();
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?}", r.failures);
    for p in &r.points {
        assert_eq!((p.expected_stable, p.stable), (Some(true), Some(true)), "{:?}", p.inputs);
    }
    let flipped = text.replace("\"-k1*a*L*sin(qe) - k2*b*L*cos(qe)\"", "\"k1*a*L*sin(qe) + k2*b*L*cos(qe)\"");
    let sc = scenario::parse(Path::new("flipped.toml"), &flipped).unwrap();
    let r = run(&sc, &RunOptions::default());
    let mut failures = r.failures.clone();
    failures.sort();
    assert_eq!(failures, vec![Failure::Stability, Failure::Energy]);
    assert!(r.points.iter().all(|p| p.expected_stable == Some(false) && p.stable == Some(true)));
}

/// `expect = "energy"` without an `[energy]` section is an error at the word.
#[test]
fn stability_from_energy_needs_an_energy_model() {
    let text = std::fs::read_to_string(FILE).unwrap();
    let at = text.find("[energy]\n").unwrap();
    let variant = text[..at].to_string();
    common::error_at(&variant, "\"energy\"", 0, "needs an [energy] section");
}
