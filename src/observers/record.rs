//! Recording a run to a rerun `.rrd` file, headless.
//!
//! Entities: `structure/{nodes,struts,springs,cables}` (every member coloured by its force),
//! `analytic/{nodes,struts}` (the analytic prediction as a ghost overlay), and time series with
//! one named series per quantity or member: `errors` (simulated - analytic), `errors_log10`
//! (log10 of their magnitude: rerun 0.36 plots have no log axis), `forces/{springs,cables,actuators}`,
//! `inputs`, `residual` (at the ticks where the settle loop computed it), `energy/kinetic_j`; `interference/min_clearance_m`; `events` (text log);
//! with the file's model, `model/NAME` (each prediction's and equation's error) and, in a
//! motion run with `[energy.trajectory]`, `trajectory/COORD` (the coordinate simulated and its
//! Lagrangian model, two series in one plot) and `trajectory_error/COORD` at every compared
//! tick; in a motion run, `frequencies/NAME` (each frequency check's fit, corrected, and its
//! model value) and `frequencies/trajectory:COORD` (the frequencies fitted to the coordinate's
//! simulated and model trajectories) over the motion, each with an event.
//! The scenario file and the report summary are stored as documents. Timelines: `tick` and
//! `sim_time`. A blueprint ([`blueprint`]) stored at the start of the recording lays the viewer
//! out: the 3D structure, the error, force and energy plots, the events and the documents.
//!
//! Per-tick data and events are buffered per entity and sent in blocks of ticks as one chunk each
//! (`send_columns`): one `log` call per entity and tick cost more than the simulation step.
//! The file is written to `<path>.partial` and renamed when the run ends, so a reader never
//! sees a half-written recording under the final name.

use super::{Made, Note, Observer, ObserverError, Setup, Tick};
use crate::mechanisms::wrap_angle;
use crate::report::ScenarioReport;
use crate::structure::MemberKind;
use std::path::{Path, PathBuf};

/// Why a recording could not be written.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file was refused, or could not be put in place (`output`).
    #[error("cannot record to {path}: {source}")]
    Output { path: String, source: crate::output::OutputError },
    /// The file's directory could not be made.
    #[error("cannot record to {path}: {source}")]
    Io { path: String, source: std::io::Error },
    /// rerun's SDK refused (in its words).
    #[error("cannot record to {path}: {message}")]
    Rerun { path: String, message: String },
}

/// Where a recording goes.
#[derive(Clone, Debug, PartialEq)]
pub enum RecordTarget {
    /// An `.rrd` file, written to `<path>.partial` and renamed when complete.
    File(PathBuf),
    /// A live rerun viewer or server at this address ("" for rerun's default).
    Live(String),
}

/// A run's recording: where, how often, and the scenario text stored with it.
pub struct Recording<'a> {
    pub target: RecordTarget,
    /// Every N-th tick is recorded (events always).
    pub every: u64,
    /// The scenario file's text, stored as a document.
    pub scenario: &'a str,
    /// The scenario has a model of its own (`[[predictions]]`, `[[equations]]`): the viewer
    /// opens on its errors (`model/NAME`).
    pub file_model: bool,
}

/// The application name recordings carry.
const APP: &str = "tensegrity-testbed";

/// The recording's series of the simulation's own error estimate per quantity, at every tick of
/// a motion judged extrapolated over the time step (`run/levels.rs`).
pub const ESTIMATE_SERIES: &str = "simulation_error";

pub struct Recorder {
    rec: rerun::RecordingStream,
    target: Target,
    every: u64,
    /// Whether the static parts (labels, radii, fixed colours, series names) were logged.
    statics_logged: bool,
    /// Whether the series of the simulation's own error estimate were named (a motion judged
    /// extrapolated over the time step).
    estimate_named: bool,
    /// Per-tick data waiting to be sent.
    columns: Columns,
    /// Scalar series logged through [`Recorder::scalar`], by entity.
    extra: Vec<Column>,
    /// Ticks buffered since the last send, and when that was.
    pending: usize,
    last_send: std::time::Instant,
    /// The last tick seen and its simulated time [s] (for events and extra scalars).
    last_tick: u64,
    last_time_s: f64,
}

/// Ticks buffered per entity before they are sent as one chunk.
const BLOCK_TICKS: usize = 1024;

/// Longest buffered data waits before it is sent, so a live viewer stays current [s].
const BLOCK_MAX_AGE_S: f64 = 0.25;

/// What one buffered entity holds per tick.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// `Points3D` positions.
    Points,
    /// `LineStrips3D` of two points each, with per-strip colours when given.
    Segments,
    /// `Scalars`, one per named series.
    Scalars,
    /// `TextLog` lines, one per row.
    Text,
}

/// The rows of one entity since the last send: time columns, the number of instances per row,
/// and the instances of all rows end to end.
struct Column {
    entity: String,
    kind: Kind,
    ticks: Vec<i64>,
    secs: Vec<f64>,
    lengths: Vec<usize>,
    points: Vec<[f32; 3]>,
    colors: Vec<[u8; 4]>,
    values: Vec<f64>,
    texts: Vec<String>,
}

