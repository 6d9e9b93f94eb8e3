//! A motion judged at fourth order, with its own error estimate.
//!
//! From its stated start at a half step (`sim/levels.rs`) rapier's steps are the leapfrog
//! scheme, whose error at the tick times is an even series in the step h: x_h = x + c2 h^2 +
//! c4 h^4 + ... The same motion is stepped at h, h/2 and h/4 from the same start. Richardson's
//! rule over two of them, T(h, h/2) = x_{h/2} + (x_{h/2} - x_h) / 3, cancels the h^2 term; the
//! judged state is T(h/2, h/4), whose error is -c4 h^4 / 64, and T(h/2, h/4) - T(h, h/2) =
//! 15 c4 h^4 / 64, so a fifteenth of that difference is the judged state's own error estimate.
//! Every number of the state is combined (`snapshot::richardson`), and each quantity's estimate
//! is reported per tick and at its largest over the motion.
//!
//! The rule holds where the motion is smooth in time. A cable that goes slack or taut puts a
//! kink into it (its force law changes there): the first tick whose step saw any cable change
//! between slack and taut, at any level, is reported, and the estimates after it are not to be
//! trusted.

use crate::mechanisms::Values;
use crate::sim::{SimError, Simulation};
use crate::snapshot::{richardson, Snapshot, RICHARDSON_ESTIMATE_DIVISOR};

/// The order of the leapfrog scheme's leading error term, cancelled by one Richardson step.
const LEAPFROG_ORDER: i32 = 2;

/// The prefix of a node coordinate's name among the estimated values (`observers::table`).
const NODE_PREFIX: &str = "node:";
/// The key of the largest estimate over every node coordinate in the motion's report.
pub(super) const NODE_POSITIONS: &str = "node positions";

/// What [`Levels::judge`] gives at a tick.
pub(super) struct Judged {
    /// The judged state: Richardson's value from h/2 and h/4.
    pub state: Snapshot,
    /// The mechanism's quantities in it.
    pub values: Values,
    /// Each quantity's estimate of the judged state's error.
    pub estimate: Values,
    /// Richardson's value from h and h/2, with the mechanism's quantities in it.
    pub rougher: (Snapshot, Values),
}

/// The motion at h/2 and h/4 beside the runner's own at h.
pub(super) struct Levels {
    half: Simulation,
    quarter: Simulation,
    /// Each quantity's largest error estimate over the motion so far.
    pub largest: Values,
    /// The first tick whose step saw a cable change between slack and taut, if any.
    pub rough_from_tick: Option<u64>,
    /// Each cable's slack at the last tick, at the finest level.
    last_slack: Option<Vec<bool>>,
}

/// Actuator commands at a time of the motion [s] (a driven motion's inputs).
pub(super) type CommandsAt<'a> = &'a dyn Fn(f64) -> Vec<f64>;

impl Levels {
    /// The finer levels of `sim`, each from its present state started at its own half step.
    /// Call before `sim` itself starts at its half step.
    pub fn new(sim: &Simulation) -> Result<Self, SimError> {
        let dt_s = sim.model().settings.dt_s;
        let mut half = sim.at_time_step(dt_s / 2.0);
        half.start_at_half_step()?;
        let mut quarter = sim.at_time_step(dt_s / 4.0);
        quarter.start_at_half_step()?;
        Ok(Levels { half, quarter, largest: Values::new(), rough_from_tick: None, last_slack: None })
    }

    /// Steps the finer levels over the coarse step that ends at motion time `end_s` [s] (of
    /// length `dt_s`), a driven motion's commands set at the end of each of their steps.
    pub fn step(&mut self, end_s: f64, dt_s: f64, commands_at: Option<CommandsAt>) -> Result<(), SimError> {
        for (sim, n) in [(&mut self.half, 2u32), (&mut self.quarter, 4)] {
            for j in 1..=n {
                if let Some(c) = commands_at {
                    sim.drive_commands(&c(end_s - dt_s + f64::from(j) * dt_s / f64::from(n)));
                }
                sim.step()?;
            }
        }
        Ok(())
    }

    /// The judged state at this tick (`coarse` the runner's own, at h) with the mechanism's
    /// quantities in it (`observe` reads them off a state), the error estimate of each of them
    /// and of each value `estimated_too` reads (the joint coordinates), and the state one level
    /// rougher with its quantities.
    pub fn judge(
        &mut self,
        coarse: &Snapshot,
        observe: &dyn Fn(&Snapshot) -> Values,
        estimated_too: &dyn Fn(&Snapshot) -> Values,
    ) -> Judged {
        let half = self.half.snapshot_with(false);
        let quarter = self.quarter.snapshot_with(false);
        let slack = &quarter.forces.slack;
        let smooth = coarse.forces.slack == *slack
            && half.forces.slack == *slack
            && self.last_slack.as_ref().is_none_or(|last| last == slack);
        self.last_slack = Some(slack.clone());
        if !smooth && self.rough_from_tick.is_none() {
            self.rough_from_tick = Some(coarse.tick);
        }
        let mut judged = richardson(&half, &quarter, LEAPFROG_ORDER);
        let rougher = richardson(coarse, &half, LEAPFROG_ORDER);
        (judged.tick, judged.time_s) = (coarse.tick, coarse.time_s);
        let (values, rough_values) = (observe(&judged), observe(&rougher));
        let (too, rough_too) = (estimated_too(&judged), estimated_too(&rougher));
        let estimate: Values = values
            .iter()
            .chain(&too)
            .filter_map(|(k, v)| {
                let r = rough_values.get(k).or_else(|| rough_too.get(k))?;
                Some((k.clone(), (v - r).abs() / RICHARDSON_ESTIMATE_DIVISOR))
            })
            .collect();
        let rougher = (rougher, rough_values);
        for (k, e) in &estimate {
            // Every node's position is estimated (per tick, in the table and the recording);
            // the motion's report keeps their largest as one.
            let key = if k.starts_with(NODE_PREFIX) { NODE_POSITIONS } else { k };
            let largest = self.largest.entry(key.to_string()).or_insert(0.0);
            *largest = largest.max(*e);
        }
        Judged { state: judged, values, estimate, rougher }
    }
}

/// The node positions \[m\] of `sim`'s motion after `ticks` of its step, judged as a motion
/// run judges them: the finer levels made from its present state, every level started at its
/// half step, the three stepped together (seven steps a tick, as a run's), and the judged
/// state T(h/2, h/4) at the end (the benchmark's measure of the judged motion's cost).
pub fn judged_nodes_after(sim: &mut Simulation, ticks: u64) -> Result<Vec<[f64; 3]>, SimError> {
    let mut levels = Levels::new(sim)?;
    sim.start_at_half_step()?;
    let dt_s = sim.model().settings.dt_s;
    for k in 1..=ticks {
        sim.step()?;
        levels.step(k as f64 * dt_s, dt_s, None)?;
    }
    let judged = richardson(&levels.half.snapshot_with(false), &levels.quarter.snapshot_with(false), LEAPFROG_ORDER);
    Ok(judged.nodes)
}
