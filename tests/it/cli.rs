//! The command line: exit codes 0 / 1 / 2, file:line:col errors, solve, list, record.

use crate::common;

use common::{tensegrity, tensegrity_guarded};

fn temp_file(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("tensegrity-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const VALID: &str = r#"name = "t"
mechanism = "ji2014"
[params]
L = 1.0
[actuation]
points = [ { L3 = 1.0, theta1 = 0.5 } ]
[[checks]]
quantity = "theta2"
tolerance = 1e-9
"#;

#[test]
fn run_passes_with_exit_0_and_writes_the_json_report() {
    let json = std::env::temp_dir().join(format!("tensegrity-report-{}.json", std::process::id()));
    let (code, out, err) = tensegrity(&["run", "scenarios/ji2014/quick.toml", "--json", json.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("PASS"));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let s = &v["scenarios"][0];
    assert_eq!(s["mechanism"], "ji2014");
    assert_eq!(s["passed"], true);
    assert_eq!(s["settle"]["settled"], true);
    assert!(s["points"][0]["inputs"]["L3"].is_number());
    assert!(s["points"][0]["simulated"]["theta2"].is_number());
    assert!(s["points"][0]["stable"].is_boolean());
    assert!(s["checks"][0]["max_rel_error"].as_f64().unwrap() <= 1e-9);
}

#[test]
fn a_check_that_fails_gives_exit_1() {
    // A tolerance below what f64 can resolve cannot pass.
    let p = temp_file("tight.toml", &VALID.replace("tolerance = 1e-9", "tolerance = 1e-300"));
    let (code, out, _) = tensegrity(&["run", p.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("FAIL"));
}

/// Each malformed scenario gives exit 2 from check and run, with file:line:col in the message.
#[test]
fn bad_scenarios_give_exit_2_with_file_line_and_column() {
    let cases: &[(&str, String, &str)] = &[
        ("syntax", VALID.replace("L = 1.0", "L = = 1.0"), ":4:"),
        ("unknown key", VALID.replace("[params]", "colour = 3\n[params]"), ":3:1"),
        ("wrong type", VALID.replace("L = 1.0", "L = \"one\""), ":4:"),
        ("negative length", VALID.replace("L = 1.0", "L = -1.0"), ":4:5"),
        ("unknown param", VALID.replace("L = 1.0", "Q = 1.0"), ":4:1"),
        ("theta1 out of range", VALID.replace("theta1 = 0.5", "theta1 = 4.0"), ":6:"),
        ("missing input", VALID.replace(", theta1 = 0.5", ""), ":6:"),
        ("unknown mechanism", VALID.replace("\"ji2014\"", "\"ji2015\""), ":2:13"),
        ("zero dt", VALID.replace("[actuation]", "[sim]\ndt = 0.0\n[actuation]"), ":6:6"),
        ("unknown start key", VALID.replace("[actuation]", "[start]\ntheta9 = 1.0\n[actuation]"), ":6:1"),
        ("nan", VALID.replace("L = 1.0", "L = nan"), ":4:5"),
        ("unknown quantity", VALID.replace("quantity = \"theta2\"", "quantity = \"zeta\""), ":8:12"),
        ("empty points", VALID.replace("points = [ { L3 = 1.0, theta1 = 0.5 } ]", "points = []"), ":5:1"),
        (
            "unsorted waypoints",
            VALID.replace(
                "points = [ { L3 = 1.0, theta1 = 0.5 } ]",
                "waypoints = [ { t = 1.0, L3 = 1.0, theta1 = 0.5 }, { t = 0.5, L3 = 1.0, theta1 = 0.5 } ]",
            ),
            ":6:",
        ),
    ];
    for (what, text, loc) in cases {
        let p = temp_file(&format!("{}.toml", what.replace(' ', "_")), text);
        for cmd in ["check", "run"] {
            let (code, out, err) = tensegrity(&[cmd, p.to_str().unwrap()]);
            assert_eq!(code, 2, "{what} ({cmd}): exit {code}\n{out}{err}");
            let file = p.to_str().unwrap();
            assert!(err.contains(&format!("{file}{loc}")), "{what} ({cmd}): expected '{file}{loc}' in: {err}");
            assert!(!err.contains("panicked"), "{what}: {err}");
        }
    }
}

#[test]
fn a_missing_file_gives_exit_2() {
    let (code, _, err) = tensegrity(&["check", "no/such/file.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("no/such/file.toml:1:1"), "{err}");
}

#[test]
fn every_shipped_scenario_is_valid() {
    let mut checked = 0;
    for dir in std::fs::read_dir("scenarios").unwrap() {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().is_some_and(|e| e == "toml") {
                let (code, out, err) = tensegrity(&["check", p.to_str().unwrap()]);
                assert_eq!(code, 0, "{}: {out}{err}", p.display());
                checked += 1;
            }
        }
    }
    assert!(checked >= 20, "{checked} scenario files checked");
}

#[test]
fn solve_fk_prints_both_equilibria_with_their_stability() {
    let (code, out, err) = tensegrity(&[
        "solve",
        "ji2014",
        "fk",
        "--set",
        "L3=6",
        "--set",
        "theta1=0.3141592653589793",
        "--set",
        "K1=100",
        "--set",
        "K2=10",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let sols = v["solutions"].as_array().unwrap();
    assert_eq!(sols.len(), 2);
    assert_eq!(sols[0]["stable"], true);
    assert!((sols[0]["values"]["theta2"].as_f64().unwrap() - 2.656091).abs() < 1e-6);
    assert_eq!(sols[1]["stable"], false);
}

#[test]
fn solve_ik_solutions_reproduce_the_target_through_fk() {
    let (code, out, err) = tensegrity(&["solve", "ji2014", "ik", "--set", "x=-0.5", "--set", "y=0.8", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let sols = v["solutions"].as_array().unwrap();
    assert!(!sols.is_empty());
    for s in sols {
        let (l3, th1, th2) = (
            s["values"]["L3"].as_f64().unwrap(),
            s["values"]["theta1"].as_f64().unwrap(),
            s["values"]["theta2"].as_f64().unwrap(),
        );
        let x = l3 * th1.cos() + th2.cos();
        let y = l3 * th1.sin() + th2.sin();
        assert!((x + 0.5).abs() < 1e-10 && (y - 0.8).abs() < 1e-10, "({x}, {y})");
    }
}

#[test]
fn solve_rejects_unknown_names_and_unreachable_targets_with_exit_2() {
    assert_eq!(tensegrity(&["solve", "ji2014", "fk", "--set", "L3=1"]).0, 2);
    assert_eq!(tensegrity(&["solve", "ji2014", "fk", "--set", "L3=1", "--set", "theta1=0.5", "--set", "Z=1"]).0, 2);
    assert_eq!(tensegrity(&["solve", "ji2014", "ik", "--set", "x=0", "--set", "y=-5"]).0, 2);
    assert_eq!(tensegrity(&["solve", "nope", "fk"]).0, 2);
    assert_eq!(tensegrity(&["solve", "ji2014", "fk", "--set", "L3=1", "--set", "theta1=0.5", "--set", "K1=-3"]).0, 2);
}

#[test]
fn list_names_parameters_with_units_and_queries() {
    let (code, out, _) = tensegrity(&["list"]);
    assert_eq!(code, 0);
    for s in ["ji2014", "K1", "[N/m]", "L3", "theta1", "fk", "ik"] {
        assert!(out.contains(s), "missing {s} in list output");
    }
}

#[test]
fn record_writes_an_rrd_file_and_no_partial_file() {
    let dir = std::env::temp_dir().join(format!("tensegrity-rec-{}", std::process::id()));
    let path = dir.join("quick.rrd");
    let (code, out, err) = tensegrity(&["run", "scenarios/ji2014/quick.toml", "--record", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    let len = std::fs::metadata(&path).expect("recording exists").len();
    assert!(len > 10_000, "recording is only {len} bytes");
    assert!(no_partial_files(&dir), "a temporary file was left in {}", dir.display());
}

/// No file in `dir` is a temporary one (`.NAME.PID.SEQ.partial.EXT`).
fn no_partial_files(dir: &std::path::Path) -> bool {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .all(|e| !e.file_name().to_string_lossy().contains(".partial"))
}

/// A settle that runs out of time is a failure (exit 1), never a pass.
#[test]
fn a_settle_that_never_comes_fails_with_exit_1() {
    let text = VALID.replace("[actuation]", "[settle]\nmax_time = 0.05\n[actuation]");
    let p = temp_file("timeout.toml", &text);
    let json = p.with_extension("json");
    let (code, out, err) = tensegrity(&["run", p.to_str().unwrap(), "--json", json.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("NOT SETTLED: kinetic energy"), "{out}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["scenarios"][0]["settle"]["settled"], false);
    assert_eq!(v["scenarios"][0]["passed"], false);
    assert!(v["scenarios"][0]["points"][0]["final_kinetic_energy_j"].as_f64().unwrap() > 0.0);
}

/// A time step far too large for stiff springs diverges: the run stops, says what diverged and
/// when, fails (exit 1), and still writes the report and the recording up to that tick.
#[test]
fn an_absurd_time_step_diverges_and_still_writes_report_and_recording() {
    let text = VALID
        .replace("L = 1.0", "L = 1.0\nK1 = 1e9\nK2 = 1e9\nc_D1 = 0.0")
        .replace("[actuation]", "[sim]\ndt = 0.5\n[settle]\nmax_time = 50.0\n[actuation]");
    let p = temp_file("diverge.toml", &text);
    let json = p.with_extension("json");
    let rrd = p.with_extension("rrd");
    let (code, out, err) =
        tensegrity(&["run", p.to_str().unwrap(), "--json", json.to_str().unwrap(), "--record", rrd.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let s = &v["scenarios"][0];
    assert_eq!(s["passed"], false);
    let e = s["error"].as_str().expect("the divergence is reported");
    assert!(e.contains("diverged at tick"), "{e}");
    assert!(std::fs::metadata(&rrd).map(|m| m.len() > 0).unwrap_or(false), "recording written");
    assert!(no_partial_files(rrd.parent().unwrap()));
    assert!(!err.contains("panicked"));
}

/// `--jobs` above the machine's threads is lowered, and said; the sweep runs.
#[test]
fn too_many_jobs_are_lowered_and_said() {
    let (code, out, err) = tensegrity(&["sweep", "scenarios/ji2014/quick.toml", "--jobs", "100000"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(err.contains("--jobs 100000 lowered to"), "{err}");
}

/// A reader that closes the pipe early (`tensegrity list | head -1`) ends the command quietly:
/// no panic message, killed by SIGPIPE like any Unix filter.
#[test]
fn a_closed_pipe_ends_the_command_quietly() {
    use std::io::BufRead;
    for args in [vec!["list"], vec!["findings", "ji2014"], vec!["solve", "furet2018", "workspace", "--set", "b=0.9"]] {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_tensegrity"))
            .args(&args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked") && !err.contains("Broken pipe"), "{args:?}: {err}");
        assert_ne!(out.status.code(), Some(101), "{args:?}");
    }
}

/// Extreme parameter values are errors or findings, never a hang or a panic: a furet2018 target
/// at 1e100 m (its quartic's companion matrix never converged) and mohr2011 with l_o = 1e6 l_b
/// (a point that did not assemble panicked).
#[test]
fn extreme_values_give_answers_not_hangs_or_panics() {
    let (code, _, err) = tensegrity_guarded(&["solve", "furet2018", "ik", "--set", "x=1e100", "--set", "y=1"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("outside the workspace"), "{err}");
    let (code, out, err) = tensegrity_guarded(&["findings", "mohr2011", "--set", "lo=1e6", "--set", "lb=1"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("Eq. 12-14") && !err.contains("panicked"), "{out}{err}");
}

/// `solve manriquez2019 fk` prints the cable ends P_M1 and P_M2 (Eq. 8-9) beside M, G and the
/// cable lengths, each cable length equal to the distance from its base point to its end.
#[test]
fn manriquez2019_fk_prints_the_cable_ends_of_eq8_9() {
    let (code, out, err) =
        tensegrity(&["solve", "manriquez2019", "fk", "--set", "theta1=0.0941", "--set", "theta2=0.0332", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let values = &v["solutions"][0]["values"];
    let value = |k: &str| values[k].as_f64().unwrap_or_else(|| panic!("{k} in {values}"));
    // The base points B1 = (bx, b, -b) and B2 = (bx, -b, b) of the paper's parameters.
    use tensegrity_testbed::mechanisms::manriquez2019::analytic::{cable_base_points, Params};
    let bases = cable_base_points(&Params::PAPER);
    for (i, base) in bases.iter().enumerate() {
        let end = ["x", "y", "z"].map(|c| value(&format!("{c}_M{}", i + 1)));
        let distance = ((end[0] - base.x).powi(2) + (end[1] - base.y).powi(2) + (end[2] - base.z).powi(2)).sqrt();
        let length = value(&format!("L{}", i + 1));
        assert!((length - distance).abs() <= 1e-12, "cable {}: L = {length} m, |B P_M| = {distance} m", i + 1);
    }
}

#[test]
fn meaningless_flags_are_refused_with_exit_2_before_any_work() {
    let sweep = "scenarios/custom/pinned_bar_sweep.toml";
    for (args, said) in [
        (vec!["sweep", sweep, "--jobs", "0"], "--jobs"),
        (vec!["run", "scenarios/ji2014/quick.toml", "--record-every", "0"], "--record-every"),
        (vec!["run", "scenarios/ji2014/quick.toml", "--table", "out.txt"], "--table out.txt"),
        (vec!["sweep", sweep, "--figure", "f.png", "--x", "nope"], "--x nope: not an axis"),
    ] {
        let (code, out, err) = tensegrity_guarded(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(said), "{args:?}: {err}");
        // Refused from the flags and the file alone: nothing settled (no summary, no sweep's
        // "N/M points" progress line) and nothing written.
        let progress = err.lines().any(|l| l.ends_with(" points") && l.contains('/'));
        assert!(out.is_empty() && !progress, "{args:?}: {out}{err}");
        assert!(!std::path::Path::new("out.txt").exists() && !std::path::Path::new("f.png").exists());
    }
}

/// `--set` of a name the file's `[actuation]` grid or points set at every point would be
/// ignored: every command that reads a scenario with `--set` refuses it with exit 2, naming the
/// flag and the sweep's key at file:LINE:COL, before any work.
#[test]
fn a_set_of_a_swept_name_is_refused_naming_the_flag_and_the_sweep() {
    let file = "scenarios/custom/pinned_bar_sweep.toml";
    let text = std::fs::read_to_string(file).unwrap();
    let (line, col) = common::line_col(&text, text.find("k1 = { from").expect("the grid's k1"));
    let at = format!("{file}:{line}:{col}: ");
    let commands: [&[&str]; 6] = [
        &["run", file],
        &["check", file],
        &["list", file],
        &["sweep", file, "--out", "-"],
        &["modes", file],
        &["export", "mjcf", file, "--out", "-"],
    ];
    for args in commands {
        let args: Vec<&str> = args.iter().copied().chain(["--set", "k1=50"]).collect();
        let (code, out, err) = tensegrity(&args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(err.contains(&at), "{args:?}: {err}");
        assert!(err.contains("--set k1=50 conflicts with the file: 'k1' is set here by [actuation] grid"), "{err}");
        assert!(out.is_empty(), "{args:?}: nothing ran, yet: {out}");
    }
    // A name the grid does not sweep is still set.
    assert_eq!(tensegrity(&["check", file, "--set", "k2=35"]).0, 0);
    // An input a point sets is swept as well (a built-in mechanism's point).
    let p = temp_file("swept_point.toml", VALID);
    let (code, _, err) = tensegrity(&["check", p.to_str().unwrap(), "--set", "theta1=0.3"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(":6:24: --set theta1=0.3 conflicts with the file: 'theta1' is set here by [actuation] points"),
        "{err}"
    );
}

/// `--json -` (or `--json` where it is a switch) makes standard output the JSON alone, for
/// every command that has it: the human table goes to standard error.
#[test]
fn json_to_stdout_is_json_alone_for_every_command() {
    let commands: [&[&str]; 7] = [
        &["run", "scenarios/custom/pinned_bar_vibration.toml", "--json", "-"],
        &["modes", "scenarios/custom/pinned_bar_modes.toml", "--json", "-"],
        &["sweep", "scenarios/custom/pinned_bar_sweep.toml", "--json", "-"],
        &["solve", "ji2014", "ik", "--set", "x=-0.5", "--set", "y=0.8", "--json"],
        &["findings", "ji2014", "--json"],
        &["bench", "--mechanism", "ji2014", "--rounds", "1", "--json"],
        &["run", "scenarios/custom/pinned_bar_vibration.toml", "scenarios/custom/pinned_bar_modes.toml", "--json", "-"],
    ];
    for args in commands {
        let (code, out, err) = tensegrity(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        let v: serde_json::Value =
            serde_json::from_str(&out).unwrap_or_else(|e| panic!("{args:?}: stdout is not JSON alone ({e}): {out}"));
        assert!(v.is_object() || v.is_array(), "{args:?}");
    }
    // Two outputs on standard output would mix: refused before any work.
    let (code, out, err) =
        tensegrity(&["sweep", "scenarios/custom/pinned_bar_sweep.toml", "--json", "-", "--out", "-"]);
    assert!(code == 2 && out.is_empty() && err.contains("both write to standard output"), "{out}{err}");
    // The modes table still shows, on standard error.
    let (_, _, err) = tensegrity(&["modes", "scenarios/custom/pinned_bar_modes.toml", "--json", "-"]);
    assert!(err.contains("mode    omega [rad/s]"), "{err}");
}

/// What `tensegrity modes` analyses and refuses is said in the same words by its `--help`, the
/// command table (docs/command-line.md) and the Modes chapter (docs/modes.md), and is true:
/// it works on a joint tree (the pinned bar), and on loops and taut inextensible cables (furet2018
/// and mohr2011 at their commands: held rigid, no degree of freedom left).
#[test]
fn modes_help_command_table_and_chapter_say_the_same_true_thing() {
    let scope = "free bodies held by springs and elastic cables (and by supports in some directions), or the revolute and prismatic joints of joint trees; joints that close loops, ball and universal joints, and taut inextensible cables are constraints; refused (exit 2): a loop closed by a prismatic joint";
    let words = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let (code, help, _) = tensegrity(&["modes", "--help"]);
    assert_eq!(code, 0);
    let large = "every mode, or above 100 free bodies on springs and elastic cables: the lowest 20 non-rigid modes and every rigid one (sparse shift-invert)";
    for (what, text) in [
        ("modes --help", help),
        ("docs/command-line.md", std::fs::read_to_string("docs/command-line.md").unwrap()),
        ("docs/modes.md", std::fs::read_to_string("docs/modes.md").unwrap()),
    ] {
        assert!(words(&text).contains(scope), "{what} does not say: {scope}");
        assert!(words(&text).to_lowercase().contains(large), "{what} does not say: {large}");
    }
    assert_eq!(tensegrity(&["modes", "scenarios/custom/pinned_bar_modes.toml"]).0, 0);
    let (code, out, err) = tensegrity(&["modes", "scenarios/furet2018/ik_solutions.toml"]);
    assert!(code == 0 && out.contains("(0 degree(s) of freedom); loops closed by X1 D, X2 D"), "{out}{err}");
    let (code, out, err) = tensegrity(&["modes", "scenarios/mohr2011/quick.toml"]);
    assert!(code == 0 && out.contains("15 rows of rank 15 (0 degree(s) of freedom)"), "{out}{err}");
}
