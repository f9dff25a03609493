//! ibeam against Fidget, side by side: the same workloads, from the same
//! views, rendered by both, interleaved (ibeam warm, Fidget, ibeam cold,
//! ibeam warm, ...), best of N each. See README.md beside Cargo.toml.

mod cold;
mod fidget_side;
mod ibeam_side;
mod plot;
mod table;
mod views;
mod workloads;

use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::Parser;

use cold::{ColdError, ColdRender};
use fidget_side::{FidgetRun, FidgetSpec};
use ibeam_side::{Worker, WorkerError, WorkerSpec};
use table::{ColdFigures, FidgetFigures, FlatRow, Outcome, Row, WarmFigures};
use views::View;
use workloads::{Workload, sphere_centres, spheres_scene};

/// Renders each workload with ibeam and with Fidget and prints the times.
#[derive(Parser, Debug)]
#[command(name = "ibeam-peers")]
struct Args {
    /// Timed renders of each workload by each renderer, after one untimed
    /// warm-up render; the best one counts.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1000))]
    reps: u32,
    /// Image side in pixels (Fidget's voxel depth is the same).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(8..=8192))]
    size: u32,
    /// Render threads for both.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Folder for the table, the CSV, the plot and the last render's images.
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/target/bench"))]
    out: PathBuf,
    /// Workloads to run, comma-separated: prospero, colonnade, spheres (all
    /// counts of --spheres) or spheres-N.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "prospero,colonnade,spheres"
    )]
    only: Vec<String>,
    /// Sphere counts of the sphere-union workloads.
    #[arg(long, value_delimiter = ',', default_value = "10,100,1000,3000")]
    spheres: Vec<usize>,
    /// Seed of the random sphere centres.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Folder holding prospero.vm and colonnade.vm.
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/models"))]
    models: PathBuf,
    /// Seconds one ibeam render (or its loading) may take; past that the
    /// worker is killed and the table says `timeout`.
    #[arg(long, default_value_t = 120.0)]
    timeout: f64,
    /// Also run ibeam on 1000 spheres or more at sizes above 256 (skipped
    /// by default: several seconds per render).
    #[arg(long)]
    all: bool,
    /// Views of the 3D workloads, comma-separated: top (Fidget's default,
    /// parallel rays down -z), corner (perspective from a corner). A flat
    /// model is seen from the top only.
    #[arg(long, value_delimiter = ',', default_value = "top,corner")]
    views: Vec<String>,
    /// Target folder of the default build of ibeam the cold mode runs
    /// (`cargo build --release` with RUSTFLAGS empty, run by this command).
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../target"))]
    cold_target: PathBuf,
    /// Run this ibeam binary in the cold mode instead of building one.
    #[arg(long)]
    ibeam_bin: Option<PathBuf>,
    /// Leave out the cold mode (and the default render of a flat model).
    #[arg(long)]
    no_cold: bool,
    /// ibeam's enclosure (`ibeam render --enclosure`), in both modes; the
    /// table says which.
    #[arg(long, default_value = "auto", value_parser = ["interval", "affine", "auto"])]
    enclosure: String,
    /// Internal: render one workload for the parent process (see ibeam_side).
    #[arg(long, hide = true)]
    worker: Option<String>,
    /// Internal: the worker's view.
    #[arg(long, hide = true, default_value = "top")]
    worker_view: String,
}

/// Sphere counts from which ibeam is skipped above SKIP_SIZE without --all.
const SKIP_FROM: usize = 1000;
const SKIP_SIZE: u32 = 256;

/// What the run needs besides the arguments.
struct Setup {
    models: PathBuf,
    limit: Duration,
    /// The default-build binary of the cold mode.
    cold: Option<PathBuf>,
}

/// One workload seen from one view.
#[derive(Clone, Debug)]
struct Case {
    workload: Workload,
    view: View,
}

impl Case {
    fn name(&self) -> String {
        format!("{}-{}", self.workload.name(), self.view.name())
    }
}

