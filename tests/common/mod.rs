//! Shared test helpers: the evaluator conformance suite that every
//! implementation of `Evaluator` (the interpreter, the JIT) runs, and
//! generators of edge values, boxes and points.
//!
//! Use it from a test file with `mod common;` and one `#[test]` per check:
//! ```ignore
//! #[test]
//! fn point_ops() { common::check_point_ops(&|f| Box::new(Interpreter::new(f.clone()))); }
//! ```
#![allow(dead_code)]

use ibeam::eval::Evaluator;
use ibeam::eval::interp::Interpreter;
use ibeam::interval::Interval;
use ibeam::ir::random::{BINARY_OPS, Rng, UNARY_OPS, random_function};
use ibeam::ir::semantics::{point_binary, point_powi, point_unary};
use ibeam::ir::{BinaryOp, Builder, Function, UnaryOp, Var};

/// Builds the evaluator under test for a function.
pub type Make<'a> = &'a dyn Fn(&Function) -> Box<dyn Evaluator>;

/// Arguments that exercise the edges of every op.
pub const EDGE_VALUES: [f64; 20] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    2.0,
    -2.2,
    3.7,
    std::f64::consts::PI,
    -std::f64::consts::FRAC_PI_2,
    1e10,
    1e300,
    -1e300,
    1e-300,
    5e-324,
    -5e-324,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    1e16,
];

/// Argument intervals that exercise the edges of every op: points, signed
/// zeros, intervals with 0 inside or at an end, half-lines, huge and tiny.
pub const EDGE_INTERVALS: [(f64, f64); 20] = [
    (0.0, 0.0),
    (-0.0, 0.0),
    (-1.0, 1.0),
    (0.0, 1.0),
    (-1.0, 0.0),
    (-2.0, -1.0),
    (1.0, 2.0),
    (0.5, 0.5),
    (1e-300, 1e-300),
    (-1e300, 1e300),
    (f64::NEG_INFINITY, f64::INFINITY),
    (f64::NEG_INFINITY, 0.0),
    (0.0, f64::INFINITY),
    (3.0, 3.5),
    (1e15, 1e15 + 10.0),
    (-7.0, 7.0),
    (1.4, 1.7),
    (-3.3, -2.9),
    (0.9, 1.1),
    (2.0, f64::INFINITY),
];

/// Bit equality with every NaN equal to every other.
pub fn same(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan()) || a.to_bits() == b.to_bits()
}

/// `op(x)`.
pub fn unary_fn(op: UnaryOp) -> Function {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let r = b.unary(op, x);
    b.finish(r)
}

/// `op(x, y)`.
pub fn binary_fn(op: BinaryOp) -> Function {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let y = b.var(Var::Y);
    let r = b.binary(op, x, y);
    b.finish(r)
}

/// `powi(x, n)`.
pub fn powi_fn(n: i32) -> Function {
    let mut b = Builder::new();
    let x = b.var(Var::X);
    let r = b.powi(x, n);
    b.finish(r)
}

/// The point semantics of a single-op function of (x, y).
pub type Reference = Box<dyn Fn(f64, f64) -> f64>;

/// Every single-op function with its point semantics: (name, function,
/// reference of (x, y)).
pub fn single_op_functions() -> Vec<(String, Function, Reference)> {
    let mut v: Vec<(String, Function, Reference)> = Vec::new();
    for op in UNARY_OPS {
        v.push((
            format!("{op:?}"),
            unary_fn(op),
            Box::new(move |x, _| point_unary(op, x)),
        ));
    }
    for op in BINARY_OPS {
        v.push((
            format!("{op:?}"),
            binary_fn(op),
            Box::new(move |x, y| point_binary(op, x, y)),
        ));
    }
    for n in -4..=6 {
        v.push((
            format!("powi {n}"),
            powi_fn(n),
            Box::new(move |x, _| point_powi(x, n)),
        ));
    }
    v
}

/// A finite point of `i` chosen by `t` in [0, 1] (ends included; an
/// infinite end is replaced by a large finite value).
pub fn sample(i: Interval, t: f64) -> f64 {
    let (lo, hi) = (i.lo.max(f64::MIN), i.hi.min(f64::MAX));
    (lo * (1.0 - t) + hi * t).clamp(lo, hi)
}

/// Sample positions: both ends, the middle, near the ends, and random.
pub fn sample_positions(rng: &mut Rng, n_random: usize) -> Vec<f64> {
    let mut t = vec![0.0, 1.0, 0.5, 1e-9, 1.0 - 1e-9, 0.25];
    t.extend((0..n_random).map(|_| rng.unit()));
    t
}

