//! Intervals of every op and of random functions' ops against the
//! references of [`super`] and the oracle of [`crate::common::tight`]: see
//! the module docs there.

use std::f64::consts::FRAC_PI_2;

use ibeam::eval::interp::Interpreter;
use ibeam::ir::random::random_function;

use super::super::suite::Make;
use super::super::tight::{self, Tight};
use super::super::*;
use super::{Agree, Case, agrees, binary, cases, powi, unary};

/// Points of `i` where ops change behaviour: both zeros, ±1 (the ends of
/// asin's domain), the integers and halves next to its ends and middle
/// (the steps' jumps, round's ties) and the multiples of π/2 nearest them
/// (extrema of sin and cos, poles of tan), those that `i` holds.
fn landmarks(i: Interval) -> Vec<f64> {
    let (lo, hi) = (i.lo.max(f64::MIN), i.hi.min(f64::MAX));
    let mut v = vec![0.0, -0.0, 1.0, -1.0];
    for c in [lo, 0.5 * lo + 0.5 * hi, hi] {
        let k = c.floor();
        v.extend([k - 0.5, k, k + 0.5, k + 1.0]);
        v.push((c / FRAC_PI_2).round() * FRAC_PI_2);
    }
    v.retain(|&x| i.contains(x));
    v
}

/// Whether `i` is a non-empty interval with a finite point.
fn has_points(i: Interval) -> bool {
    !i.is_empty() && i.lo < f64::INFINITY && i.hi > f64::NEG_INFINITY
}

/// Sampled points of `i`: both ends, the middle, near the ends, random
/// ones and the [`landmarks`].
fn points_of(i: Interval, rng: &mut Rng, n_random: usize) -> Vec<f64> {
    if !has_points(i) {
        return Vec::new();
    }
    let mut v: Vec<f64> = sample_positions(rng, n_random)
        .into_iter()
        .map(|t| sample(i, t))
        .collect();
    v.extend(landmarks(i));
    v
}

/// `x` moved `k` floats down (`k` negative: up).
fn step(x: f64, k: i64) -> f64 {
    let mut v = x;
    for _ in 0..k.unsigned_abs() {
        v = if k > 0 { v.next_down() } else { v.next_up() };
    }
    v
}

/// `i` moved `k` floats out on both sides.
fn widen(i: Interval, k: u64) -> Interval {
    Interval::new(step(i.lo, k as i64), step(i.hi, -(k as i64)))
}

/// What the oracle says of an op's interval.
enum Want {
    /// Holds this, at most two ulps wider (`tight::tight_enough`).
    Tight(Tight),
    /// Exactly these bounds (the op is exact in f64).
    Exact((f64, f64)),
}

/// The oracle's result of the op called `name` over `(a, b)`, for the ops
/// [`tight`] knows.
fn tightest(name: &str, a: (f64, f64), b: (f64, f64)) -> Option<Want> {
    Some(match name {
        "Add" => Want::Tight(tight::add(a, b)),
        "Sub" => Want::Tight(tight::sub(a, b)),
        "Mul" => Want::Tight(tight::mul(a, b)),
        "Div" => Want::Tight(tight::div(a, b)),
        "Sqrt" => Want::Tight(tight::sqrt(a)),
        "Square" => Want::Tight(tight::square(a)),
        "Min" => Want::Exact(tight::min(a, b)),
        "Max" => Want::Exact(tight::max(a, b)),
        "Neg" => Want::Exact(tight::neg(a)),
        "Abs" => Want::Exact(tight::abs(a)),
        "Floor" => Want::Exact(tight::steps(a, f64::floor)),
        "Ceil" => Want::Exact(tight::steps(a, f64::ceil)),
        "Round" => Want::Exact(tight::steps(a, f64::round)),
        "Sign" => Want::Exact(tight::steps(a, tight::sign)),
        _ => return None,
    })
}

/// The interval `got` of the op called `name` over `(x, y)` (`y` unused
/// unless `binary`): EMPTY for an EMPTY operand (but `powi(_, 0)`), and
/// tight against the oracle where it knows the op and the operands are
/// IEEE 1788 intervals (non-empty, `lo < +inf`, `hi > -inf`).
fn check_tight(name: &str, binary: bool, got: Interval, (x, y): (Interval, Interval)) {
    let what = format!("{name} over {x:?}, {y:?}: {got:?}");
    if (x.is_empty() || (binary && y.is_empty())) && name != "powi 0" {
        assert!(got.is_empty(), "{what}: an EMPTY operand gives EMPTY");
    }
    if !(has_points(x) && has_points(y)) {
        return;
    }
    match tightest(name, (x.lo, x.hi), (y.lo, y.hi)) {
        Some(Want::Tight(t)) => {
            if let Err(e) = tight::tight_enough((got.lo, got.hi), t) {
                panic!("{what}: {e}");
            }
        }
        Some(Want::Exact((lo, hi))) => {
            assert!(
                got.lo == lo && got.hi == hi,
                "{what}: want [{lo:e}, {hi:e}]"
            );
        }
        None => {}
    }
}

