//! The JIT against the reference interpreter: the shared evaluator
//! conformance suite (tests/common), every op on edge arguments, random
//! functions, gradients, batches, big functions and laziness.

mod common;

use ibeam::eval::interp::Interpreter;
use ibeam::eval::jit::{JitEvaluator, Kind, clif_text};
use ibeam::eval::{Evaluator, Grad, IntervalGrad};
use ibeam::interval::Interval;
use ibeam::ir::random::{BINARY_OPS as BINARY, Rng, UNARY_OPS as UNARY, random_function};
use ibeam::ir::semantics::{point_binary, point_powi, point_unary};
use ibeam::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId, Var};

fn make(f: &Function) -> Box<dyn Evaluator> {
    Box::new(JitEvaluator::new(f).expect("compiles"))
}

#[test]
fn conformance_point_ops() {
    common::check_point_ops(&make);
}

#[test]
fn conformance_interval_ops() {
    common::check_interval_ops(&make);
}

#[test]
fn conformance_grad_ops() {
    common::check_grad_ops(&make);
}

#[test]
fn conformance_random_functions() {
    common::check_random_functions(&make, 0..300);
}

// The reference is the interpreter; the random functions are those of
// `ir::random`, shared with the interpreter's own tests.

fn ref_point(f: &Function, p: [f64; 3]) -> f64 {
    Evaluator::point(&Interpreter::new(f.clone()), p)
}

/// Every op's point value.
fn ref_point_all(f: &Function, p: [f64; 3]) -> Vec<f64> {
    Interpreter::new(f.clone()).point_values(p)
}

fn ref_interval(f: &Function, b: [Interval; 3]) -> Interval {
    Evaluator::interval(&Interpreter::new(f.clone()), b)
}

/// Forward-mode gradient with the JIT's derivative rules, written
/// independently (partials that are exactly zero are `None`).
fn ref_grad(f: &Function, p: [f64; 3]) -> Grad {
    type D = [Option<f64>; 3];
    let mut v: Vec<(f64, D)> = Vec::with_capacity(f.ops.len());
    let map = |d: D, g: &dyn Fn(f64) -> f64| d.map(|x| x.map(g));
    for op in &f.ops {
        let r = match *op {
            Op::Var(x) => {
                let mut d = [None; 3];
                d[x.index()] = Some(1.0);
                (p[x.index()], d)
            }
            Op::Const(c) => (c, [None; 3]),
            Op::Unary(u, a) => {
                let (a, da) = v[a.index()];
                let val = point_unary(u, a);
                let d = match u {
                    UnaryOp::Neg => map(da, &|x| -x),
                    UnaryOp::Abs => map(da, &|x| if a < 0.0 { -x } else { x }),
                    UnaryOp::Square => map(da, &|x| (a + a) * x),
                    UnaryOp::Sqrt => map(da, &|x| x / (val + val)),
                    UnaryOp::Exp => map(da, &|x| val * x),
                    UnaryOp::Ln => map(da, &|x| x / a),
                    UnaryOp::Sin => map(da, &|x| point_unary(UnaryOp::Cos, a) * x),
                    UnaryOp::Cos => map(da, &|x| -(point_unary(UnaryOp::Sin, a) * x)),
                };
                (val, d)
            }
            Op::Binary(op, x, y) => {
                let ((a, da), (b, db)) = (v[x.index()], v[y.index()]);
                let val = point_binary(op, a, b);
                let mut d = [None; 3];
                for k in 0..3 {
                    if da[k].is_none() && db[k].is_none() {
                        continue;
                    }
                    let sum = |l: Option<f64>, r: Option<f64>| match (l, r) {
                        (Some(l), Some(r)) => l + r,
                        (Some(x), None) | (None, Some(x)) => x,
                        (None, None) => 0.0,
                    };
                    let (xa, xb) = (da[k], db[k]);
                    let (za, zb) = (xa.unwrap_or(0.0), xb.unwrap_or(0.0));
                    d[k] = Some(match op {
                        BinaryOp::Add => sum(xa, xb),
                        BinaryOp::Sub => match (xa, xb) {
                            (Some(x), Some(y)) => x - y,
                            (Some(x), None) => x,
                            (None, y) => -y.unwrap_or(0.0),
                        },
                        BinaryOp::Mul => sum(xa.map(|x| x * b), xb.map(|y| a * y)),
                        BinaryOp::Div => {
                            let n = match (xa, xb) {
                                (Some(x), Some(y)) => x - val * y,
                                (Some(x), None) => x,
                                (None, y) => -(val * y.unwrap_or(0.0)),
                            };
                            n / b
                        }
                        BinaryOp::Min => {
                            if a < b {
                                za
                            } else {
                                zb
                            }
                        }
                        BinaryOp::Max => {
                            if a > b {
                                za
                            } else {
                                zb
                            }
                        }
                        BinaryOp::Atan2 => {
                            let (l, r) = (xa.map(|x| b * x), xb.map(|y| a * y));
                            let n = match (l, r) {
                                (Some(l), Some(r)) => l - r,
                                (Some(l), None) => l,
                                (None, r) => -r.unwrap_or(0.0),
                            };
                            n / (a * a + b * b)
                        }
                        BinaryOp::Pow => {
                            let l = xb.map(|y| y * point_unary(UnaryOp::Ln, a));
                            let r = xa.map(|x| b * (x / a));
                            val * sum(l, r)
                        }
                    });
                }
                (val, d)
            }
            Op::Powi(a, n) => {
                let (a, da) = v[a.index()];
                let val = point_powi(a, n);
                let d = match n {
                    0 => [None; 3],
                    1 => da,
                    _ => {
                        let k = f64::from(n) * point_powi(a, n - 1);
                        map(da, &|x| k * x)
                    }
                };
                (val, d)
            }
        };
        v.push(r);
    }
    let (val, d) = v[f.root.index()];
    Grad {
        v: val,
        d: d.map(|x| x.unwrap_or(0.0)),
    }
}

