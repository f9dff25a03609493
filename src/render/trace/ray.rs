//! One ray: guaranteed first-root isolation (`RaySearch` on the sweep
//! driver: interval rejection, the centred form, interval Newton and its
//! gaps, the tangency policy), bracketed refinement, and the fixed-step
//! point march baseline. `docs/tracer.md` states the first-root policy and
//! why each of its rules is there.

use super::refine::{refine, sign_change};
use super::sweep::{Piece, Search, SweepState, Visit, sweep};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, ray_box};
use crate::render::context::stats::RenderStats;
use crate::render::enclose::affine::{self, AlongRay};
use crate::render::enclose::centred::{Centred, Newton, centred, newton};
use crate::render::enclose::mean_value::MV_LEVELS;
use crate::render::enclose::proof;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::view::camera::PixelRay;
use crate::render::{Enclosure, Hit};

// Caps that keep a pathological function from stalling a render; reaching
// one counts as a hit at the current piece (never a silent miss).
const MAX_RAY_STEPS: usize = 20_000;

// How much narrower than the depth tolerance a piece without a sign change
// must be before the tangency policy draws it (see the module doc).
const TANGENT_SPLIT: f64 = 64.0;

/// The smallest live-object value at `p` and the object attaining it.
pub(crate) fn scene_point(
    tr: &Scope<'_>,
    live: &[u32],
    p: [f64; 3],
    st: &mut RenderStats,
) -> (f64, usize) {
    let mut best = (f64::INFINITY, live.first().copied().unwrap_or(0) as usize);
    for &k in live {
        let v = tr.ctx.point(k as usize, p, st);
        if v < best.0 {
            best = (v, k as usize);
        }
    }
    best
}

/// Point test of the start: a ray that begins inside a solid hits at t0.
pub(crate) fn starts_inside(
    tr: &Scope<'_>,
    ray: &PixelRay,
    live: &[u32],
    t0: f64,
    st: &mut RenderStats,
) -> Option<Hit> {
    let (v, obj) = scene_point(tr, live, ray.at(t0), st);
    (v < 0.0).then_some(Hit {
        t: t0,
        obj,
        inside: true,
        grad: None,
        front: None,
    })
}

/// Guaranteed first-root isolation on one ray over [t0, t1] (policy in
/// the module doc).
pub(crate) fn trace_ray(
    tr: &Scope<'_>,
    ray: &PixelRay,
    t0: f64,
    t1: f64,
    live: &[u32],
    st: &mut TileState,
) -> Option<Hit> {
    trace_ray_near_first(tr, ray, (t0, t0), t1, live, st)
}

/// [`trace_ray`], with `[t0, near]` swept first as a piece of its own
/// (when `t0 < near < t1`): where a beam left its candidate piece, the
/// first root of its rays most often lies there, and bisecting the whole
/// range down to that piece's width costs as many evaluations again.
pub(crate) fn trace_ray_near_first(
    tr: &Scope<'_>,
    ray: &PixelRay,
    (t0, near): (f64, f64),
    t1: f64,
    live: &[u32],
    st: &mut TileState,
) -> Option<Hit> {
    st.stats.rays += 1;
    if live.is_empty() {
        return None;
    }
    if let Some(h) = starts_inside(tr, ray, live, t0, &mut st.stats) {
        return Some(h);
    }
    let pieces = tr.ray_pieces(t0, near, t1);
    let mut search = RaySearch {
        ray,
        live,
        st,
        cand: Vec::with_capacity(live.len()),
        forms: Vec::with_capacity(live.len()),
    };
    sweep(tr, pieces, &mut search, &mut SweepState::new())
}

/// A piece this many times narrower than the one its functions were last
/// pruned to prunes them again (to the piece's box) for its sub-pieces.
const RAY_PRUNE_RATIO: f64 = 4.0;

