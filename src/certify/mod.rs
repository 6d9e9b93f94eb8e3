//! Certified equilibria (issue 65): a proof, in interval arithmetic, that a structure of free
//! bodies on springs and elastic cables has exactly one equilibrium in a box around its
//! settled state, and of that equilibrium's stability.
//!
//! What is proven is about the equilibrium equations as built (`Problem`: the settled
//! structure's geometry, members, rest lengths and constant forces, read from the simulation
//! by `sim/certificate.rs`), F(q) = dV/dq = 0 in each free body's coordinates (a translation of
//! its centre of mass and a rotation about it, the directions that move no node left out: a
//! strut's spin, a point mass's turns), not about rapier's integrator. Over a box X around a
//! centre x (the settled state after float Newton steps), Krawczyk's operator
//! K(X) = x - Y F(x) + (1 - Y J(X)) (X - x), Y a float inverse of J(x), J(X) the enclosure of
//! the Hessian over X: where K(X) lies in X's interior, F has exactly one zero in X, and it lies
//! in K(X) (Krawczyk 1969; Moore, Kearfott & Cloud, Introduction to Interval Analysis, section
//! 8.2). The box is grown from the Newton step's size by fours and bisected back to the largest
//! that passes. Stability: the inertia of every matrix in J(X) by interval LDL^T
//! (`inertia.rs`), and a lower bound on the smallest eigenvalue (N/m, rotations measured as
//! arcs at the structure's size) where it is positive definite. Every float operation is
//! rounded outward (`crate::interval`); Y, the centre and the radii need no rigour: a poor one
//! only makes the test fail.

pub mod enclosure;
pub mod inertia;
pub mod jet;
mod krawczyk;

pub use krawczyk::{certify, excludes_equilibrium, reduced_stiffness};

/// A free body's block of coordinates: dx, dy, dz of its centre of mass \[m\], then one
/// rotation \[rad\] per kept direction.
#[derive(Clone, Debug)]
pub struct Block {
    pub name: String,
    /// Its centre of mass at the settled state \[m\].
    pub com: [f64; 3],
    /// The rotation directions that move a node (orthonormal; none for a point mass).
    pub rotations: Vec<[f64; 3]>,
    /// Its first coordinate.
    pub first: usize,
}

impl Problem {
    /// The proof's unknowns: every coordinate but the gauge's ([`Problem::gauge`]).
    pub fn unknowns(&self) -> Vec<usize> {
        let gauge = self.gauge();
        (0..self.size()).filter(|&i| Some(i) != gauge).collect()
    }

    /// The coordinate held by the gauge of [`Problem::turn_axis`]: the translation that the
    /// turn moves most (its rate along the turn, u x (c - a), largest in magnitude).
    pub fn gauge(&self) -> Option<usize> {
        let (a, u) = self.turn_axis?;
        let mut best: Option<(usize, f64)> = None;
        for b in &self.blocks {
            let r = [b.com[0] - a[0], b.com[1] - a[1], b.com[2] - a[2]];
            let rate = [u[1] * r[2] - u[2] * r[1], u[2] * r[0] - u[0] * r[2], u[0] * r[1] - u[1] * r[0]];
            for (k, v) in rate.iter().enumerate() {
                if best.is_none_or(|(_, m)| v.abs() > m) {
                    best = Some((b.first + k, v.abs()));
                }
            }
        }
        best.filter(|(_, m)| *m > 0.0).map(|(i, _)| i)
    }
}

/// Where a node is: fixed, or on a free body at an arm from its centre of mass (settled) \[m\].
#[derive(Clone, Debug)]
pub enum Node {
    Fixed([f64; 3]),
    OnBlock { block: usize, arm: [f64; 3] },
}

/// A straight elastic member between two nodes: a spring or an elastic strut (two-sided), or
/// an elastic cable (tension only).
#[derive(Clone, Debug)]
pub struct Spring {
    pub name: String,
    pub a: usize,
    pub b: usize,
    pub stiffness_n_per_m: f64,
    pub rest_m: f64,
    pub tension_only: bool,
}

/// The equilibrium equations of a settled structure (module docs).
#[derive(Clone, Debug)]
pub struct Problem {
    /// The structure's size \[m\]: a rotation's arc is measured at it.
    pub length_m: f64,
    pub blocks: Vec<Block>,
    pub nodes: Vec<Node>,
    pub node_names: Vec<String>,
    pub members: Vec<Spring>,
    /// Each block's constant force at its centre of mass (gravity and loads) \[N\].
    pub forces: Vec<[f64; 3]>,
    /// Constant loads at nodes \[N\].
    pub node_loads: Vec<(usize, [f64; 3])>,
    /// A line about which the whole structure turns freely (its anchors on it, every constant
    /// force along it): a point on it and its direction. Equilibria then form circles about
    /// it, and the proof holds the one translation coordinate that the turn moves most at its
    /// settled value (a gauge): uniqueness is up to the turn.
    pub turn_axis: Option<([f64; 3], [f64; 3])>,
}

impl Problem {
    /// The number of coordinates.
    pub fn size(&self) -> usize {
        self.blocks.last().map_or(0, |b| b.first + 3 + b.rotations.len())
    }

    /// Each coordinate's scale: 1 for a translation \[m\], the structure's size for a rotation
    /// (its arc there, m).
    pub fn scales(&self) -> Vec<f64> {
        self.blocks
            .iter()
            .flat_map(|b| (0..3 + b.rotations.len()).map(|i| if i < 3 { 1.0 } else { self.length_m }))
            .collect()
    }

