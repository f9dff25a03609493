//! What each op means: its point rule, its interval rule and its
//! derivative rules (point and interval dual numbers). The reference
//! interpreter (`eval::interp`) is a loop over these; the JIT calls the
//! point and interval rules of the transcendentals through shims, and runs
//! the very same derivative rules over CLIF values.
//!
//! - [`grad_unary`], [`grad_binary`] and [`grad_powi`]: the chain rule,
//!   written once, generic over [`Arith`] (f64 and [`Interval`] here, CLIF
//!   values in the JIT; [`Arith`] has one method per place where the two
//!   backends' bits differ, saying why);
//! - the interval rules drop the points where an op is undefined, and
//!   EMPTY means undefined on the whole box: no real root is ever missed.
//!
//! `docs/semantics.md` states the derivative conventions (zeros that stay
//! zero, `abs` at 0, ties of `min`/`max`, `sqrt` and `ln` at 0, `pow`) and
//! the partial-domain rule in full.

use super::{BinaryOp, Op, UnaryOp};
use crate::interval::{Interval, max_nan, min_nan, powi_point, rem_euclid, sign};

/// A point value and its gradient (∂f/∂x, ∂f/∂y, ∂f/∂z); the default is
/// all zeros (a buffer's filler before a batch writes it).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Grad {
    /// f at the point.
    pub v: f64,
    /// The partial derivatives.
    pub d: [f64; 3],
}

/// An interval of f over a box and an interval for each partial derivative.
#[derive(Copy, Clone, Debug, PartialEq)]
#[repr(C)]
pub struct IntervalGrad {
    /// f over the box.
    pub v: Interval,
    /// ∂f/∂x, ∂f/∂y, ∂f/∂z over the box.
    pub d: [Interval; 3],
}

/// Point semantics of a one-operand op (the JIT calls this for the
/// transcendentals, so both give identical bits).
pub fn point_unary(op: UnaryOp, a: f64) -> f64 {
    match op {
        UnaryOp::Neg => -a,
        UnaryOp::Abs => a.abs(),
        UnaryOp::Square => a * a,
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Exp => crate::interval::exp::exp(a),
        UnaryOp::Ln => libm::log(a),
        UnaryOp::Sin => libm::sin(a),
        UnaryOp::Cos => libm::cos(a),
        UnaryOp::Tan => libm::tan(a),
        UnaryOp::Asin => libm::asin(a),
        UnaryOp::Acos => libm::acos(a),
        UnaryOp::Atan => libm::atan(a),
        UnaryOp::Sinh => libm::sinh(a),
        UnaryOp::Cosh => libm::cosh(a),
        UnaryOp::Tanh => libm::tanh(a),
        UnaryOp::Floor => a.floor(),
        UnaryOp::Ceil => a.ceil(),
        UnaryOp::Round => a.round(),
        UnaryOp::Sign => sign(a),
    }
}

/// Point semantics of a two-operand op.
pub fn point_binary(op: BinaryOp, a: f64, b: f64) -> f64 {
    match op {
        BinaryOp::Add => a + b,
        BinaryOp::Sub => a - b,
        BinaryOp::Mul => a * b,
        BinaryOp::Div => a / b,
        BinaryOp::Min => min_nan(a, b),
        BinaryOp::Max => max_nan(a, b),
        BinaryOp::Atan2 => libm::atan2(a, b),
        BinaryOp::Pow => {
            // NaN in, NaN out (libm's pow(NaN, 0) = pow(1, NaN) = 1 would
            // hide an undefined operand); -0 is taken as +0 so that the
            // result is exp(b·ln a) with ln(±0) = -inf, never negative.
            if a.is_nan() || b.is_nan() || a < 0.0 {
                f64::NAN
            } else {
                libm::pow(a + 0.0, b)
            }
        }
        BinaryOp::Mod => rem_euclid(a, b),
    }
}

/// Point semantics of `powi`.
pub fn point_powi(a: f64, n: i32) -> f64 {
    powi_point(a, n)
}

