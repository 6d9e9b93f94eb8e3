//! The `tensegrity` command line.

use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use tensegrity_testbed::mechanisms::{self, Origin, Values};
use tensegrity_testbed::report::{Report, EXIT_BAD_INPUT, EXIT_FAIL, EXIT_PASS};
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario::{self, Scenario};

#[derive(Parser)]
#[command(
    name = "tensegrity",
    version,
    about = "Check published tensegrity mechanism models against rigid-body dynamics"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run scenario files headless and compare the simulation with the analytic model.
    Run {
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
        /// Write the JSON report {"scenarios": [...]} to this file.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Record to this .rrd file (with several scenarios: one file each, named FILE-<scenario>.rrd).
        #[arg(long)]
        record: Option<PathBuf>,
        /// Stream live to a running rerun viewer or server instead (default: rerun's own address,
        /// rerun+http://127.0.0.1:9876/proxy).
        #[arg(long, num_args = 0..=1, default_missing_value = "", value_name = "ADDR")]
        connect: Option<String>,
        /// Record every N-th tick only (thins long runs).
        #[arg(long, default_value_t = 1, value_name = "N")]
        record_every: u64,
        /// Write every tick as a row of this CSV table at full f64 precision (with several
        /// scenarios: one file each, named FILE-<scenario>.csv).
        #[arg(long, value_name = "FILE.csv")]
        table: Option<PathBuf>,
    },
    /// Validate scenario files without running them.
    Check {
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
    },
    /// List the mechanisms, their parameters (units, defaults) and their queries; with a
    /// scenario file, that file's mechanism (a custom file's own parameters with their values)
    /// and the symbols its model's expressions may use.
    List { scenario: Option<PathBuf> },
    /// Settle every point of a scenario's grid in parallel; write a CSV and a JSON summary.
    Sweep {
        scenario: PathBuf,
        /// The CSV (one row per point); default: print the summary only.
        #[arg(long)]
        out: Option<PathBuf>,
        /// The JSON summary.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Worker threads (at most the machine's threads; more is lowered, and said).
        #[arg(long, default_value_t = 2)]
        jobs: usize,
        /// Run the K-th of N interleaved slices of the grid (for job arrays), as K/N.
        #[arg(long)]
        shard: Option<String>,
        /// A figure of the sweep (FILE.png or FILE.svg): each compared quantity, analytic and
        /// settled, against one axis, and the errors.
        #[arg(long)]
        figure: Option<PathBuf>,
        /// The figure's axis: an input or a swept parameter (default: the one with most values).
        #[arg(long)]
        x: Option<String>,
    },
    /// Draw one of the papers' figures (analytic, with the dynamics' verdict) as PNG and SVG.
    Figure {
        /// The figure's name (`tensegrity figure --list`).
        name: Option<String>,
        /// Directory for NAME.png and NAME.svg.
        #[arg(long, default_value = "assets/figures")]
        out: PathBuf,
        /// List the figures.
        #[arg(long)]
        list: bool,
    },
    /// Join the CSVs of a sharded sweep into one, rows in grid order.
    Merge {
        #[arg(required = true)]
        csvs: Vec<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        /// Merge what is there even when points of the grid are missing (a shard left out).
        #[arg(long)]
        partial: bool,
    },
    /// The analytic model alone: print every result of a query.
    Solve {
        mechanism: String,
        query: String,
        /// NAME=VALUE for a parameter or an input (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<String>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Measure settling speed and accuracy on the built-in case sets (medians over rounds).
    Bench {
        /// Rounds per case set.
        #[arg(long, default_value_t = 5)]
        rounds: usize,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Write each case set as DIR/MECHANISM.json for a peer simulator (parameters, time
        /// step, settle criterion, inputs, analytic values, start and analytic node positions)
        /// and stop.
        #[arg(long, value_name = "DIR")]
        export_cases: Option<PathBuf>,
        /// Only this mechanism's case set (repeatable; default: all).
        #[arg(long = "mechanism", value_name = "NAME")]
        mechanisms: Vec<String>,
        /// Also run each case set through a peer simulator, alternating rounds with the
        /// testbed, and print the ratios. CMD gets the case-set file and `--rounds 1` appended
        /// (default: the MuJoCo peer, `benches/peers/mujoco/peer.py` run by `$TENSEGRITY_PYTHON`, else python3).
        #[arg(long, value_name = "CMD", num_args = 0..=1, default_missing_value = DEFAULT_PEER)]
        peer: Option<String>,
        /// Settle the scale families instead (n-strut prisms, the icosahedron, force-density
        /// towers, furet2018 X chains) from perturbed starts: steps, wall time, memory, error
        /// against the closed form, growth exponent. With --peer: the same structures in MuJoCo
        /// too (default `benches/peers/mujoco/scale_peer.py`).
        #[arg(long)]
        scale: bool,
        /// With --scale: largest structure, in struts.
        #[arg(long, value_name = "N", default_value_t = 1000)]
        max_struts: usize,
        /// With --scale: only this family (prism, icosahedron, tower, furet; repeatable).
        #[arg(long = "family", value_name = "NAME")]
        families: Vec<String>,
        /// With --scale: a case still moving after this wall time is reported as not settled
        /// (checked between steps) [s].
        #[arg(long, value_name = "S", default_value_t = 120.0)]
        max_case_wall_s: f64,
    },
    /// Write a scenario's structure in another simulator's format.
    Export {
        #[command(subcommand)]
        format: ExportFormat,
    },
    /// Read a structure from another tool's format and write it as a scenario file.
    Import {
        #[command(subcommand)]
        format: ImportFormat,
    },
    /// Check every printed equation of a mechanism's paper against the testbed's derivation.
    Findings {
        mechanism: String,
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<String>,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum ExportFormat {
    /// MuJoCo MJCF XML of the structure at the scenario's first actuation point.
    Mjcf {
        scenario: PathBuf,
        /// The XML file (default: stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// How the testbed's ideal actuators are written: `mocap` (bodies placed by actuated
        /// joints are mocap bodies: exact) or `position` (position servos of gain --kp).
        #[arg(long, default_value = "mocap", value_parser = ["mocap", "position"])]
        actuators: String,
        /// Gain of the position actuators on joints [N/m or N m/rad].
        #[arg(long, default_value_t = 1e6)]
        kp: f64,
        /// Viscous damping along every cable [N s/m] (tendon damping, winch kv): zero at rest,
        /// it only helps MuJoCo settle (the testbed's cables have none).
        #[arg(long, default_value_t = 0.0)]
        cable_damping: f64,
    },
}

#[derive(Subcommand)]
enum ImportFormat {
    /// An NTRT YAML model (nodes, pair_groups, builders, substructures, bond_groups).
    Ntrt {
        file: PathBuf,
        /// The scenario file (default: stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Keep NTRT's axes (y up) instead of mapping its y to the testbed's z.
        #[arg(long)]
        keep_axes: bool,
    },
    /// A node matrix N (3 x n) and connectivity matrices C_b (bars x n) and C_s (strings x n),
    /// as CSV (Skelton and de Oliveira's notation, TsgFEM, MOTES).
    Matrices {
        n: PathBuf,
        cb: PathBuf,
        cs: PathBuf,
        /// The scenario file (default: stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Mass of each bar [kg].
        #[arg(long, default_value_t = 1.0)]
        bar_mass: f64,
        /// Radius of each bar [m].
        #[arg(long, default_value_t = 0.01)]
        bar_radius: f64,
        /// Stiffness of each string [N/m].
        #[arg(long, default_value_t = 1000.0)]
        string_stiffness: f64,
        /// Tension of each string at its drawn length [N] (sets its rest length).
        #[arg(long, default_value_t = 10.0)]
        string_tension: f64,
    },
}

/// Set by SIGINT or SIGTERM: the running scenario stops at its next tick, the reports of what
/// ran are written, and the batch stops.
static CANCEL: AtomicBool = AtomicBool::new(false);

/// Set while the command runs a phase that stops by itself on [`CANCEL`] (the scenarios' runs and
/// the writing of their reports). In every other phase (parsing, an analytic solve, findings,
/// figures) a signal ends the command within [`SIGNAL_POLL_S`]: its temporary files are
/// removed, its outputs stay as they were, exit 1.
static STOPS_ITSELF: AtomicBool = AtomicBool::new(false);

/// How often the main thread looks for a signal while the command's thread works [s].
const SIGNAL_POLL_S: f64 = 0.05;

/// Stack of the command's thread [bytes] (the main thread's usual 8 MiB, with room).
const COMMAND_STACK_BYTES: usize = 64 << 20;

extern "C" fn on_signal(_signal: libc::c_int) {
    CANCEL.store(true, Ordering::SeqCst);
}

fn install_signal_handlers() {
    let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, handler);
        libc::signal(libc::SIGTERM, handler);
    }
}

fn main() -> ExitCode {
    install_signal_handlers();
    // A closed pipe (`tensegrity list | head -1`) ends the process quietly, as it does any
    // Unix filter, instead of a panic in println!.
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let (tx, rx) = std::sync::mpsc::channel();
    let worker = std::thread::Builder::new().stack_size(COMMAND_STACK_BYTES).spawn(move || {
        let _ = tx.send(dispatch(cli));
    });
    if let Err(e) = worker {
        eprintln!("error: cannot start the command's thread: {e}");
        return ExitCode::from(EXIT_FAIL as u8);
    }
    loop {
        match rx.recv_timeout(std::time::Duration::from_secs_f64(SIGNAL_POLL_S)) {
            Ok(code) => return ExitCode::from(code as u8),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                if CANCEL.load(Ordering::SeqCst) && !STOPS_ITSELF.load(Ordering::SeqCst) {
                    tensegrity_testbed::output::remove_partials();
                    eprintln!("interrupted");
                    return ExitCode::from(EXIT_FAIL as u8);
                }
            }
            // The command's thread panicked (its message is printed): an internal error.
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                tensegrity_testbed::output::remove_partials();
                return ExitCode::from(EXIT_INTERNAL_ERROR);
            }
        }
    }
}

