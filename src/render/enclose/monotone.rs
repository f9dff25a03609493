//! The monotone tests: an object proven increasing or decreasing along a
//! direction over a box, from one directional-derivative enclosure read
//! by `proof`'s rule (an unbounded derivative proves nothing).

use crate::interval::boxes::IBox;
use crate::render::context::Context;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::proof;

/// Whether object `k` is proven strictly decreasing along every direction
/// in `dir` over `b`.
pub(crate) fn decreasing_along(
    ctx: &Context<'_>,
    k: usize,
    b: IBox,
    dir: IBox,
    stats: &mut RenderStats,
) -> bool {
    proof::decreasing(ctx.interval_dir(k, b, dir, stats)[1])
}

/// Whether object `k` is proven strictly increasing along every direction
/// in `dir` over `b`.
pub(crate) fn increasing_along(
    ctx: &Context<'_>,
    k: usize,
    b: IBox,
    dir: IBox,
    stats: &mut RenderStats,
) -> bool {
    proof::increasing(ctx.interval_dir(k, b, dir, stats)[1])
}
