//! The pruning seam: a [`Scope`] is an evaluation context together with
//! the [`Pruner`] that specialises it to regions (tiles, slices, blocks,
//! pieces of rays), and [`TileState`] what one tile carries from one
//! evaluation to the next.

use std::sync::Arc;

use crate::eval::Evaluator;
use crate::eval::regional::{Answer, Parent, Regional};
use crate::eval::tape::{Tape, Workspace};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_within};
use crate::render::Enclosure;
use crate::render::context::stats::RenderStats;
use crate::render::context::{Context, EvalSet, PRUNE_MIN_OPS};
use crate::render::enclose::mean_value::{self, FormPolicy, MeanValueUse};
use crate::render::enclose::proof::SignBound;
use crate::render::prune::cells::{CellTapes, SharedCells};
use crate::render::prune::groups::TileGroups;
use crate::render::view::camera::RayCamera;
use crate::scene::Scene;

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

/// One object's pruned evaluator and its op count.
type PrunedEval = (Arc<Regional>, usize);

/// Where one pruning starts (see `Scope::prune_plan`).
struct PrunePlan<'p> {
    // What the pruned one falls back on outside its region.
    source: Parent,
    // The tape pruned.
    tape: &'p Tape,
    // What answers for the region now, and its length.
    answer: &'p Arc<dyn Evaluator>,
    before: usize,
    // `gain` of the answer, and the longest child that pays.
    gain: usize,
    most: usize,
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

/// What specialises an evaluation context to regions: the tapes it prunes,
/// the groups of tiles they were pruned to, and where in a tile's tree of
/// slices the current evaluators stand.
#[derive(Clone)]
pub(crate) struct Pruner {
    /// The tape of each whole function that is large enough to prune.
    pub tapes: Arc<[Option<Arc<Tape>>]>,
    /// Prune large functions to tiles and blocks.
    pub enabled: bool,
    /// Evaluators pruned to groups of tiles, which tiles prune theirs
    /// from (shared by the scopes of one camera).
    pub groups: Arc<TileGroups>,
    /// The render's coarse octree cells for shadow segments (see
    /// `prune::cells`), shared by every scope of the scene.
    pub cells: Arc<SharedCells>,
    /// The interior ends, in increasing order, of the slices of the tile
    /// these evaluators are pruned to (empty outside such a tile).
    pub slice_ends: Arc<[f64]>,
}

/// An evaluation context and its pruner: what every search of one tile,
/// slice or block evaluates with.
pub(crate) struct Scope<'a> {
    /// The scene's constants and the current evaluators.
    pub ctx: Context<'a>,
    /// What specialises them to regions.
    pub pruner: Pruner,
}

/// What tracing one tile carries from one evaluation to the next, by
/// owner: the counters and the enclosure policy, and the pruner's scratch
/// (the refinement's is the tile's rays', `trace::tile_rays`).
#[derive(Clone, Debug, Default)]
pub(crate) struct TileState {
    /// The tile's counters, merged into the render's at the end.
    pub stats: RenderStats,
    /// The tile's record of the mean-value form (policy, not a counter).
    pub mean_value: FormPolicy,
    /// The tile's record of the affine form on blocks.
    pub affine: FormPolicy,
    /// The tile's record of the affine form along single rays (a form of
    /// its own: one noise symbol, and it clips pieces as well as rejects).
    pub affine_along: FormPolicy,
    /// What the pruner keeps from one pruning to the next.
    pub prune: PruneScratch,
}

/// The pruner's per-tile scratch.
#[derive(Clone, Debug, Default)]
pub(crate) struct PruneScratch {
    /// Scratch space for pruning tapes.
    pub workspace: Workspace,
    /// The tile's octree cells, for shadow segments (see `prune::cells`),
    /// dropped with the tile.
    pub cells: CellTapes,
}

