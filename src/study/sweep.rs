//! Sweeps: every point of a scenario's grid settled by the dynamics, in parallel, to a CSV and
//! a summary; sharded for job arrays, and merged back.
//!
//! The grid is cut into fixed blocks of `BLOCK_POINTS` consecutive points. Within a block each
//! point starts from its neighbour's equilibrium (continuation, as the scenario says); blocks
//! run in parallel on `--jobs` threads. The blocks do not depend on the number of jobs, so
//! `--jobs 1` and `--jobs 2` give bit-identical rows. A shard `K/N` takes every N-th point from
//! the K-th (interleaved slices); its continuation path differs from the unsharded one, so its
//! numbers agree with it within the scenario's tolerances, not bit for bit.

use crate::mechanisms::Values;
use crate::report::{PointReport, ReportedError, WorkspaceAgreement};
use crate::run::{run, RunError, RunOptions};
use crate::scenario::{Actuation, Scenario};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::AtomicBool;

/// Points settled one after the other (continuation) in one parallel task.
pub const BLOCK_POINTS: usize = 8;

/// Why a sweep, or a merge of its shards, gave no result.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A grid or shard CSV the sweep cannot take (its message).
    #[error("{0}")]
    BadInput(String),
    /// The pool of `jobs` threads could not be started.
    #[error("cannot start {jobs} threads: {source}")]
    Threads { jobs: usize, source: rayon::ThreadPoolBuildError },
}

/// One settled grid point, in the order of the full grid.
#[derive(Clone, Debug)]
pub struct Row {
    pub index: usize,
    /// Points in the whole grid (so that `merge` can tell a missing shard).
    pub grid_points: usize,
    pub point: PointReport,
}

#[derive(Clone, Debug, Serialize)]
pub struct SweepSummary {
    pub scenario: String,
    pub mechanism: String,
    pub points: usize,
    pub settled: usize,
    /// Points where every check is within tolerance.
    pub within_tolerance: usize,
    pub shard: Option<String>,
    pub jobs: usize,
    pub wall_s: f64,
    pub workspace: Option<WorkspaceAgreement>,
    /// The scenario's `[workspace] min_agreement_percent`: a workspace sweep passes on the
    /// agreement instead of on every point (as `run` judges it).
    pub min_agreement_percent: Option<f64>,
    /// Points that did not settle, had a check out of tolerance or lost the prestress (where
    /// `[prestress] on_loss` fails).
    pub disagreements: Vec<usize>,
    /// Errors of the blocks that stopped early (divergence, interruption).
    pub errors: Vec<ReportedError>,
    /// The sweep's verdict, with `run`'s pass policy: no block stopped early, and either the
    /// workspace agreement reaches `min_agreement_percent` or every point settled within
    /// tolerance (points outside the model's validity aside).
    pub passed: bool,
}

/// A `--shard` that is not `K/N` with 1 <= K <= N.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// No `/`.
    #[error("--shard must be K/N, got '{0}'")]
    NotKOfN(String),
    /// K is not a whole number.
    #[error("bad K in '{0}'")]
    BadK(String),
    /// N is not a whole number.
    #[error("bad N in '{0}'")]
    BadN(String),
    /// K or N out of range.
    #[error("--shard K/N needs 1 <= K <= N, got {k}/{n}")]
    OutOfRange { k: usize, n: usize },
}

/// Parses `K/N` (1 <= K <= N).
pub fn parse_shard(s: &str) -> Result<(usize, usize), ShardError> {
    let (k, n) = s.split_once('/').ok_or_else(|| ShardError::NotKOfN(s.to_string()))?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| ShardError::BadK(s.to_string()))?,
        n.trim().parse().map_err(|_| ShardError::BadN(s.to_string()))?,
    );
    if n == 0 || k == 0 || k > n {
        return Err(ShardError::OutOfRange { k, n });
    }
    Ok((k, n))
}

