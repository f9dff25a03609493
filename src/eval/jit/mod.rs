//! Cranelift JIT: native point, interval and gradient evaluators.
//!
//! [`JitEvaluator`] compiles each evaluator kind of [`crate::eval::Evaluator`]
//! on its first use (so a scene pays only for what it needs) and gives the
//! same answers as the reference in [`crate::eval::interp`] and
//! [`crate::interval`]: point values bit for bit (NaN payloads aside),
//! intervals bit for bit for the arithmetic ops, and transcendentals through
//! `extern "C"` calls to the very Rust functions the reference uses.
//!
//! ```
//! use ibeam::eval::{Bulk, Evaluator, Single, Specialise};
//! use ibeam::ir::{BinaryOp, Builder, Var};
//! let mut b = Builder::new();
//! let (x, y) = (b.var(Var::X), b.var(Var::Y));
//! let r = b.binary(BinaryOp::Mul, x, y);
//! let f = b.finish(r);
//! let jit = ibeam::eval::jit::JitEvaluator::new(&f).unwrap();
//! assert_eq!(jit.point([2.0, 3.0, 0.0]), 6.0);
//! assert_eq!(jit.compile_times().len(), 1); // only `point` was compiled
//! ```
//!
//! An interval is one `F64X2` value holding `(-lo, hi)`, so one packed,
//! branch-free `interval::up` rounds both bounds outward; MXCSR is never
//! touched.
//!
//! Layout: `emit` holds the CLIF building blocks (packed rounding, min/max,
//! interval ops), `lower` the sweep over the IR per kind, `derive` the
//! derivative rules over CLIF values, `evaluator` the lazily compiled
//! table of kinds behind [`JitEvaluator`], `shims` the
//! callbacks into Rust, and `raw` the only `unsafe` code (owning JIT memory
//! and calling it).
//!
//! Two environment variables exist for experiments: `IBEAM_JIT_OPT`
//! (Cranelift's `opt_level`, default `none`) and `IBEAM_JIT_RA` (its
//! `regalloc_algorithm`, default `backtracking`); docs/performance.md says
//! what they measured.

mod derive;
mod emit;
mod evaluator;
mod lower;
mod powers;
#[allow(unsafe_code)] // the one module that calls JIT code and frees its memory
mod raw;
mod shims;

use std::fmt;
use std::sync::OnceLock;

use cranelift_codegen::Context;
use cranelift_codegen::ir::{self, BlockArg, InstBuilder, UserFuncName, condcodes::IntCC, types};
use cranelift_codegen::isa::OwnedTargetIsa;
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{FuncId, Linkage, Module, default_libcall_names};

use crate::ir::Function;
pub use evaluator::JitEvaluator;

use emit::{Emitter, ShimRefs};
use raw::{Code, EntryFn, IntervalBatchFn, IntervalFn, PointBatchFn, PointFn, PointGradFn};
use shims::{SHIM_COUNT, Shim};

/// Why a function could not be compiled.
#[derive(Debug, Clone, PartialEq)]
pub struct JitError(String);

impl fmt::Display for JitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "JIT compilation failed: {}", self.0)
    }
}

impl std::error::Error for JitError {}

impl JitError {
    fn new(what: &str, e: impl fmt::Display) -> JitError {
        JitError(format!("{what}: {e}"))
    }
}

/// One evaluator kind; each is compiled separately and lazily. The
/// declaration order is the index of its slot in [`JitEvaluator`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Kind {
    /// f at a point.
    Point,
    /// f and its gradient at a point.
    PointGrad,
    /// An interval of f over a box.
    Interval,
    /// Intervals of f and its gradient over a box.
    IntervalGrad,
    /// Intervals of f and of its derivative along a direction over a box.
    IntervalDir,
    /// f at many points (a loop around the point body).
    PointBatch,
    /// Intervals of f over many boxes.
    IntervalBatch,
}

