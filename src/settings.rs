//! Plain configuration types, read from a scenario file and handed to the simulation and the
//! observers. Nothing here parses, builds or steps anything: `scenario` fills them in, `sim`
//! and `observers` read them, and neither needs the other.

use crate::mechanisms::QuantityKind;
use crate::structure::Structure;
use std::cmp::Ordering;

/// Numerical settings of the integrator, all from the scenario file.
#[derive(Clone, Debug, PartialEq)]
pub struct SimSettings {
    /// Time step \[s\].
    pub dt_s: f64,
    /// rapier substeps per step (`num_solver_iterations`).
    pub substeps: usize,
    /// rapier PGS iterations per substep (`num_internal_pgs_iterations`).
    pub pgs_iterations: usize,
    /// PGS iterations while a settle approaches its equilibrium (cheaper, with a larger
    /// impulse-joint offset); the last phase runs at `pgs_iterations`. None: one phase.
    pub approach_pgs_iterations: Option<usize>,
    /// The Newton damping schedule (`damping.rs`): before every step each damped revolute or
    /// prismatic joint's velocity is quenched and its damping set so that the step is a Newton
    /// step on its tangent stiffness (a settling strategy).
    pub newton_damping: bool,
    /// Static relaxation (`relaxation.rs`) of structures of free bodies held by springs and
    /// elastic cables: a saddle-free Newton step on the potential energy and the bodies at
    /// rest before every step (a settling strategy; on by default, ignored where it does not
    /// apply).
    pub relaxation: bool,
    /// Half-size of the box that every node must stay inside, else the run diverged \[m\].
    pub bounding_box_m: f64,
    /// Linear and angular damping of free bodies [1/s] (applied after each step; it slows
    /// motion but does not move the equilibrium).
    pub body_damping_per_s: f64,
    /// Kinetic energy above which the run has diverged \[J\].
    pub max_kinetic_energy_j: f64,
    /// Separation of a loop-closing joint's anchors above which the run has diverged \[m\]
    /// (None: 1 % of the structure's size).
    pub max_joint_gap_m: Option<f64>,
}

/// Default kinetic-energy limit \[J\]: far above anything a settling mechanism of this testbed
/// holds (a few J), far below what a numerical blow-up reaches within a few ticks.
pub const DEFAULT_MAX_KINETIC_ENERGY_J: f64 = 1e6;

/// Default limit of a loop-closing joint's anchor gap, as a fraction of the structure's size.
pub const DEFAULT_JOINT_GAP_FRACTION: f64 = 1e-2;

impl Default for SimSettings {
    fn default() -> Self {
        SimSettings {
            dt_s: 0.01,
            substeps: 1,
            pgs_iterations: 8,
            approach_pgs_iterations: None,
            newton_damping: false,
            relaxation: true,
            bounding_box_m: 1e3,
            body_damping_per_s: 0.0,
            max_kinetic_energy_j: DEFAULT_MAX_KINETIC_ENERGY_J,
            max_joint_gap_m: None,
        }
    }
}

/// When a run counts as settled. All from the scenario file.
#[derive(Clone, Debug, PartialEq)]
pub struct SettleCriteria {
    /// Largest node speed allowed while settled [m/s].
    pub speed_tol_m_per_s: f64,
    /// Consecutive steps the speed must stay below the threshold.
    pub window_steps: u64,
    /// Largest residual force on a free coordinate \[N\].
    pub residual_force_tol_n: f64,
    /// Largest residual torque on a free coordinate [N m].
    pub residual_torque_tol_nm: f64,
    /// Simulated time allowed for one settle \[s\]; past it the settle fails.
    pub max_time_s: f64,
}

impl Default for SettleCriteria {
    fn default() -> Self {
        SettleCriteria {
            speed_tol_m_per_s: 1e-10,
            window_steps: 10,
            residual_force_tol_n: 1e-7,
            residual_torque_tol_nm: 1e-7,
            max_time_s: 60.0,
        }
    }
}

/// Settings of the interference checks (`[interference]`), which run in every scenario unless
/// it turns them off: struts as capsules, cables and springs (tendons) as thinner capsules.
#[derive(Clone, Debug, PartialEq)]
pub struct InterferenceSettings {
    /// False only when the scenario says `enabled = false` (the report says it was off).
    pub enabled: bool,
    /// Cables and springs are checked too (against struts and each other).
    pub tendons: bool,
    /// A pair whose clearance falls below this is a violation \[m\] (0: only actual overlap).
    pub threshold_m: f64,
    /// Pairs farther apart than this are not measured \[m\] (the broad phase's inflation).
    pub margin_m: f64,
    /// Violations are reported but do not fail the run.
    pub informative: bool,
    /// Further pairs to exclude, by member name (strut, cable or spring).
    pub exclude: Vec<(String, String)>,
}

