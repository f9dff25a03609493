//! Second-order forms along a ray: `c0 + c1·ε + c2·ε² ± e`, a Taylor
//! model of degree 2 in the ray parameter's one noise symbol ε in
//! [-1, 1] (`t = m + r·ε`, as [`Affine::along`] takes it).
//!
//! A first-order form along a ray leaves each product's quadratic rest in
//! its error, so a polynomial written expanded (`(x−1)¹⁰` as ten powers
//! of x times binomial coefficients) sums ten such rests that its terms
//! would have cancelled: an error of about 3,000·w² over a piece of width
//! w (docs/performance.md). Here the ε² terms stay coefficients, and they
//! cancel as the expansion's terms do; what goes to the error is of third
//! order in w.
//!
//! # Guarantee
//! As for [`Affine`]: a form built from a ray piece by these ops encloses
//! the exact op's value at every parameter of the piece. Products
//! truncate their terms of degree 3 and 4 with the Chebyshev identities
//! `ε³ = ¾ε + ¼T₃(ε)` and `ε⁴ = ε² − ⅛ + ⅛T₄(ε)`, `|Tₙ(ε)| ≤ 1` on
//! [-1, 1]: the ε and ε² parts join the coefficients and the `T` parts'
//! magnitudes the error. Every coefficient's rounding goes into the error
//! (summed by [`ErrSum`], bounded once); a part that overflowed makes the
//! form [`Quadratic::UNBOUNDED`].

use super::affine::{Affine, ErrSum, meet, mul_up};
use super::form::Form;
use super::{Interval, up, up_sum};

/// `c[0] + c[1]·ε + c[2]·ε² ± e` for ε in [-1, 1] (see the module doc).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Quadratic {
    /// The coefficients of 1, ε and ε².
    pub c: [f64; 3],
    /// The accumulated error, `≥ 0` (+inf: unbounded).
    pub e: f64,
}

/// A lower bound of the real sum or difference that rounded to `v`.
#[inline]
fn down_sum(v: f64) -> f64 {
    -up_sum(-v)
}

impl Quadratic {
    /// The form that encloses every value.
    pub const UNBOUNDED: Quadratic = Quadratic {
        c: [0.0; 3],
        e: f64::INFINITY,
    };

    /// The first-order form `a` along the same ray, with no ε² term.
    pub fn from_affine(a: Affine<1>) -> Quadratic {
        Quadratic {
            c: [a.c, a.k[0], 0.0],
            e: a.e,
        }
        .checked()
    }

    /// Coordinate `o + d·t` of a ray over the parameter range `t` (see
    /// [`Affine::along`], whose noise symbol this shares).
    pub fn along(o: Interval, d: Interval, t: Interval) -> Quadratic {
        Quadratic::from_affine(Affine::<1>::along(o, d, t))
    }

    /// UNBOUNDED where a part overflowed or went NaN, else the form.
    fn checked(self) -> Quadratic {
        if self.is_bounded() {
            self
        } else {
            Quadratic::UNBOUNDED
        }
    }

    /// An upper bound of `|c0| + |c1| + |c2|`, the largest magnitude of
    /// the polynomial part over [-1, 1].
    fn magnitude(&self) -> f64 {
        up_sum(self.c[0].abs() + self.spread())
    }

    /// The coefficients of the exact product `p0 + … + p4·ε⁴` folded to
    /// degree 2 (see the module doc) into `err`, whose error terms they
    /// take: `p3` and `p4` are given as their rounded values.
    fn fold(p: [f64; 3], p3: f64, p4: f64, err: &mut ErrSum) -> [f64; 3] {
        // p4 reaches two coefficients: its rounding is counted twice.
        err.add(super::affine::rounding(p4));
        let p4_8 = err.rounded(0.125 * p4);
        let c0 = err.rounded(p[0] - p4_8);
        let p3_34 = err.rounded(0.75 * p3);
        let c1 = err.rounded(p[1] + p3_34);
        let c2 = err.rounded(p[2] + p4);
        // The T₃ and T₄ parts: |p3|/4 and |p4|/8 rounded up.
        err.add(mul_up(p3.abs(), 0.25));
        err.add(mul_up(p4.abs(), 0.125));
        [c0, c1, c2]
    }

    /// `selfⁿ`, `n ≥ 1`, by binary powering (squares and products), the
    /// squares `self^(2^j)` taken from `squares[j - 1]` where it holds
    /// them and pushed there where it does not (the same squares, so the
    /// same bits, either way).
    fn powered(&self, n: u32, squares: &mut Vec<Quadratic>) -> Quadratic {
        let (mut acc, mut k, mut j) = (None::<Quadratic>, n, 0);
        loop {
            let base = if j == 0 {
                *self
            } else {
                if squares.len() < j {
                    let below = squares.last().copied().unwrap_or(*self);
                    squares.push(below.square());
                }
                squares[j - 1]
            };
            if k & 1 == 1 {
                acc = Some(acc.map_or(base, |a| a.mul(&base)));
            }
            k >>= 1;
            if k == 0 {
                return acc.unwrap_or(base);
            }
            j += 1;
        }
    }

