//! A finished band of image rows, as [`super::Frame::stream`] hands them
//! out: the encoded images the PNGs take, and, when asked for, the float
//! values that 16-bit and floating-point outputs need.

use super::stats::RenderStats;
use super::tile::TileOut;
use super::{RenderOptions, output};

/// Which float images a streamed band also carries (each costs 12 bytes a
/// pixel of the band, on top of its encoded image).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct FloatLayers {
    /// Linear colour ([`Band::linear`]).
    pub color: bool,
    /// Ray parameter of the hit ([`Band::depth_t`]); needs `want_depth`.
    pub depth: bool,
    /// Raw unit normals ([`Band::normals_f`]); needs `want_normals`.
    pub normals: bool,
}

/// Finished image rows `y0..y0 + rows`, each `width` pixels, row-major;
/// [`super::Frame::stream`] hands them out top to bottom.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Band {
    /// First image row of the band.
    pub y0: u32,
    /// Rows in the band.
    pub rows: u32,
    /// Pixels in a row.
    pub width: u32,
    /// The shaded image, 8-bit sRGB, 3 bytes a pixel.
    pub color: Vec<u8>,
    /// Depth as [`output::depth_u16`] encodes it, if asked for.
    pub depth: Option<Vec<u16>>,
    /// Normals as [`output::normal_pixel`], 3 bytes a pixel, if asked for.
    pub normals: Option<Vec<u8>>,
    /// Classification colours, 3 bytes a pixel, if asked for.
    pub classify: Option<Vec<u8>>,
    /// Linear colour (the values the 8-bit image encodes), if asked for
    /// with [`FloatLayers::color`].
    pub linear: Option<Vec<[f32; 3]>>,
    /// The hit's ray parameter (the distance along the view direction),
    /// +inf where nothing was hit, if asked for with [`FloatLayers::depth`].
    pub depth_t: Option<Vec<f32>>,
    /// Unit normals, zero where nothing was hit, if asked for with
    /// [`FloatLayers::normals`].
    pub normals_f: Option<Vec<[f32; 3]>>,
}

/// One row of tiles (`outs`, left to right) as a band of output pixels;
/// merges the tiles' counters, and the band's hit pixels, into `stats` in
/// tile order, as the in-memory render does.
pub(super) fn band(
    outs: &[TileOut],
    opts: &RenderOptions,
    float: FloatLayers,
    y0: u32,
    depth_range: (f64, f64),
    stats: &mut RenderStats,
) -> Band {
    let w = opts.width as usize;
    let rows = outs.first().map_or(0, |t| t.h);
    let n = w * rows as usize;
    let mut b = Band {
        y0,
        rows,
        width: opts.width,
        color: vec![0; 3 * n],
        depth: opts.want_depth.then(|| vec![0; n]),
        normals: opts.want_normals.then(|| vec![0; 3 * n]),
        classify: opts.want_classify.then(|| vec![0; 3 * n]),
        linear: float.color.then(|| vec![[0.0; 3]; n]),
        depth_t: (float.depth && opts.want_depth).then(|| vec![0.0; n]),
        normals_f: (float.normals && opts.want_normals).then(|| vec![[0.0; 3]; n]),
    };
    let mut srgb = output::SrgbRun::default();
    for t in outs {
        stats.merge(&t.state.stats);
        for j in 0..t.h {
            for i in 0..t.w {
                let src = (j * t.w + i) as usize;
                let dst = (j as usize) * w + (t.x0 + i) as usize;
                b.color[3 * dst..3 * dst + 3].copy_from_slice(&srgb.pixel(t.linear[src]).0);
                stats.pixels_hit += u64::from(t.depth[src].is_finite());
                if let Some(d) = b.depth.as_mut() {
                    d[dst] = output::depth_u16(t.depth[src], depth_range);
                }
                if let (Some(n), Some(tn)) = (b.normals.as_mut(), t.normals.as_ref()) {
                    n[3 * dst..3 * dst + 3].copy_from_slice(&output::normal_or_none(tn[src]).0);
                }
                if let (Some(c), Some(tc)) = (b.classify.as_mut(), t.class.as_ref()) {
                    c[3 * dst..3 * dst + 3].copy_from_slice(&tc[src].0);
                }
                if let Some(l) = b.linear.as_mut() {
                    l[dst] = t.linear[src].map(|c| c as f32);
                }
                if let Some(d) = b.depth_t.as_mut() {
                    d[dst] = t.depth[src] as f32;
                }
                if let (Some(n), Some(tn)) = (b.normals_f.as_mut(), t.normals.as_ref()) {
                    let v = tn[src];
                    n[dst] = if v[0].is_nan() {
                        [0.0; 3]
                    } else {
                        v.map(|c| c as f32)
                    };
                }
            }
        }
    }
    b
}
