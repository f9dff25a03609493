//! The SSA intermediate representation of one implicit surface.
//!
//! # Contract
//! A [`Function`] is a flat list of [`Op`]s. Value `vN` is the result of
//! `ops[N]`; every operand of an op names a value defined *earlier* in the
//! list, so the list is in topological order and evaluation is one forward
//! sweep with no control flow. Each value is defined exactly once (SSA).
//! The function has one result, [`Function::root`], which is f(x, y, z):
//! negative inside the shape, positive outside, zero on the surface.
//!
//! Every op is a pure function of its operands; there is no memory and no
//! side effect, so a pass may reorder, merge or delete ops freely as long as
//! the operand-before-use order holds. The point semantics of each op are
//! IEEE-754 binary64 with round-to-nearest (see [`Op`] for NaN rules); the
//! interval semantics are in [`crate::interval`].
//!
//! Passes ([`passes`]) take a `&Function` and return a new `Function`; they
//! keep no hidden state. [`validate::validate`] checks the contract and runs
//! after lowering and after every pass in debug builds and in tests.

pub mod affine_rules;
pub mod passes;
pub mod print;
pub mod prune;
pub mod random;
pub mod semantics;
pub mod validate;

use rustc_hash::FxHashMap;
use std::fmt;

/// Index of an SSA value (and of the op that defines it) in a [`Function`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ValueId(pub u32);

impl ValueId {
    /// The index into [`Function::ops`].
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl fmt::Display for ValueId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "v{}", self.0)
    }
}

/// One of the three input coordinates.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Var {
    /// The x coordinate.
    X,
    /// The y coordinate.
    Y,
    /// The z coordinate.
    Z,
}

impl Var {
    /// All three variables in argument order.
    pub const ALL: [Var; 3] = [Var::X, Var::Y, Var::Z];

    /// Position of this variable in an `[x, y, z]` argument array.
    pub fn index(self) -> usize {
        match self {
            Var::X => 0,
            Var::Y => 1,
            Var::Z => 2,
        }
    }

    /// The lower-case name used in source and in the printed IR.
    pub fn name(self) -> &'static str {
        match self {
            Var::X => "x",
            Var::Y => "y",
            Var::Z => "z",
        }
    }
}

/// Ops of one operand.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum UnaryOp {
    /// -a
    Neg,
    /// |a|
    Abs,
    /// a*a, with the tighter interval of an even power.
    Square,
    /// sqrt(a); NaN for a < 0.
    Sqrt,
    /// e^a
    Exp,
    /// ln(a); NaN for a < 0, -inf at 0.
    Ln,
    /// sin(a), radians.
    Sin,
    /// cos(a), radians.
    Cos,
    /// tan(a), radians; unbounded near its poles.
    Tan,
    /// asin(a) in [-π/2, π/2]; NaN outside [-1, 1].
    Asin,
    /// acos(a) in [0, π]; NaN outside [-1, 1].
    Acos,
    /// atan(a) in (-π/2, π/2).
    Atan,
    /// sinh(a)
    Sinh,
    /// cosh(a)
    Cosh,
    /// tanh(a)
    Tanh,
    /// The largest integer not above a (exact).
    Floor,
    /// The smallest integer not below a (exact).
    Ceil,
    /// The nearest integer, halves away from zero (exact).
    Round,
    /// -1, 0 or 1 as a is negative, zero (either sign) or positive; NaN
    /// for NaN.
    Sign,
}

impl UnaryOp {
    /// Every one-operand op, in declaration order.
    pub const ALL: [UnaryOp; 19] = [
        UnaryOp::Neg,
        UnaryOp::Abs,
        UnaryOp::Square,
        UnaryOp::Sqrt,
        UnaryOp::Exp,
        UnaryOp::Ln,
        UnaryOp::Sin,
        UnaryOp::Cos,
        UnaryOp::Tan,
        UnaryOp::Asin,
        UnaryOp::Acos,
        UnaryOp::Atan,
        UnaryOp::Sinh,
        UnaryOp::Cosh,
        UnaryOp::Tanh,
        UnaryOp::Floor,
        UnaryOp::Ceil,
        UnaryOp::Round,
        UnaryOp::Sign,
    ];

    /// The op's mnemonic in the printed IR (and the `.vm` format).
    pub fn name(self) -> &'static str {
        match self {
            UnaryOp::Neg => "neg",
            UnaryOp::Abs => "abs",
            UnaryOp::Square => "square",
            UnaryOp::Sqrt => "sqrt",
            UnaryOp::Exp => "exp",
            UnaryOp::Ln => "ln",
            UnaryOp::Sin => "sin",
            UnaryOp::Cos => "cos",
            UnaryOp::Tan => "tan",
            UnaryOp::Asin => "asin",
            UnaryOp::Acos => "acos",
            UnaryOp::Atan => "atan",
            UnaryOp::Sinh => "sinh",
            UnaryOp::Cosh => "cosh",
            UnaryOp::Tanh => "tanh",
            UnaryOp::Floor => "floor",
            UnaryOp::Ceil => "ceil",
            UnaryOp::Round => "round",
            UnaryOp::Sign => "sign",
        }
    }

    /// Whether the op is piecewise constant: its derivative is 0 between
    /// jumps, and unbounded over a box that may hold one.
    pub fn is_step(self) -> bool {
        matches!(
            self,
            UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round | UnaryOp::Sign
        )
    }
}

