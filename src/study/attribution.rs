//! What each idealization costs a paper's model (`tensegrity attribute`): the file's checks run
//! under the ideal structure, under each `[[fidelity]]` relaxation alone, and under all of them
//! together. For every compared value (a check at a point, a file model's check, a measured
//! frequency) the deviation of the simulation from the model at each level, each relaxation's
//! share of the change and what is left over, the interaction:
//!
//! d_all - d_ideal = sum_r (d_r - d_base(r)) + interaction,
//!
//! d_r the deviation with r applied (on top of its base: a heavy cable's "inextensible cables"
//! relaxation, `structure::fidelity::with_base`), d_base(r) the deviation with its base alone
//! (the ideal's where it has none). The shares add up by construction; the interaction is
//! where the relaxations do not add.

use crate::report::ScenarioReport;
use crate::run::{run, RunOptions};
use crate::scenario::Scenario;
use crate::structure::fidelity::{self, Relaxation};
use serde::Serialize;
use std::sync::atomic::AtomicBool;

/// One level of fidelity run: which relaxations it applies and how its run went.
#[derive(Clone, Debug, Serialize)]
pub struct Level {
    /// "ideal", a relaxation's name, or "all".
    pub name: String,
    /// The relaxations applied, by name.
    pub relaxed: Vec<String>,
    /// Whether the run passed its own checks (the ideal's tolerances: a relaxed run is
    /// expected to fail them by what the relaxations cost).
    pub passed: bool,
    /// Whether the run did what the file's `[expect]` says (the ideal level's verdict; a
    /// relaxed level is not expected to).
    pub as_expected: Option<bool>,
    /// Why the run stopped, if it did.
    pub error: Option<String>,
    /// The settle points that did not settle (their values are NaN at this level).
    pub unsettled: Vec<usize>,
    pub wall_s: f64,
}

/// A relaxation as the report states it: the file's, with what it is measured on top of and
/// what it relaxes.
#[derive(Clone, Debug, Serialize)]
pub struct RelaxationReport {
    #[serde(flatten)]
    pub relaxation: Relaxation,
    /// The relaxations its share is measured on top of (by name).
    pub on_top_of: Vec<String>,
    /// The members it relaxes in the first point's structure (none: the assumption holds for
    /// no member there, and its share is zero).
    pub relaxes: Vec<String>,
}

/// One compared value across the levels.
#[derive(Clone, Debug, Serialize)]
pub struct Item {
    /// "check" (a quantity at a settle point), "frequency" (a motion's measured frequency) or
    /// the file model's check kind ("prediction", "equation", "energy", "frequency model").
    pub kind: String,
    pub name: String,
    /// The settle point (None: the run's largest error, or a motion's frequency).
    pub point: Option<usize>,
    /// The point's inputs (and swept parameters), where it is a point's.
    pub inputs: crate::mechanisms::Values,
    /// The model's value (NaN where the report gives an error only).
    pub model: f64,
    /// The deviation from the model at each level, in [`AttributionReport::levels`]' order:
    /// simulated - model (signed; an angle wrapped), or the largest error where only that is
    /// reported.
    pub deviation: Vec<f64>,
    /// Each relaxation's share of d_all - d_ideal, in [`AttributionReport::relaxations`]' order.
    pub shares: Vec<f64>,
    /// d_all - d_ideal - sum of the shares.
    pub interaction: f64,
}

/// `tensegrity attribute`'s report.
#[derive(Clone, Debug, Serialize)]
pub struct AttributionReport {
    pub scenario: String,
    pub file: String,
    pub relaxations: Vec<RelaxationReport>,
    pub levels: Vec<Level>,
    pub items: Vec<Item>,
}

/// Why attribution cannot run.
#[derive(Debug, thiserror::Error)]
pub enum AttributionError {
    #[error("the scenario has no [[fidelity]] relaxation: list the idealizations to relax, each with its data")]
    NoRelaxation,
    /// The scenario read again with a level's parameter values is refused.
    #[error("level '{level}': {error}")]
    Level { level: String, error: crate::scenario::ScenarioError },
    #[error("stopped by a signal")]
    Cancelled,
}

