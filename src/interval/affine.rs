//! Reduced affine forms over a box: `c + kx·εx + ky·εy + kz·εz ± e`, with
//! each noise symbol ε in [-1, 1] standing for one coordinate of the box
//! (`x = mx + rx·εx`, see [`Affine::var`]) and `e ≥ 0` bounding everything
//! else: the nonlinear remainders, every rounding error of the
//! coefficients, and the rounding of the point op the form encloses.
//!
//! # Guarantee
//! A form built from the box `B` by these ops encloses its value at every
//! point `p` of `B`: with `ε(p)` the point's noise symbols, the value lies
//! in `c + k·ε(p) ± e`. Each coefficient is computed in round-to-nearest
//! and its rounding error, bounded by [`rounding`], is added to `e`: an
//! op's error terms are summed in round-to-nearest and the sum bounded
//! upward once (`ErrSum::total`); nothing here relies on a rounding
//! mode. A form whose centre or coefficients overflow becomes
//! [`Affine::UNBOUNDED`] (`e = +inf`), which encloses everything.
//!
//! The nonlinear rules that need an op's shape (Chebyshev and mean-value
//! linearisations) live in `ir::affine_rules`; they hand this module a
//! slope, an offset and an error bound computed with outward-rounded
//! intervals ([`Affine::linear`]).

use super::{FLOOR_STEP, Interval, down, mx, up, up_sum};

/// `c + Σ k_i·ε_i ± e` (see the module doc).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Affine<const N: usize = 3> {
    /// The centre.
    pub c: f64,
    /// The coefficients of the noise symbols: x, y and z over a box, or
    /// the ray parameter along a ray ([`Affine::along`]).
    pub k: [f64; N],
    /// The accumulated error, `≥ 0` (+inf: unbounded).
    pub e: f64,
}

/// `2⁻⁵²`: `|z|·STEP` is at least one ulp of a normal `z`.
const STEP: f64 = f64::EPSILON;

/// An upper bound of the error of a correctly rounded `+ - *` whose
/// result is `z`: at least half an ulp of `z` (`|z|·2⁻⁵²` is one ulp or
/// more where it is at least 2⁻⁵¹¹, and 2⁻⁵¹¹ covers every `z` below
/// 2⁻⁴⁵⁹, subnormals and underflow to 0 included; see `interval::up`).
/// +inf for an infinite `z` (an overflow), NaN for a NaN one.
#[inline]
pub fn rounding(z: f64) -> f64 {
    mx(z.abs() * STEP, FLOOR_STEP)
}

/// An upper bound of the exact `x·y` (any signs).
#[inline]
pub(crate) fn mul_up(x: f64, y: f64) -> f64 {
    up(x * y)
}

/// Error terms summed in round-to-nearest, bounded once at the end
/// ([`ErrSum::total`]): rounding each partial sum upward made every op a
/// chain of dependent roundings (most of an affine evaluation's time).
#[derive(Copy, Clone, Debug, Default)]
pub(crate) struct ErrSum {
    sum: f64,
    terms: u32,
}

impl ErrSum {
    /// Adds the non-negative upper bound `v`.
    #[inline]
    pub(crate) fn add(&mut self, v: f64) {
        self.sum += v;
        self.terms += 1;
    }

    /// Returns the rounded result `z` of a `+ - *`, adding its error.
    #[inline]
    pub(crate) fn rounded(&mut self, z: f64) -> f64 {
        self.add(rounding(z));
        z
    }

    /// An upper bound of the exact sum of the terms. Why it is sound:
    /// the terms are not negative, so each of the `n - 1` additions
    /// rounds a partial sum of the exact terms by a factor `1 + δ`, `|δ|
    /// ≤ 2⁻⁵³`, never underflowing (a sum of non-negative floats below
    /// 2⁻¹⁰²² is exact); the computed sum is then at least the exact one
    /// times `(1 - 2⁻⁵³)^(n-1)`, and the exact one at most the computed
    /// one times `1 + n·2⁻⁵²` (for n far below 2⁵¹), a product [`up`]
    /// rounds upward. NaN and +inf stay.
    #[inline]
    pub(crate) fn total(&self) -> f64 {
        // One term is its own exact sum.
        if self.terms <= 1 {
            return self.sum;
        }
        up(self.sum * (1.0 + f64::from(self.terms) * STEP))
    }
}

impl<const N: usize> Affine<N> {
    /// The form that encloses every value: no centre, unbounded error.
    pub const UNBOUNDED: Affine<N> = Affine {
        c: 0.0,
        k: [0.0; N],
        e: f64::INFINITY,
    };

    /// The exact constant `v` (UNBOUNDED for a value that is not finite).
    pub fn constant(v: f64) -> Affine<N> {
        if !v.is_finite() {
            return Affine::UNBOUNDED;
        }
        Affine {
            c: v,
            k: [0.0; N],
            e: 0.0,
        }
    }

