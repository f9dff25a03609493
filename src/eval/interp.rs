//! The reference interpreter: the oracle the JIT is tested against, and
//! the baseline of its benchmarks.
//!
//! [`Interpreter`] walks the op list once per call with one `match` per op
//! (the rules are in [`crate::ir::semantics`]), storing values in a
//! per-thread scratch vector (no allocation per call once warm). It
//! implements all the evaluations of [`Evaluator`]: point values,
//! forward-mode gradients (dual numbers), intervals, and interval gradients
//! (interval dual numbers).

use crate::eval::{Bulk, Grad, IntervalGrad, Single, Specialise};
use crate::interval::Interval;
use crate::ir::semantics::*;
use crate::ir::validate::{InvalidIr, debug_validate, validate};
use crate::ir::{BinaryOp, Function, Op, UnaryOp};
use std::cell::RefCell;
use std::sync::Arc;

/// The interpreter's [`Arith`]: plain f64 and [`Interval`] arithmetic.
struct Reference;

/// `n` as the interpreter's i32 exponent; only `i32::MIN - 1` (the
/// derivative of `powi(_, i32::MIN)`) is out of range, and wraps as the
/// i32 arithmetic before the shared rules did.
fn exponent(n: i64) -> i32 {
    n as i32
}

impl Arith<f64> for Reference {
    fn konst(&mut self, c: f64) -> f64 {
        c
    }
    fn add(&mut self, a: f64, b: f64) -> f64 {
        a + b
    }
    fn sub(&mut self, a: f64, b: f64) -> f64 {
        a - b
    }
    fn mul(&mut self, a: f64, b: f64) -> f64 {
        a * b
    }
    fn div(&mut self, a: f64, b: f64) -> f64 {
        a / b
    }
    fn neg(&mut self, a: f64) -> f64 {
        -a
    }
    fn unary(&mut self, op: UnaryOp, a: f64) -> f64 {
        point_unary(op, a)
    }
    fn binary(&mut self, op: BinaryOp, a: f64, b: f64) -> f64 {
        point_binary(op, a, b)
    }
    fn powi(&mut self, a: f64, n: i64) -> f64 {
        point_powi(a, exponent(n))
    }
    fn keep_zero(&mut self, t: f64, x: f64) -> f64 {
        if t == 0.0 { 0.0 } else { x }
    }
    fn step_grad(&mut self, _: UnaryOp, _: f64, _: f64) -> f64 {
        0.0
    }
    fn abs_grad(&mut self, a: f64, x: f64) -> f64 {
        let s = if a > 0.0 {
            1.0
        } else if a < 0.0 {
            -1.0
        } else if a == 0.0 {
            0.0
        } else {
            f64::NAN
        };
        self.chain(s, x)
    }
    fn min_grad(&mut self, a: f64, b: f64, x: f64, y: f64) -> f64 {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else if a < b {
            x
        } else {
            y
        }
    }
    fn max_grad(&mut self, a: f64, b: f64, x: f64, y: f64) -> f64 {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else if a > b {
            x
        } else {
            y
        }
    }
}

