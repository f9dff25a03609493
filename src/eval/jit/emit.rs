//! Small CLIF building blocks shared by every evaluator kind: the min/max
//! flavours, and the interval ops of [`crate::interval`] (integer powers
//! and calls into Rust are in `powers`).
//!
//! An interval lives in one `F64X2` register as its lanes `(-lo, hi)`: both
//! are upper bounds, so one SIMD rounding step (`interval::up`, branch-free)
//! rounds both bounds outward, and most ops are a handful of packed
//! instructions. Every helper here mirrors one function of
//! `crate::interval` or `crate::ir::semantics` step by step, so that the native
//! code gives the same bits (NaN payloads aside).

use cranelift_codegen::ir::condcodes::FloatCC;
use cranelift_codegen::ir::{
    BlockArg, ConstantData, Endianness, FuncRef, InstBuilder, MemFlagsData, Value, types,
};
use cranelift_frontend::FunctionBuilder;

use super::shims::{SHIM_COUNT, Shim};

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

/// An interval as one `F64X2` SSA value holding its lanes `(-lo, hi)`.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Iv(pub Value);

/// The shims imported into the function being built, by [`Shim`].
#[derive(Copy, Clone, Debug)]
pub(crate) struct ShimRefs(pub [FuncRef; SHIM_COUNT]);

impl ShimRefs {
    /// The imported reference of `shim`.
    pub fn get(&self, shim: Shim) -> FuncRef {
        self.0[shim.index()]
    }
}

/// A function builder plus the shims it may call.
pub(crate) struct Emitter<'a, 'b> {
    pub b: &'a mut FunctionBuilder<'b>,
    pub shims: ShimRefs,
    /// Emit float selects as integer selects (see [`Self::select`]).
    pub int_select: bool,
    /// Recently built packed constants (see [`Self::vconst`]).
    consts: Vec<RecentConst>,
    /// Packed constants built so far (the age of a cached one).
    const_clock: u32,
}

/// A packed constant built in `block` at `const_clock` time `at`.
struct RecentConst {
    bits: (u64, u64),
    value: Value,
    block: cranelift_codegen::ir::Block,
    at: u32,
}

/// A packed constant is reused for this many later constant requests
/// (a few ops' worth), then rebuilt: reuse saves a constant-pool load per
/// use, and the bound keeps its live range short, which the register
/// allocator needs in large functions (see `lower::WINDOW`).
const CONST_REUSE: u32 = 40;

impl<'a, 'b> Emitter<'a, 'b> {
    pub fn new(b: &'a mut FunctionBuilder<'b>, shims: ShimRefs, int_select: bool) -> Self {
        Emitter {
            b,
            shims,
            int_select,
            consts: Vec::new(),
            const_clock: 0,
        }
    }
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

    // ---- packed intervals -------------------------------------------

    /// An `F64X2` constant with lanes `(l0, l1)`, reused if the same one
    /// was built recently in the current block.
    pub fn vconst(&mut self, l0: f64, l1: f64) -> Value {
        let bits = (l0.to_bits(), l1.to_bits());
        let block = self.b.current_block().expect("inside a block");
        self.const_clock += 1;
        let now = self.const_clock;
        self.consts.retain(|c| now - c.at <= CONST_REUSE);
        if let Some(c) = self
            .consts
            .iter()
            .find(|c| c.bits == bits && c.block == block)
        {
            return c.value;
        }
        let value = self.vconst_fresh(l0, l1);
        self.consts.push(RecentConst {
            bits,
            value,
            block,
            at: now,
        });
        value
    }

    fn vconst_fresh(&mut self, l0: f64, l1: f64) -> Value {
        let mut bytes = l0.to_le_bytes().to_vec();
        bytes.extend_from_slice(&l1.to_le_bytes());
        let c = self.b.func.dfg.constants.insert(ConstantData::from(bytes));
        self.b.ins().vconst(types::F64X2, c)
    }

