//! furet2018 parameters -> the generic structure.
//!
//! Two Snelson X mechanisms in series (Section 2). Each X is a closed crossed four-bar of
//! rigid bars: base bar A-B (for X1 the fixed base; for X2 the top bar of X1), crossed bars
//! A-C and B-D of length L, top bar D-C of length b; revolute joints about Z at A, B, C, D;
//! springs on the lateral sides A-D and B-C. The paper leaves the actuation open: here each X
//! is driven by an ideal rotary actuator at its base joint A, which sets the angle phi of the
//! crossed bar A->C from the base bar A->B (`analytic::base_joint_angle_a`, a strictly
//! increasing function of the paper's theta). The joint tree runs A (actuated) -> C -> top bar,
//! and B -> B-D; the joint at D closes the loop.
//!
//! The two crossed bars of an X lie in different planes in a real build (the paper's remark on
//! collisions): bar A-C is drawn at z = +dz and bar B-D at z = -dz, the joints' axes along Z.

use super::analytic::{self, Params};
use crate::structure::{
    Actuator, ActuatorTarget, BodyKind, Inertia, Joint, JointKind, Member, Structure, TorsionSpring, Vec3,
    DEFAULT_TENDON_RADIUS_M,
};
use nalgebra::Vector2;

/// Model choices that the paper does not give (defaults in `Furet2018::params`).
#[derive(Clone, Copy, Debug)]
pub struct ModelChoices {
    /// Mass of each bar \[kg\].
    pub bar_mass_kg: f64,
    /// Stiffness of the lateral springs [N/m].
    pub spring_stiffness_n_per_m: f64,
    /// Free length of the lateral springs \[m\].
    pub spring_rest_length_m: f64,
    /// Viscous damping of the free joints [N m s/rad].
    pub joint_damping: f64,
    /// Half the distance between the planes of the two crossed bars of an X \[m\].
    pub plane_offset_m: f64,
    /// Bar radius for drawing and interference \[m\].
    pub strut_radius_m: f64,
    /// The actuators at A as servos of this stiffness [N m/rad] (`structure::Structure::servo_of`);
    /// None: ideal position actuators.
    pub servo_stiffness_nm_per_rad: Option<f64>,
}

fn at(v: Vector2<f64>, z: f64) -> Vec3 {
    [v.x, v.y, z]
}

/// The structure with the mechanism assembled at (theta1, theta2).
pub fn build(p: &Params, m: &ModelChoices, theta1: f64, theta2: f64) -> Structure {
    build_chain("furet2018", p, m, &analytic::x_nodes(p, theta1, theta2)).0
}

/// A chain of X modules drawn as `xs` (X(i + 1) standing on X(i)'s top bar; the paper's Fig. 1
/// bird neck for many), named `name`; also each module's top-midpoint node.
pub fn build_chain(name: &str, p: &Params, m: &ModelChoices, xs: &[analytic::XGeometry]) -> (Structure, Vec<usize>) {
    let mut s = Structure { name: name.into(), gravity: [0.0; 3], ..Default::default() };
    let base = s.add_body("base", BodyKind::Fixed, None);
    let mut below = base; // the body carrying this X's base bar
    let mut below_nodes =
        (s.add_node("A1", base, at(xs[0].base_left, 0.0)), s.add_node("B1", base, at(xs[0].base_right, 0.0)));
    s.members.push(Member::strut("base A1B1", below_nodes.0, below_nodes.1, m.strut_radius_m));
    let mut ends = Vec::with_capacity(xs.len());
    for (i, x) in xs.iter().enumerate() {
        let (top, nodes, end) = add_module(&mut s, p, m, x, i + 1, below, below_nodes);
        (below, below_nodes) = (top, nodes);
        ends.push(end);
    }
    (s, ends)
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
/// returns its top body, its top nodes (D, C) and its top-midpoint node.
fn add_module(
    s: &mut Structure,
    p: &Params,
    m: &ModelChoices,
    x: &analytic::XGeometry,
    k: usize,
    below: usize,
    (a, b): (usize, usize),
) -> (usize, (usize, usize), usize) {
    let bar = |mid: Vector2<f64>, len: f64| Inertia {
        mass_kg: m.bar_mass_kg,
        com: at(mid, 0.0),
        // A slender bar about its midpoint: m len^2 / 12 (isotropic: the motion is planar).
        principal_kg_m2: [m.bar_mass_kg * len * len / 12.0; 3],
    };
    let (dz, r) = (m.plane_offset_m, m.strut_radius_m);
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
    s.members.push(Member::strut(format!("X{k} crossed bar AC"), ac_a, ac_c, r));
    s.members.push(Member::strut(format!("X{k} crossed bar BD"), bd_b, bd_d, r));
    s.members.push(Member::strut(format!("X{k} top bar DC"), d, c, r));
    for (name, na, nb) in [(format!("X{k} spring AD"), a, d), (format!("X{k} spring BC"), b, c)] {
        s.members.push(Member::spring(
            name,
            [na, nb],
            m.spring_stiffness_n_per_m,
            m.spring_rest_length_m,
            DEFAULT_TENDON_RADIUS_M,
        ));
    }
    let actuated = s.joints.len();
    let mut actuated_a = revolute(format!("X{k} A (actuated, phi{k})"), below, ac, a, x.joint_angle_a, 0.0);
    actuated_a.torsion_spring = m
        .servo_stiffness_nm_per_rad
        .map(|k| TorsionSpring { stiffness_nm_per_rad: k, rest_angle_rad: x.joint_angle_a });
    s.joints.push(actuated_a);
    s.joints.push(revolute(format!("X{k} C"), ac, top, c, 0.0, m.joint_damping));
    s.joints.push(revolute(format!("X{k} B"), below, bd, b, x.joint_angle_b, m.joint_damping));
    // The loop closes at D with a planar pin: the other three joints already hold the loop in
    // the plane, so a full revolute joint would over-constrain it.
    let pin = JointKind::PlanarPin { axis: [0.0, 0.0, 1.0] };
    s.joints.push(Joint { kind: pin, ..revolute(format!("X{k} D"), bd, top, d, 0.0, 0.0) });
    s.actuators.push(Actuator { symbol: format!("phi{k}"), target: ActuatorTarget::Joint(actuated) });
    (top, (d, c), end)
}
