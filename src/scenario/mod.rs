//! Scenario files (TOML): what to simulate, how, and what to check.
//!
//! Every error names the file, line and column (`file.toml:LINE:COL: ...`) and says what was
//! expected. Parsing is two passes: serde for the shape (unknown keys, wrong types, missing
//! fields), then `validate` for the values (ranges, the mechanism's own rules).
//!
//! One file per concern: `raw.rs` the shape serde reads, `error.rs` errors at a place in the file
//! and the checks on single values, then one file per section, each read in turn by `validate`
//! (in a fixed order: the first error found is the one reported).

mod actuation;
mod bounds;
mod checks;
mod energy;
mod error;
mod expect;
mod fidelity;
mod file_model;
mod for_each;
mod interference;
mod kinetic;
mod mechanism;
mod motion;
mod names;
mod number;
mod overrides;
mod params;
mod pattern;
mod physical;
mod prestress;
mod raw;
mod record;
mod repeat;
mod sim;
mod structure;

use crate::mechanisms::{self, Mechanism, Values};
use crate::settings::{Check, Probe, SettleCriteria, SimSettings};
use error::Ctx;
use raw::RawScenario;
use std::path::{Path, PathBuf};

pub use bounds::{MAX_STEPS_PER_RUN, MAX_STEPS_PER_SETTLE};
pub use error::ScenarioError;
pub use overrides::{Override, OverrideError};

/// A validated scenario, ready to run.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub file: PathBuf,
    pub source: String,
    /// The `--set` flags it was parsed with: a study that builds the structure again at other
    /// parameters (`with_parameter_sets`) applies them as the parse did.
    pub overrides: Vec<Override>,
    pub name: String,
    pub description: String,
    pub mechanism: String,
    /// Every parameter's value (the mechanism's defaults where the file gives none).
    pub params: Values,
    /// The file's `[params]`, to evaluate again at a point that sets some ([`Scenario::params_at`]).
    pub param_table: crate::file_model::params::ParamTable,
    pub sim: SimSettings,
    pub settle: SettleCriteria,
    pub start: Values,
    pub actuation: Actuation,
    pub checks: Vec<Check>,
    pub stability_perturbation: Option<f64>,
    /// `[stability] expect`; see [`Scenario::expected_stable`].
    pub expected_stability: ExpectedStability,
    pub probe: Option<Probe>,
    pub record: Option<PathBuf>,
    pub interference: crate::settings::InterferenceSettings,
    /// Workspace sweep: pass on this agreement percentage instead of on every check.
    pub min_agreement_percent: Option<f64>,
    /// Grid points dropped by `skip_outside`, with the reason.
    pub skipped_points: Vec<(Values, String)>,
    /// `mechanism = "custom"`: the mechanism built from the file.
    pub custom: Option<crate::mechanisms::custom::Custom>,
    /// `[expect]`: what the run must do, if the file declares it.
    pub expect: Option<crate::report::verdict::Expectation>,
    /// `[[quantities]]`, `[[predictions]]`, `[[equations]]`: the file's own model, if any.
    pub model: Option<crate::file_model::spec::ModelSpec>,
    /// `[motion]`: a motion run (the physical dynamics for a stated time), if the file asks.
    pub motion: Option<crate::settings::Motion>,
    /// A sweep over a parameter that changes the structure's topology (a pattern's range):
    /// the scenario validated again for each value, with that value's points, run one after
    /// the other (empty: one structure for every point).
    pub topologies: Vec<Scenario>,
    /// The parameters the patterns' ranges and templates read (`pattern.rs`).
    pub topology_params: Vec<String>,
    /// One structure of a split scenario (a topology's, or a motion's point): the parameters
    /// its patterns were expanded with, which a study's steps expand them with again (None:
    /// the file's own).
    topology: Option<Topology>,
    /// Swept parameters that change nothing in a custom structure (only formulas see them).
    pub unseen_params: Vec<String>,
    /// `[prestress]`, or the default of a custom structure with cables: when the structure has
    /// lost its self-stress and what that does (None: not judged).
    pub prestress: Option<crate::settings::Prestress>,
    /// `[[fidelity]]`: the idealizations the file can relax, with their data.
    pub fidelity: Vec<crate::structure::fidelity::Relaxation>,
    /// Which of them a run applies (indices into `fidelity`; empty: the ideal structure, as
    /// every run but `tensegrity attribute`'s).
    pub relaxed: Vec<usize>,
    /// `[certify]` (or `--certify`): a proof of the equilibrium at every settle point.
    pub certify: bool,
}

