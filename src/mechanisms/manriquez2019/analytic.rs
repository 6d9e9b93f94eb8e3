//! Closed-form model of the class 2 tensegrity robot of Manríquez-Padilla,
//! Zavala-Pérez, Pérez-Soto, Rodríguez-Reséndiz & Camarillo-Gómez (2019),
//! "Form-Finding Analysis of a Class 2 Tensegrity Robot", Appl. Sci. 9, 2948.
//!
//! Everything here is a pure function of `f64` / `nalgebra` values.
//! **Public API units are SI**: lengths \[m\], angles \[rad\], forces \[N\],
//! moments \[N*m\], stiffness [N/m], energies \[J\]. The paper's tables are in
//! millimetres and N*mm; they are kept as `*_MM` / `*_NMM` constants and the
//! helpers [`to_mm`], [`from_mm`], [`vec_to_mm`] convert.
//!
//! # Model
//! * Frames (paper Fig. 2, Eq. 1-5). `Σ_W` is the base frame. The universal
//!   joint centre `O` (origin of `Σ_0`) is at `(l1, 0, 0)` (Eq. 1). The joint
//!   turns by `θ1` about `z_W` (axis fixed in the base) and then by `θ2` about
//!   the platform's own `y_M` axis (fixed in the platform), so the platform
//!   orientation is `R = Rz(θ1) Ry(θ2)` (the rotation block of Eq. 15) and
//!   `M = O + R (a2, 0, 0)`. The two joint axes always stay perpendicular; the
//!   joint can transmit a moment only about `n = z_W × y_M` (unit).
//! * Platform points (platform frame, measured from `O`): cable ends
//!   `M1 = (a2, +l2/2, -l2/2)`, `M2 = (a2, -l2/2, +l2/2)` (Eq. 4-5, 8-9);
//!   spring ends (not in the paper; the other diagonal of the same square)
//!   `R1 = (a2, +l2/2, +l2/2)`, `R2 = (a2, -l2/2, -l2/2)`; centroid `G` on the
//!   rod axis at [`CENTROID_RADIUS_MM`] from `O` (see [`Params::PAPER`]).
//! * Base points (not in the paper; fitted, see [`FIT_BASE_X_MM`]): a square
//!   in the plane `x = base_x` aligned with the platform square:
//!   `B1 = (bx, +b, -b)`, `B2 = (bx, -b, +b)` (cables),
//!   `B3 = (bx, +b, +b)`, `B4 = (bx, -b, -b)` (springs `r1`, `r2`).
//! * Gravity `g = 9.81 m/s^2` acts along **`+x_W`**: the base is the upper
//!   ("superior") base and the platform hangs below the joint. Table 5 forces
//!   this reading: in every experiment `Σ|f_flexible| - |f_joint| = 4.63 N ≈ m g
//!   = 4.642 N`, i.e. the weight is (anti)parallel to the pull of the four
//!   flexible elements (see [`findings`](super::findings::findings)).
//! * Springs are linear, tension-only: `f = k max(0, L - L0)` toward the base
//!   point. Cables are tension-only members of actuated length.
//!
//! # Statics (Eq. 18-23) and the equilibrium condition (Eq. 26-27)
//! With the spring forces known from their lengths, Eq. 22-23 have exactly six
//! unknowns: the two cable tensions, the joint force (3 components) and the
//! joint moment about `n` (the universal joint cannot resist a moment about its
//! two free axes `z_W` and `y_M`). The moment equation about `O` gives
//! `T1, T2, m_n` (3x3 linear system); Eq. 22 then gives `f_joint`.
//! The configuration is an **equilibrium** (implemented reading of the garbled
//! Eq. 26-27) when both cable tensions are `>= 0` and both springs are
//! stretched (`L >= L0`): every flexible element in tension. The rigid link's
//! axial force (`f_joint · x_M > 0`: the rod is compressed) is reported
//! separately ([`Statics::rod_in_compression`]); it is not required because a
//! universal joint carries tension as well. As printed, Eq. 26-27 require
//! `|f_joint| <= 0` and `|m_joint| = 0`, which Table 5 itself violates.

use crate::mechanisms::ParamError;
use nalgebra::{Matrix2, Matrix3, Matrix4, Vector2, Vector3};
use std::cmp::Ordering;

// ---------------------------------------------------------------------------
// Paper constants (Table 1-3, 5) and unit helpers.
// ---------------------------------------------------------------------------

/// Millimetres per metre.
pub const MM_PER_M: f64 = 1000.0;
/// Table 1-2: `a2`, distance from the joint centre to the platform \[mm\].
pub const A2_MM: f64 = 210.0;
/// Table 2: `l1`, distance from the base to the joint centre \[mm\].
pub const L1_MM: f64 = 190.0;
/// Table 2: `l2`, width of the moving platform \[mm\].
pub const L2_MM: f64 = 220.0;
/// Table 2: mass of the moving platform \[kg\].
pub const PLATFORM_MASS_KG: f64 = 0.4732;
/// Gravitational acceleration used throughout [m/s^2] (the paper gives none).
pub const GRAVITY_M_S2: f64 = 9.81;
/// Table 2: "initial" centroid `(x_ce, y_ce, z_ce)` in `Σ_W` \[mm\].
pub const TABLE2_CENTROID_MM: [f64; 3] = [354.0442, 0.0, 76.4886];
/// Decoded from Table 2: `|O G| = sqrt(164.0442^2 + 76.4886^2) = 181.000 mm`.
pub const CENTROID_RADIUS_MM: f64 = 181.0;
/// Decoded from Table 2: `atan2(76.4886, 164.0442) = 0.4363 rad` (25 deg rounded
/// to four decimals like the paper's other angles). Table 2's centroid is the
/// on-axis centroid at `θ = (0, -CENTROID_ELEVATION_RAD)`.
pub const CENTROID_ELEVATION_RAD: f64 = 0.4363;
/// Table 2: first value of both joint coordinates \[rad\].
// The paper's printed value, rounded to four decimals like its other angles: not `-π/6`.
#[allow(clippy::approx_constant)]
pub const GRID_START_RAD: f64 = -0.5236;
/// Table 2: joint-coordinate increment \[rad\].
pub const GRID_STEP_RAD: f64 = 0.0087;
/// Upper end of the grid, symmetric to [`GRID_START_RAD`] (`π/6`, rounded) \[rad\].
// The paper's printed value, rounded to four decimals like its other angles: not `π/6`.
#[allow(clippy::approx_constant)]
pub const GRID_END_RAD: f64 = 0.5236;
/// Values per joint coordinate from `-0.5236` to `<= +0.5236` in steps of `0.0087`.
pub const GRID_N_PER_AXIS: usize = 121;
/// Table 2: "number of geometrical configurations analyzed".
pub const PAPER_N_CONFIGURATIONS: usize = 14761;
/// Table 3: `(θ1, θ2)` \[rad\] of the four numerical experiments.
pub const TABLE3_EXPERIMENTS: [(f64, f64); 4] =
    [(0.0941, 0.0332), (0.0854, -0.0277), (-0.0625, 0.0245), (-0.0799, -0.0364)];

/// Joint angles within this of a Table 3 experiment [rad] are that experiment.
const TABLE3_MATCH_RAD: f64 = 1e-9;

/// The index of the Table 3 experiment at (theta1, theta2), if any.
pub fn table3_experiment(theta1: f64, theta2: f64) -> Option<usize> {
    TABLE3_EXPERIMENTS
        .iter()
        .position(|(a, b)| (a - theta1).abs() < TABLE3_MATCH_RAD && (b - theta2).abs() < TABLE3_MATCH_RAD)
}
/// Table 5, "Analytical" column, per experiment:
/// `[|f_C1| N, |f_C2| N, |f_R1| N, |f_R2| N, |f_joint| N, m_joint N*mm]`.
pub const TABLE5_ANALYTICAL: [[f64; 6]; 4] = [
    [0.28507, 0.36316, 4.5394, 4.5765, 5.1333, 0.97461],
    [4.6879, 4.7231, 0.14290, 0.21225, 5.1331, -0.74492],
    [4.4108, 4.3877, 0.51232, 0.45902, 5.1324, -0.47259],
    [0.71580, 0.64452, 4.2162, 4.1898, 5.1328, 0.88771],
];
/// Table 5, "ANSYS" column (same layout as [`TABLE5_ANALYTICAL`]).
pub const TABLE5_ANSYS: [[f64; 6]; 4] = [
    [0.26909, 0.34520, 4.5399, 4.5759, 5.0993, 0.97163],
    [4.5984, 4.6288, 0.14785, 0.20779, 4.9498, -0.73097],
    [4.2653, 4.2470, 0.50689, 0.46487, 4.8467, -0.45867],
    [0.63767, 0.57423, 4.2147, 4.1912, 4.9843, 0.87524],
];
/// Table 5, "Error" column [%] (same layout).
pub const TABLE5_ERROR_PERCENT: [[f64; 6]; 4] = [
    [5.60, 4.94, 0.01, 0.01, 0.66, 0.30],
    [1.90, 1.99, 3.46, 2.10, 3.57, 1.87],
    [3.29, 3.20, 1.05, 1.27, 5.56, 2.94],
    [10.91, 10.90, 0.03, 0.03, 2.89, 1.40],
];