    /// A byte shuffle of two `F64X2` values (`mask` indexes the 32 bytes
    /// of `x` then `y`); the x64 backend turns the masks used here into one
    /// `pshufd` or `pblendw`.
    fn shuffle(&mut self, x: Value, y: Value, mask: [u8; 16]) -> Value {
        let le = MemFlagsData::new().with_endianness(Endianness::Little);
        let xb = self.b.ins().bitcast(types::I8X16, le, x);
        let yb = self.b.ins().bitcast(types::I8X16, le, y);
        let imm = self
            .b
            .func
            .dfg
            .immediates
            .push(ConstantData::from(mask.to_vec()));
        let r = self.b.ins().shuffle(xb, yb, imm);
        self.b.ins().bitcast(types::F64X2, le, r)
    }

    /// `(x1, x0)`.
    fn swap(&mut self, x: Value) -> Value {
        self.shuffle(x, x, [8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7])
    }

    /// `(x0, y1)`.
    fn blend(&mut self, x: Value, y: Value) -> Value {
        let mut m = [0u8; 16];
        for (i, b) in m.iter_mut().enumerate() {
            *b = if i < 8 { i as u8 } else { 16 + i as u8 };
        }
        self.shuffle(x, y, m)
    }

    /// A packed compare as an `F64X2` bit mask.
    fn vcmp(&mut self, cc: FloatCC, x: Value, y: Value) -> Value {
        let m = self.b.ins().fcmp(cc, x, y);
        self.b.ins().bitcast(types::F64X2, MemFlagsData::new(), m)
    }

    /// `maxpd x, y` lane-wise: `x > y ? x : y` (`interval::mx`); the
    /// backend matches exactly this shape.
    pub(super) fn vmax(&mut self, x: Value, y: Value) -> Value {
        let m = self.vcmp(FloatCC::LessThan, y, x);
        self.b.ins().bitselect(m, x, y)
    }

    /// `minpd x, y` lane-wise: `x < y ? x : y` (`interval::mn`).
    pub(super) fn vmin(&mut self, x: Value, y: Value) -> Value {
        let m = self.vcmp(FloatCC::LessThan, x, y);
        self.b.ins().bitselect(m, x, y)
    }

    /// Lane-wise: NaN where `a` or `b` is NaN, else `r`.
    fn vnan_if(&mut self, a: Value, b: Value, r: Value) -> Value {
        let m = self.vcmp(FloatCC::Unordered, a, b);
        self.b.ins().bor(r, m)
    }

    /// Both lanes NaN where any lane of `a` or `b` is NaN, else `r`: the
    /// `is_empty() → EMPTY` test of the reference.
    fn vempty_if(&mut self, a: Value, b: Value, r: Value) -> Value {
        let m = self.vcmp(FloatCC::Unordered, a, b);
        let s = self.swap(m);
        let m = self.b.ins().bor(m, s);
        self.b.ins().bor(r, m)
    }

    /// `interval::up` on both lanes: `c + max(|c|·2⁻⁵², 2⁻⁵¹¹)` with
    /// `c = max(-MAX, v)` (NaN stays NaN: `maxpd` returns its second
    /// operand).
    pub fn vup(&mut self, v: Value) -> Value {
        let neg_max = self.vconst(-f64::MAX, -f64::MAX);
        let c = self.vmax(neg_max, v);
        let a = self.vabs(c);
        let step = self.vconst(f64::EPSILON, f64::EPSILON);
        let floor_step = self.vconst(crate::interval::FLOOR_STEP, crate::interval::FLOOR_STEP);
        let t = self.b.ins().fmul(a, step);
        let t = self.vmax(t, floor_step);
        self.b.ins().fadd(c, t)
    }

