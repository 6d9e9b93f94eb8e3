//! `tensegrity fit`: parameters of the pinned bar (q* = atan2(k1 a, k2 b)) fitted to synthetic
//! measurements made from known values and a small deterministic noise, against the truth and
//! the interval the linearised model gives; the combination the data cannot identify named;
//! bad input refused with exit 2, naming what is wrong.

use crate::common;
use std::path::PathBuf;
use tensegrity_testbed::report::fit::FitReport;
use tensegrity_testbed::study::{fit, FitParameter, FitProblem, Measurement};

/// The pinned bar swept over k1 (nine points, k1 = 10 .. 90 N/m), with a = 0.8 m, b = 0.6 m.
const SWEPT_K1: &str = "scenarios/custom/pinned_bar_sweep.toml";
const A: f64 = 0.8;
const B: f64 = 0.6;
/// The measurement noise's standard deviation (rad or m), the sigma every row states.
const SIGMA: f64 = 1e-4;

/// k1 at point `i` of the file's sweep \[N/m\].
fn k1_at(i: usize) -> f64 {
    10.0 + 10.0 * i as f64
}

/// A deterministic noise of amplitude `SIGMA` (no generator: the same numbers on every run).
fn noise(i: usize) -> f64 {
    SIGMA * (1.7 * i as f64 + 0.3).sin()
}

/// The pinned bar's equilibrium angle \[rad\].
fn angle(k1: f64, k2: f64, a: f64, b: f64) -> f64 {
    (k1 * a).atan2(k2 * b)
}

/// A problem on the scenario text `source` (named `file`) with these parameters and rows.
fn problem(file: &str, source: String, parameters: &[&str], rows: Vec<(usize, &str, f64)>) -> FitProblem {
    FitProblem {
        file: PathBuf::from(file),
        source,
        overrides: Vec::new(),
        parameters: parameters.iter().map(|n| FitParameter { name: n.to_string(), low: None, high: None }).collect(),
        measurements: rows
            .into_iter()
            .enumerate()
            .map(|(k, (point, output, value))| Measurement {
                at: format!("row {k}"),
                point,
                output: output.to_string(),
                value,
                sigma: Some(SIGMA),
                time_s: None,
            })
            .collect(),
    }
}

fn parameter<'a>(r: &'a FitReport, name: &str) -> &'a tensegrity_testbed::report::fit::FittedParameter {
    r.parameters.iter().find(|p| p.name == name).expect("a fitted parameter")
}

/// k2 fitted from the angle at the sweep's nine k1 (truth 33 N/m, the file's 30 N/m the
/// start): within its 95 % interval of the truth, its sigma within 1e-3 of the linearised
/// model's SIGMA / sqrt(sum (dq/dk2)^2), dq/dk2 = -k1 a b / (k1^2 a^2 + k2^2 b^2), and chi^2
/// the noise's own sum of (noise/SIGMA)^2 less the part the fit absorbs (below it).
#[test]
fn k2_fitted_from_the_angle_at_nine_points_holds_the_truth_in_its_interval() {
    let truth = 33.0;
    let rows = (0..9).map(|i| (i, "q", angle(k1_at(i), truth, A, B) + noise(i))).collect();
    let source = std::fs::read_to_string(SWEPT_K1).expect("scenario");
    let r = fit(&problem(SWEPT_K1, source, &["k2"], rows), None).expect("a fit");
    let k2 = parameter(&r, "k2");
    let slope2: f64 = (0..9)
        .map(|i| {
            let k1 = k1_at(i);
            (k1 * A * B / (k1 * k1 * A * A + truth * truth * B * B)).powi(2)
        })
        .sum();
    let sigma = SIGMA / slope2.sqrt();
    assert!((k2.sigma / sigma - 1.0).abs() <= 1e-3, "sigma {:.6e}, linearised {sigma:.6e}", k2.sigma);
    assert!(k2.low <= truth && truth <= k2.high, "k2 = {} in [{}, {}]", k2.value, k2.low, k2.high);
    // Noise of 1e-4 rad moves k2 by at most sum |noise| / min |dq/dk2|: far below 0.05 N/m.
    assert!((k2.value - truth).abs() <= 0.05, "k2 = {}", k2.value);
    let noise_chi2: f64 = (0..9).map(|i| (noise(i) / SIGMA).powi(2)).sum();
    assert!(r.chi2 <= noise_chi2 + 1e-6, "chi^2 {} above the noise's {noise_chi2}", r.chi2);
    assert!(!r.covariance_scaled && r.unidentifiable.is_empty() && r.degrees_of_freedom == 8);
    assert!(r.iterations <= 10, "{} iterations ({})", r.iterations, r.stopped);
}

