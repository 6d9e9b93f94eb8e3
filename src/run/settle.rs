//! The settle loop, the one place that decides when a state has settled: an optional approach
//! phase at fewer PGS iterations, then every body's speed (from the change of its pose over one
//! step, which is what is really static, not rapier's reported velocity) below a threshold for
//! a window of steps, then, independently, the force/torque residual below its tolerance;
//! running out of `settle.max_time` is a failure, never a pass.

use super::runner::Runner;
use super::RunError;
use crate::mechanisms::{Prediction, Values};
use crate::settings::SettleCriteria;
use crate::snapshot::Snapshot;

/// Result of one settle.
pub(super) struct Settled {
    pub settled: bool,
    pub steps: u64,
    pub final_speed: f64,
    pub snapshot: Snapshot,
    pub simulated: Values,
}

/// The approach phase of a settle ends when the speed falls below the settle threshold times
/// this factor (for a 1e-12 m/s threshold: 1e-6 m/s).
const APPROACH_SWITCH_SPEED_FACTOR: f64 = 1e6;

impl Runner<'_> {
    /// Steps until the speed stays below the threshold for the window and the residual passes,
    /// or until the settle time runs out (a failure, never a pass).
    pub(super) fn settle(&mut self, inputs: &Values, prediction: &Prediction) -> Result<Settled, RunError> {
        let criteria = self.sc.settle.clone();
        let dt = self.sc.sim.dt_s;
        let max_steps = (criteria.max_time_s / dt).ceil() as u64;
        let mut detector = SettleDetector::new();
        let mut last = None;
        // Two phases when the scenario asks: approach with few PGS iterations, then finish
        // with the full count once the motion has nearly stopped.
        let mut approaching = self.sc.sim.approach_pgs_iterations.is_some();
        if let Some(n) = self.sc.sim.approach_pgs_iterations {
            self.sim.set_pgs_iterations(n);
        }
        let switch_speed = criteria.speed_tol_m_per_s * APPROACH_SWITCH_SPEED_FACTOR;
        // The static relaxation (where it runs) stops once the motion has: the quiet window
        // and the residual check are then plain steps of the dynamics.
        let relaxation = self.sim.relaxing();
        for k in 1..=max_steps {
            let (mut snap, simulated) = self.step(inputs, prediction)?;
            let quiet = detector.update(&snap, dt, &criteria);
            if relaxation {
                self.sim.set_relaxation(detector.last_speed > criteria.speed_tol_m_per_s);
            }
            if approaching && detector.last_speed <= switch_speed {
                approaching = false;
                self.sim.set_pgs_iterations(self.sc.sim.pgs_iterations);
                detector.reset();
                continue;
            }
            let quiet = quiet && !approaching;
            if quiet {
                self.add_residual(&mut snap);
            }
            if quiet && SettleDetector::residual_ok(&snap, &criteria) {
                self.sim.set_relaxation(relaxation);
                return Ok(Settled {
                    settled: true,
                    steps: k,
                    final_speed: detector.last_speed,
                    snapshot: snap,
                    simulated,
                });
            }
            last = Some((snap, simulated));
        }
        let (snapshot, simulated) = match last {
            // The last state is the simulation's current one: its residual can still be had.
            Some((mut snap, simulated)) => {
                self.add_residual(&mut snap);
                (snap, simulated)
            }
            None => {
                let s = self.sim.snapshot();
                let v = self.observe(&s);
                (s, v)
            }
        };
        self.sim.set_pgs_iterations(self.sc.sim.pgs_iterations);
        self.sim.set_relaxation(relaxation);
        Ok(Settled { settled: false, steps: max_steps, final_speed: detector.last_speed, snapshot, simulated })
    }
}

/// Tracks node speeds tick by tick.
#[derive(Clone, Debug, Default)]
pub struct SettleDetector {
    previous: Option<Vec<[f64; 3]>>,
    quiet_steps: u64,
    /// Largest node speed seen at the last tick [m/s].
    pub last_speed: f64,
}

impl SettleDetector {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds one tick; returns true when the speed has been below the threshold for the window.
    pub fn update(&mut self, snap: &Snapshot, dt_s: f64, criteria: &SettleCriteria) -> bool {
        self.update_nodes(&snap.nodes, dt_s, criteria)
    }

    /// [`Self::update`] from the node positions alone (the scale bench reads no forces while
    /// the motion runs).
    pub fn update_nodes(&mut self, nodes: &[[f64; 3]], dt_s: f64, criteria: &SettleCriteria) -> bool {
        let speed = match &self.previous {
            Some(prev) => {
                prev.iter().zip(nodes).map(|(a, b)| crate::structure::distance(*a, *b) / dt_s).fold(0.0, f64::max)
            }
            None => f64::INFINITY,
        };
        match &mut self.previous {
            Some(prev) => prev.copy_from_slice(nodes),
            None => self.previous = Some(nodes.to_vec()),
        }
        self.last_speed = speed;
        if speed <= criteria.speed_tol_m_per_s {
            self.quiet_steps += 1;
        } else {
            self.quiet_steps = 0;
        }
        self.quiet_steps >= criteria.window_steps
    }

    /// Forget the history (after a command change or a perturbation).
    pub fn reset(&mut self) {
        self.previous = None;
        self.quiet_steps = 0;
    }

    /// Whether the residual of `snap` meets the criteria (false when it was not computed).
    pub fn residual_ok(snap: &Snapshot, criteria: &SettleCriteria) -> bool {
        snap.forces.residual.as_ref().is_some_and(|r| {
            r.max_force_n <= criteria.residual_force_tol_n && r.max_torque_nm <= criteria.residual_torque_tol_nm
        })
    }
}
