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
//!
//! One test binary; the cases are in its modules.

mod adversarial;
mod extremes;
mod jumps;
#[path = "../common/models.rs"]
mod models;
mod singular;

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

/// The scene of `src`, which must load.
fn load(name: &str, src: &str) -> Scene {
    ibeam::lang::load_scene_source(name, src).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The scene of examples/`name`, which must load.
fn load_example(name: &str) -> Scene {
    let path = format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR"));
    ibeam::lang::load_scene(std::path::Path::new(&path)).unwrap_or_else(|e| panic!("{e}"))
}

/// Renders `scene` at `w × h` by `method` with the JIT.
fn render_with(scene: &Scene, w: u32, h: u32, method: Method) -> RenderOutput {
    render_by(scene, &evaluators(scene), w, h, method)
}

/// Renders `scene` with `evals`, depths and normals on, checking the output is free of NaN.
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

/// The beam render of `scene` at `w × h`.
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

/// How many pixels of `mask` are set.
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

/// The dot product of two vectors.
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

/// Scene text for `object` seen from `eye`, in the cube of half-side `bounds`.
fn scene_text(object: &str, eye: [f64; 3], target: [f64; 3], bounds: f64) -> String {
    scene_text_box(object, eye, target, [-bounds; 3], [bounds; 3])
}

/// Scene text for `object` seen from `eye`, in the box `lo .. hi`.
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

/// Where the camera of most cases stands.
const EYE: [f64; 3] = [2.0, 1.5, 3.5];
