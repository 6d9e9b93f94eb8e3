//! Reports: a readable table on stdout, one JSON document for machines, and the exit code
//! (0 every check passed, 1 a check failed, 2 bad input).

pub mod certificate;
pub mod equilibrium;
pub mod fit;
pub mod modes;
pub mod sensitivity;
pub mod verdict;

use crate::mechanisms::{Finding, Values};
use serde::Serialize;

pub const EXIT_PASS: i32 = 0;
pub const EXIT_FAIL: i32 = 1;
pub const EXIT_BAD_INPUT: i32 = 2;

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Report {
    pub scenarios: Vec<ScenarioReport>,
}

#[derive(Clone, Debug, Serialize, PartialEq, Default)]
pub struct ScenarioReport {
    pub name: String,
    pub file: String,
    pub mechanism: String,
    pub passed: bool,
    /// The parts of the verdict that failed (empty when `passed`), named as `[expect] failing`
    /// names them.
    pub failures: Vec<crate::report::verdict::Failure>,
    /// What the scenario declares it must do (`[expect]`), if it declares it.
    pub expect: Option<crate::report::verdict::Expectation>,
    /// Whether the run did what `[expect]` declares (absent without `[expect]`).
    pub as_expected: Option<bool>,
    pub params: Values,
    pub settle: SettleSummary,
    pub checks: Vec<CheckReport>,
    pub points: Vec<PointReport>,
    pub stiffness_probe: Option<ProbeReport>,
    /// Every interval of ticks in which a cable was slack.
    pub slack_intervals: Vec<SlackInterval>,
    /// Whether the structure kept its self-stress at the settle points (absent where it is
    /// not judged: no `[prestress]` and no custom structure with cables).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prestress: Option<PrestressReport>,
    /// Analytic against dynamic workspace classification (mechanisms with cables).
    pub workspace: Option<WorkspaceAgreement>,
    /// Grid points dropped as outside the mechanism's domain (`actuation.skip_outside`).
    pub skipped_points: usize,
    /// The interference checks (on unless the scenario turns them off; absent only when the
    /// run stopped before its observers started).
    pub interference: Option<InterferenceReport>,
    pub findings: Vec<FindingReport>,
    /// Along a scheduled trajectory: the range of every simulated quantity over its ticks
    /// (for example the smallest |det J| on a path that must avoid singularities).
    pub trajectory_ranges: std::collections::BTreeMap<String, QuantityRange>,
    /// Why the run stopped early (divergence, interruption), if it did.
    pub error: Option<ReportedError>,
    /// What the run went on without (a live viewer nobody runs), for the command line to say
    /// (absent from the JSON when there is nothing).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The file's own model: its `[[predictions]]` and `[[equations]]`, judged (absent from the
    /// JSON when the file states none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub model_checks: Vec<ModelCheckReport>,
    /// Which kind of path the run took: "physical" (no step took a settle accelerator; in a
    /// motion run, no step of its motion) or "accelerated" (the static relaxation or the
    /// Newton damping schedule acted: a quasi-static or accelerated settle, whose path is not
    /// the dynamics').
    pub path: PathKind,
    /// Steps of the whole run that took a settle accelerator (a motion run's settle to its
    /// start included).
    pub accelerated_steps: u64,
    /// A motion run (`[motion]`): what ran, and the frequencies measured from it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<MotionReport>,
    /// A sweep over a topology parameter: each structure the run rebuilt, with the parameter
    /// values and the structure's size (absent when one structure served every point).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub topologies: Vec<String>,
    /// Swept parameters that change nothing in the file's structure: only its formulas see
    /// them (a structure drawn for one value, swept over others).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unseen_params: Vec<String>,
}

/// An error kept in a report as its own kind (a `run::RunError`, an
/// `observers::lagrangian::LagrangianError`, ...: [`ReportedError::get`] and `downcast_ref`
/// recover it), written as its message. Two are equal when they say the same.
#[derive(Clone, Debug)]
pub struct ReportedError(std::sync::Arc<dyn std::error::Error + Send + Sync>);

impl ReportedError {
    /// Keeps `error` as it is.
    pub fn new(error: impl std::error::Error + Send + Sync + 'static) -> Self {
        ReportedError(std::sync::Arc::new(error))
    }

    /// The error as it was reported.
    pub fn get(&self) -> &(dyn std::error::Error + Send + Sync + 'static) {
        self.0.as_ref()
    }
}

impl std::fmt::Display for ReportedError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for ReportedError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

impl PartialEq for ReportedError {
    fn eq(&self, other: &Self) -> bool {
        self.to_string() == other.to_string()
    }
}

impl Serialize for ReportedError {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Which kind of path a run took (see [`ScenarioReport::path`]).
#[derive(Clone, Copy, Debug, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum PathKind {
    /// Only the physical dynamics: the path is a trajectory of the structure.
    Physical,
    /// A settle accelerator acted: the path reaches equilibria but is not a trajectory.
    #[default]
    Accelerated,
}

impl PathKind {
    pub fn name(self) -> &'static str {
        match self {
            PathKind::Physical => "physical",
            PathKind::Accelerated => "accelerated",
        }
    }
}

/// A motion run: the physical dynamics for a stated time.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct MotionReport {
    /// "drawn" or "settled".
    pub start: crate::settings::MotionStart,
    pub duration_s: f64,
    pub dt_s: f64,
    /// Steps the motion asks for, and the steps it took (fewer when it stopped early).
    pub steps: u64,
    pub steps_taken: u64,
    /// The tick the motion started after (its time origin: the model's t = 0).
    pub start_tick: u64,
    /// The displaced joint, its displacement [rad or m] and start rate [rad/s or m/s].
    pub coordinate: Option<String>,
    pub displacement: f64,
    pub rate: f64,
    /// Steps of the motion that took a settle accelerator (0: the motion is physical).
    pub accelerated_steps: u64,
    /// Every joint's damping was released for the motion (`[motion] undamped`).
    pub undamped: bool,
    pub frequencies: Vec<FrequencyReport>,
    /// The file's Lagrangian model integrated beside the motion (`[energy.trajectory]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lagrangian: Option<LagrangianReport>,
    /// The inputs followed in time and how (`[actuation] waypoints` or `[motion] inputs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub driven: Option<String>,
    /// How the judged motion was made: "leapfrog from a half step" (rapier's steps), or
    /// extrapolated over the time step (`run/levels.rs`).
    pub integration: String,
    /// In a motion judged extrapolated: each quantity's largest error estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extrapolation: Option<ExtrapolationReport>,
}

