//! Tapes: a function's live ops in evaluation order with registers
//! assigned, evaluated over many points or boxes per pass, and pruned to a
//! region in two passes without rebuilding a [`Function`] (after Fidget).
//!
//! A [`Tape`] keeps two views of the same ops:
//! - `ssa`: the ops as a [`Function`] whose root is its last op, which the
//!   IR's printer and validator understand and pruning reads;
//! - `code`: one [`Instr`] per op, reading and writing registers. A value
//!   holds its register from its definition to its last use, so a tape
//!   needs as many registers as values are alive at once (a few dozen for
//!   a CSG tree of thousands of ops), and batch evaluation keeps one
//!   column of the batch per register, not per op.
//!
//! Batch evaluation runs the loop over the batch inside each op, so that
//! each op's loop is a tight pass over contiguous memory the compiler can
//! vectorise. Every value is the same bits as the reference interpreter's
//! (both call the rules of [`crate::ir::semantics`]).
//!
//! [`Tape::prune`] evaluates the tape's intervals over a box once,
//! recording for each `min`/`max` whether one operand always wins there
//! (the rules of [`crate::ir::prune`], so the pruned tape gives the same
//! bits at every point of the box), then one backward pass writes the
//! child tape: it keeps only what the root still reads through the
//! decided nodes and assigns registers as it goes (a value's register is
//! taken at its last use, met first when walking backwards, and freed at
//! its definition). A child prunes further to a smaller box from its own
//! tape, never from the whole function. A tape that keeps signs only
//! ([`Tape::keeping_signs`], the renderer's) also drops the members of a
//! union proven positive on the box: its children give the root's sign,
//! not its bits.

use std::sync::Arc;

use crate::eval::cpu::{self, CpuPath};
use crate::eval::interp::IntervalDual;
use crate::interval::Interval;
use crate::ir::prune::{
    Facts, binary_facts, const_facts, decided_operand, powi_facts, sign_decided_operand,
    unary_facts, var_facts,
};
use crate::ir::semantics::{interval_binary, interval_unary};
use crate::ir::{BinaryOp, Function, Op, UnaryOp, ValueId, Var};

mod dir;
mod run;
mod wide;

use run::{Registers, fixed_registers};

mod passes;
use passes::*;

/// A register index.
pub type Reg = u32;

/// One instruction: an op over registers. The ops of distance fields and
/// CSG have variants of their own, so that the scalar loops dispatch once
/// per instruction rather than on the instruction and then on its op.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Instr {
    /// `out = var`.
    Var(Reg, Var),
    /// `out = c`.
    Const(Reg, f64),
    /// `out = a + b`.
    Add(Reg, Reg, Reg),
    /// `out = a - b`.
    Sub(Reg, Reg, Reg),
    /// `out = a * b`.
    Mul(Reg, Reg, Reg),
    /// `out = min(a, b)`.
    Min(Reg, Reg, Reg),
    /// `out = max(a, b)`.
    Max(Reg, Reg, Reg),
    /// `out = -a`.
    Neg(Reg, Reg),
    /// `out = a²`.
    Square(Reg, Reg),
    /// `out = sqrt(a)`.
    Sqrt(Reg, Reg),
    /// `out = op(a)`, any other one-operand op.
    Unary(Reg, UnaryOp, Reg),
    /// `out = op(a, b)`, any other two-operand op.
    Binary(Reg, BinaryOp, Reg, Reg),
    /// `out = a^n`.
    Powi(Reg, Reg, i32),
}

/// An instruction in general form: one variant per arity (what the
/// loops that treat every op alike match on).
#[derive(Copy, Clone, Debug, PartialEq)]
enum Form {
    Var(Reg, Var),
    Const(Reg, f64),
    Unary(Reg, UnaryOp, Reg),
    Binary(Reg, BinaryOp, Reg, Reg),
    Powi(Reg, Reg, i32),
}