// The search of `trace_ray` over its pieces, on the sweep driver
// (`super::sweep`): the driver's piece count is the ray's step count,
// across nested sweeps. Where pruning is on, a piece `RAY_PRUNE_RATIO`
// times narrower than the one the evaluators were last specialised to,
// that its interval does not reject, is swept again, with its
// sub-pieces, with the functions pruned to it (when that shrinks them): a
// ray's pieces soon shrink to a few pixels across, over which a union of
// many objects keeps one or two, while the tile's slices keep every
// object that meets them. Pruning is exact, so the nesting changes the
// cost of the evaluations and the tightness of their intervals, not the
// order in which pieces are visited.
struct RaySearch<'r, 's> {
    ray: &'r PixelRay,
    live: &'r [u32],
    st: &'s mut TileState,
    // The live objects that may vanish on the piece.
    cand: Vec<u32>,
    // The centred form's evaluations of each candidate, which interval
    // Newton reads again on the same piece.
    forms: Vec<(u32, Centred)>,
}

impl Search for RaySearch<'_, '_> {
    type Found = Hit;

    #[inline]
    fn visit(&mut self, tr: &Scope<'_>, (a, b): Piece, at: &mut SweepState) -> Visit<Hit> {
        let (ray, live) = (self.ray, self.live);
        let bx = ray_box(ray.o, ray.d, Interval::new(a, b));
        self.cand.clear();
        for &k in live {
            let f = tr.ctx.interval(k as usize, bx, &mut self.st.stats);
            if !proof::holds_no_surface(f) {
                self.cand.push(k);
            }
        }
        if self.cand.is_empty() {
            return Visit::Drop;
        }
        // Only a piece that may hold surface is pruned to: most pieces are
        // rejected by their first evaluation, which costs a third of a
        // pruning pass over the same tape.
        if tr.pruner.enabled
            && (b - a) * RAY_PRUNE_RATIO <= at.specialised_width
            && let Some(set) = tr.pruned_to_ray(ray, Interval::new(a, b), self.st)
        {
            return Visit::Specialise(set);
        }
        let Some((na, nb)) = affine_narrows(tr, ray, (a, b), bx, &mut self.cand, self.st) else {
            return Visit::Drop;
        };
        // The parts the forms exclude hold no surface: sweep what is left
        // where that is at most half the piece (a sure step forward).
        if nb - na <= 0.5 * (b - a) {
            return Visit::Parts(Some((na, nb)), None);
        }
        self.forms.clear();
        for &k in &self.cand {
            let c = centred(&tr.ctx, ray, k as usize, bx, (a, b), &mut self.st.stats);
            if !c.positive {
                self.forms.push((k, c));
            }
        }
        if self.forms.is_empty() {
            return Visit::Drop;
        }
        let stt = &mut self.st.stats;
        let tol = tr.ctx.cam.tolerance(a);
        if at.pieces >= MAX_RAY_STEPS {
            return Visit::Stop(narrow_hit(tr, ray, live, a, b, stt));
        }
        // A narrow piece is a hit when its ends show a sign change (the
        // root is refined); without one it is a tangency candidate, bisected
        // on down to TANGENT_SPLIT times narrower before the tangency
        // policy draws it (see the module doc).
        if b - a <= tol
            && (b - a <= tol / TANGENT_SPLIT || sign_change(tr, ray, live, (a, b), stt).is_some())
        {
            return Visit::Stop(narrow_hit(tr, ray, live, a, b, stt));
        }
        let [(k, c)] = self.forms[..] else {
            return Visit::Halve;
        };
        match newton(&tr.ctx, ray, k as usize, (a, b), c.parts, stt) {
            Newton::Empty => Visit::Drop,
            // Point signs that disagree with the proof at the limits of
            // precision make it a narrow piece.
            Newton::Unique(na, nb) => Visit::Stop(
                refine(tr, ray, live, na, nb, stt)
                    .unwrap_or_else(|| narrow_hit(tr, ray, live, na, nb, stt)),
            ),
            Newton::Shrunk(na, nb) if nb - na < 0.5 * (b - a) => Visit::Parts(Some((na, nb)), None),
            Newton::Shrunk(na, nb) => {
                let m = 0.5 * (na + nb);
                Visit::Parts(Some((na, m)), Some((m, nb)))
            }
            Newton::Gap(front, back) => Visit::Parts(front, back),
        }
    }
}

