//! Closed-form model of the translational 3-DOF tensegrity mechanism of
//! Mohr & Arsenault (2011), "Kinematic analysis of a translational 3-DOF
//! tensegrity mechanism", Trans. CSME 35(4).
//!
//! Everything here is a pure function of `f64` / `nalgebra` values.
//! Units: lengths in metres \[m\], angles in radians \[rad\], forces in newtons
//! \[N\], force densities (tension coefficients) in [N/m], torques in [N m],
//! the torsion spring constant `kappa` in [N m/rad], energies in joules \[J\].
//!
//! # Model (paper Eq. 1-6)
//! * Fixed frame `XYZ` at the centroid `O` of the base triangle `A1A2A3`
//!   (side `lb`), `X` along `A1 -> A2`, `Y` through `A3`, `Z` up (Eq. 1):
//!   `a1 = lb(-1/2, -sqrt3/6, 0)`, `a2 = lb(1/2, -sqrt3/6, 0)`, `a3 = lb(0, sqrt3/3, 0)`.
//! * End-effector: rigid equilateral triangle `B1B2B3` (side `lb`) with
//!   centroid `p = (x, y, z)`, translating only, body frame parallel to
//!   `XYZ`; body-frame offsets `b_i = -a_i` (Eq. 2), so `B_i = p - a_i`.
//! * Compression members `A_iB_i`, each the "virtual compression spring" of
//!   Fig. 2: two rigid links of length `lo/2` joined by a revolute knee with a
//!   linear torsion spring; universal joint at `A_i`, spherical joint at `B_i`.
//!   Effective length `l_i = |p - 2 a_i|` (Eq. 16).
//! * Six cables (tension only), numbered as the columns of Eq. 21:
//!   `1: A2B3, 2: A1B3, 3: A1B2, 4: A3B2, 5: A3B1, 6: A2B1`; cables `j` and
//!   `j+3` form pair `rho_j` (Eq. 6) and are parallel and of equal length
//!   `rho_j = |p + a_j|` (Eq. 10, 15). See [`CABLES`].
//!
//! # Sign conventions
//! Internal forces are tension-positive (the paper's convention): `f_i < 0`
//! is compression. Unit vectors `u_i` (springs) and `n_j` (cables) point from
//! the platform node toward the base node, so an element of internal force
//! `F` pushes/pulls the platform with `F * u` (Eq. 19-21).
//!
//! # Torsion spring convention (Eq. 3-5)
//! The knee angle (angle between the two links at the knee) is `2 theta_i`,
//! `theta_i = asin(l_i/lo)` (Eq. 3); straight links: knee angle `pi`, `l_i = lo`.
//! The spring is at rest when straight (`theta_o = pi/2`). Stored energy
//! `E = kappa/2 (2 theta - pi)^2`; Eq. 4's `tau = kappa (2 theta - pi) = dE/d(2 theta)`
//! is `<= 0`: the torque the spring applies to the links *opens* the knee
//! with magnitude `|tau| = kappa (pi - 2 theta)`. The knee sits
//! `h = (lo/2) cos theta` off the line `A_iB_i` and the member is a two-force
//! member with axial force `f = tau / h = dE/dl` (Eq. 5).
//!
//! # Key derived results (see [`findings`](super::findings::findings) for the numeric checks)
//! * Eq. 1-10 and 12-31 hold (Eq. 11 has a typo, `a_iy^2`
//!   twice).
//! * `f(l) = -(4 kappa/lo) phi / sin(phi)` with `phi = acos(l/lo)`: the spring
//!   pushes with `2 pi kappa/lo` at `l = 0` and still `4 kappa/lo` as `l -> lo`.
//!   The text's "fully extended springs no longer apply any compressive force"
//!   is false. The outer static boundary coincides with the kinematic sphere
//!   `l_i = lo` only where the triangle inequality below still holds (63% of
//!   the sphere patch for `lo = 3 lb`, see [`outer_boundary_survey`](super::findings::outer_boundary_survey)).
//! * Eq. 26-28 are the unique solution of Eq. 19 (for `z != 0`); Eq. 29-31
//!   say that the three compression force densities `g_i = -f_i/l_i` obey
//!   the strict triangle inequality. Because `f` is linear in `kappa`, the
//!   whole static workspace (not only its inner boundary) is independent of
//!   `kappa`.
//! * `det W_t = det[p+a1, p+a2, p+a3] * (-3/2 lb^4 z^2) / (rho1 rho2 rho3)^2`
//!   `= -3 sqrt3/4 z^3 lb^6 / (rho1 rho2 rho3)^2` (Eq. 25 holds).

use crate::mechanisms::ParamError;
use nalgebra::{Matrix3, Matrix6, Matrix6x3, Rotation3, Vector3, Vector6};
use std::f64::consts::PI;

/// `sqrt(3)`, appears throughout the equilateral-triangle geometry.
pub const SQRT_3: f64 = 1.732_050_807_568_877_2;
/// Fig. 4-6 example: triangle side `lb = 2` (the paper gives no unit; metres here).
pub const PAPER_LB: f64 = 2.0;
/// Fig. 4-6 example: `lo = l_max = 3 lb`.
pub const PAPER_LO_OVER_LB: f64 = 3.0;
/// Torsion spring constant used by default [N m/rad]. Not in the paper (which
/// shows that nothing it computes depends on it): a model choice giving axial
/// spring forces between `4 kappa/lo = 6.7 N` and `2 pi kappa/lo = 10.5 N`
/// for `lo = 6 m`, i.e. about the weight of a 1 kg end-effector.
pub const DEFAULT_KAPPA: f64 = 10.0;
/// `f -> -FULL_EXTENSION_FORCE_FACTOR * kappa / lo` as `l -> lo` (limit of Eq. 5).
pub const FULL_EXTENSION_FORCE_FACTOR: f64 = 4.0;
/// `f = -ZERO_LENGTH_FORCE_FACTOR * kappa / lo` at `l = 0` (Eq. 5).
pub const ZERO_LENGTH_FORCE_FACTOR: f64 = 2.0 * PI;
/// Below this `phi = acos(l/lo)` [rad] the ratio `phi / sin(phi)` is taken
/// from its series `1 + phi^2/6` (error < 1e-17).
const PHI_SERIES_BELOW: f64 = 1e-4;
/// DKP: a negative Eq. 14 radicand down to this fraction of
/// `lb^2 (rho1^2+rho2^2+rho3^2)` is rounding and gives `z = 0`.
const DKP_RADICAND_REL_TOL: f64 = 1e-12;

/// Mechanism parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Side of the base and end-effector triangles `l_b` \[m\].
    pub lb: f64,
    /// Length of a straight virtual spring `l_o` \[m\] (two links of `lo/2`);
    /// also the maximum spring length `l_max` of Eq. 18.
    pub lo: f64,
    /// Torsion spring constant `kappa` [N m/rad] (Eq. 4), same for all three.
    pub kappa: f64,
    /// Minimum spring length `l_min` \[m\] of Eq. 17 (the paper uses 0).
    pub l_min: f64,
}

impl Params {
    /// Figs. 4-6: `lb = 2 m`, `lo = 3 lb = 6 m`, `l_min = 0`; `kappa` = [`DEFAULT_KAPPA`]
    /// (not in the paper).
    pub const PAPER: Params =
        Params { lb: PAPER_LB, lo: PAPER_LO_OVER_LB * PAPER_LB, kappa: DEFAULT_KAPPA, l_min: 0.0 };

