//! A scenario's structure settled at its first point, for analyses of the settled state
//! (`tensegrity modes`): the run's own start and settle loop (the same accelerators and
//! criteria as `run`), and the simulation handed back instead of a report.

use super::{start, RunError, RunOptions};
use crate::scenario::{Actuation, Scenario};
use crate::sim::Simulation;
use std::sync::atomic::AtomicBool;

/// The simulation at its settled state.
pub struct SettledState {
    pub sim: Simulation,
    /// Whether the settle criteria were met (else the state is where the settle time ran out).
    pub settled: bool,
    /// Steps taken.
    pub steps: u64,
}

/// Settles `sc` at its first point (a schedule: its first waypoint) as `run` does (without a
/// recording, so with nothing to warn of).
pub fn settle_first_point(sc: &Scenario, cancel: Option<&AtomicBool>) -> Result<SettledState, RunError> {
    let inputs = match &sc.actuation {
        Actuation::Points { points, .. } => points[0].clone(),
        Actuation::Schedule { waypoints } => waypoints[0].1.clone(),
    };
    let opts = RunOptions { cancel, skip_findings: true, ..RunOptions::default() };
    let mut runner = start(sc.mechanism(), sc, &opts, &mut Vec::new())?;
    let prediction = runner.mech.predict(&runner.params, &inputs)?;
    let settled = runner.settle(&inputs, &prediction)?;
    Ok(SettledState { sim: runner.sim, settled: settled.settled, steps: settled.steps })
}