// Where the scene's enclosure choice asks for them (`auto`: while the
// tile's own record for single rays says they pay at the piece's size
// class, `piece_level`), the second-order forms along the ray: drops
// from `cand` the objects they prove free of surface on the piece, and
// returns the hull of the parts where the rest may have theirs (`None`:
// none left). Where a variable appears many times (an
// expanded polynomial) the natural interval of a piece stays wide however
// narrow the piece, so a ray bisected thousands of pieces that the form,
// which keeps the ray's coordinates tied, rejects or clips at once.
fn affine_narrows(
    tr: &Scope<'_>,
    ray: &PixelRay,
    (a, b): Piece,
    bx: IBox,
    cand: &mut Vec<u32>,
    st: &mut TileState,
) -> Option<Piece> {
    // Under `auto`, a piece none of whose candidates is a polynomial
    // goes on at once: this runs on every piece the intervals leave
    // undecided.
    let choice = tr.ctx.enclosure;
    if choice == Enclosure::Interval
        || (choice == Enclosure::Auto
            && !cand
                .iter()
                .any(|&k| affine::along_may_pay(&tr.ctx, k as usize)))
    {
        return (!cand.is_empty()).then_some((a, b));
    }
    let level = piece_level(b - a, tr.ctx.cam.tolerance(a));
    if !st.affine_along.along_wanted(choice, level) {
        return (!cand.is_empty()).then_some((a, b));
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    cand.retain(|&k| {
        let along = affine::affine_along_line(&tr.ctx, k as usize, ray.o, ray.d, (a, b), bx);
        st.stats.affine_ray_tries += u64::from(along.is_some());
        let (pa, pb) = affine::part_left(along, (a, b));
        if along.is_some() {
            // A win: the object is dropped, or its part is at most half.
            // The policy counts drops only, per piece size: a try takes
            // the time of some ten interval evaluations, a clip saves a
            // few bisections, and the form drops the wider pieces of an
            // expanded polynomial only (docs/performance.md).
            let win = pb - pa <= 0.5 * (b - a);
            st.stats.affine_ray_wins += u64::from(win);
            st.affine_along.record(level, along == Some(AlongRay::Free));
        }
        lo = lo.min(pa);
        hi = hi.max(pb);
        pa <= pb
    });
    (!cand.is_empty()).then_some((lo, hi))
}

// The size class of a ray piece `width` wide for the forms' policy: a
// class per factor of 4 of its width over the depth tolerance `tol`
// (from the quotient's binary exponent, which is floor(log2) for a
// normal one: this runs on every piece the intervals leave undecided).
fn piece_level(width: f64, tol: f64) -> usize {
    let r = width / tol;
    if !(r.is_finite() && r > 1.0) {
        return 0;
    }
    let log2 = ((r.to_bits() >> 52) & 0x7ff).saturating_sub(1023);
    ((log2 / 2) as usize).min(MV_LEVELS - 1)
}

// A narrow piece with 0 ∈ F: refine a sign change if the ends show one,
// else the front of the piece is the hit (tangency policy).
fn narrow_hit(
    tr: &Scope<'_>,
    ray: &PixelRay,
    live: &[u32],
    a: f64,
    b: f64,
    st: &mut RenderStats,
) -> Hit {
    if let Some(h) = refine(tr, ray, live, a, b, st) {
        return h;
    }
    let obj = scene_point(tr, live, ray.at(a), st).1;
    Hit {
        t: a,
        obj,
        inside: false,
        grad: None,
        front: None,
    }
}

/// The baseline: `steps` equal steps of point evaluation over [t0, t1];
/// the first sign change is refined by Illinois.
pub(crate) fn march(
    tr: &Scope<'_>,
    ray: &PixelRay,
    t0: f64,
    t1: f64,
    live: &[u32],
    steps: u32,
    st: &mut RenderStats,
) -> Option<Hit> {
    st.rays += 1;
    if let Some(h) = starts_inside(tr, ray, live, t0, st) {
        return Some(h);
    }
    let n = steps.max(1);
    let mut prev_t = t0;
    for i in 1..=n {
        let t = if i == n {
            t1
        } else {
            t0 + (t1 - t0) * f64::from(i) / f64::from(n)
        };
        let (v, _) = scene_point(tr, live, ray.at(t), st);
        if v <= 0.0 {
            let obj = scene_point(tr, live, ray.at(t), st).1;
            return refine(tr, ray, live, prev_t, t, st).or(Some(Hit {
                t,
                obj,
                inside: false,
                grad: None,
                front: None,
            }));
        }
        prev_t = t;
    }
    None
}

#[cfg(test)]
#[path = "ray_tests.rs"]
mod tests;
