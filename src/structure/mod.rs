//! The generic structure description: bodies, nodes, struts, springs, cables, joints and
//! actuators. A mechanism module turns its parameters into one of these; the simulator turns
//! one of these into rapier sets. Nothing in here knows about a particular paper.
//!
//! Conventions: SI units (m, kg, N, N/m, N m/rad, rad); node coordinates are *world*
//! coordinates in the initial configuration; a body's frame is its initial world pose.

use std::collections::BTreeMap;

pub mod equilibrium;
pub mod fidelity;
pub mod linear;
pub mod lumped;
mod member;
pub mod sparse_null;
pub use member::*;

/// A 3-vector in metres (or a unit axis).
pub type Vec3 = [f64; 3];

/// Radius of a cable or spring when nothing else is given \[m\]: a thin steel cable or wire
/// spring; used by the interference checks (a tendon through a strut or another tendon).
pub const DEFAULT_TENDON_RADIUS_M: f64 = 1e-3;

/// Index of a body in [`Structure::bodies`].
pub type BodyId = usize;
/// Index of a node in [`Structure::nodes`].
pub type NodeId = usize;
/// Index of a joint in [`Structure::joints`].
pub type JointId = usize;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyKind {
    /// Welded to the world.
    Fixed,
    /// Moves under the forces of the members and joints.
    Free,
}

/// Mass properties of a free body, expressed at its initial pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia {
    /// Mass \[kg\].
    pub mass_kg: f64,
    /// Centre of mass, world coordinates in the initial configuration \[m\].
    pub com: Vec3,
    /// Principal moments of inertia about the centre of mass, along the world axes [kg m^2].
    pub principal_kg_m2: Vec3,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    pub name: String,
    pub kind: BodyKind,
    /// Needed for free bodies; ignored for fixed ones.
    pub inertia: Option<Inertia>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub name: String,
    pub body: BodyId,
    /// World position in the initial configuration \[m\].
    pub position: Vec3,
}

#[derive(Clone, Debug, PartialEq)]
pub enum JointKind {
    /// One rotation about `axis` (world, initial configuration).
    Revolute { axis: Vec3 },
    /// One translation along `axis` (world, initial configuration).
    Prismatic { axis: Vec3 },
    /// Three rotations about the anchor.
    Spherical,
    /// Two rotations, about `axis1` (fixed in the parent) and `axis2` (fixed in the child).
    Universal { axis1: Vec3, axis2: Vec3 },
    /// No relative motion.
    Fixed,
    /// Keeps the two bodies' anchor points together in the plane normal to `axis` (two
    /// constraints). It closes a loop of a planar mechanism whose other joints already hold the
    /// motion in the plane: a full revolute joint there would add three redundant constraints,
    /// which rapier's solver did not resolve (measured on furet2018: a 1.3e-4 m gap that stayed).
    /// Never part of the joint tree.
    PlanarPin { axis: Vec3 },
}

impl JointKind {
    /// The coordinates the joint leaves its child (a joint that closes a loop takes as many
    /// constraint rows away instead).
    pub fn coordinate_count(&self) -> usize {
        match self {
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => 1,
            JointKind::Universal { .. } => 2,
            JointKind::Spherical => 3,
            JointKind::Fixed | JointKind::PlanarPin { .. } => 0,
        }
    }

    pub fn label(&self) -> &'static str {
        match self {
            JointKind::Revolute { .. } => "revolute",
            JointKind::Prismatic { .. } => "prismatic",
            JointKind::Spherical => "spherical",
            JointKind::Universal { .. } => "universal",
            JointKind::Fixed => "fixed",
            JointKind::PlanarPin { .. } => "planar pin",
        }
    }
}

