//! `tensegrity modes`: a structure's natural frequencies at its settled state, from the
//! relaxation's tangent stiffness and the bodies' mass matrix, against a closed form and
//! against MuJoCo's linearisation of the MJCF export (`mjd_transitionFD`).

use crate::common;

use std::path::Path;
use std::process::Command;
use tensegrity_testbed::run::settle_first_point;
use tensegrity_testbed::scenario;
use tensegrity_testbed::sim::modes::{Lowest, StructureModes};

/// A free body (2.5 kg, nodes C at the origin and D 0.1 m above it: centre of mass 0.05 m
/// above C) held at C by six zero-free-length springs (k = 40 N/m each, to anchors 1 m away on
/// the axes): each spring's tangent stiffness is k e e^T + (t / l)(1 - e e^T) = k 1 (t = k l),
/// so C sits in an isotropic 6 k spring: the stiffness has rank 3 (one point held), so the three
/// turns about C are free; the translation along z (the line through C and the centre of mass)
/// moves C alone: omega^2 = 6 k / m = 96 rad^2/s^2.
const BODY_ON_SIX_SPRINGS: &str = r#"name = "body on six springs"
mechanism = "custom"
[actuation]
points = [ {} ]
[structure]
[[structure.bodies]]
name = "ground"
fixed = true
nodes = { XP = [1, 0, 0], XM = [-1, 0, 0], YP = [0, 1, 0], YM = [0, -1, 0], ZP = [0, 0, 1], ZM = [0, 0, -1] }
[[structure.bodies]]
name = "bob"
mass = 2.5
inertia = [0.1, 0.2, 0.3]
nodes = { C = [0, 0, 0], D = [0, 0, 0.1] }
[[structure.springs]]
name = "sxp"
a = "C"
b = "XP"
stiffness = 40.0
length = 0.0
[[structure.springs]]
name = "sxm"
a = "C"
b = "XM"
stiffness = 40.0
length = 0.0
[[structure.springs]]
name = "syp"
a = "C"
b = "YP"
stiffness = 40.0
length = 0.0
[[structure.springs]]
name = "sym"
a = "C"
b = "YM"
stiffness = 40.0
length = 0.0
[[structure.springs]]
name = "szp"
a = "C"
b = "ZP"
stiffness = 40.0
length = 0.0
[[structure.springs]]
name = "szm"
a = "C"
b = "ZM"
stiffness = 40.0
length = 0.0
"#;

fn modes_of(path: &str, text: Option<&str>) -> StructureModes {
    let sc = match text {
        Some(t) => scenario::parse(Path::new(path), t).unwrap(),
        None => scenario::load(Path::new(path)).unwrap(),
    };
    let mut state = settle_first_point(&sc, None).unwrap();
    assert!(state.settled, "{path} settles");
    state.sim.modes().unwrap()
}

/// Three rigid-body modes (the turns about C) and three more, each within 1e-9 relative: the
/// vertical translation at omega^2 = K / m (K = 6 k: C moves alone), and the horizontal
/// translations coupled with the turns about the centre of mass G, d = 0.05 m above C. Along x
/// with the turn about y, C moves by x - d theta_y: V = K (x - d theta)^2 / 2 and
/// T = (m x'^2 + I_y theta'^2) / 2 leave one turn about C free and omega^2 = K (1 / m + d^2 / I_y);
/// along y with the turn about x, the same with I_x. With I = (0.1, 0.2, 0.3) kg m^2 about G:
/// 96, 99 and 102 rad^2/s^2.
#[test]
fn a_body_on_six_springs_vibrates_at_the_closed_form_frequency() {
    let m = modes_of("six.toml", Some(BODY_ON_SIX_SPRINGS));
    assert_eq!(m.rigid, 3, "{:?}", m.modes.iter().map(|x| x.omega()).collect::<Vec<_>>());
    let (k, mass, d, inertia) = (6.0 * 40.0, 2.5, 0.05, [0.1, 0.2]);
    let want = [k / mass, k * (1.0 / mass + d * d / inertia[1]), k * (1.0 / mass + d * d / inertia[0])];
    let got: Vec<f64> = m.modes.iter().filter(|x| !x.rigid).map(|x| x.omega_squared).collect();
    assert_eq!(got.len(), 3, "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(((g - w) / w).abs() <= 1e-9, "{got:?} vs {want:?}");
    }
}

