//! Algebraic identities.
//! | rewrite | IEEE | applied |
//! |---|---|---|
//! | x + (-0) → x, x - 0 → x, x·1 → x, x/1 → x | bit-exact | yes |
//! | x + 0 → x | bit-exact but for the sign of a zero result (-0 + 0 = +0) | yes: the real value is the same; only `atan2(±0, x<0)` and `1/±0` see the sign, on the branch cut / pole where no real value is promised |
//! | x·(-1) → -x, x - (-y) → x + y, x + (-y) → x - y | bit-exact | yes |
//! | -(-x) → x, \|-x\| → \|x\|, \|\|x\|\| → \|x\|, (-x)² → x², \|x\|² → x², (-x)^2k → x^2k | bit-exact | yes |
//! | min(x, x) → x, max(x, x) → x | bit-exact | yes |
//! | x / 2^k → x · 2^-k (2^-k normal) | bit-exact (both round the same real) | yes |
//! | x - x → 0 | NaN and ±inf give NaN, 0 after | no: would define f where it is undefined |
//! | x · 0 → 0 | NaN, ±inf give NaN; sign of zero | no: same reason |
//! | 0 - x → -x | sign of zero only | no: the gain is nil, `neg` is lowered directly |
//! | sqrt(x²) → \|x\|, exp(ln x) → x | overflow, domain | no |
//!

use super::fold::{constant, is_const};
use super::rewrite;
use crate::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId};

/// Algebraic identities that hold in IEEE arithmetic (table in the module
/// doc).
pub fn identities(f: &Function) -> Function {
    rewrite(f, |b, op| identity(b, op).unwrap_or_else(|| b.push(op)))
}

fn identity(b: &mut Builder, op: Op) -> Option<ValueId> {
    use BinaryOp::*;
    use UnaryOp::*;
    let negated = |b: &Builder, v: ValueId| match *b.op(v) {
        Op::Unary(Neg, x) => Some(x),
        _ => None,
    };
    match op {
        Op::Binary(Add, x, y) => {
            for (p, q) in [(x, y), (y, x)] {
                if is_const(b, q, 0.0) || is_const(b, q, -0.0) {
                    return Some(p);
                }
                if let Some(n) = negated(b, q) {
                    return Some(b.binary(Sub, p, n));
                }
            }
            None
        }
        Op::Binary(Sub, x, y) => {
            if is_const(b, y, 0.0) {
                return Some(x);
            }
            negated(b, y).map(|n| b.binary(Add, x, n))
        }
        Op::Binary(Mul, x, y) => {
            for (p, q) in [(x, y), (y, x)] {
                if is_const(b, q, 1.0) {
                    return Some(p);
                }
                if is_const(b, q, -1.0) {
                    return Some(b.unary(Neg, p));
                }
            }
            None
        }
        Op::Binary(Div, x, y) => {
            if is_const(b, y, 1.0) {
                return Some(x);
            }
            let c = constant(b, y)?;
            let r = 1.0 / c;
            // c = ±2^k with 2^-k normal: x/c and x·(1/c) round the same real.
            let power_of_two = c.is_finite()
                && c != 0.0
                && r.is_normal()
                && c.abs().to_bits() & ((1u64 << 52) - 1) == 0
                && c.is_normal();
            if power_of_two {
                let r = b.constant(r);
                Some(b.binary(Mul, x, r))
            } else {
                None
            }
        }
        Op::Binary(Min | Max, x, y) if x == y => Some(x),
        Op::Unary(Neg, x) => negated(b, x),
        Op::Unary(Abs, x) => match *b.op(x) {
            Op::Unary(Neg | Abs, y) => Some(b.unary(Abs, y)),
            _ => None,
        },
        Op::Unary(Square, x) => match *b.op(x) {
            Op::Unary(Neg | Abs, y) => Some(b.unary(Square, y)),
            _ => None,
        },
        Op::Powi(x, n) if n % 2 == 0 => match *b.op(x) {
            Op::Unary(Neg | Abs, y) => Some(b.powi(y, n)),
            _ => None,
        },
        _ => None,
    }
}