    /// `lb > 0`, `lo > 0`, `kappa > 0`, `0 <= l_min < lo`, all finite.
    pub fn validate(&self) -> Result<(), ParamError> {
        for (name, value) in [("lb", self.lb), ("lo", self.lo), ("kappa", self.kappa), ("l_min", self.l_min)] {
            if !value.is_finite() {
                return Err(ParamError::NotFinite { name, value });
            }
        }
        for (name, value) in [("lb", self.lb), ("lo", self.lo), ("kappa", self.kappa)] {
            if value <= 0.0 {
                return Err(ParamError::NotPositive { name, value });
            }
        }
        if self.l_min < 0.0 || self.l_min >= self.lo {
            return Err(ParamError::Condition(format!("l_min must be in [0, lo = {}), got {}", self.lo, self.l_min)));
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// Geometry (Eq. 1-2, 6, 10, 15-16).
// ---------------------------------------------------------------------------

/// Eq. 1: base nodes `a_i` \[m\] in `XYZ` (index 0, 1, 2 = `A1, A2, A3`).
pub fn base_nodes(p: &Params) -> [Vector3<f64>; 3] {
    let l = p.lb;
    [
        l * Vector3::new(-0.5, -SQRT_3 / 6.0, 0.0),
        l * Vector3::new(0.5, -SQRT_3 / 6.0, 0.0),
        l * Vector3::new(0.0, SQRT_3 / 3.0, 0.0),
    ]
}

/// Eq. 2: platform node offsets `b_i` \[m\] in the body frame `X'Y'Z'`
/// (parallel to `XYZ`); `b_i = -a_i`.
pub fn platform_offsets(p: &Params) -> [Vector3<f64>; 3] {
    base_nodes(p).map(|a| -a)
}

/// Platform nodes `B_i = p + b_i` \[m\] in `XYZ` for centroid `p` (pure translation).
pub fn platform_nodes(p: &Params, centroid: &Vector3<f64>) -> [Vector3<f64>; 3] {
    platform_offsets(p).map(|b| centroid + b)
}

/// One cable: base node index, platform node index (0-based: 0 = node 1) and
/// the actuated length `rho_j` it follows (0-based: 0 = `rho1`), Eq. 6.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cable {
    pub base: usize,
    pub platform: usize,
    pub rho: usize,
}

/// The six cables in the column order of Eq. 21 (`t1..t6` of Eq. 23):
/// `t1 A2B3, t2 A1B3, t3 A1B2, t4 A3B2, t5 A3B1, t6 A2B1`. Cables `j` and
/// `j+3` follow `rho_j` (Eq. 6, 26-28).
pub const CABLES: [Cable; 6] = [
    Cable { base: 1, platform: 2, rho: 0 },
    Cable { base: 0, platform: 2, rho: 1 },
    Cable { base: 0, platform: 1, rho: 2 },
    Cable { base: 2, platform: 1, rho: 0 },
    Cable { base: 2, platform: 0, rho: 1 },
    Cable { base: 1, platform: 0, rho: 2 },
];

/// Lengths \[m\] of the six cables ([`CABLES`] order) for a platform with
/// centroid `centroid` and orientation `rot` (body frame -> `XYZ`). With
/// `rot = identity` the pairs are equal (Eq. 7-9).
pub fn cable_lengths_posed(p: &Params, centroid: &Vector3<f64>, rot: &Rotation3<f64>) -> [f64; 6] {
    let a = base_nodes(p);
    let b = platform_offsets(p);
    CABLES.map(|c| (centroid + rot * b[c.platform] - a[c.base]).norm())
}

/// Lengths \[m\] of the six cables for a translated platform.
pub fn cable_lengths(p: &Params, centroid: &Vector3<f64>) -> [f64; 6] {
    cable_lengths_posed(p, centroid, &Rotation3::identity())
}

/// Eq. 15 (IKP): `rho_j = |p + a_j|` \[m\].
pub fn ikp(p: &Params, centroid: &Vector3<f64>) -> [f64; 3] {
    base_nodes(p).map(|a| (centroid + a).norm())
}

/// Eq. 11 exactly as printed, `rho_i^2 = x^2+y^2+z^2 + 2x a_ix + 2y a_iy + a_iy^2 + a_iy^2`
/// [m^2] (a typo: the last term should be `a_ix^2`). `i` 0-based.
pub fn rho_sq_eq11_as_printed(p: &Params, centroid: &Vector3<f64>, i: usize) -> f64 {
    let a = base_nodes(p)[i];
    let c = centroid;
    c.norm_squared() + 2.0 * c.x * a.x + 2.0 * c.y * a.y + a.y * a.y + a.y * a.y
}

/// Radicand of Eq. 14 [m^4]: `-rho1^4 - rho2^4 - rho3^4 + rho1^2 rho2^2 + rho1^2 rho3^2
/// + rho2^2 rho3^2 + lb^2 (rho1^2 + rho2^2 + rho3^2 - lb^2)`; equals `3 lb^2 z^2`.
pub fn dkp_radicand_eq14(p: &Params, rho: &[f64; 3]) -> f64 {
    let [u1, u2, u3] = rho.map(|r| r * r);
    let l2 = p.lb * p.lb;
    -u1 * u1 - u2 * u2 - u3 * u3 + u1 * u2 + u1 * u3 + u2 * u3 + l2 * (u1 + u2 + u3 - l2)
}

/// Eq. 12-14 (DKP), the `z >= 0` branch: centroid \[m\] from the actuated
/// lengths `rho` \[m\]. `None` when the radicand of Eq. 14 is negative (no
/// assembly) or not a finite number (overflowed), or a `rho` is negative / not finite. The `z < 0` mirror image
/// is `(x, y, -z)`.
pub fn dkp(p: &Params, rho: &[f64; 3]) -> Option<Vector3<f64>> {
    if rho.iter().any(|r| !r.is_finite() || *r < 0.0) {
        return None;
    }
    let [u1, u2, u3] = rho.map(|r| r * r);
    let lb = p.lb;
    let x = (u2 - u1) / (2.0 * lb); // Eq. 12
    let y = (2.0 * u3 - u2 - u1) / (2.0 * SQRT_3 * lb); // Eq. 13
    let rad = dkp_radicand_eq14(p, rho);
    let scale = lb * lb * (u1 + u2 + u3);
    // An overflowed radicand (lb = 1e300) is no branch: it had printed (0, 0, 0).
    if !rad.is_finite() || !scale.is_finite() || rad < -DKP_RADICAND_REL_TOL * scale {
        return None;
    }
    let z = rad.max(0.0).sqrt() / (SQRT_3 * lb); // Eq. 14, + branch
    Some(Vector3::new(x, y, z))
}

/// Eq. 16: effective spring lengths `l_i = |p + b_i - a_i| = |p - 2 a_i|` \[m\].
pub fn spring_lengths(p: &Params, centroid: &Vector3<f64>) -> [f64; 3] {
    base_nodes(p).map(|a| (centroid - 2.0 * a).norm())
}

// ---------------------------------------------------------------------------
// Virtual compression spring (Eq. 3-5).
// ---------------------------------------------------------------------------

/// Eq. 3: half knee angle `theta = asin(l/lo)` \[rad\], for `0 <= l <= lo`
/// (NaN outside).
pub fn half_angle(p: &Params, l: f64) -> f64 {
    if !(0.0..=p.lo).contains(&l) {
        return f64::NAN;
    }
    (l / p.lo).asin()
}

/// Knee angle `2 theta` \[rad\] between the two links (`pi` = straight, at rest).
pub fn knee_angle(p: &Params, l: f64) -> f64 {
    2.0 * half_angle(p, l)
}

/// Spring length `l = lo sin(knee/2)` \[m\] for a knee angle in `[0, pi]`.
pub fn length_from_knee_angle(p: &Params, knee: f64) -> f64 {
    p.lo * (0.5 * knee).sin()
}

/// Distance `h = (lo/2) cos theta = sqrt(lo^2 - l^2)/2` \[m\] of the knee from
/// the line `A_iB_i` (the lever arm of the axial force about the knee).
pub fn knee_offset(p: &Params, l: f64) -> f64 {
    0.5 * (p.lo * p.lo - l * l).max(0.0).sqrt()
}

/// Eq. 4: `tau = kappa (knee - pi)` [N m], `knee = 2 theta`; `tau = dE/d(knee)`.
/// Negative for a bent knee: the torque the spring exerts on the links opens
/// the knee (towards `pi`) with magnitude `-tau`.
pub fn torsion_torque(p: &Params, knee: f64) -> f64 {
    p.kappa * (knee - PI)
}

/// Torsion spring energy `E = kappa/2 (knee - pi)^2` \[J\].
pub fn torsion_energy(p: &Params, knee: f64) -> f64 {
    0.5 * p.kappa * (knee - PI).powi(2)
}

/// Virtual spring energy as a function of its length, `E(l) = kappa/2 (2 asin(l/lo) - pi)^2` \[J\].
pub fn spring_energy(p: &Params, l: f64) -> f64 {
    torsion_energy(p, knee_angle(p, l))
}

/// Moment balance about the knee: axial force `f = tau / h` \[N\] for knee
/// torque `tau` [N m] (Eq. 4) at length `l` \[m\] (tension positive).
pub fn axial_force_from_torque(p: &Params, tau: f64, l: f64) -> f64 {
    tau / knee_offset(p, l)
}

/// Knee torque [N m] that balances axial force `f` \[N\] at length `l` \[m\]: `tau = f h`.
pub fn torque_from_axial_force(p: &Params, f: f64, l: f64) -> f64 {
    f * knee_offset(p, l)
}

/// Eq. 5, derived and written without the `0/0` at `l = lo`:
/// `f = dE/dl = -(4 kappa/lo) phi / sin(phi)`, `phi = acos(l/lo) = pi/2 - theta` \[N\].
/// Tension positive, so `f < 0` (compression) on `0 <= l <= lo`, from
/// `-2 pi kappa/lo` at `l = 0` to `-4 kappa/lo` at `l = lo`. NaN outside `[0, lo]`.
pub fn spring_force(p: &Params, l: f64) -> f64 {
    if !(0.0..=p.lo).contains(&l) {
        return f64::NAN;
    }
    let phi = (l / p.lo).acos();
    let ratio = if phi < PHI_SERIES_BELOW { 1.0 + phi * phi / 6.0 } else { phi / phi.sin() };
    -FULL_EXTENSION_FORCE_FACTOR * p.kappa / p.lo * ratio
}

/// Eq. 5 exactly as printed: `f = 2 kappa (2 asin(l/lo) - pi) / (lo sqrt(1 - (l/lo)^2))` \[N\]
/// (NaN at `l = lo`: `0/0`).
pub fn spring_force_eq5_as_printed(p: &Params, l: f64) -> f64 {
    let s = l / p.lo;
    2.0 * p.kappa * (2.0 * s.asin() - PI) / (p.lo * (1.0 - s * s).sqrt())
}

/// `lim_{l -> lo} f = -4 kappa / lo` \[N\]: the spring still pushes when fully extended.
pub fn spring_force_full_extension_limit(p: &Params) -> f64 {
    -FULL_EXTENSION_FORCE_FACTOR * p.kappa / p.lo
}

/// Force density (tension coefficient) `f_i / l_i` [N/m] (Sec. 4.2).
pub fn force_density(p: &Params, l: f64) -> f64 {
    spring_force(p, l) / l
}

/// One virtual spring placed in space, for the dynamic model.
#[derive(Clone, Copy, Debug)]
pub struct SpringChain {
    /// Base node `A_i` (universal joint centre) \[m\].
    pub a: Vector3<f64>,
    /// Platform node `B_i` (spherical joint centre) \[m\].
    pub b: Vector3<f64>,
    /// Knee (revolute joint centre) \[m\]: `(A+B)/2 + h c`, `c` the unit vector in
    /// the chain plane perpendicular to `AB` with `c . e1 > 0`.
    pub knee: Vector3<f64>,
    /// First universal-joint axis (fixed to the base): `e1 = z x a_i/|a_i|`,
    /// horizontal, orthogonal to `a_i` (and to `e2`).
    pub e1: Vector3<f64>,
    /// Second universal-joint axis = knee revolute axis = chain-plane normal:
    /// `e2 = (e1 x (B-A)) / |e1 x (B-A)|`.
    pub e2: Vector3<f64>,
    /// Effective length `l_i` \[m\].
    pub length: f64,
    /// Knee angle `2 theta_i` \[rad\].
    pub knee_angle: f64,
    /// Eq. 4 torque [N m].
    pub torque: f64,
    /// Eq. 5 axial force \[N\] (tension positive).
    pub force: f64,
}

/// Place virtual spring `i` (0-based) for the platform at `centroid` (Sec. 2).
/// Convention (the paper's Fig. 2 is missing): the first (base-fixed)
/// universal-joint axis is `e1 = z x a_i/|a_i|`, the horizontal direction
/// orthogonal to `a_i`; the chain plane contains `e1` and `A_iB_i`, and the
/// knee is displaced towards `+e1` (at the home pose `p = (0,0,z)` the three
/// knees then sit at `p/2 + h e1_i`, apart by `sqrt3 h`). With this choice
/// `e1 || A_iB_i` (joint singularity) needs `z = 0`, outside the workspace;
/// the alternative reading `e1 = z` would be singular at `p = 2 a_i + z ez`,
/// inside it. Either way the chain is a two-force member (axial force only).
/// `None` when `l_i > lo` or `e1 || A_iB_i`.
pub fn spring_chain(p: &Params, centroid: &Vector3<f64>, i: usize) -> Option<SpringChain> {
    let a = base_nodes(p)[i];
    let b = platform_nodes(p, centroid)[i];
    let d = b - a;
    let l = d.norm();
    if l > p.lo || l == 0.0 {
        return None;
    }
    let e1 = Vector3::z().cross(&a).normalize();
    let n = e1.cross(&d);
    if n.norm() <= f64::EPSILON * l {
        return None;
    }
    let e2 = n.normalize();
    let dh = d / l;
    let c = (e1 - e1.dot(&dh) * dh).normalize();
    let knee = 0.5 * (a + b) + knee_offset(p, l) * c;
    let ka = knee_angle(p, l);
    Some(SpringChain {
        a,
        b,
        knee,
        e1,
        e2,
        length: l,
        knee_angle: ka,
        torque: torsion_torque(p, ka),
        force: spring_force(p, l),
    })
}

// ---------------------------------------------------------------------------
// Statics (Eq. 19-31).
// ---------------------------------------------------------------------------

/// Unit vectors `u_i = (a_i - B_i)/l_i` of the springs (platform -> base).
pub fn spring_unit_vectors(p: &Params, centroid: &Vector3<f64>) -> [Vector3<f64>; 3] {
    let a = base_nodes(p);
    let b = platform_nodes(p, centroid);
    [0, 1, 2].map(|i| (a[i] - b[i]).normalize())
}

/// Unit vectors `n_j = -(p + a_j)/rho_j` of the cable pairs (platform -> base);
/// both cables of pair `j` have this direction.
pub fn cable_pair_unit_vectors(p: &Params, centroid: &Vector3<f64>) -> [Vector3<f64>; 3] {
    base_nodes(p).map(|a| -(centroid + a).normalize())
}

/// Eq. 20: `W_f` (6x3) with columns `[u_i; b_i x u_i]` (moments about `P`).
pub fn wf(p: &Params, centroid: &Vector3<f64>) -> Matrix6x3<f64> {
    let u = spring_unit_vectors(p, centroid);
    let b = platform_offsets(p);
    let mut m = Matrix6x3::zeros();
    for i in 0..3 {
        let mo = b[i].cross(&u[i]);
        m.set_column(i, &Vector6::new(u[i].x, u[i].y, u[i].z, mo.x, mo.y, mo.z));
    }
    m
}

/// `W_t` (6x6) built from the six cables individually: column `j` is
/// `[v_j; b_k x v_j]`, `v_j` the unit vector from the cable's platform node
/// `B_k` to its base node.
pub fn wt(p: &Params, centroid: &Vector3<f64>) -> Matrix6<f64> {
    let a = base_nodes(p);
    let b = platform_offsets(p);
    let mut m = Matrix6::zeros();
    for (j, c) in CABLES.iter().enumerate() {
        let v = (a[c.base] - (centroid + b[c.platform])).normalize();
        let mo = b[c.platform].cross(&v);
        m.set_column(j, &Vector6::new(v.x, v.y, v.z, mo.x, mo.y, mo.z));
    }
    m
}

/// Eq. 21 as printed: top row `n1 n2 n3 n1 n2 n3`, bottom row
/// `b3xn1, b3xn2, b2xn3, b2xn1, b1xn2, b1xn3` (three pair directions `n_j`).
pub fn wt_as_printed(p: &Params, centroid: &Vector3<f64>) -> Matrix6<f64> {
    let n = cable_pair_unit_vectors(p, centroid);
    let b = platform_offsets(p);
    let arms = [(2, 0), (2, 1), (1, 2), (1, 0), (0, 1), (0, 2)]; // (b index, n index)
    let mut m = Matrix6::zeros();
    for (j, &(bi, ni)) in arms.iter().enumerate() {
        let v = n[ni];
        let mo = b[bi].cross(&v);
        m.set_column(j, &Vector6::new(v.x, v.y, v.z, mo.x, mo.y, mo.z));
    }
    m
}

/// Spring forces `f_i` \[N\] (Eq. 5) at the platform pose (NaN if some `l_i > lo`).
pub fn spring_forces(p: &Params, centroid: &Vector3<f64>) -> [f64; 3] {
    spring_lengths(p, centroid).map(|l| spring_force(p, l))
}

/// Eq. 24: `t = -W_t^{-1} W_f f` \[N\] by LU on the full 6x6 system, for given
/// spring forces `f` \[N\]. NaN entries when `W_t` is singular (`z = 0`).
pub fn tensions_full_for(p: &Params, centroid: &Vector3<f64>, f: &[f64; 3]) -> [f64; 6] {
    let rhs = -(wf(p, centroid) * Vector3::from(*f));
    match wt(p, centroid).lu().solve(&rhs) {
        Some(t) => [t[0], t[1], t[2], t[3], t[4], t[5]],
        None => [f64::NAN; 6],
    }
}

/// Eq. 26-28 for given spring forces `f` \[N\]:
/// `t_j = t_{j+3} = rho_j/2 (fh_j - fh_k - fh_l)` \[N\], `fh_i = f_i/l_i`.
pub fn tensions_closed_form_for(p: &Params, centroid: &Vector3<f64>, f: &[f64; 3]) -> [f64; 6] {
    let rho = ikp(p, centroid);
    let l = spring_lengths(p, centroid);
    let fh = [f[0] / l[0], f[1] / l[1], f[2] / l[2]];
    let s = fh[0] + fh[1] + fh[2];
    let t = [0, 1, 2].map(|j| 0.5 * rho[j] * (2.0 * fh[j] - s));
    [t[0], t[1], t[2], t[0], t[1], t[2]]
}

/// Wrench on the platform `W_f f + W_t t` [N; N m] (Eq. 19; zero at equilibrium).
pub fn wrench(p: &Params, centroid: &Vector3<f64>, f: &[f64; 3], t: &[f64; 6]) -> Vector6<f64> {
    wf(p, centroid) * Vector3::from(*f) + wt(p, centroid) * Vector6::from_column_slice(t)
}

/// `det W_t` [-] computed from the matrix.
pub fn det_wt(p: &Params, centroid: &Vector3<f64>) -> f64 {
    wt(p, centroid).determinant()
}

/// `det W_t` derived by block elimination (columns `j+3` minus `j`):
/// `det[p+a1, p+a2, p+a3] * det[(a3-a2)x(p+a1), (a3-a1)x(p+a2), (a2-a1)x(p+a3)] / (rho1 rho2 rho3)^2`.
pub fn det_wt_derived(p: &Params, centroid: &Vector3<f64>) -> f64 {
    let a = base_nodes(p);
    let q = a.map(|ai| centroid + ai);
    let qm = Matrix3::from_columns(&q);
    let r =
        Matrix3::from_columns(&[(a[2] - a[1]).cross(&q[0]), (a[2] - a[0]).cross(&q[1]), (a[1] - a[0]).cross(&q[2])]);
    let rho2: f64 = q.iter().map(|v| v.norm_squared()).product();
    qm.determinant() * r.determinant() / rho2
}

/// Eq. 25 as printed: `-3 sqrt3/4 z^3 lb^6 / (rho1^2 rho2^2 rho3^2)`.
pub fn det_wt_eq25(p: &Params, centroid: &Vector3<f64>) -> f64 {
    let rho = ikp(p, centroid);
    let r2: f64 = rho.iter().map(|r| r * r).product();
    -3.0 * SQRT_3 / 4.0 * centroid.z.powi(3) * p.lb.powi(6) / r2
}

/// Eq. 29-31 left-hand sides [N/m]: `fh_j - fh_k - fh_l` (pair `j` taut iff `> 0`).
pub fn static_margins(p: &Params, centroid: &Vector3<f64>) -> [f64; 3] {
    let fh = spring_lengths(p, centroid).map(|l| force_density(p, l));
    let s = fh[0] + fh[1] + fh[2];
    [0, 1, 2].map(|j| 2.0 * fh[j] - s)
}

/// Full static state at a translated pose.
#[derive(Clone, Debug)]
pub struct Statics {
    /// Centroid `p` \[m\].
    pub centroid: Vector3<f64>,
    /// Actuated lengths `rho_j` \[m\] (Eq. 15).
    pub rho: [f64; 3],
    /// Spring lengths `l_i` \[m\] (Eq. 16).
    pub spring_lengths: [f64; 3],
    /// Knee angles `2 theta_i` \[rad\] (Eq. 3).
    pub knee_angles: [f64; 3],
    /// Spring forces `f_i` \[N\] (Eq. 5), tension positive; NaN if `l_i > lo`.
    pub spring_forces: [f64; 3],
    /// Force densities `f_i / l_i` [N/m].
    pub force_densities: [f64; 3],
    /// Cable tensions `t_1..t_6` \[N\] from the full 6x6 balance (Eq. 24).
    pub tensions_full: [f64; 6],
    /// Cable tensions from Eq. 26-28 \[N\].
    pub tensions_closed_form: [f64; 6],
    /// `det W_t` (Eq. 25).
    pub det_wt: f64,
    /// Cables with negative (closed-form) tension, [`CABLES`] order.
    pub slack: [bool; 6],
    /// All Eq. 17-18 and `z > 0` hold.
    pub in_kinematic_workspace: bool,
    /// Kinematic workspace and Eq. 29-31 hold (all cables strictly taut).
    pub in_static_workspace: bool,
}

/// Statics at centroid `centroid` \[m\]: spring forces from Eq. 5 and cable
/// tensions both by Eq. 24 and Eq. 26-28.
pub fn statics(p: &Params, centroid: &Vector3<f64>) -> Statics {
    let l = spring_lengths(p, centroid);
    let f = l.map(|li| spring_force(p, li));
    let tf = tensions_full_for(p, centroid, &f);
    let tc = tensions_closed_form_for(p, centroid, &f);
    let w = classify(p, centroid);
    Statics {
        centroid: *centroid,
        rho: ikp(p, centroid),
        spring_lengths: l,
        knee_angles: l.map(|li| knee_angle(p, li)),
        spring_forces: f,
        force_densities: [f[0] / l[0], f[1] / l[1], f[2] / l[2]],
        tensions_full: tf,
        tensions_closed_form: tc,
        det_wt: det_wt(p, centroid),
        slack: tc.map(|t| t < 0.0),
        in_kinematic_workspace: w.region != Region::OutsideKinematic,
        in_static_workspace: w.region == Region::Static,
    }
}

/// Largest `|t_full - t_closed| / max|t|` over the six cables at `centroid`
/// (the agreement of Eq. 24 and Eq. 26-28).
pub fn tension_agreement(p: &Params, centroid: &Vector3<f64>) -> f64 {
    let s = statics(p, centroid);
    let scale = s.tensions_closed_form.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    s.tensions_full.iter().zip(s.tensions_closed_form.iter()).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / scale
}

// ---------------------------------------------------------------------------
// Workspace (Eq. 17-18, 29-31; Figs. 4-6).
// ---------------------------------------------------------------------------

/// A workspace constraint (indices 0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Constraint {
    /// `z > 0` (Sec. 4.1: the end-effector may not cross the base plane).
    AboveBase,
    /// Eq. 17: `l_i >= l_min` for spring `i`.
    SpringMin(usize),
    /// Eq. 18: `l_i <= l_max = lo` for spring `i`.
    SpringMax(usize),
    /// Eq. 29-31: pair `rho_j` in tension (`fh_j - fh_k - fh_l > 0`).
    CableTension(usize),
}

/// Where a point lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Region {
    /// Violates `z > 0` or Eq. 17-18.
    OutsideKinematic,
    /// Satisfies the kinematic constraints but some cable pair would be slack.
    KinematicOnly,
    /// Kinematic constraints and Eq. 29-31 hold.
    Static,
}