/// The pinned bar swept over the anchor a instead (0.4 .. 1.2 m, five points), so that k1 and
/// k2 are free to fit.
fn swept_a() -> String {
    common::edited(
        SWEPT_K1,
        &[(
            "grid = { k1 = { from = 10.0, to = 90.0, count = 9 } }",
            "grid = { a = { from = 0.4, to = 1.2, count = 5 } }",
        )],
    )
}

/// a at point `i` of [`swept_a`] \[m\].
fn a_at(i: usize) -> f64 {
    0.4 + 0.2 * i as f64
}

/// k1 fitted from the tip's x coordinate P.x = L cos q* (L = 1 m) at five anchors a (truth
/// 47 N/m, start 50): within its interval and 0.05 N/m of the truth.
#[test]
fn k1_fitted_from_the_tips_coordinate_holds_the_truth_in_its_interval() {
    let truth = 47.0;
    let rows = (0..5).map(|i| (i, "P.x", angle(truth, 30.0, a_at(i), B).cos() + noise(i))).collect();
    let r = fit(&problem("swept_a.toml", swept_a(), &["k1"], rows), None).expect("a fit");
    let k1 = parameter(&r, "k1");
    assert!(k1.low <= truth && truth <= k1.high, "k1 = {} in [{}, {}]", k1.value, k1.low, k1.high);
    assert!((k1.value - truth).abs() <= 0.05 && k1.sigma > 0.0 && k1.sigma < 0.05, "k1 = {} +- {}", k1.value, k1.sigma);
}

/// k1 and k2 together from the angle atan2(k1 a, k2 b), which knows only k1/k2: one
/// combination named, d k1/k1 + d k2/k2 (both scaled up alike: equal weights, 1/sqrt 2 each,
/// within 1e-6), both intervals infinite, and the ratio the data have recovered within 1e-3.
#[test]
fn k1_and_k2_from_the_angle_alone_are_named_as_one_unidentifiable_ratio() {
    let (k1, k2) = (47.0, 33.0);
    let rows = (0..5).map(|i| (i, "q", angle(k1, k2, a_at(i), B) + noise(i))).collect();
    let r = fit(&problem("swept_a.toml", swept_a(), &["k1", "k2"], rows), None).expect("a fit");
    assert_eq!(r.unidentifiable.len(), 1, "{:?}", r.unidentifiable);
    let c = &r.unidentifiable[0];
    let w = |n: &str| c.weights.iter().find(|(m, _)| m == n).map(|(_, w)| *w).expect("named");
    let half = std::f64::consts::FRAC_1_SQRT_2;
    assert!((w("k1").abs() - half).abs() <= 1e-6 && (w("k1") - w("k2")).abs() <= 1e-6, "{:?}", c.weights);
    assert!(c.ratio <= 1e-6);
    for p in &r.parameters {
        assert!(p.sigma.is_infinite() && p.low == f64::NEG_INFINITY && p.high == f64::INFINITY, "{p:?}");
    }
    let ratio = parameter(&r, "k1").value / parameter(&r, "k2").value;
    assert!((ratio / (k1 / k2) - 1.0).abs() <= 1e-3, "k1/k2 = {ratio}");
    assert!(r.to_table().contains("unidentifiable"));
}

