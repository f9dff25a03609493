//! The evaluator conformance suite (tests/common/suite.rs) run on every
//! evaluator: the reference interpreter, the JIT, and the regional
//! evaluator (a function pruned to a region, the whole function
//! interpreted outside it).

#[macro_use]
mod common;

use std::sync::Arc;

use ibeam::eval::Evaluator;
use ibeam::eval::interp::Interpreter;
use ibeam::eval::jit::JitEvaluator;
use ibeam::eval::regional::Regional;
use ibeam::interval::Interval;
use ibeam::ir::Function;
use ibeam::ir::prune::prune;
use ibeam::ir::random::random_function;

mod interp {
    use super::*;

    conformance_suite!(
        |f: &Function| -> Arc<dyn Evaluator> { Arc::new(Interpreter::new(f.clone())) },
        exact_intervals: true
    );
}

mod jit {
    use super::*;

    conformance_suite!(
        |f: &Function| -> Arc<dyn Evaluator> { Arc::new(JitEvaluator::new(f).expect("compiles")) },
        exact_intervals: true
    );
}

/// The region the regional evaluator is pruned to: the suite's points and
/// boxes fall inside it (most edge arguments near 0, z = 0 or 0.5 of the
/// single-op checks, many random boxes) and outside it alike.
const REGION: [Interval; 3] = [
    Interval { lo: -1.5, hi: 2.0 },
    Interval { lo: -1.0, hi: 2.5 },
    Interval { lo: -0.5, hi: 1.0 },
];

/// `f` pruned to [`REGION`] (itself where nothing is decided there), with
/// the whole function interpreted outside the region.
///
/// The fallback is the interpreter, not the JIT: the JIT's derivative of
/// |a| at a = 0 is +da (over a box with lower end 0, da), the reference
/// rules' is 0 (`[0, 1]·da`), so with a JIT fallback the interval gradient
/// of a box outside the region can miss the point gradient, at a point
/// inside it, of an `abs` whose argument is exactly 0 (e.g. |x| over
/// x = [-0, -0], y unbounded, against the point (-0, 0, 0)).
fn regional(f: &Function) -> Arc<dyn Evaluator> {
    let pruned = prune(f, REGION).map_or_else(|| f.clone(), |p| p.function);
    Arc::new(Regional {
        region: REGION,
        pruned: Interpreter::new(pruned),
        whole: Arc::new(Interpreter::new(f.clone())),
    })
}

mod regional {
    use super::*;

    // Pruned functions give tighter intervals than the reference rules, so
    // only containment is checked.
    conformance_suite!(super::regional, exact_intervals: false);

    /// The suite's random functions do get pruned on the region (so the
    /// regional instance checks pruned functions, not copies).
    #[test]
    fn random_functions_are_pruned_on_the_region() {
        let pruned = (0..300)
            .filter(|&seed| {
                let f = random_function(seed, 8);
                prune(&f, REGION).is_some_and(|p| p.function.len() < f.len())
            })
            .count();
        assert!(pruned >= 30, "only {pruned} of 300 random functions pruned");
    }
}
