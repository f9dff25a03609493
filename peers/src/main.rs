//! ibeam against Fidget, side by side: the same workloads rendered by both,
//! interleaved (ibeam, Fidget, ibeam, Fidget, ...), best of N each.
//! See README.md beside Cargo.toml.

mod fidget_side;
mod ibeam_side;
mod plot;
mod workloads;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::Parser;

use fidget_side::FidgetRun;
use ibeam_side::{Worker, WorkerError, WorkerSpec};
use workloads::Workload;

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
    /// by default: several minutes per render today).
    #[arg(long)]
    all: bool,
    /// Internal: render one workload for the parent process (see ibeam_side).
    #[arg(long, hide = true)]
    worker: Option<String>,
}

/// Sphere counts from which ibeam is skipped above SKIP_SIZE without --all.
const SKIP_FROM: usize = 1000;
const SKIP_SIZE: u32 = 256;

/// What happened to ibeam on one workload.
#[derive(Clone, Debug)]
enum IbeamOutcome {
    Done {
        best_ms: f64,
        compile_ms: f64,
        load_ms: f64,
        hit: u64,
    },
    Skipped,
    Timeout,
    Failed(String),
}

/// One line of the table.
#[derive(Clone, Debug)]
struct Row {
    workload: Workload,
    /// Best Fidget render, tape building time, pixels hit.
    fidget: Result<(f64, f64, u64), String>,
    ibeam: IbeamOutcome,
}