impl Kind {
    /// Every kind, in the order of [`clif_text`] and [`JitEvaluator::compile_times`].
    pub const ALL: [Kind; 7] = [
        Kind::Point,
        Kind::PointGrad,
        Kind::Interval,
        Kind::IntervalGrad,
        Kind::IntervalDir,
        Kind::PointBatch,
        Kind::IntervalBatch,
    ];

    /// The name used in reports and CLIF headers.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Point => "point",
            Kind::PointGrad => "point_grad",
            Kind::Interval => "interval",
            Kind::IntervalGrad => "interval_grad",
            Kind::IntervalDir => "interval_dir",
            Kind::PointBatch => "point_batch",
            Kind::IntervalBatch => "interval_batch",
        }
    }

    fn signature(self, cc: cranelift_codegen::isa::CallConv) -> ir::Signature {
        match self {
            Kind::Point => PointFn::signature(cc),
            Kind::PointGrad => PointGradFn::signature(cc),
            Kind::Interval | Kind::IntervalGrad | Kind::IntervalDir => IntervalFn::signature(cc),
            Kind::PointBatch => PointBatchFn::signature(cc),
            Kind::IntervalBatch => IntervalBatchFn::signature(cc),
        }
    }
}

/// The host ISA, built once per process.
///
/// `opt_level=none`: measured on prospero (7591 ops, release build), the
/// e-graph optimiser of `speed` made compilation 2-5x slower *and* the code
/// slower (point 2.7 vs 1.9 µs, interval 40 vs 26 µs), because global value
/// numbering merges every use of a constant such as 0.0 or +inf into one
/// value live across the whole function, which is exactly the long live
/// range that the register allocator handles badly (see `lower::WINDOW`).
/// Our input is already hash-consed and constant-folded, so the optimiser
/// has little left to find; instruction selection (which turns our
/// `select(fcmp ...)` shapes into `minsd`/`maxsd`) runs at every level.
/// The verifier runs in debug builds only (it checks our own codegen, which
/// the test suite exercises in debug builds).
fn isa() -> Result<OwnedTargetIsa, JitError> {
    static ISA: OnceLock<Result<OwnedTargetIsa, JitError>> = OnceLock::new();
    ISA.get_or_init(|| {
        let mut flags = settings::builder();
        let set = |fb: &mut settings::Builder, k: &str, v: &str| {
            fb.set(k, v).map_err(|e| JitError::new(k, e))
        };
        let lvl = std::env::var("IBEAM_JIT_OPT").unwrap_or_else(|_| "none".into());
        set(&mut flags, "opt_level", &lvl)?;
        if let Ok(ra) = std::env::var("IBEAM_JIT_RA") {
            set(&mut flags, "regalloc_algorithm", &ra)?;
        }
        set(&mut flags, "use_colocated_libcalls", "false")?;
        set(&mut flags, "is_pic", "false")?;
        let verify = if cfg!(debug_assertions) {
            "true"
        } else {
            "false"
        };
        set(&mut flags, "enable_verifier", verify)?;
        // Frames stay small (spill slots are reused), but probe anyway so a
        // large one can never skip a guard page.
        set(&mut flags, "enable_probestack", "true")?;
        set(&mut flags, "probestack_strategy", "inline")?;
        let builder = cranelift_native::builder().map_err(|e| JitError::new("host ISA", e))?;
        builder
            .finish(settings::Flags::new(flags))
            .map_err(|e| JitError::new("host ISA", e))
    })
    .clone()
}

/// The shims declared in one module, by [`Shim`].
struct ShimIds([FuncId; SHIM_COUNT]);

impl ShimIds {
    /// Imports every shim into `func`.
    fn import(&self, module: &mut JITModule, func: &mut ir::Function) -> ShimRefs {
        ShimRefs(self.0.map(|id| module.declare_func_in_func(id, func)))
    }
}

