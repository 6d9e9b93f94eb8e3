//! The one error type of the [`Mechanism`](super::Mechanism) contract.

/// Why a mechanism's analytic model or builder gave no result. Its text (`Display`) is the
/// message alone; a scenario locates a [`ModelError::Value`] at its symbol's key in the file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A parameter or input outside the model's domain (or missing), named by its symbol.
    #[error("{message}")]
    Value { symbol: String, message: String },
    /// The model has no answer here (an unreachable target, an unknown query, a structure that
    /// cannot be assembled).
    #[error("{0}")]
    NoSolution(String),
    /// A parameter outside the model's domain ([`ParamError`]), located at `symbol`.
    #[error("{source}")]
    Param { symbol: String, source: ParamError },
}

/// A parameter of an analytic model outside its domain.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// Not a finite number.
    #[error("{name} must be finite, got {value}")]
    NotFinite { name: &'static str, value: f64 },
    /// Not above 0.
    #[error("{name} must be > 0, got {value}")]
    NotPositive { name: &'static str, value: f64 },
    /// Not a finite number above 0.
    #[error("{name} must be finite and > 0, got {value}")]
    NotFinitePositive { name: &'static str, value: f64 },
    /// Not a finite number at or above 0.
    #[error("{name} must be finite and >= 0, got {value}")]
    NotFiniteNonNegative { name: &'static str, value: f64 },
    /// A condition between parameters, as the model states it.
    #[error("{0}")]
    Condition(String),
}

/// A name that names no built-in mechanism, or no query of one.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum UnknownName {
    /// No built-in mechanism is called `name` (`known`: those that are).
    #[error("unknown mechanism '{name}' (expected one of: {known})")]
    Mechanism { name: String, known: String },
    /// `mechanism` has no analytic query `query` (`known`: those it has).
    #[error("unknown query '{query}' for {mechanism} (expected one of: {known})")]
    Query { query: String, mechanism: String, known: String },
}

impl ModelError {
    /// A [`ModelError::Value`] for `symbol`.
    pub fn value(symbol: impl Into<String>, message: impl Into<String>) -> Self {
        ModelError::Value { symbol: symbol.into(), message: message.into() }
    }
    /// A [`ModelError::Param`] located at `symbol`.
    pub fn param(symbol: impl Into<String>, source: ParamError) -> Self {
        ModelError::Param { symbol: symbol.into(), source }
    }
    /// A [`ModelError::NoSolution`].
    pub fn no_solution(message: impl Into<String>) -> Self {
        ModelError::NoSolution(message.into())
    }
    /// The symbol a [`ModelError::Value`] names.
    pub fn symbol(&self) -> Option<&str> {
        match self {
            ModelError::Value { symbol, .. } | ModelError::Param { symbol, .. } => Some(symbol),
            ModelError::NoSolution(_) => None,
        }
    }
}
