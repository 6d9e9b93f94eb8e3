//! The findings of Furet, Lettl & Wenger (2018): every printed equation and claim of the
//! paper checked numerically against the model of [`super::analytic`] (which keeps the
//! paper's equations, by number).

use super::analytic::*;
use crate::mechanisms::finding::{check_all, EquationGroup};
use crate::mechanisms::{finding, Finding};
use nalgebra::Vector2;
use std::f64::consts::PI;

/// Representative joint angles [rad]: a 9 x 9 grid offset from the special values.
fn sample_joints() -> Vec<(f64, f64)> {
    let ts: Vec<f64> = (0..9).map(|k| -3.0 + 0.71 * k as f64 + 0.013).collect();
    let mut v = Vec::new();
    for &a in &ts {
        for &b in &ts {
            v.push((a, b));
        }
    }
    v
}

/// The paper's equations and claims, one group a function, in the order the findings print.
pub const EQUATION_GROUPS: &[EquationGroup<Params>] = &[
    EquationGroup { equations: &["Eq. 1", "Sec. 2.1"], check: node_geometry },
    EquationGroup { equations: &["Eq. 2", "Eq. 3"], check: direct_kinematics_in_series },
    EquationGroup { equations: &["Eq. 4", "Eq. 5", "Eq. 12"], check: crossed_bars_and_loop_closure },
    EquationGroup { equations: &["Eq. 6-11"], check: characteristic_quartic },
    EquationGroup { equations: &["Fig. 3"], check: fig_3_inverse_solutions },
    EquationGroup { equations: &["Eq. 13"], check: jacobian_determinant },
    EquationGroup { equations: &["Sec. 3", "Eq. 14"], check: singular_families },
    // Aspects, cuspidality, Fig. 5
    EquationGroup { equations: &["Sec. 3 / Fig. 4"], check: aspects_fig_4 },
    EquationGroup { equations: &["Sec. 3 (cuspidal)"], check: cuspidality },
    EquationGroup { equations: &["Sec. 4 / Fig. 5"], check: workspace_regions_fig_5 },
];

/// Every printed equation and claim checked against the derivation, with numbers: the findings
/// of every group of [`EQUATION_GROUPS`]. Generic identities use `sample_joints` with `p`;
/// figure claims use the paper's parameters (`L = 1`, `b` of Fig. 3 / Fig. 5).
pub fn findings(p: &Params) -> Vec<Finding> {
    check_all(EQUATION_GROUPS, p)
}

/// Eq. 1 and alpha = 2 theta: the mid-line length of an X mechanism and the rotation of its
/// top bar (Sec. 2.1), on the node geometry.
fn node_geometry(p: &Params) -> Vec<Finding> {
    let pts = sample_joints();
    let l = p.l;
    let (mut e1, mut ebar, mut ealpha) = (0.0f64, 0.0f64, 0.0f64);
    for &(t1, t2) in &pts {
        for g in x_nodes(p, t1, t2) {
            let sl = (g.top_left - g.base_left).norm();
            let sr = (g.top_right - g.base_right).norm();
            e1 = e1.max((0.5 * (sl + sr) - midline_length(p, g.theta)).abs());
            e1 = e1.max(((g.top_mid - g.base_mid).norm() - g.midline_length).abs());
            ebar = ebar
                .max(((g.top_right - g.base_left).norm() - p.l).abs())
                .max(((g.top_left - g.base_right).norm() - p.l).abs())
                .max(((g.top_right - g.top_left).norm() - p.b).abs());
            let d = g.top_right - g.top_left;
            ealpha = ealpha.max(wrap_angle(d.y.atan2(d.x) - g.base_angle - 2.0 * g.theta).abs());
        }
    }
    vec![
        finding("Eq. 1", "l_i = (l_i1 + l_i2)/2 = sqrt(L^2 - b^2 cos^2 theta_i)",
            format!("max error {e1:.1e} m on the node geometry (bar-length errors {ebar:.1e} m); springs are l -/+ b sin theta"), e1 < 1e-12 * l),
        finding("Sec. 2.1", "alpha_i = 2 theta_i; -pi < theta_i < pi is a full turn",
            format!("top-bar rotation minus 2 theta: max {ealpha:.1e} rad; over theta in (-pi, pi] the base-joint angle phi advances by {:.15} rad (2pi), strictly increasing (dphi/dtheta = 1 + b sin th / l > 0 since l^2 - b^2 sin^2 th = L^2 - b^2 > 0)", base_joint_angle_a(p, PI) - base_joint_angle_a(p, -PI)), ealpha < 1e-12),
    ]
}