// ---------------------------------------------------------------------------

/// Equal bits, or both NaN (NaN payloads are not part of the semantics).
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Equal bits, or finite and within a few ulps (relative 1e-12).
fn close(a: f64, b: f64) -> bool {
    same(a, b) || (a.is_finite() && b.is_finite() && (a - b).abs() <= 1e-12 * a.abs().max(b.abs()))
}

fn same_iv(a: Interval, b: Interval) -> bool {
    same(a.lo, b.lo) && same(a.hi, b.hi)
}

fn one_op(op: Op) -> Function {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let y = b.var(Var::Y);
    let r = match op {
        Op::Unary(u, _) => b.unary(u, x),
        Op::Binary(o, _, _) => b.binary(o, x, y),
        Op::Powi(_, n) => b.powi(x, n),
        other => b.push(other),
    };
    b.finish(r)
}

const EDGE: [f64; 16] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    -2.5,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    1e308,
    -1e308,
    f64::MAX,
    f64::MIN_POSITIVE,
    5e-324,
    -5e-324,
    std::f64::consts::PI,
];

fn edge_intervals() -> Vec<Interval> {
    let mut v = vec![
        Interval::EMPTY,
        Interval::ENTIRE,
        Interval::new(0.0, 0.0),
        Interval::new(-0.0, -0.0),
        Interval::new(-0.0, 0.0),
        Interval::new(0.0, 1.0),
        Interval::new(-1.0, 0.0),
        Interval::new(-1.0, 2.0),
        Interval::new(1.0, 2.0),
        Interval::new(-3.0, -0.5),
        Interval::new(0.0, f64::INFINITY),
        Interval::new(f64::NEG_INFINITY, 0.0),
        Interval::new(f64::NEG_INFINITY, -1.0),
        Interval::new(1e300, 1e308),
        Interval::new(-f64::MAX, f64::MAX),
        Interval::new(5e-324, 5e-324),
        Interval::new(-5e-324, 5e-324),
        Interval::new(f64::INFINITY, f64::INFINITY),
        Interval::new(-2.0, f64::INFINITY),
    ];
    for &c in &[0.5, -2.5, std::f64::consts::PI] {
        v.push(Interval::point(c));
    }
    v
}

fn all_ops() -> Vec<Op> {
    let mut ops: Vec<Op> = UNARY.iter().map(|&u| Op::Unary(u, ValueId(0))).collect();
    ops.extend(
        BINARY
            .iter()
            .map(|&b| Op::Binary(b, ValueId(0), ValueId(1))),
    );
    for n in [
        -17,
        -4,
        -3,
        -2,
        -1,
        0,
        1,
        2,
        3,
        4,
        5,
        8,
        13,
        64,
        i32::MAX,
        i32::MIN,
    ] {
        ops.push(Op::Powi(ValueId(0), n));
    }
    ops
}

