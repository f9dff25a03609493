//! Layer 3, enclosures and what they prove: the rules every search reads
//! an enclosure by ([`proof`]), and the mean-value form with the policy
//! that learns where it pays ([`mean_value`]).

pub(crate) mod mean_value;
pub(crate) mod proof;
