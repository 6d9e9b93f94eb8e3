//! ji2014: the planar tensegrity parallel mechanism of Ji, Li and Lin (2014).

pub mod analytic;
pub mod build;
pub mod findings;

use super::{
    input, param, wrap_angle, Finding, InputSpec, Mechanism, MechanismSpec, ModelError, Origin, ParamSpec, Prediction,
    QuantityKind, QuantitySpec, QuerySpec, Solution, StiffnessProbe, Values,
};
use crate::snapshot::Snapshot;
use crate::structure::Structure;
use analytic::Params;

pub struct Ji2014;

/// Default start of the free coordinate: this far from the stable root \[rad\], so that every
/// settle is a real dynamic approach rather than a check of the initial guess.
pub const DEFAULT_START_OFFSET_RAD: f64 = 0.5;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        symbol: "L",
        unit: "m",
        default: 1.0,
        description: "side of the mobile triangle (base side is 2L)",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "K1",
        unit: "N/m",
        default: 200.0,
        description: "stiffness of spring K1 (D2-C2), zero free length",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "K2",
        unit: "N/m",
        default: 100.0,
        description: "stiffness of spring K2 (D3-C3), zero free length",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "m_platform",
        unit: "kg",
        default: 1.0,
        description: "mass of the mobile triangle (not in the paper: quasi-static results do not depend on it)",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "c_D1",
        unit: "N m s/rad",
        default: 20.0,
        description: "viscous damping of the pivot at D1 (not in the paper: zero at rest, it only speeds settling)",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "r_strut",
        unit: "m",
        default: 0.01,
        description: "strut radius for drawing and interference (not in the paper)",
        origin: Origin::ModelChoice,
    },
];

const INPUTS: &[InputSpec] = &[
    InputSpec { symbol: "L3", unit: "m", description: "length of the prismatic actuator C1D1" },
    InputSpec {
        symbol: "theta1",
        unit: "rad",
        description: "angle of the actuator from the X axis, 0 <= theta1 <= pi",
    },
];

const QUANTITIES: &[QuantitySpec] = &[
    QuantitySpec {
        symbol: "theta2",
        unit: "rad",
        kind: QuantityKind::Angle,
        description: "angle of strut D1D3 from the X axis (Eq. 5)",
    },
    QuantitySpec { symbol: "x", unit: "m", kind: QuantityKind::Length, description: "x of node D3 (Eq. 2)" },
    QuantitySpec { symbol: "y", unit: "m", kind: QuantityKind::Length, description: "y of node D3 (Eq. 3)" },
    QuantitySpec {
        symbol: "F_K1",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "force in spring K1 = K1 |D2C2|",
    },
    QuantitySpec {
        symbol: "F_K2",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "force in spring K2 = K2 |D3C3|",
    },
    QuantitySpec {
        symbol: "F_L3",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "axial force of the actuator on D1 along C1->D1",
    },
    QuantitySpec {
        symbol: "K",
        unit: "N m/rad",
        kind: QuantityKind::Magnitude,
        description: "stiffness d tau / d theta2 with the actuators locked (Eq. 42); simulated by the stiffness probe",
    },
];

const QUERIES: &[QuerySpec] = &[
    QuerySpec {
        name: "fk",
        inputs: &["L3", "theta1"],
        description: "forward kinematics: both equilibria of Eq. 5 (energy minimum and maximum), with K and stability",
    },
    QuerySpec {
        name: "ik",
        inputs: &["x", "y"],
        description: "inverse kinematics: every (L3, theta1) placing D3 at (x, y) in equilibrium",
    },
    QuerySpec {
        name: "jacobian",
        inputs: &["L3", "theta1"],
        description: "Jacobian of Eq. 17 and det J at the stable equilibrium",
    },
];

pub fn params_of(v: &Values) -> Params {
    Params { l: v["L"], k1: v["K1"], k2: v["K2"] }
}

fn model_of(v: &Values) -> build::ModelChoices {
    build::ModelChoices { platform_mass_kg: v["m_platform"], pivot_damping: v["c_D1"], strut_radius_m: v["r_strut"] }
}

/// Analytic statics at an equilibrium: spring forces and the actuator's axial force.
fn statics(p: &Params, l3: f64, theta1: f64, theta2: f64) -> (f64, f64, f64) {
    let n = analytic::nodes(p, l3, theta1, theta2);
    let f_k1 = p.k1 * (n.c2 - n.d2).norm();
    let f_k2 = p.k2 * (n.c3 - n.d3).norm();
    // Spring forces on the platform; the actuator balances them at D1.
    let on_platform = p.k1 * (n.c2 - n.d2) + p.k2 * (n.c3 - n.d3);
    let axis = nalgebra::Vector2::new(theta1.cos(), theta1.sin());
    (f_k1, f_k2, -on_platform.dot(&axis))
}