    /// `interval::up_sum` on both lanes: `c + |c|·2⁻⁵²` with
    /// `c = max(-MAX, v)` (an exact zero stays zero).
    pub fn vup_sum(&mut self, v: Value) -> Value {
        let neg_max = self.vconst(-f64::MAX, -f64::MAX);
        let c = self.vmax(neg_max, v);
        let a = self.vabs(c);
        let step = self.vconst(f64::EPSILON, f64::EPSILON);
        let t = self.b.ins().fmul(a, step);
        self.b.ins().fadd(c, t)
    }

    /// All ones in both lanes where `x` is the interval [0, 0] (both lanes
    /// zero), none elsewhere (NaN lanes compare unequal).
    fn vzero_mask(&mut self, x: Value) -> Value {
        let z = self.vconst(0.0, 0.0);
        let m = self.vcmp(FloatCC::Equal, x, z);
        let s = self.swap(m);
        self.b.ins().band(m, s)
    }

    /// `|x|` lane-wise, as one `andpd` with a (reused) mask constant
    /// (Cranelift's `fabs` rebuilds the mask with two instructions).
    pub(super) fn vabs(&mut self, x: Value) -> Value {
        let m = f64::from_bits(0x7fff_ffff_ffff_ffff);
        let m = self.vconst(m, m);
        self.b.ins().band(x, m)
    }

    /// Lane 0 negated: `(-x0, x1)`; turns `[lo, hi]` into lanes and back.
    fn flip_lo(&mut self, x: Value) -> Value {
        let m = self.vconst(-0.0, 0.0);
        self.b.ins().bxor(x, m)
    }

    /// Loads an `Interval` (`[lo, hi]` in memory) as lanes.
    pub fn iv_load(&mut self, p: Value, offset: i32) -> Iv {
        let v = self
            .b
            .ins()
            .load(types::F64X2, MemFlagsData::new().with_notrap(), p, offset);
        Iv(self.flip_lo(v))
    }

    /// Stores lanes as an `Interval`.
    pub fn iv_store(&mut self, a: Iv, p: Value, offset: i32) {
        let v = self.flip_lo(a.0);
        self.b
            .ins()
            .store(MemFlagsData::new().with_notrap(), v, p, offset);
    }

    /// The scalar lanes `(-lo, hi)`.
    pub fn iv_lanes(&mut self, a: Iv) -> (Value, Value) {
        (
            self.b.ins().extractlane(a.0, 0),
            self.b.ins().extractlane(a.0, 1),
        )
    }

    /// The bounds `(lo, hi)` as scalars.
    pub(super) fn iv_bounds(&mut self, a: Iv) -> (Value, Value) {
        let (n, h) = self.iv_lanes(a);
        (self.neg(n), h)
    }

    /// Lanes from the bounds `(lo, hi)`.
    pub(super) fn iv_from_bounds(&mut self, lo: Value, hi: Value) -> Iv {
        let n = self.neg(lo);
        let v = self.b.ins().scalar_to_vector(types::F64X2, n);
        Iv(self.b.ins().insertlane(v, hi, 1))
    }

    /// `c ? a : b` on intervals.
    pub fn iv_select(&mut self, c: Value, a: Iv, b: Iv) -> Iv {
        if !self.int_select {
            return Iv(self.b.ins().select(c, a.0, b.0));
        }
        // Branch-free in large functions (see `select`): a lane mask.
        let m = self.b.ins().bmask(types::I64, c);
        let m = self.b.ins().splat(types::I64X2, m);
        let m = self.b.ins().bitcast(types::F64X2, MemFlagsData::new(), m);
        Iv(self.b.ins().bitselect(m, a.0, b.0))
    }

    pub fn iv_const(&mut self, v: f64) -> Iv {
        Iv(self.vconst(-v, v))
    }

    /// `Interval::neg`: swap the lanes (exact).
    pub fn iv_neg(&mut self, a: Iv) -> Iv {
        Iv(self.swap(a.0))
    }

