//! `tensegrity export mjcf`: the XML holds every body, joint, site, tendon and actuator with
//! the structure's numbers, and, where MuJoCo is installed, it settles in MuJoCo to the
//! testbed's equilibrium.

use crate::common;
use common::tensegrity;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use tensegrity_testbed::export::{self, mjcf, mjcf::ActuatorMode};
use tensegrity_testbed::scenario::{self, Scenario};
use tensegrity_testbed::sim::Simulation;

type P3 = [f64; 3];

/// Joint gain of the position-actuator export in these tests [N m/rad or N/m].
const KP: f64 = 1e6;

fn load(path: &str) -> Scenario {
    scenario::load(Path::new(path)).expect("scenario is valid")
}

fn xml_of(path: &str, mode: ActuatorMode) -> String {
    let m = export::scenario_mjcf(&load(path), mode, KP, 0.0).expect("exports");
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    m.xml
}

/// The start tag `<TAG ... name="NAME" ...>` of the XML, or None.
fn element<'a>(xml: &'a str, tag: &str, name: &str) -> Option<&'a str> {
    let open = format!("<{tag} ");
    let key = format!("name=\"{name}\"");
    xml.match_indices(&open).map(|(i, _)| &xml[i..i + xml[i..].find('>').unwrap()]).find(|e| e.contains(&key))
}

/// Attribute `attr` of a start tag.
fn attr<'a>(el: &'a str, attr: &str) -> &'a str {
    let key = format!(" {attr}=\"");
    let i = el.find(&key).unwrap_or_else(|| panic!("no {attr} in {el}")) + key.len();
    &el[i..i + el[i..].find('"').unwrap()]
}

fn numbers(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|x| x.parse().expect("a number")).collect()
}

