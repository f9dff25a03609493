//! A whole render: the options checked, the image cut into tiles traced in
//! parallel (each with its anti-aliasing), and the tiles' outputs and
//! counters merged in tile order into the images.

mod assemble;
pub(crate) mod band;
mod pipeline;
pub(crate) mod subsample;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use crate::eval::{Evaluator, Single};
use crate::render::aa::SplitSamples;
use crate::render::aa::{self, Aa, AaError, NeighbourTiles, Sampling, TileEdges};
use crate::render::context::stats::RenderStats;
use crate::render::frame::assemble::assemble;
use crate::render::frame::band::{Band, FloatLayers, band};
use crate::render::frame::subsample::{PixelFacts, SplitJob, TileArea, downsample, trace_split};
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::tile::{ShadowHint, TileOut, TileSpec, ms_since, render_tile};
use crate::render::view::camera::{self, RayCamera};
use crate::render::view::output;
use crate::render::{MAX_SIZE, RenderError, RenderOptions, RenderOutput, TILE};
use crate::scene::Scene;

mod iaa;
use iaa::{anti_alias, edges_of};

/// Rows of tiles [`Frame::stream`]'s base renders run ahead of the first
/// row not yet handed to the sink, outside IAA: room for workers done with
/// a row to take tiles further on while its slowest tile finishes. Each
/// row held costs about 2 MB at 1024 pixels wide, so wider images hold
/// fewer (at most [`AHEAD_PIXELS`] pixels across the rows together, one
/// row at least).
const AHEAD_ROWS: usize = 8;

/// Image width times rows of tiles that the rows ahead hold at most.
const AHEAD_PIXELS: usize = 32768;

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
    Ok(Frame::new(scene, evaluators, opts, aa)?.render())
}

/// IAA's tracers of finer images.
struct FinerScopes<'a> {
    /// Entry `l` traces at 2^l× the resolution, for the split pixels
    /// sampled `l` levels below the pixel (`aa::Sampling::level`): the
    /// depth, one below it (covered pixels) and 1 (shading alone).
    levels: Vec<Option<Scope<'a>>>,
}

impl<'a> FinerScopes<'a> {
    // The tracer of level `l` (one exists for every level a pixel can get).
    fn at(&self, l: u32) -> Option<&Scope<'a>> {
        self.levels.get(l as usize).and_then(Option::as_ref)
    }
}

/// A render whose scene, evaluators and options have been checked, ready
/// to trace: whole into memory ([`Frame::render`]) or streamed in bands
/// of rows ([`Frame::stream`]), with the same pixels and counters.
pub struct Frame<'a> {
    evaluators: &'a [Arc<dyn Evaluator>],
    opts: RenderOptions,
    aa: Aa,
    tr: Scope<'a>,
    fine: Option<FinerScopes<'a>>,
    pool: rayon::ThreadPool,
    bg: [f64; 3],
    depth_range: (f64, f64),
    start: Instant,
    // Compile time before the render, ms.
    compiled_before: f64,
    float: FloatLayers,
    progress: Option<Progress>,
    cancel: Option<Arc<AtomicBool>>,
}

/// A caller's progress report: called with (tiles done, tiles in all)
/// after each tile, from the render's worker threads.
pub type Progress = Box<dyn Fn(usize, usize) + Send + Sync>;

