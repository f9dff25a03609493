//! Random 2D models seen along their missing axis (flat scenes), which the
//! beam tracer settles as a quadtree of screen rectangles with no search
//! along the rays (`render::plane`): it must draw exactly the pixels that
//! single interval rays draw (`Method::Pixel`), hit for hit: the same
//! masks, depths, objects and colours. The formulas mix partial functions
//! (sqrt, ln, division, pow) into min/max trees, so some pixels' start
//! values are undefined; scenes have one to three objects, so the object
//! hit is chosen among several.

mod common;

use common::source_number as num;
use ibeam::eval::{EvalKind, build_evaluators};
use ibeam::ir::random::Rng;
use ibeam::render::{Aa, Method, RenderError, RenderOptions, is_flat, render, render_aa};

/// A random expression over the two variables `vars`.
fn expr(rng: &mut Rng, vars: [&str; 2], depth: u32) -> String {
    if depth == 0 || rng.chance(0.2) {
        return match rng.below(4) {
            0 => vars[0].into(),
            1 => vars[1].into(),
            _ => num(rng.range(-2.0, 2.0)),
        };
    }
    let d = depth - 1;
    match rng.below(12) {
        0..=3 => {
            let op = rng.pick(&["+", "-", "*", "/"]);
            format!("({} {op} {})", expr(rng, vars, d), expr(rng, vars, d))
        }
        4..=6 => {
            let f = rng.pick(&["sqrt", "abs", "ln", "sin", "square"]);
            format!("{f}({})", expr(rng, vars, d))
        }
        7..=9 => {
            let f = rng.pick(&["min", "max"]);
            format!("{f}({}, {})", expr(rng, vars, d), expr(rng, vars, d))
        }
        10 => format!("pow({}, {})", expr(rng, vars, d), num(rng.range(-2.0, 3.0))),
        _ => format!("-{}", expr(rng, vars, d)),
    }
}

/// A disc or a box in the plane of `vars`, unions and differences of
/// them, or a free formula.
fn shape(rng: &mut Rng, vars: [&str; 2], depth: u32) -> String {
    let [u, v] = vars;
    if depth == 0 || rng.chance(0.3) {
        let (a, b) = (num(rng.range(-1.0, 1.0)), num(rng.range(-1.0, 1.0)));
        let r = num(rng.range(0.1, 0.8));
        return match rng.below(3) {
            0 => format!("sqrt(({u} - {a})^2 + ({v} - {b})^2) - {r}"),
            1 => format!("max(abs({u} - {a}), abs({v} - {b})) - {r}"),
            _ => format!("{u}^2 + {v}^2 - 1 + 0.3*({})", expr(rng, vars, 3)),
        };
    }
    let d = depth - 1;
    match rng.below(3) {
        0 => format!("min({}, {})", shape(rng, vars, d), shape(rng, vars, d)),
        1 => format!("max({}, -({}))", shape(rng, vars, d), shape(rng, vars, d)),
        _ => expr(rng, vars, 4),
    }
}

/// The scene text for a seed: objects over two of x, y, z, seen along the
/// third by an orthographic camera, with a shadow-casting light.
fn scene_source(seed: u64) -> String {
    let mut rng = Rng::new(seed);
    let (vars, eye, up) = match rng.below(3) {
        0 => (["x", "y"], "(0, 0, 4)", "(0, 1, 0)"),
        1 => (["x", "z"], "(0, 4, 0)", "(0, 0, -1)"),
        _ => (["y", "z"], "(-4, 0, 0)", "(0, 1, 0)"),
    };
    let mut text = String::new();
    for i in 0..1 + rng.below(3) {
        text += &format!("object o{i} = {};\n", shape(&mut rng, vars, 3));
    }
    text += &format!(
        "camera {{ eye = {eye}; target = (0, 0, 0); up = {up}; ortho = 3.4; }}\n\
         bounds = (-1.5, -1.5, -1.5) .. (1.5, 1.5, 1.5);\n\
         light {{ direction = (-0.5, -1, -0.7); shadows = true; }}\n"
    );
    text
}

