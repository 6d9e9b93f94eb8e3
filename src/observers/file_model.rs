//! The file's own model against the dynamics: every `[[predictions]]` entry compared with its
//! quantity, and every `[[equations]]` residual, at each settle point (which decides the
//! verdict) and at each tick (reported as transient errors, as the checks are). In a motion
//! run with `[energy.trajectory]` it gathers the energy coordinates at every tick for the
//! comparison with the Lagrangian model (`lagrangian.rs`).

use super::lagrangian::{LagrangianError, Row, Tracker};
use super::{Made, MotionStarted, Note, Observer, SettlePoint, Setup, Tick};
use crate::file_model::dynamics::TrajectoryCheck;
use crate::file_model::energy_model::Kind;
use crate::file_model::spec::{ErrorClass, ModelSpec, Source};
use crate::mechanisms::Values;
use crate::report::{
    EnergyPointReport, ModelCheckReport, ModelModeReport, PointReport, ScenarioReport, StationaryReport,
};
use crate::snapshot::{unit, Snapshot};
use crate::structure::{JointKind, Structure};
use std::cmp::Ordering;

/// How a state symbol is read from a snapshot of the run's structure.
#[derive(Clone, Debug)]
enum Bind {
    /// Not used by any expression (or not in this structure): NaN.
    Unused,
    Time,
    Node(usize, usize),
    /// A spring's or a cable's force and length (member index).
    MemberForce(usize),
    MemberLength(usize),
    /// A clustered cable's segment tension and an inner node's slip (member, index).
    SegmentForce(usize, usize),
    Slip(usize, usize),
    /// Distance between a strut's end nodes.
    StrutLength(usize, usize),
    Observed(String),
    /// A revolute joint: parent and child bodies, unit axis, initial coordinate.
    JointAngle {
        parent: usize,
        child: usize,
        axis: [f64; 3],
        initial: f64,
    },
    /// A prismatic joint: parent and child bodies, the anchor at the build, unit axis,
    /// initial coordinate.
    JointSlide {
        parent: usize,
        child: usize,
        anchor: [f64; 3],
        axis: [f64; 3],
        initial: f64,
    },
}

/// A joint's coordinate symbol, if its kind has one coordinate.
fn joint_bind(s: &Structure, name: &str, angle: bool) -> Option<Bind> {
    let j = s.joints.iter().find(|j| j.name == name)?;
    let (parent, child, initial) = (j.parent, j.child, j.initial_coordinate);
    match (&j.kind, angle) {
        (JointKind::Revolute { axis }, true) => Some(Bind::JointAngle { parent, child, axis: unit(*axis), initial }),
        (JointKind::Prismatic { axis }, false) => {
            let anchor = s.nodes.get(j.anchor)?.position;
            Some(Bind::JointSlide { parent, child, anchor, axis: unit(*axis), initial })
        }
        _ => None,
    }
}

impl Bind {
    fn new(source: &Source, s: &Structure) -> Bind {
        let tension = |name: &str| s.member_id(name).filter(|&i| !s.members[i].is_rigid_strut());
        let bound = match source {
            Source::Time => Some(Bind::Time),
            Source::Node(n, axis) => s.node_id(n).map(|i| Bind::Node(i, *axis)),
            Source::MemberForce(m) => tension(m).map(Bind::MemberForce),
            Source::SegmentForce(m, k) => s.member_id(m).map(|i| Bind::SegmentForce(i, *k)),
            Source::Slip(m, k) => s.member_id(m).map(|i| Bind::Slip(i, *k)),
            Source::MemberLength(m) => tension(m).map(Bind::MemberLength).or_else(|| {
                let (_, t) = s.rigid_struts().find(|(_, t)| &t.name == m)?;
                Some(Bind::StrutLength(t.ends().0, t.ends().1))
            }),
            Source::Observed(q) => Some(Bind::Observed(q.clone())),
            Source::JointAngle(j) => joint_bind(s, j, true),
            Source::JointSlide(j) => joint_bind(s, j, false),
            Source::Param(_) | Source::Input(_) | Source::Quantity(_) => None,
        };
        bound.unwrap_or(Bind::Unused)
    }

