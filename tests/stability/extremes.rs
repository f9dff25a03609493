//! Extreme scales, ill-conditioning, domain edges and huge formulas.

use super::*;

// ----------------------------------------------------------------- scale

/// The unit sphere seen from `EYE`, everything multiplied by `s`.
fn scaled_sphere(s: f64, form: &str) -> Scene {
    let obj = form.replace("R", &format!("{s:e}"));
    load(
        "scaled.ib",
        &scene_text(&obj, EYE.map(|c| c * s), [0.0; 3], 1.2 * s),
    )
}

#[test]
fn tiny_and_huge_spheres_have_the_unit_mask() {
    let (w, h) = (32, 32);
    let unit = scaled_sphere(1.0, "x^2 + y^2 + z^2 - R^2");
    let want = analytic(&unit, w, h, |o, d, t0, t1| {
        ray_meets_ball(o, d, t0, t1, [0.0; 3], 1.0)
    });
    let base = beam(&unit, w, h);
    assert_matches("unit", &base.hit_mask, &want);
    for s in [1e-6, 1e6] {
        for form in ["x^2 + y^2 + z^2 - R^2", "sphere(R)"] {
            let scene = scaled_sphere(s, form);
            let out = beam(&scene, w, h);
            let name = format!("{form} at scale {s:e}");
            let mine = analytic(&scene, w, h, |o, d, t0, t1| {
                ray_meets_ball(o, d, t0, t1, [0.0; 3], s)
            });
            assert_matches(&name, &out.hit_mask, &mine);
            assert_matches(&name, &out.hit_mask, &want);
            // Depths scale with the scene.
            for k in 0..out.depth_t.len() {
                if out.hit_mask[k] && base.hit_mask[k] {
                    let rel = out.depth_t[k] / s / base.depth_t[k] - 1.0;
                    assert!(rel.abs() < 0.01, "{name}: pixel {k} depth off by {rel}");
                }
            }
        }
    }
}

#[test]
fn far_translated_sphere_with_the_camera_following() {
    let (w, h) = (32, 32);
    let unit = scaled_sphere(1.0, "x^2 + y^2 + z^2 - R^2");
    let base = beam(&unit, w, h);
    let c = [1e6, 0.0, 0.0];
    for form in [
        "(x - 1e6)^2 + y^2 + z^2 - 1",
        "translate(sphere(1), 1e6, 0, 0)",
    ] {
        let scene = load(
            "far.ib",
            &scene_text_box(
                form,
                [EYE[0] + 1e6, EYE[1], EYE[2]],
                c,
                [1e6 - 1.2, -1.2, -1.2],
                [1e6 + 1.2, 1.2, 1.2],
            ),
        );
        let out = beam(&scene, w, h);
        let want = analytic(&scene, w, h, |o, d, t0, t1| {
            ray_meets_ball(o, d, t0, t1, c, 1.0)
        });
        assert_matches(form, &out.hit_mask, &want);
        // Nearly the unit sphere's mask: the rays differ by the rounding
        // of coordinates near 1e6 (ulp 1.2e-10), far below a pixel.
        let diff = (0..out.hit_mask.len())
            .filter(|&k| out.hit_mask[k] != base.hit_mask[k])
            .count();
        assert!(
            diff <= 2,
            "{form}: {diff} pixels differ from the unit sphere"
        );
    }
}

// --------------------------------------------------------- ill-conditioning

/// (x − 1)^10 + y² + z² − 0.5 as written, and with (x − 1)^10 expanded.
const FACTORED: &str = "(x - 1)^10 + y^2 + z^2 - 0.5";
const EXPANDED: &str = "x^10 - 10*x^9 + 45*x^8 - 120*x^7 + 210*x^6 - 252*x^5 \
     + 210*x^4 - 120*x^3 + 45*x^2 - 10*x + 1 + y^2 + z^2 - 0.5";

