//! The readable table: one error convention per check, the same in its row and in the point
//! lines, and no header or line with nothing under it.

use crate::common;
use tensegrity_testbed::report::Report;

/// The errors a point line of `table` gives for `quantity`, in point order.
fn point_errors(table: &str, quantity: &str) -> Vec<f64> {
    let key = format!(" {quantity}=");
    table
        .lines()
        .filter(|l| l.trim_start().starts_with("point "))
        .filter_map(|l| {
            let rest = &l[l.find(&key)? + key.len()..];
            let e = &rest[rest.find("(err ")? + 5..];
            e[..e.find(')')?].parse().ok()
        })
        .collect()
}

/// The pinned bar's probe: each point line gives the stiffness's relative error (as the
/// probe's summary does), equal to |K - K_closed| / K_closed at that point to the 2 digits
/// printed, the largest of them the summary's max rel err; the prediction q its wrapped angle
/// error (below 1e-15 rad).
#[test]
fn the_point_lines_give_each_error_as_its_verdict_measures_it() {
    let r = common::run_file("scenarios/custom/pinned_bar_sweep.toml");
    let probe = r.stiffness_probe.clone().unwrap();
    let want: Vec<f64> = r
        .points
        .iter()
        .map(|p| ((p.simulated["pin.stiffness"] - p.analytic["pin.stiffness"]) / p.analytic["pin.stiffness"]).abs())
        .collect();
    let table = Report { scenarios: vec![r] }.to_table();
    let got = point_errors(&table, "pin.stiffness");
    assert_eq!(got.len(), 9, "{table}");
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() <= 0.05 * w, "point line {g:e}, relative error {w:e}\n{table}");
    }
    let largest = got.iter().copied().fold(0.0, f64::max);
    assert!((largest / probe.max_rel_error.unwrap() - 1.0).abs() <= 0.05, "{largest:e}\n{table}");
    assert!(point_errors(&table, "q").iter().all(|e| *e <= 1e-15), "{table}");
}

/// A checks row gives its errors in the convention its tolerance applies to, named at its
/// end: ji2014's x is a length, its settled and transient errors both divided by the length
/// scale L (the relative transient is the absolute one over L within 1e-12), and the table
/// names "length / L"; theta2 is an angle in rad (relative = absolute).
#[test]
fn a_check_row_gives_one_convention() {
    let r = common::run_file("scenarios/ji2014/quick.toml");
    let x = r.checks.iter().find(|c| c.quantity == "x").unwrap();
    let scale = x.max_abs_error / x.max_rel_error;
    assert!((x.transient_max_rel_error * scale / x.transient_max_abs_error - 1.0).abs() <= 1e-12, "{x:?}");
    let theta = r.checks.iter().find(|c| c.quantity == "theta2").unwrap();
    assert_eq!(
        (theta.convention.as_str(), theta.transient_max_rel_error),
        ("angle [rad]", theta.transient_max_abs_error)
    );
    let table = Report { scenarios: vec![r] }.to_table();
    let row = table.lines().find(|l| l.trim_start().starts_with("x ")).unwrap();
    assert!(row.ends_with("pass (length / L)"), "{row}");
    assert!(table.contains("check ") && !table.contains("max |err|"), "{table}");
}

/// A structure with no checks, no inputs and nothing compared prints no checks header and no
/// empty point line.
#[test]
fn nothing_to_show_prints_no_header_and_no_line() {
    let table = Report { scenarios: vec![common::run_file("scenarios/custom/prism3.toml")] }.to_table();
    assert!(!table.contains("max err") && !table.contains("point    0"), "{table}");
}
