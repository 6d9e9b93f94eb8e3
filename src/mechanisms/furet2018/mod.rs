//! furet2018: the planar manipulator of two Snelson X mechanisms in series (Furet, Lettl,
//! Wenger 2018).

pub mod analytic;
pub mod build;
pub mod findings;

use super::{
    input, param, wrap_angle, Finding, InputSpec, Mechanism, MechanismSpec, ModelError, Origin, ParamSpec, Prediction,
    QuantityKind, QuantitySpec, QuerySpec, Solution, Values,
};
use crate::snapshot::Snapshot;
use crate::structure::Structure;
use analytic::Params;

pub struct Furet2018;

/// Inputs closer than this to a change point theta = +-pi/2 are refused \[rad\]: there the four
/// nodes of an X are collinear and the base-joint actuator cannot keep it crossed.
pub const CHANGE_POINT_MARGIN_RAD: f64 = 1e-3;

/// Grid of the workspace maps (cells per side over [-2L, 2L]^2).
pub const WORKSPACE_GRID: usize = 400;

/// Grid of the joint-space search for a non-singular path (cells per side).
pub const PATH_GRID: usize = 240;

const PARAMS: &[ParamSpec] = &[
    ParamSpec { symbol: "L", unit: "m", default: 1.0, description: "length of the crossed bars (Fig. 3-4: 1)", origin: Origin::Paper },
    ParamSpec { symbol: "b", unit: "m", default: 2.0 / 3.0, description: "length of the base and top bars, 0 < b < L (Fig. 3-4: 2/3)", origin: Origin::Paper },
    ParamSpec { symbol: "k_spring", unit: "N/m", default: 100.0, description: "stiffness of the lateral springs (not in the paper: with position-controlled actuators they load the bars, they do not move the end point)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "l0_spring", unit: "m", default: 0.5, description: "free length of the lateral springs (not in the paper)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "m_bar", unit: "kg", default: 0.1, description: "mass of each bar (not in the paper)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "c_joint", unit: "N m s/rad", default: 0.5, description: "viscous damping of the free joints (not in the paper: zero at rest)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "dz", unit: "m", default: 0.03, description: "half the distance between the planes of the two crossed bars of an X (the paper's remark on collisions; 0 puts them in one plane)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "r_strut", unit: "m", default: 0.01, description: "bar radius for drawing and interference (not in the paper)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "k_servo", unit: "N m/rad", default: 0.0, description: "stiffness of the actuators at A as servos (not in the paper): 0 = ideal position actuators, phi exactly its command (the mechanism is then rigid); > 0 = phi held by a torsion spring whose rest angle is the command, so the X modules vibrate and sag by the springs' torque over k_servo", origin: Origin::ModelChoice },
];

const INPUTS: &[InputSpec] = &[
    InputSpec {
        symbol: "theta1",
        unit: "rad",
        description: "angle of X1's mid-line from its base normal (Eq. 1-3); set through the base-joint angle phi1",
    },
    InputSpec {
        symbol: "theta2",
        unit: "rad",
        description: "angle of X2's mid-line from its base normal; set through phi2",
    },
];

const QUANTITIES: &[QuantitySpec] = &[
    QuantitySpec {
        symbol: "x",
        unit: "m",
        kind: QuantityKind::Length,
        description: "x of the top-bar midpoint of X2 (Eq. 3)",
    },
    QuantitySpec {
        symbol: "y",
        unit: "m",
        kind: QuantityKind::Length,
        description: "y of the top-bar midpoint of X2 (Eq. 3)",
    },
    QuantitySpec {
        symbol: "theta1",
        unit: "rad",
        kind: QuantityKind::Angle,
        description: "theta1 read off the simulated nodes of X1",
    },
    QuantitySpec {
        symbol: "theta2",
        unit: "rad",
        kind: QuantityKind::Angle,
        description: "theta2 read off the simulated nodes of X2",
    },
    QuantitySpec {
        symbol: "detJ",
        unit: "m^2/rad^2",
        kind: QuantityKind::Magnitude,
        description: "det J (derived; Eq. 13 as printed is wrong, see findings) at the simulated (theta1, theta2)",
    },
];

const QUERIES: &[QuerySpec] = &[
    QuerySpec { name: "dk", inputs: &["theta1", "theta2"], description: "direct kinematics (Eq. 3): the end point and det J" },
    QuerySpec { name: "ik", inputs: &["x", "y"], description: "inverse kinematics through the quartic (Eq. 6-12): every solution with det J and aspect" },
    QuerySpec { name: "workspace", inputs: &[], description: "area fractions of the workspace with 2 and with 4 inverse solutions (Fig. 5)" },
    QuerySpec { name: "path", inputs: &["theta1", "theta2", "theta1_end", "theta2_end"], description: "a joint-space path between two configurations of the same aspect that never crosses det J = 0 (cuspidality)" },
];

pub fn params_of(v: &Values) -> Params {
    Params { l: v["L"], b: v["b"] }
}

