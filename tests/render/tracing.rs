//! Hits, depths and masks against references; beam against pixel rays;
//! threads; rays from inside; 2D masks; empty scenes.

use super::*;

// ---------------------------------------------------------------- tests

#[test]
fn sphere_depth_and_mask_match_closed_form() {
    let sc = scene(1, Camera::default(), vec![no_shadow_light()]);
    for method in [Method::Beam, Method::Pixel] {
        let out = run(&sc, vec![sphere()], &opts(48, 40, method));
        let c = check_against_reference(&sc, &out, 48, 40, &sphere_sdf);
        assert!(
            c.compared > 1500 && c.skipped < 200,
            "{method:?}: {} {}",
            c.compared,
            c.skipped
        );
        assert!(out.stats.pixels_hit > 300);
    }
}

#[test]
fn a_thin_layer_in_front_of_a_solid_is_the_first_hit() {
    // A shell of thickness 0.02 around a solid core of radius 0.9: a block
    // can be positive in front and negative inside the core, yet its rays'
    // first root is on the thin shell. Inclusion must not pick the core.
    let sc = scene(2, Camera::default(), vec![no_shadow_light()]);
    let ev: Vec<Arc<dyn Evaluator>> = vec![
        Arc::new(Shell { h: 0.01 }),
        Arc::new(Sphere {
            c: [0.0; 3],
            r2: 0.81,
        }),
    ];
    let out = run(&sc, ev, &opts(48, 48, Method::Beam));
    let sdf = |p: [f64; 3]| {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        ((r - 1.0).abs() - 0.01).min(r - 0.9)
    };
    let c = check_against_reference(&sc, &out, 48, 48, &sdf);
    assert!(c.compared > 1800, "{} {}", c.compared, c.skipped);
}

#[test]
fn auxiliary_images_show_normals_depth_and_classes() {
    let sc = scene(1, Camera::default(), vec![no_shadow_light()]);
    let o = RenderOptions {
        want_depth: true,
        want_normals: true,
        want_classify: true,
        ..opts(48, 48, Method::Beam)
    };
    let out = run(&sc, vec![sphere()], &o);
    // The sphere's normal at the centre of the view points at the eye.
    let e = sc.camera.eye;
    let len = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    let want = e.map(|c| (c / len * 0.5 + 0.5) * 255.0);
    let got = out.normals.as_ref().unwrap().get_pixel(24, 24).0;
    for c in 0..3 {
        assert!(
            (f64::from(got[c]) - want[c]).abs() < 6.0,
            "{got:?} vs {want:?}"
        );
    }
    let depth = out.depth.as_ref().unwrap();
    // Depth is normalised over the bounds' view-depth range, fixed before
    // tracing; the centre of the sphere is nearer than its rim.
    let range = ibeam::render::output::depth_range(&sc.camera, &sc.bounds);
    let centre = depth.get_pixel(24, 24).0[0];
    let k = 24 * 48 + 24;
    assert_eq!(
        centre,
        ibeam::render::output::depth_u16(out.depth_t[k], range)
    );
    let rim = (0..48)
        .map(|i| depth.get_pixel(i, 24).0[0])
        .find(|&d| d != u16::MAX)
        .unwrap();
    assert!(centre < rim, "{centre} {rim}");
    assert_eq!(depth.get_pixel(0, 0).0[0], u16::MAX);
    assert_eq!(
        *out.normals.as_ref().unwrap().get_pixel(0, 0),
        image::Rgb([0, 0, 0])
    );
    let class = out.classify.as_ref().unwrap();
    let green = image::Rgb([40, 180, 70]);
    assert_eq!(*class.get_pixel(24, 24), green);
    let json = out.stats.to_json();
    for key in [
        "width",
        "height",
        "pixels_hit",
        "rays",
        "interval_evals",
        "point_evals",
        "shadow_rays",
        "shadow_rays_saved",
        "blocks_rejected",
        "blocks_included",
        "blocks_undecided",
        "time_ms",
        "compile_ms",
    ] {
        assert!(json.get(key).is_some(), "{key}");
    }
    assert_eq!(json["width"], 48);
    assert!(json["blocks_included"].as_u64().unwrap() > 0);
}