/// A linear torsion spring on a revolute joint: torque = -stiffness (q - rest_angle), with q the
/// joint angle measured from the initial configuration plus `Joint::initial_coordinate`.
#[derive(Clone, Debug, PartialEq)]
pub struct TorsionSpring {
    pub stiffness_nm_per_rad: f64,
    pub rest_angle_rad: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    pub parent: BodyId,
    pub child: BodyId,
    /// The joint's centre, a node of the child or the parent (world, initial configuration).
    pub anchor: NodeId,
    /// Joint coordinate (rad or m) in the initial configuration, so that actuator targets and
    /// torsion-spring rest angles are absolute, in the paper's convention.
    pub initial_coordinate: f64,
    pub torsion_spring: Option<TorsionSpring>,
    /// Viscous damping on the joint's free coordinates [N m s/rad or N s/m]; zero at rest.
    pub damping: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ActuatorTarget {
    /// Position-controlled revolute or prismatic joint: its coordinate follows the command. A
    /// revolute joint with a torsion spring is a servo instead ([`Structure::servo_of`]): the
    /// command is the spring's rest angle, and the joint turns against it.
    Joint(JointId),
    /// Winch: the cable's unstretched length follows the command.
    CableLength(usize),
    /// A node of a fixed body moved directly: the body (with every node on it) is displaced
    /// from its drawn place by the command \[m\] along `direction` (a unit vector, world);
    /// several such actuators on one body add up.
    FixedNode { node: usize, direction: Vec3 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Actuator {
    /// The paper's symbol for the input (for example `L3`, `theta1`).
    pub symbol: String,
    pub target: ActuatorTarget,
}

/// A constant external force on a body, applied at its centre of mass (a payload's weight,
/// for example) \[N\], world frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ExternalLoad {
    pub body: BodyId,
    pub force_n: Vec3,
}

/// A constant external force at a node (a point load) \[N\], world frame: it moves with the
/// node, so on a rigid body off its centre of mass it turns the body.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeLoad {
    pub node: NodeId,
    pub force_n: Vec3,
}

/// A support that holds a node in some world directions only (a roller, a slot), on a point
/// mass (`lumped::is_point_mass`): its body cannot translate along the held axes, and the
/// support's reaction is the force it takes there.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeSupport {
    pub node: NodeId,
    /// Whether x, y and z (world) are held.
    pub held: [bool; 3],
}

