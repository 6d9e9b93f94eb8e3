//! A motion run's motion as one value: its start tick and time step (the origin and spacing of
//! its time), its drive (the inputs every level follows), and, where it is judged extrapolated,
//! its finer levels (`levels.rs`). It starts them in order (the levels made from the present
//! state, then every level at its half step), gives each tick's motion time, steps the finer
//! levels beside the runner's own and judges the state there. The runner holds it while the
//! motion runs; the observers are told its constants once, at its start
//! (`observers::MotionStarted`).

use super::levels::{Judged, Levels};
use crate::mechanisms::{Mechanism, Values};
use crate::settings::Drive;
use crate::sim::{SimError, Simulation};
use crate::snapshot::Snapshot;
use crate::structure::Structure;

pub(super) struct JudgedMotion {
    /// The tick the motion started at: its time origin.
    start_tick: u64,
    /// The motion's time step h \[s\] (the runner's own level's).
    dt_s: f64,
    /// The inputs in time of a driven motion, followed by every level.
    drive: Option<Drive>,
    /// The finer levels of a motion judged extrapolated over the time step.
    levels: Option<Levels>,
}

/// The actuator commands (structure order) of `drive`'s inputs at motion time `t_s` \[s\].
pub(super) fn commands_at(
    mech: &dyn Mechanism,
    params: &Values,
    structure: &Structure,
    drive: &Drive,
    t_s: f64,
) -> Vec<f64> {
    structure.commands_from(&mech.commands(params, &drive.inputs_at(params, t_s)))
}

impl JudgedMotion {
    /// Starts the motion of `sim` from its present state and tick: over `levels` levels made
    /// from it where it is judged extrapolated (None: rapier's own steps), then `sim` itself
    /// started at its half step.
    pub fn start(sim: &mut Simulation, levels: Option<usize>, drive: Option<Drive>) -> Result<Self, SimError> {
        let levels = levels.map(|count| Levels::new(sim, count)).transpose()?;
        sim.start_at_half_step()?;
        Ok(JudgedMotion { start_tick: sim.tick(), dt_s: sim.model().settings.dt_s, drive, levels })
    }

    /// The motion's time step h \[s\].
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The time since the motion's start at `tick` \[s\].
    pub fn time_s(&self, tick: u64) -> f64 {
        tick.saturating_sub(self.start_tick) as f64 * self.dt_s
    }

    /// The inputs of a driven motion at the end of step `k` of the motion (t = k h); None
    /// where the motion holds its start point's inputs.
    pub fn inputs_after(&self, params: &Values, k: u64) -> Option<Values> {
        self.drive.as_ref().map(|d| d.inputs_at(params, k as f64 * self.dt_s))
    }

    /// The estimate divisor of a motion judged extrapolated (`Levels::estimate_divisor`);
    /// None: not extrapolated.
    pub fn estimate_divisor(&self) -> Option<f64> {
        self.levels.as_ref().map(Levels::estimate_divisor)
    }

    /// The judged state after the runner's own level has stepped to `coarse`: the finer levels
    /// stepped to the same time and the levels combined, the mechanism's quantities read in it
    /// and in the state a level rougher; None where the motion is not judged extrapolated.
    pub fn judge(
        &mut self,
        coarse: &Snapshot,
        mech: &dyn Mechanism,
        params: &Values,
        structure: &Structure,
    ) -> Result<Option<Judged>, SimError> {
        let end_s = self.time_s(coarse.tick);
        let Some(levels) = self.levels.as_mut() else { return Ok(None) };
        let commands = self.drive.as_ref().map(|d| move |t| commands_at(mech, params, structure, d, t));
        let driven = commands.as_ref().map(|c| c as &dyn Fn(f64) -> Vec<f64>);
        levels.step(end_s, driven)?;
        let coordinates = |s: &Snapshot| crate::observers::table::estimated_columns(structure, s);
        Ok(Some(levels.judge(coarse, &|s| mech.observe(params, structure, s), &coordinates)))
    }

    /// The levels the motion was judged over, for its report (None: not extrapolated).
    pub fn into_levels(self) -> Option<Levels> {
        self.levels
    }
}
