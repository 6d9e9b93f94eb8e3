//! The built-in mechanisms. Each one lives in its own folder: `analytic.rs` (the paper's model,
//! pure functions), `findings.rs` (the paper's printed equations checked against that model,
//! as [`Finding`]s) and `build.rs` (parameters -> [`Structure`]); `mod.rs` ties them to the
//! [`Mechanism`] trait that the rest of the testbed uses.

mod angle;
pub mod custom;
mod error;
pub mod finding;
pub mod furet2018;
pub mod ji2014;
pub mod manriquez2019;
pub mod mohr2011;
pub mod relaxed;

pub use angle::wrap_angle;
pub use error::{ModelError, ParamError, UnknownName};
pub use finding::{finding, Finding};

use crate::snapshot::Snapshot;
use crate::structure::Structure;
use std::collections::BTreeMap;

/// Named values keyed by the paper's symbols (SI units unless a spec says otherwise).
pub type Values = BTreeMap<String, f64>;

/// Whether a parameter comes from the paper or is a choice of the dynamic model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    Paper,
    /// Not in the paper: a plausible value chosen for the simulation (documented in `source`).
    ModelChoice,
}

#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    pub symbol: &'static str,
    pub unit: &'static str,
    pub default: f64,
    pub description: &'static str,
    pub origin: Origin,
}

#[derive(Clone, Copy, Debug)]
pub struct InputSpec {
    pub symbol: &'static str,
    pub unit: &'static str,
    pub description: &'static str,
}

/// How errors of a quantity are normalised for the relative error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuantityKind {
    /// Divided by the mechanism's characteristic length.
    Length,
    /// Angles: the error is wrapped to (-pi, pi] and taken as is (rad).
    Angle,
    /// Divided by the magnitude of the analytic value (forces, stiffness, energy).
    Magnitude,
}

#[derive(Clone, Copy, Debug)]
pub struct QuantitySpec {
    pub symbol: &'static str,
    pub unit: &'static str,
    pub kind: QuantityKind,
    pub description: &'static str,
}

#[derive(Clone, Copy, Debug)]
pub struct QuerySpec {
    pub name: &'static str,
    pub inputs: &'static [&'static str],
    pub description: &'static str,
}

/// One result of an analytic query: one branch, root or solution.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    pub label: String,
    pub values: Values,
    /// Stability of the equilibrium, where that applies.
    pub stable: Option<bool>,
}

/// The analytic quasi-static prediction for one set of inputs.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// The branch the dynamics is expected to reach (the stable one), keyed by quantity.
    pub expected: Values,
    /// Every branch, for identifying which one the dynamics landed on.
    pub branches: Vec<Solution>,
    /// For mechanisms with cables: the cables (by structure name) that the analytic statics
    /// says are slack here. A non-empty set means the analytic point is not an equilibrium:
    /// the settled state is not checked against it; the slack set is.
    pub expected_slack: Option<Vec<String>>,
}

/// A small load applied to a body to measure a stiffness in the simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct StiffnessProbe {
    /// Body that carries the load.
    pub body: String,
    /// Torque axis (world) [unit vector].
    pub torque_axis: [f64; 3],
    /// The coordinate whose change is measured (a simulated quantity, rad).
    pub coordinate: String,
    /// The analytic quantity to compare dtau/dq with (N m/rad).
    pub analytic: String,
}