    /// The symbol's value in `snap`; `time_s` is the model's time `t` there.
    fn read(&self, snap: &Snapshot, observed: &Values, time_s: f64) -> f64 {
        let at = |v: &Vec<f64>, i: usize| v.get(i).copied().unwrap_or(f64::NAN);
        match self {
            Bind::Unused => f64::NAN,
            Bind::Time => time_s,
            Bind::Node(i, axis) => snap.nodes.get(*i).map_or(f64::NAN, |p| p[*axis]),
            Bind::MemberForce(i) => at(&snap.forces.force_n, *i),
            Bind::MemberLength(i) => at(&snap.forces.length_m, *i),
            Bind::SegmentForce(i, k) => snap.forces.segment_force_n.get(*i).map_or(f64::NAN, |t| at(t, *k)),
            Bind::Slip(i, k) => match snap.forces.at_friction_bound.get(*i).and_then(|b| b.get(*k)) {
                Some(&slipping) => f64::from(u8::from(slipping)),
                None => f64::NAN,
            },
            Bind::StrutLength(a, b) => match (snap.nodes.get(*a), snap.nodes.get(*b)) {
                (Some(pa), Some(pb)) => crate::structure::distance(*pa, *pb),
                _ => f64::NAN,
            },
            Bind::Observed(q) => observed.get(q).copied().unwrap_or(f64::NAN),
            Bind::JointAngle { parent, child, axis, initial } => {
                snap.joint_angle(*parent, *child, *axis).map_or(f64::NAN, |q| initial + q)
            }
            Bind::JointSlide { parent, child, anchor, axis, initial } => {
                snap.joint_slide(*parent, *child, *anchor, *axis).map_or(f64::NAN, |q| initial + q)
            }
        }
    }
}

/// The recording's series of the model's errors, one per prediction and equation (named once
/// per recorded run: the recorder takes static names).
fn series_names(spec: &ModelSpec) -> Vec<&'static str> {
    let names = spec.predictions.iter().map(|p| &p.name).chain(spec.equations.iter().map(|e| &e.name));
    names.map(|n| &*Box::leak(format!("model/{n}").into_boxed_str())).collect()
}

/// The number of `[[energy.frequencies]]` entries.
fn frequency_count(spec: &ModelSpec) -> usize {
    spec.energy.as_ref().and_then(|e| e.dynamics.as_ref()).map_or(0, |d| d.frequencies.len())
}

/// The dynamic model's modes at a settle point and its frequency predictions' errors.
struct ModesAt {
    reports: Vec<ModelModeReport>,
    errors: Vec<f64>,
}

/// Errors gathered for one prediction or equation.
#[derive(Clone, Debug, Default)]
pub(super) struct Acc {
    settled_max: f64,
    points: usize,
    transient_max: f64,
    transient_sum_sq: f64,
    ticks: u64,
    /// Over a motion's ticks (a motion run's predictions are judged there).
    motion_max: f64,
    motion_sum_sq: f64,
    motion_ticks: u64,
    /// Over a motion judged extrapolated: the largest estimate of the simulation's own error.
    estimate_max: Option<f64>,
}

impl Acc {
    /// A settle point's error (a NaN or an unsettled point counts as infinite).
    pub(super) fn point(&mut self, e: f64, settled: bool) {
        let e = if settled && e.is_finite() { e } else { f64::INFINITY };
        self.settled_max = self.settled_max.max(e);
        self.points += 1;
    }

    /// A motion tick's error (NaN counts as infinite: the prediction failed there).
    pub(super) fn motion_tick(&mut self, e: f64) {
        let e = if e.is_nan() { f64::INFINITY } else { e };
        self.motion_max = self.motion_max.max(e);
        self.motion_sum_sq += e * e;
        self.motion_ticks += 1;
    }

    /// A motion tick's estimate of the simulation's own error in what the check compares.
    pub(super) fn estimate(&mut self, e: f64) {
        self.estimate_max = Some(self.estimate_max.unwrap_or(0.0).max(e));
    }

    fn motion_rms(&self) -> f64 {
        if self.motion_ticks > 0 {
            (self.motion_sum_sq / self.motion_ticks as f64).sqrt()
        } else {
            f64::INFINITY
        }
    }

    pub(super) fn tick(&mut self, e: f64) {
        if e.is_finite() {
            self.transient_max = self.transient_max.max(e);
            self.transient_sum_sq += e * e;
            self.ticks += 1;
        }
    }
}

/// What a compared entry is judged by.
pub(super) struct Judged<'a> {
    pub(super) kind: &'a str,
    pub(super) name: &'a str,
    pub(super) class: &'a str,
    pub(super) tolerance: f64,
    pub(super) rms_tolerance: Option<f64>,
}

/// The report of one compared entry from its errors `a`: judged at the settle points, or over a
/// motion's ticks (`over_motion`: the largest error and, if given, the rms one).
pub(super) fn check_report(j: &Judged, a: &Acc, over_motion: bool) -> ModelCheckReport {
    let mut r = ModelCheckReport {
        kind: j.kind.into(),
        name: j.name.into(),
        class: j.class.into(),
        max_error: a.settled_max,
        tolerance: j.tolerance,
        passed: a.points > 0 && a.settled_max <= j.tolerance,
        points_compared: a.points,
        transient_max_error: a.transient_max,
        transient_rms_error: if a.ticks > 0 { (a.transient_sum_sq / a.ticks as f64).sqrt() } else { 0.0 },
        ticks_compared: a.ticks,
        rms_error: None,
        rms_tolerance: None,
        motion_ticks: None,
        simulation_error: a.estimate_max,
    };
    if over_motion {
        let rms = a.motion_rms();
        r.max_error = if a.motion_ticks > 0 { a.motion_max } else { f64::INFINITY };
        r.passed = a.motion_ticks > 0 && r.max_error <= j.tolerance && j.rms_tolerance.is_none_or(|t| rms <= t);
        r.rms_error = Some(rms);
        r.rms_tolerance = j.rms_tolerance;
        r.motion_ticks = Some(a.motion_ticks);
    }
    r
}