/// A fresh module that knows every shim symbol, and the shims declared in it.
fn new_module() -> Result<(JITModule, ShimIds), JitError> {
    let isa = isa()?;
    let cc = isa.default_call_conv();
    let mut jb = JITBuilder::with_isa(isa, default_libcall_names());
    for shim in Shim::all() {
        let (name, _, ptr) = shim.entry();
        jb.symbol(name, ptr);
    }
    let mut module = JITModule::new(jb);
    let mut ids = Vec::with_capacity(SHIM_COUNT);
    for shim in Shim::all() {
        let (name, sig, _) = shim.entry();
        let (params, rets) = sig.arity();
        let mut s = ir::Signature::new(cc);
        s.params
            .extend((0..params).map(|_| ir::AbiParam::new(types::F64)));
        s.returns
            .extend((0..rets).map(|_| ir::AbiParam::new(types::F64)));
        let id = module
            .declare_function(&name, Linkage::Import, &s)
            .map_err(|e| JitError::new(&name, e))?;
        ids.push(id);
    }
    let ids = ids
        .try_into()
        .map_err(|_| JitError("shim table size".into()))?;
    Ok((module, ShimIds(ids)))
}

/// Builds the CLIF function of `kind` for `f` (not yet compiled).
fn build(
    kind: Kind,
    f: &Function,
    live: &[bool],
    module: &mut JITModule,
    shim_ids: &ShimIds,
    body: Option<FuncId>,
) -> ir::Function {
    let cc = module.isa().default_call_conv();
    let mut func =
        ir::Function::with_name_signature(UserFuncName::user(0, kind as u32), kind.signature(cc));
    let fe_config = module.isa().frontend_config();
    let shims = shim_ids.import(module, &mut func);
    let callee = body.map(|id| module.declare_func_in_func(id, &mut func));
    let mut fctx = FunctionBuilderContext::new();
    let mut b = FunctionBuilder::new(&mut func, &mut fctx);
    let entry = b.create_block();
    b.append_block_params_for_function_params(entry);
    b.switch_to_block(entry);
    b.seal_block(entry);
    let params = b.block_params(entry).to_vec();
    let int_select = emit::use_int_select(live);
    let load_box = |e: &mut Emitter, p: ir::Value| [0, 1, 2].map(|k| e.iv_load(p, 16 * k));
    match kind {
        Kind::Point => {
            let mut e = Emitter::new(&mut b, shims, int_select);
            let v = lower::point(&mut e, f, live, [params[0], params[1], params[2]]);
            b.ins().return_(&[v]);
        }
        Kind::PointGrad => {
            let mut e = Emitter::new(&mut b, shims, int_select);
            let (v, d) = derive::grad(&mut e, f, live, [params[0], params[1], params[2]]);
            let out = params[3];
            e.store(v, out, 0);
            for (k, dk) in d.into_iter().enumerate() {
                let dk = dk.unwrap_or_else(|| e.c(0.0));
                e.store(dk, out, 8 * (k as i32 + 1));
            }
            b.ins().return_(&[]);
        }
        Kind::Interval => {
            let mut e = Emitter::new(&mut b, shims, int_select);
            let bx = load_box(&mut e, params[0]);
            let v = lower::interval(&mut e, f, live, bx);
            e.iv_store(v, params[1], 0);
            b.ins().return_(&[]);
        }
        Kind::IntervalGrad => {
            let mut e = Emitter::new(&mut b, shims, int_select);
            let bx = load_box(&mut e, params[0]);
            let (v, d) = derive::grad(&mut e, f, live, bx);
            let out = params[1];
            e.iv_store(v, out, 0);
            for (k, dk) in d.into_iter().enumerate() {
                let dk = dk.unwrap_or_else(|| e.iv_const(0.0));
                e.iv_store(dk, out, 16 * (k as i32 + 1));
            }
            b.ins().return_(&[]);
        }
        Kind::IntervalDir => {
            let mut e = Emitter::new(&mut b, shims, int_select);
            let bx = load_box(&mut e, params[0]);
            let dir = [0, 1, 2].map(|k| e.iv_load(params[0], 48 + 16 * k));
            let (v, d) = derive::directional(&mut e, f, live, bx, dir);
            let out = params[1];
            e.iv_store(v, out, 0);
            let d = d.unwrap_or_else(|| e.iv_const(0.0));
            e.iv_store(d, out, 16);
            b.ins().return_(&[]);
        }
        Kind::PointBatch | Kind::IntervalBatch => {
            let callee = callee.expect("batch kinds are built with a body function");
            batch_loop(&mut b, kind, &params, callee, shims, int_select);
        }
    }
    b.finalize(fe_config);
    func
}

