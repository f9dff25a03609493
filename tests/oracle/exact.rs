//! Shadows against exact geometry: a union of 300 small spheres (every
//! hit's true position and every blocking chord solved in closed form),
//! and a plate thinner than half a pixel hovering closer than half a pixel
//! above a floor. A hit is blocked when its segment to the light passes
//! deeper inside a sphere (or the plate) than the margin allowed for the
//! renderer's hit being off the true one; every blocked hit must be drawn
//! dark. Before shadow segments started at the root bracket's front end
//! (they started half a pixel off the surface), both tests failed.

use std::sync::Arc;

use ibeam::eval::{EvalKind, Evaluator, build_evaluators};
use ibeam::ir::random::Rng;
use ibeam::render::{Aa, RenderOptions, RenderOutput, render_aa};
use ibeam::scene::Scene;

use super::certify::{Oracle, at, dot3};

type Vec3 = [f64; 3];

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Where the ray `o + t·d` (unit `d`) first meets the sphere, if it does.
fn ray_sphere(o: Vec3, d: Vec3, c: Vec3, r: f64) -> Option<f64> {
    let oc = sub(o, c);
    let b = dot3(oc, d);
    let disc = b * b - (dot3(oc, oc) - r * r);
    (disc >= 0.0)
        .then(|| -b - disc.sqrt())
        .filter(|&t| t >= 0.0)
}

/// How deep inside the sphere the half-line `p + s·l` (s > 0, unit `l`)
/// passes: the radius minus its distance from the centre (negative: it
/// misses).
fn depth_inside(p: Vec3, l: Vec3, c: Vec3, r: f64) -> f64 {
    let pc = sub(c, p);
    let s = dot3(pc, l).max(0.0);
    let q = sub(pc, l.map(|v| v * s));
    r - dot3(q, q).sqrt()
}

const SIZE: u32 = 96;

fn render_scene(text: &str, aa: Aa) -> (Scene, RenderOutput) {
    let scene = ibeam::lang::load_scene_source("exact.ib", text).expect("loads");
    let evals: Vec<Arc<dyn Evaluator>> = build_evaluators(&scene, EvalKind::Jit).expect("valid IR");
    let out = render_aa(&scene, &evals, &RenderOptions::new(SIZE, SIZE), aa).expect("renders");
    (scene, out)
}

/// The ambient-only colour of an object of colour 0.8: what a shadowed
/// hit is drawn with (lit ones facing the light are far brighter).
const DARK: f32 = 0.08 + 0.02;

#[test]
fn no_hit_a_sphere_blocks_is_drawn_lit() {
    let mut rng = Rng::new(300);
    let r = 0.05;
    let centres: Vec<Vec3> = (0..300)
        .map(|_| std::array::from_fn(|_| rng.range(-1.0, 1.0)))
        .collect();
    let terms: Vec<String> = centres
        .iter()
        .map(|c| {
            format!(
                "sqrt((x - {:?})^2 + (y - {:?})^2 + (z - {:?})^2) - {r:?}",
                c[0], c[1], c[2]
            )
        })
        .collect();
    let text = format!(
        "object balls = min({});\n\
         camera {{ eye = (0.3, 4, 0.5); target = (0, 0, 0); up = (0, 0, -1); ortho = 2.6; }}\n\
         bounds = (-1.2, -1.2, -1.2) .. (1.2, 1.2, 1.2);\n\
         light {{ direction = (-0.3, -1, 0.2); color = (1, 1, 1); shadows = true; }}\n",
        terms.join(", ")
    );
    // Without anti-aliasing: IAA splits nearly every pixel of balls two
    // pixels across, whose mean colours this test cannot read.
    {
        let aa = Aa::None;
        let (scene, out) = render_scene(&text, aa);
        let o = Oracle::new(&scene, SIZE, SIZE);
        let l = {
            let d = [0.3, 1.0, -0.2];
            let n = dot3(d, d).sqrt();
            d.map(|v| v / n)
        };
        let (mut blocked, mut leaks) = (0, Vec::new());
        for j in 0..SIZE {
            for i in 0..SIZE {
                let k = (j * SIZE + i) as usize;
                let (ro, d) = (o.origin(i, j), o.dir());
                let hit = centres
                    .iter()
                    .filter_map(|&c| ray_sphere(ro, d, c, r).map(|t| (t, c)))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                let (Some((t, own)), true) = (hit, out.samples[k] <= 1) else {
                    continue;
                };
                let t_r = out.depth_t[k];
                // The margin: how far the renderer's hit is from the true
                // one, plus the refinement tolerance (a 64th of a pixel).
                let margin = (t_r - t).abs() + o.pixel / 64.0;
                let p = at(ro, d, t);
                let n = sub(p, own).map(|v| v / r);
                if dot3(n, l) <= 0.05 {
                    continue;
                }
                if centres
                    .iter()
                    .any(|&c| depth_inside(p, l, c, r) > margin && c != own)
                {
                    blocked += 1;
                    if out.linear[k][0] > DARK {
                        leaks.push((i, j, out.linear[k][0]));
                    }
                }
            }
        }
        assert!(blocked > 100, "{aa:?}: only {blocked} blocked hits");
        assert!(
            leaks.is_empty(),
            "{aa:?}: {} of {blocked} blocked hits drawn lit: {leaks:?}",
            leaks.len()
        );
    }
}