fn main() {
    let args = Args::parse();
    if let Some(name) = &args.worker {
        let Some(workload) = Workload::parse(name) else {
            eprintln!("unknown workload `{name}`");
            std::process::exit(2);
        };
        let spec = WorkerSpec {
            workload,
            size: args.size,
            threads: args.threads,
            models: args.models.clone(),
            seed: args.seed,
        };
        std::process::exit(ibeam_side::worker_main(&spec));
    }
    if let Err(e) = run(&args) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn selected(args: &Args) -> Result<Vec<Workload>, String> {
    let mut list = Vec::new();
    for item in &args.only {
        match item.trim() {
            "spheres" => list.extend(args.spheres.iter().map(|&n| Workload::Spheres(n))),
            s => list.push(Workload::parse(s).ok_or_else(|| {
                format!("unknown workload `{s}` (prospero, colonnade, spheres, spheres-N)")
            })?),
        }
    }
    if list.iter().any(|w| *w == Workload::Spheres(0)) || args.spheres.contains(&0) {
        return Err("sphere counts must be at least 1".into());
    }
    list.dedup();
    Ok(list)
}

fn run(args: &Args) -> Result<(), String> {
    let list = selected(args)?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let models = args
        .models
        .canonicalize()
        .unwrap_or_else(|_| args.models.clone());
    let limit = Duration::from_secs_f64(args.timeout.max(0.001));
    println!(
        "ibeam vs Fidget 0.5.1: {0}x{0} px, best of {1}, {2} threads each, seed {3}, ibeam timeout {4} s",
        args.size, args.reps, args.threads, args.seed, args.timeout
    );
    let skipping = !args.all && args.size > SKIP_SIZE;
    if skipping
        && list
            .iter()
            .any(|w| matches!(w, Workload::Spheres(n) if *n >= SKIP_FROM))
    {
        println!(
            "ibeam is skipped for {SKIP_FROM} spheres or more at sizes above {SKIP_SIZE} \
             (minutes per render today); --all runs it"
        );
    }
    let mut rows = Vec::new();
    for w in list {
        let skip = skipping && matches!(w, Workload::Spheres(n) if n >= SKIP_FROM);
        eprintln!("-- {}", w.name());
        let row = run_workload(args, &w, &models, limit, skip);
        eprintln!("   {}", describe(&row));
        rows.push(row);
    }
    let table = table(&rows, args);
    println!("\n{table}");
    write(&args.out.join("results.md"), &table)?;
    write(&args.out.join("results.csv"), &csv(&rows, args))?;
    let plot_path = args.out.join("spheres.png");
    match plot::plot_spheres(&rows_for_plot(&rows), args.size, &plot_path) {
        Ok(true) => println!("plot: {}", plot_path.display()),
        Ok(false) => {}
        Err(e) => eprintln!("plot failed: {e}"),
    }
    println!("table, CSV and last-render images: {}", args.out.display());
    Ok(())
}

fn run_workload(args: &Args, w: &Workload, models: &Path, limit: Duration, skip: bool) -> Row {
    let fidget = FidgetRun::new(w, args.size, args.threads, models, args.seed);
    let spec = WorkerSpec {
        workload: w.clone(),
        size: args.size,
        threads: args.threads,
        models: models.to_path_buf(),
        seed: args.seed,
    };
    let mut ibeam = if skip {
        Err(IbeamOutcome::Skipped)
    } else {
        Worker::start(&spec, limit).map_err(outcome_of)
    };
    let mut ibeam_best = f64::INFINITY;
    let mut ibeam_compile = 0.0;
    let mut ibeam_hit = 0;
    let mut fidget_best = f64::INFINITY;
    let mut fidget_hit = 0;
    // Rep 0 warms both up and is not timed: ibeam compiles the kinds a
    // render waits for on their first use (its compile time is reported on
    // its own), and a render's time then subtracts that wait only
    // approximately when other threads go on rendering meanwhile.
    for rep in 0..=args.reps {
        let (timed, last) = (rep > 0, rep == args.reps);
        let image = |who: &str| last.then(|| args.out.join(format!("{}-{who}.png", w.name())));
        if let Ok(worker) = &mut ibeam {
            match worker.render(image("ibeam").as_deref(), limit) {
                Ok(t) => {
                    if timed {
                        ibeam_best = ibeam_best.min(t.time_ms);
                    }
                    ibeam_compile += t.compile_ms;
                    ibeam_hit = t.hit;
                    eprintln!("   ibeam  rep {rep}: {:.1} ms", t.time_ms);
                }
                Err(e) => ibeam = Err(outcome_of(e)),
            }
        }
        if let Ok(f) = &fidget {
            let t = f.render(image("fidget").as_deref());
            if timed {
                fidget_best = fidget_best.min(t.time_ms);
            }
            fidget_hit = t.hit;
            eprintln!("   fidget rep {rep}: {:.1} ms", t.time_ms);
        }
    }
    let ibeam = match ibeam {
        Ok(worker) => IbeamOutcome::Done {
            best_ms: ibeam_best,
            compile_ms: ibeam_compile,
            load_ms: worker.load_ms,
            hit: ibeam_hit,
        },
        Err(o) => o,
    };
    Row {
        workload: w.clone(),
        fidget: fidget.map(|f| (fidget_best, f.build_ms, fidget_hit)),
        ibeam,
    }
}

fn outcome_of(e: WorkerError) -> IbeamOutcome {
    match e {
        WorkerError::Timeout => IbeamOutcome::Timeout,
        WorkerError::Failed(m) => IbeamOutcome::Failed(m),
    }
}

fn describe(row: &Row) -> String {
    let f = match &row.fidget {
        Ok((ms, _, _)) => format!("Fidget {ms:.1} ms"),
        Err(e) => format!("Fidget failed: {e}"),
    };
    let i = match &row.ibeam {
        IbeamOutcome::Done { best_ms, .. } => format!("ibeam {best_ms:.1} ms"),
        IbeamOutcome::Skipped => "ibeam skipped".into(),
        IbeamOutcome::Timeout => "ibeam timeout".into(),
        IbeamOutcome::Failed(e) => format!("ibeam failed: {e}"),
    };
    format!("{f}, {i}")
}

fn table(rows: &[Row], args: &Args) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| workload | Fidget ms | ibeam ms | ibeam/Fidget | ibeam compile ms | ibeam load ms | Fidget build ms | hit px Fidget / ibeam |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let (f_ms, f_build, f_hit) = match &r.fidget {
            Ok((ms, build, hit)) => (format!("{ms:.1}"), format!("{build:.1}"), hit.to_string()),
            Err(_) => ("failed".into(), "".into(), "".into()),
        };
        let (i_ms, ratio, compile, load, i_hit) = match &r.ibeam {
            IbeamOutcome::Done {
                best_ms,
                compile_ms,
                load_ms,
                hit,
            } => {
                let ratio = match &r.fidget {
                    Ok((f, _, _)) if *f > 0.0 => format!("{:.2}", best_ms / f),
                    _ => String::new(),
                };
                (
                    format!("{best_ms:.1}"),
                    ratio,
                    format!("{compile_ms:.1}"),
                    format!("{load_ms:.1}"),
                    hit.to_string(),
                )
            }
            IbeamOutcome::Skipped => ("skipped".into(), "".into(), "".into(), "".into(), "".into()),
            IbeamOutcome::Timeout => (
                format!("timeout (>{} s)", args.timeout),
                format!(">{:.0}", timeout_ratio(r, args)),
                "".into(),
                "".into(),
                "".into(),
            ),
            IbeamOutcome::Failed(_) => {
                ("failed".into(), "".into(), "".into(), "".into(), "".into())
            }
        };
        let _ = writeln!(
            s,
            "| {} | {f_ms} | {i_ms} | {ratio} | {compile} | {load} | {f_build} | {f_hit} / {i_hit} |",
            label(&r.workload, args.size)
        );
    }
    s
}

