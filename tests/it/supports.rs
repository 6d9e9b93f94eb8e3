//! Supports in some directions (`[[structure.supports]]`): a point mass held along some world
//! axes, in the settle, the equilibrium matrix with its reactions, and the modes, each against a
//! closed form.

use super::common;
use nalgebra::{DMatrix, Matrix2, Vector2};
use std::path::Path;
use tensegrity_testbed::scenario;

const TRUSS: &str = "scenarios/custom/truss_on_a_roller.toml";

fn truss() -> String {
    std::fs::read_to_string(TRUSS).unwrap()
}

/// The pin takes P / 2 up and the roller P / 2 up, nothing along its rail, within 1e-9 of P
/// (P = 200 N, the file's first point); the apex, held only across the truss's plane, takes
/// nothing. A is 3 rows (j = 2 free nodes, 3 coordinates held) by 3 bars: r = 3, statically and
/// kinematically determinate (s = m = 0).
#[test]
fn a_roller_truss_reactions_are_half_the_load_each_and_none_along_the_rail() {
    let v = common::json_of("equilibrium", &truss(), "reactions");
    let counts = ["rows", "free_nodes", "held_coordinates", "columns", "rank", "self_stress_states", "mechanisms"];
    let got: Vec<u64> = counts.iter().map(|k| v[k].as_u64().unwrap()).collect();
    assert_eq!(got, [3, 2, 3, 3, 3, 0, 0], "{counts:?}");
    let p = 200.0;
    let want = [("A", [0.0, 0.0, p / 2.0]), ("B", [0.0, 0.0, p / 2.0]), ("C", [0.0; 3])];
    let reactions = v["reactions_n"].as_array().unwrap();
    assert_eq!(reactions.len(), 3);
    for ((node, r), (name, w)) in reactions.iter().map(|x| (x[0].as_str().unwrap(), &x[1])).zip(want) {
        assert_eq!(node, name);
        for k in 0..3 {
            let r = r[k].as_f64().unwrap();
            assert!((r - w[k]).abs() <= 1e-9 * p, "{node}[{k}]: {r} against {}", w[k]);
        }
    }
}

/// The stiffness of a member of tension t and length l along the unit e, in the truss's plane
/// (x, z): k e e^T + (t / l)(1 - e e^T).
fn member_stiffness(k: f64, t: f64, l: f64, e: Vector2<f64>) -> Matrix2<f64> {
    e * e.transpose() * k + (Matrix2::identity() - e * e.transpose()) * (t / l)
}

/// The modes are those of the three coordinates the supports leave (the roller's x, the apex's
/// x and z): the eigenvalues of K v = omega^2 m v with K assembled by hand from the bars' and
/// the tie's tangent stiffness at the loaded shape (tie: tension P a / (2 h), bars:
/// compression P L / (2 h)), within 1e-9 relative.
#[test]
fn the_roller_truss_modes_are_those_of_its_three_free_coordinates() {
    let v = common::json_of("modes", &truss(), "modes");
    let (a, h, p, k_tie, k_bar, m) = (1.0_f64, 0.75_f64, 200.0, 1e4, 2e4, 10.0);
    let l = a.hypot(h);
    let (tie, bar) = (p * a / (2.0 * h), -p * l / (2.0 * h));
    // B's and C's (x, z), then the three the supports leave: B.x, C.x, C.z.
    let mut full = DMatrix::<f64>::zeros(4, 4);
    let mut add = |r: usize, c: usize, block: Matrix2<f64>| {
        let mut view = full.view_mut((r, c), (2, 2));
        view += block;
    };
    add(0, 0, member_stiffness(k_tie, tie, 2.0 * a, Vector2::new(1.0, 0.0)));
    add(2, 2, member_stiffness(k_bar, bar, l, Vector2::new(a, h) / l));
    let right = member_stiffness(k_bar, bar, l, Vector2::new(-a, h) / l);
    add(0, 0, right);
    add(2, 2, right);
    add(0, 2, -right);
    add(2, 0, -right);
    let k = full.select_rows(&[0, 2, 3]).select_columns(&[0, 2, 3]);
    let mut want: Vec<f64> = k.symmetric_eigen().eigenvalues.iter().map(|x| x / m).collect();
    want.sort_by(f64::total_cmp);
    let modes = v["modes"].as_array().unwrap();
    assert_eq!((v["coordinates"].as_u64(), modes.len()), (Some(3), 3));
    for (mode, w) in modes.iter().zip(want) {
        let got = mode["omega_squared"].as_f64().unwrap();
        assert!((got - w).abs() <= 1e-9 * w, "omega^2 {got} against {w}");
    }
}