/// The interval `got` of `case` over `(x, y)` holds the reference values
/// at the operands' sampled points where those are real (widened by the
/// reference's own error for the transcendentals).
fn check_samples(case: &Case, got: Interval, (x, y): (Interval, Interval), rng: &mut Rng) {
    let ys = if case.binary {
        points_of(y, rng, 10)
    } else {
        vec![0.5]
    };
    for px in points_of(x, rng, if case.binary { 10 } else { 60 }) {
        for &py in &ys {
            let (v, how) = (case.reference)(px, py);
            if !(v.is_finite() && px.is_finite() && py.is_finite()) {
                continue;
            }
            let room = match how {
                Agree::Bits => got,
                Agree::Ulps(k) => widen(got, k),
            };
            assert!(
                room.contains(v),
                "{} over {x:?}, {y:?} = {got:?} misses f({px:e}, {py:e}) = {v:e} by std",
                case.name
            );
        }
    }
}

/// Every op's interval over every pair of edge intervals and over random
/// boxes (see [`check_tight`] and [`check_samples`]).
pub fn check_intervals(make: Make) {
    let mut rng = Rng::new(1789);
    let edges = edge_intervals();
    for case in cases() {
        let e = make(&case.f);
        let mut boxes = Vec::new();
        for &a in &edges {
            if case.binary {
                boxes.extend(edges.iter().map(|&b| (a, b)));
            } else {
                boxes.push((a, Interval::point(0.5)));
            }
        }
        for _ in 0..300 {
            let b = random_box(&mut rng);
            boxes.push((b[0], b[1]));
        }
        for (x, y) in boxes {
            let got = e.interval([x, y, Interval::point(0.5)]);
            check_tight(&case.name, case.binary, got, (x, y));
            check_samples(&case, got, (x, y), &mut rng);
        }
    }
}

/// The reference of `op` at the point `p`, its operands' values read from
/// `vals`.
fn reference_op(op: Op, vals: &[f64], p: [f64; 3]) -> (f64, Agree) {
    match op {
        Op::Var(Var::X) => (p[0], Agree::Bits),
        Op::Var(Var::Y) => (p[1], Agree::Bits),
        Op::Var(Var::Z) => (p[2], Agree::Bits),
        Op::Const(c) => (c, Agree::Bits),
        Op::Unary(u, a) => unary(u, vals[a.index()]),
        Op::Binary(b, a, c) => binary(b, vals[a.index()], vals[c.index()]),
        Op::Powi(a, n) => (powi(vals[a.index()], n), Agree::Bits),
    }
}

/// Random functions through the interpreter, op by op: each point value
/// against its op's reference at the interpreter's values of the
/// operands, and each interval of an op the oracle knows against the
/// tightest result over the interpreter's intervals of the operands.
pub fn check_random_functions(seeds: std::ops::Range<u64>) {
    let mut rng = Rng::new(seeds.start);
    for seed in seeds {
        let f = random_function(seed, 8);
        let it = Interpreter::new(f.clone());
        for _ in 0..4 {
            let b = random_box(&mut rng);
            let ivs = it.interval_values(b);
            assert!(same_iv(it.interval(b), ivs[f.root.index()]), "seed {seed}");
            for (i, &op) in f.ops.iter().enumerate() {
                let got = ivs[i];
                let arg = |a: ValueId| ivs[a.index()];
                match op {
                    Op::Var(v) => {
                        let k = [Var::X, Var::Y, Var::Z].iter().position(|&w| w == v);
                        assert!(same_iv(got, b[k.expect("a variable")]), "seed {seed}: v{i}");
                    }
                    Op::Const(c) => assert!(same_iv(got, Interval::point(c)), "seed {seed}: v{i}"),
                    Op::Unary(u, a) => check_tight(&format!("{u:?}"), false, got, (arg(a), arg(a))),
                    Op::Binary(o, a, c) => {
                        check_tight(&format!("{o:?}"), true, got, (arg(a), arg(c)));
                    }
                    Op::Powi(..) => {}
                }
            }
            for p in box_points(b, &mut rng, 4) {
                let vals = it.point_values(p);
                assert!(
                    same(it.point(p), vals[f.root.index()]),
                    "seed {seed} at {p:?}"
                );
                for (i, &op) in f.ops.iter().enumerate() {
                    let (want, how) = reference_op(op, &vals, p);
                    assert!(
                        agrees(vals[i], want, how),
                        "seed {seed} at {p:?}: v{i} = {op:?} is {:e}, std gives {want:e}",
                        vals[i]
                    );
                }
            }
        }
    }
}
