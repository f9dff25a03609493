//! Enclosures along one ray: the centred form of an object over a piece
//! of the ray, and interval Newton steps from its parts.

use crate::interval::Interval;
use crate::interval::boxes::{IBox, ray_box};
use crate::render::context::Context;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::proof;
use crate::render::view::camera::PixelRay;

// The centred form along the ray: f(p(t)) ∈ F(p(m)) + (∇F·d)·([a, b] − m)
// for t ∈ [a, b]. One-dimensional, it ignores the box's extent across the
// ray, which makes the natural extension of a grazing segment's box
// straddle 0 while the segment stays clear. Sound under the same
// gradient-enclosure assumption as interval Newton.
#[derive(Copy, Clone)]
pub(crate) struct Centred {
    /// The form proves f > 0 on the piece.
    pub positive: bool,
    /// The form's parts, where dF/dt is bounded and F defined at the
    /// midpoint (which interval Newton reads again).
    pub parts: Option<CentredParts>,
}

/// dF/dt over a piece and F at its midpoint, from one evaluator (see
/// `Scope::answering`): with sign-pruned tapes (`eval::tape::Keep::Signs`)
/// two tapes agree on signs only, and a formula that combines a value
/// with a derivative must take both from the same one. Only `centred`
/// builds it, so no caller can mix in another evaluation.
#[derive(Copy, Clone)]
pub(crate) struct CentredParts {
    dfdt: Interval,
    fm: Interval,
}

/// The centred form of object k over the piece [a, b] whose box is `bx`.
pub(crate) fn centred(
    ctx: &Context<'_>,
    ray: &PixelRay,
    k: usize,
    bx: IBox,
    (a, b): (f64, f64),
    st: &mut RenderStats,
) -> Centred {
    // F at the midpoint and dF/dt over the piece from one function (see
    // `Specialise::answering`).
    let e = ctx.answering(k, &bx);
    st.interval_evals += 1;
    let [_, dfdt] = e.interval_dir(bx, ray.d);
    let mut c = Centred {
        positive: false,
        parts: None,
    };
    if !proof::bounded(dfdt) {
        return c;
    }
    let m = 0.5 * (a + b);
    st.interval_evals += 1;
    let fm = e.interval(ray_box(ray.o, ray.d, Interval::point(m)));
    if fm.is_empty() {
        return c;
    }
    let off = Interval::new(a, b).sub(Interval::point(m));
    c.positive = fm.add(dfdt.mul(off)).lo > 0.0;
    c.parts = Some(CentredParts { dfdt, fm });
    c
}

// Interval Newton with extended division, where dF/dt over [a, b] holds 0
// and F is positive at the midpoint m: by the mean value theorem a root t
// behind m has F(m) + F'(ξ)(t − m) = 0 with F'(ξ) ≥ dlo, so t − m ≥
// F(m)/(−dlo), and one before m has m − t ≥ F(m)/dhi: no root lies in the
// gap between, and none behind (before) m where dlo (dhi) is 0.
pub(crate) fn newton_gap((a, b): (f64, f64), m: f64, fm: Interval, dfdt: Interval) -> Newton {
    if fm.lo <= 0.0 {
        return Newton::Shrunk(a, b);
    }
    let f = Interval::point(fm.lo);
    let front = (dfdt.hi > 0.0).then(|| {
        // The gap's front end, rounded outward (towards a).
        let end = Interval::point(m).sub(f.div(Interval::point(dfdt.hi))).hi;
        (a, end.min(b))
    });
    let back = (dfdt.lo < 0.0).then(|| {
        let start = Interval::point(m).add(f.div(Interval::point(-dfdt.lo))).lo;
        (start.max(a), b)
    });
    let keep = |p: Option<(f64, f64)>| p.filter(|&(x, y)| x <= y);
    Newton::Gap(keep(front), keep(back))
}

pub(crate) enum Newton {
    /// No root of the object in the piece.
    Empty,
    /// Exactly one root, in this bracket (proven signs, monotone).
    Unique(f64, f64),
    /// The roots, if any, lie in this sub-piece.
    Shrunk(f64, f64),
    /// The roots, if any, lie in these sub-pieces before and behind a gap
    /// around the midpoint (None: no root on that side).
    Gap(Option<(f64, f64)>, Option<(f64, f64)>),
}

/// One interval Newton step for object k on [a, b], from the centred
// form's dF/dt over the piece and F at its midpoint (`c`, None where the
// form had no bounded parts: the piece is only halved then). The points
// `na` and `nb` are evaluated for their signs alone, which every tape
// gives alike.
pub(crate) fn newton(
    ctx: &Context<'_>,
    ray: &PixelRay,
    k: usize,
    (a, b): (f64, f64),
    c: Option<CentredParts>,
    st: &mut RenderStats,
) -> Newton {
    let Some(CentredParts { dfdt, fm }) = c else {
        return Newton::Shrunk(a, b);
    };
    let m = 0.5 * (a + b);
    if dfdt.contains(0.0) {
        return newton_gap((a, b), m, fm, dfdt);
    }
    let n = Interval::point(m).sub(fm.div(dfdt));
    let (na, nb) = (a.max(n.lo), b.min(n.hi));
    // Newton keeps the roots of the piece, but a ray can also enter the
    // solid without a root, through the edge of f's domain (undefined
    // before it, negative after: sqrt or pow inside a max that takes
    // another branch, whose gradient stays bounded). Where f is proven
    // negative at the midpoint, the piece holds solid that may have no root
    // in front of it, so it is bisected instead of narrowed, and the
    // tangency policy draws its first narrow piece that keeps 0 ∈ F.
    if fm.hi < 0.0 {
        return Newton::Shrunk(a, b);
    }
    if na.partial_cmp(&nb).is_none_or(|o| o.is_gt()) {
        return Newton::Empty;
    }
    let fa = ctx.interval(k, ray_box(ray.o, ray.d, Interval::point(na)), st);
    let fb = ctx.interval(k, ray_box(ray.o, ray.d, Interval::point(nb)), st);
    if fa.hi < 0.0 && fb.hi < 0.0 {
        return Newton::Shrunk(a, b);
    }
    if fa.lo > 0.0 && fb.lo > 0.0 {
        // Monotone and positive at both ends: no root and no hit.
        return Newton::Empty;
    }
    if fa.lo > 0.0 && fb.hi < 0.0 {
        return Newton::Unique(na, nb);
    }
    Newton::Shrunk(na, nb)
}
