//! Small CLIF building blocks shared by every evaluator kind: ulp stepping,
//! the min/max flavours, and the interval ops of [`crate::interval`].
//!
//! Every helper here mirrors one function of `crate::interval` or
//! `crate::ir::interp` so that the native code gives the same bits; the
//! comments say where (and why) a lowering may differ.

use cranelift_codegen::ir::condcodes::FloatCC;
use cranelift_codegen::ir::{FuncRef, InstBuilder, MemFlagsData, Value, types};
use cranelift_frontend::FunctionBuilder;

use crate::ir::{BinaryOp, UnaryOp};

/// Live-op count from which float selects are emitted as integer `cmov`s
/// (see [`Emitter::select`]).
const INT_SELECT_FROM: usize = 500;

/// Whether a function with these live ops gets integer selects. Measured
/// (release, boxes 1/64 of the bounds): on prospero (7576 ops) integer
/// selects make interval evaluation 1.45x faster (21.5 vs 31.5 µs/box),
/// on orthocircle (28 ops) 1.5x slower (186 vs 123 ns/box): a small body's
/// branches stay predicted, a large one's overflow the predictor.
pub(crate) fn use_int_select(live: &[bool]) -> bool {
    live.iter().filter(|&&l| l).count() >= INT_SELECT_FROM
}

/// An interval as two SSA values (lower, upper bound).
#[derive(Copy, Clone, Debug)]
pub(crate) struct Iv {
    pub lo: Value,
    pub hi: Value,
}

/// The transcendental shims imported into the function being built.
#[derive(Copy, Clone, Debug)]
pub(crate) struct ShimRefs {
    /// Point shims: exp, ln, sin, cos (f64 -> f64).
    pub point_unary: [FuncRef; 4],
    /// Point shims: atan2, pow ((f64, f64) -> f64).
    pub point_binary: [FuncRef; 2],
    /// Interval shims: exp, ln, sin, cos ((lo, hi) -> (lo, hi)).
    pub interval_unary: [FuncRef; 4],
    /// Interval shims: atan2, pow ((lo, hi, lo, hi) -> (lo, hi)).
    pub interval_binary: [FuncRef; 2],
}

/// Position of a transcendental unary op in [`ShimRefs`] arrays.
pub(crate) fn unary_shim_index(op: UnaryOp) -> Option<usize> {
    match op {
        UnaryOp::Exp => Some(0),
        UnaryOp::Ln => Some(1),
        UnaryOp::Sin => Some(2),
        UnaryOp::Cos => Some(3),
        _ => None,
    }
}

/// Position of a transcendental binary op in [`ShimRefs`] arrays.
pub(crate) fn binary_shim_index(op: BinaryOp) -> Option<usize> {
    match op {
        BinaryOp::Atan2 => Some(0),
        BinaryOp::Pow => Some(1),
        _ => None,
    }
}

/// A function builder plus the shims it may call.
pub(crate) struct Emitter<'a, 'b> {
    pub b: &'a mut FunctionBuilder<'b>,
    pub shims: ShimRefs,
    /// Emit float selects as integer selects (see [`Self::select`]).
    pub int_select: bool,
}

impl Emitter<'_, '_> {
    pub fn c(&mut self, v: f64) -> Value {
        self.b.ins().f64const(v)
    }

    pub fn add(&mut self, a: Value, b: Value) -> Value {
        self.b.ins().fadd(a, b)
    }

    pub fn sub(&mut self, a: Value, b: Value) -> Value {
        self.b.ins().fsub(a, b)
    }

    pub fn mul(&mut self, a: Value, b: Value) -> Value {
        self.b.ins().fmul(a, b)
    }

    pub fn div(&mut self, a: Value, b: Value) -> Value {
        self.b.ins().fdiv(a, b)
    }

    pub fn neg(&mut self, a: Value) -> Value {
        self.b.ins().fneg(a)
    }

    pub fn fcmp(&mut self, cc: FloatCC, a: Value, b: Value) -> Value {
        self.b.ins().fcmp(cc, a, b)
    }

