//! Adversarial scenes have time bounds: every loop of the tracer is
//! bounded in depth and count, so scenes built to defeat interval
//! arithmetic (frequencies near 1e300, coefficients near the largest f64,
//! objects 1e-300 wide, functions undefined almost everywhere) render at
//! 64² in seconds, or are refused with a clear error, and never panic.
//!
//! Each render runs on a thread of its own and the test waits for it with
//! a deadline, so a hang fails the test (and prints which scene and
//! method) instead of hanging the suite. Every scene is rendered by beam,
//! by single pixel rays and by beam with IAA; beam and pixel must draw
//! the same pixels, and IAA must keep every pixel beam draws.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use ibeam::render::{Aa, RenderError, render_aa};

use super::*;

/// Image side of every render here.
const SIDE: u32 = 64;

/// How long one render (JIT compile included) may take. The slowest here
/// (beam+IAA on `sin(1e300*x) + y*y + z*z - 1`) took 0.6 s on the 2-core
/// development machine in release and in the `ci-debug` profile (debug
/// assertions, the IR validator and Cranelift's verifier on) alike; 20 s
/// leaves room for a loaded machine, while a tracer loop with no bound
/// still fails it.
const BOUND: Duration = Duration::from_secs(20);

/// The three ways each scene is rendered.
const WAYS: [(&str, Method, Aa); 3] = [
    ("beam", Method::Beam, Aa::None),
    ("pixel", Method::Pixel, Aa::None),
    (
        "beam+iaa",
        Method::Beam,
        Aa::Iaa {
            threshold: ibeam::render::aa::DEFAULT_THRESHOLD,
            depth: ibeam::render::aa::DEFAULT_DEPTH,
        },
    ),
];

/// Builds the JIT evaluators and renders `scene` at 64² by `method` with
/// `aa` on a thread of its own; panics if that takes longer than
/// [`BOUND`] or if the render panics. Returns the render's result and its
/// wall time.
fn timed(
    name: &str,
    scene: &Scene,
    way: &str,
    method: Method,
    aa: Aa,
) -> (Result<RenderOutput, RenderError>, Duration) {
    let (tx, rx) = mpsc::channel();
    let scene = scene.clone();
    let start = Instant::now();
    let worker = std::thread::spawn(move || {
        let evals = evaluators(&scene);
        let mut opts = RenderOptions::new(SIDE, SIDE);
        opts.method = method;
        opts.want_depth = true;
        opts.want_normals = true;
        let _ = tx.send(render_aa(&scene, &evals, &opts, aa));
    });
    match rx.recv_timeout(BOUND) {
        Ok(res) => {
            let took = start.elapsed();
            println!("{name} [{way}]: {took:.2?}, {}", summary(&res));
            (res, took)
        }
        Err(mpsc::RecvTimeoutError::Timeout) => {
            // The worker is left running: the test binary exits anyway.
            panic!("{name} [{way}]: no answer after {BOUND:?}")
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            // The sender was dropped without a send: the worker panicked.
            let why = worker.join().err().map(|p| {
                p.downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default()
            });
            panic!("{name} [{way}]: the render panicked: {why:?}")
        }
    }
}

/// One line about a render's result.
fn summary(res: &Result<RenderOutput, RenderError>) -> String {
    match res {
        Ok(out) => format!(
            "{} of {} pixels hit, {} rays",
            count(&out.hit_mask),
            out.hit_mask.len(),
            out.stats.rays
        ),
        Err(e) => format!("error: {e}"),
    }
}

/// What rendering one scene every way gave.
struct Rendered {
    /// The beam render, or the error every way gave.
    beam: Result<RenderOutput, RenderError>,
}

