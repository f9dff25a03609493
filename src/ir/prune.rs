//! Pruning a function to a box (tape simplification, after Fidget).
//!
//! Over a small region of space most `min` and `max` nodes of a CSG tree
//! have one operand below (or above) the other everywhere: the branch that
//! loses can never be picked there. [`prune`] evaluates every op's
//! interval over the box and replaces each such node by the operand it
//! always picks, then drops the ops nothing reads any more. A 2D model
//! such as prospero (7576 ops) shrinks to a few hundred ops over one tile
//! of a render, so evaluating the pruned function, even in the
//! interpreter, is cheaper than evaluating the whole one natively.
//!
//! # Exactness
//! The pruned function gives the same bits as `f` at every point of the
//! box (NaN payloads aside), not just a value close to it: a node
//! `min(a, b)` with `sup A < inf B` picks `a` at every point, since the
//! point values lie in the intervals (each interval op contains the
//! correctly rounded point op of any arguments in its operands'
//! intervals). A `min` also returns NaN where the losing operand is NaN,
//! so a branch is dropped only if it is proven defined on the whole box:
//! every op in it has finite operand and result intervals and arguments
//! inside its domain (`sqrt` of a non-negative, `ln` of a positive,
//! division by an interval without 0, and so on).

use super::semantics::run_interval;
use super::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId};
use crate::interval::Interval;

/// Result of [`prune`].
#[derive(Clone, Debug)]
pub struct Pruned {
    /// The function restricted to the box.
    pub function: Function,
    /// How many `min`/`max` nodes were decided.
    pub decided: usize,
}

/// What pruning knows of one value over a box.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct Facts {
    /// The value is a finite number at every point of the box.
    pub defined: bool,
    /// The value is never negative, by its form (a square, a sum of
    /// squares...). Floating-point point values keep that sign exactly,
    /// while the interval of such a sum may dip below 0 by rounding, which
    /// alone would leave `sqrt(x² + y²)` unproven.
    pub nonneg: bool,
    /// The value's point bits lie in its interval (or are NaN) at every
    /// point of the box. Only a division by a signed zero breaks this:
    /// the interval of `a / [0, b]` is a half-line, while the point value
    /// at `-0` is the infinity of the other sign. A `min`/`max` may only
    /// be decided in favour of a contained operand.
    pub contained: bool,
}

/// The facts of `op`'s value over a box, from its own interval `value`
/// and its operands' intervals and facts (`arg`). The one statement of
/// the rules, shared by [`prune`] and the tapes' pruning (which calls the
/// per-arity rules below directly).
pub fn facts(op: &Op, value: Interval, arg: impl Fn(ValueId) -> (Interval, Facts)) -> Facts {
    match *op {
        Op::Var(_) => var_facts(value),
        Op::Const(c) => const_facts(c),
        Op::Unary(u, a) => {
            let (va, fa) = arg(a);
            unary_facts(u, (va, fa), value)
        }
        Op::Binary(o, a, b) => binary_facts(o, arg(a), arg(b), value),
        Op::Powi(a, n) => powi_facts(n, arg(a), value),
    }
}

fn finite(i: Interval) -> bool {
    i.lo.is_finite() && i.hi.is_finite()
}

fn zero_in(i: Interval) -> bool {
    i.lo <= 0.0 && i.hi >= 0.0
}

/// The facts of an input coordinate whose interval is `value`.
#[inline]
pub fn var_facts(value: Interval) -> Facts {
    Facts {
        defined: finite(value),
        nonneg: false,
        contained: true,
    }
}

/// The facts of the constant `c`.
#[inline]
pub fn const_facts(c: f64) -> Facts {
    Facts {
        defined: c.is_finite(),
        nonneg: c >= 0.0,
        contained: true,
    }
}

/// The facts of `u(a)` with value interval `value`.
#[inline]
pub fn unary_facts(u: UnaryOp, (va, fa): (Interval, Facts), value: Interval) -> Facts {
    let nonneg = matches!(
        u,
        UnaryOp::Square | UnaryOp::Abs | UnaryOp::Sqrt | UnaryOp::Exp | UnaryOp::Cosh
    );
    let domain = match u {
        UnaryOp::Sqrt => va.lo >= 0.0 || fa.nonneg,
        UnaryOp::Ln => va.lo > 0.0,
        UnaryOp::Asin | UnaryOp::Acos => va.lo >= -1.0 && va.hi <= 1.0,
        _ => true,
    };
    Facts {
        defined: fa.defined && domain && finite(value),
        nonneg,
        contained: fa.contained,
    }
}

