//! Guaranteed shadows: a point is lit by a shadow-casting light only where
//! its segment towards the light is proven free of surface (`FreeSearch`
//! on the sweep driver, its pieces on cell tapes in large scenes), an
//! included block first trying one shadow beam for all its points, and a
//! pixel first testing the point where its neighbour's segment met a
//! solid. `docs/tracer.md` states where a segment starts, when a piece is
//! free and what each shortcut saves.

use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;

use super::reach;
use super::shade::HitSurface;
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_hull, box_meet, point_box};
use crate::render::context::EvalSet;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::monotone::increasing_along;
use crate::render::enclose::proof;
use crate::render::prune::cells::{self, CellTapes};
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::trace::sweep::{self, Search, SweepState, Visit};
use crate::render::view::camera::{bounds_box, normalize};
use crate::scene::LightKind;

const MAX_SHADOW_PIECES: usize = 4000;

/// How much shorter than the sweep's resolution pieces next to a
/// segment's start may get (see `Segments::resolution`).
const NEAR_START_SPLIT: f64 = 16.0;

/// The far end of a shadow segment.
#[derive(Copy, Clone, Debug)]
pub(crate) enum SegEnd {
    /// A point light's position.
    Point(DVec3),
    /// A fixed offset from the start (directional light).
    Offset(DVec3),
}

impl SegEnd {
    /// The segment from `start` to this end, as a vector.
    fn from(self, start: DVec3) -> DVec3 {
        match self {
            SegEnd::Point(l) => l - start,
            SegEnd::Offset(o) => o,
        }
    }
}

/// The unit direction from `p` towards the light, and the segment end.
pub(crate) fn light_dir(tr: &Scope<'_>, kind: LightKind, p: DVec3) -> Option<(DVec3, SegEnd)> {
    match kind {
        LightKind::Point(l) => {
            let l = DVec3::from_array(l);
            let d = normalize(l - p)?;
            Some((d, SegEnd::Point(l)))
        }
        LightKind::Directional(dir) => {
            // `-x` is `x * -1.0` bit for bit (both flip the sign only).
            let d = normalize(-DVec3::from_array(dir))?;
            Some((d, SegEnd::Offset(d * (2.0 * tr.ctx.diag))))
        }
    }
}

/// The monotonicity test of a piece is put off to its halves while the
/// functions' derivatives run a tape longer than this (a long function's
/// JIT interprets them) and the piece is wider than [`MONOTONE_ALWAYS`]
/// (a fraction of the segment). It never loses a proof: what it proves
/// on a piece it proves on the piece's halves (interval arithmetic is
/// inclusion-isotone), the first half starts where the piece did, and the
/// second where the first, proven positive and increasing, ends (inside
/// the bounds or not). Meanwhile the halves
/// are pruned, and the test runs a few hundred ops instead of the whole
/// tape: on 1000 spheres the test over the first, long pieces of each
/// segment cost most of the render.
const MONOTONE_DEFER_OPS: usize = 2048;
/// See [`MONOTONE_DEFER_OPS`].
const MONOTONE_ALWAYS: f64 = 1.0 / 64.0;

/// A piece this many times narrower than the one whose cell's evaluators
/// (see `render::cells`) the sweep runs takes its own cell's.
const SEGMENT_CELL_RATIO: f64 = 2.0;

/// Tests one shadow beam for a set of surface points and one light.
///
/// `blocker` carries, from one beam of a tile to the next, where along
/// its first segment a failed beam found a point inside a solid: where
/// the same point along this beam's first segment lies inside a solid
/// too, that segment is blocked and the beam would fail, so it fails at
/// the cost of one point evaluation. On 3000 spheres with shadows a third
/// of the beams fail, mostly in shadowed areas whose neighbours failed on
/// the same solid, and the failed ones cost as much as all the beams that
/// succeed.
pub(crate) fn shadow_beam(
    tr: &Scope<'_>,
    surfs: &[HitSurface],
    kind: LightKind,
    blocker: &mut Option<f64>,
    st: &mut TileState,
) -> bool {
    let Some(first) = surfs.first() else {
        return false;
    };
    let Some((_, end)) = light_dir(tr, kind, first.p) else {
        return false;
    };
    if let Some(s) = *blocker
        && hint_blocked(tr, (first.q + s * end.from(first.q)).to_array(), st)
    {
        return false;
    }
    let mut qb = point_box(first.q.to_array());
    let mut min_w = f64::INFINITY;
    for s in surfs {
        qb = box_hull(qb, point_box(s.q.to_array()));
        min_w = min_w.min(s.min_w);
    }
    let starts: Vec<DVec3> = surfs.iter().map(|s| s.q).collect();
    // A beam cannot be resolved much below its own cross-section: give up
    // (and fall back to per-pixel segments) once pieces get that short.
    let diam = qb.iter().map(|c| c.width() * c.width()).sum::<f64>().sqrt();
    let (free, at) = sweep_segments(tr, qb, &starts, end, min_w.max(diam), st);
    if at.is_some() {
        *blocker = at;
    }
    free
}

