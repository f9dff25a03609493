//! Affine enclosures (`eval::affine`) against point values: a random
//! function (`ir::random::random_function`, seed and depth from the fuzz
//! bytes, sometimes simplified first as renders simplify), boxes from the
//! bytes.
//!
//! Checked, per the contract in `src/eval/affine.rs`:
//! - the interpreter, a tape and a tape's batch give the same bits;
//! - the affine enclosure lies inside the interval rules' enclosure
//!   wherever that is not EMPTY;
//! - it contains f at the box's corners, centre and sampled points (faces
//!   hit often) wherever every op's point value is finite (the point rules
//!   of `ir::semantics`, not the code under test);
//! - along the ray through the box's diagonal (one noise symbol for the
//!   ray parameter, `eval::affine::affine_along`), the form contains f at
//!   sampled points of the ray, and f is positive wherever the form's
//!   clip (`may_reach_zero`) leaves a point out;
//! - the same for the second-order form along that ray
//!   (`eval::affine::quadratic_along`), whose quadratic at each sampled
//!   parameter's noise value (plus or minus its error) contains f there
//!   too.
//!
//! Bytes: 0..8 seed, 8 depth, 9 flags (bit 0: simplify), then boxes (six
//! bytes each, two a side), at most 8.

#![no_main]

use ibeam::eval::Single;
use ibeam::eval::affine::{AffineEvaluator, affine_along, quadratic_along};
use ibeam::eval::interp::Interpreter;
use ibeam::eval::tape::Tape;
use ibeam::interval::Interval;
use ibeam::interval::affine::{along_parameter, centre_radius};
use ibeam::interval::boxes::ray_box;
use ibeam::ir::passes;
use ibeam::ir::random::{Rng, random_function};
use ibeam::ir::semantics::run_point;
use libfuzzer_sys::fuzz_target;

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same_iv(a: Interval, b: Interval) -> bool {
    (a.is_empty() && b.is_empty()) || (same(a.lo, b.lo) && same(a.hi, b.hi))
}

