//! Which compiled path the Rust tape passes take: the baseline build's,
//! or clones compiled for AVX2 and FMA that `multiversion` picks at run
//! time on CPUs that have them (the JIT already compiles for the host).
//!
//! Both paths run the same source, and Rust never fuses a product and a
//! sum into an FMA unless the code asks for one (`mul_add`, which the
//! interval rules never call), so both give the same bits: the clones
//! gain from the wider encodings and registers, not from other rounding.
//! The tape tests check it path against path. `IBEAM_CPU=baseline` forces
//! the baseline path for a whole process (CI runs the conformance suite
//! so).

use std::sync::OnceLock;

/// A compiled path of the tape passes.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum CpuPath {
    /// Code for the target's baseline (what `cargo build --release`
    /// compiles for with no CPU flags).
    Baseline,
    /// The AVX2 and FMA clones where the CPU has both, else the baseline
    /// code again.
    Wide,
}

/// The path this process takes: [`CpuPath::Baseline`] when the
/// environment variable `IBEAM_CPU` is `baseline`, else [`CpuPath::Wide`].
pub fn path() -> CpuPath {
    static PATH: OnceLock<CpuPath> = OnceLock::new();
    *PATH.get_or_init(|| match std::env::var("IBEAM_CPU") {
        Ok(v) if v.eq_ignore_ascii_case("baseline") => CpuPath::Baseline,
        _ => CpuPath::Wide,
    })
}

/// Whether this CPU runs the AVX2 and FMA clones under [`CpuPath::Wide`].
pub fn wide_clones_run() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
