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
    let ops = |set: &Option<cells::Cell>| set.as_ref().map(|s| s.live_ops.iter().sum::<usize>());
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

// The render's cells are the same whichever tile asks first, in whatever
// order and from whatever scope (a tile's, or a cell's own in a nested
// sweep): a cell is pruned from its parent cell or the whole functions,
// never from the asker's, so images do not depend on thread order. Each
// is built once: a second tile asking gets the first one's and prunes
// nothing.
#[test]
fn shared_cells_do_not_depend_on_who_asks_first() {
    let scene = balls_scene(balls(400, -0.9, 0.9, 0.04));
    let evals = build_evaluators(&scene, EvalKind::Interp).expect("evaluators");
    let cam = RayCamera::new(&scene.camera, 16, 16).expect("camera");
    let mut rng = Rng::new(17);
    // Boxes of the levels 2 to 5 (cells 1, 0.5, 0.25, 0.125 wide).
    let boxes: Vec<IBox> = (0..40)
        .map(|i| {
            let w = [0.9, 0.45, 0.2, 0.1][i % 4];
            std::array::from_fn(|_| {
                let lo = rng.range(-1.0, 1.0 - w);
                Interval::new(lo, lo + w)
            })
        })
        .collect();
    let ask = |order: &mut dyn Iterator<Item = usize>, nested: bool| {
        let tr = Scope::new(&scene, &evals, cam, true);
        let mut st = TileState::default();
        let inner = CellTapes::holding(&tr, &boxes[1], &mut st).expect("a cell prunes");
        let cell_scope = tr.with_evals(&inner);
        let asker = if nested { &cell_scope } else { &tr };
        let mut got = vec![None; boxes.len()];
        for i in order {
            got[i] = CellTapes::holding(asker, &boxes[i], &mut st);
        }
        got
    };
    let forward = ask(&mut (0..boxes.len()), false);
    let backward = ask(&mut (0..boxes.len()).rev(), true);
    let mut pruned = 0;
    for (i, (f, b)) in forward.iter().zip(&backward).enumerate() {
        let (Some(f), Some(b)) = (f, b) else {
            assert!(f.is_none() && b.is_none(), "box {i}");
            continue;
        };
        pruned += 1;
        assert_eq!(f.live_ops, b.live_ops, "box {i}");
        for _ in 0..20 {
            let sub: IBox = std::array::from_fn(|k| {
                let (lo, w) = (boxes[i][k].lo, boxes[i][k].width());
                let a = lo + w * rng.range(0.0, 0.9);
                Interval::new(a, a + 0.1 * w)
            });
            let (x, y) = (f.evals[0].interval(sub), b.evals[0].interval(sub));
            assert_eq!(
                (x.lo.to_bits(), x.hi.to_bits()),
                (y.lo.to_bits(), y.hi.to_bits())
            );
        }
    }
    assert!(
        pruned >= 30,
        "{pruned} of {} boxes in pruned cells",
        boxes.len()
    );
    // A second tile of one render gets the first tile's shared cells.
    let tr = Scope::new(&scene, &evals, cam, true);
    let (mut one, mut two) = (TileState::default(), TileState::default());
    let first = CellTapes::holding(&tr, &boxes[2], &mut one).expect("a level-4 cell prunes");
    let again = CellTapes::holding(&tr, &boxes[2], &mut two).expect("the same cell");
    assert!(Arc::ptr_eq(&first, &again));
    assert!(one.stats.pruned_ops_before > 0);
    assert_eq!(two.stats.pruned_ops_before, 0);
}