/// With the roller held only vertically (its y free), no member stretches as B moves across
/// the truss's plane: 4 rows, one mechanism, B moving along y alone. Its stiffness is the
/// prestress's alone, the tie's tension over its length less the bar's compression over its
/// own, T / (2 a) - C / L = -66.7 N/m at P = 200 N: the compressed bar pushes the roller off its
/// line, and the lowest mode is that unstable one, omega^2 = (T / (2 a) - C / L) / m within 1e-9.
#[test]
fn a_direction_that_no_member_stretches_is_a_mechanism_stiffened_by_the_prestress_alone() {
    let text = common::edited(TRUSS, &[("fixed = [\"y\", \"z\"]", "fixed = [\"z\"]")]);
    let v = common::json_of("equilibrium", &text, "mechanism");
    assert_eq!((v["rows"].as_u64(), v["rank"].as_u64(), v["mechanisms"].as_u64()), (Some(4), Some(3), Some(1)));
    for (node, d) in v["mechanism_shapes"][0].as_array().unwrap().iter().map(|x| (x[0].as_str().unwrap(), &x[1])) {
        let d: Vec<f64> = (0..3).map(|k| d[k].as_f64().unwrap().abs()).collect();
        let want = if node == "B" { [0.0, 1.0, 0.0] } else { [0.0; 3] };
        assert!(d.iter().zip(want).all(|(d, w)| (d - w).abs() <= 1e-12), "{node}: {d:?}");
    }
    let modes = common::json_of("modes", &text, "mechanism-modes");
    let (a, h, p, m) = (1.0_f64, 0.75_f64, 200.0, 10.0);
    let (tie, bar) = (p * a / (2.0 * h), p * a.hypot(h) / (2.0 * h));
    let want = (tie / (2.0 * a) - bar / a.hypot(h)) / m;
    let lowest = &modes["modes"][0];
    assert_eq!(modes["coordinates"].as_u64(), Some(4));
    let got = lowest["omega_squared"].as_f64().unwrap();
    assert!((got - want).abs() <= 1e-9 * want.abs(), "omega^2 {got} against {want}");
    assert!(lowest["node_displacements_m"][1][1][1].as_f64().unwrap().abs() > 0.0, "{lowest}");
}

/// A string of `n` beads of mass 0.1 kg on springs between two anchors 2 m apart, sagging under
/// gravity, each bead held across the string's plane where `held`.
fn chain(n: usize, held: bool) -> String {
    let mut text = common::one_point_head("a beaded chain").replace("gravity = [0, 0, 0]", "gravity = [0, 0, -9.81]");
    let x = |i: usize| -1.0 + 2.0 * i as f64 / (n + 1) as f64;
    text += "[[structure.bodies]]\nname = \"ground\"\nfixed = true\nnodes = { A = [-1, 0, 0], B = [1, 0, 0] }\n\n";
    for i in 1..=n {
        text +=
            &format!("[[structure.bodies]]\nname = \"bead{i}\"\nmass = 0.1\nnodes = {{ P{i} = [{}, 0, 0] }}\n\n", x(i));
        if held {
            text += &format!("[[structure.supports]]\nnode = \"P{i}\"\nfixed = [\"y\"]\n\n");
        }
    }
    let name = |i: usize| {
        if i == 0 {
            "A".to_string()
        } else if i == n + 1 {
            "B".to_string()
        } else {
            format!("P{i}")
        }
    };
    for i in 0..=n {
        let (a, b) = (name(i), name(i + 1));
        text += &format!(
            "[[structure.springs]]\nname = \"s{i}\"\na = \"{a}\"\nb = \"{b}\"\nstiffness = 400.0\nlength = {}\n\n",
            1.6 / (n + 1) as f64
        );
    }
    text
}

/// Twelve beads (the relaxation's sparse step, past eight free bodies): held across the plane,
/// the chain settles where it settles free, every bead within 1e-9 m, and exactly in the plane;
/// its modes are the free chain's in-plane modes (24 of its 36), each omega^2 within 1e-9.
#[test]
fn a_chain_held_in_its_plane_settles_and_vibrates_as_the_free_chain_does_in_it() {
    let n = 12;
    let run = |held: bool| {
        let sc = scenario::parse(Path::new("chain.toml"), &chain(n, held)).expect("valid");
        tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default())
    };
    let (held, free) = (run(true), run(false));
    assert!(held.points[0].settled && free.points[0].settled, "{}", held.verdict_line());
    for i in 1..=n {
        let (p, q) = (common::node(&held, &format!("P{i}")), common::node(&free, &format!("P{i}")));
        assert!(p[1] == 0.0, "P{i} left the plane: {p:?}");
        assert!((0..3).all(|k| (p[k] - q[k]).abs() <= 1e-9), "P{i}: {p:?} against {q:?}");
    }
    let (held, free) = (
        common::json_of("modes", &chain(n, true), "chain-held"),
        common::json_of("modes", &chain(n, false), "chain-free"),
    );
    let omega2 = |v: &serde_json::Value| -> Vec<f64> {
        v["modes"].as_array().unwrap().iter().map(|m| m["omega_squared"].as_f64().unwrap()).collect()
    };
    let (held, free) = (omega2(&held), omega2(&free));
    assert_eq!((held.len(), free.len()), (2 * n, 3 * n));
    let largest = free.iter().fold(0.0_f64, |l, w| l.max(w.abs()));
    for w in held {
        let nearest = free.iter().map(|f| (f - w).abs()).fold(f64::INFINITY, f64::min);
        assert!(nearest <= 1e-9 * largest, "omega^2 {w}: nearest free mode {nearest:e} away");
    }
}

