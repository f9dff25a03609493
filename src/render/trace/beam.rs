//! Beams: blocks of pixels traced together with interval hulls.
//!
//! A block's rays form a beam; its hull over a ray-parameter interval T is
//! exact up to rounding ([`crate::render::view::camera`]). The block's T range (the union
//! of its pixels' slab ranges) is bisected front to back down to a width
//! comparable with the block's footprint; pieces where every live object is
//! strictly positive are rejected. If all of T is rejected the block is
//! background and no ray is traced. Otherwise, with [t0, ta] rejected, the
//! inclusion test checks F over the hull of the block's points at t = ta
//! (strictly positive) and at some tb > ta (strictly negative), and that
//! F is non-increasing along every ray over the beam piece [ta, tb]
//! (interval gradient · direction ≤ 0; where tb lies deep, as behind a
//! grazing beam, over up to four pieces of [ta, tb]): every ray then has
//! its first root in [ta, tb], with F ≤ 0 behind it, and each pixel only
//! refines that bracket on the point evaluator. Blocks that are neither
//! split in four, keeping the rejected prefix and dropping objects proven
//! positive over the whole remaining beam; single pixels get a guaranteed
//! single ray ([`super::ray`]). The interval tests themselves (scene
//! minimum over a beam piece, the sweep, the inclusion search) are shared
//! with anti-aliasing in `super::probe`.
//!
//! A block whose rays' start points (each at its own clip start) all lie
//! where F < 0 is settled at once: every ray hits at its start (cut-away
//! faces, filled 2D masks). Over a block, an object's interval that
//! straddles 0 is tightened by the mean-value form
//! (`Scope::interval_tight`), which pays off on the small hulls near a
//! surface, where the natural extension overestimates most.

use super::probe::{self, EmptyPrefix, Rect, SignForm, SweepOutcome, SweepRange};
use super::ray::{scene_point, trace_ray, trace_ray_near_first};
use super::refine::{Bracket, refine_batch, scene_points};
use super::sweep::{self, Search, SweepState, Visit};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_hull, ray_box};
use crate::render::context::stats::RenderStats;
use crate::render::enclose::proof;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::view::camera::CornerRays;
use crate::render::{Class, Hit};

pub(crate) use super::tile_rays::TileRays;

/// Traces every pixel of the tile with beams.
pub(crate) fn trace_tile(tr: &Scope<'_>, tile: &mut TileRays, h: u32, st: &mut TileState) {
    debug_assert_eq!(h, tile.h);
    let live: Vec<u32> = (0..tr.ctx.evals.len() as u32).collect();
    // An IAA fine tile holds the sub-samples of a 2×2-pixel square whose
    // split pixels' area tests were each undecided: a beam over the whole
    // square almost never decides (orthocircle at 256², depth 2: 1,100
    // such tests, 3 included, none rejected), so its quarters start.
    if tr.ctx.sub_samples && !tile.whole().is_pixel() {
        split(tr, tile, tile.whole(), tile.top, &live, st);
        return;
    }
    block(tr, tile, tile.whole(), tile.top, &live, st);
}

fn block(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    b: Rect,
    floor: EmptyPrefix,
    live: &[u32],
    st: &mut TileState,
) {
    let t_floor = floor.at;
    // The block's T range from its pixels' slabs.
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, j) in b.pixels() {
        if let Some((a, c)) = tile.slabs[tile.idx(i, j)] {
            t0 = t0.min(a);
            t1 = t1.max(c);
        }
    }
    let single = b.is_pixel();
    t0 = t0.max(t_floor);
    if t0.partial_cmp(&t1).is_none_or(|o| o.is_gt()) || live.is_empty() {
        if !single {
            st.stats.blocks_rejected += 1;
        }
        set_block(tile, b, Class::Background);
        return;
    }
    if single {
        let k = tile.idx(b.x0, b.y0);
        let from_floor = tr.ctx.large || tr.ctx.sub_samples;
        let start = RayStart { floor, from_floor };
        single_ray(tr, tile, k, start, (t0, t1), live, st);
        return;
    }
    // The beam's corner rays (the camera's, to the bit), which both tests
    // below read.
    let corners = tile.grid.corners((b.x0, b.y0), (b.x1, b.y1));
    if t_floor <= t0 && all_start_inside(tr, tile, b, &corners, live, &mut st.stats) {
        st.stats.blocks_included += 1;
        return;
    }
    let near = floor.near_from(t0);
    beam_tests(tr, tile, b, &corners, (t0, near, t1), live, st);
}

