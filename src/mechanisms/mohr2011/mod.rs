//! mohr2011: the translational 3-DOF tensegrity mechanism of Mohr and Arsenault (2011).

pub mod analytic;
pub mod build;
pub mod findings;

use super::{
    input, param, Finding, InputSpec, Mechanism, MechanismSpec, ModelError, Origin, ParamSpec, Prediction,
    QuantityKind, QuantitySpec, QuerySpec, Solution, Values,
};
use crate::snapshot::Snapshot;
use crate::structure::Structure;
use analytic::Params;
use nalgebra::Vector3;

pub struct Mohr2011;

/// Default start: the end-effector this fraction of its height below the analytic point, so
/// every cable starts slack and every settle is a real dynamic approach.
pub const DEFAULT_START_DROP_FRACTION: f64 = 0.1;

const PARAMS: &[ParamSpec] = &[
    ParamSpec { symbol: "lb", unit: "m", default: 2.0, description: "side of the base and end-effector triangles l_b (Fig. 4-6: 2)", origin: Origin::Paper },
    ParamSpec { symbol: "lo", unit: "m", default: 6.0, description: "outer length of a virtual compression spring l_o, two links of l_o/2 (Fig. 4-6: 3 l_b)", origin: Origin::Paper },
    ParamSpec { symbol: "kappa", unit: "N m/rad", default: 10.0, description: "torsion spring constant (Eq. 4); the paper gives no value and the static workspace does not depend on it (Section 4.2)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "m_platform", unit: "kg", default: 1.0, description: "end-effector mass (not in the paper: quasi-static results without gravity do not depend on it)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "m_link", unit: "kg", default: 0.1, description: "mass of each link of a virtual spring (not in the paper)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "c_joint", unit: "N m s/rad", default: 2.0, description: "viscous damping of the leg joints (not in the paper: zero at rest, it only speeds settling)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "k_cable", unit: "N/m", default: 0.0, description: "cable stiffness; 0 = inextensible, the paper's assumption (Section 3)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "g_z", unit: "m/s^2", default: 0.0, description: "gravity along the paper's Z on the end-effector mass: 0 = the paper's assumption (Section 4); -9.81 base below; +9.81 hanging below the base (Section 5)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "straight", unit: "-", default: 0.0, description: "1: replace each virtual compression spring by one straight strut, a linear spring of stiffness k_straight and free length l_o (the design Section 2 rejects because the struts collide at their midpoints); 0: the paper's two-link springs", origin: Origin::ModelChoice },
    ParamSpec { symbol: "k_straight", unit: "N/m", default: 5.0, description: "stiffness of a straight strut's spring (straight = 1; not in the paper)", origin: Origin::ModelChoice },
    ParamSpec { symbol: "r_strut", unit: "m", default: 0.02, description: "link radius for drawing and interference (not in the paper)", origin: Origin::ModelChoice },
];

const INPUTS: &[InputSpec] = &[
    InputSpec { symbol: "rho1", unit: "m", description: "length of cables A2B3 and A3B2 (Eq. 6)" },
    InputSpec { symbol: "rho2", unit: "m", description: "length of cables A1B3 and A3B1 (Eq. 6)" },
    InputSpec { symbol: "rho3", unit: "m", description: "length of cables A1B2 and A2B1 (Eq. 6)" },
];

