//! Each op's affine rule: what reduced affine arithmetic
//! ([`crate::interval::affine`]) makes of it, beside its interval rule in
//! [`super::semantics`].
//!
//! # The value each op carries
//! An [`AffineValue`] is a form and an interval of the same values. Every
//! rule computes both: the interval by the op's interval rule over its
//! operands' intervals, the form by the affine rule below, and keeps
//! their intersection as the interval. Computing both costs one interval
//! op per op (small beside the form's) and pays three times: the result
//! is never wider than the interval rule's, so affine never loses to
//! intervals in width; the decisions that need a range (a `min` decided,
//! the sign of `abs`'s operand, a domain's edge, the interval a
//! linearisation is taken over) read the tightest range known; and an op
//! with no affine rule converts that interval back into a form.
//!
//! The second-order form ([`Form::MEET_EACH_OP`] false) meets them only
//! where a rule reads the range, and at the root ([`tightened`]): after
//! `+`, `-`, `*`, `neg`, squares and powers by products its value carries
//! the interval rule's result alone.
//!
//! # Rules
//! - Exact: `neg`, `+`, `-`, `min`/`max` decided by the ranges, `abs` of
//!   an operand of one sign, `powi(_, 0 | 1)`.
//! - Products: `*` and squares by [`Affine::mul`] and [`Affine::square`].
//! - Chebyshev (min-max) linearisations over the operand's range, for the
//!   convex or concave ones: `exp`, `sqrt`, `ln`, `powi(_, n)` (|n| ≥ 3,
//!   or negative, where the range has one sign), and the reciprocal in
//!   `a / b = a · (1/b)`. The error is bounded with outward-rounded
//!   intervals: the chord's end values above (convex case) and the tangent
//!   at the point where the slope is the chord's below.
//! - Mean-value linearisations (slope: the midpoint of the derivative's
//!   interval) for `sin`, `cos`, `tan`, `asin`, `acos`, `atan`, `sinh`,
//!   `cosh`, `tanh`, and odd `powi` across 0.
//! - Everything else (`floor`, `ceil`, `round`, `sign`, `mod`, `atan2`,
//!   `pow`, undecided `min`/`max`, `abs` across 0, a quotient by a range
//!   holding 0, a domain edge inside the range) takes the interval rule
//!   and turns it into a form of pure error.
//!
//! # Forms
//! The rules are written once for any [`Form`]: the first-order
//! [`Affine`] forms (over a box, or along a ray) and the second-order
//! [`Quadratic`] form along a ray. They differ in one rule: a power
//! `n ≥ 3` of a form that offers [`Form::power`] (the quadratic) is taken
//! by products, which keep each step's second-order terms, where a
//! first-order form takes the Chebyshev linearisation below.
//!
//! # Undefined and partly defined results
//! The interval carried is always the interval rule's result over the
//! operands' intervals, intersected with the form's range. So an op is
//! EMPTY (undefined on the whole box) exactly where its interval rule
//! says so over those intervals, and a partly defined op (`sqrt` of a
//! range reaching below 0, `ln` of one reaching 0, a quotient by a range
//! holding 0) takes the interval rule's defined part, as
//! [`super::semantics`] describes; the linearisations run only where the
//! whole range lies inside the domain. Where the form and the interval
//! do not meet (no value is real there), the interval rule's result is
//! kept rather than EMPTY, so that an EMPTY result always means what the
//! interval rule means by it.
//!
//! # Rounding of the point ops
//! A form encloses the exact op applied to the operand values; the point
//! evaluation rounds each op. Each rule widens its form by the point op's
//! rounding (`+ - * / sqrt`: one ulp of the largest magnitude in range;
//! `powi`: one per product; the transcendentals: [`TRANSCENDENTAL_SLACK`]
//! ulps), so the forms enclose the values the point evaluation computes.