/// The loop of a batch kind: calls the single-evaluation `callee` once per
/// element, `params` being the batch entry's (pointers, then the count).
fn batch_loop(
    b: &mut FunctionBuilder,
    kind: Kind,
    params: &[ir::Value],
    callee: ir::FuncRef,
    shims: ShimRefs,
    int_select: bool,
) {
    let n = *params.last().expect("count parameter");
    let header = b.create_block();
    let body = b.create_block();
    let exit = b.create_block();
    let i_param = b.append_block_param(header, types::I64);
    let zero = b.ins().iconst(types::I64, 0);
    b.ins().jump(header, &[BlockArg::Value(zero)]);
    b.switch_to_block(header);
    let more = b.ins().icmp(IntCC::UnsignedLessThan, i_param, n);
    b.ins().brif(more, body, &[], exit, &[]);
    b.switch_to_block(body);
    b.seal_block(body);
    // The loop calls the single-evaluation function (compiled into
    // the same module) rather than inlining its body: the call costs
    // a few ns against the microseconds a large body takes, and the
    // loop stays small enough to read in `--clif` output.
    if kind == Kind::PointBatch {
        let off = b.ins().ishl_imm_u(i_param, 3);
        let addr = |b: &mut FunctionBuilder, base: ir::Value| b.ins().iadd(base, off);
        let ptrs = [0, 1, 2, 3].map(|k| addr(b, params[k]));
        let mut e = Emitter::new(b, shims, int_select);
        let xyz = [0, 1, 2].map(|k| e.load(ptrs[k], 0));
        let call = b.ins().call(callee, &xyz);
        let v = b.inst_results(call)[0];
        let mut e = Emitter::new(b, shims, int_select);
        e.store(v, ptrs[3], 0);
    } else {
        let in_off = b.ins().imul_imm_u(i_param, 48);
        let out_off = b.ins().ishl_imm_u(i_param, 4);
        let inp = b.ins().iadd(params[0], in_off);
        let outp = b.ins().iadd(params[1], out_off);
        b.ins().call(callee, &[inp, outp]);
    }
    let next = b.ins().iadd_imm_u(i_param, 1);
    b.ins().jump(header, &[BlockArg::Value(next)]);
    b.seal_block(header);
    b.switch_to_block(exit);
    b.seal_block(exit);
    b.ins().return_(&[]);
}

/// The single-evaluation kind a batch kind loops over.
fn batch_body(kind: Kind) -> Option<Kind> {
    match kind {
        Kind::PointBatch => Some(Kind::Point),
        Kind::IntervalBatch => Some(Kind::Interval),
        _ => None,
    }
}

/// Declares the body function of a batch kind in `module`.
fn declare_body(module: &mut JITModule, body: Kind) -> Result<FuncId, JitError> {
    let sig = body.signature(module.isa().default_call_conv());
    let name = format!("{}_body", body.name());
    module
        .declare_function(&name, Linkage::Local, &sig)
        .map_err(|e| JitError::new(&name, e))
}

