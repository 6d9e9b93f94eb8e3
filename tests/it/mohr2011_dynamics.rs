//! The mohr2011 issue's bars: settled centroid, pure translation, taut cables and tensions
//! against Eq. 12-14 and 26-28; exactly the predicted cables slack outside the static
//! workspace; a trajectory across its boundary; the workspace classified by the dynamics.

use crate::common;
use common::run_file;
use std::path::Path;
use tensegrity_testbed::report::ScenarioReport;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

/// A variant of a scenario file with its actuation replaced (same model and settings).
fn run_variant(path: &str, actuation: &str) -> ScenarioReport {
    let src = std::fs::read_to_string(path).expect("scenario file");
    let head = &src[..src.find("[actuation]").expect("has [actuation]")];
    let tail = &src[src.find("[[checks]]").expect("has checks")..];
    let text = format!("{head}[actuation]\n{actuation}\n\n{tail}");
    let sc = scenario::parse(Path::new(path), &text).expect("variant is valid");
    run(&sc, &RunOptions::default())
}

/// Inside the static workspace (24 points, l_b = 2, l_o = 3 l_b): the centroid within 1e-9 l_b
/// of Eq. 12-14, rotation below 1e-9 rad, every cable taut, tensions within 1e-7 of Eq. 26-28.
#[test]
fn static_workspace_points_match_eq12_14_and_eq26_28() {
    let r = run_file("scenarios/mohr2011/static_workspace.toml");
    assert_passes_but_for_interference(&r);
    assert!(r.points.len() >= 20, "{} points", r.points.len());
    let lb = r.params["lb"];
    for p in &r.points {
        assert!(p.settled, "point {} did not settle", p.index);
        assert!(p.slack_cables.is_empty(), "point {}: slack {:?}", p.index, p.slack_cables);
        for q in ["x", "y", "z"] {
            let e = (p.simulated[q] - p.analytic[q]).abs() / lb;
            assert!(e <= 1e-9, "point {} {q}: {e:e} l_b", p.index);
        }
        assert!(p.simulated["rotation"].abs() <= 1e-9, "point {}: rotation {:e}", p.index, p.simulated["rotation"]);
        for j in 1..=6 {
            let t = format!("t{j}");
            let e = ((p.simulated[&t] - p.analytic[&t]) / p.analytic[&t]).abs();
            assert!(p.analytic[&t] > 0.0 && e <= 1e-7, "point {} {t}: {e:e}", p.index);
        }
    }
}

/// Outside the static workspace the cable pair that Eq. 26-28 makes negative goes slack, and
/// only that pair; the end-effector settles elsewhere, at a reported distance.
#[test]
fn outside_the_static_workspace_exactly_the_predicted_pair_goes_slack() {
    let r = run_variant(
        "scenarios/mohr2011/outside_static.toml",
        "continuation = false\npoints = [ { x = 0.0, y = 1.0, z = 0.5 }, { x = 2.0, y = 0.0, z = 1.5 } ]",
    );
    assert_passes_but_for_interference(&r);
    let expected: [&[&str]; 2] = [&["A1B2", "A2B1"], &["A1B3", "A3B1"]];
    for (p, want) in r.points.iter().zip(expected) {
        assert!(p.settled, "point {} did not settle", p.index);
        let mut got = p.slack_cables.clone();
        got.sort();
        assert_eq!(got, want, "point {}", p.index);
        assert_eq!(p.slack_agrees, Some(true));
        let d = p.distance_from_analytic_m.expect("distance reported");
        assert!(d > 0.1, "point {}: settled {d} m from the analytic point", p.index);
    }
    // Nothing to compare the checks with: they are not applicable, and say so.
    assert!(r.checks.iter().all(|c| c.points_compared == 0 && c.passed));
}

/// Along a path that leaves the static workspace and comes back, the report gives the error
/// at every tick and the ticks where cables were slack; it settles back within 1e-9.
#[test]
fn trajectory_across_the_boundary_reports_slack_ticks_and_resettles() {
    let r = run_file("scenarios/mohr2011/trajectory.toml");
    assert_passes_but_for_interference(&r);
    let x = r.checks.iter().find(|c| c.quantity == "x").expect("x checked");
    assert!(x.ticks_compared >= 1200, "{} ticks compared", x.ticks_compared);
    assert!(x.max_rel_error <= 1e-9);
    // Pair rho1 (A2B3, A3B2) loses tension on the way out (t = 4 s is tick 400).
    let late_slack =
        r.slack_intervals.iter().filter(|i| i.cable == "A2B3" && i.last_tick >= 300 && i.first_tick <= 500).count();
    assert!(late_slack >= 1, "{:?}", r.slack_intervals);
}

