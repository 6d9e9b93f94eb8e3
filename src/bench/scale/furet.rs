//! The furet2018 family of `tensegrity bench --scale`: n Snelson X modules in series (the bird
//! neck of the paper's Fig. 1), n = 1 .. 20, each X as the built-in mechanism builds its two
//! (`mechanisms/furet2018/build.rs`: crossed bars A-C and B-D in planes [`PLANE_OFFSET_M`]
//! apart, top bar D-C, revolute joints about z at A (actuated), B and C, the loop closed at D
//! by a planar pin, lateral springs A-D and B-C), X(i + 1) standing on X(i)'s top bar.
//!
//! Every X is commanded to theta = [`THETA_RAD`] through its base-joint angle
//! phi = theta + atan2(l, b cos theta) and drawn at theta + [`START_OFFSET_RAD`]; with ideal
//! actuators the chain's pose is the kinematics' alone, so the settled end point (the last
//! top-bar midpoint) is compared with the direct kinematics of n modules, Eq. 2
//! (`analytic::direct_kinematics_n`). L = 1 m, b = 2/3 m (Fig. 3-4) and the mechanism's
//! default model choices.

use super::{Case, Measure};
use crate::mechanisms::furet2018::analytic::{self, Params};
use crate::settings::SimSettings;
use crate::structure::{
    Actuator, ActuatorTarget, BodyKind, Inertia, Joint, JointKind, Spring, Structure, Strut, Vec3,
    DEFAULT_TENDON_RADIUS_M,
};
use nalgebra::Vector2;

/// Module counts of the family.
pub const MODULES: [usize; 7] = [1, 2, 3, 5, 10, 15, 20];
/// The commanded theta of every X [rad].
pub const THETA_RAD: f64 = 0.1;
/// The start's theta past the commanded one [rad].
pub const START_OFFSET_RAD: f64 = 0.05;
/// The mechanism's default model choices (`furet2018` parameters m_bar, k_spring, l0_spring,
/// c_joint, dz, r_strut).
const BAR_MASS_KG: f64 = 0.1;
const SPRING_STIFFNESS_N_PER_M: f64 = 100.0;
const SPRING_REST_LENGTH_M: f64 = 0.5;
const JOINT_DAMPING_NMS_PER_RAD: f64 = 0.5;
const PLANE_OFFSET_M: f64 = 0.03;
const STRUT_RADIUS_M: f64 = 0.01;
/// Time step [s] and PGS iterations (the furet2018 scenarios'; the rest of the settings are the
/// defaults).
const DT_S: f64 = 0.005;
const PGS_ITERATIONS: usize = 64;

fn at(v: Vector2<f64>, z: f64) -> Vec3 {
    [v.x, v.y, z]
}

/// A slender bar about its midpoint (isotropic: the motion is planar).
fn bar(mid: Vector2<f64>, len: f64) -> Inertia {
    Inertia { mass_kg: BAR_MASS_KG, com: at(mid, 0.0), principal_kg_m2: [BAR_MASS_KG * len * len / 12.0; 3] }
}

/// A revolute joint about z.
fn revolute(name: String, parent: usize, child: usize, anchor: usize, q0: f64, damping: f64) -> Joint {
    Joint {
        name,
        kind: JointKind::Revolute { axis: [0.0, 0.0, 1.0] },
        parent,
        child,
        anchor,
        initial_coordinate: q0,
        torsion_spring: None,
        damping,
    }
}

