//! `tensegrity sensitivity`: a settled state's derivatives with respect to every parameter by
//! the implicit function theorem (one linear solve on the tangent stiffness), against central
//! differences of full settles (extrapolated over h and 2 h, `--check`) and against closed
//! forms where the file or the paper has one.

use crate::common;
use std::path::Path;
use tensegrity_testbed::mechanisms::Values;
use tensegrity_testbed::report::sensitivity::{ParameterSensitivity, SensitivityReport};
use tensegrity_testbed::scenario;

/// The report of `file` (with its check by differences of settles).
fn report_of(file: &str) -> SensitivityReport {
    let sc = scenario::load(Path::new(file)).expect("shipped scenario");
    tensegrity_testbed::study::sensitivity(&sc, file, 0, true, None).expect("sensitivities")
}

/// Parameter `name`'s row.
fn row<'a>(r: &'a SensitivityReport, name: &str) -> &'a ParameterSensitivity {
    r.parameters.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("no parameter {name}"))
}

/// (value, derivative, check) of output `output` with respect to `param`.
fn derivative(r: &SensitivityReport, param: &str, output: &str) -> (f64, f64, f64) {
    let i = r.outputs.iter().position(|o| o.name == output).unwrap_or_else(|| panic!("no output {output}"));
    let p = row(r, param);
    (r.outputs[i].value, p.derivatives[i], p.check.as_ref().expect("checked")[i])
}

/// |a - b| / |b|.
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Asserts that d(output)/d(param) agrees with the difference of settles within `tol`
/// relative, and returns it.
fn against_settles(r: &SensitivityReport, param: &str, output: &str, tol: f64) -> f64 {
    let (_, d, c) = derivative(r, param, output);
    assert!(rel(d, c) <= tol, "d {output}/d {param} = {d:.15e}, by settles {c:.15e}: {:.2e} > {tol:.0e}", rel(d, c));
    d
}

/// The pinned bar between zero-free-length springs settles at q* = atan2(k1 a, k2 b)
/// (pinned_bar_modes.toml, first point k1 = 10 N/m): dq*/dk1 = a k2 b / (k1^2 a^2 + k2^2 b^2),
/// dq*/dk2 = -k1 a b / (...), dq*/da = k1 k2 b / (...), dq*/db = -k1 k2 a / (...), each
/// within 1e-12 of the closed form and 1e-6 of the settles'. Its frequency
/// omega^2 = L hypot(k1 a, k2 b) / I (I = m L^2 / 3) gives d omega / d k1 =
/// L k1 a^2 / (2 I omega hypot) within 1e-9.
#[test]
fn the_pinned_bars_angle_moves_with_each_parameter_as_atan2_does() {
    let r = report_of("scenarios/custom/pinned_bar_modes.toml");
    let (k1, k2, a, b, l, m) = (10.0, 30.0, 0.8, 0.6, 1.0, 0.5);
    let den = k1 * k1 * a * a + k2 * k2 * b * b;
    for (p, closed) in
        [("k1", a * k2 * b / den), ("k2", -k1 * a * b / den), ("a", k1 * k2 * b / den), ("b", -k1 * k2 * a / den)]
    {
        let d = against_settles(&r, p, "pin.angle", 1e-6);
        assert!(rel(d, closed) <= 1e-12, "d q*/d {p} = {d:.15e}, closed form {closed:.15e}: {:.2e}", rel(d, closed));
    }
    let inertia = m * l * l / 3.0;
    let hypot = (k1 * a).hypot(k2 * b);
    let omega = (l * hypot / inertia).sqrt();
    let closed = l * k1 * a * a / (2.0 * inertia * omega * hypot);
    let d = against_settles(&r, "k1", "mode1.omega", 1e-6);
    assert!(rel(d, closed) <= 1e-9, "d omega/d k1 = {d:.15e}, closed form {closed:.15e}: {:.2e}", rel(d, closed));
    // The drawn angle q0 moves no node: the joint's coordinate, counted from the drawing,
    // turns back by as much as the drawing turned.
    for node in ["P.x", "P.y"] {
        let (_, d, _) = derivative(&r, "q0", node);
        assert!(d.abs() <= 1e-9, "d {node}/d q0 = {d:.3e}");
    }
    let (_, d, _) = derivative(&r, "q0", "pin.angle");
    assert!((d + 1.0).abs() <= 1e-9, "d pin.angle/d q0 = {d:.15e}");
}

/// The rocker (rocker_frequency_curve.toml at its first point, k1 = 10 N/m: springs of
/// natural lengths l1, l2, no closed form): its angle and frequency with respect to each
/// stiffness and natural length within 1e-6 of the differences of settles.
#[test]
fn the_rockers_angle_and_frequency_agree_with_differences_of_settles() {
    let r = report_of("scenarios/custom/rocker_frequency_curve.toml");
    for p in ["k1", "k2", "l1", "l2", "a", "b", "L"] {
        against_settles(&r, p, "pin.angle", 1e-6);
        against_settles(&r, p, "mode1.omega", 1e-6);
    }
    assert!(row(&r, "k1").max_check_error.expect("checked") <= 1e-6);
}

