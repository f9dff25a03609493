//! `extern "C"` entry points through which native code calls the Rust
//! transcendentals, so that JIT and interpreter give identical bits.
//!
//! Intervals travel as two f64 arguments and come back as a `#[repr(C)]`
//! [`Interval`] (two doubles, returned in xmm0/xmm1 by the C ABI, which is
//! how Cranelift's two-f64-result signature reads them).

use crate::interval::Interval;
use crate::ir::semantics::{point_binary, point_unary};
use crate::ir::{BinaryOp, UnaryOp};

extern "C" fn point_exp(a: f64) -> f64 {
    point_unary(UnaryOp::Exp, a)
}
extern "C" fn point_ln(a: f64) -> f64 {
    point_unary(UnaryOp::Ln, a)
}
extern "C" fn point_sin(a: f64) -> f64 {
    point_unary(UnaryOp::Sin, a)
}
extern "C" fn point_cos(a: f64) -> f64 {
    point_unary(UnaryOp::Cos, a)
}
extern "C" fn point_atan2(a: f64, b: f64) -> f64 {
    point_binary(BinaryOp::Atan2, a, b)
}
extern "C" fn point_pow(a: f64, b: f64) -> f64 {
    point_binary(BinaryOp::Pow, a, b)
}
extern "C" fn interval_exp(lo: f64, hi: f64) -> Interval {
    Interval::new(lo, hi).exp()
}
extern "C" fn interval_ln(lo: f64, hi: f64) -> Interval {
    Interval::new(lo, hi).ln()
}
extern "C" fn interval_sin(lo: f64, hi: f64) -> Interval {
    Interval::new(lo, hi).sin()
}
extern "C" fn interval_cos(lo: f64, hi: f64) -> Interval {
    Interval::new(lo, hi).cos()
}
extern "C" fn interval_atan2(alo: f64, ahi: f64, blo: f64, bhi: f64) -> Interval {
    Interval::new(alo, ahi).atan2(Interval::new(blo, bhi))
}
extern "C" fn interval_pow(alo: f64, ahi: f64, blo: f64, bhi: f64) -> Interval {
    Interval::new(alo, ahi).pow(Interval::new(blo, bhi))
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
/// [`Shim::ALL`] is its discriminant, which keys per-shim tables.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Shim {
    PointExp,
    PointLn,
    PointSin,
    PointCos,
    PointAtan2,
    PointPow,
    IntervalExp,
    IntervalLn,
    IntervalSin,
    IntervalCos,
    IntervalAtan2,
    IntervalPow,
    /// `Interval::div_by_zero_part`, the rare branch of interval division.
    IntervalDivZero,
}

/// Number of shims.
pub(crate) const SHIM_COUNT: usize = 13;

impl Shim {
    /// Every shim, in discriminant order.
    pub(crate) const ALL: [Shim; SHIM_COUNT] = [
        Shim::PointExp,
        Shim::PointLn,
        Shim::PointSin,
        Shim::PointCos,
        Shim::PointAtan2,
        Shim::PointPow,
        Shim::IntervalExp,
        Shim::IntervalLn,
        Shim::IntervalSin,
        Shim::IntervalCos,
        Shim::IntervalAtan2,
        Shim::IntervalPow,
        Shim::IntervalDivZero,
    ];

    /// Symbol name, signature shape and address.
    pub(crate) fn entry(self) -> (&'static str, ShimSig, *const u8) {
        use ShimSig::*;
        match self {
            Shim::PointExp => ("ibeam_point_exp", PointUnary, point_exp as *const u8),
            Shim::PointLn => ("ibeam_point_ln", PointUnary, point_ln as *const u8),
            Shim::PointSin => ("ibeam_point_sin", PointUnary, point_sin as *const u8),
            Shim::PointCos => ("ibeam_point_cos", PointUnary, point_cos as *const u8),
            Shim::PointAtan2 => ("ibeam_point_atan2", PointBinary, point_atan2 as *const u8),
            Shim::PointPow => ("ibeam_point_pow", PointBinary, point_pow as *const u8),
            Shim::IntervalExp => (
                "ibeam_interval_exp",
                IntervalUnary,
                interval_exp as *const u8,
            ),
            Shim::IntervalLn => ("ibeam_interval_ln", IntervalUnary, interval_ln as *const u8),
            Shim::IntervalSin => (
                "ibeam_interval_sin",
                IntervalUnary,
                interval_sin as *const u8,
            ),
            Shim::IntervalCos => (
                "ibeam_interval_cos",
                IntervalUnary,
                interval_cos as *const u8,
            ),
            Shim::IntervalAtan2 => (
                "ibeam_interval_atan2",
                IntervalBinary,
                interval_atan2 as *const u8,
            ),
            Shim::IntervalPow => (
                "ibeam_interval_pow",
                IntervalBinary,
                interval_pow as *const u8,
            ),
            Shim::IntervalDivZero => (
                "ibeam_interval_div_zero",
                IntervalBinary,
                interval_div_zero as *const u8,
            ),
        }
    }

    /// The point and interval shims of a transcendental one-operand op.
    pub(crate) fn of_unary(op: UnaryOp) -> Option<(Shim, Shim)> {
        match op {
            UnaryOp::Exp => Some((Shim::PointExp, Shim::IntervalExp)),
            UnaryOp::Ln => Some((Shim::PointLn, Shim::IntervalLn)),
            UnaryOp::Sin => Some((Shim::PointSin, Shim::IntervalSin)),
            UnaryOp::Cos => Some((Shim::PointCos, Shim::IntervalCos)),
            _ => None,
        }
    }

    /// The point and interval shims of a transcendental two-operand op.
    pub(crate) fn of_binary(op: BinaryOp) -> Option<(Shim, Shim)> {
        match op {
            BinaryOp::Atan2 => Some((Shim::PointAtan2, Shim::IntervalAtan2)),
            BinaryOp::Pow => Some((Shim::PointPow, Shim::IntervalPow)),
            _ => None,
        }
    }
}
