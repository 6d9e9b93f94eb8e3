//! issue 4's bars for furet2018's dynamics: the four inverse solutions, a joint-space
//! trajectory and a cuspidal path, settled in rapier with the loops closed by projection.

use crate::common;
use common::run_file;

/// Target of the paper's Fig. 3 [m] (L = 1, b = 2/3).
const TARGET: (f64, f64) = (0.03, 1.6);

/// Each of the four inverse solutions, driven to one after the other, puts the top-bar midpoint
/// within 1e-9 L of the target, with the joint angles within 1e-9 rad of the solution.
#[test]
fn the_four_inverse_solutions_reach_the_target_within_1e_9_of_l() {
    let r = run_file("scenarios/furet2018/ik_solutions.toml");
    assert_passes_but_for_interference(&r);
    assert_eq!(r.points.len(), 4);
    let l = r.params["L"];
    for p in &r.points {
        assert!(p.settled);
        let (ex, ey) = ((p.simulated["x"] - TARGET.0).abs() / l, (p.simulated["y"] - TARGET.1).abs() / l);
        assert!(ex <= 1e-9 && ey <= 1e-9, "solution {}: end point off by ({ex:e}, {ey:e}) L", p.index);
        for q in ["theta1", "theta2"] {
            assert!((p.simulated[q] - p.inputs[q]).abs() <= 1e-9, "solution {} {q}", p.index);
        }
    }
    // Two solutions per aspect: the sign of det J alternates along the list.
    let signs: Vec<bool> = r.points.iter().map(|p| p.simulated["detJ"] > 0.0).collect();
    assert_eq!(signs, [true, false, true, false]);
}

/// Along a joint-space trajectory through both aspects the top-bar midpoint matches Eq. 3
/// within 1e-9 L at every waypoint.
#[test]
fn a_joint_space_trajectory_matches_eq_3_within_1e_9_of_l_at_every_waypoint() {
    let r = run_file("scenarios/furet2018/trajectory.toml");
    assert_passes_but_for_interference(&r);
    assert_eq!(r.points.len(), 8);
    for c in &r.checks {
        assert!(c.max_rel_error <= 1e-9, "{}: {:e}", c.quantity, c.max_rel_error);
        assert!(c.ticks_compared > 0);
    }
}

/// Cuspidality: the path from solution 1 to solution 3 (same aspect) keeps det J >= 0.13,
/// the end point comes back to the target and the joint angles end on the other solution.
#[test]
fn the_cuspidal_path_changes_solution_without_crossing_a_singularity() {
    let r = run_file("scenarios/furet2018/cuspidal_path.toml");
    assert_passes_but_for_interference(&r);
    let det = r.trajectory_ranges["detJ"];
    assert!(det.min > 0.13 && det.min < 0.1316, "smallest det J along the path {}", det.min);
    let end = &r.points[0];
    assert!((end.simulated["x"] - TARGET.0).abs() <= 1e-9 && (end.simulated["y"] - TARGET.1).abs() <= 1e-9);
    assert!((end.simulated["theta1"] - 0.283463664203).abs() <= 1e-9, "{}", end.simulated["theta1"]);
    assert!((end.simulated["theta2"] - -0.843622868024).abs() <= 1e-9, "{}", end.simulated["theta2"]);
}

/// Fig. 5 twice: at every grid point the dynamics reach (x, y) from each of its inverse
/// solutions within 1e-9 L, so the count of solutions the simulation reaches equals the
/// quartic's count at every one of the 169 points.
#[test]
fn the_workspace_grid_reaches_every_inverse_solution_within_1e_9_of_l() {
    use tensegrity_testbed::mechanisms::furet2018::analytic;
    let r = run_file("scenarios/furet2018/workspace_grid.toml");
    assert_passes_but_for_interference(&r);
    let p = analytic::Params { l: r.params["L"], b: r.params["b"] };
    let key = |x: f64, y: f64| ((x * 1e6).round() as i64, (y * 1e6).round() as i64);
    let mut reached = std::collections::BTreeMap::new();
    for q in &r.points {
        let (x, y) = (q.analytic["x"], q.analytic["y"]);
        let within = (q.simulated["x"] - x).abs() <= 1e-9 && (q.simulated["y"] - y).abs() <= 1e-9;
        assert!(q.settled && within, "point {} off its target", q.index);
        *reached.entry(key(x, y)).or_insert(0usize) += 1;
    }
    let mut by_count = [0usize; 5];
    for i in 0..13 {
        for j in 0..13 {
            let (x, y) = (-1.8 + 0.3 * i as f64, -0.2 + 2.2 * j as f64 / 12.0);
            let analytic = analytic::ik_query(&p, x, y).len();
            let simulated = reached.get(&key(x, y)).copied().unwrap_or(0);
            assert_eq!(simulated, analytic, "solutions at ({x}, {y})");
            by_count[analytic] += 1;
        }
    }
    assert_eq!(r.points.len(), 244);
    assert_eq!(r.skipped_points, 4 * 169 - 244);
    assert!(by_count[4] > 0, "the grid meets the 4-solution region: {by_count:?}");
}

/// Everything but the interference checks passes (these scenarios declare that their members
/// pass through each other somewhere, and fail on that alone), or the run passes outright.
fn assert_passes_but_for_interference(r: &tensegrity_testbed::report::ScenarioReport) {
    use tensegrity_testbed::report::verdict::Failure;
    assert!(r.error.is_none(), "{:?}", r.error);
    assert!(r.failures.iter().all(|f| *f == Failure::Interference), "{:?}", r.failures);
}