impl Arith<Interval> for Reference {
    fn konst(&mut self, c: f64) -> Interval {
        Interval::point(c)
    }
    fn add(&mut self, a: Interval, b: Interval) -> Interval {
        a.add(b)
    }
    fn sub(&mut self, a: Interval, b: Interval) -> Interval {
        a.sub(b)
    }
    fn mul(&mut self, a: Interval, b: Interval) -> Interval {
        a.mul(b)
    }
    fn div(&mut self, a: Interval, b: Interval) -> Interval {
        a.div(b)
    }
    fn neg(&mut self, a: Interval) -> Interval {
        a.neg()
    }
    fn unary(&mut self, op: UnaryOp, a: Interval) -> Interval {
        interval_unary(op, a)
    }
    fn binary(&mut self, op: BinaryOp, a: Interval, b: Interval) -> Interval {
        interval_binary(op, a, b)
    }
    fn powi(&mut self, a: Interval, n: i64) -> Interval {
        a.powi(exponent(n))
    }
    fn abs_grad(&mut self, a: Interval, x: Interval) -> Interval {
        let s = if a.is_empty() {
            Interval::EMPTY
        } else if a.lo > 0.0 {
            Interval::point(1.0)
        } else if a.hi < 0.0 {
            Interval::point(-1.0)
        } else if a.lo == 0.0 && a.hi == 0.0 {
            Interval::point(0.0)
        } else if a.lo == 0.0 {
            Interval::new(0.0, 1.0)
        } else if a.hi == 0.0 {
            Interval::new(-1.0, 0.0)
        } else {
            Interval::new(-1.0, 1.0)
        };
        s.mul(x)
    }
    fn step_grad(&mut self, op: UnaryOp, a: Interval, x: Interval) -> Interval {
        interval_step_grad(op, a, x)
    }
    fn min_grad(&mut self, a: Interval, b: Interval, x: Interval, y: Interval) -> Interval {
        // The op returns a's value at every point of the box when a.hi < b.lo.
        pick_operand(a, b, a.hi < b.lo, b.hi <= a.lo, x, y)
    }
    fn max_grad(&mut self, a: Interval, b: Interval, x: Interval, y: Interval) -> Interval {
        pick_operand(a, b, a.lo > b.hi, b.lo >= a.hi, x, y)
    }
    fn atan2_cut(
        &mut self,
        a: Interval,
        b: Interval,
        x: Option<Interval>,
        y: Option<Interval>,
        d: Interval,
    ) -> Interval {
        if !(b.lo <= 0.0 && a.lo <= 0.0 && 0.0 <= a.hi) {
            return d;
        }
        let zero = |x: Option<Interval>| x.is_none_or(|x| x.lo == 0.0 && x.hi == 0.0);
        if zero(x) && zero(y) {
            Interval::point(0.0)
        } else {
            Interval::ENTIRE
        }
    }
    fn ln_deriv_arg(&mut self, a: Interval) -> Interval {
        if a.is_empty() || a.hi < 0.0 {
            Interval::EMPTY
        } else {
            Interval::new(a.lo.max(0.0), a.hi)
        }
    }
}

/// The derivative of min or max over a box: `x` where the op returns a
/// everywhere (`first`), `y` where it returns b everywhere, else the hull.
fn pick_operand(
    a: Interval,
    b: Interval,
    first: bool,
    second: bool,
    x: Interval,
    y: Interval,
) -> Interval {
    // The op's value is EMPTY exactly when an operand is.
    if a.is_empty() || b.is_empty() {
        Interval::EMPTY
    } else if first {
        x
    } else if second {
        y
    } else {
        x.hull(y)
    }
}

/// An interval value and `S` of its partials (one for a directional
/// derivative, three for the gradient).
pub(crate) type IntervalDual<const S: usize> = (Interval, [Interval; S]);

/// The first `S` partials as the shared rules' operand (the rest absent).
fn partials<const S: usize>(x: [Interval; S]) -> [Option<Interval>; 3] {
    std::array::from_fn(|k| (k < S).then(|| x[k]))
}

/// The first `S` of the shared rules' partials (absent ones are 0).
fn first<const S: usize>(d: [Option<Interval>; 3]) -> [Interval; S] {
    std::array::from_fn(|k| d[k].unwrap_or(Interval::point(0.0)))
}

/// `op(a)` and `S` partials by the reference rules: the bits of the
/// interpreter's [`Single::interval_dir`] (S = 1) and
/// [`Single::interval_grad`] (S = 3), as each partial is computed from
/// the same partial of the operands alone. The ops of distance fields are
/// written out with the rules' own arithmetic; the rest go through the
/// shared rules.
#[inline(always)]
pub(crate) fn dual_unary<const S: usize>(op: UnaryOp, (a, x): IntervalDual<S>) -> IntervalDual<S> {
    match op {
        UnaryOp::Neg => (a.neg(), x.map(Interval::neg)),
        UnaryOp::Square => {
            let fp = a.add(a);
            (a.square(), x.map(|x| chain(fp, x)))
        }
        UnaryOp::Sqrt => {
            let v = a.sqrt();
            let fp = Interval::point(0.5).div(v);
            (v, x.map(|x| chain(fp, x)))
        }
        _ => dual_unary_shared(op, (a, x)),
    }
}

/// [`dual_unary`] by the shared rules, out of line: the written-out ops
/// inline where the op is known, and the rest cost a call.
#[inline(never)]
fn dual_unary_shared<const S: usize>(op: UnaryOp, (a, x): IntervalDual<S>) -> IntervalDual<S> {
    let (v, d) = grad_unary(&mut Reference, op, (a, partials(x)));
    (v, first(d))
}

