//! The hostile suite, one test per class of input that used to misbehave (issue 30): checks
//! that cannot fail, names that mean something else, values that invert a meaning, outputs
//! that lie, work before validation, unbounded resources, signals and flags. Every input is
//! written here; every refusal is asserted as exit 2 with its `file:LINE:COL` and its words,
//! every bounded behaviour by what it refuses or leaves behind (never by wall time).

use crate::common::{line_col, tensegrity, PINNED_STRUT};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The bar of `scenarios/custom/pinned_bar_sweep.toml`: parameters, a grid over k1, a joint
/// probe, an energy model.
const SWEEP_FILE: &str = "scenarios/custom/pinned_bar_sweep.toml";

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tensegrity-hostile-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn sweep_text() -> String {
    std::fs::read_to_string(SWEEP_FILE).unwrap()
}

/// Writes `text` as `d/NAME.toml`, runs `tensegrity check` on it and asserts exit 2 with the
/// error at the first occurrence of `at` (plus `shift` bytes) and `msg` in its message.
fn refused_at(d: &Path, name: &str, text: &str, at: &str, shift: usize, msg: &str) {
    let p = d.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    let (code, _, err) = tensegrity(&["check", p.to_str().unwrap()]);
    let offset = text.find(at).unwrap_or_else(|| panic!("{name}: '{at}' in the input")) + shift;
    let (line, col) = line_col(text, offset);
    assert_eq!(code, 2, "{name}: {err}");
    assert!(err.contains(&format!("{name}.toml:{line}:{col}: ")), "{name}: expected at {line}:{col}: {err}");
    assert!(err.contains(msg), "{name}: expected '{msg}': {err}");
}

/// A value or a tolerance that would make a comparison that cannot fail (NaN, an infinity,
/// zero against a relative error, a negative tolerance) is bad input where it is written.
#[test]
fn checks_that_cannot_fail() {
    let d = dir("cannot-fail");
    let s = sweep_text();
    for (name, expected, words) in [
        ("probe_nan", "sqrt(-1)", "probe.expected is NaN at the point"),
        ("probe_zero", "0*k1", "probe.expected is 0 at the point"),
        ("probe_inf", "1/(k1-10)", "probe.expected is inf at the point"),
        ("probe_minus_inf", "-1/(k1-10)", "probe.expected is -inf at the point"),
    ] {
        let text = s.replace("\"L*hypot(k1*a, k2*b)\"", &format!("\"{expected}\""));
        refused_at(&d, name, &text, &format!("\"{expected}\""), 0, words);
    }
    let prediction = s.replace("\"atan2(ratio*a, b)\"", "\"sqrt(30-k1)\"");
    let words = "prediction 'q' is NaN at the point {\"k1\": 40.0}: a predicted value is a finite number";
    refused_at(&d, "prediction_nan", &prediction, "\"sqrt(30-k1)\"", 0, words);
    let modes = std::fs::read_to_string("scenarios/custom/pinned_bar_modes.toml").unwrap();
    let frequency = modes.replace("\"sqrt(L*hypot(k1*a, k2*b)/I)\"", "\"50-k1\"");
    let words = "frequency 'omega' is 0 rad/s at the point {\"k1\": 50.0}: a frequency is finite and > 0";
    refused_at(&d, "frequency_zero", &frequency, "\"50-k1\"", 0, words);
    let nan_tolerance = s.replacen("tolerance = 1e-9", "tolerance = nan", 1);
    refused_at(&d, "tolerance_nan", &nan_tolerance, "nan\n", 0, "must be a finite number, got NaN");
    let negative = s.replacen("tolerance = 1e-9", "tolerance = -1e-9", 1);
    refused_at(&d, "tolerance_negative", &negative, "-1e-9", 0, "must be > 0, got -0.000000001");
    let inf_value = PINNED_STRUT
        .replace("[structure]", "[[checks]]\nquantity = \"k.force\"\nvalue = inf\ntolerance = 1e-6\n[structure]");
    refused_at(&d, "value_inf", &inf_value, "inf\n", 0, "value must be a finite number, got inf");
    std::fs::remove_dir_all(&d).ok();
}