/// The mechanism's default model choices (its parameters' defaults).
pub fn default_model_choices() -> build::ModelChoices {
    model_of(&crate::mechanisms::with_defaults(&Furet2018, &Values::new()))
}

fn model_of(v: &Values) -> build::ModelChoices {
    build::ModelChoices {
        bar_mass_kg: v["m_bar"],
        spring_stiffness_n_per_m: v["k_spring"],
        spring_rest_length_m: v["l0_spring"],
        joint_damping: v["c_joint"],
        plane_offset_m: v["dz"],
        strut_radius_m: v["r_strut"],
        servo_stiffness_nm_per_rad: (v["k_servo"] > 0.0).then_some(v["k_servo"]),
    }
}

fn dk_values(p: &Params, th1: f64, th2: f64) -> Values {
    let (x, y) = analytic::direct_kinematics(p, th1, th2);
    Values::from([
        ("x".into(), x),
        ("y".into(), y),
        ("theta1".into(), th1),
        ("theta2".into(), th2),
        ("detJ".into(), analytic::det_jacobian(p, th1, th2)),
    ])
}

/// theta of an X from its base nodes (left, right) and top nodes (left, right), as in Eq. 1:
/// the angle from the base normal to the line joining the bars' midpoints.
fn theta_of(a: [f64; 3], b: [f64; 3], d: [f64; 3], c: [f64; 3]) -> f64 {
    let base = (b[1] - a[1]).atan2(b[0] - a[0]);
    let (mx, my) = ((c[0] + d[0] - a[0] - b[0]) / 2.0, (c[1] + d[1] - a[1] - b[1]) / 2.0);
    wrap_angle(my.atan2(mx) - base - std::f64::consts::FRAC_PI_2)
}

/// The mechanism as data (name, title, symbols).
const SPEC: MechanismSpec = MechanismSpec {
    name: "furet2018",
    title: "Furet, Lettl, Wenger (2018): planar manipulator of two Snelson X mechanisms in series, cuspidal",
    params: PARAMS,
    inputs: INPUTS,
    quantities: QUANTITIES,
    queries: QUERIES,
    start_keys: &[],
    alternative_inputs: &[&["x", "y", "solution"]],
};

impl Mechanism for Furet2018 {
    fn spec(&self) -> &MechanismSpec {
        &SPEC
    }
    fn validate_params(&self, v: &Values) -> Result<(), ModelError> {
        super::require_positive(v, &[("L", "m"), ("b", "m"), ("k_spring", "N/m"), ("m_bar", "kg")])?;
        super::require_non_negative(
            v,
            &[("l0_spring", "m"), ("c_joint", "N m s/rad"), ("dz", "m"), ("r_strut", "m"), ("k_servo", "N m/rad")],
        )?;
        let (l, b) = (param(v, "L")?, param(v, "b")?);
        if l <= b {
            return Err(ModelError::value(
                "b",
                format!("b must be shorter than L (the X assembles only if L > b, Section 2): L = {}, b = {}", l, b),
            ));
        }
        Ok(())
    }