/// Exit code of a command that panicked (Rust's own for a panic in main).
const EXIT_INTERNAL_ERROR: u8 = 101;

/// Runs the command; its exit code.
fn dispatch(cli: Cli) -> i32 {
    match cli.command {
        Command::Run { scenarios, json, record, connect, record_every, table } => {
            cmd_run(&scenarios, json.as_deref(), record.as_deref(), connect.as_deref(), record_every, table.as_deref())
        }
        Command::Check { scenarios } => match load_all(&scenarios) {
            Ok(list) => {
                for s in &list {
                    println!("{}: ok ({} on {})", s.file.display(), s.name, s.mechanism);
                }
                EXIT_PASS
            }
            Err(code) => code,
        },
        Command::List { scenario: None } => cmd_list(),
        Command::List { scenario: Some(file) } => cmd_list_file(&file),
        Command::Sweep { scenario, out, json, jobs, shard, figure, x } => {
            let outputs =
                SweepOutputs { csv: out.as_deref(), json: json.as_deref(), figure: figure.as_deref(), x: x.as_deref() };
            cmd_sweep(&scenario, &outputs, jobs, shard.as_deref())
        }
        Command::Merge { csvs, out, partial } => cmd_merge(&csvs, &out, partial),
        Command::Figure { name, out, list } => cmd_figure(name.as_deref(), &out, list),
        Command::Solve { mechanism, query, set, json } => cmd_solve(&mechanism, &query, &set, json),
        Command::Findings { mechanism, set, json } => cmd_findings(&mechanism, &set, json),
        Command::Import { format: ImportFormat::Ntrt { file, out, keep_axes } } => {
            cmd_import_ntrt(&file, out.as_deref(), keep_axes)
        }
        Command::Import {
            format: ImportFormat::Matrices { n, cb, cs, out, bar_mass, bar_radius, string_stiffness, string_tension },
        } => {
            let o = tensegrity_testbed::import::matrices::MatrixOptions {
                bar_mass_kg: bar_mass,
                bar_radius_m: bar_radius,
                string_stiffness_n_per_m: string_stiffness,
                string_tension_n: string_tension,
            };
            cmd_import_matrices(&[n, cb, cs], out.as_deref(), &o)
        }
        Command::Export { format: ExportFormat::Mjcf { scenario, out, actuators, kp, cable_damping } } => {
            cmd_export_mjcf(&scenario, out.as_deref(), &actuators, kp, cable_damping)
        }
        Command::Bench { scale: true, json, max_struts, families, max_case_wall_s, peer, .. } => {
            cmd_bench_scale(json, max_struts, &families, max_case_wall_s, peer.as_deref())
        }
        Command::Bench { export_cases: Some(dir), .. } => cmd_export_cases(&dir),
        Command::Bench { rounds, json, export_cases: None, mechanisms, peer: Some(peer), .. } => {
            cmd_bench_peer(rounds, json, &mechanisms, &peer)
        }
        Command::Bench { rounds, json, export_cases: None, mechanisms, peer: None, .. } => {
            cmd_bench(rounds, json, &mechanisms)
        }
    }
}