/// A motion judged extrapolated over the time step: the steps combined, each quantity's largest
/// estimate of the simulation's own error over the motion, and where the motion stopped being
/// smooth in time (the estimates after it do not hold).
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct ExtrapolationReport {
    /// The time steps combined \[s\]: h, h/2, h/4 (and h/8, h/16 where a target asked for more).
    pub steps_s: Vec<f64>,
    /// The judged motion's order in the step: 2 (levels - 1).
    pub order: i32,
    /// The largest distance of any judged node from where it was at the motion's first tick \[m\].
    pub amplitude_m: f64,
    /// The error target, a fraction of the amplitude: the file's `target_error`, or
    /// `settings::DEFAULT_TARGET_ERROR`.
    pub target_error: f64,
    /// Whether the largest estimate of the node positions is at most the target times the
    /// amplitude.
    pub target_met: bool,
    /// Each quantity's largest error estimate over the motion (its unit).
    pub largest_estimate: std::collections::BTreeMap<String, f64>,
    /// The first tick whose step saw a cable change between slack and taut (the levels disagree
    /// on it, or it changed since the tick before), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_smooth_from_tick: Option<u64>,
}

/// The key of the largest estimate over every node coordinate in `largest_estimate`.
pub const NODE_POSITIONS: &str = "node positions";

impl ExtrapolationReport {
    /// The largest error estimate of the judged node positions over the motion \[m\].
    pub fn node_estimate_m(&self) -> f64 {
        self.largest_estimate.get(NODE_POSITIONS).copied().unwrap_or(0.0)
    }
}

/// How a motion judged extrapolated was judged, and how far its node positions may be off.
fn judged_line(x: &ExtrapolationReport) -> String {
    let estimate = x.node_estimate_m();
    let rough = x
        .not_smooth_from_tick
        .map_or(String::new(), |t| format!("; not smooth from tick {t}: the estimate does not hold after it"));
    format!(
        "judged: extrapolated over {} levels (order {}); node positions' error estimate {estimate:.1e} m, {} the target {:.0e} of the amplitude {:.3e} m{rough}",
        x.steps_s.len(),
        x.order,
        if x.target_met { "within" } else { "above" },
        x.target_error,
        x.amplitude_m
    )
}

/// A motion against the file's Lagrangian model, compared tick by tick
/// (`observers::lagrangian`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct LagrangianReport {
    /// The integrator, its error control and how its start is read from the motion.
    pub method: String,
    /// Where the model started (`[energy.trajectory] start`): "samples" (from the motion's
    /// first three samples, at t = 1.5 dt) or "stated" (the file's initial condition, t = 0).
    pub start: String,
    /// The model's start: the motion's time \[s\], the coordinates [m or rad] and rates there.
    pub start_time_s: f64,
    pub start_coordinates: Vec<f64>,
    pub start_rates: Vec<f64>,
    /// Accepted steps of the integrator.
    pub integrator_steps: usize,
    /// Why the model could not be compared (every coordinate then fails, its error infinite).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ReportedError>,
    /// "period" where the trajectories' frequencies are measured by their periods
    /// (`[energy.trajectory] measure`); absent: by the cosine fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measure: Option<String>,
    pub coordinates: Vec<LagrangianCoordinateReport>,
}

/// One `[energy]` coordinate of the simulated motion against the Lagrangian model.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct LagrangianCoordinateReport {
    pub name: String,
    /// "length" \[m\], "angle" [rad, wrapped] or "relative".
    pub class: String,
    /// The largest and the rms error over the ticks compared, in the class.
    pub max_error: f64,
    pub rms_error: f64,
    pub tolerance: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rms_tolerance: Option<f64>,
    pub passed: bool,
    pub ticks_compared: usize,
    /// The frequency fitted to the model's trajectory, and to the simulated one (corrected for
    /// symplectic Euler's dispersion) [rad/s]; NaN where the motion is no oscillation.
    pub model_omega_rad_per_s: f64,
    pub simulated_omega_rad_per_s: f64,
}

/// A natural frequency measured from a motion run's free vibration and its prediction.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FrequencyReport {
    pub name: String,
    /// The joint whose coordinate was fitted.
    pub coordinate: String,
    /// "cosine" (a least-squares cosine fit) or "period" (zero crossings of the rate).
    pub measure: String,
    pub predicted_rad_per_s: f64,
    /// The structure's own modal analysis at the motion's start, for a frequency fitted to a
    /// mode (`mode = N`) that also has a formula: the mode's omega [rad/s], judged against the
    /// formula too (the third of the three values a frequency claim compares).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modal_rad_per_s: Option<f64>,
    /// |modal - predicted| / predicted, where there is a modal value beside a formula.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modal_error: Option<f64>,
    /// In a motion judged extrapolated over the time step: the estimate of the simulation's own
    /// error in the measured frequency, relative (the same measure on the state one level
    /// rougher, their difference over the levels' estimate divisor: 2^4 - 1 at fourth order).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulation_error: Option<f64>,
    /// The measure's own error over the record, relative: the largest difference between the
    /// measure on either half of the record and on the whole.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measure_error: Option<f64>,
    /// The frequency of the same motion at half the amplitude, run alone after it, corrected
    /// as `corrected_rad_per_s` is \[rad/s\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub half_amplitude_rad_per_s: Option<f64>,
    /// The amplitude's own shift of the corrected frequency from its zero-amplitude limit,
    /// relative and signed: 4/3 (corrected - half amplitude) / corrected (a shift c A^2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude_shift: Option<f64>,
    /// The corrected frequency's error bar against a small-amplitude (linear) prediction,
    /// relative: simulation_error + measure_error + |amplitude_shift|, those that were made.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_bar: Option<f64>,
    /// What the error bar leaves out, and why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub error_bar_leaves_out: Vec<String>,
    /// The measured angular frequency of the simulated samples, w_d [rad/s].
    pub measured_rad_per_s: f64,
    /// Corrected for symplectic Euler's dispersion: w = (2 / dt) sin(w_d dt / 2) [rad/s].
    pub corrected_rad_per_s: f64,
    /// |corrected - predicted| / predicted: what the tolerance applies to.
    pub error: f64,
    /// |measured - predicted| / predicted: the error without the correction.
    pub uncorrected_error: f64,
    pub tolerance: f64,
    pub passed: bool,
    /// The cosine fit (with either measure): offset c, amplitude A and the rms of its residual
    /// [rad or m], samples fitted.
    pub fit_offset: f64,
    pub fit_amplitude: f64,
    pub fit_rms_residual: f64,
    pub samples: usize,
    /// How it was measured.
    pub method: String,
}