/// A file in the temporary directory with `text`.
fn temp_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tt-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary directory");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path
}

/// `tensegrity fit` on the swept pinned bar with `csv` as data and these flags.
fn fit_cli(name: &str, csv: &str, flags: &[&str]) -> (i32, String) {
    let data = temp_file(name, csv);
    let mut args = vec!["fit", SWEPT_K1, "--data", data.to_str().expect("utf-8")];
    args.extend_from_slice(flags);
    let (code, _, stderr) = common::tensegrity(&args);
    (code, stderr)
}

/// Nine angles from k2 = 33 N/m, as a CSV.
fn angles_csv() -> String {
    let mut s = "point,output,value,sigma\n".to_string();
    for i in 0..9 {
        s += &format!("{i},q,{:.15},{SIGMA}\n", angle(k1_at(i), 33.0, A, B) + noise(i));
    }
    s
}

/// Each bad input is refused with exit 2 and a message naming the thing: a column, an output
/// (with the close names), a NaN, too few rows, an unknown or swept parameter, a bound the
/// fit runs into, a column named twice, sigmas so small that chi^2 overflows.
#[test]
fn bad_fit_input_gives_exit_2_naming_what_is_wrong() {
    let cases: Vec<(&str, String, Vec<&str>, Vec<&str>)> = vec![
        ("column.csv", "point,outptu,value\n0,q,1\n".into(), vec!["--param", "k2"], vec![":1:7", "'outptu'"]),
        (
            "output.csv",
            "point,output,value\n0,P.w,1\n1,q,1\n".into(),
            vec!["--param", "k2"],
            vec![":2", "'P.w'", "P.x"],
        ),
        ("nan.csv", "point,output,value,sigma\n0,q,NaN,1e-4\n".into(), vec!["--param", "k2"], vec![":2:5", "NaN"]),
        (
            "few.csv",
            "point,output,value,sigma\n0,q,1,1e-4\n".into(),
            vec!["--param", "k2", "--param", "b"],
            vec!["1 measurements for 2"],
        ),
        ("unknown.csv", angles_csv(), vec!["--param", "k3"], vec!["'k3'", "k1", "k2"]),
        ("swept.csv", angles_csv(), vec!["--param", "k1"], vec!["--param k1", "[actuation]"]),
        ("bound.csv", angles_csv(), vec!["--param", "k2=1:31"], vec!["k2 ran into its bound 31"]),
        // Started at its bound (the file's 30 below it) with the data wanting 33 below it: every
        // step is cut to nothing there, which had stopped the fit at 40 with exit 0.
        ("start.csv", angles_csv(), vec!["--param", "k2=40:100"], vec!["k2 ran into its bound 40"]),
        ("point.csv", "point,output,value\n9,q,1\n0,q,1\n".into(), vec!["--param", "k2"], vec!["no point 9"]),
        // Two columns named value: the CLI had read the last, Python the first.
        (
            "twice.csv",
            "point,output,value,value\n0,q,1,2\n1,q,1,2\n".into(),
            vec!["--param", "k2"],
            vec![":1:20: the column 'value' is named twice (also at column 14)"],
        ),
        // Sigmas of 1e-300 overflow chi^2 (had exited 0 at the start value with sigma 0).
        (
            "tiny.csv",
            angles_csv().replace(&format!(",{SIGMA}\n"), ",1e-300\n"),
            vec!["--param", "k2"],
            vec![".csv:", "sigma 1e-300 of q weighs the fit past what a float holds", "chi^2 inf"],
        ),
    ];
    for (name, csv, flags, said) in cases {
        let (code, stderr) = fit_cli(name, &csv, &flags);
        assert_eq!(code, 2, "{name}: {stderr}");
        for s in said {
            assert!(stderr.contains(s), "{name}: '{s}' not in {stderr}");
        }
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
}

/// `tensegrity fit --json -` with `data` as standard input: (exit code, stdout, stderr).
fn fit_with_stdin(data_flag: &str, stdin: &str) -> (i32, String, String) {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensegrity"))
        .args(["fit", SWEPT_K1, "--data", data_flag, "--param", "k2=1:100", "--json", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    child.stdin.take().expect("stdin").write_all(stdin.as_bytes()).expect("write stdin");
    let out = child.wait_with_output().expect("binary ends");
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), text(&out.stdout), text(&out.stderr))
}

/// k2's estimate in a fit's JSON.
fn k2_of(json: &str) -> f64 {
    let j: serde_json::Value = serde_json::from_str(json).expect("JSON alone on stdout");
    j["parameters"][0]["value"].as_f64().expect("a value")
}

/// A spreadsheet's CSV (a UTF-8 byte-order mark before the header: it had been read as part of
/// the column 'point' and refused as an unknown column) and the data on standard input
/// (`--data -`: it had been refused as a missing file named "-") fit as the plain file does:
/// exit 0 and k2 bit for bit the same, within 0.05 of the truth 33 N/m.
#[test]
fn data_with_a_byte_order_mark_or_on_standard_input_fits_as_the_file_does() {
    let plain = temp_file("plain.csv", &angles_csv());
    let marked = temp_file("marked.csv", &format!("\u{feff}{}", angles_csv()));
    let (code, out, err) = fit_with_stdin(plain.to_str().unwrap(), "");
    assert_eq!(code, 0, "{err}");
    let k2 = k2_of(&out);
    assert!((k2 - 33.0).abs() <= 0.05, "k2 = {k2}");
    let (code, out, err) = fit_with_stdin(marked.to_str().unwrap(), "");
    assert_eq!((code, k2_of(&out)), (0, k2), "{err}");
    let (code, out, err) = fit_with_stdin("-", &format!("\u{feff}{}", angles_csv()));
    assert_eq!((code, k2_of(&out)), (0, k2), "{err}");
}

/// The command's JSON has the estimate and its interval, and exit 0.
#[test]
fn fit_command_writes_the_estimate_and_its_interval_as_json() {
    let data = temp_file("good.csv", &angles_csv());
    let (code, stdout, stderr) = common::tensegrity(&[
        "fit",
        SWEPT_K1,
        "--data",
        data.to_str().expect("utf-8"),
        "--param",
        "k2=1:100",
        "--json",
        "-",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let j: serde_json::Value = serde_json::from_str(&stdout).expect("JSON alone on stdout");
    let p = &j["parameters"][0];
    let (v, lo, hi) = (p["value"].as_f64().unwrap(), p["low"].as_f64().unwrap(), p["high"].as_f64().unwrap());
    assert!(lo <= 33.0 && 33.0 <= hi && (v - 33.0).abs() <= 0.05, "{v} in [{lo}, {hi}]");
    assert!(stderr.contains("k2"), "the table on standard error");
}

/// Angles the pinned bar cannot reach (q = -0.01 rad at every k1, where atan2(k1 a, k2 b) > 0
/// for every k2 > 0) pull an unbounded k2 towards infinity, each step about doubling it: the fit
/// stops once it is more than 1e6 times its initial 30 N/m away (above 3.0e7 N/m), exit 2,
/// naming k2, where it went and the flag that bounds it; no panic, no settle of a runaway
/// spring.
#[test]
fn a_parameter_without_bounds_that_runs_away_is_stopped_and_named() {
    let mut csv = "point,output,value,sigma\n".to_string();
    for i in 0..9 {
        csv += &format!("{i},q,-0.01,{SIGMA}\n");
    }
    let (code, stderr) = fit_cli("runaway.csv", &csv, &["--param", "k2"]);
    assert_eq!(code, 2, "{stderr}");
    let said = "k2 ran away from 30 to ";
    let at = stderr.find(said).unwrap_or_else(|| panic!("'{said}' not in {stderr}"));
    let to: f64 = stderr[at + said.len()..].split(':').next().and_then(|v| v.trim().parse().ok()).expect("a number");
    assert!(to > 30.0 + 1e6 * 30.0 && to.is_finite(), "stopped at {to}");
    assert!(stderr.contains("--param k2=LOW:HIGH") && !stderr.contains("panicked"), "{stderr}");
}

/// The pinned bar released half a radian from its equilibrium (k2 = 30 N/m), 4 s at 1 ms.
const RELEASED: &str = "scenarios/custom/pinned_bar_large_amplitude.toml";

/// Its pin angle at t = 0.1, 0.2, .. 2.0 s of the motion (the judged trajectory, as the
/// table has it), each row as `point,output,value,sigma,t_s` with noise `sigma` times
/// standard normal draws from `seed` (none for 0 noise).
fn released_angles(sigma: f64, seed: u64) -> String {
    use tensegrity_testbed::observers::table::{MemoryTable, TableTarget};
    let sc = tensegrity_testbed::scenario::load(std::path::Path::new(RELEASED)).expect("shipped");
    let kept = MemoryTable::default();
    let opts =
        tensegrity_testbed::run::RunOptions { table: Some(TableTarget::Memory(kept.clone())), ..Default::default() };
    assert!(tensegrity_testbed::run::run(&sc, &opts).error.is_none());
    let (schema, batches) = kept.take().expect("a table");
    let column = |name: &str| -> Vec<f64> {
        let k = schema.index_of(name).expect("a column");
        batches
            .iter()
            .flat_map(|b| {
                let c = b.column(k).as_any().downcast_ref::<arrow_array::Float64Array>().expect("f64").clone();
                (0..c.len()).map(move |i| c.value(i))
            })
            .collect()
    };
    let (times, angles) = (column("motion_time_s"), column("joint:pin.angle"));
    let mut state = seed;
    let mut csv = "point,output,value,sigma,t_s\n".to_string();
    for k in 1..=20 {
        let t = 0.1 * k as f64;
        let tick = times.iter().position(|m| (m - t).abs() < 1e-9).expect("a tick at t");
        let noise = if sigma > 0.0 { sigma * tensegrity_testbed::study::standard_normal(&mut state) } else { 0.0 };
        csv += &format!("0,joint:pin.angle,{:?},{},{:?}\n", angles[tick] + noise, sigma.max(1e-12), times[tick]);
    }
    csv
}

/// The fit of k2 to `csv` starting from k2 = 25 N/m (the truth 30).
fn fit_released(csv: &str) -> FitReport {
    let measurements = tensegrity_testbed::study::measurements_from_csv("angles.csv", csv).expect("valid data");
    let problem = FitProblem {
        file: PathBuf::from(RELEASED),
        source: std::fs::read_to_string(RELEASED).expect("shipped"),
        overrides: vec![tensegrity_testbed::scenario::Override { name: "k2".into(), value: "25".into() }],
        parameters: vec![FitParameter { name: "k2".into(), low: None, high: None }],
        measurements,
    };
    fit(&problem, None).expect("a fit")
}

/// A trajectory fitted (rows with `t_s`: the motion's table at that time): the released bar's
/// pin angle at twenty times over 2 s. Without noise the fit from k2 = 25 lands on the truth
/// 30 N/m within 1e-7 relative (the judged trajectory's own error, about 1e-9 rad, over the
/// angle's sensitivity); with Gaussian noise of 1e-4 rad (seed 11) within three of its sigmas,
/// chi^2 within 6 standard deviations of its 19 degrees of freedom, each in at most 6 steps.
#[test]
fn a_stiffness_is_fitted_from_a_released_bars_trajectory() {
    let exact = fit_released(&released_angles(0.0, 0));
    let k2 = parameter(&exact, "k2");
    assert!((k2.value - 30.0).abs() <= 1e-7 * 30.0, "k2 = {} from the exact trajectory", k2.value);
    assert!(exact.residuals.iter().all(|r| r.time_s.is_some()));
    let noisy = fit_released(&released_angles(1e-4, 11));
    let k2 = parameter(&noisy, "k2");
    assert!((k2.value - 30.0).abs() <= 3.0 * k2.sigma, "k2 = {} +- {}", k2.value, k2.sigma);
    assert!((noisy.chi2 - 19.0).abs() <= 6.0 * (2.0f64 * 19.0).sqrt(), "chi^2 = {}", noisy.chi2);
    assert!(exact.iterations <= 6 && noisy.iterations <= 6, "{} and {} steps", exact.iterations, noisy.iterations);
}

/// A trajectory row is refused with exit 2 at its place when its time is no tick's, when its
/// output is no column of the motion's table (the close names said), and when the scenario has
/// no motion.
#[test]
fn bad_trajectory_rows_give_exit_2_naming_what_is_wrong() {
    let header = "point,output,value,sigma,t_s\n";
    let cases = [
        (
            RELEASED,
            format!("{header}0,joint:pin.angle,0.1,1e-4,0.1\n0,joint:pin.angle,0.1,1e-4,0.10005\n"),
            vec!["angles.csv:3", "t_s = 0.10005 is not the time of a tick"],
        ),
        (
            RELEASED,
            format!("{header}0,joint:pin.angel,0.1,1e-4,0.1\n0,joint:pin.angle,0.1,1e-4,0.2\n"),
            vec!["angles.csv:2", "'joint:pin.angel' is no column", "joint:pin.angle"],
        ),
        (SWEPT_K1, format!("{header}0,q,0.1,1e-4,0.1\n1,q,0.1,1e-4,0.2\n"), vec!["has no [motion]"]),
    ];
    for (scenario, csv, said) in cases {
        let data = temp_file("angles.csv", &csv);
        let (code, _, err) = common::tensegrity(&["fit", scenario, "--data", data.to_str().unwrap(), "--param", "k2"]);
        assert_eq!(code, 2, "{csv}: {err}");
        for s in said {
            assert!(err.contains(s), "'{s}' not in {err}");
        }
    }
}

/// Data of one row past `MAX_DATA_ROWS` are refused at that row's line, naming the bound (the
/// bound `tt.fit` applies to a DataFrame too); data at the bound are read.
#[test]
fn data_past_the_row_bound_are_refused_at_the_row() {
    use tensegrity_testbed::study::{measurements_from_csv, MAX_DATA_ROWS};
    let at_bound = format!("point,output,value\n{}", "0,q,0.1\n".repeat(MAX_DATA_ROWS));
    assert_eq!(measurements_from_csv("d.csv", &at_bound).expect("at the bound").len(), MAX_DATA_ROWS);
    let past = format!("{at_bound}0,q,0.1\n");
    let e = measurements_from_csv("d.csv", &past).expect_err("past the bound").to_string();
    let line = MAX_DATA_ROWS + 2;
    assert!(e.starts_with(&format!("d.csv:{line}:1: more than {MAX_DATA_ROWS} measurement rows")), "{e}");
}

/// A fit asks for the fitted parameters' sensitivities alone (issue 63: it had computed every
/// parameter's, helpers included): the prism's sensitivities to k_side alone are one row, the
/// same to the bit as k_side's row among all four.
#[test]
fn a_fit_computes_the_fitted_parameters_sensitivities_alone() {
    use tensegrity_testbed::study::sensitivity::{sensitivity, sensitivity_to};
    let file = "tests/fixtures/fit/prism3_loads.toml";
    let sc = tensegrity_testbed::scenario::load(std::path::Path::new(file)).unwrap();
    let all = sensitivity(&sc, file, 0, false, None).unwrap();
    let only = sensitivity_to(&sc, file, (0, Some(&["k_side".to_string()])), false, None).unwrap();
    assert_eq!(all.parameters.len(), 4);
    assert_eq!(only.parameters.len(), 1);
    let row = all.parameters.iter().find(|p| p.name == "k_side").unwrap();
    let bits = |d: &[f64]| d.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    assert_eq!(bits(&only.parameters[0].derivatives), bits(&row.derivatives));
}