/// Builds and defines `kind` in `module` under a fresh id.
fn define(
    kind: Kind,
    f: &Function,
    live: &[bool],
    module: &mut JITModule,
    shim_ids: &ShimIds,
    id: FuncId,
    body: Option<FuncId>,
) -> Result<(), JitError> {
    let func = build(kind, f, live, module, shim_ids, body);
    let mut ctx = Context::for_function(func);
    module
        .define_function(id, &mut ctx)
        .map_err(|e| JitError::new(kind.name(), format!("{e:?}")))
}

/// Compiles `kind` for `f` into its own module.
fn compile<F: EntryFn>(kind: Kind, f: &Function, live: &[bool]) -> Result<Code<F>, JitError> {
    let (mut module, shim_ids) = new_module()?;
    match define_all(kind, f, live, &mut module, &shim_ids) {
        Ok(id) => {
            Code::new(module, id).ok_or_else(|| JitError::new(kind.name(), "signature mismatch"))
        }
        Err(e) => {
            raw::discard(module);
            Err(e)
        }
    }
}

/// Defines `kind` (and the body a batch kind calls) and finalizes `module`.
fn define_all(
    kind: Kind,
    f: &Function,
    live: &[bool],
    module: &mut JITModule,
    shim_ids: &ShimIds,
) -> Result<FuncId, JitError> {
    let body = match batch_body(kind) {
        Some(bk) => {
            let bid = declare_body(module, bk)?;
            define(bk, f, live, module, shim_ids, bid, None)?;
            Some(bid)
        }
        None => None,
    };
    let sig = kind.signature(module.isa().default_call_conv());
    let id = module
        .declare_function(kind.name(), Linkage::Local, &sig)
        .map_err(|e| JitError::new(kind.name(), e))?;
    define(kind, f, live, module, shim_ids, id, body)?;
    module
        .finalize_definitions()
        .map_err(|e| JitError::new(kind.name(), e))?;
    Ok(id)
}

