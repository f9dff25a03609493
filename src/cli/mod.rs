//! The command-line interface: one module per subcommand; `main.rs` only
//! parses arguments and reports errors.

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
    match kind {
        EvalKind::Interp => Ok(scene
            .objects
            .iter()
            .map(|o| {
                let f = crate::ir::passes::simplify(&o.function);
                std::sync::Arc::new(crate::ir::interp::Interpreter::new(f))
                    as std::sync::Arc<dyn crate::eval::Evaluator>
            })
            .collect()),
        EvalKind::Jit => Err("the JIT evaluator is not built yet (use --eval interp)".into()),
    }
}