impl<'a> Frame<'a> {
    /// Checks a render and sets it up (cameras, threads) without tracing.
    pub fn new(
        scene: &'a Scene,
        evaluators: &'a [Arc<dyn Evaluator>],
        opts: &RenderOptions,
        aa: Aa,
    ) -> Result<Frame<'a>, RenderError> {
        let start = Instant::now();
        let compiled_before = compile_ms(evaluators);
        check(scene, evaluators, opts, aa)?;
        let (w, h) = (opts.width, opts.height);
        let s = aa.grid_factor();
        let cam = RayCamera::new(&scene.camera, w * s, h * s).map_err(RenderError::Camera)?;
        let tr = Scope::new(scene, evaluators, cam, opts.prune).with_enclosure(opts.enclosure);
        // IAA traces each split pixel's sub-samples on the 2^level× image of
        // its level (`aa::Sampling::level`, where grid:2^level puts them),
        // with the depth tolerance of the finest level's, 2^depth×,
        // whatever the level: every sub-sample of a depth-d render has
        // grid:2^d's tolerance (a coarser one moved the points shaded).
        let finer = |level: u32, depth: u32| -> Result<Scope<'a>, RenderError> {
            let cam = RayCamera::new(&scene.camera, w << level, h << level)
                .map_err(RenderError::Camera)?
                .with_tolerance_of_finer(1 << (depth - level));
            let mut scope = tr.with_camera(cam);
            scope.ctx.sub_samples = true;
            Ok(scope)
        };
        let fine = match aa {
            Aa::Iaa { depth, .. } => {
                let used = Sampling::SPLIT.map(|s| s.level(depth));
                let levels = (0..=depth)
                    .map(|l| {
                        (l > 0 && used.contains(&l))
                            .then(|| finer(l, depth))
                            .transpose()
                    })
                    .collect::<Result<_, _>>()?;
                Some(FinerScopes { levels })
            }
            _ => None,
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(opts.threads.unwrap_or(0))
            .build()
            .map_err(|e| RenderError::Threads(e.to_string()))?;
        Ok(Frame {
            evaluators,
            opts: opts.clone(),
            aa,
            tr,
            fine,
            pool,
            bg: scene.render.background,
            depth_range: output::depth_range(&scene.camera, &scene.bounds),
            start,
            compiled_before,
            float: FloatLayers::default(),
            progress: None,
            cancel: None,
        })
    }

    /// Makes [`Frame::stream`]'s bands carry the float images `float`
    /// names as well (for 16-bit and floating-point files).
    pub fn with_float_layers(mut self, float: FloatLayers) -> Frame<'a> {
        self.float = float;
        self
    }

    /// Reports progress to `report` after each tile, instead of the plain
    /// counter that [`RenderOptions::progress`] prints (the CLI draws a
    /// progress bar with it).
    pub fn with_progress(mut self, report: Progress) -> Frame<'a> {
        self.progress = Some(report);
        self
    }

    /// Makes [`Frame::stream`] stop before its next row of tiles once
    /// `cancel` is set, with [`RenderError::Cancelled`]: a live view drops
    /// a stale render within a row's time instead of finishing it.
    pub fn with_cancel(mut self, cancel: Arc<AtomicBool>) -> Frame<'a> {
        self.cancel = Some(cancel);
        self
    }

    /// The camera's ray parameter range over the scene bounds, which the
    /// depth image maps to 0..=65534 (see [`output::depth_range`]).
    pub fn depth_range(&self) -> (f64, f64) {
        self.depth_range
    }

    /// Traces every tile at once and keeps the whole image in memory
    /// (about 100 bytes a pixel at the peak).
    pub fn render(self) -> RenderOutput {
        let all = tiles(self.opts.width, self.opts.height);
        let done = AtomicUsize::new(0);
        let mut outs = self.trace(&all);
        // Only IAA's shadow-edge rule reads the tiles' sides.
        let edges: Vec<TileEdges> = match self.aa {
            Aa::Iaa { .. } => outs.iter().map(edges_of).collect(),
            _ => Vec::new(),
        };
        let cols = self.opts.width.div_ceil(TILE) as usize;
        let beside = |i: usize| NeighbourTiles {
            above: i.checked_sub(cols).and_then(|k| edges.get(k)),
            below: edges.get(i + cols),
            left: (!i.is_multiple_of(cols))
                .then(|| edges.get(i - 1))
                .flatten(),
            right: (i % cols + 1 < cols).then(|| edges.get(i + 1)).flatten(),
        };
        self.anti_alias_tiles(&mut outs, beside, &done, all.len());
        if self.opts.progress && self.progress.is_none() {
            eprintln!();
        }
        let mut out = self
            .pool
            .install(|| assemble(&outs, &self.opts, self.depth_range));
        drop(outs);
        self.finish_times(&mut out.stats);
        out
    }

    /// Traces the tiles in image order, workers taking the next tile as
    /// they free up ([`pipeline`]), and hands each finished band of image
    /// rows to `sink`, top to bottom, so memory holds a few rows of tiles
    /// ([`AHEAD_ROWS`] at most; three with IAA, whose rule reads the next
    /// row's base samples) and a band, not the image. `sink` runs on the
    /// worker that finished the band's last tile while the others trace on.
    /// Returns the counters (the same as [`Frame::render`]'s); its
    /// `output_ms` includes the time spent in `sink`. Stops at the first
    /// error of `sink`, or once the cancel flag is set
    /// ([`Frame::with_cancel`]).
    pub fn stream<E: Send + From<RenderError>>(
        self,
        mut sink: impl FnMut(&Band) -> Result<(), E> + Send,
    ) -> Result<RenderStats, E> {
        let (w, h) = (self.opts.width, self.opts.height);
        let mut stats = RenderStats {
            width: w,
            height: h,
            ..RenderStats::default()
        };
        let done = AtomicUsize::new(0);
        let mut output_ms = 0.0;
        let (opts, float, depth_range) = (&self.opts, self.float, self.depth_range);
        // IAA's shadow-edge rule reads the base samples just outside a
        // tile (`aa::NeighbourTiles`), the next row's included: its base
        // renders run at most a row past the next row's.
        let ahead = match self.aa {
            Aa::Iaa { .. } => 3,
            _ => (AHEAD_PIXELS / w as usize).clamp(1, AHEAD_ROWS),
        };
        self.stream_rows(ahead, &done, |outs, y0| -> Result<(), E> {
            if self.cancelled() {
                return Err(RenderError::Cancelled.into());
            }
            let t0 = Instant::now();
            sink(&band(&outs, opts, float, y0, depth_range, &mut stats))?;
            output_ms += ms_since(t0);
            Ok(())
        })?;
        if self.opts.progress && self.progress.is_none() {
            eprintln!();
        }
        stats.output_ms = output_ms;
        self.finish_times(&mut stats);
        Ok(stats)
    }

    fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }

    // Drops the tracers' groups of tiles above output row `y` (see
    // `crate::render::prune::groups`), which no later row of tiles reads.
    fn release_groups_above(&self, y: u32) {
        let s = self.aa.grid_factor();
        self.tr.pruner.groups.release_above(y * s);
        if let Some(fine) = &self.fine {
            for (l, t) in fine.levels.iter().enumerate() {
                if let Some(t) = t {
                    t.pruner.groups.release_above(y << l);
                }
            }
        }
    }

    // Traces the base render of `tiles` in parallel (a `grid:N` render's
    // samples averaged); the results in the order of `tiles`.
    fn trace(&self, tiles: &[(u32, u32, u32, u32)]) -> Vec<TileOut> {
        self.pool.install(|| {
            tiles
                .par_iter()
                .map(|&tile| self.trace_tile(tile))
                .collect()
        })
    }

    // The base render of one tile (x0, y0, w, h).
    fn trace_tile(&self, (x0, y0, tw, th): (u32, u32, u32, u32)) -> TileOut {
        if let Aa::Iaa { threshold, .. } = self.aa {
            return self.trace_classified((x0, y0, tw, th), threshold);
        }
        let s = self.aa.grid_factor();
        let spec = TileSpec::plain(x0 * s, y0 * s, tw * s, th * s);
        let out = render_tile(&self.tr, &self.opts, spec, self.bg);
        if s > 1 { downsample(out, s) } else { out }
    }

    // IAA's base render of one tile (`area`: x0, y0, w, h): the
    // pixel-area tests first, then the centre rays of the pixels they did
    // not prove background, refined in their included cells' brackets or
    // traced one by one from where their areas were proven empty (the
    // tests already found the beams over pixel centres undecided there).
    // The tests' findings go with the tile to its anti-aliasing.
    fn trace_classified(&self, area: (u32, u32, u32, u32), threshold: f64) -> TileOut {
        let t0 = Instant::now();
        let mut st = TileState::default();
        let c = aa::classify_tile(&self.tr, area, threshold, &mut st);
        let tests_ms = ms_since(t0);
        let (x0, y0, w, h) = area;
        let spec = TileSpec {
            x0,
            y0,
            w,
            h,
            mask: Some(&c.traced),
            floors: Some(&c.floors),
            shadow_hints: None,
            brackets: Some(&c.brackets),
            mean_value: true,
            rays_from_floors: true,
        };
        let mut out = render_tile(&self.tr, &self.opts, spec, self.bg);
        st.stats.aa_tests_cpu_ms += tests_ms;
        st.stats.aa_cpu_ms += tests_ms;
        out.state.stats.merge(&st.stats);
        out.classified = Some(Box::new(c));
        out
    }

    // Anti-aliases traced tiles in parallel (`beside(i)`: the base samples
    // around `outs[i]`), reporting progress after each.
    fn anti_alias_tiles<'e>(
        &self,
        outs: &mut [TileOut],
        beside: impl Fn(usize) -> NeighbourTiles<'e> + Sync,
        done: &AtomicUsize,
        total: usize,
    ) {
        self.pool.install(|| {
            outs.par_iter_mut()
                .enumerate()
                .for_each(|(i, out)| self.anti_alias_one(out, beside(i), done, total))
        })
    }

    // Anti-aliases one traced tile (`beside`: the base samples around it)
    // and reports progress.
    fn anti_alias_one(
        &self,
        out: &mut TileOut,
        beside: NeighbourTiles<'_>,
        done: &AtomicUsize,
        total: usize,
    ) {
        let (tr, opts, bg) = (&self.tr, &self.opts, self.bg);
        anti_alias(tr, self.fine.as_ref(), opts, self.aa, out, beside, bg);
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(report) = &self.progress {
            report(n, total);
        } else if opts.progress {
            eprint!("\rrendering: {n}/{total} tiles");
        }
    }

    // Sets the render-wide times: native code compiles lazily, on an
    // evaluator kind's first use during the render, on the render's
    // threads or in the background. All of it is reported as compilation;
    // what the render waited for is not counted as rendering.
    fn finish_times(&self, stats: &mut RenderStats) {
        let end = Instant::now();
        stats.compile_ms += compile_ms(self.evaluators) - self.compiled_before;
        let spans = self.evaluators.iter().flat_map(|e| e.compile_waits());
        let waited = span_union(spans, (self.start, end));
        stats.compile_wait_ms = waited.as_secs_f64() * 1e3;
        stats.time_ms = (end - self.start).saturating_sub(waited).as_secs_f64() * 1e3;
    }
}

