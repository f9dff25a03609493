//! Anti-aliasing: interval adaptive anti-aliasing (IAA, after Flórez et
//! al.) and regular grid supersampling, the baseline.
//!
//! # IAA
//! After the base render (one ray through each pixel centre), each tile is
//! revisited as beams over the *whole area* of its pixels, starting with
//! the tile and quartering down to single pixels. A block's beam gets the
//! front-to-back rejection sweep of [`super::beam`] over its hull clipped
//! to the bounds and, where a surface remains, the inclusion test; the
//! outcome is one of:
//! - *background*: every ray of the block misses: no extra sample, the
//!   pixels are background exactly;
//! - *smooth*: every ray of the block hits one object (the only one that
//!   may vanish on the included beam piece) in a proven bracket, and the
//!   interval of the lit colour over that piece — Lambert and Blinn-Phong
//!   terms bounded with interval arithmetic over the interval of the unit
//!   normal (from `interval_grad`), the view directions and the light
//!   directions — is narrower than the threshold in every channel: each
//!   pixel keeps its one base sample;
//! - *split*: anything else, in particular silhouettes and thin features,
//!   which the tests cannot settle. A single pixel that is split gets
//!   `2^depth × 2^depth` sub-samples: the split pixels of a tile are traced
//!   together as one beam tile of the `2^depth`× image, every other
//!   sub-sample masked out, so sub-beams keep splitting 2×2 down to single
//!   sub-samples and a sub-beam that is rejected contributes background
//!   exactly, with no ray. Sub-samples sit where `grid:2^depth` puts them
//!   and have its depth tolerance. Their linear colours are averaged.
//!
//! Shadows are not part of the colour interval (proving a shadow edge
//! absent over a beam needs a shadow beam from a surface patch, which the
//! surface itself obstructs). Instead a hit pixel whose base sample has
//! another set of shadowed lights than a hit 4-neighbour's (in the same
//! tile) is never smooth: shadow edges are split like silhouettes. This is
//! a sampling heuristic, not a proof: a shadow narrower than the pixel
//! spacing can fall between base samples, and an edge running exactly
//! along a tile border is not seen. The
//! pixel's centre ray is never discarded when it is the only evidence of
//! surface: if every sub-sample of a split pixel misses but the centre ray
//! hit, the centre sample joins the average with a sub-sample's weight, so
//! an AA render never loses a pixel the plain render drew.
//!
//! # Grid
//! `grid:N` traces the image at N× the resolution with the chosen method
//! (beams then span sub-samples) and averages each N×N block in linear
//! light.

use std::fmt;

use super::Tracer;
use super::camera::{CornerRays, bounds_box, normalize, scale};
#[cfg(test)]
use super::shade;
use super::shade::{AMBIENT, SHININESS, SPECULAR};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_hull, dot, normalize_box};
use crate::render::stats::RenderStats;
use crate::scene::LightKind;

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

impl Aa {
    /// Parses `none`, `iaa` (default threshold and depth) or `grid:N`.
    pub fn parse(s: &str) -> Result<Aa, String> {
        match s.trim() {
            "none" => Ok(Aa::None),
            "iaa" => Ok(Aa::Iaa {
                threshold: DEFAULT_THRESHOLD,
                depth: DEFAULT_DEPTH,
            }),
            t => {
                let n = t
                    .strip_prefix("grid:")
                    .ok_or_else(|| format!("anti-aliasing `{s}` is not none, iaa or grid:N"))?;
                let n: u32 = n
                    .parse()
                    .map_err(|_| format!("anti-aliasing `{s}`: `{n}` is not a whole number"))?;
                let aa = Aa::Grid(n);
                aa.validate()?;
                Ok(aa)
            }
        }
    }