impl Instr {
    /// `out = op(a)`.
    pub fn unary(out: Reg, op: UnaryOp, a: Reg) -> Instr {
        match op {
            UnaryOp::Neg => Instr::Neg(out, a),
            UnaryOp::Square => Instr::Square(out, a),
            UnaryOp::Sqrt => Instr::Sqrt(out, a),
            _ => Instr::Unary(out, op, a),
        }
    }

    /// `out = op(a, b)`.
    pub fn binary(out: Reg, op: BinaryOp, a: Reg, b: Reg) -> Instr {
        match op {
            BinaryOp::Add => Instr::Add(out, a, b),
            BinaryOp::Sub => Instr::Sub(out, a, b),
            BinaryOp::Mul => Instr::Mul(out, a, b),
            BinaryOp::Min => Instr::Min(out, a, b),
            BinaryOp::Max => Instr::Max(out, a, b),
            _ => Instr::Binary(out, op, a, b),
        }
    }

    /// The instruction in general form.
    #[inline]
    fn form(self) -> Form {
        match self {
            Instr::Var(o, v) => Form::Var(o, v),
            Instr::Const(o, c) => Form::Const(o, c),
            Instr::Add(o, a, b) => Form::Binary(o, BinaryOp::Add, a, b),
            Instr::Sub(o, a, b) => Form::Binary(o, BinaryOp::Sub, a, b),
            Instr::Mul(o, a, b) => Form::Binary(o, BinaryOp::Mul, a, b),
            Instr::Min(o, a, b) => Form::Binary(o, BinaryOp::Min, a, b),
            Instr::Max(o, a, b) => Form::Binary(o, BinaryOp::Max, a, b),
            Instr::Neg(o, a) => Form::Unary(o, UnaryOp::Neg, a),
            Instr::Square(o, a) => Form::Unary(o, UnaryOp::Square, a),
            Instr::Sqrt(o, a) => Form::Unary(o, UnaryOp::Sqrt, a),
            Instr::Unary(o, op, a) => Form::Unary(o, op, a),
            Instr::Binary(o, op, a, b) => Form::Binary(o, op, a, b),
            Instr::Powi(o, a, n) => Form::Powi(o, a, n),
        }
    }

    /// The register it writes.
    pub fn out(&self) -> Reg {
        match self.form() {
            Form::Var(o, _)
            | Form::Const(o, _)
            | Form::Unary(o, ..)
            | Form::Binary(o, ..)
            | Form::Powi(o, ..) => o,
        }
    }
}

/// A register-allocated evaluation tape (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Tape {
    ssa: Arc<Function>,
    code: Vec<Instr>,
    registers: usize,
    // What its pruned children keep; under `Keep::Signs`, which ops reach
    // the root through `min`/`max` and negations alone (empty under
    // `Keep::Bits`).
    keep: Keep,
    sign_only: Vec<bool>,
}

/// What a tape pruned to a box keeps of its parent there.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Keep {
    /// Every value, bit for bit: the contract of [`crate::ir::prune`].
    #[default]
    Bits,
    /// The root's sign at every point of the box (negative, zero,
    /// positive or NaN), and bit for bit every value the root's sign
    /// depends on through more than `min`, `max` and negation. A ray
    /// tracer needs no more: the surface and the solid are where the root
    /// is zero and negative. See [`Tape::keeping_signs`].
    Signs,
}

/// Per-thread scratch space for batch evaluation: one column of the batch
/// per register, reused across calls.
#[derive(Clone, Default, Debug)]
pub struct Workspace {
    points: Vec<f64>,
    intervals: Vec<Interval>,
    point_duals: Vec<(f64, [f64; 3])>,
    dir: Vec<IntervalDual<1>>,
    grad: Vec<IntervalDual<3>>,
    // Scratch of `Tape::prune`: facts per register, aliases and liveness
    // per op.
    facts: Vec<Facts>,
    alias: Vec<usize>,
    live: Vec<bool>,
    // The kept ops, last first (see `liveness`).
    order: Vec<u32>,
    child: ChildScratch,
    // Per box of `Tape::prune_batch`: its decided `min`/`max` ops, each
    // with the operand it picks, in tape order.
    picks: Vec<Picks>,
}

