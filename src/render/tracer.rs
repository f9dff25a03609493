//! The tracer's state: what every tile of a render reads ([`Tracer`]: the
//! camera, the evaluators, the lights), the per-tile state it carries
//! from one evaluation to the next ([`TileState`]: counters and the
//! mean-value policy's record), and evaluators pruned to a region of space.

use std::sync::Arc;

use glam::DVec3;

use super::camera::RayCamera;
use super::stats::RenderStats;
use crate::eval::{Evaluator, Grad, IntervalGrad};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_within, point_box};
use crate::scene::{Bounds, Light, Scene};

/// Block-size classes (log2 of the side) the mean-value policy tells apart.
pub(crate) const MV_LEVELS: usize = 8;
/// Tries at one block size before the mean-value policy judges the form.
const MV_MIN_TRIES: u64 = 64;
/// The form stays in use at a block size while at least one try in this
/// many wins.
const MV_WIN_RATIO: u64 = 32;

/// Functions with fewer live ops than this are not pruned.
const PRUNE_MIN_OPS: usize = 64;
/// A pruned function replaces a native one only if it is at least this
/// many times shorter: it runs in the interpreter, which costs about 3-7x
/// the JIT per op (`ibeam bench eval`).
const PRUNE_GAIN_NATIVE: usize = 8;
/// ... and an interpreted one if it is at least this many times shorter.
const PRUNE_GAIN_INTERPRETED: usize = 2;
/// Relative padding of a pruning region, so that boxes the tracer rounds
/// outward stay inside it.
const REGION_PAD: f64 = 1e-9;

/// Evaluators (some pruned) and the live op count of each one's function.
pub(crate) type PrunedEvals = (Vec<Arc<dyn Evaluator>>, Vec<usize>);

/// Shared read-only state of one render.
pub(crate) struct Tracer<'a> {
    /// The camera at the traced resolution.
    pub cam: RayCamera,
    /// One evaluator per object.
    pub evals: &'a [Arc<dyn Evaluator>],
    /// Each object's linear colour.
    pub colors: Vec<[f64; 3]>,
    /// The scene's lights.
    pub lights: &'a [Light],
    /// The scene's bounds, outside which there is no surface.
    pub bounds: Bounds,
    /// Length of the bounds' diagonal.
    pub diag: f64,
    /// Live ops of each evaluator's function (0 when it has none).
    pub live_ops: Vec<usize>,
    /// Prune large functions to tiles and blocks.
    pub prune: bool,
    /// Every object is proven constant along every ray inside the bounds
    /// (2D models viewed along the missing axis): a block's T range then
    /// needs no bisection.
    pub flat: bool,
}

/// Whether the mean-value form still pays in one tile, per block size.
///
/// Where the form seldom decides anything (min/max-heavy functions, whose
/// gradients are discontinuous), it only costs gradient evaluations:
/// after [`MV_MIN_TRIES`] tries at one block size (it pays off on small
/// blocks first) with under 1 in [`MV_WIN_RATIO`] winning, the tile stops
/// using it at that size. The record is per tile, so the choice does not
/// depend on the thread count.
#[derive(Clone, Debug, Default)]
pub(crate) struct MeanValuePolicy {
    /// (tries, wins) per block-size class.
    levels: [(u64, u64); MV_LEVELS],
}

impl MeanValuePolicy {
    /// Whether the form is still worth trying on blocks of class `level`.
    fn pays(&self, level: usize) -> bool {
        let (tries, wins) = self.levels[level.min(MV_LEVELS - 1)];
        !(tries >= MV_MIN_TRIES && wins * MV_WIN_RATIO < tries)
    }

    /// Records one try at class `level`.
    fn record(&mut self, level: usize, win: bool) {
        let lv = &mut self.levels[level.min(MV_LEVELS - 1)];
        lv.0 += 1;
        lv.1 += u64::from(win);
    }
}

/// What tracing one tile carries from one evaluation to the next.
#[derive(Clone, Debug, Default)]
pub(crate) struct TileState {
    /// The tile's counters, merged into the render's at the end.
    pub stats: RenderStats,
    /// The tile's record of the mean-value form (policy, not a counter).
    pub mean_value: MeanValuePolicy,
}

