//! [`wrap_angle`], shared by the papers' analytic models, the mechanisms and the observers
//! (plain `f64`, nothing of the simulation).

/// Wraps an angle (or an angle difference) to `(-pi, pi]`.
pub fn wrap_angle(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut r = a.rem_euclid(two_pi);
    if r > std::f64::consts::PI {
        r -= two_pi;
    }
    r
}