/// Fitted (not in the paper): `x` of the base plane holding `B1..B4` in `Σ_W` \[mm\]
/// (negative: 72 mm beyond the base origin, on the side away from the joint).
///
/// How found: least squares of the 24 numbers of [`TABLE5_ANALYTICAL`]
/// (forces in N and the joint moment in N*mm, unweighted, cost = [`table5_cost`])
/// over `(base_x, base_half, spring_k)` with the symmetric geometry of the
/// module docs, `L0 = 0`, gravity `+x_W`, centroid on the rod axis at 181 mm;
/// Nelder-Mead from 6 random starts, all converging to this point (cost
/// 65.994). Alternatives explored and rejected (cost): centroid fixed off-axis
/// so that `θ=(0,0)` gives Table 2 (> 4000); gravity `-x_W` (> 91); gravity
/// `-z_W` (> 32000); free spring rest length / separate spring square (no gain:
/// the optimum drives `L0` to 0); stiffer springs (`k = 10, 20, 50, 100 N/m`:
/// 66.3, 67.9, 202, 1073). The test `fitted_constants_minimise_table5_cost`
/// re-checks the minimum.
pub const FIT_BASE_X_MM: f64 = -72.2183;
/// Fitted: half-side `b` of the base square \[mm\] (see [`FIT_BASE_X_MM`]).
pub const FIT_BASE_HALF_MM: f64 = 136.3245;
/// Fitted: spring rate of `r1`, `r2` [N/m] (see [`FIT_BASE_X_MM`]).
pub const FIT_SPRING_K_N_PER_M: f64 = 4.99007;
/// Chosen: spring rest length \[mm\] (the fit drives it to its bound 0; the
/// paper's "spring attached to a fixed-length cable" makes any value plausible).
pub const FIT_SPRING_REST_MM: f64 = 0.0;

/// Thin-rod + thin-cross inertia model (module [`platform_inertia`]): the
/// rod runs from `O` to `M`, the cross is two diagonal bars of length `√2 l2`
/// through `M` in the platform's `y-z` plane; masses split so that the centre of
/// mass is at [`CENTROID_RADIUS_MM`].
const INERTIA_ROD_COM_FRACTION: f64 = 0.5;
/// Thin uniform bar about its centre: `I = m L^2 / 12`.
const THIN_BAR_INERTIA_FACTOR: f64 = 1.0 / 12.0;

/// Form-finding/statics: a cable tension or spring stretch within this of zero
/// counts as zero (rounding) \[N\] / \[m\].
pub const TENSION_TOL_N: f64 = 1e-9;
/// [`statics`]: the moment system counts as singular when `|det A|` is below
/// this fraction of the product of its column norms.
pub const SINGULAR_REL_DET: f64 = 1e-10;
/// [`statics`]: offset used for the limit at the singular pose \[rad\].
pub const SINGULAR_LIMIT_STEP_RAD: f64 = 1e-6;
/// Newton iterations for [`theta_from_cable_lengths`].
const NEWTON_MAX_ITERS: usize = 50;
/// Newton convergence on cable lengths [m].
const NEWTON_TOL_M: f64 = 1e-13;
/// Central-difference step for Hessians of the analytic gradients [rad].
const HESSIAN_STEP_RAD: f64 = 1e-6;
/// [`ik_position`]: accepted relative deviation of `|M - O|` from `a2`.
pub const IK_RADIUS_REL_TOL: f64 = 1e-6;

/// Metres -> millimetres.
pub fn to_mm(x_m: f64) -> f64 {
    x_m * MM_PER_M
}
/// Millimetres -> metres.
pub fn from_mm(x_mm: f64) -> f64 {
    x_mm / MM_PER_M
}
/// A point \[m\] -> \[mm\].
pub fn vec_to_mm(v: &Vector3<f64>) -> Vector3<f64> {
    v * MM_PER_M
}

// ---------------------------------------------------------------------------
// Parameters.
// ---------------------------------------------------------------------------

/// Mechanism parameters (SI).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// `a2`: joint centre to platform centre `M` \[m\].
    pub a2: f64,
    /// `l1`: base origin to joint centre `O`, along `x_W` \[m\].
    pub l1: f64,
    /// `l2`: platform width; attachment points at `(±l2/2, ±l2/2)` \[m\].
    pub l2: f64,
    /// Platform mass \[kg\].
    pub mass: f64,
    /// Gravity magnitude [m/s^2], acting along `+x_W`.
    pub gravity: f64,
    /// Centroid `G` in the platform frame, measured from `O` \[m\].
    pub centroid_local: [f64; 3],
    /// `x_W` of the base plane of `B1..B4` \[m\].
    pub base_x: f64,
    /// Half-side of the base square `B1..B4` \[m\].
    pub base_half: f64,
    /// Spring rate of `r1`, `r2` [N/m].
    pub spring_k: f64,
    /// Rest length of `r1`, `r2` \[m\].
    pub spring_rest: f64,
}

impl Params {
    /// Table 2 values plus the fitted/chosen constants (`FIT_*`, centroid on
    /// the rod axis at 181 mm, `g = 9.81 m/s^2`).
    pub const PAPER: Params = Params {
        a2: A2_MM / MM_PER_M,
        l1: L1_MM / MM_PER_M,
        l2: L2_MM / MM_PER_M,
        mass: PLATFORM_MASS_KG,
        gravity: GRAVITY_M_S2,
        centroid_local: [CENTROID_RADIUS_MM / MM_PER_M, 0.0, 0.0],
        base_x: FIT_BASE_X_MM / MM_PER_M,
        base_half: FIT_BASE_HALF_MM / MM_PER_M,
        spring_k: FIT_SPRING_K_N_PER_M,
        spring_rest: FIT_SPRING_REST_MM / MM_PER_M,
    };

