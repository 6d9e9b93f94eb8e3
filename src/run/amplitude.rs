//! The motion again at half its amplitude, for the amplitude's own shift of its frequencies.
//!
//! A free vibration's frequency moves with its amplitude A (a nonlinear structure's shift,
//! c A^2 to leading order); a linear prediction (a mode's, a paper's small-oscillation
//! formula) is its limit at A -> 0. So that a measured frequency's error bar holds that shift,
//! the motion runs a second time, alone and after the motion itself, from the same start state
//! (settled, or drawn at an equilibrium; damping released, the modes analysed) at half the
//! amplitude: the mode's amplitude,
//! or the coordinate's displacement and rate, halved. The observers see each of its judged
//! states (`Observer::half_amplitude_tick`); with omega(A) = omega(0) + c A^2, the shift at A is
//! 4/3 (omega(A) - omega(A/2)) (`observers/motion.rs`). It costs a second motion; a motion
//! whose amplitude is not its own (driven, spun, released from a drawing that is no
//! equilibrium) or that measures no frequency has none.

use super::levels::each_judged_state;
use super::runner::Runner;
use super::RunError;
use crate::settings::{Motion, MotionStart};
use crate::sim::modes::StructureModes;
use crate::sim::Simulation;

/// The half-amplitude motion's start state, made beside the motion's own.
pub(super) struct HalfAmplitude {
    sim: Simulation,
}

impl HalfAmplitude {
    /// A copy of `sim` at the motion's start (before its displacement), where `m` measures
    /// frequencies of a free vibration whose amplitude it states about an equilibrium: a
    /// settled start, or a drawn one `at_equilibrium` (at rest, its residual within the settle's
    /// tolerances).
    pub fn wanted(sim: &Simulation, m: &Motion, at_equilibrium: bool) -> Option<Self> {
        let from_rest = m.start == MotionStart::Settled || at_equilibrium;
        let free = m.drive.is_none() && m.spin.is_none() && from_rest;
        let stated = m.mode.is_some() || m.coordinate.is_some();
        (free && stated && !m.frequencies.is_empty())
            .then(|| HalfAmplitude { sim: sim.at_time_step(sim.model().settings.dt_s) })
    }

    /// Displaces the copy along mode `index` of `analysis` by half of `amplitude_m`.
    pub fn displace_along_mode(&mut self, analysis: &StructureModes, index: usize, amplitude_m: f64) {
        self.sim.displace_along_mode(analysis, index, 0.5 * amplitude_m);
    }

    /// Gives the copy's joint `j` half of the displacement and rate.
    pub fn set_joint_motion(&mut self, j: usize, displacement: f64, rate: f64) -> Result<(), RunError> {
        Ok(self.sim.set_joint_motion(j, 0.5 * displacement, 0.5 * rate)?)
    }

    /// Runs the copy over `ticks` ticks judged as the motion was (`levels`), each judged state
    /// handed to the runner's observers.
    pub fn run(mut self, runner: &mut Runner, ticks: u64, levels: Option<usize>) -> Result<(), RunError> {
        // The copy's structure is the runner's own (the same build).
        let (structure, observers) = (runner.sim.structure(), &mut runner.observers);
        let mut each = |t_s: f64, state: &crate::snapshot::Snapshot| {
            for o in observers.iter_mut() {
                o.half_amplitude_tick(t_s, state, structure);
            }
        };
        let tick = runner.sim.tick();
        match each_judged_state(&mut self.sim, (ticks, levels), runner.cancel, &mut each)? {
            true => Ok(()),
            false => Err(RunError::Interrupted(tick)),
        }
    }
}
