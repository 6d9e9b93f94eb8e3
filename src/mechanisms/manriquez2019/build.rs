//! manriquez2019 parameters -> the generic structure.
//!
//! A fixed base; the moving platform, a free rigid body of the paper's mass under gravity,
//! held by a universal joint at O (first axis z_W fixed in the base, second axis y_M fixed in
//! the platform, Eq. 1-5), two inextensible cables of actuated length (Eq. 12-13; elastic as a
//! model choice) and two
//! linear springs. Everything is placed at the start configuration (theta1, theta2).

use super::analytic::{self, Params};
use crate::structure::{
    Actuator, ActuatorTarget, BodyKind, CableLaw, Inertia, Joint, JointKind, Member, Structure, Vec3,
    DEFAULT_TENDON_RADIUS_M,
};
use nalgebra::Vector3;

fn arr(v: Vector3<f64>) -> Vec3 {
    [v.x, v.y, v.z]
}

/// Model choices the paper does not give.
#[derive(Clone, Copy, Debug)]
pub struct ModelChoices {
    /// Viscous damping of the universal joint [N m s/rad] (zero at rest).
    pub joint_damping: f64,
    /// Strut radius for drawing and interference \[m\].
    pub strut_radius_m: f64,
    /// Cable law: `None` inextensible (the paper's), `Some(k)` elastic with stiffness k [N/m].
    pub cable_stiffness_n_per_m: Option<f64>,
}

/// The structure at the start pose (theta1, theta2), cables at `cable_lengths` \[m\].
pub fn build(p: &Params, m: &ModelChoices, theta1: f64, theta2: f64, cable_lengths: [f64; 2]) -> Structure {
    let d = analytic::dynamic_model(p, theta1, theta2);
    let mut s = Structure { name: "manriquez2019".into(), gravity: arr(d.gravity), ..Default::default() };
    let base = s.add_body("base", BodyKind::Fixed, None);
    // The inertia's diagonal in the platform frame, taken along the world axes: the statics do
    // not depend on it (analytic::platform_inertia: a thin rod plus a cross).
    let i = d.inertia_local;
    let platform = s.add_body(
        "platform",
        BodyKind::Free,
        Some(Inertia { mass_kg: d.mass, com: arr(d.com), principal_kg_m2: [i[(0, 0)], i[(1, 1)], i[(2, 2)]] }),
    );
    let o_base = s.add_node("O", base, arr(d.joint_centre));
    let o_platform = s.add_node("M_O", platform, arr(d.joint_centre));
    let g = s.add_node("G", platform, arr(d.com));
    let q = analytic::points(p, theta1, theta2);
    let m_node = s.add_node("M", platform, arr(q.m));
    let r = m.strut_radius_m;
    s.members.push(Member::strut("rod O-M", o_platform, m_node, r));
    let _ = g;
    for (k, (b, t)) in d.cables.iter().enumerate() {
        let nb = s.add_node(&format!("B{}", k + 1), base, arr(*b));
        let nt = s.add_node(&format!("C{}", k + 1), platform, arr(*t));
        s.members.push(Member::strut(format!("platform M-C{}", k + 1), m_node, nt, r));
        s.members.push(Member::cable(
            format!("cable {}", k + 1),
            vec![nb, nt],
            m.cable_stiffness_n_per_m.map_or(CableLaw::Inextensible, |k| CableLaw::Elastic { stiffness_n_per_m: k }),
            cable_lengths[k],
            DEFAULT_TENDON_RADIUS_M,
        ));
        let cable = s.members.len() - 1;
        s.actuators.push(Actuator { symbol: format!("L{}", k + 1), target: ActuatorTarget::CableLength(cable) });
    }
    for (k, (b, t)) in d.springs.iter().enumerate() {
        let nb = s.add_node(&format!("B{}", k + 3), base, arr(*b));
        let nt = s.add_node(&format!("R{}", k + 1), platform, arr(*t));
        s.members.push(Member::strut(format!("platform M-R{}", k + 1), m_node, nt, r));
        s.members.push(Member::spring(
            format!("spring {}", k + 1),
            [nb, nt],
            d.spring_k,
            d.spring_rest,
            DEFAULT_TENDON_RADIUS_M,
        ));
    }
    s.joints.push(Joint {
        name: "universal O".into(),
        kind: JointKind::Universal { axis1: arr(d.joint_axis_base), axis2: arr(d.joint_axis_platform) },
        parent: base,
        child: platform,
        anchor: o_base,
        initial_coordinate: 0.0,
        torsion_spring: None,
        damping: m.joint_damping,
    });
    s
}
