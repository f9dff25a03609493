//! Flat scenes (2D models seen along their missing axis): a quadtree of
//! screen rectangles, with no search along the rays. Each level's
//! rectangles take one interval batch per object over their beams;
//! rejected ones are background, proven-positive objects are dropped (and
//! tapes pruned) for the quarters, and the pixels left open are settled in
//! point and interval batches, with a single ray only where both leave
//! them open. The same pixels as `Method::Pixel` (`tests/flat_scenes.rs`);
//! `docs/tracer.md` says why.

use super::beam::{TileRays, clear_boxes, set_block};
use super::probe::Rect;
use super::ray::trace_ray;
use super::refine::scene_points;
use crate::interval::Interval;
use crate::interval::boxes::{IBox, ray_box};
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::view::camera::{PixelRay, RayGrid};
use crate::render::{Class, Hit};

/// Rectangles of at most this many pixels are finished without pruning
/// (`small`): a 32×32 tile's quarters. Pruning them too, four in one
/// pass over the tile's tape, cost more than their shorter tapes saved
/// (prospero at 1024², one thread: 53.3 against 54.8 ms of tracing, the
/// same images), as pruning 8×8 blocks did before (63 ms).
const SMALL_PIXELS: u32 = 256;

/// Rectangles of at most this many pixels that their interval leaves open
/// are settled pixel by pixel, with no interval per pixel first.
const DIRECT_PIXELS: u32 = 4;

// What every rectangle of one tile reads: the terms its beams are summed
// from, and a table of how many of its pixels' rays meet the bounds.
struct Plane<'g> {
    // Per column of the tile, the ray origins' term `o0 + X·ox`; per row,
    // `Y·oy` (a pixel's origin is their sum, `camera::RayGrid`); and
    // `T·d`, with d the direction every ray shares (a flat scene's camera
    // is parallel) and T the tile's range of the ray parameter
    // (`TileRays::depths`, which the tile's functions are pruned to), so
    // that every rectangle's beam lies inside the tile's.
    columns: &'g [IBox],
    rows: &'g [IBox],
    along: IBox,
    // `count[j * (w + 1) + i]`: pixels with a clip range among the first
    // `j` rows and `i` columns; `None` where the tile holds no clip ranges
    // (then every rectangle may meet the bounds, and `settle` checks each
    // pixel).
    count: Option<Vec<u32>>,
    w: u32,
}

impl<'g> Plane<'g> {
    fn new(tr: &Scope<'_>, tile: &TileRays, grid: &'g RayGrid) -> Option<Plane<'g>> {
        let (w, h) = (tile.w, tile.h);
        let t = tile.depths(tr)?;
        let d = grid.shared_direction()?;
        let count = (!tile.slabs.is_empty()).then(|| {
            let stride = (w + 1) as usize;
            let mut count = vec![0u32; stride * (h as usize + 1)];
            for j in 0..h as usize {
                let mut row = 0;
                for i in 0..w as usize {
                    row += u32::from(tile.slabs[j * w as usize + i].is_some());
                    count[(j + 1) * stride + i + 1] = count[j * stride + i + 1] + row;
                }
            }
            count
        });
        Some(Plane {
            columns: grid.origin_columns(),
            rows: grid.origin_rows(),
            along: std::array::from_fn(|k| t.mul(d[k])),
            count,
            w,
        })
    }

    // Whether some pixel of `r` may have a ray that meets the bounds.
    fn may_meet_bounds(&self, r: Rect) -> bool {
        let Some(count) = &self.count else {
            return true;
        };
        let s = (self.w + 1) as usize;
        let at = |i: u32, j: u32| count[j as usize * s + i as usize];
        at(r.x1, r.y1) + at(r.x0, r.y0) > at(r.x0, r.y1) + at(r.x1, r.y0)
    }

    // A box holding every point of `r`'s rays over the tile's T range:
    // each axis's column and row terms are monotone in the pixel's
    // position, so the hull of the first and last column's (row's) holds
    // them all, and interval sums and products hold every sum and product
    // of their members (each pixel's ray box over its own range lies
    // inside).
    fn beam(&self, r: Rect) -> IBox {
        let span = |v: &[IBox], a: u32, b: u32, k: usize| {
            let (p, q) = (v[a as usize][k], v[b as usize - 1][k]);
            Interval::new(p.lo.min(q.lo), p.hi.max(q.hi))
        };
        std::array::from_fn(|k| {
            span(self.columns, r.x0, r.x1, k)
                .add(span(self.rows, r.y0, r.y1, k))
                .add(self.along[k])
        })
    }
}

