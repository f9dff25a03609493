//! `ibeam bench`: benchmarks that print tables with their baseline in the
//! same run, so every speed claim in docs/performance.md can be rerun.

use super::image::MethodArg;
use super::{CliError, EvalKind, build_evaluator};
use ibeam::eval::jit::JitEvaluator;
use ibeam::eval::taped::TapeEvaluator;
use ibeam::eval::{Bulk, Evaluator};
use ibeam::interval::Interval;
use ibeam::ir::passes::simplify;
use ibeam::render::{RenderOptions, RenderStats, render};
use ibeam::scene::Scene;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Arguments of `ibeam bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to measure.
    #[command(subcommand)]
    pub what: What,
}

/// The benchmarks.
#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// Evaluator throughput, interpreter against JIT and against the tape
    /// evaluator, and JIT compile time.
    Eval(EvalArgs),
    /// Render times and rays traced: beam against per-pixel and point
    /// sampling, with shadows as the scene sets them.
    Render(RenderArgs),
    /// Run time against error of every method and anti-aliasing mode, with
    /// a CSV and a log-log plot.
    Accuracy(super::accuracy::Args),
    /// Width of the interval and affine enclosures over the true range,
    /// on small cubes, against 200-bit reference ranges.
    Enclosure(EnclosureArgs),
}

/// Arguments of `ibeam bench enclosure`.
#[derive(clap::Args, Debug)]
pub struct EnclosureArgs {
    /// Reference ranges (written by tests/data/enclosure.py; default: this
    /// checkout's tests/data/enclosure.txt).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Use at most this many boxes per surface.
    #[arg(long)]
    pub boxes: Option<usize>,
}

/// Arguments of `ibeam bench render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scenes to render (default: orthocircle, metaballs, drop, tangle
    /// cube, the CSG scene and ../shared/models/prospero.vm when present).
    pub files: Vec<PathBuf>,
    /// Square image sizes to render at.
    #[arg(long, value_delimiter = ',', default_values_t = [512u32, 1024])]
    pub sizes: Vec<u32>,
    /// Methods to compare.
    // Possible values hidden: `--help` reads as it did when this was a
    // list of strings (`ibeam render --help` describes each method).
    #[arg(long, value_enum, value_delimiter = ',', hide_possible_values = true, default_values_t = [MethodArg::Beam, MethodArg::Pixel, MethodArg::Point])]
    pub methods: Vec<MethodArg>,
    /// Steps along each ray for the point-sampling method.
    #[arg(long, default_value_t = 256)]
    pub steps: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Arguments of `ibeam bench eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Scenes or models to measure (default: orthocircle, tangle cube and
    /// ../shared/models/prospero.vm when present).
    pub files: Vec<PathBuf>,
    /// Minimum time spent on each measurement, in milliseconds.
    #[arg(long, default_value_t = 300)]
    pub millis: u64,
}

/// Runs `ibeam bench`.
pub fn run(args: &Args) -> Result<(), CliError> {
    match &args.what {
        What::Eval(a) => bench_eval(a),
        What::Render(a) => bench_render(a),
        What::Accuracy(a) => super::accuracy::run(a),
        What::Enclosure(a) => bench_enclosure(a),
    }
}

/// `ibeam bench enclosure`: the table of [`ibeam::bench::enclosure`].
fn bench_enclosure(args: &EnclosureArgs) -> Result<(), CliError> {
    use ibeam::bench::enclosure::{DEFAULT_DATA, measure, parse, summarise, table};
    let path = args
        .data
        .clone()
        .unwrap_or_else(|| PathBuf::from(DEFAULT_DATA));
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut rows = Vec::new();
    for mut s in parse(&text).map_err(|e| format!("{}: {e}", path.display()))? {
        s.boxes.truncate(args.boxes.unwrap_or(usize::MAX));
        let n = s.boxes.len();
        let summary = summarise(&measure(&s)?);
        rows.push((format!("{} ({n} boxes)", s.name), summary));
    }
    let missed: usize = rows.iter().map(|(_, s)| s.missed).sum();
    super::emit(&table(&rows))?;
    if missed > 0 {
        return Err(format!("{missed} enclosures miss their reference range").into());
    }
    Ok(())
}

fn default_eval_files() -> Vec<PathBuf> {
    let mut files = vec![
        PathBuf::from("examples/orthocircle.ib"),
        PathBuf::from("examples/tangle_cube.ib"),
    ];
    let prospero = PathBuf::from("../shared/models/prospero.vm");
    if prospero.exists() {
        files.push(prospero);
    }
    files
}

// A fixed xorshift stream, so every run measures the same inputs.
struct Rng(u64);

impl Rng {
    fn next_unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Calls `body` (which does `per_call` evaluations) until `min` has passed;
/// returns evaluations per second.
fn rate(min: Duration, per_call: usize, mut body: impl FnMut()) -> f64 {
    body(); // warm-up: compiles a lazy JIT kind outside the timing
    let start = Instant::now();
    let mut calls = 0usize;
    while start.elapsed() < min {
        body();
        calls += 1;
    }
    (calls * per_call) as f64 / start.elapsed().as_secs_f64()
}

const BATCH: usize = 1024;

/// [`BATCH`] random points in the scene's bounds, and a box at each.
fn sample_inputs(scene: &Scene) -> (Vec<[f64; 3]>, Vec<[Interval; 3]>) {
    let (lo, hi) = (scene.bounds.min, scene.bounds.max);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut coord = |axis: usize| lo[axis] + (hi[axis] - lo[axis]) * rng.next_unit();
    let points: Vec<[f64; 3]> = (0..BATCH).map(|_| [coord(0), coord(1), coord(2)]).collect();
    // Boxes the size of a beam in a 512² render: 1/64 of the bounds.
    let boxes: Vec<[Interval; 3]> = points
        .iter()
        .map(|p| {
            let side = |axis: usize| {
                let w = (hi[axis] - lo[axis]) / 64.0;
                Interval::new(p[axis], p[axis] + w)
            };
            [side(0), side(1), side(2)]
        })
        .collect();
    (points, boxes)
}

// long-fn: one table, every evaluator kind measured in turn on the same
// points and boxes; each row is a few lines of the same shape.
fn bench_eval(args: &EvalArgs) -> Result<(), CliError> {
    let files = if args.files.is_empty() {
        default_eval_files()
    } else {
        args.files.clone()
    };
    let min = Duration::from_millis(args.millis);
    println!(
        "| scene | ops | interp points/s | JIT points/s | JIT batch points/s | point speedup | interp boxes/s | JIT boxes/s | JIT batch boxes/s | box speedup | JIT compile ms (all kinds) |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    // The tape evaluator (what pruned regions answer with) against the
    // interpreter, printed as a second table after the first.
    let mut tape_rows = Vec::new();
    for file in &files {
        let scene = ibeam::lang::load_scene(file)?;
        let object = &scene.objects[0];
        let f = simplify(&object.function);
        let interp = build_evaluator(&f, EvalKind::Interp)?;
        let start = Instant::now();
        let jit_all = JitEvaluator::new(&f)?;
        jit_all.compile_all()?;
        let compile_ms = start.elapsed().as_secs_f64() * 1e3;
        let jit: &dyn Evaluator = &jit_all;

        let (points, boxes) = sample_inputs(&scene);
        let (xs, ys, zs): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            points.iter().map(|p| p[0]).collect(),
            points.iter().map(|p| p[1]).collect(),
            points.iter().map(|p| p[2]).collect(),
        );
        let mut out = vec![0.0; BATCH];
        let mut iout = vec![Interval::point(0.0); BATCH];

        let single_points = |e: &dyn Evaluator| {
            rate(min, BATCH, || {
                for p in &points {
                    black_box(e.point(black_box(*p)));
                }
            })
        };
        let single_boxes = |e: &dyn Evaluator| {
            rate(min, BATCH, || {
                for b in &boxes {
                    black_box(e.interval(black_box(*b)));
                }
            })
        };
        let interp_pts = single_points(interp.as_ref());
        let jit_pts = single_points(jit);
        let jit_batch_pts = rate(min, BATCH, || {
            jit.point_batch(&xs, &ys, &zs, &mut out);
            black_box(&out);
        });
        let interp_boxes = single_boxes(interp.as_ref());
        let jit_boxes = single_boxes(jit);
        let jit_batch_boxes = rate(min, BATCH, || {
            jit.interval_batch(&boxes, &mut iout);
            black_box(&iout);
        });
        let tape = TapeEvaluator::of_function(&f);
        let tape_pts = single_points(&tape);
        let tape_batch_pts = rate(min, BATCH, || {
            tape.point_batch(&xs, &ys, &zs, &mut out);
            black_box(&out);
        });
        let tape_boxes = single_boxes(&tape);
        let tape_batch_boxes = rate(min, BATCH, || {
            tape.interval_batch(&boxes, &mut iout);
            black_box(&iout);
        });
        let along = [0.3, -0.5, 0.8].map(Interval::point);
        let dirs = |e: &dyn Evaluator| {
            rate(min, BATCH, || {
                for b in &boxes {
                    black_box(e.interval_dir(black_box(*b), along));
                }
            })
        };
        // Pruning the whole tape to each box, against one interval over
        // it (`tape boxes/s`): the issue asks a pruning to cost about
        // one interval evaluation of its parent.
        let whole = ibeam::eval::tape::Tape::new(&f);
        let prunes = rate(min, BATCH, || {
            ibeam::eval::tape::with_workspace(|ws| {
                for b in &boxes {
                    black_box(whole.prune(black_box(*b), ws));
                }
            })
        });
        // The same prunings, sixteen boxes a pass (`Tape::prune_batch`).
        let batch_prunes = rate(min, BATCH, || {
            ibeam::eval::tape::with_workspace(|ws| {
                for b in boxes.chunks(16) {
                    black_box(whole.prune_batch(black_box(b), usize::MAX, ws));
                }
            })
        });
        tape_rows.push(format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.2} |",
            file.display(),
            f.len(),
            si(interp_pts),
            si(tape_pts),
            si(tape_batch_pts),
            si(interp_boxes),
            si(tape_boxes),
            si(tape_batch_boxes),
            si(dirs(interp.as_ref())),
            si(dirs(&tape)),
            si(prunes),
            si(batch_prunes),
            tape_boxes / prunes,
            tape_boxes / batch_prunes,
        ));
        println!(
            "| {} | {} | {} | {} | {} | {:.1}x | {} | {} | {} | {:.1}x | {:.2} |",
            file.display(),
            f.len(),
            si(interp_pts),
            si(jit_pts),
            si(jit_batch_pts),
            jit_pts.max(jit_batch_pts) / interp_pts,
            si(interp_boxes),
            si(jit_boxes),
            si(jit_batch_boxes),
            jit_boxes.max(jit_batch_boxes) / interp_boxes,
            compile_ms,
        );
    }
    println!();
    println!(
        "| scene | ops | interp points/s | tape points/s | tape batch points/s | interp boxes/s | tape boxes/s | tape batch boxes/s | interp directional/s | tape directional/s | tape prunes/s | tape batch prunes/s | prune / tape box | batch prune / tape box |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for row in tape_rows {
        println!("{row}");
    }
    Ok(())
}

/// A rate with an SI suffix, 3 significant digits.
fn si(v: f64) -> String {
    let (scaled, suffix) = if v >= 1e9 {
        (v / 1e9, "G")
    } else if v >= 1e6 {
        (v / 1e6, "M")
    } else if v >= 1e3 {
        (v / 1e3, "k")
    } else {
        (v, "")
    };
    format!("{scaled:.3}{suffix}")
}

fn default_render_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["orthocircle", "metaballs", "drop", "tangle_cube", "csg"]
        .iter()
        .map(|n| PathBuf::from(format!("examples/{n}.ib")))
        .collect();
    let prospero = PathBuf::from("../shared/models/prospero.vm");
    if prospero.exists() {
        files.push(prospero);
    }
    files
}

fn bench_render(args: &RenderArgs) -> Result<(), CliError> {
    let files = if args.files.is_empty() {
        default_render_files()
    } else {
        args.files.clone()
    };
    println!(
        "| scene | size | method | time ms | rays | rays vs pixel | interval evals | point evals | shadow rays | pixels hit |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|");
    let mut skipped = std::collections::BTreeSet::new();
    for file in &files {
        let scene = ibeam::lang::load_scene(file)?;
        let evaluators = super::build_evaluators(&scene, EvalKind::Jit)?;
        // Marching a 2D model along its missing axis measures nothing (f
        // is constant along every ray) and takes minutes: point sampling
        // is left out of its rows, and a note below says so.
        let flat = args.methods.contains(&MethodArg::Point) && ibeam::render::is_flat(&scene);
        for &size in &args.sizes {
            if flat {
                skipped.insert(file.display().to_string());
            }
            let rows = time_methods(&scene, &evaluators, size, args, flat)?;
            print_render_rows(file, size, &rows, args.steps);
        }
    }
    for f in skipped {
        println!(
            "\n{f}: point sampling left out (a 2D model seen along its missing axis: f is constant along every ray)."
        );
    }
    Ok(())
}

/// Renders `scene` at `size`² with each method asked for (point sampling
/// left out when `flat`), in order.
fn time_methods(
    scene: &Scene,
    evaluators: &[Arc<dyn Evaluator>],
    size: u32,
    args: &RenderArgs,
    flat: bool,
) -> Result<Vec<(MethodArg, RenderStats)>, CliError> {
    let mut rows = Vec::new();
    for &method in &args.methods {
        if method == MethodArg::Point && flat {
            continue;
        }
        let opts = RenderOptions {
            width: size,
            height: size,
            threads: args.threads,
            method: method.method(args.steps),
            want_depth: false,
            want_normals: false,
            want_classify: false,
            want_buffers: true,
            progress: false,
            prune: true,
            enclosure: ibeam::render::Enclosure::Auto,
        };
        // The first render of a scene also compiles its lazy JIT kinds;
        // render once untimed so every row is steady-state.
        if rows.is_empty() {
            render(
                scene,
                evaluators,
                &RenderOptions {
                    width: 32,
                    height: 32,
                    ..opts.clone()
                },
            )?;
        }
        let out = render(scene, evaluators, &opts)?;
        rows.push((method, out.stats));
    }
    Ok(rows)
}

/// Prints one table row per method, with rays relative to the pixel
/// method's when it ran.
fn print_render_rows(file: &Path, size: u32, rows: &[(MethodArg, RenderStats)], steps: u32) {
    let pixel_rays = rows
        .iter()
        .rev()
        .find(|(m, _)| *m == MethodArg::Pixel)
        .map(|(_, st)| st.rays);
    for (method, st) in rows {
        let ratio = match pixel_rays {
            Some(p) if p > 0 => format!("{:.1}%", 100.0 * st.rays as f64 / p as f64),
            _ => "-".into(),
        };
        let label = if *method == MethodArg::Point {
            format!("point ({steps} steps)")
        } else {
            method.to_string()
        };
        println!(
            "| {} | {size}² | {label} | {:.1} | {} | {ratio} | {} | {} | {} | {} |",
            file.display(),
            st.time_ms,
            st.rays,
            st.interval_evals,
            st.point_evals,
            st.shadow_rays,
            st.pixels_hit,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: RenderArgs,
    }

    #[test]
    fn methods_are_the_same_names_as_before() {
        let p = |extra: &[&str]| {
            let mut v = vec!["bench"];
            v.extend_from_slice(extra);
            Cli::try_parse_from(v).map(|c| c.args.methods)
        };
        use MethodArg::{Beam, Pixel, Point};
        assert_eq!(p(&[]).unwrap(), [Beam, Pixel, Point]);
        assert_eq!(p(&["--methods", "point,beam"]).unwrap(), [Point, Beam]);
        assert!(p(&["--methods", "ray"]).is_err());
        let names: Vec<String> = [Beam, Pixel, Point].iter().map(|m| m.to_string()).collect();
        assert_eq!(names, ["beam", "pixel", "point"]);
    }
}