/// The sets of relaxations each level applies (indices into `sc.fidelity`): the ideal, each
/// relaxation with its base, and all of them (left out where it repeats the one before).
pub fn level_sets(sc: &Scenario) -> Vec<(String, Vec<usize>)> {
    let list = &sc.fidelity;
    let mut sets = vec![("ideal".to_string(), Vec::new())];
    sets.extend((0..list.len()).map(|i| (list[i].name.clone(), fidelity::with_base(list, i))));
    // Each share's base (its set less itself), where no level above applies it alone.
    for i in 0..list.len() {
        let base: Vec<usize> = sets[i + 1].1.iter().copied().filter(|&j| j != i).collect();
        if !base.is_empty() && !sets.iter().any(|(_, s)| *s == base) {
            sets.push((format!("base of {}", list[i].name), base));
        }
    }
    let all: Vec<usize> = (0..list.len()).collect();
    if !sets.iter().any(|(_, s)| *s == all) {
        sets.push(("all".to_string(), all));
    }
    sets
}

/// Runs `sc` at every level and attributes each compared value's change.
pub fn attribute(sc: &Scenario, cancel: Option<&AtomicBool>) -> Result<AttributionReport, AttributionError> {
    if sc.fidelity.is_empty() {
        return Err(AttributionError::NoRelaxation);
    }
    let sets = level_sets(sc);
    let mut reports = Vec::new();
    let mut levels = Vec::new();
    for (name, set) in &sets {
        let wall = std::time::Instant::now();
        let level = level_scenario(sc, set).map_err(|error| AttributionError::Level { level: name.clone(), error })?;
        let report = run(&level, &RunOptions { cancel, skip_findings: true, ..RunOptions::default() });
        if cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
            return Err(AttributionError::Cancelled);
        }
        let relaxed = set.iter().map(|&i| sc.fidelity[i].name.clone()).collect();
        let error = report.error.as_ref().map(|e| e.to_string());
        levels.push(Level {
            name: name.clone(),
            relaxed,
            passed: report.passed,
            as_expected: report.as_expected,
            error,
            unsettled: report.points.iter().filter(|p| !p.settled).map(|p| p.index).collect(),
            wall_s: wall.elapsed().as_secs_f64(),
        });
        reports.push(report);
    }
    let items =
        compared(sc, &reports[0]).into_iter().map(|(key, model)| item(sc, &sets, &reports, key, model)).collect();
    Ok(AttributionReport {
        scenario: sc.name.clone(),
        file: sc.file.display().to_string(),
        relaxations: relaxation_reports(sc, &sets),
        levels,
        items,
    })
}

/// `sc` at the level that applies `set`: read again with its parameter values (as `--set`
/// sets them, after the file's own flags) where it has any, then with its structural
/// relaxations.
fn level_scenario(sc: &Scenario, set: &[usize]) -> Result<Scenario, crate::scenario::ScenarioError> {
    let params: Vec<(String, f64)> =
        set.iter().flat_map(|&i| sc.fidelity[i].params.iter().map(|(k, v)| (k.clone(), *v))).collect();
    if params.is_empty() {
        return Ok(sc.relaxed_by(set));
    }
    let mut overrides = sc.overrides.clone();
    overrides.extend(
        params
            .iter()
            .map(|(name, value)| crate::scenario::Override { name: name.clone(), value: format!("{value:e}") }),
    );
    Ok(crate::scenario::parse_with(&sc.file, &sc.source, &overrides)?.relaxed_by(set))
}

/// What a compared value is, to find it in every level's report.
#[derive(Clone, Debug, PartialEq)]
enum Key {
    /// A check's quantity at a settle point.
    Check { quantity: String, point: usize },
    /// A file model's check (its largest error over the run).
    ModelCheck { kind: String, name: String },
    /// A motion's measured frequency against its prediction.
    Frequency { name: String },
}

