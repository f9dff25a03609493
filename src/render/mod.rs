//! The guaranteed beam tracer, after Flórez et al.
//!
//! The image is cut into 32×32 tiles traced in parallel. Each tile is a
//! block of pixels whose rays form a beam ([`camera`] gives its exact
//! hull); [`beam`] rejects empty stretches of the beam with interval
//! arithmetic, settles blocks whose rays all cross the surface in a proven
//! bracket (inclusion test), and splits the rest down to single rays,
//! which [`ray`] traces with guaranteed first-root isolation. [`shade`]
//! lights the hits with guaranteed shadows. Two baselines share the code:
//! [`Method::Pixel`] (one interval ray per pixel, no beams) and
//! [`Method::Point`] (fixed-step point sampling, the technique the paper
//! improves on).
//!
//! [`aa`] adds anti-aliasing on top of any method ([`render_aa`]):
//! interval adaptive (extra samples only where a pixel's beam cannot
//! prove one smoothly lit surface) or regular grid supersampling;
//! `crate::bench::accuracy` measures every method against a supersampled reference.
//!
//! The scene function is the minimum over the objects; the object hit is
//! the one whose own f is smallest at the hit point. Output is identical
//! for any thread count: every tile is computed independently and the
//! results and counters are merged in tile order.

pub mod aa;
pub mod beam;
pub mod camera;
pub mod output;
pub mod ray;
pub mod shade;
pub mod stats;

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use image::{ImageBuffer, Luma, Rgb, RgbImage};
use rayon::prelude::*;

use crate::eval::{Evaluator, Grad, IntervalGrad};
use crate::interval::Interval;
use crate::interval::boxes::IBox;
use crate::scene::{Bounds, Light, Scene};
pub use aa::Aa;
use camera::{CameraError, PixelRay, RayCamera};
pub use stats::RenderStats;

/// Side of the square tiles traced in parallel.
pub const TILE: u32 = 32;
/// Block-size classes (log2 of the side) for the mean-value statistics.
pub const MV_LEVELS: usize = 8;
/// Largest accepted image side.
pub const MAX_SIZE: u32 = 16384;

/// How visibility is computed.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Beams of rays with rejection and inclusion tests (the default).
    #[default]
    Beam,
    /// One guaranteed interval ray per pixel, no beams.
    Pixel,
    /// Fixed-step point sampling along each ray; misses thin features.
    Point {
        /// Samples per ray over its clipped range.
        steps: u32,
    },
}

/// What to render and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Worker threads (None: rayon's default, one per core).
    pub threads: Option<usize>,
    /// Visibility method.
    pub method: Method,
    /// Produce a 16-bit depth image.
    pub want_depth: bool,
    /// Produce a normal image.
    pub want_normals: bool,
    /// Produce a map of how each pixel was decided.
    pub want_classify: bool,
    /// Print tile progress on stderr.
    pub progress: bool,
    /// Prune large functions to each tile and block (see
    /// [`crate::ir::prune`]); off only to measure what it saves.
    pub prune: bool,
}

impl RenderOptions {
    /// Beam method, default threads, colour image only.
    pub fn new(width: u32, height: u32) -> RenderOptions {
        RenderOptions {
            width,
            height,
            threads: None,
            method: Method::Beam,
            want_depth: false,
            want_normals: false,
            want_classify: false,
            progress: false,
            prune: true,
        }
    }
}

/// Everything a render produces.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The shaded image, sRGB.
    pub image: RgbImage,
    /// Depth (see [`output::depth_image`]) if asked for.
    pub depth: Option<ImageBuffer<Luma<u16>, Vec<u16>>>,
    /// Normals as `(n + 1) / 2` if asked for.
    pub normals: Option<RgbImage>,
    /// How each pixel was decided if asked for: blue rejected block,
    /// green included block, red single ray, black outside the bounds.
    pub classify: Option<RgbImage>,
    /// Row-major: whether the pixel's ray hit a surface (with
    /// anti-aliasing: whether any of its samples did).
    pub hit_mask: Vec<bool>,
    /// Row-major: the ray parameter of the hit, +inf for none (with
    /// anti-aliasing: the nearest hit among the pixel's samples).
    pub depth_t: Vec<f64>,
    /// Row-major: linear colour, the area-weighted mean over the pixel's
    /// samples (one sample without anti-aliasing).
    pub linear: Vec<[f64; 3]>,
    /// Row-major: fraction of the pixel (by sample area) whose samples hit.
    pub coverage: Vec<f64>,
    /// Row-major: samples taken in the pixel (1 without anti-aliasing).
    pub samples: Vec<u32>,
    /// Counters and times.
    pub stats: RenderStats,
}

