//! Lowering of an IR [`Function`] to the body of each evaluator kind.
//!
//! Each lowering is one forward sweep over the ops (no recursion, so
//! 100,000-op functions are fine) that keeps one CLIF value (or a pair, or a
//! dual number) per live IR value. Ops the root does not reach are skipped.
//! Derivatives that are known to be exactly zero are tracked as `None`, so a
//! function of x and y emits no code for ∂/∂z.

use cranelift_codegen::ir::condcodes::FloatCC;
use cranelift_codegen::ir::{InstBuilder, StackSlotData, StackSlotKind, Value, types};

use super::emit::{Emitter, Iv, binary_shim_index, unary_shim_index};
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
fn sweep<T: Spill>(
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

fn point_unary(e: &mut Emitter, u: UnaryOp, a: Value) -> Value {
    match u {
        UnaryOp::Neg => e.neg(a),
        UnaryOp::Abs => e.b.ins().fabs(a),
        UnaryOp::Square => e.mul(a, a),
        UnaryOp::Sqrt => e.b.ins().sqrt(a),
        UnaryOp::Exp | UnaryOp::Ln | UnaryOp::Sin | UnaryOp::Cos => {
            let i = unary_shim_index(u).expect("transcendental");
            e.call_point_unary(i, a)
        }
    }
}

fn point_binary(e: &mut Emitter, op: BinaryOp, a: Value, b: Value) -> Value {
    match op {
        BinaryOp::Add => e.add(a, b),
        BinaryOp::Sub => e.sub(a, b),
        BinaryOp::Mul => e.mul(a, b),
        BinaryOp::Div => e.div(a, b),
        BinaryOp::Min => e.min_nan(a, b),
        BinaryOp::Max => e.max_nan(a, b),
        BinaryOp::Atan2 | BinaryOp::Pow => {
            let i = binary_shim_index(op).expect("transcendental");
            e.call_point_binary(i, a, b)
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

fn iv_unary(e: &mut Emitter, u: UnaryOp, a: Iv) -> Iv {
    match u {
        UnaryOp::Neg => e.iv_neg(a),
        UnaryOp::Abs => e.iv_abs(a),
        UnaryOp::Square => e.iv_square(a),
        UnaryOp::Sqrt => e.iv_sqrt(a),
        UnaryOp::Exp | UnaryOp::Ln | UnaryOp::Sin | UnaryOp::Cos => {
            let i = unary_shim_index(u).expect("transcendental");
            e.call_iv_unary(i, a)
        }
    }
}

fn iv_binary(e: &mut Emitter, op: BinaryOp, a: Iv, b: Iv) -> Iv {
    match op {
        BinaryOp::Add => e.iv_add(a, b),
        BinaryOp::Sub => e.iv_sub(a, b),
        BinaryOp::Mul => e.iv_mul(a, b, None),
        BinaryOp::Div => e.iv_div(a, b),
        BinaryOp::Min => e.iv_min(a, b),
        BinaryOp::Max => e.iv_max(a, b),
        BinaryOp::Atan2 | BinaryOp::Pow => {
            let i = binary_shim_index(op).expect("transcendental");
            e.call_iv_binary(i, a, b)
        }
    }
}

/// The arithmetic a dual number needs, for points (`Value`) and for
/// intervals (`Iv`), so that one set of derivative rules serves both.
pub(crate) trait Num: Copy {
    fn konst(e: &mut Emitter, c: f64) -> Self;
    fn add(e: &mut Emitter, a: Self, b: Self) -> Self;
    fn sub(e: &mut Emitter, a: Self, b: Self) -> Self;
    fn mul(e: &mut Emitter, a: Self, b: Self) -> Self;
    fn div(e: &mut Emitter, a: Self, b: Self) -> Self;
    fn neg(e: &mut Emitter, a: Self) -> Self;
    fn unary(e: &mut Emitter, u: UnaryOp, a: Self) -> Self;
    fn binary(e: &mut Emitter, op: BinaryOp, a: Self, b: Self) -> Self;
    fn powi(e: &mut Emitter, a: Self, n: i64) -> Self;
    /// Derivative of |a|: `da` where a ≥ 0 (and at ±0), `-da` where a < 0.
    fn abs_grad(e: &mut Emitter, a: Self, da: Self) -> Self;
    /// Derivative of min(a, b): `da` where a < b, else `db`.
    fn min_grad(e: &mut Emitter, a: Self, b: Self, da: Self, db: Self) -> Self;
    /// Derivative of max(a, b): `da` where a > b, else `db`.
    fn max_grad(e: &mut Emitter, a: Self, b: Self, da: Self, db: Self) -> Self;
    /// A partial `d` of atan2(a, b), widened where the box touches the
    /// branch cut (a = 0, b ≤ 0) across which atan2 jumps by 2π.
    fn atan2_cut(e: &mut Emitter, a: Self, b: Self, d: Self) -> Self;
}

impl Num for Value {
    fn konst(e: &mut Emitter, c: f64) -> Self {
        e.c(c)
    }
    fn add(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.add(a, b)
    }
    fn sub(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.sub(a, b)
    }
    fn mul(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.mul(a, b)
    }
    fn div(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.div(a, b)
    }
    fn neg(e: &mut Emitter, a: Self) -> Self {
        e.neg(a)
    }
    fn unary(e: &mut Emitter, u: UnaryOp, a: Self) -> Self {
        point_unary(e, u, a)
    }
    fn binary(e: &mut Emitter, op: BinaryOp, a: Self, b: Self) -> Self {
        point_binary(e, op, a, b)
    }
    fn powi(e: &mut Emitter, a: Self, n: i64) -> Self {
        e.powi_point(a, n)
    }
    fn abs_grad(e: &mut Emitter, a: Self, da: Self) -> Self {
        let z = e.c(0.0);
        let neg = e.fcmp(FloatCC::LessThan, a, z);
        let nda = e.neg(da);
        e.select(neg, nda, da)
    }
    fn min_grad(e: &mut Emitter, a: Self, b: Self, da: Self, db: Self) -> Self {
        let lt = e.fcmp(FloatCC::LessThan, a, b);
        e.select(lt, da, db)
    }
    fn max_grad(e: &mut Emitter, a: Self, b: Self, da: Self, db: Self) -> Self {
        let gt = e.fcmp(FloatCC::GreaterThan, a, b);
        e.select(gt, da, db)
    }
    /// At a point the derivative formula holds off the cut, and the cut
    /// itself is a measure-zero set the point evaluators do not special-case
    /// (as `ir::semantics::grad_binary`).
    fn atan2_cut(_: &mut Emitter, _: Self, _: Self, d: Self) -> Self {
        d
    }
}

impl Num for Iv {
    fn konst(e: &mut Emitter, c: f64) -> Self {
        e.iv_const(c)
    }
    fn add(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.iv_add(a, b)
    }
    fn sub(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.iv_sub(a, b)
    }
    fn mul(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.iv_mul(a, b, None)
    }
    fn div(e: &mut Emitter, a: Self, b: Self) -> Self {
        e.iv_div(a, b)
    }
    fn neg(e: &mut Emitter, a: Self) -> Self {
        e.iv_neg(a)
    }
    fn unary(e: &mut Emitter, u: UnaryOp, a: Self) -> Self {
        iv_unary(e, u, a)
    }
    fn binary(e: &mut Emitter, op: BinaryOp, a: Self, b: Self) -> Self {
        iv_binary(e, op, a, b)
    }
    fn powi(e: &mut Emitter, a: Self, n: i64) -> Self {
        e.iv_powi(a, n)
    }
    fn abs_grad(e: &mut Emitter, a: Self, da: Self) -> Self {
        // The sign of a is certain only when a.lo >= 0 (lane -lo <= 0) or
        // a.hi < 0.
        let z = e.c(0.0);
        let (n, h) = e.iv_lanes(a);
        let nonneg = e.fcmp(FloatCC::LessThanOrEqual, n, z);
        let neg = e.fcmp(FloatCC::LessThan, h, z);
        let nda = e.iv_neg(da);
        let both = e.iv_hull(da, nda);
        pick(e, nonneg, da, neg, nda, both)
    }
    fn min_grad(e: &mut Emitter, a: Self, b: Self, da: Self, db: Self) -> Self {
        // a < b everywhere iff a.hi < b.lo; nowhere iff b.hi <= a.lo.
        let (alo, ahi) = bounds(e, a);
        let (blo, bhi) = bounds(e, b);
        let a_first = e.fcmp(FloatCC::LessThan, ahi, blo);
        let b_first = e.fcmp(FloatCC::LessThanOrEqual, bhi, alo);
        let both = e.iv_hull(da, db);
        pick(e, a_first, da, b_first, db, both)
    }
    fn max_grad(e: &mut Emitter, a: Self, b: Self, da: Self, db: Self) -> Self {
        let (alo, ahi) = bounds(e, a);
        let (blo, bhi) = bounds(e, b);
        let a_first = e.fcmp(FloatCC::GreaterThan, alo, bhi);
        let b_first = e.fcmp(FloatCC::LessThanOrEqual, ahi, blo);
        let both = e.iv_hull(da, db);
        pick(e, a_first, da, b_first, db, both)
    }
    /// As `ir::semantics::igrad_binary`: a box with `b.lo <= 0` and
    /// `0 ∈ a` touches the cut, where no finite bound on the rate of change
    /// exists, so the partial is the whole line. (Partials known to be
    /// exactly zero never reach here: they stay zero, as in the reference.)
    fn atan2_cut(e: &mut Emitter, a: Self, b: Self, d: Self) -> Self {
        let z = e.c(0.0);
        let (alo, ahi) = bounds(e, a);
        let (blo, _) = bounds(e, b);
        let b_nonpos = e.fcmp(FloatCC::LessThanOrEqual, blo, z);
        let a_lo = e.fcmp(FloatCC::LessThanOrEqual, alo, z);
        let a_hi = e.fcmp(FloatCC::LessThanOrEqual, z, ahi);
        let a_has0 = e.b.ins().band(a_lo, a_hi);
        let cut = e.b.ins().band(b_nonpos, a_has0);
        let entire = Iv(e.vconst(f64::INFINITY, f64::INFINITY));
        e.iv_select(cut, entire, d)
    }
}

/// The bounds `(lo, hi)` of an interval as scalars.
fn bounds(e: &mut Emitter, a: Iv) -> (Value, Value) {
    let (n, h) = e.iv_lanes(a);
    (e.neg(n), h)
}

/// `if c1 { r1 } else if c2 { r2 } else { r3 }`.
fn pick(e: &mut Emitter, c1: Value, r1: Iv, c2: Value, r2: Iv, r3: Iv) -> Iv {
    let r = e.iv_select(c2, r2, r3);
    e.iv_select(c1, r1, r)
}

/// A value with its three partial derivatives (`None` = exactly zero).
type Dual<T> = (T, [Option<T>; 3]);

/// Forward-mode value and gradient of f; inputs are the (point or interval)
/// coordinates.
pub(crate) fn grad<T: Num + Spill>(
    e: &mut Emitter,
    f: &Function,
    live: &[bool],
    xyz: [T; 3],
) -> Dual<T> {
    let unit = |e: &mut Emitter, k: usize| {
        let mut d = [None; 3];
        d[k] = Some(T::konst(e, 1.0));
        d
    };
    seeded(e, f, live, xyz, &unit)
}

/// Forward-mode value and directional derivative `∇f·v` of f (in partial
/// slot 0): each coordinate's derivative is seeded with its component of
/// `v`, so one partial is carried instead of three.
pub(crate) fn directional<T: Num + Spill>(
    e: &mut Emitter,
    f: &Function,
    live: &[bool],
    xyz: [T; 3],
    v: [T; 3],
) -> (T, Option<T>) {
    let seed = |_: &mut Emitter, k: usize| [Some(v[k]), None, None];
    let (val, d) = seeded(e, f, live, xyz, &seed);
    (val, d[0])
}

/// Forward mode with the partials of the coordinate `k` seeded by `seed(k)`.
fn seeded<T: Num + Spill>(
    e: &mut Emitter,
    f: &Function,
    live: &[bool],
    xyz: [T; 3],
    seed: &dyn Fn(&mut Emitter, usize) -> [Option<T>; 3],
) -> Dual<T> {
    let var = |e: &mut Emitter, k: usize| (xyz[k], seed(e, k));
    sweep(e, f, live, var, |e, op, a| match *op {
        Op::Const(c) => (T::konst(e, c), [None; 3]),
        Op::Unary(u, _) => grad_unary(e, u, a[0]),
        Op::Binary(o, _, _) => grad_binary(e, o, a[0], a[1]),
        Op::Powi(_, n) => grad_powi(e, a[0], i64::from(n)),
        Op::Var(v) => var(e, v.index()),
    })
}

/// `d[k] = rule(d[k])` for each non-zero partial.
fn map_d<T: Num>(
    e: &mut Emitter,
    d: [Option<T>; 3],
    mut rule: impl FnMut(&mut Emitter, T) -> T,
) -> [Option<T>; 3] {
    d.map(|dk| dk.map(|dk| rule(e, dk)))
}

fn grad_unary<T: Num>(e: &mut Emitter, u: UnaryOp, (a, da): Dual<T>) -> Dual<T> {
    let v = T::unary(e, u, a);
    let d = match u {
        UnaryOp::Neg => map_d(e, da, |e, x| T::neg(e, x)),
        UnaryOp::Abs => map_d(e, da, |e, x| T::abs_grad(e, a, x)),
        UnaryOp::Square => {
            if da.iter().all(Option::is_none) {
                da
            } else {
                let two_a = T::add(e, a, a);
                map_d(e, da, |e, x| T::mul(e, two_a, x))
            }
        }
        UnaryOp::Sqrt => {
            if da.iter().all(Option::is_none) {
                da
            } else {
                let two_s = T::add(e, v, v);
                map_d(e, da, |e, x| T::div(e, x, two_s))
            }
        }
        UnaryOp::Exp => map_d(e, da, |e, x| T::mul(e, v, x)),
        UnaryOp::Ln => map_d(e, da, |e, x| T::div(e, x, a)),
        UnaryOp::Sin => {
            if da.iter().all(Option::is_none) {
                da
            } else {
                let c = T::unary(e, UnaryOp::Cos, a);
                map_d(e, da, |e, x| T::mul(e, c, x))
            }
        }
        UnaryOp::Cos => {
            if da.iter().all(Option::is_none) {
                da
            } else {
                let s = T::unary(e, UnaryOp::Sin, a);
                map_d(e, da, |e, x| {
                    let p = T::mul(e, s, x);
                    T::neg(e, p)
                })
            }
        }
    };
    (v, d)
}

fn grad_binary<T: Num>(
    e: &mut Emitter,
    op: BinaryOp,
    (a, da): Dual<T>,
    (b, db): Dual<T>,
) -> Dual<T> {
    let v = T::binary(e, op, a, b);
    let mut d = [None; 3];
    for k in 0..3 {
        d[k] = match (da[k], db[k]) {
            (None, None) => None,
            (x, y) => Some(binary_partial(e, op, a, b, v, x, y)),
        };
    }
    (v, d)
}

/// One partial of `op(a, b)` (value `v`) given the operands' partials,
/// at least one of which is non-zero.
fn binary_partial<T: Num>(
    e: &mut Emitter,
    op: BinaryOp,
    a: T,
    b: T,
    v: T,
    da: Option<T>,
    db: Option<T>,
) -> T {
    let zero = |e: &mut Emitter, x: Option<T>| match x {
        Some(x) => x,
        None => T::konst(e, 0.0),
    };
    match op {
        BinaryOp::Add => match (da, db) {
            (Some(x), Some(y)) => T::add(e, x, y),
            (Some(x), None) | (None, Some(x)) => x,
            (None, None) => T::konst(e, 0.0),
        },
        BinaryOp::Sub => match (da, db) {
            (Some(x), Some(y)) => T::sub(e, x, y),
            (Some(x), None) => x,
            (None, Some(y)) => T::neg(e, y),
            (None, None) => T::konst(e, 0.0),
        },
        // da·b + a·db
        BinaryOp::Mul => {
            let l = da.map(|x| T::mul(e, x, b));
            let r = db.map(|y| T::mul(e, a, y));
            sum(e, l, r)
        }
        // (da - (a/b)·db) / b
        BinaryOp::Div => {
            let n = match (da, db) {
                (Some(x), Some(y)) => {
                    let t = T::mul(e, v, y);
                    T::sub(e, x, t)
                }
                (Some(x), None) => x,
                (None, Some(y)) => {
                    let t = T::mul(e, v, y);
                    T::neg(e, t)
                }
                (None, None) => T::konst(e, 0.0),
            };
            T::div(e, n, b)
        }
        BinaryOp::Min => {
            let (x, y) = (zero(e, da), zero(e, db));
            T::min_grad(e, a, b, x, y)
        }
        BinaryOp::Max => {
            let (x, y) = (zero(e, da), zero(e, db));
            T::max_grad(e, a, b, x, y)
        }
        // atan2(a, b): (b·da - a·db) / (a² + b²)
        BinaryOp::Atan2 => {
            let l = da.map(|x| T::mul(e, b, x));
            let r = db.map(|y| T::mul(e, a, y));
            let n = match (l, r) {
                (Some(l), Some(r)) => T::sub(e, l, r),
                (Some(l), None) => l,
                (None, Some(r)) => T::neg(e, r),
                (None, None) => T::konst(e, 0.0),
            };
            let a2 = T::unary(e, UnaryOp::Square, a);
            let b2 = T::unary(e, UnaryOp::Square, b);
            let r2 = T::add(e, a2, b2);
            let q = T::div(e, n, r2);
            T::atan2_cut(e, a, b, q)
        }
        // a^b = exp(b ln a): v · (db·ln a + b·da/a)
        BinaryOp::Pow => {
            let l = db.map(|y| {
                let ln = T::unary(e, UnaryOp::Ln, a);
                T::mul(e, y, ln)
            });
            let r = da.map(|x| {
                let q = T::div(e, x, a);
                T::mul(e, b, q)
            });
            let s = sum(e, l, r);
            T::mul(e, v, s)
        }
    }
}

fn sum<T: Num>(e: &mut Emitter, l: Option<T>, r: Option<T>) -> T {
    match (l, r) {
        (Some(l), Some(r)) => T::add(e, l, r),
        (Some(x), None) | (None, Some(x)) => x,
        (None, None) => T::konst(e, 0.0),
    }
}

fn grad_powi<T: Num>(e: &mut Emitter, (a, da): Dual<T>, n: i64) -> Dual<T> {
    let v = T::powi(e, a, n);
    let d = match n {
        0 => [None; 3],
        1 => da,
        _ if da.iter().all(Option::is_none) => da,
        _ => {
            // n · a^(n-1), computed once for all partials.
            let nk = T::konst(e, n as f64);
            let p = T::powi(e, a, n - 1);
            let k = T::mul(e, nk, p);
            map_d(e, da, |e, x| T::mul(e, k, x))
        }
    };
    (v, d)
}