/// Interval semantics of a one-operand op.
#[inline]
pub fn interval_unary(op: UnaryOp, a: Interval) -> Interval {
    match op {
        UnaryOp::Neg => a.neg(),
        UnaryOp::Abs => a.abs(),
        UnaryOp::Square => a.square(),
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Exp => a.exp(),
        UnaryOp::Ln => a.ln(),
        UnaryOp::Sin => a.sin(),
        UnaryOp::Cos => a.cos(),
        UnaryOp::Tan => a.tan(),
        UnaryOp::Asin => a.asin(),
        UnaryOp::Acos => a.acos(),
        UnaryOp::Atan => a.atan(),
        UnaryOp::Sinh => a.sinh(),
        UnaryOp::Cosh => a.cosh(),
        UnaryOp::Tanh => a.tanh(),
        UnaryOp::Floor => a.floor(),
        UnaryOp::Ceil => a.ceil(),
        UnaryOp::Round => a.round(),
        UnaryOp::Sign => a.sign(),
    }
}

/// Interval semantics of a two-operand op.
#[inline]
pub fn interval_binary(op: BinaryOp, a: Interval, b: Interval) -> Interval {
    match op {
        BinaryOp::Add => a.add(b),
        BinaryOp::Sub => a.sub(b),
        BinaryOp::Mul => a.mul(b),
        BinaryOp::Div => a.div(b),
        BinaryOp::Min => a.min(b),
        BinaryOp::Max => a.max(b),
        BinaryOp::Atan2 => a.atan2(b),
        BinaryOp::Pow => a.pow(b),
        BinaryOp::Mod => a.rem_euclid(b),
    }
}

/// The interval partial of a step op (`floor`, `ceil`, `round`, `sign`)
/// of `a` whose partial is `x` (see [`Arith::step_grad`]): `[0, 0]` where
/// the op is constant over `a` or `a` does not move along the axis, the
/// whole line where it may jump. The interpreter and the JIT's shim both
/// call this.
pub fn interval_step_grad(op: UnaryOp, a: Interval, x: Interval) -> Interval {
    if a.is_empty() || x.is_empty() {
        Interval::EMPTY
    } else if (x.lo == 0.0 && x.hi == 0.0) || !a.may_jump(|v| point_unary(op, v)) {
        Interval::point(0.0)
    } else {
        Interval::ENTIRE
    }
}

/// A value's partials (∂/∂x, ∂/∂y, ∂/∂z); `None` is a partial known to be
/// exactly 0 before evaluation (the JIT emits no code for it; the
/// interpreter never uses `None` on its inputs).
pub type Partials<N> = [Option<N>; 3];

/// A value and its partials: a dual number.
pub type Dual<N> = (N, Partials<N>);

/// The arithmetic the derivative rules are written in, for one kind of
/// number `N`: the interpreter's (`f64`, [`Interval`]) and the JIT's (CLIF
/// values of a point or a packed interval).
///
/// The first methods are the ops themselves. The rest are the places where
/// the backends' rules differ today in their bits; each says how and why,
/// and the defaults are the interpreter's.
pub trait Arith<N: Copy> {
    /// The constant `c`.
    fn konst(&mut self, c: f64) -> N;
    /// `a + b`.
    fn add(&mut self, a: N, b: N) -> N;
    /// `a - b`.
    fn sub(&mut self, a: N, b: N) -> N;
    /// `a · b`.
    fn mul(&mut self, a: N, b: N) -> N;
    /// `a / b`.
    fn div(&mut self, a: N, b: N) -> N;
    /// `-a`.
    fn neg(&mut self, a: N) -> N;
    /// A one-operand op.
    fn unary(&mut self, op: UnaryOp, a: N) -> N;
    /// A two-operand op.
    fn binary(&mut self, op: BinaryOp, a: N, b: N) -> N;
    /// `a^n` (i64 so that the derivative's `n - 1` cannot overflow).
    fn powi(&mut self, a: N, n: i64) -> N;

    /// `x`, or exactly 0 where `t` is exactly 0. The point interpreter
    /// tracks exact zeros at run time (so a partial that is 0 stays 0 even
    /// times an infinite `f'(a)`); intervals get that from
    /// [`Interval::mul`] and the JIT from `None` partials, so for them it
    /// is `x`.
    fn keep_zero(&mut self, t: N, x: N) -> N {
        let _ = t;
        x
    }