    /// Checks the parameters' ranges.
    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Aa::None => Ok(()),
            Aa::Grid(n) if (1..=MAX_GRID).contains(&n) => Ok(()),
            Aa::Grid(n) => Err(format!("grid:{n}: N must be in 1..={MAX_GRID}")),
            Aa::Iaa { threshold, depth } => {
                if !(threshold >= 0.0 && threshold.is_finite()) {
                    Err(format!("IAA threshold {threshold} must be finite and ≥ 0"))
                } else if depth > MAX_DEPTH {
                    Err(format!("IAA depth {depth} must be in 0..={MAX_DEPTH}"))
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

/// The IAA results of one tile, row-major within the tile.
pub(crate) struct TilePixels<'a> {
    /// Left column of the tile (pixels).
    pub x0: u32,
    /// Top row of the tile (pixels).
    pub y0: u32,
    /// Tile width.
    pub w: u32,
    /// Tile height.
    pub h: u32,
    /// Linear colour of the base render, replaced by the AA average.
    pub linear: &'a mut [[f64; 3]],
    /// Ray parameter of the base hit (+inf: none), min over samples after.
    pub depth: &'a mut [f64],
    /// Fraction of the pixel's samples (by area) that hit.
    pub coverage: &'a mut [f64],
    /// Samples per pixel.
    pub samples: &'a mut [u32],
    /// Lights shadowed at each base sample (bit per light).
    pub shadowed: &'a [u64],
}

/// What a cell's beam tests decided.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Cell {
    Background,
    Smooth,
    Split,
}

/// A cell's test outcome and the rejected prefix its children inherit.
struct Decision {
    cell: Cell,
    t_floor: f64,
    /// The beam was included: only the colour interval was too wide.
    by_shading: bool,
}

/// The pixel-area tests of IAA over one tile whose base render is in
/// `px`: background and smooth pixels are settled in place (background
/// colour, or the base sample); returns which pixels need sub-samples.
pub(crate) fn classify_tile(
    tr: &Tracer<'_>,
    px: &mut TilePixels<'_>,
    background: [f64; 3],
    threshold: f64,
    st: &mut RenderStats,
) -> Vec<bool> {
    let n = (px.w * px.h) as usize;
    let mut split = vec![false; n];
    // A hit pixel whose shadow state differs from a hit neighbour's sits
    // on a shadow edge (neighbours in other tiles are not seen, so an edge
    // running exactly along a tile border is missed).
    let hit = |i: u32, j: u32| px.depth[(j * px.w + i) as usize].is_finite();
    let shadow_edge: Vec<bool> = (0..n)
        .map(|k| {
            let (i, j) = (k as u32 % px.w, k as u32 / px.w);
            hit(i, j)
                && [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)]
                    .iter()
                    .any(|&(di, dj)| {
                        let (ni, nj) = (i64::from(i) + di, i64::from(j) + dj);
                        (0..i64::from(px.w)).contains(&ni)
                            && (0..i64::from(px.h)).contains(&nj)
                            && hit(ni as u32, nj as u32)
                            && px.shadowed[(nj as u32 * px.w + ni as u32) as usize]
                                != px.shadowed[k]
                    })
        })
        .collect();
    let ctx = Ctx {
        tr,
        background,
        threshold,
        shadow_edge: &shadow_edge,
    };
    ctx.block(px, &mut split, (0, 0, px.w, px.h), 0.0, st);
    split
}

/// Per pixel: mean linear colour, covered fraction and nearest hit of the
/// sub-samples.
pub(crate) type FineSamples<'a> = (&'a [[f64; 3]], &'a [f64], &'a [f64]);