    /// Coordinate `axis` of the box whose side on that axis is `side`:
    /// `m + r·ε` with `m` the side's midpoint and `r` an upper bound of its
    /// distance to either end, so the form covers the side whatever the
    /// rounding. UNBOUNDED for a side that is not finite (or EMPTY).
    pub fn var(side: Interval, axis: usize) -> Affine<N> {
        let (m, r) = centre_radius(side);
        if !(m.is_finite() && r.is_finite()) {
            return Affine::UNBOUNDED;
        }
        let mut k = [0.0; N];
        k[axis] = r;
        Affine { c: m, k, e: 0.0 }
    }

    /// The interval `i` as a form of pure error: its midpoint ± an upper
    /// bound of its radius (UNBOUNDED for an unbounded or EMPTY `i`).
    pub fn from_interval(i: Interval) -> Affine<N> {
        let (m, e) = centre_radius(i);
        if !(m.is_finite() && e.is_finite()) {
            return Affine::UNBOUNDED;
        }
        Affine {
            c: m,
            k: [0.0; N],
            e,
        }
    }

    /// Whether every part is finite (otherwise the form says nothing).
    pub fn is_bounded(&self) -> bool {
        self.c.is_finite() && self.k.iter().all(|k| k.is_finite()) && self.e.is_finite()
    }

    /// UNBOUNDED where a part overflowed or went NaN, else the form.
    fn checked(self) -> Affine<N> {
        if self.is_bounded() {
            self
        } else {
            Affine::UNBOUNDED
        }
    }

    /// An upper bound of `Σ|k_i|`, the reach of the noise symbols.
    pub fn reach(&self) -> f64 {
        let mut r = ErrSum::default();
        for k in self.k {
            r.add(k.abs());
        }
        r.total()
    }

    /// An upper bound of the form's radius, `Σ|k_i| + e`.
    pub fn radius(&self) -> f64 {
        up_sum(self.reach() + self.e)
    }

    /// The interval the form ranges over, rounded outward (the whole line
    /// for an unbounded form).
    pub fn range(&self) -> Interval {
        if !self.is_bounded() {
            return Interval::ENTIRE;
        }
        self.range_within(self.reach())
    }

    /// [`Affine::range`] of a bounded form whose [`Affine::reach`] is
    /// `reach` (or any upper bound of it).
    pub fn range_within(&self, reach: f64) -> Interval {
        let r = up_sum(reach + self.e);
        let (lo, hi) = (-up_sum(r - self.c), up_sum(self.c + r));
        if lo.is_nan() || hi.is_nan() {
            return Interval::ENTIRE;
        }
        Interval::new(lo, hi)
    }

    /// `-self` (exact).
    pub fn neg(&self) -> Affine<N> {
        Affine {
            c: -self.c,
            k: self.k.map(|k| -k),
            e: self.e,
        }
    }

    /// `self + o`.
    pub fn add(&self, o: &Affine<N>) -> Affine<N> {
        let mut err = ErrSum::default();
        err.add(self.e);
        err.add(o.e);
        let c = err.rounded(self.c + o.c);
        let k = std::array::from_fn(|i| err.rounded(self.k[i] + o.k[i]));
        Affine {
            c,
            k,
            e: err.total(),
        }
        .checked()
    }

    /// `self - o`.
    pub fn sub(&self, o: &Affine<N>) -> Affine<N> {
        self.add(&o.neg())
    }

    /// `alpha·self + beta ± delta`, with `delta ≥ 0` an upper bound of
    /// whatever the caller's linearisation leaves out.
    pub fn linear(&self, alpha: f64, beta: f64, delta: f64) -> Affine<N> {
        let mut err = ErrSum::default();
        err.add(delta);
        err.add(mul_up(alpha.abs(), self.e));
        let ac = err.rounded(alpha * self.c);
        let c = err.rounded(ac + beta);
        let k = self.k.map(|k| err.rounded(alpha * k));
        Affine {
            c,
            k,
            e: err.total(),
        }
        .checked()
    }

