//! `ibeam ir`: print what the compiler makes of a scene.

use super::CliError;
use ibeam::eval::jit::{JitEvaluator, clif_text};
use ibeam::ir::passes::{simplify, simplify_traced};
use ibeam::ir::print::{op_counts, print};
use std::fmt::Write;

/// Arguments of `ibeam ir`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (`.ib`) or Fidget model (`.vm`).
    pub file: std::path::PathBuf,
    /// Print the IR before simplification and after each pass.
    #[arg(long)]
    pub passes: bool,
    /// Print op counts per kind before and after simplification, and the
    /// JIT compile time of each evaluator (compiles all of them).
    #[arg(long)]
    pub stats: bool,
    /// Print the Cranelift IR (CLIF) of each evaluator.
    #[arg(long)]
    pub clif: bool,
}

/// Runs `ibeam ir`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let scene = ibeam::lang::load_scene(&args.file)?;
    let mut out = String::new();
    for object in &scene.objects {
        let _ = writeln!(out, "; object {}", object.name);
        let simplified = if args.passes {
            let _ = write!(out, "; before simplification\n{}", print(&object.function));
            let mut last = object.function.clone();
            for (name, f) in simplify_traced(&object.function) {
                let _ = write!(out, "; after {name}\n{}", print(&f));
                last = f;
            }
            last
        } else {
            let f = simplify(&object.function);
            out.push_str(&print(&f));
            f
        };
        if args.stats {
            write_stats(&mut out, &object.function, &simplified)?;
        }
        if args.clif {
            out.push_str(&clif_text(&simplified)?);
        }
    }
    super::emit(&out)
}

fn write_stats(
    out: &mut String,
    before: &ibeam::ir::Function,
    after: &ibeam::ir::Function,
) -> Result<(), CliError> {
    let (counts_before, total_before) = op_counts(before);
    let (counts_after, total_after) = op_counts(after);
    let _ = writeln!(out, "; op        before  after");
    let mut names: Vec<&str> = counts_before
        .iter()
        .chain(&counts_after)
        .map(|c| c.0)
        .collect();
    names.sort_unstable();
    names.dedup();
    let find = |counts: &[(&str, usize)], name: &str| {
        counts.iter().find(|c| c.0 == name).map_or(0, |c| c.1)
    };
    for name in names {
        let _ = writeln!(
            out,
            "; {name:<8} {:>7} {:>6}",
            find(&counts_before, name),
            find(&counts_after, name)
        );
    }
    let _ = writeln!(out, "; total    {total_before:>7} {total_after:>6}");
    let jit = JitEvaluator::new(after)?;
    jit.compile_all()?;
    for (kind, time) in jit.compile_times() {
        let _ = writeln!(
            out,
            "; jit compile {kind:<14} {:>8.3} ms",
            time.as_secs_f64() * 1e3
        );
    }
    Ok(())
}