#[test]
fn expanded_polynomial_draws_the_factored_surface() {
    let (w, h) = (32, 32);
    let mk = |f: &str| {
        load(
            "poly.ib",
            &scene_text_box(
                f,
                [3.0, 1.5, 3.5],
                [1.0, 0.0, 0.0],
                [-0.2, -1.0, -1.0],
                [2.2, 1.0, 1.0],
            ),
        )
    };
    let (fa, ex) = (mk(FACTORED), mk(EXPANDED));
    let a = beam(&fa, w, h);
    let b = beam(&ex, w, h);
    // Along a ray (x − 1)^10 is no quadratic; a dense march of the
    // factored form in f64 is accurate here (no cancellation) and is the
    // reference, with the silhouette band left out by the probe rays.
    let want = analytic(&fa, w, h, |o, d, t0, t1| {
        let f = |t: f64| {
            let p = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
            (p[0] - 1.0).powi(10) + p[1] * p[1] + p[2] * p[2] - 0.5
        };
        (0..=4000).any(|i| f(t0 + (t1 - t0) * i as f64 / 4000.0) <= 0.0)
    });
    assert_matches("factored", &a.hit_mask, &want);
    assert_matches("expanded", &b.hit_mask, &want);
    // Every pixel the factored form finds, the expanded form finds too:
    // both are guaranteed, only the cost differs.
    let lost: Vec<usize> = (0..a.hit_mask.len())
        .filter(|&k| a.hit_mask[k] && !b.hit_mask[k])
        .collect();
    assert!(lost.is_empty(), "expanded form loses {lost:?}");
    assert_beam_equals_pixel("expanded", &ex, &b, w, h);
    // The cost, printed for docs/stability.md: the expanded form's
    // interval extension is far wider, so more work per pixel.
    let (sa, sb) = (&a.stats, &b.stats);
    println!(
        "factored: {} interval evals, {} rays, {} undecided blocks; \
         expanded: {} interval evals, {} rays, {} undecided blocks",
        sa.interval_evals,
        sa.rays,
        sa.blocks_undecided,
        sb.interval_evals,
        sb.rays,
        sb.blocks_undecided
    );
    assert!(sb.interval_evals > sa.interval_evals);
}

// ------------------------------------------------------------ domain edges

/// Checks a domain-edge scene: no NaN, beam = pixel, march ⊆ beam.
fn domain_case(name: &str, object: &str) -> RenderOutput {
    let scene = load(
        "domain.ib",
        &scene_text(object, [3.0, 1.5, 2.5], [0.0; 3], 2.0),
    );
    let (w, h) = (32, 32);
    let out = beam(&scene, w, h);
    assert_beam_equals_pixel(name, &scene, &out, w, h);
    assert_covers_march(name, &scene, &out, w, h);
    out
}

#[test]
fn sqrt_domain_edge_keeps_the_sphere() {
    // Undefined for x < −1.2 (partly in view, in front of and beside the
    // sphere); where defined, zero exactly on the unit sphere.
    let object = "(x^2 + y^2 + z^2 - 1) * (1 + sqrt(x + 1.2))";
    let out = domain_case("sqrt", object);
    let scene = load(
        "domain.ib",
        &scene_text(object, [3.0, 1.5, 2.5], [0.0; 3], 2.0),
    );
    let want = analytic(&scene, 32, 32, |o, d, t0, t1| {
        ray_meets_ball(o, d, t0, t1, [0.0; 3], 1.0)
    });
    assert_matches("sqrt", &out.hit_mask, &want);
}

#[test]
fn ln_domain_edge_draws_the_boundary_where_f_goes_to_minus_infinity() {
    // ln(x + 1.5) → −inf at the domain edge x = −1.5: the solid reaches the
    // edge, which is drawn (it is the boundary of {f < 0}); left of it f
    // is undefined and nothing is drawn.
    let out = domain_case("ln", "x^2 + y^2 + z^2 - 1 + 0.2*ln(x + 1.5)");
    assert!(count(&out.hit_mask) > 50);
}

#[test]
fn division_pole_in_view() {
    // A pole at x = 1.5, outside the sphere: f jumps from −inf to +inf
    // there, so a thin solid sheet ends at the pole plane.
    let out = domain_case("div", "x^2 + y^2 + z^2 - 1 + 0.05/(x - 1.5)");
    assert!(count(&out.hit_mask) > 50);
    let out = domain_case("div0", "(x^2 + y^2 + z^2 - 1) / x");
    assert!(count(&out.hit_mask) > 50);
}

