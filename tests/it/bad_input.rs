//! Bad input never panics and never passes: a table of malformed or impossible scenarios, each
//! rejected by `tensegrity check` and `tensegrity run` with exit 2 and a message that names
//! `file.toml:LINE:COL` and says what was expected.

use crate::common;

use common::{tensegrity, PINNED_STRUT as PIN};

const JI: &str = r#"name = "ji"
mechanism = "ji2014"
[params]
L = 1.0
K1 = 200.0
[sim]
dt = 0.01
[settle]
max_time = 10.0
[actuation]
points = [ { L3 = 1.0, theta1 = 0.5 } ]
[[checks]]
quantity = "theta2"
tolerance = 1e-9
"#;

const MOHR: &str = r#"name = "mohr"
mechanism = "mohr2011"
[params]
lb = 2.0
lo = 6.0
[actuation]
points = [ { x = 0.0, y = 0.0, z = 3.0 } ]
[[checks]]
quantity = "z"
tolerance = 1e-9
"#;

const FURET: &str = r#"name = "furet"
mechanism = "furet2018"
[params]
L = 1.0
b = 0.6666666666666666
[actuation]
points = [ { theta1 = 0.2, theta2 = -0.3 } ]
[[checks]]
quantity = "x"
tolerance = 1e-9
"#;

const MQ: &str = r#"name = "mq"
mechanism = "manriquez2019"
[actuation]
points = [ { theta1 = 0.0941, theta2 = 0.0332 } ]
[[checks]]
quantity = "theta1"
tolerance = 1e-9
"#;

