//! Friction where a clustered cable turns at a node: the capstan (Euler-Eytelwein) law.
//!
//! What is modelled: a massless cable whose unstretched material is shared among its segments.
//! Segment i holds s_i of it (the s_i add up to the cable's rest length) and carries the
//! tension EA (l_i - s_i) / s_i, tension only, with EA = k L0 from the cable's stiffness k and
//! rest length L0 as drawn (a material constant: a winch reels at the cable's end b, so the
//! last segment's share changes). At an inner node j with coefficient mu_j, theta_j the angle
//! the cable turns through there (between its two segments' directions: a point contact, the
//! node has no radius), the node holds (sticks) while the tensions on either side stay within
//! e^(mu_j theta_j) of each other; past that the cable slips toward the tenser side, material
//! moving into it, until the ratio is the bound. The slip is instantaneous (no mass, no rate
//! dependence): before every step each node past its bound is brought back to it, node after
//! node until none is (Gauss-Seidel sweeps; each node's balance solved by bisection to
//! round-off). A node at its bound is reported as slipping: pulled further, it moves.
//!
//! Without friction (mu = 0, or a straight pass where theta = 0) the balance is equal
//! tensions, the clustered cable of `structure/member.rs`. A cable with friction has no
//! energy of its own (the path matters), so the relaxation, the modes and the sensitivities
//! refuse it.

use super::data::Data;
use super::model::Model;
use crate::structure::{ElasticLaw, Member};

/// Sweeps over a cable's inner nodes per step, at most.
const MAX_SWEEPS: usize = 100;

/// A node is at its friction bound (slipping) when the tension ratio is within this fraction
/// of e^(mu theta).
const AT_BOUND_FRACTION: f64 = 1e-9;

/// The least share of the rest length a segment keeps when a winch reels in at it.
const MIN_SHARE_FRACTION: f64 = 1e-9;

/// Bisection steps of one node's balance (each halves the interval of the moved material).
const BALANCE_STEPS: usize = 200;

/// Each segment's share of the unstretched length as drawn: proportional to its drawn length
/// (one strain, so one tension: the drawn state of a frictionless cable) \[m\].
pub(super) fn initial_material(member: &Member, position: impl Fn(usize) -> [f64; 3]) -> Vec<f64> {
    let Some(rest) = member.rest_length_m().filter(|_| member.has_friction()) else { return Vec::new() };
    let lengths: Vec<f64> =
        member.segments().map(|(a, b)| crate::structure::distance(position(a), position(b))).collect();
    let total: f64 = lengths.iter().sum();
    lengths.iter().map(|l| rest * l / total).collect()
}

/// EA of a cable \[N\]: its stiffness times its rest length, as drawn.
fn axial_stiffness_n(member: &Member) -> f64 {
    member.stiffness_n_per_m().unwrap_or(0.0) * member.rest_length_m().unwrap_or(0.0)
}

/// The segment's tension of the linear law, negative when it is shorter than its share [N].
fn linear_tension(ea: f64, length: f64, share: f64) -> f64 {
    ea * (length - share) / share
}

impl Data {
    /// Each segment's law of member `i` if it is a cable with friction: stiffness EA / s_k and
    /// rest length s_k (tension EA (l_k - s_k) / s_k, tension only); None for any other member.
    pub(super) fn segment_laws(&self, m: &Model, i: usize) -> Option<Vec<ElasticLaw>> {
        let shares = self.material.get(i).filter(|s| !s.is_empty())?;
        let ea = axial_stiffness_n(&m.structure.members[i]);
        let law = |&s: &f64| ElasticLaw { stiffness_n_per_m: ea / s, rest_length_m: s, tension_only: true };
        Some(shares.iter().map(law).collect())
    }

    /// A winch's new rest length `rest_m` for cable `i` with friction: the change reeled at its
    /// end b, in its last segment's share.
    pub(super) fn reel(&mut self, i: usize, rest_m: f64) {
        if let Some(shares) = self.material.get_mut(i).filter(|s| !s.is_empty()) {
            let others: f64 = shares[..shares.len() - 1].iter().sum();
            let last = shares.len() - 1;
            // A winch cannot reel in more than the last segment holds: long before that its
            // tension makes the node slip and material come through (the next step's slide).
            shares[last] = (rest_m - others).max(MIN_SHARE_FRACTION * rest_m);
        }
    }