impl<'a> Scope<'a> {
    /// The scope of `scene` seen through `cam`, with one evaluator per
    /// object, pruning large functions when `prune`.
    pub(crate) fn new(
        scene: &'a Scene,
        evals: &'a [Arc<dyn Evaluator>],
        cam: RayCamera,
        prune: bool,
    ) -> Scope<'a> {
        let ctx = Context::new(scene, evals, cam);
        let tapes = evals
            .iter()
            .zip(&ctx.live_ops)
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
        let whole = EvalSet {
            evals: evals.to_vec(),
            live_ops: ctx.live_ops.clone(),
            regions: vec![None; evals.len()],
        };
        Scope {
            ctx,
            pruner: Pruner {
                tapes,
                enabled: prune,
                groups: Arc::default(),
                cells: Arc::new(SharedCells::new(whole)),
                slice_ends: Arc::new([]),
            },
        }
    }

    /// The same scope with `choice` of enclosures, and the whole-function
    /// tapes its affine form runs on.
    pub(crate) fn with_enclosure(mut self, choice: Enclosure) -> Scope<'a> {
        self.ctx.affine_tapes = crate::render::enclose::affine::whole_tapes(&self.ctx, choice);
        self.ctx.enclosure = choice;
        self
    }

    /// The same scope through another camera (the same scene at another
    /// resolution): everything else, flatness included, is kept; groups
    /// and slices belong to a camera and start empty.
    pub(crate) fn with_camera(&self, cam: RayCamera) -> Scope<'a> {
        Scope {
            ctx: self.ctx.with_camera(cam),
            pruner: Pruner {
                groups: Arc::default(),
                slice_ends: Arc::new([]),
                ..self.pruner.clone()
            },
        }
    }

    /// The same scope with the evaluators of `set` (pruned ones).
    pub(crate) fn with_evals<'b>(&self, set: &'b EvalSet) -> Scope<'b>
    where
        'a: 'b,
    {
        Scope {
            ctx: self.ctx.with_evals(set),
            pruner: self.pruner.clone(),
        }
    }

    /// tile (its camera, scene and T range) alone, so that every method
    /// cuts a ray the same way.
    pub(crate) fn first_pieces(&self, t0: f64, t1: f64) -> Vec<(f64, f64)> {
        if !self.pruner.slice_ends.is_empty() && t0 < t1 {
            let inner = self
                .pruner
                .slice_ends
                .iter()
                .copied()
                .filter(|&c| c > t0 && c < t1);
            let mut pieces = Vec::with_capacity(self.pruner.slice_ends.len() + 1);
            let mut last = t0;
            for end in inner.chain([t1]) {
                pieces.push((last, end));
                last = end;
            }
            pieces.reverse();
            return pieces;
        }
        equal_pieces(t0, t1, self.equal_piece_count(t0, t1))
    }

    // How many equal pieces `first_pieces` cuts `[t0, t1]` into without a
    // tile's slices.
    fn equal_piece_count(&self, t0: f64, t1: f64) -> usize {
        if self.ctx.flat || !self.pruner.tapes.iter().any(Option::is_some) {
            return 1;
        }
        let slice = SLICE_ASPECT * f64::from(crate::render::TILE) * self.ctx.cam.spacing(t1);
        let n = ((t1 - t0) / slice).ceil();
        if n.is_nan() || n <= 1.0 {
            return 1;
        }
        (n.min(f64::from(1u32 << SLICE_DEPTH)) as usize).next_power_of_two()
    }

    /// [`Scope::first_pieces`], with `[t0, near]` a piece of its own,
    /// taken first, when `t0 < near < t1` (see `probe::EmptyPrefix`).
    pub(crate) fn first_pieces_near(&self, t0: f64, near: f64, t1: f64) -> Vec<(f64, f64)> {
        if !(t0 < near && near < t1) {
            return self.first_pieces(t0, t1);
        }
        // Behind the first piece, pieces twice as deep as the one before,
        // cut again at the slices' ends: the two ascending sequences of
        // ends merged (this runs for every block and ray).
        let mut slices = self
            .pruner
            .slice_ends
            .iter()
            .copied()
            .filter(|&c| c > t0 && c < t1)
            .peekable();
        let mut pieces = Vec::with_capacity(8 + self.pruner.slice_ends.len());
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
    /// [`Scope::first_pieces_near`]'s doubling pieces (the candidate is
    /// their pixel's; their own surface is often a few of its depths
    /// further); other rays, in scenes large enough to prune, take the
    /// pieces [`Scope::first_pieces`] cuts (the tile's slices): at 1024²
    /// the candidate first took colonnade from 561 to 508 ms at one
    /// thread, where doubling pieces gained less on 1000 spheres than
    /// they cost.
    pub(crate) fn ray_pieces(&self, t0: f64, near: f64, t1: f64) -> Vec<(f64, f64)> {
        if self.ctx.sub_samples || !(t0 < near && near < t1) {
            return self.first_pieces_near(t0, near, t1);
        }
        let mut pieces = self.first_pieces(near, t1);
        pieces.push((t0, near));
        pieces
    }

    /// The first end of a slice of this tile after `t`, if any.
    pub(crate) fn slice_end_after(&self, t: f64) -> Option<f64> {
        let i = self.pruner.slice_ends.partition_point(|&e| e <= t);
        self.pruner.slice_ends.get(i).copied()
    }

    /// Whether `[a, b]` lies inside one slice of this tile (always, outside
    /// a sliced tile): pruning to a region inside one slice prunes that
    /// slice's short tape, not the long one of the region around it.
    pub(crate) fn within_one_slice(&self, a: f64, b: f64) -> bool {
        self.slice_end_after(a).is_none_or(|e| e >= b)
    }

    /// The same tracer with the interior ends of a tile's slices (see
    /// [`Scope::first_pieces`]).
    pub(crate) fn with_slice_ends(mut self, ends: Vec<f64>) -> Self {
        self.pruner.slice_ends = ends.into();
        self
    }

    /// The signs of object `k`'s F over `b`, tightened by the mean-value
    /// form where it pays (see [`mean_value::sign_bound`]).
    pub(crate) fn interval_tight(
        &self,
        k: usize,
        b: IBox,
        level: usize,
        st: &mut TileState,
    ) -> Option<SignBound> {
        let tile = MeanValueUse {
            stats: &mut st.stats,
            policy: &mut st.mean_value,
            affine: &mut st.affine,
        };
        mean_value::sign_bound(&self.ctx, k, b, level, tile)
    }

    /// The scene's evaluators pruned to the box of `ray` over `t` (see
    /// [`Scope::pruned_to`]), for the sub-pieces of a piece of a ray.
    pub(crate) fn pruned_to_ray(
        &self,
        ray: &crate::render::view::camera::PixelRay,
        t: Interval,
        st: &mut TileState,
    ) -> Option<EvalSet> {
        let region = self
            .ctx
            .region_around(crate::interval::boxes::ray_box(ray.o, ray.d, t))?;
        self.pruned_to_from(region, RAY_PRUNE_MIN_OPS, st)
    }

    /// counts; `None` when none does. Each is pruned from the nearest
    /// evaluator up its chain of parents whose region holds `region` (the
    /// whole function at the top), which also answers outside `region`.
    pub(crate) fn pruned_to(&self, region: IBox, st: &mut TileState) -> Option<EvalSet> {
        self.pruned_to_from(region, PRUNE_MIN_OPS, st)
    }

    /// [`Scope::pruned_to`], pruning only tapes of at least `min_ops`.
    fn pruned_to_from(&self, region: IBox, min_ops: usize, st: &mut TileState) -> Option<EvalSet> {
        // Whether to prune depends on the tape that answers for `region`,
        // not on this evaluator's own: a short tape of a block answers only
        // inside the block, and a box beside it meets the tile's longer
        // ones.
        if !self.pruner.enabled || self.pruner.tapes.iter().all(Option::is_none) {
            return None;
        }
        self.ctx.replace_evals(|k, e| {
            self.pruner.tapes[k]
                .is_some()
                .then(|| self.prune_one(k, e, region, min_ops, st))
                .flatten()
        })
    }

    /// [`Scope::pruned_to`] for each of `regions` (sibling blocks), the
    /// same evaluators, with the regions that prune from one tape pruned
    /// in one pass over it (`Tape::prune_batch`).
    pub(crate) fn pruned_to_batch(
        &self,
        regions: &[IBox],
        st: &mut TileState,
    ) -> Vec<Option<EvalSet>> {
        if !self.pruner.enabled || self.pruner.tapes.iter().all(Option::is_none) {
            return vec![None; regions.len()];
        }
        // Per object, per region: its pruned evaluator, if any.
        let mut pruned: Vec<Vec<Option<PrunedEval>>> = Vec::with_capacity(self.ctx.evals.len());
        for (k, e) in self.ctx.evals.iter().enumerate() {
            let mut out = vec![None; regions.len()];
            if self.pruner.tapes[k].is_some() {
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
                    let children =
                        plan.tape
                            .prune_batch(&boxes, plan.most, &mut st.prune.workspace);
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
            .map(|i| self.ctx.replace_evals(|k, _| pruned[k][i].take()))
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
    ) -> Option<PrunedEval> {
        let plan = self.prune_plan(k, e, region, min_ops)?;
        let p = plan
            .tape
            .prune_to_at_most(region, plan.most, &mut st.prune.workspace)?;
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
        // Up the object's tree of regions (typed: see `Context::regions`)
        // to the first that holds `region`; past the top, the evaluator
        // the tree was pruned from.
        let mut tree = self.ctx.region_of(k);
        let mut whole = e;
        while let Some(t) = tree {
            if box_within(&region, &t.region()) {
                break;
            }
            tree = t.parent_region();
            if tree.is_none() {
                whole = t.parent_evaluator();
            }
        }
        let (source, tape, answer, before) = match tree {
            Some(t) => {
                let node = t.smallest_holding(&region);
                let source = Parent::Region(Arc::clone(t));
                (source, node.pruned_tape(), node.answer(), node.answer_len())
            }
            None => {
                let tape = self.pruner.tapes[k].as_deref()?;
                (Parent::Whole(Arc::clone(whole)), tape, whole, tape.len())
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
    ) -> PrunedEval {
        let after = p.tape.len();
        let pruned = if after * plan.gain <= plan.before {
            st.stats.pruned_ops_before += plan.before as u64;
            st.stats.pruned_ops_after += after as u64;
            Regional::new(region, p.tape, plan.source.clone())
        } else {
            let answer = Answer {
                evaluator: Arc::clone(plan.answer),
                ops: plan.before,
            };
            Regional::delegating(region, p.tape, answer, plan.source.clone())
        };
        (Arc::new(pruned), after)
    }
}

/// `[t0, t1]` cut into `n` equal pieces, as a stack: the nearest piece
/// last, so that it is popped first.
pub(crate) fn equal_pieces(t0: f64, t1: f64, n: usize) -> Vec<(f64, f64)> {
    let n = n.max(1);
    let at = |i: usize| {
        if i == n {
            t1
        } else {
            t0 + (t1 - t0) * (i as f64 / n as f64)
        }
    };
    (0..n).rev().map(|i| (at(i), at(i + 1))).collect()
}

#[cfg(test)]
impl<'a> Scope<'a> {
    /// A scope over `evals` (white, none pruned) and `lights`, through the
    /// default camera at `size`², in the default bounds.
    pub(crate) fn of_objects_for_tests(
        evals: &'a [Arc<dyn Evaluator>],
        lights: &'a [crate::scene::Light],
        size: u32,
    ) -> Scope<'a> {
        Scope {
            ctx: Context::of_objects_for_tests(evals, lights, size),
            pruner: Pruner::off(evals.len()),
        }
    }
}

#[cfg(test)]
impl Scope<'static> {
    /// A scope with no objects or lights through `camera` at `size`²,
    /// over bounds that are not a cube and not centred, pruning on.
    pub(crate) fn for_tests(camera: &crate::scene::Camera, size: u32) -> Scope<'static> {
        Scope {
            ctx: Context::for_tests(camera, size),
            pruner: Pruner {
                enabled: true,
                ..Pruner::off(0)
            },
        }
    }
}

#[cfg(test)]
impl Pruner {
    /// A pruner of `n` objects that prunes nothing.
    fn off(n: usize) -> Pruner {
        Pruner {
            tapes: vec![None; n].into(),
            enabled: false,
            groups: Arc::default(),
            cells: Arc::default(),
            slice_ends: Arc::new([]),
        }
    }
}

#[cfg(test)]
#[path = "scope_tests.rs"]
mod tests;
