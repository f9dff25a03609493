//! The command-line interface: one module per subcommand; `main.rs` only
//! parses arguments and reports errors.

pub mod accuracy;
pub mod eval;
pub mod ir;
pub mod render;

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

/// One evaluator per scene object, each for the object's simplified
/// function, built by `kind`.
pub fn build_evaluators(
    scene: &crate::scene::Scene,
    kind: EvalKind,
) -> Result<Vec<std::sync::Arc<dyn crate::eval::Evaluator>>, CliError> {
    let _ = (scene, kind);
    Err("evaluators are not wired up yet".into())
}