/// Why a render could not run.
#[derive(Clone, Debug, PartialEq)]
pub enum RenderError {
    /// Width or height is 0 or above [`MAX_SIZE`].
    BadSize(u32, u32),
    /// The scene has no objects.
    NoObjects,
    /// The number of evaluators differs from the number of objects.
    EvaluatorCount {
        /// Objects in the scene.
        objects: usize,
        /// Evaluators passed.
        evaluators: usize,
    },
    /// The camera cannot form rays.
    Camera(CameraError),
    /// The bounds are empty or not finite.
    BadBounds,
    /// The thread pool could not be built.
    Threads(String),
    /// Anti-aliasing parameters out of range.
    BadAa(String),
    /// An object's function is undefined at every point of the bounds.
    Undefined(String),
}

impl std::fmt::Display for RenderError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RenderError::BadSize(w, h) => {
                write!(
                    f,
                    "image size {w}x{h} is invalid (each side 1..={MAX_SIZE})"
                )
            }
            RenderError::NoObjects => write!(f, "the scene has no objects to render"),
            RenderError::EvaluatorCount {
                objects,
                evaluators,
            } => write!(f, "{objects} objects but {evaluators} evaluators"),
            RenderError::Camera(e) => write!(f, "bad camera: {e}"),
            RenderError::BadBounds => write!(f, "scene bounds are empty or not finite"),
            RenderError::Threads(e) => write!(f, "cannot start render threads: {e}"),
            RenderError::BadAa(e) => write!(f, "bad anti-aliasing: {e}"),
            RenderError::Undefined(name) => write!(
                f,
                "object `{name}` is undefined everywhere inside the bounds \
                 (e.g. a division by zero or the square root of a negative \
                 number), so it has no surface to draw"
            ),
        }
    }
}

impl std::error::Error for RenderError {}

/// A ray's hit.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f64,
    /// Index of the object hit.
    pub obj: usize,
    /// The ray started inside a solid (hit at its clip start).
    pub inside: bool,
}

/// How a pixel was decided.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Class {
    /// Its ray misses the bounds.
    Outside,
    /// Its block was rejected: no surface.
    Background,
    /// Its block passed the inclusion test: bracketed refinement.
    Included,
    /// A single ray (or a point march).
    Ray,
}

/// Functions with fewer live ops than this are not pruned.
const PRUNE_MIN_OPS: usize = 64;
/// A pruned function replaces a native one only if it is at least this
/// many times shorter: it runs in the interpreter, which costs about 3-7x
/// the JIT per op (`ibeam bench eval`).
const PRUNE_GAIN_NATIVE: usize = 8;
/// ... and an interpreted one if it is at least this many times shorter.
const PRUNE_GAIN_INTERPRETED: usize = 2;

/// The region the evaluations for the rays through the pixel centres
/// `xs × ys` over `t` happen in: their beam's hull (not clipped to the
/// bounds, which the tracer's own boxes overhang by rounding), widened by
/// a relative 1e-9 so that boxes the tracer rounds outward stay inside it.
/// An evaluation that still falls outside uses the whole function (see
/// `crate::eval::regional`).
pub(crate) fn beam_region(
    tr: &Tracer<'_>,
    xs: (f64, f64),
    ys: (f64, f64),
    t: Interval,
) -> Option<IBox> {
    let region = tr.cam.corners(xs, ys).hull(t);
    if region
        .iter()
        .any(|c| c.is_empty() || !c.lo.is_finite() || !c.hi.is_finite())
    {
        return None;
    }
    Some(region.map(|c| {
        let pad = 1e-9 * (c.width() + c.lo.abs().max(c.hi.abs())) + f64::MIN_POSITIVE;
        Interval::new(c.lo - pad, c.hi + pad)
    }))
}

