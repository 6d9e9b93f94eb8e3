//! `tensegrity import matrices`: a structure given by its node matrix N and connectivity
//! matrices C_b, C_s (Skelton and de Oliveira's notation, as TsgFEM and MOTES use it) becomes
//! a scenario that runs and settles to the closed form; malformed matrices are errors at their
//! row.

use crate::common;
use common::tensegrity;
use std::path::{Path, PathBuf};
use tensegrity_testbed::import::matrices::{import, MatrixOptions};
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

type P3 = [f64; 3];

const OPTIONS: MatrixOptions =
    MatrixOptions { bar_mass_kg: 1.0, bar_radius_m: 0.02, string_stiffness_n_per_m: 100.0, string_tension_n: 20.0 };

/// A 3-strut prism drawn untwisted: nodes 1-3 the bottom triangle (radius 1 m), 4-6 the top
/// one 1.5 m above; bars 1-5, 2-6, 3-4; strings: bottom, top, and verticals i to i+3.
fn prism_files(dir: &Path) -> [PathBuf; 3] {
    std::fs::create_dir_all(dir).unwrap();
    let angle = |k: f64| 2.0 * std::f64::consts::PI * k / 3.0;
    let cols: Vec<P3> =
        (0..6).map(|i| [angle(i as f64).cos(), angle(i as f64).sin(), if i < 3 { 0.0 } else { 1.5 }]).collect();
    let n: String =
        (0..3).map(|r| cols.iter().map(|c| format!("{:?}", c[r])).collect::<Vec<_>>().join(", ") + "\n").collect();
    let row = |a: usize, b: usize| {
        (1..=6)
            .map(|k| {
                if k == a {
                    "-1"
                } else if k == b {
                    "1"
                } else {
                    "0"
                }
            })
            .collect::<Vec<_>>()
            .join(",")
            + "\n"
    };
    let cb: String = [(1, 5), (2, 6), (3, 4)].iter().map(|&(a, b)| row(a, b)).collect();
    let cs: String = [(1, 2), (2, 3), (3, 1), (4, 5), (5, 6), (6, 4), (1, 4), (2, 5), (3, 6)]
        .iter()
        .map(|&(a, b)| row(a, b))
        .collect();
    let files = [dir.join("N.csv"), dir.join("Cb.csv"), dir.join("Cs.csv")];
    let texts = [format!("# node matrix, one column per node\n{n}"), format!("# C_b: one row per bar\n\n{cb}"), cs];
    for (f, text) in files.iter().zip(texts) {
        std::fs::write(f, text).unwrap();
    }
    files
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("import-matrices-{name}-{}", std::process::id()))
}