/// Whether every segment from a point of `q` to `end` is proven free of
/// surface (the sweep of [`shadow_beam`] without its hint, which the
/// tests hold the hinted answers to). `starts` are the segments' start points (all inside `q`);
/// they are proven outside every object only if the monotonicity test on
/// the first piece needs it (one interval evaluation per point and object).
#[cfg(test)]
pub(crate) fn segment_free(
    tr: &Scope<'_>,
    q: IBox,
    starts: &[DVec3],
    end: SegEnd,
    min_w: f64,
    st: &mut TileState,
) -> bool {
    sweep_segments(tr, q, starts, end, min_w, st).0
}

/// [`segment_free`] for the one segment from `start` (a shading point) to
/// `end`, which first tries the point at `blocker` along it (a fraction of
/// the segment): where a nearby sample's segment found a point inside a
/// solid, this one most often meets the same solid there. A point of the
/// segment inside a solid settles the answer (not free) as the sweep's own
/// such test does (`Segments::piece`), so the answer is the same, found
/// with one point evaluation instead of a sweep up to the blocker. Also
/// returns where along the segment a point inside a solid was found, for
/// the next sample to try.
pub(crate) fn point_segment_free(
    tr: &Scope<'_>,
    start: DVec3,
    end: SegEnd,
    min_w: f64,
    blocker: Option<f64>,
    st: &mut TileState,
) -> (bool, Option<f64>) {
    // A segment with no point in the bounds (a cut face lit from outside
    // them: every hit of a flat model under the default light) is free,
    // as its sweep would find with no piece to visit and its hint outside
    // the bounds, without the sweep's setup or reading the clock, which
    // cost a tenth of prospero's default render.
    if misses_bounds(tr, start, end) {
        return (true, None);
    }
    let q = point_box(start.to_array());
    let t0 = Instant::now();
    let answer = match blocker {
        Some(s) if hint_blocked(tr, (start + s * end.from(start)).to_array(), st) => {
            (false, Some(s))
        }
        _ => sweep_segments(tr, q, &[start], end, min_w, st),
    };
    st.stats.shadow_cpu_ms += t0.elapsed().as_secs_f64() * 1e3;
    answer
}

/// Whether the segment from `start` to `end` has no point in the bounds,
/// so no surface: a cut face lit from outside them, every hit of a flat
/// model under the default light.
pub(crate) fn misses_bounds(tr: &Scope<'_>, start: DVec3, end: SegEnd) -> bool {
    let q = point_box(start.to_array());
    let bounds = bounds_box(&tr.ctx.bounds);
    let until = reach::inside_until(&q, &segment_delta(&q, end), &bounds);
    // Where `pieces_within` keeps no piece for the sweep (a NaN keeps none).
    until < 0.0 || until.is_nan()
}

// The displacements from the points of `q` to `end`.
fn segment_delta(q: &IBox, end: SegEnd) -> IBox {
    match end {
        SegEnd::Point(l) => std::array::from_fn(|i| Interval::point(l[i]).sub(q[i])),
        SegEnd::Offset(o) => point_box(o.to_array()),
    }
}