use super::semantics::{interval_binary, interval_unary};
use super::{BinaryOp, Op, UnaryOp};
use crate::interval::affine::{Affine, meet, ulps_of};
use crate::interval::form::Form;
use crate::interval::quadratic::Quadratic;
use crate::interval::{Interval, mx, up_sum};

/// A form and an interval of the same values (see the module doc);
/// EMPTY where the interval is.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FormValue<F> {
    /// The form.
    pub form: F,
    /// The interval, intersected with the form's range.
    pub range: Interval,
}

/// A reduced affine form in `N` noise symbols and its interval.
pub type AffineValue<const N: usize = 3> = FormValue<Affine<N>>;

/// A second-order form along a ray and its interval.
pub type QuadraticValue = FormValue<Quadratic>;

/// Ulps by which a transcendental's form is widened for its point op:
/// libm (and `interval::exp::exp`) is within 1 ulp of the real value,
/// and the rest covers the magnitude bound's own rounding.
pub const TRANSCENDENTAL_SLACK: u32 = 4;

impl<F: Form> FormValue<F> {
    /// The empty set.
    pub const EMPTY: FormValue<F> = FormValue {
        form: F::UNBOUNDED,
        range: Interval::EMPTY,
    };

    /// The constant `c` (EMPTY for NaN, as its interval).
    pub fn constant(c: f64) -> FormValue<F> {
        let range = Interval::point(c);
        if range.is_empty() {
            return FormValue::EMPTY;
        }
        FormValue {
            form: F::constant(c),
            range,
        }
    }

    /// Whether it is EMPTY.
    pub fn is_empty(&self) -> bool {
        self.range.is_empty()
    }
}

impl<const N: usize> AffineValue<N> {
    /// Coordinate `axis` over the box side `side`.
    pub fn var(side: Interval, axis: usize) -> AffineValue<N> {
        if side.is_empty() {
            return AffineValue::EMPTY;
        }
        AffineValue {
            form: Affine::var(side, axis),
            range: side,
        }
    }
}

impl AffineValue<1> {
    /// Coordinate `o + d·t` of a ray over the parameter range `t`, whose
    /// interval is `side` (see [`Affine::along`]).
    pub fn along(o: Interval, d: Interval, t: Interval, side: Interval) -> AffineValue<1> {
        if side.is_empty() {
            return AffineValue::EMPTY;
        }
        AffineValue {
            form: Affine::<1>::along(o, d, t),
            range: side,
        }
    }
}

impl QuadraticValue {
    /// Coordinate `o + d·t` of a ray over the parameter range `t`, whose
    /// interval is `side` (see [`Quadratic::along`]).
    pub fn along(o: Interval, d: Interval, t: Interval, side: Interval) -> QuadraticValue {
        if side.is_empty() {
            return QuadraticValue::EMPTY;
        }
        FormValue {
            form: Quadratic::along(o, d, t),
            range: side,
        }
    }
}

/// The result of an op whose interval rule gives `iv` and whose affine
/// rule gives `form`, before the point op's rounding of `ulps` ulps:
/// see the module doc.
fn finish<F: Form>(form: F, iv: Interval, ulps: u32) -> FormValue<F> {
    if iv.is_empty() {
        return FormValue::EMPTY;
    }
    // The interval rule alone, as a form of pure error: built only where
    // the form says nothing (most ops keep their form).
    let plain = || FormValue {
        form: F::from_interval(iv),
        range: iv,
    };
    if !form.is_bounded() {
        return plain();
    }
    // The form's reach is summed once: this runs after every op, and
    // the radius and the range each summed it again (a fifth of an
    // affine evaluation's time).
    let reach = form.spread();
    let mut e = form.error();
    if ulps > 0 {
        // The largest magnitude of the values, by the interval, and by the
        // form where that is tighter; the second-order form skips the
        // form's bound where the interval's is finite (its chain of
        // roundings slowed every op along a ray, deciding no clip there).
        let by_iv = mx(iv.lo.abs(), iv.hi.abs());
        let m = if F::MEET_EACH_OP || !by_iv.is_finite() {
            up_sum(form.centre().abs() + up_sum(reach + e)).min(by_iv)
        } else {
            by_iv
        };
        e = up_sum(e + ulps_of(m, ulps));
        if !e.is_finite() {
            return plain();
        }
    }
    let form = form.with_error(e);
    if !F::MEET_EACH_OP {
        return FormValue { form, range: iv };
    }
    match meet(iv, form.range_within(reach)) {
        Some(range) => FormValue { form, range },
        None => plain(),
    }
}

