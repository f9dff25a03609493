//! One tile: visibility (beams, or one ray per pixel for the baselines),
//! then surfaces, shadow beams over included blocks, and shading.

use std::time::Instant;

use image::Rgb;

use crate::interval::Interval;
use crate::render::context::EvalSet;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::mean_value::FormPolicy;
use crate::render::light::shade::{self, TileSurfs};
use crate::render::light::shadow;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::trace::beam::{self, TileRays};
use crate::render::trace::probe::{EmptyPrefix, Rect};
use crate::render::trace::refine::{RefineScratch, RootBracket};
use crate::render::trace::{plane, ray};
use crate::render::view::camera::RayGrid;
use crate::render::{Class, Method, RenderOptions};
use crate::scene::LightKind;
use glam::DVec3;

mod shading;
use crate::render::enclose::monotone;
use shading::{CutFaces, PixelShadows, class_color, shade_pixels, shadow_beams};

/// Which pixels of the traced image a tile covers.
#[derive(Copy, Clone, Debug)]
pub(crate) struct TileSpec<'m> {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
    /// Row-major: the pixels to trace (None: all of them).
    pub mask: Option<&'m [bool]>,
    /// Row-major: a ray parameter before which each pixel's ray is known
    /// to meet no surface, and where its first surface most likely lies
    /// (None: its clip start).
    pub floors: Option<&'m [EmptyPrefix]>,
    /// Row-major: shadow states a sample may take instead of tracing
    /// its shadow segments (None: every sample traces its own).
    pub shadow_hints: Option<&'m [ShadowHint]>,
    /// Row-major: where a sample's first root is already bracketed
    /// (None: nowhere). Such a sample is refined in its bracket and kept
    /// out of the tile's beams.
    pub brackets: Option<&'m [Option<RootBracket>]>,
    /// Whether blocks may try the mean-value form (see
    /// [`FormPolicy`]). The policy learns per tile, from 16 tries at a
    /// block size; IAA's fine tiles (a few split pixels' sub-samples) end
    /// before it has learnt anything, so they would pay for the form on
    /// every block. Without it they ran faster on every scene measured
    /// (256², threshold 1/4, one thread: orthocircle 448–506 → 408–439 ms,
    /// metaballs 248–261 → 231–236 ms, CSG unchanged).
    pub mean_value: bool,
    /// IAA's base render, after its pixel-area tests (`aa::classify_tile`):
    /// every traced pixel that `brackets` does not settle is one
    /// guaranteed ray from its floor, not part of a beam (the area tests
    /// left it undecided, and a beam over pixel centres would repeat
    /// them), and shadow beams are tried over every square of
    /// [`SHADOW_GROUP`] pixels (false: beams as usual).
    pub rays_from_floors: bool,
}

impl TileSpec<'static> {
    /// The `w`×`h` tile at (`x0`, `y0`), every pixel traced from its clip
    /// start, blocks free to try the mean-value form.
    pub(crate) fn plain(x0: u32, y0: u32, w: u32, h: u32) -> TileSpec<'static> {
        TileSpec {
            x0,
            y0,
            w,
            h,
            mask: None,
            floors: None,
            shadow_hints: None,
            brackets: None,
            mean_value: true,
            rays_from_floors: false,
        }
    }
}

/// The shadow state of a nearby sample that a sample may reuse: IAA's
/// sub-samples take their pixel's base sample's (see
/// `aa::SHADOW_REUSE_REACH`).
#[derive(Copy, Clone, Debug)]
pub(crate) struct ShadowHint {
    /// Ray parameter of the nearby sample's hit (NaN: none to reuse).
    pub t: f64,
    /// How far from `t` a hit may lie and still reuse it.
    pub reach: f64,
    /// Lights shadowed at the nearby sample (bit per light).
    pub shadowed: u64,
}

/// What tracing a tile produces, row-major within the tile.
pub(crate) struct TileOut {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
    /// Linear colour.
    pub linear: Vec<[f64; 3]>,
    /// Lights shadowed at each sample (bit per light; see `shade::shade`).
    pub shadowed: Vec<u64>,
    /// Fraction of the pixel whose samples hit.
    pub coverage: Vec<f64>,
    /// Samples taken per pixel.
    pub samples: Vec<u32>,
    /// Ray parameter of the hit, +inf for none (the in-memory render holds
    /// every tile at once; the streaming one a row of tiles).
    pub depth: Vec<f64>,
    /// Unit normals, if asked for; NaN where nothing was hit (kept as
    /// f64 so that float outputs get them raw and the 8-bit image's bytes
    /// are [`crate::render::view::output::normal_pixel`]'s of the same values as before).
    pub normals: Option<Vec<[f64; 3]>>,
    /// Classification image pixels, if asked for.
    pub class: Option<Vec<Rgb<u8>>>,
    /// Counters and the mean-value record, which anti-aliasing carries on.
    pub state: TileState,
    /// IAA: what the pixel-area tests found, for the anti-aliasing pass.
    pub classified: Option<Box<crate::render::aa::Classified>>,
}

