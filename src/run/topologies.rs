//! A sweep over a parameter that changes the structure's topology (a pattern's range, an
//! n-strut prism for n = 3..12), or a motion run over several points (one motion from each
//! point): each part's scenario runs on its own, with its own structure, and the reports join
//! into one. Checks, predictions and measured frequencies of the same name join by their worst
//! error; each point keeps its own values (a motion's frequencies among them).

use super::{conclude, run, RunError, RunOptions};
use crate::observers::table::TableTarget;
use crate::report::{
    CheckReport, FrequencyReport, LagrangianCoordinateReport, ModelCheckReport, MotionReport, PrestressReport,
    ScenarioReport,
};
use crate::scenario::Scenario;
use crate::structure::MemberKind;
use std::path::{Path, PathBuf};

/// Runs every topology of `sc` and joins the reports.
pub(super) fn run_topologies(sc: &Scenario, opts: &RunOptions) -> ScenarioReport {
    let mut joined: Option<ScenarioReport> = None;
    let mut rebuilt_at = Vec::new();
    for (k, variant) in sc.topologies.iter().enumerate() {
        let part = if sc.motion.is_some() { "point" } else { "topology" };
        let record = opts.record.clone().or_else(|| sc.record.clone()).map(|p| numbered(&p, part, k));
        let options = RunOptions {
            record,
            cancel: opts.cancel,
            connect: opts.connect.clone(),
            record_every: opts.record_every,
            skip_findings: opts.skip_findings || k > 0,
            // A file per structure; a table in memory keeps the last structure's ticks.
            table: opts.table.as_ref().map(|t| match t {
                TableTarget::File(p) => TableTarget::File(numbered(p, part, k)),
                other => other.clone(),
            }),
            external: opts.external.clone(),
            bare: opts.bare,
            certify: opts.certify,
        };
        let mut r = run(variant, &options);
        let note = rebuilt(sc, variant);
        rebuilt_at.push(format!("{note} ({} point(s))", variant.actuation.all_inputs().len()));
        r.error = r.error.map(|source| RunError::Topology { note: note.clone(), source }.into());
        let stop = r.error.is_some();
        joined = Some(match joined {
            None => r,
            Some(mut j) => {
                join(&mut j, r);
                j
            }
        });
        if stop {
            break;
        }
    }
    let mut report = joined.expect("a topology sweep or a motion over points has at least two parts");
    report.params = sc.params.clone();
    report.topologies = rebuilt_at;
    conclude(&mut report, sc);
    report
}

/// What a topology's run says of itself: the parameters that rebuilt the structure (a motion
/// over points: the point it started from).
pub fn rebuilt(sc: &Scenario, variant: &Scenario) -> String {
    let first = variant.actuation.first_inputs();
    if sc.motion.is_some() {
        let values: Vec<String> = first.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        return format!("motion from the point {}", if values.is_empty() { "{}".into() } else { values.join(", ") });
    }
    let params = variant.params_at(first);
    let values: Vec<String> =
        sc.topology_params.iter().map(|k| format!("{k} = {}", params.get(k).copied().unwrap_or(f64::NAN))).collect();
    let size = match &variant.custom {
        Some(c) => {
            let s = &c.structure;
            format!(
                ": {} bodies, {} nodes, {} struts, {} cables, {} springs, {} joints",
                s.bodies.len(),
                s.nodes.len(),
                s.count_of(MemberKind::Strut),
                s.count_of(MemberKind::Cable),
                s.count_of(MemberKind::Spring),
                s.joints.len()
            )
        }
        None => String::new(),
    };
    format!("structure rebuilt at {}{size}", values.join(", "))
}

/// `path` with the part's number before its extension (`run.rrd` -> `run.topology2.rrd`, or
/// `run.point2.rrd` for a motion over points).
fn numbered(path: &Path, part: &str, k: usize) -> PathBuf {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let name = match path.extension() {
        Some(ext) => format!("{stem}.{part}{k}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{part}{k}"),
    };
    path.with_file_name(name)
}

/// Adds a later topology's report to the joined one.
fn join(j: &mut ScenarioReport, r: ScenarioReport) {
    let offset = j.points.len();
    j.points.extend(r.points.into_iter().map(|mut p| {
        p.index += offset;
        p
    }));
    for c in r.checks {
        match j.checks.iter_mut().find(|x| x.quantity == c.quantity) {
            Some(x) => join_check(x, &c),
            None => j.checks.push(c),
        }
    }
    for m in r.model_checks {
        match j.model_checks.iter_mut().find(|x| x.kind == m.kind && x.name == m.name) {
            Some(x) => join_model_check(x, &m),
            None => j.model_checks.push(m),
        }
    }
    j.prestress = match (j.prestress.take(), r.prestress) {
        (Some(mut x), Some(p)) => {
            join_prestress(&mut x, p, offset);
            Some(x)
        }
        (x, p) => x.or(p),
    };
    j.motion = match (j.motion.take(), r.motion) {
        (Some(mut x), Some(m)) => {
            join_motion(&mut x, m);
            Some(x)
        }
        (x, m) => x.or(m),
    };
    j.slack_intervals.extend(r.slack_intervals);
    j.skipped_points += r.skipped_points;
    j.accelerated_steps += r.accelerated_steps;
    j.settle.settled &= r.settle.settled;
    j.settle.steps += r.settle.steps;
    j.settle.sim_time_s += r.settle.sim_time_s;
    j.settle.wall_s += r.settle.wall_s;
    j.error = j.error.take().or(r.error);
    j.warnings.extend(r.warnings);
}

