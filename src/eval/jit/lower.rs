//! Lowering of an IR [`Function`] to the body of each evaluator kind.
//!
//! Each lowering is one forward sweep over the ops (no recursion, so
//! 100,000-op functions are fine) that keeps one CLIF value (or a pair, or a
//! dual number) per live IR value. Ops the root does not reach are skipped.
//! Derivatives that are known to be exactly zero are tracked as `None`, so a
//! function of x and y emits no code for ∂/∂z.

use cranelift_codegen::ir::{InstBuilder, StackSlotData, StackSlotKind, Value, types};

use super::emit::{Emitter, Iv};
use super::shims::Shim;
use crate::ir::{BinaryOp, Function, Op, UnaryOp};

/// Which ops the root depends on (by index).
pub(crate) fn live_ops(f: &Function) -> Vec<bool> {
    f.live_mask()
}

/// A use further than this many ops from the value's last register copy
/// reloads it from a stack slot. Cranelift's register allocator slows down
/// sharply (superlinearly) when thousands of long live ranges overlap, as in
/// a large CSG tree where a coordinate or a shared subexpression is used all
/// over; bounding every CLIF live range to a window of ops keeps
/// compilation linear, and a reload from L1 costs less than a spill the
/// allocator would insert anyway.
const WINDOW: usize = 24;

/// Where each value that is used far from its definition is kept.
struct SpillPlan {
    /// Slot index of each op's value, if it is ever reloaded.
    slot: Vec<Option<u32>>,
    /// Number of slots needed at once.
    slots: u32,
}

/// Assigns stack slots to far-used values, reusing a slot once the value
/// in it is dead (so the frame stays small even for huge functions).
fn plan_spills(f: &Function, live: &[bool]) -> SpillPlan {
    let n = f.ops.len();
    let mut far = vec![false; n];
    let mut last_use = vec![0usize; n];
    for (i, op) in f.ops.iter().enumerate() {
        if !live[i] {
            continue;
        }
        for a in op.operands() {
            let a = a.index();
            if i - a > WINDOW {
                far[a] = true;
            }
            last_use[a] = last_use[a].max(i);
        }
    }
    let mut release: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut free: Vec<u32> = Vec::new();
    let mut slots = 0u32;
    let mut slot = vec![None; n];
    for i in 0..n {
        // Values last read by op i are dead once i has loaded its operands,
        // so i's own value may take their slot.
        free.append(&mut release[i]);
        if far[i] {
            let s = free.pop().unwrap_or_else(|| {
                slots += 1;
                slots - 1
            });
            slot[i] = Some(s);
            release[last_use[i]].push(s);
        }
    }
    SpillPlan { slot, slots }
}

/// A lowered value that can be saved to and reloaded from memory: its CLIF
/// values in a fixed order. The shape (e.g. which partials are known zero)
/// is kept in a template copy.
pub(crate) trait Spill: Copy {
    /// The CLIF values (at most [`MAX_PARTS`]).
    fn parts(&self, out: &mut Vec<Value>);
    /// The same shape, with values taken in order from `vals`.
    fn rebuild(&self, vals: &mut dyn Iterator<Item = Value>) -> Self;
}

/// Most f64 one lowered value holds (an interval and three partials; a
/// packed interval counts as two).
const MAX_PARTS: i32 = 8;

impl Spill for Value {
    fn parts(&self, out: &mut Vec<Value>) {
        out.push(*self);
    }
    fn rebuild(&self, vals: &mut dyn Iterator<Item = Value>) -> Self {
        vals.next().expect("one part")
    }
}

impl Spill for Iv {
    fn parts(&self, out: &mut Vec<Value>) {
        out.push(self.0);
    }
    fn rebuild(&self, vals: &mut dyn Iterator<Item = Value>) -> Self {
        Iv(vals.next().expect("lanes"))
    }
}

impl<T: Spill> Spill for (T, [Option<T>; 3]) {
    fn parts(&self, out: &mut Vec<Value>) {
        self.0.parts(out);
        for d in self.1.iter().flatten() {
            d.parts(out);
        }
    }
    fn rebuild(&self, vals: &mut dyn Iterator<Item = Value>) -> Self {
        let v = self.0.rebuild(vals);
        let d = self.1.map(|d| d.map(|d| d.rebuild(vals)));
        (v, d)
    }
}