thread_local! {
    static WORKSPACE: std::cell::RefCell<Workspace> = std::cell::RefCell::new(Workspace::default());
}

/// Runs `f` with this thread's batch workspace (for callers that evaluate
/// tapes through `&self` APIs, such as the regional evaluator's batches).
pub fn with_workspace<R>(f: impl FnOnce(&mut Workspace) -> R) -> R {
    WORKSPACE.with(|ws| f(&mut ws.borrow_mut()))
}

/// The result of [`Tape::prune`].
#[derive(Clone, Debug)]
pub struct PrunedTape {
    /// The tape restricted to the box.
    pub tape: Tape,
    /// How many `min`/`max` nodes were decided.
    pub decided: usize,
}

impl Tape {
    /// The tape of `f`'s live ops, scheduled depth first from the root:
    /// each op comes just before the first op that reads it, so a tree of
    /// n ops needs registers for about its depth, not its width (lowering
    /// and the balancing pass put all the leaves of a long `min` first).
    pub fn new(f: &Function) -> Tape {
        let order = depth_first(f);
        let mut index = vec![ValueId(0); f.ops.len()];
        let mut ops = Vec::with_capacity(order.len());
        for &i in &order {
            index[i] = ValueId(ops.len() as u32);
            ops.push(f.ops[i].map_operands(|a| index[a.index()]));
        }
        let root = index[f.root.index()];
        let identity: Vec<usize> = (0..ops.len()).collect();
        let ssa = Function { ops, root };
        let (mut live, mut order) = (Vec::new(), Vec::new());
        liveness(&ssa, &identity, &mut live, &mut order);
        Tape::write_child(
            &ssa,
            Keep::Bits,
            &identity,
            &order,
            &mut ChildScratch::default(),
        )
    }

    /// The same tape, whose prunings (and theirs, nested) keep only the
    /// root's sign on their box ([`Keep::Signs`]).
    ///
    /// A `min(a, b)` that only `min`/`max` ops and negations lie between it
    /// and the root (a union, directly or inside an intersection or the
    /// cut of a difference) is replaced by `a` over a box where `b` is
    /// proven positive and defined: at every point there, `min(a, b)` and
    /// `a` have the same sign (and are NaN together), and the sign of a
    /// `min` or `max` of two values depends only on their signs (a
    /// negation's on its operand's), so the root keeps its sign. Likewise
    /// a `max` whose other operand is proven negative. Value pruning
    /// ([`Keep::Bits`]) drops `b` only where it is proven above `a`; over
    /// a long box through a union of many small objects every object's
    /// interval overlaps the nearest one's, and nearly nothing is dropped,
    /// while every object that misses the box is proven positive on it.
    ///
    /// What changes is the root's value off its zero set, so what
    /// combines values from several evaluations must take them from one
    /// tape (see [`crate::eval::Specialise::answering`]); intervals over a
    /// box inside the pruned one hold 0, or lie above or below it,
    /// exactly when the whole function's do (`min` and `max` are monotone
    /// and keep their operands' signs).
    pub fn keeping_signs(mut self) -> Tape {
        self.sign_only = sign_only_ops(&self.ssa);
        self.keep = Keep::Signs;
        self
    }

    /// What the tape's prunings keep.
    pub fn keeps(&self) -> Keep {
        self.keep
    }

    /// The ops as a function (its root is the last op).
    pub fn function(&self) -> &Function {
        &self.ssa
    }

    /// [`Tape::function`], shared (an interpreter of the tape holds it
    /// without a copy).
    pub fn shared_function(&self) -> Arc<Function> {
        Arc::clone(&self.ssa)
    }

    /// The instructions, one per op of [`Tape::function`].
    pub fn code(&self) -> &[Instr] {
        &self.code
    }

    /// Number of ops.
    pub fn len(&self) -> usize {
        self.code.len()
    }

    /// Whether the tape has no op (never true: a tape has a root).
    pub fn is_empty(&self) -> bool {
        self.code.is_empty()
    }

    /// Registers the tape needs.
    pub fn registers(&self) -> usize {
        self.registers
    }

