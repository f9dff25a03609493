//! ibeam turns implicit-surface formulas into native code and ray traces
//! them with guaranteed interval arithmetic.
//!
//! Pipeline: [`lang`] parses a scene file, [`ir`] lowers each object to an
//! SSA function and simplifies it, [`jit`] compiles the evaluators of
//! [`eval::Evaluator`] to native code (with [`ir::interp`] as the reference),
//! and [`render`] traces beams of rays through the [`scene`].

pub mod cli;
pub mod eval;
pub mod interval;
pub mod ir;
pub mod jit;
pub mod lang;
pub mod render;
pub mod scene;
