//! Outward-rounded interval arithmetic over f64.
//!
//! # Guarantee
//! For every op `F` here and every box of argument intervals, `F(A, B)`
//! contains `f(a, b)` for every `a ∈ A`, `b ∈ B` where the point op `f`
//! (see `ir::Op`) gives a real (finite or not NaN) value. Rounding
//! error is covered: the hardware computes in round-to-nearest, and each
//! bound is then moved outward by one or two ulps ([`up`], [`down`]; by at
//! most 2⁻⁵¹⁰ within 2⁻⁴⁵⁹ of zero, which keeps subnormals out), which
//! covers the half-ulp error of a correctly rounded `+ - * / sqrt`.
//! Transcendentals call `libm`, whose stated error is below 1 ulp; we widen
//! their results by [`TRANSCENDENTAL_ULPS`] ulps. The JIT (`eval::jit`)
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

/// `2^-52`: `|v| * STEP` is at least one ulp of any normal `v`.
const STEP: f64 = f64::EPSILON;
/// `2^-511`: at least one ulp of every `v` below `2^-459` in magnitude,
/// where `|v|·2⁻⁵²` falls under it; the smallest power of two whose
/// square is a normal number.
///
/// Why not the smallest subnormal (one ulp of zero, so the tightest step
/// there): every bound that is exactly 0 (a square's or an absolute
/// value's low end, `max(0, ·)`, a sum of equal and opposite terms, a
/// constant derivative) then became a subnormal, and so did its products;
/// Intel cores take a microcode assist on each operation that reads or
/// writes one. Stepping by the smallest normal instead kept the products
/// of such widened zeros subnormal (2⁻¹⁰²² · 0.5); from 2⁻⁵¹¹, a product
/// of two of them is still normal. `ibeam render … --threads 1` at 1024²
/// on a 16-core Xeon, the same PNGs for all three steps: colonnade
/// 2.85–2.98 s (subnormal step) → 1.93–2.13 s (2⁻¹⁰²²) → 1.10–1.21 s
/// (2⁻⁵¹¹); 100 spheres 1.04 → 0.80 → 0.57–0.61 s. No change on this
/// project's AMD machine. Near zero, bounds then move out by about
/// 1.5e-154 instead of 4.9e-324: far below
/// anything a render or a root decision reads.
pub(crate) const FLOOR_STEP: f64 = f64::from_bits(0x2000_0000_0000_0000);

/// An upper bound strictly above `v` (for finite `v`):
/// `c + max(|c|·2⁻⁵², 2⁻⁵¹¹)` in round-to-nearest, where
/// `c = max(-MAX, v)`.
///
/// Why it is sound: `|c|·2⁻⁵²` is at least one ulp of a normal `c` (exact,
/// or rounded to a multiple of 2⁻¹⁰⁷⁴ no smaller than that ulp, itself such
/// a multiple), and `2⁻⁵¹¹` is at least one ulp of any `c` below `2⁻⁴⁵⁹`
/// in magnitude (subnormals included), so the exact sum is at least the
/// next float above `c`, which is representable; rounding to nearest is
/// monotone, so the result is `>= next_up(v)` and covers the half-ulp
/// error of the correctly rounded op that produced `v`. It is at most two
/// ulps above `v` where `|v| >= 2⁻⁴⁵⁹`, and at most `2⁻⁵¹⁰` above it
/// nearer zero. `up(+inf) = +inf` and `up(NaN)` is NaN; `up(-inf)` is just
/// above `-MAX`, the right bound when a sum or product overflowed to
/// `-inf`.
/// It is branch-free and costs the same in both lanes of a SIMD register,
/// which is why the JIT's intervals use it (see `eval::jit`); this
/// function is the reference the JIT must match bit for bit.
#[inline]
pub fn up(v: f64) -> f64 {
    let c = mx(-f64::MAX, v);
    c + mx(c.abs() * STEP, FLOOR_STEP)
}

/// An upper bound of the real sum or difference that rounded to `v`:
/// `c + |c|·2⁻⁵²` in round-to-nearest, with `c = max(-MAX, v)`; [`up`]
/// without its floor, so an exact zero stays zero.
///
/// Why it is sound: an addition is exact where its result is zero or
/// subnormal (both operands are multiples of 2⁻¹⁰⁷⁴, and so is the sum,
/// which then needs no rounding: `x + y` rounds to 0 only when x = −y),
/// and for a normal result its error is at most half an ulp of `c`, while
/// `|c|·2⁻⁵²` is at least one ulp of `c`, so the bound is at or above the
/// next float above `c` (see [`up`]). The floor of `up` stays where it is
/// needed, on products and quotients, which can underflow to 0.
///
/// Why it matters: a directional derivative along a camera axis adds
/// exact zeros (dx/dt = 0), and `up` turned each into ±2⁻⁵¹¹; the
/// beam's inclusion test then saw dF/dt reach 6.6e-153 above zero on the
/// edge-on faces of colonnade and split 5,000 blocks into single rays.
///
/// A NaN `c` (an EMPTY bound) meets a NaN step, and the sum's NaN may
/// carry either one's sign and payload, depending on how the compiler
/// orders the addition: NaN payloads are not part of the semantics (every
/// bit-for-bit comparison takes any NaN as equal to any other).
#[inline]
pub fn up_sum(v: f64) -> f64 {
    let c = mx(-f64::MAX, v);
    c + c.abs() * STEP
}

