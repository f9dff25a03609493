//! The mean-value form `f(c) + ∇F(b)·(b − c)` where a natural enclosure
//! straddles 0, and the per-tile policy that learns, per block size,
//! whether the form still pays.

use crate::eval::Evaluator;
use crate::interval::Interval;
use crate::interval::boxes::{IBox, point_box};
use crate::render::Enclosure;
use crate::render::context::Context;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::affine;
use crate::render::enclose::proof::{self, SignBound};

/// Block-size classes (log2 of the side) the mean-value policy tells apart.
pub(crate) const MV_LEVELS: usize = 8;
/// Tries at one block size before the mean-value policy judges the form.
const MV_MIN_TRIES: u64 = 16;
/// The form stays in use at a block size while at least one try in this
/// many wins.
const MV_WIN_RATIO: u64 = 32;

/// Tries at one block size before the affine form is judged: few, as
/// each costs about fifty interval evaluations.
const AFFINE_MIN_TRIES: u64 = 2;
/// The affine form stays in use at a block size while at least one try in
/// this many wins (where it does not, the mean-value form and bisection
/// were cheaper on every example: `docs/performance.md`).
const AFFINE_WIN_RATIO: u64 = 2;

/// The share of its tries (numerator, denominator) that the form along
/// a ray must win at a piece size to stay in use there. A try of the
/// second-order form costs about ten interval evaluations; a piece it
/// drops saves the interval evaluations of the piece's bisection, which
/// on the examples came to less than that wherever under three tries in
/// four dropped theirs, and to far more on the expanded polynomial, where
/// nineteen in twenty do (docs/performance.md).
const ALONG_WIN_SHARE: (u64, u64) = (3, 4);

/// Whether a form still pays in one tile, per block size.
///
/// Where the form seldom decides anything (min/max-heavy functions, whose
/// gradients are discontinuous), it only costs gradient evaluations:
/// after [`MV_MIN_TRIES`] tries at one block size (it pays off on small
/// blocks first) with under 1 in [`MV_WIN_RATIO`] winning, the tile stops
/// using it at that size. The record is per tile, so the choice does not
/// depend on the thread count.
#[derive(Clone, Debug, Default)]
pub(crate) struct FormPolicy {
    /// (tries, wins) per block-size class.
    levels: [(u64, u64); MV_LEVELS],
}

impl FormPolicy {
    /// A policy that never tries the form, as if it had lost every try at
    /// every block size.
    pub(crate) fn never() -> FormPolicy {
        FormPolicy {
            levels: [(MV_MIN_TRIES, 0); MV_LEVELS],
        }
    }

    /// Whether the mean-value form is still worth trying on blocks of
    /// class `level`.
    pub(crate) fn pays(&self, level: usize) -> bool {
        self.pays_at(level, MV_MIN_TRIES, MV_WIN_RATIO)
    }

    /// Whether the affine form is still worth trying on blocks of class
    /// `level`: a try costs about fifty interval evaluations, so it must
    /// win one try in [`AFFINE_WIN_RATIO`], judged after
    /// [`AFFINE_MIN_TRIES`].
    pub(crate) fn pays_affine(&self, level: usize) -> bool {
        self.pays_at(level, AFFINE_MIN_TRIES, AFFINE_WIN_RATIO)
    }

    /// Whether a block or piece of class `level` tries the affine form
    /// under the scene's `choice` (`auto`: while it pays, see
    /// [`FormPolicy::pays_affine`]).
    pub(crate) fn affine_wanted(&self, choice: Enclosure, level: usize) -> bool {
        match choice {
            Enclosure::Interval => false,
            Enclosure::Affine => true,
            Enclosure::Auto => self.pays_affine(level),
        }
    }

    /// Whether a ray piece of class `level` tries the form along the ray
    /// under the scene's `choice` (`auto`: while at least
    /// [`ALONG_WIN_SHARE`] of its tries at that class won, judged after
    /// [`AFFINE_MIN_TRIES`]).
    pub(crate) fn along_wanted(&self, choice: Enclosure, level: usize) -> bool {
        match choice {
            Enclosure::Interval => false,
            Enclosure::Affine => true,
            Enclosure::Auto => {
                let (tries, wins) = self.levels[level.min(MV_LEVELS - 1)];
                let (num, den) = ALONG_WIN_SHARE;
                tries < AFFINE_MIN_TRIES || wins * den >= tries * num
            }
        }
    }

    // Whether fewer than `min_tries` tries were made at `level`, or at
    // least one in `ratio` won.
    fn pays_at(&self, level: usize, min_tries: u64, ratio: u64) -> bool {
        let (tries, wins) = self.levels[level.min(MV_LEVELS - 1)];
        !(tries >= min_tries && wins * ratio < tries)
    }

    /// Whether a try has won at any class.
    pub(crate) fn has_won(&self) -> bool {
        self.levels.iter().any(|&(_, wins)| wins > 0)
    }

