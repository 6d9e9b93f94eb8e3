//! Analytic versus simulated, tick by tick and at the settle points.

use super::{Made, Note, Observer, SettlePoint, Setup, Tick};
use crate::mechanisms::{wrap_angle, QuantityKind};
use crate::report::{CheckReport, PointReport, ScenarioReport};
use crate::settings::Check;
use std::cmp::Ordering;

/// Error of `simulated` against `analytic` for a quantity: (absolute, normalised).
/// Lengths are normalised by `length_scale`, angles are wrapped and taken in rad, other
/// quantities are divided by |analytic| (by 1 when the analytic value is zero).
pub fn error(kind: QuantityKind, analytic: f64, simulated: f64, length_scale: f64) -> (f64, f64) {
    match kind {
        QuantityKind::Angle => {
            let e = wrap_angle(simulated - analytic).abs();
            (e, e)
        }
        QuantityKind::Length => {
            let e = (simulated - analytic).abs();
            (e, e / length_scale)
        }
        QuantityKind::Magnitude => {
            let e = (simulated - analytic).abs();
            let scale = if analytic != 0.0 { analytic.abs() } else { 1.0 };
            (e, e / scale)
        }
    }
}

/// How a check's error is measured (see [`error`]).
pub fn convention(kind: QuantityKind) -> &'static str {
    match kind {
        QuantityKind::Angle => "angle [rad]",
        QuantityKind::Length => "length / L",
        QuantityKind::Magnitude => "relative",
    }
}

/// The root mean square of `ticks` values whose squares sum to `sum_sq` (0 without ticks).
fn rms(sum_sq: f64, ticks: u64) -> f64 {
    if ticks > 0 {
        (sum_sq / ticks as f64).sqrt()
    } else {
        0.0
    }
}

#[derive(Clone, Debug)]
struct Accumulator {
    check: Check,
    settled_max_abs: f64,
    settled_max_rel: f64,
    settled_points: usize,
    transient_max_abs: f64,
    transient_sum_sq: f64,
    transient_max_rel: f64,
    transient_sum_sq_rel: f64,
    ticks: u64,
    missing: bool,
    /// Settle points outside the analytic model's validity (not compared).
    outside_points: usize,
}

/// The comparison observer: accumulates errors per checked quantity.
pub struct Compare {
    acc: Vec<Accumulator>,
    length_scale: f64,
}

impl Compare {
    pub fn new(checks: &[Check], length_scale: f64) -> Self {
        Compare {
            acc: checks
                .iter()
                .map(|c| Accumulator {
                    check: c.clone(),
                    settled_max_abs: 0.0,
                    settled_max_rel: 0.0,
                    settled_points: 0,
                    transient_max_abs: 0.0,
                    transient_sum_sq: 0.0,
                    transient_max_rel: 0.0,
                    transient_sum_sq_rel: 0.0,
                    ticks: 0,
                    missing: false,
                    outside_points: 0,
                })
                .collect(),
            length_scale,
        }
    }

    /// Records the errors at a settle point (settled or not: an unsettled point fails).
    fn record_point(
        &mut self,
        analytic: &crate::mechanisms::Values,
        simulated: &crate::mechanisms::Values,
        settled: bool,
    ) {
        for a in &mut self.acc {
            match (analytic.get(&a.check.quantity), simulated.get(&a.check.quantity)) {
                (Some(&x), Some(&y)) => {
                    let (abs, rel) = error(a.check.kind, x, y, self.length_scale);
                    let (abs, rel) =
                        if settled && abs.is_finite() { (abs, rel) } else { (f64::INFINITY, f64::INFINITY) };
                    a.settled_max_abs = a.settled_max_abs.max(abs);
                    a.settled_max_rel = a.settled_max_rel.max(rel);
                    a.settled_points += 1;
                }
                _ => a.missing = true,
            }
        }
    }

    /// Every check's normalised error at one point (a missing value: infinite).
    fn point_errors(&self, p: &PointReport) -> Vec<(&Check, f64)> {
        self.acc
            .iter()
            .map(|a| {
                let e = match (p.analytic.get(&a.check.quantity), p.simulated.get(&a.check.quantity)) {
                    (Some(x), Some(y)) => error(a.check.kind, *x, *y, self.length_scale).1,
                    _ => f64::INFINITY,
                };
                (&a.check, e)
            })
            .collect()
    }

    pub fn reports(&self) -> Vec<CheckReport> {
        self.acc
            .iter()
            .map(|a| CheckReport {
                quantity: a.check.quantity.clone(),
                unit: a.check.unit.clone(),
                convention: convention(a.check.kind).into(),
                max_abs_error: a.settled_max_abs,
                max_rel_error: a.settled_max_rel,
                tolerance: a.check.tolerance,
                // A check passes when every compared point is within tolerance; a run whose
                // points all lie outside the model's validity has nothing to compare.
                passed: !a.missing
                    && if a.settled_points > 0 { a.settled_max_rel <= a.check.tolerance } else { a.outside_points > 0 },
                points_compared: a.settled_points,
                transient_max_abs_error: a.transient_max_abs,
                transient_rms_abs_error: rms(a.transient_sum_sq, a.ticks),
                transient_max_rel_error: a.transient_max_rel,
                transient_rms_rel_error: rms(a.transient_sum_sq_rel, a.ticks),
                ticks_compared: a.ticks,
            })
            .collect()
    }
}

/// Every run compares the analytic model with the simulation (`observers::KINDS`).
pub(super) fn make(setup: &Setup, _warnings: &mut Vec<String>) -> Made {
    Ok(Some(Box::new(Compare::new(setup.checks, setup.length_scale_m))))
}

impl Observer for Compare {
    fn tick(&mut self, t: &Tick, _notes: &mut Vec<Note>) {
        for a in &mut self.acc {
            if let (Some(&x), Some(&y)) =
                (t.prediction.expected.get(&a.check.quantity), t.simulated.get(&a.check.quantity))
            {
                let (abs, rel) = error(a.check.kind, x, y, self.length_scale);
                a.transient_max_abs = a.transient_max_abs.max(abs);
                a.transient_sum_sq += abs * abs;
                a.transient_max_rel = a.transient_max_rel.max(rel);
                a.transient_sum_sq_rel += rel * rel;
                a.ticks += 1;
            }
        }
    }

    /// Outside the analytic model's validity (a cable it predicts slack) the point is counted
    /// but not compared; elsewhere every check's error is recorded, and the point is within
    /// tolerance when it settled and every check passes there.
    fn settle_point(&mut self, p: &SettlePoint, point: &mut PointReport, notes: &mut Vec<Note>) {
        if p.outside_model {
            self.acc.iter_mut().for_each(|a| a.outside_points += 1);
            point.within_tolerance = false;
            return;
        }
        self.record_point(&point.analytic, &point.simulated, point.settled);
        let errors = self.point_errors(point);
        point.errors.extend(errors.iter().map(|(c, e)| (c.quantity.clone(), *e)));
        if point.settled {
            for (c, e) in errors.iter().filter(|(c, e)| e.partial_cmp(&c.tolerance).is_none_or(Ordering::is_gt)) {
                notes.push(Note::Event(format!(
                    "point {}: check {} failed: error {e:.3e} > tolerance {:.1e}",
                    point.index, c.quantity, c.tolerance
                )));
            }
        }
        let within = point.settled && errors.iter().all(|(c, e)| *e <= c.tolerance);
        point.within_tolerance = within;
    }

    fn finish(&mut self, report: &mut ScenarioReport) {
        report.checks = self.reports();
    }
}
