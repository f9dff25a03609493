//! The one module with `unsafe`: owning JIT memory and calling into it.
//!
//! Everything else in `crate::eval::jit` builds CLIF and manages lifetimes in safe
//! code; here a finalized function address becomes a typed `extern "C"` fn
//! pointer that lives exactly as long as the `JITModule` holding its code.

use cranelift_codegen::ir::{AbiParam, Signature, types};
use cranelift_codegen::isa::CallConv;
use cranelift_jit::JITModule;
use cranelift_module::{FuncId, Module};

use crate::eval::IntervalGrad;
use crate::interval::Interval;

/// `f(x, y, z)`.
pub(crate) type PointFn = unsafe extern "C" fn(f64, f64, f64) -> f64;
/// `(x, y, z, out)`: writes `[f, ∂x, ∂y, ∂z]` to `out[0..4]`.
pub(crate) type PointGradFn = unsafe extern "C" fn(f64, f64, f64, *mut f64);
/// `(box, out)`: reads 6 bounds, writes 2 (interval evaluator) or 8
/// (interval gradient evaluator).
pub(crate) type IntervalFn = unsafe extern "C" fn(*const f64, *mut f64);
/// `(xs, ys, zs, out, n)`.
pub(crate) type PointBatchFn =
    unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64, usize);
/// `(boxes, out, n)`: `n` boxes of 6 bounds in, `n` intervals out.
pub(crate) type IntervalBatchFn = unsafe extern "C" fn(*const f64, *mut f64, usize);

/// A native entry point type: its Cranelift signature is derived from the
/// same table as the Rust fn-pointer type, so the two cannot drift apart.
pub(crate) trait EntryFn: Copy {
    /// Parameter types (`P` = pointer, `F` = f64, `N` = usize).
    const PARAMS: &'static [Param];
    /// Whether the function returns one f64 (else nothing).
    const RETURNS_F64: bool;

    /// The Cranelift signature under `cc`.
    fn signature(cc: CallConv) -> Signature {
        let mut s = Signature::new(cc);
        for p in Self::PARAMS {
            let t = match p {
                Param::F => types::F64,
                Param::P | Param::N => types::I64,
            };
            s.params.push(AbiParam::new(t));
        }
        if Self::RETURNS_F64 {
            s.returns.push(AbiParam::new(types::F64));
        }
        s
    }
}

/// One parameter kind of an [`EntryFn`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Param {
    /// f64
    F,
    /// pointer (64-bit)
    P,
    /// usize count (64-bit)
    N,
}

use Param::{F, N, P};

impl EntryFn for PointFn {
    const PARAMS: &'static [Param] = &[F, F, F];
    const RETURNS_F64: bool = true;
}
impl EntryFn for PointGradFn {
    const PARAMS: &'static [Param] = &[F, F, F, P];
    const RETURNS_F64: bool = false;
}
impl EntryFn for IntervalFn {
    const PARAMS: &'static [Param] = &[P, P];
    const RETURNS_F64: bool = false;
}
impl EntryFn for PointBatchFn {
    const PARAMS: &'static [Param] = &[P, P, P, P, N];
    const RETURNS_F64: bool = false;
}
impl EntryFn for IntervalBatchFn {
    const PARAMS: &'static [Param] = &[P, P, N];
    const RETURNS_F64: bool = false;
}

/// A compiled function and the module that owns its machine code.
pub(crate) struct Code<F> {
    module: Option<JITModule>,
    entry: F,
}

// SAFETY: the generated code is pure (it reads its arguments, writes only
// through its output pointers and calls only the pure shims), so calling it
// from several threads at once is fine. `JITModule` itself is not `Sync`
// (it keeps a `RefCell` symbol cache), but it is never touched through
// `&Code`: the field is private and only `Drop` (which has `&mut self`)
// uses it. Its code memory is owned by it and not tied to a thread.
unsafe impl<F> Send for Code<F> {}
// SAFETY: see the `Send` impl above.
unsafe impl<F> Sync for Code<F> {}

impl<F: EntryFn> Code<F> {
    /// Takes ownership of a finalized `module` and types its function `id`
    /// as `F`, or `None` if the declared signature is not `F`'s.
    pub(crate) fn new(module: JITModule, id: FuncId) -> Option<Code<F>> {
        let decl = module.declarations().get_function_decl(id);
        if decl.signature != F::signature(module.isa().default_call_conv())
            || size_of::<F>() != size_of::<*const u8>()
        {
            discard(module);
            return None;
        }
        let entry = module.get_finalized_function(id);
        // SAFETY: `entry` is finalized code of `module` whose signature
        // (checked above) is the C ABI signature of `F` (an `extern "C"`
        // fn-pointer type, same size as a pointer, checked).
        let entry = unsafe { std::mem::transmute_copy::<*const u8, F>(&entry) };
        Some(Code {
            module: Some(module),
            entry,
        })
    }
}

