//! Tapes against the reference interpreter: every run and batch gives its
//! bits, and pruned tapes keep them on their boxes.

use super::*;
use crate::eval::Single;
use crate::eval::interp::Interpreter;
use crate::ir::passes::simplify;
use crate::ir::random::{Rng, random_function};

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same_iv(a: Interval, b: Interval) -> bool {
    (a.is_empty() && b.is_empty()) || (same(a.lo, b.lo) && same(a.hi, b.hi))
}

fn random_box(rng: &mut Rng, s: f64) -> [Interval; 3] {
    std::array::from_fn(|_| {
        let (a, b) = (rng.range(-s, s), rng.range(-s, s));
        Interval::new(a.min(b), a.max(b))
    })
}

#[test]
fn batches_give_the_interpreters_bits() {
    let mut rng = Rng::new(7);
    let mut ws = Workspace::default();
    for seed in 0..300 {
        let f = random_function(seed, 8);
        let tape = Tape::new(&f);
        crate::ir::validate::validate(tape.function()).unwrap();
        let it = Interpreter::new(f);
        let pts: Vec<[f64; 3]> = (0..17)
            .map(|_| std::array::from_fn(|_| rng.range(-3.0, 3.0)))
            .collect();
        let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
        let mut out = vec![0.0; pts.len()];
        tape.point_batch([&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
        for (p, v) in pts.iter().zip(&out) {
            assert!(same(*v, it.point(*p)), "seed {seed} at {p:?}");
        }
        let boxes: Vec<_> = (0..9).map(|_| random_box(&mut rng, 3.0)).collect();
        let mut iv = vec![Interval::point(0.0); boxes.len()];
        tape.interval_batch(&boxes, &mut iv, &mut ws);
        for (b, v) in boxes.iter().zip(&iv) {
            assert!(same_iv(*v, it.interval(*b)), "seed {seed} over {b:?}");
        }
    }
}

// A gradient batch gives each point's own `point_grad`, to the bit, which
// gives the interpreter's.
#[test]
fn gradient_batches_give_each_points_bits() {
    let mut rng = Rng::new(29);
    let mut ws = Workspace::default();
    for seed in 0..300 {
        let f = random_function(seed, 9);
        let tape = Tape::new(&f);
        let it = Interpreter::new(f);
        let pts: Vec<[f64; 3]> = (0..1 + seed as usize % 23)
            .map(|_| std::array::from_fn(|_| rng.range(-3.0, 3.0)))
            .collect();
        let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
        let mut out = vec![
            crate::eval::Grad {
                v: 0.0,
                d: [0.0; 3]
            };
            pts.len()
        ];
        tape.point_grad_batch([&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
        for (p, g) in pts.iter().zip(&out) {
            let alone = tape.point_grad(*p, &mut ws);
            let reference = it.point_grad(*p);
            for (x, y) in [(g.v, alone.v), (g.v, reference.v)] {
                assert!(same(x, y), "seed {seed} at {p:?}");
            }
            for k in 0..3 {
                assert!(same(g.d[k], alone.d[k]), "seed {seed} at {p:?}");
                assert!(same(g.d[k], reference.d[k]), "seed {seed} at {p:?}");
            }
        }
    }
}

#[test]
fn scalar_runs_directions_and_gradients_give_the_interpreters_bits() {
    let mut rng = Rng::new(17);
    let mut ws = Workspace::default();
    for seed in 0..300 {
        let f = random_function(seed, 10);
        let tape = Tape::new(&f);
        let it = Interpreter::new(f);
        for _ in 0..8 {
            let p: [f64; 3] = std::array::from_fn(|_| rng.range(-3.0, 3.0));
            assert!(
                same(tape.point(p, &mut ws), it.point(p)),
                "seed {seed} at {p:?}"
            );
            let b = random_box(&mut rng, 3.0);
            assert!(
                same_iv(tape.interval(b, &mut ws), it.interval(b)),
                "seed {seed} over {b:?}"
            );
            let v = random_box(&mut rng, 2.0);
            let [tv, td] = tape.interval_dir(b, v, &mut ws);
            let [iv, id] = it.interval_dir(b, v);
            assert!(
                same_iv(tv, iv) && same_iv(td, id),
                "seed {seed} over {b:?} along {v:?}"
            );
            let (tg, ig) = (tape.interval_grad(b, &mut ws), it.interval_grad(b));
            assert!(
                same_iv(tg.v, ig.v) && (0..3).all(|k| same_iv(tg.d[k], ig.d[k])),
                "seed {seed} over {b:?}: gradient {tg:?} vs {ig:?}"
            );
        }
    }
}

/// A union of `n` spheres along x: a min chain, balanced by simplify.
fn spheres(n: usize) -> Function {
    let mut b = crate::ir::Builder::new();
    let x = b.var(Var::X);
    let y = b.var(Var::Y);
    let z = b.var(Var::Z);
    let yz = {
        let y2 = b.unary(UnaryOp::Square, y);
        let z2 = b.unary(UnaryOp::Square, z);
        b.binary(BinaryOp::Add, y2, z2)
    };
    let mut acc = None;
    for i in 0..n {
        let c = b.constant(i as f64);
        let dx = b.binary(BinaryOp::Sub, x, c);
        let dx2 = b.unary(UnaryOp::Square, dx);
        let r2 = b.binary(BinaryOp::Add, dx2, yz);
        let r = b.unary(UnaryOp::Sqrt, r2);
        let half = b.constant(0.5);
        let s = b.binary(BinaryOp::Sub, r, half);
        acc = Some(match acc {
            None => s,
            Some(a) => b.binary(BinaryOp::Min, a, s),
        });
    }
    simplify(&b.finish(acc.unwrap()))
}

#[test]
fn pruning_keeps_the_bits_inside_and_nests() {
    let f = spheres(200);
    let whole = Tape::new(&f);
    assert!(whole.registers() < 40, "{} registers", whole.registers());
    let mut ws = Workspace::default();
    let outer = [
        Interval::new(40.2, 47.8),
        Interval::new(-1.0, 1.0),
        Interval::new(-1.0, 1.0),
    ];
    let p1 = whole
        .prune(outer, &mut ws)
        .expect("a small box decides most mins");
    assert!(
        p1.tape.len() * 5 < whole.len(),
        "{} of {}",
        p1.tape.len(),
        whole.len()
    );
    crate::ir::validate::validate(p1.tape.function()).unwrap();
    let inner = [
        Interval::new(44.6, 45.3),
        Interval::new(-0.2, 0.3),
        Interval::new(0.0, 0.1),
    ];
    let p2 = p1
        .tape
        .prune(inner, &mut ws)
        .expect("nested pruning decides more");
    assert!(p2.tape.len() < p1.tape.len());
    let direct = crate::ir::prune::prune(&f, outer).unwrap();
    assert_eq!(direct.decided, p1.decided);
    let it = Interpreter::new(f.clone());
    let mut rng = Rng::new(3);
    for (tape, bx) in [(&p1.tape, outer), (&p2.tape, inner)] {
        let pts: Vec<[f64; 3]> = (0..64)
            .map(|_| std::array::from_fn(|c| rng.range(bx[c].lo, bx[c].hi)))
            .collect();
        let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
        let mut out = vec![0.0; pts.len()];
        tape.point_batch([&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
        for (p, v) in pts.iter().zip(&out) {
            assert!(same(*v, it.point(*p)), "at {p:?}");
        }
    }
}

#[test]
fn a_size_limit_refuses_a_longer_child_and_keeps_a_shorter_one() {
    let whole = Tape::new(&spheres(50));
    let mut ws = Workspace::default();
    let b = [
        Interval::new(20.2, 22.8),
        Interval::new(-1.0, 1.0),
        Interval::new(-1.0, 1.0),
    ];
    let child = whole.prune(b, &mut ws).expect("prunes").tape;
    let n = child.len();
    assert!(whole.prune_to_at_most(b, n - 1, &mut ws).is_none());
    let same = whole.prune_to_at_most(b, n, &mut ws).expect("fits");
    assert_eq!(same.tape, child);
}

#[test]
fn pruned_random_functions_keep_their_bits_in_the_box() {
    let mut rng = Rng::new(11);
    let mut ws = Workspace::default();
    let mut pruned = 0;
    for seed in 0..400 {
        let f = random_function(seed, 9);
        let tape = Tape::new(&f);
        let bx = random_box(&mut rng, 2.0);
        let Some(p) = tape.prune(bx, &mut ws) else {
            continue;
        };
        pruned += 1;
        let it = Interpreter::new(f);
        for _ in 0..16 {
            let q: [f64; 3] = std::array::from_fn(|c| rng.range(bx[c].lo, bx[c].hi));
            let mut out = [0.0];
            p.tape
                .point_batch([&[q[0]], &[q[1]], &[q[2]]], &mut out, &mut ws);
            assert!(same(out[0], it.point(q)), "seed {seed} at {q:?}");
        }
    }
    assert!(pruned > 20, "only {pruned} random functions pruned");
}

// One pass over a batch of boxes writes the tapes that pruning to each
// box alone writes, bit for bit, whatever the batch's size, and the same
// length limit refuses the same boxes.
#[test]
fn batched_pruning_writes_each_boxs_own_tape() {
    let mut rng = Rng::new(23);
    let mut ws = Workspace::default();
    let (mut pruned, mut refused) = (0, 0);
    for seed in 0..300 {
        let tape = Tape::new(&random_function(seed, 9));
        let lanes = 1 + seed as usize % 7;
        let boxes: Vec<[Interval; 3]> = (0..lanes)
            .map(|_| random_box(&mut rng, [0.3, 1.0, 3.0][seed as usize % 3]))
            .collect();
        let max_len = if seed % 4 == 0 {
            tape.len() / 2
        } else {
            usize::MAX
        };
        let batch = tape.prune_batch(&boxes, max_len, &mut ws);
        assert_eq!(batch.len(), lanes);
        for (b, got) in boxes.iter().zip(&batch) {
            let alone = tape.prune_to_at_most(*b, max_len, &mut ws);
            match (got, &alone) {
                (Some(g), Some(a)) => {
                    assert_eq!(g.tape, a.tape, "seed {seed}");
                    assert_eq!(g.decided, a.decided, "seed {seed}");
                    pruned += 1;
                }
                (None, None) => refused += 1,
                _ => panic!(
                    "seed {seed}: batch {} alone {}",
                    got.is_some(),
                    alone.is_some()
                ),
            }
        }
    }
    assert!(
        pruned > 50 && refused > 50,
        "pruned {pruned}, refused {refused}"
    );
}

// A function whose tape keeps `n` values alive at once: each
// `x·y + c_i` joins a sum and, after all of them, a max, so every one
// waits in a register from the sum to the max.
fn wide(n: usize) -> Function {
    let mut b = crate::ir::Builder::new();
    let (x, y) = (b.var(Var::X), b.var(Var::Y));
    let xy = b.binary(BinaryOp::Mul, x, y);
    let terms: Vec<ValueId> = (0..n)
        .map(|i| {
            let c = b.constant(0.37 * i as f64 - 11.0);
            b.binary(BinaryOp::Add, xy, c)
        })
        .collect();
    let sum = terms[1..]
        .iter()
        .fold(terms[0], |s, &t| b.binary(BinaryOp::Add, s, t));
    let max = terms[1..]
        .iter()
        .rev()
        .fold(terms[0], |m, &t| b.binary(BinaryOp::Max, m, t));
    let root = b.binary(BinaryOp::Sub, max, sum);
    b.finish(root)
}

#[test]
fn tapes_past_the_fixed_register_file_give_the_interpreters_bits() {
    let mut rng = Rng::new(29);
    let mut ws = Workspace::default();
    // A short tape first, so the workspace holds stale fixed registers
    // when the long one runs, and the other way round.
    for n in [3, 400, 5, 300] {
        let f = wide(n);
        let tape = Tape::new(&f);
        let it = Interpreter::new(f);
        if n >= 300 {
            assert!(tape.registers() > 256, "{} registers", tape.registers());
        }
        for _ in 0..16 {
            let p: [f64; 3] = std::array::from_fn(|_| rng.range(-3.0, 3.0));
            assert!(same(tape.point(p, &mut ws), it.point(p)), "n {n} at {p:?}");
            let b = random_box(&mut rng, 3.0);
            assert!(
                same_iv(tape.interval(b, &mut ws), it.interval(b)),
                "n {n} over {b:?}"
            );
            let v = random_box(&mut rng, 2.0);
            let ([tv, td], [iv, id]) = (tape.interval_dir(b, v, &mut ws), it.interval_dir(b, v));
            assert!(same_iv(tv, iv) && same_iv(td, id), "n {n} over {b:?}");
            let (tg, ig) = (tape.interval_grad(b, &mut ws), it.interval_grad(b));
            assert!(
                (0..3).all(|k| same_iv(tg.d[k], ig.d[k])),
                "n {n} over {b:?}"
            );
            let small = random_box(&mut rng, 0.05);
            if let Some(pruned) = tape.prune(small, &mut ws) {
                let q: [f64; 3] = std::array::from_fn(|k| small[k].mid());
                assert!(same(pruned.tape.point(q, &mut ws), it.point(q)), "n {n}");
            }
        }
    }
}

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

// The sign class of an interval's ends (what "the interval holds 0, lies
// above or below it" reads).
fn sign_class(i: Interval) -> (i8, i8) {
    if i.is_empty() {
        (2, 2)
    } else {
        (sign(i.lo), sign(i.hi))
    }
}

// A union of spheres pruned to a box that two of them reach keeps only
// those two by sign, where pruning by value keeps nearly all: the far
// spheres' intervals overlap the near ones' over a long box.
#[test]
fn pruning_by_sign_keeps_only_the_objects_that_reach_the_box() {
    let f = spheres(200);
    let mut ws = Workspace::default();
    // Along x over spheres 40..=47, thin across: the spheres at 44 and 45
    // reach it (|y|, |z| <= 0.1 < 0.5 at x = 44, 45), the rest are proven
    // positive there only where x is far from them.
    let long = [
        Interval::new(44.2, 45.3),
        Interval::new(-0.1, 0.1),
        Interval::new(-0.1, 0.1),
    ];
    let by_value = Tape::new(&f).prune(long, &mut ws).expect("prunes");
    let by_sign = Tape::new(&f)
        .keeping_signs()
        .prune(long, &mut ws)
        .expect("prunes");
    assert_eq!(by_sign.tape.keeps(), Keep::Signs);
    let sqrts = |t: &Tape| {
        t.code()
            .iter()
            .filter(|i| matches!(i, Instr::Sqrt(..)))
            .count()
    };
    assert_eq!(sqrts(&by_sign.tape), 2, "{:?}", by_sign.tape.function());
    assert!(sqrts(&by_value.tape) >= 2);
    // Pruned again inside, the child keeps signs too.
    let inner = [
        Interval::new(44.2, 44.4),
        Interval::new(-0.1, 0.1),
        Interval::new(-0.1, 0.1),
    ];
    let nested = by_sign.tape.prune(inner, &mut ws).expect("prunes again");
    assert_eq!(sqrts(&nested.tape), 1);
    assert_eq!(nested.tape.keeps(), Keep::Signs);
}

// On random functions and boxes, a tape pruned by sign (nested twice) has
// the whole function's sign at every sampled point of its box, and its
// intervals over sub-boxes hold 0, or lie above or below it, exactly when
// the whole function's do; every value the root reads through more than
// min/max is untouched, so functions without a min/max at the top keep
// their bits.
#[test]
fn pruning_by_sign_keeps_the_sign_in_the_box() {
    let mut rng = Rng::new(31);
    let mut ws = Workspace::default();
    let (mut pruned, mut shorter) = (0, 0);
    for seed in 0..600 {
        let f = random_function(seed, 9);
        let whole = Tape::new(&f).keeping_signs();
        let bx = random_box(&mut rng, 2.0);
        let Some(p) = whole.prune(bx, &mut ws) else {
            continue;
        };
        crate::ir::validate::validate(p.tape.function()).unwrap();
        pruned += 1;
        let by_value = Tape::new(&f).prune(bx, &mut ws);
        if by_value.is_none_or(|v| v.tape.len() > p.tape.len()) {
            shorter += 1;
        }
        // A sub-box, pruned again from the child.
        let sub: [Interval; 3] = std::array::from_fn(|c| {
            let (a, b) = (rng.range(bx[c].lo, bx[c].hi), rng.range(bx[c].lo, bx[c].hi));
            Interval::new(a.min(b), a.max(b))
        });
        let nested = p.tape.prune(sub, &mut ws).map(|q| q.tape);
        let it = Interpreter::new(f);
        for (tape, region) in [(Some(&p.tape), bx), (nested.as_ref(), sub)] {
            let Some(tape) = tape else { continue };
            for _ in 0..16 {
                let q: [f64; 3] = std::array::from_fn(|c| rng.range(region[c].lo, region[c].hi));
                let v = tape.point(q, &mut ws);
                assert_eq!(sign(v), sign(it.point(q)), "seed {seed} at {q:?}");
                let small: [Interval; 3] = std::array::from_fn(|c| {
                    let w = 0.1 * region[c].width();
                    let lo = (q[c] - w).max(region[c].lo);
                    Interval::new(lo, (q[c] + w).min(region[c].hi).max(lo))
                });
                assert_eq!(
                    sign_class(tape.interval(small, &mut ws)),
                    sign_class(it.interval(small)),
                    "seed {seed} over {small:?}"
                );
            }
        }
    }
    assert!(pruned > 40, "only {pruned} random functions pruned");
    assert!(
        shorter > 5,
        "sign pruning shorter than value pruning {shorter} times"
    );
}

// Both compiled paths (`crate::eval::cpu`) give the interpreter's bits, on
// fixed register files and on register slices, one at a time and in
// batches. The AVX2 and FMA clones run only where the CPU has both; the
// test says on stderr when they could not run here.
#[test]
fn both_cpu_paths_give_the_interpreters_bits() {
    use crate::eval::cpu::{self, CpuPath};
    if !cpu::wide_clones_run() {
        eprintln!("this CPU lacks AVX2 or FMA: both paths run the baseline code");
    }
    let mut rng = Rng::new(41);
    let mut ws = Workspace::default();
    let mut slices = 0;
    let mut pruned_any = false;
    // Random functions, and two past the fixed register file.
    for seed in 0..162 {
        let f = match seed {
            160 => wide(300),
            161 => wide(400),
            _ => random_function(seed, 9),
        };
        let tape = Tape::new(&f);
        slices += usize::from(tape.registers() > super::run::FIXED_REGISTERS);
        let it = Interpreter::new(f);
        let pts: Vec<[f64; 3]> = (0..9)
            .map(|_| std::array::from_fn(|_| rng.range(-3.0, 3.0)))
            .collect();
        let cols: [Vec<f64>; 3] = std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
        let boxes: Vec<_> = (0..9).map(|_| random_box(&mut rng, 3.0)).collect();
        for path in [CpuPath::Baseline, CpuPath::Wide] {
            let mut out = vec![0.0; pts.len()];
            tape.point_batch_on(path, [&cols[0], &cols[1], &cols[2]], &mut out, &mut ws);
            for (p, v) in pts.iter().zip(&out) {
                let want = it.point(*p);
                assert!(same(*v, want), "{path:?} batch, seed {seed} at {p:?}");
                let one = tape.point_on(path, *p, &mut ws);
                assert!(same(one, want), "{path:?}, seed {seed} at {p:?}");
            }
            let mut iv = vec![Interval::point(0.0); boxes.len()];
            tape.interval_batch_on(path, &boxes, &mut iv, &mut ws);
            for (b, v) in boxes.iter().zip(&iv) {
                let want = it.interval(*b);
                assert!(same_iv(*v, want), "{path:?} batch, seed {seed} over {b:?}");
                let one = tape.interval_on(path, *b, &mut ws);
                assert!(same_iv(one, want), "{path:?}, seed {seed} over {b:?}");
            }
            // Pruned to a small box, each path writes the same tape.
            let small = random_box(&mut rng, 0.3);
            let pruned = |p, ws: &mut Workspace| {
                let t = tape.prune_to_at_most_on(p, small, usize::MAX, ws);
                t.map(|t| (t.decided, t.tape.code().to_vec()))
            };
            let here = pruned(path, &mut ws);
            pruned_any |= here.is_some();
            assert_eq!(here, pruned(CpuPath::Baseline, &mut ws), "seed {seed}");
        }
    }
    assert!(slices > 0, "no tape was long enough for a register slice");
    assert!(pruned_any, "no tape was pruned");
}
