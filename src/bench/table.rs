//! The bench's tables as text: the built-in case sets, the peer comparison, the
//! interference observer's cost, and the scale families with MuJoCo beside them.

use super::scale::peer::PeerRow;
use super::scale::FamilyReport;
use super::{BenchResult, InterferenceBench, PeerComparison};
use std::fmt::Write;

/// One scale family: a row per size, then its growth exponent.
pub fn scale_family(r: &FamilyReport) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "\n{:<12} {:>5} {:>6} {:>6} {:>7} {:>7} {:>9} {:>10} {:>9} {:>9} {:>10} {:>10}",
        "family",
        "size",
        "struts",
        "cables",
        "springs",
        "settled",
        "steps",
        "wall s",
        "rss MiB",
        "peak MiB",
        "error",
        "residual"
    );
    let mib = |k: Option<u64>| k.map_or(f64::NAN, |k| k as f64 / 1024.0);
    for c in &r.cases {
        let _ = writeln!(
            t,
            "{:<12} {:>5} {:>6} {:>6} {:>7} {:>7} {:>9} {:>10.4} {:>9.1} {:>9.1} {:>7.2e} {:<3} {:>9.2e}{}",
            c.family,
            c.size,
            c.struts,
            c.cables,
            c.springs,
            c.settled,
            c.steps,
            c.wall_s,
            mib(c.rss_before_kib),
            mib(c.peak_rss_kib),
            c.error,
            c.error_unit,
            c.residual,
            c.note.as_ref().map_or(String::new(), |n| format!("  ({n})"))
        );
    }
    let _ = match r.growth_exponent {
        Some(e) => writeln!(t, "{}: wall ~ struts^{e:.2} over the largest settled sizes", r.family),
        None => writeln!(t, "{}: growth exponent: fewer than two settled sizes", r.family),
    };
    t
}

/// The scale families beside MuJoCo: cases per second, steps and errors, and their ratios.
pub fn scale_peer(rows: &[PeerRow]) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "\nMuJoCo side by side (cases/s = 1 / wall per case; rate x = testbed / MuJoCo cases/s; error x = testbed / MuJoCo error)"
    );
    let _ = writeln!(
        t,
        "{:<12} {:>5} {:>6} | {:>9} {:>7} {:>10} {:>9} | {:>9} {:>7} {:>10} {:>9} | {:>9} {:>9}",
        "family",
        "size",
        "struts",
        "tb cases/s",
        "steps",
        "error",
        "settled",
        "mj cases/s",
        "steps",
        "error",
        "settled",
        "rate x",
        "error x"
    );
    for r in rows {
        let _ = writeln!(
            t,
            "{:<12} {:>5} {:>6} | {:>9.2} {:>7} {:>10.2e} {:>9} | {:>9.2} {:>7} {:>10.2e} {:>9} | {:>9.2} {:>9.2e} {}{}",
            r.family,
            r.size,
            r.struts,
            r.testbed_cases_per_s,
            r.testbed_steps,
            r.testbed_error,
            r.testbed_settled,
            r.peer_cases_per_s,
            r.peer_steps,
            r.peer_error,
            r.peer_settled,
            r.ratio_cases_per_s,
            r.ratio_error,
            r.error_unit,
            if r.peer_notes.is_empty() { String::new() } else { format!("  (MuJoCo: {})", r.peer_notes.join("; ")) }
        );
    }
    t
}

/// The testbed and the peer on each case set, and their ratios.
pub fn peer_comparison(out: &[PeerComparison]) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "{:<10} {:<8} {:>6} {:>10} {:>11} {:>9} {:>11} {:>11}",
        "mechanism", "side", "cases", "cases/s", "steps/case", "us/step", "median err", "max err"
    );
    for c in out {
        for (side, r) in [("testbed", &c.testbed), ("peer", &c.peer)] {
            let _ = writeln!(
                t,
                "{:<10} {:<8} {:>6} {:>10.1} {:>11.1} {:>9.2} {:>11.2e} {:>11.2e}{}",
                c.mechanism,
                side,
                r.cases,
                r.median_cases_per_s,
                r.median_steps_per_case,
                r.median_us_per_step,
                r.median_error,
                r.max_error,
                if r.all_settled { "" } else { "  (not all settled)" }
            );
        }
        let _ = writeln!(
            t,
            "{:<10} {:<8} {:>6} {:>10.2} {:>11.2} {:>9.2} {:>11.2e} {:>11.2e}",
            c.mechanism,
            "ratio",
            "",
            c.ratio_cases_per_s,
            c.ratio_steps_per_case,
            c.ratio_us_per_step,
            c.ratio_median_error,
            c.ratio_max_error
        );
    }
    if let Some(c) = out.first() {
        let _ = writeln!(t, "\npeer: {} ({})", c.peer.scenario, c.peer_name);
    }
    t
}