/// Folds the sub-samples of the split pixels (`fine`: per pixel the mean
/// linear colour, covered fraction and nearest hit of its `per` samples)
/// into the tile, and counts the samples.
pub(crate) fn merge_split(
    px: &mut TilePixels<'_>,
    split: &[bool],
    fine: Option<FineSamples<'_>>,
    per: u32,
    st: &mut RenderStats,
) {
    for k in 0..split.len() {
        let centre_hit = px.depth[k].is_finite();
        match fine {
            Some((lin, cov, dep)) if split[k] => {
                let (mut c, mut h) = (lin[k], cov[k]);
                let mut s = per;
                if h == 0.0 && centre_hit {
                    // Keep the proof of surface the centre ray gave: it
                    // joins the average with the weight of one sample.
                    let wl = 1.0 / f64::from(per);
                    let tot = 1.0 + wl;
                    c = std::array::from_fn(|i| (c[i] + wl * px.linear[k][i]) / tot);
                    h = wl / tot;
                    s += 1;
                }
                px.linear[k] = c;
                px.coverage[k] = h;
                px.depth[k] = px.depth[k].min(dep[k]);
                px.samples[k] = s;
            }
            _ => {
                px.coverage[k] = if centre_hit { 1.0 } else { 0.0 };
                px.samples[k] = 1;
            }
        }
        let s = u64::from(px.samples[k]);
        st.aa_samples += s;
        st.aa_samples_max = st.aa_samples_max.max(s);
        st.aa_pixels_split += u64::from(s > 1);
    }
}

struct Ctx<'t, 'a> {
    tr: &'t Tracer<'a>,
    background: [f64; 3],
    threshold: f64,
    /// Pixels on a shadow edge (see `classify_tile`).
    shadow_edge: &'t [bool],
}