/// Milliseconds since `t`.
pub(crate) fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Traces and shades one tile of `tr`'s image.
pub(crate) fn render_tile(
    tr: &Scope<'_>,
    opts: &RenderOptions,
    spec: TileSpec<'_>,
    background: [f64; 3],
) -> TileOut {
    let mut out = render_tile_from(tr, opts, spec, background, TileState::default());
    // The tile's cells go with the tile: a finished tile waits for its
    // row, and the tapes of its cells are most of its memory.
    out.state.prune = Default::default();
    out
}

/// [`render_tile`] carrying on from `st`, and keeping the shadow cells it
/// built in the output's state: each of a tile's squares of IAA
/// sub-samples hands them to the next.
pub(crate) fn render_tile_from(
    tr: &Scope<'_>,
    opts: &RenderOptions,
    spec: TileSpec<'_>,
    background: [f64; 3],
    mut st: TileState,
) -> TileOut {
    if !spec.mean_value {
        st.mean_value = FormPolicy::never();
        st.affine = FormPolicy::never();
        st.affine_along = FormPolicy::never();
    }
    let t_trace = Instant::now();
    if proven_empty(tr, opts, &spec, &mut st) {
        st.stats.trace_cpu_ms += ms_since(t_trace);
        return empty_out(&spec, opts, background, st);
    }
    let mut tile = tile_rays(tr, opts, &spec);
    let bracketed = refine_bracketed(tr, &spec, &mut tile, &mut st);
    // Visibility inside the tile's beam runs on functions pruned to it;
    // shading and shadows, whose segments leave the beam, keep `tr`.
    let pruned = prune_to_tile(tr, &tile, spec.h, &mut st);
    let local;
    let tr_vis = match &pruned {
        Some((set, ends)) => {
            local = tr.with_evals(set).with_slice_ends(ends.clone());
            &local
        }
        None => tr,
    };
    if spec.rays_from_floors {
        rays_from_floors(tr_vis, &mut tile, spec.floors, &mut st);
        tile.included = squares(spec.w, spec.h, SHADOW_GROUP).collect();
    } else {
        visibility(tr_vis, opts.method, &mut tile, spec.h, &mut st);
    }
    for (k, h) in bracketed {
        tile.hits[k] = Some(h);
        tile.class[k] = Class::Included;
    }
    st.stats.trace_cpu_ms += ms_since(t_trace);

    // Hit points lie in the tile's beam: their normals may come from the
    // pruned functions too: on the surface the pruned tapes keep the
    // branch the whole function's `min`/`max` takes, and the normals agree
    // to rounding (`render::signs_tests`).
    let t_shade = Instant::now();
    let cut = CutFaces::of(tr, &tile);
    let surfs = surfaces(tr_vis, &tile, cut.is_some(), &mut st.stats);
    st.stats.shade_cpu_ms += ms_since(t_shade);
    let known = known_shadows(&spec, &tile);
    let lit_by_beam = shadow_beams(tr, &tile, &surfs, &known, &mut st);
    let shadows = PixelShadows {
        lit_by_beam: &lit_by_beam,
        known: &known,
    };
    let mut lit = shade_pixels(tr, &surfs, shadows, background, opts, &mut st);
    if let Some(cut) = cut {
        let t_cut = Instant::now();
        cut.paint(tr, &tile, &known, &mut lit, &mut st);
        st.stats.shade_cpu_ms += ms_since(t_cut);
    }
    traced_out(&spec, opts, &tile, lit, st)
}

