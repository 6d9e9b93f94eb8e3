//! `tensegrity bench`: the case-set export for peer simulators and the side-by-side comparison.

use crate::common;
use common::tensegrity;

#[test]
fn export_cases_writes_every_case_with_inputs_analytic_values_and_nodes() {
    let dir = std::env::temp_dir().join(format!("tt-export-{}", std::process::id()));
    let (code, out, err) = tensegrity(&["bench", "--export-cases", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    let ji: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ji2014.json")).unwrap()).unwrap();
    let cases = ji["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 110, "the 10 x 11 grid of scenarios/ji2014/grid.toml");
    assert_eq!(ji["dt_s"].as_f64(), Some(0.15));
    let first = &cases[0];
    assert_eq!(first["inputs"]["L3"].as_f64(), Some(0.2));
    // The analytic equilibrium puts D3 at (x, y): the two exports agree to the last digit.
    let d3 = &first["analytic_nodes"]["D3"];
    assert!((d3[0].as_f64().unwrap() - first["analytic"]["x"].as_f64().unwrap()).abs() < 1e-15);
    assert!((d3[1].as_f64().unwrap() - first["analytic"]["y"].as_f64().unwrap()).abs() < 1e-15);
    let mohr: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("mohr2011.json")).unwrap()).unwrap();
    assert_eq!(mohr["cases"].as_array().unwrap().len(), 24);
    assert_eq!(mohr["length_scale_m"].as_f64(), Some(2.0));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bench_against_a_peer_reports_both_sides_and_their_ratios() {
    let (code, out, err) = tensegrity(&[
        "bench",
        "--mechanism",
        "ji2014",
        "--rounds",
        "2",
        "--json",
        "--peer",
        "sh tests/fixtures/fake_peer.sh",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let c = &v["comparisons"][0];
    assert_eq!(c["mechanism"], "ji2014");
    assert_eq!(c["peer"]["cases"].as_u64(), Some(110));
    assert_eq!(c["peer"]["median_steps_per_case"].as_f64(), Some(40.0));
    assert_eq!(c["peer"]["max_error"].as_f64(), Some(1e-9));
    assert_eq!(c["testbed"]["rounds"].as_u64(), Some(2));
    assert!(c["testbed"]["all_settled"].as_bool().unwrap());
    let ours = c["testbed"]["median_cases_per_s"].as_f64().unwrap();
    let ratio = c["ratio_cases_per_s"].as_f64().unwrap();
    assert!((ratio - ours / 100.0).abs() <= 1e-12 * ratio, "ratio {ratio} against {ours} / 100");
    let steps = c["ratio_steps_per_case"].as_f64().unwrap();
    assert!((steps - c["testbed"]["median_steps_per_case"].as_f64().unwrap() / 40.0).abs() < 1e-12);
}

#[test]
fn a_peer_that_fails_or_prints_no_json_is_bad_input() {
    let (code, _, err) = tensegrity(&["bench", "--mechanism", "ji2014", "--rounds", "1", "--peer", "false"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("the peer 'false' failed"), "{err}");
    let (code, _, err) = tensegrity(&["bench", "--mechanism", "ji2014", "--rounds", "1", "--peer", "echo hello"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("printed no JSON"), "{err}");
    let (code, _, err) = tensegrity(&["bench", "--mechanism", "nosuch"]);
    assert_eq!(code, 2);
    assert!(err.contains("no bench case set for mechanism 'nosuch'"), "{err}");
}