/// (what, scenario text, expected line of the error, a word the message must contain).
fn cases() -> Vec<(&'static str, String, usize, &'static str)> {
    vec![
        // Syntax and shape.
        ("syntax error", JI.replace("L = 1.0", "L = = 1.0"), 4, "expected"),
        ("unterminated string", JI.replace("name = \"ji\"", "name = \"ji"), 1, ""),
        ("unknown top-level key", JI.replace("[params]", "colour = 3\n[params]"), 3, "unknown"),
        ("unknown sim key", JI.replace("dt = 0.01", "dtt = 0.01"), 7, "unknown"),
        ("unknown settle key", JI.replace("max_time = 10.0", "maxtime = 10.0"), 9, "unknown"),
        ("unknown actuation key", JI.replace("points =", "pointz ="), 11, "unknown field"),
        ("wrong type for a parameter", JI.replace("L = 1.0", "L = true"), 4, "invalid type"),
        ("unknown symbol in a parameter", JI.replace("L = 1.0", "L = \"one\""), 4, "unknown symbol 'one'"),
        ("wrong type for substeps", JI.replace("dt = 0.01", "dt = 0.01\nsubsteps = 1.5"), 8, "invalid type"),
        ("missing mechanism", JI.replace("mechanism = \"ji2014\"\n", ""), 1, "mechanism"),
        ("missing actuation", JI.replace("[actuation]\npoints = [ { L3 = 1.0, theta1 = 0.5 } ]\n", ""), 1, "actuation"),
        (
            "checks nothing",
            JI.replace("[[checks]]\nquantity = \"theta2\"\ntolerance = 1e-9\n", ""),
            1,
            "checks nothing",
        ),
        // Values.
        ("negative length", JI.replace("L = 1.0", "L = -1.0"), 4, "> 0"),
        ("negative stiffness", JI.replace("K1 = 200.0", "K1 = -5.0"), 5, "> 0"),
        ("zero stiffness", JI.replace("K1 = 200.0", "K1 = 0.0"), 5, "> 0"),
        ("unknown parameter", JI.replace("K1 = 200.0", "K9 = 200.0"), 5, "unknown"),
        ("nan parameter", JI.replace("L = 1.0", "L = nan"), 4, "finite"),
        ("infinite parameter", JI.replace("L = 1.0", "L = inf"), 4, "finite"),
        ("zero time step", JI.replace("dt = 0.01", "dt = 0.0"), 7, "> 0"),
        ("negative time step", JI.replace("dt = 0.01", "dt = -0.01"), 7, "> 0"),
        ("time step far too long", JI.replace("dt = 0.01", "dt = 5.0"), 7, "1 s"),
        ("zero substeps", JI.replace("dt = 0.01", "dt = 0.01\nsubsteps = 0"), 8, "substeps"),
        ("negative settle time", JI.replace("max_time = 10.0", "max_time = -1.0"), 9, "> 0"),
        ("zero tolerance", JI.replace("tolerance = 1e-9", "tolerance = 0.0"), 14, "> 0"),
        ("unknown quantity", JI.replace("quantity = \"theta2\"", "quantity = \"zeta\""), 13, "expected one of"),
        ("unknown mechanism", JI.replace("\"ji2014\"", "\"ji2015\""), 2, "expected one of"),
        ("unknown start key", JI.replace("[actuation]", "[start]\ntheta9 = 1.0\n[actuation]"), 11, "expected one of"),
        // Schedules.
        ("empty points", JI.replace("points = [ { L3 = 1.0, theta1 = 0.5 } ]", "points = []"), 10, "empty"),
        ("empty waypoints", JI.replace("points = [ { L3 = 1.0, theta1 = 0.5 } ]", "waypoints = []"), 10, "empty"),
        (
            "unsorted waypoints",
            JI.replace(
                "points = [ { L3 = 1.0, theta1 = 0.5 } ]",
                "waypoints = [ { t = 1.0, L3 = 1.0, theta1 = 0.5 }, { t = 0.5, L3 = 1.0, theta1 = 0.5 } ]",
            ),
            11,
            "sorted",
        ),
        (
            "waypoint without time",
            JI.replace("points = [ { L3 = 1.0, theta1 = 0.5 } ]", "waypoints = [ { L3 = 1.0, theta1 = 0.5 } ]"),
            11,
            "time t",
        ),
        ("two schedules", JI.replace("points =", "waypoints = []\npoints ="), 10, "exactly one"),
        ("missing input", JI.replace(", theta1 = 0.5", ""), 11, "missing input"),
        (
            "grid count zero",
            JI.replace(
                "points = [ { L3 = 1.0, theta1 = 0.5 } ]",
                "grid = { L3 = { from = 0.5, to = 1.0, count = 0 }, theta1 = { from = 0.1, to = 0.2, count = 2 } }",
            ),
            11,
            "count",
        ),
        // Actuator targets outside the workspace.
        ("ji2014 theta1 beyond pi", JI.replace("theta1 = 0.5", "theta1 = 4.0"), 11, "[0, pi]"),
        ("ji2014 zero actuator length", JI.replace("L3 = 1.0", "L3 = 0.0"), 11, "> 0"),
        ("mohr2011 below the base", MOHR.replace("z = 3.0", "z = -1.0"), 7, "z > 0"),
        ("mohr2011 spring longer than l_o", MOHR.replace("z = 3.0", "z = 5.9"), 7, "l_o"),
        (
            "mohr2011 unreachable cable lengths",
            MOHR.replace("{ x = 0.0, y = 0.0, z = 3.0 }", "{ rho1 = 0.1, rho2 = 5.0, rho3 = 0.1 }"),
            7,
            "unreachable",
        ),
        ("mohr2011 l_o not positive", MOHR.replace("lo = 6.0", "lo = 0.0"), 5, "> 0"),
        ("mohr2011 straight not 0 or 1", MOHR.replace("lo = 6.0", "lo = 6.0\nstraight = 0.5"), 6, "straight"),
        ("furet2018 L not above b", FURET.replace("b = 0.6666666666666666", "b = 1.5"), 5, "shorter than L"),
        ("furet2018 L below the default b", FURET.replace("b = 0.6666666666666666\n", "").replace("L = 1.0", "L = 0.5"), 4, "shorter than L"),
        ("furet2018 change point", FURET.replace("theta1 = 0.2", "theta1 = 1.5707963267948966"), 7, "change point"),
        ("furet2018 angle beyond pi", FURET.replace("theta2 = -0.3", "theta2 = -4.0"), 7, "(-pi, pi)"),
        (
            "manriquez2019 singular pose",
            MQ.replace("theta1 = 0.0941, theta2 = 0.0332", "theta1 = 0.0, theta2 = 0.0"),
            4,
            "singular",
        ),
        ("manriquez2019 angle too large", MQ.replace("theta1 = 0.0941", "theta1 = 2.0"), 4, "(-pi/2, pi/2)"),
        ("manriquez2019 negative mass", MQ.replace("[actuation]", "[params]\nm = -0.4\n[actuation]"), 4, "> 0"),
        // Vectors of the wrong length or type (a 4th and 5th entry used to be ignored).
        ("node with 4 coordinates", PIN.replace("Q = [1.0, 0.0, 0.0]", "Q = [1.0, 0.0, 0.0, 2.0]"), 14, "three"),
        // A string is an expression of the parameters (none here).
        ("node with junk and nan", PIN.replace("Q = [1.0, 0.0, 0.0]", "Q = [0, 1, 0, \"junk\", nan]"), 14, "unknown symbol 'junk'"),
        ("node with a fourth number", PIN.replace("Q = [1.0, 0.0, 0.0]", "Q = [0, 1, 0, 2]"), 14, "three finite numbers"),
        ("axis with 5 entries", PIN.replace("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 1.0, 0.0, 0.0]"), 31, "three"),
        ("gravity with 4 entries", PIN.replace("gravity = [0.0, 0.0, 0.0]", "gravity = [0.0, 0.0, 0.0, 9.81]"), 6, "three"),
        ("node at 1e300", PIN.replace("S = [1.0, 1.0, 0.0]", "S = [1e300, 1.0, 0.0]"), 10, "magnitude"),
        // Duplicate names: a check on the name would read only one.
        ("duplicate member name", PIN.replace("name = \"k\"", "name = \"bar\""), 20, "duplicate"),
        ("duplicate joint name", PIN.replace("damping = 0.5", "damping = 0.5\n[[structure.joints]]\nname = \"pin\"\nkind = \"fixed\"\nparent = \"ground\"\nchild = \"bar\"\nat = \"Q\""), 34, "duplicate"),
        ("a joint whose child is fixed, at the joint", PIN.replace("child = \"bar\"", "child = \"ground\"\nparent2 = 1").replace("parent2 = 1\n", "").replace("parent = \"ground\"", "parent = \"bar\""), 26, "fixed"),
        // Physical sizes the simulation cannot handle, found at check time.
        ("mass far too small", PIN.replace("mass = 1.0", "mass = 1e-320"), 13, "mass"),
        ("ji2014 L = 1e308", JI.replace("L = 1.0", "L = 1e308"), 4, ""),
        ("ji2014 L = 1e-300", JI.replace("L = 1.0", "L = 1e-300"), 11, "1000 L"),
        ("ji2014 L = 1000 outside the bounding box", JI.replace("L = 1.0", "L = 1000.0"), 4, "bounding_box"),
        // Bounded work.
        ("time step of 5e-324 s", JI.replace("dt = 0.01", "dt = 5e-324"), 9, "steps per settle"),
        ("1e10 steps per settle", JI.replace("dt = 0.01", "dt = 1e-9"), 9, "steps per settle"),
        (
            "waypoint at t = 1e300",
            JI.replace("points = [ { L3 = 1.0, theta1 = 0.5 } ]", "waypoints = [ { t = 0.0, L3 = 1.0, theta1 = 0.5 }, { t = 1e300, L3 = 1.0, theta1 = 0.6 } ]"),
            11,
            "time steps away",
        ),
        (
            "waypoints closer than dt",
            JI.replace(
                "points = [ { L3 = 1.0, theta1 = 0.5 } ]",
                "waypoints = [ { t = 0.0, L3 = 1.0, theta1 = 0.5 }, { t = 1.0, L3 = 1.0, theta1 = 0.6 }, { t = 1.004, L3 = 1.0, theta1 = 0.7 } ]",
            ),
            11,
            "never be reached",
        ),
        // Quantities and expectations that need a section.
        ("stiffness check without a probe", JI.replace("quantity = \"theta2\"", "quantity = \"K\""), 13, "[probe]"),
        ("stability expect misspelt", JI.replace("[actuation]", "[stability]\nperturbation = 1e-3\nexpect = \"stabel\"\n[actuation]"), 12, "stable"),
        ("stability expect per point of the wrong length", JI.replace("[actuation]", "[stability]\nperturbation = 1e-3\nexpect = [\"stable\", \"stable\"]\n[actuation]"), 12, "one per point"),
        ("interference exclusion of an unknown member", PIN.replace("[actuation]", "[interference]\nexclude = [[\"bar\", \"nope\"]]\n[actuation]"), 4, "'nope'"),
        ("negative interference threshold", PIN.replace("[actuation]", "[interference]\nthreshold = -1.0\n[actuation]"), 4, ">= 0 m"),
        (
            "force of a strut on a fixed body",
            PIN.replace("[structure]", "[[checks]]\nquantity = \"post.force\"\nvalue = 1.0\ntolerance = 1e-9\n[structure]")
                .replace("[[structure.springs]]", "[[structure.struts]]\nname = \"post\"\na = \"O\"\nb = \"S\"\n[[structure.springs]]"),
            6,
            "unknown quantity",
        ),
        // A motion's frequency measured a way that does not exist.
        {
            let (text, line) = shipped_edit(LARGE_AMPLITUDE, "measure = \"period\"", "measure = \"zero crossings\"");
            ("unknown frequency measure", text, line, "measure must be \"cosine\"")
        },
    ]
}

