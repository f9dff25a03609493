//! Tests of the affine rules: the second-order form against the first
//! on the expanded polynomial.

use super::*;

// (x − 1)¹⁰ written expanded, run by the rules over the form `x`
// (whose interval is `range`).
fn expanded<F: Form>(x: F, range: Interval) -> FormValue<F> {
    let binom = [
        1.0, -10.0, 45.0, -120.0, 210.0, -252.0, 210.0, -120.0, 45.0, -10.0, 1.0,
    ];
    let x = FormValue { form: x, range };
    let mut sum = FormValue::constant(0.0);
    for (k, c) in binom.into_iter().enumerate() {
        let term = affine_powi(&x, k as i32);
        let term = affine_binary(BinaryOp::Mul, &FormValue::constant(c), &term);
        sum = affine_binary(BinaryOp::Add, &sum, &term);
    }
    sum
}

#[test]
fn second_order_forms_keep_the_expansions_cancellation() {
    // x = 1.3 + t along a ray, t over [0, w]: the expansion is
    // (0.3 + t)¹⁰, and each form holds it at the ends.
    let (o, d) = (Interval::point(1.3), Interval::point(1.0));
    let mut errors = Vec::new();
    for w in [0.01, 0.001] {
        let t = Interval::new(0.0, w);
        let range = o.add(t);
        let second = expanded(Quadratic::along(o, d, t), range);
        let first = expanded(Affine::<1>::along(o, d, t), range);
        for end in [0.3f64, 0.3 + w] {
            let v = end.powi(10);
            assert!(second.range.contains(v) && first.range.contains(v));
        }
        errors.push((second.form.e, first.form.e));
    }
    // The first-order error falls as w², the second-order one as w³.
    let [(q1, a1), (q2, a2)] = errors[..] else {
        unreachable!()
    };
    assert!(q1 * 10.0 < a1 && q2 * 100.0 < a2, "{errors:?}");
    assert!(q2 < q1 * 2e-3 && a2 > a1 * 5e-3, "{errors:?}");
}
