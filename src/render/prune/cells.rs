//! Evaluators pruned to the cells of a loose octree over the bounds, for
//! a tile's shadow segments.
//!
//! Tiles prune to their own beams (`render::slices`), but a shadow
//! segment leaves its tile's beam at once: it used to run the whole
//! function, and on a union of 1000 spheres that took 40 s of a 256²
//! render. A segment's pieces instead take the evaluators of the smallest
//! cell holding them, each cell pruned once from its parent cell's (per
//! render or per tile, below). A tile's segments start close together and run parallel (or
//! towards one point light), so they meet the same few cells.
//!
//! Level `L` cuts the bounds into `2^L` cells along each axis. A cell's
//! region is the cell widened by half its size on every side, so that any
//! box no wider than a cell lies in the region of the cell holding its
//! centre, and a cell's region lies in its parent's. Levels stop at
//! [`MAX_LEVEL`], and a cell whose parent's functions are all shorter than
//! [`CELL_MIN_OPS`] keeps its parent's.
//!
//! Cells of levels up to [`SHARED_LEVEL`] belong to the render
//! ([`SharedCells`]): each is built once, by the first tile that asks,
//! from its parent cell's tapes or the whole functions, never from the
//! asking scope's, so what it holds depends on the cell alone and the
//! images do not depend on the order the threads asked in. Every tile
//! used to prune its own copies of them from the whole function (3000
//! spheres at 1024²: a quarter of the render). The finer cells belong to
//! the tile (its `TileState`): shared between threads, the cells of a
//! megapixel's segments held about 850 MB of tapes, and a render-wide
//! budget would make which cells exist, and so which tape answers, depend
//! on the order the threads asked in. A tile builds at most
//! [`CELL_TILE_OPS`] ops of tapes, in its own fixed order; past that its
//! pieces take the deepest cell it has.

use std::sync::{Arc, Mutex, OnceLock};

use rustc_hash::FxHashMap;

use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_within};
use crate::render::context::EvalSet;
use crate::render::context::PRUNE_MIN_OPS;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;

/// The finest level of cells.
const MAX_LEVEL: u32 = 5;
/// The finest level of the render's shared cells (at most 16³ of them, 2^L a side).
const SHARED_LEVEL: u32 = 4;
/// Functions shorter than this are not pruned further down the tree.
const CELL_MIN_OPS: usize = 2 * PRUNE_MIN_OPS;
/// The most ops of pruned tapes one tile's cells hold (about 40 bytes an
/// op with its function).
const CELL_TILE_OPS: usize = 1 << 20;

/// A cell: its level and its index along each axis.
type CellKey = (u32, [u32; 3]);

/// A shared cell's slot, filled once by the first tile that asks.
type Slot = Arc<OnceLock<Option<Cell>>>;

/// A cell's evaluators, shared by every piece that runs them.
pub(crate) type Cell = Arc<EvalSet>;

/// The render's cells of levels up to [`SHARED_LEVEL`], and the whole
/// functions they are pruned from.
#[derive(Default)]
pub(crate) struct SharedCells {
    // The whole functions' evaluators (empty where the scope was made for
    // tests without them: cells then prune from the asking scope's).
    whole: Option<EvalSet>,
    cells: Mutex<FxHashMap<CellKey, Slot>>,
}

impl SharedCells {
    /// No cells yet, pruned from `whole` (the scene's own evaluators).
    pub(crate) fn new(whole: EvalSet) -> SharedCells {
        SharedCells {
            whole: Some(whole),
            cells: Mutex::default(),
        }
    }

    // Shared cell `key`'s evaluators, building it (and its ancestors) now
    // if no tile has asked yet (outside the map's lock).
    fn evals(&self, tr: &Scope<'_>, key: CellKey, st: &mut TileState) -> Option<Cell> {
        let slot = {
            let mut map = self.cells.lock().unwrap_or_else(|e| e.into_inner());
            Arc::clone(map.entry(key).or_default())
        };
        slot.get_or_init(|| {
            let (level, at) = key;
            let parent = if level == 0 {
                None
            } else {
                self.evals(tr, (level - 1, at.map(|i| i / 2)), st)
            };
            self.with_root(tr, |root| prune_cell(root, parent, key, st).0)
        })
        .clone()
    }

    // Runs `f` on the scope of the whole functions (of `tr` without them).
    fn with_root<R>(&self, tr: &Scope<'_>, f: impl FnOnce(&Scope<'_>) -> R) -> R {
        match &self.whole {
            Some(set) if set.evals.len() == tr.ctx.evals.len() => f(&tr.with_evals(set)),
            _ => f(tr),
        }
    }
}