/// The file's `[energy.trajectory]`, if it has one.
fn trajectory_check(spec: &ModelSpec) -> Option<TrajectoryCheck> {
    spec.energy.as_ref()?.dynamics.as_ref()?.trajectory
}

/// The model observer.
pub struct ModelObserver {
    spec: ModelSpec,
    bind: Vec<Bind>,
    /// One per prediction, then one per equation.
    acc: Vec<Acc>,
    /// The energy model's: the distance to the stationary point landed on.
    energy: Acc,
    /// One per `[[energy.frequencies]]` entry: the relative error of its prediction.
    frequencies: Vec<Acc>,
    /// When the run is recorded: the series of each prediction's and equation's error per
    /// tick (`model/NAME`), in the order of `acc`.
    series: Option<Vec<&'static str>>,
    /// A motion run: the predictions are judged over the motion's ticks, not at settle points.
    motion: bool,
    /// With `[energy.trajectory]` in a motion run: the comparison with the Lagrangian model,
    /// tick by tick.
    trajectory: Option<Tracker>,
    /// A motion run's `[motion]` as the stated start needs it.
    stated: Option<StatedMotion>,
    /// When the run is recorded, with `[energy.trajectory]`: each coordinate's series, and the
    /// tick and simulated time [s] of every motion tick (a row of the comparison may be known
    /// ticks later).
    trajectory_series: Option<TrajectorySeries>,
    /// In a motion judged extrapolated: what divides a difference from the rougher state into
    /// the judged error (`MotionStarted::estimate_divisor`).
    estimate_divisor: f64,
}

/// What the stated start takes from `[motion]`.
#[derive(Clone, Copy, Debug)]
struct StatedMotion {
    /// The displaced joint's displacement [rad or m] (0 when none).
    displacement: f64,
    /// Its rate [rad/s or m/s].
    rate: f64,
    /// A free body is spun at the start (a rate that no coordinate states).
    spun: bool,
}

impl StatedMotion {
    fn new(m: &crate::settings::Motion) -> Self {
        let (displacement, rate) = m.coordinate.as_ref().map_or((0.0, 0.0), |(_, d, r)| (*d, *r));
        StatedMotion { displacement, rate, spun: m.spin.is_some() }
    }

    /// The coordinates' rates at the start, `q0` the coordinates of the start state and `q_eq`
    /// of the equilibrium it was displaced from: the stated rate times each coordinate's change
    /// per unit of the joint's displacement (exact where a coordinate moves linearly with the
    /// joint, as a joint angle does; no rate, no rates).
    fn rates(&self, classes: &[ErrorClass], q0: &[f64], q_eq: &[f64]) -> Result<Vec<f64>, LagrangianError> {
        if self.spun {
            let why = "a spun body's rate is no coordinate's: start = \"samples\" reads it from the motion";
            return Err(LagrangianError::NoStatedStart(why.into()));
        }
        if self.rate == 0.0 {
            return Ok(vec![0.0; q0.len()]);
        }
        if self.displacement == 0.0 {
            let why = "[motion] states a rate without a displacement: how it moves the coordinates is not known";
            return Err(LagrangianError::NoStatedStart(why.into()));
        }
        let change = |(c, (a, b)): (&ErrorClass, (&f64, &f64))| match c {
            ErrorClass::Angle => crate::mechanisms::wrap_angle(a - b),
            _ => a - b,
        };
        Ok(classes.iter().zip(q0.iter().zip(q_eq)).map(change).map(|d| self.rate * d / self.displacement).collect())
    }
}

/// The recording's series of the comparison with the Lagrangian model.
#[derive(Clone, Debug)]
struct TrajectorySeries {
    /// Per coordinate: `trajectory/NAME` (simulated, model) and `trajectory_error/NAME`.
    entities: Vec<(&'static str, &'static str)>,
    /// (tick, simulated time [s]) of every motion tick so far.
    ticks: Vec<(u64, f64)>,
}

/// The per-tick table's columns of the comparison, per coordinate: its simulated value, the
/// model's, the error.
pub const TRAJECTORY_COLUMNS: [&str; 3] = ["trajectory_sim", "trajectory_model", "trajectory_error"];

