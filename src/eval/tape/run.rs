//! Running a tape: one point or box over its registers, with values,
//! gradients or a directional derivative, and batches of points or boxes a
//! column per register. Every result is the reference interpreter's bits.

use super::{Form, Instr, Reg, Tape, Workspace};
use crate::eval::interp::{
    IntervalDual, dual_binary, dual_powi, dual_unary, point_dual_binary, point_dual_powi,
    point_dual_unary,
};
use crate::eval::{Grad, IntervalGrad};
use crate::interval::{Interval, max_nan, min_nan};
use crate::ir::semantics::{
    interval_binary, interval_unary, point_binary, point_powi, point_unary,
};
use crate::ir::{BinaryOp, UnaryOp};

impl Tape {
    /// f at `p`, the same bits as the reference interpreter: one pass over
    /// the registers, one dispatch per instruction, the common ops inline
    /// (the reference rules' `match` per op, a call each, costs more than
    /// the op).
    pub fn point(&self, p: [f64; 3], ws: &mut Workspace) -> f64 {
        let root = self.root_reg() as Reg;
        match fixed_registers(&mut ws.points, self.registers, 0.0) {
            Some(m) => point_pass(&self.code, p, m, root),
            None => point_pass(&self.code, p, &mut ws.points[..], root),
        }
    }

    /// An interval containing f over `b`, the same bits as the reference
    /// interpreter's (see [`Tape::point`]).
    pub fn interval(&self, b: [Interval; 3], ws: &mut Workspace) -> Interval {
        let root = self.root_reg() as Reg;
        let zero = Interval::point(0.0);
        match fixed_registers(&mut ws.intervals, self.registers, zero) {
            Some(m) => interval_pass(&self.code, b, m, root),
            None => interval_pass(&self.code, b, &mut ws.intervals[..], root),
        }
    }

    /// f and its gradient at `p`, the same bits as the reference
    /// interpreter's [`crate::eval::Evaluator::point_grad`].
    pub fn point_grad(&self, p: [f64; 3], ws: &mut Workspace) -> Grad {
        let m = &mut ws.point_duals;
        m.clear();
        m.resize(self.registers, (0.0, [0.0; 3]));
        for instr in &self.code {
            let (o, d) = match instr.form() {
                Form::Var(o, var) => {
                    let mut d = [0.0; 3];
                    d[var.index()] = 1.0;
                    (o, (p[var.index()], d))
                }
                Form::Const(o, c) => (o, (c, [0.0; 3])),
                Form::Unary(o, op, a) => (o, point_dual_unary(op, m[a as usize])),
                Form::Binary(o, op, a, c) => {
                    (o, point_dual_binary(op, m[a as usize], m[c as usize]))
                }
                Form::Powi(o, a, k) => (o, point_dual_powi(m[a as usize], k)),
            };
            m[o as usize] = d;
        }
        let (v, d) = m[self.root_reg()];
        Grad { v, d }
    }

    /// F over `b` and its derivative along every direction in `v`, the
    /// same bits as the reference interpreter's
    /// [`crate::eval::Evaluator::interval_dir`].
    pub fn interval_dir(
        &self,
        b: [Interval; 3],
        v: [Interval; 3],
        ws: &mut Workspace,
    ) -> [Interval; 2] {
        let (f, [d]) = self.duals(b, v.map(|vk| [vk]), &mut ws.dir);
        [f, d]
    }

    /// F over `b` and its three partials, the same bits as the reference
    /// interpreter's [`crate::eval::Evaluator::interval_grad`].
    pub fn interval_grad(&self, b: [Interval; 3], ws: &mut Workspace) -> IntervalGrad {
        let (o, z) = (Interval::point(1.0), Interval::point(0.0));
        let (v, d) = self.duals(b, [[o, z, z], [z, o, z], [z, z, o]], &mut ws.grad);
        IntervalGrad { v, d }
    }

