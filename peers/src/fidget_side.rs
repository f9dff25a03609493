//! Fidget's side: the shape is built once (the `.vm` file read into a
//! `Context`, or the sphere union built as a `Tree`), then each render is
//! timed alone: Fidget's 2D image renderer for a 2D model, its voxel
//! renderer (depth = image side, normals included) for a 3D one, over the
//! [-1, 1] square/cube, with the identity view from above or the corner
//! view's `world_to_model` (`views.rs`).

use std::path::Path;
use std::time::Instant;

use fidget::context::{Context, Tree};
use fidget::jit::JitShape;
use fidget::raster::{pixel, voxel};
use fidget::render::{ImageSize, ThreadPool, VoxelSize};
use fidget::shape::BoundShape;

use crate::views::{View, fidget_matrix};
use crate::workloads::{SPHERE_RADIUS, Workload, sphere_centres};

/// A built shape, ready to render.
pub struct FidgetRun {
    shape: JitShape,
    pool: ThreadPool,
    size: u32,
    flat: bool,
    view: View,
    /// Time to read/build the expression and make the JIT shape, ms.
    pub build_ms: f64,
}

/// One render's figures.
#[derive(Clone, Debug, Default)]
pub struct FidgetTimes {
    /// Wall time of the render call, ms.
    pub time_ms: f64,
    /// Pixels inside (2D) or with a surface (3D).
    pub hit: u64,
}

/// `min` over the spheres, as a balanced tree (depth log2 n).
fn sphere_union(centres: &[[f64; 3]]) -> Tree {
    if let [c] = centres {
        let d2 = (Tree::x() - c[0] as f32).square()
            + (Tree::y() - c[1] as f32).square()
            + (Tree::z() - c[2] as f32).square();
        return d2.sqrt() - SPHERE_RADIUS as f32;
    }
    let (a, b) = centres.split_at(centres.len() / 2);
    sphere_union(a).min(sphere_union(b))
}

impl FidgetRun {
    /// Builds the workload's shape for `threads` render threads.
    pub fn new(spec: &FidgetSpec, models: &Path) -> Result<FidgetRun, String> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(spec.threads)
            .build()
            .map_err(|e| e.to_string())?;
        let t0 = Instant::now();
        let shape = match (&spec.workload, spec.workload.vm_file()) {
            (_, Some(file)) => read_model(&models.join(file))?,
            (Workload::Spheres(n), None) => {
                JitShape::from(sphere_union(&sphere_centres(*n, spec.seed)))
            }
            _ => unreachable!("every workload is a model or spheres"),
        };
        let build_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(FidgetRun {
            shape,
            pool: ThreadPool::Custom(pool),
            size: spec.size,
            flat: spec.workload.is_2d(),
            view: spec.view,
            build_ms,
        })
    }

    /// A flat model's whole job in this process, timed as one: read and
    /// parse the `.vm` file, build the `JitShape`, render one frame (the
    /// thread pool already exists, as ibeam's process starts its threads
    /// inside its own figure). Returns the wall time, ms.
    pub fn parse_build_frame(path: &Path, size: u32, threads: usize) -> Result<f64, String> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| e.to_string())?;
        let pool = ThreadPool::Custom(pool);
        let t0 = Instant::now();
        let shape = read_model(path)?;
        let bound = BoundShape::try_from(shape).map_err(|e| format!("{e:?}"))?;
        let cfg = pixel::RenderConfig::from_size(ImageSize::from(size));
        let eval = pixel::EvalConfig {
            threads: Some(&pool),
            ..Default::default()
        };
        let img = pixel::render(bound, &cfg, &eval).ok_or("cancelled")?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        std::hint::black_box(img);
        Ok(ms)
    }

    /// Renders once (and writes a picture to `save`).
    pub fn render(&self, save: Option<&Path>) -> FidgetTimes {
        let bound = BoundShape::try_from(self.shape.clone()).expect("x, y, z only");
        if self.flat {
            let cfg = pixel::RenderConfig::from_size(ImageSize::from(self.size));
            let eval = pixel::EvalConfig {
                threads: Some(&self.pool),
                ..Default::default()
            };
            let t0 = Instant::now();
            let img = pixel::render(bound, &cfg, &eval).expect("not cancelled");
            let time_ms = t0.elapsed().as_secs_f64() * 1e3;
            let hit = img.iter().filter(|p| p.inside()).count() as u64;
            if let Some(path) = save {
                let px: Vec<u8> = img
                    .iter()
                    .map(|p| if p.inside() { 255 } else { 0 })
                    .collect();
                save_png(path, image::GrayImage::from_raw(self.size, self.size, px));
            }
            FidgetTimes { time_ms, hit }
        } else {
            let cfg = voxel::RenderConfig {
                image_size: VoxelSize::from(self.size),
                world_to_model: fidget_matrix(self.view),
            };
            let eval = voxel::EvalConfig {
                threads: Some(&self.pool),
                ..Default::default()
            };
            let t0 = Instant::now();
            let img = voxel::render(bound, &cfg, &eval).expect("not cancelled");
            let time_ms = t0.elapsed().as_secs_f64() * 1e3;
            let hit = img.iter().filter(|p| p.depth > 0).count() as u64;
            if let Some(path) = save {
                // Same colours as ibeam's normal map: (n + 1) / 2.
                let px: Vec<u8> = img
                    .iter()
                    .flat_map(|p| {
                        let [x, y, z] = p.normal;
                        let len = (x * x + y * y + z * z).sqrt();
                        if p.depth == 0 || len == 0.0 {
                            [0; 3]
                        } else {
                            [x, y, z].map(|v| ((v / len + 1.0) * 127.5).round() as u8)
                        }
                    })
                    .collect();
                save_png(path, image::RgbImage::from_raw(self.size, self.size, px));
            }
            FidgetTimes { time_ms, hit }
        }
    }
}

/// What [`FidgetRun::new`] builds.
#[derive(Clone, Debug)]
pub struct FidgetSpec {
    /// The workload.
    pub workload: Workload,
    /// Where it is seen from (3D only).
    pub view: View,
    /// Image side (and voxel depth).
    pub size: u32,
    /// Render threads.
    pub threads: usize,
    /// Seed of the random spheres.
    pub seed: u64,
}

fn read_model(path: &Path) -> Result<JitShape, String> {
    let f =
        std::fs::File::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let (ctx, node) = Context::from_text(f).map_err(|e| format!("{e:?}"))?;
    JitShape::new(&ctx, node).map_err(|e| format!("{e:?}"))
}

fn save_png<P: image::Pixel<Subpixel = u8> + image::PixelWithColorType>(
    path: &Path,
    img: Option<image::ImageBuffer<P, Vec<u8>>>,
) {
    match img.map(|i| i.save(path)) {
        Some(Ok(())) => {}
        Some(Err(e)) => eprintln!("cannot write {}: {e}", path.display()),
        None => eprintln!("cannot write {}: wrong pixel count", path.display()),
    }
}
