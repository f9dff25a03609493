//! Shared test helpers: the evaluator conformance suite ([`suite`]) that
//! every implementation of `Evaluator` runs (the interpreter, the JIT, the
//! regional evaluator), references independent of the interpreter's rules
//! ([`independent`]), the tightest-interval oracle ([`tight`]), the
//! shared models that must be present ([`models`]),
//! generators of edge values, boxes and points, and the runner of the
//! `ibeam` binary.
//!
//! Use it from a test file with `mod common;` (from a directory module,
//! `#[path = "../common/mod.rs"] mod common;`).
#![allow(dead_code, unused_imports, unused_macros)]

#[macro_use]
pub mod suite;
pub mod independent;
pub mod models;
pub mod tight;

use std::process::{Command, Output};

use ibeam::eval::{Bulk, Evaluator, Single, Specialise};
use ibeam::interval::Interval;
use ibeam::ir::random::{BINARY_OPS, Rng, UNARY_OPS};
use ibeam::ir::semantics::{point_binary, point_powi, point_unary};
use ibeam::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId, Var};

/// Arguments that exercise the edges of every op.
pub const EDGE_VALUES: [f64; 25] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    2.0,
    -2.2,
    -2.5,
    3.7,
    std::f64::consts::PI,
    -std::f64::consts::FRAC_PI_2,
    1e10,
    1e300,
    -1e300,
    1e308,
    -1e308,
    f64::MAX,
    1e-300,
    f64::MIN_POSITIVE,
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

/// Every interval of [`EDGE_INTERVALS`] and more: EMPTY, signed zero
/// points, subnormal and infinite points, the whole finite line.
pub fn edge_intervals() -> Vec<Interval> {
    let mut v = vec![
        Interval::EMPTY,
        Interval::ENTIRE,
        Interval::new(-0.0, -0.0),
        Interval::new(-1.0, 2.0),
        Interval::new(-3.0, -0.5),
        Interval::new(f64::NEG_INFINITY, -1.0),
        Interval::new(1e300, 1e308),
        Interval::new(-f64::MAX, f64::MAX),
        Interval::new(5e-324, 5e-324),
        Interval::new(-5e-324, 5e-324),
        Interval::new(f64::INFINITY, f64::INFINITY),
        Interval::new(-2.0, f64::INFINITY),
        Interval::point(-2.5),
        Interval::point(std::f64::consts::PI),
    ];
    v.extend(EDGE_INTERVALS.iter().map(|&(lo, hi)| Interval::new(lo, hi)));
    v
}

/// Equal bits, or finite and within a few ulps (relative 1e-12).
pub fn close(a: f64, b: f64) -> bool {
    same(a, b) || (a.is_finite() && b.is_finite() && (a - b).abs() <= 1e-12 * a.abs().max(b.abs()))
}

/// Both bounds equal by [`same`].
pub fn same_iv(a: Interval, b: Interval) -> bool {
    same(a.lo, b.lo) && same(a.hi, b.hi)
}

/// The one-op function of (x, y) with the kind of `op` (its operands are
/// replaced by x and y).
pub fn one_op(op: Op) -> Function {
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

/// Every op kind, with integer powers from the extremes of i32 included
/// (operands are placeholders for [`one_op`]).
pub fn all_ops() -> Vec<Op> {
    let mut ops: Vec<Op> = UNARY_OPS
        .iter()
        .map(|&u| Op::Unary(u, ValueId(0)))
        .collect();
    ops.extend(
        BINARY_OPS
            .iter()
            .map(|&b| Op::Binary(b, ValueId(0), ValueId(1))),
    );
    for n in independent::POWERS {
        ops.push(Op::Powi(ValueId(0), n));
    }
    ops
}

/// Bit equality with every NaN equal to every other (NaN payloads are not
/// part of the semantics).
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

/// A point of `a` drawn at random, its finite bounds and 0 (when inside)
/// often; NaN if `a` is empty.
pub fn sample_random(rng: &mut Rng, a: Interval) -> f64 {
    if a.is_empty() {
        return f64::NAN;
    }
    match rng.below(6) {
        0 if a.lo.is_finite() => a.lo,
        1 if a.hi.is_finite() => a.hi,
        2 if a.contains(0.0) => 0.0,
        // No finite point ([inf, inf]): the bound itself.
        _ if a.lo == f64::INFINITY || a.hi == f64::NEG_INFINITY => a.lo,
        _ => sample(a, rng.unit()),
    }
}

/// A random point: mostly in [-4, 4]³, a coordinate from [`EDGE_VALUES`]
/// now and then.
pub fn random_point(rng: &mut Rng) -> [f64; 3] {
    [0, 1, 2].map(|_| match rng.below(20) {
        0 => EDGE_VALUES[rng.below(EDGE_VALUES.len())],
        _ => rng.range(-4.0, 4.0),
    })
}

/// The `ibeam` binary run with `args` in the crate root; fails the test if
/// it panicked (exit code 101), which no input may cause.
pub fn ibeam(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_ibeam"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run ibeam");
    assert_ne!(
        out.status.code(),
        Some(101),
        "ibeam {args:?} panicked:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The standard output of a run, as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The standard error of a run, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A number as scene source text: two decimals, negatives in parentheses
/// (the random scene generators write formulas with it).
pub fn source_number(v: f64) -> String {
    let v = (v * 100.0).round() / 100.0;
    if v < 0.0 {
        format!("({v})")
    } else {
        format!("{v}")
    }
}
