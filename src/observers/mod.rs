//! Observers watch a run: each is fed one snapshot per tick and each settle point, and puts
//! what it gathered into the report at the end. They are held as one list ([`observers`]):
//! `compare` (analytic versus simulated), `slack` (cable slackness intervals), `interference`
//! (parry distances between struts), `model` (the scenario file's own model) and `record`
//! (rerun).
//!
//! Adding an observer: its own file here implementing [`Observer`] with a `make` that says
//! when a run has one, and one line in `KINDS`.

pub mod compare;
pub mod external;
pub mod file_model;
pub mod interference;
pub mod lagrangian;
pub mod modes_record;
pub mod motion;
pub mod record;
pub mod slack;
pub mod table;

use crate::mechanisms::{Prediction, Values};
use crate::report::{PointReport, ScenarioReport};
use crate::settings::{Check, InterferenceSettings};
use crate::snapshot::{Residual, Snapshot};
use crate::structure::Structure;

/// What every observer sees at a tick.
pub struct Tick<'a> {
    pub structure: &'a Structure,
    pub snapshot: &'a Snapshot,
    pub inputs: &'a Values,
    /// Every parameter's value at this tick (a sweep over parameters changes them).
    pub params: &'a Values,
    pub prediction: &'a Prediction,
    pub simulated: &'a Values,
    /// Analytic node positions for the ghost overlay (only for observers that record).
    pub ghost_nodes: Option<&'a [[f64; 3]]>,
    /// In a motion run's motion: the time since the motion started \[s\] (the model's `t`
    /// there). None before it (a settle to its start) and in every other run.
    pub motion_time_s: Option<f64>,
    /// The step to this tick took a settle accelerator (the static relaxation or the Newton
    /// damping schedule): it is no part of a physical path.
    pub accelerated: bool,
    /// In a motion judged extrapolated over the time step: each quantity's estimate of the
    /// simulation's own error at this tick (`run/levels.rs`).
    pub estimate: Option<&'a Values>,
    /// There too: the state one level rougher with the mechanism's quantities in it.
    pub rougher: Option<Rougher<'a>>,
    /// The run's cancel flag, for an observer's own long work at a tick (the Lagrangian
    /// model's integration between two ticks).
    pub cancel: Option<&'a std::sync::atomic::AtomicBool>,
}

/// In a motion judged extrapolated: the state one level rougher than the judged one
/// (`run/levels.rs`). What an observer measures differs between it and the judged state by
/// the motion's [`MotionStarted::estimate_divisor`] times the judged value's error.
#[derive(Clone, Copy)]
pub struct Rougher<'a> {
    pub state: &'a Snapshot,
    /// The mechanism's quantities in it.
    pub values: &'a Values,
}

/// A motion run's motion as it starts (after its start point, its levels made and started at
/// their half step, before its first step): what stays the same over all its ticks, told to
/// every observer once.
pub struct MotionStarted<'a> {
    /// The structure's own modes at the start that its frequencies are fitted to.
    pub modes: &'a [ModeAtStart],
    /// The motion's time step h \[s\] (the ticks' spacing).
    pub dt_s: f64,
    /// In a motion judged extrapolated over the time step (`run/levels.rs`): what divides a
    /// difference between the judged state and the one a level rougher into the judged
    /// state's error (15 at fourth order). None: rapier's own steps, not extrapolated.
    pub estimate_divisor: Option<f64>,
}

/// What the observers see of a settle point besides its report (which holds the inputs, the
/// analytic and simulated values and whether it settled).
pub struct SettlePoint<'a> {
    pub structure: &'a Structure,
    /// The settled state (or the last one, when the settle ran out of time).
    pub snapshot: &'a Snapshot,
    /// Every parameter's value at this point.
    pub params: &'a Values,
    /// The analytic model does not apply here (it predicts a slack cable): nothing to compare.
    pub outside_model: bool,
}

