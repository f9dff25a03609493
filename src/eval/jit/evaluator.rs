//! [`JitEvaluator`]: the evaluator kinds of one function, each compiled on
//! first use into a table keyed by [`Kind`].

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use super::raw::{Code, IntervalBatchFn, IntervalFn, PointBatchFn, PointFn, PointGradFn};
use super::{JitError, Kind, compile, lower};
use crate::eval::taped::TapeEvaluator;
use crate::eval::{Bulk, Grad, IntervalGrad, Single, Specialise};
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

/// A lazily compiled kind, how long its compilation took, and whether a
/// caller waited for it (compiled on the calling thread).
struct Slot {
    code: Result<Entry, JitError>,
    time: Duration,
    // When it started, if a caller waited for it.
    waited: Option<Instant>,
}

/// The evaluator's shared state: background compilations hold it too.
struct Inner {
    f: Arc<Function>,
    live: Arc<[bool]>,
    slots: [OnceLock<Slot>; Kind::ALL.len()],
    // Whether a background compilation of each kind has been started.
    started: [AtomicBool; Kind::ALL.len()],
    // Calls of each kind the tape answered in the background mode (a
    // batch counts its length), toward `COMPILE_AFTER_CALLS`.
    calls: [AtomicU64; Kind::ALL.len()],
    // Answers for the kinds still compiling in the background (and the
    // derivative kinds of a long function): the function's tape, the
    // reference rules over registers.
    interp: OnceLock<TapeEvaluator>,
    // More live ops than `DERIVATIVES_MAX_OPS` (counted once, not per call).
    long: bool,
}

impl Inner {
    /// The slot of `kind`, compiled now if it was not yet.
    fn slot(&self, kind: Kind, waited: bool) -> &Slot {
        self.slots[kind as usize].get_or_init(|| {
            let t = Instant::now();
            let code = Entry::compile(kind, &self.f, &self.live);
            Slot {
                code,
                time: t.elapsed(),
                waited: waited.then_some(t),
            }
        })
    }
}

/// Functions with more live ops than this never compile their derivative
/// kinds in the background mode: those are not bit for bit the
/// interpreter's (rounding order in the chain rules), so they cannot be
/// swapped in once compiled, and compile at first use on the calling
/// thread, which waits. The function's tape ([`TapeEvaluator`], the
/// interpreter's rules and bits) answers them. Functions this long are
/// unions whose work runs on pruned tapes: 100 spheres (1,403 ops) asked
/// the whole function for 30 derivatives in a 1024² render and waited
/// 90–200 ms for two derivative kinds to compile. Colonnade (795 ops)
/// asks 2,575, which its tape answers in less time than the 120–380 ms its
/// render waited for them to compile (with the same images).
pub const DERIVATIVES_MAX_OPS: usize = 512;

/// Calls of one kind (a batch counts each box or point) that the tape
/// answers in the background mode before that kind starts compiling.
///
/// Ski rental: compiling costs about as much per op as this many tape
/// evaluations per op (Cranelift 40–50 µs per op and kind, a tape's
/// interval op 10–15 ns), so a kind is compiled once the tape has spent
/// about what compiling costs, and a function asked less never is; either
/// way the time spent is at most twice the better choice's. Renders of
/// large unions ask the whole function a handful of times (2 interval
/// calls and 16 point batches for 1000 spheres at 1024², all else on
/// pruned tapes), yet compiled it for 1.2 s of a core beside the render;
/// colonnade asks 13,769 intervals and compiles early in its render.
pub const COMPILE_AFTER_CALLS: u64 = 3000;

/// Native evaluators of one function, each kind compiled on first use.
///
/// If Cranelift rejects a kind (an internal bug, never bad input: the IR is
/// validated in [`JitEvaluator::new`]), that kind answers with NaN points and
/// whole-line intervals, which are sound; [`JitEvaluator::compile_all`]
/// reports the error.
///
/// By default a kind compiles on the calling thread at its first use.
/// [`JitEvaluator::in_background`] makes the kinds whose answers are the
/// interpreter's bit for bit (point, interval and their batches) compile
/// on a thread of their own instead, once the function's tape has
/// answered [`COMPILE_AFTER_CALLS`] calls of the kind, the tape answering
/// until the code is ready: a render never waits for them, and its pixels
/// do not depend on when the code arrives.
pub struct JitEvaluator {
    inner: Arc<Inner>,
    background: bool,
}