/// The facts of `o(a, b)` with value interval `value`.
#[inline]
pub fn binary_facts(
    o: BinaryOp,
    (va, fa): (Interval, Facts),
    (vb, fb): (Interval, Facts),
    value: Interval,
) -> Facts {
    let nonneg = match o {
        BinaryOp::Add | BinaryOp::Mul | BinaryOp::Div | BinaryOp::Min | BinaryOp::Max => {
            fa.nonneg && fb.nonneg
        }
        BinaryOp::Mod => true,
        _ => false,
    };
    let (domain, signed_zero_pole) = match o {
        BinaryOp::Div => (vb.lo > 0.0 || vb.hi < 0.0, zero_in(vb)),
        BinaryOp::Mod => (vb.lo > 0.0 || vb.hi < 0.0, false),
        BinaryOp::Pow => (va.lo > 0.0, va.lo <= 0.0),
        _ => (true, false),
    };
    Facts {
        defined: fa.defined && fb.defined && domain && finite(value),
        nonneg,
        contained: !signed_zero_pole && fa.contained && fb.contained,
    }
}

/// The facts of `a^n` with value interval `value`.
#[inline]
pub fn powi_facts(n: i32, (va, fa): (Interval, Facts), value: Interval) -> Facts {
    let domain = n >= 0 || va.lo > 0.0 || va.hi < 0.0;
    let signed_zero_pole = n < 0 && zero_in(va);
    Facts {
        defined: fa.defined && domain && finite(value),
        nonneg: n % 2 == 0,
        contained: !signed_zero_pole && fa.contained,
    }
}

/// The operand (0 or 1) that `op` (`min` or `max`) picks at every point of
/// a box where its operands have these intervals and facts, if one is
/// proven to (the other must be proven defined: a NaN would win; and the
/// winner's point values must lie in its interval).
#[inline]
pub fn decided_operand(op: BinaryOp, x: (Interval, Facts), y: (Interval, Facts)) -> Option<usize> {
    let (a, c) = (x.0, y.0);
    let (x_wins, y_wins) = match op {
        BinaryOp::Min => (a.hi < c.lo, c.hi < a.lo),
        BinaryOp::Max => (a.lo > c.hi, c.lo > a.hi),
        _ => return None,
    };
    if x_wins && y.1.defined && x.1.contained {
        Some(0)
    } else if y_wins && x.1.defined && y.1.contained {
        Some(1)
    } else {
        None
    }
}

/// The operand (0 or 1) that `op` (`min` or `max`) may be replaced by on a
/// box where only the sign of its value matters (see
/// [`crate::eval::tape::Keep::Signs`]): the other operand is proven
/// defined and positive there (for `min`) or negative (for `max`), so the
/// node and the kept operand have the same sign, and are NaN together
/// (`min` and `max` return NaN for a NaN operand), at every point of the
/// box. A defined value is contained in its interval (only undefined
/// operations break containment).
#[inline]
pub fn sign_decided_operand(
    op: BinaryOp,
    x: (Interval, Facts),
    y: (Interval, Facts),
) -> Option<usize> {
    let beyond = |v: (Interval, Facts)| {
        v.1.defined
            && match op {
                BinaryOp::Min => v.0.lo > 0.0,
                BinaryOp::Max => v.0.hi < 0.0,
                _ => false,
            }
    };
    if beyond(y) {
        Some(0)
    } else if beyond(x) {
        Some(1)
    } else {
        None
    }
}

/// `f` restricted to the box `b` (see the module docs); `None` when no
/// `min`/`max` node is decided there.
pub fn prune(f: &Function, b: [Interval; 3]) -> Option<Pruned> {
    prune_to_at_most(f, b, usize::MAX)
}