fn count(xml: &str, tag: &str) -> usize {
    xml.matches(&format!("<{tag} name=")).count()
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// The prism: strut1 welded to the world (no joint), strut2 and strut3 free bodies of 1 kg
/// whose frames sit at their centres of mass, each node a site at its drawn position, each
/// strut a capsule of radius 0.02 m, each cable a tension-only tendon (dead band [0, L]) of
/// 100 N/m, no gravity; numbers to 1e-15.
#[test]
fn prism3_exports_bodies_sites_capsules_and_tension_only_tendons() {
    let sc = load("scenarios/custom/prism3.toml");
    let (s, _) = export::first_structure(&sc).unwrap();
    let xml = xml_of("scenarios/custom/prism3.toml", ActuatorMode::Mocap);
    assert_eq!(count(&xml, "body"), 3);
    assert_eq!(count(&xml, "joint"), 2);
    assert_eq!(count(&xml, "site"), 6);
    assert_eq!(count(&xml, "geom"), 3);
    assert_eq!(count(&xml, "spatial"), 9);
    assert!(!xml.contains("<actuator>") && !xml.contains("<equality>"));
    assert!(!element(&xml, "body", "strut1").unwrap().contains("mocap"));
    for b in &s.bodies[1..] {
        let inertia = b.inertia.unwrap();
        let body = element(&xml, "body", &b.name).unwrap();
        assert!(close(&numbers(attr(body, "pos")), &inertia.com, 1e-15), "{body}");
        let joint = element(&xml, "joint", &format!("{}:free", b.name)).unwrap();
        assert_eq!(attr(joint, "type"), "free");
        assert_eq!(numbers(attr(joint, "damping")), [sc.sim.body_damping_per_s * inertia.mass_kg]);
        let inertial = xml[xml.find(body).unwrap()..].split("<inertial ").nth(1).unwrap();
        assert_eq!(numbers(attr(inertial, "mass")), [1.0]);
        assert!(close(&numbers(attr(inertial, "diaginertia")), &inertia.principal_kg_m2, 1e-15));
    }
    for n in &s.nodes {
        let site = element(&xml, "site", &n.name).unwrap();
        let b = &s.bodies[n.body];
        let origin = if b.name == "strut1" { [0.0; 3] } else { b.inertia.unwrap().com };
        let local: Vec<f64> = (0..3).map(|k| n.position[k] - origin[k]).collect();
        assert!(close(&numbers(attr(site, "pos")), &local, 1e-15), "{site}");
    }
    for (_, st) in s.members_of(tensegrity_testbed::structure::MemberKind::Strut) {
        let geom = element(&xml, "geom", &st.name).unwrap();
        assert_eq!(attr(geom, "type"), "capsule");
        assert_eq!(numbers(attr(geom, "size")), [st.radius_m]);
    }
    for (_, c) in s.members_of(tensegrity_testbed::structure::MemberKind::Cable) {
        let t = element(&xml, "spatial", &c.name).unwrap();
        assert_eq!(numbers(attr(t, "stiffness")), [100.0]);
        assert_eq!(numbers(attr(t, "springlength")), [0.0, c.rest_length_m().unwrap()]);
        let sites = &xml[xml.find(t).unwrap()..];
        let sites = &sites[..sites.find("</spatial>").unwrap()];
        assert!(sites.contains(&format!("site=\"{}\"", s.nodes[c.ends().0].name)));
        assert!(sites.contains(&format!("site=\"{}\"", s.nodes[c.ends().1].name)));
    }
    let option = &xml[xml.find("<option ").unwrap()..];
    assert_eq!(numbers(attr(option, "gravity")), [0.0; 3]);
}

/// ji2014 at its grid's first point: the actuator's housing and rod are mocap bodies at their
/// drawn poses (ideal actuators), the platform hangs from the rod on the hinge D1 whose `ref`
/// is the drawn theta2 and whose damping is c_D1; the springs K1, K2 are tendons with the
/// paper's stiffness and zero free length. With position actuators instead: hinge theta1 and
/// slide L3 with `ref` at the grid point, servos of gain kp and the keyframe's commands.
#[test]
fn ji2014_exports_the_actuator_as_mocap_bodies_or_as_position_servos() {
    let sc = load("scenarios/ji2014/grid.toml");
    let (s, commands) = export::first_structure(&sc).unwrap();
    let xml = xml_of("scenarios/ji2014/grid.toml", ActuatorMode::Mocap);
    for b in ["actuator_housing", "actuator_rod"] {
        assert_eq!(attr(element(&xml, "body", b).unwrap(), "mocap"), "true");
    }
    let d1 = &s.joints[2];
    let hinge = element(&xml, "joint", "D1").unwrap();
    assert_eq!(attr(hinge, "type"), "hinge");
    assert_eq!(numbers(attr(hinge, "ref")), [d1.initial_coordinate]);
    assert_eq!(numbers(attr(hinge, "damping")), [sc.params["c_D1"]]);
    assert_eq!(numbers(attr(hinge, "axis")), [0.0, 0.0, 1.0]);
    // The rod's frame is at C1, the anchor of its joint L3; the platform's at D1, relative to it.
    let (c1, d1_at) = (s.nodes[0].position, s.nodes[4].position);
    assert_eq!(numbers(attr(element(&xml, "body", "actuator_rod").unwrap(), "pos")), c1);
    let platform: Vec<f64> = (0..3).map(|k| d1_at[k] - c1[k]).collect();
    assert_eq!(numbers(attr(element(&xml, "body", "platform").unwrap(), "pos")), platform);
    for (name, k) in [("K1", sc.params["K1"]), ("K2", sc.params["K2"])] {
        let t = element(&xml, "spatial", name).unwrap();
        assert_eq!(numbers(attr(t, "stiffness")), [k]);
        assert_eq!(numbers(attr(t, "springlength")), [0.0]);
    }
    assert_eq!(count(&xml, "joint"), 1);
    assert_eq!(count(&xml, "position"), 0);

    let xml = xml_of("scenarios/ji2014/grid.toml", ActuatorMode::Position);
    assert_eq!(count(&xml, "joint"), 3);
    for (joint, kind, symbol) in [("theta1", "hinge", "theta1"), ("L3", "slide", "L3")] {
        let j = element(&xml, "joint", joint).unwrap();
        assert_eq!(attr(j, "type"), kind);
        let a = s.actuators.iter().position(|a| a.symbol == symbol).unwrap();
        assert_eq!(numbers(attr(j, "ref")), [commands[a]]);
        let p = element(&xml, "position", symbol).unwrap();
        assert_eq!(attr(p, "joint"), joint);
        assert_eq!(numbers(attr(p, "kp")), [KP]);
    }
    let key = &xml[xml.find("<key ").unwrap()..];
    assert_eq!(numbers(attr(key, "ctrl")), commands);
}

/// The command line writes the file atomically, refuses to write over its input (exit 2) and
/// reports a bad scenario with exit 2.
#[test]
fn the_command_writes_the_xml_and_refuses_bad_input() {
    let dir = std::env::temp_dir().join(format!("export-mjcf-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("prism.xml");
    let (code, _, err) =
        tensegrity(&["export", "mjcf", "scenarios/custom/prism3.toml", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.starts_with("<mujoco model=\"3-strut tensegrity prism\">"));
    assert!(!dir.join("prism.partial").exists());
    let copy = dir.join("copy.toml");
    std::fs::copy("scenarios/custom/prism3.toml", &copy).unwrap();
    let (code, _, err) = tensegrity(&["export", "mjcf", copy.to_str().unwrap(), "--out", copy.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(
        std::fs::read_to_string(&copy).unwrap(),
        std::fs::read_to_string("scenarios/custom/prism3.toml").unwrap()
    );
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "name = \"x\"\nmechanism = \"nope\"\n[actuation]\npoints = [{}]\n").unwrap();
    let (code, _, err) = tensegrity(&["export", "mjcf", bad.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("bad.toml:"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

// ------------------------------------------------------------------------------------------
// MuJoCo: settle the export and compare with the testbed
// ------------------------------------------------------------------------------------------

/// Steps the testbed's simulation of the scenario's first structure until every node moves
/// slower than the scenario's speed tolerance for its window (as the settle loop does).
fn testbed_settled(sc: &Scenario) -> BTreeMap<String, P3> {
    let (s, commands) = export::first_structure(sc).unwrap();
    let mut sim = Simulation::new(&s, &sc.sim).unwrap();
    sim.set_commands(&commands);
    let positions = |sim: &Simulation| (0..s.nodes.len()).map(|i| sim.node_position(i)).collect::<Vec<P3>>();
    let max_steps = (sc.settle.max_time_s / sc.sim.dt_s).ceil() as usize;
    let (mut last, mut quiet) = (positions(&sim), 0);
    for _ in 0..max_steps {
        sim.step().unwrap();
        let now = positions(&sim);
        let moved = now.iter().zip(&last).map(|(a, b)| dist(*a, *b)).fold(0.0, f64::max);
        quiet = if moved <= sc.settle.speed_tol_m_per_s * sc.sim.dt_s { quiet + 1 } else { 0 };
        last = now;
        if quiet >= sc.settle.window_steps as usize {
            return s.nodes.iter().map(|n| n.name.clone()).zip(last).collect();
        }
    }
    panic!("{}: the testbed did not settle", sc.name);
}

fn dist(a: P3, b: P3) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// MuJoCo's settled sites for the export of `path`: (steps, sites).
fn mujoco_settled(py: &str, path: &str, mode: ActuatorMode) -> (u64, BTreeMap<String, P3>) {
    mujoco_settled_xml(py, &load(path), &xml_of(path, mode))
}

/// MuJoCo's settled sites for `xml`, with the settle criterion of `sc`: (steps, sites).
fn mujoco_settled_xml(py: &str, sc: &Scenario, xml: &str) -> (u64, BTreeMap<String, P3>) {
    let dir = std::env::temp_dir().join(format!("export-mjcf-mujoco-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let xml_path: PathBuf = dir.join(format!("{}-{}.xml", sc.name.replace(' ', "_"), xml.len()));
    std::fs::write(&xml_path, xml).unwrap();
    let out = Command::new(py)
        .args([
            "tests/mujoco/settle_mjcf.py",
            xml_path.to_str().unwrap(),
            "--max-time",
            &sc.settle.max_time_s.to_string(),
            "--speed-tol",
            &sc.settle.speed_tol_m_per_s.to_string(),
            "--window",
            &sc.settle.window_steps.to_string(),
        ])
        .output()
        .expect("python runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["settled"], true, "{}: MuJoCo did not settle", sc.name);
    let sites = v["sites"].as_object().unwrap();
    let sites = sites
        .iter()
        .map(|(k, p)| (k.clone(), [0, 1, 2].map(|i| p[i].as_f64().unwrap())))
        .collect::<BTreeMap<String, P3>>();
    (v["steps"].as_u64().unwrap(), sites)
}

/// Largest difference of the distance between any two nodes [m] (the shape, free of rigid
/// motions), and largest difference of any node's position [m].
fn differences(a: &BTreeMap<String, P3>, b: &BTreeMap<String, P3>) -> (f64, f64) {
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    let (mut shape, mut position) = (0.0f64, 0.0f64);
    for (n, p) in a {
        position = position.max(dist(*p, b[n]));
        for (m, q) in a {
            shape = shape.max((dist(*p, *q) - dist(b[n], b[m])).abs());
        }
    }
    (shape, position)
}

/// The prism settles in MuJoCo to the testbed's shape: every distance between two nodes within
/// 1e-10 m (measured 7.6e-13 m with mujoco 4.0.0; struts 1.5 m; one strut is held, and the prism may still turn about it at no cost,
/// so positions are compared through the shape).
#[test]
fn prism3_settles_in_mujoco_to_the_testbed_shape() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let path = "scenarios/custom/prism3.toml";
    let ours = testbed_settled(&load(path));
    let (steps, theirs) = mujoco_settled(&py, path, ActuatorMode::Mocap);
    let (shape, _) = differences(&ours, &theirs);
    eprintln!("prism3: MuJoCo settled in {steps} steps; shape difference {shape:.2e} m");
    assert!(shape <= 1e-10, "shape differs by {shape} m");
}

/// ji2014 at its grid's first point (L3 = 0.2 m, theta1 = 0) settles in MuJoCo to the
/// testbed's node positions within 1e-11 m (measured 1.5e-13 m with mujoco 4.0.0; L = 1 m): with the actuator as mocap bodies the
/// MuJoCo model has no soft constraint, only springs and the damped hinge.
#[test]
fn ji2014_settles_in_mujoco_to_the_testbed_positions() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let path = "scenarios/ji2014/grid.toml";
    let ours = testbed_settled(&load(path));
    let (steps, theirs) = mujoco_settled(&py, path, ActuatorMode::Mocap);
    let (shape, position) = differences(&ours, &theirs);
    eprintln!("ji2014: MuJoCo settled in {steps} steps; position difference {position:.2e} m, shape {shape:.2e} m");
    assert!(position <= 1e-11, "positions differ by {position} m");
}

/// The difference between MuJoCo's and the testbed's settled nodes [m] for the export of
/// `path` at the scenario's dt, dt / 4 and dt / 16, with `cable_damping` [N s/m].
fn differences_over_dt(py: &str, path: &str, cable_damping: f64) -> Vec<f64> {
    let sc = load(path);
    let ours = testbed_settled(&sc);
    let (s, commands) = export::first_structure(&sc).unwrap();
    let mut out = Vec::new();
    for dt in [sc.sim.dt_s, sc.sim.dt_s / 4.0, sc.sim.dt_s / 16.0] {
        let options = mjcf::MjcfOptions {
            model_name: sc.name.clone(),
            timestep_s: dt,
            body_damping_per_s: sc.sim.body_damping_per_s,
            actuators: ActuatorMode::Mocap,
            joint_kp: KP,
            commands: commands.clone(),
            cable_damping_n_s_per_m: cable_damping,
        };
        let m = mjcf::to_mjcf(&s, &options);
        assert!(m.warnings.is_empty(), "{:?}", m.warnings);
        let (steps, theirs) = mujoco_settled_xml(py, &sc, &m.xml);
        let (_, position) = differences(&ours, &theirs);
        eprintln!("{}: dt {dt} s, MuJoCo settled in {steps} steps; position difference {position:.2e} m", sc.name);
        out.push(position);
    }
    out
}

/// mohr2011 (quick.toml's first point: universal joints as two hinges, knees with torsion
/// springs, two legs closed on the end-effector by connect equalities, six inextensible cables
/// as limited tendons) settles in MuJoCo to the testbed's node positions within MuJoCo's own
/// accuracy: its joint closures and cable limits are soft constraints whose offset falls with
/// the time step squared (the MuJoCo peer's README), so the difference must be below 1e-5 m at
/// the scenario's dt = 0.01 s and fall at least 8 times with each quarter of dt (16 times for
/// dt^2). Measured with mujoco 4.0.0: 2.9e-6, 1.8e-7 and 1.1e-8 m at dt, dt/4 and dt/16.
#[test]
fn mohr2011_settles_in_mujoco_to_the_testbed_within_its_soft_constraint_offset() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let d = differences_over_dt(&py, "scenarios/mohr2011/quick.toml", 0.0);
    assert!(d[0] <= 1e-5, "{d:?}");
    assert!(d.windows(2).all(|w| w[1] <= w[0] / 8.0), "{d:?}");
}

/// furet2018's two crossed four-bars (ik_solutions.toml's first point: loops closed at D by
/// connect equalities, the first actuator a mocap bar, the second, on a moving body, held by a
/// joint equality) settle in MuJoCo to the testbed's nodes within MuJoCo's soft-constraint
/// offset: below 1e-4 m (bars 1 m) at the scenario's dt = 0.005 s, falling at least 8 times with
/// each quarter of dt. Measured with mujoco 4.0.0: 4.0e-5, 2.5e-6 and 1.6e-7 m.
#[test]
fn furet2018_settles_in_mujoco_to_the_testbed_within_its_soft_constraint_offset() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let d = differences_over_dt(&py, "scenarios/furet2018/ik_solutions.toml", 0.0);
    assert!(d[0] <= 1e-4, "{d:?}");
    assert!(d.windows(2).all(|w| w[1] <= w[0] / 8.0), "{d:?}");
}

/// Cable damping of the winch test [N s/m]: without it MuJoCo needed 126 s of simulated time
/// (62872 steps) to meet the 1e-10 m/s criterion, with it 14 s; zero at rest.
const WINCH_TEST_DAMPING_N_S_PER_M: f64 = 10.0;

/// mohr2011 with elastic cables wound by winches (elastic_cables.toml's first point): each
/// winch is a `<position>` actuator on its tendon with kp = the cable's stiffness and no push
/// (force range [-max, 0]), started from the keyframe of the commands; with cable damping
/// (`kv`) it settles in MuJoCo to the testbed's nodes within the soft-constraint offset of the
/// two leg closures, falling at least 8 times with each quarter of dt. Measured with mujoco
/// 4.0.0: 1.0e-7, 6.4e-9 and 4.0e-10 m at dt, dt/4 and dt/16.
#[test]
fn mohr2011_with_winched_elastic_cables_settles_in_mujoco_to_the_testbed() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let d = differences_over_dt(&py, "scenarios/mohr2011/elastic_cables.toml", WINCH_TEST_DAMPING_N_S_PER_M);
    assert!(d[0] <= 1e-5, "{d:?}");
    assert!(d.windows(2).all(|w| w[1] <= w[0] / 8.0), "{d:?}");
}

/// manriquez2019 (table3.toml's first experiment: a universal joint as two hinges, gravity,
/// two zero-free-length springs, two inextensible cables as limited tendons) settles in MuJoCo
/// to the testbed's nodes within the soft offset of its cable limits, falling at least 8 times
/// with each quarter of dt. Measured with mujoco 4.0.0: 2.1e-6, 1.3e-7 and 8.1e-9 m.
#[test]
fn manriquez2019_settles_in_mujoco_to_the_testbed_within_its_soft_constraint_offset() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    let d = differences_over_dt(&py, "scenarios/manriquez2019/table3.toml", 0.0);
    assert!(d[0] <= 1e-5, "{d:?}");
    assert!(d.windows(2).all(|w| w[1] <= w[0] / 8.0), "{d:?}");
}