/// Runs the sweep. `progress` is called after each block with (points done, points total).
pub fn sweep(
    sc: &Scenario,
    jobs: usize,
    shard: Option<(usize, usize)>,
    cancel: Option<&AtomicBool>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Vec<Row>, SweepSummary), SweepError> {
    let start = std::time::Instant::now();
    let (rows, errors) = if sc.topologies.is_empty() {
        let grid_points = sc.actuation.all_inputs().len();
        sweep_points(sc, (0, grid_points), jobs, shard, cancel, progress)?
    } else {
        sweep_topologies(sc, jobs, shard, cancel, progress)?
    };
    let summary = summarise(sc, &rows, errors, shard, jobs, start.elapsed().as_secs_f64());
    Ok((rows, summary))
}

/// The points of one structure, the first numbered `offset` in a grid of `grid_points` (a
/// shard takes every N-th point of the whole grid): blocks settled in parallel.
fn sweep_points(
    sc: &Scenario,
    (offset, grid_points): (usize, usize),
    jobs: usize,
    shard: Option<(usize, usize)>,
    cancel: Option<&AtomicBool>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Vec<Row>, Vec<ReportedError>), SweepError> {
    let (points, continuation) = match &sc.actuation {
        Actuation::Points { points, continuation } => (points.clone(), *continuation),
        Actuation::Schedule { .. } => {
            return Err(SweepError::BadInput(format!(
                "{}: a sweep needs a grid or points, not waypoints",
                sc.file.display()
            )))
        }
    };
    let indexed: Vec<(usize, Values)> =
        points.into_iter().enumerate().map(|(i, p)| (offset + i, p)).filter(|(i, _)| in_shard(shard, *i)).collect();
    let blocks: Vec<&[(usize, Values)]> = indexed.chunks(BLOCK_POINTS).collect();
    let total = indexed.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let pool = pool(jobs)?;
    // What every block's run shares, without the grid's points and the file's text (cloned
    // once here, not once per block: a million points had made a signal take 29 s to stop).
    let mut template = sc.clone();
    template.actuation = Actuation::Points { points: Vec::new(), continuation };
    template.skipped_points.clear();
    template.source.clear();
    template.record = None;
    let cancelled = || cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::SeqCst));
    let settle_block = |block: &&[(usize, Values)]| {
        if cancelled() {
            return (Vec::new(), None);
        }
        let r = settle_block(&template, block, continuation, grid_points, cancel);
        let n = done.fetch_add(block.len(), std::sync::atomic::Ordering::SeqCst) + block.len();
        progress(n, total);
        r
    };
    let results: Vec<(Vec<Row>, Option<ReportedError>)> =
        pool.install(|| blocks.par_iter().map(settle_block).collect());
    let mut rows = Vec::new();
    let mut errors = Vec::new();
    for (r, e) in results {
        rows.extend(r);
        errors.extend(e);
    }
    rows.sort_by_key(|r| r.index);
    Ok((rows, errors))
}

/// Whether the point of grid index `i` is in `shard` K/N (every N-th point from the K-th; every
/// point without a shard).
fn in_shard(shard: Option<(usize, usize)>, i: usize) -> bool {
    shard.is_none_or(|(k, n)| i % n == k - 1)
}

/// A pool of `jobs` threads (at least one).
fn pool(jobs: usize) -> Result<rayon::ThreadPool, SweepError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|source| SweepError::Threads { jobs, source })
}

/// A sweep over a topology parameter, or a motion over several points: each part's points
/// swept with its own structure, the parts in parallel on `jobs` threads (each part's points
/// on one), the rows numbered in the whole grid's order; the rows and the errors, each error
/// saying which part it stopped.
fn sweep_topologies(
    sc: &Scenario,
    jobs: usize,
    shard: Option<(usize, usize)>,
    cancel: Option<&AtomicBool>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Vec<Row>, Vec<ReportedError>), SweepError> {
    let grid_points = sc.actuation.all_inputs().len();
    let mut offsets = Vec::with_capacity(sc.topologies.len());
    let mut offset = 0;
    for variant in &sc.topologies {
        offsets.push(offset);
        offset += variant.actuation.all_inputs().len();
    }
    let total = (0..grid_points).filter(|&i| in_shard(shard, i)).count();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let quiet = |_: usize, _: usize| {};
    let each = |(variant, &offset): (&Scenario, &usize)| {
        let swept = sweep_points(variant, (offset, grid_points), 1, shard, cancel, &quiet);
        let n = variant.actuation.all_inputs().len();
        let part = (offset..offset + n).filter(|&i| in_shard(shard, i)).count();
        progress(done.fetch_add(part, std::sync::atomic::Ordering::SeqCst) + part, total);
        swept.map(|(rows, errors)| (rows, errors, crate::run::rebuilt(sc, variant)))
    };
    let parts: Vec<Result<_, SweepError>> =
        pool(jobs)?.install(|| sc.topologies.par_iter().zip(&offsets).map(each).collect());
    let (mut rows, mut errors) = (Vec::new(), Vec::new());
    for part in parts {
        let (part_rows, part_errors, note) = part?;
        errors.extend(part_errors.into_iter().map(|source| RunError::Topology { note: note.clone(), source }.into()));
        rows.extend(part_rows);
    }
    rows.sort_by_key(|r| r.index);
    Ok((rows, errors))
}