/// Loads `src`, renders it every way of [`WAYS`] within [`BOUND`], and
/// checks the results agree: all images or all the same error; images
/// free of NaN with beam and pixel masks equal and IAA covering beam.
fn adversarial(name: &str, src: &str) -> Rendered {
    let scene = load(name, src);
    let mut results = Vec::new();
    for (way, method, aa) in WAYS {
        results.push(timed(name, &scene, way, method, aa).0);
    }
    let mut it = results.into_iter();
    let (beam, pixel, iaa) = (it.next().unwrap(), it.next().unwrap(), it.next().unwrap());
    match (&beam, &pixel, &iaa) {
        (Ok(b), Ok(p), Ok(a)) => {
            for out in [b, p, a] {
                check_finite(out);
            }
            let diff: Vec<usize> = (0..b.hit_mask.len())
                .filter(|&k| b.hit_mask[k] != p.hit_mask[k])
                .collect();
            assert!(diff.is_empty(), "{name}: beam and pixel differ at {diff:?}");
            // IAA starts from the plain render and keeps a pixel's centre
            // hit even when every sub-sample misses (src/render/aa.rs):
            // it can add pixels, never lose one.
            let lost: Vec<usize> = (0..b.hit_mask.len())
                .filter(|&k| b.hit_mask[k] && !a.hit_mask[k])
                .collect();
            assert!(lost.is_empty(), "{name}: IAA loses beam's pixels {lost:?}");
        }
        (Err(b), Err(p), Err(a)) => {
            // The render refuses the scene before tracing, the same way
            // whatever the method.
            assert_eq!(b, p, "{name}");
            assert_eq!(b, a, "{name}");
        }
        _ => panic!(
            "{name}: some ways render and some fail: beam {}, pixel {}, iaa {}",
            summary(&beam),
            summary(&pixel),
            summary(&iaa)
        ),
    }
    Rendered { beam }
}

/// `object` in the cube of half-side `half`, seen from `EYE` scaled to it.
fn cube(object: &str, half: f64) -> String {
    scene_text(object, EYE.map(|c| c * half / 1.2), [0.0; 3], half)
}

/// The beam image of a scene that must render.
fn image(name: &str, r: Rendered) -> RenderOutput {
    r.beam.unwrap_or_else(|e| panic!("{name}: {e}"))
}

// ------------------------------------------------------ huge frequencies

#[test]
fn huge_frequencies_render_in_time() {
    // sin(1e300·x) has about 1e300 periods per unit, far below any
    // rounding: every interval wider than a point gives [−1, 1], so
    // bisection never decides and only the loop bounds stop it.
    for object in [
        "sin(1e300*x) + y*y + z*z - 1",
        "sin(1e300*x) + y",
        "sin(1e300*x*y*z) + x*x + y*y + z*z - 1",
        "x*x + y*y + z*z - 1 + 0.001*sin(1e300*(x + y + z))",
        "sin(1.7e308*x) * cos(1.7e308*y) - z",
    ] {
        let out = image(object, adversarial(object, &cube(object, 2.0)));
        // Everything in view is somewhere within reach of f ≤ 0 (the
        // sine takes −1 arbitrarily close to every point), so something
        // is drawn: an empty image would have thrown real surface away.
        assert!(count(&out.hit_mask) > 100, "{object}: nearly nothing drawn");
    }
}

// ---------------------------------------------------- huge coefficients

#[test]
fn coefficients_near_the_largest_f64_render_in_time() {
    for object in [
        "1.7e308*x*x + y - 1",
        "1.7976931348623157e308*x - 1.7976931348623157e308*y",
        "(1e200*x)*(1e200*y) + z",
    ] {
        let out = image(object, adversarial(object, &cube(object, 2.0)));
        assert!(count(&out.hit_mask) > 0, "{object}: nothing drawn");
    }
    // Two of them with a known shape: the products overflow to ±inf away
    // from the surface, which must only make the sign easier to decide.
    let half_space = "x*1e308 - 1e308";
    let src = cube(half_space, 2.0);
    let scene = load(half_space, &src);
    let out = image(half_space, adversarial(half_space, &src));
    let want = analytic(&scene, SIDE, SIDE, |o, d, t0, t1| {
        (o[0] + t0 * d[0]).min(o[0] + t1 * d[0]) <= 1.0
    });
    assert_matches(half_space, &out.hit_mask, &want);
    let ball = "1e308*(x*x + y*y + z*z) - 1e308";
    let src = cube(ball, 2.0);
    let scene = load(ball, &src);
    let out = image(ball, adversarial(ball, &src));
    let want = analytic(&scene, SIDE, SIDE, |o, d, t0, t1| {
        ray_meets_ball(o, d, t0, t1, [0.0; 3], 1.0)
    });
    assert_matches(ball, &out.hit_mask, &want);
}