    /// Derivative of `|a|` for the partial `x` of `a`. The kink is handled
    /// differently: the interpreter takes sign(0) = 0 (interval: the sign
    /// set times `x`, rounded); the JIT takes `x` at 0 and returns `x` or
    /// `-x` exactly (interval: the hull of both where the sign is unsure).
    fn abs_grad(&mut self, a: N, x: N) -> N;
    /// The partial of a piecewise-constant op (`floor`, `ceil`, `round`,
    /// `sign`) of `a`, whose partial is `x`: 0 where the op cannot jump.
    /// Points: 0 (the derivative between jumps). Intervals: `[0, 0]` when
    /// the op is constant over the operand interval or `x` is `[0, 0]`
    /// (the operand does not move along this axis), else the whole line,
    /// since a jump has no finite bound on how fast f changes; the
    /// inclusion test and interval Newton then cannot treat f as smooth
    /// across it (as at atan2's cut).
    fn step_grad(&mut self, op: UnaryOp, a: N, x: N) -> N;
    /// Derivative of `min(a, b)` given the partials `x`, `y`: that of the
    /// operand min returns (interval: of the one it returns on the whole
    /// box, else the hull). The interpreter gives NaN (EMPTY) where an
    /// operand is NaN (EMPTY); the JIT does not test for it.
    fn min_grad(&mut self, a: N, b: N, x: N, y: N) -> N;
    /// Derivative of `max(a, b)` (see [`Arith::min_grad`]).
    fn max_grad(&mut self, a: N, b: N, x: N, y: N) -> N;
    /// A partial `d` of `atan2(a, b)` from the operands' partials `x`, `y`,
    /// widened where an interval box touches the branch cut (see
    /// [`grad_binary`]). Points: `d`. The interval interpreter keeps a
    /// partial that is exactly [0, 0] in both operands; the JIT tracks that
    /// as `None` and never gets here with it.
    fn atan2_cut(&mut self, a: N, b: N, x: Option<N>, y: Option<N>, d: N) -> N {
        let _ = (a, b, x, y);
        d
    }
    /// The operand whose reciprocal is ln's derivative. The interval
    /// interpreter takes its non-negative part (where ln is defined, see
    /// the module doc), the JIT all of it (wider, still sound).
    fn ln_deriv_arg(&mut self, a: N) -> N {
        a
    }
    /// Each partial times `c / q` (the chain rule with f'(a) = c/q; c is
    /// 1 or 1/2). The interpreter multiplies by the quotient
    /// ([`Arith::chain`]); the JIT divides each partial by `q / c` (for
    /// c = 1/2, `q + q`). Intervals round these differently.
    fn chain_quot(&mut self, c: f64, q: N, da: Partials<N>) -> Partials<N> {
        scale(self, da, |cx| {
            let c = cx.konst(c);
            cx.div(c, q)
        })
    }
    /// The factor `n·a^(n-1)` of `powi(a, n)`'s derivative, or `None` to
    /// pass the partials through unchanged. The JIT does that for n = 1
    /// (its product by exactly 1 is exact); the interpreter multiplies by
    /// 1 like every factor, which its [`Arith::chain`] rounds (intervals)
    /// or turns -0 into +0 (points).
    fn powi_factor(&mut self, a: N, n: i64) -> Option<N> {
        Some(powi_factor(self, a, n))
    }
    /// The partials of `pow(a, b) = v`. The interpreter uses
    /// [`pow_partials_factored`], the JIT [`pow_partials_log`]: different
    /// formulas, hence different roundings.
    fn pow_partials(&mut self, a: N, b: N, v: N, da: Partials<N>, db: Partials<N>) -> Partials<N> {
        pow_partials_factored(self, a, b, v, da, db)
    }

    /// The chain-rule product `f'(a)·x` (see [`Arith::keep_zero`]).
    fn chain(&mut self, fp: N, x: N) -> N {
        let p = self.mul(fp, x);
        self.keep_zero(x, p)
    }
}

/// `rule(x)` for each partial that is not known to be 0.
fn map_partials<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    d: Partials<N>,
    mut rule: impl FnMut(&mut C, N) -> N,
) -> Partials<N> {
    d.map(|x| x.map(|x| rule(cx, x)))
}

