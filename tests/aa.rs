//! Anti-aliasing (IAA and grid) and the accuracy sweep, on example scenes
//! evaluated by the reference interpreter.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use ibeam::bench::accuracy::{
    CSV_HEADER, Family, REFERENCE, compare, default_variants, run_accuracy, sweep_scene,
};
use ibeam::eval::Evaluator;
use ibeam::eval::interp::Interpreter;
use ibeam::ir::passes::simplify;
use ibeam::render::{Aa, Enclosure, Method, RenderOptions, RenderOutput, render_aa};
use ibeam::scene::Scene;

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(format!("{name}.ib"))
}

fn interp(scene: &Scene) -> Result<Vec<Arc<dyn Evaluator>>, String> {
    Ok(scene
        .objects
        .iter()
        .map(|o| Arc::new(Interpreter::new(simplify(&o.function))) as Arc<dyn Evaluator>)
        .collect())
}

fn load(name: &str) -> (Scene, Vec<Arc<dyn Evaluator>>) {
    let scene = ibeam::lang::load_scene(&example(name)).unwrap();
    let evals = interp(&scene).unwrap();
    (scene, evals)
}

fn go(
    scene: &Scene,
    evals: &[Arc<dyn Evaluator>],
    size: u32,
    aa: Aa,
    threads: usize,
) -> RenderOutput {
    let mut o = RenderOptions::new(size, size);
    o.threads = Some(threads);
    render_aa(scene, evals, &o, aa).unwrap()
}

// Pixels whose base hit differs from a 4-neighbour's: the silhouette.
fn silhouette(hit: &[bool], w: usize, h: usize) -> Vec<bool> {
    let mut out = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let k = y * w + x;
            let mut nb = Vec::new();
            if x > 0 {
                nb.push(k - 1);
            }
            if x + 1 < w {
                nb.push(k + 1);
            }
            if y > 0 {
                nb.push(k - w);
            }
            if y + 1 < h {
                nb.push(k + w);
            }
            out[k] = nb.iter().any(|&n| hit[n] != hit[k]);
        }
    }
    out
}

#[test]
fn iaa_on_a_sphere_samples_the_interior_once_and_splits_the_silhouette() {
    let (scene, evals) = load("sphere");
    let n = 40usize;
    let plain = go(&scene, &evals, n as u32, Aa::None, 1);
    // The loosest threshold (every clamped colour interval passes): at
    // this size one pixel spans a wide range of normals, and the point
    // here is the geometric split rule.
    let aa = Aa::Iaa {
        threshold: 1.0,
        depth: 2,
    };
    let out = go(&scene, &evals, n as u32, aa, 1);
    let sil = silhouette(&plain.hit_mask, n, n);
    // Where 4×4 samples see both surface and background, the silhouette
    // crosses the pixel: neither the rejection nor the inclusion test can
    // settle it.
    let grid = go(&scene, &evals, n as u32, Aa::Grid(4), 1);
    let mut crossed = 0;
    let mut interior = 0;
    for k in 0..n * n {
        if grid.coverage[k] > 0.0 && grid.coverage[k] < 1.0 {
            crossed += 1;
            assert!(out.samples[k] > 1, "silhouette pixel {k} not split");
            assert!(out.coverage[k] > 0.0 && out.coverage[k] < 1.0);
        }
        // Two pixels inside the silhouette, or far outside it.
        let (x, y) = (k % n, k / n);
        let near = (x.saturating_sub(2)..(x + 3).min(n))
            .flat_map(|i| (y.saturating_sub(2)..(y + 3).min(n)).map(move |j| j * n + i))
            .any(|m| sil[m]);
        if !near && plain.hit_mask[k] {
            interior += 1;
            assert_eq!(out.samples[k], 1, "interior pixel {k} split");
            // The same centre ray, its root refined in the bracket of the
            // pixel's area rather than of the plain render's beam: the
            // same colour to within the root tolerance (one level in 8
            // bits).
            let (a, p) = (out.image.as_raw(), plain.image.as_raw());
            for c in 3 * k..3 * k + 3 {
                let d = (i32::from(a[c]) - i32::from(p[c])).abs();
                assert!(d <= 1, "interior pixel {k}: {} against {}", a[c], p[c]);
            }
        }
        if !near && !plain.hit_mask[k] {
            assert_eq!(out.samples[k], 1, "background pixel {k} split");
            assert_eq!(out.coverage[k], 0.0);
        }
    }
    assert!(interior > 100, "only {interior} interior pixels");
    assert!(crossed > 40, "only {crossed} silhouette pixels");
    assert_eq!(out.stats.aa_samples_max, 16);
    assert_eq!(
        out.stats.aa_pixels_split,
        out.samples.iter().filter(|&&s| s > 1).count() as u64
    );
    let mean = out.samples.iter().map(|&s| f64::from(s)).sum::<f64>() / (n * n) as f64;
    assert!((out.stats.aa_samples_mean() - mean).abs() < 1e-12);
    // The tight default threshold splits more.
    let tight = go(
        &scene,
        &evals,
        n as u32,
        Aa::Iaa {
            threshold: 1.0 / 256.0,
            depth: 2,
        },
        1,
    );
    assert!(tight.stats.aa_pixels_split > out.stats.aa_pixels_split);
}

