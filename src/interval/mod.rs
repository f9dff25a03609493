//! Outward-rounded interval arithmetic over f64.
//!
//! # Guarantee
//! For every op `F` here and every box of argument intervals, `F(A, B)`
//! contains `f(a, b)` for every `a ∈ A`, `b ∈ B` where the point op `f`
//! (see [`crate::ir::Op`]) gives a real (finite or not NaN) value. Rounding
//! error is covered: the hardware computes in round-to-nearest, and each
//! bound is then stepped one ulp outward (lower bound down, upper bound up),
//! which covers the half-ulp error of a correctly rounded `+ - * / sqrt`.
//! Transcendentals call `libm`, whose stated error is below 1 ulp; we widen
//! their results by [`TRANSCENDENTAL_ULPS`] ulps. The JIT (`crate::jit`)
//! implements the same rules and is tested against this module.
//!
//! # Partial domains (IEEE 1788 style)
//! An op takes only the defined part of its domain: `sqrt([-1, 4]) = [0, 2]`,
//! `ln([-1, e]) = [-inf, 1]`, `pow` with a negative base part uses the
//! non-negative part. An op with no defined part returns [`Interval::EMPTY`]
//! (both bounds NaN), and EMPTY propagates through every op (but `powi(_, 0)`,
//! which is 1 at every point, NaN included), so a box on which f is
//! undefined everywhere is rejected (it holds no root).
//! Division takes the nonzero part of the divisor: the whole line when 0 is
//! inside it, a half-line when 0 is one of its ends, EMPTY for [0, 0].
//! Infinities are not real values: a bound at ±inf means "unbounded".
//!
//! # Transcendentals
//! exp, ln, sin, cos, atan2 and pow (in `transcendental.rs`) bound libm at
//! the ends (corners for atan2 and pow), widened by [`TRANSCENDENTAL_ULPS`]
//! ulps with [`widen_down`] / [`widen_up`], plus the extrema the argument
//! reaches: sin and cos find the multiples of π/2 inside the interval
//! (arguments beyond 1e15 in magnitude give [-1, 1]); atan2 gives [-π, π]
//! when the box touches its branch cut (x ≤ 0, y = 0).

/// A closed interval `[lo, hi]`; both bounds NaN is the empty set.
#[derive(Copy, Clone, Debug, PartialEq)]
#[repr(C)]
pub struct Interval {
    /// Lower bound (may be -inf).
    pub lo: f64,
    /// Upper bound (may be +inf).
    pub hi: f64,
}

/// Ulps by which libm transcendental results are widened on each side.
pub const TRANSCENDENTAL_ULPS: u32 = 2;

impl Interval {
    /// The empty set (both bounds NaN).
    pub const EMPTY: Interval = Interval {
        lo: f64::NAN,
        hi: f64::NAN,
    };
    /// The whole real line.
    pub const ENTIRE: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    /// `[lo, hi]`; the caller guarantees `lo <= hi`.
    pub const fn new(lo: f64, hi: f64) -> Interval {
        Interval { lo, hi }
    }

    /// The degenerate interval `[v, v]` (EMPTY for NaN).
    pub const fn point(v: f64) -> Interval {
        Interval { lo: v, hi: v }
    }

    /// Whether this is the empty set.
    pub fn is_empty(self) -> bool {
        self.lo.is_nan() || self.hi.is_nan()
    }

    /// Whether `v` lies in the interval (false for NaN and for EMPTY).
    pub fn contains(self, v: f64) -> bool {
        self.lo <= v && v <= self.hi
    }

    /// Midpoint (finite for finite bounds).
    pub fn mid(self) -> f64 {
        self.lo + 0.5 * (self.hi - self.lo)
    }

    /// `hi - lo`.
    pub fn width(self) -> f64 {
        self.hi - self.lo
    }
}

/// Rounds a lower bound one ulp down (NaN stays NaN, -inf stays -inf).
#[inline]
pub fn down(v: f64) -> f64 {
    v.next_down()
}

/// Rounds an upper bound one ulp up (NaN stays NaN, +inf stays +inf).
#[inline]
pub fn up(v: f64) -> f64 {
    v.next_up()
}

