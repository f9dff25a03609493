//! The command-line interface: one module per subcommand; `main.rs` only
//! parses arguments and reports errors.

pub mod accuracy;
pub mod bench;
pub mod eval;
pub mod ir;
pub mod render;

use crate::eval::Evaluator;
use crate::ir::interp::Interpreter;
use crate::ir::passes::simplify;
use crate::jit::JitEvaluator;
use crate::scene::Scene;
use std::sync::Arc;

/// The error type of every subcommand: printed to stderr, exit code 1.
pub type CliError = Box<dyn std::error::Error + Send + Sync>;

/// Which implementation evaluates the surface functions.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum EvalKind {
    /// Native code compiled by Cranelift (default).
    #[default]
    Jit,
    /// The reference interpreter: slower, and the oracle for the JIT.
    Interp,
}

/// An evaluator of `kind` for an already simplified function.
pub fn build_evaluator(
    f: &crate::ir::Function,
    kind: EvalKind,
) -> Result<Arc<dyn Evaluator>, CliError> {
    Ok(match kind {
        EvalKind::Jit => Arc::new(JitEvaluator::new(f)?),
        EvalKind::Interp => Arc::new(Interpreter::new(f.clone())),
    })
}

/// One evaluator per scene object, each for the object's simplified
/// function, built by `kind`. The JIT compiles each evaluator kind lazily,
/// on first use, so this is cheap; compile time shows up in the first
/// render phase that needs it.
pub fn build_evaluators(
    scene: &Scene,
    kind: EvalKind,
) -> Result<Vec<Arc<dyn Evaluator>>, CliError> {
    scene
        .objects
        .iter()
        .map(|o| build_evaluator(&simplify(&o.function), kind))
        .collect()
}

/// Parses `a,b,c,...` into exactly `n` finite numbers.
pub fn parse_numbers(text: &str, n: usize, what: &str) -> Result<Vec<f64>, CliError> {
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{what}: `{text}` is not a list of numbers ({e})"))?;
    if values.len() != n {
        return Err(format!(
            "{what}: expected {n} comma-separated numbers, got {}",
            values.len()
        )
        .into());
    }
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(format!("{what}: {v} is not a finite number").into());
    }
    Ok(values)
}

/// Writes `text` to stdout; a closed pipe (`ibeam ir big.vm | head`) ends
/// the output quietly instead of failing.
pub fn emit(text: &str) -> Result<(), CliError> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
