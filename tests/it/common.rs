//! Helpers shared by the test modules.

use std::process::Command;

/// Runs the `tensegrity` binary: (exit code, stdout, stderr).
pub fn tensegrity(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity")).args(args).output().expect("binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The report of `tensegrity CMD FILE --json -` on the scenario `text` (written to a temporary
/// file named after `name`).
pub fn json_of(cmd: &str, text: &str, name: &str) -> serde_json::Value {
    let path = std::env::temp_dir().join(format!("tensegrity-json-{}-{name}.toml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let (code, out, err) = tensegrity(&[cmd, path.to_str().unwrap(), "--json", "-"]);
    let _ = std::fs::remove_file(&path);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

/// The text of the scenario file at `path` with each (from, to) replaced once (each `from`
/// must be there).
pub fn edited(path: &str, edits: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(path).expect("the scenario file");
    for (from, to) in edits {
        assert!(text.contains(from), "'{from}' in {path}");
        text = text.replacen(from, to, 1);
    }
    text
}

/// Runs the scenario `text` writing its per-tick table: the report, the header and every
/// column (NaN where a cell is empty).
pub fn table(text: &str, name: &str) -> (tensegrity_testbed::report::ScenarioReport, Vec<String>, Vec<Vec<f64>>) {
    let path = std::env::temp_dir().join(format!("tensegrity-table-{}-{name}.csv", std::process::id()));
    let _ = std::fs::remove_file(&path);
    let sc = tensegrity_testbed::scenario::parse(std::path::Path::new("variant.toml"), text).expect("valid");
    let opts = tensegrity_testbed::run::RunOptions { table: Some(path.clone().into()), ..Default::default() };
    let report = tensegrity_testbed::run::run(&sc, &opts);
    let csv = std::fs::read_to_string(&path).expect("the table");
    let _ = std::fs::remove_file(&path);
    let mut lines = csv.lines();
    let header: Vec<String> = lines.next().expect("a header").split(',').map(str::to_string).collect();
    let mut out = vec![Vec::new(); header.len()];
    for line in lines {
        for (o, cell) in out.iter_mut().zip(line.split(',')) {
            o.push(cell.parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    (report, header, out)
}

/// Runs the scenario `text` writing its per-tick table: the report, and the named columns,
/// one vector per column (NaN where a cell is empty).
pub fn table_columns(
    text: &str,
    name: &str,
    columns: &[&str],
) -> (tensegrity_testbed::report::ScenarioReport, Vec<Vec<f64>>) {
    let (report, header, mut all) = table(text, name);
    let out = columns
        .iter()
        .map(|c| {
            let i = header.iter().position(|h| h == c).unwrap_or_else(|| panic!("column {c}"));
            std::mem::take(&mut all[i])
        })
        .collect();
    (report, out)
}

/// The slope of log(error) against log(dt): an error's fitted order in the time step.
pub fn fitted_order(steps: &[f64], errors: &[f64]) -> f64 {
    let x: Vec<f64> = steps.iter().map(|d| d.ln()).collect();
    let y: Vec<f64> = errors.iter().map(|e| e.ln()).collect();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum::<f64>() / x.iter().map(|a| (a - mx).powi(2)).sum::<f64>()
}

/// Loads and runs a scenario file through the library, with the default options.
/// The head of a one-point custom scenario named `name`, settled to 1e-12 m/s and 1e-10 N
/// (N m), without gravity: a test's structure follows it, from `[[structure.bodies]]` on.
pub fn one_point_head(name: &str) -> String {
    format!(
        "name = \"{name}\"\nmechanism = \"custom\"\n\n[settle]\nspeed_tol = 1e-12\nresidual_force_tol = 1e-10\nresidual_torque_tol = 1e-10\n\n[actuation]\npoints = [ {{}} ]\n\n[structure]\ngravity = [0, 0, 0]\n\n"
    )
}

pub fn run_file(path: &str) -> tensegrity_testbed::report::ScenarioReport {
    let sc = tensegrity_testbed::scenario::load(std::path::Path::new(path)).expect("scenario is valid");
    tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default())
}

/// A bar pinned to the ground at P (a revolute joint about z) and held by a spring from its
/// free end Q to the ground point S. `tests/it/bad_input.rs` locates errors by its line numbers.
pub const PINNED_STRUT: &str = r#"name = "pin"
mechanism = "custom"
[actuation]
points = [ {} ]
[structure]
gravity = [0.0, 0.0, 0.0]
[[structure.bodies]]
name = "ground"
fixed = true
nodes = { O = [0.0, 0.0, 0.0], S = [1.0, 1.0, 0.0] }
[[structure.bodies]]
name = "bar"
mass = 1.0
nodes = { P = [0.0, 0.0, 0.0], Q = [1.0, 0.0, 0.0] }
[[structure.struts]]
name = "bar"
a = "P"
b = "Q"
[[structure.springs]]
name = "k"
a = "Q"
b = "S"
stiffness = 10.0
length = 0.5
[[structure.joints]]
name = "pin"
kind = "revolute"
parent = "ground"
child = "bar"
at = "P"
axis = [0.0, 0.0, 1.0]
damping = 0.5
"#;

/// A 3-vector [m].
pub type P3 = [f64; 3];

/// The settled coordinates of node `n` at a report's first point.
pub fn node(r: &tensegrity_testbed::report::ScenarioReport, n: &str) -> P3 {
    let s = &r.points[0].simulated;
    [s[&format!("{n}.x")], s[&format!("{n}.y")], s[&format!("{n}.z")]]
}

pub fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: P3, b: P3) -> P3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub fn norm(a: P3) -> f64 {
    dot(a, a).sqrt()
}

/// Line and column (from 1) of byte `offset` of `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset];
    (before.matches('\n').count() + 1, before.rsplit('\n').next().unwrap().chars().count() + 1)
}

/// Parses `text` (a variant of a scenario file) and asserts that it fails with a message
/// containing `msg`, located at the first occurrence of `at` in the text plus `shift` bytes.
pub fn error_at(text: &str, at: &str, shift: usize, msg: &str) {
    let err = tensegrity_testbed::scenario::parse(std::path::Path::new("variant.toml"), text).expect_err(msg);
    let offset = text.find(at).unwrap_or_else(|| panic!("'{at}' in the variant")) + shift;
    let (line, col) = line_col(text, offset);
    assert_eq!((err.line, err.col), (line, col), "{msg}: {err}");
    assert!(err.message.contains(msg), "{err}");
    assert!(err.to_string().starts_with(&format!("variant.toml:{line}:{col}: ")), "{err}");
}

/// Every `.rs` file under `dir` (at any depth), sorted.
pub fn rust_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// Set (to 1) where no test may skip a check: `.ci/run` sets it, so a CI run skips nothing (no
/// MuJoCo, pandas or pyarrow, no root for a tmpfs: the test fails); elsewhere a check that
/// cannot run is skipped, saying so on stderr.
pub const NO_SKIPS_VAR: &str = "TENSEGRITY_NO_SKIPS";

/// How many checks this run of the suite has skipped so far.
static SKIPPED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Skips `check` because of `why`, or fails where [`NO_SKIPS_VAR`] is set. The line goes to the
/// process's stderr itself, past the test harness's capture (which hides what passing tests
/// print), counted: `cargo test` shows every skip, named, as it happens.
pub fn skip(check: &str, why: &str) {
    use std::io::Write as _;
    assert!(std::env::var(NO_SKIPS_VAR).is_err(), "{check}: {why}, and {NO_SKIPS_VAR} forbids skipping it");
    let n = SKIPPED.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
    // The harness names each test's thread after the test.
    let test = std::thread::current().name().map_or(check.to_string(), str::to_string);
    let _ = writeln!(std::io::stderr().lock(), "SKIPPED (skip {n} of this run) {test}: {why}");
}

/// The Python (`TENSEGRITY_PYTHON`, else `python3`) that imports every one of `modules`, or
/// None after [`skip`]ping `check`.
pub fn peer_python(modules: &[&str], check: &str) -> Option<String> {
    let py = std::env::var("TENSEGRITY_PYTHON").unwrap_or_else(|_| "python3".into());
    let import = format!("import {}", modules.join(", "));
    let ok = Command::new(&py).args(["-c", &import]).output().is_ok_and(|o| o.status.success());
    if !ok {
        let why = format!("no Python with `{import}` (set TENSEGRITY_PYTHON, or pip install -r benches/peers/mujoco/requirements.txt -r benches/peers/musclepy/requirements.txt pandas pyarrow)");
        skip(check, &why);
    }
    ok.then_some(py)
}

/// How long a test waits for an event or a command before it fails [s]: a guard against a hang
/// on any machine, loaded or not, never a speed target (speeds are the benchmarks').
pub const HANG_GUARD_S: u64 = 60;

/// Polls `ready` every 10 ms until it holds; fails the test, naming `what`, when it has not
/// after [`HANG_GUARD_S`].
pub fn wait_for(what: &str, mut ready: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(HANG_GUARD_S);
    while !ready() {
        if std::time::Instant::now() > deadline {
            panic!("no {what} within the {HANG_GUARD_S} s hang guard");
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// Whether process `pid` has started its command: it catches SIGINT and SIGTERM (bits 2 and 15
/// of `SigCgt` in /proc/PID/status, set by `install_handlers`) and runs the command's thread
/// beside its main thread (/proc/PID/task), which it starts after the handlers.
pub fn runs_its_command(pid: u32) -> bool {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    let caught = status
        .lines()
        .find_map(|l| l.strip_prefix("SigCgt:"))
        .and_then(|hex| u64::from_str_radix(hex.trim(), 16).ok())
        .unwrap_or(0);
    let both = (1u64 << (2 - 1)) | (1u64 << (15 - 1));
    let threads = std::fs::read_dir(format!("/proc/{pid}/task")).map(|d| d.count()).unwrap_or(0);
    caught & both == both && threads >= 2
}

/// Sends `signal` ("INT", "TERM") to process `pid`.
pub fn send_signal(signal: &str, pid: u32) {
    let sent = Command::new("kill").args([&format!("-{signal}"), &pid.to_string()]).status().expect("kill runs");
    assert!(sent.success(), "kill -{signal} {pid}");
}

/// Like [`tensegrity`], but fails the test (killing the command) when it has not ended after
/// [`HANG_GUARD_S`]: for commands whose promise is to give an answer rather than hang.
pub fn tensegrity_guarded(args: &[&str]) -> (i32, String, String) {
    let child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("binary runs");
    let pid = child.id();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(child.wait_with_output()));
    let Ok(out) = rx.recv_timeout(std::time::Duration::from_secs(HANG_GUARD_S)) else {
        send_signal("KILL", pid);
        panic!("{args:?} did not end within the {HANG_GUARD_S} s hang guard");
    };
    let out = out.expect("the command's output");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