/// Points of the box `b` (the corners, and random interior points).
pub fn box_points(b: [Interval; 3], rng: &mut Rng, n: usize) -> Vec<[f64; 3]> {
    let mut pts = Vec::new();
    for c in 0..8 {
        let t = |k: usize| if c >> k & 1 == 1 { 1.0 } else { 0.0 };
        pts.push([sample(b[0], t(0)), sample(b[1], t(1)), sample(b[2], t(2))]);
    }
    for _ in 0..n {
        pts.push([
            sample(b[0], rng.unit()),
            sample(b[1], rng.unit()),
            sample(b[2], rng.unit()),
        ]);
    }
    // 0 when a box holds it: the edge of many ops.
    let z = |i: Interval, v: f64| if i.contains(0.0) { 0.0 } else { v };
    pts.push([z(b[0], pts[8][0]), z(b[1], pts[8][1]), z(b[2], pts[8][2])]);
    pts
}

/// A random box, sides drawn from [`EDGE_INTERVALS`] or random.
pub fn random_box(rng: &mut Rng) -> [Interval; 3] {
    let mut side = || {
        if rng.chance(0.4) {
            let (lo, hi) = rng.pick(&EDGE_INTERVALS);
            Interval::new(lo, hi)
        } else {
            let scale = rng.pick(&[0.01, 1.0, 4.0, 100.0]);
            let a = rng.range(-scale, scale);
            let w = rng.range(0.0, scale) * rng.pick(&[0.0, 0.001, 0.1, 1.0]);
            Interval::new(a, a + w)
        }
    };
    [side(), side(), side()]
}

/// Point values of every single-op function on edge arguments are those
/// of the point semantics, bit for bit (NaN equal to NaN), and so are the
/// values that come with gradients.
pub fn check_point_ops(make: Make) {
    for (name, f, reference) in single_op_functions() {
        let e = make(&f);
        for &x in &EDGE_VALUES {
            for &y in &EDGE_VALUES {
                let want = reference(x, y);
                let got = e.point([x, y, 0.5]);
                assert!(
                    same(got, want),
                    "{name}({x:e}, {y:e}) = {got:e}, want {want:e}"
                );
                let g = e.point_grad([x, y, 0.5]);
                assert!(same(g.v, want), "{name}({x:e}, {y:e}) grad value {:e}", g.v);
            }
        }
    }
}

/// Every single-op interval over edge and random boxes contains the point
/// values at the sampled points where those are real; EMPTY only where no
/// sampled point is real. Interval gradients give the same value interval.
pub fn check_interval_ops(make: Make) {
    let mut rng = Rng::new(7);
    for (name, f, reference) in single_op_functions() {
        let e = make(&f);
        let mut boxes: Vec<(Interval, Interval)> = Vec::new();
        for &(a, b) in &EDGE_INTERVALS {
            for &(c, d) in &EDGE_INTERVALS {
                boxes.push((Interval::new(a, b), Interval::new(c, d)));
            }
        }
        for _ in 0..200 {
            let b = random_box(&mut rng);
            boxes.push((b[0], b[1]));
        }
        for (x, y) in boxes {
            let bx = [x, y, Interval::point(0.5)];
            let got = e.interval(bx);
            let ig = e.interval_grad(bx);
            assert!(
                got == ig.v || (got.is_empty() && ig.v.is_empty()),
                "{name} over {x:?} {y:?}: interval {got:?} but interval_grad value {:?}",
                ig.v
            );
            let ts = sample_positions(&mut rng, 6);
            for &tx in &ts {
                for &ty in &ts {
                    let (px, py) = (sample(x, tx), sample(y, ty));
                    let v = reference(px, py);
                    if v.is_finite() {
                        assert!(
                            got.contains(v),
                            "{name} over {x:?} {y:?} = {got:?} misses f({px:e}, {py:e}) = {v:e}"
                        );
                    }
                }
            }
        }
    }
}

/// Central difference of `e` along axis `k` at `p`, with step `h`.
pub fn central_difference(e: &dyn Evaluator, p: [f64; 3], k: usize, h: f64) -> f64 {
    let (mut a, mut b) = (p, p);
    a[k] += h;
    b[k] -= h;
    (e.point(a) - e.point(b)) / (2.0 * h)
}

/// Whether `g` matches the finite differences of `e` at `p` (where the two
/// step sizes agree with each other, i.e. `e` looks smooth there).
/// Returns how many partials were compared.
pub fn check_gradient_at(e: &dyn Evaluator, p: [f64; 3], what: &str) -> usize {
    let g = e.point_grad(p);
    let mut compared = 0;
    for k in 0..3 {
        let scale = p[k].abs().max(1.0);
        let fd1 = central_difference(e, p, k, 1e-4 * scale);
        let fd2 = central_difference(e, p, k, 1e-5 * scale);
        if !(fd1.is_finite() && fd2.is_finite() && g.d[k].is_finite()) {
            continue;
        }
        let tol = 1e-4 * fd2.abs().max(1.0);
        if (fd1 - fd2).abs() > tol {
            continue;
        }
        assert!(
            (g.d[k] - fd2).abs() <= 10.0 * tol,
            "{what}: ∂{k} at {p:?} is {:e}, finite differences give {fd2:e}",
            g.d[k]
        );
        compared += 1;
    }
    compared
}

