//! Turning per-pixel results into images: sRGB colour, 16-bit depth,
//! normals and a classification map.

use glam::DVec3;
use image::{ImageBuffer, Luma, Rgb, RgbImage};

use super::camera::normalize;
use crate::scene::{Bounds, Camera};

/// Encodes one linear channel in [0, 1] as 8-bit sRGB (NaN as 0, values
/// outside clamped): the sRGB transfer function rounded to the nearest
/// code, found among the 255 linear values where the code steps up (a
/// binary search; the transfer function's `powf` costs more than the rest
/// of shading a flat model's pixel).
pub fn srgb_u8(c: f64) -> u8 {
    static TABLE: std::sync::OnceLock<SrgbTable> = std::sync::OnceLock::new();
    let t = TABLE.get_or_init(SrgbTable::new);
    if c.is_nan() || c <= 0.0 {
        return 0;
    }
    if c >= 1.0 {
        return 255;
    }
    // `c · BINS` is exact (a power of two), so `c` is at least the start
    // of its bin, whose code the table holds; the steps inside the bin
    // (at most two) are then counted one by one.
    let mut code = t.bins[(c * SRGB_BINS as f64) as usize];
    while code < 255 && t.steps[code as usize] <= c {
        code += 1;
    }
    code
}

/// Bins of [0, 1] in the sRGB table (a power of two).
const SRGB_BINS: usize = 4096;

// The linear values where the sRGB code steps up (`steps[k]` is the least
// value of code k + 1), and the code at the start of each of `SRGB_BINS`
// equal bins of [0, 1].
struct SrgbTable {
    steps: Vec<f64>,
    bins: Vec<u8>,
}

impl SrgbTable {
    fn new() -> SrgbTable {
        let steps: Vec<f64> = (1..=255).map(srgb_step).collect();
        let bins = (0..SRGB_BINS)
            .map(|i| {
                let start = i as f64 / SRGB_BINS as f64;
                steps.partition_point(|&s| s <= start) as u8
            })
            .collect();
        SrgbTable { steps, bins }
    }
}

// The least linear value in [0, 1] that `srgb_u8_formula` encodes as at
// least `code`: a bisection over the ordered bit patterns of the
// non-negative doubles.
fn srgb_step(code: u8) -> f64 {
    let (mut lo, mut hi) = (0u64, 1f64.to_bits());
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if srgb_u8_formula(f64::from_bits(mid)) >= code {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    f64::from_bits(lo)
}

// The sRGB transfer function of a linear value, rounded to a code.
fn srgb_u8_formula(c: f64) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// Encodes one linear channel in [0, 1] as 16-bit sRGB (NaN as 0, values
/// outside clamped): the transfer function itself, rounded to the nearest
/// code. Only the 16-bit PNG uses it, so it need not be as fast as
/// [`srgb_u8`]'s table.
pub fn srgb_u16(c: f64) -> u16 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 65535.0 + 0.5).floor().clamp(0.0, 65535.0) as u16
}

/// An 8-bit sRGB pixel from linear RGB.
pub fn srgb_pixel(c: [f64; 3]) -> Rgb<u8> {
    Rgb([srgb_u8(c[0]), srgb_u8(c[1]), srgb_u8(c[2])])
}

/// [`srgb_pixel`] that remembers the last colour it encoded: runs of one
/// colour (background, flat 2D masks) are encoded once.
#[derive(Clone, Debug, Default)]
pub struct SrgbRun {
    last: Option<([u64; 3], Rgb<u8>)>,
}

impl SrgbRun {
    /// The 8-bit sRGB pixel of linear `c`.
    pub fn pixel(&mut self, c: [f64; 3]) -> Rgb<u8> {
        let key = c.map(f64::to_bits);
        match self.last {
            Some((k, p)) if k == key => p,
            _ => {
                let p = srgb_pixel(c);
                self.last = Some((key, p));
                p
            }
        }
    }
}

/// The range of ray parameters a hit can have: the camera's t over the
/// scene bounds, `(near, far)`, which the depth image maps to 0..=65534.
///
/// Every ray has unit component along the view direction `w` (a
/// perspective ray is `w` plus screen offsets, an orthographic one is `w`
/// from a point in the eye's plane), so t is the depth `(p - eye) · w`;
/// being linear, it is extreme at corners of the bounds. Hits lie inside
/// the bounds at t ≥ 0, so they fall in this range (up to rounding, which
/// [`depth_u16`] clamps), and the range is known before anything is
/// traced: a streamed render needs no second pass, and the same scene and
/// camera give the same depth code at any size.
pub fn depth_range(cam: &Camera, b: &Bounds) -> (f64, f64) {
    let eye = DVec3::from_array(cam.eye);
    let Some(w) = normalize(DVec3::from_array(cam.target) - eye) else {
        // No camera, so no hits: any range will do.
        return (0.0, 1.0);
    };
    let (mut near, mut far) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..8 {
        let c = DVec3::from_array(std::array::from_fn(|i| {
            if k >> i & 1 == 0 { b.min[i] } else { b.max[i] }
        }));
        let t = (c - eye).dot(w);
        near = near.min(t);
        far = far.max(t);
    }
    // Rays start at t = 0: an eye inside the bounds sees from there.
    (near.max(0.0), far.max(0.0))
}

