//! A researcher's own model, stated in the scenario file: expressions of the parameters,
//! inputs and the simulated state (`expr.rs`), and the quantities, predictions and implicit
//! equations compiled from them (`spec.rs`), which the model observer evaluates, and an
//! energy model's stationary points (`energy_model.rs`), its kinetic energy's modes and
//! Lagrangian equations of motion (`dynamics.rs`), integrated by Dormand-Prince 5(4)
//! (`integrate.rs`); the file's parameters, evaluated again at
//! each point of a sweep over them (`params.rs`).

mod dual;
pub mod dynamics;
pub mod energy_model;
pub mod expr;
pub mod integrate;
pub mod params;
pub mod spec;