/// What a mechanism is, as data: its name and title and the symbols a scenario may use.
#[derive(Clone, Copy, Debug)]
pub struct MechanismSpec {
    pub name: &'static str,
    pub title: &'static str,
    pub params: &'static [ParamSpec],
    pub inputs: &'static [InputSpec],
    pub quantities: &'static [QuantitySpec],
    pub queries: &'static [QuerySpec],
    /// Keys accepted in a scenario's `[start]` table: (key, meaning).
    pub start_keys: &'static [(&'static str, &'static str)],
    /// Other sets of symbols a scenario may give instead of the inputs (for example the
    /// end-effector position of a cable-driven mechanism); [`Mechanism::convert_inputs`] turns
    /// them into inputs through the analytic inverse model.
    pub alternative_inputs: &'static [&'static [&'static str]],
}

/// A mechanism from a paper: its analytic model and how to build it for the simulator.
pub trait Mechanism: Send + Sync {
    /// The mechanism's name, title and symbols.
    fn spec(&self) -> &MechanismSpec;
    fn name(&self) -> &'static str {
        self.spec().name
    }
    fn title(&self) -> &'static str {
        self.spec().title
    }
    fn params(&self) -> &'static [ParamSpec] {
        self.spec().params
    }
    fn inputs(&self) -> &'static [InputSpec] {
        self.spec().inputs
    }
    fn quantities(&self) -> &'static [QuantitySpec] {
        self.spec().quantities
    }
    fn queries(&self) -> &'static [QuerySpec] {
        self.spec().queries
    }
    fn start_keys(&self) -> &'static [(&'static str, &'static str)] {
        self.spec().start_keys
    }
    /// The start keys that are flags: 0 or 1 (another number had been taken as 1).
    fn start_flags(&self) -> &'static [&'static str] {
        &[]
    }
    /// Pairs of start keys that exclude each other: with both given, the second would be
    /// ignored (the file names the start once).
    fn start_exclusive(&self) -> &'static [(&'static str, &'static str)] {
        &[]
    }
    fn alternative_inputs(&self) -> &'static [&'static [&'static str]] {
        self.spec().alternative_inputs
    }
    /// Checks parameter values; the message names the parameter and the accepted range.
    fn validate_params(&self, params: &Values) -> Result<(), ModelError>;
    /// Converts one of the [`Mechanism::alternative_inputs`] sets into inputs;
    /// a [`ModelError::Value`] naming the symbol when it has no solution.
    fn convert_inputs(&self, _params: &Values, given: &Values) -> Result<Values, ModelError> {
        Ok(given.clone())
    }
    /// Checks one set of inputs against the parameters; the error names the input.
    fn validate_inputs(&self, params: &Values, inputs: &Values) -> Result<(), ModelError>;
    /// The analytic model alone: every result of `query`.
    fn solve(&self, query: &str, params: &Values, inputs: &Values) -> Result<Vec<Solution>, ModelError>;
    /// The structure at `inputs`, with the free coordinates started from `start` (symbols of
    /// free coordinates; missing ones take the mechanism's default start).
    fn build(&self, params: &Values, inputs: &Values, start: &Values) -> Result<Structure, ModelError>;
    /// Actuator commands for `inputs`, keyed by the structure's actuator symbols (m or rad;
    /// default: the inputs themselves, for actuators named after them).
    fn commands(&self, _params: &Values, inputs: &Values) -> Values {
        inputs.clone()
    }
    /// Whether the `[start]` table deliberately starts the dynamics on an analytically
    /// unstable branch (landing there is then what the scenario asks, not a failure).
    fn starts_on_unstable_branch(&self, _start: &Values) -> bool {
        false
    }
    /// The analytic prediction for `inputs`.
    fn predict(&self, params: &Values, inputs: &Values) -> Result<Prediction, ModelError>;
    /// The simulated quantities read off a snapshot.
    fn observe(&self, params: &Values, structure: &Structure, snap: &Snapshot) -> Values;
    /// Characteristic length \[m\] used to normalise length errors.
    fn length_scale(&self, params: &Values) -> f64;
    /// The paper's own printed values at `inputs`, where it prints any (for example a table of
    /// forces): (source, values in the testbed's units). Shown beside the testbed's analytic and
    /// simulated values in reports, never checked against: a printed table can be wrong.
    fn paper_values(&self, _params: &Values, _inputs: &Values) -> Option<(String, Values)> {
        None
    }
    /// Analytic node positions at the expected equilibrium, in the order of the structure's
    /// nodes, for the ghost overlay of recordings.
    fn analytic_nodes(&self, _params: &Values, _inputs: &Values) -> Option<Vec<[f64; 3]>> {
        None
    }
    fn stiffness_probe(&self) -> Option<StiffnessProbe> {
        None
    }
    /// Every printed equation checked against the derivation.
    fn findings(&self, params: &Values) -> Vec<Finding>;
}

