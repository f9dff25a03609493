//! How an image is traced: the flags `render`, `watch` and `serve` share
//! (shadows, size, threads, method, anti-aliasing, evaluator, pruning),
//! and their parsers.

use std::fmt;

use super::EvalKind;
use ibeam::render::aa::{DEFAULT_DEPTH, DEFAULT_THRESHOLD, MAX_DEPTH};
use ibeam::render::{Aa, Enclosure, MAX_SIZE, Method};
use ibeam::scene::Scene;

/// How an image is traced, as flags.
#[derive(clap::Args, Clone, Debug)]
pub struct ImageArgs {
    /// Every light casts shadows, whatever the scene says.
    #[arg(long, conflicts_with = "no_shadows")]
    pub shadows: bool,
    /// No light casts shadows, whatever the scene says (faster).
    #[arg(long)]
    pub no_shadows: bool,
    /// Image size as WxH (default: the scene's); cost grows with the pixels.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Worker threads (default: one per core); output is the same for any.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Visibility method.
    #[arg(long, value_enum, default_value_t = MethodArg::Beam)]
    pub method: MethodArg,
    /// Samples per ray for `--method point` (cost is linear in it).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub steps: u32,
    /// Anti-aliasing: `none`, `iaa` (interval adaptive: extra samples only
    /// where the pixel's beam cannot prove one smooth surface) or `grid:N`
    /// (N×N samples in every pixel, the baseline).
    #[arg(long, default_value = "none", value_parser = parse_aa)]
    pub aa: Aa,
    /// IAA: largest width of a pixel's colour interval (linear light, per
    /// channel) that one sample may stand for (default 1/64).
    #[arg(long, default_value_t = DEFAULT_THRESHOLD, value_parser = parse_threshold)]
    pub aa_threshold: f64,
    /// IAA: levels of 2×2 splitting below a pixel (up to 4^D samples).
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(0..=MAX_DEPTH as i64))]
    pub aa_depth: u32,
    /// Evaluator: native code (default) or the reference interpreter.
    #[arg(long = "eval", value_enum, default_value_t = EvalKind::Jit)]
    pub eval: EvalKind,
    /// Evaluate large functions whole, without pruning them to each tile
    /// and block (slower; for measuring what pruning saves).
    #[arg(long)]
    pub no_prune: bool,
    /// Enclosures where a block's or a single ray's piece's interval
    /// straddles 0: `interval` (intervals and the mean-value form),
    /// `affine` (every time, an affine form over a block and a
    /// second-order form along a ray: tight where a variable appears many
    /// times, tens of interval evaluations each) or `auto` (the block form
    /// where it has paid on the tile at that block size; the ray form on
    /// polynomials whose affine forms beat intervals at least 8 times,
    /// while it drops 3 pieces in 4 on the tile at that piece size).
    #[arg(long, value_enum, default_value_t = EnclosureArg::Auto)]
    pub enclosure: EnclosureArg,
}

/// `--enclosure` on the command line.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EnclosureArg {
    /// Intervals only.
    Interval,
    /// An affine form wherever the interval straddles 0.
    Affine,
    /// The affine form where it pays.
    Auto,
}

impl EnclosureArg {
    /// The renderer's enclosure choice.
    pub fn enclosure(self) -> Enclosure {
        match self {
            EnclosureArg::Interval => Enclosure::Interval,
            EnclosureArg::Affine => Enclosure::Affine,
            EnclosureArg::Auto => Enclosure::Auto,
        }
    }
}

impl ImageArgs {
    /// Sets every light's shadows as `--shadows` or `--no-shadows` says.
    pub fn set_shadows(&self, scene: &mut Scene) {
        if self.shadows || self.no_shadows {
            for light in &mut scene.lights {
                light.shadows = self.shadows;
            }
        }
    }

    /// `aa` with IAA's threshold and depth from their flags.
    pub fn aa_with(&self, aa: Aa) -> Aa {
        match aa {
            Aa::Iaa { .. } => Aa::Iaa {
                threshold: self.aa_threshold,
                depth: self.aa_depth,
            },
            other => other,
        }
    }

    /// The anti-aliasing the flags ask for.
    pub fn aa(&self) -> Aa {
        self.aa_with(self.aa)
    }

    /// The visibility method the flags ask for.
    pub fn method(&self) -> Method {
        self.method.method(self.steps)
    }
}

/// Visibility method on the command line.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum MethodArg {
    /// Beams with interval rejection and inclusion tests (guaranteed).
    #[default]
    Beam,
    /// One guaranteed interval ray per pixel (slower; same pixels).
    Pixel,
    /// Fixed-step point sampling (fast, can miss thin features).
    Point,
}

impl MethodArg {
    /// The render method, with `steps` samples per ray for point sampling.
    pub fn method(self, steps: u32) -> Method {
        match self {
            MethodArg::Beam => Method::Beam,
            MethodArg::Pixel => Method::Pixel,
            MethodArg::Point => Method::Point { steps },
        }
    }
}

/// As on the command line: `beam`, `pixel`, `point`.
impl fmt::Display for MethodArg {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MethodArg::Beam => "beam",
            MethodArg::Pixel => "pixel",
            MethodArg::Point => "point",
        })
    }
}

/// Parses `WxH` with both sides in 1..=16384.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size `{s}` is not WxH"))?;
    let side = |v: &str| -> Result<u32, String> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|_| format!("size `{s}`: `{v}` is not a whole number"))?;
        if n == 0 || n > MAX_SIZE {
            return Err(format!("size `{s}`: each side must be in 1..={MAX_SIZE}"));
        }
        Ok(n)
    };
    Ok((side(w)?, side(h)?))
}

/// Parses an `--aa` value.
pub fn parse_aa(s: &str) -> Result<Aa, String> {
    Aa::parse(s).map_err(|e| e.to_string())
}

/// Parses an `--aa-threshold` value: finite and ≥ 0.
pub fn parse_threshold(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .parse()
        .map_err(|_| format!("threshold `{s}` is not a number"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("threshold `{s}` must be finite and ≥ 0"))
    }
}
