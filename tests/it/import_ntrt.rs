//! `tensegrity import ntrt`: NTRT YAML models (written for these tests from NTRT's documented
//! format, `doc/source/yaml-model-builder.rst`) become scenarios that run as they are and
//! settle to the closed-form equilibria; what the testbed does not model is listed, never
//! dropped silently; bad input is an error at its line.

use crate::common;
use common::{cross, dot, node, norm, sub, tensegrity, P3};
use std::path::Path;
use tensegrity_testbed::import::ntrt::{import, Axes};
use tensegrity_testbed::report::ScenarioReport;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;
use tensegrity_testbed::structure::MemberKind;

const FIXTURES: &str = "tests/fixtures/ntrt";

fn imported(file: &str) -> (String, Vec<String>) {
    let i = import(&Path::new(FIXTURES).join(file), Axes::ZUp).expect("imports");
    (i.toml, i.skipped)
}

fn run_text(name: &str, toml: &str) -> ScenarioReport {
    let sc = scenario::parse(Path::new(name), toml).unwrap_or_else(|e| panic!("{e}\n{toml}"));
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{name}: {:?} {:?}", r.error, r.failures);
    r
}

/// The prism imports with NTRT's y mapped to z (the drawn bottom at z = 0, the top at
/// z = 1.5), rods of mass density pi r^2 L, strings of rest length drawn - pretension /
/// stiffness; the scenario runs and the top triangle settles turned by pi/2 + pi/3 from the
/// bottom (measured between the two ends of each rod) within 1e-8 rad (measured 1.6e-13).
#[test]
fn ntrt_prism_settles_to_the_closed_form_twist() {
    let (toml, skipped) = imported("prism3.yaml");
    assert!(toml.contains("(x, y, z) in NTRT is (x, -z, y) here"), "{toml}");
    assert!(skipped.iter().any(|s| s.contains("friction = 0.9")), "{skipped:?}");
    assert!(skipped.iter().any(|s| s.contains("damping = 5.0")), "{skipped:?}");
    let sc = scenario::parse(Path::new("prism3.toml"), &toml).unwrap();
    let s = &sc.custom.as_ref().unwrap().structure;
    let t1 = s.nodes[s.node_id("t1").unwrap()].position;
    assert_eq!(t1, [1.0, -0.0, 1.5]);
    let rod_length = (1.5f64 * 1.5 + 3.0).sqrt();
    let rod = s.bodies.iter().find(|b| b.inertia.is_some()).unwrap().inertia.unwrap();
    assert!((rod.mass_kg - 200.0 * std::f64::consts::PI * 0.02 * 0.02 * rod_length).abs() <= 1e-12);
    let side = s.member("string b1-t1").unwrap();
    assert!((side.rest_length_m().unwrap() - (1.5 - 20.0 / 100.0)).abs() <= 1e-15);

    let r = run_text("prism3.toml", &toml);
    let b: Vec<P3> = ["b1", "b2", "b3"].iter().map(|n| node(&r, n)).collect();
    let t: Vec<P3> = ["t1", "t2", "t3"].iter().map(|n| node(&r, n)).collect();
    let centroid = |v: &[P3]| [0, 1, 2].map(|k| v.iter().map(|p| p[k]).sum::<f64>() / 3.0);
    let (cb, ct) = (centroid(&b), centroid(&t));
    let axis = sub(ct, cb).map(|x| x / norm(sub(ct, cb)));
    let flat = |v: P3| {
        let d = dot(v, axis);
        [v[0] - d * axis[0], v[1] - d * axis[1], v[2] - d * axis[2]]
    };
    let expected = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / 3.0;
    let mut worst = 0.0f64;
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let (u, w) = (flat(sub(b[i], cb)), flat(sub(t[j], ct)));
        let twist = dot(cross(u, w), axis).atan2(dot(u, w)).abs();
        worst = worst.max((twist - expected).abs());
    }
    eprintln!("NTRT prism: twist within {worst:.1e} rad of pi/2 + pi/3");
    assert!(worst <= 1e-8, "twist off by {worst} rad");
}