/// One depth pixel: t mapped linearly from `near` (0) to `far` (65534) of
/// [`depth_range`], clamped to that; background (+inf) is 65535.
pub fn depth_u16(t: f64, (near, far): (f64, f64)) -> u16 {
    if !t.is_finite() {
        return u16::MAX;
    }
    // A degenerate range (bounds seen edge-on, or behind the eye) would
    // divide by zero: its hits all map near 0.
    let span = if far > near { far - near } else { 1.0 };
    (((t - near) / span) * 65534.0).round().clamp(0.0, 65534.0) as u16
}

/// A 16-bit depth image of [`depth_u16`] pixels over `range` (see
/// [`depth_range`]).
pub fn depth_image(
    w: u32,
    h: u32,
    depth_t: &[f64],
    range: (f64, f64),
) -> ImageBuffer<Luma<u16>, Vec<u16>> {
    ImageBuffer::from_fn(w, h, |x, y| {
        Luma([depth_u16(depth_t[(y * w + x) as usize], range)])
    })
}

/// Maps a unit normal to 8-bit RGB (`(n + 1) / 2`), black for none.
pub fn normal_pixel(n: Option<[f64; 3]>) -> Rgb<u8> {
    match n {
        Some(n) => Rgb(n.map(|c| ((c * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8)),
        None => Rgb([0, 0, 0]),
    }
}

/// [`normal_pixel`] of a tile's normal, whose NaN marks no hit.
pub fn normal_or_none(n: [f64; 3]) -> Rgb<u8> {
    normal_pixel((!n[0].is_nan()).then_some(n))
}

/// Builds an RGB image from a row-major pixel vector.
pub fn rgb_image(w: u32, h: u32, px: &[Rgb<u8>]) -> RgbImage {
    ImageBuffer::from_fn(w, h, |x, y| px[(y * w + x) as usize])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_and_midtone() {
        assert_eq!(srgb_u8(0.0), 0);
        assert_eq!(srgb_u8(1.0), 255);
        assert_eq!(srgb_u8(2.0), 255);
        assert_eq!(srgb_u8(-1.0), 0);
        // Linear 0.214 is about sRGB 0.5.
        assert!((srgb_u8(0.214) as i32 - 128).abs() <= 1);
    }

    // The table gives the formula's code everywhere: at every step, a few
    // ulps either side of it, and at a million spread values.
    #[test]
    fn srgb_table_matches_the_transfer_function() {
        let mut probes = vec![f64::NAN, -0.0, 0.0, 1.0, 1.5, -3.0, f64::INFINITY];
        for code in 1..=255u8 {
            let s = srgb_step(code).to_bits();
            probes.extend((s.saturating_sub(3)..s + 3).map(f64::from_bits));
        }
        probes.extend((0..1_000_000).map(|i| (f64::from(i) / 1e6).powi(2)));
        for c in probes {
            assert_eq!(srgb_u8(c), srgb_u8_formula(c), "at {c:e}");
        }
    }

    // 16-bit codes are the 8-bit ones times 257 within rounding.
    #[test]
    fn srgb_u16_agrees_with_u8() {
        for i in 0..=1000 {
            let c = f64::from(i) / 1000.0;
            let (a, b) = (i32::from(srgb_u16(c)), i32::from(srgb_u8(c)));
            assert!((a - b * 257).abs() <= 257, "at {c}: {a} vs {b}");
        }
        assert_eq!(srgb_u16(f64::NAN), 0);
        assert_eq!(srgb_u16(2.0), 65535);
        assert_eq!(normal_or_none([f64::NAN; 3]), Rgb([0, 0, 0]));
        assert_eq!(normal_or_none([0.0, 0.0, 1.0]), Rgb([128, 128, 255]));
    }

    #[test]
    fn depth_orders_hits_and_marks_background() {
        let img = depth_image(4, 1, &[1.0, f64::INFINITY, 3.0, 2.0], (1.0, 3.0));
        assert_eq!(img.get_pixel(0, 0).0[0], 0);
        assert_eq!(img.get_pixel(1, 0).0[0], u16::MAX);
        assert_eq!(img.get_pixel(2, 0).0[0], 65534);
        assert_eq!(img.get_pixel(3, 0).0[0], 32767);
        // Rounding can put a hit a hair outside the range: clamped.
        assert_eq!(depth_u16(0.5, (1.0, 3.0)), 0);
        assert_eq!(depth_u16(3.5, (1.0, 3.0)), 65534);
        assert_eq!(depth_u16(2.0, (2.0, 2.0)), 0);
    }

    #[test]
    fn depth_range_is_the_view_depth_of_the_bounds() {
        let b = Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        };
        let cam = Camera {
            eye: [0.0, 0.0, 5.0],
            target: [0.0; 3],
            ..Camera::default()
        };
        assert_eq!(depth_range(&cam, &b), (4.0, 6.0));
        // From inside the bounds, rays start at t = 0.
        let inside = Camera {
            eye: [0.0, 0.0, 0.5],
            ..cam
        };
        assert_eq!(depth_range(&inside, &b), (0.0, 1.5));
    }
}