fn equilibrium_values(p: &Params, l3: f64, theta1: f64, e: &analytic::Equilibrium) -> Values {
    let (f1, f2, fl3) = statics(p, l3, theta1, e.theta2);
    Values::from([
        ("theta2".into(), e.theta2),
        ("x".into(), e.x),
        ("y".into(), e.y),
        ("U".into(), e.energy),
        ("K".into(), e.stiffness),
        ("F_K1".into(), f1),
        ("F_K2".into(), f2),
        ("F_L3".into(), fl3),
    ])
}

/// Both roots of dU/dtheta2 = 0, energy minimum first, each labelled with whether it is the
/// root the paper's Eq. 5 picks (theta2 restricted to [0, pi]).
fn branches(p: &Params, l3: f64, th1: f64) -> Vec<Solution> {
    let paper = analytic::fk_paper(p, l3, th1);
    analytic::equilibria(p, l3, th1)
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let mut label = if i == 0 { "energy minimum".to_string() } else { "energy maximum".to_string() };
            if wrap_angle(e.theta2 - paper.theta2).abs() < SAME_ROOT_RAD {
                label.push_str(PAPER_ROOT_MARK);
            }
            Solution { label, values: equilibrium_values(p, l3, th1, e), stable: Some(e.stable) }
        })
        .collect()
}

/// Appended to the label of the root that Eq. 5 picks with theta2 in [0, pi].
pub const PAPER_ROOT_MARK: &str = " (the root of Eq. 5 with theta2 in [0, pi])";

/// Two roots closer than this are the same root [rad] (the two roots are pi apart).
const SAME_ROOT_RAD: f64 = 1e-9;

/// The mechanism as data (name, title, symbols).
const SPEC: MechanismSpec = MechanismSpec {
    name: "ji2014",
    title: "Ji, Li, Lin (2014): planar tensegrity parallel mechanism, two springs, actuator (L3, theta1)",
    params: PARAMS,
    inputs: INPUTS,
    quantities: QUANTITIES,
    queries: QUERIES,
    start_keys: &[
        ("theta2", "start angle of strut D1D3 [rad]"),
        ("theta2_offset", "start this far from the stable root [rad] (default 0.5)"),
        ("at_unstable_root", "1: start exactly on the energy maximum"),
    ],
    alternative_inputs: &[],
};

