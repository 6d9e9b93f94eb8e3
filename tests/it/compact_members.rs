//! The compact member syntax of `[structure]`: `strut_groups`, `spring_groups` and
//! `cable_groups` list node pairs sharing their properties; the one-table-per-member form
//! stays valid beside it, and every error points at the offending pair.

use std::path::Path;
use tensegrity_testbed::scenario::{self, Scenario};
use tensegrity_testbed::structure::CableLaw;
use tensegrity_testbed::structure::MemberKind;

/// scenarios/custom/prism3.toml's structure with its nine cables and three struts as four
/// groups (names generated for the polygons, given for the sides).
const PRISM_GROUPS: &str = r#"name = "prism, compact"
mechanism = "custom"

[actuation]
points = [ {} ]

[structure]

[[structure.bodies]]
name = "strut1"
fixed = true
nodes = { B1 = [1, 0, 0], T1 = [-0.642787609686539, 0.766044443118978, 1.5] }

[[structure.bodies]]
name = "strut2"
mass = 1.0
nodes = { B2 = [-0.5, 0.866025403784439, 0], T2 = [-0.342020143325669, -0.939692620785908, 1.5] }

[[structure.bodies]]
name = "strut3"
mass = 1.0
nodes = { B3 = [-0.5, -0.866025403784438, 0], T3 = [0.984807753012208, 0.17364817766693, 1.5] }

[[structure.strut_groups]]
name = "strut"
radius = 0.02
pairs = [["B1", "T1"], ["B2", "T2"], ["B3", "T3"]]
names = ["strut1", "strut2", "strut3"]

[[structure.cable_groups]]
name = "bottom"
stiffness = 100.0
length = 1.5
pairs = [["B1", "B2"], ["B2", "B3"], ["B3", "B1"]]

[[structure.cable_groups]]
name = "top"
stiffness = 100.0
length = 1.5
pairs = [["T1", "T2"], ["T2", "T3"], ["T3", "T1"]]

[[structure.cable_groups]]
name = "side"
stiffness = 100.0
length = 1.2
pairs = [["B1", "T3"], ["B2", "T1"], ["B3", "T2"]]
names = ["side1", "side2", "side3"]
"#;

fn parse(text: &str) -> Result<Scenario, String> {
    scenario::parse(Path::new("compact.toml"), text).map_err(|e| e.to_string())
}

/// The four groups give the prism of the long form: the same 3 struts (radius 0.02 m) and 9
/// cables (same nodes, 100 N/m, lengths 1.5 m and 1.2 m), in the same order, named
/// "<group>:<a>-<b>" where no names are given.
#[test]
fn groups_build_the_same_prism_as_one_table_per_member() {
    let long = scenario::load(Path::new("scenarios/custom/prism3.toml")).unwrap();
    let short = parse(PRISM_GROUPS).unwrap();
    let (l, s) = (&long.custom.unwrap().structure, &short.custom.unwrap().structure);
    let of = |s: &'_ tensegrity_testbed::structure::Structure, kind| {
        s.members_of(kind).map(|(_, m)| m.clone()).collect::<Vec<_>>()
    };
    assert_eq!(of(s, MemberKind::Strut), of(l, MemberKind::Strut));
    assert_eq!(s.count_of(MemberKind::Cable), 9);
    for (a, b) in of(s, MemberKind::Cable).iter().zip(&of(l, MemberKind::Cable)) {
        assert_eq!((&a.path, &a.law), (&b.path, &b.law));
        assert_eq!(a.cable_law(), Some(&CableLaw::Elastic { stiffness_n_per_m: 100.0 }));
    }
    let names: Vec<&str> = s.members_of(MemberKind::Cable).map(|(_, c)| c.name.as_str()).collect();
    assert_eq!(&names[..4], ["bottom:B1-B2", "bottom:B2-B3", "bottom:B3-B1", "top:T1-T2"]);
    assert_eq!(&names[6..], ["side1", "side2", "side3"]);
}