const QUANTITIES: &[QuantitySpec] = &[
    QuantitySpec {
        symbol: "x",
        unit: "m",
        kind: QuantityKind::Length,
        description: "end-effector centroid x (Eq. 12)",
    },
    QuantitySpec {
        symbol: "y",
        unit: "m",
        kind: QuantityKind::Length,
        description: "end-effector centroid y (Eq. 13)",
    },
    QuantitySpec {
        symbol: "z",
        unit: "m",
        kind: QuantityKind::Length,
        description: "end-effector centroid z > 0 (Eq. 14)",
    },
    QuantitySpec {
        symbol: "rotation",
        unit: "rad",
        kind: QuantityKind::Angle,
        description: "rotation angle of the end-effector from the base's orientation (0: pure translation, Section 2)",
    },
    QuantitySpec {
        symbol: "l1",
        unit: "m",
        kind: QuantityKind::Length,
        description: "effective length of virtual spring 1, |A1B1| (Eq. 16)",
    },
    QuantitySpec {
        symbol: "l2",
        unit: "m",
        kind: QuantityKind::Length,
        description: "effective length of virtual spring 2, |A2B2| (Eq. 16)",
    },
    QuantitySpec {
        symbol: "l3",
        unit: "m",
        kind: QuantityKind::Length,
        description: "effective length of virtual spring 3, |A3B3| (Eq. 16)",
    },
    QuantitySpec {
        symbol: "t1",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "tension of cable A2B3 (Eq. 26)",
    },
    QuantitySpec {
        symbol: "t2",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "tension of cable A1B3 (Eq. 27)",
    },
    QuantitySpec {
        symbol: "t3",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "tension of cable A1B2 (Eq. 28)",
    },
    QuantitySpec {
        symbol: "t4",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "tension of cable A3B2 (Eq. 26)",
    },
    QuantitySpec {
        symbol: "t5",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "tension of cable A3B1 (Eq. 27)",
    },
    QuantitySpec {
        symbol: "t6",
        unit: "N",
        kind: QuantityKind::Magnitude,
        description: "tension of cable A2B1 (Eq. 28)",
    },
];

const QUERIES: &[QuerySpec] = &[
    QuerySpec { name: "ikp", inputs: &["x", "y", "z"], description: "inverse kinematics (Eq. 15): the cable lengths rho1..rho3 for a centroid" },
    QuerySpec { name: "dkp", inputs: &["rho1", "rho2", "rho3"], description: "direct kinematics (Eq. 12-14): the centroid, z > 0 branch (and the mirror z < 0)" },
    QuerySpec { name: "statics", inputs: &["x", "y", "z"], description: "spring forces (Eq. 5), cable tensions by the wrench balance (Eq. 24) and the closed form (Eq. 26-28), det W_t (Eq. 25), workspace membership" },
];

/// Structure name of cable j (0-based, the paper's order t1..t6 of Eq. 21), e.g. `A2B3`.
pub fn cable_name(j: usize) -> String {
    let c = analytic::CABLES[j];
    format!("A{}B{}", c.base + 1, c.platform + 1)
}

/// The input symbol (rho1..rho3) that drives cable j (Eq. 6).
fn cable_symbol(j: usize) -> String {
    format!("rho{}", analytic::CABLES[j].rho + 1)
}

pub fn params_of(v: &Values) -> Params {
    Params { lb: v["lb"], lo: v["lo"], kappa: v["kappa"], l_min: 0.0 }
}

fn model_of(v: &Values) -> build::ModelChoices {
    build::ModelChoices {
        platform_mass_kg: v["m_platform"],
        link_mass_kg: v["m_link"],
        joint_damping: v["c_joint"],
        cable_stiffness_n_per_m: (v["k_cable"] > 0.0).then_some(v["k_cable"]),
        strut_radius_m: v["r_strut"],
        gravity_z_m_per_s2: v["g_z"],
    }
}

fn rho_of(inputs: &Values) -> Result<[f64; 3], ModelError> {
    Ok([input(inputs, "rho1")?, input(inputs, "rho2")?, input(inputs, "rho3")?])
}

/// Cable tensions \[N\] at centroid `p` with an external force `load` \[N\] on the end-effector's
/// centroid, from the full wrench balance (Eq. 19 with the load added: W_f f + W_t t + w = 0).
pub fn tensions_with_load(pa: &Params, p: &Vector3<f64>, f: [f64; 3], load: Vector3<f64>) -> [f64; 6] {
    let w = analytic::wf(pa, p) * nalgebra::Vector3::from(f)
        + nalgebra::Vector6::new(load.x, load.y, load.z, 0.0, 0.0, 0.0);
    match analytic::wt(pa, p).lu().solve(&(-w)) {
        Some(t) => [t[0], t[1], t[2], t[3], t[4], t[5]],
        None => [f64::NAN; 6],
    }
}

/// Fixed-point iterations of the elastic-cable equilibrium.
const ELASTIC_ITERATIONS: usize = 200;