/// The prism from N, C_b, C_s: 3 bars (bar1 held), 9 strings of rest length drawn - 20 / 100 m;
/// it settles with each bar's ends turned by pi/2 + pi/3 about the axis, within 1e-8 rad.
#[test]
fn a_prism_from_connectivity_matrices_settles_to_the_closed_form_twist() {
    let dir = temp("prism");
    let [n, cb, cs] = prism_files(&dir);
    let imported = import(&n, &cb, &cs, &OPTIONS).unwrap();
    let sc =
        scenario::parse(Path::new("prism.toml"), &imported.toml).unwrap_or_else(|e| panic!("{e}\n{}", imported.toml));
    let s = &sc.custom.as_ref().unwrap().structure;
    assert_eq!((s.struts.len(), s.cables.len(), s.bodies.len()), (3, 9, 3));
    assert!(s.bodies[0].inertia.is_none(), "bar1 is held fixed");
    let vertical = s.cables.iter().find(|c| c.name == "string7").unwrap();
    assert!((vertical.length_m - (1.5 - 0.2)).abs() <= 1e-15);
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?}", r.error);
    let sim = &r.points[0].simulated;
    let p = |k: usize| [sim[&format!("n{k}.x")], sim[&format!("n{k}.y")], sim[&format!("n{k}.z")]];
    let centroid = |ks: [usize; 3]| [0, 1, 2].map(|c| ks.iter().map(|&k| p(k)[c]).sum::<f64>() / 3.0);
    let (cb_, ct) = (centroid([1, 2, 3]), centroid([4, 5, 6]));
    let d = [ct[0] - cb_[0], ct[1] - cb_[1], ct[2] - cb_[2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let axis = d.map(|x| x / len);
    let flat = |v: P3, c: P3| {
        let w = [v[0] - c[0], v[1] - c[1], v[2] - c[2]];
        let h = w[0] * axis[0] + w[1] * axis[1] + w[2] * axis[2];
        [w[0] - h * axis[0], w[1] - h * axis[1], w[2] - h * axis[2]]
    };
    let expected = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / 3.0;
    let mut worst = 0.0f64;
    for (a, b) in [(1, 5), (2, 6), (3, 4)] {
        let (u, w) = (flat(p(a), cb_), flat(p(b), ct));
        let cross = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
        let sin = cross[0] * axis[0] + cross[1] * axis[1] + cross[2] * axis[2];
        let cos = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
        worst = worst.max((sin.atan2(cos).abs() - expected).abs());
    }
    eprintln!("matrices prism: twist within {worst:.1e} rad of pi/2 + pi/3");
    assert!(worst <= 1e-8, "{worst}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A node on two bars (class 2), a row without exactly one -1 and one 1, a row with too few
/// columns and a value that is no number are errors naming the file and the row's line
/// (comments and blank lines counted).
#[test]
fn malformed_matrices_are_errors_at_their_row() {
    let dir = temp("bad");
    let [n, cb, cs] = prism_files(&dir);
    let good_cb = std::fs::read_to_string(&cb).unwrap();
    let cases = [
        (&cb, good_cb.replacen("-1,0,0,0,1,0", "-1,0,0,0,0,1", 1), 4, "node 6 is on bars 1 and 2"),
        (&cs, "-1,1,1,0,0,0\n".to_string(), 1, "one -1, one 1 and zeros"),
        (&cs, "-1,1,0,0,0,0\n-1,1,0,0\n".to_string(), 2, "values where the first row has 6"),
        (&n, "1,2,x,4,5,6\n0,0,0,0,0,0\n0,0,0,1,1,1\n".to_string(), 1, "'x' is not a finite number"),
    ];
    for (file, text, line, message) in cases {
        let [n2, cb2, cs2] = prism_files(&dir);
        std::fs::write(file, &text).unwrap();
        let e = import(&n2, &cb2, &cs2, &OPTIONS).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}:{line}:", file.display())), "{e}");
        assert!(e.contains(message), "{e}");
    }
    let _ = n;
    std::fs::remove_dir_all(&dir).ok();
}

/// The command writes a scenario that `check` accepts, and refuses a bad option with exit 2.
#[test]
fn the_matrices_command_writes_a_scenario_that_checks() {
    let dir = temp("cli");
    let [n, cb, cs] = prism_files(&dir);
    let out = dir.join("prism.toml");
    let args = |extra: &[&str]| {
        let mut a = vec!["import", "matrices", n.to_str().unwrap(), cb.to_str().unwrap(), cs.to_str().unwrap()];
        a.extend_from_slice(extra);
        a.into_iter().map(str::to_string).collect::<Vec<_>>()
    };
    let run_with = |extra: &[&str]| {
        let a = args(extra);
        tensegrity(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let (code, _, err) = run_with(&["--out", out.to_str().unwrap(), "--string-stiffness", "200"]);
    assert_eq!(code, 0, "{err}");
    assert!(std::fs::read_to_string(&out).unwrap().contains("stiffness = 200.0"));
    let (code, stdout, err) = tensegrity(&["check", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}{err}");
    let (code, _, err) = run_with(&["--bar-mass=-1"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--bar-mass"), "{err}");
    let (code, _, _) = run_with(&["--out", n.to_str().unwrap()]);
    assert_eq!(code, 2);
    std::fs::remove_dir_all(&dir).ok();
}

/// The README tutorial's pinned bar from arrays (`from_arrays`, the Python package's
/// `from_matrices`): one stiffness per string, zero-free-length springs, a damped revolute pin
/// and a quantity; it settles at q = atan2(k1 a, k2 b) within 1e-15 rad. A property with one
/// value too few is an error naming it.
#[test]
fn the_pinned_bar_from_arrays_settles_at_the_closed_form() {
    use tensegrity_testbed::import::matrices::{from_arrays, MemberProperties, StringRest};
    let (k1, k2, a, b, q0) = (50.0, 30.0, 0.8, 0.6, std::f64::consts::PI / 10.0);
    let n = [vec![0.0, q0.cos(), 0.0, b], vec![0.0, q0.sin(), a, 0.0], vec![0.0; 4]];
    let cb = [vec![-1.0, 1.0, 0.0, 0.0]];
    let cs = [vec![0.0, -1.0, 1.0, 0.0], vec![0.0, -1.0, 0.0, 1.0]];
    let mut p = MemberProperties {
        bar_mass_kg: vec![0.5],
        bar_radius_m: vec![0.01],
        string_stiffness_n_per_m: vec![k1, k2],
        string_rest: StringRest::LengthM(vec![0.0, 0.0]),
        tension_only: vec![false, false],
        pins: vec![("n1".into(), Some([0.0, 0.0, 1.0]))],
        quantities: vec![("q".into(), "atan2(n2.y - n1.y, n2.x - n1.x)".into())],
    };
    let toml = from_arrays("pinned bar", &n, &cb, &cs, &p).unwrap().toml;
    assert!(toml.contains("[[structure.springs]]") && toml.contains("kind = \"revolute\""), "{toml}");
    let sc = scenario::parse(Path::new("bar.toml"), &toml).unwrap_or_else(|e| panic!("{e}\n{toml}"));
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?} {:?}", r.failures, r.error);
    let q = r.points[0].simulated["q"];
    assert!((q - (k1 * a).atan2(k2 * b)).abs() <= 1e-15, "{q}");
    p.string_stiffness_n_per_m.pop();
    let e = from_arrays("pinned bar", &n, &cb, &cs, &p).unwrap_err();
    assert!(e.message.contains("string_stiffness_n_per_m has 1 values: expected 2"), "{e}");
}
