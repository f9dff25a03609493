//! End-to-end tests of the beam tracer with hand-written evaluators
//! (interval ops and gradients written out per shape), against closed-form
//! or sphere-traced reference intersections.
//!
//! One test binary; the tests are in its modules.

#[path = "../common/models.rs"]
mod models;
mod scenes;
mod stream;
mod tracing;

use std::sync::Arc;

use ibeam::eval::{Bulk, Evaluator, Grad, IntervalGrad, Single, Specialise};
use ibeam::interval::Interval;
use ibeam::ir::{BinaryOp, Builder, Var};
use ibeam::render::camera::{PixelRay, RayCamera};
use ibeam::render::output::srgb_pixel;
use ibeam::render::shade::AMBIENT;
use ibeam::render::{Method, RenderError, RenderOptions, RenderOutput, render};
use ibeam::scene::{Bounds, Camera, Light, LightKind, Object, Projection, RenderSettings, Scene};

// ---------------------------------------------------------------- shapes

/// The point interval [v, v].
fn pt(v: f64) -> Interval {
    Interval::point(v)
}

/// |p − c|² − r² (r² < 0 gives a function positive everywhere).
struct Sphere {
    c: [f64; 3],
    r2: f64,
}

impl Single for Sphere {
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

impl Bulk for Sphere {}

impl Specialise for Sphere {}

/// (x²+y²+z²+R²−r²)² − 4R²(x²+y²): a torus around the z axis.
struct Torus {
    big: f64,
    small: f64,
}

impl Single for Torus {
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

impl Bulk for Torus {}

impl Specialise for Torus {}

/// |‖p‖ − 1| − h: a shell of thickness 2h around the unit sphere.
struct Shell {
    h: f64,
}

impl Single for Shell {
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

impl Bulk for Shell {}

impl Specialise for Shell {}

/// p[axis] − h: the half-space below a plane.
struct Ground {
    axis: usize,
    h: f64,
}

impl Single for Ground {
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

impl Bulk for Ground {}

impl Specialise for Ground {}

/// x² + y² − 1: a 2D disc (no z), drawn as a filled mask.
struct Disc;

impl Single for Disc {
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

impl Bulk for Disc {}

impl Specialise for Disc {}

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

/// An object over x, y and z (see [`object_using`]).
fn object(name: &str, color: [f64; 3]) -> Object {
    object_using(name, color, &Var::ALL)
}

/// A scene of `n` objects seen by `camera` under `lights`.
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

/// The default light, casting no shadows.
fn no_shadow_light() -> Light {
    Light {
        shadows: false,
        ..Light::default_light()
    }
}

/// Options for a `w × h` render by `method` on one thread.
fn opts(w: u32, h: u32, method: Method) -> RenderOptions {
    RenderOptions {
        threads: Some(1),
        method,
        ..RenderOptions::new(w, h)
    }
}

/// Renders `sc` with the evaluators `ev`, which must succeed.
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

/// How many pixels a reference comparison compared and skipped.
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

/// Signed distance to the unit sphere.
fn sphere_sdf(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 1.0
}

/// Signed distance to the torus of radii 1 and 0.5 around z.
fn torus_sdf(p: [f64; 3]) -> f64 {
    let q = (p[0] * p[0] + p[1] * p[1]).sqrt() - 1.0;
    (q * q + p[2] * p[2]).sqrt() - 0.5
}

/// The unit sphere at the origin.
fn sphere() -> Arc<dyn Evaluator> {
    Arc::new(Sphere {
        c: [0.0; 3],
        r2: 1.0,
    })
}

/// The torus of radii 1 and 0.5 around the z axis.
fn torus() -> Arc<dyn Evaluator> {
    Arc::new(Torus {
        big: 1.0,
        small: 0.5,
    })
}

/// A camera looking down at the torus from above one side.
fn torus_camera() -> Camera {
    Camera {
        eye: [0.5, -3.0, 3.5],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        projection: Projection::Perspective { fov_deg: 45.0 },
    }
}
