//! The JIT against the reference interpreter on the same simplified
//! function. The first byte picks the source of the function: a seed for
//! `ir::random::random_function` (8 bytes), or the rest of the input as a
//! formula string. The remaining bytes give evaluation points and boxes.
//!
//! Checked: point values have equal bits (any NaN equals any NaN), point
//! gradients' values likewise, and the JIT's interval over a box contains
//! the interpreter's and its own point values at the box's corners and
//! centre wherever every intermediate value there is finite (real).

#![no_main]

use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::eval::jit::JitEvaluator;
use ibeam::interval::Interval;
use ibeam::ir::{Function, passes, random};
use libfuzzer_sys::fuzz_target;

/// Reads f64s from the bytes, 8 at a time, mapped to a useful range: most
/// inputs become coordinates in [-4, 4]; some keep their raw bits (huge,
/// tiny, infinite, NaN).
struct Coords<'a>(&'a [u8]);

impl Coords<'_> {
    fn next(&mut self) -> Option<f64> {
        if self.0.len() < 8 {
            return None;
        }
        let (head, rest) = self.0.split_at(8);
        self.0 = rest;
        let bits = u64::from_le_bytes(head.try_into().ok()?);
        Some(if bits & 0xf == 0 {
            f64::from_bits(bits)
        } else {
            (bits >> 11) as f64 / (1u64 << 53) as f64 * 8.0 - 4.0
        })
    }
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn function(data: &[u8]) -> Option<(Function, &[u8])> {
    let (&kind, rest) = data.split_first()?;
    if kind & 1 == 0 {
        if rest.len() < 8 {
            return None;
        }
        let (seed, rest) = rest.split_at(8);
        let seed = u64::from_le_bytes(seed.try_into().ok()?);
        let depth = u32::from(kind >> 1) % 12 + 1;
        Some((random::random_function(seed, depth), rest))
    } else {
        // A formula up to the first NUL byte; points after it.
        let end = rest.iter().position(|&b| b == 0).unwrap_or(rest.len());
        let text = std::str::from_utf8(&rest[..end]).ok()?;
        let f = ibeam::lang::function_from_formula(text).ok()?;
        Some((f, rest.get(end + 1..).unwrap_or(&[])))
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((f, rest)) = function(data) else {
        return;
    };
    let f = passes::simplify(&f);
    let Ok(jit) = JitEvaluator::new(&f) else {
        return;
    };
    if let Err(e) = jit.compile_all() {
        panic!("JIT failed to compile valid IR: {e}");
    }
    let interp = Interpreter::new(f);
    let mut c = Coords(rest);
    while let (Some(x), Some(y), Some(z)) = (c.next(), c.next(), c.next()) {
        let p = [x, y, z];
        let (a, b) = (interp.point(p), jit.point(p));
        assert!(same(a, b), "point at {p:?}: interpreter {a}, JIT {b}");
        let (ga, gb) = (interp.point_grad(p), jit.point_grad(p));
        assert!(
            same(ga.v, gb.v),
            "gradient value at {p:?}: interpreter {}, JIT {}",
            ga.v,
            gb.v
        );
        // A box from this point to the next three coordinates.
        let Some(q) = (|| Some([c.next()?, c.next()?, c.next()?]))() else {
            break;
        };
        if !q.iter().chain(&p).all(|v| v.is_finite()) {
            continue;
        }
        let bx: [Interval; 3] =
            std::array::from_fn(|i| Interval::new(p[i].min(q[i]), p[i].max(q[i])));
        let fi = jit.interval(bx);
        let gi = jit.interval_grad(bx);
        let centre = bx.map(|i| i.mid());
        for k in 0..9 {
            let pt: [f64; 3] = if k == 8 {
                centre
            } else {
                std::array::from_fn(|i| if k >> i & 1 == 0 { bx[i].lo } else { bx[i].hi })
            };
            // Intervals hold the real values of f. A point value is real
            // only if every intermediate value is: ±inf (a pole, an
            // overflow) and NaN are not, and an op can turn them back into
            // a finite number (atan2(inf, 1) = π/2, exp(-inf) = 0) where
            // the interval, rightly, has nothing.
            if !interp.point_values(pt).iter().all(|v| v.is_finite()) {
                continue;
            }
            for v in [interp.point(pt), jit.point(pt)] {
                assert!(
                    fi.contains(v),
                    "interval {fi:?} over {bx:?} misses {v} at {pt:?}"
                );
                assert!(
                    gi.v.contains(v),
                    "interval-gradient value {:?} over {bx:?} misses {v} at {pt:?}",
                    gi.v
                );
            }
        }
    }
});