/// A whole mechanism, ready to be simulated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Structure {
    pub name: String,
    /// Gravity [m/s^2].
    pub gravity: Vec3,
    pub bodies: Vec<Body>,
    pub nodes: Vec<Node>,
    /// Struts, springs and cables, one list ([`Member`]).
    pub members: Vec<Member>,
    pub joints: Vec<Joint>,
    pub actuators: Vec<Actuator>,
    pub loads: Vec<ExternalLoad>,
    /// Point loads at nodes.
    pub node_loads: Vec<NodeLoad>,
    /// Supports in some directions, at point masses.
    pub supports: Vec<NodeSupport>,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StructureError {
    #[error("{what} '{name}' refers to {kind} index {index}, which does not exist")]
    DanglingReference { what: &'static str, name: String, kind: &'static str, index: usize },
    #[error("{what} '{name}' has zero length: its two nodes coincide")]
    ZeroLength { what: &'static str, name: String },
    #[error("free body '{0}' needs a positive mass and positive moments of inertia")]
    NoMass(String),
    #[error("{what} '{name}': {message}")]
    Invalid { what: &'static str, name: String, message: String },
    #[error("duplicate name '{0}'")]
    Duplicate(String),
}

impl Structure {
    pub fn add_body(&mut self, name: &str, kind: BodyKind, inertia: Option<Inertia>) -> BodyId {
        self.bodies.push(Body { name: name.into(), kind, inertia });
        self.bodies.len() - 1
    }

    pub fn add_node(&mut self, name: &str, body: BodyId, position: Vec3) -> NodeId {
        self.nodes.push(Node { name: name.into(), body, position });
        self.nodes.len() - 1
    }

    /// The actuator commands the structure is built at, in actuator order: each actuated
    /// joint's initial coordinate (rad or m), each winch's cable length (m).
    pub fn initial_commands(&self) -> Vec<f64> {
        self.commands_from(&std::collections::BTreeMap::new())
    }

    /// Moves the nodes of every fixed body that carries a moved node ([`ActuatorTarget::FixedNode`])
    /// to where `commands` (actuator order) place them: the drawing of the structure at those
    /// commands, for a reader that has no such actuator.
    pub fn displace_fixed_nodes(&mut self, commands: &[f64]) {
        let mut offsets: Vec<Vec3> = vec![[0.0; 3]; self.bodies.len()];
        for (a, command) in self.actuators.iter().zip(commands) {
            if let ActuatorTarget::FixedNode { node, direction } = a.target {
                let o = &mut offsets[self.nodes[node].body];
                for (ok, d) in o.iter_mut().zip(direction) {
                    *ok += d * command;
                }
            }
        }
        for n in &mut self.nodes {
            for (x, d) in n.position.iter_mut().zip(offsets[n.body]) {
                *x += d;
            }
        }
    }

    /// Actuator commands in actuator order from values keyed by actuator symbol (m or rad);
    /// an actuator whose symbol has no value keeps its drawn coordinate or cable length.
    pub fn commands_from(&self, by_symbol: &std::collections::BTreeMap<String, f64>) -> Vec<f64> {
        self.actuators
            .iter()
            .map(|a| {
                by_symbol.get(&a.symbol).copied().unwrap_or(match a.target {
                    ActuatorTarget::Joint(j) => self.joints[j].initial_coordinate,
                    ActuatorTarget::CableLength(c) => self.members[c].rest_length_m().unwrap_or(f64::NAN),
                    ActuatorTarget::FixedNode { .. } => 0.0,
                })
            })
            .collect()
    }

    /// The member called `name`.
    pub fn member_id(&self, name: &str) -> Option<MemberId> {
        self.members.iter().position(|m| m.name == name)
    }

    /// The member called `name`.
    pub fn member(&self, name: &str) -> Option<&Member> {
        self.members.iter().find(|m| m.name == name)
    }

    /// Every member with its index, grouped by kind (struts, springs, cables) and in their
    /// order within a kind: the order every sum over members takes, so that a structure's
    /// forces add up alike however its builder interleaved the kinds.
    pub fn members_by_kind(&self) -> impl Iterator<Item = (MemberId, &Member)> + '_ {
        [MemberKind::Strut, MemberKind::Spring, MemberKind::Cable].into_iter().flat_map(|k| self.members_of(k))
    }

    /// Every member whose force follows from its length (springs, cables, elastic struts), with
    /// its index, in [`Self::members_by_kind`]'s order; a rigid strut has no law of its own.
    pub fn members_with_law(&self) -> impl Iterator<Item = (MemberId, &Member)> + '_ {
        self.members_by_kind().filter(|(_, m)| !m.is_rigid_strut())
    }

    /// The rigid struts with their indices, in their order.
    pub fn rigid_struts(&self) -> impl Iterator<Item = (MemberId, &Member)> + '_ {
        self.members_of(MemberKind::Strut).filter(|(_, m)| m.is_rigid_strut())
    }

    /// How many members of one kind there are.
    pub fn count_of(&self, kind: MemberKind) -> usize {
        self.members_of(kind).count()
    }

    /// The members of one kind with their indices, in their order.
    pub fn members_of(&self, kind: MemberKind) -> impl Iterator<Item = (MemberId, &Member)> + '_ {
        self.members.iter().enumerate().filter(move |(_, m)| m.kind() == kind)
    }

    /// The actuator of joint `j` if it is a servo: a revolute joint with a torsion spring,
    /// driven by an [`ActuatorTarget::Joint`] that sets the spring's rest angle (a position
    /// controller of finite stiffness) rather than the joint's coordinate.
    pub fn servo_of(&self, j: usize) -> Option<usize> {
        let joint = &self.joints[j];
        let revolute = matches!(joint.kind, JointKind::Revolute { .. });
        (revolute && joint.torsion_spring.is_some())
            .then(|| self.actuators.iter().position(|a| a.target == ActuatorTarget::Joint(j)))
            .flatten()
    }

    /// The first actuator driven by input `symbol`.
    pub fn actuator_id(&self, symbol: &str) -> Option<usize> {
        self.actuators.iter().position(|a| a.symbol == symbol)
    }

    /// The cables' total tension at the drawn state \[N\]: each elastic cable's stiffness times
    /// its stretch past its rest length (an inextensible cable carries none until loaded).
    pub fn drawn_cable_tension_n(&self) -> f64 {
        self.members_of(MemberKind::Cable)
            .filter_map(|(_, c)| {
                let law = c.elastic_law(c.rest_length_m()?)?;
                Some(law.tension_n(c.length_at(|n| self.nodes[n].position)))
            })
            .sum()
    }

    pub fn node_id(&self, name: &str) -> Option<NodeId> {
        let found = self.nodes.iter().position(|n| n.name == name);
        #[cfg(test)]
        NODE_NAMES_COMPARED.with(|c| c.set(c.get() + found.map_or(self.nodes.len(), |k| k + 1)));
        found
    }

    pub fn body_id(&self, name: &str) -> Option<BodyId> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Initial world positions of all nodes, by name.
    pub fn initial_positions(&self) -> BTreeMap<String, Vec3> {
        self.nodes.iter().map(|n| (n.name.clone(), n.position)).collect()
    }

    /// Checks references, lengths and masses. Every built-in mechanism and every file-described
    /// structure goes through this before it reaches the simulator.
    pub fn validate(&self) -> Result<(), StructureError> {
        self.validate_bodies()?;
        self.validate_nodes()?;
        self.validate_members()?;
        self.validate_joints()?;
        self.validate_actuators()?;
        self.validate_loads()?;
        self.validate_supports()?;
        Ok(())
    }

    /// Each support holds at least one direction of a point mass, one support per node.
    fn validate_supports(&self) -> Result<(), StructureError> {
        if self.supports.is_empty() {
            return Ok(());
        }
        let points = lumped::point_masses(self);
        let mut supported = vec![false; self.nodes.len()];
        for (i, support) in self.supports.iter().enumerate() {
            let name = self.nodes.get(support.node).map_or(format!("#{i}"), |n| n.name.clone());
            self.check_node("support", &name, support.node)?;
            if !support.held.contains(&true) {
                return Err(invalid("support", &name, "holds no direction"));
            }
            if !points[self.nodes[support.node].body] {
                return Err(invalid("support", &name, "the node's body is not a point mass"));
            }
            if std::mem::replace(&mut supported[support.node], true) {
                return Err(invalid("support", &name, "the node has another support"));
            }
        }
        Ok(())
    }

    /// The free bodies that no joint carries (beside the joint trees, or every free body of a
    /// structure without joints).
    pub fn unjointed_free_bodies(&self) -> Vec<BodyId> {
        let mut carried = vec![false; self.bodies.len()];
        for j in &self.joints {
            carried[j.child] = true;
        }
        (0..self.bodies.len()).filter(|&b| self.bodies[b].kind == BodyKind::Free && !carried[b]).collect()
    }

    /// Which world translations (x, y, z) of each body its supports hold.
    pub fn held_translations(&self) -> Vec<[bool; 3]> {
        let mut held = vec![[false; 3]; self.bodies.len()];
        for support in &self.supports {
            let body = &mut held[self.nodes[support.node].body];
            for (h, s) in body.iter_mut().zip(support.held) {
                *h |= s;
            }
        }
        held
    }

    /// Body names are unique; a free body has a finite mass and inertia > 0.
    fn validate_bodies(&self) -> Result<(), StructureError> {
        let mut seen = std::collections::BTreeSet::new();
        for b in &self.bodies {
            if !seen.insert(&b.name) {
                return Err(StructureError::Duplicate(b.name.clone()));
            }
            if b.kind == BodyKind::Free {
                let ok = b.inertia.is_some_and(|i| {
                    i.mass_kg > 0.0
                        && i.mass_kg.is_finite()
                        && i.principal_kg_m2.iter().all(|m| *m > 0.0 && m.is_finite())
                });
                if !ok {
                    return Err(StructureError::NoMass(b.name.clone()));
                }
            }
        }
        Ok(())
    }

    /// Node names are unique, each on an existing body, at finite coordinates.
    fn validate_nodes(&self) -> Result<(), StructureError> {
        let mut seen = std::collections::BTreeSet::new();
        for n in &self.nodes {
            if !seen.insert(&n.name) {
                return Err(StructureError::Duplicate(n.name.clone()));
            }
            self.check_body("node", &n.name, n.body)?;
            if n.position.iter().any(|c| !c.is_finite()) {
                return Err(invalid("node", &n.name, "coordinates must be finite numbers"));
            }
        }
        Ok(())
    }

    /// Members have unique names and join existing nodes with finite positive sizes and
    /// stiffnesses: struts and springs two distinct nodes, cables two or more, no node twice
    /// in a row.
    fn validate_members(&self) -> Result<(), StructureError> {
        let mut seen = std::collections::BTreeSet::new();
        for m in &self.members {
            let what = m.kind().label();
            if !seen.insert(&m.name) {
                return Err(invalid(what, &m.name, "another member has this name"));
            }
            self.check_path(m)?;
            if !(m.radius_m >= 0.0 && m.radius_m.is_finite()) {
                return Err(invalid(what, &m.name, "radius must be a finite number >= 0 m"));
            }
            if let Some(k) = m.stiffness_n_per_m() {
                if !(k > 0.0 && k.is_finite()) {
                    return Err(invalid(what, &m.name, "stiffness must be a finite number > 0 N/m"));
                }
            }
            if !m.friction.is_empty() && m.friction.len() + 2 != m.path.len() {
                let message = format!(
                    "friction takes one coefficient per inner node: {} for {}",
                    m.friction.len(),
                    m.path.len().saturating_sub(2)
                );
                return Err(invalid(what, &m.name, &message));
            }
            if m.friction.iter().any(|mu| !(mu.is_finite() && *mu >= 0.0)) {
                return Err(invalid(what, &m.name, "a friction coefficient must be a finite number >= 0"));
            }
            if m.has_friction() && m.kind() != MemberKind::Cable {
                return Err(invalid(what, &m.name, "only a cable has friction at its inner nodes"));
            }
            match m.law {
                Law::Spring { rest_length_m, .. } if !(rest_length_m >= 0.0 && rest_length_m.is_finite()) => {
                    return Err(invalid(what, &m.name, "rest length must be a finite number >= 0 m"))
                }
                Law::Cable { length_m, .. } if !(length_m > 0.0 && length_m.is_finite()) => {
                    return Err(invalid(what, &m.name, "length must be a finite number > 0 m"))
                }
                Law::Cable { law: CableLaw::Inextensible, .. } if m.is_clustered() => {
                    return Err(invalid(
                        what,
                        &m.name,
                        "a clustered cable needs a stiffness (an inextensible one through inner nodes is not modelled)",
                    ))
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Joints join two different existing bodies (the child free) at an existing node, along finite non-zero axes; torsion springs on revolute joints only.
    fn validate_joints(&self) -> Result<(), StructureError> {
        for j in &self.joints {
            self.check_body("joint", &j.name, j.parent)?;
            self.check_body("joint", &j.name, j.child)?;
            self.check_node("joint", &j.name, j.anchor)?;
            if j.parent == j.child {
                return Err(invalid("joint", &j.name, "parent and child must be different bodies"));
            }
            if self.bodies[j.child].kind == BodyKind::Fixed {
                return Err(invalid("joint", &j.name, "the child body must not be fixed"));
            }
            let axes: Vec<Vec3> = match &j.kind {
                JointKind::Revolute { axis } | JointKind::Prismatic { axis } => vec![*axis],
                JointKind::Universal { axis1, axis2 } => vec![*axis1, *axis2],
                _ => vec![],
            };
            for a in axes {
                let n = norm(a);
                if !(n > 1e-12 && n.is_finite()) {
                    return Err(invalid("joint", &j.name, "axis must be a finite non-zero vector"));
                }
            }
            if j.torsion_spring.is_some() && !matches!(j.kind, JointKind::Revolute { .. }) {
                return Err(invalid("joint", &j.name, "a torsion spring needs a revolute joint"));
            }
            if !(j.damping >= 0.0 && j.damping.is_finite()) {
                return Err(invalid("joint", &j.name, "damping must be a finite number >= 0"));
            }
        }
        Ok(())
    }

    /// A moved node lies on a fixed body that no joint holds (a joint to it is anchored in the
    /// ground), along a unit direction.
    fn validate_fixed_node(&self, symbol: &str, node: usize, direction: Vec3) -> Result<(), StructureError> {
        let n = self.nodes.get(node).ok_or_else(|| StructureError::DanglingReference {
            what: "actuator",
            name: symbol.to_string(),
            kind: "node",
            index: node,
        })?;
        if self.bodies[n.body].kind != BodyKind::Fixed {
            return Err(invalid(
                "actuator",
                symbol,
                "a moved node must lie on a fixed body (free nodes follow the dynamics)",
            ));
        }
        if self.joints.iter().any(|j| j.parent == n.body || j.child == n.body) {
            return Err(invalid(
                "actuator",
                symbol,
                "a moved node's body must carry no joint (put the node on a fixed body of its own)",
            ));
        }
        let norm = direction.iter().map(|x| x * x).sum::<f64>().sqrt();
        let off = (norm - 1.0).abs();
        if off.is_nan() || off > 1e-12 {
            return Err(invalid("actuator", symbol, "the direction of a moved node must be a unit vector"));
        }
        Ok(())
    }

    /// Actuators drive an existing revolute or prismatic joint (a revolute one with a torsion
    /// spring as a servo), an existing cable, or a node of a fixed body.
    fn validate_actuators(&self) -> Result<(), StructureError> {
        for a in &self.actuators {
            match a.target {
                ActuatorTarget::Joint(j) => {
                    let joint = self.joints.get(j).ok_or_else(|| StructureError::DanglingReference {
                        what: "actuator",
                        name: a.symbol.clone(),
                        kind: "joint",
                        index: j,
                    })?;
                    if !matches!(joint.kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. }) {
                        return Err(invalid(
                            "actuator",
                            &a.symbol,
                            "only revolute and prismatic joints can be actuated",
                        ));
                    }
                    // A torsion spring on an actuated joint makes it a servo (`servo_of`).
                }
                ActuatorTarget::CableLength(c) => {
                    if self.members.get(c).is_none_or(|m| m.kind() != MemberKind::Cable) {
                        return Err(StructureError::DanglingReference {
                            what: "actuator",
                            name: a.symbol.clone(),
                            kind: "cable",
                            index: c,
                        });
                    }
                }
                ActuatorTarget::FixedNode { node, direction } => {
                    self.validate_fixed_node(&a.symbol, node, direction)?
                }
            }
        }
        Ok(())
    }

    /// External loads act on existing bodies with finite forces.
    fn validate_loads(&self) -> Result<(), StructureError> {
        for (i, load) in self.loads.iter().enumerate() {
            self.check_body("load", &format!("#{i}"), load.body)?;
            if load.force_n.iter().any(|f| !f.is_finite()) {
                return Err(invalid("load", &format!("#{i}"), "force must be finite"));
            }
        }
        for (i, load) in self.node_loads.iter().enumerate() {
            self.check_node("load", &format!("#{i}"), load.node)?;
            if load.force_n.iter().any(|f| !f.is_finite()) {
                return Err(invalid("load", &format!("#{i}"), "force must be finite"));
            }
        }
        Ok(())
    }

    fn check_body(&self, what: &'static str, name: &str, b: BodyId) -> Result<(), StructureError> {
        if b >= self.bodies.len() {
            return Err(StructureError::DanglingReference { what, name: name.into(), kind: "body", index: b });
        }
        Ok(())
    }

    fn check_node(&self, what: &'static str, name: &str, n: NodeId) -> Result<(), StructureError> {
        if n >= self.nodes.len() {
            return Err(StructureError::DanglingReference { what, name: name.into(), kind: "node", index: n });
        }
        Ok(())
    }

    /// A member's path: existing nodes, two of them for a strut or a spring, at least two for
    /// a cable, no node twice in a row, and every segment of a strut or a cable longer than
    /// [`MIN_MEMBER_LENGTH_M`].
    fn check_path(&self, m: &Member) -> Result<(), StructureError> {
        let what = m.kind().label();
        for &n in &m.path {
            self.check_node(what, &m.name, n)?;
        }
        if m.kind() != MemberKind::Cable && m.path.len() != 2 {
            return Err(invalid(what, &m.name, "needs exactly two nodes"));
        }
        if m.path.len() < 2 {
            return Err(invalid(what, &m.name, "a cable runs through at least two nodes"));
        }
        for (a, b) in m.segments() {
            if a == b && m.is_clustered() {
                return Err(invalid(what, &m.name, "repeats a node in a row"));
            }
            if a == b {
                return Err(StructureError::ZeroLength { what, name: m.name.clone() });
            }
            let short = distance(self.nodes[a].position, self.nodes[b].position) < MIN_MEMBER_LENGTH_M;
            if m.kind() != MemberKind::Spring && short {
                return Err(StructureError::ZeroLength { what, name: m.name.clone() });
            }
        }
        Ok(())
    }
}

/// Shortest strut or cable the description accepts \[m\]. (A spring may start at zero length:
/// a zero-free-length spring whose ends coincide carries no force and is legal.)
pub const MIN_MEMBER_LENGTH_M: f64 = 1e-9;

fn invalid(what: &'static str, name: &str, message: &str) -> StructureError {
    StructureError::Invalid { what, name: name.into(), message: message.into() }
}

/// The diagonal of the nodes' bounding box in the drawing \[m\]: the structure's extent, which the
/// simulation's ranges scale with (linear in the nodes, unlike [`structure_size`]).
pub fn extent_m(s: &Structure) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for n in &s.nodes {
        for k in 0..3 {
            lo[k] = lo[k].min(n.position[k]);
            hi[k] = hi[k].max(n.position[k]);
        }
    }
    (0..3).map(|k| (hi[k] - lo[k]).max(0.0).powi(2)).sum::<f64>().sqrt()
}

pub fn norm(v: Vec3) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

pub fn distance(a: Vec3, b: Vec3) -> f64 {
    norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]])
}

