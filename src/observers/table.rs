//! Every tick as one row of a table at full f64 precision, readable by pandas, polars or any
//! spreadsheet without the rerun SDK (whose recordings store positions as f32): CSV, or an Arrow
//! IPC file when the name ends in `.arrow`, `.feather` or `.ipc` (`tick` a UInt64 column, every
//! other column Float64, nulls where the CSV leaves a cell empty; written in record batches of
//! [`ARROW_BATCH_ROWS`] rows), or the same record batches kept in memory ([`MemoryTable`]: the
//! Python package hands them to pyarrow without a file).
//!
//! Columns, fixed at the first tick: `tick`, `time_s`, `kinetic_energy_j`, the inputs
//! (`input:SYMBOL`), every node's coordinates (`node:NAME.x`, `.y`, `.z`, m), every spring's
//! force and every cable's tension (`spring:NAME.force_n`, `cable:NAME.tension_n`), every
//! actuator's force (`actuator:SYMBOL@JOINT_OR_CABLE.force`, N or N m), and the mechanism's quantities,
//! simulated (`sim:QUANTITY`, but for the node coordinates and member forces the columns above
//! hold) and analytic (`analytic:QUANTITY`, empty where the model has no value), then `path_accelerated` (1 when the step to the tick took a settle accelerator, 0 on
//! a physical path), `motion_time_s` (a motion run's time since its start, the model's `t`;
//! empty elsewhere), every revolute joint's angle and prismatic joint's slide
//! (`joint:NAME.angle` rad, `joint:NAME.slide` m) and the file's model: each quantity
//! (`model:NAME`), each prediction's predicted value and error (`predicted:NAME`,
//! `error:NAME`), each equation's residual (`equation:NAME`); in a motion run with
//! `[energy.trajectory]`, per `[energy]` coordinate its simulated value (angles unwrapped,
//! continuous through +-pi), the Lagrangian model's value and the error in the coordinate's
//! class (`trajectory_sim:NAME`, `trajectory_model:NAME`, `trajectory_error:NAME`; the model's
//! two empty where it is not compared: before the motion, and at the samples it starts from).
//! A row waits until its model value is known (started from the samples, ticks 1 and 2 of the
//! motion wait for tick 3). Numbers are written in Rust's shortest round-trip form, so reading them back gives
//! the same f64 bit for bit. The file is written to a temporary file (`output::partial_path`) and renamed when the run
//! is over.

use super::file_model::ModelObserver;
use super::{Made, Observer, ObserverError, Setup, Tick};
use crate::report::ScenarioReport;
use crate::structure::{ActuatorTarget, MemberKind};
use arrow_array::{ArrayRef, Float64Array, RecordBatch, UInt64Array};
use arrow_schema::{DataType, Field, Schema, SchemaRef};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Rows buffered before an Arrow record batch is written.
pub const ARROW_BATCH_ROWS: usize = 8192;

/// The file endings that select the Arrow IPC format.
const ARROW_ENDINGS: &[&str] = &["arrow", "feather", "ipc"];

/// Whether `path` names a table file: `.csv`, or one of `ARROW_ENDINGS`.
pub fn is_table_file(path: &std::path::Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e == "csv" || ARROW_ENDINGS.contains(&e))
}

/// Where a run's table goes: a file (CSV or Arrow IPC, by its ending) or memory.
#[derive(Clone)]
pub enum TableTarget {
    File(PathBuf),
    Memory(MemoryTable),
}

impl From<PathBuf> for TableTarget {
    fn from(path: PathBuf) -> Self {
        TableTarget::File(path)
    }
}

/// A table kept in memory: the run's record batches and their schema, handed over when the
/// run closes (None before, and when no tick ran).
#[derive(Clone, Default)]
pub struct MemoryTable(Arc<Mutex<Option<Batched>>>);

/// A run's table: its schema and its record batches.
pub type Batched = (SchemaRef, Vec<RecordBatch>);

