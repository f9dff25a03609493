//! Interval arithmetic against the tightest outward-rounded results of
//! tests/common/tight.rs (`+ - * /`, sqrt, square, and the exact ops) and
//! against sampled point values.
//!
//! The oracle has no transcendentals, so exp, ln, sin, cos, atan2 and pow
//! are checked by containment of sampled point values (including points
//! placed on their extrema, at huge arguments and on the atan2 branch cut)
//! and by a width bound on degenerate intervals.

mod common;

use common::tight::{self, Tight};
use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::interval::{Interval, TRANSCENDENTAL_ULPS};
use ibeam::ir::random::{BINARY_OPS, UNARY_OPS, random_function};
use ibeam::ir::semantics::{
    interval_binary, interval_unary, point_binary, point_powi, point_unary,
};
use ibeam::ir::{BinaryOp, UnaryOp};
use proptest::prelude::*;

fn bound() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => -10.0..10.0f64,
        1 => prop::sample::select(vec![
            0.0, -0.0, 1.0, -1.0, 0.5, 2.0, f64::INFINITY, f64::NEG_INFINITY,
            f64::MAX, f64::MIN, f64::MIN_POSITIVE, 5e-324, -5e-324, 1e300, -1e300, 1e-300,
        ]),
        1 => prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO,
        1 => -1e6..1e6f64,
    ]
}

/// Intervals with lo <= hi, lo < +inf, hi > -inf (IEEE 1788's valid
/// intervals, which the oracle takes).
fn interval() -> impl Strategy<Value = Interval> {
    (bound(), bound()).prop_map(|(a, b)| {
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        let lo = if lo == f64::INFINITY { f64::MAX } else { lo };
        let hi = if hi == f64::NEG_INFINITY {
            f64::MIN
        } else {
            hi
        };
        Interval::new(lo, hi)
    })
}

/// `(lo, hi)`, the oracle's form of an interval.
fn pair(i: Interval) -> (f64, f64) {
    (i.lo, i.hi)
}

