//! Numerical stress suite for the whole pipeline (load → simplify → beam
//! trace): double roots and tangency, singular points, extreme scales,
//! ill-conditioned polynomials, domain edges with NaN and inf, and huge
//! formulas. Every case renders a tiny image without a panic and checks
//! the answer wherever it is known. What each case shows is written up in
//! `docs/stability.md`.
//!
//! Two oracles recur:
//! - an analytic mask, decided per pixel only where the answer is the same
//!   for rays a fraction of a pixel around the pixel centre ([`analytic`]);
//!   pixels on the silhouette band are left undecided;
//! - a dense point march ([`Method::Point`]): any ray on which it finds a
//!   point with f ≤ 0 holds a real point of the solid, which the guaranteed
//!   tracer must not miss, so `march ⊆ beam` holds exactly.

use std::sync::Arc;

use ibeam::eval::Evaluator;
use ibeam::eval::{EvalKind, build_evaluators};
use ibeam::ir::passes;
use ibeam::render::camera::{PixelRay, RayCamera};
use ibeam::render::{Method, RenderOptions, RenderOutput, render};
use ibeam::scene::Scene;

/// The evaluators every render in this file uses: the JIT, built as the
/// CLI builds it.
fn evaluators(scene: &Scene) -> Vec<Arc<dyn Evaluator>> {
    build_evaluators(scene, EvalKind::Jit).expect("JIT accepts valid IR")
}

/// The reference interpreter over the same simplified functions.
fn interp_evaluators(scene: &Scene) -> Vec<Arc<dyn Evaluator>> {
    build_evaluators(scene, EvalKind::Interp).expect("valid IR")
}

fn load(name: &str, src: &str) -> Scene {
    ibeam::lang::load_scene_source(name, src).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn load_example(name: &str) -> Scene {
    let path = format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR"));
    ibeam::lang::load_scene(std::path::Path::new(&path)).unwrap_or_else(|e| panic!("{e}"))
}

fn render_with(scene: &Scene, w: u32, h: u32, method: Method) -> RenderOutput {
    render_by(scene, &evaluators(scene), w, h, method)
}

fn render_by(
    scene: &Scene,
    evals: &[Arc<dyn Evaluator>],
    w: u32,
    h: u32,
    method: Method,
) -> RenderOutput {
    let mut opts = RenderOptions::new(w, h);
    opts.method = method;
    opts.want_depth = true;
    opts.want_normals = true;
    let out = render(scene, evals, &opts).unwrap_or_else(|e| panic!("render: {e}"));
    check_finite(&out);
    out
}

fn beam(scene: &Scene, w: u32, h: u32) -> RenderOutput {
    render_with(scene, w, h, Method::Beam)
}

/// No NaN anywhere in the output: a hit has a finite depth, a miss +inf,
/// and the mask agrees with the depths.
fn check_finite(out: &RenderOutput) {
    for (k, (&t, &m)) in out.depth_t.iter().zip(&out.hit_mask).enumerate() {
        assert!(!t.is_nan(), "pixel {k}: NaN depth");
        assert_eq!(m, t.is_finite(), "pixel {k}: mask {m} but depth {t}");
        assert!(!m || t >= 0.0, "pixel {k}: hit behind the eye at t = {t}");
    }
    assert_eq!(out.stats.pixels_hit as usize, count(&out.hit_mask));
}

fn count(mask: &[bool]) -> usize {
    mask.iter().filter(|&&m| m).count()
}

/// Screen offsets (pixels) at which the analytic answer must agree for a
/// pixel to count as decided: the centre and four points a third of a
/// pixel away. Pixels whose footprint straddles the silhouette differ
/// among them and are left out of the comparison.
const PROBES: [(f64, f64); 5] = [
    (0.0, 0.0),
    (1.0 / 3.0, 0.0),
    (-1.0 / 3.0, 0.0),
    (0.0, 1.0 / 3.0),
    (0.0, -1.0 / 3.0),
];

/// The analytic mask of `scene` at `w × h`: `Some(hit)` where `hits`
/// gives the same answer for every probe ray around the pixel centre,
/// `None` on the silhouette band. `hits(o, d, t0, t1)` says whether the
/// ray `o + t·d` meets the solid for t in [t0, t1] (its clip range).
fn analytic(
    scene: &Scene,
    w: u32,
    h: u32,
    hits: impl Fn([f64; 3], [f64; 3], f64, f64) -> bool,
) -> Vec<Option<bool>> {
    let cam = RayCamera::new(&scene.camera, w, h).unwrap();
    let mut out = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let answers: Vec<bool> = PROBES
                .iter()
                .map(|(dx, dy)| {
                    let (o, d) = cam.ray_at(i as f64 + 0.5 + dx, j as f64 + 0.5 + dy);
                    let r = PixelRay {
                        o,
                        d,
                        om: o.map(|c| c.mid()),
                        dm: d.map(|c| c.mid()),
                    };
                    r.slab(&scene.bounds)
                        .is_some_and(|(t0, t1)| hits(r.om, r.dm, t0, t1))
                })
                .collect();
            out.push(
                answers
                    .iter()
                    .all(|&a| a == answers[0])
                    .then_some(answers[0]),
            );
        }
    }
    out
}

