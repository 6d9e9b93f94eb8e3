//! Patterns: a structure written once over an index range (`[[structure.repeat]]`), checks
//! written once over a range or a group of members (`for`), aggregates, and a sweep over a
//! parameter that changes the topology.

use crate::common::tensegrity;
use std::path::Path;
use tensegrity_testbed::scenario::{parse, ScenarioError};
use tensegrity_testbed::structure::MemberKind;

/// The regular prism's twist pi/2 + pi/n is met within this at every n [rad].
const TWIST_TOL_RAD: f64 = 1e-12;

/// Round-off on a node placed by a repeat's rotation and offset [m].
const PLACEMENT_TOL_M: f64 = 1e-15;

fn load(text: &str) -> Result<tensegrity_testbed::scenario::Scenario, ScenarioError> {
    parse(Path::new("pattern.toml"), text)
}

/// A ring of `n` fixed rods, each rod i turned by i quarter turns and lifted by 0.1 i m, and
/// one free body on springs to every rod (so the structure settles).
fn ring(n: &str, extra: &str) -> String {
    format!(
        r#"name = "ring"
mechanism = "custom"
[params]
n = {n}
[actuation]
points = [ {{}} ]
[structure]
[[structure.repeat]]
for = {{ i = "0..n" }}
rotate = {{ axis = [0, 0, 1], angle = "i*pi/2" }}
offset = [0, 0, "0.1*i"]
[[structure.repeat.bodies]]
name = "rod{{i}}"
fixed = true
nodes = {{ "A{{i}}" = [1, 0, 0], "B{{i}}" = [2, 0, 0] }}
[[structure.repeat.springs]]
name = "s{{i}}"
a = "A{{i}}"
b = "C"
stiffness = 10.0
length = 0.5
[[structure.bodies]]
name = "hub"
mass = 1.0
nodes = {{ C = [0, 0, 0.2] }}
{extra}"#
    )
}

#[test]
fn a_repeat_places_each_copy_by_its_rotation_then_its_offset() {
    let sc = load(&ring("4", "")).expect("valid");
    let s = &sc.custom.as_ref().expect("custom").structure;
    let at = |name: &str| s.nodes.iter().find(|n| n.name == name).unwrap_or_else(|| panic!("{name}")).position;
    // Rod 3: (1, 0, 0) turned by 3 pi/2 is (0, -1, 0), then lifted by 0.3 m.
    for (got, want) in [(at("A3"), [0.0, -1.0, 0.3]), (at("B1"), [0.0, 2.0, 0.1]), (at("A0"), [1.0, 0.0, 0.0])] {
        let err = got.iter().zip(want).map(|(g, w)| (g - w).abs()).fold(0.0, f64::max);
        assert!(err <= PLACEMENT_TOL_M, "{got:?} against {want:?}");
    }
    assert_eq!(s.count_of(MemberKind::Spring), 4);
    assert_eq!(s.bodies.len(), 5);
}

#[test]
fn templates_wrap_around_the_ring_and_a_name_twice_is_an_error_at_the_template() {
    let wrapped = ring("3", "[[structure.repeat]]\nfor = { i = \"0..n\" }\n[[structure.repeat.cables]]\nname = \"c{i}\"\na = \"B{i}\"\nb = \"B{(i+1) mod n}\"\n");
    let sc = load(&wrapped).expect("valid");
    let s = &sc.custom.as_ref().expect("custom").structure;
    let c2 = s.member("c2").expect("c2");
    assert_eq!((s.nodes[c2.ends().0].name.as_str(), s.nodes[c2.ends().1].name.as_str()), ("B2", "B0"));
    let twice = ring("3", "[[structure.repeat]]\nfor = { i = \"0..n\" }\n[[structure.repeat.cables]]\nname = \"c{i mod 2}\"\na = \"B{i}\"\nb = \"A{i}\"\n");
    let e = load(&twice).expect_err("c0 twice");
    assert!(e.message.contains("c0"), "{e}");
    assert_eq!(e.line, wrapped.lines().position(|l| l.starts_with("name = \"c{i")).expect("line") + 1);
}

