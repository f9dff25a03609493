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
//! tape, never from the whole function.

use std::sync::Arc;

use crate::eval::interp::{
    IntervalDual, dual_binary, dual_powi, dual_unary, point_dual_binary, point_dual_powi,
    point_dual_unary,
};
use crate::eval::{Grad, IntervalGrad};
use crate::interval::Interval;
use crate::ir::prune::{
    Facts, binary_facts, const_facts, decided_operand, powi_facts, unary_facts, var_facts,
};
use crate::ir::semantics::{
    interval_binary, interval_unary, point_binary, point_powi, point_unary,
};
use crate::ir::{BinaryOp, Function, Op, UnaryOp, ValueId, Var};

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
    child: ChildScratch,
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
        let mut live = Vec::new();
        liveness(&ssa, &identity, &mut live);
        Tape::write_child(&ssa, &identity, &live, &mut ChildScratch::default())
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

    /// f at `p`, the same bits as the reference interpreter: one pass over
    /// the registers, one dispatch per instruction, the common ops inline
    /// (the reference rules' `match` per op, a call each, costs more than
    /// the op).
    pub fn point(&self, p: [f64; 3], ws: &mut Workspace) -> f64 {
        let m = &mut ws.points;
        m.clear();
        m.resize(self.registers, 0.0);
        for instr in &self.code {
            let r = |a: Reg| m[a as usize];
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
            m[o as usize] = v;
        }
        m[self.root_reg()]
    }

    /// An interval containing f over `b`, the same bits as the reference
    /// interpreter's (see [`Tape::point`]).
    pub fn interval(&self, b: [Interval; 3], ws: &mut Workspace) -> Interval {
        let m = &mut ws.intervals;
        m.clear();
        m.resize(self.registers, Interval::point(0.0));
        for instr in &self.code {
            let r = |a: Reg| m[a as usize];
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
            m[o as usize] = v;
        }
        m[self.root_reg()]
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
        for instr in &self.code {
            let col = |r: Reg| r as usize * n;
            match instr.form() {
                Form::Var(o, v) => {
                    let src = [xs, ys, zs][v.index()];
                    m[col(o)..col(o) + n].copy_from_slice(src);
                }
                Form::Const(o, c) => m[col(o)..col(o) + n].fill(c),
                Form::Unary(o, op, a) => {
                    let (o, a) = (col(o), col(a));
                    for i in 0..n {
                        m[o + i] = point_unary(op, m[a + i]);
                    }
                }
                Form::Binary(o, op, a, b) => point_binary_column(m, op, n, [o, a, b].map(col)),
                Form::Powi(o, a, k) => {
                    let (o, a) = (col(o), col(a));
                    for i in 0..n {
                        m[o + i] = point_powi(m[a + i], k);
                    }
                }
            }
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
        let ops = &self.ssa.ops;
        let n = ops.len();
        // Values and facts live in registers, as in evaluation: a few dozen
        // slots, not one per op.
        let regs = &mut ws.intervals;
        regs.clear();
        regs.resize(self.registers, Interval::point(0.0));
        let fact = &mut ws.facts;
        fact.clear();
        fact.resize(self.registers, Facts::default());
        // alias[k]: the op whose value op k always equals on the box.
        let alias = &mut ws.alias;
        alias.clear();
        alias.extend(0..n);
        let mut decided = 0;
        for (k, instr) in self.code.iter().enumerate() {
            let at = |r: Reg| (regs[r as usize], fact[r as usize]);
            let (out, v, f) = match instr.form() {
                Form::Var(o, var) => {
                    let v = b[var.index()];
                    (o, v, var_facts(v))
                }
                Form::Const(o, c) => (o, Interval::point(c), const_facts(c)),
                Form::Unary(o, u, a) => {
                    let a = at(a);
                    let v = interval_unary_inline(u, a.0);
                    (o, v, unary_facts(u, a, v))
                }
                Form::Binary(o, op, x, y) => {
                    let (x, y) = (at(x), at(y));
                    if let Some(w) = decided_operand(op, x, y)
                        && let Op::Binary(_, xa, ya) = ops[k]
                    {
                        alias[k] = alias[[xa, ya][w].index()];
                        decided += 1;
                    }
                    let v = interval_binary_inline(op, x.0, y.0);
                    (o, v, binary_facts(op, x, y, v))
                }
                Form::Powi(o, a, p) => {
                    let a = at(a);
                    let v = a.0.powi(p);
                    (o, v, powi_facts(p, a, v))
                }
            };
            regs[out as usize] = v;
            fact[out as usize] = f;
        }
        if decided == 0 {
            return None;
        }
        // Ops the child keeps: those the root reads through the aliases.
        let kept = liveness(&self.ssa, alias, &mut ws.live);
        if kept > max_len {
            return None;
        }
        Some(PrunedTape {
            tape: Tape::write_child(&self.ssa, alias, &ws.live, &mut ws.child),
            decided,
        })
    }

    /// The one backward pass that writes a tape: the ops of `parent` marked
    /// `live` (see [`liveness`]), each operand read through `alias`, with
    /// registers assigned as it goes. Each op is written straight into its
    /// final slot: a forward count over `live` gives every kept op its
    /// index in the child first.
    fn write_child(
        parent: &Function,
        alias: &[usize],
        live: &[bool],
        scratch: &mut ChildScratch,
    ) -> Tape {
        const NONE: Reg = Reg::MAX;
        let n = parent.ops.len();
        let index = &mut scratch.index;
        index.clear();
        index.reserve(n);
        let mut kept = 0u32;
        for &l in live {
            index.push(ValueId(kept));
            kept += u32::from(l);
        }
        let kept = kept as usize;
        let root = alias[parent.root.index()];
        let reg = &mut scratch.reg;
        reg.clear();
        reg.resize(n, NONE);
        let free = &mut scratch.free;
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
        for k in (0..n).rev() {
            if !live[k] {
                continue;
            }
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
        Tape {
            ssa: Arc::new(Function {
                ops,
                root: index[root],
            }),
            code,
            registers: registers as usize,
        }
    }
}

/// Marks in `live` the ops of `f` its root reads through `alias` (an op
/// is read in place of the ops that alias it) and returns how many.
fn liveness(f: &Function, alias: &[usize], live: &mut Vec<bool>) -> usize {
    let n = f.ops.len();
    live.clear();
    live.resize(n, false);
    live[alias[f.root.index()]] = true;
    let mut kept = 0;
    for k in (0..n).rev() {
        if live[k] && alias[k] == k {
            kept += 1;
            for a in f.ops[k].operands() {
                live[alias[a.index()]] = true;
            }
        }
    }
    kept
}

/// Per-op scratch of writing a child tape.
#[derive(Clone, Default, Debug)]
pub struct ChildScratch {
    reg: Vec<Reg>,
    index: Vec<ValueId>,
    free: Vec<Reg>,
}

/// The ops the root of `f` reads, in depth-first post-order (operands
/// left to right before the op; an explicit stack, as functions may be
/// millions of ops deep).
fn depth_first(f: &Function) -> Vec<usize> {
    let mut placed = vec![false; f.ops.len()];
    let mut order = Vec::new();
    // (op, whether its operands were pushed already)
    let mut stack = vec![(f.root.index(), false)];
    while let Some((i, expanded)) = stack.pop() {
        if placed[i] {
            continue;
        }
        if expanded {
            placed[i] = true;
            order.push(i);
            continue;
        }
        stack.push((i, true));
        let args: Vec<usize> = f.ops[i].operands().map(|a| a.index()).collect();
        for &a in args.iter().rev() {
            if !placed[a] {
                stack.push((a, false));
            }
        }
    }
    order
}

/// One binary op over a column of points: the common ops as plain loops the
/// compiler vectorises, the rest through the reference rule.
fn point_binary_column(m: &mut [f64], op: BinaryOp, n: usize, [o, a, b]: [usize; 3]) {
    match op {
        BinaryOp::Add => (0..n).for_each(|i| m[o + i] = m[a + i] + m[b + i]),
        BinaryOp::Sub => (0..n).for_each(|i| m[o + i] = m[a + i] - m[b + i]),
        BinaryOp::Mul => (0..n).for_each(|i| m[o + i] = m[a + i] * m[b + i]),
        _ => (0..n).for_each(|i| m[o + i] = point_binary(op, m[a + i], m[b + i])),
    }
}

/// [`interval_unary`] with the ops of distance fields and CSG inline.
#[inline(always)]
fn interval_unary_inline(op: UnaryOp, a: Interval) -> Interval {
    match op {
        UnaryOp::Neg => a.neg(),
        UnaryOp::Square => a.square(),
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Abs => a.abs(),
        _ => interval_unary(op, a),
    }
}

/// [`interval_binary`] with the ops of distance fields and CSG inline.
#[inline(always)]
fn interval_binary_inline(op: BinaryOp, a: Interval, b: Interval) -> Interval {
    match op {
        BinaryOp::Add => a.add(b),
        BinaryOp::Sub => a.sub(b),
        BinaryOp::Mul => a.mul(b),
        BinaryOp::Min => a.min(b),
        BinaryOp::Max => a.max(b),
        _ => interval_binary(op, a, b),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::Evaluator;
    use crate::eval::interp::Interpreter;
    use crate::ir::passes::simplify;
    use crate::ir::random::{Rng, random_function};

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    fn same_iv(a: Interval, b: Interval) -> bool {
        (a.is_empty() && b.is_empty()) || (same(a.lo, b.lo) && same(a.hi, b.hi))
    }

    fn random_box(rng: &mut Rng, s: f64) -> [Interval; 3] {
        std::array::from_fn(|_| {
            let (a, b) = (rng.range(-s, s), rng.range(-s, s));
            Interval::new(a.min(b), a.max(b))
        })
    }

    #[test]
    fn batches_give_the_interpreters_bits() {
        let mut rng = Rng::new(7);
        let mut ws = Workspace::default();
        for seed in 0..300 {
            let f = random_function(seed, 8);
            let tape = Tape::new(&f);
            crate::ir::validate::validate(tape.function()).unwrap();
            let it = Interpreter::new(f);
            let pts: Vec<[f64; 3]> = (0..17)
                .map(|_| std::array::from_fn(|_| rng.range(-3.0, 3.0)))
                .collect();
            let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
            let mut out = vec![0.0; pts.len()];
            tape.point_batch([&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
            for (p, v) in pts.iter().zip(&out) {
                assert!(same(*v, it.point(*p)), "seed {seed} at {p:?}");
            }
            let boxes: Vec<_> = (0..9).map(|_| random_box(&mut rng, 3.0)).collect();
            let mut iv = vec![Interval::point(0.0); boxes.len()];
            tape.interval_batch(&boxes, &mut iv, &mut ws);
            for (b, v) in boxes.iter().zip(&iv) {
                assert!(same_iv(*v, it.interval(*b)), "seed {seed} over {b:?}");
            }
        }
    }

    #[test]
    fn scalar_runs_and_directions_give_the_interpreters_bits() {
        let mut rng = Rng::new(17);
        let mut ws = Workspace::default();
        for seed in 0..300 {
            let f = random_function(seed, 10);
            let tape = Tape::new(&f);
            let it = Interpreter::new(f);
            for _ in 0..8 {
                let p: [f64; 3] = std::array::from_fn(|_| rng.range(-3.0, 3.0));
                assert!(
                    same(tape.point(p, &mut ws), it.point(p)),
                    "seed {seed} at {p:?}"
                );
                let b = random_box(&mut rng, 3.0);
                assert!(
                    same_iv(tape.interval(b, &mut ws), it.interval(b)),
                    "seed {seed} over {b:?}"
                );
                let v = random_box(&mut rng, 2.0);
                let [tv, td] = tape.interval_dir(b, v, &mut ws);
                let [iv, id] = it.interval_dir(b, v);
                assert!(
                    same_iv(tv, iv) && same_iv(td, id),
                    "seed {seed} over {b:?} along {v:?}"
                );
            }
        }
    }

    /// A union of `n` spheres along x: a min chain, balanced by simplify.
    fn spheres(n: usize) -> Function {
        let mut b = crate::ir::Builder::new();
        let x = b.var(Var::X);
        let y = b.var(Var::Y);
        let z = b.var(Var::Z);
        let yz = {
            let y2 = b.unary(UnaryOp::Square, y);
            let z2 = b.unary(UnaryOp::Square, z);
            b.binary(BinaryOp::Add, y2, z2)
        };
        let mut acc = None;
        for i in 0..n {
            let c = b.constant(i as f64);
            let dx = b.binary(BinaryOp::Sub, x, c);
            let dx2 = b.unary(UnaryOp::Square, dx);
            let r2 = b.binary(BinaryOp::Add, dx2, yz);
            let r = b.unary(UnaryOp::Sqrt, r2);
            let half = b.constant(0.5);
            let s = b.binary(BinaryOp::Sub, r, half);
            acc = Some(match acc {
                None => s,
                Some(a) => b.binary(BinaryOp::Min, a, s),
            });
        }
        simplify(&b.finish(acc.unwrap()))
    }

    #[test]
    fn pruning_keeps_the_bits_inside_and_nests() {
        let f = spheres(200);
        let whole = Tape::new(&f);
        assert!(whole.registers() < 40, "{} registers", whole.registers());
        let mut ws = Workspace::default();
        let outer = [
            Interval::new(40.2, 47.8),
            Interval::new(-1.0, 1.0),
            Interval::new(-1.0, 1.0),
        ];
        let p1 = whole
            .prune(outer, &mut ws)
            .expect("a small box decides most mins");
        assert!(
            p1.tape.len() * 5 < whole.len(),
            "{} of {}",
            p1.tape.len(),
            whole.len()
        );
        crate::ir::validate::validate(p1.tape.function()).unwrap();
        let inner = [
            Interval::new(44.6, 45.3),
            Interval::new(-0.2, 0.3),
            Interval::new(0.0, 0.1),
        ];
        let p2 = p1
            .tape
            .prune(inner, &mut ws)
            .expect("nested pruning decides more");
        assert!(p2.tape.len() < p1.tape.len());
        let direct = crate::ir::prune::prune(&f, outer).unwrap();
        assert_eq!(direct.decided, p1.decided);
        let it = Interpreter::new(f.clone());
        let mut rng = Rng::new(3);
        for (tape, bx) in [(&p1.tape, outer), (&p2.tape, inner)] {
            let pts: Vec<[f64; 3]> = (0..64)
                .map(|_| std::array::from_fn(|c| rng.range(bx[c].lo, bx[c].hi)))
                .collect();
            let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
            let mut out = vec![0.0; pts.len()];
            tape.point_batch([&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
            for (p, v) in pts.iter().zip(&out) {
                assert!(same(*v, it.point(*p)), "at {p:?}");
            }
        }
    }

    #[test]
    fn a_size_limit_refuses_a_longer_child_and_keeps_a_shorter_one() {
        let whole = Tape::new(&spheres(50));
        let mut ws = Workspace::default();
        let b = [
            Interval::new(20.2, 22.8),
            Interval::new(-1.0, 1.0),
            Interval::new(-1.0, 1.0),
        ];
        let child = whole.prune(b, &mut ws).expect("prunes").tape;
        let n = child.len();
        assert!(whole.prune_to_at_most(b, n - 1, &mut ws).is_none());
        let same = whole.prune_to_at_most(b, n, &mut ws).expect("fits");
        assert_eq!(same.tape, child);
    }

    #[test]
    fn pruned_random_functions_keep_their_bits_in_the_box() {
        let mut rng = Rng::new(11);
        let mut ws = Workspace::default();
        let mut pruned = 0;
        for seed in 0..400 {
            let f = random_function(seed, 9);
            let tape = Tape::new(&f);
            let bx = random_box(&mut rng, 2.0);
            let Some(p) = tape.prune(bx, &mut ws) else {
                continue;
            };
            pruned += 1;
            let it = Interpreter::new(f);
            for _ in 0..16 {
                let q: [f64; 3] = std::array::from_fn(|c| rng.range(bx[c].lo, bx[c].hi));
                let mut out = [0.0];
                p.tape
                    .point_batch([&[q[0]], &[q[1]], &[q[2]]], &mut out, &mut ws);
                assert!(same(out[0], it.point(q)), "seed {seed} at {q:?}");
            }
        }
        assert!(pruned > 20, "only {pruned} random functions pruned");
    }
}
