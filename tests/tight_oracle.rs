//! The tightest-interval oracle of tests/common/tight.rs against results
//! known from elsewhere: hand-picked bounds, a table from exact rational
//! arithmetic (tests/data/tight_cases.py), and fused multiply-add
//! residuals where those are exact. tests/interval.rs and the
//! interpreter's conformance tests trust this oracle, so a bug in it must
//! fail here first.

mod common;

use common::tight::{self, Tight, add_bounds, div_bounds, mul_bounds, sqrt_bounds};
use proptest::prelude::*;

/// Bounds equal as numbers (a zero's sign carries no meaning for a bound).
fn assert_bounds(got: (f64, f64), want: (f64, f64), what: &str) {
    assert!(
        got.0 == want.0 && got.1 == want.1,
        "{what}: [{:e}, {:e}], want [{:e}, {:e}]",
        got.0,
        got.1,
        want.0,
        want.1
    );
}

#[test]
fn hand_picked_roundings() {
    // 0.1 + 0.2 is 0.3000000000000000166…, between the floats 0.3 and
    // 0.30000000000000004; it rounds to the upper one.
    assert_bounds(
        add_bounds(0.1, 0.2),
        (0.3, 0.300_000_000_000_000_04),
        "0.1 + 0.2",
    );
    // 1/3 = 0.0101…₂ rounds down (the bits after the 53rd are 0101…).
    let third = (0.333_333_333_333_333_3, 0.333_333_333_333_333_37);
    assert_bounds(div_bounds(1.0, 3.0), third, "1/3");
    assert_bounds(div_bounds(-1.0, -3.0), third, "-1/-3");
    assert_bounds(div_bounds(-1.0, 3.0), (-third.1, -third.0), "-1/3");
    // √2 = 1.41421356237309504880…, below its nearest float
    // 1.4142135623730951454….
    let s2 = std::f64::consts::SQRT_2;
    let root2 = (s2.next_down(), s2);
    assert_bounds(sqrt_bounds(2.0), root2, "sqrt 2");
    // Exact results stay points.
    assert_bounds(add_bounds(0.5, 0.25), (0.75, 0.75), "0.5 + 0.25");
    assert_bounds(mul_bounds(-3.0, 7.0), (-21.0, -21.0), "-3 · 7");
    assert_bounds(div_bounds(6.0, 4.0), (1.5, 1.5), "6 / 4");
    assert_bounds(sqrt_bounds(9.0), (3.0, 3.0), "sqrt 9");
    assert_bounds(
        sqrt_bounds(5e-324),
        (2f64.powi(-537), 2f64.powi(-537)),
        "sqrt 2^-1074",
    );
    // 1 + 2^-60 rounds to 1: only the error term sees the 2^-60.
    assert_bounds(
        add_bounds(1.0, 2f64.powi(-60)),
        (1.0, 1.0f64.next_up()),
        "1 + 2^-60",
    );
    assert_bounds(
        add_bounds(-1.0, -(2f64.powi(-60))),
        (-1.0f64.next_up(), -1.0),
        "-1 - 2^-60",
    );
}

#[test]
fn overflow_and_underflow() {
    let (max, inf) = (f64::MAX, f64::INFINITY);
    assert_bounds(add_bounds(max, max), (max, inf), "MAX + MAX");
    assert_bounds(add_bounds(-max, -max), (-inf, -max), "-MAX - MAX");
    assert_bounds(mul_bounds(max, 2.0), (max, inf), "MAX · 2");
    assert_bounds(mul_bounds(-max, 2.0), (-inf, -max), "-MAX · 2");
    assert_bounds(div_bounds(max, 0.5), (max, inf), "MAX / 0.5");
    // 1e-400 underflows to 0 but is positive.
    assert_bounds(mul_bounds(1e-200, 1e-200), (0.0, 5e-324), "1e-200²");
    assert_bounds(mul_bounds(-1e-200, 1e-200), (-5e-324, 0.0), "-1e-200²");
    // 1.5·2^-1074 ties between 2^-1074 and 2^-1073 and rounds to the
    // even 2^-1073; fma(a, b, -r) = RN(-2^-1075) = -0 would call it exact.
    assert_bounds(
        mul_bounds(3.0 * 5e-324, 0.5),
        (5e-324, 1e-323),
        "3·2^-1074 / 2",
    );
    assert_bounds(div_bounds(5e-324, 2.0), (0.0, 5e-324), "2^-1074 / 2");
    // Sums of subnormals are exact.
    assert_bounds(
        add_bounds(1e-310, 2e-310),
        (1e-310 + 2e-310, 1e-310 + 2e-310),
        "1e-310 + 2e-310",
    );
    // Division by an infinite divisor is the limit 0.
    assert_bounds(div_bounds(1.0, -inf), (-0.0, -0.0), "1 / -inf");
}