impl Column {
    fn new(entity: &str, kind: Kind) -> Self {
        Column {
            entity: entity.to_string(),
            kind,
            ticks: Vec::new(),
            secs: Vec::new(),
            lengths: Vec::new(),
            points: Vec::new(),
            colors: Vec::new(),
            values: Vec::new(),
            texts: Vec::new(),
        }
    }

    fn row(&mut self, tick: u64, time_s: f64, len: usize) {
        self.ticks.push(tick as i64);
        self.secs.push(time_s);
        self.lengths.push(len);
    }

    fn push_points(&mut self, tick: u64, time_s: f64, points: impl ExactSizeIterator<Item = [f64; 3]>) {
        self.row(tick, time_s, points.len());
        self.points.extend(points.map(f32x3));
    }

    /// One segment per pair of node indices into `nodes`.
    fn push_segments(
        &mut self,
        tick: u64,
        time_s: f64,
        nodes: &[[f64; 3]],
        pairs: impl Iterator<Item = (usize, usize)>,
    ) {
        let before = self.points.len();
        for (a, b) in pairs {
            self.points.push(f32x3(nodes[a]));
            self.points.push(f32x3(nodes[b]));
        }
        self.row(tick, time_s, (self.points.len() - before) / 2);
    }

    fn push_values(&mut self, tick: u64, time_s: f64, values: impl IntoIterator<Item = f64>) {
        let before = self.values.len();
        self.values.extend(values);
        self.row(tick, time_s, self.values.len() - before);
    }

    fn push_text(&mut self, tick: u64, time_s: f64, text: &str) {
        self.row(tick, time_s, 1);
        self.texts.push(text.to_string());
    }

    /// Sends the buffered rows as one chunk and empties the buffer (keeping its capacity).
    fn send(&mut self, rec: &rerun::RecordingStream) {
        if self.ticks.is_empty() {
            return;
        }
        let times = [
            rerun::TimeColumn::new_sequence("tick", self.ticks.drain(..)),
            rerun::TimeColumn::new_duration_secs("sim_time", self.secs.drain(..)),
        ];
        let lengths = self.lengths.iter().copied();
        let columns: Result<Vec<_>, _> = match self.kind {
            Kind::Points => rerun::Points3D::update_fields()
                .with_positions(self.points.drain(..))
                .columns(lengths)
                .map(Iterator::collect),
            Kind::Segments => segments(&self.points).and_then(|array| {
                let mut strips = rerun::LineStrips3D::update_fields();
                strips.strips =
                    Some(rerun::SerializedComponentBatch::new(array, rerun::LineStrips3D::descriptor_strips()));
                if !self.colors.is_empty() {
                    strips = strips.with_colors(self.colors.drain(..));
                }
                strips.columns(lengths).map(Iterator::collect)
            }),
            Kind::Scalars => rerun::Scalars::update_fields()
                .with_scalars(self.values.drain(..))
                .columns(lengths)
                .map(Iterator::collect),
            Kind::Text => rerun::TextLog::update_fields()
                .with_many_text(self.texts.drain(..))
                .columns(lengths)
                .map(Iterator::collect),
        };
        self.points.clear();
        self.lengths.clear();
        if let Ok(columns) = columns {
            let _ = rec.send_columns(self.entity.as_str(), times, columns);
        }
    }
}

/// Line strips of two points each, `points` taken in pairs, as one arrow array built directly:
/// the component's own conversion allocates a vector per strip.
fn segments(points: &[[f32; 3]]) -> rerun::SerializationResult<rerun::external::arrow::array::ArrayRef> {
    use rerun::external::arrow::{array::ListArray, buffer::OffsetBuffer, datatypes::DataType};
    use rerun::Loggable as _;
    let DataType::List(field) = rerun::LineStrip3D::arrow_datatype() else {
        unreachable!("a line strip is a list of points")
    };
    let values = rerun::datatypes::Vec3D::to_arrow(points.iter().map(|p| rerun::datatypes::Vec3D(*p)))?;
    let offsets = OffsetBuffer::from_lengths(std::iter::repeat_n(2, points.len() / 2));
    Ok(std::sync::Arc::new(ListArray::try_new(field, offsets, values, None)?))
}

/// Every per-tick entity of a recording.
struct Columns {
    nodes: Column,
    struts: Column,
    springs: Column,
    cables: Column,
    ghost_nodes: Column,
    ghost_struts: Column,
    errors: Column,
    errors_log10: Column,
    spring_forces: Column,
    cable_forces: Column,
    actuator_forces: Column,
    inputs: Column,
    residual: Column,
    kinetic_energy: Column,
    events: Column,
}