/// A lower bound below `v`: `-up(-v)` (see [`up`]).
#[inline]
pub fn down(v: f64) -> f64 {
    -up(-v)
}

/// `x > y ? x : y`, the x86 `maxsd`/`maxpd` rule: `y` when either is NaN
/// and on ties (so the sign of a zero result is fixed). The interval ops
/// are written with these two so that the JIT's SIMD code gives the same
/// bits.
#[inline]
pub fn mx(x: f64, y: f64) -> f64 {
    if x > y { x } else { y }
}

/// `x < y ? x : y`, the x86 `minsd`/`minpd` rule (see [`mx`]).
#[inline]
pub fn mn(x: f64, y: f64) -> f64 {
    if x < y { x } else { y }
}

/// `mx` that ignores a NaN `y` (NaN only if both are NaN).
#[inline]
fn mx_ignore_nan(x: f64, y: f64) -> f64 {
    if y.is_nan() { x } else { mx(x, y) }
}

/// NaN when `a` or `b` is NaN, else `r`: EMPTY propagating lane by lane.
#[inline]
fn nan_if(a: f64, b: f64, r: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        r
    }
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
        return 1.0 / powi_unsigned(x, n.unsigned_abs());
    }
    powi_unsigned(x, n as u32)
}

fn powi_unsigned(x: f64, n: u32) -> f64 {
    binary_pow(x, n, |a, b| a * b)
}

/// x^n (n >= 0; 1 for n = 0) by binary exponentiation with `mul` as the
/// product: the one algorithm behind the point `powi` and [`pow_up`], and
/// unrolled the same way by the JIT.
fn binary_pow(x: f64, mut n: u32, mul: impl Fn(f64, f64) -> f64) -> f64 {
    let mut result: Option<f64> = None;
    let mut base = x;
    while n > 0 {
        if n & 1 == 1 {
            result = Some(match result {
                None => base,
                Some(r) => mul(r, base),
            });
        }
        n >>= 1;
        if n > 0 {
            base = mul(base, base);
        }
    }
    result.unwrap_or(1.0)
}

/// An upper bound of `sign(v)·|v|^n` (n >= 1): binary exponentiation where
/// every product is `x·|y|`, so the sign of `v` rides along in one factor,
/// rounded with [`up`]. For `v >= 0` each step bounds a magnitude from
/// above; for `v < 0` it bounds `-magnitude` from above, i.e. the
/// magnitude from below, and `|y|` of such a factor is again a lower
/// bound of its magnitude, so every product stays an upper bound.
pub(crate) fn pow_up(v: f64, n: u32) -> f64 {
    binary_pow(v, n, |a, b| up(a * b.abs()))
}

// Named methods rather than operator traits: every call site of an
// outward-rounded op stays visible as such.
//
// The ops are written on the "lanes" of an interval, `(-lo, hi)`: both are
// upper bounds (of -x and of x), so one rounding, `up`, serves both, and
// the JIT keeps an interval in one SIMD register in this form. Each method
// here is the scalar twin of its JIT lowering, step by step.
#[allow(clippy::should_implement_trait)]
impl Interval {
    /// `(-lo, hi)`.
    #[inline]
    pub fn lanes(self) -> (f64, f64) {
        (-self.lo, self.hi)
    }

    /// The interval whose lanes are `(n, h)`: `[-n, h]`.
    #[inline]
    pub fn from_lanes(n: f64, h: f64) -> Interval {
        Interval { lo: -n, hi: h }
    }

    /// `-self` (exact).
    #[inline]
    pub fn neg(self) -> Interval {
        Interval::new(-self.hi, -self.lo)
    }

    /// `self + o` (each bound rounded out by [`up_sum`]).
    #[inline]
    pub fn add(self, o: Interval) -> Interval {
        let ((an, ah), (bn, bh)) = (self.lanes(), o.lanes());
        Interval::from_lanes(up_sum(an + bn), up_sum(ah + bh))
    }

    /// `self - o` (each bound rounded out by [`up_sum`]).
    #[inline]
    pub fn sub(self, o: Interval) -> Interval {
        let ((an, ah), (bn, bh)) = (self.lanes(), o.lanes());
        Interval::from_lanes(up_sum(an + bh), up_sum(ah + bn))
    }

