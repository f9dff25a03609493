//! References for the interpreter's conformance tests written out here,
//! from std's f64 methods (the platform's libm behind them) and calculus,
//! with no code from `ibeam::ir::semantics` or `ibeam::interval`. The
//! suite's own references are the rules the interpreter runs, so against
//! them the interpreter checks nothing; against these it does:
//! - point values of every op: to the bit where the op is exact or
//!   correctly rounded in f64 (`+ - * /`, sqrt, the steps, min, max, mod,
//!   powi's binary exponentiation), within a few ulps for the
//!   transcendentals (ours are libm's or a table's, std's the platform's);
//! - derivatives by calculus at smooth points, point and interval;
//! - intervals: they contain the reference values at dense samples and at
//!   the points where ops change behaviour, and for the ops of
//!   [`super::tight`] they hold the tightest result and are at most two
//!   ulps wider (exactly it for the steps);
//! - random functions op by op, each value against its op's reference
//!   applied to the values of its operands.
//!
//! The interval checks are in [`intervals`].

use super::suite::Make;
use super::*;

pub mod intervals;

/// How closely a value must match its reference.
#[derive(Copy, Clone, Debug)]
pub enum Agree {
    /// To the bit (any NaN equal to any other).
    Bits,
    /// Within this many floats (NaN only against NaN).
    Ulps(u64),
}

/// Transcendentals: libm and glibc are each within 1 ulp of the real
/// value (ours: `exp` within 0.55), so 2 floats apart at most.
const LIBM: Agree = Agree::Ulps(2);
/// glibc documents up to 2 ulps for sinh, cosh and tanh.
const HYPERBOLIC: Agree = Agree::Ulps(3);

/// The order of floats as integers: adjacent floats differ by 1, both
/// zeros are 0.
fn ordered(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    if b < 0 { -(b & i64::MAX) } else { b }
}

/// Whether `got` matches `want` as `how` asks.
pub fn agrees(got: f64, want: f64, how: Agree) -> bool {
    match how {
        Agree::Bits => same(got, want),
        Agree::Ulps(k) => {
            same(got, want)
                || (!got.is_nan() && !want.is_nan() && ordered(got).abs_diff(ordered(want)) <= k)
        }
    }
}