#[test]
fn torus_depth_and_mask_match_sphere_traced_reference() {
    let sc = scene(1, torus_camera(), vec![no_shadow_light()]);
    for method in [Method::Beam, Method::Pixel] {
        let out = run(&sc, vec![torus()], &opts(48, 48, method));
        let c = check_against_reference(&sc, &out, 48, 48, &torus_sdf);
        assert!(
            c.compared > 1800 && c.skipped < 400,
            "{method:?}: {} {}",
            c.compared,
            c.skipped
        );
        assert!(out.stats.pixels_hit > 400);
    }
}

#[test]
fn beam_and_pixel_give_the_same_hit_mask_with_fewer_rays() {
    for (sc, ev) in [
        (
            scene(1, Camera::default(), vec![no_shadow_light()]),
            sphere(),
        ),
        (scene(1, torus_camera(), vec![no_shadow_light()]), torus()),
    ] {
        let b = run(&sc, vec![ev.clone()], &opts(64, 64, Method::Beam));
        let p = run(&sc, vec![ev], &opts(64, 64, Method::Pixel));
        let diff: Vec<usize> = (0..b.hit_mask.len())
            .filter(|&k| b.hit_mask[k] != p.hit_mask[k])
            .collect();
        let info: Vec<_> = diff
            .iter()
            .map(|&k| (k % 64, k / 64, b.depth_t[k], p.depth_t[k]))
            .collect();
        assert!(diff.is_empty(), "{info:?}");
        eprintln!("{}", b.stats);
        assert!(
            b.stats.rays * 4 < p.stats.rays,
            "{} vs {}",
            b.stats.rays,
            p.stats.rays
        );
        assert!(b.stats.blocks_included > 0 && b.stats.blocks_rejected > 0);
        eprintln!(
            "rays beam {} (refined {}) vs pixel {}",
            b.stats.rays, b.stats.pixels_refined, p.stats.rays
        );
    }
}

#[test]
fn thin_shell_is_found_where_point_sampling_misses_it() {
    let sc = scene(1, Camera::default(), vec![no_shadow_light()]);
    let ev = || -> Vec<Arc<dyn Evaluator>> { vec![Arc::new(Shell { h: 0.01 })] };
    let (w, h) = (40, 40);
    let beam = run(&sc, ev(), &opts(w, h, Method::Beam));
    let coarse = run(&sc, ev(), &opts(w, h, Method::Point { steps: 64 }));
    let fine = run(&sc, ev(), &opts(w, h, Method::Point { steps: 64 * 16 }));
    let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
    let fine_not_beam = (0..beam.hit_mask.len())
        .filter(|&k| fine.hit_mask[k] && !beam.hit_mask[k])
        .count();
    assert_eq!(fine_not_beam, 0);
    assert!(count(&fine.hit_mask) > 300);
    assert!(
        count(&coarse.hit_mask) + 50 < count(&fine.hit_mask),
        "coarse {} fine {}",
        count(&coarse.hit_mask),
        count(&fine.hit_mask)
    );
}

/// The torus, a sphere above it and the ground, under two lights.
fn two_object_scene() -> (Scene, Vec<Arc<dyn Evaluator>>) {
    let mut sc = scene(
        3,
        torus_camera(),
        vec![
            Light::default_light(),
            Light {
                kind: LightKind::Point([1.5, -1.5, 1.8]),
                color: [0.5, 0.4, 0.3],
                shadows: true,
            },
        ],
    );
    sc.bounds = Bounds {
        min: [-2.0, -2.0, -1.0],
        max: [2.0, 2.0, 2.0],
    };
    let ev: Vec<Arc<dyn Evaluator>> = vec![
        torus(),
        Arc::new(Sphere {
            c: [0.0, 0.0, 0.9],
            r2: 0.25,
        }),
        Arc::new(Ground { axis: 2, h: -0.7 }),
    ];
    (sc, ev)
}