/// A small workspace slice classified by the dynamics agrees with Eq. 29-31 at every point
/// away from the outer boundary.
#[test]
fn workspace_slice_by_dynamics_agrees_with_eq29_31() {
    let r = run_variant(
        "scenarios/mohr2011/workspace_grid_small.toml",
        "skip_outside = true\ncontinuation = false\ngrid = { x = { from = -2.0, to = 2.0, count = 3 }, y = { from = -2.0, to = 2.0, count = 3 }, z = { from = 1.5, to = 1.5, count = 1 } }",
    );
    let w = r.workspace.as_ref().expect("workspace classification");
    assert_eq!(w.points, 9);
    assert!(w.analytic_inside > 0 && w.analytic_inside < 9, "{w:?}");
    assert_eq!(w.agreement_percent, 100.0, "{w:?}");
    assert!(r.passed);
}

/// Elastic cables stretch by t/k: the dynamics settle where Eq. 12-14 on the stretched lengths
/// (iterated with Eq. 26-28) says, 1.7e-3 m above the inextensible answer, within 1e-9 l_b.
#[test]
fn elastic_cables_settle_on_the_stretched_equilibrium() {
    let r = run_variant("scenarios/mohr2011/elastic_cables.toml", "points = [ { x = 0.0, y = 0.0, z = 3.0 } ]");
    assert_passes_but_for_interference(&r);
    let p = &r.points[0];
    let stretch = p.analytic["z"] - 3.0;
    assert!(stretch > 1e-3 && stretch < 3e-3, "stretch {stretch} m");
    assert!((p.simulated["z"] - p.analytic["z"]).abs() <= 1e-9 * r.params["lb"]);
}

/// A settled state far from every analytic branch is labelled as on none of them, never with
/// the nearest one's name: with continuation, elastic_cables.toml's cable lengths jump between
/// points and throw the end-effector through the base (z < 0, the mirror assembly), and the
/// run fails on z.
#[test]
fn a_state_on_the_mirror_assembly_is_on_none_of_the_branches_and_fails() {
    let r = run_variant(
        "scenarios/mohr2011/elastic_cables.toml",
        "continuation = true\npoints = [ { x = 0.0, y = 0.0, z = 3.0 }, { x = 0.3, y = -0.2, z = 2.5 } ]",
    );
    assert_eq!(r.points[0].branch, "z > 0 (Eq. 12-14)");
    let p = &r.points[1];
    assert!(p.settled && p.simulated["z"] < -2.0, "z = {} m", p.simulated["z"]);
    assert_eq!(p.branch, format!("{} (nearest: z > 0 (Eq. 12-14))", tensegrity_testbed::run::NO_BRANCH));
    assert!(r.failures.contains(&tensegrity_testbed::report::verdict::Failure::Check("z".into())), "{:?}", r.failures);
}

/// With straight struts (the design Section 2 rejects) all three struts cross at p/2: the
/// interference observer reports each pair, from the drawn state (tick 0), with the closest points.
#[test]
fn straight_struts_collide_at_their_midpoints() {
    let r = run_file("scenarios/mohr2011/straight_struts.toml");
    assert!(!r.passed, "the collision must fail the run");
    assert!(r.error.is_none(), "{:?}", r.error);
    assert!(r.checks.iter().all(|c| c.passed), "the statics still hold");
    let i = r.interference.as_ref().expect("interference report");
    let struts: Vec<_> = i.violations.iter().filter(|v| v.kinds == ["strut", "strut"]).collect();
    assert_eq!(struts.len(), 3, "{:?}", i.violations);
    let radius = r.params["r_strut"];
    for v in struts {
        assert!(v.pair.iter().all(|s| s.contains("straight")), "{:?}", v.pair);
        assert_eq!(v.first_tick, 0, "as drawn");
        assert!((v.min_clearance_m + 2.0 * radius).abs() <= 1e-9, "clearance {}", v.min_clearance_m);
        // The closest points lie on the Z axis at half the end-effector's height (p/2).
        let [a, b] = v.closest_points;
        assert!(a[0].hypot(a[1]) <= 1e-6 && (a[2] - b[2]).abs() <= 1e-6, "{a:?} {b:?}");
    }
}

