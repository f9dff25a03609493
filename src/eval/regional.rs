//! An evaluator that answers with a function pruned to a region (see
//! [`crate::ir::prune`]) for points and boxes inside that region, and
//! with the whole function everywhere else.
//!
//! The pruned function gives the same bits as the whole one on its region,
//! so the choice is invisible in point values; intervals over boxes inside
//! the region come out tighter. Falling back outside the region is what
//! lets the tracer prune to a block's beam near the surface while single
//! rays still sweep from where they enter the bounds.

use std::sync::Arc;

use crate::eval::interp::Interpreter;
use crate::eval::{Evaluator, Grad, IntervalGrad};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_within, point_box};
use crate::ir::Function;

/// `pruned` on `region`, `whole` elsewhere.
pub struct Regional {
    /// Where `pruned` equals the whole function.
    pub region: IBox,
    /// The function pruned to `region`, interpreted.
    pub pruned: Interpreter,
    /// The whole function (native code, usually).
    pub whole: Arc<dyn Evaluator>,
}

impl Regional {
    /// The evaluator for a box: the pruned one if the box lies in the
    /// region.
    fn for_box(&self, b: &IBox) -> &dyn Evaluator {
        if box_within(b, &self.region) {
            &self.pruned
        } else {
            self.whole.as_ref()
        }
    }

    /// The evaluator for a point (see [`Self::for_box`]).
    fn for_point(&self, p: [f64; 3]) -> &dyn Evaluator {
        self.for_box(&point_box(p))
    }
}

impl Evaluator for Regional {
    fn point(&self, p: [f64; 3]) -> f64 {
        self.for_point(p).point(p)
    }

    fn point_grad(&self, p: [f64; 3]) -> Grad {
        self.for_point(p).point_grad(p)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        self.for_box(&b).interval(b)
    }

    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        self.for_box(&b).interval_grad(b)
    }

    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        self.for_box(&b).interval_dir(b, v)
    }

    /// The pruned function (exact on [`Evaluator::valid_region`]).
    fn function(&self) -> Option<&Function> {
        Some(self.pruned.function())
    }

    fn valid_region(&self) -> Option<IBox> {
        Some(self.region)
    }

    fn whole(&self) -> Option<&Arc<dyn Evaluator>> {
        Some(&self.whole)
    }
}
