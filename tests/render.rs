//! End-to-end tests of the beam tracer with hand-written evaluators
//! (interval ops and gradients written out per shape), against closed-form
//! or sphere-traced reference intersections.

use std::sync::Arc;

use ibeam::eval::{Evaluator, Grad, IntervalGrad};
use ibeam::interval::Interval;
use ibeam::ir::{BinaryOp, Builder, Var};
use ibeam::render::camera::{PixelRay, RayCamera};
use ibeam::render::output::srgb_pixel;
use ibeam::render::shade::AMBIENT;
use ibeam::render::{Method, RenderError, RenderOptions, RenderOutput, render};
use ibeam::scene::{Bounds, Camera, Light, LightKind, Object, Projection, RenderSettings, Scene};

// ---------------------------------------------------------------- shapes

fn pt(v: f64) -> Interval {
    Interval::point(v)
}

/// |p − c|² − r² (r² < 0 gives a function positive everywhere).
struct Sphere {
    c: [f64; 3],
    r2: f64,
}

impl Evaluator for Sphere {
    fn point(&self, p: [f64; 3]) -> f64 {
        (0..3).map(|i| (p[i] - self.c[i]).powi(2)).sum::<f64>() - self.r2
    }
    fn point_grad(&self, p: [f64; 3]) -> Grad {
        Grad {
            v: self.point(p),
            d: std::array::from_fn(|i| 2.0 * (p[i] - self.c[i])),
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        b.iter()
            .zip(self.c)
            .fold(pt(0.0), |s, (bi, ci)| s.add(bi.sub(pt(ci)).square()))
            .sub(pt(self.r2))
    }
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        IntervalGrad {
            v: self.interval(b),
            d: std::array::from_fn(|i| pt(2.0).mul(b[i].sub(pt(self.c[i])))),
        }
    }
}

/// (x²+y²+z²+R²−r²)² − 4R²(x²+y²): a torus around the z axis.
struct Torus {
    big: f64,
    small: f64,
}

impl Evaluator for Torus {
    fn point(&self, p: [f64; 3]) -> f64 {
        let (rr, r) = (self.big * self.big, self.small * self.small);
        let s = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + rr - r;
        s * s - 4.0 * rr * (p[0] * p[0] + p[1] * p[1])
    }
    fn point_grad(&self, p: [f64; 3]) -> Grad {
        let (rr, r) = (self.big * self.big, self.small * self.small);
        let s = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + rr - r;
        Grad {
            v: self.point(p),
            d: [
                4.0 * s * p[0] - 8.0 * rr * p[0],
                4.0 * s * p[1] - 8.0 * rr * p[1],
                4.0 * s * p[2],
            ],
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        let (rr, r) = (self.big * self.big, self.small * self.small);
        let (x2, y2, z2) = (b[0].square(), b[1].square(), b[2].square());
        let s = x2.add(y2).add(z2).add(pt(rr - r));
        s.square().sub(pt(4.0 * rr).mul(x2.add(y2)))
    }
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        let (rr, r) = (self.big * self.big, self.small * self.small);
        let (x2, y2, z2) = (b[0].square(), b[1].square(), b[2].square());
        let s = x2.add(y2).add(z2).add(pt(rr - r));
        let k = pt(4.0).mul(s);
        IntervalGrad {
            v: self.interval(b),
            d: [
                k.sub(pt(8.0 * rr)).mul(b[0]),
                k.sub(pt(8.0 * rr)).mul(b[1]),
                k.mul(b[2]),
            ],
        }
    }
}

/// |‖p‖ − 1| − h: a shell of thickness 2h around the unit sphere.
struct Shell {
    h: f64,
}

