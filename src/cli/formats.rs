//! Output file formats, chosen by each file's extension: 8-bit PNGs are
//! streamed band by band (`png_stream`); 16-bit PNGs and OpenEXR files
//! need float values, which are gathered from the bands and written whole
//! at the end (12 bytes a pixel per float image, 6 for a 16-bit PNG).

use std::path::{Path, PathBuf};

use super::CliError;
use super::png_stream::Layer;
use ibeam::render::output::srgb_u16;
use ibeam::render::{Band, FloatLayers};
use image::{ImageBuffer, ImageFormat, Rgb};

/// How one output file is encoded.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Format {
    /// PNG as the layer has always been written (streamed).
    Png,
    /// The colour image as 16-bit sRGB PNG.
    Png16,
    /// OpenEXR, 32-bit float, linear (no sRGB encoding).
    Exr,
}

/// The extensions output files may have.
const SUPPORTED: &str = ".png, .exr";

/// The format of `path`, given after `flag`, for `layer`, from its
/// extension (any case); `bit_depth` is `--bit-depth`. A usage error
/// names the extension and the supported ones, so that nothing is
/// rendered into a file whose name promises another format.
pub fn format_of(path: &Path, flag: &str, layer: Layer, bit_depth: u8) -> Result<Format, CliError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let shown = path.display();
    let supported = if layer == Layer::Classify {
        ".png"
    } else {
        SUPPORTED
    };
    let format = match ext.as_deref() {
        Some("png") if layer == Layer::Color && bit_depth == 16 => Format::Png16,
        Some("png") => Format::Png,
        Some("exr") if layer != Layer::Classify => Format::Exr,
        Some(other) => {
            return Err(format!(
                "{flag} {shown}: unsupported extension `.{other}` (supported: {supported})"
            )
            .into());
        }
        None => {
            return Err(format!(
                "{flag} {shown}: no file extension to choose the format by (supported: {supported})"
            )
            .into());
        }
    };
    if layer == Layer::Color && bit_depth == 16 && format != Format::Png16 {
        return Err(format!("--bit-depth 16 needs a .png output, not {shown}").into());
    }
    Ok(format)
}

/// Parses `--bit-depth`: 8 or 16.
pub fn parse_bit_depth(s: &str) -> Result<u8, String> {
    match s.trim() {
        "8" => Ok(8),
        "16" => Ok(16),
        _ => Err(format!("bit depth `{s}` must be 8 or 16")),
    }
}

/// The float images of a render, gathered band by band for the files
/// that cannot be streamed.
pub struct Gathered {
    files: Vec<(PathBuf, Layer, Format)>,
    size: (u32, u32),
    color: Vec<f32>,
    color16: Vec<u16>,
    depth: Vec<f32>,
    normals: Vec<f32>,
}

impl Gathered {
    /// Gathers what the non-streamed `files` of a `size` image need.
    pub fn new(files: Vec<(PathBuf, Layer, Format)>, size: (u32, u32)) -> Gathered {
        Gathered {
            files,
            size,
            color: Vec::new(),
            color16: Vec::new(),
            depth: Vec::new(),
            normals: Vec::new(),
        }
    }

    /// The float images the frame's bands must carry.
    pub fn layers(&self) -> FloatLayers {
        let has = |l: Layer| self.files.iter().any(|f| f.1 == l);
        FloatLayers {
            color: has(Layer::Color),
            depth: has(Layer::Depth),
            normals: has(Layer::Normals),
        }
    }

    /// Appends a band's float values.
    pub fn push(&mut self, band: &Band) {
        if let Some(l) = &band.linear {
            // A 16-bit PNG keeps its codes, not the floats: 6 bytes a pixel.
            if self.files.iter().any(|f| f.2 == Format::Png16) {
                let codes = l.iter().flatten().map(|&c| srgb_u16(f64::from(c)));
                self.color16.extend(codes);
            }
            if self
                .files
                .iter()
                .any(|f| f.1 == Layer::Color && f.2 == Format::Exr)
            {
                self.color.extend(l.iter().flatten());
            }
        }
        if let Some(d) = &band.depth_t {
            // Three equal channels: the `image` crate writes and reads
            // OpenEXR as RGB(A) only.
            self.depth.extend(d.iter().flat_map(|&t| [t; 3]));
        }
        if let Some(n) = &band.normals_f {
            self.normals.extend(n.iter().flatten());
        }
    }

    /// Writes every gathered file.
    pub fn write(self) -> Result<(), CliError> {
        let Gathered {
            files,
            size: (w, h),
            color,
            color16,
            depth,
            normals,
        } = self;
        // Each image is moved into its file's buffer, never copied.
        let (mut color, mut depth, mut normals) = (Some(color), Some(depth), Some(normals));
        let mut color16 = Some(color16);
        for (path, layer, format) in &files {
            let err = |e: &dyn std::fmt::Display| format!("cannot write {}: {e}", path.display());
            let result = match format {
                Format::Png16 => {
                    ImageBuffer::<Rgb<u16>, _>::from_raw(w, h, color16.take().unwrap_or_default())
                        .ok_or("image size mismatch")
                        .map_err(|e| err(&e))?
                        .save_with_format(path, ImageFormat::Png)
                }
                Format::Exr => {
                    let values = match layer {
                        Layer::Color => color.take(),
                        Layer::Depth => depth.take(),
                        Layer::Normals => normals.take(),
                        Layer::Classify => None,
                    };
                    ImageBuffer::<Rgb<f32>, _>::from_raw(w, h, values.unwrap_or_default())
                        .ok_or("image size mismatch")
                        .map_err(|e| err(&e))?
                        .save_with_format(path, ImageFormat::OpenExr)
                }
                Format::Png => continue,
            };
            result.map_err(|e| err(&e))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_follow_the_extension_in_any_case() {
        let f = |p: &str, l: Layer, b: u8| format_of(Path::new(p), "-o", l, b);
        assert_eq!(f("a.png", Layer::Color, 8).unwrap(), Format::Png);
        assert_eq!(f("a.PNG", Layer::Color, 16).unwrap(), Format::Png16);
        assert_eq!(f("a.Exr", Layer::Color, 8).unwrap(), Format::Exr);
        assert_eq!(f("d.png", Layer::Depth, 16).unwrap(), Format::Png);
        assert_eq!(f("d.exr", Layer::Normals, 8).unwrap(), Format::Exr);
        let e = f("a.jpg", Layer::Color, 8).unwrap_err().to_string();
        assert!(e.contains("`.jpg`") && e.contains(".png, .exr"), "{e}");
        let e = f("out", Layer::Color, 8).unwrap_err().to_string();
        assert!(e.contains("no file extension"), "{e}");
        assert!(f("c.exr", Layer::Classify, 8).is_err());
        assert!(f("a.exr", Layer::Color, 16).is_err());
        assert_eq!(parse_bit_depth("16"), Ok(16));
        assert!(parse_bit_depth("12").is_err());
    }
}
