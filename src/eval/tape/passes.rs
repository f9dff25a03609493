//! The passes pruning runs over a function: which ops only the root's
//! sign depends on, liveness, and the interval pass over one region or
//! over many regions in lanes.

use super::*;

/// Per op of `f`: whether the root's sign is all that depends on its value,
/// that is, it is the root or every op reading it is such a `min`, `max`
/// or negation (the sign of each depends on its operands' signs alone).
/// [`Keep::Signs`] may replace such a `min` or `max` by one operand.
/// Walking backwards, every reader of an op is met before it.
pub(super) fn sign_only_ops(f: &Function) -> Vec<bool> {
    let n = f.ops.len();
    let root = f.root.index();
    let mut read = vec![false; n];
    let mut read_by_value = vec![false; n];
    let mut sign_only = vec![false; n];
    for k in (0..n).rev() {
        let only = (k == root || read[k]) && !read_by_value[k];
        sign_only[k] = only;
        // A negation passes its operand's sign on too (flipped): the cut
        // of a `difference`, `max(a, -b)`, keeps signs only.
        let passes_sign = only
            && matches!(
                f.ops[k],
                Op::Binary(BinaryOp::Min | BinaryOp::Max, ..) | Op::Unary(UnaryOp::Neg, _)
            );
        for a in f.ops[k].operands() {
            read[a.index()] = true;
            read_by_value[a.index()] |= !passes_sign;
        }
    }
    sign_only
}

/// Marks in `live` the ops of `f` its root reads through `alias` (an op
/// is read in place of the ops that alias it), lists them in `order`, last
/// first, and returns how many.
pub(super) fn liveness(
    f: &Function,
    alias: &[usize],
    live: &mut Vec<bool>,
    order: &mut Vec<u32>,
) -> usize {
    let n = f.ops.len();
    live.clear();
    live.resize(n, false);
    order.clear();
    live[alias[f.root.index()]] = true;
    for k in (0..n).rev() {
        if live[k] && alias[k] == k {
            order.push(k as u32);
            for a in f.ops[k].operands() {
                live[alias[a.index()]] = true;
            }
        }
    }
    order.len()
}

/// Per-op scratch of writing a child tape.
#[derive(Clone, Default, Debug)]
pub struct ChildScratch {
    pub(super) reg: Vec<Reg>,
    pub(super) index: Vec<ValueId>,
    pub(super) free: Vec<Reg>,
}

/// The ops the root of `f` reads, in depth-first post-order (operands
/// left to right before the op; an explicit stack, as functions may be
/// millions of ops deep).
pub(super) fn depth_first(f: &Function) -> Vec<usize> {
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

/// Pruning's forward pass over `code` (the instructions of `ops`) with
/// register files for values and facts: records in `alias` each decided
/// `min`/`max` and returns how many were decided.
#[inline(always)]
pub(super) fn prune_pass<V: Registers<Interval> + ?Sized, F: Registers<Facts> + ?Sized>(
    code: &[Instr],
    ops: &[Op],
    sign_only: &[bool],
    b: [Interval; 3],
    (regs, fact): (&mut V, &mut F),
    alias: &mut [usize],
) -> usize {
    let mut decided = 0;
    // One dispatch per instruction: each common op's arm calls the
    // shared rules with its op fixed, which inlining specialises (a
    // dispatch on the form, then on the op inside each rule, costs
    // several mispredicted branches per op).
    for (k, instr) in code.iter().enumerate() {
        let at = |r: Reg| (regs.get(r), fact.get(r));
        let (out, v, f, pick) = match *instr {
            Instr::Var(o, var) => {
                let v = b[var.index()];
                (o, v, var_facts(v), None)
            }
            Instr::Const(o, c) => (o, Interval::point(c), const_facts(c), None),
            Instr::Add(o, x, y) => binary(o, BinaryOp::Add, at(x), at(y), Interval::add),
            Instr::Sub(o, x, y) => binary(o, BinaryOp::Sub, at(x), at(y), Interval::sub),
            Instr::Mul(o, x, y) => binary(o, BinaryOp::Mul, at(x), at(y), Interval::mul),
            Instr::Min(o, x, y) => {
                let signs = sign_only.get(k) == Some(&true);
                choice(o, BinaryOp::Min, (at(x), at(y)), signs, Interval::min)
            }
            Instr::Max(o, x, y) => {
                let signs = sign_only.get(k) == Some(&true);
                choice(o, BinaryOp::Max, (at(x), at(y)), signs, Interval::max)
            }
            Instr::Binary(o, op, x, y) => {
                binary(o, op, at(x), at(y), |p, q| interval_binary_inline(op, p, q))
            }
            Instr::Neg(o, x) => unary(o, UnaryOp::Neg, at(x), Interval::neg),
            Instr::Square(o, x) => unary(o, UnaryOp::Square, at(x), Interval::square),
            Instr::Sqrt(o, x) => unary(o, UnaryOp::Sqrt, at(x), Interval::sqrt),
            Instr::Unary(o, u, x) => unary(o, u, at(x), |p| interval_unary_inline(u, p)),
            Instr::Powi(o, x, p) => {
                let x = at(x);
                let v = x.0.powi(p);
                (o, v, powi_facts(p, x, v), None)
            }
        };
        if let Some(w) = pick
            && let Op::Binary(_, xa, ya) = ops[k]
        {
            alias[k] = alias[[xa, ya][w].index()];
            decided += 1;
        }
        regs.set(out, v);
        fact.set(out, f);
    }
    decided
}

/// One box's decided `min`/`max` ops in a batched pruning, each with the
/// op it always equals there (the operand it picks), in tape order.
pub(super) type Picks = Vec<(u32, u32)>;

/// Pruning's forward pass over many boxes at once: per register, a
/// column of one value and its facts per box.
pub(super) struct LanesPass<'w> {
    pub(super) iv: &'w mut [Interval],
    pub(super) fact: &'w mut [Facts],
    pub(super) lanes: usize,
}

