//! `extern "C"` entry points through which native code calls the Rust
//! rules of the ops it does not inline (transcendentals, steps, `mod`),
//! so that JIT and interpreter give identical bits.
//!
//! Intervals travel as two f64 arguments and come back as a `#[repr(C)]`
//! [`Interval`] (two doubles, returned in xmm0/xmm1 by the C ABI, which is
//! how Cranelift's two-f64-result signature reads them). One generic
//! function per shape serves every op, keyed by the op's position in
//! [`UnaryOp::ALL`] or [`BinaryOp::ALL`] as a const parameter.

use crate::interval::Interval;
use crate::ir::semantics::{
    interval_binary, interval_step_grad, interval_unary, point_binary, point_unary,
};
use crate::ir::{BinaryOp, UnaryOp};

extern "C" fn point_unary_shim<const OP: usize>(a: f64) -> f64 {
    point_unary(UnaryOp::ALL[OP], a)
}
extern "C" fn point_binary_shim<const OP: usize>(a: f64, b: f64) -> f64 {
    point_binary(BinaryOp::ALL[OP], a, b)
}
extern "C" fn interval_unary_shim<const OP: usize>(lo: f64, hi: f64) -> Interval {
    interval_unary(UnaryOp::ALL[OP], Interval::new(lo, hi))
}
extern "C" fn interval_binary_shim<const OP: usize>(
    alo: f64,
    ahi: f64,
    blo: f64,
    bhi: f64,
) -> Interval {
    interval_binary(
        BinaryOp::ALL[OP],
        Interval::new(alo, ahi),
        Interval::new(blo, bhi),
    )
}
/// The interpreter's interval `step_grad` (see `ir::semantics::Arith`):
/// operand `a`, partial `x`.
extern "C" fn interval_step_grad_shim<const OP: usize>(
    alo: f64,
    ahi: f64,
    xlo: f64,
    xhi: f64,
) -> Interval {
    interval_step_grad(
        UnaryOp::ALL[OP],
        Interval::new(alo, ahi),
        Interval::new(xlo, xhi),
    )
}
extern "C" fn interval_div_zero(alo: f64, ahi: f64, blo: f64, bhi: f64) -> Interval {
    Interval::new(alo, ahi).div_by_zero_part(Interval::new(blo, bhi))
}

/// Shape of a shim's signature.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum ShimSig {
    /// f64 -> f64
    PointUnary,
    /// (f64, f64) -> f64
    PointBinary,
    /// (f64, f64) -> (f64, f64)
    IntervalUnary,
    /// (f64, f64, f64, f64) -> (f64, f64)
    IntervalBinary,
}

impl ShimSig {
    /// Numbers of f64 parameters and results.
    pub(crate) fn arity(self) -> (usize, usize) {
        match self {
            ShimSig::PointUnary => (1, 1),
            ShimSig::PointBinary => (2, 1),
            ShimSig::IntervalUnary => (2, 2),
            ShimSig::IntervalBinary => (4, 2),
        }
    }
}

/// One out-of-line helper that native code calls; its position in
/// [`Shim::ALL`] keys per-shim tables.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Shim {
    /// The point rule of a one-operand op.
    PointUnary(UnaryOp),
    /// The point rule of a two-operand op.
    PointBinary(BinaryOp),
    /// The interval rule of a one-operand op.
    IntervalUnary(UnaryOp),
    /// The interval rule of a two-operand op.
    IntervalBinary(BinaryOp),
    /// The interval partial of a step op (`Arith::step_grad`).
    IntervalStepGrad(UnaryOp),
    /// `Interval::div_by_zero_part`, the rare branch of interval division.
    IntervalDivZero,
}

/// One-operand ops the JIT calls out for (the rest it inlines).
const CALLED_UNARY: [UnaryOp; 15] = [
    UnaryOp::Exp,
    UnaryOp::Ln,
    UnaryOp::Sin,
    UnaryOp::Cos,
    UnaryOp::Tan,
    UnaryOp::Asin,
    UnaryOp::Acos,
    UnaryOp::Atan,
    UnaryOp::Sinh,
    UnaryOp::Cosh,
    UnaryOp::Tanh,
    UnaryOp::Floor,
    UnaryOp::Ceil,
    UnaryOp::Round,
    UnaryOp::Sign,
];

/// Two-operand ops the JIT calls out for.
const CALLED_BINARY: [BinaryOp; 3] = [BinaryOp::Atan2, BinaryOp::Pow, BinaryOp::Mod];

/// Step ops, whose interval partials are called out for.
const STEP_UNARY: [UnaryOp; 4] = [UnaryOp::Floor, UnaryOp::Ceil, UnaryOp::Round, UnaryOp::Sign];

/// Number of shims.
pub(crate) const SHIM_COUNT: usize =
    2 * CALLED_UNARY.len() + 2 * CALLED_BINARY.len() + STEP_UNARY.len() + 1;

