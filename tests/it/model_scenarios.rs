//! A researcher's own model in the scenario file: `[params]` expressions in a custom structure,
//! `[[quantities]]`, `[[predictions]]` and `[[equations]]`, judged by the run; errors inside an
//! expression located at `file:LINE:COL` inside the string.

use crate::common;

use common::{error_at, run_file, tensegrity};
use std::path::Path;
use tensegrity_testbed::report::verdict::Failure;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

const PRISM: &str = "scenarios/custom/prism3_model.toml";

fn prism_text() -> String {
    std::fs::read_to_string(PRISM).unwrap()
}

/// The structure's numbers are the parameters' expressions evaluated: node T2 of the prism lies
/// at r (cos, sin)(2 pi/3 + 130 deg), h (within 1e-15 m), and the cables have k = 100 N/m.
#[test]
fn parameter_expressions_place_the_nodes() {
    let sc = scenario::load(Path::new(PRISM)).unwrap();
    let s = &sc.custom.as_ref().unwrap().structure;
    let t2 = s.nodes[s.node_id("T2").unwrap()].position;
    let a = 2.0 * std::f64::consts::PI / 3.0 + 130f64.to_radians();
    let want = [a.cos(), a.sin(), 1.5];
    for k in 0..3 {
        assert!((t2[k] - want[k]).abs() <= 1e-15, "T2 {t2:?} != {want:?}");
    }
    assert!((sc.params["twist0"] - 130f64.to_radians()).abs() <= 1e-15);
    assert!((sc.params["step"] - 2.0 * std::f64::consts::PI / 3.0).abs() <= 1e-15);
    assert_eq!(s.member("top23").unwrap().rest_length_m(), Some(1.5));
}

/// A built-in mechanism's parameters may be expressions of each other (ji2014: K2 = K1/2).
#[test]
fn builtin_parameters_may_be_expressions() {
    let text = std::fs::read_to_string("scenarios/ji2014/quick.toml").unwrap();
    let text = text.replacen("K2 = 100.0", "K2 = \"K1/2\"", 1);
    let sc = scenario::parse(Path::new("quick.toml"), &text).unwrap();
    assert_eq!(sc.params["K2"], 100.0);
    let bad = text.replacen("K1 = 200.0", "K1 = { value = 200.0, unit = \"N/mm\" }", 1);
    error_at(&bad, "{ value = 200.0", 0, "parameter 'K1' is in N/m");
}

/// Errors in parameter and structure expressions are at their place inside the string.
#[test]
fn parameter_errors_are_located_inside_the_string() {
    let good = prism_text();
    let cyc = good.replacen("r = { value = 1.0", "r = { value = \"h/step\"", 1).replacen(
        "value = \"2*pi/n\"",
        "value = \"2*pi/n*r\"",
        1,
    );
    error_at(&cyc, "\"h/step\"", 0, "parameter 'r' depends on itself");
    let unknown = good.replacen("value = \"130*pi/180\"", "value = \"130*pi/180*q\"", 1);
    error_at(&unknown, "130*pi/180*q", 11, "parameter 'twist0': unknown symbol 'q' (symbols here: h, k, l_poly");
    let node = good.replacen("\"r*sin(step)\"", "\"r*sine(step)\"", 1);
    error_at(&node, "r*sine(step)", 2, "a coordinate of node 'B2': unknown function 'sine'");
    let joint = std::fs::read_to_string("scenarios/custom/ji2014_in_file.toml").unwrap();
    let axis = joint.replacen("\"sin(theta1_0)\"", "\"sin(theta1_00)\"", 1);
    error_at(&axis, "theta1_00", 0, "axis: unknown symbol 'theta1_00'");
    let inertia = joint.replacen("\"m_platform*L^2/3\"", "\"m_platform*L^2/3/M\"", 1);
    error_at(&inertia, "M\"]", 0, "inertia: unknown symbol 'M'");
    let stiff = good.replacen("stiffness = \"k\"", "stiffness = \"k*\"", 1);
    assert!(scenario::parse(Path::new("v.toml"), &stiff).unwrap_err().message.contains("stiffness"));
}