const LARGE_AMPLITUDE: &str = "scenarios/custom/pinned_bar_large_amplitude.toml";

/// The shipped file at `path` with `from` replaced by `to` (once), and the line of the edit.
fn shipped_edit(path: &str, from: &str, to: &str) -> (String, usize) {
    let text = common::edited(path, &[(from, to)]);
    let line = text[..text.find(to).expect("the edit")].lines().count() + 1;
    (text, line)
}

#[test]
fn every_malformed_scenario_gives_exit_2_with_file_line_and_column() {
    let dir = std::env::temp_dir().join(format!("tensegrity-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases = cases();
    assert!(cases.len() >= 40, "{} cases", cases.len());
    let mut failures = Vec::new();
    for (what, text, line, word) in &cases {
        let p = dir.join(format!("{}.toml", what.replace([' ', '(', ')', ','], "_")));
        std::fs::write(&p, text).unwrap();
        let file = p.to_str().unwrap();
        for cmd in ["check", "run"] {
            let (code, out, err) = tensegrity(&[cmd, file]);
            let prefix = format!("{file}:{line}:");
            let col_ok =
                err.find(&prefix).is_some_and(|i| err[i + prefix.len()..].starts_with(|c: char| c.is_ascii_digit()));
            if code != 2 || err.contains("panicked") || !col_ok || !err.contains(word) {
                failures.push(format!("{what} ({cmd}): exit {code}, expected line {line} and '{word}': {out}{err}"));
            }
        }
    }
    assert!(failures.is_empty(), "{} failure(s):\n{}", failures.len(), failures.join("\n"));
}

/// A scenario file over 16 MiB (a list of a million points) is refused before it is parsed:
/// exit 2 at line 1 column 1 (where nothing is parsed yet), naming the limit.
#[test]
fn an_oversized_scenario_file_is_refused_before_parsing() {
    let dir = std::env::temp_dir().join(format!("tensegrity-big-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("many.toml");
    let points = vec!["{ L3 = 1.0, theta1 = 0.5 }"; 1_000_001].join(", ");
    std::fs::write(&p, JI.replace("points = [ { L3 = 1.0, theta1 = 0.5 } ]", &format!("points = [ {points} ]")))
        .unwrap();
    let (code, out, err) = super::common::tensegrity_guarded(&["check", p.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(":1:1:") && err.contains("at most 16777216"), "{err}");
    assert!(out.is_empty() && err.lines().count() == 1, "one error, nothing validated: {out}{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// F7 of issue 60: a body's mass or moments out of the simulation's range are an error at that
/// body's `mass` (the file's own range) or `inertia` key (the range scaled by the structure's
/// extent, found once the structure is built), not at `[structure]`.
#[test]
fn a_body_mass_out_of_range_is_an_error_at_its_mass() {
    let text = std::fs::read_to_string("scenarios/custom/prism3.toml").unwrap();
    let light = text.replacen("name = \"strut2\"\nmass = 1.0", "name = \"strut2\"\nmass = 1e-10", 1);
    crate::common::error_at(&light, "mass = 1e-10", 7, "mass must lie in [1e-9, 1e9] kg");
    let tiny = text.replacen(
        "name = \"strut3\"\nmass = 1.0",
        "name = \"strut3\"\nmass = 1.0\ninertia = [1e-12, 1e-12, 1e-12]",
        1,
    );
    crate::common::error_at(&tiny, "inertia = [1e-12", 10, "body 'strut3' has mass 1e0 kg and moments");
}