/// Position of an op in its `ALL` list: the const parameter of its shims.
const fn unary_index(op: UnaryOp) -> usize {
    op as usize
}

/// The four shim functions of the one-operand op with index `I`.
macro_rules! unary_ptrs {
    ($op:expr, $($name:ident),*) => {
        match $op {
            $(UnaryOp::$name => (
                point_unary_shim::<{ unary_index(UnaryOp::$name) }> as *const u8,
                interval_unary_shim::<{ unary_index(UnaryOp::$name) }> as *const u8,
                interval_step_grad_shim::<{ unary_index(UnaryOp::$name) }> as *const u8,
            ),)*
            _ => unreachable!("{} is inlined, not called", $op.name()),
        }
    };
}

/// The point and interval shim functions of a two-operand op.
macro_rules! binary_ptrs {
    ($op:expr, $($name:ident),*) => {
        match $op {
            $(BinaryOp::$name => (
                point_binary_shim::<{ BinaryOp::$name as usize }> as *const u8,
                interval_binary_shim::<{ BinaryOp::$name as usize }> as *const u8,
            ),)*
            _ => unreachable!("{} is inlined, not called", $op.name()),
        }
    };
}

impl Shim {
    /// Every shim, in table order.
    pub(crate) fn all() -> impl Iterator<Item = Shim> {
        CALLED_UNARY
            .into_iter()
            .flat_map(|u| [Shim::PointUnary(u), Shim::IntervalUnary(u)])
            .chain(
                CALLED_BINARY
                    .into_iter()
                    .flat_map(|b| [Shim::PointBinary(b), Shim::IntervalBinary(b)]),
            )
            .chain(STEP_UNARY.into_iter().map(Shim::IntervalStepGrad))
            .chain([Shim::IntervalDivZero])
    }

    /// Position in [`Shim::all`].
    pub(crate) fn index(self) -> usize {
        let pos = |ops: &[UnaryOp], u| ops.iter().position(|&o| o == u);
        let posb = |b| CALLED_BINARY.iter().position(|&o| o == b);
        let nu = CALLED_UNARY.len();
        let nb = CALLED_BINARY.len();
        let i = match self {
            Shim::PointUnary(u) => pos(&CALLED_UNARY, u).map(|i| 2 * i),
            Shim::IntervalUnary(u) => pos(&CALLED_UNARY, u).map(|i| 2 * i + 1),
            Shim::PointBinary(b) => posb(b).map(|i| 2 * nu + 2 * i),
            Shim::IntervalBinary(b) => posb(b).map(|i| 2 * nu + 2 * i + 1),
            Shim::IntervalStepGrad(u) => pos(&STEP_UNARY, u).map(|i| 2 * nu + 2 * nb + i),
            Shim::IntervalDivZero => Some(SHIM_COUNT - 1),
        };
        i.unwrap_or_else(|| unreachable!("no shim {self:?}"))
    }

    /// Symbol name, signature shape and address.
    pub(crate) fn entry(self) -> (String, ShimSig, *const u8) {
        use ShimSig::*;
        let unary = |u: UnaryOp| {
            unary_ptrs!(
                u, Exp, Ln, Sin, Cos, Tan, Asin, Acos, Atan, Sinh, Cosh, Tanh, Floor, Ceil, Round,
                Sign
            )
        };
        let binary = |b: BinaryOp| binary_ptrs!(b, Atan2, Pow, Mod);
        match self {
            Shim::PointUnary(u) => (format!("ibeam_point_{}", u.name()), PointUnary, unary(u).0),
            Shim::IntervalUnary(u) => (
                format!("ibeam_interval_{}", u.name()),
                IntervalUnary,
                unary(u).1,
            ),
            Shim::IntervalStepGrad(u) => (
                format!("ibeam_interval_{}_grad", u.name()),
                IntervalBinary,
                unary(u).2,
            ),
            Shim::PointBinary(b) => (
                format!("ibeam_point_{}", b.name()),
                PointBinary,
                binary(b).0,
            ),
            Shim::IntervalBinary(b) => (
                format!("ibeam_interval_{}", b.name()),
                IntervalBinary,
                binary(b).1,
            ),
            Shim::IntervalDivZero => (
                "ibeam_interval_div_zero".into(),
                IntervalBinary,
                interval_div_zero as *const u8,
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_positions_are_distinct_and_dense() {
        let all: Vec<Shim> = Shim::all().collect();
        assert_eq!(all.len(), SHIM_COUNT);
        for (i, s) in all.iter().enumerate() {
            assert_eq!(s.index(), i, "{s:?}");
        }
        for u in UnaryOp::ALL {
            assert_eq!(UnaryOp::ALL[unary_index(u)], u);
        }
        for b in BinaryOp::ALL {
            assert_eq!(BinaryOp::ALL[b as usize], b);
        }
    }
}
