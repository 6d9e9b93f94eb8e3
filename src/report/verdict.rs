//! The verdict, in one place: its parts ([`Failure`]), what a scenario declares of them
//! ([`Expectation`]), and the pass policy: which parts of a run's verdict failed ([`failures`]), whether
//! it passed, and whether that is what the scenario's `[expect]` declares.
//!
//! A run passes when [`failures`] is empty. Each failure is named the way a scenario file
//! names it in `[expect] failing`, so a deliberate demonstration of a failure (two struts
//! through each other, a model that does not hold) declares exactly which part must fail.

use super::{PointReport, ScenarioReport};
use std::cmp::Ordering;
use std::fmt;

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
        if w.agreement_percent.partial_cmp(&min).is_none_or(Ordering::is_lt) {
            out.push(Failure::Workspace);
        }
    } else {
        // A motion run needs no settle: only one that starts from the settled state fails
        // when that settle does.
        let needs_settle = report.motion.as_ref().is_none_or(|m| m.start == crate::settings::MotionStart::Settled);
        if needs_settle && !report.settle.settled {
            out.push(Failure::Settle);
        }
        if let Some(m) = &report.motion {
            out.extend(m.frequencies.iter().filter(|f| !f.passed).map(|f| Failure::Frequency(f.name.clone())));
            let lagrangian = m.lagrangian.iter().flat_map(|l| &l.coordinates);
            out.extend(lagrangian.filter(|c| !c.passed).map(|c| Failure::Trajectory(c.name.clone())));
        }
        out.extend(report.checks.iter().filter(|c| !c.passed).map(|c| Failure::Check(c.quantity.clone())));
        out.extend(report.model_checks.iter().filter(|c| !c.passed).map(|c| c.failure()));
        if report.stiffness_probe.as_ref().is_some_and(|p| !p.passed) {
            out.push(Failure::Probe);
        }
        // The perturbation test must agree with the analytic stability and with the stability
        // the scenario expects (a point that did not settle fails on `settle` instead).
        let agrees = |p: &PointReport, want: Option<bool>| p.stable.is_none() || want.is_none() || p.stable == want;
        let stability_agrees =
            report.points.iter().all(|p| agrees(p, p.analytic_stable) && (!p.settled || agrees(p, p.expected_stable)));
        if !stability_agrees {
            out.push(Failure::Stability);
        }
        if report.points.iter().any(|p| p.slack_agrees == Some(false)) {
            out.push(Failure::Slack);
        }
        if report.prestress.as_ref().is_some_and(|p| !p.passed) {
            out.push(Failure::Prestress);
        }
    }
    if report.interference.as_ref().is_some_and(|i| !i.passed) {
        out.push(Failure::Interference);
    }
    out
}

/// Defines [`Failure`] from one table: each variant with its name in `[expect] failing`
/// (`NAME`, or `NAME:PLACEHOLDER` for a part named by what follows the colon), and from that
/// table alone [`FAILURE_NAMES`], `Display` and `FromStr`.
macro_rules! failures {
    ($($(#[doc = $doc:literal])* $variant:ident $(($field:ident: $placeholder:literal))? = $name:literal,)*) => {
        /// One part of a run's verdict that failed.
        #[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
        pub enum Failure {
            $($(#[doc = $doc])* $variant $((failures!(@string $field)))?,)*
        }

        /// The names a scenario may give in `[expect] failing` (a check is `check:QUANTITY`).
        pub const FAILURE_NAMES: &[&str] = &[$(concat!($name $(, ":", $placeholder)?)),*];

        impl fmt::Display for Failure {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                match self {
                    $(Failure::$variant $(($field))? => {
                        f.write_str($name)?;
                        $(write!(f, ":{}", $field)?;)?
                        Ok(())
                    })*
                }
            }
        }

        impl std::str::FromStr for Failure {
            type Err = UnknownFailure;
            fn from_str(s: &str) -> Result<Self, UnknownFailure> {
                $(failures!(@parse s, $variant, $name $(, $field)?);)*
                Err(UnknownFailure(s.to_string()))
            }
        }
    };
    (@string $field:ident) => { String };
    (@parse $s:ident, $variant:ident, $name:literal) => {
        if $s == $name {
            return Ok(Failure::$variant);
        }
    };
    (@parse $s:ident, $variant:ident, $name:literal, $field:ident) => {
        if let Some($field) = $s.strip_prefix(concat!($name, ":")).filter(|n| !n.is_empty()) {
            return Ok(Failure::$variant($field.to_string()));
        }
    };
}

failures! {
    /// The run stopped early (divergence, interruption, a model error, a panic, a recording
    /// that could not be written): `error`.
    Error = "error",
    /// A settle point did not settle within `settle.max_time`: `settle`.
    Settle = "settle",
    /// A `[[checks]]` quantity exceeded its tolerance: `check:QUANTITY`.
    Check(quantity: "QUANTITY") = "check",
    /// The stiffness probe disagreed with the analytic stiffness: `probe`.
    Probe = "probe",
    /// The perturbation test disagreed with the analytic stability: `stability`.
    Stability = "stability",
    /// The slack cables differ from the analytic model's: `slack`.
    Slack = "slack",
    /// The structure lost its self-stress (every cable slack, or below `[prestress]
    /// min_fraction` of the drawn tension) where `[prestress] on_loss` fails: `prestress`.
    Prestress = "prestress",
    /// Two members came closer than the interference threshold: `interference`.
    Interference = "interference",
    /// A workspace sweep's agreement fell below `workspace.min_agreement_percent`: `workspace`.
    Workspace = "workspace",
    /// A `[[predictions]]` entry of the file's model exceeded its tolerance: `prediction:NAME`.
    Prediction(name: "NAME") = "prediction",
    /// A `[[equations]]` residual exceeded its tolerance: `equation:NAME`.
    Equation(name: "NAME") = "equation",
    /// The dynamics settled away from the `[energy]` model's minima: `energy`.
    Energy = "energy",
    /// A frequency prediction failed: a `[[energy.frequencies]]` one against the dynamic
    /// model's natural frequency, or a `[[motion.frequencies]]` one against the frequency
    /// measured from a motion run: `frequency:NAME`.
    Frequency(name: "NAME") = "frequency",
    /// A coordinate of the `[energy]` model strayed from its Lagrangian trajectory
    /// (`[energy.trajectory]`) in a motion run: `trajectory:COORDINATE`.
    Trajectory(coordinate: "COORDINATE") = "trajectory",
}

/// A name in `[expect] failing` that names no [`Failure`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown failure '{0}' (expected one of: {names})", names = FAILURE_NAMES.join(", "))]
pub struct UnknownFailure(pub String);

impl serde::Serialize for Failure {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// What a scenario declares it must do: pass, or fail in exactly these parts.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Expectation {
    /// Empty: the run must pass. Otherwise the run must fail in these parts and no other.
    pub failing: Vec<Failure>,
}

impl Expectation {
    pub const PASS: Expectation = Expectation { failing: Vec::new() };

    /// Whether a run that failed in `failures` did what was declared (the order is free).
    pub fn met_by(&self, failures: &[Failure]) -> bool {
        let mut want = self.failing.clone();
        want.sort();
        want.dedup();
        let mut got = failures.to_vec();
        got.sort();
        got.dedup();
        want == got
    }
}