/// End-effector position with elastic cables of stiffness k_cable: each taut cable is
/// stretched to rho_j + t_j / k, so the centroid is Eq. 12-14 applied to the stretched lengths,
/// with the tensions of Eq. 26-28 (or the loaded balance) there; solved by fixed-point
/// iteration from the inextensible answer `p0`. (The two cables of a pair carry one tension
/// without load; with a load, each pair is stretched by its mean tension.)
fn elastic_equilibrium(params: &Values, rho: [f64; 3], p0: Vector3<f64>) -> Vector3<f64> {
    let pa = params_of(params);
    let k = params["k_cable"];
    let mut p = p0;
    for _ in 0..ELASTIC_ITERATIONS {
        let v = values_at(params, p);
        let mut stretched = rho;
        for j in 0..3 {
            let mean = 0.5 * (v[&format!("t{}", j + 1)] + v[&format!("t{}", j + 4)]);
            stretched[analytic::CABLES[j].rho] = rho[analytic::CABLES[j].rho] + mean.max(0.0) / k;
        }
        match analytic::dkp(&pa, &stretched) {
            Some(next) if (next - p).norm() <= f64::EPSILON * pa.lb => return next,
            Some(next) => p = next,
            None => return p,
        }
    }
    p
}

/// Whether the legs are straight struts (the variant Section 2 rejects).
fn is_straight(params: &Values) -> bool {
    params["straight"] != 0.0
}

/// Internal force of each leg at centroid `p` [N] (compression negative): Eq. 5 for the
/// paper's two-link springs; k (l - l_o) for straight struts.
fn leg_forces(params: &Values, p: &Vector3<f64>) -> [f64; 3] {
    let pa = params_of(params);
    if is_straight(params) {
        analytic::spring_lengths(&pa, p).map(|l| params["k_straight"] * (l - pa.lo))
    } else {
        analytic::spring_forces(&pa, p)
    }
}

/// The end-effector's weight [N] along the paper's Z (zero in the paper's model).
fn payload(params: &Values) -> Vector3<f64> {
    Vector3::new(0.0, 0.0, params["m_platform"] * params["g_z"])
}

/// Analytic values at centroid `p`: position, spring lengths, tensions (closed form of
/// Eq. 26-28 without load; the full wrench balance with the payload's weight when g_z != 0).
fn values_at(params: &Values, p: Vector3<f64>) -> Values {
    let pa = &params_of(params);
    let st = analytic::statics(pa, &p);
    let forces = leg_forces(params, &p);
    let tensions = if params["g_z"] == 0.0 && !is_straight(params) {
        st.tensions_closed_form
    } else {
        tensions_with_load(pa, &p, forces, payload(params))
    };
    let mut v = Values::from([("x".into(), p.x), ("y".into(), p.y), ("z".into(), p.z), ("rotation".into(), 0.0)]);
    for (i, (l, f)) in st.spring_lengths.iter().zip(forces).enumerate() {
        v.insert(format!("l{}", i + 1), *l);
        v.insert(format!("f{}", i + 1), f);
    }
    for (j, t) in tensions.iter().enumerate() {
        v.insert(format!("t{}", j + 1), *t);
    }
    v
}

/// The mechanism as data (name, title, symbols).
const SPEC: MechanismSpec = MechanismSpec {
    name: "mohr2011",
    title: "Mohr, Arsenault (2011): translational 3-DOF tensegrity mechanism, six cables in pairs, three virtual compression springs",
    params: PARAMS,
    inputs: INPUTS,
    quantities: QUANTITIES,
    queries: QUERIES,
    start_keys: &[("drop", "start the end-effector this fraction of its height below the analytic point (default 0.1)")],
    alternative_inputs: &[&["x", "y", "z"]],
};