/// A name that the expressions already read otherwise, an empty name, a name that spells
/// another symbol, and a name defined twice (the error names both places).
#[test]
fn names_that_mean_something_else() {
    let d = dir("names");
    let with_params = |params: &str| PINNED_STRUT.replace("[actuation]", &format!("[params]\n{params}\n[actuation]"));
    for (name, param, words) in [
        ("param_pi", "pi = 3.0", "parameter 'pi' is a built-in constant of the expressions"),
        ("param_e", "e = 2.0", "parameter 'e' is a built-in constant of the expressions"),
        ("param_sin", "sin = 1.0", "parameter 'sin' is a built-in function of the expressions"),
        ("param_t", "t = 1.0", "parameter 't' is the time symbol of the expressions"),
        ("param_empty", "\"\" = 1.0", "a parameter needs a name, got ''"),
        ("param_coordinate", "\"Q.x\" = 1.0", "parameter 'Q.x' must be an identifier"),
        ("param_force", "\"k.force\" = 1.0", "parameter 'k.force' must be an identifier"),
    ] {
        let text = with_params(param);
        refused_at(&d, name, &text, param, 0, words);
    }
    // An actuator's symbol equal to a parameter's: the second place, naming the first.
    let actuated = with_params("q = 0.5")
        .replace("damping = 0.5\n", "damping = 0.5\n[[structure.actuators]]\nsymbol = \"q\"\njoint = \"pin\"\n");
    let (line, col) = line_col(&actuated, actuated.find("q = 0.5").unwrap());
    let words = format!("duplicate name 'q': this actuator symbol and the parameter at {line}:{col}");
    refused_at(&d, "actuator_is_param", &actuated, "\"q\"\njoint", 0, &words);
    // A group's generated name equal to a cable of the member table.
    let grouped = PINNED_STRUT.to_string()
        + "[[structure.cables]]\nname = \"g:Q-S\"\na = \"Q\"\nb = \"S\"\n[[structure.cable_groups]]\nname = \"g\"\npairs = [[\"Q\", \"S\"]]\n";
    let (line, col) = line_col(&grouped, grouped.find("\"g:Q-S\"").unwrap());
    let words = format!("duplicate name 'g:Q-S': this cable of group 'g' and the cable at {line}:{col}");
    refused_at(&d, "group_name_twice", &grouped, "[\"Q\", \"S\"]]", 0, &words);
    // A quantity of the file's model named like a constant.
    let quantity = PINNED_STRUT.to_string() + "[[quantities]]\nname = \"e\"\nexpr = \"Q.x\"\n";
    refused_at(&d, "quantity_e", &quantity, "\"e\"", 0, "quantity 'e' is a built-in constant");
    std::fs::remove_dir_all(&d).ok();
}

