//! Point loads at nodes (`[[structure.loads]]`): a constant force that moves with its node,
//! in the settle, the relaxation and the modes, each against a closed form.

use super::common;
use std::path::Path;
use tensegrity_testbed::run::{self, RunOptions};
use tensegrity_testbed::scenario;

const PENDULUM: &str = "scenarios/custom/pendulum_tip_load.toml";

/// A bead between two anchors 2 a apart on two springs (stiffness k, rest length l0 each),
/// pulled across by a point load P: 2 k (l - l0) d / l = P with l = sqrt(a^2 + d^2). The
/// deflection d [m], solved by Newton.
pub(super) fn rope_deflection(a: f64, k: f64, l0: f64, p: f64) -> f64 {
    let mut d: f64 = 0.1;
    for _ in 0..100 {
        let l = a.hypot(d);
        let r = 2.0 * k * (l - l0) * d / l - p;
        let dr = 2.0 * k * ((l - l0) / l + l0 * d * d / (l * l * l));
        d -= r / dr;
    }
    d
}

pub(super) fn rope(p: f64) -> String {
    let structure = format!(
        r#"[[structure.bodies]]
name = "ground"
fixed = true
nodes = {{ A = [-1, 0, 0], B = [1, 0, 0] }}

[[structure.bodies]]
name = "bead"
mass = 0.2
nodes = {{ P = [0, 0, 0] }}

[[structure.springs]]
name = "left"
a = "A"
b = "P"
stiffness = 40.0
length = 0.8

[[structure.springs]]
name = "right"
a = "P"
b = "B"
stiffness = 40.0
length = 0.8

[[structure.loads]]
node = "P"
force = [0, 0, {}]
"#,
        -p
    );
    common::one_point_head("a bead on a rope, pulled across") + &structure
}

/// The bead settles at the rope's exact deflection under the load, within 1e-9 m, for loads
/// from 0.5 to 20 N (the springs, at 0.8 of the half-span, from pretensioned to far stretched).
#[test]
fn a_bead_on_a_rope_settles_at_the_exact_deflection_under_a_point_load() {
    for p in [0.5, 5.0, 20.0] {
        let sc = scenario::parse(Path::new("rope.toml"), &rope(p)).expect("valid");
        let report = run::run(&sc, &RunOptions::default());
        assert!(report.points[0].settled, "P = {p}: {}", report.verdict_line());
        let got = common::node(&report, "P");
        let want = rope_deflection(1.0, 40.0, 0.8, p);
        assert!((got[2] + want).abs() <= 1e-9 && got[0].abs() <= 1e-9, "P = {p}: {got:?} against z = {}", -want);
    }
}

/// The load's work enters the modes: the pendulum's frequency from `tensegrity modes` is
/// sqrt(hypot(m g L / 2, F L) / (m L^2 / 3)) within 1e-7 at each of the file's loads (the
/// joint modes' central differences: measured 1.1e-8 at F = 0.5 N).
#[test]
fn the_modes_of_a_pendulum_with_a_tip_load_hold_the_loads_stiffness() {
    let (m, g, l) = (0.5, 9.81, 1.0);
    let file = std::fs::read_to_string(PENDULUM).unwrap();
    for f in [0.5, 2.75, 5.0] {
        let text = file.replacen("grid = { F = { from = 0.5, to = 5.0, count = 3 } }", "points = [ {} ]", 1).replacen(
            "F = { value = 2.0,",
            &format!("F = {{ value = {f},"),
            1,
        );
        let sc = scenario::parse(Path::new("pendulum.toml"), &text).expect("valid");
        let (report, ..) = run::modes(&sc, "pendulum.toml", 20, None).expect("modes");
        let omega = report.modes[0].omega_rad_per_s;
        let want = (f64::hypot(m * g * l / 2.0, f * l) / (m * l * l / 3.0)).sqrt();
        assert!(((omega - want) / want).abs() <= 1e-7, "F = {f}: {omega} against {want}");
    }
}