/// `v`'s interval met with its form's range, as [`finish`] meets every
/// op's (where they do not meet, the interval alone, as there).
pub fn tightened<F: Form>(v: &FormValue<F>) -> FormValue<F> {
    if F::MEET_EACH_OP || v.is_empty() || !v.form.is_bounded() {
        return *v;
    }
    match meet(v.range, v.form.range_within(v.form.spread())) {
        Some(range) => FormValue {
            form: v.form,
            range,
        },
        None => FormValue {
            form: F::from_interval(v.range),
            range: v.range,
        },
    }
}

/// The interval rule alone, as a form of pure error.
fn fallback<F: Form>() -> (F, u32) {
    (F::UNBOUNDED, 0)
}

/// Affine rule of a one-operand op.
pub fn affine_unary<F: Form>(op: UnaryOp, a: &FormValue<F>) -> FormValue<F> {
    let held;
    let a = match op {
        UnaryOp::Neg | UnaryOp::Square => a,
        _ => {
            held = tightened(a);
            &held
        }
    };
    let iv = interval_unary(op, a.range);
    if iv.is_empty() {
        return FormValue::EMPTY;
    }
    let r = a.range;
    let t = TRANSCENDENTAL_SLACK;
    let (form, ulps) = match op {
        UnaryOp::Neg => (a.form.neg(), 0),
        UnaryOp::Abs if r.lo >= 0.0 => (a.form, 0),
        UnaryOp::Abs if r.hi <= 0.0 => (a.form.neg(), 0),
        UnaryOp::Square => (a.form.square(), 1),
        UnaryOp::Sqrt if r.lo >= 0.0 => (chebyshev(a, &SQRT), 1),
        UnaryOp::Exp => (chebyshev(a, &EXP), t),
        UnaryOp::Ln if r.lo > 0.0 => (chebyshev(a, &LN), t),
        UnaryOp::Asin | UnaryOp::Acos if r.lo < -1.0 || r.hi > 1.0 => fallback(),
        UnaryOp::Sin
        | UnaryOp::Cos
        | UnaryOp::Tan
        | UnaryOp::Asin
        | UnaryOp::Acos
        | UnaryOp::Atan
        | UnaryOp::Sinh
        | UnaryOp::Cosh
        | UnaryOp::Tanh => (
            mean_value(a, |i| interval_unary(op, i), |i| derivative(op, i)),
            t,
        ),
        _ => fallback(),
    };
    finish(form, iv, ulps)
}

/// The derivative's interval over `i` of a smooth one-operand op.
fn derivative(op: UnaryOp, i: Interval) -> Interval {
    let one = Interval::point(1.0);
    match op {
        UnaryOp::Sin => i.cos(),
        UnaryOp::Cos => i.sin().neg(),
        UnaryOp::Tan => one.add(i.tan().square()),
        UnaryOp::Asin => one.div(one.sub(i.square()).sqrt()),
        UnaryOp::Acos => one.div(one.sub(i.square()).sqrt()).neg(),
        UnaryOp::Atan => one.div(one.add(i.square())),
        UnaryOp::Sinh => i.cosh(),
        UnaryOp::Cosh => i.sinh(),
        UnaryOp::Tanh => one.sub(i.tanh().square()),
        _ => Interval::ENTIRE,
    }
}

