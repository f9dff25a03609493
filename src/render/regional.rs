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

use super::camera::IBox;
use crate::eval::{Evaluator, Grad, IntervalGrad};
use crate::interval::Interval;
use crate::ir::Function;
use crate::ir::interp::Interpreter;

/// `pruned` on `region`, `whole` elsewhere.
pub(crate) struct Regional {
    /// Where `pruned` equals the whole function.
    pub region: IBox,
    /// The function pruned to `region`, interpreted.
    pub pruned: Interpreter,
    /// The whole function (native code, usually).
    pub whole: Arc<dyn Evaluator>,
}

impl Regional {
    fn holds_box(&self, b: &IBox) -> bool {
        (0..3).all(|i| self.region[i].lo <= b[i].lo && b[i].hi <= self.region[i].hi)
    }

    fn holds_point(&self, p: [f64; 3]) -> bool {
        (0..3).all(|i| self.region[i].contains(p[i]))
    }
}

impl Evaluator for Regional {
    fn point(&self, p: [f64; 3]) -> f64 {
        if self.holds_point(p) {
            self.pruned.point(p)
        } else {
            self.whole.point(p)
        }
    }

    fn point_grad(&self, p: [f64; 3]) -> Grad {
        if self.holds_point(p) {
            self.pruned.point_grad(p)
        } else {
            self.whole.point_grad(p)
        }
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if self.holds_box(&b) {
            self.pruned.interval(b)
        } else {
            self.whole.interval(b)
        }
    }

    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        if self.holds_box(&b) {
            self.pruned.interval_grad(b)
        } else {
            self.whole.interval_grad(b)
        }
    }

    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        if self.holds_box(&b) {
            self.pruned.interval_dir(b, v)
        } else {
            self.whole.interval_dir(b, v)
        }
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
