//! Running a tape: one point or box over its registers, with values,
//! gradients or a directional derivative, and batches of points or boxes a
//! column per register. Every result is the reference interpreter's bits.

use super::{Form, Instr, Reg, Tape, Workspace, wide};
use crate::eval::Grad;
use crate::eval::cpu::{self, CpuPath};
use crate::eval::interp::{point_dual_binary, point_dual_powi, point_dual_unary};
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
        self.point_on(cpu::path(), p, ws)
    }

    /// [`Tape::point`] on the compiled path `path` (the same bits on
    /// each).
    pub fn point_on(&self, path: CpuPath, p: [f64; 3], ws: &mut Workspace) -> f64 {
        let root = self.root_reg() as Reg;
        let code = &self.code[..];
        match (fixed_registers(&mut ws.points, self.registers, 0.0), path) {
            (Some(m), CpuPath::Wide) => wide::point_fixed(code, p, m, root),
            (Some(m), CpuPath::Baseline) => point_pass(code, p, m, root),
            (None, CpuPath::Wide) => wide::point_slice(code, p, &mut ws.points[..], root),
            (None, CpuPath::Baseline) => point_pass(code, p, &mut ws.points[..], root),
        }
    }

    /// An interval containing f over `b`, the same bits as the reference
    /// interpreter's (see [`Tape::point`]).
    pub fn interval(&self, b: [Interval; 3], ws: &mut Workspace) -> Interval {
        self.interval_on(cpu::path(), b, ws)
    }

    /// [`Tape::interval`] on the compiled path `path` (the same bits on
    /// each).
    pub fn interval_on(&self, path: CpuPath, b: [Interval; 3], ws: &mut Workspace) -> Interval {
        let root = self.root_reg() as Reg;
        let code = &self.code[..];
        let zero = Interval::point(0.0);
        match (
            fixed_registers(&mut ws.intervals, self.registers, zero),
            path,
        ) {
            (Some(m), CpuPath::Wide) => wide::interval_fixed(code, b, m, root),
            (Some(m), CpuPath::Baseline) => interval_pass(code, b, m, root),
            (None, CpuPath::Wide) => wide::interval_slice(code, b, &mut ws.intervals[..], root),
            (None, CpuPath::Baseline) => interval_pass(code, b, &mut ws.intervals[..], root),
        }
    }

    /// f and its gradient at `p`, the same bits as the reference
    /// interpreter's [`crate::eval::Single::point_grad`].
    pub fn point_grad(&self, p: [f64; 3], ws: &mut Workspace) -> Grad {
        // Every register is written before it is read: no clearing.
        let m = &mut ws.point_duals;
        if m.len() < self.registers {
            m.resize(self.registers, (0.0, [0.0; 3]));
        }
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

    /// `out[i]` = f and its gradient at `(xs[i], ys[i], zs[i])`, the same
    /// bits as [`Tape::point_grad`] at each point: one pass over the tape
    /// for all of them, a column of values and partials per register.
    pub fn point_grad_batch(
        &self,
        [xs, ys, zs]: [&[f64]; 3],
        out: &mut [Grad],
        ws: &mut Workspace,
    ) {
        let n = out.len();
        assert!(xs.len() == n && ys.len() == n && zs.len() == n);
        // Every register is written before it is read: no clearing.
        let m = &mut ws.point_duals;
        if m.len() < self.registers * n {
            m.resize(self.registers * n, (0.0, [0.0; 3]));
        }
        let m = &mut m[..self.registers * n];
        for instr in &self.code {
            let col = |r: Reg| r as usize * n;
            match instr.form() {
                Form::Var(o, var) => {
                    let k = var.index();
                    let mut d = [0.0; 3];
                    d[k] = 1.0;
                    let v = [xs, ys, zs][k];
                    for (slot, &x) in m[col(o)..col(o) + n].iter_mut().zip(v) {
                        *slot = (x, d);
                    }
                }
                Form::Const(o, c) => m[col(o)..col(o) + n].fill((c, [0.0; 3])),
                Form::Unary(o, op, a) => point_dual_unary_column(m, n, [o, a], op),
                Form::Binary(o, op, a, b) => point_dual_binary_column(m, n, [o, a, b], op),
                Form::Powi(o, a, k) => apply1(m, n, [o, a], |x| point_dual_powi(x, k)),
            }
        }
        let r = self.root_reg() * n;
        for (g, &(v, d)) in out.iter_mut().zip(&m[r..r + n]) {
            *g = Grad { v, d };
        }
    }

    /// `out[i] = f(xs[i], ys[i], zs[i])`, the same bits as the reference
    /// interpreter.
    pub fn point_batch(&self, xyz: [&[f64]; 3], out: &mut [f64], ws: &mut Workspace) {
        self.point_batch_on(cpu::path(), xyz, out, ws);
    }

    /// [`Tape::point_batch`] on the compiled path `path` (the same bits on
    /// each).
    pub fn point_batch_on(
        &self,
        path: CpuPath,
        xyz: [&[f64]; 3],
        out: &mut [f64],
        ws: &mut Workspace,
    ) {
        match path {
            CpuPath::Wide => wide::point_batch(self, xyz, out, ws),
            CpuPath::Baseline => point_batch_pass(self, xyz, out, ws),
        }
    }

    /// `out[i]` contains f over `boxes[i]`, the same bits as the reference
    /// interpreter's interval.
    pub fn interval_batch(
        &self,
        boxes: &[[Interval; 3]],
        out: &mut [Interval],
        ws: &mut Workspace,
    ) {
        self.interval_batch_on(cpu::path(), boxes, out, ws);
    }

    /// [`Tape::interval_batch`] on the compiled path `path` (the same bits
    /// on each).
    pub fn interval_batch_on(
        &self,
        path: CpuPath,
        boxes: &[[Interval; 3]],
        out: &mut [Interval],
        ws: &mut Workspace,
    ) {
        match path {
            CpuPath::Wide => wide::interval_batch(self, boxes, out, ws),
            CpuPath::Baseline => interval_batch_pass(self, boxes, out, ws),
        }
    }
}