/// The 3-prism (prism3_model.toml): its twist is pi/2 + pi/n whatever the stiffness and the
/// rest lengths (d twist/dp within 1e-9 of 0), and its member forces move with them as the
/// differences of settles say, within 1e-6. The node coordinates, free to turn with the
/// structure about the fixed strut, are marked free and left out of the check.
#[test]
fn the_prisms_twist_stays_and_its_member_forces_agree_with_settles() {
    let r = report_of("scenarios/custom/prism3_model.toml");
    for p in ["k", "l_poly", "l_side", "r", "h", "twist0"] {
        let (_, d, _) = derivative(&r, p, "twist");
        assert!(d.abs() <= 1e-9, "d twist/d {p} = {d:.3e}");
        assert!(row(&r, p).max_check_error.expect("checked") <= 1e-6, "{p}: {:?}", row(&r, p).max_check_error);
    }
    for p in ["k", "l_poly", "l_side"] {
        for member in ["side1.force", "top12.force", "bottom23.force", "strut2.force"] {
            against_settles(&r, p, member, 1e-6);
        }
    }
    let free = |name: &str| r.outputs.iter().find(|o| o.name == name).expect("output").free;
    assert!(free("T2.x") && !free("twist") && !free("side1.force"));
}

/// ji2014's platform pose (quick.toml's first point): theta2, x and y with respect to K1, K2
/// and L within 1e-6 of the differences of settles, and within 1e-8 of the paper's own model
/// (its forward kinematics) differentiated by central differences extrapolated over h and 2 h.
#[test]
fn ji2014s_platform_pose_agrees_with_settles_and_the_papers_model() {
    let file = "scenarios/ji2014/quick.toml";
    let r = report_of(file);
    let sc = scenario::load(Path::new(file)).expect("shipped scenario");
    let mech = sc.mechanism();
    let inputs = sc.actuation.first_inputs().clone();
    let params = sc.params_at(&inputs);
    let predicted = |p: &str, v: f64, q: &str| {
        let mut moved: Values = params.clone();
        moved.insert(p.to_string(), v);
        mech.predict(&moved, &inputs).expect("the paper's model").expected[q]
    };
    for p in ["K1", "K2", "L"] {
        let (v, h) = (params[p], 1e-3 * params[p]);
        for q in ["theta2", "x", "y"] {
            let d = against_settles(&r, p, q, 1e-6);
            let f = |s: f64| predicted(p, v + s * h, q);
            let model = (8.0 * (f(1.0) - f(-1.0)) - (f(2.0) - f(-2.0))) / (12.0 * h);
            assert!(rel(d, model) <= 1e-8, "d {q}/d {p} = {d:.15e}, the paper's {model:.15e}: {:.2e}", rel(d, model));
        }
    }
}