impl Columns {
    fn new() -> Self {
        Columns {
            nodes: Column::new("structure/nodes", Kind::Points),
            struts: Column::new("structure/struts", Kind::Segments),
            springs: Column::new("structure/springs", Kind::Segments),
            cables: Column::new("structure/cables", Kind::Segments),
            ghost_nodes: Column::new("analytic/nodes", Kind::Points),
            ghost_struts: Column::new("analytic/struts", Kind::Segments),
            errors: Column::new("errors", Kind::Scalars),
            errors_log10: Column::new("errors_log10", Kind::Scalars),
            spring_forces: Column::new("forces/springs", Kind::Scalars),
            cable_forces: Column::new("forces/cables", Kind::Scalars),
            actuator_forces: Column::new("forces/actuators", Kind::Scalars),
            inputs: Column::new("inputs", Kind::Scalars),
            residual: Column::new("residual", Kind::Scalars),
            kinetic_energy: Column::new("energy/kinetic_j", Kind::Scalars),
            events: Column::new("events", Kind::Text),
        }
    }

    fn all(&mut self) -> [&mut Column; 15] {
        [
            &mut self.nodes,
            &mut self.struts,
            &mut self.springs,
            &mut self.cables,
            &mut self.ghost_nodes,
            &mut self.ghost_struts,
            &mut self.errors,
            &mut self.errors_log10,
            &mut self.spring_forces,
            &mut self.cable_forces,
            &mut self.actuator_forces,
            &mut self.inputs,
            &mut self.residual,
            &mut self.kinetic_energy,
            &mut self.events,
        ]
    }
}

/// Where a recording goes.
enum Target {
    /// An `.rrd` file, written to `partial` and renamed to `path` when complete.
    File { partial: PathBuf, path: PathBuf },
    /// A live stream to a rerun viewer or server.
    Live { url: String },
}

/// How long the end of a live stream waits for a viewer to take the data [s].
const LIVE_FLUSH_TIMEOUT_S: f64 = 2.0;

/// How long to wait for a viewer to accept a connection before streaming [s].
const CONNECT_PROBE_TIMEOUT_S: f64 = 0.5;

/// Whether something accepts TCP connections at the host and port of a rerun URL such as
/// `rerun+http://127.0.0.1:9876/proxy`.
fn listening(url: &str) -> bool {
    use std::net::ToSocketAddrs;
    let rest = url.split("://").nth(1).unwrap_or(url);
    let authority = rest.split('/').next().unwrap_or(rest);
    let Ok(addrs) = authority.to_socket_addrs() else { return false };
    addrs.into_iter().any(|a| {
        std::net::TcpStream::connect_timeout(&a, std::time::Duration::from_secs_f64(CONNECT_PROBE_TIMEOUT_S)).is_ok()
    })
}

/// rerun's own default address for a live viewer.
pub const DEFAULT_CONNECT_URL: &str = "rerun+http://127.0.0.1:9876/proxy";

fn f32x3(p: [f64; 3]) -> [f32; 3] {
    [p[0] as f32, p[1] as f32, p[2] as f32]
}

/// Each strut's axial force [N], tension positive, from the springs and cables pulling at its
/// first node: sum of their forces there along the strut, from the other end outwards
/// (compression when they pull the end away from the strut). Loads at the node other than
/// members (gravity, actuators, joints) are not counted: a colour, not a measurement.
fn strut_forces(s: &crate::structure::Structure, snap: &crate::snapshot::Snapshot) -> Vec<f64> {
    use nalgebra::Vector3;
    let f = &snap.forces;
    let p = |n: usize| Vector3::from(snap.nodes[n]);
    // The springs' and cables' pull at every node, summed once: one pass over the members.
    let mut pull = vec![Vector3::zeros(); snap.nodes.len()];
    let tensioned = s.members_of(MemberKind::Spring).chain(s.members_of(MemberKind::Cable));
    for (i, member) in tensioned {
        let t = f.force_n[i];
        for (a, b) in member.segments() {
            let d = p(b) - p(a);
            let len = d.norm();
            if len > 0.0 {
                pull[a] += d * (t / len);
                pull[b] -= d * (t / len);
            }
        }
    }
    let axial = |(_, strut): (usize, &crate::structure::Member)| {
        let (a, b) = strut.ends();
        -pull[a].dot(&(p(a) - p(b)).normalize())
    };
    s.members_of(MemberKind::Strut).map(axial).collect()
}

/// Each segment's label among the members of `kind`: its member's name.
fn segment_names(s: &crate::structure::Structure, kind: MemberKind) -> Vec<String> {
    s.members_of(kind).flat_map(|(_, m)| m.segments().map(|_| m.name.clone())).collect()
}