    /// `self · o`: the linear part `a0·b0 + a0·Σb_i ε_i + b0·Σa_i ε_i`,
    /// and the quadratic rest bounded per term: `Σ a_i b_i ε_i²` (in
    /// `[min(0, a_i b_i), max(0, a_i b_i)]` each), `Σ_{i<j} (a_i b_j +
    /// a_j b_i) ε_i ε_j`, and the products with the error terms, then
    /// centred: its midpoint joins the centre, its radius the error.
    pub fn mul(&self, o: &Affine<N>) -> Affine<N> {
        let (a, b) = (self, o);
        let mut err = ErrSum::default();
        // The error terms times the other form's centre.
        err.add(mul_up(a.c.abs(), b.e));
        err.add(mul_up(b.c.abs(), a.e));
        let c0 = err.rounded(a.c * b.c);
        let k = std::array::from_fn(|i| {
            let l = err.rounded(a.c * b.k[i]);
            let r = err.rounded(b.c * a.k[i]);
            err.rounded(l + r)
        });
        // The quadratic rest lies in [-neg, pos]; both are upper bounds.
        let (mut neg, mut pos) = (ErrSum::default(), ErrSum::default());
        for i in 0..N {
            let d = a.k[i] * b.k[i];
            if d > 0.0 {
                pos.add(mul_up(a.k[i], b.k[i]));
            } else if d < 0.0 {
                neg.add(mul_up(-a.k[i], b.k[i]));
            }
        }
        let mut cross = ErrSum::default();
        for i in 0..N {
            for j in i + 1..N {
                let s_up = up_sum(mul_up(a.k[i], b.k[j]) + mul_up(a.k[j], b.k[i]));
                let s_dn = up_sum(mul_up(-a.k[i], b.k[j]) + mul_up(-a.k[j], b.k[i]));
                cross.add(mx(s_up, s_dn));
            }
        }
        cross.add(mul_up(a.reach(), b.e));
        cross.add(mul_up(b.reach(), a.e));
        cross.add(mul_up(a.e, b.e));
        let cross = cross.total();
        neg.add(cross);
        pos.add(cross);
        Affine::centred(c0, k, err, [neg.total(), pos.total()]).checked()
    }

    /// `self²`: as [`Affine::mul`] with itself, where the quadratic rest
    /// `(Σ k_i ε_i ± e)²` lies in `[0, (Σ|k_i| + e)²]` (the same error
    /// symbol on both sides: a square is never negative).
    pub fn square(&self) -> Affine<N> {
        let mut err = ErrSum::default();
        err.add(mul_up(2.0 * self.c.abs(), self.e));
        let c0 = err.rounded(self.c * self.c);
        let k = self.k.map(|k| err.rounded(2.0 * self.c * k));
        let r = self.radius();
        Affine::centred(c0, k, err, [0.0, mul_up(r, r)]).checked()
    }

    /// `c0 + k·ε` plus a rest in `[-neg, pos]`: the rest's midpoint joins
    /// the centre and its radius (rounded up) the error.
    fn centred(c0: f64, k: [f64; N], mut err: ErrSum, [neg, pos]: [f64; 2]) -> Affine<N> {
        let m = 0.5 * (pos - neg);
        // Distances from m to either end of the rest, rounded up.
        err.add(mx(up_sum(pos - m), up_sum(m + neg)));
        let c = err.rounded(c0 + m);
        Affine {
            c,
            k,
            e: err.total(),
        }
    }

    /// The form with `slack` added to its error (the rounding of the point
    /// op it encloses, see `ir::affine_rules`).
    pub fn widened(&self, slack: f64) -> Affine<N> {
        Affine {
            e: up_sum(self.e + slack),
            ..*self
        }
        .checked()
    }
}

impl Affine<1> {
    /// Coordinate `o + d·t` of a ray, `t` over the range `t` and the
    /// ray's origin and direction coordinates anywhere in the intervals
    /// `o` and `d` (a pixel's ray is itself an enclosure), in one noise
    /// symbol for the ray parameter: `t = m + r·ε` as in [`Affine::var`],
    /// so the coordinate is `(o_m + d_m·m) + (d_m·r)·ε`, with `o_m`, `d_m`
    /// the midpoints, plus an error for the rounding of those ops and for
    /// `o` and `d` away from their midpoints (`r_o + r_d·|t|`). A ray's
    /// coordinates stay tied to each other this way, where a box's three
    /// symbols take them as independent. UNBOUNDED where not finite.
    pub fn along(o: Interval, d: Interval, t: Interval) -> Affine<1> {
        let ((om, or), (dm, dr), (m, r)) = (centre_radius(o), centre_radius(d), centre_radius(t));
        let mut err = ErrSum::default();
        err.add(or);
        err.add(mul_up(dr, up_sum(m.abs() + r)));
        let dtm = err.rounded(dm * m);
        let c = err.rounded(om + dtm);
        let k = err.rounded(dm * r);
        Affine {
            c,
            k: [k],
            e: err.total(),
        }
        .checked()
    }