/// Gradients of every single-op function agree with central finite
/// differences at smooth points, and lie in the interval gradients of small
/// boxes around them.
pub fn check_grad_ops(make: Make) {
    let mut rng = Rng::new(11);
    for (name, f, _) in single_op_functions() {
        let e = make(&f);
        let mut compared = 0;
        for _ in 0..40 {
            // Smooth region of every op: positive, away from 0 and from ties.
            let x = rng.range(0.3, 3.0);
            let y = x + rng.pick(&[-1.0, 1.0]) * rng.range(0.2, 2.0);
            let p = [x, y.max(0.1), 0.7];
            compared += check_gradient_at(e.as_ref(), p, &name);
            check_interval_grad_contains(e.as_ref(), p, 1e-3, &name);
        }
        assert!(compared >= 40, "{name}: only {compared} partials compared");
    }
}

/// The interval gradient over a box of half-width `r` around `p` contains
/// the point gradient at the box's corners, centre and random points.
pub fn check_interval_grad_contains(e: &dyn Evaluator, p: [f64; 3], r: f64, what: &str) {
    let b = [
        Interval::new(p[0] - r, p[0] + r),
        Interval::new(p[1] - r, p[1] + r),
        Interval::new(p[2] - r, p[2] + r),
    ];
    let ig = e.interval_grad(b);
    let mut rng = Rng::new(p[0].to_bits());
    for q in box_points(b, &mut rng, 4) {
        let g = e.point_grad(q);
        if g.v.is_finite() {
            assert!(
                ig.v.contains(g.v),
                "{what}: value {:e} at {q:?} not in {:?}",
                g.v,
                ig.v
            );
        }
        for k in 0..3 {
            if g.d[k].is_finite() {
                assert!(
                    ig.d[k].contains(g.d[k]),
                    "{what}: ∂{k} = {:e} at {q:?} not in {:?} over {b:?}",
                    g.d[k],
                    ig.d[k]
                );
            }
        }
    }
}

/// Random functions: point values and gradient values agree with the
/// interpreter bit for bit; intervals and interval gradients over random
/// boxes contain the values at points of the box where every intermediate
/// value is real (a point where some op is undefined is outside f's domain);
/// gradients match finite differences where f looks smooth.
pub fn check_random_functions(make: Make, seeds: std::ops::Range<u64>) {
    let mut rng = Rng::new(seeds.start);
    let n_seeds = seeds.end - seeds.start;
    let mut compared = 0;
    for seed in seeds {
        let f = random_function(seed, 8);
        let e = make(&f);
        let reference = Interpreter::new(f.clone());
        for _ in 0..6 {
            let b = random_box(&mut rng);
            let got = e.interval(b);
            let ig = e.interval_grad(b);
            assert!(
                got == ig.v || (got.is_empty() && ig.v.is_empty()),
                "seed {seed}: interval {got:?} vs interval_grad {:?}",
                ig.v
            );
            for q in box_points(b, &mut rng, 6) {
                let want = Evaluator::point(&reference, q);
                let v = e.point(q);
                assert!(
                    same(v, want),
                    "seed {seed} at {q:?}: {v:e}, interpreter {want:e}"
                );
                let g = e.point_grad(q);
                assert!(
                    same(g.v, want),
                    "seed {seed} at {q:?}: grad value {:e}",
                    g.v
                );
                if !reference.point_values(q).iter().all(|v| v.is_finite()) {
                    continue;
                }
                assert!(
                    got.contains(v),
                    "seed {seed}: f{q:?} = {v:e} not in {got:?} over {b:?}"
                );
                for k in 0..3 {
                    if g.d[k].is_finite() {
                        assert!(
                            ig.d[k].contains(g.d[k]),
                            "seed {seed}: ∂{k} f{q:?} = {:e} not in {:?} over {b:?}",
                            g.d[k],
                            ig.d[k]
                        );
                    }
                }
            }
        }
        for _ in 0..3 {
            let p = [
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            ];
            if reference
                .point_values(p)
                .iter()
                .all(|v| v.is_finite() && v.abs() < 1e6)
            {
                compared += check_gradient_at(e.as_ref(), p, &format!("seed {seed}"));
            }
        }
    }
    // Many random functions are undefined or non-smooth at random points;
    // enough of them must still be compared for the check to mean anything.
    assert!(
        compared as u64 >= n_seeds / 2,
        "only {compared} partials compared with finite differences over {n_seeds} functions"
    );
}

/// The whole suite.
pub fn conformance(make: Make) {
    check_point_ops(make);
    check_interval_ops(make);
    check_grad_ops(make);
    check_random_functions(make, 0..300);
}
