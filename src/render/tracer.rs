//! The tracer's state: what every tile of a render reads ([`Tracer`]: the
//! camera, the evaluators, the lights), the per-tile state it carries
//! from one evaluation to the next ([`TileState`]: counters and the
//! mean-value policy's record), and evaluators pruned to a region of space.

use std::sync::Arc;

use glam::DVec3;

use super::camera::{CornerRays, RayCamera};
use super::cells::CellTapes;
use super::groups::TileGroups;
use super::proof::SignBound;
use super::stats::RenderStats;
use crate::eval::regional::Regional;
use crate::eval::tape::{Tape, Workspace};
use crate::eval::{Evaluator, Grad, IntervalGrad};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_within, point_box};
use crate::scene::{Bounds, Light, Scene};

/// Block-size classes (log2 of the side) the mean-value policy tells apart.
pub(crate) const MV_LEVELS: usize = 8;
/// Tries at one block size before the mean-value policy judges the form.
const MV_MIN_TRIES: u64 = 16;
/// The form stays in use at a block size while at least one try in this
/// many wins.
const MV_WIN_RATIO: u64 = 32;

/// Functions with fewer live ops than this are not pruned.
pub(crate) const PRUNE_MIN_OPS: usize = 64;
/// ... and native ones below this many: their pruned tapes must be
/// [`PRUNE_GAIN_NATIVE`] times shorter to be used, which a short function
/// seldom is, while every tile, slice and block pays its pruning pass
/// (unions of 10 and 20 spheres, 143 and 283 ops, rendered 1.8x and 1.5x
/// faster unpruned; 50 spheres, 703 ops, 1.2x slower).
const NATIVE_PRUNE_MIN_OPS: usize = 512;
/// ... and not along single rays below this many: a ray prunes at every
/// fourfold narrowing of its pieces, and a short tape does not repay
/// that.
const RAY_PRUNE_MIN_OPS: usize = 256;
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

/// One object's pruned evaluator and its op count.
type PrunedEval = (Arc<dyn Evaluator>, usize);

