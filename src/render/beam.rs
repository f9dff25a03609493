//! Beams: blocks of pixels traced together with interval hulls.
//!
//! A block's rays form a beam; its hull over a ray-parameter interval T is
//! exact up to rounding ([`super::camera`]). The block's T range (the union
//! of its pixels' slab ranges) is bisected front to back down to a width
//! comparable with the block's footprint; pieces where every live object is
//! strictly positive are rejected. If all of T is rejected the block is
//! background and no ray is traced. Otherwise, with [t0, ta] rejected, the
//! inclusion test checks F over the hull of the block's points at t = ta
//! (strictly positive) and at some tb > ta (strictly negative), and that
//! F is strictly decreasing along every ray over the beam piece [ta, tb]
//! (interval gradient · direction < 0): every ray then has exactly one
//! root in [ta, tb], its first, and each pixel only refines that bracket
//! on the point evaluator. Blocks that are neither split in four,
//! keeping the rejected prefix and dropping objects proven positive over
//! the whole remaining beam; single pixels get a guaranteed single ray
//! ([`super::ray`]).
//!
//! A block whose rays' start points (each at its own clip start) all lie
//! where F < 0 is settled at once: every ray hits at its start (cut-away
//! faces, filled 2D masks). Over a block, an object's interval that
//! straddles 0 is tightened by the mean-value form
//! (`Tracer::interval_tight`), which pays off on the small hulls near a
//! surface, where the natural extension overestimates most.

use super::camera::{CornerRays, PixelRay};
use super::ray::{refine, scene_point, trace_ray};
use super::{Class, Hit, Tracer};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_hull, dot, ray_box};
use crate::render::stats::RenderStats;

// Rejection pieces per sweep before the block is declared undecided.
const MAX_SWEEP_PIECES: usize = 256;

/// The front-to-back rejection sweep of a beam over `[t0, t1]`, shared by
/// the tracer and anti-aliasing: bisects nearest half first, drops every
/// piece `excluded` proves free of surface, and returns the first piece it
/// cannot drop once that piece is narrower than `min_w(start)` (or after
/// [`MAX_SWEEP_PIECES`] pieces); `None` when the whole range is dropped.
pub(crate) fn first_candidate(
    t0: f64,
    t1: f64,
    min_w: impl Fn(f64) -> f64,
    mut excluded: impl FnMut(Interval) -> bool,
) -> Option<(f64, f64)> {
    let mut stack = vec![(t0, t1)];
    let mut pieces = 0usize;
    while let Some((a, c)) = stack.pop() {
        pieces += 1;
        if excluded(Interval::new(a, c)) {
            continue;
        }
        if c - a <= min_w(a) || pieces >= MAX_SWEEP_PIECES {
            return Some((a, c));
        }
        let m = 0.5 * (a + c);
        stack.push((m, c));
        stack.push((a, m));
    }
    None
}

/// The per-pixel data of one tile.
pub(crate) struct TileRays {
    /// Left column of the tile.
    pub x0: u32,
    /// Top row of the tile.
    pub y0: u32,
    /// Tile width in pixels.
    pub w: u32,
    /// Per-pixel rays, row-major within the tile.
    pub rays: Vec<PixelRay>,
    /// Per-pixel slab ranges (None: the ray misses the bounds).
    pub slabs: Vec<Option<(f64, f64)>>,
    /// Per-pixel results.
    pub hits: Vec<Option<Hit>>,
    /// How each pixel was decided.
    pub class: Vec<Class>,
    /// Included blocks (x0, y0, x1, y1 in tile coordinates), for shadow beams.
    pub included: Vec<(u32, u32, u32, u32)>,
}

impl TileRays {
    fn idx(&self, i: u32, j: u32) -> usize {
        (j * self.w + i) as usize
    }
}

