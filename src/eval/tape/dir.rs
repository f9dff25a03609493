//! The interval passes with derivatives, [`Tape::interval_dir`] (F over a
//! box and its derivative along one direction) and
//! [`Tape::interval_grad`]: on a fixed register file where the tape
//! fits, each common op's rule chosen by the instruction itself.
//!
//! The general pass these replaced turned each instruction into an op
//! code and matched on it again inside the reference rules; the centred
//! form runs the directional kind on every ray piece it tries (13% of the
//! samples of 3000 spheres with shadows). The rules are the reference
//! interpreter's own functions ([`dual_unary`], [`dual_binary`]), called
//! with constant op codes, so the bits are the interpreter's.

use super::run::{Registers, fixed_registers};
use super::{Instr, Reg, Tape, Workspace};
use crate::eval::IntervalGrad;
use crate::eval::interp::{IntervalDual, dual_binary, dual_powi, dual_unary};
use crate::interval::Interval;
use crate::ir::{BinaryOp, UnaryOp};

impl Tape {
    /// F over `b` and its derivative along every direction in `v`, the
    /// same bits as the reference interpreter's
    /// [`crate::eval::Single::interval_dir`].
    pub fn interval_dir(
        &self,
        b: [Interval; 3],
        v: [Interval; 3],
        ws: &mut Workspace,
    ) -> [Interval; 2] {
        let root = self.root_reg() as Reg;
        let code = &self.code[..];
        let zero = Interval::point(0.0);
        let seed = v.map(|vk| [vk]);
        let (f, [d]) = match fixed_registers(&mut ws.dir, self.registers, (zero, [zero])) {
            Some(m) => dual_pass(code, b, seed, m, root),
            None => dual_pass(code, b, seed, &mut ws.dir[..], root),
        };
        [f, d]
    }

    /// F over `b` and its three partials, the same bits as the reference
    /// interpreter's [`crate::eval::Single::interval_grad`].
    pub fn interval_grad(&self, b: [Interval; 3], ws: &mut Workspace) -> IntervalGrad {
        let root = self.root_reg() as Reg;
        let code = &self.code[..];
        let (o, z) = (Interval::point(1.0), Interval::point(0.0));
        let seed = [[o, z, z], [z, o, z], [z, z, o]];
        let (v, d) = match fixed_registers(&mut ws.grad, self.registers, (z, [z; 3])) {
            Some(m) => dual_pass(code, b, seed, m, root),
            None => dual_pass(code, b, seed, &mut ws.grad[..], root),
        };
        IntervalGrad { v, d }
    }
}

/// F over `b` and `S` partials, those of coordinate k starting as
/// `seed[k]`, through `code` with register file `m` (every register is
/// written before it is read).
#[inline(always)]
fn dual_pass<const S: usize, M: Registers<IntervalDual<S>> + ?Sized>(
    code: &[Instr],
    b: [Interval; 3],
    seed: [[Interval; S]; 3],
    m: &mut M,
    root: Reg,
) -> IntervalDual<S> {
    // Each arm stores its own result: with one store after the `match`,
    // every arm wrote its two intervals to a stack slot as four scalars
    // that the store then read back as two vectors, a failed store
    // forwarding that stalled a third of the pass.
    for instr in code {
        let r = |a: Reg| m.get(a);
        match *instr {
            Instr::Var(o, var) => m.set(o, (b[var.index()], seed[var.index()])),
            Instr::Const(o, c) => m.set(o, (Interval::point(c), [Interval::point(0.0); S])),
            Instr::Add(o, a, c) => m.set(o, dual_binary(BinaryOp::Add, r(a), r(c))),
            Instr::Sub(o, a, c) => m.set(o, dual_binary(BinaryOp::Sub, r(a), r(c))),
            Instr::Mul(o, a, c) => m.set(o, dual_binary(BinaryOp::Mul, r(a), r(c))),
            Instr::Min(o, a, c) => m.set(o, dual_binary(BinaryOp::Min, r(a), r(c))),
            Instr::Max(o, a, c) => m.set(o, dual_binary(BinaryOp::Max, r(a), r(c))),
            Instr::Neg(o, a) => m.set(o, dual_unary(UnaryOp::Neg, r(a))),
            Instr::Square(o, a) => m.set(o, dual_unary(UnaryOp::Square, r(a))),
            Instr::Sqrt(o, a) => m.set(o, dual_unary(UnaryOp::Sqrt, r(a))),
            Instr::Unary(o, op, a) => m.set(o, dual_unary(op, r(a))),
            Instr::Binary(o, op, a, c) => m.set(o, dual_binary(op, r(a), r(c))),
            Instr::Powi(o, a, k) => m.set(o, dual_powi(r(a), k)),
        }
    }
    m.get(root)
}
