//! Shading (Lambert + Blinn-Phong + ambient, linear light) and guaranteed
//! shadows.
//!
//! Shadows are in [`super::shadow`].

use glam::DVec3;

use super::shadow::{SegEnd, light_dir, point_segment_free};
use crate::interval::boxes::point_box;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::proof;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::trace::refine::illinois;
use crate::render::view::camera::{normalize, normalize_with_length};
use crate::scene::LightKind;

pub use crate::render::enclose::colour::{AMBIENT, SHININESS, SPECULAR};

/// The geometry of one hit pixel, ready for shading.
#[derive(Copy, Clone, Debug)]
pub(crate) struct HitSurface {
    /// Hit point.
    pub p: DVec3,
    /// Unit normal facing the viewer.
    pub n: DVec3,
    /// Shadow segment start: proven outside every solid, next to `p`.
    pub q: DVec3,
    /// Unit vector towards the eye.
    pub v: DVec3,
    /// Shadow segment resolution (world units).
    pub min_w: f64,
    /// Object colour (linear RGB).
    pub color: DVec3,
    /// Length of f's gradient at `p` (NaN for a cut face at the bounds).
    pub grad_len: f64,
}

/// The surfaces of a tile's hits, found by pixel. Most pixels of many
/// tiles hit nothing; a full vector of optional surfaces (144 bytes a
/// pixel) cost more to write than shading the hits of a sparse tile.
#[derive(Clone, Debug)]
pub(crate) struct TileSurfs {
    // Per pixel: the index of its surface in `list` (`NONE`: no hit).
    at: Vec<u32>,
    list: Vec<HitSurface>,
    // Per surface in `list`: its pixel.
    pixel: Vec<u32>,
}

impl TileSurfs {
    const NONE: u32 = u32::MAX;

    /// No surface on any of `n` pixels yet, room for `hits` of them (a
    /// list grown hit by hit was a tenth of a flat tile's shading).
    pub(crate) fn new(n: usize, hits: usize) -> TileSurfs {
        TileSurfs {
            at: vec![Self::NONE; n],
            list: Vec::with_capacity(hits),
            pixel: Vec::with_capacity(hits),
        }
    }

    /// Each surface with its pixel, in the order they were set.
    pub(crate) fn iter(&self) -> impl Iterator<Item = (usize, &HitSurface)> {
        self.pixel.iter().map(|&k| k as usize).zip(&self.list)
    }

    /// Pixels of the tile.
    pub(crate) fn len(&self) -> usize {
        self.at.len()
    }

    /// Sets pixel `k`'s surface (each pixel at most once).
    pub(crate) fn set(&mut self, k: usize, s: HitSurface) {
        debug_assert_eq!(self.at[k], Self::NONE);
        self.at[k] = self.list.len() as u32;
        self.list.push(s);
        self.pixel.push(k as u32);
    }

    /// Pixel `k`'s surface, if it hit.
    pub(crate) fn get(&self, k: usize) -> Option<&HitSurface> {
        self.list.get(self.at[k] as usize)
    }

    /// Pixel `k`'s surface, if it hit.
    pub(crate) fn get_mut(&mut self, k: usize) -> Option<&mut HitSurface> {
        self.list.get_mut(self.at[k] as usize)
    }
}