/// One forward sweep over the live ops: `var` lowers an input, `op` an op
/// given its lowered operands. Far uses reload from stack slots (see
/// [`WINDOW`]).
pub(crate) fn sweep<T: Spill>(
    e: &mut Emitter,
    f: &Function,
    live: &[bool],
    mut var: impl FnMut(&mut Emitter, usize) -> T,
    mut op: impl FnMut(&mut Emitter, &Op, &[T]) -> T,
) -> T {
    let plan = plan_spills(f, live);
    let ss = (plan.slots > 0).then(|| {
        let bytes = plan.slots * 8 * MAX_PARTS as u32;
        e.b.create_sized_stack_slot(StackSlotData::new(StackSlotKind::ExplicitSlot, bytes, 4))
    });
    let mut vals: Vec<Option<(T, usize)>> = vec![None; f.ops.len()];
    let mut parts = Vec::with_capacity(MAX_PARTS as usize);
    for (i, o) in f.ops.iter().enumerate() {
        if !live[i] {
            continue;
        }
        let mut args: [Option<T>; 2] = [None, None];
        for (k, a) in o.operands().enumerate() {
            let a = a.index();
            let (t, at) = vals[a].expect("operand lowered before use");
            let t = match (i - at > WINDOW, ss, plan.slot[a]) {
                (true, Some(ss), Some(s)) => {
                    let base = s as i32 * 8 * MAX_PARTS;
                    let mut off = base;
                    parts.clear();
                    t.parts(&mut parts);
                    let loaded: Vec<Value> = parts
                        .iter()
                        .map(|&p| {
                            let ty = e.b.func.dfg.value_type(p);
                            let v = e.b.ins().stack_load(types::I64, ty, ss, off);
                            off += ty.bytes() as i32;
                            v
                        })
                        .collect();
                    let r = t.rebuild(&mut loaded.into_iter());
                    vals[a] = Some((r, i));
                    r
                }
                _ => t,
            };
            args[k] = Some(t);
        }
        let r = match *o {
            Op::Var(v) => var(e, v.index()),
            _ => {
                let args: Vec<T> = args.iter().flatten().copied().collect();
                op(e, o, &args)
            }
        };
        if let (Some(ss), Some(s)) = (ss, plan.slot[i]) {
            parts.clear();
            r.parts(&mut parts);
            let mut off = s as i32 * 8 * MAX_PARTS;
            for &p in &parts {
                e.b.ins().stack_store(types::I64, p, ss, off);
                off += e.b.func.dfg.value_type(p).bytes() as i32;
            }
        }
        vals[i] = Some((r, i));
    }
    vals[f.root.index()].expect("root lowered").0
}

/// Point value of f at `(x, y, z)`.
pub(crate) fn point(e: &mut Emitter, f: &Function, live: &[bool], xyz: [Value; 3]) -> Value {
    sweep(
        e,
        f,
        live,
        |_, k| xyz[k],
        |e, op, a| match *op {
            Op::Const(c) => e.c(c),
            Op::Unary(u, _) => point_unary(e, u, a[0]),
            Op::Binary(b, _, _) => point_binary(e, b, a[0], a[1]),
            Op::Powi(_, n) => e.powi_point(a[0], i64::from(n)),
            Op::Var(v) => xyz[v.index()],
        },
    )
}

pub(crate) fn point_unary(e: &mut Emitter, u: UnaryOp, a: Value) -> Value {
    match u {
        UnaryOp::Neg => e.neg(a),
        UnaryOp::Abs => e.b.ins().fabs(a),
        UnaryOp::Square => e.mul(a, a),
        UnaryOp::Sqrt => e.b.ins().sqrt(a),
        _ => e.call_point_unary(Shim::PointUnary(u), a),
    }
}

pub(crate) fn point_binary(e: &mut Emitter, op: BinaryOp, a: Value, b: Value) -> Value {
    match op {
        BinaryOp::Add => e.add(a, b),
        BinaryOp::Sub => e.sub(a, b),
        BinaryOp::Mul => e.mul(a, b),
        BinaryOp::Div => e.div(a, b),
        BinaryOp::Min => e.min_nan(a, b),
        BinaryOp::Max => e.max_nan(a, b),
        BinaryOp::Atan2 | BinaryOp::Pow | BinaryOp::Mod => {
            e.call_point_binary(Shim::PointBinary(op), a, b)
        }
    }
}

/// Interval of f over the box `b`.
pub(crate) fn interval(e: &mut Emitter, f: &Function, live: &[bool], b: [Iv; 3]) -> Iv {
    sweep(
        e,
        f,
        live,
        |_, k| b[k],
        |e, op, a| match *op {
            Op::Const(c) => e.iv_const(c),
            Op::Unary(u, _) => iv_unary(e, u, a[0]),
            Op::Binary(BinaryOp::Mul, x, y) => {
                let konst = |v: crate::ir::ValueId| match f.ops[v.index()] {
                    Op::Const(c) => Some(c),
                    _ => None,
                };
                match (konst(x), konst(y)) {
                    (Some(c), _) => e.iv_mul(a[1], a[0], Some(c)),
                    (_, c) => e.iv_mul(a[0], a[1], c),
                }
            }
            Op::Binary(o, _, _) => iv_binary(e, o, a[0], a[1]),
            Op::Powi(_, n) => e.iv_powi(a[0], i64::from(n)),
            Op::Var(v) => b[v.index()],
        },
    )
}

pub(crate) fn iv_unary(e: &mut Emitter, u: UnaryOp, a: Iv) -> Iv {
    match u {
        UnaryOp::Neg => e.iv_neg(a),
        UnaryOp::Abs => e.iv_abs(a),
        UnaryOp::Square => e.iv_square(a),
        UnaryOp::Sqrt => e.iv_sqrt(a),
        _ => e.call_iv_unary(Shim::IntervalUnary(u), a),
    }
}

pub(crate) fn iv_binary(e: &mut Emitter, op: BinaryOp, a: Iv, b: Iv) -> Iv {
    match op {
        BinaryOp::Add => e.iv_add(a, b),
        BinaryOp::Sub => e.iv_sub(a, b),
        BinaryOp::Mul => e.iv_mul(a, b, None),
        BinaryOp::Div => e.iv_div(a, b),
        BinaryOp::Min => e.iv_min(a, b),
        BinaryOp::Max => e.iv_max(a, b),
        BinaryOp::Atan2 | BinaryOp::Pow | BinaryOp::Mod => {
            e.call_iv_binary(Shim::IntervalBinary(op), a, b)
        }
    }
}
