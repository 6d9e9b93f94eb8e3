//! Helpers shared by the test binaries.

use std::process::Command;

/// Runs the `tensegrity` binary: (exit code, stdout, stderr).
#[allow(dead_code)]
pub fn tensegrity(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity")).args(args).output().expect("binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Loads and runs a scenario file through the library, with the default options.
#[allow(dead_code)]
pub fn run_file(path: &str) -> tensegrity_testbed::report::ScenarioReport {
    let sc = tensegrity_testbed::scenario::load(std::path::Path::new(path)).expect("scenario is valid");
    tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default())
}
