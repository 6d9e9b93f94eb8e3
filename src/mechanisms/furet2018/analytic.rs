//! Closed-form kinematic model of the planar tensegrity 2-X manipulator of
//! Furet, Lettl & Wenger (2018), "Kinematic analysis of planar tensegrity 2-X
//! manipulators", Advances in Robot Kinematics (ARK 2018), hal-01791317.
//!
//! Everything here is a pure function of `f64` / `nalgebra` values.
//! Units: lengths in metres \[m\], angles in radians \[rad\]; `det J` in [m^2/rad^2].
//!
//! # One X mechanism (Snelson's X, a crossed four-bar / anti-parallelogram)
//! Local frame: origin at the middle of the base bar, `x` along the base bar
//! (from the base-left node `A` to the base-right node `B`), `y` to the side
//! of the top bar when `theta = 0`; angles counter-clockwise positive.
//! * base bar `A = (-b/2, 0)`, `B = (b/2, 0)`; top bar `D` (top-left) - `C`
//!   (top-right), length `b`;
//! * crossed bars `A-C` and `B-D`, length `L > b` (assembly condition);
//! * springs on the lateral sides `A-D` (left, `l_left`) and `B-C` (right, `l_right`).
//!
//! `A, B, C, D` form an isosceles trapezoid whose parallel sides are the two
//! springs. `theta` is the angle from the base-bar normal `+y` to the segment
//! joining the base and top midpoints (the trapezoid mid-line), CCW positive:
//! * mid-line `u = (-sin th, cos th)`, length `l(th) = sqrt(L^2 - b^2 cos^2 th)` (Eq. 1);
//! * top midpoint `M = l u`; top bar direction `e = (cos 2th, sin 2th)`, so the top
//!   bar is rotated by `alpha = 2 theta` relative to the base bar;
//! * `D = M - b/2 e`, `C = M + b/2 e`;
//! * springs `l_left = |AD| = l - b sin th`, `l_right = |BC| = l + b sin th`,
//!   both parallel to `u`, and `(l_left + l_right)/2 = l` (Eq. 1).
//!
//! `theta` is not a joint angle. The base-joint angles are
//! `phi = angle(A->C) = th + atan2(l, b cos th)` at `A` and
//! `psi = angle(B->D) = th + atan2(l, -b cos th)` at `B`, both measured CCW from
//! the base direction `A->B` (the paper's `phi_1`, `psi_2` of Eq. 4). Each is a
//! strictly increasing bijection of the circle (`dphi/dth = 1 + b sin th / l > 0`),
//! inverted by Eq. 12: `th = atan2(b - L cos phi, L sin phi)`, so a rotary actuator
//! at a base joint imposes `theta` uniquely. The X exists for every `theta`; at
//! `theta = +-pi/2` (`phi = pi` resp. `0`) all four nodes are collinear: the
//! change point where the crossed mode meets the parallelogram mode (`alpha = pi`),
//! the only place where a base-joint actuator does not fix the assembly mode.
//!
//! # Two X in series (Eq. 2-3)
//! Mechanism 2 stands on the top bar of mechanism 1 (its base-left node is `D1`,
//! base-right `C1`). World frame = local frame of mechanism 1. End point = top
//! midpoint `M2`:
//! `x = -l1 sin th1 - l2 sin(2th1+th2)`, `y = l1 cos th1 + l2 cos(2th1+th2)`.
//! Top bar 2 orientation `2 th1 + 2 th2`.
//!
//! # Key derived results (see [`findings`](super::findings::findings) for the numeric checks)
//! * Eq. 1-5, 6-11 (characteristic quartic in `t = tan(phi1/2)`), 12 and 14 hold.
//!   The quartic, derived here for any `L`, is homogeneous of degree 6 in
//!   `(L, b, x, y)` and equals the printed `L = 1` one after scaling.
//! * Eq. 13 (det J) as printed is wrong; `l1 l2 det J` is
//!   `(-b^2 s1^2 c1 - l1^2 c1 - 2 l1 l2 cos s)(b^2 c2 s2 cos s - l2^2 sin s)
//!   - (-b^2 c2 s2 sin s - l2^2 cos s)(b^2 c1^2 s1 - l1^2 s1 - 2 l1 l2 sin s)`,
//!   `s = 2th1 + th2` (printed: `+b^2 s1^2 c1` and `l1^2` where `l1 l2` belongs).
//! * Every real root of the quartic is a solution (one `theta2` per root), so the
//!   number of solutions is the number of real roots: 0, 2 or 4.
//! * `L = 1`, fractions of the workspace area (800 x 800 grid): `b = 2/5`: workspace
//!   11.735 m^2, all of it 2-solution; `b = 2/3`: 10.945 m^2, 4-solution 2.107 %;
//!   `b = 9/10`: 10.298 m^2, 4-solution 15.62 %. The 4-solution regions (around the
//!   `y` axis, near `(0, +-1.5)`) vanish below `b ~ 0.4101 L` (scan of the `y` axis).
//! * Off the singular curves, the solutions at a point are split equally between the
//!   two aspects (`det J > 0` / `< 0`); two same-aspect solutions are joined by
//!   [`nonsingular_path`] (the manipulator is cuspidal).

/// Wraps an angle to `(-pi, pi]` (one definition for the testbed, in `mechanisms`).
pub use crate::mechanisms::wrap_angle;
use crate::mechanisms::ParamError;
use nalgebra::{Complex, Matrix2, Matrix4, Vector2};
use std::collections::VecDeque;
use std::f64::consts::{FRAC_PI_2, PI};

/// Full turn [rad].
pub(super) const TWO_PI: f64 = 2.0 * PI;
/// Fig. 3 / Fig. 4: `L = 1`, `b = 2/3` (paper sets `L = 1`, units arbitrary: metres here).
pub const PAPER_FIG3_B: f64 = 2.0 / 3.0;
/// Fig. 3: target `(x, y) = (0.03, 1.6)` \[m\] with four inverse solutions.
pub const PAPER_FIG3_POINT: (f64, f64) = (0.03, 1.6);
/// Fig. 5: the three base/top bar lengths `b` (with `L = 1`).
pub const PAPER_FIG5_B: [f64; 3] = [2.0 / 5.0, 2.0 / 3.0, 9.0 / 10.0];
/// Change points of one X: at `theta = +-pi/2` the four nodes are collinear.
pub const CHANGE_POINT_THETA: f64 = FRAC_PI_2;
/// Inverse kinematics: every returned solution reproduces `(x, y)` through
/// [`direct_kinematics`] to within this tolerance times `L`.
pub const IK_VERIFY_REL_TOL: f64 = 1e-9;
/// A quartic root with `|Im t| <= IK_IMAG_REL_TOL (1 + |t|)` is tried as a real root
/// (it is then polished and must pass the `IK_VERIFY_REL_TOL` check).
const IK_IMAG_REL_TOL: f64 = 1e-6;
/// Newton steps polishing a quartic root, then the joint-space solution.
const IK_NEWTON_STEPS: usize = 4;
/// Two IK solutions closer than this (max over both wrapped angles) [rad] are merged.
const IK_DUPLICATE_TOL: f64 = 1e-7;
/// `(x, y)` closer than this times `L` to the origin is the self-motion point
/// (the whole family `theta1 + theta2 = +-pi` maps there).
const ORIGIN_REL_TOL: f64 = 1e-12;
/// Half-width of the workspace bounding square, in units of `L` (max reach `2L`).
const REACH_OVER_L: f64 = 2.0;
/// Fine resampling of a joint-space path: samples per grid step when checking segments.
const PATH_SAMPLES_PER_CELL: f64 = 4.0;
/// Clearance ladder for [`nonsingular_path`]: allowed cells need
/// `|det J| > margin * max|det J|`, tried from the safest margin down.
const PATH_MARGINS: [f64; 7] = [0.2, 0.1, 0.05, 0.02, 0.01, 0.003, 0.0];

/// Mechanism parameters (identical X mechanisms).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Crossed-bar length `L` \[m\].
    pub l: f64,
    /// Base and top bar length `b` \[m\].
    pub b: f64,
}

impl Params {
    /// Fig. 3-4: `L = 1 m`, `b = 2/3 m`.
    pub const PAPER: Params = Params { l: 1.0, b: PAPER_FIG3_B };

    /// `L` and `b` finite, `b > 0`, `L > b` (crossed-bar assembly condition).
    pub fn validate(&self) -> Result<(), ParamError> {
        for (name, value) in [("L", self.l), ("b", self.b)] {
            if !value.is_finite() {
                return Err(ParamError::NotFinite { name, value });
            }
        }
        if self.b <= 0.0 {
            return Err(ParamError::NotPositive { name: "b", value: self.b });
        }
        if self.l <= self.b {
            return Err(ParamError::Condition(format!(
                "L must be > b (assembly condition), got L = {} <= b = {}",
                self.l, self.b
            )));
        }
        Ok(())
    }
}

fn rot(a: f64) -> Vector2<f64> {
    Vector2::new(a.cos(), a.sin())
}