    fn root_reg(&self) -> usize {
        self.code.last().map_or(0, |i| i.out() as usize)
    }

    /// The tape restricted to the box `b`: `None` when no `min`/`max` is
    /// decided there (see the module doc and [`crate::ir::prune`]).
    pub fn prune(&self, b: [Interval; 3], ws: &mut Workspace) -> Option<PrunedTape> {
        self.prune_to_at_most(b, usize::MAX, ws)
    }

    /// [`Tape::prune`], but `None` as well when the child would keep more
    /// than `max_len` ops (counted before it is written, which is most of
    /// the cost of a pruning that does not pay).
    pub fn prune_to_at_most(
        &self,
        b: [Interval; 3],
        max_len: usize,
        ws: &mut Workspace,
    ) -> Option<PrunedTape> {
        self.prune_to_at_most_on(cpu::path(), b, max_len, ws)
    }

    /// [`Tape::prune_to_at_most`] on the compiled path `path` (the same
    /// tape on each).
    pub fn prune_to_at_most_on(
        &self,
        path: CpuPath,
        b: [Interval; 3],
        max_len: usize,
        ws: &mut Workspace,
    ) -> Option<PrunedTape> {
        let ops = &self.ssa.ops;
        let n = ops.len();
        // alias[k]: the op whose value op k always equals on the box.
        let alias = &mut ws.alias;
        alias.clear();
        alias.extend(0..n);
        // Values and facts live in registers, as in evaluation: a few dozen
        // slots, not one per op.
        let zero = Interval::point(0.0);
        let decided = match (
            fixed_registers(&mut ws.intervals, self.registers, zero),
            fixed_registers(&mut ws.facts, self.registers, Facts::default()),
        ) {
            (Some(regs), Some(fact)) if path == CpuPath::Wide => {
                wide::prune_fixed(&self.code, ops, &self.sign_only, b, regs, fact, alias)
            }
            (Some(regs), Some(fact)) => {
                prune_pass(&self.code, ops, &self.sign_only, b, (regs, fact), alias)
            }
            _ => prune_pass(
                &self.code,
                ops,
                &self.sign_only,
                b,
                (&mut ws.intervals[..], &mut ws.facts[..]),
                alias,
            ),
        };
        if decided == 0 {
            return None;
        }
        // Ops the child keeps: those the root reads through the aliases.
        let kept = liveness(&self.ssa, alias, &mut ws.live, &mut ws.order);
        if kept > max_len {
            return None;
        }
        Some(PrunedTape {
            tape: Tape::write_child(&self.ssa, self.keep, alias, &ws.order, &mut ws.child),
            decided,
        })
    }

    /// [`Tape::prune_to_at_most`] to each of `boxes`, the same tapes, with
    /// one forward pass over the tape for all of them: each instruction is
    /// dispatched once and applied box after box, as in batch evaluation,
    /// where one pass per box dispatched every instruction again (twice
    /// the cost of an interval evaluation, for a pass that is mostly that).
    /// Sibling regions (the quarters of a block, the tiles of a group)
    /// prune from the same parent, so they come in batches.
    pub fn prune_batch(
        &self,
        boxes: &[[Interval; 3]],
        max_len: usize,
        ws: &mut Workspace,
    ) -> Vec<Option<PrunedTape>> {
        let lanes = boxes.len();
        let ops = &self.ssa.ops;
        let Workspace {
            intervals,
            facts,
            alias,
            live,
            order,
            child,
            picks,
            ..
        } = ws;
        let cells = self.registers * lanes;
        if intervals.len() < cells {
            intervals.resize(cells, Interval::point(0.0));
        }
        if facts.len() < cells {
            facts.resize(cells, Facts::default());
        }
        if picks.len() < lanes {
            picks.resize_with(lanes, Vec::new);
        }
        let picks = &mut picks[..lanes];
        picks.iter_mut().for_each(Vec::clear);
        let lanes_pass = LanesPass {
            iv: &mut intervals[..cells],
            fact: &mut facts[..cells],
            lanes,
        };
        lanes_pass.run((&self.code, ops, &self.sign_only), boxes, picks);
        // Each box's child, written from its picks through one alias
        // table that is the identity between boxes.
        alias.clear();
        alias.extend(0..ops.len());
        picks
            .iter()
            .map(|p| {
                if p.is_empty() {
                    return None;
                }
                for &(k, w) in p.iter() {
                    alias[k as usize] = alias[w as usize];
                }
                let kept = liveness(&self.ssa, alias, live, order);
                let written = (kept <= max_len).then(|| PrunedTape {
                    tape: Tape::write_child(&self.ssa, self.keep, alias, order, child),
                    decided: p.len(),
                });
                for &(k, _) in p.iter() {
                    alias[k as usize] = k as usize;
                }
                written
            })
            .collect()
    }

