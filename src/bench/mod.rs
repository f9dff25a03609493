//! Benchmarks that are part of the library: the accuracy sweep (time
//! against error of every method and anti-aliasing mode) and its plot.

pub mod accuracy;
pub mod enclosure;
pub mod plot;