impl MemoryTable {
    /// The schema and the record batches of the finished run (once; None when no tick ran).
    pub fn take(&self) -> Option<Batched> {
        self.0.lock().ok().and_then(|mut t| t.take())
    }
}

/// Input, simulated and analytic keys, fixed at the first tick.
type Keys = (Vec<String>, Vec<String>, Vec<String>);

/// Where the record batches go.
enum Batches {
    /// The file until the first tick gives the schema, then its writer.
    File { file: Option<std::fs::File>, writer: Option<arrow_ipc::writer::FileWriter<std::fs::File>> },
    /// Kept, then handed to the [`MemoryTable`] when the run closes.
    Memory { kept: Vec<RecordBatch>, to: MemoryTable },
}

/// Where the rows go.
enum Sink {
    Csv(std::io::BufWriter<std::fs::File>),
    /// Record batches; the schema from the first tick, and the rows not yet made a batch
    /// (tick, then every other column).
    Arrow {
        out: Box<Batches>,
        schema: Option<SchemaRef>,
        ticks: Vec<u64>,
        columns: Vec<Vec<Option<f64>>>,
    },
}

/// Why the table could not be written.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// The output was refused or its directory could not be made.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// The file could not be made or written.
    #[error("cannot write the table {}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    /// The Arrow IPC writer failed.
    #[error("cannot write the table {}: {source}", path.display())]
    Arrow { path: PathBuf, source: arrow_schema::ArrowError },
    /// The file was handed to its writer already.
    #[error("cannot write the table {}: the file is gone", path.display())]
    Gone { path: PathBuf },
}

pub struct Table {
    /// The file, or "(memory)" for a table kept in memory (for messages).
    path: PathBuf,
    /// The temporary file written until the run closes (None in memory).
    partial: Option<PathBuf>,
    sink: Sink,
    keys: Option<Keys>,
    /// The first write error, reported when the run closes.
    error: Option<TableError>,
    /// The file's model, evaluated for its columns (quantities, predictions, errors).
    model: Option<super::file_model::ModelObserver>,
    /// Whether each joint coordinate gets a column of the motion's own error estimate
    /// (`estimate:joint:NAME.angle`: a motion judged extrapolated over the time step).
    estimates: bool,
    /// The column names, until the first row is written.
    header: Option<Vec<String>>,
    /// With the comparison with the Lagrangian model: the rows not written yet (tick, values),
    /// the first `waiting` of them (from the back) still without the comparison's columns.
    held: std::collections::VecDeque<(u64, Vec<Option<f64>>)>,
    waiting: usize,
}

/// Every joint with one coordinate: its index and column (`joint:NAME.angle` \[rad\] for a
/// revolute, `joint:NAME.slide` \[m\] for a prismatic).
pub fn coordinates(s: &crate::structure::Structure) -> impl Iterator<Item = (usize, String)> + '_ {
    s.joints.iter().enumerate().filter_map(|(j, joint)| match joint.kind {
        crate::structure::JointKind::Revolute { .. } => Some((j, format!("joint:{}.angle", joint.name))),
        crate::structure::JointKind::Prismatic { .. } => Some((j, format!("joint:{}.slide", joint.name))),
        _ => None,
    })
}

/// The columns of a state that carry an error estimate beside the mechanism's quantities in a
/// motion judged extrapolated (`run/levels.rs`): every joint coordinate and every node's
/// position, named as their columns.
pub fn estimated_columns(
    s: &crate::structure::Structure,
    snap: &crate::snapshot::Snapshot,
) -> crate::mechanisms::Values {
    let joints = coordinates(s).filter_map(|(j, name)| snap.joint_coordinate(s, j).map(|q| (name, q)));
    let nodes =
        s.nodes.iter().zip(&snap.nodes).flat_map(|(n, p)| {
            ["x", "y", "z"].into_iter().zip(p).map(move |(c, x)| (format!("node:{}.{c}", n.name), *x))
        });
    joints.chain(nodes).collect()
}