/// Where one pruning starts (see `Tracer::prune_plan`).
struct PrunePlan<'p> {
    // The evaluator the pruned one falls back on outside its region.
    source: &'p Arc<dyn Evaluator>,
    // The tape pruned.
    tape: &'p Tape,
    // What answers for the region now, and its length.
    answer: &'p Arc<dyn Evaluator>,
    before: usize,
    // `gain` of the answer, and the longest child that pays.
    gain: usize,
    most: usize,
}

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
    /// The tape of each whole function that is large enough to prune.
    pub tapes: Vec<Option<Arc<Tape>>>,
    /// Prune large functions to tiles and blocks.
    pub prune: bool,
    /// Every object is proven constant along every ray inside the bounds
    /// (2D models viewed along the missing axis): a block's T range then
    /// needs no bisection.
    pub flat: bool,
    /// Evaluators pruned to groups of tiles, which tiles prune theirs
    /// from (shared by the tracers of one camera).
    pub groups: Arc<TileGroups>,
    /// The interior ends, in increasing order, of the slices of the tile
    /// these evaluators are pruned to (empty outside such a tile).
    pub slice_ends: Arc<[f64]>,
    /// Some object's whole function has [`PRUNE_MIN_OPS`] live ops or
    /// more (whatever the evaluators and the pruning option): single rays
    /// in a beam then start at the beam's proven-empty prefix (see
    /// `beam::block`).
    pub large: bool,
    /// This tracer draws IAA's sub-samples (`frame::Fine`): its single
    /// rays in a beam start at the beam's proven-empty prefix, whatever
    /// the scene's size, and sweep the prefix's first candidate piece
    /// first (see `beam::block`).
    pub sub_samples: bool,
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
    /// A policy that never tries the form, as if it had lost every try at
    /// every block size.
    pub(crate) fn never() -> MeanValuePolicy {
        MeanValuePolicy {
            levels: [(MV_MIN_TRIES, 0); MV_LEVELS],
        }
    }

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
    /// Scratch space for pruning tapes.
    pub workspace: Workspace,
    /// The tile's octree cells, for shadow segments (see `render::cells`).
    pub cells: CellTapes,
    /// Buffers of batched root refinement.
    pub refine: super::refine::RefineScratch,
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
        let live_ops: Vec<usize> = evals
            .iter()
            .map(|e| e.function().map_or(0, |f| f.live_count()))
            .collect();
        let tapes = evals
            .iter()
            .zip(&live_ops)
            .map(|(e, &n)| {
                let least = if e.is_native() {
                    NATIVE_PRUNE_MIN_OPS
                } else {
                    PRUNE_MIN_OPS
                };
                let f = e.function().filter(|_| prune && n >= least)?;
                Some(Arc::new(Tape::new(f).keeping_signs()))
            })
            .collect();
        let large = live_ops.iter().any(|&n| n >= PRUNE_MIN_OPS);
        Tracer {
            cam,
            evals,
            colors: scene.objects.iter().map(|o| o.color).collect(),
            lights: &scene.lights,
            bounds: b,
            diag: (DVec3::from_array(b.max) - DVec3::from_array(b.min)).length(),
            live_ops,
            tapes,
            prune,
            flat: constant_along_rays(&cam, scene),
            groups: Arc::default(),
            slice_ends: Arc::new([]),
            large,
            sub_samples: false,
        }
    }

    /// The same tracer through another camera (the same scene at another
    /// resolution): everything else, flatness included, is kept.
    pub(crate) fn with_camera(&self, cam: RayCamera) -> Tracer<'a> {
        Tracer {
            cam,
            colors: self.colors.clone(),
            live_ops: self.live_ops.clone(),
            tapes: self.tapes.clone(),
            groups: Arc::default(),
            slice_ends: Arc::new([]),
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
            tapes: self.tapes.clone(),
            groups: Arc::clone(&self.groups),
            slice_ends: Arc::clone(&self.slice_ends),
            ..*self
        }
    }

    /// The pieces a sweep along rays over `[t0, t1]` starts from, as a
    /// stack (the nearest last): inside a tile whose functions are pruned
    /// to a tree of slices (see [`Tracer::pruned_to_beam`]), the range cut
    /// at the slices' ends, so that every piece lies in one slice and even
    /// the first evaluations run a slice's short tape rather than the
    /// whole function; elsewhere with pruning on, equal pieces about as
    /// deep as such slices; else one. A function of the range and of the
    /// tile (its camera, scene and T range) alone, so that every method
    /// cuts a ray the same way.
    pub(crate) fn first_pieces(&self, t0: f64, t1: f64) -> Vec<(f64, f64)> {
        if !self.slice_ends.is_empty() && t0 < t1 {
            let inner = self
                .slice_ends
                .iter()
                .copied()
                .filter(|&c| c > t0 && c < t1);
            let mut pieces = Vec::with_capacity(self.slice_ends.len() + 1);
            let mut last = t0;
            for end in inner.chain([t1]) {
                pieces.push((last, end));
                last = end;
            }
            pieces.reverse();
            return pieces;
        }
        super::probe::equal_pieces(t0, t1, self.equal_pieces(t0, t1))
    }

    // How many equal pieces `first_pieces` cuts `[t0, t1]` into without a
    // tile's slices.
    fn equal_pieces(&self, t0: f64, t1: f64) -> usize {
        if self.flat || !self.tapes.iter().any(Option::is_some) {
            return 1;
        }
        let slice = SLICE_ASPECT * f64::from(super::TILE) * self.cam.spacing(t1);
        let n = ((t1 - t0) / slice).ceil();
        if n.is_nan() || n <= 1.0 {
            return 1;
        }
        (n.min(f64::from(1u32 << SLICE_DEPTH)) as usize).next_power_of_two()
    }

    /// [`Tracer::first_pieces`], with `[t0, near]` a piece of its own,
    /// taken first, when `t0 < near < t1` (see `probe::Floor`).
    pub(crate) fn first_pieces_near(&self, t0: f64, near: f64, t1: f64) -> Vec<(f64, f64)> {
        if !(t0 < near && near < t1) {
            return self.first_pieces(t0, t1);
        }
        // Behind the first piece, pieces twice as deep as the one before,
        // cut again at the slices' ends: the two ascending sequences of
        // ends merged (this runs for every block and ray).
        let mut slices = self
            .slice_ends
            .iter()
            .copied()
            .filter(|&c| c > t0 && c < t1)
            .peekable();
        let mut pieces = Vec::with_capacity(8 + self.slice_ends.len());
        let (mut last, mut w, mut e) = (t0, near - t0, near);
        loop {
            let doubling = (e < t1).then_some(e);
            let end = match (doubling, slices.peek().copied()) {
                (Some(d), Some(s)) if s < d => {
                    slices.next();
                    s
                }
                (Some(d), _) => {
                    w *= 2.0;
                    e += w;
                    d
                }
                (None, Some(s)) => {
                    slices.next();
                    s
                }
                (None, None) => break,
            };
            if end != last {
                pieces.push((last, end));
                last = end;
            }
        }
        pieces.push((last, t1));
        pieces.reverse();
        pieces
    }

    /// The pieces a single ray's sweep over `[t0, t1]` starts from (a
    /// stack, the nearest last), where the beam it was split from found
    /// its first candidate piece at `[t0, near]` (`near` = `t0`: none).
    /// That piece comes first. Behind it, IAA's sub-samples take
    /// [`Tracer::first_pieces_near`]'s doubling pieces (the candidate is
    /// their pixel's; their own surface is often a few of its depths
    /// further); other rays, in scenes large enough to prune, take the
    /// pieces [`Tracer::first_pieces`] cuts (the tile's slices): at 1024²
    /// the candidate first took colonnade from 561 to 508 ms at one
    /// thread, where doubling pieces gained less on 1000 spheres than
    /// they cost.
    pub(crate) fn ray_pieces(&self, t0: f64, near: f64, t1: f64) -> Vec<(f64, f64)> {
        if self.sub_samples || !(t0 < near && near < t1) {
            return self.first_pieces_near(t0, near, t1);
        }
        let mut pieces = self.first_pieces(near, t1);
        pieces.push((t0, near));
        pieces
    }

    /// Whether the scene is flat, and [`Tracer::first_pieces_near`], for
    /// `probe::sweep`.
    pub(crate) fn sweep_mode(&self, t0: f64, near: f64, t1: f64) -> (bool, Vec<(f64, f64)>) {
        (self.flat, self.first_pieces_near(t0, near, t1))
    }

    /// The first end of a slice of this tile after `t`, if any.
    pub(crate) fn slice_end_after(&self, t: f64) -> Option<f64> {
        let i = self.slice_ends.partition_point(|&e| e <= t);
        self.slice_ends.get(i).copied()
    }

    /// Whether `[a, b]` lies inside one slice of this tile (always, outside
    /// a sliced tile): pruning to a region inside one slice prunes that
    /// slice's short tape, not the long one of the region around it.
    pub(crate) fn within_one_slice(&self, a: f64, b: f64) -> bool {
        self.slice_end_after(a).is_none_or(|e| e >= b)
    }

    /// The same tracer with the interior ends of a tile's slices (see
    /// [`Tracer::first_pieces`]).
    pub(crate) fn with_slice_ends(mut self, ends: Vec<f64>) -> Self {
        self.slice_ends = ends.into();
        self
    }

    /// Object `k` over `b`.
    pub(crate) fn interval(&self, k: usize, b: IBox, st: &mut RenderStats) -> Interval {
        st.interval_evals += 1;
        self.evals[k].interval(b)
    }

    /// The signs of F over `b` (None: F undefined on all of it), tightened
    /// where the natural enclosure straddles 0 by the mean-value form
    /// `f(c) + ∇F(b)·(b − c)` (c the box centre), met with it. Sound
    /// wherever the evaluator's gradient enclosure covers the
    /// (generalised) gradient of f over the box; it is used only when
    /// every gradient bound is finite, which rules out the poles and
    /// domain edges where it would not. `level` is the block's size class
    /// for the [`MeanValuePolicy`]. Signs only: the natural enclosure may
    /// come from another region's tape than the form (see
    /// [`SignBound`]).
    pub(crate) fn interval_tight(
        &self,
        k: usize,
        b: IBox,
        level: usize,
        st: &mut TileState,
    ) -> Option<SignBound> {
        let f = self.interval(k, b, &mut st.stats);
        if f.is_empty() {
            return None;
        }
        let natural = SignBound::of(f);
        if f.lo > 0.0 || f.hi < 0.0 {
            return Some(natural);
        }
        // Flat scenes (2D models seen along their missing axis) skip the
        // form outright: their functions are min/max trees of thousands of
        // ops, where it measured 7 wins in 13,833 tries on prospero at 512²
        // while compiling and running the interval-gradient evaluator
        // doubled the render time.
        if self.flat || !st.mean_value.pays(level) {
            return Some(natural);
        }
        if !b.iter().all(|c| c.lo.is_finite() && c.hi.is_finite()) {
            return Some(natural);
        }
        let c: [f64; 3] = b.map(|i| i.mid());
        // The centre's value and the gradient from one function (see
        // `Evaluator::answering`).
        let e = self.answering(k, &b);
        st.stats.interval_evals += 2;
        let g = e.interval_grad(b);
        if !g.d.iter().all(|&d| super::proof::bounded(d)) {
            return Some(natural);
        }
        let fc = e.interval(point_box(c));
        if !super::proof::bounded(fc) {
            return Some(natural);
        }
        let mut mv = fc;
        for i in 0..3 {
            mv = mv.add(g.d[i].mul(b[i].sub(Interval::point(c[i]))));
        }
        // `f` may come from another region's tape than `mv` (one that
        // keeps signs only); the meet still proves a sign only where one of
        // the two does, and every tape of the tree has the same signs.
        let tight = natural.meet(SignBound::of(mv));
        let win = tight.positive() || tight.negative();
        st.stats.mean_value_tries += 1;
        st.stats.mean_value_wins += u64::from(win);
        st.mean_value.record(level, win);
        Some(tight)
    }

    /// What evaluates object `k` over `b` and at the points of `b` with
    /// one function (see [`Evaluator::answering`]), for formulas that
    /// combine values from several evaluations.
    pub(crate) fn answering(&self, k: usize, b: &IBox) -> &dyn Evaluator {
        let e = self.evals[k].as_ref();
        e.answering(b).unwrap_or(e)
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

    /// [`Tracer::point_grad`] of object `k` at each of `points`, in one
    /// batch (on the tape of the region holding them all: the same signs
    /// as one by one, and on the surface the same normals to rounding),
    /// into `out` (as long as `points`); `cols`
    /// holds the coordinate columns.
    pub(crate) fn point_grads(
        &self,
        k: usize,
        points: &[[f64; 3]],
        cols: &mut [Vec<f64>; 3],
        out: &mut [Grad],
        st: &mut RenderStats,
    ) {
        st.point_evals += points.len() as u64;
        for (c, col) in cols.iter_mut().enumerate() {
            col.clear();
            col.extend(points.iter().map(|p| p[c]));
        }
        self.evals[k].point_grad_batch(&cols[0], &cols[1], &cols[2], out);
    }

    /// The scene's evaluators pruned to the box of `ray` over `t` (see
    /// [`Tracer::pruned_to`]), for the sub-pieces of a piece of a ray.
    pub(crate) fn pruned_to_ray(
        &self,
        ray: &super::camera::PixelRay,
        t: Interval,
        st: &mut TileState,
    ) -> Option<PrunedEvals> {
        let region = padded(crate::interval::boxes::ray_box(ray.o, ray.d, t))?;
        self.pruned_to_from(region, RAY_PRUNE_MIN_OPS, st)
    }

    /// The region the evaluations for the rays through the pixel centres
    /// `xs × ys` over `t` happen in: their beam's hull (not clipped to the
    /// bounds, which the tracer's own boxes overhang by rounding), widened
    /// by a relative [`REGION_PAD`]. An evaluation that still falls outside
    /// uses the whole function (see `crate::eval::regional`).
    pub(crate) fn beam_region(&self, xs: (f64, f64), ys: (f64, f64), t: Interval) -> Option<IBox> {
        padded(self.cam.corners(xs, ys).hull(t))
    }

    /// A region for pruning around `b`, a box the tracer computed (see
    /// [`Tracer::beam_region`]).
    pub(crate) fn region_around(&self, b: IBox) -> Option<IBox> {
        padded(b)
    }

    /// [`Tracer::beam_region`] of a beam whose corner rays are known.
    pub(crate) fn corner_region(&self, corners: &CornerRays, t: Interval) -> Option<IBox> {
        padded(corners.hull(t))
    }

    /// The scene's evaluators with every function that shrinks enough
    /// pruned to `region` (see [`crate::eval::tape`]), and their live op
    /// counts; `None` when none does. Each is pruned from the nearest
    /// evaluator up its chain of parents whose region holds `region` (the
    /// whole function at the top), which also answers outside `region`.
    pub(crate) fn pruned_to(&self, region: IBox, st: &mut TileState) -> Option<PrunedEvals> {
        self.pruned_to_from(region, PRUNE_MIN_OPS, st)
    }

    /// [`Tracer::pruned_to`], pruning only tapes of at least `min_ops`.
    fn pruned_to_from(
        &self,
        region: IBox,
        min_ops: usize,
        st: &mut TileState,
    ) -> Option<PrunedEvals> {
        // Whether to prune depends on the tape that answers for `region`,
        // not on this evaluator's own: a short tape of a block answers only
        // inside the block, and a box beside it meets the tile's longer
        // ones.
        if !self.prune || self.tapes.iter().all(Option::is_none) {
            return None;
        }
        self.replace_evals(|k, e| {
            self.tapes[k]
                .is_some()
                .then(|| self.prune_one(k, e, region, min_ops, st))
                .flatten()
        })
    }

    /// [`Tracer::pruned_to`] for each of `regions` (sibling blocks), the
    /// same evaluators, with the regions that prune from one tape pruned
    /// in one pass over it (`Tape::prune_batch`).
    pub(crate) fn pruned_to_batch(
        &self,
        regions: &[IBox],
        st: &mut TileState,
    ) -> Vec<Option<PrunedEvals>> {
        if !self.prune || self.tapes.iter().all(Option::is_none) {
            return vec![None; regions.len()];
        }
        // Per object, per region: its pruned evaluator, if any.
        let mut pruned: Vec<Vec<Option<PrunedEval>>> = Vec::with_capacity(self.evals.len());
        for (k, e) in self.evals.iter().enumerate() {
            let mut out = vec![None; regions.len()];
            if self.tapes[k].is_some() {
                let plans: Vec<Option<PrunePlan>> = regions
                    .iter()
                    .map(|&r| self.prune_plan(k, e, r, PRUNE_MIN_OPS))
                    .collect();
                // Regions that prune from the same tape with the same
                // limit go in one batch.
                let mut done = vec![false; regions.len()];
                for i in 0..regions.len() {
                    let Some(plan) = plans[i].as_ref().filter(|_| !done[i]) else {
                        continue;
                    };
                    let same: Vec<usize> = (i..regions.len())
                        .filter(|&j| {
                            plans[j].as_ref().is_some_and(|q| {
                                std::ptr::eq(q.tape, plan.tape) && q.most == plan.most
                            })
                        })
                        .collect();
                    let boxes: Vec<IBox> = same.iter().map(|&j| regions[j]).collect();
                    let children = plan.tape.prune_batch(&boxes, plan.most, &mut st.workspace);
                    for (&j, child) in same.iter().zip(children) {
                        done[j] = true;
                        let plan = plans[j].as_ref().expect("planned");
                        out[j] = child.map(|c| self.prune_finish(plan, regions[j], c, st));
                    }
                }
            }
            pruned.push(out);
        }
        (0..regions.len())
            .map(|i| self.replace_evals(|k, _| pruned[k][i].take()))
            .collect()
    }

    // Object `k`'s evaluator `e` pruned to `region`, and its op count, if
    // that shrinks it enough: pruned from the smallest region that holds
    // `region` (up `e`'s parents, then down its tree of sub-regions).
    fn prune_one(
        &self,
        k: usize,
        e: &Arc<dyn Evaluator>,
        region: IBox,
        min_ops: usize,
        st: &mut TileState,
    ) -> Option<(Arc<dyn Evaluator>, usize)> {
        let plan = self.prune_plan(k, e, region, min_ops)?;
        let p = plan
            .tape
            .prune_to_at_most(region, plan.most, &mut st.workspace)?;
        Some(self.prune_finish(&plan, region, p, st))
    }

    // What pruning object `k`'s evaluator `e` to `region` starts from:
    // the smallest region that holds `region` (up `e`'s parents, then down
    // its tree of sub-regions), and how long a child may be to pay;
    // `None` where it would not.
    fn prune_plan<'p>(
        &'p self,
        k: usize,
        e: &'p Arc<dyn Evaluator>,
        region: IBox,
        min_ops: usize,
    ) -> Option<PrunePlan<'p>> {
        let mut source = e;
        while let (Some(r), Some(p)) = (source.valid_region(), source.parent()) {
            if box_within(&region, &r) {
                break;
            }
            source = p;
        }
        let (tape, answer, before) = match source.as_regional() {
            Some(tree) => {
                let node = tree.smallest_holding(&region);
                (node.pruned_tape(), node.answer(), node.answer_len())
            }
            None => {
                let tape = self.tapes[k].as_deref()?;
                (tape, source, tape.len())
            }
        };
        // Along rays, only interpreted tapes are pruned: native code of a
        // few hundred ops seldom shrinks the eightfold it must.
        if before < min_ops || (min_ops >= RAY_PRUNE_MIN_OPS && answer.is_native()) {
            return None;
        }
        // Where the answer runs native code but leaves derivatives to its
        // tape (a long function's JIT), any shrinking pays: the region
        // keeps its tape for gradients and directional derivatives (see
        // `Regional`) and for its sub-regions to prune from.
        let g = gain(answer.as_ref());
        let any = answer.is_native() && !answer.derivatives_native();
        let most = if any { tape.len() - 1 } else { before / g };
        Some(PrunePlan {
            source,
            tape,
            answer,
            before,
            gain: g,
            most,
        })
    }

    // The evaluator of `plan`'s pruning `p` to `region`, and its op count.
    fn prune_finish(
        &self,
        plan: &PrunePlan<'_>,
        region: IBox,
        p: crate::eval::tape::PrunedTape,
        st: &mut TileState,
    ) -> (Arc<dyn Evaluator>, usize) {
        let after = p.tape.len();
        let pruned = if after * plan.gain <= plan.before {
            st.stats.pruned_ops_before += plan.before as u64;
            st.stats.pruned_ops_after += after as u64;
            Regional::new(region, p.tape, Arc::clone(plan.source))
        } else {
            let answer = (Arc::clone(plan.answer), plan.before);
            Regional::delegating(region, p.tape, answer, Arc::clone(plan.source))
        };
        (Arc::new(pruned) as Arc<dyn Evaluator>, after)
    }

    // The evaluators with each one `replace` gives (and its op count) in
    // place of the object's own; `None` when it replaces none.
    pub(crate) fn replace_evals(
        &self,
        mut replace: impl FnMut(usize, &Arc<dyn Evaluator>) -> Option<(Arc<dyn Evaluator>, usize)>,
    ) -> Option<PrunedEvals> {
        let mut any = false;
        let mut live = self.live_ops.clone();
        let mut evals = Vec::with_capacity(self.evals.len());
        for (k, e) in self.evals.iter().enumerate() {
            match replace(k, e) {
                Some((p, n)) => {
                    any = true;
                    live[k] = n;
                    evals.push(p);
                }
                None => evals.push(Arc::clone(e)),
            }
        }
        any.then_some((evals, live))
    }
}