/// Affine rule of a two-operand op.
pub fn affine_binary<F: Form>(op: BinaryOp, a: &FormValue<F>, b: &FormValue<F>) -> FormValue<F> {
    let held;
    let (a, b) = match op {
        BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul => (a, b),
        _ => {
            held = [tightened(a), tightened(b)];
            (&held[0], &held[1])
        }
    };
    let iv = interval_binary(op, a.range, b.range);
    if iv.is_empty() {
        return FormValue::EMPTY;
    }
    let (ra, rb) = (a.range, b.range);
    let (form, ulps) = match op {
        BinaryOp::Add => (a.form.add(&b.form), 1),
        BinaryOp::Sub => (a.form.sub(&b.form), 1),
        // A product by an exact constant (an expanded polynomial's
        // coefficients) scales the form: no cross terms to fold.
        BinaryOp::Mul if exact_constant(&b.form) => (a.form.linear(b.form.centre(), 0.0, 0.0), 1),
        BinaryOp::Mul if exact_constant(&a.form) => (b.form.linear(a.form.centre(), 0.0, 0.0), 1),
        BinaryOp::Mul => (a.form.mul(&b.form), 1),
        BinaryOp::Div if rb.lo > 0.0 || rb.hi < 0.0 => (a.form.mul(&chebyshev(b, &RECIP)), 1),
        // On a tie both operands are the same number: either form holds.
        BinaryOp::Min if ra.hi <= rb.lo => (a.form, 0),
        BinaryOp::Min if rb.hi <= ra.lo => (b.form, 0),
        BinaryOp::Max if ra.lo >= rb.hi => (a.form, 0),
        BinaryOp::Max if rb.lo >= ra.hi => (b.form, 0),
        _ => fallback(),
    };
    finish(form, iv, ulps)
}

/// Whether `f` is one exact number: no noise terms and no error.
fn exact_constant<F: Form>(f: &F) -> bool {
    f.spread() == 0.0 && f.error() == 0.0
}

/// Affine rule of `powi(a, n)`.
pub fn affine_powi<F: Form>(a: &FormValue<F>, n: i32) -> FormValue<F> {
    affine_powi_sharing(a, n, &mut Vec::new())
}

/// [`affine_powi`], the same value, with the squares of `a`'s form shared
/// through `squares` (see [`Form::power_sharing`]): empty, or what earlier
/// powers of this very value left there.
pub fn affine_powi_sharing<F: Form>(
    a: &FormValue<F>,
    n: i32,
    squares: &mut Vec<F>,
) -> FormValue<F> {
    let iv = a.range.powi(n);
    if iv.is_empty() {
        return FormValue::EMPTY;
    }
    // A form that keeps a power's higher terms by products takes them.
    if n >= 3
        && let Some(p) = a.form.power_sharing(n, squares)
    {
        let ulps = 2 * (32 - n.unsigned_abs().leading_zeros()) + 1;
        return finish(p, iv, ulps);
    }
    let held = tightened(a);
    let a = &held;
    let iv = if F::MEET_EACH_OP { iv } else { a.range.powi(n) };
    if iv.is_empty() {
        return FormValue::EMPTY;
    }
    let r = a.range;
    // The point rule's products (binary powering) and its division.
    let ulps = 2 * (32 - n.unsigned_abs().leading_zeros()) + 1;
    let odd = n % 2 != 0;
    let (form, ulps) = match n {
        0 => (F::constant(1.0), 0),
        1 => (a.form, 0),
        2 => (a.form.square(), 1),
        // Its derivative's exponent n - 1 would overflow.
        i32::MIN => fallback(),
        _ if !odd || r.lo >= 0.0 || r.hi <= 0.0 => {
            if n < 0 && r.lo <= 0.0 && r.hi >= 0.0 {
                fallback()
            } else {
                let shape = Shape {
                    f: &|i: Interval| i.powi(n),
                    df: &|i: Interval| Interval::point(f64::from(n)).mul(i.powi(n - 1)),
                    convex: &|i: Interval| !odd || i.lo >= 0.0,
                    at_slope: &|s: f64, r: Interval| powi_at_slope(s, n, r),
                };
                (chebyshev(a, &shape), ulps)
            }
        }
        _ if n > 0 => (
            mean_value(
                a,
                |i| i.powi(n),
                |i| Interval::point(f64::from(n)).mul(i.powi(n - 1)),
            ),
            ulps,
        ),
        _ => fallback(),
    };
    finish(form, iv, ulps)
}