/// Adds X module `k` (from 1) drawn as `x`, standing on body `below` at its nodes (A, B);
/// returns its top body, its top nodes (D, C) and its top midpoint node.
fn add_module(
    s: &mut Structure,
    p: &Params,
    x: &analytic::XGeometry,
    k: usize,
    below: usize,
    (a, b): (usize, usize),
) -> (usize, (usize, usize), usize) {
    let (dz, r) = (PLANE_OFFSET_M, STRUT_RADIUS_M);
    let ac = s.add_body(&format!("X{k}_bar_AC"), BodyKind::Free, Some(bar((x.base_left + x.top_right) / 2.0, p.l)));
    let bd = s.add_body(&format!("X{k}_bar_BD"), BodyKind::Free, Some(bar((x.base_right + x.top_left) / 2.0, p.l)));
    let top = s.add_body(&format!("X{k}_top"), BodyKind::Free, Some(bar(x.top_mid, p.b)));
    // Strut ends in the bars' planes; joint anchors in the plane z = 0.
    let ac_a = s.add_node(&format!("X{k}_AC_A"), ac, at(x.base_left, dz));
    let ac_c = s.add_node(&format!("X{k}_AC_C"), ac, at(x.top_right, dz));
    let bd_b = s.add_node(&format!("X{k}_BD_B"), bd, at(x.base_right, -dz));
    let bd_d = s.add_node(&format!("X{k}_BD_D"), bd, at(x.top_left, -dz));
    let c = s.add_node(&format!("C{k}"), top, at(x.top_right, 0.0));
    let d = s.add_node(&format!("D{k}"), top, at(x.top_left, 0.0));
    let end = s.add_node(&format!("P{k}"), top, at(x.top_mid, 0.0));
    s.struts.push(Strut { name: format!("X{k} crossed bar AC"), a: ac_a, b: ac_c, radius_m: r });
    s.struts.push(Strut { name: format!("X{k} crossed bar BD"), a: bd_b, b: bd_d, radius_m: r });
    s.struts.push(Strut { name: format!("X{k} top bar DC"), a: d, b: c, radius_m: r });
    for (name, na, nb) in [(format!("X{k} spring AD"), a, d), (format!("X{k} spring BC"), b, c)] {
        let (stiffness_n_per_m, rest_length_m) = (SPRING_STIFFNESS_N_PER_M, SPRING_REST_LENGTH_M);
        s.springs.push(Spring {
            name,
            a: na,
            b: nb,
            stiffness_n_per_m,
            rest_length_m,
            radius_m: DEFAULT_TENDON_RADIUS_M,
        });
    }
    let actuated = s.joints.len();
    s.joints.push(revolute(format!("X{k} A (actuated, phi{k})"), below, ac, a, x.joint_angle_a, 0.0));
    s.joints.push(revolute(format!("X{k} C"), ac, top, c, 0.0, JOINT_DAMPING_NMS_PER_RAD));
    s.joints.push(revolute(format!("X{k} B"), below, bd, b, x.joint_angle_b, JOINT_DAMPING_NMS_PER_RAD));
    // The loop closes at D with a planar pin (a full revolute would over-constrain it).
    let pin = JointKind::PlanarPin { axis: [0.0, 0.0, 1.0] };
    s.joints.push(Joint { kind: pin, ..revolute(format!("X{k} D"), bd, top, d, 0.0, 0.0) });
    s.actuators.push(Actuator { symbol: format!("phi{k}"), target: ActuatorTarget::Joint(actuated) });
    (top, (d, c), end)
}

/// n X modules drawn at `thetas` (one per module); returns the structure and each module's
/// top-midpoint node.
pub fn chain(p: &Params, thetas: &[f64]) -> (Structure, Vec<usize>) {
    let xs = analytic::chain_nodes(p, thetas);
    let mut s = Structure { name: format!("furet2018 x{}", thetas.len()), gravity: [0.0; 3], ..Default::default() };
    let base = s.add_body("base", BodyKind::Fixed, None);
    let mut below = base;
    let mut below_nodes =
        (s.add_node("A1", base, at(xs[0].base_left, 0.0)), s.add_node("B1", base, at(xs[0].base_right, 0.0)));
    s.struts.push(Strut { name: "base A1B1".into(), a: below_nodes.0, b: below_nodes.1, radius_m: STRUT_RADIUS_M });
    let mut ends = Vec::new();
    for (i, x) in xs.iter().enumerate() {
        let (top, nodes, end) = add_module(&mut s, p, x, i + 1, below, below_nodes);
        (below, below_nodes) = (top, nodes);
        ends.push(end);
    }
    (s, ends)
}

/// The n-module case: drawn at theta + [`START_OFFSET_RAD`], commanded to [`THETA_RAD`]; the
/// target is the end point of Eq. 2.
pub fn case(n: usize) -> Case {
    let p = Params::PAPER;
    let (start, ends) = chain(&p, &vec![THETA_RAD + START_OFFSET_RAD; n]);
    let (x, y) = analytic::direct_kinematics_n(&p, &vec![THETA_RAD; n]);
    Case {
        family: "furet",
        size: n,
        start,
        // The default settling: with ideal actuators the chain's pose is kinematic and the
        // position projection of the loop closures (`sim/projection.rs`) settles it (11 steps
        // at every n measured, with or without the Newton damping schedule).
        settings: SimSettings { dt_s: DT_S, pgs_iterations: PGS_ITERATIONS, ..Default::default() },
        commands: vec![analytic::base_joint_angle_a(&p, THETA_RAD); n],
        target: vec![(ends[n - 1], [x, y, 0.0])],
        measure: Measure::Absolute,
    }
}
