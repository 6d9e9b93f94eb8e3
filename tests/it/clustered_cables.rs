//! Clustered cables: one cable through several nodes, one rest length and one stiffness for
//! its whole length, sliding without friction at its inner nodes (`through`), so every segment
//! carries one tension. The ring on a cable settles on the closed form by the plain dynamics as
//! by the relaxation; interference checks every segment; bad input is located.

use crate::common::{self, edited, error_at, node, norm, sub};
use std::path::Path;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;
use tensegrity_testbed::structure::MemberKind;

const RING: &str = "scenarios/custom/ring_on_clustered_cable.toml";

/// The ring settled by the plain dynamics (no relaxation, body damping 5 /s) lands where the
/// relaxation puts it: the ring within 1e-9 m and the tension within 1e-9 relative at every
/// height, and the file's closed forms pass (theta = theta_s, T = m g / (2 cos theta_s)).
#[test]
fn the_ring_settles_on_the_closed_form_by_the_plain_dynamics_too() {
    let fast = common::run_file(RING);
    let text = edited(
        RING,
        &[("[settle]\n", "[sim]\nrelaxation = false\nbody_damping = 5.0\n\n[settle]\nmax_time = 200.0\n")],
    );
    let plain = run(&scenario::parse(Path::new("ring.toml"), &text).unwrap(), &RunOptions::default());
    assert!(fast.passed && plain.passed, "{:?} {:?} {:?}", fast.error, plain.error, plain.failures);
    assert!(
        plain.settle.steps > 10 * fast.settle.steps,
        "plain {} steps, relaxed {}",
        plain.settle.steps,
        fast.settle.steps
    );
    for (f, p) in fast.points.iter().zip(&plain.points) {
        let (rf, rp) = (f.simulated["hang.force"], p.simulated["hang.force"]);
        assert!(((rf - rp) / rf).abs() <= 1e-9, "tension {rf} N relaxed, {rp} N plain");
        let d = ["R.x", "R.y", "R.z"].map(|k| f.simulated[k] - p.simulated[k]);
        assert!(norm(d) <= 1e-9, "ring {d:?} m apart");
    }
}

/// The ring's cable is one member whose path runs A, R, B; its one tension is the whole
/// cable's law, k (|AR| + |RB| - L0) with the settled nodes' distances, within 1e-12 relative.
#[test]
fn a_clustered_cable_is_one_member_with_one_tension() {
    let sc = scenario::load(Path::new(RING)).unwrap();
    let s = &sc.custom.as_ref().unwrap().structure;
    assert_eq!(s.count_of(MemberKind::Cable), 1);
    let hang = s.member("hang").unwrap();
    let names: Vec<&str> = hang.path.iter().map(|&n| s.nodes[n].name.as_str()).collect();
    assert_eq!(names, ["A", "R", "B"]);
    let r = common::run_file(RING);
    let (a, ring, b) = (node(&r, "A"), node(&r, "R"), node(&r, "B"));
    let length = norm(sub(ring, a)) + norm(sub(b, ring));
    let (k, rest) = (sc.params["k"], sc.params["L0"]);
    let tension = r.points[0].simulated["hang.force"];
    assert!((tension - k * (length - rest)).abs() <= 1e-12 * tension, "{tension} N against {}", k * (length - rest));
}

