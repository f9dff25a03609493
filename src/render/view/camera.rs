//! Screen-to-ray mapping and sound beam hulls.
//!
//! A pixel at screen position (X, Y) (pixel units, centres at `i + 0.5`)
//! owns the ray `p(t) = o(X, Y) + t·d(X, Y)` with `o` and `d` affine in
//! X and Y. Perspective cameras have constant `o` (the eye), orthographic
//! ones constant `d`. Either way `p` is multilinear in (X, Y, t), so over a
//! box X × Y × T it takes its extremes at the 8 corners: the hull of the
//! corners is the exact hull of the beam. The corners are evaluated with
//! outward-rounded interval arithmetic, so the hull is sound for the exact
//! rays defined by the (f64) camera coefficients; single-ray boxes use the
//! same coefficients, so a ray's boxes and its block's hulls describe the
//! same real line.

use glam::DVec3;

use crate::interval::Interval;
pub use crate::interval::boxes::IBox;
use crate::interval::boxes::{box_hull, ray_box, ray_point_box};
use crate::scene::{Bounds, Camera, Projection};

pub use super::pixel_ray::PixelRay;

/// Smallest depth tolerance, in t units.
const TOLERANCE_FLOOR: f64 = 1e-9;
/// Relative widening of a ray's slab range, so that rounding in the slab
/// test never clips off a point inside the bounds.
pub(crate) const SLAB_PAD: f64 = 1e-9;

/// Why a camera cannot produce rays.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// `eye == target`, or a coordinate is not finite.
    EyeIsTarget,
    /// `up` is zero or parallel to the view direction.
    UpParallel,
    /// Field of view outside (0, 180) degrees or a non-positive width.
    BadProjection,
    /// Width or height is zero.
    ZeroSize,
}

impl std::fmt::Display for CameraError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CameraError::EyeIsTarget => write!(f, "camera eye equals target (no view direction)"),
            CameraError::UpParallel => {
                write!(
                    f,
                    "camera up vector is zero or parallel to the view direction"
                )
            }
            CameraError::BadProjection => {
                write!(
                    f,
                    "camera fov must be in (0, 180) degrees and width positive"
                )
            }
            CameraError::ZeroSize => write!(f, "image size must be at least 1x1"),
        }
    }
}

/// The affine ray map of a camera for one image size.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RayCamera {
    /// Ray origin at screen position (0, 0).
    pub o0: DVec3,
    /// Change of the origin per pixel in X.
    pub ox: DVec3,
    /// Change of the origin per pixel in Y.
    pub oy: DVec3,
    /// Ray direction at screen position (0, 0).
    pub d0: DVec3,
    /// Change of the direction per pixel in X.
    pub dx: DVec3,
    /// Change of the direction per pixel in Y.
    pub dy: DVec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    // Pixel spacing in world units at t = 0 and its growth per unit t.
    spacing0: f64,
    spacing_per_t: f64,
    // The depth tolerance as a share of the pixel spacing.
    tolerance_share: f64,
}

/// The depth tolerance of a camera as a share of its pixel spacing.
const TOLERANCE_SHARE: f64 = 0.25;

/// How many times finer than the depth tolerance a root is refined (see
/// [`RayCamera::root_tolerance`]).
const ROOT_REFINEMENT: f64 = 16.0;

/// `a / |a|`, computed as `a * (1 / |a|)`, when |a| is finite and > 0.
///
/// The renderer's contract, spelled out rather than borrowed from
/// `DVec3::try_normalize`, which tests `1 / |a|` instead: the two agree
/// today (a nonzero |a| is at least √(smallest subnormal) ≈ 2.2e-162, so
/// `1 / |a|` never overflows), but the images must not depend on glam
/// keeping that test and that arithmetic.
pub(crate) fn normalize(a: DVec3) -> Option<DVec3> {
    normalize_with_length(a).0
}

/// [`normalize`] and the length `|a|` it divides by, for callers that
/// need both (the same bits as computing each alone).
pub(crate) fn normalize_with_length(a: DVec3) -> (Option<DVec3>, f64) {
    let n = a.length();
    ((n.is_finite() && n > 0.0).then(|| a * (1.0 / n)), n)
}

/// The scene bounds as a box.
pub fn bounds_box(b: &Bounds) -> IBox {
    std::array::from_fn(|i| Interval::new(b.min[i], b.max[i]))
}

