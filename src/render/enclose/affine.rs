//! The affine form of an object over a block, where its natural interval
//! straddles 0: reduced affine arithmetic (`eval::affine`) on the tape
//! that answers for the block's region, which overestimates far less than
//! intervals where a variable appears many times (quartics and sextics
//! with many nodes, expanded polynomials). Along a single ray's piece, the
//! second-order form in the ray parameter (`interval::quadratic`), which
//! also keeps the cancellation of an expanded polynomial's terms.

use std::sync::Arc;

use crate::eval::affine::{AffineEvaluator, quadratic_along};
use crate::eval::tape::Instr;
use crate::eval::tape::{Tape, with_workspace};
use crate::interval::Interval;
use crate::interval::affine::along_parameter;
use crate::interval::boxes::{IBox, box_within};
use crate::render::Enclosure;
use crate::render::context::stats::RenderStats;
use crate::render::context::{Context, FormTape};
use crate::render::enclose::proof::{self, SignBound};

/// Functions with more live ops than this get no affine form: unions of
/// many objects are min/max trees, where the form falls back to the
/// interval rule at every undecided `min` and only costs (an affine
/// evaluation costs about fifty interval ones, `ibeam bench enclosure`).
pub(crate) const AFFINE_MAX_OPS: usize = 4096;

/// Whole-function tapes for the affine form, one per object (None: too
/// long, or no function), for `choice`; empty where intervals only.
pub(crate) fn whole_tapes(ctx: &Context<'_>, choice: Enclosure) -> Arc<[Option<FormTape>]> {
    if choice == Enclosure::Interval {
        return Arc::new([]);
    }
    ctx.evals
        .iter()
        .map(|e| {
            let f = e.function()?;
            (f.live_count() <= AFFINE_MAX_OPS).then(|| {
                let tape = Arc::new(Tape::new(f));
                let along_pays = polynomial(&tape) && dependency_gain(&tape, ctx) >= ALONG_MIN_GAIN;
                FormTape { tape, along_pays }
            })
        })
        .collect()
}

/// How many times narrower than its intervals an object's affine forms
/// must be (the median over small boxes of the bounds,
/// [`dependency_gain`]) for `auto` to try its form along rays. The ray
/// form pays where intervals lose most to the dependency problem (the
/// expanded `(x−1)^10`: thousands of times); on quartics and sextics
/// (Kummer, Klein, orthocircle, tangle_cube: 1.5 to 3 times) its tries
/// dropped pieces that bisection would have dropped after a few more
/// interval evaluations, costing more than they saved (orthocircle and
/// tangle_cube 5% slower than intervals alone).
const ALONG_MIN_GAIN: f64 = 8.0;

/// The median, over 31 cubes a hundredth of the bounds' diagonal wide at
/// fixed pseudo-random places in the bounds, of the width of `tape`'s
/// interval over the width of its affine form (at least 1: the form is
/// intersected with the interval). Cubes where either is unbounded or
/// the form has no width count as no gain.
fn dependency_gain(tape: &Tape, ctx: &Context<'_>) -> f64 {
    let b = ctx.bounds;
    let side = 0.01 * ctx.diag;
    let mut rng = crate::ir::random::Rng::new(40);
    let mut gains: Vec<f64> = (0..31)
        .map(|_| {
            let cube: IBox = std::array::from_fn(|i| {
                let c = rng.range(b.min[i], b.max[i]);
                Interval::new(c - 0.5 * side, c + 0.5 * side)
            });
            let wide = with_workspace(|ws| tape.interval(cube, ws)).width();
            let narrow = tape.affine(cube).width();
            if wide.is_finite() && narrow > 0.0 {
                wide / narrow
            } else {
                1.0
            }
        })
        .collect();
    gains.sort_by(f64::total_cmp);
    gains[gains.len() / 2]
}

/// Whether every op of `tape` is a polynomial's (`+ - ·`, negation,
/// squares, whole powers) or a `min`/`max` of them. The second-order
/// form keeps these ops' cancellation, for a few hundred instructions
/// an op; every other op takes a linearisation or the interval rule,
/// which cost more (up to several thousand instructions for a
/// transcendental) and keep less: on the examples with such ops
/// (`shapes`: trigonometry and `mod`) its tries cost up to fifty
/// interval evaluations each and their drops saved less than that.
pub(crate) fn polynomial(tape: &Tape) -> bool {
    tape.code().iter().all(|i| {
        !matches!(
            i,
            Instr::Sqrt(..) | Instr::Unary(..) | Instr::Binary(..) | Instr::Powi(_, _, i32::MIN..0)
        )
    })
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
        _ => &ctx.affine_tapes.get(k)?.as_ref()?.tape,
    };
    (tape.len() <= AFFINE_MAX_OPS).then_some(tape)
}

/// Whether `auto` tries the form along a ray on object `k`: its whole
/// function is a [`polynomial`] short enough for the affine forms, whose
/// affine forms beat its intervals at least [`ALONG_MIN_GAIN`] times.
pub(crate) fn along_may_pay(ctx: &Context<'_>, k: usize) -> bool {
    ctx.affine_tapes
        .get(k)
        .and_then(Option::as_ref)
        .is_some_and(|t| t.along_pays)
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

/// The part of the piece `(a, b)` where an object may have surface, by
/// what its form along the line proved (`None`: no form, the whole
/// piece); an empty part (lower end above the upper) where it has none.
pub(crate) fn part_left(along: Option<AlongRay>, (a, b): (f64, f64)) -> (f64, f64) {
    match along {
        None => (a, b),
        Some(AlongRay::Free) => (f64::INFINITY, f64::NEG_INFINITY),
        Some(AlongRay::Within(pa, pb)) => (pa, pb),
    }
}

/// Object `k`'s second-order form along the line `o + t·d` (a single
/// ray, or a shadow segment: origin and direction anywhere in the boxes
/// `o` and `d`) over the piece `t ∈ (a, b)`, whose box is `bx`, a
/// quadratic in the line parameter's one noise
/// symbol ([`eval::affine::quadratic_along`]): where the quadratic stays
/// above its error, f is positive, so the piece shrinks to the hull of
/// where it does not. `None` where no tape pays (as [`affine_signs`]),
/// and under `auto` for an object on which it does not pay
/// ([`along_may_pay`]).
///
/// It replaced the first-order form along rays (`Affine<1>`): on the
/// expanded polynomial each power's Chebyshev remainder added to the
/// error, and the first-order form clipped only pieces about 0.003 wide;
/// a try of the second-order one costs about a third more and drops
/// pieces 30 times as wide (docs/performance.md).
///
/// [`eval::affine::quadratic_along`]: crate::eval::affine::quadratic_along
pub(crate) fn affine_along_line(
    ctx: &Context<'_>,
    k: usize,
    o: IBox,
    d: IBox,
    (a, b): (f64, f64),
    bx: IBox,
) -> Option<AlongRay> {
    if ctx.enclosure == Enclosure::Auto && !along_may_pay(ctx, k) {
        return None;
    }
    let tape = tape_for(ctx, k, &bx)?;
    let t = Interval::new(a, b);
    let v = quadratic_along(tape, o, d, t, bx);
    if proof::holds_no_surface(v.range) {
        return Some(AlongRay::Free);
    }
    let part = v
        .form
        .may_reach_zero()
        .and_then(|eps| along_parameter(t, eps));
    Some(part.map_or(AlongRay::Free, |p| AlongRay::Within(p.lo, p.hi)))
}
