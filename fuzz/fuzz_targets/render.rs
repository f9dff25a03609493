//! A small random scene, assembled as scene text from the fuzz bytes (a
//! grammar of the prelude's primitives, CSG ops and transforms, and of
//! expressions over the built-in functions), loaded, and rendered at
//! 16×16 with each method: beam, pixel and point sampling.
//!
//! Checked, as `tests/random_scenes.rs` checks its seeded scenes: the
//! loader never reports an "internal error" (its name for a panic); the
//! JIT accepts the lowered IR; a render is refused only with
//! `Undefined(name)` for an object whose interval over the whole bounds
//! is empty; no depth is NaN; neither guaranteed method misses a ray on
//! which point sampling found f <= 0; and beam and pixel draw exactly the
//! same hit mask. An IAA render (depth 2, threshold 1/4, so that pixels
//! split by shading alone are refined in their proven brackets) keeps
//! surface wherever the beam render's centre ray hit, has finite colours
//! and coverages in [0, 1]. Each render must also finish within a time
//! bound: a
//! 16×16 image that takes seconds is a hang in the making (libFuzzer's
//! own timeout is much longer).

#![no_main]

use std::time::{Duration, Instant};

use ibeam::eval::{EvalKind, Evaluator, build_evaluators};
use ibeam::interval::Interval;
use ibeam::render::{Aa, Method, RenderError, RenderOptions, RenderOutput, render, render_aa};
use libfuzzer_sys::fuzz_target;

/// Longest one 16×16 render may take. Generous: the build is
/// instrumented for coverage and the machine may be shared.
const TIME_BOUND: Duration = Duration::from_secs(5);

/// Choices read from the fuzz bytes; zeros once they run out, so every
/// input is a complete scene and short inputs give small scenes (zero
/// always picks a leaf).
struct Choices<'a>(&'a [u8]);

impl Choices<'_> {
    fn byte(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn below(&mut self, n: u8) -> u8 {
        self.byte() % n
    }

    /// A number in [lo, hi] on a grid of 256 steps, written as source
    /// text (negatives in parentheses, as a unary minus needs nothing
    /// else there).
    fn num(&mut self, lo: f64, hi: f64) -> String {
        let v = lo + (hi - lo) * f64::from(self.byte()) / 255.0;
        let v = (v * 100.0).round() / 100.0;
        if v < 0.0 {
            format!("({v})")
        } else {
            format!("{v}")
        }
    }
}

/// An expression over x, y, z and the built-in functions.
fn expr(c: &mut Choices, depth: u32) -> String {
    let k = c.below(16);
    if depth == 0 || k < 3 {
        return match c.below(5) {
            0 => "x".into(),
            1 => "y".into(),
            2 => "z".into(),
            _ => c.num(-2.0, 2.0),
        };
    }
    let d = depth - 1;
    match k {
        3..=5 => {
            let op = ["+", "-", "*", "/"][usize::from(c.below(4))];
            format!("({} {op} {})", expr(c, d), expr(c, d))
        }
        6..=8 => {
            let f = ["sqrt", "abs", "exp", "ln", "sin", "cos", "square"][usize::from(c.below(7))];
            format!("{f}({})", expr(c, d))
        }
        9 | 10 => {
            let f = if c.below(2) == 0 { "min" } else { "max" };
            format!("{f}({}, {})", expr(c, d), expr(c, d))
        }
        11 => format!("pow({}, {})", expr(c, d), c.num(-2.0, 3.0)),
        12 => format!("atan2({}, {})", expr(c, d), expr(c, d)),
        13 => format!("({})^{}", expr(c, d), i32::from(c.below(8)) - 2),
        _ => format!("-{}", expr(c, d)),
    }
}