/// Every compared value of the ideal run, with the model's value.
fn compared(sc: &Scenario, ideal: &ScenarioReport) -> Vec<(Key, f64)> {
    let mut out = Vec::new();
    for p in &ideal.points {
        for c in &sc.checks {
            let model = p.analytic.get(&c.quantity).copied().unwrap_or(f64::NAN);
            out.push((Key::Check { quantity: c.quantity.clone(), point: p.index }, model));
        }
    }
    for m in &ideal.model_checks {
        out.push((Key::ModelCheck { kind: m.kind.clone(), name: m.name.clone() }, f64::NAN));
    }
    for f in ideal.motion.iter().flat_map(|m| &m.frequencies) {
        out.push((Key::Frequency { name: f.name.clone() }, f.predicted_rad_per_s));
    }
    out
}

/// The deviation of `key` in `report` from the model's `model` (NaN where the run has none).
fn deviation(sc: &Scenario, report: &ScenarioReport, key: &Key, model: f64) -> f64 {
    match key {
        Key::Check { quantity, point } => {
            let p = report.points.iter().find(|p| p.index == *point);
            let simulated = p.filter(|p| p.settled).and_then(|p| p.simulated.get(quantity)).copied();
            let d = simulated.map_or(f64::NAN, |s| s - model);
            if sc.is_angle(quantity) {
                crate::mechanisms::wrap_angle(d)
            } else {
                d
            }
        }
        Key::ModelCheck { kind, name } => {
            report.model_checks.iter().find(|m| m.kind == *kind && m.name == *name).map_or(f64::NAN, |m| m.max_error)
        }
        Key::Frequency { name } => report
            .motion
            .iter()
            .flat_map(|m| &m.frequencies)
            .find(|f| f.name == *name)
            .map_or(f64::NAN, |f| f.corrected_rad_per_s - model),
    }
}

/// One compared value across the levels: its deviations, shares and interaction.
fn item(sc: &Scenario, sets: &[(String, Vec<usize>)], reports: &[ScenarioReport], key: Key, model: f64) -> Item {
    let deviation: Vec<f64> = reports.iter().map(|r| deviation(sc, r, &key, model)).collect();
    let at = |set: &[usize]| sets.iter().position(|(_, s)| s == set).map_or(f64::NAN, |l| deviation[l]);
    let shares: Vec<f64> = (0..sc.fidelity.len())
        .map(|i| {
            let with = &sets[i + 1].1;
            let base: Vec<usize> = with.iter().copied().filter(|&j| j != i).collect();
            at(with) - at(&base)
        })
        .collect();
    let all: Vec<usize> = (0..sc.fidelity.len()).collect();
    let interaction = at(&all) - deviation[0] - shares.iter().sum::<f64>();
    let (kind, name, point) = match key {
        Key::Check { quantity, point } => ("check".to_string(), quantity, Some(point)),
        Key::ModelCheck { kind, name } => (kind, name, None),
        Key::Frequency { name } => ("frequency".to_string(), name, None),
    };
    let at_point = point.and_then(|p| reports[0].points.iter().find(|q| q.index == p));
    let inputs = at_point.map(|p| p.inputs.clone()).unwrap_or_default();
    Item { kind, name, point, inputs, model, deviation, shares, interaction }
}

/// The report's statement of each relaxation, with the relaxations it is measured on top of.
fn relaxation_reports(sc: &Scenario, sets: &[(String, Vec<usize>)]) -> Vec<RelaxationReport> {
    let inputs = sc.actuation.first_inputs();
    let first = sc.mechanism().build(&sc.params_at(inputs), inputs, &sc.start).ok();
    sc.fidelity
        .iter()
        .enumerate()
        .map(|(i, r)| RelaxationReport {
            relaxation: r.clone(),
            on_top_of: sets[i + 1].1.iter().filter(|&&j| j != i).map(|&j| sc.fidelity[j].name.clone()).collect(),
            relaxes: first.as_ref().map_or(Vec::new(), |s| {
                fidelity::members_of(s, r).unwrap_or_default().iter().map(|&m| s.members[m].name.clone()).collect()
            }),
        })
        .collect()
}