/// The prism's lowest frequencies are MuJoCo's (from the notes, mujoco 4.0 at dt = 1e-4):
/// 7.856, 9.092, 12.675 and 16.40 rad/s, within half a unit of their last printed digit;
/// three rigid-body modes
/// (the two free struts' spins about their axes, and the turn of the whole about the held
/// strut's line).
#[test]
fn prism3_has_the_frequencies_mujoco_reports() {
    let m = modes_of("scenarios/custom/prism3.toml", None);
    assert_eq!((m.modes.len(), m.rigid), (12, 3));
    let omega: Vec<f64> = m.modes.iter().filter(|x| !x.rigid).map(|x| x.omega()).collect();
    for (got, (want, half_digit)) in omega.iter().zip([(7.856, 5e-4), (9.092, 5e-4), (12.675, 5e-4), (16.40, 5e-3)]) {
        assert!((got - want).abs() <= half_digit, "{got} vs {want}");
    }
}

/// A jointed structure's modes are reduced to its free joints' coordinates: the pinned bar's
/// one mode is the pendulum's sqrt(V''(q*) / I) = 16.2228403 rad/s, and ji2014's platform about
/// D1 (the actuators held) has sqrt(K / I_D1) with K of Eq. 42, each within 1e-7 (measured
/// 1.5e-8 and 5.1e-9: the finite differences' round-off).
#[test]
fn a_jointed_structure_is_reduced_to_its_joints_coordinates() {
    let bar = modes_of("scenarios/custom/pinned_bar_vibration.toml", None);
    assert_eq!((bar.joints.len(), bar.modes.len(), bar.rigid), (1, 1, 0));
    let k = 1.0 * f64::hypot(50.0 * 0.8, 30.0 * 0.6);
    let omega = (k / (0.5 / 3.0)).sqrt();
    assert!((bar.modes[0].omega() - omega).abs() <= 1e-7 * omega, "{} against {omega}", bar.modes[0].omega());
    let ji = modes_of("scenarios/ji2014/free_vibration.toml", None);
    assert_eq!(ji.joints.len(), 1, "D1 alone: L3 and theta1 are held");
    let eq42 = 29.258228902; // sqrt(K / (2 m L^2 / 3)) at L3 = 1, theta1 = 0.5 (the motion run's)
    assert!((ji.modes[0].omega() - eq42).abs() <= 1e-7 * eq42, "{}", ji.modes[0].omega());
}

/// A rigid body (m = 2 kg, isotropic moment I = 0.05 kg m^2 about its centre of mass) hung
/// from a fixed anchor by an inextensible cable of c = 1 m tied d = 0.25 m above its centre of
/// mass, under g = 9.81 m/s^2.
const HANGING_BODY: &str = r#"name = "body hanging on an inextensible cable"
mechanism = "custom"
[settle]
speed_tol = 1e-12
residual_force_tol = 1e-10
residual_torque_tol = 1e-10
[actuation]
points = [ {} ]
[structure]
gravity = [0, 0, -9.81]
[[structure.bodies]]
name = "ground"
fixed = true
nodes = { Q = [0, 0, 0] }
[[structure.bodies]]
name = "bob"
mass = 2.0
inertia = [0.05, 0.05, 0.05]
nodes = { P = [0, 0, -1], S = [0, 0, -1.5] }
[[structure.cables]]
name = "rope"
a = "Q"
b = "P"
length = 1.0
"#;

/// The frequencies [rad/s] of the body on its cable: in each vertical plane a double pendulum
/// (cable angle phi, body angle psi) with M = [[m c^2, m c d], [m c d, m d^2 + I]] and
/// K = [[m g c, 0], [0, m g d]] (the cable's stiffness m g c is its tension T = m g times the
/// curvature of its length: all of it from the constraint force). det(K - w^2 M) = 0 is
/// a w^4 + b w^2 + e = 0 with a = m c^2 I, b = -(m g c (m d^2 + I) + m^2 g c^2 d),
/// e = m^2 g^2 c d.
fn hanging_body_frequencies() -> [f64; 2] {
    let (m, c, d, i, g): (f64, f64, f64, f64, f64) = (2.0, 1.0, 0.25, 0.05, 9.81);
    let a = m * c * c * i;
    let b = -(m * g * c * (m * d * d + i) + m * m * g * c * c * d);
    let e = m * m * g * g * c * d;
    let root = (b * b - 4.0 * a * e).sqrt();
    [((-b - root) / (2.0 * a)).sqrt(), ((-b + root) / (2.0 * a)).sqrt()]
}