/// A clustered cable that runs through a strut is an interference: a fixed bar along y and a
/// cable from A over the bar's middle (its first segment crosses the bar's axis) to P and on
/// to B fails with a violation naming the cable and the strut.
#[test]
fn interference_checks_every_segment_of_a_clustered_cable() {
    let text = r#"name = "a clustered cable through a bar"
mechanism = "custom"
[interference]
tendons = true
[actuation]
points = [ {} ]
[structure]
[[structure.bodies]]
name = "ground"
fixed = true
nodes = { Y0 = [0, -1, 0], Y1 = [0, 1, 0], A = [-1, 0, 0.5], P = [1, 0, -0.5], B = [1, 0, 1] }
[[structure.bodies]]
name = "bob"
mass = 1.0
nodes = { Q = [2, 0, 0], Q2 = [2, 0.1, 0] }
[[structure.struts]]
name = "bar"
a = "Y0"
b = "Y1"
[[structure.cables]]
name = "rope"
a = "A"
through = ["P", "B"]
b = "Q"
stiffness = 100.0
"#;
    let r = run(&scenario::parse(Path::new("through.toml"), text).unwrap(), &RunOptions::default());
    assert!(!r.passed, "a cable through a bar must fail");
    let i = r.interference.as_ref().expect("an interference report");
    assert!(!i.passed && !i.violations.is_empty(), "{i:?}");
    assert!(i.min_clearance_m.is_some_and(|c| c < 0.0), "{i:?}");
    let pair = i.closest_pair.clone().expect("the closest pair");
    assert!(pair.contains(&"rope".to_string()) && pair.contains(&"bar".to_string()), "{pair:?}");
}

/// `[prestress] least_tension` with a clustered ring: the drawn self-stress is found with the
/// ring as one member (its column the sum of its three segments'), so the prism whose bottom
/// ring is one cable gets the plain prism's self-stress: at each of the 8 least tensions the
/// ring's one tension equals the plain bottom cables' within 1e-9 relative, and the nodes stay
/// where the plain prism's do within 1e-9 m.
#[test]
fn a_clustered_ring_takes_the_drawn_self_stress() {
    let text = std::fs::read_to_string("scenarios/custom/prism3_prestress_frequencies.toml").unwrap();
    let statics =
        format!("{}[expect]{}", &text[..text.find("[motion]").unwrap()], text.split("[expect]").nth(1).unwrap());
    let start = statics.find("[[structure.cables]]\nname = \"bottom12\"").unwrap();
    let end = statics.find("[[structure.cables]]\nname = \"top12\"").unwrap();
    let ring = "[[structure.cables]]\nname = \"bottom\"\na = \"B1\"\nthrough = [\"B2\", \"B3\"]\nb = \"B1\"\nstiffness = \"100/3\"\n\n";
    let clustered = format!("{}{ring}{}", &statics[..start], &statics[end..]);
    let run_text = |t: &str| run(&scenario::parse(Path::new("ring.toml"), t).unwrap(), &RunOptions::default());
    let (plain, ring) = (run_text(&statics), run_text(&clustered));
    assert!(plain.passed && ring.passed, "{:?} {:?} {:?}", plain.failures, ring.error, ring.failures);
    assert_eq!((plain.points.len(), ring.points.len()), (8, 8));
    for (p, c) in plain.points.iter().zip(&ring.points) {
        let (tp, tc) = (p.simulated["bottom12.force"], c.simulated["bottom.force"]);
        assert!(((tp - tc) / tp).abs() <= 1e-9, "t0 = {}: ring {tc} N, plain {tp} N", p.inputs["t0"]);
        for n in ["B2", "B3", "T1", "T2", "T3"] {
            let d = ["x", "y", "z"].map(|k| p.simulated[&format!("{n}.{k}")] - c.simulated[&format!("{n}.{k}")]);
            assert!(norm(d) <= 1e-9, "{n}: {d:?}");
        }
    }
}