#[test]
fn a_plate_thinner_and_closer_than_half_a_pixel_casts_its_shadow() {
    // The plate covers x < 0 for 0.005 < y < 0.007; seen from +x above,
    // a pixel is about 0.03 wide, and half a pixel off the floor a
    // segment would start above the plate. Light from -x, low: a floor
    // point is blocked for x < 0.07 (at y = 0.005 the segment is 0.05 to
    // its left, at y = 0.007 0.07).
    let text = "object floor = y;\n\
                object plate = max(abs(y - 0.006) - 0.001, x, abs(z) - 0.8);\n\
                camera { eye = (3, 3, 1); target = (0.2, 0, 0); up = (0, 1, 0); ortho = 3; }\n\
                bounds = (-1, -0.5, -1) .. (1.5, 0.5, 1);\n\
                light { direction = (1, -0.1, 0); color = (1, 1, 1); shadows = true; }\n";
    for aa in [
        Aa::None,
        Aa::Iaa {
            threshold: 1.0 / 64.0,
            depth: 2,
        },
    ] {
        let (scene, out) = render_scene(text, aa);
        let o = Oracle::new(&scene, SIZE, SIZE);
        let (mut shadowed, mut lit, mut wrong) = (0, 0, Vec::new());
        for k in 0..(SIZE * SIZE) as usize {
            let (i, j) = (k as u32 % SIZE, k as u32 / SIZE);
            // Where the pixel's centre ray meets the floor (in front of
            // the plate there, which lies at x < 0).
            let (ro, d) = (o.origin(i, j), o.dir());
            let p = at(ro, d, -ro[1] / d[1]);
            if p[2].abs() > 0.7 || !out.hit_mask[k] {
                continue;
            }
            // A pixel split by IAA is read by its mean: half way between
            // the floor's dark and lit colours (0.08 and 0.16).
            let c = out.linear[k][0];
            let dark = if out.samples[k] > 1 {
                c < 0.12
            } else {
                c <= DARK
            };
            if p[0] > 0.0 && p[0] < 0.04 {
                shadowed += 1;
                if !dark {
                    wrong.push((i, j, p[0], c));
                }
            } else if p[0] > 0.12 && p[0] < 1.4 {
                lit += 1;
                if dark {
                    wrong.push((i, j, p[0], c));
                }
            }
        }
        assert!(
            shadowed > 20 && lit > 500,
            "{aa:?}: {shadowed} shadowed, {lit} lit"
        );
        assert!(wrong.is_empty(), "{aa:?}: {wrong:?}");
    }
}

/// The expanded `(u - 1)^10` of `u`, its terms written out (they cancel:
/// intervals overestimate it by orders of magnitude).
fn expanded_tenth_power(u: &str) -> String {
    let binomial = [1, 10, 45, 120, 210, 252, 210, 120, 45, 10, 1];
    let terms: Vec<String> = (0..=10)
        .map(|k| {
            let sign = if (10 - k) % 2 == 0 { "" } else { "-" };
            format!("{sign}{}*{u}^{k}", binomial[k])
        })
        .collect();
    format!("({})", terms.join(" + "))
}

#[test]
fn a_thin_expanded_rod_casts_its_shadow_and_nothing_else_does() {
    // The rod (x^10, expanded in u = x + 1) + (y - 0.3)^2 + z^2 <= 0.0009
    // hangs 0.3 above the floor. Light comes from (-0.5, 1, 0), so the
    // segment of a floor point (x, 0, z) passes (x - 0.5y, y, z): blocked
    // where (x - 0.15)^10 + z^2 <= 0.0009 at y = 0.3 (|z| < 0.0299 for
    // |x - 0.15| < 0.3), never where z^2 > 0.0009. The segments run along
    // x, over which intervals cannot prove the rod absent (its
    // expansion cancels), so without the second-order forms along shadow
    // segments most of the floor near it was drawn shadowed; and the
    // forms must keep every part of a segment where the rod may lie.
    let rod = expanded_tenth_power("(x + 1)");
    let text = format!(
        "object floor = y;\n\
         object rod = {rod} + (y - 0.3)^2 + z^2 - 0.0009;\n\
         camera {{ eye = (0.4, 3, 2.2); target = (0, 0, 0); up = (0, 1, 0); ortho = 1.6; }}\n\
         bounds = (-1, -0.2, -1) .. (1, 0.5, 1);\n\
         light {{ direction = (0.5, -1, 0); color = (1, 1, 1); shadows = true; }}\n"
    );
    let (scene, out) = render_scene(&text, Aa::None);
    let o = Oracle::new(&scene, SIZE, SIZE);
    let (mut shadowed, mut lit, mut wrong) = (0, 0, Vec::new());
    for k in 0..(SIZE * SIZE) as usize {
        let (i, j) = (k as u32 % SIZE, k as u32 / SIZE);
        let (ro, d) = (o.origin(i, j), o.dir());
        let t = -ro[1] / d[1];
        let p = at(ro, d, t);
        // Floor hits only (the rod hides part of the floor).
        if !out.hit_mask[k] || (out.depth_t[k] - t).abs() > 1e-3 || p[0].abs() > 0.7 {
            continue;
        }
        let dark = out.linear[k][0] <= DARK;
        if (p[0] - 0.15).abs() < 0.3 && p[2].abs() < 0.025 {
            shadowed += 1;
            if !dark {
                wrong.push((i, j, p, "lit"));
            }
        } else if p[2].abs() > 0.05 && p[2].abs() < 0.7 {
            lit += 1;
            if dark {
                wrong.push((i, j, p, "dark"));
            }
        }
    }
    assert!(
        shadowed >= 8 && lit > 1000,
        "{shadowed} shadowed, {lit} lit"
    );
    assert!(
        wrong.is_empty(),
        "{} wrong: {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(5)]
    );
    assert!(out.stats.affine_shadow_tries > 0, "{}", out.stats);
}