// ---------------------------------------------------------------------------
// One X mechanism.
// ---------------------------------------------------------------------------

/// Eq. 1: mid-line length `l(theta) = sqrt(L^2 - b^2 cos^2 theta)` \[m\]
/// (in `[sqrt(L^2-b^2), L]`).
pub fn midline_length(p: &Params, theta: f64) -> f64 {
    let c = theta.cos();
    (p.l * p.l - p.b * p.b * c * c).sqrt()
}

/// `dl/dtheta = b^2 sin th cos th / l` [m/rad].
pub fn midline_length_rate(p: &Params, theta: f64) -> f64 {
    let (s, c) = theta.sin_cos();
    p.b * p.b * s * c / midline_length(p, theta)
}

/// Spring (lateral side) lengths `(l_left, l_right) = (|AD|, |BC|) = (l - b sin th, l + b sin th)` \[m\].
/// Both are `> 0` for every `theta` since `l^2 - b^2 sin^2 th = L^2 - b^2 > 0`.
pub fn spring_lengths(p: &Params, theta: f64) -> (f64, f64) {
    let l = midline_length(p, theta);
    let bs = p.b * theta.sin();
    (l - bs, l + bs)
}

/// Base-joint angle at `A` \[rad\]: angle of the crossed bar `A->C` measured CCW from
/// the base direction `A->B`: `phi = theta + atan2(l, b cos theta)` (the paper's
/// `phi_1`). Continuous and increasing in `theta`, `phi(theta + 2pi) = phi + 2pi`;
/// `phi(0) = atan2(sqrt(L^2-b^2), b)`, `phi(pi/2) = pi`, `phi(-pi/2) = 0`.
pub fn base_joint_angle_a(p: &Params, theta: f64) -> f64 {
    theta + midline_length(p, theta).atan2(p.b * theta.cos())
}

/// Inverse of [`base_joint_angle_a`] (Eq. 12 with `alpha = 2 theta`):
/// `theta = atan2(b - L cos phi, L sin phi)`, in `(-pi, pi]`.
pub fn theta_from_base_joint_angle_a(p: &Params, phi: f64) -> f64 {
    (p.b - p.l * phi.cos()).atan2(p.l * phi.sin())
}

/// Transmission ratio `dphi/dtheta = 1 + b sin theta / l` (> 0) [rad/rad].
pub fn base_joint_rate_a(p: &Params, theta: f64) -> f64 {
    1.0 + p.b * theta.sin() / midline_length(p, theta)
}

/// Base-joint angle at `B` \[rad\]: angle of the crossed bar `B->D` measured CCW from the
/// base direction `A->B`: `psi = theta + atan2(l, -b cos theta)` (the paper's `psi_2`).
pub fn base_joint_angle_b(p: &Params, theta: f64) -> f64 {
    theta + midline_length(p, theta).atan2(-p.b * theta.cos())
}

/// Inverse of [`base_joint_angle_b`]: `theta = atan2(-(b + L cos psi), L sin psi)`, in `(-pi, pi]`.
pub fn theta_from_base_joint_angle_b(p: &Params, psi: f64) -> f64 {
    (-(p.b + p.l * psi.cos())).atan2(p.l * psi.sin())
}

/// Transmission ratio `dpsi/dtheta = 1 - b sin theta / l` (> 0) [rad/rad].
pub fn base_joint_rate_b(p: &Params, theta: f64) -> f64 {
    1.0 - p.b * theta.sin() / midline_length(p, theta)
}

/// Distance to the change points, `|cos theta|` (0 at `theta = +-pi/2`, where the
/// four nodes are collinear and the crossed mode can switch to the parallelogram mode).
pub fn crossed_mode_margin(theta: f64) -> f64 {
    theta.cos().abs()
}

/// Full geometry of one X mechanism in world coordinates \[m\] / \[rad\].
#[derive(Clone, Copy, Debug)]
pub struct XGeometry {
    /// Base-left node `A` (for X2: the top-left node of X1).
    pub base_left: Vector2<f64>,
    /// Base-right node `B` (for X2: the top-right node of X1).
    pub base_right: Vector2<f64>,
    /// Top-left node `D` (crossed bar `B-D`, spring `A-D`).
    pub top_left: Vector2<f64>,
    /// Top-right node `C` (crossed bar `A-C`, spring `B-C`).
    pub top_right: Vector2<f64>,
    /// Base-bar midpoint.
    pub base_mid: Vector2<f64>,
    /// Top-bar midpoint (for the last X: the end point `(x, y)`).
    pub top_mid: Vector2<f64>,
    /// World orientation of the base bar (`A->B`) \[rad\].
    pub base_angle: f64,
    /// World orientation of the top bar (`D->C`) = `base_angle + 2 theta` \[rad\].
    pub top_angle: f64,
    /// The paper's `theta_i` \[rad\].
    pub theta: f64,
    /// Eq. 1 mid-line length `l_i` \[m\].
    pub midline_length: f64,
    /// `|AD| = l - b sin theta` \[m\].
    pub spring_left: f64,
    /// `|BC| = l + b sin theta` \[m\].
    pub spring_right: f64,
    /// Base-joint angle at `A` (crossed bar `A->C` relative to the base bar) \[rad\].
    pub joint_angle_a: f64,
    /// Base-joint angle at `B` (crossed bar `B->D` relative to the base bar) \[rad\].
    pub joint_angle_b: f64,
}

/// Geometry of `n = thetas.len()` X mechanisms in series (Eq. 2 chain): X1's base is
/// centred at the origin along `+x`; X(i+1) stands on the top bar of X(i).
pub fn chain_nodes(p: &Params, thetas: &[f64]) -> Vec<XGeometry> {
    let mut out = Vec::with_capacity(thetas.len());
    let mut origin = Vector2::zeros();
    let mut beta = 0.0f64;
    let hb = 0.5 * p.b;
    for &th in thetas {
        let l = midline_length(p, th);
        let u = rot(beta + FRAC_PI_2 + th);
        let e = rot(beta + 2.0 * th);
        let base_dir = rot(beta);
        let m = origin + l * u;
        let (sl, sr) = spring_lengths(p, th);
        out.push(XGeometry {
            base_left: origin - hb * base_dir,
            base_right: origin + hb * base_dir,
            top_left: m - hb * e,
            top_right: m + hb * e,
            base_mid: origin,
            top_mid: m,
            base_angle: beta,
            top_angle: beta + 2.0 * th,
            theta: th,
            midline_length: l,
            spring_left: sl,
            spring_right: sr,
            joint_angle_a: base_joint_angle_a(p, th),
            joint_angle_b: base_joint_angle_b(p, th),
        });
        origin = m;
        beta += 2.0 * th;
    }
    out
}

/// The two X mechanisms of the manipulator at `(theta1, theta2)` \[rad\].
pub fn x_nodes(p: &Params, theta1: f64, theta2: f64) -> [XGeometry; 2] {
    let v = chain_nodes(p, &[theta1, theta2]);
    [v[0], v[1]]
}

// ---------------------------------------------------------------------------
// Direct kinematics.
// ---------------------------------------------------------------------------

/// Eq. 2 as printed: end point of `n` X mechanisms in series \[m\],
/// `x = sum l_i cos((pi - 2th_i)/2 + sum_{j<=i} 2th_j)`, `y` with `sin`.
pub fn direct_kinematics_n(p: &Params, thetas: &[f64]) -> (f64, f64) {
    let (mut x, mut y, mut acc) = (0.0, 0.0, 0.0);
    for &th in thetas {
        acc += 2.0 * th;
        let a = 0.5 * (PI - 2.0 * th) + acc;
        let l = midline_length(p, th);
        x += l * a.cos();
        y += l * a.sin();
    }
    (x, y)
}

/// Eq. 3: end point `(x, y)` \[m\] of the 2-X manipulator,
/// `x = -l1 sin th1 - l2 sin(2th1+th2)`, `y = l1 cos th1 + l2 cos(2th1+th2)`.
pub fn direct_kinematics(p: &Params, theta1: f64, theta2: f64) -> (f64, f64) {
    let (l1, l2) = (midline_length(p, theta1), midline_length(p, theta2));
    let s = 2.0 * theta1 + theta2;
    (-l1 * theta1.sin() - l2 * s.sin(), l1 * theta1.cos() + l2 * s.cos())
}

/// Eq. 4: end point \[m\] from the crossed-bar angles `phi1` (at `A1`), `psi2` (at `B2`,
/// relative to X2's base) and the relative top-bar rotations `alpha1`, `alpha2` \[rad\].
pub fn direct_kinematics_crossed_bars_eq4(p: &Params, phi1: f64, psi2: f64, alpha1: f64, alpha2: f64) -> (f64, f64) {
    let (l, b) = (p.l, p.b);
    (
        -0.5 * b + l * phi1.cos() + l * (psi2 + alpha1).cos() + 0.5 * b * (alpha1 + alpha2).cos(),
        l * phi1.sin() + l * (psi2 + alpha1).sin() + 0.5 * b * (alpha1 + alpha2).sin(),
    )
}