/// Classification of one point with the constraints it violates.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkspacePoint {
    pub region: Region,
    pub violated: Vec<Constraint>,
}

/// Kinematic constraints (`z > 0`, Eq. 17, Eq. 18) violated at `centroid`.
pub fn kinematic_violations(p: &Params, centroid: &Vector3<f64>) -> Vec<Constraint> {
    let mut v = Vec::new();
    if centroid.z.is_nan() || centroid.z <= 0.0 {
        v.push(Constraint::AboveBase);
    }
    for (i, l) in spring_lengths(p, centroid).iter().enumerate() {
        if *l < p.l_min {
            v.push(Constraint::SpringMin(i));
        }
        if *l > p.lo {
            v.push(Constraint::SpringMax(i));
        }
    }
    v
}

/// Eq. 29-31 violated at `centroid` (meaningful inside the kinematic workspace).
pub fn static_violations(p: &Params, centroid: &Vector3<f64>) -> Vec<Constraint> {
    static_margins(p, centroid)
        .iter()
        .enumerate()
        .filter(|(_, m)| m.is_nan() || **m <= 0.0)
        .map(|(j, _)| Constraint::CableTension(j))
        .collect()
}

/// Classify a point: outside the kinematic workspace (with the violated
/// kinematic constraints), kinematic only (with the slack pairs), or static.
pub fn classify(p: &Params, centroid: &Vector3<f64>) -> WorkspacePoint {
    let k = kinematic_violations(p, centroid);
    if !k.is_empty() {
        return WorkspacePoint { region: Region::OutsideKinematic, violated: k };
    }
    let s = static_violations(p, centroid);
    let region = if s.is_empty() { Region::Static } else { Region::KinematicOnly };
    WorkspacePoint { region, violated: s }
}