/// Eq. 2, 3: the direct kinematics of X mechanisms in series (n = 2, 3) against the node chain.
fn direct_kinematics_in_series(p: &Params) -> Vec<Finding> {
    let pts = sample_joints();
    let l = p.l;
    let (mut e2, mut e3) = (0.0f64, 0.0f64);
    for &(t1, t2) in &pts {
        let g = x_nodes(p, t1, t2);
        let (x, y) = direct_kinematics(p, t1, t2);
        let (x2, y2) = direct_kinematics_n(p, &[t1, t2]);
        e3 = e3.max((g[1].top_mid - Vector2::new(x, y)).norm());
        e2 = e2.max((x2 - x).hypot(y2 - y));
        let c3 = chain_nodes(p, &[t1, t2, 0.37 * t1 - 0.2]);
        let (x3, y3) = direct_kinematics_n(p, &[t1, t2, 0.37 * t1 - 0.2]);
        e2 = e2.max((c3[2].top_mid - Vector2::new(x3, y3)).norm());
    }
    vec![
        finding("Eq. 2", "DK of n mechanisms in series as a virtual nR arm with link l_i(theta_i) at angle (pi-2th_i)/2 + sum_{j<=i} 2th_j",
            format!("max error vs node chain (n = 2, 3) {e2:.1e} m"), e2 < 1e-12 * l),
        finding(
            "Eq. 3",
            "x = -l1 sin th1 - l2 sin(2th1+th2), y = l1 cos th1 + l2 cos(2th1+th2)",
            format!("max error vs node chain {e3:.1e} m"),
            e3 < 1e-12 * l,
        ),
    ]
}

/// Eq. 4, 5, 12: the direct kinematics in the base-joint angles (Eq. 4), the loop closures
/// (Eq. 5) and alpha from phi (Eq. 12).
fn crossed_bars_and_loop_closure(p: &Params) -> Vec<Finding> {
    let pts = sample_joints();
    let l = p.l;
    let (mut e4, mut e5, mut e12) = (0.0f64, 0.0f64, 0.0f64);
    for &(t1, t2) in &pts {
        let (phi1, psi2) = (base_joint_angle_a(p, t1), base_joint_angle_b(p, t2));
        let (x, y) = direct_kinematics(p, t1, t2);
        let (x4, y4) = direct_kinematics_crossed_bars_eq4(p, phi1, psi2, 2.0 * t1, 2.0 * t2);
        e4 = e4.max((x4 - x).hypot(y4 - y));
        let (r1, r2) = loop_closure_eq5(p, phi1, 2.0 * t1, psi2, 2.0 * t2);
        e5 = e5.max(r1.abs()).max(r2.abs());
        let half = p.b - p.l * phi1.cos();
        let ta = (p.l * phi1.sin() * t1.sin() - half * t1.cos()).abs(); // tan(alpha/2) = half / (L sin phi)
        e12 = e12.max(ta).max(wrap_angle(theta_from_base_joint_angle_a(p, phi1) - t1).abs());
    }
    vec![
        finding(
            "Eq. 4",
            "x = -b/2 + L cos phi1 + L cos(psi2 + alpha1) + b/2 cos(alpha1 + alpha2), y likewise",
            format!("with phi1, psi2 the base-joint angles: max error {e4:.1e} m"),
            e4 < 1e-12 * l,
        ),
        finding("Eq. 5", "loop closures of X1 (phi1, alpha1) and X2 (psi2, alpha2)",
            format!("max |residual| {e5:.1e} m^2 on the crossed mode; both are 4b cos th [b cos th -/+ L cos(angle - th)] so they also vanish at alpha = pi (parallelogram/change point)"), e5 < 1e-12 * l * l),
        finding(
            "Eq. 12",
            "tan(alpha1/2) = (-L cos phi1 + b)/(L sin phi1)",
            format!("max error (cross-multiplied, and theta recovered by atan2) {e12:.1e}"),
            e12 < 1e-12 * l,
        ),
    ]
}