#[test]
fn grid_takes_n_squared_samples_everywhere() {
    let (scene, evals) = load("sphere");
    for nn in [2u32, 3] {
        let out = go(&scene, &evals, 12, Aa::Grid(nn), 1);
        assert!(out.samples.iter().all(|&s| s == nn * nn));
        assert_eq!(out.stats.aa_samples_max, u64::from(nn * nn));
        assert!((out.stats.aa_samples_mean() - f64::from(nn * nn)).abs() < 1e-12);
        assert_eq!(out.stats.aa_pixels_split, 144);
        // Coverage is a multiple of 1/N².
        for &c in &out.coverage {
            // f32 holds every multiple of 1/9 and 1/4 to within 1e-6.
            let q = f64::from(c) * f64::from(nn * nn);
            assert!((q - q.round()).abs() < 1e-5, "{c}");
        }
    }
    let plain = go(&scene, &evals, 12, Aa::Grid(1), 1);
    let none = go(&scene, &evals, 12, Aa::None, 1);
    assert_eq!(plain.image, none.image);
    assert_eq!(none.stats.aa_pixels_split, 0);
}

#[test]
fn anti_aliased_output_is_the_same_for_one_and_two_threads() {
    let (scene, evals) = load("sphere");
    for aa in [
        Aa::Iaa {
            threshold: 1.0 / 64.0,
            depth: 2,
        },
        Aa::Grid(2),
    ] {
        // 40 pixels: more than one tile, so the threads share work.
        let a = go(&scene, &evals, 40, aa, 1);
        let b = go(&scene, &evals, 40, aa, 2);
        assert_eq!(a.image, b.image, "{aa}");
        assert_eq!(a.linear, b.linear);
        assert_eq!(a.samples, b.samples);
        assert_eq!(a.coverage, b.coverage);
        assert_eq!(a.stats.rays, b.stats.rays);
        assert_eq!(a.stats.interval_evals, b.stats.interval_evals);
        assert_eq!(a.stats.aa_samples, b.stats.aa_samples);
    }
}

#[test]
fn iaa_never_loses_surface_on_a_thin_feature() {
    let (scene, evals) = load("orthocircle_thin");
    let n = 40;
    let plain = go(&scene, &evals, n, Aa::None, 2);
    let aa = go(
        &scene,
        &evals,
        n,
        Aa::Iaa {
            threshold: 1.0 / 64.0,
            depth: 2,
        },
        2,
    );
    let hits = plain.hit_mask.iter().filter(|&&h| h).count();
    assert!(hits > 50, "{hits}");
    for k in 0..plain.hit_mask.len() {
        if plain.hit_mask[k] {
            assert!(aa.coverage[k] > 0.0, "pixel {k} lost its surface");
            assert!(aa.hit_mask[k]);
        }
    }
}

