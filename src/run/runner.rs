//! The state of one running scenario: its mechanism, its simulation and its observers, and the
//! one step that every phase (settle, perturbation, probe, trajectory) goes through.

use super::judged::JudgedMotion;
use super::RunError;
use crate::mechanisms::{Mechanism, Prediction, Values};
use crate::observers::{Note, Observer, Rougher, Tick};
use crate::scenario::Scenario;
use crate::sim::Simulation;
use crate::snapshot::Snapshot;
use std::sync::atomic::{AtomicBool, Ordering};

/// The recording's series that says, per tick, whether the step took a settle accelerator
/// (1) or was physical (0).
pub const ACCELERATED_SERIES: &str = "path/accelerated";

pub(super) struct Runner<'a> {
    pub mech: Box<dyn Mechanism>,
    pub sc: &'a Scenario,
    /// Every parameter's value at the current point (a sweep over parameters changes them).
    pub params: crate::mechanisms::Values,
    pub sim: Simulation,
    pub observers: Vec<Box<dyn Observer>>,
    /// Whether an observer writes the run down: events and ghost nodes are made only then.
    recording: bool,
    /// Notes of the observers at the current tick, handed to every observer after it.
    pub notes: Vec<Note>,
    /// The run's cancel flag (a signal, Ctrl-C): looked at every step, and by the long phases
    /// between two steps (a motion's modal analysis).
    pub cancel: Option<&'a AtomicBool>,
    /// Steps over the whole run.
    pub steps: u64,
    /// The analytic ghost nodes for the last inputs (recordings only).
    ghost: Option<(Values, Option<Vec<[f64; 3]>>)>,
    /// Whether the step before the last one was accelerated (the recording notes each change).
    was_accelerated: Option<bool>,
    /// Steps over the whole run that took a settle accelerator.
    pub accelerated_steps: u64,
    /// A motion run's motion, once it has started (`judged.rs`).
    pub motion: Option<JudgedMotion>,
    /// Whether each settle point's equilibrium is certified (`RunOptions::certify`).
    pub certify: bool,
}

/// The judged state and the mechanism's quantities in it; in a motion judged extrapolated also
/// the quantities' error estimates, and the state one level rougher with its quantities.
type JudgedState = (Snapshot, Values, Option<(Values, Snapshot, Values)>);

impl<'a> Runner<'a> {
    pub fn new(
        mech: Box<dyn Mechanism>,
        sc: &'a Scenario,
        sim: Simulation,
        observers: Vec<Box<dyn Observer>>,
        cancel: Option<&'a AtomicBool>,
        params: Values,
    ) -> Self {
        let recording = observers.iter().any(|o| o.records());
        Runner {
            mech,
            sc,
            params,
            sim,
            observers,
            recording,
            notes: Vec::new(),
            cancel,
            steps: 0,
            ghost: None,
            was_accelerated: None,
            accelerated_steps: 0,
            motion: None,
            certify: false,
        }
    }

    /// Commands every actuator for `inputs` (by its symbol).
    pub fn command(&mut self, inputs: &Values) {
        let by_symbol = self.mech.commands(&self.params, inputs);
        let commands = self.sim.structure().commands_from(&by_symbol);
        self.sim.set_commands(&commands);
    }

    /// Commands the mechanism's `inputs` for the end of the next step, followed through the
    /// solver (a motion's drive; `Simulation::drive_commands`).
    pub fn drive(&mut self, inputs: &Values) {
        let by_symbol = self.mech.commands(&self.params, inputs);
        let commands = self.sim.structure().commands_from(&by_symbol);
        self.sim.drive_commands(&commands);
    }

    /// The mechanism's quantities in a snapshot of this simulation.
    pub fn observe(&self, snap: &Snapshot) -> Values {
        self.mech.observe(&self.params, self.sim.structure(), snap)
    }

    /// Tells every observer an event of the run (formatted only when one records).
    pub fn emit(&mut self, text: impl std::fmt::Display) {
        if self.recording {
            self.notes.push(Note::Event(text.to_string()));
            self.hand_out_notes();
        }
    }

    /// Hands the notes gathered at this tick to every observer.
    pub fn hand_out_notes(&mut self) {
        let tick = self.sim.tick();
        if self.recording {
            for note in &self.notes {
                for o in &mut self.observers {
                    o.note(tick, note);
                }
            }
        }
        self.notes.clear();
    }

