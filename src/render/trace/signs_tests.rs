//! What holds between a sign-pruned region (`eval::tape::Keep::Signs`)
//! and the whole function, now that their values differ off the surface:
//! batched refinement on the region finds the roots single refinement
//! finds on the whole function, within the root tolerance, with the same
//! normals; and the sign bounds of the beam sweep (`probe::scene_signs`,
//! natural and mean-value forms met across tapes) never contradict the
//! whole function's point values.

use std::sync::Arc;

use super::probe::{SignForm, scene_signs};
use super::refine::{Bracket, RefineScratch, refine, refine_batch};
use crate::eval::Evaluator;
use crate::eval::interp::Interpreter;
use crate::eval::regional::{Parent, Regional};
use crate::eval::tape::{Tape, Workspace};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, point_box};
use crate::ir::random::Rng;
use crate::ir::{BinaryOp, Builder, Function, UnaryOp, Var};
use crate::render::context::stats::RenderStats;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::view::camera::PixelRay;

/// A union (one `min`) of `n` balls of radius 0.3 along the x axis, one
/// unit apart, wobbling in y and z.
fn balls(n: usize) -> Function {
    let mut b = Builder::new();
    let vars = [b.var(Var::X), b.var(Var::Y), b.var(Var::Z)];
    let mut acc = None;
    for i in 0..n {
        let c = [i as f64, 0.1 * (i as f64).sin(), 0.1 * (i as f64).cos()];
        let mut s = b.constant(0.0);
        for (v, ci) in vars.into_iter().zip(c) {
            let k = b.constant(ci);
            let d = b.binary(BinaryOp::Sub, v, k);
            let d2 = b.powi(d, 2);
            s = b.binary(BinaryOp::Add, s, d2);
        }
        let r = b.unary(UnaryOp::Sqrt, s);
        let k = b.constant(0.3);
        let ball = b.binary(BinaryOp::Sub, r, k);
        acc = Some(match acc {
            None => ball,
            Some(a) => b.binary(BinaryOp::Min, a, ball),
        });
    }
    b.finish(acc.expect("at least one ball"))
}

/// The region around ball 3 and up to ball 4, which is proven positive
/// there (and dropped) but smaller than ball 3 near it, the whole
/// function, and the region's evaluator: its tape pruned keeping signs,
/// the whole one outside it.
fn region_and_whole() -> (IBox, Arc<dyn Evaluator>, Arc<dyn Evaluator>) {
    let f = balls(12);
    let region = [
        Interval::new(2.5, 3.65),
        Interval::new(-0.6, 0.6),
        Interval::new(-0.6, 0.6),
    ];
    let whole: Arc<dyn Evaluator> = Arc::new(Interpreter::new(f.clone()));
    let pruned = Tape::new(&f)
        .keeping_signs()
        .prune(region, &mut Workspace::default())
        .expect("prunes");
    assert!(
        pruned.tape.len() < f.len() / 3,
        "pruned to {}",
        pruned.tape.len()
    );
    let regional: Arc<dyn Evaluator> = Arc::new(Regional::new(
        region,
        pruned.tape,
        Parent::Whole(Arc::clone(&whole)),
    ));
    (region, whole, regional)
}

/// A ray from `o` along `d`.
fn ray(o: [f64; 3], d: [f64; 3]) -> PixelRay {
    PixelRay {
        o: point_box(o),
        d: point_box(d),
        om: o,
        dm: d,
    }
}

#[test]
fn batched_refinement_on_a_sign_pruned_region_finds_the_whole_functions_roots() {
    let (_, whole, regional) = region_and_whole();
    let (on_whole, on_region) = ([whole], [regional]);
    let (tw, tr) = (
        Scope::of_objects_for_tests(&on_whole, &[], 64),
        Scope::of_objects_for_tests(&on_region, &[], 64),
    );
    let mut rng = Rng::new(5);
    // Rays down through ball 3, inside the region, their brackets from
    // above the ball to its centre plane.
    let brackets: Vec<Bracket> = (0..40)
        .map(|_| {
            let o = [3.0 + rng.range(-0.2, 0.2), 0.55, rng.range(-0.2, 0.2)];
            Bracket {
                ray: ray(o, [rng.range(-0.05, 0.05), -1.0, 0.0]),
                a: 0.0,
                b: 0.55,
            }
        })
        .collect();
    let mut scratch = RefineScratch::default();
    scratch.brackets.clone_from(&brackets);
    let batch = refine_batch(&tr, &mut scratch, &[0], &mut RenderStats::default());
    let mut st = RenderStats::default();
    let mut values_differ = false;
    for (k, got) in brackets.iter().zip(batch) {
        let got = got.expect("a sign change on the region's tape");
        let want = refine(&tw, &k.ray, &[0], k.a, k.b, &mut st).expect("and on the whole");
        let tol = tw.ctx.cam.root_tolerance(k.a);
        assert!(
            (got.t - want.t).abs() <= tol,
            "{} vs {} (tol {tol})",
            got.t,
            want.t
        );
        // The normals agree to rounding: the pruned tape keeps the ball the
        // root is on, whose gradient the whole function's `min` picks.
        let (g, w) = (got.grad.expect("grad"), want.grad.expect("grad"));
        let cos = (0..3).map(|i| g[i] * w[i]).sum::<f64>()
            / ((0..3).map(|i| g[i] * g[i]).sum::<f64>() * (0..3).map(|i| w[i] * w[i]).sum::<f64>())
                .sqrt();
        assert!(cos > 1.0 - 1e-9, "normals {g:?} and {w:?}");
        // Off the surface the region's values are not the whole one's.
        let p = k.ray.at(k.a);
        values_differ |= tr.ctx.evals[0].point(p) != tw.ctx.evals[0].point(p);
    }
    // The test means something only if the values differ somewhere.
    let between = [3.6, 0.0, 0.0];
    values_differ |= tr.ctx.evals[0].point(between) != tw.ctx.evals[0].point(between);
    assert!(values_differ, "pruning kept every value");
}

