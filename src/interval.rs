//! Interval arithmetic with outward rounding, for proofs (`certify`): every operation's result
//! encloses the exact result of the operation on every pair of reals in its operands.
//!
//! Each bound is computed in round-to-nearest (IEEE 754: the correctly rounded result, within
//! half an ulp of the exact one for +, -, *, / and sqrt) and then moved one ulp outward
//! (`f64::next_down` / `next_up`), which contains the exact result whatever the rounding did.
//! The enclosures are one ulp wider than directed rounding's would be; no elementary function
//! beyond sqrt is offered, so none needs an enclosure of its own. A NaN anywhere gives the
//! whole line, never a false containment. Moore, Kearfott & Cloud, Introduction to Interval
//! Analysis (SIAM 2009), chapters 2 and 4.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// The closed interval [lo, hi] of reals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

/// The next float below `x` (x itself where it is -inf).
fn down(x: f64) -> f64 {
    if x.is_nan() {
        f64::NEG_INFINITY
    } else {
        x.next_down()
    }
}

/// The next float above `x`.
fn up(x: f64) -> f64 {
    if x.is_nan() {
        f64::INFINITY
    } else {
        x.next_up()
    }
}

impl Interval {
    /// The whole line.
    pub const ENTIRE: Interval = Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY };
    /// Zero, exactly.
    pub const ZERO: Interval = Interval { lo: 0.0, hi: 0.0 };

    /// The exact point `x` (a float is a real: no rounding).
    pub fn point(x: f64) -> Interval {
        if x.is_nan() {
            Interval::ENTIRE
        } else {
            Interval { lo: x, hi: x }
        }
    }

    /// [lo, hi]; the whole line where a bound is NaN or lo > hi.
    pub fn new(lo: f64, hi: f64) -> Interval {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            Interval::ENTIRE
        } else {
            Interval { lo, hi }
        }
    }

    /// [x - r, x + r], rounded outward (r >= 0).
    pub fn around(x: f64, r: f64) -> Interval {
        Interval::new(down(x - r), up(x + r))
    }

    /// The midpoint (a float inside the interval).
    pub fn mid(self) -> f64 {
        let m = 0.5 * self.lo + 0.5 * self.hi;
        m.clamp(self.lo, self.hi)
    }

    /// An upper bound of the radius.
    pub fn rad(self) -> f64 {
        let m = self.mid();
        up((self.hi - m).max(m - self.lo))
    }

    /// The largest |x| over the interval.
    pub fn mag(self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    /// The smallest |x| over the interval.
    pub fn mig(self) -> f64 {
        if self.contains(0.0) {
            0.0
        } else {
            self.lo.abs().min(self.hi.abs())
        }
    }

    /// Whether `x` lies in the interval.
    pub fn contains(self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// Whether the interval lies in the interior of `outer`.
    pub fn inside(self, outer: Interval) -> bool {
        outer.lo < self.lo && self.hi < outer.hi
    }

    /// The smallest interval holding both.
    pub fn hull(self, other: Interval) -> Interval {
        Interval { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi) }
    }

    /// x^2 (tighter than x * x where the interval holds 0).
    pub fn square(self) -> Interval {
        let (a, b) = (self.mig(), self.mag());
        Interval::new(down(a * a).max(0.0), up(b * b))
    }

    /// sqrt(x) over the interval's non-negative part (a length: the negative part is outside
    /// the function's domain and is left out).
    pub fn sqrt(self) -> Interval {
        if self.hi < 0.0 {
            return Interval::ENTIRE;
        }
        Interval::new(down(self.lo.max(0.0).sqrt()).max(0.0), up(self.hi.sqrt()))
    }

    /// max(x, 0).
    pub fn positive_part(self) -> Interval {
        Interval { lo: self.lo.max(0.0), hi: self.hi.max(0.0) }
    }
}

impl Add for Interval {
    type Output = Interval;
    fn add(self, o: Interval) -> Interval {
        // Adding an exact zero is exact: the sparse sums of the Hessian keep their zeros.
        if o == Interval::ZERO {
            return self;
        }
        if self == Interval::ZERO {
            return o;
        }
        Interval::new(down(self.lo + o.lo), up(self.hi + o.hi))
    }
}

impl Sub for Interval {
    type Output = Interval;
    fn sub(self, o: Interval) -> Interval {
        if o == Interval::ZERO {
            return self;
        }
        Interval::new(down(self.lo - o.hi), up(self.hi - o.lo))
    }
}