/// Whether the scene of `seed` loaded and rendered, so its pixels were
/// compared (a generated scene may be refused, or undefined everywhere).
fn check_seed(seed: u64) -> bool {
    let text = scene_source(seed);
    let scene = match ibeam::lang::load_scene_source("flat.ib", &text) {
        Ok(s) => s,
        Err(e) => {
            assert!(
                !e.message.contains("internal error"),
                "seed {seed}: loader panicked\n{text}\n{e}"
            );
            return false;
        }
    };
    assert!(is_flat(&scene), "seed {seed}: not flat\n{text}");
    let evals = build_evaluators(&scene, EvalKind::Jit).expect("JIT accepts valid IR");
    let mut opts = RenderOptions::new(48, 40);
    let beam = match render(&scene, &evals, &opts) {
        Ok(out) => out,
        Err(RenderError::Undefined(_)) => return false,
        Err(e) => panic!("seed {seed}: {e}\n{text}"),
    };
    opts.method = Method::Pixel;
    let pixel = render(&scene, &evals, &opts).unwrap();
    for k in 0..beam.hit_mask.len() {
        assert_eq!(
            beam.hit_mask[k], pixel.hit_mask[k],
            "seed {seed}: hit differs at pixel {k}\n{text}"
        );
        assert_eq!(
            beam.depth_t[k].to_bits(),
            pixel.depth_t[k].to_bits(),
            "seed {seed}: depth differs at pixel {k}\n{text}"
        );
        assert_eq!(
            beam.linear[k].map(f32::to_bits),
            pixel.linear[k].map(f32::to_bits),
            "seed {seed}: colour differs at pixel {k}\n{text}"
        );
    }
    true
}

/// Anti-aliased renders trace their sub-samples with the same tracer
/// (masked fine tiles for IAA, a finer image for grids): the beam and
/// pixel methods must again agree to the bit. Whether they were compared
/// (see [`check_seed`]).
fn check_anti_aliased(seed: u64) -> bool {
    let text = scene_source(seed);
    let Ok(scene) = ibeam::lang::load_scene_source("flat.ib", &text) else {
        return false;
    };
    let evals = build_evaluators(&scene, EvalKind::Jit).unwrap();
    for aa in [
        Aa::Grid(2),
        Aa::Iaa {
            threshold: 1.0 / 64.0,
            depth: 2,
        },
    ] {
        let mut opts = RenderOptions::new(24, 20);
        let beam = match render_aa(&scene, &evals, &opts, aa) {
            Ok(out) => out,
            Err(RenderError::Undefined(_)) => return false,
            Err(e) => panic!("seed {seed}, {aa:?}: {e}\n{text}"),
        };
        opts.method = Method::Pixel;
        let pixel = render_aa(&scene, &evals, &opts, aa).unwrap();
        for k in 0..beam.linear.len() {
            assert_eq!(
                beam.linear[k].map(f32::to_bits),
                pixel.linear[k].map(f32::to_bits),
                "seed {seed}, {aa:?}: colour differs at pixel {k}\n{text}"
            );
            assert_eq!(beam.coverage[k], pixel.coverage[k], "seed {seed}, {aa:?}");
        }
    }
    true
}

/// Of 96 seeds, how many scenes must load and render for the comparisons
/// to mean something (a third as many of 32 for anti-aliasing); 62 of 96
/// and 19 of 32 do.
const MIN_COMPARED: usize = 48;

#[test]
fn anti_aliased_flat_scenes_draw_the_pixels_of_single_rays() {
    let compared = (0..32).filter(|&seed| check_anti_aliased(seed)).count();
    assert!(
        compared >= MIN_COMPARED * 32 / 96,
        "only {compared} of 32 scenes compared"
    );
}

#[test]
fn flat_scenes_draw_the_pixels_of_single_rays() {
    let compared = (0..96).filter(|&seed| check_seed(seed)).count();
    assert!(
        compared >= MIN_COMPARED,
        "only {compared} of 96 scenes compared"
    );
}

/// Some generated scenes must show both surface and background, or the
/// comparison above would prove little.
#[test]
fn flat_scenes_show_surface_and_background() {
    let mut mixed = 0;
    for seed in 0..96 {
        let text = scene_source(seed);
        let Ok(scene) = ibeam::lang::load_scene_source("flat.ib", &text) else {
            continue;
        };
        let evals = build_evaluators(&scene, EvalKind::Jit).unwrap();
        let Ok(out) = render(&scene, &evals, &RenderOptions::new(48, 40)) else {
            continue;
        };
        let hit = out.hit_mask.iter().filter(|&&h| h).count();
        mixed += usize::from(hit > 0 && hit < out.hit_mask.len());
    }
    assert!(mixed >= 48, "only {mixed} of 96 scenes show both");
}