impl LanesPass<'_> {
    // Runs `code` (the instructions of `ops`) over `boxes`, pushing each
    // box's decided `min`/`max` ops, with the operand each picks, to its
    // list in `picks`.
    pub(super) fn run(
        mut self,
        (code, ops, sign_only): (&[Instr], &[Op], &[bool]),
        boxes: &[[Interval; 3]],
        picks: &mut [Picks],
    ) {
        // One dispatch per instruction, then a loop over the boxes with
        // the op fixed (see `prune_pass`).
        for (k, instr) in code.iter().enumerate() {
            match *instr {
                Instr::Var(o, var) => {
                    for (j, b) in boxes.iter().enumerate() {
                        let v = b[var.index()];
                        self.put(o, j, v, var_facts(v));
                    }
                }
                Instr::Const(o, c) => {
                    let (v, f) = (Interval::point(c), const_facts(c));
                    for j in 0..self.lanes {
                        self.put(o, j, v, f);
                    }
                }
                Instr::Add(o, x, y) => self.binary(o, [x, y], BinaryOp::Add, Interval::add),
                Instr::Sub(o, x, y) => self.binary(o, [x, y], BinaryOp::Sub, Interval::sub),
                Instr::Mul(o, x, y) => self.binary(o, [x, y], BinaryOp::Mul, Interval::mul),
                Instr::Min(o, x, y) => {
                    let signs = sign_only.get(k) == Some(&true);
                    self.choice(
                        o,
                        [x, y],
                        (BinaryOp::Min, signs),
                        Interval::min,
                        (k, ops, picks),
                    )
                }
                Instr::Max(o, x, y) => {
                    let signs = sign_only.get(k) == Some(&true);
                    self.choice(
                        o,
                        [x, y],
                        (BinaryOp::Max, signs),
                        Interval::max,
                        (k, ops, picks),
                    )
                }
                Instr::Binary(o, op, x, y) => {
                    self.binary(o, [x, y], op, |p, q| interval_binary_inline(op, p, q))
                }
                Instr::Neg(o, x) => self.unary(o, x, UnaryOp::Neg, Interval::neg),
                Instr::Square(o, x) => self.unary(o, x, UnaryOp::Square, Interval::square),
                Instr::Sqrt(o, x) => self.unary(o, x, UnaryOp::Sqrt, Interval::sqrt),
                Instr::Unary(o, u, x) => self.unary(o, x, u, |p| interval_unary_inline(u, p)),
                Instr::Powi(o, x, p) => {
                    for j in 0..self.lanes {
                        let a = self.at(x, j);
                        let v = a.0.powi(p);
                        self.put(o, j, v, powi_facts(p, a, v));
                    }
                }
            }
        }
    }

    #[inline(always)]
    pub(super) fn at(&self, r: Reg, j: usize) -> (Interval, Facts) {
        let i = r as usize * self.lanes + j;
        (self.iv[i], self.fact[i])
    }

    #[inline(always)]
    pub(super) fn put(&mut self, r: Reg, j: usize, v: Interval, f: Facts) {
        let i = r as usize * self.lanes + j;
        self.iv[i] = v;
        self.fact[i] = f;
    }

    #[inline(always)]
    pub(super) fn unary(
        &mut self,
        o: Reg,
        x: Reg,
        u: UnaryOp,
        value: impl Fn(Interval) -> Interval,
    ) {
        for j in 0..self.lanes {
            let a = self.at(x, j);
            let v = value(a.0);
            self.put(o, j, v, unary_facts(u, a, v));
        }
    }

    #[inline(always)]
    pub(super) fn binary(
        &mut self,
        o: Reg,
        [x, y]: [Reg; 2],
        op: BinaryOp,
        value: impl Fn(Interval, Interval) -> Interval,
    ) {
        for j in 0..self.lanes {
            let (a, b) = (self.at(x, j), self.at(y, j));
            let v = value(a.0, b.0);
            self.put(o, j, v, binary_facts(op, a, b, v));
        }
    }

    // A `min` or `max` at op `k` of `ops`: as `binary`, and the operand
    // it picks on each box where one is proven (by value, or by sign where
    // `signs`: see `Keep::Signs`).
    #[inline(always)]
    pub(super) fn choice(
        &mut self,
        o: Reg,
        [x, y]: [Reg; 2],
        (op, signs): (BinaryOp, bool),
        value: impl Fn(Interval, Interval) -> Interval,
        (k, ops, picks): (usize, &[Op], &mut [Picks]),
    ) {
        let Op::Binary(_, xa, ya) = ops[k] else {
            unreachable!("a min or max instruction is a binary op");
        };
        for (j, p) in picks.iter_mut().enumerate() {
            let (a, b) = (self.at(x, j), self.at(y, j));
            if let Some(w) = picked_operand(op, a, b, signs) {
                p.push((k as u32, [xa, ya][w].0));
            }
            let v = value(a.0, b.0);
            self.put(o, j, v, binary_facts(op, a, b, v));
        }
    }
}