/// Values that would turn a meaning around: a parameter that follows a swept one to an
/// infinity, a negative interference threshold, an analytic solve that overflows.
#[test]
fn values_that_invert_a_meaning() {
    let d = dir("invert");
    let s = sweep_text();
    let text = s.replace("ratio = { value = \"k1/k2\"", "ratio = { value = \"k2/(k1-10)\"");
    refused_at(&d, "derived_inf", &text, "\"k2/(k1-10)\"", 0, "parameter 'ratio' is inf at the point");
    let text = PINNED_STRUT.replace("[actuation]", "[interference]\nthreshold = -0.5\n[actuation]");
    refused_at(&d, "threshold_negative", &text, "-0.5", 0, ">= 0 m");
    for (query, words) in [
        (vec!["ji2014", "fk", "--set", "L3=1e300", "--set", "theta1=0.3"], "gives F_K1 = inf"),
        (vec!["mohr2011", "statics", "--set", "x=1e300", "--set", "y=0.8", "--set", "z=1.5"], "gives f1 = NaN"),
    ] {
        let (code, out, err) = tensegrity(&[&["solve"], &query[..]].concat());
        assert_eq!(code, 2, "{query:?}: {out}{err}");
        assert!(err.contains(words) && err.contains("outside the range where the model is a number"), "{err}");
        assert!(out.is_empty(), "nothing printed: {out}");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// Outputs that would lie: shards of two different sweeps merged into one, an import that
/// would write an infinity, an interrupted sweep over an earlier complete CSV.
#[test]
fn outputs_that_lie() {
    let d = dir("lie");
    let (a, b, merged) = (d.join("a.csv"), d.join("b.csv"), d.join("merged.csv"));
    let sweep = |shard: &str, set: &str, out: &Path| {
        let args = ["sweep", SWEEP_FILE, "--shard", shard, "--set", set, "--jobs", "1", "--out", out.to_str().unwrap()];
        let (code, _, err) = tensegrity(&args);
        assert_eq!(code, 0, "{err}");
    };
    sweep("1/2", "k2=30", &a);
    sweep("2/2", "k2=35", &b);
    let (code, _, err) =
        tensegrity(&["merge", a.to_str().unwrap(), b.to_str().unwrap(), "--out", merged.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!(
            "{}:2: a row of another sweep than {}'s: its parameters differ",
            b.display(),
            a.display()
        )),
        "{err}"
    );
    assert!(!merged.exists(), "nothing written");

    let yaml = d.join("huge.yaml");
    std::fs::write(&yaml, "nodes:\n  a: [0, 0, 0]\n  b: [1e308, -1e308, 1e308]\npair_groups:\n  rod:\n    - [a, b]\nbuilders:\n  rod:\n    class: tgRodInfo\n    parameters:\n      density: 1.0\n      radius: 0.01\n").unwrap();
    let toml = d.join("huge.toml");
    let (code, _, err) = tensegrity(&["import", "ntrt", yaml.to_str().unwrap(), "--out", toml.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("too large (or not numbers) to write"), "{err}");
    assert!(!toml.exists(), "no scenario with inf or NaN written");
    std::fs::remove_dir_all(&d).ok();
}

/// Work that used to run before the input was known to be valid: a grid of 40,000 sets of
/// parameters (refused from its counts), energy scans whose product passes the bound, a
/// sweep's unknown `--x` axis.
#[test]
fn work_before_validation() {
    let d = dir("before");
    let s = sweep_text();
    let grid = s.replace(
        "grid = { k1 = { from = 10.0, to = 90.0, count = 9 } }",
        "grid = { k1 = { from = 10.0, to = 90.0, count = 200 }, k2 = { from = 10.0, to = 90.0, count = 200 } }",
    );
    refused_at(&d, "sets", &grid, "[actuation]", 0, "the actuation asks for 40000 sets of parameters; at most 10000");
    let points: Vec<String> = (0..10_001).map(|i| format!("{{ k1 = {} }}", 10.0 + i as f64 * 1e-3)).collect();
    let listed = s.replace(
        "grid = { k1 = { from = 10.0, to = 90.0, count = 9 } }",
        &format!("points = [ {} ]", points.join(", ")),
    );
    refused_at(&d, "listed_sets", &listed, "[actuation]", 0, "asks for more than 10000 sets of parameters");
    let scans = s.replace("count = 4 }", "count = 4 }\n[[energy.coordinates]]\nname = \"q2\"\nmeasured = \"q\"\nclass = \"angle\"\nscan = { from = -3.0, to = 3.0, count = 5000 }");
    refused_at(&d, "scans", &scans, "count = 5000", 8, "the scans ask for 20000 Newton starts together");
    let terms: Vec<String> = (1..12).map(|i| format!("sin(qe*{i})^2")).collect();
    let heavy = s.replacen("count = 4 }", "count = 10000 }", 1).replacen(
        "potential = \"",
        &format!("potential = \"{}+", terms.join("+")),
        1,
    );
    refused_at(&d, "scan_work", &heavy, "\"sin(qe*1)", 0, "Newton starts times the");
    assert!(heavy.contains("count = 10000 }"));
    let (code, _, err) =
        tensegrity(&["sweep", SWEEP_FILE, "--figure", d.join("f.png").to_str().unwrap(), "--x", "nope"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--x nope: not an axis of this sweep"), "{err}");
    assert!(!d.join("f.png").exists());
    std::fs::remove_dir_all(&d).ok();
}

/// Inputs whose cost had no bound: long and deep expressions, derivatives that grow, YAML
/// aliases, a second YAML document, endless or blocking files.
#[test]
fn unbounded_resources() {
    let d = dir("unbounded");
    let param = |expr: &str| PINNED_STRUT.replace("[actuation]", &format!("[params]\na = \"{expr}\"\n[actuation]"));
    let long = vec!["1"; 20_000].join("+");
    refused_at(&d, "long", &param(&long), "a = ", 5, "an expression has at most 10000 bytes, this one 39999");
    let deep = format!("{}1{}", "(".repeat(4000), ")".repeat(4000));
    refused_at(&d, "deep", &param(&deep), "a = ", 4 + 1 + 64, "nested deeper than 64 levels");
    let signs = format!("{}1", "-".repeat(5000));
    refused_at(&d, "signs", &param(&signs), "a = ", 4 + 1 + 64, "nested deeper than 64 levels");
    let powers = vec!["2"; 1000].join("^");
    refused_at(&d, "powers", &param(&powers), "a = ", 4 + 1 + 64 * 2, "nested deeper than 64 levels");
    // Derivatives are taken forward (one pass over the expression per value, no derivative
    // text): a product of 50 sines and a sum of 800, which the symbolic engine had refused or
    // overflowed on, are read (a product's potential has no stationary point near the start, so
    // `check` alone), and the sum of 800 runs.
    let modes = std::fs::read_to_string("scenarios/custom/pinned_bar_modes.toml").unwrap();
    for (name, terms, join) in [("product50", 50, "*"), ("sum800", 800, "+")] {
        let terms: Vec<String> = (0..terms).map(|i| format!("sin(qe+{i})")).collect();
        let text = modes.replace("\"-k1*a*L*sin(qe) - k2*b*L*cos(qe)\"", &format!("\"{}\"", terms.join(join)));
        let p = d.join(format!("{name}.toml"));
        std::fs::write(&p, text).unwrap();
        let (code, out, err) = tensegrity(&["check", p.to_str().unwrap()]);
        assert_eq!(code, 0, "{name}: {out}{err}");
    }

    let import = |file: &Path| tensegrity(&["import", "ntrt", file.to_str().unwrap()]);
    let mut laughs = String::from("a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n");
    for i in 1..12 {
        let refs = vec![format!("*a{}", i - 1); 10].join(", ");
        laughs.push_str(&format!("a{i}: &a{i} [{refs}]\n"));
    }
    let yaml = d.join("laughs.yaml");
    std::fs::write(&yaml, &laughs).unwrap();
    let (code, _, err) = import(&yaml);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("laughs.yaml:6:45: the document expands to more than 1000000 nodes"), "{err}");
    let two = d.join("two.yaml");
    std::fs::write(&two, "nodes:\n  a: [0, 0, 0]\n---\nnodes:\n  b: [1, 0, 0]\n").unwrap();
    let (code, _, err) = import(&two);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("two.yaml:3:1: a second YAML document"), "{err}");

    let fifo = d.join("fifo.yaml");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let (code, _, err) = import(&fifo);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("a pipe, socket or device, not a regular file"), "{err}");
    let (code, _, err) = tensegrity(&["check", fifo.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("fifo.yaml:1:1: the scenario file: cannot read: a pipe"), "{err}");
    let (code, _, err) = tensegrity(&["check", "/dev/zero"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a regular file"), "{err}");
    let big = d.join("big.yaml");
    std::fs::write(&big, "#".repeat((16 << 20) + 1)).unwrap();
    let (code, _, err) = import(&big);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("at most 16777216 bytes"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

// Signals: SIGINT and SIGTERM to a sweep (the earlier CSV kept, the partial one whole) are
// `interrupts::an_interrupted_sweep_writes_the_rows_it_has`, one test for both.

/// Flags and shapes that meant nothing: zero jobs, a zero recording interval, a table of an
/// unknown kind, a stability of the wrong shape (in the file's words, not a parser's).
#[test]
fn flags() {
    let d = dir("flags");
    let quick = "scenarios/ji2014/quick.toml";
    for (args, words) in [
        (vec!["sweep", SWEEP_FILE, "--jobs", "0"], "--jobs"),
        (vec!["run", quick, "--record-every", "0"], "--record-every"),
        (vec!["run", quick, "--table", "/tmp/x.txt"], "--table"),
    ] {
        let (code, _, err) = tensegrity(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(words), "{args:?}: {err}");
    }
    let text = PINNED_STRUT.replace("[actuation]", "[stability]\nperturbation = 0.01\nexpect = 3\n[actuation]");
    refused_at(&d, "stability_number", &text, "3\n[actuation]", 0, "\"stable\", \"unstable\", \"energy\", or a list");
    let p = d.join("stability_number.toml");
    let (_, _, err) = tensegrity(&["check", p.to_str().unwrap()]);
    assert!(!err.contains("untagged") && !err.contains("Raw"), "{err}");
    for (name, section, at, words) in [
        ("dt_text", "[sim]\ndt = \"a\"", "\"a\"", "invalid type: string \"a\", expected a number"),
        ("substeps_fraction", "[sim]\nsubsteps = 1.5", "1.5", "expected a whole number"),
        ("points_number", "", "3\n", "expected a list [...]"),
    ] {
        let text = PINNED_STRUT.replace("[actuation]", &format!("{section}\n[actuation]"));
        let text = if section.is_empty() { text.replace("points = [ {} ]", "points = 3\n") } else { text };
        refused_at(&d, name, &text, at, 0, words);
        let (_, _, err) = tensegrity(&["check", d.join(format!("{name}.toml")).to_str().unwrap()]);
        assert!(!err.contains("f64") && !err.contains("i64") && !err.contains("sequence"), "{err}");
    }
    std::fs::remove_dir_all(&d).ok();
}

// Issue 46, the third pass: whole numbers in checked arithmetic, the work of `check` bounded,
// standard output that cannot be written, flags twice, figure paths before any work.

/// The regular n-strut prism, whose patterns are rewritten below.
const PRISM_N: &str = "scenarios/custom/prism_n.toml";

/// A range's length, a template's quotient, remainder, product or negation past the 64-bit
/// whole numbers is refused where it is written (it had panicked with a capacity overflow or
/// an integer overflow, or wrapped into a name).
#[test]
fn whole_numbers_past_64_bits() {
    let d = dir("whole");
    let s = std::fs::read_to_string(PRISM_N).unwrap();
    let huge = "-9000000000000000000..9000000000000000000";
    let repeat = s.replacen("for = { i = \"0..n\" }", &format!("for = {{ i = \"{huge}\" }}"), 1);
    refused_at(&d, "repeat_range", &repeat, huge, 0, "at most 10000 entries");
    let looped = s.replace(
        "for = { i = \"1..n\" }\nname = \"strut_to_side{i}\"",
        &format!("for = {{ i = \"{huge}\" }}\nname = \"strut_to_side{{i}}\""),
    );
    refused_at(&d, "looped_range", &looped, huge, 0, "at most 10000 entries");
    let summed = s.replacen("sum(i in 0..n, B{i}.x)", &format!("sum(i in {huge}, B{{i}}.x)"), 1);
    refused_at(&d, "sum_range", &summed, huge, 0, "at most 10000 entries");
    let min = "(-9223372036854775807-1)";
    for (name, template, shift) in [
        ("quotient", format!("{min}/-1"), min.len()),
        ("remainder", format!("{min} mod -1"), min.len() + 1),
        ("product", format!("{min}*2"), min.len()),
        ("negation", format!("-{min}"), 0),
    ] {
        let text = s.replacen("name = \"bottom{i}\"", &format!("name = \"bottom{{{template}}}\""), 1);
        let at = format!("{{{template}}}");
        refused_at(&d, name, &text, &at, 1 + shift, "whole number out of range");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// What `check` expands is bounded before it is spent: 9,900 looped sums of 450 terms (they
/// had taken 27.6 s and 7.4 GB), and a topology sweep over 1,000 prisms, are refused at the
/// entry that passes the bound.
#[test]
fn expanded_work_is_bounded() {
    let d = dir("expanded");
    let s = std::fs::read_to_string(PRISM_N).unwrap();
    let sums = "[[quantities]]\nfor = { j = \"0..9900\" }\nname = \"big{j}\"\nexpr = \"sum(i in 0..450, B{i mod n}.x + {j})\"\n";
    let text = s.replacen("[[predictions]]", &format!("{sums}\n[[predictions]]"), 1);
    let words = "the patterns expand past 2097152 bytes of names and expressions";
    refused_at(&d, "looped_sums", &text, "\"sum(i in 0..450", 1, words);
    let topologies = s.replace("count = 10 }", "count = 1000 }").replace("to = 12,", "to = 1002,");
    let topologies = topologies.replace("n_max = { value = 17,", "n_max = { value = 1002,");
    let p = d.join("topologies.toml");
    std::fs::write(&p, &topologies).unwrap();
    let (code, _, err) = tensegrity(&["check", p.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("topologies.toml:") && err.contains(words), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// Runs the binary with its standard output on `/dev/full` or closed (`>&-`).
fn with_stdout(how: &str, args: &[&str]) -> (i32, String) {
    let bin = env!("CARGO_BIN_EXE_tensegrity");
    let redirect = if how == "full" { ">/dev/full" } else { ">&-" };
    let script = format!("exec \"$0\" \"$@\" {redirect}");
    let out = Command::new("sh").arg("-c").arg(script).arg(bin).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Standard output that cannot be written (full, closed) fails the command with exit 1 and
/// its message, for every command that writes there; never a panic, never a silent exit 0.
#[test]
fn standard_output_that_cannot_be_written() {
    let quick = "scenarios/custom/prism3.toml";
    for how in ["full", "closed"] {
        for args in [
            vec!["list"],
            vec!["check", quick],
            vec!["run", quick, "--json", "-"],
            vec!["sweep", SWEEP_FILE, "--jobs", "1", "--out", "-"],
            vec!["modes", quick],
            vec!["equilibrium", quick],
            vec!["sensitivity", "scenarios/custom/pinned_bar_modes.toml"],
            vec!["solve", "mohr2011", "ikp", "--set", "x=0", "--set", "y=0", "--set", "z=1"],
            vec![
                "fit",
                "scenarios/custom/pinned_bar_sweep.toml",
                "--data",
                "tests/fixtures/fit/pinned_bar_angles.csv",
                "--param",
                "k2=1:100",
            ],
            vec!["attribute", "tests/fixtures/attribution/hanging_bar.toml"],
        ] {
            let (code, err) = with_stdout(how, &args);
            assert_eq!(code, 1, "{how} {args:?}: {err}");
            let words = if how == "full" { "writing to standard output" } else { "standard output is closed" };
            assert!(err.contains(words) && !err.contains("panicked"), "{how} {args:?}: {err}");
        }
    }
}

/// The class behind the test above, kept closed: no source file but the command line's own
/// `cli/mod.rs` (`print_out`, the one checked writer) prints to standard output or takes it;
/// code under `#[cfg(test)]` aside. `fit` and `sensitivity` had printed with `print!` and
/// panicked on a full standard output.
#[test]
fn only_the_checked_writer_writes_standard_output() {
    let mut offenders = Vec::new();
    let mut dirs = vec![std::path::PathBuf::from("src")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") || path.ends_with("src/cli/mod.rs") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let code = text.split("#[cfg(test)]").next().unwrap_or("");
            for (n, line) in code.lines().enumerate() {
                let line = line.split("//").next().unwrap_or("");
                if ["print!(", "println!(", "io::stdout()", "stdout().lock"].iter().any(|w| line.contains(w))
                    && !line.contains("eprint")
                {
                    offenders.push(format!("{}:{}: {}", path.display(), n + 1, line.trim()));
                }
            }
        }
    }
    assert!(offenders.is_empty(), "standard output outside the checked writer:\n{}", offenders.join("\n"));
}

/// A /dev/null the caller opened read-write for standard output (Python's
/// `subprocess.DEVNULL`) is a place the caller chose: a passing run exits 0 (it had exited 1,
/// taken for a closed standard output, which Rust's runtime also fills with /dev/null).
#[test]
fn a_passing_run_into_a_read_write_dev_null_exits_0() {
    let null = std::fs::OpenOptions::new().read(true).write(true).open("/dev/null").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["run", "scenarios/custom/prism3.toml"])
        .stdout(null)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

/// `--set` of one name twice is refused with both flags named (the last had won in silence).
#[test]
fn a_name_set_twice() {
    let (code, _, err) = tensegrity(&["check", SWEEP_FILE, "--set", "k2=10", "--set", "k2=20"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--set k2=10 and --set k2=20: 'k2' is set twice"), "{err}");
    let (code, _, err) = tensegrity(&["solve", "mohr2011", "dkp", "--set", "lb=1", "--set", "lb=2"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--set lb=2: 'lb' is set twice"), "{err}");
}

/// A figure whose folder cannot be made is refused before any point is settled, as any output
/// is; a missing folder is made, as for `--out`.
#[test]
fn a_figure_folder_checked_before_work() {
    let d = dir("figure-folder");
    let file = d.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    let under_file = file.join("f.png");
    let (code, out, err) = tensegrity(&["sweep", SWEEP_FILE, "--figure", under_file.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("{} cannot be written: {} is not a directory", under_file.display(), file.display())),
        "{err}"
    );
    assert!(!out.contains("point(s)"), "nothing settled: {out}");
    let missing = d.join("new").join("f.png");
    let (code, _, err) = tensegrity(&["sweep", SWEEP_FILE, "--jobs", "1", "--figure", missing.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(missing.exists(), "the figure in its new folder");
    std::fs::remove_dir_all(&d).ok();
}

/// A branch whose closed form overflowed is no branch: `dkp` with lb = 1e300 had printed
/// (0, 0, 0) as the z > 0 branch and exited 0.
#[test]
fn an_overflowed_branch_is_refused() {
    let args = ["solve", "mohr2011", "dkp", "--set", "rho1=1", "--set", "rho2=1", "--set", "rho3=1"];
    for lb in ["1e300", "1e155", "-1e300"] {
        let set = format!("lb={lb}");
        let (code, out, err) = tensegrity(&[&args[..], &["--set", &set]].concat());
        assert_eq!(code, 2, "lb = {lb}: {out}{err}");
        assert!(!out.contains("z > 0"), "lb = {lb}: no branch printed: {out}");
    }
}

/// A Lagrangian model stiff against the motion (its kinetic energy scaled by 1e-9: about 5e5
/// rad/s against a 1 ms step, some 50,000 integrator steps a tick) is named at its first
/// compared tick by the bound of 10,000 steps a tick, the run going on without the comparison;
/// it had integrated for about a minute to the integrator's ten million steps (and a signal had
/// had to wait for them, until the integration polled it).
#[test]
fn a_stiff_lagrangian_model_is_named_within_a_tick() {
    let d = dir("stiff");
    let text = crate::common::edited(
        "scenarios/custom/pinned_bar_large_amplitude.toml",
        &[("kinetic = \"0.5*I_pivot*qe_dot^2\"", "kinetic = \"0.5*I_pivot*1e-9*qe_dot^2\"")],
    );
    let p = d.join("stiff.toml");
    std::fs::write(&p, text).unwrap();
    let (code, out, err) = crate::common::tensegrity_guarded(&["run", p.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("more than 10000 a tick: it is stiff against the motion"), "{out}");
    std::fs::remove_dir_all(&d).ok();
}

/// Keys that mean nothing together are refused, the error naming both: a second axis on a
/// joint that has one, an axis on a joint that has none, a rest angle of no torsion spring, a
/// start given twice, a flag that is no flag; a triple of two numbers says so (it had been
/// reported as [0.0, 1.0, NaN]).
#[test]
fn keys_that_mean_nothing_together() {
    let d = dir("together");
    let planar = PINNED_STRUT
        .replace("kind = \"revolute\"", "kind = \"planar_pin\"")
        .replace("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 1.0]\naxis2 = [1.0, 0.0, 0.0]");
    refused_at(&d, "axis2", &planar, "axis2 = [", 8, "axis2 means nothing on a planar_pin joint");
    let spherical = PINNED_STRUT.replace("kind = \"revolute\"", "kind = \"spherical\"");
    refused_at(
        &d,
        "spherical_axis",
        &spherical,
        "[0.0, 0.0, 1.0]\ndamping",
        0,
        "axis means nothing on a spherical joint",
    );
    let rest = PINNED_STRUT.replace("damping = 0.5", "damping = 0.5\ntorsion_rest = 0.3");
    refused_at(&d, "torsion_rest", &rest, "0.3", 0, "torsion_rest means nothing without torsion_stiffness");
    let two = PINNED_STRUT.replace("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 1.0]");
    refused_at(
        &d,
        "two_components",
        &two,
        "[0.0, 1.0]",
        0,
        "axis must be three finite numbers [x, y, z], got 2 of them",
    );
    let prism = std::fs::read_to_string(PRISM_N).unwrap();
    let turned = prism.replace("rotate = { axis = [0, 0, 1]", "rotate = { axis = [0, 1]");
    refused_at(
        &d,
        "rotate_axis",
        &turned,
        "[0, 1]",
        0,
        "rotate.axis must be three finite numbers [x, y, z], got 2 of them",
    );
    let quick = std::fs::read_to_string("scenarios/ji2014/quick.toml").unwrap();
    let both = format!("{quick}\n[start]\ntheta2 = 1.0\ntheta2_offset = 0.2\n");
    refused_at(&d, "theta2_twice", &both, "theta2_offset = 0.2", 0, "[start] theta2_offset means nothing with theta2");
    let flag = format!("{quick}\n[start]\nat_unstable_root = 2.0\n");
    refused_at(&d, "flag", &flag, "2.0\n", 0, "at_unstable_root is a flag: 0 or 1, got 2");
    std::fs::remove_dir_all(&d).ok();
}

/// A spin faster than the simulator keeps (rapier clamps a body's turn at pi/4 rad a step, in
/// silence) is refused at its angular velocity, whatever its size up to an overflow; one just
/// under the bound is accepted.
#[test]
fn a_spin_beyond_what_the_simulator_keeps() {
    let d = dir("spin");
    let text = |w: &str| {
        format!(
            "name = \"spin\"\nmechanism = \"custom\"\n[sim]\ndt = 0.01\n[actuation]\npoints = [ {{}} ]\n[structure]\n\
             [[structure.bodies]]\nname = \"top\"\nmass = 1.0\ninertia = [1.0, 2.0, 3.0]\n\
             nodes = {{ XP = [1, 0, 0], XM = [-1, 0, 0], ZP = [0, 0, 1] }}\n\
             [motion]\nduration_s = 0.1\nstart = \"drawn\"\nspin = {{ body = \"top\", angular_velocity = {w} }}\n"
        )
    };
    // pi/4 / 0.01 s = 78.54 rad/s.
    for w in ["[1e300, 0.2, 4.0]", "[1e10, 0.2, 4.0]", "[0.0, 0.0, 78.6]", "[60.0, 60.0, 0.0]"] {
        let words = "the simulator keeps at most pi/4 rad a step, 7.853981633974483e1 rad/s at sim.dt = 0.01 s";
        refused_at(&d, "fast", &text(w), w, 0, words);
    }
    let p = d.join("under.toml");
    std::fs::write(&p, text("[0.0, 0.0, 78.5]")).unwrap();
    let (code, _, err) = tensegrity(&["check", p.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// A run that diverges at its first step (a 1e9 N/m spring at dt = 0.1 s) leaves an earlier
/// complete table as it was (it had been replaced by an empty file) and says so.
#[test]
fn a_run_without_a_tick_leaves_an_earlier_table() {
    let d = dir("no-tick");
    let text = PINNED_STRUT
        .replace("stiffness = 10.0", "stiffness = 1e9")
        .replace("[actuation]", "[sim]\ndt = 0.1\n[actuation]")
        + "\n[motion]\nduration_s = 1.0\nstart = \"drawn\"\n";
    let (p, table) = (d.join("diverges.toml"), d.join("table.csv"));
    std::fs::write(&p, text).unwrap();
    std::fs::write(&table, "tick,earlier\n0,1\n").unwrap();
    let (code, out, err) = tensegrity(&["run", p.to_str().unwrap(), "--table", table.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("simulation diverged at tick 1"), "{out}");
    assert!(err.contains(&format!("no tick ran: the table {} was not written", table.display())), "{err}");
    assert_eq!(std::fs::read_to_string(&table).unwrap(), "tick,earlier\n0,1\n");
    std::fs::remove_dir_all(&d).ok();
}

/// A motion along a rigid-body mode (the prism's modes 1-3 spin its struts about their axes)
/// is refused by name, never judged against a frequency of about 0 rad/s.
#[test]
fn a_motion_along_a_rigid_body_mode_is_refused() {
    let d = dir("rigid-mode");
    let text = crate::common::edited(
        "scenarios/custom/prism3_free_vibration.toml",
        &[
            ("mode = 4              # displaced", "mode = 1              # displaced"),
            ("mode = 4              # fitted", "mode = 2              # fitted"),
        ],
    );
    let p = d.join("rigid.toml");
    std::fs::write(&p, text).unwrap();
    let (code, out, err) = tensegrity(&["run", p.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("mode 1 is a rigid-body mode") && out.contains("choose a mode from 4"), "{out}");
    assert!(!out.contains("frequency lowest mode (cosine fit): predicted -"), "{out}");
    std::fs::remove_dir_all(&d).ok();
}

/// A motion along a mode above the sparse solver's lowest 20 asks it for every mode through
/// that one (the 102-strut prism: 101 free bodies, 606 modes, 102 of them rigid): mode 123,
/// the 21st non-rigid, runs; mode 303 would need 201 non-rigid modes and is refused by name
/// when the motion starts.
#[test]
fn a_motion_along_a_mode_past_the_sparse_solvers_bound_is_refused() {
    let d = dir("sparse-mode");
    let s = std::fs::read_to_string("benches/prism_modes.toml")
        .unwrap()
        .replace("n = { value = 300,", "n = { value = 102,");
    for (mode, computed) in [(303, false), (123, true)] {
        let text = s.replace(
            "[actuation]",
            &format!(
                "[motion]\nduration_s = 0.01\nstart = \"settled\"\nmode = {mode}\namplitude = 1e-6\n\n[actuation]"
            ),
        );
        let p = d.join(format!("mode{mode}.toml"));
        std::fs::write(&p, text).unwrap();
        let (code, out, err) = tensegrity(&["run", p.to_str().unwrap()]);
        let refused = out.contains(
            "the lowest 201 modes beyond the structure's 102 rigid ones were asked for (through mode 303); the sparse solver computes at most 200",
        );
        assert_eq!(refused, !computed, "mode {mode}: {out}{err}");
        if computed {
            assert!(code == 0 && out.contains("mode 123 displaced by 1e-6"), "{out}{err}");
        } else {
            assert_eq!(code, 1, "{out}{err}");
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

/// `--set k=nan` of a parameter a pattern reads is reported at the flag (it had been reported
/// at a range of the structure), and a grid of one point over a pattern's parameter builds
/// the structure of that point (it had built the file's and judged it at the point's n).
#[test]
fn a_topology_parameter_at_its_flag_and_at_its_one_point() {
    let (code, _, err) = tensegrity(&["check", PRISM_N, "--set", "r=nan"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--set r=nan:1:5: parameter 'r' must be a finite number, got NaN"), "{err}");
    let d = dir("one-topology");
    let text = std::fs::read_to_string(PRISM_N)
        .unwrap()
        .replace("from = 3, to = 12, count = 10", "from = 5, to = 5, count = 1");
    let p = d.join("five.toml");
    std::fs::write(&p, text).unwrap();
    let (code, out, err) = tensegrity(&["run", p.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("strut_to_side4"), "five struts built: {out}");
    std::fs::remove_dir_all(&d).ok();
}

/// `prism_n.toml` holds for the n it states (3 to 17) and refuses an n past them where its
/// bound is written (it had claimed any n and settled 2.85 rad off at n = 20 and 40).
#[test]
fn prism_n_refuses_an_n_it_does_not_hold() {
    let d = dir("prism-n");
    let s = std::fs::read_to_string(PRISM_N).unwrap();
    assert!(s.contains("n from 3 to 17") && s.contains("n_max = { value = 17,"));
    let text = s.replace("from = 3, to = 12, count = 10", "from = 3, to = 20, count = 18");
    refused_at(
        &d,
        "prism_20",
        &text,
        "n_checked = { value",
        22,
        "parameter 'n_checked' must be a finite number, got NaN",
    );
    let text = s.replace("from = 3, to = 12, count = 10", "from = 17, to = 17, count = 1");
    let p = d.join("prism_17.toml");
    std::fs::write(&p, text).unwrap();
    let (code, out, err) = tensegrity(&["run", p.to_str().unwrap()]);
    assert_eq!(code, 0, "n = 17 holds: {out}{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// The modes of free bodies on springs and elastic cables past 2000 free bodies (the sparse
/// solver's bound: the report of its rigid modes grows with the square of the count; jointed
/// structures keep the dense bound of 400) are refused: at the motion's mode key by `check`,
/// and by `modes` before it settles.
#[test]
fn modes_past_their_size_are_refused() {
    let d = dir("modes-size");
    let s = std::fs::read_to_string("benches/prism_modes.toml").unwrap();
    let big = s.replace("n = { value = 300,", "n = { value = 2002,");
    let motion = big.replace(
        "[actuation]",
        "[motion]\nduration_s = 0.1\nstart = \"drawn\"\nmode = 7\namplitude = 1e-5\n\n[actuation]",
    );
    refused_at(
        &d,
        "motion_mode",
        &motion,
        "mode = 7",
        7,
        "the structure has 2001 free bodies, and the lowest modes of free bodies on springs and elastic cables are computed for at most 2000",
    );
    let p = d.join("big.toml");
    std::fs::write(&p, &big).unwrap();
    let (code, _, err) = tensegrity(&["modes", p.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("2001 free bodies: the lowest modes of free bodies on springs and elastic cables are computed for at most 2000 free bodies"),
        "{err}"
    );
    std::fs::remove_dir_all(&d).ok();
}

/// `modes --count` outside 1 to 200 (the sparse solver's bound) is refused at its flag.
#[test]
fn a_modes_count_outside_its_range_is_refused_at_its_flag() {
    for count in ["0", "201", "-3", "many"] {
        let flag = format!("--count={count}");
        let (code, _, err) = tensegrity(&["modes", "scenarios/custom/prism3.toml", &flag]);
        assert_eq!(code, 2, "--count {count}: {err}");
        assert!(err.contains("--count"), "--count {count}: {err}");
    }
}
