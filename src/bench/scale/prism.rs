//! The prism family of `tensegrity bench --scale`: regular n-strut tensegrity prisms, settled from a twisted start,
//! against their closed-form twist.
//!
//! A regular prism with struts from bottom node i to top node i, side cables from bottom node
//! i to top node i - 1 and two polygons of cables is in equilibrium (has a self-stress) only
//! at the relative twist pi/2 + pi/n of its top polygon (Tibert & Pellegrino, "Review of
//! form-finding methods for tensegrity structures", 2003, Sec. 2.1). Each case draws the
//! prism at radius `RADIUS_M` and height `HEIGHT_M`, turned `START_TWIST_OFFSET_FRACTION`
//! of the polygons' angle short of that twist, with rest lengths that make the drawn closed-form shape the
//! equilibrium (force densities side : polygon = 1 : 1 / (2 sin(pi/n)), ibid.; polygon cables
//! stretched by `POLYGON_STRAIN`), strut 1 held; it settles with the structure's
//! default settling (the static relaxation) and reports steps, wall time and the largest
//! twist error over the n struts.

use super::{run_case, Caps, Case, Measure, ScaleCase};
use crate::settings::SimSettings;
use crate::structure::{BodyKind, CableLaw, Inertia, Member, Structure, Vec3};
use std::f64::consts::{FRAC_PI_2, PI};

/// Radius of the drawn polygons [m].
const RADIUS_M: f64 = 1.0;
/// Height of the drawn prism [m].
const HEIGHT_M: f64 = 1.5;
/// The start's twist short of the closed form, as a fraction of the polygons' angle 2 pi / n
/// (20 degrees at n = 3, as `scenarios/custom/prism3.toml`).
const START_TWIST_OFFSET_FRACTION: f64 = 1.0 / 18.0;
/// Strain of the polygon cables in the closed-form shape; the side cables' follows from the
/// force densities (the closed-form shape is the equilibrium).
const POLYGON_STRAIN: f64 = 0.1;
/// Cable stiffness [N/m].
const CABLE_STIFFNESS_N_PER_M: f64 = 100.0;
/// Mass of each strut [kg].
const STRUT_MASS_KG: f64 = 1.0;
/// Time step [s] and body damping [1/s] (those of prism3.toml).
const DT_S: f64 = 0.005;
const BODY_DAMPING_PER_S: f64 = 2.0;
/// Steps after which a case counts as not settled.
const MAX_STEPS: u64 = 20_000;

fn polar(angle: f64, z: f64) -> Vec3 {
    [RADIUS_M * angle.cos(), RADIUS_M * angle.sin(), z]
}

fn distance(a: Vec3, b: Vec3) -> f64 {
    crate::structure::distance(a, b)
}

/// The n-strut prism drawn at `twist` \[rad\], rest lengths from the closed-form shape.
pub fn prism(n: usize, twist: f64) -> Structure {
    let closed = FRAC_PI_2 + PI / n as f64;
    let step = 2.0 * PI / n as f64;
    let mut s = Structure { name: format!("{n}-strut prism"), ..Default::default() };
    let (mut bottom, mut top) = (Vec::new(), Vec::new());
    for i in 0..n {
        let (b, t) = (polar(i as f64 * step, 0.0), polar(i as f64 * step + twist, HEIGHT_M));
        let length = distance(b, t);
        let inertia = Inertia {
            mass_kg: STRUT_MASS_KG,
            com: [0.5 * (b[0] + t[0]), 0.5 * (b[1] + t[1]), 0.5 * (b[2] + t[2])],
            // Isotropic: a slender rod's transverse moment about every axis.
            principal_kg_m2: [STRUT_MASS_KG * length * length / 12.0; 3],
        };
        let kind = if i == 0 { BodyKind::Fixed } else { BodyKind::Free };
        let body = s.add_body(&format!("strut{i}"), kind, (i > 0).then_some(inertia));
        bottom.push(s.add_node(&format!("B{i}"), body, b));
        top.push(s.add_node(&format!("T{i}"), body, t));
        s.members.push(Member::strut(format!("strut{i}"), bottom[i], top[i], 0.01));
    }
    let k = CABLE_STIFFNESS_N_PER_M;
    let polygon_length = distance(polar(0.0, 0.0), polar(step, 0.0));
    let side_length = distance(polar(0.0, 0.0), polar(closed - step, HEIGHT_M));
    let polygon_tension = POLYGON_STRAIN * k * polygon_length;
    // q_polygon = q_side / (2 sin(pi/n)), and the polygon's length is 2 r sin(pi/n).
    let side_density = polygon_tension / RADIUS_M;
    let polygon = polygon_length - polygon_tension / k;
    let side = side_length - side_density * side_length / k;
    let mut cable = |name: String, a: usize, b: usize, length_m: f64| {
        let law = CableLaw::Elastic { stiffness_n_per_m: k };
        s.members.push(Member::cable(name, vec![a, b], law, length_m, 0.001));
    };
    for i in 0..n {
        let j = (i + 1) % n;
        cable(format!("bottom{i}"), bottom[i], bottom[j], polygon);
        cable(format!("top{i}"), top[i], top[j], polygon);
        cable(format!("side{i}"), bottom[j], top[i], side);
    }
    s
}

