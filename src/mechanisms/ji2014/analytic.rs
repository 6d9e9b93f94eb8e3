//! Closed-form model of the planar tensegrity parallel mechanism of
//! Ji, Li & Lin (2014), "Kinematics and stiffness of a planar tensegrity
//! parallel mechanism", Periodica Polytechnica Mech. Eng. 58(2) 101-111.
//!
//! Everything here is a pure function of `f64` / `nalgebra` values.
//! Units: lengths in metres \[m\], angles in radians \[rad\], spring rates in
//! newtons per metre [N/m], energies in joules \[J\], torques in newton-metres
//! \[N*m\] and the rotational stiffness `K = d2U/dtheta2^2` in [N*m/rad].
//!
//! # Model (paper Eq. 1-4)
//! Base nodes `C1=(0,0)`, `C2=(-L,-sqrt3 L)`, `C3=(L,-sqrt3 L)`; actuator
//! node `D1 = L3 (cos th1, sin th1)`; mobile equilateral triangle of side `L`
//! with `D3 = D1 + L (cos th2, sin th2)` and `D2 = D1 + L (cos(th2+pi/3),
//! sin(th2+pi/3))`. Zero-free-length springs `K1: D2-C2`, `K2: D3-C3`:
//! `U = K1/2 |D2-C2|^2 + K2/2 |D3-C3|^2`. With the actuators locked the only
//! freedom is `th2` (the triangle pivots about `D1`).
//!
//! # Key derived results (see `findings::findings()` for the numeric checks)
//! * `U = U0 + A cos th2 + B sin th2` exactly (Eq. 4 is correct), with
//!   `A = L eta2 / 2`, `B = L eta1 / 2` (Eq. 6-7).
//! * Equilibria: `(cos th2, sin th2) = -/+ (eta2, eta1)/|eta|`; the minus sign
//!   is the energy minimum (stiffness `+L|eta|/2`), the plus sign the maximum.
//!   The paper's `th2 in [0, pi]` root is the minimum only when `eta1 < 0`.
//! * Stable stiffness `K = L sqrt(K1^2+K1K2+K2^2) |D1 - D1*|`, `D1*` being the
//!   neutral point where `eta = 0` ([`neutral_point`]).
//! * `det J = L3 (1 + s L (K1+2K2)/|eta|)`, `s = -1` on the stable branch,
//!   `+1` on the unstable one: finite whenever `eta != 0`.
//! * Inverse kinematics in closed form from Eq. 48: `delta1 cos th2 - delta2
//!   sin th2 + sqrt3 K1 L = 0` is one trigonometric equation in `th2` only.

/// Wraps an angle to `(-pi, pi]` (one definition for the testbed, in `mechanisms`).
pub use crate::mechanisms::wrap_angle;
use crate::mechanisms::ParamError;
use nalgebra::{Matrix2, Vector2};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_3, PI};

/// `sqrt(3)`, appears throughout the equilateral-triangle geometry.
pub const SQRT_3: f64 = 1.732_050_807_568_877_2;
/// Eq. 31: the paper limits the actuator to `0 <= L3 <= 2L`.
pub const PAPER_L3_MAX_OVER_L: f64 = 2.0;
/// Figs. 4-6 example: actuator length `L3 = 6 m`.
pub const PAPER_FIG4_L3: f64 = 6.0;
/// Figs. 4-6 example: `theta1 = pi/10` (the captions print "theta2 = pi/10", a typo).
pub const PAPER_FIG4_THETA1: f64 = PI / 10.0;
/// Inverse kinematics: every returned solution reproduces `(x, y)` through
/// [`equilibria`] to within this tolerance times `max(L, |(x,y)|)`.
pub const IK_VERIFY_REL_TOL: f64 = 1e-10;
/// Inverse kinematics: `L3` below this fraction of `L` is treated as `L3 = 0`
/// (then `theta1` is irrelevant and `0` is returned as representative).
const IK_L3_ZERO_REL: f64 = 1e-12;
/// Inverse kinematics: `D1` may lie this far (relative to `L3`) below the X
/// axis (rounding) and still be accepted with `theta1` clamped to `0` or `pi`.
const IK_THETA1_CLAMP_REL: f64 = 1e-12;
/// Newton polishing steps applied to each closed-form IK root of Eq. 48.
const IK_NEWTON_STEPS: usize = 3;
/// Two IK roots closer than this (in `theta2` [rad]) are merged.
const IK_DUPLICATE_TOL: f64 = 1e-12;

/// Mechanism parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Side of the mobile triangle `L` \[m\] (base triangle side is `2L`).
    pub l: f64,
    /// Spring rate `K1` of spring `D2-C2` [N/m].
    pub k1: f64,
    /// Spring rate `K2` of spring `D3-C3` [N/m].
    pub k2: f64,
}

impl Params {
    /// Figs. 2, 3, 7, 8: `L = 1 m, K1 = 200 N/m, K2 = 100 N/m`.
    pub const PAPER_WORKSPACE: Params = Params { l: 1.0, k1: 200.0, k2: 100.0 };
    /// Figs. 4-6: `L = 1 m, K1 = 100 N/m, K2 = 10 N/m` (with `L3 = 6 m`, `theta1 = pi/10`).
    pub const PAPER_FIG4: Params = Params { l: 1.0, k1: 100.0, k2: 10.0 };

    /// `L > 0`, `K1 > 0`, `K2 > 0`, all finite.
    pub fn validate(&self) -> Result<(), ParamError> {
        for (name, value) in [("L", self.l), ("K1", self.k1), ("K2", self.k2)] {
            if !value.is_finite() {
                return Err(ParamError::NotFinite { name, value });
            }
            if value <= 0.0 {
                return Err(ParamError::NotPositive { name, value });
            }
        }
        Ok(())
    }
}

/// Node positions \[m\] (Eq. 1-3).
#[derive(Clone, Copy, Debug)]
pub struct Nodes {
    pub c1: Vector2<f64>,
    pub c2: Vector2<f64>,
    pub c3: Vector2<f64>,
    pub d1: Vector2<f64>,
    pub d2: Vector2<f64>,
    pub d3: Vector2<f64>,
}

/// Eq. 1-3: node coordinates for inputs `l3` \[m\], `theta1` \[rad\] and the free
/// coordinate `theta2` \[rad\].
pub fn nodes(p: &Params, l3: f64, theta1: f64, theta2: f64) -> Nodes {
    let l = p.l;
    let c1 = Vector2::zeros();
    let c2 = Vector2::new(-l, -SQRT_3 * l);
    let c3 = Vector2::new(l, -SQRT_3 * l);
    let d1 = l3 * Vector2::new(theta1.cos(), theta1.sin());
    let d2 = d1 + l * Vector2::new((theta2 + FRAC_PI_3).cos(), (theta2 + FRAC_PI_3).sin());
    let d3 = d1 + l * Vector2::new(theta2.cos(), theta2.sin());
    Nodes { c1, c2, c3, d1, d2, d3 }
}

/// Spring lengths `(|D2-C2|, |D3-C3|)` \[m\].
pub fn spring_lengths(p: &Params, l3: f64, theta1: f64, theta2: f64) -> (f64, f64) {
    let n = nodes(p, l3, theta1, theta2);
    ((n.d2 - n.c2).norm(), (n.d3 - n.c3).norm())
}

/// Ground-truth potential energy \[J\]: `K1/2 |D2-C2|^2 + K2/2 |D3-C3|^2`
/// (zero free lengths).
pub fn potential_energy(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let n = nodes(p, l3, theta1, theta2);
    0.5 * p.k1 * (n.d2 - n.c2).norm_squared() + 0.5 * p.k2 * (n.d3 - n.c3).norm_squared()
}

/// Coefficients of Eq. 4 written as `U = u0 + a cos th2 + b sin th2`
/// (`u0` \[J\], `a` \[J\], `b` \[J\]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergyCoefficients {
    pub u0: f64,
    pub a: f64,
    pub b: f64,
}

