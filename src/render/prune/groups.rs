//! Evaluators pruned to groups of tiles, shared by the tiles of a group.
//!
//! Every tile prunes its functions to its own beam (`Scope::pruned_to_beam`).
//! From the whole function that costs one interval pass over all of it per
//! tile: for a model of thousands of ops, the largest single cost of a
//! render (8 M ops pruned for prospero at 1024², 1024 tiles of 8k ops).
//! So tiles prune from the tape of their group instead: a square of
//! [`GROUP_TILES`]² tiles whose beam over the bounds is pruned once, the
//! first time one of its tiles asks, by whichever thread asks first. The
//! group's tape depends only on its region, so the images and counters do
//! not depend on the thread count.
//!
//! In 3D the group's beam is a tree of regions along the rays, like a
//! tile's (see `render::slices`), halved down to slices about as deep as
//! the group is wide. Over a long beam nearly every object's interval
//! overlaps the nearest one's, so pruning a tile's whole beam, or its
//! halves, kept nearly all of the group's tape and cost as much as an
//! evaluation of it: those regions of a tile now share the group's tape,
//! and the tile's shorter slices prune from the group's slice holding them
//! (1000 spheres at 1024²: 107 M ops pruned, now 61 M, for the same image).
//!
//! A streamed render drops the groups above the rows it has finished, so
//! memory holds one row of groups, not the image's.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock, TryLockError};

use crate::eval::regional::Regional;
use crate::eval::tape::Tape;
use crate::interval::Interval;
use crate::interval::boxes::IBox;
use crate::render::TILE;
use crate::render::context::EvalSet;
use crate::render::context::PRUNE_MIN_OPS;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::view::camera::CornerRays;

/// Tiles along each side of a group.
pub(crate) const GROUP_TILES: u32 = 4;
/// Side of a group in pixels.
const GROUP_SIDE: u32 = GROUP_TILES * TILE;

/// One group's pruned evaluators (`None`: nothing prunes there), the
/// region where they have the whole function's signs, which of its tiles (row-major,
/// [`GROUP_TILES`] a row) they prove empty (see [`empty_tiles`]), and, in
/// a flat scene, its other tiles' tapes (see [`TileTapes`]).
type Group = Option<(EvalSet, IBox, Vec<bool>, Vec<Option<Arc<TileTapes>>>)>;

/// A tile's tapes pruned from its group's when the group is built, all
/// the group's tiles in one pass over each of its tapes
/// (`Tape::prune_batch`), where each tile's own pass cost as much as a
/// third of a flat scene's render (prospero). Only in flat scenes, whose
/// tiles' regions are one box each that the group computes as the tile
/// does (`TileRays::depths` of a tile with no pixel rays).
#[derive(Clone, Debug)]
pub(crate) struct TileTapes {
    /// The region the tapes are pruned to: the tile's beam region.
    pub region: IBox,
    /// Per object: the address of the tape pruned (a tile takes the
    /// result only in place of pruning that very tape) and the result
    /// (`None`: no `min`/`max` decided there); `None` where the group
    /// holds no tape of the object.
    pub tapes: Vec<Option<PrunedAhead>>,
}

/// The address of a tape and the tape it prunes to over a region (`None`:
/// no `min`/`max` decided there).
pub(crate) type PrunedAhead = (usize, Option<Tape>);

/// A group's slot, filled once by the first tile that asks.
type Slot = Arc<OnceLock<Group>>;

/// The groups of one camera's image, built as tiles ask for them.
#[derive(Default)]
pub(crate) struct TileGroups {
    groups: Mutex<HashMap<(u32, u32), Slot>>,
    // In a flat scene, per row of groups: each group's tapes, the row's
    // groups pruned from the whole functions in one batch by the first
    // group of the row built (`row_tapes`).
    rows: Mutex<HashMap<u32, RowSlot>>,
}

/// A row of groups' tapes (see [`row_tapes`]), pruned once by the first
/// group of the row built.
type RowSlot = Arc<Mutex<Option<RowTapes>>>;

