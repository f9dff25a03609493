//! Integer powers (unrolled binary exponentiation, point and interval) and
//! calls of the Rust shims, as [`Emitter`] methods.

use cranelift_codegen::ir::{InstBuilder, Value};

use super::emit::{Emitter, Iv};
use super::shims::Shim;

impl Emitter<'_, '_> {
    /// `interval::binary_pow` unrolled for the constant `n`, with `mul`
    /// emitting each product.
    fn binary_pow(
        &mut self,
        x: Value,
        mut n: u64,
        one: impl Fn(&mut Self) -> Value,
        mul: impl Fn(&mut Self, Value, Value) -> Value,
    ) -> Value {
        let mut result: Option<Value> = None;
        let mut base = x;
        while n > 0 {
            if n & 1 == 1 {
                result = Some(match result {
                    None => base,
                    Some(r) => mul(self, r, base),
                });
            }
            n >>= 1;
            if n > 0 {
                base = mul(self, base, base);
            }
        }
        result.unwrap_or_else(|| one(self))
    }

    /// `interval::pow_up` on both lanes: products `up(x·|y|)`.
    fn vpow_up(&mut self, v: Value, n: u64) -> Value {
        let one = |e: &mut Self| e.vconst(1.0, 1.0);
        self.binary_pow(v, n, one, |e, x, y| {
            let m = e.vabs(y);
            let p = e.b.ins().fmul(x, m);
            e.vup(p)
        })
    }

    /// `interval::powi_unsigned` unrolled for the constant `n`, in
    /// round-to-nearest (the point semantics).
    fn pow_unrolled(&mut self, x: Value, n: u64) -> Value {
        self.binary_pow(x, n, |e| e.c(1.0), |e, a, b| e.mul(a, b))
    }

    /// `interval::powi_point` for the constant `n` (widened to i64 so that
    /// the gradient's `n - 1` cannot overflow).
    pub fn powi_point(&mut self, x: Value, n: i64) -> Value {
        let p = self.pow_unrolled(x, n.unsigned_abs());
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
            let r = self.iv_abs(a);
            let p = self.vpow_up(r.0, m);
            let c = self.vconst(0.0, f64::INFINITY);
            Iv(self.vmin(c, p))
        } else {
            Iv(self.vpow_up(a.0, m))
        };
        if n < 0 {
            let one = self.iv_const(1.0);
            return self.iv_div(one, p);
        }
        p
    }

    /// A point transcendental through its shim.
    pub fn call_point_unary(&mut self, shim: Shim, a: Value) -> Value {
        let call = self.b.ins().call(self.shims.get(shim), &[a]);
        self.b.inst_results(call)[0]
    }

    pub fn call_point_binary(&mut self, shim: Shim, a: Value, b: Value) -> Value {
        let call = self.b.ins().call(self.shims.get(shim), &[a, b]);
        self.b.inst_results(call)[0]
    }

    /// An interval transcendental through its shim: bounds travel as f64
    /// arguments and come back as two f64 results (xmm0, xmm1), which is
    /// the C ABI of a returned `#[repr(C)]` pair of doubles.
    pub fn call_iv_unary(&mut self, shim: Shim, a: Iv) -> Iv {
        let (lo, hi) = self.iv_bounds(a);
        let call = self.b.ins().call(self.shims.get(shim), &[lo, hi]);
        let r = self.b.inst_results(call).to_vec();
        self.iv_from_bounds(r[0], r[1])
    }

    pub fn call_iv_binary(&mut self, shim: Shim, a: Iv, b: Iv) -> Iv {
        let (alo, ahi) = self.iv_bounds(a);
        let (blo, bhi) = self.iv_bounds(b);
        let call = self
            .b
            .ins()
            .call(self.shims.get(shim), &[alo, ahi, blo, bhi]);
        let r = self.b.inst_results(call).to_vec();
        self.iv_from_bounds(r[0], r[1])
    }
}
