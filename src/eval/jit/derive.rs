//! Lowering of the gradient kinds: the derivative rules of
//! [`crate::ir::semantics`] (the interpreter's too) run over CLIF values,
//! with the emitter as their [`Arith`] for points (`Value`) and for packed
//! intervals ([`Iv`]). Only the conventions where the JIT's bits differ
//! from the interpreter's (see [`Arith`]) are written here.

use cranelift_codegen::ir::condcodes::FloatCC;
use cranelift_codegen::ir::{InstBuilder, Value};

use super::emit::{Emitter, Iv};
use super::lower::{Spill, iv_binary, iv_unary, point_binary, point_unary, sweep};
use super::shims::Shim;
use crate::ir::semantics::{
    Arith, Dual, Partials, grad_binary, grad_powi, grad_unary, pow_partials_log, powi_factor,
};
use crate::ir::{BinaryOp, Function, Op, UnaryOp};

impl Arith<Value> for Emitter<'_, '_> {
    fn konst(&mut self, c: f64) -> Value {
        self.c(c)
    }
    fn add(&mut self, a: Value, b: Value) -> Value {
        Emitter::add(self, a, b)
    }
    fn sub(&mut self, a: Value, b: Value) -> Value {
        Emitter::sub(self, a, b)
    }
    fn mul(&mut self, a: Value, b: Value) -> Value {
        Emitter::mul(self, a, b)
    }
    fn div(&mut self, a: Value, b: Value) -> Value {
        Emitter::div(self, a, b)
    }
    fn neg(&mut self, a: Value) -> Value {
        Emitter::neg(self, a)
    }
    fn unary(&mut self, u: UnaryOp, a: Value) -> Value {
        point_unary(self, u, a)
    }
    fn binary(&mut self, op: BinaryOp, a: Value, b: Value) -> Value {
        point_binary(self, op, a, b)
    }
    fn powi(&mut self, a: Value, n: i64) -> Value {
        self.powi_point(a, n)
    }
    fn step_grad(&mut self, _: UnaryOp, _: Value, _: Value) -> Value {
        self.c(0.0)
    }
    /// `x` where a ≥ 0 (and at ±0 and NaN), `-x` where a < 0.
    fn abs_grad(&mut self, a: Value, x: Value) -> Value {
        let z = self.c(0.0);
        let neg = self.fcmp(FloatCC::LessThan, a, z);
        let nx = Emitter::neg(self, x);
        self.select(neg, nx, x)
    }
    fn min_grad(&mut self, a: Value, b: Value, x: Value, y: Value) -> Value {
        let lt = self.fcmp(FloatCC::LessThan, a, b);
        self.select(lt, x, y)
    }
    fn max_grad(&mut self, a: Value, b: Value, x: Value, y: Value) -> Value {
        let gt = self.fcmp(FloatCC::GreaterThan, a, b);
        self.select(gt, x, y)
    }
    fn chain_quot(&mut self, c: f64, q: Value, da: Partials<Value>) -> Partials<Value> {
        divide_partials(self, c, q, da)
    }
    fn powi_factor(&mut self, a: Value, n: i64) -> Option<Value> {
        (n != 1).then(|| powi_factor(self, a, n))
    }
    fn pow_partials(
        &mut self,
        a: Value,
        b: Value,
        v: Value,
        da: Partials<Value>,
        db: Partials<Value>,
    ) -> Partials<Value> {
        pow_partials_log(self, a, b, v, da, db)
    }
}