    pub fn iv_add(&mut self, a: Iv, b: Iv) -> Iv {
        let s = self.b.ins().fadd(a.0, b.0);
        Iv(self.vup_sum(s))
    }

    pub fn iv_sub(&mut self, a: Iv, b: Iv) -> Iv {
        let bs = self.swap(b.0);
        let s = self.b.ins().fadd(a.0, bs);
        Iv(self.vup_sum(s))
    }

    /// `Interval::hull4` with packed products or quotients: lane 0 gathers
    /// the negated candidates, lane 1 the plain ones, in the reference's
    /// order, each `max` skipping a NaN candidate; a lane with a NaN
    /// candidate then also takes 0.
    fn hull4(&mut self, a: Iv, b: Iv, div: bool) -> Value {
        let bn = self.flip_lo(b.0); // (b.lo, b.hi)
        let bs = self.swap(bn); // (b.hi, b.lo)
        let sa = self.swap(a.0);
        let nas = self.b.ins().fneg(sa); // (-a.hi, a.lo)
        let ninf = self.vconst(f64::NEG_INFINITY, f64::NEG_INFINITY);
        let mut acc = ninf;
        let mut p = Vec::with_capacity(4);
        for (x, y) in [(a.0, bn), (a.0, bs), (nas, bn), (nas, bs)] {
            let q = if div {
                self.b.ins().fdiv(x, y)
            } else {
                self.b.ins().fmul(x, y)
            };
            acc = self.vmax(q, acc);
            p.push(q);
        }
        let n01 = self.vcmp(FloatCC::Unordered, p[0], p[1]);
        let n23 = self.vcmp(FloatCC::Unordered, p[2], p[3]);
        let any_nan = self.b.ins().bor(n01, n23);
        // 0 where a candidate was NaN, -inf elsewhere.
        let z = self.b.ins().band_not(ninf, any_nan);
        let acc = self.vmax(z, acc);
        self.vup(acc)
    }

    /// `Interval::mul`. A factor that is a positive or negative constant
    /// takes a short path with the same bits: the hull of `a·[c, c]` is
    /// `a·c` (lanes swapped for c < 0), since the maxima the general path
    /// picks are those same products.
    pub fn iv_mul(&mut self, a: Iv, b: Iv, b_const: Option<f64>) -> Iv {
        let r = match b_const {
            Some(c) if c.is_finite() && c != 0.0 => {
                let x = if c > 0.0 { a.0 } else { self.swap(a.0) };
                let k = self.vconst(c.abs(), c.abs());
                let p = self.b.ins().fmul(x, k);
                self.vup(p)
            }
            _ => self.hull4(a, b, false),
        };
        // A factor [0, 0] makes the product exactly [0, 0] (lanes +0);
        // an EMPTY one still wins below.
        let za = self.vzero_mask(a.0);
        let zero = match b_const {
            Some(c) if c.is_finite() && c != 0.0 => za,
            _ => {
                let zb = self.vzero_mask(b.0);
                self.b.ins().bor(za, zb)
            }
        };
        let r = self.b.ins().band_not(r, zero);
        Iv(self.vempty_if(a.0, b.0, r))
    }