    // Forward mode over the registers: each value with `S` partials, those
    // of coordinate k starting as `seed[k]`.
    fn duals<const S: usize>(
        &self,
        b: [Interval; 3],
        seed: [[Interval; S]; 3],
        m: &mut Vec<IntervalDual<S>>,
    ) -> IntervalDual<S> {
        let zero = Interval::point(0.0);
        m.clear();
        m.resize(self.registers, (zero, [zero; S]));
        for instr in &self.code {
            let (o, d) = match instr.form() {
                Form::Var(o, var) => (o, (b[var.index()], seed[var.index()])),
                Form::Const(o, c) => (o, (Interval::point(c), [zero; S])),
                Form::Unary(o, op, a) => (o, dual_unary(op, m[a as usize])),
                Form::Binary(o, op, a, c) => (o, dual_binary(op, m[a as usize], m[c as usize])),
                Form::Powi(o, a, k) => (o, dual_powi(m[a as usize], k)),
            };
            m[o as usize] = d;
        }
        m[self.root_reg()]
    }

    /// `out[i] = f(xs[i], ys[i], zs[i])`, the same bits as the reference
    /// interpreter.
    pub fn point_batch(&self, [xs, ys, zs]: [&[f64]; 3], out: &mut [f64], ws: &mut Workspace) {
        let n = out.len();
        assert!(xs.len() == n && ys.len() == n && zs.len() == n);
        let m = &mut ws.points;
        m.clear();
        m.resize(self.registers * n, 0.0);
        // Each op writes a scratch column, then copies it into its
        // register: the loops then read and write disjoint slices, which
        // the compiler vectorises, whereas an output register that reuses
        // an operand's would alias it.
        let col = &mut ws.point_column;
        col.clear();
        col.resize(n, 0.0);
        for instr in &self.code {
            let at = |r: Reg| r as usize * n;
            let o = match instr.form() {
                Form::Var(o, v) => {
                    col.copy_from_slice([xs, ys, zs][v.index()]);
                    o
                }
                Form::Const(o, c) => {
                    col.fill(c);
                    o
                }
                Form::Unary(o, op, a) => {
                    point_unary_column(col, op, &m[at(a)..at(a) + n]);
                    o
                }
                Form::Binary(o, op, a, b) => {
                    point_binary_column(col, op, &m[at(a)..at(a) + n], &m[at(b)..at(b) + n]);
                    o
                }
                Form::Powi(o, a, k) => {
                    map1(col, &m[at(a)..at(a) + n], |x| point_powi(x, k));
                    o
                }
            };
            m[at(o)..at(o) + n].copy_from_slice(col);
        }
        let r = self.root_reg() * n;
        out.copy_from_slice(&m[r..r + n]);
    }

    /// `out[i]` contains f over `boxes[i]`, the same bits as the reference
    /// interpreter's interval.
    pub fn interval_batch(
        &self,
        boxes: &[[Interval; 3]],
        out: &mut [Interval],
        ws: &mut Workspace,
    ) {
        let n = out.len();
        assert_eq!(boxes.len(), n);
        let m = &mut ws.intervals;
        m.clear();
        m.resize(self.registers * n, Interval::point(0.0));
        for instr in &self.code {
            let col = |r: Reg| r as usize * n;
            match instr.form() {
                Form::Var(o, v) => {
                    for (i, b) in boxes.iter().enumerate() {
                        m[col(o) + i] = b[v.index()];
                    }
                }
                Form::Const(o, c) => m[col(o)..col(o) + n].fill(Interval::point(c)),
                Form::Unary(o, op, a) => {
                    let (o, a) = (col(o), col(a));
                    interval_unary_column(m, op, n, [o, a]);
                }
                Form::Binary(o, op, a, b) => {
                    let (o, a, b) = (col(o), col(a), col(b));
                    interval_binary_column(m, op, n, [o, a, b]);
                }
                Form::Powi(o, a, k) => {
                    let (o, a) = (col(o), col(a));
                    for i in 0..n {
                        m[o + i] = m[a + i].powi(k);
                    }
                }
            }
        }
        let r = self.root_reg() * n;
        out.copy_from_slice(&m[r..r + n]);
    }
}

/// Tapes with at most this many registers run on a fixed-size register
/// file indexed modulo its size, which the compiler proves in bounds: no
/// bounds check per operand (a tape's registers lie below its count, so
/// the modulo never wraps). Longer tapes run on a slice.
const FIXED_REGISTERS: usize = 256;