/// Eq. 4 coefficients exactly as printed:
/// `u0 = (K1+K2)/2 (5L^2 + L3^2 + 2 sqrt3 L L3 sin th1) + (K1-K2) L L3 cos th1`,
/// `a = (2K1-K2)L^2 + (K1/2+K2) L L3 cos th1 + sqrt3/2 K1 L L3 sin th1`,
/// `b = (K1/2+K2) L L3 sin th1 - sqrt3/2 K1 L L3 cos th1 + sqrt3 K2 L^2`.
pub fn energy_coefficients_eq4(p: &Params, l3: f64, theta1: f64) -> EnergyCoefficients {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    let u0 = 0.5 * (k1 + k2) * (5.0 * l * l + l3 * l3 + 2.0 * SQRT_3 * l * l3 * s1) + (k1 - k2) * l * l3 * c1;
    let a = (2.0 * k1 - k2) * l * l + (0.5 * k1 + k2) * l * l3 * c1 + 0.5 * SQRT_3 * k1 * l * l3 * s1;
    let b = (0.5 * k1 + k2) * l * l3 * s1 - 0.5 * SQRT_3 * k1 * l * l3 * c1 + SQRT_3 * k2 * l * l;
    EnergyCoefficients { u0, a, b }
}

/// Eq. 4 exactly as printed \[J\].
pub fn potential_energy_eq4(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let e = energy_coefficients_eq4(p, l3, theta1);
    let (s2, c2) = theta2.sin_cos();
    e.u0 + e.a * c2 + e.b * s2
}

/// Eq. 6-7: `(eta1, eta2)` \[N\], with
/// `eta1 = (K1+2K2) L3 sin th1 - sqrt3 K1 L3 cos th1 + 2 sqrt3 K2 L` and
/// `eta2 = 2(2K1-K2) L + (K1+2K2) L3 cos th1 + sqrt3 K1 L3 sin th1`.
/// Note `eta1 = 2B/L`, `eta2 = 2A/L` with `A, B` the Eq. 4 coefficients.
pub fn eta(p: &Params, l3: f64, theta1: f64) -> (f64, f64) {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    let eta1 = (k1 + 2.0 * k2) * l3 * s1 - SQRT_3 * k1 * l3 * c1 + 2.0 * k2 * SQRT_3 * l;
    let eta2 = 2.0 * (2.0 * k1 - k2) * l + (k1 + 2.0 * k2) * l3 * c1 + SQRT_3 * k1 * l3 * s1;
    (eta1, eta2)
}

/// `N = eta1^2 + eta2^2` [N^2]; equals `4[4L^2(K1^2-K1K2+K2^2) + L3^2(K1^2+K1K2+K2^2)
/// + 2 L3 L cos th1 (K1^2-K2^2) + 2 sqrt3 L3 L sin th1 (K1^2+K2^2)]` (the bracket of Eq. 24).
pub fn eta_norm_sq(p: &Params, l3: f64, theta1: f64) -> f64 {
    let (e1, e2) = eta(p, l3, theta1);
    e1 * e1 + e2 * e2
}

/// Rotate a plane vector by +90 degrees (derivative of a rotation).
fn perp(v: Vector2<f64>) -> Vector2<f64> {
    Vector2::new(-v.y, v.x)
}

/// `tau = dU/dtheta2` \[N*m\], derived directly from the spring vectors:
/// `tau = K1 (D2-C2).perp(D2-D1) + K2 (D3-C3).perp(D3-D1)`.
/// Equals Eq. 41 (`-A sin th2 + B cos th2`), which is correct as printed.
pub fn torque(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let n = nodes(p, l3, theta1, theta2);
    p.k1 * (n.d2 - n.c2).dot(&perp(n.d2 - n.d1)) + p.k2 * (n.d3 - n.c3).dot(&perp(n.d3 - n.d1))
}

/// Eq. 41 as printed: `tau = -A sin th2 + B cos th2` \[N*m\].
pub fn torque_eq41(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let e = energy_coefficients_eq4(p, l3, theta1);
    let (s2, c2) = theta2.sin_cos();
    -e.a * s2 + e.b * c2
}

/// `K = d2U/dtheta2^2` [N*m/rad], derived from the spring vectors:
/// `K = K1 (L^2 - (D2-C2).(D2-D1)) + K2 (L^2 - (D3-C3).(D3-D1))`.
/// Equals Eq. 42 (`-A cos th2 - B sin th2`), which is correct as printed.
pub fn stiffness(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let n = nodes(p, l3, theta1, theta2);
    let l2 = p.l * p.l;
    p.k1 * (l2 - (n.d2 - n.c2).dot(&(n.d2 - n.d1))) + p.k2 * (l2 - (n.d3 - n.c3).dot(&(n.d3 - n.d1)))
}

/// Eq. 42 as printed: `K = -A cos th2 - B sin th2` [N*m/rad].
pub fn stiffness_eq42(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let e = energy_coefficients_eq4(p, l3, theta1);
    let (s2, c2) = theta2.sin_cos();
    -e.a * c2 - e.b * s2
}

/// An equilibrium (`tau = 0`) for fixed inputs.
#[derive(Clone, Copy, Debug)]
pub struct Equilibrium {
    /// \[rad\], wrapped to `(-pi, pi]` (by [`fk_paper`]: in `[0, pi]`).
    pub theta2: f64,
    /// `D3.x` \[m\] (Eq. 2).
    pub x: f64,
    /// `D3.y` \[m\] (Eq. 3).
    pub y: f64,
    /// Potential energy \[J\].
    pub energy: f64,
    /// `K = d2U/dtheta2^2` [N*m/rad].
    pub stiffness: f64,
    /// `K > 0` (energy minimum).
    pub stable: bool,
}

fn equilibrium_at(p: &Params, l3: f64, theta1: f64, theta2: f64) -> Equilibrium {
    let n = nodes(p, l3, theta1, theta2);
    let k = stiffness(p, l3, theta1, theta2);
    Equilibrium {
        theta2,
        x: n.d3.x,
        y: n.d3.y,
        energy: potential_energy(p, l3, theta1, theta2),
        stiffness: k,
        stable: k > 0.0,
    }
}

/// Both roots of `dU/dtheta2 = 0` (they differ by pi), energy minimum first.
/// `theta2` wrapped to `(-pi, pi]`. Minimum: `(cos, sin) th2 = -(eta2, eta1)/|eta|`;
/// maximum: `+(eta2, eta1)/|eta|`. In the degenerate case `eta = 0` (the
/// neutral point, `U` independent of `theta2`) `theta2 = 0` and `pi` are
/// returned, both with `K = 0`, `stable = false`.
pub fn equilibria(p: &Params, l3: f64, theta1: f64) -> [Equilibrium; 2] {
    let (e1, e2) = eta(p, l3, theta1);
    let (th_min, th_max) =
        if e1 == 0.0 && e2 == 0.0 { (0.0, PI) } else { (wrap_angle((-e1).atan2(-e2)), wrap_angle(e1.atan2(e2))) };
    [equilibrium_at(p, l3, theta1, th_min), equilibrium_at(p, l3, theta1, th_max)]
}

/// The paper's FK: Eq. 5 `tan th2 = eta1/eta2` with `theta2` restricted to
/// `[0, pi]` (one root). This is the energy minimum only when `eta1 < 0`
/// (for `eta1 > 0` it is the maximum); for `eta1 = 0` it returns `0` if
/// `eta2 >= 0` else `pi`.
pub fn fk_paper(p: &Params, l3: f64, theta1: f64) -> Equilibrium {
    let (e1, e2) = eta(p, l3, theta1);
    let (s, c) = if e1 < 0.0 { (-e1, -e2) } else { (e1, e2) };
    let th2 = if s == 0.0 && c == 0.0 { 0.0 } else { s.atan2(c) };
    equilibrium_at(p, l3, theta1, th2)
}

/// One inverse-kinematics solution.
#[derive(Clone, Copy, Debug)]
pub struct IkSolution {
    /// \[m\], `>= 0`.
    pub l3: f64,
    /// \[rad\], in `[0, pi]`.
    pub theta1: f64,
    /// \[rad\], `(-pi, pi]`, of the equilibrium whose `D3` is the target.
    pub theta2: f64,
    pub stable: bool,
    /// [N*m/rad].
    pub stiffness: f64,
}

/// Eq. 50-51: `(delta1, delta2)` \[N\] of the target `(x, y)` \[m\]:
/// `delta1 = (K1+2K2) y - sqrt3 K1 x + 2 sqrt3 K2 L`,
/// `delta2 = 2(2K1-K2) L + (K1+2K2) x + sqrt3 K1 y`.
pub fn delta(p: &Params, x: f64, y: f64) -> (f64, f64) {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let d1 = (k1 + 2.0 * k2) * y - SQRT_3 * k1 * x + 2.0 * SQRT_3 * k2 * l;
    let d2 = 2.0 * (2.0 * k1 - k2) * l + (k1 + 2.0 * k2) * x + SQRT_3 * k1 * y;
    (d1, d2)
}

