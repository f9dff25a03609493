//! What each op means: its point rule, its interval rule and its
//! derivative rules (point and interval dual numbers), written once. The
//! reference interpreter (`eval::interp`) is a loop over these; the JIT
//! calls the point rules for the transcendentals and is tested to give the
//! same bits as all of them.
//!
//! # Derivative rules
//! The rules live in [`grad_unary`], [`grad_binary`], [`grad_powi`] and
//! their interval twins [`igrad_unary`], [`igrad_binary`], [`igrad_powi`], so
//! the JIT can reuse them. Each is the chain rule `f'(a)·da`, with these
//! conventions:
//! - A partial that is exactly 0 stays 0 (`chain`): a value that does not
//!   depend on a variable contributes nothing to its partial even where
//!   `f'(a)` is infinite (sqrt at 0, ln at 0). Intervals get the same effect
//!   from [`Interval::mul`], which drops the 0·inf products.
//! - `abs` at 0: point derivative `sign(a)·da` with sign(0) = 0; interval
//!   `[-1, 1]·da` when 0 is inside the operand, `[0, 1]·da` (`[-1, 0]·da`)
//!   when 0 is its lower (upper) end.
//! - `min`/`max`: the derivative of the operand the point op returns (on a
//!   tie, the second operand, as [`min_nan`] and [`max_nan`] return it);
//!   interval: that operand's derivative when the operand intervals are
//!   ordered strictly, else the hull of both.
//! - `sqrt` at 0: `f'(0) = +inf`, so the partial is ±inf (or 0 by the rule
//!   above). `ln` at 0 likewise; `ln` and `sqrt` of a negative, and `a / 0`,
//!   give NaN or ±inf as IEEE arithmetic does.
//! - `pow(a, b)`: `b·a^(b-1)·da + a^b·ln(a)·db`, the second term 0 where
//!   `a^b = 0` (0^b for b > 0 is 0 for every b nearby). NaN for a < 0.
//! - `powi(a, n)`: `n·a^(n-1)·da`; 0 for n = 0.
//!
//! # Partial domains
//! The interval of every op covers the op's point values at every point of
//! its operand box where those are real; points where an op is undefined
//! (sqrt or ln of a negative, division by 0, pow of a negative base) are
//! simply dropped, so `sqrt([-1, 4]) = [0, 2]`. EMPTY means the op is
//! undefined on the whole box; it propagates through every later op (except
//! `powi(_, 0)`, which is 1 everywhere, NaN included). For the tracer this is
//! the right reading: if `F(box)` is EMPTY, f is undefined at every point of
//! the box, so the box holds no root; if `F(box)` is not EMPTY and excludes
//! 0, f has no real zero in the box. No root of the real function f (a
//! point where every op is defined and f = 0) is ever missed, because every
//! op's interval contains every real value of that op on the box. Interval
//! gradients follow the same rule over the defined part (the ln derivative
//! `1/a` over the non-negative part of `a`, and so on).

use super::{BinaryOp, Op, UnaryOp};
use crate::interval::{Interval, max_nan, min_nan, powi_point};

/// A point value and its gradient (∂f/∂x, ∂f/∂y, ∂f/∂z).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Grad {
    /// f at the point.
    pub v: f64,
    /// The partial derivatives.
    pub d: [f64; 3],
}

/// An interval of f over a box and an interval for each partial derivative.
#[derive(Copy, Clone, Debug, PartialEq)]
#[repr(C)]
pub struct IntervalGrad {
    /// f over the box.
    pub v: Interval,
    /// ∂f/∂x, ∂f/∂y, ∂f/∂z over the box.
    pub d: [Interval; 3],
}

/// Point semantics of a one-operand op (the JIT calls this for the
/// transcendentals, so both give identical bits).
pub fn point_unary(op: UnaryOp, a: f64) -> f64 {
    match op {
        UnaryOp::Neg => -a,
        UnaryOp::Abs => a.abs(),
        UnaryOp::Square => a * a,
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Exp => libm::exp(a),
        UnaryOp::Ln => libm::log(a),
        UnaryOp::Sin => libm::sin(a),
        UnaryOp::Cos => libm::cos(a),
    }
}