#[test]
fn every_op_on_edge_points_is_bit_exact() {
    for op in all_ops() {
        let f = one_op(op);
        let jit = JitEvaluator::new(&f).unwrap();
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for &x in &EDGE {
            for &y in &EDGE {
                let p = [x, y, 0.0];
                let (got, want) = (jit.point(p), ref_point(&f, p));
                assert!(
                    same(got, want),
                    "{op:?} at {p:?}: jit {got:e}, ref {want:e}"
                );
                xs.push(x);
                ys.push(y);
            }
        }
        let zs = vec![0.0; xs.len()];
        let mut out = vec![0.0; xs.len()];
        jit.point_batch(&xs, &ys, &zs, &mut out);
        for i in 0..xs.len() {
            assert!(same(out[i], jit.point([xs[i], ys[i], 0.0])), "{op:?} batch");
        }
    }
}

#[test]
fn every_op_on_edge_intervals_is_bit_exact() {
    let ivs = edge_intervals();
    for op in all_ops() {
        let f = one_op(op);
        let jit = JitEvaluator::new(&f).unwrap();
        let mut boxes = Vec::new();
        for &a in &ivs {
            for &b in &ivs {
                let bx = [a, b, Interval::point(0.0)];
                let (got, want) = (jit.interval(bx), ref_interval(&f, bx));
                assert!(
                    same_iv(got, want),
                    "{op:?} on {a:?}, {b:?}: jit {got:?}, ref {want:?}"
                );
                boxes.push(bx);
            }
        }
        let mut out = vec![Interval::point(7.0); boxes.len()];
        jit.interval_batch(&boxes, &mut out);
        for (bx, o) in boxes.iter().zip(&out) {
            assert!(same_iv(*o, jit.interval(*bx)), "{op:?} batch on {bx:?}");
        }
    }
}

/// Ops whose interval result must hold the point result at every point of
/// the box where that result is finite.
#[test]
fn every_op_contains_its_points_on_edge_boxes() {
    let ivs = edge_intervals();
    let mut r = Rng::new(7);
    for op in all_ops() {
        let f = one_op(op);
        let jit = JitEvaluator::new(&f).unwrap();
        for &a in &ivs {
            for &b in &ivs {
                let got = jit.interval([a, b, Interval::point(0.0)]);
                for _ in 0..4 {
                    let p = [sample(&mut r, a), sample(&mut r, b), 0.0];
                    let v = ref_point(&f, p);
                    if v.is_finite() && p.iter().all(|c| c.is_finite()) {
                        assert!(
                            got.contains(v),
                            "{op:?} on {a:?},{b:?}: {got:?} lacks f{p:?} = {v:e}"
                        );
                    }
                }
            }
        }
    }
}

/// A point of the interval (bounds and zero included often); NaN if empty.
fn sample(r: &mut Rng, a: Interval) -> f64 {
    if a.is_empty() {
        return f64::NAN;
    }
    let lo = a.lo.max(-1e300);
    let hi = a.hi.min(1e300);
    match r.below(6) {
        0 if a.lo.is_finite() => a.lo,
        1 if a.hi.is_finite() => a.hi,
        2 if a.contains(0.0) => 0.0,
        _ if lo <= hi => r.range(lo, hi).clamp(lo, hi),
        _ => a.lo,
    }
}

fn random_box(r: &mut Rng) -> [Interval; 3] {
    [0, 1, 2].map(|_| {
        let a = r.range(-4.0, 4.0);
        match r.below(12) {
            0 => Interval::point(a),
            1 => Interval::new(a, f64::INFINITY),
            2 => Interval::new(-0.0, r.range(0.0, 1.0)),
            _ => {
                let w = r.range(0.0, 2.0) * r.unit();
                Interval::new(a, a + w)
            }
        }
    })
}

fn random_point(r: &mut Rng) -> [f64; 3] {
    [0, 1, 2].map(|_| match r.below(20) {
        0 => EDGE[r.below(EDGE.len())],
        _ => r.range(-4.0, 4.0),
    })
}

/// `[0, 0]` times an interval with only infinite bounds: every bound
/// product is 0·inf (NaN), yet every real product is 0: the result is
/// [0, 0] rounded outward, as the reference gives.
#[test]
fn zero_times_unbounded_is_zero() {
    let f = one_op(Op::Binary(BinaryOp::Mul, ValueId(0), ValueId(1)));
    let jit = JitEvaluator::new(&f).unwrap();
    let z = Interval::point(0.0);
    for (a, b) in [(z, Interval::ENTIRE), (Interval::ENTIRE, z)] {
        let got = jit.interval([a, b, z]);
        assert!(same_iv(got, a.mul(b)), "{got:?}");
        assert!(got.contains(0.0) && got.width() < 1e-300, "{got:?}");
    }
    assert!(jit.interval([Interval::EMPTY, z, z]).is_empty());
    let (a, b) = (Interval::new(-0.0, 0.0), Interval::new(1.0, f64::INFINITY));
    assert!(same_iv(jit.interval([a, b, z]), a.mul(b)));
}