/// Evaluators (some pruned) and the live op count of each one's function.
pub(crate) type PrunedEvals = (Vec<Arc<dyn Evaluator>>, Vec<usize>);

/// The scene's evaluators with every function that shrinks enough pruned
/// to `region` (see [`crate::ir::prune`]) and run by the interpreter, and
/// their live op counts; `None` when none does. Exact on the region: use
/// them only for evaluations inside it.
pub(crate) fn prune_evals(
    tr: &Tracer<'_>,
    region: IBox,
    st: &mut RenderStats,
) -> Option<PrunedEvals> {
    if !tr.prune || !tr.live_ops.iter().any(|&n| n >= PRUNE_MIN_OPS) {
        return None;
    }
    let mut any = false;
    let mut live = tr.live_ops.clone();
    let evals = tr
        .evals
        .iter()
        .zip(live.iter_mut())
        .map(|(e, n)| {
            let before = *n;
            if before < PRUNE_MIN_OPS {
                return None;
            }
            // Prune what `e` already pruned when the new region lies in
            // the old one; else start again from the whole function.
            let whole = e.whole().cloned().unwrap_or_else(|| Arc::clone(e));
            let (source, before) = match e.valid_region() {
                Some(r) if !crate::interval::boxes::box_within(&region, &r) => {
                    let f = whole.function()?;
                    (f, f.live_count())
                }
                _ => (e.function()?, before),
            };
            let gain = if whole.is_native() {
                PRUNE_GAIN_NATIVE
            } else {
                PRUNE_GAIN_INTERPRETED
            };
            let p = crate::ir::prune::prune_to_at_most(source, region, before / gain)?;
            let after = p.function.live_count();
            any = true;
            *n = after;
            st.pruned_ops_before += before as u64;
            st.pruned_ops_after += after as u64;
            Some(Arc::new(crate::eval::regional::Regional {
                region,
                pruned: crate::eval::interp::Interpreter::new(p.function),
                whole,
            }) as Arc<dyn Evaluator>)
        })
        .collect::<Vec<Option<Arc<dyn Evaluator>>>>()
        .into_iter()
        .zip(tr.evals)
        .map(|(p, e)| p.unwrap_or_else(|| Arc::clone(e)))
        .collect();
    any.then_some((evals, live))
}

/// Evaluators pruned to the tile's beam: the rays through its pixel
/// centres over their clipped T ranges.
fn prune_to_tile(
    tr: &Tracer<'_>,
    tile: &beam::TileRays,
    th: u32,
    st: &mut RenderStats,
) -> Option<PrunedEvals> {
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for &(a, c) in tile.slabs.iter().flatten() {
        t0 = t0.min(a);
        t1 = t1.max(c);
    }
    if t0.partial_cmp(&t1).is_none_or(|o| o.is_gt()) {
        return None;
    }
    let xs = (f64::from(tile.x0) + 0.5, f64::from(tile.x0 + tile.w) - 0.5);
    let ys = (f64::from(tile.y0) + 0.5, f64::from(tile.y0 + th) - 0.5);
    prune_evals(tr, beam_region(tr, xs, ys, Interval::new(t0, t1))?, st)
}

/// Shared read-only state of one render.
pub(crate) struct Tracer<'a> {
    pub cam: RayCamera,
    pub evals: &'a [Arc<dyn Evaluator>],
    pub colors: Vec<[f64; 3]>,
    pub lights: &'a [Light],
    pub bounds: Bounds,
    pub diag: f64,
    /// Live ops of each evaluator's function (0 when it has none).
    pub live_ops: Vec<usize>,
    /// Prune large functions to tiles and blocks.
    pub prune: bool,
    /// Every object is proven constant along every ray inside the bounds
    /// (2D models viewed along the missing axis): a block's T range then
    /// needs no bisection.
    pub flat: bool,
}

