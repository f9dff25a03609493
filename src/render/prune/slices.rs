//! Trees of regions along a tile's beam, or a group of tiles': the beam
//! over its whole depth, halved along the rays into slices about as deep
//! as the beam is wide, each slice's tape pruned from the shortest one
//! exact on it (see [`Scope::pruned_to_beam`]), and the slices' ends,
//! where sweeps along rays start their pieces (`Scope::first_pieces`).

use std::sync::Arc;

use super::groups::TileTapes;
use crate::eval::regional::{Answer, Parent, Regional};
use crate::eval::tape::Tape;
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_within};
use crate::render::context::EvalSet;
use crate::render::context::PRUNE_MIN_OPS;
use crate::render::prune::scope::SLICE_ASPECT;
use crate::render::prune::scope::SLICE_DEPTH;
use crate::render::prune::scope::Scope;
use crate::render::prune::scope::TileState;
use crate::render::prune::scope::gain;
use crate::render::view::camera::CornerRays;

impl Scope<'_> {
    /// The interior ends, in increasing order, of the slices that
    /// [`Scope::pruned_to_beam`] cuts the beam through the pixel centres
    /// `xs × ys` over `t` into.
    pub(crate) fn slice_ends(&self, xs: (f64, f64), ys: (f64, f64), t: Interval) -> Vec<f64> {
        fn collect(
            tr: &Scope<'_>,
            b: ((f64, f64), (f64, f64)),
            t: Interval,
            depth: u32,
            out: &mut Vec<f64>,
        ) {
            if tr.halves(b, t, depth, SLICE_ASPECT) {
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
    // slice is deeper than `aspect` times its width, unless the scene is
    // flat.
    fn halves(
        &self,
        (xs, ys): ((f64, f64), (f64, f64)),
        t: Interval,
        depth: u32,
        aspect: f64,
    ) -> bool {
        !(depth == 0 || self.ctx.flat || t.width() <= aspect * self.beam_width(xs, ys, t))
    }

    // The width of the beam through the pixel centres `xs × ys` at the far
    // end of `t`.
    fn beam_width(&self, xs: (f64, f64), ys: (f64, f64), t: Interval) -> f64 {
        let w = |r: (f64, f64)| (r.1 - r.0 + 1.0) * self.ctx.cam.spacing(t.hi);
        w(xs).max(w(ys))
    }

    /// The scene's evaluators pruned to the beam of the rays through the
    /// pixel centres `xs × ys` over `t`, each a tree of regions: the beam
    /// over all of `t`, then (unless the scene is flat) its halves along
    /// the rays, and so on down to slices about as deep as the beam is
    /// wide. Near the eye and behind it a long beam thus becomes short
    /// slices, over which a CSG tree of many objects keeps only the few
    /// that cross each one; the whole beam's own tape seldom shrinks much.
    /// Each region prunes from the shortest tape exact on it: the one it
    /// halves, or its group's smallest region holding it (see
    /// `render::groups`). `None` when nothing prunes.
    pub(crate) fn pruned_to_beam(
        &self,
        xs: (f64, f64),
        ys: (f64, f64),
        t: Interval,
        st: &mut TileState,
    ) -> Option<EvalSet> {
        if !self.pruner.enabled || !self.ctx.live_ops.iter().any(|&n| n >= PRUNE_MIN_OPS) {
            return None;
        }
        // The tile prunes from its group's tapes when the group's region
        // holds the tile's (a tape is exact only on its own region).
        let pixel = (xs.0 as u32, ys.0 as u32);
        let group = self
            .pruner
            .groups
            .of_pixel(self, pixel, st)
            .filter(|(_, g, _)| {
                self.ctx
                    .beam_region(xs, ys, t)
                    .is_some_and(|r| box_within(&r, g))
            });
        let tiles = group.as_ref().and_then(|(_, _, tiles)| tiles.as_deref());
        let group = group.as_ref().map(|(evals, _, _)| evals);
        let from = TreeSource {
            group,
            tiles,
            is_group: false,
        };
        self.beam_trees(xs, ys, t, from, st)
    }

    /// The trees of [`Scope::pruned_to_beam`] for a group of tiles, each
    /// pruned from the whole function, down to slices about as deep as the
    /// group is wide (a tile's slices, four times narrower, stop at twice
    /// their width), for its tiles' slices to prune from.
    /// Where `pre` is given, its tapes (pruned to the group's region, see
    /// `groups::TileTapes`) are taken instead of pruning again.
    pub(crate) fn pruned_group(
        &self,
        xs: (f64, f64),
        ys: (f64, f64),
        t: Interval,
        pre: Option<&TileTapes>,
        st: &mut TileState,
    ) -> Option<EvalSet> {
        if !self.pruner.enabled {
            return None;
        }
        let from = TreeSource {
            group: None,
            tiles: pre,
            is_group: true,
        };
        self.beam_trees(xs, ys, t, from, st)
    }

    // Each large function's tree of regions along the beam through `xs ×
    // ys` over `t`, pruned from `group`'s trees where given, its root
    // taking the tape the group pruned for it where `tiles` has one.
    fn beam_trees(
        &self,
        xs: (f64, f64),
        ys: (f64, f64),
        t: Interval,
        from: TreeSource<'_>,
        st: &mut TileState,
    ) -> Option<EvalSet> {
        let TreeSource {
            group,
            tiles,
            is_group: group_beam,
        } = from;
        self.ctx.replace_evals(|k, e| match &self.pruner.tapes[k] {
            Some(tape)
                if self.ctx.live_ops[k] >= PRUNE_MIN_OPS && self.ctx.region_of(k).is_none() =>
            {
                let from = group.and_then(|g| g.regions[k].as_ref());
                let (parent, tape, above, tree) = match from {
                    Some(r) => (
                        Parent::Region(Arc::clone(r)),
                        r.pruned_tape(),
                        Answer {
                            evaluator: Arc::clone(r.answer()),
                            ops: r.answer_len(),
                        },
                        Some(&**r),
                    ),
                    None => {
                        let above = Answer {
                            evaluator: Arc::clone(e),
                            ops: tape.len(),
                        };
                        (Parent::Whole(Arc::clone(e)), &**tape, above, None)
                    }
                };
                let beam = Beam {
                    xs,
                    ys,
                    corners: self.ctx.cam.corners(xs, ys),
                    parent,
                    group: tree,
                    is_group: group_beam,
                    pre: tiles.and_then(|p| {
                        let (from, tape) = p.tapes.get(k)?.as_ref()?;
                        Some((p.region, *from, tape))
                    }),
                };
                let placed = beam.place(self, tape, t)?;
                let tree = beam.node(self, tape, placed, above, SLICE_DEPTH, st)?;
                let n = tree.pruned_tape().len();
                Some((Arc::new(tree), n))
            }
            _ => None,
        })
    }
}

// What a beam's trees start from: the trees of its group of tiles (for
// a tile's beam), the tapes pruned for it ahead of time, and whether the
// beam is a group's.
struct TreeSource<'a> {
    group: Option<&'a EvalSet>,
    tiles: Option<&'a TileTapes>,
    is_group: bool,
}

// A region of a beam's tree, placed before its node is built: its box,
// the smallest region of the group's tree holding it (when that tape is
// no longer than the one it would prune from), and its pruning from that
// tape, where it was made with its sibling's (`None`: not made yet).
struct Placed<'g> {
    // The stretch of the rays the region covers.
    range: Interval,
    region: IBox,
    held: Option<&'g Regional>,
    pruned: Option<Option<Tape>>,
}