    /// `c ? a : b`. Cranelift's x64 backend lowers a select of f64 values
    /// to a conditional jump around a move; in a large function those
    /// jumps overflow the branch predictor, so there (`int_select`) the
    /// select is done on the bits, as a `cmov`, at the price of two moves
    /// between xmm and general registers and a longer dependency chain.
    pub fn select(&mut self, c: Value, a: Value, b: Value) -> Value {
        if !self.int_select || self.b.func.dfg.value_type(a) != types::F64 {
            return self.b.ins().select(c, a, b);
        }
        let ai = self.b.ins().bitcast(types::I64, MemFlagsData::new(), a);
        let bi = self.b.ins().bitcast(types::I64, MemFlagsData::new(), b);
        let r = self.b.ins().select(c, ai, bi);
        self.b.ins().bitcast(types::F64, MemFlagsData::new(), r)
    }

    /// A float select that the backend may pattern-match (minsd/maxsd).
    fn fselect(&mut self, c: Value, a: Value, b: Value) -> Value {
        self.b.ins().select(c, a, b)
    }

    pub fn load(&mut self, p: Value, offset: i32) -> Value {
        self.b
            .ins()
            .load(types::F64, MemFlagsData::trusted(), p, offset)
    }

    pub fn store(&mut self, v: Value, p: Value, offset: i32) {
        self.b.ins().store(MemFlagsData::trusted(), v, p, offset);
    }

    /// `a < b ? a : b`; the x64 backend matches exactly this shape to one
    /// `minsd a, b`, which returns `b` when either operand is NaN and on
    /// ties (so `minsd(-0, +0) = +0`, as `interval::min_nan` gives).
    pub fn minsd(&mut self, a: Value, b: Value) -> Value {
        let lt = self.fcmp(FloatCC::LessThan, a, b);
        self.fselect(lt, a, b)
    }

    /// `a > b ? a : b`, one `maxsd a, b` (returns `b` on NaN and ties).
    pub fn maxsd(&mut self, a: Value, b: Value) -> Value {
        let gt = self.fcmp(FloatCC::LessThan, b, a);
        self.fselect(gt, a, b)
    }

    /// `interval::min_nan`, the IR's `min`. `minsd` already returns `b`
    /// (NaN) when `b` is NaN and matches the reference everywhere else
    /// except when only `a` is NaN, which the select repairs by returning
    /// `a`. The NaN may carry a different payload than `f64::NAN`; every
    /// consumer only asks whether a value is NaN, so that is sound.
    pub fn min_nan(&mut self, a: Value, b: Value) -> Value {
        let m = self.minsd(a, b);
        let a_nan = self.fcmp(FloatCC::Unordered, a, a);
        self.select(a_nan, a, m)
    }

    /// `interval::max_nan`, the IR's `max` (see [`Self::min_nan`]).
    pub fn max_nan(&mut self, a: Value, b: Value) -> Value {
        let m = self.maxsd(a, b);
        let a_nan = self.fcmp(FloatCC::Unordered, a, a);
        self.select(a_nan, a, m)
    }

    /// `interval::min_ignore_nan` (`f64::min`): NaN only if both are NaN.
    /// When `b` is NaN `minsd` gives `b`, so the select returns `a` then. On
    /// a tie of `-0` and `+0` this may pick the other zero than `f64::min`;
    /// the callers round the result outward with `next_down`/`next_up`,
    /// which map both zeros to the same value, so the bits agree.
    pub fn min_ign(&mut self, a: Value, b: Value) -> Value {
        let m = self.minsd(a, b);
        let b_nan = self.fcmp(FloatCC::Unordered, b, b);
        self.select(b_nan, a, m)
    }

    /// `interval::max_ignore_nan` (see [`Self::min_ign`]).
    pub fn max_ign(&mut self, a: Value, b: Value) -> Value {
        let m = self.maxsd(a, b);
        let b_nan = self.fcmp(FloatCC::Unordered, b, b);
        self.select(b_nan, a, m)
    }

    /// `x.max(0.0)` where `x` is a `next_down` result: `maxsd x, 0` gives 0
    /// for NaN as `f64::max` does, and `next_down` never returns `-0`, so
    /// the signed-zero tie cannot arise.
    pub fn clamp0(&mut self, x: Value) -> Value {
        let z = self.c(0.0);
        self.maxsd(x, z)
    }