/// The recording's entity of a coordinate's simulated and model values, and of its error.
fn trajectory_entities(spec: &ModelSpec) -> Vec<(&'static str, &'static str)> {
    let leak = |s: String| &*Box::leak(s.into_boxed_str());
    let coordinates = spec.energy.iter().flat_map(|e| &e.coordinates);
    coordinates
        .map(|c| (leak(format!("trajectory/{}", c.name)), leak(format!("trajectory_error/{}", c.name))))
        .collect()
}

/// Why the file's dynamic model has no modes at a settle point.
#[derive(Debug, thiserror::Error)]
enum ModelModesError {
    /// The dynamics landed on no stationary point of the energy.
    #[error("no stationary point landed on")]
    NotLanded,
    /// The mass matrix at the coordinates `q` is not positive definite.
    #[error("energy kinetic at {q:?}: {source}")]
    Kinetic { q: Vec<f64>, source: crate::eigen::EigenError },
}

impl ModelObserver {
    /// The observer of `spec` on the run's `structure`; `recorded`: the run is recorded (each
    /// error per tick then goes to the recording). `motion`: a motion run's `[motion]`.
    pub fn new(
        spec: &ModelSpec,
        structure: &Structure,
        recorded: bool,
        motion: Option<&crate::settings::Motion>,
    ) -> Self {
        let mut used = vec![false; spec.symbols.len()];
        let exprs = spec
            .quantities
            .iter()
            .map(|q| &q.expr)
            .chain(spec.predictions.iter().map(|p| &p.formula))
            .chain(spec.equations.iter().map(|e| &e.residual));
        for u in exprs.flat_map(|e| e.uses().iter()) {
            used[*u] = true;
        }
        spec.predictions.iter().for_each(|p| used[p.symbol] = true);
        if let Some(e) = &spec.energy {
            let dynamics =
                e.dynamics.iter().flat_map(|d| d.mass.iter().chain(d.frequencies.iter().map(|f| &f.formula)));
            let exprs =
                e.coordinates.iter().map(|c| &c.measured).chain([&e.potential]).chain(&e.hessian).chain(dynamics);
            let n = used.len();
            for u in exprs.flat_map(|x| x.uses().iter()).filter(|u| **u < n) {
                used[*u] = true;
            }
        }
        let bind = spec
            .symbols
            .iter()
            .zip(&used)
            .map(|(s, u)| if *u { Bind::new(&s.source, structure) } else { Bind::Unused })
            .collect();
        ModelObserver {
            spec: spec.clone(),
            bind,
            acc: vec![Acc::default(); spec.predictions.len() + spec.equations.len()],
            energy: Acc::default(),
            frequencies: vec![Acc::default(); frequency_count(spec)],
            series: recorded.then(|| series_names(spec)),
            motion: motion.is_some(),
            trajectory: Self::tracker(spec, motion),
            stated: motion.map(StatedMotion::new),
            trajectory_series: Self::tracker(spec, motion)
                .filter(|_| recorded)
                .map(|_| TrajectorySeries { entities: trajectory_entities(spec), ticks: Vec::new() }),
            estimate_divisor: f64::NAN,
        }
    }

    /// The comparison with the Lagrangian model, in a motion run with `[energy.trajectory]`.
    fn tracker(spec: &ModelSpec, motion: Option<&crate::settings::Motion>) -> Option<Tracker> {
        let (energy, check, m) = (spec.energy.as_ref()?, trajectory_check(spec)?, motion?);
        Some(Tracker::new(energy, (check.start, check.measure), m.duration_s))
    }

    /// Every symbol's value in this state, at the model's time `time_s`.
    pub(super) fn values(
        &self,
        snap: &Snapshot,
        inputs: &Values,
        params: &Values,
        observed: &Values,
        time_s: f64,
    ) -> Vec<f64> {
        self.spec.values(inputs, params, |i| self.bind[i].read(snap, observed, time_s))
    }

    /// The estimate of the simulation's own error in each prediction's simulated value (its
    /// class's error) and each equation's residual, from the judged values `v` and those of the
    /// state one level rougher (`run/levels.rs`: they differ by `divisor` times the judged error).
    fn estimates(&self, v: &[f64], rougher: &[f64], divisor: f64) -> Vec<f64> {
        let predictions = self.spec.predictions.iter().map(|p| p.class.error(rougher[p.symbol], v[p.symbol]));
        let equations = self.spec.equations.iter().map(|e| (e.residual.eval(v) - e.residual.eval(rougher)).abs());
        predictions.chain(equations).map(|d| d / divisor).collect()
    }

    /// Each prediction's (predicted, simulated, error), then each equation's (0, residual,
    /// |residual|), in the order of `acc`.
    pub(super) fn errors(&self, v: &[f64]) -> Vec<(f64, f64, f64)> {
        let predictions = self.spec.predictions.iter().map(|p| {
            let (predicted, simulated) = (p.formula.eval(v), v[p.symbol]);
            (predicted, simulated, p.class.error(predicted, simulated))
        });
        let equations = self.spec.equations.iter().map(|e| {
            let r = e.residual.eval(v);
            (0.0, r, r.abs())
        });
        predictions.chain(equations).collect()
    }