/// Errors in quantities, predictions and equations are at their place inside the string and
/// say what exists there.
#[test]
fn model_errors_are_located_inside_the_string() {
    let good = prism_text();
    let q = good.replacen("(B1.x + B2.x + B3.x)/3", "(B1.x + B2.x + B4.x)/3", 1);
    error_at(&q, "B4.x", 0, "quantity 'cb_x': unknown symbol 'B4.x' (symbols here: B1.x, B1.y");
    // A prediction's formula sees the parameters and inputs only.
    let p = good.replacen("formula = \"pi/2 + pi/n\"", "formula = \"pi/2 + pi/n + 0*T1.x\"", 1);
    error_at(
        &p,
        "T1.x\"",
        0,
        "prediction 'twist' (parameters, inputs and their quantities only): unknown symbol 'T1.x'",
    );
    // ... and a quantity of the state is not a closed form either.
    let p = good.replacen("formula = \"pi/2 + pi/n\"", "formula = \"pi/2 + pi/n + 0*q_side\"", 1);
    error_at(&p, "0*q_side", 2, "unknown symbol 'q_side'");
    let multi = good.replacen("u_z*w_x - u_x*w_z", "u_z*w_x - u_x*wz", 1);
    error_at(&multi, "wz)", 0, "unknown symbol 'wz'");
    let class = good.replacen("class = \"angle\"", "class = \"degrees\"", 1);
    error_at(&class, "\"degrees\"", 0, "unknown class 'degrees' (expected one of: length, angle, relative)");
    let unknown = good.replacen("quantity = \"twist\"", "quantity = \"twirl\"", 1);
    error_at(&unknown, "\"twirl\"", 0, "unknown quantity 'twirl'");
    let eq = good.replacen("abs(top12.force - top23.force)", "abs(top12.force - top24.force)", 1);
    error_at(&eq, "top24.force", 0, "equation 'equal_top_tensions': unknown symbol 'top24.force'");
    let clash = good.replacen("name = \"q_side\"", "name = \"k\"", 1);
    error_at(&clash, "\"k\"\nexpr", 0, "duplicate name 'k': this quantity and the parameter at");
}

/// The prism settles on the closed form stated in its file: twist pi/2 + pi/n, force densities
/// strut : side = -1 and polygon : side = 1/(2 sin(pi/n)), each within its 1e-9; the equal
/// tensions within 1e-7 N; the quantities are in the point's simulated values.
#[test]
fn the_prism_model_in_the_file_passes() {
    let r = run_file(PRISM);
    assert!(r.passed, "{:?} {:?}", r.failures, r.error);
    assert_eq!(r.model_checks.len(), 5);
    for c in &r.model_checks {
        assert!(c.passed && c.max_error <= c.tolerance, "{c:?}");
        assert_eq!(c.points_compared, 1);
        assert!(c.ticks_compared >= 10, "{c:?}");
    }
    let p = &r.points[0];
    let twist = p.simulated["twist"];
    let want = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / 3.0;
    assert!((twist - want).abs() <= 1e-9, "twist {twist}");
    assert!((p.analytic["twist"] - want).abs() <= 1e-15);
    assert!((p.simulated["polygon_to_side"] - 1.0 / 3f64.sqrt()).abs() <= 1e-9);
    // The drawn twist is 130 degrees, 20 short; the first tick comes after the static
    // relaxation's first step, which has already closed most of that (0.054 rad left).
    let tw = r.model_checks.iter().find(|c| c.name == "twist").unwrap();
    assert!(tw.transient_max_error > 1e-3 && tw.transient_max_error < 20f64.to_radians(), "{tw:?}");
}

/// A prediction that does not hold fails the run as `prediction:NAME`, and an equation that
/// does not vanish as `equation:NAME`; `[expect]` can declare both.
#[test]
fn a_wrong_prediction_fails_the_run_by_name() {
    let text = prism_text()
        .replacen("formula = \"pi/2 + pi/n\"", "formula = \"pi/2 + pi/(n+1)\"", 1)
        .replacen("residual = \"max(abs(side1.force", "residual = \"1e-6 + max(abs(side1.force", 1)
        .replacen(
            "verdict = \"pass\"",
            "verdict = \"fail\"\nfailing = [\"prediction:twist\", \"equation:equal_side_tensions\"]",
            1,
        );
    let sc = scenario::parse(Path::new("wrong.toml"), &text).unwrap();
    let r = run(&sc, &RunOptions::default());
    assert!(!r.passed);
    assert_eq!(r.failures, vec![Failure::Prediction("twist".into()), Failure::Equation("equal_side_tensions".into())]);
    assert_eq!(r.as_expected, Some(true));
    let tw = r.model_checks.iter().find(|c| c.name == "twist").unwrap();
    // pi/3 - pi/4 = 15 degrees off.
    assert!((tw.max_error - 15f64.to_radians()).abs() <= 1e-9, "{tw:?}");
}