/// Colour of a member by its force: blue in compression, red in tension, grey when slack.
fn force_colour(force: f64, max_abs: f64) -> [u8; 4] {
    if force == 0.0 {
        return [150, 150, 150, 255];
    }
    let s = (force.abs() / max_abs.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    let c = (80.0 + 175.0 * s) as u8;
    if force > 0.0 {
        [c, 60, 60, 255]
    } else {
        [60, 60, c, 255]
    }
}

impl Recorder {
    /// Starts the recording `r` with the scenario stored in it (None: a live viewer that
    /// nobody runs, said in `warnings`).
    pub fn start(r: &Recording, warnings: &mut Vec<String>) -> Result<Option<Self>, RecordError> {
        let mut recorder = match &r.target {
            RecordTarget::File(path) => Recorder::create(path, APP, r.every, r.file_model).map(Some),
            RecordTarget::Live(url) => Recorder::connect(url, APP, r.every, r.file_model, warnings),
        }?;
        if let Some(rec) = recorder.as_mut() {
            rec.document("scenario", r.scenario);
        }
        Ok(recorder)
    }

    /// Starts a recording that will be renamed to `path` by [`Recorder::finish`].
    pub fn create(path: &Path, app: &'static str, every: u64, file_model: bool) -> Result<Self, RecordError> {
        let shown = || path.display().to_string();
        if let Some(dir) = path.parent() {
            if !dir.as_os_str().is_empty() {
                std::fs::create_dir_all(dir).map_err(|source| RecordError::Io { path: shown(), source })?;
            }
        }
        crate::output::check_replaceable(path).map_err(|source| RecordError::Output { path: shown(), source })?;
        let partial = crate::output::partial_path(path);
        let rec = rerun::RecordingStreamBuilder::new(app)
            .with_blueprint(blueprint(file_model))
            .save(&partial)
            .map_err(|e| RecordError::Rerun { path: shown(), message: e.to_string() })?;
        Ok(Recorder::new(rec, Target::File { partial, path: path.to_path_buf() }, every))
    }

    fn new(rec: rerun::RecordingStream, target: Target, every: u64) -> Self {
        Recorder {
            rec,
            target,
            every: every.max(1),
            statics_logged: false,
            estimate_named: false,
            columns: Columns::new(),
            extra: Vec::new(),
            pending: 0,
            last_send: std::time::Instant::now(),
            last_tick: 0,
            last_time_s: 0.0,
        }
    }

    /// Streams the same data live to a rerun viewer or server at `url` (rerun's default when
    /// empty). A run never fails or waits because nobody listens: `warnings` says so once.
    pub fn connect(
        url: &str,
        app: &'static str,
        every: u64,
        file_model: bool,
        warnings: &mut Vec<String>,
    ) -> Result<Option<Self>, RecordError> {
        let url = if url.is_empty() { DEFAULT_CONNECT_URL.to_string() } else { url.to_string() };
        // rerun's gRPC sink blocks the logging calls while nobody listens (measured: a run
        // stalled for good): check that a viewer or server answers first.
        if !listening(&url) {
            warnings.push(format!("no rerun viewer or server listens at {url}; the run goes on without streaming"));
            return Ok(None);
        }
        let rec = rerun::RecordingStreamBuilder::new(app)
            .with_blueprint(blueprint(file_model))
            .connect_grpc_opts(url.clone())
            .map_err(|e| RecordError::Rerun { path: url.clone(), message: e.to_string() })?;
        Ok(Some(Recorder::new(rec, Target::Live { url }, every)))
    }

    /// The simulated time of `tick` \[s\]: the last tick seen's, or the start's.
    fn time_of(&self, tick: u64) -> f64 {
        if tick == self.last_tick {
            self.last_time_s
        } else {
            0.0
        }
    }

    /// Stores a text document (static: it belongs to the whole run).
    pub fn document(&mut self, entity: &str, text: &str) {
        let _ = self.rec.log_static(entity, &rerun::TextDocument::new(text));
    }

    /// Buffers one scalar time series value at `tick` (every `record_every`-th tick, like the
    /// rest).
    pub fn scalar(&mut self, tick: u64, entity: &str, value: f64) {
        // Called right after `tick` for the same tick: its time is the last one seen.
        self.scalars_at(tick, self.last_time_s, entity, &[value]);
    }

    /// Buffers the values of an entity's series at `tick` (simulated time `time_s` \[s\]), which
    /// may be earlier than the last one seen (every `record_every`-th tick, like the rest).
    pub fn scalars_at(&mut self, tick: u64, time_s: f64, entity: &str, values: &[f64]) {
        if !tick.is_multiple_of(self.every) {
            return;
        }
        let column = match self.extra.iter().position(|c| c.entity == entity) {
            Some(i) => &mut self.extra[i],
            None => {
                self.extra.push(Column::new(entity, Kind::Scalars));
                self.extra.last_mut().expect("just pushed")
            }
        };
        column.push_values(tick, time_s, values.iter().copied());
    }

    /// Sends every buffered tick.
    fn send(&mut self) {
        for c in self.columns.all().into_iter().chain(self.extra.iter_mut()) {
            c.send(&self.rec);
        }
        self.pending = 0;
        self.last_send = std::time::Instant::now();
    }

    /// Logs what does not change during the run once, as static data: labels, radii, fixed
    /// colours and series names. Every tick then carries only positions, force colours and values.
    fn log_statics(&self, t: &Tick, error_names: &[String]) {
        let s = t.structure;
        let rec = &self.rec;
        let names = |v: Vec<&String>| v.into_iter().cloned().collect::<Vec<_>>();
        let _ = rec.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP());
        let _ = rec.log_static(
            "structure/nodes",
            &rerun::Points3D::update_fields()
                .with_labels(names(s.nodes.iter().map(|n| &n.name).collect()))
                .with_radii([0.02f32]),
        );
        let _ = rec.log_static(
            "structure/struts",
            &rerun::LineStrips3D::update_fields()
                .with_radii(s.members_of(MemberKind::Strut).map(|(_, m)| m.radius_m as f32).collect::<Vec<_>>())
                .with_labels(segment_names(s, MemberKind::Strut)),
        );
        let _ = rec.log_static(
            "structure/springs",
            &rerun::LineStrips3D::update_fields().with_labels(segment_names(s, MemberKind::Spring)),
        );
        let _ = rec.log_static(
            "structure/cables",
            &rerun::LineStrips3D::update_fields().with_labels(segment_names(s, MemberKind::Cable)),
        );
        let _ = rec.log_static(
            "analytic/nodes",
            &rerun::Points3D::update_fields().with_colors([[80u8, 220, 120, 160]]).with_radii([0.015f32]),
        );
        let _ = rec
            .log_static("analytic/struts", &rerun::LineStrips3D::update_fields().with_colors([[80u8, 220, 120, 120]]));
        let series = |entity: &str, names: Vec<String>| {
            if !names.is_empty() {
                let _ = rec.log_static(entity, &rerun::SeriesLines::new().with_names(names));
            }
        };
        series("errors", error_names.to_vec());
        series("errors_log10", error_names.to_vec());
        series("forces/springs", s.members_of(MemberKind::Spring).map(|(_, m)| m.name.clone()).collect());
        series("forces/cables", s.members_of(MemberKind::Cable).map(|(_, m)| m.name.clone()).collect());
        let actuators: Vec<String> =
            s.actuators.iter().enumerate().map(|(i, a)| format!("{} #{}", a.symbol, i + 1)).collect();
        series("forces/actuators", actuators.clone());
        series("inputs", actuators);
        series("residual", vec!["force_n".into(), "torque_nm".into()]);
        series("energy/kinetic_j", vec!["kinetic energy".into()]);
    }

    /// Flushes and moves the recording to its final name (a live stream: waits a moment for
    /// the viewer, and says once in `warnings` if none took the data). The recorder records
    /// nothing after.
    pub fn finish(&mut self, warnings: &mut Vec<String>) -> Result<Option<PathBuf>, RecordError> {
        self.send();
        let rec = std::mem::replace(&mut self.rec, rerun::RecordingStream::disabled());
        match &self.target {
            Target::File { partial, path } => {
                let shown = || path.display().to_string();
                let flushed = rec.flush_blocking();
                drop(rec);
                if let Err(e) = flushed {
                    crate::output::discard(partial);
                    return Err(RecordError::Rerun { path: shown(), message: e.to_string() });
                }
                crate::output::commit(partial, path).map_err(|source| RecordError::Output { path: shown(), source })?;
                Ok(Some(path.clone()))
            }
            Target::Live { url } => {
                if rec.flush_with_timeout(std::time::Duration::from_secs_f64(LIVE_FLUSH_TIMEOUT_S)).is_err() {
                    warnings.push(format!("no rerun viewer took the live stream at {url}; the run went on without it"));
                }
                Ok(None)
            }
        }
    }
}