impl Scenario {
    /// The scenario with every settle point certified (`--certify`), its topologies' parts too.
    pub fn certified(mut self) -> Scenario {
        self.certify = true;
        self.topologies = self.topologies.into_iter().map(Scenario::certified).collect();
        self
    }

    /// The stability the scenario states for settle point `index` (None: it does not say,
    /// or leaves it to the energy model, which decides at the settled state).
    pub fn expected_stable(&self, index: usize) -> Option<bool> {
        match &self.expected_stability {
            ExpectedStability::Listed(list) => match list.as_slice() {
                [all] => Some(*all),
                list => list.get(index).copied(),
            },
            _ => None,
        }
    }

    /// Every parameter's value at a settle point or waypoint: the point's own where it sets
    /// some (a sweep over parameters), with every parameter that depends on them.
    pub fn params_at(&self, point: &Values) -> Values {
        params::params_at(&self.param_table, &self.params, point)
    }

    /// The parameters that nothing reads (`params::unread`): a change to one changes no
    /// structure, model, check, motion or input, so a study gives it no steps. None for a
    /// built-in mechanism, which reads its parameters itself.
    pub fn unread_params(&self) -> Vec<String> {
        match &self.custom {
            Some(_) => params::unread(&self.source, &self.overrides, &self.param_table),
            None => Vec::new(),
        }
    }

    /// The scenario's mechanism: a built-in one, or the file's own structure.
    pub fn mechanism(&self) -> Box<dyn Mechanism> {
        let ideal: Box<dyn Mechanism> = match &self.custom {
            Some(c) => Box::new(c.clone()),
            None => mechanisms::find(&self.mechanism).expect("validated mechanism"),
        };
        if self.relaxed.is_empty() {
            return ideal;
        }
        let set = self.relaxed.iter().map(|&i| self.fidelity[i].clone()).collect();
        fidelity::relaxed(ideal, set)
    }

    /// The scenario with the relaxations `set` (indices into `fidelity`) applied to every
    /// structure its runs build, its topologies' too.
    pub fn relaxed_by(&self, set: &[usize]) -> Scenario {
        let mut sc = self.clone();
        sc.relaxed = set.to_vec();
        sc.topologies = self.topologies.iter().map(|t| t.relaxed_by(set)).collect();
        sc
    }

    /// The quantities a run measures at every tick, by name: the mechanism's and the file's
    /// `[[quantities]]` (what an external model's prediction may be compared with).
    pub fn quantity_names(&self) -> Vec<String> {
        let quantities = match &self.custom {
            Some(c) => c.quantities(),
            None => self.mechanism().quantities(),
        };
        let own = quantities.iter().map(|q| q.symbol.to_string()).collect::<Vec<_>>();
        let file = self.model.iter().flat_map(|m| m.quantities.iter().map(|q| q.name.clone()));
        own.into_iter().chain(file).collect()
    }

    /// Whether a compared quantity is an angle (its errors are wrapped to (-pi, pi]): one of
    /// the mechanism's angle quantities, a prediction of the file's model of class angle, or
    /// an `[energy]` coordinate of class angle.
    pub fn is_angle(&self, quantity: &str) -> bool {
        // Borrowed, never cloned: a custom mechanism holds a structure per swept set of
        // parameters, and a sweep's CSV asks here per cell (4000 points had taken 28.8 s).
        let quantities = match &self.custom {
            Some(c) => c.quantities(),
            None => self.mechanism().quantities(),
        };
        quantities.iter().any(|q| q.symbol == quantity && q.kind == mechanisms::QuantityKind::Angle)
            || self.model.as_ref().is_some_and(|m| m.is_angle(quantity) || m.is_angle_coordinate(quantity))
    }
}

/// `[stability] expect`: what the perturbation test must find at each settle point.
#[derive(Clone, Debug, PartialEq)]
pub enum ExpectedStability {
    /// The scenario does not say.
    Unsaid,
    /// One stability for every point, or one per point (true: stable).
    Listed(Vec<bool>),
    /// What the `[energy]` model says of the stationary point the dynamics landed on: a
    /// minimum is stable, a maximum or a saddle unstable (a degenerate point says nothing).
    FromEnergy,
}

