//! Framing the solid itself: a box guaranteed to contain every point of
//! the bounds where the scene function is ≤ 0 ([`solid_box`]), found by
//! interval subdivision, and a camera that looks at it ([`frame_box`]).
//!
//! The box is sound because a region is dropped only when interval
//! arithmetic proves f > 0 (or f undefined) everywhere in it, or when it
//! lies inside the hull of points already known to be solid, which the
//! answer contains anyway. It is tight to about one cell of the finest
//! level: the regions kept at that level are cells of side
//! `bounds / 2^depth`, and each holds a point where interval arithmetic
//! could not exclude f ≤ 0.

use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use super::camera::normalize;
use crate::eval::Evaluator;
use crate::eval::tape::{PrunedTape, Tape, with_workspace};
use crate::interval::Interval;
use crate::scene::{Bounds, Camera, Projection, Scene};

/// Levels of subdivision [`solid_box`] goes down by default: cells of
/// 1/256 of the bounds, a fit within about 1% of the image.
pub const FIT_DEPTH: u32 = 8;

/// Most regions [`solid_box`] evaluates at one level; beyond it the
/// regions left are kept whole (still sound, less tight), which bounds
/// the cost on surfaces interval arithmetic cannot tell from solid.
pub const MAX_REGIONS: usize = 1 << 16;

/// Share of the image the framed box fills along its tighter side.
pub const FILL: f64 = 0.8;

/// An axis-aligned box that contains every point of `scene.bounds` where
/// the scene function (the minimum over the objects, `evaluators[i]`
/// evaluating object i) is ≤ 0, subdividing `depth` levels; `None` when
/// interval arithmetic proves there is no such point. Axes that no object
/// uses are not subdivided: the solid spans the bounds along them.
pub fn solid_box(scene: &Scene, evaluators: &[Arc<dyn Evaluator>], depth: u32) -> Option<Bounds> {
    solid_box_within(scene, evaluators, depth, MAX_REGIONS, Pruning::On)
}

// Whether split cells prune their tapes (`Off` for tests: the same box).
#[derive(Copy, Clone, PartialEq)]
enum Pruning {
    On,
    #[cfg_attr(not(test), allow(dead_code))]
    Off,
}

// [`solid_box`] evaluating at most `max_regions` cells a level.
fn solid_box_within(
    scene: &Scene,
    evaluators: &[Arc<dyn Evaluator>],
    depth: u32,
    max_regions: usize,
    pruning: Pruning,
) -> Option<Bounds> {
    let b = scene.bounds;
    let mut split = [false; 3];
    for o in &scene.objects {
        for (s, u) in split.iter_mut().zip(o.function.uses_vars()) {
            *s |= u;
        }
    }
    // The function's tape answers without compiling: a large function's
    // native interval code would cost more to compile than the few
    // thousand cells cost to interpret (the render itself runs pruned
    // tapes, not that code), and a tape runs a family's cells in one
    // batch. Each split cell prunes its tapes to itself for its children
    // (values kept bit for bit, so the box is the whole tapes'): cells near
    // prospero's letters keep a few hundred of its 7,800 ops, where the
    // whole tape's fit took half of a 16×16 render's process.
    let tapes: Vec<Option<Arc<Tape>>> = evaluators
        .iter()
        .map(|e| e.function().map(|f| Arc::new(Tape::new(f))))
        .collect();
    let mut level = vec![Family {
        tapes,
        cells: vec![std::array::from_fn(|i| Interval::new(b.min[i], b.max[i]))],
    }];
    // `known` holds points shown to be solid (cell centres where f ≤ 0 and
    // whole cells where f ≤ 0 throughout); `kept` the cells kept at the end.
    let mut known = Hull::default();
    let mut kept = Hull::default();
    for d in 0..=depth {
        // Per family, its undecided cells and the solid it shows: families
        // are independent (a hull is the same whatever order it grows
        // in), so they run in parallel and the box is the same bits.
        let (undecided, shown): (Vec<Vec<[Interval; 3]>>, Vec<Hull>) = level
            .par_iter()
            .map(|fam| {
                let mut shown = Hull::default();
                (fam.undecided(evaluators, split, &mut shown), shown)
            })
            .unzip();
        shown.iter().for_each(|h| known = known.union(h));
        let count: usize = undecided.iter().map(Vec::len).sum();
        let last = d == depth || count * (1 << split.iter().filter(|&&s| s).count()) > max_regions;
        let undecided = undecided
            .into_iter()
            .map(|mut cells| {
                cells.retain(|c| !known.contains_box(c));
                cells
            })
            .collect::<Vec<_>>();
        if last {
            undecided.iter().flatten().for_each(|c| kept.add_box(c));
            break;
        }
        level = level
            .par_iter()
            .zip(undecided)
            .flat_map_iter(|(fam, cells)| fam.split(&cells, split, pruning))
            .collect();
    }
    let all = kept.union(&known);
    all.min.map(|min| Bounds {
        min,
        max: all.max.map_or(min, |m| m),
    })
}