    fn tolerances(&self) -> impl Iterator<Item = (&str, f64)> {
        let p = self.spec.predictions.iter().map(|p| (p.name.as_str(), p.tolerance));
        p.chain(self.spec.equations.iter().map(|e| (e.name.as_str(), e.tolerance)))
    }

    /// The energy model at a settle point: its stationary points, the one nearest the settled
    /// state, and the error counted (the distance to it; infinite when it is no minimum).
    fn energy_point(&self, v: &[f64]) -> Option<(EnergyPointReport, f64)> {
        let e = self.spec.energy.as_ref()?;
        let measured = e.measured(v);
        let mut values = v.to_vec();
        values.resize(e.values_len(), 0.0);
        let stationary = e.stationary_points(&mut values, &measured);
        let landed = (0..stationary.len()).min_by(|a, b| {
            e.distance(&stationary[*a].coordinates, &measured)
                .total_cmp(&e.distance(&stationary[*b].coordinates, &measured))
        });
        let distance = landed.map_or(f64::INFINITY, |i| e.distance(&stationary[i].coordinates, &measured));
        let error = match landed {
            Some(i) if stationary[i].kind == Kind::Minimum => distance,
            _ => f64::INFINITY,
        };
        let named = |x: &[f64]| e.coordinates.iter().zip(x).map(|(c, v)| (c.name.clone(), *v)).collect::<Values>();
        let solved = match landed {
            Some(i) => {
                e.solved_names().into_iter().zip(e.solved_values(&mut values, &stationary[i].coordinates)).collect()
            }
            None => Values::new(),
        };
        let stationary = stationary
            .iter()
            .map(|s| StationaryReport {
                coordinates: named(&s.coordinates),
                energy: s.energy,
                eigenvalues: s.eigenvalues.clone(),
                kind: s.kind.name().into(),
            })
            .collect();
        let report =
            EnergyPointReport { measured: named(&measured), stationary, landed, distance, modes: None, solved };
        Some((report, error))
    }

    /// The dynamic model's modes at the stationary point landed on, and each frequency
    /// prediction's relative error there (infinite where there are no modes: no point landed
    /// on, or a mass matrix that is not positive definite, which is `Err` with the message).
    fn model_modes(&self, v: &[f64], report: &EnergyPointReport) -> Option<Result<ModesAt, ModelModesError>> {
        let e = self.spec.energy.as_ref()?;
        let d = e.dynamics.as_ref()?;
        let landed = report.landed.map(|i| &report.stationary[i]);
        let Some(point) = landed else { return Some(Err(ModelModesError::NotLanded)) };
        let q: Vec<f64> = e.coordinates.iter().map(|c| point.coordinates[&c.name]).collect();
        let mut values = v.to_vec();
        values.resize(e.values_len(), 0.0);
        let modes = match e.modes_at(&mut values, &q)? {
            Ok(m) => m,
            Err(source) => return Some(Err(ModelModesError::Kinetic { q, source })),
        };
        let closed = &v[..self.spec.symbols.len()];
        let solved = e.solved_names().into_iter().map(|n| report.solved.get(&n).copied().unwrap_or(f64::NAN));
        let with_solved: Vec<f64> = closed.iter().copied().chain(solved).collect();
        let errors = d
            .frequencies
            .iter()
            .map(|f| {
                let predicted = f.formula.eval(&with_solved);
                crate::file_model::spec::ErrorClass::Relative.error(predicted, modes[f.mode].omega())
            })
            .collect();
        let reports = modes
            .iter()
            .map(|m| {
                let scale = m.shape.iter().copied().fold(0.0f64, |a, x| if x.abs() > a.abs() { x } else { a });
                let scale = if scale == 0.0 { 1.0 } else { scale };
                let shape = e.coordinates.iter().zip(m.shape.iter()).map(|(c, x)| (c.name.clone(), x / scale));
                ModelModeReport {
                    omega_squared: m.omega_squared,
                    omega_rad_per_s: m.omega(),
                    frequency_hz: m.omega() / std::f64::consts::TAU,
                    shape: shape.collect(),
                }
            })
            .collect();
        Some(Ok(ModesAt { reports, errors }))
    }