impl Ctx<'_, '_> {
    // A block of whole pixels (tile coordinates, half-open).
    fn block(
        &self,
        px: &mut TilePixels<'_>,
        split: &mut [bool],
        (bx0, by0, bx1, by1): (u32, u32, u32, u32),
        t_floor: f64,
        st: &mut RenderStats,
    ) {
        let xs = (f64::from(px.x0 + bx0), f64::from(px.x0 + bx1));
        let ys = (f64::from(px.y0 + by0), f64::from(px.y0 + by1));
        let d = self.test(xs, ys, t_floor, st);
        // A verdict stands only where every base ray agrees with it (a
        // rounding disagreement between a beam and a ray is settled by
        // looking closer).
        let agrees = |px: &TilePixels<'_>, want_hit: bool| {
            (by0..by1).all(|j| {
                (bx0..bx1).all(|i| px.depth[(j * px.w + i) as usize].is_finite() == want_hit)
            })
        };
        let edge_in = |px: &TilePixels<'_>| {
            (by0..by1).any(|j| (bx0..bx1).any(|i| self.shadow_edge[(j * px.w + i) as usize]))
        };
        match d.cell {
            Cell::Background if agrees(px, false) => {
                for j in by0..by1 {
                    for i in bx0..bx1 {
                        px.linear[(j * px.w + i) as usize] = self.background;
                    }
                }
                return;
            }
            Cell::Smooth if agrees(px, true) && !edge_in(px) => return,
            _ => {}
        }
        if bx1 - bx0 == 1 && by1 - by0 == 1 {
            let k = (by0 * px.w + bx0) as usize;
            split[k] = true;
            let edge = d.cell == Cell::Smooth && self.shadow_edge[k];
            st.aa_split_by_shading += u64::from(d.by_shading || edge);
            return;
        }
        let mx = (bx0 + bx1).div_ceil(2);
        let my = (by0 + by1).div_ceil(2);
        for (y0, y1) in [(by0, my), (my, by1)] {
            for (x0, x1) in [(bx0, mx), (mx, bx1)] {
                if x0 < x1 && y0 < y1 {
                    self.block(px, split, (x0, y0, x1, y1), d.t_floor, st);
                }
            }
        }
    }

    // The beam tests of the screen rectangle xs × ys (whole area).
    fn test(&self, xs: (f64, f64), ys: (f64, f64), t_floor: f64, st: &mut RenderStats) -> Decision {
        let tr = self.tr;
        let split = |t_floor| Decision {
            cell: Cell::Split,
            t_floor,
            by_shading: false,
        };
        let corners = tr.cam.corners(xs, ys);
        let bounds = bounds_box(&tr.bounds);
        let t1 = far_t(&corners, &bounds);
        let t0 = t_floor.max(0.0);
        if t0.partial_cmp(&t1).is_none_or(|o| o.is_gt()) {
            return Decision {
                cell: Cell::Background,
                t_floor,
                by_shading: false,
            };
        }
        let side = (xs.1 - xs.0).max(ys.1 - ys.0);
        let min_w = |t: f64| side * tr.cam.spacing(t).max(1e-9);
        let n = tr.evals.len();
        // F over the part of the beam piece inside the bounds; None when
        // the piece lies wholly outside them.
        let eval_min = |t: Interval, st: &mut RenderStats| -> Option<Interval> {
            let hb = crate::interval::boxes::box_meet(corners.hull(t), bounds)?;
            let mut f = Interval::point(f64::INFINITY);
            for k in 0..n {
                let v = tr.interval_tight(k, hb, 0, st);
                if !v.is_empty() {
                    f = f.min(v);
                }
            }
            Some(f)
        };
        if tr.flat {
            // Constant along the rays: no bracket to include.
            let rejected = eval_min(Interval::new(t0, t1), st).is_none_or(|f| f.lo > 0.0);
            return Decision {
                cell: if rejected {
                    Cell::Background
                } else {
                    Cell::Split
                },
                t_floor,
                by_shading: false,
            };
        }
        let found = super::beam::first_candidate(t0, t1, min_w, |t| {
            eval_min(t, st).is_none_or(|f| f.lo > 0.0)
        });
        let Some((ta, tb)) = found else {
            return Decision {
                cell: Cell::Background,
                t_floor,
                by_shading: false,
            };
        };
        // Inclusion: the unclipped cross-sections at ta (positive) and at
        // tb2 (negative), the piece between inside the bounds (so no ray
        // leaves them before its root), one object that may vanish there,
        // strictly decreasing along every ray.
        let whole = |t: Interval, st: &mut RenderStats| -> Interval {
            let hb = corners.hull(t);
            let mut f = Interval::point(f64::INFINITY);
            for k in 0..n {
                let v = tr.interval(k, hb, st);
                if !v.is_empty() {
                    f = f.min(v);
                }
            }
            f
        };
        if whole(Interval::point(ta), st).lo <= 0.0 {
            return split(ta);
        }
        let w = (tb - ta).max(min_w(ta));
        for mult in [1.0, 2.0, 4.0] {
            let tb2 = (ta + mult * w).min(t1);
            if whole(Interval::point(tb2), st).hi < 0.0 {
                // Narrow the bracket while a mid cross-section has one
                // sign: the normal's enclosure over the piece tightens
                // with its depth.
                let (mut a, mut b) = (ta, tb2);
                for _ in 0..NARROW_STEPS {
                    let m = 0.5 * (a + b);
                    let fm = whole(Interval::point(m), st);
                    if fm.lo > 0.0 {
                        a = m;
                    } else if fm.hi < 0.0 {
                        b = m;
                    } else {
                        break;
                    }
                }
                let piece = Interval::new(a, b);
                let smooth = self.smooth_on(&corners, &bounds, piece, st);
                return Decision {
                    cell: if smooth == Some(true) {
                        Cell::Smooth
                    } else {
                        Cell::Split
                    },
                    t_floor: ta,
                    by_shading: smooth == Some(false),
                };
            }
            if tb2 >= t1 {
                break;
            }
        }
        split(ta)
    }

    // None unless one object alone may vanish on the beam piece and it
    // decreases strictly along every ray there (facing the viewer
    // throughout); then whether the lit colour's interval over the piece
    // is narrower than the threshold.
    fn smooth_on(
        &self,
        corners: &CornerRays,
        bounds: &IBox,
        piece: Interval,
        st: &mut RenderStats,
    ) -> Option<bool> {
        let tr = self.tr;
        let hb = corners.hull(piece);
        if (0..3).any(|i| hb[i].lo < bounds[i].lo || hb[i].hi > bounds[i].hi) {
            return None;
        }
        let mut only = None;
        for k in 0..tr.evals.len() {
            let f = tr.interval(k, hb, st);
            if f.is_empty() || f.lo > 0.0 {
                continue;
            }
            if only.is_some() {
                return None;
            }
            only = Some(k);
        }
        let k = only?;
        let c = &corners.0;
        let dirs = box_hull(box_hull(c[0].1, c[1].1), box_hull(c[2].1, c[3].1));
        let g = tr.interval_grad(k, hb, st);
        if !g.d.iter().all(|d| d.lo.is_finite() && d.hi.is_finite()) {
            return None;
        }
        let dfdt = dot(&g.d, &dirs);
        if dfdt.is_empty() || dfdt.hi >= 0.0 {
            return None;
        }
        let nout = normalize_box(&g.d)?;
        let v = normalize_box(&dirs.map(|d| d.neg()))?;
        let facing = dot(&nout, &v);
        let n = if facing.lo > 0.0 {
            nout
        } else if facing.hi < 0.0 {
            nout.map(|c| c.neg())
        } else {
            return None;
        };
        let col = colour_interval(tr, tr.colors[k], &n, &v, &hb)?;
        Some(
            col.iter()
                .all(|c| c.hi.clamp(0.0, 1.0) - c.lo.clamp(0.0, 1.0) <= self.threshold),
        )
    }
}

