//! What a simulation is built from and keeps for its whole life (MuJoCo's `mjModel`), and the
//! simulator's error: the types every concept of the step reads, beneath the step itself
//! (`mod.rs` orders the step; each concept file imports its types from here and its state from
//! `data.rs`). The plan types are the build's (`build.rs`): which bodies hang in which tree,
//! which loops close inside a multibody, which groups the projection closes. Their behaviour
//! lives in their concept's file (`tree.rs`, `group_tree.rs`, `projection.rs`); only the build
//! writes them.

use crate::settings::SimSettings;
use crate::structure::{BodyKind, Structure};
use rapier3d_f64::prelude::*;

/// Why the simulator refused a structure or a request, or stopped.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SimError {
    #[error("the structure cannot be simulated: {0}")]
    Build(String),
    #[error("simulation diverged at tick {tick} (t = {time_s:.6} s): {what}")]
    Diverged { tick: u64, time_s: f64, what: String },
    /// A request the built structure cannot carry out (a coordinate it does not have, a body
    /// that is not free, an actuator that cannot be driven physically).
    #[error("the simulator cannot do this: {0}")]
    Refused(String),
}

/// Where a free body sits in a multibody, so its joint coordinates can be read and perturbed.
#[derive(Clone, Copy, Debug)]
pub(super) struct LinkRef {
    pub(super) multibody_joint: MultibodyJointHandle,
}

/// What a simulation is built from and keeps for its whole life (MuJoCo's `mjModel`): the
/// structure and settings, and how the build mapped them onto rapier (handles, multibody
/// links, loop closures, rope joints, the link tree, constant loads). Only the build writes it.
#[derive(Clone)]
pub struct Model {
    pub structure: Structure,
    pub settings: SimSettings,
    /// rapier handle of each structure body.
    pub(super) handles: Vec<RigidBodyHandle>,
    /// For each joint: whether an actuator sets its coordinate (a kinematic multibody degree
    /// of freedom).
    pub(super) actuated: Vec<bool>,
    /// For each joint: the multibody link it made, if any.
    pub(super) joint_links: Vec<Option<LinkRef>>,
    /// First halves of universal joints split into two multibody revolutes.
    pub(super) hidden_links: Vec<LinkRef>,
    /// For each joint: the impulse joint it made, if any (loop closures).
    pub(super) joint_impulse: Vec<Option<ImpulseJointHandle>>,
    /// Loop closures inside one multibody, closed by position projection after each step.
    pub(super) internal_closures: Vec<InternalClosure>,
    /// Groups of free bodies (plain bodies and multibodies) whose joints and taut cables are
    /// closed by position projection.
    pub(super) projected_groups: Vec<ProjectedGroup>,
    /// Whether a cable has friction at a node (`capstan.rs`).
    pub(super) has_friction: bool,
    /// For each member: its rope joint if it is an inextensible cable.
    pub(super) ropes: Vec<Option<ImpulseJointHandle>>,
    /// The joint each body hangs from in the multibody forest (fixed at build).
    pub(super) tree: Tree,
    /// The reaction fit's tree: the multibody forest and the sparse groups' spanning trees
    /// (`tree.rs`).
    pub(super) fit_tree: Tree,
    /// The structure's constant external forces, summed per body [N].
    pub(super) external_loads: Vec<[f64; 3]>,
    /// The point loads on free bodies' nodes: node, force [N] (`Structure::node_loads`).
    pub(super) node_loads: Vec<(usize, nalgebra::Vector3<f64>)>,
    /// Characteristic length of the structure \[m\], for speeds and tolerances.
    pub length_scale_m: f64,
    /// Whether the static relaxation applies to this structure (`relaxation/`).
    pub(super) relaxation_applies: bool,
    /// Which bodies are point masses (`structure::lumped::point_masses`).
    pub(super) point_masses: Vec<bool>,
    /// Which world translations of each body its supports hold (`Structure::held_translations`;
    /// rapier locks them, the relaxation and the modes leave them out).
    pub(super) held_translations: Vec<[bool; 3]>,
}

impl Model {
    /// Bodies that move (not fixed).
    pub fn is_free(&self, body: usize) -> bool {
        self.structure.bodies[body].kind == BodyKind::Free
    }