/// Point semantics of a two-operand op.
pub fn point_binary(op: BinaryOp, a: f64, b: f64) -> f64 {
    match op {
        BinaryOp::Add => a + b,
        BinaryOp::Sub => a - b,
        BinaryOp::Mul => a * b,
        BinaryOp::Div => a / b,
        BinaryOp::Min => min_nan(a, b),
        BinaryOp::Max => max_nan(a, b),
        BinaryOp::Atan2 => libm::atan2(a, b),
        BinaryOp::Pow => {
            // NaN in, NaN out (libm's pow(NaN, 0) = pow(1, NaN) = 1 would
            // hide an undefined operand); -0 is taken as +0 so that the
            // result is exp(b·ln a) with ln(±0) = -inf, never negative.
            if a.is_nan() || b.is_nan() || a < 0.0 {
                f64::NAN
            } else {
                libm::pow(a + 0.0, b)
            }
        }
    }
}

/// Point semantics of `powi`.
pub fn point_powi(a: f64, n: i32) -> f64 {
    powi_point(a, n)
}

/// Interval semantics of a one-operand op.
pub fn interval_unary(op: UnaryOp, a: Interval) -> Interval {
    match op {
        UnaryOp::Neg => a.neg(),
        UnaryOp::Abs => a.abs(),
        UnaryOp::Square => a.square(),
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Exp => a.exp(),
        UnaryOp::Ln => a.ln(),
        UnaryOp::Sin => a.sin(),
        UnaryOp::Cos => a.cos(),
    }
}

/// Interval semantics of a two-operand op.
pub fn interval_binary(op: BinaryOp, a: Interval, b: Interval) -> Interval {
    match op {
        BinaryOp::Add => a.add(b),
        BinaryOp::Sub => a.sub(b),
        BinaryOp::Mul => a.mul(b),
        BinaryOp::Div => a.div(b),
        BinaryOp::Min => a.min(b),
        BinaryOp::Max => a.max(b),
        BinaryOp::Atan2 => a.atan2(b),
        BinaryOp::Pow => a.pow(b),
    }
}

// f'(a)·da, keeping an exactly-zero partial at zero (see the module doc).
#[inline]
fn chain(fp: f64, da: f64) -> f64 {
    if da == 0.0 { 0.0 } else { fp * da }
}

#[inline]
fn scale(fp: f64, a: Grad, v: f64) -> Grad {
    Grad {
        v,
        d: [chain(fp, a.d[0]), chain(fp, a.d[1]), chain(fp, a.d[2])],
    }
}

/// Value and gradient of a one-operand op (forward mode).
pub fn grad_unary(op: UnaryOp, a: Grad) -> Grad {
    let v = point_unary(op, a.v);
    match op {
        UnaryOp::Neg => Grad {
            v,
            d: [-a.d[0], -a.d[1], -a.d[2]],
        },
        UnaryOp::Abs => {
            let s = if a.v > 0.0 {
                1.0
            } else if a.v < 0.0 {
                -1.0
            } else if a.v == 0.0 {
                0.0
            } else {
                f64::NAN
            };
            scale(s, a, v)
        }
        UnaryOp::Square => scale(2.0 * a.v, a, v),
        UnaryOp::Sqrt => scale(0.5 / v, a, v),
        UnaryOp::Exp => scale(v, a, v),
        UnaryOp::Ln => scale(1.0 / a.v, a, v),
        UnaryOp::Sin => scale(libm::cos(a.v), a, v),
        UnaryOp::Cos => scale(-libm::sin(a.v), a, v),
    }
}