/// Horizontal slice at height `z` \[m\] (Figs. 4-6): a regular `n x n` grid on
/// `[-half_width, half_width]^2` \[m\], returned as `(x, y, region)` row by row.
pub fn slice(p: &Params, z: f64, half_width: f64, n: usize) -> Vec<(f64, f64, Region)> {
    let mut out = Vec::with_capacity(n * n);
    let step = if n > 1 { 2.0 * half_width / (n - 1) as f64 } else { 0.0 };
    for iy in 0..n {
        for ix in 0..n {
            let (x, y) = (-half_width + step * ix as f64, -half_width + step * iy as f64);
            out.push((x, y, classify(p, &Vector3::new(x, y, z)).region));
        }
    }
    out
}

/// Areas [m^2] of the kinematic workspace and of the static workspace in the
/// slice at height `z` \[m\], by midpoint counting on an `n x n` grid over
/// `[-half_width, half_width]^2` (Figs. 4-5).
pub fn slice_areas(p: &Params, z: f64, half_width: f64, n: usize) -> (f64, f64) {
    let cell = (2.0 * half_width / n as f64).powi(2);
    let (mut kin, mut sta) = (0usize, 0usize);
    for iy in 0..n {
        for ix in 0..n {
            let x = -half_width + 2.0 * half_width * (ix as f64 + 0.5) / n as f64;
            let y = -half_width + 2.0 * half_width * (iy as f64 + 0.5) / n as f64;
            match classify(p, &Vector3::new(x, y, z)).region {
                Region::OutsideKinematic => {}
                Region::KinematicOnly => kin += 1,
                Region::Static => {
                    kin += 1;
                    sta += 1;
                }
            }
        }
    }
    (kin as f64 * cell, sta as f64 * cell)
}

