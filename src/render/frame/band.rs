//! A finished band of image rows, as [`super::Frame::stream`] hands them
//! out: the encoded images the PNGs take, and, when asked for, the float
//! values that 16-bit and floating-point outputs need.

use crate::render::RenderOptions;
use crate::render::context::stats::RenderStats;
use crate::render::tile::TileOut;
use crate::render::view::output;

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
        for j in 0..t.h as usize {
            let tw = t.w as usize;
            let d = j * w + t.x0 as usize..j * w + t.x0 as usize + tw;
            let span = Encoded {
                color: &mut b.color[3 * d.start..3 * d.end],
                depth: b.depth.as_deref_mut().map(|v| &mut v[d.clone()]),
                normals: b
                    .normals
                    .as_deref_mut()
                    .map(|v| &mut v[3 * d.start..3 * d.end]),
                class: b
                    .classify
                    .as_deref_mut()
                    .map(|v| &mut v[3 * d.start..3 * d.end]),
            };
            encode(t, j * tw..(j + 1) * tw, span, &mut srgb, depth_range);
        }
        for j in 0..t.h {
            for i in 0..t.w {
                let src = (j * t.w + i) as usize;
                let dst = (j as usize) * w + (t.x0 + i) as usize;
                stats.pixels_hit += u64::from(t.depth[src].is_finite());
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

/// A run of output pixels' encoded layers (8-bit sRGB colour, 16-bit
/// depth, normals, classes), each exactly as long as the run; the layers
/// not asked for are absent.
pub(super) struct Encoded<'a> {
    /// 3 bytes a pixel.
    pub color: &'a mut [u8],
    /// [`output::depth_u16`] of the hit.
    pub depth: Option<&'a mut [u16]>,
    /// [`output::normal_or_none`], 3 bytes a pixel.
    pub normals: Option<&'a mut [u8]>,
    /// Classification colours, 3 bytes a pixel.
    pub class: Option<&'a mut [u8]>,
}

/// Encodes the pixels `s` of tile `t` (a run within one of its rows) into
/// `out`: what both the streamed bands and the in-memory images hold.
pub(super) fn encode(
    t: &TileOut,
    s: std::ops::Range<usize>,
    out: Encoded<'_>,
    srgb: &mut output::SrgbRun,
    depth_range: (f64, f64),
) {
    for (px, &c) in out.color.chunks_exact_mut(3).zip(&t.linear[s.clone()]) {
        px.copy_from_slice(&srgb.pixel(c).0);
    }
    if let Some(d) = out.depth {
        for (o, &z) in d.iter_mut().zip(&t.depth[s.clone()]) {
            *o = output::depth_u16(z, depth_range);
        }
    }
    if let (Some(n), Some(tn)) = (out.normals, t.normals.as_ref()) {
        for (px, &v) in n.chunks_exact_mut(3).zip(&tn[s.clone()]) {
            px.copy_from_slice(&output::normal_or_none(v).0);
        }
    }
    if let (Some(c), Some(tc)) = (out.class, t.class.as_ref()) {
        for (px, v) in c.chunks_exact_mut(3).zip(&tc[s]) {
            px.copy_from_slice(&v.0);
        }
    }
}