/// A quotient bound of -0 (from `next_up` of the smallest negative
/// subnormal) is reported as +0 by both the reference and the JIT, in debug
/// and release builds alike (`f64::min` picks either zero).
#[test]
fn half_line_quotient_bound_is_plus_zero() {
    let f = one_op(Op::Binary(BinaryOp::Div, ValueId(0), ValueId(1)));
    let jit = JitEvaluator::new(&f).unwrap();
    let (a, b) = (Interval::point(5e-324), Interval::new(-1.0, 0.0));
    let want = Interval::new(f64::NEG_INFINITY, 0.0);
    assert_eq!(a.div(b).hi.to_bits(), 0.0f64.to_bits());
    let got = jit.interval([a, b, Interval::point(0.0)]);
    assert!(same_iv(got, want), "{got:?}");
}

#[test]
fn random_functions_points_intervals_gradients() {
    let mut r = Rng::new(12345);
    let (mut points, mut boxes) = (0, 0);
    let mut compared = 0;
    for seed in 0..60 {
        let f = random_function(seed, 12);
        let jit = JitEvaluator::new(&f).unwrap();
        let interp = Interpreter::new(f.clone());
        for _ in 0..100 {
            let p = random_point(&mut r);
            let (got, want) = (jit.point(p), ref_point(&f, p));
            assert!(
                same(got, want),
                "seed {seed} at {p:?}: jit {got:e}, ref {want:e}"
            );
            let (g, gw) = (jit.point_grad(p), ref_grad(&f, p));
            assert!(same(g.v, got), "seed {seed}: grad value differs from point");
            let gi = interp.point_grad(p);
            let finite = interp.point_values(p).iter().all(|v| v.is_finite());
            for k in 0..3 {
                assert!(
                    same(g.d[k], gw.d[k]),
                    "seed {seed} at {p:?}: d{k} {g:?} vs {gw:?}"
                );
                // The interpreter's gradient rules round in a different
                // order and turn a numerically zero partial times an
                // infinite derivative into 0 (the JIT: NaN), so compare
                // where every value and both partials are finite.
                if finite && g.d[k].is_finite() && gi.d[k].is_finite() {
                    assert!(
                        close(g.d[k], gi.d[k]),
                        "seed {seed} at {p:?}: d{k} {g:?} vs interpreter {gi:?}"
                    );
                    compared += 1;
                }
            }
            points += 1;
        }
        for _ in 0..100 {
            let bx = random_box(&mut r);
            let (got, want) = (jit.interval(bx), ref_interval(&f, bx));
            assert!(
                same_iv(got, want),
                "seed {seed} on {bx:?}: {got:?} vs {want:?}"
            );
            let ig = jit.interval_grad(bx);
            assert!(
                same_iv(ig.v, got),
                "seed {seed}: interval_grad value differs"
            );
            for _ in 0..4 {
                let p = [0, 1, 2].map(|k| sample(&mut r, bx[k]));
                check_contains(&f, &jit, bx, ig, got, p, seed);
            }
            boxes += 1;
        }
    }
    assert!(points + boxes >= 10_000);
    assert!(compared >= 1000, "only {compared} partials compared");
}