/// The sensitivities read a clustered cable through its one law: the ring's angle moves with
/// the cable's rest length as the implicit equilibrium d / sin(theta) = L0 + m g / (2 k
/// cos(theta)) says, d theta / d L0 = -1 / (d cos / sin^2 + m g sin / (2 k cos^2)), within 1e-8
/// relative (both segments' angles; measured 2.1e-9 and 6.0e-9, the parameter derivative of the
/// forces being a difference), and within 1e-6 of central differences of settles.
#[test]
fn the_rings_angle_moves_with_the_rest_length_as_the_implicit_equilibrium_says() {
    let sc = scenario::load(Path::new(RING)).unwrap();
    // L0 is derived in the file (from the drawn angle): asked for by name, an input of its own.
    let only = ["L0".to_string()];
    let r = tensegrity_testbed::study::sensitivity::sensitivity_to(&sc, RING, (0, Some(&only)), true, None)
        .expect("sensitivities");
    let (d, m, g, k, theta) = (sc.params["d"], sc.params["m"], sc.params["g"], sc.params["k"], sc.params["theta_s"]);
    let (s, c) = theta.sin_cos();
    let closed = -1.0 / (d * c / (s * s) + m * g * s / (2.0 * k * c * c));
    let p = r.parameters.iter().find(|p| p.name == "L0").expect("L0");
    for output in ["theta_A", "theta_B"] {
        let i = r.outputs.iter().position(|o| o.name == output).unwrap();
        let (ift, settles) = (p.derivatives[i], p.check.as_ref().expect("checked")[i]);
        assert!(((ift - closed) / closed).abs() <= 1e-8, "{output}: {ift} against {closed}");
        assert!(((ift - settles) / settles).abs() <= 1e-6, "{output}: {ift} against settles {settles}");
    }
}

const CAPSTAN: &str = "scenarios/custom/capstan.toml";

/// The capstan: a weight on a slide below the node P, the cable turning pi/2 there (mu = 0.3)
/// and reeled in at W. Where the held tension ratio k L0 (1 / (L - L0 / 2) - 1) / (m g) is
/// below e^(0.3 pi / 2) the node holds (not reported slipping) and the ratio is that value;
/// past it P is reported slipping and T_out / T_in = e^(0.3 pi / 2), both within 1e-6 (the
/// criterion; measured 3e-14). Two points hold and seven slip.
#[test]
fn the_capstan_holds_below_e_mu_theta_and_slips_at_it() {
    let sc = scenario::load(Path::new(CAPSTAN)).unwrap();
    let r = common::run_file(CAPSTAN);
    assert!(r.passed, "{:?} {:?}", r.error, r.failures);
    let (m, g, k, l0) = (sc.params["m"], sc.params["g"], sc.params["k"], sc.params["L0"]);
    let bound = (0.3 * std::f64::consts::FRAC_PI_2).exp();
    let mut held = 0;
    for p in &r.points {
        let held_ratio = k * l0 * (1.0 / (p.inputs["L"] - l0 / 2.0) - 1.0) / (m * g);
        let ratio = p.simulated["ratio"];
        if held_ratio < bound {
            held += 1;
            assert!(p.slipping.is_empty(), "L = {}: {:?}", p.inputs["L"], p.slipping);
            assert!((ratio - held_ratio).abs() <= 1e-6 * held_ratio, "held at {ratio}, expected {held_ratio}");
        } else {
            assert_eq!(p.slipping, ["rope at P"], "L = {}", p.inputs["L"]);
            assert!((ratio - bound).abs() <= 1e-6 * bound, "slipping at {ratio}, bound {bound}");
        }
    }
    assert_eq!((held, r.points.len() - held), (2, 7));
}

/// The per-tick table carries each segment's tension and each inner node's slip: on the
/// capstan's last row the segment beyond P holds e^(0.3 pi / 2) times the one below it within
/// 1e-9, P slips (1), and the cable's own column is its last segment's.
#[test]
fn the_table_has_every_segment_and_the_slip() {
    let text = std::fs::read_to_string(CAPSTAN).unwrap();
    let (_, header, columns) = common::table(&text, "capstan");
    let column = |name: &str| &columns[header.iter().position(|h| h == name).unwrap_or_else(|| panic!("{name}"))];
    let last = |name: &str| *column(name).last().unwrap();
    let (below, beyond) = (last("cable:rope.segment_1.tension_n"), last("cable:rope.segment_2.tension_n"));
    let bound = (0.3 * std::f64::consts::FRAC_PI_2).exp();
    assert!((beyond / below - bound).abs() <= 1e-9 * bound, "{beyond} / {below}");
    assert_eq!(last("cable:rope.slip_1"), 1.0);
    assert_eq!(last("cable:rope.tension_n"), beyond);
    assert_eq!(column("cable:rope.slip_1")[0], 0.0, "P holds at the drawn state");
}