/// Eq. 5 residuals [m^2] (zero on the crossed mode):
/// `(-2Lb sin a1 sin phi1 - 2Lb (cos a1 + 1) cos phi1 + 2b^2 (cos a1 + 1),
///    2Lb sin a2 sin psi2 + 2Lb (cos a2 + 1) cos psi2 + 2b^2 (cos a2 + 1))`.
/// Derived: they equal `4b cos th [b cos th - L cos(phi - th)]` and
/// `4b cos th [b cos th + L cos(psi - th)]` with `alpha = 2 th`.
pub fn loop_closure_eq5(p: &Params, phi1: f64, alpha1: f64, psi2: f64, alpha2: f64) -> (f64, f64) {
    let (l, b) = (p.l, p.b);
    (
        -2.0 * l * b * alpha1.sin() * phi1.sin() - 2.0 * l * b * (alpha1.cos() + 1.0) * phi1.cos()
            + 2.0 * b * b * (alpha1.cos() + 1.0),
        2.0 * l * b * alpha2.sin() * psi2.sin()
            + 2.0 * l * b * (alpha2.cos() + 1.0) * psi2.cos()
            + 2.0 * b * b * (alpha2.cos() + 1.0),
    )
}

// ---------------------------------------------------------------------------
// Jacobian and singularities.
// ---------------------------------------------------------------------------

/// `J = d(x, y)/d(theta1, theta2)` [m/rad] of Eq. 3 (rows x, y; columns th1, th2).
pub fn jacobian(p: &Params, theta1: f64, theta2: f64) -> Matrix2<f64> {
    let (l1, l2) = (midline_length(p, theta1), midline_length(p, theta2));
    let (d1, d2) = (midline_length_rate(p, theta1), midline_length_rate(p, theta2));
    let (s1, c1) = theta1.sin_cos();
    let (ss, cs) = (2.0 * theta1 + theta2).sin_cos();
    Matrix2::new(
        -d1 * s1 - l1 * c1 - 2.0 * l2 * cs,
        -d2 * ss - l2 * cs,
        d1 * c1 - l1 * s1 - 2.0 * l2 * ss,
        d2 * cs - l2 * ss,
    )
}

/// `det J` [m^2/rad^2] (derived).
pub fn det_jacobian(p: &Params, theta1: f64, theta2: f64) -> f64 {
    jacobian(p, theta1, theta2).determinant()
}

/// Derived counterpart of Eq. 13: `l1 l2 det J` [m^4/rad^2]
/// `= (-b^2 s1^2 c1 - l1^2 c1 - 2 l1 l2 cos s)(b^2 c2 s2 cos s - l2^2 sin s)
///  - (-b^2 c2 s2 sin s - l2^2 cos s)(b^2 c1^2 s1 - l1^2 s1 - 2 l1 l2 sin s)`, `s = 2th1+th2`.
pub fn det_jacobian_eq13_corrected(p: &Params, theta1: f64, theta2: f64) -> f64 {
    let b2 = p.b * p.b;
    let (l1, l2) = (midline_length(p, theta1), midline_length(p, theta2));
    let (s1, c1) = theta1.sin_cos();
    let (s2, c2) = theta2.sin_cos();
    let (ss, cs) = (2.0 * theta1 + theta2).sin_cos();
    (-b2 * s1 * s1 * c1 - l1 * l1 * c1 - 2.0 * l1 * l2 * cs) * (cs * b2 * c2 * s2 - l2 * l2 * ss)
        - (-ss * b2 * c2 * s2 - l2 * l2 * cs) * (c1 * c1 * b2 * s1 - l1 * l1 * s1 - 2.0 * l1 * l2 * ss)
}

/// Eq. 13 exactly as printed [m^4/rad^2]:
/// `(sin^2 th1 b^2 cos th1 - (L^2 - b^2 cos^2 th1)(cos th1 + 2 cos s))(cos s b^2 c2 s2 - l2^2 sin s)
///  - (-sin s b^2 c2 s2 - l2^2 cos s)(cos^2 th1 b^2 sin th1 - (L^2 - b^2 cos^2 th1)(sin th1 + 2 sin s))`.
pub fn det_jacobian_eq13_as_printed(p: &Params, theta1: f64, theta2: f64) -> f64 {
    let b2 = p.b * p.b;
    let (s1, c1) = theta1.sin_cos();
    let (s2, c2) = theta2.sin_cos();
    let (ss, cs) = (2.0 * theta1 + theta2).sin_cos();
    let l1sq = p.l * p.l - b2 * c1 * c1;
    let l2sq = p.l * p.l - b2 * c2 * c2;
    (s1 * s1 * b2 * c1 - l1sq * (c1 + 2.0 * cs)) * (cs * b2 * c2 * s2 - l2sq * ss)
        - (-ss * b2 * c2 * s2 - l2sq * cs) * (c1 * c1 * b2 * s1 - l1sq * (s1 + 2.0 * ss))
}

/// Aspect of a configuration: sign of `det J` (`+1`, `-1`, or `0` exactly singular).
pub fn aspect(p: &Params, theta1: f64, theta2: f64) -> i8 {
    let d = det_jacobian(p, theta1, theta2);
    if d > 0.0 {
        1
    } else if d < 0.0 {
        -1
    } else {
        0
    }
}

/// First singularity family: `theta1 = -theta2 + pi` (wrapped; `-theta2 - pi` is the same
/// angle). The two X coincide folded back and the end point is the origin.
pub fn singular_theta1_folded(theta2: f64) -> f64 {
    wrap_angle(PI - theta2)
}

/// Eq. 14 (second family, ICRs aligned with the end point):
/// `theta1 = atan2(-sin th2 (4b^4 c2^4 - 4L^2b^2 c2^2 - L^2b^2 + L^4),
///                 cos th2 (4b^4 c2^4 - 4b^4 c2^2 - 4L^2b^2 c2^2 + 3L^2b^2 + L^4))`.
pub fn singular_theta1_eq14(p: &Params, theta2: f64) -> f64 {
    let (l2, b2) = (p.l * p.l, p.b * p.b);
    let (s2, c2) = theta2.sin_cos();
    let cc = c2 * c2;
    let num = -s2 * (4.0 * b2 * b2 * cc * cc - 4.0 * l2 * b2 * cc - l2 * b2 + l2 * l2);
    let den = c2 * (4.0 * b2 * b2 * cc * cc - 4.0 * b2 * b2 * cc - 4.0 * l2 * b2 * cc + 3.0 * l2 * b2 + l2 * l2);
    num.atan2(den)
}

/// Every `theta1` in `(-pi, pi]` with `det J(theta1, theta2) = 0`, found numerically
/// (sign changes on `n_scan` samples, then bisection); independent of Eq. 14.
pub fn singular_theta1_numeric(p: &Params, theta2: f64, n_scan: usize) -> Vec<f64> {
    let f = |t: f64| det_jacobian(p, t, theta2);
    scan_roots(&f, -PI, PI, n_scan.max(8))
}

/// Roots of a continuous function on `[lo, hi)` by sign changes on `n` samples and bisection.
fn scan_roots(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let h = (hi - lo) / n as f64;
    let mut out = Vec::new();
    let mut a = lo;
    let mut fa = f(a);
    for k in 1..=n {
        let bb = lo + h * k as f64;
        let fb = f(bb);
        if fa == 0.0 {
            out.push(a);
        } else if fa * fb < 0.0 {
            let (mut x0, mut x1, mut f0) = (a, bb, fa);
            for _ in 0..200 {
                let xm = 0.5 * (x0 + x1);
                let fm = f(xm);
                if fm == 0.0 || (x1 - x0).abs() < 1e-15 {
                    x0 = xm;
                    x1 = xm;
                    break;
                }
                if f0 * fm < 0.0 {
                    x1 = xm;
                } else {
                    x0 = xm;
                    f0 = fm;
                }
            }
            out.push(0.5 * (x0 + x1));
        }
        a = bb;
        fa = fb;
    }
    out
}

// ---------------------------------------------------------------------------
// Inverse kinematics.
// ---------------------------------------------------------------------------

