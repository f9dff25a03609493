//! The second-order forms along a single shadow segment, tried on the
//! pieces that the interval and monotonicity proofs leave open (see
//! `docs/tracer.md`, "Shadows").

use super::{FreeSearch, Front};
use crate::interval::boxes::IBox;
use crate::render::Enclosure;
use crate::render::enclose::affine;
use crate::render::prune::scope::Scope;
use crate::render::trace::sweep::Visit;

impl FreeSearch<'_, '_> {
    // Where the scene's enclosure choice asks for them (`auto`: objects
    // whose forms pay, `affine::along_may_pay`), the second-order forms
    // along a single segment, as single rays try them (`trace::ray`):
    // drops from `maybe` the objects they prove free of surface on the
    // piece, and sweeps only the part where the rest may have theirs,
    // when that is at most half the piece. A part dropped proves what a
    // rejected piece proves, nothing about what follows it (`proof`): the
    // front is then unknown, and a part behind the kept one is swept as a
    // piece of its own, so that the pieces stay contiguous.
    pub(super) fn along_forms(
        &mut self,
        tr: &Scope<'_>,
        (a, c): (f64, f64),
        bx: IBox,
    ) -> Option<Visit<()>> {
        let seg = self.seg;
        let choice = tr.ctx.enclosure;
        if seg.starts.len() != 1
            || choice == Enclosure::Interval
            || (choice == Enclosure::Auto
                && !self
                    .maybe
                    .iter()
                    .any(|&k| affine::along_may_pay(&tr.ctx, k)))
        {
            return None;
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let st = &mut *self.st;
        self.maybe.retain(|&k| {
            let along = affine::affine_along_line(&tr.ctx, k, seg.q, seg.delta, (a, c), bx);
            st.stats.affine_shadow_tries += u64::from(along.is_some());
            let (pa, pb) = affine::part_left(along, (a, c));
            if along.is_some() {
                st.stats.affine_shadow_wins += u64::from(pb - pa <= 0.5 * (c - a));
            }
            lo = lo.min(pa);
            hi = hi.max(pb);
            pa <= pb
        });
        if self.maybe.is_empty() {
            self.sw.front = Front::Unknown;
            return Some(Visit::Drop);
        }
        // (A part of no width goes on as the whole piece: pieces have a < c.)
        if hi - lo > 0.5 * (c - a) || lo >= hi {
            return None;
        }
        if lo > a {
            self.sw.front = Front::Unknown;
        }
        Some(Visit::Parts(Some((lo, hi)), (hi < c).then_some((hi, c))))
    }
}
