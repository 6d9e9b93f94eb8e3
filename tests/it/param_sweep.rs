//! Sweeps over parameters: a grid or a point may set parameters besides the inputs, for a
//! custom structure (rebuilt at each value, its derived parameters following) and for a
//! built-in mechanism (its analytic model and its structure both at the point's parameters).

use crate::common;

use std::path::Path;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

const BAR: &str = "scenarios/custom/pinned_bar_sweep.toml";
const JI_QUICK: &str = "scenarios/ji2014/quick.toml";
/// The pinned bar with no closed form: no prediction, a probe without `expected`.
const MEASURED: &str = "scenarios/custom/pinned_bar_measured.toml";

/// Each k1 of the custom sweep settles on its own energy minimum q = atan2(k1 a, k2 b)
/// (a = 0.8 m, b = 0.6 m, k2 = 30 N/m) within 1e-9 rad, read off the settled nodes.
#[test]
fn a_custom_structure_is_rebuilt_at_each_swept_stiffness() {
    let sc = scenario::load(Path::new(BAR)).unwrap();
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?}", r.failures);
    assert_eq!(r.points.len(), 9);
    for p in &r.points {
        let k1 = p.inputs["k1"];
        let q = (p.simulated["P.y"] - p.simulated["A.y"]).atan2(p.simulated["P.x"] - p.simulated["A.x"]);
        let want = (k1 * 0.8).atan2(30.0 * 0.6);
        assert!((q - want).abs() <= 1e-9, "k1 = {k1}: q = {q}, atan2 = {want}");
    }
    let first = r.points[0].simulated["P.x"];
    let last = r.points[8].simulated["P.x"];
    assert!((first - last).abs() > 0.3, "the sweep moved the bar: P.x {first} -> {last}");
}

/// The prediction's derived parameter ratio = k1/k2 follows the swept k1: the model check
/// passes at every point within 1e-9 rad (with ratio frozen at 50/30 it would be off by up to
/// 0.73 rad).
#[test]
fn a_derived_parameter_follows_the_swept_one_in_the_model() {
    let sc = scenario::load(Path::new(BAR)).unwrap();
    let r = run(&sc, &RunOptions::default());
    let q = r.model_checks.iter().find(|c| c.name == "q").expect("the prediction of q");
    assert!(q.max_error <= 1e-9, "{q:?}");
}

/// ji2014 swept over K1 (50, 225, 400 N/m) at two inputs: each point's theta2 is its own
/// K1's energy minimum (the built-in model at the point's parameters) within 1e-9 rad, and the
/// minima differ between K1 values by more than 0.3 rad.
#[test]
fn a_builtin_mechanism_is_swept_over_a_parameter() {
    let text = std::fs::read_to_string(JI_QUICK).unwrap();
    let start = text.find("points = [").unwrap();
    let end = start + text[start..].find("]\n").unwrap() + 2;
    let grid = "grid = { K1 = { from = 50.0, to = 400.0, count = 3 }, L3 = { from = 1.0, to = 1.0, count = 1 }, theta1 = { from = 0.5, to = 1.5, count = 2 } }\n";
    let text = format!("{}{grid}{}", &text[..start], &text[end..]);
    let sc = scenario::parse(Path::new("ji_k1.toml"), &text).unwrap();
    let r = run(&sc, &RunOptions { skip_findings: true, ..RunOptions::default() });
    assert!(r.passed, "{:?}", r.failures);
    assert_eq!(r.points.len(), 6);
    // The parameters vary slowest: K1 = 50 for the first two points.
    assert_eq!(r.points[0].inputs["K1"], 50.0);
    assert_eq!(r.points[5].inputs["K1"], 400.0);
    for p in &r.points {
        assert!((p.simulated["theta2"] - p.analytic["theta2"]).abs() <= 1e-9, "{:?}", p.inputs);
    }
    let d = (r.points[0].simulated["theta2"] - r.points[4].simulated["theta2"]).abs();
    assert!(d > 0.3, "K1 moved the equilibrium: {d} rad");
}

