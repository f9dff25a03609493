//! Layer 2, the evaluation context: the scene's constants and the current
//! evaluators ([`Context`]), every evaluation call counted
//! ([`stats`]), and regions around what the tracer evaluates.

pub mod stats;

use std::sync::Arc;

use glam::DVec3;

use crate::eval::regional::Regional;
use crate::eval::tape::Tape;
use crate::eval::{Evaluator, Grad, IntervalGrad};
use crate::interval::Interval;
use crate::interval::boxes::IBox;
use crate::render::Enclosure;
use crate::render::context::stats::RenderStats;
use crate::render::view::camera::{CornerRays, RayCamera};
use crate::scene::{Bounds, Light, Scene};

/// Functions with fewer live ops than this are not pruned.
pub(crate) const PRUNE_MIN_OPS: usize = 64;
/// Relative padding of a pruning region, so that boxes the tracer rounds
/// outward stay inside it.
const REGION_PAD: f64 = 1e-9;

/// An evaluator per object (some specialised to a region) and the live
/// op count of each one's function.
#[derive(Clone)]
pub(crate) struct EvalSet {
    /// One evaluator per object.
    pub evals: Vec<Arc<dyn Evaluator>>,
    /// Live ops of each evaluator's function.
    pub live_ops: Vec<usize>,
    /// Each evaluator again, typed, where it is a region of a tree pruned
    /// from the object's function (what pruning further starts from).
    pub regions: Vec<Option<Arc<Regional>>>,
}

/// An object's whole-function tape for the affine forms
/// (`enclose::affine::whole_tapes` builds them).
#[derive(Clone, Debug)]
pub(crate) struct FormTape {
    /// The tape.
    pub tape: Arc<Tape>,
    /// Whether `auto` tries the form along a ray on the object: a
    /// polynomial whose affine forms beat its intervals by far
    /// (`enclose::affine::along_may_pay`).
    pub along_pays: bool,
}

/// The read-only evaluation context of one render (or of a region of it,
/// with pruned evaluators): the scene's constants, the current evaluator
/// set, and the counted evaluation calls.
pub(crate) struct Context<'a> {
    /// The camera at the traced resolution.
    pub cam: RayCamera,
    /// One evaluator per object.
    pub evals: &'a [Arc<dyn Evaluator>],
    /// Those evaluators that are regions of pruned trees, typed (empty:
    /// none is).
    pub regions: &'a [Option<Arc<Regional>>],
    /// Each object's linear colour.
    pub colors: Arc<[[f64; 3]]>,
    /// Which enclosure tightens a block's interval (see
    /// `enclose::mean_value::sign_bound`).
    pub enclosure: Enclosure,
    /// Each object's whole-function tape for the affine forms (empty:
    /// intervals only; see `enclose::affine`).
    pub affine_tapes: Arc<[Option<FormTape>]>,
    /// The scene's lights.
    pub lights: &'a [Light],
    /// The scene's bounds, outside which there is no surface.
    pub bounds: Bounds,
    /// Length of the bounds' diagonal.
    pub diag: f64,
    /// Live ops of each evaluator's function (0 when it has none).
    pub live_ops: Vec<usize>,
    /// Every object is proven constant along every ray inside the bounds
    /// (2D models viewed along the missing axis): a block's T range then
    /// needs no bisection.
    pub flat: bool,
    /// Some object's whole function has [`PRUNE_MIN_OPS`] live ops or
    /// more (whatever the evaluators and the pruning option): single rays
    /// in a beam then start at the beam's proven-empty prefix (see
    /// `beam::block`).
    pub large: bool,
    /// This tracer draws IAA's sub-samples (`frame::Fine`): its single
    /// rays in a beam start at the beam's proven-empty prefix, whatever
    /// the scene's size, and sweep the prefix's first candidate piece
    /// first (see `beam::block`).
    pub sub_samples: bool,
}