/// Characteristic quartic `a4 t^4 + a3 t^3 + a2 t^2 + a1 t + a0` in `t = tan(phi1/2)`
/// (Eq. 6), derived for any `L` (returns `[a4, a3, a2, a1, a0]`, [m^6]).
///
/// Derivation: with `t`, Eq. 12 gives `tan th1 = N/D`, `N = (b+L)t^2 + b - L`,
/// `D = 2Lt`, hence `C1 = A1 + L(cos phi1, sin phi1)`, `alpha1 = 2 th1`,
/// `M1 = C1 - b/2 (cos alpha1, sin alpha1)`. X2 places its top midpoint at the point
/// `P` of its base frame iff `|P|^4 - L^2 |P|^2 + b^2 P_y^2 = 0` (Eq. 1 with
/// `cos th2 = P_y/|P|`). With `P = R(-alpha1)((x, y) - M1)` this is rational in `t`;
/// its numerator factors as `16 ((L-b)^2 + (L+b)^2 t^2)^3 (1+t^2)^7 q(t)`; `q` is
/// returned. At `L = 1` it equals Eq. 7-11 exactly.
pub fn quartic_coefficients(p: &Params, x: f64, y: f64) -> [f64; 5] {
    let (l, b) = (p.l, p.b);
    let (l2, l3, l4) = (l * l, l * l * l, l * l * l * l);
    let (b2, b4) = (b * b, b * b * b * b);
    let (x2, y2) = (x * x, y * y);
    let r4 = (x2 + y2) * (x2 + y2);
    let a4 =
        (l + b).powi(2) * (2.0 * l3 * x + 5.0 * l2 * x2 + l2 * y2 + 4.0 * l * x * x2 + 4.0 * l * x * y2 + b2 * y2 + r4);
    let a3 = -4.0 * l * y * (l + b) * (l3 + 4.0 * l2 * x - l * b2 + 2.0 * l * x2 + 2.0 * l * y2 - 2.0 * b2 * x);
    let a2 = 2.0 * (-3.0 * l4 * x2 + 9.0 * l4 * y2 + l2 * b2 * x2 - 10.0 * l2 * b2 * y2 + l2 * r4 + b4 * y2 + b2 * r4);
    let a1 = 4.0 * l * y * (b - l) * (l3 - 4.0 * l2 * x - l * b2 + 2.0 * l * x2 + 2.0 * l * y2 + 2.0 * b2 * x);
    let a0 = (b - l).powi(2)
        * (-2.0 * l3 * x + 5.0 * l2 * x2 + l2 * y2 - 4.0 * l * x * x2 - 4.0 * l * x * y2 + b2 * y2 + r4);
    [a4, a3, a2, a1, a0]
}

/// Eq. 7-11 exactly as printed (they assume `L = 1`), applied to any `L` by scaling:
/// evaluated at `(b/L, x/L, y/L)` and multiplied by `L^6` (the degree of homogeneity),
/// so that it is comparable with [`quartic_coefficients`].
pub fn quartic_coefficients_eq7_11_as_printed(p: &Params, x: f64, y: f64) -> [f64; 5] {
    let (b, x, y) = (p.b / p.l, x / p.l, y / p.l);
    let s = p.l.powi(6);
    let (b2, x2, y2) = (b * b, x * x, y * y);
    let a4 = (b + 1.0).powi(2)
        * (b2 * y2 + x2 * x2 + 2.0 * x2 * y2 + y2 * y2 + 4.0 * x2 * x + 4.0 * x * y2 + 5.0 * x2 + y2 + 2.0 * x);
    let a3 = 4.0 * y * (b + 1.0) * (2.0 * b2 * x + b2 - 2.0 * x2 - 2.0 * y2 - 4.0 * x - 1.0);
    let a2 = 2.0
        * (b2 * b2 * y2 + b2 * x2 * x2 + 2.0 * b2 * x2 * y2 + b2 * y2 * y2 + b2 * x2 - 10.0 * b2 * y2
            + x2 * x2
            + 2.0 * x2 * y2
            + y2 * y2
            - 3.0 * x2
            + 9.0 * y2);
    let a1 = 4.0 * y * (b - 1.0) * (2.0 * b2 * x - b2 + 2.0 * x2 + 2.0 * y2 - 4.0 * x + 1.0);
    let a0 = (b - 1.0).powi(2)
        * (b2 * y2 + x2 * x2 + 2.0 * x2 * y2 + y2 * y2 - 4.0 * x2 * x - 4.0 * x * y2 + 5.0 * x2 + y2 - 2.0 * x);
    [a4 * s, a3 * s, a2 * s, a1 * s, a0 * s]
}

/// X2 closure residual [m^4] used by the derivation and the numeric solver:
/// `|P|^4 - L^2 |P|^2 + b^2 P_y^2`, `P` = end point in X2's base frame for the given
/// `theta1`. Zero iff some `theta2` reaches `(x, y)`; that `theta2 = atan2(-P_x, P_y)`.
pub fn x2_closure_residual(p: &Params, x: f64, y: f64, theta1: f64) -> f64 {
    let (pp, _) = x2_local_target(p, x, y, theta1);
    let r2 = pp.norm_squared();
    r2 * r2 - p.l * p.l * r2 + p.b * p.b * pp.y * pp.y
}

/// `(P, theta2)`: target in X2's base frame and the `theta2` pointing X2's mid-line at it.
fn x2_local_target(p: &Params, x: f64, y: f64, theta1: f64) -> (Vector2<f64>, f64) {
    let l1 = midline_length(p, theta1);
    let m1 = l1 * Vector2::new(-theta1.sin(), theta1.cos());
    let e = rot(2.0 * theta1);
    let d = Vector2::new(x, y) - m1;
    let pp = Vector2::new(d.dot(&e), -d.x * e.y + d.y * e.x);
    (pp, (-pp.x).atan2(pp.y))
}

/// One inverse-kinematics solution (crossed-bar assembly mode of both X).
#[derive(Clone, Copy, Debug)]
pub struct IkSolution {
    /// \[rad\], `(-pi, pi]`.
    pub theta1: f64,
    /// \[rad\], `(-pi, pi]`.
    pub theta2: f64,
    /// Base-joint angle of X1 at `A1`, the paper's `phi1` \[rad\], `(-pi, pi]`.
    pub phi1: f64,
    /// `det J` [m^2/rad^2].
    pub det_j: f64,
    /// Aspect: sign of `det J` (`+1` / `-1`, `0` if exactly singular).
    pub aspect: i8,
    /// `|DK(theta1, theta2) - (x, y)|` \[m\].
    pub residual: f64,
}

fn poly_eval(c: &[f64], z: Complex<f64>) -> (Complex<f64>, Complex<f64>) {
    // Horner for value and derivative; c = highest degree first.
    let mut v = Complex::new(0.0, 0.0);
    let mut d = Complex::new(0.0, 0.0);
    for &a in c {
        d = d * z + v;
        v = v * z + a;
    }
    (v, d)
}

/// Iterations allowed to the companion matrix's Schur decomposition: a quartic converges in
/// tens; non-finite or astronomically scaled coefficients (a target at 1e100 m) never do, and
/// nalgebra's default would iterate without end.
const SCHUR_MAX_ITERATIONS: usize = 10_000;

/// Complex roots of the quartic with highest-degree-first coefficients `c`
/// (`c[0] != 0`), via the companion-matrix eigenvalues, each Newton-polished. None found (an
/// empty list) when a coefficient is not finite or the decomposition does not converge.
fn quartic_roots(c: &[f64; 5]) -> Vec<Complex<f64>> {
    if !c.iter().all(|x| x.is_finite()) || c[0] == 0.0 {
        return Vec::new();
    }
    let m = Matrix4::new(
        -c[1] / c[0],
        -c[2] / c[0],
        -c[3] / c[0],
        -c[4] / c[0],
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
    );
    let Some(schur) = nalgebra::linalg::Schur::try_new(m, f64::EPSILON, SCHUR_MAX_ITERATIONS) else {
        return Vec::new();
    };
    schur
        .complex_eigenvalues()
        .iter()
        .map(|&z0| {
            let mut z = z0;
            for _ in 0..IK_NEWTON_STEPS {
                let (v, d) = poly_eval(c, z);
                if d.norm() == 0.0 {
                    break;
                }
                let zn = z - v / d;
                if !zn.re.is_finite() || !zn.im.is_finite() {
                    break;
                }
                z = zn;
            }
            z
        })
        .collect()
}

/// Newton polish of `(theta1, theta2)` on Eq. 3 (stops if `J` is near singular).
fn polish_joint(p: &Params, x: f64, y: f64, mut t1: f64, mut t2: f64) -> (f64, f64) {
    for _ in 0..IK_NEWTON_STEPS {
        let (fx, fy) = direct_kinematics(p, t1, t2);
        let r = Vector2::new(fx - x, fy - y);
        if r.norm() < 1e-15 * p.l {
            break;
        }
        let j = jacobian(p, t1, t2);
        if j.determinant().abs() < 1e-10 * p.l * p.l {
            break;
        }
        if let Some(inv) = j.try_inverse() {
            let d = inv * r;
            t1 -= d.x;
            t2 -= d.y;
        }
    }
    (wrap_angle(t1), wrap_angle(t2))
}

fn make_solution(p: &Params, x: f64, y: f64, t1: f64, t2: f64) -> IkSolution {
    let (fx, fy) = direct_kinematics(p, t1, t2);
    let d = det_jacobian(p, t1, t2);
    IkSolution {
        theta1: t1,
        theta2: t2,
        phi1: wrap_angle(base_joint_angle_a(p, t1)),
        det_j: d,
        aspect: if d > 0.0 {
            1
        } else if d < 0.0 {
            -1
        } else {
            0
        },
        residual: (fx - x).hypot(fy - y),
    }
}

fn push_unique(out: &mut Vec<IkSolution>, s: IkSolution) {
    let dup = out.iter().any(|o| {
        wrap_angle(o.theta1 - s.theta1).abs() < IK_DUPLICATE_TOL
            && wrap_angle(o.theta2 - s.theta2).abs() < IK_DUPLICATE_TOL
    });
    if !dup {
        out.push(s);
    }
}