/// [`Tape::point_batch`]'s pass, inlined into each path's code.
#[inline(always)]
pub(super) fn point_batch_pass(
    tape: &Tape,
    [xs, ys, zs]: [&[f64]; 3],
    out: &mut [f64],
    ws: &mut Workspace,
) {
    let n = out.len();
    assert!(xs.len() == n && ys.len() == n && zs.len() == n);
    // Every register is written before it is read (the tape is in
    // order), so the columns need no clearing between calls.
    let m = &mut ws.points;
    if m.len() < tape.registers * n {
        m.resize(tape.registers * n, 0.0);
    }
    let m = &mut m[..tape.registers * n];
    for instr in &tape.code {
        let at = |r: Reg| r as usize * n;
        match instr.form() {
            Form::Var(o, v) => m[at(o)..at(o) + n].copy_from_slice([xs, ys, zs][v.index()]),
            Form::Const(o, c) => m[at(o)..at(o) + n].fill(c),
            Form::Unary(o, op, a) => point_unary_column(m, n, [o, a], op),
            Form::Binary(o, op, a, b) => point_binary_column(m, n, [o, a, b], op),
            Form::Powi(o, a, k) => apply1(m, n, [o, a], |x| point_powi(x, k)),
        }
    }
    let r = tape.root_reg() * n;
    out.copy_from_slice(&m[r..r + n]);
}

/// [`Tape::interval_batch`]'s pass, inlined into each path's code.
#[inline(always)]
pub(super) fn interval_batch_pass(
    tape: &Tape,
    boxes: &[[Interval; 3]],
    out: &mut [Interval],
    ws: &mut Workspace,
) {
    let n = out.len();
    assert_eq!(boxes.len(), n);
    // As in `point_batch`: no clearing, columns updated in place.
    let m = &mut ws.intervals;
    if m.len() < tape.registers * n {
        m.resize(tape.registers * n, Interval::point(0.0));
    }
    let m = &mut m[..tape.registers * n];
    for instr in &tape.code {
        let col = |r: Reg| r as usize * n;
        match instr.form() {
            Form::Var(o, v) => {
                for (d, b) in m[col(o)..col(o) + n].iter_mut().zip(boxes) {
                    *d = b[v.index()];
                }
            }
            Form::Const(o, c) => m[col(o)..col(o) + n].fill(Interval::point(c)),
            Form::Unary(o, op, a) => interval_unary_column(m, n, [o, a], op),
            Form::Binary(o, op, a, b) => interval_binary_column(m, n, [o, a, b], op),
            Form::Powi(o, a, k) => apply1(m, n, [o, a], |x| x.powi(k)),
        }
    }
    let r = tape.root_reg() * n;
    out.copy_from_slice(&m[r..r + n]);
}

