//! The tightest outward-rounded f64 enclosures of `+ - * /`, `sqrt` and
//! `square` over intervals (IEEE 1788's tightest results), written for
//! the tests with no code from `ibeam::interval`.
//!
//! Each bound is the round-to-nearest result, moved one float (`next_down`
//! / `next_up`) towards the exact value where that is not exactly
//! representable. Which side of the rounded result the exact value lies on
//! is decided exactly, on every target and with no CPU flags:
//! - sums: the error of `fl(a + b)` is itself a float (Fast2Sum recovers it
//!   exactly whenever the sum is finite, subnormals included);
//! - products, quotients and square roots: the exact value's significand
//!   and exponent are compared with the rounded result's as integers
//!   (`a·b` against `r`, `a` against `r·b`, `a` against `r²`). A fused
//!   multiply-add residual would do in the normal range, but where the
//!   error is below the smallest subnormal it rounds to 0 and reports an
//!   inexact result as exact; the integers hold down to 2⁻¹⁰⁷⁴. The
//!   residuals are compared with these integers in tests/tight_oracle.rs.
//!
//! Overflow gives the largest finite float on the inner side and the
//! infinity on the outer; bounds at ±inf mean "unbounded". Intervals are
//! `(lo, hi)` pairs with `lo <= hi`, `lo < +inf` and `hi > -inf`; `None`
//! is the empty set.

use std::cmp::Ordering;

/// An enclosure: `Some((lo, hi))`, or `None` for the empty set.
pub type Tight = Option<(f64, f64)>;

/// The bounds of an exact value whose round-to-nearest result is `r` and
/// which lies `side` of it (`Less`: below `r`).
fn around(r: f64, side: Ordering) -> (f64, f64) {
    match side {
        Ordering::Less => (r.next_down(), r),
        Ordering::Equal => (r, r),
        Ordering::Greater => (r, r.next_up()),
    }
}

/// `(m, e)` with `|x| = m·2^e` (finite `x`).
fn split(x: f64) -> (u128, i32) {
    let bits = x.to_bits() & !(1u64 << 63);
    let biased = (bits >> 52) as i32;
    let frac = u128::from(bits & ((1u64 << 52) - 1));
    if biased == 0 {
        (frac, -1074)
    } else {
        (frac | 1 << 52, biased - 1075)
    }
}

/// `m1·2^e1` against `m2·2^e2`, both positive.
fn cmp_scaled(m1: u128, e1: i32, m2: u128, e2: i32) -> Ordering {
    // The exponent just above the leading bit decides unless it is equal;
    // then the significands, aligned at bit 127, do.
    let top = |m: u128, e: i32| e + 128 - m.leading_zeros() as i32;
    top(m1, e1)
        .cmp(&top(m2, e2))
        .then_with(|| (m1 << m1.leading_zeros()).cmp(&(m2 << m2.leading_zeros())))
}

/// Which side of its rounded result `r` the exact value lies on, given
/// its sign and, for a finite nonzero `r`, `cmp_exact`: its magnitude
/// against `|r|`. An infinite `r` overflowed (the exact value is finite),
/// a zero `r` underflowed (the exact value is not 0).
fn side_of(r: f64, negative: bool, cmp_exact: impl Fn() -> Ordering) -> Ordering {
    let magnitude = if r.is_infinite() {
        Ordering::Less
    } else if r == 0.0 {
        Ordering::Greater
    } else {
        cmp_exact()
    };
    if negative {
        magnitude.reverse()
    } else {
        magnitude
    }
}

/// `[RD(a + b), RU(a + b)]` for finite `a`, `b`.
pub fn add_bounds(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    if s.is_infinite() {
        return around(
            s,
            if s > 0.0 {
                Ordering::Less
            } else {
                Ordering::Greater
            },
        );
    }
    // Fast2Sum: with |big| >= |small|, s - big and the error are exact.
    let (big, small) = if a.abs() >= b.abs() { (a, b) } else { (b, a) };
    let err = small - (s - big);
    around(s, err.partial_cmp(&0.0).expect("finite error"))
}

/// `[RD(a·b), RU(a·b)]` for `a`, `b` not NaN and not 0·inf.
pub fn mul_bounds(a: f64, b: f64) -> (f64, f64) {
    let r = a * b;
    if a == 0.0 || b == 0.0 || a.is_infinite() || b.is_infinite() {
        return (r, r);
    }
    let side = side_of(r, (a < 0.0) != (b < 0.0), || {
        let ((ma, ea), (mb, eb), (mr, er)) = (split(a), split(b), split(r));
        cmp_scaled(ma * mb, ea + eb, mr, er)
    });
    around(r, side)
}