    /// Judges the frequency predictions at a settle point, or at a motion's start (`judged`),
    /// and puts the modes in its report.
    fn frequency_point(&mut self, v: &[f64], point: &mut PointReport, judged: bool, notes: &mut Vec<Note>) {
        let Some(report) = point.energy.as_mut() else { return };
        let Some(result) = self.model_modes(v, report) else { return };
        let errors = match result {
            Ok(m) => {
                report.modes = Some(m.reports);
                m.errors
            }
            Err(message) => {
                notes.push(Note::Event(format!("point {}: dynamic model: {message}", point.index)));
                vec![f64::INFINITY; self.frequencies.len()]
            }
        };
        let predictions = self.spec.energy.iter().flat_map(|e| e.dynamics.iter()).flat_map(|d| &d.frequencies);
        for ((a, e), f) in self.frequencies.iter_mut().zip(&errors).zip(predictions) {
            a.point(*e, judged);
            if judged && e.partial_cmp(&f.tolerance).is_none_or(Ordering::is_gt) {
                notes.push(Note::Event(format!(
                    "point {}: frequency {} failed: relative error {e:.3e} > tolerance {:.1e}",
                    point.index, f.name, f.tolerance
                )));
                point.within_tolerance = false;
            }
        }
    }

    /// The frequency predictions, judged.
    fn frequency_reports(&self) -> Vec<ModelCheckReport> {
        let predictions = self.spec.energy.iter().flat_map(|e| e.dynamics.iter()).flat_map(|d| &d.frequencies);
        predictions
            .zip(&self.frequencies)
            .map(|(f, a)| {
                ModelCheckReport::at_settle_points(
                    "frequency",
                    &f.name,
                    "relative",
                    a.settled_max,
                    f.tolerance,
                    a.points,
                )
            })
            .collect()
    }

    /// The file's quantities in the state `snap` at its own time, by name, in file order
    /// (`run::sensitivity`: outputs of a settled state).
    pub fn quantities_at(
        &self,
        snap: &Snapshot,
        inputs: &Values,
        params: &Values,
        observed: &Values,
    ) -> Vec<(String, f64)> {
        let v = self.values(snap, inputs, params, observed, snap.time_s);
        let quantities = self.spec.symbols.iter().enumerate().filter(|(_, s)| matches!(s.source, Source::Quantity(_)));
        quantities.map(|(i, s)| (s.name.clone(), v[i])).collect()
    }

    /// The table's columns of the model: each quantity (`model:NAME`), each prediction's
    /// predicted value and error (`predicted:NAME`, `error:NAME`), each equation's residual
    /// (`equation:NAME`).
    /// The file's quantities in this tick's state, by name.
    pub(super) fn quantities(&self, snap: &Snapshot, t: &Tick) -> Values {
        let time_s = t.motion_time_s.unwrap_or(snap.time_s);
        let v = self.values(snap, t.inputs, t.params, t.simulated, time_s);
        let quantities = self.spec.symbols.iter().enumerate().filter(|(_, s)| matches!(s.source, Source::Quantity(_)));
        quantities.map(|(i, s)| (s.name.clone(), v[i])).collect()
    }

    pub(super) fn table_columns(&self) -> Vec<String> {
        let q = self.spec.quantities.iter().map(|q| format!("model:{}", q.name));
        let p =
            self.spec.predictions.iter().flat_map(|p| [format!("predicted:{}", p.name), format!("error:{}", p.name)]);
        q.chain(p).chain(self.spec.equations.iter().map(|e| format!("equation:{}", e.name))).collect()
    }

    /// This tick's values of [`ModelObserver::table_columns`].
    pub(super) fn table_values(&self, t: &Tick) -> Vec<Option<f64>> {
        let time_s = t.motion_time_s.unwrap_or(t.snapshot.time_s);
        let v = self.values(t.snapshot, t.inputs, t.params, t.simulated, time_s);
        let errors = self.errors(&v);
        let quantities = self.spec.symbols.iter().enumerate().filter(|(_, s)| matches!(s.source, Source::Quantity(_)));
        let mut out: Vec<Option<f64>> = quantities.map(|(i, _)| Some(v[i])).collect();
        let n = self.spec.predictions.len();
        out.extend(errors[..n].iter().flat_map(|(p, _, e)| [Some(*p), Some(*e)]));
        out.extend(errors[n..].iter().map(|(_, r, _)| Some(*r)));
        out
    }

    /// A motion tick's coordinates (every symbol's value `v`, the motion's time [s]) to the
    /// comparison with the Lagrangian model: the rows known now (none without one).
    pub(super) fn push_trajectory(&mut self, t: &Tick, v: &[f64], time_s: f64) -> Vec<Row> {
        let (Some(tracker), Some(e)) = (self.trajectory.as_mut(), &self.spec.energy) else { return vec![] };
        tracker.push(e, (v, &e.measured(v)), time_s, t.cancel)
    }

    /// This motion tick's coordinates to the comparison (as [`ModelObserver::push_trajectory`]).
    pub(super) fn trajectory_tick(&mut self, t: &Tick) -> Vec<Row> {
        let Some(time_s) = t.motion_time_s.filter(|_| self.trajectory.is_some()) else { return vec![] };
        let v = self.values(t.snapshot, t.inputs, t.params, t.simulated, time_s);
        self.push_trajectory(t, &v, time_s)
    }