/// Encloses the colour `shade::shade` gives (shadows aside) for every
/// unit normal in `n`, view vector in `v` and point in `p`.
fn colour_interval(
    tr: &Tracer<'_>,
    color: [f64; 3],
    n: &IBox,
    v: &IBox,
    p: &IBox,
) -> Option<[Interval; 3]> {
    let mut c: [Interval; 3] =
        std::array::from_fn(|i| Interval::point(color[i]).mul(Interval::point(AMBIENT)));
    for light in tr.lights {
        let l: IBox = match light.kind {
            LightKind::Directional(dir) => normalize(scale(dir, -1.0))?.map(Interval::point),
            LightKind::Point(lp) => {
                normalize_box(&std::array::from_fn(|i| Interval::point(lp[i]).sub(p[i])))?
            }
        };
        let ndl = dot(n, &l);
        if ndl.is_empty() {
            return None;
        }
        if ndl.hi <= 0.0 {
            continue;
        }
        let h = normalize_box(&std::array::from_fn(|i| l[i].add(v[i])))?;
        let ndh = dot(n, &h);
        let ndh = Interval::new(ndh.lo.max(0.0), ndh.hi.max(0.0));
        let spec = Interval::point(SPECULAR).mul(ndh.powi(SHININESS));
        let lam = Interval::new(ndl.lo.max(0.0), ndl.hi);
        for (ch, out) in c.iter_mut().enumerate() {
            let mut add =
                Interval::point(light.color[ch]).mul(Interval::point(color[ch]).mul(lam).add(spec));
            if ndl.lo <= 0.0 {
                // The light may be behind the surface for some normals.
                add = Interval::new(add.lo.min(0.0), add.hi.max(0.0));
            }
            *out = out.add(add);
        }
    }
    c.iter()
        .all(|i| !i.is_empty() && i.lo.is_finite() && i.hi.is_finite())
        .then_some(c)
}