/// Value and gradient of a two-operand op (forward mode).
pub fn grad_binary(op: BinaryOp, a: Grad, b: Grad) -> Grad {
    let v = point_binary(op, a.v, b.v);
    let d = |f: &dyn Fn(usize) -> f64| [f(0), f(1), f(2)];
    match op {
        BinaryOp::Add => Grad {
            v,
            d: d(&|i| a.d[i] + b.d[i]),
        },
        BinaryOp::Sub => Grad {
            v,
            d: d(&|i| a.d[i] - b.d[i]),
        },
        BinaryOp::Mul => Grad {
            v,
            d: d(&|i| chain(a.v, b.d[i]) + chain(b.v, a.d[i])),
        },
        BinaryOp::Div => Grad {
            v,
            d: d(&|i| (a.d[i] - chain(v, b.d[i])) / b.v),
        },
        BinaryOp::Min => {
            let chosen = if a.v.is_nan() || b.v.is_nan() {
                return Grad {
                    v,
                    d: [f64::NAN; 3],
                };
            } else if a.v < b.v {
                a
            } else {
                b
            };
            Grad { v, d: chosen.d }
        }
        BinaryOp::Max => {
            let chosen = if a.v.is_nan() || b.v.is_nan() {
                return Grad {
                    v,
                    d: [f64::NAN; 3],
                };
            } else if a.v > b.v {
                a
            } else {
                b
            };
            Grad { v, d: chosen.d }
        }
        BinaryOp::Atan2 => {
            // d atan2(y, x) = (x·dy - y·dx) / (x² + y²), with y = a, x = b.
            let r2 = a.v * a.v + b.v * b.v;
            Grad {
                v,
                d: d(&|i| (chain(b.v, a.d[i]) - chain(a.v, b.d[i])) / r2),
            }
        }
        BinaryOp::Pow => {
            // a^0 is 1 for every a: its a-partial is 0 even at a = 0.
            let da = if b.v == 0.0 {
                0.0
            } else {
                point_binary(BinaryOp::Pow, a.v, b.v - 1.0) * b.v
            };
            let db = if v == 0.0 { 0.0 } else { v * libm::log(a.v) };
            Grad {
                v,
                d: d(&|i| chain(da, a.d[i]) + chain(db, b.d[i])),
            }
        }
    }
}

/// Value and gradient of `powi(a, n)` (forward mode).
pub fn grad_powi(a: Grad, n: i32) -> Grad {
    let v = point_powi(a.v, n);
    if n == 0 {
        return Grad { v, d: [0.0; 3] };
    }
    scale(f64::from(n) * point_powi(a.v, n - 1), a, v)
}

#[inline]
fn iscale(fp: Interval, a: IntervalGrad, v: Interval) -> IntervalGrad {
    IntervalGrad {
        v,
        d: [fp.mul(a.d[0]), fp.mul(a.d[1]), fp.mul(a.d[2])],
    }
}

/// Intervals of value and gradient of a one-operand op over a box.
pub fn igrad_unary(op: UnaryOp, a: IntervalGrad) -> IntervalGrad {
    let v = interval_unary(op, a.v);
    match op {
        UnaryOp::Neg => IntervalGrad {
            v,
            d: [a.d[0].neg(), a.d[1].neg(), a.d[2].neg()],
        },
        UnaryOp::Abs => {
            let s = if a.v.is_empty() {
                Interval::EMPTY
            } else if a.v.lo > 0.0 {
                Interval::point(1.0)
            } else if a.v.hi < 0.0 {
                Interval::point(-1.0)
            } else if a.v.lo == 0.0 && a.v.hi == 0.0 {
                Interval::point(0.0)
            } else if a.v.lo == 0.0 {
                Interval::new(0.0, 1.0)
            } else if a.v.hi == 0.0 {
                Interval::new(-1.0, 0.0)
            } else {
                Interval::new(-1.0, 1.0)
            };
            iscale(s, a, v)
        }
        UnaryOp::Square => iscale(a.v.mul(Interval::point(2.0)), a, v),
        UnaryOp::Sqrt => iscale(Interval::point(0.5).div(v), a, v),
        UnaryOp::Exp => iscale(v, a, v),
        UnaryOp::Ln => {
            let pos = if a.v.is_empty() || a.v.hi < 0.0 {
                Interval::EMPTY
            } else {
                Interval::new(a.v.lo.max(0.0), a.v.hi)
            };
            iscale(Interval::point(1.0).div(pos), a, v)
        }
        UnaryOp::Sin => iscale(a.v.cos(), a, v),
        UnaryOp::Cos => iscale(a.v.sin().neg(), a, v),
    }
}

