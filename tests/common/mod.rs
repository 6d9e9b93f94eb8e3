//! Helpers shared by the test binaries.

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
