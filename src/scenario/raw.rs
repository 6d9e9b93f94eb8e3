//! The shape of a scenario file, as serde reads it: every value keeps its span, so that
//! [`super::validate`] can name the line and column of a value it rejects.

use super::number::{Num, ParamMap};
use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

pub(super) type SpannedMap = BTreeMap<Spanned<String>, Spanned<f64>>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScenario {
    pub(super) name: Spanned<String>,
    #[serde(default)]
    pub(super) description: String,
    pub(super) mechanism: Spanned<String>,
    /// Numbers, expressions of other parameters, or tables { value, unit, description }.
    #[serde(default)]
    pub(super) params: ParamMap,
    #[serde(default)]
    pub(super) sim: RawSim,
    #[serde(default)]
    pub(super) settle: RawSettle,
    #[serde(default)]
    pub(super) start: SpannedMap,
    pub(super) actuation: Spanned<RawActuation>,
    #[serde(default)]
    pub(super) checks: Vec<RawCheck>,
    #[serde(default)]
    pub(super) stability: Option<RawStability>,
    #[serde(default)]
    pub(super) probe: Option<Spanned<RawProbe>>,
    #[serde(default)]
    pub(super) record: Option<RawRecord>,
    #[serde(default)]
    pub(super) interference: Option<Spanned<RawInterference>>,
    #[serde(default)]
    pub(super) workspace: Option<RawWorkspace>,
    /// When the structure counts as having lost its self-stress, and what that does.
    #[serde(default)]
    pub(super) prestress: Option<Spanned<RawPrestress>>,
    /// `[[fidelity]]`: the idealizations `tensegrity attribute` relaxes (`fidelity.rs`).
    #[serde(default)]
    pub(super) fidelity: Vec<Spanned<super::fidelity::RawRelaxation>>,
    /// `mechanism = "custom"`: the structure itself.
    #[serde(default)]
    pub(super) structure: Option<Spanned<RawStructure>>,
    /// What the run must do: pass, or fail in named parts.
    #[serde(default)]
    pub(super) expect: Option<Spanned<RawExpect>>,
    /// The file's own model: named expressions of the state.
    #[serde(default)]
    pub(super) quantities: Vec<RawQuantity>,
    /// Closed forms of the parameters and inputs compared with the state.
    #[serde(default)]
    pub(super) predictions: Vec<RawPrediction>,
    /// Residuals that must vanish at every settled state.
    #[serde(default)]
    pub(super) equations: Vec<RawEquation>,
    /// Derivatives of the settled state with respect to a parameter, as symbols.
    #[serde(default)]
    pub(super) sensitivities: Vec<RawSensitivity>,
    /// A potential energy in named coordinates: its stationary points and the one the
    /// dynamics landed on.
    #[serde(default)]
    pub(super) energy: Option<RawEnergy>,
    /// A motion run: the physical dynamics for a stated time (`motion.rs`).
    #[serde(default)]
    pub(super) motion: Option<Spanned<super::motion::RawMotion>>,
    /// `[certify]`: a proof of the equilibrium at every settle point (`crate::certify`).
    #[serde(default)]
    pub(super) certify: Option<Spanned<RawCertify>>,
}

/// `[certify]`: whether every settle point's equilibrium is certified (`enabled`, default true).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCertify {
    #[serde(default = "certify_by_default")]
    pub(super) enabled: bool,
}

