//! manriquez2019: the class-2 tensegrity robot of Manríquez-Padilla et al. (2019): a platform
//! on a universal joint, two cables, two springs, under gravity.

pub mod analytic;
pub mod build;
pub mod findings;

use super::{
    input, param, wrap_angle, Finding, InputSpec, Mechanism, MechanismSpec, ModelError, Origin, ParamSpec, Prediction,
    QuantityKind, QuantitySpec, QuerySpec, Solution, Values,
};
use crate::snapshot::Snapshot;
use crate::structure::{MemberKind, Structure};
use analytic::Params;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

pub struct Manriquez2019;

/// Default start: both joint angles this far from the target \[rad\], so every settle is a real
/// dynamic approach (the cable lengths are those of the target).
pub const DEFAULT_START_OFFSET_RAD: f64 = 0.03;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        symbol: "a2",
        unit: "m",
        default: analytic::A2_MM / analytic::MM_PER_M,
        description: "distance from the joint to the platform centre M (Table 1: 210 mm)",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "l1",
        unit: "m",
        default: analytic::L1_MM / analytic::MM_PER_M,
        description: "offset of the joint O from the world origin along x (Table 1: 190 mm)",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "l2",
        unit: "m",
        default: analytic::L2_MM / analytic::MM_PER_M,
        description: "side of the platform square (Table 1: 220 mm)",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "m",
        unit: "kg",
        default: analytic::PLATFORM_MASS_KG,
        description: "platform mass (Section 3: 0.4732 kg)",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "g",
        unit: "m/s^2",
        default: analytic::GRAVITY_M_S2,
        description: "gravity along +x_W: the base above, the platform hanging (Table 5 forces this reading)",
        origin: Origin::Paper,
    },
    ParamSpec {
        symbol: "base_x",
        unit: "m",
        default: analytic::FIT_BASE_X_MM / analytic::MM_PER_M,
        description: "x of the base plane holding B1..B4 (not in the paper: fitted to Table 5)",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "base_half",
        unit: "m",
        default: analytic::FIT_BASE_HALF_MM / analytic::MM_PER_M,
        description: "half-side of the base square B1..B4 (not in the paper: fitted to Table 5)",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "k_spring",
        unit: "N/m",
        default: analytic::FIT_SPRING_K_N_PER_M,
        description: "spring stiffness (not in the paper: fitted to Table 5)",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "l0_spring",
        unit: "m",
        default: analytic::FIT_SPRING_REST_MM / analytic::MM_PER_M,
        description: "spring free length (not in the paper: the fit drives it to 0)",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "c_joint",
        unit: "N m s/rad",
        default: 0.05,
        description: "viscous damping of the universal joint (not in the paper: zero at rest)",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "k_cable",
        unit: "N/m",
        default: 0.0,
        description: "cable stiffness; 0 = inextensible, the paper's assumption (Eq. 12-13). The statics (Eq. 18-27) assume it: elastic cables settle off the inputs' pose by their stretch",
        origin: Origin::ModelChoice,
    },
    ParamSpec {
        symbol: "r_strut",
        unit: "m",
        default: 0.005,
        description: "strut radius for drawing and interference (not in the paper)",
        origin: Origin::ModelChoice,
    },
];

const INPUTS: &[InputSpec] = &[
    InputSpec {
        symbol: "theta1",
        unit: "rad",
        description: "joint angle about z_W; the cables are set to its lengths (Eq. 12-13)",
    },
    InputSpec {
        symbol: "theta2",
        unit: "rad",
        description: "joint angle about y_M; the cables are set to its lengths (Eq. 12-13)",
    },
];

const QUANTITIES: &[QuantitySpec] = &[
    QuantitySpec {
        symbol: "theta1",
        unit: "rad",
        kind: QuantityKind::Angle,
        description: "settled joint angle about z_W",
    },
    QuantitySpec {
        symbol: "theta2",
        unit: "rad",
        kind: QuantityKind::Angle,
        description: "settled joint angle about y_M",
    },
    QuantitySpec {
        symbol: "f_C1",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "tension of cable 1 (Eq. 18-23)",
    },
    QuantitySpec { symbol: "f_C2", unit: "N", kind: QuantityKind::Magnitude, description: "tension of cable 2" },
    QuantitySpec { symbol: "f_R1", unit: "N", kind: QuantityKind::Magnitude, description: "force of spring 1" },
    QuantitySpec { symbol: "f_R2", unit: "N", kind: QuantityKind::Magnitude, description: "force of spring 2" },
    QuantitySpec {
        symbol: "f_joint",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "magnitude of the joint reaction force at O",
    },
    QuantitySpec {
        symbol: "m_joint",
        unit: "N m",
        kind: QuantityKind::Magnitude,
        description: "joint reaction moment about z_W x y_M, signed as Table 5",
    },
];