// The sweep of `segment_free`, and where it found a point inside a solid.
fn sweep_segments(
    tr: &Scope<'_>,
    q: IBox,
    starts: &[DVec3],
    end: SegEnd,
    min_w: f64,
    st: &mut TileState,
) -> (bool, Option<f64>) {
    let delta = segment_delta(&q, end);
    let len = delta
        .iter()
        .map(|c| c.lo.abs().max(c.hi.abs()))
        .map(|m| m * m)
        .sum::<f64>()
        .sqrt();
    let seg = Segments {
        q,
        delta,
        len,
        starts,
        end,
        min_w,
        bounds: bounds_box(&tr.ctx.bounds),
    };
    let mut sw = SegmentSweep {
        front: Front::Starts,
        starts_outside: Vec::new(),
        blocked_at: None,
    };
    // The sweep starts from the pieces of bisection level k, about an
    // eighth of the bounds' diagonal long, rather than from the whole
    // segment: the same pieces that bisection reaches, in the same order,
    // so the same proofs (what a piece's tests prove they prove on its
    // halves), without evaluating the function over boxes spanning the
    // bounds (on 1000 spheres, the whole function's native code over a
    // dozen such boxes per segment).
    //
    // Where pieces run cells' tapes, they start as long as the finest
    // cells are wide: the coarser cells keep thousands of ops of a union
    // of many objects (their pieces delegate to the whole function's
    // native code, about 10 µs each) and seldom reject a piece, while a
    // finest cell's few hundred ops reject most pieces at once.
    let piece = if tr.pruner.enabled && tr.ctx.large {
        cells::finest_width(tr)
    } else {
        tr.ctx.diag / 8.0
    };
    let levels = (len / piece).log2().ceil();
    let levels = if levels.is_finite() {
        levels.clamp(0.0, 10.0) as u32
    } else {
        0
    };
    // Pieces past the last point any segment has in the bounds would each
    // be dropped by the sweep's box test: they are not visited at all (a
    // cut face lit from outside the bounds then costs no sweep).
    let until = reach::inside_until(&q, &delta, &seg.bounds);
    let pieces = reach::pieces_within(1 << levels, until);
    if pieces.is_empty() {
        return (true, None);
    }
    let mut search = FreeSearch {
        seg: &seg,
        sw: &mut sw,
        st,
        maybe: Vec::new(),
    };
    let free = sweep::sweep(tr, pieces, &mut search, &mut SweepState::new()).is_none();
    (free, sw.blocked_at)
}

// The segments from the points of `q` along `delta` (`len` long at most),
// with what their sweep reads.
struct Segments<'s> {
    q: IBox,
    delta: IBox,
    len: f64,
    starts: &'s [DVec3],
    end: SegEnd,
    min_w: f64,
    bounds: IBox,
}

// What one sweep of a segment proves as it goes, across nested sweeps.
struct SegmentSweep {
    // What is proven at the start of the next piece (pieces are settled
    // front to back and contiguously).
    front: Front,
    // Per object: whether every start point is proven outside it (None:
    // not checked yet).
    starts_outside: Vec<Option<bool>>,
    // Where along the segments a point inside a solid was found.
    blocked_at: Option<f64>,
}

// The search over a shadow segment's pieces on the sweep driver
// (`trace::sweep`), which finds whether it is blocked. A piece
// `SEGMENT_CELL_RATIO` times narrower than the one the evaluators were
// last specialised to is swept, with its sub-pieces, on the evaluators of
// the smallest cell holding it. Pruning keeps signs, and a piece's
// proofs read signs only (a pruned function positive at a start and
// increasing has the whole function's sign, positive, on the piece), so
// the nesting changes the cost of the evaluations and the tightness of
// their intervals, not the order in which pieces are visited. Every
// branch reads or sets `front`, which holds only because the driver pops
// pieces in order.
struct FreeSearch<'a, 's> {
    seg: &'a Segments<'s>,
    sw: &'a mut SegmentSweep,
    st: &'a mut TileState,
    // The objects that may vanish on the current piece (a buffer kept
    // from piece to piece).
    maybe: Vec<usize>,
}

impl Search for FreeSearch<'_, '_> {
    // Found: the segments are blocked.
    type Found = ();