    /// The rows the comparison still holds when the motion ends, uncompared.
    pub(super) fn trajectory_flush(&mut self) -> Vec<Row> {
        self.trajectory.as_mut().map_or(vec![], Tracker::flush)
    }

    /// Whether the run compares a motion with the Lagrangian model.
    pub(super) fn has_trajectory(&self) -> bool {
        self.trajectory.is_some()
    }

    /// The table's columns of the comparison with the Lagrangian model (none without one):
    /// per coordinate, [`TRAJECTORY_COLUMNS`]`:NAME`.
    pub(super) fn trajectory_columns(&self) -> Vec<String> {
        let coordinates = self.spec.energy.iter().flat_map(|e| &e.coordinates).filter(|_| self.has_trajectory());
        coordinates.flat_map(|c| TRAJECTORY_COLUMNS.map(|k| format!("{k}:{}", c.name))).collect()
    }

    /// A row's values of [`ModelObserver::trajectory_columns`] (None where uncompared).
    pub(super) fn trajectory_cells(row: &Row) -> Vec<Option<f64>> {
        let compared = |i: usize| row.compared.as_ref().map(|(m, e)| (m[i], e[i]));
        let cells = row
            .simulated
            .iter()
            .enumerate()
            .map(|(i, s)| [Some(*s), compared(i).map(|c| c.0), compared(i).map(|c| c.1)]);
        cells.flatten().collect()
    }

    /// The rows of the comparison to the recording (each at its own tick), and at the motion's
    /// first tick the names of the series.
    fn record_trajectory(&mut self, t: &Tick, rows: &[Row], notes: &mut Vec<Note>) {
        let Some(series) = self.trajectory_series.as_mut() else { return };
        if series.ticks.is_empty() {
            for (values, errors) in &series.entities {
                notes.push(Note::SeriesNames(values, vec!["simulated".into(), "model".into()]));
                notes.push(Note::SeriesNames(errors, vec!["|simulated - model|".into()]));
            }
        }
        series.ticks.push((t.snapshot.tick, t.snapshot.time_s));
        for row in rows {
            let Some((model, errors)) = &row.compared else { continue };
            let (tick, time_s) = series.ticks[row.index];
            for (i, (values, error)) in series.entities.iter().enumerate() {
                notes.push(Note::ScalarsAt { entity: values, tick, time_s, values: vec![row.simulated[i], model[i]] });
                notes.push(Note::ScalarsAt { entity: error, tick, time_s, values: vec![errors[i]] });
            }
        }
    }

    pub fn reports(&self) -> Vec<ModelCheckReport> {
        let kinds = self.spec.predictions.iter().map(|p| ("prediction", p.class.name()));
        let kinds = kinds.chain(self.spec.equations.iter().map(|_| ("equation", "residual")));
        let rms_tolerances = self.spec.predictions.iter().map(|p| p.rms_tolerance);
        let rms_tolerances = rms_tolerances.chain(self.spec.equations.iter().map(|_| None));
        kinds
            .zip(self.tolerances())
            .zip(&self.acc)
            .zip(rms_tolerances)
            .map(|((((kind, class), (name, tolerance)), a), rms_tolerance)| {
                let judged = Judged { kind, name, class, tolerance, rms_tolerance };
                check_report(&judged, a, self.motion && kind == "prediction")
            })
            .chain(self.frequency_reports())
            .chain(self.spec.energy.as_ref().map(|e| {
                let (max, points) = (self.energy.settled_max, self.energy.points);
                ModelCheckReport::at_settle_points("energy", "energy", "coordinates", max, e.tolerance, points)
            }))
            .collect()
    }
}

/// A run whose file states its own model compares it (`observers::KINDS`).
pub(super) fn make(setup: &Setup, _warnings: &mut Vec<String>) -> Made {
    let Some(spec) = setup.model else { return Ok(None) };
    let recorded = setup.recording.is_some();
    Ok(Some(Box::new(ModelObserver::new(spec, setup.structure, recorded, setup.motion))))
}

impl Observer for ModelObserver {
    fn tick(&mut self, t: &Tick, notes: &mut Vec<Note>) {
        let time_s = t.motion_time_s.unwrap_or(t.snapshot.time_s);
        let v = self.values(t.snapshot, t.inputs, t.params, t.simulated, time_s);
        let errors = self.errors(&v);
        for (a, (_, _, e)) in self.acc.iter_mut().zip(&errors) {
            a.tick(*e);
        }
        if let Some(time_s) = t.motion_time_s {
            let predictions = self.spec.predictions.len();
            for (a, (_, _, e)) in self.acc.iter_mut().zip(&errors).take(predictions) {
                a.motion_tick(*e);
            }
            if let Some(rougher) = t.rougher {
                let v_rougher = self.values(rougher.state, t.inputs, t.params, rougher.values, time_s);
                let estimates = self.estimates(&v, &v_rougher, self.estimate_divisor);
                for (a, e) in self.acc.iter_mut().zip(estimates) {
                    a.estimate(e);
                }
            }
            let rows = self.push_trajectory(t, &v, time_s);
            self.record_trajectory(t, &rows, notes);
        }
        if let Some(series) = &self.series {
            notes.extend(series.iter().zip(&errors).map(|(s, (_, _, e))| Note::Scalar(s, *e)));
        }
    }