/// Loads and validates every scenario; prints each error; exit code 2 if any is bad.
fn load_all(paths: &[PathBuf]) -> Result<Vec<Scenario>, i32> {
    let mut out = Vec::new();
    let mut bad = false;
    for p in paths {
        match scenario::load(p) {
            Ok(s) => out.push(s),
            Err(e) => {
                eprintln!("error: {e}");
                bad = true;
            }
        }
    }
    if bad {
        Err(EXIT_BAD_INPUT)
    } else {
        Ok(out)
    }
}

/// Writes `text` to `path` through a unique temporary file and a rename (`output`).
fn write_atomic(path: &Path, text: &str) -> Result<(), String> {
    tensegrity_testbed::output::write_atomic(path, text.as_bytes())
}

/// Refuses outputs that would destroy data (`output::check_outputs`): exit 2 before anything runs.
fn check_outputs(inputs: &[PathBuf], outputs: Vec<(String, PathBuf)>) -> Result<(), i32> {
    tensegrity_testbed::output::check_outputs(inputs, &outputs).map_err(|e| {
        eprintln!("error: {e}");
        EXIT_BAD_INPUT
    })
}

fn record_path(base: &Path, name: &str, several: bool) -> PathBuf {
    if !several {
        return base.to_path_buf();
    }
    let stem = base.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "run".into());
    let safe: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect();
    base.with_file_name(format!("{stem}-{safe}.rrd"))
}

/// The table file of one scenario: `base` itself, or `base-<scenario>.csv` with several.
fn table_path(base: &Path, name: &str, several: bool) -> PathBuf {
    let rrd = record_path(base, name, several);
    if several {
        rrd.with_extension("csv")
    } else {
        rrd
    }
}

fn cmd_run(
    paths: &[PathBuf],
    json: Option<&Path>,
    record: Option<&Path>,
    connect: Option<&str>,
    record_every: u64,
    table: Option<&Path>,
) -> i32 {
    let scenarios = match load_all(paths) {
        Ok(s) => s,
        Err(code) => return code,
    };
    if let Some(r) = record {
        if r.extension().and_then(|e| e.to_str()) != Some("rrd") {
            eprintln!("error: --record {} must end in .rrd", r.display());
            return EXIT_BAD_INPUT;
        }
    }
    let several = scenarios.len() > 1;
    let mut outputs: Vec<(String, PathBuf)> =
        json.map(|j| ("--json".to_string(), j.to_path_buf())).into_iter().collect();
    if connect.is_none() {
        for sc in &scenarios {
            if let Some(r) = record.map(|r| record_path(r, &sc.name, several)).or_else(|| sc.record.clone()) {
                outputs.push((format!("the recording of scenario '{}' ({})", sc.name, sc.file.display()), r));
            }
        }
    }
    for sc in &scenarios {
        if let Some(t) = table.map(|t| table_path(t, &sc.name, several)) {
            outputs.push((format!("the table of scenario '{}' ({})", sc.name, sc.file.display()), t));
        }
    }
    if let Err(code) = check_outputs(paths, outputs) {
        return code;
    }
    // From here on each run stops at its next tick on a signal and the reports are written.
    STOPS_ITSELF.store(true, Ordering::SeqCst);
    let mut report = Report { scenarios: vec![] };
    for sc in &scenarios {
        if CANCEL.load(Ordering::SeqCst) {
            eprintln!("interrupted: {} scenario(s) not run", scenarios.len() - report.scenarios.len());
            break;
        }
        let opts = RunOptions {
            record: record.map(|r| record_path(r, &sc.name, several)),
            cancel: Some(&CANCEL),
            connect: connect.map(str::to_string),
            record_every,
            skip_findings: false,
            table: table.map(|t| table_path(t, &sc.name, several)),
        };
        // A panic inside one scenario fails that scenario, with its message; the batch goes on.
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(sc, &opts)))
            .unwrap_or_else(|payload| tensegrity_testbed::run::panicked(sc, payload.as_ref()));
        report.scenarios.push(r);
    }
    print!("{}", report.to_table());
    if let Some(j) = json {
        if let Err(e) = write_atomic(j, &report.to_json()) {
            eprintln!("error: the JSON report: {e}");
            return EXIT_FAIL;
        }
    }
    if report.passed() && !CANCEL.load(Ordering::SeqCst) {
        EXIT_PASS
    } else {
        EXIT_FAIL
    }
}