/// One step of pruning's forward pass over `u(x)` written to `o`: its
/// interval (by `value`), its facts, and no decision.
#[inline(always)]
pub(super) fn unary(
    o: Reg,
    u: UnaryOp,
    x: (Interval, Facts),
    value: impl Fn(Interval) -> Interval,
) -> (Reg, Interval, Facts, Option<usize>) {
    let v = value(x.0);
    (o, v, unary_facts(u, x, v), None)
}

/// One step of pruning's forward pass over `op(x, y)` written to `o`: its
/// interval (by `value`), its facts, and the operand a `min` or `max`
/// always picks on the box, if proven.
#[inline(always)]
pub(super) fn binary(
    o: Reg,
    op: BinaryOp,
    x: (Interval, Facts),
    y: (Interval, Facts),
    value: impl Fn(Interval, Interval) -> Interval,
) -> (Reg, Interval, Facts, Option<usize>) {
    let pick = if matches!(op, BinaryOp::Min | BinaryOp::Max) {
        decided_operand(op, x, y)
    } else {
        None
    };
    let v = value(x.0, y.0);
    (o, v, binary_facts(op, x, y, v), pick)
}

/// One step of pruning's forward pass over a `min` or `max` written to
/// `o`: as [`binary`], deciding by sign too where `signs` (the op reaches
/// the root through `min`/`max` alone on a tape that keeps signs).
#[inline(always)]
pub(super) fn choice(
    o: Reg,
    op: BinaryOp,
    (x, y): ((Interval, Facts), (Interval, Facts)),
    signs: bool,
    value: impl Fn(Interval, Interval) -> Interval,
) -> (Reg, Interval, Facts, Option<usize>) {
    let v = value(x.0, y.0);
    (
        o,
        v,
        binary_facts(op, x, y, v),
        picked_operand(op, x, y, signs),
    )
}

/// The operand a `min` or `max` is replaced by on a box: the one it always
/// picks there, or, where only its sign matters (`signs`), the one that
/// keeps its sign.
#[inline(always)]
pub(super) fn picked_operand(
    op: BinaryOp,
    x: (Interval, Facts),
    y: (Interval, Facts),
    signs: bool,
) -> Option<usize> {
    decided_operand(op, x, y).or_else(|| signs.then(|| sign_decided_operand(op, x, y)).flatten())
}

/// [`interval_unary`] with the ops of distance fields and CSG inline.
#[inline(always)]
pub(super) fn interval_unary_inline(op: UnaryOp, a: Interval) -> Interval {
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
pub(super) fn interval_binary_inline(op: BinaryOp, a: Interval, b: Interval) -> Interval {
    match op {
        BinaryOp::Add => a.add(b),
        BinaryOp::Sub => a.sub(b),
        BinaryOp::Mul => a.mul(b),
        BinaryOp::Min => a.min(b),
        BinaryOp::Max => a.max(b),
        _ => interval_binary(op, a, b),
    }
}