// The beam a tree of regions is built over.
struct Beam<'e> {
    xs: (f64, f64),
    ys: (f64, f64),
    corners: CornerRays,
    // What the beam's regions fall back on outside them.
    parent: Parent,
    // The tree of the group of tiles the beam lies in, whose regions a
    // region inside one of them may prune from.
    group: Option<&'e Regional>,
    // Whether the beam is a group's.
    is_group: bool,
    // A tape pruned for the group's tile or row ahead of time
    // (`groups::TileTapes`): the region, the address of the tape pruned,
    // and the result (`None`: nothing decided there).
    pre: Option<(IBox, usize, &'e Option<Tape>)>,
}

impl<'e> Beam<'e> {
    // The region of the beam over `t`, with its tape pruned from `tape`
    // (exact on a region holding it) or from the group's smallest region
    // holding it, whichever is shorter, and its halves along the rays
    // below it. `above` is what answers for the region if its own tape is
    // not much shorter, with the length of its tape.
    //
    // A region deeper than `LONG_ASPECT` times its width, inside a group's
    // region, is not pruned: over a long beam nearly every object's
    // interval overlaps the nearest one's, so the pruned tape keeps most
    // of the group's (on 1000 spheres, a tile's whole beam kept 12.9k of
    // 13.5k ops), and the pass cost as much as evaluating it. It shares
    // the group's tape and lets the group answer; its short slices prune
    // from the group's slices.
    //
    // The region is placed beforehand (`Beam::place`), with its pruning
    // from `tape` where that was made with its sibling's.
    // long-fn: one node of the slice tree, placed, pruned and recursed
    // into; the recursion's state is the function's locals.
    fn node(
        &self,
        tr: &Scope<'_>,
        tape: &Tape,
        placed: Placed<'_>,
        above: Answer,
        depth: u32,
        st: &mut TileState,
    ) -> Option<Regional> {
        let Placed {
            range: t,
            region,
            held,
            pruned,
        } = placed;
        let above = match held {
            Some(h) if h.answer_len() < above.ops => Answer {
                evaluator: Arc::clone(h.answer()),
                ops: h.answer_len(),
            },
            _ => above,
        };
        let parent = self.parent.clone();
        let node = match held {
            Some(h) if self.long(tr, t) => {
                Regional::sharing(region, Arc::clone(h.shared_tape()), above, parent)
            }
            _ => {
                let source = held.map_or(tape, Regional::pruned_tape);
                // The pruning of this very region from this very tape,
                // where the group made it ahead of time: the same tape.
                let own = match (self.pre, pruned) {
                    (Some((r, from, pre)), _)
                        if r == region && std::ptr::from_ref(source) as usize == from =>
                    {
                        // Only tiles count: whether a group takes its
                        // row's tapes depends on which thread pruned the
                        // row first, and counters must not.
                        st.stats.pruned_ahead += u64::from(!self.is_group);
                        pre.clone()
                    }
                    // Pruned from `tape` itself (nothing held it).
                    (_, Some(own)) if held.is_none() => own,
                    _ => source
                        .prune(region, &mut st.prune.workspace)
                        .map(|p| p.tape),
                };
                let own = own.unwrap_or_else(|| source.clone());
                if own.len() * gain(above.evaluator.as_ref()) <= above.ops {
                    st.stats.pruned_ops_before += above.ops as u64;
                    st.stats.pruned_ops_after += own.len() as u64;
                    Regional::new(region, own, parent)
                } else {
                    Regional::delegating(region, own, above, parent)
                }
            }
        };
        // A group's tree goes on to slices as deep as it is wide, for its
        // tiles' slices to prune from.
        let aspect = if self.is_group { 1.0 } else { SLICE_ASPECT };
        if !tr.halves((self.xs, self.ys), t, depth, aspect) {
            return Some(node);
        }
        let below = Answer {
            evaluator: Arc::clone(node.answer()),
            ops: node.answer_len(),
        };
        let m = t.mid();
        let halves = [Interval::new(t.lo, m), Interval::new(m, t.hi)];
        let tape = node.pruned_tape();
        let placed = self.place_halves(tr, tape, halves, st);
        let children = halves
            .into_iter()
            .zip(placed)
            .filter_map(|(_, placed)| self.node(tr, tape, placed?, below.clone(), depth - 1, st))
            .collect();
        Some(node.with_children(children))
    }