    #[inline]
    fn visit(&mut self, tr: &Scope<'_>, (a, c): sweep::Piece, at: &mut SweepState) -> Visit<()> {
        if at.pieces > MAX_SHADOW_PIECES {
            return Visit::Stop(());
        }
        let seg = self.seg;
        let s = Interval::new(a, c);
        let bx: IBox = std::array::from_fn(|i| seg.q[i].add(s.mul(seg.delta[i])));
        let Some(clip) = box_meet(bx, seg.bounds) else {
            // Wholly outside the bounds: no surface, but nothing known of f.
            self.sw.front = Front::Unknown;
            return Visit::Drop;
        };
        if tr.pruner.enabled && tr.ctx.large && (c - a) * SEGMENT_CELL_RATIO <= at.specialised_width
        {
            // A piece that no cell holds runs these evaluators, and its
            // halves and the pieces after it look again: narrowing
            // `specialised_width` here (as this did) sent every later piece
            // of this width to the whole function (3000 spheres: 5 times
            // as many whole-function pieces).
            if let Some(set) = CellTapes::holding(tr, &clip, self.st) {
                if !same_evals(&set, tr) {
                    return Visit::Specialise(EvalSet::clone(&set));
                }
                // The cell these evaluators already are (the halves of a
                // piece of the finest cells mostly are): the piece goes on
                // here, counted as the nested sweep would count it again,
                // without a scope and a stack built for it.
                at.pieces += 1;
                if at.pieces > MAX_SHADOW_PIECES {
                    return Visit::Stop(());
                }
            }
        }
        self.maybe.clear();
        for k in 0..tr.ctx.evals.len() {
            if !proof::holds_no_surface(tr.ctx.interval(k, clip, &mut self.st.stats)) {
                self.maybe.push(k);
            }
        }
        if self.maybe.is_empty() {
            self.sw.front = Front::Unknown;
            return Visit::Drop;
        }
        match seg.piece(tr, (a, c), bx, &self.maybe, self.sw, &mut self.st.stats) {
            Piece::Blocked => Visit::Stop(()),
            // Positive at its start and increasing over its whole box
            // (not only the part inside the bounds): positive at its end.
            Piece::Increasing => {
                self.sw.front = Front::Outside;
                Visit::Drop
            }
            // Where the proofs fail, the forms along the segment may still
            // drop the piece or the parts of it that hold no surface.
            Piece::Open => match self.along_forms(tr, (a, c), bx) {
                Some(visit) => visit,
                None if (c - a) * seg.len <= seg.resolution(a) => Visit::Stop(()),
                None => Visit::Halve,
            },
        }
    }
}

// What is proven of the objects at the start of the next piece.
#[derive(Copy, Clone, PartialEq, Eq)]
enum Front {
    // The segments' start points (s = 0): checked once, when first needed.
    Starts,
    // Every object positive: the piece before was proven increasing from
    // a positive start (see `proof`).
    Outside,
    // Nothing: the piece before was rejected, which proves nothing about
    // its end (f may be undefined there, see `proof`).
    Unknown,
}

impl Segments<'_> {
    // The shortest piece the sweep halves at `a` (a fraction of the
    // segment): `min_w`, but 16 times shorter within twice `min_w` of the
    // start. The segment starts within the refinement tolerance of the
    // surface, and where the light grazes it (or the surface curves away)
    // only pieces that short have a derivative enclosure tight enough to
    // prove the segment leaving it: at `min_w` alone, isolated lit pixels
    // were drawn shadowed.
    fn resolution(&self, a: f64) -> f64 {
        if a * self.len <= 2.0 * self.min_w {
            self.min_w / NEAR_START_SPLIT
        } else {
            self.min_w
        }
    }

    // What the tests beyond the interval one prove of the piece `[a, c]`
    // (box `bx`), where the objects `maybe` may vanish.
    fn piece(
        &self,
        tr: &Scope<'_>,
        (a, c): (f64, f64),
        bx: IBox,
        maybe: &[usize],
        sw: &mut SegmentSweep,
        st: &mut RenderStats,
    ) -> Piece {
        // A point of one of the segments (the first start's) inside a
        // solid settles the answer (not free) at once, where the bisection
        // would otherwise go down to `min_w` at the blocker's surface
        // before giving up. It never changes a provable answer: every
        // interval over a box holding that point contains its (negative)
        // value, so no piece around it could be rejected, and the
        // monotonicity proof would need f > 0 on that segment.
        if let Some(&s0) = self.starts.first() {
            let m = 0.5 * (a + c);
            // Clamped into the piece's box against rounding (max/min, not
            // `clamp`, which panics on NaN bounds).
            let on = (s0 + m * self.end.from(s0)).to_array();
            let p: [f64; 3] = std::array::from_fn(|i| on[i].max(bx[i].lo).min(bx[i].hi));
            if inside_a_solid(tr, p, &self.bounds, maybe.iter().copied(), st) {
                sw.blocked_at = Some(m);
                return Piece::Blocked;
            }
        }
        // Positive at the start and increasing along every segment over
        // the piece: positive on the whole piece.
        let ok = match sw.front {
            Front::Outside => true,
            // Only the objects that may vanish on the piece need be outside
            // at its start: the others hold no surface there, whatever
            // their sign at its start (f may be undefined there).
            Front::Starts => maybe.iter().all(|&k| {
                if sw.starts_outside.len() <= k {
                    sw.starts_outside.resize(k + 1, None);
                }
                *sw.starts_outside[k].get_or_insert_with(|| {
                    self.starts
                        .iter()
                        .all(|&p| outside_all(tr, p.to_array(), std::iter::once(k), st))
                })
            }),
            // One segment: its point at the piece's start.
            Front::Unknown => match self.starts {
                &[s0] => {
                    let p = (s0 + a * self.end.from(s0)).to_array();
                    outside_all(tr, p, maybe.iter().copied(), st)
                }
                _ => false,
            },
        };
        // The monotonicity test waits for narrower pieces while it would
        // run a long tape (see `MONOTONE_DEFER_OPS`).
        let affordable = |k: usize| {
            c - a <= MONOTONE_ALWAYS
                || tr.ctx.evals[k].derivatives_native()
                || tr.ctx.live_ops[k] <= MONOTONE_DEFER_OPS
        };
        if ok
            && maybe.iter().all(|&k| affordable(k))
            && maybe
                .iter()
                .all(|&k| increasing_along(&tr.ctx, k, bx, self.delta, st))
        {
            return Piece::Increasing;
        }
        Piece::Open
    }
}