const QUERIES: &[QuerySpec] = &[
    QuerySpec { name: "fk", inputs: &["theta1", "theta2"], description: "forward kinematics (Eq. 1-11, 15): centre M, centroid G, cable lengths (Eq. 12-13)" },
    QuerySpec { name: "ik", inputs: &["x_m", "y_m", "z_m"], description: "inverse kinematics from the position of the platform centre M (Eq. 14-17, derived)" },
    QuerySpec { name: "statics", inputs: &["theta1", "theta2"], description: "cable and spring forces, joint reaction (Eq. 18-23), equilibrium (Eq. 26-27 as read), Table 5 beside it" },
    QuerySpec { name: "form_finding", inputs: &[], description: "the form-finding grid of Section 4 (121 x 121 from -0.5236 rad in steps of 0.0087) classified by the statics" },
];

/// The forces of a Table 5 row, in its column order (the sixth column is the joint moment).
const TABLE5_FORCES: [&str; 5] = ["f_C1", "f_C2", "f_R1", "f_R2", "f_joint"];

/// N mm per N m: Table 5 gives the joint moment in N mm.
const N_MM_PER_N_M: f64 = 1e3;

pub fn params_of(v: &Values) -> Params {
    Params {
        a2: v["a2"],
        l1: v["l1"],
        l2: v["l2"],
        mass: v["m"],
        gravity: v["g"],
        centroid_local: [analytic::CENTROID_RADIUS_MM / analytic::MM_PER_M, 0.0, 0.0],
        base_x: v["base_x"],
        base_half: v["base_half"],
        spring_k: v["k_spring"],
        spring_rest: v["l0_spring"],
    }
}

fn statics_values(p: &Params, th1: f64, th2: f64) -> Values {
    let s = analytic::statics(p, th1, th2);
    Values::from([
        ("theta1".into(), th1),
        ("theta2".into(), th2),
        ("f_C1".into(), s.cable_tensions[0]),
        ("f_C2".into(), s.cable_tensions[1]),
        ("f_R1".into(), s.spring_forces[0]),
        ("f_R2".into(), s.spring_forces[1]),
        ("f_joint".into(), s.joint_reaction_force.norm()),
        ("m_joint".into(), s.joint_moment_paper_sign),
    ])
}

/// (theta1, theta2) of a rotation R = Rz(theta1) Ry(theta2) (Eq. 15).
fn angles_of(r: &Matrix3<f64>) -> (f64, f64) {
    ((-r[(0, 1)]).atan2(r[(1, 1)]), (-r[(2, 0)]).atan2(r[(2, 2)]))
}

/// The mechanism as data (name, title, symbols).
const SPEC: MechanismSpec = MechanismSpec {
    name: "manriquez2019",
    title:
        "Manriquez-Padilla et al. (2019): class-2 tensegrity robot, universal joint, two cables, two springs, gravity",
    params: PARAMS,
    inputs: INPUTS,
    quantities: QUANTITIES,
    queries: QUERIES,
    start_keys: &[("offset", "start both joint angles this far from the target [rad] (default 0.03)")],
    alternative_inputs: &[],
};