    /// Lengths `a2, l2, base_half > 0`, `l1`, `base_x` finite, `mass, gravity,
    /// spring_k >= 0`, `spring_rest >= 0`, centroid finite, and the base plane
    /// not through the joint centre.
    pub fn validate(&self) -> Result<(), ParamError> {
        for (name, value) in [("a2", self.a2), ("l2", self.l2), ("base_half", self.base_half)] {
            if !value.is_finite() || value <= 0.0 {
                return Err(ParamError::NotFinitePositive { name, value });
            }
        }
        for (name, value) in [
            ("mass", self.mass),
            ("gravity", self.gravity),
            ("spring_k", self.spring_k),
            ("spring_rest", self.spring_rest),
        ] {
            if !value.is_finite() || value < 0.0 {
                return Err(ParamError::NotFiniteNonNegative { name, value });
            }
        }
        for (name, value) in [("l1", self.l1), ("base_x", self.base_x)] {
            if !value.is_finite() {
                return Err(ParamError::NotFinite { name, value });
            }
        }
        if self.centroid_local.iter().any(|c| !c.is_finite()) {
            return Err(ParamError::Condition(format!("centroid_local must be finite, got {:?}", self.centroid_local)));
        }
        if (self.base_x - self.l1).abs() < 1e-9 {
            return Err(ParamError::Condition(format!(
                "base_x must differ from l1 (base plane through the joint), got {}",
                self.base_x
            )));
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// Kinematics (Eq. 1-17).
// ---------------------------------------------------------------------------

fn homogeneous(r: &Matrix3<f64>, t: &Vector3<f64>) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(t);
    m
}

/// Eq. 1: `^W T_0`, translation `l1` along `x_W`.
pub fn t_w_0(p: &Params) -> Matrix4<f64> {
    homogeneous(&Matrix3::identity(), &Vector3::new(p.l1, 0.0, 0.0))
}

/// Standard Denavit-Hartenberg link transform `Rot_z(θ) Trans_z(d) Trans_x(a) Rot_x(α)`.
pub fn dh(theta: f64, d: f64, a: f64, alpha: f64) -> Matrix4<f64> {
    let (st, ct) = theta.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    Matrix4::new(
        ct,
        -st * ca,
        st * sa,
        a * ct, //
        st,
        ct * ca,
        -ct * sa,
        a * st, //
        0.0,
        sa,
        ca,
        d, //
        0.0,
        0.0,
        0.0,
        1.0,
    )
}

/// Eq. 2: `^0 T_1` = DH row 1 of Table 1 (`d=0, a=0, α=-π/2`). Correct as printed.
pub fn t_0_1(theta1: f64) -> Matrix4<f64> {
    dh(theta1, 0.0, 0.0, -std::f64::consts::FRAC_PI_2)
}

/// `^1 T_M` derived = DH row 2 of Table 1 (`d=0, a=a2, α=π/2`); its `(2,4)`
/// entry is `a2 sin θ2`.
pub fn t_1_m(p: &Params, theta2: f64) -> Matrix4<f64> {
    dh(theta2, 0.0, p.a2, std::f64::consts::FRAC_PI_2)
}

/// Eq. 3 as printed: identical to [`t_1_m`] except the `(2,4)` entry `a2 cos θ2`.
pub fn t_1_m_as_printed(p: &Params, theta2: f64) -> Matrix4<f64> {
    let mut m = t_1_m(p, theta2);
    m[(1, 3)] = p.a2 * theta2.cos();
    m
}

/// Eq. 4: `^M T_{M1}`, translation `(0, l2/2, -l2/2)`.
pub fn t_m_m1(p: &Params) -> Matrix4<f64> {
    homogeneous(&Matrix3::identity(), &Vector3::new(0.0, 0.5 * p.l2, -0.5 * p.l2))
}

/// Eq. 5: `^M T_{M2}`, translation `(0, -l2/2, l2/2)`.
pub fn t_m_m2(p: &Params) -> Matrix4<f64> {
    homogeneous(&Matrix3::identity(), &Vector3::new(0.0, -0.5 * p.l2, 0.5 * p.l2))
}

/// Platform orientation `R = Rz(θ1) Ry(θ2)` (rotation block of Eq. 15).
pub fn rotation(theta1: f64, theta2: f64) -> Matrix3<f64> {
    let (s1, c1) = theta1.sin_cos();
    let (s2, c2) = theta2.sin_cos();
    Matrix3::new(c1 * c2, -s1, c1 * s2, s1 * c2, c1, s1 * s2, -s2, 0.0, c2)
}

/// Eq. 15: `^W T_M` in closed form (correct as printed).
pub fn t_w_m(p: &Params, theta1: f64, theta2: f64) -> Matrix4<f64> {
    let r = rotation(theta1, theta2);
    let o = joint_centre(p);
    homogeneous(&r, &(o + r * Vector3::new(p.a2, 0.0, 0.0)))
}

/// `^W T_M = ^W T_0 ^0 T_1 ^1 T_M` by the chain (derived Eq. 3).
pub fn t_w_m_chain(p: &Params, theta1: f64, theta2: f64) -> Matrix4<f64> {
    t_w_0(p) * t_0_1(theta1) * t_1_m(p, theta2)
}

/// Eq. 6: `^W T_{M1}`.
pub fn t_w_m1(p: &Params, theta1: f64, theta2: f64) -> Matrix4<f64> {
    t_w_m_chain(p, theta1, theta2) * t_m_m1(p)
}

/// Eq. 7: `^W T_{M2}`.
pub fn t_w_m2(p: &Params, theta1: f64, theta2: f64) -> Matrix4<f64> {
    t_w_m_chain(p, theta1, theta2) * t_m_m2(p)
}

/// Eq. 8 as printed: `^W P_{M1}` \[m\].
pub fn p_m1_eq8(p: &Params, theta1: f64, theta2: f64) -> Vector3<f64> {
    let (s1, c1) = theta1.sin_cos();
    let (s2, c2) = theta2.sin_cos();
    let h = 0.5 * p.l2;
    Vector3::new(c1 * (-s2 * h + p.a2 * c2) - s1 * h + p.l1, s1 * (-s2 * h + p.a2 * c2) + c1 * h, -c2 * h - p.a2 * s2)
}

/// Eq. 9 as printed: `^W P_{M2}` \[m\].
pub fn p_m2_eq9(p: &Params, theta1: f64, theta2: f64) -> Vector3<f64> {
    let (s1, c1) = theta1.sin_cos();
    let (s2, c2) = theta2.sin_cos();
    let h = 0.5 * p.l2;
    Vector3::new(c1 * (s2 * h + p.a2 * c2) + s1 * h + p.l1, s1 * (s2 * h + p.a2 * c2) - c1 * h, c2 * h - p.a2 * s2)
}

/// Universal-joint centre `O` (origin of `Σ_0`) in `Σ_W` \[m\].
pub fn joint_centre(p: &Params) -> Vector3<f64> {
    Vector3::new(p.l1, 0.0, 0.0)
}

/// First joint axis (`θ1`), fixed in the base: `z_W`.
pub fn joint_axis_base() -> Vector3<f64> {
    Vector3::z()
}

/// Second joint axis (`θ2`), fixed in the platform: `y_M = (-sin θ1, cos θ1, 0)`
/// in `Σ_W` (at `θ = 0` it is `y_W`).
pub fn joint_axis_platform(theta1: f64, _theta2: f64) -> Vector3<f64> {
    let (s1, c1) = theta1.sin_cos();
    Vector3::new(-s1, c1, 0.0)
}

/// Axis about which the universal joint transmits a moment:
/// `n = z_W × y_M = (-cos θ1, -sin θ1, 0)` (unit; `-x_W` at `θ = 0`).
pub fn joint_constrained_axis(theta1: f64, theta2: f64) -> Vector3<f64> {
    joint_axis_base().cross(&joint_axis_platform(theta1, theta2))
}

/// Gravity acceleration vector in `Σ_W` [m/s^2]: `(+g, 0, 0)`.
pub fn gravity_vector(p: &Params) -> Vector3<f64> {
    Vector3::new(p.gravity, 0.0, 0.0)
}

/// Cable attachment points on the platform, platform frame from `O` \[m\]:
/// `M1 = (a2, l2/2, -l2/2)`, `M2 = (a2, -l2/2, l2/2)` (Eq. 4-5).
pub fn cable_platform_local(p: &Params) -> [Vector3<f64>; 2] {
    let h = 0.5 * p.l2;
    [Vector3::new(p.a2, h, -h), Vector3::new(p.a2, -h, h)]
}

/// Spring attachment points on the platform, platform frame from `O` \[m\]:
/// `R1 = (a2, l2/2, l2/2)`, `R2 = (a2, -l2/2, -l2/2)` (model choice).
pub fn spring_platform_local(p: &Params) -> [Vector3<f64>; 2] {
    let h = 0.5 * p.l2;
    [Vector3::new(p.a2, h, h), Vector3::new(p.a2, -h, -h)]
}

/// Cable base points `B1 = (bx, b, -b)`, `B2 = (bx, -b, b)` in `Σ_W` \[m\] (Eq. 10-11).
pub fn cable_base_points(p: &Params) -> [Vector3<f64>; 2] {
    let b = p.base_half;
    [Vector3::new(p.base_x, b, -b), Vector3::new(p.base_x, -b, b)]
}

/// Spring base points `B3 = (bx, b, b)`, `B4 = (bx, -b, -b)` in `Σ_W` \[m\].
pub fn spring_base_points(p: &Params) -> [Vector3<f64>; 2] {
    let b = p.base_half;
    [Vector3::new(p.base_x, b, b), Vector3::new(p.base_x, -b, -b)]
}

/// A platform-frame point (from `O`) in `Σ_W` at `(θ1, θ2)` \[m\].
pub fn platform_point(p: &Params, theta1: f64, theta2: f64, local: &Vector3<f64>) -> Vector3<f64> {
    joint_centre(p) + rotation(theta1, theta2) * local
}

/// Named points of the platform in `Σ_W` \[m\].
#[derive(Clone, Copy, Debug)]
pub struct Points {
    /// Joint centre `O`.
    pub o: Vector3<f64>,
    /// Platform centre `M`.
    pub m: Vector3<f64>,
    /// Cable ends `M1`, `M2`.
    pub cable_platform: [Vector3<f64>; 2],
    /// Spring ends `R1`, `R2`.
    pub spring_platform: [Vector3<f64>; 2],
    /// Centroid / centre of mass `G`.
    pub g: Vector3<f64>,
}

/// Forward kinematics (Eq. 6-9, 15): every platform point at `(θ1, θ2)`.
pub fn points(p: &Params, theta1: f64, theta2: f64) -> Points {
    let pt = |l: &Vector3<f64>| platform_point(p, theta1, theta2, l);
    let c = cable_platform_local(p);
    let s = spring_platform_local(p);
    Points {
        o: joint_centre(p),
        m: pt(&Vector3::new(p.a2, 0.0, 0.0)),
        cable_platform: [pt(&c[0]), pt(&c[1])],
        spring_platform: [pt(&s[0]), pt(&s[1])],
        g: pt(&Vector3::from(p.centroid_local)),
    }
}

/// Eq. 12-13: cable lengths `(L_C1, L_C2)` \[m\].
pub fn cable_lengths(p: &Params, theta1: f64, theta2: f64) -> [f64; 2] {
    let q = points(p, theta1, theta2);
    let b = cable_base_points(p);
    [(q.cable_platform[0] - b[0]).norm(), (q.cable_platform[1] - b[1]).norm()]
}

/// Spring lengths `(L_r1, L_r2)` \[m\].
pub fn spring_lengths(p: &Params, theta1: f64, theta2: f64) -> [f64; 2] {
    let q = points(p, theta1, theta2);
    let b = spring_base_points(p);
    [(q.spring_platform[0] - b[0]).norm(), (q.spring_platform[1] - b[1]).norm()]
}

/// Eq. 14-17 derived: joint angles from a pose `^W T_M` (only the rotation is
/// used): `θ1 = atan2(-t12, t22)`, `θ2 = atan2(-t31, t33)`. Valid for
/// `|θ1|, |θ2| < π/2` and every sign of `θ2`.
pub fn ik_pose(t: &Matrix4<f64>) -> (f64, f64) {
    ((-t[(0, 1)]).atan2(t[(1, 1)]), (-t[(2, 0)]).atan2(t[(2, 2)]))
}

/// Eq. 16-17 as printed: `θ1 = atan2(t23, t13)`, `θ2 = atan2(-t31, t33)`.
/// Returns `θ1 + π` (wrapped) when `θ2 < 0` and is undefined (`atan2(0, 0)`) at `θ2 = 0`.
pub fn ik_pose_as_printed(t: &Matrix4<f64>) -> (f64, f64) {
    (t[(1, 2)].atan2(t[(0, 2)]), (-t[(2, 0)]).atan2(t[(2, 2)]))
}

/// Inverse kinematics from the position of `M` (translation of Eq. 14) \[m\]:
/// A platform point `M` off the sphere of radius `a2` about the joint centre `O`: no joint
/// angles place it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("|M - O| = {distance_m:.6} m must equal a2 = {a2_m:.6} m")]
pub struct OffSphere {
    /// `|M - O|` \[m\].
    pub distance_m: f64,
    /// `a2` \[m\].
    pub a2_m: f64,
}

/// `θ1 = atan2(y_m, x_m - l1)`, `θ2 = atan2(-z_m, sqrt((x_m-l1)^2 + y_m^2))`
/// (branch `cos θ2 > 0`). Errors when `|M - O|` differs from `a2` by more than
/// [`IK_RADIUS_REL_TOL`].
pub fn ik_position(p: &Params, m: &Vector3<f64>) -> Result<(f64, f64), OffSphere> {
    let d = m - joint_centre(p);
    if (d.norm() - p.a2).abs() > IK_RADIUS_REL_TOL * p.a2 {
        return Err(OffSphere { distance_m: d.norm(), a2_m: p.a2 });
    }
    let rho = (d.x * d.x + d.y * d.y).sqrt();
    Ok((d.y.atan2(d.x), (-d.z).atan2(rho)))
}

/// `∂P/∂θ1 = z_W × (P - O)` and `∂P/∂θ2 = y_M × (P - O)` for a platform point `P` [m/rad].
fn point_derivatives(p: &Params, theta1: f64, theta2: f64, pw: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let r = pw - joint_centre(p);
    [joint_axis_base().cross(&r), joint_axis_platform(theta1, theta2).cross(&r)]
}

/// `∂(L_C1, L_C2)/∂(θ1, θ2)` [m/rad] (row = cable, column = joint coordinate).
pub fn cable_length_jacobian(p: &Params, theta1: f64, theta2: f64) -> Matrix2<f64> {
    let q = points(p, theta1, theta2);
    let b = cable_base_points(p);
    let mut j = Matrix2::zeros();
    for i in 0..2 {
        let e = (q.cable_platform[i] - b[i]).normalize();
        let d = point_derivatives(p, theta1, theta2, &q.cable_platform[i]);
        j[(i, 0)] = e.dot(&d[0]);
        j[(i, 1)] = e.dot(&d[1]);
    }
    j
}

/// Actuator-space forward kinematics: `(θ1, θ2)` whose Eq. 12-13 cable lengths
/// are `lengths` \[m\], by Newton's method from `guess`. `None` if it does not
/// converge (singular Jacobian or no solution nearby).
pub fn theta_from_cable_lengths(p: &Params, lengths: [f64; 2], guess: (f64, f64)) -> Option<(f64, f64)> {
    let mut th = Vector2::new(guess.0, guess.1);
    for _ in 0..NEWTON_MAX_ITERS {
        let l = cable_lengths(p, th.x, th.y);
        let r = Vector2::new(l[0] - lengths[0], l[1] - lengths[1]);
        if r.amax() < NEWTON_TOL_M {
            return Some((th.x, th.y));
        }
        let step = cable_length_jacobian(p, th.x, th.y).lu().solve(&r)?;
        th -= step;
        if !th.iter().all(|v| v.is_finite()) {
            return None;
        }
    }
    let l = cable_lengths(p, th.x, th.y);
    ((l[0] - lengths[0]).abs().max((l[1] - lengths[1]).abs()) < 1e3 * NEWTON_TOL_M).then_some((th.x, th.y))
}

/// Every `(θ1, θ2)` in `[-π/2, π/2]^2` with the given cable lengths \[m\]: Newton
/// from a 7x7 grid of starts over `±0.6 rad`, duplicates (within 1e-9 rad)
/// merged. Generically two solutions near `θ = 0`: the pose and (nearly) its
/// mirror image in the cable plane `y = -z` (the map θ → (L_C1, L_C2) folds
/// along the curve where [`cable_length_jacobian`] is singular, through `θ = 0`).
pub fn all_thetas_from_cable_lengths(p: &Params, lengths: [f64; 2]) -> Vec<(f64, f64)> {
    const STARTS_PER_AXIS: usize = 7;
    const START_SPAN_RAD: f64 = 0.6;
    const DUPLICATE_TOL_RAD: f64 = 1e-9;
    let mut out: Vec<(f64, f64)> = Vec::new();
    for i in 0..STARTS_PER_AXIS {
        for j in 0..STARTS_PER_AXIS {
            let f = |k: usize| -START_SPAN_RAD + 2.0 * START_SPAN_RAD * k as f64 / (STARTS_PER_AXIS - 1) as f64;
            if let Some((a, b)) = theta_from_cable_lengths(p, lengths, (f(i) + 1e-3, f(j) - 1e-3)) {
                let inside = a.abs() < std::f64::consts::FRAC_PI_2 && b.abs() < std::f64::consts::FRAC_PI_2;
                if inside
                    && !out.iter().any(|&(c, d)| (c - a).abs() < DUPLICATE_TOL_RAD && (d - b).abs() < DUPLICATE_TOL_RAD)
                {
                    out.push((a, b));
                }
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------
// Statics (Eq. 18-23, 26-27).
// ---------------------------------------------------------------------------

/// Spring forces `k max(0, L - L0)` \[N\] (tension-only).
pub fn spring_forces(p: &Params, theta1: f64, theta2: f64) -> [f64; 2] {
    let l = spring_lengths(p, theta1, theta2);
    [p.spring_k * (l[0] - p.spring_rest).max(0.0), p.spring_k * (l[1] - p.spring_rest).max(0.0)]
}

/// Result of the static analysis of the moving platform.
#[derive(Clone, Copy, Debug)]
pub struct Statics {
    /// Cable tensions `(T_C1, T_C2)` \[N\]; negative means the cable would have to push.
    pub cable_tensions: [f64; 2],
    /// Spring forces `(f_R1, f_R2)` \[N\], `k max(0, L - L0)`.
    pub spring_forces: [f64; 2],
    /// Unit vectors from the platform ends toward `B1, B2` (cables) [-].
    pub cable_directions: [Vector3<f64>; 2],
    /// Unit vectors from the platform ends toward `B3, B4` (springs) [-].
    pub spring_directions: [Vector3<f64>; 2],
    /// Force exerted by the joint on the platform, `Σ_W` \[N\].
    pub joint_reaction_force: Vector3<f64>,
    /// Moment exerted by the joint on the platform about `O`, `Σ_W` \[N*m\];
    /// always parallel to [`joint_constrained_axis`].
    pub joint_reaction_moment: Vector3<f64>,
    /// The joint moment as a signed scalar along `n = z_W × y_M` \[N*m\]; this is
    /// the sign convention of Table 5's `m_joint` (which is in N*mm).
    pub joint_moment_paper_sign: f64,
    /// Weight `m g` on the platform \[N\] (`Σ_W`).
    pub weight: Vector3<f64>,
    /// Cable lengths (Eq. 12-13) \[m\].
    pub cable_lengths: [f64; 2],
    /// Spring lengths \[m\].
    pub spring_lengths: [f64; 2],
    /// Both cables in tension (`T >= -TENSION_TOL_N`).
    pub cables_taut: bool,
    /// Both springs stretched (`L >= L0`).
    pub springs_taut: bool,
    /// `f_joint · x_M > 0`: the joint pushes the platform away from the base (rod compressed).
    pub rod_in_compression: bool,
    /// Implemented Eq. 26-27: `cables_taut && springs_taut`.
    pub equilibrium: bool,
    /// The moment system was singular (`θ = (0, 0)`): the values are the limit
    /// `θ → (0, 0)`; with rigid members the cable pretension is indeterminate there.
    pub singular: bool,
}

/// Eq. 22-23 solved with Hooke springs: cable tensions and joint moment from the
/// moment balance about `O`, then the joint force from the force balance.
///
/// At `θ = (0, 0)` both cables lie in one plane through `O` (`y_W = -z_W`), so
/// the 3x3 moment system is singular: only `T1 - T2` is determined and the pair
/// pretension is balanced by the joint alone. There (flag [`Statics::singular`])
/// the continuous limit is returned: the mean of the solutions at `θ ± ε(1, ±1)`,
/// `ε =` [`SINGULAR_LIMIT_STEP_RAD`].
pub fn statics(p: &Params, theta1: f64, theta2: f64) -> Statics {
    match statics_regular(p, theta1, theta2) {
        Some(s) => s,
        None => {
            let e = SINGULAR_LIMIT_STEP_RAD;
            let ss: Vec<Statics> = [(e, e), (e, -e), (-e, e), (-e, -e)]
                .iter()
                .filter_map(|&(a, b)| statics_regular(p, theta1 + a, theta2 + b))
                .collect();
            let k = ss.len() as f64;
            let mut s = statics_regular_unchecked(p, theta1, theta2);
            s.cable_tensions = [0.0; 2];
            for x in &ss {
                s.cable_tensions[0] += x.cable_tensions[0] / k;
                s.cable_tensions[1] += x.cable_tensions[1] / k;
            }
            s.joint_reaction_force = ss.iter().map(|x| x.joint_reaction_force).sum::<Vector3<f64>>() / k;
            s.joint_moment_paper_sign = ss.iter().map(|x| x.joint_moment_paper_sign).sum::<f64>() / k;
            s.joint_reaction_moment = s.joint_moment_paper_sign * joint_constrained_axis(theta1, theta2);
            s.cables_taut = s.cable_tensions.iter().all(|t| *t >= -TENSION_TOL_N);
            s.rod_in_compression = s.joint_reaction_force.dot(&rotation(theta1, theta2).column(0).into_owned()) > 0.0;
            s.equilibrium = s.cables_taut && s.springs_taut;
            s.singular = true;
            s
        }
    }
}

/// [`statics`] away from the singular pose; `None` when the moment system is
/// singular (relative determinant below [`SINGULAR_REL_DET`]).
fn statics_regular(p: &Params, theta1: f64, theta2: f64) -> Option<Statics> {
    let s = statics_regular_unchecked(p, theta1, theta2);
    (!s.singular).then_some(s)
}

fn statics_regular_unchecked(p: &Params, theta1: f64, theta2: f64) -> Statics {
    let q = points(p, theta1, theta2);
    let o = q.o;
    let cb = cable_base_points(p);
    let sb = spring_base_points(p);
    let ucab = [(cb[0] - q.cable_platform[0]).normalize(), (cb[1] - q.cable_platform[1]).normalize()];
    let uspr = [(sb[0] - q.spring_platform[0]).normalize(), (sb[1] - q.spring_platform[1]).normalize()];
    let fs = spring_forces(p, theta1, theta2);
    let weight = p.mass * gravity_vector(p);
    let n = joint_constrained_axis(theta1, theta2);
    // Eq. 23: Σ r × f + r_G × W + m n = 0 with unknowns (T1, T2, m).
    let known_moment = (q.spring_platform[0] - o).cross(&(fs[0] * uspr[0]))
        + (q.spring_platform[1] - o).cross(&(fs[1] * uspr[1]))
        + (q.g - o).cross(&weight);
    let a = Matrix3::from_columns(&[
        (q.cable_platform[0] - o).cross(&ucab[0]),
        (q.cable_platform[1] - o).cross(&ucab[1]),
        n,
    ]);
    let scale = a.column(0).norm() * a.column(1).norm() * a.column(2).norm();
    // Unordered (a NaN in the matrix) counts as singular.
    let singular = a.determinant().abs().partial_cmp(&(SINGULAR_REL_DET * scale)).is_none_or(Ordering::is_le);
    let x = if singular {
        Vector3::repeat(f64::NAN)
    } else {
        a.lu().solve(&(-known_moment)).unwrap_or_else(|| Vector3::repeat(f64::NAN))
    };
    let t = [x[0], x[1]];
    // Eq. 22.
    let f_joint = -(t[0] * ucab[0] + t[1] * ucab[1] + fs[0] * uspr[0] + fs[1] * uspr[1] + weight);
    let ls = spring_lengths(p, theta1, theta2);
    let cables_taut = t[0] >= -TENSION_TOL_N && t[1] >= -TENSION_TOL_N;
    let springs_taut = ls.iter().all(|l| *l >= p.spring_rest - TENSION_TOL_N);
    let x_m = rotation(theta1, theta2).column(0).into_owned();
    Statics {
        cable_tensions: t,
        spring_forces: fs,
        cable_directions: ucab,
        spring_directions: uspr,
        joint_reaction_force: f_joint,
        joint_reaction_moment: x[2] * n,
        joint_moment_paper_sign: x[2],
        weight,
        cable_lengths: cable_lengths(p, theta1, theta2),
        spring_lengths: ls,
        cables_taut,
        springs_taut,
        rod_in_compression: f_joint.dot(&x_m) > 0.0,
        equilibrium: cables_taut && springs_taut,
        singular,
    }
}

/// Eq. 27 as printed (garbled scan, read literally): all four flexible
/// magnitudes `>= 0`, `|f_joint| <= 0`, `|m_joint| = 0` (within `tol_n` \[N\] and
/// `tol_nm` \[N*m\]).
pub fn equilibrium_eq27_as_printed(s: &Statics, tol_n: f64, tol_nm: f64) -> bool {
    s.cable_tensions.iter().chain(s.spring_forces.iter()).all(|f| f.abs() >= 0.0)
        && s.joint_reaction_force.norm() <= tol_n
        && s.joint_reaction_moment.norm() <= tol_nm
}

/// Total potential of gravity and springs \[J\] (zero at `x_W = 0` / `L = L0`).
pub fn potential_gravity_springs(p: &Params, theta1: f64, theta2: f64) -> f64 {
    let q = points(p, theta1, theta2);
    let ls = spring_lengths(p, theta1, theta2);
    -p.mass * gravity_vector(p).dot(&q.g)
        + ls.iter().map(|l| 0.5 * p.spring_k * (l - p.spring_rest).max(0.0).powi(2)).sum::<f64>()
}

/// Generalised forces `Q_j = a_j · M_O` [N*m/rad] of gravity, springs and cable
/// tensions `tensions` \[N\] on the platform (`a_1 = z_W`, `a_2 = y_M`);
/// `Q = -∇V_gs - J_Lᵀ T`. Zero at an equilibrium with the [`statics`] tensions.
pub fn generalized_forces(p: &Params, theta1: f64, theta2: f64, tensions: [f64; 2]) -> Vector2<f64> {
    let q = points(p, theta1, theta2);
    let cb = cable_base_points(p);
    let sb = spring_base_points(p);
    let fs = spring_forces(p, theta1, theta2);
    let mut forces: Vec<(Vector3<f64>, Vector3<f64>)> = Vec::new();
    for i in 0..2 {
        forces.push((q.cable_platform[i], tensions[i] * (cb[i] - q.cable_platform[i]).normalize()));
        forces.push((q.spring_platform[i], fs[i] * (sb[i] - q.spring_platform[i]).normalize()));
    }
    forces.push((q.g, p.mass * gravity_vector(p)));
    let m_o: Vector3<f64> = forces.iter().map(|(pt, f)| (pt - q.o).cross(f)).sum();
    Vector2::new(joint_axis_base().dot(&m_o), joint_axis_platform(theta1, theta2).dot(&m_o))
}

/// Second-order stability with the cable lengths fixed: the 2x2 stiffness
/// matrix `K = -∂Q/∂θ (T frozen) + k_c J_Lᵀ J_L` [N*m/rad] of the platform held
/// by cables of axial stiffness `cable_stiffness` [N/m] pretensioned to the
/// [`statics`] tensions (gravity, springs and the cable geometric stiffness
/// `Σ T ∇²L` included; `-∂Q/∂θ` by central differences of the analytic `Q`).
pub fn stiffness_matrix(p: &Params, theta1: f64, theta2: f64, cable_stiffness: f64) -> Matrix2<f64> {
    let t = statics(p, theta1, theta2).cable_tensions;
    let h = HESSIAN_STEP_RAD;
    let dq1 = (generalized_forces(p, theta1 + h, theta2, t) - generalized_forces(p, theta1 - h, theta2, t)) / (2.0 * h);
    let dq2 = (generalized_forces(p, theta1, theta2 + h, t) - generalized_forces(p, theta1, theta2 - h, t)) / (2.0 * h);
    let mut k = -Matrix2::from_columns(&[dq1, dq2]);
    k = 0.5 * (k + k.transpose());
    let j = cable_length_jacobian(p, theta1, theta2);
    k + cable_stiffness * j.transpose() * j
}

/// Stable with inextensible cables (`k_c → ∞`): both cables strictly taut and
/// the cable-length Jacobian nonsingular (two active unilateral constraints with
/// positive multipliers lock both degrees of freedom), and springs taut.
pub fn stable_with_fixed_cables(p: &Params, theta1: f64, theta2: f64) -> bool {
    let s = statics(p, theta1, theta2);
    s.cable_tensions.iter().all(|t| *t > TENSION_TOL_N)
        && s.springs_taut
        && cable_length_jacobian(p, theta1, theta2).determinant().abs() > 1e-12
}

// ---------------------------------------------------------------------------
// Dynamic-model data.
// ---------------------------------------------------------------------------

/// Platform inertia about `G` in platform axes `(x_M, y_M, z_M)` [kg*m^2].
/// Model (not in the paper): thin rod `O→M` of mass `m_r` plus a thin cross of
/// two diagonal bars (length `√2 l2`, mass `m_c/2` each) centred at `M` in the
/// `y_M z_M` plane, with `m_r = m (a2 - g)/(a2 - a2/2)`, `m_c = m - m_r` so the
/// centre of mass lies at `g = |centroid_local|` on the axis (181 mm →
/// `m_r = 0.1307 kg`, `m_c = 0.3425 kg`). Diagonal.
pub fn platform_inertia(p: &Params) -> Matrix3<f64> {
    let gx = p.centroid_local[0];
    let rod_com = INERTIA_ROD_COM_FRACTION * p.a2;
    let m_rod = (p.mass * (p.a2 - gx) / (p.a2 - rod_com)).clamp(0.0, p.mass);
    let m_cross = p.mass - m_rod;
    let bar = std::f64::consts::SQRT_2 * p.l2;
    let i_cross_axial = m_cross * bar * bar * THIN_BAR_INERTIA_FACTOR; // two bars, each m_c/2
    let i_cross_inplane = 0.5 * i_cross_axial + m_cross * (p.a2 - gx).powi(2);
    let i_rod_trans = m_rod * p.a2 * p.a2 * THIN_BAR_INERTIA_FACTOR + m_rod * (gx - rod_com).powi(2);
    let i_t = i_cross_inplane + i_rod_trans;
    Matrix3::from_diagonal(&Vector3::new(i_cross_axial, i_t, i_t))
}

/// Everything the dynamic-model builder needs at `(θ1, θ2)`, in `Σ_W`, SI.
#[derive(Clone, Debug)]
pub struct DynamicModel {
    /// Joint centre `O` \[m\].
    pub joint_centre: Vector3<f64>,
    /// Joint axis fixed in the base (`θ1`) [unit].
    pub joint_axis_base: Vector3<f64>,
    /// Joint axis fixed in the platform (`θ2`) at this pose [unit].
    pub joint_axis_platform: Vector3<f64>,
    /// Platform orientation `R = Rz(θ1) Ry(θ2)` (columns `x_M, y_M, z_M`).
    pub rotation: Matrix3<f64>,
    /// Centre of mass `G` \[m\].
    pub com: Vector3<f64>,
    /// Platform mass \[kg\].
    pub mass: f64,
    /// Inertia about `G` in platform axes [kg*m^2] ([`platform_inertia`]).
    pub inertia_local: Matrix3<f64>,
    /// Gravity [m/s^2].
    pub gravity: Vector3<f64>,
    /// Cable (base point, platform point) pairs \[m\].
    pub cables: [(Vector3<f64>, Vector3<f64>); 2],
    /// Spring (base point, platform point) pairs \[m\].
    pub springs: [(Vector3<f64>, Vector3<f64>); 2],
    /// Spring rate [N/m] and rest length \[m\].
    pub spring_k: f64,
    pub spring_rest: f64,
    /// Cable lengths at this pose (the actuator commands) \[m\].
    pub cable_lengths: [f64; 2],
}

/// The dynamic model at `(θ1, θ2)` (use `(0, 0)` for the reference pose).
pub fn dynamic_model(p: &Params, theta1: f64, theta2: f64) -> DynamicModel {
    let q = points(p, theta1, theta2);
    let cb = cable_base_points(p);
    let sb = spring_base_points(p);
    DynamicModel {
        joint_centre: q.o,
        joint_axis_base: joint_axis_base(),
        joint_axis_platform: joint_axis_platform(theta1, theta2),
        rotation: rotation(theta1, theta2),
        com: q.g,
        mass: p.mass,
        inertia_local: platform_inertia(p),
        gravity: gravity_vector(p),
        cables: [(cb[0], q.cable_platform[0]), (cb[1], q.cable_platform[1])],
        springs: [(sb[0], q.spring_platform[0]), (sb[1], q.spring_platform[1])],
        spring_k: p.spring_k,
        spring_rest: p.spring_rest,
        cable_lengths: cable_lengths(p, theta1, theta2),
    }
}

// ---------------------------------------------------------------------------
// Table 5 comparison and form finding (Section 4-5).
// ---------------------------------------------------------------------------

/// The model's Table-5 row at `(θ1, θ2)`: `[T_C1, T_C2, f_R1, f_R2, |f_joint|]`
/// in N and `m_joint` in N*mm (paper sign, [`Statics::joint_moment_paper_sign`]).
pub fn table5_row(p: &Params, theta1: f64, theta2: f64) -> [f64; 6] {
    let s = statics(p, theta1, theta2);
    [
        s.cable_tensions[0],
        s.cable_tensions[1],
        s.spring_forces[0],
        s.spring_forces[1],
        s.joint_reaction_force.norm(),
        to_mm(s.joint_moment_paper_sign),
    ]
}

/// Residual model − Table 5 "Analytical" for the four experiments of Table 3
/// (N for the forces, N*mm for the moment).
pub fn table5_residual(p: &Params) -> [[f64; 6]; 4] {
    let mut r = [[0.0; 6]; 4];
    for (k, &(t1, t2)) in TABLE3_EXPERIMENTS.iter().enumerate() {
        let row = table5_row(p, t1, t2);
        for j in 0..6 {
            r[k][j] = row[j] - TABLE5_ANALYTICAL[k][j];
        }
    }
    r
}

/// Least-squares cost: sum of squares of [`table5_residual`] (N^2 and (N*mm)^2).
pub fn table5_cost(p: &Params) -> f64 {
    table5_residual(p).iter().flatten().map(|v| v * v).sum()
}

/// Grid of joint coordinates `(θ1, θ2)`, `θ1` outer: `start + i step`,
/// `i < n1`, and `start + j step`, `j < n2` \[rad\].
pub fn form_finding_grid(start: f64, step: f64, n1: usize, n2: usize) -> Vec<(f64, f64)> {
    let mut v = Vec::with_capacity(n1 * n2);
    for i in 0..n1 {
        for j in 0..n2 {
            v.push((start + i as f64 * step, start + j as f64 * step));
        }
    }
    v
}

/// Table 2's grid: `-0.5236 + k 0.0087`, `k = 0..=120`, on both axes (121 x 121
/// = 14641 points, the last value +0.5204 rad). Table 2 prints `n = 14761`,
/// which no rectangular grid gives (`14761 = 29 x 509`; see [`findings`](super::findings::findings)).
pub fn paper_grid() -> Vec<(f64, f64)> {
    form_finding_grid(GRID_START_RAD, GRID_STEP_RAD, GRID_N_PER_AXIS, GRID_N_PER_AXIS)
}

/// Section 4 classifier: [`Statics::equilibrium`] at each grid point.
pub fn classify(p: &Params, grid: &[(f64, f64)]) -> Vec<bool> {
    grid.iter().map(|&(a, b)| statics(p, a, b).equilibrium).collect()
}

/// Number of equilibria on `grid`.
pub fn count_equilibria(p: &Params, grid: &[(f64, f64)]) -> usize {
    classify(p, grid).into_iter().filter(|e| *e).count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanisms::manriquez2019::findings::SAMPLE_THETAS;
    use approx::assert_relative_eq;

    const P: Params = Params::PAPER;

    #[test]
    fn validate_accepts_paper_and_rejects_bad_params() {
        assert!(P.validate().is_ok());
        assert!(Params { a2: 0.0, ..P }.validate().is_err());
        assert!(Params { spring_k: -1.0, ..P }.validate().is_err());
        assert!(Params { mass: f64::NAN, ..P }.validate().is_err());
        assert!(Params { base_x: P.l1, ..P }.validate().is_err());
    }

    #[test]
    fn home_pose_platform_points_in_mm() {
        let q = points(&P, 0.0, 0.0);
        assert_relative_eq!(vec_to_mm(&q.m), Vector3::new(400.0, 0.0, 0.0), epsilon = 1e-9);
        assert_relative_eq!(vec_to_mm(&q.cable_platform[0]), Vector3::new(400.0, 110.0, -110.0), epsilon = 1e-9);
        assert_relative_eq!(vec_to_mm(&q.cable_platform[1]), Vector3::new(400.0, -110.0, 110.0), epsilon = 1e-9);
        assert_relative_eq!(vec_to_mm(&q.g), Vector3::new(371.0, 0.0, 0.0), epsilon = 1e-9);
    }

    #[test]
    fn dh_chain_equals_eq15_and_eq8_eq9() {
        for &(a, b) in &SAMPLE_THETAS {
            assert_relative_eq!(t_w_m_chain(&P, a, b), t_w_m(&P, a, b), epsilon = 1e-14);
            assert_relative_eq!(
                t_w_m1(&P, a, b).fixed_view::<3, 1>(0, 3).into_owned(),
                p_m1_eq8(&P, a, b),
                epsilon = 1e-14
            );
            assert_relative_eq!(
                t_w_m2(&P, a, b).fixed_view::<3, 1>(0, 3).into_owned(),
                p_m2_eq9(&P, a, b),
                epsilon = 1e-14
            );
            let q = points(&P, a, b);
            assert_relative_eq!(q.cable_platform[0], p_m1_eq8(&P, a, b), epsilon = 1e-14);
        }
    }

    #[test]
    fn printed_eq3_is_off_by_a2_cos_minus_sin() {
        let d = t_1_m_as_printed(&P, 0.3) - t_1_m(&P, 0.3);
        assert_relative_eq!(to_mm(d[(1, 3)]), 210.0 * (0.3f64.cos() - 0.3f64.sin()), epsilon = 1e-9);
        assert_relative_eq!(to_mm(d[(1, 3)]), 138.5614, epsilon = 1e-3);
    }

    #[test]
    fn table2_centroid_is_on_axis_181mm_at_theta2_minus_0_4363() {
        let g = vec_to_mm(&points(&P, 0.0, -CENTROID_ELEVATION_RAD).g);
        assert_relative_eq!(g, Vector3::from(TABLE2_CENTROID_MM), epsilon = 2e-4);
    }

    #[test]
    fn ik_pose_round_trip_and_printed_eq16_fails_for_negative_theta2() {
        for &(a, b) in &SAMPLE_THETAS {
            let (c, d) = ik_pose(&t_w_m(&P, a, b));
            assert_relative_eq!(c, a, epsilon = 1e-14);
            assert_relative_eq!(d, b, epsilon = 1e-14);
        }
        let (c, _) = ik_pose_as_printed(&t_w_m(&P, 0.3, -0.2));
        assert_relative_eq!(c, 0.3 - std::f64::consts::PI, epsilon = 1e-12);
        let (c, _) = ik_pose_as_printed(&t_w_m(&P, 0.3, 0.2));
        assert_relative_eq!(c, 0.3, epsilon = 1e-12);
    }

    #[test]
    fn ik_position_recovers_angles_and_rejects_off_sphere() {
        let m = points(&P, -0.25, 0.4).m;
        let (a, b) = ik_position(&P, &m).unwrap();
        assert_relative_eq!(a, -0.25, epsilon = 1e-13);
        assert_relative_eq!(b, 0.4, epsilon = 1e-13);
        assert!(ik_position(&P, &(m * 1.01)).is_err());
    }

    #[test]
    fn cable_lengths_at_home_and_actuator_space_fk() {
        let l = cable_lengths(&P, 0.0, 0.0);
        // |(400+72.2183, 110-136.3245, -(110-136.3245))| mm
        let expect = ((400.0 - FIT_BASE_X_MM).powi(2) + 2.0 * (FIT_BASE_HALF_MM - 110.0).powi(2)).sqrt();
        assert_relative_eq!(to_mm(l[0]), expect, epsilon = 1e-9);
        assert_relative_eq!(to_mm(l[0]), 473.683, epsilon = 1e-3);
        for &(a, b) in &TABLE3_EXPERIMENTS {
            let (c, d) = theta_from_cable_lengths(&P, cable_lengths(&P, a, b), (a + 0.02, b - 0.01)).unwrap();
            assert_relative_eq!(c, a, epsilon = 1e-10);
            assert_relative_eq!(d, b, epsilon = 1e-10);
            let all = all_thetas_from_cable_lengths(&P, cable_lengths(&P, a, b));
            println!("({a}, {b}): cable-length solutions {all:?}");
            assert!(all.iter().any(|&(c, d)| (c - a).abs() < 1e-9 && (d - b).abs() < 1e-9));
        }
        // At θ = 0 the cable-length Jacobian is singular (fold of θ -> L).
        assert!(cable_length_jacobian(&P, 0.0, 0.0).determinant().abs() < 1e-15);
    }

    #[test]
    fn cable_length_jacobian_matches_finite_differences() {
        let (a, b, h) = (0.2, -0.15, 1e-6);
        let j = cable_length_jacobian(&P, a, b);
        let d1 = (Vector2::from(cable_lengths(&P, a + h, b)) - Vector2::from(cable_lengths(&P, a - h, b))) / (2.0 * h);
        let d2 = (Vector2::from(cable_lengths(&P, a, b + h)) - Vector2::from(cable_lengths(&P, a, b - h))) / (2.0 * h);
        assert_relative_eq!(j, Matrix2::from_columns(&[d1, d2]), epsilon = 1e-8);
    }

    #[test]
    fn statics_balances_forces_and_moments() {
        for &(a, b) in SAMPLE_THETAS[1..].iter().chain(TABLE3_EXPERIMENTS.iter()) {
            let s = statics(&P, a, b);
            assert!(!s.singular);
            let q = points(&P, a, b);
            let f: Vector3<f64> = (0..2)
                .map(|i| s.cable_tensions[i] * s.cable_directions[i] + s.spring_forces[i] * s.spring_directions[i])
                .sum::<Vector3<f64>>()
                + s.weight
                + s.joint_reaction_force;
            let m: Vector3<f64> = (0..2)
                .map(|i| {
                    (q.cable_platform[i] - q.o).cross(&(s.cable_tensions[i] * s.cable_directions[i]))
                        + (q.spring_platform[i] - q.o).cross(&(s.spring_forces[i] * s.spring_directions[i]))
                })
                .sum::<Vector3<f64>>()
                + (q.g - q.o).cross(&s.weight)
                + s.joint_reaction_moment;
            assert!(f.norm() < 1e-12 && m.norm() < 1e-13, "Eq. 22 {f:?}, Eq. 23 {m:?}");
            // The joint moment has no component about the two free axes.
            assert!(s.joint_reaction_moment.dot(&joint_axis_base()).abs() < 1e-15);
            assert!(s.joint_reaction_moment.dot(&joint_axis_platform(a, b)).abs() < 1e-15);
            // Virtual work: generalised forces vanish with the statics tensions.
            assert!(generalized_forces(&P, a, b, s.cable_tensions).norm() < 1e-13);
        }
    }

    #[test]
    fn statics_at_home_pose_is_singular_limit() {
        let s = statics(&P, 0.0, 0.0);
        assert!(s.singular);
        assert_relative_eq!(s.cable_tensions[0], s.cable_tensions[1], epsilon = 1e-4);
        assert_relative_eq!(s.cable_tensions[0], 2.5375, epsilon = 1e-3);
        assert_relative_eq!(s.spring_forces[0], FIT_SPRING_K_N_PER_M * s.spring_lengths[0], epsilon = 1e-12);
        assert_relative_eq!(s.spring_forces[0], 2.3637, epsilon = 1e-3);
        assert_relative_eq!(s.joint_reaction_force.norm(), 5.1300, epsilon = 1e-3);
        assert!(s.joint_reaction_moment.norm() < 1e-8);
        assert!(s.equilibrium && s.rod_in_compression);
        // Off the singular pose the system is regular and continuous with the limit.
        let t = statics(&P, 1e-4, 2e-4);
        assert!(!t.singular);
        assert_relative_eq!(t.cable_tensions[0], 2.5373, epsilon = 1e-3);
    }

    #[test]
    fn statics_experiment_1_numbers() {
        let s = statics(&P, 0.0941, 0.0332);
        assert_relative_eq!(s.cable_tensions[0], 2.45570, epsilon = 1e-4);
        assert_relative_eq!(s.cable_tensions[1], 2.60902, epsilon = 1e-4);
        assert_relative_eq!(s.spring_forces[0], 2.32397, epsilon = 1e-4);
        assert_relative_eq!(s.spring_forces[1], 2.39770, epsilon = 1e-4);
        assert_relative_eq!(s.joint_reaction_force.norm(), 5.12255, epsilon = 1e-4);
        assert_relative_eq!(to_mm(s.joint_moment_paper_sign), 0.97015, epsilon = 1e-4);
        assert_relative_eq!(to_mm(s.cable_lengths[0]), 457.6755, epsilon = 1e-3);
        assert_relative_eq!(to_mm(s.cable_lengths[1]), 488.5443, epsilon = 1e-3);
    }

    #[test]
    fn table5_joint_force_and_moment_reproduced_split_not() {
        let r = table5_residual(&P);
        for row in &r {
            assert!(row[4].abs() < 0.011, "|f_joint| residual {} N", row[4]);
            assert!(row[5].abs() < 0.016, "m_joint residual {} N*mm", row[5]);
            assert!(row[0].abs() > 1.8 && row[0].abs() < 2.25, "cable split residual {} N", row[0]);
        }
        assert_relative_eq!(table5_cost(&P), 65.9943, epsilon = 1e-3);
    }

    #[test]
    fn fitted_constants_minimise_table5_cost() {
        let c0 = table5_cost(&P);
        let steps = [("base_x", 1e-4), ("base_half", 1e-4), ("spring_k", 1e-3)];
        for (name, h) in steps {
            for sgn in [-1.0, 1.0] {
                let mut q = P;
                match name {
                    "base_x" => q.base_x += sgn * h,
                    "base_half" => q.base_half += sgn * h,
                    _ => q.spring_k += sgn * h,
                }
                assert!(table5_cost(&q) > c0, "{name} {sgn}: {} <= {c0}", table5_cost(&q));
            }
        }
        // L0 is at its bound: lengthening the springs' rest length raises the cost.
        assert!(table5_cost(&Params { spring_rest: 1e-3, ..P }) > c0);
    }

    #[test]
    fn table3_experiments_are_stable_equilibria() {
        for &(a, b) in &TABLE3_EXPERIMENTS {
            let s = statics(&P, a, b);
            assert!(s.equilibrium && s.rod_in_compression);
            assert!(s.cable_tensions.iter().all(|t| *t > 2.4 && *t < 2.65), "{:?}", s.cable_tensions);
            assert!(stable_with_fixed_cables(&P, a, b));
            let k = stiffness_matrix(&P, a, b, 1e4);
            let e = k.symmetric_eigenvalues();
            assert!(e.min() > 0.0, "{e:?}");
        }
    }

    #[test]
    fn stiffness_matrix_matches_energy_hessian() {
        // With k_c = 0 and T frozen, K = ∇²V_gs + Σ T ∇²L.
        let (a, b, h) = (0.05, -0.04, 1e-4);
        let t = statics(&P, a, b).cable_tensions;
        let v = |x: f64, y: f64| {
            let l = cable_lengths(&P, x, y);
            potential_gravity_springs(&P, x, y) + t[0] * l[0] + t[1] * l[1]
        };
        let k11 = (v(a + h, b) - 2.0 * v(a, b) + v(a - h, b)) / (h * h);
        let k22 = (v(a, b + h) - 2.0 * v(a, b) + v(a, b - h)) / (h * h);
        let k12 = (v(a + h, b + h) - v(a + h, b - h) - v(a - h, b + h) + v(a - h, b - h)) / (4.0 * h * h);
        let k = stiffness_matrix(&P, a, b, 0.0);
        assert_relative_eq!(k, Matrix2::new(k11, k12, k12, k22), epsilon = 1e-5, max_relative = 1e-4);
    }

    #[test]
    // The grid starts at Table 2's printed -0.5236 rad (rounded, not -π/6): the test says so.
    #[allow(clippy::approx_constant)]
    fn paper_grid_has_121_by_121_points_not_14761() {
        let g = paper_grid();
        // Table 2's range -0.5236..0.5204 rad at its step 0.0087 rad: 121 values per angle.
        assert_eq!(g.len(), 121 * 121);
        assert_relative_eq!((0.5204 - -0.5236) / 120.0, 0.0087, epsilon = 1e-12);
        assert_ne!(g.len(), PAPER_N_CONFIGURATIONS);
        assert_eq!(PAPER_N_CONFIGURATIONS, 29 * 509);
        assert_relative_eq!(g[0].0, -0.5236, epsilon = 1e-15);
        assert_relative_eq!(g.last().unwrap().1, 0.5204, epsilon = 1e-12);
    }

    #[test]
    fn form_finding_count_on_paper_grid() {
        let g = paper_grid();
        let n_eq = count_equilibria(&P, &g);
        println!("equilibria on the 121x121 grid: {n_eq} of {}", g.len());
        assert_eq!(n_eq, EXPECTED_EQUILIBRIA_121);
    }

    /// Equilibria of [`Params::PAPER`] on [`paper_grid`] (recorded from the model).
    const EXPECTED_EQUILIBRIA_121: usize = 14641;

    #[test]
    fn platform_inertia_numbers() {
        let i = platform_inertia(&P);
        assert_relative_eq!(i[(0, 0)], 0.002763, epsilon = 2e-6);
        assert_relative_eq!(i[(1, 1)], 0.002905, epsilon = 2e-6);
        assert_relative_eq!(i[(1, 1)], i[(2, 2)], epsilon = 1e-15);
    }

    #[test]
    fn dynamic_model_is_consistent() {
        let d = dynamic_model(&P, 0.0941, 0.0332);
        assert_relative_eq!(d.joint_axis_base.dot(&d.joint_axis_platform), 0.0, epsilon = 1e-15);
        assert_relative_eq!(d.rotation.column(1).into_owned(), d.joint_axis_platform, epsilon = 1e-15);
        for i in 0..2 {
            assert_relative_eq!((d.cables[i].1 - d.cables[i].0).norm(), d.cable_lengths[i], epsilon = 1e-15);
        }
        assert_relative_eq!(d.gravity, Vector3::new(9.81, 0.0, 0.0));
    }
}