    /// Whether this is the point interval [0, 0] (either zero's sign).
    #[inline]
    pub fn is_zero(self) -> bool {
        self.lo == 0.0 && self.hi == 0.0
    }

    /// `[0, 0]` as the lanes `(+0, +0)`: the exact product of a factor
    /// [0, 0] and any non-EMPTY interval (0 times a real is 0), and the
    /// exact quotient of [0, 0] by a divisor without 0. Rounding it out
    /// would turn every zero partial derivative into ±2⁻⁵¹¹.
    const ZERO_LANES: Interval = Interval { lo: -0.0, hi: 0.0 };

    /// Lanes of the hull of the four bound products (or quotients, with
    /// `op` = division) of non-EMPTY operands: both lanes are maxima, of
    /// the negated and of the plain candidates, in the JIT's order. A NaN
    /// candidate (0·inf, or inf/inf) is skipped and 0 joins the hull
    /// instead: 0·inf means 0 is in a factor, so 0 is a product; inf/inf
    /// means the divisor is unbounded, so quotients come arbitrarily close
    /// to 0. One operand [0, 0] and the other infinite gives [0, 0] (then
    /// rounded).
    fn hull4(self, o: Interval, op: impl Fn(f64, f64) -> f64) -> (f64, f64) {
        let (an, ah) = self.lanes();
        let (bl, bh) = (o.lo, o.hi);
        let (al, nah) = (-an, -ah);
        let lane = |p: [f64; 4]| {
            let m = p.iter().fold(f64::NEG_INFINITY, |acc, &x| mx(x, acc));
            let any_nan = p.iter().any(|x| x.is_nan());
            up(mx(if any_nan { 0.0 } else { f64::NEG_INFINITY }, m))
        };
        let n = lane([op(an, bl), op(an, bh), op(nah, bl), op(nah, bh)]);
        let h = lane([op(ah, bh), op(ah, bl), op(al, bh), op(al, bl)]);
        (n, h)
    }

    /// `self * o`: hull of the four bound products, ignoring the NaN of
    /// 0·inf, each bound then rounded outward; EMPTY if either is, and
    /// exactly [0, 0] where a factor is [0, 0] and the other is not EMPTY.
    #[inline]
    pub fn mul(self, o: Interval) -> Interval {
        let finite = |i: Interval| i.lo.is_finite() && i.hi.is_finite();
        if (self.is_zero() && !o.is_empty()) || (o.is_zero() && !self.is_empty()) {
            return Interval::ZERO_LANES;
        }
        if finite(self) && finite(o) {
            // No candidate can be NaN, so the lanes are `-min` and `max`
            // of the products: the same values as `hull4` finds (a zero's
            // sign may differ, which `up` erases), with a quarter of the
            // work. The tracer multiplies finite boxes all the time.
            let p = [
                self.lo * o.lo,
                self.lo * o.hi,
                self.hi * o.lo,
                self.hi * o.hi,
            ];
            let lo = mn(mn(p[0], p[1]), mn(p[2], p[3]));
            let hi = mx(mx(p[0], p[1]), mx(p[2], p[3]));
            return Interval::from_lanes(up(-lo), up(hi));
        }
        if self.is_empty() || o.is_empty() {
            return Interval::EMPTY;
        }
        let (n, h) = self.hull4(o, |x, y| x * y);
        Interval::from_lanes(n, h)
    }

    /// `self * t` for `t` a finite interval of positive numbers (a ray
    /// parameter's): the same bounds as [`Interval::mul`] with half the
    /// products. Every product with `self.lo` is at most the one with
    /// `self.hi` at the same factor (rounding is monotone), so the least
    /// of the four is one of `self.lo`'s and the greatest one of
    /// `self.hi`'s. Any other `t` takes [`Interval::mul`].
    #[inline]
    pub fn mul_by_positive(self, t: Interval) -> Interval {
        if t.lo > 0.0
            && t.hi < f64::INFINITY
            && self.lo.is_finite()
            && self.hi.is_finite()
            && !self.is_zero()
        {
            let lo = mn(self.lo * t.lo, self.lo * t.hi);
            let hi = mx(self.hi * t.lo, self.hi * t.hi);
            return Interval::from_lanes(up(-lo), up(hi));
        }
        self.mul(t)
    }

    /// `self · [t, t]`, the same bits as `self.mul(Interval::point(t))`
    /// with half the products (ray boxes at a fixed parameter).
    #[inline]
    pub fn mul_point(self, t: f64) -> Interval {
        if t.is_finite() && self.lo.is_finite() && self.hi.is_finite() {
            if t == 0.0 || self.is_zero() {
                return Interval::ZERO_LANES;
            }
            // `mul`'s four products are these two, each twice.
            let (a, b) = (self.lo * t, self.hi * t);
            return Interval::from_lanes(up(-mn(a, b)), up(mx(a, b)));
        }
        self.mul(Interval::point(t))
    }

