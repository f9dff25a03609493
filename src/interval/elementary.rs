//! Interval bounds of tan, the inverse trigonometric functions and the
//! hyperbolic functions.
//!
//! Each is monotone on its domain (tan between its poles, cosh on each
//! side of 0), so a bound is libm at an end, widened like the other
//! transcendentals, and clamped to the function's range where that range
//! limits it for free (|atan| < π/2, |tanh| ≤ 1, cosh ≥ 1).

use super::Interval;
use super::transcendental::{PI_UP, TRIG_HUGE, extrema_in};
use super::{widen_down, widen_up};

/// An upper bound of π/2 (the f64 nearest π/2 lies below it).
const HALF_PI_UP: f64 = PI_UP / 2.0;

impl Interval {
    /// `[f(lo), f(hi)]` widened, for an increasing `f`.
    fn increasing(self, f: fn(f64) -> f64) -> Interval {
        if self.is_empty() {
            return Interval::EMPTY;
        }
        Interval::new(widen_down(f(self.lo)), widen_up(f(self.hi)))
    }

    /// `tan(self)`: the whole line when the interval may hold a pole
    /// π/2 + kπ (or is too wide to tell), else increasing between its ends.
    pub fn tan(self) -> Interval {
        if self.is_empty() {
            return Interval::EMPTY;
        }
        if !(self.lo.abs() <= TRIG_HUGE && self.hi.abs() <= TRIG_HUGE) {
            return Interval::ENTIRE;
        }
        // The poles of tan are the extrema of sin.
        let (even, odd) = extrema_in(self.lo, self.hi, 0.5);
        if even || odd {
            return Interval::ENTIRE;
        }
        self.increasing(libm::tan)
    }

    /// `asin(self)` over the part of self inside [-1, 1] (EMPTY if none).
    pub fn asin(self) -> Interval {
        let Some(d) = self.within_unit() else {
            return Interval::EMPTY;
        };
        let r = d.increasing(libm::asin);
        Interval::new(r.lo.max(-HALF_PI_UP), r.hi.min(HALF_PI_UP))
    }

    /// `acos(self)` over the part of self inside [-1, 1] (EMPTY if none):
    /// decreasing.
    pub fn acos(self) -> Interval {
        let Some(d) = self.within_unit() else {
            return Interval::EMPTY;
        };
        Interval::new(
            widen_down(libm::acos(d.hi)).max(0.0),
            widen_up(libm::acos(d.lo)).min(PI_UP),
        )
    }

    /// The part of self inside [-1, 1], the domain of asin and acos.
    fn within_unit(self) -> Option<Interval> {
        if self.is_empty() || self.hi < -1.0 || self.lo > 1.0 {
            return None;
        }
        Some(Interval::new(self.lo.max(-1.0), self.hi.min(1.0)))
    }

    /// `atan(self)`, within (-π/2, π/2).
    pub fn atan(self) -> Interval {
        let r = self.increasing(libm::atan);
        if r.is_empty() {
            return r;
        }
        Interval::new(r.lo.max(-HALF_PI_UP), r.hi.min(HALF_PI_UP))
    }

    /// `sinh(self)`.
    pub fn sinh(self) -> Interval {
        self.increasing(libm::sinh)
    }

    /// `cosh(self)`: 1 at 0, growing on each side; never below 1.
    pub fn cosh(self) -> Interval {
        if self.is_empty() {
            return Interval::EMPTY;
        }
        let (a, b) = (libm::cosh(self.lo), libm::cosh(self.hi));
        let lo = if self.lo <= 0.0 && self.hi >= 0.0 {
            1.0
        } else {
            widen_down(a.min(b)).max(1.0)
        };
        Interval::new(lo, widen_up(a.max(b)))
    }

    /// `tanh(self)`, within [-1, 1].
    pub fn tanh(self) -> Interval {
        let r = self.increasing(libm::tanh);
        if r.is_empty() {
            return r;
        }
        Interval::new(r.lo.max(-1.0), r.hi.min(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tan_is_whole_across_a_pole() {
        assert_eq!(Interval::new(1.5, 1.6).tan(), Interval::ENTIRE);
        assert_eq!(Interval::new(-1.6, -1.5).tan(), Interval::ENTIRE);
        let t = Interval::new(-1.0, 1.0).tan();
        assert!(t.lo < -1.557 && t.lo > -1.558 && t.hi > 1.557 && t.hi < 1.558);
        let t = Interval::new(3.0, 3.2).tan();
        assert!(t.contains(libm::tan(3.1)) && t.hi < 0.06);
    }

    #[test]
    fn inverse_trig_partial_domain() {
        assert!(Interval::new(1.5, 2.0).asin().is_empty());
        assert!(Interval::new(-3.0, -1.5).acos().is_empty());
        let a = Interval::new(-2.0, 0.5).asin();
        assert!(a.lo <= -std::f64::consts::FRAC_PI_2 && a.hi >= libm::asin(0.5));
        let c = Interval::new(0.5, 7.0).acos();
        assert!(c.lo == 0.0 && c.hi >= libm::acos(0.5) && c.hi < 1.05);
        let t = Interval::ENTIRE.atan();
        assert!(t.lo >= -HALF_PI_UP && t.hi <= HALF_PI_UP && t.hi > 1.57);
    }

    #[test]
    fn hyperbolic_ranges() {
        let c = Interval::new(-1.0, 2.0).cosh();
        assert!(c.lo == 1.0 && c.hi >= libm::cosh(2.0));
        let c = Interval::new(1.0, 2.0).cosh();
        assert!(c.lo <= libm::cosh(1.0) && c.lo > 1.5);
        let t = Interval::new(-100.0, 100.0).tanh();
        assert_eq!(t, Interval::new(-1.0, 1.0));
        let s = Interval::new(-800.0, 1.0).sinh();
        assert!(s.lo == f64::NEG_INFINITY && s.hi >= libm::sinh(1.0));
    }
}