impl InterferenceSettings {
    /// The checks of a scenario without an `[interference]` section: on, tendons included,
    /// threshold 0 (actual overlap), margin `margin_m` (the mechanism's length scale).
    pub fn default_on(margin_m: f64) -> Self {
        InterferenceSettings {
            enabled: true,
            tendons: true,
            threshold_m: 0.0,
            margin_m,
            informative: false,
            exclude: Vec::new(),
        }
    }

    /// Whether every excluded pair names members of `s` (else the error names the first that
    /// does not, and the members there are).
    pub fn check_member_names(&self, s: &Structure) -> Result<(), UnknownMember> {
        use crate::structure::MemberKind::{Cable, Spring, Strut};
        let names: Vec<&str> =
            [Strut, Cable, Spring].into_iter().flat_map(|k| s.members_of(k)).map(|(_, m)| m.name.as_str()).collect();
        match self.exclude.iter().flat_map(|(a, b)| [a, b]).find(|n| !names.contains(&n.as_str())) {
            Some(name) => Err(UnknownMember { name: name.clone(), members: names.join(", ") }),
            None => Ok(()),
        }
    }
}

/// One `[[checks]]` entry: a quantity compared with the analytic model.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    pub quantity: String,
    pub kind: QuantityKind,
    pub unit: String,
    /// On the normalised error (see `QuantityKind`).
    pub tolerance: f64,
}

/// `[prestress]`: when the structure counts as having lost its self-stress, and what that does
/// to the verdict. Lost at a settle point when every cable is slack there, or (with
/// `min_fraction`) when the cables' total tension there falls below `min_fraction` of their
/// total tension at the drawn state.
#[derive(Clone, Debug, PartialEq)]
pub struct Prestress {
    /// The smallest share of the drawn total cable tension a settled state may keep.
    pub min_fraction: Option<f64>,
    /// Whether a loss fails the run (`prestress`) or is reported as a warning.
    pub on_loss: OnLoss,
}

/// What a loss of prestress does (`[prestress] on_loss`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OnLoss {
    Fail,
    Warn,
}

impl Prestress {
    /// What a custom structure with cables gets without a `[prestress]` section: it fails
    /// when every cable is slack at a settle point.
    pub const DEFAULT: Prestress = Prestress { min_fraction: None, on_loss: OnLoss::Fail };

    /// Whether a settled state of a structure of `cables` cables, `slack` of them slack,
    /// keeping `fraction` of the drawn cable tension, has lost its self-stress.
    pub fn lost(&self, cables: usize, slack: usize, fraction: Option<f64>) -> bool {
        (cables > 0 && slack == cables)
            || self.min_fraction.zip(fraction).is_some_and(|(min, f)| f.partial_cmp(&min).is_none_or(Ordering::is_lt))
    }
}

/// The stiffness probe (`[probe]`): the mechanism's own, or one on a named joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// The load applied as +load and -load: a torque [N m] (the mechanism's probe, a
    /// revolute joint) or a force \[N\] (a prismatic joint).
    pub torque_nm: f64,
    /// A probe on a named joint of the structure, with its predicted stiffness.
    pub joint: Option<JointProbe>,
    /// On the relative stiffness error; None: a joint probe without a closed form, which
    /// measures the stiffness and gives no verdict.
    pub tolerance: Option<f64>,
}

/// A stiffness probe on a named revolute or prismatic joint: equal and opposite loads on its
/// child and parent about (along) its axis, the joint's coordinate measured, the stiffness
/// dload/dq compared with a closed form of the parameters and inputs.
#[derive(Clone, Debug)]
pub struct JointProbe {
    /// The joint's name and index in the structure.
    pub joint: String,
    pub index: usize,
    /// Prismatic (a force along the axis, N/m) rather than revolute (a torque, N m/rad).
    pub prismatic: bool,
    /// The predicted stiffness, compiled against `symbols` (None: the probe only measures).
    pub expected: Option<crate::file_model::expr::Expr>,
    /// The symbols `expected` may use: the parameters, then the inputs.
    pub symbols: Vec<String>,
}

impl PartialEq for JointProbe {
    fn eq(&self, other: &Self) -> bool {
        self.joint == other.joint
            && self.expected.as_ref().map(|e| e.text()) == other.expected.as_ref().map(|e| e.text())
    }
}