/// `true` at the self-motion point `(0, 0)`, reached by the whole family
/// `theta1 + theta2 = +-pi` (all quartic coefficients vanish there).
pub fn is_self_motion_point(p: &Params, x: f64, y: f64) -> bool {
    x.hypot(y) <= ORIGIN_REL_TOL * p.l
}

/// Inverse kinematics through the characteristic quartic (Eq. 6-12): every real
/// solution, sorted by `theta1`; each verified by [`direct_kinematics`] to
/// `IK_VERIFY_REL_TOL * L`. Empty if `(x, y)` is unreachable, and at the self-motion
/// point `(0, 0)` (infinitely many solutions, see [`is_self_motion_point`]).
///
/// Route: roots `t` of [`quartic_coefficients`] (or of the reversed polynomial in
/// `s = 1/t = cot(phi1/2)` when `|a0| > |a4|`, so that `phi1 = pi`, i.e. `t = inf`,
/// is handled); `theta1 = atan2((b+L)t^2 + b - L, 2Lt)` (Eq. 12 with `alpha1 = 2 th1`);
/// `theta2 = atan2(-P_x, P_y)` (unique: the paper's second root of system (4) is
/// spurious); Newton polish on Eq. 3.
pub fn inverse_kinematics(p: &Params, x: f64, y: f64) -> Vec<IkSolution> {
    let mut out: Vec<IkSolution> = Vec::new();
    if !(x.is_finite() && y.is_finite()) || is_self_motion_point(p, x, y) {
        return out;
    }
    let a = quartic_coefficients(p, x, y);
    let reversed = a[4].abs() > a[0].abs();
    let c = if reversed { [a[4], a[3], a[2], a[1], a[0]] } else { a };
    if c[0] == 0.0 {
        return out;
    }
    let (l, b) = (p.l, p.b);
    for z in quartic_roots(&c) {
        if z.im.abs() > IK_IMAG_REL_TOL * (1.0 + z.norm()) {
            continue;
        }
        let v = z.re;
        // theta1 from Eq. 12: atan2(N, D) with N = (b+L)t^2 + b - L, D = 2Lt (times s^2 if reversed).
        let t1 = if reversed {
            ((b + l) + (b - l) * v * v).atan2(2.0 * l * v)
        } else {
            ((b + l) * v * v + (b - l)).atan2(2.0 * l * v)
        };
        let (_, t2) = x2_local_target(p, x, y, t1);
        let (t1, t2) = polish_joint(p, x, y, t1, t2);
        let s = make_solution(p, x, y, t1, t2);
        if s.residual <= IK_VERIFY_REL_TOL * l {
            push_unique(&mut out, s);
        }
    }
    out.sort_by(|u, v| u.theta1.total_cmp(&v.theta1));
    out
}

/// Numeric inverse kinematics (cross-check, independent of the quartic): sign changes
/// of [`x2_closure_residual`] on `n_scan` samples of `theta1 in [-pi, pi)`, bisection,
/// `theta2 = atan2(-P_x, P_y)`. Misses only tangential (double) roots, i.e. points on
/// the workspace boundary. Sorted by `theta1`.
pub fn inverse_kinematics_numeric(p: &Params, x: f64, y: f64, n_scan: usize) -> Vec<IkSolution> {
    let mut out = Vec::new();
    if is_self_motion_point(p, x, y) {
        return out;
    }
    let f = |t: f64| x2_closure_residual(p, x, y, t);
    for t1 in scan_roots(&f, -PI, PI, n_scan.max(8)) {
        let (_, t2) = x2_local_target(p, x, y, t1);
        let s = make_solution(p, x, y, wrap_angle(t1), t2);
        if s.residual <= IK_VERIFY_REL_TOL * p.l {
            push_unique(&mut out, s);
        }
    }
    out.sort_by(|u, v| u.theta1.total_cmp(&v.theta1));
    out
}

/// Number of inverse solutions at `(x, y)`: 0, 2 or 4 off the singular curves
/// (`usize::MAX` at the self-motion point `(0, 0)`).
pub fn solution_count(p: &Params, x: f64, y: f64) -> usize {
    if is_self_motion_point(p, x, y) {
        return usize::MAX;
    }
    inverse_kinematics(p, x, y).len()
}

/// Workspace regions by number of inverse solutions, on a `grid_n x grid_n` grid of
/// cell centres over the square `[-2L, 2L]^2` (which contains the workspace: reach `<= 2L`).
#[derive(Clone, Copy, Debug)]
pub struct RegionAreas {
    /// Workspace area (cells with at least one solution) [m^2].
    pub workspace_area: f64,
    /// Area with exactly 2 solutions divided by the workspace area.
    pub frac_2: f64,
    /// Area with exactly 4 solutions divided by the workspace area.
    pub frac_4: f64,
    /// Rest of the workspace (1 or 3 solutions: cells cut by a boundary, numerically
    /// ambiguous) divided by the workspace area.
    pub frac_other: f64,
    /// Largest solution count met on the grid.
    pub max_count: usize,
}

/// Fractions of the workspace area with 2 and with 4 inverse solutions (Fig. 5),
/// computed on a `grid_n x grid_n` grid (see [`RegionAreas`]).
pub fn region_area_fractions(p: &Params, grid_n: usize) -> RegionAreas {
    let n = grid_n.max(2);
    let half = REACH_OVER_L * p.l;
    let h = 2.0 * half / n as f64;
    let (mut ws, mut n2, mut n4, mut mx) = (0usize, 0usize, 0usize, 0usize);
    for i in 0..n {
        let x = -half + (i as f64 + 0.5) * h;
        for j in 0..n {
            let y = -half + (j as f64 + 0.5) * h;
            let k = solution_count(p, x, y);
            if k == 0 {
                continue;
            }
            ws += 1;
            if k != usize::MAX {
                mx = mx.max(k);
            }
            match k {
                2 => n2 += 1,
                4 => n4 += 1,
                _ => {}
            }
        }
    }
    let w = ws.max(1) as f64;
    RegionAreas {
        workspace_area: ws as f64 * h * h,
        frac_2: n2 as f64 / w,
        frac_4: n4 as f64 / w,
        frac_other: (ws - n2 - n4) as f64 / w,
        max_count: mx,
    }
}

// ---------------------------------------------------------------------------
// Query contract (`tensegrity solve furet2018 dk|ik`).
// ---------------------------------------------------------------------------

/// Answer of the `dk` query.
#[derive(Clone, Copy, Debug)]
pub struct DkAnswer {
    /// End point (top midpoint of X2) \[m\].
    pub x: f64,
    /// \[m\].
    pub y: f64,
    /// `det J` [m^2/rad^2].
    pub det_j: f64,
    /// Sign of `det J`.
    pub aspect: i8,
}

/// `dk` query: inputs `theta1`, `theta2` \[rad\] -> point and `det J`.
pub fn dk_query(p: &Params, theta1: f64, theta2: f64) -> DkAnswer {
    let (x, y) = direct_kinematics(p, theta1, theta2);
    DkAnswer { x, y, det_j: det_jacobian(p, theta1, theta2), aspect: aspect(p, theta1, theta2) }
}

/// `ik` query: inputs `x`, `y` \[m\] -> every solution with its `det J` and aspect
/// (= [`inverse_kinematics`]).
pub fn ik_query(p: &Params, x: f64, y: f64) -> Vec<IkSolution> {
    inverse_kinematics(p, x, y)
}

// ---------------------------------------------------------------------------
// Aspects and non-singular solution-changing paths (cuspidality).
// ---------------------------------------------------------------------------

fn grid_theta(k: usize, n: usize) -> f64 {
    -PI + (k as f64 + 0.5) * TWO_PI / n as f64
}

fn det_grid(p: &Params, n: usize) -> Vec<f64> {
    let mut g = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            g[i * n + j] = det_jacobian(p, grid_theta(i, n), grid_theta(j, n));
        }
    }
    g
}

/// Number of aspects: connected components (4-neighbour, on the torus `(-pi, pi]^2`)
/// of the sign of `det J` sampled at the centres of an `n x n` joint-space grid.
pub fn aspect_count(p: &Params, grid_n: usize) -> usize {
    let n = grid_n.max(4);
    let g = det_grid(p, n);
    let mut label = vec![usize::MAX; n * n];
    let mut comps = 0;
    for start in 0..n * n {
        if label[start] != usize::MAX {
            continue;
        }
        let sgn = g[start] > 0.0;
        let mut q = VecDeque::from([start]);
        label[start] = comps;
        while let Some(c) = q.pop_front() {
            let (i, j) = (c / n, c % n);
            for (di, dj) in [(1, 0), (n - 1, 0), (0, 1), (0, n - 1)] {
                let nb = ((i + di) % n) * n + (j + dj) % n;
                if label[nb] == usize::MAX && (g[nb] > 0.0) == sgn {
                    label[nb] = comps;
                    q.push_back(nb);
                }
            }
        }
        comps += 1;
    }
    comps
}