impl Arith<Iv> for Emitter<'_, '_> {
    fn konst(&mut self, c: f64) -> Iv {
        self.iv_const(c)
    }
    fn add(&mut self, a: Iv, b: Iv) -> Iv {
        self.iv_add(a, b)
    }
    fn sub(&mut self, a: Iv, b: Iv) -> Iv {
        self.iv_sub(a, b)
    }
    fn mul(&mut self, a: Iv, b: Iv) -> Iv {
        self.iv_mul(a, b, None)
    }
    fn div(&mut self, a: Iv, b: Iv) -> Iv {
        self.iv_div(a, b)
    }
    fn neg(&mut self, a: Iv) -> Iv {
        self.iv_neg(a)
    }
    fn unary(&mut self, u: UnaryOp, a: Iv) -> Iv {
        iv_unary(self, u, a)
    }
    fn binary(&mut self, op: BinaryOp, a: Iv, b: Iv) -> Iv {
        iv_binary(self, op, a, b)
    }
    fn powi(&mut self, a: Iv, n: i64) -> Iv {
        self.iv_powi(a, n)
    }
    /// The interpreter's rule, called out: jumps are rare and need the
    /// op's point rule at both ends of the operand.
    fn step_grad(&mut self, op: UnaryOp, a: Iv, x: Iv) -> Iv {
        self.call_iv_binary(Shim::IntervalStepGrad(op), a, x)
    }
    fn abs_grad(&mut self, a: Iv, x: Iv) -> Iv {
        // The sign of a is certain only when a.lo >= 0 (lane -lo <= 0) or
        // a.hi < 0.
        let z = self.c(0.0);
        let (n, h) = self.iv_lanes(a);
        let nonneg = self.fcmp(FloatCC::LessThanOrEqual, n, z);
        let neg = self.fcmp(FloatCC::LessThan, h, z);
        let nx = self.iv_neg(x);
        let both = self.iv_hull(x, nx);
        pick(self, nonneg, x, neg, nx, both)
    }
    fn min_grad(&mut self, a: Iv, b: Iv, x: Iv, y: Iv) -> Iv {
        // a < b everywhere iff a.hi < b.lo; nowhere iff b.hi <= a.lo.
        let (alo, ahi) = bounds(self, a);
        let (blo, bhi) = bounds(self, b);
        let a_first = self.fcmp(FloatCC::LessThan, ahi, blo);
        let b_first = self.fcmp(FloatCC::LessThanOrEqual, bhi, alo);
        let both = self.iv_hull(x, y);
        pick(self, a_first, x, b_first, y, both)
    }
    fn max_grad(&mut self, a: Iv, b: Iv, x: Iv, y: Iv) -> Iv {
        let (alo, ahi) = bounds(self, a);
        let (blo, bhi) = bounds(self, b);
        let a_first = self.fcmp(FloatCC::GreaterThan, alo, bhi);
        let b_first = self.fcmp(FloatCC::LessThanOrEqual, ahi, blo);
        let both = self.iv_hull(x, y);
        pick(self, a_first, x, b_first, y, both)
    }
    /// A box with `b.lo <= 0` and `0 ∈ a` touches the cut: the whole line.
    fn atan2_cut(&mut self, a: Iv, b: Iv, _: Option<Iv>, _: Option<Iv>, d: Iv) -> Iv {
        let z = self.c(0.0);
        let (alo, ahi) = bounds(self, a);
        let (blo, _) = bounds(self, b);
        let b_nonpos = self.fcmp(FloatCC::LessThanOrEqual, blo, z);
        let a_lo = self.fcmp(FloatCC::LessThanOrEqual, alo, z);
        let a_hi = self.fcmp(FloatCC::LessThanOrEqual, z, ahi);
        let a_has0 = self.b.ins().band(a_lo, a_hi);
        let cut = self.b.ins().band(b_nonpos, a_has0);
        let entire = Iv(self.vconst(f64::INFINITY, f64::INFINITY));
        self.iv_select(cut, entire, d)
    }
    fn chain_quot(&mut self, c: f64, q: Iv, da: Partials<Iv>) -> Partials<Iv> {
        divide_partials(self, c, q, da)
    }
    fn powi_factor(&mut self, a: Iv, n: i64) -> Option<Iv> {
        (n != 1).then(|| powi_factor(self, a, n))
    }
    /// The log form, with `da / a` taken as 0 where the partial `da` is
    /// `[0, 0]`: at a base that is exactly 0 the quotient is 0/0, and the
    /// EMPTY it gives would claim f undefined where it is not (a floor or
    /// a constant can make such a base).
    fn pow_partials(
        &mut self,
        a: Iv,
        b: Iv,
        v: Iv,
        da: Partials<Iv>,
        db: Partials<Iv>,
    ) -> Partials<Iv> {
        let mut d = [None; 3];
        for k in 0..3 {
            let l = db[k].map(|y| {
                let ln = iv_unary(self, UnaryOp::Ln, a);
                self.iv_mul(y, ln, None)
            });
            let r = da[k].map(|x| {
                let (lo, hi) = bounds(self, x);
                let z = self.c(0.0);
                let lo0 = self.fcmp(FloatCC::Equal, lo, z);
                let hi0 = self.fcmp(FloatCC::Equal, hi, z);
                let is0 = self.b.ins().band(lo0, hi0);
                let q = self.iv_div(x, a);
                let zero = self.iv_const(0.0);
                let q = self.iv_select(is0, zero, q);
                self.iv_mul(b, q, None)
            });
            let s = match (l, r) {
                (Some(l), Some(r)) => self.iv_add(l, r),
                (Some(t), None) | (None, Some(t)) => t,
                (None, None) => continue,
            };
            d[k] = Some(self.iv_mul(v, s, None));
        }
        d
    }
}