impl AttributionReport {
    /// The level that applies every relaxation.
    pub fn all_level(&self) -> usize {
        let all = self.relaxations.len();
        self.levels.iter().position(|l| l.relaxed.len() == all).unwrap_or(self.levels.len() - 1)
    }

    /// The table: per compared value, the model, the ideal and the relaxed deviation, each
    /// relaxation's share and the interaction.
    pub fn to_table(&self) -> String {
        let mut out = format!("{} ({})\n", self.scenario, self.file);
        for report in &self.relaxations {
            let (r, on_top_of) = (&report.relaxation, &report.on_top_of);
            let on_top =
                if on_top_of.is_empty() { String::new() } else { format!(", on top of {}", on_top_of.join(", ")) };
            let members = match (r.gravity_m_per_s2, report.relaxes.is_empty()) {
                (Some(g), _) => format!("every body, g = {g:?} m/s^2"),
                (None, true) => "no member".to_string(),
                (None, false) => report.relaxes.join(", "),
            };
            out += &format!("relaxation '{}': {} ({members}){on_top}\n", r.name, r.assumption.label());
        }
        for l in &self.levels {
            let mut error = l.error.as_ref().map_or(String::new(), |e| format!(": {e}"));
            if !l.unsettled.is_empty() {
                error += &format!(" (points {:?} did not settle)", l.unsettled);
            }
            out += &format!("level {:<24} {:.3} s{error}\n", l.name, l.wall_s);
        }
        let mut header =
            format!("{:<12} {:<16} {:>5} {:>14} {:>12} {:>12}", "kind", "name", "point", "model", "ideal", "all");
        for r in &self.relaxations {
            header += &format!(" {:>14}", clip(&r.relaxation.name, 14));
        }
        out += &format!("{header} {:>12}\n", "interaction");
        for it in &self.items {
            let point = it.point.map_or("-".to_string(), |p| p.to_string());
            let mut row = format!(
                "{:<12} {:<16} {point:>5} {:>14.6e} {:>12.4e} {:>12.4e}",
                it.kind,
                clip(&it.name, 16),
                it.model,
                it.deviation[0],
                it.deviation[self.all_level()]
            );
            for s in &it.shares {
                row += &format!(" {s:>14.4e}");
            }
            out += &format!("{row} {:>12.4e}\n", it.interaction);
        }
        out + "deviation = simulated - model at each level; the shares and the interaction add up to all - ideal\n"
    }

    /// One row per compared value (a grid's shares per point, with the point's inputs).
    pub fn to_csv(&self) -> String {
        let inputs: std::collections::BTreeSet<&String> = self.items.iter().flat_map(|it| it.inputs.keys()).collect();
        let mut header = "kind,name,point".to_string();
        for k in &inputs {
            header += &format!(",{}", csv_field(k));
        }
        header += ",model";
        for l in &self.levels {
            header += &format!(",deviation:{}", csv_field(&l.name));
        }
        for r in &self.relaxations {
            header += &format!(",share:{}", csv_field(&r.relaxation.name));
        }
        let mut out = header + ",interaction\n";
        for it in &self.items {
            let point = it.point.map_or(String::new(), |p| p.to_string());
            out += &format!("{},{},{point}", it.kind, csv_field(&it.name));
            for k in &inputs {
                out += &it.inputs.get(*k).map_or(",".to_string(), |v| format!(",{v:e}"));
            }
            out += &format!(",{:e}", it.model);
            for v in it.deviation.iter().chain(&it.shares) {
                out += &format!(",{v:e}");
            }
            out += &format!(",{:e}\n", it.interaction);
        }
        out
    }
}

fn clip(s: &str, n: usize) -> String {
    s.chars().take(n).collect()
}

/// A CSV field quoted where it holds a comma or a quote.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
