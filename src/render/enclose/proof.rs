//! What an interval evaluation proves, for every front-to-back search
//! (single rays and block sweeps, shadow segments and shadow beams, IAA's
//! pixel-area tests, the inclusion and monotonicity tests): one rule, in
//! one place.
//!
//! Partial domains make two readings of an enclosure unsound:
//! - An undefined piece (EMPTY) or one positive wherever f is defined holds
//!   no surface, but proves nothing about what follows it: f may be
//!   undefined at the piece's end and enter its domain already negative
//!   (the face of `sqrt(y) - 0.2` at y = 0 is such a domain edge). So no
//!   search carries "positive here" past a piece it rejected: positivity
//!   at a point is proven only by an enclosure of f at that point that is
//!   defined ([`outside_at`]), or by a monotonicity proof ending there.
//! - A derivative enclosure with an infinite (or NaN) bound proves no
//!   monotonicity: it is what the evaluators give at a domain edge
//!   (`sqrt`, `ln`, `asin`, `acos`, `pow`), at a pole and at a jump
//!   (`floor`, `mod`, `atan2`'s cut), where f need not be continuous.
//!
//! What remains assumed: a domain edge hidden by a `min` or `max` that
//! takes its other operand over a whole piece (the other operand's
//! derivative is then the only one computed) is not seen.

use crate::interval::Interval;

/// Whether f's enclosure over a piece proves it holds no surface: f is
/// undefined on all of it, or positive wherever it is defined.
pub(crate) fn holds_no_surface(f: Interval) -> bool {
    f.is_empty() || f.lo > 0.0
}

/// Whether f's enclosure at a point proves the point outside the solid:
/// f defined and positive there (EMPTY, undefined, proves nothing).
pub(crate) fn outside_at(f: Interval) -> bool {
    !f.is_empty() && f.lo > 0.0
}

/// Whether an enclosure is finite (not EMPTY, no infinite bound): the
/// condition for a derivative enclosure to say anything of f's change
/// along a piece (Newton steps, centred and mean-value forms).
pub(crate) fn bounded(d: Interval) -> bool {
    d.lo > f64::NEG_INFINITY && d.hi < f64::INFINITY
}

/// Whether a derivative enclosure proves f strictly increasing: a
/// positive lower bound and a finite upper one.
pub(crate) fn increasing(d: Interval) -> bool {
    d.lo > 0.0 && d.hi < f64::INFINITY
}

/// Whether a derivative enclosure proves f strictly decreasing.
pub(crate) fn decreasing(d: Interval) -> bool {
    d.hi < 0.0 && d.lo > f64::NEG_INFINITY
}

/// Whether a derivative enclosure proves f non-increasing.
pub(crate) fn non_increasing(d: Interval) -> bool {
    d.hi <= 0.0 && d.lo > f64::NEG_INFINITY
}

/// What an enclosure built from several tapes proves: the signs of f
/// over a box, and nothing of its values. Sign-pruned tapes
/// (`eval::tape::Keep::Signs`) agree with the whole function on where it
/// is negative, zero or positive, not on its value off the surface: the
/// meet of two such tapes' intervals, or the minimum over objects of each
/// one's own tape, bounds signs only, and this type keeps it at that.
#[derive(Copy, Clone, Debug)]
pub(crate) struct SignBound {
    lo: f64,
    hi: f64,
}

impl SignBound {
    /// No object over the box (every one undefined there): positive.
    pub(crate) const NONE: SignBound = SignBound {
        lo: f64::INFINITY,
        hi: f64::INFINITY,
    };

    /// The signs an enclosure of f proves (EMPTY: none either way).
    pub(crate) fn of(f: Interval) -> SignBound {
        SignBound { lo: f.lo, hi: f.hi }
    }

    /// The signs of the smaller of two functions.
    pub(crate) fn min(self, other: SignBound) -> SignBound {
        SignBound {
            lo: self.lo.min(other.lo),
            hi: self.hi.min(other.hi),
        }
    }

    /// The signs both bounds prove (a meet of two sound bounds).
    pub(crate) fn meet(self, other: SignBound) -> SignBound {
        let (lo, hi) = (self.lo.max(other.lo), self.hi.min(other.hi));
        if lo <= hi { SignBound { lo, hi } } else { self }
    }

    /// f > 0 wherever it is defined on the box.
    pub(crate) fn positive(self) -> bool {
        self.lo > 0.0
    }

    /// f < 0 wherever it is defined on the box.
    pub(crate) fn negative(self) -> bool {
        self.hi < 0.0
    }

    /// Whether a bound that may hold both signs reaches further below zero
    /// than above: a cost heuristic (how deep a bracket is looked for),
    /// which may answer differently on different tapes; no proof reads it.
    pub(crate) fn leans_negative(self) -> bool {
        self.lo < 0.0 && self.hi < -self.lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::Single;
    use crate::eval::interp::Interpreter;
    use crate::ir::{Builder, UnaryOp, Var};

    // sqrt(y) - 0.2 over a box straddling its domain edge y = 0: its
    // derivative along y is unbounded there, so no monotonicity is proven,
    // though f jumps from undefined to -0.2; away from the edge it is.
    #[test]
    fn a_domain_edge_proves_no_monotonicity() {
        let mut b = Builder::new();
        let y = b.var(Var::Y);
        let s = b.unary(UnaryOp::Sqrt, y);
        let c = b.constant(0.2);
        let f = b.binary(crate::ir::BinaryOp::Sub, s, c);
        let e = Interpreter::new(b.finish(f));
        let up = [
            Interval::point(0.0),
            Interval::point(1.0),
            Interval::point(0.0),
        ];
        let across = [
            Interval::point(0.0),
            Interval::new(-0.5, 0.5),
            Interval::point(0.0),
        ];
        let [v, d] = e.interval_dir(across, up);
        assert!(v.lo <= -0.2 && !increasing(d), "{v:?} {d:?}");
        let away = [
            Interval::point(0.0),
            Interval::new(0.5, 1.0),
            Interval::point(0.0),
        ];
        assert!(increasing(e.interval_dir(away, up)[1]));
        // Undefined below the edge: no surface there, and not outside.
        let below = [
            Interval::point(0.0),
            Interval::point(-0.1),
            Interval::point(0.0),
        ];
        let fb = e.interval(below);
        assert!(holds_no_surface(fb) && !outside_at(fb));
    }

    #[test]
    fn infinite_or_empty_bounds_prove_nothing() {
        let inf = f64::INFINITY;
        for d in [Interval::new(1.0, inf), Interval::EMPTY, Interval::ENTIRE] {
            assert!(!increasing(d), "{d:?}");
        }
        for d in [Interval::new(-inf, -1.0), Interval::EMPTY] {
            assert!(!decreasing(d) && !non_increasing(d), "{d:?}");
        }
        assert!(increasing(Interval::new(1.0, 2.0)));
        assert!(decreasing(Interval::new(-2.0, -1.0)));
        assert!(non_increasing(Interval::new(-2.0, 0.0)));
        assert!(!outside_at(Interval::EMPTY) && outside_at(Interval::point(1e-300)));
    }
}
