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
use crate::report::NODE_POSITIONS;
use crate::sim::{SimError, Simulation};
use crate::snapshot::{richardson, richardson_estimate_divisor, Snapshot};
use std::sync::atomic::{AtomicBool, Ordering};

/// The order of the leapfrog scheme's leading error term, cancelled by one Richardson step.
const LEAPFROG_ORDER: i32 = 2;

/// The fewest levels a motion is judged over: h, h/2 and h/4, fourth order, seven steps a tick.
pub const MIN_LEVELS: usize = 3;
/// The most: each level more halves the finest step, adds two orders and doubles the steps
/// (five: h ... h/16, eighth order, 31 steps a tick).
pub const MAX_LEVELS: usize = 5;

/// The prefix of a node coordinate's name among the estimated values (`observers::table`).
const NODE_PREFIX: &str = "node:";

/// What [`Levels::judge`] gives at a tick.
pub(super) struct Judged {
    /// The judged state: the top of Romberg's table but one (`Levels::judge`).
    pub state: Snapshot,
    /// The mechanism's quantities in it.
    pub values: Values,
    /// Each quantity's estimate of the judged state's error.
    pub estimate: Values,
    /// The same from one level coarser, with the mechanism's quantities in it.
    pub rougher: (Snapshot, Values),
}

/// The motion at h/2, h/4, ... beside the runner's own at h.
pub(super) struct Levels {
    /// The coarse level's time step h \[s\] (the runner's own), read once from its simulation.
    dt_s: f64,
    /// The finer levels, at h/2, h/4, ..., h/2^(K-1) for K levels in all.
    finer: Vec<Simulation>,
    /// Each quantity's largest error estimate over the motion so far.
    pub largest: Values,
    /// The first tick whose step saw a cable change between slack and taut, if any.
    pub rough_from_tick: Option<u64>,
    /// Each cable's slack at the last tick, at the finest level.
    last_slack: Option<Vec<bool>>,
    /// The largest distance of any judged node from where it was at the first tick judged \[m\].
    pub amplitude_m: f64,
    /// The judged node positions at the first tick judged.
    first_nodes: Option<Vec<[f64; 3]>>,
}

/// Actuator commands at a time of the motion \[s\] (a driven motion's inputs).
pub type CommandsAt<'a> = &'a dyn Fn(f64) -> Vec<f64>;

/// What takes each judged state of a motion run alone, with its motion time \[s\].
pub type EachJudged<'a> = &'a mut dyn FnMut(f64, &Snapshot);

impl Levels {
    /// `count` levels of `sim` (the runner's own at h; [`MIN_LEVELS`] to [`MAX_LEVELS`]), the
    /// finer ones each from its present state started at its own half step. Call before `sim`
    /// itself starts at its half step.
    pub fn new(sim: &Simulation, count: usize) -> Result<Self, SimError> {
        assert!((MIN_LEVELS..=MAX_LEVELS).contains(&count), "{count} levels");
        let dt_s = sim.model().settings.dt_s;
        let finer = (1..count)
            .map(|i| {
                let mut level = sim.at_time_step(dt_s / f64::from(1u32 << i));
                level.start_at_half_step()?;
                Ok(level)
            })
            .collect::<Result<Vec<_>, SimError>>()?;
        Ok(Levels {
            dt_s,
            finer,
            largest: Values::new(),
            rough_from_tick: None,
            last_slack: None,
            amplitude_m: 0.0,
            first_nodes: None,
        })
    }

    /// How many levels, the runner's own included.
    pub fn count(&self) -> usize {
        self.finer.len() + 1
    }

    /// The judged motion's order in the step: 2 (K - 1) for K levels.
    pub fn order(&self) -> i32 {
        LEAPFROG_ORDER * self.finer.len() as i32
    }

    /// The time steps of the levels, h first \[s\].
    pub fn steps_s(&self) -> Vec<f64> {
        (0..self.count()).map(|i| self.dt_s / f64::from(1u32 << i)).collect()
    }

    /// What divides the judged state's difference from the state a level rougher into its
    /// error: 4^(K-1) - 1 for K levels.
    pub fn estimate_divisor(&self) -> f64 {
        richardson_estimate_divisor(self.order())
    }