impl Mechanism for Mohr2011 {
    fn spec(&self) -> &MechanismSpec {
        &SPEC
    }
    fn convert_inputs(&self, params: &Values, given: &Values) -> Result<Values, ModelError> {
        let get = |k: &str| given.get(k).copied().ok_or(ModelError::value(k, format!("missing input '{k}'")));
        let p = Vector3::new(get("x")?, get("y")?, get("z")?);
        if !(p.z > 0.0 && p.iter().all(|c| c.is_finite())) {
            return Err(ModelError::value(
                "z",
                format!("the end-effector must be above the base: z > 0 m (Section 4.1), got {}", p.z),
            ));
        }
        let rho = analytic::ikp(&params_of(params), &p);
        Ok(Values::from([("rho1".into(), rho[0]), ("rho2".into(), rho[1]), ("rho3".into(), rho[2])]))
    }
    fn validate_params(&self, v: &Values) -> Result<(), ModelError> {
        super::require_positive(
            v,
            &[("lb", "m"), ("lo", "m"), ("kappa", "N m/rad"), ("m_platform", "kg"), ("m_link", "kg")],
        )?;
        let straight = param(v, "straight")?;
        if !(straight == 0.0 || straight == 1.0) {
            return Err(ModelError::value(
                "straight",
                format!("straight must be 0 (two-link springs) or 1 (straight struts), got {straight}"),
            ));
        }
        super::require_positive(v, &[("k_straight", "N/m")])?;
        super::require_non_negative(v, &[("c_joint", "N m s/rad"), ("k_cable", "N/m"), ("r_strut", "m")])?;
        let g_z = param(v, "g_z")?;
        if !g_z.is_finite() {
            return Err(ModelError::value("g_z", format!("g_z must be a finite number (m/s^2), got {g_z}")));
        }
        params_of(v).validate().map_err(|e| ModelError::param("lo", e))
    }
    fn validate_inputs(&self, params: &Values, inputs: &Values) -> Result<(), ModelError> {
        let pa = params_of(params);
        let mut rho = [0.0; 3];
        for (i, s) in ["rho1", "rho2", "rho3"].iter().enumerate() {
            let x = inputs.get(*s).copied().ok_or(ModelError::value(*s, format!("missing input {s} [m]")))?;
            if !(x > 0.0 && x.is_finite()) {
                return Err(ModelError::value(*s, format!("{s} must be a finite number > 0 m, got {x}")));
            }
            rho[i] = x;
        }
        let p = analytic::dkp(&pa, &rho).ok_or_else(|| {
            ModelError::value(
                "rho1",
                format!("cable lengths {rho:?} m are unreachable: Eq. 14 has no real z > 0 (the radicand is negative)"),
            )
        })?;
        // Kinematic workspace (Eq. 17-18): every virtual spring strictly between 0 and l_o.
        let st = analytic::statics(&pa, &p);
        for (i, l) in st.spring_lengths.iter().enumerate() {
            if !(*l > 0.0 && *l < pa.lo) {
                return Err(ModelError::value("rho1", format!(
                    "cable lengths {rho:?} m put the end-effector at ({:.6}, {:.6}, {:.6}) m, where virtual spring {} would be {l:.6} m long: outside 0 < l_i < l_o = {} m (Eq. 17-18)",
                    p.x, p.y, p.z, i + 1, pa.lo
                )));
            }
        }
        Ok(())
    }
    fn solve(&self, query: &str, params: &Values, inputs: &Values) -> Result<Vec<Solution>, ModelError> {
        let pa = params_of(params);
        let centroid = || -> Result<Vector3<f64>, ModelError> {
            Ok(Vector3::new(input(inputs, "x")?, input(inputs, "y")?, input(inputs, "z")?))
        };
        match query {
            "ikp" => {
                let p = centroid()?;
                let rho = analytic::ikp(&pa, &p);
                Ok(vec![Solution {
                    label: "Eq. 15".into(),
                    values: Values::from([("rho1".into(), rho[0]), ("rho2".into(), rho[1]), ("rho3".into(), rho[2])]),
                    stable: None,
                }])
            }
            "dkp" => {
                let rho = rho_of(inputs)?;
                let p = analytic::dkp(&pa, &rho).ok_or_else(|| {
                    let rad = analytic::dkp_radicand_eq14(&pa, &rho);
                    ModelError::no_solution(match rad.is_finite() {
                        true => format!("cable lengths {rho:?} m are unreachable: Eq. 14 has no real z"),
                        false => format!("cable lengths {rho:?} m: Eq. 14's radicand overflows ({rad}) with these values, no branch computed"),
                    })
                })?;
                let st = analytic::statics(&pa, &p);
                Ok(vec![
                    Solution {
                        label: "z > 0 (Eq. 12-14, the mechanism's branch)".into(),
                        values: Values::from([("x".into(), p.x), ("y".into(), p.y), ("z".into(), p.z)]),
                        stable: Some(st.in_static_workspace),
                    },
                    Solution {
                        label: "z < 0 (mirror, through the base: ignored by the paper)".into(),
                        values: Values::from([("x".into(), p.x), ("y".into(), p.y), ("z".into(), -p.z)]),
                        stable: None,
                    },
                ])
            }
            "statics" => {
                let p = centroid()?;
                let st = analytic::statics(&pa, &p);
                let mut v = values_at(params, p);
                for j in 0..6 {
                    v.insert(format!("t{}_full", j + 1), st.tensions_full[j]);
                }
                v.insert("det_Wt".into(), st.det_wt);
                v.insert("det_Wt_eq25".into(), analytic::det_wt_eq25(&pa, &p));
                v.insert("in_kinematic_workspace".into(), f64::from(u8::from(st.in_kinematic_workspace)));
                v.insert("in_static_workspace".into(), f64::from(u8::from(st.in_static_workspace)));
                Ok(vec![Solution {
                    label: "statics at the centroid".into(),
                    values: v,
                    stable: Some(st.in_static_workspace),
                }])
            }
            other => Err(ModelError::no_solution(format!(
                "unknown query '{other}' for mohr2011 (expected one of: ikp, dkp, statics)"
            ))),
        }
    }
    fn build(&self, params: &Values, inputs: &Values, start: &Values) -> Result<Structure, ModelError> {
        let pa = params_of(params);
        let rho = rho_of(inputs)?;
        let p = analytic::dkp(&pa, &rho)
            .ok_or_else(|| ModelError::no_solution(format!("cable lengths {rho:?} m are unreachable")))?;
        let drop = start.get("drop").copied().unwrap_or(DEFAULT_START_DROP_FRACTION);
        let p0 = Vector3::new(p.x, p.y, p.z * (1.0 - drop));
        let leg = |i: usize| {
            analytic::spring_chain(&pa, &p0, i).ok_or_else(|| {
                ModelError::no_solution(format!(
                    "virtual spring {} cannot be assembled at the start ({:?})",
                    i + 1,
                    p0.as_slice()
                ))
            })
        };
        let g = build::Geometry {
            lo: pa.lo,
            kappa: pa.kappa,
            legs: [leg(0)?, leg(1)?, leg(2)?],
            cables: (0..6)
                .map(|j| {
                    let c = analytic::CABLES[j];
                    (cable_name(j), c.base, c.platform, cable_symbol(j))
                })
                .collect(),
            cable_lengths: (0..6).map(|j| input(inputs, &cable_symbol(j))).collect::<Result<_, _>>()?,
            straight_stiffness_n_per_m: if is_straight(params) { Some(param(params, "k_straight")?) } else { None },
        };
        Ok(build::build(&g, &model_of(params)))
    }
    fn predict(&self, params: &Values, inputs: &Values) -> Result<Prediction, ModelError> {
        let pa = params_of(params);
        let rho = rho_of(inputs)?;
        let p = analytic::dkp(&pa, &rho)
            .ok_or_else(|| ModelError::no_solution(format!("cable lengths {rho:?} m are unreachable")))?;
        let p = if param(params, "k_cable")? > 0.0 { elastic_equilibrium(params, rho, p) } else { p };
        let expected = values_at(params, p);
        let slack = (0..6).filter(|j| expected[&format!("t{}", j + 1)] < 0.0).map(cable_name).collect();
        Ok(Prediction {
            branches: vec![Solution { label: "z > 0 (Eq. 12-14)".into(), values: expected.clone(), stable: None }],
            expected,
            expected_slack: Some(slack),
        })
    }
    fn observe(&self, _params: &Values, s: &Structure, snap: &Snapshot) -> Values {
        let node = |name: &str| Vector3::from(snap.nodes[s.node_id(name).expect("mohr2011 node")]);
        let b = [node("B1"), node("B2"), node("B3")];
        let a = [node("A1"), node("A2"), node("A3")];
        let c = (b[0] + b[1] + b[2]) / 3.0;
        let mut v = Values::from([("x".into(), c.x), ("y".into(), c.y), ("z".into(), c.z)]);
        if let Some(platform) = s.body_id("end_effector") {
            let q = snap.body_poses[platform].rotation_xyzw;
            let sin_half = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            v.insert("rotation".into(), 2.0 * sin_half.atan2(q[3].abs()));
        }
        for i in 0..3 {
            v.insert(format!("l{}", i + 1), (b[i] - a[i]).norm());
        }
        for j in 0..6 {
            if let Some(t) = snap.member_force_n(s, &cable_name(j)) {
                v.insert(format!("t{}", j + 1), t);
            }
        }
        v
    }
    fn length_scale(&self, params: &Values) -> f64 {
        params["lb"]
    }
    fn analytic_nodes(&self, params: &Values, inputs: &Values) -> Option<Vec<[f64; 3]>> {
        let s = self.build(params, inputs, &Values::from([("drop".into(), 0.0)])).ok()?;
        Some(s.nodes.iter().map(|n| n.position).collect())
    }
    fn findings(&self, params: &Values) -> Vec<Finding> {
        let mut out = findings::findings(&params_of(params));
        out.push(gravity_finding(params));
        out
    }
}