/// [`prune`], but `None` as well when more than `max_live` ops would stay
/// live (checked before the pruned function is built, which is the costly
/// part of a pruning that does not pay).
pub fn prune_to_at_most(f: &Function, b: [Interval; 3], max_live: usize) -> Option<Pruned> {
    let Decided { alias, decided, .. } = decide(f, b);
    if decided == 0 {
        return None;
    }
    let root = alias[f.root.index()];
    let live = live_through(f, &alias);
    let kept = (0..f.ops.len())
        .filter(|&i| live[i] && alias[i] == i)
        .count();
    if kept > max_live {
        return None;
    }
    let mut b = Builder::with_capacity(kept);
    let mut new_id: Vec<Option<ValueId>> = vec![None; f.ops.len()];
    for (i, op) in f.ops.iter().enumerate() {
        if live[i] && alias[i] == i {
            let op = op.map_operands(|a| new_id[alias[a.index()]].expect("operand built first"));
            new_id[i] = Some(b.push(op));
        }
    }
    Some(Pruned {
        function: b.finish(new_id[root].expect("root built")),
        decided,
    })
}

// Every op's interval over a box, and which `min`/`max` nodes are
// decided there.
struct Decided {
    /// Each op's interval over the box.
    iv: Vec<Interval>,
    /// alias[i]: the op whose value op i always equals on the box.
    alias: Vec<usize>,
    /// How many `min`/`max` nodes were decided.
    decided: usize,
}

fn decide(f: &Function, b: [Interval; 3]) -> Decided {
    let mut iv = Vec::with_capacity(f.ops.len());
    run_interval(&f.ops, b, &mut iv);
    let mut fact = vec![Facts::default(); f.ops.len()];
    let mut alias: Vec<usize> = (0..f.ops.len()).collect();
    let mut decided = 0;
    for (i, op) in f.ops.iter().enumerate() {
        let arg = |v: ValueId| (iv[v.index()], fact[v.index()]);
        let choice = match *op {
            Op::Binary(o, x, y) => decided_operand(o, arg(x), arg(y)).map(|k| [x, y][k]),
            _ => None,
        };
        fact[i] = facts(op, iv[i], arg);
        if let Some(winner) = choice {
            alias[i] = alias[winner.index()];
            decided += 1;
        }
    }
    Decided { iv, alias, decided }
}

// The ops the root reads through the aliases (an aliased op itself is
// marked but reads nothing).
fn live_through(f: &Function, alias: &[usize]) -> Vec<bool> {
    let root = alias[f.root.index()];
    let mut live = vec![false; f.ops.len()];
    live[root] = true;
    for i in (0..f.ops.len()).rev() {
        if live[i] && alias[i] == i {
            for a in f.ops[i].operands() {
                live[alias[a.index()]] = true;
            }
        }
    }
    live
}

