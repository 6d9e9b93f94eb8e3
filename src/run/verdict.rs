//! The pass policy, in one place: which parts of a run's verdict failed ([`failures`]), whether
//! it passed, and whether that is what the scenario's `[expect]` declares.
//!
//! A run passes when [`failures`] is empty. Each failure is named the way a scenario file
//! names it in `[expect] failing`, so a deliberate demonstration of a failure (two struts
//! through each other, a model that does not hold) declares exactly which part must fail.

use crate::report::ScenarioReport;
use crate::scenario::Scenario;
use crate::settings::Failure;

/// Which parts of the verdict failed. A workspace sweep (`[workspace] min_agreement_percent`,
/// given here) passes on the agreement of the analytic and dynamic classifications instead of
/// on every point: settling and checks are what the classification is made of, reported per
/// point.
pub fn failures(report: &ScenarioReport, min_agreement_percent: Option<f64>) -> Vec<Failure> {
    let mut out = Vec::new();
    if report.error.is_some() {
        out.push(Failure::Error);
    }
    if let (Some(min), Some(w)) = (min_agreement_percent, &report.workspace) {
        if !(w.agreement_percent >= min) {
            out.push(Failure::Workspace);
        }
    } else {
        if !report.settle.settled {
            out.push(Failure::Settle);
        }
        out.extend(report.checks.iter().filter(|c| !c.passed).map(|c| Failure::Check(c.quantity.clone())));
        out.extend(report.model_checks.iter().filter(|c| !c.passed).map(|c| c.failure()));
        if report.stiffness_probe.as_ref().is_some_and(|p| !p.passed) {
            out.push(Failure::Probe);
        }
        // The perturbation test must agree with the analytic stability and with the stability
        // the scenario expects (a point that did not settle fails on `settle` instead).
        let agrees = |p: &crate::report::PointReport, want: Option<bool>| {
            p.stable.is_none() || want.is_none() || p.stable == want
        };
        let stability_agrees =
            report.points.iter().all(|p| agrees(p, p.analytic_stable) && (!p.settled || agrees(p, p.expected_stable)));
        if !stability_agrees {
            out.push(Failure::Stability);
        }
        if report.points.iter().any(|p| p.slack_agrees == Some(false)) {
            out.push(Failure::Slack);
        }
    }
    if report.interference.as_ref().is_some_and(|i| !i.passed) {
        out.push(Failure::Interference);
    }
    out
}

/// The verdict of a finished report: its failures (the one pass policy, [`failures`]),
/// whether it passed, and whether that is what the scenario declares.
pub(super) fn conclude(report: &mut ScenarioReport, sc: &Scenario) {
    report.failures = failures(report, sc.min_agreement_percent);
    report.passed = report.failures.is_empty();
    report.as_expected = sc.expect.as_ref().map(|e| e.met_by(&report.failures));
}
