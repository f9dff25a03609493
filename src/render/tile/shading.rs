//! The tile's hits lit: shadow beams over included blocks, then each
//! pixel shaded, with cut faces and singular normals handled.

use super::*;
use crate::render::light::shade::KnownShadows;

// Shadow beams over the included blocks: row-major per pixel and light,
// whether one beam proved the pixel lit. Pixels whose shadow state is
// `known` (row-major; empty: none is) stay out of the beams: shading
// never reads the beams' answer for them.
pub(super) fn shadow_beams(
    tr: &Scope<'_>,
    tile: &TileRays,
    surfs: &TileSurfs,
    known: &[Option<u64>],
    ts: &mut TileState,
) -> Vec<bool> {
    let t_shadow = Instant::now();
    let nl = tr.ctx.lights.len();
    let mut lit_by_beam = vec![false; surfs.len() * nl];
    let mut blockers = vec![None; nl];
    for b in &tile.included {
        for (li, light) in tr.ctx.lights.iter().enumerate() {
            if !light.shadows {
                continue;
            }
            let mut members = Vec::new();
            let mut pts = Vec::new();
            for (i, j) in b.pixels() {
                let k = (j * tile.w + i) as usize;
                let Some(&s) = surfs.get(k) else { continue };
                if known.get(k).is_some_and(Option::is_some) {
                    continue;
                }
                let facing =
                    shadow::light_dir(tr, light.kind, s.p).is_some_and(|(l, _)| s.n.dot(l) > 0.0);
                if facing {
                    members.push(k);
                    pts.push(s);
                }
            }
            if members.len() < 2 {
                continue;
            }
            ts.stats.shadow_beams += 1;
            if shadow::shadow_beam(tr, &pts, light.kind, &mut blockers[li], ts) {
                ts.stats.shadow_beams_ok += 1;
                ts.stats.shadow_rays_saved += members.len() as u64;
                for k in members {
                    lit_by_beam[k * nl + li] = true;
                }
            }
        }
    }
    ts.stats.shadow_cpu_ms += ms_since(t_shadow);
    lit_by_beam
}

// The shaded pixels of a tile.
pub(super) struct LitPixels {
    pub(super) linear: Vec<[f64; 3]>,
    pub(super) shadowed: Vec<u64>,
    pub(super) normals: Option<Vec<[f64; 3]>>,
}

/// The cut faces of a tile (hits where a ray starts inside a solid, at the
/// bounds: every hit of a flat scene), lit once per object where every
/// pixel's ray has the same direction and every light is directional. A
/// cut face's normal faces the viewer along the ray (`shade::surface`), so
/// where no light's shadow segment from it meets the bounds (no light
/// casts shadows, or each shines from outside the bounds) its colour
/// depends on the object alone: the one `shade::shade` gives its first
/// such pixel is every such pixel's, bit for bit. Shading each of them was
/// a tenth of prospero's render. The others are shaded one by one.
pub(super) struct CutFaces {
    // Per object: the colour and shadow bits of its cut faces lit from
    // outside the bounds, and their normal, once one of them is shaded.
    pub(super) shaded: Vec<Option<(DVec3, u64, DVec3)>>,
}

impl CutFaces {
    // The tile's cut faces, where they share their object's colour.
    pub(super) fn of(tr: &Scope<'_>, tile: &TileRays) -> Option<CutFaces> {
        let uniform = tile.grid.shared_direction().is_some()
            && tr
                .ctx
                .lights
                .iter()
                .all(|l| matches!(l.kind, LightKind::Directional(_)));
        uniform.then(|| CutFaces {
            shaded: vec![None; tr.ctx.evals.len()],
        })
    }

