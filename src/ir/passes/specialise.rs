//! Specialisation.
//! `x·x → x²`, `powi(x, 2) → x²`, `powi(x, 1) → x`, `powi(x, 0) → 1` and
//! `1 / x^n → x^-n` are bit-exact (our `powi` is binary exponentiation).
//! Products of powers of one value (`x·x·x·x`, `x²·x`, `(x²)²`, `(x³)²`)
//! become one `powi` with the summed (multiplied) positive exponent, and a
//! constant factor is pulled out of the chain (`5·x·x → 5·x²`): exact in
//! real arithmetic, rounding may differ by a few ulps, and the interval is
//! much tighter (x·x·x·x over [-1, 1] is [-1, 1], x⁴ is [0, 1]; 5·x·x is
//! [-5, 5], 5·x² is [0, 5]).
//!

use super::fold::{constant, is_const};
use super::rewrite;
use crate::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId};

/// Largest exponent a product chain is folded into (beyond it the chain is
/// left alone; such powers do not occur in real formulas).
const MAX_CHAIN_POWER: i64 = 64;

/// Specialisation: squares and integer powers in place of products (see
/// the module doc).
pub fn specialise(f: &Function) -> Function {
    rewrite(f, |b, op| specialised(b, op).unwrap_or_else(|| b.push(op)))
}

// `v` as base^k for a positive k, looking through square and positive powi.
fn as_power(b: &Builder, v: ValueId) -> (ValueId, i64) {
    match *b.op(v) {
        Op::Unary(UnaryOp::Square, x) => (x, 2),
        Op::Powi(x, n) if n >= 1 => (x, i64::from(n)),
        _ => (v, 1),
    }
}

// base^k in the cheapest bit-exact form.
fn power(b: &mut Builder, base: ValueId, k: i64) -> ValueId {
    match k {
        1 => base,
        2 => b.unary(UnaryOp::Square, base),
        _ => b.powi(base, k as i32),
    }
}

// `v` as coefficient·base^k, the coefficient a constant factor of a
// product (`5·x` is (5, x, 1)).
fn as_scaled_power(b: &Builder, v: ValueId) -> (Option<ValueId>, ValueId, i64) {
    if let Op::Binary(BinaryOp::Mul, p, q) = *b.op(v) {
        for (c, rest) in [(p, q), (q, p)] {
            if constant(b, c).is_some() && constant(b, rest).is_none() {
                let (base, k) = as_power(b, rest);
                return (Some(c), base, k);
            }
        }
    }
    let (base, k) = as_power(b, v);
    (None, base, k)
}

fn specialised(b: &mut Builder, op: Op) -> Option<ValueId> {
    match op {
        Op::Binary(BinaryOp::Mul, x, y) => {
            // (c·x^i)·x^j → c·x^(i+j): one coefficient at most, so no
            // product of constants (which might round) is formed.
            let (cx, bx, kx) = as_scaled_power(b, x);
            let (cy, by, ky) = as_scaled_power(b, y);
            let one_coefficient = cx.is_none() || cy.is_none();
            if bx != by || !one_coefficient || kx + ky > MAX_CHAIN_POWER {
                return None;
            }
            let p = power(b, bx, kx + ky);
            Some(match cx.or(cy) {
                Some(c) => b.binary(BinaryOp::Mul, c, p),
                None => p,
            })
        }
        Op::Binary(BinaryOp::Div, x, y) if is_const(b, x, 1.0) => {
            let (base, k) = as_power(b, y);
            (k >= 2).then(|| b.powi(base, -(k as i32)))
        }
        Op::Unary(UnaryOp::Square, x) => {
            let (base, k) = as_power(b, x);
            (k >= 2 && 2 * k <= MAX_CHAIN_POWER).then(|| power(b, base, 2 * k))
        }
        Op::Powi(x, n) => match n {
            0 => Some(b.constant(1.0)),
            1 => Some(x),
            2 => Some(b.unary(UnaryOp::Square, x)),
            _ if n > 2 => {
                let (base, k) = as_power(b, x);
                let total = k * i64::from(n);
                (k >= 2 && total <= MAX_CHAIN_POWER).then(|| power(b, base, total))
            }
            _ => None,
        },
        _ => None,
    }
}