/// `[RD(a/b), RU(a/b)]` for `b != 0`, not both infinite; `x/±inf` is the
/// limit 0.
pub fn div_bounds(a: f64, b: f64) -> (f64, f64) {
    assert!(b != 0.0 && !(a.is_infinite() && b.is_infinite()));
    let r = a / b;
    if a == 0.0 || a.is_infinite() || b.is_infinite() {
        return (r, r);
    }
    // |a|/|b| against |r| is |a| against |r|·|b|.
    let side = side_of(r, (a < 0.0) != (b < 0.0), || {
        let ((ma, ea), (mb, eb), (mr, er)) = (split(a), split(b), split(r));
        cmp_scaled(ma, ea, mr * mb, er + eb)
    });
    around(r, side)
}

/// `[RD(sqrt a), RU(sqrt a)]` for `a >= 0`.
pub fn sqrt_bounds(a: f64) -> (f64, f64) {
    assert!(a >= 0.0);
    let r = a.sqrt();
    if a == 0.0 || a.is_infinite() {
        return (r, r);
    }
    // sqrt(a) against r is a against r².
    let ((ma, ea), (mr, er)) = (split(a), split(r));
    around(r, cmp_scaled(ma, ea, mr * mr, 2 * er))
}

/// A valid interval (see the module docs).
fn valid((lo, hi): (f64, f64)) -> (f64, f64) {
    assert!(
        lo <= hi && lo < f64::INFINITY && hi > f64::NEG_INFINITY,
        "[{lo}, {hi}]"
    );
    (lo, hi)
}

/// `a + b`.
pub fn add(a: (f64, f64), b: (f64, f64)) -> Tight {
    let ((al, ah), (bl, bh)) = (valid(a), valid(b));
    let lo = if al == f64::NEG_INFINITY || bl == f64::NEG_INFINITY {
        f64::NEG_INFINITY
    } else {
        add_bounds(al, bl).0
    };
    let hi = if ah == f64::INFINITY || bh == f64::INFINITY {
        f64::INFINITY
    } else {
        add_bounds(ah, bh).1
    };
    Some((lo, hi))
}

/// `-a` (exact).
pub fn neg(a: (f64, f64)) -> (f64, f64) {
    (-a.1, -a.0)
}

/// `a - b`.
pub fn sub(a: (f64, f64), b: (f64, f64)) -> Tight {
    add(a, neg(valid(b)))
}

/// The hull of `f` at the four corners of `a × b`, each rounded outward;
/// `None` corners (no value) are left out.
fn corners(a: (f64, f64), b: (f64, f64), f: impl Fn(f64, f64) -> Option<(f64, f64)>) -> Tight {
    let all = [(a.0, b.0), (a.0, b.1), (a.1, b.0), (a.1, b.1)];
    let bounds: Vec<(f64, f64)> = all.iter().filter_map(|&(x, y)| f(x, y)).collect();
    let lo = bounds.iter().map(|b| b.0).fold(f64::INFINITY, f64::min);
    let hi = bounds.iter().map(|b| b.1).fold(f64::NEG_INFINITY, f64::max);
    Some((lo, hi))
}

/// `a · b`: the hull of the corner products, 0·inf taken as 0 (a zero end
/// against an unbounded one: products of that end are all 0).
pub fn mul(a: (f64, f64), b: (f64, f64)) -> Tight {
    let (a, b) = (valid(a), valid(b));
    corners(a, b, |x, y| {
        Some(if x == 0.0 || y == 0.0 {
            (0.0, 0.0)
        } else {
            mul_bounds(x, y)
        })
    })
}

