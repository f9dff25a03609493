//! The affine form of an object over a block, where its natural interval
//! straddles 0: reduced affine arithmetic (`eval::affine`) on the tape
//! that answers for the block's region, which overestimates far less than
//! intervals where a variable appears many times (quartics and sextics
//! with many nodes, expanded polynomials).

use std::sync::Arc;

use crate::eval::affine::AffineEvaluator;
use crate::eval::tape::Tape;
use crate::interval::boxes::{IBox, box_within};
use crate::render::Enclosure;
use crate::render::context::Context;
use crate::render::context::stats::RenderStats;
use crate::render::enclose::proof::SignBound;

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

/// The signs object `k`'s affine form proves over `b`, on the tape of the
/// smallest region of its evaluator's tree that holds `b` (a sign-keeping
/// tape proves signs alone, which is all this returns) or on its whole
/// tape; `None` where it has neither, or the tape is too long to pay.
pub(crate) fn affine_signs(
    ctx: &Context<'_>,
    k: usize,
    b: IBox,
    stats: &mut RenderStats,
) -> Option<SignBound> {
    // A region's tape is exact on its region only (and keeps its signs
    // there): a box reaching out of it takes the whole function's.
    let tape: &Tape = match ctx.region_of(k) {
        Some(r) if box_within(&b, &r.region()) => r.smallest_holding(&b).pruned_tape(),
        _ => ctx.affine_tapes.get(k)?.as_deref()?,
    };
    if tape.len() > AFFINE_MAX_OPS {
        return None;
    }
    stats.affine_tries += 1;
    let a = tape.affine(b);
    (!a.is_empty()).then(|| SignBound::of(a))
}