/// A block of pixels in tile coordinates, half-open.
#[derive(Copy, Clone, Debug)]
struct Block {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// Traces every pixel of the tile with beams.
pub(crate) fn trace_tile(tr: &Tracer<'_>, tile: &mut TileRays, h: u32, st: &mut RenderStats) {
    let live: Vec<u32> = (0..tr.evals.len() as u32).collect();
    let b = Block {
        x0: 0,
        y0: 0,
        x1: tile.w,
        y1: h,
    };
    block(tr, tile, b, 0.0, &live, st);
}

fn block(
    tr: &Tracer<'_>,
    tile: &mut TileRays,
    b: Block,
    t_floor: f64,
    live: &[u32],
    st: &mut RenderStats,
) {
    // The block's T range from its pixels' slabs.
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for j in b.y0..b.y1 {
        for i in b.x0..b.x1 {
            if let Some((a, c)) = tile.slabs[tile.idx(i, j)] {
                t0 = t0.min(a);
                t1 = t1.max(c);
            }
        }
    }
    let single = b.x1 - b.x0 == 1 && b.y1 - b.y0 == 1;
    t0 = t0.max(t_floor);
    if t0.partial_cmp(&t1).is_none_or(|o| o.is_gt()) || live.is_empty() {
        if !single {
            st.blocks_rejected += 1;
        }
        set_block(tile, b, Class::Background);
        return;
    }
    if single {
        let k = tile.idx(b.x0, b.y0);
        let (pt0, pt1) = tile.slabs[k].unwrap_or((t0, t1));
        let ray = tile.rays[k];
        // The ray starts at its own clip start, not at the block's rejected
        // prefix: the bisection pieces, and so the tangency decisions of
        // the first-root policy, are then those of `Method::Pixel`, and
        // both methods draw the same pixels. Re-rejecting the prefix costs
        // a few interval evaluations.
        tile.hits[k] = trace_ray(tr, &ray, pt0, pt1, live, st);
        tile.class[k] = Class::Ray;
        return;
    }
    if t_floor <= t0 && all_start_inside(tr, tile, b, live, st) {
        st.blocks_included += 1;
        return;
    }
    // Screen extents of the pixel centres.
    let xs = ((b.x0 + tile.x0) as f64 + 0.5, (b.x1 + tile.x0) as f64 - 0.5);
    let ys = ((b.y0 + tile.y0) as f64 + 0.5, (b.y1 + tile.y0) as f64 - 0.5);
    let side_px = (b.x1 - b.x0).max(b.y1 - b.y0);
    let side = f64::from(side_px);
    let level = side_px.ilog2() as usize;
    let min_w = |t: f64| side * tr.cam.spacing(t).max(1e-9);
    let corners = tr.cam.corners(xs, ys);
    let eval_min = |t: Interval, st: &mut RenderStats| -> Interval {
        let hb = corners.hull(t);
        let mut f = Interval::point(f64::INFINITY);
        for &k in live {
            let v = tr.interval_tight(k as usize, hb, level, st);
            if v.is_empty() {
                continue;
            }
            f = f.min(v);
        }
        f
    };
    if tr.flat {
        // f is constant along the rays: bisecting T cannot help.
        if eval_min(Interval::new(t0, t1), st).lo > 0.0 {
            st.blocks_rejected += 1;
            set_block(tile, b, Class::Background);
        } else {
            st.blocks_undecided += 1;
            // The tile already pruned to its beam over the whole depth; a
            // flat block's sub-blocks gain little from pruning again, and
            // it costs an interval pass and a rebuild per block (prospero
            // at 1024² measured no faster with it).
            split(tr, tile, b, t0, live, st);
        }
        return;
    }
    // Front-to-back rejection sweep.
    let found = first_candidate(t0, t1, min_w, |t| eval_min(t, st).lo > 0.0);
    let Some((ta, tb)) = found else {
        st.blocks_rejected += 1;
        set_block(tile, b, Class::Background);
        return;
    };
    // Inclusion test: positive at ta, negative at some tb' ahead.
    let fa = eval_min(Interval::point(ta), st);
    if fa.lo > 0.0 {
        let w = (tb - ta).max(min_w(ta));
        for mult in [1.0, 2.0, 4.0] {
            let tb2 = (ta + mult * w).min(t1);
            let fb = eval_min(Interval::point(tb2), st);
            if fb.hi < 0.0 {
                if decreasing(tr, &corners, Interval::new(ta, tb2), live, st) {
                    st.blocks_included += 1;
                    include_block(tr, tile, b, ta, tb2, live, st);
                    return;
                }
                break;
            }
            if tb2 >= t1 {
                break;
            }
        }
    }
    st.blocks_undecided += 1;
    // Objects positive over the whole remaining beam are dropped below.
    let rest = corners.hull(Interval::new(ta, t1));
    let sub_live: Vec<u32> = live
        .iter()
        .copied()
        .filter(|&k| {
            let v = tr.interval(k as usize, rest, st);
            !(v.is_empty() || v.lo > 0.0)
        })
        .collect();
    // The sub-blocks work near the first candidate piece: prune there.
    let window = Interval::new(ta, t1.min(ta + PRUNE_WINDOW * (tb - ta).max(min_w(ta))));
    split_pruned(tr, tile, b, (xs, ys, window), ta, &sub_live, st);
}

// Width of the window a split block prunes its functions to, in units of
// its first candidate piece: its sub-blocks and rays evaluate mostly there
// (evaluations outside it use the unpruned functions, see
// `crate::eval::regional`).
const PRUNE_WINDOW: f64 = 8.0;

// `split`, with the functions first pruned to the block's beam over
// `window` (screen extents of its pixel centres) where that shrinks them
// enough (see `super::prune_evals`).
fn split_pruned(
    tr: &Tracer<'_>,
    tile: &mut TileRays,
    b: Block,
    (xs, ys, window): ((f64, f64), (f64, f64), Interval),
    t_floor: f64,
    live: &[u32],
    st: &mut RenderStats,
) {
    let pruned = super::beam_region(tr, xs, ys, window)
        .and_then(|region| super::prune_evals(tr, region, st));
    match pruned {
        Some((evals, live_ops)) => {
            let local = tr.with_evals(&evals, live_ops);
            split(&local, tile, b, t_floor, live, st);
        }
        None => split(tr, tile, b, t_floor, live, st),
    }
}

// Traces the four quarters of a block.
fn split(
    tr: &Tracer<'_>,
    tile: &mut TileRays,
    b: Block,
    t_floor: f64,
    live: &[u32],
    st: &mut RenderStats,
) {
    let mx = (b.x0 + b.x1).div_ceil(2);
    let my = (b.y0 + b.y1).div_ceil(2);
    for (x0, x1) in [(b.x0, mx), (mx, b.x1)] {
        for (y0, y1) in [(b.y0, my), (my, b.y1)] {
            if x0 < x1 && y0 < y1 {
                block(tr, tile, Block { x0, y0, x1, y1 }, t_floor, live, st);
            }
        }
    }
}

// Whether the scene function is strictly decreasing along every ray of the
// block over T: every live object that may be ≤ 0 on the beam piece has
// ∇F · d < 0 there (d over the block's directions, the hull of the corner
// directions since d is affine in screen position). Objects positive on
// the piece do not change where the minimum vanishes, and a minimum of
// strictly decreasing functions is strictly decreasing; so with a sign
// change over T each ray has exactly one root there, and the refinement
// converges to the first root, not a later one.
fn decreasing(
    tr: &Tracer<'_>,
    corners: &CornerRays,
    t: Interval,
    live: &[u32],
    st: &mut RenderStats,
) -> bool {
    let hb = corners.hull(t);
    let c = &corners.0;
    let dirs = box_hull(box_hull(c[0].1, c[1].1), box_hull(c[2].1, c[3].1));
    live.iter().all(|&k| {
        let f = tr.interval(k as usize, hb, st);
        if f.is_empty() || f.lo > 0.0 {
            return true;
        }
        let g = tr.interval_grad(k as usize, hb, st);
        let dfdt = dot(&g.d, &dirs);
        dfdt.hi < 0.0
    })
}

// Whether every ray of the block starts inside a solid, proven by F < 0
// over the hull of the rays' start points (each at its own clip start);
// if so, records the hits. Agrees with the point test of single rays.
fn all_start_inside(
    tr: &Tracer<'_>,
    tile: &mut TileRays,
    b: Block,
    live: &[u32],
    st: &mut RenderStats,
) -> bool {
    let mut hull: Option<IBox> = None;
    for j in b.y0..b.y1 {
        for i in b.x0..b.x1 {
            let k = tile.idx(i, j);
            if let Some((pt0, _)) = tile.slabs[k] {
                let r = &tile.rays[k];
                let p = ray_box(r.o, r.d, Interval::point(pt0));
                hull = Some(hull.map_or(p, |h| box_hull(h, p)));
            }
        }
    }
    let Some(hull) = hull else {
        return false;
    };
    // The smallest object value must be negative: one object negative
    // over the whole hull suffices.
    let mut inside_obj = None;
    for &k in live {
        let v = tr.interval(k as usize, hull, st);
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
    for j in b.y0..b.y1 {
        for i in b.x0..b.x1 {
            let k = tile.idx(i, j);
            if let Some((pt0, _)) = tile.slabs[k] {
                let (v, obj) = scene_point(tr, live, tile.rays[k].at(pt0), st);
                // NaN (undefined) is not inside.
                if v.is_nan() || v >= 0.0 {
                    return false;
                }
                starts.push((k, pt0, obj));
            }
        }
    }
    for j in b.y0..b.y1 {
        for i in b.x0..b.x1 {
            let k = tile.idx(i, j);
            tile.class[k] = Class::Included;
            tile.hits[k] = None;
        }
    }
    for (k, t, obj) in starts {
        tile.hits[k] = Some(Hit {
            t,
            obj,
            inside: true,
        });
    }
    true
}

// Every ray of the block has its first root in [ta, tb]: refine per pixel.
fn include_block(
    tr: &Tracer<'_>,
    tile: &mut TileRays,
    b: Block,
    ta: f64,
    tb: f64,
    live: &[u32],
    st: &mut RenderStats,
) {
    for j in b.y0..b.y1 {
        for i in b.x0..b.x1 {
            let k = tile.idx(i, j);
            let ray = tile.rays[k];
            tile.class[k] = Class::Included;
            let Some((pt0, pt1)) = tile.slabs[k] else {
                tile.hits[k] = None;
                continue;
            };
            st.pixels_refined += 1;
            // The bracket is clipped to the pixel's own range first: a root
            // just past the pixel's clip end (within the refinement
            // tolerance) would otherwise be refined to a point inside it.
            let (ca, cb) = (ta.max(pt0), tb.min(pt1));
            let hit = if ca < cb {
                refine(tr, &ray, live, ca, cb, st)
            } else {
                None
            };
            tile.hits[k] = match hit {
                Some(h) if h.t >= pt0 && h.t <= pt1 => Some(h),
                // The root lies outside this pixel's own clip range (only
                // at the bounds' edges), or rounding hid the bracket's sign
                // change: this pixel gets a full ray.
                _ => {
                    tile.class[k] = Class::Ray;
                    trace_ray(tr, &ray, pt0, pt1, live, st)
                }
            };
        }
    }
    tile.included.push((b.x0, b.y0, b.x1, b.y1));
}

fn set_block(tile: &mut TileRays, b: Block, c: Class) {
    for j in b.y0..b.y1 {
        for i in b.x0..b.x1 {
            let k = tile.idx(i, j);
            tile.hits[k] = None;
            tile.class[k] = c;
        }
    }
}