/// min that ignores a NaN operand (NaN only if both are NaN). Used over the
/// candidate bounds of `*` and `/`, where 0·inf and inf/inf give NaN for a
/// combination of bounds that no real operand pair attains.
#[inline]
pub fn min_ignore_nan(a: f64, b: f64) -> f64 {
    a.min(b)
}

/// max that ignores a NaN operand (NaN only if both are NaN).
#[inline]
pub fn max_ignore_nan(a: f64, b: f64) -> f64 {
    a.max(b)
}

/// `min(u, 0)` for an upper bound `u`, giving +0 for -0 and 0 for NaN.
/// `f64::min(-0.0, 0.0)` picks either zero, and which one differs between
/// debug and release builds; this keeps the bits (and the JIT) reproducible.
#[inline]
fn nonpositive(u: f64) -> f64 {
    if u < 0.0 { u } else { 0.0 }
}

/// min that propagates NaN: the point semantics of the IR's `min`.
#[inline]
pub fn min_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if a < b {
        a
    } else {
        b
    }
}

/// max that propagates NaN: the point semantics of the IR's `max`.
#[inline]
pub fn max_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if a > b {
        a
    } else {
        b
    }
}

/// x^n for n >= 0 by binary exponentiation, in round-to-nearest. This is the
/// point semantics of `powi` (and of the JIT): deterministic everywhere,
/// unlike `f64::powi`, whose algorithm is not specified.
pub fn powi_point(x: f64, n: i32) -> f64 {
    if n < 0 {
        return 1.0 / powi_unsigned(x, n.unsigned_abs(), |v| v);
    }
    powi_unsigned(x, n as u32, |v| v)
}

// Binary exponentiation with `round` applied after every multiplication; with
// `up`/`down` on non-negative x it gives a rigorous upper/lower bound.
fn powi_unsigned(x: f64, mut n: u32, round: impl Fn(f64) -> f64) -> f64 {
    let mut result = 1.0;
    let mut base = x;
    let mut first = true;
    while n > 0 {
        if n & 1 == 1 {
            result = if first { base } else { round(result * base) };
            first = false;
        }
        n >>= 1;
        if n > 0 {
            base = round(base * base);
        }
    }
    result
}

// Named methods rather than operator traits: every call site of an
// outward-rounded op stays visible as such.
#[allow(clippy::should_implement_trait)]
impl Interval {
    /// `-self` (exact).
    pub fn neg(self) -> Interval {
        Interval::new(-self.hi, -self.lo)
    }

    /// `self + o`.
    pub fn add(self, o: Interval) -> Interval {
        Interval::new(down(self.lo + o.lo), up(self.hi + o.hi))
    }

    /// `self - o`.
    pub fn sub(self, o: Interval) -> Interval {
        Interval::new(down(self.lo - o.hi), up(self.hi - o.lo))
    }

    /// `self * o`: hull of the four bound products, ignoring the NaN of
    /// 0·inf, each bound then rounded outward.
    pub fn mul(self, o: Interval) -> Interval {
        let p = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        let lo = min_ignore_nan(min_ignore_nan(p[0], p[1]), min_ignore_nan(p[2], p[3]));
        let hi = max_ignore_nan(max_ignore_nan(p[0], p[1]), max_ignore_nan(p[2], p[3]));
        if lo.is_nan() {
            // All four products are 0·inf: one operand is [0, 0] and the
            // other has only infinite bounds, so every real product is 0.
            return if self.is_empty() || o.is_empty() {
                Interval::EMPTY
            } else {
                Interval::point(0.0)
            };
        }
        Interval::new(down(lo), up(hi))
    }