/// A cable with friction has no stiffness to linearise: `modes` refuses it, naming the cable
/// (exit 2).
#[test]
fn the_modes_of_a_cable_with_friction_are_refused() {
    let (code, _, err) = common::tensegrity(&["modes", CAPSTAN]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cable 'rope' has friction"), "{err}");
}

/// Bad friction is located: on a spring, a count that is not one per inner node, a negative
/// or non-finite coefficient.
#[test]
fn bad_friction_is_located() {
    let text = std::fs::read_to_string(CAPSTAN).unwrap();
    let with = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        text.replacen(from, to, 1)
    };
    let two = with("friction = [\"mu\"]", "friction = [\"mu\", 0.1]");
    error_at(&two, "friction = [", 11, "one per node of `through`");
    let negative = with("friction = [\"mu\"]", "friction = [-0.2]");
    error_at(&negative, "-0.2", 0, "must be >= 0");
    let not_a_number = with("friction = [\"mu\"]", "friction = [nan]");
    error_at(&not_a_number, "nan]", 0, "must be a finite number");
    let spring = with(
        "[[structure.actuators]]",
        "[[structure.springs]]\nname = \"s\"\na = \"M\"\nb = \"W\"\nstiffness = 1.0\nfriction = [0.1]\n\n[[structure.actuators]]",
    );
    error_at(&spring, "friction = [0.1]", 11, "only a cable has friction");
}

/// Bad clustered cables are located at the key that is wrong: a strut or a spring with
/// `through`, an empty `through`, a node twice in a row, an unknown inner node, and a clustered
/// cable without a stiffness (an inextensible one is not modelled).
#[test]
fn bad_clustered_cables_are_located() {
    let text = std::fs::read_to_string(RING).unwrap();
    let cable = "[[structure.cables]]\nname = \"hang\"\na = \"A\"\nthrough = [\"R\"]\nb = \"B\"\nstiffness = \"k\"\n";
    assert!(text.contains(cable));
    let with = |replacement: &str| text.replacen(cable, replacement, 1);
    let strut = with(
        "[[structure.struts]]\nname = \"bar\"\na = \"A\"\nthrough = [\"R\"]\nb = \"B\"\n[[structure.cables]]\nname = \"hang\"\na = \"A\"\nb = \"B\"\nstiffness = \"k\"\n",
    );
    error_at(&strut, "through = [\"R\"]\nb = \"B\"\n[[structure.cables]]", 10, "only a cable runs through inner nodes");
    let empty = with("[[structure.cables]]\nname = \"hang\"\na = \"A\"\nthrough = []\nb = \"B\"\nstiffness = \"k\"\n");
    error_at(&empty, "through = []", 10, "names no inner node");
    let twice = with(
        "[[structure.cables]]\nname = \"hang\"\na = \"A\"\nthrough = [\"R\", \"R\"]\nb = \"B\"\nstiffness = \"k\"\n",
    );
    error_at(&twice, "\"R\", \"R\"]", 5, "runs through node 'R' twice in a row");
    let unknown =
        with("[[structure.cables]]\nname = \"hang\"\na = \"A\"\nthrough = [\"X\"]\nb = \"B\"\nstiffness = \"k\"\n");
    error_at(&unknown, "\"X\"", 0, "unknown node 'X'");
    let rigid = with("[[structure.cables]]\nname = \"hang\"\na = \"A\"\nthrough = [\"R\"]\nb = \"B\"\n");
    error_at(&rigid, "\"hang\"", 0, "needs a stiffness");
}
