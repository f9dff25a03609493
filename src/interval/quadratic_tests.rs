use super::*;

// Points of [-1, 1] where the containment tests look, the ends included.
fn eps_points() -> Vec<f64> {
    (0..=64).map(|i| -1.0 + f64::from(i) / 32.0).collect()
}

// The form's values at `x`, by outward intervals: the polynomial part
// plus or minus the error.
fn form_at(q: &Quadratic, x: f64) -> Interval {
    let p = Interval::point(q.c[2])
        .mul_point(x)
        .add(Interval::point(q.c[1]))
        .mul_point(x)
        .add(Interval::point(q.c[0]));
    p.add(Interval::new(-q.e, q.e))
}

// The form's values for ε anywhere in `eps`, by outward intervals.
fn over(q: &Quadratic, eps: Interval) -> Interval {
    let p = Interval::point(q.c[2])
        .mul(eps)
        .add(Interval::point(q.c[1]))
        .mul(eps)
        .add(Interval::point(q.c[0]));
    p.add(Interval::new(-q.e, q.e))
}

// Parameters `t` of the range (as point intervals) and an interval of
// their noise values `(t − m)/r` (`m`, `r` as `Affine::along` takes them).
fn ray_points(t: Interval) -> Vec<(Interval, Interval)> {
    let (m, r) = crate::interval::affine::centre_radius(t);
    (0..=64)
        .map(|i| {
            let x = Interval::point(t.lo + (t.hi - t.lo) * f64::from(i) / 64.0);
            let eps = x.sub(Interval::point(m)).div(Interval::point(r));
            (x, eps)
        })
        .collect()
}

// Whether the form at `x` holds a value that the outward interval `v`
// encloses (the two must meet).
fn holds(q: &Quadratic, x: f64, v: Interval) -> bool {
    let f = form_at(q, x);
    f.lo <= v.hi && v.lo <= f.hi
}

// Some forms with terms of every sign and size, and an error.
fn samples() -> Vec<Quadratic> {
    let mut out = Vec::new();
    for (i, c0) in [-1.5, 0.0, 0.3, 2.0].into_iter().enumerate() {
        for c1 in [-0.7, 0.05, 1.1] {
            for c2 in [-0.9, 0.0, 0.6] {
                let e = [0.0, 1e-3, 0.02, 0.2][i];
                out.push(Quadratic { c: [c0, c1, c2], e });
            }
        }
    }
    out
}

// The sample's value at `x` moved by `s·e` (s in [-1, 1]): a value the
// form encloses, as an outward interval.
fn member(q: &Quadratic, x: f64, s: f64) -> Interval {
    form_at(&Quadratic { e: 0.0, ..*q }, x).add(Interval::point(q.e).mul_point(s))
}

#[test]
fn products_and_squares_hold_the_values_of_their_operands() {
    let qs = samples();
    for a in &qs {
        for b in qs.iter().step_by(5) {
            let (m, s, d) = (a.mul(b), a.square(), a.add(b).sub(&b.linear(2.0, 0.5, 0.0)));
            for x in eps_points() {
                for sa in [-1.0, 1.0] {
                    let (va, vb) = (member(a, x, sa), member(b, x, -sa));
                    assert!(holds(&m, x, va.mul(vb)), "{a:?} · {b:?} at {x}");
                    assert!(holds(&s, x, va.square()), "{a:?}² at {x}");
                    let want = va.add(vb).sub(vb.mul_point(2.0).add(Interval::point(0.5)));
                    assert!(holds(&d, x, want), "{a:?} + {b:?} - (2b + 0.5) at {x}");
                }
            }
        }
    }
}

#[test]
fn powers_hold_their_values() {
    let (o, d) = (Interval::point(1.3), Interval::point(1.0));
    for w in [0.01, 0.001] {
        // x = 1.3 + t along the ray, t over [0, w].
        let t = Interval::new(0.0, w);
        let q = Quadratic::along(o, d, t);
        for k in 2..=10 {
            let p = q.power(k).unwrap();
            for (x, eps) in ray_points(t) {
                let v = o.add(x).powi(k);
                let f = over(&p, eps);
                assert!(
                    f.lo <= v.hi && v.lo <= f.hi,
                    "x^{k} at {x:?}: {p:?} lacks {v:?}"
                );
            }
        }
    }
}

#[test]
fn the_range_is_the_vertex_range_rounded_outward() {
    // 1 + ε + 2ε² is least at ε = −1/4 (0.875), most at ε = 1 (4).
    let q = Quadratic {
        c: [1.0, 1.0, 2.0],
        e: 0.0,
    };
    let r = q.range_within(q.spread());
    assert!(r.lo <= 0.875 && r.lo > 0.875 - 1e-12, "{r:?}");
    assert!(r.hi >= 4.0 && r.hi < 4.0 + 1e-12, "{r:?}");
    // Mirrored and widened by its error: most at the vertex.
    let n = Quadratic { e: 0.5, ..q.neg() };
    let r = n.range_within(n.spread());
    assert!(r.hi >= -0.375 && r.hi < -0.375 + 1e-12, "{r:?}");
    assert!(r.lo <= -4.5 && r.lo > -4.5 - 1e-12, "{r:?}");
    // Every sample's range holds its values.
    for q in samples() {
        let r = q.range_within(q.spread());
        for x in eps_points() {
            // Within rounding of the value (a wrong end is off by far more).
            let v = form_at(&q, x);
            let slack = 1e-15 * (1.0 + v.hi.abs());
            assert!(r.lo <= v.lo + slack && v.hi - slack <= r.hi, "{q:?} at {x}");
        }
    }
}

#[test]
fn may_reach_zero_cuts_at_the_roots_and_keeps_every_low_point() {
    // (ε − 0.3)(ε − 0.9): at most 0 on [0.3, 0.9].
    let q = Quadratic {
        c: [0.27, -1.2, 1.0],
        e: 0.0,
    };
    let p = q.may_reach_zero().unwrap();
    assert!(p.lo <= 0.3 && p.lo > 0.3 - 1e-6 && p.hi >= 0.9 && p.hi < 0.9 + 1e-6);
    // Positive everywhere, and concave with both ends low (the hull).
    let up = Quadratic {
        c: [0.1, 0.0, 1.0],
        e: 0.05,
    };
    assert_eq!(up.may_reach_zero(), None);
    let cap = Quadratic {
        c: [0.25, 0.0, -1.0],
        e: 0.0,
    };
    assert_eq!(cap.may_reach_zero(), Some(Interval::new(-1.0, 1.0)));
    // Every sample keeps each point where its lowest value is not
    // positive.
    for q in samples() {
        let part = q.may_reach_zero();
        for x in eps_points() {
            if form_at(&q, x).lo <= 0.0 {
                assert!(
                    part.is_some_and(|p| p.contains(x)),
                    "{q:?}: {part:?} lacks {x}"
                );
            }
        }
    }
}

#[test]
fn overflow_gives_the_unbounded_form() {
    let q = Quadratic {
        c: [1e300, 1e300, 0.0],
        e: 0.0,
    };
    assert_eq!(q.mul(&q), Quadratic::UNBOUNDED);
    assert_eq!(q.square().may_reach_zero(), Some(Interval::new(-1.0, 1.0)));
}