/// All built-in mechanisms.
pub fn registry() -> Vec<Box<dyn Mechanism>> {
    vec![
        Box::new(ji2014::Ji2014),
        Box::new(mohr2011::Mohr2011),
        Box::new(furet2018::Furet2018),
        Box::new(manriquez2019::Manriquez2019),
    ]
}

pub fn find(name: &str) -> Option<Box<dyn Mechanism>> {
    registry().into_iter().find(|m| m.name() == name)
}

/// The built-in mechanism called `name`, or the message that lists the known ones.
pub fn find_named(name: &str) -> Result<Box<dyn Mechanism>, UnknownName> {
    find(name).ok_or_else(|| {
        let known: Vec<_> = registry().iter().map(|m| m.name()).collect();
        UnknownName::Mechanism { name: name.to_string(), known: known.join(", ") }
    })
}

/// The analytic query `query` of `m`, or the message that lists its queries.
pub fn query_named(m: &dyn Mechanism, query: &str) -> Result<&'static QuerySpec, UnknownName> {
    m.queries().iter().find(|q| q.name == query).ok_or_else(|| {
        let known: Vec<_> = m.queries().iter().map(|q| q.name).collect();
        UnknownName::Query { query: query.to_string(), mechanism: m.name().to_string(), known: known.join(", ") }
    })
}

/// The parameter values: the defaults overridden by `given`.
pub fn with_defaults(m: &dyn Mechanism, given: &Values) -> Values {
    let mut out: Values = m.params().iter().map(|p| (p.symbol.to_string(), p.default)).collect();
    for (k, v) in given {
        out.insert(k.clone(), *v);
    }
    out
}

/// Checks that every `(symbol, unit)` parameter is a finite number > 0; the error names the
/// first that is not.
pub fn require_positive(v: &Values, specs: &[(&str, &str)]) -> Result<(), ModelError> {
    for (sym, unit) in specs {
        let x = param(v, sym)?;
        if !(x > 0.0 && x.is_finite()) {
            return Err(ModelError::value(*sym, format!("{sym} must be a finite number > 0 {unit}, got {x}")));
        }
    }
    Ok(())
}

/// Checks that every `(symbol, unit)` parameter is a finite number >= 0.
pub fn require_non_negative(v: &Values, specs: &[(&str, &str)]) -> Result<(), ModelError> {
    for (sym, unit) in specs {
        let x = param(v, sym)?;
        if !(x >= 0.0 && x.is_finite()) {
            return Err(ModelError::value(*sym, format!("{sym} must be a finite number >= 0 {unit}, got {x}")));
        }
    }
    Ok(())
}

/// The value of parameter `symbol`, or an error naming it (a symbol the mechanism's spec does
/// not declare: [`with_defaults`] fills every declared one).
pub fn param(params: &Values, symbol: &str) -> Result<f64, ModelError> {
    params.get(symbol).copied().ok_or_else(|| ModelError::value(symbol, format!("missing parameter '{symbol}'")))
}

/// The value of input `key`, or an error naming it.
pub fn input(inputs: &Values, key: &str) -> Result<f64, ModelError> {
    inputs.get(key).copied().ok_or_else(|| ModelError::value(key, format!("missing input '{key}'")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_symbol_is_an_error_naming_it_not_a_panic() {
        let v = Values::from([("L".to_string(), 1.0)]);
        assert_eq!(param(&v, "L"), Ok(1.0));
        assert_eq!(param(&v, "K1"), Err(ModelError::value("K1", "missing parameter 'K1'")));
        assert_eq!(require_positive(&v, &[("L", "m"), ("K1", "N/m")]).unwrap_err().symbol(), Some("K1"));
        assert_eq!(input(&v, "theta1").unwrap_err().to_string(), "missing input 'theta1'");
        assert!(find("ji2014").unwrap().build(&with_defaults(&ji2014::Ji2014, &Values::new()), &v, &v).is_err());
    }
}