impl JointProbe {
    /// The quantity the probe reports: `JOINT.stiffness`.
    pub fn quantity(&self) -> String {
        format!("{}.stiffness", self.joint)
    }

    /// The predicted stiffness with the point's parameters and inputs (None: no closed form).
    pub fn predicted(&self, params: &crate::mechanisms::Values, inputs: &crate::mechanisms::Values) -> Option<f64> {
        let values: Vec<f64> =
            self.symbols.iter().map(|s| inputs.get(s).or_else(|| params.get(s)).copied().unwrap_or(f64::NAN)).collect();
        self.expected.as_ref().map(|e| e.eval(&values))
    }
}

/// `[motion]`: a motion run, the physical dynamics for a stated time (`scenario/motion.rs`).
/// Where a motion run starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MotionStart {
    /// The structure as drawn (at rest): no step before the motion.
    Drawn,
    /// Settled first, with the scenario's settle accelerators, which are then switched off.
    Settled,
}

/// A joint coordinate named by a motion run: the joint's name, its index in the structure and
/// whether it slides (prismatic, m) or turns (revolute, rad).
#[derive(Clone, Debug, PartialEq)]
pub struct JointCoordinate {
    pub joint: String,
    pub index: usize,
    pub prismatic: bool,
}

/// What a measured frequency is fitted to.
#[derive(Clone, Debug, PartialEq)]
pub enum FrequencySignal {
    /// A revolute or prismatic joint's coordinate.
    Joint(JointCoordinate),
    /// The coordinate of one of the structure's own modes (from 0, ascending, rigid-body modes
    /// counted) at the motion's start (`snapshot::ModalProjector`).
    Mode(usize),
}

impl FrequencySignal {
    /// As the report names it: the joint's name, or "mode N" (from 1).
    pub fn label(&self) -> String {
        match self {
            FrequencySignal::Joint(c) => c.joint.clone(),
            FrequencySignal::Mode(i) => format!("mode {}", i + 1),
        }
    }
}

/// How a motion's frequency is measured (`[[motion.frequencies]] measure`, `[energy.trajectory]
/// measure`): defined beside the file's dynamic model, which reads it too.
pub use crate::file_model::dynamics::FrequencyMeasure;

/// A natural frequency predicted (in closed form, or by the structure's own modal analysis)
/// and measured from the motion.
#[derive(Clone, Debug)]
pub struct FrequencyPrediction {
    pub name: String,
    pub signal: FrequencySignal,
    /// How the frequency is measured from the motion.
    pub measure: FrequencyMeasure,
    /// Compiled against [`FrequencyPrediction::symbols`]; None: the modal analysis's frequency
    /// of the mode fitted.
    pub formula: Option<crate::file_model::expr::Expr>,
    /// The parameters, then the inputs, then the mechanism's analytic quantities, then the
    /// energy model's solved equilibrium (`file_model::dynamics::solved_names`).
    pub symbols: Vec<String>,
    /// Relative.
    pub tolerance: f64,
    /// The prediction holds at the motion's amplitude: the amplitude's shift is no part of its
    /// error bar.
    pub at_amplitude: bool,
}

impl PartialEq for FrequencyPrediction {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
            && self.measure == other.measure
            && self.formula.as_ref().map(|f| f.text()) == other.formula.as_ref().map(|f| f.text())
            && self.tolerance == other.tolerance
            && self.at_amplitude == other.at_amplitude
    }
}

impl FrequencyPrediction {
    /// The predicted angular frequency [rad/s] with these parameters, inputs, analytic
    /// quantities and the energy model's solved equilibrium (`solved`: its coordinates and
    /// `V_a_b`, `M_a_b` there; None without a formula).
    pub fn predicted(
        &self,
        params: &crate::mechanisms::Values,
        inputs: &crate::mechanisms::Values,
        analytic: &crate::mechanisms::Values,
        solved: &crate::mechanisms::Values,
    ) -> Option<f64> {
        let value =
            |s: &String| inputs.get(s).or_else(|| params.get(s)).or_else(|| analytic.get(s)).or_else(|| solved.get(s));
        let values: Vec<f64> = self.symbols.iter().map(|s| value(s).copied().unwrap_or(f64::NAN)).collect();
        Some(self.formula.as_ref()?.eval(&values))
    }
}