/// A range at most this wide relative to its largest magnitude takes the
/// midpoint as its tangent point in [`powi_at_slope`].
const NARROW_POWER_RANGE: f64 = 0.125;

/// Where `n·u^(n-1) = s`, roughly (any `u` is sound, this one is tight):
/// `|u| = |s/n|^(1/(n-1))`, with the sign of `s/n` for an odd `n - 1`
/// and of the range `r` for an even one.
fn powi_at_slope(s: f64, n: i32, r: Interval) -> f64 {
    // Over a range narrow beside its magnitude that point is within a
    // few percent of the range's width of the midpoint, and the tangent
    // there bounds as tightly to second order, without a `pow`.
    if r.hi - r.lo <= NARROW_POWER_RANGE * mx(r.lo.abs(), r.hi.abs()) {
        return r.mid();
    }
    let q = s / f64::from(n);
    let m = libm::pow(q.abs(), 1.0 / f64::from(n - 1));
    let positive = if (n - 1) % 2 != 0 {
        q >= 0.0
    } else {
        r.lo >= 0.0
    };
    if positive { m } else { -m }
}

/// A convex or concave op over a range, for [`chebyshev`].
struct Shape<'a> {
    /// The op's interval rule.
    f: &'a dyn Fn(Interval) -> Interval,
    /// The interval rule of its derivative.
    df: &'a dyn Fn(Interval) -> Interval,
    /// Whether it is convex (else concave) over the whole range given.
    convex: &'a dyn Fn(Interval) -> bool,
    /// A point of the range where the derivative is about the given
    /// slope.
    at_slope: &'a dyn Fn(f64, Interval) -> f64,
}

const EXP: Shape = Shape {
    f: &Interval::exp,
    df: &Interval::exp,
    convex: &|_| true,
    at_slope: &|s, _| libm::log(s),
};

const SQRT: Shape = Shape {
    f: &Interval::sqrt,
    df: &|i| Interval::point(0.5).div(i.sqrt()),
    convex: &|_| false,
    at_slope: &|s, _| 0.25 / (s * s),
};

const LN: Shape = Shape {
    f: &Interval::ln,
    df: &|i| Interval::point(1.0).div(i),
    convex: &|_| false,
    at_slope: &|s, _| 1.0 / s,
};

/// `1/t` over a range of one sign.
const RECIP: Shape = Shape {
    f: &|i| Interval::point(1.0).div(i),
    df: &|i| Interval::point(-1.0).div(i.square()),
    convex: &|i| i.lo > 0.0,
    at_slope: &|s, r| {
        let m = 1.0 / (-s).sqrt();
        if r.lo > 0.0 { m } else { -m }
    },
};

