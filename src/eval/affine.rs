//! Affine enclosures: f over a box by reduced affine arithmetic, each
//! op's form intersected with its interval (the rules of
//! [`crate::ir::affine_rules`]). A trait of its own, [`AffineEvaluator`],
//! implemented by the reference interpreter, by tapes (one box, or a
//! batch a column per register) and by the tape evaluator; native code
//! has no affine kind.
//!
//! Every enclosure contains every point value of f in the box (as the
//! interval kinds do), and lies inside the interval evaluation's
//! enclosure: [`AffineEvaluator::affine`] intersects the root's affine
//! value with it ([`clip`]). The per-op intersection alone does not give
//! that: the interval rules are not inclusion-isotone at exact zeros (a
//! quotient by `[0, h]` is exactly `[0, +inf]`, by the tighter `[ε, h]` its
//! lower bound rounds out to -2⁻⁵¹¹ or so), so a tighter operand can give
//! a lower bound a hair wider. It is EMPTY where the interval evaluation
//! is, or where an op's interval rule, over its operands' affine
//! enclosures, is.

use std::cell::RefCell;

use crate::eval::Single;
use crate::eval::interp::Interpreter;
use crate::eval::tape::{Instr, Reg, Tape, with_workspace};
use crate::eval::taped::TapeEvaluator;
use crate::interval::Interval;
use crate::interval::affine::meet;
use crate::interval::form::Form;
use crate::interval::quadratic::Quadratic;
use crate::ir::affine_rules::{
    AffineValue, FormValue, QuadraticValue, affine_binary, affine_powi, affine_powi_sharing,
    affine_unary, run_affine, tightened,
};
use crate::ir::{BinaryOp, UnaryOp};

/// Evaluates f over boxes with affine forms.
pub trait AffineEvaluator {
    /// f's affine form over the box `b = [X, Y, Z]`, and its interval.
    fn affine_value(&self, b: [Interval; 3]) -> AffineValue;

    /// An interval containing f over `b`: the affine value's, clipped to
    /// the interval evaluation's ([`clip`]).
    fn affine(&self, b: [Interval; 3]) -> Interval;

    /// `out[i] = affine(boxes[i])` for every i.
    fn affine_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        assert_eq!(boxes.len(), out.len());
        for (b, o) in boxes.iter().zip(out.iter_mut()) {
            *o = self.affine(*b);
        }
    }
}

/// The root's affine enclosure `affine` clipped to the interval
/// evaluation's `plain` of the same function over the same box: EMPTY if
/// either is (each means f is undefined on the whole box), else their
/// intersection, or `plain` where they do not meet (as
/// `ir::affine_rules` does per op, so that EMPTY keeps its meaning).
pub fn clip(affine: Interval, plain: Interval) -> Interval {
    if affine.is_empty() || plain.is_empty() {
        return Interval::EMPTY;
    }
    meet(affine, plain).unwrap_or(plain)
}

thread_local! {
    // Per-thread value slots (one per op or register, times the batch),
    // reused across calls.
    static SCRATCH: RefCell<Vec<AffineValue>> = const { RefCell::new(Vec::new()) };
    // The same for forms along a ray (`affine_along`).
    static SCRATCH_ALONG: RefCell<Vec<AffineValue<1>>> = const { RefCell::new(Vec::new()) };
    // The same for second-order forms along a ray (`quadratic_along`),
    // and the squares its powers share (see `run_tape`).
    static SCRATCH_QUADRATIC: RefCell<(Vec<QuadraticValue>, Vec<Quadratic>)> =
        const { RefCell::new((Vec::new(), Vec::new())) };
}

/// f's affine form along the ray `o + d·t` (origin and direction anywhere
/// in the boxes `o` and `d`) for `t` over `t_range`, in the
/// one noise symbol of the ray parameter ([`Affine::along`]), on `tape`;
/// `sides` is the ray's box over that range (each coordinate's interval).
/// Cheaper than a box's form (two numbers per value, not four) and
/// tighter over a ray, whose coordinates it keeps tied together.
///
/// [`Affine::along`]: crate::interval::affine::Affine::along
pub fn affine_along(
    tape: &Tape,
    o: [Interval; 3],
    d: [Interval; 3],
    t_range: Interval,
    sides: [Interval; 3],
) -> AffineValue<1> {
    SCRATCH_ALONG.with_borrow_mut(|m| {
        run_tape(tape, m, &mut Vec::new(), |v| {
            AffineValue::along(o[v], d[v], t_range, sides[v])
        })
    })
}

/// f's second-order form along the ray `o + d·t` for `t` over `t_range`
/// (a quadratic in the ray parameter's noise symbol,
/// [`Quadratic::along`]), on `tape`, as [`affine_along`] takes its
/// arguments. Three numbers per value where [`affine_along`] has two, and
/// the products keep their second-order terms: an expanded polynomial's
/// terms cancel in it as they do in the polynomial.
///
/// [`Quadratic::along`]: crate::interval::quadratic::Quadratic::along
pub fn quadratic_along(
    tape: &Tape,
    o: [Interval; 3],
    d: [Interval; 3],
    t_range: Interval,
    sides: [Interval; 3],
) -> QuadraticValue {
    SCRATCH_QUADRATIC.with_borrow_mut(|(m, squares)| {
        run_tape(tape, m, squares, |v| {
            QuadraticValue::along(o[v], d[v], t_range, sides[v])
        })
    })
}

