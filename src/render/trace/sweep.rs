//! The one front-to-back sweep driver every search along a ray, a beam or
//! a shadow segment runs: a stack of pieces of the parameter, nearest
//! popped first; a count of the pieces visited, which each search reads
//! as its budget; and the re-specialise hook, which sweeps a piece again
//! on evaluators pruned to it. What a search does with a piece (its
//! tests, what it proves, when it stops) is its [`Search`] policy.
//!
//! Every search keeps the rule of `enclose::proof`: a piece the interval
//! test rejects, or on which f is undefined, proves nothing about the
//! pieces behind it; a policy carries a fact forward only from a piece it
//! proved it on.

use crate::render::context::EvalSet;
use crate::render::prune::scope::Scope;

/// A piece `(a, b)` of the swept parameter, `a < b`.
pub(crate) type Piece = (f64, f64);

/// What a search decided about one piece.
pub(crate) enum Visit<R> {
    /// Nothing to find on the piece: go on behind it.
    Drop,
    /// The search ends with this result.
    Stop(R),
    /// Sweep the piece's halves, nearer first.
    Halve,
    /// Sweep these parts of the piece instead, the first nearer (either
    /// may be absent).
    Parts(Option<Piece>, Option<Piece>),
    /// Sweep the piece again, with its sub-pieces, on evaluators
    /// specialised to it.
    Specialise(EvalSet),
}

/// Where a sweep stands, shared by its nested sweeps.
#[derive(Clone, Debug)]
pub(crate) struct SweepState {
    /// Pieces visited so far, nested sweeps' included: the budget every
    /// search reads.
    pub pieces: usize,
    /// Width of the piece the current evaluators were specialised to
    /// (infinite for the unspecialised ones); a search may narrow it to
    /// look again only once pieces are narrower.
    pub specialised_width: f64,
}

impl SweepState {
    /// A sweep that has visited nothing, on unspecialised evaluators.
    pub(crate) fn new() -> SweepState {
        SweepState {
            pieces: 0,
            specialised_width: f64::INFINITY,
        }
    }
}

/// One search's policy: what it tests on each piece and what it finds.
pub(crate) trait Search {
    /// What the search finds (a hit, a blocked segment, a candidate).
    type Found;

    /// Decides about `piece`, with `scope`'s evaluators; `at.pieces`
    /// already counts it.
    fn visit(&mut self, scope: &Scope<'_>, piece: Piece, at: &mut SweepState)
    -> Visit<Self::Found>;
}

/// Sweeps `stack` (nearest piece last) with `search`, front to back, until
/// it stops; `None` when every piece was dropped.
pub(crate) fn sweep<S: Search>(
    scope: &Scope<'_>,
    mut stack: Vec<Piece>,
    search: &mut S,
    at: &mut SweepState,
) -> Option<S::Found> {
    // The width this level's evaluators were specialised to, which the
    // search may narrow while it sweeps this level, and which a nested
    // level's own does not change.
    let width = at.specialised_width;
    let found = loop {
        let Some((a, b)) = stack.pop() else {
            break None;
        };
        at.pieces += 1;
        match search.visit(scope, (a, b), at) {
            Visit::Drop => {}
            Visit::Stop(r) => break Some(r),
            Visit::Halve => {
                let m = 0.5 * (a + b);
                stack.push((m, b));
                stack.push((a, m));
            }
            Visit::Parts(front, back) => {
                stack.extend(back);
                stack.extend(front);
            }
            Visit::Specialise(set) => {
                let local = scope.with_evals(&set);
                let here = at.specialised_width;
                at.specialised_width = b - a;
                let found = sweep(&local, vec![(a, b)], search, at);
                at.specialised_width = here;
                if found.is_some() {
                    break found;
                }
            }
        }
    };
    at.specialised_width = width;
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    // Records the pieces it sees; halves down to `min_w`, stops at the
    // first piece holding `target` that is that narrow.
    struct Find {
        target: f64,
        min_w: f64,
        seen: Vec<Piece>,
    }

    impl Search for Find {
        type Found = Piece;
        fn visit(&mut self, _: &Scope<'_>, (a, b): Piece, _: &mut SweepState) -> Visit<Piece> {
            self.seen.push((a, b));
            if !(a <= self.target && self.target <= b) {
                Visit::Drop
            } else if b - a <= self.min_w {
                Visit::Stop((a, b))
            } else {
                Visit::Halve
            }
        }
    }

    #[test]
    fn pieces_are_visited_front_to_back_and_counted() {
        let scope = Scope::for_tests(&crate::scene::Camera::default(), 8);
        let mut find = Find {
            target: 0.3,
            min_w: 0.25,
            seen: Vec::new(),
        };
        let mut at = SweepState::new();
        let found = sweep(&scope, vec![(1.0, 2.0), (0.0, 1.0)], &mut find, &mut at);
        assert_eq!(found, Some((0.25, 0.5)));
        assert_eq!(
            find.seen,
            [(0.0, 1.0), (0.0, 0.5), (0.0, 0.25), (0.25, 0.5)]
        );
        assert_eq!(at.pieces, 4);
        // A target nowhere drops every piece, the second start included.
        find.target = 5.0;
        find.seen.clear();
        let mut at = SweepState::new();
        assert_eq!(
            sweep(&scope, vec![(1.0, 2.0), (0.0, 1.0)], &mut find, &mut at),
            None
        );
        assert_eq!(find.seen, [(0.0, 1.0), (1.0, 2.0)]);
    }

    // Splits every piece into explicit parts, back part absent past 0.5.
    struct Parts(Vec<Piece>);

    impl Search for Parts {
        type Found = ();
        fn visit(&mut self, _: &Scope<'_>, (a, b): Piece, _: &mut SweepState) -> Visit<()> {
            self.0.push((a, b));
            if b - a < 0.2 {
                return Visit::Drop;
            }
            let m = 0.5 * (a + b);
            Visit::Parts(Some((a, m)), (m < 0.5).then_some((m, b)))
        }
    }

    #[test]
    fn parts_go_nearer_first_and_may_be_absent() {
        let scope = Scope::for_tests(&crate::scene::Camera::default(), 8);
        let mut parts = Parts(Vec::new());
        let mut at = SweepState::new();
        assert_eq!(sweep(&scope, vec![(0.0, 1.0)], &mut parts, &mut at), None);
        assert_eq!(
            parts.0,
            [
                (0.0, 1.0),
                (0.0, 0.5),
                (0.0, 0.25),
                (0.0, 0.125),
                (0.125, 0.25),
                (0.25, 0.5),
                (0.25, 0.375),
                (0.375, 0.5)
            ]
        );
    }
}