#[test]
fn a_bad_range_is_an_error_at_its_text() {
    for (range, words) in
        [("0..m", "not a whole-number expression"), ("3..0", "end >= start"), ("0..100000", "at most")]
    {
        let text = ring("4", "").replace("for = { i = \"0..n\" }", &format!("for = {{ i = \"{range}\" }}"));
        let e = load(&text).expect_err(range);
        assert!(e.message.contains(words), "{range}: {e}");
        assert_eq!(e.line, 9, "{range}: {e}");
    }
    let e = load(&ring("4", "").replace("axis = [0, 0, 1]", "axis = [0, 0, 0]")).expect_err("zero axis");
    assert!(e.message.contains("rotate.axis") && e.line == 10, "{e}");
    let e = load(&ring("2.5", "")).expect_err("n = 2.5");
    assert!(e.message.contains("not a whole number"), "{e}");
}

#[test]
fn a_for_over_an_unknown_group_names_the_groups_there_are() {
    let text = ring(
        "4",
        "[[predictions]]\nfor = { c = \"cables\" }\nquantity = \"{c}.force\"\nformula = \"0\"\nclass = \"relative\"\ntolerance = 1e-9\n",
    )
    .replace("for = { c = \"cables\" }", "for = { c = \"ropes\" }");
    let e = load(&text).expect_err("ropes");
    assert!(e.message.contains("'ropes'") && e.message.contains("springs"), "{e}");
}

/// `tensegrity sweep` of the shipped n-prism over n = 3..12: every row settles, each n has its
/// n twists, and each is within 1e-12 rad of the closed form.
#[test]
fn the_n_prism_sweep_meets_the_closed_form_twist_at_every_n_from_3_to_12() {
    let dir = std::env::temp_dir().join(format!("tt-prism-n-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let csv = dir.join("prism_n.csv");
    let (code, out, err) =
        tensegrity(&["sweep", "scenarios/custom/prism_n.toml", "--out", csv.to_str().expect("utf-8")]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&csv).expect("csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let mut worst: f64 = 0.0;
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 10);
    for row in rows {
        let cells: Vec<&str> = row.split(',').collect();
        let n: usize = cells[col("n").expect("n column")].parse::<f64>().expect("n") as usize;
        for i in 0..12 {
            let cell = cells[col(&format!("error_twist{i}")).expect("twist column")];
            assert_eq!(cell.is_empty(), i >= n, "n = {n}: twist{i} is '{cell}'");
            if i < n {
                worst = worst.max(cell.parse::<f64>().expect("number").abs());
            }
        }
        assert_eq!(cells[col("settled").expect("settled")], "true");
    }
    assert!(worst <= TWIST_TOL_RAD, "worst twist error {worst:e} rad");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_topology_run_says_which_structures_it_rebuilt() {
    let (code, out, err) = tensegrity(&["run", "scenarios/custom/prism_n.toml", "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).expect("json");
    let t = json["scenarios"][0]["topologies"].as_array().expect("topologies");
    assert_eq!(t.len(), 10);
    assert!(t[9].as_str().expect("text").starts_with("structure rebuilt at n = 12: 12 bodies, 24 nodes"), "{}", t[9]);
}

#[test]
fn a_swept_parameter_the_structure_does_not_see_is_reported() {
    let text = ring("4", "[[checks]]\nquantity = \"C.z\"\nvalue = 0.15\ntolerance = 1.0\n")
        .replace("n = 4\n", "n = 4\nunused = 1.0\n")
        .replace("points = [ {} ]", "grid = { unused = { from = 1, to = 2, count = 2 } }");
    let sc = load(&text).expect("valid");
    assert_eq!(sc.unseen_params, vec!["unused".to_string()]);
}

/// Generated work is bounded before it is done: the repeats' copies in all, and an aggregate's
/// expansion while it grows (a sum over 10,000 indices of a long body).
#[test]
fn patterns_are_bounded_before_their_work() {
    let mut text = ring("4", "");
    for _ in 0..3 {
        text.push_str("[[structure.repeat]]\nfor = { i = \"0..4000\" }\n[[structure.repeat.cables]]\nname = \"x{i}\"\na = \"A0\"\nb = \"C\"\n");
    }
    let e = load(&text).expect_err("12,004 copies");
    assert!(e.message.contains("more than 10000 copies"), "{e}");
    let long = format!("sum(i in 0..9000, {})", "C.x + ".repeat(20) + "C.x");
    let text = ring("4", &format!("[[quantities]]\nname = \"big\"\nexpr = \"{long}\"\n"));
    let e = load(&text).expect_err("too long");
    // Stopped while it grew, at the bound (the whole sum: 9000 copies of a 123-byte body).
    assert!(e.message.contains("expands beyond 10000 bytes"), "{e}");
}
