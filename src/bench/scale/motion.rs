//! `tensegrity bench --scale --motion --peer`: the cost of physical dynamics on the free-body
//! scale families, beside MuJoCo's, at equal trajectory error (issue 33).
//!
//! Each case's perturbed start moves undamped (body damping 0, no settle accelerator: the
//! path is the dynamics' own) for [`DURATION_S`] at each time step of [`DT_S`], in the testbed
//! and in MuJoCo (the case's MJCF export, `implicitfast` as exported). The reference is
//! MuJoCo's RK4 at [`REFERENCE_DT_S`]: the same equations of motion on both sides (rigid
//! bodies, springs and tension-only cables as tendons, held bodies; no constraint). The furet
//! chains are left out: MuJoCo closes their loops with soft equalities, another model. Error:
//! the largest node distance from the reference at the end \[m\]. Steps per second: the steps
//! over the wall time of stepping alone (building excluded on both sides; runs repeated until
//! they add up to 0.2 s, the median taken; MuJoCo's steps are `mj_step` calls from a Python
//! loop, as in its other comparisons).
//!
//! At equal error: the testbed's error at [`EQUAL_ERROR_DT_S`] is the level; MuJoCo's time
//! step and wall time at that error are interpolated in log-log between its runs (None when
//! the level is outside them), and the ratio compares simulated seconds per wall second.

use super::{cases, Case};
use crate::bench::{write_error, BenchError};
use crate::structure::Vec3;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The families whose equations of motion are the same in MuJoCo: free bodies, and the
/// judged-motion structures of `judged.rs` (hinges, a spinning body).
pub const FAMILIES: [&str; 8] = ["prism", "icosahedron", "tower", "spine", "pendulum", "rocker", "spin", "cart"];
/// Simulated time of every run \[s\].
pub const DURATION_S: f64 = 0.5;
/// Time steps of both sides \[s\].
pub const DT_S: [f64; 4] = [4e-3, 2e-3, 1e-3, 5e-4];
/// MuJoCo's RK4 step for the reference \[s\]: a tenth of the finest step, fourth order.
pub const REFERENCE_DT_S: f64 = 5e-5;
/// The testbed's time step whose error sets the level compared \[s\].
pub const EQUAL_ERROR_DT_S: f64 = 1e-3;
/// MuJoCo's time steps with RK4 and with Euler \[s\], spanning the testbed's judged motion's
/// wall time at [`EQUAL_ERROR_DT_S`] (seven steps a tick).
pub const INTEGRATOR_DT_S: [f64; 7] = [8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4];

/// One run of one side at one time step.
#[derive(Clone, Debug, Serialize)]
pub struct MotionRun {
    pub dt_s: f64,
    pub steps: u64,
    /// Wall time of the steps alone \[s\].
    pub wall_s: f64,
    pub steps_per_s: f64,
    /// Largest node distance from the reference at the end \[m\].
    pub error_m: f64,
}

/// One case: both sides' runs and the comparison at the testbed's error at
/// [`EQUAL_ERROR_DT_S`].
#[derive(Clone, Debug, Serialize)]
pub struct MotionCase {
    pub family: &'static str,
    pub size: usize,
    pub struts: usize,
    pub testbed: Vec<MotionRun>,
    pub peer: Vec<MotionRun>,
    /// The error level compared \[m\].
    pub equal_error_m: f64,
    /// MuJoCo's time step and wall time reaching that level (interpolated), if within its runs.
    pub peer_dt_at_equal_error_s: Option<f64>,
    pub peer_wall_at_equal_error_s: Option<f64>,
    /// Testbed / MuJoCo simulated seconds per wall second at that level.
    pub ratio_at_equal_error: Option<f64>,
    /// The testbed's judged motion (extrapolated over the step, `judged.rs`) at each of [`DT_S`].
    pub judged: Vec<MotionRun>,
    /// MuJoCo's RK4 and Euler at each of [`INTEGRATOR_DT_S`].
    pub peer_rk4: Vec<MotionRun>,
    pub peer_euler: Vec<MotionRun>,
    /// At equal stepping time: MuJoCo's RK4 and Euler errors at the wall time of the testbed's
    /// judged run at [`EQUAL_ERROR_DT_S`] \[m\], interpolated in log-log between their runs
    /// (None outside them).
    pub rk4_error_at_equal_time_m: Option<f64>,
    pub euler_error_at_equal_time_m: Option<f64>,
    /// The judged motion over four levels (h ... h/8, sixth order, 15 steps a tick) at
    /// [`EQUAL_ERROR_DT_S`], and MuJoCo's RK4 error at its wall time \[m\].
    pub judged_sixth: MotionRun,
    pub rk4_error_at_equal_time_sixth_m: Option<f64>,
}