/// Surface geometry at a hit (normal from the point gradient).
pub(crate) fn surface(
    tr: &Scope<'_>,
    ray: &crate::render::view::camera::PixelRay,
    hit: &crate::render::Hit,
    st: &mut RenderStats,
) -> HitSurface {
    let p = DVec3::from_array(ray.at(hit.t));
    let (dm, dm_len) = normalize_with_length(DVec3::from_array(ray.dm));
    let v = -dm.unwrap_or(DVec3::Z);
    let eps = offset_length(tr, hit.t, dm_len);
    let color = DVec3::from_array(tr.ctx.colors[hit.obj]);
    if hit.inside {
        // A cut face at the bounds: face the viewer; its shadow segments
        // start on the face itself (inside the solid, which shadows it
        // wherever the light shines into the bounds).
        return HitSurface {
            p,
            n: v,
            q: p,
            v,
            min_w: 0.5 * eps,
            color,
            grad_len: f64::NAN,
        };
    }
    let d = hit
        .grad
        .unwrap_or_else(|| tr.ctx.point_grad(hit.obj, p.to_array(), st).d);
    let (nout, grad_len) = normalize_with_length(DVec3::from_array(d));
    let nout = nout.unwrap_or(v);
    let n = if nout.dot(v) < 0.0 { -nout } else { nout };
    // Shadow segments start where the root's bracket was proven outside
    // every solid, within the refinement tolerance of the surface; only a
    // contact drawn by the tangency policy, which has no such point,
    // starts `eps` (about half a pixel) off the surface along the normal.
    let q = match hit.front {
        Some(t) => DVec3::from_array(ray.at(segment_start(tr, ray, hit.obj, t, st))),
        None => p + nout * eps,
    };
    HitSurface {
        p,
        n,
        q,
        v,
        min_w: 0.5 * eps,
        color,
        grad_len,
    }
}

/// How far off the surface a hit's shadow segments start where no point
/// proven outside is at hand, and twice the shadow sweep's resolution:
/// twice the depth tolerance at `t` (`dm_len`: the length of the ray's
/// direction), or a 10⁴th of the bounds' diagonal.
fn offset_length(tr: &Scope<'_>, t: f64, dm_len: f64) -> f64 {
    (1e-4 * tr.ctx.diag).max(2.0 * tr.ctx.cam.tolerance(t) * dm_len)
}

/// Where on the ray a hit's shadow segments start: its bracket's front
/// end `front`, where f was evaluated positive, or, where rounding leaves
/// f's enclosure there straddling 0 (a secant step can land within an
/// ulp of a planar face), the first of a few points up to one root
/// tolerance further out where the enclosure proves f positive. A start
/// not proven outside costs the shadow sweep its monotonicity test on
/// the first piece, and the point a shadow.
fn segment_start(
    tr: &Scope<'_>,
    ray: &crate::render::view::camera::PixelRay,
    obj: usize,
    front: f64,
    st: &mut RenderStats,
) -> f64 {
    let tol = tr.ctx.cam.root_tolerance(front);
    [0.0, 0.125, 0.5, 1.0]
        .into_iter()
        .map(|k| front - k * tol)
        .find(|&t| proof::outside_at(tr.ctx.interval(obj, point_box(ray.at(t)), st)))
        .unwrap_or(front)
}

/// Below this fraction of the largest gradient of the same object among a
/// tile's hits, a hit's normal is recomputed at a polished root.
pub(crate) const SINGULAR_GRADIENT: f64 = 0.05;

/// How much tighter than the visibility tolerance a near-singular hit is
/// polished before its normal is taken.
const POLISH: f64 = 1e-6;