/// The root's value of `tape` run over the registers `m` (grown to fit),
/// `var` giving each coordinate's value; `squares` is room for the
/// squares that powers share (a first-order form keeps none).
fn run_tape<F: Form>(
    tape: &Tape,
    m: &mut Vec<FormValue<F>>,
    squares: &mut Vec<F>,
    var: impl Fn(usize) -> FormValue<F>,
) -> FormValue<F> {
    if m.len() < tape.registers() {
        m.resize(tape.registers(), FormValue::EMPTY);
    }
    // The squares of the form in one register, which the powers reading
    // it share (an expanded polynomial raises one value to every power),
    // while that register keeps the value; the same bits as without.
    let mut shared = None::<Reg>;
    squares.clear();
    for &instr in tape.code() {
        let (o, v) = match instr {
            Instr::Powi(o, a, n) => {
                if shared != Some(a) {
                    shared = Some(a);
                    squares.clear();
                }
                (o, affine_powi_sharing(&m[a as usize], n, squares))
            }
            _ => step(instr, &var, |r| m[r as usize]),
        };
        if shared == Some(o) {
            shared = None;
        }
        m[o as usize] = v;
    }
    tightened(&m[root(tape)])
}

impl AffineEvaluator for Interpreter {
    fn affine_value(&self, b: [Interval; 3]) -> AffineValue {
        let f = self.function();
        SCRATCH.with_borrow_mut(|vals| {
            run_affine(&f.ops, b, vals);
            vals[f.root.index()]
        })
    }

    fn affine(&self, b: [Interval; 3]) -> Interval {
        clip(self.affine_value(b).range, Single::interval(self, b))
    }
}

/// The value one instruction writes, and its register; `var` gives a
/// coordinate's value, `read` an operand register's.
#[inline]
fn step<F: Form>(
    instr: Instr,
    var: impl Fn(usize) -> FormValue<F>,
    read: impl Fn(Reg) -> FormValue<F>,
) -> (Reg, FormValue<F>) {
    let un = |o: Reg, op: UnaryOp, a: Reg| (o, affine_unary(op, &read(a)));
    let bin = |o: Reg, op: BinaryOp, a: Reg, c: Reg| (o, affine_binary(op, &read(a), &read(c)));
    match instr {
        Instr::Var(o, v) => (o, var(v.index())),
        Instr::Const(o, c) => (o, FormValue::constant(c)),
        Instr::Add(o, a, c) => bin(o, BinaryOp::Add, a, c),
        Instr::Sub(o, a, c) => bin(o, BinaryOp::Sub, a, c),
        Instr::Mul(o, a, c) => bin(o, BinaryOp::Mul, a, c),
        Instr::Min(o, a, c) => bin(o, BinaryOp::Min, a, c),
        Instr::Max(o, a, c) => bin(o, BinaryOp::Max, a, c),
        Instr::Neg(o, a) => un(o, UnaryOp::Neg, a),
        Instr::Square(o, a) => un(o, UnaryOp::Square, a),
        Instr::Sqrt(o, a) => un(o, UnaryOp::Sqrt, a),
        Instr::Unary(o, op, a) => un(o, op, a),
        Instr::Binary(o, op, a, c) => bin(o, op, a, c),
        Instr::Powi(o, a, n) => (o, affine_powi(&read(a), n)),
    }
}

/// The register the tape's result is in (its last instruction's).
fn root(tape: &Tape) -> usize {
    tape.code().last().map_or(0, |i| i.out() as usize)
}

impl AffineEvaluator for Tape {
    fn affine_value(&self, b: [Interval; 3]) -> AffineValue {
        SCRATCH
            .with_borrow_mut(|m| run_tape(self, m, &mut Vec::new(), |v| AffineValue::var(b[v], v)))
    }

    fn affine(&self, b: [Interval; 3]) -> Interval {
        let plain = with_workspace(|ws| self.interval(b, ws));
        clip(self.affine_value(b).range, plain)
    }

    /// One pass over the tape for the whole batch, a column of the batch
    /// per register (as [`Tape::interval_batch`]); each box's own bits.
    fn affine_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        let n = out.len();
        assert_eq!(boxes.len(), n);
        SCRATCH.with_borrow_mut(|m| {
            if m.len() < self.registers() * n {
                m.resize(self.registers() * n, AffineValue::EMPTY);
            }
            for &instr in self.code() {
                for (j, b) in boxes.iter().enumerate() {
                    let (o, v) = step(
                        instr,
                        |v| AffineValue::var(b[v], v),
                        |r| m[r as usize * n + j],
                    );
                    m[o as usize * n + j] = v;
                }
            }
            let r = root(self) * n;
            for (o, v) in out.iter_mut().zip(&m[r..r + n]) {
                *o = v.range;
            }
        });
        let mut plain = vec![Interval::EMPTY; n];
        with_workspace(|ws| self.interval_batch(boxes, &mut plain, ws));
        for (o, p) in out.iter_mut().zip(plain) {
            *o = clip(*o, p);
        }
    }
}

impl AffineEvaluator for TapeEvaluator {
    fn affine_value(&self, b: [Interval; 3]) -> AffineValue {
        self.tape().affine_value(b)
    }

    fn affine(&self, b: [Interval; 3]) -> Interval {
        self.tape().affine(b)
    }

    fn affine_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        self.tape().affine_batch(boxes, out)
    }
}