/// The names of [`estimated_columns`], in their order.
fn estimated_names(s: &crate::structure::Structure) -> impl Iterator<Item = String> + '_ {
    let nodes = s.nodes.iter().flat_map(|n| ["x", "y", "z"].map(|c| format!("node:{}.{c}", n.name)));
    coordinates(s).map(|(_, name)| name).chain(nodes)
}

/// A CSV field: quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl Table {
    /// With a column of the motion's own error estimate per joint coordinate.
    pub fn with_estimates(self, estimates: bool) -> Self {
        Table { estimates, ..self }
    }

    /// Starts the table at `path` (its directory is made if needed); Arrow IPC for the endings
    /// in `ARROW_ENDINGS`, CSV otherwise.
    /// `model`: the file's model, whose quantities, predictions and errors get columns.
    pub fn start(path: &Path, model: Option<super::file_model::ModelObserver>) -> Result<Self, TableError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            crate::output::create_dir(dir)?;
        }
        crate::output::check_replaceable(path)?;
        let partial = crate::output::partial_path(path);
        let file = std::fs::File::create(&partial).map_err(|source| {
            crate::output::discard(&partial);
            TableError::Io { path: path.to_path_buf(), source }
        })?;
        let arrow = path.extension().and_then(|e| e.to_str()).is_some_and(|e| ARROW_ENDINGS.contains(&e));
        let sink = if arrow {
            Self::arrow(Batches::File { file: Some(file), writer: None })
        } else {
            Sink::Csv(std::io::BufWriter::new(file))
        };
        Ok(Table::new(path.to_path_buf(), Some(partial), sink, model))
    }

    fn new(
        path: PathBuf,
        partial: Option<PathBuf>,
        sink: Sink,
        model: Option<super::file_model::ModelObserver>,
    ) -> Self {
        let (header, held, waiting) = (None, std::collections::VecDeque::new(), 0);
        Table { path, partial, sink, keys: None, error: None, model, estimates: false, header, held, waiting }
    }

    /// Starts a table kept in memory, handed to `to` when the run closes.
    pub fn in_memory(to: MemoryTable, model: Option<super::file_model::ModelObserver>) -> Self {
        let sink = Self::arrow(Batches::Memory { kept: Vec::new(), to });
        Table::new(PathBuf::from("(memory)"), None, sink, model)
    }

    fn arrow(out: Batches) -> Sink {
        Sink::Arrow { out: Box::new(out), schema: None, ticks: Vec::new(), columns: Vec::new() }
    }

    /// The column names after `tick`.
    fn columns(&self, t: &Tick, keys: &Keys) -> Vec<String> {
        let s = t.structure;
        let mut cols: Vec<String> = vec!["time_s".into(), "kinetic_energy_j".into()];
        cols.extend(keys.0.iter().map(|k| format!("input:{k}")));
        for n in &s.nodes {
            cols.extend(["x", "y", "z"].map(|c| format!("node:{}.{c}", n.name)));
        }
        // Elastic struts' axial forces (tension positive), then springs' and cables'.
        cols.extend(s.members_with_law().map(|(_, m)| match m.kind() {
            MemberKind::Strut => format!("strut:{}.force_n", m.name),
            MemberKind::Spring => format!("spring:{}.force_n", m.name),
            MemberKind::Cable => format!("cable:{}.tension_n", m.name),
        }));
        // A clustered cable's segments, and where it has friction whether each inner node slips.
        for (_, m) in s.members_of(MemberKind::Cable).filter(|(_, m)| m.is_clustered()) {
            cols.extend((1..m.path.len()).map(|k| format!("cable:{}.segment_{k}.tension_n", m.name)));
            cols.extend((1..=m.friction.len()).map(|k| format!("cable:{}.slip_{k}", m.name)));
        }
        // Several actuators may share a symbol (mohr2011's cable pairs): named by what they drive.
        cols.extend(s.actuators.iter().map(|a| {
            let target = match a.target {
                ActuatorTarget::Joint(j) => &s.joints[j].name,
                ActuatorTarget::CableLength(c) => &s.members[c].name,
                ActuatorTarget::FixedNode { node, .. } => &s.nodes[node].name,
            };
            format!("actuator:{}@{target}.force", a.symbol)
        }));
        cols.extend(keys.1.iter().map(|k| format!("sim:{k}")));
        cols.extend(keys.2.iter().map(|k| format!("analytic:{k}")));
        cols.extend(["path_accelerated".to_string(), "motion_time_s".to_string()]);
        cols.extend(coordinates(s).map(|(_, name)| name));
        if self.estimates {
            cols.extend(estimated_names(s).map(|name| format!("estimate:{name}")));
        }
        cols.extend(self.model.iter().flat_map(|m| m.table_columns()));
        cols.extend(self.model.iter().flat_map(|m| m.trajectory_columns()));
        cols
    }

    /// The values of one tick, in the order of [`Table::columns`] (None: no value there).
    fn values(&self, t: &Tick, keys: &Keys) -> Vec<Option<f64>> {
        let snap = t.snapshot;
        let mut v = vec![Some(snap.time_s), Some(snap.kinetic_energy_j)];
        v.extend(keys.0.iter().map(|k| t.inputs.get(k).copied()));
        v.extend(snap.nodes.iter().flatten().map(|x| Some(*x)));
        let f = &snap.forces;
        let s = t.structure;
        let tensions = s.members_with_law().map(|(i, _)| f.force_n[i]);
        v.extend(tensions.map(Some));
        for (i, _) in s.members_of(MemberKind::Cable).filter(|(_, m)| m.is_clustered()) {
            v.extend(f.segment_force_n[i].iter().map(|x| Some(*x)));
            v.extend(f.at_friction_bound[i].iter().map(|slips| Some(f64::from(u8::from(*slips)))));
        }
        v.extend(f.actuator_force.iter().map(|x| Some(*x)));
        v.extend(keys.1.iter().map(|k| t.simulated.get(k).copied()));
        v.extend(keys.2.iter().map(|k| t.prediction.expected.get(k).copied()));
        v.push(Some(if t.accelerated { 1.0 } else { 0.0 }));
        v.push(t.motion_time_s);
        v.extend(coordinates(t.structure).map(|(j, _)| snap.joint_coordinate(t.structure, j)));
        if self.estimates {
            v.extend(estimated_names(t.structure).map(|name| t.estimate.and_then(|e| e.get(&name)).copied()));
        }
        v.extend(self.model.iter().flat_map(|m| m.table_values(t)));
        v
    }

    /// Writes one tick (with the column names before the first).
    fn write(&mut self, tick: u64, values: Vec<Option<f64>>) -> Result<(), TableError> {
        let header = self.header.take();
        let io = |source| TableError::Io { path: self.path.clone(), source };
        let arrow = |source| TableError::Arrow { path: self.path.clone(), source };
        match &mut self.sink {
            Sink::Csv(out) => {
                let mut text = String::new();
                if let Some(h) = header {
                    let names: Vec<String> = std::iter::once("tick".to_string()).chain(h).map(|c| field(&c)).collect();
                    text.push_str(&names.join(","));
                    text.push('\n');
                }
                let _ = write!(text, "{tick}");
                for x in values {
                    text.push(',');
                    if let Some(x) = x {
                        let _ = write!(text, "{x:?}");
                    }
                }
                text.push('\n');
                out.write_all(text.as_bytes()).map_err(io)
            }
            Sink::Arrow { out, schema, ticks, columns } => {
                if let Some(h) = header {
                    let mut fields = vec![Field::new("tick", DataType::UInt64, false)];
                    fields.extend(h.iter().map(|c| Field::new(c, DataType::Float64, true)));
                    let s = Arc::new(Schema::new(fields));
                    if let Batches::File { file, writer } = &mut **out {
                        let f = file.take().ok_or_else(|| TableError::Gone { path: self.path.clone() })?;
                        *writer = Some(arrow_ipc::writer::FileWriter::try_new(f, &s).map_err(arrow)?);
                    }
                    *schema = Some(s);
                    *columns = vec![Vec::with_capacity(ARROW_BATCH_ROWS); h.len()];
                }
                ticks.push(tick);
                for (c, x) in columns.iter_mut().zip(values) {
                    c.push(x);
                }
                if ticks.len() >= ARROW_BATCH_ROWS {
                    Self::flush_batch(out, schema, ticks, columns).map_err(arrow)?;
                }
                Ok(())
            }
        }
    }

    /// Writes (or keeps) the buffered rows as one record batch.
    fn flush_batch(
        out: &mut Batches,
        schema: &Option<SchemaRef>,
        ticks: &mut Vec<u64>,
        columns: &mut [Vec<Option<f64>>],
    ) -> Result<(), arrow_schema::ArrowError> {
        let Some(schema) = schema else { return Ok(()) };
        if ticks.is_empty() {
            return Ok(());
        }
        let mut arrays: Vec<ArrayRef> = vec![Arc::new(UInt64Array::from(std::mem::take(ticks)))];
        arrays.extend(columns.iter_mut().map(|c| Arc::new(Float64Array::from(std::mem::take(c))) as ArrayRef));
        let batch = RecordBatch::try_new(schema.clone(), arrays)?;
        match out {
            Batches::File { writer: Some(w), .. } => w.write(&batch),
            Batches::File { writer: None, .. } => Ok(()),
            Batches::Memory { kept, .. } => {
                kept.push(batch);
                Ok(())
            }
        }
    }

    /// Finishes the file (the last batch and the Arrow footer, or the CSV buffer) and syncs it.
    fn finish_file(&mut self) -> Result<(), TableError> {
        let io = |source| TableError::Io { path: self.path.clone(), source };
        let arrow = |source| TableError::Arrow { path: self.path.clone(), source };
        match &mut self.sink {
            Sink::Csv(out) => out.flush().and_then(|_| out.get_ref().sync_all()).map_err(io),
            Sink::Arrow { out, schema, ticks, columns } => {
                Self::flush_batch(out, schema, ticks, columns).map_err(arrow)?;
                match &mut **out {
                    Batches::File { writer, file } => match (writer.take(), file.take()) {
                        (Some(mut w), _) => {
                            w.finish().map_err(arrow)?;
                            w.into_inner().and_then(|f| f.sync_all().map_err(Into::into)).map_err(arrow)
                        }
                        (None, Some(f)) => f.sync_all().map_err(io),
                        (None, None) => Ok(()),
                    },
                    Batches::Memory { kept, to } => {
                        if let (Some(s), Ok(mut handed)) = (schema.clone(), to.0.lock()) {
                            *handed = Some((s, std::mem::take(kept)));
                        }
                        Ok(())
                    }
                }
            }
        }
    }
}