impl Mechanism for Manriquez2019 {
    fn spec(&self) -> &MechanismSpec {
        &SPEC
    }
    fn validate_params(&self, v: &Values) -> Result<(), ModelError> {
        super::require_positive(v, &[("a2", "m"), ("l2", "m"), ("m", "kg"), ("base_half", "m"), ("k_spring", "N/m")])?;
        super::require_non_negative(
            v,
            &[("g", "m/s^2"), ("l0_spring", "m"), ("c_joint", "N m s/rad"), ("k_cable", "N/m"), ("r_strut", "m")],
        )?;
        params_of(v).validate().map_err(|e| ModelError::param("base_x", e))
    }
    fn validate_inputs(&self, params: &Values, inputs: &Values) -> Result<(), ModelError> {
        for s in ["theta1", "theta2"] {
            let t = inputs.get(s).copied().ok_or(ModelError::value(s, format!("missing input {s} [rad]")))?;
            if !(t.is_finite() && t.abs() < std::f64::consts::FRAC_PI_2) {
                return Err(ModelError::value(s, format!("{s} must lie in (-pi/2, pi/2) rad, got {t}")));
            }
        }
        let st = analytic::statics(&params_of(params), input(inputs, "theta1")?, input(inputs, "theta2")?);
        if st.singular {
            return Err(ModelError::value("theta1", "inputs on the singular pose where both cables lie in one plane through the joint: the cable tensions are not determined"));
        }
        Ok(())
    }
    fn solve(&self, query: &str, params: &Values, inputs: &Values) -> Result<Vec<Solution>, ModelError> {
        let p = params_of(params);
        match query {
            "fk" => fk_solution(&p, inputs),
            "ik" => {
                let m = Vector3::new(input(inputs, "x_m")?, input(inputs, "y_m")?, input(inputs, "z_m")?);
                let (t1, t2) = analytic::ik_position(&p, &m).map_err(|e| ModelError::no_solution(e.to_string()))?;
                Ok(vec![Solution {
                    label: "derived Eq. 16-17".into(),
                    values: Values::from([("theta1".into(), t1), ("theta2".into(), t2)]),
                    stable: None,
                }])
            }
            "statics" => statics_solutions(&p, inputs),
            "form_finding" => {
                let grid = analytic::paper_grid();
                let n_eq = analytic::classify(&p, &grid).iter().filter(|e| **e).count();
                Ok(vec![Solution {
                    label: format!(
                        "grid of {} points (the paper reports n = {})",
                        grid.len(),
                        analytic::PAPER_N_CONFIGURATIONS
                    ),
                    values: Values::from([("points".into(), grid.len() as f64), ("equilibria".into(), n_eq as f64)]),
                    stable: None,
                }])
            }
            other => Err(ModelError::no_solution(format!(
                "unknown query '{other}' for manriquez2019 (expected one of: fk, ik, statics, form_finding)"
            ))),
        }
    }
    fn build(&self, params: &Values, inputs: &Values, start: &Values) -> Result<Structure, ModelError> {
        let p = params_of(params);
        let (t1, t2) = (input(inputs, "theta1")?, input(inputs, "theta2")?);
        let off = start.get("offset").copied().unwrap_or(DEFAULT_START_OFFSET_RAD);
        let m = build::ModelChoices {
            joint_damping: param(params, "c_joint")?,
            strut_radius_m: param(params, "r_strut")?,
            cable_stiffness_n_per_m: Some(param(params, "k_cable")?).filter(|k| *k > 0.0),
        };
        Ok(build::build(&p, &m, t1 + off, t2 + off, analytic::cable_lengths(&p, t1, t2)))
    }
    /// The cables' lengths L1, L2 of Eq. 12-13 at the joint angles.
    fn commands(&self, params: &Values, inputs: &Values) -> Values {
        let [l1, l2] = analytic::cable_lengths(&params_of(params), inputs["theta1"], inputs["theta2"]);
        Values::from([("L1".into(), l1), ("L2".into(), l2)])
    }
    fn predict(&self, params: &Values, inputs: &Values) -> Result<Prediction, ModelError> {
        let p = params_of(params);
        let v = statics_values(&p, input(inputs, "theta1")?, input(inputs, "theta2")?);
        let slack = [("cable 1", v["f_C1"]), ("cable 2", v["f_C2"])]
            .iter()
            .filter(|(_, t)| *t < 0.0)
            .map(|(n, _)| n.to_string())
            .collect();
        Ok(Prediction {
            branches: vec![Solution { label: "statics (Eq. 18-23)".into(), values: v.clone(), stable: None }],
            expected: v,
            expected_slack: Some(slack),
        })
    }