/// Bad supports are refused at their place in the file: an unknown direction, one named twice,
/// none, a node on the fixed ground, a node of a rigid body with two nodes, and a second
/// support at one node.
#[test]
fn bad_supports_are_refused_at_their_key() {
    let text = truss();
    let at = |from: &str, to: &str, mark: &str, msg: &str| {
        let variant = text.replacen(from, to, 1);
        common::error_at(&variant, mark, 0, msg);
    };
    at("fixed = [\"y\", \"z\"]", "fixed = [\"y\", \"w\"]", "[\"y\", \"w\"]", "'w' is not a direction");
    at("fixed = [\"y\", \"z\"]", "fixed = [\"z\", \"z\"]", "[\"z\", \"z\"]", "'z' is listed twice");
    at("fixed = [\"y\", \"z\"]", "fixed = []", "[]", "fixed lists no direction");
    at("node = \"B\"\nfixed", "node = \"A\"\nfixed", "\"A\"\nfixed", "which is fixed");
    at("node = \"C\"\nfixed", "node = \"B\"\nfixed", "\"B\"\nfixed = [\"y\"]", "has a support already");
    let rigid = text.replacen(
        "nodes = { B = [\"tie0\", 0, 0] }",
        "nodes = { B = [\"tie0\", 0, 0], B2 = [\"tie0\", 0.1, 0] }",
        1,
    );
    common::error_at(&rigid, "\"B\"\nfixed", 0, "is not a point mass");
}

/// A structure with supports in some directions has no sensitivities yet: `sensitivity` exits 2
/// naming the supported node, where a silent answer would read the supports' reactions as
/// out-of-balance forces.
#[test]
fn sensitivities_of_a_structure_with_supports_are_refused_by_name() {
    let (code, _, err) = common::tensegrity(&["sensitivity", TRUSS]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("node 'B' has a support in some directions"), "{err}");
}

/// Past 100 free bodies the modes come from the sparse solver, where each held coordinate
/// stands in the relaxation's Hessian with a stiffness of its own: on a chain of 110 beads held
/// in its plane, the sparse solver's lowest modes are the dense solver's (which drops the held
/// coordinates), each omega^2 within 1e-8 of the largest computed, with none of the stand-ins.
#[test]
fn the_sparse_modes_of_a_held_chain_are_its_dense_modes() {
    let sc = scenario::parse(Path::new("chain.toml"), &chain(110, true)).expect("valid");
    let mut state = tensegrity_testbed::run::settle_first_point(&sc, None).expect("settles");
    let sparse = state.sim.modes().expect("sparse modes");
    let dense = state.sim.modes_dense().expect("dense modes");
    assert_eq!(dense.modes.len(), 220);
    assert!(sparse.lowest_of.is_some() && sparse.modes.len() >= 10, "{} modes", sparse.modes.len());
    let scale = sparse.modes.iter().fold(0.0_f64, |l, m| l.max(m.omega_squared.abs()));
    for (s, d) in sparse.modes.iter().zip(&dense.modes) {
        assert!(
            (s.omega_squared - d.omega_squared).abs() <= 1e-8 * scale,
            "{} against {}",
            s.omega_squared,
            d.omega_squared
        );
    }
}

/// A truss bar is a spring stated by its EA: `EA = "k_tie*tie0"` in place of the tie's
/// stiffness gives EA / L0 = k_tie, and the truss stands where it does with the stiffness, the
/// roller within 1e-12 m.
#[test]
fn a_spring_stated_by_its_ea_is_a_bar_of_stiffness_ea_over_its_free_length() {
    let text = common::edited(TRUSS, &[("stiffness = \"k_tie\"", "EA = \"k_tie*tie0\"")]);
    let run = |text: &str| {
        let sc = scenario::parse(Path::new("truss.toml"), text).expect("valid");
        tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default())
    };
    let (by_ea, by_k) = (run(&text), run(&truss()));
    let (b, c) = (common::node(&by_ea, "B"), common::node(&by_k, "B"));
    assert!((b[0] - c[0]).abs() <= 1e-12 && (b[0] - 2.0).abs() <= 1e-9, "{b:?} against {c:?}");
}
