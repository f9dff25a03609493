//! Layer 6, light at the hits: shading and colour intervals ([`shade`]),
//! guaranteed shadow segments and beams ([`shadow`]), how far a segment
//! stays in the bounds ([`reach`]).

pub(crate) mod reach;
pub mod shade;
pub(crate) mod shadow;