/// `a / b` over the nonzero part of `b`: empty for `b = [0, 0]`, a
/// half-line when 0 is an end of `b`, the whole line when it is inside
/// (unless `a = [0, 0]`, which gives `[0, 0]`).
pub fn div(a: (f64, f64), b: (f64, f64)) -> Tight {
    let ((al, ah), (bl, bh)) = (valid(a), valid(b));
    let (inf, entire) = (f64::INFINITY, Some((f64::NEG_INFINITY, f64::INFINITY)));
    if bl == 0.0 && bh == 0.0 {
        return None;
    }
    if al == 0.0 && ah == 0.0 {
        return Some((0.0, 0.0));
    }
    if bl > 0.0 || bh < 0.0 {
        // inf/inf is never an extreme: an unbounded divisor's extremes
        // come from its finite end.
        return corners(a, b, |x, y| {
            (x.is_finite() || y.is_finite()).then(|| div_bounds(x, y))
        });
    }
    if bl < 0.0 && bh > 0.0 {
        return entire;
    }
    // 0 is one end of b: the quotients keep one sign and are unbounded on
    // the far side (a holds a nonzero value of that sign).
    match (al >= 0.0, ah <= 0.0, bl == 0.0) {
        (true, _, true) => Some((div_bounds(al, bh).0, inf)),
        (_, true, true) => Some((-inf, div_bounds(ah, bh).1)),
        (true, _, false) => Some((-inf, div_bounds(al, bl).1)),
        (_, true, false) => Some((div_bounds(ah, bl).0, inf)),
        _ => entire,
    }
}

/// `sqrt(a)` over the non-negative part of `a`; empty if there is none.
pub fn sqrt(a: (f64, f64)) -> Tight {
    let (lo, hi) = valid(a);
    if hi < 0.0 {
        return None;
    }
    Some((sqrt_bounds(lo.max(0.0)).0, sqrt_bounds(hi).1))
}

/// `a²` (never negative, unlike `a · a` when 0 is inside `a`).
pub fn square(a: (f64, f64)) -> Tight {
    let (lo, hi) = valid(a);
    let sq = |x: f64| mul_bounds(x.abs(), x.abs());
    Some(if lo >= 0.0 {
        (sq(lo).0, sq(hi).1)
    } else if hi <= 0.0 {
        (sq(hi).0, sq(lo).1)
    } else {
        (0.0, sq(lo).1.max(sq(hi).1))
    })
}

/// `|a|` (exact).
pub fn abs(a: (f64, f64)) -> (f64, f64) {
    let (lo, hi) = valid(a);
    if lo >= 0.0 {
        (lo, hi)
    } else if hi <= 0.0 {
        (-hi, -lo)
    } else {
        (0.0, hi.max(-lo))
    }
}

/// `min(a, b)` (exact).
pub fn min(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0.min(b.0), a.1.min(b.1))
}

/// `max(a, b)` (exact).
pub fn max(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0.max(b.0), a.1.max(b.1))
}

/// A non-decreasing step function exact in f64 (floor, ceil, round, sign)
/// at both ends: its tightest result.
pub fn steps(a: (f64, f64), f: impl Fn(f64) -> f64) -> (f64, f64) {
    let (lo, hi) = valid(a);
    (f(lo), f(hi))
}

/// -1, 0 or 1 as `x` is negative, zero (either sign) or positive.
pub fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Two floats out from `v`, or 2⁻⁵¹⁰ near zero: how far outside the
/// tightest bound `ibeam::interval` may put its own (see its module docs).
pub fn down2(v: f64) -> f64 {
    let near_zero = (v - 2f64.powi(-510)).next_down();
    v.next_down().next_down().min(near_zero)
}

/// See [`down2`].
pub fn up2(v: f64) -> f64 {
    let near_zero = (v + 2f64.powi(-510)).next_up();
    v.next_up().next_up().max(near_zero)
}

/// Whether `(lo, hi)` (an interval computed by the code under test, NaN
/// bounds for empty) holds the tightest enclosure and is at most two
/// floats (2⁻⁵¹⁰ near zero) wider on each side; `Err` says how not.
pub fn tight_enough((lo, hi): (f64, f64), want: Tight) -> Result<(), String> {
    let empty = lo.is_nan() || hi.is_nan();
    let Some((tl, th)) = want else {
        return if empty {
            Ok(())
        } else {
            Err(format!("[{lo:e}, {hi:e}] where the result is empty"))
        };
    };
    if empty || !(lo <= tl && th <= hi) {
        return Err(format!(
            "[{lo:e}, {hi:e}] does not contain the tightest [{tl:e}, {th:e}]"
        ));
    }
    if lo < down2(tl) || hi > up2(th) {
        return Err(format!(
            "[{lo:e}, {hi:e}] is more than 2 ulps wider than the tightest [{tl:e}, {th:e}]"
        ));
    }
    Ok(())
}
