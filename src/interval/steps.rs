//! Interval bounds of the piecewise-constant ops (floor, ceil, round,
//! sign) and of the remainder `mod`.
//!
//! The step functions are exact in floating point and non-decreasing, so
//! their bounds are the op at the ends, with no widening. Over an interval
//! that holds a jump the result is the hull of the values on both sides:
//! it contains every value the op takes there, which is what the tracer's
//! guarantee needs (it draws the boundary of the solid {f < 0}).

use super::Interval;

/// Point semantics of `sign`: -1, 0 or 1, NaN for NaN (0 for both zeros,
/// unlike `f64::signum`).
pub fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        // ±0 stays 0 (positive); NaN stays NaN.
        a * 0.0 + 0.0
    }
}

/// Point semantics of `mod`: the least non-negative remainder of `a / b`,
/// as `f64::rem_euclid` computes it (NaN for b = 0 or an infinite a).
pub fn rem_euclid(a: f64, b: f64) -> f64 {
    a.rem_euclid(b)
}

impl Interval {
    /// `[f(lo), f(hi)]` for a non-decreasing `f` exact in floating point.
    fn non_decreasing(self, f: fn(f64) -> f64) -> Interval {
        if self.is_empty() {
            return Interval::EMPTY;
        }
        Interval::new(f(self.lo), f(self.hi))
    }

    /// `floor(self)`.
    pub fn floor(self) -> Interval {
        self.non_decreasing(f64::floor)
    }

    /// `ceil(self)`.
    pub fn ceil(self) -> Interval {
        self.non_decreasing(f64::ceil)
    }

    /// `round(self)`, halves away from zero.
    pub fn round(self) -> Interval {
        self.non_decreasing(f64::round)
    }

    /// `sign(self)`.
    pub fn sign(self) -> Interval {
        self.non_decreasing(sign)
    }

    /// Whether a piecewise-constant op (`f` one of the above) may jump
    /// inside self: it is constant on self iff it is equal at both ends.
    pub fn may_jump(self, f: impl Fn(f64) -> f64) -> bool {
        !self.is_empty() && f(self.lo) != f(self.hi)
    }

    /// `self mod b`, the least non-negative remainder (see [`rem_euclid`]).
    ///
    /// The point op is `fl(a - k|b|)` with k = floor(a/|b|): `fmod` is
    /// exact and the one addition after it rounds once. Where the divisor
    /// is a constant c and one k serves the whole interval (checked in
    /// interval arithmetic, so a wrongly rounded guess of k fails the test
    /// instead of giving a wrong bound), the result is `self - k·c`, which
    /// round-to-nearest cannot leave. Otherwise every remainder lies in
    /// [0, max |b|].
    pub fn rem_euclid(self, b: Interval) -> Interval {
        if self.is_empty() || b.is_empty() {
            return Interval::EMPTY;
        }
        let m = b.abs();
        if m.hi == 0.0 || (self.lo == self.hi && self.lo.is_infinite()) {
            return Interval::EMPTY;
        }
        let whole = Interval::new(0.0, m.hi);
        if !(self.lo.is_finite() && self.hi.is_finite() && m.hi.is_finite()) {
            return whole;
        }
        if self.lo >= 0.0 && self.hi < m.lo {
            return self;
        }
        if m.lo == m.hi {
            let c = m.lo;
            let k0 = (self.lo / c).floor();
            for k in [k0, k0 - 1.0, k0 + 1.0] {
                let d = self.sub(Interval::point(k).mul(m));
                if d.lo >= 0.0 && d.hi < c {
                    return d;
                }
            }
        }
        whole
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_exact_at_the_ends() {
        assert_eq!(Interval::new(-1.5, 2.5).floor(), Interval::new(-2.0, 2.0));
        assert_eq!(Interval::new(-1.5, 2.5).ceil(), Interval::new(-1.0, 3.0));
        assert_eq!(Interval::new(-2.5, 2.5).round(), Interval::new(-3.0, 3.0));
        assert_eq!(Interval::new(-0.0, 3.0).sign(), Interval::new(0.0, 1.0));
        assert!(sign(f64::NAN).is_nan() && sign(-0.0) == 0.0 && sign(-3.0) == -1.0);
        assert!(Interval::new(0.2, 0.7).may_jump(f64::round));
        assert!(!Interval::new(0.2, 0.7).may_jump(f64::floor));
    }

    #[test]
    fn remainder_within_one_period_is_tight() {
        // Outward rounding moves exact ends by an ulp or two.
        let near = |r: Interval, lo: f64, hi: f64| {
            r.lo <= lo && r.lo > lo - 1e-14 && r.hi >= hi && r.hi < hi + 1e-14
        };
        let r = Interval::new(2.25, 2.75).rem_euclid(Interval::point(1.0));
        assert!(near(r, 0.25, 0.75), "{r:?}");
        let r = Interval::new(-0.75, -0.25).rem_euclid(Interval::point(-1.0));
        assert!(r.lo <= 0.25 && r.lo > 0.24 && r.hi >= 0.75 && r.hi < 0.76);
        let r = Interval::new(0.5, 1.5).rem_euclid(Interval::point(1.0));
        assert_eq!(r, Interval::new(0.0, 1.0));
        assert!(
            Interval::new(1.0, 2.0)
                .rem_euclid(Interval::point(0.0))
                .is_empty()
        );
        let r = Interval::new(1.0, 2.0).rem_euclid(Interval::new(3.0, 4.0));
        assert_eq!(r, Interval::new(1.0, 2.0));
    }

    #[test]
    fn remainder_contains_sampled_points() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..20_000 {
            let a0 = (next() - 0.5) * 40.0;
            let a1 = a0 + next() * next() * 3.0;
            let c = [0.3, 1.0, -2.5, 1e-3, 7.0][(next() * 5.0) as usize % 5];
            let r = Interval::new(a0, a1).rem_euclid(Interval::point(c));
            for t in [0.0, 1.0, next()] {
                let a = a0 + (a1 - a0) * t;
                let v = rem_euclid(a, c);
                assert!(r.contains(v), "{a} mod {c} = {v} not in {r:?}");
            }
        }
    }
}
