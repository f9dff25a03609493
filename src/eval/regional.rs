//! An evaluator that answers with a tape pruned to a region (see
//! [`crate::eval::tape`] and [`crate::ir::prune`]) for points and boxes
//! inside that region, and with its parent everywhere else.
//!
//! A tape pruned by value gives the same bits as the whole function on its
//! region, so the choice is invisible in point values; intervals over boxes
//! inside the region come out tighter. The renderer's tapes keep only the
//! sign ([`crate::eval::tape::Keep::Signs`]): every region then agrees on
//! where the function is negative, zero or positive, but not on its value
//! off the surface, and a formula that combines a value with a derivative
//! takes both from [`Specialise::answering`]. Regions nest two ways:
//! - the parent is the evaluator the tape was pruned from (a tile's, whose
//!   parent is the whole function's), so an evaluation just outside a
//!   block's region still runs the tile's short tape, not the whole
//!   function;
//! - a region may hold sub-regions, each with a tape pruned from its own
//!   (the tracer cuts a tile's beam into slices along the rays), and an
//!   evaluation runs the tape of the smallest one that holds its box.
//!
//! A region whose tape is not much shorter than what answers above it
//! (native code runs several times faster per op than the interpreter)
//! keeps its tape only to prune its sub-regions from, and lets the
//! evaluator above it answer.

use std::sync::Arc;

use crate::eval::tape::Tape;
use crate::eval::taped::TapeEvaluator;
use crate::eval::{Bulk, Evaluator, Grad, IntervalGrad, Single, Specialise};
use crate::interval::Interval;
use crate::interval::boxes::{IBox, box_within, point_box};
use crate::ir::Function;

/// `tape` on `region` (or on the smallest sub-region holding a box),
/// `parent` elsewhere.
pub struct Regional {
    region: IBox,
    tape: Arc<TapeEvaluator>,
    // What evaluates boxes inside the region: the tape run as it is,
    // or, for a region that did not shrink enough, what answers above it.
    answer: Arc<dyn Evaluator>,
    // Whether `answer` is this region's own tape.
    own: bool,
    // Ops of the function `answer` evaluates.
    answer_len: usize,
    parent: Arc<dyn Evaluator>,
    // The parent again, typed, when it is a region of the same tree.
    parent_region: Option<Arc<Regional>>,
    children: Vec<Regional>,
}

/// What evaluates a region that lets another evaluator answer for it (one
/// exact on the region, usually its parent's), and that function's ops.
#[derive(Clone)]
pub struct Answer {
    /// The evaluator that answers.
    pub evaluator: Arc<dyn Evaluator>,
    /// Ops of the function it evaluates.
    pub ops: usize,
}

/// What a region's evaluator falls back on outside its region.
#[derive(Clone)]
pub enum Parent {
    /// The whole function's evaluator (or any evaluator not a region).
    Whole(Arc<dyn Evaluator>),
    /// A larger region of the same function.
    Region(Arc<Regional>),
}

impl Parent {
    /// The parent as an evaluator, and as a region when it is one.
    fn split(self) -> (Arc<dyn Evaluator>, Option<Arc<Regional>>) {
        match self {
            Parent::Whole(e) => (e, None),
            Parent::Region(r) => (Arc::clone(&r) as Arc<dyn Evaluator>, Some(r)),
        }
    }
}

impl Regional {
    /// `tape` (exact on `region`) with `parent` answering outside it.
    pub fn new(region: IBox, tape: Tape, parent: Parent) -> Regional {
        let (parent, parent_region) = parent.split();
        let tape = Arc::new(TapeEvaluator::new(tape));
        Regional {
            region,
            answer: Arc::clone(&tape) as Arc<dyn Evaluator>,
            own: true,
            answer_len: tape.tape().len(),
            tape,
            parent,
            parent_region,
            children: Vec::new(),
        }
    }

    /// A region that keeps `tape` only to prune from and lets `answer`
    /// (an evaluator exact on the region, usually the parent's, of a
    /// function of `answer_len` ops) evaluate.
    pub fn delegating(region: IBox, tape: Tape, answer: Answer, parent: Parent) -> Regional {
        let (parent, parent_region) = parent.split();
        let Answer {
            evaluator: answer,
            ops: answer_len,
        } = answer;
        Regional {
            region,
            tape: Arc::new(TapeEvaluator::new(tape)),
            answer,
            own: false,
            answer_len,
            parent,
            parent_region,
            children: Vec::new(),
        }
    }

    /// [`Regional::delegating`] with a tape another region already holds
    /// (exact on a region holding this one), shared rather than pruned
    /// again: for regions whose pruning would not pay.
    pub fn sharing(
        region: IBox,
        tape: Arc<TapeEvaluator>,
        answer: Answer,
        parent: Parent,
    ) -> Regional {
        let (parent, parent_region) = parent.split();
        let Answer {
            evaluator: answer,
            ops: answer_len,
        } = answer;
        Regional {
            region,
            tape,
            answer,
            own: false,
            answer_len,
            parent,
            parent_region,
            children: Vec::new(),
        }
    }