    fn motion_start(&mut self, start: &MotionStarted) {
        let Some(divisor) = start.estimate_divisor else { return };
        self.estimate_divisor = divisor;
        if let Some(tracker) = self.trajectory.as_mut() {
            tracker.note_extrapolated();
        }
    }

    fn motion_start_state(&mut self, equilibrium: &Tick, start: &Tick) {
        let (Some(tracker), Some(e), Some(stated)) = (self.trajectory.as_mut(), &self.spec.energy, self.stated) else {
            return;
        };
        let read = |t: &Tick| {
            let v = self.spec.values(t.inputs, t.params, |i| self.bind[i].read(t.snapshot, t.simulated, 0.0));
            e.measured(&v)
        };
        let (q_eq, q0) = (read(equilibrium), read(start));
        let classes: Vec<ErrorClass> = e.coordinates.iter().map(|c| c.class).collect();
        tracker.set_stated(stated.rates(&classes, &q0, &q_eq).map(|v0| (q0, v0)));
    }

    /// Compares at the point (outside the analytic model's validity: not compared), and adds
    /// the quantities to the point's simulated values and the predictions to its analytic ones.
    fn settle_point(&mut self, p: &SettlePoint, point: &mut PointReport, notes: &mut Vec<Note>) {
        if p.outside_model {
            return;
        }
        let v = self.values(p.snapshot, &point.inputs, p.params, &point.simulated, p.snapshot.time_s);
        let errors = self.errors(&v);
        let tolerances: Vec<(String, f64)> = self.tolerances().map(|(n, t)| (n.to_string(), t)).collect();
        // A motion run judges its predictions over the motion, not at its start point.
        let skip = if self.motion { self.spec.predictions.len() } else { 0 };
        for ((a, (_, _, e)), (name, tol)) in self.acc.iter_mut().zip(&errors).zip(&tolerances).skip(skip) {
            a.point(*e, point.settled);
            if point.settled && e.partial_cmp(tol).is_none_or(Ordering::is_gt) {
                notes.push(Note::Event(format!(
                    "point {}: {name} failed: error {e:.3e} > tolerance {tol:.1e}",
                    point.index
                )));
                point.within_tolerance = false;
            }
        }
        for (i, s) in self.spec.symbols.iter().enumerate() {
            if let Source::Quantity(_) = s.source {
                point.simulated.entry(s.name.clone()).or_insert(v[i]);
            }
        }
        for (pr, (predicted, _, e)) in self.spec.predictions.iter().zip(&errors).filter(|_| !self.motion) {
            let name = &self.spec.symbols[pr.symbol].name;
            point.analytic.entry(name.clone()).or_insert(*predicted);
            point.errors.insert(name.clone(), *e);
        }
        // A motion's start point is judged where the motion starts: released from the drawn
        // state it has not settled, and the energy model (its distance to the stationary point,
        // its own frequencies there) is judged at that state all the same (issue 62 item 6:
        // both had been infinite, with no reason).
        let judged = point.settled || self.motion;
        if let Some((report, error)) = self.energy_point(&v) {
            self.energy.point(error, judged);
            let tol = self.spec.energy.as_ref().map_or(0.0, |e| e.tolerance);
            if judged && error.partial_cmp(&tol).is_none_or(Ordering::is_gt) {
                let at = if point.settled { "settled" } else { "the motion's start (released, not settled) is" };
                notes.push(Note::Event(format!(
                    "point {}: energy: {at} {:.3e} from a minimum (tolerance {tol:.1e})",
                    point.index, error
                )));
                point.within_tolerance = false;
            }
            point.energy = Some(report);
            self.frequency_point(&v, point, judged, notes);
        }
    }

    fn finish(&mut self, report: &mut ScenarioReport) {
        report.model_checks = self.reports();
        for c in report.model_checks.iter().filter(|c| c.below_resolution()) {
            report.warnings.push(format!(
                "{}: tolerance {:.1e} below what this run resolves (its simulation error estimate {:.1e}): a finer time step resolves it",
                c.failure(),
                c.tolerance,
                c.simulation_error.unwrap_or(f64::NAN)
            ));
        }
        let (Some(tracker), Some(e), Some(check)) = (&self.trajectory, &self.spec.energy, trajectory_check(&self.spec))
        else {
            return;
        };
        if let Some(m) = report.motion.as_mut() {
            m.lagrangian = Some(tracker.report(e, (check.tolerance, check.rms_tolerance)));
        }
    }
}
