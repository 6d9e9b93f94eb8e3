//! The plain structure an import makes (bodies with their nodes, struts, cables) and the
//! scenario file it is written as, with simulation settings chosen from its stiffness and
//! masses.

use crate::structure::{distance, Vec3};
use std::fmt::Write;

#[derive(Clone, Debug, PartialEq)]
pub struct DraftBody {
    pub name: String,
    pub fixed: bool,
    /// Mass \[kg\] of a free body.
    pub mass_kg: f64,
    /// Principal moments along the world axes [kg m^2] (None: the file format's default).
    pub inertia_kg_m2: Option<Vec3>,
    pub nodes: Vec<(String, Vec3)>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct DraftStrut {
    pub name: String,
    pub a: String,
    pub b: String,
    pub radius_m: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct DraftCable {
    pub name: String,
    pub a: String,
    /// The inner nodes of a clustered cable, in order from `a` to `b` (empty: straight).
    pub through: Vec<String>,
    pub b: String,
    /// [N/m]; None: inextensible.
    pub stiffness_n_per_m: Option<f64>,
    /// Unstretched length \[m\].
    pub length_m: f64,
    /// A tension-only cable (true) or a linear spring that pushes as well (false, written as
    /// `[[structure.springs]]`; needs a stiffness).
    pub tension_only: bool,
}

/// A joint from a fixed body to a node of a body: revolute about `axis`, or spherical (None);
/// damped so that it settles (`Draft::joint_damping`).
#[derive(Clone, Debug, PartialEq)]
pub struct DraftJoint {
    pub name: String,
    pub parent: String,
    pub child: String,
    pub at: String,
    pub axis: Option<Vec3>,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Draft {
    pub name: String,
    pub description: String,
    pub bodies: Vec<DraftBody>,
    pub struts: Vec<DraftStrut>,
    pub cables: Vec<DraftCable>,
    pub joints: Vec<DraftJoint>,
    /// `[[quantities]]`: (name, expression).
    pub quantities: Vec<(String, String)>,
}

/// The share of its drawn cable tension an imported structure must keep at its settled
/// state (`[prestress] min_fraction` written with every import whose cables are drawn taut).
pub const IMPORTED_MIN_FRACTION: f64 = 0.1;

/// Time step as a fraction of the fastest body's period scale sqrt(m / sum k) (the prism of
/// `scenarios/custom/prism3.toml`: 0.05 x sqrt(1 kg / 100 N/m) = 0.005 s, its own step).
const DT_FRACTION: f64 = 0.05;
/// Free-body damping [1/s] as a fraction of the fastest body's rate sqrt(sum k / m) (prism3:
/// 0.2 x 10/s = 2/s, its own damping): zero at rest, it only speeds settling.
const DAMPING_FRACTION: f64 = 0.2;
/// The rate [1/s] the settings assume when no free body carries a cable.
const FALLBACK_RATE_PER_S: f64 = 1.0;
/// Settle speed tolerance per metre of structure [1/s].
const SPEED_TOL_PER_M: f64 = 1e-12;
/// Residual tolerances relative to a cable force scale (stiffness x size) [-].
const RESIDUAL_FRACTION: f64 = 1e-10;
/// Settle time limit [s], in periods of the slowest body: generous, the limit fails a run.
const MAX_TIME_PERIODS: f64 = 4000.0;

/// A TOML basic string.
pub fn quote(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The body of a TOML multi-line basic string.
fn multiline(s: &str) -> String {
    s.replace('\\', "\\\\").replace("\"\"\"", "\"\"\\\"")
}

/// Why a draft cannot become a scenario file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DraftError {
    /// A number TOML cannot carry (inf or nan would make a scenario that means nothing).
    #[error("{what} would be {value}: the model's numbers are too large (or not numbers) to write")]
    NotFinite { what: String, value: f64 },
    /// A cable's share of the self-stress leaves it no rest length.
    #[error(
        "cable {cable}: its share of the self-stress, {tension_n} N at {stiffness_n_per_m} N/m, leaves no rest length (drawn {drawn_m} m)"
    )]
    SelfStressNoRest { cable: String, tension_n: f64, stiffness_n_per_m: f64, drawn_m: f64 },
    /// A string at the tension every string is given leaves it no rest length.
    #[error("string {string}: {tension_n} N at {stiffness_n_per_m} N/m leaves no rest length (drawn {drawn_m})")]
    TensionNoRest { string: String, tension_n: f64, stiffness_n_per_m: f64, drawn_m: f64 },
}

/// A number as TOML writes it back exactly, or an error naming `what` when it is not finite (TOML's
/// inf and nan would make a scenario that means nothing).
fn num(x: f64, what: &str) -> Result<String, DraftError> {
    if x.is_finite() {
        Ok(format!("{x:?}"))
    } else {
        Err(DraftError::NotFinite { what: what.to_string(), value: x })
    }
}

fn xyz(v: Vec3, what: &str) -> Result<String, DraftError> {
    Ok(format!("[{}, {}, {}]", num(v[0], what)?, num(v[1], what)?, num(v[2], what)?))
}

impl DraftCable {
    /// Its nodes in order: `a`, the inner ones, `b`.
    pub fn path(&self) -> impl Iterator<Item = &str> {
        std::iter::once(self.a.as_str()).chain(self.through.iter().map(String::as_str)).chain([self.b.as_str()])
    }
}

impl Draft {
    fn position(&self, node: &str) -> Option<Vec3> {
        self.bodies.iter().flat_map(|b| &b.nodes).find(|(n, _)| n == node).map(|(_, p)| *p)
    }

