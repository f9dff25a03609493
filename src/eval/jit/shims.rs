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

/// Every shim: symbol name, signature shape, address. The order within each
/// shape is the order of the arrays in `emit::ShimRefs`.
pub(crate) fn all() -> [(&'static str, ShimSig, *const u8); 13] {
    use ShimSig::*;
    [
        ("ibeam_point_exp", PointUnary, point_exp as *const u8),
        ("ibeam_point_ln", PointUnary, point_ln as *const u8),
        ("ibeam_point_sin", PointUnary, point_sin as *const u8),
        ("ibeam_point_cos", PointUnary, point_cos as *const u8),
        ("ibeam_point_atan2", PointBinary, point_atan2 as *const u8),
        ("ibeam_point_pow", PointBinary, point_pow as *const u8),
        (
            "ibeam_interval_exp",
            IntervalUnary,
            interval_exp as *const u8,
        ),
        ("ibeam_interval_ln", IntervalUnary, interval_ln as *const u8),
        (
            "ibeam_interval_sin",
            IntervalUnary,
            interval_sin as *const u8,
        ),
        (
            "ibeam_interval_cos",
            IntervalUnary,
            interval_cos as *const u8,
        ),
        (
            "ibeam_interval_atan2",
            IntervalBinary,
            interval_atan2 as *const u8,
        ),
        (
            "ibeam_interval_pow",
            IntervalBinary,
            interval_pow as *const u8,
        ),
        (
            "ibeam_interval_div_zero",
            IntervalBinary,
            interval_div_zero as *const u8,
        ),
    ]
}
