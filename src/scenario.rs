//! Scenario files (TOML): what to simulate, how, and what to check.
//!
//! Every error names the file, line and column (`file.toml:LINE:COL: ...`) and says what was
//! expected. Parsing is two passes: serde for the shape (unknown keys, wrong types, missing
//! fields), then [`validate`] for the values (ranges, the mechanism's own rules).

use crate::mechanisms::{self, Mechanism, QuantityKind, Values};
use crate::sim::settle::SettleCriteria;
use crate::sim::SimSettings;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::Spanned;

#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[error("{file}:{line}:{col}: {message}")]
pub struct ScenarioError {
    pub file: String,
    pub line: usize,
    pub col: usize,
    pub message: String,
}

type SpannedMap = BTreeMap<Spanned<String>, Spanned<f64>>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawScenario {
    pub name: Spanned<String>,
    #[serde(default)]
    pub description: String,
    pub mechanism: Spanned<String>,
    #[serde(default)]
    pub params: SpannedMap,
    #[serde(default)]
    pub sim: RawSim,
    #[serde(default)]
    pub settle: RawSettle,
    #[serde(default)]
    pub start: SpannedMap,
    pub actuation: Spanned<RawActuation>,
    #[serde(default)]
    pub checks: Vec<RawCheck>,
    #[serde(default)]
    pub stability: Option<RawStability>,
    #[serde(default)]
    pub probe: Option<RawProbe>,
    #[serde(default)]
    pub record: Option<RawRecord>,
    #[serde(default)]
    pub interference: Option<Spanned<RawInterference>>,
    #[serde(default)]
    pub workspace: Option<RawWorkspace>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawWorkspace {
    /// The run passes when the analytic and dynamic workspace classifications agree at least
    /// at this percentage of the points; checks and settling are then reported per point.
    pub min_agreement_percent: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawInterference {
    /// Clearance below which a pair violates [m] (default 0: actual overlap only).
    pub threshold: Option<Spanned<f64>>,
    /// Pairs farther apart are not measured [m] (default: the mechanism's length scale).
    pub margin: Option<Spanned<f64>>,
    /// Report violations without failing the run (default false).
    pub informative: Option<bool>,
    /// Further strut pairs to exclude, by name.
    #[serde(default)]
    pub exclude: Vec<Spanned<(String, String)>>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RawSim {
    pub dt: Option<Spanned<f64>>,
    pub substeps: Option<Spanned<i64>>,
    pub pgs_iterations: Option<Spanned<i64>>,
    /// PGS iterations while approaching an equilibrium, before the final phase at
    /// `pgs_iterations` (default: the same, one phase).
    pub approach_pgs_iterations: Option<Spanned<i64>>,
    pub body_damping: Option<Spanned<f64>>,
    pub bounding_box: Option<Spanned<f64>>,
    /// Kinetic energy above which the run has diverged [J] (default 1e6).
    pub max_kinetic_energy: Option<Spanned<f64>>,
    /// Anchor gap of a loop-closing joint above which the run has diverged [m] (default 1 % of
    /// the structure's size).
    pub max_joint_gap: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RawSettle {
    pub speed_tol: Option<Spanned<f64>>,
    pub window: Option<Spanned<i64>>,
    pub residual_force_tol: Option<Spanned<f64>>,
    pub residual_torque_tol: Option<Spanned<f64>>,
    pub max_time: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRange {
    pub from: Spanned<f64>,
    pub to: Spanned<f64>,
    pub count: Spanned<i64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawActuation {
    /// A grid of inputs, each settled one by one (row-major in the inputs' order).
    pub grid: Option<BTreeMap<Spanned<String>, Spanned<RawRange>>>,
    /// Explicit input sets, each settled one by one.
    pub points: Option<Vec<Spanned<SpannedMap>>>,
    /// Waypoints in time (key `t` in s), linearly interpolated, held at the last; the run is
    /// compared tick by tick and settled after the last waypoint.
    pub waypoints: Option<Vec<Spanned<SpannedMap>>>,
    /// Grid and points: start each point from the previous equilibrium (default true).
    pub continuation: Option<bool>,
    /// Grid only: drop grid points outside the mechanism's domain (for example outside the
    /// kinematic workspace) instead of rejecting the file; they are counted in the report.
    pub skip_outside: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCheck {
    pub quantity: Spanned<String>,
    pub tolerance: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawStability {
    /// Displacement of every free coordinate [rad or m].
    pub perturbation: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawProbe {
    /// Probe torque [N m] (applied as +torque and -torque).
    pub torque: Spanned<f64>,
    /// Tolerance on the relative stiffness error.
    pub tolerance: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRecord {
    pub path: Spanned<String>,
}

/// A validated scenario, ready to run.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub file: PathBuf,
    pub source: String,
    pub name: String,
    pub description: String,
    pub mechanism: String,
    pub params: Values,
    pub sim: SimSettings,
    pub settle: SettleCriteria,
    pub start: Values,
    pub actuation: Actuation,
    pub checks: Vec<Check>,
    pub stability_perturbation: Option<f64>,
    pub probe: Option<Probe>,
    pub record: Option<PathBuf>,
    pub interference: Option<crate::observers::interference::InterferenceSettings>,
    /// Workspace sweep: pass on this agreement percentage instead of on every check.
    pub min_agreement_percent: Option<f64>,
    /// Grid points dropped by `skip_outside`, with the reason.
    pub skipped_points: Vec<(Values, String)>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Actuation {
    Points { points: Vec<Values>, continuation: bool },
    Schedule { waypoints: Vec<(f64, Values)> },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    pub quantity: String,
    pub kind: QuantityKind,
    pub unit: String,
    /// On the normalised error (see `QuantityKind`).
    pub tolerance: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    pub torque_nm: f64,
    pub tolerance: f64,
}

/// Reads and validates a scenario file.
pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
    let source = std::fs::read_to_string(path).map_err(|e| ScenarioError {
        file: path.display().to_string(),
        line: 1,
        col: 1,
        message: format!("cannot read the scenario file: {e}"),
    })?;
    parse(path, &source)
}

/// Parses and validates scenario text (`path` names it in errors).
pub fn parse(path: &Path, source: &str) -> Result<Scenario, ScenarioError> {
    let ctx = Ctx { file: path.display().to_string(), source };
    let raw: RawScenario = toml::from_str(source).map_err(|e| {
        let start = e.span().map(|s| s.start).unwrap_or(0);
        ctx.err_at(start, e.message().trim().to_string())
    })?;
    validate(&ctx, path, raw)
}

struct Ctx<'a> {
    file: String,
    source: &'a str,
}

impl Ctx<'_> {
    fn err_at(&self, offset: usize, message: String) -> ScenarioError {
        let offset = offset.min(self.source.len());
        let before = &self.source[..offset];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map(|l| l.chars().count()).unwrap_or(0) + 1;
        ScenarioError { file: self.file.clone(), line, col, message }
    }
    fn err<T>(&self, at: &Spanned<T>, message: impl Into<String>) -> ScenarioError {
        self.err_at(at.span().start, message.into())
    }
}

fn finite(ctx: &Ctx, v: &Spanned<f64>, what: &str) -> Result<f64, ScenarioError> {
    let x = *v.get_ref();
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ctx.err(v, format!("{what} must be a finite number, got {x}")))
    }
}

fn positive(ctx: &Ctx, v: &Option<Spanned<f64>>, what: &str, default: f64) -> Result<f64, ScenarioError> {
    match v {
        None => Ok(default),
        Some(s) => {
            let x = finite(ctx, s, what)?;
            if x > 0.0 {
                Ok(x)
            } else {
                Err(ctx.err(s, format!("{what} must be > 0, got {x}")))
            }
        }
    }
}

fn count(ctx: &Ctx, v: &Option<Spanned<i64>>, what: &str, default: usize, max: i64) -> Result<usize, ScenarioError> {
    match v {
        None => Ok(default),
        Some(s) => {
            let x = *s.get_ref();
            if (1..=max).contains(&x) {
                Ok(x as usize)
            } else {
                Err(ctx.err(s, format!("{what} must be a whole number from 1 to {max}, got {x}")))
            }
        }
    }
}

fn values(ctx: &Ctx, m: &SpannedMap) -> Result<Values, ScenarioError> {
    m.iter().map(|(k, v)| Ok((k.get_ref().clone(), finite(ctx, v, k.get_ref())?))).collect()
}

/// Largest number of settle points a scenario may ask for.
pub const MAX_POINTS: usize = 1_000_000;

fn validate(ctx: &Ctx, path: &Path, raw: RawScenario) -> Result<Scenario, ScenarioError> {
    if raw.name.get_ref().trim().is_empty() {
        return Err(ctx.err(&raw.name, "name must not be empty"));
    }
    let mech: Box<dyn Mechanism> = mechanisms::find(raw.mechanism.get_ref()).ok_or_else(|| {
        let known: Vec<_> = mechanisms::registry().iter().map(|m| m.name()).collect();
        ctx.err(
            &raw.mechanism,
            format!("unknown mechanism '{}' (expected one of: {})", raw.mechanism.get_ref(), known.join(", ")),
        )
    })?;
    let m = mech.as_ref();

    // Parameters: known symbols, finite, then the mechanism's own ranges.
    for (k, _) in &raw.params {
        if !m.params().iter().any(|p| p.symbol == k.get_ref()) {
            let known: Vec<_> = m.params().iter().map(|p| p.symbol).collect();
            return Err(ctx.err(
                k,
                format!("unknown parameter '{}' for {} (expected one of: {})", k.get_ref(), m.name(), known.join(", ")),
            ));
        }
    }
    let given = values(ctx, &raw.params)?;
    let params = mechanisms::with_defaults(m, &given);
    if let Err((sym, msg)) = m.validate_params(&params) {
        let at = raw.params.iter().find(|(k, _)| k.get_ref() == &sym).map(|(_, v)| v.span().start).unwrap_or(0);
        return Err(ctx.err_at(at, msg));
    }

    let sim = SimSettings {
        dt_s: positive(ctx, &raw.sim.dt, "sim.dt (time step, s)", SimSettings::default().dt_s)?,
        substeps: count(ctx, &raw.sim.substeps, "sim.substeps", 1, 64)?,
        pgs_iterations: count(ctx, &raw.sim.pgs_iterations, "sim.pgs_iterations", 8, 4096)?,
        approach_pgs_iterations: match &raw.sim.approach_pgs_iterations {
            None => None,
            Some(_) => Some(count(ctx, &raw.sim.approach_pgs_iterations, "sim.approach_pgs_iterations", 8, 4096)?),
        },
        body_damping_per_s: match &raw.sim.body_damping {
            None => 0.0,
            Some(s) => {
                let x = finite(ctx, s, "sim.body_damping")?;
                if x < 0.0 {
                    return Err(ctx.err(s, format!("sim.body_damping must be >= 0 1/s, got {x}")));
                }
                x
            }
        },
        bounding_box_m: positive(ctx, &raw.sim.bounding_box, "sim.bounding_box (m)", 1e3)?,
        max_kinetic_energy_j: positive(
            ctx,
            &raw.sim.max_kinetic_energy,
            "sim.max_kinetic_energy (J)",
            crate::sim::DEFAULT_MAX_KINETIC_ENERGY_J,
        )?,
        max_joint_gap_m: match &raw.sim.max_joint_gap {
            None => None,
            Some(_) => Some(positive(ctx, &raw.sim.max_joint_gap, "sim.max_joint_gap (m)", 0.0)?),
        },
    };
    if sim.dt_s > 1.0 {
        let s = raw.sim.dt.as_ref().unwrap();
        return Err(ctx.err(s, format!("sim.dt = {} s is longer than 1 s: use a time step of a few ms", sim.dt_s)));
    }
    let d = SettleCriteria::default();
    let settle = SettleCriteria {
        speed_tol_m_per_s: positive(ctx, &raw.settle.speed_tol, "settle.speed_tol (m/s)", d.speed_tol_m_per_s)?,
        window_steps: count(ctx, &raw.settle.window, "settle.window (steps)", d.window_steps as usize, 1_000_000)?
            as u64,
        residual_force_tol_n: positive(
            ctx,
            &raw.settle.residual_force_tol,
            "settle.residual_force_tol (N)",
            d.residual_force_tol_n,
        )?,
        residual_torque_tol_nm: positive(
            ctx,
            &raw.settle.residual_torque_tol,
            "settle.residual_torque_tol (N m)",
            d.residual_torque_tol_nm,
        )?,
        max_time_s: positive(ctx, &raw.settle.max_time, "settle.max_time (s)", d.max_time_s)?,
    };
    for (k, _) in &raw.start {
        if !m.start_keys().iter().any(|(key, _)| key == k.get_ref()) {
            let known: Vec<_> = m.start_keys().iter().map(|(key, _)| *key).collect();
            return Err(ctx.err(
                k,
                format!("unknown start key '{}' for {} (expected one of: {})", k.get_ref(), m.name(), known.join(", ")),
            ));
        }
    }
    let start = values(ctx, &raw.start)?;

    let native: Vec<&str> = m.inputs().iter().map(|i| i.symbol).collect();
    // The accepted sets of input symbols: the mechanism's inputs, or one of its alternatives.
    let mut input_sets: Vec<Vec<&str>> = vec![native.clone()];
    input_sets.extend(m.alternative_inputs().iter().map(|s| s.to_vec()));
    let expected_sets = input_sets.iter().map(|s| s.join(", ")).collect::<Vec<_>>().join("; or ");
    // The set a table of keys belongs to: the first that contains its first key.
    let set_of = |keys: &[&str]| -> Vec<&str> {
        input_sets.iter().find(|s| keys.iter().any(|k| s.contains(k))).cloned().unwrap_or_else(|| native.clone())
    };
    let check_inputs =
        |map: &SpannedMap, whole: &Spanned<SpannedMap>, allow_t: bool| -> Result<Values, ScenarioError> {
            let keys: Vec<&str> = map.iter().map(|(k, _)| k.get_ref().as_str()).filter(|k| *k != "t").collect();
            let input_syms = set_of(&keys);
            for (k, _) in map {
                if !(input_syms.contains(&k.get_ref().as_str()) || (allow_t && k.get_ref() == "t")) {
                    return Err(ctx.err(
                        k,
                        format!(
                            "unknown input '{}' (expected {}{})",
                            k.get_ref(),
                            expected_sets,
                            if allow_t { ", and t" } else { "" }
                        ),
                    ));
                }
            }
            for s in &input_syms {
                if !map.iter().any(|(k, _)| k.get_ref() == s) {
                    return Err(ctx.err(whole, format!("missing input '{s}' (expected {expected_sets})")));
                }
            }
            let mut vals = values(ctx, map)?;
            let t = vals.remove("t");
            if input_syms != native {
                vals = m.convert_inputs(&params, &vals).map_err(|(sym, msg)| {
                    let at = map
                        .iter()
                        .find(|(k, _)| k.get_ref() == &sym)
                        .map(|(_, v)| v.span().start)
                        .unwrap_or(whole.span().start);
                    ctx.err_at(at, msg)
                })?;
            }
            if let Some(t) = t {
                vals.insert("t".into(), t);
            }
            if let Err((sym, msg)) = m.validate_inputs(&params, &vals) {
                let at = map
                    .iter()
                    .find(|(k, _)| k.get_ref() == &sym)
                    .map(|(_, v)| v.span().start)
                    .unwrap_or(whole.span().start);
                return Err(ctx.err_at(at, msg));
            }
            Ok(vals)
        };

    let act = raw.actuation.get_ref();
    let given = [act.grid.is_some(), act.points.is_some(), act.waypoints.is_some()].iter().filter(|b| **b).count();
    if given != 1 {
        return Err(ctx.err(&raw.actuation, "actuation needs exactly one of: grid, points, waypoints"));
    }
    let mut skipped_points = Vec::new();
    if act.skip_outside.is_some() && act.grid.is_none() {
        return Err(ctx.err(&raw.actuation, "skip_outside applies to a grid only"));
    }
    let actuation = if let Some(grid) = &act.grid {
        let keys: Vec<&str> = grid.iter().map(|(k, _)| k.get_ref().as_str()).collect();
        let input_syms = set_of(&keys);
        for (k, _) in grid {
            if !input_syms.contains(&k.get_ref().as_str()) {
                return Err(
                    ctx.err(k, format!("unknown input '{}' in actuation.grid (expected {expected_sets})", k.get_ref()))
                );
            }
        }
        let mut axes: Vec<(String, Vec<f64>)> = Vec::new();
        for s in &input_syms {
            let (_, r) = grid
                .iter()
                .find(|(k, _)| k.get_ref() == s)
                .ok_or_else(|| ctx.err(&raw.actuation, format!("actuation.grid is missing input '{s}'")))?;
            let r2 = r.get_ref();
            let (a, b) = (finite(ctx, &r2.from, "from")?, finite(ctx, &r2.to, "to")?);
            let n = *r2.count.get_ref();
            if !(1..=MAX_POINTS as i64).contains(&n) {
                return Err(ctx.err(&r2.count, format!("count must be a whole number from 1 to {MAX_POINTS}, got {n}")));
            }
            if n > 1 && a == b {
                return Err(ctx.err(&r2.to, "from and to are equal but count > 1: give count = 1 or a range"));
            }
            let vals = (0..n).map(|i| if n == 1 { a } else { a + (b - a) * i as f64 / (n - 1) as f64 }).collect();
            axes.push((s.to_string(), vals));
        }
        let total: usize = axes.iter().map(|(_, v)| v.len()).product();
        if total > MAX_POINTS {
            return Err(ctx.err(&raw.actuation, format!("the grid has {total} points; at most {MAX_POINTS}")));
        }
        let mut points = vec![Values::new()];
        for (sym, vals) in &axes {
            points = points
                .into_iter()
                .flat_map(|p| {
                    vals.iter().map(move |v| {
                        let mut q = p.clone();
                        q.insert(sym.clone(), *v);
                        q
                    })
                })
                .collect();
        }
        if input_syms != native {
            let mut converted = Vec::new();
            for p in points {
                match m.convert_inputs(&params, &p) {
                    Ok(c) => converted.push(c),
                    Err((_, msg)) if act.skip_outside.unwrap_or(false) => skipped_points.push((p, msg)),
                    Err((sym, msg)) => {
                        let at =
                            grid.iter().find(|(k, _)| k.get_ref() == &sym).map(|(_, v)| v.span().start).unwrap_or(0);
                        return Err(ctx.err_at(at, format!("grid point {:?}: {msg}", p)));
                    }
                }
            }
            points = converted;
        }
        let skip = act.skip_outside.unwrap_or(false);
        let mut kept = Vec::new();
        for p in points {
            match m.validate_inputs(&params, &p) {
                Ok(()) => kept.push(p),
                Err((_, msg)) if skip => skipped_points.push((p, msg)),
                Err((sym, msg)) => {
                    let at = grid.iter().find(|(k, _)| k.get_ref() == &sym).map(|(_, v)| v.span().start).unwrap_or(0);
                    return Err(ctx.err_at(
                        at,
                        format!("grid point {:?}: {msg} (or set actuation.skip_outside = true to drop such points)", p),
                    ));
                }
            }
        }
        if kept.is_empty() {
            return Err(ctx.err(
                &raw.actuation,
                format!("every grid point is outside the mechanism's domain ({} skipped)", skipped_points.len()),
            ));
        }
        let points = kept;
        Actuation::Points { points, continuation: act.continuation.unwrap_or(true) }
    } else if let Some(list) = &act.points {
        if list.is_empty() {
            return Err(ctx.err(&raw.actuation, "actuation.points is empty: give at least one point"));
        }
        let points = list.iter().map(|p| check_inputs(p.get_ref(), p, false)).collect::<Result<Vec<_>, _>>()?;
        Actuation::Points { points, continuation: act.continuation.unwrap_or(true) }
    } else {
        let list = act.waypoints.as_ref().unwrap();
        if list.is_empty() {
            return Err(ctx.err(&raw.actuation, "actuation.waypoints is empty: give at least one waypoint"));
        }
        let mut waypoints = Vec::new();
        let mut last_t = f64::NEG_INFINITY;
        for w in list {
            let (tk, tv) = w
                .get_ref()
                .iter()
                .find(|(k, _)| k.get_ref() == "t")
                .ok_or_else(|| ctx.err(w, "waypoint needs a time t (s)"))?;
            let t = finite(ctx, tv, "t")?;
            if t < 0.0 {
                return Err(ctx.err(tk, format!("waypoint time must be >= 0 s, got {t}")));
            }
            if t <= last_t {
                return Err(
                    ctx.err(tv, format!("waypoints must be sorted by strictly increasing t: {t} s follows {last_t} s"))
                );
            }
            last_t = t;
            let mut vals = check_inputs(w.get_ref(), w, true)?;
            vals.remove("t");
            waypoints.push((t, vals));
        }
        Actuation::Schedule { waypoints }
    };
    if act.continuation.is_some() && matches!(actuation, Actuation::Schedule { .. }) {
        return Err(ctx.err(&raw.actuation, "continuation applies to grid and points, not to waypoints"));
    }

    let mut checks = Vec::new();
    for c in &raw.checks {
        let q = m.quantities().iter().find(|q| q.symbol == c.quantity.get_ref()).ok_or_else(|| {
            let known: Vec<_> = m.quantities().iter().map(|q| q.symbol).collect();
            ctx.err(
                &c.quantity,
                format!("unknown quantity '{}' (expected one of: {})", c.quantity.get_ref(), known.join(", ")),
            )
        })?;
        let tol = finite(ctx, &c.tolerance, "tolerance")?;
        if tol <= 0.0 {
            return Err(ctx.err(&c.tolerance, format!("tolerance must be > 0, got {tol}")));
        }
        checks.push(Check { quantity: q.symbol.into(), kind: q.kind, unit: q.unit.into(), tolerance: tol });
    }
    if checks.is_empty() && raw.probe.is_none() {
        return Err(ctx
            .err_at(0, "the scenario checks nothing: add at least one [[checks]] entry (quantity, tolerance)".into()));
    }

    let stability_perturbation = match &raw.stability {
        None => None,
        Some(s) => {
            let x = finite(ctx, &s.perturbation, "stability.perturbation")?;
            if !(x > 0.0 && x < 1.0) {
                return Err(
                    ctx.err(&s.perturbation, format!("stability.perturbation must be in (0, 1) (rad or m), got {x}"))
                );
            }
            Some(x)
        }
    };
    let probe = match &raw.probe {
        None => None,
        Some(p) => {
            if m.stiffness_probe().is_none() {
                return Err(ctx.err(&p.torque, format!("{} has no stiffness probe", m.name())));
            }
            let t = finite(ctx, &p.torque, "probe.torque")?;
            if t <= 0.0 {
                return Err(ctx.err(&p.torque, format!("probe.torque must be > 0 N m, got {t}")));
            }
            let tol = finite(ctx, &p.tolerance, "probe.tolerance")?;
            if tol <= 0.0 {
                return Err(ctx.err(&p.tolerance, format!("probe.tolerance must be > 0, got {tol}")));
            }
            Some(Probe { torque_nm: t, tolerance: tol })
        }
    };
    let record = match &raw.record {
        None => None,
        Some(r) => {
            let p = r.path.get_ref();
            if !p.ends_with(".rrd") {
                return Err(ctx.err(&r.path, format!("record.path must end in .rrd, got '{p}'")));
            }
            Some(PathBuf::from(p))
        }
    };
    let min_agreement_percent = match &raw.workspace {
        None => None,
        Some(w) => {
            let x = finite(ctx, &w.min_agreement_percent, "workspace.min_agreement_percent")?;
            if !(0.0..=100.0).contains(&x) {
                return Err(ctx.err(
                    &w.min_agreement_percent,
                    format!("workspace.min_agreement_percent must lie in [0, 100], got {x}"),
                ));
            }
            Some(x)
        }
    };
    let interference = match &raw.interference {
        None => None,
        Some(i) => {
            let threshold = match &i.get_ref().threshold {
                None => 0.0,
                Some(t) => finite(ctx, t, "interference.threshold")?,
            };
            let margin = match &i.get_ref().margin {
                None => m.length_scale(&params),
                Some(t) => {
                    let x = finite(ctx, t, "interference.margin")?;
                    if x <= 0.0 {
                        return Err(ctx.err(t, format!("interference.margin must be > 0 m, got {x}")));
                    }
                    x
                }
            };
            if threshold >= margin {
                return Err(ctx.err(
                    i,
                    format!("interference.threshold ({threshold} m) must be below interference.margin ({margin} m)"),
                ));
            }
            let exclude = i.get_ref().exclude.iter().map(|e| e.get_ref().clone()).collect();
            // Strut names are checked against the built structure.
            let settings = crate::observers::interference::InterferenceSettings {
                threshold_m: threshold,
                margin_m: margin,
                informative: i.get_ref().informative.unwrap_or(false),
                exclude,
            };
            let first = match &actuation {
                Actuation::Points { points, .. } => points[0].clone(),
                Actuation::Schedule { waypoints } => waypoints[0].1.clone(),
            };
            let structure = m.build(&params, &first, &start).map_err(|e| ctx.err(&raw.actuation, e))?;
            if let Err(e) = crate::observers::interference::Interference::new(&structure, &settings) {
                return Err(ctx.err(i, e));
            }
            Some(settings)
        }
    };
    Ok(Scenario {
        file: path.to_path_buf(),
        source: ctx.source.to_string(),
        name: raw.name.into_inner(),
        description: raw.description,
        mechanism: m.name().into(),
        params,
        sim,
        settle,
        start,
        actuation,
        checks,
        stability_perturbation,
        probe,
        record,
        interference,
        min_agreement_percent,
        skipped_points,
    })
}