/// Sound normals where ∇f nearly vanishes on the surface.
///
/// A hit is accurate to a quarter pixel along its ray. Where ∇f is
/// regular that offset barely turns the gradient, but near a curve where
/// ∇f vanishes on the surface (the equator of `heart.ib`, where f behaves
/// like the cube of a regular function) the part of ∇f that the offset
/// adds outgrows the part that the surface's own shape gives, and the
/// normal swings to a wrong direction: a dotted dark line. Such hits are
/// recognised by a gradient far below the largest one of the same object
/// in the tile; their root is re-bracketed around the hit and refined a
/// million times tighter, and the normal is the gradient there. Where no
/// sign change brackets the hit (a tangency), the normal is kept.
pub(crate) fn mend_singular_normals(
    tr: &Scope<'_>,
    ray_of: impl Fn(usize) -> crate::render::view::camera::PixelRay,
    hits: &[Option<crate::render::Hit>],
    surfs: &mut TileSurfs,
    st: &mut RenderStats,
) {
    // Only surfaces with a gradient (no cut faces) can be near-singular.
    if surfs.list.iter().all(|s| !s.grad_len.is_finite()) {
        return;
    }
    let mut largest = vec![0.0f64; tr.ctx.evals.len()];
    for (k, h) in hits.iter().enumerate() {
        if let (Some(h), Some(s)) = (h, surfs.get(k))
            && s.grad_len.is_finite()
        {
            largest[h.obj] = largest[h.obj].max(s.grad_len);
        }
    }
    for (k, hit) in hits.iter().enumerate() {
        let (Some(hit), Some(surf)) = (hit, surfs.get_mut(k)) else {
            continue;
        };
        // A NaN length (a cut face) is never near-singular.
        let singular = surf.grad_len < SINGULAR_GRADIENT * largest[hit.obj];
        if !singular {
            continue;
        }
        let ray = &ray_of(k);
        let tol = tr.ctx.cam.tolerance(hit.t);
        let (a, b) = (hit.t - 2.0 * tol, hit.t + 2.0 * tol);
        let f = |t: f64, st: &mut RenderStats| tr.ctx.point(hit.obj, ray.at(t), st);
        let (fa, fb) = (f(a, st), f(b, st));
        if !(fa.is_finite() && fb.is_finite() && (fa <= 0.0) != (fb <= 0.0)) {
            continue;
        }
        let t = illinois(|t| f(t, st), a, b, fa, fb, POLISH * tol);
        let p = DVec3::from_array(ray.at(t));
        let g = tr.ctx.point_grad(hit.obj, p.to_array(), st);
        let Some(nout) = normalize(DVec3::from_array(g.d)) else {
            continue;
        };
        // Where the gradient nearly vanishes on the surface, no
        // monotonicity proof can start at it (f grows like the cube of the
        // distance there), and a segment from the bracket's front would be
        // drawn shadowed: such hits alone start their shadow segments
        // `eps` (about half a pixel) off the surface along the normal.
        let dm_len = DVec3::from_array(ray.dm).length();
        let eps = offset_length(tr, hit.t, dm_len);
        surf.n = if nout.dot(surf.v) < 0.0 { -nout } else { nout };
        surf.q = p + nout * eps;
        surf.p = p;
        surf.grad_len = DVec3::from_array(g.d).length();
    }
}

/// What the points [`shade`] lights one after another share, per light:
/// a directional light's direction, and the half vector of the last view
/// vector met with it (a parallel camera's is every pixel's). Each is the
/// same bits as computing it again; two square roots and two divisions a
/// light and pixel were most of shading a hit.
///
/// With [`LightMemo::with_blockers`] it also keeps, per light, where the
/// last shadowed point's segment met a solid, which the next point's
/// segment tries first (see `shadow::point_segment_free`).
#[derive(Clone, Debug, Default)]
pub(crate) struct LightMemo {
    lights: Vec<Memo>,
    blockers: Vec<Option<f64>>,
}

impl LightMemo {
    /// A memo that also keeps the blockers of `lights` lights.
    pub(crate) fn with_blockers(lights: usize) -> LightMemo {
        LightMemo {
            lights: Vec::new(),
            blockers: vec![None; lights],
        }
    }
}

/// What is already known of a point's shadows before its segments are
/// traced.
#[derive(Copy, Clone, Debug, Default)]
pub(crate) struct KnownShadows<'a> {
    /// Per light: a shadow beam proved it visible.
    pub lit_by_beam: &'a [bool],
    /// The shadowed lights (bit l) of a nearby sample this point takes.
    pub known: Option<u64>,
}

#[derive(Copy, Clone, Debug, Default)]
struct Memo {
    // A directional light's `light_dir` (which ignores the point).
    dir: Option<Option<(DVec3, SegEnd)>>,
    // The last view vector's bits and `normalize(l + v)` for it.
    half: Option<([u64; 3], Option<DVec3>)>,
}

