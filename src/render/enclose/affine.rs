//! The affine form of an object over a block, where its natural interval
//! straddles 0: reduced affine arithmetic (`eval::affine`) on the tape
//! that answers for the block's region, which overestimates far less than
//! intervals where a variable appears many times (quartics and sextics
//! with many nodes, expanded polynomials).

use std::sync::Arc;

use crate::eval::affine::{AffineEvaluator, affine_along};
use crate::eval::tape::Tape;
use crate::interval::Interval;
use crate::interval::affine::along_parameter;
use crate::interval::boxes::{IBox, box_within};
use crate::render::Enclosure;
use crate::render::context::Context;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::proof::{self, SignBound};
use crate::render::view::camera::PixelRay;

/// Functions with more live ops than this get no affine form: unions of
/// many objects are min/max trees, where the form falls back to the
/// interval rule at every undecided `min` and only costs (an affine
/// evaluation costs about fifty interval ones, `ibeam bench enclosure`).
pub(crate) const AFFINE_MAX_OPS: usize = 4096;

/// Whole-function tapes for the affine form, one per object (None: too
/// long, or no function), for `choice`; empty where intervals only.
pub(crate) fn whole_tapes(ctx: &Context<'_>, choice: Enclosure) -> Arc<[Option<Arc<Tape>>]> {
    if choice == Enclosure::Interval {
        return Arc::new([]);
    }
    ctx.evals
        .iter()
        .map(|e| {
            let f = e.function()?;
            (f.live_count() <= AFFINE_MAX_OPS).then(|| Arc::new(Tape::new(f)))
        })
        .collect()
}

/// The signs object `k`'s affine form proves over `b`, on [`tape_for`]'s
/// tape (a sign-keeping tape proves signs alone, which is all this
/// returns); `None` where no tape pays.
pub(crate) fn affine_signs(
    ctx: &Context<'_>,
    k: usize,
    b: IBox,
    stats: &mut RenderStats,
) -> Option<SignBound> {
    let tape = tape_for(ctx, k, &b)?;
    stats.affine_tries += 1;
    let a = tape.affine(b);
    (!a.is_empty()).then(|| SignBound::of(a))
}

/// The tape object `k`'s affine forms run on over `b`: the smallest region
/// of its evaluator's tree that holds `b`, or its whole tape; `None`
/// where it has neither, or the tape is too long to pay.
fn tape_for<'c>(ctx: &'c Context<'_>, k: usize, b: &IBox) -> Option<&'c Tape> {
    // A region's tape is exact on its region only (and keeps its signs
    // there): a box reaching out of it takes the whole function's.
    let tape: &Tape = match ctx.region_of(k) {
        Some(r) if box_within(b, &r.region()) => r.smallest_holding(b).pruned_tape(),
        _ => ctx.affine_tapes.get(k)?.as_deref()?,
    };
    (tape.len() <= AFFINE_MAX_OPS).then_some(tape)
}

/// What an object's form along a ray proves over a piece of the ray.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) enum AlongRay {
    /// No surface of it on the piece: f positive or undefined throughout.
    Free,
    /// Its surface, if any, lies in this part `(a, b)` of the piece: f is
    /// positive or undefined on the rest.
    Within(f64, f64),
}

/// Object `k`'s affine form along `ray` over the piece `(a, b)`, whose box
/// is `bx`, in the ray parameter's one noise symbol
/// ([`eval::affine::affine_along`]): where the form's linear part stays
/// above its error, f is positive, so the piece shrinks to where it does
/// not. `None` where no tape pays (as [`affine_signs`]).
///
/// [`eval::affine::affine_along`]: crate::eval::affine::affine_along
pub(crate) fn affine_along_ray(
    ctx: &Context<'_>,
    k: usize,
    ray: &PixelRay,
    (a, b): (f64, f64),
    bx: IBox,
    stats: &mut RenderStats,
) -> Option<AlongRay> {
    let tape = tape_for(ctx, k, &bx)?;
    stats.affine_ray_tries += 1;
    let t = Interval::new(a, b);
    let v = affine_along(tape, ray.o, ray.d, t, bx);
    if proof::holds_no_surface(v.range) {
        return Some(AlongRay::Free);
    }
    let part = v
        .form
        .may_reach_zero()
        .and_then(|eps| along_parameter(t, eps));
    Some(part.map_or(AlongRay::Free, |p| AlongRay::Within(p.lo, p.hi)))
}