/// `f'(a)·x` for each partial, with `f'(a)` from `fp`, built only if some
/// partial is not known to be 0.
pub fn scale<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    da: Partials<N>,
    fp: impl FnOnce(&mut C) -> N,
) -> Partials<N> {
    if da.iter().all(Option::is_none) {
        return da;
    }
    let fp = fp(cx);
    map_partials(cx, da, |cx, x| cx.chain(fp, x))
}

/// `f(x, y)` for each k where the operands' partials are not both known
/// to be 0.
fn zip_partials<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    da: Partials<N>,
    db: Partials<N>,
    mut f: impl FnMut(&mut C, Option<N>, Option<N>) -> N,
) -> Partials<N> {
    let mut d = [None; 3];
    for k in 0..3 {
        if da[k].is_some() || db[k].is_some() {
            d[k] = Some(f(cx, da[k], db[k]));
        }
    }
    d
}

/// `l + r`, where `None` is 0.
fn sum<N: Copy, C: Arith<N> + ?Sized>(cx: &mut C, l: Option<N>, r: Option<N>) -> N {
    match (l, r) {
        (Some(l), Some(r)) => cx.add(l, r),
        (Some(x), None) | (None, Some(x)) => x,
        (None, None) => cx.konst(0.0),
    }
}

/// `l - r`, where `None` is 0.
fn difference<N: Copy, C: Arith<N> + ?Sized>(cx: &mut C, l: Option<N>, r: Option<N>) -> N {
    match (l, r) {
        (Some(l), Some(r)) => cx.sub(l, r),
        (Some(x), None) => x,
        (None, Some(y)) => cx.neg(y),
        (None, None) => cx.konst(0.0),
    }
}

/// Value and partials of a one-operand op (forward mode).
pub fn grad_unary<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    op: UnaryOp,
    (a, da): Dual<N>,
) -> Dual<N> {
    let v = cx.unary(op, a);
    let d = match op {
        UnaryOp::Neg => map_partials(cx, da, |cx, x| cx.neg(x)),
        UnaryOp::Abs => map_partials(cx, da, |cx, x| cx.abs_grad(a, x)),
        UnaryOp::Square => scale(cx, da, |cx| cx.add(a, a)),
        UnaryOp::Sqrt => cx.chain_quot(0.5, v, da),
        UnaryOp::Exp => scale(cx, da, |_| v),
        UnaryOp::Ln => {
            let q = cx.ln_deriv_arg(a);
            cx.chain_quot(1.0, q, da)
        }
        UnaryOp::Sin => scale(cx, da, |cx| cx.unary(UnaryOp::Cos, a)),
        UnaryOp::Cos => scale(cx, da, |cx| {
            let s = cx.unary(UnaryOp::Sin, a);
            cx.neg(s)
        }),
        // 1 + tan²
        UnaryOp::Tan => scale(cx, da, |cx| {
            let one = cx.konst(1.0);
            let t2 = cx.unary(UnaryOp::Square, v);
            cx.add(one, t2)
        }),
        // ±1 / sqrt(1 - a²)
        UnaryOp::Asin | UnaryOp::Acos => {
            let one = cx.konst(1.0);
            let a2 = cx.unary(UnaryOp::Square, a);
            let r = cx.sub(one, a2);
            let q = cx.unary(UnaryOp::Sqrt, r);
            let d = cx.chain_quot(1.0, q, da);
            if op == UnaryOp::Acos {
                map_partials(cx, d, |cx, x| cx.neg(x))
            } else {
                d
            }
        }
        // 1 / (1 + a²)
        UnaryOp::Atan => {
            let one = cx.konst(1.0);
            let a2 = cx.unary(UnaryOp::Square, a);
            let q = cx.add(one, a2);
            cx.chain_quot(1.0, q, da)
        }
        UnaryOp::Sinh => scale(cx, da, |cx| cx.unary(UnaryOp::Cosh, a)),
        UnaryOp::Cosh => scale(cx, da, |cx| cx.unary(UnaryOp::Sinh, a)),
        // 1 - tanh²
        UnaryOp::Tanh => scale(cx, da, |cx| {
            let one = cx.konst(1.0);
            let t2 = cx.unary(UnaryOp::Square, v);
            cx.sub(one, t2)
        }),
        UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round | UnaryOp::Sign => {
            map_partials(cx, da, |cx, x| cx.step_grad(op, a, x))
        }
    };
    (v, d)
}

