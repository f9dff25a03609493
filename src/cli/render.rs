//! `ibeam render`: scene settings are the defaults, flags override them.

use std::fs::OpenOptions;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::CliError;
use super::formats::{Format, Gathered, format_of, parse_bit_depth};
use super::image::ImageArgs;
use super::png_stream::{Layer, PngCompression, write_pngs};
use super::progress::Bar;
use super::view::ViewArgs;
use ibeam::render::{Aa, Frame, MAX_SIZE, Method, RenderOptions};

/// Arguments of `ibeam render`.
#[derive(clap::Args, Clone, Debug)]
pub struct Args {
    /// Scene file (`.ib`) or Fidget model (`.vm`).
    pub file: PathBuf,
    /// Output image; its extension picks the format: `.png` (8-bit sRGB,
    /// streamed in bands, or 16-bit with --bit-depth 16) or `.exr` (32-bit
    /// float linear colour). 16-bit and EXR images are held whole in
    /// memory (6 or 12 bytes a pixel) until written.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Bits per channel of a `.png` colour output: 8 or 16 (sRGB either way).
    #[arg(long, default_value = "8", value_parser = parse_bit_depth)]
    pub bit_depth: u8,
    /// How hard the streamed 8-bit colour, depth, normal and classification
    /// PNGs are compressed: `fast` (default) encodes in about a third of
    /// `balanced`'s time, into files 1.1 to 3.4 times larger; `high` gives
    /// the smallest files.
    #[arg(long, value_enum, default_value_t = PngCompression::Fast)]
    pub png_compression: PngCompression,
    /// Camera overrides and framing (boxed: the flags would make every
    /// subcommand's arguments as big as this one's).
    #[command(flatten)]
    pub view: Box<ViewArgs>,
    /// How the image is traced.
    #[command(flatten)]
    pub image: ImageArgs,
    /// Render the slow, trustworthy reference instead: 16×16 samples per
    /// pixel, each a guaranteed interval ray (`--method pixel`) at 16× the
    /// resolution, so a 16× tighter depth tolerance; overrides --method
    /// and --aa.
    #[arg(long)]
    pub reference: bool,
    /// Also write a depth image of the distance along the view direction.
    /// `.png`: 16-bit grey, mapped linearly from the nearest (0) to the
    /// farthest (65534) point of the scene bounds, background 65535 (the
    /// range is the bounds', not the hits', so it is fixed before
    /// tracing). `.exr`: that distance as a float in all three channels,
    /// background +inf (held in memory).
    #[arg(long)]
    pub depth: Option<PathBuf>,
    /// Also write a normal map: `.png` as (n + 1) / 2, 8-bit, black where
    /// nothing was hit; `.exr` the raw unit normal's x, y, z as floats,
    /// 0 where nothing was hit (held in memory).
    #[arg(long)]
    pub normals: Option<PathBuf>,
    /// Also write a PNG of how each pixel was decided (blue rejected,
    /// green included block, red single ray).
    #[arg(long)]
    pub classify: Option<PathBuf>,
    /// Write the render statistics as JSON.
    #[arg(long)]
    pub stats_json: Option<PathBuf>,
    /// No progress bar and no summary (the bar, on stderr, appears only
    /// on a terminal and after half a second).
    #[arg(long)]
    pub quiet: bool,
}

/// The anti-aliasing and method the arguments ask for.
pub fn aa_and_method(args: &Args) -> (Aa, Method) {
    if args.reference {
        return (REFERENCE_AA, Method::Pixel);
    }
    (args.image.aa(), args.image.method())
}

/// Anti-aliasing of the reference render (with [`Method::Pixel`]).
pub const REFERENCE_AA: Aa = Aa::Grid(16);

/// Output files opened before rendering, so an unwritable path fails
/// fast; files this run created are removed again if it fails.
struct Outputs {
    created: Vec<PathBuf>,
    done: bool,
}

impl Outputs {
    fn claim(&mut self, path: &Path) -> Result<(), CliError> {
        let existed = path.exists();
        OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        if !existed {
            self.created.push(path.to_path_buf());
        }
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        if !self.done {
            for p in &self.created {
                let _ = std::fs::remove_file(p);
            }
        }
    }
}

/// Runs `ibeam render`.
pub fn run(args: &Args) -> Result<(), CliError> {
    run_with(args, |file| Ok(ibeam::lang::load_scene(file)?))
}