/// `tensegrity list FILE` lists a custom file's own parameters with their values and units,
/// and the symbols its model may use.
#[test]
fn list_names_a_files_parameters_and_symbols() {
    let (code, out, err) = tensegrity(&["list", PRISM]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("twist0       [rad] default 2.2689280275926285"), "{out}");
    assert!(out.contains("    step         = 2.0943951023931953"), "{out}");
    assert!(out.contains("model symbols"), "{out}");
    assert!(out.contains(" side1.length ") && out.contains(" strut2.force ") && out.contains(" twist"), "{out}");
}

/// The tutorial's file (a pinned bar between two zero-length springs), as the README's first
/// steps and the full chapter `docs/tutorial-static.md` both show it: the two copies are the
/// same text, and it settles at the energy minimum q = atan2(k1 a, k2 b) within 1e-9 rad with
/// the moment about the pin vanishing within 1e-9 N m.
#[test]
fn the_readme_tutorial_model_passes() {
    let mut copies = Vec::new();
    for file in ["README.md", "docs/tutorial-static.md"] {
        let doc = std::fs::read_to_string(file).unwrap();
        let start =
            doc.find("name = \"pinned bar between two springs\"").unwrap_or_else(|| panic!("tutorial in {file}"));
        copies.push((file, doc[start..start + doc[start..].find("```").unwrap()].to_string()));
    }
    assert_eq!(copies[0].1, copies[1].1, "the README's tutorial file and the chapter's differ");
    let (file, text) = &copies[0];
    let sc = scenario::parse(Path::new(file), text).expect("the tutorial parses");
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?} {:?} {:?}", r.failures, r.error, r.model_checks);
    let q = r.points[0].simulated["q"];
    let want = (50.0f64 * 0.8).atan2(30.0 * 0.6);
    assert!((q - want).abs() <= 1e-9, "q {q} != {want}");
    let moment = r.model_checks.iter().find(|c| c.name == "moment").unwrap();
    assert!(moment.max_error <= 1e-9, "{moment:?}");
}

/// ji2014's equations written in the file (Eq. 4-7 as quantities and predictions, Eq. 48 as an
/// implicit equation) hold on the 110-point grid as the built-in model does: Eq. 5's stable
/// root within 1e-12 rad of the settled theta2 at every point, which lies within 1e-9 rad of
/// the built-in model's; Eq. 48's residual below 1e-8 N; Eq. 4 within 1e-9 J of the springs'
/// energy.
#[test]
fn ji2014_restated_in_the_file_agrees_with_the_builtin_model() {
    let r = run_file("scenarios/ji2014/model_in_file.toml");
    assert!(r.passed, "{:?} {:?}", r.failures, r.error);
    assert_eq!(r.points.len(), 110);
    let get = |n: &str| r.model_checks.iter().find(|c| c.name == n).unwrap();
    assert!(get("eq5_stable_root").max_error <= 1e-12, "{:?}", get("eq5_stable_root"));
    assert!(get("energy_minimum").max_error <= 1e-12, "{:?}", get("energy_minimum"));
    assert!(get("eq48").max_error <= 1e-8 && get("eq4").max_error <= 1e-9);
    for p in &r.points {
        let (sim, builtin) = (p.simulated["theta2"], p.analytic["theta2"]);
        let d = tensegrity_testbed::mechanisms::wrap_angle(sim - builtin).abs();
        assert!(d <= 1e-9, "point {}: {sim} against the built-in {builtin}", p.index);
    }
}