/// The Chebyshev (min-max) linearisation of a convex or concave op over
/// the operand's range `[l, h]`: slope `α` of the chord, and the range of
/// `g(t) = f(t) - α·t` bounded with outward-rounded intervals. For a
/// convex `f`, `g` is convex too: at most its larger end value, and at
/// least the tangent at `u` (where `f'(u) ≈ α`) minus `α·t`, since a
/// convex function lies above each tangent: `f(u) - f'(u)·u + (f'(u) -
/// α)·t` over the range. A concave `f` swaps the two bounds. Any `α` and
/// `u` give a sound bound; these give about the tightest.
fn chebyshev<F: Form>(a: &FormValue<F>, s: &Shape) -> F {
    let r = a.range;
    if !(r.lo.is_finite() && r.hi.is_finite()) {
        return F::UNBOUNDED;
    }
    let (pl, ph) = (Interval::point(r.lo), Interval::point(r.hi));
    let (fl, fh) = ((s.f)(pl), (s.f)(ph));
    if fl.is_empty() || fh.is_empty() {
        return F::UNBOUNDED;
    }
    let alpha = if r.hi > r.lo {
        (fh.mid() - fl.mid()) / (r.hi - r.lo)
    } else {
        0.0
    };
    if !alpha.is_finite() {
        return F::UNBOUNDED;
    }
    let g_at = |p: Interval, fp: Interval| fp.sub(p.mul_point(alpha));
    let ends = g_at(pl, fl).hull(g_at(ph, fh));
    let u = (s.at_slope)(alpha, r);
    let u = if u.is_nan() {
        r.mid()
    } else {
        u.clamp(r.lo, r.hi)
    };
    let pu = Interval::point(u);
    let du = (s.df)(pu);
    let tangent = (s.f)(pu)
        .sub(du.mul(pu))
        .add(du.sub(Interval::point(alpha)).mul(r));
    let g = if (s.convex)(r) {
        Interval::new(tangent.lo, ends.hi)
    } else {
        Interval::new(ends.lo, tangent.hi)
    };
    linear_from(a, alpha, g)
}

/// The mean-value linearisation over the operand's range `I` with
/// midpoint `m`: `f(t) - α·t = f(m) - α·m + (f'(ξ) - α)·(t - m)` for some
/// ξ in `I`, bounded with the derivative's interval `D` over `I`; `α` is
/// the midpoint of `D`.
fn mean_value<F: Form>(
    a: &FormValue<F>,
    f: impl Fn(Interval) -> Interval,
    df: impl Fn(Interval) -> Interval,
) -> F {
    let r = a.range;
    if !(r.lo.is_finite() && r.hi.is_finite()) {
        return F::UNBOUNDED;
    }
    let d = df(r);
    let alpha = d.mid();
    if !(d.lo.is_finite() && d.hi.is_finite() && alpha.is_finite()) {
        return F::UNBOUNDED;
    }
    let pm = Interval::point(r.mid());
    let g = f(pm)
        .sub(pm.mul_point(alpha))
        .add(d.sub(Interval::point(alpha)).mul(r.sub(pm)));
    linear_from(a, alpha, g)
}

/// `α·a + β ± δ` for `f(a) - α·a` in `g`: `β` its midpoint, `δ` an upper
/// bound of its radius (UNBOUNDED when `g` is not a finite interval).
fn linear_from<F: Form>(a: &FormValue<F>, alpha: f64, g: Interval) -> F {
    if !(g.lo.is_finite() && g.hi.is_finite() && g.lo <= g.hi) {
        return F::UNBOUNDED;
    }
    let beta = g.mid();
    let delta = mx(up_sum(g.hi - beta), up_sum(beta - g.lo));
    a.form.linear(alpha, beta, delta)
}

/// Every affine value of the function `ops` over `b`, in op order, into
/// `vals` (the interval twin is [`super::semantics::run_interval`]).
pub fn run_affine(ops: &[Op], b: [Interval; 3], vals: &mut Vec<AffineValue>) {
    vals.clear();
    for op in ops {
        let v = match *op {
            Op::Var(var) => AffineValue::var(b[var.index()], var.index()),
            Op::Const(c) => AffineValue::constant(c),
            Op::Unary(u, a) => affine_unary(u, &vals[a.index()]),
            Op::Binary(o, x, y) => affine_binary(o, &vals[x.index()], &vals[y.index()]),
            Op::Powi(a, n) => affine_powi(&vals[a.index()], n),
        };
        vals.push(v);
    }
}

#[cfg(test)]
#[path = "affine_rules_tests.rs"]
mod tests;