    /// The part of `[-1, 1]` where the form may be 0 or below: the values
    /// of the noise symbol outside it give `c + k·ε - e > 0`, so f is
    /// positive there (where defined). Bounds rounded outward; `None`
    /// where the form is positive everywhere, the whole range where it
    /// is unbounded.
    pub fn may_reach_zero(&self) -> Option<Interval> {
        let whole = Interval::new(-1.0, 1.0);
        if !self.is_bounded() {
            return Some(whole);
        }
        let k = self.k[0];
        // c + k·ε ≤ e, i.e. k·ε ≤ e - c, which is at most `hi`.
        let hi = up_sum(self.e - self.c);
        let part = if k > 0.0 {
            Interval::new(-1.0, up(hi / k))
        } else if k < 0.0 {
            Interval::new(down(hi / k), 1.0)
        } else if hi >= 0.0 {
            whole
        } else {
            return None;
        };
        meet(part, whole)
    }
}

/// The parameters `m + r·ε` for `ε` in `eps`, `m` and `r` as
/// [`Affine::along`] takes them from the range `t`, rounded outward and
/// kept within `t`: the part of `t` where [`Affine::may_reach_zero`]'s
/// noise values lie.
pub fn along_parameter(t: Interval, eps: Interval) -> Option<Interval> {
    let (m, r) = centre_radius(t);
    meet(Interval::point(m).add(Interval::point(r).mul(eps)), t)
}

/// An interval's midpoint `m` and an upper bound `r` of its distance to
/// either end, so that `m + r·[-1, 1]` covers it whatever the rounding.
pub fn centre_radius(i: Interval) -> (f64, f64) {
    let m = i.mid();
    (m, mx(up_sum(i.hi - m), up_sum(m - i.lo)))
}

/// An upper bound of `ulps` ulps of every value of magnitude at most `m`
/// (`m·2⁻⁵²·ulps`, at least 2⁻⁵¹¹; see [`rounding`]).
pub fn ulps_of(m: f64, ulps: u32) -> f64 {
    mul_up(rounding(m), f64::from(ulps))
}

/// `[max(a.lo, b.lo), min(a.hi, b.hi)]`: the intersection of two
/// enclosures of the same values, or `None` where they do not meet (then
/// there is no value to enclose).
pub fn meet(a: Interval, b: Interval) -> Option<Interval> {
    if a.is_empty() || b.is_empty() {
        return None;
    }
    let (lo, hi) = (a.lo.max(b.lo), a.hi.min(b.hi));
    (lo <= hi).then_some(Interval::new(lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_of_a_variable_enclose_its_square() {
        let x = Affine::<3>::var(Interval::new(0.9, 1.1), 0);
        let s = x.square().range();
        let m = x.mul(&x).range();
        for v in [0.9f64, 1.0, 1.1] {
            assert!(s.contains(v * v) && m.contains(v * v));
        }
        // x² - 2x over [0.9, 1.1] is within 0.01 of -1: no dependency.
        let two_x = x.linear(2.0, 0.0, 0.0);
        let d = x.square().sub(&two_x).range();
        assert!(d.lo >= -1.0 - 1e-12 && d.hi <= -1.0 + 0.0101, "{d:?}");
    }

    #[test]
    fn a_ray_keeps_its_coordinates_tied() {
        // Along x = 1 + t, y = 1 - t, x + y is the constant 2: one symbol
        // cancels exactly, where a box's two symbols add their widths.
        let t = Interval::new(0.0, 0.5);
        let x = Affine::along(Interval::point(1.0), Interval::point(1.0), t);
        let y = Affine::along(Interval::point(1.0), Interval::point(-1.0), t);
        let r = x.add(&y).range();
        assert!(r.contains(2.0) && r.width() < 1e-12, "{r:?}");
    }

    #[test]
    fn may_reach_zero_keeps_the_part_that_can_vanish() {
        // 1 + 2ε ± 0.5 is positive for ε > -0.25.
        let f = Affine {
            c: 1.0,
            k: [2.0],
            e: 0.5,
        };
        let p = f.may_reach_zero().unwrap();
        assert!(p.lo == -1.0 && p.hi >= -0.25 && p.hi < -0.2499, "{p:?}");
        // Mirrored, and wholly positive.
        let g = Affine { k: [-2.0], ..f };
        let q = g.may_reach_zero().unwrap();
        assert!(q.hi == 1.0 && q.lo <= 0.25 && q.lo > 0.2499, "{q:?}");
        assert_eq!(Affine { k: [0.4], ..f }.may_reach_zero(), None);
        // On t over [2, 4] (m = 3, r = 1) the first part is [2, 2.75].
        let t = along_parameter(Interval::new(2.0, 4.0), p).unwrap();
        assert!(t.lo == 2.0 && t.hi >= 2.75 && t.hi < 2.7501, "{t:?}");
    }

    #[test]
    fn overflow_gives_the_unbounded_form() {
        let x = Affine::<3>::var(Interval::new(1e300, 1.1e300), 0);
        assert_eq!(x.mul(&x), Affine::UNBOUNDED);
        assert_eq!(x.mul(&x).range(), Interval::ENTIRE);
    }
}