/// Each group's [`TileTapes`] in a row of groups.
type RowTapes = Arc<Vec<Option<TileTapes>>>;

impl TileGroups {
    /// The evaluators of the group holding the pixel `(x, y)` and the
    /// region where they have the whole function's signs, built now if no tile has asked yet;
    /// `None` when nothing prunes there.
    pub(crate) fn of_pixel(
        &self,
        tr: &Scope<'_>,
        (x, y): (u32, u32),
        st: &mut TileState,
    ) -> Option<(EvalSet, IBox, Option<Arc<TileTapes>>)> {
        let slot = self.built(tr, (x / GROUP_SIDE, y / GROUP_SIDE), st);
        let group = slot.get().and_then(Option::as_ref);
        group.map(|(evals, region, _, tiles)| {
            let at = tile_slot(x, y);
            (evals.clone(), *region, tiles.get(at).cloned().flatten())
        })
    }

    // The slot of group `key`, built now if no tile has asked yet (outside
    // the map's lock: tiles of other groups go on).
    fn built(&self, tr: &Scope<'_>, key: (u32, u32), st: &mut TileState) -> Slot {
        let slot = {
            let mut map = self.groups.lock().unwrap_or_else(|e| e.into_inner());
            Arc::clone(map.entry(key).or_default())
        };
        slot.get_or_init(|| {
            let row = tr.ctx.flat.then(|| self.row(tr, key.1, st)).flatten();
            let pre = row.as_ref().and_then(|r| r.get(key.0 as usize)?.as_ref());
            build(tr, key, pre, st)
        });
        slot
    }

    // The tapes of row `gy`'s groups, pruned now if no group of the row
    // has been built yet; `None` while another thread prunes them: the
    // group then prunes its own rather than wait (the same tapes).
    fn row(&self, tr: &Scope<'_>, gy: u32, st: &mut TileState) -> Option<RowTapes> {
        let slot = {
            let mut map = self.rows.lock().unwrap_or_else(|e| e.into_inner());
            Arc::clone(map.entry(gy).or_default())
        };
        let mut row = match slot.try_lock() {
            Ok(row) => row,
            Err(TryLockError::WouldBlock) => return None,
            Err(TryLockError::Poisoned(e)) => e.into_inner(),
        };
        Some(Arc::clone(
            row.get_or_insert_with(|| Arc::new(row_tapes(tr, gy, st))),
        ))
    }

    /// Whether the groups' evaluators prove every object positive or
    /// undefined over the beams of every `TILE`-sized cell of the pixels
    /// `x0..x0 + w` × `y0..y0 + h` (a tile: `TILE` wide, or a multiple of it
    /// when `grid:N` traces a finer image), each over a range of the ray
    /// parameter that holds every one of its pixels' slab ranges (see
    /// [`empty_tiles`]); false where nothing prunes.
    pub(crate) fn tile_is_empty(
        &self,
        tr: &Scope<'_>,
        (x0, y0): (u32, u32),
        (w, h): (u32, u32),
        st: &mut TileState,
    ) -> bool {
        if w == 0 || h == 0 || x0 % TILE != 0 || y0 % TILE != 0 {
            return false;
        }
        let cells_x = (x0 / TILE)..(x0 + w).div_ceil(TILE);
        let cells_y = (y0 / TILE)..(y0 + h).div_ceil(TILE);
        cells_y.into_iter().all(|cy| {
            cells_x.clone().all(|cx| {
                let (x, y) = (cx * TILE, cy * TILE);
                let slot = self.built(tr, (x / GROUP_SIDE, y / GROUP_SIDE), st);
                let group = slot.get().and_then(Option::as_ref);
                group.is_some_and(|(_, _, empty, _)| empty.get(tile_slot(x, y)) == Some(&true))
            })
        })
    }