    /// `self / o` over the nonzero part of `o` (a quotient by 0 is not
    /// real). When 0 is outside `o`: the hull of the four quotients (EMPTY
    /// if either operand is). Otherwise see [`Interval::div_by_zero_part`].
    pub fn div(self, o: Interval) -> Interval {
        if o.lo > 0.0 || o.hi < 0.0 {
            if self.is_empty() || o.is_empty() {
                return Interval::EMPTY;
            }
            if self.is_zero() {
                return Interval::ZERO_LANES;
            }
            let (n, h) = self.hull4(o, |x, y| x / y);
            return Interval::from_lanes(n, h);
        }
        self.div_by_zero_part(o)
    }

    /// `self / o` when 0 is in `o` or either is EMPTY (the JIT calls this
    /// out of line): EMPTY when o = [0, 0], a half-line when 0 is an end
    /// of `o`, the whole line when 0 is inside `o` (unless self = [0, 0]).
    pub fn div_by_zero_part(self, o: Interval) -> Interval {
        if self.is_empty() || o.is_empty() || (o.lo == 0.0 && o.hi == 0.0) {
            return Interval::EMPTY;
        }
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
        let nonpositive = |u: f64| if u < 0.0 { u } else { 0.0 };
        if self.lo >= 0.0 {
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
        }
    }

    /// `|self|` (exact): lanes `(min(-lo, hi, 0), max(-lo, hi))`, i.e.
    /// `[max(lo, -hi, 0), max(-lo, hi)]`. An EMPTY operand keeps a NaN lane.
    #[inline]
    pub fn abs(self) -> Interval {
        let (n, h) = self.lanes();
        Interval::from_lanes(mn(0.0, mn(n, h)), mx(h, n))
    }

    /// `self²`, never negative (tighter than `self * self` when 0 ∈ self).
    #[inline]
    pub fn square(self) -> Interval {
        let (n, h) = self.abs().lanes();
        Interval::from_lanes(mn(0.0, up(n * n.abs())), up(h * h.abs()))
    }

    /// `sqrt(self)` over the non-negative part; EMPTY if self < 0.
    #[inline]
    pub fn sqrt(self) -> Interval {
        let n = mn(0.0, up(-mx(0.0, self.lo).sqrt()));
        let h = up(self.hi.sqrt());
        if n.is_nan() || h.is_nan() {
            return Interval::EMPTY;
        }
        Interval::from_lanes(n, h)
    }

    /// `min(self, o)` (exact; a bound is NaN where either operand's is).
    #[inline]
    pub fn min(self, o: Interval) -> Interval {
        let ((an, ah), (bn, bh)) = (self.lanes(), o.lanes());
        Interval::from_lanes(nan_if(an, bn, mx(an, bn)), nan_if(ah, bh, mn(ah, bh)))
    }

    /// `max(self, o)` (exact; a bound is NaN where either operand's is).
    #[inline]
    pub fn max(self, o: Interval) -> Interval {
        let ((an, ah), (bn, bh)) = (self.lanes(), o.lanes());
        Interval::from_lanes(nan_if(an, bn, mn(an, bn)), nan_if(ah, bh, mx(ah, bh)))
    }

    /// The smallest interval holding both, ignoring an EMPTY one (EMPTY
    /// only if both are).
    pub fn hull(self, o: Interval) -> Interval {
        let ((an, ah), (bn, bh)) = (self.lanes(), o.lanes());
        Interval::from_lanes(mx_ignore_nan(an, bn), mx_ignore_nan(ah, bh))
    }

    /// `self^n` for integer n: each lane by [`pow_up`] (even powers from
    /// `|self|`, whose lower lane is then clamped so the result is never
    /// negative); negative n divides 1 by the positive power. `self^0` is
    /// [1, 1] (as the point semantics give 1).
    pub fn powi(self, n: i32) -> Interval {
        if n == 0 {
            return Interval::point(1.0);
        }
        let m = n.unsigned_abs();
        let p = if m.is_multiple_of(2) {
            let (x, y) = self.abs().lanes();
            Interval::from_lanes(mn(0.0, pow_up(x, m)), pow_up(y, m))
        } else {
            let (x, y) = self.lanes();
            Interval::from_lanes(pow_up(x, m), pow_up(y, m))
        };
        if n < 0 {
            return Interval::point(1.0).div(p);
        }
        p
    }
}

pub mod affine;
pub mod boxes;
mod elementary;
pub mod exp;
pub mod form;
pub mod quadratic;
mod steps;
mod transcendental;
pub use steps::{rem_euclid, sign};
pub use transcendental::{widen_down, widen_up};