/// Whether a simulated quantity is a node coordinate or a spring's or cable's force, which
/// the `node:`, `spring:` and `cable:` columns already hold (a `sim:` column would repeat it).
fn repeats_a_column(s: &crate::structure::Structure, key: &str) -> bool {
    let Some((name, what)) = key.rsplit_once('.') else { return false };
    match what {
        "x" | "y" | "z" => s.nodes.iter().any(|n| n.name == name),
        "force" => s.members.iter().any(|m| !m.is_rigid_strut() && m.name == name),
        _ => false,
    }
}

impl Table {
    /// The rows of the comparison with the Lagrangian model known at a tick (`rows`) complete
    /// the rows waiting for them, in order; then the complete rows at the front are written.
    fn complete(&mut self, rows: Vec<super::lagrangian::Row>) -> Result<(), TableError> {
        for row in &rows {
            let at = self.held.len() - self.waiting;
            self.held[at].1.extend(super::file_model::ModelObserver::trajectory_cells(row));
            self.waiting -= 1;
        }
        while self.held.len() > self.waiting {
            let (tick, values) = self.held.pop_front().expect("a complete row");
            self.write(tick, values)?;
        }
        Ok(())
    }

    /// Writes the rows still held at the end, the comparison's columns empty where it never
    /// reached them.
    fn flush_held(&mut self) -> Result<(), TableError> {
        let rows = self.model.as_mut().map_or(vec![], |m| m.trajectory_flush());
        self.complete(rows)?;
        let width = self.model.as_ref().map_or(0, |m| m.trajectory_columns().len());
        while let Some((tick, mut values)) = self.held.pop_front() {
            values.resize(values.len() + width, None);
            self.write(tick, values)?;
        }
        self.waiting = 0;
        Ok(())
    }