    /// Drops the groups that lie wholly above image row `y`.
    pub(crate) fn release_above(&self, y: u32) {
        let mut map = self.groups.lock().unwrap_or_else(|e| e.into_inner());
        map.retain(|&(_, gy), _| (gy + 1) * GROUP_SIDE > y);
        let mut rows = self.rows.lock().unwrap_or_else(|e| e.into_inner());
        rows.retain(|&gy, _| (gy + 1) * GROUP_SIDE > y);
    }
}

// The group `(gx, gy)`'s evaluators: each large function pruned to the
// group's beam over every ray parameter at which its rays can be inside
// the bounds, and to its slices along the rays (see
// `Scope::pruned_group`). A tape that does not shrink enough to answer
// (see `Scope::pruned_to_beam`) is kept to prune the tiles' from.
fn build(
    tr: &Scope<'_>,
    (gx, gy): (u32, u32),
    pre: Option<&TileTapes>,
    st: &mut TileState,
) -> Group {
    let ((x0, y0), (x1, y1)) = group_pixels(tr, (gx, gy));
    let xs = (f64::from(x0) + 0.5, f64::from(x1) - 0.5);
    let ys = (f64::from(y0) + 0.5, f64::from(y1) - 0.5);
    let t = beam_range(tr, xs, ys)?;
    let region = tr.ctx.beam_region(xs, ys, t)?;
    let evals = tr.pruned_group(xs, ys, t, pre, st)?;
    let beams = tile_beams(tr, (x0, y0), (x1, y1));
    let empty = empty_tiles(&evals, &beams, st);
    let tiles = if tr.ctx.flat {
        tile_tapes(tr, &evals, &beams, &empty, st)
    } else {
        Vec::new()
    };
    Some((evals, region, empty, tiles))
}

// The pixels `x0..x1 × y0..y1` of group `(gx, gy)`, as `(x0, y0), (x1,
// y1)`.
fn group_pixels(tr: &Scope<'_>, (gx, gy): (u32, u32)) -> ((u32, u32), (u32, u32)) {
    let (x0, y0) = (gx * GROUP_SIDE, gy * GROUP_SIDE);
    let x1 = (x0 + GROUP_SIDE).min(tr.ctx.cam.width);
    let y1 = (y0 + GROUP_SIDE).min(tr.ctx.cam.height);
    ((x0, y0), (x1, y1))
}

// Per group of row `gy` of a flat scene: the whole functions that
// `Scope::pruned_group` prunes, pruned to the region it prunes the
// group's beam to, the row's groups in one pass over each function's
// tape (pruning each group's from the whole function on its own was a
// sixteenth of prospero's render).
fn row_tapes(tr: &Scope<'_>, gy: u32, st: &mut TileState) -> Vec<Option<TileTapes>> {
    let groups = tr.ctx.cam.width.div_ceil(GROUP_SIDE);
    let mut regions = Vec::with_capacity(groups as usize);
    let mut at = Vec::with_capacity(groups as usize);
    for gx in 0..groups {
        let ((x0, y0), (x1, y1)) = group_pixels(tr, (gx, gy));
        let xs = (f64::from(x0) + 0.5, f64::from(x1) - 0.5);
        let ys = (f64::from(y0) + 0.5, f64::from(y1) - 0.5);
        let corners = tr.ctx.cam.corners(xs, ys);
        if let Some(region) = beam_range(tr, xs, ys).and_then(|t| {
            tr.ctx
                .corner_region(&corners, super::slices::group_reach(t))
        }) {
            regions.push(region);
            at.push(gx as usize);
        }
    }
    let tapes: Vec<Option<&Tape>> = (0..tr.ctx.evals.len())
        .map(|k| {
            tr.pruner.tapes[k]
                .as_deref()
                .filter(|_| tr.ctx.live_ops[k] >= PRUNE_MIN_OPS && tr.ctx.region_of(k).is_none())
        })
        .collect();
    let mut row: Vec<Option<TileTapes>> = vec![None; groups as usize];
    for (gx, pruned) in at.into_iter().zip(pruned_to_each(&tapes, &regions, st)) {
        row[gx] = Some(pruned);
    }
    row
}