/// What answers one call: native code, or the interpreter while it
/// compiles (or instead of it).
enum Answer<'a> {
    Native(&'a Entry),
    Interpreted(&'a TapeEvaluator),
    Failed,
}

impl JitEvaluator {
    /// Prepares an evaluator for `f` (validated here); compiles nothing yet.
    pub fn new(f: &Function) -> Result<JitEvaluator, JitError> {
        crate::ir::validate::validate(f).map_err(|e| JitError::new("invalid IR", e))?;
        super::isa()?;
        let live: Arc<[bool]> = lower::live_ops(f).into();
        let long = live.iter().filter(|&&l| l).count() > DERIVATIVES_MAX_OPS;
        Ok(JitEvaluator {
            inner: Arc::new(Inner {
                long,
                live,
                f: Arc::new(f.clone()),
                slots: std::array::from_fn(|_| OnceLock::new()),
                started: std::array::from_fn(|_| AtomicBool::new(false)),
                calls: std::array::from_fn(|_| AtomicU64::new(0)),
                interp: OnceLock::new(),
            }),
            background: false,
        })
    }

    /// The same evaluator, compiling in the background (see the type's
    /// doc); functions over [`DERIVATIVES_MAX_OPS`] live ops also leave
    /// their derivative kinds to the interpreter.
    pub fn in_background(mut self) -> JitEvaluator {
        self.background = true;
        self
    }

    /// The function being evaluated.
    pub fn function(&self) -> &Function {
        &self.inner.f
    }

    /// The code of `kind`, compiled now if it was not yet, or None if
    /// Cranelift rejected it.
    fn entry(&self, kind: Kind) -> Option<&Entry> {
        self.inner.slot(kind, true).code.as_ref().ok()
    }

    /// What answers `kind` for a call of `n` points or boxes now: its code
    /// if compiled; in the background mode, the interpreter while a kind
    /// exact to its bits has not been asked enough to compile, or
    /// compiles, and always for the derivative kinds of a long function.
    fn answer(&self, kind: Kind, n: usize) -> Answer<'_> {
        if !self.background {
            return self.entry(kind).map_or(Answer::Failed, Answer::Native);
        }
        let exact = matches!(
            kind,
            Kind::Point | Kind::Interval | Kind::PointBatch | Kind::IntervalBatch
        );
        if !exact {
            if self.inner.long {
                return Answer::Interpreted(self.interpreter());
            }
            return self.entry(kind).map_or(Answer::Failed, Answer::Native);
        }
        if let Some(slot) = self.inner.slots[kind as usize].get() {
            return slot.code.as_ref().map_or(Answer::Failed, Answer::Native);
        }
        let asked = self.inner.calls[kind as usize].fetch_add(n as u64, Ordering::Relaxed);
        if asked + n as u64 >= COMPILE_AFTER_CALLS
            && !self.inner.started[kind as usize].swap(true, Ordering::AcqRel)
        {
            let inner = Arc::clone(&self.inner);
            let spawned = std::thread::Builder::new()
                .name(format!("ibeam-jit-{}", kind.name()))
                .spawn(move || {
                    inner.slot(kind, false);
                });
            if spawned.is_err() {
                // No thread to compile on: compile here, as without the mode.
                return self.entry(kind).map_or(Answer::Failed, Answer::Native);
            }
        }
        Answer::Interpreted(self.interpreter())
    }

    fn interpreter(&self) -> &TapeEvaluator {
        self.inner
            .interp
            .get_or_init(|| TapeEvaluator::of_function(&self.inner.f))
    }

    /// The kinds compiled so far and how long each took to compile.
    pub fn compile_times(&self) -> Vec<(&'static str, Duration)> {
        Kind::ALL
            .into_iter()
            .filter_map(|k| {
                self.inner.slots[k as usize]
                    .get()
                    .map(|s| (k.name(), s.time))
            })
            .collect()
    }

    /// Compiles the given kind now (if not yet done).
    pub fn compile(&self, kind: Kind) -> Result<(), JitError> {
        match &self.inner.slot(kind, true).code {
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

impl Single for JitEvaluator {
    fn point(&self, p: [f64; 3]) -> f64 {
        match self.answer(Kind::Point, 1) {
            Answer::Native(Entry::Point(c)) => c.call(p),
            Answer::Interpreted(i) => i.point(p),
            _ => f64::NAN,
        }
    }

    fn point_grad(&self, p: [f64; 3]) -> Grad {
        match self.answer(Kind::PointGrad, 1) {
            Answer::Native(Entry::PointGrad(c)) => {
                let r = c.call(p);
                Grad {
                    v: r[0],
                    d: [r[1], r[2], r[3]],
                }
            }
            Answer::Interpreted(i) => i.point_grad(p),
            _ => Grad {
                v: f64::NAN,
                d: [f64::NAN; 3],
            },
        }
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        match self.answer(Kind::Interval, 1) {
            Answer::Native(Entry::Interval(c)) => c.call_interval(&b),
            Answer::Interpreted(i) => i.interval(b),
            _ => Interval::ENTIRE,
        }
    }

    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        match self.answer(Kind::IntervalGrad, 1) {
            Answer::Native(Entry::IntervalGrad(c)) => c.call_interval_grad(&b),
            Answer::Interpreted(i) => i.interval_grad(b),
            _ => IntervalGrad {
                v: Interval::ENTIRE,
                d: [Interval::ENTIRE; 3],
            },
        }
    }

    fn interval_grad_interpreted(&self, b: [Interval; 3]) -> IntervalGrad {
        self.interpreter().interval_grad(b)
    }

    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        match self.answer(Kind::IntervalDir, 1) {
            Answer::Native(Entry::IntervalDir(c)) => {
                c.call_interval_dir(&[b[0], b[1], b[2], v[0], v[1], v[2]])
            }
            Answer::Interpreted(i) => i.interval_dir(b, v),
            _ => [Interval::ENTIRE; 2],
        }
    }
}

impl Bulk for JitEvaluator {
    /// Evaluates `min(len)` points of the four slices in one native loop.
    fn point_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        match self.answer(Kind::PointBatch, out.len()) {
            Answer::Native(Entry::PointBatch(c)) => c.call(xs, ys, zs, out),
            Answer::Interpreted(i) => i.point_batch(xs, ys, zs, out),
            _ => out.fill(f64::NAN),
        }
    }

    /// Evaluates `min(len)` boxes in one native loop.
    fn interval_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        match self.answer(Kind::IntervalBatch, out.len()) {
            Answer::Native(Entry::IntervalBatch(c)) => c.call(boxes, out),
            Answer::Interpreted(i) => i.interval_batch(boxes, out),
            _ => out.fill(Interval::ENTIRE),
        }
    }
}

