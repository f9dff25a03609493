//! Layer 3, enclosures and what they prove: the rules every search reads
//! an enclosure by ([`proof`]), the affine form ([`affine`]), the
//! mean-value form with the policy that
//! learns where it pays ([`mean_value`]), and the centred form and
//! interval Newton along a ray ([`centred`]), the monotone tests
//! ([`monotone`]), and the colour interval of the shading model
//! ([`colour`]).

pub(crate) mod affine;
pub(crate) mod centred;
pub(crate) mod colour;
pub(crate) mod mean_value;
pub(crate) mod monotone;
pub(crate) mod proof;