// Each of `tapes` (one per object; `None`: not pruned) pruned to each of
// `regions`, one batch per tape (`Tape::prune_batch`): a `TileTapes` per
// region.
fn pruned_to_each(tapes: &[Option<&Tape>], regions: &[IBox], st: &mut TileState) -> Vec<TileTapes> {
    let mut per_object: Vec<Vec<Option<PrunedAhead>>> = tapes
        .iter()
        .map(|tape| match tape {
            Some(tape) if !regions.is_empty() => {
                let from = std::ptr::from_ref(*tape) as usize;
                (tape
                    .prune_batch(regions, usize::MAX, &mut st.prune.workspace)
                    .into_iter())
                .map(|p| Some((from, p.map(|p| p.tape))))
                .collect()
            }
            _ => vec![None; regions.len()],
        })
        .collect();
    (regions.iter().enumerate())
        .map(|(i, &region)| TileTapes {
            region,
            tapes: per_object.iter_mut().map(|o| o[i].take()).collect(),
        })
        .collect()
}

// The slot in its group's per-tile vectors of the tile holding pixel
// `(x, y)`.
fn tile_slot(x: u32, y: u32) -> usize {
    ((y % GROUP_SIDE) / TILE * GROUP_TILES + (x % GROUP_SIDE) / TILE) as usize
}

// Per tile of a group (slot as in `empty_tiles`): the group's tapes
// `evals` pruned to the tile's beam region, for the tiles of `beams` not
// proven `empty`; the region is the one `Scope::pruned_to_beam` prunes a
// flat tile with no pixel rays to, and a tile whose region differs
// prunes on its own.
fn tile_tapes(
    tr: &Scope<'_>,
    evals: &EvalSet,
    beams: &[TileBeam],
    empty: &[bool],
    st: &mut TileState,
) -> Vec<Option<Arc<TileTapes>>> {
    let n = (GROUP_TILES * GROUP_TILES) as usize;
    let (at, regions): (Vec<usize>, Vec<IBox>) = (beams.iter())
        .filter(|&&(slot, ..)| !empty[slot])
        .filter_map(|(slot, corners, t)| Some((*slot, tr.ctx.corner_region(corners, *t)?)))
        .unzip();
    let tapes: Vec<Option<&Tape>> = (evals.regions.iter())
        .map(|r| r.as_deref().map(Regional::pruned_tape))
        .collect();
    let mut tiles: Vec<Option<Arc<TileTapes>>> = vec![None; n];
    for (slot, pruned) in at.into_iter().zip(pruned_to_each(&tapes, &regions, st)) {
        tiles[slot] = Some(Arc::new(pruned));
    }
    tiles
}

// Per tile of a group (row-major, `GROUP_TILES` a row; tiles not in
// `beams`, past the image's edge or with every ray missing the bounds,
// stay false): whether the group's evaluators `evals` prove every object
// positive or undefined over the tile's beam over its range in `beams`,
// which holds every pixel's slab range. Every box the tile's tracing would evaluate lies in
// that hull, and interval arithmetic is inclusion-isotone (a tape pruned
// to a region answers inside it within the whole function's interval),
// so the tile would settle every pixel as background: `tile` skips it
// (see `tile::proven_empty`). One interval batch per object over the
// group's tiles: a megapixel's 1024 tiles cost about what 64 single
// tapes' passes do, where pruning each empty tile cost a pass over its
// group's tape, and its rays and shading a pass over its pixels.
fn empty_tiles(evals: &EvalSet, beams: &[TileBeam], st: &mut TileState) -> Vec<bool> {
    let n = (GROUP_TILES * GROUP_TILES) as usize;
    let (at, boxes): (Vec<usize>, Vec<IBox>) = (beams.iter())
        .map(|(slot, corners, t)| (*slot, corners.hull(*t)))
        .unzip();
    let mut empty = vec![false; n];
    if boxes.is_empty() {
        return empty;
    }
    let mut clear = vec![true; boxes.len()];
    let mut f = vec![Interval::point(0.0); boxes.len()];
    for (e, region) in evals.evals.iter().zip(&evals.regions) {
        // A group's own tape, even where it is not short enough to answer
        // for the group (it then delegates to native code of the whole
        // function): one batch over it costs a fraction of the whole
        // function's.
        match region {
            Some(r) => r.own_interval_batch(&boxes, &mut f),
            None => e.interval_batch(&boxes, &mut f),
        }
        for (c, v) in clear.iter_mut().zip(&f) {
            *c &= crate::render::enclose::proof::holds_no_surface(*v);
        }
    }
    st.stats.interval_evals += (boxes.len() * evals.evals.len()) as u64;
    for (&i, c) in at.iter().zip(clear) {
        empty[i] = c;
    }
    empty
}

