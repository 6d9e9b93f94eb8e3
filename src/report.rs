//! Reports: a readable table on stdout, one JSON document for machines, and the exit code
//! (0 every check passed, 1 a check failed, 2 bad input).

use crate::mechanisms::{Finding, Values};
use serde::Serialize;

pub const EXIT_PASS: i32 = 0;
pub const EXIT_FAIL: i32 = 1;
pub const EXIT_BAD_INPUT: i32 = 2;

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Report {
    pub scenarios: Vec<ScenarioReport>,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ScenarioReport {
    pub name: String,
    pub file: String,
    pub mechanism: String,
    pub passed: bool,
    pub params: Values,
    pub settle: SettleSummary,
    pub checks: Vec<CheckReport>,
    pub points: Vec<PointReport>,
    pub stiffness_probe: Option<ProbeReport>,
    pub findings: Vec<FindingReport>,
    /// Why the run stopped early (divergence, interruption), if it did.
    pub error: Option<String>,
}

#[derive(Clone, Debug, Serialize, PartialEq, Default)]
pub struct SettleSummary {
    /// Every settle point settled (velocity window and residual check both met).
    pub settled: bool,
    pub steps: u64,
    pub sim_time_s: f64,
    pub wall_s: f64,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct CheckReport {
    pub quantity: String,
    pub unit: String,
    /// Largest error at the settle points, in the quantity's unit.
    pub max_abs_error: f64,
    /// Largest normalised error at the settle points (lengths / L, angles in rad, other
    /// quantities / |analytic|): what the tolerance applies to.
    pub max_rel_error: f64,
    pub tolerance: f64,
    pub passed: bool,
    /// Every tick, including transients (reported, not checked).
    pub transient_max_abs_error: f64,
    pub transient_rms_abs_error: f64,
    pub ticks_compared: u64,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PointReport {
    pub index: usize,
    pub inputs: Values,
    pub analytic: Values,
    pub simulated: Values,
    pub settled: bool,
    pub steps: u64,
    pub residual_force_n: f64,
    pub residual_torque_nm: f64,
    /// Speed at the last tick of the settle [m/s].
    pub final_speed_m_per_s: f64,
    /// The analytic branch the dynamics landed on.
    pub branch: String,
    /// Stability from the perturbation test (None when not tested).
    pub stable: Option<bool>,
    /// Stability from the analytic model (sign of the stiffness) for the branch landed on.
    pub analytic_stable: Option<bool>,
    pub slack_cables: Vec<String>,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ProbeReport {
    pub torque_nm: f64,
    pub tolerance: f64,
    pub max_rel_error: f64,
    pub passed: bool,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FindingReport {
    pub equation: String,
    pub claim: String,
    pub measured: String,
    pub holds: bool,
}

impl From<Finding> for FindingReport {
    fn from(f: Finding) -> Self {
        FindingReport { equation: f.equation, claim: f.claim, measured: f.measured, holds: f.holds }
    }
}

impl Report {
    pub fn passed(&self) -> bool {
        self.scenarios.iter().all(|s| s.passed)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("report serialises")
    }

    /// The human-readable table.
    pub fn to_table(&self) -> String {
        let mut out = String::new();
        for s in &self.scenarios {
            out.push_str(&format!(
                "== {} ({}) [{}]: {}\n",
                s.name,
                s.mechanism,
                s.file,
                if s.passed { "PASS" } else { "FAIL" }
            ));
            out.push_str(&format!(
                "   settle: {} point(s), all settled: {}, {} steps, {:.3} s simulated, {:.3} s wall\n",
                s.points.len(),
                s.settle.settled,
                s.settle.steps,
                s.settle.sim_time_s,
                s.settle.wall_s
            ));
            if let Some(e) = &s.error {
                out.push_str(&format!("   stopped: {e}\n"));
            }
            out.push_str(&format!(
                "   {:<10} {:>12} {:>12} {:>10} {:>12} {:>12}  {}\n",
                "quantity", "max |err|", "max rel err", "tolerance", "transient", "rms trans.", "verdict"
            ));
            for c in &s.checks {
                out.push_str(&format!(
                    "   {:<10} {:>12.3e} {:>12.3e} {:>10.1e} {:>12.3e} {:>12.3e}  {}\n",
                    c.quantity,
                    c.max_abs_error,
                    c.max_rel_error,
                    c.tolerance,
                    c.transient_max_abs_error,
                    c.transient_rms_abs_error,
                    if c.passed { "pass" } else { "FAIL" }
                ));
            }
            if let Some(p) = &s.stiffness_probe {
                out.push_str(&format!(
                    "   stiffness probe (+-{} N m): max rel err {:.3e} (tolerance {:.1e}) {}\n",
                    p.torque_nm,
                    p.max_rel_error,
                    p.tolerance,
                    if p.passed { "pass" } else { "FAIL" }
                ));
            }
            let unstable = s.points.iter().filter(|p| p.stable == Some(false)).count();
            let tested = s.points.iter().filter(|p| p.stable.is_some()).count();
            let disagree = s
                .points
                .iter()
                .filter(|p| p.stable.is_some() && p.analytic_stable.is_some() && p.stable != p.analytic_stable)
                .count();
            if tested > 0 {
                out.push_str(&format!(
                    "   stability: {tested} point(s) perturbed, {unstable} unstable, {disagree} disagree with the analytic sign of K\n"
                ));
            }
            let mut branches: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
            for p in &s.points {
                *branches.entry(p.branch.as_str()).or_default() += 1;
            }
            for (b, n) in &branches {
                out.push_str(&format!("   landed on: {b}: {n} point(s)\n"));
            }
            let shown = s.points.len().min(MAX_POINTS_IN_TABLE);
            for p in &s.points[..shown] {
                out.push_str(&format!(
                    "   point {:>4}: {}  -> {}  [{}{}]\n",
                    p.index,
                    fmt_values(&p.inputs),
                    fmt_errors(&p.analytic, &p.simulated),
                    p.branch,
                    if p.settled { "" } else { ", NOT SETTLED" }
                ));
            }
            if s.points.len() > shown {
                out.push_str(&format!("   ... {} more point(s) in the JSON report\n", s.points.len() - shown));
            }
            let wrong: Vec<_> = s.findings.iter().filter(|f| !f.holds).collect();
            if !s.findings.is_empty() {
                out.push_str(&format!(
                    "   findings: {} printed equation(s) checked, {} do not hold as printed:\n",
                    s.findings.len(),
                    wrong.len()
                ));
                for f in wrong {
                    out.push_str(&format!("     - {}: {} ({})\n", f.equation, f.claim, f.measured));
                }
            }
        }
        out
    }
}

/// Points listed in the table; the JSON has them all.
const MAX_POINTS_IN_TABLE: usize = 12;

fn fmt_values(v: &Values) -> String {
    v.iter().map(|(k, x)| format!("{k}={x:.6}")).collect::<Vec<_>>().join(" ")
}

fn fmt_errors(analytic: &Values, simulated: &Values) -> String {
    simulated
        .iter()
        .filter_map(|(k, s)| {
            analytic.get(k).map(|a| {
                // Angles (the papers' theta symbols) are compared modulo 2 pi.
                let e = if k.starts_with("theta") { crate::mechanisms::wrap_angle(s - a) } else { s - a };
                format!("{k}={s:.9} (err {:.1e})", e.abs())
            })
        })
        .collect::<Vec<_>>()
        .join(" ")
}
