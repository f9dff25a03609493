//! The tape passes compiled again for AVX2 and FMA, which `multiversion`
//! selects at run time where the CPU has both (see [`crate::eval::cpu`]).
//! Each clone inlines the same pass as the baseline path. Only the passes
//! that gained are cloned: the directional and gradient passes ran slower
//! in a whole-program AVX2 build (`docs/performance.md`).

use multiversion::multiversion;

use super::passes::prune_pass;
use super::run::{
    FIXED_REGISTERS, interval_batch_pass, interval_pass, point_batch_pass, point_pass,
};
use super::{Facts, Instr, Reg, Tape, Workspace};
use crate::interval::Interval;
use crate::ir::Op;

/// [`Tape::point`]'s pass on a fixed register file.
#[multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn point_fixed(
    code: &[Instr],
    p: [f64; 3],
    m: &mut [f64; FIXED_REGISTERS],
    root: Reg,
) -> f64 {
    point_pass(code, p, m, root)
}

/// [`Tape::point`]'s pass on a register slice.
#[multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn point_slice(code: &[Instr], p: [f64; 3], m: &mut [f64], root: Reg) -> f64 {
    point_pass(code, p, m, root)
}

/// [`Tape::interval`]'s pass on a fixed register file.
#[multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn interval_fixed(
    code: &[Instr],
    b: [Interval; 3],
    m: &mut [Interval; FIXED_REGISTERS],
    root: Reg,
) -> Interval {
    interval_pass(code, b, m, root)
}

/// [`Tape::interval`]'s pass on a register slice.
#[multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn interval_slice(
    code: &[Instr],
    b: [Interval; 3],
    m: &mut [Interval],
    root: Reg,
) -> Interval {
    interval_pass(code, b, m, root)
}

/// [`Tape::point_batch`]'s pass.
#[multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn point_batch(tape: &Tape, xyz: [&[f64]; 3], out: &mut [f64], ws: &mut Workspace) {
    point_batch_pass(tape, xyz, out, ws);
}

/// [`Tape::interval_batch`]'s pass.
#[multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn interval_batch(
    tape: &Tape,
    boxes: &[[Interval; 3]],
    out: &mut [Interval],
    ws: &mut Workspace,
) {
    interval_batch_pass(tape, boxes, out, ws);
}

/// The pruning pass of [`Tape::prune_to_at_most`] on fixed register files.
#[multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn prune_fixed(
    code: &[Instr],
    ops: &[Op],
    sign_only: &[bool],
    b: [Interval; 3],
    regs: &mut [Interval; FIXED_REGISTERS],
    facts: &mut [Facts; FIXED_REGISTERS],
    alias: &mut [usize],
) -> usize {
    prune_pass(code, ops, sign_only, b, (regs, facts), alias)
}