/// A validated `[motion]` section.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    pub duration_s: f64,
    /// Whole time steps of the motion: duration / dt, rounded.
    pub steps: u64,
    pub start: MotionStart,
    /// The displaced coordinate, with its displacement and start rate.
    pub coordinate: Option<(JointCoordinate, f64, f64)>,
    /// A displacement along one of the structure's own modes at the start: the mode (from 0,
    /// rigid-body modes counted) and the largest node displacement \[m\].
    pub mode: Option<(usize, f64)>,
    pub frequencies: Vec<FrequencyPrediction>,
    /// Every joint's damping released (set to zero) for the motion; the settle to a settled
    /// start keeps the damping the structure states.
    pub undamped: bool,
    /// The inputs followed in time during the motion, at their real speed (`[actuation]
    /// waypoints` or `[motion] inputs`); None: the single point's inputs held.
    pub drive: Option<Drive>,
    /// A free body without joints started spinning: (body, its name, angular velocity
    /// [rad/s], world frame).
    pub spin: Option<(usize, String, [f64; 3])>,
    /// Judge the motion extrapolated over the time step: the same motion at h, h/2 and h/4,
    /// combined by Richardson's rule at fourth order, with its own error estimate
    /// (`run/levels.rs`). None: extrapolated ([`Motion::extrapolated`]).
    pub extrapolate: Option<bool>,
    /// The judged motion's error target, a fraction of its amplitude (the largest node
    /// excursion): the fewest levels that meet it are chosen by running them first. None: three
    /// levels, reported against [`DEFAULT_TARGET_ERROR`].
    pub target_error: Option<f64>,
}

impl Motion {
    /// Whether the motion is judged extrapolated over the time step (the one place that says
    /// so: the run's levels and the table's estimate columns both ask here).
    pub fn extrapolated(&self) -> bool {
        self.extrapolate != Some(false)
    }
}

/// What a motion judged over the default three levels aims at: its error estimate at most this
/// fraction of its amplitude (the report says whether it was met).
pub const DEFAULT_TARGET_ERROR: f64 = 1e-9;

/// Inputs as functions of the motion's time, followed physically: each actuated joint a
/// dynamic degree of freedom held to its commanded path through the solver.
#[derive(Clone, Debug)]
pub enum Drive {
    /// Linearly interpolated in time (s since the motion started), held at the last.
    Waypoints(Vec<(f64, crate::mechanisms::Values)>),
    /// Closed forms of the parameters and `t` for some inputs, the others held at the point's.
    Functions {
        held: crate::mechanisms::Values,
        /// (input, its formula compiled against `symbols`).
        functions: Vec<(String, crate::file_model::expr::Expr)>,
        /// The parameters, then `t`.
        symbols: Vec<String>,
    },
}

impl PartialEq for Drive {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Drive::Waypoints(a), Drive::Waypoints(b)) => a == b,
            (Drive::Functions { functions: a, held: ha, .. }, Drive::Functions { functions: b, held: hb, .. }) => {
                ha == hb && a.iter().map(|(n, e)| (n, e.text())).eq(b.iter().map(|(n, e)| (n, e.text())))
            }
            _ => false,
        }
    }
}

impl Drive {
    /// The inputs at motion time `t` \[s\] with these parameters.
    pub fn inputs_at(&self, params: &crate::mechanisms::Values, t: f64) -> crate::mechanisms::Values {
        match self {
            Drive::Waypoints(w) => interpolate(w, t),
            Drive::Functions { held, functions, symbols } => {
                let values: Vec<f64> = symbols
                    .iter()
                    .map(|s| if s == "t" { t } else { params.get(s).copied().unwrap_or(f64::NAN) })
                    .collect();
                let mut inputs = held.clone();
                for (name, e) in functions {
                    inputs.insert(name.clone(), e.eval(&values));
                }
                inputs
            }
        }
    }
}

/// Linear interpolation of the waypoints at time `t`, held at the last.
pub fn interpolate(waypoints: &[(f64, crate::mechanisms::Values)], t: f64) -> crate::mechanisms::Values {
    if t <= waypoints[0].0 {
        return waypoints[0].1.clone();
    }
    for w in waypoints.windows(2) {
        let ((t0, a), (t1, b)) = (&w[0], &w[1]);
        if t <= *t1 {
            let s = (t - t0) / (t1 - t0);
            return a.iter().map(|(k, x)| (k.clone(), x + (b[k] - x) * s)).collect();
        }
    }
    waypoints.last().unwrap().1.clone()
}

/// An interference exclusion that names no member of the structure.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("interference exclusion names member '{name}', which does not exist (members: {members})")]
pub struct UnknownMember {
    /// The name given.
    pub name: String,
    /// The structure's members, listed.
    pub members: String,
}