/// A measured frequency against its prediction (and the modal analysis where it is judged too).
fn frequency_line(f: &FrequencyReport) -> String {
    let modal = match (f.modal_rad_per_s, f.modal_error) {
        (Some(w), Some(e)) => format!(", modal {w:.9} (error {e:.3e})"),
        _ => String::new(),
    };
    let modal = match f.simulation_error {
        Some(e) => format!("{modal}, simulation error {e:.1e}"),
        None => modal,
    };
    let modal = match f.error_bar {
        Some(e) => format!("{modal}, error bar {e:.1e}{}", error_bar_parts(f)),
        None => modal,
    };
    format!(
        "frequency {} ({}): predicted {:.9} rad/s, measured {:.9}, corrected {:.9}: error {:.3e} (uncorrected {:.3e}){modal}, tolerance {:.1e}  {}",
        f.name,
        if f.measure == "period" { "period" } else { "cosine fit" },
        f.predicted_rad_per_s,
        f.measured_rad_per_s,
        f.corrected_rad_per_s,
        f.error,
        f.uncorrected_error,
        f.tolerance,
        if f.passed { "pass" } else { "FAIL" }
    )
}

/// The error bar's parts beyond the simulation's error, and what it leaves out.
fn error_bar_parts(f: &FrequencyReport) -> String {
    let mut parts = Vec::new();
    if let Some(e) = f.measure_error {
        parts.push(format!("measure {e:.1e}"));
    }
    if let Some(e) = f.amplitude_shift {
        parts.push(format!("amplitude shift {e:+.1e}"));
    }
    if !f.error_bar_leaves_out.is_empty() {
        parts.push(format!("leaves out {}", f.error_bar_leaves_out.join(", ")));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!(" ({})", parts.join("; "))
    }
}

/// The note under a table of checks in a motion run, whose transient cells are "-".
const NOT_TRANSIENT_IN_MOTION: &str = "   (a motion run: checks, equations and the energy model are judged at its start point; their errors during the motion mean nothing and are not shown: \"-\")\n";

/// The transient cells of a table row: the errors, or "-" where they mean nothing.
fn transient_cells(show: bool, max: f64, rms: f64) -> (String, String) {
    if show {
        (format!("{max:.3e}"), format!("{rms:.3e}"))
    } else {
        ("-".into(), "-".into())
    }
}

/// The motion against the Lagrangian model: one line per coordinate.
fn table_lagrangian(l: &LagrangianReport, out: &mut String) {
    out.push_str(&format!(
        "   lagrangian model from t = {:.6} s, started from {} ({} integrator steps){}\n",
        l.start_time_s,
        match l.start.as_str() {
            "stated" => "the file's initial condition (start = \"stated\")",
            _ => "the motion's first samples (start = \"samples\")",
        },
        l.integrator_steps,
        l.error.as_ref().map_or(String::new(), |e| format!(": {e}"))
    ));
    for c in &l.coordinates {
        out.push_str(&format!(
            "   trajectory {}: max error {:.3e} (tolerance {:.1e}), rms {:.3e}{} over {} ticks; omega model {:.9}, simulated {:.9} rad/s  {}\n",
            c.name,
            c.max_error,
            c.tolerance,
            c.rms_error,
            c.rms_tolerance.map_or(String::new(), |t| format!(" (tolerance {t:.1e})")),
            c.ticks_compared,
            c.model_omega_rad_per_s,
            c.simulated_omega_rad_per_s,
            if c.passed { "pass" } else { "FAIL" }
        ));
    }
}

/// A `[[predictions]]` or `[[equations]]` entry of the scenario file's model, judged at every
/// settle point (the verdict) and at every tick (transient errors, reported only).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ModelCheckReport {
    /// "prediction", "equation", "energy" or "frequency".
    pub kind: String,
    pub name: String,
    /// A prediction's error class (length \[m\], angle [rad, wrapped], relative); "residual" for
    /// an equation (|residual|); "coordinates" for the energy model (the largest coordinate
    /// difference from the settled state to the stationary point it landed on, infinite when
    /// that point is not a minimum); "relative" for a frequency of the dynamic model.
    pub class: String,
    /// Largest error over the settle points (infinite at a point that did not settle).
    pub max_error: f64,
    pub tolerance: f64,
    pub passed: bool,
    pub points_compared: usize,
    pub transient_max_error: f64,
    pub transient_rms_error: f64,
    pub ticks_compared: u64,
    /// A prediction in a motion run, judged over the motion's ticks: its rms error there (the
    /// largest is `max_error`), the rms tolerance if the file gives one, and the ticks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rms_error: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rms_tolerance: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion_ticks: Option<u64>,
    /// In a motion judged extrapolated over the time step: the largest estimate of the
    /// simulation's own error in what the check compares (its class), over the motion. A
    /// tolerance below it asks for more than the run resolves (`warnings` says so).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulation_error: Option<f64>,
}

impl ModelCheckReport {
    /// A check judged at settle points only (no per-tick errors): its largest error over the
    /// `points` compared against `tolerance`; it passes when at least one point was compared.
    pub fn at_settle_points(
        kind: &str,
        name: &str,
        class: &str,
        max_error: f64,
        tolerance: f64,
        points: usize,
    ) -> Self {
        ModelCheckReport {
            kind: kind.into(),
            name: name.into(),
            class: class.into(),
            max_error,
            tolerance,
            passed: points > 0 && max_error <= tolerance,
            points_compared: points,
            transient_max_error: 0.0,
            transient_rms_error: 0.0,
            ticks_compared: 0,
            rms_error: None,
            rms_tolerance: None,
            motion_ticks: None,
            simulation_error: None,
        }
    }

    /// Whether the check's tolerance is below what the run resolves: under the largest estimate
    /// of the simulation's own error.
    pub fn below_resolution(&self) -> bool {
        self.simulation_error.is_some_and(|e| self.tolerance < e)
    }

    /// The failure this entry is when it does not pass (`prediction:NAME`, `equation:NAME`).
    pub fn failure(&self) -> crate::report::verdict::Failure {
        use crate::report::verdict::Failure;
        match self.kind.as_str() {
            "equation" => Failure::Equation(self.name.clone()),
            "energy" => Failure::Energy,
            "frequency" => Failure::Frequency(self.name.clone()),
            _ => Failure::Prediction(self.name.clone()),
        }
    }
}

/// Smallest, largest and smallest absolute value of a quantity over the ticks of a trajectory.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct QuantityRange {
    pub min: f64,
    pub max: f64,
    pub min_abs: f64,
}

