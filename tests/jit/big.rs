//! Big functions: long chains, spilling, a prospero-sized model, integer
//! selects.

use super::*;

/// Builds `x·c₀ + y` repeated: a chain of `n` ops with distinct constants.
fn long_chain(n: usize) -> Function {
    let mut b = Builder::new();
    let (x, y) = (b.var(Var::X), b.var(Var::Y));
    let mut v = x;
    let mut i = 0;
    while b.len() < n {
        let c = b.constant(1.0 + (i as f64) * 1e-9);
        let m = b.binary(BinaryOp::Mul, v, c);
        v = b.binary(
            if i % 2 == 0 {
                BinaryOp::Add
            } else {
                BinaryOp::Sub
            },
            m,
            y,
        );
        v = b.binary(BinaryOp::Max, v, x);
        i += 1;
    }
    b.finish(v)
}

/// `width` values live at once (more than any register file), then summed
/// in reverse: exercises spilling.
pub fn wide(width: usize) -> Function {
    let mut b = Builder::new();
    let (x, y, z) = (b.var(Var::X), b.var(Var::Y), b.var(Var::Z));
    let mut vals = Vec::new();
    for i in 0..width {
        let c = b.constant(i as f64 * 0.01);
        let d = b.binary(BinaryOp::Sub, x, c);
        let d2 = b.unary(UnaryOp::Square, d);
        let e = b.binary(BinaryOp::Mul, d2, y);
        vals.push(b.binary(BinaryOp::Min, e, z));
    }
    let mut acc = vals.pop().unwrap();
    while let Some(v) = vals.pop() {
        acc = b.binary(BinaryOp::Add, acc, v);
    }
    b.finish(acc)
}

#[test]
fn a_100k_op_function_compiles_and_evaluates() {
    let f = long_chain(100_000);
    assert!(f.len() >= 100_000);
    let jit = JitEvaluator::new(&f).unwrap();
    let p = [0.3, -0.2, 0.1];
    assert!(same(jit.point(p), ref_point(&f, p)));
    // The interval kind of a quarter of it (compiling all 100k ops for both
    // kinds would exceed the test time budget in the dev profile).
    let g = long_chain(25_000);
    let jit = JitEvaluator::new(&g).unwrap();
    let bx = [
        Interval::new(0.25, 0.5),
        Interval::new(-0.25, 0.0),
        Interval::point(0.0),
    ];
    assert!(same_iv(jit.interval(bx), ref_interval(&g, bx)));
}

#[test]
fn many_live_values_spill_correctly() {
    let f = wide(400);
    let jit = JitEvaluator::new(&f).unwrap();
    let mut r = Rng::new(5);
    for _ in 0..20 {
        let p = random_point(&mut r);
        assert!(same(jit.point(p), ref_point(&f, p)));
        let bx = random_box(&mut r);
        assert!(same_iv(jit.interval(bx), ref_interval(&f, bx)));
        let g = jit.point_grad(p);
        let gw = ref_grad(&f, p);
        assert!((0..3).all(|k| same(g.d[k], gw.d[k])));
    }
    let bx = [
        Interval::new(0.0, 1.0),
        Interval::new(1.0, 2.0),
        Interval::new(-1.0, 1.0),
    ];
    jit.interval_grad(bx);
    assert_eq!(jit.compile_all().unwrap().len(), Kind::ALL.len());
}

/// Same op mix and size as the prospero model (7866 ops of
/// add/sub/mul/min/max/neg/square/sqrt over x and y).
fn prospero_like(seed: u64) -> Function {
    let mut r = Rng::new(seed);
    let mut b = Builder::new();
    let mut vals = vec![b.var(Var::X), b.var(Var::Y)];
    while b.len() < 7866 {
        let n = vals.len();
        let a = vals[n - 1 - r.below(n.min(40))];
        let c = vals[n - 1 - r.below(n.min(400))];
        let v = match r.below(10) {
            0 => b.constant(r.range(-5.0, 5.0)),
            1 => b.binary(BinaryOp::Add, a, c),
            2 => b.binary(BinaryOp::Sub, a, c),
            3 => b.binary(BinaryOp::Mul, a, c),
            4 | 5 => b.binary(BinaryOp::Max, a, c),
            6 => b.binary(BinaryOp::Min, a, c),
            7 => b.unary(UnaryOp::Neg, a),
            8 => b.unary(UnaryOp::Square, a),
            _ => b.unary(UnaryOp::Sqrt, a),
        };
        vals.push(v);
    }
    let root = *vals.last().unwrap();
    b.finish(root)
}

#[test]
fn a_prospero_sized_function_compiles_and_matches() {
    let f = prospero_like(3);
    let jit = JitEvaluator::new(&f).unwrap();
    let mut r = Rng::new(8);
    for _ in 0..50 {
        let p = [r.range(-1.0, 1.0), r.range(-1.0, 1.0), 0.0];
        assert!(same(jit.point(p), ref_point(&f, p)));
        let bx = [0, 1, 2].map(|_| {
            let a = r.range(-1.0, 1.0);
            Interval::new(a, a + 0.1)
        });
        assert!(same_iv(jit.interval(bx), ref_interval(&f, bx)));
    }
}

/// The sum of `n` random functions: big enough (≥ 500 live ops) that the
/// JIT switches to integer selects, with every op kind inside.
fn sum_of_random_functions(n: u64) -> Function {
    let mut b = Builder::new();
    let mut total: Option<ValueId> = None;
    for seed in 0..n {
        let f = random_function(1000 + seed, 8);
        let mut ids: Vec<ValueId> = Vec::with_capacity(f.ops.len());
        for op in &f.ops {
            let m = |v: ValueId| ids[v.index()];
            let id = match *op {
                Op::Var(v) => b.var(v),
                Op::Const(c) => b.constant(c),
                Op::Unary(u, a) => b.unary(u, m(a)),
                Op::Binary(o, x, y) => b.binary(o, m(x), m(y)),
                Op::Powi(a, k) => b.powi(m(a), k),
            };
            ids.push(id);
        }
        let r = ids[f.root.index()];
        total = Some(match total {
            None => r,
            Some(t) => b.binary(BinaryOp::Add, t, r),
        });
    }
    b.finish(total.expect("n > 0"))
}

/// A large function (integer selects) agrees with the interpreter bit for
/// bit on random and edge boxes and points.
#[test]
fn large_functions_use_integer_selects_and_match() {
    let f = sum_of_random_functions(60);
    assert!(f.len() >= 600, "{} ops", f.len());
    let jit = JitEvaluator::new(&f).unwrap();
    let interp = Interpreter::new(f.clone());
    let mut r = Rng::new(31);
    let ivs = edge_intervals();
    for i in 0..300 {
        let bx = if i < 100 {
            [0, 1, 2].map(|_| ivs[r.below(ivs.len())])
        } else {
            random_box(&mut r)
        };
        let (got, want) = (jit.interval(bx), Single::interval(&interp, bx));
        assert!(same_iv(got, want), "{bx:?}: {got:?} vs {want:?}");
        let p = random_point(&mut r);
        let (got, want) = (jit.point(p), Single::point(&interp, p));
        assert!(same(got, want), "{p:?}: {got:e} vs {want:e}");
    }
}