/// The output of a tile proven empty: background everywhere.
fn empty_out(
    spec: &TileSpec<'_>,
    opts: &RenderOptions,
    background: [f64; 3],
    st: TileState,
) -> TileOut {
    let n = (spec.w * spec.h) as usize;
    TileOut {
        x0: spec.x0,
        y0: spec.y0,
        w: spec.w,
        h: spec.h,
        linear: vec![background; n],
        shadowed: vec![0; n],
        coverage: vec![0.0; n],
        samples: vec![1; n],
        depth: vec![f64::INFINITY; n],
        normals: opts.want_normals.then(|| vec![[f64::NAN; 3]; n]),
        class: None,
        state: st,
        classified: None,
    }
}

/// The surfaces at the tile's hits (none at a cut face's hits when the
/// tile paints them on the shared path), their singular normals mended.
fn surfaces(tr_vis: &Scope<'_>, tile: &TileRays, cut: bool, stats: &mut RenderStats) -> TileSurfs {
    let n = tile.hits.len();
    let mut surfs = TileSurfs::new(n, tile.hits.iter().flatten().count());
    for (k, h) in tile.hits.iter().enumerate() {
        if let Some(h) = h
            && !(h.inside && cut)
        {
            surfs.set(k, shade::surface(tr_vis, &tile.ray(k), h, stats));
        }
    }
    shade::mend_singular_normals(tr_vis, |k| tile.ray(k), &tile.hits, &mut surfs, stats);
    surfs
}

/// Per pixel, the shadow state of the hint whose reach its hit lies
/// within: such a hit takes it, and needs no shadow beam either (empty
/// without hints).
fn known_shadows(spec: &TileSpec<'_>, tile: &TileRays) -> Vec<Option<u64>> {
    let Some(hints) = spec.shadow_hints else {
        return Vec::new();
    };
    tile.hits
        .iter()
        .zip(hints)
        .map(|(h, s)| {
            h.filter(|h| (h.t - s.t).abs() <= s.reach)
                .map(|_| s.shadowed)
        })
        .collect()
}

/// The output of a traced tile: its lit pixels, coverage, depth and
/// classes.
fn traced_out(
    spec: &TileSpec<'_>,
    opts: &RenderOptions,
    tile: &TileRays,
    lit: shading::LitPixels,
    st: TileState,
) -> TileOut {
    let n = tile.hits.len();
    TileOut {
        x0: spec.x0,
        y0: spec.y0,
        w: spec.w,
        h: spec.h,
        coverage: tile
            .hits
            .iter()
            .map(|h| if h.is_some() { 1.0 } else { 0.0 })
            .collect(),
        linear: lit.linear,
        shadowed: lit.shadowed,
        samples: vec![1; n],
        depth: tile
            .hits
            .iter()
            .map(|h| h.map_or(f64::INFINITY, |h| h.t))
            .collect(),
        normals: lit.normals,
        class: opts
            .want_classify
            .then(|| tile.class.iter().map(|&c| class_color(c)).collect()),
        state: st,
        classified: None,
    }
}

/// Functions with at most this many live ops in all are tested over a
/// whole tile's beam before its pixels' rays are built: one interval of
/// each costs less than building the rays of a tile that turns out empty
/// (100 spheres, 1400 ops, 1.2x faster). Longer functions are tested on
/// their group's tapes, all the group's tiles in one batch when the group
/// is built (`groups::empty_tiles`): one box at a time on those tapes, as
/// each tile came, made prospero's render 1.4x slower; the batch skips 280
/// of its 1024 tiles at 1024² for about 1 ms.
const EMPTY_TILE_MAX_OPS: usize = 4096;

