//! What the per-op rules of `ir::affine_rules` ask of a form: the
//! first-order [`Affine`] forms (over a box, or along a ray) and the
//! second-order [`Quadratic`] form along a ray share those rules, so each
//! op's domain edges, linearisations and interval fallback are written
//! once.
//!
//! # Contract
//! A form encloses a set of values (each point of its domain gives one);
//! every method returns a form that encloses the exact result of the op
//! on those values, with every rounding error of its coefficients inside
//! its error term. A form that overflowed is the form's `UNBOUNDED`,
//! which encloses everything.
//!
//! [`Quadratic`]: super::quadratic::Quadratic

use super::Interval;
use super::affine::Affine;

/// A form the rules of `ir::affine_rules` run on (see the module doc).
pub trait Form: Copy + std::fmt::Debug + PartialEq {
    /// The form that encloses every value.
    const UNBOUNDED: Self;
    /// Whether every op's interval is met with its form's range, or only
    /// where a rule reads its operands' ranges, and at the root (see
    /// `ir::affine_rules`, "The value each op carries").
    const MEET_EACH_OP: bool = true;
    /// The exact constant `v` (UNBOUNDED where not finite).
    fn constant(v: f64) -> Self;
    /// The interval `i` as a constant plus error (UNBOUNDED where it is
    /// unbounded or EMPTY).
    fn from_interval(i: Interval) -> Self;
    /// Whether every part is finite (otherwise the form says nothing).
    fn is_bounded(&self) -> bool;
    /// `-self`.
    fn neg(&self) -> Self;
    /// `self + o`.
    fn add(&self, o: &Self) -> Self;
    /// `self - o`.
    fn sub(&self, o: &Self) -> Self;
    /// `self · o`.
    fn mul(&self, o: &Self) -> Self;
    /// `self²`.
    fn square(&self) -> Self;
    /// `alpha·self + beta ± delta` (a linearisation of an op whose rest
    /// over the operand's range is within `beta ± delta`).
    fn linear(&self, alpha: f64, beta: f64, delta: f64) -> Self;
    /// `selfⁿ` for `n ≥ 3` by products, where the form keeps more of a
    /// power that way than a linearisation over its range does; `None`
    /// where the linearisation is the better rule.
    fn power(&self, n: i32) -> Option<Self>;
    /// [`Form::power`], the same form, taking the squares `self²`,
    /// `self⁴`, … from `squares` as far as it holds them and adding those
    /// it computes: the powers of one operand (an expanded polynomial's)
    /// then share their squares.
    fn power_sharing(&self, n: i32, _squares: &mut Vec<Self>) -> Option<Self> {
        self.power(n)
    }
    /// The centre (the value where every noise symbol is 0).
    fn centre(&self) -> f64;
    /// An upper bound of the distance from the centre that the noise
    /// symbols reach, the error term left out.
    fn spread(&self) -> f64;
    /// The error term.
    fn error(&self) -> f64;
    /// The form with its error term replaced by `e` (at least the old).
    fn with_error(self, e: f64) -> Self;
    /// The interval the form ranges over, rounded outward, for a bounded
    /// form whose [`Form::spread`] is `spread`.
    fn range_within(&self, spread: f64) -> Interval;
}

impl<const N: usize> Form for Affine<N> {
    const UNBOUNDED: Self = Affine::UNBOUNDED;

    fn constant(v: f64) -> Self {
        Affine::constant(v)
    }
    fn from_interval(i: Interval) -> Self {
        Affine::from_interval(i)
    }
    fn is_bounded(&self) -> bool {
        Affine::is_bounded(self)
    }
    fn neg(&self) -> Self {
        Affine::neg(self)
    }
    fn add(&self, o: &Self) -> Self {
        Affine::add(self, o)
    }
    fn sub(&self, o: &Self) -> Self {
        Affine::sub(self, o)
    }
    fn mul(&self, o: &Self) -> Self {
        Affine::mul(self, o)
    }
    fn square(&self) -> Self {
        Affine::square(self)
    }
    fn linear(&self, alpha: f64, beta: f64, delta: f64) -> Self {
        Affine::linear(self, alpha, beta, delta)
    }
    // A product of first-order forms adds each step's quadratic rest to
    // the error: the Chebyshev linearisation over the range is tighter.
    fn power(&self, _n: i32) -> Option<Self> {
        None
    }
    fn centre(&self) -> f64 {
        self.c
    }
    fn spread(&self) -> f64 {
        self.reach()
    }
    fn error(&self) -> f64 {
        self.e
    }
    fn with_error(self, e: f64) -> Self {
        Affine { e, ..self }
    }
    fn range_within(&self, spread: f64) -> Interval {
        Affine::range_within(self, spread)
    }
}