/// What drives the mechanism: points settled one by one, or waypoints followed in time.
#[derive(Clone, Debug, PartialEq)]
pub enum Actuation {
    Points { points: Vec<Values>, continuation: bool },
    Schedule { waypoints: Vec<(f64, Values)> },
}

impl Actuation {
    /// The inputs of the first point or waypoint (validation keeps both lists non-empty).
    pub fn first_inputs(&self) -> &Values {
        match self {
            Actuation::Points { points, .. } => &points[0],
            Actuation::Schedule { waypoints } => &waypoints[0].1,
        }
    }

    /// The inputs of every point or waypoint, in order.
    pub fn all_inputs(&self) -> Vec<&Values> {
        match self {
            Actuation::Points { points, .. } => points.iter().collect(),
            Actuation::Schedule { waypoints } => waypoints.iter().map(|(_, v)| v).collect(),
        }
    }
}

/// Reads and validates a scenario file.
pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
    load_with(path, &[])
}

/// Reads a scenario file (`-`: standard input) and validates it with `overrides` applied.
pub fn load_with(path: &Path, overrides: &[Override]) -> Result<Scenario, ScenarioError> {
    let source = read_source(path)?;
    parse_with(path, &source, overrides)
}

/// The path that stands for standard input.
pub const STDIN: &str = crate::input::STDIN;

/// A scenario's text, from its file or standard input, at most [`MAX_SCENARIO_BYTES`].
fn read_source(path: &Path) -> Result<String, ScenarioError> {
    crate::input::read_text(path, MAX_SCENARIO_BYTES, true).map_err(|e| ScenarioError {
        file: path.display().to_string(),
        line: 1,
        col: 1,
        message: format!("the scenario file: {e}"),
    })
}

/// Largest scenario file read \[bytes\]: 16 MiB. A list of 1,000,001 points (28 MB) took 2.1 GB
/// to parse before its length was checked.
pub const MAX_SCENARIO_BYTES: u64 = 16 << 20;

impl Scenario {
    /// This scenario with its custom structure resolved at the sets of parameters `sets` too
    /// (each every parameter's value), read from the file's text as at any other set a sweep
    /// asks for (plain data: nothing is built); a built-in mechanism's scenario as it is. A
    /// sweep over a topology is refused: its structures differ by more than their values.
    pub fn with_parameter_sets(&self, sets: &[Values]) -> Result<Scenario, ScenarioError> {
        let Some(custom) = &self.custom else { return Ok(self.clone()) };
        // The file's text with its `--set` flags, read as `parse_with` read it.
        let (extended, file_lines) = overrides::extended_source(&self.source, &self.overrides);
        let ctx = Ctx { file: self.file.display().to_string(), source: &extended };
        if !self.topologies.is_empty() {
            return Err(ctx.err_at(0, "a sweep over a topology has no structure at other parameters".into()));
        }
        let mut raw: RawScenario = toml::from_str(&self.source).map_err(|e| {
            let start = e.span().map(|s| s.start).unwrap_or(0);
            ctx.err_at(start, error::in_file_words(e.message().trim()))
        })?;
        overrides::apply(&ctx, &mut raw, &self.overrides, file_lines)
            .map_err(|e| overrides::at_flag(e, &self.overrides, file_lines))?;
        // The file passed the expansion's bound when it was parsed; the same text again, with
        // the counts of this scenario's own topology (a split scenario's part: its point's).
        expand_patterns(&ctx, &mut raw, self.topology.as_ref(), &std::rc::Rc::default())?;
        let variants = mechanism::variants(&ctx, &raw, sets.iter())?;
        Ok(Scenario { custom: Some(custom.clone().with_more_variants(variants)), ..self.clone() })
    }
}

/// Parses and validates scenario text (`path` names it in errors).
pub fn parse(path: &Path, source: &str) -> Result<Scenario, ScenarioError> {
    parse_with(path, source, &[])
}

