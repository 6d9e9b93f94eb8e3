//! ji2014 parameters -> the generic structure.
//!
//! Bodies: the fixed base triangle C1C2C3; the actuator, an ideal RP chain from C1 (a housing
//! turned by the angle actuator theta1 about z at C1, and a rod slid by the length actuator L3
//! along the housing); the mobile triangle D1D2D3, a rigid body pivoting about z at D1 on the
//! rod's tip. Springs K1 (D2-C2) and K2 (D3-C3) have zero free length (Section 2). The revolute
//! joints about z keep the motion in the plane.

use super::analytic::{self, Params};
use crate::structure::{
    Actuator, ActuatorTarget, BodyKind, Inertia, Joint, JointKind, Member, Structure, DEFAULT_TENDON_RADIUS_M,
};

/// Model choices that the paper does not give (defaults in `Ji2014::params`).
#[derive(Clone, Copy, Debug)]
pub struct ModelChoices {
    /// Mass of the mobile triangle \[kg\], three equal point masses at its nodes.
    pub platform_mass_kg: f64,
    /// Viscous damping of the pivot at D1 [N m s/rad].
    pub pivot_damping: f64,
    /// Strut radius for drawing and interference \[m\].
    pub strut_radius_m: f64,
}

/// Nominal mass of the actuator's kinematic bodies [kg]: they are placed, not integrated, so
/// the value never enters the dynamics; rapier only needs it positive.
const ACTUATOR_BODY_MASS_KG: f64 = 1.0;

pub fn build(p: &Params, m: &ModelChoices, l3: f64, theta1: f64, theta2: f64) -> Structure {
    let nodes = analytic::nodes(p, l3, theta1, theta2);
    let xyz = |v: nalgebra::Vector2<f64>| [v.x, v.y, 0.0];
    let mut s = Structure { name: "ji2014".into(), gravity: [0.0; 3], ..Default::default() };
    // Centred where each body's placement carries it along: the housing turns about C1, the
    // rod's tip is D1 (so every build of the mechanism is the same structure, placed anew).
    let nominal = |com: [f64; 3]| {
        Some(Inertia { mass_kg: ACTUATOR_BODY_MASS_KG, com, principal_kg_m2: [ACTUATOR_BODY_MASS_KG; 3] })
    };
    let ground = s.add_body("base", BodyKind::Fixed, None);
    let housing = s.add_body("actuator_housing", BodyKind::Free, nominal(xyz(nodes.c1)));
    let rod = s.add_body("actuator_rod", BodyKind::Free, nominal(xyz(nodes.d1)));
    // Three point masses m/3 at the vertices of an equilateral triangle of side L:
    // I_z = m L^2 / 3 about the centroid, I_x = I_y = m L^2 / 6.
    let centroid = (nodes.d1 + nodes.d2 + nodes.d3) / 3.0;
    let ml2 = m.platform_mass_kg * p.l * p.l;
    let platform = s.add_body(
        "platform",
        BodyKind::Free,
        Some(Inertia {
            mass_kg: m.platform_mass_kg,
            com: xyz(centroid),
            principal_kg_m2: [ml2 / 6.0, ml2 / 6.0, ml2 / 3.0],
        }),
    );
    let c1 = s.add_node("C1", ground, xyz(nodes.c1));
    let c2 = s.add_node("C2", ground, xyz(nodes.c2));
    let c3 = s.add_node("C3", ground, xyz(nodes.c3));
    let tip = s.add_node("L3_tip", rod, xyz(nodes.d1));
    let d1 = s.add_node("D1", platform, xyz(nodes.d1));
    let d2 = s.add_node("D2", platform, xyz(nodes.d2));
    let d3 = s.add_node("D3", platform, xyz(nodes.d3));
    let r = m.strut_radius_m;
    for (name, a, b) in
        [("C1C2", c1, c2), ("C2C3", c2, c3), ("C1C3", c1, c3), ("D1D2", d1, d2), ("D2D3", d2, d3), ("D1D3", d1, d3)]
    {
        s.members.push(Member::strut(name, a, b, r));
    }
    if l3 > 0.0 {
        s.members.push(Member::strut("C1D1 (actuator L3)", c1, tip, r));
    }
    s.members.extend(zero_free_length_springs(p, (d2, c2), (d3, c3)));
    s.joints.extend(joints(m, [ground, housing, rod, platform], (c1, d1), (theta1, l3, theta2)));
    s.actuators.push(Actuator { symbol: "L3".into(), target: ActuatorTarget::Joint(1) });
    s.actuators.push(Actuator { symbol: "theta1".into(), target: ActuatorTarget::Joint(0) });
    s
}

/// K1 (D2-C2) and K2 (D3-C3): zero-free-length springs of the paper's stiffnesses.
fn zero_free_length_springs(p: &Params, (d2, c2): (usize, usize), (d3, c3): (usize, usize)) -> [Member; 2] {
    [
        Member::spring("K1", [d2, c2], p.k1, 0.0, DEFAULT_TENDON_RADIUS_M),
        Member::spring("K2", [d3, c3], p.k2, 0.0, DEFAULT_TENDON_RADIUS_M),
    ]
}

/// theta1 (the housing about C1, z), L3 (the rod along theta1 from C1) and the platform's
/// pivot D1 (about z, damped by the model's pivot damping).
fn joints(
    m: &ModelChoices,
    [ground, housing, rod, platform]: [usize; 4],
    (c1, d1): (usize, usize),
    (theta1, l3, theta2): (f64, f64, f64),
) -> [Joint; 3] {
    let z = [0.0, 0.0, 1.0];
    [
        Joint {
            name: "theta1".into(),
            kind: JointKind::Revolute { axis: z },
            parent: ground,
            child: housing,
            anchor: c1,
            initial_coordinate: theta1,
            torsion_spring: None,
            damping: 0.0,
        },
        Joint {
            name: "L3".into(),
            kind: JointKind::Prismatic { axis: [theta1.cos(), theta1.sin(), 0.0] },
            parent: housing,
            child: rod,
            anchor: c1,
            initial_coordinate: l3,
            torsion_spring: None,
            damping: 0.0,
        },
        Joint {
            name: "D1".into(),
            kind: JointKind::Revolute { axis: z },
            parent: rod,
            child: platform,
            anchor: d1,
            initial_coordinate: theta2,
            torsion_spring: None,
            damping: m.pivot_damping,
        },
    ]
}