/// Ours contains the tightest result and is at most 2 ulps wider on each
/// side (2^-510 near zero); see `tight::tight_enough`.
fn assert_tight(ours: Interval, tightest: Tight, what: &str) {
    if let Err(e) = tight::tight_enough(pair(ours), tightest) {
        panic!("{what}: {e}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 2000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn arithmetic_is_tight(a in interval(), b in interval()) {
        let (pa, pb) = (pair(a), pair(b));
        assert_tight(a.add(b), tight::add(pa, pb), &format!("{a:?} + {b:?}"));
        assert_tight(a.sub(b), tight::sub(pa, pb), &format!("{a:?} - {b:?}"));
        assert_tight(a.mul(b), tight::mul(pa, pb), &format!("{a:?} * {b:?}"));
        assert_tight(a.div(b), tight::div(pa, pb), &format!("{a:?} / {b:?}"));
        assert_tight(a.min(b), Some(tight::min(pa, pb)), &format!("min {a:?} {b:?}"));
        assert_tight(a.max(b), Some(tight::max(pa, pb)), &format!("max {a:?} {b:?}"));
        assert_tight(a.sqrt(), tight::sqrt(pa), &format!("sqrt {a:?}"));
        assert_tight(a.square(), tight::square(pa), &format!("square {a:?}"));
        assert_tight(a.abs(), Some(tight::abs(pa)), &format!("abs {a:?}"));
        assert_tight(a.neg(), Some(tight::neg(pa)), &format!("neg {a:?}"));
        // The steps are exact: equal to the tightest result.
        let exact = |f: fn(f64) -> f64| {
            let (lo, hi) = tight::steps(pa, f);
            Interval::new(lo, hi)
        };
        assert_eq!(a.floor(), exact(f64::floor), "floor {a:?}");
        assert_eq!(a.ceil(), exact(f64::ceil), "ceil {a:?}");
        assert_eq!(a.round(), exact(f64::round), "round {a:?}");
        assert_eq!(a.sign(), exact(tight::sign), "sign {a:?}");
    }

    #[test]
    fn every_op_contains_sampled_points(
        a in interval(),
        b in interval(),
        ts in prop::collection::vec(0.0..=1.0f64, 4),
        n in -4i32..=6,
    ) {
        let pick = |i: Interval, t: f64| {
            let (lo, hi) = (i.lo.max(f64::MIN), i.hi.min(f64::MAX));
            (lo * (1.0 - t) + hi * t).clamp(lo, hi)
        };
        let xs = [a.lo, a.hi, pick(a, ts[0]), pick(a, ts[1]), if a.contains(0.0) { 0.0 } else { a.lo }];
        let ys = [b.lo, b.hi, pick(b, ts[2]), pick(b, ts[3]), if b.contains(0.0) { 0.0 } else { b.lo }];
        for op in UNARY_OPS {
            let r = interval_unary(op, a);
            for &x in &xs {
                let v = point_unary(op, x);
                prop_assert!(!x.is_finite() || !v.is_finite() || r.contains(v),
                    "{op:?} {a:?} = {r:?} misses f({x:e}) = {v:e}");
            }
        }
        for op in BINARY_OPS {
            let r = interval_binary(op, a, b);
            for &x in &xs {
                for &y in &ys {
                    let v = point_binary(op, x, y);
                    prop_assert!(!x.is_finite() || !y.is_finite() || !v.is_finite() || r.contains(v),
                        "{op:?} {a:?} {b:?} = {r:?} misses f({x:e}, {y:e}) = {v:e}");
                }
            }
        }
        let r = a.powi(n);
        for &x in &xs {
            let v = point_powi(x, n);
            prop_assert!(!x.is_finite() || !v.is_finite() || r.contains(v),
                "powi {a:?} {n} = {r:?} misses {v:e} at {x:e}");
        }
    }

    #[test]
    fn tan_and_mod_near_their_jumps(k in -1_000_000i64..1_000_000, d in 1e-12..1e-3f64, t in 0.0..=1.0f64, c in prop_oneof![Just(1.0f64), Just(0.1), Just(2.5), Just(-3.0)]) {
        // Intervals ending just short of, or reaching past, a pole of tan
        // and a multiple of the period of mod.
        let pole = k as f64 * std::f64::consts::PI + std::f64::consts::FRAC_PI_2;
        let edge = k as f64 * c;
        for (lo, hi) in [(pole - 2.0 * d, pole - d), (pole - d, pole + d), (edge - d, edge + d), (edge, edge + d), (edge - d, edge)] {
            let a = Interval::new(lo, hi);
            let x = lo + (hi - lo) * t;
            for &x in &[lo, hi, x] {
                let v = libm::tan(x);
                prop_assert!(a.tan().contains(v), "tan {a:?} = {:?} misses {v:e} at {x:e}", a.tan());
                let m = x.rem_euclid(c);
                let r = a.rem_euclid(Interval::point(c));
                prop_assert!(r.contains(m), "mod {a:?} {c} = {r:?} misses {m:e} at {x:e}");
            }
        }
    }

    #[test]
    fn trig_extrema_far_out(k in 0u64..100_000_000_000_000, half in any::<bool>(), d in 1e-9..1.0f64, t in 0.0..=1.0f64) {
        // An interval around k·π (or k·π + π/2) must reach the extremum there:
        // the point of the interval closest to it is sampled.
        let centre = k as f64 * std::f64::consts::PI + if half { std::f64::consts::FRAC_PI_2 } else { 0.0 };
        let i = Interval::new(centre - d, centre + d * t);
        for op in [UnaryOp::Sin, UnaryOp::Cos] {
            let r = interval_unary(op, i);
            for x in [i.lo, i.hi, centre, centre.next_up(), centre.next_down(), i.mid()] {
                if i.contains(x) {
                    let v = point_unary(op, x);
                    prop_assert!(r.contains(v), "{op:?} {i:?} = {r:?} misses f({x:e}) = {v:e}");
                }
            }
        }
    }

    #[test]
    fn atan2_near_the_cut(y0 in -1.0..1.0f64, w in 0.0..1.0f64, x0 in -2.0..2.0f64, v in 0.0..1.0f64) {
        let (y, x) = (Interval::new(y0, y0 + w), Interval::new(x0, x0 + v));
        let r = y.atan2(x);
        for py in [y.lo, y.hi, y.mid(), 0.0, -0.0] {
            for px in [x.lo, x.hi, x.mid(), 0.0] {
                if y.contains(py) && x.contains(px) {
                    let a = point_binary(BinaryOp::Atan2, py, px);
                    prop_assert!(r.contains(a), "atan2({y:?}, {x:?}) = {r:?} misses {a:e} at ({py:e}, {px:e})");
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_functions_enclose_points(
        seed in any::<u64>(),
        bx in prop::array::uniform3(interval()),
        ts in prop::collection::vec(prop::array::uniform3(0.0..=1.0f64), 8),
    ) {
        // Points where every intermediate value is real must be enclosed;
        // elsewhere f is undefined and nothing is promised.
        let f = random_function(seed, 8);
        let it = Interpreter::new(f);
        let r = it.interval(bx);
        for t in ts {
            let p = [0, 1, 2].map(|k| {
                let (lo, hi) = (bx[k].lo.max(f64::MIN), bx[k].hi.min(f64::MAX));
                (lo * (1.0 - t[k]) + hi * t[k]).clamp(lo, hi)
            });
            if it.point_values(p).iter().all(|v| v.is_finite()) {
                let v = it.point(p);
                prop_assert!(r.contains(v), "seed {seed}: f{p:?} = {v:e} not in {r:?} over {bx:?}");
            }
        }
    }
}

#[test]
fn transcendentals_are_tight_on_points() {
    // On a point the result is the libm value widened by TRANSCENDENTAL_ULPS
    // ulps, clamped: at most 2·ULPS+1 representable numbers wide.
    let steps = 2 * TRANSCENDENTAL_ULPS as usize;
    let within = |r: Interval, what: &str| {
        let mut v = r.lo;
        for _ in 0..steps {
            v = v.next_up();
        }
        assert!(r.hi <= v, "{what}: {r:?} is more than {steps} ulps wide");
    };
    for &x in &[0.1, 0.5, 1.0, 2.0, 3.0, 10.0, 700.0, 1e-5, 123.456] {
        let p = Interval::point(x);
        for op in [
            UnaryOp::Exp,
            UnaryOp::Ln,
            UnaryOp::Sin,
            UnaryOp::Cos,
            UnaryOp::Tan,
            UnaryOp::Atan,
            UnaryOp::Sinh,
            UnaryOp::Cosh,
            UnaryOp::Tanh,
        ] {
            if x < 700.0 || op != UnaryOp::Tanh {
                within(interval_unary(op, p), &format!("{op:?}({x})"));
            }
        }
        if x <= 1.0 {
            within(p.asin(), &format!("asin({x})"));
            within(p.acos(), &format!("acos({x})"));
        }
        for &y in &[0.3, 1.5, -2.0] {
            let q = Interval::point(y);
            within(p.atan2(q), &format!("atan2({x}, {y})"));
            within(p.pow(q), &format!("pow({x}, {y})"));
        }
    }
}

#[test]
fn edge_results() {
    let e = Interval::EMPTY;
    for op in UNARY_OPS {
        assert!(interval_unary(op, e).is_empty(), "{op:?} of EMPTY");
    }
    for op in BINARY_OPS {
        assert!(
            interval_binary(op, e, Interval::new(1.0, 2.0)).is_empty(),
            "{op:?}(EMPTY, x)"
        );
        assert!(
            interval_binary(op, Interval::new(1.0, 2.0), e).is_empty(),
            "{op:?}(x, EMPTY)"
        );
    }
    assert!(Interval::new(-3.0, -1.0).ln().is_empty());
    assert!(Interval::new(-3.0, -1.0).sqrt().is_empty());
    assert!(
        Interval::new(-3.0, -1.0)
            .pow(Interval::point(0.5))
            .is_empty()
    );
    let exp = Interval::new(f64::NEG_INFINITY, 0.0).exp();
    assert_eq!(exp.lo, 0.0);
    assert!(exp.hi >= 1.0 && exp.hi < 1.0 + 1e-15);
    assert_eq!(Interval::ENTIRE.sin(), Interval::new(-1.0, 1.0));
    // A factor [0, 0] makes the product exactly [0, 0], even against an
    // unbounded factor (0 times any real is 0).
    let z = Interval::new(0.0, 0.0).mul(Interval::ENTIRE);
    assert!(z.lo == 0.0 && z.hi == 0.0, "{z:?}");
    let d = Interval::new(1.0, 2.0).div(Interval::new(0.0, 4.0));
    assert!(d.lo <= 0.25 && d.lo > 0.24 && d.hi == f64::INFINITY);
    let d = Interval::new(1.0, 2.0).div(Interval::new(-4.0, 0.0));
    assert!(d.hi >= -0.25 && d.hi < -0.24 && d.lo == f64::NEG_INFINITY);
    // sin over [0, π] reaches 1 but stays at or above sin(π) ≈ 1.2e-16 - ulps.
    let s = Interval::new(0.0, std::f64::consts::PI).sin();
    assert_eq!(s.hi, 1.0);
    assert!(s.lo <= 0.0 && s.lo > -1e-15);
}

/// Where the platform's tanh is 2 ulps off, ours still holds the real
/// value (0.496337112301545704069 to 21 digits, computed with 50-digit
/// decimal arithmetic), which lies between the two f64s below.
#[test]
fn tanh_holds_the_real_value_where_glibc_is_two_ulps_high() {
    let r = Interval::point(5.444341524673745e-1).tanh();
    assert!(r.lo <= 0.496_337_112_301_545_7, "{r:?}");
    assert!(r.hi >= 0.496_337_112_301_545_76, "{r:?}");
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 3000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// A second, independent implementation (the platform's libm behind
    /// `std`) must land inside our widened bounds on point intervals: both
    /// are within 1 ulp of the real value, ours is widened by 2.
    #[test]
    fn platform_libm_inside_point_bounds(
        x in prop_oneof![-20.0..20.0f64, -1e6..1e6f64, -745.0..710.0f64, 1e-300..1e-10f64],
        y in prop_oneof![-20.0..20.0f64, 1e-3..10.0f64],
    ) {
        let p = Interval::point(x);
        let q = Interval::point(y);
        let check = |r: Interval, v: f64, what: &str| {
            assert!(!v.is_finite() || r.contains(v), "{what}: std gives {v:e}, ours {r:?}");
        };
        check(p.exp(), x.exp(), &format!("exp {x:e}"));
        check(p.sin(), x.sin(), &format!("sin {x:e}"));
        check(p.cos(), x.cos(), &format!("cos {x:e}"));
        check(p.atan2(q), x.atan2(y), &format!("atan2 {x:e} {y:e}"));
        check(p.tan(), x.tan(), &format!("tan {x:e}"));
        check(p.atan(), x.atan(), &format!("atan {x:e}"));
        // glibc documents up to 2 ulps of error for the hyperbolic
        // functions (tanh at 0.5444341524673745 is 2 ulps high): one more
        // ulp of slack each side for them.
        let loose = |r: Interval| Interval::new(r.lo.next_down(), r.hi.next_up());
        check(loose(p.sinh()), x.sinh(), &format!("sinh {x:e}"));
        check(loose(p.cosh()), x.cosh(), &format!("cosh {x:e}"));
        check(loose(p.tanh()), x.tanh(), &format!("tanh {x:e}"));
        let u = x.sin();
        check(Interval::point(u).asin(), u.asin(), &format!("asin {u:e}"));
        check(Interval::point(u).acos(), u.acos(), &format!("acos {u:e}"));
        check(p.rem_euclid(q), x.rem_euclid(y), &format!("mod {x:e} {y:e}"));
        let ax = x.abs();
        check(Interval::point(ax).ln(), ax.ln(), &format!("ln {ax:e}"));
        if (ax * y.abs()) < 300.0 {
            check(Interval::point(ax).pow(q), ax.powf(y), &format!("pow {ax:e} {y:e}"));
        }
    }

    /// Ray boxes multiply by ray parameters with `mul_by_positive`, which
    /// reads two of `mul`'s four products: by any interval of positive
    /// numbers it must give `mul`'s bounds to the bit (and fall back to
    /// `mul` by anything else).
    #[test]
    fn products_by_positive_intervals_are_muls_to_the_bit(
        a in interval(),
        lo in prop_oneof![1e-300..1e-6f64, 1e-3..100.0f64, 1.0..1e300f64, bound()],
        w in prop_oneof![0.0..1e-9f64, 0.0..10.0f64, bound()],
    ) {
        let t = Interval::new(lo, lo + w.abs());
        let bits = |i: Interval| (i.lo.to_bits(), i.hi.to_bits());
        let fast = a.mul_by_positive(t);
        prop_assert_eq!(bits(fast), bits(a.mul(t)), "{:?} · {:?}", a, t);
        prop_assert_eq!(bits(fast), bits(t.mul(a)), "{:?} · {:?}", t, a);
    }
}

// Zeros that are exact stay exact: a sum that rounds to 0 is exact (x + y
// rounds to 0 only for y = -x), as is 0 times or over a real; products
// that underflow to 0 are not, and stay rounded out.
#[test]
fn exact_zeros_are_not_rounded_out() {
    let z = Interval::point(0.0);
    let exact = |i: Interval, what: &str| assert!(i.lo == 0.0 && i.hi == 0.0, "{what}: {i:?}");
    exact(z.add(z), "0 + 0");
    exact(z.sub(z), "0 - 0");
    exact(Interval::point(0.3).sub(Interval::point(0.3)), "0.3 - 0.3");
    exact(
        Interval::point(-2.5).add(Interval::point(2.5)),
        "-2.5 + 2.5",
    );
    exact(z.mul(Interval::new(-3.0, 7.0)), "0 · [-3, 7]");
    exact(Interval::new(-3.0, 7.0).mul(z), "[-3, 7] · 0");
    exact(Interval::new(-3.0, 7.0).mul_point(0.0), "[-3, 7] · point 0");
    exact(z.mul_point(5.0), "0 · point 5");
    exact(z.div(Interval::new(2.0, 3.0)), "0 / [2, 3]");
    exact(z.div(Interval::new(-3.0, -2.0)), "0 / [-3, -2]");
    assert!(z.mul(Interval::EMPTY).is_empty() && Interval::EMPTY.mul(z).is_empty());
    assert!(Interval::EMPTY.add(z).is_empty() && z.div(Interval::EMPTY).is_empty());
    // 1e-200 · 1e-200 underflows to 0 in floating point; the real product
    // is positive and must stay inside.
    let tiny = Interval::point(1e-200);
    let p = tiny.mul(tiny);
    assert!(p.lo <= 0.0 && p.hi > 0.0, "{p:?}");
    // A sum that does not cancel still moves out past its rounding.
    let s = Interval::point(0.1).add(Interval::point(0.2));
    assert!(s.lo < 0.30000000000000004 && s.hi > 0.3, "{s:?}");
    let s = Interval::point(1e-310).add(Interval::point(2e-310));
    assert!(
        s.lo <= 3e-310 && s.hi >= 3e-310,
        "subnormal sums are exact: {s:?}"
    );
}