    /// Table 5's analytical and ANSYS columns at the four experiments of Table 3 (m_joint
    /// converted from N mm to N m).
    fn paper_values(&self, _params: &Values, inputs: &Values) -> Option<(String, Values)> {
        let (t1, t2) = (inputs.get("theta1")?, inputs.get("theta2")?);
        let k = analytic::table3_experiment(*t1, *t2)?;
        let mut v = Values::new();
        for (column, table) in [("", analytic::TABLE5_ANALYTICAL[k]), ("ansys_", analytic::TABLE5_ANSYS[k])] {
            for (q, f) in TABLE5_FORCES.iter().zip(table) {
                v.insert(format!("{column}{q}"), f);
            }
            v.insert(format!("{column}m_joint"), table[5] / N_MM_PER_N_M);
        }
        Some((format!("Table 5, experiment {} (analytical; ansys_: ANSYS column)", k + 1), v))
    }
    fn observe(&self, params: &Values, s: &Structure, snap: &Snapshot) -> Values {
        let p = params_of(params);
        let at = |n: &str| Vector3::from(snap.nodes[s.node_id(n).expect("manriquez2019 node")]);
        // Platform rotation: the body's rotation times the start pose's.
        let body = s.body_id("platform").expect("platform");
        let q = snap.body_poses[body].rotation_xyzw;
        let rq = UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2]));
        let (c1, c2) = (at("C1") - at("B1"), at("C2") - at("B2"));
        // The start pose is where the platform frame was built: recover it from node M.
        let o = at("O");
        let m0 = s.nodes[s.node_id("M").expect("M")].position;
        let m0 = Vector3::from(m0) - o;
        let start = (m0.y.atan2(m0.x), (-m0.z).atan2((m0.x * m0.x + m0.y * m0.y).sqrt()));
        let r = rq.to_rotation_matrix().into_inner() * analytic::rotation(start.0, start.1);
        let (th1, th2) = angles_of(&r);
        // Forces on the platform: cables (towards the base), springs, gravity; the joint reacts.
        let of = |kind| s.members_of(kind).map(|(i, _)| snap.forces.force_n[i]).collect::<Vec<_>>();
        let (tension, spring) = (of(MemberKind::Cable), of(MemberKind::Spring));
        let (r1, r2) = (at("B3") - at("R1"), at("B4") - at("R2"));
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        let mut add = |f: Vector3<f64>, point: Vector3<f64>| {
            force += f;
            moment += (point - o).cross(&f);
        };
        add(-c1.normalize() * tension[0], at("C1"));
        add(-c2.normalize() * tension[1], at("C2"));
        add(r1.normalize() * spring[0], at("R1"));
        add(r2.normalize() * spring[1], at("R2"));
        add(Vector3::from(s.gravity) * p.mass, at("G"));
        let n = analytic::joint_constrained_axis(th1, th2);
        Values::from([
            ("theta1".into(), wrap_angle(th1)),
            ("theta2".into(), wrap_angle(th2)),
            ("f_C1".into(), tension[0]),
            ("f_C2".into(), tension[1]),
            ("f_R1".into(), spring[0]),
            ("f_R2".into(), spring[1]),
            ("f_joint".into(), force.norm()),
            ("m_joint".into(), -moment.dot(&n)),
        ])
    }
    fn length_scale(&self, params: &Values) -> f64 {
        params["a2"]
    }
    fn findings(&self, params: &Values) -> Vec<Finding> {
        findings::findings(&params_of(params))
    }
}

/// `fk`: the cable ends and the platform points through the DH chain, and the cable lengths.
fn fk_solution(p: &analytic::Params, inputs: &Values) -> Result<Vec<Solution>, ModelError> {
    let (t1, t2) = (input(inputs, "theta1")?, input(inputs, "theta2")?);
    let q = analytic::points(p, t1, t2);
    let l = analytic::cable_lengths(p, t1, t2);
    let [m1, m2] = q.cable_platform;
    Ok(vec![Solution {
        label: "Eq. 8-9 (cable ends P_M1, P_M2 through the DH chain), Eq. 15 (lengths in m)".into(),
        values: Values::from([
            ("x_m".into(), q.m.x),
            ("y_m".into(), q.m.y),
            ("z_m".into(), q.m.z),
            ("x_G".into(), q.g.x),
            ("y_G".into(), q.g.y),
            ("z_G".into(), q.g.z),
            ("x_M1".into(), m1.x),
            ("y_M1".into(), m1.y),
            ("z_M1".into(), m1.z),
            ("x_M2".into(), m2.x),
            ("y_M2".into(), m2.y),
            ("z_M2".into(), m2.z),
            ("L1".into(), l[0]),
            ("L2".into(), l[1]),
        ]),
        stable: None,
    }])
}

/// `statics`: the statics at the joint angles, and Table 5's analytical column where the
/// angles are one of Table 3's experiments.
fn statics_solutions(p: &analytic::Params, inputs: &Values) -> Result<Vec<Solution>, ModelError> {
    let (t1, t2) = (input(inputs, "theta1")?, input(inputs, "theta2")?);
    let st = analytic::statics(p, t1, t2);
    let mut v = statics_values(p, t1, t2);
    v.insert("equilibrium".into(), f64::from(u8::from(st.equilibrium)));
    v.insert("stable_fixed_cables".into(), f64::from(u8::from(analytic::stable_with_fixed_cables(p, t1, t2))));
    let mut out =
        vec![Solution { label: "statics (SI; m_joint in N m)".into(), values: v, stable: Some(st.equilibrium) }];
    if let Some(k) = analytic::table3_experiment(t1, t2) {
        let t = analytic::TABLE5_ANALYTICAL[k];
        let mut values: Values = TABLE5_FORCES.iter().zip(t).map(|(q, f)| (q.to_string(), f)).collect();
        values.insert("m_joint_Nmm".into(), t[5]);
        out.push(Solution {
            label: format!("Table 5, experiment {} (analytical column; m_joint in N mm)", k + 1),
            values,
            stable: None,
        });
    }
    Ok(out)
}
