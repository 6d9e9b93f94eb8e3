//! A member: a path of two or more nodes with a law. Struts, springs, cables and clustered
//! cables are one list ([`super::Structure::members`]), read through one view: the path's
//! segments, its length, and the force its law gives at that length.
//!
//! A clustered cable runs through more than two nodes: it slides without friction at the
//! inner ones, so every segment carries the one tension k (l - l0), l the sum of the segments'
//! lengths and l0 the whole cable's unstretched length. It may close on itself (its last node
//! its first: a ring).

use super::{distance, NodeId, Vec3};

/// The length of the polyline through `points` \[m\]: its segments' lengths added in order
/// (0 for fewer than two points).
pub fn path_length(points: impl IntoIterator<Item = Vec3>) -> f64 {
    let mut points = points.into_iter();
    let Some(mut last) = points.next() else { return 0.0 };
    let mut total: Option<f64> = None;
    for p in points {
        let segment = distance(last, p);
        total = Some(total.map_or(segment, |t| t + segment));
        last = p;
    }
    total.unwrap_or(0.0)
}

/// Index of a member in [`super::Structure::members`].
pub type MemberId = usize;

/// The kind of a member, as a scenario file names its list.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum MemberKind {
    Strut,
    Spring,
    Cable,
}

impl MemberKind {
    /// The word a file, a table column and a message use (`strut`, `spring`, `cable`).
    pub fn label(self) -> &'static str {
        match self {
            MemberKind::Strut => "strut",
            MemberKind::Spring => "spring",
            MemberKind::Cable => "cable",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum CableLaw {
    /// Inextensible: never longer than `length_m`, slack (no force) when shorter.
    Inextensible,
    /// Elastic, tension only: force = max(0, stiffness (l - length_m)).
    Elastic { stiffness_n_per_m: f64 },
}

/// What a member does with its length.
#[derive(Clone, Debug, PartialEq)]
pub enum Law {
    /// A compression member drawn between two nodes of the same body (or of two bodies joined
    /// at its ends). It carries no force law of its own: it is rigid through its body.
    Strut,
    /// An elastic strut (a bar): its two nodes are point masses of their own
    /// (`structure/lumped.rs`), and it pushes and pulls along its axis with the axial stiffness
    /// EA / L: force = stiffness (l - rest_length).
    ElasticStrut {
        /// EA / L \[N/m\].
        stiffness_n_per_m: f64,
        /// Its length unloaded \[m\].
        rest_length_m: f64,
    },
    /// A linear spring that pushes as well as pulls: force = stiffness (l - rest_length).
    Spring {
        stiffness_n_per_m: f64,
        /// Free length \[m\]; zero is allowed (a zero-free-length spring).
        rest_length_m: f64,
    },
    /// A cable, which only pulls; clustered when its path has inner nodes.
    Cable {
        law: CableLaw,
        /// Unstretched length of the whole path in the initial configuration \[m\] (an
        /// actuator may change it).
        length_m: f64,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Member {
    pub name: String,
    /// The nodes it runs through, in order: two for a straight member, more for a clustered
    /// cable.
    pub path: Vec<NodeId>,
    pub law: Law,
    /// Radius of every segment's capsule, for interference checks and drawing \[m\].
    pub radius_m: f64,
    /// A clustered cable's Coulomb friction coefficient at each inner node, in path order
    /// (empty: it slides freely everywhere). Where one is above zero the cable is a capstan
    /// there (`sim/capstan.rs`): the segments on either side hold tensions within
    /// e^(mu theta) of each other, theta the angle the cable turns through at the node.
    pub friction: Vec<f64>,
}

impl Member {
    pub fn strut(name: impl Into<String>, a: NodeId, b: NodeId, radius_m: f64) -> Member {
        Member { name: name.into(), path: vec![a, b], law: Law::Strut, radius_m, friction: Vec::new() }
    }

    pub fn spring(
        name: impl Into<String>,
        [a, b]: [NodeId; 2],
        stiffness_n_per_m: f64,
        rest_length_m: f64,
        radius_m: f64,
    ) -> Member {
        let law = Law::Spring { stiffness_n_per_m, rest_length_m };
        Member { name: name.into(), path: vec![a, b], law, radius_m, friction: Vec::new() }
    }

    pub fn cable(name: impl Into<String>, path: Vec<NodeId>, law: CableLaw, length_m: f64, radius_m: f64) -> Member {
        Member { name: name.into(), path, law: Law::Cable { law, length_m }, radius_m, friction: Vec::new() }
    }

    pub fn kind(&self) -> MemberKind {
        match self.law {
            Law::Strut | Law::ElasticStrut { .. } => MemberKind::Strut,
            Law::Spring { .. } => MemberKind::Spring,
            Law::Cable { .. } => MemberKind::Cable,
        }
    }

    /// The first and the last node of the path.
    pub fn ends(&self) -> (NodeId, NodeId) {
        (self.path[0], self.path[self.path.len() - 1])
    }

    /// The straight segments of the path, node to node, in order.
    pub fn segments(&self) -> impl Iterator<Item = (NodeId, NodeId)> + '_ {
        self.path.windows(2).map(|w| (w[0], w[1]))
    }

    /// The same member with Coulomb friction `mu` at its inner nodes (a capstan).
    pub fn with_friction(mut self, mu: Vec<f64>) -> Member {
        self.friction = mu;
        self
    }

    /// Whether friction holds the cable at any inner node.
    pub fn has_friction(&self) -> bool {
        self.friction.iter().any(|&mu| mu > 0.0)
    }

    /// Whether the path has inner nodes (a clustered cable).
    pub fn is_clustered(&self) -> bool {
        self.path.len() > 2
    }

    /// The length it has no force at as drawn \[m\]: a spring's rest length, a cable's
    /// unstretched length, an elastic strut's unloaded length; None for a rigid strut.
    pub fn rest_length_m(&self) -> Option<f64> {
        match self.law {
            Law::Strut => None,
            Law::Spring { rest_length_m, .. } | Law::ElasticStrut { rest_length_m, .. } => Some(rest_length_m),
            Law::Cable { length_m, .. } => Some(length_m),
        }
    }

    /// The stiffness of its elastic law \[N/m\]: None for a rigid strut and an inextensible
    /// cable.
    pub fn stiffness_n_per_m(&self) -> Option<f64> {
        match self.law {
            Law::Spring { stiffness_n_per_m, .. } | Law::ElasticStrut { stiffness_n_per_m, .. } => {
                Some(stiffness_n_per_m)
            }
            Law::Cable { law: CableLaw::Elastic { stiffness_n_per_m }, .. } => Some(stiffness_n_per_m),
            Law::Strut | Law::Cable { law: CableLaw::Inextensible, .. } => None,
        }
    }

    /// A cable's law; None for a strut or a spring.
    pub fn cable_law(&self) -> Option<&CableLaw> {
        match &self.law {
            Law::Cable { law, .. } => Some(law),
            _ => None,
        }
    }

    /// A strut rigid through its body, with no force law of its own (an elastic strut has one).
    pub fn is_rigid_strut(&self) -> bool {
        matches!(self.law, Law::Strut)
    }

    pub fn is_inextensible_cable(&self) -> bool {
        matches!(self.law, Law::Cable { law: CableLaw::Inextensible, .. })
    }

    /// The path's length with the nodes at `position` \[m\]: the sum of its segments'.
    pub fn length_at(&self, position: impl Fn(NodeId) -> Vec3) -> f64 {
        path_length(self.path.iter().map(|&n| position(n)))
    }
}

/// The force law of a member whose force follows from its length: a spring (pushes and pulls)
/// or an elastic cable (pulls only), at its current rest length. The one law every reader of
/// member forces uses (the step, the relaxation, the modes, the sensitivities).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElasticLaw {
    pub stiffness_n_per_m: f64,
    pub rest_length_m: f64,
    pub tension_only: bool,
}

impl ElasticLaw {
    /// Whether the member carries force at length `l` \[m\] (a cable goes slack when not
    /// stretched).
    pub fn engaged(&self, l: f64) -> bool {
        !self.tension_only || l > self.rest_length_m
    }

    /// Tension at length `l` \[m\]: k (l - l0), at least 0 for a cable \[N\].
    pub fn tension_n(&self, l: f64) -> f64 {
        let t = self.stiffness_n_per_m * (l - self.rest_length_m);
        if self.tension_only {
            t.max(0.0)
        } else {
            t
        }
    }

    /// Elastic energy \[J\] at length `l` \[m\] on the branch of its law where it is `engaged`
    /// (a cable taut: k (l - l0)^2 / 2 on either side of l0; slack: 0): the energy's smooth
    /// part about a state where the member was so. A modal analysis's differences read it, so
    /// that none crosses a cable's kink at its rest length.
    pub fn energy_on_branch_j(&self, l: f64, engaged: bool) -> f64 {
        if engaged {
            0.5 * self.stiffness_n_per_m * (l - self.rest_length_m).powi(2)
        } else {
            0.0
        }
    }

    /// Elastic energy at length `l` \[J\]: k (l - l0)^2 / 2 where engaged.
    pub fn energy_j(&self, l: f64) -> f64 {
        self.energy_on_branch_j(l, self.engaged(l))
    }
}

impl Member {
    /// Its elastic law at the rest length `rest_length_m` \[m\] (a winch may have changed a
    /// cable's): None for a strut and an inextensible cable.
    pub fn elastic_law(&self, rest_length_m: f64) -> Option<ElasticLaw> {
        let tension_only = self.kind() == MemberKind::Cable;
        self.stiffness_n_per_m().map(|stiffness_n_per_m| ElasticLaw { stiffness_n_per_m, rest_length_m, tension_only })
    }
}
