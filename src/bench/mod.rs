//! `tensegrity bench`: how fast and how accurately the testbed settles a fixed case set.
//!
//! The case set of a mechanism is a scenario's settle points, each settled from a fresh build
//! (no continuation, no stability test): the same work a peer simulator would do per case.
//! Several rounds are run and medians reported, so that one noisy round does not decide.

pub mod scale;
pub mod table;

use crate::run::{run, RunOptions};
use crate::scenario::{self, Actuation};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Why a bench could not run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A case set or scale family that a bench cannot run: its scenario, model or structure.
    #[error("{0}")]
    Case(String),
    /// The peer simulator could not be run, or answered outside its protocol.
    #[error("{0}")]
    Peer(String),
    /// A file the bench writes for its peer.
    #[error("cannot write {}: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },
    /// An output refused or not written (`output`).
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// A case's scenario is not valid.
    #[error(transparent)]
    Scenario(#[from] scenario::ScenarioError),
    /// The scale bench's tower has no design.
    #[error(transparent)]
    Tower(#[from] scale::tower::TowerError),
    /// A case's model gave no result.
    #[error(transparent)]
    Model(#[from] crate::mechanisms::ModelError),
    /// The simulation could not be built, or diverged.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
}

/// A write error at `path`.
pub(crate) fn write_error(path: &Path) -> impl FnOnce(std::io::Error) -> BenchError + '_ {
    move |source| BenchError::Write { path: path.to_path_buf(), source }
}

/// Writes `text` to `path` whole or not at all (`output::write_atomic`).
pub(crate) fn write_whole(path: &Path, text: &str) -> Result<(), BenchError> {
    Ok(crate::output::write_atomic(path, text.as_bytes())?)
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchResult {
    pub mechanism: String,
    pub scenario: String,
    pub cases: usize,
    pub rounds: usize,
    /// Median over rounds of cases settled per wall-clock second.
    pub median_cases_per_s: f64,
    /// Median over cases of the steps needed to settle.
    pub median_steps_per_case: f64,
    /// Median over rounds of the wall time per step \[us\].
    pub median_us_per_step: f64,
    /// Median and largest normalised error over cases and checked quantities.
    pub median_error: f64,
    pub max_error: f64,
    pub all_settled: bool,
}

/// The built-in case sets: (mechanism, scenario file).
pub const CASE_SETS: &[(&str, &str)] =
    &[("ji2014", "scenarios/ji2014/grid.toml"), ("mohr2011", "scenarios/mohr2011/static_workspace.toml")];

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        return f64::NAN;
    }
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The case set's scenario as the bench runs it: every point built afresh (no continuation),
/// no stability test, no stiffness probe, no recording, no interference checks (the peer's
/// tendons cannot collide, so it does none: the rates compare the same work; the checks' own
/// cost is the bench's interference table and BENCHMARKS.md's).
pub fn bench_scenario(file: &Path) -> Result<scenario::Scenario, BenchError> {
    let mut sc = scenario::load(file)?;
    sc.stability_perturbation = None;
    sc.probe = None;
    sc.record = None;
    sc.interference.enabled = false;
    if let Actuation::Points { continuation, .. } = &mut sc.actuation {
        *continuation = false;
    }
    Ok(sc)
}

/// What one round over a case set measured.
#[derive(Clone, Debug, Default)]
struct Round {
    cases: usize,
    cases_per_s: f64,
    us_per_step: f64,
    /// Steps of each case.
    steps: Vec<f64>,
    /// Normalised error of every checked quantity of every case.
    errors: Vec<f64>,
    all_settled: bool,
}

/// A testbed round times passes over the case set until they add up to this wall time [s]: one
/// pass over ji2014's 110 cases takes about 10 ms, and single passes varied by 1.4x within a
/// run (8.2k to 11.7k cases/s), more than the peer's rounds.
const MIN_ROUND_WALL_S: f64 = 0.2;

/// Passes over the case set, after an untimed one: the peer too goes over every case untimed
/// first (its start-state check) in the process that then times them, so both sides are timed
/// warm (the testbed's cold pass, right after a peer round, measured up to 1.5x slower). The
/// rates are over all timed passes; steps and errors from the first (every pass settles the
/// same cases the same way).
fn testbed_round(mechanism: &str, sc: &scenario::Scenario) -> Round {
    let opts = RunOptions { skip_findings: true, ..Default::default() };
    let _warm_up = run(sc, &opts);
    let r = run(sc, &opts);
    let (mut cases, mut wall_s, mut steps) = (r.points.len(), r.settle.wall_s, r.settle.steps);
    while wall_s < MIN_ROUND_WALL_S {
        let again = run(sc, &opts);
        cases += again.points.len();
        wall_s += again.settle.wall_s;
        steps += again.settle.steps;
    }
    let scale = crate::mechanisms::find(mechanism).map_or(1.0, |m| m.length_scale(&r.params));
    let mut round = Round {
        cases: r.points.len(),
        cases_per_s: cases as f64 / wall_s,
        us_per_step: wall_s * 1e6 / steps.max(1) as f64,
        all_settled: r.settle.settled,
        ..Default::default()
    };
    for p in &r.points {
        round.steps.push(p.steps as f64);
        for c in &sc.checks {
            if let (Some(a), Some(s)) = (p.analytic.get(&c.quantity), p.simulated.get(&c.quantity)) {
                round.errors.push(crate::observers::compare::error(c.kind, *a, *s, scale).1);
            }
        }
    }
    round
}

/// Medians over rounds of the rates; steps and errors of the first round (every round settles
/// the same cases the same way).
fn summarize(mechanism: &str, scenario: &str, mut rounds: Vec<Round>) -> BenchResult {
    let mut rates: Vec<f64> = rounds.iter().map(|r| r.cases_per_s).collect();
    let mut us: Vec<f64> = rounds.iter().map(|r| r.us_per_step).collect();
    let all_settled = rounds.iter().all(|r| r.all_settled);
    let first = rounds.swap_remove(0);
    let (mut steps, mut errors) = (first.steps, first.errors);
    BenchResult {
        mechanism: mechanism.into(),
        scenario: scenario.into(),
        cases: first.cases,
        rounds: rates.len(),
        median_cases_per_s: median(&mut rates),
        median_steps_per_case: median(&mut steps),
        median_us_per_step: median(&mut us),
        median_error: median(&mut errors),
        max_error: errors.iter().copied().fold(0.0, f64::max),
        all_settled,
    }
}

/// Runs one case set `rounds` times.
pub fn bench_case_set(mechanism: &str, file: &Path, rounds: usize) -> Result<BenchResult, BenchError> {
    let sc = bench_scenario(file)?;
    let rounds = (0..rounds.max(1)).map(|_| testbed_round(mechanism, &sc)).collect();
    Ok(summarize(mechanism, &file.display().to_string(), rounds))
}

/// The testbed and a peer simulator on the same case set, measured in the same run.
#[derive(Clone, Debug, Serialize)]
pub struct PeerComparison {
    pub mechanism: String,
    pub testbed: BenchResult,
    pub peer: BenchResult,
    /// The peer's own description (simulator, version, variant).
    pub peer_name: String,
    /// Testbed / peer: above 1 the testbed settles more cases per second.
    pub ratio_cases_per_s: f64,
    /// Testbed / peer: below 1 the testbed needs fewer steps per case.
    pub ratio_steps_per_case: f64,
    /// Testbed / peer: below 1 a testbed step costs less.
    pub ratio_us_per_step: f64,
    /// Testbed / peer: below 1 the testbed is more accurate.
    pub ratio_median_error: f64,
    pub ratio_max_error: f64,
}

/// Runs the peer `command` with `file` and `extra` arguments appended; returns the one JSON
/// object it must print (the peers' protocol, `benches/peers/mujoco/README.md`).
pub(crate) fn run_peer(command: &[String], file: &Path, extra: &[&str]) -> Result<serde_json::Value, BenchError> {
    let (program, args) = command.split_first().ok_or_else(|| BenchError::Peer("empty peer command".into()))?;
    let out = std::process::Command::new(program)
        .args(args)
        .arg(file)
        .args(extra)
        .output()
        .map_err(|e| BenchError::Peer(format!("cannot run the peer '{}': {e}", command.join(" "))))?;
    if !out.status.success() {
        return Err(BenchError::Peer(format!(
            "the peer '{}' failed ({}): {}",
            command.join(" "),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    serde_json::from_slice(&out.stdout)
        .map_err(|e| BenchError::Peer(format!("the peer '{}' printed no JSON object: {e}", command.join(" "))))
}

/// One round of a peer simulator: `command` is run with the case-set file, `--rounds 1` and
/// `--min-round-wall-s` (the testbed's [`MIN_ROUND_WALL_S`]) appended and must print one JSON
/// object (see `benches/peers/mujoco/README.md`).
fn peer_round(command: &[String], cases_file: &Path) -> Result<(Round, String), BenchError> {
    let protocol = |what: &str| BenchError::Peer(format!("the peer's JSON has no {what}"));
    let min_wall = MIN_ROUND_WALL_S.to_string();
    let v = run_peer(command, cases_file, &["--rounds", "1", "--min-round-wall-s", &min_wall])?;
    let num =
        |key: &str| v.get(key).and_then(serde_json::Value::as_f64).ok_or_else(|| protocol(&format!("number '{key}'")));
    let cases = v.get("cases").and_then(|c| c.as_array()).ok_or_else(|| protocol("'cases' list"))?;
    let mut round = Round {
        cases: cases.len(),
        cases_per_s: num("median_cases_per_s")?,
        us_per_step: num("median_us_per_step")?,
        all_settled: true,
        ..Default::default()
    };
    for c in cases {
        round.steps.push(c.get("steps").and_then(|s| s.as_f64()).ok_or_else(|| protocol("'steps' in a case"))?);
        round.all_settled &= c.get("settled").and_then(|s| s.as_bool()).unwrap_or(false);
        if let Some(errs) = c.get("errors").and_then(|e| e.as_object()) {
            round.errors.extend(errs.values().filter_map(|e| e.as_f64()));
        }
    }
    let name = ["simulator", "mujoco_version", "variant"]
        .iter()
        .filter_map(|k| v.get(*k).map(|x| format!("{k} {}", x.as_str().map_or_else(|| x.to_string(), str::to_string))))
        .collect::<Vec<_>>()
        .join(", ");
    Ok((round, name))
}

/// Runs the case set through the testbed and through the peer, alternating, `rounds` times
/// each, so that both see the same machine load. The case set is written to `dir` first.
pub fn bench_against_peer(
    mechanism: &str,
    file: &Path,
    rounds: usize,
    peer: &[String],
    dir: &Path,
) -> Result<PeerComparison, BenchError> {
    let sc = bench_scenario(file)?;
    let set = peer_case_set(mechanism, &sc)?;
    let cases_file = dir.join(format!("{mechanism}.json"));
    std::fs::create_dir_all(dir).map_err(write_error(dir))?;
    write_whole(&cases_file, &serde_json::to_string_pretty(&set).expect("case set serialises"))?;
    let mut ours = Vec::new();
    let mut theirs = Vec::new();
    let mut peer_name = String::new();
    for _ in 0..rounds.max(1) {
        ours.push(testbed_round(mechanism, &sc));
        let (round, name) = peer_round(peer, &cases_file)?;
        if round.cases != set.cases.len() {
            return Err(BenchError::Peer(format!("the peer settled {} cases of {}", round.cases, set.cases.len())));
        }
        theirs.push(round);
        peer_name = name;
    }
    let testbed = summarize(mechanism, &file.display().to_string(), ours);
    let peer = summarize(mechanism, &peer.join(" "), theirs);
    Ok(PeerComparison {
        mechanism: mechanism.into(),
        ratio_cases_per_s: testbed.median_cases_per_s / peer.median_cases_per_s,
        ratio_steps_per_case: testbed.median_steps_per_case / peer.median_steps_per_case,
        ratio_us_per_step: testbed.median_us_per_step / peer.median_us_per_step,
        ratio_median_error: testbed.median_error / peer.median_error,
        ratio_max_error: testbed.max_error / peer.max_error,
        testbed,
        peer,
        peer_name,
    })
}

/// Time per tick of the interference observer's measurement for `n` struts.
#[derive(Clone, Debug, Serialize)]
pub struct InterferenceBench {
    pub struts: usize,
    /// Pairs measured in the narrow phase (within the margin) per tick.
    pub pairs_measured: usize,
    pub median_us_per_tick: f64,
}

/// Unit vectors uniform on the sphere from a fixed linear congruential sequence: the same
/// directions every run for a given seed (benchmark structures, not statistics).
pub(crate) struct FixedDirections {
    state: u64,
}

impl FixedDirections {
    pub(crate) fn new(seed: u64) -> Self {
        FixedDirections { state: seed }
    }

    /// The next number of the sequence, uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        self.state = self.state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The next direction: z uniform in [-1, 1), the azimuth uniform in [0, 2 pi).
    pub(crate) fn next_unit(&mut self) -> [f64; 3] {
        let (u, v) = (self.uniform() * 2.0 - 1.0, self.uniform() * std::f64::consts::TAU);
        let s = (1.0 - u * u).sqrt();
        [s * v.cos(), s * v.sin(), u]
    }
}

/// Struts for the interference benchmark: `n` capsules of radius 0.01 m, length 0.5 m, in
/// pseudo-random directions, centred on a jittered cubic lattice of spacing 0.5 m, so that each
/// strut has a bounded number of neighbours (a structure, not a bundle).
pub fn interference_capsules(n: usize) -> Vec<crate::observers::interference::Capsule> {
    const SPACING_M: f64 = 0.5;
    const HALF_LENGTH_M: f64 = 0.25;
    const RADIUS_M: f64 = 0.01;
    let side = (n as f64).cbrt().ceil() as usize;
    let mut directions = FixedDirections::new(0x2545_f491_4f6c_dd1d);
    (0..n)
        .map(|k| {
            let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
            let c = [i as f64 * SPACING_M, j as f64 * SPACING_M, l as f64 * SPACING_M];
            let d = directions.next_unit().map(|x| x * HALF_LENGTH_M);
            ([c[0] - d[0], c[1] - d[1], c[2] - d[2]], [c[0] + d[0], c[1] + d[1], c[2] + d[2]], RADIUS_M)
        })
        .collect()
}

/// Median time of one interference measurement (broad phase + narrow phase) for each size.
pub fn bench_interference(sizes: &[usize], repeats: usize) -> Vec<InterferenceBench> {
    const MARGIN_M: f64 = 0.1;
    sizes
        .iter()
        .map(|&n| {
            let caps = interference_capsules(n);
            let mut times = Vec::new();
            let mut pairs = 0;
            for _ in 0..repeats.max(1) {
                let t = std::time::Instant::now();
                let out = crate::observers::interference::clearances(&caps, MARGIN_M, |_, _| false);
                times.push(t.elapsed().as_secs_f64() * 1e6);
                pairs = out.len();
            }
            InterferenceBench { struts: n, pairs_measured: pairs, median_us_per_tick: median(&mut times) }
        })
        .collect()
}

/// One case set written for a peer simulator (`tensegrity bench --export-cases DIR`): the same
/// points, parameters, time step, settle criterion and the testbed's analytic values, so that a
/// peer settles exactly the testbed's cases and is scored by exactly its error measure.
#[derive(Clone, Debug, Serialize)]
pub struct PeerCaseSet {
    pub mechanism: String,
    pub scenario: String,
    pub params: crate::mechanisms::Values,
    pub dt_s: f64,
    pub speed_tol_m_per_s: f64,
    pub window_steps: u64,
    pub max_time_s: f64,
    /// The mechanism's characteristic length \[m\]: length errors are divided by it.
    pub length_scale_m: f64,
    /// The checked quantities: `kind` is "length" (error / length_scale_m), "angle" (wrapped,
    /// rad) or "magnitude" (error / |analytic|).
    pub checks: Vec<PeerCheck>,
    pub cases: Vec<PeerCase>,
}

#[derive(Clone, Debug, Serialize)]
pub struct PeerCheck {
    pub quantity: String,
    pub kind: &'static str,
    pub tolerance: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct PeerCase {
    pub inputs: crate::mechanisms::Values,
    /// Every analytic quantity of the testbed's prediction at this case.
    pub analytic: crate::mechanisms::Values,
    /// Node positions of the testbed's start state (the scenario's `[start]`) \[m\].
    pub start_nodes: std::collections::BTreeMap<String, [f64; 3]>,
    /// Node positions at the analytic equilibrium, where the model gives them \[m\].
    pub analytic_nodes: Option<std::collections::BTreeMap<String, [f64; 3]>>,
}

/// The case set of scenario `sc` for a peer simulator.
pub fn peer_case_set(mechanism: &str, sc: &scenario::Scenario) -> Result<PeerCaseSet, BenchError> {
    use crate::mechanisms::QuantityKind;
    let file = &sc.file;
    let m = sc.mechanism();
    let params = crate::mechanisms::with_defaults(m.as_ref(), &sc.params);
    let Actuation::Points { points, .. } = &sc.actuation else {
        return Err(BenchError::Case(format!(
            "{}: a bench case set needs [actuation] points or a grid",
            file.display()
        )));
    };
    let mut cases = Vec::new();
    for p in points {
        // The scenario's loader already turned alternative inputs into the mechanism's inputs.
        let inputs = p.clone();
        let prediction = m.predict(&params, &inputs)?;
        let start = m.build(&params, &inputs, &sc.start)?;
        let name = |i: usize| start.nodes[i].name.clone();
        let start_nodes = start.nodes.iter().enumerate().map(|(i, n)| (name(i), n.position)).collect();
        let analytic_nodes = m
            .analytic_nodes(&params, &inputs)
            .map(|ps| ps.into_iter().enumerate().map(|(i, p)| (name(i), p)).collect());
        cases.push(PeerCase { inputs, analytic: prediction.expected, start_nodes, analytic_nodes });
    }
    let checks = sc
        .checks
        .iter()
        .map(|c| PeerCheck {
            quantity: c.quantity.clone(),
            kind: match c.kind {
                QuantityKind::Length => "length",
                QuantityKind::Angle => "angle",
                QuantityKind::Magnitude => "magnitude",
            },
            tolerance: c.tolerance,
        })
        .collect();
    Ok(PeerCaseSet {
        mechanism: mechanism.into(),
        scenario: file.display().to_string(),
        length_scale_m: m.length_scale(&params),
        params,
        dt_s: sc.sim.dt_s,
        speed_tol_m_per_s: sc.settle.speed_tol_m_per_s,
        window_steps: sc.settle.window_steps,
        max_time_s: sc.settle.max_time_s,
        checks,
        cases,
    })
}

/// The MuJoCo peer of `bench --peer` (the case sets) and of `bench --scale --peer`.
pub const PEER_SCRIPT: &str = "benches/peers/mujoco/peer.py";
pub const SCALE_PEER_SCRIPT: &str = "benches/peers/mujoco/scale_peer.py";

/// A peer command given as one string, split at white space; or, for the default peer
/// (`None`), `script` run by `$TENSEGRITY_PYTHON` (the Python that has MuJoCo), else python3.
pub fn peer_command(given: Option<&str>, script: &str) -> Vec<String> {
    match given {
        None => {
            let python = std::env::var("TENSEGRITY_PYTHON").unwrap_or_else(|_| "python3".into());
            vec![python, script.into()]
        }
        Some(command) => command.split_whitespace().map(str::to_string).collect(),
    }
}

/// Strut counts of the interference benchmark, and the repetitions whose median is reported.
pub const INTERFERENCE_BENCH_SIZES: [usize; 3] = [10, 100, 1000];
pub const INTERFERENCE_BENCH_REPEATS: usize = 201;