    /// (x, y, solution k): the k-th inverse solution (1-based, in the order `solve furet2018
    /// ik` prints them) of the end point (x, y).
    fn convert_inputs(&self, params: &Values, given: &Values) -> Result<Values, ModelError> {
        let get = |k: &str| given.get(k).copied().ok_or(ModelError::value(k, format!("missing input '{k}'")));
        let (x, y, k) = (get("x")?, get("y")?, get("solution")?);
        if !(k >= 1.0 && k.fract() == 0.0) {
            return Err(ModelError::value("solution", format!("solution must be a whole number from 1, got {k}")));
        }
        let sols = analytic::ik_query(&params_of(params), x, y);
        let Some(s) = sols.get(k as usize - 1) else {
            return Err(ModelError::value(
                "solution",
                format!("({x}, {y}) has {} inverse solution(s) (Eq. 6-12), not a solution {k}", sols.len()),
            ));
        };
        Ok(Values::from([("theta1".into(), s.theta1), ("theta2".into(), s.theta2)]))
    }
    fn validate_inputs(&self, _params: &Values, inputs: &Values) -> Result<(), ModelError> {
        for s in ["theta1", "theta2"] {
            let t = inputs.get(s).copied().ok_or(ModelError::value(s, format!("missing input {s} [rad]")))?;
            if !(t.is_finite() && t.abs() < std::f64::consts::PI) {
                return Err(ModelError::value(s, format!("{s} must lie in (-pi, pi) rad, got {t}")));
            }
            if analytic::crossed_mode_margin(t) < CHANGE_POINT_MARGIN_RAD {
                return Err(ModelError::value(s, format!("{s} = {t} is at a change point (theta = +-pi/2): the X's nodes are collinear and the base-joint actuator cannot keep it crossed")));
            }
        }
        Ok(())
    }
    fn solve(&self, query: &str, params: &Values, inputs: &Values) -> Result<Vec<Solution>, ModelError> {
        let p = params_of(params);
        match query {
            "dk" => {
                let (t1, t2) = (input(inputs, "theta1")?, input(inputs, "theta2")?);
                let mut v = dk_values(&p, t1, t2);
                v.insert("aspect".into(), f64::from(analytic::aspect(&p, t1, t2)));
                Ok(vec![Solution { label: "Eq. 3".into(), values: v, stable: None }])
            }
            "ik" => {
                let (x, y) = (input(inputs, "x")?, input(inputs, "y")?);
                let sols = analytic::ik_query(&p, x, y);
                if sols.is_empty() {
                    return Err(ModelError::no_solution(format!(
                        "({x}, {y}) is outside the workspace: the quartic (Eq. 6-11) has no real root"
                    )));
                }
                Ok(sols
                    .iter()
                    .enumerate()
                    .map(|(i, s)| Solution {
                        label: format!("solution {} (aspect {:+})", i + 1, s.aspect),
                        values: Values::from([
                            ("theta1".into(), s.theta1),
                            ("theta2".into(), s.theta2),
                            ("phi1".into(), s.phi1),
                            ("detJ".into(), s.det_j),
                            ("aspect".into(), f64::from(s.aspect)),
                        ]),
                        stable: None,
                    })
                    .collect())
            }
            "workspace" => {
                let a = analytic::region_area_fractions(&p, WORKSPACE_GRID);
                Ok(vec![Solution {
                    label: format!("b = {} m, grid {WORKSPACE_GRID} x {WORKSPACE_GRID} over [-2L, 2L]^2", p.b),
                    values: Values::from([
                        ("workspace_area".into(), a.workspace_area),
                        ("fraction_2_solutions".into(), a.frac_2),
                        ("fraction_4_solutions".into(), a.frac_4),
                        ("fraction_other".into(), a.frac_other),
                        ("max_solutions".into(), a.max_count as f64),
                    ]),
                    stable: None,
                }])
            }
            "path" => {
                let from = (input(inputs, "theta1")?, input(inputs, "theta2")?);
                let to = (input(inputs, "theta1_end")?, input(inputs, "theta2_end")?);
                let path = analytic::nonsingular_path(&p, from, to, PATH_GRID).ok_or_else(|| {
                    ModelError::no_solution(
                        "no path that avoids det J = 0: the two configurations are in different aspects",
                    )
                })?;
                let min_det = analytic::min_abs_det_along(&p, &path, 200);
                Ok(path
                    .iter()
                    .enumerate()
                    .map(|(i, (t1, t2))| Solution {
                        label: format!("waypoint {i} (min |det J| along the path {min_det:.6})"),
                        values: Values::from([("theta1".into(), *t1), ("theta2".into(), *t2)]),
                        stable: None,
                    })
                    .collect())
            }
            other => Err(ModelError::no_solution(format!(
                "unknown query '{other}' for furet2018 (expected one of: dk, ik, workspace, path)"
            ))),
        }
    }
    fn build(&self, params: &Values, inputs: &Values, _start: &Values) -> Result<Structure, ModelError> {
        let (t1, t2) = (input(inputs, "theta1")?, input(inputs, "theta2")?);
        Ok(build::build(&params_of(params), &model_of(params), t1, t2))
    }
    /// Each module's actuated joint angle phi_k at A from its theta_k.
    fn commands(&self, params: &Values, inputs: &Values) -> Values {
        let p = params_of(params);
        let phi = |theta: &str| analytic::base_joint_angle_a(&p, inputs[theta]);
        Values::from([("phi1".into(), phi("theta1")), ("phi2".into(), phi("theta2"))])
    }
    fn predict(&self, params: &Values, inputs: &Values) -> Result<Prediction, ModelError> {
        let p = params_of(params);
        let v = dk_values(&p, input(inputs, "theta1")?, input(inputs, "theta2")?);
        Ok(Prediction {
            branches: vec![Solution { label: "crossed mode (Eq. 3)".into(), values: v.clone(), stable: None }],
            expected: v,
            expected_slack: None,
        })
    }
    fn observe(&self, params: &Values, s: &Structure, snap: &Snapshot) -> Values {
        let n = |name: &str| snap.nodes[s.node_id(name).expect("furet2018 node")];
        let th1 = theta_of(n("A1"), n("B1"), n("D1"), n("C1"));
        let th2 = theta_of(n("D1"), n("C1"), n("D2"), n("C2"));
        let p2 = n("P2");
        Values::from([
            ("x".into(), p2[0]),
            ("y".into(), p2[1]),
            ("theta1".into(), th1),
            ("theta2".into(), th2),
            ("detJ".into(), analytic::det_jacobian(&params_of(params), th1, th2)),
        ])
    }
    fn length_scale(&self, params: &Values) -> f64 {
        params["L"]
    }
    fn analytic_nodes(&self, params: &Values, inputs: &Values) -> Option<Vec<[f64; 3]>> {
        let s = self.build(params, inputs, &Values::new()).ok()?;
        Some(s.nodes.iter().map(|n| n.position).collect())
    }
    fn findings(&self, params: &Values) -> Vec<Finding> {
        findings::findings(&params_of(params))
    }
}