impl QuantityRange {
    pub fn of(v: f64) -> Self {
        QuantityRange { min: v, max: v, min_abs: v.abs() }
    }

    pub fn include(&mut self, v: f64) {
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        self.min_abs = self.min_abs.min(v.abs());
    }
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
    /// How its error is measured, the one convention of `max_rel_error`, the transient
    /// `_rel_` errors and the table: "length / L", "angle \[rad\]" or "relative".
    pub convention: String,
    /// Largest error at the settle points, in the quantity's unit.
    pub max_abs_error: f64,
    /// Largest normalised error at the settle points (lengths / L, angles in rad, other
    /// quantities / |analytic|): what the tolerance applies to.
    pub max_rel_error: f64,
    pub tolerance: f64,
    pub passed: bool,
    /// Every tick, including transients (reported, not checked; in a motion run they include
    /// the motion's ticks, away from the settle point, and mean nothing: the table shows "-").
    pub transient_max_abs_error: f64,
    pub transient_rms_abs_error: f64,
    /// The same, normalised as `max_rel_error` is.
    pub transient_max_rel_error: f64,
    pub transient_rms_rel_error: f64,
    pub ticks_compared: u64,
    /// Settle points compared (points outside the analytic model's validity are not).
    pub points_compared: usize,
}

#[derive(Clone, Debug, Serialize, PartialEq, Default)]
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
    /// Kinetic energy left at the last tick of the settle \[J\] (what an unsettled point still had).
    pub final_kinetic_energy_j: f64,
    /// The analytic branch the dynamics landed on.
    pub branch: String,
    /// Stability from the perturbation test (None when not tested).
    pub stable: Option<bool>,
    /// Stability from the analytic model (sign of the stiffness) for the branch landed on.
    pub analytic_stable: Option<bool>,
    /// The stability the scenario expects here (`[stability] expect`), if it says.
    pub expected_stable: Option<bool>,
    pub slack_cables: Vec<String>,
    /// The nodes where a cable with friction is at its bound and slips ("CABLE at NODE").
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slipping: Vec<String>,
    /// Cables the analytic statics says are slack (mechanisms with cables only).
    pub expected_slack: Option<Vec<String>>,
    /// Whether the simulated slack set equals the analytic one.
    pub slack_agrees: Option<bool>,
    /// The cables' total tension at the settled state over their total tension at the drawn
    /// state (the share of the self-stress kept); None without cables or without a drawn
    /// tension.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prestress_fraction: Option<f64>,
    /// Whether the structure lost its self-stress here (`[prestress]`; None: not judged).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prestress_lost: Option<bool>,
    /// Outside the analytic model's validity (some cable slack): the distance of the settled
    /// state from the analytic point, over the length quantities \[m\].
    pub distance_from_analytic_m: Option<f64>,
    /// Settled, and every check within its tolerance at this point.
    pub within_tolerance: bool,
    /// Smallest strut clearance at the settled state \[m\] (with an `[interference]` section;
    /// None when no pair came within the margin).
    pub min_clearance_m: Option<f64>,
    /// No strut pair below the interference threshold at the settled state.
    pub interference_free: Option<bool>,
    /// The paper's printed values at this point, where it prints any (never checked).
    pub paper: Option<PaperValues>,
    /// The file's `[energy]` model at this point: its stationary points and which one the
    /// dynamics landed on (absent without one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy: Option<EnergyPointReport>,
    /// A motion run's natural frequencies measured from the motion that started here (a motion
    /// over several points has one motion per point; empty without `[[motion.frequencies]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frequencies: Vec<FrequencyReport>,
    /// With `run --certify`: the proof of the equilibrium here, or why there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certificate: Option<crate::certify::Certificate>,
    /// Each judged quantity's error here as its verdict measures it (a check's normalised
    /// error, a prediction's in its class, the probe's relative): what the table's point lines
    /// show (the JSON has them per check, prediction and probe).
    #[serde(skip)]
    pub errors: Values,
}

/// The stationary points of a file's energy model at one settle point.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EnergyPointReport {
    /// The coordinates read off the settled state.
    pub measured: Values,
    /// Every stationary point found (from the settled state and the scan), in that order.
    pub stationary: Vec<StationaryReport>,
    /// The index in `stationary` of the one nearest the settled state.
    pub landed: Option<usize>,
    /// Largest coordinate difference (angles wrapped) from the settled state to it.
    pub distance: f64,
    /// With a kinetic energy: the linearised modes of the file's dynamic model at the
    /// stationary point landed on (K v = omega^2 M v), omega ascending.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes: Option<Vec<ModelModeReport>>,
    /// The solved equilibrium that formulas may read, at the stationary point landed on: each
    /// coordinate, the potential's second derivatives `V_a_b` and, with a kinetic energy, the
    /// mass matrix's entries `M_a_b` (empty where no point was landed on).
    #[serde(skip_serializing_if = "Values::is_empty")]
    pub solved: Values,
}

/// One linearised mode of the file's dynamic model.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ModelModeReport {
    /// Eigenvalue of K v = omega^2 M v [rad^2/s^2] (negative: an unstable direction).
    pub omega_squared: f64,
    /// sqrt(omega_squared) [rad/s] (minus sqrt(-omega_squared) where it is negative).
    pub omega_rad_per_s: f64,
    /// omega / (2 pi) \[Hz\].
    pub frequency_hz: f64,
    /// The shape in the coordinates, scaled so that its largest component is +1.
    pub shape: Values,
}

/// One stationary point of an energy model.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct StationaryReport {
    pub coordinates: Values,
    /// Potential energy there.
    pub energy: f64,
    /// The Hessian's eigenvalues, ascending: the stiffnesses along its eigenvectors.
    pub eigenvalues: Vec<f64>,
    /// minimum, maximum, saddle or degenerate.
    pub kind: String,
}

/// A paper's own printed values at a point: its source (table, column) and the values.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PaperValues {
    pub source: String,
    pub values: Values,
}

/// Workspace classification, analytic against dynamic, over the points of a run whose
/// mechanism predicts slack cables: a point is in the static workspace analytically when no
/// cable is predicted slack, and by the dynamics when it settled with every cable taut and
/// every check within tolerance.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct WorkspaceAgreement {
    pub points: usize,
    pub analytic_inside: usize,
    pub simulated_inside: usize,
    pub agree: usize,
    pub agreement_percent: f64,
    /// Indices of the points where the two classifications differ.
    pub disagreements: Vec<usize>,
    /// The scenario's pass threshold, if it is a workspace sweep.
    pub min_agreement_percent: Option<f64>,
    /// With an `[interference]` section: the points inside by the dynamics whose struts are
    /// clear of each other, and their share of the inside points.
    pub inside_interference_free: Option<usize>,
    pub interference_free_percent_of_inside: Option<f64>,
}