/// `v` turned by `angle` \[rad\] about `axis` (through the origin; any length but zero), by
/// Rodrigues' formula.
pub fn rotated(v: Vec3, axis: Vec3, angle: f64) -> Vec3 {
    let n = norm(axis);
    let k = axis.map(|c| c / n);
    let (s, c) = angle.sin_cos();
    let kxv = [k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]];
    let kdv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    std::array::from_fn(|i| v[i] * c + kxv[i] * s + k[i] * kdv * (1.0 - c))
}

/// Largest distance between two nodes of the structure \[m\] (at least 1e-3 m). The squares
/// are compared: the square root is monotonic and correctly rounded, so the root of the
/// largest square is the largest of the roots, to the bit.
///
/// The nodes are taken in runs of `SIZE_RUN_NODES` in their order (a structure is drawn
/// member by member, so a run is compact), each with its bounding box. The pairs between two
/// runs are measured only where the two boxes' farthest corners are farther apart than the
/// largest pair found so far, starting from a double sweep (the node farthest from the first,
/// then the node farthest from it). Rounding is monotonic, so the boxes bound every pair as
/// computed, and the result is the all-pairs maximum to the bit (a unit test compares them).
/// Measuring every pair had been a third of building a 100-X furet2018 chain.
pub fn structure_size(s: &Structure) -> f64 {
    let p: Vec<Vec3> = s.nodes.iter().map(|n| n.position).collect();
    let Some(first) = p.first() else { return MIN_STRUCTURE_SIZE_M };
    let squared = |a: &Vec3, b: &Vec3| {
        let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    };
    let farthest =
        |a: &Vec3| p.iter().map(|b| squared(a, b)).enumerate().fold((0, 0.0), |m, x| if x.1 > m.1 { x } else { m });
    let mut largest_squared = farthest(&p[farthest(first).0]).1;
    let runs: Vec<(&[Vec3], Vec3, Vec3)> = p
        .chunks(SIZE_RUN_NODES)
        .map(|run| {
            let (lo, hi) = run.iter().fold((run[0], run[0]), |(lo, hi), q| {
                (std::array::from_fn(|k| lo[k].min(q[k])), std::array::from_fn(|k| hi[k].max(q[k])))
            });
            (run, lo, hi)
        })
        .collect();
    for (i, (a, alo, ahi)) in runs.iter().enumerate() {
        for (b, blo, bhi) in &runs[i..] {
            let bound = (0..3).map(|k| (ahi[k] - blo[k]).max(bhi[k] - alo[k])).fold(0.0, |x, d| x + d * d);
            if bound <= largest_squared {
                continue;
            }
            let same = std::ptr::eq(*a, *b);
            for (x, pa) in a.iter().enumerate() {
                let others = if same { &b[x + 1..] } else { &b[..] };
                largest_squared = others.iter().fold(largest_squared, |m, pb| m.max(squared(pa, pb)));
            }
        }
    }
    largest_squared.sqrt().max(MIN_STRUCTURE_SIZE_M)
}