impl Specialise for JitEvaluator {
    fn function(&self) -> Option<&Function> {
        Some(&self.inner.f)
    }

    fn is_native(&self) -> bool {
        true
    }

    fn derivatives_native(&self) -> bool {
        !(self.background && self.inner.long)
    }

    fn compile_time(&self) -> Duration {
        self.compile_times().iter().map(|(_, t)| *t).sum()
    }

    fn compile_waits(&self) -> Vec<(Instant, Instant)> {
        Kind::ALL
            .into_iter()
            .filter_map(|k| self.inner.slots[k as usize].get())
            .filter_map(|s| s.waited.map(|t| (t, t + s.time)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::interp::Interpreter;
    use crate::ir::random::{Rng, random_function};

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    fn same_iv(a: Interval, b: Interval) -> bool {
        (a.is_empty() && b.is_empty()) || (same(a.lo, b.lo) && same(a.hi, b.hi))
    }

    // Whatever answers (the interpreter while the code compiles, the code
    // once it is there), the bits are the interpreter's; the compilation
    // is reported, and nobody waited for it.
    #[test]
    fn background_answers_keep_the_interpreters_bits_across_compilation() {
        let mut rng = Rng::new(5);
        for seed in 0..12 {
            let f = random_function(seed, 8);
            let bg = JitEvaluator::new(&f).unwrap().in_background();
            let reference = Interpreter::new(f.clone());
            let check = |rng: &mut Rng| {
                for _ in 0..50 {
                    let p = [
                        rng.range(-2.0, 2.0),
                        rng.range(-2.0, 2.0),
                        rng.range(-2.0, 2.0),
                    ];
                    assert!(
                        same(bg.point(p), reference.point(p)),
                        "seed {seed} at {p:?}"
                    );
                    let b = p.map(|c| Interval::new(c - 0.25, c + 0.25));
                    let (got, want) = (bg.interval(b), reference.interval(b));
                    assert!(
                        same_iv(got, want),
                        "seed {seed} over {b:?}: {got:?} against {want:?}"
                    );
                    // The interpreted gradient, however often asked.
                    let (g, gw) = (bg.interval_grad_interpreted(b), reference.interval_grad(b));
                    assert!(
                        (0..3).all(|k| same_iv(g.d[k], gw.d[k])),
                        "seed {seed} over {b:?}"
                    );
                }
            };
            check(&mut rng);
            // Asked often enough, both value kinds compile; the checks go
            // on meanwhile.
            let start = Instant::now();
            while bg.compile_times().len() < 2 {
                assert!(start.elapsed() < Duration::from_secs(60), "never compiled");
                check(&mut rng);
            }
            check(&mut rng);
            assert!(bg.compile_time() > Duration::ZERO);
            assert!(bg.compile_waits().is_empty());
            // Only the two value kinds compiled: the interpreted gradient
            // compiles nothing.
            assert_eq!(bg.compile_times().len(), 2, "{:?}", bg.compile_times());
        }
    }

    // Ski rental: a kind asked fewer than COMPILE_AFTER_CALLS times (a
    // batch counting its length) is never compiled in the background mode;
    // the call that reaches the count starts its compilation.
    #[test]
    fn background_kinds_compile_only_once_asked_enough() {
        let f = random_function(3, 6);
        let bg = JitEvaluator::new(&f).unwrap().in_background();
        let b = [Interval::new(0.0, 0.5); 3];
        for _ in 0..COMPILE_AFTER_CALLS - 1 {
            bg.interval(b);
        }
        let boxes = vec![b; COMPILE_AFTER_CALLS as usize - 1];
        let mut out = vec![Interval::EMPTY; boxes.len()];
        bg.interval_batch(&boxes, &mut out);
        std::thread::sleep(Duration::from_millis(50));
        assert!(bg.compile_times().is_empty(), "{:?}", bg.compile_times());
        bg.interval(b);
        bg.interval_batch(&boxes[..1], &mut out[..1]);
        let start = Instant::now();
        while bg.compile_times().len() < 2 {
            assert!(start.elapsed() < Duration::from_secs(60), "never compiled");
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    // A long function leaves its derivative kinds to the interpreter in the
    // background mode: the same bits as the interpreter, nothing compiled.
    #[test]
    fn long_functions_interpret_their_derivatives_in_the_background_mode() {
        let mut b = crate::ir::Builder::new();
        let x = b.var(crate::ir::Var::X);
        let mut acc = x;
        for k in 0..DERIVATIVES_MAX_OPS {
            let c = b.constant(1.0 + k as f64 * 1e-3);
            let t = b.binary(crate::ir::BinaryOp::Mul, x, c);
            acc = b.binary(crate::ir::BinaryOp::Min, acc, t);
        }
        let f = b.finish(acc);
        let bg = JitEvaluator::new(&f).unwrap().in_background();
        let reference = Interpreter::new(f.clone());
        let g = bg.point_grad([0.5, 0.0, 0.0]);
        let want = reference.point_grad([0.5, 0.0, 0.0]);
        assert!(same(g.v, want.v) && (0..3).all(|k| same(g.d[k], want.d[k])));
        assert!(bg.compile_times().iter().all(|(k, _)| *k != "point_grad"));
    }
}
