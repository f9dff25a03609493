//! The in-memory render's images: every tile's output copied into
//! whole-image buffers, one row of tiles per task, in parallel.
//!
//! Copying a megapixel render's tiles one pixel at a time on one thread,
//! into buffers first filled with background values, took 30–36 ms of a
//! 75–100 ms render (prospero and 10 spheres at 1024², two threads); the
//! streamed render ([`super::band`]) never paid it, as it encodes each band
//! while the next row is traced. Here the buffers are cleared in parallel,
//! every pixel is written by exactly one tile, and the rows of tiles fill
//! their own slices of every buffer at once.

use image::{ImageBuffer, RgbImage};
use rayon::prelude::*;

use super::band::{Encoded, encode};
use crate::render::context::stats::RenderStats;
use crate::render::tile::TileOut;
use crate::render::view::output;
use crate::render::{RenderOptions, RenderOutput, TILE};

/// One row of tiles' share of every output buffer.
struct Rows<'a> {
    // Whether the per-pixel buffers below are filled (else all empty).
    buffers: bool,
    color: &'a mut [u8],
    linear: &'a mut [[f32; 3]],
    coverage: &'a mut [f32],
    samples: &'a mut [u32],
    hit_mask: &'a mut [bool],
    depth_t: &'a mut [f64],
    depth: Option<&'a mut [u16]>,
    normals: Option<&'a mut [u8]>,
    class: Option<&'a mut [u8]>,
}

/// The first `n` elements of `s`, which keeps the rest.
fn take_front<'a, T>(s: &mut &'a mut [T], n: usize) -> &'a mut [T] {
    let all = std::mem::take(s);
    let (front, rest) = all.split_at_mut(n.min(all.len()));
    *s = rest;
    front
}

impl<'a> Rows<'a> {
    /// The first `n` pixels of every buffer; `self` keeps the rest.
    fn split_front(&mut self, n: usize) -> Rows<'a> {
        fn opt<'a, T>(s: &mut Option<&'a mut [T]>, k: usize) -> Option<&'a mut [T]> {
            s.as_mut().map(|s| take_front(s, k))
        }
        Rows {
            buffers: self.buffers,
            color: take_front(&mut self.color, 3 * n),
            linear: take_front(&mut self.linear, n),
            coverage: take_front(&mut self.coverage, n),
            samples: take_front(&mut self.samples, n),
            hit_mask: take_front(&mut self.hit_mask, n),
            depth_t: take_front(&mut self.depth_t, n),
            depth: opt(&mut self.depth, n),
            normals: opt(&mut self.normals, 3 * n),
            class: opt(&mut self.class, 3 * n),
        }
    }

    /// Copies `tiles` (all in this row of tiles, `width` pixels wide) in,
    /// a tile row at a time (slices, so the plain copies are `memcpy`s).
    fn fill(&mut self, tiles: &[&TileOut], width: usize, depth_range: (f64, f64)) {
        let mut srgb = output::SrgbRun::default();
        for t in tiles {
            let tw = t.w as usize;
            for j in 0..t.h as usize {
                let s = j * tw..(j + 1) * tw;
                let d = j * width + t.x0 as usize..j * width + t.x0 as usize + tw;
                let (d3, depth) = (3 * d.start..3 * d.end, &t.depth[s.clone()]);
                if self.buffers {
                    for (o, c) in self.linear[d.clone()].iter_mut().zip(&t.linear[s.clone()]) {
                        *o = c.map(|v| v as f32);
                    }
                    for (o, &c) in self.coverage[d.clone()]
                        .iter_mut()
                        .zip(&t.coverage[s.clone()])
                    {
                        *o = c as f32;
                    }
                    self.samples[d.clone()].copy_from_slice(&t.samples[s.clone()]);
                    self.depth_t[d.clone()].copy_from_slice(depth);
                    for (m, z) in self.hit_mask[d.clone()].iter_mut().zip(depth) {
                        *m = z.is_finite();
                    }
                }
                let span = Encoded {
                    color: &mut self.color[d3.clone()],
                    depth: self.depth.as_deref_mut().map(|v| &mut v[d]),
                    normals: self.normals.as_deref_mut().map(|v| &mut v[d3.clone()]),
                    class: self.class.as_deref_mut().map(|v| &mut v[d3]),
                };
                encode(t, s, span, &mut srgb, depth_range);
            }
        }
    }
}

