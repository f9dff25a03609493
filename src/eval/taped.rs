//! An evaluator that runs a [`Tape`]: values, intervals and their
//! derivatives in one pass over its registers, batches column by column.
//!
//! Pruned tapes answer most evaluations of a render (see
//! [`crate::eval::regional`]); interpreting them through the tape instead
//! of the SSA function spends one slot per register rather than one per op,
//! and lets a batch of points or boxes run each op over the whole batch.
//! Every answer is the reference interpreter's bits (both call the rules
//! of [`crate::ir::semantics`]); the conformance suite checks it.

use crate::eval::tape::{Tape, with_workspace};
use crate::eval::{Bulk, Grad, IntervalGrad, Single, Specialise};
use crate::interval::Interval;
use crate::ir::Function;

/// Batches run this many inputs per pass, so that the registers' columns
/// (registers × inputs values) stay in cache whatever the caller's batch.
const CHUNK: usize = 256;

/// Calls `f` on each run of at most [`CHUNK`] points: the coordinate
/// columns' slices and the matching slice of `out`.
fn by_chunks<T>(
    [xs, ys, zs]: [&[f64]; 3],
    out: &mut [T],
    mut f: impl FnMut([&[f64]; 3], &mut [T]),
) {
    for (i, out) in out.chunks_mut(CHUNK).enumerate() {
        let r = i * CHUNK..i * CHUNK + out.len();
        f([&xs[r.clone()], &ys[r.clone()], &zs[r]], out);
    }
}

/// A [`Tape`] as an [`Evaluator`].
pub struct TapeEvaluator {
    tape: Tape,
}

impl TapeEvaluator {
    /// An evaluator running `tape`.
    pub fn new(tape: Tape) -> TapeEvaluator {
        TapeEvaluator { tape }
    }

    /// An evaluator running the tape of `f`.
    pub fn of_function(f: &Function) -> TapeEvaluator {
        TapeEvaluator::new(Tape::new(f))
    }

    /// The tape it runs.
    pub fn tape(&self) -> &Tape {
        &self.tape
    }
}

impl Single for TapeEvaluator {
    fn point(&self, p: [f64; 3]) -> f64 {
        with_workspace(|ws| self.tape.point(p, ws))
    }

    fn point_grad(&self, p: [f64; 3]) -> Grad {
        with_workspace(|ws| self.tape.point_grad(p, ws))
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        with_workspace(|ws| self.tape.interval(b, ws))
    }

    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        with_workspace(|ws| self.tape.interval_grad(b, ws))
    }

    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        with_workspace(|ws| self.tape.interval_dir(b, v, ws))
    }
}

impl Bulk for TapeEvaluator {
    fn point_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        with_workspace(|ws| {
            by_chunks([xs, ys, zs], out, |cols, out| {
                self.tape.point_batch(cols, out, ws)
            })
        })
    }

    fn point_grad_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [Grad]) {
        with_workspace(|ws| {
            by_chunks([xs, ys, zs], out, |cols, out| {
                self.tape.point_grad_batch(cols, out, ws)
            })
        })
    }

    fn interval_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        with_workspace(|ws| {
            for (b, out) in boxes.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
                self.tape.interval_batch(b, out, ws);
            }
        })
    }
}

impl Specialise for TapeEvaluator {
    fn function(&self) -> Option<&Function> {
        Some(self.tape.function())
    }
}