/// The levels of the bench's second judged motion: sixth order.
const SIXTH_ORDER_LEVELS: usize = 4;

/// The testbed's run of `case` at `dt`, repeated until the runs add up to
/// [`super::MIN_CASE_WALL_S`] (as the settles are): the node positions at the end, steps and
/// the median wall time.
fn testbed_run(case: &Case, dt: f64) -> Result<(Vec<Vec3>, u64, f64), BenchError> {
    let (positions, steps, first) = testbed_run_once(case, dt)?;
    let wall = super::median_wall(first, || Ok(testbed_run_once(case, dt)?.2))?;
    Ok((positions, steps, wall))
}

/// One run of `case` at `dt`: the node positions at the end, steps and wall time of the steps.
fn testbed_run_once(case: &Case, dt: f64) -> Result<(Vec<Vec3>, u64, f64), BenchError> {
    let mut sim = super::judged::physical(case, dt)?;
    let steps = (DURATION_S / dt).round() as u64;
    let start = Instant::now();
    for k in 1..=steps {
        if let Some(d) = &case.drive {
            sim.drive_commands(&d.commands_at(k as f64 * dt));
        }
        sim.step()?;
    }
    Ok((sim.node_positions(), steps, start.elapsed().as_secs_f64()))
}

/// Largest distance between corresponding points [m].
fn largest_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| crate::structure::distance(*p, *q)).fold(0.0, f64::max)
}

/// Linear interpolation of `y` at `x` in log-log through points sorted by x; None outside.
fn log_log_at(points: &[(f64, f64)], x: f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        let (lo, hi) = (x0.min(x1), x0.max(x1));
        (x >= lo && x <= hi && x0 != x1).then(|| {
            let t = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
            (y0.ln() + t * (y1.ln() - y0.ln())).exp()
        })
    })
}

/// MuJoCo's time step and wall time at error `level`, interpolated between its runs.
fn peer_at_error(peer: &[MotionRun], level: f64) -> (Option<f64>, Option<f64>) {
    let mut by_error: Vec<&MotionRun> = peer.iter().filter(|r| r.error_m > 0.0 && r.error_m.is_finite()).collect();
    by_error.sort_by(|a, b| a.error_m.total_cmp(&b.error_m));
    let dt = log_log_at(&by_error.iter().map(|r| (r.error_m, r.dt_s)).collect::<Vec<_>>(), level);
    let wall = log_log_at(&by_error.iter().map(|r| (r.error_m, r.wall_s)).collect::<Vec<_>>(), level);
    (dt, wall)
}

/// The case list for the peer: each case's MJCF (undamped) and its node sites.
fn peer_case(case: &Case, dir: &Path) -> Result<serde_json::Value, BenchError> {
    let s = &case.start;
    let path = dir.join(format!("motion-{}-{}.xml", case.family, case.size));
    super::peer::write_mjcf(case, EQUAL_ERROR_DT_S, 0.0, &path)?;
    let spin = case.spin.map(|(b, w)| serde_json::json!({ "body": s.bodies[b].name, "angular_velocity": w }));
    let drive = case.drive.as_ref().map(
        |d| serde_json::json!({ "body": d.body, "axis": d.axis, "stroke_m": d.stroke_m, "rad_per_s": d.rad_per_s }),
    );
    Ok(serde_json::json!({
        "family": case.family, "size": case.size, "mjcf": path.display().to_string(),
        "nodes": s.nodes.iter().map(|n| n.name.clone()).collect::<Vec<_>>(), "spin": spin, "drive": drive,
    }))
}

/// One run of the peer: time step [s], steps, wall time [s] and the nodes' final positions.
type PeerRun = (f64, u64, f64, Vec<Vec3>);

