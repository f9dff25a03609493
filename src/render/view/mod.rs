//! Layer 1, what the camera sees, before any evaluation: rays, beam hulls
//! and ray grids ([`camera`]), the box and camera that frame a solid
//! ([`fit`]), and how values become pixels ([`output`]).

pub mod camera;
pub mod fit;
pub mod output;
pub mod pixel_ray;
