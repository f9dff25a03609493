//! The oracle: what a scene's rays and shadow segments surely do, from
//! interval evaluations of each object's whole, unsimplified function on
//! the reference interpreter, and nothing else of the renderer (no
//! simplification, tapes, pruning, regions, beams, sweeps, refinement or
//! camera code: the rays are rebuilt here from the scene's camera).
//!
//! A ray is stepped front to back by halving pieces of a fixed first
//! length down to a fixed finest length; a piece is free when every
//! object's interval over the piece's box (widened by a margin across the
//! ray) is positive or empty. A finest piece that is not free has its
//! midpoint box tried for "surely inside" (some object's interval wholly
//! negative). So a ray is *surely empty* (every piece free), *surely hit*
//! (its first root lies between the first piece that is not free and the
//! first surely-inside box) or *unknown*.
//!
//! A hit's segment towards a light is stepped the same way with boxes as
//! wide as the distance between the renderer's hit and the oracle's
//! bracket: *surely shadowed* when one box is surely inside (every point
//! that close to the hit has its segment cross solid), *surely lit* when
//! every piece is free, the first ones by a monotone increase of the
//! objects along the segment (which assumes f continuous next to the hit:
//! it is read only to catch false shadows, never to excuse a light leak).

use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::interval::Interval;
use ibeam::scene::{LightKind, Projection, Scene};

type Vec3 = [f64; 3];
type IBox = [Interval; 3];

/// What the oracle proves of one pixel's centre ray.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum RayFate {
    /// No object vanishes or is negative anywhere along it (in the bounds).
    Empty,
    /// Its first root lies in `[lo, hi]` (ray parameter).
    Hit { lo: f64, hi: f64 },
    /// Its first root lies in `[lo, hi]`, within a finest piece of where
    /// it enters the bounds: it may be a cut face (a solid cut open by the
    /// bounds), lit or shadowed from inside the solid.
    Cut { lo: f64, hi: f64 },
    /// Not free from `lo` on, and no surely-inside point found.
    Unknown { lo: f64 },
}

/// What the oracle proves of a hit's segment towards a light.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ShadowFate {
    /// Solid lies on the segment of every point near the hit.
    Shadowed,
    /// No solid on the segment.
    Lit,
    /// Neither proven.
    Unknown,
}

/// The scene's objects, camera and bounds as the oracle reads them.
pub struct Oracle {
    objects: Vec<Interpreter>,
    lo: Vec3,
    hi: Vec3,
    diag: f64,
    eye: Vec3,
    right: Vec3,
    down: Vec3,
    dir: Vec3,
    view_w: f64,
    view_h: f64,
    width: u32,
    height: u32,
    /// Distance between neighbouring pixel centres (world units).
    pub pixel: f64,
}

fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: Vec3) -> Vec3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}

/// The box around the straight piece from `a` to `b`, `margin` wider on
/// every side (plus a relative pad for the rounding of the corners).
fn piece_box(a: Vec3, b: Vec3, margin: f64) -> IBox {
    std::array::from_fn(|i| {
        let (l, h) = (a[i].min(b[i]), a[i].max(b[i]));
        let pad = margin + 1e-12 * (l.abs().max(h.abs()) + 1.0);
        Interval::new(l - pad, h + pad)
    })
}

/// How an object's interval over a box reads.
#[derive(Copy, Clone, PartialEq, Eq)]
enum Sign {
    Positive,
    Negative,
    Either,
}

fn sign_of(f: Interval) -> Sign {
    if f.lo.is_nan() || f.hi.is_nan() || f.lo > 0.0 {
        Sign::Positive
    } else if f.hi < 0.0 {
        Sign::Negative
    } else {
        Sign::Either
    }
}

impl Oracle {
    /// The oracle of `scene` (orthographic cameras only) at `width × height`.
    pub fn new(scene: &Scene, width: u32, height: u32) -> Oracle {
        let Projection::Orthographic { width: view_w } = scene.camera.projection else {
            panic!("the oracle rebuilds orthographic rays only");
        };
        let c = &scene.camera;
        let dir = unit(add(c.target, scale(c.eye, -1.0)));
        let right = unit(cross(dir, unit(c.up)));
        let up = cross(right, dir);
        let view_h = view_w * f64::from(height) / f64::from(width);
        let (lo, hi) = (scene.bounds.min, scene.bounds.max);
        let diag = dot(add(hi, scale(lo, -1.0)), add(hi, scale(lo, -1.0))).sqrt();
        Oracle {
            objects: scene
                .objects
                .iter()
                .map(|o| Interpreter::new(o.function.clone()))
                .collect(),
            lo,
            hi,
            diag,
            eye: c.eye,
            right,
            down: scale(up, -1.0),
            dir,
            view_w,
            view_h,
            width,
            height,
            pixel: view_w / f64::from(width),
        }
    }

    /// The ray direction (every pixel's).
    pub fn dir(&self) -> Vec3 {
        self.dir
    }