impl RayCamera {
    /// The ray map of `cam` for a `width × height` image.
    pub fn new(cam: &Camera, width: u32, height: u32) -> Result<RayCamera, CameraError> {
        if width == 0 || height == 0 {
            return Err(CameraError::ZeroSize);
        }
        let finite = |v: [f64; 3]| v.iter().all(|c| c.is_finite());
        if !finite(cam.eye) || !finite(cam.target) || !finite(cam.up) {
            return Err(CameraError::EyeIsTarget);
        }
        let eye = DVec3::from_array(cam.eye);
        let target = DVec3::from_array(cam.target);
        let w = normalize(target - eye).ok_or(CameraError::EyeIsTarget)?;
        let up = normalize(DVec3::from_array(cam.up)).ok_or(CameraError::UpParallel)?;
        let side = w.cross(up);
        // A relative threshold: an up vector within ~0.06° of the view
        // direction gives a basis too ill-conditioned to be meaningful.
        if side.length() < 1e-6 {
            return Err(CameraError::UpParallel);
        }
        let u = normalize(side).ok_or(CameraError::UpParallel)?;
        let v = u.cross(w);
        let (wf, hf) = (width as f64, height as f64);
        let aspect = wf / hf;
        match cam.projection {
            Projection::Perspective { fov_deg } => {
                if !(fov_deg > 0.0 && fov_deg < 180.0) {
                    return Err(CameraError::BadProjection);
                }
                let hh = (fov_deg.to_radians() * 0.5).tan();
                let hw = hh * aspect;
                let d0 = w - u * hw + v * hh;
                let dx = u * (2.0 * hw / wf);
                let dy = v * (-2.0 * hh / hf);
                Ok(RayCamera {
                    o0: eye,
                    ox: DVec3::ZERO,
                    oy: DVec3::ZERO,
                    d0,
                    dx,
                    dy,
                    width,
                    height,
                    spacing0: 0.0,
                    spacing_per_t: dx.length().max(dy.length()),
                    tolerance_share: TOLERANCE_SHARE,
                })
            }
            Projection::Orthographic { width: vw } => {
                if !(vw > 0.0 && vw.is_finite()) {
                    return Err(CameraError::BadProjection);
                }
                let hw = vw * 0.5;
                let hh = hw / aspect;
                let o0 = eye - u * hw + v * hh;
                let ox = u * (2.0 * hw / wf);
                let oy = v * (-2.0 * hh / hf);
                Ok(RayCamera {
                    o0,
                    ox,
                    oy,
                    d0: w,
                    dx: DVec3::ZERO,
                    dy: DVec3::ZERO,
                    width,
                    height,
                    spacing0: ox.length().max(oy.length()),
                    spacing_per_t: 0.0,
                    tolerance_share: TOLERANCE_SHARE,
                })
            }
        }
    }

    /// Enclosures of the origin and direction of the ray at screen (x, y).
    pub fn ray_at(&self, x: f64, y: f64) -> (IBox, IBox) {
        let (xi, yi) = (Interval::point(x), Interval::point(y));
        let aff = |c: DVec3, cx: DVec3, cy: DVec3| -> IBox {
            let axis = |i: usize| {
                Interval::point(c[i])
                    .add(xi.mul(Interval::point(cx[i])))
                    .add(yi.mul(Interval::point(cy[i])))
            };
            [axis(0), axis(1), axis(2)]
        };
        (
            aff(self.o0, self.ox, self.oy),
            aff(self.d0, self.dx, self.dy),
        )
    }

    /// Origin and direction of the ray through the centre of pixel (i, j),
    /// as enclosures and as f64 midpoints.
    pub fn pixel_ray(&self, i: u32, j: u32) -> PixelRay {
        let (o, d) = self.ray_at(i as f64 + 0.5, j as f64 + 0.5);
        PixelRay::new(o, d)
    }

    /// The rays through the centres of the `w × h` pixels from `(x0, y0)`,
    /// row-major: the same bits as [`RayCamera::pixel_ray`] for each (see
    /// [`RayGrid`]).
    pub fn pixel_rays(&self, (x0, y0): (u32, u32), (w, h): (u32, u32)) -> Vec<PixelRay> {
        RayGrid::new(self, (x0, y0), (w, h)).rays()
    }

    /// A sound hull of every ray point with screen x ∈ `xs`, y ∈ `ys`
    /// and parameter t ∈ `t` (from the 8 corners, see the module doc).
    pub fn hull(&self, xs: (f64, f64), ys: (f64, f64), t: Interval) -> IBox {
        self.corners(xs, ys).hull(t)
    }

