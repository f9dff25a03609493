//! Boxes in space as three intervals, and the vector maths over them that
//! the tracer needs (one copy of each, all outward-rounded through
//! [`Interval`]).

use super::Interval;

/// An interval box in space.
pub type IBox = [Interval; 3];

/// The point interval of each coordinate.
pub fn point_box(p: [f64; 3]) -> IBox {
    [
        Interval::point(p[0]),
        Interval::point(p[1]),
        Interval::point(p[2]),
    ]
}

/// The smallest box holding both boxes.
// Written out per axis rather than with `array::from_fn`, whose closure
// calls the optimiser did not inline in these per-pixel helpers.
pub fn box_hull(a: IBox, b: IBox) -> IBox {
    let hull = |i: usize| Interval::new(a[i].lo.min(b[i].lo), a[i].hi.max(b[i].hi));
    [hull(0), hull(1), hull(2)]
}

/// Whether `inner` lies in `outer` (false where a bound is NaN).
pub fn box_within(inner: &IBox, outer: &IBox) -> bool {
    (0..3).all(|i| outer[i].lo <= inner[i].lo && inner[i].hi <= outer[i].hi)
}

/// `a ∩ b`, or `None` when they do not meet.
pub fn box_meet(a: IBox, b: IBox) -> Option<IBox> {
    let mut out = a;
    for i in 0..3 {
        let lo = a[i].lo.max(b[i].lo);
        let hi = a[i].hi.min(b[i].hi);
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return None;
        }
        out[i] = Interval::new(lo, hi);
    }
    Some(out)
}

/// `o + t·d` for interval operands.
pub fn ray_box(o: IBox, d: IBox, t: Interval) -> IBox {
    [
        o[0].add(d[0].mul_by_positive(t)),
        o[1].add(d[1].mul_by_positive(t)),
        o[2].add(d[2].mul_by_positive(t)),
    ]
}

/// [`ray_box`] at the single parameter `t` (the same bits, half the
/// products).
#[inline]
pub fn ray_point_box(o: IBox, d: IBox, t: f64) -> IBox {
    [
        o[0].add(d[0].mul_point(t)),
        o[1].add(d[1].mul_point(t)),
        o[2].add(d[2].mul_point(t)),
    ]
}

/// An interval containing `a · b` for every pair of vectors in the boxes
/// (summed in axis order, so every caller gets the same bits).
pub fn dot(a: &IBox, b: &IBox) -> Interval {
    (0..3).fold(Interval::point(0.0), |acc, i| acc.add(a[i].mul(b[i])))
}

/// Encloses `g / |g|` for every g in the box, component by component:
/// `g_i / sqrt(g_i² + r)` (r the other components' squared length) is
/// increasing in g_i and, for fixed sign of g_i, monotone in r, so each
/// bound sits at an end of g_i and an end of r. None when the box may hold
/// the zero vector.
pub fn normalize_box(g: &IBox) -> Option<IBox> {
    if g.iter().all(|c| c.contains(0.0)) || g.iter().any(|c| c.is_empty()) {
        return None;
    }
    let mut out = [Interval::point(0.0); 3];
    for i in 0..3 {
        let r = (0..3)
            .filter(|&j| j != i)
            .fold(Interval::point(0.0), |acc, j| acc.add(g[j].square()));
        let at = |a: f64, r: f64| -> Interval {
            if a == 0.0 {
                return Interval::point(0.0);
            }
            let ai = Interval::point(a);
            ai.div(ai.square().add(Interval::point(r)).sqrt())
        };
        let lo = at(g[i].lo, if g[i].lo >= 0.0 { r.hi } else { r.lo }).lo;
        let hi = at(g[i].hi, if g[i].hi >= 0.0 { r.lo } else { r.hi }).hi;
        if lo.partial_cmp(&hi).is_none_or(|o| o.is_gt()) {
            return None;
        }
        out[i] = Interval::new(lo.max(-1.0), hi.min(1.0));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    // Bits, with every NaN as the one canonical NaN (NaN payloads are not
    // part of the semantics: see `interval::up_sum`).
    fn bits(b: IBox) -> [u64; 6] {
        [b[0].lo, b[0].hi, b[1].lo, b[1].hi, b[2].lo, b[2].hi]
            .map(|v| if v.is_nan() { f64::NAN } else { v })
            .map(f64::to_bits)
    }

    fn iv() -> impl Strategy<Value = Interval> {
        let v = prop_oneof![
            -1e3..1e3f64,
            Just(0.0),
            Just(-0.0),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(f64::MAX),
        ];
        (v.clone(), v).prop_map(|(a, b)| Interval::new(a.min(b), a.max(b)))
    }

    proptest! {
        #[test]
        fn point_ray_box_has_the_bits_of_ray_box(
            o in [iv(), iv(), iv()],
            d in [iv(), iv(), iv()],
            t in prop_oneof![-1e3..1e3f64, Just(0.0), Just(-0.0), Just(f64::INFINITY)],
        ) {
            prop_assert_eq!(bits(ray_point_box(o, d, t)), bits(ray_box(o, d, Interval::point(t))));
        }
    }
}
