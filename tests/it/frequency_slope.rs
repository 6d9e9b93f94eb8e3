//! The dynamic tutorial's curve omega(k1) (scenarios/custom/rocker_frequency_curve.toml, k1 =
//! 10 .. 80 N/m in steps of 10) and its slope: d omega / d k1 from the sensitivities (one linear
//! solve, Nelson's eigenvector formula) against the differences of the swept curve itself.

use std::path::Path;
use tensegrity_testbed::scenario;
use tensegrity_testbed::study::sensitivity;

const ROCKER: &str = "scenarios/custom/rocker_frequency_curve.toml";

/// The sweep's modal omega at each k1 of the grid, from `tensegrity sweep --out`.
fn swept_omega() -> Vec<(f64, f64)> {
    let dir = std::env::temp_dir().join(format!("tt-slope-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary directory");
    let out = dir.join("rocker.csv");
    let (code, _, stderr) = crate::common::tensegrity(&["sweep", ROCKER, "--out", out.to_str().expect("utf-8")]);
    assert_eq!(code, 0, "{stderr}");
    let text = std::fs::read_to_string(&out).expect("the sweep's CSV");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let (k1, omega) = (column("k1"), column("frequency_omega_modal"));
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            (cells[k1].parse().expect("k1"), cells[omega].parse().expect("omega"))
        })
        .collect()
}

/// At k1 = 40 N/m the sensitivities give d omega / d k1 = 0.1322070 rad/s per N/m; the curve's
/// central difference over its 10 N/m step, (omega(50) - omega(30)) / 20, lies 0.49 % above it
/// (the step's h^2 term) and its five-point difference (omega(20) - 8 omega(30) + 8 omega(50) -
/// omega(60)) / 120 0.081 % below (h^4): within 0.6 % and 0.1 %, the second at least five
/// times closer, and the slope itself within 1e-6 of 0.1322070.
#[test]
fn the_rocker_curves_slope_is_the_sensitivity_of_its_frequency() {
    let sc = scenario::load(Path::new(ROCKER)).expect("the rocker");
    let r = sensitivity(&sc, ROCKER, 3, false, None).expect("sensitivities at point 3");
    assert_eq!(r.inputs.get("k1"), Some(&40.0));
    let i = r.outputs.iter().position(|o| o.name == "mode1.omega").expect("the lowest mode");
    let slope = r.parameters.iter().find(|p| p.name == "k1").expect("k1").derivatives[i];
    let curve = swept_omega();
    let at = |k: f64| curve.iter().find(|(k1, _)| (*k1 - k).abs() < 1e-9).map(|(_, w)| *w).expect("a point");
    let central = (at(50.0) - at(30.0)) / 20.0;
    let five = (at(20.0) - 8.0 * at(30.0) + 8.0 * at(50.0) - at(60.0)) / 120.0;
    let (e2, e4) = ((central / slope - 1.0).abs(), (five / slope - 1.0).abs());
    eprintln!("rocker d omega/d k1 at 40 N/m: {slope:.7} (sensitivities), {central:.7} (central, {e2:.2e}), {five:.7} (five-point, {e4:.2e})");
    assert!((slope - 0.1322070).abs() <= 1e-6, "slope {slope}");
    assert!(e2 <= 6e-3 && e4 <= 1e-3 && e4 * 5.0 <= e2, "central {e2:.2e}, five-point {e4:.2e}");
}
