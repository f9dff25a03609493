//! Which evaluators a shadow segment's pieces run in a scene large enough
//! to prune.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;

use super::*;
use crate::eval::build::{EvalKind, build_evaluators};
use crate::eval::{Bulk, Evaluator, Grad, IntervalGrad, Single, Specialise};
use crate::ir::random::Rng;
use crate::ir::{BinaryOp, Builder, Function, UnaryOp, Var};
use crate::render::view::camera::RayCamera;
use crate::scene::{Bounds, Camera, Light, Object, RenderSettings, Scene};

// The whole function's evaluator, counting its interval evaluations (the
// cells' pruned tapes answer the others).
struct Counting {
    inner: Arc<dyn Evaluator>,
    intervals: AtomicUsize,
}

impl Single for Counting {
    fn point(&self, p: [f64; 3]) -> f64 {
        self.inner.point(p)
    }
    fn point_grad(&self, p: [f64; 3]) -> Grad {
        self.inner.point_grad(p)
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        self.intervals.fetch_add(1, Ordering::Relaxed);
        self.inner.interval(b)
    }
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        self.intervals.fetch_add(1, Ordering::Relaxed);
        self.inner.interval_grad(b)
    }
    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        self.intervals.fetch_add(1, Ordering::Relaxed);
        self.inner.interval_dir(b, v)
    }
}

impl Bulk for Counting {}

impl Specialise for Counting {
    fn function(&self) -> Option<&Function> {
        self.inner.function()
    }
}

// A union of `n` balls of radius `r`, centres in [lo, hi]³.
fn balls(n: usize, lo: f64, hi: f64, r: f64) -> Function {
    let mut rng = Rng::new(11);
    let mut b = Builder::new();
    let (x, y, z) = (b.var(Var::X), b.var(Var::Y), b.var(Var::Z));
    let mut all = None;
    for _ in 0..n {
        let mut sq = Vec::new();
        for v in [x, y, z] {
            let c = b.constant(rng.range(lo, hi));
            let d = b.binary(BinaryOp::Sub, v, c);
            sq.push(b.powi(d, 2));
        }
        let s = b.binary(BinaryOp::Add, sq[0], sq[1]);
        let s = b.binary(BinaryOp::Add, s, sq[2]);
        let (d, r) = (b.unary(UnaryOp::Sqrt, s), b.constant(r));
        let ball = b.binary(BinaryOp::Sub, d, r);
        all = Some(all.map_or(ball, |u| b.binary(BinaryOp::Min, u, ball)));
    }
    let root = all.expect("at least one ball");
    b.finish(root)
}

// One object, the default light, bounds [-2, 2]³.
fn balls_scene(function: Function) -> Scene {
    Scene {
        objects: vec![Object {
            name: "balls".into(),
            function,
            color: [0.8; 3],
        }],
        camera: Camera::default(),
        lights: vec![Light::default_light()],
        bounds: Bounds {
            min: [-2.0; 3],
            max: [2.0; 3],
        },
        render: RenderSettings::default(),
    }
}

// A cell is built the same whichever scope asks for it first: the whole
// functions' (a top-level sweep's) or a cell's own (a nested sweep's, the
// next piece leaving that cell). Asked from a cell's scope first, cells
// were measured against that cell's few hundred ops, found no smaller,
// and left to the whole functions for the rest of the tile.
#[test]
fn cells_do_not_depend_on_the_scope_asking_first() {
    let scene = balls_scene(balls(400, -0.9, 0.9, 0.04));
    let evals = build_evaluators(&scene, EvalKind::Interp).expect("evaluators");
    let cam = RayCamera::new(&scene.camera, 16, 16).expect("camera");
    let tr = Scope::new(&scene, &evals, cam, true);
    let cell_box =
        |c: [f64; 3]| -> IBox { std::array::from_fn(|i| Interval::new(c[i], c[i] + 0.05)) };
    let (near, far) = (cell_box([-0.6, -0.6, -0.6]), cell_box([0.6, 0.5, 0.6]));
    let ops = |set: &Option<crate::render::context::EvalSet>| {
        set.as_ref().map(|s| s.live_ops.iter().sum::<usize>())
    };
    // Asked from the top: the far box's cell prunes.
    let mut fresh = TileState::default();
    let from_top = CellTapes::holding(&tr, &far, &mut fresh);
    assert!(ops(&from_top).is_some_and(|n| 2 * n <= tr.ctx.live_ops[0]));
    // Asked first from the near box's cell.
    let mut st = TileState::default();
    let near_set = CellTapes::holding(&tr, &near, &mut st).expect("the near box's cell prunes");
    let nested = tr.with_evals(&near_set);
    let from_cell = CellTapes::holding(&nested, &far, &mut st);
    assert_eq!(ops(&from_cell), ops(&from_top));
}

// Pieces that no cell's evaluators hold (a cell keeps no tapes where the
// balls do not prune) run the whole function, but the pieces after them
// still look for a cell: one piece without a cell once sent every later
// piece of its segment at that width to the whole function, most of a
// 3000-ball union's shadow time.
#[test]
fn pieces_after_one_without_a_cell_still_run_cells() {
    // A cluster in one corner of the bounds, far from which no cell prunes.
    let scene = balls_scene(balls(300, 0.5, 0.9, 0.02));
    let whole = build_evaluators(&scene, EvalKind::Interp).expect("evaluators");
    let counting = Arc::new(Counting {
        inner: whole[0].clone(),
        intervals: AtomicUsize::new(0),
    });
    let evals: Vec<Arc<dyn Evaluator>> = vec![counting.clone()];
    let cam = RayCamera::new(&scene.camera, 16, 16).expect("camera");
    let tr = Scope::new(&scene, &evals, cam, true);
    assert!(tr.ctx.large && tr.pruner.enabled);
    let mut st = TileState::default();
    // Segments from the far corner to a light beyond the cluster: their
    // first pieces have no cell, those through the cluster have.
    let end = SegEnd::Point(DVec3::splat(1.9));
    let mut rng = Rng::new(5);
    let mut pieces = 0;
    for _ in 0..40 {
        let p = DVec3::new(
            rng.range(-1.6, -1.4),
            rng.range(-1.6, -1.4),
            rng.range(-1.6, -1.4),
        );
        let before = st.stats.interval_evals;
        segment_free(&tr, point_box(p.to_array()), &[p], end, 1e-3, &mut st);
        pieces += st.stats.interval_evals - before;
    }
    let on_whole = counting.intervals.load(Ordering::Relaxed);
    // The far pieces run the whole function: 180 of 3115 evaluations here,
    // and 382 when one piece without a cell sent its later siblings there.
    assert!(
        on_whole * 12 < pieces as usize,
        "{on_whole} of {pieces} interval evaluations on the whole function"
    );
}