/// A list of points from the peer's JSON.
fn points(v: &serde_json::Value) -> Option<Vec<Vec3>> {
    v.as_array()?.iter().map(|p| serde_json::from_value::<Vec3>(p.clone()).ok()).collect()
}

/// The peer's runs under `key` of one case (none where the key is absent).
fn peer_runs(p: &serde_json::Value, key: &str) -> Result<Vec<PeerRun>, BenchError> {
    let bad = || BenchError::Peer(format!("the peer's motion case has a malformed '{key}'"));
    let Some(runs) = p.get(key) else { return Ok(Vec::new()) };
    runs.as_array()
        .ok_or_else(bad)?
        .iter()
        .map(|r| {
            let num = |k: &str| r.get(k).and_then(|x| x.as_f64());
            Some((num("dt_s")?, r.get("steps")?.as_u64()?, num("wall_s")?, points(r.get("positions")?)?))
        })
        .collect::<Option<Vec<_>>>()
        .ok_or_else(bad)
}

fn run(dt_s: f64, steps: u64, wall_s: f64, error_m: f64) -> MotionRun {
    MotionRun { dt_s, steps, wall_s, steps_per_s: steps as f64 / wall_s, error_m }
}

/// Every case of `families` (free-body ones) up to `max_struts`: the testbed's runs, then the
/// peer's with its reference, compared. `progress` is told what starts (a line of text, for
/// the command line to show).
pub fn compare(
    families: &[&'static str],
    max_struts: usize,
    command: &[String],
    dir: &Path,
    progress: &dyn Fn(&str),
) -> Result<Vec<MotionCase>, BenchError> {
    std::fs::create_dir_all(dir).map_err(write_error(dir))?;
    let (mut ours, mut listed) = (Vec::new(), Vec::new());
    for family in families.iter().filter(|f| FAMILIES.contains(f)) {
        let family_cases = if super::judged::FAMILIES.contains(family) {
            super::judged::cases(family)?
        } else {
            cases(family, max_struts)?
        };
        for case in family_cases {
            progress(&format!("{} {}: testbed motion ...", case.family, case.size));
            let runs = DT_S.iter().map(|&dt| testbed_run(&case, dt)).collect::<Result<Vec<_>, _>>()?;
            let judged = DT_S
                .iter()
                .map(|&dt| super::judged::judged_run(&case, dt, DURATION_S, crate::run::MIN_LEVELS))
                .collect::<Result<Vec<_>, _>>()?;
            let sixth = super::judged::judged_run(&case, EQUAL_ERROR_DT_S, DURATION_S, SIXTH_ORDER_LEVELS)?;
            listed.push(peer_case(&case, dir)?);
            ours.push((case, runs, judged, sixth));
        }
    }
    let file = dir.join("motion_cases.json");
    let list = serde_json::json!({
        "motion": {
            "duration_s": DURATION_S, "dts": DT_S, "reference_dt_s": REFERENCE_DT_S, "integrator_dts": INTEGRATOR_DT_S,
        },
        "cases": listed,
    });
    crate::bench::write_whole(&file, &serde_json::to_string_pretty(&list).expect("case list serialises"))?;
    progress(&format!("{} cases: peer motion ...", listed.len()));
    let v = crate::bench::run_peer(command, &file, &[])?;
    let theirs = v.get("cases").and_then(|c| c.as_array()).filter(|c| c.len() == ours.len());
    let theirs =
        theirs.ok_or_else(|| BenchError::Peer(format!("the peer did not return {} motion cases", ours.len())))?;
    ours.into_iter()
        .zip(theirs)
        .map(|((case, runs, judged, sixth), p)| compare_case(&case, [runs, judged], sixth, p))
        .collect()
}

/// One testbed run: end positions, steps (or ticks), wall time.
type TestbedRun = (Vec<Vec3>, u64, f64);
/// The testbed's runs at each of [`DT_S`].
type TestbedRuns = Vec<TestbedRun>;

/// One case's comparison against the peer's reference: `[raw, judged]` the testbed's runs of
/// rapier's steps alone and of the judged motion at each of [`DT_S`], `sixth` its sixth-order
/// judged run at [`EQUAL_ERROR_DT_S`].
fn compare_case(
    case: &Case,
    [raw, judged]: [TestbedRuns; 2],
    sixth: TestbedRun,
    p: &serde_json::Value,
) -> Result<MotionCase, BenchError> {
    let bad = || BenchError::Peer("the peer's motion case lacks its 'reference'".into());
    let reference = points(p.get("reference").ok_or_else(bad)?).ok_or_else(bad)?;
    let ours = |runs: TestbedRuns| -> Vec<MotionRun> {
        DT_S.iter()
            .zip(runs)
            .map(|(&dt, (pos, steps, wall))| run(dt, steps, wall, largest_distance(&pos, &reference)))
            .collect()
    };
    let theirs = |key: &str| -> Result<Vec<MotionRun>, BenchError> {
        let runs = peer_runs(p, key)?;
        Ok(runs
            .into_iter()
            .map(|(dt, steps, wall, pos)| run(dt, steps, wall, largest_distance(&pos, &reference)))
            .collect())
    };
    let sixth = run(EQUAL_ERROR_DT_S, sixth.1, sixth.2, largest_distance(&sixth.0, &reference));
    let (testbed, judged, peer) = (ours(raw), ours(judged), theirs("runs")?);
    let (peer_rk4, peer_euler) = (theirs("rk4_runs")?, theirs("euler_runs")?);
    let at = |runs: &[MotionRun]| {
        runs.iter().find(|r| r.dt_s == EQUAL_ERROR_DT_S).expect("EQUAL_ERROR_DT_S is one of DT_S").clone()
    };
    let (raw_at, judged_at) = (at(&testbed), at(&judged));
    let (dt, wall) = peer_at_error(&peer, raw_at.error_m);
    Ok(MotionCase {
        family: case.family,
        size: case.size,
        struts: case.start.count_of(crate::structure::MemberKind::Strut),
        equal_error_m: raw_at.error_m,
        peer_dt_at_equal_error_s: dt,
        peer_wall_at_equal_error_s: wall,
        ratio_at_equal_error: wall.map(|w| w / raw_at.wall_s),
        rk4_error_at_equal_time_m: error_at_wall(&peer_rk4, judged_at.wall_s),
        euler_error_at_equal_time_m: error_at_wall(&peer_euler, judged_at.wall_s),
        rk4_error_at_equal_time_sixth_m: error_at_wall(&peer_rk4, sixth.wall_s),
        judged_sixth: sixth,
        testbed,
        peer,
        judged,
        peer_rk4,
        peer_euler,
    })
}

/// A peer's error at wall time `wall_s`, interpolated in log-log between its runs (those with
/// a finite, positive error, by wall time).
fn error_at_wall(runs: &[MotionRun], wall_s: f64) -> Option<f64> {
    let mut by_wall: Vec<&MotionRun> = runs.iter().filter(|r| r.error_m > 0.0 && r.error_m.is_finite()).collect();
    by_wall.sort_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
    log_log_at(&by_wall.iter().map(|r| (r.wall_s, r.error_m)).collect::<Vec<_>>(), wall_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Log-log interpolation of y = x^2 between (1, 1) and (4, 16) gives 4 at 2 within 1e-12,
    /// and nothing outside [1, 4].
    #[test]
    fn log_log_interpolation_is_exact_for_a_power_law() {
        let pts = [(1.0, 1.0), (4.0, 16.0)];
        assert!((log_log_at(&pts, 2.0).unwrap() - 4.0).abs() <= 1e-12);
        assert!(log_log_at(&pts, 0.5).is_none() && log_log_at(&pts, 5.0).is_none());
    }

    /// MuJoCo's wall time at an error between two of its runs is read off the line between
    /// them: errors 1e-3 and 1e-4 at 1 and 10 ms of wall give 10^-2.5 s at 10^-3.5 m.
    #[test]
    fn the_peer_wall_at_a_level_between_its_runs_is_interpolated() {
        let peer = [run(2e-3, 250, 1e-3, 1e-3), run(2e-4, 2500, 1e-2, 1e-4)];
        let (dt, wall) = peer_at_error(&peer, 10f64.powf(-3.5));
        assert!((wall.unwrap() - 10f64.powf(-2.5)).abs() <= 1e-15);
        assert!((dt.unwrap() - 2e-3 * 10f64.powf(-0.5)).abs() <= 1e-15);
    }
}
