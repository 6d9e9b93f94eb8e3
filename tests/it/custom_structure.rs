//! Mechanisms described in a scenario file: the 3-strut prism and a Snelson X, with no Rust.

use crate::common;
use common::{cross, dot, node, norm, run_file, sub, P3};
use std::path::Path;
use std::process::Command;
use tensegrity_testbed::mechanisms::furet2018::analytic as furet;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

/// The prism settles with the top triangle turned by pi/2 + pi/3 = 150 degrees from the bottom
/// (within 1e-8 rad), force densities side : strut : polygon = 1 : -1 : 1/sqrt(3) (within 1e-8),
/// and a node force residual below 1e-9 of the largest member force.
#[test]
fn prism3_settles_at_150_degrees_with_the_self_stress_ratios() {
    let r = run_file("scenarios/custom/prism3.toml");
    assert!(r.passed, "{:?}", r.error);
    let b: Vec<P3> = (1..=3).map(|i| node(&r, &format!("B{i}"))).collect();
    let t: Vec<P3> = (1..=3).map(|i| node(&r, &format!("T{i}"))).collect();
    let centroid = |v: &[P3]| [0, 1, 2].map(|k| v.iter().map(|p| p[k]).sum::<f64>() / 3.0);
    let (cb, ct) = (centroid(&b), centroid(&t));
    let axis = sub(ct, cb);
    let axis = axis.map(|x| x / norm(axis));
    let proj = |v: P3| {
        let d = dot(v, axis);
        [v[0] - d * axis[0], v[1] - d * axis[1], v[2] - d * axis[2]]
    };
    let (u, w) = (proj(sub(b[0], cb)), proj(sub(t[0], ct)));
    let twist = dot(cross(u, w), axis).atan2(dot(u, w));
    let expected = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / 3.0;
    assert!((twist - expected).abs() <= 1e-8, "twist {twist} rad, expected {expected}");
    let s = &r.points[0].simulated;
    let q = |member: &str, a: P3, c: P3| s[&format!("{member}.force")] / norm(sub(a, c));
    let q_side = q("side1", b[0], t[2]);
    assert!(q_side > 0.0);
    let q_strut = q("strut2", b[1], t[1]) / q_side;
    let q_poly = q("top23", t[1], t[2]) / q_side;
    assert!((q_strut + 1.0).abs() <= 1e-8, "strut : side = {q_strut}");
    assert!((q_poly - 1.0 / 3f64.sqrt()).abs() <= 1e-8, "polygon : side = {q_poly}");
    let largest = s.iter().filter(|(k, _)| k.ends_with(".force")).map(|(_, v)| v.abs()).fold(0.0, f64::max);
    let p = &r.points[0];
    assert!(p.residual_force_n <= 1e-9 * largest, "residual {} N of {largest} N", p.residual_force_n);
}

/// A Snelson X built from the file alone agrees with the built-in furet2018 module (Eq. 1-2 for
/// one X at theta = 0.3) within 1e-10.
#[test]
fn snelson_x_from_a_file_agrees_with_the_furet2018_module() {
    let r = run_file("scenarios/custom/snelson-x.toml");
    assert!(r.passed, "{:?}", r.error);
    let x = furet::chain_nodes(&furet::Params { l: 1.0, b: 2.0 / 3.0 }, &[0.3])[0];
    let p = node(&r, "P");
    assert!((p[0] - x.top_mid.x).abs() <= 1e-10 && (p[1] - x.top_mid.y).abs() <= 1e-10, "{p:?} vs {:?}", x.top_mid);
    for (n, want) in [("C", x.top_right), ("D", x.top_left)] {
        let got = node(&r, n);
        assert!((got[0] - want.x).abs() <= 1e-10 && (got[1] - want.y).abs() <= 1e-10, "{n}: {got:?}");
    }
}

/// Bad references, zero-length members and massless bodies are errors at their place.
#[test]
fn structure_errors_name_file_line_and_column() {
    let good = std::fs::read_to_string("scenarios/custom/snelson-x.toml").unwrap();
    let cases = [
        ("unknown node", good.replacen("a = \"D\"\nb = \"C\"", "a = \"Q\"\nb = \"C\"", 1), "unknown node 'Q'"),
        ("unknown body", good.replacen("parent = \"bar_AC\"", "parent = \"bar_XX\"", 1), "unknown body 'bar_XX'"),
        ("massless body", good.replacen("name = \"top\"\nmass = 0.1", "name = \"top\"", 1), "needs a mass"),
        ("zero-length member", good.replacen("a = \"A\"\nb = \"D\"", "a = \"A\"\nb = \"A\"", 1), "zero length"),
        ("unknown joint kind", good.replacen("kind = \"planar_pin\"", "kind = \"hinge\"", 1), "unknown joint kind"),
        ("check without value", good.replacen("value = ", "# value = ", 1), "give the expected value"),
    ];
    let dir = std::env::temp_dir().join(format!("tensegrity-custom-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (what, text, msg) in cases {
        assert_ne!(text, good, "{what}: the replacement must change the file");
        let p = dir.join(format!("{}.toml", what.replace(' ', "_")));
        std::fs::write(&p, &text).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_tensegrity")).args(["check", p.to_str().unwrap()]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{what}: {err}");
        let prefix = format!("{}:", p.display());
        assert!(err.contains(&prefix) && err.contains(msg), "{what}: {err}");
        let after = &err[err.find(&prefix).unwrap() + prefix.len()..];
        assert!(after.chars().next().unwrap().is_ascii_digit(), "{what}: no line:col in {err}");
    }
}