    /// One tick's row: written, or held until the comparison with the Lagrangian model reaches it.
    fn row(&mut self, t: &Tick) -> Result<(), TableError> {
        let mut values = self.values(t, self.keys.as_ref().expect("set at the first tick"));
        let Some(model) = self.model.as_mut().filter(|m| m.has_trajectory()) else {
            return self.write(t.snapshot.tick, values);
        };
        if t.motion_time_s.is_none() {
            // After a motion (none follows one today) its rows are complete first.
            let rest = if self.waiting > 0 { model.trajectory_flush() } else { vec![] };
            values.resize(values.len() + model.trajectory_columns().len(), None);
            self.complete(rest)?;
            self.held.push_back((t.snapshot.tick, values));
            return self.complete(vec![]);
        }
        let rows = model.trajectory_tick(t);
        self.held.push_back((t.snapshot.tick, values));
        self.waiting += 1;
        self.complete(rows)
    }
}

/// A run asked for a per-tick table writes one (`observers::KINDS`), with the motion's own
/// error estimates where the motion is judged extrapolated.
pub(super) fn make(setup: &Setup, _warnings: &mut Vec<String>) -> Made {
    let Some(target) = &setup.table else { return Ok(None) };
    let extrapolated = setup.motion.is_some_and(|m| m.extrapolated());
    let model = setup.model.map(|spec| ModelObserver::new(spec, setup.structure, false, setup.motion));
    Ok(Some(Box::new(match target {
        TableTarget::File(path) => Table::start(path, model)?.with_estimates(extrapolated),
        TableTarget::Memory(to) => Table::in_memory(to.clone(), model).with_estimates(extrapolated),
    })))
}

