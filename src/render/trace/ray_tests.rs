//! Tests of `render::ray`.

use super::*;
use crate::eval::{Bulk, Evaluator, Grad, IntervalGrad, Single, Specialise};
use crate::interval::boxes::point_box;
use std::sync::Arc;

/// A function of x alone, with its interval extension and derivative.
struct OfX {
    f: fn(f64) -> f64,
    df: fn(f64) -> f64,
    fi: fn(Interval) -> Interval,
    dfi: fn(Interval) -> Interval,
}

impl Single for OfX {
    fn point(&self, p: [f64; 3]) -> f64 {
        (self.f)(p[0])
    }
    fn point_grad(&self, p: [f64; 3]) -> Grad {
        Grad {
            v: (self.f)(p[0]),
            d: [(self.df)(p[0]), 0.0, 0.0],
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        (self.fi)(b[0])
    }
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        let z = Interval::point(0.0);
        IntervalGrad {
            v: (self.fi)(b[0]),
            d: [(self.dfi)(b[0]), z, z],
        }
    }
}

impl Bulk for OfX {}

impl Specialise for OfX {}

// Traces the ray x = -2 + t (t in [0, 4]) through `e`.
fn trace(e: OfX) -> (Option<Hit>, RenderStats, f64) {
    let evals: Vec<Arc<dyn Evaluator>> = vec![Arc::new(e)];
    let tr = Scope::of_objects_for_tests(&evals, &[], 64);
    let (o, d) = ([-2.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    let ray = PixelRay {
        o: point_box(o),
        d: point_box(d),
        om: o,
        dm: d,
    };
    let mut st = TileState::default();
    let hit = trace_ray(&tr, &ray, 0.0, 4.0, &[0], &mut st);
    (hit, st.stats, tr.ctx.cam.tolerance(2.5))
}

fn h(v: f64) -> Interval {
    Interval::point(v)
}

#[test]
fn a_simple_root_is_proven_by_newton_quickly() {
    let (hit, st, tol) = trace(OfX {
        f: |x| 0.5 - x,
        df: |_| -1.0,
        fi: |x| h(0.5).sub(x),
        dfi: |_| h(-1.0),
    });
    let hit = hit.unwrap();
    assert!(!hit.inside);
    assert!((hit.t - 2.5).abs() <= tol);
    assert!(st.interval_evals < 20, "{}", st.interval_evals);
}

#[test]
fn a_double_root_counts_as_a_hit_at_the_tangency() {
    // (x - 0.5)² touches 0 at x = 0.5 and never changes sign.
    let (hit, _, tol) = trace(OfX {
        f: |x| (x - 0.5) * (x - 0.5),
        df: |x| 2.0 * (x - 0.5),
        fi: |x| x.sub(h(0.5)).square(),
        dfi: |x| h(2.0).mul(x.sub(h(0.5))),
    });
    let hit = hit.unwrap();
    assert!((hit.t - 2.5).abs() <= tol, "{} vs 2.5 ± {tol}", hit.t);
}

#[test]
fn a_positive_function_has_no_hit() {
    let (hit, st, _) = trace(OfX {
        f: |x| x * x + 0.01,
        df: |x| 2.0 * x,
        fi: |x| x.square().add(h(0.01)),
        dfi: |x| h(2.0).mul(x),
    });
    assert_eq!(hit, None);
    assert_eq!(st.rays, 1);
}

#[test]
fn a_ray_starting_inside_hits_at_its_start() {
    let (hit, _, _) = trace(OfX {
        f: |x| x - 5.0,
        df: |_| 1.0,
        fi: |x| x.sub(h(5.0)),
        dfi: |_| h(1.0),
    });
    assert_eq!(
        hit,
        Some(Hit {
            t: 0.0,
            obj: 0,
            inside: true,
            grad: None,
            front: None,
        })
    );
}

// |x - 0.3| (+ 1e-9 when `lifted`), written as a max of two lines: its
// interval extension over a piece around the kink reaches below zero
// by up to half the piece's width, and dF/dt there is [-1, 1].
// Off the bisection's dyadic points, where the extension is exact.
const KINK: f64 = 0.3;

fn kink(lifted: bool) -> OfX {
    fn dfi(x: Interval) -> Interval {
        if x.lo >= KINK {
            h(1.0)
        } else if x.hi <= KINK {
            h(-1.0)
        } else {
            Interval::new(-1.0, 1.0)
        }
    }
    fn f(x: f64) -> f64 {
        (x - KINK).max(KINK - x)
    }
    fn fi(x: Interval) -> Interval {
        x.sub(h(KINK)).max(h(KINK).sub(x))
    }
    OfX {
        f: if lifted { |x| f(x) + 1e-9 } else { f },
        df: |x| if x >= KINK { 1.0 } else { -1.0 },
        fi: if lifted { |x| fi(x).add(h(1e-9)) } else { fi },
        dfi,
    }
}

#[test]
fn a_kink_touching_zero_is_drawn_at_its_vertex() {
    // No sign change: the tangency policy draws it, once the pieces
    // around the vertex are narrow enough; the gaps Newton cuts around
    // each midpoint (F > 0 there, |dF/dt| ≤ 1) close in on it.
    let (hit, st, tol) = trace(kink(false));
    let hit = hit.unwrap();
    assert!((hit.t - 2.3).abs() <= tol, "{} vs 2.3 ± {tol}", hit.t);
    assert!(st.interval_evals < 20, "{} evaluations", st.interval_evals);
}

#[test]
fn a_kinked_near_miss_is_not_drawn_as_a_tangency() {
    // 1e-9 above zero at the kink, far below what bisection to a 64th
    // of the tolerance can separate from zero: the gap around a
    // midpoint where F ≥ 1e-9 + its distance to the kink covers the
    // kink.
    let (hit, st, _) = trace(kink(true));
    assert_eq!(hit, None);
    assert!(st.interval_evals < 20, "{} evaluations", st.interval_evals);
}