/// Nodes per run of [`structure_size`]'s bounding boxes.
const SIZE_RUN_NODES: usize = 16;

/// The smallest size [`structure_size`] reports [m].
const MIN_STRUCTURE_SIZE_M: f64 = 1e-3;

/// Most free bodies whose modes are computed (`sim::modes`) where they are a dense
/// eigenproblem (jointed structures and those held by constraints): it grows with the cube of
/// their count (100, 200, 300 struts: 0.9, 5.2, 19.8 s; 1000 struts more than 2 GiB); at the
/// bound about 25-45 s, stopped by a signal within a poll.
pub const MAX_MODAL_FREE_BODIES: usize = 400;

/// Free bodies up to which the modes of a structure of free bodies held by springs and elastic
/// cables are the dense eigenproblem (every mode); above, the sparse shift-invert solver gives
/// the lowest [`SPARSE_MODAL_COUNT`] beyond the rigid ones. Measured on the bench prisms: at
/// 100 free bodies the dense problem takes 0.25-0.32 s (every mode; 8.9 s at 299, growing with
/// the cube), the sparse one at 101 free bodies 0.08 s; below, every mode is cheap enough to
/// list, and every shipped scenario (at most a few tens of bodies) keeps the dense solver.
pub const DENSE_MODAL_MAX_FREE_BODIES: usize = 100;

