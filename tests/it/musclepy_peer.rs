//! MusclePy, the structural peer (`benches/peers/musclepy/`), side by side with the testbed on
//! the structures of MusclePy's own test suite: `compare.py` runs both and an exact answer of
//! its own (closed forms, Newton's method on the same file, the eigenproblem), and every row is
//! held here to what it claims.

use super::common;

/// Every compared quantity of every case, as `compare.py --json` writes it.
fn rows() -> Option<Vec<serde_json::Value>> {
    let py = common::peer_python(&["musclepy", "numpy"], "the MusclePy peer")?;
    let out = std::env::temp_dir().join(format!("tensegrity-musclepy-{}.json", std::process::id()));
    let status = std::process::Command::new(py)
        .args(["benches/peers/musclepy/compare.py", "--tensegrity", env!("CARGO_BIN_EXE_tensegrity"), "--json"])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .status()
        .expect("compare.py runs");
    assert!(status.success(), "compare.py: {status}");
    let rows: Vec<serde_json::Value> = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let _ = std::fs::remove_file(&out);
    Some(rows)
}

fn number(row: &serde_json::Value, key: &str) -> Option<f64> {
    row[key].as_f64()
}

/// The 18 cases run on both tools. Wherever an exact answer is computed (88 rows: forces,
/// displacements, reactions, frequencies), the testbed is within 1e-9 of it (relative, measured
/// 2.5e-12), and it is never farther from MusclePy than MusclePy is from the exact answer (to
/// 1e-9): each difference between the two tools is MusclePy's own (its stopping tolerance, its
/// linear method, its load steps without equilibrium iterations, its geometric stiffness). The
/// SVD cases' counts and subspaces, which have no exact column, agree within 1e-12, and so does
/// the testbed's linear analysis with MusclePy's linear method on the two-bar truss.
#[test]
fn the_testbed_agrees_with_musclepy_where_musclepy_agrees_with_the_exact_answer() {
    let Some(rows) = rows() else { return };
    let cases: std::collections::BTreeSet<&str> = rows.iter().map(|r| r["case"].as_str().unwrap()).collect();
    assert_eq!(cases.len(), 18, "{cases:?}");
    let mut exact_rows = 0;
    for row in &rows {
        let (case, quantity) = (row["case"].as_str().unwrap(), row["quantity"].as_str().unwrap());
        let (Some(mp_tb), Some(tb_ex), Some(mp_ex)) =
            (number(row, "d_mp_tb"), number(row, "d_tb_ex"), number(row, "d_mp_ex"))
        else {
            continue;
        };
        exact_rows += 1;
        assert!(tb_ex <= 1e-9, "{case} {quantity}: the testbed is {tb_ex:e} from the exact answer");
        assert!(mp_tb <= mp_ex + 1e-9, "{case} {quantity}: {mp_tb:e} from MusclePy, which is {mp_ex:e} from exact");
    }
    assert!(exact_rows >= 88, "{exact_rows} rows with an exact answer");
    // The testbed's linear analysis is MusclePy's linear method (truss2, unstressed at its
    // reference: the same K).
    let linear: Vec<&serde_json::Value> =
        rows.iter().filter(|r| r["quantity"].as_str().unwrap().starts_with("testbed linear analysis:")).collect();
    assert_eq!(linear.len(), 4, "the testbed's linear analysis of truss2");
    for row in linear {
        let d = number(row, "d_mp_tb").unwrap();
        assert!(d <= 1e-12, "{}: {d:e}", row["quantity"]);
    }
    for row in rows.iter().filter(|r| {
        ["svd_2cables", "svd_3cables", "snelson2x_selfstress", "svd_simplex"].contains(&r["case"].as_str().unwrap())
    }) {
        let d = number(row, "d_mp_tb").unwrap_or_else(|| panic!("{row}: no comparison"));
        assert!(d <= 1e-12, "{}: {d:e}", row["quantity"]);
    }
}

/// The lowest frequency of MusclePy's dynamic simplex with its bars' axial stiffness scaled by
/// `scale` and its cables' mass `mc` \[kg\] (`tensegrity modes`, the bars' step cut to suit).
fn simplex_f1_hz(scale: f64, mc: f64) -> f64 {
    let es = format!("Es={}", 7.039e10 * scale);
    let mc = format!("mc={mc}");
    let file = "benches/peers/musclepy/cases/simplex_dynamic.toml";
    let args = ["modes", file, "--set", &es, "--set", &mc, "--set", "sim.dt=1e-7", "--set", "settle.max_time=0.9"];
    let (code, out, err) = common::tensegrity(&[&args[..], &["--json", "-"]].concat());
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out[out.find('{').unwrap()..]).unwrap();
    v["modes"][0]["frequency_hz"].as_f64().unwrap()
}

/// What the simplex's idealizations cost its lowest frequency (the peer's README). With its
/// cables' mass (0.502 kg) and its bars' EA the testbed gives MusclePy's lumped 2.16647 Hz; the
/// rigid-bar limit, by Richardson's rule over EA x 10 and x 100 (f linear in 1/EA near it), is
/// 2.32804 Hz with the cables' mass and 2.52044 Hz without (the README's values from x 100 and
/// x 1000, 2.32810 and 2.52050, within 1e-4). So against the rigid, massless ideal (2.5205 Hz)
/// the bars' EA costs -0.1750 Hz, the cables' mass -0.1924 Hz, and together they cost 0.0134 Hz
/// less than the two added.
#[test]
fn the_simplexs_frequency_splits_into_the_bars_ea_and_the_cables_mass() {
    let rigid = |mc: f64| {
        let (f10, f100) = (simplex_f1_hz(10.0, mc), simplex_f1_hz(100.0, mc));
        f100 + (f100 - f10) / 9.0
    };
    let (elastic_heavy, elastic_light) = (simplex_f1_hz(1.0, 0.502), simplex_f1_hz(1.0, 0.0));
    let (rigid_heavy, rigid_light) = (rigid(0.502), rigid(0.0));
    assert!((elastic_heavy - 2.16647).abs() < 1e-5, "{elastic_heavy}");
    assert!((rigid_heavy - 2.32810).abs() < 1e-4, "{rigid_heavy}");
    assert!((rigid_light - 2.52050).abs() < 1e-4, "{rigid_light}");
    let (ea, mass) = (elastic_light - rigid_light, rigid_heavy - rigid_light);
    let interaction = elastic_heavy - rigid_light - ea - mass;
    assert!((ea + 0.1750).abs() < 2e-4 && (mass + 0.1924).abs() < 2e-4, "{ea} {mass}");
    assert!((interaction - 0.0134).abs() < 2e-4, "{interaction}");
}
