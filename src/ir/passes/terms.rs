//! Collecting like terms: a sum tree that adds the same value more than
//! once (`x + x + … + x`, `2·a − b + a`) becomes one product per distinct
//! value, `n·x`, with the coefficients merged.
//!
//! A sum tree is a tree of `add`, `sub`, `neg` and products by a constant
//! whose inner nodes are used once (a node used elsewhere too is a term of
//! its own, so every node is walked once and the pass is linear in the size
//! of the function). Coefficients are merged only where their sum or
//! product is exact; a value whose coefficients would cancel to 0 keeps its
//! terms (`x − x` is NaN where x is infinite, so dropping it would define f
//! where the source leaves it undefined). The result has the same real
//! value and the same domain; point values may round differently, like the
//! product chains of `specialise` (see the module doc of `passes`), and
//! intervals come out tighter (`3·X` against `X + X + X`). A tree where
//! nothing merges is left exactly as it was.

use std::collections::HashMap;

use super::fold::{exact_add, exact_mul};
use crate::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId};

/// Rewrites every sum tree that repeats a term (see the module doc).
pub fn collect_terms(f: &Function) -> Function {
    let uses = use_counts(f);
    let mut users_are_sums = vec![true; f.ops.len()];
    for op in &f.ops {
        if coefficients(f, op).is_none() {
            for a in op.operands() {
                users_are_sums[a.index()] = false;
            }
        }
    }
    users_are_sums[f.root.index()] = false;
    let interior =
        |v: ValueId| uses[v.index()] == 1 && users_are_sums[v.index()] && is_sum(f, f.op(v));
    let mut b = Builder::with_capacity(f.ops.len());
    let mut map: Vec<ValueId> = Vec::with_capacity(f.ops.len());
    for (i, op) in f.ops.iter().enumerate() {
        let v = ValueId(i as u32);
        let mut out = b.push(op.map_operands(|a| map[a.index()]));
        if is_sum(f, op) && !interior(v) {
            let terms = flatten(f, v, &interior);
            if terms.pays() {
                out = emit(&mut b, &terms.entries, &map);
            }
        }
        map.push(out);
    }
    b.finish(map[f.root.index()])
}

/// How many ops read each value (the root counts as one more use).
fn use_counts(f: &Function) -> Vec<u32> {
    let mut uses = vec![0u32; f.ops.len()];
    for op in &f.ops {
        for a in op.operands() {
            uses[a.index()] = uses[a.index()].saturating_add(1);
        }
    }
    uses[f.root.index()] = uses[f.root.index()].saturating_add(1);
    uses
}

/// The operands of a sum node with the factor each is taken with, or None
/// for an op that is not a sum node.
fn coefficients(f: &Function, op: &Op) -> Option<[(ValueId, f64); 2]> {
    let konst = |v: ValueId| match *f.op(v) {
        Op::Const(c) if c.is_finite() => Some(c),
        _ => None,
    };
    match *op {
        Op::Binary(BinaryOp::Add, a, c) => Some([(a, 1.0), (c, 1.0)]),
        Op::Binary(BinaryOp::Sub, a, c) => Some([(a, 1.0), (c, -1.0)]),
        // The second entry carries a zero factor: it contributes nothing.
        Op::Unary(UnaryOp::Neg, a) => Some([(a, -1.0), (a, 0.0)]),
        Op::Binary(BinaryOp::Mul, a, c) => match (konst(a), konst(c)) {
            (Some(k), None) => Some([(c, k), (c, 0.0)]),
            (None, Some(k)) => Some([(a, k), (a, 0.0)]),
            _ => None,
        },
        _ => None,
    }
}

fn is_sum(f: &Function, op: &Op) -> bool {
    coefficients(f, op).is_some()
}

/// The terms of one sum tree.
struct Terms {
    /// Each distinct term (an old value) and its coefficient, in the order
    /// first met.
    entries: Vec<(ValueId, f64)>,
    /// Whether some term was met twice and merged.
    merged: bool,
    /// Sum nodes walked through (the ops the tree has now).
    nodes: usize,
}