/// The CLIF (Cranelift IR, before optimisation) of every evaluator kind of
/// `f`, each headed `; evaluator: NAME`. The batch kinds are loops that
/// call the point or interval function.
pub fn clif_text(f: &Function) -> Result<String, JitError> {
    crate::ir::validate::validate(f).map_err(|e| JitError::new("invalid IR", e))?;
    let live = lower::live_ops(f);
    let (mut module, shim_ids) = new_module()?;
    let mut out = String::new();
    for kind in Kind::ALL {
        let body = match batch_body(kind) {
            Some(bk) => Some(declare_body(&mut module, bk)?),
            None => None,
        };
        let func = build(kind, f, &live, &mut module, &shim_ids, body);
        out.push_str(&format!(
            "; evaluator: {}\n{}\n",
            kind.name(),
            func.display()
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Compiles `x -> emit(x)` as a point-signature function.
    fn compile_unary(emit: impl Fn(&mut Emitter, ir::Value) -> ir::Value) -> Code<PointFn> {
        let (mut module, shim_ids) = new_module().unwrap();
        let cc = module.isa().default_call_conv();
        let sig = PointFn::signature(cc);
        let mut func = ir::Function::with_name_signature(UserFuncName::user(0, 0), sig.clone());
        let shims = shim_ids.import(&mut module, &mut func);
        let fe = module.isa().frontend_config();
        let mut fctx = FunctionBuilderContext::new();
        let mut b = FunctionBuilder::new(&mut func, &mut fctx);
        let entry = b.create_block();
        b.append_block_params_for_function_params(entry);
        b.switch_to_block(entry);
        b.seal_block(entry);
        let x = b.block_params(entry)[0];
        let int_select = false;
        let mut e = Emitter::new(&mut b, shims, int_select);
        let v = emit(&mut e, x);
        b.ins().return_(&[v]);
        b.finalize(fe);
        let id = module.declare_function("t", Linkage::Local, &sig).unwrap();
        let mut ctx = Context::for_function(func);
        module.define_function(id, &mut ctx).unwrap();
        module.finalize_definitions().unwrap();
        Code::new(module, id).unwrap()
    }

    const SPECIAL: [f64; 14] = [
        0.0,
        -0.0,
        5e-324,
        -5e-324,
        f64::MIN_POSITIVE,
        1.0,
        -1.0,
        f64::MAX,
        f64::MIN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        -f64::NAN,
        1e-310,
    ];

    /// Every bit pattern class the ulp step can meet, NaN payloads included
    /// (a signalling NaN next to -inf, and one next to -0 in bits).
    fn cases() -> Vec<f64> {
        let mut v = SPECIAL.to_vec();
        v.push(f64::from_bits(0xfff0_0000_0000_0001));
        v.push(f64::from_bits(0x7fff_ffff_ffff_ffff));
        v.push(f64::from_bits(0x7ff0_0000_0000_0001));
        v
    }

    // Checks a packed rounding step against its scalar reference on every
    // case, lane by lane: a value in lane 0 and its negation in lane 1,
    // read back from both lanes. Returns each case with the reference's
    // result, for the caller's bounds.
    fn packed_matches(
        round: fn(&mut Emitter, ir::Value) -> ir::Value,
        reference: fn(f64) -> f64,
        name: &str,
    ) -> Vec<(f64, f64)> {
        let lane = |k: u8| {
            compile_unary(move |e, x| {
                let v = e.b.ins().splat(types::F64X2, x);
                let m = e.vconst(1.0, -1.0);
                let v = e.b.ins().fmul(v, m);
                let u = round(e, v);
                e.b.ins().extractlane(u, k)
            })
        };
        let (l0, l1) = (lane(0), lane(1));
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        cases()
            .into_iter()
            .map(|x| {
                let (u0, u1) = (l0.call([x, 0.0, 0.0]), l1.call([x, 0.0, 0.0]));
                let (r0, r1) = (reference(x), reference(-x));
                assert!(same(u0, r0), "{name}({x:e}): {u0:e} vs {r0:e}");
                assert!(same(u1, r1), "{name}({:e}): {u1:e} vs {r1:e}", -x);
                (x, r0)
            })
            .collect()
    }

    #[test]
    fn packed_rounding_matches_the_reference_bit_for_bit() {
        let up = packed_matches(|e, v| e.vup(v), crate::interval::up, "up");
        for (x, r) in up.into_iter().filter(|(x, _)| x.is_finite()) {
            // Two ulps, or 2^-510 near zero (see `interval::up`).
            let near_zero = (x + 2.0 * crate::interval::FLOOR_STEP).next_up();
            let most = x.next_up().next_up().max(near_zero);
            assert!(r > x && r <= most, "up({x:e}) = {r:e}");
        }
    }

    #[test]
    fn packed_sum_rounding_matches_the_reference_bit_for_bit() {
        // `up_sum` leaves zero and subnormal sums alone (they are exact)
        // and moves every other finite value up by one or two ulps.
        let up = packed_matches(|e, v| e.vup_sum(v), crate::interval::up_sum, "up_sum");
        for (x, r) in up.into_iter().filter(|(x, _)| x.is_finite()) {
            let exact = x.abs() < f64::MIN_POSITIVE;
            let most = x.next_up().next_up();
            assert!(
                if exact { r == x } else { r > x && r <= most },
                "up_sum({x:e}) = {r:e}"
            );
        }
    }

    #[test]
    fn min_max_flavours_match_the_reference() {
        use crate::interval::{max_nan, min_nan};
        for y in cases() {
            let mn = compile_unary(move |e, x| {
                let c = e.c(y);
                e.min_nan(x, c)
            });
            let mx = compile_unary(move |e, x| {
                let c = e.c(y);
                e.max_nan(x, c)
            });
            for x in cases() {
                let p = [x, 0.0, 0.0];
                let same =
                    |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
                assert!(same(mn.call(p), min_nan(x, y)), "min_nan({x:e}, {y:e})");
                assert!(same(mx.call(p), max_nan(x, y)), "max_nan({x:e}, {y:e})");
            }
        }
    }
}