/// The recording's entity of a frequency check (`frequencies/NAME`) and of the frequencies
/// fitted to a coordinate's trajectory and to its Lagrangian model (`frequencies/trajectory:NAME`).
pub const FREQUENCIES_ENTITY: &str = "frequencies";

impl Recorder {
    /// Each frequency check of a motion `m` (the fit, corrected, against the model's value) and
    /// each frequency fitted to a coordinate's simulated and model trajectory, as two series
    /// [rad/s] drawn over the motion (at its first and last tick), and one event each.
    fn log_frequencies(&mut self, m: &crate::report::MotionReport) {
        let (first, last) = (m.start_tick, m.start_tick + m.steps_taken);
        let first_time_s = self.last_time_s - (self.last_tick.saturating_sub(first)) as f64 * m.dt_s;
        let checks = m.frequencies.iter().map(|f| {
            let event = format!(
                "frequency {}: fit {:.9} rad/s (corrected), model {:.9} rad/s, error {:.3e} (tolerance {:.1e}) {}",
                f.name,
                f.corrected_rad_per_s,
                f.predicted_rad_per_s,
                f.error,
                f.tolerance,
                if f.passed { "pass" } else { "FAIL" }
            );
            (f.name.clone(), ["fit (corrected)", "model"], [f.corrected_rad_per_s, f.predicted_rad_per_s], event)
        });
        let lagrangian = m.lagrangian.iter().flat_map(|l| &l.coordinates).map(|c| {
            let (simulated, model) = (c.simulated_omega_rad_per_s, c.model_omega_rad_per_s);
            let event =
                format!("trajectory {}: fit {simulated:.9} rad/s (corrected), model's fit {model:.9} rad/s", c.name);
            (format!("trajectory:{}", c.name), ["simulated fit (corrected)", "model fit"], [simulated, model], event)
        });
        let all: Vec<_> = checks.chain(lagrangian).collect();
        for (name, names, values, event) in all {
            let entity = format!("{FREQUENCIES_ENTITY}/{name}");
            let _ = self.rec.log_static(entity.as_str(), &rerun::SeriesLines::new().with_names(names));
            let mut column = Column::new(&entity, Kind::Scalars);
            column.push_values(first, first_time_s, values);
            column.push_values(last, self.last_time_s, values);
            column.send(&self.rec);
            self.note(last, &Note::Event(event));
        }
    }
}