/// The command: its table names each parameter, `--json -` is the JSON alone (the table on
/// standard error), `--csv` writes one row per parameter and output, both on standard output
/// is refused, and so is a cable with friction (exit 2, named: its force depends on the path).
#[test]
fn the_command_writes_json_and_csv_and_refuses_friction_by_name() {
    let file = "scenarios/custom/pinned_bar_modes.toml";
    let (code, out, _) = common::tensegrity(&["sensitivity", file]);
    assert!(code == 0 && out.contains("d/d k1 (= 10") && out.contains("pin.angle"), "{out}");
    let csv = std::env::temp_dir().join(format!("sensitivity-{}.csv", std::process::id()));
    let (code, out, err) = common::tensegrity(&["sensitivity", file, "--json", "-", "--csv", csv.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("stdout is the JSON alone");
    // Eight parameters, of which I = m L^2 / 3 is derived and listed apart.
    assert_eq!(v["parameters"].as_array().map(Vec::len), Some(7));
    assert_eq!(v["derived"], serde_json::json!(["I"]));
    assert!(err.contains("d/d k1"), "{err}");
    let text = std::fs::read_to_string(&csv).expect("the CSV");
    // A header and one row per parameter (7) and output (5 nodes x 3 coordinates, 2 spring
    // forces, the pin's angle, mode 1's omega: 19).
    assert_eq!(text.lines().count(), 1 + 7 * 19, "{text}");
    let _ = std::fs::remove_file(&csv);
    let (code, out, err) = common::tensegrity(&["sensitivity", file, "--json", "-", "--csv", "-"]);
    assert!(code == 2 && out.is_empty() && err.contains("only one of them"), "{out}{err}");
    // Another settle point of the grid over k1: the last, k1 = 90 N/m.
    let (code, out, err) = common::tensegrity(&["sensitivity", file, "--point", "2", "--json", "-"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    let (k1, k2, a, b) = (90.0, 30.0, 0.8, 0.6);
    let closed = a * k2 * b / (k1 * k1 * a * a + k2 * k2 * b * b);
    let i = v["outputs"].as_array().unwrap().iter().position(|o| o["name"] == "pin.angle").unwrap();
    let row = v["parameters"].as_array().unwrap().iter().find(|p| p["name"] == "k1").unwrap();
    let d = row["derivatives"][i].as_f64().unwrap();
    assert!(rel(d, closed) <= 1e-12, "at k1 = 90: {d:.15e} against {closed:.15e}");
    let (code, _, err) = common::tensegrity(&["sensitivity", file, "--point", "3"]);
    assert!(code == 2 && err.contains("--point 3: the scenario has no point 3"), "{err}");
    let (code, _, err) = common::tensegrity(&["sensitivity", "scenarios/custom/capstan.toml"]);
    assert!(code == 2 && err.contains("cable 'rope' has friction at a node"), "{err}");
}

/// The pinned bar's file with `[[sensitivities]]` as symbols and a paper's printed
/// sensitivities as predictions: dq*/dk1 = a k2 b / (k1^2 a^2 + k2^2 b^2) within 1e-12 and
/// d omega/d k1 within 1e-9, at every point of the grid over k1.
const PRINTED_SENSITIVITIES: &str = r#"
[[sensitivities]]
name = "dq_dk1"
output = "pin.angle"
parameter = "k1"

[[sensitivities]]
name = "domega_dk1"
output = "mode1.omega"
parameter = "k1"

[[predictions]]
quantity = "dq_dk1"
formula = "a*k2*b/(k1^2*a^2 + k2^2*b^2)"
class = "relative"
tolerance = 1e-12

[[predictions]]
quantity = "domega_dk1"
formula = "L*k1*a^2/(2*(m*L^2/3)*sqrt(L*hypot(k1*a, k2*b)/(m*L^2/3))*hypot(k1*a, k2*b))"
class = "relative"
tolerance = 1e-9
"#;

/// A paper's printed sensitivity is a prediction like any other: `[[sensitivities]]` names
/// d(output)/d(parameter) at each settle point, and the run judges it.
#[test]
fn a_printed_sensitivity_is_judged_as_a_prediction_at_every_point() {
    let text = std::fs::read_to_string("scenarios/custom/pinned_bar_modes.toml").unwrap() + PRINTED_SENSITIVITIES;
    let sc = scenario::parse(Path::new("printed.toml"), &text).expect("valid");
    let report = tensegrity_testbed::run::run(&sc, &Default::default());
    assert!(report.passed, "{:?} {:?}", report.failures, report.warnings);
    assert_eq!(report.points.len(), 3);
    for p in &report.points {
        assert!(p.errors["dq_dk1"] <= 1e-12 && p.errors["domega_dk1"] <= 1e-9, "{:?}", p.errors);
    }
    // A tolerance below the sensitivity's own error estimate is warned of, naming it.
    let fine = text.replace("class = \"relative\"\ntolerance = 1e-9", "class = \"relative\"\ntolerance = 1e-30");
    let report =
        tensegrity_testbed::run::run(&scenario::parse(Path::new("f.toml"), &fine).unwrap(), &Default::default());
    let warned =
        report.warnings.iter().filter(|w| w.contains("below what the sensitivity domega_dk1 resolves")).count();
    assert_eq!(warned, 3, "one a point: {:?}", report.warnings);
    // A wrong formula fails.
    let wrong = text.replace("a*k2*b/(k1^2", "1.001*a*k2*b/(k1^2");
    let report =
        tensegrity_testbed::run::run(&scenario::parse(Path::new("w.toml"), &wrong).unwrap(), &Default::default());
    assert!(!report.passed);
    // An output the state has not, a parameter the scenario has not: located.
    let bad = text.replace("output = \"pin.angle\"", "output = \"pin.angel\"");
    common::error_at(&bad, "\"pin.angel\"", 0, "'pin.angel' is no output of the settled state");
    let bad = text.replace("parameter = \"k1\"\n\n[[sens", "parameter = \"k9\"\n\n[[sens");
    common::error_at(&bad, "\"k9\"", 0, "'k9' is not a parameter of this scenario");
}

/// What the held bars below share: a tight settle at one point, under gravity g.
const SETTLED_ONCE_UNDER_GRAVITY: &str = r#"
[settle]
speed_tol = 1e-12
residual_force_tol = 1e-10
residual_torque_tol = 1e-10

[actuation]
points = [ {} ]

[structure]
gravity = [0.0, 0.0, "-g"]
"#;

/// The sensitivities of `text` (a scenario file whose `[structure]` takes
/// [`SETTLED_ONCE_UNDER_GRAVITY`]) at its first point, with the check.
fn report_of_text(text: &str) -> SensitivityReport {
    let text = text.replace("\n[structure]\n", SETTLED_ONCE_UNDER_GRAVITY);
    let sc = scenario::parse(Path::new("held.toml"), &text).expect("a valid scenario");
    tensegrity_testbed::study::sensitivity(&sc, "held.toml", 0, true, None).expect("sensitivities")
}

/// A bar pinned at O (revolute about y), its tip A held up by an inextensible cable of
/// length l to P at height H above O; gravity. No degree of freedom is left: the constraints
/// alone move the state, through dg/dp.
const CABLE_HELD_BAR: &str = r#"
name = "a bar held up by an inextensible cable"
mechanism = "custom"

[params]
a = { value = 1.0, unit = "m", description = "bar length" }
H = { value = 1.0, unit = "m", description = "height of the cable's fixed end P above the pin" }
l = { value = 1.2, unit = "m", description = "cable length" }
m = { value = 2.0, unit = "kg" }
g = { value = 9.81, unit = "m/s^2" }
th = { value = "asin((a^2 + H^2 - l^2)/(2*a*H))", unit = "rad", description = "the bar's angle above the horizontal" }

[structure]

[[structure.bodies]]
name = "ground"
fixed = true
nodes = { O = [0, 0, 0], P = [0, 0, "H"] }

[[structure.bodies]]
name = "bar"
mass = "m"
nodes = { B = [0, 0, 0], A = ["a*cos(th)", 0, "a*sin(th)"] }

[[structure.joints]]
name = "pin"
kind = "revolute"
parent = "ground"
child = "bar"
at = "B"
axis = [0, 1, 0]
damping = 0.5

[[structure.cables]]
name = "stay"
a = "A"
b = "P"
length = "l"
"#;

/// The cable-held bar: |A - P| = l gives sin(theta) = (a^2 + H^2 - l^2) / (2 a H), so
/// dA.z/dl = -l / H and dA.x/dl = l tan(theta) / H; the moment about O,
/// T a H cos(theta) / l = m g (a / 2) cos(theta), gives T = m g l / (2 H). Each derivative
/// within 1e-9 of the closed form (parameters inside the constraint, l and H, as well as the
/// loads m and g) and 1e-6 of the settles'.
#[test]
fn a_bar_held_by_an_inextensible_cable_moves_with_its_length_as_the_closed_form_does() {
    let r = report_of_text(CABLE_HELD_BAR);
    let (a, h, l, m, g): (f64, f64, f64, f64, f64) = (1.0, 1.0, 1.2, 2.0, 9.81);
    let theta = ((a * a + h * h - l * l) / (2.0 * a * h)).asin();
    let closed = [
        ("l", "stay.force", m * g / (2.0 * h)),
        ("H", "stay.force", -m * g * l / (2.0 * h * h)),
        ("m", "stay.force", g * l / (2.0 * h)),
        ("g", "stay.force", m * l / (2.0 * h)),
        ("l", "A.z", -l / h),
        ("l", "A.x", l * theta.tan() / h),
    ];
    for (p, output, expected) in closed {
        let d = against_settles(&r, p, output, 1e-6);
        assert!(rel(d, expected) <= 1e-9, "d {output}/d {p} = {d:.15e}, closed form {expected:.15e}");
    }
}

/// A bar on a ball joint at O, its tip A held aside by an inextensible cable of length l to
/// P = (d, 0, 0): A keeps to a circle about the x axis, and the bar may also spin about OA.
const BALL_JOINT_BAR_ON_A_CABLE: &str = r#"
name = "a bar on a ball joint held aside by an inextensible cable"
mechanism = "custom"

[params]
a = { value = 1.0, unit = "m", description = "bar length" }
d = { value = 1.0, unit = "m", description = "the cable's fixed end P on the x axis" }
l = { value = 1.2, unit = "m", description = "cable length" }
m = { value = 2.0, unit = "kg" }
g = { value = 9.81, unit = "m/s^2" }
ax = { value = "(a^2 + d^2 - l^2)/(2*d)", unit = "m", description = "the tip's x" }

[structure]

[[structure.bodies]]
name = "ground"
fixed = true
nodes = { O = [0, 0, 0], P = ["d", 0, 0] }

[[structure.bodies]]
name = "bar"
mass = "m"
nodes = { B = [0, 0, 0], A = ["ax", 0, "-sqrt(a^2 - ax^2)"] }

[[structure.joints]]
name = "ball"
kind = "spherical"
parent = "ground"
child = "bar"
at = "B"
damping = 0.5

[[structure.cables]]
name = "stay"
a = "A"
b = "P"
length = "l"
"#;

/// The swing of the ball-jointed bar on its cable, in closed form: about the x axis
/// (the line OP) gravity's stiffness is m g r (r = |A_perp| / 2, the centre of mass's distance
/// from the axis); the spin about OA has none, so the swing's inertia is the Schur complement
/// M_xx - M_xs^2 / M_ss of the inertia about O (isotropic m a^2 / 12 about the centre plus
/// m (|c|^2 1 - c c^T)) on the two axes. omega = 3.9151149408 rad/s; d omega/d g = omega / (2 g)
/// within 1e-9; d omega/d l and d omega/d a (inside the constraint: the state and the
/// inertia move) within 1e-6 of their central differences in closed form, and of the
/// settles' within 1e-5 (the constrained Hessian's differences carry about 1e-7).
#[test]
fn a_ball_jointed_bar_on_a_cable_has_the_closed_form_sensitivities_of_its_swing() {
    let omega = |g: f64, a: f64, l: f64| {
        let (m, d) = (2.0, 1.0);
        let ax = (a * a + d * d - l * l) / (2.0 * d);
        let ar = (a * a - ax * ax).sqrt();
        let c = nalgebra::Vector3::new(ax, 0.0, -ar) / 2.0;
        let inertia = nalgebra::Matrix3::identity() * (m * a * a / 12.0 + m * c.dot(&c)) - c * c.transpose() * m;
        let (x, s) = (nalgebra::Vector3::x(), nalgebra::Vector3::new(ax, 0.0, -ar) / a);
        let (mxx, mxs, mss) = (x.dot(&(inertia * x)), x.dot(&(inertia * s)), s.dot(&(inertia * s)));
        (m * g * ar / 2.0 / (mxx - mxs * mxs / mss)).sqrt()
    };
    let (g, a, l, h) = (9.81, 1.0, 1.2, 1e-5);
    let r = report_of_text(BALL_JOINT_BAR_ON_A_CABLE);
    let (w, _, _) = derivative(&r, "g", "mode2.omega");
    assert!(rel(w, omega(g, a, l)) <= 1e-9, "omega = {w:.12e}, closed form {:.12e}", omega(g, a, l));
    let closed = [
        ("g", (omega(g + h, a, l) - omega(g - h, a, l)) / (2.0 * h), 1e-9),
        ("l", (omega(g, a, l + h) - omega(g, a, l - h)) / (2.0 * h), 1e-6),
        ("a", (omega(g, a + h, l) - omega(g, a - h, l)) / (2.0 * h), 1e-6),
    ];
    for (p, expected, tol) in closed {
        let d = against_settles(&r, p, "mode2.omega", 1e-5);
        assert!(
            rel(d, expected) <= tol,
            "d omega/d {p} = {d:.15e}, closed form {expected:.15e}: {:.2e}",
            rel(d, expected)
        );
    }
}

/// A bar hanging from a ball joint at O.
const BALL_JOINT_PENDULUM: &str = r#"
name = "a bar hanging from a ball joint"
mechanism = "custom"

[params]
a = { value = 0.8, unit = "m", description = "bar length" }
m = { value = 2.0, unit = "kg" }
g = { value = 9.81, unit = "m/s^2" }

[structure]

[[structure.bodies]]
name = "ground"
fixed = true
nodes = { O = [0, 0, 0] }

[[structure.bodies]]
name = "bar"
mass = "m"
nodes = { B = [0, 0, 0], A = [0, 0, "-a"] }

[[structure.joints]]
name = "ball"
kind = "spherical"
parent = "ground"
child = "bar"
at = "B"
damping = 0.5
"#;

/// The ball-jointed pendulum swings at omega^2 = m g (a/2) / (m a^2 / 3) = 3 g / (2 a) about
/// either horizontal axis and spins freely about its own: its spin differences (second
/// differences of the Lagrangian) to omega^2 = -2.6e-8 rad^2/s^2, 1.4e-9 of the swing's, which
/// the reduced Hessian's own error (1.8e-5) marks rigid. The modes list one rigid mode and two
/// swings within 1e-9 of the closed form; the sensitivities list only the swings, with
/// d omega/d g = omega / (2 g) within 1e-9.
#[test]
fn a_ball_jointed_pendulums_spin_is_rigid_and_its_swing_meets_the_closed_form() {
    let (a, g): (f64, f64) = (0.8, 9.81);
    let omega = (3.0 * g / (2.0 * a)).sqrt();
    let text = BALL_JOINT_PENDULUM.replace("\n[structure]\n", SETTLED_ONCE_UNDER_GRAVITY);
    let sc = scenario::parse(Path::new("ball.toml"), &text).expect("a valid scenario");
    let (modes, _, _) = tensegrity_testbed::run::modes(&sc, "ball.toml", 20, None).expect("modes");
    assert_eq!(modes.rigid_modes, 1, "{:?}", modes.modes);
    let floor = modes.constraints.as_ref().expect("the constrained analysis").zero_floor_rad2_per_s2;
    assert!(modes.modes[0].rigid && modes.modes[0].omega_squared.abs() < floor, "{:?} against {floor}", modes.modes[0]);
    for swing in &modes.modes[1..] {
        assert!(rel(swing.omega_rad_per_s, omega) <= 1e-9, "{} against {omega}", swing.omega_rad_per_s);
    }
    let r = report_of_text(BALL_JOINT_PENDULUM);
    assert!(!r.outputs.iter().any(|o| o.name == "mode1.omega"), "the spin is not listed");
    let d = against_settles(&r, "g", "mode2.omega", 1e-6);
    assert!(rel(d, omega / (2.0 * g)) <= 1e-9, "d omega/d g = {d:.15e}, closed form {:.15e}", omega / (2.0 * g));
}

/// A study builds the structure again at each stepped parameter as the parse built it, `--set`
/// flags and patterns included: on the patterned prism of `benches/prism_modes.toml` with
/// `--set n=6 --set k=120` every parameter has its derivatives (each step had been rebuilt at
/// the file's own n = 300 and refused as another structure), and with every stiffness and
/// tension proportional to k the frequencies go as sqrt(k): d omega / d k = omega / (2 k)
/// within 1e-6 for the lowest mode.
#[test]
fn a_studys_steps_honour_the_set_flags_and_the_patterns() {
    let overrides: Vec<scenario::Override> =
        ["n=6", "k=120"].iter().map(|f| scenario::Override::parse(f).unwrap()).collect();
    let file = "benches/prism_modes.toml";
    let sc = scenario::load_with(Path::new(file), &overrides).expect("valid");
    let r = tensegrity_testbed::study::sensitivity(&sc, file, 0, false, None).expect("sensitivities");
    for p in &r.parameters {
        assert!(p.error.is_none(), "d/d {}: {:?}", p.name, p.error);
    }
    let i = r.outputs.iter().position(|o| o.name.ends_with(".omega")).expect("a mode's frequency");
    let (omega, d) = (r.outputs[i].value, row(&r, "k").derivatives[i]);
    assert!(rel(d, omega / 240.0) <= 1e-6, "{}: {d} against {}", r.outputs[i].name, omega / 240.0);
}

/// A study at `--point N` of a sweep over a topology builds the steps at the point's own
/// counts, as `run` builds that point: at point 2 of `scenarios/custom/prism_n.toml` (n = 5)
/// every parameter but n has its derivatives (each step had been rebuilt at the file's n = 3
/// and refused as another structure), the twist pi/2 + pi/5 does not move with the cables'
/// stiffness (|d twist1 / d k| below 1e-9 rad per N/m), and with every cable force
/// proportional to k the frequencies go as sqrt(k): d omega / d k = omega / (2 k) within 1e-6.
#[test]
fn a_study_at_a_point_of_a_topology_sweep_builds_its_steps_at_that_points_counts() {
    let file = "scenarios/custom/prism_n.toml";
    let sc = scenario::load(Path::new(file)).expect("shipped scenario");
    let r = tensegrity_testbed::study::sensitivity(&sc, file, 2, false, None).expect("sensitivities");
    assert_eq!(r.inputs.get("n"), Some(&5.0), "point 2 is n = 5");
    for p in r.parameters.iter().filter(|p| p.name != "n") {
        assert!(p.error.is_none(), "d/d {}: {:?}", p.name, p.error);
    }
    let twist = r.outputs.iter().position(|o| o.name == "twist1").expect("twist1");
    let expected = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / 5.0;
    assert!((r.outputs[twist].value - expected).abs() <= 1e-9, "twist1 = {}", r.outputs[twist].value);
    assert!(row(&r, "k").derivatives[twist].abs() <= 1e-9, "d twist1/d k = {}", row(&r, "k").derivatives[twist]);
    let i = r.outputs.iter().position(|o| o.name.ends_with(".omega")).expect("a mode's frequency");
    let (omega, d) = (r.outputs[i].value, row(&r, "k").derivatives[i]);
    assert!(rel(d, omega / 200.0) <= 1e-6, "{}: {d} against {}", r.outputs[i].name, omega / 200.0);
}

/// A `[[sensitivities]]` entry whose output is another entry is refused where the parse reads
/// it, at the output's string (it had passed `check` and come out NaN at every settle point),
/// and `tensegrity check` exits 2 with that `file:LINE:COL`.
#[test]
fn a_sensitivity_of_a_sensitivity_is_refused_at_its_output() {
    let text = std::fs::read_to_string("scenarios/custom/pinned_bar_modes.toml").unwrap()
        + PRINTED_SENSITIVITIES
        + "\n[[sensitivities]]\nname = \"d2q\"\noutput = \"dq_dk1\"\nparameter = \"k2\"\n";
    let said = "'dq_dk1' is another [[sensitivities]] entry, not an output of the settled state";
    common::error_at(&text, "output = \"dq_dk1\"", "output = ".len(), said);
    let path = std::env::temp_dir().join(format!("tt-sens-of-sens-{}.toml", std::process::id()));
    std::fs::write(&path, &text).unwrap();
    let (code, _, err) = common::tensegrity(&["check", path.to_str().unwrap()]);
    let offset = text.find("output = \"dq_dk1\"").unwrap() + "output = ".len();
    let line = text[..offset].matches('\n').count() + 1;
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(&format!(".toml:{line}:10: {said}")), "{err}");
}

/// A parameter that switches the model is named as a switch and not differentiated: mohr2011's
/// k_cable at its default 0 means inextensible cables (`(k_cable > 0).then_some(..)` in its
/// build), so its step h = 1e-3 N/m builds elastic ones and d/d k_cable had been printed as a
/// number (-1889.7). It now has no derivatives and no error, its row says why, the table says
/// "switch", the command exits 0 and every other parameter but the flag `straight` keeps its
/// derivatives. With
/// `--set k_cable=2000` (elastic at the value and at every step) it is differentiated.
#[test]
fn a_parameter_that_switches_the_model_is_named_and_not_differentiated() {
    let file = "scenarios/mohr2011/quick.toml";
    let sc = scenario::load(Path::new(file)).expect("shipped scenario");
    let r = tensegrity_testbed::study::sensitivity(&sc, file, 0, false, None).expect("sensitivities");
    let k = row(&r, "k_cable");
    let why = k.switch.as_deref().expect("k_cable named as a switch");
    assert!(why.contains("an inextensible cable at the value and an elastic cable at the step"), "{why}");
    assert!(k.derivatives.is_empty() && k.error.is_none(), "{k:?}");
    // `straight` (0: the paper's two-link springs, any other value one straight strut) too:
    // its steps build other bodies (it had been an error, failing the command).
    let straight = row(&r, "straight").switch.as_deref().expect("straight named as a switch");
    assert!(straight.contains("the structure built at the step has other bodies"), "{straight}");
    for p in r.parameters.iter().filter(|p| p.name != "k_cable" && p.name != "straight") {
        assert!(p.error.is_none() && p.switch.is_none(), "d/d {}: {:?} {:?}", p.name, p.error, p.switch);
        assert_eq!(p.derivatives.len(), r.outputs.len(), "d/d {}", p.name);
    }
    assert!(r.to_table().contains("d/d k_cable (= 0, step 1.000e-3): switch, not differentiated"), "{}", r.to_table());
    let (code, _, err) = common::tensegrity(&["sensitivity", file]);
    assert_eq!(code, 0, "{err}");
    let elastic = [scenario::Override::parse("k_cable=2000").unwrap()];
    let sc = scenario::load_with(Path::new(file), &elastic).expect("valid");
    let r = tensegrity_testbed::study::sensitivity(&sc, file, 0, false, None).expect("sensitivities");
    let k = row(&r, "k_cable");
    assert!(k.switch.is_none() && k.error.is_none(), "{k:?}");
    assert!(k.derivatives.iter().all(|d| d.is_finite()) && k.derivatives.len() == r.outputs.len());
}

/// A parameter that nothing in the file reads gets no steps: it is named unused and not
/// differentiated (every derivative 0, as its steps would have given), where 3,000 of them had
/// each resolved the file's structure four times (142 s on the pendulum, against 0.3 s for
/// `check`; 0.47 s now). What a read parameter derives from is read too (`w = "2*v"` with `w`
/// in a quantity reaches `v`), and the read parameters' rows are bit for bit those of the file
/// without the unread ones.
#[test]
fn a_parameter_that_nothing_reads_is_named_unused_and_not_differentiated() {
    let file = "scenarios/custom/pendulum_tip_load.toml";
    let plain = std::fs::read_to_string(file).unwrap().replace("[settle]", "v = 1.5\nw = \"2*v\"\n\n[settle]")
        + "\n[[quantities]]\nname = \"twice_v\"\nexpr = \"w\"\n";
    let unread: String = (0..40).map(|i| format!("u{i} = {}\n", 1.0 + i as f64)).collect();
    let hostile = plain.replace("[settle]", &format!("{unread}from_u = \"u0 + u1\"\n\n[settle]"));
    let report = |text: &str| {
        let sc = scenario::parse(Path::new(file), text).expect("valid");
        tensegrity_testbed::study::sensitivity(&sc, file, 0, false, None).expect("sensitivities")
    };
    let (plain, hostile) = (report(&plain), report(&hostile));
    // The 40 unread numbers get rows; from_u = u0 + u1 is derived, listed apart beside I and w.
    assert_eq!(hostile.parameters.len(), plain.parameters.len() + 40);
    assert_eq!(hostile.derived, ["I", "from_u", "w"]);
    for p in &hostile.parameters {
        let unused = p.name.starts_with('u');
        assert_eq!(p.unused, unused, "d/d {}", p.name);
        if unused {
            assert!(p.derivatives.iter().all(|d| *d == 0.0) && p.derivatives.len() == hostile.outputs.len());
            assert!(p.error.is_none() && p.switch.is_none() && p.check.is_none(), "{p:?}");
        } else {
            assert_eq!(p, row(&plain, &p.name), "d/d {}", p.name);
        }
    }
    assert!(!row(&hostile, "v").derivatives.iter().all(|d| *d == 0.0), "v is read through w");
    let table = hostile.to_table();
    assert!(table.contains("d/d u7 (= 8, step 8.000e-3): unused, not differentiated"), "{table}");
}

/// The derived parameters (expressions of others) are listed apart, not differentiated
/// (issue 62 item 5: `--check` had found errors up to 2.6e2 on them); `--param` asks for named
/// ones alone, a derived one as an input of its own, and an unknown name is exit 2. The elastic
/// strut's file: EA, L, a, b, k, m differentiated, delta and F listed apart; with
/// `--param delta --param k` those two rows alone, and k's the same to the bit as in the full run.
#[test]
fn derived_parameters_are_listed_apart_and_asked_for_by_name() {
    let file = "scenarios/custom/elastic_strut.toml";
    let json = |extra: &[&str]| -> serde_json::Value {
        let (code, out, err) = super::common::tensegrity(&[&["sensitivity", file, "--json", "-"], extra].concat());
        assert_eq!(code, 0, "{err}");
        serde_json::from_str(&out).unwrap()
    };
    let names = |v: &serde_json::Value| -> Vec<String> {
        v["parameters"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect()
    };
    let all = json(&[]);
    assert_eq!(names(&all), ["EA", "L", "a", "b", "k", "m"]);
    assert_eq!(all["derived"], serde_json::json!(["F", "delta"]));
    let asked = json(&["--param", "delta", "--param", "k"]);
    assert_eq!(names(&asked), ["delta", "k"]);
    assert_eq!(asked["parameters"][1]["derivatives"], all["parameters"][4]["derivatives"]);
    let (code, _, err) = super::common::tensegrity(&["sensitivity", file, "--param", "nope"]);
    assert_eq!(code, 2);
    assert!(err.contains("--param nope: not a parameter"), "{err}");
}

/// The base-pinned prism's mechanism frequency against its prestress (issue 62 item 4): d omega
/// / d t0 of mode 4 on the constrained analysis meets an independent numpy modal analysis's
/// converged difference quotient (Richardson over t0 +- 1e-3 and +- 1e-2, k = 1e4 N/m) within
/// 1e-6 at t0 = 5 N (measured 1.0e-7; it had been 2.9e-4 off while the analysis's differences
/// crossed the cables' kinks) and at t0 = 1 N (measured 3.3e-10), and each derivative's estimate
/// (five-point against three-point stencil) is no smaller than its true error.
#[test]
fn the_prism_mechanisms_slope_against_prestress_meets_the_reference_with_its_estimate() {
    const REFERENCE: [(f64, f64); 2] = [(5.0, 0.6992971561), (1.0, 1.5637183620)];
    let file = "scenarios/custom/pinned_prism_mechanism.toml";
    for (t0, exact) in REFERENCE {
        let set = [scenario::Override::parse(&format!("t0={t0}")).unwrap()];
        let sc = scenario::load_with(Path::new(file), &set).expect("the shipped file with t0 set");
        let r = tensegrity_testbed::study::sensitivity(&sc, file, 0, false, None).expect("sensitivities");
        let i = r.outputs.iter().position(|o| o.name == "mode4.omega").expect("the mechanism's frequency");
        let p = row(&r, "t0");
        let (d, estimate) = (p.derivatives[i], p.estimates[i]);
        assert!(rel(d, exact) <= 1e-6, "t0 = {t0}: d omega / d t0 = {d:.10e}, reference {exact:.10e}");
        assert!(estimate >= (d - exact).abs() && estimate <= 1e-5 * exact, "t0 = {t0}: estimate {estimate:e}");
    }
}

/// Above 100 free bodies, where `tensegrity modes` turns sparse, the sensitivities do too
/// (`sim/sparse_sensitivity.rs`): on the 150-strut prism of `benches/prism_modes.toml` the six
/// frequencies are `tensegrity modes`' own within 1e-12 (the dense K of differenced forces had
/// put a thin strut's spin among them and the others up to 0.7 % off at 300 struts), d omega /
/// d k = omega / (2 k) within 1e-8 (every force proportional to k), and every derivative by h
/// and by k (nodes, forces, frequencies) meets the differences of settles (`--check`) within
/// 1e-6.
#[test]
fn a_large_structures_sensitivities_are_its_modes_own_and_meet_the_settles() {
    let overrides: Vec<scenario::Override> = ["n=150"].iter().map(|f| scenario::Override::parse(f).unwrap()).collect();
    let file = "benches/prism_modes.toml";
    let sc = scenario::load_with(Path::new(file), &overrides).expect("valid");
    let only = ["h".to_string(), "k".to_string()];
    let r = tensegrity_testbed::study::sensitivity::sensitivity_to(&sc, file, (0, Some(&only)), true, None)
        .expect("sensitivities");
    let (modes, _, _) = tensegrity_testbed::run::modes(&sc, file, 6, None).expect("modes");
    let frequencies: Vec<(usize, &tensegrity_testbed::report::sensitivity::OutputValue)> =
        r.outputs.iter().enumerate().filter(|(_, o)| o.name.ends_with(".omega")).collect();
    assert_eq!(frequencies.len(), 6, "six frequencies");
    for (i, o) in &frequencies {
        let index: usize = o.name.trim_start_matches("mode").trim_end_matches(".omega").parse().unwrap();
        let mode = &modes.modes[index - 1];
        assert!(!mode.rigid, "{} is a deforming mode", o.name);
        assert!(
            rel(o.value, mode.omega_rad_per_s) <= 1e-12,
            "{}: {} against modes' {}",
            o.name,
            o.value,
            mode.omega_rad_per_s
        );
        let d = row(&r, "k").derivatives[*i];
        assert!(rel(d, o.value / 200.0) <= 1e-8, "d {}/d k = {d} against {}", o.name, o.value / 200.0);
    }
    for p in &r.parameters {
        let error = p.max_check_error.expect("checked");
        assert!(error <= 1e-6, "d/d {}: largest error against the settles {error:e}", p.name);
    }
}
