//! Scenario files (TOML): what to simulate, how, and what to check.
//!
//! Every error names the file, line and column (`file.toml:LINE:COL: ...`) and says what was
//! expected. Parsing is two passes: serde for the shape (unknown keys, wrong types, missing
//! fields), then [`validate`] for the values (ranges, the mechanism's own rules).

use crate::mechanisms::{self, Mechanism, Values};
use crate::settings::{Check, Probe, SettleCriteria, SimSettings};
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
    /// `mechanism = "custom"`: the structure itself.
    #[serde(default)]
    pub structure: Option<Spanned<RawStructure>>,
    /// What the run must do: pass, or fail in named parts.
    #[serde(default)]
    pub expect: Option<Spanned<RawExpect>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawExpect {
    /// "pass" or "fail".
    pub verdict: Spanned<String>,
    /// With "fail": every part of the verdict that must fail, and no other
    /// (see [`crate::settings::FAILURE_NAMES`]).
    #[serde(default)]
    pub failing: Vec<Spanned<String>>,
}

type Xyz = Spanned<[f64; 3]>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawStructure {
    /// Gravity [m/s^2] (default none).
    pub gravity: Option<Xyz>,
    #[serde(default)]
    pub bodies: Vec<RawBody>,
    #[serde(default)]
    pub struts: Vec<RawMember>,
    #[serde(default)]
    pub springs: Vec<RawMember>,
    #[serde(default)]
    pub cables: Vec<RawMember>,
    #[serde(default)]
    pub joints: Vec<RawJoint>,
    #[serde(default)]
    pub actuators: Vec<RawActuator>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawBody {
    pub name: Spanned<String>,
    /// Welded to the world (default false).
    pub fixed: Option<bool>,
    /// Mass of a free body [kg].
    pub mass: Option<Spanned<f64>>,
    /// Principal moments about the centre of mass, along the world axes [kg m^2] (default:
    /// isotropic, mass times the square of the body's size over 12).
    pub inertia: Option<Xyz>,
    /// Named nodes with their coordinates [m] (the centre of mass is their mean).
    pub nodes: BTreeMap<Spanned<String>, Xyz>,
}

/// A strut, spring or cable between two named nodes.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawMember {
    pub name: Spanned<String>,
    pub a: Spanned<String>,
    pub b: Spanned<String>,
    /// Struts: radius [m] (default 0.01).
    pub radius: Option<Spanned<f64>>,
    /// Springs: stiffness [N/m] (required); cables: stiffness of an elastic cable (absent:
    /// inextensible).
    pub stiffness: Option<Spanned<f64>>,
    /// Springs: free length [m]; cables: unstretched length [m]. Absent: the initial distance.
    pub length: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawJoint {
    pub name: Spanned<String>,
    /// revolute, prismatic, spherical, universal, fixed or planar_pin.
    pub kind: Spanned<String>,
    pub parent: Spanned<String>,
    pub child: Spanned<String>,
    /// The node at the joint's centre.
    pub at: Spanned<String>,
    pub axis: Option<Xyz>,
    /// Universal joints: the second axis (fixed in the child).
    pub axis2: Option<Xyz>,
    /// Revolute joints: a linear torsion spring [N m/rad], at rest in the given geometry plus
    /// `torsion_rest` [rad].
    pub torsion_stiffness: Option<Spanned<f64>>,
    pub torsion_rest: Option<Spanned<f64>>,
    /// Viscous damping [N m s/rad or N s/m].
    pub damping: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawActuator {
    pub symbol: Spanned<String>,
    pub joint: Option<Spanned<String>>,
    pub cable: Option<Spanned<String>>,
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
    /// The Newton damping schedule (default false: the structure's fixed damping).
    pub newton_damping: Option<Spanned<bool>>,
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
    /// Custom structures only: the expected value (there is no analytic model).
    pub value: Option<Spanned<f64>>,
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
    pub interference: Option<crate::settings::InterferenceSettings>,
    /// Workspace sweep: pass on this agreement percentage instead of on every check.
    pub min_agreement_percent: Option<f64>,
    /// Grid points dropped by `skip_outside`, with the reason.
    pub skipped_points: Vec<(Values, String)>,
    /// `mechanism = "custom"`: the mechanism built from the file.
    pub custom: Option<crate::custom::Custom>,
    /// `[expect]`: what the run must do, if the file declares it.
    pub expect: Option<crate::settings::Expectation>,
}

impl Scenario {
    /// The scenario's mechanism: a built-in one, or the file's own structure.
    pub fn mechanism(&self) -> Box<dyn Mechanism> {
        match &self.custom {
            Some(c) => Box::new(c.clone()),
            None => mechanisms::find(&self.mechanism).expect("validated mechanism"),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Actuation {
    Points { points: Vec<Values>, continuation: bool },
    Schedule { waypoints: Vec<(f64, Values)> },
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
    let custom =
        match (raw.mechanism.get_ref().as_str(), &raw.structure) {
            ("custom", Some(st)) => {
                let structure = structure_from_file(ctx, st)?;
                let mut expected = Values::new();
                for c in &raw.checks {
                    let v = c.value.as_ref().ok_or_else(|| {
                        ctx.err(
                            &c.quantity,
                            "a custom structure has no analytic model: give the expected value (value = ...)",
                        )
                    })?;
                    expected.insert(c.quantity.get_ref().clone(), finite(ctx, v, "value")?);
                }
                Some(crate::custom::Custom::new(structure, expected))
            }
            ("custom", None) => return Err(ctx.err(
                &raw.mechanism,
                "mechanism = \"custom\" needs a [structure] table (bodies, struts, springs, cables, joints, actuators)",
            )),
            (_, Some(st)) => return Err(ctx.err(st, "a [structure] table goes with mechanism = \"custom\" only")),
            _ => None,
        };
    if custom.is_none() {
        if let Some(v) = raw.checks.iter().find_map(|c| c.value.as_ref()) {
            return Err(ctx.err(
                v,
                "value is for custom structures; a built-in mechanism's checks compare with its analytic model",
            ));
        }
    }
    let mech: Box<dyn Mechanism> = match &custom {
        Some(c) => Box::new(c.clone()),
        None => mechanisms::find(raw.mechanism.get_ref()).ok_or_else(|| {
            let known: Vec<_> = mechanisms::registry().iter().map(|m| m.name()).collect();
            ctx.err(
                &raw.mechanism,
                format!(
                    "unknown mechanism '{}' (expected one of: {}, custom)",
                    raw.mechanism.get_ref(),
                    known.join(", ")
                ),
            )
        })?,
    };
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
        newton_damping: raw.sim.newton_damping.as_ref().is_some_and(|b| *b.get_ref()),
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
            crate::settings::DEFAULT_MAX_KINETIC_ENERGY_J,
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
    // A custom structure is checked by its settling and force balance even without [[checks]].
    if checks.is_empty() && raw.probe.is_none() && custom.is_none() {
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
            let settings = crate::settings::InterferenceSettings {
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
            if let Err(e) = settings.check_strut_names(&structure) {
                return Err(ctx.err(i, e));
            }
            Some(settings)
        }
    };
    let expect = match &raw.expect {
        None => None,
        Some(e) => Some(expectation(ctx, e, &checks)?),
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
        custom,
        expect,
    })
}

/// `[expect]`: `verdict = "pass"`, or `"fail"` with the parts that must fail (`failing`), each
/// a part this scenario has (a `check:` names one of its `[[checks]]`).
fn expectation(
    ctx: &Ctx,
    raw: &Spanned<RawExpect>,
    checks: &[Check],
) -> Result<crate::settings::Expectation, ScenarioError> {
    use crate::settings::{Expectation, Failure};
    let e = raw.get_ref();
    let mut failing = Vec::new();
    for f in &e.failing {
        let failure: Failure = f.get_ref().parse().map_err(|m: String| ctx.err(f, m))?;
        if let Failure::Check(q) = &failure {
            if !checks.iter().any(|c| &c.quantity == q) {
                let known: Vec<_> = checks.iter().map(|c| c.quantity.as_str()).collect();
                return Err(ctx.err(f, format!("'{q}' is not among this scenario's checks ({})", known.join(", "))));
            }
        }
        failing.push(failure);
    }
    match e.verdict.get_ref().as_str() {
        "pass" if failing.is_empty() => Ok(Expectation::PASS),
        "pass" => Err(ctx.err(&e.failing[0], "expect.failing goes with verdict = \"fail\"")),
        "fail" if failing.is_empty() => Err(ctx.err(
            &e.verdict,
            "verdict = \"fail\" needs expect.failing: the parts that must fail (for example [\"interference\"])",
        )),
        "fail" => Ok(Expectation { failing }),
        other => Err(ctx.err(&e.verdict, format!("expect.verdict must be \"pass\" or \"fail\", got '{other}'"))),
    }
}

/// Builds the structure of a `[structure]` table; every bad reference, zero-length member or
/// massless free body is an error at its place in the file.
fn structure_from_file(ctx: &Ctx, raw: &Spanned<RawStructure>) -> Result<crate::structure::Structure, ScenarioError> {
    use crate::structure::{
        Actuator, ActuatorTarget, BodyKind, Cable, CableLaw, Inertia, Joint, JointKind, Spring, Structure, Strut,
        TorsionSpring,
    };
    let r = raw.get_ref();
    let xyz = |v: &Xyz, what: &str| -> Result<[f64; 3], ScenarioError> {
        let a = *v.get_ref();
        if a.iter().all(|c| c.is_finite()) {
            Ok(a)
        } else {
            Err(ctx.err(v, format!("{what} must be three finite numbers, got {a:?}")))
        }
    };
    let mut s = Structure { name: "custom".into(), ..Default::default() };
    if let Some(g) = &r.gravity {
        s.gravity = xyz(g, "gravity")?;
    }
    if r.bodies.is_empty() {
        return Err(ctx.err(raw, "[structure] needs at least one body ([[structure.bodies]])"));
    }
    let mut body_names: Vec<String> = Vec::new();
    for b in &r.bodies {
        if body_names.contains(b.name.get_ref()) {
            return Err(ctx.err(&b.name, format!("duplicate body name '{}'", b.name.get_ref())));
        }
        body_names.push(b.name.get_ref().clone());
        if b.nodes.is_empty() {
            return Err(ctx.err(
                &b.name,
                format!("body '{}' needs at least one node (nodes = {{ N1 = [x, y, z] }})", b.name.get_ref()),
            ));
        }
        let mut pts = Vec::new();
        for (n, p) in &b.nodes {
            pts.push((n, xyz(p, "a node's coordinates")?));
        }
        let fixed = b.fixed.unwrap_or(false);
        let inertia = if fixed {
            None
        } else {
            let m = b.mass.as_ref().ok_or_else(|| {
                ctx.err(
                    &b.name,
                    format!("free body '{}' needs a mass > 0 kg (mass = ...), or fixed = true", b.name.get_ref()),
                )
            })?;
            let mass = finite(ctx, m, "mass")?;
            if mass <= 0.0 {
                return Err(ctx.err(m, format!("mass must be > 0 kg, got {mass}")));
            }
            let n = pts.len() as f64;
            let com = [0, 1, 2].map(|k| pts.iter().map(|(_, p)| p[k]).sum::<f64>() / n);
            let size = pts
                .iter()
                .flat_map(|(_, a)| pts.iter().map(move |(_, b)| crate::structure::distance(*a, *b)))
                .fold(MIN_BODY_SIZE_M, f64::max);
            let principal = match &b.inertia {
                Some(i) => {
                    let v = xyz(i, "inertia")?;
                    if v.iter().any(|x| *x <= 0.0) {
                        return Err(ctx.err(i, "inertia must be three moments > 0 kg m^2"));
                    }
                    v
                }
                None => [mass * size * size / 12.0; 3],
            };
            Some(Inertia { mass_kg: mass, com, principal_kg_m2: principal })
        };
        let id = s.add_body(b.name.get_ref(), if fixed { BodyKind::Fixed } else { BodyKind::Free }, inertia);
        for (n, p) in pts {
            if s.node_id(n.get_ref()).is_some() {
                return Err(ctx.err(n, format!("duplicate node name '{}'", n.get_ref())));
            }
            s.add_node(n.get_ref(), id, p);
        }
    }
    let node = |s: &Structure, n: &Spanned<String>| -> Result<usize, ScenarioError> {
        s.node_id(n.get_ref()).ok_or_else(|| {
            ctx.err(n, format!("unknown node '{}' (nodes are declared in the bodies' nodes tables)", n.get_ref()))
        })
    };
    let body = |s: &Structure, n: &Spanned<String>| -> Result<usize, ScenarioError> {
        s.body_id(n.get_ref()).ok_or_else(|| ctx.err(n, format!("unknown body '{}'", n.get_ref())))
    };
    let ends = |s: &Structure, m: &RawMember, what: &str| -> Result<(usize, usize, f64), ScenarioError> {
        let (a, b) = (node(s, &m.a)?, node(s, &m.b)?);
        let l = crate::structure::distance(s.nodes[a].position, s.nodes[b].position);
        if l <= 0.0 {
            return Err(ctx.err(&m.name, format!("{what} '{}' has zero length: its nodes coincide", m.name.get_ref())));
        }
        Ok((a, b, l))
    };
    let positive = |v: &Spanned<f64>, what: &str| -> Result<f64, ScenarioError> {
        let x = finite(ctx, v, what)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(ctx.err(v, format!("{what} must be > 0, got {x}")))
        }
    };
    for m in &r.struts {
        let (a, b, _) = ends(&s, m, "strut")?;
        let radius = match &m.radius {
            Some(v) => positive(v, "radius (m)")?,
            None => DEFAULT_STRUT_RADIUS_M,
        };
        s.struts.push(Strut { name: m.name.get_ref().clone(), a, b, radius_m: radius });
    }
    for m in &r.springs {
        let (a, b, l) = ends(&s, m, "spring")?;
        let k = m.stiffness.as_ref().ok_or_else(|| ctx.err(&m.name, "a spring needs a stiffness (N/m)"))?;
        let rest = match &m.length {
            Some(v) => {
                let x = finite(ctx, v, "length (m)")?;
                if x < 0.0 {
                    return Err(ctx.err(v, format!("a spring's free length must be >= 0 m, got {x}")));
                }
                x
            }
            None => l,
        };
        s.springs.push(Spring {
            name: m.name.get_ref().clone(),
            a,
            b,
            stiffness_n_per_m: positive(k, "stiffness (N/m)")?,
            rest_length_m: rest,
        });
    }
    for m in &r.cables {
        let (a, b, l) = ends(&s, m, "cable")?;
        let law = match &m.stiffness {
            Some(k) => CableLaw::Elastic { stiffness_n_per_m: positive(k, "stiffness (N/m)")? },
            None => CableLaw::Inextensible,
        };
        let length = match &m.length {
            Some(v) => positive(v, "length (m)")?,
            None => l,
        };
        s.cables.push(Cable { name: m.name.get_ref().clone(), a, b, law, length_m: length });
    }
    for j in &r.joints {
        let axis = |v: &Option<Xyz>, what: &str| -> Result<[f64; 3], ScenarioError> {
            let v = v
                .as_ref()
                .ok_or_else(|| ctx.err(&j.kind, format!("a {} joint needs {what} = [x, y, z]", j.kind.get_ref())))?;
            let a = xyz(v, what)?;
            if a.iter().all(|c| *c == 0.0) {
                return Err(ctx.err(v, format!("{what} must not be zero")));
            }
            Ok(a)
        };
        let kind = match j.kind.get_ref().as_str() {
            "revolute" => JointKind::Revolute { axis: axis(&j.axis, "axis")? },
            "prismatic" => JointKind::Prismatic { axis: axis(&j.axis, "axis")? },
            "spherical" => JointKind::Spherical,
            "universal" => JointKind::Universal { axis1: axis(&j.axis, "axis")?, axis2: axis(&j.axis2, "axis2")? },
            "fixed" => JointKind::Fixed,
            "planar_pin" => JointKind::PlanarPin { axis: axis(&j.axis, "axis")? },
            other => {
                return Err(ctx.err(
                    &j.kind,
                    format!("unknown joint kind '{other}' (expected revolute, prismatic, spherical, universal, fixed or planar_pin)"),
                ))
            }
        };
        let (parent, child, at) = (body(&s, &j.parent)?, body(&s, &j.child)?, node(&s, &j.at)?);
        let torsion_spring = match &j.torsion_stiffness {
            Some(k) => Some(TorsionSpring {
                stiffness_nm_per_rad: positive(k, "torsion_stiffness (N m/rad)")?,
                rest_angle_rad: match &j.torsion_rest {
                    Some(v) => finite(ctx, v, "torsion_rest")?,
                    None => 0.0,
                },
            }),
            None => None,
        };
        let damping = match &j.damping {
            Some(v) => {
                let x = finite(ctx, v, "damping")?;
                if x < 0.0 {
                    return Err(ctx.err(v, format!("damping must be >= 0, got {x}")));
                }
                x
            }
            None => 0.0,
        };
        s.joints.push(Joint {
            name: j.name.get_ref().clone(),
            kind,
            parent,
            child,
            anchor: at,
            initial_coordinate: 0.0,
            torsion_spring,
            damping,
        });
    }
    for a in &r.actuators {
        let target = match (&a.joint, &a.cable) {
            (Some(j), None) => ActuatorTarget::Joint(
                s.joints
                    .iter()
                    .position(|x| &x.name == j.get_ref())
                    .ok_or_else(|| ctx.err(j, format!("unknown joint '{}'", j.get_ref())))?,
            ),
            (None, Some(c)) => ActuatorTarget::CableLength(
                s.cables
                    .iter()
                    .position(|x| &x.name == c.get_ref())
                    .ok_or_else(|| ctx.err(c, format!("unknown cable '{}'", c.get_ref())))?,
            ),
            _ => {
                return Err(ctx.err(&a.symbol, "an actuator drives exactly one of: joint = \"name\", cable = \"name\""))
            }
        };
        s.actuators.push(Actuator { symbol: a.symbol.get_ref().clone(), target });
    }
    s.validate().map_err(|e| ctx.err(raw, format!("the structure is not valid: {e}")))?;
    Ok(s)
}

/// Smallest size used for a body's default inertia [m].
const MIN_BODY_SIZE_M: f64 = 1e-3;

/// Strut radius when the file gives none [m].
const DEFAULT_STRUT_RADIUS_M: f64 = 0.01;