    /// Whether the structure's modes and sensitivities are those of the constrained analysis
    /// (`constrained_modes.rs`): an inextensible cable, a joint that closes a loop, or a free
    /// joint of several coordinates (a universal joint: two revolute links and a hidden body,
    /// `build.rs`, charted by its multibody's degrees of freedom there).
    pub(super) fn is_constrained(&self) -> bool {
        let s = &self.structure;
        let several = |(j, joint): (usize, &crate::structure::Joint)| {
            !self.actuated[j]
                && !matches!(
                    joint.kind,
                    crate::structure::JointKind::Revolute { .. } | crate::structure::JointKind::Prismatic { .. }
                )
        };
        s.members.iter().any(|c| c.is_inextensible_cable())
            || self.joint_impulse.iter().any(Option::is_some)
            || s.joints.iter().enumerate().any(several)
    }

    /// Whether every projected group is of plain bodies alone (no multibody coordinates).
    pub(super) fn projected_groups_are_plain(&self) -> bool {
        self.projected_groups.iter().all(|g| g.multibodies.is_empty())
    }

    /// The same model stepped at `dt_s` [s] (a copy: the model itself never changes).
    pub(super) fn at_time_step(&self, dt_s: f64) -> Model {
        Model { settings: SimSettings { dt_s, ..self.settings.clone() }, ..self.clone() }
    }
}

/// A loop-closing joint inside one multibody: the rows of its gap that the projection zeroes.
#[derive(Clone, Debug)]
pub(super) struct InternalClosure {
    pub(super) joint: usize,
    pub(super) multibody: MultibodyIndex,
}

/// Free bodies held by impulse joints and inextensible cables to each other or to fixed
/// bodies: a group whose constraints the projection can close. Its coordinates are the poses
/// of its plain bodies and the free coordinates of the multibodies whose links it touches
/// (mohr2011's legs, each a multibody hung from the base, hold the end-effector, a plain body,
/// by spherical impulse joints).
///
/// rapier holds these constraints at the velocity level too; under a steady load (gravity on
/// manriquez2019's platform) the position offset it leaves grows like dt^2 and shrank only
/// slowly with PGS iterations (3e-5 rad at dt = 2 ms; on mohr2011 1e-9 took 64 to 512 PGS
/// iterations). After each step the group's coordinates are moved (Gauss-Newton, minimum norm,
/// rotations of plain bodies scaled by the structure's size) until every joint's anchor gap and
/// angular rows and every taut cable's stretch vanish to round-off; the velocities lose the
/// components that would open a joint or stretch a taut cable. The tensions of the cables held
/// this way are fitted from the equilibrium (`forces.rs`).
#[derive(Clone, Debug, Default)]
pub(super) struct ProjectedGroup {
    /// Structure body indices of the group's free plain bodies.
    pub bodies: Vec<usize>,
    /// Multibodies whose links the group's joints or cables touch.
    pub multibodies: Vec<MultibodyIndex>,
    /// Impulse joints (structure indices) between the group's bodies or to fixed bodies.
    pub joints: Vec<usize>,
    /// Inextensible cables with a rope joint.
    pub(super) cables: Vec<usize>,
    /// A sparse group's spanning tree, along which its Gauss-Newton steps move it.
    pub tree: Option<GroupTree>,
}

/// Where a body hangs in a tree: the joint that carries it and the body on that joint's other
/// side (the joint's parent for a multibody link; either side for a group's tree link).
#[derive(Clone, Copy, Debug)]
pub(super) struct Hang {
    pub joint: usize,
    pub parent: usize,
}

/// A forest of joints that carry bodies.
#[derive(Clone, Debug, Default)]
pub(super) struct Tree {
    /// Each body's hang, if any (None: a root).
    pub(super) hang: Vec<Option<Hang>>,
    /// Each joint's carried body, if the joint is in the tree.
    pub(super) carried: Vec<Option<usize>>,
    /// Each body's number of joints to its root.
    pub(super) depth: Vec<usize>,
    /// Bodies deepest first (ties: the higher index first): the order in which subtree sums
    /// are handed to the parents.
    pub(super) order: Vec<usize>,
    /// Whether any joint besides a multibody link's carries a body.
    pub(super) has_group_links: bool,
}

/// One body of the tree: its index in the group's bodies, its tree parent's (None: a fixed
/// body) and the joint between them.
#[derive(Clone, Copy, Debug)]
pub(super) struct Link {
    pub body: usize,
    pub parent: Option<usize>,
    pub joint: usize,
}

/// The spanning tree of a group's plain bodies, parents before children.
#[derive(Clone, Debug, Default)]
pub(super) struct GroupTree {
    pub(super) links: Vec<Link>,
}