impl<'a> Tracer<'a> {
    /// The tracer of `scene` seen through `cam`, with one evaluator per
    /// object.
    pub(crate) fn new(
        scene: &'a Scene,
        evals: &'a [Arc<dyn Evaluator>],
        cam: RayCamera,
        prune: bool,
    ) -> Tracer<'a> {
        let b = scene.bounds;
        Tracer {
            cam,
            evals,
            colors: scene.objects.iter().map(|o| o.color).collect(),
            lights: &scene.lights,
            bounds: b,
            diag: (DVec3::from_array(b.max) - DVec3::from_array(b.min)).length(),
            live_ops: evals
                .iter()
                .map(|e| e.function().map_or(0, |f| f.live_count()))
                .collect(),
            prune,
            flat: constant_along_rays(&cam, scene),
        }
    }

    /// The same tracer through another camera (the same scene at another
    /// resolution): everything else, flatness included, is kept.
    pub(crate) fn with_camera(&self, cam: RayCamera) -> Tracer<'a> {
        Tracer {
            cam,
            colors: self.colors.clone(),
            live_ops: self.live_ops.clone(),
            ..*self
        }
    }

    /// The same tracer with other evaluators (pruned ones) and their live
    /// op counts.
    pub(crate) fn with_evals<'b>(
        &self,
        evals: &'b [Arc<dyn Evaluator>],
        live_ops: Vec<usize>,
    ) -> Tracer<'b>
    where
        'a: 'b,
    {
        Tracer {
            evals,
            colors: self.colors.clone(),
            live_ops,
            ..*self
        }
    }

    /// Object `k` over `b`.
    pub(crate) fn interval(&self, k: usize, b: IBox, st: &mut RenderStats) -> Interval {
        st.interval_evals += 1;
        self.evals[k].interval(b)
    }

    /// F over `b`, tightened where it straddles 0 by the mean-value form
    /// `f(c) + ∇F(b)·(b − c)` (c the box centre), intersected with the
    /// natural enclosure. Sound wherever the evaluator's gradient
    /// enclosure covers the (generalised) gradient of f over the box; it is
    /// used only when every gradient bound is finite, which rules out the
    /// poles and domain edges where it would not. `level` is the block's
    /// size class for the [`MeanValuePolicy`].
    pub(crate) fn interval_tight(
        &self,
        k: usize,
        b: IBox,
        level: usize,
        st: &mut TileState,
    ) -> Interval {
        let f = self.interval(k, b, &mut st.stats);
        if f.is_empty() || f.lo > 0.0 || f.hi < 0.0 {
            return f;
        }
        // Flat scenes (2D models seen along their missing axis) skip the
        // form outright: their functions are min/max trees of thousands of
        // ops, where it measured 7 wins in 13,833 tries on prospero at 512²
        // while compiling and running the interval-gradient evaluator
        // doubled the render time.
        if self.flat || !st.mean_value.pays(level) {
            return f;
        }
        if !b.iter().all(|c| c.lo.is_finite() && c.hi.is_finite()) {
            return f;
        }
        let c: [f64; 3] = b.map(|i| i.mid());
        let g = self.interval_grad(k, b, &mut st.stats);
        if !g.d.iter().all(|d| d.lo.is_finite() && d.hi.is_finite()) {
            return f;
        }
        let fc = self.interval(k, point_box(c), &mut st.stats);
        if fc.is_empty() || !fc.lo.is_finite() || !fc.hi.is_finite() {
            return f;
        }
        let mut mv = fc;
        for i in 0..3 {
            mv = mv.add(g.d[i].mul(b[i].sub(Interval::point(c[i]))));
        }
        let (lo, hi) = (f.lo.max(mv.lo), f.hi.min(mv.hi));
        let win = lo > 0.0 || hi < 0.0;
        st.stats.mean_value_tries += 1;
        st.stats.mean_value_wins += u64::from(win);
        st.mean_value.record(level, win);
        if lo <= hi { Interval::new(lo, hi) } else { f }
    }

    /// Object `k` and its gradient over `b`.
    pub(crate) fn interval_grad(&self, k: usize, b: IBox, st: &mut RenderStats) -> IntervalGrad {
        st.interval_evals += 1;
        self.evals[k].interval_grad(b)
    }

    /// F and its derivative along `v` over `b` (see
    /// [`Evaluator::interval_dir`]).
    pub(crate) fn interval_dir(
        &self,
        k: usize,
        b: IBox,
        v: IBox,
        st: &mut RenderStats,
    ) -> [Interval; 2] {
        st.interval_evals += 1;
        self.evals[k].interval_dir(b, v)
    }

    /// Object `k` at `p`.
    pub(crate) fn point(&self, k: usize, p: [f64; 3], st: &mut RenderStats) -> f64 {
        st.point_evals += 1;
        self.evals[k].point(p)
    }

    /// Object `k` and its gradient at `p`.
    pub(crate) fn point_grad(&self, k: usize, p: [f64; 3], st: &mut RenderStats) -> Grad {
        st.point_evals += 1;
        self.evals[k].point_grad(p)
    }

    /// The region the evaluations for the rays through the pixel centres
    /// `xs × ys` over `t` happen in: their beam's hull (not clipped to the
    /// bounds, which the tracer's own boxes overhang by rounding), widened
    /// by a relative [`REGION_PAD`]. An evaluation that still falls outside
    /// uses the whole function (see `crate::eval::regional`).
    pub(crate) fn beam_region(&self, xs: (f64, f64), ys: (f64, f64), t: Interval) -> Option<IBox> {
        let region = self.cam.corners(xs, ys).hull(t);
        if region
            .iter()
            .any(|c| c.is_empty() || !c.lo.is_finite() || !c.hi.is_finite())
        {
            return None;
        }
        Some(region.map(|c| {
            let pad = REGION_PAD * (c.width() + c.lo.abs().max(c.hi.abs())) + f64::MIN_POSITIVE;
            Interval::new(c.lo - pad, c.hi + pad)
        }))
    }

    /// The scene's evaluators with every function that shrinks enough
    /// pruned to `region` (see [`crate::ir::prune`]) and run by the
    /// interpreter, and their live op counts; `None` when none does. Exact
    /// on the region: use them only for evaluations inside it.
    pub(crate) fn pruned_to(&self, region: IBox, st: &mut RenderStats) -> Option<PrunedEvals> {
        if !self.prune || !self.live_ops.iter().any(|&n| n >= PRUNE_MIN_OPS) {
            return None;
        }
        let mut any = false;
        let mut live = self.live_ops.clone();
        let evals = self
            .evals
            .iter()
            .zip(live.iter_mut())
            .map(|(e, n)| {
                let before = *n;
                if before < PRUNE_MIN_OPS {
                    return None;
                }
                // Prune what `e` already pruned when the new region lies in
                // the old one; else start again from the whole function.
                let whole = e.whole().cloned().unwrap_or_else(|| Arc::clone(e));
                let (source, before) = match e.valid_region() {
                    Some(r) if !box_within(&region, &r) => {
                        let f = whole.function()?;
                        (f, f.live_count())
                    }
                    _ => (e.function()?, before),
                };
                let gain = if whole.is_native() {
                    PRUNE_GAIN_NATIVE
                } else {
                    PRUNE_GAIN_INTERPRETED
                };
                let p = crate::ir::prune::prune_to_at_most(source, region, before / gain)?;
                let after = p.function.live_count();
                any = true;
                *n = after;
                st.pruned_ops_before += before as u64;
                st.pruned_ops_after += after as u64;
                Some(Arc::new(crate::eval::regional::Regional {
                    region,
                    pruned: crate::eval::interp::Interpreter::new(p.function),
                    whole,
                }) as Arc<dyn Evaluator>)
            })
            .collect::<Vec<Option<Arc<dyn Evaluator>>>>()
            .into_iter()
            .zip(self.evals)
            .map(|(p, e)| p.unwrap_or_else(|| Arc::clone(e)))
            .collect();
        any.then_some((evals, live))
    }
}

/// Whether `scene` is a 2D model seen along its missing axis (every
/// object constant along every ray of its camera).
pub fn is_flat(scene: &Scene) -> bool {
    RayCamera::new(&scene.camera, 1, 1).is_ok_and(|cam| constant_along_rays(&cam, scene))
}

// Whether every object is constant along every ray: the camera is
// orthographic (one direction d for all rays) and d has an exact zero
// component on every coordinate an object's function reads (2D models seen
// along the missing axis). Reads the scene functions' variable use, which
// simplification can only shrink, so it holds for the evaluators too.
fn constant_along_rays(cam: &RayCamera, scene: &Scene) -> bool {
    let one_direction = cam.dx == DVec3::ZERO && cam.dy == DVec3::ZERO;
    one_direction
        && scene.objects.iter().all(|o| {
            let uses = o.function.uses_vars();
            (0..3).all(|i| !uses[i] || cam.d0[i] == 0.0)
        })
}