    /// `Interval::div`: the quotient hull when 0 is outside the divisor
    /// (`b.lo > 0` or `b.hi < 0`: a lane of `(-b.lo, b.hi)` below 0);
    /// otherwise an out-of-line call of `Interval::div_by_zero_part`, a
    /// rare branch that keeps the common path short.
    pub fn iv_div(&mut self, a: Iv, b: Iv) -> Iv {
        let z = self.vconst(0.0, 0.0);
        let neg = self.b.ins().fcmp(FloatCC::LessThan, b.0, z);
        let zero_outside = self.b.ins().vany_true(neg);
        let fast = self.b.create_block();
        let slow = self.b.create_block();
        let join = self.b.create_block();
        let r = self.b.append_block_param(join, types::F64X2);
        self.b.set_cold_block(slow);
        self.b.ins().brif(zero_outside, fast, &[], slow, &[]);
        self.b.seal_block(fast);
        self.b.seal_block(slow);

        self.b.switch_to_block(fast);
        let h = self.hull4(a, b, true);
        // [0, 0] divided by a divisor without 0 is exactly [0, 0].
        let za = self.vzero_mask(a.0);
        let h = self.b.ins().band_not(h, za);
        let h = self.vempty_if(a.0, b.0, h);
        self.b.ins().jump(join, &[BlockArg::Value(h)]);

        self.b.switch_to_block(slow);
        let (alo, ahi) = self.iv_bounds(a);
        let (blo, bhi) = self.iv_bounds(b);
        let call = self
            .b
            .ins()
            .call(self.shims.get(Shim::IntervalDivZero), &[alo, ahi, blo, bhi]);
        let res = self.b.inst_results(call).to_vec();
        let q = self.iv_from_bounds(res[0], res[1]);
        self.b.ins().jump(join, &[BlockArg::Value(q.0)]);

        self.b.seal_block(join);
        self.b.switch_to_block(join);
        Iv(r)
    }

    /// `Interval::abs`: lanes `(min(0, min(n, h)), max(h, n))`.
    pub fn iv_abs(&mut self, a: Iv) -> Iv {
        let s = self.swap(a.0);
        let lo = self.vmin(a.0, s);
        let hi = self.vmax(a.0, s);
        let r = self.blend(lo, hi);
        let c = self.vconst(0.0, f64::INFINITY);
        Iv(self.vmin(c, r))
    }

    /// `Interval::square`: `up(r·|r|)` of the `abs` lanes, lane 0 clamped
    /// at 0 (lane 1 of the clamp constant, +inf, leaves lane 1 alone).
    pub fn iv_square(&mut self, a: Iv) -> Iv {
        let r = self.iv_abs(a);
        let m = self.vabs(r.0);
        let p = self.b.ins().fmul(r.0, m);
        let u = self.vup(p);
        let c = self.vconst(0.0, f64::INFINITY);
        Iv(self.vmin(c, u))
    }

    /// `Interval::sqrt`.
    pub fn iv_sqrt(&mut self, a: Iv) -> Iv {
        let x = self.flip_lo(a.0); // (lo, hi)
        let c = self.vconst(0.0, f64::NEG_INFINITY);
        let x = self.vmax(c, x); // (mx(0, lo), hi)
        let s = self.b.ins().sqrt(x);
        let s = self.flip_lo(s);
        let u = self.vup(s);
        let c = self.vconst(0.0, f64::INFINITY);
        let r = self.vmin(c, u);
        Iv(self.vempty_if(r, r, r))
    }

    /// `Interval::min`: lanes `(max(-lo), min(hi))`, NaN lane-wise.
    pub fn iv_min(&mut self, a: Iv, b: Iv) -> Iv {
        let x = self.vmax(a.0, b.0);
        let y = self.vmin(a.0, b.0);
        let r = self.blend(x, y);
        Iv(self.vnan_if(a.0, b.0, r))
    }

    /// `Interval::max`: lanes `(min(-lo), max(hi))`, NaN lane-wise.
    pub fn iv_max(&mut self, a: Iv, b: Iv) -> Iv {
        let x = self.vmin(a.0, b.0);
        let y = self.vmax(a.0, b.0);
        let r = self.blend(x, y);
        Iv(self.vnan_if(a.0, b.0, r))
    }

    /// `Interval::hull`: lane-wise max, skipping a NaN lane of `b`.
    pub fn iv_hull(&mut self, a: Iv, b: Iv) -> Iv {
        let m = self.vmax(a.0, b.0);
        let b_nan = self.vcmp(FloatCC::Unordered, b.0, b.0);
        Iv(self.b.ins().bitselect(b_nan, a.0, m))
    }
}