/// Frees a module whose functions are never called (a failed compilation).
pub(crate) fn discard(module: JITModule) {
    // SAFETY: no pointer into this module's memory was ever handed out:
    // `Code::new`, the only place that takes one, consumes the module.
    unsafe { module.free_memory() }
}

impl<F> Drop for Code<F> {
    fn drop(&mut self) {
        if let Some(m) = self.module.take() {
            // SAFETY: `entry` is the only pointer into this module's memory
            // and it is dropped with `self`; no call can be running, since
            // calls borrow `&self` and we hold `&mut self`.
            unsafe { m.free_memory() }
        }
    }
}

impl Code<PointFn> {
    /// f(x, y, z).
    pub(crate) fn call(&self, p: [f64; 3]) -> f64 {
        // SAFETY: the signature matches (see `Code::new`); arguments are
        // plain values.
        unsafe { (self.entry)(p[0], p[1], p[2]) }
    }
}

impl Code<PointGradFn> {
    /// `[f, ∂x, ∂y, ∂z]` at p.
    pub(crate) fn call(&self, p: [f64; 3]) -> [f64; 4] {
        let mut out = [0.0; 4];
        // SAFETY: the code writes exactly 4 f64 at `out`, which is a live,
        // aligned `[f64; 4]`.
        unsafe { (self.entry)(p[0], p[1], p[2], out.as_mut_ptr()) };
        out
    }
}

impl Code<IntervalFn> {
    /// Runs the code on one box; the interval kind fills `out[0..2]`, the
    /// interval-gradient kind `out[0..8]`.
    fn run(&self, b: &[Interval; 3]) -> [f64; 8] {
        let mut out = [0.0; 8];
        // SAFETY: `Interval` is `repr(C)` of two f64, so `[Interval; 3]` is
        // 6 aligned f64, which is what either kind reads. The larger kind
        // writes 8 f64 and `out` holds 8, so even a mixed-up kind stays in
        // bounds.
        unsafe { (self.entry)(b.as_ptr().cast::<f64>(), out.as_mut_ptr()) };
        out
    }

    /// F over the box.
    pub(crate) fn call_interval(&self, b: &[Interval; 3]) -> Interval {
        let out = self.run(b);
        Interval::new(out[0], out[1])
    }

    /// F and its derivative along a direction over a box (`bv` is the box
    /// then the direction).
    pub(crate) fn call_interval_dir(&self, bv: &[Interval; 6]) -> [Interval; 2] {
        let mut out = [0.0; 4];
        // SAFETY: `Interval` is `repr(C)` of two f64, so `[Interval; 6]` is
        // the 12 aligned f64 the directional kind reads; it writes 4 f64,
        // which `out` holds.
        unsafe { (self.entry)(bv.as_ptr().cast::<f64>(), out.as_mut_ptr()) };
        [Interval::new(out[0], out[1]), Interval::new(out[2], out[3])]
    }

    /// F and its partials over the box.
    pub(crate) fn call_interval_grad(&self, b: &[Interval; 3]) -> IntervalGrad {
        let out = self.run(b);
        let iv = |i: usize| Interval::new(out[2 * i], out[2 * i + 1]);
        IntervalGrad {
            v: iv(0),
            d: [iv(1), iv(2), iv(3)],
        }
    }
}

impl Code<PointBatchFn> {
    /// `out[i] = f(xs[i], ys[i], zs[i])` for i below the shortest length.
    pub(crate) fn call(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let n = out.len().min(xs.len()).min(ys.len()).min(zs.len());
        // SAFETY: the loop reads xs, ys, zs and writes out at indices
        // 0..n, all in bounds of the four slices.
        unsafe { (self.entry)(xs.as_ptr(), ys.as_ptr(), zs.as_ptr(), out.as_mut_ptr(), n) };
    }
}

impl Code<IntervalBatchFn> {
    /// `out[i] = F(boxes[i])` for i below the shorter length.
    pub(crate) fn call(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        let n = out.len().min(boxes.len());
        // SAFETY: `Interval` is `repr(C)` of two f64, so box i is the 6 f64
        // at `boxes + 48 i` and result i the 2 f64 at `out + 16 i`; the loop
        // touches i in 0..n only, in bounds of both slices.
        unsafe {
            (self.entry)(
                boxes.as_ptr().cast::<f64>(),
                out.as_mut_ptr().cast::<f64>(),
                n,
            )
        };
    }
}