/// A CSG tree over the prelude's primitives and transforms.
fn csg(c: &mut Choices, depth: u32) -> String {
    let k = c.below(16);
    if depth == 0 || k < 5 {
        return match c.below(7) {
            0 => format!("sphere({})", c.num(0.1, 1.2)),
            1 => format!(
                "box({}, {}, {})",
                c.num(0.1, 1.0),
                c.num(0.1, 1.0),
                c.num(0.1, 1.0)
            ),
            2 => format!("torus({}, {})", c.num(0.3, 1.0), c.num(0.05, 0.4)),
            3 => format!("cylinder({})", c.num(0.1, 1.0)),
            4 => format!(
                "plane({}, {}, {}, {})",
                c.num(-1.0, 1.0),
                c.num(0.1, 1.0),
                c.num(-1.0, 1.0),
                c.num(-1.0, 0.5)
            ),
            5 => format!(
                "ellipsoid({}, {}, {})",
                c.num(0.1, 1.0),
                c.num(0.1, 1.0),
                c.num(0.1, 1.0)
            ),
            _ => format!("capsule({}, {})", c.num(0.1, 1.0), c.num(0.1, 1.0)),
        };
    }
    let d = depth - 1;
    match k {
        5 | 6 => format!("union({}, {})", csg(c, d), csg(c, d)),
        7 => format!("intersect({}, {})", csg(c, d), csg(c, d)),
        8 => format!("difference({}, {})", csg(c, d), csg(c, d)),
        9 => format!("blend({}, {}, {})", csg(c, d), csg(c, d), c.num(0.01, 0.5)),
        10 => format!(
            "translate({}, {}, {}, {})",
            csg(c, d),
            c.num(-0.8, 0.8),
            c.num(-0.8, 0.8),
            c.num(-0.8, 0.8)
        ),
        11 => format!("scale({}, {})", csg(c, d), c.num(0.3, 2.0)),
        12 => {
            let f = ["rotate_x", "rotate_y", "rotate_z"][usize::from(c.below(3))];
            format!("{f}({}, {})", csg(c, d), c.num(-180.0, 180.0))
        }
        13 => format!("complement({})", csg(c, d)),
        // A CSG shape perturbed by an expression: surfaces of any kind
        // near real objects.
        14 => format!("{} + 0.2*({})", csg(c, d), expr(c, 3)),
        _ => format!("union({}, {}, {})", csg(c, d), csg(c, d), csg(c, d)),
    }
}

/// The whole scene text: one to three objects, a camera on a sphere
/// around the origin (perspective or orthographic), optional shadows.
fn scene_source(c: &mut Choices) -> String {
    let n = 1 + c.below(3);
    let mut text = String::new();
    for i in 0..n {
        let src = match c.below(4) {
            0 => expr(c, 4),
            1 => format!("x^2 + y^2 + z^2 - 1 + 0.3*({})", expr(c, 3)),
            _ => csg(c, 4),
        };
        text += &format!("object o{i} = {src};\n");
    }
    // Never straight above or below: the up vector is y.
    let th = f64::from(c.byte()) / 256.0 * std::f64::consts::TAU;
    let el = (f64::from(c.byte()) / 255.0 - 0.5) * 2.4;
    let r = 2.5 + f64::from(c.below(4));
    let eye = [
        r * el.cos() * th.cos(),
        r * el.sin(),
        r * el.cos() * th.sin(),
    ];
    let lens = if c.below(4) == 0 {
        format!("ortho = {};", c.num(0.5, 5.0))
    } else {
        format!("fov = {};", c.num(10.0, 90.0))
    };
    let shadows = c.below(2) == 0;
    text += &format!(
        "camera {{ eye = ({}, {}, {}); target = (0, 0, 0); {lens} }}\n\
         bounds = (-1.5, -1.5, -1.5) .. (1.5, 1.5, 1.5);\n\
         light {{ direction = (-0.5, -1, -0.7); shadows = {shadows}; }}\n",
        eye[0], eye[1], eye[2]
    );
    text
}