/// Parses scenario text and validates it with `overrides` applied (`--set`; an error in one
/// is reported at its flag).
pub fn parse_with(path: &Path, source: &str, overrides: &[Override]) -> Result<Scenario, ScenarioError> {
    // Text handed over whole (the Python package's) is bounded as a file is while it is read.
    if source.len() as u64 > MAX_SCENARIO_BYTES {
        let message = format!("the scenario text has {} bytes: at most {MAX_SCENARIO_BYTES}", source.len());
        return Err(ScenarioError { file: path.display().to_string(), line: 1, col: 1, message });
    }
    let (extended, file_lines) = overrides::extended_source(source, overrides);
    let ctx = Ctx { file: path.display().to_string(), source: &extended };
    let mut raw: RawScenario = toml::from_str(source).map_err(|e| {
        let start = e.span().map(|s| s.start).unwrap_or(0);
        ctx.err_at(start, error::in_file_words(e.message().trim()))
    })?;
    let located = |e| overrides::at_flag(e, overrides, file_lines);
    overrides::apply(&ctx, &mut raw, overrides, file_lines).map_err(located)?;
    let spent = std::rc::Rc::default();
    let mut sc = match validate(&ctx, path, raw, None, &spent).map_err(located)? {
        Validated::One(sc) => *sc,
        Validated::Split(topologies) => {
            let mut variants = Vec::new();
            for t in &topologies {
                let mut raw: RawScenario = toml::from_str(source).expect("read once already");
                overrides::apply(&ctx, &mut raw, overrides, file_lines).map_err(located)?;
                match validate(&ctx, path, raw, Some(t), &spent).map_err(located)? {
                    // Each part keeps the text, the flags and its topology, so that a study
                    // builds its structure again as the parse built it.
                    Validated::One(v) => variants.push(Scenario {
                        source: source.to_string(),
                        overrides: overrides.to_vec(),
                        topology: Some(t.clone()),
                        ..*v
                    }),
                    Validated::Split(_) => unreachable!("a topology's scenario is not split again"),
                }
            }
            pattern_sweep(variants)
        }
    };
    sc.source = source.to_string();
    sc.overrides = overrides.to_vec();
    Ok(sc)
}

/// The scenario of a sweep over a topology parameter: the first topology's, with every
/// topology's points, and the topologies to run.
fn pattern_sweep(mut variants: Vec<Scenario>) -> Scenario {
    let mut sc = variants[0].clone();
    let continuation = matches!(sc.actuation, Actuation::Points { continuation: true, .. });
    let points = variants
        .iter()
        .flat_map(|v| match &v.actuation {
            Actuation::Points { points, .. } => points.clone(),
            Actuation::Schedule { .. } => Vec::new(),
        })
        .collect();
    sc.actuation = Actuation::Points { points, continuation };
    sc.skipped_points = variants.iter_mut().flat_map(|v| std::mem::take(&mut v.skipped_points)).collect();
    sc.topologies = variants;
    sc
}

/// A validated scenario, or the topologies a sweep over a pattern's parameter asks for.
enum Validated {
    One(Box<Scenario>),
    Split(Vec<Topology>),
}

/// One structure of a sweep over a topology parameter: the parameters its patterns are
/// expanded with, and the points settled with it.
#[derive(Clone, Debug)]
struct Topology {
    params: Values,
    points: Vec<Values>,
    /// The topology parameters, each set to its value here as `--set` would.
    used: Vec<String>,
}

/// The points grouped by the values of the topology parameters `used` (in grid order; one
/// group when the sweep leaves them alone, none when no pattern reads a parameter).
fn topologies(
    table: &crate::file_model::params::ParamTable,
    params: &Values,
    actuation: &Actuation,
    used: &[String],
) -> Vec<Topology> {
    if used.is_empty() {
        return Vec::new(); // no pattern reads a parameter: one structure serves every point
    }
    let mut groups: Vec<Topology> = Vec::new();
    let mut index: std::collections::HashMap<Vec<u64>, usize> = std::collections::HashMap::new();
    for p in actuation.all_inputs() {
        let set = params::params_at(table, params, p);
        let key: Vec<u64> = used.iter().map(|k| set.get(k).copied().unwrap_or(f64::NAN).to_bits()).collect();
        match index.get(&key) {
            Some(&g) => groups[g].points.push(p.clone()),
            None => {
                index.insert(key, groups.len());
                groups.push(Topology { params: set, points: vec![p.clone()], used: used.to_vec() });
            }
        }
    }
    groups
}