/// Non-rigid modes the sparse solver computes unless asked for more (the lowest, with every
/// rigid one it finds): `modes --count`, or a motion along a higher mode.
pub const SPARSE_MODAL_COUNT: usize = 20;

/// Most non-rigid modes the sparse solver computes: its block of `count` + 20 vectors is
/// orthonormalised and its Rayleigh-Ritz problem solved every iteration, work that grows with
/// the block's square times the coordinates (measured in BENCHMARKS.md).
pub const MAX_SPARSE_MODAL_COUNT: usize = 200;

/// Most free bodies whose lowest modes the sparse solver computes: each rigid mode it reports
/// (a strut's spin: about one per body) holds a shape and a motion per node, so the report
/// grows with the square of the count (at the bound 410 MB and about 4 s for the whole
/// command on the bench prism), the settle before it with the count.
pub const MAX_SPARSE_MODAL_FREE_BODIES: usize = 2000;

/// Most point masses (`lumped::is_point_mass`: elastic struts' ends, heavy cables' beads) whose
/// structure's lowest modes the sparse solver computes. Their turns are no modes, so the report
/// does not grow with them; the solve does, about linearly (measured in BENCHMARKS.md: 2898
/// point masses of a 100-strut prism, 8998 of a 300-strut one).
pub const MAX_SPARSE_MODAL_POINT_MASSES: usize = 10_000;

