//! Reference evaluators over the IR in plain Rust: the oracle the JIT is
//! tested against.

use super::{BinaryOp, UnaryOp};
use crate::interval::{max_nan, min_nan, powi_point};

/// Point semantics of a one-operand op (the JIT calls this for the
/// transcendentals, so both give identical bits).
pub fn point_unary(op: UnaryOp, a: f64) -> f64 {
    match op {
        UnaryOp::Neg => -a,
        UnaryOp::Abs => a.abs(),
        UnaryOp::Square => a * a,
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Exp => libm::exp(a),
        UnaryOp::Ln => libm::log(a),
        UnaryOp::Sin => libm::sin(a),
        UnaryOp::Cos => libm::cos(a),
    }
}

/// Point semantics of a two-operand op.
pub fn point_binary(op: BinaryOp, a: f64, b: f64) -> f64 {
    match op {
        BinaryOp::Add => a + b,
        BinaryOp::Sub => a - b,
        BinaryOp::Mul => a * b,
        BinaryOp::Div => a / b,
        BinaryOp::Min => min_nan(a, b),
        BinaryOp::Max => max_nan(a, b),
        BinaryOp::Atan2 => libm::atan2(a, b),
        BinaryOp::Pow => {
            // NaN in, NaN out (libm's pow(NaN, 0) = pow(1, NaN) = 1 would
            // hide an undefined operand); -0 is taken as +0 so that the
            // result is exp(b·ln a) with ln(±0) = -inf, never negative.
            if a.is_nan() || b.is_nan() || a < 0.0 {
                f64::NAN
            } else {
                libm::pow(a + 0.0, b)
            }
        }
    }
}

/// Point semantics of `powi`.
pub fn point_powi(a: f64, n: i32) -> f64 {
    powi_point(a, n)
}