/// Both forms in one file: the member tables first, then the groups; a spring group with a
/// free length.
#[test]
fn groups_and_member_tables_mix() {
    let text = PRISM_GROUPS.replace(
        "[[structure.strut_groups]]",
        "[[structure.cables]]\nname = \"extra\"\na = \"B1\"\nb = \"T2\"\n\n[[structure.spring_groups]]\nname = \"k\"\nstiffness = 5.0\nlength = 0.25\npairs = [[\"B2\", \"T3\"]]\n\n[[structure.strut_groups]]",
    );
    let s = parse(&text).unwrap().custom.unwrap().structure;
    let (_, first_cable) = s.members_of(MemberKind::Cable).next().unwrap();
    assert_eq!(first_cable.name, "extra");
    assert_eq!(first_cable.cable_law(), Some(&CableLaw::Inextensible));
    assert_eq!(s.count_of(MemberKind::Cable), 10);
    assert_eq!(s.count_of(MemberKind::Spring), 1);
    let (_, spring) = s.members_of(MemberKind::Spring).next().unwrap();
    assert_eq!(
        (spring.name.as_str(), spring.stiffness_n_per_m(), spring.rest_length_m()),
        ("k:B2-T3", Some(5.0), Some(0.25))
    );
}

/// file:line:col of the offending pair (or list) and what was wrong.
fn error_of(from: &str, to: &str) -> String {
    let text = PRISM_GROUPS.replacen(from, to, 1);
    parse(&text).expect_err("must be rejected")
}

fn line_col(text: &str, needle: &str) -> String {
    let i = text.find(needle).unwrap();
    let line = text[..i].matches('\n').count() + 1;
    let col = i - text[..i].rfind('\n').map_or(0, |k| k + 1) + 1;
    format!("compact.toml:{line}:{col}:")
}

#[test]
fn an_unknown_node_in_a_pair_is_an_error_at_that_node() {
    let text = PRISM_GROUPS.replacen(r#"["B2", "B3"]"#, r#"["B2", "X9"]"#, 1);
    let e = parse(&text).unwrap_err();
    assert!(e.starts_with(&line_col(&text, "\"X9\"")), "{e}");
    assert!(e.contains("unknown node 'X9'"), "{e}");
}

#[test]
fn a_pair_of_three_names_is_an_error_at_the_pair() {
    let text = PRISM_GROUPS.replacen(r#"["T2", "T3"]"#, r#"["T2", "T3", "T1"]"#, 1);
    let e = parse(&text).unwrap_err();
    assert!(e.starts_with(&line_col(&text, r#"["T2", "T3", "T1"]"#)), "{e}");
    assert!(e.contains("got 3 names"), "{e}");
}

#[test]
fn names_must_match_the_pairs_one_to_one() {
    let e = error_of(r#"names = ["side1", "side2", "side3"]"#, r#"names = ["side1", "side2"]"#);
    assert!(e.contains("names has 2 entries for 3 pairs"), "{e}");
    let text = PRISM_GROUPS.replacen(r#"names = ["side1", "side2", "side3"]"#, r#"names = ["side1", "side2"]"#, 1);
    assert!(e.starts_with(&line_col(&text, r#"["side1", "side2"]"#)), "{e}");
}

#[test]
fn a_repeated_pair_is_a_duplicate_name_at_the_second_pair() {
    let text = PRISM_GROUPS.replacen(r#"["T3", "T1"]]"#, r#"["T1", "T2"]]"#, 1);
    let e = parse(&text).unwrap_err();
    let second = text.match_indices(r#"["T1", "T2"]"#).nth(1).unwrap().0;
    let line = text[..second].matches('\n').count() + 1;
    assert!(e.starts_with(&format!("compact.toml:{line}:")), "{e}");
    let first =
        line_col(&text, r#"["T1", "T2"]"#).trim_start_matches("compact.toml:").trim_end_matches(':').to_string();
    assert!(
        e.contains(&format!(
            "duplicate name 'top:T1-T2': this cable of group 'top' and the cable of group 'top' at {first}"
        )),
        "{e}"
    );
}

#[test]
fn an_empty_group_and_a_zero_length_pair_are_rejected() {
    let e = error_of(r#"pairs = [["T1", "T2"], ["T2", "T3"], ["T3", "T1"]]"#, "pairs = []");
    assert!(e.contains("at least one pair"), "{e}");
    let text = PRISM_GROUPS.replacen(r#"["B3", "B1"]"#, r#"["B3", "B3"]"#, 1);
    let e = parse(&text).unwrap_err();
    assert!(e.contains("zero length") || e.contains("coincide"), "{e}");
}

#[test]
fn an_unknown_key_in_a_group_is_an_error() {
    let e = error_of("radius = 0.02", "radius = 0.02\ncolour = \"red\"");
    assert!(e.contains("unknown field `colour`"), "{e}");
}
