//! Balancing long chains: `a + b + c + …` (and the same for `*`, `min` and
//! `max`), as written or as exported by tools, is a chain as deep as it is
//! long; it becomes a balanced tree of the same operands in the same order.
//!
//! A chain is a tree of one associative op whose inner nodes are used only
//! by it. Only chains deeper than [`MAX_DEPTH`] are rebuilt, so formulas
//! as people write them keep their exact op order (and bits). The result
//! has the same real value and domain; for `+` and `*`, point values may
//! round differently (real-exact, as the module doc of `passes` allows),
//! `min`/`max` give the same value up to the sign of a zero tie. A balanced
//! tree has depth log2(n) instead of n: shorter dependency chains for the
//! evaluators, and no deep recursion anywhere downstream.

use super::terms::balanced;
use crate::ir::{BinaryOp, Builder, Function, Op, ValueId};

/// Chains deeper than this are rebuilt as balanced trees.
pub const MAX_DEPTH: usize = 32;

/// Rebuilds every chain deeper than [`MAX_DEPTH`] as a balanced tree.
pub fn balance_chains(f: &Function) -> Function {
    let mut uses = vec![0u32; f.ops.len()];
    for op in &f.ops {
        for a in op.operands() {
            uses[a.index()] = uses[a.index()].saturating_add(1);
        }
    }
    // Whether value v is an inner node of a chain of its own op: used once,
    // by an op of the same kind.
    let mut inner = vec![false; f.ops.len()];
    for op in &f.ops {
        if let Op::Binary(o, a, b) = *op
            && associative(o)
        {
            for x in [a, b] {
                let same = matches!(*f.op(x), Op::Binary(p, ..) if p == o);
                inner[x.index()] = same && uses[x.index()] == 1 && x != f.root;
            }
        }
    }
    let mut b = Builder::with_capacity(f.ops.len());
    let mut map: Vec<ValueId> = Vec::with_capacity(f.ops.len());
    let mut depth = vec![0usize; f.ops.len()];
    for (i, op) in f.ops.iter().enumerate() {
        let mut out = b.push(op.map_operands(|a| map[a.index()]));
        if let Op::Binary(o, l, r) = *op
            && associative(o)
        {
            let d = |x: ValueId| {
                if inner[x.index()] {
                    depth[x.index()]
                } else {
                    0
                }
            };
            depth[i] = 1 + d(l).max(d(r));
            if !inner[i] && depth[i] > MAX_DEPTH {
                let leaves = chain_leaves(f, ValueId(i as u32), o, &inner);
                let mapped: Vec<ValueId> = leaves.iter().map(|v| map[v.index()]).collect();
                out = balanced(&mut b, o, &mapped).unwrap_or(out);
            }
        }
        map.push(out);
    }
    b.finish(map[f.root.index()])
}

fn associative(op: BinaryOp) -> bool {
    matches!(
        op,
        BinaryOp::Add | BinaryOp::Mul | BinaryOp::Min | BinaryOp::Max
    )
}

/// The operands of the chain under `root`, left to right (an explicit
/// stack: chains may be millions of nodes long).
fn chain_leaves(f: &Function, root: ValueId, op: BinaryOp, inner: &[bool]) -> Vec<ValueId> {
    let mut leaves = Vec::new();
    let mut stack = vec![root];
    while let Some(v) = stack.pop() {
        match *f.op(v) {
            Op::Binary(o, l, r) if o == op && (v == root || inner[v.index()]) => {
                stack.push(r);
                stack.push(l);
            }
            _ => leaves.push(v),
        }
    }
    leaves
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::Var;
    use crate::ir::semantics::run_point;

    fn chain(op: BinaryOp, n: usize) -> Function {
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let mut s = b.constant(0.5);
        for i in 0..n {
            let c = b.constant(i as f64);
            let t = b.binary(BinaryOp::Sub, x, c);
            s = b.push(Op::Binary(op, s, t));
        }
        b.finish(s)
    }

    fn depth(f: &Function) -> usize {
        let mut d = vec![0usize; f.ops.len()];
        for (i, op) in f.ops.iter().enumerate() {
            d[i] = 1 + op.operands().map(|a| d[a.index()]).max().unwrap_or(0);
        }
        d[f.root.index()]
    }

    #[test]
    fn long_chains_become_shallow_with_the_same_min() {
        let f = chain(BinaryOp::Min, 3000);
        let g = balance_chains(&f);
        assert!(depth(&f) > 3000);
        assert!(depth(&g) <= 16, "depth {}", depth(&g));
        for x in [-5.0, 0.25, 1234.5, 4000.0] {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            run_point(&f.ops, [x, 0.0, 0.0], &mut a);
            run_point(&g.ops, [x, 0.0, 0.0], &mut b);
            assert_eq!(a[f.root.index()], b[g.root.index()]);
        }
    }

    #[test]
    fn short_chains_are_untouched() {
        let f = chain(BinaryOp::Add, MAX_DEPTH - 1);
        assert_eq!(balance_chains(&f), super::super::cse(&f));
    }
}