    /// Outward bounds of `c0 + c1·ε + c2·ε²` over [-1, 1]: the ends
    /// `c0 + c2 ± c1`, and the vertex value `c0 − c1²/(4·c2)` where the
    /// vertex `−c1/(2·c2)` lies in [-1, 1] (`|c1| ≤ 2|c2|`, a comparison
    /// with no rounding).
    fn poly_range(&self) -> (f64, f64) {
        let [c0, c1, c2] = self.c;
        let b = c1.abs();
        let s = c0 + c2;
        let (lo, hi) = (-up_sum(b - down_sum(s)), up_sum(up_sum(s) + b));
        if b > 2.0 * c2.abs() || c2 == 0.0 {
            return (lo, hi);
        }
        // c1²/(4·|c2|), rounded up.
        let q = mul_up(up(mul_up(c1, c1) / c2.abs()), 0.25);
        if c2 > 0.0 {
            (-up_sum(q - c0), hi)
        } else {
            (lo, up_sum(c0 + q))
        }
    }

    /// The part of `[-1, 1]` where the form may be 0 or below (as
    /// [`Affine::may_reach_zero`]): outside it the polynomial part is
    /// above the error, so f is positive there (where defined). Each part
    /// left out is proved positive by [`Lowest::positive_on`], so the
    /// approximate roots that place the cuts cannot make it unsound;
    /// `None` where the form is positive everywhere, the whole range
    /// where it is unbounded.
    pub fn may_reach_zero(&self) -> Option<Interval> {
        let whole = Interval::new(-1.0, 1.0);
        if !self.is_bounded() {
            return Some(whole);
        }
        let p = Lowest {
            a: -up_sum(self.e - self.c[0]),
            b: self.c[1],
            c: self.c[2],
        };
        if p.positive_on(-1.0, 1.0) {
            return None;
        }
        let [r1, r2] = p.roots();
        let first = if r1 > -1.0 { r1 } else { r2 };
        let last = if r2 < 1.0 { r2 } else { r1 };
        let mut lo = -1.0;
        let mut hi = 1.0;
        for delta in CUT_MARGINS {
            let s = first - delta;
            if s > -1.0 && s < 1.0 && p.positive_on(-1.0, s) {
                lo = s;
                break;
            }
        }
        for delta in CUT_MARGINS {
            let s = last + delta;
            if s > -1.0 && s < 1.0 && p.positive_on(s, 1.0) {
                hi = s;
                break;
            }
        }
        // lo > hi: the two parts proved positive cover the whole range.
        meet(Interval::new(lo, hi), whole)
    }
}

/// How far before (after) an approximate root the cut is tried, in units
/// of the noise symbol: the first margin that proves positive is kept.
const CUT_MARGINS: [f64; 3] = [1.0 / (1u64 << 40) as f64, 1.0 / (1u64 << 26) as f64, 1e-4];

/// `a + b·ε + c·ε²` with exact float coefficients, `a` a lower bound of
/// the form's `c0 − e`: at every ε it is at most the form's lowest value.
struct Lowest {
    a: f64,
    b: f64,
    c: f64,
}

impl Lowest {
    /// Its value at `s`, by outward-rounded intervals.
    fn at(&self, s: f64) -> Interval {
        Interval::point(self.c)
            .mul_point(s)
            .add(Interval::point(self.b))
            .mul_point(s)
            .add(Interval::point(self.a))
    }

    /// Whether it is positive throughout `[l, h]`: a quadratic's least
    /// value over an interval is at an end, or at the vertex of a convex
    /// one where the vertex lies inside (both enclosed by intervals).
    fn positive_on(&self, l: f64, h: f64) -> bool {
        if !(self.at(l).lo > 0.0 && self.at(h).lo > 0.0) {
            return false;
        }
        if self.c <= 0.0 {
            return true;
        }
        let c = Interval::point(self.c);
        let vertex = Interval::point(-self.b).div(c).mul_point(0.5);
        if vertex.hi < l || vertex.lo > h {
            return true;
        }
        let b2_4c = Interval::point(self.b).square().div(c).mul_point(0.25);
        Interval::point(self.a).sub(b2_4c).lo > 0.0
    }

    /// Its real roots, roughly, in increasing order (NaN where none):
    /// only where to try a cut, which [`Lowest::positive_on`] proves.
    fn roots(&self) -> [f64; 2] {
        let (a, b, c) = (self.a, self.b, self.c);
        if c == 0.0 {
            let r = -a / b;
            return [r, r];
        }
        let disc = b * b - 4.0 * a * c;
        if disc.is_nan() || disc < 0.0 {
            return [f64::NAN; 2];
        }
        let q = -0.5 * (b + disc.sqrt().copysign(b));
        if q == 0.0 {
            return [0.0; 2];
        }
        let (r1, r2) = (q / c, a / q);
        if r1 <= r2 { [r1, r2] } else { [r2, r1] }
    }
}