// Whether the point `p` lies inside `bounds` and one of `objects` is
// negative there: a point of a shadow segment for which this holds puts
// the segment's start in shadow, wherever along the segment it lies.
fn inside_a_solid(
    tr: &Scope<'_>,
    p: [f64; 3],
    bounds: &IBox,
    mut objects: impl Iterator<Item = usize>,
    st: &mut RenderStats,
) -> bool {
    (0..3).all(|i| bounds[i].contains(p[i])) && objects.any(|k| tr.ctx.point(k, p, st) < 0.0)
}

// Whether `set` holds the very evaluators `tr` runs.
fn same_evals(set: &EvalSet, tr: &Scope<'_>) -> bool {
    let ours = tr.ctx.evals.iter();
    set.evals.len() == tr.ctx.evals.len()
        && set.evals.iter().zip(ours).all(|(a, b)| Arc::ptr_eq(a, b))
}

// Whether the blocker hint `p` lies inside a solid (see
// `point_segment_free`), on the evaluators of the smallest cell holding it
// where pieces run cells': the point lies far outside the tile's beam,
// where the tile's evaluators run the whole function's native code
// (3000 spheres: 42 000 ops a point, 15% of the render), while a fine
// cell's pruned tape has the same sign at every point of its region, so
// the same answer, in a few hundred ops.
fn hint_blocked(tr: &Scope<'_>, p: [f64; 3], st: &mut TileState) -> bool {
    let bounds = bounds_box(&tr.ctx.bounds);
    if !(0..3).all(|i| bounds[i].contains(p[i])) {
        return false;
    }
    let all = 0..tr.ctx.evals.len();
    let cell = (tr.pruner.enabled && tr.ctx.large)
        .then(|| CellTapes::holding(tr, &point_box(p), st))
        .flatten();
    match cell {
        Some(set) => inside_a_solid(&tr.with_evals(&set), p, &bounds, all, &mut st.stats),
        None => inside_a_solid(tr, p, &bounds, all, &mut st.stats),
    }
}

// What `Segments::piece` proved.
enum Piece {
    // A point of a segment lies inside a solid: shadow.
    Blocked,
    // Positive at its start and increasing along every segment: no
    // surface on the piece.
    Increasing,
    // Neither: bisect.
    Open,
}

// Whether the point `p` is proven outside each of `objects`: each defined
// and positive there (see `proof::outside_at`).
fn outside_all(
    tr: &Scope<'_>,
    p: [f64; 3],
    mut objects: impl Iterator<Item = usize>,
    st: &mut RenderStats,
) -> bool {
    let b = point_box(p);
    objects.all(|k| proof::outside_at(tr.ctx.interval(k, b, st)))
}

// The second-order forms along a single segment (`FreeSearch::along_forms`).
#[path = "shadow_forms.rs"]
mod forms;

#[cfg(test)]
#[path = "shadow_hint_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "shadow_cells_tests.rs"]
mod cells_tests;
