//! Observers, each fed one snapshot per tick: `compare` (analytic versus simulated), `slack`
//! (cable slackness intervals), `interference` (parry distances between struts) and `record`
//! (rerun).

pub mod compare;
pub mod interference;
pub mod record;
pub mod slack;

use crate::mechanisms::{Prediction, Values};
use crate::sim::Snapshot;
use crate::structure::Structure;

/// What every observer sees at a tick.
pub struct Tick<'a> {
    pub structure: &'a Structure,
    pub snapshot: &'a Snapshot,
    pub inputs: &'a Values,
    pub prediction: &'a Prediction,
    pub simulated: &'a Values,
    /// Analytic node positions for the ghost overlay, when the mechanism gives them.
    pub ghost_nodes: Option<&'a [[f64; 3]]>,
}

/// Something that watches a run tick by tick.
pub trait Observer {
    fn tick(&mut self, t: &Tick);
    /// A text event (settled, perturbed, check failed...).
    fn event(&mut self, _tick: u64, _text: &str) {}
}