    /// A cable's drawn length, the sum of its segments' \[m\] (None: a node not drawn).
    pub fn drawn_length(&self, c: &DraftCable) -> Option<f64> {
        let path: Vec<Vec3> = c.path().map(|n| self.position(n)).collect::<Option<_>>()?;
        Some(crate::structure::path_length(path))
    }

    /// Whether an elastic cable is drawn longer than its rest length (in tension when drawn).
    fn drawn_taut(&self) -> bool {
        // Springs (not tension-only) are no cables: `[prestress]` judges cables only.
        self.cables
            .iter()
            .filter(|c| c.tension_only)
            .any(|c| c.stiffness_n_per_m.is_some() && self.drawn_length(c).is_some_and(|l| l > c.length_m))
    }

    /// Size of the structure \[m\]: the largest distance between two nodes (at least 1e-3).
    pub fn size_m(&self) -> f64 {
        let all: Vec<Vec3> = self.bodies.iter().flat_map(|b| b.nodes.iter().map(|(_, p)| *p)).collect();
        all.iter().flat_map(|a| all.iter().map(move |b| distance(*a, *b))).fold(1e-3, f64::max)
    }

    /// For each free body: (mass, sum of the stiffness of the cables on it).
    fn body_rates(&self) -> Vec<(f64, f64)> {
        self.bodies
            .iter()
            .filter(|b| !b.fixed)
            .map(|b| {
                let on = |n: &str| b.nodes.iter().any(|(m, _)| m == n);
                let k: f64 = self
                    .cables
                    .iter()
                    .filter(|c| on(&c.a) != on(&c.b))
                    .map(|c| c.stiffness_n_per_m.unwrap_or(0.0))
                    .sum();
                (b.mass_kg, k)
            })
            .collect()
    }

    /// The free bodies' rates sqrt(sum k / m) [1/s]: (fastest, slowest).
    fn rates(&self) -> (f64, f64) {
        let rates: Vec<f64> = self.body_rates().iter().filter(|(_, k)| *k > 0.0).map(|(m, k)| (k / m).sqrt()).collect();
        // Nothing elastic moves (all held, or no cable on a free body): the rate of a 1 s period.
        let fastest = rates.iter().copied().fold(f64::NAN, f64::max);
        let fastest = if fastest.is_finite() { fastest } else { FALLBACK_RATE_PER_S };
        (fastest, rates.iter().copied().fold(f64::INFINITY, f64::min).min(fastest))
    }

    /// A joint's damping [N m s/rad]: the bodies' damping rate times the child's moment of
    /// inertia about the joint (its largest principal moment plus m d^2, d from its nodes'
    /// centroid). A jointed body is a link of a multibody, which `body_damping` does not damp;
    /// zero at rest, this only lets it settle.
    fn joint_damping(&self, j: &DraftJoint) -> f64 {
        let Some(child) = self.bodies.iter().find(|b| b.name == j.child) else { return 0.0 };
        let n = child.nodes.len().max(1) as f64;
        let centroid = [0, 1, 2].map(|c| child.nodes.iter().map(|(_, p)| p[c]).sum::<f64>() / n);
        let d = self.position(&j.at).map_or(0.0, |p| distance(p, centroid));
        let moment = child.inertia_kg_m2.map_or(0.0, |i| i.iter().copied().fold(0.0, f64::max));
        DAMPING_FRACTION * self.rates().0 * (moment + child.mass_kg * d * d)
    }

    /// The `[sim]` and `[settle]` tables: a step and a damping from the fastest body, a time
    /// limit from the slowest.
    fn settings(&self) -> Result<String, DraftError> {
        let (fastest, slowest) = self.rates();
        let size = self.size_m();
        let k_max = self.cables.iter().filter_map(|c| c.stiffness_n_per_m).fold(0.0, f64::max).max(1.0);
        let residual = RESIDUAL_FRACTION * k_max * size;
        Ok(format!(
            "[sim]\ndt = {}\nbody_damping = {}\n\n[settle]\nspeed_tol = {}\nwindow = 10\nresidual_force_tol = {}\nresidual_torque_tol = {}\nmax_time = {}\n",
            num(DT_FRACTION / fastest, "sim.dt")?,
            num(DAMPING_FRACTION * fastest, "sim.body_damping")?,
            num(SPEED_TOL_PER_M * size, "settle.speed_tol")?,
            num(residual, "settle.residual_force_tol")?,
            num(residual * size, "settle.residual_torque_tol")?,
            num((MAX_TIME_PERIODS / slowest).ceil(), "settle.max_time")?
        ))
    }

