//! [`JitEvaluator`]: the evaluator kinds of one function, each compiled on
//! first use into a table keyed by [`Kind`].

use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use super::raw::{Code, IntervalBatchFn, IntervalFn, PointBatchFn, PointFn, PointGradFn};
use super::{JitError, Kind, compile, lower};
use crate::eval::{Evaluator, Grad, IntervalGrad};
use crate::interval::Interval;
use crate::ir::Function;

/// Compiled code of one kind. The variant names the kind, so code compiled
/// for one kind is never called as another (three kinds share the
/// interval entry signature).
enum Entry {
    Point(Code<PointFn>),
    PointGrad(Code<PointGradFn>),
    Interval(Code<IntervalFn>),
    IntervalGrad(Code<IntervalFn>),
    IntervalDir(Code<IntervalFn>),
    PointBatch(Code<PointBatchFn>),
    IntervalBatch(Code<IntervalBatchFn>),
}

impl Entry {
    /// Compiles `kind` for `f`: the one place a kind meets its entry type.
    fn compile(kind: Kind, f: &Function, live: &[bool]) -> Result<Entry, JitError> {
        Ok(match kind {
            Kind::Point => Entry::Point(compile(kind, f, live)?),
            Kind::PointGrad => Entry::PointGrad(compile(kind, f, live)?),
            Kind::Interval => Entry::Interval(compile(kind, f, live)?),
            Kind::IntervalGrad => Entry::IntervalGrad(compile(kind, f, live)?),
            Kind::IntervalDir => Entry::IntervalDir(compile(kind, f, live)?),
            Kind::PointBatch => Entry::PointBatch(compile(kind, f, live)?),
            Kind::IntervalBatch => Entry::IntervalBatch(compile(kind, f, live)?),
        })
    }
}

/// A lazily compiled kind and how long its compilation took.
struct Slot {
    code: Result<Entry, JitError>,
    time: Duration,
}

/// Native evaluators of one function, each kind compiled on first use.
///
/// If Cranelift rejects a kind (an internal bug, never bad input: the IR is
/// validated in [`JitEvaluator::new`]), that kind answers with NaN points and
/// whole-line intervals, which are sound; [`JitEvaluator::compile_all`]
/// reports the error.
pub struct JitEvaluator {
    f: Arc<Function>,
    live: Arc<[bool]>,
    slots: [OnceLock<Slot>; Kind::ALL.len()],
}

impl JitEvaluator {
    /// Prepares an evaluator for `f` (validated here); compiles nothing yet.
    pub fn new(f: &Function) -> Result<JitEvaluator, JitError> {
        crate::ir::validate::validate(f).map_err(|e| JitError::new("invalid IR", e))?;
        super::isa()?;
        Ok(JitEvaluator {
            live: lower::live_ops(f).into(),
            f: Arc::new(f.clone()),
            slots: std::array::from_fn(|_| OnceLock::new()),
        })
    }

    /// The function being evaluated.
    pub fn function(&self) -> &Function {
        &self.f
    }

    /// The slot of `kind`, compiled now if it was not yet.
    fn slot(&self, kind: Kind) -> &Slot {
        self.slots[kind as usize].get_or_init(|| {
            let t = Instant::now();
            let code = Entry::compile(kind, &self.f, &self.live);
            Slot {
                code,
                time: t.elapsed(),
            }
        })
    }

    /// The code of `kind`, or None if Cranelift rejected it.
    fn entry(&self, kind: Kind) -> Option<&Entry> {
        self.slot(kind).code.as_ref().ok()
    }

    /// The kinds compiled so far and how long each took to compile.
    pub fn compile_times(&self) -> Vec<(&'static str, Duration)> {
        Kind::ALL
            .into_iter()
            .filter_map(|k| self.slots[k as usize].get().map(|s| (k.name(), s.time)))
            .collect()
    }

    /// Compiles the given kind now (if not yet done).
    pub fn compile(&self, kind: Kind) -> Result<(), JitError> {
        match &self.slot(kind).code {
            Err(e) => Err(e.clone()),
            Ok(_) => Ok(()),
        }
    }

    /// Compiles every kind (for `ibeam ir --stats`) and returns the
    /// compile time of each, or the first error.
    pub fn compile_all(&self) -> Result<Vec<(&'static str, Duration)>, JitError> {
        for kind in Kind::ALL {
            self.compile(kind)?;
        }
        Ok(self.compile_times())
    }
}

impl Evaluator for JitEvaluator {
    fn point(&self, p: [f64; 3]) -> f64 {
        match self.entry(Kind::Point) {
            Some(Entry::Point(c)) => c.call(p),
            _ => f64::NAN,
        }
    }

    fn point_grad(&self, p: [f64; 3]) -> Grad {
        match self.entry(Kind::PointGrad) {
            Some(Entry::PointGrad(c)) => {
                let r = c.call(p);
                Grad {
                    v: r[0],
                    d: [r[1], r[2], r[3]],
                }
            }
            _ => Grad {
                v: f64::NAN,
                d: [f64::NAN; 3],
            },
        }
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        match self.entry(Kind::Interval) {
            Some(Entry::Interval(c)) => c.call_interval(&b),
            _ => Interval::ENTIRE,
        }
    }

    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        match self.entry(Kind::IntervalGrad) {
            Some(Entry::IntervalGrad(c)) => c.call_interval_grad(&b),
            _ => IntervalGrad {
                v: Interval::ENTIRE,
                d: [Interval::ENTIRE; 3],
            },
        }
    }

    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        match self.entry(Kind::IntervalDir) {
            Some(Entry::IntervalDir(c)) => {
                c.call_interval_dir(&[b[0], b[1], b[2], v[0], v[1], v[2]])
            }
            _ => [Interval::ENTIRE; 2],
        }
    }

    fn function(&self) -> Option<&Function> {
        Some(&self.f)
    }

    fn is_native(&self) -> bool {
        true
    }

    fn compile_time(&self) -> Duration {
        self.compile_times().iter().map(|(_, t)| *t).sum()
    }

    /// Evaluates `min(len)` points of the four slices in one native loop.
    fn point_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        match self.entry(Kind::PointBatch) {
            Some(Entry::PointBatch(c)) => c.call(xs, ys, zs, out),
            _ => out.fill(f64::NAN),
        }
    }

    /// Evaluates `min(len)` boxes in one native loop.
    fn interval_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        match self.entry(Kind::IntervalBatch) {
            Some(Entry::IntervalBatch(c)) => c.call(boxes, out),
            _ => out.fill(Interval::ENTIRE),
        }
    }
}