impl Form for Quadratic {
    const UNBOUNDED: Self = Quadratic::UNBOUNDED;
    // Along a ray the ops read their operands' ranges rarely (an expanded
    // polynomial never), and the range of each value cost a sixth of a
    // render's instructions.
    const MEET_EACH_OP: bool = false;

    fn constant(v: f64) -> Self {
        Quadratic::from_affine(Affine::constant(v))
    }

    fn from_interval(i: Interval) -> Self {
        Quadratic::from_affine(Affine::from_interval(i))
    }

    fn is_bounded(&self) -> bool {
        self.c.iter().all(|c| c.is_finite()) && self.e.is_finite()
    }

    fn neg(&self) -> Self {
        Quadratic {
            c: self.c.map(|c| -c),
            e: self.e,
        }
    }

    fn add(&self, o: &Self) -> Self {
        let mut err = ErrSum::default();
        err.add(self.e);
        err.add(o.e);
        let c = std::array::from_fn(|i| err.rounded(self.c[i] + o.c[i]));
        Quadratic { c, e: err.total() }.checked()
    }

    fn sub(&self, o: &Self) -> Self {
        self.add(&o.neg())
    }

    /// The product's five coefficients folded to degree 2, and the error
    /// terms times the other polynomial part's magnitude.
    fn mul(&self, o: &Self) -> Self {
        let ([a0, a1, a2], [b0, b1, b2]) = (self.c, o.c);
        let mut err = ErrSum::default();
        err.add(mul_up(self.magnitude(), o.e));
        err.add(mul_up(o.magnitude(), self.e));
        err.add(mul_up(self.e, o.e));
        let mut prod = |x: f64, y: f64| err.rounded(x * y);
        let (p0, p1a, p1b) = (prod(a0, b0), prod(a0, b1), prod(a1, b0));
        let (p2a, p2b, p2c) = (prod(a0, b2), prod(a1, b1), prod(a2, b0));
        let (p3a, p3b, p4) = (prod(a1, b2), prod(a2, b1), prod(a2, b2));
        let p1 = err.rounded(p1a + p1b);
        let p2ac = err.rounded(p2a + p2c);
        let p2 = err.rounded(p2ac + p2b);
        let p3 = err.rounded(p3a + p3b);
        let c = Quadratic::fold([p0, p1, p2], p3, p4, &mut err);
        Quadratic { c, e: err.total() }.checked()
    }

    /// As [`Form::mul`] with itself; the error part `2·P·e·η + e²·η²`
    /// of `(P + e·η)²` is within `±(2·|P|·e + e²)`.
    fn square(&self) -> Self {
        let [a0, a1, a2] = self.c;
        let mut err = ErrSum::default();
        err.add(mul_up(2.0 * self.magnitude(), self.e));
        err.add(mul_up(self.e, self.e));
        let p0 = err.rounded(a0 * a0);
        let p1 = err.rounded(2.0 * a0 * a1);
        let p2a = err.rounded(a1 * a1);
        let p2b = err.rounded(2.0 * a0 * a2);
        let p2 = err.rounded(p2a + p2b);
        let p3 = err.rounded(2.0 * a1 * a2);
        let p4 = err.rounded(a2 * a2);
        let c = Quadratic::fold([p0, p1, p2], p3, p4, &mut err);
        Quadratic { c, e: err.total() }.checked()
    }

    fn linear(&self, alpha: f64, beta: f64, delta: f64) -> Self {
        let mut err = ErrSum::default();
        err.add(delta);
        err.add(mul_up(alpha.abs(), self.e));
        let ac = err.rounded(alpha * self.c[0]);
        let c0 = err.rounded(ac + beta);
        let c1 = err.rounded(alpha * self.c[1]);
        let c2 = err.rounded(alpha * self.c[2]);
        Quadratic {
            c: [c0, c1, c2],
            e: err.total(),
        }
        .checked()
    }

    // Products keep each step's second-order terms, where a Chebyshev
    // linearisation over the range puts them all in the error.
    fn power(&self, n: i32) -> Option<Self> {
        (n >= 1).then(|| self.powered(n.unsigned_abs(), &mut Vec::new()))
    }

    fn power_sharing(&self, n: i32, squares: &mut Vec<Self>) -> Option<Self> {
        (n >= 1).then(|| self.powered(n.unsigned_abs(), squares))
    }

    fn centre(&self) -> f64 {
        self.c[0]
    }

    fn spread(&self) -> f64 {
        up_sum(self.c[1].abs() + self.c[2].abs())
    }

    fn error(&self) -> f64 {
        self.e
    }

    fn with_error(self, e: f64) -> Self {
        Quadratic { e, ..self }
    }

    /// The vertex range ([`Quadratic::poly_range`]) widened by the error;
    /// the spread is not needed.
    fn range_within(&self, _spread: f64) -> Interval {
        let (lo, hi) = self.poly_range();
        let (lo, hi) = (-up_sum(self.e - lo), up_sum(hi + self.e));
        if lo.is_nan() || hi.is_nan() {
            return Interval::ENTIRE;
        }
        Interval::new(lo, hi)
    }
}

#[cfg(test)]
#[path = "quadratic_tests.rs"]
mod tests;
