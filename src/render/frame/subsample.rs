//! Tiles traced at a finer resolution and averaged back: `grid:N`'s
//! samples, and IAA's sub-samples of split pixels, traced square by square
//! of the pixels that need them.

use rayon::prelude::*;

use crate::render::RenderOptions;
use crate::render::aa::SplitSamples;
use crate::render::context::stats::RenderStats;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::{PruneScratch, TileState};
use crate::render::tile::{ShadowHint, TileOut, TileSpec, render_tile_from, squares};
use crate::render::trace::probe::{EmptyPrefix, Rect};
use crate::render::trace::refine::RootBracket;

// Averages each s×s block of a tile traced at s× resolution, in linear
// light. Depth: the nearest hit; normals and classes: the sample at
// (s/2, s/2) of the block.
pub(super) fn downsample(t: TileOut, s: u32) -> TileOut {
    let (w, h) = (t.w / s, t.h / s);
    let n = (w * h) as usize;
    let inv = 1.0 / f64::from(s * s);
    let mut linear = vec![[0.0; 3]; n];
    let mut coverage = vec![0.0; n];
    let mut depth = vec![f64::INFINITY; n];
    fn pick<T: Copy>(v: &[T], (w, h, s, tw): (u32, u32, u32, u32)) -> Vec<T> {
        (0..h)
            .flat_map(|j| (0..w).map(move |i| (i, j)))
            .map(|(i, j)| v[((j * s + s / 2) * tw + i * s + s / 2) as usize])
            .collect()
    }
    let dims = (w, h, s, t.w);
    for j in 0..h {
        for i in 0..w {
            let k = (j * w + i) as usize;
            for sj in 0..s {
                for si in 0..s {
                    let src = ((j * s + sj) * t.w + i * s + si) as usize;
                    for (l, v) in linear[k].iter_mut().zip(t.linear[src]) {
                        *l += v * inv;
                    }
                    if t.depth[src].is_finite() {
                        coverage[k] += inv;
                        depth[k] = depth[k].min(t.depth[src]);
                    }
                }
            }
        }
    }
    TileOut {
        x0: t.x0 / s,
        y0: t.y0 / s,
        w,
        h,
        linear,
        // Anti-aliasing on a supersampled image never reads this.
        shadowed: vec![0; n],
        coverage,
        samples: vec![s * s; n],
        depth,
        normals: t.normals.as_deref().map(|v| pick(v, dims)),
        class: t.class.as_deref().map(|v| pick(v, dims)),
        state: t.state,
        classified: None,
    }
}

/// What a tile's pixel-area tests proved for the sub-samples of each
/// pixel (row-major).
#[derive(Copy, Clone)]
pub(super) struct PixelFacts<'a> {
    /// Where each pixel's rays may start (its area proven empty before).
    pub floors: &'a [EmptyPrefix],
    /// The shadow state each pixel's sub-samples may reuse.
    pub hints: &'a [ShadowHint],
    /// The bracket of each pixel's first roots, where its area's beam was
    /// included.
    pub brackets: &'a [Option<RootBracket>],
}

/// The split pixels of one tile to trace at one finer resolution.
pub(super) struct SplitJob<'a> {
    /// The render's options.
    pub opts: &'a RenderOptions,
    /// The tile: its left column, top row, width and height.
    pub area: TileArea,
    /// Per pixel of the tile: whether it is traced at this resolution.
    pub split: &'a [bool],
    /// What the pixel-area tests proved for each pixel.
    pub facts: PixelFacts<'a>,
    /// Sub-samples a pixel side.
    pub factor: u32,
    /// The background colour, linear.
    pub background: [f64; 3],
}

/// A tile's place in the image, in pixels.
#[derive(Copy, Clone, Debug)]
pub(super) struct TileArea {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width.
    pub w: u32,
    /// Height.
    pub h: u32,
}

/// Side, in pixels, of the squares of a tile whose split pixels are traced
/// together at the fine resolution. A fine tile spans only squares that
/// hold a split pixel: building, clipping and sweeping the sub-samples of
/// a whole tile cost more than tracing its few split pixels.
const FINE_GROUP: u32 = 2;

// The options a fine tile is traced with: only the buffers the pixels'
// means are taken from.
fn fine_options(opts: &RenderOptions) -> RenderOptions {
    RenderOptions {
        want_depth: false,
        want_normals: false,
        want_classify: false,
        want_buffers: true,
        progress: false,
        ..opts.clone()
    }
}