/// Whether the modes of `s` are those of free bodies held by springs and elastic cables (the
/// static relaxation's domain: no joints, no inextensible cables, no friction): the sparse
/// solver's domain above [`DENSE_MODAL_MAX_FREE_BODIES`].
pub fn modes_of_free_bodies(s: &Structure) -> bool {
    s.joints.is_empty() && !s.members.iter().any(|c| c.is_inextensible_cable() || c.has_friction())
}

/// What bounds and numbers the modes of `s`: its free bodies, and the point masses among them
/// whose turns the analysis of free bodies on springs and elastic cables leaves out
/// (`sim/modes.rs`; none elsewhere). The modes number six per free body less three per such
/// point mass, and the point masses count apart from [`modal_free_body_bound`].
pub fn modal_bodies(s: &Structure) -> (usize, usize) {
    let free = s.bodies.iter().filter(|b| b.kind == BodyKind::Free).count();
    let points = if modes_of_free_bodies(s) { lumped::point_masses(s).into_iter().filter(|&p| p).count() } else { 0 };
    (free, points)
}

/// The most free bodies whose modes are computed for `s`: [`MAX_SPARSE_MODAL_FREE_BODIES`] for
/// free bodies on springs and elastic cables, [`MAX_MODAL_FREE_BODIES`] otherwise.
pub fn modal_free_body_bound(s: &Structure) -> usize {
    if modes_of_free_bodies(s) {
        MAX_SPARSE_MODAL_FREE_BODIES
    } else {
        MAX_MODAL_FREE_BODIES
    }
}

