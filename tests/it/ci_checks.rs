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

/// CI skips no check: `.ci/run` requires the peers' venv (no `|| echo` around its install) and
/// sets `TENSEGRITY_NO_SKIPS` before the tests, under which `common::skip` fails a test.
#[test]
fn ci_requires_every_peer_and_forbids_skips() {
    let script = std::fs::read_to_string(".ci/run").expect(".ci/run");
    let tests = script.lines().position(|l| l.trim() == "cargo test --release").expect("the test command");
    let no_skips = format!("export {}=1", crate::common::NO_SKIPS_VAR);
    let at = script.lines().position(|l| l.trim() == no_skips).expect(".ci/run exports TENSEGRITY_NO_SKIPS=1");
    assert!(at < tests, "TENSEGRITY_NO_SKIPS must be set before the tests");
    assert!(!script.contains("will skip") && !script.contains("|| echo"), "an install failure must fail CI");
}

/// No test returns early saying it skipped unless through `common::skip` (which CI turns into a
/// failure): a bare `eprintln!("skipped ...")` followed by `return` would pass silently.
#[test]
fn every_skip_goes_through_common_skip() {
    for file in crate::common::rust_files(std::path::Path::new("tests/it")) {
        let text = std::fs::read_to_string(&file).unwrap();
        if file.ends_with("common.rs") || file.ends_with("ci_checks.rs") {
            continue;
        }
        for (k, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            assert!(
                !(lower.contains("eprintln!(\"skipped") || lower.contains("println!(\"skipped")),
                "{}:{}: a skip that CI cannot see: use common::skip",
                file.display(),
                k + 1
            );
        }
    }
}