/// Eq. 48 / 40 residual \[N\]: `delta1 cos th2 - delta2 sin th2 + sqrt3 K1 L`
/// (zero iff `theta2` is an equilibrium of the inputs with `D3 = (x, y)`;
/// it equals `eta1 cos th2 - eta2 sin th2 = 2 tau / L`).
pub fn equilibrium_residual_eq48(p: &Params, x: f64, y: f64, theta2: f64) -> f64 {
    let (d1, d2) = delta(p, x, y);
    let (s, c) = theta2.sin_cos();
    d1 * c - d2 * s + SQRT_3 * p.k1 * p.l
}

/// Inverse kinematics. Every `(L3, theta1)` with `0 <= theta1 <= pi`,
/// `L3 >= 0`, for which `(x, y)` \[m\] is `D3` of an equilibrium (stable or
/// not) of that input. Each solution is verified by [`equilibria`] to
/// `IK_VERIFY_REL_TOL * max(L, |(x,y)|)`.
///
/// Derivation (replaces Eq. 9-16 / Appendix A): substituting Eq. 2-3 into
/// Eq. 5 gives Eq. 48, `delta1 cos th2 - delta2 sin th2 = -sqrt3 K1 L`, which
/// involves `theta2` only. With `delta1 = R cos(phi)`, `delta2 = R sin(phi)`
/// it reads `R cos(th2 + phi) = -sqrt3 K1 L`, so
/// `th2 = -phi +/- acos(-sqrt3 K1 L / R)` (no solution if `R < sqrt3 K1 L`).
/// Then `D1 = D3 - L(cos th2, sin th2)`, `L3 = |D1|`, `theta1 = atan2(D1)`;
/// roots with `D1` below the X axis are discarded (they need `L3 < 0`).
/// At most two solutions. Each root is polished by Newton on Eq. 48.
pub fn inverse_kinematics(p: &Params, x: f64, y: f64) -> Vec<IkSolution> {
    let (d1, d2) = delta(p, x, y);
    let c = SQRT_3 * p.k1 * p.l;
    let r = d1.hypot(d2);
    let mut out: Vec<IkSolution> = Vec::new();
    if !(r.is_finite()) || r == 0.0 {
        return out;
    }
    let ratio = -c / r;
    if ratio < -1.0 - 1e-12 {
        return out;
    }
    let alpha = ratio.clamp(-1.0, 1.0).acos();
    let phi = d2.atan2(d1);
    let mut roots = vec![wrap_angle(-phi + alpha)];
    if alpha > IK_DUPLICATE_TOL {
        roots.push(wrap_angle(-phi - alpha));
    }
    let target = Vector2::new(x, y);
    let tol = IK_VERIFY_REL_TOL * p.l.max(target.norm());
    for mut th2 in roots {
        for _ in 0..IK_NEWTON_STEPS {
            let (s, co) = th2.sin_cos();
            let f = d1 * co - d2 * s + c;
            let df = -d1 * s - d2 * co;
            if df.abs() > 1e-8 * r {
                th2 -= f / df;
            }
        }
        let d1v = target - p.l * Vector2::new(th2.cos(), th2.sin());
        let mut l3 = d1v.norm();
        let theta1 = if l3 <= IK_L3_ZERO_REL * p.l {
            l3 = 0.0;
            0.0
        } else {
            let t = d1v.y.atan2(d1v.x);
            if t >= 0.0 {
                t
            } else if d1v.y >= -IK_THETA1_CLAMP_REL * l3 {
                if t > -FRAC_PI_2 {
                    0.0
                } else {
                    PI
                }
            } else {
                continue;
            }
        };
        // Verify by forward kinematics.
        let eqs = equilibria(p, l3, theta1);
        let best = eqs
            .iter()
            .map(|e| ((Vector2::new(e.x, e.y) - target).norm(), *e))
            .min_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(std::cmp::Ordering::Equal));
        if let Some((err, e)) = best {
            if err <= tol {
                let dup = out
                    .iter()
                    .any(|s| (s.l3 - l3).abs() <= tol && (s.theta1 - theta1).abs() <= IK_DUPLICATE_TOL.max(tol));
                if !dup {
                    out.push(IkSolution { l3, theta1, theta2: e.theta2, stable: e.stable, stiffness: e.stiffness });
                }
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------
// The paper's own IK route (Eq. 8-16, Appendix A), for comparison.
// ---------------------------------------------------------------------------

/// Eq. 10: `[E1, E2, E3] = [1, -2(x cos th1 + y sin th1), x^2 + y^2 - L^2]` of
/// Eq. 9 `E1 L3^2 + E2 L3 + E3 = 0` (units 1, m, m^2). Correct.
pub fn e_coefficients_eq10(p: &Params, x: f64, y: f64, theta1: f64) -> [f64; 3] {
    let (s1, c1) = theta1.sin_cos();
    [1.0, -2.0 * (x * c1 + y * s1), x * x + y * y - p.l * p.l]
}

/// Eq. 12, derived (units N*m, N*m^2, N*m^3) for Eq. 11 `F1 L3^2 + F2 L3 + F3 = 0`,
/// which is `L (eta1 (x - L3 cos th1) - eta2 (y - L3 sin th1)) = 0`:
/// `F1 = sqrt3 K1 L` and `F2` as printed; `F3 = 2 sqrt3 K2 L^2 x - 2(2K1-K2) L^2 y`
/// (printed as a second "F2" and without the `sqrt3`).
pub fn f_coefficients_eq12(p: &Params, x: f64, y: f64, theta1: f64) -> [f64; 3] {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    let f1 = SQRT_3 * k1 * l;
    let f2 = l * (k1 + 2.0 * k2) * (x * s1 - y * c1) - SQRT_3 * l * c1 * (k1 * x + 2.0 * k2 * l)
        + (2.0 * (2.0 * k1 - k2) * l - SQRT_3 * k1 * y) * l * s1;
    let f3 = 2.0 * SQRT_3 * k2 * l * l * x - 2.0 * (2.0 * k1 - k2) * l * l * y;
    [f1, f2, f3]
}

/// Eq. 12's third coefficient exactly as printed: `2 K2 L^2 x - 2(2K1-K2) L^2 y` (wrong).
pub fn f3_eq12_as_printed(p: &Params, x: f64, y: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    2.0 * k2 * l * l * x - 2.0 * (2.0 * k1 - k2) * l * l * y
}

fn det2(a: f64, b: f64, c: f64, d: f64) -> f64 {
    a * d - b * c
}

/// Eq. 13: Bezout resultant of Eq. 9 and Eq. 11 (with the derived `F`).
pub fn bezout_eq13(p: &Params, x: f64, y: f64, theta1: f64) -> f64 {
    let [e1, e2, e3] = e_coefficients_eq10(p, x, y, theta1);
    let [f1, f2, f3] = f_coefficients_eq12(p, x, y, theta1);
    let m = det2(e1, e3, f1, f3);
    det2(e1, e2, f1, f2) * det2(e2, e3, f2, f3) - m * m
}

/// Eq. 14: common root `L3 = -|E2 E3; F2 F3| / |E1 E3; F1 F3|` \[m\].
pub fn l3_eq14(p: &Params, x: f64, y: f64, theta1: f64) -> f64 {
    let [e1, e2, e3] = e_coefficients_eq10(p, x, y, theta1);
    let [f1, f2, f3] = f_coefficients_eq12(p, x, y, theta1);
    -det2(e2, e3, f2, f3) / det2(e1, e3, f1, f3)
}

/// `phi1..phi4` of Eq. 15 derived from Eq. 13: with `G = E1F2 - E2F1 =
/// L (delta2 sin th1 - delta1 cos th1)` and `H = E2F3 - E3F2 = Hs sin th1 + Hc cos th1`,
/// `phi1 = L delta2 Hs`, `phi2 = L delta2 Hc - L delta1 Hs`, `phi3 = -L delta1 Hc`,
/// `phi4 = -(F3 - E3 F1)^2`.
pub fn phi_coefficients_derived(p: &Params, x: f64, y: f64) -> [f64; 4] {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (dl1, dl2) = delta(p, x, y);
    let e3 = x * x + y * y - l * l;
    let f1 = SQRT_3 * k1 * l;
    let f3 = 2.0 * SQRT_3 * k2 * l * l * x - 2.0 * (2.0 * k1 - k2) * l * l * y;
    let f2s = l * ((k1 + 2.0 * k2) * x + 2.0 * (2.0 * k1 - k2) * l - SQRT_3 * k1 * y);
    let f2c = -l * ((k1 + 2.0 * k2) * y + SQRT_3 * k1 * x + 2.0 * SQRT_3 * k2 * l);
    let hs = -2.0 * y * f3 - e3 * f2s;
    let hc = -2.0 * x * f3 - e3 * f2c;
    let (gs, gc) = (l * dl2, -l * dl1);
    let m = f3 - e3 * f1;
    [gs * hs, gs * hc + gc * hs, gc * hc, -m * m]
}

/// Appendix A, C.1-C.4 as printed, with C.3 (whose two factors the scan
/// flattened into a sum) read as the product
/// `[L(x^2+y^2-L^2)(K1y+2K2y+2sqrt3K2L+sqrt3K1x) - 4L^2x(K2y-2K1y+sqrt3K2x)]
///  * [-Ly(K1+2K2) - 2sqrt3L^2K2 + sqrt3K1Lx]`.
pub fn phi_coefficients_appendix_a(p: &Params, x: f64, y: f64) -> [f64; 4] {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let r2 = x * x + y * y;
    let w = k2 * y - 2.0 * k1 * y + SQRT_3 * k2 * x;
    let dm = 4.0 * k1 * l - 2.0 * k2 * l + k1 * x + 2.0 * k2 * x - SQRT_3 * k1 * y;
    let dp = 4.0 * k1 * l - 2.0 * k2 * l + k1 * x + 2.0 * k2 * x + SQRT_3 * k1 * y;
    let gm = k1 * y + 2.0 * k2 * y + 2.0 * SQRT_3 * k2 * l - SQRT_3 * k1 * x;
    let gp = k1 * y + 2.0 * k2 * y + 2.0 * SQRT_3 * k2 * l + SQRT_3 * k1 * x;
    let c1 = l * (l * (l * l - r2) * dm - 4.0 * l * l * y * w) * dp;
    let c2 = (4.0 * l * l * l * y * w + l * l * (r2 - l * l) * dm) * gm
        - l * (4.0 * l * l * x * w - l * (r2 - l * l) * gp) * dp;
    let c3 = (l * (r2 - l * l) * gp - 4.0 * l * l * x * w)
        * (-l * y * (k1 + 2.0 * k2) - 2.0 * SQRT_3 * l * l * k2 + SQRT_3 * k1 * l * x);
    let q = 2.0 * SQRT_3 * k2 * l * x - 2.0 * (2.0 * k1 - k2) * l * y + SQRT_3 * k1 * (l * l - r2);
    let c4 = -l * l * q * q;
    [c1, c2, c3, c4]
}

/// The paper's IK route: Eq. 15-16 roots `tan th1` mapped to `theta1 in [0, pi)`,
/// then Eq. 14 for `L3` (which may come out negative, i.e. `D1` below the X
/// axis). Uses the given `phi` coefficients. Returns `(L3, theta1)` pairs.
pub fn inverse_kinematics_eq16(p: &Params, x: f64, y: f64, phi: [f64; 4]) -> Vec<(f64, f64)> {
    let (qa, qb, qc) = (phi[0] + phi[3], phi[1], phi[2] + phi[3]);
    let mut ts = Vec::new();
    if qa == 0.0 {
        if qb != 0.0 {
            ts.push(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            ts.push((-qb + sq) / (2.0 * qa));
            ts.push((-qb - sq) / (2.0 * qa));
        }
    }
    ts.into_iter()
        .map(|t| {
            let mut th1 = t.atan();
            if th1 < 0.0 {
                th1 += PI;
            }
            (l3_eq14(p, x, y, th1), th1)
        })
        .collect()
}

// ---------------------------------------------------------------------------
// Jacobian and singularities (Eq. 17-37).
// ---------------------------------------------------------------------------

/// `(dtheta2/dL3 [rad/m], dtheta2/dtheta1 [rad/rad])` at an equilibrium, by
/// the implicit-function theorem on `tau = 0`: `dth2/dI = -(dtau/dI)/K`.
/// Equal to Eq. 22 `cos^2 th2 d(tan th2)/dI` (whose printed denominators lack the `d`).
pub fn dtheta2_dinputs(p: &Params, l3: f64, theta1: f64, theta2: f64) -> (f64, f64) {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    let (s2, c2) = theta2.sin_cos();
    // dA/dL3, dB/dL3; dA/dth1 = -L3 dB/dL3, dB/dth1 = L3 dA/dL3.
    let a_l = (0.5 * k1 + k2) * l * c1 + 0.5 * SQRT_3 * k1 * l * s1;
    let b_l = (0.5 * k1 + k2) * l * s1 - 0.5 * SQRT_3 * k1 * l * c1;
    let dtau_dl3 = -a_l * s2 + b_l * c2;
    let dtau_dth1 = l3 * (b_l * s2 + a_l * c2);
    let k = stiffness(p, l3, theta1, theta2);
    (-dtau_dl3 / k, -dtau_dth1 / k)
}

/// Eq. 22 as intended: `cos^2 th2 * d(eta1/eta2)/dI`, `I = (L3, theta1)`.
pub fn dtheta2_dinputs_eq22(p: &Params, l3: f64, theta1: f64, theta2: f64) -> (f64, f64) {
    let (k1, k2) = (p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    let (e1, e2) = eta(p, l3, theta1);
    let pp = (k1 + 2.0 * k2) * s1 - SQRT_3 * k1 * c1; // d eta1 / d L3
    let qq = (k1 + 2.0 * k2) * c1 + SQRT_3 * k1 * s1; // d eta2 / d L3
    let c2sq = theta2.cos().powi(2);
    let dtan_dl3 = (pp * e2 - e1 * qq) / (e2 * e2);
    let dtan_dth1 = (l3 * qq * e2 + e1 * l3 * pp) / (e2 * e2);
    (c2sq * dtan_dl3, c2sq * dtan_dth1)
}

/// Eq. 17-21: `J = d(x, y)/d(L3, theta1)` at an equilibrium `theta2`
/// (units: column 1 dimensionless, column 2 [m/rad]).
pub fn jacobian(p: &Params, l3: f64, theta1: f64, theta2: f64) -> Matrix2<f64> {
    let (s1, c1) = theta1.sin_cos();
    let (s2, c2) = theta2.sin_cos();
    let (a, b) = dtheta2_dinputs(p, l3, theta1, theta2);
    let l = p.l;
    Matrix2::new(
        c1 - l * s2 * a,       // Eq. 18
        -l3 * s1 - l * s2 * b, // Eq. 19
        s1 + l * c2 * a,       // Eq. 20
        l3 * c1 + l * c2 * b,  // Eq. 21
    )
}

/// `det J` [m/rad] from [`jacobian`].
pub fn det_jacobian(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    jacobian(p, l3, theta1, theta2).determinant()
}

/// Derived closed form: `det J = L3 (1 + s L (K1+2K2)/sqrt(eta1^2+eta2^2))`
/// with `s = -1` at the energy minimum and `+1` at the maximum
/// (`s = sign(eta2 cos th2 + eta1 sin th2)`). Equivalently
/// `det J = L3 (1 + L (K1+2K2) sin th2 / eta1)` (the corrected Eq. 23-24).
pub fn det_jacobian_closed_form(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let (e1, e2) = eta(p, l3, theta1);
    let (s2, c2) = theta2.sin_cos();
    let s = (e2 * c2 + e1 * s2).signum();
    l3 * (1.0 + s * p.l * (p.k1 + 2.0 * p.k2) / e1.hypot(e2))
}

/// Corrected Eq. 24 [N^3]: `Phi1 = eta1 N + L (K1+2K2) sin th2 N` with
/// `N = eta1^2 + eta2^2` (the printed version has a spurious extra `L3`).
pub fn phi1(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let (e1, _) = eta(p, l3, theta1);
    let n = eta_norm_sq(p, l3, theta1);
    e1 * n + p.l * (p.k1 + 2.0 * p.k2) * theta2.sin() * n
}

/// Eq. 24 exactly as printed: `eta1 N + 4 L3 L sin th2 (K1+2K2) [N/4]`.
pub fn phi1_eq24_as_printed(p: &Params, l3: f64, theta1: f64, theta2: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    let (e1, _) = eta(p, l3, theta1);
    let n = eta_norm_sq(p, l3, theta1);
    let bracket = 4.0 * l * l * (k1 * k1 + k2 * k2 - k1 * k2)
        + l3 * l3 * (k1 * k1 + k2 * k2 + k1 * k2)
        + 2.0 * l3 * l * c1 * (k1 * k1 - k2 * k2)
        + 2.0 * SQRT_3 * l3 * l * s1 * (k1 * k1 + k2 * k2);
    e1 * n + 4.0 * l3 * l * theta2.sin() * (k1 + 2.0 * k2) * bracket
}

/// Eq. 25 [N^3]: `Phi2 = eta1 (eta1^2 + eta2^2)` (correct).
pub fn phi2(p: &Params, l3: f64, theta1: f64) -> f64 {
    let (e1, _) = eta(p, l3, theta1);
    e1 * eta_norm_sq(p, l3, theta1)
}

/// Eq. 23 as printed, `L3 Phi1 / Phi2` with the printed Eq. 24-25; `None` when `Phi2 = 0`.
/// Dimensionally inconsistent (extra factor `L3` in the second term of `Phi1`).
pub fn det_jacobian_eq23(p: &Params, l3: f64, theta1: f64, theta2: f64) -> Option<f64> {
    let d = phi2(p, l3, theta1);
    if d == 0.0 {
        None
    } else {
        Some(l3 * phi1_eq24_as_printed(p, l3, theta1, theta2) / d)
    }
}

/// Eq. 23 with the corrected `Phi1` ([`phi1`]); `None` when `Phi2 = 0`.
pub fn det_jacobian_eq23_corrected(p: &Params, l3: f64, theta1: f64, theta2: f64) -> Option<f64> {
    let d = phi2(p, l3, theta1);
    if d == 0.0 {
        None
    } else {
        Some(l3 * phi1(p, l3, theta1, theta2) / d)
    }
}

/// Eq. 26, curve i: `L3 = 0` \[m\].
pub fn curve_i_eq26(l3: f64) -> f64 {
    l3
}

/// Eq. 27, curve ii: `sin th1 = 0` (only a boundary of the imposed range
/// `0 <= th1 <= pi`, not a singularity of `J`).
pub fn curve_ii_eq27(theta1: f64) -> f64 {
    theta1.sin()
}

/// Eq. 28, curve iii: `eta1 = 0` \[N\] (where the paper's `[0, pi]` FK branch
/// jumps; `det J` stays finite on both true branches).
pub fn curve_iii_eq28(p: &Params, l3: f64, theta1: f64) -> f64 {
    eta(p, l3, theta1).0
}

/// The theta1 in [0, pi/2] on curve iii (eta1 = 0, Eq. 28) for a given L3, by bisection;
/// None when the curve does not cross that range.
pub fn curve_iii_theta1(p: &Params, l3: f64) -> Option<f64> {
    let (mut lo, mut hi) = (0.0, FRAC_PI_2);
    if curve_iii_eq28(p, l3, lo) * curve_iii_eq28(p, l3, hi) > 0.0 {
        return None;
    }
    const BISECTION_STEPS: usize = 200;
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if curve_iii_eq28(p, l3, lo) * curve_iii_eq28(p, l3, mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// Eq. 33, curve iv (`theta1 = theta2 mod pi` substituted in Eq. 5) \[N*m\]:
/// `2(2K1-K2) L sin th1 - 2 sqrt3 K2 L cos th1 + sqrt3 K1 L3` (correct algebra;
/// equals `eta2 sin th1 - eta1 cos th1`).
pub fn curve_iv_eq33(p: &Params, l3: f64, theta1: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    2.0 * (2.0 * k1 - k2) * l * s1 - 2.0 * SQRT_3 * k2 * l * c1 + SQRT_3 * k1 * l3
}

/// `L3` on curve iv (Eq. 33 solved for `L3`) \[m\]; may be negative.
pub fn curve_iv_l3(p: &Params, theta1: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s1, c1) = theta1.sin_cos();
    -(2.0 * (2.0 * k1 - k2) * l * s1 - 2.0 * SQRT_3 * k2 * l * c1) / (SQRT_3 * k1)
}

/// Eq. 30 corrected, curve v [N^2]: `eta1^2 + eta2^2 - L^2 (K1+2K2)^2`;
/// zero exactly where the *stable* branch has `det J = 0` (`Phi1 = 0`).
/// In the `D1` plane this is a circle of radius `L(K1+2K2)/(2 sqrt(K1^2+K1K2+K2^2))`
/// about [`neutral_point`].
pub fn curve_v_eq30(p: &Params, l3: f64, theta1: f64) -> f64 {
    let g = p.l * (p.k1 + 2.0 * p.k2);
    eta_norm_sq(p, l3, theta1) - g * g
}

/// Eq. 34, curve i in Cartesian space [m^2]: `x^2 + y^2 - L^2`.
pub fn curve_i_eq34(p: &Params, x: f64, y: f64) -> f64 {
    x * x + y * y - p.l * p.l
}

/// Eq. 35, curve ii in Cartesian space [m^2]: `(x - L3)^2 + y^2 - L^2`.
pub fn curve_ii_eq35(p: &Params, x: f64, y: f64, l3: f64) -> f64 {
    (x - l3).powi(2) + y * y - p.l * p.l
}

/// Eq. 36 as printed \[N*m\]: `2 sqrt3 K1 x - (K1+2K2) y + 2 sqrt3 L (K2 - K1)` (wrong).
pub fn curve_iii_eq36_as_printed(p: &Params, x: f64, y: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    2.0 * SQRT_3 * k1 * x - (k1 + 2.0 * k2) * y + 2.0 * SQRT_3 * l * (k2 - k1)
}

/// Curve iii (`eta1 = 0`) in Cartesian space, derived \[N*m\]. On `eta1 = 0`
/// the equilibria are `theta2 = 0` and `theta2 = pi`; with `theta2 = 0`
/// (`theta2_is_pi = false`, the paper's Eq. 38-39):
/// `(K1+2K2) y - sqrt3 K1 x + sqrt3 (K1+2K2) L = 0`; with `theta2 = pi`:
/// `(K1+2K2) y - sqrt3 K1 x + sqrt3 (2K2-K1) L = 0`.
pub fn curve_iii_cartesian(p: &Params, x: f64, y: f64, theta2_is_pi: bool) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let c = if theta2_is_pi { 2.0 * k2 - k1 } else { k1 + 2.0 * k2 };
    (k1 + 2.0 * k2) * y - SQRT_3 * k1 * x + SQRT_3 * c * l
}

/// Eq. 37 as printed [m^2]: `x^2 + y^2 - 9 L^2` (this is the outer reach
/// circle `L3 = 2L, theta2 = theta1`, not curve iv).
pub fn curve_iv_eq37_as_printed(p: &Params, x: f64, y: f64) -> f64 {
    x * x + y * y - 9.0 * p.l * p.l
}

/// Curve iv in Cartesian space, derived [N*m^2]:
/// `2(2K1-K2) L y - 2 sqrt3 K2 L x + sqrt3 K1 (r^2 - L r) = 0`, `r = |D3|`.
/// Covers `theta2 = theta1` (`D3 = (L3 + L) e(theta1)`) and `theta2 = theta1 + pi`
/// with `L3 < L` (`D3 = -(L - L3) e(theta1)`); for `theta2 = theta1 + pi` with
/// `L3 > L` the term is `+L r` instead.
pub fn curve_iv_cartesian(p: &Params, x: f64, y: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let r = x.hypot(y);
    2.0 * (2.0 * k1 - k2) * l * y - 2.0 * SQRT_3 * k2 * l * x + SQRT_3 * k1 * (r * r - l * r)
}

/// The neutral point `D1*` \[m\]: the actuator-node position where
/// `eta1 = eta2 = 0`, i.e. where `U` does not depend on `theta2` (`K = 0`).
pub fn neutral_point(p: &Params) -> Vector2<f64> {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    // eta2 = 0: (K1+2K2) X + sqrt3 K1 Y = -2(2K1-K2) L
    // eta1 = 0: -sqrt3 K1 X + (K1+2K2) Y = -2 sqrt3 K2 L
    let m = Matrix2::new(k1 + 2.0 * k2, SQRT_3 * k1, -SQRT_3 * k1, k1 + 2.0 * k2);
    let rhs = Vector2::new(-2.0 * (2.0 * k1 - k2) * l, -2.0 * SQRT_3 * k2 * l);
    let det = m.determinant();
    let inv = Matrix2::new(m[(1, 1)], -m[(0, 1)], -m[(1, 0)], m[(0, 0)]) / det;
    inv * rhs
}

/// Stiffness at the stable equilibrium, closed form [N*m/rad]:
/// `K = (L/2) sqrt(eta1^2+eta2^2) = L sqrt(K1^2+K1K2+K2^2) |D1 - D1*|`.
pub fn stiffness_stable_closed_form(p: &Params, l3: f64, theta1: f64) -> f64 {
    let d1 = l3 * Vector2::new(theta1.cos(), theta1.sin());
    p.l * (p.k1 * p.k1 + p.k1 * p.k2 + p.k2 * p.k2).sqrt() * (d1 - neutral_point(p)).norm()
}

// ---------------------------------------------------------------------------
// Stiffness distribution formulas (Eq. 46-52).
// ---------------------------------------------------------------------------

/// Eq. 46 as printed: `(sin th2, cos th2) = (|eta1|/|eta|, |eta1|/|eta| * eta2/eta1)`
/// (the `[0, pi]` root of Eq. 5). Returns `(sin, cos)`.
pub fn sincos_theta2_eq46(p: &Params, l3: f64, theta1: f64) -> (f64, f64) {
    let (e1, e2) = eta(p, l3, theta1);
    let f = (e1 * e1 / (e1 * e1 + e2 * e2)).sqrt();
    (f, f * e2 / e1)
}

/// Eq. 47 as printed [N*m/rad]: `K = -sqrt(eta1^2/(eta1^2+eta2^2)) (A eta2/eta1 + B)`.
/// Equals `-sign(eta1) (L/2) sqrt(eta1^2+eta2^2)`: the stiffness at the
/// paper's `[0, pi]` root, negative (unstable) whenever `eta1 > 0`.
pub fn stiffness_eq47(p: &Params, l3: f64, theta1: f64) -> f64 {
    let e = energy_coefficients_eq4(p, l3, theta1);
    let (e1, e2) = eta(p, l3, theta1);
    -(e1 * e1 / (e1 * e1 + e2 * e2)).sqrt() * (e.a * e2 / e1 + e.b)
}

/// Eq. 49 as printed [N*m/rad], `K` in terms of `(x, y, theta2)` (wrong sign
/// pattern, see [`stiffness_xy_derived`]).
pub fn stiffness_eq49_as_printed(p: &Params, x: f64, y: f64, theta2: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s2, c2) = theta2.sin_cos();
    ((2.0 * k1 - k2) * l * l + (0.5 * k1 + k2) * l * x - 0.5 * SQRT_3 * k1 * l * y) * c2
        + ((0.5 * k1 + k2) * l * y - 0.5 * SQRT_3 * k1 * l * x + SQRT_3 * k2 * l * l) * s2
        - (0.5 * k1 + k2) * l * l
}

/// Corrected Eq. 49 [N*m/rad]:
/// `K = -[(2K1-K2)L^2 + (K1/2+K2)Lx + sqrt3/2 K1 L y] cos th2
///      - [(K1/2+K2)Ly - sqrt3/2 K1 L x + sqrt3 K2 L^2] sin th2 + (K1/2+K2) L^2`.
pub fn stiffness_xy_derived(p: &Params, x: f64, y: f64, theta2: f64) -> f64 {
    let (l, k1, k2) = (p.l, p.k1, p.k2);
    let (s2, c2) = theta2.sin_cos();
    -((2.0 * k1 - k2) * l * l + (0.5 * k1 + k2) * l * x + 0.5 * SQRT_3 * k1 * l * y) * c2
        - ((0.5 * k1 + k2) * l * y - 0.5 * SQRT_3 * k1 * l * x + SQRT_3 * k2 * l * l) * s2
        + (0.5 * k1 + k2) * l * l
}

/// The `theta2` root Eq. 52 uses \[rad\]:
/// `2 atan((delta2 + sqrt(delta1^2+delta2^2-3K1^2L^2)) / (sqrt3 K1 L - delta1))`
/// (a correct root of Eq. 48; NaN outside the workspace).
pub fn theta2_eq52(p: &Params, x: f64, y: f64) -> f64 {
    let (d1, d2) = delta(p, x, y);
    let c = SQRT_3 * p.k1 * p.l;
    2.0 * ((d2 + (d1 * d1 + d2 * d2 - c * c).sqrt()) / (c - d1)).atan()
}

/// Eq. 52 as printed [N*m/rad]: Eq. 49 (as printed) evaluated at [`theta2_eq52`].
pub fn stiffness_eq52(p: &Params, x: f64, y: f64) -> f64 {
    stiffness_eq49_as_printed(p, x, y, theta2_eq52(p, x, y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    const P: Params = Params::PAPER_WORKSPACE;
    /// Full turn [rad].
    const TWO_PI: f64 = 2.0 * PI;

    /// Deterministic 64-bit LCG (Knuth MMIX constants) -> uniform [0, 1).
    struct Lcg(u64);
    impl Lcg {
        fn next_f64(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn validate_rejects_bad_params() {
        assert!(P.validate().is_ok());
        assert!(Params { l: 0.0, ..P }.validate().is_err());
        assert!(Params { k1: -1.0, ..P }.validate().is_err());
        assert!(Params { k2: f64::NAN, ..P }.validate().is_err());
        assert!(Params { l: f64::INFINITY, ..P }.validate().is_err());
    }

    proptest! {
        #[test]
        fn energy_eq4_equals_spring_energy(l in 0.1f64..3.0, k1 in 1.0f64..500.0, k2 in 1.0f64..500.0,
                                           l3 in 0.0f64..8.0, t1 in -4.0f64..4.0, t2 in -4.0f64..4.0) {
            let p = Params { l, k1, k2 };
            let u = potential_energy(&p, l3, t1, t2);
            let u4 = potential_energy_eq4(&p, l3, t1, t2);
            prop_assert!((u - u4).abs() <= 1e-12 * (k1 + k2) * (l + l3).powi(2) + 1e-12);
        }

        #[test]
        fn torque_and_stiffness_match_central_differences(l3 in 0.0f64..6.0, t1 in 0.0f64..3.2, t2 in -3.2f64..3.2) {
            let h = 1e-5;
            let fd_tau = (potential_energy(&P, l3, t1, t2 + h) - potential_energy(&P, l3, t1, t2 - h)) / (2.0 * h);
            let fd_k = (torque(&P, l3, t1, t2 + h) - torque(&P, l3, t1, t2 - h)) / (2.0 * h);
            let sc = (P.k1 + P.k2) * (P.l + l3).powi(2);
            prop_assert!((fd_tau - torque(&P, l3, t1, t2)).abs() < 1e-7 * sc);
            prop_assert!((fd_k - stiffness(&P, l3, t1, t2)).abs() < 1e-7 * sc);
            prop_assert!((torque_eq41(&P, l3, t1, t2) - torque(&P, l3, t1, t2)).abs() < 1e-11 * sc);
            prop_assert!((stiffness_eq42(&P, l3, t1, t2) - stiffness(&P, l3, t1, t2)).abs() < 1e-11 * sc);
        }
    }

    #[test]
    fn nodes_form_equilateral_triangles() {
        let n = nodes(&P, 1.3, 0.7, -2.1);
        assert_relative_eq!((n.d1 - n.d2).norm(), 1.0, epsilon = 1e-14);
        assert_relative_eq!((n.d2 - n.d3).norm(), 1.0, epsilon = 1e-14);
        assert_relative_eq!((n.d1 - n.d3).norm(), 1.0, epsilon = 1e-14);
        assert_relative_eq!((n.c2 - n.c3).norm(), 2.0, epsilon = 1e-14);
        assert_relative_eq!((n.c1 - n.c3).norm(), 2.0, epsilon = 1e-14);
        let (a, b) = spring_lengths(&P, 1.3, 0.7, -2.1);
        assert_relative_eq!(a, (n.d2 - n.c2).norm());
        assert_relative_eq!(b, (n.d3 - n.c3).norm());
    }

    #[test]
    fn eta_is_twice_eq4_coefficients_over_l() {
        let p = Params { l: 0.7, k1: 30.0, k2: 55.0 };
        let e = energy_coefficients_eq4(&p, 1.1, 2.3);
        let (e1, e2) = eta(&p, 1.1, 2.3);
        assert_relative_eq!(e1, 2.0 * e.b / p.l, max_relative = 1e-13);
        assert_relative_eq!(e2, 2.0 * e.a / p.l, max_relative = 1e-13);
    }

    #[test]
    fn equilibria_have_zero_torque_and_minimum_has_positive_stiffness() {
        let mut rng = Lcg(7);
        for _ in 0..300 {
            let l3 = 3.0 * rng.next_f64();
            let t1 = PI * rng.next_f64();
            let [mn, mx] = equilibria(&P, l3, t1);
            let sc = (P.k1 + P.k2) * (1.0 + l3).powi(2);
            assert!(torque(&P, l3, t1, mn.theta2).abs() < 1e-12 * sc);
            assert!(torque(&P, l3, t1, mx.theta2).abs() < 1e-12 * sc);
            assert!(mn.stable && mn.stiffness > 0.0 && !mx.stable && mx.stiffness < 0.0);
            assert!(mn.energy < mx.energy);
            assert_relative_eq!(mn.stiffness, -mx.stiffness, max_relative = 1e-10);
            assert_relative_eq!(mn.stiffness, stiffness_stable_closed_form(&P, l3, t1), max_relative = 1e-10);
            assert!(mn.theta2 > -PI && mn.theta2 <= PI && mx.theta2 > -PI && mx.theta2 <= PI);
            assert_relative_eq!(wrap_angle(mx.theta2 - mn.theta2).abs(), PI, epsilon = 1e-12);
            // Energy minimum really is a minimum against a scan.
            for k in 0..64 {
                let t2 = -PI + TWO_PI * k as f64 / 64.0;
                assert!(potential_energy(&P, l3, t1, t2) >= mn.energy - 1e-9 * sc);
            }
        }
    }

    #[test]
    fn paper_fk_branch_is_minimum_iff_eta1_negative() {
        for (l3, t1) in [(0.5, 1.0), (1.8, 0.05), (1.5, 0.2), (2.0, 2.5), (0.0, 0.0)] {
            let (e1, _) = eta(&P, l3, t1);
            let e = fk_paper(&P, l3, t1);
            assert!(e.theta2 >= 0.0 && e.theta2 <= PI);
            assert!(torque(&P, l3, t1, e.theta2).abs() < 1e-9);
            assert_eq!(e.stable, e1 < 0.0, "l3={l3} t1={t1} eta1={e1}");
            assert_relative_eq!(stiffness_eq47(&P, l3, t1), e.stiffness, max_relative = 1e-10);
        }
    }

    #[test]
    fn figs_4_to_6_example_numbers() {
        let q = Params::PAPER_FIG4;
        let [mn, mx] = equilibria(&q, PAPER_FIG4_L3, PAPER_FIG4_THETA1);
        // Independent hand computation: eta1 = 120*6 sin18 - 100 sqrt3 *6 cos18 + 20 sqrt3,
        // eta2 = 380 + 720 cos18 + 600 sqrt3 sin18; th2_m = atan2(-eta1, -eta2).
        let s18 = (PI / 10.0).sin();
        let c18 = (PI / 10.0).cos();
        let e1 = 720.0 * s18 - 600.0 * SQRT_3 * c18 + 20.0 * SQRT_3;
        let e2 = 380.0 + 720.0 * c18 + 600.0 * SQRT_3 * s18;
        assert_relative_eq!(e1, -731.233_672_154_258_6, epsilon = 1e-9);
        assert_relative_eq!(mn.theta2, (-e1).atan2(-e2), epsilon = 1e-12);
        assert_relative_eq!(mn.theta2, 2.656_091_256_013_927, epsilon = 1e-12);
        assert_relative_eq!(mn.stiffness, 0.5 * e1.hypot(e2), max_relative = 1e-12);
        assert_relative_eq!(mn.stiffness, 783.489_483_054_247_6, epsilon = 1e-9);
        assert!(mn.stable && !mx.stable);
        // Paper's [0, pi] FK gives the same (stable) root here because eta1 < 0.
        let pk = fk_paper(&q, PAPER_FIG4_L3, PAPER_FIG4_THETA1);
        assert_relative_eq!(pk.theta2, mn.theta2, epsilon = 1e-12);
        // K = 0 at th2_0 = th2_m - pi/2, inside [0, pi].
        let th2_0 = mn.theta2 - FRAC_PI_2;
        assert!(stiffness(&q, PAPER_FIG4_L3, PAPER_FIG4_THETA1, th2_0).abs() < 1e-9);
        assert!(th2_0 > 0.0 && th2_0 < PI);
    }

    fn check_round_trip(p: &Params, seed: u64, l3_max: f64, n: usize) -> (usize, f64) {
        let mut rng = Lcg(seed);
        let mut worst: f64 = 0.0;
        let mut tested = 0;
        for i in 0..n {
            let l3 = 0.02 * p.l + (l3_max - 0.02 * p.l) * rng.next_f64();
            let t1 = PI * rng.next_f64();
            let e = equilibria(p, l3, t1)[i % 2];
            let sols = inverse_kinematics(p, e.x, e.y);
            assert!(!sols.is_empty() && sols.len() <= 2);
            for s in &sols {
                assert!(s.l3 >= 0.0 && s.theta1 >= 0.0 && s.theta1 <= PI);
                let eqs = equilibria(p, s.l3, s.theta1);
                let err = eqs.iter().map(|q| (q.x - e.x).hypot(q.y - e.y)).fold(f64::INFINITY, f64::min);
                assert!(err < 1e-10, "IK solution not verified: {err}");
            }
            let best = sols.iter().map(|s| (s.l3 - l3).abs().max((s.theta1 - t1).abs())).fold(f64::INFINITY, f64::min);
            let m = sols.iter().find(|s| (s.l3 - l3).abs().max((s.theta1 - t1).abs()) == best).unwrap();
            assert_eq!(m.stable, e.stable);
            worst = worst.max(best);
            tested += 1;
        }
        (tested, worst)
    }

    #[test]
    fn fk_ik_round_trip_200_random_points() {
        let (n, worst) = check_round_trip(&P, 12345, 2.0, 200);
        assert_eq!(n, 200);
        assert!(worst < 1e-10, "worst round-trip deviation {worst}");
        let (n, worst) = check_round_trip(&Params::PAPER_FIG4, 999, 8.0, 200);
        assert_eq!(n, 200);
        assert!(worst < 1e-10, "worst round-trip deviation {worst}");
    }

    #[test]
    fn ik_solutions_are_verified_by_fk_on_a_cartesian_grid() {
        let mut count = 0;
        for i in -12..=12 {
            for j in -12..=12 {
                let (x, y) = (0.25 * i as f64, 0.25 * j as f64);
                for s in inverse_kinematics(&P, x, y) {
                    let e = equilibria(&P, s.l3, s.theta1);
                    let m = e.iter().find(|q| (q.x - x).hypot(q.y - y) < 1e-10).expect("verified");
                    assert_relative_eq!(m.theta2, s.theta2, epsilon = 1e-12);
                    assert_eq!(m.stable, s.stable);
                    count += 1;
                }
            }
        }
        assert!(count > 100, "only {count} solutions");
    }

    #[test]
    fn paper_ik_route_with_appendix_a_reproduces_ik() {
        let mut rng = Lcg(4242);
        for _ in 0..50 {
            let l3 = 0.1 + 1.9 * rng.next_f64();
            let t1 = 0.05 + 3.0 * rng.next_f64();
            let e = equilibria(&P, l3, t1)[0];
            let a = phi_coefficients_appendix_a(&P, e.x, e.y);
            let d = phi_coefficients_derived(&P, e.x, e.y);
            let sc = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..4 {
                assert!((a[k] - d[k]).abs() < 1e-10 * sc, "phi{} mismatch", k + 1);
            }
            assert!(bezout_eq13(&P, e.x, e.y, t1).abs() < 1e-9 * d[3].abs().max(1.0));
            assert_relative_eq!(l3_eq14(&P, e.x, e.y, t1), l3, epsilon = 1e-8);
            let c = inverse_kinematics_eq16(&P, e.x, e.y, a);
            assert!(c.iter().any(|&(cl, ct)| (cl - l3).abs() < 1e-7 && (ct - t1).abs() < 1e-7));
            // printed F3 (without sqrt3) breaks Eq. 11
            let [f1, f2, _] = f_coefficients_eq12(&P, e.x, e.y, t1);
            let r = f1 * l3 * l3 + f2 * l3 + f3_eq12_as_printed(&P, e.x, e.y);
            let r_ok = f1 * l3 * l3 + f2 * l3 + f_coefficients_eq12(&P, e.x, e.y, t1)[2];
            assert!(r_ok.abs() < 1e-9 * P.k1);
            if e.x.abs() > 0.05 {
                assert!(r.abs() > 1e-3 * P.k1);
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences_of_fk() {
        let h = 1e-6;
        let mut rng = Lcg(31);
        for _ in 0..100 {
            let l3 = 0.1 + 1.9 * rng.next_f64();
            let t1 = 0.05 + 3.0 * rng.next_f64();
            for b in 0..2 {
                let fk = |a: f64, t: f64| {
                    let e = equilibria(&P, a, t)[b];
                    Vector2::new(e.x, e.y)
                };
                let j = jacobian(&P, l3, t1, equilibria(&P, l3, t1)[b].theta2);
                let c1 = (fk(l3 + h, t1) - fk(l3 - h, t1)) / (2.0 * h);
                let c2 = (fk(l3, t1 + h) - fk(l3, t1 - h)) / (2.0 * h);
                let jf = Matrix2::from_columns(&[c1, c2]);
                assert!((j - jf).abs().max() < 1e-6 * (1.0 + j.abs().max()), "J={j} fd={jf}");
                let th2 = equilibria(&P, l3, t1)[b].theta2;
                let dj = det_jacobian(&P, l3, t1, th2);
                assert_relative_eq!(
                    dj,
                    det_jacobian_closed_form(&P, l3, t1, th2),
                    epsilon = 1e-10,
                    max_relative = 1e-10
                );
                assert_relative_eq!(
                    dj,
                    det_jacobian_eq23_corrected(&P, l3, t1, th2).unwrap(),
                    epsilon = 1e-9,
                    max_relative = 1e-9
                );
                let (a1, b1) = dtheta2_dinputs(&P, l3, t1, th2);
                let (a2, b2) = dtheta2_dinputs_eq22(&P, l3, t1, th2);
                assert_relative_eq!(a1, a2, epsilon = 1e-9, max_relative = 1e-9);
                assert_relative_eq!(b1, b2, epsilon = 1e-9, max_relative = 1e-9);
            }
        }
    }

    #[test]
    fn printed_det_eq23_differs_but_corrected_matches() {
        let (l3, t1) = (1.5, 1.0);
        let th2 = equilibria(&P, l3, t1)[0].theta2;
        let dj = det_jacobian(&P, l3, t1, th2);
        let pr = det_jacobian_eq23(&P, l3, t1, th2).unwrap();
        assert!((pr - dj).abs() > 1e-2 * dj.abs().max(1e-3));
        // At L3 = L the spurious factor L3/L = 1 makes them agree.
        let th2b = equilibria(&P, 1.0, t1)[0].theta2;
        assert_relative_eq!(
            det_jacobian_eq23(&P, 1.0, t1, th2b).unwrap(),
            det_jacobian(&P, 1.0, t1, th2b),
            max_relative = 1e-9
        );
    }

    #[test]
    fn det_j_is_zero_on_curve_v_and_finite_on_curve_iii() {
        let c = neutral_point(&P);
        let (e1, e2) = eta(&P, c.norm(), c.y.atan2(c.x));
        assert!(e1.abs() < 1e-10 && e2.abs() < 1e-10);
        let rad = P.l * (P.k1 + 2.0 * P.k2) / (2.0 * (P.k1 * P.k1 + P.k1 * P.k2 + P.k2 * P.k2).sqrt());
        let d1 = c + rad * Vector2::new(1.2f64.cos(), 1.2f64.sin());
        let (l3, t1) = (d1.norm(), d1.y.atan2(d1.x));
        assert!(curve_v_eq30(&P, l3, t1).abs() < 1e-8);
        let st = equilibria(&P, l3, t1)[0];
        assert!(det_jacobian(&P, l3, t1, st.theta2).abs() < 1e-10);
        assert!(phi1(&P, l3, t1, st.theta2).abs() < 1e-6 * phi2(&P, l3, t1).abs().max(1.0) + 1e-3);
        // curve iii: eta1 = 0 at L3 = 2, th1 from bisection -> det J finite
        let (mut lo, mut hi) = (0.0, FRAC_PI_2);
        for _ in 0..100 {
            let m = 0.5 * (lo + hi);
            if curve_iii_eq28(&P, 2.0, lo) * curve_iii_eq28(&P, 2.0, m) <= 0.0 {
                hi = m
            } else {
                lo = m
            }
        }
        for e in equilibria(&P, 2.0, lo) {
            let dj = det_jacobian(&P, 2.0, lo, e.theta2);
            assert!(dj.is_finite() && dj.abs() < 10.0);
            assert!(curve_iii_cartesian(&P, e.x, e.y, e.theta2.abs() > FRAC_PI_2).abs() < 1e-9 * P.k1);
            assert!(curve_iii_eq36_as_printed(&P, e.x, e.y).abs() > 1.0);
        }
    }

    #[test]
    fn curve_iv_is_theta1_equals_theta2_but_not_radius_3l() {
        for t1 in [0.05, 0.2, 0.4] {
            let l3 = curve_iv_l3(&P, t1);
            assert!(l3 > 0.0);
            assert!(curve_iv_eq33(&P, l3, t1).abs() < 1e-10);
            let hit = equilibria(&P, l3, t1).into_iter().find(|e| wrap_angle(e.theta2 - t1).abs() < 1e-9).unwrap();
            assert_relative_eq!(hit.x.hypot(hit.y), l3 + P.l, epsilon = 1e-12);
            assert!(curve_iv_cartesian(&P, hit.x, hit.y).abs() < 1e-9 * P.k1);
            assert!(curve_iv_eq37_as_printed(&P, hit.x, hit.y).abs() > 1.0);
            assert!(det_jacobian(&P, l3, t1, hit.theta2).abs() > 1e-3);
            // the stable equilibrium is th2 = th1 + pi here, |D3| = L - L3, same Cartesian curve
            let st = equilibria(&P, l3, t1)[0];
            assert_relative_eq!(wrap_angle(st.theta2 - t1 - PI), 0.0, epsilon = 1e-9);
            assert_relative_eq!(st.x.hypot(st.y), P.l - l3, epsilon = 1e-12);
            assert!(curve_iv_cartesian(&P, st.x, st.y).abs() < 1e-9 * P.k1);
        }
    }

    #[test]
    fn stiffness_xy_forms() {
        let mut rng = Lcg(77);
        for _ in 0..50 {
            let l3 = 0.1 + 1.9 * rng.next_f64();
            let t1 = 0.05 + 3.0 * rng.next_f64();
            for e in equilibria(&P, l3, t1) {
                assert_relative_eq!(
                    stiffness_xy_derived(&P, e.x, e.y, e.theta2),
                    e.stiffness,
                    epsilon = 1e-9,
                    max_relative = 1e-10
                );
                assert!(equilibrium_residual_eq48(&P, e.x, e.y, e.theta2).abs() < 1e-10 * P.k1);
                let t52 = theta2_eq52(&P, e.x, e.y);
                assert!(equilibrium_residual_eq48(&P, e.x, e.y, t52).abs() < 1e-9 * P.k1);
            }
        }
        // printed Eq. 49 is off
        let e = equilibria(&P, 1.2, 1.0)[0];
        assert!((stiffness_eq49_as_printed(&P, e.x, e.y, e.theta2) - e.stiffness).abs() > 1.0);
    }

    /// K' = -tau and K'' = -K by central differences, each within the bound of its error: with
    /// K = -A cos th2 - B sin th2 (Eq. 42) every derivative of K is at most R = hypot(A, B), so
    /// truncation is at most h^2 R / 6 (first) and h^2 R / 12 (second); each evaluation of K
    /// rounds its terms, of size at most S = |u0| + R, by at most 4 eps S, which the difference
    /// quotients divide by h and h^2. h = 1e-3 balances the two for the second difference.
    #[test]
    fn derivative_identities_eq43_to_45() {
        let (l3, t1) = (1.3, 0.9);
        let e = energy_coefficients_eq4(&P, l3, t1);
        let (r, h) = (e.a.hypot(e.b), 1e-3);
        let ulp = 4.0 * f64::EPSILON * (e.u0.abs() + r);
        let tol_first = h * h * r / 6.0 + 2.0 * ulp / (2.0 * h);
        let tol_second = h * h * r / 12.0 + 4.0 * ulp / (h * h);
        for t2 in [-2.0, 0.4, 1.7] {
            let k = |t: f64| stiffness(&P, l3, t1, t);
            let dk = (k(t2 + h) - k(t2 - h)) / (2.0 * h);
            let d2k = (k(t2 + h) - 2.0 * k(t2) + k(t2 - h)) / (h * h);
            assert!((dk + torque(&P, l3, t1, t2)).abs() <= tol_first, "K' + tau = {:e}", dk + torque(&P, l3, t1, t2));
            assert!((d2k + k(t2)).abs() <= tol_second, "K'' + K = {:e} (bound {tol_second:e})", d2k + k(t2));
            // j = 0 only up to the constant U0
            assert_relative_eq!(
                potential_energy(&P, l3, t1, t2) + stiffness(&P, l3, t1, t2),
                e.u0,
                max_relative = 1e-12
            );
        }
    }
}