#[test]
fn overflow_to_inf_and_nan_in_part_of_the_scene() {
    // exp(800 x) overflows to +inf for x > 0.887: there the term is +inf
    // (that part of the sphere is cut away) and where exp(800 y) overflows
    // too, inf − inf = NaN (undefined: nothing drawn).
    let out = domain_case(
        "inf-nan",
        "x^2 + y^2 + z^2 - 1 + (exp(800*x) - exp(800*y)) * 1e-320",
    );
    assert!(count(&out.hit_mask) > 50);
    // An interval that is all NaN over a region: f undefined for
    // |x| > 1.1; the sphere inside is unaffected.
    let object = "x^2 + y^2 + z^2 - 1 + 0*sqrt(1.21 - x^2)";
    let out = domain_case("nan-region", object);
    let scene = load(
        "domain.ib",
        &scene_text(object, [3.0, 1.5, 2.5], [0.0; 3], 2.0),
    );
    let want = analytic(&scene, 32, 32, |o, d, t0, t1| {
        ray_meets_ball(o, d, t0, t1, [0.0; 3], 1.0)
    });
    assert_matches("nan-region", &out.hit_mask, &want);
}

// --------------------------------------------------------- huge formulas

#[test]
fn prospero_renders_at_32() {
    let Some(path) = models::shared_model("prospero.vm") else {
        return;
    };
    let scene = ibeam::lang::load_scene(&path).unwrap();
    let ops = scene.objects[0].function.len();
    assert!(ops > 5000, "{ops} ops");
    let out = beam(&scene, 32, 32);
    let frac = count(&out.hit_mask) as f64 / out.hit_mask.len() as f64;
    // Text on a background: ink covers a minority of the square.
    assert!(frac > 0.05 && frac < 0.6, "filled fraction {frac}");
}

#[test]
fn hundred_thousand_op_sum_of_spheres() {
    // f = (1/n) Σ |p − c_i|² − 1 with the centres c_i = ±(a, b, c) in
    // pairs, so Σ c_i = 0 and f = |p|² + v − 1 with v the mean |c_i|²:
    // a sphere of radius sqrt(1 − v).
    let mut rng = ibeam::ir::random::Rng::new(7);
    let pairs = 4200;
    let mut terms = Vec::with_capacity(2 * pairs);
    let mut v = 0.0;
    for _ in 0..pairs {
        // Distinct centres, so hash-consing merges nothing but x, y, z;
        // the rounding of the sum is ~1e-12, far below a pixel.
        let c: [f64; 3] = std::array::from_fn(|_| rng.range(-0.3, 0.3));
        v += 2.0 * dot(c, c);
        for s in [1.0, -1.0] {
            terms.push(format!(
                "(x - {})^2 + (y - {})^2 + (z - {})^2",
                s * c[0],
                s * c[1],
                s * c[2]
            ));
        }
    }
    let n = terms.len() as f64;
    v /= n;
    let object = format!("({}) / {n} - 1", terms.join(" + "));
    let scene = load("sum.ib", &scene_text(&object, EYE, [0.0; 3], 1.2));
    let ops = scene.objects[0].function.len();
    assert!(ops >= 100_000, "{ops} ops");
    let simplified = passes::simplify(&scene.objects[0].function);
    assert!(simplified.len() >= 90_000, "{} ops", simplified.len());
    let (w, h) = (16, 16);
    // The interpreter: the JIT compiles 100,000 ops too, but its interval
    // and gradient kinds take tens of seconds to compile at that size
    // (see docs/performance.md, Evaluators), too slow for CI.
    let out = render_by(&scene, &interp_evaluators(&scene), w, h, Method::Beam);
    let r = (1.0 - v).sqrt();
    let want = analytic(&scene, w, h, |o, d, t0, t1| {
        ray_meets_ball(o, d, t0, t1, [0.0; 3], r)
    });
    let decided_hits = want.iter().filter(|&&x| x == Some(true)).count();
    assert!(decided_hits > 10);
    for (k, &wk) in want.iter().enumerate() {
        if let Some(wk) = wk {
            assert_eq!(out.hit_mask[k], wk, "pixel {k}");
        }
    }
}
