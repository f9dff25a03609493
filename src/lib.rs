//! ibeam turns implicit-surface formulas into native code and ray traces
//! them with guaranteed interval arithmetic.
//!
//! The folders are the pipeline: [`lang`] turns scene text into a
//! [`scene::Scene`] whose objects are [`ir`] functions; [`ir`] simplifies
//! and prunes them; [`eval`] evaluates them (the reference interpreter,
//! native code from Cranelift, pruned regional evaluators), over
//! [`interval`] arithmetic; [`render`] traces beams of rays through the
//! scene; [`bench`](mod@bench) measures time against error. `docs/architecture.md`
//! says what each owns and what may depend on what.
//!
//! ```
//! use ibeam::eval::{EvalKind, build_evaluators};
//! use ibeam::render::{RenderOptions, render};
//!
//! let scene = ibeam::lang::load_scene_source(
//!     "example.ib",
//!     "object ball = sphere(1); bounds = (-2, -2, -2) .. (2, 2, 2);",
//! )
//! .unwrap();
//! let evaluators = build_evaluators(&scene, EvalKind::Jit).unwrap();
//! let out = render(&scene, &evaluators, &RenderOptions::new(32, 32)).unwrap();
//! assert!(out.hit_mask.iter().any(|&hit| hit));
//! ```

#![deny(unsafe_code)]

pub mod bench;
pub mod eval;
pub mod interval;
pub mod ir;
pub mod lang;
pub mod render;
pub mod scene;