    /// The region this one was pruned from, when it is one (typed, so that
    /// pruning walks up a tree without asking an evaluator what it is).
    pub fn parent_region(&self) -> Option<&Arc<Regional>> {
        self.parent_region.as_ref()
    }

    /// The evaluator this region falls back on outside it.
    pub fn parent_evaluator(&self) -> &Arc<dyn Evaluator> {
        &self.parent
    }

    /// `out[i]` = F over `boxes[i]` on this region's own pruned tape, even
    /// where the region lets another evaluator answer: a batch over a
    /// short tape costs a fraction of one over the whole function, and is
    /// exact wherever the boxes lie in the region.
    pub fn own_interval_batch(&self, boxes: &[IBox], out: &mut [Interval]) {
        crate::eval::tape::with_workspace(|ws| self.pruned_tape().interval_batch(boxes, out, ws));
    }

    /// The same region with these sub-regions (each inside it, exact on
    /// its own region; their parents are never asked, as a box reaches a
    /// sub-region only through this one).
    pub fn with_children(mut self, children: Vec<Regional>) -> Regional {
        self.children = children;
        self
    }

    /// What answers inside the region (the own tape, or what answers
    /// above it).
    pub fn answer(&self) -> &Arc<dyn Evaluator> {
        &self.answer
    }

    /// Ops of the function that answers inside the region.
    pub fn answer_len(&self) -> usize {
        self.answer_len
    }

    /// Whether the region answers with its own tape.
    pub fn answers_itself(&self) -> bool {
        self.own
    }

    /// The region.
    pub fn region(&self) -> IBox {
        self.region
    }

    /// The pruned tape.
    pub fn pruned_tape(&self) -> &Tape {
        self.tape.tape()
    }

    /// The pruned tape as an evaluator, to share with a region inside
    /// this one (see [`Regional::sharing`]).
    pub fn shared_tape(&self) -> &Arc<TapeEvaluator> {
        &self.tape
    }

    /// The smallest region of the tree (this one or a sub-region, nested)
    /// that holds `b`; `b` must lie in this region.
    pub fn smallest_holding(&self, b: &IBox) -> &Regional {
        let mut node = self;
        'down: loop {
            for c in &node.children {
                if box_within(b, &c.region) {
                    node = c;
                    continue 'down;
                }
            }
            return node;
        }
    }

    /// The evaluator for a box: the smallest region's if the box lies in
    /// the region, else the parent.
    fn for_box(&self, b: &IBox) -> &dyn Evaluator {
        self.answer_for(b).unwrap_or(self.parent.as_ref())
    }

    /// What answers for every box in `hull` at once, if the hull lies in
    /// the region (a batch inside it then runs in one pass).
    fn answer_for(&self, hull: &IBox) -> Option<&dyn Evaluator> {
        box_within(hull, &self.region).then(|| self.smallest_holding(hull).answer.as_ref())
    }

    /// The evaluator for a point (see [`Self::for_box`]).
    fn for_point(&self, p: [f64; 3]) -> &dyn Evaluator {
        self.for_box(&point_box(p))
    }

    /// The evaluator for gradients and directional derivatives over a box:
    /// as [`Self::for_box`], except that a region whose answer interprets
    /// them (a long function's JIT leaves its derivative kinds to its
    /// whole tape) runs its own pruned tape, which is never longer. Over
    /// 1000 spheres at 256², the inclusion test's directional derivatives
    /// ran the whole 14k-op tape.
    fn for_derivatives(&self, b: &IBox) -> &dyn Evaluator {
        if !box_within(b, &self.region) {
            return self.parent.as_ref();
        }
        let node = self.smallest_holding(b);
        if node.own || node.answer.derivatives_native() {
            node.answer.as_ref()
        } else {
            node.tape.as_ref()
        }
    }
}

impl Single for Regional {
    fn point(&self, p: [f64; 3]) -> f64 {
        self.for_point(p).point(p)
    }

    fn point_grad(&self, p: [f64; 3]) -> Grad {
        self.for_derivatives(&point_box(p)).point_grad(p)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        self.for_box(&b).interval(b)
    }

    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        self.for_derivatives(&b).interval_grad(b)
    }

    fn interval_dir(&self, b: [Interval; 3], v: [Interval; 3]) -> [Interval; 2] {
        self.for_derivatives(&b).interval_dir(b, v)
    }
}

