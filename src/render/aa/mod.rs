//! Anti-aliasing: interval adaptive anti-aliasing (IAA, after Flórez et
//! al.) and regular grid supersampling, the baseline. `docs/iaa.md` gives
//! the reasoning and the measurements behind each rule.
//!
//! - this file: the [`Aa`] option, its parsing and its limits;
//! - `classify`: a tile's pixels classified as background, smooth,
//!   covered or split ([`classify_tile`]), the shadow-edge rule over the
//!   base samples ([`shadow_edges`]) and the merge of sub-samples
//!   ([`merge_split`]);
//! - `area`: the pixel-area tests themselves, beams over the whole area
//!   of a block of pixels, quartered down to single pixels.
//!
//! `grid:N` traces the image at N× the resolution with the chosen method
//! and averages each N×N block in linear light (`frame`).

use std::fmt;

use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_meet, dot, normalize_box};
use crate::ir::prune::smooth_on;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::colour::colour_interval;
use crate::render::enclose::proof;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::trace::probe::{self, EmptyPrefix, Rect, SignForm, SweepOutcome};
use crate::render::trace::refine::RootBracket;
use crate::render::view::camera::{CornerRays, RayGrid, bounds_box};

/// Default IAA threshold: 1/64 of the linear colour range per channel.
pub const DEFAULT_THRESHOLD: f64 = 1.0 / 64.0;
/// Default IAA depth: 2 levels below the pixel, up to 16 samples.
pub const DEFAULT_DEPTH: u32 = 2;
/// Largest IAA depth (4^6 = 4096 samples per pixel).
pub const MAX_DEPTH: u32 = 6;
/// Largest grid factor.
pub const MAX_GRID: u32 = 32;

// Bisections of an included bracket before the colour test.
const NARROW_STEPS: usize = 6;
// Relative and absolute margin that keeps `far_t` beyond the bounds
// despite its rounding.
const FAR_MARGIN: f64 = 1e-9;

/// An anti-aliasing mode.
#[derive(Copy, Clone, Debug, PartialEq, Default)]
pub enum Aa {
    /// One ray per pixel centre.
    #[default]
    None,
    /// Regular N×N supersampling.
    Grid(u32),
    /// Interval adaptive anti-aliasing.
    Iaa {
        /// Largest accepted width of a cell's colour interval (linear).
        threshold: f64,
        /// Levels of 2×2 splitting below a pixel.
        depth: u32,
    },
}

/// Why an anti-aliasing mode was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum AaError {
    /// The text names no mode.
    UnknownMode(String),
    /// `grid:N` where N is not a whole number.
    NotANumber {
        /// The whole mode text.
        mode: String,
        /// The part after `grid:`.
        n: String,
    },
    /// `grid:N` with N out of `1..=MAX_GRID`.
    GridOutOfRange(u32),
    /// An IAA threshold that is negative or not finite.
    BadThreshold(f64),
    /// An IAA depth above [`MAX_DEPTH`].
    DepthOutOfRange(u32),
    /// A `grid:N` image too large to trace.
    TooManySamples {
        /// The grid factor.
        grid: u32,
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
    },
}

impl fmt::Display for AaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AaError::UnknownMode(s) => write!(f, "anti-aliasing `{s}` is not none, iaa or grid:N"),
            AaError::NotANumber { mode, n } => {
                write!(f, "anti-aliasing `{mode}`: `{n}` is not a whole number")
            }
            AaError::GridOutOfRange(n) => write!(f, "grid:{n}: N must be in 1..={MAX_GRID}"),
            AaError::BadThreshold(t) => write!(f, "IAA threshold {t} must be finite and ≥ 0"),
            AaError::DepthOutOfRange(d) => write!(f, "IAA depth {d} must be in 0..={MAX_DEPTH}"),
            AaError::TooManySamples {
                grid,
                width,
                height,
            } => write!(f, "grid:{grid} on {width}x{height} is too many samples"),
        }
    }
}

impl std::error::Error for AaError {}

impl Aa {
    /// Parses `none`, `iaa` (default threshold and depth) or `grid:N`.
    pub fn parse(s: &str) -> Result<Aa, AaError> {
        match s.trim() {
            "none" => Ok(Aa::None),
            "iaa" => Ok(Aa::Iaa {
                threshold: DEFAULT_THRESHOLD,
                depth: DEFAULT_DEPTH,
            }),
            t => {
                let n = t
                    .strip_prefix("grid:")
                    .ok_or_else(|| AaError::UnknownMode(s.to_string()))?;
                let n: u32 = n.parse().map_err(|_| AaError::NotANumber {
                    mode: s.to_string(),
                    n: n.to_string(),
                })?;
                let aa = Aa::Grid(n);
                aa.validate()?;
                Ok(aa)
            }
        }
    }

    /// Checks the parameters' ranges.
    pub fn validate(&self) -> Result<(), AaError> {
        match *self {
            Aa::None => Ok(()),
            Aa::Grid(n) if (1..=MAX_GRID).contains(&n) => Ok(()),
            Aa::Grid(n) => Err(AaError::GridOutOfRange(n)),
            Aa::Iaa { threshold, depth } => {
                if !(threshold >= 0.0 && threshold.is_finite()) {
                    Err(AaError::BadThreshold(threshold))
                } else if depth > MAX_DEPTH {
                    Err(AaError::DepthOutOfRange(depth))
                } else {
                    Ok(())
                }
            }
        }
    }

    /// The supersampling factor of the traced grid (1 unless `Grid`).
    pub fn grid_factor(&self) -> u32 {
        match *self {
            Aa::Grid(n) => n,
            _ => 1,
        }
    }
}

impl fmt::Display for Aa {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Aa::None => write!(f, "none"),
            Aa::Grid(n) => write!(f, "grid:{n}"),
            Aa::Iaa { threshold, depth } => write!(f, "iaa(t={threshold}, d={depth})"),
        }
    }
}

mod area;
mod classify;

pub(crate) use classify::*;

#[cfg(test)]
#[path = "aa_tests.rs"]
mod tests;