/// Errors below this magnitude are drawn at its log10 in `errors_log10` (an error can be exactly 0).
const LOG10_FLOOR: f64 = 1e-20;

/// A run recorded writes its recording (`observers::KINDS`, the last: nothing is written when
/// another observer cannot start); a live viewer nobody runs is a warning, no recording.
pub(super) fn make(setup: &Setup, warnings: &mut Vec<String>) -> Made {
    let Some(r) = &setup.recording else { return Ok(None) };
    Ok(Recorder::start(r, warnings)?.map(|recorder| Box::new(recorder) as Box<dyn Observer>))
}

impl Observer for Recorder {
    fn tick(&mut self, t: &Tick, notes: &mut Vec<Note>) {
        let snap = t.snapshot;
        self.last_tick = snap.tick;
        self.last_time_s = snap.time_s;
        if !snap.tick.is_multiple_of(self.every) {
            return;
        }
        if let Some(estimate) = t.estimate {
            if !self.estimate_named {
                self.estimate_named = true;
                notes.push(Note::SeriesNames(ESTIMATE_SERIES, estimate.keys().cloned().collect()));
            }
            let values = estimate.values().copied().collect();
            notes.push(Note::ScalarsAt { entity: ESTIMATE_SERIES, tick: snap.tick, time_s: snap.time_s, values });
        }
        let s = t.structure;
        let (tick, time) = (snap.tick, snap.time_s);
        let (names, errors): (Vec<&String>, Vec<f64>) = t
            .prediction
            .expected
            .iter()
            .filter_map(|(q, a)| {
                let sv = t.simulated.get(q)?;
                Some((q, if q.starts_with("theta") { wrap_angle(sv - a) } else { sv - a }))
            })
            .unzip();
        if !self.statics_logged {
            self.statics_logged = true;
            self.log_statics(t, &names.into_iter().cloned().collect::<Vec<_>>());
        }
        let c = &mut self.columns;
        let nodes = &snap.nodes;
        c.nodes.push_points(tick, time, nodes.iter().copied());
        let segments = |kind| s.members_of(kind).flat_map(|(_, m)| m.segments());
        c.struts.push_segments(tick, time, nodes, segments(MemberKind::Strut));
        let f = &snap.forces;
        let struts = strut_forces(s, snap);
        let tensions = |kind| s.members_of(kind).map(|(i, _)| f.force_n[i]);
        let max_f = tensions(MemberKind::Spring)
            .chain(tensions(MemberKind::Cable))
            .chain(struts.iter().copied())
            .fold(0.0f64, |m, x| m.max(x.abs()));
        c.struts.colors.extend(struts.iter().map(|x| force_colour(*x, max_f)));
        // Every segment of a member coloured by the member's force.
        for (kind, column) in [(MemberKind::Spring, &mut c.springs), (MemberKind::Cable, &mut c.cables)] {
            if s.members_of(kind).next().is_some() {
                column.push_segments(tick, time, nodes, segments(kind));
                let colours =
                    s.members_of(kind).flat_map(|(i, m)| m.segments().map(move |_| force_colour(f.force_n[i], max_f)));
                column.colors.extend(colours);
            }
        }
        if let Some(ghost) = t.ghost_nodes {
            c.ghost_nodes.push_points(tick, time, ghost.iter().copied());
            c.ghost_struts.push_segments(tick, time, ghost, segments(MemberKind::Strut));
        }
        // Time series: one entity per family, one named series per member or quantity.
        if !errors.is_empty() {
            c.errors_log10.push_values(tick, time, errors.iter().map(|e| e.abs().max(LOG10_FLOOR).log10()));
            c.errors.push_values(tick, time, errors);
        }
        for (column, values) in [
            (&mut c.spring_forces, &tensions(MemberKind::Spring).collect::<Vec<_>>()),
            (&mut c.cable_forces, &tensions(MemberKind::Cable).collect::<Vec<_>>()),
            (&mut c.actuator_forces, &f.actuator_force),
            (&mut c.inputs, &snap.actuator_values),
        ] {
            if !values.is_empty() {
                column.push_values(tick, time, values.iter().copied());
            }
        }
        if let Some(r) = &f.residual {
            c.residual.push_values(tick, time, [r.max_force_n, r.max_torque_nm]);
        }
        c.kinetic_energy.push_values(tick, time, [snap.kinetic_energy_j]);
        self.pending += 1;
        if self.pending >= BLOCK_TICKS || self.last_send.elapsed().as_secs_f64() >= BLOCK_MAX_AGE_S {
            self.send();
        }
    }