/// One block of points settled as one run (with continuation where the scenario asks): its
/// rows, each with its index in the whole grid, and the run's error if it stopped.
fn settle_block(
    template: &Scenario,
    block: &[(usize, Values)],
    continuation: bool,
    grid_points: usize,
    cancel: Option<&AtomicBool>,
) -> (Vec<Row>, Option<ReportedError>) {
    let mut sub = template.clone();
    sub.actuation = Actuation::Points { points: block.iter().map(|(_, v)| v.clone()).collect(), continuation };
    let r = run(&sub, &RunOptions { cancel, skip_findings: true, ..RunOptions::default() });
    let rows = r
        .points
        .into_iter()
        .zip(block.iter())
        .map(|(mut p, (i, _))| {
            p.index = *i;
            Row { index: *i, grid_points, point: p }
        })
        .collect();
    (rows, r.error)
}

/// The sweep's summary of its rows (in grid order) and the blocks' errors, and its verdict.
fn summarise(
    sc: &Scenario,
    rows: &[Row],
    errors: Vec<ReportedError>,
    shard: Option<(usize, usize)>,
    jobs: usize,
    wall_s: f64,
) -> SweepSummary {
    let reports: Vec<PointReport> = rows.iter().map(|r| r.point.clone()).collect();
    let mut summary = SweepSummary {
        scenario: sc.name.clone(),
        mechanism: sc.mechanism.clone(),
        points: rows.len(),
        settled: rows.iter().filter(|r| r.point.settled).count(),
        within_tolerance: rows.iter().filter(|r| r.point.within_tolerance).count(),
        shard: shard.map(|(k, n)| format!("{k}/{n}")),
        jobs: jobs.max(1),
        wall_s,
        workspace: WorkspaceAgreement::from_points(&reports),
        min_agreement_percent: sc.min_agreement_percent,
        disagreements: rows
            .iter()
            .filter(|r| {
                !r.point.settled
                    || (r.point.prestress_lost == Some(true)
                        && sc.prestress.as_ref().is_some_and(|p| p.on_loss == crate::settings::OnLoss::Fail))
                    || (!r.point.within_tolerance && r.point.expected_slack.as_ref().is_none_or(|e| e.is_empty()))
            })
            .map(|r| r.index)
            .collect(),
        errors,
        passed: false,
    };
    summary.passed = summary.errors.is_empty()
        && match (summary.min_agreement_percent, &summary.workspace) {
            (Some(min), Some(w)) => w.agreement_percent >= min,
            _ => summary.disagreements.is_empty() && summary.settled == summary.points,
        };
    summary
}

/// Formats a number so that it reads back bit for bit.
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// The parts of a sweep's identity, in the order [`fingerprint`] writes them.
const FINGERPRINT_PARTS: [&str; 3] = ["scenario (its text and settings)", "parameters", "grid"];