/// What a sweep writes: its CSV, its JSON summary, its figure (against axis `x`).
struct SweepOutputs<'a> {
    csv: Option<&'a Path>,
    json: Option<&'a Path>,
    figure: Option<&'a Path>,
    x: Option<&'a str>,
}

fn cmd_sweep(path: &Path, o: &SweepOutputs, jobs: usize, shard: Option<&str>) -> i32 {
    let (out, json) = (o.csv, o.json);
    let sc = match load_all(&[path.to_path_buf()]) {
        Ok(mut s) => s.remove(0),
        Err(code) => return code,
    };
    if let Some(f) = o.figure.filter(|f| !matches!(f.extension().and_then(|e| e.to_str()), Some("png" | "svg"))) {
        eprintln!("error: --figure {}: give a .png or .svg file", f.display());
        return EXIT_BAD_INPUT;
    }
    let outputs = [("--out", out), ("--json", json), ("--figure", o.figure)]
        .into_iter()
        .filter_map(|(what, p)| p.map(|p| (what.to_string(), p.to_path_buf())))
        .collect();
    if let Err(code) = check_outputs(&[path.to_path_buf()], outputs) {
        return code;
    }
    let jobs = capped_jobs(jobs);
    // From here on every block stops at its next tick on a signal and the outputs are written.
    STOPS_ITSELF.store(true, Ordering::SeqCst);
    let shard = match shard.map(tensegrity_testbed::sweep::parse_shard).transpose() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} points, {per_sec}, {eta} left")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let result = tensegrity_testbed::sweep::sweep(&sc, jobs, shard, Some(&CANCEL), &progress);
    bar.finish_and_clear();
    let (rows, summary) = match result {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    println!(
        "{}: {} point(s), {} settled, {} within tolerance, {:.2} s wall on {} job(s){}",
        summary.scenario,
        summary.points,
        summary.settled,
        summary.within_tolerance,
        summary.wall_s,
        summary.jobs,
        summary.shard.as_ref().map(|s| format!(", shard {s}")).unwrap_or_default()
    );
    if let Some(w) = &summary.workspace {
        println!("workspace agreement {:.2} % ({} of {} points)", w.agreement_percent, w.agree, w.points);
    }
    for e in &summary.errors {
        println!("stopped: {e}");
    }
    let mech = sc.mechanism();
    let is_angle = |q: &str| {
        mech.quantities().iter().any(|s| s.symbol == q && s.kind == mechanisms::QuantityKind::Angle)
            || sc.model.as_ref().is_some_and(|m| m.is_angle(q))
    };
    if let Some(o) = out {
        if let Err(e) = write_atomic(o, &tensegrity_testbed::sweep::to_csv(&rows, &is_angle)) {
            eprintln!("error: {e}");
            return EXIT_FAIL;
        }
    }
    if let Some(f) = o.figure {
        if let Err(e) = tensegrity_testbed::figures::sweep::draw(&rows, &summary.scenario, o.x, &is_angle, f) {
            eprintln!("error: {e}");
            return EXIT_FAIL;
        }
    }
    if let Some(j) = json {
        if let Err(e) = write_atomic(j, &serde_json::to_string_pretty(&summary).unwrap_or_default()) {
            eprintln!("error: {e}");
            return EXIT_FAIL;
        }
    }
    if let Some(min) = summary.min_agreement_percent {
        println!("required agreement {min:.2} %");
    }
    if !summary.disagreements.is_empty() {
        println!("{} point(s) did not settle or are out of tolerance", summary.disagreements.len());
    }
    if summary.passed && !CANCEL.load(Ordering::SeqCst) {
        println!("PASS");
        EXIT_PASS
    } else {
        println!("FAIL");
        EXIT_FAIL
    }
}

/// `--jobs`, at least 1 and at most the machine's threads (lowered with a note on stderr).
fn capped_jobs(jobs: usize) -> usize {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    if jobs > threads {
        eprintln!("note: --jobs {jobs} lowered to {threads}, the threads of this machine");
    }
    jobs.clamp(1, threads)
}

fn cmd_figure(name: Option<&str>, out: &Path, list: bool) -> i32 {
    let name = match (name, list) {
        (Some(n), false) => n,
        _ => {
            for f in tensegrity_testbed::figures::all() {
                println!("{}: {}", f.name, f.description);
            }
            return if list { EXIT_PASS } else { EXIT_BAD_INPUT };
        }
    };
    match tensegrity_testbed::figures::draw(name, out) {
        Ok(files) => {
            for f in files {
                println!("wrote {}", f.display());
            }
            EXIT_PASS
        }
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_BAD_INPUT
        }
    }
}