/// Minimum of `|det J|` along the polyline `path` (unwrapped joint angles \[rad\]),
/// each segment resampled with `samples_per_segment` (>= 1) sub-steps; returns `0` if
/// `det J` changes sign anywhere along the samples.
pub fn min_abs_det_along(p: &Params, path: &[(f64, f64)], samples_per_segment: usize) -> f64 {
    let m = samples_per_segment.max(1);
    let mut mn = f64::INFINITY;
    let mut sign = 0i8;
    let mut visit = |t1: f64, t2: f64| {
        let d = det_jacobian(p, t1, t2);
        let s = if d > 0.0 {
            1
        } else if d < 0.0 {
            -1
        } else {
            0
        };
        if s == 0 || (sign != 0 && s != sign) {
            mn = 0.0;
        }
        sign = s;
        mn = mn.min(d.abs());
    };
    if let Some(&(a, b)) = path.first() {
        visit(a, b);
    }
    for w in path.windows(2) {
        for k in 1..=m {
            let f = k as f64 / m as f64;
            visit(w[0].0 + f * (w[1].0 - w[0].0), w[0].1 + f * (w[1].1 - w[0].1));
        }
    }
    mn
}

/// `true` if the straight segment `a -> b` keeps `sgn * det J > thr` on samples spaced
/// at most `step` [rad].
fn segment_ok(p: &Params, a: (f64, f64), b: (f64, f64), sgn: f64, thr: f64, step: f64) -> bool {
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    let m = (len / step).ceil().max(1.0) as usize;
    (0..=m).all(|k| {
        let f = k as f64 / m as f64;
        sgn * det_jacobian(p, a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1)) > thr
    })
}