/// The icosahedron from substructures (three rod pairs turned about (1, 1, 1), nested in a
/// file that scales it by 2 and lifts it), bond groups and three builders imports as 6 struts
/// and 24 cables and settles to the closed form: every cable sqrt(6)/4 of the strut length and
/// every strut's compression sqrt(6) times every cable's tension, within 1e-12 and 1e-10
/// (measured 4.6e-15 and 7.0e-13); the tether no
/// builder matches and the node it would hang from are listed as skipped.
#[test]
fn ntrt_icosahedron_from_substructures_settles_to_the_closed_form() {
    let (toml, skipped) = imported("ball.yaml");
    assert!(skipped.iter().any(|s| s.contains("tether") && s.contains("matches no builder")), "{skipped:?}");
    assert!(skipped.iter().any(|s| s.contains("node 'anchor'")), "{skipped:?}");
    assert!(skipped.iter().any(|s| s.contains("motor_inertia = 2.0")), "{skipped:?}");
    assert!(toml.contains("Skipped:\n- "), "{toml}");
    let sc = scenario::parse(Path::new("ball.toml"), &toml).unwrap();
    let s = &sc.custom.as_ref().unwrap().structure;
    assert_eq!((s.count_of(MemberKind::Strut), s.count_of(MemberKind::Cable), s.bodies.len()), (6, 24, 6));
    let n = |name: &str| s.nodes[s.node_id(name).unwrap()].position;
    // Scaled by 2 about the centre, lifted by 3 (NTRT's y is z here).
    let p1n1 = n("ball.p1.n1");
    assert!(norm(sub(p1n1, [0.0, 1.0, 3.0 - 0.45])) <= 1e-12, "{p1n1:?}");
    assert_eq!(s.members_of(MemberKind::Cable).filter(|(_, c)| c.name.starts_with("edge ")).count(), 8);

    let r = run_text("ball.toml", &toml);
    let sim = &r.points[0].simulated;
    let ratio = 6f64.sqrt() / 4.0;
    let strut = norm(sub(node(&r, "ball.p1.n1"), node(&r, "ball.p1.n2")));
    // The first strut is held (a fixed body reports no force): read the last one's.
    let strut_force = sim[&format!("{}.force", s.members_of(MemberKind::Strut).last().unwrap().1.name)];
    let (mut length_error, mut force_error) = (0.0f64, 0.0f64);
    for (_, c) in s.members_of(MemberKind::Cable) {
        let l = norm(sub(node(&r, &s.nodes[c.ends().0].name), node(&r, &s.nodes[c.ends().1].name)));
        length_error = length_error.max((l / strut - ratio).abs());
        let t = sim[&format!("{}.force", c.name)];
        force_error = force_error.max((-strut_force / t - 6f64.sqrt()).abs());
    }
    eprintln!("NTRT icosahedron: cable/strut within {length_error:.1e} of sqrt(6)/4, forces within {force_error:.1e} of sqrt 6");
    assert!(length_error <= 1e-12 && force_error <= 1e-10, "{length_error}, {force_error}");
    for (_, st) in s.members_of(MemberKind::Strut) {
        let l = norm(sub(node(&r, &s.nodes[st.ends().0].name), node(&r, &s.nodes[st.ends().1].name)));
        assert!((l - 2.0).abs() <= 1e-12, "{}: {l}", st.name);
    }
}

/// The imported SuperBall with one added prediction over every cable (`for = { c = "cables"
/// }`): each of its 24 cables is judged against sqrt(6)/4 of the 2 m strut, within 1e-12 m.
#[test]
fn an_imported_superball_checks_every_cable_with_one_added_prediction() {
    let (toml, _) = imported("ball.yaml");
    let added = "\n[[predictions]]\nfor = { c = \"cables\" }\nname = \"cable_length\"\nquantity = \"{c}.length\"\n\
                 formula = \"2*sqrt(6)/4\"\nclass = \"length\"\ntolerance = 1e-12\n";
    let r = run_text("ball.toml", &format!("{toml}{added}"));
    let cables: Vec<_> = r.model_checks.iter().filter(|m| m.name.starts_with("cable_length[")).collect();
    assert_eq!(cables.len(), 24);
    let worst = cables.iter().map(|m| m.max_error).fold(0.0, f64::max);
    eprintln!("NTRT SuperBall: every cable within {worst:.1e} m of sqrt(6)/4 of the strut");
    assert!(cables.iter().all(|m| m.passed) && worst <= 1e-12, "{worst}");
}