    // The region of the beam over `t` and the smallest region of the
    // group's tree that holds it, if its tape is no longer than `tape`;
    // nothing pruned yet.
    fn place(&self, tr: &Scope<'_>, tape: &Tape, t: Interval) -> Option<Placed<'e>> {
        // A group's regions reach a little further along the rays: its
        // tiles' slices, whose ranges come from their own pixels, then
        // fit inside them despite rounding.
        let reach = if self.is_group { group_reach(t) } else { t };
        let region = tr.ctx.corner_region(&self.corners, reach)?;
        let held = self
            .group
            .filter(|g| box_within(&region, &g.region()))
            .map(|g| g.smallest_holding(&region))
            .filter(|h| h.pruned_tape().len() <= tape.len());
        Some(Placed {
            range: t,
            region,
            held,
            pruned: None,
        })
    }

    // Both halves placed, and where both prune from `tape` (no region of
    // the group's tree holds either), pruned in one pass over it (see
    // `Tape::prune_batch`): on 1000 spheres a region's two halves were
    // pruned one after the other from the same tape, each pass
    // dispatching every op again.
    fn place_halves(
        &self,
        tr: &Scope<'_>,
        tape: &Tape,
        halves: [Interval; 2],
        st: &mut TileState,
    ) -> [Option<Placed<'e>>; 2] {
        let mut placed = halves.map(|h| self.place(tr, tape, h));
        if let [Some(p0), Some(p1)] = &mut placed
            && p0.held.is_none()
            && p1.held.is_none()
        {
            let mut pruned = tape
                .prune_batch(&[p0.region, p1.region], usize::MAX, &mut st.prune.workspace)
                .into_iter()
                .map(|p| p.map(|p| p.tape));
            p0.pruned = pruned.next();
            p1.pruned = pruned.next();
        }
        placed
    }

    // Whether the beam over `t` is deeper than `LONG_ASPECT` times its
    // width, in a 3D scene (in a flat scene nothing along the rays
    // matters, and a tile's beam prunes to the few objects that cross its
    // narrow footprint).
    fn long(&self, tr: &Scope<'_>, t: Interval) -> bool {
        !tr.ctx.flat && t.width() > LONG_ASPECT * tr.beam_width(self.xs, self.ys, t)
    }
}

/// Regions of a tile's tree deeper than this many times their width share
/// their group's tape instead of pruning (see `Beam::node`).
const LONG_ASPECT: f64 = 6.0;

/// How much further along the rays than its own range, relative to it, a
/// group's region reaches (see `Beam::node`).
const GROUP_SLACK: f64 = 1e-6;

/// The range along the rays a group's region over `t` reaches (see
/// `Beam::node`).
pub(crate) fn group_reach(t: Interval) -> Interval {
    let slack = GROUP_SLACK * t.width();
    Interval::new(t.lo - slack, t.hi + slack)
}