impl<'a> Tracer<'a> {
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
            ..*self
        }
    }

    pub(crate) fn interval(&self, k: usize, b: IBox, st: &mut RenderStats) -> Interval {
        st.interval_evals += 1;
        self.evals[k].interval(b)
    }
    /// F over `b`, tightened where it straddles 0 by the mean-value form
    /// `f(c) + ∇F(b)·(b − c)` (c the box centre), intersected with the
    /// natural enclosure. Sound wherever the evaluator's gradient
    /// enclosure covers the (generalised) gradient of f over the box; it is
    /// used only when every gradient bound is finite, which rules out the
    /// poles and domain edges where it would not.
    pub(crate) fn interval_tight(
        &self,
        k: usize,
        b: IBox,
        level: usize,
        st: &mut RenderStats,
    ) -> Interval {
        let f = self.interval(k, b, st);
        if f.is_empty() || f.lo > 0.0 || f.hi < 0.0 {
            return f;
        }
        // Where the form seldom decides anything (min/max-heavy functions,
        // whose gradients are discontinuous), it only costs gradient
        // evaluations: after 64 tries at one block size (it pays off on
        // small blocks first) with under 1 in 32 winning, the tile stops
        // using it at that size. Counts are per tile, so the choice does
        // not depend on the thread count. Flat scenes (2D models seen
        // along their missing axis) skip it outright: their functions are
        // min/max trees of thousands of ops, where it measured 7 wins in
        // 13,833 tries on prospero at 512² while compiling and running
        // the interval-gradient evaluator doubled the render time.
        let lv = &st.mean_value_levels[level.min(MV_LEVELS - 1)];
        if self.flat || (lv.0 >= 64 && lv.1 * 32 < lv.0) {
            return f;
        }
        if !b.iter().all(|c| c.lo.is_finite() && c.hi.is_finite()) {
            return f;
        }
        let c: [f64; 3] = b.map(|i| i.mid());
        let g = self.interval_grad(k, b, st);
        if !g.d.iter().all(|d| d.lo.is_finite() && d.hi.is_finite()) {
            return f;
        }
        let fc = self.interval(k, crate::interval::boxes::point_box(c), st);
        if fc.is_empty() || !fc.lo.is_finite() || !fc.hi.is_finite() {
            return f;
        }
        let mut mv = fc;
        for i in 0..3 {
            mv = mv.add(g.d[i].mul(b[i].sub(Interval::point(c[i]))));
        }
        let (lo, hi) = (f.lo.max(mv.lo), f.hi.min(mv.hi));
        let win = lo > 0.0 || hi < 0.0;
        st.mean_value_tries += 1;
        st.mean_value_wins += u64::from(win);
        let lv = &mut st.mean_value_levels[level.min(MV_LEVELS - 1)];
        lv.0 += 1;
        lv.1 += u64::from(win);
        if lo <= hi { Interval::new(lo, hi) } else { f }
    }
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
    pub(crate) fn point(&self, k: usize, p: [f64; 3], st: &mut RenderStats) -> f64 {
        st.point_evals += 1;
        self.evals[k].point(p)
    }
    pub(crate) fn point_grad(&self, k: usize, p: [f64; 3], st: &mut RenderStats) -> Grad {
        st.point_evals += 1;
        self.evals[k].point_grad(p)
    }
}

struct TileOut {
    x0: u32,
    y0: u32,
    w: u32,
    h: u32,
    linear: Vec<[f64; 3]>,
    /// Lights shadowed at each sample (bit per light; see `shade::shade`).
    shadowed: Vec<u64>,
    coverage: Vec<f64>,
    samples: Vec<u32>,
    // Kept compact: a full-size render holds every tile at once.
    depth: Vec<f64>,
    normals: Option<Vec<Rgb<u8>>>,
    class: Option<Vec<Rgb<u8>>>,
    stats: RenderStats,
}

/// Renders `scene` with one evaluator per object (same order):
/// `evaluators[i]` evaluates `scene.objects[i].function` (the renderer
/// reads the functions only to see which of x, y, z they use).
pub fn render(
    scene: &Scene,
    evaluators: &[Arc<dyn Evaluator>],
    opts: &RenderOptions,
) -> Result<RenderOutput, RenderError> {
    render_aa(scene, evaluators, opts, Aa::None)
}

