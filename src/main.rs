//! The `ibeam` command line: parses arguments and reports errors; each
//! subcommand lives in `cli`.

use clap::{Parser, Subcommand};
mod cli;
use std::process::ExitCode;

/// Compile implicit surfaces to native code and ray trace them with
/// guaranteed interval arithmetic.
#[derive(Parser, Debug)]
#[command(name = "ibeam", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Print the SSA IR of each object (simplified), optionally per pass.
    Ir(cli::ir::Args),
    /// Evaluate each object at a point (value and gradient) or over a box.
    Eval(cli::eval::Args),
    /// Render a scene to PNG with the guaranteed beam tracer.
    Render(cli::render::Args),
    /// Render a scene, then again (preview first) each time it or an import is saved.
    Watch(cli::watch::Args),
    /// Serve a live view of a scene in the browser: turn it, and see each save.
    Serve(cli::serve::Args),
    /// Run a benchmark and print its table (baseline in the same run).
    Bench(cli::bench::Args),
    /// Write a scene's objects in another format (`--vm`: Fidget's text).
    Export(cli::export::Args),
}

// Deeply nested input is rejected by the parser, but lowering and
// evaluation of large formulas still recurse a little; a big stack keeps
// every supported input far from overflow.
const MAIN_STACK_BYTES: usize = 256 << 20;

fn main() -> ExitCode {
    let args = Cli::parse();
    let worker = std::thread::Builder::new()
        .stack_size(MAIN_STACK_BYTES)
        .spawn(move || match &args.command {
            Command::Ir(a) => cli::ir::run(a),
            Command::Eval(a) => cli::eval::run(a),
            Command::Render(a) => cli::render::run(a),
            Command::Watch(a) => cli::watch::run(a),
            Command::Serve(a) => cli::serve::run(a),
            Command::Bench(a) => cli::bench::run(a),
            Command::Export(a) => cli::export::run(a),
        });
    let result = match worker.map(|h| h.join()) {
        Ok(Ok(r)) => r,
        Ok(Err(_)) => Err("internal error: the worker thread panicked".into()),
        Err(e) => Err(format!("cannot start the worker thread: {e}").into()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;

    #[test]
    fn argument_definitions_are_consistent() {
        Cli::command().debug_assert();
    }
}