/// Ops of two operands.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BinaryOp {
    /// a + b
    Add,
    /// a - b
    Sub,
    /// a * b
    Mul,
    /// a / b
    Div,
    /// min(a, b); NaN if either operand is NaN.
    Min,
    /// max(a, b); NaN if either operand is NaN.
    Max,
    /// atan2(a, b) = angle of the point (b, a), as `f64::atan2(a, b)`.
    Atan2,
    /// a^b for real b, defined as exp(b ln a): NaN for a < 0.
    Pow,
    /// The least non-negative remainder of a divided by b (as Fidget's
    /// `mod` and `f64::rem_euclid`): in [0, |b|], NaN where b = 0 or a is
    /// infinite.
    Mod,
}

impl BinaryOp {
    /// Every two-operand op, in declaration order.
    pub const ALL: [BinaryOp; 9] = [
        BinaryOp::Add,
        BinaryOp::Sub,
        BinaryOp::Mul,
        BinaryOp::Div,
        BinaryOp::Min,
        BinaryOp::Max,
        BinaryOp::Atan2,
        BinaryOp::Pow,
        BinaryOp::Mod,
    ];

    /// The op's mnemonic in the printed IR (and the `.vm` format).
    pub fn name(self) -> &'static str {
        match self {
            BinaryOp::Add => "add",
            BinaryOp::Sub => "sub",
            BinaryOp::Mul => "mul",
            BinaryOp::Div => "div",
            BinaryOp::Min => "min",
            BinaryOp::Max => "max",
            BinaryOp::Atan2 => "atan2",
            BinaryOp::Pow => "pow",
            BinaryOp::Mod => "mod",
        }
    }
}

impl BinaryOp {
    /// Whether `op(a, b)` and `op(b, a)` have the same bits for every pair
    /// (NaN payloads aside). Not `min`/`max`: on a tie they return the
    /// second operand, so `min(0, -0)` is `-0` and `min(-0, 0)` is `0`.
    pub fn is_commutative(self) -> bool {
        matches!(self, BinaryOp::Add | BinaryOp::Mul)
    }
}

/// One SSA definition.
///
/// Point semantics: IEEE binary64, round to nearest. `min`/`max` propagate
/// NaN (unlike `f64::min`), so that a value undefined at a point stays
/// undefined through every op; this is what lets the interval semantics take
/// only the defined part of a domain and still contain every real value.
#[derive(Copy, Clone, Debug)]
pub enum Op {
    /// An input coordinate.
    Var(Var),
    /// A constant (never NaN after lowering; may be ±inf only via folding).
    Const(f64),
    /// A one-operand op.
    Unary(UnaryOp, ValueId),
    /// A two-operand op.
    Binary(BinaryOp, ValueId, ValueId),
    /// a^n for an integer n (n may be negative; a^0 = 1).
    Powi(ValueId, i32),
}

impl Op {
    /// The operands this op reads, in order.
    pub fn operands(&self) -> impl Iterator<Item = ValueId> {
        let (a, b) = match *self {
            Op::Var(_) | Op::Const(_) => (None, None),
            Op::Unary(_, a) | Op::Powi(a, _) => (Some(a), None),
            Op::Binary(_, a, b) => (Some(a), Some(b)),
        };
        a.into_iter().chain(b)
    }

    /// The same op with every operand passed through `f`.
    pub fn map_operands(&self, mut f: impl FnMut(ValueId) -> ValueId) -> Op {
        match *self {
            Op::Var(_) | Op::Const(_) => *self,
            Op::Unary(u, a) => Op::Unary(u, f(a)),
            Op::Powi(a, n) => Op::Powi(f(a), n),
            Op::Binary(b, x, y) => Op::Binary(b, f(x), f(y)),
        }
    }

    /// The op's mnemonic in the printed IR.
    pub fn mnemonic(&self) -> &'static str {
        match self {
            Op::Var(_) => "var",
            Op::Const(_) => "const",
            Op::Powi(..) => "powi",
            Op::Unary(u, _) => u.name(),
            Op::Binary(b, ..) => b.name(),
        }
    }
}

// Constants compare by bit pattern so that hash-consing merges exactly the
// constants that are interchangeable (0.0 and -0.0 stay distinct).
impl PartialEq for Op {
    fn eq(&self, other: &Op) -> bool {
        match (self, other) {
            (Op::Const(a), Op::Const(b)) => a.to_bits() == b.to_bits(),
            (Op::Var(a), Op::Var(b)) => a == b,
            (Op::Unary(u, a), Op::Unary(v, b)) => u == v && a == b,
            (Op::Binary(o, a, b), Op::Binary(p, c, d)) => o == p && a == c && b == d,
            (Op::Powi(a, n), Op::Powi(b, m)) => a == b && n == m,
            _ => false,
        }
    }
}