    /// The one backward pass that writes a tape: the ops of `parent` that
    /// [`liveness`] listed in `order` (last first), each operand read
    /// through `alias`, with registers assigned as it goes. Each op is
    /// written straight into its final slot, its place in `order` counted
    /// from the end. Only the kept ops are visited: a pruned child keeps a
    /// small part of its parent (a tenth on a union of 1000 spheres), and
    /// passes over every parent op were most of this function's time.
    // long-fn: one backward pass with register assignment inline; split,
    // the hot loop would pass its state through calls (see the doc).
    fn write_child(
        parent: &Function,
        keep: Keep,
        alias: &[usize],
        order: &[u32],
        scratch: &mut ChildScratch,
    ) -> Tape {
        const NONE: Reg = Reg::MAX;
        let n = parent.ops.len();
        let kept = order.len();
        // Per parent op, read only at kept ops, which are set below first:
        // the scratch keeps whatever earlier tapes left elsewhere.
        let ChildScratch { index, reg, free } = scratch;
        if index.len() < n {
            index.resize(n, ValueId(0));
        }
        if reg.len() < n {
            reg.resize(n, NONE);
        }
        for (p, &k) in order.iter().enumerate() {
            index[k as usize] = ValueId((kept - 1 - p) as u32);
            reg[k as usize] = NONE;
        }
        let root = alias[parent.root.index()];
        free.clear();
        let mut registers: Reg = 0;
        let mut take = |free: &mut Vec<Reg>| {
            free.pop().unwrap_or_else(|| {
                registers += 1;
                registers - 1
            })
        };
        reg[root] = take(free);
        let mut ops = vec![Op::Const(0.0); kept];
        let mut code = vec![Instr::Const(0, 0.0); kept];
        for &k in order {
            let k = k as usize;
            let out = reg[k];
            debug_assert!(
                out != NONE,
                "a live value has its register from its last use"
            );
            // Before its definition the value is not alive.
            free.push(out);
            let mut operand = |a: ValueId| {
                let a = alias[a.index()];
                if reg[a] == NONE {
                    reg[a] = take(free);
                }
                (index[a], reg[a])
            };
            let (op, instr) = match parent.ops[k] {
                Op::Var(v) => (Op::Var(v), Instr::Var(out, v)),
                Op::Const(c) => (Op::Const(c), Instr::Const(out, c)),
                Op::Unary(u, a) => {
                    let (ia, ra) = operand(a);
                    (Op::Unary(u, ia), Instr::unary(out, u, ra))
                }
                Op::Binary(o, a, b) => {
                    let (ia, ra) = operand(a);
                    let (ib, rb) = operand(b);
                    (Op::Binary(o, ia, ib), Instr::binary(out, o, ra, rb))
                }
                Op::Powi(a, p) => {
                    let (ia, ra) = operand(a);
                    (Op::Powi(ia, p), Instr::Powi(out, ra, p))
                }
            };
            let at = index[k].index();
            ops[at] = op;
            code[at] = instr;
        }
        let ssa = Function {
            ops,
            root: index[root],
        };
        let sign_only = match keep {
            Keep::Bits => Vec::new(),
            Keep::Signs => sign_only_ops(&ssa),
        };
        Tape {
            ssa: Arc::new(ssa),
            code,
            registers: registers as usize,
            keep,
            sign_only,
        }
    }
}

#[cfg(test)]
mod tests;