/// A side of a box from two bytes: its low end in [-3, 3] and a width
/// from a single point through tiny to wide; the top byte values are
/// unbounded or huge sides.
fn side(lo: u8, w: u8) -> Interval {
    match lo {
        253 => return Interval::ENTIRE,
        254 => return Interval::new(1e300, 1e300 + 1e299),
        255 => return Interval::new(-0.0, 0.0),
        _ => {}
    }
    let lo = f64::from(lo) / 252.0 * 6.0 - 3.0;
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

/// Points of `b`: corners, centre, and sampled ones, ends often.
fn points(b: [Interval; 3], rng: &mut Rng) -> Vec<[f64; 3]> {
    let b = b.map(|s| Interval::new(s.lo.max(-f64::MAX), s.hi.min(f64::MAX)));
    let corners =
        (0..8).map(|k| std::array::from_fn(|i| if k >> i & 1 == 0 { b[i].lo } else { b[i].hi }));
    let centre = std::iter::once(b.map(|c| c.mid().clamp(c.lo, c.hi)));
    let sampled: Vec<[f64; 3]> = (0..24)
        .map(|_| {
            b.map(|c| match rng.below(6) {
                0 => c.lo,
                1 => c.hi,
                _ => rng.range(c.lo, c.hi).clamp(c.lo, c.hi),
            })
        })
        .collect();
    corners.chain(centre).chain(sampled).collect()
}

/// The ray from `b`'s low corner to its high one, its origin a box a
/// little wider than rounding (so that points computed on the ray lie on
/// rays from it), checked as the module doc says; boxes not finite or
/// not small enough for that margin are skipped.
fn check_along(f: &ibeam::ir::Function, tape: &Tape, b: [Interval; 3], rng: &mut Rng, ctx: &str) {
    if !b.iter().all(|s| s.lo.abs() < 1e3 && s.hi.abs() < 1e3) {
        return;
    }
    let om = b.map(|s| s.lo);
    let dm: [f64; 3] = std::array::from_fn(|i| b[i].hi - b[i].lo);
    let o = om.map(|c| Interval::new(c - 1e-9, c + 1e-9));
    let d = dm.map(Interval::point);
    let t = Interval::new(0.0, 1.0);
    let v = affine_along(tape, o, d, t, ray_box(o, d, t));
    let part = v.form.may_reach_zero().and_then(|e| along_parameter(t, e));
    let q = quadratic_along(tape, o, d, t, ray_box(o, d, t));
    let q_part = q.form.may_reach_zero().and_then(|e| along_parameter(t, e));
    let (m, r) = centre_radius(t);
    // The quadratic's values at the noise value of tk, by outward intervals.
    let q_at = |tk: f64| {
        let eps = Interval::point(tk).sub(Interval::point(m)).div(Interval::point(r));
        let [c0, c1, c2] = q.form.c.map(Interval::point);
        let e = q.form.e;
        c2.mul(eps).add(c1).mul(eps).add(c0).add(Interval::new(-e, e))
    };
    let mut vals = Vec::new();
    for k in 0..24 {
        let tk = if k < 2 { f64::from(k) } else { rng.range(0.0, 1.0) };
        let shift = rng.pick(&[-0.9e-9, 0.0, 0.9e-9]);
        let p: [f64; 3] = std::array::from_fn(|i| (om[i] + shift) + dm[i] * tk);
        run_point(&f.ops, p, &mut vals);
        if !vals.iter().all(|v| v.is_finite()) {
            continue;
        }
        let fp = vals[f.root.index()];
        assert!(v.range.contains(fp), "along {b:?} at t = {tk}: {:?} lacks {fp:e} ({ctx})", v.range);
        assert!(
            part.is_some_and(|p| p.contains(tk)) || fp > 0.0,
            "along {b:?}: t = {tk} clipped out by {part:?} where f = {fp:e} ({ctx})"
        );
        assert!(q.range.contains(fp), "quadratic along {b:?} at t = {tk}: {:?} lacks {fp:e} ({ctx})", q.range);
        assert!(
            !q.form.e.is_finite() || q_at(tk).contains(fp),
            "quadratic along {b:?} at t = {tk}: {:?} lacks {fp:e} ({ctx})",
            q.form
        );
        assert!(
            q_part.is_some_and(|p| p.contains(tk)) || fp > 0.0,
            "quadratic along {b:?}: t = {tk} clipped out by {q_part:?} where f = {fp:e} ({ctx})"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 16 {
        return;
    }
    let seed = u64::from_le_bytes(data[..8].try_into().unwrap());
    let depth = u32::from(data[8]) % 12 + 1;
    let simplify = data[9] & 1 == 1;
    let mut f = random_function(seed, depth);
    if simplify {
        f = passes::simplify(&f);
    }
    let ctx = format!("seed {seed}, depth {depth}, simplified {simplify}");
    let boxes: Vec<[Interval; 3]> = data[10..]
        .chunks_exact(6)
        .take(8)
        .map(|c| [0, 1, 2].map(|i| side(c[2 * i], c[2 * i + 1])))
        .collect();
    let interp = Interpreter::new(f.clone());
    let tape = Tape::new(&f);
    let mut batch = vec![Interval::EMPTY; boxes.len()];
    tape.affine_batch(&boxes, &mut batch);
    let mut rng = Rng::new(seed ^ 0x0a44_1e);
    let mut vals = Vec::new();
    for (b, from_batch) in boxes.iter().zip(batch) {
        let a = interp.affine(*b);
        let t = tape.affine(*b);
        assert!(
            same_iv(a, t) && same_iv(a, from_batch),
            "over {b:?}: interpreter {a:?}, tape {t:?}, batch {from_batch:?} ({ctx})"
        );
        let iv = interp.interval(*b);
        assert!(
            iv.is_empty() || a.is_empty() || (iv.lo <= a.lo && a.hi <= iv.hi),
            "over {b:?}: affine {a:?} wider than interval {iv:?} ({ctx})"
        );
        for p in points(*b, &mut rng) {
            run_point(&f.ops, p, &mut vals);
            if !vals.iter().all(|v| v.is_finite()) {
                continue;
            }
            let v = vals[f.root.index()];
            assert!(
                a.contains(v),
                "at {p:?} in {b:?}: affine {a:?} lacks f = {v:e} ({ctx})"
            );
        }
        check_along(&f, &tape, *b, &mut rng, &ctx);
    }
});