/// Python's exact rationals agree to the bit (zeros' signs aside).
#[test]
fn cases_from_exact_rational_arithmetic() {
    let text = include_str!("data/tight_cases.txt");
    let float = |h: &str| f64::from_bits(u64::from_str_radix(h, 16).expect("hex bits"));
    let mut n = 0;
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let w: Vec<&str> = line.split_whitespace().collect();
        let (a, b, lo, hi) = (float(w[1]), float(w[2]), float(w[3]), float(w[4]));
        let got = match w[0] {
            "add" => add_bounds(a, b),
            "mul" => mul_bounds(a, b),
            "div" => div_bounds(a, b),
            "sqrt" => sqrt_bounds(a),
            op => panic!("unknown op {op}"),
        };
        assert_bounds(got, (lo, hi), &format!("{} {a:e} {b:e}", w[0]));
        n += 1;
    }
    assert!(n >= 250, "only {n} cases");
}

#[test]
fn interval_results() {
    let (inf, entire): (f64, Tight) = (f64::INFINITY, Some((f64::NEG_INFINITY, f64::INFINITY)));
    let third = div_bounds(1.0, 3.0);
    assert_eq!(tight::div((1.0, 2.0), (0.0, 4.0)), Some((0.25, inf)));
    assert_eq!(tight::div((1.0, 2.0), (-4.0, 0.0)), Some((-inf, -0.25)));
    assert_eq!(tight::div((-2.0, -1.0), (0.0, 4.0)), Some((-inf, -0.25)));
    assert_eq!(tight::div((-2.0, -1.0), (-4.0, -0.0)), Some((0.25, inf)));
    assert_eq!(tight::div((1.0, 2.0), (-1.0, 1.0)), entire);
    assert_eq!(tight::div((-1.0, 2.0), (0.0, 4.0)), entire);
    assert_eq!(tight::div((0.0, 0.0), (-1.0, 1.0)), Some((0.0, 0.0)));
    assert_eq!(tight::div((1.0, 2.0), (0.0, 0.0)), None);
    assert_eq!(tight::div((1.0, 1.0), (3.0, inf)), Some((0.0, third.1)));
    assert_eq!(tight::div((1.0, inf), (1.0, inf)), Some((0.0, inf)));
    assert_eq!(
        tight::div((-1.0, 1.0), (3.0, 3.0)),
        Some((-third.1, third.1))
    );
    assert_eq!(tight::mul((0.0, 0.0), (-inf, inf)), Some((0.0, 0.0)));
    assert_eq!(tight::mul((0.0, 1.0), (1.0, inf)), Some((0.0, inf)));
    assert_eq!(tight::mul((-2.0, 3.0), (-5.0, 4.0)), Some((-15.0, 12.0)));
    // 1 + 0.2 is 1.2000000000000000111…, above the float 1.2.
    assert_eq!(
        tight::add((-inf, 1.0), (0.1, 0.2)),
        Some((-inf, 1.200_000_000_000_000_2))
    );
    assert_eq!(tight::sub((0.0, 1.0), (-inf, 2.0)), Some((-2.0, inf)));
    assert_eq!(tight::sqrt((-4.0, -1.0)), None);
    assert_eq!(tight::sqrt((-1.0, 4.0)), Some((0.0, 2.0)));
    assert_eq!(tight::sqrt((2.0, inf)), Some((sqrt_bounds(2.0).0, inf)));
    assert_eq!(tight::square((-3.0, 2.0)), Some((0.0, 9.0)));
    assert_eq!(tight::square((-3.0, -2.0)), Some((4.0, 9.0)));
    assert_eq!(tight::square((1e-200, 1e200)), Some((0.0, inf)));
    assert_eq!(tight::abs((-3.0, 2.0)), (0.0, 3.0));
    assert_eq!(tight::abs((-3.0, -2.0)), (2.0, 3.0));
    assert_eq!(tight::steps((-0.5, 2.5), f64::round), (-1.0, 3.0));
    assert_eq!(tight::steps((-0.0, 2.5), tight::sign), (0.0, 1.0));
}