/// Value and partials of a two-operand op (forward mode).
pub fn grad_binary<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    op: BinaryOp,
    (a, da): Dual<N>,
    (b, db): Dual<N>,
) -> Dual<N> {
    let v = cx.binary(op, a, b);
    let zero = |cx: &mut C, x: Option<N>| x.unwrap_or_else(|| cx.konst(0.0));
    let d = match op {
        BinaryOp::Add => zip_partials(cx, da, db, sum),
        BinaryOp::Sub => zip_partials(cx, da, db, difference),
        // b·da + a·db
        BinaryOp::Mul => zip_partials(cx, da, db, |cx, x, y| {
            let l = x.map(|x| cx.chain(b, x));
            let r = y.map(|y| cx.chain(a, y));
            sum(cx, l, r)
        }),
        // (da - v·db) / b
        BinaryOp::Div => zip_partials(cx, da, db, |cx, x, y| {
            let r = y.map(|y| cx.chain(v, y));
            let n = difference(cx, x, r);
            cx.div(n, b)
        }),
        BinaryOp::Min => zip_partials(cx, da, db, |cx, x, y| {
            let (x, y) = (zero(cx, x), zero(cx, y));
            cx.min_grad(a, b, x, y)
        }),
        BinaryOp::Max => zip_partials(cx, da, db, |cx, x, y| {
            let (x, y) = (zero(cx, x), zero(cx, y));
            cx.max_grad(a, b, x, y)
        }),
        // (b·da - a·db) / (a² + b²). atan2(a, b) jumps by 2π across its
        // branch cut (a = 0, b < 0); a box touching the cut has no finite
        // bound on how fast f changes, so interval contexts widen the
        // partial there ([`Arith::atan2_cut`]): the formula would miss the
        // jump, and interval Newton, the centred form and the inclusion
        // test would drop or misplace the sign change.
        BinaryOp::Atan2 => {
            if da.iter().chain(&db).all(Option::is_none) {
                return (v, [None; 3]);
            }
            let a2 = cx.unary(UnaryOp::Square, a);
            let b2 = cx.unary(UnaryOp::Square, b);
            let r2 = cx.add(a2, b2);
            zip_partials(cx, da, db, |cx, x, y| {
                let l = x.map(|x| cx.chain(b, x));
                let r = y.map(|y| cx.chain(a, y));
                let n = difference(cx, l, r);
                let q = cx.div(n, r2);
                cx.atan2_cut(a, b, x, y, q)
            })
        }
        BinaryOp::Pow => cx.pow_partials(a, b, v, da, db),
        BinaryOp::Mod => mod_partials(cx, (a, da), (b, db)),
    };
    (v, d)
}

/// The partials of `mod(a, b)` by the chain rule of the identity
/// `mod(a, b) = a - m·floor(a / m)` with `m = |b|`: where no jump of the
/// floor is possible this is `da - floor(a/m)·dm`, and where one is, the
/// floor's [`Arith::step_grad`] makes the partial unbounded. Written with
/// the arithmetic directly, not through [`grad_binary`], and kept out of
/// line: a recursive call would stop `grad_binary` from being inlined
/// into the interpreter's loops (colonnade's trace took 13% longer).
#[inline(never)]
fn mod_partials<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    (a, da): Dual<N>,
    (b, db): Dual<N>,
) -> Partials<N> {
    if da.iter().chain(&db).all(Option::is_none) {
        return [None; 3];
    }
    let m = cx.unary(UnaryOp::Abs, b);
    let dm = map_partials(cx, db, |cx, y| cx.abs_grad(b, y));
    let q = cx.div(a, m);
    let k = cx.unary(UnaryOp::Floor, q);
    zip_partials(cx, da, dm, |cx, x, y| {
        // dq = (da - q·dm) / m, then d(m·k) = dm·k + m·step(dq).
        let r = y.map(|y| cx.chain(q, y));
        let n = difference(cx, x, r);
        let dq = cx.div(n, m);
        let dk = cx.step_grad(UnaryOp::Floor, q, dq);
        let l = y.map(|y| cx.chain(k, y));
        let mk = cx.chain(m, dk);
        let dmk = sum(cx, l, Some(mk));
        difference(cx, x, Some(dmk))
    })
}