/// [`render`] with anti-aliasing (see [`aa`]). The depth, normal and
/// classification images of a `grid:N` render show one sample per pixel
/// (the one right of and below the centre).
pub fn render_aa(
    scene: &Scene,
    evaluators: &[Arc<dyn Evaluator>],
    opts: &RenderOptions,
    aa: Aa,
) -> Result<RenderOutput, RenderError> {
    let start = Instant::now();
    // Native code compiles lazily, on an evaluator kind's first use during
    // the render; that time is reported as compilation, not rendering.
    let compiled = |evals: &[Arc<dyn Evaluator>]| -> f64 {
        evals
            .iter()
            .map(|e| e.compile_time().as_secs_f64())
            .sum::<f64>()
            * 1e3
    };
    let compiled_before = compiled(evaluators);
    let (w, h) = (opts.width, opts.height);
    if w == 0 || h == 0 || w > MAX_SIZE || h > MAX_SIZE {
        return Err(RenderError::BadSize(w, h));
    }
    aa.validate().map_err(RenderError::BadAa)?;
    let s = aa.grid_factor();
    if u64::from(w.max(h)) * u64::from(s) > u64::from(u32::MAX / 2) {
        return Err(RenderError::BadAa(format!(
            "grid:{s} on {w}x{h} is too many samples"
        )));
    }
    if scene.objects.is_empty() {
        return Err(RenderError::NoObjects);
    }
    if evaluators.len() != scene.objects.len() {
        return Err(RenderError::EvaluatorCount {
            objects: scene.objects.len(),
            evaluators: evaluators.len(),
        });
    }
    let b = scene.bounds;
    if !(0..3).all(|i| b.min[i].is_finite() && b.max[i].is_finite() && b.min[i] <= b.max[i]) {
        return Err(RenderError::BadBounds);
    }
    // EMPTY over the whole bounds proves f undefined at every point there:
    // say so rather than draw an empty image.
    let whole = camera::bounds_box(&b);
    for (o, e) in scene.objects.iter().zip(evaluators) {
        // The interpreter answers this one question without compiling.
        let f = match e.function() {
            Some(f) => crate::eval::interp::Interpreter::new(f.clone()).interval(whole),
            None => e.interval(whole),
        };
        if f.is_empty() {
            return Err(RenderError::Undefined(o.name.clone()));
        }
    }
    let cam = RayCamera::new(&scene.camera, w * s, h * s).map_err(RenderError::Camera)?;
    let tr = Tracer {
        cam,
        evals: evaluators,
        colors: scene.objects.iter().map(|o| o.color).collect(),
        lights: &scene.lights,
        bounds: b,
        diag: camera::norm(camera::sub(b.max, b.min)),
        live_ops: evaluators
            .iter()
            .map(|e| e.function().map_or(0, |f| f.live_count()))
            .collect(),
        prune: opts.prune,
        flat: constant_along_rays(&cam, scene),
    };
    // IAA traces split pixels' sub-samples on the 2^depth× image, with its
    // tighter depth tolerance (the samples are those of grid:2^depth).
    let fine = match aa {
        Aa::Iaa { depth, .. } => Some(Tracer {
            cam: RayCamera::new(&scene.camera, w << depth, h << depth)
                .map_err(RenderError::Camera)?,
            evals: evaluators,
            colors: tr.colors.clone(),
            lights: &scene.lights,
            bounds: b,
            diag: tr.diag,
            live_ops: tr.live_ops.clone(),
            prune: tr.prune,
            flat: tr.flat,
        }),
        _ => None,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads.unwrap_or(0))
        .build()
        .map_err(|e| RenderError::Threads(e.to_string()))?;
    let mut tiles = Vec::new();
    for y0 in (0..h).step_by(TILE as usize) {
        for x0 in (0..w).step_by(TILE as usize) {
            tiles.push((x0, y0, TILE.min(w - x0), TILE.min(h - y0)));
        }
    }
    let done = AtomicUsize::new(0);
    let n_tiles = tiles.len();
    let bg_linear = scene.render.background;
    let background = output::srgb_pixel(bg_linear);
    let outs: Vec<TileOut> = pool.install(|| {
        tiles
            .par_iter()
            .map(|&(x0, y0, tw, th)| {
                let mut out =
                    render_tile(&tr, opts, x0 * s, y0 * s, tw * s, th * s, bg_linear, None);
                if s > 1 {
                    out = downsample(out, s);
                }
                anti_alias(&tr, fine.as_ref(), opts, aa, &mut out, bg_linear);
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                if opts.progress {
                    eprint!("\rrendering: {n}/{n_tiles} tiles");
                }
                out
            })
            .collect()
    });
    if opts.progress {
        eprintln!();
    }
    let out_start = Instant::now();
    let npx = (w as usize) * (h as usize);
    let mut stats = RenderStats {
        width: w,
        height: h,
        ..RenderStats::default()
    };
    let mut color = vec![background; npx];
    let mut linear = vec![bg_linear; npx];
    let mut coverage = vec![0.0; npx];
    let mut samples = vec![1u32; npx];
    let mut hit_mask = vec![false; npx];
    let mut depth_t = vec![f64::INFINITY; npx];
    let mut normals = opts.want_normals.then(|| vec![Rgb([0u8; 3]); npx]);
    let mut class = opts.want_classify.then(|| vec![Rgb([0u8; 3]); npx]);
    for t in &outs {
        stats.merge(&t.stats);
        for j in 0..t.h {
            for i in 0..t.w {
                let src = (j * t.w + i) as usize;
                let dst = ((t.y0 + j) as usize) * (w as usize) + (t.x0 + i) as usize;
                color[dst] = output::srgb_pixel(t.linear[src]);
                linear[dst] = t.linear[src];
                coverage[dst] = t.coverage[src];
                samples[dst] = t.samples[src];
                depth_t[dst] = t.depth[src];
                hit_mask[dst] = t.depth[src].is_finite();
                if let (Some(n), Some(tn)) = (normals.as_mut(), t.normals.as_ref()) {
                    n[dst] = tn[src];
                }
                if let (Some(c), Some(tc)) = (class.as_mut(), t.class.as_ref()) {
                    c[dst] = tc[src];
                }
            }
        }
    }
    stats.pixels_hit = hit_mask.iter().filter(|&&m| m).count() as u64;
    let image = output::rgb_image(w, h, &color);
    let depth = opts.want_depth.then(|| output::depth_image(w, h, &depth_t));
    let normals_img = normals.map(|px| output::rgb_image(w, h, &px));
    let classify = class.map(|px| output::rgb_image(w, h, &px));
    stats.output_ms = out_start.elapsed().as_secs_f64() * 1e3;
    let lazy_compile_ms = compiled(evaluators) - compiled_before;
    stats.compile_ms += lazy_compile_ms;
    stats.time_ms = start.elapsed().as_secs_f64() * 1e3 - lazy_compile_ms;
    Ok(RenderOutput {
        image,
        depth,
        normals: normals_img,
        classify,
        hit_mask,
        depth_t,
        linear,
        coverage,
        samples,
        stats,
    })
}