/// What makes a sweep the one it is, as three 64-bit FNV-1a hashes `scenario/parameters/grid`
/// in hex: the file's text with its settings, every parameter's value, every grid point. Each
/// CSV row carries it (column `sweep`), so that `merge` refuses shards of different sweeps and
/// names the part that differs.
pub fn fingerprint(sc: &Scenario) -> String {
    let mut scenario = Fnv::default();
    scenario.write(sc.source.as_bytes());
    scenario.write(format!("{:?}{:?}{}", sc.sim, sc.settle, sc.mechanism).as_bytes());
    let mut params = Fnv::default();
    for (k, v) in &sc.params {
        params.write(k.as_bytes());
        params.write(&v.to_bits().to_le_bytes());
    }
    let mut grid = Fnv::default();
    for p in sc.actuation.all_inputs() {
        for (k, v) in p {
            grid.write(k.as_bytes());
            grid.write(&v.to_bits().to_le_bytes());
        }
    }
    format!("{:016x}/{:016x}/{:016x}", scenario.0, params.0, grid.0)
}

/// The 64-bit FNV-1a hash (stable across Rust versions and machines, unlike the standard
/// library's hasher).
struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    fn write(&mut self, bytes: &[u8]) {
        const PRIME: u64 = 0x0100_0000_01b3;
        for b in bytes {
            self.0 = (self.0 ^ u64::from(*b)).wrapping_mul(PRIME);
        }
    }
}

