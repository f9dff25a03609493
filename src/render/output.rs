//! Turning per-pixel results into images: sRGB colour, 16-bit depth,
//! normals and a classification map.

use image::{ImageBuffer, Luma, Rgb, RgbImage};

/// Encodes one linear channel in [0, 1] as 8-bit sRGB.
pub fn srgb_u8(c: f64) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// An 8-bit sRGB pixel from linear RGB.
pub fn srgb_pixel(c: [f64; 3]) -> Rgb<u8> {
    Rgb([srgb_u8(c[0]), srgb_u8(c[1]), srgb_u8(c[2])])
}

/// A 16-bit depth image: hits map linearly from the nearest (0) to the
/// farthest (65534) hit; background is 65535.
pub fn depth_image(w: u32, h: u32, depth_t: &[f64]) -> ImageBuffer<Luma<u16>, Vec<u16>> {
    let finite = depth_t.iter().copied().filter(|t| t.is_finite());
    let lo = finite.clone().fold(f64::INFINITY, f64::min);
    let hi = finite.fold(f64::NEG_INFINITY, f64::max);
    let span = if hi > lo { hi - lo } else { 1.0 };
    ImageBuffer::from_fn(w, h, |x, y| {
        let t = depth_t[(y * w + x) as usize];
        if t.is_finite() {
            Luma([(((t - lo) / span) * 65534.0).round().clamp(0.0, 65534.0) as u16])
        } else {
            Luma([u16::MAX])
        }
    })
}

/// Maps a unit normal to 8-bit RGB (`(n + 1) / 2`), black for none.
pub fn normal_pixel(n: Option<[f64; 3]>) -> Rgb<u8> {
    match n {
        Some(n) => Rgb(n.map(|c| ((c * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8)),
        None => Rgb([0, 0, 0]),
    }
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

    #[test]
    fn depth_orders_hits_and_marks_background() {
        let img = depth_image(3, 1, &[1.0, f64::INFINITY, 3.0]);
        assert_eq!(img.get_pixel(0, 0).0[0], 0);
        assert_eq!(img.get_pixel(1, 0).0[0], u16::MAX);
        assert_eq!(img.get_pixel(2, 0).0[0], 65534);
    }
}
