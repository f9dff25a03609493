//! A tile's rays, what is known along them, and their results: what the
//! beam sweep of [`super::beam`] fills in.

use crate::interval::Interval;
use crate::interval::boxes::IBox;
use crate::render::prune::scope::Scope;
use crate::render::trace::probe::{EmptyPrefix, Rect};
use crate::render::trace::refine::RefineScratch;
use crate::render::view::camera::{PixelRay, RayGrid};
use crate::render::{Class, Hit};

/// The per-pixel data of one tile.
pub(crate) struct TileRays {
    /// Left column of the tile.
    pub x0: u32,
    /// Top row of the tile.
    pub y0: u32,
    /// Tile width in pixels.
    pub w: u32,
    /// Tile height in pixels.
    pub h: u32,
    /// The terms every pixel's ray is summed from.
    pub grid: RayGrid,
    /// Per-pixel rays, row-major within the tile; empty in a flat scene's
    /// tile, whose pixels mostly need none ([`TileRays::ray`] builds one).
    pub rays: Vec<PixelRay>,
    /// Per-pixel slab ranges (None: the ray misses the bounds); empty
    /// where `rays` is (see [`TileRays::slab`]).
    pub slabs: Vec<Option<(f64, f64)>>,
    /// Per-pixel box around the ray's point at its clip start (None: the
    /// ray misses the bounds); empty until a block first needs them, then
    /// computed for the whole tile once, as every block level reads them.
    pub starts: Vec<Option<IBox>>,
    /// Per-pixel results.
    pub hits: Vec<Option<Hit>>,
    /// How each pixel was decided.
    pub class: Vec<Class>,
    /// Included blocks, for shadow beams.
    pub included: Vec<Rect>,
    /// What is known along the whole tile's beam before tracing it.
    pub top: EmptyPrefix,
    /// Buffers of batched root refinement, reused by the tile's blocks.
    pub refine: RefineScratch,
}

impl TileRays {
    /// The range of the ray parameter a tile's pixels are traced over: the
    /// hull of their slab ranges, or, in a tile that holds none (see
    /// `tile_rays`), the range of its beam inside the bounds, which holds
    /// them all; `None` when no pixel's ray meets the bounds.
    pub(crate) fn depths(&self, tr: &Scope<'_>) -> Option<Interval> {
        if self.slabs.is_empty() {
            let xs = (f64::from(self.x0) + 0.5, f64::from(self.x0 + self.w) - 0.5);
            let ys = (f64::from(self.y0) + 0.5, f64::from(self.y0 + self.h) - 0.5);
            return tr.ctx.cam.corners(xs, ys).slab_range(&tr.ctx.bounds);
        }
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for &(a, c) in self.slabs.iter().flatten() {
            t0 = t0.min(a);
            t1 = t1.max(c);
        }
        (t0 <= t1).then(|| Interval::new(t0, t1))
    }

    /// Index of the pixel in column `i`, row `j` of the tile.
    pub(crate) fn idx(&self, i: u32, j: u32) -> usize {
        (j * self.w + i) as usize
    }

    /// The whole tile as a block.
    pub(crate) fn whole(&self) -> Rect {
        Rect {
            x0: 0,
            y0: 0,
            x1: self.w,
            y1: self.h,
        }
    }

    /// Whether `b` is the whole tile.
    pub(crate) fn is_whole(&self, b: Rect) -> bool {
        b == self.whole()
    }

    /// The ray of pixel `k` (the same bits whether or not the tile holds
    /// its rays).
    #[inline]
    pub(crate) fn ray(&self, k: usize) -> PixelRay {
        match self.rays.get(k) {
            Some(r) => *r,
            None => self.grid.ray_at_index(k),
        }
    }

    /// Pixel `k`'s ray and its slab range inside `bounds`, as the tile
    /// holds them or (where it holds none: a flat scene's tile, never
    /// masked or floored) as `tile::tile_rays` would compute them.
    pub(crate) fn ray_and_slab(
        &self,
        k: usize,
        bounds: &crate::scene::Bounds,
    ) -> (PixelRay, Option<(f64, f64)>) {
        let ray = self.ray(k);
        let slab = match self.slabs.get(k) {
            Some(s) => *s,
            None => ray.slab(bounds),
        };
        (ray, slab)
    }
}
