//! Fuzzing the scenario parser and validator: random mutations of the corpus scenarios in
//! `tests/fuzz_corpus/` must give `Ok` or a located error, never a panic; a scenario that
//! parses must build a structure and a simulation without panicking. Numbers are also mutated
//! into extremes (1e300, 1e-300, subnormals), and each case must give an answer (no hang in
//! parsing, validation or the analytic checks it runs: a case still running after
//! `common::HANG_GUARD_S` fails as a hang).
//!
//! The test suite runs a few hundred cases. The long run (documented in `docs/testing.md`):
//! `PROPTEST_CASES=1000000 cargo test --release --test it fuzz_scenarios` (stop it after 10
//! minutes or more; any failing input is saved under `proptest-regressions/`).

use proptest::prelude::*;
use std::path::Path;
use tensegrity_testbed::scenario;
use tensegrity_testbed::sim::Simulation;

fn corpus() -> Vec<String> {
    let mut files: Vec<_> =
        std::fs::read_dir("tests/fuzz_corpus").unwrap().filter_map(|e| e.ok()).map(|e| e.path()).collect();
    files.sort();
    files.iter().map(|p| std::fs::read_to_string(p).unwrap()).collect()
}

/// Tokens that stress the parser and the validator.
const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1.0",
    "0",
    "0.0",
    "1e309",
    "-1e-300",
    "1e300",
    "-1e300",
    "1e-300",
    "5e-324",
    "1e-320",
    "2.2250738585072014e-308",
    "1e100",
    "-1e100",
    "1e80",
    "\"x\"",
    "[",
    "]",
    "{",
    "}",
    "=",
    ",",
    "\n",
    "[[checks]]",
    "[actuation]",
    "[sim]",
    "[params]",
    "[start]",
    "[interference]",
    "[workspace]",
    "t = ",
    "points = []",
    "grid = {}",
    "waypoints = [",
    "quantity = \"zeta\"",
    "mechanism = \"mohr2011\"",
    "mechanism = \"furet2018\"",
    "mechanism = \"manriquez2019\"",
    "straight = 1.0",
    "count = 0",
    "count = 100000",
    "skip_outside = true",
    "dt = 1e-300",
    "pgs_iterations = 0",
    "approach_pgs_iterations = 4096",
    "\u{0}",
    "é",
    "#",
];

#[derive(Clone, Debug)]
enum Mutation {
    Delete { at: usize, len: usize },
    Insert { at: usize, token: usize },
    ReplaceNumber { which: usize, token: usize },
    SwapLines { a: usize, b: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(which, token)| Mutation::ReplaceNumber { which, token }),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapLines { a, b }),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let chars: Vec<char> = text.chars().collect();
    let n = chars.len().max(1);
    match m {
        Mutation::Delete { at, len } => {
            let a = at % n;
            let b = (a + len).min(chars.len());
            chars[..a].iter().chain(&chars[b..]).collect()
        }
        Mutation::Insert { at, token } => {
            let a = at % n;
            let mut s: String = chars[..a.min(chars.len())].iter().collect();
            s.push_str(TOKENS[*token]);
            s.extend(&chars[a.min(chars.len())..]);
            s
        }
        Mutation::ReplaceNumber { which, token } => {
            // Replace the which-th number-looking word.
            let words: Vec<(usize, usize)> = text
                .char_indices()
                .filter(|(i, c)| c.is_ascii_digit() && (*i == 0 || !text.as_bytes()[i - 1].is_ascii_alphanumeric()))
                .map(|(i, _)| {
                    (
                        i,
                        text[i..]
                            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
                            .map_or(text.len(), |e| i + e),
                    )
                })
                .collect();
            if words.is_empty() {
                return text.to_string();
            }
            let (a, b) = words[which % words.len()];
            format!("{}{}{}", &text[..a], TOKENS[*token], &text[b..])
        }
        Mutation::SwapLines { a, b } => {
            let mut lines: Vec<&str> = text.lines().collect();
            if lines.len() > 1 {
                let (i, j) = (a % lines.len(), b % lines.len());
                lines.swap(i, j);
            }
            lines.join("\n")
        }
    }
}

/// Parses and validates `text` on a thread of its own: its answer, or why there is none
/// ("panicked", or "hung" when it still runs after the hang guard; validation solves the
/// analytic model at every point, and a hang at a target of 1e100 m was found this way).
fn parse_guarded(text: String) -> Result<Result<scenario::Scenario, scenario::ScenarioError>, &'static str> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(scenario::parse(Path::new("fuzz.toml"), &text));
    });
    rx.recv_timeout(std::time::Duration::from_secs(super::common::HANG_GUARD_S)).map_err(|e| match e {
        std::sync::mpsc::RecvTimeoutError::Timeout => "hung",
        std::sync::mpsc::RecvTimeoutError::Disconnected => "panicked",
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: Some(Box::new(proptest::test_runner::FileFailurePersistence::WithSource("regressions"))), ..ProptestConfig::default() })]

    #[test]
    fn mutated_scenarios_never_panic(seed in 0usize..1000, muts in proptest::collection::vec(mutation(), 1..6)) {
        let corpus = corpus();
        let mut text = corpus[seed % corpus.len()].clone();
        for m in &muts {
            text = apply(&text, m);
        }
        let parsed = parse_guarded(text.clone());
        prop_assert!(parsed.is_ok(), "check {} on:\n{}", parsed.as_ref().err().unwrap_or(&""), text);
        match parsed.unwrap() {
            Err(e) => {
                // Every error is located.
                prop_assert!(e.to_string().starts_with("fuzz.toml:"), "{}", e);
            }
            Ok(sc) => {
                // The scenario's mechanism: a built-in one or its own [structure].
                let m = sc.mechanism();
                let inputs = match &sc.actuation {
                    scenario::Actuation::Points { points, .. } => points[0].clone(),
                    scenario::Actuation::Schedule { waypoints } => waypoints[0].1.clone(),
                };
                if let Ok(s) = m.build(&sc.params, &inputs, &sc.start) {
                    let _ = Simulation::new(&s, &sc.sim);
                }
            }
        }
    }
}