// A ray parameter beyond which every ray of the cell is outside the
// bounds: |d| ≥ 1 for both projections, so a point at parameter t is at
// least t from its origin, and the distance from an origin in the cell
// (convex in the origin) to the bounds is largest at a corner pair.
fn far_t(corners: &CornerRays, bounds: &IBox) -> f64 {
    let mut far = 0.0f64;
    for (o, _) in &corners.0 {
        for cx in [bounds[0].lo, bounds[0].hi] {
            for cy in [bounds[1].lo, bounds[1].hi] {
                for cz in [bounds[2].lo, bounds[2].hi] {
                    let d2 = [cx, cy, cz]
                        .iter()
                        .zip(o)
                        .map(|(c, oi)| {
                            let e = (c - oi.lo).abs().max((c - oi.hi).abs());
                            e * e
                        })
                        .sum::<f64>();
                    far = far.max(d2.sqrt());
                }
            }
        }
    }
    far * (1.0 + 1e-9) + 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::camera::RayCamera;
    use crate::scene::{Bounds, Camera, Light};

    // The colour interval holds the shaded colour of every normal, view
    // vector and point in its boxes (lights without shadows here).
    #[test]
    fn colour_interval_encloses_the_shading() {
        let lights = [
            Light {
                kind: LightKind::Directional([-0.5, -1.0, -0.7]),
                color: [1.0, 1.0, 1.0],
                shadows: false,
            },
            Light {
                kind: LightKind::Point([-4.0, 3.0, 5.0]),
                color: [0.35, 0.35, 0.4],
                shadows: false,
            },
        ];
        let tr = Tracer {
            cam: RayCamera::new(&Camera::default(), 8, 8).unwrap(),
            evals: &[],
            colors: vec![],
            lights: &lights,
            bounds: Bounds::default(),
            diag: 7.0,
            live_ops: vec![0; 1],
            prune: false,
            flat: false,
        };
        let color = [0.8, 0.3, 0.2];
        let mut seed = 0x1234_5678_9abc_def0u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let g0 = [rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0];
            let w = 0.3 * rnd();
            let gb: IBox = std::array::from_fn(|i| Interval::new(g0[i], g0[i] + w));
            let vb: IBox = [
                Interval::new(0.4, 0.45),
                Interval::new(0.3, 0.32),
                Interval::new(0.8, 0.83),
            ];
            let pb: IBox = [Interval::new(0.1, 0.2); 3];
            let (Some(nb), Some(vn)) = (normalize_box(&gb), normalize_box(&vb)) else {
                continue;
            };
            let Some(ci) = colour_interval(&tr, color, &nb, &vn, &pb) else {
                continue;
            };
            for _ in 0..20 {
                let g: [f64; 3] = std::array::from_fn(|i| g0[i] + w * rnd());
                let Some(n) = normalize(g) else { continue };
                let v =
                    normalize(std::array::from_fn(|i| vb[i].lo + rnd() * vb[i].width())).unwrap();
                let p = [0.1 + 0.1 * rnd(), 0.1 + 0.1 * rnd(), 0.1 + 0.1 * rnd()];
                let surf = shade::Surf {
                    p,
                    n,
                    q: p,
                    v,
                    min_w: 1e-3,
                    color,
                };
                let mut st = RenderStats::default();
                let (c, _) = shade::shade(&tr, &surf, &[true, true], &mut st);
                for ch in 0..3 {
                    assert!(
                        ci[ch].lo - 1e-12 <= c[ch] && c[ch] <= ci[ch].hi + 1e-12,
                        "{ch}: {} not in {:?}",
                        c[ch],
                        ci[ch]
                    );
                }
            }
        }
    }

    #[test]
    fn modes_parse() {
        assert_eq!(Aa::parse("none"), Ok(Aa::None));
        assert_eq!(Aa::parse("grid:4"), Ok(Aa::Grid(4)));
        assert!(matches!(Aa::parse("iaa"), Ok(Aa::Iaa { depth: 2, .. })));
        assert!(Aa::parse("grid:0").is_err());
        assert!(Aa::parse("grid:x").is_err());
        assert!(Aa::parse("ssaa").is_err());
    }

    #[test]
    fn normalized_box_holds_every_unit_vector() {
        let g = [
            Interval::new(0.5, 2.0),
            Interval::new(-1.0, 0.25),
            Interval::new(3.0, 3.5),
        ];
        let n = normalize_box(&g).unwrap();
        for a in [0.5, 1.0, 2.0] {
            for b in [-1.0, 0.0, 0.25] {
                for c in [3.0f64, 3.5] {
                    let l = (a * a + b * b + c * c).sqrt();
                    for (i, v) in [a / l, b / l, c / l].iter().enumerate() {
                        assert!(n[i].contains(*v), "{i} {v} {:?}", n[i]);
                    }
                }
            }
        }
        let z = [Interval::new(-1.0, 1.0); 3];
        assert!(normalize_box(&z).is_none());
    }
}