/// `op(a, b)` and `S` partials (see [`dual_unary`]).
#[inline(always)]
pub(crate) fn dual_binary<const S: usize>(
    op: BinaryOp,
    (a, x): IntervalDual<S>,
    (b, y): IntervalDual<S>,
) -> IntervalDual<S> {
    // Generic rather than `&dyn`, so that each op's rule inlines.
    #[inline(always)]
    fn zip<const S: usize>(
        x: [Interval; S],
        y: [Interval; S],
        f: impl Fn(Interval, Interval) -> Interval,
    ) -> [Interval; S] {
        std::array::from_fn(|k| f(x[k], y[k]))
    }
    match op {
        BinaryOp::Add => (a.add(b), zip(x, y, |x, y| x.add(y))),
        BinaryOp::Sub => (a.sub(b), zip(x, y, |x, y| x.sub(y))),
        BinaryOp::Mul => (a.mul(b), zip(x, y, |x, y| chain(b, x).add(chain(a, y)))),
        BinaryOp::Min => (a.min(b), zip(x, y, |x, y| Reference.min_grad(a, b, x, y))),
        BinaryOp::Max => (a.max(b), zip(x, y, |x, y| Reference.max_grad(a, b, x, y))),
        _ => dual_binary_shared(op, (a, x), (b, y)),
    }
}

/// [`dual_binary`] by the shared rules, out of line, as [`dual_unary_shared`].
#[inline(never)]
fn dual_binary_shared<const S: usize>(
    op: BinaryOp,
    (a, x): IntervalDual<S>,
    (b, y): IntervalDual<S>,
) -> IntervalDual<S> {
    let (v, d) = grad_binary(&mut Reference, op, (a, partials(x)), (b, partials(y)));
    (v, first(d))
}

/// `a^n` and `S` partials (see [`dual_unary`]).
pub(crate) fn dual_powi<const S: usize>((a, x): IntervalDual<S>, n: i32) -> IntervalDual<S> {
    let (v, d) = grad_powi(&mut Reference, (a, partials(x)), i64::from(n));
    (v, first(d))
}

/// `f'(a)·x` by the reference rule ([`Arith::chain`]).
#[inline]
fn chain<N: Copy>(fp: N, x: N) -> N
where
    Reference: Arith<N>,
{
    Reference.chain(fp, x)
}

/// `op(a)` and its three partials by the reference rules: the bits of the
/// interpreter's [`Single::point_grad`], with the ops of distance
/// fields written out (see [`dual_unary`]).
#[inline(always)]
pub(crate) fn point_dual_unary(op: UnaryOp, (a, x): (f64, [f64; 3])) -> (f64, [f64; 3]) {
    match op {
        UnaryOp::Neg => (-a, x.map(|x| -x)),
        UnaryOp::Square => {
            let fp = a + a;
            (a * a, x.map(|x| chain(fp, x)))
        }
        UnaryOp::Sqrt => {
            let v = a.sqrt();
            let fp = 0.5 / v;
            (v, x.map(|x| chain(fp, x)))
        }
        _ => {
            let (v, d) = grad_unary(&mut Reference, op, (a, x.map(Some)));
            (v, d.map(|d| d.unwrap_or(0.0)))
        }
    }
}

/// `op(a, b)` and its three partials (see [`point_dual_unary`]).
#[inline(always)]
pub(crate) fn point_dual_binary(
    op: BinaryOp,
    (a, x): (f64, [f64; 3]),
    (b, y): (f64, [f64; 3]),
) -> (f64, [f64; 3]) {
    // Generic rather than `&dyn`, so that each op's rule inlines into
    // the loops that run it.
    #[inline(always)]
    fn zip3(x: [f64; 3], y: [f64; 3], f: impl Fn(f64, f64) -> f64) -> [f64; 3] {
        std::array::from_fn(|k| f(x[k], y[k]))
    }
    match op {
        BinaryOp::Add => (a + b, zip3(x, y, |x, y| x + y)),
        BinaryOp::Sub => (a - b, zip3(x, y, |x, y| x - y)),
        BinaryOp::Mul => (a * b, zip3(x, y, |x, y| chain(b, x) + chain(a, y))),
        BinaryOp::Min => (
            point_binary(op, a, b),
            zip3(x, y, |x, y| Reference.min_grad(a, b, x, y)),
        ),
        BinaryOp::Max => (
            point_binary(op, a, b),
            zip3(x, y, |x, y| Reference.max_grad(a, b, x, y)),
        ),
        _ => {
            let (v, d) = grad_binary(&mut Reference, op, (a, x.map(Some)), (b, y.map(Some)));
            (v, d.map(|d| d.unwrap_or(0.0)))
        }
    }
}

