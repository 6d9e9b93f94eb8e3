//! mohr2011 parameters -> the generic structure.
//!
//! Bodies: the fixed base triangle A1A2A3; the end-effector triangle B1B2B3, a free rigid
//! body; for each leg i, the two links of the paper's virtual compression spring (Section 2,
//! Fig. 2): link `i_lower` from A_i to the knee K_i and link `i_upper` from K_i to B_i, each of
//! length l_o/2.
//!
//! Joints (Section 2): a universal joint at A_i whose first axis is fixed in the base,
//! orthogonal to a_i and horizontal (e1_i = z x a_i / |a_i|), and whose second axis is parallel
//! to the knee; a revolute knee at K_i carrying the linear torsion spring of Eq. 4 (at rest when
//! the links are aligned, 2 theta_i = pi); a spherical joint at B_i. The legs' plane contains
//! e1_i, so the knee bends sideways along e1_i: the three knees form a pinwheel and never meet
//! at the common midpoint p/2 of the straight struts.
//!
//! Cables: six, tension only, between the base and the end-effector, driven in pairs (Eq. 6).

use super::analytic::SpringChain;
use crate::structure::{
    Actuator, ActuatorTarget, BodyKind, CableLaw, ExternalLoad, Inertia, Joint, JointKind, Member, Structure,
    TorsionSpring, Vec3, DEFAULT_TENDON_RADIUS_M,
};
use nalgebra::Vector3;

/// Model choices that the paper does not give (defaults in `Mohr2011::params`).
#[derive(Clone, Copy, Debug)]
pub struct ModelChoices {
    /// Mass of the end-effector triangle \[kg\] (three equal point masses at its nodes).
    pub platform_mass_kg: f64,
    /// Mass of each link of a virtual compression spring \[kg\].
    pub link_mass_kg: f64,
    /// Viscous damping of every leg joint (universal and knee) [N m s/rad].
    pub joint_damping: f64,
    /// Cable law: `None` inextensible, `Some(k)` elastic with stiffness k [N/m].
    pub cable_stiffness_n_per_m: Option<f64>,
    /// Strut (link) radius for drawing and interference \[m\].
    pub strut_radius_m: f64,
    /// Gravity along the paper's Z axis [m/s^2], carried by the end-effector (a payload): 0 is
    /// the paper's assumption; negative pulls it towards the base (base below), positive away
    /// from it (the mechanism hanging below its base, Section 5).
    pub gravity_z_m_per_s2: f64,
}

/// What the analytic model supplies: the geometry at the start configuration.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// Torsion spring constant kappa [N m/rad] (Eq. 4).
    pub kappa: f64,
    /// Outer length of a virtual compression spring l_o \[m\].
    pub lo: f64,
    /// The three virtual springs placed at the start (A_i, knee, B_i, universal axes).
    pub legs: [SpringChain; 3],
    /// The six cables: (name, base node index, end-effector node index, actuated symbol).
    pub cables: Vec<(String, usize, usize, String)>,
    /// Unstretched length of each cable at the start \[m\] (Eq. 6 with the commanded rho).
    pub cable_lengths: Vec<f64>,
    /// Straight-strut variant: each leg a straight strut A_i-B_i, a linear spring of this
    /// stiffness [N/m] and free length l_o, instead of the two-link virtual spring.
    pub straight_stiffness_n_per_m: Option<f64>,
}

fn arr(v: Vector3<f64>) -> Vec3 {
    [v.x, v.y, v.z]
}

pub fn build(g: &Geometry, m: &ModelChoices) -> Structure {
    let mut s = Structure { name: "mohr2011".into(), gravity: [0.0; 3], ..Default::default() };
    let base = s.add_body("base", BodyKind::Fixed, None);
    let a = g.legs.map(|c| c.a);
    let b = g.legs.map(|c| c.b);
    let centroid = (b[0] + b[1] + b[2]) / 3.0;
    // Three point masses m/3 at the vertices of an equilateral triangle of side l_b:
    // I_z = m l_b^2 / 3, I_x = I_y = m l_b^2 / 6 about the centroid.
    let lb = (b[1] - b[0]).norm();
    let ml2 = m.platform_mass_kg * lb * lb;
    let platform = s.add_body(
        "end_effector",
        BodyKind::Free,
        Some(Inertia {
            mass_kg: m.platform_mass_kg,
            com: arr(centroid),
            principal_kg_m2: [ml2 / 6.0, ml2 / 6.0, ml2 / 3.0],
        }),
    );
    if m.gravity_z_m_per_s2 != 0.0 {
        // The end-effector's weight only: the links are taken as massless for the load, as in
        // the analytic statics (their inertia only shapes the motion).
        s.loads.push(ExternalLoad { body: platform, force_n: [0.0, 0.0, m.platform_mass_kg * m.gravity_z_m_per_s2] });
    }
    let a_nodes: Vec<usize> = (0..3).map(|i| s.add_node(&format!("A{}", i + 1), base, arr(a[i]))).collect();
    let b_nodes: Vec<usize> = (0..3).map(|i| s.add_node(&format!("B{}", i + 1), platform, arr(b[i]))).collect();
    let r = m.strut_radius_m;
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        s.members.push(Member::strut(format!("A{}A{}", i + 1, j + 1), a_nodes[i], a_nodes[j], r));
        s.members.push(Member::strut(format!("B{}B{}", i + 1, j + 1), b_nodes[i], b_nodes[j], r));
    }
    if let Some(k) = g.straight_stiffness_n_per_m {
        for i in 0..3 {
            s.members.push(Member::spring(
                format!("leg{} spring", i + 1),
                [a_nodes[i], b_nodes[i]],
                k,
                g.lo,
                DEFAULT_TENDON_RADIUS_M,
            ));
            s.members.push(Member::strut(format!("leg{} (straight)", i + 1), a_nodes[i], b_nodes[i], r));
        }
    } else {
        add_two_link_legs(&mut s, g, m, base, platform, &a_nodes);
    }
    for (c, (name, ai, bi, symbol)) in g.cables.iter().enumerate() {
        let law = match m.cable_stiffness_n_per_m {
            None => CableLaw::Inextensible,
            Some(k) => CableLaw::Elastic { stiffness_n_per_m: k },
        };
        s.members.push(Member::cable(
            name.clone(),
            vec![a_nodes[*ai], b_nodes[*bi]],
            law,
            g.cable_lengths[c],
            DEFAULT_TENDON_RADIUS_M,
        ));
        let cable = s.members.len() - 1;
        s.actuators.push(Actuator { symbol: symbol.clone(), target: ActuatorTarget::CableLength(cable) });
    }
    s
}

