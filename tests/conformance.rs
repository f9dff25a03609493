//! The evaluator conformance suite (tests/common/suite.rs) run on every
//! evaluator: the reference interpreter, a tape run over its registers
//! (`eval::taped`), the JIT, and the regional evaluator (a function pruned to a region, the whole function
//! interpreted outside it). The interpreter, whose rules are the suite's
//! references, is also checked against references independent of them
//! (tests/common/independent.rs).

#[macro_use]
mod common;

use std::sync::Arc;

use ibeam::eval::Evaluator;
use ibeam::eval::interp::Interpreter;
use ibeam::eval::jit::JitEvaluator;
use ibeam::eval::regional::{Parent, Regional};
use ibeam::eval::tape::{Tape, Workspace};
use ibeam::interval::Interval;
use ibeam::ir::Function;
use ibeam::ir::random::{Rng, random_function};

use common::{EDGE_VALUES, random_box};

mod interp {
    use super::*;
    use common::independent;

    conformance_suite!(
        |f: &Function| -> Arc<dyn Evaluator> { Arc::new(Interpreter::new(f.clone())) },
        exact_intervals: true
    );

    // The suite's references are `ir::semantics`, the very rules the
    // interpreter runs, so for it those comparisons are identities; these
    // compare it with references written out in the tests instead
    // (tests/common/independent.rs).

    #[test]
    fn point_ops_match_std() {
        independent::check_points(&make);
    }

    #[test]
    fn derivatives_match_calculus() {
        independent::check_derivatives(&make);
    }

    #[test]
    fn intervals_hold_std_values_and_are_tight() {
        independent::intervals::check_intervals(&make);
    }

    #[test]
    fn random_functions_match_std_op_by_op() {
        independent::intervals::check_random_functions(0..300);
    }
}

mod taped {
    use super::*;
    use ibeam::eval::taped::TapeEvaluator;

    conformance_suite!(
        |f: &Function| -> Arc<dyn Evaluator> { Arc::new(TapeEvaluator::of_function(f)) },
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
    let whole = Tape::new(f);
    let mut ws = Workspace::default();
    let pruned = whole.prune(REGION, &mut ws).map_or(whole, |p| p.tape);
    Arc::new(Regional::new(
        REGION,
        pruned,
        Parent::Whole(Arc::new(Interpreter::new(f.clone()))),
    ))
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
                let whole = Tape::new(&f);
                whole
                    .prune(REGION, &mut Workspace::default())
                    .is_some_and(|p| p.tape.len() < whole.len())
            })
            .count();
        assert!(pruned >= 30, "only {pruned} of 300 random functions pruned");
    }

    /// The suite's boxes and points fall on both sides of the region, so
    /// both the pruned function and the fallback answer.
    #[test]
    fn the_suite_reaches_both_sides_of_the_region() {
        let within =
            |b: [Interval; 3]| (0..3).all(|k| REGION[k].lo <= b[k].lo && b[k].hi <= REGION[k].hi);
        let mut rng = Rng::new(7);
        let boxes: Vec<bool> = (0..1000).map(|_| within(random_box(&mut rng))).collect();
        let inside = boxes.iter().filter(|&&b| b).count();
        assert!(
            inside >= 50 && boxes.len() - inside >= 50,
            "{inside} of 1000 boxes inside"
        );
        let points: Vec<bool> = EDGE_VALUES
            .iter()
            .flat_map(|&x| EDGE_VALUES.map(|y| within([x, y, 0.5].map(Interval::point))))
            .collect();
        let inside = points.iter().filter(|&&b| b).count();
        assert!(
            inside >= 25 && points.len() - inside >= 25,
            "{inside} edge points inside"
        );
    }
}
