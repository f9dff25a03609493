//! Layer 6, light at the hits: shading and colour intervals ([`shade`]),
//! guaranteed shadow segments and beams ([`shadow`]).

pub mod shade;
pub(crate) mod shadow;
