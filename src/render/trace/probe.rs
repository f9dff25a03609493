//! The interval tests of a beam, shared by the tracer's blocks
//! ([`super::beam`]) and anti-aliasing's pixel-area cells
//! ([`crate::render::aa`]): the scene function over a beam piece, the front-to-back
//! rejection sweep, the search for the far end of an inclusion bracket,
//! and the quartering of a block.

use crate::interval::Interval;
use crate::interval::boxes::IBox;
use crate::render::enclose::proof::SignBound;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::trace::sweep::{self, Search, SweepState, Visit};

/// EmptyPrefix of the pixel spacing a sweep's smallest piece is sized from, so
/// that the sweep ends where the spacing vanishes (at the eye of a
/// perspective camera).
pub(crate) const MIN_SPACING: f64 = 1e-9;
/// Where the inclusion test looks for a proven-negative cross-section past
/// the first candidate piece: at these multiples of the piece's width.
pub(crate) const INCLUSION_REACH: [f64; 3] = [1.0, 2.0, 4.0];
/// Rejection pieces per sweep before the beam is declared undecided.
const MAX_SWEEP_PIECES: usize = 256;

// A half-open range of columns or rows.
type Span = (u32, u32);

/// A block of pixels (tile coordinates, half-open).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) struct Rect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// Column past the last.
    pub x1: u32,
    /// Row past the last.
    pub y1: u32,
}

impl Rect {
    /// Whether the block is one pixel.
    pub(crate) fn is_pixel(&self) -> bool {
        self.x1 - self.x0 == 1 && self.y1 - self.y0 == 1
    }

    /// How many pixels the block holds.
    pub(crate) fn pixel_count(&self) -> u32 {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }

    /// The pixels of the block, row by row.
    pub(crate) fn pixels(&self) -> impl Iterator<Item = (u32, u32)> + use<> {
        let Rect { x0, y0, x1, y1 } = *self;
        (y0..y1).flat_map(move |j| (x0..x1).map(move |i| (i, j)))
    }

    // The two halves of each side (the first one the larger), as ranges.
    fn halves(&self) -> ([Span; 2], [Span; 2]) {
        let mx = (self.x0 + self.x1).div_ceil(2);
        let my = (self.y0 + self.y1).div_ceil(2);
        (
            [(self.x0, mx), (mx, self.x1)],
            [(self.y0, my), (my, self.y1)],
        )
    }

    /// The non-empty quarters, left column first. The visiting order
    /// matters beyond the counters: the mean-value policy learns as it
    /// goes, so each caller keeps the order it was tuned with.
    pub(crate) fn quarters_by_column(&self) -> impl Iterator<Item = Rect> + use<> {
        let (xs, ys) = self.halves();
        xs.into_iter()
            .flat_map(move |(x0, x1)| ys.map(|(y0, y1)| Rect { x0, y0, x1, y1 }))
            .filter(|r| r.x0 < r.x1 && r.y0 < r.y1)
    }

    /// The non-empty quarters, top row first (see
    /// [`Rect::quarters_by_column`]).
    pub(crate) fn quarters_by_row(&self) -> impl Iterator<Item = Rect> + use<> {
        let (xs, ys) = self.halves();
        ys.into_iter()
            .flat_map(move |(y0, y1)| xs.map(|(x0, x1)| Rect { x0, y0, x1, y1 }))
            .filter(|r| r.x0 < r.x1 && r.y0 < r.y1)
    }
}

/// The width below which a sweep stops bisecting at parameter `t`: the
/// footprint of a block `side` pixels across.
pub(crate) fn min_width(tr: &Scope<'_>, side: f64, t: f64) -> f64 {
    side * tr.ctx.cam.spacing(t).max(MIN_SPACING)
}

/// How each object's interval over a beam piece is taken.
#[derive(Copy, Clone, Debug)]
pub(crate) enum SignForm {
    /// The natural interval extension.
    Natural,
    /// Tightened by the mean-value form, for blocks of this size class
    /// (see `Scope::interval_tight`).
    Tight(usize),
}