/// A body on a taut inextensible cable: the cable's length is a constraint (5 degrees of
/// freedom of 6 coordinates), its tension from the equilibrium is the weight m g = 19.62 N,
/// and the modes are the double pendulum's in both vertical planes (each twice) and the free
/// spin about the vertical, within 1e-9 (measured 2e-10: the finite differences, extrapolated).
#[test]
fn a_body_on_a_taut_inextensible_cable_swings_at_the_double_pendulum_frequencies() {
    let m = modes_of("hanging.toml", Some(HANGING_BODY));
    let c = m.constraints.as_ref().expect("held by a constraint");
    assert_eq!((c.coordinates.len(), c.rows, c.degrees_of_freedom()), (6, 1, 5));
    assert!((c.multipliers[0] - 2.0 * 9.81).abs() <= 1e-9 * 19.62, "tension {}", c.multipliers[0]);
    assert_eq!((m.modes.len(), m.rigid), (5, 1));
    let omega: Vec<f64> = m.modes.iter().filter(|x| !x.rigid).map(|x| x.omega()).collect();
    let [low, high] = hanging_body_frequencies();
    for (got, want) in omega.iter().zip([low, low, high, high]) {
        assert!((got - want).abs() <= 1e-9 * want, "{got} against {want}");
    }
}

/// A parallelogram four-bar hanging in gravity: cranks of a = 0.5 m (0.3 kg, 0.01 kg m^2 about
/// their middles) pinned 0.8 m apart, a coupler of 0.7 kg, the loop closed at D by a planar
/// pin.
const FOUR_BAR: &str = r#"name = "hanging parallelogram four-bar"
mechanism = "custom"
[settle]
speed_tol = 1e-12
residual_force_tol = 1e-10
residual_torque_tol = 1e-10
[interference]
informative = true
[actuation]
points = [ {} ]
[structure]
gravity = [0, -9.81, 0]
[[structure.bodies]]
name = "base"
fixed = true
nodes = { A = [0, 0, 0], B = [0.8, 0, 0] }
[[structure.bodies]]
name = "crank1"
mass = 0.3
inertia = [0.01, 0.01, 0.01]
nodes = { A1 = [0, 0, 0], C1 = [0, -0.5, 0] }
[[structure.bodies]]
name = "crank2"
mass = 0.3
inertia = [0.01, 0.01, 0.01]
nodes = { B2 = [0.8, 0, 0], D2 = [0.8, -0.5, 0] }
[[structure.bodies]]
name = "coupler"
mass = 0.7
inertia = [0.02, 0.02, 0.02]
nodes = { C = [0, -0.5, 0], D = [0.8, -0.5, 0] }
[[structure.joints]]
name = "A"
kind = "revolute"
parent = "base"
child = "crank1"
at = "A"
axis = [0, 0, 1]
[[structure.joints]]
name = "C"
kind = "revolute"
parent = "crank1"
child = "coupler"
at = "C"
axis = [0, 0, 1]
[[structure.joints]]
name = "B"
kind = "revolute"
parent = "base"
child = "crank2"
at = "B"
axis = [0, 0, 1]
[[structure.joints]]
name = "D"
kind = "planar_pin"
parent = "crank2"
child = "coupler"
at = "D"
axis = [0, 0, 1]
"#;

/// The four-bar's loop is a constraint (3 joint coordinates, 2 rows, 1 degree of freedom): the
/// coupler translates on a circle of radius a, so T = (2 (I + m a^2 / 4) + M a^2) w^2 / 2 and
/// V = -(m + M) g a cos phi give w^2 = g a (m + M) / (2 I + m a^2 / 2 + M a^2) =
/// (4.5931224884 rad/s)^2, met within 1e-9 (measured 5e-10).
#[test]
fn a_parallelogram_four_bar_closed_by_a_loop_swings_at_the_closed_form_frequency() {
    let m = modes_of("four_bar.toml", Some(FOUR_BAR));
    let c = m.constraints.as_ref().expect("held by its loop");
    assert_eq!((c.coordinates.len(), c.rows, c.degrees_of_freedom(), m.modes.len()), (3, 2, 1, 1));
    let (a, crank, inertia, coupler, g): (f64, f64, f64, f64, f64) = (0.5, 0.3, 0.01, 0.7, 9.81);
    let want = (g * a * (crank + coupler) / (2.0 * inertia + crank * a * a / 2.0 + coupler * a * a)).sqrt();
    assert!((m.modes[0].omega() - want).abs() <= 1e-9 * want, "{} against {want}", m.modes[0].omega());
}

