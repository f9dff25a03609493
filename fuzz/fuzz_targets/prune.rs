//! Pruning against the whole function: a random function
//! (`ir::random::random_function`, seed and depth from the fuzz bytes,
//! sometimes simplified first as the renderer prunes simplified
//! functions), a box from the bytes, and `ir::prune::prune` over it.
//!
//! Checked, per the contract in `src/ir/prune.rs` and as
//! `tests/prune.rs` checks it: where a pruned function comes back, it is
//! valid IR, has no more live ops than the whole one, and the interpreter
//! gives the same bits on it as on the whole function (NaN equal to NaN)
//! at points of the box: its corners, its centre and points sampled
//! inside, with the box's faces hit often, where rounding decides.

#![no_main]

use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::interval::Interval;
use ibeam::ir::passes;
use ibeam::ir::prune::prune;
use ibeam::ir::random::{Rng, random_function};
use ibeam::ir::validate::validate;
use libfuzzer_sys::fuzz_target;

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// A side of the box from two bytes: its low end in [-3, 3] and a width
/// from tiny (one ulp-ish) to wide, or a single point.
fn side(lo: u8, w: u8) -> Interval {
    let lo = f64::from(lo) / 255.0 * 6.0 - 3.0;
    let width = match w % 8 {
        0 => 0.0,
        1 => 1e-12,
        2 => 0.01,
        3 => 0.05,
        4 => 0.5,
        5 => 3.0,
        _ => f64::from(w) / 255.0 * 2.0,
    };
    Interval::new(lo, lo + width)
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 16 {
        return;
    }
    let seed = u64::from_le_bytes(data[..8].try_into().unwrap());
    let depth = u32::from(data[8]) % 12 + 1;
    let simplify = data[9] & 1 == 1;
    let b = [0, 1, 2].map(|i| side(data[10 + 2 * i], data[11 + 2 * i]));
    let mut f = random_function(seed, depth);
    if simplify {
        f = passes::simplify(&f);
    }
    let Some(p) = prune(&f, b) else {
        return;
    };
    if let Err(e) = validate(&p.function) {
        panic!("invalid pruned function over {b:?}: {e}");
    }
    assert!(
        p.function.live_count() <= f.live_count(),
        "pruning grew the function: {} > {} live ops",
        p.function.live_count(),
        f.live_count()
    );
    let whole = Interpreter::new(f.clone());
    let pruned = Interpreter::new(p.function.clone());
    let mut r = Rng::new(seed ^ u64::from_le_bytes([data[8], data[9], 0, 0, 0, 0, 0, 1]));
    let corners =
        (0..8).map(|k| std::array::from_fn(|i| if k >> i & 1 == 0 { b[i].lo } else { b[i].hi }));
    let centre = std::iter::once(b.map(|c| c.mid()));
    let sampled = (0..32).map(|_| {
        b.map(|c| match r.below(8) {
            0 => c.lo,
            1 => c.hi,
            // Clamped: rounding in `range` may step an ulp past `hi`,
            // and the contract covers the box only.
            _ => r.range(c.lo, c.hi).clamp(c.lo, c.hi),
        })
    });
    for pt in corners.chain(centre).chain(sampled) {
        let (a, c) = (whole.point(pt), pruned.point(pt));
        assert!(
            same(a, c),
            "at {pt:?} in {b:?}: whole {a:e}, pruned {c:e} (seed {seed}, depth {depth}, simplified {simplify})"
        );
    }
});