fn main() {
    let args = Args::parse();
    if let Some(name) = &args.worker {
        let Some(workload) = Workload::parse(name) else {
            eprintln!("unknown workload `{name}`");
            std::process::exit(2);
        };
        let Some(view) = View::parse(&args.worker_view) else {
            eprintln!("unknown view `{}`", args.worker_view);
            std::process::exit(2);
        };
        let spec = WorkerSpec {
            workload,
            view,
            size: args.size,
            threads: args.threads,
            models: args.models.clone(),
            seed: args.seed,
            enclosure: args.enclosure.clone(),
        };
        std::process::exit(ibeam_side::worker_main(&spec));
    }
    if let Err(e) = run(&args) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn selected(args: &Args) -> Result<Vec<Case>, String> {
    let mut list = Vec::new();
    for item in &args.only {
        match item.trim() {
            "spheres" => list.extend(args.spheres.iter().map(|&n| Workload::Spheres(n))),
            s => list.push(Workload::parse(s).ok_or_else(|| {
                format!("unknown workload `{s}` (prospero, colonnade, spheres, spheres-N)")
            })?),
        }
    }
    if list.contains(&Workload::Spheres(0)) || args.spheres.contains(&0) {
        return Err("sphere counts must be at least 1".into());
    }
    list.dedup();
    let views = args
        .views
        .iter()
        .map(|v| View::parse(v.trim()).ok_or_else(|| format!("unknown view `{v}` (top, corner)")))
        .collect::<Result<Vec<_>, _>>()?;
    let mut cases = Vec::new();
    for workload in list {
        for &view in &views {
            if workload.is_2d() && view != View::Top {
                continue;
            }
            cases.push(Case {
                workload: workload.clone(),
                view,
            });
        }
        if workload.is_2d() && !views.contains(&View::Top) {
            cases.push(Case {
                workload,
                view: View::Top,
            });
        }
    }
    Ok(cases)
}

fn cold_binary(args: &Args) -> Result<Option<PathBuf>, String> {
    if args.no_cold {
        return Ok(None);
    }
    if let Some(bin) = &args.ibeam_bin {
        return Ok(Some(bin.clone()));
    }
    eprintln!(
        "building the default ibeam (RUSTFLAGS empty) into {}",
        args.cold_target.display()
    );
    cold::build_default(&args.cold_target).map(Some)
}

fn run(args: &Args) -> Result<(), String> {
    let cases = selected(args)?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let setup = Setup {
        models: args
            .models
            .canonicalize()
            .unwrap_or_else(|_| args.models.clone()),
        limit: Duration::from_secs_f64(args.timeout.max(0.001)),
        cold: cold_binary(args)?,
    };
    println!(
        "ibeam vs Fidget 0.5.1: {0}x{0} px, best of {1}, {2} threads each, seed {3}, ibeam timeout {4} s",
        args.size, args.reps, args.threads, args.seed, args.timeout
    );
    if let Some(bin) = &setup.cold {
        println!("cold mode: {} (default build)", bin.display());
    }
    let skipping = !args.all && args.size > SKIP_SIZE;
    if skipping && cases.iter().any(|c| big(&c.workload)) {
        println!(
            "ibeam is skipped for {SKIP_FROM} spheres or more at sizes above {SKIP_SIZE}; --all runs it"
        );
    }
    let mut rows = Vec::new();
    for case in cases {
        let skip = skipping && big(&case.workload);
        eprintln!("-- {}", case.name());
        let row = run_case(args, &setup, &case, skip);
        eprintln!("   {}", table::describe(&row));
        rows.push(row);
    }
    let flat = match &setup.cold {
        Some(bin) if rows.iter().any(|r| r.workload.is_2d()) => {
            eprintln!("-- default render of prospero");
            Some(run_flat(args, &setup, bin))
        }
        _ => None,
    };
    let text = format!(
        "ibeam's enclosure: `{}` (`--enclosure`)\n\n{}",
        args.enclosure,
        table::markdown(&rows, flat.as_ref(), args.size, args.timeout)
    );
    println!("\n{text}");
    write(&args.out.join("results.md"), &text)?;
    write(
        &args.out.join("results.csv"),
        &table::csv(&rows, args.size, args.reps, args.threads),
    )?;
    let plot_path = args.out.join("spheres.png");
    match plot::plot_spheres(&rows_for_plot(&rows), args.size, &plot_path) {
        Ok(true) => println!("plot: {}", plot_path.display()),
        Ok(false) => {}
        Err(e) => eprintln!("plot failed: {e}"),
    }
    println!("table, CSV and last-render images: {}", args.out.display());
    Ok(())
}

fn big(w: &Workload) -> bool {
    matches!(w, Workload::Spheres(n) if *n >= SKIP_FROM)
}

/// The scene file the cold mode renders: the model, or the sphere union
/// written into the output folder.
fn scene_file(args: &Args, setup: &Setup, w: &Workload) -> Result<PathBuf, String> {
    match (w, w.vm_file()) {
        (_, Some(file)) => Ok(setup.models.join(file)),
        (Workload::Spheres(n), None) => {
            let path = args.out.join(format!("{}.ib", w.name()));
            write(&path, &spheres_scene(&sphere_centres(*n, args.seed)))?;
            Ok(path)
        }
        _ => unreachable!("every workload is a model or spheres"),
    }
}

/// The best of each renderer's figures over the reps.
#[derive(Default)]
struct Best {
    warm: Option<WarmFigures>,
    cold: Option<ColdFigures>,
    fidget: Option<FidgetFigures>,
}

// long-fn: one loop interleaves the three renderers rep by rep, so that
// load on the shared machine falls on all three alike.
fn run_case(args: &Args, setup: &Setup, case: &Case, skip: bool) -> Row {
    let fspec = FidgetSpec {
        workload: case.workload.clone(),
        view: case.view,
        size: args.size,
        threads: args.threads,
        seed: args.seed,
    };
    let fidget = FidgetRun::new(&fspec, &setup.models);
    let spec = WorkerSpec {
        workload: case.workload.clone(),
        view: case.view,
        size: args.size,
        threads: args.threads,
        models: setup.models.clone(),
        seed: args.seed,
        enclosure: args.enclosure.clone(),
    };
    let mut warm = if skip {
        Err(Outcome::Skipped)
    } else {
        Worker::start(&spec, setup.limit).map_err(warm_outcome)
    };
    let scene = scene_file(args, setup, &case.workload);
    let mut cold: Result<(&Path, PathBuf), Outcome<ColdFigures>> = match (&setup.cold, scene) {
        _ if skip => Err(Outcome::Skipped),
        (None, _) => Err(Outcome::Skipped),
        (Some(_), Err(e)) => Err(Outcome::Failed(e)),
        (Some(bin), Ok(scene)) => Ok((bin.as_path(), scene)),
    };
    let mut best = Best::default();
    let mut warm_compile = 0.0;
    // Rep 0 warms the warm child and Fidget up and is not timed: the child
    // compiles the kinds a render waits for on their first use (reported
    // on its own). Every cold render is a first render, so the cold mode
    // runs on the timed reps only.
    for rep in 0..=args.reps {
        let (timed, last) = (rep > 0, rep == args.reps);
        let image = |who: &str| last.then(|| args.out.join(format!("{}-{who}.png", case.name())));
        if let Ok(worker) = &mut warm {
            match worker.render(image("ibeam").as_deref(), setup.limit) {
                Ok(t) => {
                    warm_compile += t.compile_ms;
                    if timed && best.warm.as_ref().is_none_or(|b| t.time_ms < b.best_ms) {
                        best.warm = Some(WarmFigures {
                            best_ms: t.time_ms,
                            compile_ms: 0.0,
                            load_ms: worker.load_ms,
                            hit: t.hit,
                        });
                    }
                    eprintln!("   ibeam warm rep {rep}: {:.1} ms", t.time_ms);
                }
                Err(e) => warm = Err(warm_outcome(e)),
            }
        }
        if let Ok(f) = &fidget {
            let t = f.render(image("fidget").as_deref());
            if timed && best.fidget.as_ref().is_none_or(|b| t.time_ms < b.best_ms) {
                best.fidget = Some(FidgetFigures {
                    best_ms: t.time_ms,
                    build_ms: f.build_ms,
                    hit: t.hit,
                });
            }
            eprintln!("   fidget rep {rep}: {:.1} ms", t.time_ms);
        }
        if let (true, Ok((bin, scene))) = (timed, &cold) {
            let stem = format!("{}-cold", case.name());
            let render = ColdRender {
                exe: bin,
                scene,
                view: case.view,
                layers: !case.workload.is_2d(),
                size: args.size,
                threads: args.threads,
                out: &args.out,
                stem: &stem,
                enclosure: &args.enclosure,
            };
            match render.run(setup.limit) {
                Ok(t) => {
                    eprintln!(
                        "   ibeam cold rep {rep}: {:.1} ms, process {:.1} ms",
                        t.time_ms, t.wall_ms
                    );
                    best.cold = Some(table::best_cold(best.cold.take(), &t));
                }
                Err(e) => cold = Err(cold_outcome(e)),
            }
        }
    }
    Row {
        workload: case.workload.clone(),
        view: case.view,
        fidget: match fidget {
            Ok(_) => best.fidget.ok_or_else(|| "no render".to_string()),
            Err(e) => Err(e),
        },
        warm: match (warm, best.warm) {
            (Ok(_), Some(w)) => Outcome::Done(WarmFigures {
                compile_ms: warm_compile,
                ..w
            }),
            (Ok(_), None) => Outcome::Failed("no render".into()),
            (Err(o), _) => o,
        },
        cold: match (cold, best.cold) {
            (Ok(_), Some(c)) => Outcome::Done(c),
            (Ok(_), None) => Outcome::Failed("no render".into()),
            (Err(o), _) => o,
        },
    }
}

/// The default render of a flat model: the whole `ibeam render
/// prospero.vm -o p.png --size SxS` process against Fidget's parse, build
/// and one frame in this process, alternating, best of `--reps` each.
fn run_flat(args: &Args, setup: &Setup, bin: &Path) -> FlatRow {
    let model = setup.models.join("prospero.vm");
    let png = args.out.join("prospero-default.png");
    let mut row = FlatRow {
        fidget_ms: Err("not run".into()),
        ibeam_ms: Outcome::Failed("not run".into()),
    };
    for rep in 1..=args.reps {
        let t = cold::default_render(bin, &model, &png, args.size);
        eprintln!("   ibeam default render rep {rep}: {t:?} ms");
        row.ibeam_ms = match (t, &row.ibeam_ms) {
            (Ok(t), Outcome::Done(b)) => Outcome::Done(t.min(*b)),
            (Ok(t), _) => Outcome::Done(t),
            (Err(e), _) => cold_outcome(e),
        };
        let f = FidgetRun::parse_build_frame(&model, args.size, args.threads);
        eprintln!("   fidget parse, build, frame rep {rep}: {f:?} ms");
        row.fidget_ms = match (f, &row.fidget_ms) {
            (Ok(f), Ok(b)) => Ok(f.min(*b)),
            (f, _) => f,
        };
    }
    row
}

fn warm_outcome<T>(e: WorkerError) -> Outcome<T> {
    match e {
        WorkerError::Timeout => Outcome::Timeout,
        WorkerError::Failed(m) => Outcome::Failed(m),
    }
}

fn cold_outcome<T>(e: ColdError) -> Outcome<T> {
    match e {
        ColdError::Timeout => Outcome::Timeout,
        ColdError::Failed(m) => Outcome::Failed(m),
    }
}

fn rows_for_plot(rows: &[Row]) -> Vec<plot::Point> {
    rows.iter()
        .filter_map(|r| match (&r.workload, r.view) {
            (Workload::Spheres(n), View::Top) => Some(plot::Point {
                n: *n,
                fidget_ms: r.fidget.as_ref().ok().map(|f| f.best_ms),
                ibeam_ms: r.warm.done().map(|w| w.best_ms),
                ibeam_compile_ms: r.warm.done().map(|w| w.compile_ms),
            }),
            _ => None,
        })
        .collect()
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}