/// The CSV of a sweep: one row per point, the full grid's index and size first, the sweep's
/// [`fingerprint`] last. `is_angle` names the quantities whose error is wrapped into (-pi, pi].
pub fn to_csv(rows: &[Row], is_angle: &dyn Fn(&str) -> bool, sweep: &str) -> String {
    let mut inputs: Vec<String> = Vec::new();
    let mut quantities: Vec<String> = Vec::new();
    for r in rows {
        for k in r.point.inputs.keys() {
            if !inputs.contains(k) {
                inputs.push(k.clone());
            }
        }
        for k in r.point.analytic.keys().chain(r.point.simulated.keys()) {
            if !quantities.contains(k) {
                quantities.push(k.clone());
            }
        }
    }
    quantities.sort();
    let energy = EnergyColumns::of(rows);
    let frequencies = FrequencyColumns::of(rows);
    let mut header = vec!["index".to_string(), "grid_points".to_string()];
    header.extend(inputs.iter().cloned());
    for q in &quantities {
        header.push(format!("analytic_{q}"));
        header.push(format!("simulated_{q}"));
        header.push(format!("error_{q}"));
    }
    header.extend(energy.header());
    header.extend(frequencies.header());
    let certified = rows.iter().any(|r| r.point.certificate.is_some());
    if certified {
        header.extend(CERTIFICATE_COLUMNS.map(String::from));
    }
    header.extend(POINT_COLUMNS.map(String::from));
    let mut out = header.join(",");
    out.push('\n');
    let opt = |x: Option<f64>| x.map(num).unwrap_or_default();
    for r in rows {
        let p = &r.point;
        let mut cells = vec![r.index.to_string(), r.grid_points.to_string()];
        cells.extend(inputs.iter().map(|k| opt(p.inputs.get(k).copied())));
        for q in &quantities {
            let (a, s) = (p.analytic.get(q).copied(), p.simulated.get(q).copied());
            cells.push(opt(a));
            cells.push(opt(s));
            let error = |(a, s): (f64, f64)| if is_angle(q) { crate::mechanisms::wrap_angle(s - a) } else { s - a };
            cells.push(opt(a.zip(s).map(error)));
        }
        cells.extend(energy.cells(p));
        cells.extend(frequencies.cells(p));
        if certified {
            cells.extend(certificate_cells(p));
        }
        cells.extend(point_cells(p, sweep));
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// The last columns of every row: the point's settle and judgement, and the sweep's
/// fingerprint.
const POINT_COLUMNS: [&str; 11] = [
    "settled",
    "steps",
    "within_tolerance",
    "stable",
    "branch",
    "slack_cables",
    "expected_slack",
    "prestress_fraction",
    "prestress_lost",
    "min_clearance_m",
    "sweep",
];

/// A point's cells under [`POINT_COLUMNS`].
fn point_cells(p: &PointReport, sweep: &str) -> Vec<String> {
    let opt = |x: Option<f64>| x.map(num).unwrap_or_default();
    vec![
        p.settled.to_string(),
        p.steps.to_string(),
        p.within_tolerance.to_string(),
        p.stable.map(|b| b.to_string()).unwrap_or_default(),
        format!("\"{}\"", p.branch.replace('"', "'")),
        p.slack_cables.join(";"),
        p.expected_slack.as_ref().map(|e| e.join(";")).unwrap_or_default(),
        opt(p.prestress_fraction),
        p.prestress_lost.map(|b| b.to_string()).unwrap_or_default(),
        opt(p.min_clearance_m),
        sweep.to_string(),
    ]
}

/// The columns of a certified sweep (`[certify]`, `--certify`): the largest box proven to
/// hold exactly one equilibrium (scaled radius, m), the settled state's distance from that
/// equilibrium (m), the stability proven there (`stable`, `unstable`, `unproven`, or
/// `not proven` without a proof), the lower bound on the smallest eigenvalue (N/m) or the
/// unstable index.
const CERTIFICATE_COLUMNS: [&str; 5] = [
    "certified_radius_m",
    "certified_offset_m",
    "certified_stability",
    "certified_smallest_eigenvalue_n_per_m",
    "certified_index",
];

/// A point's cells under [`CERTIFICATE_COLUMNS`].
fn certificate_cells(p: &PointReport) -> Vec<String> {
    use crate::certify::Stability;
    let Some(proof) = p.certificate.as_ref().and_then(|c| c.proof.as_ref()) else {
        let said = if p.certificate.is_some() { "not proven" } else { "" };
        return vec![String::new(), String::new(), said.to_string(), String::new(), String::new()];
    };
    let (kind, bound, index) = match &proof.stability {
        Stability::Stable { smallest_eigenvalue_at_least_n_per_m: s } => ("stable", num(*s), String::new()),
        Stability::Unstable { index } => ("unstable", String::new(), index.to_string()),
        Stability::Unproven { .. } => ("unproven", String::new(), String::new()),
    };
    vec![num(proof.radius_m), num(proof.settled_offset_m), kind.to_string(), bound, index]
}

/// The columns of the `[energy]` model's stationary points: the one landed on
/// (`equilibrium_COORD`, `equilibrium_energy`, `equilibrium_eigenvalue_K`, `equilibrium_kind`,
/// `equilibrium_index`), then every one found (`stationary_I_...`, I from 0, as many as the
/// point with the most), each with its coordinates, energy, Hessian eigenvalues (ascending,
/// K from 1) and kind.
struct EnergyColumns {
    coordinates: Vec<String>,
    /// Hessian eigenvalues per stationary point (the number of coordinates).
    eigenvalues: usize,
    /// Stationary points of the point with the most.
    stationary: usize,
}

impl EnergyColumns {
    fn of(rows: &[Row]) -> Self {
        let reports = || rows.iter().filter_map(|r| r.point.energy.as_ref());
        let coordinates: Vec<String> =
            reports().next().map(|e| e.measured.keys().cloned().collect()).unwrap_or_default();
        let stationary = reports().map(|e| e.stationary.len()).max().unwrap_or(0);
        EnergyColumns { eigenvalues: coordinates.len(), coordinates, stationary }
    }

    /// The names of one stationary point's columns, after `prefix`.
    fn point_header(&self, prefix: &str) -> Vec<String> {
        let mut h: Vec<String> = self.coordinates.iter().map(|c| format!("{prefix}_{c}")).collect();
        h.push(format!("{prefix}_energy"));
        h.extend((1..=self.eigenvalues).map(|k| format!("{prefix}_eigenvalue_{k}")));
        h.push(format!("{prefix}_kind"));
        h
    }

    fn header(&self) -> Vec<String> {
        if self.coordinates.is_empty() {
            return Vec::new();
        }
        let mut h = self.point_header("equilibrium");
        h.push("equilibrium_index".into());
        for i in 0..self.stationary {
            h.extend(self.point_header(&format!("stationary_{i}")));
        }
        h
    }

    /// One stationary point's cells (empty where there is none).
    fn point_cells(&self, s: Option<&crate::report::StationaryReport>) -> Vec<String> {
        let opt = |x: Option<f64>| x.map(num).unwrap_or_default();
        let mut c: Vec<String> =
            self.coordinates.iter().map(|k| opt(s.and_then(|s| s.coordinates.get(k).copied()))).collect();
        c.push(opt(s.map(|s| s.energy)));
        c.extend((0..self.eigenvalues).map(|k| opt(s.and_then(|s| s.eigenvalues.get(k).copied()))));
        c.push(s.map(|s| s.kind.clone()).unwrap_or_default());
        c
    }

    fn cells(&self, p: &PointReport) -> Vec<String> {
        if self.coordinates.is_empty() {
            return Vec::new();
        }
        let e = p.energy.as_ref();
        let landed = e.and_then(|e| e.landed);
        let mut c = self.point_cells(e.zip(landed).and_then(|(e, i)| e.stationary.get(i)));
        c.push(landed.map(|i| i.to_string()).unwrap_or_default());
        for i in 0..self.stationary {
            c.extend(self.point_cells(e.and_then(|e| e.stationary.get(i))));
        }
        c
    }
}

/// The columns of the natural frequencies at each point: each `[[motion.frequencies]]` entry
/// measured from the motion started there (`frequency_NAME_predicted`, `_measured`,
/// `_corrected`, `_error`, and where a mode's modal analysis is judged beside a formula
/// `_modal`, `_modal_error`; rad/s and relative), then the `[energy]` model's linearised
/// frequencies (`model_omega_K`, K from 1, ascending) [rad/s].
struct FrequencyColumns {
    names: Vec<String>,
    modal: Vec<bool>,
    model_modes: usize,
}

impl FrequencyColumns {
    fn of(rows: &[Row]) -> Self {
        let mut names: Vec<String> = Vec::new();
        let mut modal: Vec<bool> = Vec::new();
        for f in rows.iter().flat_map(|r| &r.point.frequencies) {
            match names.iter().position(|n| *n == f.name) {
                Some(i) => modal[i] |= f.modal_rad_per_s.is_some(),
                None => {
                    names.push(f.name.clone());
                    modal.push(f.modal_rad_per_s.is_some());
                }
            }
        }
        let model_modes = rows
            .iter()
            .filter_map(|r| r.point.energy.as_ref().and_then(|e| e.modes.as_ref()).map(Vec::len))
            .max()
            .unwrap_or(0);
        FrequencyColumns { names, modal, model_modes }
    }

    fn header(&self) -> Vec<String> {
        let mut h = Vec::new();
        for (name, modal) in self.names.iter().zip(&self.modal) {
            for part in ["predicted", "measured", "corrected", "error", "error_bar", "amplitude_shift"] {
                h.push(format!("frequency_{name}_{part}"));
            }
            if *modal {
                h.push(format!("frequency_{name}_modal"));
                h.push(format!("frequency_{name}_modal_error"));
            }
        }
        h.extend((1..=self.model_modes).map(|k| format!("model_omega_{k}")));
        h
    }

    fn cells(&self, p: &PointReport) -> Vec<String> {
        let opt = |x: Option<f64>| x.map(num).unwrap_or_default();
        let mut c = Vec::new();
        for (name, modal) in self.names.iter().zip(&self.modal) {
            let f = p.frequencies.iter().find(|f| f.name == *name);
            c.push(opt(f.map(|f| f.predicted_rad_per_s)));
            c.push(opt(f.map(|f| f.measured_rad_per_s)));
            c.push(opt(f.map(|f| f.corrected_rad_per_s)));
            c.push(opt(f.map(|f| f.error)));
            c.push(opt(f.and_then(|f| f.error_bar)));
            c.push(opt(f.and_then(|f| f.amplitude_shift)));
            if *modal {
                c.push(opt(f.and_then(|f| f.modal_rad_per_s)));
                c.push(opt(f.and_then(|f| f.modal_error)));
            }
        }
        let modes = p.energy.as_ref().and_then(|e| e.modes.as_ref());
        c.extend((0..self.model_modes).map(|k| opt(modes.and_then(|m| m.get(k)).map(|m| m.omega_rad_per_s))));
        c
    }
}

/// Joins shard CSVs (same header) into one, rows ordered by grid index; a point present twice
/// is an error, and so is a point missing from the grid (a shard left out) unless `partial`,
/// and a row of another sweep (its `sweep` fingerprint differs: the part that differs is named).
pub fn merge_csv(texts: &[(String, String)], partial: bool) -> Result<String, SweepError> {
    let bad = |m: String| SweepError::BadInput(m);
    let mut header: Option<&str> = None;
    let mut rows: Vec<(usize, &str)> = Vec::new();
    let mut grid_points: Option<usize> = None;
    let mut sweep: Option<(&str, &str)> = None;
    for (name, text) in texts {
        let mut lines = text.lines();
        let h = lines.next().ok_or_else(|| bad(format!("{name}: empty CSV")))?;
        if !h.starts_with("index,grid_points,") || !h.ends_with(",sweep") {
            return Err(bad(format!("{name}:1:1: expected a sweep CSV (index,grid_points,...,sweep)")));
        }
        match header {
            None => header = Some(h),
            Some(first) if first != h => return Err(bad(format!("{name}: its header differs from the first file's"))),
            _ => {}
        }
        for (k, line) in lines.enumerate().filter(|(_, l)| !l.is_empty()) {
            let at = format!("{name}:{}", k + 2);
            let id = line.rsplit(',').next().unwrap_or_default();
            let (first_id, first_file) = *sweep.get_or_insert((id, name));
            if id != first_id {
                return Err(bad(format!(
                    "{at}: a row of another sweep than {first_file}'s: {}",
                    differing(first_id, id)
                )));
            }
            let mut cells = line.split(',');
            let mut number = |col: usize| {
                cells
                    .next()
                    .and_then(|s| s.parse::<usize>().ok())
                    .ok_or_else(|| bad(format!("{at}:{col}: expected a whole number")))
            };
            let (idx, n) = (number(1)?, number(2)?);
            if *grid_points.get_or_insert(n) != n || idx >= n {
                return Err(bad(format!("{at}: point {idx} of a {n}-point grid does not fit the other files' grid")));
            }
            rows.push((idx, line));
        }
    }
    rows.sort_by_key(|(i, _)| *i);
    if let Some(w) = rows.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(bad(format!("grid point {} appears in more than one file", w[0].0)));
    }
    let total = grid_points.unwrap_or(0);
    if !partial && rows.len() != total {
        let present: std::collections::BTreeSet<usize> = rows.iter().map(|(i, _)| *i).collect();
        let missing: Vec<String> =
            (0..total).filter(|i| !present.contains(i)).take(10).map(|i| i.to_string()).collect();
        return Err(bad(format!(
            "{} of the grid's {total} points are missing (first: {}): a shard left out? (--partial merges what is there)",
            total - rows.len(),
            missing.join(", ")
        )));
    }
    let mut out = String::from(header.unwrap_or("index"));
    out.push('\n');
    for (_, l) in rows {
        out.push_str(l);
        out.push('\n');
    }
    Ok(out)
}

/// Which parts of two sweep fingerprints differ, in words.
fn differing(a: &str, b: &str) -> String {
    let parts: Vec<&str> = a
        .split('/')
        .zip(b.split('/'))
        .zip(FINGERPRINT_PARTS)
        .filter(|((x, y), _)| x != y)
        .map(|(_, what)| what)
        .collect();
    if parts.is_empty() {
        format!("its fingerprint {b} is not {a}")
    } else {
        format!("its {} differ", parts.join(" and "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An angle simulated at pi against an analytic -pi (the same angle) has error 0 in the
    /// CSV, not -2 pi; a length's error is the plain difference.
    #[test]
    fn csv_angle_errors_are_wrapped_and_length_errors_are_not() {
        let pi = std::f64::consts::PI;
        let point = PointReport {
            analytic: Values::from([("theta2".into(), -pi), ("x".into(), 1.0)]),
            simulated: Values::from([("theta2".into(), pi), ("x".into(), 1.25)]),
            ..PointReport::default()
        };
        let csv = to_csv(&[Row { index: 0, grid_points: 1, point }], &|q| q == "theta2", "0/0/0");
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let row: Vec<&str> = lines.next().unwrap().split(',').collect();
        let cell = |name: &str| row[header.iter().position(|h| *h == name).unwrap()].parse::<f64>().unwrap();
        assert!(cell("error_theta2").abs() <= 1e-15, "{}", cell("error_theta2"));
        assert_eq!(cell("error_x"), 0.25);
        assert_eq!(&header[..2], &["index", "grid_points"]);
    }
}