/// Bad sweeps are errors at the key or value at fault: a parameter in a waypoint, a swept
/// value the mechanism rejects (K1 <= 0), a grid key that is neither an input nor a parameter
/// (the message lists the parameters).
#[test]
fn bad_parameter_sweeps_are_located() {
    let text = std::fs::read_to_string(JI_QUICK).unwrap();
    let cases = [
        ("{ L3 = 1.0, theta1 = 0.5 }", "{ L3 = 1.0, theta1 = 0.5, K1 = -5.0 }", "-5.0", "K1"),
        ("{ L3 = 1.0, theta1 = 0.5 }", "{ L3 = 1.0, theta1 = 0.5, k9 = 1.0 }", "k9", "any parameter: K1, K2, L"),
    ];
    for (from, to, at, msg) in cases {
        common::error_at(&text.replacen(from, to, 1), at, 0, msg);
    }
    let traj = std::fs::read_to_string("scenarios/ji2014/trajectory.toml").unwrap();
    let at = traj.find("{ t = 0.0, ").expect("a waypoint") + "{ t = 0.0, ".len();
    let variant = format!("{}K1 = 150.0, {}", &traj[..at], &traj[at..]);
    common::error_at(&variant, "K1 = 150.0", 0, "cannot follow waypoints");
}