/// The signs of the scene function over the box `hb`: the minimum over
/// the `live` objects, skipping those undefined on all of it (positive
/// when all are). Signs only: each object's tape is pruned keeping signs.
pub(crate) fn scene_signs(
    tr: &Scope<'_>,
    live: &[u32],
    hb: IBox,
    form: SignForm,
    st: &mut TileState,
) -> SignBound {
    let mut f = SignBound::NONE;
    for &k in live {
        let v = match form {
            SignForm::Natural => {
                let v = tr.ctx.interval(k as usize, hb, &mut st.stats);
                if v.is_empty() {
                    continue;
                }
                SignBound::of(v)
            }
            SignForm::Tight(level) => match tr.interval_tight(k as usize, hb, level, st) {
                Some(v) => v,
                None => continue,
            },
        };
        f = f.min(v);
    }
    f
}

/// What the sweep of a beam leaves the beams inside it: where along their
/// rays they may start, and where to look first.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct EmptyPrefix {
    /// The beam was proven empty before this ray parameter.
    pub at: f64,
    /// The end of the beam's first candidate piece (`at` when there is
    /// none). The first surface of a narrower beam inside it most often
    /// lies in `[at, near]`: its sweep takes that piece first instead of
    /// bisecting the whole range down to it, a dozen halvings of a
    /// silhouette block's range saved at every level of the quadtree.
    pub near: f64,
}

impl EmptyPrefix {
    /// Nothing proven: start at 0.
    pub(crate) const NONE: EmptyPrefix = EmptyPrefix { at: 0.0, near: 0.0 };

    /// Proven empty before `at`, with no candidate to look at first.
    pub(crate) fn at(at: f64) -> EmptyPrefix {
        EmptyPrefix { at, near: at }
    }

    /// Where a sweep of an inner beam starting at `t0` ends its first
    /// piece: the candidate's end when it starts at the floor (a beam
    /// whose own range starts later has no candidate there), else `t0`
    /// (no first piece of its own).
    pub(crate) fn near_from(self, t0: f64) -> f64 {
        if t0 == self.at { self.near } else { t0 }
    }
}

/// What the rejection sweep of a beam over its T range found.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) enum SweepOutcome {
    /// Every piece was proven free of surface: no ray of the beam hits.
    Empty,
    /// The scene is flat (constant along the rays, so bisecting T cannot
    /// help) and one test over all of T did not reject it.
    Flat,
    /// The first piece, front to back, that could not be rejected.
    Candidate(f64, f64),
}

/// The part of a beam's T range a rejection sweep covers: `[t0, t1]`,
/// with `[t0, near]` a piece of its own, taken first, when
/// `t0 < near < t1` (see [`EmptyPrefix`]).
#[derive(Copy, Clone, Debug)]
pub(crate) struct SweepRange {
    /// Start of the range.
    pub t0: f64,
    /// End of the first piece (`t0`: none of its own).
    pub near: f64,
    /// End of the range.
    pub t1: f64,
}

/// The rejection sweep of a beam over `range`: bisects nearest half
/// first (on the sweep driver, from the pieces
/// [`Scope::first_pieces_near`] cuts), drops every piece `excluded`
/// proves free of surface, and returns the first piece it cannot drop
/// once that piece is narrower than `min_w(start)` (or after
/// [`MAX_SWEEP_PIECES`] pieces); a flat scene gets one test over the whole
/// range.
pub(crate) fn sweep(
    tr: &Scope<'_>,
    range: SweepRange,
    min_w: impl Fn(f64) -> f64,
    mut excluded: impl FnMut(Interval) -> bool,
) -> SweepOutcome {
    let SweepRange { t0, near, t1 } = range;
    if tr.ctx.flat {
        return if excluded(Interval::new(t0, t1)) {
            SweepOutcome::Empty
        } else {
            SweepOutcome::Flat
        };
    }
    let pieces = tr.first_pieces_near(t0, near, t1);
    let mut search = FirstCandidate { min_w, excluded };
    match sweep::sweep(tr, pieces, &mut search, &mut SweepState::new()) {
        Some((ta, tb)) => SweepOutcome::Candidate(ta, tb),
        None => SweepOutcome::Empty,
    }
}

// The search of `sweep`: the first piece not excluded, once narrow
// enough or out of budget.
struct FirstCandidate<W, E> {
    min_w: W,
    excluded: E,
}

impl<W: Fn(f64) -> f64, E: FnMut(Interval) -> bool> Search for FirstCandidate<W, E> {
    type Found = (f64, f64);