/// `a^n` and its three partials (see [`point_dual_unary`]).
pub(crate) fn point_dual_powi((a, x): (f64, [f64; 3]), n: i32) -> (f64, [f64; 3]) {
    let (v, d) = grad_powi(&mut Reference, (a, x.map(Some)), i64::from(n));
    (v, d.map(|d| d.unwrap_or(0.0)))
}

/// The reference evaluator: walks the op list once per evaluation.
#[derive(Clone, Debug)]
pub struct Interpreter {
    f: Arc<Function>,
}

// Per-thread value slots, reused across calls so an evaluation allocates
// nothing once the vectors have grown to the largest function seen.
#[derive(Default)]
struct Scratch {
    point: Vec<f64>,
    grad: Vec<Grad>,
    interval: Vec<Interval>,
    igrad: Vec<IntervalGrad>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

impl Interpreter {
    /// An interpreter for `f`, which must be valid IR (checked in debug
    /// builds; see [`Interpreter::try_new`] for untrusted input).
    pub fn new(f: Function) -> Interpreter {
        Interpreter::shared(Arc::new(f))
    }

    /// [`Interpreter::new`] for a function shared with its owner (a
    /// pruned tape's), without copying it.
    pub fn shared(f: Arc<Function>) -> Interpreter {
        debug_validate(&f, "Interpreter::new");
        Interpreter { f }
    }

    /// An interpreter for `f`, or why `f` is not valid IR.
    pub fn try_new(f: Function) -> Result<Interpreter, InvalidIr> {
        validate(&f)?;
        Ok(Interpreter { f: Arc::new(f) })
    }

    /// The function it evaluates.
    pub fn function(&self) -> &Function {
        &self.f
    }

    /// Every value of the function at `p`, in op order (for tests and
    /// debugging: which op first went NaN, and so on).
    pub fn point_values(&self, p: [f64; 3]) -> Vec<f64> {
        let mut vals = Vec::with_capacity(self.f.ops.len());
        run_point(&self.f.ops, p, &mut vals);
        vals
    }

    /// Every interval of the function over `b`, in op order.
    pub fn interval_values(&self, b: [Interval; 3]) -> Vec<Interval> {
        let mut vals = Vec::with_capacity(self.f.ops.len());
        run_interval(&self.f.ops, b, &mut vals);
        vals
    }
}

// The interpreter knows no partial to be 0 before evaluating it: every
// partial is `Some` going in, and a `None` coming out (powi(_, 0)) is 0.
fn dual(g: Grad) -> Dual<f64> {
    (g.v, g.d.map(Some))
}

fn from_dual((v, d): Dual<f64>) -> Grad {
    Grad {
        v,
        d: d.map(|x| x.unwrap_or(0.0)),
    }
}

fn from_idual((v, d): Dual<Interval>) -> IntervalGrad {
    IntervalGrad {
        v,
        d: d.map(|x| x.unwrap_or(Interval::point(0.0))),
    }
}

fn run_grad(ops: &[Op], p: [f64; 3], vals: &mut Vec<Grad>) {
    vals.clear();
    for op in ops {
        let v = match *op {
            Op::Var(var) => {
                let mut d = [0.0; 3];
                d[var.index()] = 1.0;
                Grad {
                    v: p[var.index()],
                    d,
                }
            }
            Op::Const(c) => Grad { v: c, d: [0.0; 3] },
            Op::Unary(u, a) => from_dual(grad_unary(&mut Reference, u, dual(vals[a.index()]))),
            Op::Binary(o, a, b) => {
                let (a, b) = (dual(vals[a.index()]), dual(vals[b.index()]));
                from_dual(grad_binary(&mut Reference, o, a, b))
            }
            Op::Powi(a, n) => {
                let a = dual(vals[a.index()]);
                from_dual(grad_powi(&mut Reference, a, i64::from(n)))
            }
        };
        vals.push(v);
    }
}

/// Forward mode over a box; the partials of coordinate k start as
/// `seed[k]` (unit vectors for the gradient, `[v_k, 0, 0]` for the
/// derivative along v).
/// Interval values and partials of every op over `b`, each variable's
/// partials seeded by `seed`. Only the first `slots` partials are
/// computed (the rest read as 0): a directional derivative needs one, and
/// each partial is computed from the same partial of the operands alone,
/// so the ones computed keep their bits.
fn run_igrad(
    ops: &[Op],
    b: [Interval; 3],
    seed: [[Interval; 3]; 3],
    slots: usize,
    vals: &mut Vec<IntervalGrad>,
) {
    let idual = |g: IntervalGrad| -> Dual<Interval> {
        let mut d = [None; 3];
        for (k, dk) in d.iter_mut().enumerate().take(slots) {
            *dk = Some(g.d[k]);
        }
        (g.v, d)
    };
    vals.clear();
    for op in ops {
        let v = match *op {
            Op::Var(var) => IntervalGrad {
                v: b[var.index()],
                d: seed[var.index()],
            },
            Op::Const(c) => IntervalGrad {
                v: Interval::point(c),
                d: [Interval::point(0.0); 3],
            },
            Op::Unary(u, a) => from_idual(grad_unary(&mut Reference, u, idual(vals[a.index()]))),
            Op::Binary(o, x, y) => {
                let (a, b) = (idual(vals[x.index()]), idual(vals[y.index()]));
                from_idual(grad_binary(&mut Reference, o, a, b))
            }
            Op::Powi(a, n) => {
                let a = idual(vals[a.index()]);
                from_idual(grad_powi(&mut Reference, a, i64::from(n)))
            }
        };
        vals.push(v);
    }
}

impl Single for Interpreter {
    fn point(&self, p: [f64; 3]) -> f64 {
        SCRATCH.with_borrow_mut(|s| {
            run_point(&self.f.ops, p, &mut s.point);
            s.point[self.f.root.index()]
        })
    }

