//! Layer 5, the first hit along rays: the beam tests ([`probe`]), beams
//! over 3D scenes ([`beam`]), quadtrees over flat ones ([`plane`]), single
//! rays ([`ray`]) and root refinement in a bracket ([`refine`]).

pub mod beam;
pub(crate) mod plane;
pub(crate) mod probe;
pub mod ray;
pub(crate) mod refine;
#[cfg(test)]
mod signs_tests;
pub(crate) mod sweep;
pub(crate) mod tile_rays;