/// Largest |twist - (pi/2 + pi/n)| over the struts of settled node positions (bottom node i
/// at 2 i, top node i at 2 i + 1) \[rad\], about the axis through the polygons' centroids.
pub fn twist_error(nodes: &[Vec3], n: usize) -> f64 {
    let centroid = |k: usize| {
        let mut c = [0.0; 3];
        for i in 0..n {
            for (x, p) in c.iter_mut().zip(nodes[2 * i + k]) {
                *x += p / n as f64;
            }
        }
        nalgebra::Vector3::from(c)
    };
    let (cb, ct) = (centroid(0), centroid(1));
    let axis = (ct - cb).normalize();
    let flat = |v: nalgebra::Vector3<f64>| v - axis * v.dot(&axis);
    let expected = FRAC_PI_2 + PI / n as f64;
    (0..n)
        .map(|i| {
            let u = flat(nalgebra::Vector3::from(nodes[2 * i]) - cb);
            let w = flat(nalgebra::Vector3::from(nodes[2 * i + 1]) - ct);
            let twist = u.cross(&w).dot(&axis).atan2(u.dot(&w));
            (twist - expected).abs()
        })
        .fold(0.0, f64::max)
}

/// Strut counts of the family.
pub const SIZES: [usize; 13] = [3, 4, 6, 8, 12, 16, 24, 32, 64, 128, 256, 512, 1000];

/// The n-strut prism's case: drawn `START_TWIST_OFFSET_FRACTION` of the polygons' angle short
/// of the closed-form twist, strut 1 held; compared by its twist.
pub fn case(n: usize) -> Case {
    case_with(n, true)
}

/// The case with the relaxation on or off (`false`: the plain dynamics, body damping alone).
pub fn case_with(n: usize, relaxation: bool) -> Case {
    let closed = FRAC_PI_2 + PI / n as f64;
    let start = prism(n, closed - START_TWIST_OFFSET_FRACTION * 2.0 * PI / n as f64);
    let design = prism(n, closed);
    Case {
        family: "prism",
        size: n,
        settings: SimSettings { dt_s: DT_S, body_damping_per_s: BODY_DAMPING_PER_S, relaxation, ..Default::default() },
        commands: Vec::new(),
        target: design.nodes.iter().enumerate().map(|(i, p)| (i, p.position)).collect(),
        measure: Measure::Twist,
        spin: None,
        drive: None,
        start,
    }
}

/// Settles the n-strut prism from its twisted start, as the settle loop does: stepping until
/// the speed stays below 1e-11 m/s per metre of size for 10 steps (the relaxation off once it is) and the
/// residual is below 1e-9 N and N m, at most `MAX_STEPS` steps.
/// `relaxation = false`: the plain dynamics (body damping alone), for comparison.
pub fn settle_prism(n: usize, relaxation: bool) -> Result<ScaleCase, crate::bench::BenchError> {
    let caps = Caps { max_steps: MAX_STEPS, ..super::DEFAULT_CAPS };
    run_case(&case_with(n, relaxation), &caps)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A prism drawn at the closed-form twist reads back with zero twist error (1e-14 rad).
    #[test]
    fn a_prism_drawn_at_the_closed_form_has_no_twist_error() {
        for n in [3, 4, 7] {
            let s = prism(n, FRAC_PI_2 + PI / n as f64);
            let nodes: Vec<Vec3> = s.nodes.iter().map(|p| p.position).collect();
            assert!(twist_error(&nodes, n) <= 1e-14, "n = {n}");
        }
    }

    /// The 3-, 4- and 6-strut prisms settle in at most 30 steps (measured 16) to the closed-form
    /// twist within 1e-12 rad, where the plain dynamics take over 1000 steps to the same twist
    /// within 1e-9 rad.
    #[test]
    fn small_prisms_settle_in_tens_of_steps_at_the_closed_form_twist() {
        for n in [3, 4, 6] {
            let fast = settle_prism(n, true).unwrap();
            let plain = settle_prism(n, false).unwrap();
            assert!(fast.settled && plain.settled, "n = {n}");
            assert!(fast.steps <= 30 && plain.steps > 1000, "n = {n}: {} and {} steps", fast.steps, plain.steps);
            let (fast_err, plain_err) = (fast.error, plain.error);
            assert!(fast_err <= 1e-12, "n = {n}: {fast_err} rad");
            assert!(plain_err <= 1e-9, "n = {n}: {plain_err} rad plain");
        }
    }
}
