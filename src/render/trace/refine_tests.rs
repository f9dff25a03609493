//! Tests of `render::refine`.

use std::sync::Arc;

use super::*;
use crate::eval::Evaluator;
use crate::eval::interp::Interpreter;
use crate::interval::boxes::point_box;
use crate::ir::random::{Rng, random_function};

#[test]
fn illinois_converges_within_tolerance() {
    let t = illinois(|t| 2.0 - t * t, 0.0, 2.0, 2.0, -2.0, 1e-10);
    assert!((t - 2f64.sqrt()).abs() <= 1e-10);
}

// On a linear function the first secant step lands on the root and
// the next evaluation, a 64th of the tolerance past it, closes the
// bracket; curved ones still end within half the tolerance of their
// root.
#[test]
fn a_secant_step_next_to_the_root_closes_the_bracket() {
    let mut n = 0;
    let t = illinois(
        |t| {
            n += 1;
            1.0 - t
        },
        0.0,
        8.0,
        1.0,
        -7.0,
        1e-3,
    );
    assert!((t - 1.0).abs() <= 0.5e-3, "{t}");
    assert!(n <= 2, "{n} evaluations");
    let mut rng = Rng::new(3);
    for _ in 0..1000 {
        let r = rng.range(0.1, 2.9);
        let tol = 10f64.powf(rng.range(-9.0, -1.0));
        let f = |t: f64| r * r * r - t * t * t + 0.3 * (r - t).sin();
        let t = illinois(f, 0.0, 3.0, f(0.0), f(3.0), tol);
        assert!((t - r).abs() <= 0.5 * tol, "root {r}, tol {tol}: {t}");
    }
}

// A bracketed root comes back within the root tolerance (a sixteenth
// of the depth tolerance) of the true one, alone and batched. The
// function is flat at its root, (z − c)³ + 10⁻⁶ (z − c), so the false
// position crawls there and stops close to its tolerance rather than
// far inside it (on a sphere a secant step lands within 10⁻¹⁰); the
// root along a ray is where z = c.
#[test]
fn roots_are_refined_to_the_root_tolerance() {
    use crate::ir::{BinaryOp, Builder, Var};
    const C: f64 = 0.3;
    let mut b = Builder::new();
    let z = b.var(Var::Z);
    let c = b.constant(C);
    let u = b.binary(BinaryOp::Sub, z, c);
    let u2 = b.binary(BinaryOp::Mul, u, u);
    let u3 = b.binary(BinaryOp::Mul, u2, u);
    let k = b.constant(1e-6);
    let ku = b.binary(BinaryOp::Mul, k, u);
    let f = b.binary(BinaryOp::Add, u3, ku);
    // Negative towards −z: the rays below start outside.
    let minus = b.constant(-1.0);
    let f = b.binary(BinaryOp::Mul, minus, f);
    let evals: Vec<Arc<dyn Evaluator>> = vec![Arc::new(Interpreter::new(b.finish(f)))];
    let tr = Scope::of_objects_for_tests(&evals, &[], 64);
    let mut rng = Rng::new(29);
    let mut scratch = RefineScratch::default();
    let mut worst: f64 = 0.0;
    for _ in 0..300 {
        let o = [rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), -4.0];
        let d = [rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), 1.0];
        let root = (C - o[2]) / d[2];
        let ray = PixelRay {
            o: point_box(o),
            d: point_box(d),
            om: o,
            dm: d,
        };
        let (a, b) = (root - rng.range(0.01, 0.5), root + rng.range(0.01, 0.5));
        let tol = tr.ctx.cam.root_tolerance(a);
        let mut st = RenderStats::default();
        let alone = refine(&tr, &ray, &[0], a, b, &mut st).expect("a sign change");
        scratch.brackets = vec![Bracket { ray, a, b }];
        let batched = refine_batch(&tr, &mut scratch, &[0], &mut st)[0].expect("a sign change");
        for t in [alone.t, batched.t] {
            assert!(
                (t - root).abs() <= tol,
                "{t} against {root}, tolerance {tol}"
            );
            worst = worst.max((t - root).abs() / tol);
        }
    }
    // The test can tell: some roots end within a factor 16 of the
    // root tolerance, where a coarser one would have stopped.
    assert!(worst > 1.0 / 16.0, "every root within {worst} tolerances");
}

// Batched refinement gives each bracket what refining it alone gives,
// bit for bit, with the same evaluation count: random functions of two
// objects, random rays, brackets with and without a sign change.
#[test]
fn batched_refinement_gives_single_refinements_bits() {
    let mut rng = Rng::new(17);
    let mut refined = 0;
    let mut scratch = RefineScratch::default();
    for seed in 0..80 {
        let evals: Vec<Arc<dyn Evaluator>> = (0..2)
            .map(|k| {
                Arc::new(Interpreter::new(random_function(2 * seed + k, 6))) as Arc<dyn Evaluator>
            })
            .collect();
        let tr = Scope::of_objects_for_tests(&evals, &[], 64);
        let brackets: Vec<Bracket> = (0..24)
            .map(|_| {
                let o = [
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                ];
                let d = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 1.0];
                let a = rng.range(0.0, 1.0);
                let ray = PixelRay {
                    o: point_box(o),
                    d: point_box(d),
                    om: o,
                    dm: d,
                };
                Bracket {
                    ray,
                    a,
                    b: a + rng.range(0.01, 3.0),
                }
            })
            .collect();
        // Both objects, and one alone (whose roots are on it without
        // a look); the scratch carries over from block to block.
        for live in [&[0, 1][..], &[1][..]] {
            scratch.brackets.clone_from(&brackets);
            let mut batch_st = RenderStats::default();
            let batch = refine_batch(&tr, &mut scratch, live, &mut batch_st);
            let mut single_st = RenderStats::default();
            for (k, got) in brackets.iter().zip(batch) {
                let want = refine(&tr, &k.ray, live, k.a, k.b, &mut single_st);
                refined += usize::from(want.is_some());
                match (got, want) {
                    (Some(g), Some(w)) => {
                        let bits = |h: &Hit| h.grad.map(|d| d.map(f64::to_bits));
                        assert!(
                            g.t.to_bits() == w.t.to_bits()
                                && g.obj == w.obj
                                && bits(&g) == bits(&w),
                            "seed {seed}"
                        );
                    }
                    (g, w) => assert_eq!(g, w, "seed {seed}"),
                }
            }
            assert_eq!(batch_st.point_evals, single_st.point_evals, "seed {seed}");
        }
    }
    assert!(refined > 50, "only {refined} brackets had a sign change");
}