impl Terms {
    /// Whether rebuilding is worth it: something merged, and the new tree
    /// (one add or sub between terms, at most a product and a constant per
    /// coefficient other than ±1, a neg when every term is negative) is
    /// smaller than the old one, so simplification never grows a function.
    fn pays(&self) -> bool {
        // A product by 0 leaves no term at all (`flatten` drops zero
        // factors); such a tree has nothing to merge.
        if !self.merged || self.entries.is_empty() {
            return false;
        }
        let scaled = self.entries.iter().filter(|e| e.1.abs() != 1.0).count();
        let all_negative = self.entries.iter().all(|e| e.1 < 0.0);
        let rebuilt = self.entries.len() - 1 + 2 * scaled + usize::from(all_negative);
        rebuilt < self.nodes
    }
}

/// Walks the sum tree under `root` (an explicit stack: chains may be
/// millions of nodes long).
fn flatten(f: &Function, root: ValueId, interior: &dyn Fn(ValueId) -> bool) -> Terms {
    let mut terms = Terms {
        entries: Vec::new(),
        merged: false,
        nodes: 0,
    };
    let mut slot: HashMap<ValueId, usize> = HashMap::new();
    let mut stack = vec![(root, 1.0f64)];
    while let Some((v, k)) = stack.pop() {
        let inner = v == root || interior(v);
        let parts = if inner {
            coefficients(f, f.op(v))
        } else {
            None
        };
        let products = parts.map(|p| p.map(|(a, c)| (a, c, exact_mul(k, c))));
        match products {
            Some(p) if p.iter().all(|(_, _, kc)| kc.is_some()) => {
                terms.nodes += 1;
                // Pushed in reverse so terms are met left to right.
                for &(a, c, kc) in p.iter().rev() {
                    if c != 0.0 {
                        stack.push((a, kc.unwrap_or(0.0)));
                    }
                }
            }
            _ => add_term(&mut terms, &mut slot, v, k),
        }
    }
    terms
}

/// Adds `k·v` to the terms, merging with an earlier entry for `v` where the
/// coefficient sum is exact and not zero.
fn add_term(terms: &mut Terms, slot: &mut HashMap<ValueId, usize>, v: ValueId, k: f64) {
    if let Some(&i) = slot.get(&v)
        && let Some(sum) = exact_add(terms.entries[i].1, k).filter(|&s| s != 0.0)
    {
        terms.entries[i].1 = sum;
        terms.merged = true;
        return;
    }
    slot.insert(v, terms.entries.len());
    terms.entries.push((v, k));
}

/// Builds `Σ kᵢ·vᵢ` as (sum of the positive terms) − (sum of the negated
/// negative ones), each sum a balanced tree.
fn emit(b: &mut Builder, entries: &[(ValueId, f64)], map: &[ValueId]) -> ValueId {
    let mut scaled = |v: ValueId, k: f64| -> ValueId {
        let v = map[v.index()];
        if k == 1.0 {
            v
        } else {
            let c = b.constant(k);
            b.binary(BinaryOp::Mul, c, v)
        }
    };
    let plus: Vec<ValueId> = entries
        .iter()
        .filter(|e| e.1 > 0.0)
        .map(|&(v, k)| scaled(v, k))
        .collect();
    let minus: Vec<ValueId> = entries
        .iter()
        .filter(|e| e.1 < 0.0)
        .map(|&(v, k)| scaled(v, -k))
        .collect();
    let p = balanced(b, BinaryOp::Add, &plus);
    let m = balanced(b, BinaryOp::Add, &minus);
    match (p, m) {
        (Some(p), Some(m)) => b.binary(BinaryOp::Sub, p, m),
        (Some(p), None) => p,
        (None, Some(m)) => b.unary(UnaryOp::Neg, m),
        (None, None) => unreachable!("a sum tree has at least one term"),
    }
}

