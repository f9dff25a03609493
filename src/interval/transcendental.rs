//! Interval bounds of the transcendental ops: exp, ln, sin, cos, atan2, pow.
//!
//! Each bound is a libm result at an end of the argument (or at a corner of
//! the argument box) stepped [`TRANSCENDENTAL_ULPS`] ulps outward, plus the
//! function's extrema where the argument reaches them. Where the range of
//! the function limits a bound for free (exp ≥ 0, |sin| ≤ 1, |atan2| ≤ π)
//! the widened bound is clamped to it.

use super::{Interval, TRANSCENDENTAL_ULPS};

/// `v` stepped [`TRANSCENDENTAL_ULPS`] ulps down (a rigorous lower bound of
/// the real value that libm approximated by `v`).
#[inline]
pub fn widen_down(v: f64) -> f64 {
    let mut r = v;
    for _ in 0..TRANSCENDENTAL_ULPS {
        r = r.next_down();
    }
    r
}

/// `v` stepped [`TRANSCENDENTAL_ULPS`] ulps up.
#[inline]
pub fn widen_up(v: f64) -> f64 {
    let mut r = v;
    for _ in 0..TRANSCENDENTAL_ULPS {
        r = r.next_up();
    }
    r
}

/// Past this magnitude sin and cos give [-1, 1]: the reduction of the ends
/// by π below would lose the parity of k, and such boxes carry no
/// useful information anyway.
pub(super) const TRIG_HUGE: f64 = 1e15;

/// Lower bound of π's upper neighbour: `PI` (the f64 nearest π) is below π.
pub(super) const PI_UP: f64 = 3.141_592_653_589_793_6;

/// Whether `[a, b]` holds a point `(k + offset)·π` with k even, and one
/// with k odd (the maxima and minima of cos for offset 0, of sin for offset
/// 1/2). Possibly over-approximated (an extra k only widens the result toward ±1, which is
/// sound; a missing k would not be). Returns `(has_even, has_odd)`.
pub(super) fn extrema_in(a: f64, b: f64, offset_halves: f64) -> (bool, bool) {
    // t = x/π - offset, computed in floating point: the relative error of
    // FRAC_1_PI, of the product and of the subtraction is below 3 ulps of
    // the magnitudes involved, so a slack of 1e-15·(|x/π| + 1) covers it.
    let t = |x: f64| x * std::f64::consts::FRAC_1_PI - offset_halves;
    let slack = |x: f64| ((x * std::f64::consts::FRAC_1_PI).abs() + 1.0) * 1e-15;
    let k_min = (t(a) - slack(a)).ceil();
    let k_max = (t(b) + slack(b)).floor();
    if k_max < k_min {
        return (false, false);
    }
    if k_max > k_min {
        return (true, true);
    }
    let even = k_min.rem_euclid(2.0) == 0.0;
    (even, !even)
}

impl Interval {
    /// `exp(self)`, clamped to be non-negative.
    pub fn exp(self) -> Interval {
        if self.is_empty() {
            return Interval::EMPTY;
        }
        let hi = super::exp::exp(self.hi);
        // A point interval (the mean-value form's centre, a ray's fixed
        // parameter) needs one call: exp is a function of its argument's
        // value, so the bits are those of two calls.
        let lo = if self.lo == self.hi {
            hi
        } else {
            super::exp::exp(self.lo)
        };
        Interval::new(widen_down(lo).max(0.0), widen_up(hi))
    }

    /// `ln(self)` over the non-negative part: EMPTY if self < 0, lower
    /// bound -inf when 0 ∈ self.
    pub fn ln(self) -> Interval {
        if self.is_empty() || self.hi < 0.0 {
            return Interval::EMPTY;
        }
        let lo = if self.lo <= 0.0 {
            f64::NEG_INFINITY
        } else {
            widen_down(libm::log(self.lo))
        };
        Interval::new(lo, widen_up(libm::log(self.hi)))
    }

    /// `cos(self)`: the hull of cos at the ends, extended to 1 where the
    /// interval holds an even multiple of π and to -1 at an odd one.
    pub fn cos(self) -> Interval {
        self.trig(libm::cos, 0.0)
    }

    /// `sin(self)`: as [`Interval::cos`], with the extrema at π/2 + kπ
    /// (maxima for even k, minima for odd k).
    pub fn sin(self) -> Interval {
        self.trig(libm::sin, 0.5)
    }

    // sin(x) = cos(x - π/2): the extrema of both sit at (k + offset)·π, with
    // maxima at even k.
    fn trig(self, f: fn(f64) -> f64, offset: f64) -> Interval {
        if self.is_empty() {
            return Interval::EMPTY;
        }
        let whole = Interval::new(-1.0, 1.0);
        if !(self.lo.abs() <= TRIG_HUGE && self.hi.abs() <= TRIG_HUGE) {
            return whole;
        }
        let (has_max, has_min) = extrema_in(self.lo, self.hi, offset);
        if has_max && has_min {
            return whole;
        }
        let (fa, fb) = (f(self.lo), f(self.hi));
        let lo = if has_min {
            -1.0
        } else {
            widen_down(fa.min(fb)).max(-1.0)
        };
        let hi = if has_max {
            1.0
        } else {
            widen_up(fa.max(fb)).min(1.0)
        };
        Interval::new(lo, hi)
    }

