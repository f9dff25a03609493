//! The command-line interface (part of the binary, not the library): one
//! module per subcommand; `main.rs` only parses arguments and reports
//! errors.

pub mod accuracy;
pub mod bench;
pub mod eval;
pub mod export;
pub mod formats;
pub mod image;
pub mod ir;
pub mod png_stream;
pub mod progress;
pub mod render;
pub mod serve;
pub mod view;
pub mod watch;

pub use ibeam::eval::{EvalKind, build_evaluator, build_evaluators};

/// The error type of every subcommand: printed to stderr, exit code 1.
pub type CliError = Box<dyn std::error::Error + Send + Sync>;

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
