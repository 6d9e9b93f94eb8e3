//! Settle detection: every body's speed (from the change of its pose over one step, which is
//! what is really static, not rapier's reported velocity) below a threshold for a window of
//! steps; then, independently, the force/torque residual below its tolerance.

use super::Snapshot;

/// When a run counts as settled. All from the scenario file.
#[derive(Clone, Debug, PartialEq)]
pub struct SettleCriteria {
    /// Largest node speed allowed while settled [m/s].
    pub speed_tol_m_per_s: f64,
    /// Consecutive steps the speed must stay below the threshold.
    pub window_steps: u64,
    /// Largest residual force on a free coordinate [N].
    pub residual_force_tol_n: f64,
    /// Largest residual torque on a free coordinate [N m].
    pub residual_torque_tol_nm: f64,
    /// Simulated time allowed for one settle [s]; past it the settle fails.
    pub max_time_s: f64,
}

impl Default for SettleCriteria {
    fn default() -> Self {
        SettleCriteria {
            speed_tol_m_per_s: 1e-10,
            window_steps: 10,
            residual_force_tol_n: 1e-7,
            residual_torque_tol_nm: 1e-7,
            max_time_s: 60.0,
        }
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
        let speed = match &self.previous {
            Some(prev) => {
                prev.iter().zip(&snap.nodes).map(|(a, b)| crate::structure::distance(*a, *b) / dt_s).fold(0.0, f64::max)
            }
            None => f64::INFINITY,
        };
        match &mut self.previous {
            Some(prev) => prev.clone_from(&snap.nodes),
            None => self.previous = Some(snap.nodes.clone()),
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