/// Where a single ray below a beam may start.
#[derive(Copy, Clone, Debug)]
pub(crate) struct RayStart {
    /// What the beams above proved empty along the ray.
    pub floor: EmptyPrefix,
    /// Whether the ray starts at the floor (where f is positive there)
    /// rather than at its clip start.
    pub from_floor: bool,
}

/// Traces pixel `k` of the tile as one guaranteed ray, below a beam that
/// proved its rays empty up to `floor` (the block's T range `(t0, t1)`
/// where its slab holds none); from the floor where `from_floor` says so
/// (see below), else from its clip start.
pub(crate) fn single_ray(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    k: usize,
    start: RayStart,
    (t0, t1): (f64, f64),
    live: &[u32],
    st: &mut TileState,
) {
    let RayStart { floor, from_floor } = start;
    let t_floor = floor.at;
    let (pt0, pt1) = tile.slabs[k].unwrap_or((t0, t1));
    let ray = tile.ray(k);
    // In a scene large enough to prune (`Scope::large`), the ray
    // starts where the blocks above it proved its beam empty
    // (`t_floor`) rather than at its clip start, when f is positive
    // there: sweeping that
    // prefix again cost a third of a 1000-sphere render, its pieces
    // evaluated on the tile's slice tapes of hundreds of ops. No
    // surface is skipped (interval arithmetic excluded it over the
    // whole beam). `Method::Pixel`'s rays start at their clip starts
    // and cut their pieces elsewhere: roots are refined from other
    // brackets (depths agree to the refinement tolerance), and where
    // f overflows or is undefined along the prefix the two sweeps can
    // settle a pixel differently (an adversarial 2-op scene drew 198
    // more pixels), so small scenes, where the prefix costs a few
    // short evaluations, keep the clip start and the pixel method's
    // exact mask.
    // IAA's base samples and sub-samples start at the floor too (their
    // masks are compared with no other method's). Both sweep the block's
    // first candidate piece first (see `probe::EmptyPrefix` and
    // `Scope::ray_pieces`).
    let start = if from_floor
        && t_floor > pt0
        && scene_point(tr, live, ray.at(t_floor), &mut st.stats).0 > 0.0
    {
        t_floor
    } else {
        pt0
    };
    let near = if from_floor {
        floor.near_from(start)
    } else {
        start
    };
    tile.hits[k] = trace_ray_near_first(tr, &ray, (start, near), pt1, live, st);
    tile.class[k] = Class::Ray;
}

// The beam tests of a block of several pixels over its T range: rejected,
// included (every ray's first root bracketed), or split in four.
// long-fn: one decision (rejected, included or split) read as the
// sequence of tests the paper gives, each needing the last one's facts.
fn beam_tests(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    b: Rect,
    corners: &CornerRays,
    (t0, near, t1): (f64, f64, f64),
    live: &[u32],
    st: &mut TileState,
) {
    let side_px = (b.x1 - b.x0).max(b.y1 - b.y0);
    let side = f64::from(side_px);
    let form = SignForm::Tight(side_px.ilog2() as usize);
    let min_w = |t: f64| probe::min_width(tr, side, t);
    let eval_min =
        |t: Interval, st: &mut TileState| probe::scene_signs(tr, live, corners.hull(t), form, st);
    let (ta, tb) = match probe::sweep(tr, SweepRange { t0, near, t1 }, min_w, |t| {
        eval_min(t, st).positive()
    }) {
        SweepOutcome::Empty => {
            st.stats.blocks_rejected += 1;
            set_block(tile, b, Class::Background);
            return;
        }
        // Flat scenes are traced by `super::plane`; a flat sweep here
        // would only be split down to single rays.
        SweepOutcome::Flat => {
            st.stats.blocks_undecided += 1;
            split(tr, tile, b, EmptyPrefix::at(t0), live, st);
            return;
        }
        SweepOutcome::Candidate(ta, tb) => (ta, tb),
    };
    // Inclusion test: positive at ta, negative at some tb' ahead.
    let end = probe::bracket_end((ta, tb), t1, min_w, probe::Reach::INCLUSION, |t| {
        eval_min(Interval::point(t), st)
    });
    // A bracket found past `INCLUSION_REACH` (a grazing beam) is long: its
    // hull's gradient enclosure is tightened by testing it in pieces.
    let splits = |tb2: f64| {
        let reach = probe::INCLUSION_REACH[probe::INCLUSION_REACH.len() - 1];
        if tb2 - ta > reach * (tb - ta).max(min_w(ta)) {
            DEEP_SPLITS
        } else {
            0
        }
    };
    if let Some(tb2) = end
        && decreasing_in_pieces(tr, corners, (ta, tb2), live, splits(tb2), &mut st.stats)
    {
        st.stats.blocks_included += 1;
        // Every pixel refines its root inside the bracket's beam: prune
        // there (a few pixels wide and a bracket deep), if that is inside
        // one slice of the tile (else its points run the slices' tapes).
        let bracket = tr
            .within_one_slice(ta, tb2)
            .then(|| tr.ctx.corner_region(corners, Interval::new(ta, tb2)))
            .flatten()
            .and_then(|region| tr.pruned_to(region, st));
        match bracket {
            Some(set) => {
                let local = tr.with_evals(&set);
                include_block(&local, tile, b, ta, tb2, live, st);
            }
            None => include_block(tr, tile, b, ta, tb2, live, st),
        }
        return;
    }
    st.stats.blocks_undecided += 1;
    // Objects positive over the whole remaining beam are dropped below.
    let rest = corners.hull(Interval::new(ta, t1));
    let sub_live: Vec<u32> = if live.len() == 1 {
        live.to_vec()
    } else {
        live.iter()
            .copied()
            .filter(|&k| {
                let v = tr.ctx.interval(k as usize, rest, &mut st.stats);
                !proof::holds_no_surface(v)
            })
            .collect()
    };
    // The sub-blocks work near the first candidate piece: prune there, up
    // to the end of the tile's slice that holds it (pruning across slices
    // would prune the long tape of the region around them).
    let reach = ta + PRUNE_WINDOW * (tb - ta).max(min_w(ta));
    let end = tr.slice_end_after(ta).map_or(t1, |e| e.min(t1));
    let window = Interval::new(ta, end.min(reach));
    let floor = EmptyPrefix { at: ta, near: tb };
    split_pruned(tr, tile, b, (corners, window), floor, &sub_live, st);
}