#[cfg(test)]
thread_local! {
    /// The node names [`Structure::node_id`] has compared on this thread: the tests' count of
    /// the work of looking nodes up by name (each lookup scans the nodes).
    pub(crate) static NODE_NAMES_COMPARED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

#[cfg(test)]
mod tests {
    /// The largest distance between nodes, every pair measured (what [`super::structure_size`]
    /// prunes).
    fn all_pairs_size(s: &super::Structure) -> f64 {
        let mut largest_squared: f64 = 0.0;
        for (i, a) in s.nodes.iter().enumerate() {
            for b in &s.nodes[i + 1..] {
                let d = [a.position[0] - b.position[0], a.position[1] - b.position[1], a.position[2] - b.position[2]];
                largest_squared = largest_squared.max(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
        }
        largest_squared.sqrt().max(1e-3)
    }

    /// The pruned structure size is the all-pairs one to the bit: on 50 clouds of 1 to 295
    /// pseudo-random nodes (a fixed linear congruential sequence), each stretched along x by
    /// up to 50 times, one of them a node alone; and on as many noisy half circles of nodes in
    /// order, where most pairs of runs are left out.
    #[test]
    fn the_pruned_size_is_the_largest_pair_distance_to_the_bit() {
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for cloud in 0..50 {
            let (mut s, mut arc) = (super::Structure::default(), super::Structure::default());
            let (body, arc_body) =
                (s.add_body("b", super::BodyKind::Fixed, None), arc.add_body("b", super::BodyKind::Fixed, None));
            let stretch = 1.0 + 49.0 * (cloud as f64 / 49.0);
            let nodes = 1 + cloud * 6;
            for i in 0..nodes {
                s.add_node(&format!("n{i}"), body, [stretch * next(), next(), 0.1 * next()]);
                // In order along a half circle, as a curled chain is drawn.
                let angle = std::f64::consts::PI * i as f64 / nodes as f64;
                let at = [stretch * angle.cos() + 0.1 * next(), stretch * angle.sin() + 0.1 * next(), 0.1 * next()];
                arc.add_node(&format!("n{i}"), arc_body, at);
            }
            assert_eq!(super::structure_size(&s).to_bits(), all_pairs_size(&s).to_bits(), "cloud {cloud}");
            assert_eq!(super::structure_size(&arc).to_bits(), all_pairs_size(&arc).to_bits(), "arc {cloud}");
        }
    }

    use super::*;

    fn two_bodies() -> Structure {
        let mut s = Structure::default();
        let g = s.add_body("ground", BodyKind::Fixed, None);
        let b = s.add_body(
            "b",
            BodyKind::Free,
            Some(Inertia { mass_kg: 1.0, com: [1.0, 0.0, 0.0], principal_kg_m2: [0.1; 3] }),
        );
        s.add_node("A", g, [0.0; 3]);
        s.add_node("B", b, [1.0, 0.0, 0.0]);
        s
    }

    #[test]
    fn a_valid_structure_passes_validation() {
        let mut s = two_bodies();
        s.members.push(Member::spring("k", [0, 1], 10.0, 0.0, DEFAULT_TENDON_RADIUS_M));
        assert_eq!(s.validate(), Ok(()));
    }

    #[test]
    fn a_member_naming_an_unknown_node_is_rejected() {
        let mut s = two_bodies();
        s.members.push(Member::cable("c", vec![0, 7], CableLaw::Inextensible, 1.0, DEFAULT_TENDON_RADIUS_M));
        assert!(matches!(s.validate(), Err(StructureError::DanglingReference { index: 7, .. })));
    }

    #[test]
    fn a_zero_length_strut_is_rejected() {
        let mut s = two_bodies();
        s.add_node("A2", 0, [0.0; 3]);
        s.members.push(Member::strut("s", 0, 2, 0.01));
        assert_eq!(s.validate(), Err(StructureError::ZeroLength { what: "strut", name: "s".into() }));
    }

    #[test]
    fn a_free_body_without_mass_is_rejected() {
        let mut s = two_bodies();
        s.bodies[1].inertia = Some(Inertia { mass_kg: 0.0, com: [0.0; 3], principal_kg_m2: [0.1; 3] });
        assert_eq!(s.validate(), Err(StructureError::NoMass("b".into())));
    }

    #[test]
    fn a_negative_spring_stiffness_is_rejected() {
        let mut s = two_bodies();
        s.members.push(Member::spring("k", [0, 1], -1.0, 0.0, DEFAULT_TENDON_RADIUS_M));
        assert!(matches!(s.validate(), Err(StructureError::Invalid { what: "spring", .. })));
    }
}