fn cmd_merge(csvs: &[PathBuf], out: &Path, partial: bool) -> i32 {
    if let Err(code) = check_outputs(csvs, vec![("--out".into(), out.to_path_buf())]) {
        return code;
    }
    let mut texts = Vec::new();
    for p in csvs {
        match std::fs::read_to_string(p) {
            Ok(t) => texts.push((p.display().to_string(), t)),
            Err(e) => {
                eprintln!("error: cannot read {}: {e}", p.display());
                return EXIT_BAD_INPUT;
            }
        }
    }
    match tensegrity_testbed::sweep::merge_csv(&texts, partial) {
        Ok(text) => match write_atomic(out, &text) {
            Ok(()) => EXIT_PASS,
            Err(e) => {
                eprintln!("error: {e}");
                EXIT_FAIL
            }
        },
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_BAD_INPUT
        }
    }
}

fn cmd_list() -> i32 {
    for m in mechanisms::registry() {
        print_mechanism(m.as_ref());
    }
    EXIT_PASS
}

/// `list FILE`: the file's mechanism with the parameter values the file gives, then the
/// symbols of its model section, if it has one.
fn cmd_list_file(file: &std::path::Path) -> i32 {
    let sc = match load_all(&[file.to_path_buf()]) {
        Ok(mut list) => list.remove(0),
        Err(code) => return code,
    };
    let m = sc.mechanism();
    print_mechanism(m.as_ref());
    println!("  parameter values in {}:", file.display());
    for (k, v) in &sc.params {
        println!("    {k:<12} = {v}");
    }
    if let Some(model) = &sc.model {
        println!("  model symbols (for [[quantities]], [[predictions]], [[equations]]):");
        println!("    {}", model.names().join(" "));
    }
    EXIT_PASS
}

/// A mechanism's parameters, inputs, start keys, quantities and queries.
fn print_mechanism(m: &dyn mechanisms::Mechanism) {
    println!("{}: {}", m.name(), m.title());
    println!("  parameters:");
    for p in m.params() {
        let origin = match p.origin {
            // A custom file's own parameters.
            _ if m.name() == "custom" => "file",
            Origin::Paper => "paper",
            Origin::ModelChoice => "model choice",
        };
        println!("    {:<12} [{}] default {} ({}): {}", p.symbol, p.unit, p.default, origin, p.description);
    }
    println!("  inputs:");
    for i in m.inputs() {
        println!("    {:<12} [{}] {}", i.symbol, i.unit, i.description);
    }
    println!("  start keys ([start] table):");
    for (k, what) in m.start_keys() {
        println!("    {k:<16} {what}");
    }
    println!("  checkable quantities:");
    for q in m.quantities() {
        println!("    {:<12} [{}] {}", q.symbol, q.unit, q.description);
    }
    println!("  queries (tensegrity solve {} QUERY --set NAME=VALUE ...):", m.name());
    for q in m.queries() {
        println!("    {:<12} inputs {}: {}", q.name, q.inputs.join(" "), q.description);
    }
}

/// Writes `text` to `out` (never over an input, `output::check_outputs`), or to stdout
/// without `out`.
fn write_output(out: Option<&Path>, inputs: &[PathBuf], text: &str) -> i32 {
    let Some(o) = out else {
        print!("{text}");
        return EXIT_PASS;
    };
    if let Err(code) = check_outputs(inputs, vec![("--out".into(), o.to_path_buf())]) {
        return code;
    }
    match write_atomic(o, text) {
        Ok(()) => EXIT_PASS,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_FAIL
        }
    }
}

fn cmd_import_ntrt(path: &Path, out: Option<&Path>, keep_axes: bool) -> i32 {
    use tensegrity_testbed::import::ntrt::{import, Axes};
    let axes = if keep_axes { Axes::Keep } else { Axes::ZUp };
    match import(path, axes) {
        Ok(imported) => {
            for s in &imported.skipped {
                eprintln!("skipped: {s}");
            }
            write_output(out, &[path.to_path_buf()], &imported.toml)
        }
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_BAD_INPUT
        }
    }
}

fn cmd_import_matrices(
    inputs: &[PathBuf; 3],
    out: Option<&Path>,
    o: &tensegrity_testbed::import::matrices::MatrixOptions,
) -> i32 {
    let positive = [
        ("--bar-mass", o.bar_mass_kg),
        ("--bar-radius", o.bar_radius_m),
        ("--string-stiffness", o.string_stiffness_n_per_m),
    ];
    if let Some((flag, x)) = positive.iter().find(|(_, x)| !(*x > 0.0 && x.is_finite())) {
        eprintln!("error: {flag} must be a finite number > 0, got {x}");
        return EXIT_BAD_INPUT;
    }
    if !(o.string_tension_n >= 0.0 && o.string_tension_n.is_finite()) {
        eprintln!("error: --string-tension must be a finite number >= 0, got {}", o.string_tension_n);
        return EXIT_BAD_INPUT;
    }
    if let Some(path) = out {
        if inputs.iter().any(|i| path.exists() && std::fs::canonicalize(i).ok() == std::fs::canonicalize(path).ok()) {
            eprintln!("error: --out {} is an input file; choose another", path.display());
            return EXIT_BAD_INPUT;
        }
    }
    match tensegrity_testbed::import::matrices::import(&inputs[0], &inputs[1], &inputs[2], o) {
        Ok(imported) => write_output(out, inputs.as_slice(), &imported.toml),
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_BAD_INPUT
        }
    }
}

