//! Tapes against the reference interpreter: a random function
//! (`ir::random::random_function`, seed and depth from the fuzz bytes,
//! sometimes simplified first as the renderer tapes simplified functions)
//! turned into an `eval::tape::Tape`.
//!
//! Checked, per the contract in `src/eval/tape/mod.rs`:
//! - batched and single points and boxes, batched point gradients,
//!   interval gradients and derivatives along a box of directions give
//!   the same bits as the interpreter's `point`, `interval`, `point_grad`,
//!   `interval_grad` and `interval_dir`
//!   (NaN equal to NaN, empty equal to empty), at points and boxes from
//!   the bytes, edge values (signed zeros, infinities, NaN, huge) included;
//! - pruning to all the boxes in one pass (`Tape::prune_batch`) writes
//!   the tape that pruning to each box alone writes;
//! - a tape pruned to a box from the bytes, and that pruned tape pruned
//!   again to a sub-box (pruning nests), is valid IR and gives the same
//!   point bits as the whole function at the corners, the centre and
//!   points sampled in its box (faces hit often, where rounding decides);
//! - the same with a tape that keeps signs only (`Tape::keeping_signs`):
//!   the pruned and nested tapes give the whole function's sign (negative,
//!   zero, positive or NaN) at those points, and batched pruning writes
//!   each box's own tape.
//!
//! Bytes: 0..8 seed, 8 depth, 9 flags (bit 0: simplify), 10..16 the outer
//! box (two bytes a side), 16..22 the sub-box (fractions of the outer
//! box), the rest points (three bytes each) and boxes (six bytes each).

#![no_main]

use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::eval::tape::{Keep, Tape, Workspace};
use ibeam::interval::Interval;
use ibeam::ir::passes;
use ibeam::ir::random::{Rng, random_function};
use ibeam::ir::validate::validate;
use libfuzzer_sys::fuzz_target;

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same_iv(a: Interval, b: Interval) -> bool {
    (a.is_empty() && b.is_empty()) || (same(a.lo, b.lo) && same(a.hi, b.hi))
}

/// Values where the ops' rules have their special cases.
const EDGES: [f64; 6] = [0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 1e300];

/// A coordinate from one byte: mostly in [-4, 4], the top few bytes are
/// edge values.
fn coord(b: u8) -> f64 {
    if b >= 250 {
        EDGES[usize::from(b - 250)]
    } else {
        f64::from(b) / 249.0 * 8.0 - 4.0
    }
}

/// A side of a box from two bytes: its low end in [-3, 3] and a width
/// from a single point through tiny to wide.
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

/// The part of `outer` between the fractions `a` and `b` (bytes), always
/// inside `outer` whatever the rounding.
fn sub_side(outer: Interval, a: u8, b: u8) -> Interval {
    let (s, t) = (f64::from(a.min(b)) / 255.0, f64::from(a.max(b)) / 255.0);
    let at = |t: f64| (outer.lo + (outer.hi - outer.lo) * t).clamp(outer.lo, outer.hi);
    Interval::new(at(s), at(t).max(at(s)))
}

/// The sign class of a point value: NaN, negative, zero (either sign) or
/// positive.
fn sign(v: f64) -> i8 {
    if v.is_nan() {
        2
    } else if v < 0.0 {
        -1
    } else if v > 0.0 {
        1
    } else {
        0
    }
}