    /// Brings every node of every cable with friction within its bound (module docs) and
    /// records which nodes are at it.
    pub(super) fn slide_cables(&mut self, m: &Model) {
        for i in 0..self.material.len() {
            if self.material[i].is_empty() {
                continue;
            }
            let member = &m.structure.members[i];
            let geometry = self.cable_geometry(m, member);
            let ea = axial_stiffness_n(member);
            let shares = &mut self.material[i];
            for _ in 0..MAX_SWEEPS {
                let mut moved = false;
                for (j, &(mu, theta)) in geometry.turns.iter().enumerate() {
                    moved |= hold_or_slip(ea, &geometry.lengths, shares, j, (mu * theta).exp());
                }
                if !moved {
                    break;
                }
            }
            self.at_bound[i] = geometry
                .turns
                .iter()
                .enumerate()
                .map(|(j, &(mu, theta))| {
                    let t = |k: usize| linear_tension(ea, geometry.lengths[k], shares[k]);
                    let (before, after) = (t(j), t(j + 1));
                    let bound = (mu * theta).exp();
                    let ratio = if before.abs() >= after.abs() { before / after } else { after / before };
                    before > 0.0 && after > 0.0 && (ratio - bound).abs() <= AT_BOUND_FRACTION * bound
                })
                .collect();
        }
    }

    /// A cable's segment lengths now and, at each inner node, its friction coefficient and
    /// the angle the cable turns through there.
    fn cable_geometry(&self, m: &Model, member: &Member) -> CableGeometry {
        let p: Vec<[f64; 3]> = member.path.iter().map(|&n| self.node_position(m, n)).collect();
        let d: Vec<[f64; 3]> = p.windows(2).map(|w| std::array::from_fn(|k| w[1][k] - w[0][k])).collect();
        let lengths: Vec<f64> = d.iter().map(|v| crate::structure::norm(*v)).collect();
        let turns = (0..d.len() - 1)
            .map(|j| {
                let cos = (0..3).map(|k| d[j][k] * d[j + 1][k]).sum::<f64>() / (lengths[j] * lengths[j + 1]);
                (member.friction.get(j).copied().unwrap_or(0.0), cos.clamp(-1.0, 1.0).acos())
            })
            .collect();
        CableGeometry { lengths, turns }
    }
}

/// Segment lengths [m] and each inner node's (mu, theta [rad]).
struct CableGeometry {
    lengths: Vec<f64>,
    turns: Vec<(f64, f64)>,
}

/// Node `j` (between segments j and j + 1) holds if the tensions on its two sides are within
/// `bound` of each other; else material moves into the tenser segment until their ratio is
/// `bound`. Whether it moved.
fn hold_or_slip(ea: f64, lengths: &[f64], shares: &mut [f64], j: usize, bound: f64) -> bool {
    let t = |k: usize, s: f64| linear_tension(ea, lengths[k], s);
    let (before, after) = (t(j, shares[j]), t(j + 1, shares[j + 1]));
    let (hi, lo) = if after > bound * before.max(0.0) && after > 0.0 {
        (j + 1, j)
    } else if before > bound * after.max(0.0) && before > 0.0 {
        (j, j + 1)
    } else {
        return false;
    };
    // Move x of lo's share into hi: T_hi falls and T_lo rises with x; the root of
    // T_hi - bound T_lo lies in (0, s_lo).
    let total = shares[hi] + shares[lo];
    let gap = |x: f64| t(hi, shares[hi] + x) - bound * t(lo, shares[lo] - x);
    let (mut a, mut b) = (0.0, shares[lo]);
    for _ in 0..BALANCE_STEPS {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            break;
        }
        if gap(mid) > 0.0 {
            a = mid;
        } else {
            b = mid;
        }
    }
    if a == 0.0 {
        return false;
    }
    shares[hi] += a;
    shares[lo] = total - shares[hi];
    true
}

#[cfg(test)]
mod tests {
    use super::{hold_or_slip, linear_tension};

    /// Two segments 1 m long sharing 1.9 m of material (EA = 1000 N): at equal shares both
    /// carry 52.6 N and the node holds at any bound; with 0.9 m left in the second it is
    /// tenser (111 N against none) and slips until it holds e^(0.3 pi / 2) times the first,
    /// within 1e-12, the material kept (1.9 m to the bit of its sum); a bound of 1 makes the
    /// tensions equal (no friction).
    #[test]
    fn a_node_holds_within_its_bound_and_slips_to_it() {
        let (ea, lengths) = (1000.0, [1.0, 1.0]);
        let mut equal = [0.95, 0.95];
        assert!(!hold_or_slip(ea, &lengths, &mut equal, 0, 1.0001));
        for bound in [(0.3 * std::f64::consts::FRAC_PI_2).exp(), 1.0] {
            let mut shares = [1.0, 0.9];
            assert!(hold_or_slip(ea, &lengths, &mut shares, 0, bound));
            let t = |k: usize| linear_tension(ea, lengths[k], shares[k]);
            assert!((t(1) / t(0) - bound).abs() <= 1e-12 * bound, "{} / {}", t(1), t(0));
            assert!((shares[0] + shares[1] - 1.9).abs() <= 1e-15);
        }
    }
}