fn cmd_export_mjcf(path: &Path, out: Option<&Path>, actuators: &str, kp: f64, cable_damping: f64) -> i32 {
    use tensegrity_testbed::export::{mjcf::ActuatorMode, scenario_mjcf};
    let sc = match load_all(&[path.to_path_buf()]) {
        Ok(mut s) => s.remove(0),
        Err(code) => return code,
    };
    if !(kp > 0.0 && kp.is_finite()) {
        eprintln!("error: --kp must be a finite number > 0, got {kp}");
        return EXIT_BAD_INPUT;
    }
    if !(cable_damping >= 0.0 && cable_damping.is_finite()) {
        eprintln!("error: --cable-damping must be a finite number >= 0, got {cable_damping}");
        return EXIT_BAD_INPUT;
    }
    let mode = if actuators == "position" { ActuatorMode::Position } else { ActuatorMode::Mocap };
    let mjcf = match scenario_mjcf(&sc, mode, kp, cable_damping) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {}: {e}", path.display());
            return EXIT_BAD_INPUT;
        }
    };
    for w in &mjcf.warnings {
        eprintln!("warning: not exported: {w}");
    }
    write_output(out, &[path.to_path_buf()], &mjcf.xml)
}

/// Splits --set NAME=VALUE arguments into parameters and inputs of the mechanism.
fn parse_sets(
    m: &dyn mechanisms::Mechanism,
    sets: &[String],
    allowed_inputs: &[&str],
) -> Result<(Values, Values), String> {
    let mut params = Values::new();
    let mut inputs = Values::new();
    for s in sets {
        let (k, v) = s.split_once('=').ok_or_else(|| format!("--set {s}: expected NAME=VALUE"))?;
        let x: f64 = v.trim().parse().map_err(|_| format!("--set {s}: '{v}' is not a number"))?;
        if !x.is_finite() {
            return Err(format!("--set {s}: the value must be finite"));
        }
        if m.params().iter().any(|p| p.symbol == k) {
            params.insert(k.into(), x);
        } else if allowed_inputs.contains(&k) {
            inputs.insert(k.into(), x);
        } else {
            let known: Vec<&str> = m.params().iter().map(|p| p.symbol).chain(allowed_inputs.iter().copied()).collect();
            return Err(format!("--set {s}: unknown name '{k}' (expected one of: {})", known.join(", ")));
        }
    }
    let params = mechanisms::with_defaults(m, &params);
    m.validate_params(&params).map_err(|e| e.to_string())?;
    Ok((params, inputs))
}

fn cmd_solve(mechanism: &str, query: &str, sets: &[String], json: bool) -> i32 {
    let Some(m) = mechanisms::find(mechanism) else {
        let known: Vec<_> = mechanisms::registry().iter().map(|m| m.name()).collect();
        eprintln!("error: unknown mechanism '{mechanism}' (expected one of: {})", known.join(", "));
        return EXIT_BAD_INPUT;
    };
    let Some(q) = m.queries().iter().find(|q| q.name == query) else {
        let known: Vec<_> = m.queries().iter().map(|q| q.name).collect();
        eprintln!("error: unknown query '{query}' for {mechanism} (expected one of: {})", known.join(", "));
        return EXIT_BAD_INPUT;
    };
    let (params, inputs) = match parse_sets(m.as_ref(), sets, q.inputs) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    for i in q.inputs {
        if !inputs.contains_key(*i) {
            eprintln!("error: query '{query}' needs --set {i}=VALUE (inputs: {})", q.inputs.join(" "));
            return EXIT_BAD_INPUT;
        }
    }
    match m.solve(query, &params, &inputs) {
        Ok(sols) => {
            if json {
                let v = serde_json::json!({
                    "mechanism": mechanism, "query": query, "params": params, "inputs": inputs,
                    "solutions": sols.iter().map(|s| serde_json::json!({"label": s.label, "values": s.values, "stable": s.stable})).collect::<Vec<_>>(),
                });
                println!("{}", serde_json::to_string_pretty(&v).unwrap());
            } else {
                println!("{mechanism} {query}: {} result(s)", sols.len());
                for s in &sols {
                    let st = match s.stable {
                        Some(true) => ", stable",
                        Some(false) => ", unstable",
                        None => "",
                    };
                    println!("  {}{st}:", s.label);
                    for (k, v) in &s.values {
                        println!("    {k:<12} = {v:.12}");
                    }
                }
            }
            EXIT_PASS
        }
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_BAD_INPUT
        }
    }
}

fn cmd_findings(mechanism: &str, sets: &[String], json: bool) -> i32 {
    let Some(m) = mechanisms::find(mechanism) else {
        eprintln!("error: unknown mechanism '{mechanism}'");
        return EXIT_BAD_INPUT;
    };
    let (params, _) = match parse_sets(m.as_ref(), sets, &[]) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let f = m.findings(&params);
    if json {
        let v: Vec<_> = f.iter().map(|f| serde_json::json!({"equation": f.equation, "claim": f.claim, "measured": f.measured, "holds": f.holds})).collect();
        println!("{}", serde_json::to_string_pretty(&v).unwrap());
    } else {
        for f in &f {
            println!(
                "[{}] {}: {}\n      measured: {}",
                if f.holds { "holds" } else { "WRONG" },
                f.equation,
                f.claim,
                f.measured
            );
        }
    }
    EXIT_PASS
}

/// Strut counts of the interference benchmark, and the repetitions whose median is reported.
const INTERFERENCE_BENCH_SIZES: [usize; 3] = [10, 100, 1000];
const INTERFERENCE_BENCH_REPEATS: usize = 201;