/// One render, failing if it takes longer than [`TIME_BOUND`].
fn timed(
    scene: &ibeam::scene::Scene,
    evals: &[std::sync::Arc<dyn Evaluator>],
    (method, aa): (Method, Aa),
    text: &str,
) -> Result<RenderOutput, RenderError> {
    let opts = RenderOptions {
        // One thread: the fuzzer runs one input at a time, and the
        // output does not depend on the thread count.
        threads: Some(1),
        method,
        ..RenderOptions::new(16, 16)
    };
    let start = Instant::now();
    let out = match aa {
        Aa::None => render(scene, evals, &opts),
        _ => render_aa(scene, evals, &opts, aa),
    };
    let took = start.elapsed();
    assert!(
        took <= TIME_BOUND,
        "{method:?} {aa:?} render took {took:?} (bound {TIME_BOUND:?})\n{text}"
    );
    out
}

fuzz_target!(|data: &[u8]| {
    let text = scene_source(&mut Choices(data));
    let scene = match ibeam::lang::load_scene_source("fuzz.ib", &text) {
        Ok(s) => s,
        Err(e) => {
            assert!(
                !e.message.contains("internal error"),
                "loader panicked: {e}\n{text}"
            );
            return;
        }
    };
    let evals = build_evaluators(&scene, EvalKind::Jit).expect("JIT accepts valid IR");
    let beam = match timed(&scene, &evals, (Method::Beam, Aa::None), &text) {
        Ok(out) => out,
        Err(RenderError::Undefined(name)) => {
            // Only an object proven undefined on the whole bounds may be
            // refused.
            let k = scene.objects.iter().position(|o| o.name == name).unwrap();
            let b = scene.bounds;
            let whole = [0, 1, 2].map(|i| Interval::new(b.min[i], b.max[i]));
            assert!(evals[k].interval(whole).is_empty(), "{name}\n{text}");
            return;
        }
        Err(e) => panic!("beam: {e}\n{text}"),
    };
    let pixel = timed(&scene, &evals, (Method::Pixel, Aa::None), &text)
        .unwrap_or_else(|e| panic!("pixel failed where beam rendered: {e}\n{text}"));
    for (k, &t) in beam.depth_t.iter().chain(&pixel.depth_t).enumerate() {
        assert!(!t.is_nan(), "NaN depth at {k}\n{text}");
    }
    let march = timed(
        &scene,
        &evals,
        (Method::Point { steps: 200 }, Aa::None),
        &text,
    )
    .unwrap_or_else(|e| panic!("point failed where beam rendered: {e}\n{text}"));
    // Point sampling finds real points with f <= 0; a guaranteed method
    // may not miss such a ray.
    for (name, out) in [("beam", &beam), ("pixel", &pixel)] {
        let missed: Vec<usize> = (0..out.hit_mask.len())
            .filter(|&k| march.hit_mask[k] && !out.hit_mask[k])
            .collect();
        assert!(
            missed.is_empty(),
            "{name} misses point-sampled hits at {missed:?}\n{text}"
        );
    }
    let diff: Vec<usize> = (0..beam.hit_mask.len())
        .filter(|&k| beam.hit_mask[k] != pixel.hit_mask[k])
        .collect();
    assert!(diff.is_empty(), "beam and pixel differ at {diff:?}\n{text}");
    let aa = Aa::Iaa {
        threshold: 0.25,
        depth: 2,
    };
    let iaa = timed(&scene, &evals, (Method::Beam, aa), &text)
        .unwrap_or_else(|e| panic!("IAA failed where beam rendered: {e}\n{text}"));
    for k in 0..iaa.coverage.len() {
        let c = iaa.coverage[k];
        assert!((0.0..=1.0).contains(&c), "coverage {c} at {k}\n{text}");
        assert!(
            !beam.hit_mask[k] || c > 0.0,
            "IAA lost the centre ray's surface at {k}\n{text}"
        );
        assert!(
            iaa.linear[k].iter().all(|v| v.is_finite()),
            "IAA colour at {k}\n{text}"
        );
    }
});