    /// `self / o` over the nonzero part of `o` (a quotient by 0 is not
    /// real): EMPTY when o = [0, 0], a half-line when 0 is an end of `o`,
    /// the whole line when 0 is inside `o` (unless self = [0, 0]).
    pub fn div(self, o: Interval) -> Interval {
        if self.is_empty() || o.is_empty() || (o.lo == 0.0 && o.hi == 0.0) {
            return Interval::EMPTY;
        }
        if o.lo <= 0.0 && 0.0 <= o.hi {
            if self.lo == 0.0 && self.hi == 0.0 {
                return Interval::point(0.0);
            }
            if o.lo < 0.0 && 0.0 < o.hi {
                return Interval::ENTIRE;
            }
            // 0 is an end of o: the divisor keeps one sign, o = [0+, hi] or
            // [lo, 0-], and the quotient is bounded on one side.
            let positive = o.lo == 0.0;
            let d = if positive { o.hi } else { o.lo };
            return if self.lo >= 0.0 {
                if positive {
                    Interval::new(down(self.lo / d).max(0.0), f64::INFINITY)
                } else {
                    Interval::new(f64::NEG_INFINITY, nonpositive(up(self.lo / d)))
                }
            } else if self.hi <= 0.0 {
                if positive {
                    Interval::new(f64::NEG_INFINITY, nonpositive(up(self.hi / d)))
                } else {
                    Interval::new(down(self.hi / d).max(0.0), f64::INFINITY)
                }
            } else {
                Interval::ENTIRE
            };
        }
        let q = [
            self.lo / o.lo,
            self.lo / o.hi,
            self.hi / o.lo,
            self.hi / o.hi,
        ];
        let lo = min_ignore_nan(min_ignore_nan(q[0], q[1]), min_ignore_nan(q[2], q[3]));
        let hi = max_ignore_nan(max_ignore_nan(q[0], q[1]), max_ignore_nan(q[2], q[3]));
        Interval::new(down(lo), up(hi))
    }

    /// `|self|` (exact).
    pub fn abs(self) -> Interval {
        if self.is_empty() {
            Interval::EMPTY
        } else if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            self.neg()
        } else {
            Interval::new(0.0, max_nan(-self.lo, self.hi))
        }
    }

    /// `self²`, never negative (tighter than `self * self` when 0 ∈ self).
    pub fn square(self) -> Interval {
        if self.is_empty() {
            return Interval::EMPTY;
        }
        let a = self.abs();
        Interval::new(down(a.lo * a.lo).max(0.0), up(a.hi * a.hi))
    }

    /// `sqrt(self)` over the non-negative part; EMPTY if self < 0.
    pub fn sqrt(self) -> Interval {
        if self.is_empty() || self.hi < 0.0 {
            return Interval::EMPTY;
        }
        let lo = if self.lo <= 0.0 {
            0.0
        } else {
            down(self.lo.sqrt()).max(0.0)
        };
        Interval::new(lo, up(self.hi.sqrt()))
    }

    /// `min(self, o)` (exact; EMPTY if either is).
    pub fn min(self, o: Interval) -> Interval {
        Interval::new(min_nan(self.lo, o.lo), min_nan(self.hi, o.hi))
    }

    /// `max(self, o)` (exact; EMPTY if either is).
    pub fn max(self, o: Interval) -> Interval {
        Interval::new(max_nan(self.lo, o.lo), max_nan(self.hi, o.hi))
    }

    /// `self^n` for integer n: each bound by binary exponentiation with
    /// outward rounding after every step; negative n divides 1 by the
    /// positive power. `self^0` is [1, 1] (as the point semantics give 1).
    pub fn powi(self, n: i32) -> Interval {
        if n == 0 {
            return Interval::point(1.0);
        }
        if self.is_empty() {
            return Interval::EMPTY;
        }
        if n < 0 {
            return Interval::point(1.0).div(self.powi_positive(n.unsigned_abs()));
        }
        self.powi_positive(n as u32)
    }

    fn powi_positive(self, n: u32) -> Interval {
        let up_pow = |m: f64| powi_unsigned(m, n, up);
        let down_pow = |m: f64| powi_unsigned(m, n, |v| down(v).max(0.0));
        if n.is_multiple_of(2) {
            let a = self.abs();
            let lo = if n == 1 { a.lo } else { down_pow(a.lo) };
            Interval::new(lo, up_pow(a.hi))
        } else {
            // Odd powers are increasing: bound each end, keeping signs.
            let lo = if self.lo >= 0.0 {
                down_pow(self.lo)
            } else {
                -up_pow(-self.lo)
            };
            let hi = if self.hi >= 0.0 {
                up_pow(self.hi)
            } else {
                -down_pow(-self.hi)
            };
            Interval::new(lo, hi)
        }
    }
}

mod transcendental;
pub use transcendental::{widen_down, widen_up};
