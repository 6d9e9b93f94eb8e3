//! The equilibrium matrix and its four subspaces (`structure/equilibrium.rs`,
//! `tensegrity equilibrium`), each against a closed form.

use super::common;
use std::path::Path;
use tensegrity_testbed::run;
use tensegrity_testbed::scenario;
use tensegrity_testbed::structure::equilibrium::equilibrium_matrix;

/// The report of `tensegrity equilibrium --json -` on `file`.
fn report(file: &str) -> serde_json::Value {
    let (code, out, err) = common::tensegrity(&["equilibrium", file, "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

/// Kenner's 3-strut prism, one strut held (`prism3.toml`): 4 free nodes, 11 members with a free
/// node, so 3 j - b = 1; it has one self-stress state (s = 1) and two mechanisms (m = 2: the
/// prism's infinitesimal twist and its turn about the held strut's line). The state is the
/// settled member forces (the file's baseline, side : polygon : strut = 29.34 : 19.19 : -46.22
/// N) to within 1e-9 of the largest, and the turn about the held strut lies in the mechanisms'
/// span to within 1e-9.
#[test]
fn the_kenner_prisms_self_stress_is_its_settled_forces_and_its_mechanisms_hold_the_turn() {
    let v = report("scenarios/custom/prism3.toml");
    assert_eq!((v["rows"].as_u64(), v["columns"].as_u64(), v["rank"].as_u64()), (Some(12), Some(11), Some(10)));
    assert_eq!((v["self_stress_states"].as_u64(), v["mechanisms"].as_u64()), (Some(1), Some(2)));
    let settled = common::run_file("scenarios/custom/prism3.toml");
    let forces = &settled.points[0].simulated;
    let state = v["self_stress"][0].as_array().unwrap();
    let strut = forces["strut2.force"].abs();
    for pair in state {
        let (name, t) = (pair[0].as_str().unwrap(), pair[1].as_f64().unwrap());
        let force = forces[&format!("{name}.force")] / strut;
        assert!((t - force).abs() <= 1e-9, "{name}: {t} against {force}");
    }
    // The turn about the held strut's line B1-T1: d = w x (p - B1) at each free node.
    let sc =
        scenario::parse(Path::new("prism3.toml"), &std::fs::read_to_string("scenarios/custom/prism3.toml").unwrap())
            .unwrap();
    let state = run::settle_first_point(&sc, None).unwrap();
    let s = state.sim.structure();
    let p: Vec<[f64; 3]> = (0..s.nodes.len()).map(|n| state.sim.node_position(n)).collect();
    let e = equilibrium_matrix(s, &p).unwrap();
    let at = |name: &str| nalgebra::Vector3::from(p[s.node_id(name).unwrap()]);
    let w = (at("T1") - at("B1")).normalize();
    let mut turn = nalgebra::DVector::zeros(3 * e.nodes.len());
    for (k, &n) in e.nodes.iter().enumerate() {
        turn.fixed_rows_mut::<3>(3 * k).copy_from(&w.cross(&(nalgebra::Vector3::from(p[n]) - at("B1"))));
    }
    let turn = turn.normalize();
    let along: f64 = e.mechanisms.iter().map(|m| m.dot(&turn).powi(2)).sum();
    assert!((along - 1.0).abs() <= 1e-9, "the turn's share in the mechanisms' span: {along}");
}

/// A straight rope, a bead between two anchors (the prestressed rope of the structural texts):
/// 3 j = 3 rows, b = 2 members, rank 1, so s = 1 (equal tensions, (1, 1)) and m = 2 (the two
/// motions across the rope, to first order stretching neither segment).
#[test]
fn a_straight_rope_has_one_self_stress_and_two_mechanisms() {
    let structure = r#"[[structure.bodies]]
name = "ground"
fixed = true
nodes = { A = [0, 0, 0], B = [2, 0, 0] }

[[structure.bodies]]
name = "bead"
mass = 0.1
nodes = { P = [1, 0, 0] }

[[structure.cables]]
name = "left"
a = "A"
b = "P"
stiffness = 100.0
length = 0.9

[[structure.cables]]
name = "right"
a = "P"
b = "B"
stiffness = 100.0
length = 0.9
"#;
    let text = common::one_point_head("a bead on a straight rope") + structure;
    let file = std::env::temp_dir().join(format!("tensegrity-equilibrium-rope-{}.toml", std::process::id()));
    std::fs::write(&file, text).unwrap();
    let v = report(file.to_str().unwrap());
    std::fs::remove_file(&file).unwrap();
    assert_eq!(
        (v["rank"].as_u64(), v["self_stress_states"].as_u64(), v["mechanisms"].as_u64()),
        (Some(1), Some(1), Some(2))
    );
    for pair in v["self_stress"][0].as_array().unwrap() {
        assert!((pair[1].as_f64().unwrap() - 1.0).abs() <= 1e-12, "{pair}");
    }
    for shape in v["mechanism_shapes"].as_array().unwrap() {
        let d = &shape[0][1];
        assert!(d[0].as_f64().unwrap().abs() <= 1e-12, "a mechanism moves along the rope: {d}");
    }
}

/// A structure that is not pin-jointed (a body on a joint, a body of three nodes) is refused
/// with exit 2 and the part that is not.
#[test]
fn a_structure_that_is_not_pin_jointed_is_refused_by_name() {
    let (code, _, err) = common::tensegrity(&["equilibrium", "scenarios/ji2014/grid.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("joint 'theta1' holds a body"), "{err}");
}

/// The reactions at the supports: Kenner's prism is held by one strut's two nodes, so the
/// supports take what that strut would carry. By the prism's symmetry it is what each free
/// strut carries: the reactions at B1 and T1 are equal and opposite, along the held strut's
/// line, of the free struts' force (46.22 N) within 1e-9 relative.
#[test]
fn the_kenner_prisms_supports_take_a_struts_force_along_its_line() {
    let v = report("scenarios/custom/prism3.toml");
    let settled = common::run_file("scenarios/custom/prism3.toml");
    let strut = settled.points[0].simulated["strut2.force"].abs();
    let r: Vec<nalgebra::Vector3<f64>> = v["reactions_n"]
        .as_array()
        .unwrap()
        .iter()
        .map(|pair| nalgebra::Vector3::from_iterator(pair[1].as_array().unwrap().iter().map(|x| x.as_f64().unwrap())))
        .collect();
    let names: Vec<&str> = v["reactions_n"].as_array().unwrap().iter().map(|p| p[0].as_str().unwrap()).collect();
    assert_eq!(names, ["B1", "T1"]);
    assert!((r[0] + r[1]).norm() <= 1e-9 * strut, "{} {}", r[0], r[1]);
    assert!((r[0].norm() - strut).abs() <= 1e-9 * strut, "{} against {strut}", r[0].norm());
    let (b1, t1) = (common::node(&settled, "B1"), common::node(&settled, "T1"));
    let axis = nalgebra::Vector3::new(t1[0] - b1[0], t1[1] - b1[1], t1[2] - b1[2]).normalize();
    assert!(r[0].cross(&axis).norm() <= 1e-9 * strut, "off the strut's line: {}", r[0]);
}

/// `tensegrity modes` flags each mode that is a mechanism stiffened by the prestress (less than
/// half of its omega^2 in the members' stretching). On the n-strut prism with one strut held
/// the equilibrium matrix has m mechanisms, one of them the rigid turn about the held strut's
/// line (a zero mode): the modes flag exactly m - 1 others, for n = 3, 4 and 6 (m = 2, 4, 8),
/// and no mode that stretches its members.
#[test]
fn the_modes_flag_as_many_prestress_stiffened_mechanisms_as_the_equilibrium_matrix_has() {
    for (n, m) in [(3, 2), (4, 4), (6, 8)] {
        let set = format!("n={n}");
        let run = |cmd: &str| {
            let (code, out, err) = common::tensegrity(&[cmd, "benches/prism_modes.toml", "--set", &set, "--json", "-"]);
            assert_eq!(code, 0, "{err}");
            serde_json::from_str::<serde_json::Value>(&out).unwrap()
        };
        let (modes, matrix) = (run("modes"), run("equilibrium"));
        assert_eq!(matrix["mechanisms"].as_u64(), Some(m), "n = {n}");
        let flagged = modes["modes"].as_array().unwrap().iter().filter(|x| x["mechanism"] == true).count();
        assert_eq!(flagged as u64, m - 1, "n = {n}");
    }
}

/// The sparse analysis (`structure/sparse_null.rs`: shift-invert subspace iteration on A^T A
/// and A A^T, each vector's singular value read as |A x|) is the dense SVD's: on the 60-strut
/// prism (354 by 239) both find r = 238, s = 1 and m = 116, the same self-stress state within
/// 1e-9 and the same mechanism space (the sine of the largest principal angle between the two
/// bases below 1e-8), and the sparse one's smallest nonzero singular value is the dense one's
/// within 1e-8 relative.
#[test]
fn the_sparse_null_spaces_are_the_dense_svds() {
    use tensegrity_testbed::structure::equilibrium::analysis;
    let overrides = [tensegrity_testbed::scenario::Override { name: "n".into(), value: "60".into() }];
    let sc = scenario::load_with(Path::new("benches/prism_modes.toml"), &overrides).unwrap();
    let state = run::settle_first_point(&sc, None).unwrap();
    let s = state.sim.structure();
    let p: Vec<[f64; 3]> = (0..s.nodes.len()).map(|n| state.sim.node_position(n)).collect();
    let (dense, sparse) = (analysis(s, &p, true).unwrap(), analysis(s, &p, false).unwrap());
    assert_eq!((dense.rank, dense.self_stress.len(), dense.mechanism_count), (238, 1, 116));
    assert_eq!((sparse.rank, sparse.self_stress.len(), sparse.mechanism_count), (238, 1, 116));
    let (t, u) = (&dense.self_stress[0], &sparse.self_stress[0]);
    let sign = t.dot(u).signum();
    assert!((t - u * sign).amax() <= 1e-9, "self-stress off by {:e}", (t - u * sign).amax());
    let basis = |v: &[nalgebra::DVector<f64>]| nalgebra::DMatrix::from_columns(v);
    let (qd, qs) = (basis(&dense.mechanisms), basis(&sparse.mechanisms));
    let sine = (&qs - &qd * (qd.transpose() * &qs)).singular_values().max();
    assert!(sine <= 1e-8, "largest principal angle's sine {sine:e}");
    let smallest = |e: &tensegrity_testbed::structure::equilibrium::EquilibriumMatrix| -> f64 {
        e.singular_values.iter().copied().filter(|&x| x > 1e-10 * e.singular_values[0]).fold(f64::INFINITY, f64::min)
    };
    let (d, sp) = (smallest(&dense), smallest(&sparse));
    assert!((d - sp).abs() <= 1e-8 * d, "smallest nonzero singular value {sp} against {d}");
}