/// Whether every live object is proven positive or undefined over each of
/// `boxes`, one batch per object.
pub(crate) fn clear_boxes(
    tr: &Scope<'_>,
    boxes: &[IBox],
    live: &[u32],
    st: &mut TileState,
) -> Vec<bool> {
    let mut clear = vec![true; boxes.len()];
    let mut f = vec![Interval::point(0.0); boxes.len()];
    for &o in live {
        tr.ctx.evals[o as usize].interval_batch(boxes, &mut f);
        for (c, fi) in clear.iter_mut().zip(&f) {
            *c &= proof::holds_no_surface(*fi);
        }
    }
    st.stats.interval_evals += (boxes.len() * live.len()) as u64;
    clear
}

// Width of the window a split block prunes its functions to, in units of
// its first candidate piece: its sub-blocks and rays evaluate mostly there
// (evaluations outside it use the unpruned functions, see
// `crate::eval::regional`).
pub(crate) const PRUNE_WINDOW: f64 = 8.0;

// `split`, with the functions first pruned to the block's beam over
// `window` (the beam of its pixel centres, whose corner rays are
// `corners`) where that shrinks them enough (see `Scope::pruned_to`).
fn split_pruned(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    b: Rect,
    (corners, window): (&CornerRays, Interval),
    floor: EmptyPrefix,
    live: &[u32],
    st: &mut TileState,
) {
    let pruned = tr
        .ctx
        .corner_region(corners, window)
        .and_then(|region| tr.pruned_to(region, st));
    match pruned {
        Some(set) => {
            let local = tr.with_evals(&set);
            split(&local, tile, b, floor, live, st);
        }
        None => split(tr, tile, b, floor, live, st),
    }
}

// Traces the four quarters of a block.
fn split(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    b: Rect,
    floor: EmptyPrefix,
    live: &[u32],
    st: &mut TileState,
) {
    for q in b.quarters_by_column() {
        block(tr, tile, q, floor, live, st);
    }
}