#[test]
fn sphere_scaled_by_1e150_renders_in_time_and_1e300_is_refused() {
    // Camera, bounds and sphere all 1e150 across: the squares in the
    // formula reach 1e301, near the top of the f64 range.
    for object in ["scale(sphere(1), 1e150)", "x*x + y*y + z*z - 1e300"] {
        let src = cube(object, 1.2e150);
        let scene = load(object, &src);
        let out = image(object, adversarial(object, &src));
        let want = analytic(&scene, SIDE, SIDE, |o, d, t0, t1| {
            ray_meets_ball(o, d, t0, t1, [0.0; 3], 1e150)
        });
        assert_matches(object, &out.hit_mask, &want);
    }
    // At 1e300 the camera itself cannot be set up: the squared length of
    // eye − target overflows. The loader refuses it with a diagnostic on
    // the camera (its wording, "`up` is zero or parallel to the view
    // direction", comes from the overflowed norms), not a panic.
    let err = ibeam::lang::load_scene_source("huge.ib", &cube("scale(sphere(1), 1e300)", 1.2e300))
        .expect_err("a camera 1e300 away is refused");
    assert!(err.to_string().contains("camera"), "{err}");
}

// ---------------------------------------------------------- tiny objects

#[test]
fn objects_1e_300_wide_render_in_time() {
    // A ball of radius 1e-300 at the centre of a unit view: far below a
    // pixel, so at most the few pixels whose footprint holds the origin
    // may be drawn (x*x underflows to 0 near it, which only widens the
    // ball to ~1e-154).
    for object in ["sqrt(x*x + y*y + z*z) - 1e-300", "sphere(1e-300)"] {
        let out = image(object, adversarial(object, &cube(object, 1.2)));
        assert!(
            count(&out.hit_mask) <= 4,
            "{object}: {} pixels",
            count(&out.hit_mask)
        );
    }
}

#[test]
fn slab_1e_300_thick_is_found_by_every_ray_that_crosses_it() {
    // A slab 2e-300 thick around the plane x = 0, seen obliquely: no
    // sampler would ever land in it, the guaranteed tracer must draw
    // every pixel whose ray crosses the plane inside the bounds.
    let object = "abs(x) - 1e-300";
    let src = cube(object, 1.2);
    let scene = load(object, &src);
    let out = image(object, adversarial(object, &src));
    let want = analytic(&scene, SIDE, SIDE, |o, d, t0, t1| {
        let x0 = o[0] + t0 * d[0];
        let x1 = o[0] + t1 * d[0];
        x0 * x1 <= 0.0
    });
    assert_matches(object, &out.hit_mask, &want);
}

#[test]
fn scene_1e_160_across_renders_in_time_and_1e_300_is_refused() {
    // Camera, bounds and sphere all 1e-160 across: squares of coordinates
    // (and the sphere's constant 1e-320) are subnormal, ray offsets and
    // depth tolerances tiny, which must not stall a bisection. The image
    // is not resolved: the depth tolerance and the slab padding have
    // absolute floors of 1e-9 world units (docs/stability.md, "extreme
    // scales"), so at the time of writing every pixel is drawn. What the
    // guarantee still demands is that no pixel whose every probe ray
    // meets the ball is missed.
    for object in ["scale(sphere(1), 1e-160)", "x*x + y*y + z*z - 1e-320"] {
        let src = cube(object, 1.2e-160);
        let scene = load(object, &src);
        let out = image(object, adversarial(object, &src));
        let r = if object.starts_with("scale") {
            1e-160
        } else {
            1e-320_f64.sqrt()
        };
        // In units of r (the helper's 1/r² would overflow): p = o + t·d
        // meets the ball iff o/r + (t/r)·d meets the unit ball.
        let want = analytic(&scene, SIDE, SIDE, |o, d, t0, t1| {
            ray_meets_ball(o.map(|c| c / r), d, t0 / r, t1 / r, [0.0; 3], 1.0)
        });
        let missed: Vec<usize> = (0..want.len())
            .filter(|&k| want[k] == Some(true) && !out.hit_mask[k])
            .collect();
        assert!(missed.is_empty(), "{object}: misses {missed:?}");
        let hits = want.iter().filter(|&&w| w == Some(true)).count();
        assert!(hits > 500, "{object}: only {hits} decided hits");
    }
    // At 1e-300 the squared length of eye − target underflows to 0: the
    // loader refuses the camera ("`eye` and `target` are the same
    // point"), not a panic.
    let err =
        ibeam::lang::load_scene_source("tiny.ib", &cube("scale(sphere(1), 1e-300)", 1.2e-300))
            .expect_err("a camera 1e-300 away is refused");
    assert!(err.to_string().contains("camera"), "{err}");
}