    fn records(&self) -> bool {
        true
    }

    /// Buffers an event (every one, whatever `record_every`) at `tick`: the last tick seen, or
    /// the start; or one value of a named series.
    fn note(&mut self, tick: u64, note: &Note) {
        match note {
            Note::Event(text) => {
                let time_s = self.time_of(tick);
                self.columns.events.push_text(tick, time_s, text);
            }
            Note::Scalar(entity, value) => self.scalar(tick, entity, *value),
            Note::ScalarsAt { entity, tick, time_s, values } => self.scalars_at(*tick, *time_s, entity, values),
            Note::SeriesNames(entity, names) => {
                let _ = self.rec.log_static(*entity, &rerun::SeriesLines::new().with_names(names.clone()));
            }
        }
    }

    /// A certified settle point's proof as an event (`run --certify`, `[certify]`), and its
    /// box's radius and the settled state's distance from the equilibrium as series.
    fn settle_point(&mut self, p: &super::SettlePoint, point: &mut crate::report::PointReport, _notes: &mut Vec<Note>) {
        let Some(c) = &point.certificate else { return };
        let tick = p.snapshot.tick;
        self.note(tick, &Note::Event(format!("point {}: {}", point.index, c.summary())));
        if let Some(proof) = &c.proof {
            let time_s = self.time_of(tick);
            self.scalars_at(tick, time_s, "certificate/radius_m", &[proof.radius_m]);
            self.scalars_at(tick, time_s, "certificate/settled_offset_m", &[proof.settled_offset_m]);
        }
    }

    /// Buffers the equilibrium residual of `tick`, computed after the tick was recorded.
    fn residual(&mut self, tick: u64, r: &crate::snapshot::Residual) {
        if !tick.is_multiple_of(self.every) {
            return;
        }
        let time_s = self.last_time_s;
        self.columns.residual.push_values(tick, time_s, [r.max_force_n, r.max_torque_nm]);
    }

    /// Stores the final report, the frequency checks, the verdict as the last event, and
    /// writes the file.
    fn close(&mut self, tick: u64, report: &ScenarioReport, warnings: &mut Vec<String>) -> Result<(), ObserverError> {
        self.document("report", &serde_json::to_string_pretty(report).unwrap_or_default());
        if let Some(m) = &report.motion {
            self.log_frequencies(m);
        }
        self.note(tick, &Note::Event(if report.passed { "run passed" } else { "run FAILED" }.into()));
        self.finish(warnings)?;
        Ok(())
    }
}

