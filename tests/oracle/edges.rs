//! Solids bounded by domain edges and jumps against the same solids
//! written without them: their shadows (and everything else) must match,
//! with and without IAA, at 256².

use std::sync::Arc;

use ibeam::eval::{EvalKind, Evaluator, build_evaluators};
use ibeam::render::{Aa, RenderOptions, RenderOutput, render_aa};
use ibeam::scene::Scene;

use super::certify::{Oracle, at};

/// A solid written with a domain edge or a jump, and the same solid
/// written with `abs`, `min` and `max` only.
struct Pair {
    name: &'static str,
    edge: &'static str,
    plain: &'static str,
    light: &'static str,
    /// The face is a jump (f defined on both sides): light passing
    /// through a gap at the jump need not be proven (the enclosure over a
    /// box straddling the jump takes both sides' values at once), so only
    /// leaks are counted.
    jump: bool,
}

const PAIRS: [Pair; 6] = [
    // The three of the issue: a slab whose lower face is sqrt's edge
    // (y < 0.24 where sqrt(y - 0.2) < 0.2), a disc whose lower face is
    // ln's (y + 0.3 < e^-2.5), a dome whose inner face is asin's
    // (0.6 ≤ r < 1.6 - sin 1.5).
    Pair {
        name: "sqrt slab",
        edge: "max(max(sqrt(y - 0.2) - 0.2, abs(x) - 0.6), abs(z) - 0.6)",
        plain: "max(max(abs(y - 0.22) - 0.02, abs(x) - 0.6), abs(z) - 0.6)",
        light: "direction = (0, -1, 0)",
        jump: false,
    },
    Pair {
        name: "ln disc",
        edge: "max(ln(y + 0.3) + 2.5, sqrt(x*x + z*z) - 0.7)",
        plain: "max(abs(y + 0.3 - 0.04104249931194940) - 0.04104249931194940, sqrt(x*x + z*z) - 0.7)",
        light: "direction = (0.5, -1, 0.3)",
        jump: false,
    },
    Pair {
        name: "asin dome",
        edge: "max(1.5 - asin(1.6 - sqrt(x*x + y*y + z*z)), -y)",
        plain: "max(abs(sqrt(x*x + y*y + z*z) - 0.6012525066979728) - 0.0012525066979728, -y)",
        light: "direction = (0.3, -1, -0.2)",
        jump: false,
    },
    // acos's edge at y = 0.2 (1.2 - y ≤ 1), the top at 1.2 - cos 0.5.
    Pair {
        name: "acos slab",
        edge: "max(acos(1.2 - y) - 0.5, abs(x) - 0.6, abs(z) - 0.6)",
        plain: "max(abs(y - 0.2612087190548136) - 0.0612087190548136, abs(x) - 0.6, abs(z) - 0.6)",
        light: "direction = (-0.4, -1, 0.2)",
        jump: false,
    },
    // A pole: -1/(y - 0.2) - 10 jumps from +inf to -inf at y = 0.2 (and
    // is negative again below y = 0.1, which 0.15 - y cuts off).
    Pair {
        name: "pole slab",
        edge: "max(-1/(y - 0.2) - 10, abs(x) - 0.6, abs(z) - 0.6, y - 0.35, 0.15 - y)",
        plain: "max(abs(y - 0.275) - 0.075, abs(x) - 0.6, abs(z) - 0.6)",
        light: "direction = (0.2, -1, 0.5)",
        jump: false,
    },
    // Stairs from floor's jumps, and the same four boxes side by side.
    Pair {
        name: "floor stairs",
        edge: "max(abs(y - 0.1*floor(3*x) - 0.2) - 0.03, abs(x) - 0.6, abs(z) - 0.6)",
        plain: "min(max(abs(y) - 0.03, abs(x + 0.4666666666666667) - 0.13333333333333333, abs(z) - 0.6), \
                max(abs(y - 0.1) - 0.03, abs(x + 0.16666666666666666) - 0.16666666666666666, abs(z) - 0.6), \
                max(abs(y - 0.2) - 0.03, abs(x - 0.16666666666666666) - 0.16666666666666666, abs(z) - 0.6), \
                max(abs(y - 0.3) - 0.03, abs(x - 0.4666666666666667) - 0.13333333333333333, abs(z) - 0.6))",
        light: "direction = (0.6, -1, -0.3)",
        jump: true,
    },
];

fn scene_text(solid: &str, light: &str) -> String {
    format!(
        "object solid = {solid};\nobject floor = y + 1;\n\
         camera {{ eye = (2.2, 3.4, 3.0); target = (0, -0.5, 0); up = (0, 1, 0); ortho = 4.5; }}\n\
         bounds = (-2, -1.5, -2) .. (2, 1, 2);\n\
         light {{ {light}; color = (1, 1, 1); shadows = true; }}\n"
    )
}

fn rendered(text: &str, aa: Aa) -> (Scene, RenderOutput) {
    let scene = ibeam::lang::load_scene_source("edge.ib", text).expect("scene loads");
    let evals: Vec<Arc<dyn Evaluator>> = build_evaluators(&scene, EvalKind::Jit).expect("valid IR");
    let out = render_aa(&scene, &evals, &RenderOptions::new(SIZE, SIZE), aa).expect("renders");
    (scene, out)
}

/// Image side.
const SIZE: u32 = 256;

/// Over the pixels whose centre ray hits the floor in both renders: those
/// lit in `edge` and dark in `plain` (light leaking through a domain
/// edge), and those whose shading differs either way; and the number of
/// floor pixels dark in `plain`. Solids' own faces are left out: at a jump
/// the gradient, and so the normal, is the one of either side.
fn floor_differences(scene: &Scene, edge: &RenderOutput, plain: &RenderOutput) -> [usize; 3] {
    let o = Oracle::new(scene, SIZE, SIZE);
    let on_floor = |out: &RenderOutput, k: usize| {
        let (i, j) = (k as u32 % SIZE, k as u32 / SIZE);
        let y = at(o.origin(i, j), o.dir(), out.depth_t[k])[1];
        (y + 1.0).abs() < 1e-3
    };
    let (mut leaks, mut differ, mut dark) = (0, 0, 0);
    for k in 0..edge.linear.len() {
        if !(on_floor(edge, k) && on_floor(plain, k)) {
            continue;
        }
        let (a, b) = (edge.linear[k][0], plain.linear[k][0]);
        leaks += usize::from(a > b + 0.1);
        differ += usize::from((a - b).abs() > 0.1);
        dark += usize::from(b < 0.1);
    }
    [leaks, differ, dark]
}

#[test]
fn domain_edges_shadow_like_their_edge_free_forms() {
    let iaa = Aa::Iaa {
        threshold: 1.0 / 64.0,
        depth: 2,
    };
    let mut report = Vec::new();
    for p in &PAIRS {
        for (mode, aa) in [("plain", Aa::None), ("iaa", iaa)] {
            let (scene, edge) = rendered(&scene_text(p.edge, p.light), aa);
            let (_, plain) = rendered(&scene_text(p.plain, p.light), aa);
            let [leaks, differ, dark] = floor_differences(&scene, &edge, &plain);
            // Each solid casts a shadow on the floor.
            assert!(
                dark > 200,
                "{} ({mode}): {dark} floor pixels in shadow",
                p.name
            );
            if leaks > 0 || (differ > 3 && !p.jump) {
                report.push(format!(
                    "{} ({mode}): {leaks} floor pixels leak light, {differ} differ",
                    p.name
                ));
            }
        }
    }
    assert!(report.is_empty(), "{}", report.join("\n"));
}