// Whether the scene function is non-increasing along every ray of the
// block over T: every live object that may be ≤ 0 on the beam piece has
// ∇F · d ≤ 0 there (d over the block's directions, the hull of the corner
// directions since d is affine in screen position). Objects positive on
// the piece do not change where the minimum vanishes, and a minimum of
// non-increasing functions is non-increasing, so once F ≤ 0 along a ray
// it stays so: with a sign change over T, {t : F ≤ 0} is one final part
// [r, tb] of T, r is the ray's first root, and the refinement's brackets
// (positive end before r, non-positive end in [r, tb]) converge to it.
// Strictness is not needed, and asking for it refused the faces seen
// edge-on (dF/dt = 0 exactly), which are everywhere in an axis-aligned
// model seen along an axis: colonnade split 5,000 more 2×2 blocks into
// single rays. Where F = 0 on a stretch of a ray (a ray inside a face's
// plane), any point of the stretch is on the surface; the refinement may
// end anywhere in it, within the bracket.
fn decreasing(
    tr: &Scope<'_>,
    corners: &CornerRays,
    t: Interval,
    live: &[u32],
    st: &mut RenderStats,
) -> bool {
    let hb = corners.hull(t);
    let dirs = corners.directions();
    let positive = proof::holds_no_surface;
    // The one directional partial, in forward mode: half the work of the
    // gradient, and usually tighter than its dot product with `dirs` (the
    // chain rule factored rather than expanded).
    if let [k] = live[..] {
        // One object: the derivative's pass encloses its value too, so the
        // separate interval evaluation is saved.
        let [f, dfdt] = tr.ctx.interval_dir(k as usize, hb, dirs, st);
        return positive(f) || proof::non_increasing(dfdt);
    }
    live.iter().all(|&k| {
        // Several: most are positive over the piece, for one interval each.
        if positive(tr.ctx.interval(k as usize, hb, st)) {
            return true;
        }
        let [_, dfdt] = tr.ctx.interval_dir(k as usize, hb, dirs, st);
        proof::non_increasing(dfdt)
    })
}

/// Levels of halving [`decreasing_in_pieces`] may apply to a bracket found
/// past [`probe::INCLUSION_REACH`] (up to four pieces). On orthocircle at
/// 1024² the deeper reach with these pieces settled blocks holding 12,500
/// single rays (8% of the render); brackets within the usual reach are
/// tested whole, as splitting them cost colonnade and 1000 spheres 2-4%
/// for few rays saved.
const DEEP_SPLITS: u32 = 2;

// `decreasing` over T = [a, b], or else over its halves, down to `depth`
// levels: a narrower piece's hull has a tighter gradient enclosure. Each
// piece having the property is enough: on each, {t : F ≤ 0} is a final
// part of the piece (the live objects that may vanish there do not
// increase), so over consecutive pieces it is one final part of T, and a
// ray with a sign change over T still has its first root there and F ≤ 0
// behind it.
fn decreasing_in_pieces(
    tr: &Scope<'_>,
    corners: &CornerRays,
    (a, b): (f64, f64),
    live: &[u32],
    depth: u32,
    st: &mut RenderStats,
) -> bool {
    // A piece `depth` halvings down is 2^-depth of the range wide, one a
    // level up twice that: the threshold between them stops the halving.
    let narrowest = 1.5 * (b - a) / f64::from(1u32 << depth);
    let mut search = AllDecreasing {
        corners,
        live,
        narrowest,
        st,
    };
    sweep::sweep(tr, vec![(a, b)], &mut search, &mut SweepState::new()).is_none()
}

// The search of `decreasing_in_pieces`: found, a piece too narrow to
// halve on which the decrease was not proven.
struct AllDecreasing<'a> {
    corners: &'a CornerRays,
    live: &'a [u32],
    narrowest: f64,
    st: &'a mut RenderStats,
}

impl Search for AllDecreasing<'_> {
    type Found = ();

    #[inline]
    fn visit(&mut self, tr: &Scope<'_>, (a, b): (f64, f64), _: &mut SweepState) -> Visit<()> {
        if decreasing(tr, self.corners, Interval::new(a, b), self.live, self.st) {
            Visit::Drop
        } else if b - a <= self.narrowest {
            Visit::Stop(())
        } else {
            Visit::Halve
        }
    }
}

// Whether every ray of the block starts inside a solid, proven by F < 0
// over the hull of the rays' start points (each at its own clip start);
// if so, records the hits. Agrees with the point test of single rays.
fn all_start_inside(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    b: Rect,
    corners: &CornerRays,
    live: &[u32],
    st: &mut RenderStats,
) -> bool {
    let Some(hull) = start_hull(tr, tile, b, corners) else {
        return false;
    };
    // The smallest object value must be negative: one object negative
    // over the whole hull suffices.
    let mut inside_obj = None;
    for &k in live {
        let v = tr.ctx.interval(k as usize, hull, st);
        if v.hi < 0.0 {
            inside_obj = Some(k);
            break;
        }
    }
    if inside_obj.is_none() {
        return false;
    }
    // F < 0 over the hull says only that f < 0 wherever it is defined
    // there (partial domains): a start point where f is undefined is not
    // inside. The single-ray start test is a point test, so each start is
    // confirmed the same way, keeping both methods' pixels identical.
    let mut starts = Vec::new();
    for (i, j) in b.pixels() {
        let k = tile.idx(i, j);
        if let Some((pt0, _)) = tile.slabs[k] {
            starts.push((k, pt0));
        }
    }
    let points: Vec<[f64; 3]> = starts.iter().map(|&(k, t0)| tile.ray(k).at(t0)).collect();
    let values = scene_points(tr, live, &points, st);
    // NaN (undefined) is not inside.
    if values.iter().any(|&(v, _)| v.is_nan() || v >= 0.0) {
        return false;
    }
    for (i, j) in b.pixels() {
        let k = tile.idx(i, j);
        tile.class[k] = Class::Included;
        tile.hits[k] = None;
    }
    for (&(k, t), &(_, obj)) in starts.iter().zip(&values) {
        tile.hits[k] = Some(Hit {
            t,
            obj,
            inside: true,
            grad: None,
            front: None,
        });
    }
    true
}

