//! Lights and shadows, bad inputs, and per-tile pruning.

use super::*;

#[test]
fn a_light_inside_an_object_lights_nothing() {
    let light_pos = [1.3, 1.3, 1.3];
    let mk = |shadows: bool| {
        let sc = scene(
            2,
            Camera::default(),
            vec![Light {
                kind: LightKind::Point(light_pos),
                color: [1.0; 3],
                shadows,
            }],
        );
        let ev: Vec<Arc<dyn Evaluator>> = vec![
            sphere(),
            Arc::new(Sphere {
                c: light_pos,
                r2: 0.04,
            }),
        ];
        run(&sc, ev, &opts(40, 40, Method::Beam))
    };
    let sc = scene(2, Camera::default(), vec![]);
    let ambient: Vec<_> = sc
        .objects
        .iter()
        .map(|o| srgb_pixel(o.color.map(|c| c * AMBIENT)))
        .collect();
    let dark = mk(true);
    let lit = mk(false);
    let mut brighter = 0;
    for k in 0..dark.hit_mask.len() {
        if dark.hit_mask[k] {
            let (x, y) = ((k % 40) as u32, (k / 40) as u32);
            assert!(ambient.contains(dark.image.get_pixel(x, y)), "pixel {k}");
            if !ambient.contains(lit.image.get_pixel(x, y)) {
                brighter += 1;
            }
        }
    }
    assert!(brighter > 100, "{brighter}");
}