/// The built-in case sets' medians, and the interference observer's cost per tick.
pub fn case_sets(results: &[BenchResult], interference: &[InterferenceBench]) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "{:<10} {:>6} {:>7} {:>12} {:>12} {:>10} {:>12} {:>12}",
        "mechanism", "cases", "rounds", "cases/s", "steps/case", "us/step", "median err", "max err"
    );
    for r in results {
        let _ = writeln!(
            t,
            "{:<10} {:>6} {:>7} {:>12.1} {:>12.1} {:>10.2} {:>12.2e} {:>12.2e}",
            r.mechanism,
            r.cases,
            r.rounds,
            r.median_cases_per_s,
            r.median_steps_per_case,
            r.median_us_per_step,
            r.median_error,
            r.max_error
        );
    }
    if !interference.is_empty() {
        let _ = writeln!(t, "\ninterference observer (broad + narrow phase), per tick:");
        let _ = writeln!(t, "{:>8} {:>14} {:>12}", "struts", "pairs measured", "us/tick");
        for b in interference {
            let _ = writeln!(t, "{:>8} {:>14} {:>12.2}", b.struts, b.pairs_measured, b.median_us_per_tick);
        }
    }
    t
}

/// The motion comparison: per case, each time step's steps per second and error on both
/// sides, then the cost at equal error.
pub fn scale_motion(cases: &[crate::bench::scale::motion::MotionCase]) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "Physical motion, undamped, {} s; error = largest node distance from MuJoCo's RK4 at {} s [m]",
        crate::bench::scale::motion::DURATION_S,
        crate::bench::scale::motion::REFERENCE_DT_S
    );
    let _ = writeln!(
        t,
        "{:<12} {:>5} {:>6} {:>8} | {:>11} {:>10} | {:>11} {:>10}",
        "family", "size", "struts", "dt s", "tb steps/s", "tb error", "mj steps/s", "mj error"
    );
    for c in cases {
        for (a, b) in c.testbed.iter().zip(&c.peer) {
            let _ = writeln!(
                t,
                "{:<12} {:>5} {:>6} {:>8.1e} | {:>11.0} {:>10.2e} | {:>11.0} {:>10.2e}",
                c.family, c.size, c.struts, a.dt_s, a.steps_per_s, a.error_m, b.steps_per_s, b.error_m
            );
        }
    }
    let _ = writeln!(
        t,
        "\nAt equal error (the testbed's at dt = {} s): MuJoCo's step and wall interpolated in log-log; rate x = MuJoCo wall / testbed wall",
        crate::bench::scale::motion::EQUAL_ERROR_DT_S
    );
    let _ = writeln!(
        t,
        "{:<12} {:>5} {:>10} {:>12} {:>12} {:>9}",
        "family", "size", "error", "mj dt s", "mj wall s", "rate x"
    );
    let opt = |x: Option<f64>| x.map_or("outside".to_string(), |v| format!("{v:.2e}"));
    for c in cases {
        let _ = writeln!(
            t,
            "{:<12} {:>5} {:>10.2e} {:>12} {:>12} {:>9}",
            c.family,
            c.size,
            c.equal_error_m,
            opt(c.peer_dt_at_equal_error_s),
            opt(c.peer_wall_at_equal_error_s),
            c.ratio_at_equal_error.map_or("-".to_string(), |r| format!("{r:.2}"))
        );
    }
    t.push_str(&judged_motion(cases));
    t
}

/// The judged motion (extrapolated over the step) against MuJoCo's RK4 and Euler at equal
/// stepping time.
fn judged_motion(cases: &[crate::bench::scale::motion::MotionCase]) -> String {
    let dt = crate::bench::scale::motion::EQUAL_ERROR_DT_S;
    let mut t = format!(
        "\nJudged motion (extrapolated over the step: h, h/2, h/4, seven steps a tick, fourth order; '6th': h ... h/8, 15 steps a tick, sixth order) at dt = {dt} s, against MuJoCo's RK4 and Euler at the same wall time (interpolated in log-log between their runs at dt {:?} s)\n",
        crate::bench::scale::motion::INTEGRATOR_DT_S
    );
    let _ = writeln!(
        t,
        "{:<12} {:>5} {:>10} {:>12} | {:>12} {:>12} | {:>10} {:>12} {:>12} | judged errors at dt {:?} s",
        "family",
        "size",
        "wall s",
        "judged err",
        "mj RK4 err",
        "mj Euler err",
        "6th wall s",
        "6th err",
        "mj RK4 err",
        crate::bench::scale::motion::DT_S
    );
    let opt = |x: Option<f64>| x.map_or("outside".to_string(), |v| format!("{v:.2e}"));
    for c in cases {
        let Some(j) = c.judged.iter().find(|r| r.dt_s == dt) else { continue };
        let errors: Vec<String> = c.judged.iter().map(|r| format!("{:.2e}", r.error_m)).collect();
        let _ = writeln!(
            t,
            "{:<12} {:>5} {:>10.2e} {:>12.2e} | {:>12} {:>12} | {:>10.2e} {:>12.2e} {:>12} | {}",
            c.family,
            c.size,
            j.wall_s,
            j.error_m,
            opt(c.rk4_error_at_equal_time_m),
            opt(c.euler_error_at_equal_time_m),
            c.judged_sixth.wall_s,
            c.judged_sixth.error_m,
            opt(c.rk4_error_at_equal_time_sixth_m),
            errors.join(" ")
        );
    }
    t
}