// Whether the beam tracer would settle every pixel of the tile as
// background: every object strictly positive, or undefined, over the hull
// of the tile's beam over a range that holds every pixel's slab. Each box
// the beam tests would evaluate lies inside that hull, and interval
// arithmetic is inclusion-isotone (a tape pruned to a region gives, over
// a box inside it, an interval inside the whole function's over any box
// holding that one), so they would all reject too: the pixels are the
// same as tracing gives (no classification is asked for, which tells rays
// outside the bounds from rejected ones, and no pixel is masked or starts
// at a floor of its own). Per-pixel rays, slabs and shading were most of
// a sparse scene's time.
fn proven_empty(
    tr: &Scope<'_>,
    opts: &RenderOptions,
    spec: &TileSpec<'_>,
    st: &mut TileState,
) -> bool {
    if opts.method != Method::Beam
        || opts.want_classify
        || spec.mask.is_some()
        || spec.floors.is_some()
    {
        return false;
    }
    // Longer functions are tested on their group's tapes, a group's tiles
    // in one batch when the group is built (`groups::empty_tiles`).
    if tr.ctx.live_ops.iter().sum::<usize>() > EMPTY_TILE_MAX_OPS {
        let empty = tr.pruner.enabled
            && tr.pruner.tapes.iter().any(Option::is_some)
            && tr
                .pruner
                .groups
                .tile_is_empty(tr, (spec.x0, spec.y0), (spec.w, spec.h), st);
        st.stats.blocks_rejected += u64::from(empty);
        return empty;
    }
    let xs = (f64::from(spec.x0) + 0.5, f64::from(spec.x0 + spec.w) - 0.5);
    let ys = (f64::from(spec.y0) + 0.5, f64::from(spec.y0 + spec.h) - 0.5);
    let corners = tr.ctx.cam.corners(xs, ys);
    let Some(t) = corners.slab_range(&tr.ctx.bounds) else {
        return false;
    };
    let hull = corners.hull(t);
    let empty = (0..tr.ctx.evals.len()).all(|k| {
        let v = tr.ctx.interval(k, hull, &mut st.stats);
        crate::render::enclose::proof::holds_no_surface(v)
    });
    st.stats.blocks_rejected += u64::from(empty);
    empty
}

// The hits of the samples whose first root `spec` brackets, each refined
// in its bracket, and those samples taken out of the tile's beams (their
// slabs cleared). A sample whose bracket shows no sign change at points
// (rounding at the limits of precision) is left to the beams.
fn refine_bracketed(
    tr: &Scope<'_>,
    spec: &TileSpec<'_>,
    tile: &mut TileRays,
    st: &mut TileState,
) -> Vec<(usize, crate::render::Hit)> {
    let Some(brackets) = spec.brackets else {
        return Vec::new();
    };
    let mut hits = Vec::new();
    for (k, b) in brackets.iter().enumerate() {
        let Some(b) = b else { continue };
        if tile.slabs[k].is_none() {
            continue;
        }
        let live = [b.obj as u32];
        let ray = &tile.rays[k];
        if !b.unique && !decreasing_along(tr, ray, b, &mut st.stats) {
            continue;
        }
        if let Some(h) =
            crate::render::trace::refine::refine(tr, ray, &live, b.a, b.b, &mut st.stats)
        {
            tile.slabs[k] = None;
            hits.push((k, h));
        }
    }
    hits
}

// Whether object `b.obj` is proven strictly decreasing along `ray` over
// `[b.a, b.b]`: then its one root there is the ray's first hit (see
// `RootBracket`).
fn decreasing_along(
    tr: &Scope<'_>,
    ray: &crate::render::view::camera::PixelRay,
    b: &RootBracket,
    st: &mut crate::render::context::stats::RenderStats,
) -> bool {
    let bx = crate::interval::boxes::ray_box(ray.o, ray.d, Interval::new(b.a, b.b));
    monotone::decreasing_along(&tr.ctx, b.obj, bx, ray.d, st)
}

// The tile's pixel rays and their ranges inside the bounds, nothing traced.
// A flat scene's tile traced by `plane` keeps neither: its rectangles'
// beams come from the ray terms, and only the pixels no rectangle settles
// (and the hits, for shading) need a ray and a range of their own, which
// `TileRays::ray` and `TileRays::slab` build (the same bits). Unless the
// pixels are masked or floored, or classified (which marks every pixel
// outside the bounds).
fn tile_rays(tr: &Scope<'_>, opts: &RenderOptions, spec: &TileSpec<'_>) -> TileRays {
    let n = (spec.w * spec.h) as usize;
    let grid = RayGrid::new(&tr.ctx.cam, (spec.x0, spec.y0), (spec.w, spec.h));
    let lazy = tr.ctx.flat
        && opts.method == Method::Beam
        && spec.mask.is_none()
        && spec.floors.is_none()
        && !opts.want_classify;
    let rays = if lazy { Vec::new() } else { grid.rays() };
    // Masked-out samples look like rays outside the bounds: beams over
    // them are rejected at once.
    let slabs = rays
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let on = spec.mask.is_none_or(|m| m[k]);
            let slab = if on { r.slab(&tr.ctx.bounds) } else { None };
            let floor = spec.floors.map_or(0.0, |f| f[k].at);
            // A floor at or past the clip end leaves nothing to trace.
            slab.and_then(|(t0, t1)| (floor < t1).then_some((t0.max(floor), t1)))
        })
        .collect();
    // The tile's beam starts where the nearest floor is, and looks first
    // as deep as the deepest candidate.
    let top = spec.floors.map_or(EmptyPrefix::NONE, |f| {
        let on = |k: &usize| spec.mask.is_none_or(|m| m[*k]);
        let at = (0..n)
            .filter(on)
            .map(|k| f[k].at)
            .fold(f64::INFINITY, f64::min);
        let near = (0..n).filter(on).map(|k| f[k].near).fold(at, f64::max);
        if at.is_finite() {
            EmptyPrefix { at, near }
        } else {
            EmptyPrefix::NONE
        }
    });
    TileRays {
        top,
        starts: Vec::new(),
        x0: spec.x0,
        y0: spec.y0,
        w: spec.w,
        h: spec.h,
        grid,
        rays,
        slabs,
        hits: vec![None; n],
        class: vec![Class::Outside; n],
        included: Vec::new(),
        refine: RefineScratch::default(),
    }
}