fn cmd_export_cases(dir: &Path) -> i32 {
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!("error: cannot create {}: {e}", dir.display());
        return EXIT_BAD_INPUT;
    }
    for (m, file) in tensegrity_testbed::bench::CASE_SETS {
        let set = match tensegrity_testbed::bench::bench_scenario(Path::new(file))
            .and_then(|sc| tensegrity_testbed::bench::peer_case_set(m, &sc))
        {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
        };
        let path = dir.join(format!("{m}.json"));
        let text = serde_json::to_string_pretty(&set).expect("case set serialises");
        if let Err(e) = write_atomic(&path, &text) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return EXIT_BAD_INPUT;
        }
        println!("wrote {} ({} cases)", path.display(), set.cases.len());
    }
    EXIT_PASS
}

/// The MuJoCo peer of `benches/peers/mujoco/`.
const DEFAULT_PEER: &str = "python3 benches/peers/mujoco/peer.py";

/// The MuJoCo peer of `tensegrity bench --scale --peer`.
const DEFAULT_SCALE_PEER: &str = "benches/peers/mujoco/scale_peer.py";

/// The peer command `peer` as given, or the default peer's `script` (`DEFAULT_PEER` names the
/// default) run with `$TENSEGRITY_PYTHON` (the Python that has MuJoCo), else python3.
fn peer_command(peer: &str, script: &str) -> Vec<String> {
    if peer == DEFAULT_PEER {
        let python = std::env::var("TENSEGRITY_PYTHON").unwrap_or_else(|_| "python3".into());
        vec![python, script.into()]
    } else {
        peer.split_whitespace().map(str::to_string).collect()
    }
}

fn cmd_bench_scale(json: bool, max_struts: usize, only: &[String], max_wall_s: f64, peer: Option<&str>) -> i32 {
    use tensegrity_testbed::bench::scale;
    let families: Vec<&'static str> =
        scale::FAMILIES.iter().copied().filter(|f| only.is_empty() || only.iter().any(|o| o == f)).collect();
    if let Some(bad) = only.iter().find(|o| !scale::FAMILIES.contains(&o.as_str())) {
        eprintln!("error: no scale family '{bad}' (families: {})", scale::FAMILIES.join(", "));
        return EXIT_BAD_INPUT;
    }
    let caps = scale::Caps { max_wall_s, ..scale::DEFAULT_CAPS };
    if let Some(peer) = peer {
        let command = peer_command(peer, DEFAULT_SCALE_PEER);
        return cmd_bench_scale_peer(json, max_struts, &families, &caps, &command);
    }
    let mut reports = Vec::new();
    for family in families {
        eprintln!("{family}: settling up to {max_struts} struts ...");
        match scale::run_family(family, max_struts, &caps) {
            Ok(r) => {
                if !json {
                    print_scale_family(&r);
                }
                reports.push(r);
            }
            Err(e) => {
                eprintln!("error: {family}: {e}");
                return 1;
            }
        }
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&serde_json::json!({ "scale": reports })).unwrap());
    }
    EXIT_PASS
}

fn print_scale_family(r: &tensegrity_testbed::bench::scale::FamilyReport) {
    println!(
        "\n{:<12} {:>5} {:>6} {:>6} {:>7} {:>7} {:>9} {:>10} {:>9} {:>9} {:>10} {:>10}",
        "family",
        "size",
        "struts",
        "cables",
        "springs",
        "settled",
        "steps",
        "wall s",
        "rss MiB",
        "peak MiB",
        "error",
        "residual"
    );
    let mib = |k: Option<u64>| k.map_or(f64::NAN, |k| k as f64 / 1024.0);
    for c in &r.cases {
        println!(
            "{:<12} {:>5} {:>6} {:>6} {:>7} {:>7} {:>9} {:>10.4} {:>9.1} {:>9.1} {:>7.2e} {:<3} {:>9.2e}{}",
            c.family,
            c.size,
            c.struts,
            c.cables,
            c.springs,
            c.settled,
            c.steps,
            c.wall_s,
            mib(c.rss_before_kib),
            mib(c.peak_rss_kib),
            c.error,
            c.error_unit,
            c.residual,
            c.note.as_ref().map_or(String::new(), |n| format!("  ({n})"))
        );
    }
    match r.growth_exponent {
        Some(e) => println!("{}: wall ~ struts^{e:.2} over the largest settled sizes", r.family),
        None => println!("{}: growth exponent: fewer than two settled sizes", r.family),
    }
}