/// A topology's own points, or the parts a scenario splits into: the topologies of a sweep over
/// a pattern's parameter, or one motion per point (None: one scenario).
fn split(raw: &RawScenario, s: &mut Sections, topology: Option<&Topology>, used: &[String]) -> Option<Vec<Topology>> {
    if let Some(t) = topology {
        let continuation = matches!(s.actuation, Actuation::Points { continuation: true, .. });
        s.actuation = Actuation::Points { points: t.points.clone(), continuation };
        return None;
    }
    let parts = match &raw.motion {
        Some(_) => motion_points(&s.param_table, &s.params, &s.actuation, used),
        None => topologies(&s.param_table, &s.params, &s.actuation, used),
    };
    // One part whose topology parameters differ from the file's (a grid of one point over n)
    // is a structure of its own too: expanded with the file's n it had been judged at another.
    let differs = |t: &Topology| t.used.iter().any(|k| t.params.get(k) != s.params.get(k));
    (parts.len() > 1 || parts.first().is_some_and(differs)).then_some(parts)
}

/// A motion run over several points (a grid or points of inputs or parameters): one motion
/// per point, each validated on its own with its point's parameters (its displacement, its
/// formulas and, where a pattern reads a parameter, its structure), run one after the other
/// and joined as a topology sweep's are. Waypoints are one motion (empty).
fn motion_points(
    table: &crate::file_model::params::ParamTable,
    params: &Values,
    actuation: &Actuation,
    used: &[String],
) -> Vec<Topology> {
    let Actuation::Points { points, .. } = actuation else { return Vec::new() };
    let each = |p: &Values| Topology {
        params: params::params_at(table, params, p),
        points: vec![p.clone()],
        used: used.to_vec(),
    };
    points.iter().map(each).collect()
}

/// Expands the file's patterns (`repeat.rs`, `for_each.rs`) with the parameters of
/// `topology`, or the file's own; returns the parameters their ranges and templates read.
fn expand_patterns(
    ctx: &Ctx,
    raw: &mut RawScenario,
    topology: Option<&Topology>,
    spent: &std::rc::Rc<std::cell::Cell<usize>>,
) -> Result<Vec<String>, ScenarioError> {
    // A parameter's error first: templates read with no parameters would report it elsewhere
    // (a NaN given by `--set k=nan` had been reported at a range of the structure).
    let params = match topology {
        Some(t) => {
            for (k, p) in raw.params.iter_mut().filter(|(k, _)| t.used.contains(k.get_ref())) {
                p.get_mut().value = number::Num::Value(t.params[k.get_ref()]);
            }
            t.params.clone()
        }
        None => number::param_values(ctx, &raw.params)?,
    };
    let env = pattern::Env::new(&params, spent);
    if topology.is_some() {
        // Each structure of a topology sweep reads the file's text again.
        env.spend(ctx.source.len()).map_err(|e| ctx.err(&raw.actuation, e.message))?;
    }
    if let Some(s) = &mut raw.structure {
        repeat::expand(ctx, s.get_mut(), &env)?;
    }
    for_each::expand_model(ctx, raw, &env)?;
    let used = env.used.borrow().iter().cloned().collect();
    Ok(used)
}

/// Largest number of settle points a scenario may ask for.
pub const MAX_POINTS: usize = 1_000_000;

/// Every expected value that is an expression of the parameters and inputs (a joint probe's
/// stiffness, the model's predictions and frequencies), evaluated at every settle point: a
/// comparison with a value that is not a number could not fail.
fn closed_forms(
    ctx: &Ctx,
    raw: &RawScenario,
    probe: Option<&Probe>,
    model: Option<&crate::file_model::spec::ModelSpec>,
    table: &crate::file_model::params::ParamTable,
    params: &Values,
    actuation: &Actuation,
) -> Result<(), ScenarioError> {
    let at_point = |p: &Values| params::params_at(table, params, p);
    checks::probe_expected(ctx, &raw.probe, probe, &at_point, actuation)?;
    match model {
        Some(spec) => file_model::closed_forms_at_points(ctx, raw, spec, &at_point, actuation),
        None => Ok(()),
    }
}

/// The structures a scenario builds: at its first point, and at every other set of parameters
/// its points ask for.
struct Structures<'a> {
    sets: &'a [Values],
    first: &'a Values,
    start: &'a Values,
    actuation: &'a Actuation,
}