/// Eq. 4 as the file's energy model on the ji2014 grid: two stationary points at each of the
/// 110 points, pi apart, a minimum and a maximum; the dynamics landed on the minimum within
/// 1e-12 rad; its Hessian (the stiffness) is Eq. 42's L |eta| / 2 within 1e-12 relative; and
/// Eq. 5's root in [0, pi) is the energy maximum exactly where the built-in model says the
/// minimum is the other root (103 of 110 points).
#[test]
fn ji2014_energy_in_the_file_finds_and_classifies_both_equilibria() {
    let r = run_file("scenarios/ji2014/model_in_file.toml");
    assert!(r.passed, "{:?}", r.failures);
    let sqrt3 = 3f64.sqrt();
    let (l, k1, k2) = (1.0, 200.0, 100.0);
    let mut paper_root_is_max = 0;
    for p in &r.points {
        let e = p.energy.as_ref().expect("energy at every point");
        assert_eq!(e.stationary.len(), 2, "point {}", p.index);
        assert!(e.distance <= 1e-12, "point {}: {}", p.index, e.distance);
        let landed = &e.stationary[e.landed.unwrap()];
        assert_eq!(landed.kind, "minimum");
        let (l3, t1) = (p.inputs["L3"], p.inputs["theta1"]);
        let eta1 = (k1 + 2.0 * k2) * l3 * t1.sin() - sqrt3 * k1 * l3 * t1.cos() + 2.0 * sqrt3 * k2 * l;
        let eta2 = 2.0 * (2.0 * k1 - k2) * l + (k1 + 2.0 * k2) * l3 * t1.cos() + sqrt3 * k1 * l3 * t1.sin();
        let k = l / 2.0 * eta1.hypot(eta2);
        assert!((landed.eigenvalues[0] - k).abs() <= 1e-12 * k, "point {}: {:?} != {k}", p.index, landed.eigenvalues);
        let gap = tensegrity_testbed::mechanisms::wrap_angle(
            e.stationary[0].coordinates["th"] - e.stationary[1].coordinates["th"],
        );
        assert!((gap.abs() - std::f64::consts::PI).abs() <= 1e-12);
        // Half-open: at L3 = 1, theta1 = 0 the roots are 0 and pi, and Eq. 5 gives 0.
        let paper = e.stationary.iter().find(|s| (0.0..std::f64::consts::PI).contains(&s.coordinates["th"])).unwrap();
        let builtin_says_paper_root_is_min = p.branch.contains("[0, pi]");
        assert_eq!(paper.kind == "minimum", builtin_says_paper_root_is_min, "point {}", p.index);
        paper_root_is_max += (paper.kind == "maximum") as usize;
    }
    assert_eq!(paper_root_is_max, 103);
}

/// `[energy]` errors: an unknown symbol in the potential (a state symbol is not a closed
/// form), a potential without a symbolic derivative, a coordinate named like a symbol, at
/// their place in the file.
#[test]
fn energy_errors_are_located() {
    let good = std::fs::read_to_string("scenarios/ji2014/model_in_file.toml").unwrap();
    let v = good.replacen("\"u0 + a*cos(th) + b*sin(th)\"", "\"u0 + a*cos(th) + b*sin(th) + x\"", 1);
    error_at(
        &v,
        "x\"\ntolerance",
        0,
        "energy potential (coordinates, parameters, inputs, their quantities, fixed nodes): unknown symbol 'x'",
    );
    let n = good.replacen("name = \"th\"", "name = \"theta2\"", 1);
    error_at(&n, "\"theta2\"\nmeasured", 0, "coordinate name 'theta2' is already a symbol of this scenario");
    let m = good.replacen("measured = \"theta2\"", "measured = \"theta3\"", 1);
    error_at(&m, "theta3", 0, "coordinate 'th' measured: unknown symbol 'theta3'");
}

/// ji2014 described as a custom structure (`scenarios/custom/ji2014_in_file.toml`) settles the
/// 110-point grid exactly as the built-in mechanism (grid.toml): the same steps at every
/// point, theta2 and D3 within 1e-12, the same stability by perturbation.
#[test]
fn ji2014_as_a_custom_structure_matches_the_builtin_grid() {
    let custom = run_file("scenarios/custom/ji2014_in_file.toml");
    let builtin = run_file("scenarios/ji2014/grid.toml");
    assert!(custom.passed && builtin.passed, "{:?}", custom.failures);
    assert_eq!(custom.points.len(), 110);
    for (c, b) in custom.points.iter().zip(&builtin.points) {
        assert_eq!(c.inputs, b.inputs);
        assert_eq!(c.steps, b.steps, "point {}", c.index);
        assert_eq!(c.stable, b.stable, "point {}", c.index);
        let d = tensegrity_testbed::mechanisms::wrap_angle(c.simulated["theta2"] - b.simulated["theta2"]);
        assert!(d.abs() <= 1e-12, "point {}: {d}", c.index);
        assert!((c.simulated["D3.x"] - b.simulated["x"]).abs() <= 1e-12);
        assert!((c.simulated["D3.y"] - b.simulated["y"]).abs() <= 1e-12);
    }
}

