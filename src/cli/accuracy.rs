//! `ibeam bench accuracy`: time against error of every method and
//! anti-aliasing mode, against a 16×16-supersampled guaranteed reference
//! (see [`ibeam::bench::accuracy`]). Ready to be wired in as a `bench`
//! subcommand: `What::Accuracy(accuracy::Args)` → `accuracy::run`.

use std::path::PathBuf;

use super::image::EnclosureArg;
use super::{CliError, EvalKind};
use ibeam::bench::accuracy::{iaa_versus_grid, run_accuracy};
use ibeam::render::MAX_SIZE;

/// Arguments of `ibeam bench accuracy`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scenes to sweep (default: orthocircle, metaballs and the CSG scene).
    pub scenes: Vec<PathBuf>,
    /// Directory for accuracy.csv and accuracy.png (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Square image size; the reference traces 256 rays per pixel, so
    /// its cost grows fast with this.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..=MAX_SIZE as i64))]
    pub size: u32,
    /// Evaluator: native code (default) or the reference interpreter.
    #[arg(long = "eval", value_enum, default_value_t = EvalKind::Jit)]
    pub eval: EvalKind,
    /// Enclosure every render uses, as `ibeam render --enclosure`.
    #[arg(long, value_enum, default_value_t = EnclosureArg::Auto)]
    pub enclosure: EnclosureArg,
}

/// Runs the sweep and prints the table.
pub fn run(args: &Args) -> Result<(), CliError> {
    let scenes = if args.scenes.is_empty() {
        ["orthocircle", "metaballs", "csg"]
            .iter()
            .map(|s| PathBuf::from(format!("examples/{s}.ib")))
            .collect()
    } else {
        args.scenes.clone()
    };
    let kind = args.eval;
    let make = move |scene: &ibeam::scene::Scene| {
        super::build_evaluators(scene, kind).map_err(|e| e.to_string())
    };
    let enclosure = args.enclosure.enclosure();
    let rows = run_accuracy(&scenes, &args.out, args.size, enclosure, &make)?;
    println!(
        "| scene | method | param | enclosure | time ms | RMSE | max abs | coverage diff % | missed surface | samples/px | Pareto |"
    );
    println!("|---|---|---|---|---:|---:|---:|---:|---:|---:|:-:|");
    for r in &rows {
        println!(
            "| {} | {} | {} | {} | {:.1} | {:.2e} | {:.3} | {:.2} | {} | {:.2} | {} |",
            r.scene,
            r.family,
            r.param,
            r.enclosure.name(),
            r.time_ms,
            r.rmse,
            r.max_abs,
            r.coverage_diff_pct,
            r.missed_surface,
            r.samples_mean,
            if r.pareto { "*" } else { "" }
        );
    }
    println!();
    println!(
        "| scene | grid | grid ms | grid RMSE | fastest IAA within 1% of that RMSE or below | IAA ms | IAA RMSE | IAA / grid time |"
    );
    println!("|---|---|---:|---:|---|---:|---:|---:|");
    for c in iaa_versus_grid(&rows) {
        match &c.iaa {
            Some((param, t, e)) => println!(
                "| {} | {} | {:.1} | {:.2e} | {} | {:.1} | {:.2e} | {:.2} |",
                c.scene,
                c.grid,
                c.grid_time_ms,
                c.grid_rmse,
                param,
                t,
                e,
                c.ratio().unwrap_or(f64::NAN)
            ),
            None => println!(
                "| {} | {} | {:.1} | {:.2e} | none reaches it | | | |",
                c.scene, c.grid, c.grid_time_ms, c.grid_rmse
            ),
        }
    }
    eprintln!(
        "wrote {} and {}",
        args.out.join("accuracy.csv").display(),
        args.out.join("accuracy.png").display()
    );
    Ok(())
}
