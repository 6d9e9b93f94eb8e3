//! A researcher's own model, stated in the scenario file: expressions of the parameters,
//! inputs and the simulated state (`expr.rs`), and the quantities, predictions and implicit
//! equations compiled from them (`spec.rs`), which the model observer evaluates, and an
//! energy model's stationary points (`energy_model.rs`); the file's parameters, evaluated again at
//! each point of a sweep over them (`params.rs`).

pub mod energy_model;
pub mod expr;
pub mod params;
pub mod spec;