#[test]
fn accuracy_sweep_writes_its_files_and_obeys_the_obvious_relations() {
    let dir = std::env::temp_dir().join(format!("ibeam-aa-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let rows = run_accuracy(&[example("sphere")], &dir, 12, Enclosure::Affine, &interp).unwrap();
    let csv = std::fs::read_to_string(dir.join("accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    // Every line names the enclosure its render used.
    let lines: Vec<&str> = lines.collect();
    assert_eq!(lines.len(), rows.len());
    assert!(lines.iter().all(|l| l.split(',').nth(3) == Some("affine")));
    assert!(rows.iter().all(|r| r.enclosure == Enclosure::Affine));
    assert_eq!(rows.len(), 1 + default_variants().len());
    let png = image::open(dir.join("accuracy.png")).unwrap();
    assert!(png.width() >= 400 && png.height() >= 300);
    let reference = &rows[0];
    assert_eq!(reference.family, Family::Reference);
    assert_eq!(reference.rmse, 0.0);
    assert_eq!(reference.max_abs, 0.0);
    assert_eq!(reference.coverage_diff_pct, 0.0);
    assert_eq!(reference.missed_surface, 0);
    assert_eq!(reference.samples_mean, 256.0);
    // Each row's errors are those of its variant's render against the
    // reference's, recomputed here from the two images.
    let (scene, evals) = load("sphere");
    let draw = |method: Method, aa: Aa| {
        let mut o = RenderOptions::new(12, 12);
        o.method = method;
        o.enclosure = Enclosure::Affine;
        render_aa(&scene, &evals, &o, aa).unwrap()
    };
    let reference_image = draw(REFERENCE.0, REFERENCE.1);
    for (r, v) in rows[1..].iter().zip(default_variants()) {
        assert_eq!((r.family, &r.param), (v.family, &v.param));
        let (rmse, max_abs) = colour_errors(&reference_image, &draw(v.method, v.aa));
        assert!(
            (r.rmse - rmse).abs() <= 1e-12 * rmse && r.max_abs == max_abs,
            "{} {}: rmse {} and max {} reported, {rmse} and {max_abs} recomputed",
            r.family,
            r.param,
            r.rmse,
            r.max_abs
        );
        assert!(r.time_ms > 0.0);
        if r.family != Family::Point {
            assert_eq!(r.missed_surface, 0, "{} {}", r.family, r.param);
        }
    }
    // Not vacuous: point sampling at 16 steps differs from the reference.
    assert!(
        rows[1].rmse > 1e-3 && rows[1].max_abs > 0.1,
        "{:?}",
        rows[1]
    );
    assert!(rows[1..].iter().any(|r| r.pareto));
    // The beam and pixel methods draw the same pixels (their colours
    // differ within the depth tolerance).
    let fam = |f: Family| rows.iter().find(|r| r.family == f).unwrap();
    assert_eq!(
        fam(Family::Beam).coverage_diff_pct,
        fam(Family::Pixel).coverage_diff_pct
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// RMSE and largest error of linear colour, channels clamped to [0, 1],
/// over every pixel and channel (what the accuracy rows report).
fn colour_errors(reference: &RenderOutput, out: &RenderOutput) -> (f64, f64) {
    assert_eq!(reference.linear.len(), out.linear.len());
    let errors: Vec<f64> = reference
        .linear
        .iter()
        .zip(&out.linear)
        .flat_map(|(a, b)| {
            (0..3).map(move |c| {
                (f64::from(a[c]).clamp(0.0, 1.0) - f64::from(b[c]).clamp(0.0, 1.0)).abs()
            })
        })
        .collect();
    let mean_square = errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64;
    (
        mean_square.sqrt(),
        errors.iter().copied().fold(0.0, f64::max),
    )
}

/// `compare` on a render against a copy with known damage: one channel of
/// one pixel off by 1/4, one covered pixel emptied.
#[test]
fn compare_reports_known_errors() {
    let (scene, evals) = load("sphere");
    let reference = go(&scene, &evals, 12, Aa::None, 1);
    let n = reference.linear.len();
    assert_eq!(
        compare(&reference, &reference.hit_mask, &reference.clone()).rmse,
        0.0
    );
    let mut damaged = reference.clone();
    let c = damaged.linear[3][1];
    damaged.linear[3][1] = if c <= 0.5 { c + 0.25 } else { c - 0.25 };
    let hit = reference.hit_mask.iter().position(|&h| h).expect("a hit");
    assert_ne!(hit, 3, "the sphere covers pixel 3");
    damaged.coverage[hit] = 0.0;
    let e = compare(&reference, &reference.hit_mask, &damaged);
    let want = (0.0625 / (3.0 * n as f64)).sqrt();
    assert!(
        (e.rmse - want).abs() < 1e-6 * want,
        "rmse {} want {want}",
        e.rmse
    );
    assert!((e.max_abs - 0.25).abs() < 1e-6, "max {:e}", e.max_abs);
    assert_eq!(e.missed_surface, 1);
    assert_eq!(e.coverage_diff_pct, 100.0 / n as f64);
}

#[test]
fn sweep_of_a_custom_variant_list_has_one_row_each() {
    let (scene, evals) = load("sphere");
    let v: Vec<_> = default_variants()
        .into_iter()
        .filter(|v| v.method == Method::Beam && v.aa == Aa::None)
        .collect();
    let rows = sweep_scene("sphere", &scene, &evals, 8, &v, 1, Enclosure::Auto).unwrap();
    assert_eq!(rows.len(), 2);
    assert!(rows[1].pareto);
}

/// A scene's `n`² render without anti-aliasing and with IAA at threshold
/// 1 (geometry and shadow edges alone decide), both on the interpreter.
fn plain_and_loosest_iaa(name: &str, text: &str, n: u32) -> (RenderOutput, RenderOutput) {
    let scene = ibeam::lang::load_scene_source(name, text).unwrap();
    let evals = interp(&scene).unwrap();
    let aa = Aa::Iaa {
        threshold: 1.0,
        depth: 2,
    };
    (
        go(&scene, &evals, n, Aa::None, 1),
        go(&scene, &evals, n, aa, 1),
    )
}

/// A straight shadow edge that runs along the border between two tiles
/// (a plate's shadow, seen from straight above, the edge between pixel
/// columns 31 and 32, x = 2/3, cast by the plate's top inner edge at
/// x = 2/3 + 1.05, y = 1.05): each side's only differing neighbour is in
/// the other tile, which the base render of the tile beside provides.
#[test]
fn iaa_splits_shadow_edges_along_tile_borders() {
    let text = "object ground = y;\n\
                object plates = max(max(y - 1.05, 0.95 - y), min(1.7166666666666666 - x, x + 1.7166666666666666));\n\
                camera { eye = (0, 6, 0); target = (0, 0, 0); up = (0, 0, -1); ortho = 4; }\n\
                bounds = (-2, -0.5, -2) .. (2, 2, 2);\n\
                light { direction = (-1, -1, 0); color = (1, 1, 1); shadows = true; }\n";
    let n = 48usize;
    let (plain, out) = plain_and_loosest_iaa("border.ib", text, n as u32);
    let lum = |k: usize| plain.linear[k].iter().map(|&c| f64::from(c)).sum::<f64>();
    for y in 0..n {
        let (a, b) = (y * n + 31, y * n + 32);
        assert!(
            lum(a) > 2.0 * lum(b),
            "row {y}: the edge is not between columns 31 and 32 ({} {})",
            lum(a),
            lum(b)
        );
        assert!(
            out.samples[a] > 1 && out.samples[b] > 1,
            "row {y}: a pixel beside the tile border kept one sample"
        );
    }
}

/// Sub-samples take their pixel's base shadow state only off shadow edges
/// (and near the base hit): a ball lit from above and behind, its shadow
/// on the ground behind it as the camera sees it, so that its silhouette
/// is also a shadow edge. IAA at depth 2 (grid:4's sample positions)
/// stays within a few hundredths of grid:4 on every pixel; with the base
/// state taken on shadow-edge pixels too, pixels over the shadowed ground
/// came out lit, 0.45 off.
#[test]
fn iaa_sub_samples_reuse_shadows_only_off_shadow_edges() {
    let text = "object ground = plane(0, 1, 0, 0);\n\
                object ball = translate(sphere(0.5), 0, 1, 0);\n\
                camera { eye = (3, 4, 0.001); target = (0, 0.5, 0); up = (0, 1, 0); fov = 30; }\n\
                bounds = (-2, -0.5, -2) .. (2, 2, 2);\n\
                light { direction = (-1, -1.5, 0.2); color = (1, 1, 1); shadows = true; }\n";
    let scene = ibeam::lang::load_scene_source("behind.ib", text).unwrap();
    let evals = interp(&scene).unwrap();
    let n = 40;
    let iaa = Aa::Iaa {
        threshold: 0.0,
        depth: 2,
    };
    let grid = go(&scene, &evals, n, Aa::Grid(4), 1);
    let out = go(&scene, &evals, n, iaa, 1);
    let mut worst = (0.0f64, 0);
    for k in 0..(n * n) as usize {
        for c in 0..3 {
            let d = (f64::from(out.linear[k][c]) - f64::from(grid.linear[k][c])).abs();
            if d > worst.0 {
                worst = (d, k);
            }
        }
    }
    assert!(
        worst.0 < 0.05,
        "pixel {} differs from grid:4 by {}",
        worst.1,
        worst.0
    );
    assert!(
        out.stats.shadow_rays > 0 && out.stats.aa_pixels_split > 0,
        "the scene lost its shadows or its splits"
    );
}

/// Shadow edges: a ball above a ground plane, lit from the side, seen
/// from above. The colour interval leaves shadows out, so IAA finds shadow
/// edges by comparing each pixel's shadow state with its neighbours':
/// every ground pixel whose base colour jumps against a ground neighbour
/// (lit against shadowed; the ground is flat, so nothing else changes its
/// colour) is split, even at the loosest colour threshold, also where
/// the neighbour lies in another tile.
#[test]
fn iaa_splits_shadow_edges() {
    let text = "object ground = plane(0, 1, 0, 0);\n\
                object ball = translate(sphere(0.5), 0, 1, 0);\n\
                camera { eye = (0, 6, 0.001); target = (0, 0, 0); up = (0, 0, -1); fov = 30; }\n\
                bounds = (-2, -0.5, -2) .. (2, 2, 2);\n\
                light { direction = (-1, -1, 0); color = (1, 1, 1); shadows = true; }\n";
    let n = 48usize;
    let (plain, out) = plain_and_loosest_iaa("shadow.ib", text, n as u32);
    let ground_t = plain
        .depth_t
        .iter()
        .copied()
        .fold(0.0f64, |m, t| if t.is_finite() { m.max(t) } else { m });
    let ground = |k: usize| (plain.depth_t[k] - ground_t).abs() < 0.3;
    let mut edges = 0;
    for y in 0..n {
        for x in 0..n {
            let k = y * n + x;
            if !ground(k) {
                continue;
            }
            // Diagonal neighbours count too: a thin lit strip can cross
            // a pixel whose four side neighbours are all shadowed.
            let (xm, ym) = (x.wrapping_sub(1), y.wrapping_sub(1));
            let jumps: Vec<(usize, usize)> = [
                (xm, y),
                (x + 1, y),
                (x, ym),
                (x, y + 1),
                (xm, ym),
                (x + 1, ym),
                (xm, y + 1),
                (x + 1, y + 1),
            ]
            .into_iter()
            .filter(|&(i, j)| i < n && j < n)
            .filter(|&(i, j)| {
                let m = j * n + i;
                ground(m) && (0..3).any(|c| (plain.linear[m][c] - plain.linear[k][c]).abs() > 0.1)
            })
            .collect();
            if !jumps.is_empty() {
                edges += 1;
                assert!(
                    out.samples[k] > 1,
                    "shadow-edge pixel ({x}, {y}) kept one sample"
                );
            }
        }
    }
    assert!(
        edges >= 10,
        "only {edges} shadow-edge pixels: the scene lost its shadow"
    );
}

#[test]
fn covered_pixels_are_sampled_sparser_and_every_sample_hits() {
    // Orthocircle's tubes, seen at a slant: many pixels near their
    // silhouettes fail the inclusion test (grazing rays) yet are proven
    // covered. At depth 3 those get 4×4 sub-samples instead of 8×8.
    let (scene, evals) = load("orthocircle");
    let n = 64u32;
    let aa = Aa::Iaa {
        threshold: 1.0 / 64.0,
        depth: 3,
    };
    let out = go(&scene, &evals, n, aa, 2);
    let grid = go(&scene, &evals, n, Aa::Grid(8), 2);
    let covered: Vec<usize> = (0..(n * n) as usize)
        .filter(|&k| out.samples[k] == 16)
        .collect();
    assert!(covered.len() > 20, "only {} covered pixels", covered.len());
    assert_eq!(covered.len() as u64, out.stats.aa_split_covered);
    for &k in &covered {
        // The proof holds for every ray through the pixel's area, so for
        // grid:8's samples too, not only for IAA's own.
        assert_eq!(out.coverage[k], 1.0, "covered pixel {k}");
        assert_eq!(grid.coverage[k], 1.0, "covered pixel {k} misses in grid:8");
    }
    // Full splits keep the depth's 64 samples (65 with the centre ray).
    assert!(out.samples.contains(&64));
    assert!(
        out.samples
            .iter()
            .all(|&s| matches!(s, 1 | 4 | 5 | 16 | 64 | 65))
    );
}

#[test]
fn pixels_split_by_shading_alone_take_grid_2_colours() {
    // On a sphere with a tight threshold, the interior pixels' colour
    // intervals are too wide: their areas' beams are included, and their
    // sub-samples are refined in the included bracket, at grid:2's
    // positions, without beams of their own. They must hit, and agree
    // with grid:2's colour to within the roots' tolerance.
    let (scene, evals) = load("sphere");
    let n = 40u32;
    let aa = Aa::Iaa {
        threshold: 1.0 / 256.0,
        depth: 2,
    };
    let out = go(&scene, &evals, n, aa, 1);
    let grid = go(&scene, &evals, n, Aa::Grid(2), 1);
    let four: Vec<usize> = (0..(n * n) as usize)
        .filter(|&k| out.samples[k] == 4)
        .collect();
    assert!(four.len() > 200, "only {} pixels at 2×2", four.len());
    assert!(out.stats.aa_split_by_shading >= four.len() as u64 / 2);
    let (a, g) = (out.image.as_raw(), grid.image.as_raw());
    for &k in &four {
        assert_eq!(out.coverage[k], 1.0, "pixel {k}");
        for c in 3 * k..3 * k + 3 {
            let d = (i32::from(a[c]) - i32::from(g[c])).abs();
            assert!(d <= 1, "pixel {k}: {} against grid:2's {}", a[c], g[c]);
        }
    }
}

/// IAA on a union large enough to prune (60 spheres, shadows on): the
/// area tests run on pruned tapes and the squares of sub-samples carry
/// shadow cells from one to the next, yet 1 and 2 threads give the same
/// bytes, and no pixel the plain render hit is lost, pruned or not.
#[test]
fn iaa_on_a_pruned_union_is_thread_independent_and_keeps_surface() {
    let mut x = 7u64;
    let mut at = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 1.6 - 0.8
    };
    let balls: Vec<String> = (0..60)
        .map(|_| format!("translate(sphere(0.12), {}, {}, {})", at(), at(), at()))
        .collect();
    let text = format!(
        "object u = union({});\nbounds = (-1, -1, -1) .. (1, 1, 1);",
        balls.join(",")
    );
    let scene = ibeam::lang::load_scene_source("balls", &text).unwrap();
    assert!(scene.lights.iter().any(|l| l.shadows));
    let evals = interp(&scene).unwrap();
    let aa = Aa::Iaa {
        threshold: 1.0 / 64.0,
        depth: 2,
    };
    let (a, b) = (go(&scene, &evals, 72, aa, 1), go(&scene, &evals, 72, aa, 2));
    assert!(a.stats.pruned_ops_before > 0 && a.stats.aa_pixels_split > 100);
    assert_eq!(
        (&a.image, &a.linear, &a.samples),
        (&b.image, &b.linear, &b.samples)
    );
    let mut o = RenderOptions::new(72, 72);
    o.prune = false;
    let unpruned = render_aa(&scene, &evals, &o, aa).unwrap();
    let plain = go(&scene, &evals, 72, Aa::None, 2);
    assert!(plain.hit_mask.iter().filter(|&&h| h).count() > 500);
    for k in (0..plain.hit_mask.len()).filter(|&k| plain.hit_mask[k]) {
        assert!(
            a.coverage[k] > 0.0 && unpruned.coverage[k] > 0.0,
            "pixel {k} lost"
        );
    }
}