/// Intervals of value and gradient of a two-operand op over a box.
pub fn igrad_binary(op: BinaryOp, a: IntervalGrad, b: IntervalGrad) -> IntervalGrad {
    let v = interval_binary(op, a.v, b.v);
    let d = |f: &dyn Fn(usize) -> Interval| [f(0), f(1), f(2)];
    match op {
        BinaryOp::Add => IntervalGrad {
            v,
            d: d(&|i| a.d[i].add(b.d[i])),
        },
        BinaryOp::Sub => IntervalGrad {
            v,
            d: d(&|i| a.d[i].sub(b.d[i])),
        },
        BinaryOp::Mul => IntervalGrad {
            v,
            d: d(&|i| a.v.mul(b.d[i]).add(b.v.mul(a.d[i]))),
        },
        BinaryOp::Div => IntervalGrad {
            v,
            d: d(&|i| a.d[i].sub(v.mul(b.d[i])).div(b.v)),
        },
        BinaryOp::Min | BinaryOp::Max => {
            // `first`: the op returns a's value at every point of the box.
            let first = if op == BinaryOp::Min {
                a.v.hi < b.v.lo
            } else {
                a.v.lo > b.v.hi
            };
            let second = if op == BinaryOp::Min {
                b.v.hi <= a.v.lo
            } else {
                b.v.lo >= a.v.hi
            };
            IntervalGrad {
                v,
                d: d(&|i| {
                    if v.is_empty() {
                        Interval::EMPTY
                    } else if first {
                        a.d[i]
                    } else if second {
                        b.d[i]
                    } else {
                        a.d[i].hull(b.d[i])
                    }
                }),
            }
        }
        BinaryOp::Atan2 => {
            // atan2(a, b) jumps by 2π across its branch cut (a = 0, b < 0).
            // A box touching the cut (the same test as the value's) has no
            // finite bound on how fast f changes: the derivative formula
            // below would miss the jump, and interval Newton, the centred
            // form and the inclusion test would then drop or misplace the
            // sign change there. Every direction that moves a or b gets the
            // whole line.
            if b.v.lo <= 0.0 && a.v.lo <= 0.0 && 0.0 <= a.v.hi {
                let zero = |x: Interval| x.lo == 0.0 && x.hi == 0.0;
                return IntervalGrad {
                    v,
                    d: d(&|i| {
                        if zero(a.d[i]) && zero(b.d[i]) {
                            Interval::point(0.0)
                        } else {
                            Interval::ENTIRE
                        }
                    }),
                };
            }
            let r2 = a.v.square().add(b.v.square());
            IntervalGrad {
                v,
                d: d(&|i| b.v.mul(a.d[i]).sub(a.v.mul(b.d[i])).div(r2)),
            }
        }
        BinaryOp::Pow => {
            let da = a.v.pow(b.v.sub(Interval::point(1.0))).mul(b.v);
            let db = v.mul(a.v.ln());
            IntervalGrad {
                v,
                d: d(&|i| da.mul(a.d[i]).add(db.mul(b.d[i]))),
            }
        }
    }
}

/// Intervals of value and gradient of `powi(a, n)` over a box.
pub fn igrad_powi(a: IntervalGrad, n: i32) -> IntervalGrad {
    let v = a.v.powi(n);
    if n == 0 {
        return IntervalGrad {
            v,
            d: [Interval::point(0.0); 3],
        };
    }
    iscale(Interval::point(f64::from(n)).mul(a.v.powi(n - 1)), a, v)
}

/// Every value of the function `ops` at `p`, in op order, into `vals`.
pub fn run_point(ops: &[Op], p: [f64; 3], vals: &mut Vec<f64>) {
    vals.clear();
    for op in ops {
        let v = match *op {
            Op::Var(var) => p[var.index()],
            Op::Const(c) => c,
            Op::Unary(u, a) => point_unary(u, vals[a.index()]),
            Op::Binary(o, a, b) => point_binary(o, vals[a.index()], vals[b.index()]),
            Op::Powi(a, n) => point_powi(vals[a.index()], n),
        };
        vals.push(v);
    }
}

/// Every interval of the function `ops` over `b`, in op order, into
/// `vals`.
pub fn run_interval(ops: &[Op], b: [Interval; 3], vals: &mut Vec<Interval>) {
    vals.clear();
    for op in ops {
        let v = match *op {
            Op::Var(var) => b[var.index()],
            Op::Const(c) => Interval::point(c),
            Op::Unary(u, a) => interval_unary(u, vals[a.index()]),
            Op::Binary(o, x, y) => interval_binary(o, vals[x.index()], vals[y.index()]),
            Op::Powi(a, n) => vals[a.index()].powi(n),
        };
        vals.push(v);
    }
}
