//! Motions judged extrapolated over the time step (`src/run/levels.rs`) against the same
//! motion at a sixteenth of the step: the judged trajectory meets that reference within 1e-8 of
//! its amplitude at every tick, and the run's own error estimate is within a factor 3 of the
//! difference. Both runs start from one state (the drawn one, an equilibrium where the
//! structure is prestressed by its own self-stress), so the difference is the integration's
//! alone (a settle at each step lands 1e-13 m apart, above what is compared here).

/// The reference's step as a fraction of the judged motion's: its own error, fourth order,
/// is 16^4 = 65536 times smaller.
const REFERENCE_STEP_DIVISOR: f64 = 16.0;
/// The largest difference from the reference, relative to the motion's amplitude.
const RELATIVE_TOLERANCE: f64 = 1e-8;
/// The estimate may differ from the true error by this factor either way.
const ESTIMATE_FACTOR: f64 = 3.0;

/// What a motion and its reference give: the largest difference over the compared columns
/// and ticks, the largest estimate of those columns, and the motion's amplitude (the largest
/// excursion of a compared column from its first motion value).
struct Compared {
    difference: f64,
    estimate: f64,
    amplitude: f64,
}

/// The motion of `text` at its time step `dt` and at dt / 16, compared over the columns whose
/// names start with one of `prefixes`.
fn against_reference(text: &str, dt: &str, name: &str, prefixes: &[&str]) -> Compared {
    let fine = format!("{}", dt.parse::<f64>().unwrap() / REFERENCE_STEP_DIVISOR);
    let reference = text.replacen(&format!("dt = {dt}\n"), &format!("dt = {fine}\n"), 1);
    assert_ne!(reference, text, "{name}: the step is 'dt = {dt}'");
    let (_, header, judged) = super::common::table(text, &format!("{name}-judged"));
    let (_, ref_header, exact) = super::common::table(&reference, &format!("{name}-reference"));
    assert_eq!(header, ref_header, "{name}: one table");
    let col = |n: &str| header.iter().position(|h| h == n).unwrap_or_else(|| panic!("{name}: column {n}"));
    let time = col("motion_time_s");
    // The reference's tick k * 16 is the judged motion's tick k.
    let rows: Vec<(usize, usize)> = (0..judged[time].len())
        .filter(|&i| judged[time][i] > 0.0)
        .map(|i| {
            let t = judged[time][i];
            let j = exact[time].iter().position(|r| (r - t).abs() < 1e-9).unwrap_or_else(|| panic!("{name}: t = {t}"));
            (i, j)
        })
        .collect();
    assert!(rows.len() > 100, "{name}: {} ticks compared", rows.len());
    let compared: Vec<usize> =
        (0..header.len()).filter(|&c| prefixes.iter().any(|p| header[c].starts_with(p))).collect();
    let mut out = Compared { difference: 0.0, estimate: 0.0, amplitude: 0.0 };
    for &c in &compared {
        let estimate = col(&format!("estimate:{}", header[c]));
        let first = judged[c][rows[0].0];
        for &(i, j) in &rows {
            out.difference = out.difference.max((judged[c][i] - exact[c][j]).abs());
            out.estimate = out.estimate.max(judged[estimate][i]);
            out.amplitude = out.amplitude.max((judged[c][i] - first).abs());
        }
    }
    eprintln!(
        "{name}: largest difference {:.3e} ({:.2e} of the amplitude {:.3e}), estimate {:.3e} ({:.3} of it)",
        out.difference,
        out.difference / out.amplitude,
        out.amplitude,
        out.estimate,
        out.estimate / out.difference
    );
    out
}

fn assert_meets_its_reference(c: &Compared, name: &str) {
    assert!(c.difference <= RELATIVE_TOLERANCE * c.amplitude, "{name}: {:e} of {:e}", c.difference, c.amplitude);
    let ratio = c.estimate / c.difference;
    assert!((1.0 / ESTIMATE_FACTOR..=ESTIMATE_FACTOR).contains(&ratio), "{name}: estimate over difference {ratio}");
}

/// A prestressed free structure, started from its drawn equilibrium displaced 1e-3 m along its
/// lowest non-rigid mode, for 3 s at its shipped step.
fn released_along_its_mode(path: &str, dt: &str, name: &str) -> Compared {
    let text = super::common::edited(
        path,
        &[
            ("grid = { t0 = { from = 1.0, to = 15.0, count = 8 } }", "points = [{ t0 = 5.0 }]"),
            ("duration_s = 20.0", "duration_s = 3.0"),
            ("start = \"settled\"", "start = \"drawn\""),
            ("amplitude = 1e-5", "amplitude = 1e-3"),
        ],
    );
    against_reference(&text, dt, name, &["node:"])
}

/// The 3-strut prism (measured: 2.4e-12 m, 1.25e-9 of the amplitude, estimate 1.004 of it).
#[test]
fn prism3_along_its_lowest_mode_meets_its_reference_at_a_sixteenth_of_the_step() {
    let c = released_along_its_mode("scenarios/custom/prism3_prestress_frequencies.toml", "0.005", "prism3");
    assert_meets_its_reference(&c, "prism3");
}

/// The 6-strut icosahedron (measured: 2.7e-13 m, 1.34e-10 of the amplitude, estimate 0.979 of
/// it).
#[test]
fn the_icosahedron_along_its_lowest_mode_meets_its_reference_at_a_sixteenth_of_the_step() {
    let path = "scenarios/custom/icosahedron6_prestress_frequencies.toml";
    let c = released_along_its_mode(path, "0.002", "icosahedron");
    assert_meets_its_reference(&c, "icosahedron");
}

/// The pendulum on a driven cart over its first 2 s, its joints and nodes (measured: 1.2e-15
/// rad or m, 5.6e-14 of the amplitude, estimate 1.04 of it).
#[test]
fn the_driven_cart_pendulum_meets_its_reference_at_a_sixteenth_of_the_step() {
    let text = super::common::edited(
        "scenarios/custom/cart_pendulum_driven.toml",
        &[("duration_s = 10.0", "duration_s = 2.0")],
    );
    let c = against_reference(&text, "1e-3", "cart", &["node:", "joint:"]);
    assert_meets_its_reference(&c, "cart");
}