// The sub-samples of the job's split pixels, traced with `fine` at the
// job's factor × the resolution, square by square of `FINE_GROUP` pixels
// (in order, carrying on with the tile's pruning scratch `prune`, where
// shadows run cells' tapes), other sub-samples masked out: per pixel of
// the tile the mean linear colour,
// covered fraction and nearest hit of its sub-samples (zero, zero, +inf
// where not split).
pub(super) fn trace_split(
    fine: &Scope<'_>,
    job: SplitJob<'_>,
    prune: &mut PruneScratch,
    stats: &mut RenderStats,
) -> SplitSamples {
    let TileArea { w, h, .. } = job.area;
    let n = (w * h) as usize;
    let mut linear = vec![[0.0; 3]; n];
    let mut coverage = vec![0.0; n];
    let mut depth = vec![f64::INFINITY; n];
    let fine_opts = fine_options(job.opts);
    let in_tile = |(i, j): (u32, u32)| (j * w + i) as usize;
    let wanted: Vec<Rect> = squares(w, h, FINE_GROUP)
        .filter(|g| g.pixels().any(|p| job.split[in_tile(p)]))
        .collect();
    let outs: Vec<(Rect, TileOut)> = if fine.pruner.enabled && fine.ctx.large {
        // In a scene whose shadow segments run cells' tapes, the squares
        // are traced one after the other, each carrying on with the cells
        // the one before it built: neighbouring squares' segments meet
        // the same cells, and each
        // square pruning its own from the whole functions made the
        // sub-samples' shadows 3/4 of an IAA render of 400 spheres (see
        // docs/performance.md). The order is the tile's alone, so the
        // answers do not depend on the thread count; tiles run in
        // parallel.
        let mut carry = |g: Rect| {
            let st = TileState {
                prune: std::mem::take(prune),
                ..TileState::default()
            };
            let mut out = trace_square(fine, &fine_opts, &job, g, st);
            *prune = std::mem::take(&mut out.state.prune);
            (g, downsample(out, job.factor))
        };
        wanted.into_iter().map(&mut carry).collect()
    } else {
        // Elsewhere they share nothing and run in parallel: a tile's split
        // pixels can be most of a render's work (a silhouette crossing few
        // tiles), more than one thread should carry.
        let fresh = |&g: &Rect| {
            let out = trace_square(fine, &fine_opts, &job, g, TileState::default());
            (g, downsample(out, job.factor))
        };
        wanted.par_iter().map(fresh).collect()
    };
    for (g, out) in &outs {
        stats.merge(&out.state.stats);
        // Row by row, as the downsampled square's pixels.
        for (q, p) in g.pixels().enumerate() {
            let k = in_tile(p);
            linear[k] = out.linear[q];
            coverage[k] = out.coverage[q];
            depth[k] = out.depth[q];
        }
    }
    SplitSamples {
        linear,
        coverage,
        depth,
    }
}

// The sub-samples of the split pixels of the square `g` of the job's tile
// (tile coordinates), traced with `fine` as one masked tile at the job's
// factor × the resolution, carrying on from `st`.
fn trace_square(
    fine: &Scope<'_>,
    fine_opts: &RenderOptions,
    job: &SplitJob<'_>,
    g: Rect,
    st: TileState,
) -> TileOut {
    let (f, TileArea { x0, y0, w, .. }) = (job.factor, job.area);
    let facts = job.facts;
    let (fw, fh) = ((g.x1 - g.x0) * f, (g.y1 - g.y0) * f);
    let pixel = |k: usize| {
        let (i, j) = (k as u32 % fw, k as u32 / fw);
        ((g.y0 + j / f) * w + g.x0 + i / f) as usize
    };
    let nf = (fw * fh) as usize;
    let mask: Vec<bool> = (0..nf).map(|k| job.split[pixel(k)]).collect();
    // Each sub-sample starts where its pixel's area was proven empty up
    // to: the fine render need not sweep that prefix again.
    let starts: Vec<EmptyPrefix> = (0..nf).map(|k| facts.floors[pixel(k)]).collect();
    let hints: Vec<ShadowHint> = (0..nf).map(|k| facts.hints[pixel(k)]).collect();
    let brackets: Vec<Option<RootBracket>> = (0..nf).map(|k| facts.brackets[pixel(k)]).collect();
    let spec = TileSpec {
        x0: (x0 + g.x0) * f,
        y0: (y0 + g.y0) * f,
        w: fw,
        h: fh,
        mask: Some(&mask),
        floors: Some(&starts),
        shadow_hints: Some(&hints),
        brackets: Some(&brackets),
        // Too few blocks to learn whether the form pays.
        mean_value: false,
        rays_from_floors: false,
    };
    render_tile_from(fine, fine_opts, spec, job.background, st)
}