/// The directional kind (one forward-mode partial seeded with v) of the
/// JIT and of the interpreter: its value is the interval kind's, bit for
/// bit, and its derivative holds ∇f·v at points of the box (up to the
/// rounding of that point sum), as the full interval gradient does.
#[test]
fn directional_derivatives_hold_the_point_gradient() {
    let mut r = Rng::new(777);
    let mut checked = 0;
    for seed in 0..60 {
        let f = random_function(seed, 12);
        let jit = JitEvaluator::new(&f).unwrap();
        let interp = Interpreter::new(f.clone());
        for _ in 0..40 {
            let bx = random_box(&mut r);
            let v = [0, 1, 2].map(|_| Interval::point(r.range(-2.0, 2.0)));
            let [jv, jd] = jit.interval_dir(bx, v);
            let [iv, id] = interp.interval_dir(bx, v);
            assert!(same_iv(jv, jit.interval(bx)), "seed {seed}: value {jv:?}");
            assert!(
                same_iv(iv, interp.interval(bx)),
                "seed {seed}: value {iv:?}"
            );
            for _ in 0..4 {
                let p = [0, 1, 2].map(|k| sample(&mut r, bx[k]));
                if !interp.point_values(p).iter().all(|x| x.is_finite()) {
                    continue;
                }
                // The JIT's point rules pick the same one-sided derivative
                // at a kink (|x| at 0) as the interval rules.
                let g = jit.point_grad(p);
                let terms = [0, 1, 2].map(|k| g.d[k] * v[k].lo);
                let s: f64 = terms.iter().sum();
                if !s.is_finite() {
                    continue;
                }
                let tol = 1e-9 * terms.iter().map(|t| t.abs()).sum::<f64>();
                for (who, d) in [("jit", jd), ("interp", id)] {
                    assert!(
                        d.lo - tol <= s && s <= d.hi + tol,
                        "seed {seed} {who}: {d:?} lacks ∇f·v = {s:e} at {p:?} of {bx:?}"
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked >= 2000, "only {checked} points checked");
}

fn check_contains(
    f: &Function,
    jit: &JitEvaluator,
    bx: [Interval; 3],
    ig: IntervalGrad,
    iv: Interval,
    p: [f64; 3],
    seed: u64,
) {
    // The guarantee is per op: it composes where every intermediate value
    // is real (an infinite intermediate, e.g. x/0, is outside the domain).
    let all = ref_point_all(f, p);
    let v = all[f.root.index()];
    if !all.iter().all(|x| x.is_finite()) {
        return;
    }
    assert!(
        iv.contains(v),
        "seed {seed}: {iv:?} lacks f{p:?} = {v:e}: {}",
        first_uncontained(f, bx, p)
    );
    let g = jit.point_grad(p);
    for k in 0..3 {
        if g.d[k].is_finite() {
            assert!(
                ig.d[k].contains(g.d[k]),
                "seed {seed}: d{k} {:?} lacks {:e} at {p:?}",
                ig.d[k],
                g.d[k]
            );
        }
    }
}

/// f = sin(x)·y² + exp(x/4) − sqrt(x² + z² + 1) + atan2(y, x+3) + pow(z²+1, y/3),
/// smooth everywhere: gradients checked against central differences.
#[test]
fn gradients_match_finite_differences() {
    let mut b = Builder::new();
    let (x, y, z) = (b.var(Var::X), b.var(Var::Y), b.var(Var::Z));
    let sx = b.unary(UnaryOp::Sin, x);
    let y2 = b.unary(UnaryOp::Square, y);
    let t1 = b.binary(BinaryOp::Mul, sx, y2);
    let four = b.constant(4.0);
    let x4 = b.binary(BinaryOp::Div, x, four);
    let t2 = b.unary(UnaryOp::Exp, x4);
    let x2 = b.powi(x, 2);
    let z2 = b.unary(UnaryOp::Square, z);
    let one = b.constant(1.0);
    let s = b.binary(BinaryOp::Add, x2, z2);
    let s = b.binary(BinaryOp::Add, s, one);
    let t3 = b.unary(UnaryOp::Sqrt, s);
    let three = b.constant(3.0);
    let xp3 = b.binary(BinaryOp::Add, x, three);
    let t4 = b.binary(BinaryOp::Atan2, y, xp3);
    let zb = b.binary(BinaryOp::Add, z2, one);
    let y3 = b.binary(BinaryOp::Div, y, three);
    let t5 = b.binary(BinaryOp::Pow, zb, y3);
    let c = b.unary(UnaryOp::Cos, z);
    let l = b.unary(UnaryOp::Ln, zb);
    let t6 = b.binary(BinaryOp::Mul, c, l);
    let r = b.binary(BinaryOp::Add, t1, t2);
    let r = b.binary(BinaryOp::Sub, r, t3);
    let r = b.binary(BinaryOp::Add, r, t4);
    let r = b.binary(BinaryOp::Add, r, t5);
    let r = b.binary(BinaryOp::Add, r, t6);
    let f = b.finish(r);
    let jit = JitEvaluator::new(&f).unwrap();
    let mut rng = Rng::new(99);
    for _ in 0..200 {
        let p = [
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
        ];
        let g = jit.point_grad(p);
        let gw = ref_grad(&f, p);
        for k in 0..3 {
            let h = 1e-6;
            let (mut a, mut c) = (p, p);
            a[k] += h;
            c[k] -= h;
            let fd = (jit.point(a) - jit.point(c)) / (2.0 * h);
            assert!(
                (g.d[k] - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                "d{k} at {p:?}: {} vs {fd}",
                g.d[k]
            );
            assert!(same(g.d[k], gw.d[k]));
        }
    }
}

#[test]
fn min_max_abs_gradients_follow_the_chosen_branch() {
    let mut b = Builder::new();
    let (x, y) = (b.var(Var::X), b.var(Var::Y));
    let two = b.constant(2.0);
    let y2 = b.binary(BinaryOp::Mul, two, y);
    let m = b.binary(BinaryOp::Min, x, y2);
    let a = b.unary(UnaryOp::Abs, m);
    let f = b.finish(a);
    let jit = JitEvaluator::new(&f).unwrap();
    // min picks x (x < 2y), x < 0: d = (-1, 0, 0).
    assert_eq!(jit.point_grad([-1.0, 3.0, 0.0]).d, [-1.0, 0.0, 0.0]);
    // min picks 2y (tie goes to the second operand), 2y > 0: d = (0, 2, 0).
    assert_eq!(jit.point_grad([2.0, 1.0, 0.0]).d, [0.0, 2.0, 0.0]);
    // Over a box where the branch is uncertain, the hull of both.
    let ig = jit.interval_grad([
        Interval::new(1.0, 3.0),
        Interval::new(0.5, 1.0),
        Interval::point(0.0),
    ]);
    assert!(ig.d[0].contains(0.0) && ig.d[0].contains(1.0));
    assert!(ig.d[1].contains(0.0) && ig.d[1].contains(2.0));
    assert_eq!(ig.d[2], Interval::point(0.0));
}

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
fn wide(width: usize) -> Function {
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

#[test]
fn kinds_compile_lazily() {
    let f = random_function(4, 6);
    let jit = JitEvaluator::new(&f).unwrap();
    assert!(jit.compile_times().is_empty());
    jit.point([1.0, 2.0, 3.0]);
    let names: Vec<_> = jit.compile_times().into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["point"]);
    jit.interval([Interval::point(1.0); 3]);
    let names: Vec<_> = jit.compile_times().into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["point", "interval"]);
    jit.compile(Kind::IntervalBatch).unwrap();
    assert_eq!(jit.compile_times().len(), 3);
}

#[test]
fn batches_equal_single_calls() {
    let mut r = Rng::new(77);
    for seed in 100..110 {
        let f = random_function(seed, 10);
        let jit = JitEvaluator::new(&f).unwrap();
        let n = 257;
        let pts: Vec<[f64; 3]> = (0..n).map(|_| random_point(&mut r)).collect();
        let (xs, ys, zs): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            pts.iter().map(|p| p[0]).collect(),
            pts.iter().map(|p| p[1]).collect(),
            pts.iter().map(|p| p[2]).collect(),
        );
        let mut out = vec![0.0; n];
        jit.point_batch(&xs, &ys, &zs, &mut out);
        for (p, o) in pts.iter().zip(&out) {
            assert!(same(*o, jit.point(*p)));
        }
        let boxes: Vec<[Interval; 3]> = (0..n).map(|_| random_box(&mut r)).collect();
        let mut iout = vec![Interval::EMPTY; n];
        jit.interval_batch(&boxes, &mut iout);
        for (b, o) in boxes.iter().zip(&iout) {
            assert!(same_iv(*o, jit.interval(*b)));
        }
        // Mismatched lengths: only the common prefix is written.
        let mut short = vec![-1.0; 5];
        jit.point_batch(&xs[..3], &ys, &zs, &mut short);
        assert!(same(short[2], jit.point(pts[2])));
        assert_eq!(short[3], -1.0);
        jit.point_batch(&[], &[], &[], &mut []);
        jit.interval_batch(&[], &mut []);
    }
}

#[test]
fn transcendental_shims_pass_intervals_in_order() {
    // With any sound transcendental bounds, exp over a box is non-empty and
    // ordered, and the JIT returns exactly what the Rust method returns.
    for op in [UnaryOp::Exp, UnaryOp::Ln, UnaryOp::Sin, UnaryOp::Cos] {
        let f = one_op(Op::Unary(op, ValueId(0)));
        let jit = JitEvaluator::new(&f).unwrap();
        for a in edge_intervals() {
            let got = jit.interval([a, Interval::point(0.0), Interval::point(0.0)]);
            assert!(same_iv(
                got,
                ref_interval(&f, [a, Interval::point(0.0), Interval::point(0.0)])
            ));
            assert!(
                got.is_empty() || got.lo <= got.hi,
                "{op:?} on {a:?}: {got:?}"
            );
        }
    }
    let f = one_op(Op::Binary(BinaryOp::Atan2, ValueId(0), ValueId(1)));
    let jit = JitEvaluator::new(&f).unwrap();
    let b = [
        Interval::new(1.0, 2.0),
        Interval::new(-3.0, -1.0),
        Interval::point(0.0),
    ];
    let got = jit.interval(b);
    assert!(same_iv(got, ref_interval(&f, b)));
    assert!(got.contains(libm::atan2(1.5, -2.0)));
}

#[test]
fn evaluator_is_shared_across_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<JitEvaluator>();
    let f = random_function(9, 8);
    let jit = JitEvaluator::new(&f).unwrap();
    std::thread::scope(|s| {
        for t in 0..4 {
            let (jit, f) = (&jit, &f);
            s.spawn(move || {
                let mut r = Rng::new(t + 1);
                for _ in 0..200 {
                    let p = random_point(&mut r);
                    assert!(same(jit.point(p), ref_point(f, p)));
                }
            });
        }
    });
    assert_eq!(jit.compile_times().len(), 1);
}

#[test]
fn clif_text_lists_every_kind_and_invalid_ir_is_an_error() {
    let f = random_function(2, 5);
    let text = clif_text(&f).unwrap();
    for k in Kind::ALL {
        assert!(
            text.contains(&format!("; evaluator: {}\n", k.name())),
            "{k:?}"
        );
    }
    assert!(text.contains("function"));
    let bad = Function {
        ops: vec![Op::Unary(UnaryOp::Neg, ValueId(3))],
        root: ValueId(0),
    };
    let err = JitEvaluator::new(&bad).err().expect("invalid IR rejected");
    assert!(err.to_string().contains("invalid IR"));
    assert!(clif_text(&bad).is_err());
}

/// For a failure message: the first op whose reference interval over `bx`
/// misses its finite reference point value at `p`.
fn first_uncontained(f: &Function, bx: [Interval; 3], p: [f64; 3]) -> String {
    for i in 0..f.ops.len() {
        let g = Function {
            ops: f.ops[..=i].to_vec(),
            root: ValueId(i as u32),
        };
        let (iv, v) = (ref_interval(&g, bx), ref_point(&g, p));
        if v.is_finite() && !iv.contains(v) {
            let args: Vec<String> = f.ops[i]
                .operands()
                .map(|a| {
                    let h = Function {
                        ops: f.ops[..=a.index()].to_vec(),
                        root: a,
                    };
                    format!("{:?} ∋? {:e}", ref_interval(&h, bx), ref_point(&h, p))
                })
                .collect();
            return format!(
                "op v{i} = {:?}: {iv:?} lacks {v:e}; operands {args:?}",
                f.ops[i]
            );
        }
    }
    "no single op to blame".into()
}

/// Compile times of each kind for the big test functions (run with
/// `--ignored --nocapture`, ideally in release).
#[test]
#[ignore]
fn print_compile_times() {
    for (name, f) in [("wide100", wide(100))] {
        let jit = JitEvaluator::new(&f).unwrap();
        for k in Kind::ALL {
            let t = std::time::Instant::now();
            jit.compile(k).unwrap();
            println!("{name} ({} ops) {}: {:?}", f.len(), k.name(), t.elapsed());
        }
    }
}

/// The prospero model through the crate's own `.vm` importer, simplified
/// as the CLI does; `None` when `../shared` is not beside the checkout.
fn prospero() -> Option<Function> {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models/prospero.vm");
    let scene = ibeam::lang::load_scene(&path).ok()?;
    Some(ibeam::ir::passes::simplify(&scene.objects[0].function))
}

/// Compile times and speed on ../shared/models/prospero.vm (run with
/// `cargo test --release --test jit -- --ignored prospero --nocapture`).
#[test]
#[ignore]
fn prospero_timing() {
    let f = prospero().expect("../shared/models/prospero.vm loads");
    let clif = clif_text(&f).unwrap();
    for part in clif.split("; evaluator: ").skip(1) {
        let name = part.lines().next().unwrap_or("");
        println!("{name}: {} CLIF lines", part.lines().count());
    }
    let jit = JitEvaluator::new(&f).unwrap();
    for k in Kind::ALL {
        let t = std::time::Instant::now();
        jit.compile(k).unwrap();
        println!("prospero ({} ops) {}: {:?}", f.len(), k.name(), t.elapsed());
    }
}

/// Evaluation speed of the JIT against the interpreter, on prospero (run in release
/// with `--ignored prospero_speed --nocapture`).
#[test]
#[ignore]
fn prospero_speed() {
    let f = prospero().expect("../shared/models/prospero.vm loads");
    let jit = JitEvaluator::new(&f).unwrap();
    let n = 20_000;
    let mut r = Rng::new(1);
    let pts: Vec<[f64; 3]> = (0..n)
        .map(|_| [r.range(-1.0, 1.0), r.range(-1.0, 1.0), 0.0])
        .collect();
    let bxs: Vec<[Interval; 3]> = pts
        .iter()
        .map(|p| p.map(|c| Interval::new(c, c + 1.0 / 64.0)))
        .collect();
    let time = |name: &str, g: &mut dyn FnMut() -> f64| {
        let t = std::time::Instant::now();
        let s = g();
        let dt = t.elapsed();
        println!(
            "{name}: {:.1} ns/eval (checksum {s:e})",
            dt.as_nanos() as f64 / n as f64
        );
        dt
    };
    let interp = Interpreter::new(f.clone());
    jit.compile_all().unwrap();
    let ti = time("interp point", &mut || {
        pts.iter().map(|p| Evaluator::point(&interp, *p)).sum()
    });
    let tj = time("jit point", &mut || pts.iter().map(|p| jit.point(*p)).sum());
    println!("point speedup {:.1}x", ti.as_secs_f64() / tj.as_secs_f64());
    let ti = time("interp interval", &mut || {
        bxs.iter()
            .map(|b| Evaluator::interval(&interp, *b).lo)
            .sum()
    });
    let tj = time("jit interval", &mut || {
        bxs.iter().map(|b| jit.interval(*b).lo).sum()
    });
    println!(
        "interval speedup {:.1}x",
        ti.as_secs_f64() / tj.as_secs_f64()
    );
    let (xs, ys, zs): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        pts.iter().map(|p| p[0]).collect(),
        pts.iter().map(|p| p[1]).collect(),
        pts.iter().map(|p| p[2]).collect(),
    );
    let mut out = vec![0.0; n];
    for _ in 0..2 {
        time("jit point_batch", &mut || {
            jit.point_batch(&xs, &ys, &zs, &mut out);
            out.iter().sum()
        });
        time("jit point", &mut || pts.iter().map(|p| jit.point(*p)).sum());
    }
    let mut iout = vec![Interval::EMPTY; n];
    time("jit interval_batch", &mut || {
        jit.interval_batch(&bxs, &mut iout);
        iout.iter().map(|i| i.lo).sum()
    });
    for (name, t) in jit.compile_times() {
        println!("compile {name}: {t:?}");
    }
}

/// Interval evaluation time per box, the best of 15 rounds (robust against a
/// busy machine), JIT and interpreter, on the example scenes and prospero.
/// Run in release with `--ignored interval_speed --nocapture`.
#[test]
#[ignore]
fn interval_speed() {
    let mut fs = Vec::new();
    for file in ["examples/orthocircle.ib", "examples/tangle_cube.ib"] {
        let scene = ibeam::lang::load_scene(std::path::Path::new(file)).unwrap();
        fs.push((
            file,
            ibeam::ir::passes::simplify(&scene.objects[0].function),
        ));
    }
    if let Some(f) = prospero() {
        fs.push(("prospero", f));
    }
    for (name, f) in fs {
        let jit = JitEvaluator::new(&f).unwrap();
        let interp = Interpreter::new(f.clone());
        let n = if f.len() > 1000 { 500 } else { 20_000 };
        let mut r = Rng::new(3);
        let bxs: Vec<[Interval; 3]> = (0..n)
            .map(|_| {
                [0, 1, 2].map(|_| {
                    let c = r.range(-1.25, 1.25);
                    Interval::new(c, c + 2.5 / 64.0)
                })
            })
            .collect();
        let best = |e: &dyn Evaluator| {
            (0..15)
                .map(|_| {
                    let t = std::time::Instant::now();
                    for b in &bxs {
                        std::hint::black_box(e.interval(std::hint::black_box(*b)));
                    }
                    t.elapsed().as_nanos() as f64 / n as f64
                })
                .fold(f64::INFINITY, f64::min)
        };
        let (tj, ti) = (best(&jit), best(&interp));
        println!(
            "{name}: jit {tj:.1} ns/box, interp {ti:.1} ns/box, {:.2}x",
            ti / tj
        );
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
        let (got, want) = (jit.interval(bx), Evaluator::interval(&interp, bx));
        assert!(same_iv(got, want), "{bx:?}: {got:?} vs {want:?}");
        let p = random_point(&mut r);
        let (got, want) = (jit.point(p), Evaluator::point(&interp, p));
        assert!(same(got, want), "{p:?}: {got:e} vs {want:e}");
    }
}