/// A tile's slot in its group, the corner rays of its beam, and the range
/// of the ray parameter its pixels' slabs lie in (see [`tile_beams`]).
type TileBeam = (usize, CornerRays, Interval);

// Per tile of the group whose pixels span `x0..x1 × y0..y1` whose rays
// meet the bounds (a tile whose rays all miss them is left to the
// tracer): its slot (row-major, `GROUP_TILES` a row), the corner rays of
// its beam, and `CornerRays::slab_range` of them, which holds every
// pixel's slab range.
fn tile_beams(tr: &Scope<'_>, (x0, y0): (u32, u32), (x1, y1): (u32, u32)) -> Vec<TileBeam> {
    let mut beams = Vec::with_capacity((GROUP_TILES * GROUP_TILES) as usize);
    for ty in 0..GROUP_TILES {
        for tx in 0..GROUP_TILES {
            let (tx0, ty0) = (x0 + tx * TILE, y0 + ty * TILE);
            if tx0 >= x1 || ty0 >= y1 {
                continue;
            }
            let xs = (f64::from(tx0) + 0.5, f64::from((tx0 + TILE).min(x1)) - 0.5);
            let ys = (f64::from(ty0) + 0.5, f64::from((ty0 + TILE).min(y1)) - 0.5);
            let corners = tr.ctx.cam.corners(xs, ys);
            if let Some(t) = corners.slab_range(&tr.ctx.bounds) {
                beams.push(((ty * GROUP_TILES + tx) as usize, corners, t));
            }
        }
    }
    beams
}