    /// The origin of the centre ray of pixel (i, j).
    pub fn origin(&self, i: u32, j: u32) -> Vec3 {
        let x = (f64::from(i) + 0.5) / f64::from(self.width) - 0.5;
        let y = (f64::from(j) + 0.5) / f64::from(self.height) - 0.5;
        add(
            self.eye,
            add(
                scale(self.right, x * self.view_w),
                scale(self.down, y * self.view_h),
            ),
        )
    }

    /// The parameter range over which `o + t·d` lies in the bounds.
    fn clip(&self, o: Vec3, d: Vec3) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for i in 0..3 {
            if d[i] == 0.0 {
                if o[i] < self.lo[i] || o[i] > self.hi[i] {
                    return None;
                }
                continue;
            }
            let (a, b) = ((self.lo[i] - o[i]) / d[i], (self.hi[i] - o[i]) / d[i]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        // Widened a little: the renderer must not see surface the oracle
        // did not look at.
        let pad = 1e-9 * self.diag;
        (t0 <= t1).then_some(((t0 - pad).max(0.0), t1 + pad))
    }

    /// The box clipped to the bounds (widened as in `clip`); None outside.
    fn in_bounds(&self, b: IBox) -> Option<IBox> {
        let pad = 1e-9 * self.diag;
        let mut out = b;
        for i in 0..3 {
            let (l, h) = (b[i].lo.max(self.lo[i] - pad), b[i].hi.min(self.hi[i] + pad));
            if l > h {
                return None;
            }
            out[i] = Interval::new(l, h);
        }
        Some(out)
    }

    /// Whether the box lies wholly inside the (unwidened) bounds.
    fn inside_bounds(&self, b: &IBox) -> bool {
        (0..3).all(|i| b[i].lo >= self.lo[i] && b[i].hi <= self.hi[i])
    }

    /// The scene's sign over a box: positive (every object positive or
    /// undefined), negative (one object wholly negative) or either.
    fn scene_sign(&self, b: IBox) -> Sign {
        let Some(c) = self.in_bounds(b) else {
            return Sign::Positive;
        };
        let mut all_positive = true;
        for f in &self.objects {
            match sign_of(f.interval(c)) {
                Sign::Negative if c == b && self.inside_bounds(&c) => return Sign::Negative,
                Sign::Positive => {}
                _ => all_positive = false,
            }
        }
        if all_positive {
            Sign::Positive
        } else {
            Sign::Either
        }
    }

    /// Front-to-back steps over `[t0, t1]` of the line `o + t·d` with boxes
    /// `margin` wide across it, halved down to `least` long: calls
    /// `finest(a, b)` on each finest piece that is not free, in order,
    /// until it returns true; whether every piece was free.
    fn steps(
        &self,
        o: Vec3,
        d: Vec3,
        (t0, t1): (f64, f64),
        (margin, least): (f64, f64),
        mut finest: impl FnMut(f64, f64) -> bool,
    ) -> bool {
        let first = self.diag / 64.0;
        let n = ((t1 - t0) / first).ceil().max(1.0) as usize;
        let mut stack: Vec<(f64, f64)> = (0..n)
            .rev()
            .map(|k| {
                let a = t0 + (t1 - t0) * k as f64 / n as f64;
                let b = t0 + (t1 - t0) * (k + 1) as f64 / n as f64;
                (a, b)
            })
            .collect();
        let mut all_free = true;
        while let Some((a, b)) = stack.pop() {
            let bx = piece_box(add(o, scale(d, a)), add(o, scale(d, b)), margin);
            if self.scene_sign(bx) == Sign::Positive {
                continue;
            }
            if b - a > least {
                let m = 0.5 * (a + b);
                stack.push((m, b));
                stack.push((a, m));
                continue;
            }
            all_free = false;
            if finest(a, b) {
                break;
            }
        }
        all_free
    }

    /// Whether the point `p` surely lies inside a solid, with every point
    /// within `radius` of it.
    fn surely_inside(&self, p: Vec3, radius: f64) -> bool {
        self.scene_sign(piece_box(p, p, radius)) == Sign::Negative
    }

    /// What the centre ray of pixel (i, j) surely does.
    pub fn ray(&self, i: u32, j: u32) -> RayFate {
        let (o, d) = (self.origin(i, j), self.dir);
        let Some(range) = self.clip(o, d) else {
            return RayFate::Empty;
        };
        let margin = 1e-9 * self.diag;
        let (mut first, mut inside) = (None, None);
        let mut budget = 4096;
        let free = self.steps(o, d, range, (margin, self.pixel / 64.0), |a, b| {
            first.get_or_insert(a);
            let m = 0.5 * (a + b);
            if self.surely_inside(add(o, scale(d, m)), margin) {
                inside = Some(m);
                return true;
            }
            budget -= 1;
            budget == 0
        });
        match (free, first, inside) {
            (true, _, _) => RayFate::Empty,
            (_, Some(lo), Some(hi)) if lo <= range.0 + self.pixel / 32.0 => RayFate::Cut { lo, hi },
            (_, Some(lo), Some(hi)) => RayFate::Hit { lo, hi },
            (_, lo, _) => RayFate::Unknown {
                lo: lo.unwrap_or(range.0),
            },
        }
    }

    /// The unit direction towards the light from `p`, and how far the
    /// segment reaches (to the light, or out of the bounds).
    fn towards(&self, light: LightKind, p: Vec3) -> (Vec3, f64) {
        match light {
            LightKind::Directional(dir) => (unit(scale(dir, -1.0)), 2.0 * self.diag),
            LightKind::Point(l) => {
                let v = add(l, scale(p, -1.0));
                let len = dot(v, v).sqrt();
                (scale(v, 1.0 / len), len)
            }
        }
    }

    /// What the segment from the hit `p` towards `light` surely does,
    /// for every start point within `near` of `p` (the distance between
    /// the renderer's hit and the true one).
    pub fn shadow(&self, p: Vec3, light: LightKind, near: f64) -> ShadowFate {
        let (l, reach) = self.towards(light, p);
        let Some((_, s1)) = self.clip(p, l) else {
            return ShadowFate::Unknown;
        };
        let s1 = s1.min(reach);
        // For a point light, start points `near` apart have segments up
        // to `near` apart: the margin covers both. Lit is proven at the
        // resolution of the renderer's own shadow sweep (pieces a quarter
        // of a pixel long), shadow down to a 64th of a pixel.
        // Positivity at a piece's start is carried only from a piece
        // proven increasing from a positive start (at s = 0, the hit
        // itself, where f = 0); after a free piece, which says nothing
        // of f where it is undefined, it is checked at the start anew.
        let (mut front, mut lit, mut last_end) = (true, true, 0.0);
        self.steps(p, l, (0.0, s1), (near, self.pixel / 4.0), |a, b| {
            let start_known = front && a == last_end;
            lit = (start_known || self.outside_near(add(p, scale(l, a)), near))
                && self.increasing(p, l, (a, b), near);
            front = lit;
            last_end = b;
            !lit
        });
        let front = lit;
        if front {
            return ShadowFate::Lit;
        }
        let mut blocked = false;
        self.steps(p, l, (0.0, s1), (near, self.pixel / 64.0), |a, b| {
            blocked = self.surely_inside(add(p, scale(l, 0.5 * (a + b))), near);
            blocked
        });
        if blocked {
            ShadowFate::Shadowed
        } else {
            ShadowFate::Unknown
        }
    }

    /// Whether every object is defined and positive over the box around
    /// `p` (a box on which f is undefined in part can still pass: this is
    /// read only for lit proofs, see the module doc).
    fn outside_near(&self, p: Vec3, near: f64) -> bool {
        let c = piece_box(p, p, near);
        self.objects.iter().all(|f| {
            let v = f.interval(c);
            !v.lo.is_nan() && v.lo > 0.0
        })
    }

    /// Whether every object that may vanish over the piece's box
    /// increases strictly along `l` there (finite derivative bounds).
    fn increasing(&self, p: Vec3, l: Vec3, (a, b): (f64, f64), near: f64) -> bool {
        let bx = piece_box(add(p, scale(l, a)), add(p, scale(l, b)), near);
        let Some(c) = self.in_bounds(bx) else {
            return true;
        };
        let dirs = l.map(Interval::point);
        self.objects.iter().all(|f| {
            if sign_of(f.interval(c)) == Sign::Positive {
                return true;
            }
            let [_, dv] = f.interval_dir(c, dirs);
            dv.lo > 0.0 && dv.hi.is_finite()
        })
    }

    /// The outward unit normal at `p` of the object nearest zero there,
    /// by central differences of point values, if they are finite.
    pub fn normal(&self, p: Vec3) -> Option<Vec3> {
        let f = self
            .objects
            .iter()
            .min_by(|a, b| a.point(p).abs().total_cmp(&b.point(p).abs()))?;
        let h = 1e-6 * self.diag;
        let g: Vec3 = std::array::from_fn(|i| {
            let (mut a, mut b) = (p, p);
            a[i] += h;
            b[i] -= h;
            (f.point(a) - f.point(b)) / (2.0 * h)
        });
        let n = dot(g, g).sqrt();
        (n.is_finite() && n > 0.0).then(|| scale(g, 1.0 / n))
    }

    /// The unit direction towards `light` from `p`.
    pub fn light_dir(&self, light: LightKind, p: Vec3) -> Vec3 {
        self.towards(light, p).0
    }
}

/// The point `o + t·d`.
pub fn at(o: Vec3, d: Vec3, t: f64) -> Vec3 {
    add(o, scale(d, t))
}

/// The dot product.
pub fn dot3(a: Vec3, b: Vec3) -> f64 {
    dot(a, b)
}