/// `n` copies of `v`, written by the pool's threads. Most of that time is
/// the kernel faulting in fresh pages for the 50 MB of a megapixel's
/// buffers (about 10 ms either way), which threads share: output 19 ms ->
/// 15-17 ms on prospero and 10 spheres at 1024², two threads.
fn filled<T: Copy + Send + Sync>(n: usize, v: T) -> Vec<T> {
    let mut out = Vec::with_capacity(n);
    out.par_extend(rayon::iter::repeat_n(v, n));
    out
}

/// The render's images and counters from its tiles (which cover the image
/// and come in tile order: rows of tiles top to bottom, each left to
/// right); counters merge in that order, so they do not depend on the
/// thread count. Times other than the output's own are left to the
/// caller. Runs on the current rayon pool.
pub(super) fn assemble(
    outs: &[TileOut],
    opts: &RenderOptions,
    depth_range: (f64, f64),
) -> RenderOutput {
    let out_start = std::time::Instant::now();
    let (w, h) = (opts.width, opts.height);
    let npx = (w as usize) * (h as usize);
    let mut stats = RenderStats {
        width: w,
        height: h,
        ..RenderStats::default()
    };
    for t in outs {
        stats.merge(&t.state.stats);
    }
    let per_pixel = if opts.want_buffers { npx } else { 0 };
    let mut color = filled(3 * npx, 0u8);
    let mut linear = filled(per_pixel, [0.0f32; 3]);
    let mut coverage = filled(per_pixel, 0.0f32);
    let mut samples = filled(per_pixel, 0u32);
    let mut hit_mask = filled(per_pixel, false);
    let mut depth_t = filled(per_pixel, 0.0);
    let mut depth = opts.want_depth.then(|| filled(npx, 0u16));
    let mut normals = opts.want_normals.then(|| filled(3 * npx, 0u8));
    let mut class = opts.want_classify.then(|| filled(3 * npx, 0u8));

    let band_rows = (h as usize).div_ceil(TILE as usize);
    let mut tiles_of: Vec<Vec<&TileOut>> = vec![Vec::new(); band_rows];
    for t in outs {
        tiles_of[(t.y0 / TILE) as usize].push(t);
    }
    let mut rest = Rows {
        buffers: opts.want_buffers,
        color: &mut color,
        linear: &mut linear,
        coverage: &mut coverage,
        samples: &mut samples,
        hit_mask: &mut hit_mask,
        depth_t: &mut depth_t,
        depth: depth.as_deref_mut(),
        normals: normals.as_deref_mut(),
        class: class.as_deref_mut(),
    };
    let bands: Vec<Rows<'_>> = (0..h)
        .step_by(TILE as usize)
        .map(|y0| rest.split_front(TILE.min(h - y0) as usize * w as usize))
        .collect();
    bands
        .into_par_iter()
        .zip(tiles_of.par_iter())
        .for_each(|(mut rows, tiles)| rows.fill(tiles, w as usize, depth_range));

    // Every pixel lies in exactly one tile: counted there, with or
    // without the buffers.
    stats.pixels_hit = (outs.iter().flat_map(|t| &t.depth))
        .filter(|z| z.is_finite())
        .count() as u64;
    let image = |px: Vec<u8>| -> RgbImage {
        ImageBuffer::from_raw(w, h, px).expect("a buffer of 3 bytes per pixel")
    };
    let depth =
        depth.map(|d| ImageBuffer::from_raw(w, h, d).expect("a buffer of 1 sample per pixel"));
    let (image, normals, classify) = (image(color), normals.map(image), class.map(image));
    stats.output_ms = crate::render::tile::ms_since(out_start);
    RenderOutput {
        image,
        depth,
        normals,
        classify,
        hit_mask,
        depth_t,
        linear,
        coverage,
        samples,
        stats,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::prune::scope::TileState;

    // A tile of `w`×`h` pixels at (x0, y0) whose pixel values encode
    // their image position, so that any misplaced copy shows.
    fn tile(x0: u32, y0: u32, w: u32, h: u32) -> TileOut {
        let n = (w * h) as usize;
        let at = |k: usize| {
            let (i, j) = (k as u32 % w + x0, k as u32 / w + y0);
            f64::from(j * 4096 + i)
        };
        TileOut {
            x0,
            y0,
            w,
            h,
            linear: (0..n).map(|k| [at(k) / 1e7, 0.5, 0.25]).collect(),
            shadowed: vec![0; n],
            coverage: (0..n).map(|k| at(k) / 1e7).collect(),
            samples: (0..n).map(|k| at(k) as u32).collect(),
            depth: (0..n)
                .map(|k| if k % 3 == 0 { f64::INFINITY } else { at(k) })
                .collect(),
            normals: Some((0..n).map(|k| [at(k).sin(), 0.0, 0.0]).collect()),
            class: None,
            state: TileState::default(),
            classified: None,
        }
    }

    #[test]
    fn every_pixel_lands_where_its_tile_says() {
        let (w, h) = (TILE * 2 + 5, TILE + 7);
        let mut opts = RenderOptions::new(w, h);
        opts.want_depth = true;
        opts.want_normals = true;
        let outs: Vec<TileOut> = (0..h)
            .step_by(TILE as usize)
            .flat_map(|y0| {
                (0..w)
                    .step_by(TILE as usize)
                    .map(move |x0| tile(x0, y0, TILE.min(w - x0), TILE.min(h - y0)))
            })
            .collect();
        let range = (0.0, 1e6);
        let out = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| assemble(&outs, &opts, range));
        let mut hits = 0;
        for y in 0..h {
            for x in 0..w {
                let k = (y * w + x) as usize;
                let v = f64::from(y * 4096 + x);
                assert_eq!(out.samples[k], v as u32, "samples at ({x}, {y})");
                assert_eq!(out.coverage[k], (v / 1e7) as f32);
                assert_eq!(out.linear[k], [(v / 1e7) as f32, 0.5, 0.25]);
                assert_eq!(
                    out.image.get_pixel(x, y).0,
                    output::srgb_pixel([v / 1e7, 0.5, 0.25]).0
                );
                let d = out.depth_t[k];
                assert!(d == v || d == f64::INFINITY);
                assert_eq!(out.hit_mask[k], d.is_finite());
                hits += u64::from(d.is_finite());
                let depth = out.depth.as_ref().unwrap().get_pixel(x, y).0[0];
                assert_eq!(depth, output::depth_u16(d, range));
                let n = out.normals.as_ref().unwrap().get_pixel(x, y).0;
                assert_eq!(n, output::normal_or_none([v.sin(), 0.0, 0.0]).0);
            }
        }
        assert!(hits > 0);
        assert_eq!(out.stats.pixels_hit, hits);
        assert!(out.classify.is_none());

        // Without the per-pixel buffers: the same images and hit count.
        opts.want_buffers = false;
        let bare = assemble(&outs, &opts, range);
        assert_eq!(bare.image, out.image);
        assert_eq!(bare.depth, out.depth);
        assert_eq!(bare.normals, out.normals);
        assert_eq!(bare.stats.pixels_hit, hits);
        assert!(bare.hit_mask.is_empty() && bare.depth_t.is_empty());
        assert!(bare.linear.is_empty() && bare.coverage.is_empty() && bare.samples.is_empty());
    }
}