    /// `f64::next_up` on the bits, without touching MXCSR: adding +0 turns
    /// -0 into +0 (round-to-nearest), then one integer step away from or
    /// towards zero by the sign (`+1` for positive, `-1` for negative bit
    /// patterns; +0 becomes the smallest subnormal, `MAX` becomes +inf,
    /// -inf becomes `-MAX`). NaN and +inf, where that step is wrong, are
    /// returned unchanged as the reference does. (A branch-free variant,
    /// `maxsd(step(minsd(MAX, v) + 0), v)`, measured no faster: the select
    /// here is always predicted and stays off the dependency chain.)
    pub fn next_up(&mut self, v: Value) -> Value {
        let z = self.c(0.0);
        let s = self.add(v, z);
        let bits = self.b.ins().bitcast(types::I64, MemFlagsData::new(), s);
        let sign = self.b.ins().sshr_imm_u(bits, 63);
        let step = self.b.ins().bor_imm_u(sign, 1);
        let nb = self.b.ins().iadd(bits, step);
        let r = self.b.ins().bitcast(types::F64, MemFlagsData::new(), nb);
        let inf = self.c(f64::INFINITY);
        let finite_or_neg_inf = self.fcmp(FloatCC::LessThan, v, inf);
        self.fselect(finite_or_neg_inf, r, v)
    }

    /// `f64::next_down(v) = -next_up(-v)`, exactly, NaN included.
    pub fn next_down(&mut self, v: Value) -> Value {
        let n = self.neg(v);
        let u = self.next_up(n);
        self.neg(u)
    }

    /// Whether an interval is EMPTY (either bound NaN).
    pub fn is_empty(&mut self, a: Iv) -> Value {
        self.fcmp(FloatCC::Unordered, a.lo, a.hi)
    }

    /// `if cond { EMPTY } else { r }`.
    pub fn empty_if(&mut self, cond: Value, r: Iv) -> Iv {
        let nan = self.c(f64::NAN);
        Iv {
            lo: self.select(cond, nan, r.lo),
            hi: self.select(cond, nan, r.hi),
        }
    }

    pub fn iv_const(&mut self, v: f64) -> Iv {
        let c = self.c(v);
        Iv { lo: c, hi: c }
    }

    pub fn iv_neg(&mut self, a: Iv) -> Iv {
        Iv {
            lo: self.neg(a.hi),
            hi: self.neg(a.lo),
        }
    }

    pub fn iv_add(&mut self, a: Iv, b: Iv) -> Iv {
        let lo = self.add(a.lo, b.lo);
        let hi = self.add(a.hi, b.hi);
        Iv {
            lo: self.next_down(lo),
            hi: self.next_up(hi),
        }
    }

    pub fn iv_sub(&mut self, a: Iv, b: Iv) -> Iv {
        let lo = self.sub(a.lo, b.hi);
        let hi = self.sub(a.hi, b.lo);
        Iv {
            lo: self.next_down(lo),
            hi: self.next_up(hi),
        }
    }

    /// Hull of four candidate bounds, NaN-ignoring, rounded outward: the
    /// shared tail of `Interval::mul` and `Interval::div`.
    fn hull4(&mut self, p: [Value; 4]) -> Iv {
        let l01 = self.min_ign(p[0], p[1]);
        let l23 = self.min_ign(p[2], p[3]);
        let lo = self.min_ign(l01, l23);
        let h01 = self.max_ign(p[0], p[1]);
        let h23 = self.max_ign(p[2], p[3]);
        let hi = self.max_ign(h01, h23);
        Iv {
            lo: self.next_down(lo),
            hi: self.next_up(hi),
        }
    }

    /// `Interval::mul`: when every bound product is 0·inf (one operand
    /// `[0, 0]`, the other with only infinite bounds) the NaN-ignoring hull
    /// is NaN and the answer is `[0, 0]`; EMPTY operands give EMPTY.
    pub fn iv_mul(&mut self, a: Iv, b: Iv) -> Iv {
        let p = [
            self.mul(a.lo, b.lo),
            self.mul(a.lo, b.hi),
            self.mul(a.hi, b.lo),
            self.mul(a.hi, b.hi),
        ];
        let h = self.hull4(p);
        let all_nan = self.fcmp(FloatCC::Unordered, h.lo, h.lo);
        let z = self.c(0.0);
        let r = Iv {
            lo: self.select(all_nan, z, h.lo),
            hi: self.select(all_nan, z, h.hi),
        };
        let ea = self.is_empty(a);
        let eb = self.is_empty(b);
        let e = self.b.ins().bor(ea, eb);
        self.empty_if(e, r)
    }

