//! `tensegrity certify`: proofs of a settled equilibrium's existence, uniqueness and
//! stability (`certify`), on structures whose equilibria are known in closed form, and cases
//! where a proof must shrink or fail.

use std::path::Path;
use tensegrity_testbed::certify::{certify, Stability};
use tensegrity_testbed::scenario;

/// A bead between two springs of rest length l0 = a (1 + eps) whose anchors are 2 a apart on
/// the x axis, and two springs of rest length c from anchors at z = +-c: the springs along x are
/// compressed, so the bead buckles off the axis. Its equilibria in the plane z = 0 are y = 0
/// (unstable: the compression pushes it off) and y = +-y* (stable), y* the root of
/// 2 - l0 / sqrt(a^2 + y^2) - c / sqrt(c^2 + y^2) = 0 ([`buckled_y`]): y* from 0 and 2 y*
/// apart.
fn buckled_bead(eps: f64, start_y: &str) -> String {
    format!(
        r#"
name = "bead between two compressed springs"
mechanism = "custom"

[params]
a = {{ value = 1.0, unit = "m" }}
eps = {{ value = {eps:e}, unit = "-" }}
l0 = {{ value = "a*(1 + eps)", unit = "m" }}
h = {{ value = "sqrt(l0^2 - a^2)", unit = "m" }}
c = {{ value = 0.5, unit = "m" }}
k = {{ value = 100.0, unit = "N/m" }}

[sim]
dt = 0.001
body_damping = 5.0

[settle]
speed_tol = 1e-13
window = 10
residual_force_tol = 1e-11
residual_torque_tol = 1e-11

[actuation]
points = [ {{}} ]

[structure]
gravity = [0, 0, 0]

[[structure.bodies]]
name = "ground"
fixed = true
nodes = {{ L = ["-a", 0, 0], R = ["a", 0, 0], U = [0, 0, "c"], D = [0, 0, "-c"] }}

[[structure.bodies]]
name = "bead"
mass = 1.0
nodes = {{ B = [0, "{start_y}", 0] }}

[[structure.springs]]
name = "left"
a = "L"
b = "B"
stiffness = "k"
length = "l0"

[[structure.springs]]
name = "right"
a = "R"
b = "B"
stiffness = "k"
length = "l0"

[[structure.springs]]
name = "up"
a = "U"
b = "B"
stiffness = "k"
length = "c"

[[structure.springs]]
name = "down"
a = "D"
b = "B"
stiffness = "k"
length = "c"
"#
    )
}