impl Observer for Table {
    fn tick(&mut self, t: &Tick, _notes: &mut Vec<super::Note>) {
        if self.error.is_some() {
            return;
        }
        if self.keys.is_none() {
            let keys: Keys = (
                t.inputs.keys().cloned().collect(),
                t.simulated.keys().filter(|k| !repeats_a_column(t.structure, k)).cloned().collect(),
                t.prediction.expected.keys().cloned().collect(),
            );
            self.header = Some(self.columns(t, &keys));
            self.keys = Some(keys);
        }
        if let Err(e) = self.row(t) {
            self.error = Some(e);
        }
    }

    fn motion_start(&mut self, start: &super::MotionStarted) {
        if let Some(model) = self.model.as_mut() {
            model.motion_start(start);
        }
    }

    fn motion_start_state(&mut self, equilibrium: &Tick, start: &Tick) {
        if let Some(m) = self.model.as_mut() {
            m.motion_start_state(equilibrium, start);
        }
    }

    fn close(&mut self, _tick: u64, _report: &ScenarioReport, warnings: &mut Vec<String>) -> Result<(), ObserverError> {
        if let (None, Some(partial)) = (&self.keys, &self.partial) {
            // No tick ran (a run that diverged at its first step): no table, and an earlier
            // one at the path is left as it was, never replaced by an empty file.
            crate::output::discard(partial);
            warnings.push(format!("no tick ran: the table {} was not written", self.path.display()));
            return Ok(());
        }
        let written = match self.error.take() {
            Some(e) => Err(e),
            None => self.flush_held().and_then(|_| self.finish_file()),
        };
        let Some(partial) = &self.partial else { return Ok(written?) };
        match written {
            Ok(()) => Ok(crate::output::commit(partial, &self.path).map_err(TableError::Output)?),
            Err(e) => {
                crate::output::discard(partial);
                Err(e.into())
            }
        }
    }
}
