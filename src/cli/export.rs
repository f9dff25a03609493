//! `ibeam export`: write a scene's objects for other tools.

use super::CliError;
use ibeam::ir::passes::simplify;
use ibeam::lang::vm_export::to_vm;
use std::path::PathBuf;

/// Arguments of `ibeam export`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (`.ib`) or Fidget model (`.vm`).
    pub file: PathBuf,
    /// Write the simplified IR in Fidget's `.vm` text format to this file.
    #[arg(long, value_name = "OUT.vm")]
    pub vm: PathBuf,
    /// The object to export (default: the union of every object).
    #[arg(long, value_name = "NAME")]
    pub object: Option<String>,
}

/// Runs `ibeam export`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let scene = ibeam::lang::load_scene(&args.file)?;
    let chosen: Vec<_> = match &args.object {
        None => scene.objects.iter().collect(),
        Some(name) => {
            let found: Vec<_> = scene.objects.iter().filter(|o| &o.name == name).collect();
            if found.is_empty() {
                let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
                return Err(format!(
                    "{}: no object named `{name}` (the scene has: {})",
                    args.file.display(),
                    names.join(", ")
                )
                .into());
            }
            found
        }
    };
    let functions: Vec<_> = chosen.iter().map(|o| simplify(&o.function)).collect();
    let text = to_vm(&functions);
    std::fs::write(&args.vm, text)
        .map_err(|e| format!("cannot write {}: {e}", args.vm.display()).into())
}