fn timeout_ratio(r: &Row, args: &Args) -> f64 {
    match &r.fidget {
        Ok((f, _, _)) if *f > 0.0 => args.timeout * 1e3 / f,
        _ => f64::NAN,
    }
}

fn label(w: &Workload, size: u32) -> String {
    match w {
        Workload::Prospero => format!("prospero 2D {size}²"),
        Workload::Colonnade => format!("colonnade 3D {size}² (Fidget voxels, depth {size})"),
        Workload::Spheres(n) => format!("{n} spheres {size}²"),
    }
}

fn csv(rows: &[Row], args: &Args) -> String {
    let mut s = String::from(
        "workload,size,reps,threads,fidget_ms,fidget_build_ms,fidget_hit,ibeam_status,ibeam_ms,ibeam_compile_ms,ibeam_load_ms,ibeam_hit\n",
    );
    for r in rows {
        let (f_ms, f_build, f_hit) = match &r.fidget {
            Ok((a, b, c)) => (a.to_string(), b.to_string(), c.to_string()),
            Err(_) => Default::default(),
        };
        let (status, i_ms, compile, load, hit) = match &r.ibeam {
            IbeamOutcome::Done {
                best_ms,
                compile_ms,
                load_ms,
                hit,
            } => (
                "ok",
                best_ms.to_string(),
                compile_ms.to_string(),
                load_ms.to_string(),
                hit.to_string(),
            ),
            IbeamOutcome::Skipped => (
                "skipped",
                Default::default(),
                Default::default(),
                Default::default(),
                Default::default(),
            ),
            IbeamOutcome::Timeout => (
                "timeout",
                Default::default(),
                Default::default(),
                Default::default(),
                Default::default(),
            ),
            IbeamOutcome::Failed(_) => (
                "failed",
                Default::default(),
                Default::default(),
                Default::default(),
                Default::default(),
            ),
        };
        let _ = writeln!(
            s,
            "{},{},{},{},{f_ms},{f_build},{f_hit},{status},{i_ms},{compile},{load},{hit}",
            r.workload.name(),
            args.size,
            args.reps,
            args.threads
        );
    }
    s
}

fn rows_for_plot(rows: &[Row]) -> Vec<plot::Point> {
    rows.iter()
        .filter_map(|r| match r.workload {
            Workload::Spheres(n) => Some(plot::Point {
                n,
                fidget_ms: r.fidget.as_ref().ok().map(|f| f.0),
                ibeam_ms: match r.ibeam {
                    IbeamOutcome::Done { best_ms, .. } => Some(best_ms),
                    _ => None,
                },
                ibeam_compile_ms: match r.ibeam {
                    IbeamOutcome::Done { compile_ms, .. } => Some(compile_ms),
                    _ => None,
                },
            }),
            _ => None,
        })
        .collect()
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}