/// A `[certify]` section certifies unless it says `enabled = false`.
fn certify_by_default() -> bool {
    true
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEnergy {
    /// An expression of the coordinates, parameters, inputs and their quantities [J].
    pub(super) potential: Spanned<String>,
    /// On the largest coordinate difference from the settled state to its stationary point.
    pub(super) tolerance: Spanned<f64>,
    pub(super) coordinates: Vec<RawCoordinate>,
    /// A kinetic energy [J]: an expression of the coordinates, their rates (`NAME_dot`),
    /// parameters, inputs and their quantities, quadratic in the rates.
    #[serde(default)]
    pub(super) kinetic: Option<Spanned<String>>,
    /// Natural frequencies of the dynamic model predicted by closed forms.
    #[serde(default)]
    pub(super) frequencies: Vec<RawFrequency>,
    /// A motion run compared with the Lagrangian equations of the kinetic and potential energy.
    #[serde(default)]
    pub(super) trajectory: Option<Spanned<RawTrajectory>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTrajectory {
    /// On the largest error of each coordinate over the motion, in its class [m or rad].
    pub(super) tolerance: Spanned<f64>,
    /// On the rms error of each coordinate over the motion.
    #[serde(default)]
    pub(super) rms_tolerance: Option<Spanned<f64>>,
    /// Where the model starts: "samples" (the default) or "stated".
    #[serde(default)]
    pub(super) start: Option<Spanned<String>>,
    /// How each trajectory's frequency is measured: "cosine" (the default) or "period".
    #[serde(default)]
    pub(super) measure: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFrequency {
    pub(super) name: Spanned<String>,
    /// A closed form of the parameters and inputs [rad/s].
    pub(super) formula: Spanned<String>,
    /// The mode, from 1 (the lowest frequency).
    pub(super) mode: Spanned<i64>,
    /// On the relative error.
    pub(super) tolerance: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCoordinate {
    pub(super) name: Spanned<String>,
    /// An expression of the state giving the coordinate at a settled point.
    pub(super) measured: Spanned<String>,
    /// angle (compared wrapped) or length.
    pub(super) class: Spanned<String>,
    /// Further Newton starts.
    pub(super) scan: Option<Spanned<RawRange>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawQuantity {
    /// Generated for every binding of one loop variable: a range `"0..n"` or a group of
    /// members (`for_each.rs`).
    #[serde(rename = "for", default)]
    pub(super) over: Option<For>,
    pub(super) name: Spanned<String>,
    /// An expression of the state, the parameters, the inputs, `t` and earlier quantities.
    pub(super) expr: Spanned<String>,
    /// For the listing and the report (default "-").
    pub(super) unit: Option<String>,
}

/// A `[[sensitivities]]` entry: the symbol `name` is d(output)/d(parameter) at each settle
/// point (`run::sensitivity`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSensitivity {
    pub(super) name: Spanned<String>,
    /// A node coordinate, member force, joint coordinate, observed quantity, `[[quantities]]`
    /// name or `modeN.omega`.
    pub(super) output: Spanned<String>,
    /// A parameter of the scenario.
    pub(super) parameter: Spanned<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPrediction {
    /// Generated for every binding of one loop variable: a range `"0..n"` or a group of
    /// members (`for_each.rs`).
    #[serde(rename = "for", default)]
    pub(super) over: Option<For>,
    /// The compared symbol: a `[[quantities]]` name, a node coordinate, an observed quantity.
    pub(super) quantity: Spanned<String>,
    /// The name in the report and in `[expect] failing` (default: the quantity's).
    pub(super) name: Option<Spanned<String>>,
    /// A closed form of the parameters and inputs.
    pub(super) formula: Spanned<String>,
    /// length (m), angle (rad, wrapped) or relative.
    pub(super) class: Spanned<String>,
    pub(super) tolerance: Spanned<f64>,
    /// A motion run only: on the rms error over the motion's ticks (`tolerance` is then on
    /// their maximum).
    pub(super) rms_tolerance: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEquation {
    /// Generated for every binding of one loop variable: a range `"0..n"` or a group of
    /// members (`for_each.rs`).
    #[serde(rename = "for", default)]
    pub(super) over: Option<For>,
    pub(super) name: Spanned<String>,
    /// An expression that must vanish at every settled state (same symbols as a quantity).
    pub(super) residual: Spanned<String>,
    pub(super) tolerance: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawExpect {
    /// "pass" or "fail".
    pub(super) verdict: Spanned<String>,
    /// With "fail": every part of the verdict that must fail, and no other
    /// (see [`crate::report::verdict::FAILURE_NAMES`]).
    #[serde(default)]
    pub(super) failing: Vec<Spanned<String>>,
}

/// `for = { i = "0..n" }`: a loop variable and what it runs over.
pub(super) type For = Spanned<BTreeMap<String, Spanned<String>>>;

/// Three coordinates, each a number or an expression of the parameters; read as a list so
/// that a list of another length is an error at its place (serde's fixed-size arrays left
/// trailing entries unread).
pub(super) type Xyz = Spanned<Vec<Spanned<Num>>>;

/// A table that holds the parts of a structure (`[structure]` and `[[structure.repeat]]`):
/// its own fields, then bodies, members, joints, actuators and the compact member groups
/// (struts, springs and cables sharing their properties, listed by node pairs, after the
/// one-table-per-member entries).
macro_rules! with_parts {
    ($(#[$doc:meta])* $name:ident { $($(#[$fm:meta])* $f:ident: $t:ty,)* }) => {
        $(#[$doc])*
        #[derive(Clone, Debug, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub(super) struct $name {
            $($(#[$fm])* pub(super) $f: $t,)*
            #[serde(default)]
            pub(super) bodies: Vec<RawBody>,
            #[serde(default)]
            pub(super) struts: Vec<RawMember>,
            #[serde(default)]
            pub(super) springs: Vec<RawMember>,
            #[serde(default)]
            pub(super) cables: Vec<RawMember>,
            #[serde(default)]
            pub(super) joints: Vec<RawJoint>,
            #[serde(default)]
            pub(super) actuators: Vec<RawActuator>,
            #[serde(default)]
            pub(super) strut_groups: Vec<RawMemberGroup>,
            #[serde(default)]
            pub(super) spring_groups: Vec<RawMemberGroup>,
            #[serde(default)]
            pub(super) cable_groups: Vec<RawMemberGroup>,
        }
    };
}

with_parts!(RawStructure {
    /// Gravity [m/s^2] (default none).
    gravity: Option<Xyz>,
    /// Point loads at nodes (`[[structure.loads]]`).
    #[serde(default)]
    loads: Vec<RawLoad>,
    /// Masses added at nodes that are point masses (`[[structure.masses]]`).
    #[serde(default)]
    masses: Vec<RawNodeMass>,
    /// Supports in some directions at point masses (`[[structure.supports]]`).
    #[serde(default)]
    supports: Vec<RawSupport>,
    /// Sub-structures generated over an index range (`repeat.rs`), appended to the lists.
    #[serde(default)]
    repeat: Vec<RawRepeat>,
});

with_parts!(
    /// `[[structure.repeat]]`: bodies, members, groups, joints and actuators written once with
    /// `{i}` templates and generated for every index of `for`, each copy optionally rotated
    /// about an axis through the origin and then offset.
    RawRepeat {
        /// `{ i = "0..n" }`: one loop variable over a range whose bounds are integer
        /// expressions of the parameters (end excluded).
        #[serde(rename = "for")]
        over: For,
        rotate: Option<RawRotate>,
        /// [m], added after the rotation; expressions may use the loop variable.
        offset: Option<Xyz>,
    }
);

/// `[[structure.loads]]`: a constant force [N] at a node, world frame; its components may be
/// expressions of the parameters (a grid over them sweeps the load).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLoad {
    pub(super) node: Spanned<String>,
    pub(super) force: Xyz,
}

/// `[[structure.masses]]`: a mass [kg] added at a node whose body is a point mass (a one-node
/// free body, an elastic strut's end, a heavy cable's end on a point mass).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawNodeMass {
    pub(super) node: Spanned<String>,
    pub(super) mass: Spanned<Num>,
}

/// `[[structure.supports]]`: a node of a point mass held in some world directions, `fixed`
/// a list of "x", "y" and "z" (a roller on the floor: `fixed = ["z"]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSupport {
    pub(super) node: Spanned<String>,
    pub(super) fixed: Spanned<Vec<String>>,
}

/// A rotation about `axis` (through the origin) by `angle` [rad].
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRotate {
    pub(super) axis: Xyz,
    pub(super) angle: Spanned<Num>,
}

/// Where a generated copy goes: its rotation and offset, the loop variable filled in
/// (applied when the numbers are resolved, `number.rs`).
#[derive(Clone, Debug, Default)]
pub(super) struct Placement {
    pub(super) rotate: Option<RawRotate>,
    pub(super) offset: Option<Xyz>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBody {
    pub(super) name: Spanned<String>,
    /// Welded to the world (default false).
    pub(super) fixed: Option<bool>,
    /// Mass of a free body [kg].
    pub(super) mass: Option<Spanned<Num>>,
    /// Principal moments about the centre of mass, along the world axes [kg m^2] (default:
    /// isotropic, mass times the square of the body's size over 12).
    pub(super) inertia: Option<Xyz>,
    /// Named nodes with their coordinates [m] (the centre of mass is their mean).
    pub(super) nodes: BTreeMap<Spanned<String>, Xyz>,
    /// A copy generated by `[[structure.repeat]]`: its nodes rotated and offset.
    #[serde(skip)]
    pub(super) placement: Option<Placement>,
}

/// A strut, spring or cable between two named nodes.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMember {
    pub(super) name: Spanned<String>,
    pub(super) a: Spanned<String>,
    pub(super) b: Spanned<String>,
    /// Radius [m] for interference and drawing (struts: default 0.01; cables and springs:
    /// default 0.001).
    pub(super) radius: Option<Spanned<Num>>,
    /// Springs: stiffness [N/m] (required); cables: stiffness of an elastic cable (absent:
    /// inextensible).
    pub(super) stiffness: Option<Spanned<Num>>,
    /// Springs: free length [m]; cables: unstretched length [m]. Absent: the initial distance.
    pub(super) length: Option<Spanned<Num>>,
    /// Cables only: the inner nodes a clustered cable runs through from `a` to `b`, in order;
    /// it slides there without friction (one tension in every segment).
    pub(super) through: Option<Spanned<Vec<Spanned<String>>>>,
    /// Cables only: the Coulomb friction coefficient at each node of `through` (a capstan,
    /// `sim/capstan.rs`); absent: none.
    pub(super) friction: Option<Spanned<Vec<Spanned<Num>>>>,
    /// Struts only: the axial stiffness E A [N] of an elastic strut (`structure/lumped.rs`);
    /// absent (and no `E`): rigid.
    #[serde(rename = "EA")]
    pub(super) ea: Option<Spanned<Num>>,
    /// Struts only: Young's modulus [Pa], with `area`, in place of `EA`.
    #[serde(rename = "E")]
    pub(super) youngs_modulus: Option<Spanned<Num>>,
    /// Struts only: the cross-section [m^2], with `E`.
    pub(super) area: Option<Spanned<Num>>,
    /// A cable's linear density [kg per unstretched m], a heavy cable built of `segments`
    /// segments between beads (absent: massless); a strut's [kg/m], its body's mass
    /// density x length (in place of the body's `mass`).
    pub(super) density: Option<Spanned<Num>>,
    /// Cables only, with `density`: how many segments [1, 1000].
    pub(super) segments: Option<Spanned<Num>>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawJoint {
    pub(super) name: Spanned<String>,
    /// revolute, prismatic, spherical, universal, fixed or planar_pin.
    pub(super) kind: Spanned<String>,
    pub(super) parent: Spanned<String>,
    pub(super) child: Spanned<String>,
    /// The node at the joint's centre.
    pub(super) at: Spanned<String>,
    pub(super) axis: Option<Xyz>,
    /// Universal joints: the second axis (fixed in the child).
    pub(super) axis2: Option<Xyz>,
    /// Revolute joints: a linear torsion spring [N m/rad], at rest in the given geometry plus
    /// `torsion_rest` [rad].
    pub(super) torsion_stiffness: Option<Spanned<Num>>,
    pub(super) torsion_rest: Option<Spanned<Num>>,
    /// Viscous damping [N m s/rad or N s/m].
    pub(super) damping: Option<Spanned<Num>>,
    /// The joint's coordinate in the drawn geometry [rad or m] (default 0): an actuator's
    /// command is then the coordinate itself, not its change from the drawing.
    pub(super) initial_coordinate: Option<Spanned<Num>>,
    /// A copy generated by `[[structure.repeat]]`: its axes rotated.
    #[serde(skip)]
    pub(super) placement: Option<Placement>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawActuator {
    pub(super) symbol: Spanned<String>,
    pub(super) joint: Option<Spanned<String>>,
    pub(super) cable: Option<Spanned<String>>,
    /// A node of a fixed body, moved along `direction` by the command [m].
    pub(super) node: Option<Spanned<String>>,
    pub(super) direction: Option<Xyz>,
    /// A copy generated by `[[structure.repeat]]`: its direction rotated.
    #[serde(skip)]
    pub(super) placement: Option<Placement>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawWorkspace {
    /// The run passes when the analytic and dynamic workspace classifications agree at least
    /// at this percentage of the points; checks and settling are then reported per point.
    pub(super) min_agreement_percent: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPrestress {
    /// Lost when the settled cables' total tension is below this share of the drawn one.
    pub(super) min_fraction: Option<Spanned<f64>>,
    /// "fail" (default) or "warn".
    pub(super) on_loss: Option<Spanned<String>>,
    /// A custom structure prestressed with its drawn self-stress, the least tension this [N]
    /// (a number or an expression of the parameters: a prestress axis to sweep).
    pub(super) least_tension: Option<Spanned<Num>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawInterference {
    /// false turns the checks off, which the report says (default true).
    pub(super) enabled: Option<bool>,
    /// Check cables and springs too (default true).
    pub(super) tendons: Option<bool>,
    /// Clearance below which a pair violates [m] (default 0: actual overlap only).
    pub(super) threshold: Option<Spanned<f64>>,
    /// Pairs farther apart are not measured [m] (default: the mechanism's length scale).
    pub(super) margin: Option<Spanned<f64>>,
    /// Report violations without failing the run (default false).
    pub(super) informative: Option<bool>,
    /// Further member pairs to exclude, by name (struts, cables, springs).
    #[serde(default)]
    pub(super) exclude: Vec<Spanned<(String, String)>>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSim {
    pub(super) dt: Option<Spanned<f64>>,
    pub(super) substeps: Option<Spanned<i64>>,
    pub(super) pgs_iterations: Option<Spanned<i64>>,
    /// PGS iterations while approaching an equilibrium, before the final phase at
    /// `pgs_iterations` (default: the same, one phase).
    pub(super) approach_pgs_iterations: Option<Spanned<i64>>,
    /// The Newton damping schedule (default false: the structure's fixed damping).
    pub(super) newton_damping: Option<Spanned<bool>>,
    /// Static relaxation of free bodies held by springs and elastic cables (default true).
    pub(super) relaxation: Option<Spanned<bool>>,
    pub(super) body_damping: Option<Spanned<f64>>,
    pub(super) bounding_box: Option<Spanned<f64>>,
    /// Kinetic energy above which the run has diverged [J] (default 1e6).
    pub(super) max_kinetic_energy: Option<Spanned<f64>>,
    /// Anchor gap of a loop-closing joint above which the run has diverged [m] (default 1 % of
    /// the structure's size).
    pub(super) max_joint_gap: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSettle {
    pub(super) speed_tol: Option<Spanned<f64>>,
    pub(super) window: Option<Spanned<i64>>,
    pub(super) residual_force_tol: Option<Spanned<f64>>,
    pub(super) residual_torque_tol: Option<Spanned<f64>>,
    pub(super) max_time: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRange {
    pub(super) from: Spanned<f64>,
    pub(super) to: Spanned<f64>,
    pub(super) count: Spanned<i64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawActuation {
    /// A grid of inputs, each settled one by one (row-major in the inputs' order).
    pub(super) grid: Option<BTreeMap<Spanned<String>, Spanned<RawRange>>>,
    /// Explicit input sets, each settled one by one.
    pub(super) points: Option<Vec<Spanned<SpannedMap>>>,
    /// Waypoints in time (key `t` in s), linearly interpolated, held at the last; the run is
    /// compared tick by tick and settled after the last waypoint.
    pub(super) waypoints: Option<Vec<Spanned<SpannedMap>>>,
    /// Grid and points: start each point from the previous equilibrium (default true).
    pub(super) continuation: Option<bool>,
    /// Grid only: drop grid points outside the mechanism's domain (for example outside the
    /// kinematic workspace) instead of rejecting the file; they are counted in the report.
    pub(super) skip_outside: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCheck {
    pub(super) quantity: Spanned<String>,
    pub(super) tolerance: Spanned<f64>,
    /// Custom structures only: the expected value (there is no analytic model).
    pub(super) value: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStability {
    /// Displacement of every free coordinate [rad or m].
    pub(super) perturbation: Spanned<f64>,
    /// The stability every settle point must show ("stable" or "unstable"), or one per point.
    pub(super) expect: Option<Spanned<RawExpectedStability>>,
}

#[derive(Debug, Deserialize)]
#[serde(
    untagged,
    expecting = "stability.expect must be \"stable\", \"unstable\", \"energy\", or a list of \"stable\" and \"unstable\""
)]
pub(super) enum RawExpectedStability {
    All(String),
    PerPoint(Vec<String>),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawProbe {
    /// A named revolute or prismatic joint to probe (default: the mechanism's own probe).
    pub(super) joint: Option<Spanned<String>>,
    /// Probe torque [N m] (applied as +torque and -torque): the mechanism's probe or a
    /// revolute joint.
    pub(super) torque: Option<Spanned<f64>>,
    /// Probe force [N]: a prismatic joint.
    pub(super) force: Option<Spanned<f64>>,
    /// The joint probe's predicted stiffness: an expression of the parameters and inputs.
    pub(super) expected: Option<Spanned<String>>,
    /// Tolerance on the relative stiffness error (with `expected`, or the mechanism's probe;
    /// a joint probe without either only measures).
    pub(super) tolerance: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRecord {
    pub(super) path: Spanned<String>,
}

/// Members of one kind sharing their properties: one member per node pair, named
/// "<name>:<a>-<b>" or by `names` (one per pair, in order).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMemberGroup {
    pub(super) name: Spanned<String>,
    /// `[["A", "B"], ["B", "C"], ...]`: the two nodes of each member.
    pub(super) pairs: Spanned<Vec<Spanned<Vec<Spanned<String>>>>>,
    pub(super) names: Option<Spanned<Vec<Spanned<String>>>>,
    /// As in [`RawMember`]: struts' radius, springs' and cables' stiffness and length.
    pub(super) radius: Option<Spanned<Num>>,
    pub(super) stiffness: Option<Spanned<Num>>,
    pub(super) length: Option<Spanned<Num>>,
}
