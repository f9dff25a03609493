//! The guaranteed beam tracer, after Flórez et al.
//!
//! The image is cut into 32×32 tiles traced in parallel ([`Frame`]). Each
//! tile is a block of pixels whose rays form a beam; the tracer rejects
//! empty stretches of the beam with interval arithmetic, settles blocks
//! whose rays all cross the surface in a proven bracket (inclusion test),
//! and splits the rest down to single rays with guaranteed first-root
//! isolation; shadows and anti-aliasing ([`aa`]) use the same tests. Two
//! baselines share the code: [`Method::Pixel`] (one interval ray per
//! pixel) and [`Method::Point`] (fixed-step point sampling). Output is the
//! same bytes for any thread count.
//!
//! The folders are layers, each using only those before it (see
//! `docs/architecture.md`): `view` (camera, rays, pixels) → `context`
//! (the evaluation context) → `enclose` (what an evaluation proves) →
//! `prune` (evaluators specialised to regions) → `trace` (the sweeps
//! along rays) → `light` (shading, shadows) → `aa` → `tile` → `frame`.

// The layers, lowest first: each uses only those above it in this list
// (`tests/architecture` checks it).
pub mod aa;
mod context;
mod enclose;
mod frame;
mod light;
mod prune;
mod tile;
mod trace;
mod view;

use image::{ImageBuffer, Luma, RgbImage};

pub use aa::{Aa, AaError};
pub use context::is_flat;
pub use context::stats::{self, RenderStats};
pub use frame::band::{Band, FloatLayers};
pub use frame::{Frame, Progress, render, render_aa};
pub use light::shade;
pub use trace::{beam, ray};
pub use view::{camera, fit, output};

use camera::CameraError;

/// Side of the square tiles traced in parallel.
pub const TILE: u32 = 32;
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
    /// Fill [`RenderOutput`]'s per-pixel buffers (`hit_mask`, `depth_t`,
    /// `linear`, `coverage`, `samples`); without them they are empty. A
    /// megapixel's buffers are 30 MB that the kernel faults in fresh for
    /// every render: a caller that keeps only the images saves that time.
    pub want_buffers: bool,
    /// Print a plain tile counter on stderr (unless a caller's report
    /// replaces it, see [`Frame::with_progress`]).
    pub progress: bool,
    /// Prune large functions to each tile and block (see
    /// [`crate::ir::prune`]); off only to measure what it saves.
    pub prune: bool,
    /// Which enclosure tightens a block's interval where it straddles 0.
    pub enclosure: Enclosure,
}

/// The enclosures a block's beam tests may read besides the natural
/// interval (see `enclose::mean_value::sign_bound`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Enclosure {
    /// Intervals only (the natural one and the mean-value form).
    Interval,
    /// An affine form wherever the natural interval straddles 0.
    Affine,
    /// An affine form where it has paid on the tile at that block size (a
    /// policy that learns, as the mean-value form's does).
    Auto,
}

impl Enclosure {
    /// The name `--enclosure` takes for it.
    pub fn name(self) -> &'static str {
        match self {
            Enclosure::Interval => "interval",
            Enclosure::Affine => "affine",
            Enclosure::Auto => "auto",
        }
    }
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
            want_buffers: true,
            progress: false,
            prune: true,
            enclosure: Enclosure::Auto,
        }
    }
}

/// Everything a render produces.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The shaded image, sRGB.
    pub image: RgbImage,
    /// Depth (see [`output::depth_image`]; normalised over the camera's
    /// range over the bounds, [`output::depth_range`]) if asked for.
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
    pub linear: Vec<[f32; 3]>,
    /// Row-major: fraction of the pixel (by sample area) whose samples hit.
    pub coverage: Vec<f32>,
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
    BadAa(AaError),
    /// An object's function is undefined at every point of the bounds.
    Undefined(String),
    /// The caller's cancel flag was set (see [`Frame::with_cancel`]).
    Cancelled,
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
            RenderError::Cancelled => write!(f, "the render was cancelled"),
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
    /// f's gradient at the hit, where the evaluator that refined the root
    /// took it: pruned around the root, it is the shortest tape at hand
    /// (pruning keeps signs: on the surface, the normal of any other
    /// evaluator to rounding).
    /// None where shading takes it.
    pub grad: Option<[f64; 3]>,
    /// The front end of the root's last bracket: a point of the ray
    /// within the refinement tolerance before the hit where every live
    /// object was evaluated positive (outside every solid), where its
    /// shadow segments start. None where no such point is known: a cut
    /// face, or a contact drawn by the tangency policy.
    pub front: Option<f64>,
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
