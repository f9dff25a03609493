//! Inputs the fuzz targets (fuzz/fuzz_targets/) found crashing, minimised
//! and replayed through the same library calls, so that a plain
//! `cargo test` keeps them fixed without cargo-fuzz.

use ibeam::eval::{EvalKind, build_evaluators};
use ibeam::ir::passes;
use ibeam::ir::random::random_function;

/// fuzz target `prune` (input: seed 8574853690238485660, depth 12,
/// simplified first): `passes::simplify` panicked with "attempt to
/// subtract with overflow" in `Terms::pays` (src/ir/passes/terms.rs),
/// `self.entries.len() - 1` on a sum left with no terms.
#[test]
fn simplify_random_function_from_prune_fuzzer() {
    let f = random_function(8574853690238485660, 12);
    let _ = passes::simplify(&f);
}

/// fuzz target `vm`, minimised: `0 * y` loads, and building its
/// evaluators (which simplifies it) panicked at the same place as above:
/// a product by the constant 0 is a sum whose one coefficient is 0, so
/// `flatten` keeps no term at all.
#[test]
fn simplify_vm_model_times_zero() {
    let text = "_0 var-y\n_1 const 0\n_2 mul _1 _0\n";
    let scene = ibeam::lang::load_scene_source("fuzz.vm", text).expect("loads");
    build_evaluators(&scene, EvalKind::Interp).expect("valid IR");
}