impl Structures<'_> {
    /// Builds and checks each structure (`physical`); the first one, whose joints also decide
    /// the default Newton damping schedule where `[sim]` does not.
    fn check(
        &self,
        ctx: &Ctx,
        raw: &RawScenario,
        m: &dyn Mechanism,
        sim: &mut SimSettings,
        custom: bool,
    ) -> Result<crate::structure::Structure, ScenarioError> {
        let inputs = self.actuation.first_inputs();
        let first = physical::first_structure(ctx, raw, m, self.first, self.start, inputs)?;
        physical::physical(ctx, raw, m, &first, sim)?;
        if raw.sim.newton_damping.is_none() {
            sim.newton_damping = sim::default_newton_damping(custom, &first);
        }
        for set in self.sets.iter().skip(1) {
            let s = physical::first_structure(ctx, raw, m, set, self.start, inputs)?;
            physical::physical(ctx, raw, m, &s, sim)?;
        }
        Ok(first)
    }
}

/// The sections of a scenario read before its structures are built.
struct Sections {
    params: Values,
    param_table: crate::file_model::params::ParamTable,
    sim: SimSettings,
    settle: SettleCriteria,
    start: Values,
    actuation: Actuation,
    skipped_points: Vec<(Values, String)>,
}

/// What a scenario judges, read before its structures are built.
struct Judged {
    checks: Vec<Check>,
    model: Option<crate::file_model::spec::ModelSpec>,
    stability_perturbation: Option<f64>,
    expected_stability: ExpectedStability,
    record: Option<PathBuf>,
    min_agreement_percent: Option<f64>,
}

/// The values of a scenario whose shape serde has read, section by section. The built-in
/// mechanism is found once; a custom one is the file's own structure, used as it is and then
/// with its variants at every set of parameters the points ask for.
fn validate(
    ctx: &Ctx,
    path: &Path,
    mut raw: RawScenario,
    topology: Option<&Topology>,
    spent: &std::rc::Rc<std::cell::Cell<usize>>,
) -> Result<Validated, ScenarioError> {
    if raw.name.get_ref().trim().is_empty() {
        return Err(ctx.err(&raw.name, "name must not be empty"));
    }
    let topology_params = expand_patterns(ctx, &mut raw, topology, spent)?;
    names::names(ctx, &raw)?;
    let custom = mechanism::custom(ctx, &raw)?;
    let builtin = if custom.is_some() { None } else { Some(mechanism::builtin(ctx, &raw)?) };
    let mut s = sections(ctx, &raw, mechanism::of(custom.as_ref(), builtin.as_deref()))?;
    if let Some(split) = split(&raw, &mut s, topology, &topology_params) {
        return Ok(Validated::Split(split));
    }
    let judged = judged(ctx, &raw, mechanism::of(custom.as_ref(), builtin.as_deref()), &s, custom.is_some())?;
    // Every set of parameters the points ask for (a sweep over parameters): the custom
    // structure resolved with each, and each structure checked as the first point's is.
    let parameter_sets = mechanism::parameter_sets(ctx, &raw, &s.param_table, &s.params, &s.actuation)?;
    let custom = custom.map(|c| mechanism::with_variants(ctx, &raw, c, &s.params, &parameter_sets)).transpose()?;
    let m = mechanism::of(custom.as_ref(), builtin.as_deref());
    let first_params = params::params_at(&s.param_table, &s.params, s.actuation.first_inputs());
    let structures =
        Structures { sets: &parameter_sets, first: &first_params, start: &s.start, actuation: &s.actuation };
    let first = structures.check(ctx, &raw, m, &mut s.sim, custom.is_some())?;
    let interference = interference::interference(ctx, &raw.interference, m, &first_params, &first)?;
    let probe = checks::probe(ctx, m, &raw.probe, &first, &s.params)?;
    let prestress = prestress::prestress(ctx, &raw.prestress, &first, custom.is_some())?;
    let (checks, model) = (&judged.checks, judged.model.as_ref());
    closed_forms(ctx, &raw, probe.as_ref(), model, &s.param_table, &s.params, &s.actuation)?;
    let solved = judged.model.as_ref().and_then(|m| m.energy.as_ref()).map(|e| e.solved_names()).unwrap_or_default();
    let motion = motion::motion(ctx, &raw, s.sim.dt_s, (m, &first), (&first_params, &solved), &s.actuation)?;
    let commands = m.commands(&first_params, s.actuation.first_inputs());
    let fidelity = fidelity::fidelity(ctx, &raw, &fidelity::FirstPoint::new(&first, commands, &s, motion.is_some()))?;
    let has_probe = probe.as_ref().is_some_and(|p| p.tolerance.is_some());
    let parts =
        expect::Parts { checks, model, probe: has_probe, motion: motion.as_ref(), prestress: prestress.is_some() };
    let expect = raw.expect.as_ref().map(|e| expect::expectation(ctx, e, &parts)).transpose()?;
    let unseen_params = custom.as_ref().map(|c| c.unseen(&swept(&s))).unwrap_or_default();
    let certify = certify_section(ctx, &raw)?;
    Ok(Validated::One(Box::new(Scenario {
        file: path.to_path_buf(),
        source: ctx.source.to_string(),
        overrides: Vec::new(),
        name: raw.name.into_inner(),
        description: raw.description,
        mechanism: m.name().into(),
        params: s.params,
        param_table: s.param_table,
        sim: s.sim,
        settle: s.settle,
        start: s.start,
        actuation: s.actuation,
        checks: judged.checks,
        stability_perturbation: judged.stability_perturbation,
        expected_stability: judged.expected_stability,
        probe,
        record: judged.record,
        interference,
        min_agreement_percent: judged.min_agreement_percent,
        skipped_points: s.skipped_points,
        custom,
        expect,
        model: judged.model,
        motion,
        topologies: Vec::new(),
        topology_params,
        topology: None,
        unseen_params,
        prestress,
        fidelity,
        relaxed: Vec::new(),
        certify,
    })))
}

