//! The JIT against the reference rules beyond the shared conformance suite
//! (tests/conformance.rs): its own independently written derivative rules,
//! random functions bit for bit, laziness, threads, CLIF text; big
//! functions ([`big`]) and timings ([`timing`], ignored).

mod big;
#[path = "../common/mod.rs"]
mod common;
mod timing;

use common::suite::{ref_interval, ref_point, ref_point_all};
use common::{
    close, edge_intervals, one_op, random_box, random_point, same, same_iv, sample_random,
};

use ibeam::eval::interp::Interpreter;
use ibeam::eval::jit::{JitEvaluator, Kind, clif_text};
use ibeam::eval::{Bulk, Evaluator, Grad, IntervalGrad, Single};
use ibeam::interval::Interval;
use ibeam::ir::random::{Rng, random_function};
use ibeam::ir::semantics::{point_binary, point_powi, point_unary};
use ibeam::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId, Var};

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
                    UnaryOp::Tan => map(da, &|x| (1.0 + val * val) * x),
                    UnaryOp::Asin => map(da, &|x| x / (1.0 - a * a).sqrt()),
                    UnaryOp::Acos => map(da, &|x| -(x / (1.0 - a * a).sqrt())),
                    UnaryOp::Atan => map(da, &|x| x / (1.0 + a * a)),
                    UnaryOp::Sinh => map(da, &|x| point_unary(UnaryOp::Cosh, a) * x),
                    UnaryOp::Cosh => map(da, &|x| point_unary(UnaryOp::Sinh, a) * x),
                    UnaryOp::Tanh => map(da, &|x| (1.0 - val * val) * x),
                    UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round | UnaryOp::Sign => {
                        map(da, &|_| 0.0)
                    }
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
                        // a - |b|·floor(a/|b|), the floor flat between jumps.
                        BinaryOp::Mod => {
                            let (m, k) = (b.abs(), (a / b.abs()).floor());
                            let dm = xb.map(|y| if b < 0.0 { -y } else { y });
                            let dk = (xa.is_some() || dm.is_some()).then_some(0.0);
                            let dmk = match (dm.map(|y| k * y), dk.map(|z| m * z)) {
                                (Some(l), Some(r)) => Some(l + r),
                                (l, None) => l,
                                (None, r) => r,
                            };
                            match (xa, dmk) {
                                (Some(x), Some(t)) => x - t,
                                (Some(x), None) => x,
                                (None, t) => -t.unwrap_or(0.0),
                            }
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

/// `[0, 0]` times an interval with only infinite bounds: every bound
/// product is 0·inf (NaN), yet every real product is 0: the result is
/// [0, 0] rounded outward (by 2^-511, see `interval::up`), as the
/// reference gives.
#[test]
fn zero_times_unbounded_is_zero() {
    let f = one_op(Op::Binary(BinaryOp::Mul, ValueId(0), ValueId(1)));
    let jit = JitEvaluator::new(&f).unwrap();
    let z = Interval::point(0.0);
    for (a, b) in [(z, Interval::ENTIRE), (Interval::ENTIRE, z)] {
        let got = jit.interval([a, b, z]);
        assert!(same_iv(got, a.mul(b)), "{got:?}");
        assert!(
            got.contains(0.0) && got.width() <= 2f64.powi(-510),
            "{got:?}"
        );
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
                    // Subnormal partials keep few significant bits.
                    assert!(
                        close(g.d[k], gi.d[k]) || g.d[k].abs().max(gi.d[k].abs()) < 1e-250,
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
                let p = [0, 1, 2].map(|k| sample_random(&mut r, bx[k]));
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

/// Mismatched batch lengths: the JIT writes only the common prefix (the
/// trait's default would index out of bounds).
#[test]
fn batches_write_only_the_common_prefix() {
    let mut r = Rng::new(77);
    for seed in 100..110 {
        let f = random_function(seed, 10);
        let jit = JitEvaluator::new(&f).unwrap();
        let pts: Vec<[f64; 3]> = (0..8).map(|_| random_point(&mut r)).collect();
        let (xs, ys, zs): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            pts.iter().map(|p| p[0]).collect(),
            pts.iter().map(|p| p[1]).collect(),
            pts.iter().map(|p| p[2]).collect(),
        );
        let mut short = vec![-1.0; 5];
        jit.point_batch(&xs[..3], &ys, &zs, &mut short);
        assert!(same(short[2], jit.point(pts[2])));
        assert_eq!(short[3], -1.0);
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