/// Checks a pruned tape against the whole function at points of `b`: the
/// same bits, or the same sign where the tape keeps signs only.
fn check_points(whole: &Interpreter, tape: &Tape, b: [Interval; 3], rng: &mut Rng, what: &str) {
    let corners =
        (0..8).map(|k| std::array::from_fn(|i| if k >> i & 1 == 0 { b[i].lo } else { b[i].hi }));
    let centre = std::iter::once(b.map(|c| c.mid().clamp(c.lo, c.hi)));
    let sampled: Vec<[f64; 3]> = (0..24)
        .map(|_| {
            b.map(|c| match rng.below(8) {
                0 => c.lo,
                1 => c.hi,
                // Clamped: rounding in `range` may step an ulp past `hi`,
                // and the contract covers the box only.
                _ => rng.range(c.lo, c.hi).clamp(c.lo, c.hi),
            })
        })
        .collect();
    let pts: Vec<[f64; 3]> = corners.chain(centre).chain(sampled).collect();
    let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
    let mut out = vec![0.0; pts.len()];
    let mut ws = Workspace::default();
    tape.point_batch([&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
    for (p, v) in pts.iter().zip(&out) {
        let w = whole.point(*p);
        let agree = match tape.keeps() {
            Keep::Bits => same(w, *v),
            Keep::Signs => sign(w) == sign(*v),
        };
        assert!(
            agree,
            "{what} at {p:?} in {b:?}: whole {w:e}, pruned {v:e}"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 22 {
        return;
    }
    let seed = u64::from_le_bytes(data[..8].try_into().unwrap());
    let depth = u32::from(data[8]) % 12 + 1;
    let simplify = data[9] & 1 == 1;
    let outer = [0, 1, 2].map(|i| side(data[10 + 2 * i], data[11 + 2 * i]));
    let inner = [0, 1, 2].map(|i| sub_side(outer[i], data[16 + 2 * i], data[17 + 2 * i]));
    let rest = &data[22..];
    let mut f = random_function(seed, depth);
    if simplify {
        f = passes::simplify(&f);
    }
    let ctx = format!("seed {seed}, depth {depth}, simplified {simplify}");
    let tape = Tape::new(&f);
    if let Err(e) = validate(tape.function()) {
        panic!("invalid tape ({ctx}): {e}");
    }
    let whole = Interpreter::new(f.clone());
    let mut ws = Workspace::default();

    // (a) batches against the interpreter.
    let mut pts: Vec<[f64; 3]> = rest
        .chunks_exact(3)
        .take(16)
        .map(|c| [coord(c[0]), coord(c[1]), coord(c[2])])
        .collect();
    pts.push(outer.map(|c| c.lo));
    let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
    let mut out = vec![0.0; pts.len()];
    tape.point_batch([&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
    for (p, v) in pts.iter().zip(&out) {
        let w = whole.point(*p);
        assert!(
            same(w, *v),
            "point batch at {p:?}: interpreter {w:e}, tape {v:e} ({ctx})"
        );
        let s = tape.point(*p, &mut ws);
        assert!(
            same(w, s),
            "point at {p:?}: interpreter {w:e}, tape {s:e} ({ctx})"
        );
    }
    // Gradients of the whole batch in one pass: each point's own bits.
    let mut grads = vec![
        ibeam::eval::Grad {
            v: 0.0,
            d: [0.0; 3]
        };
        pts.len()
    ];
    tape.point_grad_batch([&cols[0], &cols[1], &cols[2]], &mut grads, &mut ws);
    for (p, g) in pts.iter().zip(&grads) {
        let w = whole.point_grad(*p);
        assert!(
            same(w.v, g.v) && (0..3).all(|k| same(w.d[k], g.d[k])),
            "gradient batch at {p:?}: interpreter {w:?}, tape {g:?} ({ctx})"
        );
    }
    let mut boxes: Vec<[Interval; 3]> = rest
        .chunks_exact(6)
        .take(8)
        .map(|c| [0, 1, 2].map(|i| side(c[2 * i], c[2 * i + 1])))
        .collect();
    boxes.extend([outer, inner, [Interval::ENTIRE; 3]]);
    // Boxes whose sides are points at edge values (NaN makes them empty).
    boxes.extend(
        rest.chunks_exact(3)
            .take(4)
            .map(|c| [0, 1, 2].map(|i| Interval::point(coord(c[i])))),
    );
    let mut iv = vec![Interval::point(0.0); boxes.len()];
    tape.interval_batch(&boxes, &mut iv, &mut ws);
    for (b, v) in boxes.iter().zip(&iv) {
        let w = whole.interval(*b);
        assert!(
            same_iv(w, *v),
            "interval batch over {b:?}: interpreter {w:?}, tape {v:?} ({ctx})"
        );
        let s = tape.interval(*b, &mut ws);
        assert!(
            same_iv(w, s),
            "interval over {b:?}: interpreter {w:?}, tape {s:?} ({ctx})"
        );
        // The derivative kinds by the same rules over the registers.
        let (tg, ig) = (tape.interval_grad(*b, &mut ws), whole.interval_grad(*b));
        assert!(
            same_iv(tg.v, ig.v) && (0..3).all(|k| same_iv(tg.d[k], ig.d[k])),
            "interval gradient over {b:?}: interpreter {ig:?}, tape {tg:?} ({ctx})"
        );
        let v = inner;
        let (td, id) = (tape.interval_dir(*b, v, &mut ws), whole.interval_dir(*b, v));
        assert!(
            same_iv(td[0], id[0]) && same_iv(td[1], id[1]),
            "derivative along {v:?} over {b:?}: interpreter {id:?}, tape {td:?} ({ctx})"
        );
    }

    // Pruning to all the boxes in one pass writes each box's own tape.
    check_batch(&tape, &boxes, &ctx);

    // (b) pruning, and pruning the pruned tape again, keeping bits, then
    // (c) keeping signs.
    let mut rng = Rng::new(seed ^ u64::from_le_bytes([data[8], data[9], 0, 0, 0, 0, 0, 1]));
    check_nested(&whole, &tape, (outer, inner), &mut rng, &ctx);
    let signs = tape.clone().keeping_signs();
    check_batch(&signs, &boxes, &ctx);
    check_nested(&whole, &signs, (outer, inner), &mut rng, &ctx);
});

/// Pruning `tape` to all of `boxes` in one pass writes the tape pruning to
/// each box alone writes.
fn check_batch(tape: &Tape, boxes: &[[Interval; 3]], ctx: &str) {
    let mut ws = Workspace::default();
    let batch = tape.prune_batch(boxes, usize::MAX, &mut ws);
    for (b, got) in boxes.iter().zip(&batch) {
        let alone = tape.prune(*b, &mut ws);
        let same_tape = match (got, &alone) {
            (Some(g), Some(a)) => g.tape == a.tape && g.decided == a.decided,
            (None, None) => true,
            _ => false,
        };
        let keeps = tape.keeps();
        assert!(same_tape, "batched pruning ({keeps:?}) over {b:?} differs ({ctx})");
    }
}

/// `tape` pruned to `outer`, and that pruned to `inner`: valid, never
/// longer, and agreeing with `whole` (see `check_points`) on each box.
fn check_nested(
    whole: &Interpreter,
    tape: &Tape,
    (outer, inner): ([Interval; 3], [Interval; 3]),
    rng: &mut Rng,
    ctx: &str,
) {
    let mut ws = Workspace::default();
    let Some(p1) = tape.prune(outer, &mut ws) else {
        return;
    };
    if let Err(e) = validate(p1.tape.function()) {
        panic!("invalid pruned tape over {outer:?} ({ctx}): {e}");
    }
    assert!(
        p1.tape.len() <= tape.len(),
        "pruning grew the tape: {} > {} ops ({ctx})",
        p1.tape.len(),
        tape.len()
    );
    check_points(whole, &p1.tape, outer, rng, &format!("pruned ({ctx})"));
    let Some(p2) = p1.tape.prune(inner, &mut ws) else {
        // Nothing more decided: the outer tape must still be exact there.
        check_points(whole, &p1.tape, inner, rng, &format!("outer in inner ({ctx})"));
        return;
    };
    if let Err(e) = validate(p2.tape.function()) {
        panic!("invalid nested pruned tape over {inner:?} in {outer:?} ({ctx}): {e}");
    }
    assert!(
        p2.tape.len() <= p1.tape.len(),
        "nested pruning grew the tape: {} > {} ops ({ctx})",
        p2.tape.len(),
        p1.tape.len()
    );
    check_points(
        whole,
        &p2.tape,
        inner,
        rng,
        &format!("nested in {outer:?} ({ctx})"),
    );
}