/// The viewer layout stored in every recording: the structure in 3D with the analytic ghost
/// (left, over tabs of events and the two documents), and on the right the errors (log10 of
/// their magnitude, and signed), the member forces, and the kinetic energy with the other
/// series in tabs; with a model in the file (`file_model`) its errors (`model/NAME`) are the
/// first tab of the errors, the one the viewer shows. The time cursor follows the end of the
/// recording: the settled state.
pub fn blueprint(file_model: bool) -> rerun::blueprint::Blueprint {
    use rerun::blueprint::components::{PanelState, PlayState};
    use rerun::blueprint::{
        Blueprint, BlueprintPanel, Horizontal, SelectionPanel, Spatial3DView, Tabs, TextDocumentView, TextLogView,
        TimePanel, TimeSeriesView, Vertical,
    };
    let series = |name: &str, entities: &[&str]| TimeSeriesView::new(name).with_contents(entities.iter().copied());
    let structure = Spatial3DView::new("structure (red tension, blue compression, green analytic)")
        .with_contents(["+ /structure/**", "+ /analytic/**"])
        .with_defaults(&rerun::LineStrips3D::update_fields().with_show_labels(false))
        .with_defaults(&rerun::Points3D::update_fields().with_show_labels(false));
    let documents = Tabs::new([
        TextLogView::new("events").with_contents(["/events"]).into(),
        TextDocumentView::new("scenario").with_contents(["/scenario"]).into(),
        TextDocumentView::new("report").with_contents(["/report"]).into(),
    ]);
    let left = Vertical::new([structure.into(), documents.into()]).with_row_shares([0.68, 0.32]);
    let mut error_tabs = vec![
        series("log10 |simulated - analytic|", &["/errors_log10"]).into(),
        series("simulated - analytic", &["/errors"]).into(),
    ];
    if file_model {
        error_tabs.insert(0, series("the file's model: |error| per prediction and equation", &["/model/**"]).into());
        let trajectory = "[energy.trajectory]: each coordinate simulated and its Lagrangian model";
        error_tabs.insert(1, series(trajectory, &["/trajectory/**"]).into());
        error_tabs.insert(2, series("[energy.trajectory]: |simulated - model|", &["/trajectory_error/**"]).into());
    }
    error_tabs.push(series("frequency checks: fit and model [rad/s]", &["/frequencies/**"]).into());
    let errors = Tabs::new(error_tabs);
    let forces = series("member forces [N] (cables: tension)", &["/forces/springs", "/forces/cables"]);
    let others = Tabs::new([
        series("kinetic energy [J]", &["/energy/**"]).into(),
        series("residual (max force N, torque N m)", &["/residual"]).into(),
        series("actuator forces", &["/forces/actuators"]).into(),
        series("inputs", &["/inputs"]).into(),
        series("min clearance [m]", &["/interference/**"]).into(),
    ]);
    let right = Vertical::new([errors.into(), forces.into(), others.into()]);
    Blueprint::new(Horizontal::new([left.into(), right.into()]).with_column_shares([0.55, 0.45]))
        .with_blueprint_panel(BlueprintPanel::from_state(PanelState::Collapsed))
        .with_selection_panel(SelectionPanel::from_state(PanelState::Collapsed))
        .with_time_panel(
            TimePanel::new()
                .with_state(PanelState::Collapsed)
                .with_timeline("tick")
                .with_play_state(PlayState::Following),
        )
}

#[cfg(test)]
mod strut_force_tests {
    use super::strut_forces;
    use crate::snapshot::{MemberForces, Snapshot};
    use crate::structure::{BodyKind, CableLaw, Member, Structure};

    /// The drawn state of `s` with the member forces `force_n` \[N\].
    fn drawn(s: &Structure, force_n: Vec<f64>) -> Snapshot {
        Snapshot {
            tick: 0,
            time_s: 0.0,
            nodes: s.nodes.iter().map(|n| n.position).collect(),
            body_poses: vec![],
            forces: MemberForces { force_n, ..Default::default() },
            actuator_values: vec![],
            kinetic_energy_j: 0.0,
        }
    }

    /// A strut from A (0, 0, 0) to B (1, 0, 0) with a cable of 10 N from A to C (-1, 1, 0):
    /// the cable pulls A away from B with 10 / sqrt(2) N along the strut, a compression.
    #[test]
    fn a_cable_pulling_a_struts_end_outwards_compresses_it() {
        let mut s = Structure::default();
        let bar = s.add_body("bar", BodyKind::Free, None);
        let ground = s.add_body("ground", BodyKind::Fixed, None);
        let (a, b) = (s.add_node("A", bar, [0.0; 3]), s.add_node("B", bar, [1.0, 0.0, 0.0]));
        let c = s.add_node("C", ground, [-1.0, 1.0, 0.0]);
        s.members.push(Member::strut("AB", a, b, 0.01));
        s.members.push(Member::cable("AC", vec![a, c], CableLaw::Inextensible, 1.0, 0.001));
        let f = strut_forces(&s, &drawn(&s, vec![0.0, 10.0]))[0];
        assert!((f + 10.0 / 2f64.sqrt()).abs() <= 1e-12, "{f}");
    }

    /// A clustered cable from C through A to D is drawn as its two segments, each labelled by
    /// the cable, and both pull at A: with 10 N along A-C and A-D (D at (-1, -1, 0)) the strut
    /// is compressed by 2 x 10 / sqrt(2) N.
    #[test]
    fn every_segment_of_a_clustered_cable_is_drawn_and_pulls() {
        let mut s = Structure::default();
        let bar = s.add_body("bar", BodyKind::Free, None);
        let ground = s.add_body("ground", BodyKind::Fixed, None);
        let (a, b) = (s.add_node("A", bar, [0.0; 3]), s.add_node("B", bar, [1.0, 0.0, 0.0]));
        let (c, d) = (s.add_node("C", ground, [-1.0, 1.0, 0.0]), s.add_node("D", ground, [-1.0, -1.0, 0.0]));
        s.members.push(Member::strut("AB", a, b, 0.01));
        let law = CableLaw::Elastic { stiffness_n_per_m: 100.0 };
        s.members.push(Member::cable("CAD", vec![c, a, d], law, 2.0, 0.001));
        assert_eq!(super::segment_names(&s, crate::structure::MemberKind::Cable), ["CAD", "CAD"]);
        let f = strut_forces(&s, &drawn(&s, vec![0.0, 10.0]))[0];
        assert!((f + 2.0 * 10.0 / 2f64.sqrt()).abs() <= 1e-12, "{f}");
    }
}