fn cmd_bench_scale_peer(
    json: bool,
    max_struts: usize,
    families: &[&'static str],
    caps: &tensegrity_testbed::bench::scale::Caps,
    command: &[String],
) -> i32 {
    use tensegrity_testbed::bench::scale::peer;
    let dir = std::env::temp_dir().join(format!("tensegrity-bench-scale-peer-{}", std::process::id()));
    let out = peer::compare(families, max_struts, caps, command, &dir);
    let _ = std::fs::remove_dir_all(&dir);
    let (reports, rows) = match out {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    if json {
        let v = serde_json::json!({ "scale": reports, "scale_peer": rows });
        println!("{}", serde_json::to_string_pretty(&v).unwrap());
        return EXIT_PASS;
    }
    reports.iter().for_each(print_scale_family);
    println!(
        "\nMuJoCo side by side (cases/s = 1 / wall per case; rate x = testbed / MuJoCo cases/s; error x = testbed / MuJoCo error)"
    );
    println!(
        "{:<12} {:>5} {:>6} | {:>9} {:>7} {:>10} {:>9} | {:>9} {:>7} {:>10} {:>9} | {:>9} {:>9}",
        "family",
        "size",
        "struts",
        "tb cases/s",
        "steps",
        "error",
        "settled",
        "mj cases/s",
        "steps",
        "error",
        "settled",
        "rate x",
        "error x"
    );
    for r in &rows {
        println!(
            "{:<12} {:>5} {:>6} | {:>9.2} {:>7} {:>10.2e} {:>9} | {:>9.2} {:>7} {:>10.2e} {:>9} | {:>9.2} {:>9.2e}{}",
            r.family,
            r.size,
            r.struts,
            r.testbed_cases_per_s,
            r.testbed_steps,
            r.testbed_error,
            r.testbed_settled,
            r.peer_cases_per_s,
            r.peer_steps,
            r.peer_error,
            r.peer_settled,
            r.ratio_cases_per_s,
            r.ratio_error,
            format!(
                " {}{}",
                r.error_unit,
                if r.peer_notes.is_empty() {
                    String::new()
                } else {
                    format!("  (MuJoCo: {})", r.peer_notes.join("; "))
                }
            )
        );
    }
    EXIT_PASS
}

/// The built-in case sets that `--mechanism` selects (all when none is named).
fn selected_case_sets(only: &[String]) -> Result<Vec<(&'static str, &'static str)>, i32> {
    if let Some(bad) = only.iter().find(|m| !tensegrity_testbed::bench::CASE_SETS.iter().any(|(n, _)| n == m)) {
        eprintln!("error: no bench case set for mechanism '{bad}'");
        return Err(EXIT_BAD_INPUT);
    }
    Ok(tensegrity_testbed::bench::CASE_SETS
        .iter()
        .filter(|(m, _)| only.is_empty() || only.iter().any(|o| o == m))
        .copied()
        .collect())
}

fn cmd_bench_peer(rounds: usize, json: bool, only: &[String], peer: &str) -> i32 {
    let sets = match selected_case_sets(only) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let command = peer_command(peer, "benches/peers/mujoco/peer.py");
    let dir = std::env::temp_dir().join(format!("tensegrity-bench-peer-{}", std::process::id()));
    let mut out = Vec::new();
    for (m, file) in sets {
        eprintln!("{m}: {rounds} rounds, testbed and peer alternating ...");
        match tensegrity_testbed::bench::bench_against_peer(m, Path::new(file), rounds, &command, &dir) {
            Ok(c) => out.push(c),
            Err(e) => {
                eprintln!("error: {e}");
                let _ = std::fs::remove_dir_all(&dir);
                return EXIT_BAD_INPUT;
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if json {
        println!("{}", serde_json::to_string_pretty(&serde_json::json!({ "comparisons": out })).unwrap());
    } else {
        println!(
            "{:<10} {:<8} {:>6} {:>10} {:>11} {:>9} {:>11} {:>11}",
            "mechanism", "side", "cases", "cases/s", "steps/case", "us/step", "median err", "max err"
        );
        for c in &out {
            for (side, r) in [("testbed", &c.testbed), ("peer", &c.peer)] {
                println!(
                    "{:<10} {:<8} {:>6} {:>10.1} {:>11.1} {:>9.2} {:>11.2e} {:>11.2e}{}",
                    c.mechanism,
                    side,
                    r.cases,
                    r.median_cases_per_s,
                    r.median_steps_per_case,
                    r.median_us_per_step,
                    r.median_error,
                    r.max_error,
                    if r.all_settled { "" } else { "  (not all settled)" }
                );
            }
            println!(
                "{:<10} {:<8} {:>6} {:>10.2} {:>11.2} {:>9.2} {:>11.2e} {:>11.2e}",
                c.mechanism,
                "ratio",
                "",
                c.ratio_cases_per_s,
                c.ratio_steps_per_case,
                c.ratio_us_per_step,
                c.ratio_median_error,
                c.ratio_max_error
            );
        }
        if let Some(c) = out.first() {
            println!("\npeer: {} ({})", c.peer.scenario, c.peer_name);
        }
    }
    if out.iter().all(|c| c.testbed.all_settled) {
        EXIT_PASS
    } else {
        EXIT_FAIL
    }
}

fn cmd_bench(rounds: usize, json: bool, only: &[String]) -> i32 {
    let mut results = Vec::new();
    let sets = match selected_case_sets(only) {
        Ok(s) => s,
        Err(code) => return code,
    };
    for (m, file) in sets {
        match tensegrity_testbed::bench::bench_case_set(m, Path::new(file), rounds) {
            Ok(r) => results.push(r),
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
        }
    }
    // The interference observer's scaling is measured with the full bench only.
    let interference = if only.is_empty() {
        tensegrity_testbed::bench::bench_interference(&INTERFERENCE_BENCH_SIZES, INTERFERENCE_BENCH_REPEATS)
    } else {
        Vec::new()
    };
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({ "results": results, "interference": interference }))
                .unwrap()
        );
    } else {
        println!(
            "{:<10} {:>6} {:>7} {:>12} {:>12} {:>10} {:>12} {:>12}",
            "mechanism", "cases", "rounds", "cases/s", "steps/case", "us/step", "median err", "max err"
        );
        for r in &results {
            println!(
                "{:<10} {:>6} {:>7} {:>12.1} {:>12.1} {:>10.2} {:>12.2e} {:>12.2e}",
                r.mechanism,
                r.cases,
                r.rounds,
                r.median_cases_per_s,
                r.median_steps_per_case,
                r.median_us_per_step,
                r.median_error,
                r.max_error
            );
        }
        if !interference.is_empty() {
            println!("\ninterference observer (broad + narrow phase), per tick:");
            println!("{:>8} {:>14} {:>12}", "struts", "pairs measured", "us/tick");
            for b in &interference {
                println!("{:>8} {:>14} {:>12.2}", b.struts, b.pairs_measured, b.median_us_per_tick);
            }
        }
    }
    if results.iter().all(|r| r.all_settled) {
        EXIT_PASS
    } else {
        EXIT_FAIL
    }
}