/// A register file: one value per register.
pub(super) trait Registers<T: Copy> {
    /// Register `r`'s value.
    fn get(&self, r: Reg) -> T;
    /// Sets register `r`.
    fn set(&mut self, r: Reg, v: T);
}

impl<T: Copy> Registers<T> for [T; FIXED_REGISTERS] {
    #[inline(always)]
    fn get(&self, r: Reg) -> T {
        self[r as usize % FIXED_REGISTERS]
    }
    #[inline(always)]
    fn set(&mut self, r: Reg, v: T) {
        self[r as usize % FIXED_REGISTERS] = v;
    }
}

impl<T: Copy> Registers<T> for [T] {
    #[inline(always)]
    fn get(&self, r: Reg) -> T {
        self[r as usize]
    }
    #[inline(always)]
    fn set(&mut self, r: Reg, v: T) {
        self[r as usize] = v;
    }
}

/// `m` as a fixed register file when `registers` fit one; otherwise `m`
/// is made `registers` long and `None` comes back. Registers are written
/// before they are read (a tape defines each value before its uses), so
/// what earlier runs left in `m` is never seen.
pub(super) fn fixed_registers<T: Copy>(
    m: &mut Vec<T>,
    registers: usize,
    zero: T,
) -> Option<&mut [T; FIXED_REGISTERS]> {
    let len = if registers <= FIXED_REGISTERS {
        FIXED_REGISTERS
    } else {
        registers
    };
    if m.len() < len {
        m.resize(len, zero);
    }
    (registers <= FIXED_REGISTERS).then(|| {
        (&mut m[..FIXED_REGISTERS])
            .try_into()
            .expect("a slice of FIXED_REGISTERS")
    })
}

/// [`Tape::point`]'s pass over `code` with register file `m`.
#[inline(always)]
fn point_pass<M: Registers<f64> + ?Sized>(
    code: &[Instr],
    p: [f64; 3],
    m: &mut M,
    root: Reg,
) -> f64 {
    for instr in code {
        let r = |a: Reg| m.get(a);
        let (o, v) = match *instr {
            Instr::Var(o, v) => (o, p[v.index()]),
            Instr::Const(o, c) => (o, c),
            Instr::Add(o, a, b) => (o, r(a) + r(b)),
            Instr::Sub(o, a, b) => (o, r(a) - r(b)),
            Instr::Mul(o, a, b) => (o, r(a) * r(b)),
            Instr::Min(o, a, b) => (o, point_binary(BinaryOp::Min, r(a), r(b))),
            Instr::Max(o, a, b) => (o, point_binary(BinaryOp::Max, r(a), r(b))),
            Instr::Neg(o, a) => (o, -r(a)),
            Instr::Square(o, a) => (o, r(a) * r(a)),
            Instr::Sqrt(o, a) => (o, r(a).sqrt()),
            Instr::Unary(o, op, a) => (o, point_unary(op, r(a))),
            Instr::Binary(o, op, a, b) => (o, point_binary(op, r(a), r(b))),
            Instr::Powi(o, a, k) => (o, point_powi(r(a), k)),
        };
        m.set(o, v);
    }
    m.get(root)
}

/// [`Tape::interval`]'s pass over `code` with register file `m`.
#[inline(always)]
fn interval_pass<M: Registers<Interval> + ?Sized>(
    code: &[Instr],
    b: [Interval; 3],
    m: &mut M,
    root: Reg,
) -> Interval {
    for instr in code {
        let r = |a: Reg| m.get(a);
        let (o, v) = match *instr {
            Instr::Var(o, v) => (o, b[v.index()]),
            Instr::Const(o, c) => (o, Interval::point(c)),
            Instr::Add(o, a, b) => (o, r(a).add(r(b))),
            Instr::Sub(o, a, b) => (o, r(a).sub(r(b))),
            Instr::Mul(o, a, b) => (o, r(a).mul(r(b))),
            Instr::Min(o, a, b) => (o, r(a).min(r(b))),
            Instr::Max(o, a, b) => (o, r(a).max(r(b))),
            Instr::Neg(o, a) => (o, r(a).neg()),
            Instr::Square(o, a) => (o, r(a).square()),
            Instr::Sqrt(o, a) => (o, r(a).sqrt()),
            Instr::Unary(o, op, a) => (o, interval_unary(op, r(a))),
            Instr::Binary(o, op, a, b) => (o, interval_binary(op, r(a), r(b))),
            Instr::Powi(o, a, k) => (o, r(a).powi(k)),
        };
        m.set(o, v);
    }
    m.get(root)
}