/// A grid render traces a finer image whose tiles span several of the
/// groups' tile cells: a function long enough (over 4096 ops) for tiles
/// to be proven empty a group at a time must lose no sub-sample there.
/// Each grid:2 pixel's coverage is the share of hits among the four
/// pixels of the plain render at twice the size.
#[test]
fn grid_renders_of_long_functions_keep_every_sub_sample() {
    let mut rng = Rng::new(7);
    let discs: Vec<String> = (0..900)
        .map(|_| {
            // Around a ring, so that most tiles are empty and many are
            // empty only in part.
            let th = rng.range(0.0, std::f64::consts::TAU);
            let (a, b) = (0.8 * th.cos(), 0.8 * th.sin());
            let r = rng.range(0.01, 0.03);
            format!("sqrt((x - ({a:.5}))^2 + (y - ({b:.5}))^2) - {r:.5}")
        })
        .collect();
    let text = format!(
        "object dots = min({});\n\
         camera {{ eye = (0, 0, 4); target = (0, 0, 0); ortho = 2.2; }}\n\
         bounds = (-1.1, -1.1, -1) .. (1.1, 1.1, 1);\n",
        discs.join(", ")
    );
    let scene = ibeam::lang::load_scene_source("dots.ib", &text).unwrap();
    let ops = scene.objects[0].function.live_count();
    assert!(ops > 4096, "{ops} ops");
    let evals = build_evaluators(&scene, EvalKind::Jit).unwrap();
    let n = 96u32;
    let fine = render(&scene, &evals, &RenderOptions::new(2 * n, 2 * n)).unwrap();
    let grid = render_aa(&scene, &evals, &RenderOptions::new(n, n), Aa::Grid(2)).unwrap();
    let mut partial = 0;
    for y in 0..n as usize {
        for x in 0..n as usize {
            let at = |i: usize, j: usize| fine.hit_mask[(2 * y + j) * 2 * n as usize + 2 * x + i];
            let hits = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
            let share = hits.iter().filter(|&&h| h).count() as f32 / 4.0;
            let k = y * n as usize + x;
            assert_eq!(grid.coverage[k], share, "pixel ({x}, {y})");
            partial += usize::from(share > 0.0 && share < 1.0);
        }
    }
    assert!(partial > 50, "only {partial} partly covered pixels");
}

/// A flat union of many discs, long enough to prune with the JIT (64
/// discs, about 650 ops): its tiles take the tapes their groups pruned
/// for them in batches, and still draw exactly the pixels of single
/// rays.
#[test]
fn flat_tiles_take_the_tapes_pruned_ahead_for_them() {
    let mut rng = Rng::new(5);
    let discs: Vec<String> = (0..64)
        .map(|_| {
            let (a, b) = (num(rng.range(-1.2, 1.2)), num(rng.range(-1.2, 1.2)));
            format!(
                "sqrt((x - {a})^2 + (y - {b})^2) - {}",
                num(rng.range(0.05, 0.2))
            )
        })
        .collect();
    let text = format!(
        "object discs = min({});\n\
         camera {{ eye = (0, 0, 4); target = (0, 0, 0); up = (0, 1, 0); ortho = 3.4; }}\n\
         bounds = (-1.5, -1.5, -1.5) .. (1.5, 1.5, 1.5);\n\
         light {{ direction = (-0.5, -1, -0.7); }}\n",
        discs.join(", ")
    );
    let scene = ibeam::lang::load_scene_source("discs.ib", &text).expect("valid scene");
    assert!(is_flat(&scene));
    let evals = build_evaluators(&scene, EvalKind::Jit).unwrap();
    let mut opts = RenderOptions::new(300, 260);
    let beam = render(&scene, &evals, &opts).unwrap();
    // 10 × 9 tiles: every tile that is not proven empty.
    assert!(
        beam.stats.pruned_ahead > 9,
        "only {} tiles took tapes pruned ahead",
        beam.stats.pruned_ahead
    );
    opts.method = Method::Pixel;
    let pixel = render(&scene, &evals, &opts).unwrap();
    assert_eq!(beam.hit_mask, pixel.hit_mask);
    assert_eq!(beam.depth_t, pixel.depth_t);
    assert!(beam.hit_mask.iter().any(|&h| h) && !beam.hit_mask.iter().all(|&h| h));
}