/// The paper's virtual compression springs (Fig. 2): two links per leg, universal joint at A_i,
/// knee with the torsion spring of Eq. 4, spherical joint at B_i.
fn add_two_link_legs(
    s: &mut Structure,
    g: &Geometry,
    m: &ModelChoices,
    base: usize,
    platform: usize,
    a_nodes: &[usize],
) {
    let a = g.legs.map(|c| c.a);
    let b = g.legs.map(|c| c.b);
    let r = m.strut_radius_m;
    // A link: a slender rod of length l_o/2; an isotropic inertia m (l_o/2)^2 / 12 keeps it
    // well conditioned (quasi-static results do not depend on it).
    let link_inertia = |com: Vector3<f64>| Inertia {
        mass_kg: m.link_mass_kg,
        com: arr(com),
        principal_kg_m2: [m.link_mass_kg * g.lo * g.lo / 48.0; 3],
    };
    let mut legs = Vec::new();
    for i in 0..3 {
        let leg = &g.legs[i];
        let (k, e1) = (leg.knee, leg.e1);
        // Knee coordinate: the bend pi - 2 theta_i, zero when the links are aligned.
        let bend = std::f64::consts::PI - leg.knee_angle;
        let lower = s.add_body(&format!("leg{}_lower", i + 1), BodyKind::Free, Some(link_inertia((a[i] + k) * 0.5)));
        let upper = s.add_body(&format!("leg{}_upper", i + 1), BodyKind::Free, Some(link_inertia((k + b[i]) * 0.5)));
        let k_lower = s.add_node(&format!("K{}", i + 1), lower, arr(k));
        let a_lower = s.add_node(&format!("A{}_leg", i + 1), lower, arr(a[i]));
        let k_upper = s.add_node(&format!("K{}_upper", i + 1), upper, arr(k));
        let b_upper = s.add_node(&format!("B{}_leg", i + 1), upper, arr(b[i]));
        s.members.push(Member::strut(format!("leg{} lower link", i + 1), a_lower, k_lower, r));
        s.members.push(Member::strut(format!("leg{} upper link", i + 1), k_upper, b_upper, r));
        // Knee axis: the normal e2 of the leg's plane, along (K - A) x (B - K), so that a
        // positive rotation bends the knee further.
        let knee_axis = leg.e2;
        legs.push((i, lower, upper, e1, knee_axis, bend, k_lower, b_upper));
    }
    // Leg 1 first, then the end-effector on its spherical joint, then legs 2 and 3: the simulator
    // makes leg 1 and the end-effector one multibody chain and closes legs 2 and 3 at B2, B3.
    for &(i, lower, upper, e1, knee_axis, bend, k_node, b_leg) in &legs {
        s.joints.push(Joint {
            name: format!("U{}", i + 1),
            kind: JointKind::Universal { axis1: arr(e1), axis2: arr(knee_axis) },
            parent: base,
            child: lower,
            anchor: a_nodes[i],
            initial_coordinate: 0.0,
            torsion_spring: None,
            damping: m.joint_damping,
        });
        s.joints.push(Joint {
            name: format!("knee{}", i + 1),
            kind: JointKind::Revolute { axis: arr(knee_axis) },
            parent: lower,
            child: upper,
            anchor: k_node,
            initial_coordinate: bend,
            // Eq. 4: tau = kappa (2 theta - pi) = -kappa * bend, at rest when straight.
            torsion_spring: Some(TorsionSpring { stiffness_nm_per_rad: g.kappa, rest_angle_rad: 0.0 }),
            damping: m.joint_damping,
        });
        s.joints.push(Joint {
            name: format!("S{}", i + 1),
            kind: JointKind::Spherical,
            parent: upper,
            child: platform,
            anchor: b_leg,
            initial_coordinate: 0.0,
            torsion_spring: None,
            damping: 0.0,
        });
    }
}
