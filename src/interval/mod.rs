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
//! (both bounds NaN), and EMPTY propagates through every op, so a box on
//! which f is undefined everywhere is rejected (it holds no root).
//! Division by an interval containing 0 returns the whole line.
//! Infinities are not real values: a bound at ±inf means "unbounded".

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