impl Bulk for Regional {
    /// One batch on what answers for the smallest region holding every
    /// point; point by point when the points leave the region. The same
    /// bits either way (pruning is exact).
    fn point_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        match point_hull(xs, ys, zs).and_then(|h| self.answer_for(&h)) {
            Some(answer) => answer.point_batch(xs, ys, zs, out),
            None => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = self.point([xs[i], ys[i], zs[i]]);
                }
            }
        }
    }

    /// One batch on what answers for derivatives over the smallest region
    /// holding every point; point by point when the points leave the
    /// region. Pruned by value, the same bits either way (pruning keeps a
    /// decided `min`/`max`'s winner, whose partials the node picks at every
    /// point of the region); pruned keeping signs, the region's tape may
    /// drop an operand that is positive there yet the smaller one, so off
    /// the surface the partials may differ from a point's own tape.
    fn point_grad_batch(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [Grad]) {
        match point_hull(xs, ys, zs).filter(|h| box_within(h, &self.region)) {
            Some(hull) => self
                .for_derivatives(&hull)
                .point_grad_batch(xs, ys, zs, out),
            None => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = self.point_grad([xs[i], ys[i], zs[i]]);
                }
            }
        }
    }

    /// One batch on what answers for the smallest region holding every
    /// box; box by box when the boxes leave the region.
    fn interval_batch(&self, boxes: &[[Interval; 3]], out: &mut [Interval]) {
        let proper = |b: &IBox| b.iter().all(|c| c.lo <= c.hi);
        let hull = boxes
            .iter()
            .all(proper)
            .then(|| {
                boxes
                    .iter()
                    .copied()
                    .reduce(crate::interval::boxes::box_hull)
            })
            .flatten();
        match hull.as_ref().and_then(|h| self.answer_for(h)) {
            Some(answer) => answer.interval_batch(boxes, out),
            None => {
                for (b, o) in boxes.iter().zip(out.iter_mut()) {
                    *o = self.interval(*b);
                }
            }
        }
    }
}

impl Specialise for Regional {
    /// The pruned function (exact on `Regional::region`).
    fn function(&self) -> Option<&Function> {
        Some(self.tape.tape().function())
    }

    fn tape(&self) -> Option<&Tape> {
        Some(self.tape.tape())
    }

    fn is_native(&self) -> bool {
        self.answer.is_native()
    }

    fn derivatives_native(&self) -> bool {
        !self.own && self.answer.derivatives_native()
    }

    fn answering(&self, b: &[Interval; 3]) -> Option<&dyn Evaluator> {
        let e = self.for_derivatives(b);
        Some(e.answering(b).unwrap_or(e))
    }
}

/// The box spanned by the points `(xs[i], ys[i], zs[i])`; `None` for no
/// points or where a coordinate is NaN (which would vanish from the hull:
/// such a point goes point by point, as `point` sends it to the parent).
fn point_hull(xs: &[f64], ys: &[f64], zs: &[f64]) -> Option<IBox> {
    let any_nan = xs.iter().chain(ys).chain(zs).any(|v| v.is_nan());
    if xs.is_empty() || any_nan {
        return None;
    }
    let span = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval::new(lo, hi)
    };
    Some([span(xs), span(ys), span(zs)]).filter(|h| h.iter().all(|c| c.lo <= c.hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::interp::Interpreter;
    use crate::ir::random::{Rng, random_function};

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    // Batches inside the region run the pruned tape in one pass, batches
    // across its edge go point by point; both give each point's bits, and
    // interval batches give each box's interval.
    #[test]
    fn batches_inside_and_across_the_region_give_single_call_results() {
        let region = [
            Interval::new(-0.5, 0.5),
            Interval::new(-0.25, 1.0),
            Interval::new(0.0, 0.75),
        ];
        let mut rng = Rng::new(9);
        let mut batched_inside = 0;
        for seed in 0..200 {
            let f = random_function(seed, 8);
            let whole = Tape::new(&f);
            let mut ws = crate::eval::tape::Workspace::default();
            let Some(p) = whole.prune(region, &mut ws) else {
                continue;
            };
            let r = Regional::new(region, p.tape, Parent::Whole(Arc::new(Interpreter::new(f))));
            for spread in [0.2, 2.0] {
                let pts: Vec<[f64; 3]> = (0..9)
                    .map(|_| {
                        std::array::from_fn(|c| {
                            region[c].mid() + rng.range(-spread, spread) * region[c].width() / 2.0
                        })
                    })
                    .collect();
                batched_inside +=
                    usize::from(pts.iter().all(|p| box_within(&point_box(*p), &region)));
                let cols: [Vec<f64>; 3] =
                    std::array::from_fn(|c| pts.iter().map(|p| p[c]).collect());
                let mut out = vec![0.0; pts.len()];
                r.point_batch(&cols[0], &cols[1], &cols[2], &mut out);
                for (p, v) in pts.iter().zip(&out) {
                    assert!(same(*v, r.point(*p)), "seed {seed} at {p:?}");
                }
                let boxes: Vec<IBox> = pts
                    .iter()
                    .map(|p| p.map(|c| Interval::new(c - 0.01, c + 0.01)))
                    .collect();
                let mut iv = vec![Interval::point(0.0); boxes.len()];
                r.interval_batch(&boxes, &mut iv);
                for (b, v) in boxes.iter().zip(&iv) {
                    let s = r.interval(*b);
                    assert!(
                        (v.is_empty() && s.is_empty()) || (same(v.lo, s.lo) && same(v.hi, s.hi)),
                        "seed {seed} over {b:?}: {v:?} against {s:?}"
                    );
                }
            }
        }
        assert!(batched_inside > 20, "{batched_inside} batches inside");
    }
}
