//! Pruning a function to a box (`ir::prune`): the pruned function gives
//! the same bits as the original at every point of the box, and it is
//! much shorter where a CSG tree has been decided.

use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::interval::Interval;
use ibeam::ir::Function;
use ibeam::ir::prune::prune;
use ibeam::ir::random::{Rng, random_function};
use ibeam::ir::validate::validate;

mod common;

use common::same;

/// A point of `b`, its corners' coordinates often.
fn sample(r: &mut Rng, b: [Interval; 3]) -> [f64; 3] {
    b.map(|c| match r.below(8) {
        0 => c.lo,
        1 => c.hi,
        _ => r.range(c.lo, c.hi),
    })
}

/// Checks the pruned function against the original at `n` points of `b`.
fn check_exact(f: &Function, g: &Function, b: [Interval; 3], r: &mut Rng, n: usize, what: &str) {
    validate(g).unwrap_or_else(|e| panic!("{what}: invalid pruned function: {e}"));
    let (fi, gi) = (Interpreter::new(f.clone()), Interpreter::new(g.clone()));
    for _ in 0..n {
        let p = sample(r, b);
        let (a, c) = (fi.point(p), gi.point(p));
        assert!(same(a, c), "{what} at {p:?}: original {a:e}, pruned {c:e}");
    }
}

#[test]
fn random_functions_pruned_to_boxes_keep_every_bit() {
    let mut r = Rng::new(2024);
    let mut decided = 0;
    for seed in 0..400 {
        let f = random_function(seed, 10);
        for _ in 0..6 {
            let side = [0.05, 0.5, 3.0][r.below(3)];
            let b = [0, 1, 2].map(|_| {
                let lo = r.range(-3.0, 3.0);
                Interval::new(lo, lo + side)
            });
            if let Some(p) = prune(&f, b) {
                assert!(p.function.live_count() <= f.live_count());
                check_exact(&f, &p.function, b, &mut r, 30, &format!("seed {seed}"));
                decided += p.decided;
            }
        }
    }
    // Not vacuous: random trees hold enough min/max to decide many.
    assert!(decided >= 200, "only {decided} min/max nodes decided");
}

/// The prospero model through the crate's own `.vm` importer, simplified
/// as the CLI does (see `common::models` for when it is `None`).
fn prospero() -> Option<(Function, [Interval; 3])> {
    let path = common::models::shared_model("prospero.vm")?;
    let scene = ibeam::lang::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let f = ibeam::ir::passes::simplify(&scene.objects[0].function);
    let b = scene.bounds;
    Some((f, [0, 1, 2].map(|i| Interval::new(b.min[i], b.max[i]))))
}

#[test]
fn prospero_tiles_shrink_and_stay_exact() {
    let Some((f, bounds)) = prospero() else {
        return;
    };
    let mut r = Rng::new(7);
    let n = 16;
    let (mut before, mut after) = (0, 0);
    for j in 0..n {
        for i in 0..n {
            let cell = |c: Interval, k: usize| {
                let w = c.width() / n as f64;
                Interval::new(c.lo + w * k as f64, c.lo + w * (k + 1) as f64)
            };
            let b = [cell(bounds[0], i), cell(bounds[1], j), bounds[2]];
            let g = prune(&f, b).map_or_else(|| f.clone(), |p| p.function);
            before += f.live_count();
            after += g.live_count();
            if (i + j) % 5 == 0 {
                check_exact(&f, &g, b, &mut r, 40, &format!("tile ({i}, {j})"));
            }
        }
    }
    // Over a 1/16 × 1/16 tile the 7576-op model needs a small fraction of
    // its ops (the renderer needs at least 8x to switch evaluators).
    assert!(after * 10 < before, "pruned {after} of {before} ops");
}