    // Lights every cut face of the tile in `lit`.
    pub(super) fn paint(
        mut self,
        tr: &Scope<'_>,
        tile: &TileRays,
        known: &[Option<u64>],
        lit: &mut LitPixels,
        st: &mut TileState,
    ) {
        let memo = &mut shade::LightMemo::with_blockers(tr.ctx.lights.len());
        for (k, h) in tile.hits.iter().enumerate() {
            let Some(h) = h.filter(|h| h.inside) else {
                continue;
            };
            let s = shade::surface(tr, &tile.ray(k), &h, &mut st.stats);
            // A pixel taking a nearby sample's shadows (IAA) takes them.
            let known = KnownShadows {
                lit_by_beam: &[],
                known: known.get(k).copied().flatten(),
            };
            let mut shade_one = |st: &mut TileState| {
                let (c, shadowed) = shade::shade(tr, &s, known, memo, st);
                (c, shadowed, s.n)
            };
            let (c, shadowed, n) = if known.known.is_none() && lit_from_outside(tr, &s) {
                *self.shaded[h.obj].get_or_insert_with(|| shade_one(st))
            } else {
                shade_one(st)
            };
            lit.linear[k] = c.to_array();
            lit.shadowed[k] = shadowed;
            if let Some(nv) = lit.normals.as_mut() {
                nv[k] = n.to_array();
            }
        }
    }
}

// Whether no shadow segment of the (cut face) point `s` meets the bounds:
// every light casting shadows on it shines from outside them.
fn lit_from_outside(tr: &Scope<'_>, s: &shade::HitSurface) -> bool {
    tr.ctx.lights.iter().filter(|l| l.shadows).all(|l| {
        shadow::light_dir(tr, l.kind, s.p)
            .is_none_or(|(dir, end)| s.n.dot(dir) <= 0.0 || shadow::misses_bounds(tr, s.q, end))
    })
}

/// What is known of a tile's shadows before its pixels' segments.
pub(super) struct PixelShadows<'a> {
    /// Per pixel and light (`nl` a pixel): a shadow beam proved the light
    /// visible.
    pub lit_by_beam: &'a [bool],
    /// Per pixel (empty: none): the shadowed lights of a nearby sample it
    /// takes.
    pub known: &'a [Option<u64>],
}

// Lights every hit (the background elsewhere), with per-pixel shadow
// segments for the lights no shadow beam settled.
pub(super) fn shade_pixels(
    tr: &Scope<'_>,
    surfs: &TileSurfs,
    known: PixelShadows<'_>,
    background: [f64; 3],
    opts: &RenderOptions,
    ts: &mut TileState,
) -> LitPixels {
    let PixelShadows { lit_by_beam, known } = known;
    let t_shade = Instant::now();
    let (n, nl) = (surfs.len(), tr.ctx.lights.len());
    let mut linear = vec![background; n];
    let mut shadowed = vec![0u64; n];
    let mut normals = opts.want_normals.then(|| vec![[f64::NAN; 3]; n]);
    // Shadow segments time themselves (`shadow::point_segment_free`):
    // reading the clock twice a pixel cost more than shading it.
    let shadow_before = ts.stats.shadow_cpu_ms;
    // Per light, where the last shadowed sample's segment met a solid
    // (see `shadow::point_segment_free`).
    let mut memo = shade::LightMemo::with_blockers(nl);
    for (k, s) in surfs.iter() {
        let (c, sh) = shade::shade(
            tr,
            s,
            KnownShadows {
                lit_by_beam: &lit_by_beam[k * nl..(k + 1) * nl],
                known: known.get(k).copied().flatten(),
            },
            &mut memo,
            ts,
        );
        linear[k] = c.to_array();
        shadowed[k] = sh;
        if let Some(nv) = normals.as_mut() {
            nv[k] = s.n.to_array();
        }
    }
    let shadow_ms = ts.stats.shadow_cpu_ms - shadow_before;
    ts.stats.shade_cpu_ms += (ms_since(t_shade) - shadow_ms).max(0.0);
    LitPixels {
        linear,
        shadowed,
        normals,
    }
}

/// The classification map's colour of a pixel.
pub(super) fn class_color(c: Class) -> Rgb<u8> {
    match c {
        Class::Outside => Rgb([0, 0, 0]),
        Class::Background => Rgb([30, 50, 140]),
        Class::Included => Rgb([40, 180, 70]),
        Class::Ray => Rgb([210, 60, 40]),
    }
}