    /// `atan2(self, x)`: the angles of the points (x, y), y ∈ self, x ∈ `x`.
    /// [-π, π] (outward) when the box touches the branch cut x ≤ 0, y = 0;
    /// otherwise the angle is continuous on the box and, the box being
    /// convex and away from the origin, its extremes lie at corners.
    pub fn atan2(self, x: Interval) -> Interval {
        let y = self;
        if y.is_empty() || x.is_empty() {
            return Interval::EMPTY;
        }
        if x.lo <= 0.0 && y.lo <= 0.0 && 0.0 <= y.hi {
            return Interval::new(-PI_UP, PI_UP);
        }
        let c = [
            libm::atan2(y.lo, x.lo),
            libm::atan2(y.lo, x.hi),
            libm::atan2(y.hi, x.lo),
            libm::atan2(y.hi, x.hi),
        ];
        let lo = c[0].min(c[1]).min(c[2]).min(c[3]);
        let hi = c[0].max(c[1]).max(c[2]).max(c[3]);
        Interval::new(widen_down(lo).max(-PI_UP), widen_up(hi).min(PI_UP))
    }

    /// `self^e` = exp(e ln self) over the non-negative part of self (EMPTY
    /// if self < 0). a^b is monotone in a for fixed b and in b for fixed a
    /// (with 0^b = 0, 1, +inf for b > 0, = 0, < 0), so its extremes over
    /// the box lie at corners.
    pub fn pow(self, e: Interval) -> Interval {
        if self.is_empty() || e.is_empty() || self.hi < 0.0 {
            return Interval::EMPTY;
        }
        // -0.0 becomes +0.0 (libm's pow(-0, -1) is -inf; ours is +inf).
        let a_lo = if self.lo <= 0.0 { 0.0 } else { self.lo };
        let a_hi = self.hi + 0.0;
        let c = [
            libm::pow(a_lo, e.lo),
            libm::pow(a_lo, e.hi),
            libm::pow(a_hi, e.lo),
            libm::pow(a_hi, e.hi),
        ];
        let lo = c[0].min(c[1]).min(c[2]).min(c[3]);
        let hi = c[0].max(c[1]).max(c[2]).max(c[3]);
        Interval::new(widen_down(lo).max(0.0), widen_up(hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn pi_up_is_above_pi() {
        // π = 3.14159265358979323846…; PI (…7931159…) is below it, so its
        // successor is above.
        assert_eq!(PI.next_up(), PI_UP);
    }

    #[test]
    fn cos_finds_extrema() {
        let c = Interval::new(-0.1, 0.1).cos();
        assert_eq!(c.hi, 1.0);
        assert!(c.lo > 0.99 && c.lo < libm::cos(0.1));
        let c = Interval::new(3.0, 3.3).cos();
        assert_eq!(c.lo, -1.0);
        assert!(c.hi < -0.98);
        let c = Interval::new(0.2, 1.0).cos();
        assert!(c.lo < libm::cos(1.0) && c.hi > libm::cos(0.2) && c.hi < 0.99);
    }

    #[test]
    fn sin_finds_extrema() {
        let s = Interval::new(1.5, 1.6).sin();
        assert_eq!(s.hi, 1.0);
        let s = Interval::new(-1.6, -1.5).sin();
        assert_eq!(s.lo, -1.0);
        let s = Interval::new(0.0, 1.0).sin();
        assert!(s.lo <= 0.0 && s.lo > -1e-300 && s.hi < 0.85);
        assert_eq!(Interval::new(0.0, 7.0).sin(), Interval::new(-1.0, 1.0));
        assert_eq!(Interval::new(1e16, 1e16).sin(), Interval::new(-1.0, 1.0));
    }

    #[test]
    fn ln_partial_domain() {
        assert!(Interval::new(-2.0, -1.0).ln().is_empty());
        let l = Interval::new(-1.0, 1.0).ln();
        assert_eq!(l.lo, f64::NEG_INFINITY);
        assert!(l.hi >= 0.0 && l.hi < 1e-300);
    }

    #[test]
    fn atan2_branch_cut_and_corners() {
        let a = Interval::new(-1.0, 1.0).atan2(Interval::new(-2.0, -1.0));
        assert!(a.lo <= -PI && a.hi >= PI);
        let a = Interval::new(1.0, 2.0).atan2(Interval::new(1.0, 2.0));
        assert!(a.contains(libm::atan2(1.0, 2.0)) && a.contains(libm::atan2(2.0, 1.0)));
        assert!(a.hi < 1.2 && a.lo > 0.4);
    }

    #[test]
    fn pow_corners_and_domain() {
        assert!(
            Interval::new(-2.0, -1.0)
                .pow(Interval::point(2.0))
                .is_empty()
        );
        let p = Interval::new(-1.0, 2.0).pow(Interval::new(-1.0, 2.0));
        assert!(p.lo <= 0.0 && p.hi == f64::INFINITY);
        let p = Interval::new(2.0, 3.0).pow(Interval::new(2.0, 3.0));
        assert!(p.lo <= 4.0 && p.lo > 3.99 && p.hi >= 27.0 && p.hi < 27.01);
    }
}