/// A later point's motion added: each frequency and each coordinate against the Lagrangian
/// model keeps its worst error (the point's own values stay in its point report), the steps
/// add up, the estimate of the simulation's own error keeps its largest.
fn join_motion(x: &mut MotionReport, m: MotionReport) {
    x.steps += m.steps;
    x.steps_taken += m.steps_taken;
    x.accelerated_steps += m.accelerated_steps;
    let frequency = |f: &FrequencyReport| (f.name.clone(), f.error, f.passed);
    join_worst(&mut x.frequencies, m.frequencies, frequency, |f, passed| f.passed = passed);
    if let (Some(xl), Some(ml)) = (x.lagrangian.as_mut(), m.lagrangian) {
        let coordinate = |c: &LagrangianCoordinateReport| (c.name.clone(), c.max_error, c.passed);
        join_worst(&mut xl.coordinates, ml.coordinates, coordinate, |c, passed| c.passed = passed);
    }
    if let (Some(xe), Some(me)) = (x.extrapolation.as_mut(), m.extrapolation) {
        for (q, e) in me.largest_estimate {
            let v = xe.largest_estimate.entry(q).or_insert(e);
            *v = v.max(e);
        }
        xe.not_smooth_from_tick = xe.not_smooth_from_tick.or(me.not_smooth_from_tick);
        xe.amplitude_m = xe.amplitude_m.max(me.amplitude_m);
        xe.target_met &= me.target_met;
    }
}

/// Each entry of `later` joined into `joined` by name (`key`: its name, error and whether it
/// passed): a new name is added; a known one is replaced by the later part's where that is
/// [`worse`] or failed, passing only if both passed (`set_passed`).
fn join_worst<T>(
    joined: &mut Vec<T>,
    later: Vec<T>,
    key: impl Fn(&T) -> (String, f64, bool),
    set_passed: impl Fn(&mut T, bool),
) {
    for mut entry in later {
        let (name, error, passed) = key(&entry);
        match joined.iter_mut().find(|y| key(y).0 == name) {
            Some(y) => {
                let (_, old, was) = key(y);
                if worse(error, old) || !passed {
                    set_passed(&mut entry, was && passed);
                    *y = entry;
                }
            }
            None => joined.push(entry),
        }
    }
}

/// Whether a later part's error `new` is worse than the joined `old`: larger, or either NaN
/// (a NaN error is never hidden behind a number).
fn worse(new: f64, old: f64) -> bool {
    old.partial_cmp(&new).is_none_or(std::cmp::Ordering::is_lt)
}

fn join_check(x: &mut CheckReport, c: &CheckReport) {
    x.max_abs_error = x.max_abs_error.max(c.max_abs_error);
    x.max_rel_error = x.max_rel_error.max(c.max_rel_error);
    x.passed &= c.passed;
    x.transient_max_abs_error = x.transient_max_abs_error.max(c.transient_max_abs_error);
    x.transient_rms_abs_error = x.transient_rms_abs_error.max(c.transient_rms_abs_error);
    x.ticks_compared += c.ticks_compared;
    x.points_compared += c.points_compared;
}

fn join_model_check(x: &mut ModelCheckReport, c: &ModelCheckReport) {
    x.max_error = x.max_error.max(c.max_error);
    x.passed &= c.passed;
    x.points_compared += c.points_compared;
    x.transient_max_error = x.transient_max_error.max(c.transient_max_error);
    x.transient_rms_error = x.transient_rms_error.max(c.transient_rms_error);
    x.ticks_compared += c.ticks_compared;
}

/// A later structure's prestress judgement added: its lost points numbered after the earlier
/// structures' points, its slack cables named once.
fn join_prestress(x: &mut PrestressReport, p: PrestressReport, offset: usize) {
    x.least_fraction_kept = match (x.least_fraction_kept, p.least_fraction_kept) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    x.lost_at.extend(p.lost_at.into_iter().map(|i| i + offset));
    for c in p.slack_cables {
        if !x.slack_cables.contains(&c) {
            x.slack_cables.push(c);
        }
    }
    x.cables = x.cables.max(p.cables);
    x.passed &= p.passed;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn judged(lost_at: Vec<usize>, slack: &[&str], least: f64) -> PrestressReport {
        PrestressReport {
            on_loss: crate::settings::OnLoss::Fail,
            min_fraction: Some(0.1),
            cables: 9,
            least_fraction_kept: Some(least),
            passed: lost_at.is_empty(),
            lost_at,
            slack_cables: slack.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// A loss in a later structure fails the joined run, at that structure's point numbered
    /// after the earlier structures' points.
    #[test]
    fn a_later_structures_lost_prestress_fails_the_joined_judgement() {
        let mut first = judged(vec![], &[], 0.87);
        join_prestress(&mut first, judged(vec![0], &["side3", "top1"], 1e-14), 4);
        assert!(!first.passed);
        assert_eq!(first.lost_at, vec![4]);
        assert_eq!(first.slack_cables, vec!["side3".to_string(), "top1".to_string()]);
        assert_eq!(first.least_fraction_kept, Some(1e-14));
    }
}