    /// Steps the finer levels over the coarse step that ends at motion time `end_s` \[s\], a
    /// driven motion's commands set at the end of each of their steps.
    pub fn step(&mut self, end_s: f64, commands_at: Option<CommandsAt>) -> Result<(), SimError> {
        let dt_s = self.dt_s;
        for (i, sim) in self.finer.iter_mut().enumerate() {
            let n = 2u32 << i;
            for j in 1..=n {
                if let Some(c) = commands_at {
                    sim.drive_commands(&c(end_s - dt_s + f64::from(j) * dt_s / f64::from(n)));
                }
                sim.step()?;
            }
        }
        Ok(())
    }

    /// One tick of `coarse` (the level at h, stepped here as well) and of the finer levels,
    /// ending at motion time `end_s` \[s\], a driven motion's commands set at the end of every
    /// step (a motion's levels run alone, with no observer: [`run_alone`]).
    fn step_with(
        &mut self,
        coarse: &mut Simulation,
        end_s: f64,
        commands_at: Option<CommandsAt>,
    ) -> Result<(), SimError> {
        if let Some(c) = commands_at {
            coarse.drive_commands(&c(end_s));
        }
        coarse.step()?;
        self.step(end_s, commands_at)
    }

    /// The judged state at this tick (`coarse` the runner's own, at h) with the mechanism's
    /// quantities in it (`observe` reads them off a state), the error estimate of each of them
    /// and of each value `estimated_too` reads (the joint coordinates), and the state one level
    /// rougher with its quantities.
    ///
    /// Romberg's table over the levels x(0) at h ... x(K-1) at h/2^(K-1): column j combines
    /// neighbours of column j - 1 by Richardson's rule of order 2 j, T(i, j) = T(i, j-1) +
    /// (T(i, j-1) - T(i-1, j-1)) / (4^j - 1). The judged state is T(K-1, K-2), of order 2 (K-1);
    /// T(K-2, K-2), from one level coarser, differs from it by 4^(K-1) - 1 times its error (15
    /// for three levels).
    pub fn judge(
        &mut self,
        coarse: &Snapshot,
        observe: &dyn Fn(&Snapshot) -> Values,
        estimated_too: &dyn Fn(&Snapshot) -> Values,
    ) -> Judged {
        let finer: Vec<Snapshot> = self.finer.iter().map(|s| s.snapshot_with(false)).collect();
        let levels: Vec<&Snapshot> = std::iter::once(coarse).chain(&finer).collect();
        self.note_smoothness(coarse.tick, &levels);
        let mut column: Vec<Snapshot> = levels.windows(2).map(|w| richardson(w[0], w[1], LEAPFROG_ORDER)).collect();
        for j in 2..levels.len() - 1 {
            column = column.windows(2).map(|w| richardson(&w[0], &w[1], LEAPFROG_ORDER * j as i32)).collect();
        }
        let (Some(mut judged), Some(rougher)) = (column.pop(), column.pop()) else {
            unreachable!("three levels or more leave two values in the table's last column");
        };
        (judged.tick, judged.time_s) = (coarse.tick, coarse.time_s);
        let divisor = self.estimate_divisor();
        let (values, rough_values) = (observe(&judged), observe(&rougher));
        let (too, rough_too) = (estimated_too(&judged), estimated_too(&rougher));
        let estimate: Values = values
            .iter()
            .chain(&too)
            .filter_map(|(k, v)| {
                let r = rough_values.get(k).or_else(|| rough_too.get(k))?;
                Some((k.clone(), (v - r).abs() / divisor))
            })
            .collect();
        self.note_amplitude(&judged.nodes);
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

    /// Notes the first tick at which the levels' cables disagree on slack, or change it since
    /// the tick before (`levels` the states at this tick, coarsest first).
    fn note_smoothness(&mut self, tick: u64, levels: &[&Snapshot]) {
        let slack = &levels[levels.len() - 1].forces.slack;
        let smooth = levels.iter().all(|s| s.forces.slack == *slack)
            && self.last_slack.as_ref().is_none_or(|last| last == slack);
        self.last_slack = Some(slack.clone());
        if !smooth && self.rough_from_tick.is_none() {
            self.rough_from_tick = Some(tick);
        }
    }

    /// Widens the amplitude to the judged `nodes` at this tick (the first tick's are where it is
    /// measured from).
    fn note_amplitude(&mut self, nodes: &[[f64; 3]]) {
        let Some(first) = &self.first_nodes else {
            self.first_nodes = Some(nodes.to_vec());
            return;
        };
        for (p, p0) in nodes.iter().zip(first) {
            let d = ((p[0] - p0[0]).powi(2) + (p[1] - p0[1]).powi(2) + (p[2] - p0[2]).powi(2)).sqrt();
            self.amplitude_m = self.amplitude_m.max(d);
        }
    }

    /// The largest error estimate of the judged node positions so far \[m\].
    pub fn node_estimate_m(&self) -> f64 {
        self.largest.get(NODE_POSITIONS).copied().unwrap_or(0.0)
    }

    /// Whether the judged node positions' estimate so far is at most `target` times the
    /// amplitude.
    pub fn meets(&self, target: f64) -> bool {
        self.node_estimate_m() <= target * self.amplitude_m
    }
}

/// `sim`'s motion from its present state over `ticks` ticks of `count` levels, run alone (no
/// observer): the finer levels made from it, every level started at its half step, all
/// stepped together (2^count - 1 steps a tick, as a run's), a driven motion's commands
/// (`commands_at` a time) set at the end of every step of each level. Where `estimated_too`
/// is given, every tick is judged with it (the levels then hold the estimates and the
/// amplitude); where `each` is, every tick is judged and its judged state handed to it with its
/// motion time \[s\]. None when `cancel` is raised.
pub(super) fn run_alone(
    sim: &mut Simulation,
    (ticks, count): (u64, usize),
    commands_at: Option<CommandsAt>,
    estimated_too: Option<&dyn Fn(&Snapshot) -> Values>,
    cancel: Option<&AtomicBool>,
    mut each: Option<EachJudged>,
) -> Result<Option<Levels>, SimError> {
    let mut levels = Levels::new(sim, count)?;
    sim.start_at_half_step()?;
    let none = |_: &Snapshot| Values::new();
    for k in 1..=ticks {
        if cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
            return Ok(None);
        }
        let t_s = k as f64 * levels.dt_s;
        levels.step_with(sim, t_s, commands_at)?;
        if estimated_too.is_some() || each.is_some() {
            let judged = levels.judge(&sim.snapshot_with(false), &none, estimated_too.unwrap_or(&none));
            if let Some(each) = each.as_mut() {
                each(t_s, &judged.state);
            }
        }
    }
    Ok(Some(levels))
}