/// `out[i] = f(a[i])` over equal-length columns, a loop the compiler
/// vectorises where `f` is plain arithmetic.
#[inline(always)]
fn map1(out: &mut [f64], a: &[f64], f: impl Fn(f64) -> f64) {
    for (o, &x) in out.iter_mut().zip(a) {
        *o = f(x);
    }
}

/// `out[i] = f(a[i], b[i])`, as [`map1`].
#[inline(always)]
fn map2(out: &mut [f64], a: &[f64], b: &[f64], f: impl Fn(f64, f64) -> f64) {
    for ((o, &x), &y) in out.iter_mut().zip(a).zip(b) {
        *o = f(x, y);
    }
}

/// One unary op over a column of points: the common ops as plain loops,
/// the rest through the reference rule.
fn point_unary_column(out: &mut [f64], op: UnaryOp, a: &[f64]) {
    match op {
        UnaryOp::Neg => map1(out, a, |x| -x),
        UnaryOp::Square => map1(out, a, |x| x * x),
        UnaryOp::Sqrt => map1(out, a, f64::sqrt),
        UnaryOp::Abs => map1(out, a, f64::abs),
        _ => map1(out, a, |x| point_unary(op, x)),
    }
}

/// One binary op over a column of points: the common ops as plain loops
/// (min and max are the reference `min_nan` and `max_nan`, branch-free
/// selects once inlined), the rest through the reference rule.
fn point_binary_column(out: &mut [f64], op: BinaryOp, a: &[f64], b: &[f64]) {
    match op {
        BinaryOp::Add => map2(out, a, b, |x, y| x + y),
        BinaryOp::Sub => map2(out, a, b, |x, y| x - y),
        BinaryOp::Mul => map2(out, a, b, |x, y| x * y),
        BinaryOp::Min => map2(out, a, b, min_nan),
        BinaryOp::Max => map2(out, a, b, max_nan),
        _ => map2(out, a, b, |x, y| point_binary(op, x, y)),
    }
}

/// One unary op over a column of intervals, one loop per common op.
fn interval_unary_column(m: &mut [Interval], op: UnaryOp, n: usize, [o, a]: [usize; 2]) {
    match op {
        UnaryOp::Neg => (0..n).for_each(|i| m[o + i] = m[a + i].neg()),
        UnaryOp::Square => (0..n).for_each(|i| m[o + i] = m[a + i].square()),
        UnaryOp::Sqrt => (0..n).for_each(|i| m[o + i] = m[a + i].sqrt()),
        _ => (0..n).for_each(|i| m[o + i] = interval_unary(op, m[a + i])),
    }
}

/// One binary op over a column of intervals, one loop per common op.
fn interval_binary_column(m: &mut [Interval], op: BinaryOp, n: usize, [o, a, b]: [usize; 3]) {
    match op {
        BinaryOp::Add => (0..n).for_each(|i| m[o + i] = m[a + i].add(m[b + i])),
        BinaryOp::Sub => (0..n).for_each(|i| m[o + i] = m[a + i].sub(m[b + i])),
        BinaryOp::Mul => (0..n).for_each(|i| m[o + i] = m[a + i].mul(m[b + i])),
        BinaryOp::Min => (0..n).for_each(|i| m[o + i] = m[a + i].min(m[b + i])),
        BinaryOp::Max => (0..n).for_each(|i| m[o + i] = m[a + i].max(m[b + i])),
        _ => (0..n).for_each(|i| m[o + i] = interval_binary(op, m[a + i], m[b + i])),
    }
}
