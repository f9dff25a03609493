//! Simplification passes, each a function from IR to IR.
//!
//! Every pass takes a `&Function` and returns a new [`Function`]; none keeps
//! state between calls, and [`super::validate::debug_validate`] checks the result.
//! [`simplify`] runs the list [`PASSES`] to a fixed point.
//!
//! # What a pass may change
//! The guarantee of the tracer is about the *real* function f the source
//! formula denotes: its interval must contain f's real values. A pass may
//! therefore replace an expression by one with the same real value wherever
//! the original is defined, and *the same domain*: a rewrite that makes a
//! value defined where it was undefined (x·0 → 0 when x is NaN) could put a
//! surface where the source has none, so those are not applied. Rewrites
//! that are bit-exact in IEEE arithmetic keep point values identical; the
//! few that are exact in real arithmetic only (a chain of multiplications
//! becoming one `powi`) change the point value by a few ulps at most.
//!
//! One file per pass: [`fold`] (constant folding), [`identities`],
//! [`terms`] (collecting like terms), [`specialise`], [`balance`] (long
//! chains into balanced trees); CSE and DCE are short enough to live here.

mod balance;
mod fold;
mod identities;
mod specialise;
mod terms;

pub use balance::balance_chains;
pub use fold::fold_constants;
pub use identities::identities;
pub use specialise::specialise;
pub use terms::collect_terms;

use super::validate::debug_validate;
use super::{Builder, Function, Op, ValueId};

/// One named pass.
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    /// Its name in `ibeam ir --passes`.
    pub name: &'static str,
    /// The pass itself.
    pub run: fn(&Function) -> Function,
}

/// The passes [`simplify`] runs, in order.
pub const PASSES: &[Pass] = &[
    Pass {
        name: "fold",
        run: fold_constants,
    },
    Pass {
        name: "identities",
        run: identities,
    },
    Pass {
        name: "terms",
        run: collect_terms,
    },
    Pass {
        name: "specialise",
        run: specialise,
    },
    Pass {
        name: "cse",
        run: cse,
    },
    Pass {
        name: "balance",
        run: balance_chains,
    },
    Pass {
        name: "dce",
        run: dce,
    },
];

/// Most rounds of [`PASSES`] that [`simplify`] runs.
const MAX_ROUNDS: usize = 8;

/// Runs [`PASSES`] until the function stops changing (at most a few
/// rounds), then dead-code elimination.
pub fn simplify(f: &Function) -> Function {
    run_passes(f, |_, _| {})
}

/// The function after each pass [`simplify`] runs, in order (the last entry
/// is the result of `simplify`).
pub fn simplify_traced(f: &Function) -> Vec<(&'static str, Function)> {
    let mut trace: Vec<(&'static str, Function)> = Vec::new();
    run_passes(f, |name, g| trace.push((name, g.clone())));
    trace
}

// The rounds of [`simplify`], handing each pass's result to `seen` (a
// render keeps none of them, `ibeam ir` prints them all).
fn run_passes(f: &Function, mut seen: impl FnMut(&'static str, &Function)) -> Function {
    let mut cur = f.clone();
    for _ in 0..MAX_ROUNDS {
        let before = cur.clone();
        for p in PASSES {
            cur = (p.run)(&cur);
            debug_validate(&cur, p.name);
            seen(p.name, &cur);
        }
        if cur == before {
            break;
        }
    }
    // PASSES ends with DCE, so the result is already clean.
    cur
}

/// Rebuilds `f` op by op through a [`Builder`] (which merges identical
/// ops), letting `rule` choose the replacement of each op after its
/// operands were mapped.
fn rewrite(f: &Function, mut rule: impl FnMut(&mut Builder, Op) -> ValueId) -> Function {
    let mut b = Builder::with_capacity(f.ops.len());
    let mut map: Vec<ValueId> = Vec::with_capacity(f.ops.len());
    for op in &f.ops {
        let op = op.map_operands(|a| map[a.index()]);
        map.push(rule(&mut b, op));
    }
    b.finish(map[f.root.index()])
}

/// Common-subexpression elimination: the rebuild through [`Builder`] merges
/// identical ops (commutative operands in canonical order).
pub fn cse(f: &Function) -> Function {
    rewrite(f, |b, op| b.push(op))
}

/// Dead-code elimination: keeps only the ops the root reaches, renumbered
/// in their original order.
pub fn dce(f: &Function) -> Function {
    let mut live = vec![false; f.ops.len()];
    live[f.root.index()] = true;
    for i in (0..f.ops.len()).rev() {
        if live[i] {
            for a in f.ops[i].operands() {
                live[a.index()] = true;
            }
        }
    }
    let mut map = vec![ValueId(0); f.ops.len()];
    let mut ops = Vec::new();
    for (i, op) in f.ops.iter().enumerate() {
        if live[i] {
            map[i] = ValueId(ops.len() as u32);
            ops.push(op.map_operands(|a| map[a.index()]));
        }
    }
    Function {
        ops,
        root: map[f.root.index()],
    }
}