impl std::fmt::Debug for SharedCells {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.cells.lock().map_or(0, |m| m.len());
        write!(f, "SharedCells({n} cells)")
    }
}

/// One tile's cells below [`SHARED_LEVEL`], built as its segments ask for
/// them.
#[derive(Clone, Default)]
pub(crate) struct CellTapes {
    // Each cell's evaluators (`None`: the whole functions').
    cells: FxHashMap<CellKey, Option<Cell>>,
    // Ops of the tapes the cells hold.
    ops: usize,
}

impl std::fmt::Debug for CellTapes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "CellTapes({} cells, {} ops)", self.cells.len(), self.ops)
    }
}

impl CellTapes {
    /// The evaluators of the smallest cell whose region holds `b`, built
    /// now if no one has asked yet; `None` when no cell's region holds it
    /// (it leaves the bounds) or nothing prunes there.
    pub(crate) fn holding(tr: &Scope<'_>, b: &IBox, st: &mut TileState) -> Option<Cell> {
        let key = smallest_cell(tr, b)?;
        let shared = Arc::clone(&tr.pruner.cells);
        if key.0 <= SHARED_LEVEL {
            return shared.evals(tr, key, st);
        }
        let mut cells = std::mem::take(&mut st.prune.cells);
        let evals = cells.evals(tr, &shared, key, st);
        st.prune.cells = cells;
        evals
    }

    // Cell `key`'s evaluators, building it (and its ancestors) if needed.
    fn evals(
        &mut self,
        tr: &Scope<'_>,
        shared: &SharedCells,
        key: CellKey,
        st: &mut TileState,
    ) -> Option<Cell> {
        if let Some(e) = self.cells.get(&key) {
            return e.clone();
        }
        let (level, at) = key;
        let up = (level - 1, at.map(|i| i / 2));
        let parent = if up.0 <= SHARED_LEVEL {
            shared.evals(tr, up, st)
        } else {
            self.evals(tr, shared, up, st)
        };
        let e = if self.ops >= CELL_TILE_OPS {
            parent
        } else {
            let (e, ops) = shared.with_root(tr, |root| prune_cell(root, parent, key, st));
            self.ops += ops;
            e
        };
        self.cells.insert(key, e.clone());
        e
    }
}

// Cell `key`'s evaluators pruned from its `parent`'s (`None`: from the
// whole functions, `root`'s), and the ops of the tapes it keeps of its own
// (0 where it keeps its parent's).
fn prune_cell(
    root: &Scope<'_>,
    parent: Option<Cell>,
    key: CellKey,
    st: &mut TileState,
) -> (Option<Cell>, usize) {
    let local;
    let from = match &parent {
        Some(set) => {
            if set.live_ops.iter().all(|&n| n < CELL_MIN_OPS) {
                return (parent, 0);
            }
            local = root.with_evals(set);
            &local
        }
        None => root,
    };
    // A cell keeps tapes of its own only where they are at most half
    // its parent's: near the root of a union of many objects the cells
    // keep nearly all of it, and holding those copies spent most of a
    // tile's budget.
    let before: usize = match &parent {
        Some(set) => set.live_ops.iter().sum(),
        None => whole_ops(root),
    };
    let own = from.pruned_to(cell_region(root, key), st);
    match own.map(|own| (own.live_ops.iter().sum::<usize>(), own)) {
        Some((ops, own)) if 2 * ops <= before => (Some(Arc::new(own)), ops),
        _ => (parent, 0),
    }
}

// The ops of the whole functions, which a cell without a parent is
// measured against whoever asks: measured against a nested sweep's scope
// (a cell's few hundred ops), every cell looked no smaller than its source
// and was left to the whole functions (3000 spheres: most shadow pieces
// ran the whole function).
fn whole_ops(tr: &Scope<'_>) -> usize {
    let tapes = tr.pruner.tapes.iter();
    tapes
        .zip(&tr.ctx.live_ops)
        .map(|(t, &n)| t.as_ref().map_or(n, |t| t.function().live_count()))
        .sum()
}

/// The width of the finest cells (along their narrowest axis).
pub(crate) fn finest_width(tr: &Scope<'_>) -> f64 {
    (0..3)
        .map(|i| (tr.ctx.bounds.max[i] - tr.ctx.bounds.min[i]) / f64::from(1u32 << MAX_LEVEL))
        .fold(f64::INFINITY, f64::min)
}

