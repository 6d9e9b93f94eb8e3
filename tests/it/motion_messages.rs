//! What a report says of a motion run and of a file without expected values, in the words the
//! table prints: the accelerated steps of a settle to the motion's start named as the settle's,
//! no transient errors for checks judged at the start point, and no branch of expected values
//! that the file does not state.

use super::common::run_file;
use tensegrity_testbed::report::{Report, ScenarioReport};

/// The table `tensegrity run` prints for one report.
fn table_of(r: &ScenarioReport) -> String {
    Report { scenarios: vec![r.clone()] }.to_table()
}

/// A motion from the settled state: its path is the motion's (physical, no accelerated step),
/// and the 4 accelerated steps are said to be the settle's before it. Its `[[checks]]` are
/// judged at the start point: their errors during the motion are "-", with the note saying
/// why, not numbers that look like failures.
#[test]
fn a_settled_start_names_its_accelerated_steps_and_hides_the_checks_transients() {
    let report = run_file("scenarios/custom/icosahedron6_free_vibration.toml");
    let table = table_of(&report);
    assert_eq!(report.accelerated_steps, 4);
    assert!(
        table.contains("   path: physical (the motion: 0 accelerated step(s); the settle to its start: 4)\n"),
        "{table}"
    );
    let rows: Vec<&str> = table.lines().filter(|l| l.trim_start().starts_with("strut:a3-a4.force")).collect();
    assert_eq!(rows.len(), 1, "{table}");
    let cells: Vec<&str> = rows[0].split_whitespace().collect();
    assert_eq!(cells[3..6], ["-", "-", "pass"], "{}", rows[0]);
    assert!(table.contains("   (a motion run: checks, equations and the energy model are judged at its start point; their errors during the motion mean nothing and are not shown: \"-\")\n"), "{table}");
    assert!(table.contains("   landed on: expected values from the file: 1 point(s)\n"), "{table}");
}

/// A drawn start has no settle: the path line says the motion's steps alone. The prediction,
/// judged over the motion's ticks, keeps its errors there; the energy model, judged at the
/// start point, shows "-".
#[test]
fn a_drawn_start_keeps_the_predictions_errors_over_the_motion() {
    let table = table_of(&run_file("scenarios/custom/pinned_bar_vibration.toml"));
    assert!(table.contains("   path: physical (the motion: 0 accelerated step(s))\n"), "{table}");
    let row = |name: &str| {
        let line =
            table.lines().find(|l| l.trim_start().starts_with(name)).unwrap_or_else(|| panic!("{name}: {table}"));
        line.split_whitespace().map(str::to_string).collect::<Vec<_>>()
    };
    assert_eq!(row("small oscillation")[4..6], ["4.026e-9", "1.672e-9"]);
    assert_eq!(row("energy")[3..5], ["-", "-"]);
}

/// A custom file that states no expected values lands on no branch of them: it says so. A run
/// that is no motion keeps its accelerated steps' line and its checks' transient errors.
#[test]
fn a_file_without_expected_values_says_it_states_none() {
    let report = run_file("scenarios/custom/prism3.toml");
    let table = table_of(&report);
    assert_eq!(report.points[0].branch, "none (the file's [[checks]] state no values)");
    assert!(table.contains("   landed on: none (the file's [[checks]] state no values): 1 point(s)\n"), "{table}");
    assert!(!table.contains("expected values from the file"), "{table}");
    assert!(
        table.contains(&format!("   path: accelerated ({} accelerated step(s))\n", report.accelerated_steps)),
        "{table}"
    );
    let settle = table_of(&run_file("scenarios/custom/pinned_bar_sweep.toml"));
    assert!(!settle.contains("are not shown"), "{settle}");
}