    /// Each coordinate's name: `BODY.x` .. `BODY.z`, `BODY.r1` ...
    pub fn coordinate_names(&self) -> Vec<String> {
        self.blocks
            .iter()
            .flat_map(|b| {
                let turns = (1..=b.rotations.len()).map(move |j| format!("{}.r{j}", b.name));
                ["x", "y", "z"].iter().map(move |c| format!("{}.{c}", b.name)).chain(turns)
            })
            .collect()
    }
}

/// What the stiffness over the certified box proves.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Stability {
    /// Every matrix in the enclosure is positive definite, its smallest eigenvalue (coordinates
    /// scaled to m) at least `smallest_eigenvalue_at_least_n_per_m`.
    Stable { smallest_eigenvalue_at_least_n_per_m: f64 },
    /// Every matrix in the enclosure has `index` negative eigenvalues: an unstable equilibrium.
    Unstable { index: usize },
    /// Nothing proven, and why.
    Unproven { why: String },
}

/// A proof of existence and uniqueness.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Proof {
    /// The largest box found: each translation within this of the centre \[m\], each rotation
    /// within it over the structure's size \[rad x m\].
    pub radius_m: f64,
    /// The same box's rotations \[rad\] (none where no body turns: point masses alone).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius_rad: Option<f64>,
    /// How far each node moves over the box, at most \[m\].
    pub node_radius_m: f64,
    /// The equilibrium's enclosure K(X): its largest radius (scaled, m).
    pub enclosure_radius_m: f64,
    /// The settled state's distance from the proven equilibrium, at most (scaled, m).
    pub settled_offset_m: f64,
    /// The coordinate held at its settled value (the gauge of a free turn), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held_coordinate: Option<String>,
    pub stability: Stability,
    /// Each node's position over the equilibrium's enclosure, by name \[m\] (what the file's
    /// model is judged against: [`Proof::judge_model`]).
    #[serde(skip)]
    pub node_enclosures: Vec<(String, [crate::interval::Interval; 3])>,
    /// The file's model's node positions against the enclosure, where it predicts any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<ModelInside>,
}

/// Where the file's model puts the nodes, against the proven equilibrium's enclosure.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ModelInside {
    /// Node coordinates predicted inside the enclosure: the model's point is the proven
    /// equilibrium there, to the enclosure's width.
    pub inside: usize,
    /// Those predicted outside it, by quantity (`NODE.x`): the model is not the equilibrium
    /// there.
    pub outside: Vec<String>,
    /// The largest distance of a prediction outside the enclosure from it \[m\] (0: none).
    pub largest_outside_m: f64,
}

impl Proof {
    /// Judges the model's `predicted` values that are node coordinates (`NODE.x`, `.y`, `.z`)
    /// against the equilibrium's enclosure ([`Proof::model`]).
    pub fn judge_model(&mut self, predicted: &std::collections::BTreeMap<String, f64>) {
        let mut judged = ModelInside { inside: 0, outside: Vec::new(), largest_outside_m: 0.0 };
        for (name, &value) in predicted {
            let Some((node, axis)) = name.rsplit_once('.') else { continue };
            let Some(k) = ["x", "y", "z"].iter().position(|a| *a == axis) else { continue };
            let Some((_, p)) = self.node_enclosures.iter().find(|(n, _)| n == node) else { continue };
            if p[k].contains(value) {
                judged.inside += 1;
            } else {
                judged.outside.push(name.clone());
                judged.largest_outside_m = judged.largest_outside_m.max((p[k].lo - value).max(value - p[k].hi));
            }
        }
        if judged.inside + judged.outside.len() > 0 {
            self.model = Some(judged);
        }
    }
}

impl Certificate {
    /// No proof, for `reason` (a structure outside the proof's domain).
    pub fn refused(reason: String) -> Certificate {
        Certificate { coordinates: 0, residual: f64::NAN, proof: None, reason: Some(reason), boxes: 0 }
    }

    /// One line: what is proven, or why nothing is.
    pub fn summary(&self) -> String {
        let Some(p) = &self.proof else {
            return format!("certificate: not proven: {}", self.reason.as_deref().unwrap_or("no box passed"));
        };
        let stability = match &p.stability {
            Stability::Stable { smallest_eigenvalue_at_least_n_per_m: s } => {
                format!("stable (smallest eigenvalue >= {s:.3e} N/m)")
            }
            Stability::Unstable { index } => format!("unstable (index {index})"),
            Stability::Unproven { why } => format!("stability not proven: {why}"),
        };
        let turn = p.held_coordinate.as_ref().map(|c| format!(" up to the free turn ({c} held)")).unwrap_or_default();
        let model = match &p.model {
            Some(m) if m.outside.is_empty() => {
                format!("; the model's {} node coordinate(s) inside its enclosure: proven", m.inside)
            }
            Some(m) => format!(
                "; the model's node coordinates: {} inside its enclosure, {} outside (largest {:.1e} m): not the proven equilibrium",
                m.inside,
                m.outside.len(),
                m.largest_outside_m
            ),
            None => String::new(),
        };
        format!(
            "certificate: one equilibrium within {:.3e} m{turn}, the settled state within {:.1e} m of it; {stability}{model}",
            p.radius_m, p.settled_offset_m
        )
    }
}

/// The certificate of a settled state: a proof, or why there is none.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Certificate {
    pub coordinates: usize,
    /// The largest |F| at the settled state (an upper bound) \[N or N m\].
    pub residual: f64,
    pub proof: Option<Proof>,
    /// Why there is no proof.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Boxes tried.
    pub boxes: usize,
}
