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

/// Loads and runs a scenario file through the library, with the default options.
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