/// Traces every pixel of a tile of a flat scene (`tr.ctx.flat`), `h` rows
/// high.
pub(crate) fn trace_tile(tr: &Scope<'_>, tile: &mut TileRays, h: u32, st: &mut TileState) {
    debug_assert!(tr.ctx.flat, "only flat scenes skip the search along rays");
    debug_assert_eq!(h, tile.h);
    // The plane borrows the tile's ray terms while the tile's results are
    // written: a copy of the grid keeps the two apart.
    let grid = tile.grid.clone();
    let Some(plane) = Plane::new(tr, tile, &grid) else {
        return;
    };
    let live: Vec<u32> = (0..tr.ctx.evals.len() as u32).collect();
    // A tile reaches here only where its group, or its own interval,
    // did not prove it empty: it is not tested as a whole, which would
    // seldom decide it (a tile wholly inside a solid: its parts say the
    // same). Where its quarters are small, they are not tested either:
    // `small` tests their quarters first, all in one batch (prospero at
    // 1024², one thread: tracing 55.8 → 53.9 ms, the same images).
    let whole = tile.whole();
    let top: Vec<Rect> = if whole.pixel_count() > SMALL_PIXELS {
        whole.quarters_by_column().collect()
    } else {
        vec![whole]
    };
    if top.iter().all(|q| q.pixel_count() <= SMALL_PIXELS) {
        let untested: Vec<(Rect, bool)> = (top.into_iter())
            .filter(|&q| plane.may_meet_bounds(q))
            .map(|q| (q, false))
            .collect();
        if !untested.is_empty() {
            small(tr, tile, &plane, &untested, &live, st);
        }
        return;
    }
    level(tr, tile, &plane, &top, &live, st);
}

// Decides the rectangles `rects` (the quarters of one rectangle, or the
// whole tile) over the objects `live`.
fn level(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    plane: &Plane,
    rects: &[Rect],
    live: &[u32],
    st: &mut TileState,
) {
    let boxes: Vec<IBox> = rects.iter().map(|&r| plane.beam(r)).collect();
    // Per rectangle: the objects not proven positive, and whether one is
    // proven negative.
    let mut sub_live: Vec<Vec<u32>> = vec![Vec::new(); rects.len()];
    let mut negative = vec![false; rects.len()];
    let mut f = vec![Interval::point(0.0); rects.len()];
    for &k in live {
        tr.ctx.evals[k as usize].interval_batch(&boxes, &mut f);
        for (r, v) in f.iter().enumerate() {
            if !crate::render::enclose::proof::holds_no_surface(*v) {
                sub_live[r].push(k);
                negative[r] |= v.hi < 0.0;
            }
        }
    }
    st.stats.interval_evals += (rects.len() * live.len()) as u64;
    // The small and the proven-negative rectangles, finished together on
    // these functions (`small`), and the objects any of them needs.
    let mut finish: Vec<(Rect, bool)> = Vec::new();
    let mut finish_live: Vec<u32> = Vec::new();
    // The rectangles split further, whose regions are pruned together.
    let mut split: Vec<(usize, Option<IBox>)> = Vec::new();
    for (r, &rect) in rects.iter().enumerate() {
        if !plane.may_meet_bounds(rect) {
            // Every ray misses the bounds: `visibility` marks them.
            continue;
        }
        let live = &sub_live[r];
        let pixels = rect.pixel_count();
        if live.is_empty() {
            st.stats.blocks_rejected += u64::from(pixels > 1);
            set_block(tile, rect, Class::Background);
        } else if negative[r] || pixels <= SMALL_PIXELS {
            finish.push((rect, negative[r]));
            finish_live.extend(live);
        } else {
            st.stats.blocks_undecided += 1;
            // The whole tile's functions are already pruned to its beam.
            let region = (!tile.is_whole(rect))
                .then(|| tr.ctx.region_around(boxes[r]))
                .flatten();
            split.push((r, region));
        }
    }
    let regions: Vec<IBox> = split.iter().filter_map(|&(_, g)| g).collect();
    let mut pruned = tr.pruned_to_batch(&regions, st).into_iter();
    for (r, region) in split {
        let quarters: Vec<Rect> = rects[r].quarters_by_column().collect();
        let live = &sub_live[r];
        match region.and_then(|_| pruned.next()).flatten() {
            Some(set) => {
                let local = tr.with_evals(&set);
                level(&local, tile, plane, &quarters, live, st);
            }
            None => level(tr, tile, plane, &quarters, live, st),
        }
    }
    if !finish.is_empty() {
        finish_live.sort_unstable();
        finish_live.dedup();
        small(tr, tile, plane, &finish, &finish_live, st);
    }
}

