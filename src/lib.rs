//! tensegrity-testbed: checks published closed-form models of tensegrity mechanisms against
//! rigid-body dynamics.
//!
//! Data flows one way: [`scenario`] file -> [`mechanisms`] model -> [`structure`] ->
//! [`sim`]ulation -> [`observers`] -> [`report`].

pub mod bench;
pub mod certify;
pub mod cli;
pub mod eigen;
pub mod export;
pub mod figures;
pub mod file_model;
pub mod import;
pub mod input;
pub mod interval;
pub mod mechanisms;
pub mod observers;
pub(crate) mod ordering;
pub mod output;
pub mod report;
pub mod run;
pub mod scenario;
pub mod settings;
pub mod sim;
pub mod snapshot;
pub mod stoppable;
pub mod structure;
pub mod study;