impl Eq for Op {}

impl std::hash::Hash for Op {
    fn hash<H: std::hash::Hasher>(&self, h: &mut H) {
        std::mem::discriminant(self).hash(h);
        match self {
            Op::Var(v) => v.hash(h),
            Op::Const(c) => c.to_bits().hash(h),
            Op::Unary(u, a) => (u, a).hash(h),
            Op::Binary(b, x, y) => (b, x, y).hash(h),
            Op::Powi(a, n) => (a, n).hash(h),
        }
    }
}

/// A surface function f(x, y, z) in SSA form. See the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Function {
    /// The definitions; `ops[i]` defines value `v{i}`.
    pub ops: Vec<Op>,
    /// The value that is f(x, y, z).
    pub root: ValueId,
}

impl Function {
    /// Number of ops.
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Whether the function has no ops (never true for a valid function).
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// The op that defines `v`.
    pub fn op(&self, v: ValueId) -> &Op {
        &self.ops[v.index()]
    }

    /// Which ops the root depends on (itself included), by index.
    pub fn live_mask(&self) -> Vec<bool> {
        let mut live = vec![false; self.ops.len()];
        if let Some(l) = live.get_mut(self.root.index()) {
            *l = true;
        }
        for i in (0..self.ops.len()).rev() {
            if live[i] {
                for a in self.ops[i].operands() {
                    live[a.index()] = true;
                }
            }
        }
        live
    }

    /// Number of ops the root depends on (itself included).
    pub fn live_count(&self) -> usize {
        self.live_mask().iter().filter(|&&l| l).count()
    }

    /// Which of x, y, z the function reads (indexed by [`Var::index`]).
    pub fn uses_vars(&self) -> [bool; 3] {
        let mut used = [false; 3];
        for op in &self.ops {
            if let Op::Var(v) = op {
                used[v.index()] = true;
            }
        }
        used
    }
}

/// Builds a [`Function`] op by op, merging identical ops as they are added
/// (hash-consing, i.e. common-subexpression elimination at construction).
///
/// Operands of commutative ops are put in a canonical order first, so
/// `a + b` and `b + a` become one value (not `min`/`max`, whose operand
/// order decides the sign of a zero result, see
/// [`BinaryOp::is_commutative`]).
#[derive(Default, Debug, Clone)]
pub struct Builder {
    ops: Vec<Op>,
    index: FxHashMap<Op, ValueId>,
}

impl Builder {
    /// An empty builder.
    pub fn new() -> Builder {
        Builder::default()
    }

    /// An empty builder with room for `n` ops (a pass rebuilding a
    /// function knows about how many it gets: growing the index as it
    /// went was half of simplifying a 7,800-op model).
    pub fn with_capacity(n: usize) -> Builder {
        Builder {
            ops: Vec::with_capacity(n),
            index: FxHashMap::with_capacity_and_hasher(n, Default::default()),
        }
    }

    /// Number of distinct ops so far.
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Whether no op was added yet.
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// The op behind an already-built value.
    pub fn op(&self, v: ValueId) -> &Op {
        &self.ops[v.index()]
    }

    /// Adds `op` (operands must already exist) or returns the identical
    /// value built before.
    pub fn push(&mut self, op: Op) -> ValueId {
        let op = match op {
            Op::Binary(b, x, y) if b.is_commutative() && y < x => Op::Binary(b, y, x),
            other => other,
        };
        debug_assert!(op.operands().all(|a| a.index() < self.ops.len()));
        let next = self.ops.len();
        match self.index.entry(op) {
            std::collections::hash_map::Entry::Occupied(e) => *e.get(),
            std::collections::hash_map::Entry::Vacant(e) => {
                let v = ValueId(u32::try_from(next).expect("more than 2^32 ops"));
                self.ops.push(op);
                *e.insert(v)
            }
        }
    }

    /// An input coordinate.
    pub fn var(&mut self, v: Var) -> ValueId {
        self.push(Op::Var(v))
    }

    /// A constant.
    pub fn constant(&mut self, c: f64) -> ValueId {
        self.push(Op::Const(c))
    }

    /// A one-operand op.
    pub fn unary(&mut self, op: UnaryOp, a: ValueId) -> ValueId {
        self.push(Op::Unary(op, a))
    }

    /// A two-operand op.
    pub fn binary(&mut self, op: BinaryOp, a: ValueId, b: ValueId) -> ValueId {
        self.push(Op::Binary(op, a, b))
    }

    /// a^n for integer n.
    pub fn powi(&mut self, a: ValueId, n: i32) -> ValueId {
        self.push(Op::Powi(a, n))
    }

    /// Finishes with `root` as the result. Ops the root does not reach are
    /// kept; dead-code elimination removes them.
    pub fn finish(self, root: ValueId) -> Function {
        Function {
            ops: self.ops,
            root,
        }
    }
}
