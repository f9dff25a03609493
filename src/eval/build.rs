//! Building the evaluators of a scene: one per object, for its simplified
//! function, by the implementation the caller picks.

use std::sync::Arc;

use super::Evaluator;
use super::interp::Interpreter;
use super::jit::{JitError, JitEvaluator};
use crate::ir::Function;
use crate::ir::passes::simplify;
use crate::scene::Scene;

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
pub fn build_evaluator(f: &Function, kind: EvalKind) -> Result<Arc<dyn Evaluator>, JitError> {
    Ok(match kind {
        EvalKind::Jit => Arc::new(JitEvaluator::new(f)?.in_background()),
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
) -> Result<Vec<Arc<dyn Evaluator>>, JitError> {
    scene
        .objects
        .iter()
        .map(|o| build_evaluator(&simplify(&o.function), kind))
        .collect()
}