impl Neg for Interval {
    type Output = Interval;
    fn neg(self) -> Interval {
        Interval { lo: -self.hi, hi: -self.lo }
    }
}

impl Mul for Interval {
    type Output = Interval;
    fn mul(self, o: Interval) -> Interval {
        if (self == Interval::ZERO && o.lo.is_finite() && o.hi.is_finite())
            || (o == Interval::ZERO && self.lo.is_finite() && self.hi.is_finite())
        {
            return Interval::ZERO;
        }
        let p = [self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi];
        if p.iter().any(|x| x.is_nan()) {
            return Interval::ENTIRE;
        }
        let (lo, hi) = p.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
        Interval::new(down(lo), up(hi))
    }
}

impl Div for Interval {
    type Output = Interval;
    /// The whole line where the divisor holds 0.
    fn div(self, o: Interval) -> Interval {
        if o.contains(0.0) {
            return Interval::ENTIRE;
        }
        let q = [self.lo / o.lo, self.lo / o.hi, self.hi / o.lo, self.hi / o.hi];
        if q.iter().any(|x| x.is_nan()) {
            return Interval::ENTIRE;
        }
        let (lo, hi) = q.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
        Interval::new(down(lo), up(hi))
    }
}

impl Mul<f64> for Interval {
    type Output = Interval;
    fn mul(self, x: f64) -> Interval {
        self * Interval::point(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 0.1 + 0.2 is not 0.3 in floats; its enclosure holds the exact sum of the two floats,
    /// 0.3000000000000000166533453693773481063544750213623046875, and is at most two ulps
    /// wide.
    #[test]
    fn a_sum_encloses_the_exact_sum_of_its_floats() {
        let s = Interval::point(0.1) + Interval::point(0.2);
        let rounded = 0.1 + 0.2;
        assert!(s.lo < rounded && rounded < s.hi);
        assert!(s.lo.next_up().next_up() >= s.hi.next_down(), "{s:?} wider than two ulps");
        // The exact sum lies between 0.3 (below it) and the rounded sum (above it).
        assert!(s.contains(0.3) && s.contains(rounded));
    }

    /// (1 + 2^-52) * (1 - 2^-53) = 1 + 2^-53 - 2^-105 is no float: it lies strictly between
    /// 1 and 1 + 2^-52, and both are in the product's enclosure.
    #[test]
    fn a_product_encloses_what_no_float_is() {
        let a = Interval::point(1.0 + f64::EPSILON);
        let b = Interval::point(1.0 - f64::EPSILON / 2.0);
        let p = a * b;
        assert!(p.contains(1.0) && p.contains(1.0 + f64::EPSILON), "{p:?}");
    }

    /// Signs: [-1, 2] * [-3, 4] = [-6, 8]; [1, 2] / [-1, 1] is the whole line; sqrt of
    /// [-1, 4] is [0, 2] (its domain); the square of [-2, 1] is [0, 4].
    #[test]
    fn signs_division_by_zero_and_the_square_root_are_enclosed() {
        let p = Interval::new(-1.0, 2.0) * Interval::new(-3.0, 4.0);
        assert!(p.contains(-6.0) && p.contains(8.0) && p.lo > -6.0 - 1e-14 && p.hi < 8.0 + 1e-14);
        assert_eq!(Interval::new(1.0, 2.0) / Interval::new(-1.0, 1.0), Interval::ENTIRE);
        let r = Interval::new(-1.0, 4.0).sqrt();
        assert!(r.lo == 0.0 && r.contains(2.0) && r.hi < 2.0 + 1e-15);
        let q = Interval::new(-2.0, 1.0).square();
        assert!(q.lo == 0.0 && q.contains(4.0));
        assert!(Interval::new(0.0, f64::NAN) == Interval::ENTIRE);
    }

    /// A sum of 10^6 thirds stays an enclosure of the exact 333333.33..., where the float
    /// sum has drifted from it.
    #[test]
    fn rounding_errors_stay_inside_a_long_sum() {
        let third = Interval::point(1.0) / Interval::point(3.0);
        let mut s = Interval::ZERO;
        let mut f = 0.0;
        for _ in 0..1_000_000 {
            s = s + third;
            f += 1.0 / 3.0;
        }
        let exact = 1e6 / 3.0;
        assert!(s.contains(exact), "{s:?}");
        assert!(s.rad() < 1e-4, "{s:?}");
        assert!((f - exact).abs() > 0.0, "the float sum drifted: {f}");
    }
}
