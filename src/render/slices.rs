//! Trees of regions along a tile's beam: the beam over its whole depth,
//! halved along the rays into slices about as deep as the beam is wide,
//! each slice's tape pruned from the one it halves (see
//! [`Tracer::pruned_to_beam`]), and the slices' ends, where sweeps along
//! rays start their pieces (`Tracer::first_pieces`).

use std::sync::Arc;

use super::camera::CornerRays;
use super::tracer::{
    PRUNE_MIN_OPS, PrunedEvals, SLICE_ASPECT, SLICE_DEPTH, TileState, Tracer, gain,
};
use crate::eval::Evaluator;
use crate::eval::regional::Regional;
use crate::eval::tape::Tape;
use crate::interval::Interval;
use crate::interval::boxes::box_within;

impl Tracer<'_> {
    /// The interior ends, in increasing order, of the slices that
    /// [`Tracer::pruned_to_beam`] cuts the beam through the pixel centres
    /// `xs × ys` over `t` into.
    pub(crate) fn slice_ends(&self, xs: (f64, f64), ys: (f64, f64), t: Interval) -> Vec<f64> {
        fn collect(
            tr: &Tracer<'_>,
            b: ((f64, f64), (f64, f64)),
            t: Interval,
            depth: u32,
            out: &mut Vec<f64>,
        ) {
            if tr.halves(b.0, b.1, t, depth) {
                let m = t.mid();
                collect(tr, b, Interval::new(t.lo, m), depth - 1, out);
                out.push(m);
                collect(tr, b, Interval::new(m, t.hi), depth - 1, out);
            }
        }
        let mut out = Vec::new();
        collect(self, (xs, ys), t, SLICE_DEPTH, &mut out);
        out
    }

    // Whether the tree of regions of the beam through `xs × ys` halves its
    // region over `t` along the rays, with `depth` levels left: while a
    // slice is deeper than `SLICE_ASPECT` times its width, unless the
    // scene is flat.
    fn halves(&self, xs: (f64, f64), ys: (f64, f64), t: Interval, depth: u32) -> bool {
        let w = |r: (f64, f64)| (r.1 - r.0 + 1.0) * self.cam.spacing(t.hi);
        let width = w(xs).max(w(ys));
        !(depth == 0 || self.flat || t.width() <= SLICE_ASPECT * width)
    }

    /// The scene's evaluators pruned to the beam of the rays through the
    /// pixel centres `xs × ys` over `t`, each a tree of regions: the beam
    /// over all of `t`, then (unless the scene is flat) its halves along
    /// the rays, and so on down to slices about as deep as the beam is
    /// wide, each pruned from the one it halves. Near the eye and behind
    /// it a long beam thus becomes short slices, over which a CSG tree of
    /// many objects keeps only the few that cross each one; the whole
    /// beam's own tape seldom shrinks much. `None` when nothing prunes.
    pub(crate) fn pruned_to_beam(
        &self,
        xs: (f64, f64),
        ys: (f64, f64),
        t: Interval,
        st: &mut TileState,
    ) -> Option<PrunedEvals> {
        if !self.prune || !self.live_ops.iter().any(|&n| n >= PRUNE_MIN_OPS) {
            return None;
        }
        // The tile prunes from its group's tapes when the group's region
        // holds the tile's (a tape is exact only on its own region).
        let pixel = (xs.0 as u32, ys.0 as u32);
        let group = self.groups.of_pixel(self, pixel, st).filter(|(_, g)| {
            self.beam_region(xs, ys, t)
                .is_some_and(|r| box_within(&r, g))
        });
        self.replace_evals(|k, e| match &self.tapes[k] {
            Some(tape) if self.live_ops[k] >= PRUNE_MIN_OPS && e.as_regional().is_none() => {
                let from = group.as_ref().map(|((evals, _), _)| &evals[k]);
                let (parent, tape, above) = match from.and_then(|g| Some((g, g.as_regional()?))) {
                    Some((g, r)) => (g, r.pruned_tape(), (r.answer(), r.answer_len())),
                    None => (e, &**tape, (e, tape.len())),
                };
                let corners = self.cam.corners(xs, ys);
                let beam = Beam {
                    xs,
                    ys,
                    corners,
                    parent,
                };
                let tree = beam.node(self, tape, t, above, SLICE_DEPTH, st)?;
                let n = tree.pruned_tape().len();
                Some((Arc::new(tree) as Arc<dyn Evaluator>, n))
            }
            _ => None,
        })
    }
}

// The beam a tree of regions is built over.
struct Beam<'e> {
    xs: (f64, f64),
    ys: (f64, f64),
    corners: CornerRays,
    parent: &'e Arc<dyn Evaluator>,
}

impl Beam<'_> {
    // The region of the beam over `t`, with `tape` (exact on a region
    // holding it) pruned to it, and its halves along the rays below it.
    // `above` is what answers for the region if its own tape is not much
    // shorter, with the length of its tape.
    fn node(
        &self,
        tr: &Tracer<'_>,
        tape: &Tape,
        t: Interval,
        above: (&Arc<dyn Evaluator>, usize),
        depth: u32,
        st: &mut TileState,
    ) -> Option<Regional> {
        let region = tr.corner_region(&self.corners, t)?;
        let own = tape.prune(region, &mut st.workspace).map(|p| p.tape);
        let own = own.unwrap_or_else(|| tape.clone());
        let answers = own.len() * gain(above.0.as_ref()) <= above.1;
        let parent = Arc::clone(self.parent);
        let node = if answers {
            st.stats.pruned_ops_before += above.1 as u64;
            st.stats.pruned_ops_after += own.len() as u64;
            Regional::new(region, own, parent)
        } else {
            Regional::delegating(region, own, (Arc::clone(above.0), above.1), parent)
        };
        if !tr.halves(self.xs, self.ys, t, depth) {
            return Some(node);
        }
        let below = (Arc::clone(node.answer()), node.answer_len());
        let m = t.mid();
        let children = [Interval::new(t.lo, m), Interval::new(m, t.hi)]
            .into_iter()
            .filter_map(|half| {
                let tape = node.pruned_tape();
                self.node(tr, tape, half, (&below.0, below.1), depth - 1, st)
            })
            .collect();
        Some(node.with_children(children))
    }
}
