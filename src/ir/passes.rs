//! Simplification passes, each a function from IR to IR.
//!
//! Every pass takes a `&Function` and returns a new [`Function`]; none keeps
//! state between calls, and [`super::validate::debug_validate`] checks the result.
//! [`simplify`] runs the list [`PASSES`] to a fixed point.
//!
//! # What a pass may change
//! The guarantee of the tracer is about the *real* function f the source
//! formula denotes: its interval must contain f's real values. A pass may
//! therefore replace an expression by one with the same real value wherever
//! the original is defined, and *the same domain*: a rewrite that makes a
//! value defined where it was undefined (x·0 → 0 when x is NaN) could put a
//! surface where the source has none, so those are not applied. Rewrites
//! that are bit-exact in IEEE arithmetic keep point values identical; the
//! few that are exact in real arithmetic only (a chain of multiplications
//! becoming one `powi`) change the point value by a few ulps at most.
//!
//! # Identities
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
//! # Specialisation
//! `x·x → x²`, `powi(x, 2) → x²`, `powi(x, 1) → x`, `powi(x, 0) → 1` and
//! `1 / x^n → x^-n` are bit-exact (our `powi` is binary exponentiation).
//! Products of powers of one value (`x·x·x·x`, `x²·x`, `(x²)²`, `(x³)²`)
//! become one `powi` with the summed (multiplied) positive exponent, and a
//! constant factor is pulled out of the chain (`5·x·x → 5·x²`): exact in
//! real arithmetic, rounding may differ by a few ulps, and the interval is
//! much tighter (x·x·x·x over [-1, 1] is [-1, 1], x⁴ is [0, 1]; 5·x·x is
//! [-5, 5], 5·x² is [0, 5]).
//!
//! # Constant folding
//! An op of constants is replaced by its value only when that value is the
//! exact real result (checked with error-free transforms: `two_sum`, and
//! `f64::mul_add` for products, quotients and square roots), and for the
//! transcendentals only at their exact points (exp 0, ln 1, sin 0, cos 0,
//! pow(a, 0), atan2(0, x > 0)). An inexact constant would lose the outward
//! rounding its interval gets at run time.

use super::semantics::{point_binary, point_powi, point_unary};
use super::validate::debug_validate;
use super::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId};

/// One named pass.
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    /// Its name in `ibeam ir --passes`.
    pub name: &'static str,
    /// The pass itself.
    pub run: fn(&Function) -> Function,
}

/// The passes [`simplify`] runs, in order.
pub const PASSES: &[Pass] = &[
    Pass {
        name: "fold",
        run: fold_constants,
    },
    Pass {
        name: "identities",
        run: identities,
    },
    Pass {
        name: "specialise",
        run: specialise,
    },
    Pass {
        name: "cse",
        run: cse,
    },
    Pass {
        name: "dce",
        run: dce,
    },
];

/// Most rounds of [`PASSES`] that [`simplify`] runs.
const MAX_ROUNDS: usize = 8;

/// Runs [`PASSES`] until the function stops changing (at most a few
/// rounds), then dead-code elimination.
pub fn simplify(f: &Function) -> Function {
    simplify_traced(f)
        .pop()
        .map(|(_, g)| g)
        .unwrap_or_else(|| dce(f))
}

/// The function after each pass [`simplify`] runs, in order (the last entry
/// is the result of `simplify`).
pub fn simplify_traced(f: &Function) -> Vec<(&'static str, Function)> {
    let mut trace: Vec<(&'static str, Function)> = Vec::new();
    let mut cur = f.clone();
    for _ in 0..MAX_ROUNDS {
        let before = cur.clone();
        for p in PASSES {
            cur = (p.run)(&cur);
            debug_validate(&cur, p.name);
            trace.push((p.name, cur.clone()));
        }
        if cur == before {
            break;
        }
    }
    // PASSES ends with DCE, so the last entry is already clean.
    trace
}

/// Rebuilds `f` op by op through a [`Builder`] (which merges identical
/// ops), letting `rule` choose the replacement of each op after its
/// operands were mapped.
fn rewrite(f: &Function, mut rule: impl FnMut(&mut Builder, Op) -> ValueId) -> Function {
    let mut b = Builder::new();
    let mut map: Vec<ValueId> = Vec::with_capacity(f.ops.len());
    for op in &f.ops {
        let op = op.map_operands(|a| map[a.index()]);
        map.push(rule(&mut b, op));
    }
    b.finish(map[f.root.index()])
}

/// Common-subexpression elimination: the rebuild through [`Builder`] merges
/// identical ops (commutative operands in canonical order).
pub fn cse(f: &Function) -> Function {
    rewrite(f, |b, op| b.push(op))
}

/// Dead-code elimination: keeps only the ops the root reaches, renumbered
/// in their original order.
pub fn dce(f: &Function) -> Function {
    let mut live = vec![false; f.ops.len()];
    live[f.root.index()] = true;
    for i in (0..f.ops.len()).rev() {
        if live[i] {
            for a in f.ops[i].operands() {
                live[a.index()] = true;
            }
        }
    }
    let mut map = vec![ValueId(0); f.ops.len()];
    let mut ops = Vec::new();
    for (i, op) in f.ops.iter().enumerate() {
        if live[i] {
            map[i] = ValueId(ops.len() as u32);
            ops.push(op.map_operands(|a| map[a.index()]));
        }
    }
    Function {
        ops,
        root: map[f.root.index()],
    }
}

fn constant(b: &Builder, v: ValueId) -> Option<f64> {
    match *b.op(v) {
        Op::Const(c) => Some(c),
        _ => None,
    }
}

// a + b if the sum is exact (two_sum error 0, no overflow).
fn exact_add(a: f64, b: f64) -> Option<f64> {
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

fn exact_mul(a: f64, b: f64) -> Option<f64> {
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

fn is_const(b: &Builder, v: ValueId, c: f64) -> bool {
    constant(b, v).is_some_and(|k| k.to_bits() == c.to_bits())
}

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
