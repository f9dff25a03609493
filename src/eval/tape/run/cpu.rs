//! Runtime CPU dispatch of the tapes' hot loops. The default build targets
//! the x86-64 baseline (SSE2), which every user's CPU runs; where the CPU
//! has AVX2 and FMA, the passes over a tape run as a second copy of the
//! same code compiled for them (the `multiversion` crate generates both
//! copies and picks one at run time; no `unsafe` of ours). Setting the
//! environment variable `IBEAM_CPU=baseline` forces the baseline copy, so
//! that CI tests both.
//!
//! Why both copies give the same bits, outward rounding included: every
//! interval bound is computed with IEEE `+ - * / sqrt` in round-to-nearest
//! and then moved outward (`crate::interval::up` / `down`); with AVX2 the
//! same operations run on wider registers, each lane rounded exactly as
//! the scalar one. FMA could change bits (`a * b + c` rounded once instead
//! of twice, so a bound moved out from the twice-rounded value would no
//! longer be the one the rules were proven for), but Rust never contracts
//! `a * b + c` into a fused multiply-add on its own (LLVM gets no
//! fast-math flags), so enabling the feature changes no instruction the
//! interval rules write; an explicit `f64::mul_add` is correctly rounded
//! on both copies (in software on the baseline). The conformance and
//! tape tests run on both copies (`.ci/run`) and require the reference
//! interpreter's bits from each.

use std::sync::LazyLock;

use multiversion::multiversion;

/// The environment variable that picks the path: `baseline` forces the
/// x86-64 baseline copy; anything else, or unset, lets the CPU decide.
pub(in crate::eval::tape) const CPU_ENV: &str = "IBEAM_CPU";

/// Whether `IBEAM_CPU=baseline` (read once per process).
static BASELINE: LazyLock<bool> =
    LazyLock::new(|| std::env::var(CPU_ENV).is_ok_and(|v| v.trim() == "baseline"));

/// Runs `f`, the body of a hot pass (its callees `#[inline(always)]`), in
/// the copy compiled for this CPU: AVX2 and FMA where present and not
/// switched off, the baseline otherwise.
#[inline(always)]
pub(super) fn dispatch<R>(f: impl FnOnce() -> R) -> R {
    if *BASELINE { f() } else { fast(f) }
}

/// `f` inlined into a copy per target; the first the CPU supports runs.
#[multiversion(targets("x86_64+avx2+fma"))]
fn fast<R, F: FnOnce() -> R>(f: F) -> R {
    f()
}

#[cfg(test)]
/// The path [`dispatch`] takes in this process: `"avx2+fma"` or
/// `"baseline"`.
pub(in crate::eval::tape) fn path() -> &'static str {
    if !*BASELINE && avx2_fma() {
        "avx2+fma"
    } else {
        "baseline"
    }
}

#[cfg(test)]
/// Whether this CPU has AVX2 and FMA (what [`fast`]'s dispatcher checks).
pub(in crate::eval::tape) fn avx2_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
