//! Simplification passes: random functions keep their values, and the
//! specific rewrites happen.

use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::interval::Interval;
use ibeam::ir::passes::{PASSES, cse, dce, fold_constants, simplify, simplify_traced};
use ibeam::ir::random::{Rng, random_function};
use ibeam::ir::validate::validate;
use ibeam::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId, Var};

fn count(f: &Function, pred: impl Fn(&Op) -> bool) -> usize {
    f.ops.iter().filter(|op| pred(op)).count()
}

/// Whether the simplified value `b` of the original `a` at `p` is right:
/// both NaN, or within 1e-12 relative, or (where rounding differences were
/// amplified by cancellation, or a zero's sign flipped on a branch cut)
/// both functions' intervals over the point box overlap, which they must
/// since each contains the same real value.
fn agrees(orig: &Interpreter, simp: &Interpreter, p: [f64; 3]) -> bool {
    let (a, b) = (orig.point(p), simp.point(p));
    if a.is_nan() || b.is_nan() {
        return a.is_nan() && b.is_nan();
    }
    if a == b || (a - b).abs() <= 1e-12 * a.abs().max(b.abs()) {
        return true;
    }
    let pb = p.map(Interval::point);
    let (ia, ib) = (orig.interval(pb), simp.interval(pb));
    !ia.is_empty() && !ib.is_empty() && ia.lo <= ib.hi && ib.lo <= ia.hi
}

#[test]
fn random_functions_keep_their_values() {
    let mut rng = Rng::new(99);
    let mut shrunk = 0;
    let mut defined = 0;
    for seed in 0..400 {
        let f = random_function(seed, 10);
        let g = simplify(&f);
        validate(&g).unwrap();
        assert!(
            g.len() <= f.len(),
            "seed {seed}: simplify grew {} -> {}",
            f.len(),
            g.len()
        );
        if g.len() < f.len() {
            shrunk += 1;
        }
        let (a, b) = (Interpreter::new(f.clone()), Interpreter::new(g.clone()));
        for _ in 0..20 {
            let s = rng.pick(&[0.5, 2.0, 10.0]);
            let p = [rng.range(-s, s), rng.range(-s, s), rng.range(-s, s)];
            let p = if rng.chance(0.1) {
                [0.0, p[1], -0.0]
            } else {
                p
            };
            if a.point(p).is_finite() {
                defined += 1;
            }
            assert!(
                agrees(&a, &b, p),
                "seed {seed} at {p:?}: {:e} before, {:e} after\n{f:?}\n{g:?}",
                a.point(p),
                b.point(p)
            );
        }
    }
    assert!(
        shrunk > 100,
        "simplify shrank only {shrunk} of 400 functions"
    );
    assert!(
        defined > 2000,
        "only {defined} of 8000 points had a finite value"
    );
}

#[test]
fn simplify_is_idempotent_and_traced() {
    for seed in 0..200 {
        let f = random_function(seed, 10);
        let g = simplify(&f);
        assert_eq!(simplify(&g), g, "seed {seed}");
        let trace = simplify_traced(&f);
        assert_eq!(trace.last().map(|(_, h)| h), Some(&g));
        let names: Vec<_> = trace.iter().take(PASSES.len()).map(|(n, _)| *n).collect();
        let want: Vec<_> = PASSES.iter().map(|p| p.name).collect();
        assert_eq!(names, want);
        for (name, h) in &trace {
            validate(h).unwrap_or_else(|e| panic!("seed {seed} after {name}: {e}"));
        }
    }
}

fn x_chain(n: usize) -> (Builder, ValueId) {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let mut acc = x;
    for _ in 1..n {
        acc = b.binary(BinaryOp::Mul, acc, x);
    }
    (b, acc)
}

#[test]
fn products_become_powers() {
    let (b, r) = x_chain(2);
    let g = simplify(&b.finish(r));
    assert_eq!(g.op(g.root), &Op::Unary(UnaryOp::Square, ValueId(0)));

    let (b, r) = x_chain(4);
    let f = b.finish(r);
    let g = simplify(&f);
    assert_eq!(g.op(g.root), &Op::Powi(ValueId(0), 4));
    assert_eq!(g.len(), 2);
    // The point of it: x·x·x·x over [-1, 1] is [-1, 1], x⁴ is [0, 1].
    let bx = [
        Interval::new(-1.0, 1.0),
        Interval::point(0.0),
        Interval::point(0.0),
    ];
    let before = Interpreter::new(f).interval(bx);
    let after = Interpreter::new(g).interval(bx);
    assert!(before.lo <= -1.0);
    assert!(after.lo >= 0.0 && after.hi <= 1.0 + 1e-15);
}

#[test]
fn tangle_cube_gets_fourth_powers() {
    // x*x*x*x - 5*x*x + (the same in y and z) + 11.8
    let mut b = Builder::new();
    let five = b.constant(5.0);
    let mut acc = b.constant(11.8);
    for v in Var::ALL {
        let x = b.var(v);
        let x2 = b.binary(BinaryOp::Mul, x, x);
        let x3 = b.binary(BinaryOp::Mul, x2, x);
        let x4 = b.binary(BinaryOp::Mul, x3, x);
        let t = b.binary(BinaryOp::Mul, five, x);
        let t = b.binary(BinaryOp::Mul, t, x);
        let d = b.binary(BinaryOp::Sub, x4, t);
        acc = b.binary(BinaryOp::Add, acc, d);
    }
    let g = simplify(&b.finish(acc));
    assert_eq!(count(&g, |op| matches!(op, Op::Powi(_, 4))), 3);
    // 5·x·x becomes 5·x², tighter over boxes holding 0.
    assert_eq!(
        count(&g, |op| matches!(op, Op::Unary(UnaryOp::Square, _))),
        3
    );
    assert_eq!(
        count(&g, |op| matches!(op, Op::Binary(BinaryOp::Mul, ..))),
        3
    );
    let bx = [Interval::new(-0.1, 0.1); 3];
    let r = Interpreter::new(g).interval(bx);
    assert!(r.lo > 11.0 && r.hi < 11.81, "{r:?}");
}