/// Eq. 6-11: the printed coefficients of the characteristic quartic in tan(phi1/2), and its roots.
fn characteristic_quartic(p: &Params) -> Vec<Finding> {
    let pts = sample_joints();
    let mut e = 0.0f64;
    let q = Params { l: 1.0, b: p.b / p.l };
    for &(t1, t2) in &pts {
        let (x, y) = direct_kinematics(p, t1, t2);
        let d = quartic_coefficients(p, x, y);
        let pr = quartic_coefficients_eq7_11_as_printed(p, x, y);
        let (xq, yq) = (x / p.l, y / p.l);
        let d1 = quartic_coefficients(&q, xq, yq);
        let pr1 = quartic_coefficients_eq7_11_as_printed(&q, xq, yq);
        let sc = d.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        let sc1 = d1.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        for k in 0..5 {
            e = e.max((d[k] - pr[k]).abs() / sc).max((d1[k] - pr1[k]).abs() / sc1);
        }
    }
    // the quartic has the right roots
    let mut er = 0.0f64;
    for &(t1, t2) in &pts {
        let (x, y) = direct_kinematics(p, t1, t2);
        let phi = base_joint_angle_a(p, t1);
        let t = (0.5 * phi).tan();
        if t.abs() > 1e3 {
            continue;
        }
        let a = quartic_coefficients_eq7_11_as_printed(p, x, y);
        let v = (((a[0] * t + a[1]) * t + a[2]) * t + a[3]) * t + a[4];
        let sc = a.iter().fold(0.0f64, |m, v| m.max(v.abs())) * (1.0 + t.abs()).powi(4);
        er = er.max(v.abs() / sc);
    }
    vec![
        finding("Eq. 6-11", "characteristic quartic in t = tan(phi1/2), L = 1",
            format!("printed a4..a0 equal the derived ones (max rel. diff {e:.1e}; derivation's numerator = 16 ((L-b)^2+(L+b)^2 t^2)^3 (1+t^2)^7 q(t)); relative value at t = tan(phi1/2) of known configurations <= {er:.1e}; any L by scaling: q_L(x,y) = L^6 q_1(x/L, y/L; b/L)"), e < 1e-12 && er < 1e-10),
    ]
}

/// Fig. 3: the four inverse solutions at the figure's point.
fn fig_3_inverse_solutions(_: &Params) -> Vec<Finding> {
    let q = Params::PAPER;
    let (x, y) = PAPER_FIG3_POINT;
    let s = inverse_kinematics(&q, x, y);
    let npos = s.iter().filter(|v| v.aspect > 0).count();
    let txt: Vec<String> =
        s.iter().map(|v| format!("({:.4}, {:.4}) detJ {:+.4}", v.theta1, v.theta2, v.det_j)).collect();
    vec![finding(
        "Fig. 3",
        "L = 1, b = 2/3, (x, y) = (0.03, 1.6): four inverse solutions",
        format!("{} solutions (theta1, theta2) [rad]: {}; {} with det J > 0", s.len(), txt.join(", "), npos),
        s.len() == 4,
    )]
}

/// Eq. 13: the printed det J, against l1 l2 det J and on the singularity th1 = -th2 + pi.
fn jacobian_determinant(p: &Params) -> Vec<Finding> {
    let pts = sample_joints();
    let (mut ep, mut ec, mut scale) = (0.0f64, 0.0f64, 0.0f64);
    let mut on_fold = 0.0f64;
    for &(t1, t2) in &pts {
        let want = det_jacobian(p, t1, t2) * midline_length(p, t1) * midline_length(p, t2);
        scale = scale.max(want.abs());
        ep = ep.max((det_jacobian_eq13_as_printed(p, t1, t2) - want).abs());
        ec = ec.max((det_jacobian_eq13_corrected(p, t1, t2) - want).abs());
        on_fold = on_fold.max(det_jacobian_eq13_as_printed(p, singular_theta1_folded(t2), t2).abs());
    }
    let l4 = p.l.powi(4);
    vec![
        finding("Eq. 13", "Det(J) = (sin^2 th1 b^2 cos th1 - l1^2 (cos th1 + 2 cos(th2+2th1))) (...) - (...) (cos^2 th1 b^2 sin th1 - l1^2 (sin th1 + 2 sin(th2+2th1)))",
            format!("wrong: it is not proportional to det J: max |Eq13 - l1 l2 det J| = {ep:.3} m^4 (max |l1 l2 det J| = {scale:.3}); and it does not vanish on the singularity th1 = -th2 + pi (max |Eq13| there {on_fold:.3} = {:.3} L^4). Corrected (first factor -b^2 s1^2 c1, and 2 l1 l2 instead of 2 l1^2 in the first and fourth factors): error {ec:.1e}", on_fold / l4),
            ep < 1e-9 * l4),
    ]
}

