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
use crate::report::{PointReport, WorkspaceAgreement};
use crate::run::{run, RunOptions};
use crate::scenario::{Actuation, Scenario};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::AtomicBool;

/// Points settled one after the other (continuation) in one parallel task.
pub const BLOCK_POINTS: usize = 8;

#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("{0}")]
    BadInput(String),
    #[error("{0}")]
    Io(String),
}

/// One settled grid point, in the order of the full grid.
#[derive(Clone, Debug)]
pub struct Row {
    pub index: usize,
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
    /// Points that did not settle or had a check out of tolerance.
    pub disagreements: Vec<usize>,
    /// Errors of the blocks that stopped early (divergence, interruption).
    pub errors: Vec<String>,
}

/// Parses `K/N` (1 <= K <= N).
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s.split_once('/').ok_or_else(|| format!("--shard must be K/N, got '{s}'"))?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| format!("bad K in '{s}'"))?,
        n.trim().parse().map_err(|_| format!("bad N in '{s}'"))?,
    );
    if n == 0 || k == 0 || k > n {
        return Err(format!("--shard K/N needs 1 <= K <= N, got {k}/{n}"));
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
        points.into_iter().enumerate().filter(|(i, _)| shard.is_none_or(|(k, n)| i % n == k - 1)).collect();
    let blocks: Vec<&[(usize, Values)]> = indexed.chunks(BLOCK_POINTS).collect();
    let total = indexed.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let start = std::time::Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|e| SweepError::Io(format!("cannot start {jobs} threads: {e}")))?;
    let results: Vec<(Vec<Row>, Option<String>)> = pool.install(|| {
        blocks
            .par_iter()
            .map(|block| {
                let mut sub = sc.clone();
                sub.actuation =
                    Actuation::Points { points: block.iter().map(|(_, v)| v.clone()).collect(), continuation };
                sub.record = None;
                let r = run(&sub, &RunOptions { cancel, skip_findings: true, ..RunOptions::default() });
                let rows = r
                    .points
                    .into_iter()
                    .zip(block.iter())
                    .map(|(mut p, (i, _))| {
                        p.index = *i;
                        Row { index: *i, point: p }
                    })
                    .collect();
                let n = done.fetch_add(block.len(), std::sync::atomic::Ordering::SeqCst) + block.len();
                progress(n, total);
                (rows, r.error)
            })
            .collect()
    });
    let mut rows = Vec::new();
    let mut errors = Vec::new();
    for (r, e) in results {
        rows.extend(r);
        errors.extend(e);
    }
    rows.sort_by_key(|r| r.index);
    let reports: Vec<PointReport> = rows.iter().map(|r| r.point.clone()).collect();
    let summary = SweepSummary {
        scenario: sc.name.clone(),
        mechanism: sc.mechanism.clone(),
        points: rows.len(),
        settled: rows.iter().filter(|r| r.point.settled).count(),
        within_tolerance: rows.iter().filter(|r| r.point.within_tolerance).count(),
        shard: shard.map(|(k, n)| format!("{k}/{n}")),
        jobs: jobs.max(1),
        wall_s: start.elapsed().as_secs_f64(),
        workspace: WorkspaceAgreement::from_points(&reports),
        disagreements: rows
            .iter()
            .filter(|r| {
                !r.point.settled
                    || (!r.point.within_tolerance && r.point.expected_slack.as_ref().is_none_or(|e| e.is_empty()))
            })
            .map(|r| r.index)
            .collect(),
        errors,
    };
    Ok((rows, summary))
}

/// Formats a number so that it reads back bit for bit.
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// The CSV of a sweep: one row per point, the full grid's index first.
pub fn to_csv(rows: &[Row]) -> String {
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
    let mut header = vec!["index".to_string()];
    header.extend(inputs.iter().cloned());
    for q in &quantities {
        header.push(format!("analytic_{q}"));
        header.push(format!("simulated_{q}"));
        header.push(format!("error_{q}"));
    }
    header.extend(
        [
            "settled",
            "steps",
            "within_tolerance",
            "stable",
            "branch",
            "slack_cables",
            "expected_slack",
            "min_clearance_m",
        ]
        .map(String::from),
    );
    let mut out = header.join(",");
    out.push('\n');
    let opt = |x: Option<f64>| x.map(num).unwrap_or_default();
    for r in rows {
        let p = &r.point;
        let mut cells = vec![r.index.to_string()];
        cells.extend(inputs.iter().map(|k| opt(p.inputs.get(k).copied())));
        for q in &quantities {
            let (a, s) = (p.analytic.get(q).copied(), p.simulated.get(q).copied());
            cells.push(opt(a));
            cells.push(opt(s));
            cells.push(opt(a.zip(s).map(|(a, s)| s - a)));
        }
        cells.push(p.settled.to_string());
        cells.push(p.steps.to_string());
        cells.push(p.within_tolerance.to_string());
        cells.push(p.stable.map(|b| b.to_string()).unwrap_or_default());
        cells.push(format!("\"{}\"", p.branch.replace('"', "'")));
        cells.push(p.slack_cables.join(";"));
        cells.push(p.expected_slack.as_ref().map(|e| e.join(";")).unwrap_or_default());
        cells.push(opt(p.min_clearance_m));
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// Joins shard CSVs (same header) into one, rows ordered by grid index; a point present twice
/// is an error.
pub fn merge_csv(texts: &[(String, String)]) -> Result<String, SweepError> {
    let mut header: Option<&str> = None;
    let mut rows: Vec<(usize, &str)> = Vec::new();
    for (name, text) in texts {
        let mut lines = text.lines();
        let h = lines.next().ok_or_else(|| SweepError::BadInput(format!("{name}: empty CSV")))?;
        match header {
            None => header = Some(h),
            Some(first) if first != h => {
                return Err(SweepError::BadInput(format!("{name}: its header differs from the first file's")))
            }
            _ => {}
        }
        for (k, line) in lines.enumerate() {
            if line.is_empty() {
                continue;
            }
            let idx = line.split(',').next().and_then(|s| s.parse::<usize>().ok()).ok_or_else(|| {
                SweepError::BadInput(format!("{name}:{}:1: expected a grid index in the first column", k + 2))
            })?;
            rows.push((idx, line));
        }
    }
    rows.sort_by_key(|(i, _)| *i);
    if let Some(w) = rows.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(SweepError::BadInput(format!("grid point {} appears in more than one file", w[0].0)));
    }
    let mut out = String::from(header.unwrap_or("index"));
    out.push('\n');
    for (_, l) in rows {
        out.push_str(l);
        out.push('\n');
    }
    Ok(out)
}