/// Something an observer or the run tells the others at a tick (the recorder writes it down).
#[derive(Clone, Debug, PartialEq)]
pub enum Note {
    /// A line of the event log.
    Event(String),
    /// One value of a named time series.
    Scalar(&'static str, f64),
    /// The values of an entity's named series at `tick` (this one or an earlier one, whose
    /// simulated time is `time_s` \[s\]), in the order of its [`Note::SeriesNames`].
    ScalarsAt { entity: &'static str, tick: u64, time_s: f64, values: Vec<f64> },
    /// The names of an entity's series (once, before or with its first values).
    SeriesNames(&'static str, Vec<String>),
}

/// One of the structure's own modes at a motion run's start (the simulation's modal analysis), for the
/// frequencies fitted to it.
#[derive(Clone, Debug)]
pub struct ModeAtStart {
    /// The mode, from 0 (ascending, rigid-body modes counted).
    pub index: usize,
    pub omega_rad_per_s: f64,
    /// Reads the mode's coordinate off a snapshot.
    pub projector: crate::snapshot::ModalProjector,
}

/// Something that watches a run.
pub trait Observer {
    /// After every step; what the observer has to tell the others goes into `notes`.
    fn tick(&mut self, t: &Tick, notes: &mut Vec<Note>);
    /// Whether this observer writes the run down (it then gets the events, the residuals and
    /// the analytic ghost nodes, which cost something to make).
    fn records(&self) -> bool {
        false
    }
    /// A note of the run or of another observer at `tick`.
    fn note(&mut self, _tick: u64, _note: &Note) {}
    /// The equilibrium residual computed after `tick` (the settle loop computes it only once
    /// the motion has stopped).
    fn residual(&mut self, _tick: u64, _r: &Residual) {}
    /// A motion run's motion starts (after its start point and its start state, before its
    /// first step): its modes, time step and extrapolation, the same at every tick after.
    fn motion_start(&mut self, _start: &MotionStarted) {}
    /// A motion run's motion starts: the `equilibrium` it is displaced from (its start point)
    /// and the state it `start`s from at t = 0 (the displacement and rate of `[motion]` set, no
    /// step taken), each as a tick (`motion_time_s` Some(0)).
    fn motion_start_state(&mut self, _equilibrium: &Tick, _start: &Tick) {}
    /// A motion run's motion again, run alone from the same start at half its amplitude
    /// (`run/amplitude.rs`), after the motion itself: its judged `state` at motion time `time_s`
    /// \[s\] of `structure`, for the amplitude's own shift of the measured frequencies.
    fn half_amplitude_tick(&mut self, _time_s: f64, _state: &Snapshot, _structure: &Structure) {}
    /// A settle point: fill in what this observer measures there (`point` has the rest).
    fn settle_point(&mut self, _p: &SettlePoint, _point: &mut PointReport, _notes: &mut Vec<Note>) {}
    /// The run is over: put what was gathered into the report.
    fn finish(&mut self, _report: &mut ScenarioReport) {}
    /// The verdict is in (`report` is final): write what carries it. An error fails the run;
    /// what the run goes on without goes into `warnings`.
    fn close(
        &mut self,
        _tick: u64,
        _report: &ScenarioReport,
        _warnings: &mut Vec<String>,
    ) -> Result<(), ObserverError> {
        Ok(())
    }
}

/// Why an observer could not start, or could not write what carries the verdict.
#[derive(Debug, thiserror::Error)]
pub enum ObserverError {
    /// An interference exclusion names no member of the structure.
    #[error(transparent)]
    Interference(#[from] crate::settings::UnknownMember),
    /// The per-tick table could not be written.
    #[error(transparent)]
    Table(#[from] table::TableError),
    /// The recording could not be written.
    #[error(transparent)]
    Record(#[from] record::RecordError),
}

/// What the observers of a run are made from.
pub struct Setup<'a> {
    pub structure: &'a Structure,
    pub checks: &'a [Check],
    /// The mechanism's length scale \[m\], for normalised errors.
    pub length_scale_m: f64,
    pub interference: &'a InterferenceSettings,
    /// The scenario file's own model (`[[quantities]]`, `[[predictions]]`, `[[equations]]`).
    pub model: Option<&'a crate::file_model::spec::ModelSpec>,
    /// A recording, when the run writes one (made last: nothing is written when another
    /// observer cannot start).
    pub recording: Option<record::Recording<'a>>,
    /// A per-tick f64 table to write (CSV or Arrow IPC) or keep in memory, if the run makes one.
    pub table: Option<table::TableTarget>,
    /// A motion run's `[motion]`: its frequencies are measured from its ticks.
    pub motion: Option<&'a crate::settings::Motion>,
    /// A model outside the file (a Python callable), compared as its predictions are.
    pub external: Option<external::External>,
}

/// What a kind of observer makes of a run's setup: its observer, or None where the run does
/// not ask for it (bevy's `Plugin::build`).
pub type Made = Result<Option<Box<dyn Observer>>, ObserverError>;

/// Every kind of observer, in the order they see each tick: each file's `make` registers it
/// with what it needs of the [`Setup`], and its `finish` adds its part to the report.
/// Adding an observer is its file and a line here.
const KINDS: [fn(&Setup, &mut Vec<String>) -> Made; 8] = [
    compare::make,
    slack::make,
    interference::make,
    file_model::make,
    motion::make,
    external::make,
    table::make,
    record::make,
];

/// Every observer of a run, in the order they see each tick; what the run goes on without (a
/// live viewer nobody runs) goes into `warnings`.
pub fn observers(setup: Setup, warnings: &mut Vec<String>) -> Result<Vec<Box<dyn Observer>>, ObserverError> {
    let mut list = Vec::new();
    for make in KINDS {
        list.extend(make(&setup, warnings)?);
    }
    Ok(list)
}