/// Top of the kinematic workspace on the `Z` axis, `z = sqrt(lo^2 - 4 lb^2/3)` \[m\]
/// (`NaN` when `lo < 2 lb/sqrt3`: empty workspace).
pub fn z_max_on_axis(p: &Params) -> f64 {
    (p.lo * p.lo - 4.0 * p.lb * p.lb / 3.0).sqrt()
}

/// Jacobian [m/rad] of the three pair-length differences `len_j - len_{j+3}`
/// with respect to a small platform rotation `omega` (rows `(b_k1 - b_k2) x v_j`).
/// Nonsingular iff the paired cables lock the orientation locally (Sec. 2 claim);
/// derived `det = 3/2 lb^4 z^2 / (rho1 rho2 rho3)`.
pub fn pair_difference_rotation_jacobian(p: &Params, centroid: &Vector3<f64>) -> Matrix3<f64> {
    let a = base_nodes(p);
    let b = platform_offsets(p);
    let mut m = Matrix3::zeros();
    for j in 0..3 {
        let (c1, c2) = (CABLES[j], CABLES[j + 3]);
        // d|B + w x b - A| / dw = b x v, with v = (B - A)/|B - A| (A -> B).
        let v1 = (centroid + b[c1.platform] - a[c1.base]).normalize();
        let v2 = (centroid + b[c2.platform] - a[c2.base]).normalize();
        let row = b[c1.platform].cross(&v1) - b[c2.platform].cross(&v2);
        m.set_row(j, &row.transpose());
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanisms::mohr2011::findings::sample_points;
    use approx::assert_relative_eq;

    const P: Params = Params::PAPER;

    #[test]
    fn paper_parameters_validate_and_bad_ones_are_named() {
        assert!(P.validate().is_ok());
        assert_relative_eq!(P.lo, 6.0, epsilon = 0.0);
        let e = Params { lb: -1.0, ..P }.validate().unwrap_err().to_string();
        assert!(e.contains("lb"), "{e}");
        let e = Params { kappa: 0.0, ..P }.validate().unwrap_err().to_string();
        assert!(e.contains("kappa"), "{e}");
        let e = Params { l_min: 6.0, ..P }.validate().unwrap_err().to_string();
        assert!(e.contains("l_min"), "{e}");
        let e = Params { lo: f64::NAN, ..P }.validate().unwrap_err().to_string();
        assert!(e.contains("lo"), "{e}");
    }

    #[test]
    fn nodes_are_two_congruent_triangles_with_b_equal_minus_a() {
        let a = base_nodes(&P);
        assert_relative_eq!(a[0].x, -1.0, epsilon = 1e-15);
        assert_relative_eq!(a[0].y, -SQRT_3 / 3.0, epsilon = 1e-15);
        assert_relative_eq!(a[2].y, 2.0 * SQRT_3 / 3.0, epsilon = 1e-15);
        for i in 0..3 {
            assert_relative_eq!((a[(i + 1) % 3] - a[i]).norm(), 2.0, epsilon = 1e-14);
            assert_relative_eq!(a[i].norm(), 2.0 / SQRT_3, epsilon = 1e-14);
        }
        let c = Vector3::new(0.4, -0.3, 2.5);
        let b = platform_nodes(&P, &c);
        for i in 0..3 {
            assert_relative_eq!((b[i] - c + a[i]).norm(), 0.0, epsilon = 1e-15);
        }
        assert_relative_eq!(((b[0] + b[1] + b[2]) / 3.0 - c).norm(), 0.0, epsilon = 1e-15);
    }

    #[test]
    fn cable_table_matches_eq6_and_eq21() {
        // (base, platform) 1-based: A2B3 A1B3 A1B2 A3B2 A3B1 A2B1, pairs rho1 rho2 rho3 rho1 rho2 rho3.
        let expect = [(2, 3, 1), (1, 3, 2), (1, 2, 3), (3, 2, 1), (3, 1, 2), (2, 1, 3)];
        for (c, e) in CABLES.iter().zip(expect) {
            assert_eq!((c.base + 1, c.platform + 1, c.rho + 1), e);
        }
        // Each pair never touches node i of its own index (rho_i = |p + a_i|).
        for c in CABLES {
            assert!(c.base != c.rho && c.platform != c.rho && c.base != c.platform);
        }
    }

    #[test]
    fn ikp_at_home_pose_and_paired_lengths_equal() {
        let c = Vector3::new(0.0, 0.0, 3.0);
        let rho = ikp(&P, &c);
        // rho^2 = z^2 + |a|^2 = 9 + 4/3.
        for r in rho {
            assert_relative_eq!(r, (9.0f64 + 4.0 / 3.0).sqrt(), epsilon = 1e-14);
        }
        let c = Vector3::new(0.7, -0.4, 2.2);
        let lens = cable_lengths(&P, &c);
        let rho = ikp(&P, &c);
        for j in 0..3 {
            assert_relative_eq!(lens[j], rho[j], max_relative = 1e-14);
            assert_relative_eq!(lens[j + 3], rho[j], max_relative = 1e-14);
        }
        // Hand value: p + a1 = (0.7 - 1, -0.4 - 1/sqrt3, 2.2), |.|^2 = 0.09 + 0.955213 + 4.84.
        let a1 = Vector3::new(-1.0, -1.0 / SQRT_3, 0.0);
        assert_relative_eq!(rho[0], (c + a1).norm(), max_relative = 1e-14);
        assert_relative_eq!(rho[0], 2.425_945_908_029_491_6, max_relative = 1e-12);
    }

    #[test]
    fn dkp_inverts_ikp_and_takes_the_upper_branch() {
        for c in sample_points(&P, 200) {
            let d = dkp(&P, &ikp(&P, &c)).unwrap();
            assert!((d - c).norm() < 1e-11, "{c} -> {d}");
        }
        // A concrete input: rho = (3, 3.5, 4).
        let d = dkp(&P, &[3.0, 3.5, 4.0]).unwrap();
        assert_relative_eq!(d.x, (12.25 - 9.0) / 4.0, epsilon = 1e-14);
        assert_relative_eq!(d.y, (32.0 - 12.25 - 9.0) / (4.0 * SQRT_3), epsilon = 1e-14);
        assert!(d.z > 0.0);
        let back = ikp(&P, &d);
        assert_relative_eq!(back[0], 3.0, epsilon = 1e-12);
        assert_relative_eq!(back[1], 3.5, epsilon = 1e-12);
        assert_relative_eq!(back[2], 4.0, epsilon = 1e-12);
        // No assembly: rho far too different.
        assert!(dkp(&P, &[0.1, 0.1, 10.0]).is_none());
        assert!(dkp(&P, &[-1.0, 3.0, 3.0]).is_none());
    }

    #[test]
    fn eq11_as_printed_is_off_by_a_ix_squared_minus_a_iy_squared() {
        let c = Vector3::new(0.0, 0.0, 3.0);
        // a1: a_x^2 = 1, a_y^2 = 1/3 -> printed 9 + 2/3, true 9 + 4/3.
        assert_relative_eq!(rho_sq_eq11_as_printed(&P, &c, 0), 9.0 + 2.0 / 3.0, epsilon = 1e-13);
        assert_relative_eq!(ikp(&P, &c)[0].powi(2), 9.0 + 4.0 / 3.0, epsilon = 1e-13);
        // a3 has a_x = 0: printed 9 + 8/3 vs true 9 + 4/3.
        assert_relative_eq!(rho_sq_eq11_as_printed(&P, &c, 2), 9.0 + 8.0 / 3.0, epsilon = 1e-13);
    }

    #[test]
    fn spring_law_end_values_and_monotonic_compression() {
        let k = P.kappa / P.lo;
        assert_relative_eq!(spring_force(&P, 0.0), -ZERO_LENGTH_FORCE_FACTOR * k, max_relative = 1e-14);
        assert_relative_eq!(spring_force(&P, 0.0), -10.471_975_511_965_976, max_relative = 1e-14);
        assert_relative_eq!(spring_force(&P, P.lo), -4.0 * k, max_relative = 1e-14);
        assert_relative_eq!(spring_force(&P, P.lo), -6.666_666_666_666_667, max_relative = 1e-14);
        // Halfway: theta = pi/6, f = 2 kappa (pi/3 - pi)/(lo cos(pi/6)).
        let want = 2.0 * P.kappa * (PI / 3.0 - PI) / (P.lo * (PI / 6.0).cos());
        assert_relative_eq!(spring_force(&P, 3.0), want, max_relative = 1e-14);
        assert_relative_eq!(spring_force(&P, 3.0), -8.061_330_507_707_08, max_relative = 1e-12);
        let mut prev = f64::NEG_INFINITY;
        for k in 0..=100 {
            let f = spring_force(&P, P.lo * k as f64 / 100.0);
            assert!(f < 0.0 && f > prev, "compressive and weakening with l");
            prev = f;
        }
        assert!(spring_force(&P, 6.1).is_nan());
    }

    #[test]
    fn eq5_as_printed_equals_derived_and_tends_to_minus_4_kappa_over_lo() {
        for s in [0.01, 0.2, 0.5, 0.9, 0.999] {
            let l = s * P.lo;
            assert_relative_eq!(spring_force_eq5_as_printed(&P, l), spring_force(&P, l), max_relative = 1e-12);
        }
        let near = spring_force_eq5_as_printed(&P, (1.0 - 1e-10) * P.lo);
        assert_relative_eq!(near, spring_force_full_extension_limit(&P), max_relative = 1e-4);
        assert!(spring_force_eq5_as_printed(&P, P.lo).is_nan(), "0/0 as printed");
        // Series branch is continuous with the direct branch.
        let l = (PHI_SERIES_BELOW * 1.0001).cos() * P.lo;
        let l2 = (PHI_SERIES_BELOW * 0.9999).cos() * P.lo;
        assert_relative_eq!(spring_force(&P, l), spring_force(&P, l2), max_relative = 1e-8);
    }

    #[test]
    fn axial_force_is_energy_derivative_and_knee_torque_over_lever_arm() {
        for s in [0.1, 0.4, 0.7, 0.95] {
            let l = s * P.lo;
            let h = 1e-6;
            let de = (spring_energy(&P, l + h) - spring_energy(&P, l - h)) / (2.0 * h);
            assert_relative_eq!(de, spring_force(&P, l), max_relative = 1e-7);
            let tau = torsion_torque(&P, knee_angle(&P, l));
            assert_relative_eq!(axial_force_from_torque(&P, tau, l), spring_force(&P, l), max_relative = 1e-12);
            assert_relative_eq!(torque_from_axial_force(&P, spring_force(&P, l), l), tau, max_relative = 1e-12);
            assert_relative_eq!(length_from_knee_angle(&P, knee_angle(&P, l)), l, max_relative = 1e-14);
        }
        // Rest: straight knee, zero torque, zero energy.
        assert_relative_eq!(knee_angle(&P, P.lo), PI, epsilon = 1e-15);
        assert_relative_eq!(torsion_torque(&P, PI), 0.0, epsilon = 0.0);
        // l = lo/2: knee angle pi/3, tau = -2 pi kappa/3.
        assert_relative_eq!(knee_angle(&P, 3.0), PI / 3.0, epsilon = 1e-15);
        assert_relative_eq!(torsion_torque(&P, PI / 3.0), -20.0 * PI / 3.0, max_relative = 1e-14);
        assert_relative_eq!(knee_offset(&P, 3.0), 1.5 * SQRT_3, max_relative = 1e-14);
    }

    #[test]
    fn spring_chain_geometry() {
        let c = Vector3::new(0.0, 0.0, 3.0);
        let a = base_nodes(&P);
        let mut knees = Vec::new();
        for (i, ai) in a.iter().enumerate() {
            let s = spring_chain(&P, &c, i).unwrap();
            // Link lengths lo/2, knee in the plane normal to e2, axes orthogonal.
            assert_relative_eq!((s.knee - s.a).norm(), P.lo / 2.0, max_relative = 1e-13);
            assert_relative_eq!((s.knee - s.b).norm(), P.lo / 2.0, max_relative = 1e-13);
            assert!((s.knee - s.a).dot(&s.e2).abs() < 1e-13);
            assert!((s.b - s.a).dot(&s.e2).abs() < 1e-13);
            assert!(s.e1.dot(&s.e2).abs() < 1e-15 && s.e1.dot(ai).abs() < 1e-15 && s.e1.z == 0.0);
            let ang = (s.a - s.knee).angle(&(s.b - s.knee));
            assert_relative_eq!(ang, s.knee_angle, epsilon = 1e-12);
            assert_relative_eq!(s.length, (16.0f64 / 3.0 + 9.0).sqrt(), max_relative = 1e-14);
            // Home pose: knee displaced along e1 from the common midpoint p/2.
            assert_relative_eq!((s.knee - c / 2.0 - knee_offset(&P, s.length) * s.e1).norm(), 0.0, epsilon = 1e-13);
            knees.push(s.knee);
        }
        let h = knee_offset(&P, (16.0f64 / 3.0 + 9.0).sqrt());
        assert_relative_eq!((knees[0] - knees[1]).norm(), SQRT_3 * h, max_relative = 1e-13);
        assert!(spring_chain(&P, &Vector3::new(0.0, 0.0, 6.0), 0).is_none(), "l > lo");
    }

    #[test]
    fn closed_form_tensions_agree_with_full_wrench_balance() {
        let pts = sample_points(&P, 300);
        assert_eq!(pts.len(), 300);
        for c in &pts {
            let s = statics(&P, c);
            assert!(tension_agreement(&P, c) < 1e-10, "{c}");
            let r = wrench(&P, c, &s.spring_forces, &s.tensions_full).norm();
            assert!(r < 1e-10, "{c}: residual {r}");
        }
    }

    #[test]
    fn symmetric_pose_tensions_by_hand() {
        // p = (0,0,3): l = sqrt(16/3 + 9), rho = sqrt(4/3 + 9), t = -rho f/(2 l) for all six.
        let c = Vector3::new(0.0, 0.0, 3.0);
        let s = statics(&P, &c);
        let l = (16.0f64 / 3.0 + 9.0).sqrt();
        let rho = (4.0f64 / 3.0 + 9.0).sqrt();
        let th = (l / 6.0).asin();
        let f = 2.0 * 10.0 * (2.0 * th - PI) / (6.0 * th.cos());
        for j in 0..6 {
            assert_relative_eq!(s.tensions_closed_form[j], -rho * f / (2.0 * l), max_relative = 1e-13);
            assert_relative_eq!(s.tensions_full[j], -rho * f / (2.0 * l), max_relative = 1e-12);
            assert_relative_eq!(s.tensions_full[j], 3.239_498_837_387_423_6, max_relative = 1e-10);
        }
        assert!(s.in_static_workspace && s.slack.iter().all(|b| !b));
    }

    #[test]
    fn det_wt_eq25_holds() {
        for c in sample_points(&P, 200) {
            assert_relative_eq!(det_wt_eq25(&P, &c), det_wt(&P, &c), max_relative = 1e-9);
            assert_relative_eq!(det_wt_derived(&P, &c), det_wt(&P, &c), max_relative = 1e-9);
        }
        let c = Vector3::new(0.0, 0.0, 3.0);
        // -3 sqrt3/4 * 27 * 64 / (31/3)^3
        assert_relative_eq!(
            det_wt(&P, &c),
            -3.0 * SQRT_3 / 4.0 * 27.0 * 64.0 / (31.0f64 / 3.0).powi(3),
            max_relative = 1e-10
        );
        assert!(det_wt(&P, &Vector3::new(0.3, 0.1, 0.0)).abs() < 1e-12);
    }

    #[test]
    fn printed_wt_equals_six_cable_wt() {
        for c in sample_points(&P, 50) {
            assert!((wt(&P, &c) - wt_as_printed(&P, &c)).abs().max() < 1e-14);
        }
    }

    #[test]
    fn slack_pair_near_base_vertex_image() {
        // Near 2 a_1 spring 1 is short, its force density huge: pair rho1 slack? Eq. 29 needs
        // fh1 - fh2 - fh3 > 0, i.e. g2 + g3 > g1 with g = -fh: fails for large g1.
        let a = base_nodes(&P);
        let c = 2.0 * a[0] + Vector3::new(0.0, 0.0, 0.5);
        let w = classify(&P, &c);
        assert_eq!(w.region, Region::KinematicOnly);
        assert_eq!(w.violated, vec![Constraint::CableTension(0)]);
        let s = statics(&P, &c);
        assert_eq!(s.slack, [true, false, false, true, false, false]);
        assert!(s.tensions_full[0] < 0.0 && s.tensions_full[3] < 0.0);
        assert!(!s.in_static_workspace && s.in_kinematic_workspace);
    }

    #[test]
    fn classification_outside_names_the_constraint() {
        let w = classify(&P, &Vector3::new(0.0, 0.0, -1.0));
        assert_eq!(w.region, Region::OutsideKinematic);
        assert_eq!(w.violated, vec![Constraint::AboveBase]);
        let w = classify(&P, &Vector3::new(0.0, 0.0, 6.0));
        assert_eq!(w.violated, vec![Constraint::SpringMax(0), Constraint::SpringMax(1), Constraint::SpringMax(2)]);
        let q = Params { l_min: 1.0, ..P };
        let a = base_nodes(&P);
        let w = classify(&q, &(2.0 * a[1] + Vector3::new(0.0, 0.0, 0.5)));
        assert_eq!(w.violated, vec![Constraint::SpringMin(1)]);
        // Z axis is static up to z_max = sqrt(36 - 16/3).
        let zmax = z_max_on_axis(&P);
        assert_relative_eq!(zmax, (36.0f64 - 16.0 / 3.0).sqrt(), max_relative = 1e-15);
        assert_eq!(classify(&P, &Vector3::new(0.0, 0.0, zmax - 1e-9)).region, Region::Static);
        assert_eq!(classify(&P, &Vector3::new(0.0, 0.0, zmax + 1e-9)).region, Region::OutsideKinematic);
    }

    #[test]
    fn static_workspace_independent_of_kappa() {
        let q = Params { kappa: 0.01, ..P };
        let s1 = slice(&P, 2.0, 6.0, 41);
        let s2 = slice(&q, 2.0, 6.0, 41);
        assert_eq!(s1.len(), 41 * 41);
        assert_eq!(s1, s2);
        let nstat = s1.iter().filter(|t| t.2 == Region::Static).count();
        let nkin = s1.iter().filter(|t| t.2 == Region::KinematicOnly).count();
        assert!(nstat > 100 && nkin > 10, "static {nstat} kinematic-only {nkin}");
    }

    #[test]
    fn workspace_has_threefold_symmetry_and_static_is_inside_kinematic() {
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 2.0 * PI / 3.0);
        let mut n_static = 0;
        for (x, y, reg) in slice(&P, 2.5, 6.0, 31) {
            let c = Vector3::new(x, y, 2.5);
            let rc = r * c;
            assert_eq!(classify(&P, &rc).region, reg, "({x}, {y})");
            if reg == Region::Static {
                n_static += 1;
                assert!(kinematic_violations(&P, &c).is_empty());
            }
        }
        assert!(n_static > 50);
    }

    #[test]
    fn slice_areas_kinematic_matches_disc_intersection_at_top() {
        // Near z_max the kinematic slice is a small curvilinear triangle around the axis;
        // at z = 0+ it is the intersection of three discs of radius lo about 2 a_i.
        let (k_low, s_low) = slice_areas(&P, 1e-6, 6.0, 300);
        let (k_mid, s_mid) = slice_areas(&P, 3.0, 6.0, 300);
        assert!(s_low < k_low && s_mid <= k_mid);
        // The intersection of three discs (radius 6, centres on a circle of radius 4/sqrt3)
        // lies inside one disc of area 36 pi and contains the disc of radius 6 - 4/sqrt3.
        let inner = PI * (6.0 - 4.0 / SQRT_3).powi(2);
        assert!(k_low > inner && k_low < 36.0 * PI, "{k_low}");
        assert!(k_mid < k_low);
        println!("slice areas: z=0+: kin {k_low:.3} static {s_low:.3}; z=3: kin {k_mid:.3} static {s_mid:.3}");
    }

    #[test]
    fn spring_chain_matches_eq3_at_random_points() {
        for c in sample_points(&P, 100) {
            let l = spring_lengths(&P, &c);
            for (i, li) in l.iter().enumerate() {
                let s = spring_chain(&P, &c, i).unwrap();
                assert_relative_eq!(s.knee_angle, 2.0 * (li / P.lo).asin(), epsilon = 1e-12);
                let ang = (s.a - s.knee).angle(&(s.b - s.knee));
                assert_relative_eq!(ang, s.knee_angle, epsilon = 1e-6);
                assert_relative_eq!(s.force, s.torque / knee_offset(&P, *li), max_relative = 1e-12);
                assert!(s.e1.dot(&s.e2).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn paired_cables_lock_orientation_locally() {
        let c = Vector3::new(0.5, 0.2, 2.5);
        let j = pair_difference_rotation_jacobian(&P, &c);
        // Derived: det = 3/2 lb^4 z^2 / (rho1 rho2 rho3) (rows are -(a_k - a_l) x (p + a_j)/rho_j).
        let r = ikp(&P, &c);
        assert_relative_eq!(j.determinant(), 1.5 * 16.0 * 6.25 / (r[0] * r[1] * r[2]), max_relative = 1e-12);
        for q in sample_points(&P, 100) {
            let r = ikp(&P, &q);
            let want = 1.5 * P.lb.powi(4) * q.z * q.z / (r[0] * r[1] * r[2]);
            assert_relative_eq!(pair_difference_rotation_jacobian(&P, &q).determinant(), want, max_relative = 1e-9);
        }
        // Finite-difference check of the Jacobian.
        let h = 1e-6;
        for k in 0..3 {
            let mut w = Vector3::zeros();
            w[k] = h;
            let lp = cable_lengths_posed(&P, &c, &Rotation3::new(w));
            let lm = cable_lengths_posed(&P, &c, &Rotation3::new(-w));
            for r in 0..3 {
                let d = ((lp[r] - lp[r + 3]) - (lm[r] - lm[r + 3])) / (2.0 * h);
                assert_relative_eq!(d, j[(r, k)], epsilon = 1e-7);
            }
        }
    }
}
