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
}

impl ModelError {
    /// A [`ModelError::Value`] for `symbol`.
    pub fn value(symbol: impl Into<String>, message: impl Into<String>) -> Self {
        ModelError::Value { symbol: symbol.into(), message: message.into() }
    }
    /// A [`ModelError::NoSolution`].
    pub fn no_solution(message: impl Into<String>) -> Self {
        ModelError::NoSolution(message.into())
    }
    /// The symbol a [`ModelError::Value`] names.
    pub fn symbol(&self) -> Option<&str> {
        match self {
            ModelError::Value { symbol, .. } => Some(symbol),
            ModelError::NoSolution(_) => None,
        }
    }
}