/// Runs `ibeam render` on the scene `load` gives for `args.file` (called
/// once the outputs are known to be writable); `ibeam watch` loads the
/// scene itself, to learn the files it imports.
// long-fn: the order of a render's steps as a user sees them (check the
// outputs, load, build, render, write, report); each is a call.
pub fn run_with(
    args: &Args,
    load: impl FnOnce(&Path) -> Result<ibeam::scene::Scene, CliError>,
) -> Result<(), CliError> {
    // Every output's format is checked before any file is created or
    // anything rendered: a wrong extension costs nothing and leaves nothing.
    let named = [
        (Some(&args.output), Layer::Color, "-o"),
        (args.depth.as_ref(), Layer::Depth, "--depth"),
        (args.normals.as_ref(), Layer::Normals, "--normals"),
        (args.classify.as_ref(), Layer::Classify, "--classify"),
    ];
    let mut streamed: Vec<(&Path, Layer)> = Vec::new();
    let mut whole = Vec::new();
    for (path, layer, flag) in named {
        let Some(path) = path else { continue };
        match format_of(path, flag, layer, args.bit_depth)? {
            Format::Png => streamed.push((path, layer)),
            f => whole.push((path.clone(), layer, f)),
        }
    }
    let mut outputs = Outputs {
        created: Vec::new(),
        done: false,
    };
    let extra = [&args.depth, &args.normals, &args.classify, &args.stats_json];
    for p in std::iter::once(&args.output).chain(extra.into_iter().flatten()) {
        outputs.claim(p)?;
    }
    let mut scene = load(&args.file)?;
    if scene.objects.is_empty() {
        return Err(format!("{}: the scene has no objects", args.file.display()).into());
    }
    let (width, height) = args.image.size.unwrap_or(scene.render.size);
    if width == 0 || height == 0 || width > MAX_SIZE || height > MAX_SIZE {
        return Err(format!("image size {width}x{height} is invalid (1..={MAX_SIZE})").into());
    }
    args.image.set_shadows(&mut scene);

    // The JIT compiles lazily, on first use of each evaluator kind: this
    // times building the evaluators plus what framing compiled, and the
    // render adds the native code it compiled.
    let t = Instant::now();
    let evaluators = super::build_evaluators(&scene, args.image.eval)?;
    let compile_ms = t.elapsed().as_secs_f64() * 1e3;
    let compiled = |e: &[std::sync::Arc<dyn ibeam::eval::Evaluator>]| -> f64 {
        e.iter().map(|e| e.compile_time().as_secs_f64() * 1e3).sum()
    };
    let before_view = compiled(&evaluators);
    // Framing runs on as many threads as the render (`--threads`).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.image.threads.map_or(0, |n| n as usize))
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    pool.install(|| {
        args.view.apply(
            &args.file,
            &mut scene,
            &evaluators,
            (width, height),
            args.quiet,
        )
    })?;
    let compile_ms = compile_ms + compiled(&evaluators) - before_view;

    let (aa, method) = aa_and_method(args);
    let opts = RenderOptions {
        width,
        height,
        threads: args.image.threads.map(|n| n as usize),
        method,
        want_depth: args.depth.is_some(),
        want_normals: args.normals.is_some(),
        want_classify: args.classify.is_some(),
        // Bands are streamed (`Frame::stream`): no whole-image buffers.
        want_buffers: false,
        // The CLI draws its own bar (`progress::Bar`).
        progress: false,
        prune: !args.image.no_prune,
        enclosure: args.image.enclosure.enclosure(),
    };
    let mut gathered = Gathered::new(whole, (width, height));
    // Checked before any output is truncated: a scene that cannot render
    // leaves existing files as they were.
    let mut frame =
        Frame::new(&scene, &evaluators, &opts, aa)?.with_float_layers(gathered.layers());
    let bar = Bar::new(args.quiet);
    if let Some(b) = &bar {
        frame = frame.with_progress(b.report());
    }
    let streamed_result = write_pngs(&streamed, (width, height), args.png_compression, |sink| {
        frame.stream(|band| {
            sink(band)?;
            gathered.push(band);
            Ok(())
        })
    });
    if let Some(b) = &bar {
        b.finish();
    }
    let mut stats = streamed_result?;
    gathered.write()?;
    stats.compile_ms += compile_ms;

    if let Some(p) = &args.stats_json {
        let text = serde_json::to_string_pretty(&stats.to_json())?;
        std::fs::write(p, text + "\n").map_err(|e| format!("cannot write {}: {e}", p.display()))?;
    }
    outputs.done = true;
    if !args.quiet {
        eprintln!("{stats}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::image::parse_size;

    #[test]
    fn sizes_parse_and_reject_bad_values() {
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert_eq!(parse_size("16X9"), Ok((16, 9)));
        assert!(parse_size("0x10").is_err());
        assert!(parse_size("16385x10").is_err());
        assert!(parse_size("10").is_err());
        assert!(parse_size("axb").is_err());
    }

    #[test]
    fn aa_flags_parse() {
        use clap::Parser;
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let p = |extra: &[&str]| {
            let mut v = vec!["ibeam", "s.ib", "-o", "o.png"];
            v.extend_from_slice(extra);
            Cli::try_parse_from(v).map(|c| aa_and_method(&c.args))
        };
        assert_eq!(p(&[]).unwrap(), (Aa::None, Method::Beam));
        assert_eq!(p(&["--aa", "grid:3"]).unwrap(), (Aa::Grid(3), Method::Beam));
        assert_eq!(
            p(&["--aa", "iaa", "--aa-threshold", "0.1", "--aa-depth", "3"]).unwrap(),
            (
                Aa::Iaa {
                    threshold: 0.1,
                    depth: 3
                },
                Method::Beam
            )
        );
        assert_eq!(p(&["--reference"]).unwrap(), (REFERENCE_AA, Method::Pixel));
        assert!(p(&["--aa", "grid:0"]).is_err());
        assert!(p(&["--aa", "fxaa"]).is_err());
        assert!(p(&["--aa-threshold", "-1"]).is_err());
        assert!(p(&["--aa-depth", "9"]).is_err());
    }

    #[test]
    fn unwritable_output_fails_before_anything_else() {
        let mut o = Outputs {
            created: Vec::new(),
            done: false,
        };
        let bad = Path::new("/nonexistent-dir-ibeam/x.png");
        assert!(o.claim(bad).is_err());
        let dir = std::env::temp_dir().join(format!("ibeam-render-cli-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("out.png");
        o.claim(&p).unwrap();
        assert!(p.exists());
        drop(o);
        // Not marked done: the file this run created is removed again.
        assert!(!p.exists());
        let _ = std::fs::remove_dir(&dir);
    }
}