/// Whether `f` is proven continuously differentiable on the box `b`: once
/// the `min`/`max` nodes decided there are replaced by their winners (see
/// [`prune`]), no op the root reads has a kink, a jump or an infinite
/// slope inside the box (`abs` and `sign` of an interval holding 0, an
/// undecided `min` or `max`, `floor`, `ceil`, `round` or `mod` that is not
/// constant on the box, `sqrt` or a power of an interval reaching 0,
/// `asin` or `acos` reaching ±1, `atan2`, any op whose interval is not
/// finite). A false answer proves
/// nothing: it is what anti-aliasing uses to rule out creases (a normal
/// that jumps inside a pixel) before it samples a pixel more sparsely.
pub fn smooth_on(f: &Function, b: [Interval; 3]) -> bool {
    let Decided { iv, alias, .. } = decide(f, b);
    let live = live_through(f, &alias);
    let finite = |v: Interval| !v.is_empty() && v.lo.is_finite() && v.hi.is_finite();
    let constant = |v: Interval| v.lo == v.hi;
    (0..f.ops.len())
        .filter(|&i| live[i] && alias[i] == i)
        .all(|i| {
            let arg = |v: ValueId| iv[alias[v.index()]];
            finite(iv[i])
                && match f.ops[i] {
                    Op::Var(_) | Op::Const(_) => true,
                    Op::Unary(u, a) => {
                        let x = arg(a);
                        finite(x)
                            && match u {
                                UnaryOp::Abs | UnaryOp::Sign => x.lo > 0.0 || x.hi < 0.0,
                                UnaryOp::Sqrt => x.lo > 0.0,
                                UnaryOp::Asin | UnaryOp::Acos => x.lo > -1.0 && x.hi < 1.0,
                                UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round => constant(iv[i]),
                                _ => true,
                            }
                    }
                    Op::Binary(o, a, c) => {
                        finite(arg(a))
                            && finite(arg(c))
                            && match o {
                                BinaryOp::Min | BinaryOp::Max | BinaryOp::Atan2 => false,
                                BinaryOp::Mod => false,
                                BinaryOp::Pow => arg(a).lo > 0.0,
                                _ => true,
                            }
                    }
                    Op::Powi(a, n) => {
                        finite(arg(a)) && (n >= 0 || arg(a).lo > 0.0 || arg(a).hi < 0.0)
                    }
                }
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::Var;

    // min(x, x + 10) over x ∈ [0, 1] is x; max(sqrt(y), 5) keeps both
    // when y's box reaches below 0 (sqrt may be NaN there).
    #[test]
    fn decides_ordered_branches_only() {
        let mut b = Builder::new();
        let (x, y) = (b.var(Var::X), b.var(Var::Y));
        let ten = b.constant(10.0);
        let x10 = b.binary(BinaryOp::Add, x, ten);
        let m = b.binary(BinaryOp::Min, x, x10);
        let s = b.unary(UnaryOp::Sqrt, y);
        let five = b.constant(5.0);
        let mx = b.binary(BinaryOp::Max, s, five);
        let r = b.binary(BinaryOp::Sub, m, mx);
        let f = b.finish(r);
        let bx = |y0| {
            [
                Interval::new(0.0, 1.0),
                Interval::new(y0, 4.0),
                Interval::point(0.0),
            ]
        };
        let p = prune(&f, bx(1.0)).expect("both decided");
        assert_eq!(p.decided, 2);
        // x - 5: var, const, sub.
        assert_eq!(p.function.len(), 3);
        let q = prune(&f, bx(-1.0)).expect("min decided");
        assert_eq!(q.decided, 1);
        assert!(
            q.function
                .ops
                .iter()
                .any(|o| matches!(o, Op::Unary(UnaryOp::Sqrt, _)))
        );
        assert!(prune(&f, [Interval::new(-20.0, 20.0), bx(1.0)[1], bx(1.0)[2]]).is_some());
    }

    // x² + y² − 1 is smooth everywhere; a `min` is smooth only where it
    // is decided; `abs` and `sqrt` only away from 0.
    #[test]
    fn smooth_on_finds_kinks_only_where_the_box_holds_them() {
        let mut b = Builder::new();
        let (x, y) = (b.var(Var::X), b.var(Var::Y));
        let x2 = b.unary(UnaryOp::Square, x);
        let y2 = b.unary(UnaryOp::Square, y);
        let s = b.binary(BinaryOp::Add, x2, y2);
        let one = b.constant(1.0);
        let circle = b.binary(BinaryOp::Sub, s, one);
        let m = b.binary(BinaryOp::Min, circle, y);
        let f = b.finish(m);
        let bx = |x0: f64, x1: f64, y0: f64, y1: f64| {
            [
                Interval::new(x0, x1),
                Interval::new(y0, y1),
                Interval::point(0.0),
            ]
        };
        // Near (0, 2): circle ≈ 3 > y ≈ 2, the min picks y.
        assert!(smooth_on(&f, bx(-0.1, 0.1, 1.9, 2.1)));
        // Near (0, 1.618), where y² − 1 = y, the crease crosses the box.
        assert!(!smooth_on(&f, bx(-0.1, 0.1, 1.5, 1.7)));

        let mut b = Builder::new();
        let x = b.var(Var::X);
        let a = b.unary(UnaryOp::Abs, x);
        let r = b.unary(UnaryOp::Sqrt, a);
        let g = b.finish(r);
        assert!(smooth_on(&g, bx(0.5, 1.0, 0.0, 0.0)));
        assert!(smooth_on(&g, bx(-1.0, -0.5, 0.0, 0.0)));
        assert!(!smooth_on(&g, bx(-0.5, 0.5, 0.0, 0.0)));
        assert!(!smooth_on(&g, bx(0.0, 0.5, 0.0, 0.0)));
    }
}