/// Section 5's gravity: with a hanging 1 kg end-effector the loaded wrench balance matches the
/// dynamics, and at (1, 1, 3) the weight makes one cable (A1B2) go slack.
#[test]
fn hanging_end_effector_matches_the_loaded_statics() {
    let r = run_file("scenarios/mohr2011/gravity_hanging.toml");
    assert_passes_but_for_interference(&r);
    let last = r.points.last().expect("points");
    assert_eq!(last.slack_cables, vec!["A1B2".to_string()]);
    assert_eq!(last.slack_agrees, Some(true));
    for p in &r.points[..r.points.len() - 1] {
        let e = ((p.simulated["t1"] - p.analytic["t1"]) / p.analytic["t1"]).abs();
        assert!(e <= 1e-7, "point {}: t1 error {e:e}", p.index);
        assert!(p.analytic["t1"] != p.analytic["t4"], "the load unbalances the pair");
    }
}

/// With the legs and the taut cables projected after every step, the settled state no longer
/// carries rapier's rope offset: at 48 PGS iterations (512 were needed for 1.6e-10 before) every
/// point of the static workspace is within 1e-13 l_b of Eq. 12-14 and every tension within
/// 1e-11 of Eq. 26-28 (measured 1e-15 and 5.9e-13), in a median of at most 10 steps (7).
#[test]
fn projected_legs_and_cables_settle_to_round_off_in_few_steps() {
    let r = run_file("scenarios/mohr2011/static_workspace.toml");
    assert_passes_but_for_interference(&r);
    let lb = r.params["lb"];
    let mut steps: Vec<u64> = r.points.iter().map(|p| p.steps).collect();
    steps.sort_unstable();
    assert!(steps[steps.len() / 2] <= 10, "median steps {}", steps[steps.len() / 2]);
    for p in &r.points {
        for q in ["x", "y", "z"] {
            let e = (p.simulated[q] - p.analytic[q]).abs() / lb;
            assert!(e <= 1e-13, "point {} {q}: {e:e} l_b", p.index);
        }
        for j in 1..=6 {
            let t = format!("t{j}");
            let e = ((p.simulated[&t] - p.analytic[&t]) / p.analytic[&t]).abs();
            assert!(e <= 1e-11, "point {} {t}: {e:e}", p.index);
        }
    }
}

/// Everything but the interference checks passes (these scenarios declare that their members
/// pass through each other somewhere, and fail on that alone), or the run passes outright.
fn assert_passes_but_for_interference(r: &tensegrity_testbed::report::ScenarioReport) {
    use tensegrity_testbed::report::verdict::Failure;
    assert!(r.error.is_none(), "{:?}", r.error);
    assert!(r.failures.iter().all(|f| *f == Failure::Interference), "{:?}", r.failures);
}

/// The undamped free vibration along the lowest mode, at each of 24 workspace points with
/// elastic cables, has the constrained modal analysis's frequency within 1e-6 (measured: at most
/// 8.5e-7); the lowest pair of modes stays degenerate on the symmetry axis.
#[test]
fn free_vibration_meets_the_constrained_modal_frequency_at_every_workspace_point() {
    let r = run_file("scenarios/mohr2011/free_vibration_map.toml");
    assert!(r.error.is_none(), "{:?}", r.error);
    assert!(r.points.len() >= 24, "{} points", r.points.len());
    for p in &r.points {
        assert!(p.settled, "point {} did not settle", p.index);
        let f = p.frequencies.first().unwrap_or_else(|| panic!("point {}: no frequency measured", p.index));
        let relative = (f.corrected_rad_per_s - f.predicted_rad_per_s).abs() / f.predicted_rad_per_s;
        assert!(
            relative <= 1e-6 && f.passed,
            "point {}: {} vs modal {}",
            p.index,
            f.corrected_rad_per_s,
            f.predicted_rad_per_s
        );
    }
}