#[test]
fn sign_bounds_across_tapes_never_contradict_the_whole_function() {
    let (region, whole, regional) = region_and_whole();
    let on_region = [regional];
    let tr = Scope::of_objects_for_tests(&on_region, &[], 64);
    let mut st = TileState::default();
    let mut rng = Rng::new(9);
    let (mut proven, mut boxes) = (0, 0);
    while boxes < 3000 {
        let c: [f64; 3] = std::array::from_fn(|i| rng.range(region[i].lo, region[i].hi));
        let w = rng.range(0.001, 0.3);
        let b: IBox = std::array::from_fn(|i| Interval::new(c[i] - w, c[i] + w));
        if !(0..3).all(|i| b[i].lo >= region[i].lo && b[i].hi <= region[i].hi) {
            continue;
        }
        boxes += 1;
        for form in [SignForm::Natural, SignForm::Tight(0)] {
            let s = scene_signs(&tr, &[0], b, form, &mut st);
            if !(s.positive() || s.negative()) {
                continue;
            }
            proven += 1;
            for _ in 0..16 {
                let p: [f64; 3] = std::array::from_fn(|i| rng.range(b[i].lo, b[i].hi));
                let v = whole.point(p);
                assert!(
                    (s.positive() && v > 0.0) || (s.negative() && v < 0.0),
                    "{b:?}: {s:?} but f({p:?}) = {v}"
                );
            }
        }
    }
    assert!(proven > 1000, "only {proven} signs proven");
    // The mean-value form ran, its gradients from the region's tape.
    assert!(st.stats.mean_value_tries > 0, "the form never ran");
}

/// A torus about the z axis, radii 0.6 and 0.2, as the quartic
/// `(x² + y² + z² + R² − r²)² − 4R²(x² + y²)`: x and y appear twice, so
/// the mean-value form tightens its natural intervals.
fn torus() -> Function {
    let mut b = Builder::new();
    let [x, y, z] = [b.var(Var::X), b.var(Var::Y), b.var(Var::Z)];
    let (x2, y2, z2) = (b.powi(x, 2), b.powi(y, 2), b.powi(z, 2));
    let xy = b.binary(BinaryOp::Add, x2, y2);
    let s = b.binary(BinaryOp::Add, xy, z2);
    let k = b.constant(0.36 - 0.04);
    let s = b.binary(BinaryOp::Add, s, k);
    let s2 = b.powi(s, 2);
    let four_r2 = b.constant(4.0 * 0.36);
    let t = b.binary(BinaryOp::Mul, four_r2, xy);
    let f = b.binary(BinaryOp::Sub, s2, t);
    b.finish(f)
}

/// A point on ball `i` of [`balls`] or on [`torus`], from two angles.
fn on_surface(torus: bool, i: usize, (u, v): (f64, f64)) -> [f64; 3] {
    if torus {
        let r = 0.6 + 0.2 * v.cos();
        [r * u.cos(), r * u.sin(), 0.2 * v.sin()]
    } else {
        let c = [i as f64, 0.1 * (i as f64).sin(), 0.1 * (i as f64).cos()];
        let d = [u.cos() * v.cos(), u.sin() * v.cos(), v.sin()];
        std::array::from_fn(|k| c[k] + 0.3 * d[k])
    }
}

/// The mean-value form asks the native interval gradient only once it has
/// won on the tile, the interpreter's before: on a union of balls, where
/// the natural intervals are already tight and it never wins, the native
/// kind is never compiled (so never waited for); on a torus it wins, and
/// the native kind then compiles.
#[test]
fn mean_value_gradients_go_native_only_after_a_win_on_the_tile() {
    use crate::eval::jit::JitEvaluator;
    for (f, is_torus) in [(balls(3), false), (torus(), true)] {
        let jit = Arc::new(JitEvaluator::new(&f).unwrap().in_background());
        let evals: [Arc<dyn Evaluator>; 1] = [jit.clone()];
        let tr = Scope::of_objects_for_tests(&evals, &[], 64);
        let compiled = || {
            jit.compile_times()
                .iter()
                .any(|(kind, _)| *kind == "interval_grad")
        };
        let mut st = TileState::default();
        let mut rng = Rng::new(21);
        for _ in 0..2000 {
            let angles = (rng.range(0.0, 6.3), rng.range(-1.5, 1.5));
            let c = on_surface(is_torus, rng.range(0.0, 2.99) as usize, angles);
            let level = rng.range(0.0, 7.99) as usize;
            let w = 0.002 * f64::from(1 << level);
            // Off the surface by about a box width: boxes whose natural
            // interval straddles 0 while f does not.
            let c: [f64; 3] = std::array::from_fn(|i| c[i] + rng.range(-2.0, 2.0) * w);
            let b: IBox = std::array::from_fn(|i| Interval::new(c[i] - w, c[i] + w));
            let won_before = st.mean_value.has_won();
            scene_signs(&tr, &[0], b, SignForm::Tight(level), &mut st);
            if !won_before {
                assert!(!compiled(), "native gradient before a win");
            }
        }
        assert!(st.stats.mean_value_tries >= 16, "{:?}", st.stats);
        assert_eq!(st.stats.mean_value_wins > 0, is_torus, "{:?}", st.stats);
        assert_eq!(compiled(), is_torus);
    }
}