/// The custom ji2014 along the waypoints of scenarios/ji2014/trajectory.toml, drawn at the
/// first waypoint's stable equilibrium (theta2_0 a parameter expression of Eq. 6-7): its
/// prediction of theta2 compared tick by tick gives the same transient errors as the built-in
/// check of theta2 (within 1e-9 rad), and the final hold settles within 1e-9.
#[test]
fn ji2014_custom_trajectory_is_compared_tick_by_tick() {
    let text = std::fs::read_to_string("scenarios/custom/ji2014_in_file.toml").unwrap();
    let grid_line = text.lines().find(|l| l.starts_with("grid = ")).unwrap().to_string();
    let text = text
        .replacen(&grid_line, "waypoints = [ { t = 0.0, L3 = 1.0, theta1 = 0.3 }, { t = 4.0, L3 = 1.8, theta1 = 1.2 }, { t = 10.0, L3 = 0.6, theta1 = 2.6 } ]", 1)
        .replacen("continuation = true\n", "", 1)
        .replacen("[stability]\nperturbation = 1e-3  # rad on theta2\nexpect = \"stable\"", "#", 1)
        .replacen("dt = 0.15\nnewton_damping = true", "dt = 0.005\nnewton_damping = false", 1)
        .replacen("window = 3\nresidual_torque_tol = 1e-7\nmax_time = 30.0", "", 1)
        // The hold settles to the default residual torque (1e-7 N m): Eq. 48's residual is
        // 2 tau / L there.
        .replacen("tolerance = 1e-8", "tolerance = 1e-6", 1)
        // trajectory.toml keeps the mechanism's default pivot damping.
        .replacen("c_D1 = { value = 80.0,", "c_D1 = { value = 20.0,", 1)
        .replacen("value = 0.0, unit = \"rad\", description = \"drawn actuator angle", "value = 0.3, unit = \"rad\", description = \"drawn actuator angle", 1)
        .replacen(
            "theta2_0 = { value = -2.5,",
            "eta1_0 = \"(K1 + 2*K2)*L3_0*sin(theta1_0) - sqrt(3)*K1*L3_0*cos(theta1_0) + 2*sqrt(3)*K2*L\"\n\
             eta2_0 = \"2*(2*K1 - K2)*L + (K1 + 2*K2)*L3_0*cos(theta1_0) + sqrt(3)*K1*L3_0*sin(theta1_0)\"\n\
             theta2_0 = { value = \"atan2(-eta1_0, -eta2_0)\",",
            1,
        );
    let sc = scenario::parse(Path::new("ji2014_trajectory_variant.toml"), &text).expect("variant parses");
    let custom = run(&sc, &RunOptions::default());
    let builtin = run_file("scenarios/ji2014/trajectory.toml");
    assert!(custom.passed && builtin.passed, "{:?} {:?}", custom.failures, custom.error);
    let pred = custom.model_checks.iter().find(|c| c.name == "eq5_stable_root").unwrap();
    let check = builtin.checks.iter().find(|c| c.quantity == "theta2").unwrap();
    assert_eq!(pred.ticks_compared, check.ticks_compared);
    assert!(pred.transient_max_error > 1e-3, "the platform lags the moving equilibrium: {pred:?}");
    assert!((pred.transient_max_error - check.transient_max_abs_error).abs() <= 1e-9, "{pred:?} {check:?}");
    assert!((pred.transient_rms_error - check.transient_rms_abs_error).abs() <= 1e-9, "{pred:?} {check:?}");
    assert!(pred.max_error <= 1e-9);
}

/// mohr2011's DKP (Eq. 12-14), IKP (Eq. 15) and tensions (Eq. 26-28 with Eq. 5 at Eq. 16's
/// lengths) written in the file hold at quick.toml's three points within 1e-12 (m, or
/// relative for the tensions).
#[test]
fn mohr2011_restated_in_the_file_holds() {
    let r = run_file("scenarios/mohr2011/model_in_file.toml");
    assert!(r.passed, "{:?} {:?}", r.failures, r.error);
    assert_eq!(r.model_checks.len(), 10);
    for c in &r.model_checks {
        assert_eq!(c.points_compared, 3, "{c:?}");
        assert!(c.max_error <= 1e-12, "{c:?}");
    }
}

