//! The linear (small-displacement) analysis beside the exact settle (`structure/linear.rs`,
//! `tensegrity equilibrium` on a file with point loads), each against a closed form.

use super::common;
use super::point_loads::{rope, rope_deflection};

const TRUSS: &str = "scenarios/custom/truss_on_a_roller.toml";

fn linear(v: &serde_json::Value) -> &serde_json::Value {
    assert!(v["linear"].is_object(), "no linear analysis: {}", v["linear_refused"]);
    &v["linear"]
}

/// The (exact, linear) displacement of `node` and the (exact, linear) force of `member`.
fn node_and_member(v: &serde_json::Value, node: &str, member: &str) -> (([f64; 3], [f64; 3]), (f64, f64)) {
    let xyz = |x: &serde_json::Value| [0, 1, 2].map(|k| x[k].as_f64().unwrap());
    let d = linear(v)["displacements_m"].as_array().unwrap().iter().find(|r| r[0] == node).unwrap();
    let f = linear(v)["forces_n"].as_array().unwrap().iter().find(|r| r[0] == member).unwrap();
    ((xyz(&d[1]), xyz(&d[2])), (f[1].as_f64().unwrap(), f[2].as_f64().unwrap()))
}

/// The roller truss at P = 200 N, unstressed unloaded: the linear method is statics at the
/// drawn geometry (half span a0, height h0, bar length L0), T = P a0 / (2 h0) and
/// C = -P L0 / (2 h0), and compatibility there: the roller slides by T / k_tie, and the apex
/// moves so that each bar shortens by C / k_bar along its drawn direction. Each within 1e-9
/// (relative for the forces, of the displacement in metres). The exact settle's tie force,
/// P a / (2 h) at the loaded shape, differs from it by 3.7 %: the truss is soft.
#[test]
fn the_linear_analysis_of_the_roller_truss_is_statics_and_compatibility_at_the_drawn_shape() {
    let v = common::json_of("equilibrium", &std::fs::read_to_string(TRUSS).unwrap(), "truss");
    let (p, k_tie, k_bar) = (200.0, 1e4, 2e4);
    let (a, h) = (1.0_f64, 0.75_f64);
    let (t, c) = (p * a / (2.0 * h), p * a.hypot(h) / (2.0 * h));
    let (tie0, bar0) = (2.0 * a - t / k_tie, a.hypot(h) + c / k_bar);
    let (a0, h0) = (tie0 / 2.0, (bar0 * bar0 - tie0 * tie0 / 4.0).sqrt());
    let (tie_lin, bar_lin) = (p * a0 / (2.0 * h0), -p * bar0 / (2.0 * h0));
    let ((b_exact, b), (tie_exact, tie)) = node_and_member(&v, "B", "tie");
    let ((_, apex), (_, left)) = node_and_member(&v, "C", "left");
    let (_, (_, right)) = node_and_member(&v, "B", "right");
    for (got, want) in [(tie, tie_lin), (left, bar_lin), (right, bar_lin)] {
        assert!((got - want).abs() <= 1e-9 * want.abs(), "{got} against {want}");
    }
    assert!((b[0] - tie_lin / k_tie).abs() <= 1e-9 && b[1] == 0.0 && b[2] == 0.0, "{b:?}");
    // The bars' drawn unit vectors from A and from B to the apex; each bar shortens by C / k.
    let (left_e, right_e) = ([a0 / bar0, h0 / bar0], [-a0 / bar0, h0 / bar0]);
    let stretch = |e: [f64; 2], u: [f64; 2]| e[0] * u[0] + e[1] * u[1];
    let apex_xz = [apex[0], apex[2]];
    assert!((stretch(left_e, apex_xz) - bar_lin / k_bar).abs() <= 1e-9, "{apex:?}");
    assert!((stretch(right_e, [apex[0] - b[0], apex[2]]) - bar_lin / k_bar).abs() <= 1e-9, "{apex:?}");
    assert!((b_exact[0] - t / k_tie).abs() <= 1e-9 && (tie_exact - t).abs() <= 1e-9 * t);
    assert!(((tie_exact - tie) / tie - 0.0369).abs() <= 5e-4, "{tie_exact} against {tie}");
}

/// A bead on a rope pretensioned to t0 = k (a - l0), pulled across by P: to first order the
/// rope's tension stays t0 and the bead moves by P a / (2 t0) (the geometric stiffness alone),
/// both within 1e-12 relative. The exact deflection is smaller by a term of order P^3, so the
/// two differ relatively as P^2: over P = 0.02 and 0.2 N their relative difference grows by
/// 100, fitted order 2 within 0.01, and it is 3.12e-4 at P = 0.2 N.
#[test]
fn the_linear_deflection_of_a_pretensioned_rope_is_exact_to_first_order() {
    let (a, k, l0) = (1.0, 40.0, 0.8);
    let t0 = k * (a - l0);
    let mut differences = Vec::new();
    for p in [0.02, 0.2] {
        let v = common::json_of("equilibrium", &rope(p), &format!("rope-{p}"));
        let ((exact, d), (_, t)) = node_and_member(&v, "P", "left");
        let want = p * a / (2.0 * t0);
        assert!((d[2] + want).abs() <= 1e-12 * want && d[0].abs() <= 1e-15, "P = {p}: {d:?} against -{want}");
        assert!((t - t0).abs() <= 1e-12 * t0, "P = {p}: {t} against {t0}");
        let exact_d = rope_deflection(a, k, l0, p);
        assert!((exact[2] + exact_d).abs() <= 1e-9, "P = {p}: {exact:?} against {exact_d}");
        differences.push((want - exact_d) / exact_d);
    }
    let order = (differences[1] / differences[0]).log10();
    assert!((order - 2.0).abs() <= 0.01 && (differences[1] - 3.12e-4).abs() <= 1e-5, "{differences:?}");
}

/// Where K is singular about the reference (the truss unstressed unloaded, its roller free
/// across its plane: nothing stiffens B's y), the report says why it has no linear analysis
/// and keeps the rest.
#[test]
fn a_mechanism_without_prestress_has_no_linear_analysis_and_says_why() {
    let text = common::edited(TRUSS, &[("fixed = [\"y\", \"z\"]", "fixed = [\"z\"]")]);
    let v = common::json_of("equilibrium", &text, "singular");
    assert!(v["linear"].is_null(), "{}", v["linear"]);
    let why = v["linear_refused"].as_str().unwrap();
    assert!(why.contains("the tangent stiffness is singular"), "{why}");
    assert_eq!(v["mechanisms"].as_u64(), Some(1));
}