    /// `Interval::div`, its cases as selects (no branches): the hull of
    /// the four quotients when 0 is outside the divisor; `[0, 0]` for a
    /// dividend `[0, 0]` and ENTIRE for any other when 0 is strictly inside
    /// it; a half-line bounded by `num / d` when 0 is one end of the
    /// divisor and `d` the other (`num` the dividend end nearest 0);
    /// EMPTY for a divisor `[0, 0]` or an EMPTY operand.
    pub fn iv_div(&mut self, a: Iv, b: Iv) -> Iv {
        let q = [
            self.div(a.lo, b.lo),
            self.div(a.lo, b.hi),
            self.div(a.hi, b.lo),
            self.div(a.hi, b.hi),
        ];
        let h = self.hull4(q);
        let z = self.c(0.0);
        let ninf = self.c(f64::NEG_INFINITY);
        let pinf = self.c(f64::INFINITY);
        // Half-line case: positive divisor [0, hi] (d = hi) or negative
        // [lo, 0] (d = lo); the reference tests `o.lo == 0` first.
        let positive = self.fcmp(FloatCC::Equal, b.lo, z);
        let d = self.select(positive, b.hi, b.lo);
        let a_nonneg = self.fcmp(FloatCC::GreaterThanOrEqual, a.lo, z);
        let a_nonpos = self.fcmp(FloatCC::LessThanOrEqual, a.hi, z);
        let num = self.select(a_nonneg, a.lo, a.hi);
        let qd = self.div(num, d);
        let qdown = self.next_down(qd);
        let qdown = self.clamp0(qdown);
        let qup = self.next_up(qd);
        // `interval::nonpositive`: -0 and NaN (inf / inf) become +0.
        let lt0 = self.fcmp(FloatCC::LessThan, qup, z);
        let qup = self.select(lt0, qup, z);
        // The bound is a lower one (result [q, inf]) when the signs agree.
        let same_sign_pos = self.b.ins().band(a_nonneg, positive);
        let neg_div = self.b.ins().bnot(positive);
        let same_sign_neg = self.b.ins().band(a_nonpos, neg_div);
        let lower = self.b.ins().bor(same_sign_pos, same_sign_neg);
        let half_lo = self.select(lower, qdown, ninf);
        let half_hi = self.select(lower, pinf, qup);
        let one_sign = self.b.ins().bor(a_nonneg, a_nonpos);
        let half_lo = self.select(one_sign, half_lo, ninf);
        let half_hi = self.select(one_sign, half_hi, pinf);
        // 0 strictly inside the divisor: ENTIRE.
        let lo_lt0 = self.fcmp(FloatCC::LessThan, b.lo, z);
        let hi_gt0 = self.fcmp(FloatCC::GreaterThan, b.hi, z);
        let inside = self.b.ins().band(lo_lt0, hi_gt0);
        let zlo = self.select(inside, ninf, half_lo);
        let zhi = self.select(inside, pinf, half_hi);
        // Dividend [0, 0] over a divisor holding 0: [0, 0].
        let alo0 = self.fcmp(FloatCC::Equal, a.lo, z);
        let ahi0 = self.fcmp(FloatCC::Equal, a.hi, z);
        let a_zero = self.b.ins().band(alo0, ahi0);
        let zlo = self.select(a_zero, z, zlo);
        let zhi = self.select(a_zero, z, zhi);
        let lo_le0 = self.fcmp(FloatCC::LessThanOrEqual, b.lo, z);
        let hi_ge0 = self.fcmp(FloatCC::GreaterThanOrEqual, b.hi, z);
        let has0 = self.b.ins().band(lo_le0, hi_ge0);
        let r = Iv {
            lo: self.select(has0, zlo, h.lo),
            hi: self.select(has0, zhi, h.hi),
        };
        let lo_eq0 = self.fcmp(FloatCC::Equal, b.lo, z);
        let hi_eq0 = self.fcmp(FloatCC::Equal, b.hi, z);
        let zero = self.b.ins().band(lo_eq0, hi_eq0);
        let ea = self.is_empty(a);
        let eb = self.is_empty(b);
        let e = self.b.ins().bor(ea, eb);
        let e = self.b.ins().bor(e, zero);
        self.empty_if(e, r)
    }

