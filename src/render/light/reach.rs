//! How far along a shadow segment its points can still lie in the bounds.
//!
//! Outside the bounds there is no surface, so a shadow sweep never needs
//! the pieces beyond the last parameter at which a segment can be inside
//! them. The sweep used to visit them all the same (each dropped by a box
//! test, but up to 1024 of them per segment): on a flat model, where every
//! hit is a cut face whose segment leaves the bounds at once, that was
//! nearly all of a default render's time.

use crate::interval::Interval;
use crate::interval::boxes::IBox;

/// An upper bound on the parameters `s ≥ 0` at which a point `p + s·d`
/// (`p` in the box `q`, `d` in the box `delta`) lies in `bounds`: for
/// every larger `s`, every such point is outside them. Negative where no
/// such point is inside them even at `s = 0`; infinite where no axis
/// proves the segments leaving (a direction component that may be 0).
pub(crate) fn inside_until(q: &IBox, delta: &IBox, bounds: &IBox) -> f64 {
    // `f64::min` ignores a NaN operand (an infinite bound's 0 · ∞), which
    // leaves that axis proving nothing, as it should.
    (0..3)
        .map(|i| axis_until(q[i], delta[i], bounds[i]))
        .fold(f64::INFINITY, f64::min)
}

// One axis of `inside_until`. Moving up (every d > 0), a point with
// coordinate x ≥ q.lo is past the top once s > (b.hi − q.lo) / d.lo: s·d ≥
// s·d.lo > b.hi − q.lo for s ≥ 0 (for a negative quotient, x ≥ q.lo > b.hi
// already). The quotient is rounded up (outward-rounded intervals), so
// every s above the bound is above the real quotient. Moving down is the
// mirror image.
fn axis_until(q: Interval, d: Interval, b: Interval) -> f64 {
    let quotient = |room: Interval, speed: f64| room.div(Interval::point(speed)).hi;
    if d.lo > 0.0 {
        quotient(Interval::point(b.hi).sub(Interval::point(q.lo)), d.lo)
    } else if d.hi < 0.0 {
        quotient(Interval::point(q.hi).sub(Interval::point(b.lo)), -d.hi)
    } else {
        f64::INFINITY
    }
}

/// The pieces of `[0, 1]` cut in `n` equal ones, as
/// `prune::scope::equal_pieces(0.0, 1.0, n)` cuts them (bit for bit), that
/// start at or before `until`, last first (the sweep's stack order):
/// building all `n` to drop most of them cost as much as the rest of a
/// cut face's shading.
pub(crate) fn pieces_within(n: usize, until: f64) -> Vec<(f64, f64)> {
    let n = n.max(1);
    // i / n is what `equal_pieces` computes (0 + 1 · (i / n) is exact).
    let at = |i: usize| if i == n { 1.0 } else { i as f64 / n as f64 };
    (0..n)
        .take_while(|&i| at(i) <= until)
        .map(|i| (at(i), at(i + 1)))
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interval::boxes::point_box;
    use crate::ir::random::Rng;
    use crate::render::prune::scope::equal_pieces;

    // The pieces kept are `equal_pieces`' own, bit for bit and in order.
    #[test]
    fn pieces_within_are_the_leading_equal_pieces() {
        for n in [1, 2, 16, 1024] {
            for until in [-0.5, 0.0, 1e-9, 0.25, 0.3, 0.999, 1.0, 2.0, f64::INFINITY] {
                let mut all = equal_pieces(0.0, 1.0, n);
                all.retain(|&(a, _)| a <= until);
                let bits = |v: Vec<(f64, f64)>| -> Vec<(u64, u64)> {
                    v.iter().map(|&(a, c)| (a.to_bits(), c.to_bits())).collect()
                };
                assert_eq!(bits(pieces_within(n, until)), bits(all), "{n} {until}");
            }
        }
    }

    // Past the bound, every point of every segment is outside the bounds,
    // checked on random boxes of starts and directions (their corners and
    // random points), just past the bound and far beyond it.
    #[test]
    fn past_the_bound_every_point_is_outside() {
        let bounds: IBox = [Interval::new(-1.0, 1.0); 3];
        let mut rng = Rng::new(39);
        let mut bounded = 0;
        for _ in 0..2000 {
            let (c, r) = (rng.range(-1.2, 1.2), rng.range(0.0, 0.05));
            let q: IBox = std::array::from_fn(|_| Interval::new(c - r, c + r));
            let delta: IBox = std::array::from_fn(|_| {
                let v = rng.range(-3.0, 3.0);
                Interval::new(v, v + rng.range(0.0, 0.5))
            });
            let until = inside_until(&q, &delta, &bounds);
            if !until.is_finite() {
                continue;
            }
            bounded += 1;
            // Just past the bound by more than the rounding of `x + s·d`.
            for s in [until.max(0.0) + 1e-9, until.max(0.0) + 1.0, 7.0] {
                for _ in 0..8 {
                    let p: [f64; 3] = std::array::from_fn(|i| {
                        let x = rng.range(q[i].lo, q[i].hi);
                        let d = rng.range(delta[i].lo, delta[i].hi);
                        x + s * d
                    });
                    let inside = (0..3).all(|i| bounds[i].contains(p[i]));
                    assert!(!inside, "{p:?} at s = {s} past {until} ({q:?}, {delta:?})");
                }
            }
        }
        assert!(bounded > 1000, "{bounded} bounded");
    }

    // A cut face on the top of the bounds lit from above: only its start
    // can be inside; a start above the bounds has none inside; a segment
    // across the bounds stays in them until it reaches the first face it
    // meets (here z = 1, at s = 1 / 0.6).
    #[test]
    fn cut_faces_and_crossings() {
        let bounds: IBox = [Interval::new(-1.0, 1.0); 3];
        let up = point_box([0.4, 1.0, 0.6]);
        assert_eq!(inside_until(&point_box([0.2, 1.0, 0.1]), &up, &bounds), 0.0);
        assert!(inside_until(&point_box([0.2, 1.5, 0.1]), &up, &bounds) < 0.0);
        let across = inside_until(&point_box([0.0, -1.0, 0.0]), &up, &bounds);
        assert!((1.0 / 0.6..1.0 / 0.6 + 1e-12).contains(&across), "{across}");
        let flat = point_box([1.0, 0.0, 0.0]);
        // Rounded up, never down.
        let along = inside_until(&point_box([0.0; 3]), &flat, &bounds);
        assert!((1.0..1.0 + 1e-12).contains(&along), "{along}");
        let still = point_box([0.0, 0.0, 0.0]);
        assert_eq!(
            inside_until(&point_box([0.0; 3]), &still, &bounds),
            f64::INFINITY
        );
    }
}