/// The width check of tests/interval.rs: tight enough passes, a bound
/// that misses or strays three ulps fails.
#[test]
fn tightness_check_accepts_and_refuses() {
    let want = Some((1.0, 2.0));
    assert!(tight::tight_enough((1.0, 2.0), want).is_ok());
    let two_below = 1.0f64.next_down().next_down();
    assert!(tight::tight_enough((two_below, 2.0), want).is_ok());
    assert!(tight::tight_enough((two_below.next_down(), 2.0), want).is_err());
    assert!(tight::tight_enough((1.0f64.next_up(), 2.0), want).is_err());
    assert!(tight::tight_enough((1.0, 2.0f64.next_down()), want).is_err());
    assert!(tight::tight_enough((f64::NAN, f64::NAN), want).is_err());
    assert!(tight::tight_enough((f64::NAN, f64::NAN), None).is_ok());
    assert!(tight::tight_enough((0.0, 1.0), None).is_err());
    // Near zero 2^-510 of slack.
    assert!(tight::tight_enough((-(2f64.powi(-511)), 1e-300), Some((0.0, 1e-300))).is_ok());
    assert!(tight::tight_enough((-(2f64.powi(-509)), 1e-300), Some((0.0, 1e-300))).is_err());
}

/// A float whose exponent stays within ±`e` of 1 (so residuals of a
/// product, a quotient or a root of two such are neither huge nor below
/// the subnormals), or a small integer (exact results).
fn moderate(e: i32) -> impl Strategy<Value = f64> {
    prop_oneof![
        (any::<bool>(), 1u64 << 52..1u64 << 53, -e..=e).prop_map(|(s, m, k)| if s {
            -1.0
        } else {
            1.0
        } * m as f64
            * 2f64.powi(k - 52)),
        (-64i32..=64).prop_map(f64::from),
    ]
}

fn side(residual: f64) -> std::cmp::Ordering {
    residual.partial_cmp(&0.0).expect("finite residual")
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 20_000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// In the normal range a fused multiply-add residual has the sign of
    /// the rounding error (the brief's construction of the oracle), and
    /// two-sum's error that of Fast2Sum's.
    #[test]
    fn integer_comparisons_agree_with_fma_residuals(a in moderate(400), b in moderate(400)) {
        let up_or_down = |r: f64, s: std::cmp::Ordering| match s {
            std::cmp::Ordering::Less => (r.next_down(), r),
            std::cmp::Ordering::Equal => (r, r),
            std::cmp::Ordering::Greater => (r, r.next_up()),
        };
        let p = a * b;
        prop_assert_eq!(mul_bounds(a, b), up_or_down(p, side(a.mul_add(b, -p))), "{:e} · {:e}", a, b);
        if b != 0.0 {
            let q = a / b;
            let s = side((-q).mul_add(b, a));
            let s = if b < 0.0 { s.reverse() } else { s };
            prop_assert_eq!(div_bounds(a, b), up_or_down(q, s), "{:e} / {:e}", a, b);
        }
        let x = a.abs();
        let r = x.sqrt();
        prop_assert_eq!(sqrt_bounds(x), up_or_down(r, side((-r).mul_add(r, x))), "sqrt {:e}", x);
        // Knuth's branch-free two-sum.
        let s = a + b;
        let bb = s - a;
        let err = (a - (s - bb)) + (b - bb);
        prop_assert_eq!(add_bounds(a, b), up_or_down(s, side(err)), "{:e} + {:e}", a, b);
    }

    /// Whatever the operands, subnormal included, the bounds hold the
    /// round-to-nearest result and are at most one float apart.
    #[test]
    fn bounds_bracket_the_nearest_result(
        a in prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO,
        b in prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL,
    ) {
        for (r, (lo, hi)) in [
            (a + b, add_bounds(a, b)),
            (a * b, mul_bounds(a, b)),
            (a / b, div_bounds(a, b)),
            (a.abs().sqrt(), sqrt_bounds(a.abs())),
        ] {
            prop_assert!(lo <= r && r <= hi && (lo == hi || lo.next_up() == hi),
                "{:e}, {:e}: [{:e}, {:e}] around {:e}", a, b, lo, hi, r);
        }
    }
}