    /// The corner rays of the screen rectangle `xs × ys`, for repeated
    /// hulls over different T.
    pub fn corners(&self, xs: (f64, f64), ys: (f64, f64)) -> CornerRays {
        CornerRays::new([
            self.ray_at(xs.0, ys.0),
            self.ray_at(xs.1, ys.0),
            self.ray_at(xs.0, ys.1),
            self.ray_at(xs.1, ys.1),
        ])
    }

    /// Distance between neighbouring pixel rays at parameter t, world units.
    pub fn spacing(&self, t: f64) -> f64 {
        self.spacing0 + t.max(0.0) * self.spacing_per_t
    }

    /// The depth tolerance at parameter t: a quarter of the pixel spacing
    /// (in t units; |d| ≥ 1, so the world error is at most
    /// `tolerance · |d|`), never below a tiny absolute floor; a share
    /// `factor` times smaller after [`RayCamera::with_tolerance_of_finer`].
    /// Visibility decisions (tangency, shadow offsets) use it.
    pub fn tolerance(&self, t: f64) -> f64 {
        (self.tolerance_share * self.spacing(t)).max(TOLERANCE_FLOOR)
    }

    /// The width to which a bracketed root is refined at parameter t: the
    /// depth tolerance over `ROOT_REFINEMENT` (16). The
    /// tolerance decides visibility, but shading reads the normal at the
    /// refined point, and in a highlight a root a quarter of a sample's
    /// spacing off is visible in the mean of a few samples: at 256², IAA's
    /// pixels sampled 2×2 on orthocircle were most of its error above
    /// grid:8's. A few more false-position steps (each one point
    /// evaluation, and the secant converges superlinearly) removed it;
    /// `grid:N`'s RMSE fell by 0.5%.
    pub fn root_tolerance(&self, t: f64) -> f64 {
        (self.tolerance(t) / ROOT_REFINEMENT).max(TOLERANCE_FLOOR)
    }

    /// The same rays with the depth tolerance of a camera `factor` times
    /// finer (see [`RayCamera::tolerance`]).
    pub fn with_tolerance_of_finer(self, factor: u32) -> RayCamera {
        RayCamera {
            tolerance_share: self.tolerance_share / f64::from(factor.max(1)),
            ..self
        }
    }
}

// The bits of a box's bounds, for exact comparison (-0 and 0 differ).
fn bits(b: &IBox) -> [u64; 6] {
    [
        b[0].lo.to_bits(),
        b[0].hi.to_bits(),
        b[1].lo.to_bits(),
        b[1].hi.to_bits(),
        b[2].lo.to_bits(),
        b[2].hi.to_bits(),
    ]
}

/// Enclosures of the origin and direction of a block's four corner rays.
#[derive(Copy, Clone, Debug)]
pub struct CornerRays {
    // Origin and direction enclosures, corner by corner (private: `shape`
    // is derived from them).
    rays: [(IBox, IBox); 4],
    // What the corners share, found once: a block's hull is taken at
    // every piece of its sweep, and comparing the corners' bits there
    // cost more than the hull itself.
    shape: Shape,
    // The hulls of the corners' origins and directions, also taken once
    // (rebuilding them at each hull was a tenth of IAA's instructions).
    origins: IBox,
    directions: IBox,
}

// Which part of the ray the four corners share, to the bit.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Shape {
    SharedDirection,
    SharedOrigin,
    Neither,
}

impl CornerRays {
    /// The corner rays `rays` (origin and direction enclosures).
    pub fn new(rays: [(IBox, IBox); 4]) -> CornerRays {
        let shared = |part: fn(&(IBox, IBox)) -> IBox| {
            rays.iter().all(|r| bits(&part(r)) == bits(&part(&rays[0])))
        };
        let shape = if shared(|r| r.1) {
            Shape::SharedDirection
        } else if shared(|r| r.0) {
            Shape::SharedOrigin
        } else {
            Shape::Neither
        };
        let hull4 = |part: fn(&(IBox, IBox)) -> IBox| {
            let c = rays.map(|r| part(&r));
            box_hull(box_hull(c[0], c[1]), box_hull(c[2], c[3]))
        };
        CornerRays {
            rays,
            shape,
            origins: hull4(|r| r.0),
            directions: hull4(|r| r.1),
        }
    }

    /// Origin and direction enclosures, corner by corner.
    pub fn rays(&self) -> &[(IBox, IBox); 4] {
        &self.rays
    }