    /// Computes the equilibrium residual of `snap`, the simulation's current state, where the
    /// tick left it out, and hands it to the observers.
    pub fn add_residual(&mut self, snap: &mut Snapshot) {
        if snap.forces.residual.is_some() {
            return;
        }
        snap.forces = self.sim.member_forces();
        if let Some(r) = &snap.forces.residual {
            for o in &mut self.observers {
                o.residual(snap.tick, r);
            }
        }
    }

    /// The state the observers judge after a step with the mechanism's quantities in it, and
    /// each quantity's error estimate with the state one level rougher: the simulation's own
    /// state, or in a motion judged extrapolated, the finer levels stepped to the same time and
    /// the three combined (`levels.rs`).
    fn judged_state(&mut self) -> Result<JudgedState, RunError> {
        let snap = self.sim.snapshot_with(false);
        let judged = match self.motion.as_mut() {
            Some(m) => m.judge(&snap, self.mech.as_ref(), &self.params, self.sim.structure())?,
            None => None,
        };
        let Some(j) = judged else {
            let simulated = self.observe(&snap);
            return Ok((snap, simulated, None));
        };
        Ok((j.state, j.values, Some((j.estimate, j.rougher.0, j.rougher.1))))
    }

    /// Shows every observer the state a motion starts from (the simulation's, before its first
    /// step) and the `equilibrium` it was displaced from, at the motion's time 0.
    pub fn show_motion_start(&mut self, equilibrium: &Snapshot, inputs: &Values) -> Result<(), RunError> {
        let prediction = self.mech.predict(&self.params, inputs).map_err(RunError::Model)?;
        let start = self.sim.snapshot_with(false);
        let (sim_eq, sim_start) = (self.observe(equilibrium), self.observe(&start));
        let structure = self.sim.structure();
        let tick = |snapshot, simulated| Tick {
            motion_time_s: Some(0.0),
            accelerated: false,
            structure,
            snapshot,
            inputs,
            params: &self.params,
            prediction: &prediction,
            simulated,
            ghost_nodes: None,
            estimate: None,
            rougher: None,
            cancel: self.cancel,
        };
        let (eq, at) = (tick(equilibrium, &sim_eq), tick(&start, &sim_start));
        for o in &mut self.observers {
            o.motion_start_state(&eq, &at);
        }
        Ok(())
    }

    /// One step followed by every observer.
    pub fn step(&mut self, inputs: &Values, prediction: &Prediction) -> Result<(Snapshot, Values), RunError> {
        if self.cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
            return Err(RunError::Interrupted(self.sim.tick()));
        }
        self.sim.step()?;
        self.steps += 1;
        // The residual (a least-squares fit, the costliest read-out) is left out here: the
        // settle loop computes it once the motion has stopped, and only those ticks carry it
        // (into the recording too).
        let (snap, simulated, levels) = self.judged_state()?;
        // The ghost overlay is only drawn in recordings, and only recomputed when the inputs
        // change.
        if self.recording && self.ghost.as_ref().is_none_or(|(i, _)| i != inputs) {
            self.ghost = Some((inputs.clone(), self.mech.analytic_nodes(&self.params, inputs)));
        }
        let accelerated = self.sim.last_step_accelerated();
        if self.recording {
            self.notes.push(Note::Scalar(ACCELERATED_SERIES, f64::from(u8::from(accelerated))));
            if self.was_accelerated != Some(accelerated) {
                let kind = if accelerated { "accelerated (a settle accelerator acts)" } else { "physical" };
                self.notes.push(Note::Event(format!("path from here: {kind}")));
            }
        }
        self.was_accelerated = Some(accelerated);
        self.accelerated_steps += u64::from(accelerated);
        let motion_time_s = self.motion.as_ref().map(|m| m.time_s(snap.tick));
        let tick = Tick {
            motion_time_s,
            accelerated,
            structure: self.sim.structure(),
            snapshot: &snap,
            inputs,
            params: &self.params,
            prediction,
            simulated: &simulated,
            ghost_nodes: self.ghost.as_ref().and_then(|(_, g)| g.as_deref()),
            estimate: levels.as_ref().map(|l| &l.0),
            rougher: levels.as_ref().map(|l| Rougher { state: &l.1, values: &l.2 }),
            cancel: self.cancel,
        };
        for o in &mut self.observers {
            o.tick(&tick, &mut self.notes);
        }
        self.hand_out_notes();
        Ok((snap, simulated))
    }
}
