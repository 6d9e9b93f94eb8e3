//! The model a scenario file states, compiled: the symbols its expressions may use (each with
//! where its value comes from), its `[[quantities]]`, `[[predictions]]` and `[[equations]]`.
//! Plain data: the scenario loader builds it, the model observer evaluates it.

use super::expr::Expr;
use crate::mechanisms::{wrap_angle, Values};

/// Where the value of a symbol comes from at a tick or settle point.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A parameter (its value in the scenario).
    Param(f64),
    /// An input (actuator command) of the mechanism.
    Input(String),
    /// Simulated time \[s\].
    Time,
    /// Coordinate `axis` (0 x, 1 y, 2 z) of a node, by name \[m\].
    Node(String, usize),
    /// Force of a spring or cable, tension positive \[N\].
    MemberForce(String),
    /// Length of a spring, cable or strut (distance between its end nodes; a clustered
    /// cable's, the sum of its segments') \[m\].
    MemberLength(String),
    /// Tension of a clustered cable's segment (from 0, in path order) \[N\].
    SegmentForce(String, usize),
    /// Whether a cable with friction slips at its inner node (from 0, in path order): 1 at its
    /// friction bound, 0 held.
    Slip(String, usize),
    /// Angle of a revolute joint \[rad\]: its initial coordinate plus the child's rotation
    /// relative to the parent about the axis since the build.
    JointAngle(String),
    /// Slide of a prismatic joint \[m\]: its initial coordinate plus the child's displacement
    /// relative to the parent along the axis since the build.
    JointSlide(String),
    /// A quantity the mechanism observes (its `observe` values), by symbol.
    Observed(String),
    /// A `[[quantities]]` entry, by index.
    Quantity(usize),
}

/// A symbol an expression may use.
#[derive(Clone, Debug, PartialEq)]
pub struct Symbol {
    pub name: String,
    pub source: Source,
}

/// A `[[quantities]]` entry: a named expression of the state.
#[derive(Clone, Debug)]
pub struct Quantity {
    pub name: String,
    pub unit: String,
    pub expr: Expr,
    /// A closed form: it uses parameters, inputs and closed-form quantities only (a
    /// prediction's formula may then use it).
    pub closed_form: bool,
}

/// How a prediction's error is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorClass {
    /// |simulated - predicted| \[m\].
    Length,
    /// |simulated - predicted| wrapped to [0, pi] \[rad\].
    Angle,
    /// |simulated - predicted| / |predicted| (divided by 1 when the prediction is zero).
    Relative,
}

impl ErrorClass {
    pub const NAMES: &'static [&'static str] = &["length", "angle", "relative"];

    pub fn parse(s: &str) -> Option<ErrorClass> {
        Some(match s {
            "length" => ErrorClass::Length,
            "angle" => ErrorClass::Angle,
            "relative" => ErrorClass::Relative,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            ErrorClass::Length => "length",
            ErrorClass::Angle => "angle",
            ErrorClass::Relative => "relative",
        }
    }

    /// The error of `simulated` against `predicted`.
    pub fn error(self, predicted: f64, simulated: f64) -> f64 {
        let d = simulated - predicted;
        match self {
            ErrorClass::Length => d.abs(),
            ErrorClass::Angle => wrap_angle(d).abs(),
            ErrorClass::Relative => d.abs() / if predicted != 0.0 { predicted.abs() } else { 1.0 },
        }
    }
}

/// A `[[predictions]]` entry: a closed form of the parameters and inputs, compared with a
/// symbol of the state (a quantity, a node coordinate, an observed quantity).
#[derive(Clone, Debug)]
pub struct Prediction {
    pub name: String,
    /// The compared symbol's index in [`ModelSpec::symbols`].
    pub symbol: usize,
    pub formula: Expr,
    pub class: ErrorClass,
    /// On the error at each settle point, or in a motion run on the largest error over its
    /// ticks.
    pub tolerance: f64,
    /// A motion run only: on the rms error over its ticks.
    pub rms_tolerance: Option<f64>,
}

/// A `[[equations]]` entry: a residual that must vanish at every settled state.
#[derive(Clone, Debug)]
pub struct Equation {
    pub name: String,
    pub residual: Expr,
    pub tolerance: f64,
}

/// A scenario's model section, compiled.
#[derive(Clone, Debug, Default)]
pub struct ModelSpec {
    /// Every symbol, in the order expressions are compiled against (the quantities last).
    pub symbols: Vec<Symbol>,
    pub quantities: Vec<Quantity>,
    pub predictions: Vec<Prediction>,
    pub equations: Vec<Equation>,
    /// `[energy]`: a potential and its coordinates.
    pub energy: Option<super::energy_model::EnergySpec>,
    /// `[[sensitivities]]`: symbols read off the settled state's sensitivities.
    pub sensitivities: Vec<Sensitivity>,
}

/// A `[[sensitivities]]` entry: the symbol `name` (an observed value at each settle point) is
/// d(`output`)/d(`parameter`) there.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensitivity {
    pub name: String,
    pub output: String,
    pub parameter: String,
}

impl ModelSpec {
    /// Whether the file states nothing to compare.
    pub fn is_empty(&self) -> bool {
        self.quantities.is_empty() && self.predictions.is_empty() && self.equations.is_empty() && self.energy.is_none()
    }

    /// The names of every symbol, in order.
    pub fn names(&self) -> Vec<&str> {
        self.symbols.iter().map(|s| s.name.as_str()).collect()
    }

    /// Whether `name` is compared by an angle prediction (its error wrapped).
    pub fn is_angle(&self, name: &str) -> bool {
        self.predictions.iter().any(|p| p.class == ErrorClass::Angle && self.symbols[p.symbol].name == name)
    }

    /// Whether `name` is an `[energy]` coordinate of class angle.
    pub fn is_angle_coordinate(&self, name: &str) -> bool {
        let coordinates = self.energy.iter().flat_map(|e| &e.coordinates);
        coordinates.into_iter().any(|c| c.name == name && c.class == ErrorClass::Angle)
    }

    /// Whether symbol `i` is a closed form of the parameters and inputs.
    pub fn is_closed_form(&self, i: usize) -> bool {
        match self.symbols[i].source {
            Source::Param(_) | Source::Input(_) => true,
            Source::Quantity(q) => self.quantities[q].closed_form,
            _ => false,
        }
    }

    /// Every symbol's value, given the inputs, the parameters (a sweep over parameters
    /// changes them; one absent keeps the scenario's value) and a way to read the state's
    /// ones by symbol index (`state`: time, nodes, members, observed quantities; NaN when
    /// absent); the quantities evaluated in order.
    pub fn values(&self, inputs: &Values, params: &Values, state: impl Fn(usize) -> f64) -> Vec<f64> {
        let mut v: Vec<f64> = self
            .symbols
            .iter()
            .enumerate()
            .map(|(i, s)| match &s.source {
                Source::Param(x) => params.get(&s.name).copied().unwrap_or(*x),
                Source::Input(name) => inputs.get(name).copied().unwrap_or(f64::NAN),
                Source::Quantity(_) => f64::NAN,
                _ => state(i),
            })
            .collect();
        for (i, s) in self.symbols.iter().enumerate() {
            if let Source::Quantity(q) = s.source {
                v[i] = self.quantities[q].expr.eval(&v);
            }
        }
        v
    }
}
