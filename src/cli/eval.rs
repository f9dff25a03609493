//! `ibeam eval`.

use super::CliError;

/// Arguments of `ibeam eval`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (`.ib`) or Fidget model (`.vm`).
    pub file: std::path::PathBuf,
}

/// Runs `ibeam eval`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let scene = crate::lang::load_scene(&args.file)?;
    let _ = scene;
    Err("not built yet".into())
}