// A box holding every start point of the block's rays (each at its own
// clip start); `None` when no ray meets the bounds. Where the starts lie
// at nearly one depth (2D models, views along a face of the bounds), the
// beam's hull over their depths, from its four corner rays; else the hull
// of the pixels' own start boxes, computed once per tile, which is
// tighter where the starts spread along the rays.
fn start_hull(tr: &Scope<'_>, tile: &mut TileRays, b: Rect, corners: &CornerRays) -> Option<IBox> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, j) in b.pixels() {
        if let Some((t0, _)) = tile.slabs[tile.idx(i, j)] {
            lo = lo.min(t0);
            hi = hi.max(t0);
        }
    }
    if lo > hi {
        return None;
    }
    if hi - lo <= tr.ctx.cam.spacing(hi) {
        return Some(corners.hull(Interval::new(lo, hi)));
    }
    if tile.starts.is_empty() {
        tile.starts = (tile.rays.iter().zip(&tile.slabs))
            .map(|(r, s)| s.map(|(t0, _)| ray_box(r.o, r.d, Interval::point(t0))))
            .collect();
    }
    let mut hull: Option<IBox> = None;
    for j in b.y0..b.y1 {
        for k in tile.idx(b.x0, j)..tile.idx(b.x1, j) {
            if let Some(p) = tile.starts[k] {
                hull = Some(hull.map_or(p, |h| box_hull(h, p)));
            }
        }
    }
    hull
}

// Every ray of the block has its first root in [ta, tb]: refine per pixel,
// the pixels' searches together (`refine_batch`, the same bits as one by
// one on the same tape). A pixel whose refinement fails gets a full ray.
fn include_block(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    b: Rect,
    ta: f64,
    tb: f64,
    live: &[u32],
    st: &mut TileState,
) {
    // (pixel, its clip range, index of its bracket if it has one)
    let mut pixels: Vec<(usize, (f64, f64), Option<usize>)> = Vec::new();
    let mut scratch = std::mem::take(&mut tile.refine);
    let brackets = &mut scratch.brackets;
    brackets.clear();
    for (i, j) in b.pixels() {
        let k = tile.idx(i, j);
        tile.class[k] = Class::Included;
        let Some((pt0, pt1)) = tile.slabs[k] else {
            tile.hits[k] = None;
            continue;
        };
        st.stats.pixels_refined += 1;
        // The bracket is clipped to the pixel's own range first: a root
        // just past the pixel's clip end (within the refinement
        // tolerance) would otherwise be refined to a point inside it.
        let (ca, cb) = (ta.max(pt0), tb.min(pt1));
        let bracket = (ca < cb).then(|| {
            brackets.push(Bracket {
                ray: tile.ray(k),
                a: ca,
                b: cb,
            });
            brackets.len() - 1
        });
        pixels.push((k, (pt0, pt1), bracket));
    }
    let hits = refine_batch(tr, &mut scratch, live, &mut st.stats);
    tile.refine = scratch;
    for (k, (pt0, pt1), bracket) in pixels {
        tile.hits[k] = match bracket.and_then(|i| hits[i]) {
            Some(h) if h.t >= pt0 && h.t <= pt1 => Some(h),
            // The root lies outside this pixel's own clip range (only
            // at the bounds' edges), or rounding hid the bracket's sign
            // change: this pixel gets a full ray.
            _ => {
                tile.class[k] = Class::Ray;
                let ray = tile.ray(k);
                trace_ray(tr, &ray, pt0, pt1, live, st)
            }
        };
    }
    tile.included.push(b);
}

/// Settles every pixel of `b` as a miss of class `c`.
pub(crate) fn set_block(tile: &mut TileRays, b: Rect, c: Class) {
    for (i, j) in b.pixels() {
        let k = tile.idx(i, j);
        tile.hits[k] = None;
        tile.class[k] = c;
    }
}