    /// Records one try at class `level`.
    pub(crate) fn record(&mut self, level: usize, win: bool) {
        let lv = &mut self.levels[level.min(MV_LEVELS - 1)];
        lv.0 += 1;
        lv.1 += u64::from(win);
    }
}
/// What the mean-value form reads and writes on one tile: its counters and
/// its policy.
pub(crate) struct MeanValueUse<'s> {
    /// The tile's counters.
    pub stats: &'s mut RenderStats,
    /// The tile's record of where the mean-value form pays.
    pub policy: &'s mut FormPolicy,
    /// The tile's record of where the affine form pays.
    pub affine: &'s mut FormPolicy,
}

/// The signs of object `k`'s F over `b` (None: F undefined on all of it),
/// tightened where the natural enclosure straddles 0 by the mean-value
/// form `f(c) + ∇F(b)·(b − c)` (c the box centre), met with it. Sound
/// wherever the evaluator's gradient enclosure covers the (generalised)
/// gradient of f over the box; it is used only when every gradient bound
/// is finite, which rules out the poles and domain edges where it would
/// not. `level` is the block's size class for the [`FormPolicy`].
/// Signs only: the natural enclosure may come from another region's tape
/// than the form (see [`SignBound`]).
pub(crate) fn sign_bound(
    ctx: &Context<'_>,
    k: usize,
    b: IBox,
    level: usize,
    tile: MeanValueUse<'_>,
) -> Option<SignBound> {
    let f = ctx.interval(k, b, tile.stats);
    if f.is_empty() {
        return None;
    }
    let natural = SignBound::of(f);
    if f.lo > 0.0 || f.hi < 0.0 {
        return Some(natural);
    }
    // Flat scenes (2D models seen along their missing axis) skip the
    // forms outright: their functions are min/max trees of thousands of
    // ops, where the mean-value form measured 7 wins in 13,833 tries on
    // prospero at 512² while compiling and running the interval-gradient
    // evaluator doubled the render time.
    if ctx.flat {
        return Some(natural);
    }
    if !b.iter().all(|c| c.lo.is_finite() && c.hi.is_finite()) {
        return Some(natural);
    }
    let mut bound = natural;
    // Until the form has won on this tile, its gradients come from the
    // interpreter's rules: on min/max trees such as sphere unions it never
    // wins, and compiling the native interval gradient for it kept the
    // render waiting (10 spheres at 1024²: 13 ms of a 15 ms wait). The
    // switch depends on the tile's own tries alone, so the pixels do not
    // depend on the thread count or on when code compiles.
    let native = tile.policy.has_won();
    if tile.policy.pays(level)
        && let Some(mv) = mean_value_form(ctx.answering(k, &b), b, native, tile.stats)
    {
        // `f` may come from another region's tape than `mv` (one that
        // keeps signs only); the meet still proves a sign only where one
        // of the two does, and every tape of the tree has the same signs.
        bound = natural.meet(SignBound::of(mv));
        let win = bound.positive() || bound.negative();
        tile.stats.mean_value_tries += 1;
        tile.stats.mean_value_wins += u64::from(win);
        tile.policy.record(level, win);
        if win {
            return Some(bound);
        }
    }
    // The affine form where the mean-value form left the block undecided
    // and the scene asks for it: where a variable appears many times it
    // decides blocks the cheaper form leaves, at about fifty interval
    // evaluations a try.
    if tile.affine.affine_wanted(ctx.enclosure, level)
        && let Some(a) = affine::affine_signs(ctx, k, b, tile.stats)
    {
        // Signs only, as above.
        let tight = bound.meet(a);
        let win = tight.positive() || tight.negative();
        tile.stats.affine_wins += u64::from(win);
        tile.affine.record(level, win);
        return Some(tight);
    }
    Some(bound)
}

/// The mean-value form of `e` over the finite box `b`, with the centre's
/// value and the gradient from one function (see
/// [`Specialise::answering`]), the gradient native where `native` (else
/// the interpreter's, [`Single::interval_grad_interpreted`]); `None`
/// where a bound is not finite.
fn mean_value_form(
    e: &dyn Evaluator,
    b: IBox,
    native: bool,
    stats: &mut RenderStats,
) -> Option<Interval> {
    let c: [f64; 3] = b.map(|i| i.mid());
    stats.interval_evals += 2;
    let g = if native {
        e.interval_grad(b)
    } else {
        e.interval_grad_interpreted(b)
    };
    if !g.d.iter().all(|&d| proof::bounded(d)) {
        return None;
    }
    let fc = e.interval(point_box(c));
    if !proof::bounded(fc) {
        return None;
    }
    let mut mv = fc;
    for i in 0..3 {
        mv = mv.add(g.d[i].mul(b[i].sub(Interval::point(c[i]))));
    }
    Some(mv)
}