/// Grid cells of the static-workspace volume count along each half-axis of the kinematic
/// workspace's bounding box (reach l_o + l_b): a fixed count, so that the work does not grow
/// with l_o / l_b (it had grown with its cube: minutes at l_o = 60 l_b). At the paper's
/// l_o = 3 l_b the step is 0.125 l_b.
const VOLUME_GRID_CELLS: f64 = 32.0;

/// Points of a grid (step (l_o + l_b) / `VOLUME_GRID_CELLS` over the kinematic workspace's
/// bounding box, z > 0) in the static workspace with the end-effector's weight along Z = `g_z`.
pub fn static_workspace_count(params: &Values, g_z: f64) -> usize {
    let pa = params_of(params);
    let reach = pa.lo + pa.lb; // every spring sphere lies within this of the origin
    let h = reach / VOLUME_GRID_CELLS;
    let n = (reach / h).ceil() as i64;
    let load = Vector3::new(0.0, 0.0, params["m_platform"] * g_z);
    let a2 = analytic::base_nodes(&pa).map(|a| 2.0 * a);
    let mut count = 0;
    for i in -n..=n {
        for j in -n..=n {
            for k in 1..=n {
                let p = Vector3::new(i as f64 * h, j as f64 * h, k as f64 * h);
                // Kinematic workspace (Eq. 17-18): every spring strictly shorter than l_o.
                if a2.iter().any(|c| (p - c).norm() >= pa.lo) {
                    continue;
                }
                if tensions_with_load(&pa, &p, leg_forces(params, &p), load).iter().all(|t| *t > 0.0) {
                    count += 1;
                }
            }
        }
    }
    count
}

/// Section 5: gravity on a mechanism hanging below its base should enlarge the workspace.
fn gravity_finding(params: &Values) -> Finding {
    const G: f64 = 9.81;
    let none = static_workspace_count(params, 0.0);
    let hanging = static_workspace_count(params, G);
    let upright = static_workspace_count(params, -G);
    Finding {
        equation: "Sec. 5 (gravity)".into(),
        claim: "with gravity, a mechanism hanging below its base gains cable tension and a larger workspace".into(),
        measured: format!(
            "static-workspace grid points (step {} l_b, m = {} kg, kappa = {} N m/rad): {none} without gravity, {hanging} hanging (g along +Z), {upright} upright (g along -Z); the weight raises some tensions but unbalances the pairs (t_j != t_j+3), and the workspace then depends on m g / kappa, no longer independent of the stiffness",
            (params["lo"] + params["lb"]) / VOLUME_GRID_CELLS / params["lb"],
            params["m_platform"],
            params["kappa"]
        ),
        holds: hanging > none,
    }
}
