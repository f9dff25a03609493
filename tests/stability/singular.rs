//! Double roots, tangency and singular points.

use super::*;

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

/// Pixels of a hit region darker than 0.8 times both their upper and lower
/// neighbours: the dotted line a wrong normal draws along a curve where ∇f
/// vanishes.
fn isolated_dark_specks(img: &image::RgbImage) -> usize {
    let lum = |x: u32, y: u32| -> u32 { img.get_pixel(x, y).0.iter().map(|&c| u32::from(c)).sum() };
    let mut n = 0;
    for y in 1..img.height() - 1 {
        for x in 0..img.width() {
            let (a, c, b) = (lum(x, y - 1), lum(x, y), lum(x, y + 1));
            if a > 60 && b > 60 && 10 * c < 8 * a.min(b) {
                n += 1;
            }
        }
    }
    n
}

// On the heart's equator z = 0 the gradient vanishes on the surface (f is
// a cube there to first order); hits a quarter pixel off the surface got
// normals dominated by that offset, 14 dark specks at 160² before normals
// were taken at a polished root (`render::shade::mend_singular_normals`).
#[test]
fn heart_has_no_dark_specks_on_its_singular_curve() {
    let scene = load_example("heart.ib");
    let evals = evaluators(&scene);
    let opts = RenderOptions::new(160, 160);
    let out = render(&scene, &evals, &opts).unwrap();
    assert!(count(&out.hit_mask) > 8000);
    assert_eq!(isolated_dark_specks(&out.image), 0);
    let iaa = ibeam::render::Aa::Iaa {
        threshold: 1.0 / 64.0,
        depth: 2,
    };
    let out = ibeam::render::render_aa(&scene, &evals, &opts, iaa).unwrap();
    assert_eq!(isolated_dark_specks(&out.image), 0);
}