    /// A sound hull of the block's ray points for t ∈ `t`: the hull of the
    /// corner rays' points at both ends.
    ///
    /// Each bound of a ray's point at a fixed t is a monotone function of
    /// the bounds of its origin and direction (outward rounding is
    /// monotone), so where the corners share one direction (parallel
    /// rays) that hull is, to the bit, the point of the origins' hull, and
    /// where they share one origin (a pinhole) that of the directions'
    /// hull: two ray points instead of eight.
    pub fn hull(&self, t: Interval) -> IBox {
        let c = &self.rays;
        let (o, d) = match self.shape {
            Shape::SharedDirection => (self.origins, c[0].1),
            Shape::SharedOrigin => (c[0].0, self.directions),
            Shape::Neither => return self.hull_of_corners(t),
        };
        // For t > 0 the hull of the two ends is the box of the whole
        // piece, bound for bound (each end's bounds are monotone in its
        // product's, and the product's extremes over t are at its ends):
        // one interval product per axis instead of two point products
        // and a hull (a block's hull is taken at every piece of its sweep).
        if t.lo > 0.0 {
            return ray_box(o, d, t);
        }
        box_hull(ray_point_box(o, d, t.lo), ray_point_box(o, d, t.hi))
    }

    // [`CornerRays::hull`] corner by corner.
    fn hull_of_corners(&self, t: Interval) -> IBox {
        let mut out = ray_point_box(self.rays[0].0, self.rays[0].1, t.lo);
        for (o, d) in &self.rays {
            for tc in [t.lo, t.hi] {
                out = box_hull(out, ray_point_box(*o, *d, tc));
            }
        }
        out
    }

    /// An interval of the ray parameter holding every t at which a ray of
    /// the block is inside `b` (each ray's clipped range, as
    /// [`PixelRay::slab`] computes it, lies inside it, with a relative
    /// margin for that computation's rounding); `None` when no ray of the
    /// block meets `b`, or no finite range holds them (every axis has a
    /// direction that may be 0).
    pub fn slab_range(&self, b: &crate::scene::Bounds) -> Option<Interval> {
        let (o, d) = (self.origins(), self.directions());
        let mut t = Interval::new(0.0, f64::INFINITY);
        for i in 0..3 {
            // An axis along which some direction is zero bounds nothing.
            if d[i].lo <= 0.0 && d[i].hi >= 0.0 {
                continue;
            }
            let along = Interval::new(b.min[i], b.max[i]).sub(o[i]).div(d[i]);
            t = Interval::new(t.lo.max(along.lo), t.hi.min(along.hi));
        }
        // `slab` pads each pixel's range by `SLAB_PAD` relative; twice that,
        // plus the margin for its rounding.
        let pad = |v: f64| 2.0 * SLAB_PAD * (1.0 + v.abs()) + 1e-9 * (t.hi - t.lo);
        let t = Interval::new((t.lo - pad(t.lo)).max(0.0), t.hi + pad(t.hi));
        (t.lo <= t.hi && t.hi.is_finite()).then_some(t)
    }

    /// A sound hull of the block's ray origins (affine in screen position,
    /// like the directions).
    pub fn origins(&self) -> IBox {
        self.origins
    }

    /// A sound hull of the block's ray directions: the hull of the corner
    /// directions, since a ray's direction is affine in its screen position.
    pub fn directions(&self) -> IBox {
        self.directions
    }
}

/// The rays of a block of pixels, as per-column and per-row terms.
///
/// A pixel's ray origin is its column's term `c + x·cx` plus its row's
/// `y·cy` (its direction likewise), which are the same bits as
/// [`RayCamera::pixel_ray`] computes; the terms are computed once per
/// column and row (outward rounding makes every interval product costly,
/// and a tile's rays are a per-pixel cost of every render), and a ray is
/// two sums and its midpoints, built when it is asked for.
#[derive(Clone, Debug)]
pub struct RayGrid {
    w: u32,
    origin_columns: Vec<IBox>,
    origin_rows: Vec<IBox>,
    direction_columns: Vec<IBox>,
    direction_rows: Vec<IBox>,
    // A parallel camera's direction terms are the same for every column
    // and row: their sum, and its midpoint, computed once (the same bits,
    // from the same operands).
    parallel: Option<(IBox, [f64; 3])>,
}

impl RayGrid {
    /// The terms of the `w × h` pixels from `(x0, y0)`.
    pub fn new(cam: &RayCamera, origin: (u32, u32), size: (u32, u32)) -> RayGrid {
        RayGrid::at_offset(cam, origin, size, 0.5)
    }