/// The JIT's [`Arith::chain_quot`]: each partial divided by `q / c`
/// (`q + q` for c = 1/2), built once.
fn divide_partials<T: Copy>(e: &mut Emitter, c: f64, q: T, da: Partials<T>) -> Partials<T>
where
    for<'a, 'b> Emitter<'a, 'b>: Arith<T>,
{
    if da.iter().all(Option::is_none) {
        return da;
    }
    let den = if c == 1.0 {
        q
    } else if c == 0.5 {
        Arith::add(e, q, q)
    } else {
        let k = Arith::konst(e, 1.0 / c);
        Arith::mul(e, k, q)
    };
    da.map(|x| x.map(|x| Arith::div(e, x, den)))
}

/// The bounds `(lo, hi)` of an interval as scalars.
fn bounds(e: &mut Emitter, a: Iv) -> (Value, Value) {
    let (n, h) = e.iv_lanes(a);
    (Emitter::neg(e, n), h)
}

/// `if c1 { r1 } else if c2 { r2 } else { r3 }`.
fn pick(e: &mut Emitter, c1: Value, r1: Iv, c2: Value, r2: Iv, r3: Iv) -> Iv {
    let r = e.iv_select(c2, r2, r3);
    e.iv_select(c1, r1, r)
}

/// Forward-mode value and gradient of f; inputs are the (point or interval)
/// coordinates.
pub(crate) fn grad<T: Spill>(e: &mut Emitter, f: &Function, live: &[bool], xyz: [T; 3]) -> Dual<T>
where
    for<'a, 'b> Emitter<'a, 'b>: Arith<T>,
{
    let unit = |e: &mut Emitter, k: usize| {
        let mut d = [None; 3];
        d[k] = Some(Arith::konst(e, 1.0));
        d
    };
    seeded(e, f, live, xyz, &unit)
}

/// Forward-mode value and directional derivative `∇f·v` of f (in partial
/// slot 0): each coordinate's derivative is seeded with its component of
/// `v`, so one partial is carried instead of three.
pub(crate) fn directional<T: Spill>(
    e: &mut Emitter,
    f: &Function,
    live: &[bool],
    xyz: [T; 3],
    v: [T; 3],
) -> (T, Option<T>)
where
    for<'a, 'b> Emitter<'a, 'b>: Arith<T>,
{
    let seed = |_: &mut Emitter, k: usize| [Some(v[k]), None, None];
    let (val, d) = seeded(e, f, live, xyz, &seed);
    (val, d[0])
}

/// Forward mode with the partials of the coordinate `k` seeded by `seed(k)`.
fn seeded<T: Spill>(
    e: &mut Emitter,
    f: &Function,
    live: &[bool],
    xyz: [T; 3],
    seed: &dyn Fn(&mut Emitter, usize) -> Partials<T>,
) -> Dual<T>
where
    for<'a, 'b> Emitter<'a, 'b>: Arith<T>,
{
    let var = |e: &mut Emitter, k: usize| (xyz[k], seed(e, k));
    sweep(e, f, live, var, |e, op, a| match *op {
        Op::Const(c) => (Arith::konst(e, c), [None; 3]),
        Op::Unary(u, _) => grad_unary(e, u, a[0]),
        Op::Binary(o, _, _) => grad_binary(e, o, a[0], a[1]),
        Op::Powi(_, n) => grad_powi(e, a[0], i64::from(n)),
        Op::Var(v) => var(e, v.index()),
    })
}