    /// `Interval::abs` (EMPTY stays EMPTY).
    pub fn iv_abs(&mut self, a: Iv) -> Iv {
        let r = self.iv_abs_nonempty(a);
        let e = self.is_empty(a);
        self.empty_if(e, r)
    }

    /// `Interval::abs` for a non-EMPTY operand (for EMPTY it gives
    /// `[0, NaN]`): square and powi test emptiness once themselves.
    fn iv_abs_nonempty(&mut self, a: Iv) -> Iv {
        let z = self.c(0.0);
        let nonneg = self.fcmp(FloatCC::GreaterThanOrEqual, a.lo, z);
        let nonpos = self.fcmp(FloatCC::LessThanOrEqual, a.hi, z);
        let nlo = self.neg(a.lo);
        let nhi = self.neg(a.hi);
        let straddle_hi = self.max_nan(nlo, a.hi);
        let lo2 = self.select(nonpos, nhi, z);
        let hi2 = self.select(nonpos, nlo, straddle_hi);
        Iv {
            lo: self.select(nonneg, a.lo, lo2),
            hi: self.select(nonneg, a.hi, hi2),
        }
    }

    pub fn iv_square(&mut self, a: Iv) -> Iv {
        let m = self.iv_abs_nonempty(a);
        let l = self.mul(m.lo, m.lo);
        let l = self.next_down(l);
        let h = self.mul(m.hi, m.hi);
        let r = Iv {
            lo: self.clamp0(l),
            hi: self.next_up(h),
        };
        let e = self.is_empty(a);
        self.empty_if(e, r)
    }

    pub fn iv_sqrt(&mut self, a: Iv) -> Iv {
        let z = self.c(0.0);
        let s = self.b.ins().sqrt(a.lo);
        let s = self.next_down(s);
        let s = self.clamp0(s);
        let lo_le0 = self.fcmp(FloatCC::LessThanOrEqual, a.lo, z);
        let lo = self.select(lo_le0, z, s);
        let h = self.b.ins().sqrt(a.hi);
        let r = Iv {
            lo,
            hi: self.next_up(h),
        };
        let e = self.is_empty(a);
        let neg = self.fcmp(FloatCC::LessThan, a.hi, z);
        let e = self.b.ins().bor(e, neg);
        self.empty_if(e, r)
    }

    pub fn iv_min(&mut self, a: Iv, b: Iv) -> Iv {
        Iv {
            lo: self.min_nan(a.lo, b.lo),
            hi: self.min_nan(a.hi, b.hi),
        }
    }

    pub fn iv_max(&mut self, a: Iv, b: Iv) -> Iv {
        Iv {
            lo: self.max_nan(a.lo, b.lo),
            hi: self.max_nan(a.hi, b.hi),
        }
    }

    /// Hull of two intervals ignoring an EMPTY one (EMPTY only if both are).
    pub fn iv_hull(&mut self, a: Iv, b: Iv) -> Iv {
        Iv {
            lo: self.min_ign(a.lo, b.lo),
            hi: self.max_ign(a.hi, b.hi),
        }
    }

    /// `interval::powi_unsigned` unrolled for the constant `n`, with
    /// `round` applied after each multiplication.
    fn pow_unrolled(&mut self, x: Value, mut n: u64, round: Round) -> Value {
        let mut result: Option<Value> = None;
        let mut base = x;
        while n > 0 {
            if n & 1 == 1 {
                result = Some(match result {
                    None => base,
                    Some(r) => {
                        let p = self.mul(r, base);
                        self.round(p, round)
                    }
                });
            }
            n >>= 1;
            if n > 0 {
                let p = self.mul(base, base);
                base = self.round(p, round);
            }
        }
        match result {
            Some(r) => r,
            None => self.c(1.0),
        }
    }