/// Errors name the file, line and column: an unknown node in a pair, an unknown top-level
/// key, a builder parameter NTRT does not have, a YAML syntax error, a pretension that leaves
/// no rest length, a missing substructure file (at the parent's key).
#[test]
fn bad_ntrt_files_are_errors_at_their_line() {
    let dir = std::env::temp_dir().join(format!("import-ntrt-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let prism = std::fs::read_to_string(Path::new(FIXTURES).join("prism3.yaml")).unwrap();
    let cases: [(&str, String, &str); 6] = [
        ("unknown node", prism.replace("- [b2, b3]", "- [b2, q9]"), "unknown node 'q9'"),
        ("unknown key", format!("{prism}\ncontrollers:\n  x: 1\n"), "unknown key 'controllers'"),
        ("bad parameter", prism.replace("friction: 0.9", "colour: 0.9"), "unsupported tgRodInfo parameter 'colour'"),
        ("syntax", prism.replace("- [b1, t2]", "- [b1, t2"), "YAML syntax"),
        ("pretension", prism.replace("pretension: 20.0", "pretension: 500.0"), "leaves no rest length"),
        ("missing file", "substructures:\n  a:\n    path: nowhere.yaml\n".to_string(), "substructure 'a'"),
    ];
    for (what, text, message) in cases {
        let file = dir.join(format!("{}.yaml", what.replace(' ', "_")));
        std::fs::write(&file, &text).unwrap();
        let e = import(&file, Axes::ZUp).expect_err(what).to_string();
        assert!(e.contains(message), "{what}: {e}");
        let prefix = format!("{}:", file.display());
        assert!(e.starts_with(&prefix), "{what}: {e}");
        let line: usize = e[prefix.len()..].split(':').next().unwrap().parse().unwrap();
        assert!(line >= 1, "{what}: {e}");
        if what == "unknown node" {
            let want = text.lines().position(|l| l.contains("q9")).unwrap() + 1;
            assert_eq!(line, want, "{e}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The command writes the scenario (which `check` accepts), prints what it skipped on stderr,
/// exits 2 on a bad file and never writes over its input.
#[test]
fn the_import_command_writes_a_scenario_that_checks() {
    let dir = std::env::temp_dir().join(format!("import-ntrt-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("prism.toml");
    let (code, _, err) =
        tensegrity(&["import", "ntrt", "tests/fixtures/ntrt/prism3.yaml", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("skipped: builder 'rod' (tgRodInfo): friction = 0.9"), "{err}");
    let (code, stdout, err) = tensegrity(&["check", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}{err}");
    let (code, _, err) = tensegrity(&["import", "ntrt", "tests/fixtures/ntrt/nowhere.yaml"]);
    assert_eq!(code, 2, "{err}");
    let copy = dir.join("copy.yaml");
    std::fs::copy("tests/fixtures/ntrt/prism3.yaml", &copy).unwrap();
    let (code, _, _) = tensegrity(&["import", "ntrt", copy.to_str().unwrap(), "--out", copy.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert_eq!(
        std::fs::read_to_string(&copy).unwrap(),
        std::fs::read_to_string("tests/fixtures/ntrt/prism3.yaml").unwrap()
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// What the testbed does not model is listed, with its place: a box (tgBoxInfo), a sphere
/// (tgSphereInfo on a node), a node_edge bond; the rest (two prisms joined node to node)
/// still imports and checks.
#[test]
fn boxes_spheres_and_node_edge_bonds_are_listed_as_skipped() {
    let dir = std::env::temp_dir().join(format!("import-ntrt-skips-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(Path::new(FIXTURES).join("prism3.yaml"), dir.join("prism.yaml")).unwrap();
    let top = "substructures:\n  p/q:\n    path: prism.yaml\n    offset: [0, 2, 0]\n\
               nodes:\n  ball: [3, 0, 0]\n  box_a: [4, 0, 0]\n  box_b: [5, 0, 0]\n\
               pair_groups:\n  box:\n    - [box_a, box_b]\n\
               builders:\n  ball:\n    class: tgSphereInfo\n    parameters:\n      radius: 0.5\n\
               bond_groups:\n  string:\n    p/q/node_node:\n      - [t1, b1]\n      - [t2, b2]\n      - [t3, b3]\n\
               \x20 joint:\n    p/q/node_edge:\n      - [t1, b1/b2]\n";
    let file = dir.join("two.yaml");
    std::fs::write(&file, top).unwrap();
    let i = import(&file, Axes::ZUp).unwrap();
    let has = |s: &str| i.skipped.iter().any(|k| k.contains(s));
    assert!(has("tgBoxInfo 'box' between box_a and box_b"), "{:?}", i.skipped);
    assert!(has("sphere node 'ball'"), "{:?}", i.skipped);
    assert!(has("node_edge bond 'p/q/node_edge'"), "{:?}", i.skipped);
    let sc = scenario::parse(Path::new("two.toml"), &i.toml).unwrap_or_else(|e| panic!("{e}\n{}", i.toml));
    let s = &sc.custom.as_ref().unwrap().structure;
    assert_eq!((s.count_of(MemberKind::Strut), s.count_of(MemberKind::Cable)), (6, 21));
    // q is offset by one step of 2 along NTRT's y (z here).
    let (pb1, qb1) = (s.nodes[s.node_id("p.b1").unwrap()].position, s.nodes[s.node_id("q.b1").unwrap()].position);
    assert_eq!(qb1[2] - pb1[2], 2.0);
    std::fs::remove_dir_all(&dir).ok();
}

/// As in NTRT, the last added builder whose tag words the pair has wins: verticals tagged
/// "side string" take the later builder "side string" (200 N/m), not "string" (100 N/m); the
/// name of each cable says which builder made it.
#[test]
fn the_last_matching_builder_wins_as_in_ntrt() {
    let dir = std::env::temp_dir().join(format!("import-ntrt-builders-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let prism = std::fs::read_to_string(Path::new(FIXTURES).join("prism3.yaml")).unwrap();
    let text = prism.replace("    - [b1, t1]", "  side string:\n    - [b1, t1]")
        + "  side string:\n    class: tgBasicActuatorInfo\n    parameters:\n      stiffness: 200.0\n      pretension: 20.0\n";
    let file = dir.join("sides.yaml");
    std::fs::write(&file, &text).unwrap();
    let i = import(&file, Axes::ZUp).unwrap();
    let sc = scenario::parse(Path::new("sides.toml"), &i.toml).unwrap_or_else(|e| panic!("{e}\n{}", i.toml));
    let s = &sc.custom.as_ref().unwrap().structure;
    let side = s.member("side string b1-t1").expect("made by 'side string'");
    assert_eq!(side.cable_law(), Some(&tensegrity_testbed::structure::CableLaw::Elastic { stiffness_n_per_m: 200.0 }));
    assert!((side.rest_length_m().unwrap() - (1.5 - 20.0 / 200.0)).abs() <= 1e-15);
    let bottom = s.member("string b1-b2").unwrap();
    assert_eq!(
        bottom.cable_law(),
        Some(&tensegrity_testbed::structure::CableLaw::Elastic { stiffness_n_per_m: 100.0 })
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A model whose rods all share nodes is one rigid body, held fixed: the import still writes
/// a finite time step and the scenario runs (nothing moves).
#[test]
fn a_single_compound_body_imports_with_finite_settings() {
    let dir = std::env::temp_dir().join(format!("import-ntrt-compound-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("triangle.yaml");
    std::fs::write(&file, "nodes:\n  a: [0, 0, 0]\n  b: [1, 0, 0]\n  c: [0, 1, 0]\npair_groups:\n  rod:\n    - [a, b]\n    - [b, c]\n    - [c, a]\n").unwrap();
    let i = import(&file, Axes::ZUp).unwrap();
    let sc = scenario::parse(Path::new("triangle.toml"), &i.toml).unwrap_or_else(|e| panic!("{e}\n{}", i.toml));
    assert_eq!(sc.custom.as_ref().unwrap().structure.bodies.len(), 1);
    assert!(sc.sim.dt_s > 0.0 && sc.sim.dt_s <= 0.1, "dt {}", sc.sim.dt_s);
    run_text("triangle.toml", &i.toml);
    std::fs::remove_dir_all(&dir).ok();
}

/// An n-strut prism in NTRT's YAML (y up) drawn at its twist pi/2 + pi/n (radius 1, height
/// 1.5), its string builder giving a stiffness and `pretension` only if given.
fn ntrt_prism(n: usize, pretension: Option<f64>) -> String {
    let step = 2.0 * std::f64::consts::PI / n as f64;
    let twist = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / n as f64;
    let mut y = String::from("nodes:\n");
    for i in 0..n {
        let (b, t) = (step * i as f64, step * i as f64 + twist);
        y += &format!("  b{i}: [{:?}, 0.0, {:?}]\n  t{i}: [{:?}, 1.5, {:?}]\n", b.cos(), -b.sin(), t.cos(), -t.sin());
    }
    y += "pair_groups:\n  rod:\n";
    y += &(0..n).map(|i| format!("    - [b{i}, t{i}]\n")).collect::<String>();
    y += "  string:\n";
    for i in 0..n {
        let (j, k) = ((i + 1) % n, (i + n - 1) % n);
        y += &format!("    - [b{i}, b{j}]\n    - [t{i}, t{j}]\n    - [b{i}, t{k}]\n");
    }
    y += "builders:\n  rod:\n    class: tgRodInfo\n    parameters:\n      density: 200.0\n      radius: 0.02\n";
    y += "  string:\n    class: tgBasicActuatorInfo\n    parameters:\n      stiffness: 100.0\n";
    if let Some(p) = pretension {
        y += &format!("      pretension: {p:?}\n");
    }
    y
}

fn import_text(name: &str, yaml: &str) -> tensegrity_testbed::import::Imported {
    let dir = std::env::temp_dir().join(format!("import-ntrt-prestress-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, yaml).unwrap();
    import(&path, Axes::ZUp).unwrap()
}

/// NTRT's default pretension is 0 (every string slack): a 3- and a 5-prism whose file gives
/// none are prestressed by their drawn self-stress instead (least string tension 10 N), the
/// import says so, and each settles within 1e-9 rad of its twist pi/2 + pi/n, measured between
/// each rod's ends about the axis through the polygons' centroids.
#[test]
fn ntrt_prisms_without_pretension_are_prestressed_by_their_self_stress() {
    for n in [3usize, 5] {
        let imported = import_text(&format!("prism{n}.yaml"), &ntrt_prism(n, None));
        assert!(imported.chosen[0].contains("self-stress, its least cable tension 10 N"), "{:?}", imported.chosen);
        let r = run_text("prism.toml", &imported.toml);
        let b: Vec<P3> = (0..n).map(|i| node(&r, &format!("b{i}"))).collect();
        let t: Vec<P3> = (0..n).map(|i| node(&r, &format!("t{i}"))).collect();
        let centroid = |v: &[P3]| [0, 1, 2].map(|k| v.iter().map(|p| p[k]).sum::<f64>() / n as f64);
        let (cb, ct) = (centroid(&b), centroid(&t));
        let axis = sub(ct, cb).map(|x| x / norm(sub(ct, cb)));
        let flat = |v: P3| {
            let d = dot(v, axis);
            [v[0] - d * axis[0], v[1] - d * axis[1], v[2] - d * axis[2]]
        };
        let expected = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / n as f64;
        let worst = (0..n)
            .map(|i| {
                let (u, w) = (flat(sub(b[i], cb)), flat(sub(t[i], ct)));
                (dot(cross(u, w), axis).atan2(dot(u, w)).abs() - expected).abs()
            })
            .fold(0.0, f64::max);
        eprintln!("NTRT {n}-prism without pretension: twist within {worst:.1e} rad of pi/2 + pi/{n}");
        assert!(worst <= 1e-9, "n = {n}: twist off by {worst} rad");
    }
}

/// A pretension the file gives is kept, even 0: then every string is slack at the drawn
/// state, and the run fails on `prestress` naming every string.
#[test]
fn an_ntrt_pretension_of_zero_is_kept_and_the_slack_run_fails() {
    let imported = import_text("slack.yaml", &ntrt_prism(3, Some(0.0)));
    assert!(imported.chosen[0].contains("the file's pretensions"), "{:?}", imported.chosen);
    let sc = scenario::parse(Path::new("slack.toml"), &imported.toml).unwrap();
    let r = run(&sc, &RunOptions::default());
    assert_eq!(r.failures, vec![tensegrity_testbed::report::verdict::Failure::Prestress]);
    let p = r.prestress.unwrap();
    eprintln!("NTRT prism at pretension 0: {p:?}");
    assert_eq!(p.slack_cables.len(), 9, "{p:?}");
}