impl Mechanism for Ji2014 {
    fn spec(&self) -> &MechanismSpec {
        &SPEC
    }
    fn validate_params(&self, v: &Values) -> Result<(), ModelError> {
        super::require_positive(v, &[("L", "m"), ("K1", "N/m"), ("K2", "N/m"), ("m_platform", "kg")])?;
        super::require_non_negative(v, &[("c_D1", "N m s/rad"), ("r_strut", "m")])?;
        Ok(())
    }
    fn validate_inputs(&self, params: &Values, inputs: &Values) -> Result<(), ModelError> {
        let l = param(params, "L")?;
        let l3 = inputs.get("L3").copied().ok_or(ModelError::value("L3", "missing input L3 [m]"))?;
        let th = inputs.get("theta1").copied().ok_or(ModelError::value("theta1", "missing input theta1 [rad]"))?;
        if !(l3 > 0.0 && l3.is_finite()) {
            return Err(ModelError::value("L3", format!(
                "L3 must be a finite number > 0 m (L3 = 0 is singularity i: the equilibrium does not depend on theta1), got {l3}"
            )));
        }
        if l3 > 1e3 * l {
            return Err(ModelError::value(
                "L3",
                format!("L3 = {l3} m is more than 1000 L: outside any plausible workspace"),
            ));
        }
        if !(0.0..=std::f64::consts::PI).contains(&th) {
            return Err(ModelError::value(
                "theta1",
                format!("theta1 must lie in [0, pi] rad (Section 2: D1 above the X axis), got {th}"),
            ));
        }
        // Singularity iii (Eq. 28): eta1 = eta2 = 0 leaves theta2 undetermined.
        let (e1, e2) = analytic::eta(&params_of(params), l3, th);
        if e1.hypot(e2) < 1e-12 * param(params, "K1")?.max(param(params, "K2")?) * l {
            return Err(ModelError::value(
                "L3",
                "inputs on a singularity where eta1 = eta2 = 0: every theta2 is an equilibrium",
            ));
        }
        Ok(())
    }
    fn solve(&self, query: &str, params: &Values, inputs: &Values) -> Result<Vec<Solution>, ModelError> {
        let p = params_of(params);
        match query {
            "fk" => {
                let (l3, th1) = (input(inputs, "L3")?, input(inputs, "theta1")?);
                Ok(branches(&p, l3, th1))
            }
            "ik" => {
                let (x, y) = (input(inputs, "x")?, input(inputs, "y")?);
                let sols = analytic::inverse_kinematics(&p, x, y);
                if sols.is_empty() {
                    return Err(ModelError::no_solution(format!(
                        "({x}, {y}) is not reachable: no equilibrium places D3 there with 0 <= theta1 <= pi"
                    )));
                }
                Ok(sols
                    .iter()
                    .enumerate()
                    .map(|(i, s)| Solution {
                        label: format!("solution {}", i + 1),
                        values: Values::from([
                            ("L3".into(), s.l3),
                            ("theta1".into(), s.theta1),
                            ("theta2".into(), s.theta2),
                            ("K".into(), s.stiffness),
                        ]),
                        stable: Some(s.stable),
                    })
                    .collect())
            }
            "jacobian" => {
                let (l3, th1) = (input(inputs, "L3")?, input(inputs, "theta1")?);
                let e = analytic::equilibria(&p, l3, th1)[0];
                let j = analytic::jacobian(&p, l3, th1, e.theta2);
                Ok(vec![Solution {
                    label: "stable equilibrium".into(),
                    values: Values::from([
                        ("theta2".into(), e.theta2),
                        ("dx/dL3".into(), j[(0, 0)]),
                        ("dx/dtheta1".into(), j[(0, 1)]),
                        ("dy/dL3".into(), j[(1, 0)]),
                        ("dy/dtheta1".into(), j[(1, 1)]),
                        ("detJ".into(), j.determinant()),
                    ]),
                    stable: Some(e.stable),
                }])
            }
            other => Err(ModelError::no_solution(format!(
                "unknown query '{other}' for ji2014 (expected one of: fk, ik, jacobian)"
            ))),
        }
    }
    fn build(&self, params: &Values, inputs: &Values, start: &Values) -> Result<Structure, ModelError> {
        let p = params_of(params);
        let (l3, th1) = (input(inputs, "L3")?, input(inputs, "theta1")?);
        let eq = analytic::equilibria(&p, l3, th1);
        let theta2 = if let Some(t) = start.get("theta2") {
            *t
        } else if self.starts_on_unstable_branch(start) {
            eq[1].theta2
        } else {
            eq[0].theta2 + start.get("theta2_offset").copied().unwrap_or(DEFAULT_START_OFFSET_RAD)
        };
        Ok(build::build(&p, &model_of(params), l3, th1, theta2))
    }
    fn start_flags(&self) -> &'static [&'static str] {
        &["at_unstable_root"]
    }
    fn start_exclusive(&self) -> &'static [(&'static str, &'static str)] {
        &[("theta2", "theta2_offset"), ("theta2", "at_unstable_root"), ("at_unstable_root", "theta2_offset")]
    }
    fn starts_on_unstable_branch(&self, start: &Values) -> bool {
        start.get("at_unstable_root").is_some_and(|f| *f != 0.0)
    }
    fn predict(&self, params: &Values, inputs: &Values) -> Result<Prediction, ModelError> {
        let p = params_of(params);
        let (l3, th1) = (input(inputs, "L3")?, input(inputs, "theta1")?);
        let eqs = analytic::equilibria(&p, l3, th1);
        Ok(Prediction {
            expected: equilibrium_values(&p, l3, th1, &eqs[0]),
            branches: branches(&p, l3, th1),
            expected_slack: None,
        })
    }
    fn observe(&self, _params: &Values, s: &Structure, snap: &Snapshot) -> Values {
        let at = |name: &str| snap.nodes[s.node_id(name).expect("ji2014 node")];
        let (d1, d3) = (at("D1"), at("D3"));
        let mut v = Values::from([
            ("theta2".into(), (d3[1] - d1[1]).atan2(d3[0] - d1[0])),
            ("x".into(), d3[0]),
            ("y".into(), d3[1]),
        ]);
        for (quantity, member) in [("F_K1", "K1"), ("F_K2", "K2")] {
            if let Some(f) = snap.member_force_n(s, member) {
                v.insert(quantity.into(), f);
            }
        }
        if let Some(f) = snap.actuator_force(s, "L3") {
            v.insert("F_L3".into(), f);
        }
        v
    }
    fn length_scale(&self, params: &Values) -> f64 {
        params["L"]
    }
    fn analytic_nodes(&self, params: &Values, inputs: &Values) -> Option<Vec<[f64; 3]>> {
        let p = params_of(params);
        let (l3, th1) = (*inputs.get("L3")?, *inputs.get("theta1")?);
        let e = analytic::equilibria(&p, l3, th1)[0];
        let n = analytic::nodes(&p, l3, th1, e.theta2);
        // Structure order: C1, C2, C3, L3_tip, D1, D2, D3.
        Some([n.c1, n.c2, n.c3, n.d1, n.d1, n.d2, n.d3].iter().map(|v| [v.x, v.y, 0.0]).collect())
    }
    fn stiffness_probe(&self) -> Option<StiffnessProbe> {
        Some(StiffnessProbe {
            body: "platform".into(),
            torque_axis: [0.0, 0.0, 1.0],
            coordinate: "theta2".into(),
            analytic: "K".into(),
        })
    }
    fn findings(&self, params: &Values) -> Vec<Finding> {
        findings::findings(&params_of(params))
    }
}
