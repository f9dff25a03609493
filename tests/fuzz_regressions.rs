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

/// fuzz target `prune`: a function pruned to this box gave NaN at a corner
/// where the whole function gives 0.445. `-7.25 / sqrt(-0)` is `+inf` at a
/// point while its interval over `[-0, 5e-324]` is `[-inf, -1.8e308]`, so a
/// `min` was decided for a branch whose point value is not in its interval
/// (now the `contained` fact of `ir::prune`).
#[test]
fn pruned_function_keeps_its_bits_at_a_box_corner() {
    use ibeam::eval::Single;
    use ibeam::eval::interp::Interpreter;
    use ibeam::interval::Interval;
    let f = random_function(108843400875938916, 8);
    let b = [
        Interval::new(-0.6470588235294117, -0.1470588235294117),
        Interval::new(-0.8588235294117648, 2.1411764705882352),
        Interval::new(-0.0117647058823529, 0.4882352941176471),
    ];
    let p = [-0.6470588235294117, 2.1411764705882352, -0.0117647058823529];
    let whole = Interpreter::new(f.clone()).point(p);
    if let Some(pruned) = ibeam::ir::prune::prune(&f, b) {
        let v = Interpreter::new(pruned.function).point(p);
        assert!(
            v.to_bits() == whole.to_bits() || (v.is_nan() && whole.is_nan()),
            "{whole} vs {v}"
        );
    }
}

/// fuzz target `prune`: over a box where a `min(0, g)` always picks the
/// constant 0, the rebuilt function held `max(0, -0)` where the whole one
/// has `max(-0, min(…))`: the builder put the operands of `max` in its
/// canonical order, and `max` of two zeros returns its second operand, so
/// the pruned function gave -0 where the whole one gives 0. `min`/`max`
/// are no longer reordered. (The fuzzer's function came from a random
/// seed whose functions changed when ops were added; this is its shape.)
#[test]
fn pruning_keeps_the_sign_of_a_zero_from_max() {
    use ibeam::eval::Single;
    use ibeam::eval::interp::Interpreter;
    use ibeam::interval::Interval;
    use ibeam::ir::{BinaryOp, Builder, UnaryOp, Var};
    let mut bld = Builder::new();
    let y = bld.var(Var::Y);
    let y2 = bld.unary(UnaryOp::Square, y);
    let one = bld.constant(1.0);
    let g = bld.binary(BinaryOp::Add, y2, one);
    let zero = bld.constant(0.0);
    let m = bld.binary(BinaryOp::Min, zero, g);
    let neg_zero = bld.constant(-0.0);
    let r = bld.binary(BinaryOp::Max, neg_zero, m);
    let f = bld.finish(r);
    let b = [
        Interval::point(-3.0),
        Interval::new(-0.31764705882352917, 0.6078431372549022),
        Interval::point(-0.22352941176470598),
    ];
    let p = [-3.0, -0.31764705882352917, -0.22352941176470598];
    let pruned = ibeam::ir::prune::prune(&f, b).expect("the min is decided");
    let whole = Interpreter::new(f).point(p);
    let v = Interpreter::new(pruned.function).point(p);
    assert_eq!(whole.to_bits(), 0f64.to_bits());
    assert_eq!(v.to_bits(), whole.to_bits(), "{whole:e} vs {v:e}");
}