impl<'a> Context<'a> {
    /// The tracer of `scene` seen through `cam`, with one evaluator per
    /// object.
    pub(crate) fn new(
        scene: &'a Scene,
        evals: &'a [Arc<dyn Evaluator>],
        cam: RayCamera,
    ) -> Context<'a> {
        let b = scene.bounds;
        let live_ops: Vec<usize> = evals
            .iter()
            .map(|e| e.function().map_or(0, |f| f.live_count()))
            .collect();
        let large = live_ops.iter().any(|&n| n >= PRUNE_MIN_OPS);
        Context {
            cam,
            evals,
            regions: &[],
            enclosure: Enclosure::Interval,
            affine_tapes: Arc::new([]),
            colors: scene.objects.iter().map(|o| o.color).collect(),
            lights: &scene.lights,
            bounds: b,
            diag: (DVec3::from_array(b.max) - DVec3::from_array(b.min)).length(),
            live_ops,
            flat: constant_along_rays(&cam, scene),
            large,
            sub_samples: false,
        }
    }

    /// The same context through another camera (the same scene at another
    /// resolution): everything else, flatness included, is kept.
    pub(crate) fn with_camera(&self, cam: RayCamera) -> Context<'a> {
        Context {
            cam,
            colors: Arc::clone(&self.colors),
            live_ops: self.live_ops.clone(),
            affine_tapes: Arc::clone(&self.affine_tapes),
            ..*self
        }
    }

    /// The same context with other evaluators (pruned ones) and their live
    /// op counts.
    pub(crate) fn with_evals<'b>(&self, set: &'b EvalSet) -> Context<'b>
    where
        'a: 'b,
    {
        Context {
            evals: &set.evals,
            regions: &set.regions,
            colors: Arc::clone(&self.colors),
            live_ops: set.live_ops.clone(),
            affine_tapes: Arc::clone(&self.affine_tapes),
            ..*self
        }
    }

    /// Object `k`'s evaluator as a region of a pruned tree, if it is one.
    pub(crate) fn region_of(&self, k: usize) -> Option<&Arc<Regional>> {
        self.regions.get(k)?.as_ref()
    }

    /// Object `k` over `b`.
    pub(crate) fn interval(&self, k: usize, b: IBox, st: &mut RenderStats) -> Interval {
        st.interval_evals += 1;
        self.evals[k].interval(b)
    }

    /// What evaluates object `k` over `b` and at the points of `b` with
    /// one function (see [`Specialise::answering`]), for formulas that
    /// combine values from several evaluations.
    pub(crate) fn answering(&self, k: usize, b: &IBox) -> &dyn Evaluator {
        let e = self.evals[k].as_ref();
        e.answering(b).unwrap_or(e)
    }

    /// Object `k` and its gradient over `b`.
    pub(crate) fn interval_grad(&self, k: usize, b: IBox, st: &mut RenderStats) -> IntervalGrad {
        st.interval_evals += 1;
        self.evals[k].interval_grad(b)
    }

    /// F and its derivative along `v` over `b` (see
    /// [`Single::interval_dir`]).
    pub(crate) fn interval_dir(
        &self,
        k: usize,
        b: IBox,
        v: IBox,
        st: &mut RenderStats,
    ) -> [Interval; 2] {
        st.interval_evals += 1;
        self.evals[k].interval_dir(b, v)
    }

    /// Object `k` at `p`.
    pub(crate) fn point(&self, k: usize, p: [f64; 3], st: &mut RenderStats) -> f64 {
        st.point_evals += 1;
        self.evals[k].point(p)
    }

    /// Object `k` and its gradient at `p`.
    pub(crate) fn point_grad(&self, k: usize, p: [f64; 3], st: &mut RenderStats) -> Grad {
        st.point_evals += 1;
        self.evals[k].point_grad(p)
    }

    /// [`Context::point_grad`] of object `k` at each of `points`, in one
    /// batch (on the tape of the region holding them all: the same signs
    /// as one by one, and on the surface the same normals to rounding),
    /// into `out` (as long as `points`); `cols`
    /// holds the coordinate columns.
    pub(crate) fn point_grads(
        &self,
        k: usize,
        points: &[[f64; 3]],
        cols: &mut [Vec<f64>; 3],
        out: &mut [Grad],
        st: &mut RenderStats,
    ) {
        st.point_evals += points.len() as u64;
        for (c, col) in cols.iter_mut().enumerate() {
            col.clear();
            col.extend(points.iter().map(|p| p[c]));
        }
        self.evals[k].point_grad_batch(&cols[0], &cols[1], &cols[2], out);
    }

    /// The region the evaluations for the rays through the pixel centres
    /// `xs × ys` over `t` happen in: their beam's hull (not clipped to the
    /// bounds, which the tracer's own boxes overhang by rounding), widened
    /// by a relative [`REGION_PAD`]. An evaluation that still falls outside
    /// uses the whole function (see `crate::eval::regional`).
    pub(crate) fn beam_region(&self, xs: (f64, f64), ys: (f64, f64), t: Interval) -> Option<IBox> {
        padded(self.cam.corners(xs, ys).hull(t))
    }

    /// A region for pruning around `b`, a box the tracer computed (see
    /// [`Context::beam_region`]).
    pub(crate) fn region_around(&self, b: IBox) -> Option<IBox> {
        padded(b)
    }

    /// [`Context::beam_region`] of a beam whose corner rays are known.
    pub(crate) fn corner_region(&self, corners: &CornerRays, t: Interval) -> Option<IBox> {
        padded(corners.hull(t))
    }

    // The evaluators with each one `replace` gives (and its op count) in
    // place of the object's own; `None` when it replaces none.
    pub(crate) fn replace_evals(
        &self,
        mut replace: impl FnMut(usize, &Arc<dyn Evaluator>) -> Option<(Arc<Regional>, usize)>,
    ) -> Option<EvalSet> {
        let mut any = false;
        let mut live = self.live_ops.clone();
        let mut evals = Vec::with_capacity(self.evals.len());
        let mut regions = Vec::with_capacity(self.evals.len());
        for (k, e) in self.evals.iter().enumerate() {
            match replace(k, e) {
                Some((p, n)) => {
                    any = true;
                    live[k] = n;
                    evals.push(Arc::clone(&p) as Arc<dyn Evaluator>);
                    regions.push(Some(p));
                }
                None => {
                    evals.push(Arc::clone(e));
                    regions.push(self.region_of(k).cloned());
                }
            }
        }
        any.then_some(EvalSet {
            evals,
            live_ops: live,
            regions,
        })
    }
}