/// Evaluators pruned to the tile's beam (the rays through its pixel
/// centres over their clipped T ranges), and the interior ends of its
/// slices.
fn prune_to_tile(
    tr: &Scope<'_>,
    tile: &TileRays,
    th: u32,
    st: &mut TileState,
) -> Option<(EvalSet, Vec<f64>)> {
    let xs = (f64::from(tile.x0) + 0.5, f64::from(tile.x0 + tile.w) - 0.5);
    let ys = (f64::from(tile.y0) + 0.5, f64::from(tile.y0 + th) - 0.5);
    let t = tile.depths(tr)?;
    let pruned = tr.pruned_to_beam(xs, ys, t, st)?;
    Some((pruned, tr.slice_ends(xs, ys, t)))
}

/// Side of the squares of IAA's base render over which shadow beams are
/// tried (see [`TileSpec::rays_from_floors`]): on orthocircle at 256² they
/// left as many shadow segments to trace as the plain render's included
/// blocks did (18.2k), where the area tests' included cells, which stop
/// short of the silhouettes, left 23k.
const SHADOW_GROUP: u32 = 4;

/// The `side`×`side` squares of a `w`×`h` tile, row by row (clipped at
/// its right and bottom sides).
pub(crate) fn squares(w: u32, h: u32, side: u32) -> impl Iterator<Item = Rect> {
    (0..h).step_by(side as usize).flat_map(move |y0| {
        (0..w).step_by(side as usize).map(move |x0| Rect {
            x0,
            y0,
            x1: (x0 + side).min(w),
            y1: (y0 + side).min(h),
        })
    })
}

// Traces every pixel with a range left as one guaranteed ray from its
// floor (`floors`, None: its clip start).
fn rays_from_floors(
    tr: &Scope<'_>,
    tile: &mut TileRays,
    floors: Option<&[EmptyPrefix]>,
    st: &mut TileState,
) {
    let all: Vec<u32> = (0..tr.ctx.evals.len() as u32).collect();
    for k in 0..tile.slabs.len() {
        let Some(range) = tile.slabs[k] else {
            tile.class[k] = Class::Outside;
            continue;
        };
        let floor = floors.map_or(EmptyPrefix::NONE, |f| f[k]);
        let start = beam::RayStart {
            floor,
            from_floor: true,
        };
        beam::single_ray(tr, tile, k, start, range, &all, st);
    }
}

// Finds every pixel's first hit with `method`.
fn visibility(tr: &Scope<'_>, method: Method, tile: &mut TileRays, th: u32, st: &mut TileState) {
    let n = tile.slabs.len();
    match method {
        Method::Beam if tr.ctx.flat => plane::trace_tile(tr, tile, th, st),
        Method::Beam => beam::trace_tile(tr, tile, th, st),
        Method::Pixel | Method::Point { .. } => {
            let all: Vec<u32> = (0..tr.ctx.evals.len() as u32).collect();
            for k in 0..n {
                if let Some((a, b)) = tile.slabs[k] {
                    let r = tile.rays[k];
                    tile.hits[k] = match method {
                        Method::Point { steps } => {
                            ray::march(tr, &r, a, b, &all, steps, &mut st.stats)
                        }
                        _ => ray::trace_ray(tr, &r, a, b, &all, st),
                    };
                    tile.class[k] = Class::Ray;
                }
            }
        }
    }
    for k in 0..n {
        if tile.slabs[k].is_none() {
            tile.class[k] = Class::Outside;
        }
    }
}

#[cfg(test)]
#[path = "tile_tests.rs"]
mod tests;