#[test]
fn powers_of_powers_and_reciprocals() {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let s = b.unary(UnaryOp::Square, x);
    let s2 = b.unary(UnaryOp::Square, s);
    let one = b.constant(1.0);
    let r = b.binary(BinaryOp::Div, one, s2);
    let g = simplify(&b.finish(r));
    assert_eq!(g.op(g.root), &Op::Powi(ValueId(0), -4));

    let mut b = Builder::new();
    let x = b.var(Var::X);
    let p = b.powi(x, 2);
    let q = b.powi(x, 1);
    let z = b.powi(x, 0);
    let r = b.binary(BinaryOp::Add, p, q);
    let r = b.binary(BinaryOp::Add, r, z);
    let g = simplify(&b.finish(r));
    assert_eq!(count(&g, |op| matches!(op, Op::Powi(..))), 0);
    assert_eq!(
        count(&g, |op| matches!(op, Op::Unary(UnaryOp::Square, _))),
        1
    );
    assert!(g.ops.contains(&Op::Const(1.0)));
}

#[test]
fn identities_that_are_exact_apply_and_others_do_not() {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let zero = b.constant(0.0);
    let one = b.constant(1.0);
    let a = b.binary(BinaryOp::Add, x, zero);
    let m = b.binary(BinaryOp::Mul, a, one);
    let n = b.unary(UnaryOp::Neg, m);
    let n = b.unary(UnaryOp::Neg, n);
    let g = simplify(&b.finish(n));
    assert_eq!(g.ops, vec![Op::Var(Var::X)]);

    // x - x and x·0 change the domain (NaN, inf) and stay.
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let zero = b.constant(0.0);
    let d = b.binary(BinaryOp::Sub, x, x);
    let m = b.binary(BinaryOp::Mul, x, zero);
    let r = b.binary(BinaryOp::Add, d, m);
    let g = simplify(&b.finish(r));
    assert_eq!(g.len(), 5);

    // x / 4 becomes x · 0.25; x / 3 stays.
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let four = b.constant(4.0);
    let three = b.constant(3.0);
    let p = b.binary(BinaryOp::Div, x, four);
    let q = b.binary(BinaryOp::Div, x, three);
    let r = b.binary(BinaryOp::Add, p, q);
    let g = simplify(&b.finish(r));
    assert!(g.ops.contains(&Op::Const(0.25)));
    assert_eq!(
        count(&g, |op| matches!(op, Op::Binary(BinaryOp::Div, ..))),
        1
    );
}

#[test]
fn folds_exact_constants_only() {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let one = b.constant(1.0);
    let two = b.constant(2.0);
    let four = b.constant(4.0);
    let three = b.binary(BinaryOp::Add, one, two);
    let tenth = b.constant(0.1);
    let fifth = b.constant(0.2);
    let inexact = b.binary(BinaryOp::Add, tenth, fifth);
    let root2 = b.unary(UnaryOp::Sqrt, two);
    let root4 = b.unary(UnaryOp::Sqrt, four);
    let e = b.unary(UnaryOp::Exp, one);
    let r = b.binary(BinaryOp::Mul, three, x);
    let r = b.binary(BinaryOp::Add, r, inexact);
    let r = b.binary(BinaryOp::Add, r, root2);
    let r = b.binary(BinaryOp::Add, r, root4);
    let r = b.binary(BinaryOp::Add, r, e);
    let g = dce(&fold_constants(&b.finish(r)));
    validate(&g).unwrap();
    assert!(g.ops.contains(&Op::Const(3.0)));
    assert!(g.ops.contains(&Op::Const(2.0)));
    assert!(!g.ops.contains(&Op::Const(0.1 + 0.2)));
    assert_eq!(count(&g, |op| matches!(op, Op::Unary(UnaryOp::Sqrt, _))), 1);
    assert_eq!(count(&g, |op| matches!(op, Op::Unary(UnaryOp::Exp, _))), 1);
    assert_eq!(
        count(&g, |op| matches!(op, Op::Binary(BinaryOp::Add, ..))),
        5
    );
}

#[test]
fn dce_drops_dead_ops_and_renumbers() {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let y = b.var(Var::Y);
    let dead = b.unary(UnaryOp::Sin, y);
    let _dead2 = b.binary(BinaryOp::Mul, dead, x);
    let z = b.var(Var::Z);
    let r = b.binary(BinaryOp::Add, x, z);
    let f = b.finish(r);
    let g = dce(&f);
    assert_eq!(
        g.ops,
        vec![
            Op::Var(Var::X),
            Op::Var(Var::Z),
            Op::Binary(BinaryOp::Add, ValueId(0), ValueId(1))
        ]
    );
    assert_eq!(g.root, ValueId(2));
}

#[test]
fn cse_merges_duplicates_built_without_hash_consing() {
    // Two copies of sin(x) written directly into the op list.
    let f = Function {
        ops: vec![
            Op::Var(Var::X),
            Op::Unary(UnaryOp::Sin, ValueId(0)),
            Op::Unary(UnaryOp::Sin, ValueId(0)),
            Op::Binary(BinaryOp::Add, ValueId(2), ValueId(1)),
        ],
        root: ValueId(3),
    };
    let g = cse(&f);
    assert_eq!(g.len(), 3);
    assert_eq!(
        g.op(g.root),
        &Op::Binary(BinaryOp::Add, ValueId(1), ValueId(1))
    );
}