/// Singularities: first family and Eq. 14 (det J = 0 on th1 = -th2 +- pi, Sec. 3, and on the
/// second family of Eq. 14).
fn singular_families(p: &Params) -> Vec<Finding> {
    let l = p.l;
    let (mut e_fold, mut e_origin, mut e14) = (0.0f64, 0.0f64, 0.0f64);
    let mut e14_match = 0.0f64;
    let mut nroots_ok = true;
    for k in 0..40 {
        let t2 = -PI + 0.05 + k as f64 * TWO_PI / 40.0;
        let tf = singular_theta1_folded(t2);
        e_fold = e_fold.max(det_jacobian(p, tf, t2).abs());
        let (x, y) = direct_kinematics(p, tf, t2);
        e_origin = e_origin.max(x.hypot(y));
        let t14 = singular_theta1_eq14(p, t2);
        e14 = e14.max(det_jacobian(p, t14, t2).abs());
        let roots = singular_theta1_numeric(p, t2, 720);
        nroots_ok &= roots.len() == 2;
        let dmin = roots.iter().map(|r| wrap_angle(r - t14).abs()).fold(f64::INFINITY, f64::min);
        e14_match = e14_match.max(dmin);
    }
    let l2 = p.l * p.l;
    vec![
        finding(
            "Sec. 3",
            "det J = 0 for theta1 = -theta2 +- pi; the end point is then the origin",
            format!("max |det J| there {e_fold:.1e} m^2; max |(x, y)| {e_origin:.1e} m"),
            e_fold < 1e-12 * l2 && e_origin < 1e-12 * l,
        ),
        finding("Eq. 14", "second singular family theta1 = atan2(-sin th2 (4b^4c^4 - 4L^2b^2c^2 - L^2b^2 + L^4), cos th2 (4b^4c^4 - 4b^4c^2 - 4L^2b^2c^2 + 3L^2b^2 + L^4))",
            format!("max |det J| on it {e14:.1e} m^2; it coincides with the second numeric root of det J = 0 in theta1 (max distance {e14_match:.1e} rad); exactly two roots per theta2 at 40 samples: {nroots_ok}"), e14 < 1e-12 * l2 && e14_match < 1e-9 && nroots_ok),
    ]
}

// Aspects, cuspidality, Fig. 5: on the paper's parameters `Params::PAPER` (and Fig. 5's b).

/// Aspects (Sec. 3 / Fig. 4): the singularities divide the joint torus into two aspects.
fn aspects_fig_4(_: &Params) -> Vec<Finding> {
    let q = Params::PAPER;
    let na = aspect_count(&q, 256);
    vec![finding(
        "Sec. 3 / Fig. 4",
        "L = 1, b = 2/3: the singularities divide the joint torus into two aspects",
        format!("{na} connected components of sign(det J) on a 256 x 256 torus grid"),
        na == 2,
    )]
}

/// Cuspidality (Sec. 3): two solutions in each aspect at the Fig. 3 point, joined by
/// non-singular paths.
fn cuspidality(_: &Params) -> Vec<Finding> {
    let q = Params::PAPER;
    let (x, y) = PAPER_FIG3_POINT;
    let s = inverse_kinematics(&q, x, y);
    let pos: Vec<&IkSolution> = s.iter().filter(|v| v.aspect > 0).collect();
    let neg: Vec<&IkSolution> = s.iter().filter(|v| v.aspect < 0).collect();
    let mut mins = Vec::new();
    for grp in [&pos, &neg] {
        if grp.len() == 2 {
            if let Some(path) =
                nonsingular_path(&q, (grp[0].theta1, grp[0].theta2), (grp[1].theta1, grp[1].theta2), 192)
            {
                mins.push(min_abs_det_along(&q, &path, 200));
            }
        }
    }
    vec![
        finding("Sec. 3 (cuspidal)", "two solutions in each aspect; non-singular solution-changing motions exist",
            format!("at (0.03, 1.6): {} solutions with det J > 0, {} with det J < 0; non-singular paths found for {} of 2 pairs, min |det J| along them {:?} m^2", pos.len(), neg.len(), mins.len(), mins),
            pos.len() == 2 && neg.len() == 2 && mins.len() == 2 && mins.iter().all(|m| *m > 0.0)),
    ]
}

