//! Second-order jets over intervals: a value with its gradient and Hessian in up to
//! [`MAX_VARIABLES`] variables, each an enclosure over a box when the variables' values are the
//! box's intervals (forward differentiation in interval arithmetic: every derivative formula
//! evaluated over the box encloses that derivative everywhere in it). Enough for a node's
//! position as a function of its body's coordinates (`enclosure.rs`).

use crate::interval::Interval;

/// A free body's coordinates at most: three translations and three rotations.
pub const MAX_VARIABLES: usize = 6;

/// f, df/dx_i and d2f/dx_i dx_j over the first `n` variables.
#[derive(Clone, Copy, Debug)]
pub struct Jet {
    pub n: usize,
    pub v: Interval,
    pub g: [Interval; MAX_VARIABLES],
    pub h: [[Interval; MAX_VARIABLES]; MAX_VARIABLES],
}

impl Jet {
    /// A constant.
    pub fn constant(n: usize, x: Interval) -> Jet {
        Jet { n, v: x, g: [Interval::ZERO; MAX_VARIABLES], h: [[Interval::ZERO; MAX_VARIABLES]; MAX_VARIABLES] }
    }

    /// Variable `i` with value `x`.
    pub fn variable(n: usize, i: usize, x: Interval) -> Jet {
        let mut j = Jet::constant(n, x);
        j.g[i] = Interval::point(1.0);
        j
    }

    pub fn add(&self, o: &Jet) -> Jet {
        let mut r = *self;
        r.v = self.v + o.v;
        for i in 0..self.n {
            r.g[i] = self.g[i] + o.g[i];
            for j in 0..self.n {
                r.h[i][j] = self.h[i][j] + o.h[i][j];
            }
        }
        r
    }

    pub fn sub(&self, o: &Jet) -> Jet {
        self.add(&o.scale(Interval::point(-1.0)))
    }

    /// c f for a constant c.
    pub fn scale(&self, c: Interval) -> Jet {
        let mut r = *self;
        r.v = self.v * c;
        for i in 0..self.n {
            r.g[i] = self.g[i] * c;
            for j in 0..self.n {
                r.h[i][j] = self.h[i][j] * c;
            }
        }
        r
    }

    /// f g: (fg)'' = f'' g + f g'' + f' g'^T + g' f'^T.
    pub fn mul(&self, o: &Jet) -> Jet {
        let mut r = *self;
        r.v = self.v * o.v;
        for i in 0..self.n {
            r.g[i] = self.g[i] * o.v + self.v * o.g[i];
            for j in 0..self.n {
                r.h[i][j] = self.h[i][j] * o.v + self.v * o.h[i][j] + self.g[i] * o.g[j] + o.g[i] * self.g[j];
            }
        }
        r
    }

    /// 1 / f: (1/f)' = -f' / f^2, (1/f)'' = 2 f' f'^T / f^3 - f'' / f^2.
    pub fn recip(&self) -> Jet {
        let one = Interval::point(1.0);
        let inv = one / self.v;
        let inv2 = inv * inv;
        let inv3 = inv2 * inv;
        let mut r = *self;
        r.v = inv;
        for i in 0..self.n {
            r.g[i] = -(self.g[i] * inv2);
            for j in 0..self.n {
                r.h[i][j] = self.g[i] * self.g[j] * inv3 * 2.0 - self.h[i][j] * inv2;
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f(x, y) = x y / (1 + x^2) at (0.3, -0.7): value, gradient and Hessian enclose the
    /// closed forms within 1e-15.
    #[test]
    fn a_rational_functions_derivatives_are_enclosed() {
        let (x0, y0) = (0.3_f64, -0.7_f64);
        let x = Jet::variable(2, 0, Interval::point(x0));
        let y = Jet::variable(2, 1, Interval::point(y0));
        let one = Jet::constant(2, Interval::point(1.0));
        let f = x.mul(&y).mul(&one.add(&x.mul(&x)).recip());
        let d = 1.0 + x0 * x0;
        let fx = y0 * (1.0 - x0 * x0) / (d * d);
        let fxx = y0 * (2.0 * x0 * x0 * x0 - 6.0 * x0) / (d * d * d);
        let fxy = (1.0 - x0 * x0) / (d * d);
        for (jet, exact) in [(f.v, x0 * y0 / d), (f.g[0], fx), (f.g[1], x0 / d), (f.h[0][0], fxx), (f.h[0][1], fxy)] {
            assert!((jet.mid() - exact).abs() <= 1e-15 && jet.rad() <= 1e-14, "{jet:?} against {exact}");
            assert!(jet.lo <= exact + 1e-16 && exact - 1e-16 <= jet.hi, "{jet:?} against {exact}");
        }
        assert_eq!(f.h[1][1], Interval::ZERO);
    }
}