impl WorkspaceAgreement {
    pub fn from_points(points: &[PointReport]) -> Option<Self> {
        let classified: Vec<&PointReport> = points.iter().filter(|p| p.expected_slack.is_some()).collect();
        if classified.is_empty() {
            return None;
        }
        let analytic = |p: &PointReport| p.expected_slack.as_ref().is_some_and(|e| e.is_empty());
        let simulated = |p: &PointReport| p.settled && p.slack_cables.is_empty() && p.within_tolerance;
        let disagreements: Vec<usize> =
            classified.iter().filter(|p| analytic(p) != simulated(p)).map(|p| p.index).collect();
        let n = classified.len();
        let inside: Vec<&&PointReport> = classified.iter().filter(|p| simulated(p)).collect();
        let free = inside.iter().filter(|p| p.interference_free == Some(true)).count();
        let checked = inside.iter().any(|p| p.interference_free.is_some());
        Some(WorkspaceAgreement {
            points: n,
            analytic_inside: classified.iter().filter(|p| analytic(p)).count(),
            simulated_inside: classified.iter().filter(|p| simulated(p)).count(),
            agree: n - disagreements.len(),
            agreement_percent: 100.0 * (n - disagreements.len()) as f64 / n as f64,
            disagreements,
            min_agreement_percent: None,
            inside_interference_free: checked.then_some(free),
            interference_free_percent_of_inside: (checked && !inside.is_empty())
                .then(|| 100.0 * free as f64 / inside.len() as f64),
        })
    }
}

/// Member interference over the run (parry capsule distances).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct InterferenceReport {
    /// False when the scenario turned the checks off (`[interference] enabled = false`): then
    /// nothing was measured.
    pub enabled: bool,
    /// Cables and springs were checked too.
    pub tendons: bool,
    /// Member segments checked (struts, then cables and springs; a clustered cable's each
    /// segment): the members themselves unless a cable runs through inner nodes.
    pub members_checked: usize,
    /// Smallest clearance seen over the run \[m\] (None: no pair ever came within the margin).
    #[serde(rename = "min_clearance")]
    pub min_clearance_m: Option<f64>,
    pub closest_pair: Option<[String; 2]>,
    pub closest_points: Option<[[f64; 3]; 2]>,
    pub tick_of_min: Option<u64>,
    /// Member pairs checked every tick (all pairs minus those attached by construction or excluded).
    pub pairs_checked: usize,
    pub ticks_checked: u64,
    pub threshold_m: f64,
    pub margin_m: f64,
    /// Violations are reported without failing the run.
    pub informative: bool,
    pub passed: bool,
    pub violations: Vec<InterferenceViolation>,
    /// Every pair that came within the margin, in pair order: its smallest clearance over the
    /// run. Past `REPORTED_PAIRS_MAX` pairs, only that many, the closest.
    pub pairs: Vec<PairClearanceReport>,
    /// How many pairs came within the margin, when `pairs` lists only the closest of them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pairs_within_margin: Option<usize>,
}

/// The smallest clearance of one strut pair over the run.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PairClearanceReport {
    pub pair: [String; 2],
    /// "strut", "cable" or "spring", for each of the pair.
    pub kinds: [String; 2],
    #[serde(rename = "min_clearance")]
    pub min_clearance_m: f64,
    pub tick_of_min: u64,
    pub closest_points: [[f64; 3]; 2],
}

/// One interval of ticks in which a pair's clearance stayed below the threshold.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct InterferenceViolation {
    pub pair: [String; 2],
    /// "strut", "cable" or "spring", for each of the pair.
    pub kinds: [String; 2],
    pub first_tick: u64,
    pub last_tick: u64,
    #[serde(rename = "min_clearance")]
    pub min_clearance_m: f64,
    pub tick_of_min: u64,
    /// Closest points on the two member axes at the minimum \[m\].
    pub closest_points: [[f64; 3]; 2],
}

/// The self-stress over the settle points (`[prestress]`): where it was lost, and the verdict.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PrestressReport {
    /// What a loss does: "fail" or "warn".
    pub on_loss: crate::settings::OnLoss,
    /// The smallest share of the drawn total cable tension a settled state may keep (absent:
    /// lost only when every cable is slack).
    pub min_fraction: Option<f64>,
    /// Cables of the structure.
    pub cables: usize,
    /// The smallest share kept over the settle points (absent without a drawn tension).
    pub least_fraction_kept: Option<f64>,
    /// Settle points at which the self-stress was lost (every cable slack, or below
    /// `min_fraction`).
    pub lost_at: Vec<usize>,
    /// The cables slack at those points, by name (each once, in the structure's order of
    /// first appearance).
    pub slack_cables: Vec<String>,
    /// No loss, or a loss the scenario lets warn.
    pub passed: bool,
}

impl PrestressReport {
    /// The judgement of `points` under `p` (each point says whether it lost the prestress).
    pub fn of(p: &crate::settings::Prestress, cables: usize, points: &[PointReport]) -> Self {
        let lost_points: Vec<&PointReport> = points.iter().filter(|q| q.prestress_lost == Some(true)).collect();
        let mut slack_cables: Vec<String> = Vec::new();
        for c in lost_points.iter().flat_map(|q| &q.slack_cables) {
            if !slack_cables.contains(c) {
                slack_cables.push(c.clone());
            }
        }
        let least = points.iter().filter_map(|q| q.prestress_fraction).reduce(f64::min);
        PrestressReport {
            on_loss: p.on_loss,
            min_fraction: p.min_fraction,
            cables,
            least_fraction_kept: least,
            lost_at: lost_points.iter().map(|q| q.index).collect(),
            passed: lost_points.is_empty() || p.on_loss == crate::settings::OnLoss::Warn,
            slack_cables,
        }
    }
}