/// `items[0] op items[1] op …` as a balanced tree (None when empty).
pub(super) fn balanced(b: &mut Builder, op: BinaryOp, items: &[ValueId]) -> Option<ValueId> {
    match items {
        [] => None,
        [one] => Some(*one),
        _ => {
            let (l, r) = items.split_at(items.len() / 2);
            let l = balanced(b, op, l)?;
            let r = balanced(b, op, r)?;
            Some(b.binary(op, l, r))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::Var;
    use crate::ir::semantics::run_point;

    fn sum_of_x(n: usize) -> Function {
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let mut s = x;
        for _ in 1..n {
            s = b.push(Op::Binary(BinaryOp::Add, s, x));
        }
        b.finish(s)
    }

    fn value(f: &Function, p: [f64; 3]) -> f64 {
        let mut vals = Vec::new();
        run_point(&f.ops, p, &mut vals);
        vals[f.root.index()]
    }

    #[test]
    fn a_long_sum_of_one_value_becomes_one_product() {
        let f = super::super::dce(&collect_terms(&sum_of_x(1000)));
        assert_eq!(f.ops.len(), 3, "{f:?}");
        assert_eq!(value(&f, [0.5, 0.0, 0.0]), 500.0);
    }

    #[test]
    fn cancelling_terms_are_kept() {
        // x - x + y: merging x would give 0·x, which is not NaN at x = inf.
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let y = b.var(Var::Y);
        let d = b.binary(BinaryOp::Sub, x, x);
        let s = b.binary(BinaryOp::Add, d, y);
        let f = collect_terms(&b.finish(s));
        assert!(value(&f, [f64::INFINITY, 1.0, 0.0]).is_nan());
        assert_eq!(value(&f, [3.0, 1.0, 0.0]), 1.0);
    }

    #[test]
    fn mixed_signs_and_constant_factors_merge() {
        // 2·x - y + x - 3·y + x - y = 4x - 5y
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let y = b.var(Var::Y);
        let two = b.constant(2.0);
        let three = b.constant(3.0);
        let x2 = b.binary(BinaryOp::Mul, two, x);
        let y3 = b.binary(BinaryOp::Mul, y, three);
        let a = b.binary(BinaryOp::Sub, x2, y);
        let c = b.binary(BinaryOp::Add, a, x);
        let d = b.binary(BinaryOp::Sub, c, y3);
        let e = b.binary(BinaryOp::Add, d, x);
        let r = b.binary(BinaryOp::Sub, e, y);
        let before = b.finish(r);
        let f = collect_terms(&before);
        assert_eq!(value(&f, [1.0, 1.0, 0.0]), -1.0);
        assert_eq!(value(&f, [2.0, 0.5, 0.0]), 5.5);
        let f = super::super::dce(&f);
        assert!(f.ops.len() < before.ops.len(), "{f:?}");
        let muls = f
            .ops
            .iter()
            .filter(|o| matches!(o, Op::Binary(BinaryOp::Mul, ..)))
            .count();
        assert_eq!(muls, 2, "{f:?}");
    }

    #[test]
    fn a_product_by_zero_is_left_alone() {
        // Found by fuzzing: 0·y has no term after zero factors are dropped.
        let mut b = Builder::new();
        let y = b.var(Var::Y);
        let zero = b.constant(0.0);
        let p = b.binary(BinaryOp::Mul, zero, y);
        let f = b.finish(p);
        assert_eq!(collect_terms(&f), f);
    }

    #[test]
    fn a_short_repeat_that_would_grow_the_function_is_left() {
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let s = b.binary(BinaryOp::Add, x, x);
        let f = b.finish(s);
        assert_eq!(collect_terms(&f), f);
    }

    #[test]
    fn a_sum_without_repeats_is_untouched() {
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let y = b.var(Var::Y);
        let z = b.var(Var::Z);
        let s = b.binary(BinaryOp::Add, x, y);
        let t = b.binary(BinaryOp::Sub, s, z);
        let f = b.finish(t);
        assert_eq!(super::super::cse(&f), collect_terms(&f));
    }

    #[test]
    fn shared_subsums_are_terms_of_their_own() {
        // s = x + x is used twice: each use sees s as one term.
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let s = b.binary(BinaryOp::Add, x, x);
        let t = b.binary(BinaryOp::Add, s, s);
        let sq = b.unary(UnaryOp::Square, s);
        let r = b.binary(BinaryOp::Add, t, sq);
        let f = collect_terms(&b.finish(r));
        assert_eq!(value(&f, [1.5, 0.0, 0.0]), 15.0);
    }
}
