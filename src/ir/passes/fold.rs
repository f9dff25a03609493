//! Constant folding.
//! An op of constants is replaced by its value only when that value is the
//! exact real result (checked with error-free transforms: `two_sum`, and
//! `f64::mul_add` for products, quotients and square roots), and for the
//! transcendentals only at their exact points (exp 0, ln 1, sin 0, cos 0,
//! pow(a, 0), atan2(0, x > 0)). An inexact constant would lose the outward
//! rounding its interval gets at run time.

use super::rewrite;
use crate::ir::semantics::{point_binary, point_powi, point_unary};
use crate::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId};

pub(super) fn constant(b: &Builder, v: ValueId) -> Option<f64> {
    match *b.op(v) {
        Op::Const(c) => Some(c),
        _ => None,
    }
}

// a + b if the sum is exact (two_sum error 0, no overflow).
pub(super) fn exact_add(a: f64, b: f64) -> Option<f64> {
    let s = a + b;
    if !s.is_finite() || !a.is_finite() || !b.is_finite() {
        return None;
    }
    let bb = s - a;
    let err = (a - (s - bb)) + (b - bb);
    (err == 0.0).then_some(s)
}

// The residual of a product or quotient is exactly representable (so fma
// detects inexactness) unless it falls below the normal range; these bounds
// keep every operand and result far from it.
fn safe_magnitude(v: f64) -> bool {
    v == 0.0 || (1e-290..=1e290).contains(&v.abs())
}

pub(super) fn exact_mul(a: f64, b: f64) -> Option<f64> {
    let p = a * b;
    if !(safe_magnitude(a) && safe_magnitude(b) && safe_magnitude(p)) {
        return None;
    }
    if p == 0.0 {
        return (a == 0.0 || b == 0.0).then_some(p);
    }
    (a.mul_add(b, -p) == 0.0).then_some(p)
}

fn exact_div(a: f64, b: f64) -> Option<f64> {
    if b == 0.0 {
        return None;
    }
    let q = a / b;
    if !(safe_magnitude(a) && safe_magnitude(b) && safe_magnitude(q)) {
        return None;
    }
    if q == 0.0 {
        return (a == 0.0).then_some(q);
    }
    ((-q).mul_add(b, a) == 0.0).then_some(q)
}

fn exact_powi(a: f64, n: i32) -> Option<f64> {
    // Binary exponentiation with every product checked exact: then the
    // result is the real power, whatever the order of the products.
    let (mut r, mut base, mut m) = (1.0f64, a, n.unsigned_abs());
    while m > 0 {
        if m & 1 == 1 {
            r = exact_mul(r, base)?;
        }
        m >>= 1;
        if m > 0 {
            base = exact_mul(base, base)?;
        }
    }
    let r = if n < 0 { exact_div(1.0, r)? } else { r };
    (r.to_bits() == point_powi(a, n).to_bits()).then_some(r)
}

/// The exact value of `op` over constant operands, if there is one.
fn fold(op: Op, b: &Builder) -> Option<f64> {
    match op {
        Op::Unary(u, a) => {
            let a = constant(b, a)?;
            let r = point_unary(u, a);
            match u {
                UnaryOp::Neg | UnaryOp::Abs => Some(r),
                UnaryOp::Square => exact_mul(a, a),
                UnaryOp::Sqrt => {
                    let ok = a >= 0.0 && safe_magnitude(a) && r.mul_add(r, -a) == 0.0;
                    ok.then_some(r)
                }
                UnaryOp::Exp => (a == 0.0).then_some(r),
                UnaryOp::Ln => (a == 1.0).then_some(r),
                UnaryOp::Sin => (a == 0.0).then_some(r),
                UnaryOp::Cos => (a == 0.0).then_some(r),
                // Odd functions through the origin are exact there.
                UnaryOp::Tan | UnaryOp::Asin | UnaryOp::Atan | UnaryOp::Sinh | UnaryOp::Tanh => {
                    (a == 0.0).then_some(r)
                }
                UnaryOp::Acos => (a == 1.0).then_some(r),
                UnaryOp::Cosh => (a == 0.0).then_some(r),
                UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round | UnaryOp::Sign => Some(r),
            }
        }
        Op::Binary(o, x, y) => {
            let (x, y) = (constant(b, x)?, constant(b, y)?);
            match o {
                BinaryOp::Add => exact_add(x, y),
                BinaryOp::Sub => exact_add(x, -y),
                BinaryOp::Mul => exact_mul(x, y),
                BinaryOp::Div => exact_div(x, y),
                BinaryOp::Min | BinaryOp::Max => Some(point_binary(o, x, y)),
                BinaryOp::Atan2 => (x == 0.0 && y > 0.0).then_some(point_binary(o, x, y)),
                BinaryOp::Pow => (x >= 0.0 && y == 0.0).then_some(1.0),
                // fmod is exact; only the step back into [0, |y|) for a
                // negative x rounds.
                BinaryOp::Mod => (x >= 0.0).then_some(point_binary(o, x, y)),
            }
        }
        Op::Powi(a, n) => exact_powi(constant(b, a)?, n),
        Op::Var(_) | Op::Const(_) => None,
    }
}

/// Constant folding: ops of constants whose value is exact (see the module
/// doc) become constants.
pub fn fold_constants(f: &Function) -> Function {
    rewrite(f, |b, op| match fold(op, b) {
        Some(c) if !c.is_nan() => b.constant(c),
        _ => b.push(op),
    })
}

pub(super) fn is_const(b: &Builder, v: ValueId, c: f64) -> bool {
    constant(b, v).is_some_and(|k| k.to_bits() == c.to_bits())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exactness_checks() {
        assert_eq!(exact_add(1.0, 2.0), Some(3.0));
        assert_eq!(exact_add(0.1, 0.2), None);
        assert_eq!(exact_mul(3.0, 0.5), Some(1.5));
        assert_eq!(exact_mul(0.1, 3.0), None);
        assert_eq!(exact_mul(1e-200, 1e-200), None);
        assert_eq!(exact_div(1.0, 4.0), Some(0.25));
        assert_eq!(exact_div(1.0, 3.0), None);
        assert_eq!(exact_powi(2.0, -3), Some(0.125));
        assert_eq!(exact_powi(3.0, 40), None);
        assert_eq!(exact_powi(3.0, 5), Some(243.0));
        // Must not loop 2^31 times.
        assert_eq!(exact_powi(1.0, i32::MIN), Some(1.0));
        assert_eq!(exact_powi(-1.0, i32::MAX), Some(-1.0));
    }
}