/// `region` widened by a relative [`REGION_PAD`], so that boxes the
/// tracer rounds outward from the same rays stay inside it; `None` unless
/// it is finite.
fn padded(region: IBox) -> Option<IBox> {
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

/// Levels of halving a tile's beam along its rays (up to 2^SLICE_DEPTH
/// slices).
pub(crate) const SLICE_DEPTH: u32 = 6;
/// A slice is halved while it is deeper than this many times its width.
pub(crate) const SLICE_ASPECT: f64 = 2.0;

/// How much shorter a pruned tape must be than the one answering now.
pub(crate) fn gain(answer: &dyn Evaluator) -> usize {
    if answer.is_native() {
        PRUNE_GAIN_NATIVE
    } else {
        PRUNE_GAIN_INTERPRETED
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

#[cfg(test)]
impl<'a> Tracer<'a> {
    /// A tracer over `evals` (white, none pruned) and `lights`, through
    /// the default camera at `size`², in the default bounds.
    pub(crate) fn of_objects_for_tests(
        evals: &'a [Arc<dyn Evaluator>],
        lights: &'a [Light],
        size: u32,
    ) -> Tracer<'a> {
        Tracer {
            cam: RayCamera::new(&crate::scene::Camera::default(), size, size).unwrap(),
            evals,
            colors: vec![[1.0; 3]; evals.len()],
            lights,
            bounds: Bounds::default(),
            diag: 7.0,
            live_ops: vec![0; evals.len()],
            tapes: vec![None; evals.len()],
            prune: false,
            flat: false,
            groups: Default::default(),
            slice_ends: Arc::new([]),
            large: false,
            sub_samples: false,
        }
    }
}

#[cfg(test)]
impl Tracer<'static> {
    /// A tracer with no objects or lights through `camera` at
    /// `size`², over bounds that are not a cube and not centred.
    pub(crate) fn for_tests(camera: &crate::scene::Camera, size: u32) -> Tracer<'static> {
        Tracer {
            cam: RayCamera::new(camera, size, size).unwrap(),
            evals: &[],
            colors: vec![],
            lights: &[],
            bounds: Bounds {
                min: [-1.0, -0.5, -2.0],
                max: [1.5, 1.0, 0.25],
            },
            diag: 4.0,
            live_ops: vec![],
            tapes: vec![],
            prune: true,
            flat: false,
            groups: Default::default(),
            slice_ends: Arc::new([]),
            large: false,
            sub_samples: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // The pieces as a list front to back (the stack pops the last first).
    fn front_to_back(stack: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
        stack.into_iter().rev().collect()
    }

    #[test]
    fn pieces_near_a_candidate_take_it_first_then_double() {
        let tr = Tracer::for_tests(&crate::scene::Camera::default(), 64);
        let p = front_to_back(tr.first_pieces_near(1.0, 1.5, 10.0));
        assert_eq!(p[0], (1.0, 1.5));
        // Contiguous from t0 to t1, each piece at most twice as deep as
        // the one before.
        assert_eq!(p.last().unwrap().1, 10.0);
        for w in p.windows(2) {
            assert_eq!(w[0].1, w[1].0);
            assert!(w[1].1 - w[1].0 <= 2.0 * (w[0].1 - w[0].0) + 1e-12, "{p:?}");
        }
        assert_eq!(&p[1..4], &[(1.5, 2.5), (2.5, 4.5), (4.5, 8.5)]);
        // No candidate inside the range: the plain first pieces.
        assert_eq!(
            tr.first_pieces_near(1.0, 1.0, 10.0),
            tr.first_pieces(1.0, 10.0)
        );
        assert_eq!(
            tr.first_pieces_near(1.0, 12.0, 10.0),
            tr.first_pieces(1.0, 10.0)
        );
    }

    // The merge of the doubling ends with the slices' ends gives what
    // sorting both lists together would, equal ends once.
    #[test]
    fn pieces_near_a_candidate_merge_like_a_sort() {
        let mut tr = Tracer::for_tests(&crate::scene::Camera::default(), 64);
        let mut rng = crate::ir::random::Rng::new(7);
        for case in 0..2000 {
            let t0 = rng.unit() * 4.0;
            let near = t0 + rng.unit() * 2.0;
            let t1 = t0 + rng.unit() * 20.0;
            // Some slice ends fall exactly on doubling ends.
            let mut ends: Vec<f64> = (0..(case % 6)).map(|_| t0 + rng.unit() * 20.0).collect();
            if case % 3 == 0 {
                ends.push(near + 2.0 * (near - t0));
            }
            ends.sort_by(f64::total_cmp);
            tr.slice_ends = ends.clone().into();
            let got = tr.first_pieces_near(t0, near, t1);
            if !(t0 < near && near < t1) {
                assert_eq!(got, tr.first_pieces(t0, t1));
                continue;
            }
            let mut cuts = vec![t0];
            let (mut w, mut e) = (near - t0, near);
            while e < t1 {
                cuts.push(e);
                w *= 2.0;
                e += w;
            }
            cuts.extend(ends.iter().copied().filter(|&c| c > t0 && c < t1));
            cuts.sort_by(f64::total_cmp);
            cuts.dedup();
            cuts.push(t1);
            let want: Vec<(f64, f64)> = cuts.windows(2).rev().map(|w| (w[0], w[1])).collect();
            assert_eq!(got, want, "t0 {t0} near {near} t1 {t1} ends {ends:?}");
        }
    }

    // A ray's candidate piece comes first; behind it, a sub-sample's
    // pieces double and other rays' follow the tile's slices.
    #[test]
    fn a_rays_candidate_piece_comes_first() {
        let mut tr = Tracer::for_tests(&crate::scene::Camera::default(), 64);
        tr.slice_ends = Arc::new([2.0, 3.0]);
        let p = front_to_back(tr.ray_pieces(1.0, 1.5, 5.0));
        assert_eq!(p, vec![(1.0, 1.5), (1.5, 2.0), (2.0, 3.0), (3.0, 5.0)]);
        // Without a candidate: the plain first pieces.
        assert_eq!(tr.ray_pieces(1.0, 1.0, 5.0), tr.first_pieces(1.0, 5.0));
        tr.sub_samples = true;
        assert_eq!(
            tr.ray_pieces(1.0, 1.5, 5.0),
            tr.first_pieces_near(1.0, 1.5, 5.0)
        );
    }

    #[test]
    fn pieces_near_a_candidate_are_cut_at_slice_ends() {
        let mut tr = Tracer::for_tests(&crate::scene::Camera::default(), 64);
        tr.slice_ends = Arc::new([2.0, 3.0]);
        let p = front_to_back(tr.first_pieces_near(1.0, 1.5, 5.0));
        assert_eq!(
            p,
            vec![
                (1.0, 1.5),
                (1.5, 2.0),
                (2.0, 2.5),
                (2.5, 3.0),
                (3.0, 4.5),
                (4.5, 5.0)
            ]
        );
    }
}
