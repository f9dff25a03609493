//! One pixel's ray and the boxes along it.

use glam::DVec3;

use super::camera::*;
use crate::scene::Bounds;

/// One pixel's ray.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PixelRay {
    /// Enclosure of the origin.
    pub o: IBox,
    /// Enclosure of the direction.
    pub d: IBox,
    /// Origin midpoint (for point evaluation).
    pub om: [f64; 3],
    /// Direction midpoint.
    pub dm: [f64; 3],
}

impl PixelRay {
    /// The ray with origin and direction enclosures `o` and `d`, and their
    /// midpoints.
    pub(crate) fn new(o: IBox, d: IBox) -> PixelRay {
        PixelRay {
            o,
            d,
            om: [o[0].mid(), o[1].mid(), o[2].mid()],
            dm: [d[0].mid(), d[1].mid(), d[2].mid()],
        }
    }

    /// The f64 point at parameter t (for point evaluation and shading).
    pub fn at(&self, t: f64) -> [f64; 3] {
        (DVec3::from_array(self.om) + DVec3::from_array(self.dm) * t).to_array()
    }

    /// The parameter range inside `b` (slab test), widened a little so it
    /// covers the exact range despite rounding, clipped to t ≥ 0; `None`
    /// when the ray misses the box.
    pub fn slab(&self, b: &Bounds) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for i in 0..3 {
            let (o, d) = (self.om[i], self.dm[i]);
            if d == 0.0 {
                if o < b.min[i] || o > b.max[i] {
                    return None;
                }
                continue;
            }
            let a = (b.min[i] - o) / d;
            let c = (b.max[i] - o) / d;
            let (lo, hi) = if a < c { (a, c) } else { (c, a) };
            t0 = t0.max(lo - SLAB_PAD * (1.0 + lo.abs()));
            t1 = t1.min(hi + SLAB_PAD * (1.0 + hi.abs()));
        }
        (t0 <= t1 && t1.is_finite()).then_some((t0, t1))
    }
}