#[test]
fn thread_count_does_not_change_the_output() {
    let (sc, ev) = two_object_scene();
    let mut o = opts(70, 45, Method::Beam);
    let a = run(&sc, ev.clone(), &o);
    o.threads = Some(2);
    let b = run(&sc, ev, &o);
    assert_eq!(a.image.as_raw(), b.image.as_raw());
    assert_eq!(a.depth_t, b.depth_t);
    assert_eq!(a.stats.rays, b.stats.rays);
    assert_eq!(a.stats.interval_evals, b.stats.interval_evals);
    assert!(a.stats.shadow_rays_saved > 0, "{}", a.stats);
}

#[test]
fn rays_starting_inside_hit_at_their_clip_start() {
    let mut sc = scene(1, Camera::default(), vec![no_shadow_light()]);
    sc.bounds = Bounds {
        min: [-1.0; 3],
        max: [1.0; 3],
    };
    // A ball of radius 1.4 cuts the corners off the bounds cube.
    let ev: Vec<Arc<dyn Evaluator>> = vec![Arc::new(Sphere {
        c: [0.0; 3],
        r2: 1.96,
    })];
    let (w, h) = (40, 40);
    let out = run(&sc, ev, &opts(w, h, Method::Beam));
    let cam = RayCamera::new(&sc.camera, w, h).unwrap();
    let mut inside = 0;
    for j in 0..h {
        for i in 0..w {
            let ray = cam.pixel_ray(i, j);
            let k = (j * w + i) as usize;
            let Some((t0, _)) = ray.slab(&sc.bounds) else {
                continue;
            };
            let r = ray.at(t0).iter().map(|c| c * c).sum::<f64>().sqrt();
            if r < 1.38 {
                inside += 1;
                assert!(out.hit_mask[k]);
                assert_eq!(out.depth_t[k], t0, "pixel ({i}, {j})");
            }
        }
    }
    assert!(inside > 200);
}

#[test]
fn a_2d_function_renders_as_a_filled_mask() {
    let cam = Camera {
        eye: [0.0, 0.0, 5.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Orthographic { width: 4.0 },
    };
    let mut sc = scene(1, cam, vec![no_shadow_light()]);
    sc.objects[0] = object_using("disc", [0.5; 3], &[Var::X, Var::Y]);
    let (w, h) = (32, 32);
    let out = run(&sc, vec![Arc::new(Disc)], &opts(w, h, Method::Beam));
    let rc = RayCamera::new(&sc.camera, w, h).unwrap();
    for j in 0..h {
        for i in 0..w {
            let o = rc.pixel_ray(i, j).om;
            let r = (o[0] * o[0] + o[1] * o[1]).sqrt();
            let k = (j * w + i) as usize;
            if (r - 1.0).abs() > 0.05 {
                assert_eq!(out.hit_mask[k], r < 1.0, "pixel ({i}, {j})");
            }
        }
    }
    let px = run(&sc, vec![Arc::new(Disc)], &opts(w, h, Method::Pixel));
    assert_eq!(out.hit_mask, px.hit_mask);
    // Pixels inside and outside the disc are settled by whole blocks or by
    // a block's batches, not by single rays.
    let settled = out.stats.blocks_included + out.stats.pixels_batched;
    assert!(settled > 200, "{settled}");
    assert!(out.stats.rays < 100, "{}", out.stats.rays);
}

#[test]
fn empty_scene_traces_no_rays() {
    let sc = scene(1, Camera::default(), vec![Light::default_light()]);
    let ev: Vec<Arc<dyn Evaluator>> = vec![Arc::new(Sphere {
        c: [0.0; 3],
        r2: -1.0,
    })];
    let o = RenderOptions {
        want_classify: true,
        want_depth: true,
        ..opts(50, 30, Method::Beam)
    };
    let out = run(&sc, ev, &o);
    assert_eq!(out.stats.rays, 0);
    assert_eq!(out.stats.pixels_hit, 0);
    assert_eq!(out.stats.shadow_rays, 0);
    let bg = srgb_pixel(sc.render.background);
    assert!(out.image.pixels().all(|p| *p == bg));
    assert!(out.depth.unwrap().pixels().all(|p| p.0[0] == u16::MAX));
}