impl Evaluator for Shell {
    fn point(&self, p: [f64; 3]) -> f64 {
        ((p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 1.0).abs() - self.h
    }
    fn point_grad(&self, p: [f64; 3]) -> Grad {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let s = if r >= 1.0 { 1.0 } else { -1.0 };
        Grad {
            v: self.point(p),
            d: p.map(|c| s * c / r),
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        let r = b[0].square().add(b[1].square()).add(b[2].square()).sqrt();
        r.sub(pt(1.0)).abs().sub(pt(self.h))
    }
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        let r = b[0].square().add(b[1].square()).add(b[2].square()).sqrt();
        let e = r.sub(pt(1.0));
        let s = if e.lo > 0.0 {
            pt(1.0)
        } else if e.hi < 0.0 {
            pt(-1.0)
        } else {
            Interval::new(-1.0, 1.0)
        };
        IntervalGrad {
            v: self.interval(b),
            d: b.map(|c| s.mul(c.div(r))),
        }
    }
}

/// p[axis] − h: the half-space below a plane.
struct Ground {
    axis: usize,
    h: f64,
}

impl Evaluator for Ground {
    fn point(&self, p: [f64; 3]) -> f64 {
        p[self.axis] - self.h
    }
    fn point_grad(&self, p: [f64; 3]) -> Grad {
        Grad {
            v: self.point(p),
            d: std::array::from_fn(|i| if i == self.axis { 1.0 } else { 0.0 }),
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        b[self.axis].sub(pt(self.h))
    }
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        IntervalGrad {
            v: self.interval(b),
            d: std::array::from_fn(|i| pt(if i == self.axis { 1.0 } else { 0.0 })),
        }
    }
}

/// x² + y² − 1: a 2D disc (no z), drawn as a filled mask.
struct Disc;

impl Evaluator for Disc {
    fn point(&self, p: [f64; 3]) -> f64 {
        p[0] * p[0] + p[1] * p[1] - 1.0
    }
    fn point_grad(&self, p: [f64; 3]) -> Grad {
        Grad {
            v: self.point(p),
            d: [2.0 * p[0], 2.0 * p[1], 0.0],
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        b[0].square().add(b[1].square()).sub(pt(1.0))
    }
    fn interval_grad(&self, b: [Interval; 3]) -> IntervalGrad {
        IntervalGrad {
            v: self.interval(b),
            d: [pt(2.0).mul(b[0]), pt(2.0).mul(b[1]), pt(0.0)],
        }
    }
}

// ---------------------------------------------------------------- helpers

/// An object whose (stand-in) function reads the coordinates in `vars`:
/// the renderer uses only that from the function; the evaluators passed
/// alongside compute the shape.
fn object_using(name: &str, color: [f64; 3], vars: &[Var]) -> Object {
    let mut b = Builder::new();
    let mut root = b.constant(0.0);
    for &v in vars {
        let x = b.var(v);
        root = b.binary(BinaryOp::Add, root, x);
    }
    Object {
        name: name.into(),
        function: b.finish(root),
        color,
    }
}

fn object(name: &str, color: [f64; 3]) -> Object {
    object_using(name, color, &Var::ALL)
}

fn scene(n: usize, camera: Camera, lights: Vec<Light>) -> Scene {
    let colors = [[0.8, 0.3, 0.2], [0.2, 0.5, 0.8], [0.6, 0.6, 0.6]];
    Scene {
        objects: (0..n)
            .map(|i| object(&format!("o{i}"), colors[i % 3]))
            .collect(),
        camera,
        lights,
        bounds: Bounds::default(),
        render: RenderSettings::default(),
    }
}

fn no_shadow_light() -> Light {
    Light {
        shadows: false,
        ..Light::default_light()
    }
}

fn opts(w: u32, h: u32, method: Method) -> RenderOptions {
    RenderOptions {
        threads: Some(1),
        method,
        ..RenderOptions::new(w, h)
    }
}

fn run(sc: &Scene, ev: Vec<Arc<dyn Evaluator>>, o: &RenderOptions) -> RenderOutput {
    render(sc, &ev, o).expect("render")
}

/// Reference first intersection by sphere tracing an exact signed distance
/// (never skips a root), and whether the ray passes within `margin` of the
/// surface without crossing it before that hit (a silhouette pixel).
fn reference(
    sdf: &dyn Fn([f64; 3]) -> f64,
    ray: &PixelRay,
    t0: f64,
    t1: f64,
    margin: f64,
) -> (Option<f64>, bool) {
    let dl = ray.dm.iter().map(|c| c * c).sum::<f64>().sqrt();
    let mut t = t0;
    let mut hit = None;
    for _ in 0..200_000 {
        let s = sdf(ray.at(t));
        if s < 1e-13 {
            hit = Some(t);
            break;
        }
        t += s / dl;
        if t > t1 {
            break;
        }
    }
    // Local minima of the distance along the ray before the hit.
    let end = hit.unwrap_or(t1);
    let n = 4000;
    let samples: Vec<f64> = (0..=n)
        .map(|i| sdf(ray.at(t0 + (end - t0) * i as f64 / n as f64)))
        .collect();
    let near = (1..n).any(|i| {
        samples[i] <= samples[i - 1] && samples[i] <= samples[i + 1] && samples[i] < margin
    }) || (hit.is_none() && samples[n] < margin)
        || (hit.is_some() && hit.is_some_and(|th| th - t0 < 1e-9));
    (hit, near)
}

struct Check {
    compared: usize,
    skipped: usize,
}

/// Compares hits and depths of a render with the reference at every pixel
/// not on a silhouette.
fn check_against_reference(
    sc: &Scene,
    out: &RenderOutput,
    w: u32,
    h: u32,
    sdf: &dyn Fn([f64; 3]) -> f64,
) -> Check {
    let cam = RayCamera::new(&sc.camera, w, h).unwrap();
    let mut c = Check {
        compared: 0,
        skipped: 0,
    };
    for j in 0..h {
        for i in 0..w {
            let ray = cam.pixel_ray(i, j);
            let k = (j * w + i) as usize;
            let Some((t0, t1)) = ray.slab(&sc.bounds) else {
                assert!(!out.hit_mask[k]);
                continue;
            };
            let dl = ray.dm.iter().map(|c| c * c).sum::<f64>().sqrt();
            let margin = 3.0 * cam.tolerance(t1) * dl;
            let (hit, near) = reference(sdf, &ray, t0, t1, margin);
            if near {
                c.skipped += 1;
                continue;
            }
            c.compared += 1;
            assert_eq!(out.hit_mask[k], hit.is_some(), "pixel ({i}, {j})");
            if let Some(t) = hit {
                let err = (out.depth_t[k] - t).abs();
                assert!(
                    err <= cam.tolerance(t),
                    "pixel ({i}, {j}): depth {} vs {t}, tolerance {}",
                    out.depth_t[k],
                    cam.tolerance(t)
                );
            } else {
                assert!(out.depth_t[k].is_infinite());
            }
        }
    }
    c
}

fn sphere_sdf(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 1.0
}

fn torus_sdf(p: [f64; 3]) -> f64 {
    let q = (p[0] * p[0] + p[1] * p[1]).sqrt() - 1.0;
    (q * q + p[2] * p[2]).sqrt() - 0.5
}

fn sphere() -> Arc<dyn Evaluator> {
    Arc::new(Sphere {
        c: [0.0; 3],
        r2: 1.0,
    })
}

fn torus() -> Arc<dyn Evaluator> {
    Arc::new(Torus {
        big: 1.0,
        small: 0.5,
    })
}

fn torus_camera() -> Camera {
    Camera {
        eye: [0.5, -3.0, 3.5],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        projection: Projection::Perspective { fov_deg: 45.0 },
    }
}

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
    assert!(depth.get_pixel(24, 24).0[0] < 1000);
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
    // Whole blocks inside the disc are settled at once.
    assert!(out.stats.blocks_included > 0);
    assert!(out.stats.rays < 400, "{}", out.stats.rays);
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

/// Per-tile pruning (`ir::prune`) changes how large functions are
/// evaluated, not what is drawn: a 2D model of 36 discs (a CSG union of
/// about 200 ops, seen along z), the prospero model (2D) and the
/// colonnade model (3D) render the same hit mask and the same hit depths
/// with and without it, and pruning did happen.
#[test]
fn pruning_draws_what_the_whole_function_draws() {
    let mut text = String::from("object s = ");
    let n = 36;
    for i in 0..n {
        let (x, y) = (
            f64::from(i % 6) * 0.45 - 1.125,
            f64::from(i / 6) * 0.45 - 1.125,
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
    let mut scenes = vec![ibeam::lang::load_scene_source("discs.ib", &text).unwrap()];
    // The community models, when ../shared is beside the checkout: prospero
    // (2D) and colonnade (3D, pruned per block near the surface).
    for model in ["prospero", "colonnade"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../shared/models/{model}.vm"));
        if let Ok(s) = ibeam::lang::load_scene(&path) {
            scenes.push(s);
        }
    }
    for sc in &scenes {
        let evals = ibeam::eval::build_evaluators(sc, ibeam::eval::EvalKind::Jit).unwrap();
        assert!(evals[0].function().unwrap().live_count() >= 64);
        let size = if scenes.len() > 2 && std::ptr::eq(sc, &scenes[2]) {
            128
        } else {
            384
        };
        let mut o = opts(size, size, Method::Beam);
        let pruned = run(sc, evals.clone(), &o);
        o.prune = false;
        let whole = run(sc, evals, &o);
        assert!(pruned.stats.pruned_ops_after > 0, "nothing was pruned");
        assert!(pruned.stats.pruned_ops_after * 2 <= pruned.stats.pruned_ops_before);
        assert_eq!(whole.stats.pruned_ops_before, 0);
        assert_eq!(pruned.hit_mask, whole.hit_mask);
        // Point values agree bit for bit, but a block that prunes decides
        // its beam tests on tighter intervals, so a root may be refined
        // from another bracket: depths agree to the refinement tolerance.
        for (a, b) in pruned.depth_t.iter().zip(&whole.depth_t) {
            assert!(
                a == b || (a - b).abs() <= 1e-9 * a.abs(),
                "depth {a} against {b}"
            );
        }
    }
}