// Averages each s×s block of a tile traced at s× resolution, in linear
// light. Depth: the nearest hit; normals and classes: the sample at
// (s/2, s/2) of the block.
fn downsample(t: TileOut, s: u32) -> TileOut {
    let (w, h) = (t.w / s, t.h / s);
    let n = (w * h) as usize;
    let inv = 1.0 / f64::from(s * s);
    let mut linear = vec![[0.0; 3]; n];
    let mut coverage = vec![0.0; n];
    let mut depth = vec![f64::INFINITY; n];
    let pick = |v: &Vec<Rgb<u8>>| -> Vec<Rgb<u8>> {
        (0..h)
            .flat_map(|j| (0..w).map(move |i| (i, j)))
            .map(|(i, j)| v[((j * s + s / 2) * t.w + i * s + s / 2) as usize])
            .collect()
    };
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
        normals: t.normals.as_ref().map(pick),
        class: t.class.as_ref().map(pick),
        stats: t.stats,
    }
}

// Applies IAA to a tile (or, for the other modes, counts its samples):
// pixel-area tests, then the split pixels traced together at the fine
// resolution (`fine`: the tracer of the 2^depth× image), with beams, their
// other sub-samples masked out.
fn anti_alias(
    tr: &Tracer<'_>,
    fine: Option<&Tracer<'_>>,
    opts: &RenderOptions,
    aa: Aa,
    t: &mut TileOut,
    bg: [f64; 3],
) {
    let n = u64::from(t.w * t.h);
    match (aa, fine) {
        (Aa::Iaa { threshold, depth }, Some(fine)) => {
            let t0 = Instant::now();
            let mut st = std::mem::take(&mut t.stats);
            let mut px = aa::TilePixels {
                x0: t.x0,
                y0: t.y0,
                w: t.w,
                h: t.h,
                linear: &mut t.linear,
                depth: &mut t.depth,
                coverage: &mut t.coverage,
                samples: &mut t.samples,
                shadowed: &t.shadowed,
            };
            let split = aa::classify_tile(tr, &mut px, bg, threshold, &mut st);
            let f = 1u32 << depth;
            let sub = (depth > 0 && split.iter().any(|&s| s)).then(|| {
                let (fw, fh) = (t.w * f, t.h * f);
                let mask: Vec<bool> = (0..fh)
                    .flat_map(|j| (0..fw).map(move |i| (i, j)))
                    .map(|(i, j)| split[((j / f) * t.w + i / f) as usize])
                    .collect();
                let fine_opts = RenderOptions {
                    want_depth: false,
                    want_normals: false,
                    want_classify: false,
                    progress: false,
                    ..opts.clone()
                };
                let out = render_tile(
                    fine,
                    &fine_opts,
                    t.x0 * f,
                    t.y0 * f,
                    fw,
                    fh,
                    bg,
                    Some(&mask),
                );
                downsample(out, f)
            });
            if let Some(s) = &sub {
                st.merge(&s.stats);
            }
            aa::merge_split(
                &mut px,
                &split,
                sub.as_ref()
                    .map(|s| (&s.linear[..], &s.coverage[..], &s.depth[..])),
                f * f,
                &mut st,
            );
            st.aa_cpu_ms += ms_since(t0);
            t.stats = st;
        }
        _ => {
            let per = u64::from(aa.grid_factor()).pow(2);
            t.stats.aa_samples += n * per;
            t.stats.aa_samples_max = t.stats.aa_samples_max.max(per);
            if per > 1 {
                t.stats.aa_pixels_split += n;
            }
        }
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
    let one_direction = cam.dx == [0.0; 3] && cam.dy == [0.0; 3];
    one_direction
        && scene.objects.iter().all(|o| {
            let uses = o.function.uses_vars();
            (0..3).all(|i| !uses[i] || cam.d0[i] == 0.0)
        })
}

/// The classification map's colour of a pixel.
fn class_color(c: Class) -> Rgb<u8> {
    match c {
        Class::Outside => Rgb([0, 0, 0]),
        Class::Background => Rgb([30, 50, 140]),
        Class::Included => Rgb([40, 180, 70]),
        Class::Ray => Rgb([210, 60, 40]),
    }
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

#[allow(clippy::too_many_arguments)]
fn render_tile(
    tr: &Tracer<'_>,
    opts: &RenderOptions,
    x0: u32,
    y0: u32,
    tw: u32,
    th: u32,
    background: [f64; 3],
    mask: Option<&[bool]>,
) -> TileOut {
    let mut st = RenderStats::default();
    let t_trace = Instant::now();
    let n = (tw * th) as usize;
    let mut rays: Vec<PixelRay> = Vec::with_capacity(n);
    let mut slabs = Vec::with_capacity(n);
    for j in 0..th {
        for i in 0..tw {
            let r = tr.cam.pixel_ray(x0 + i, y0 + j);
            // Masked-out samples look like rays outside the bounds: beams
            // over them are rejected at once.
            let on = mask.is_none_or(|m| m[(j * tw + i) as usize]);
            slabs.push(if on { r.slab(&tr.bounds) } else { None });
            rays.push(r);
        }
    }
    let mut tile = beam::TileRays {
        x0,
        y0,
        w: tw,
        rays,
        slabs,
        hits: vec![None; n],
        class: vec![Class::Outside; n],
        included: Vec::new(),
    };
    let method = opts.method;
    let all: Vec<u32> = (0..tr.evals.len() as u32).collect();
    // Visibility inside the tile's beam runs on functions pruned to it;
    // shading and shadows, whose segments leave the beam, keep `tr`.
    let pruned = prune_to_tile(tr, &tile, th, &mut st);
    let local;
    let tr_vis = match &pruned {
        Some((evals, live)) => {
            local = tr.with_evals(evals, live.clone());
            &local
        }
        None => tr,
    };
    let tr_full = tr;
    let tr = tr_vis;
    match method {
        Method::Beam => beam::trace_tile(tr, &mut tile, th, &mut st),
        Method::Pixel | Method::Point { .. } => {
            for k in 0..n {
                if let Some((a, b)) = tile.slabs[k] {
                    let r = tile.rays[k];
                    tile.hits[k] = match method {
                        Method::Point { steps } => ray::march(tr, &r, a, b, &all, steps, &mut st),
                        _ => ray::trace_ray(tr, &r, a, b, &all, &mut st),
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
    st.trace_cpu_ms += ms_since(t_trace);

    // Hit points lie in the tile's beam: their normals may come from the
    // pruned functions too (the same bits).
    let t_shade = Instant::now();
    let surfs: Vec<Option<shade::Surf>> = (0..n)
        .map(|k| {
            tile.hits[k]
                .as_ref()
                .map(|h| shade::surface(tr, &tile.rays[k], h, &mut st))
        })
        .collect();
    st.shade_cpu_ms += ms_since(t_shade);
    let tr = tr_full;

    // Shadow beams over included blocks.
    let t_shadow = Instant::now();
    let nl = tr.lights.len();
    let mut lit_by_beam = vec![false; n * nl];
    for &(bx0, by0, bx1, by1) in &tile.included {
        for (li, light) in tr.lights.iter().enumerate() {
            if !light.shadows {
                continue;
            }
            let mut members = Vec::new();
            let mut pts = Vec::new();
            for j in by0..by1 {
                for i in bx0..bx1 {
                    let k = (j * tw + i) as usize;
                    let Some(s) = surfs[k] else { continue };
                    let facing = shade::light_dir(tr, light.kind, s.p)
                        .is_some_and(|(l, _)| camera::dot(s.n, l) > 0.0);
                    if facing {
                        members.push(k);
                        pts.push(s);
                    }
                }
            }
            if members.len() < 2 {
                continue;
            }
            st.shadow_beams += 1;
            if shade::shadow_beam(tr, &pts, light.kind, &mut st) {
                st.shadow_beams_ok += 1;
                st.shadow_rays_saved += members.len() as u64;
                for k in members {
                    lit_by_beam[k * nl + li] = true;
                }
            }
        }
    }
    st.shadow_cpu_ms += ms_since(t_shadow);

    let t_shade = Instant::now();
    let mut linear = vec![background; n];
    let mut shadowed = vec![0u64; n];
    let mut normals = opts.want_normals.then(|| vec![Rgb([0u8; 3]); n]);
    let mut shadow_ms = 0.0;
    for k in 0..n {
        if let Some(s) = &surfs[k] {
            let t0 = Instant::now();
            let (c, sh) = shade::shade(tr, s, &lit_by_beam[k * nl..(k + 1) * nl], &mut st);
            shadow_ms += ms_since(t0);
            linear[k] = c;
            shadowed[k] = sh;
            if let Some(nv) = normals.as_mut() {
                nv[k] = output::normal_pixel(Some(s.n));
            }
        }
    }
    // Per-pixel lighting time is dominated by shadow segments.
    st.shadow_cpu_ms += shadow_ms;
    st.shade_cpu_ms += (ms_since(t_shade) - shadow_ms).max(0.0);
    TileOut {
        x0,
        y0,
        w: tw,
        h: th,
        coverage: tile
            .hits
            .iter()
            .map(|h| if h.is_some() { 1.0 } else { 0.0 })
            .collect(),
        linear,
        shadowed,
        samples: vec![1; n],
        depth: tile
            .hits
            .iter()
            .map(|h| h.map_or(f64::INFINITY, |h| h.t))
            .collect(),
        normals,
        class: opts
            .want_classify
            .then(|| tile.class.iter().map(|&c| class_color(c)).collect()),
        stats: st,
    }
}