/// `[certify]`: whether the settle points are certified; refused in a motion, which has no
/// settled equilibrium.
fn certify_section(ctx: &Ctx, raw: &RawScenario) -> Result<bool, ScenarioError> {
    let Some(section) = &raw.certify else { return Ok(false) };
    if section.get_ref().enabled && raw.motion.is_some() {
        return Err(ctx.err(section, "[certify] in a motion: a motion has no settled equilibrium to certify; certify its settle points in a scenario without [motion]"));
    }
    Ok(section.get_ref().enabled)
}

/// The parameters, settings, start and actuation of a scenario of the mechanism `m`.
fn sections(ctx: &Ctx, raw: &RawScenario, m: &dyn Mechanism) -> Result<Sections, ScenarioError> {
    let params = params::params(ctx, m, &raw.params)?;
    let param_table = number::param_table(ctx, &raw.params)?;
    let sim = sim::sim(ctx, &raw.sim)?;
    let settle = sim::settle(ctx, &raw.settle)?;
    let start = params::start(ctx, m, &raw.start)?;
    let (actuation, skipped_points) = actuation::actuation(ctx, m, &param_table, &params, &raw.actuation)?;
    Ok(Sections { params, param_table, sim, settle, start, actuation, skipped_points })
}

/// The checks, the file's model, the stability test, the recording and the workspace
/// agreement of a scenario of the mechanism `m` (`custom`: its own structure); an error when
/// it judges nothing.
fn judged(
    ctx: &Ctx,
    raw: &RawScenario,
    m: &dyn Mechanism,
    s: &Sections,
    custom: bool,
) -> Result<Judged, ScenarioError> {
    bounds::bounds(ctx, raw, &s.sim, &s.settle, &s.actuation)?;
    let checks = checks::checks(ctx, m, &raw.checks, raw.probe.is_some())?;
    let model = file_model::model(ctx, raw, m, &s.params, &s.start, &s.actuation)?;
    // A custom structure is checked by its settling and force balance even without [[checks]].
    if checks.is_empty() && raw.probe.is_none() && !custom && model.is_none() && raw.motion.is_none() {
        return Err(ctx
            .err_at(0, "the scenario checks nothing: add at least one [[checks]] entry (quantity, tolerance)".into()));
    }
    let has_energy = model.as_ref().is_some_and(|m| m.energy.is_some());
    Ok(Judged {
        stability_perturbation: checks::stability(ctx, &raw.stability)?,
        expected_stability: checks::expected_stability(ctx, &raw.stability, &s.actuation, has_energy)?,
        record: record::record(ctx, &raw.record)?,
        min_agreement_percent: checks::workspace(ctx, &raw.workspace)?,
        checks,
        model,
    })
}

/// The parameters the points set (a sweep over them), in the order they first appear.
fn swept(s: &Sections) -> Vec<String> {
    let mut swept: Vec<String> = Vec::new();
    for k in s.actuation.all_inputs().into_iter().flat_map(|p| p.keys()) {
        if s.params.contains_key(k) && !swept.contains(k) {
            swept.push(k.clone());
        }
    }
    swept
}