    /// The scenario file: name, description, settings, one point, the structure; an error when
    /// a number of it would not be finite.
    /// A cable's (or a spring's) table, with its drawn length as a comment.
    fn write_cable(&self, t: &mut String, c: &DraftCable) -> Result<(), DraftError> {
        let drawn = match self.drawn_length(c) {
            Some(l) => format!("  # drawn {} m", num(l, &format!("cable {}", c.name))?),
            None => String::new(),
        };
        let table = if c.tension_only { "cables" } else { "springs" };
        let (name, a, b) = (quote(&c.name), quote(&c.a), quote(&c.b));
        let _ = writeln!(t, "\n[[structure.{table}]]\nname = {name}\na = {a}\nb = {b}");
        if !c.through.is_empty() {
            let inner: Vec<String> = c.through.iter().map(|n| quote(n)).collect();
            let _ = writeln!(t, "through = [{}]", inner.join(", "));
        }
        if let Some(k) = c.stiffness_n_per_m {
            let _ = writeln!(t, "stiffness = {}", num(k, &format!("the stiffness of cable {}", c.name))?);
        }
        let _ = writeln!(t, "length = {}{drawn}", num(c.length_m, &format!("the length of cable {}", c.name))?);
        Ok(())
    }

    pub fn to_toml(&self) -> Result<String, DraftError> {
        let mut t = String::new();
        let _ = writeln!(t, "name = {}", quote(&self.name));
        let _ = writeln!(t, "description = \"\"\"\n{}\n\"\"\"", multiline(&self.description));
        t.push_str("mechanism = \"custom\"\n\n");
        t.push_str(&self.settings()?);
        t.push_str("\n[actuation]\npoints = [ {} ]\n\n[structure]\n");
        for b in &self.bodies {
            let _ = writeln!(t, "\n[[structure.bodies]]\nname = {}", quote(&b.name));
            if b.fixed {
                t.push_str("fixed = true\n");
            } else {
                let _ = writeln!(t, "mass = {}", num(b.mass_kg, &format!("the mass of body {}", b.name))?);
                if let Some(i) = b.inertia_kg_m2 {
                    let _ = writeln!(t, "inertia = {}", xyz(i, &format!("the inertia of body {}", b.name))?);
                }
            }
            let node = |(n, p): &(String, Vec3)| Ok(format!("{} = {}", quote(n), xyz(*p, &format!("node {n}"))?));
            let nodes: Vec<String> = b.nodes.iter().map(node).collect::<Result<_, DraftError>>()?;
            let _ = writeln!(t, "nodes = {{ {} }}", nodes.join(", "));
        }
        for s in &self.struts {
            let _ = writeln!(
                t,
                "\n[[structure.struts]]\nname = {}\na = {}\nb = {}\nradius = {}",
                quote(&s.name),
                quote(&s.a),
                quote(&s.b),
                num(s.radius_m, &format!("the radius of strut {}", s.name))?
            );
        }
        for c in &self.cables {
            self.write_cable(&mut t, c)?;
        }
        for j in &self.joints {
            let kind = if j.axis.is_some() { "revolute" } else { "spherical" };
            let _ = writeln!(
                t,
                "\n[[structure.joints]]\nname = {}\nkind = \"{kind}\"\nparent = {}\nchild = {}\nat = {}",
                quote(&j.name),
                quote(&j.parent),
                quote(&j.child),
                quote(&j.at)
            );
            if let Some(a) = j.axis {
                let _ = writeln!(t, "axis = {}", xyz(a, &format!("the axis of joint {}", j.name))?);
            }
            let _ =
                writeln!(t, "damping = {}", num(self.joint_damping(j), &format!("the damping of joint {}", j.name))?);
        }
        for (name, expr) in &self.quantities {
            let _ = writeln!(t, "\n[[quantities]]\nname = {}\nexpr = {}", quote(name), quote(expr));
        }
        if self.drawn_taut() {
            let _ = write!(
                t,
                "\n# Written by the import: the run fails if the structure loses its self-stress (every cable\n\
                 # slack, or its cables' total tension below this share of the drawn one).\n\
                 [prestress]\nmin_fraction = {IMPORTED_MIN_FRACTION:?}\non_loss = \"fail\"\n"
            );
        }
        Ok(t)
    }
}