/// The chapter on custom structures, moved there from the README.
const CUSTOM_STRUCTURES: &str = "docs/custom-structures.md";

/// The example of a custom structure (`docs/custom-structures.md`) is a complete scenario that
/// passes.
#[test]
fn the_readme_example_runs_and_passes() {
    let chapter = std::fs::read_to_string(CUSTOM_STRUCTURES).unwrap();
    let start = chapter
        .find("name = \"Snelson X module\"\nmechanism = \"custom\"")
        .expect("example in docs/custom-structures.md");
    let text = &chapter[start..start + chapter[start..].find("```").unwrap()];
    let sc = scenario::parse(Path::new(CUSTOM_STRUCTURES), text).expect("the example parses");
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?}", r.error);
}

/// The defaults the table of `docs/custom-structures.md` states, read off the pinned strut of `common.rs` with its
/// gravity, joint damping and spring length taken out and a cable added: the 1 m bar of 1 kg on
/// nodes (0, 0, 0) and (1, 0, 0) gets its centre of mass at the midpoint and the isotropic
/// moment 1 x 1^2 / 12 kg m^2 (a uniform thin rod's about its middle) within 1e-15; a strut
/// radius 0.01 m, a cable's and a spring's 0.001 m, a cable inextensible of the drawn length
/// 1 m (the spring's too), a joint undamped without torsion spring at coordinate 0, no
/// gravity, and the `[sim]` and `[settle]` defaults; the chapter's table says each.
#[test]
fn the_documented_defaults_are_the_structures() {
    let text = common::PINNED_STRUT.replace("gravity = [0.0, 0.0, 0.0]\n", "").replace("damping = 0.5\n", "");
    let text = text.replace("length = 0.5\n", "") + "[[structure.cables]]\nname = \"c\"\na = \"Q\"\nb = \"S\"\n";
    let sc = scenario::parse(Path::new("defaults.toml"), &text).unwrap_or_else(|e| panic!("{e}"));
    let s = &sc.custom.as_ref().unwrap().structure;
    let i = s.bodies[1].inertia.as_ref().unwrap();
    assert!(i.com.iter().zip([0.5, 0.0, 0.0]).all(|(a, b)| (a - b).abs() <= 1e-15), "{:?}", i.com);
    assert!(i.principal_kg_m2.iter().all(|m| (m - 1.0 / 12.0).abs() <= 1e-15), "{:?}", i.principal_kg_m2);
    let first = |kind| s.members_of(kind).next().unwrap().1;
    let (strut, cable, spring) = (
        first(tensegrity_testbed::structure::MemberKind::Strut),
        first(tensegrity_testbed::structure::MemberKind::Cable),
        first(tensegrity_testbed::structure::MemberKind::Spring),
    );
    assert_eq!((strut.radius_m, cable.radius_m, spring.radius_m), (0.01, 0.001, 0.001));
    assert_eq!(cable.cable_law(), Some(&tensegrity_testbed::structure::CableLaw::Inextensible));
    let drawn = 1.0;
    let rest = |m: &tensegrity_testbed::structure::Member| m.rest_length_m().unwrap();
    assert!((rest(cable) - drawn).abs() <= 1e-15 && (rest(spring) - drawn).abs() <= 1e-15);
    let j = &s.joints[0];
    assert_eq!((j.damping, j.torsion_spring.is_none(), j.initial_coordinate, s.gravity), (0.0, true, 0.0, [0.0; 3]));
    let (sim, settle) = (&sc.sim, &sc.settle);
    assert_eq!((sim.dt_s, sim.substeps, sim.pgs_iterations, sim.body_damping_per_s), (0.01, 1, 8, 0.0));
    assert_eq!((sim.relaxation, sim.bounding_box_m, sim.max_kinetic_energy_j), (true, 1000.0, 1e6));
    assert!(sim.newton_damping, "a custom tree of joints");
    assert_eq!((settle.speed_tol_m_per_s, settle.window_steps, settle.max_time_s), (1e-10, 10, 60.0));
    assert_eq!((settle.residual_force_tol_n, settle.residual_torque_tol_nm), (1e-7, 1e-7));
    let chapter = std::fs::read_to_string(CUSTOM_STRUCTURES).unwrap();
    for row in [
        "| 0.01 s, 1, 8, 0 1/s, true, 1000 m, 1e6 J |",
        "| 1e-10 m/s, 10 steps, 1e-7 N, 1e-7 N m, 60 s |",
        "| a free body's centre of mass | the mean of its nodes",
        "| a free body's inertia | isotropic m s^2 / 12",
        "| strut radius (interference, drawing) | 0.01 m |",
        "| cable and spring radius | 0.001 m |",
        "| cable stiffness | none: inextensible |",
        "| cable and spring length | the drawn distance |",
        "| joint damping, torsion spring, `torsion_rest`, `initial_coordinate` | 0 N m s/rad (N s/m), none, 0 rad, 0 |",
        "| gravity | none |",
    ] {
        assert!(chapter.contains(row), "the defaults table of {CUSTOM_STRUCTURES} lacks: {row}");
    }
}
