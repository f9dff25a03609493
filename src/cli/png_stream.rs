//! PNGs written a band of rows at a time, with the `png` crate's streaming
//! encoder, so a render never holds a whole image.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use rayon::prelude::*;

use super::CliError;
use ibeam::render::Band;

/// Which of a band's images a file gets.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Layer {
    /// The shaded image, 8-bit sRGB.
    Color,
    /// Depth, 16-bit grey.
    Depth,
    /// Normals, 8-bit RGB.
    Normals,
    /// Classification, 8-bit RGB.
    Classify,
}

/// How hard a PNG's DEFLATE stream is compressed (`--png-compression`).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PngCompression {
    /// The `png` crate's PNG-tuned fast DEFLATE (`fdeflate`): a third of
    /// `balanced`'s encoding time; files 1.1 to 3.4 times larger on the
    /// examples, which are mostly background.
    #[default]
    Fast,
    /// zlib-style compression at a middle level.
    Balanced,
    /// The smallest files, for archiving; slowest.
    High,
}

impl PngCompression {
    fn to_png(self) -> png::Compression {
        match self {
            PngCompression::Fast => png::Compression::Fast,
            PngCompression::Balanced => png::Compression::Balanced,
            PngCompression::High => png::Compression::High,
        }
    }
}

impl Layer {
    fn format(self) -> (png::ColorType, png::BitDepth) {
        match self {
            Layer::Depth => (png::ColorType::Grayscale, png::BitDepth::Sixteen),
            _ => (png::ColorType::Rgb, png::BitDepth::Eight),
        }
    }
}

fn write_err(path: &Path, e: impl std::fmt::Display) -> CliError {
    format!("cannot write {}: {e}", path.display()).into()
}

/// Creates (truncates) every `(path, layer)` file of a `size` image,
/// compressed as `compression` says, and writes its header, then runs
/// `body` with a sink that appends a band to each file, then ends and
/// flushes every file, so an I/O error anywhere (a full disk included) is
/// returned, not lost in a drop.
pub fn write_pngs<R>(
    files: &[(&Path, Layer)],
    (width, height): (u32, u32),
    compression: PngCompression,
    body: impl FnOnce(&mut (dyn FnMut(&Band) -> Result<(), CliError> + Send)) -> Result<R, CliError>,
) -> Result<R, CliError> {
    let mut writers = Vec::with_capacity(files.len());
    for &(path, layer) in files {
        let file = File::create(path).map_err(|e| write_err(path, e))?;
        let mut enc = png::Encoder::new(BufWriter::new(file), width, height);
        let (color, depth) = layer.format();
        enc.set_color(color);
        enc.set_depth(depth);
        enc.set_compression(compression.to_png());
        writers.push(enc.write_header().map_err(|e| write_err(path, e))?);
    }
    let result = {
        // The stream writers borrow `writers`, which end the files after.
        let mut streams = Vec::with_capacity(files.len());
        for (w, &(path, _)) in writers.iter_mut().zip(files) {
            streams.push(w.stream_writer().map_err(|e| write_err(path, e))?);
        }
        // Each file is a stream of its own: a band's layers encode in
        // parallel (the tracing workers take them), where one after another
        // they were most of a row's time wherever tracing is cheap (the
        // empty rows of a model framed with depth and normals).
        let mut sink = |band: &Band| -> Result<(), CliError> {
            streams
                .par_iter_mut()
                .zip(files)
                .try_for_each(|(s, &(path, layer))| {
                    let depth: Vec<u8>;
                    let bytes: &[u8] = match layer {
                        Layer::Color => &band.color,
                        Layer::Depth => {
                            let d = band.depth.as_deref().unwrap_or_default();
                            depth = d.iter().flat_map(|v| v.to_be_bytes()).collect();
                            &depth
                        }
                        Layer::Normals => band.normals.as_deref().unwrap_or_default(),
                        Layer::Classify => band.classify.as_deref().unwrap_or_default(),
                    };
                    s.write_all(bytes).map_err(|e| write_err(path, e))
                })
        };
        let r = body(&mut sink)?;
        for (s, &(path, _)) in streams.into_iter().zip(files) {
            s.finish().map_err(|e| write_err(path, e))?;
        }
        r
    };
    for (w, &(path, _)) in writers.into_iter().zip(files) {
        w.finish().map_err(|e| write_err(path, e))?;
    }
    Ok(result)
}