// Time the evaluators have spent compiling native code so far, ms.
fn compile_ms(evals: &[Arc<dyn Evaluator>]) -> f64 {
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    evals.iter().map(|e| ms(e.compile_time())).sum()
}

/// The length of the union of `spans` clipped to `within`: the wall time
/// during which at least one of them ran.
fn span_union(
    spans: impl IntoIterator<Item = (Instant, Instant)>,
    (from, to): (Instant, Instant),
) -> std::time::Duration {
    let mut clipped: Vec<(Instant, Instant)> = spans
        .into_iter()
        .map(|(a, b)| (a.max(from), b.min(to)))
        .filter(|(a, b)| a < b)
        .collect();
    clipped.sort();
    let mut total = std::time::Duration::ZERO;
    let mut open: Option<(Instant, Instant)> = None;
    for (a, b) in clipped {
        open = match open {
            Some((oa, ob)) if a <= ob => Some((oa, ob.max(b))),
            Some((oa, ob)) => {
                total += ob - oa;
                Some((a, b))
            }
            None => Some((a, b)),
        };
    }
    total + open.map_or(std::time::Duration::ZERO, |(a, b)| b - a)
}

// Refuses options, scenes and evaluators that cannot be rendered.
fn check(
    scene: &Scene,
    evaluators: &[Arc<dyn Evaluator>],
    opts: &RenderOptions,
    aa: Aa,
) -> Result<(), RenderError> {
    let (w, h) = (opts.width, opts.height);
    if w == 0 || h == 0 || w > MAX_SIZE || h > MAX_SIZE {
        return Err(RenderError::BadSize(w, h));
    }
    aa.validate().map_err(RenderError::BadAa)?;
    let s = aa.grid_factor();
    if u64::from(w.max(h)) * u64::from(s) > u64::from(u32::MAX / 2) {
        return Err(RenderError::BadAa(AaError::TooManySamples {
            grid: s,
            width: w,
            height: h,
        }));
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
    Ok(())
}

// The tiles of a w×h image, row by row: (x0, y0, width, height).
fn tiles(w: u32, h: u32) -> Vec<(u32, u32, u32, u32)> {
    (0..h)
        .step_by(TILE as usize)
        .flat_map(|y0| tile_row(w, h, y0))
        .collect()
}

// The row of tiles whose top is image row y0, left to right.
fn tile_row(w: u32, h: u32, y0: u32) -> Vec<(u32, u32, u32, u32)> {
    (0..w)
        .step_by(TILE as usize)
        .map(|x0| (x0, y0, TILE.min(w - x0), TILE.min(h - y0)))
        .collect()
}

#[cfg(test)]
#[path = "frame_tests.rs"]
mod tests;