/// Whether the ray meets the ball |p − c| ≤ r for some t in [t0, t1].
fn ray_meets_ball(o: [f64; 3], d: [f64; 3], t0: f64, t1: f64, c: [f64; 3], r: f64) -> bool {
    // Scale-free: work in units of r relative to the centre.
    let oc: [f64; 3] = std::array::from_fn(|i| (o[i] - c[i]) / r);
    let dd: [f64; 3] = std::array::from_fn(|i| d[i] / r);
    // |oc + t dd|² − 1 = a t² + b t + q.
    let a = dot(dd, dd);
    let b = 2.0 * dot(oc, dd);
    let q = dot(oc, oc) - 1.0;
    min_quadratic(a, b, q, t0, t1) <= 0.0
}

/// min of a t² + b t + q over [t0, t1].
fn min_quadratic(a: f64, b: f64, q: f64, t0: f64, t1: f64) -> f64 {
    let f = |t: f64| (a * t + b) * t + q;
    let mut m = f(t0).min(f(t1));
    if a > 0.0 {
        let tv = -b / (2.0 * a);
        if tv > t0 && tv < t1 {
            m = m.min(f(tv));
        }
    }
    m
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Asserts the rendered mask equals the analytic one on every decided
/// pixel, and that enough pixels were decided (and hit) to mean something.
fn assert_matches(name: &str, got: &[bool], want: &[Option<bool>]) {
    let mut bad = Vec::new();
    for (k, (&g, &w)) in got.iter().zip(want).enumerate() {
        if let Some(w) = w
            && w != g
        {
            bad.push((k, w, g));
        }
    }
    assert!(bad.is_empty(), "{name}: (pixel, want, got) {bad:?}");
    let decided = want.iter().filter(|w| w.is_some()).count();
    let decided_hits = want.iter().filter(|&&w| w == Some(true)).count();
    assert!(
        decided * 10 >= want.len() * 8,
        "{name}: only {decided} of {} pixels decided",
        want.len()
    );
    assert!(
        decided_hits >= 20,
        "{name}: only {decided_hits} decided hits"
    );
}

/// Pixels the march hit that the render missed (must be none: the march
/// found a real point with f ≤ 0 on the ray).
fn assert_covers_march(name: &str, scene: &Scene, got: &RenderOutput, w: u32, h: u32) {
    let march = render_with(scene, w, h, Method::Point { steps: 600 });
    let missed: Vec<usize> = (0..got.hit_mask.len())
        .filter(|&k| march.hit_mask[k] && !got.hit_mask[k])
        .collect();
    assert!(
        missed.is_empty(),
        "{name}: beam misses march hits {missed:?}"
    );
}

/// Beam and single interval rays must draw exactly the same pixels.
fn assert_beam_equals_pixel(name: &str, scene: &Scene, got: &RenderOutput, w: u32, h: u32) {
    let px = render_with(scene, w, h, Method::Pixel);
    let diff: Vec<usize> = (0..got.hit_mask.len())
        .filter(|&k| px.hit_mask[k] != got.hit_mask[k])
        .collect();
    assert!(diff.is_empty(), "{name}: beam and pixel differ at {diff:?}");
}

fn scene_text(object: &str, eye: [f64; 3], target: [f64; 3], bounds: f64) -> String {
    scene_text_box(object, eye, target, [-bounds; 3], [bounds; 3])
}

fn scene_text_box(
    object: &str,
    eye: [f64; 3],
    target: [f64; 3],
    lo: [f64; 3],
    hi: [f64; 3],
) -> String {
    let v = |p: [f64; 3]| format!("({:e}, {:e}, {:e})", p[0], p[1], p[2]);
    format!(
        "object s = {object};\n\
         camera {{ eye = {}; target = {}; up = (0, 1, 0); fov = 35; }}\n\
         bounds = {} .. {};\n\
         light {{ direction = (-0.5, -1, -0.7); shadows = true; }}\n",
        v(eye),
        v(target),
        v(lo),
        v(hi)
    )
}

const EYE: [f64; 3] = [2.0, 1.5, 3.5];

// ------------------------------------------------ double roots, tangency

#[test]
fn squared_sphere_has_the_sphere_mask() {
    let (w, h) = (40, 40);
    let plain = load(
        "s.ib",
        &scene_text("x^2 + y^2 + z^2 - 1", EYE, [0.0; 3], 1.2),
    );
    let double = load(
        "d.ib",
        &scene_text("(x^2 + y^2 + z^2 - 1)^2", EYE, [0.0; 3], 1.2),
    );
    let want = analytic(&plain, w, h, |o, d, t0, t1| {
        ray_meets_ball(o, d, t0, t1, [0.0; 3], 1.0)
    });
    let a = beam(&plain, w, h);
    let b = beam(&double, w, h);
    assert_matches("sphere", &a.hit_mask, &want);
    assert_matches("squared sphere", &b.hit_mask, &want);
    // A double root never changes sign: every hit is a tangency decision,
    // made per ray, so beam and pixel must agree.
    assert_beam_equals_pixel("squared sphere", &double, &b, w, h);
    // Depths of the double root agree with the simple root to within a
    // few depth tolerances.
    let cam = RayCamera::new(&plain.camera, w, h).unwrap();
    for k in 0..a.depth_t.len() {
        if a.hit_mask[k] && b.hit_mask[k] {
            let tol = cam.tolerance(a.depth_t[k]);
            assert!(
                (a.depth_t[k] - b.depth_t[k]).abs() <= 8.0 * tol + 1e-3,
                "pixel {k}: {} vs {}",
                a.depth_t[k],
                b.depth_t[k]
            );
        }
    }
}

#[test]
fn grazing_rays_on_the_silhouette() {
    // Orthographic view, 33 px over 3.3 units: pixel centres lie on the
    // grid 0.1·k, so the rays of row 16 and column 16 pass exactly (up to
    // rounding) through the silhouette points (±1, 0) and (0, ±1).
    let src = "object s = x^2 + y^2 + z^2 - 1;\n\
               camera { eye = (0, 0, 5); target = (0, 0, 0); up = (0, 1, 0); ortho = 3.3; }\n\
               bounds = (-1.5, -1.5, -1.5) .. (1.5, 1.5, 1.5);\n";
    let scene = load("graze.ib", src);
    let (w, h) = (33, 33);
    let out = beam(&scene, w, h);
    let want = analytic(&scene, w, h, |o, d, t0, t1| {
        ray_meets_ball(o, d, t0, t1, [0.0; 3], 1.0)
    });
    assert_matches("grazing", &out.hit_mask, &want);
    assert_beam_equals_pixel("grazing", &scene, &out, w, h);
    // The four exactly tangent rays: either answer is allowed (tangency
    // policy), but both methods give the same, and a hit is at the
    // tangent point's depth (t = 5, the eye plane is z = 5).
    for (i, j) in [(26, 16), (6, 16), (16, 6), (16, 26)] {
        let k = (j * w + i) as usize;
        if out.hit_mask[k] {
            assert!((out.depth_t[k] - 5.0).abs() < 0.05, "{}", out.depth_t[k]);
        }
    }
}

// ------------------------------------------------------- singular points

/// Renders with beam, checks no NaN, beam = pixel and march ⊆ beam, and
/// returns the hit fraction.
fn singular_case(name: &str, scene: &Scene, w: u32, h: u32) -> f64 {
    let out = beam(scene, w, h);
    assert_beam_equals_pixel(name, scene, &out, w, h);
    assert_covers_march(name, scene, &out, w, h);
    count(&out.hit_mask) as f64 / out.hit_mask.len() as f64
}

#[test]
fn steiner_surface_renders_with_hits() {
    let frac = singular_case("steiner", &load_example("steiner.ib"), 32, 32);
    assert!(frac > 0.1 && frac < 0.9, "hit fraction {frac}");
}

#[test]
fn double_cone_apex_in_view() {
    let scene = load(
        "cone.ib",
        &scene_text("x^2 + y^2 - z^2", [2.5, 1.0, 1.5], [0.0; 3], 1.0),
    );
    // Odd size: the centre pixel's ray passes exactly through the apex.
    let (w, h) = (33, 33);
    let out = beam(&scene, w, h);
    // Along a ray the cone's function is a quadratic in t: exact answer.
    let want = analytic(&scene, w, h, |o, d, t0, t1| {
        let a = d[0] * d[0] + d[1] * d[1] - d[2] * d[2];
        let b = 2.0 * (o[0] * d[0] + o[1] * d[1] - o[2] * d[2]);
        let q = o[0] * o[0] + o[1] * o[1] - o[2] * o[2];
        // a may be negative: check the ends and the vertex.
        let f = |t: f64| (a * t + b) * t + q;
        let mut m = f(t0).min(f(t1));
        if a != 0.0 {
            let tv = -b / (2.0 * a);
            if tv > t0 && tv < t1 {
                m = m.min(f(tv));
            }
        }
        m <= 0.0
    });
    assert_matches("cone", &out.hit_mask, &want);
    assert_beam_equals_pixel("cone", &scene, &out, w, h);
    // The ray through the apex touches the cone there without crossing
    // it (f ≥ 0 along it, a double root at the apex): the tangency policy
    // draws it, at the apex's depth |eye|.
    let k = (h / 2 * w + w / 2) as usize;
    let apex = dot([2.5, 1.0, 1.5], [2.5, 1.0, 1.5]).sqrt();
    assert!(out.hit_mask[k], "apex ray missed");
    assert!(
        (out.depth_t[k] - apex).abs() < 0.02,
        "{} vs {apex}",
        out.depth_t[k]
    );
}

#[test]
fn barth_sextic_nodes() {
    let frac = singular_case("barth", &load_example("barth_sextic.ib"), 24, 24);
    assert!(frac > 0.1 && frac < 0.95, "hit fraction {frac}");
}

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
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models/prospero.vm");
    if !path.exists() {
        println!("note: {} absent, prospero case skipped", path.display());
        return;
    }
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
    // (see the README's JIT section), too slow for CI.
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