/// `n·a^(n-1)`, the factor of `powi(a, n)`'s derivative.
pub fn powi_factor<N: Copy, C: Arith<N> + ?Sized>(cx: &mut C, a: N, n: i64) -> N {
    let nk = cx.konst(n as f64);
    let p = cx.powi(a, n - 1);
    cx.mul(nk, p)
}

/// Value and partials of `powi(a, n)` (forward mode): `n·a^(n-1)·da`, and
/// exactly 0 for n = 0.
pub fn grad_powi<N: Copy, C: Arith<N> + ?Sized>(cx: &mut C, (a, da): Dual<N>, n: i64) -> Dual<N> {
    let v = cx.powi(a, n);
    if n == 0 {
        return (v, [None; 3]);
    }
    if da.iter().all(Option::is_none) {
        return (v, da);
    }
    let d = match cx.powi_factor(a, n) {
        None => da,
        Some(k) => map_partials(cx, da, |cx, x| cx.chain(k, x)),
    };
    (v, d)
}

/// pow's partials as `b·a^(b-1)·da + a^b·ln(a)·db` (the interpreter's):
/// each factor 0 where `keep_zero` sees b = 0 (a^0 is 1 for every a) or
/// a^b = 0 (0^b for b > 0 is 0 for every b nearby).
pub fn pow_partials_factored<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    a: N,
    b: N,
    v: N,
    da: Partials<N>,
    db: Partials<N>,
) -> Partials<N> {
    if da.iter().chain(&db).all(Option::is_none) {
        return [None; 3];
    }
    let one = cx.konst(1.0);
    let b1 = cx.sub(b, one);
    let p = cx.binary(BinaryOp::Pow, a, b1);
    let fa = cx.mul(p, b);
    let fa = cx.keep_zero(b, fa);
    let ln = cx.unary(UnaryOp::Ln, a);
    let fb = cx.mul(v, ln);
    let fb = cx.keep_zero(v, fb);
    zip_partials(cx, da, db, |cx, x, y| {
        let l = x.map(|x| cx.chain(fa, x));
        let r = y.map(|y| cx.chain(fb, y));
        sum(cx, l, r)
    })
}

/// pow's partials as `v·(db·ln a + b·da/a)` (the JIT's: one pow per op).
pub fn pow_partials_log<N: Copy, C: Arith<N> + ?Sized>(
    cx: &mut C,
    a: N,
    b: N,
    v: N,
    da: Partials<N>,
    db: Partials<N>,
) -> Partials<N> {
    zip_partials(cx, da, db, |cx, x, y| {
        let l = y.map(|y| {
            let ln = cx.unary(UnaryOp::Ln, a);
            cx.mul(y, ln)
        });
        let r = x.map(|x| {
            let q = cx.div(x, a);
            cx.mul(b, q)
        });
        let s = sum(cx, l, r);
        cx.mul(v, s)
    })
}

/// Every value of the function `ops` at `p`, in op order, into `vals`.
pub fn run_point(ops: &[Op], p: [f64; 3], vals: &mut Vec<f64>) {
    vals.clear();
    for op in ops {
        let v = match *op {
            Op::Var(var) => p[var.index()],
            Op::Const(c) => c,
            Op::Unary(u, a) => point_unary(u, vals[a.index()]),
            Op::Binary(o, a, b) => point_binary(o, vals[a.index()], vals[b.index()]),
            Op::Powi(a, n) => point_powi(vals[a.index()], n),
        };
        vals.push(v);
    }
}

/// Every interval of the function `ops` over `b`, in op order, into
/// `vals`.
pub fn run_interval(ops: &[Op], b: [Interval; 3], vals: &mut Vec<Interval>) {
    vals.clear();
    for op in ops {
        let v = match *op {
            Op::Var(var) => b[var.index()],
            Op::Const(c) => Interval::point(c),
            Op::Unary(u, a) => interval_unary(u, vals[a.index()]),
            Op::Binary(o, x, y) => interval_binary(o, vals[x.index()], vals[y.index()]),
            Op::Powi(a, n) => vals[a.index()].powi(n),
        };
        vals.push(v);
    }
}
