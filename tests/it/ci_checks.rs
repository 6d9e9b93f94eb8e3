//! `.ci/run` runs the Rust ecosystem's own checks (rustfmt, clippy and rustdoc, warnings as
//! errors) before the README's test command, under `set -euo pipefail` so that each fails the
//! run. The checks themselves run there, not here: this only keeps them from being dropped.

#[test]
fn ci_runs_fmt_clippy_and_rustdoc_before_the_tests() {
    let script = std::fs::read_to_string(".ci/run").expect(".ci/run");
    assert!(script.contains("set -euo pipefail"), ".ci/run must stop at the first failure");
    let line = |wanted: &str| {
        script.lines().position(|l| l.trim() == wanted).unwrap_or_else(|| panic!(".ci/run lacks the line `{wanted}`"))
    };
    let tests = line("cargo test --release");
    for check in [
        "cargo fmt --all --check",
        "cargo clippy --release --all-targets --workspace -- -D warnings",
        "RUSTDOCFLAGS=\"-D warnings\" cargo doc --release --no-deps --workspace",
    ] {
        assert!(line(check) < tests, "`{check}` must run before the tests");
    }
}