#[test]
fn shadows_fall_where_an_occluder_blocks_the_light() {
    let cam = Camera {
        eye: [0.0, 5.0, 0.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        projection: Projection::Orthographic { width: 4.0 },
    };
    let light = Light {
        kind: LightKind::Directional([1.0, -1.0, 0.0]),
        color: [1.0; 3],
        shadows: true,
    };
    let sc = scene(2, cam, vec![light]);
    let ev: Vec<Arc<dyn Evaluator>> = vec![
        Arc::new(Sphere {
            c: [0.0; 3],
            r2: 0.49,
        }),
        Arc::new(Ground { axis: 1, h: -1.0 }),
    ];
    let (w, h) = (40, 40);
    let out = run(&sc, ev, &opts(w, h, Method::Beam));
    let rc = RayCamera::new(&sc.camera, w, h).unwrap();
    let pixel_at = |x: f64, z: f64| {
        (0..w * h)
            .min_by(|&a, &b| {
                let d = |k: u32| {
                    let o = rc.pixel_ray(k % w, k / w).om;
                    (o[0] - x).powi(2) + (o[2] - z).powi(2)
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap()
    };
    let ground_ambient = srgb_pixel(sc.objects[1].color.map(|c| c * AMBIENT));
    let shadowed = pixel_at(1.0, 0.0);
    let lit = pixel_at(-1.2, 0.0);
    assert_eq!(
        *out.image.get_pixel(shadowed % w, shadowed / w),
        ground_ambient
    );
    assert_ne!(*out.image.get_pixel(lit % w, lit / w), ground_ambient);
    assert!(out.stats.shadow_rays_saved > 0);
}

#[test]
fn bad_inputs_are_errors() {
    let mut sc = scene(1, Camera::default(), vec![]);
    sc.camera.target = sc.camera.eye;
    assert!(matches!(
        render(&sc, &[sphere()], &opts(8, 8, Method::Beam)),
        Err(RenderError::Camera(_))
    ));
    let mut sc = scene(1, Camera::default(), vec![]);
    sc.camera.up = [3.0, 2.5, 4.0];
    assert!(matches!(
        render(&sc, &[sphere()], &opts(8, 8, Method::Beam)),
        Err(RenderError::Camera(_))
    ));
    let sc = scene(1, Camera::default(), vec![]);
    assert!(matches!(
        render(&sc, &[sphere()], &opts(0, 8, Method::Beam)),
        Err(RenderError::BadSize(0, 8))
    ));
    assert!(matches!(
        render(&sc, &[sphere()], &opts(8, 20000, Method::Beam)),
        Err(RenderError::BadSize(..))
    ));
    assert!(matches!(
        render(&sc, &[], &opts(8, 8, Method::Beam)),
        Err(RenderError::EvaluatorCount { .. })
    ));
    let sc = scene(0, Camera::default(), vec![]);
    assert!(matches!(
        render(&sc, &[], &opts(8, 8, Method::Beam)),
        Err(RenderError::NoObjects)
    ));
}

/// A union of `n` spheres of radius `r` at pseudo-random places in the
/// unit cube, seen through `camera` (the body of a camera block), lit by
/// the default light, which casts shadows unless `shadows` is false.
fn spheres_scene(n: usize, r: f64, camera: &str, shadows: bool) -> String {
    let mut rng = ibeam::ir::random::Rng::new(5);
    let balls: Vec<String> = (0..n)
        .map(|_| {
            let [x, y, z] = [(); 3].map(|_| rng.range(-0.9, 0.9));
            format!("translate(sphere({r}), {x}, {y}, {z})")
        })
        .collect();
    let light = if shadows {
        ""
    } else {
        "light { direction = (-0.4, -1, -0.6); shadows = false; }\n"
    };
    format!(
        "object s = union({});\n\
         camera {{ {camera} }}\n{light}\
         bounds = (-1, -1, -1) .. (1, 1, 1);\n",
        balls.join(", ")
    )
}

/// [`spheres_scene`] seen from a corner in perspective.
const CORNER_VIEW: &str = "eye = (2.2, 1.6, 2.8); target = (0, 0, 0);";

/// [`spheres_scene`] seen along z, orthographically, through a window a
/// quarter of the cube wide: at 128² a tile's beam is 16 times deeper
/// than wide.
const ALONG_Z: &str = "eye = (0, 0, 3); target = (0, 0, 0); ortho = 0.5;";

/// Pruning (`eval::tape`, `eval::regional`) changes how large functions
/// are evaluated, not what is drawn: a 2D model of 81 discs (a CSG union
/// of about 650 ops, seen along z), a 3D union of 80 spheres seen in
/// perspective (pruned per slice of each tile's beam and per block), a 3D
/// union of 400 smaller ones seen along z (whose tiles' long slices share
/// their group's tapes and whose short ones prune from the group's), 150
/// spheres with 150 smaller ones cut out (a `difference`: pruning keeps
/// signs through its negation), the
/// prospero model (2D) and the colonnade model (3D) render the same hit
/// mask and the same hit depths with and without it, and pruning did
/// happen; the pixel method draws the same hit mask.
#[test]
fn pruning_draws_what_the_whole_function_draws() {
    let mut text = String::from("object s = ");
    // 81 discs, each centre its own (no shared terms: about 650 ops);
    // native functions under 512 ops are not pruned at all.
    let n = 81;
    for i in 0..n {
        let (x, y) = (
            f64::from(i % 9) * 0.3 - 1.2 + 1e-3 * f64::from(i),
            f64::from(i / 9) * 0.3 - 1.2 - 1e-3 * f64::from(i),
        );
        let disc = format!("sqrt((x - {x})^2 + (y - {y})^2) - 0.1");
        if i + 1 < n {
            text.push_str(&format!("union({disc}, "));
        } else {
            text.push_str(&disc);
        }
    }
    text.push_str(&")".repeat(n as usize - 1));
    text.push_str(
        ";\ncamera { eye = (0, 0, 5); target = (0, 0, 0); ortho = 3; }\n\
         bounds = (-1.5, -1.5, -1) .. (1.5, 1.5, 1);\n",
    );
    let mut scenes = vec![
        (
            ibeam::lang::load_scene_source("discs.ib", &text).unwrap(),
            384,
        ),
        (
            ibeam::lang::load_scene_source(
                "spheres.ib",
                &spheres_scene(80, 0.06, CORNER_VIEW, true),
            )
            .unwrap(),
            160,
        ),
        (
            ibeam::lang::load_scene_source("many.ib", &spheres_scene(400, 0.04, ALONG_Z, false))
                .unwrap(),
            128,
        ),
    ];
    // A carved union: spheres with smaller ones cut out of them
    // (`difference` is `max(a, -b)`), whose cutters prune by sign through
    // the negation too.
    let carved = {
        let solid = spheres_scene(150, 0.09, CORNER_VIEW, true);
        let cut = spheres_scene(150, 0.06, CORNER_VIEW, true);
        let body = |t: &str| {
            t.split_once("union(")
                .and_then(|(_, rest)| rest.split_once(");\n"))
                .map(|(b, _)| b.to_string())
                .unwrap()
        };
        // Other places for the cutters: the same generator, shifted.
        let cutters = body(&cut).replace(
            "translate(sphere(0.06), ",
            "translate(sphere(0.06), 0.05 + ",
        );
        solid.replace(
            &format!("union({});", body(&solid)),
            &format!("difference(union({}), union({cutters}));", body(&solid)),
        )
    };
    assert!(carved.contains("difference(union("), "{carved}");
    scenes.push((
        ibeam::lang::load_scene_source("carved.ib", &carved).unwrap(),
        160,
    ));
    // The community models (see `models::shared_model`): prospero (2D)
    // and colonnade (3D, pruned per block near the surface).
    for model in ["prospero", "colonnade"] {
        if let Some(path) = models::shared_model(&format!("{model}.vm")) {
            let s = ibeam::lang::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
            scenes.push((s, if model == "prospero" { 384 } else { 128 }));
        }
    }
    for (sc, size) in &scenes {
        let evals = ibeam::eval::build_evaluators(sc, ibeam::eval::EvalKind::Jit).unwrap();
        assert!(evals[0].function().unwrap().live_count() >= 512);
        let mut o = opts(*size, *size, Method::Beam);
        let pruned = run(sc, evals.clone(), &o);
        let mut p = o.clone();
        p.method = Method::Pixel;
        assert_eq!(run(sc, evals.clone(), &p).hit_mask, pruned.hit_mask);
        o.prune = false;
        let whole = run(sc, evals.clone(), &o);
        assert!(pruned.stats.pruned_ops_after > 0, "nothing was pruned");
        assert!(pruned.stats.pruned_ops_after * 2 <= pruned.stats.pruned_ops_before);
        assert_eq!(whole.stats.pruned_ops_before, 0);
        assert_eq!(pruned.hit_mask, whole.hit_mask);
        // Point values agree bit for bit, but a block that prunes decides
        // its beam tests on tighter intervals, and sweeps inside a pruned
        // tile start from its slices: a root may be refined from another
        // bracket, so depths agree to the refinement tolerance (each root
        // lies within it of the true one). The one other difference
        // allowed is the tangency policy's: a grazing ray whose narrow
        // piece neither interval arithmetic nor the point signs settle is
        // drawn as a hit at that piece, and where pieces are cut
        // differently one render may settle a piece the other draws. Then
        // the nearer depth has no crossing behind it: f stays positive
        // along the ray up to the farther depth's root (sampled densely),
        // and such pixels are rare.
        let cam = ibeam::render::camera::RayCamera::new(&sc.camera, *size, *size).unwrap();
        let mut tangencies = 0;
        for (k, (a, b)) in pruned.depth_t.iter().zip(&whole.depth_t).enumerate() {
            let tol = 2.0 * cam.tolerance(a.max(*b));
            if a == b || (a - b).abs() <= tol {
                continue;
            }
            let (i, j) = (k as u32 % size, k as u32 / size);
            let ray = cam.pixel_ray(i, j);
            let (near, far) = (a.min(*b), a.max(*b));
            let f = |t: f64| evals[0].point(ray.at(t));
            let clear = (0..=2000)
                .map(|s| near + (far - tol - near) * f64::from(s) / 2000.0)
                .all(|t| f(t) > 0.0);
            assert!(
                clear,
                "pixel {i},{j}: depth {a} against {b}, a crossing between"
            );
            tangencies += 1;
        }
        assert!(
            tangencies * 1000 <= size * size,
            "{tangencies} tangency draws differ"
        );
    }
}

/// Shadows through a union of 300 spheres (about 3000 ops, a long
/// function: its segments' pieces run the tapes of octree cells, see
/// `render::cells`) agree with exact segment–sphere distances: a pixel is
/// lit only where its shadow segment clears every sphere (soundness, up to
/// the offset the segment starts at), and every pixel whose segment clears
/// them all by a margin is lit.
#[test]
fn shadows_through_a_large_union_match_exact_segment_tests() {
    let mut rng = ibeam::ir::random::Rng::new(11);
    let r = 0.06;
    let centres: Vec<[f64; 3]> = (0..300)
        .map(|_| [(); 3].map(|_| rng.range(-0.9, 0.9)))
        .collect();
    let balls: Vec<String> = centres
        .iter()
        .map(|[x, y, z]| format!("translate(sphere({r}), {x}, {y}, {z})"))
        .collect();
    let light = [-0.4, -1.0, -0.6];
    let text = format!(
        "object s = union({});\n\
         camera {{ {CORNER_VIEW} }}\n\
         light {{ direction = ({}, {}, {}); shadows = true; }}\n\
         bounds = (-1, -1, -1) .. (1, 1, 1);\n",
        balls.join(", "),
        light[0],
        light[1],
        light[2]
    );
    let sc = ibeam::lang::load_scene_source("union.ib", &text).unwrap();
    let size = 96;
    let evals = ibeam::eval::build_evaluators(&sc, ibeam::eval::EvalKind::Jit).unwrap();
    let out = run(&sc, evals, &opts(size, size, Method::Beam));
    let cam = RayCamera::new(&sc.camera, size, size).unwrap();
    let norm = |v: [f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|c| c / l)
    };
    let to_light = norm(light.map(|c| -c));
    let color = sc.objects[0].color;
    let (mut lit, mut dark, mut checked) = (0, 0, 0);
    for j in 0..size {
        for i in 0..size {
            let k = (j * size + i) as usize;
            if !out.hit_mask[k] {
                continue;
            }
            let ray = cam.pixel_ray(i, j);
            let p = ray.at(out.depth_t[k]);
            // The segment starts this far off the surface (see
            // `render::shadow`); distances are 1-Lipschitz, so its
            // clearance is within `eps` of the one from `p`.
            let dl = ray.dm.iter().map(|c| c * c).sum::<f64>().sqrt();
            let eps = (1e-4 * 12f64.sqrt()).max(2.0 * cam.tolerance(out.depth_t[k]) * dl) * 1.01;
            // The sphere the hit lies on, and its outward normal there.
            let dist = |c: &[f64; 3]| (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>().sqrt();
            let own = centres
                .iter()
                .min_by(|a, b| dist(a).total_cmp(&dist(b)))
                .unwrap();
            let n = norm(std::array::from_fn(|a| p[a] - own[a]));
            let facing: f64 = (0..3).map(|a| n[a] * to_light[a]).sum();
            if facing < 0.2 {
                continue;
            }
            // The segment's clearance: its distance to each sphere's
            // surface, up to where it leaves the bounds.
            let exit = (0..3)
                .map(|a| {
                    let d = to_light[a];
                    if d > 0.0 {
                        (1.0 - p[a]) / d
                    } else {
                        (-1.0 - p[a]) / d
                    }
                })
                .fold(f64::INFINITY, f64::min);
            let clearance = centres
                .iter()
                .filter(|c| !std::ptr::eq(*c, own))
                .map(|c| {
                    let w: [f64; 3] = std::array::from_fn(|a| c[a] - p[a]);
                    let s = (0..3)
                        .map(|a| w[a] * to_light[a])
                        .sum::<f64>()
                        .clamp(0.0, exit);
                    let q: [f64; 3] = std::array::from_fn(|a| p[a] + s * to_light[a]);
                    dist_between(&q, c) - r
                })
                .fold(f64::INFINITY, f64::min);
            // Lit pixels are brighter than ambient light alone.
            let ambient = color[0] * AMBIENT;
            let is_lit = f64::from(out.linear[k][0]) > ambient * 1.5;
            if is_lit {
                lit += 1;
                assert!(
                    clearance > -eps,
                    "pixel ({i}, {j}) lit through a sphere ({clearance})"
                );
            } else {
                dark += 1;
            }
            if clearance > eps + 0.02 {
                checked += 1;
                assert!(
                    is_lit,
                    "pixel ({i}, {j}) dark, its segment clears by {clearance}"
                );
            }
        }
    }
    assert!(lit > 500 && dark > 100, "{lit} lit, {dark} dark pixels");
    assert!(checked > 500, "{checked} pixels checked for light");
}

/// The distance between two points.
fn dist_between(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// Shadows through a union large enough for the shadow cells (see
/// `render::cells`), whose coarse cells the render's tiles share, each
/// built by whichever thread asks first: the image, the depths and the
/// counters do not depend on the thread count, or on which thread won.
#[test]
fn shared_shadow_cells_do_not_depend_on_the_threads() {
    let text = spheres_scene(300, 0.05, CORNER_VIEW, true);
    let sc = ibeam::lang::load_scene_source("cells.ib", &text).unwrap();
    let evals = ibeam::eval::build_evaluators(&sc, ibeam::eval::EvalKind::Jit).unwrap();
    let mut o = opts(96, 96, Method::Beam);
    let one = run(&sc, evals.clone(), &o);
    assert!(one.stats.shadow_rays > 0 && one.stats.pruned_ops_before > 0);
    for threads in [2, 2, 3] {
        o.threads = Some(threads);
        let many = run(&sc, evals.clone(), &o);
        assert_eq!(one.image.as_raw(), many.image.as_raw(), "{threads} threads");
        assert_eq!(one.depth_t, many.depth_t);
        assert_eq!(one.stats.interval_evals, many.stats.interval_evals);
        assert_eq!(one.stats.shadow_rays, many.stats.shadow_rays);
        assert_eq!(one.stats.pruned_ops_before, many.stats.pruned_ops_before);
    }
}