/// `region` widened by a relative [`REGION_PAD`], so that boxes the
/// tracer rounds outward from the same rays stay inside it; `None` unless
/// it is finite.
fn padded(region: IBox) -> Option<IBox> {
    if region
        .iter()
        .any(|c| c.is_empty() || !c.lo.is_finite() || !c.hi.is_finite())
    {
        return None;
    }
    Some(region.map(|c| {
        let pad = REGION_PAD * (c.width() + c.lo.abs().max(c.hi.abs())) + f64::MIN_POSITIVE;
        Interval::new(c.lo - pad, c.hi + pad)
    }))
}

/// Whether `scene` is a 2D model seen along its missing axis (every
/// object constant along every ray of its camera).
pub fn is_flat(scene: &Scene) -> bool {
    RayCamera::new(&scene.camera, 1, 1).is_ok_and(|cam| constant_along_rays(&cam, scene))
}

// Whether every object is constant along every ray: the camera is
// orthographic (one direction d for all rays) and d has an exact zero
// component on every coordinate an object's function reads (2D models seen
// along the missing axis). Reads the scene functions' variable use, which
// simplification can only shrink, so it holds for the evaluators too.
fn constant_along_rays(cam: &RayCamera, scene: &Scene) -> bool {
    let one_direction = cam.dx == DVec3::ZERO && cam.dy == DVec3::ZERO;
    one_direction
        && scene.objects.iter().all(|o| {
            let uses = o.function.uses_vars();
            (0..3).all(|i| !uses[i] || cam.d0[i] == 0.0)
        })
}

#[cfg(test)]
impl<'a> Context<'a> {
    /// A context over `evals` (white, none pruned) and `lights`, through
    /// the default camera at `size`², in the default bounds.
    pub(crate) fn of_objects_for_tests(
        evals: &'a [Arc<dyn Evaluator>],
        lights: &'a [Light],
        size: u32,
    ) -> Context<'a> {
        Context {
            cam: RayCamera::new(&crate::scene::Camera::default(), size, size).unwrap(),
            evals,
            regions: &[],
            enclosure: Enclosure::Interval,
            affine_tapes: Arc::new([]),
            colors: vec![[1.0; 3]; evals.len()].into(),
            lights,
            bounds: Bounds::default(),
            diag: 7.0,
            live_ops: vec![0; evals.len()],
            flat: false,
            large: false,
            sub_samples: false,
        }
    }
}

#[cfg(test)]
impl Context<'static> {
    /// A context with no objects or lights through `camera` at
    /// `size`², over bounds that are not a cube and not centred.
    pub(crate) fn for_tests(camera: &crate::scene::Camera, size: u32) -> Context<'static> {
        Context {
            cam: RayCamera::new(camera, size, size).unwrap(),
            evals: &[],
            regions: &[],
            enclosure: Enclosure::Interval,
            affine_tapes: Arc::new([]),
            colors: Arc::new([]),
            lights: &[],
            bounds: Bounds {
                min: [-1.0, -0.5, -2.0],
                max: [1.5, 1.0, 0.25],
            },
            diag: 4.0,
            live_ops: vec![],
            flat: false,
            large: false,
            sub_samples: false,
        }
    }
}
