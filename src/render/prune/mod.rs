//! Layer 4, evaluators specialised to regions of space: the seam every
//! search specialises through ([`scope`]: an evaluation context and its
//! pruner), groups of tiles and their slices along the rays ([`groups`],
//! [`slices`]), and a tile's octree cells for shadow segments ([`cells`]).

pub(crate) mod cells;
pub(crate) mod groups;
pub(crate) mod scope;
pub(crate) mod slices;