// ------------------------------------------------- undefined almost everywhere

/// Whether the ray crosses the plane x = 0 within [t0, t1] at a point
/// with y ≤ `ymax`.
fn crosses_x0_below(o: [f64; 3], d: [f64; 3], t0: f64, t1: f64, ymax: f64) -> bool {
    if d[0] == 0.0 {
        return false;
    }
    let t = -o[0] / d[0];
    t >= t0 && t <= t1 && o[1] + t * d[1] <= ymax
}

#[test]
fn functions_defined_on_a_point_or_a_line_render_in_time() {
    // Each is defined only on a set of measure zero, where it is ≤ 0
    // somewhere; intervals straddling that set are not EMPTY, so nothing
    // is refused up front and the tracer has to settle each ray by its
    // own bounds. No pixel ray passes exactly through the origin or along
    // the x axis (64 is even), so nothing is drawn.
    for object in [
        // Defined only at the origin, where it is 0.
        "sqrt(-x*x - y*y - z*z)",
        // Defined only on the x axis, where it is x.
        "sqrt(-abs(y) - abs(z)) + x",
    ] {
        let out = image(object, adversarial(object, &cube(object, 1.2)));
        assert_eq!(count(&out.hit_mask), 0, "{object}");
    }
}

#[test]
fn functions_defined_on_a_plane_draw_the_plane_in_time() {
    // Defined only on the plane x = 0: ln(−0) = −inf there, so the whole
    // plane is solid; sqrt(−0) + y = y, so the half-plane y ≤ 0 is. Rays
    // cross the plane at one point each, which the guaranteed tracer must
    // find, as for the slab 1e-300 thick.
    for (object, ymax) in [("ln(-abs(x)) + y", f64::INFINITY), ("sqrt(-x*x) + y", 0.0)] {
        let src = cube(object, 1.2);
        let scene = load(object, &src);
        let out = image(object, adversarial(object, &src));
        let want = analytic(&scene, SIDE, SIDE, |o, d, t0, t1| {
            crosses_x0_below(o, d, t0, t1, ymax)
        });
        assert_matches(object, &out.hit_mask, &want);
    }
}

#[test]
fn functions_undefined_everywhere_are_refused_in_time() {
    // Undefined at every point of the bounds, and the interval over the
    // whole bounds proves it: the render says so, the same for every
    // method, rather than drawing an empty image.
    for object in [
        "sqrt(x - 1e300)",
        "sqrt(-1 - x*x - y*y - z*z)",
        "ln(-1 - abs(x)) + y",
    ] {
        match adversarial(object, &cube(object, 1.2)).beam {
            Err(RenderError::Undefined(name)) => assert_eq!(name, "s"),
            Err(e) => panic!("{object}: unexpected error {e}"),
            Ok(out) => panic!("{object}: rendered {} pixels", count(&out.hit_mask)),
        }
    }
}

#[test]
fn cancellations_intervals_cannot_see_render_in_time() {
    // x − x is 0 at every point, but its interval over a box of width w is
    // [−w, w] (intervals do not know both operands are the same x), so
    // 1/(x − x) (+inf at every point: no solid) and (x − x)/(y − y) (NaN
    // at every point: undefined) are neither refused up front nor ever
    // excluded by a ray's intervals; likewise sqrt(x − x − 1e-300) + y,
    // undefined at every point. What is drawn is the tracer's conservative
    // answer: at the time of writing every pixel inside the bounds for the
    // first two and 2407 of 4096 for the third, where the true solid is
    // empty. The point of this test is that the bisections it takes to
    // get there stop, in time, the same way for beam and pixel, and
    // without a panic.
    for object in ["1/(x - x)", "(x - x)/(y - y)", "sqrt(x - x - 1e-300) + y"] {
        let r = adversarial(object, &cube(object, 1.2));
        if let Err(e) = &r.beam {
            assert!(matches!(e, RenderError::Undefined(_)), "{object}: {e}");
        }
    }
}