    #[inline]
    fn visit(
        &mut self,
        _: &Scope<'_>,
        (a, c): (f64, f64),
        at: &mut SweepState,
    ) -> Visit<(f64, f64)> {
        if (self.excluded)(Interval::new(a, c)) {
            Visit::Drop
        } else if c - a <= (self.min_w)(a) || at.pieces >= MAX_SWEEP_PIECES {
            Visit::Stop((a, c))
        } else {
            Visit::Halve
        }
    }
}

/// Where the inclusion test of the tracer's blocks looks on past
/// [`INCLUSION_REACH`], while the last cross-section leans inside (see
/// [`bracket_end`]): grazing beams reach their negative cross-section
/// deeper than four piece widths. On orthocircle at 1024² this settled
/// blocks whose 15,000 single rays cost 6% of the render; on colonnade
/// and 1000 spheres, whose cross-sections at 4 widths straddle a
/// silhouette and do not lean inside, it costs no measurable time.
pub(crate) const DEEP_REACH: [f64; 2] = [8.0, 16.0];

/// Whether a cross-section that may hold both signs is mostly inside: its
/// enclosure reaches further below zero than above. A beam straddling a
/// silhouette has rays in open space, where F is large and positive; a
/// grazing beam whose rays have all entered the solid is negative but for
/// the overestimate of the interval.
fn leans_inside(c: SignBound) -> bool {
    c.leans_negative()
}

/// The far end of a bracket behind the candidate piece `[ta, tb]` (with
/// `t1` the end of the beam's range): the scene function over the
/// cross-section at `ta` (`cross(ta)`) must be strictly positive, and the
/// first cross-section proven strictly negative at the `reach` multiples
/// of the piece's width (at least `min_w(ta)`) past `ta` is the end
/// ([`INCLUSION_REACH`] for the inclusion test); past those, the `deeper`
/// multiples are tried while the last cross-section
/// [leans inside](leans_inside). `None` when all fail.
/// How far past a candidate piece [`bracket_end`] looks, in multiples of
/// the piece's width: the `usual` multiples, then the `deeper` ones while
/// the cross-sections lean inside.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Reach<'a> {
    /// Always tried.
    pub usual: &'a [f64],
    /// Tried past the usual ones, while the last cross-section leans
    /// inside.
    pub deeper: &'a [f64],
}

impl Reach<'static> {
    /// The inclusion test's reach, [`INCLUSION_REACH`] then [`DEEP_REACH`].
    pub(crate) const INCLUSION: Reach<'static> = Reach {
        usual: &INCLUSION_REACH,
        deeper: &DEEP_REACH,
    };
}