/// Joint coordinates are symbols: on the custom ji2014 grid the actuated joints' coordinates
/// equal the commands (theta1.angle = theta1, L3.slide = L3, within 1e-9) and the pivot's
/// angle is theta2 - theta1 (the rod turns with theta1; within 1e-9 rad), at every point.
#[test]
fn joint_coordinates_are_symbols() {
    let text = std::fs::read_to_string("scenarios/custom/ji2014_in_file.toml").unwrap().replacen(
        "[energy]",
        "[[equations]]\nname = \"theta1_joint\"\nresidual = \"theta1.angle - theta1\"\ntolerance = 1e-9\n\n\
         [[equations]]\nname = \"L3_joint\"\nresidual = \"L3.slide - L3\"\ntolerance = 1e-9\n\n\
         [[equations]]\nname = \"pivot\"\nresidual = \"sin(D1.angle - (theta2 - theta1))\"\ntolerance = 1e-9\n\n\
         [energy]",
        1,
    );
    let sc = scenario::parse(Path::new("joints.toml"), &text).expect("variant parses");
    let r = run(&sc, &RunOptions::default());
    assert!(r.passed, "{:?} {:?}", r.failures, r.model_checks);
    for name in ["theta1_joint", "L3_joint", "pivot"] {
        let c = r.model_checks.iter().find(|c| c.name == name).unwrap();
        assert_eq!(c.points_compared, 110);
        assert!(c.max_error <= 1e-9, "{c:?}");
    }
    let (code, out, _) = tensegrity(&["list", "scenarios/custom/ji2014_in_file.toml"]);
    assert_eq!(code, 0);
    assert!(out.contains(" theta1.angle ") && out.contains(" L3.slide ") && out.contains(" D1.angle "), "{out}");
}

/// A recorded run of the prism holds each prediction's and equation's error per tick as a
/// series `model/NAME` at every tick of the run.
#[test]
fn a_recorded_run_holds_the_model_errors_per_tick() {
    let sc = scenario::load(Path::new(PRISM)).unwrap();
    let path = std::env::temp_dir().join(format!("tensegrity-model-{}.rrd", std::process::id()));
    let r = run(&sc, &RunOptions { record: Some(path.clone()), ..RunOptions::default() });
    assert!(r.passed, "{:?}", r.error);
    let file = std::io::BufReader::new(std::fs::File::open(&path).expect("recording exists"));
    let mut ticks: std::collections::BTreeMap<String, std::collections::BTreeSet<i64>> = Default::default();
    for msg in re_log_encoding::Decoder::<re_log_types::LogMsg>::decode_lazy(file) {
        if let re_log_types::LogMsg::ArrowMsg(store, arrow) = msg.expect("decodes") {
            let chunk = re_chunk::Chunk::from_arrow_msg(&arrow).expect("a chunk");
            let name = chunk.entity_path().to_string();
            if store.kind() == re_log_types::StoreKind::Recording && name.starts_with("/model/") {
                let col = chunk.timelines().iter().find(|(n, _)| n.as_str() == "tick").map(|(_, c)| c).unwrap();
                ticks.entry(name).or_default().extend(col.times_raw().iter().copied());
            }
        }
    }
    std::fs::remove_file(&path).ok();
    let names: Vec<&str> = ticks.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "/model/equal_side_tensions",
            "/model/equal_top_tensions",
            "/model/polygon_to_side",
            "/model/strut_to_side",
            "/model/twist"
        ]
    );
    for t in ticks.values() {
        assert_eq!(t.len() as u64, r.settle.steps, "a value at every tick");
    }
}

/// `[expect] failing` names parts the scenario has: a prediction or an equation of its own
/// model, `energy` only with an `[energy]` section, `probe` only with a `[probe]`; else the
/// error is at the name and lists what there is.
#[test]
fn expected_failures_name_parts_of_the_file_s_model() {
    let text = prism_text();
    let cases = [
        ("prediction:nope", "'nope' is not among this scenario's [[predictions]] (twist"),
        ("equation:nope", "'nope' is not among this scenario's [[equations]] ("),
        ("energy", "'energy' needs an [energy] section"),
        ("probe", "'probe' needs a [probe] section"),
    ];
    for (name, msg) in cases {
        let variant = text.replacen("verdict = \"pass\"", &format!("verdict = \"fail\"\nfailing = [\"{name}\"]"), 1);
        error_at(&variant, &format!("\"{name}\""), 0, msg);
    }
}