/// A joint-space path from `from` to `to` (`(theta1, theta2)` \[rad\]) that never
/// crosses `det J = 0`, or `None` if the two are in different aspects (or singular).
///
/// Method: on a `grid_n x grid_n` grid of the torus, keep the cells of the aspect of
/// `from` with `|det J| > margin * max|det J|`; breadth-first search (8-neighbour,
/// wrapping) from the cell nearest `from` to the cell nearest `to`; then greedy
/// shortcutting. Every straight segment is checked on samples spaced at most a quarter
/// grid step, with `sign(det J)` fixed and `|det J|` above half the margin (above 0 for
/// the last margin). Margins are tried from `0.2` down to `0`.
///
/// Waypoints are unwrapped (consecutive waypoints are joined by straight segments, which
/// is the motion): the first equals `from`, the last equals `to` up to multiples of `2pi`.
/// Use [`min_abs_det_along`] for the clearance.
pub fn nonsingular_path(p: &Params, from: (f64, f64), to: (f64, f64), grid_n: usize) -> Option<Vec<(f64, f64)>> {
    let n = grid_n.max(8);
    let d0 = det_jacobian(p, from.0, from.1);
    let d1 = det_jacobian(p, to.0, to.1);
    if d0 == 0.0 || d1 == 0.0 || (d0 > 0.0) != (d1 > 0.0) {
        return None;
    }
    let sgn = d0.signum();
    let g = det_grid(p, n);
    let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let cell = |t: f64| -> usize { (((wrap_angle(t) + PI) / TWO_PI * n as f64).floor() as usize).min(n - 1) };
    let step = TWO_PI / n as f64 / PATH_SAMPLES_PER_CELL;
    let (c0, c1) = (cell(from.0) * n + cell(from.1), cell(to.0) * n + cell(to.1));
    for &margin in &PATH_MARGINS {
        let thr_cell = margin * gmax;
        let thr_seg = if margin > 0.0 { 0.5 * thr_cell } else { 0.0 };
        let ok = |c: usize| sgn * g[c] > thr_cell;
        if !ok(c0) || !ok(c1) {
            continue;
        }
        let mut parent = vec![usize::MAX; n * n];
        parent[c0] = c0;
        let mut q = VecDeque::from([c0]);
        while let Some(c) = q.pop_front() {
            if c == c1 {
                break;
            }
            let (i, j) = (c / n, c % n);
            for di in [n - 1, 0, 1] {
                for dj in [n - 1, 0, 1] {
                    let nb = ((i + di) % n) * n + (j + dj) % n;
                    if parent[nb] == usize::MAX && ok(nb) {
                        parent[nb] = c;
                        q.push_back(nb);
                    }
                }
            }
        }
        if parent[c1] == usize::MAX {
            continue;
        }
        let mut cells = vec![c1];
        while *cells.last().unwrap() != c0 {
            let c = *cells.last().unwrap();
            cells.push(parent[c]);
        }
        cells.reverse();
        // Unwrapped raw polyline: from, cell centres, to.
        let mut raw = vec![from];
        for &c in &cells {
            let last = *raw.last().unwrap();
            let (t1, t2) = (grid_theta(c / n, n), grid_theta(c % n, n));
            raw.push((last.0 + wrap_angle(t1 - last.0), last.1 + wrap_angle(t2 - last.1)));
        }
        let last = *raw.last().unwrap();
        raw.push((last.0 + wrap_angle(to.0 - last.0), last.1 + wrap_angle(to.1 - last.1)));
        // Greedy shortcutting.
        let mut path = vec![raw[0]];
        let mut i = 0;
        let mut failed = false;
        while i + 1 < raw.len() {
            let mut j = raw.len() - 1;
            while j > i + 1 && !segment_ok(p, raw[i], raw[j], sgn, thr_seg, step) {
                j -= 1;
            }
            if !segment_ok(p, raw[i], raw[j], sgn, thr_seg, step) {
                failed = true;
                break;
            }
            path.push(raw[j]);
            i = j;
        }
        if !failed {
            return Some(path);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    const P: Params = Params::PAPER;
    /// Printed Eq. 13 at `theta2 = 0.5`, `theta1 = pi - 0.5` (a singular configuration):
    /// `F2 * 2 b^2 s1^2 c1 = -0.0859605...` instead of 0.
    const EQ13_FOLD_VALUE: f64 = -0.085_960_5;

    /// Deterministic 64-bit LCG (Knuth MMIX constants) -> uniform [0, 1).
    struct Lcg(u64);
    impl Lcg {
        fn next_f64(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn angle(&mut self) -> f64 {
            -PI + TWO_PI * self.next_f64()
        }
    }

    fn seg_intersect(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>, d: Vector2<f64>) -> bool {
        let cr = |o: Vector2<f64>, p: Vector2<f64>, q: Vector2<f64>| (p - o).perp(&(q - o));
        cr(a, b, c) * cr(a, b, d) < 0.0 && cr(c, d, a) * cr(c, d, b) < 0.0
    }

    #[test]
    fn validate_rejects_bad_params() {
        assert!(P.validate().is_ok());
        assert!(Params { l: 1.0, b: 0.0 }.validate().is_err());
        assert!(Params { l: 1.0, b: 1.0 }.validate().is_err());
        assert!(Params { l: 0.5, b: 0.6 }.validate().is_err());
        assert!(Params { l: f64::NAN, b: 0.5 }.validate().is_err());
        assert!(Params { l: 2.0, b: f64::INFINITY }.validate().is_err());
    }

    #[test]
    fn one_x_has_bars_b_and_l_and_springs_l_minus_plus_b_sin_theta() {
        let mut r = Lcg(7);
        for _ in 0..200 {
            let th = r.angle();
            let g = chain_nodes(&P, &[th])[0];
            assert_relative_eq!((g.base_right - g.base_left).norm(), P.b, epsilon = 1e-14);
            assert_relative_eq!((g.top_right - g.top_left).norm(), P.b, epsilon = 1e-14);
            assert_relative_eq!((g.top_right - g.base_left).norm(), P.l, epsilon = 1e-14);
            assert_relative_eq!((g.top_left - g.base_right).norm(), P.l, epsilon = 1e-14);
            assert_relative_eq!(
                (g.top_left - g.base_left).norm(),
                midline_length(&P, th) - P.b * th.sin(),
                epsilon = 1e-14
            );
            assert_relative_eq!(
                (g.top_right - g.base_right).norm(),
                midline_length(&P, th) + P.b * th.sin(),
                epsilon = 1e-14
            );
            // Eq. 1: mid-line = mean spring length
            assert_relative_eq!(
                0.5 * (g.spring_left + g.spring_right),
                (1.0 - (4.0 / 9.0) * th.cos().powi(2)).sqrt(),
                epsilon = 1e-14
            );
            if crossed_mode_margin(th) > 0.05 {
                assert!(seg_intersect(g.base_left, g.top_right, g.base_right, g.top_left), "bars cross at th = {th}");
            }
        }
        // theta = 0: upright symmetric X of height sqrt(L^2 - b^2) = sqrt(5)/3.
        let g = chain_nodes(&P, &[0.0])[0];
        assert_relative_eq!(g.top_mid.y, 5f64.sqrt() / 3.0, epsilon = 1e-15);
        assert_relative_eq!(g.top_left.x, -1.0 / 3.0, epsilon = 1e-15);
    }

    #[test]
    fn change_point_at_theta_half_pi_is_flat() {
        for th in [FRAC_PI_2, -FRAC_PI_2] {
            let g = chain_nodes(&P, &[th])[0];
            for v in [g.top_left, g.top_right] {
                assert!(v.y.abs() < 1e-15, "node off the base line: {v:?}");
            }
            assert_relative_eq!(g.midline_length, P.l, epsilon = 1e-15);
        }
        assert_relative_eq!(base_joint_angle_a(&P, FRAC_PI_2), PI, epsilon = 1e-15);
        assert_relative_eq!(base_joint_angle_a(&P, -FRAC_PI_2), 0.0, epsilon = 1e-15);
        assert_relative_eq!(crossed_mode_margin(FRAC_PI_2), 0.0, epsilon = 1e-15);
    }

    #[test]
    fn base_joint_angles_invert_and_match_node_geometry() {
        let mut r = Lcg(11);
        for _ in 0..200 {
            let th = r.angle();
            let g = chain_nodes(&P, &[th])[0];
            let ac = g.top_right - g.base_left;
            let bd = g.top_left - g.base_right;
            let phi = base_joint_angle_a(&P, th);
            let psi = base_joint_angle_b(&P, th);
            assert!(wrap_angle(ac.y.atan2(ac.x) - phi).abs() < 1e-13);
            assert!(wrap_angle(bd.y.atan2(bd.x) - psi).abs() < 1e-13);
            assert!(wrap_angle(theta_from_base_joint_angle_a(&P, phi) - th).abs() < 1e-13);
            assert!(wrap_angle(theta_from_base_joint_angle_b(&P, psi) - th).abs() < 1e-13);
            let h = 1e-6;
            let fd = (base_joint_angle_a(&P, th + h) - base_joint_angle_a(&P, th - h)) / (2.0 * h);
            assert_relative_eq!(fd, base_joint_rate_a(&P, th), epsilon = 1e-8);
            let fd = (base_joint_angle_b(&P, th + h) - base_joint_angle_b(&P, th - h)) / (2.0 * h);
            assert_relative_eq!(fd, base_joint_rate_b(&P, th), epsilon = 1e-8);
            assert!(base_joint_rate_a(&P, th) > 0.0 && base_joint_rate_b(&P, th) > 0.0);
        }
        // phi over a full turn of theta advances by exactly 2 pi
        assert_relative_eq!(base_joint_angle_a(&P, PI) - base_joint_angle_a(&P, -PI), TWO_PI, epsilon = 1e-14);
        // theta = 0: phi = atan2(sqrt(5)/3, 2/3)
        assert_relative_eq!(base_joint_angle_a(&P, 0.0), (5f64.sqrt() / 3.0).atan2(2.0 / 3.0), epsilon = 1e-15);
    }

    #[test]
    fn x_nodes_chain_second_x_on_top_of_first() {
        let (t1, t2) = (0.4, -1.1);
        let [g1, g2] = x_nodes(&P, t1, t2);
        assert_relative_eq!((g2.base_left - g1.top_left).norm(), 0.0, epsilon = 1e-15);
        assert_relative_eq!((g2.base_right - g1.top_right).norm(), 0.0, epsilon = 1e-15);
        assert_relative_eq!(g2.top_angle, 2.0 * t1 + 2.0 * t2, epsilon = 1e-15);
        let (x, y) = direct_kinematics(&P, t1, t2);
        assert_relative_eq!(g2.top_mid.x, x, epsilon = 1e-15);
        assert_relative_eq!(g2.top_mid.y, y, epsilon = 1e-15);
        // all four bars of X2 have the right lengths
        assert_relative_eq!((g2.top_right - g2.base_left).norm(), P.l, epsilon = 1e-14);
        assert_relative_eq!((g2.top_left - g2.base_right).norm(), P.l, epsilon = 1e-14);
    }

    #[test]
    fn eq2_eq3_eq4_eq5_agree_with_node_chain() {
        let mut r = Lcg(3);
        for _ in 0..200 {
            let (t1, t2) = (r.angle(), r.angle());
            let (x, y) = direct_kinematics(&P, t1, t2);
            let (xn, yn) = direct_kinematics_n(&P, &[t1, t2]);
            assert_relative_eq!(x, xn, epsilon = 1e-14);
            assert_relative_eq!(y, yn, epsilon = 1e-14);
            let (phi1, psi2) = (base_joint_angle_a(&P, t1), base_joint_angle_b(&P, t2));
            let (x4, y4) = direct_kinematics_crossed_bars_eq4(&P, phi1, psi2, 2.0 * t1, 2.0 * t2);
            assert_relative_eq!(x, x4, epsilon = 1e-14);
            assert_relative_eq!(y, y4, epsilon = 1e-14);
            let (r1, r2) = loop_closure_eq5(&P, phi1, 2.0 * t1, psi2, 2.0 * t2);
            assert!(r1.abs() < 1e-14 && r2.abs() < 1e-14);
            let t3 = r.angle();
            let c = chain_nodes(&P, &[t1, t2, t3]);
            let (x3, y3) = direct_kinematics_n(&P, &[t1, t2, t3]);
            assert_relative_eq!(c[2].top_mid.x, x3, epsilon = 1e-14);
            assert_relative_eq!(c[2].top_mid.y, y3, epsilon = 1e-14);
        }
        // theta = 0, 0: straight stack of height 2 sqrt(L^2 - b^2)
        let (x, y) = direct_kinematics(&P, 0.0, 0.0);
        assert_relative_eq!(x, 0.0, epsilon = 1e-15);
        assert_relative_eq!(y, 2.0 * 5f64.sqrt() / 3.0, epsilon = 1e-15);
        // full stretch: reach 2L at theta1 = pi/2, theta2 = -pi/2 -> (-2, 0)
        let (x, y) = direct_kinematics(&P, FRAC_PI_2, -FRAC_PI_2);
        assert_relative_eq!(x, -2.0, epsilon = 1e-15);
        assert_relative_eq!(y, 0.0, epsilon = 1e-15);
    }

    #[test]
    fn jacobian_matches_finite_differences_and_corrected_eq13() {
        let mut r = Lcg(5);
        let h = 1e-6;
        for _ in 0..100 {
            let (t1, t2) = (r.angle(), r.angle());
            let j = jacobian(&P, t1, t2);
            let a = direct_kinematics(&P, t1 + h, t2);
            let b = direct_kinematics(&P, t1 - h, t2);
            let c = direct_kinematics(&P, t1, t2 + h);
            let d = direct_kinematics(&P, t1, t2 - h);
            assert_relative_eq!(j[(0, 0)], (a.0 - b.0) / (2.0 * h), epsilon = 1e-8);
            assert_relative_eq!(j[(1, 0)], (a.1 - b.1) / (2.0 * h), epsilon = 1e-8);
            assert_relative_eq!(j[(0, 1)], (c.0 - d.0) / (2.0 * h), epsilon = 1e-8);
            assert_relative_eq!(j[(1, 1)], (c.1 - d.1) / (2.0 * h), epsilon = 1e-8);
            let l1l2 = midline_length(&P, t1) * midline_length(&P, t2);
            assert_relative_eq!(
                det_jacobian_eq13_corrected(&P, t1, t2),
                l1l2 * det_jacobian(&P, t1, t2),
                epsilon = 1e-13
            );
        }
    }

    #[test]
    fn printed_eq13_differs_from_det_j() {
        // at (0.3, 0.5): l1 l2 det J = 0.043494..., printed Eq. 13 gives 0.017859...
        let (t1, t2) = (0.3, 0.5);
        let want = det_jacobian(&P, t1, t2) * midline_length(&P, t1) * midline_length(&P, t2);
        assert_relative_eq!(want, 0.043_494_3, epsilon = 1e-6);
        assert_relative_eq!(det_jacobian_eq13_as_printed(&P, t1, t2), 0.017_859_0, epsilon = 1e-6);
        // and printed Eq. 13 does not vanish on the fold singularity theta1 = pi - theta2
        assert_relative_eq!(
            det_jacobian_eq13_as_printed(&P, singular_theta1_folded(0.5), 0.5),
            EQ13_FOLD_VALUE,
            epsilon = 1e-6
        );
    }

    #[test]
    fn singular_families_fold_and_eq14() {
        for k in 0..72 {
            let t2 = -PI + 0.02 + k as f64 * TWO_PI / 72.0;
            let tf = singular_theta1_folded(t2);
            assert!(det_jacobian(&P, tf, t2).abs() < 1e-13);
            let (x, y) = direct_kinematics(&P, tf, t2);
            assert!(x.hypot(y) < 1e-14);
            let t14 = singular_theta1_eq14(&P, t2);
            assert!(det_jacobian(&P, t14, t2).abs() < 1e-13, "Eq. 14 at th2 = {t2}");
            let roots = singular_theta1_numeric(&P, t2, 720);
            assert_eq!(roots.len(), 2, "det J = 0 has two roots in theta1 at th2 = {t2}");
            let near = |a: f64| roots.iter().any(|r| wrap_angle(r - a).abs() < 1e-9);
            assert!(near(tf) && near(t14));
        }
    }

    #[test]
    fn quartic_matches_printed_eq7_to_11_for_any_l() {
        let q = Params { l: 2.5, b: 1.1 };
        let mut r = Lcg(9);
        for _ in 0..50 {
            let (x, y) = (5.0 * r.next_f64() - 2.5, 5.0 * r.next_f64() - 2.5);
            let d = quartic_coefficients(&q, x, y);
            let pr = quartic_coefficients_eq7_11_as_printed(&q, x, y);
            let sc = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..5 {
                assert!((d[k] - pr[k]).abs() <= 1e-12 * sc);
            }
        }
    }

    #[test]
    fn fig3_four_solutions_at_paper_point() {
        let (x, y) = PAPER_FIG3_POINT;
        let s = inverse_kinematics(&P, x, y);
        assert_eq!(s.len(), 4);
        let want = [
            (-0.579_077_631_606_936_5, 1.596_234_828_580_643),
            (-0.287_254_550_659_643_2, 0.788_934_833_237_533_7),
            (0.283_463_664_203_212_4, -0.843_622_868_024_327_5),
            (0.532_533_863_216_939_4, -1.527_148_874_314_84),
        ];
        for (v, w) in s.iter().zip(want.iter()) {
            assert_relative_eq!(v.theta1, w.0, epsilon = 1e-9);
            assert_relative_eq!(v.theta2, w.1, epsilon = 1e-9);
            assert!(v.residual < 1e-14);
            let (fx, fy) = direct_kinematics(&P, v.theta1, v.theta2);
            assert_relative_eq!(fx, x, epsilon = 1e-13);
            assert_relative_eq!(fy, y, epsilon = 1e-13);
        }
        assert_eq!(s.iter().filter(|v| v.aspect > 0).count(), 2);
        assert_eq!(s.iter().filter(|v| v.aspect < 0).count(), 2);
        // numeric cross-check finds the same four
        let n = inverse_kinematics_numeric(&P, x, y, 4000);
        assert_eq!(n.len(), 4);
        for (a, b) in s.iter().zip(n.iter()) {
            assert!(wrap_angle(a.theta1 - b.theta1).abs() < 1e-10 && wrap_angle(a.theta2 - b.theta2).abs() < 1e-10);
        }
    }

    #[test]
    fn ik_scales_with_l() {
        let q = Params { l: 2.0, b: 4.0 / 3.0 };
        let (x, y) = PAPER_FIG3_POINT;
        let a = inverse_kinematics(&P, x, y);
        let b = inverse_kinematics(&q, 2.0 * x, 2.0 * y);
        assert_eq!(a.len(), b.len());
        for (u, v) in a.iter().zip(b.iter()) {
            assert_relative_eq!(u.theta1, v.theta1, epsilon = 1e-10);
            assert_relative_eq!(u.theta2, v.theta2, epsilon = 1e-10);
            assert_relative_eq!(4.0 * u.det_j, v.det_j, epsilon = 1e-9);
        }
    }

    #[test]
    fn ik_round_trip_and_numeric_cross_check_on_random_configurations() {
        for &b in &PAPER_FIG5_B {
            let q = Params { l: 1.0, b };
            let mut r = Lcg(42);
            for _ in 0..300 {
                let (t1, t2) = (r.angle(), r.angle());
                if det_jacobian(&q, t1, t2).abs() < 1e-3 {
                    continue; // near a boundary, counts are ill-conditioned
                }
                let (x, y) = direct_kinematics(&q, t1, t2);
                let s = inverse_kinematics(&q, x, y);
                assert!(s.len() == 2 || s.len() == 4, "count {} at b = {b}", s.len());
                assert!(s
                    .iter()
                    .any(|v| wrap_angle(v.theta1 - t1).abs() < 1e-9 && wrap_angle(v.theta2 - t2).abs() < 1e-9));
                assert!(s.iter().all(|v| v.residual < 1e-12));
                assert_eq!(2 * s.iter().filter(|v| v.aspect > 0).count(), s.len());
                let n = inverse_kinematics_numeric(&q, x, y, 3000);
                assert_eq!(n.len(), s.len(), "numeric vs quartic at ({x}, {y}), b = {b}");
            }
        }
    }

    #[test]
    fn ik_handles_phi1_equal_pi_and_unreachable_points() {
        // theta1 = pi/2 means phi1 = pi (t = infinity)
        let (x, y) = direct_kinematics(&P, FRAC_PI_2, 0.7);
        let s = inverse_kinematics(&P, x, y);
        assert!(s
            .iter()
            .any(|v| wrap_angle(v.theta1 - FRAC_PI_2).abs() < 1e-9 && wrap_angle(v.theta2 - 0.7).abs() < 1e-9));
        assert!(inverse_kinematics(&P, 2.1, 0.0).is_empty());
        assert_eq!(solution_count(&P, 1.5, 1.5), 0);
        assert_eq!(solution_count(&P, 0.0, 0.0), usize::MAX);
    }

    #[test]
    fn dk_query_reports_point_and_det() {
        let a = dk_query(&P, 0.0, 0.0);
        assert_relative_eq!(a.x, 0.0, epsilon = 1e-15);
        assert_relative_eq!(a.y, 2.0 * 5f64.sqrt() / 3.0, epsilon = 1e-15);
        // straight stack: J = [[-3h, -h], [0, 0]] (h = sqrt(L^2-b^2)), singular (Eq. 14 at theta2 = 0 gives theta1 = 0)
        assert!(a.det_j.abs() < 1e-15);
        let b = dk_query(&P, 0.3, 0.5);
        assert_relative_eq!(b.det_j, 0.069_564_4, epsilon = 1e-6);
        assert_eq!(b.aspect, 1);
        assert_eq!(ik_query(&P, 0.03, 1.6).len(), 4);
    }

    #[test]
    fn two_aspects_on_the_joint_torus() {
        assert_eq!(aspect_count(&P, 256), 2);
    }

    #[test]
    fn nonsingular_paths_join_same_aspect_solutions_at_fig3_point() {
        let (x, y) = PAPER_FIG3_POINT;
        let s = inverse_kinematics(&P, x, y);
        for sg in [1i8, -1] {
            let g: Vec<&IkSolution> = s.iter().filter(|v| v.aspect == sg).collect();
            assert_eq!(g.len(), 2);
            let (a, b) = ((g[0].theta1, g[0].theta2), (g[1].theta1, g[1].theta2));
            let path = nonsingular_path(&P, a, b, 192).expect("path in one aspect");
            let first = path[0];
            let last = *path.last().unwrap();
            assert_eq!(first, a);
            assert!(wrap_angle(last.0 - b.0).abs() < 1e-12 && wrap_angle(last.1 - b.1).abs() < 1e-12);
            let (x0, y0) = direct_kinematics(&P, first.0, first.1);
            let (x1, y1) = direct_kinematics(&P, last.0, last.1);
            assert_relative_eq!(x0, x, epsilon = 1e-12);
            assert_relative_eq!(y0, y, epsilon = 1e-12);
            assert_relative_eq!(x1, x, epsilon = 1e-12);
            assert_relative_eq!(y1, y, epsilon = 1e-12);
            let m = min_abs_det_along(&P, &path, 1000);
            assert!(m > 1e-3, "min |det J| = {m} for aspect {sg}");
        }
        // different aspects: no path
        let pos = s.iter().find(|v| v.aspect > 0).unwrap();
        let neg = s.iter().find(|v| v.aspect < 0).unwrap();
        assert!(nonsingular_path(&P, (pos.theta1, pos.theta2), (neg.theta1, neg.theta2), 64).is_none());
    }

    #[test]
    fn fig5_region_fractions() {
        // Converged values (800 x 800 grid): workspace 11.735 / 10.945 / 10.298 m^2,
        // 4-solution fraction 0 / 0.02107 / 0.15624 of the workspace area. A regression pin of
        // the model's own converged areas (Fig. 5 prints no number and no closed form gives
        // them): what the 200 x 200 grid shows is convergence to them within its resolution.
        let r = region_area_fractions(&Params { l: 1.0, b: 2.0 / 5.0 }, 200);
        assert_eq!(r.frac_4, 0.0);
        assert_eq!(r.max_count, 2);
        assert_relative_eq!(r.workspace_area, 11.735, epsilon = 0.03);
        let r23 = region_area_fractions(&P, 200);
        assert_relative_eq!(r23.frac_4, 0.02107, epsilon = 0.001);
        assert_relative_eq!(r23.frac_2, 1.0 - 0.02107, epsilon = 0.001);
        assert_relative_eq!(r23.workspace_area, 10.945, epsilon = 0.03);
        assert_eq!(r23.max_count, 4);
        assert!(r23.frac_other < 0.001);
        let r910 = region_area_fractions(&Params { l: 1.0, b: 0.9 }, 200);
        assert_relative_eq!(r910.frac_4, 0.15624, epsilon = 0.002);
        assert_relative_eq!(r910.workspace_area, 10.298, epsilon = 0.03);
    }
}