/// y* of [`buckled_bead`] (a = 1, c = 0.5) by bisection on (0, 1): the y-force's factor
/// 2 - l0 / s - c / r is negative near 0 and positive at 1.
fn buckled_y(eps: f64) -> f64 {
    let (a, c, l0) = (1.0_f64, 0.5_f64, 1.0 + eps);
    let g = |y: f64| 2.0 - l0 / (a * a + y * y).sqrt() - c / (c * c + y * y).sqrt();
    let (mut lo, mut hi) = (1e-9, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The settled state of a scenario's text, as equations to prove.
fn settled_problem(text: &str) -> tensegrity_testbed::certify::Problem {
    let sc = scenario::parse(Path::new("bead.toml"), text).expect("valid");
    let (sc, inputs) = tensegrity_testbed::study::sensitivity_point_of(&sc, 0).expect("a point");
    let state = tensegrity_testbed::run::settle_at(sc, &inputs, sc.params_at(&inputs), None).expect("settles");
    assert!(state.settled, "settled");
    state.sim.equilibrium_problem().expect("certifiable")
}

/// Settled near y = +y*, the bead's equilibrium is proven unique in a box that holds neither
/// the unstable one (y* away) nor the other stable one (2 y* away): its radius stays below y*,
/// at eps = 1e-4 (y* = 6.3e-3 m) and at eps = 1e-8 (y* = 6.3e-5 m), where the equilibria are
/// 100 times closer; the equilibrium is proven stable and the settled y is y* within 1e-12 m
/// plus the distance the certificate bounds.
#[test]
fn a_proof_never_holds_a_neighbouring_equilibrium() {
    for eps in [1e-4_f64, 1e-8] {
        let h = buckled_y(eps);
        let problem = settled_problem(&buckled_bead(eps, &format!("{:e}", 1.01 * h)));
        let certificate = certify(&problem);
        let proof = certificate.proof.unwrap_or_else(|| panic!("eps {eps}: {:?}", certificate.reason));
        assert!(proof.radius_m < h, "eps {eps}: a box of {} m around y = h holds y = 0 ({h} m away)", proof.radius_m);
        // The proof shrinks with the stiffness across (about y*^2): 4.9e-3 of y* at eps = 1e-4,
        // 5.2e-5 at 1e-8; the box is still wider than the equilibrium's enclosure.
        assert!(proof.radius_m > proof.enclosure_radius_m, "eps {eps}: a box of {} m", proof.radius_m);
        assert!(matches!(proof.stability, Stability::Stable { .. }), "eps {eps}: {:?}", proof.stability);
        let tensegrity_testbed::certify::Node::OnBlock { block, arm } = &problem.nodes[4] else { panic!("B moves") };
        let y = problem.blocks[*block].com[1] + arm[1];
        assert!((y - h).abs() <= 1e-12 + proof.settled_offset_m, "eps {eps}: settled y {y} against h {h}");
    }
}

/// Drawn at y = 0, where the compressed springs balance, the bead stays: that equilibrium is
/// proven, and proven unstable with one negative eigenvalue (the buckling direction), in a box
/// smaller than y*.
#[test]
fn the_unstable_equilibrium_is_proven_unstable() {
    let eps = 1e-4_f64;
    let h = buckled_y(eps);
    let certificate = certify(&settled_problem(&buckled_bead(eps, "0")));
    let proof = certificate.proof.unwrap_or_else(|| panic!("{:?}", certificate.reason));
    assert_eq!(proof.stability, Stability::Unstable { index: 1 });
    assert!(proof.radius_m < h, "{} m", proof.radius_m);
}

/// A state moved 1e-6 m off the equilibrium is no equilibrium: moved along x (where the
/// springs hold it at 200 N/m), no box of radius 1e-7 m around it holds one (the force's
/// enclosure there excludes 0); moved along y (the soft buckling direction), the certificate
/// puts it at least 1e-6 m (less its enclosure's width) from the equilibrium it proves.
#[test]
fn a_state_moved_off_the_equilibrium_is_not_certified_as_one() {
    let settled = settled_problem(&buckled_bead(1e-4, &format!("{:e}", 1.01 * buckled_y(1e-4))));
    for (axis, along) in [(0, "x"), (1, "y")] {
        let mut problem = settled.clone();
        problem.blocks[0].com[axis] += 1e-6;
        if along == "x" {
            assert!(tensegrity_testbed::certify::excludes_equilibrium(&problem, 1e-7), "a box of 1e-7 m around it");
        }
        let proof = certify(&problem).proof.expect("the equilibrium beside it is proven");
        let least = 1e-6 - proof.enclosure_radius_m - 1e-12;
        assert!(proof.settled_offset_m >= least, "moved along {along}: offset {}", proof.settled_offset_m);
    }
}

/// The shipped prism and icosahedron, held by a strut (a free turn about its line: the gauge
/// holds one coordinate), are proven unique, stable, and their settled states within 1e-11 m
/// of the equilibrium; the command exits 0 and refuses a jointed structure and a motion with
/// exit 2.
#[test]
fn the_shipped_free_body_structures_are_certified_and_the_rest_refused() {
    for file in
        ["scenarios/custom/prism3.toml", "scenarios/custom/icosahedron6.toml", "scenarios/custom/prism3_elastic.toml"]
    {
        let (code, out, err) = crate::common::tensegrity(&["certify", file, "--json", "-"]);
        assert_eq!(code, 0, "{file}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
        let proof = &v["certificate"]["proof"];
        assert!(proof["settled_offset_m"].as_f64().unwrap() <= 1e-11, "{file}: {proof}");
        assert_eq!(proof["stability"]["kind"], "stable", "{file}");
        assert!(proof["stability"]["smallest_eigenvalue_at_least_n_per_m"].as_f64().unwrap() > 0.1, "{file}");
    }
    let (code, _, err) = crate::common::tensegrity(&["certify", "scenarios/custom/pendulum_tip_load.toml"]);
    assert!(code == 2 && err.contains("joint 'pin'"), "{err}");
    let (code, _, err) = crate::common::tensegrity(&["certify", "scenarios/custom/pinned_prism_mechanism.toml"]);
    assert!(code == 2 && err.contains("a motion has no settled equilibrium"), "{err}");
}

/// `run --certify` certifies every settle point: each of the ten points of the prism family
/// (n = 3 to 12, each structure rebuilt) carries a certificate in its point report, proven
/// stable up to the free turn, the settled state within 1e-11 m of the equilibrium; a run
/// without the flag has none (the reports as before); the flag on a jointed structure exits 2.
#[test]
fn run_certify_puts_a_certificate_at_every_settle_point() {
    let (code, out, err) =
        crate::common::tensegrity(&["run", "scenarios/custom/prism_n.toml", "--certify", "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    let points = v["scenarios"][0]["points"].as_array().expect("points");
    assert_eq!(points.len(), 10);
    for p in points {
        let proof = &p["certificate"]["proof"];
        assert_eq!(proof["stability"]["kind"], "stable", "point {}", p["index"]);
        assert!(proof["settled_offset_m"].as_f64().unwrap() <= 1e-11, "point {}: {proof}", p["index"]);
        assert!(proof["held_coordinate"].is_string(), "point {}", p["index"]);
    }
    let (_, plain, _) = crate::common::tensegrity(&["run", "scenarios/custom/prism3.toml", "--json", "-"]);
    assert!(!plain.contains("\"certificate\""), "no certificate without the flag");
    let (code, _, err) = crate::common::tensegrity(&["run", "scenarios/custom/pendulum_tip_load.toml", "--certify"]);
    assert!(code == 2 && err.contains("--certify") && err.contains("joint 'pin'"), "{err}");
}

/// A file's `[certify]` section certifies its run's settle points as `--certify` does, and
/// `sweep --certify` writes each point's proof in the CSV (`certified_radius_m`,
/// `certified_offset_m`, `certified_stability`, `certified_smallest_eigenvalue_n_per_m`,
/// `certified_index`): every point of prism_n stable, its bound above 0.1 N/m. `[certify]` in a
/// motion is refused at its line (exit 2).
#[test]
fn a_certify_section_and_sweep_certify_prove_every_point() {
    let dir = std::env::temp_dir().join(format!("certify-section-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let with_section = |file: &str| {
        let path = dir.join(Path::new(file).file_name().unwrap());
        std::fs::write(&path, std::fs::read_to_string(file).unwrap() + "\n[certify]\n").unwrap();
        path.display().to_string()
    };
    let prism = with_section("scenarios/custom/prism3.toml");
    let (code, out, err) = crate::common::tensegrity(&["run", &prism, "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["scenarios"][0]["points"][0]["certificate"]["proof"]["stability"]["kind"], "stable");
    let (code, csv, err) =
        crate::common::tensegrity(&["sweep", "scenarios/custom/prism_n.toml", "--certify", "--out", "-"]);
    assert_eq!(code, 0, "{err}");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("{name}"));
    let (kind, bound) = (column("certified_stability"), column("certified_smallest_eigenvalue_n_per_m"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 10);
    for r in &rows {
        assert_eq!(r[kind], "stable");
        assert!(r[bound].parse::<f64>().unwrap() > 0.1, "{}", r[bound]);
    }
    let motion = with_section("scenarios/custom/pinned_prism_mechanism.toml");
    let (code, _, err) = crate::common::tensegrity(&["check", &motion]);
    assert!(code == 2 && err.contains("[certify] in a motion"), "{err}");
    let line = std::fs::read_to_string(&motion).unwrap().lines().count();
    assert!(err.contains(&format!(":{line}:1:")), "located at the section's line {line}: {err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The file's model judged against the proven equilibrium: the buckled bead's y* (from
/// [`buckled_y`], to about 1e-15 m) lies inside the equilibrium's enclosure, which a run with
/// `[certify]` reports as proven; the same model moved by 1e-6 m lies outside it, reported with
/// its distance (1e-6 m less the enclosure's width, within 1e-9 m).
#[test]
fn a_model_inside_the_enclosure_is_proven_and_one_moved_1e_6_is_not() {
    let eps = 1e-4;
    let h = buckled_y(eps);
    for (offset, inside) in [(0.0, true), (1e-6, false)] {
        let text = format!(
            "{}\n[[predictions]]\nquantity = \"B.y\"\nformula = \"{:e}\"\nclass = \"length\"\ntolerance = 1e-5\n\n[certify]\n",
            buckled_bead(eps, &format!("{:e}", 1.01 * h)),
            h + offset
        );
        let sc = scenario::parse(Path::new("bead.toml"), &text).expect("valid");
        let r = tensegrity_testbed::run::run(&sc, &tensegrity_testbed::run::RunOptions::default());
        let proof = r.points[0].certificate.as_ref().and_then(|c| c.proof.as_ref()).expect("proven");
        let model = proof.model.as_ref().expect("the model's node coordinate judged");
        if inside {
            assert_eq!((model.inside, model.outside.len()), (1, 0), "{model:?}");
        } else {
            assert_eq!(model.outside, vec!["B.y".to_string()]);
            assert!((model.largest_outside_m - 1e-6).abs() <= 1e-9, "{}", model.largest_outside_m);
        }
    }
}