// Rectangles of at most `SMALL_PIXELS` pixels that their intervals did
// not reject (or that were not tested), or proven negative
// (`(rectangle, negative)`): the others'
// quarters, theirs and so on down to single pixels are tested level by
// level, each level of all of them in one interval batch per object, on
// the functions `tr` holds (pruning again would cost more than it saves
// this close to the pixels); the pixels no rectangle rejects are then
// settled together (`settle`). `live` holds every object any of them
// needs: an object proven positive over a rectangle stays positive over
// its parts, and a positive value is never a start point's least.
fn small(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    plane: &Plane,
    rects: &[(Rect, bool)],
    live: &[u32],
    st: &mut TileState,
) {
    // (pixel, whether a rectangle of several pixels was proven negative
    // over it)
    let mut open: Vec<(usize, bool)> = Vec::new();
    let add = |tile: &TileRays, r: Rect, neg: bool, open: &mut Vec<(usize, bool)>| {
        let several = r.x1 - r.x0 > 1 || r.y1 - r.y0 > 1;
        open.extend(r.pixels().map(|(i, j)| (tile.idx(i, j), neg && several)));
    };
    let mut level: Vec<Rect> = Vec::new();
    for &(rect, negative) in rects {
        st.stats.blocks_undecided += 1;
        if negative {
            st.stats.blocks_included += 1;
            add(tile, rect, true, &mut open);
        } else {
            level.extend(rect.quarters_by_column());
        }
    }
    let mut f = Vec::new();
    let mut keep = Vec::new();
    let mut neg = Vec::new();
    while !level.is_empty() {
        let boxes: Vec<IBox> = level.iter().map(|&r| plane.beam(r)).collect();
        f.clear();
        f.resize(level.len(), Interval::point(0.0));
        keep.clear();
        keep.resize(level.len(), false);
        neg.clear();
        neg.resize(level.len(), false);
        for &k in live {
            tr.ctx.evals[k as usize].interval_batch(&boxes, &mut f);
            for (r, v) in f.iter().enumerate() {
                if !crate::render::enclose::proof::holds_no_surface(*v) {
                    keep[r] = true;
                    neg[r] |= v.hi < 0.0;
                }
            }
        }
        st.stats.interval_evals += (level.len() * live.len()) as u64;
        let mut next = Vec::new();
        for (r, &q) in level.iter().enumerate() {
            let single = q.is_pixel();
            if !plane.may_meet_bounds(q) {
                continue;
            }
            if !keep[r] {
                st.stats.blocks_rejected += u64::from(!single);
                set_block(tile, q, Class::Background);
            } else if neg[r] || single {
                add(tile, q, neg[r], &mut open);
            } else if q.pixel_count() <= DIRECT_PIXELS {
                // Its pixels' own tests (`settle`) cost less than a
                // level of single-pixel intervals before them, which
                // those that start inside would repeat as points.
                add(tile, q, false, &mut open);
            } else {
                next.extend(q.quarters_by_column());
            }
        }
        level = next;
    }
    settle(tr, tile, &open, live, st);
}

// Settles the pixels `open` (tile indices, each with whether a rectangle
// of several pixels was proven negative over it) one by one, in batches:
// hits at their start points, rays proven empty, and single rays for the
// rest.
fn settle(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    open: &[(usize, bool)],
    live: &[u32],
    st: &mut TileState,
) {
    // (pixel, its clip range, its ray): a flat tile builds its pixels'
    // rays from their terms (`TileRays::ray`), once each here.
    let mut px: Vec<(usize, (f64, f64), PixelRay)> = Vec::with_capacity(open.len());
    let mut starts: Vec<[f64; 3]> = Vec::with_capacity(open.len());
    for &(k, included) in open {
        tile.hits[k] = None;
        tile.class[k] = if included {
            Class::Included
        } else {
            Class::Ray
        };
        if let (ray, Some(range)) = tile.ray_and_slab(k, &tr.ctx.bounds) {
            px.push((k, range, ray));
            starts.push(ray.at(range.0));
        }
    }
    let best = scene_points(tr, live, &starts, &mut st.stats);
    let mut rest = Vec::new();
    for (&(k, (t0, t1), ray), &(v, obj)) in px.iter().zip(&best) {
        if v < 0.0 {
            st.stats.pixels_batched += 1;
            tile.hits[k] = Some(Hit {
                t: t0,
                obj,
                inside: true,
                grad: None,
                front: None,
            });
        } else {
            rest.push((k, (t0, t1), ray));
        }
    }
    if rest.is_empty() {
        return;
    }
    let boxes: Vec<IBox> = rest
        .iter()
        .map(|(_, (t0, t1), r)| ray_box(r.o, r.d, Interval::new(*t0, *t1)))
        .collect();
    let clear = clear_boxes(tr, &boxes, live, st);
    for (&(k, (t0, t1), ray), clear) in rest.iter().zip(clear) {
        if clear {
            st.stats.pixels_batched += 1;
            // What a single pixel's rectangle proves (see `small`).
            if tile.class[k] == Class::Ray {
                tile.class[k] = Class::Background;
            }
        } else {
            tile.class[k] = Class::Ray;
            tile.hits[k] = trace_ray(tr, &ray, t0, t1, live, st);
        }
    }
}