/// A load is an error at its line: on a fixed body's node (its support would take it), at an
/// unknown node, with two components, not finite.
#[test]
fn a_bad_load_is_an_error_at_its_key() {
    let file = std::fs::read_to_string(PENDULUM).unwrap();
    let fixed = file.replacen("node = \"P\"", "node = \"O\"", 1);
    common::error_at(&fixed, "node = \"O\"", 7, "its support would take the load whole");
    let unknown = file.replacen("node = \"P\"", "node = \"Q\"", 1);
    common::error_at(&unknown, "node = \"Q\"", 7, "unknown node 'Q'");
    let short = file.replacen("force = [\"F\", 0, 0]", "force = [\"F\", 0]", 1);
    common::error_at(&short, "force = [\"F\", 0]", 8, "three finite numbers");
    let huge = file.replacen("force = [\"F\", 0, 0]", "force = [\"F*1e308*10\", 0, 0]", 1);
    assert!(scenario::parse(Path::new("huge.toml"), &huge).is_err(), "a force that is not finite");
}

/// The supports' reactions balance the load: on the rope pulled across by P, each anchor
/// pushes P / 2 back along the load and pulls the rope out by the horizontal tension
/// H = k (l - l0) a / l of the exact deflection, within 1e-9 of P.
#[test]
fn the_ropes_anchors_take_half_the_load_each_and_its_horizontal_tension() {
    let p = 5.0;
    let file = std::env::temp_dir().join(format!("tensegrity-loaded-rope-{}.toml", std::process::id()));
    std::fs::write(&file, rope(p)).unwrap();
    let (code, out, err) = common::tensegrity(&["equilibrium", file.to_str().unwrap(), "--json", "-"]);
    std::fs::remove_file(&file).unwrap();
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let d = rope_deflection(1.0, 40.0, 0.8, p);
    let l = 1.0_f64.hypot(d);
    let h = 40.0 * (l - 0.8) / l;
    for (pair, sign) in v["reactions_n"].as_array().unwrap().iter().zip([-1.0, 1.0]) {
        let r: Vec<f64> = pair[1].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        assert!((r[2] - p / 2.0).abs() <= 1e-9 * p, "{pair}: z against {}", p / 2.0);
        assert!((r[0] - sign * h).abs() <= 1e-9 * p && r[1].abs() <= 1e-9 * p, "{pair}: x against {}", sign * h);
    }
}

/// A node's mass (`[[structure.masses]]`) adds to its point mass: the bead of 0.2 kg on the
/// rope (tension T = 8 N, half-span a = 1 m), with 0.3 kg added at its node, vibrates across
/// at sqrt(2 T / (a M)) with M = 0.5 kg and along at sqrt(2 k / M), within 1e-9 relative; on a
/// rigid body's node, or with a mass that is not positive, it is an error at its key.
#[test]
fn a_nodes_mass_adds_to_its_point_mass() {
    let unloaded = rope(0.0).replace("[[structure.loads]]\nnode = \"P\"\nforce = [0, 0, -0]\n", "");
    let text = format!("{unloaded}\n[[structure.masses]]\nnode = \"P\"\nmass = 0.3\n");
    let sc = scenario::parse(Path::new("rope.toml"), &text).expect("valid");
    let (report, ..) = run::modes(&sc, "rope.toml", 20, None).expect("modes");
    let omegas: Vec<f64> = report.modes.iter().map(|m| m.omega_rad_per_s).collect();
    let (across, along) = ((2.0 * 8.0 / 0.5_f64).sqrt(), (2.0 * 40.0 / 0.5_f64).sqrt());
    for (got, want) in omegas.iter().zip([across, across, along]) {
        assert!(((got - want) / want).abs() <= 1e-9, "{omegas:?} against {across}, {across}, {along}");
    }
    let rigid = text.replacen("nodes = { P = [0, 0, 0] }", "nodes = { P = [0, 0, 0], Q = [0, 0.1, 0] }", 1);
    common::error_at(&rigid, "node = \"P\"\nmass", 7, "which is not a point mass");
    let negative = text.replacen("mass = 0.3", "mass = -0.3", 1);
    common::error_at(&negative, "mass = -0.3", 7, "must be > 0");
}
