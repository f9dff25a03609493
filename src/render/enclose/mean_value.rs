//! The mean-value form `f(c) + ∇F(b)·(b − c)` where a natural enclosure
//! straddles 0, and the per-tile policy that learns, per block size,
//! whether the form still pays.

use crate::eval::Evaluator;
use crate::interval::Interval;
use crate::interval::boxes::{IBox, point_box};
use crate::render::context::Context;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::proof::{self, SignBound};

/// Block-size classes (log2 of the side) the mean-value policy tells apart.
pub(crate) const MV_LEVELS: usize = 8;
/// Tries at one block size before the mean-value policy judges the form.
const MV_MIN_TRIES: u64 = 16;
/// The form stays in use at a block size while at least one try in this
/// many wins.
const MV_WIN_RATIO: u64 = 32;

/// Whether the mean-value form still pays in one tile, per block size.
///
/// Where the form seldom decides anything (min/max-heavy functions, whose
/// gradients are discontinuous), it only costs gradient evaluations:
/// after [`MV_MIN_TRIES`] tries at one block size (it pays off on small
/// blocks first) with under 1 in [`MV_WIN_RATIO`] winning, the tile stops
/// using it at that size. The record is per tile, so the choice does not
/// depend on the thread count.
#[derive(Clone, Debug, Default)]
pub(crate) struct MeanValuePolicy {
    /// (tries, wins) per block-size class.
    levels: [(u64, u64); MV_LEVELS],
}

impl MeanValuePolicy {
    /// A policy that never tries the form, as if it had lost every try at
    /// every block size.
    pub(crate) fn never() -> MeanValuePolicy {
        MeanValuePolicy {
            levels: [(MV_MIN_TRIES, 0); MV_LEVELS],
        }
    }

    /// Whether the form is still worth trying on blocks of class `level`.
    pub(crate) fn pays(&self, level: usize) -> bool {
        let (tries, wins) = self.levels[level.min(MV_LEVELS - 1)];
        !(tries >= MV_MIN_TRIES && wins * MV_WIN_RATIO < tries)
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
    /// The tile's record of where the form pays.
    pub policy: &'s mut MeanValuePolicy,
}

/// The signs of object `k`'s F over `b` (None: F undefined on all of it),
/// tightened where the natural enclosure straddles 0 by the mean-value
/// form `f(c) + ∇F(b)·(b − c)` (c the box centre), met with it. Sound
/// wherever the evaluator's gradient enclosure covers the (generalised)
/// gradient of f over the box; it is used only when every gradient bound
/// is finite, which rules out the poles and domain edges where it would
/// not. `level` is the block's size class for the [`MeanValuePolicy`].
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
    // form outright: their functions are min/max trees of thousands of
    // ops, where it measured 7 wins in 13,833 tries on prospero at 512²
    // while compiling and running the interval-gradient evaluator
    // doubled the render time.
    if ctx.flat || !tile.policy.pays(level) {
        return Some(natural);
    }
    if !b.iter().all(|c| c.lo.is_finite() && c.hi.is_finite()) {
        return Some(natural);
    }
    let Some(mv) = mean_value_form(ctx.answering(k, &b), b, tile.stats) else {
        return Some(natural);
    };
    // `f` may come from another region's tape than `mv` (one that keeps
    // signs only); the meet still proves a sign only where one of the two
    // does, and every tape of the tree has the same signs.
    let tight = natural.meet(SignBound::of(mv));
    let win = tight.positive() || tight.negative();
    tile.stats.mean_value_tries += 1;
    tile.stats.mean_value_wins += u64::from(win);
    tile.policy.record(level, win);
    Some(tight)
}

/// The mean-value form of `e` over the finite box `b`, with the centre's
/// value and the gradient from one function (see
/// [`Specialise::answering`]); `None` where a bound is not finite.
fn mean_value_form(e: &dyn Evaluator, b: IBox, stats: &mut RenderStats) -> Option<Interval> {
    let c: [f64; 3] = b.map(|i| i.mid());
    stats.interval_evals += 2;
    let g = e.interval_grad(b);
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