/// Tapes with at most this many registers run on a fixed-size register
/// file indexed modulo its size, which the compiler proves in bounds: no
/// bounds check per operand (a tape's registers lie below its count, so
/// the modulo never wraps). Longer tapes run on a slice.
pub(super) const FIXED_REGISTERS: usize = 256;

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
pub(super) fn point_pass<M: Registers<f64> + ?Sized>(
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
pub(super) fn interval_pass<M: Registers<Interval> + ?Sized>(
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

/// Column `o` of `m` (columns `n` long) set to `f` of column `a`, in one
/// loop the compiler vectorises where `f` is plain arithmetic. The
/// register allocator often gives an op the register of an operand that
/// dies there: then the column is updated in place, element by element,
/// which reads each operand before writing it. (A scratch column copied
/// into the register after every op cost a `memcpy` call per op, 3% of a
/// colonnade render.)
#[inline(always)]
fn apply1<T: Copy>(m: &mut [T], n: usize, [o, a]: [Reg; 2], f: impl Fn(T) -> T) {
    let (dst, [x, _]) = split_columns(m, n, o, [a, a]);
    match x {
        Some(x) => dst.iter_mut().zip(x).for_each(|(d, &x)| *d = f(x)),
        None => dst.iter_mut().for_each(|d| *d = f(*d)),
    }
}

/// Column `o` of `m` set to `f` of columns `a` and `b`, as [`apply1`].
#[inline(always)]
fn apply2<T: Copy>(m: &mut [T], n: usize, [o, a, b]: [Reg; 3], f: impl Fn(T, T) -> T) {
    let (dst, [x, y]) = split_columns(m, n, o, [a, b]);
    match (x, y) {
        (Some(x), Some(y)) => {
            for ((d, &x), &y) in dst.iter_mut().zip(x).zip(y) {
                *d = f(x, y);
            }
        }
        (None, Some(y)) => dst.iter_mut().zip(y).for_each(|(d, &y)| *d = f(*d, y)),
        (Some(x), None) => dst.iter_mut().zip(x).for_each(|(d, &x)| *d = f(x, *d)),
        (None, None) => dst.iter_mut().for_each(|d| *d = f(*d, *d)),
    }
}

/// Register `o`'s column of `m` (columns `n` long), to write, and the
/// columns of `operands` to read (`None` for an operand that is `o`).
#[inline(always)]
fn split_columns<T>(
    m: &mut [T],
    n: usize,
    o: Reg,
    operands: [Reg; 2],
) -> (&mut [T], [Option<&[T]>; 2]) {
    let (before, rest) = m.split_at_mut(o as usize * n);
    let (dst, after) = rest.split_at_mut(n);
    let read = |r: Reg| -> Option<&[T]> {
        let at = r as usize * n;
        match r.cmp(&o) {
            std::cmp::Ordering::Less => Some(&before[at..at + n]),
            std::cmp::Ordering::Equal => None,
            std::cmp::Ordering::Greater => Some(&after[at - (o as usize + 1) * n..][..n]),
        }
    };
    (dst, operands.map(read))
}

/// One unary op over a column of points: the common ops as plain loops,
/// the rest through the reference rule.
#[inline(always)]
fn point_unary_column(m: &mut [f64], n: usize, regs: [Reg; 2], op: UnaryOp) {
    match op {
        UnaryOp::Neg => apply1(m, n, regs, |x| -x),
        UnaryOp::Square => apply1(m, n, regs, |x| x * x),
        UnaryOp::Sqrt => apply1(m, n, regs, f64::sqrt),
        UnaryOp::Abs => apply1(m, n, regs, f64::abs),
        _ => apply1(m, n, regs, |x| point_unary(op, x)),
    }
}

/// One binary op over a column of points: the common ops as plain loops
/// (min and max are the reference `min_nan` and `max_nan`, branch-free
/// selects once inlined), the rest through the reference rule.
#[inline(always)]
fn point_binary_column(m: &mut [f64], n: usize, regs: [Reg; 3], op: BinaryOp) {
    match op {
        BinaryOp::Add => apply2(m, n, regs, |x, y| x + y),
        BinaryOp::Sub => apply2(m, n, regs, |x, y| x - y),
        BinaryOp::Mul => apply2(m, n, regs, |x, y| x * y),
        BinaryOp::Min => apply2(m, n, regs, min_nan),
        BinaryOp::Max => apply2(m, n, regs, max_nan),
        _ => apply2(m, n, regs, |x, y| point_binary(op, x, y)),
    }
}

/// Values with partials: a column of points through one unary op, each
/// common op in a loop of its own where the reference rule inlines with
/// the op known (one call and one dispatch per point otherwise: on 1000
/// spheres, the normals of included blocks cost three times their roots'
/// refinement).
#[inline(always)]
fn point_dual_unary_column(m: &mut [Dual], n: usize, regs: [Reg; 2], op: UnaryOp) {
    match op {
        UnaryOp::Neg => apply1(m, n, regs, |x| point_dual_unary(UnaryOp::Neg, x)),
        UnaryOp::Square => apply1(m, n, regs, |x| point_dual_unary(UnaryOp::Square, x)),
        UnaryOp::Sqrt => apply1(m, n, regs, |x| point_dual_unary(UnaryOp::Sqrt, x)),
        _ => apply1(m, n, regs, |x| point_dual_unary(op, x)),
    }
}

/// Values with partials through one binary op, as
/// [`point_dual_unary_column`].
#[inline(always)]
fn point_dual_binary_column(m: &mut [Dual], n: usize, regs: [Reg; 3], op: BinaryOp) {
    use BinaryOp::{Add, Max, Min, Mul, Sub};
    match op {
        Add => apply2(m, n, regs, |x, y| point_dual_binary(Add, x, y)),
        Sub => apply2(m, n, regs, |x, y| point_dual_binary(Sub, x, y)),
        Mul => apply2(m, n, regs, |x, y| point_dual_binary(Mul, x, y)),
        Min => apply2(m, n, regs, |x, y| point_dual_binary(Min, x, y)),
        Max => apply2(m, n, regs, |x, y| point_dual_binary(Max, x, y)),
        _ => apply2(m, n, regs, |x, y| point_dual_binary(op, x, y)),
    }
}

/// A value and its three partials.
type Dual = (f64, [f64; 3]);

/// One unary op over a column of intervals, one loop per common op (in
/// place where the output register is the operand's, see [`apply1`]).
#[inline(always)]
fn interval_unary_column(m: &mut [Interval], n: usize, regs: [Reg; 2], op: UnaryOp) {
    match op {
        UnaryOp::Neg => apply1(m, n, regs, Interval::neg),
        UnaryOp::Square => apply1(m, n, regs, Interval::square),
        UnaryOp::Sqrt => apply1(m, n, regs, Interval::sqrt),
        _ => apply1(m, n, regs, |x| interval_unary(op, x)),
    }
}

/// One binary op over a column of intervals, one loop per common op.
#[inline(always)]
fn interval_binary_column(m: &mut [Interval], n: usize, regs: [Reg; 3], op: BinaryOp) {
    match op {
        BinaryOp::Add => apply2(m, n, regs, Interval::add),
        BinaryOp::Sub => apply2(m, n, regs, Interval::sub),
        BinaryOp::Mul => apply2(m, n, regs, Interval::mul),
        BinaryOp::Min => apply2(m, n, regs, Interval::min),
        BinaryOp::Max => apply2(m, n, regs, Interval::max),
        _ => apply2(m, n, regs, |x, y| interval_binary(op, x, y)),
    }
}