/// -1, 0 or 1 as `x` is negative, zero or positive; NaN for NaN.
fn sign(x: f64) -> f64 {
    if x.is_nan() {
        f64::NAN
    } else if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// A one-operand op by std, as `UnaryOp`'s docs define it.
pub fn unary(op: UnaryOp, x: f64) -> (f64, Agree) {
    use Agree::Bits;
    match op {
        UnaryOp::Neg => (-x, Bits),
        UnaryOp::Abs => (x.abs(), Bits),
        UnaryOp::Square => (x * x, Bits),
        UnaryOp::Sqrt => (x.sqrt(), Bits),
        UnaryOp::Exp => (x.exp(), LIBM),
        UnaryOp::Ln => (x.ln(), LIBM),
        UnaryOp::Sin => (x.sin(), LIBM),
        UnaryOp::Cos => (x.cos(), LIBM),
        UnaryOp::Tan => (x.tan(), LIBM),
        UnaryOp::Asin => (x.asin(), LIBM),
        UnaryOp::Acos => (x.acos(), LIBM),
        UnaryOp::Atan => (x.atan(), LIBM),
        UnaryOp::Sinh => (x.sinh(), HYPERBOLIC),
        UnaryOp::Cosh => (x.cosh(), HYPERBOLIC),
        UnaryOp::Tanh => (x.tanh(), HYPERBOLIC),
        UnaryOp::Floor => (x.floor(), Bits),
        UnaryOp::Ceil => (x.ceil(), Bits),
        // Halves away from zero.
        UnaryOp::Round => (x.round(), Bits),
        UnaryOp::Sign => (sign(x), Bits),
    }
}

/// A two-operand op by std, as `BinaryOp`'s docs define it.
pub fn binary(op: BinaryOp, x: f64, y: f64) -> (f64, Agree) {
    use Agree::Bits;
    let nan = x.is_nan() || y.is_nan();
    match op {
        BinaryOp::Add => (x + y, Bits),
        BinaryOp::Sub => (x - y, Bits),
        BinaryOp::Mul => (x * y, Bits),
        BinaryOp::Div => (x / y, Bits),
        // NaN if either is; on a tie the second operand (so the sign of a
        // zero result is fixed).
        BinaryOp::Min if nan => (f64::NAN, Bits),
        BinaryOp::Min => (if x < y { x } else { y }, Bits),
        BinaryOp::Max if nan => (f64::NAN, Bits),
        BinaryOp::Max => (if x > y { x } else { y }, Bits),
        BinaryOp::Atan2 => (x.atan2(y), LIBM),
        // NaN in, NaN out, and no negative base; -0 counts as +0.
        BinaryOp::Pow if nan || x < 0.0 => (f64::NAN, Bits),
        BinaryOp::Pow => ((x + 0.0).powf(y), LIBM),
        // The least non-negative remainder: fmod is exact, the one sum
        // after it rounds.
        BinaryOp::Mod => {
            let r = x % y;
            (if r < 0.0 { r + y.abs() } else { r }, Bits)
        }
    }
}

/// `x^n` as `powi` defines it: binary exponentiation from the lowest bit,
/// every product rounded to nearest; `1 / x^|n|` for negative `n`.
pub fn powi(x: f64, n: i32) -> f64 {
    let (mut base, mut k, mut acc) = (x, n.unsigned_abs(), None::<f64>);
    while k > 0 {
        if k & 1 == 1 {
            acc = Some(acc.map_or(base, |a| a * base));
        }
        k >>= 1;
        if k > 0 {
            base *= base;
        }
    }
    let p = acc.unwrap_or(1.0);
    if n < 0 { 1.0 / p } else { p }
}

/// One op of every kind with its reference of `(x, y)`.
pub struct Case {
    /// What failures call it.
    pub name: String,
    /// The function `op(x, y)`.
    pub f: Function,
    /// Whether it reads `y`.
    pub binary: bool,
    /// Its value and how closely it must match.
    pub reference: Box<dyn Fn(f64, f64) -> (f64, Agree)>,
}

/// The powers `powi` is checked at: small ones and the extremes of i32.
pub const POWERS: [i32; 17] = [
    -17,
    -4,
    -3,
    -2,
    -1,
    0,
    1,
    2,
    3,
    4,
    5,
    6,
    8,
    13,
    64,
    i32::MAX,
    i32::MIN,
];

/// Every unary and binary op, and `powi` at [`POWERS`].
pub fn cases() -> Vec<Case> {
    let mut v: Vec<Case> = Vec::new();
    for op in UNARY_OPS {
        v.push(Case {
            name: format!("{op:?}"),
            f: unary_fn(op),
            binary: false,
            reference: Box::new(move |x, _| unary(op, x)),
        });
    }
    for op in BINARY_OPS {
        v.push(Case {
            name: format!("{op:?}"),
            f: binary_fn(op),
            binary: true,
            reference: Box::new(move |x, y| binary(op, x, y)),
        });
    }
    for n in POWERS {
        v.push(Case {
            name: format!("powi {n}"),
            f: powi_fn(n),
            binary: false,
            reference: Box::new(move |x, _| (powi(x, n), Agree::Bits)),
        });
    }
    v
}

/// An argument: an edge value, a small number or integer or half (the
/// steps' jumps and ties), or a float of any magnitude.
fn argument(rng: &mut Rng) -> f64 {
    match rng.below(5) {
        0 => EDGE_VALUES[rng.below(EDGE_VALUES.len())],
        1 => rng.range(-4.0, 4.0),
        2 => (rng.range(-20.0, 20.0) * 2.0).round() / 2.0,
        3 => rng.range(-1e3, 1e3),
        _ => f64::from_bits(rng.next_u64()),
    }
}

/// Point values of every op against its reference on every pair of edge
/// values and on random arguments.
pub fn check_points(make: Make) {
    let mut rng = Rng::new(1788);
    for case in cases() {
        let e = make(&case.f);
        let mut args: Vec<(f64, f64)> = Vec::new();
        for &x in &EDGE_VALUES {
            for &y in &EDGE_VALUES {
                args.push((x, y));
            }
        }
        args.extend((0..3000).map(|_| (argument(&mut rng), argument(&mut rng))));
        for (x, y) in args {
            let got = e.point([x, y, 0.5]);
            let (want, how) = (case.reference)(x, y);
            assert!(
                agrees(got, want, how),
                "{}({x:e}, {y:e}) = {got:e}, std gives {want:e} ({how:?})",
                case.name
            );
        }
    }
}

/// `d op(x) / dx` by calculus, where `op` is smooth at `x`.
fn unary_slope(op: UnaryOp, x: f64) -> f64 {
    match op {
        UnaryOp::Neg => -1.0,
        UnaryOp::Abs => x.signum(),
        UnaryOp::Square => 2.0 * x,
        UnaryOp::Sqrt => 0.5 / x.sqrt(),
        UnaryOp::Exp => x.exp(),
        UnaryOp::Ln => 1.0 / x,
        UnaryOp::Sin => x.cos(),
        UnaryOp::Cos => -x.sin(),
        UnaryOp::Tan => 1.0 / (x.cos() * x.cos()),
        UnaryOp::Asin => 1.0 / (1.0 - x * x).sqrt(),
        UnaryOp::Acos => -1.0 / (1.0 - x * x).sqrt(),
        UnaryOp::Atan => 1.0 / (1.0 + x * x),
        UnaryOp::Sinh => x.cosh(),
        UnaryOp::Cosh => x.sinh(),
        UnaryOp::Tanh => 1.0 / (x.cosh() * x.cosh()),
        UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round | UnaryOp::Sign => 0.0,
    }
}

/// `(∂/∂x, ∂/∂y)` of `op(x, y)` by calculus, where it is smooth.
fn binary_slopes(op: BinaryOp, x: f64, y: f64) -> (f64, f64) {
    match op {
        BinaryOp::Add => (1.0, 1.0),
        BinaryOp::Sub => (1.0, -1.0),
        BinaryOp::Mul => (y, x),
        BinaryOp::Div => (1.0 / y, -x / (y * y)),
        BinaryOp::Min => {
            if x < y {
                (1.0, 0.0)
            } else {
                (0.0, 1.0)
            }
        }
        BinaryOp::Max => {
            if x > y {
                (1.0, 0.0)
            } else {
                (0.0, 1.0)
            }
        }
        // atan2(x, y) is the angle of the point (y, x).
        BinaryOp::Atan2 => (y / (x * x + y * y), -x / (x * x + y * y)),
        BinaryOp::Pow => (y * x.powf(y - 1.0), x.powf(y) * x.ln()),
        // x - |y|·floor(x/|y|), the floor constant between its jumps.
        BinaryOp::Mod => (1.0, -y.signum() * (x / y.abs()).floor()),
    }
}

/// `(∂/∂x, ∂/∂y)` of one op at `(x, y)`.
type Slopes = Box<dyn Fn(f64, f64) -> (f64, f64)>;

/// Whether `got` is `want` to a relative 1e-9 (exactly, for 0).
fn close_slope(got: f64, want: f64) -> bool {
    (got - want).abs() <= 1e-9 * want.abs()
}

/// `i` widened by a relative 1e-9 (where a slope by calculus may differ
/// from the rounded rules by rounding alone).
fn loosen(i: Interval) -> Interval {
    let pad = |v: f64| 1e-9 * v.abs();
    Interval::new(i.lo - pad(i.lo), i.hi + pad(i.hi))
}

/// Point gradients of every op at smooth points, and interval gradients
/// over small boxes around them at the boxes' corners and centre, against
/// calculus.
pub fn check_derivatives(make: Make) {
    let mut rng = Rng::new(11);
    let ops: Vec<(String, Function, Slopes)> = UNARY_OPS
        .iter()
        .map(|&op| {
            let slope: Slopes = Box::new(move |x, _| (unary_slope(op, x), 0.0));
            (format!("{op:?}"), unary_fn(op), slope)
        })
        .chain(BINARY_OPS.iter().map(|&op| {
            let slope: Slopes = Box::new(move |x, y| binary_slopes(op, x, y));
            (format!("{op:?}"), binary_fn(op), slope)
        }))
        .chain((-4..=6).map(|n: i32| {
            let slope: Slopes = Box::new(move |x, _| (f64::from(n) * x.powi(n - 1), 0.0));
            (format!("powi {n}"), powi_fn(n), slope)
        }))
        .collect();
    for (name, f, slope) in ops {
        let e = make(&f);
        for _ in 0..60 {
            // Smooth for every op: positive, off the integers and halves
            // (random reals), inside (-1, 1) for asin and acos.
            let x = if name == "Asin" || name == "Acos" {
                rng.range(0.05, 0.95)
            } else {
                rng.range(0.3, 3.0)
            };
            let y = (x + rng.pick(&[-1.0, 1.0]) * rng.range(0.2, 2.0)).max(0.1);
            let g = e.point_grad([x, y, 0.7]);
            let (dx, dy) = slope(x, y);
            assert!(
                close_slope(g.d[0], dx) && close_slope(g.d[1], dy) && g.d[2] == 0.0,
                "{name} at ({x}, {y}): gradient {:?}, calculus ({dx:e}, {dy:e}, 0)",
                g.d
            );
            let r = 1e-4;
            let bx = [x, y, 0.7].map(|c| Interval::new(c - r, c + r));
            let ig = e.interval_grad(bx);
            for (px, py) in [
                (x - r, y - r),
                (x + r, y - r),
                (x - r, y + r),
                (x + r, y + r),
                (x, y),
            ] {
                let (dx, dy) = slope(px, py);
                assert!(
                    loosen(ig.d[0]).contains(dx) && loosen(ig.d[1]).contains(dy),
                    "{name} over {bx:?}: {:?} misses ({dx:e}, {dy:e}) at ({px}, {py})",
                    ig.d
                );
            }
        }
    }
}