/// `sim`'s undriven motion from its present state over `ticks` ticks, run alone (no observer)
/// as a motion run steps it: over `count` levels judged extrapolated (`run_alone`), or
/// rapier's own steps from a half step (None); each tick's judged state handed to `each` with
/// its motion time \[s\]. False when `cancel` is raised.
pub(super) fn each_judged_state(
    sim: &mut Simulation,
    (ticks, count): (u64, Option<usize>),
    cancel: Option<&AtomicBool>,
    each: EachJudged,
) -> Result<bool, SimError> {
    if let Some(count) = count {
        return Ok(run_alone(sim, (ticks, count), None, None, cancel, Some(each))?.is_some());
    }
    let dt_s = sim.model().settings.dt_s;
    sim.start_at_half_step()?;
    for k in 1..=ticks {
        if cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
            return Ok(false);
        }
        sim.step()?;
        each(k as f64 * dt_s, &sim.snapshot_with(false));
    }
    Ok(true)
}

/// The node positions \[m\] of `sim`'s motion after `ticks` of its step, judged as a motion
/// run judges them over `count` levels (`run_alone`), the judged state at the end only (the
/// benchmark's measure of the judged motion's cost).
pub fn judged_nodes_after(
    sim: &mut Simulation,
    ticks: u64,
    count: usize,
    commands_at: Option<CommandsAt>,
) -> Result<Vec<[f64; 3]>, SimError> {
    let mut levels = run_alone(sim, (ticks, count), commands_at, None, None, None)?.expect("no cancel flag");
    let none = |_: &Snapshot| Values::new();
    Ok(levels.judge(&sim.snapshot_with(false), &none, &none).state.nodes)
}