// The region of cell `key`: the cell widened by half its size each side.
fn cell_region(tr: &Scope<'_>, (level, at): CellKey) -> IBox {
    let n = f64::from(1u32 << level);
    std::array::from_fn(|i| {
        let (lo, hi) = (tr.ctx.bounds.min[i], tr.ctx.bounds.max[i]);
        let size = (hi - lo) / n;
        let i0 = f64::from(at[i]);
        Interval::new(lo + (i0 - 0.5) * size, lo + (i0 + 1.5) * size)
    })
}

// The deepest cell whose region holds `b`: at the level whose cells are
// as wide as `b` (or the finest), the one holding its centre, or up the
// levels where rounding or the bounds' edge leave `b` outside it.
fn smallest_cell(tr: &Scope<'_>, b: &IBox) -> Option<CellKey> {
    let mut level = MAX_LEVEL;
    for (i, c) in b.iter().enumerate() {
        let span = tr.ctx.bounds.max[i] - tr.ctx.bounds.min[i];
        let w = c.width();
        if span.is_nan() || span <= 0.0 || !w.is_finite() {
            return None;
        }
        // Cells of level L are span / 2^L wide.
        while level > 0 && w > span / f64::from(1u32 << level) {
            level -= 1;
        }
    }
    loop {
        let n = 1u32 << level;
        let at: [u32; 3] = std::array::from_fn(|i| {
            let span = tr.ctx.bounds.max[i] - tr.ctx.bounds.min[i];
            let c = (b[i].mid() - tr.ctx.bounds.min[i]) / span * f64::from(n);
            // NaN and out-of-range centres clamp to the edge cells (the
            // region test below decides).
            c.floor().max(0.0).min(f64::from(n - 1)) as u32
        });
        if box_within(b, &cell_region(tr, (level, at))) {
            return Some((level, at));
        }
        if level == 0 {
            return None;
        }
        level -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::random::Rng;
    use crate::scene::Camera;

    fn tracer() -> Scope<'static> {
        Scope::for_tests(&Camera::default(), 8)
    }

    // A box's cell holds it, and no cell a level deeper does: the one
    // holding its centre is narrower than the box, or leaves it out. Each
    // cell's region lies in its parent's, so that cells prune from their
    // parents' tapes.
    #[test]
    fn the_smallest_cell_holds_the_box_and_lies_in_its_parent() {
        let tr = tracer();
        let mut rng = Rng::new(3);
        let mut levels = [0usize; MAX_LEVEL as usize + 1];
        for _ in 0..2000 {
            let w = 2.5 * 0.5f64.powf(rng.range(0.0, 9.0));
            let b: IBox = std::array::from_fn(|i| {
                let c = rng.range(tr.ctx.bounds.min[i] - 0.2, tr.ctx.bounds.max[i] + 0.2);
                let h = w * rng.range(0.0, 0.5);
                Interval::new(c - h, c + h)
            });
            let Some((level, at)) = smallest_cell(&tr, &b) else {
                // Only a box leaving every region: the level-0 one.
                assert!(!box_within(&b, &cell_region(&tr, (0, [0; 3]))), "{b:?}");
                continue;
            };
            levels[level as usize] += 1;
            let region = cell_region(&tr, (level, at));
            assert!(box_within(&b, &region), "{b:?} outside {region:?}");
            if level > 0 {
                let parent = cell_region(&tr, (level - 1, at.map(|i| i / 2)));
                let inside = (0..3).all(|i| {
                    let slack = 1e-12 * (parent[i].width() + 1.0);
                    parent[i].lo - slack <= region[i].lo && region[i].hi <= parent[i].hi + slack
                });
                assert!(inside, "{region:?} outside its parent {parent:?}");
            }
            if level < MAX_LEVEL {
                let n = f64::from(1u32 << (level + 1));
                let fits = (0..3).all(|i| {
                    let span = tr.ctx.bounds.max[i] - tr.ctx.bounds.min[i];
                    b[i].width() <= span / n
                });
                let at: [u32; 3] = std::array::from_fn(|i| {
                    let span = tr.ctx.bounds.max[i] - tr.ctx.bounds.min[i];
                    let c = (b[i].mid() - tr.ctx.bounds.min[i]) / span * n;
                    c.floor().max(0.0).min(n - 1.0) as u32
                });
                let deeper = cell_region(&tr, (level + 1, at));
                assert!(
                    !fits || !box_within(&b, &deeper),
                    "{b:?} fits level {}",
                    level + 1
                );
            }
        }
        assert!(
            levels.iter().all(|&n| n > 20),
            "boxes per level: {levels:?}"
        );
    }
}