// Cells of one level that share their tapes: the children of one cell,
// with that cell's tapes, one per object (`None`: the object's own
// evaluator, for an object without a function).
struct Family {
    tapes: Vec<Option<Arc<Tape>>>,
    cells: Vec<[Interval; 3]>,
}

impl Family {
    // The cells where interval arithmetic leaves the scene function's sign
    // undecided; adds to `known` the solid the others and the centres show.
    fn undecided(
        &self,
        evaluators: &[Arc<dyn Evaluator>],
        split: [bool; 3],
        known: &mut Hull,
    ) -> Vec<[Interval; 3]> {
        let [lo, hi, centres] = self.evaluate(evaluators);
        let mut left = Vec::new();
        for (k, cell) in self.cells.iter().enumerate() {
            if lo[k] > 0.0 {
                // f > 0 (or undefined) over the whole cell: no solid here.
                continue;
            }
            if hi[k] <= 0.0 {
                known.add_box(cell);
                continue;
            }
            if centres[k] <= 0.0 {
                // Along an axis no object uses, f is the same over the
                // cell's whole extent, so that segment is solid.
                let lo = std::array::from_fn(|i| if split[i] { cell[i].mid() } else { cell[i].lo });
                let hi = std::array::from_fn(|i| if split[i] { cell[i].mid() } else { cell[i].hi });
                known.add(lo, hi);
            }
            left.push(*cell);
        }
        left
    }

    // Per cell: the lower and upper bounds of the scene function (the
    // minimum over the objects) over it, EMPTY intervals (f undefined)
    // counting as +inf, and its value at the cell's centre (NaN as +inf).
    fn evaluate(&self, evaluators: &[Arc<dyn Evaluator>]) -> [Vec<f64>; 3] {
        let n = self.cells.len();
        let [mut lo, mut hi, mut centre] = [(); 3].map(|_| vec![f64::INFINITY; n]);
        let coord = |i: usize| -> Vec<f64> { self.cells.iter().map(|c| c[i].mid()).collect() };
        let (xs, ys, zs) = (coord(0), coord(1), coord(2));
        let mut iv = vec![Interval::EMPTY; n];
        let mut pv = vec![f64::NAN; n];
        for (tape, e) in self.tapes.iter().zip(evaluators) {
            match tape {
                Some(t) => with_workspace(|ws| {
                    t.interval_batch(&self.cells, &mut iv, ws);
                    t.point_batch([&xs, &ys, &zs], &mut pv, ws);
                }),
                None => {
                    e.interval_batch(&self.cells, &mut iv);
                    e.point_batch(&xs, &ys, &zs, &mut pv);
                }
            }
            for k in 0..n {
                if !iv[k].is_empty() {
                    lo[k] = lo[k].min(iv[k].lo);
                    hi[k] = hi[k].min(iv[k].hi);
                }
                if pv[k] <= centre[k] {
                    centre[k] = pv[k];
                }
            }
        }
        [lo, hi, centre]
    }

    // A family per cell of `cells` (of this family): its children, with
    // this family's tapes pruned to it.
    fn split(&self, cells: &[[Interval; 3]], split: [bool; 3], pruning: Pruning) -> Vec<Family> {
        let mut pruned: Vec<Vec<Option<PrunedTape>>> = self
            .tapes
            .iter()
            .map(|t| match t {
                Some(t) if pruning == Pruning::On => {
                    with_workspace(|ws| t.prune_batch(cells, usize::MAX, ws))
                }
                _ => Vec::new(),
            })
            .collect();
        let mut next = Vec::with_capacity(cells.len());
        for (k, cell) in cells.iter().enumerate() {
            let tapes = self
                .tapes
                .iter()
                .zip(&mut pruned)
                .map(|(t, p)| match p.get_mut(k).and_then(Option::take) {
                    Some(p) => Some(Arc::new(p.tape)),
                    None => t.clone(),
                })
                .collect();
            let mut cells = Vec::new();
            subdivide(cell, split, &mut cells);
            next.push(Family { tapes, cells });
        }
        next
    }
}