    fn round(&mut self, v: Value, round: Round) -> Value {
        match round {
            Round::Nearest => v,
            Round::Up => self.next_up(v),
            Round::DownNonNeg => {
                let d = self.next_down(v);
                self.clamp0(d)
            }
        }
    }

    /// `interval::powi_point` for the constant `n` (widened to i64 so that
    /// the gradient's `n - 1` cannot overflow).
    pub fn powi_point(&mut self, x: Value, n: i64) -> Value {
        let p = self.pow_unrolled(x, n.unsigned_abs(), Round::Nearest);
        if n < 0 {
            let one = self.c(1.0);
            self.div(one, p)
        } else {
            p
        }
    }

    /// `Interval::powi` for the constant `n`.
    pub fn iv_powi(&mut self, a: Iv, n: i64) -> Iv {
        if n == 0 {
            return self.iv_const(1.0);
        }
        let m = n.unsigned_abs();
        let p = if m.is_multiple_of(2) {
            let s = self.iv_abs_nonempty(a);
            Iv {
                lo: self.pow_unrolled(s.lo, m, Round::DownNonNeg),
                hi: self.pow_unrolled(s.hi, m, Round::Up),
            }
        } else {
            // Odd powers are increasing: each bound keeps its sign.
            let z = self.c(0.0);
            let lo_pos = self.pow_unrolled(a.lo, m, Round::DownNonNeg);
            let nlo = self.neg(a.lo);
            let lo_neg = self.pow_unrolled(nlo, m, Round::Up);
            let lo_neg = self.neg(lo_neg);
            let lo_ge0 = self.fcmp(FloatCC::GreaterThanOrEqual, a.lo, z);
            let hi_pos = self.pow_unrolled(a.hi, m, Round::Up);
            let nhi = self.neg(a.hi);
            let hi_neg = self.pow_unrolled(nhi, m, Round::DownNonNeg);
            let hi_neg = self.neg(hi_neg);
            let hi_ge0 = self.fcmp(FloatCC::GreaterThanOrEqual, a.hi, z);
            Iv {
                lo: self.select(lo_ge0, lo_pos, lo_neg),
                hi: self.select(hi_ge0, hi_pos, hi_neg),
            }
        };
        let p = if n < 0 {
            let one = self.iv_const(1.0);
            self.iv_div(one, p)
        } else {
            p
        };
        let e = self.is_empty(a);
        self.empty_if(e, p)
    }

    /// A point transcendental through its shim.
    pub fn call_point_unary(&mut self, i: usize, a: Value) -> Value {
        let call = self.b.ins().call(self.shims.point_unary[i], &[a]);
        self.b.inst_results(call)[0]
    }

    pub fn call_point_binary(&mut self, i: usize, a: Value, b: Value) -> Value {
        let call = self.b.ins().call(self.shims.point_binary[i], &[a, b]);
        self.b.inst_results(call)[0]
    }

    /// An interval transcendental through its shim: bounds travel as f64
    /// arguments and come back as two f64 results (xmm0, xmm1), which is
    /// the C ABI of a returned `#[repr(C)]` pair of doubles.
    pub fn call_iv_unary(&mut self, i: usize, a: Iv) -> Iv {
        let call = self
            .b
            .ins()
            .call(self.shims.interval_unary[i], &[a.lo, a.hi]);
        let r = self.b.inst_results(call);
        Iv { lo: r[0], hi: r[1] }
    }

    pub fn call_iv_binary(&mut self, i: usize, a: Iv, b: Iv) -> Iv {
        let call = self
            .b
            .ins()
            .call(self.shims.interval_binary[i], &[a.lo, a.hi, b.lo, b.hi]);
        let r = self.b.inst_results(call);
        Iv { lo: r[0], hi: r[1] }
    }
}

/// Rounding after each step of an unrolled power.
#[derive(Copy, Clone, Debug)]
enum Round {
    /// Plain round-to-nearest (the point semantics).
    Nearest,
    /// One ulp up: an upper bound.
    Up,
    /// One ulp down, clamped at 0: a lower bound of a non-negative power.
    DownNonNeg,
}
