//! The shading model's terms, and the enclosure of the colour it gives
//! over boxes of normals, view vectors and points (IAA's colour test).

use glam::DVec3;

use crate::interval::Interval;
use crate::interval::boxes::{IBox, dot as dot_box, normalize_box};
use crate::render::context::Context;
use crate::render::view::camera::normalize;
use crate::scene::LightKind;

/// Ambient light, as a fraction of the object colour.
pub const AMBIENT: f64 = 0.1;
/// Specular strength (white highlights).
pub const SPECULAR: f64 = 0.25;
/// Blinn-Phong exponent.
pub const SHININESS: i32 = 32;

/// Encloses the colour `light::shade::shade` gives (shadows aside) for every
/// unit normal in `n`, view vector in `v` and point in `p`.
pub(crate) fn colour_interval(
    ctx: &Context<'_>,
    color: [f64; 3],
    n: &IBox,
    v: &IBox,
    p: &IBox,
) -> Option<[Interval; 3]> {
    let mut c: [Interval; 3] =
        std::array::from_fn(|i| Interval::point(color[i]).mul(Interval::point(AMBIENT)));
    for light in ctx.lights {
        let l: IBox = match light.kind {
            LightKind::Directional(dir) => normalize(-DVec3::from_array(dir))?
                .to_array()
                .map(Interval::point),
            LightKind::Point(lp) => {
                normalize_box(&std::array::from_fn(|i| Interval::point(lp[i]).sub(p[i])))?
            }
        };
        let ndl = dot_box(n, &l);
        if ndl.is_empty() {
            return None;
        }
        if ndl.hi <= 0.0 {
            continue;
        }
        let h = normalize_box(&std::array::from_fn(|i| l[i].add(v[i])))?;
        let ndh = dot_box(n, &h);
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