// Halves `cell` along each axis in `split`, appending the children.
fn subdivide(cell: &[Interval; 3], split: [bool; 3], out: &mut Vec<[Interval; 3]>) {
    let start = out.len();
    out.push(*cell);
    for (i, &s) in split.iter().enumerate() {
        if !s {
            continue;
        }
        for k in start..out.len() {
            let c = out[k][i];
            let m = c.mid();
            out[k][i] = Interval::new(c.lo, m);
            let mut other = out[k];
            other[i] = Interval::new(m, c.hi);
            out.push(other);
        }
    }
}

// The hull of some points and boxes (none yet: `min` is None).
#[derive(Clone, Copy, Debug, Default)]
struct Hull {
    min: Option<[f64; 3]>,
    max: Option<[f64; 3]>,
}

impl Hull {
    fn add_box(&mut self, b: &[Interval; 3]) {
        self.add(b.map(|i| i.lo), b.map(|i| i.hi));
    }

    fn add(&mut self, lo: [f64; 3], hi: [f64; 3]) {
        let min = self.min.unwrap_or(lo);
        let max = self.max.unwrap_or(hi);
        self.min = Some(std::array::from_fn(|i| min[i].min(lo[i])));
        self.max = Some(std::array::from_fn(|i| max[i].max(hi[i])));
    }

    fn contains_box(&self, b: &[Interval; 3]) -> bool {
        match (self.min, self.max) {
            (Some(min), Some(max)) => (0..3).all(|i| min[i] <= b[i].lo && b[i].hi <= max[i]),
            _ => false,
        }
    }

    fn union(&self, o: &Hull) -> Hull {
        let mut h = *self;
        if let (Some(lo), Some(hi)) = (o.min, o.max) {
            h.add(lo, hi);
        }
        h
    }
}