    fn point_grad(&self, p: [f64; 3]) -> Grad {
        SCRATCH.with_borrow_mut(|s| {
            run_grad(&self.f.ops, p, &mut s.grad);
            s.grad[self.f.root.index()]
        })
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        SCRATCH.with_borrow_mut(|s| {
            run_interval(&self.f.ops, b, &mut s.interval);
            s.interval[self.f.root.index()]
        })
    }

    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        let (o, z) = (Interval::point(1.0), Interval::point(0.0));
        let unit = [[o, z, z], [z, o, z], [z, z, o]];
        SCRATCH.with_borrow_mut(|s| {
            run_igrad(&self.f.ops, b, unit, 3, &mut s.igrad);
            s.igrad[self.f.root.index()]
        })
    }

    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        let z = Interval::point(0.0);
        let seed = v.map(|vk| [vk, z, z]);
        SCRATCH.with_borrow_mut(|s| {
            run_igrad(&self.f.ops, b, seed, 1, &mut s.igrad);
            let r = s.igrad[self.f.root.index()];
            [r.v, r.d[0]]
        })
    }
}

impl Bulk for Interpreter {}

impl Specialise for Interpreter {
    fn function(&self) -> Option<&Function> {
        Some(&self.f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::{BinaryOp, Builder, UnaryOp, Var};

    #[test]
    fn evaluates_sphere_and_gradient() {
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let y = b.var(Var::Y);
        let xx = b.unary(UnaryOp::Square, x);
        let yy = b.powi(y, 2);
        let s = b.binary(BinaryOp::Add, xx, yy);
        let one = b.constant(1.0);
        let r = b.binary(BinaryOp::Sub, s, one);
        let it = Interpreter::new(b.finish(r));
        assert_eq!(it.point([3.0, 4.0, 0.0]), 24.0);
        assert_eq!(it.point_grad([3.0, 4.0, 9.0]).d, [6.0, 8.0, 0.0]);
        let i = it.interval([
            Interval::new(-1.0, 2.0),
            Interval::point(0.0),
            Interval::ENTIRE,
        ]);
        assert!(i.contains(-1.0) && i.contains(3.0) && i.hi < 3.001 && i.lo > -1.001);
    }

    #[test]
    fn zero_partials_survive_infinite_derivatives() {
        // sqrt(x) + y at x = 0: d/dy is exactly 1, not NaN.
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let y = b.var(Var::Y);
        let s = b.unary(UnaryOp::Sqrt, x);
        let r = b.binary(BinaryOp::Add, s, y);
        let g = Interpreter::new(b.finish(r)).point_grad([0.0, 1.0, 0.0]);
        assert_eq!(g.d, [f64::INFINITY, 1.0, 0.0]);
    }
}