/// Shades one surface point, given what is `known` of its shadows. Also
/// returns which lights (bit l) face the point but are shadowed there,
/// for anti-aliasing to find shadow edges. `memo` carries what one point
/// leaves for the next.
pub(crate) fn shade(
    tr: &Scope<'_>,
    s: &HitSurface,
    known: KnownShadows<'_>,
    memo: &mut LightMemo,
    st: &mut TileState,
) -> (DVec3, u64) {
    let KnownShadows { lit_by_beam, known } = known;
    let mut c = s.color * AMBIENT;
    let mut shadowed = 0u64;
    if memo.lights.len() < tr.ctx.lights.len() {
        memo.lights.resize(tr.ctx.lights.len(), Memo::default());
    }
    for (li, light) in tr.ctx.lights.iter().enumerate() {
        let m = &mut memo.lights[li];
        let directional = matches!(light.kind, LightKind::Directional(_));
        let dir = if directional {
            *m.dir.get_or_insert_with(|| light_dir(tr, light.kind, s.p))
        } else {
            light_dir(tr, light.kind, s.p)
        };
        let Some((l, end)) = dir else {
            continue;
        };
        let ndl = s.n.dot(l);
        if ndl <= 0.0 {
            continue;
        }
        let bit = 1u64.checked_shl(li as u32).unwrap_or(0);
        if let Some(bits) = known.filter(|_| light.shadows) {
            if bits & bit != 0 {
                shadowed |= bit;
                continue;
            }
        } else if light.shadows && !lit_by_beam.get(li).copied().unwrap_or(false) {
            st.stats.shadow_rays += 1;
            let blocker = memo.blockers.get(li).copied().flatten();
            let (free, found) = point_segment_free(tr, s.q, end, s.min_w, blocker, st);
            if let Some(b) = memo.blockers.get_mut(li) {
                *b = found.or(*b);
            }
            if !free {
                shadowed |= bit;
                continue;
            }
        }
        let half = if directional {
            let key = s.v.to_array().map(f64::to_bits);
            match m.half {
                Some((k, h)) if k == key => h,
                _ => {
                    let h = normalize(l + s.v);
                    m.half = Some((key, h));
                    h
                }
            }
        } else {
            normalize(l + s.v)
        };
        let h = half.unwrap_or(s.n);
        let spec = SPECULAR * crate::interval::powi_point(s.n.dot(h).max(0.0), SHININESS);
        c += DVec3::from_array(light.color) * (s.color * ndl + spec);
    }
    (c, shadowed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interval::Interval;
    use crate::interval::boxes::{IBox, normalize_box};
    use crate::scene::Light;

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
        let tr = Scope::of_objects_for_tests(&[], &lights, 8);
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
            let Some(ci) =
                crate::render::enclose::colour::colour_interval(&tr.ctx, color, &nb, &vn, &pb)
            else {
                continue;
            };
            for _ in 0..20 {
                let g: [f64; 3] = std::array::from_fn(|i| g0[i] + w * rnd());
                let Some(n) = normalize(DVec3::from_array(g)) else {
                    continue;
                };
                let v = normalize(DVec3::from_array(std::array::from_fn(|i| {
                    vb[i].lo + rnd() * vb[i].width()
                })))
                .unwrap();
                let p = DVec3::new(0.1 + 0.1 * rnd(), 0.1 + 0.1 * rnd(), 0.1 + 0.1 * rnd());
                let surf = HitSurface {
                    p,
                    n,
                    q: p,
                    v,
                    min_w: 1e-3,
                    color: DVec3::from_array(color),
                    grad_len: 1.0,
                };
                let mut st = TileState::default();
                let memo = &mut LightMemo::default();
                let known = KnownShadows {
                    lit_by_beam: &[true, true],
                    known: None,
                };
                let (c, _) = shade(&tr, &surf, known, memo, &mut st);
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
}