/// Fig. 5 (Sec. 4): the 2- and 4-solution regions of the workspace for the figure's b.
fn workspace_regions_fig_5(_: &Params) -> Vec<Finding> {
    let grid = 120;
    let mut txt = Vec::new();
    let mut fr4 = Vec::new();
    let mut both = true;
    for &b in &PAPER_FIG5_B {
        let r = region_area_fractions(&Params { l: 1.0, b }, grid);
        txt.push(format!(
            "b = {b:.3}: workspace {:.3} m^2, 2-sol {:.4}, 4-sol {:.4}, other {:.4}",
            r.workspace_area, r.frac_2, r.frac_4, r.frac_other
        ));
        fr4.push(r.frac_4);
        // both aspects cover the workspace: equal counts in each aspect at sample points
        let qb = Params { l: 1.0, b };
        for k in 0..60 {
            let (t1, t2) = (-3.0 + 0.1 * k as f64, 2.9 - 0.093 * k as f64);
            let (x, y) = direct_kinematics(&qb, t1, t2);
            let s = inverse_kinematics(&qb, x, y);
            let np = s.iter().filter(|v| v.aspect > 0).count();
            if np * 2 != s.len() && det_jacobian(&qb, t1, t2).abs() > 1e-3 {
                both = false;
            }
        }
    }
    vec![
        finding("Sec. 4 / Fig. 5", "b = 2/5: workspace of 2-solution points only; b = 2/3, 9/10: two 4-solution regions that grow with b; each aspect maps onto the whole workspace",
            format!("{} ({grid} x {grid} grid over [-2L, 2L]^2, fractions of the workspace area); solutions split equally between the aspects at 60 sample points for each b: {both}", txt.join("; ")),
            fr4[0] == 0.0 && fr4[1] > 0.0 && fr4[2] > fr4[1] && both),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanisms::finding::check_equation;
    use crate::mechanisms::finding::testing::number_after;

    const P: Params = Params::PAPER;

    #[test]
    fn eq_13_printed_det_j_is_off_by_0_263_m4_and_misses_the_singularity() {
        let f = check_equation(EQUATION_GROUPS, &P, "Eq. 13").unwrap();
        assert!(!f.holds, "{}", f.measured);
        // L = 1, b = 2/3: max |Eq13 - l1 l2 det J| 0.263 m^4 and |Eq13| 0.274 on th1 = -th2 + pi (3 digits printed).
        assert!((number_after(&f.measured, "max |Eq13 - l1 l2 det J| = ") - 0.263).abs() < 5e-4, "{}", f.measured);
        assert!((number_after(&f.measured, "max |Eq13| there ") - 0.274).abs() < 5e-4, "{}", f.measured);
        assert!(number_after(&f.measured, "factors): error ") < 1e-12, "corrected Eq. 13: {}", f.measured);
    }

    #[test]
    fn findings_report_expected_verdicts() {
        let f = findings(&P);
        let verdict = |e: &str| f.iter().find(|x| x.equation == e).unwrap_or_else(|| panic!("{e}")).holds;
        for e in [
            "Eq. 1",
            "Eq. 2",
            "Eq. 3",
            "Eq. 4",
            "Eq. 5",
            "Eq. 6-11",
            "Eq. 12",
            "Eq. 14",
            "Fig. 3",
            "Sec. 3",
            "Sec. 3 / Fig. 4",
            "Sec. 3 (cuspidal)",
            "Sec. 4 / Fig. 5",
        ] {
            assert!(verdict(e), "{e} should hold: {:?}", f.iter().find(|x| x.equation == e));
        }
        assert!(!verdict("Eq. 13"));
    }
}