// `CornerRays::slab_range` of the beam through the pixel centres
// `xs × ys`.
fn beam_range(tr: &Scope<'_>, xs: (f64, f64), ys: (f64, f64)) -> Option<Interval> {
    tr.ctx.cam.corners(xs, ys).slab_range(&tr.ctx.bounds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Projection};

    fn tracer(camera: &Camera, size: u32) -> Scope<'static> {
        Scope::for_tests(camera, size)
    }

    // Every pixel's clipped range lies in its group's range, and every
    // tile's beam region in its group's region, for views from outside,
    // from inside and at a slant, in perspective and parallel: otherwise
    // tiles could not prune from their group.
    #[test]
    fn a_group_holds_the_ranges_and_regions_of_its_pixels_and_tiles() {
        let views = [
            ([0.3, 0.2, 5.0], Projection::Perspective { fov_deg: 50.0 }),
            ([0.1, 0.1, -0.5], Projection::Perspective { fov_deg: 120.0 }),
            ([4.0, 3.0, 2.0], Projection::Orthographic { width: 4.0 }),
            ([0.0, 0.0, 3.0], Projection::Orthographic { width: 2.0 }),
        ];
        let size = 2 * GROUP_SIDE + 40;
        for (eye, projection) in views {
            let camera = Camera {
                eye,
                target: [0.2, 0.1, -0.3],
                up: [0.0, 1.0, 0.0],
                projection,
            };
            let tr = tracer(&camera, size);
            let mut groups_met = 0;
            for gy in 0..size.div_ceil(GROUP_SIDE) {
                for gx in 0..size.div_ceil(GROUP_SIDE) {
                    let (x0, y0) = (gx * GROUP_SIDE, gy * GROUP_SIDE);
                    let (x1, y1) = ((x0 + GROUP_SIDE).min(size), (y0 + GROUP_SIDE).min(size));
                    let centres = |a: u32, b: u32| (f64::from(a) + 0.5, f64::from(b) - 0.5);
                    let range = beam_range(&tr, centres(x0, x1), centres(y0, y1));
                    let rays = tr.ctx.cam.pixel_rays((x0, y0), (x1 - x0, y1 - y0));
                    let slabs: Vec<_> =
                        rays.iter().filter_map(|r| r.slab(&tr.ctx.bounds)).collect();
                    let Some(t) = range else {
                        assert!(slabs.is_empty(), "a group whose rays meet the bounds");
                        continue;
                    };
                    groups_met += 1;
                    for (a, b) in slabs {
                        assert!(t.lo <= a && b <= t.hi, "[{a}, {b}] outside {t:?}");
                    }
                    let region = tr
                        .ctx
                        .beam_region(centres(x0, x1), centres(y0, y1), t)
                        .unwrap();
                    for ty in (y0..y1).step_by(TILE as usize) {
                        for tx in (x0..x1).step_by(TILE as usize) {
                            let (tx1, ty1) = ((tx + TILE).min(x1), (ty + TILE).min(y1));
                            let rays = tr.ctx.cam.pixel_rays((tx, ty), (tx1 - tx, ty1 - ty));
                            let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
                            for (s0, s1) in rays.iter().filter_map(|r| r.slab(&tr.ctx.bounds)) {
                                a = a.min(s0);
                                b = b.max(s1);
                            }
                            if a > b {
                                continue;
                            }
                            let tile = tr
                                .ctx
                                .beam_region(
                                    centres(tx, tx1),
                                    centres(ty, ty1),
                                    Interval::new(a, b),
                                )
                                .unwrap();
                            assert!(
                                crate::interval::boxes::box_within(&tile, &region),
                                "tile ({tx}, {ty}) sticks out of its group"
                            );
                        }
                    }
                }
            }
            assert!(groups_met > 0);
        }
    }

    // A tile's slices halve its beam down to about twice its width, and
    // sweeps cut any range inside it at the slices' ends: the pieces cover
    // the range, nearest last, each inside one slice.
    #[test]
    fn sweeps_start_from_pieces_inside_single_slices() {
        let camera = Camera {
            eye: [0.3, 0.2, 5.0],
            target: [0.2, 0.1, -0.3],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Perspective { fov_deg: 50.0 },
        };
        let tr = tracer(&camera, 256);
        let (xs, ys, t) = ((64.5, 95.5), (32.5, 63.5), Interval::new(3.0, 7.5));
        let ends = tr.slice_ends(xs, ys, t);
        assert!(ends.len() >= 3, "{ends:?}");
        assert!(ends.windows(2).all(|w| w[0] < w[1]) && ends[0] > t.lo);
        let local = tracer(&camera, 256).with_slice_ends(ends.clone());
        let mut rng = crate::ir::random::Rng::new(3);
        for _ in 0..100 {
            let a = rng.range(t.lo, t.hi);
            let b = rng.range(a, t.hi);
            let pieces = local.first_pieces(a, b);
            assert_eq!(pieces.last().map(|p| p.0), Some(a));
            assert_eq!(pieces.first().map(|p| p.1), Some(b));
            for w in pieces.windows(2) {
                assert_eq!(w[0].0, w[1].1, "pieces must meet");
            }
            for (lo, hi) in pieces {
                assert!(
                    !ends.iter().any(|&e| e > lo && e < hi),
                    "[{lo}, {hi}] crosses a slice end"
                );
            }
        }
    }
}