/// Ticks during which one cable was slack.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SlackInterval {
    pub cable: String,
    pub first_tick: u64,
    pub last_tick: u64,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ProbeReport {
    /// The load applied as +load and -load [N m, or N on a prismatic joint].
    pub torque_nm: f64,
    /// The quantity the stiffness is reported as (`JOINT.stiffness`, or the mechanism's).
    pub quantity: String,
    /// The stiffness measured at each settle point [N m/rad or N/m] (null where it was not).
    pub measured: Vec<f64>,
    /// On the relative error; absent for a probe that only measures (no closed form).
    pub tolerance: Option<f64>,
    /// Largest relative error against the closed form; absent for a probe that only measures.
    pub max_rel_error: Option<f64>,
    /// Within tolerance, or a probe that only measures (no verdict from it).
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

impl ScenarioReport {
    /// "PASS", or "FAIL (what failed)", with whether that is what the scenario declares.
    pub fn verdict_line(&self) -> String {
        let names =
            |f: &[crate::report::verdict::Failure]| f.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(", ");
        let mut line = if self.passed { "PASS".to_string() } else { format!("FAIL ({})", names(&self.failures)) };
        match (&self.expect, self.as_expected) {
            (Some(_), Some(true)) if !self.passed => line.push_str(", as the scenario expects"),
            (Some(e), Some(false)) if e.failing.is_empty() => line.push_str(", NOT as expected (expect: pass)"),
            (Some(e), Some(false)) => {
                line.push_str(&format!(", NOT as expected (expect: fail in {})", names(&e.failing)))
            }
            _ => {}
        }
        line
    }
}

impl Report {
    /// Whether every scenario passed every check (the physics' verdict).
    pub fn passed(&self) -> bool {
        self.scenarios.iter().all(|s| s.passed)
    }

    /// Whether every scenario ended as it declares in `[expect]`: passed where it declares a
    /// pass (or declares nothing), failed in exactly the declared parts where it declares a
    /// failure.
    pub fn as_declared(&self) -> bool {
        self.scenarios.iter().all(|s| s.as_expected.unwrap_or(s.passed))
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("report serialises")
    }

    /// The human-readable table.
    pub fn to_table(&self) -> String {
        let mut out = String::new();
        for s in &self.scenarios {
            s.write_table(&mut out);
        }
        out
    }
}

impl ScenarioReport {
    /// This scenario's part of the table.
    fn write_table(&self, out: &mut String) {
        self.table_header(out);
        self.table_checks(out);
        self.table_model(out);
        self.table_motion(out);
        self.table_probe(out);
        self.table_slack(out);
        self.table_prestress(out);
        self.table_workspace(out);
        self.table_intervals(out);
        self.table_interference(out);
        self.table_stability(out);
        self.table_points(out);
        self.table_findings(out);
    }

    /// The verdict line, the settle summary and why the run stopped, if it did.
    fn table_header(&self, out: &mut String) {
        out.push_str(&format!("== {} ({}) [{}]: {}\n", self.name, self.mechanism, self.file, self.verdict_line()));
        out.push_str(&format!(
            "   settle: {} point(s), all settled: {}, {} steps, {:.3} s simulated, {:.3} s wall\n",
            self.points.len(),
            self.settle.settled,
            self.settle.steps,
            self.settle.sim_time_s,
            self.settle.wall_s
        ));
        out.push_str(&format!("   path: {}\n", self.path_line()));
        for t in &self.topologies {
            out.push_str(&format!("   topology: {t}\n"));
        }
        for p in &self.unseen_params {
            out.push_str(&format!(
                "   note: parameter '{p}' is swept but the structure does not change with it (only formulas see it)\n"
            ));
        }
        if let Some(e) = &self.error {
            out.push_str(&format!("   stopped: {e}\n"));
        }
    }

    /// The kind of path and the accelerated steps behind it: a motion run's path is its
    /// motion's, and the accelerated steps of the settle to its start are said to be that.
    fn path_line(&self) -> String {
        let Some(m) = &self.motion else {
            return format!("{} ({} accelerated step(s))", self.path.name(), self.accelerated_steps);
        };
        let settle = self.accelerated_steps.saturating_sub(m.accelerated_steps);
        format!(
            "{} (the motion: {} accelerated step(s){})",
            self.path.name(),
            m.accelerated_steps,
            if settle > 0 { format!("; the settle to its start: {settle}") } else { String::new() }
        )
    }

    /// A motion run: what ran, and each measured frequency against its prediction.
    fn table_motion(&self, out: &mut String) {
        let Some(m) = &self.motion else { return };
        out.push_str(&format!(
            "   motion from the {} state: {} of {} steps of {} s ({} s), {} accelerated{}; {}\n",
            if m.start == crate::settings::MotionStart::Drawn { "drawn" } else { "settled" },
            m.steps_taken,
            m.steps,
            m.dt_s,
            m.duration_s,
            m.accelerated_steps,
            if m.undamped { ", damping released" } else { "" },
            match &m.coordinate {
                Some(c) if m.displacement == 0.0 && m.rate == 0.0 => c.clone(),
                Some(c) => format!("{c} displaced by {:e}, rate {:e}", m.displacement, m.rate),
                None => "no displacement".into(),
            }
        ));
        if let Some(d) = &m.driven {
            out.push_str(&format!("   actuation: {d}\n"));
        }
        if let Some(x) = &m.extrapolation {
            out.push_str(&format!("   {}\n", judged_line(x)));
        }
        if self.points.len() > 1 && !m.frequencies.is_empty() {
            out.push_str("   (a motion from each point: each frequency's worst point below, every point's under it)\n");
        }
        for f in &m.frequencies {
            out.push_str(&format!("   {}\n", frequency_line(f)));
        }
        if let Some(l) = &m.lagrangian {
            table_lagrangian(l, out);
        }
    }

    /// One row per check, every error in the convention its tolerance applies to (named
    /// last): at the settle points, transient, verdict (nothing, not even the header, without
    /// checks).
    fn table_checks(&self, out: &mut String) {
        if self.checks.is_empty() {
            return;
        }
        let w = self.checks.iter().map(|c| c.quantity.len()).max().unwrap_or(0).max("check".len());
        out.push_str(&format!(
            "   {:<w$} {:>12} {:>10} {:>12} {:>12}  {}\n",
            "check", "max err", "tolerance", "transient", "rms trans.", "verdict"
        ));
        let motion = self.motion.is_some();
        for c in &self.checks {
            let (max, rms) = transient_cells(!motion, c.transient_max_rel_error, c.transient_rms_rel_error);
            out.push_str(&format!(
                "   {:<w$} {:>12.3e} {:>10.1e} {max:>12} {rms:>12}  {} ({})\n",
                c.quantity,
                c.max_rel_error,
                c.tolerance,
                if c.passed { "pass" } else { "FAIL" },
                c.convention
            ));
        }
        if motion {
            out.push_str(NOT_TRANSIENT_IN_MOTION);
        }
    }

    /// One row per prediction and equation of the file's model.
    fn table_model(&self, out: &mut String) {
        if self.model_checks.is_empty() {
            return;
        }
        let w = self.model_checks.iter().map(|c| c.name.len()).max().unwrap_or(0).max("model".len());
        out.push_str(&format!(
            "   {:<w$} {:>12} {:>10} {:>12} {:>12}  {}\n",
            "model", "max err", "tolerance", "transient", "rms trans.", "verdict"
        ));
        // In a motion run only the predictions judged over its ticks have errors during it.
        let shown = |c: &ModelCheckReport| self.motion.is_none() || c.motion_ticks.is_some();
        for c in &self.model_checks {
            let simulation = match c.simulation_error {
                Some(e) if c.below_resolution() => {
                    format!("; simulation error {e:.1e}: tolerance below what this run resolves")
                }
                Some(e) => format!("; simulation error {e:.1e}"),
                None => String::new(),
            };
            let (max, rms) = transient_cells(shown(c), c.transient_max_error, c.transient_rms_error);
            out.push_str(&format!(
                "   {:<w$} {:>12.3e} {:>10.1e} {max:>12} {rms:>12}  {} ({} {}{simulation})\n",
                c.name,
                c.max_error,
                c.tolerance,
                if c.passed { "pass" } else { "FAIL" },
                c.kind,
                c.class
            ));
        }
        if !self.model_checks.iter().all(shown) {
            out.push_str(NOT_TRANSIENT_IN_MOTION);
        }
    }

    /// The stiffness probe, if any.
    fn table_probe(&self, out: &mut String) {
        let Some(p) = &self.stiffness_probe else { return };
        match (p.max_rel_error, p.tolerance) {
            (Some(e), Some(t)) => out.push_str(&format!(
                "   stiffness probe {} (+-{}): max rel err {e:.3e} (tolerance {t:.1e}) {}\n",
                p.quantity,
                p.torque_nm,
                if p.passed { "pass" } else { "FAIL" }
            )),
            _ => {
                let measured: Vec<String> =
                    p.measured.iter().take(MAX_POINTS_IN_TABLE).map(|k| format!("{k:.9e}")).collect();
                out.push_str(&format!(
                    "   stiffness probe {} (+-{}): measured only (no closed form): {}{}\n",
                    p.quantity,
                    p.torque_nm,
                    measured.join(", "),
                    if p.measured.len() > MAX_POINTS_IN_TABLE { ", ..." } else { "" }
                ));
            }
        }
    }

    /// Where the slack cables agree with the analytic ones, and the points where any is slack.
    fn table_slack(&self, out: &mut String) {
        let slack_checked: Vec<_> = self.points.iter().filter(|p| p.slack_agrees.is_some()).collect();
        if !slack_checked.is_empty() {
            let agree = slack_checked.iter().filter(|p| p.slack_agrees == Some(true)).count();
            out.push_str(&format!(
                "   slack cables: simulated set equals the analytic one at {agree} of {} point(s)\n",
                slack_checked.len()
            ));
            for p in slack_checked
                .iter()
                .filter(|p| p.expected_slack.as_ref().is_some_and(|e| !e.is_empty()) || p.slack_agrees == Some(false))
            {
                out.push_str(&format!(
                    "     point {:>4}: analytic slack [{}], simulated slack [{}]{}{}\n",
                    p.index,
                    p.expected_slack.as_deref().unwrap_or(&[]).join(", "),
                    p.slack_cables.join(", "),
                    p.distance_from_analytic_m
                        .map(|d| format!(", {d:.3e} m from the analytic point"))
                        .unwrap_or_default(),
                    if p.slack_agrees == Some(false) { "  DISAGREE" } else { "" }
                ));
            }
        }
    }

    /// The self-stress kept, or where it was lost and which cables were slack there.
    fn table_prestress(&self, out: &mut String) {
        let Some(p) = &self.prestress else { return };
        let kept = p.least_fraction_kept.map(|f| format!(", least share of the drawn cable tension kept {f:.3}"));
        let rule = match p.min_fraction {
            Some(m) => format!("every cable slack or below {m} of the drawn tension"),
            None => "every cable slack".into(),
        };
        if p.lost_at.is_empty() {
            out.push_str(&format!("   prestress: kept at every settle point{}\n", kept.unwrap_or_default()));
            return;
        }
        let verdict = if p.passed { "WARNING (on_loss = \"warn\")" } else { "FAIL" };
        out.push_str(&format!(
            "   prestress: LOST at point(s) {:?} ({rule}){}; slack: {}  {verdict}\n",
            p.lost_at,
            kept.unwrap_or_default(),
            if p.slack_cables.is_empty() { "none".to_string() } else { p.slack_cables.join(", ") },
        ));
    }

    /// The workspace classifications and their agreement.
    fn table_workspace(&self, out: &mut String) {
        if let Some(w) = &self.workspace {
            out.push_str(&format!(
                "   workspace: {} point(s), {} inside analytically, {} inside by the dynamics; agreement {:.2} %{}\n",
                w.points,
                w.analytic_inside,
                w.simulated_inside,
                w.agreement_percent,
                if w.disagreements.is_empty() {
                    String::new()
                } else {
                    format!(" (disagree at points {:?})", w.disagreements)
                }
            ));
            if let (Some(f), Some(pc)) = (w.inside_interference_free, w.interference_free_percent_of_inside) {
                out.push_str(&format!(
                    "   interference-free: {f} of the {} point(s) inside ({pc:.2} %)\n",
                    w.simulated_inside
                ));
            }
        }
    }

    /// Skipped grid points and the slack intervals.
    fn table_intervals(&self, out: &mut String) {
        if self.skipped_points > 0 {
            out.push_str(&format!(
                "   skipped: {} grid point(s) outside the mechanism's domain\n",
                self.skipped_points
            ));
        }
        if !self.slack_intervals.is_empty() {
            out.push_str(&format!("   slack intervals ({}):", self.slack_intervals.len()));
            for iv in self.slack_intervals.iter().take(MAX_POINTS_IN_TABLE) {
                out.push_str(&format!(" {} ticks {}-{};", iv.cable, iv.first_tick, iv.last_tick));
            }
            out.push('\n');
        }
    }

    /// Member interference: the closest pair and every violation, or that it was off.
    fn table_interference(&self, out: &mut String) {
        if self.interference.as_ref().is_some_and(|i| !i.enabled) {
            out.push_str("   interference: OFF (the scenario sets [interference] enabled = false)\n");
        } else if let Some(i) = &self.interference {
            out.push_str(&format!(
                "   interference: {} member segment(s){}, {} pair(s) checked over {} tick(s); min clearance {}; {} violation(s) below {:.3e} m{}\n",
                i.members_checked,
                if i.tendons { " incl. cables and springs" } else { ", struts only" },
                i.pairs_checked,
                i.ticks_checked,
                match (&i.min_clearance_m, &i.closest_pair) {
                    (Some(c), Some([a, b])) => format!("{c:.6e} m ({a} / {b}, tick {})", i.tick_of_min.unwrap_or(0)),
                    _ => format!("> {:.3e} m (no pair within the margin)", i.margin_m),
                },
                i.violations.len(),
                i.threshold_m,
                if i.informative { " (informative)" } else if i.passed { "" } else { "  FAIL" }
            ));
            for v in i.violations.iter().take(MAX_POINTS_IN_TABLE) {
                let [p, q] = v.closest_points;
                out.push_str(&format!(
                    "     {} '{}' / {} '{}': ticks {}-{}, min clearance {:.6e} m at tick {}, closest points ({:.6}, {:.6}, {:.6}) ({:.6}, {:.6}, {:.6})\n",
                    v.kinds[0], v.pair[0], v.kinds[1], v.pair[1], v.first_tick, v.last_tick, v.min_clearance_m, v.tick_of_min,
                    p[0], p[1], p[2], q[0], q[1], q[2]
                ));
            }
        }
    }

    /// Stability verdicts, the branches landed on, the ranges along a trajectory.
    fn table_stability(&self, out: &mut String) {
        let unstable = self.points.iter().filter(|p| p.stable == Some(false)).count();
        let tested = self.points.iter().filter(|p| p.stable.is_some()).count();
        let disagree = self
            .points
            .iter()
            .filter(|p| p.stable.is_some() && p.analytic_stable.is_some() && p.stable != p.analytic_stable)
            .count();
        let expected = self.points.iter().filter(|p| p.stable.is_some() && p.expected_stable.is_some()).count();
        let unexpected = self
            .points
            .iter()
            .filter(|p| p.stable.is_some() && p.expected_stable.is_some() && p.stable != p.expected_stable)
            .count();
        if expected > 0 {
            out.push_str(&format!(
                "   stability expected at {expected} point(s) (the file or its energy model): {unexpected} disagree\n"
            ));
        }
        if tested > 0 {
            out.push_str(&format!(
                "   stability: {tested} point(s) perturbed, {unstable} unstable, {disagree} disagree with the analytic sign of K\n"
            ));
        }
        let mut branches: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
        for p in &self.points {
            *branches.entry(p.branch.as_str()).or_default() += 1;
        }
        for (b, n) in &branches {
            out.push_str(&format!("   landed on: {b}: {n} point(s)\n"));
        }
        for (q, r) in &self.trajectory_ranges {
            out.push_str(&format!(
                "   along the trajectory: {q} from {:.6e} to {:.6e}, smallest |{q}| {:.6e}\n",
                r.min, r.max, r.min_abs
            ));
        }
    }

    /// The first settle points, with the paper's values where it prints them.
    fn table_points(&self, out: &mut String) {
        let shown = self.points.len().min(MAX_POINTS_IN_TABLE);
        for p in &self.points[..shown] {
            let compared = fmt_errors(p);
            // A settled point with no inputs and nothing compared would be an empty line.
            if !(p.inputs.is_empty() && compared.is_empty() && p.settled) {
                out.push_str(&format!(
                    "   point {:>4}: {}  -> {compared}  [{}{}]\n",
                    p.index,
                    fmt_values(&p.inputs),
                    p.branch,
                    if p.settled {
                        String::new()
                    } else {
                        format!(", NOT SETTLED: kinetic energy {:.3e} J left", p.final_kinetic_energy_j)
                    }
                ));
            }
            if !p.slipping.is_empty() {
                out.push_str(&format!("              slipping (at the friction bound): {}\n", p.slipping.join(", ")));
            }
            if let Some(c) = &p.certificate {
                out.push_str(&format!("              {}\n", c.summary()));
            }
            if let Some(modes) = p.energy.as_ref().and_then(|e| e.modes.as_ref()) {
                let listed: Vec<String> = modes
                    .iter()
                    .map(|m| format!("{:.9} rad/s ({:.6} Hz)", m.omega_rad_per_s, m.frequency_hz))
                    .collect();
                out.push_str(&format!("              model's natural frequencies: {}\n", listed.join(", ")));
            }
            if self.points.len() > 1 {
                for f in &p.frequencies {
                    out.push_str(&format!("              {}\n", frequency_line(f)));
                }
            }
            if let Some(paper) = &p.paper {
                // The paper's value beside the testbed's analytic one, with their relative
                // difference.
                let beside: Vec<String> = paper
                    .values
                    .iter()
                    .map(|(q, v)| match p.analytic.get(q.trim_start_matches("ansys_")) {
                        Some(a) if *a != 0.0 => format!("{q}={v:.6} ({:+.1e})", (v - a) / a.abs()),
                        _ => format!("{q}={v:.6}"),
                    })
                    .collect();
                out.push_str(&format!(
                    "              paper, {}: {}  (relative difference from the testbed's analytic value)\n",
                    paper.source,
                    beside.join(" ")
                ));
            }
        }
        if self.points.len() > shown {
            out.push_str(&format!("   ... {} more point(s) in the JSON report\n", self.points.len() - shown));
        }
    }

    /// The printed equations that do not hold.
    fn table_findings(&self, out: &mut String) {
        let wrong: Vec<_> = self.findings.iter().filter(|f| !f.holds).collect();
        if !self.findings.is_empty() {
            out.push_str(&format!(
                "   findings: {} printed equation(s) checked, {} do not hold as printed:\n",
                self.findings.len(),
                wrong.len()
            ));
            for f in wrong {
                out.push_str(&format!("     - {}: {} ({})\n", f.equation, f.claim, f.measured));
            }
        }
    }
}

/// Points listed in the table; the JSON has them all.
const MAX_POINTS_IN_TABLE: usize = 12;

fn fmt_values(v: &Values) -> String {
    v.iter().map(|(k, x)| format!("{k}={x:.6}")).collect::<Vec<_>>().join(" ")
}

/// Each simulated quantity with a closed form, and its error as its verdict measures it (the
/// table's convention for it; none for a quantity nothing judges).
fn fmt_errors(p: &PointReport) -> String {
    p.simulated
        .iter()
        .filter(|(k, _)| p.analytic.contains_key(*k))
        .map(|(k, s)| match p.errors.get(k) {
            Some(e) => format!("{k}={s:.9} (err {e:.1e})"),
            None => format!("{k}={s:.9}"),
        })
        .collect::<Vec<_>>()
        .join(" ")
}