/// `cam` aimed at the centre of `b` along its own view direction, with
/// its up vector and projection kind, and distanced (perspective) or
/// sized (orthographic) so that `b` fills [`FILL`] of a `width × height`
/// image along its tighter side. An orthographic eye is put outside `b`,
/// where rays start. `None` when `cam` has no view direction.
pub fn frame_box(cam: &Camera, b: &Bounds, width: u32, height: u32) -> Option<Camera> {
    let eye = DVec3::from_array(cam.eye);
    let w = normalize(DVec3::from_array(cam.target) - eye)?;
    let u = normalize(w.cross(DVec3::from_array(cam.up)))?;
    let v = u.cross(w);
    let centre = (DVec3::from_array(b.min) + DVec3::from_array(b.max)) * 0.5;
    let mut half = (DVec3::from_array(b.max) - DVec3::from_array(b.min)) * 0.5;
    // A box of no extent (a solid too thin to split) still gets a view.
    let floor = 1e-6 * half.length().max(1e-3);
    half = half.max(DVec3::splat(floor));
    let radius = half.length();
    let aspect = f64::from(width) / f64::from(height.max(1));
    let corners = (0..8).map(|k| {
        let s = DVec3::new(
            if k & 1 == 0 { -1.0 } else { 1.0 },
            if k & 2 == 0 { -1.0 } else { 1.0 },
            if k & 4 == 0 { -1.0 } else { 1.0 },
        );
        let c = half * s;
        (c.dot(u).abs(), c.dot(v).abs(), c.dot(w))
    });
    let (projection, distance) = match cam.projection {
        Projection::Perspective { fov_deg } => {
            let tv = (fov_deg.to_radians() * 0.5).tan() * FILL;
            let th = tv * aspect;
            // Each corner at lateral offsets (x, y) and depth z past the
            // centre must lie within the shrunken view: x / (d + z) ≤ th.
            let d = corners
                .map(|(x, y, z)| (x / th).max(y / tv) - z)
                .fold(radius * 1.0001, f64::max);
            (cam.projection, d)
        }
        Projection::Orthographic { .. } => {
            let (x, y) = corners.fold((0.0f64, 0.0f64), |(a, b), (x, y, _)| (a.max(x), b.max(y)));
            let width = (2.0 * x).max(2.0 * y * aspect) / FILL;
            (Projection::Orthographic { width }, 2.0 * radius)
        }
    };
    Some(Camera {
        eye: (centre - w * distance).to_array(),
        target: centre.to_array(),
        up: cam.up,
        projection,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::interp::Interpreter;
    use crate::ir::{BinaryOp, Builder, Function, Var};
    use crate::scene::{Light, Object, RenderSettings};

    // x² + y² + z² - r² around `c`.
    fn sphere(c: [f64; 3], r: f64) -> Function {
        let mut b = Builder::new();
        let f = sphere_in(&mut b, c, r);
        b.finish(f)
    }

    // `sphere`'s value, built in `b`.
    fn sphere_in(b: &mut Builder, c: [f64; 3], r: f64) -> crate::ir::ValueId {
        let mut sum = None;
        for (i, var) in [Var::X, Var::Y, Var::Z].into_iter().enumerate() {
            let x = b.var(var);
            let k = b.constant(c[i]);
            let d = b.binary(BinaryOp::Sub, x, k);
            let sq = b.binary(BinaryOp::Mul, d, d);
            sum = Some(match sum {
                None => sq,
                Some(s) => b.binary(BinaryOp::Add, s, sq),
            });
        }
        let r2 = b.constant(r * r);
        b.binary(BinaryOp::Sub, sum.unwrap(), r2)
    }

    fn scene(functions: Vec<Function>) -> (Scene, Vec<Arc<dyn Evaluator>>) {
        let evals = functions
            .iter()
            .map(|f| Arc::new(Interpreter::new(f.clone())) as Arc<dyn Evaluator>)
            .collect();
        let objects = functions
            .into_iter()
            .enumerate()
            .map(|(i, function)| Object {
                name: format!("o{i}"),
                function,
                color: [1.0; 3],
            })
            .collect();
        let s = Scene {
            objects,
            camera: Camera::default(),
            lights: vec![Light::default_light()],
            bounds: Bounds::default(),
            render: RenderSettings::default(),
        };
        (s, evals)
    }

    #[test]
    fn sphere_box_is_tight() {
        let (s, e) = scene(vec![sphere([0.5, -0.25, 0.0], 0.6)]);
        let b = solid_box(&s, &e, FIT_DEPTH).unwrap();
        let c = [0.5, -0.25, 0.0];
        for (i, ci) in c.into_iter().enumerate() {
            // Sound: the true extent is inside; tight: within 10% of it.
            assert!(b.min[i] <= ci - 0.6 && b.max[i] >= ci + 0.6, "{b:?}");
            assert!((b.max[i] - b.min[i]) <= 1.2 * 1.1, "{b:?}");
        }
    }

    // Every sampled point where f ≤ 0 lies in the box, for a union of two
    // spheres (one partly outside the bounds).
    #[test]
    fn box_contains_every_sampled_solid_point() {
        let (s, e) = scene(vec![
            sphere([-1.0, 0.3, 0.2], 0.4),
            sphere([1.6, 1.5, -0.5], 0.7),
        ]);
        let b = solid_box(&s, &e, 5).unwrap();
        let mut found = 0;
        let n = 40;
        for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    let p = [i, j, k].map(|t| -2.0 + 4.0 * f64::from(t) / f64::from(n));
                    if e.iter().any(|e| e.point(p) <= 0.0) {
                        found += 1;
                        assert!(
                            (0..3).all(|a| b.min[a] <= p[a] && p[a] <= b.max[a]),
                            "{p:?} {b:?}"
                        );
                    }
                }
            }
        }
        assert!(found > 100);
    }

    // Out of budget, the cells left are kept whole: looser, still sound.
    #[test]
    fn a_small_budget_stays_sound() {
        let (s, e) = scene(vec![sphere([0.3, 0.2, -0.4], 0.5)]);
        let tight = solid_box(&s, &e, FIT_DEPTH).unwrap();
        let loose = solid_box_within(&s, &e, FIT_DEPTH, 64, Pruning::On).unwrap();
        for i in 0..3 {
            assert!(loose.min[i] <= tight.min[i] && tight.max[i] <= loose.max[i]);
        }
        assert!(loose.max[0] - loose.min[0] > tight.max[0] - tight.min[0]);
    }

    // A union of random spheres (one `min` tree) beside a second object.
    fn union_scene() -> (Scene, Vec<Arc<dyn Evaluator>>) {
        let mut rng = crate::ir::random::Rng::new(7);
        let mut b = Builder::new();
        let mut union = None;
        for _ in 0..24 {
            let c: [f64; 3] = std::array::from_fn(|_| rng.range(-1.5, 1.5));
            let r = rng.range(0.05, 0.3);
            let f = sphere_in(&mut b, c, r);
            union = Some(union.map_or(f, |u| b.binary(BinaryOp::Min, u, f)));
        }
        let u = b.finish(union.unwrap());
        scene(vec![u, sphere([1.7, 1.7, -1.7], 0.5)])
    }

    // Each split cell's children evaluate on tapes pruned to it the same
    // bits as on the whole tapes, and the pruning shortens tapes.
    #[test]
    fn pruned_families_evaluate_as_the_whole_tapes() {
        let (s, e) = union_scene();
        let whole: Vec<_> = e
            .iter()
            .map(|e| Some(Arc::new(Tape::new(e.function().unwrap()))))
            .collect();
        let b = s.bounds;
        let mut level = vec![Family {
            tapes: whole.clone(),
            cells: vec![std::array::from_fn(|i| Interval::new(b.min[i], b.max[i]))],
        }];
        let mut shortest = usize::MAX;
        for _ in 0..4 {
            let next: Vec<Family> = level
                .iter()
                .flat_map(|fam| fam.split(&fam.cells, [true; 3], Pruning::On))
                .collect();
            for fam in &next {
                let unpruned = Family {
                    tapes: whole.clone(),
                    cells: fam.cells.clone(),
                };
                let bits =
                    |v: [Vec<f64>; 3]| v.map(|c| c.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
                assert_eq!(
                    bits(fam.evaluate(&e)),
                    bits(unpruned.evaluate(&e)),
                    "{:?}",
                    fam.cells[0]
                );
                shortest = shortest.min(fam.tapes[0].as_ref().unwrap().len());
            }
            level = next;
        }
        assert!(
            shortest < whole[0].as_ref().unwrap().len() / 4,
            "{shortest}"
        );
    }

    // So the box is the unpruned fit's, bit for bit.
    #[test]
    fn pruned_tapes_give_the_same_box() {
        let (s, e) = union_scene();
        for depth in [3, 6] {
            let on = solid_box_within(&s, &e, depth, MAX_REGIONS, Pruning::On).unwrap();
            let off = solid_box_within(&s, &e, depth, MAX_REGIONS, Pruning::Off).unwrap();
            let bits = |b: Bounds| [b.min, b.max].map(|v| v.map(f64::to_bits));
            assert_eq!(bits(on), bits(off), "{on:?} {off:?}");
        }
    }

    #[test]
    fn no_solid_in_the_bounds_gives_none() {
        let (s, e) = scene(vec![sphere([5.0, 5.0, 5.0], 1.0)]);
        assert!(solid_box(&s, &e, FIT_DEPTH).is_none());
    }

    // A function of x and y only spans the bounds along z.
    #[test]
    fn unused_axes_span_the_bounds() {
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let y = b.var(Var::Y);
        let x2 = b.binary(BinaryOp::Mul, x, x);
        let y2 = b.binary(BinaryOp::Mul, y, y);
        let s = b.binary(BinaryOp::Add, x2, y2);
        let one = b.constant(1.0);
        let f = b.binary(BinaryOp::Sub, s, one);
        let (s, e) = scene(vec![b.finish(f)]);
        let bx = solid_box(&s, &e, FIT_DEPTH).unwrap();
        assert_eq!((bx.min[2], bx.max[2]), (-2.0, 2.0));
        assert!(bx.max[0] >= 1.0 && bx.max[0] < 1.1, "{bx:?}");
    }

    #[test]
    fn framing_keeps_the_direction_and_fills_the_view() {
        let b = Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        };
        let cam = Camera {
            eye: [0.0, 0.0, 10.0],
            ..Camera::default()
        };
        let f = frame_box(&cam, &b, 100, 100).unwrap();
        assert_eq!(f.target, [0.0; 3]);
        assert!(f.eye[0] == 0.0 && f.eye[1] == 0.0 && f.eye[2] > 1.0);
        // The front face (z = 1) spans 80% of the 40° view.
        let half = (20f64).to_radians().tan() * FILL;
        assert!((1.0 / (f.eye[2] - 1.0) - half).abs() < 1e-9, "{f:?}");
        let ortho = Camera {
            projection: Projection::Orthographic { width: 1.0 },
            ..cam
        };
        let f = frame_box(&ortho, &b, 200, 100).unwrap();
        // Height 2 must fill 80% of width / 2.
        assert_eq!(
            f.projection,
            Projection::Orthographic {
                width: 2.0 * 2.0 / FILL
            }
        );
        assert!(f.eye[2] > 1.0);
        let none = Camera {
            target: cam.eye,
            ..cam
        };
        assert!(frame_box(&none, &b, 10, 10).is_none());
    }
}