/// A loop held at its actuator's command has no motion left: the Snelson X (one four-bar, its
/// angle at A commanded) has 2 free joint coordinates and 2 loop rows of rank 2, so no mode.
#[test]
fn a_loop_held_by_its_actuator_has_no_mode() {
    let m = modes_of("scenarios/custom/snelson-x.toml", None);
    let c = m.constraints.as_ref().expect("held by its loop");
    assert_eq!((c.coordinates.len(), c.rank, c.degrees_of_freedom(), m.modes.len()), (2, 2, 0, 0));
}

/// `modes` analyses every shipped scenario of the four seeds (the first point, settled or
/// not): every frequency is finite. At every settled first point the tensions of the taut
/// inextensible cables found from the equilibrium are the simulator's within 1e-6 relative.
#[test]
fn every_seed_scenario_has_finite_frequencies() {
    for seed in ["ji2014", "mohr2011", "furet2018", "manriquez2019"] {
        let mut files: Vec<_> = std::fs::read_dir(format!("scenarios/{seed}"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        for path in files {
            let sc = scenario::load(&path).unwrap();
            let mut state = settle_first_point(&sc, None).unwrap();
            let m = state.sim.modes().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(m.modes.iter().all(|x| x.omega().is_finite()), "{}", path.display());
            let Some(c) = m.constraints.as_ref().filter(|_| state.settled) else { continue };
            let forces = state.sim.member_forces();
            let loop_rows = c.multipliers.len() - c.taut_cables.len();
            for (&k, t) in c.taut_cables.iter().zip(&c.multipliers[loop_rows..]) {
                let sim = forces.force_n[k];
                assert!(
                    (t - sim).abs() <= 1e-6 * sim.abs().max(1.0),
                    "{}: cable {k} {t} N against {sim} N",
                    path.display()
                );
            }
        }
    }
}

/// The 3-strut prism whose bottom ring is one clustered cable.
const CLUSTERED_PRISM: &str = "scenarios/custom/prism3_clustered_ring.toml";

/// Clustering the prism's bottom ring keeps its equilibrium (the file's twist and force
/// densities hold within 1e-9) but frees the ring's segments to trade length: every
/// non-rigid frequency falls, the lowest from 7.856 to 3.749 rad/s (measured, both in
/// BENCHMARKS.md), each within 1e-6 of those values.
#[test]
fn a_clustered_ring_lowers_every_frequency_of_the_prism() {
    let plain = modes_of("scenarios/custom/prism3.toml", None);
    let clustered = modes_of(CLUSTERED_PRISM, None);
    let omega = |m: &StructureModes| m.modes.iter().filter(|x| !x.rigid).map(|x| x.omega()).collect::<Vec<_>>();
    let (plain, clustered) = (omega(&plain), omega(&clustered));
    assert_eq!((plain.len(), clustered.len()), (9, 9));
    for (p, c) in plain.iter().zip(&clustered) {
        assert!(c < p, "clustered {c} rad/s against {p}");
    }
    for (got, want) in [(plain[0], 7.856140456), (clustered[0], 3.749005751)] {
        assert!((got - want).abs() <= 1e-6 * want, "{got} against {want}");
    }
}

/// MuJoCo's frequencies (dispersion-corrected) of the export of `path`, settled there.
fn mujoco_modes(py: &str, path: &str) -> Vec<f64> {
    let dir = std::env::temp_dir().join(format!("tensegrity-modes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let xml = dir.join(format!("{}.xml", Path::new(path).file_stem().unwrap().to_string_lossy()));
    let (code, _, err) = common::tensegrity(&["export", "mjcf", path, "--out", xml.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let sc = scenario::load(Path::new(path)).unwrap();
    let out = Command::new(py)
        .arg("tests/mujoco/modes_mjcf.py")
        .arg(&xml)
        .args(["--max-time", &sc.settle.max_time_s.to_string()])
        .args(["--speed-tol", &sc.settle.speed_tol_m_per_s.to_string()])
        .args(["--window", &sc.settle.window_steps.to_string()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["settled"], true, "{v}");
    v["omega"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// Every mode of prism3, of the icosahedron and of the prism whose bottom ring is one
/// clustered cable (exported as one spatial tendon through the sites B1, B2, B3, B1) agrees with
/// MuJoCo's linearisation of the MJCF export within 1e-7 relative (measured: at most 4.2e-8;
/// the clustered prism 3.3e-8), the rigid-body modes counted alike
/// (MuJoCo's below 1e-3 rad/s). The tolerance: MuJoCo's transition matrix is a centred finite
/// difference (eps 1e-6) of its step map at dt = 1e-4 s, its frequencies corrected exactly for
/// the semi-implicit step's dispersion ((w dt)^2 / 24 uncorrected: up to 1.3e-6 here), and the
/// two settle to states 1e-10 m apart; these structures use no soft constraint (springs and
/// elastic cables only), so MuJoCo adds no stiffness of its own.
#[test]
fn prism3_and_the_icosahedron_agree_with_mujoco() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    const RIGID_RAD_PER_S: f64 = 1e-3;
    let paths = ["scenarios/custom/prism3.toml", "scenarios/custom/icosahedron6.toml", CLUSTERED_PRISM];
    for path in paths {
        let ours = modes_of(path, None);
        let theirs = mujoco_modes(&py, path);
        assert_eq!(theirs.len(), ours.modes.len(), "{path}");
        assert_eq!(theirs.iter().filter(|w| **w < RIGID_RAD_PER_S).count(), ours.rigid, "{path}: {theirs:?}");
        let mut worst = 0.0f64;
        for (m, w) in ours.modes.iter().zip(&theirs).filter(|(m, _)| !m.rigid) {
            worst = worst.max(((m.omega() - w) / w).abs());
        }
        eprintln!("{path}: largest relative difference from MuJoCo {worst:.2e}");
        assert!(worst < 1e-7, "{path}: {worst:e}");
    }
}

/// `--record FILE.rrd` writes one entity group per non-rigid mode (prism3: 9), each with its
/// nodes, struts and cables, decoded back from the file.
#[test]
fn the_recording_animates_every_mode() {
    let dir = std::env::temp_dir().join(format!("tensegrity-modes-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rrd = dir.join("prism3-modes.rrd");
    let (code, _, err) =
        common::tensegrity(&["modes", "scenarios/custom/prism3.toml", "--record", rrd.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let file = std::io::BufReader::new(std::fs::File::open(&rrd).expect("recording exists"));
    let mut entities = std::collections::BTreeSet::new();
    for msg in re_log_encoding::Decoder::<re_log_types::LogMsg>::decode_lazy(file) {
        if let re_log_types::LogMsg::ArrowMsg(_, arrow) = msg.expect("decodes") {
            entities.insert(re_chunk::Chunk::from_arrow_msg(&arrow).expect("a chunk").entity_path().to_string());
        }
    }
    let modes: std::collections::BTreeSet<String> = entities
        .iter()
        .filter_map(|e| e.strip_prefix("/modes/").map(|r| r.split('/').next().unwrap().to_string()))
        .collect();
    assert_eq!(modes.len(), 9, "{entities:?}");
    assert!(
        entities.iter().any(|e| e.ends_with("/struts")) && entities.iter().any(|e| e.ends_with("/cables")),
        "{entities:?}"
    );
    let (code, _, err) = common::tensegrity(&["modes", "scenarios/custom/prism3.toml", "--record", "x.txt"]);
    assert_eq!(code, 2, "{err}");
}

/// Above `structure::DENSE_MODAL_MAX_FREE_BODIES` free bodies the modes of free bodies on
/// springs and elastic cables are the sparse solver's (`sim/relaxation/lowest_modes.rs`): on
/// the 150-strut prism of `benches/prism_modes.toml`, settled, the lowest 20 non-rigid
/// frequencies are the dense eigenproblem's within 1e-8 relative (measured 2.7e-12 at 300
/// struts), with the same 150 rigid-body modes (149 struts' spins about their axes and the turn
/// about the held strut's line), each shape mass-normalised, and it says that these are the
/// lowest of 894. Asked for more (`modes --count 60`), the lowest 60 are the dense ones too.
#[test]
fn the_sparse_lowest_modes_of_a_large_prism_are_the_dense_ones() {
    let text = std::fs::read_to_string("benches/prism_modes.toml")
        .unwrap()
        .replace("n = { value = 300,", "n = { value = 150,");
    let sc = scenario::parse(Path::new("prism150.toml"), &text).unwrap();
    let mut state = settle_first_point(&sc, None).unwrap();
    assert!(state.settled);
    let sparse = state.sim.modes().unwrap();
    let dense = state.sim.modes_dense().unwrap();
    assert_eq!((sparse.lowest_of, dense.lowest_of), (Some(6 * 149), None));
    assert_eq!((sparse.rigid, dense.rigid), (150, 150));
    assert_eq!(sparse.modes.len(), 150 + 20);
    let lowest =
        |m: &StructureModes| m.modes.iter().filter(|x| !x.rigid).map(|x| x.omega()).take(20).collect::<Vec<_>>();
    let (s, d) = (lowest(&sparse), lowest(&dense));
    for (k, (a, b)) in s.iter().zip(&d).enumerate() {
        assert!(((a - b) / b).abs() <= 1e-8, "mode {}: {a} against {b} rad/s", k + 1);
    }
    let more = state.sim.modes_until(Lowest { count: 60, through: None }, None).unwrap();
    assert_eq!((more.modes.len(), more.rigid), (150 + 60, 150));
    let non_rigid = |m: &StructureModes| m.modes.iter().filter(|x| !x.rigid).map(|x| x.omega()).collect::<Vec<_>>();
    for (k, (a, b)) in non_rigid(&more).iter().zip(&non_rigid(&dense)).enumerate() {
        assert!(((a - b) / b).abs() <= 1e-8, "mode {}: {a} against {b} rad/s", k + 1);
    }
    for mode in &sparse.modes {
        let norm: f64 = sparse
            .mass
            .iter()
            .enumerate()
            .map(|(i, block)| {
                let x = nalgebra::Vector6::from_column_slice(&mode.shape[6 * i..6 * i + 6]);
                x.dot(&(block * x))
            })
            .sum();
        assert!((norm - 1.0).abs() <= 1e-10, "x^T M x = {norm}");
    }
}

/// A motion along a mode above the sparse solver's lowest 20 asks it for every mode through
/// that one: on the 150-strut prism (150 rigid modes) mode 195, the 45th non-rigid, starts and
/// runs its steps; a mode that needs more than 200 non-rigid modes (mode 351) is refused when
/// the motion starts, naming the count asked for.
#[test]
fn a_motion_along_a_higher_mode_of_a_large_prism_asks_the_sparse_solver_for_it() {
    let text = std::fs::read_to_string("benches/prism_modes.toml")
        .unwrap()
        .replace("n = { value = 300,", "n = { value = 150,");
    let along = |mode: usize| {
        let motion =
            format!("[motion]\nduration_s = 0.05\nstart = \"drawn\"\nmode = {mode}\namplitude = 1e-6\n\n[actuation]");
        let sc = scenario::parse(Path::new("prism150.toml"), &text.replace("[actuation]", &motion)).unwrap();
        tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default())
    };
    let higher = along(195);
    assert!(higher.error.is_none(), "{:?}", higher.error);
    let motion = higher.motion.as_ref().expect("a motion");
    assert_eq!((motion.steps_taken, motion.steps), (10, 10));
    let past = along(351);
    let error = past.error.expect("refused").to_string();
    assert!(
        error.contains("the lowest 201 modes beyond the structure's 150 rigid ones were asked for (through mode 351); the sparse solver computes at most 200"),
        "{error}"
    );
}

/// The structures built of point masses (`structure/lumped.rs`) agree with MuJoCo too: the
/// prism with elastic struts (each a tendon spring between two point masses in the export) and
/// the beaded string (a heavy cable: beads on tendon springs), every mode within 1e-7 relative;
/// MuJoCo's rigid-body modes are ours and the point masses' turns, which ours leaves out.
#[test]
fn the_elastic_prism_and_the_beaded_string_agree_with_mujoco() {
    let Some(py) = crate::common::peer_python(&["mujoco"], module_path!()) else { return };
    for path in ["scenarios/custom/prism3_elastic.toml", "scenarios/custom/beaded_string.toml"] {
        let ours = modes_of(path, None);
        let theirs = mujoco_modes(&py, path);
        assert_eq!(theirs.len(), ours.modes.len() + ours.left_out, "{path}");
        let theirs_rigid = theirs.iter().filter(|w| **w < 1e-3).count();
        assert_eq!(theirs_rigid, ours.rigid + ours.left_out, "{path}: {theirs:?}");
        let theirs = &theirs[ours.left_out..];
        let worst = ours
            .modes
            .iter()
            .zip(theirs)
            .filter(|(m, _)| !m.rigid)
            .map(|(m, w)| ((m.omega() - w) / w).abs())
            .fold(0.0, f64::max);
        eprintln!("{path}: largest relative difference from MuJoCo {worst:.2e}");
        assert!(worst < 1e-7, "{path}: {worst:e}");
    }
}

/// A slider of mass m on a vertical prismatic joint, hanging from an anchor by a rope of
/// stiffness k: stretched m g / k, with its settle tolerances fine enough to find it.
fn slider_on_a_rope(mass_kg: f64, stiffness_n_per_m: f64) -> String {
    format!(
        r#"name = "slider on a rope"
mechanism = "custom"
[sim]
dt = 0.0005
[settle]
speed_tol = 1e-12
residual_force_tol = 1e-10
residual_torque_tol = 1e-10
[actuation]
points = [ {{}} ]
[structure]
gravity = [0, 0, -9.81]
[[structure.bodies]]
name = "ground"
fixed = true
nodes = {{ A = [0, 0, 1], G = [0, 0, 0] }}
[[structure.bodies]]
name = "slider"
mass = {mass_kg:?}
nodes = {{ P = [0, 0, 0] }}
[[structure.joints]]
name = "slide"
kind = "prismatic"
parent = "ground"
child = "slider"
at = "P"
axis = [0, 0, 1]
damping = 0.5
[[structure.cables]]
name = "rope"
a = "A"
b = "P"
stiffness = {stiffness_n_per_m:?}
length = 1.0
[expect]
verdict = "pass"
"#
    )
}

/// F1 of issue 60: a joint tree's modes difference its energy at a step (here 1e-4 m) that had
/// crossed a rope's slack point (stretched m g / k = 4.9e-5 m) and read its slack side: 417.2
/// rad/s for the exact sqrt(k / m) = 447.2. The analysis's energy now keeps each cable on the
/// branch of its law it is on (taut: k (l - l0)^2 / 2 on both sides of its rest length), so no
/// difference crosses the kink, however near it sits: the exact frequency within 1e-6 at
/// 1e4 N/m, and at 1e9 N/m (stretched 4.9e-10 m, 1/2e5 of the step; it had been refused).
#[test]
fn a_joint_modes_difference_stays_on_the_taut_side_of_a_rope() {
    let m = 0.05;
    for k in [1e4, 1e9] {
        // The slider given a second node, so that it is no point mass whose step `check` would
        // refuse first at 1e9 N/m; settled to its tolerances or not, the rope is taut under the
        // slider's weight, and a taut linear rope's stiffness is the same wherever it stands.
        let text = slider_on_a_rope(m, k).replacen("P = [0, 0, 0] }", "P = [0, 0, 0], Q = [0.1, 0, 0] }", 1);
        let sc = scenario::parse(Path::new("rope.toml"), &text).unwrap();
        let mut state = settle_first_point(&sc, None).unwrap();
        let analysis = state.sim.modes().unwrap();
        let omega = analysis.modes.iter().find(|x| !x.rigid).expect("a mode").omega();
        let exact: f64 = (k / m).sqrt();
        assert!((omega / exact - 1.0).abs() <= 1e-6, "k = {k}: {omega} against {exact}");
    }
}

/// A bar pinned at A (a revolute joint about z) whose tip Q holds a bead P on a spring, the
/// bead held by two more springs to the ground: a joint tree with a free body beside it (F5 of
/// issue 60, refused before as "hangs on no joint"). Its four coordinates (the pin's angle and
/// the bead's three translations; a point mass's turns move nothing) give four modes, the
/// eigenvalues of M^-1 K with K assembled by hand at the settled state (each spring's
/// k e e^T + (t / l)(1 - e e^T), the tip moving by z x rho per radian, plus the tip force's
/// F . rho_xy for the turn's curvature) and M = diag(m L^2 / 3, m_P, m_P, m_P): within 1e-7
/// relative (the analysis's second differences).
#[test]
fn a_joint_tree_with_a_free_bead_beside_it_has_the_modes_of_its_four_coordinates() {
    let text = common::one_point_head("a pinned bar holding a bead")
        .replace("[settle]", "[sim]\nbody_damping = 2.0\n\n[settle]")
        + r#"[[structure.bodies]]
name = "ground"
fixed = true
nodes = { O = [0, 0, 0], S = [1, 1, 0], G = [2, -1, 0] }

[[structure.bodies]]
name = "bar"
mass = 1.0
nodes = { A = [0, 0, 0], Q = [1, 0, 0] }

[[structure.bodies]]
name = "bead"
mass = 0.2
nodes = { P = [2, 0, 0] }

[[structure.joints]]
name = "pin"
kind = "revolute"
parent = "ground"
child = "bar"
at = "A"
axis = [0, 0, 1]
damping = 0.5
"# + &[
        ("up", "Q", "S", 50.0, 0.5),
        ("link", "Q", "P", 80.0, 0.8),
        ("down", "P", "G", 60.0, 0.7),
        ("side", "P", "S", 40.0, 1.0),
    ]
    .iter()
    .map(|(n, a, b, k, l)| {
        format!("[[structure.springs]]\nname = \"{n}\"\na = \"{a}\"\nb = \"{b}\"\nstiffness = {k}\nlength = {l}\n\n")
    })
    .collect::<String>();
    let sc = scenario::parse(Path::new("mixed.toml"), &text).expect("valid");
    let mut state = settle_first_point(&sc, None).expect("settles");
    assert!(state.settled);
    let at = |n: &str| nalgebra::Vector3::from(state.sim.node_position(state.sim.structure().node_id(n).unwrap()));
    let (q, p, s, g) = (at("Q"), at("P"), at("S"), at("G"));
    let spring = |a: nalgebra::Vector3<f64>, b: nalgebra::Vector3<f64>, k: f64, l0: f64| {
        let (d, eye) = (b - a, nalgebra::Matrix3::identity());
        let (l, e) = (d.norm(), d.normalize());
        let t = k * (l - l0);
        (e * e.transpose() * k + (eye - e * e.transpose()) * (t / l), e * t)
    };
    let rho = q - at("A");
    let r = nalgebra::Vector3::z().cross(&rho);
    let mut k = nalgebra::Matrix4::<f64>::zeros();
    let (up, up_pull) = spring(q, s, 50.0, 0.5);
    let (link, link_pull) = spring(q, p, 80.0, 0.8);
    let (down, _) = spring(p, g, 60.0, 0.7);
    let (side, _) = spring(p, s, 40.0, 1.0);
    let tip_force = up_pull + link_pull;
    k[(0, 0)] = (r.transpose() * (up + link) * r)[0] + tip_force.dot(&nalgebra::Vector3::new(rho.x, rho.y, 0.0));
    k.fixed_view_mut::<3, 3>(1, 1).copy_from(&(link + down + side));
    let coupling = -(link * r);
    k.fixed_view_mut::<3, 1>(1, 0).copy_from(&coupling);
    k.fixed_view_mut::<1, 3>(0, 1).copy_from(&coupling.transpose());
    let mass = nalgebra::Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0 / 12.0 + 0.25, 0.2, 0.2, 0.2));
    let mut want: Vec<f64> = (mass.try_inverse().unwrap() * k).eigenvalues().unwrap().iter().copied().collect();
    want.sort_by(f64::total_cmp);
    let analysis = state.sim.modes().expect("the modes of a joint tree with a bead beside it");
    assert_eq!(analysis.modes.len(), 4);
    for (mode, w) in analysis.modes.iter().zip(want) {
        assert!((mode.omega_squared - w).abs() <= 1e-7 * w, "omega^2 {} against {w}", mode.omega_squared);
    }
}