/// `sweep --figure` draws the sweep against its axis: an SVG naming each compared quantity
/// (q and the probed pin.stiffness) and the axis k1; a figure that is neither .png nor .svg is
/// refused before anything runs (exit 2), an axis the sweep does not have after (exit 1, the
/// axes named).
#[test]
fn a_sweep_draws_its_figure() {
    let dir = std::env::temp_dir().join(format!("tensegrity-sweep-figure-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("bar.svg");
    let (code, out, err) = common::tensegrity(&["sweep", BAR, "--figure", svg.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&svg).unwrap();
    for word in ["pin.stiffness", "q: closed form", "k1", "log10"] {
        assert!(text.contains(word), "{word} in the figure");
    }
    let pdf = dir.join("bar.pdf");
    let (code, _, err) = common::tensegrity(&["sweep", BAR, "--figure", pdf.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("give a .png or .svg file"), "{err}");
    // An axis the sweep does not have is bad input, refused before any point settles.
    let (code, _, err) = common::tensegrity(&["sweep", BAR, "--figure", svg.to_str().unwrap(), "--x", "k9"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not an axis of this sweep (its inputs and swept parameters: k1)"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `sweep --figure` of the pinned bar with no closed form given (`pinned_bar_measured.toml`) draws the energy model's
/// equilibrium (its coordinate qe and Hessian eigenvalue at the minimum landed on) and the
/// probe's measured stiffness against k1, and the CSV has their columns: at each of the nine
/// k1 the equilibrium is atan2(k1 a, k2 b) within 1e-12 rad, its energy -L hypot(k1 a, k2 b)
/// and its eigenvalue L hypot(k1 a, k2 b) within 1e-12 relative (the model's Newton), the
/// settled qe within 1e-9 rad of it, and the measured stiffness within 1e-6 relative of the
/// eigenvalue (L = 1 m, a = 0.8 m, b = 0.6 m, k2 = 30 N/m).
#[test]
fn a_sweep_without_closed_forms_draws_the_energy_equilibrium_and_the_measured_stiffness() {
    let dir = std::env::temp_dir().join(format!("tensegrity-sweep-measured-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = Path::new(MEASURED);
    let (svg, csv) = (dir.join("bar.svg"), dir.join("bar.csv"));
    let (code, out, err) = common::tensegrity(&[
        "sweep",
        file.to_str().unwrap(),
        "--figure",
        svg.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let figure = std::fs::read_to_string(&svg).unwrap();
    for caption in [
        "pin.stiffness: measured (dots), no closed form",
        "qe: energy model&apos;s equilibrium landed on (line), settled (dots)",
        "energy model&apos;s Hessian eigenvalue 1 at that equilibrium (line)",
    ] {
        assert!(figure.contains(caption) || figure.contains(&caption.replace("&apos;", "'")), "{caption}");
    }
    assert!(!figure.contains("closed form (line)"), "no closed form is drawn");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 9);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("column {name}"));
    let cell = |r: &Vec<&str>, name: &str| r[col(name)].parse::<f64>().unwrap();
    for r in &rows {
        let k1 = cell(r, "k1");
        let (q, stiffness) = ((k1 * 0.8).atan2(30.0 * 0.6), (k1 * 0.8).hypot(30.0 * 0.6));
        assert!((cell(r, "equilibrium_qe") - q).abs() <= 1e-12, "k1 = {k1}");
        assert!((cell(r, "equilibrium_energy") + stiffness).abs() <= 1e-12 * stiffness, "k1 = {k1}");
        assert!((cell(r, "equilibrium_eigenvalue_1") / stiffness - 1.0).abs() <= 1e-12, "k1 = {k1}");
        assert_eq!(r[col("equilibrium_kind")], "minimum");
        assert!((cell(r, "stationary_0_qe") - q).abs() <= 1e-12, "k1 = {k1}");
        let measured = cell(r, "simulated_pin.stiffness");
        assert!((measured / stiffness - 1.0).abs() <= 1e-6, "k1 = {k1}: {measured} N m/rad, want {stiffness}");
        assert_eq!(r[col("analytic_pin.stiffness")], "", "no closed form");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The pinned bar's potential from the anchors' drawn coordinates: the two springs' energy
/// k/2 |P - anchor|^2 with P = L (cos qe, sin qe), the anchors read as U.x, U.y, V.x, V.y.
const POTENTIAL_OF_NODES: &str =
    "0.5*k1*((L*cos(qe) - U.x)^2 + (L*sin(qe) - U.y)^2) + 0.5*k2*((L*cos(qe) - V.x)^2 + (L*sin(qe) - V.y)^2)";

/// The `[energy]` potential may read the nodes of fixed bodies (here the anchors U and V,
/// not typed again): swept over the anchor height a (0.6 and 1.0 m, the structure drawn again
/// at each), the model's minimum is atan2(k1 a, k2 b) within 1e-12 rad at both, and the run
/// passes (the dynamics within 1e-9 rad of it). An unknown node is an error at its name; a
/// node of the free bar is an error saying so.
#[test]
fn the_potential_reads_the_drawn_anchors() {
    let text = std::fs::read_to_string(BAR).unwrap();
    let text = text.replace("\"-k1*a*L*sin(qe) - k2*b*L*cos(qe)\"", &format!("\"{POTENTIAL_OF_NODES}\""));
    let swept = text.replace(
        "grid = { k1 = { from = 10.0, to = 90.0, count = 9 } }",
        "grid = { a = { from = 0.6, to = 1.0, count = 2 } }",
    );
    let sc = scenario::parse(Path::new("nodes.toml"), &swept).unwrap_or_else(|e| panic!("{e}"));
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?}", r.failures);
    for p in &r.points {
        let e = p.energy.as_ref().unwrap();
        let landed = &e.stationary[e.landed.unwrap()];
        let want = (50.0 * p.inputs["a"]).atan2(30.0 * 0.6);
        assert!((landed.coordinates["qe"] - want).abs() <= 1e-12, "a = {}: {landed:?}", p.inputs["a"]);
    }
    let unknown = text.replacen("U.y)^2", "W.y)^2", 1);
    common::error_at(&unknown, "W.y)^2", 0, "unknown symbol 'W.y'");
    let free = text.replacen("U.y)^2", "P.y)^2", 1);
    common::error_at(&free, "P.y)^2", 0, "node 'P' is on the free body 'bar'");
}