    /// The terms of the rays through the `(w + 1) × (h + 1)` pixel corners
    /// of the `w × h` pixels from `(x0, y0)`: ray `(i, j)` is
    /// [`RayCamera::ray_at`]`(x0 + i, y0 + j)`, to the bit.
    pub fn of_pixel_corners(cam: &RayCamera, origin: (u32, u32), (w, h): (u32, u32)) -> RayGrid {
        RayGrid::at_offset(cam, origin, (w + 1, h + 1), 0.0)
    }

    // The terms of the rays at `offset` (in pixels, both axes) from the
    // top left corners of the `w × h` pixels from `(x0, y0)`.
    fn at_offset(
        cam: &RayCamera,
        (x0, y0): (u32, u32),
        (w, h): (u32, u32),
        offset: f64,
    ) -> RayGrid {
        let column = |c: DVec3, cx: DVec3| -> Vec<IBox> {
            (x0..x0 + w)
                .map(|i| {
                    let xi = Interval::point(f64::from(i) + offset);
                    std::array::from_fn(|k| {
                        Interval::point(c[k]).add(xi.mul(Interval::point(cx[k])))
                    })
                })
                .collect()
        };
        let row = |cy: DVec3| -> Vec<IBox> {
            (y0..y0 + h)
                .map(|j| {
                    let yj = Interval::point(f64::from(j) + offset);
                    std::array::from_fn(|k| yj.mul(Interval::point(cy[k])))
                })
                .collect()
        };
        let (dc, dr) = (column(cam.d0, cam.dx), row(cam.dy));
        let same = |v: &[IBox]| v.windows(2).all(|p| bits(&p[0]) == bits(&p[1]));
        let parallel = (w > 0 && h > 0 && same(&dc) && same(&dr)).then(|| {
            let d = box_sum(&dc[0], &dr[0]);
            (d, [d[0].mid(), d[1].mid(), d[2].mid()])
        });
        RayGrid {
            w,
            origin_columns: column(cam.o0, cam.ox),
            origin_rows: row(cam.oy),
            direction_columns: dc,
            direction_rows: dr,
            parallel,
        }
    }

    /// The ray of the pixel in column `i`, row `j` of the block.
    #[inline]
    pub fn ray(&self, i: u32, j: u32) -> PixelRay {
        let (i, j) = (i as usize, j as usize);
        let o = box_sum(&self.origin_columns[i], &self.origin_rows[j]);
        let om = [o[0].mid(), o[1].mid(), o[2].mid()];
        let (d, dm) = self.parallel.unwrap_or_else(|| {
            let d = box_sum(&self.direction_columns[i], &self.direction_rows[j]);
            (d, [d[0].mid(), d[1].mid(), d[2].mid()])
        });
        PixelRay { o, d, om, dm }
    }

    /// The ray of the block's `k`-th pixel, row-major.
    #[inline]
    pub fn ray_at_index(&self, k: usize) -> PixelRay {
        let w = self.w as usize;
        self.ray((k % w) as u32, (k / w) as u32)
    }

    /// Every pixel's ray, row-major.
    pub fn rays(&self) -> Vec<PixelRay> {
        let (w, h) = (self.w, self.origin_rows.len() as u32);
        let mut rays = Vec::with_capacity((w * h) as usize);
        for j in 0..h {
            for i in 0..w {
                rays.push(self.ray(i, j));
            }
        }
        rays
    }

    /// The corner rays of the pixels in columns `i0..i1` and rows `j0..j1`
    /// of the block (its rays through the first and last pixel centres):
    /// the same bits as [`RayCamera::corners`] over those centres, from two
    /// sums per corner instead of four interval products.
    pub fn corners(&self, (i0, j0): (u32, u32), (i1, j1): (u32, u32)) -> CornerRays {
        let c = |i: u32, j: u32| {
            let r = self.ray(i, j);
            (r.o, r.d)
        };
        CornerRays::new([c(i0, j0), c(i1 - 1, j0), c(i0, j1 - 1), c(i1 - 1, j1 - 1)])
    }

    /// Per column of the block: the origin's column term.
    pub fn origin_columns(&self) -> &[IBox] {
        &self.origin_columns
    }

    /// Per row of the block: the origin's row term.
    pub fn origin_rows(&self) -> &[IBox] {
        &self.origin_rows
    }

    /// The direction shared by every ray, if the camera is parallel.
    pub fn shared_direction(&self) -> Option<IBox> {
        self.parallel.map(|(d, _)| d)
    }
}

// The sum of two boxes, axis by axis.
#[inline]
fn box_sum(a: &IBox, b: &IBox) -> IBox {
    [a[0].add(b[0]), a[1].add(b[1]), a[2].add(b[2])]
}

#[cfg(test)]
#[path = "camera_tests.rs"]
mod tests;
