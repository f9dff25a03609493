//! Evaluators: the interface the tracer calls ([`Evaluator`]), the
//! reference interpreter ([`interp`]), native code from Cranelift ([`jit`]),
//! the regional evaluator that answers with a function pruned to a region
//! ([`regional`]), tapes and the evaluator that runs one ([`tape`],
//! [`taped`]; [`cpu`], the path their passes are compiled for), and
//! building a scene's evaluators ([`build`]).

pub mod affine;
pub mod build;
pub mod cpu;
pub mod interp;
pub mod jit;
pub mod regional;
pub mod tape;
pub mod taped;

pub use crate::ir::semantics::{Grad, IntervalGrad};
pub use build::{EvalKind, build_evaluator, build_evaluators};

use crate::interval::Interval;

/// The tracer's evaluators: one surface function with every capability
/// below, which every type with all three has.
///
/// Implementations must agree with the interpreter: point values bit for
/// bit (within a documented ulp bound for transcendentals), and every
/// interval must contain the point values at every point of its box.
pub trait Evaluator: Bulk + Specialise {}

impl<T: Bulk + Specialise + ?Sized> Evaluator for T {}

/// Single evaluations, one point or box a call: what a search along one
/// ray asks for.
pub trait Single: Send + Sync {
    /// f(x, y, z).
    fn point(&self, p: [f64; 3]) -> f64;

    /// f and its gradient at a point (forward mode).
    fn point_grad(&self, p: [f64; 3]) -> Grad;

    /// An interval containing f over the box `b = [X, Y, Z]`.
    fn interval(&self, b: [Interval; 3]) -> Interval;

    /// Intervals containing f and each partial derivative over the box.
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad;

    /// [`Single::interval_grad`] by the interpreter's rules and bits,
    /// never compiling: native code compiles on first use, and its bits
    /// differ, so a caller that may not need the kind often can ask this
    /// until it does (and then ask the other, at a point that does not
    /// depend on timing). The same as `interval_grad` for evaluators
    /// without native code.
    fn interval_grad_interpreted(&self, b: [Interval; 3]) -> IntervalGrad {
        self.interval_grad(b)
    }

    /// Intervals containing f and its derivative along `v`, `∇f·v`, over
    /// the box `b` (for every direction in the box `v`). The default takes
    /// the dot product of [`Single::interval_grad`]; the evaluators
    /// carry the one directional partial in forward mode, which costs
    /// about half as much and is often tighter.
    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        let g = self.interval_grad(b);
        let d = crate::interval::boxes::dot(&g.d, &v);
        [g.v, d]
    }
}

/// Many points or boxes a call, as columns: what blocks and tiles ask
/// for. The defaults loop over [`Single`]; evaluators with a faster path
/// (tapes, native code) override them.
pub trait Bulk: Single {
    /// `out[i] = f(xs[i], ys[i], zs[i])` for every i.
    fn point_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.point([xs[i], ys[i], zs[i]]);
        }
    }

    /// `out[i]` = f and its gradient at `(xs[i], ys[i], zs[i])`, the same
    /// bits as [`Single::point_grad`] at each point.
    fn point_grad_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [Grad]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.point_grad([xs[i], ys[i], zs[i]]);
        }
    }

    /// `out[i] = F(boxes[i])` for every i.
    fn interval_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        for (b, o) in boxes.iter().zip(out.iter_mut()) {
            *o = self.interval(*b);
        }
    }
}

/// What an evaluator is and what specialising it to a region starts
/// from: its function, its region and parent when it was pruned, and
/// whether it runs native code. Every method has a default for an
/// evaluator of a whole function that compiles nothing.
pub trait Specialise {
    /// The IR function this evaluator evaluates, when it has one (the
    /// renderer prunes it per tile, see `crate::ir::prune`).
    fn function(&self) -> Option<&crate::ir::Function> {
        None
    }

    /// The tape of a pruned evaluator (the renderer prunes it further).
    fn tape(&self) -> Option<&tape::Tape> {
        None
    }

    /// The evaluator that answers derivatives over `b` when that is not
    /// this one (a tree of regions pruned differently), to take every
    /// value of a formula that combines several (a centred form: a value
    /// at a point of `b` and a derivative over `b`) from one function.
    /// Regions pruned to keep only signs ([`tape::Keep::Signs`]) agree in
    /// sign, not in value, and such a formula over values from two of
    /// them would bound neither.
    fn answering(&self, _b: &[Interval; 3]) -> Option<&dyn Evaluator> {
        None
    }

    /// Whether this evaluator runs native code (the renderer replaces it by
    /// an interpreted pruned function only if that is much shorter).
    fn is_native(&self) -> bool {
        false
    }

    /// Whether the derivative kinds (gradients and directional
    /// derivatives) run native code too; a long function's JIT leaves them
    /// to its tape (see [`jit::DERIVATIVES_MAX_OPS`]).
    fn derivatives_native(&self) -> bool {
        self.is_native()
    }

    /// Time spent so far compiling this evaluator's native code (zero for
    /// evaluators that compile nothing). Renders subtract what lazy
    /// compilation adds to their wall time.
    fn compile_time(&self) -> std::time::Duration {
        std::time::Duration::ZERO
    }

    /// When the compilations its callers waited for (on their threads, not
    /// in the background) ran, as wall-clock spans: a render subtracts
    /// the union of the spans inside it from its time. Not their sum: with
    /// several threads, kinds compile at once on different threads, and
    /// the other threads go on rendering.
    fn compile_waits(&self) -> Vec<(std::time::Instant, std::time::Instant)> {
        Vec::new()
    }
}
