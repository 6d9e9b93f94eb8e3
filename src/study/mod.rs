//! Studies: the work that drives many runs of one scenario and reads what each gives, above the
//! runner (`run/`), which knows none of them.
//!
//! - `sweep.rs`: a scenario's points (or parameter sets) run in parallel, a row each, into a
//!   CSV, a summary and figures (`tensegrity sweep`, `tensegrity merge`).
//! - `sensitivity.rs`: a point settled afresh and its sensitivities to every parameter
//!   (`tensegrity sensitivity`); the analysis of a settled state itself is the runner's
//!   (`run::sensitivity`), since a run's settle point reads a file's `[[sensitivities]]` too.
//! - `problem.rs`, `fit.rs`, `fit_trajectory.rs`: a fit's statement and data, the solver
//!   (Levenberg-Marquardt with intervals), and the outputs of a motion's trajectory
//!   (`tensegrity fit`).

pub mod attribution;
pub mod certify;
mod fit;
mod fit_trajectory;
mod problem;
pub mod sensitivity;
pub mod sweep;

pub use fit::{fit, standard_normal};
pub use problem::{
    measurements_from_csv, parse_parameter, read_measurements, too_many_rows, FitError, FitParameter, FitProblem,
    Measurement, DATA_COLUMNS, MAX_DATA_BYTES, MAX_DATA_ROWS,
};
pub use sensitivity::{point_of as sensitivity_point_of, sensitivity, SensitivityRunError};