pub(crate) fn bracket_end(
    (ta, tb): (f64, f64),
    t1: f64,
    min_w: impl Fn(f64) -> f64,
    reach: Reach<'_>,
    mut cross: impl FnMut(f64) -> SignBound,
) -> Option<f64> {
    if !cross(ta).positive() {
        return None;
    }
    let Reach {
        usual: reach,
        deeper,
    } = reach;
    let w = (tb - ta).max(min_w(ta));
    // Each multiple, and whether it is one of the deeper ones.
    let steps = reach.iter().map(|&m| (m, false));
    let steps = steps.chain(deeper.iter().map(|&m| (m, true)));
    let mut last = None;
    for (mult, deep) in steps {
        if deep && !last.is_some_and(leans_inside) {
            return None;
        }
        let tb2 = (ta + mult * w).min(t1);
        let c = cross(tb2);
        if c.negative() {
            return Some(tb2);
        }
        if tb2 >= t1 {
            return None;
        }
        last = Some(c);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::prune::scope::equal_pieces;

    #[test]
    fn quarters_cover_the_block_once_in_either_order() {
        let r = Rect {
            x0: 0,
            y0: 0,
            x1: 3,
            y1: 1,
        };
        let cols: Vec<Rect> = r.quarters_by_column().collect();
        let rows: Vec<Rect> = r.quarters_by_row().collect();
        assert_eq!(cols.len(), 2);
        assert_eq!(cols, rows);
        let n: usize = cols.iter().map(|q| q.pixels().count()).sum();
        assert_eq!(n, 3);
        let sq = Rect {
            x0: 0,
            y0: 0,
            x1: 2,
            y1: 2,
        };
        let first = |v: Vec<Rect>| (v[1].x0, v[1].y0);
        assert_eq!(first(sq.quarters_by_column().collect()), (0, 1));
        assert_eq!(first(sq.quarters_by_row().collect()), (1, 0));
    }

    #[test]
    fn the_sweep_finds_the_first_piece_with_surface() {
        let range = SweepRange {
            t0: 0.0,
            near: 0.0,
            t1: 8.0,
        };
        // One piece, or the range cut at slice ends into 4 or 5 first.
        for ends in [vec![], vec![2.0, 4.0, 6.0], vec![1.6, 3.2, 4.8, 6.4]] {
            let mut tr = Scope::for_tests(&crate::scene::Camera::default(), 8);
            tr.pruner.slice_ends = ends.into();
            let s = sweep(&tr, range, |_| 0.5, |t| t.hi < 3.0 || t.lo > 3.5);
            let SweepOutcome::Candidate(a, b) = s else {
                panic!("{s:?}")
            };
            assert!(a <= 3.0 && b >= 3.0 && b - a <= 0.5, "{a} {b}");
            assert_eq!(sweep(&tr, range, |_| 0.5, |_| true), SweepOutcome::Empty);
        }
        let mut tr = Scope::for_tests(&crate::scene::Camera::default(), 8);
        tr.ctx.flat = true;
        assert_eq!(sweep(&tr, range, |_| 0.5, |_| false), SweepOutcome::Flat);
        let p = equal_pieces(1.0, 2.0, 4);
        assert_eq!(p.last(), Some(&(1.0, 1.25)));
        assert_eq!(p[0], (1.75, 2.0));
    }

    // A cross-section model: positive before `enter`, straddling zero
    // (leaning inside by `lean`: lo = -1, hi = lean) until `inside`, then
    // negative. Counts the cross-sections asked for.
    fn model(
        enter: f64,
        inside: f64,
        lean: f64,
        calls: &mut usize,
    ) -> impl FnMut(f64) -> SignBound {
        move |t| {
            *calls += 1;
            SignBound::of(if t < enter {
                Interval::new(1.0, 2.0)
            } else if t < inside {
                Interval::new(-1.0, lean)
            } else {
                Interval::new(-2.0, -1.0)
            })
        }
    }

    #[test]
    fn the_bracket_reaches_deeper_only_while_the_cross_section_leans_inside() {
        let reach = Reach::INCLUSION;
        let w = |_| 0.0;
        // Inside within the usual reach: found there, whatever the lean.
        let mut n = 0;
        let end = bracket_end((1.0, 2.0), 100.0, w, reach, model(1.5, 2.5, 5.0, &mut n));
        assert_eq!(end, Some(3.0));
        // Inside at 10 widths: found at 16 when the cross-sections on the
        // way lean inside...
        let mut n = 0;
        let end = bracket_end((1.0, 2.0), 100.0, w, reach, model(1.5, 10.0, 0.5, &mut n));
        assert_eq!(end, Some(17.0));
        assert_eq!(n, 1 + 3 + 2);
        // ...and not when they straddle evenly or lean outside (a
        // silhouette): no cross-section is asked for past the usual reach.
        for lean in [1.0, 5.0] {
            let mut n = 0;
            let end = bracket_end((1.0, 2.0), 100.0, w, reach, model(1.5, 10.0, lean, &mut n));
            assert_eq!(end, None);
            assert_eq!(n, 1 + 3);
        }
        // The deeper multiples stop at the end of the beam's range (asked
        // once), and nothing is found unless the cross-section at ta is
        // positive.
        let mut n = 0;
        let end = bracket_end((1.0, 2.0), 7.0, w, reach, model(1.5, 10.0, 0.5, &mut n));
        assert_eq!((end, n), (None, 1 + 3 + 1));
        let mut n = 0;
        let end = bracket_end((1.0, 2.0), 7.0, w, reach, model(1.5, 6.0, 0.5, &mut n));
        assert_eq!((end, n), (Some(7.0), 1 + 3 + 1));
        let mut n = 0;
        let end = bracket_end((1.0, 2.0), 100.0, w, reach, model(0.5, 10.0, 0.5, &mut n));
        assert_eq!((end, n), (None, 1));
        // Without deeper multiples, the usual reach alone.
        let mut n = 0;
        let usual = Reach {
            usual: &INCLUSION_REACH,
            deeper: &[],
        };
        let end = bracket_end((1.0, 2.0), 100.0, w, usual, model(1.5, 10.0, 0.5, &mut n));
        assert_eq!((end, n), (None, 1 + 3));
    }
}
