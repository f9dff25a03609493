//! Root refinement inside a bracket [a, b] where f(a) > 0 >= f(b): Illinois
//! false position ([`illinois`]), for one ray ([`refine`]) or for the
//! pixels of an included block together ([`refine_batch`]), whose searches
//! run in lockstep and evaluate each step's points in one batch per object
//! over the block's tape. On the same tape both give the same bits (each
//! search sees the same values in the same order); the renderer's tapes
//! are pruned keeping signs (`eval::tape::Keep::Signs`), so a block's tape
//! and a pixel's own agree on signs, not values, and their roots agree
//! within the root tolerance (`signs_tests`).

use super::ray::scene_point;
use crate::eval::Grad;
use crate::render::Hit;
use crate::render::context::stats::RenderStats;
use crate::render::prune::scope::Scope;
use crate::render::view::camera::PixelRay;

// The shortest step, as a fraction of the tolerance, with which
// `Illinois::next` closes a bracket behind a secant step: the bracket it
// leaves is that narrow, so the root's error is half of it.
const SQUEEZE_FLOOR: f64 = 64.0;

// A cap on refinement steps that keeps a pathological function from
// stalling a render (the bracket's midpoint is then the hit).
const MAX_REFINE_STEPS: usize = 200;

/// Finds a root of `f` in [a, b] with `f(a) > 0 >= f(b)` to within `tol`
/// (Illinois false position, with a bisection step every fourth iteration
/// so the bracket always shrinks).
pub(crate) fn illinois(
    f: impl FnMut(f64) -> f64,
    a: f64,
    b: f64,
    fa: f64,
    fb: f64,
    tol: f64,
) -> f64 {
    illinois_bracketed(f, a, b, fa, fb, tol).0
}

/// [`illinois`], with the front end of the last bracket: a point within
/// `tol` of the root where f was evaluated positive.
pub(crate) fn illinois_bracketed(
    mut f: impl FnMut(f64) -> f64,
    a: f64,
    b: f64,
    fa: f64,
    fb: f64,
    tol: f64,
) -> (f64, f64) {
    let mut s = Illinois::new(a, b, fa, fb);
    for it in 0..MAX_REFINE_STEPS {
        if s.narrow(tol) {
            break;
        }
        let c = s.next(it, tol);
        s.update(c, f(c));
    }
    (s.root(), s.front())
}

/// The state of one [`illinois`] search, stepped from outside so that many
/// searches can evaluate their next points in one batch.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Illinois {
    a: f64,
    b: f64,
    fa: f64,
    fb: f64,
    side: i8,
    // The last step was a secant step (see `Illinois::next`).
    after_secant: bool,
}

impl Illinois {
    /// A search over [a, b] with `f(a) = fa > 0 >= fb = f(b)`.
    pub(crate) fn new(a: f64, b: f64, fa: f64, fb: f64) -> Illinois {
        Illinois {
            a,
            b,
            fa,
            fb,
            side: 0,
            after_secant: false,
        }
    }

    /// Whether the bracket is within `tol`.
    pub(crate) fn narrow(&self, tol: f64) -> bool {
        self.b - self.a <= tol
    }

    /// The point iteration `it` evaluates next, for a search that stops
    /// once the bracket is `tol` wide.
    ///
    /// Regula falsi moves one end at a time: once a secant step has put
    /// one end next to the root, the far end still takes several steps to
    /// come in. So where the secant, right after a secant step, puts the
    /// root within `tol / 4` of the end that step moved, the point twice
    /// as far past that end (at least `tol / 64`) is taken instead: it
    /// closes the bracket if the root lies there, and moves that end on
    /// if not. The bracket it leaves is as narrow as the secant's
    /// correction was small, so the roots stay as accurate as the plain
    /// iteration's (a fixed step of `tol / 2` left them up to `tol / 4`
    /// off, which raised IAA's error against the 16×16 reference by 1%).
    /// On planar faces (colonnade at 1024²) this cut the point
    /// evaluations of root refinement by 40%.
    pub(crate) fn next(&mut self, it: usize, tol: f64) -> f64 {
        let (a, b, fa, fb) = (self.a, self.b, self.fa, self.fb);
        let secant = !(it % 4 == 3 || !(fa - fb).is_finite() || fa == fb);
        let c = if secant {
            b - fb * (b - a) / (fb - fa)
        } else {
            0.5 * (a + b)
        };
        if std::mem::take(&mut self.after_secant) && secant {
            // How far the secant puts the root from the end the last step
            // moved, and a step twice that (not below a 64th of the
            // tolerance) past that end.
            let moved = if self.side == 1 { c - a } else { b - c };
            let step = (2.0 * moved).max(tol / SQUEEZE_FLOOR);
            let probe = if self.side == 1 { a + step } else { b - step };
            if step <= 0.5 * tol && probe > a && probe < b {
                return probe;
            }
        }
        if !(c > a && c < b) {
            return 0.5 * (a + b);
        }
        self.after_secant = secant;
        c
    }

    /// Takes f(c) = `fc` into the bracket.
    pub(crate) fn update(&mut self, c: f64, fc: f64) {
        if fc.is_nan() {
            // Undefined inside the bracket: shrink towards the front end.
            self.b = c;
            return;
        }
        if fc > 0.0 {
            self.a = c;
            self.fa = fc;
            if self.side == 1 {
                self.fb *= 0.5;
            }
            self.side = 1;
        } else {
            self.b = c;
            self.fb = fc;
            if self.side == -1 {
                self.fa *= 0.5;
            }
            self.side = -1;
        }
    }

    /// The root estimate: the bracket's midpoint.
    pub(crate) fn root(&self) -> f64 {
        0.5 * (self.a + self.b)
    }

    /// The bracket's front end, where f was evaluated positive.
    pub(crate) fn front(&self) -> f64 {
        self.a
    }
}

/// The scene function's point values at `a` and `b` on the ray, when they
/// show a sign change (positive at a, not positive at b): a root is then
/// in [a, b].
pub(crate) fn sign_change(
    tr: &Scope<'_>,
    ray: &PixelRay,
    live: &[u32],
    (a, b): (f64, f64),
    st: &mut RenderStats,
) -> Option<(f64, f64)> {
    let fa = scene_point(tr, live, ray.at(a), st).0;
    let fb = scene_point(tr, live, ray.at(b), st).0;
    (fa > 0.0 && fb <= 0.0).then_some((fa, fb))
}

/// Refines the first root of the scene function on the pixel's ray in the
/// bracket [a, b] (f(a) > 0 ≥ f(b) expected), returning the hit.
pub(crate) fn refine(
    tr: &Scope<'_>,
    ray: &PixelRay,
    live: &[u32],
    a: f64,
    b: f64,
    st: &mut RenderStats,
) -> Option<Hit> {
    let (fa, fb) = sign_change(tr, ray, live, (a, b), st)?;
    let tol = tr.ctx.cam.root_tolerance(a);
    let mut evals = 0u64;
    let (t, front) = illinois_bracketed(
        |t| {
            evals += live.len() as u64;
            let p = ray.at(t);
            live.iter()
                .map(|&k| tr.ctx.evals[k as usize].point(p))
                .fold(f64::INFINITY, f64::min)
        },
        a,
        b,
        fa,
        fb,
        tol,
    );
    st.point_evals += evals;
    let p = ray.at(t);
    let obj = root_object(tr, live, p, st);
    Some(Hit {
        t,
        obj,
        inside: false,
        grad: Some(tr.ctx.point_grad(obj, p, st).d),
        front: Some(front),
    })
}

/// The object a root at `p` is on: the live object smallest there, as
/// `scene_point` picks it; with one live object, that one, unevaluated.
fn root_object(tr: &Scope<'_>, live: &[u32], p: [f64; 3], st: &mut RenderStats) -> usize {
    match live {
        [only] => *only as usize,
        _ => scene_point(tr, live, p, st).1,
    }
}

/// One pixel's bracket for [`refine_batch`]: its ray and [a, b].
#[derive(Copy, Clone, Debug)]
pub(crate) struct Bracket {
    /// The pixel's ray.
    pub ray: PixelRay,
    /// Front end of the bracket.
    pub a: f64,
    /// Back end of the bracket.
    pub b: f64,
}

/// A bracket proven to hold the first root of every ray of a beam (IAA's
/// pixel-area tests, for the base sample and sub-samples of a pixel):
/// every object is positive along the rays before `a`;
/// over the beam's hull on `[a, b]`, inside the bounds, object `obj`
/// alone may vanish, and its cross-section is positive at `a` and
/// negative at `b`. So each ray's first hit is a root of `obj` in
/// `[a, b]`. Where the beam was included, `obj` decreases strictly along
/// every ray there (`unique`): each ray's first hit is its one root in
/// `[a, b]`. A covered pixel's bracket is not `unique`: a ray is refined
/// in it where `obj` is proven decreasing along that ray's own segment
/// (one directional-derivative interval over a box a ray wide, where the
/// pixel's hull was too wide to prove it), and traced as usual elsewhere.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct RootBracket {
    /// Front end: f > 0 on every ray.
    pub a: f64,
    /// Back end: f < 0 on every ray.
    pub b: f64,
    /// The object hit.
    pub obj: usize,
    /// Whether `obj` is proven strictly decreasing along every ray on
    /// `[a, b]`.
    pub unique: bool,
}

/// The buffers [`refine_batch`] reuses from one block to the next (a
/// tile keeps one in its `TileState`): the block's brackets, the batch's
/// columns, the searches and the points of each step. An included block
/// used to allocate about twenty vectors; colonnade refines 24,000 of
/// them at 1024².
#[derive(Clone, Debug, Default)]
pub(crate) struct RefineScratch {
    /// The brackets of the block being refined (filled by the caller).
    pub brackets: Vec<Bracket>,
    batch: SceneBatch,
    fa: Vec<f64>,
    // (index, search, tolerance) of the brackets with a sign change.
    searches: Vec<(usize, Illinois, f64)>,
    running: Vec<usize>,
    points: Vec<[f64; 3]>,
    cs: Vec<f64>,
    objects: Vec<usize>,
    grads: Vec<Grad>,
    // One object's roots among several: their indices, points and normals.
    at: Vec<usize>,
    at_points: Vec<[f64; 3]>,
    at_grads: Vec<Grad>,
}

/// [`refine`] for many brackets (`scratch.brackets`): each result is the
/// same as its own call would give (the same steps on the same values),
/// but every step's points are evaluated in one batch per object.
// long-fn: the lockstep of every bracket's Illinois search (start, step,
// finish, shade) shares one set of buffers; split, each part would take
// the scratch apart again.
pub(crate) fn refine_batch(
    tr: &Scope<'_>,
    scratch: &mut RefineScratch,
    live: &[u32],
    st: &mut RenderStats,
) -> Vec<Option<Hit>> {
    let RefineScratch {
        brackets,
        batch,
        fa,
        searches,
        running,
        points,
        cs,
        objects,
        grads,
        at,
        at_points,
        at_grads,
    } = scratch;
    let n = brackets.len();
    let mut out = vec![None; n];
    if n == 0 {
        return out;
    }
    points.clear();
    points.extend(brackets.iter().map(|k| k.ray.at(k.a)));
    fa.clear();
    fa.extend(
        batch
            .min_and_object(tr, live, points, st)
            .iter()
            .map(|v| v.0),
    );
    points.clear();
    points.extend(brackets.iter().map(|k| k.ray.at(k.b)));
    let fb = batch.min_and_object(tr, live, points, st);
    searches.clear();
    searches.extend((0..n).filter(|&i| fa[i] > 0.0 && fb[i].0 <= 0.0).map(|i| {
        let k = &brackets[i];
        let s = Illinois::new(k.a, k.b, fa[i], fb[i].0);
        (i, s, tr.ctx.cam.root_tolerance(k.a))
    }));
    running.clear();
    running.extend(0..searches.len());
    for it in 0..MAX_REFINE_STEPS {
        running.retain(|&j| !searches[j].1.narrow(searches[j].2));
        if running.is_empty() {
            break;
        }
        points.clear();
        cs.clear();
        for &j in running.iter() {
            let (i, s, tol) = &mut searches[j];
            let c = s.next(it, *tol);
            cs.push(c);
            points.push(brackets[*i].ray.at(c));
        }
        let fc = batch.min(tr, live, points, st);
        for ((&j, &c), &v) in running.iter().zip(cs.iter()).zip(fc) {
            searches[j].1.update(c, v);
        }
    }
    // The roots (`points` from here on).
    points.clear();
    points.extend(
        searches
            .iter()
            .map(|(i, s, _)| brackets[*i].ray.at(s.root())),
    );
    // Which object each root is on: with one live object, that one (what
    // `min_and_object` picks), without evaluating it again.
    objects.clear();
    match live {
        [only] => objects.resize(points.len(), *only as usize),
        _ => objects.extend(
            batch
                .min_and_object(tr, live, points, st)
                .iter()
                .map(|v| v.1),
        ),
    }
    // The normals at the roots, one gradient batch per object.
    grads.clear();
    grads.resize(points.len(), Grad::default());
    if let [only] = live {
        tr.ctx
            .point_grads(*only as usize, points, &mut batch.cols, grads, st);
    } else {
        let mut on: Vec<usize> = objects.clone();
        on.sort_unstable();
        on.dedup();
        for obj in on {
            at.clear();
            at.extend((0..points.len()).filter(|&j| objects[j] == obj));
            at_points.clear();
            at_points.extend(at.iter().map(|&j| points[j]));
            at_grads.clear();
            at_grads.resize(at.len(), Grad::default());
            tr.ctx
                .point_grads(obj, at_points, &mut batch.cols, at_grads, st);
            for (&j, g) in at.iter().zip(at_grads.iter()) {
                grads[j] = *g;
            }
        }
    }
    for (((i, s, _), &obj), grad) in searches.iter().zip(objects.iter()).zip(grads.iter()) {
        out[*i] = Some(Hit {
            t: s.root(),
            obj,
            inside: false,
            grad: Some(grad.d),
            front: Some(s.front()),
        });
    }
    out
}

/// `ray::scene_point` at each of `points`, one batch per live object: the
/// same signs (the batch runs the tape of the region holding them all,
/// which a point alone may not), so the same points inside a solid; off
/// the surface the values, and the object found smallest, may differ.
pub(crate) fn scene_points(
    tr: &Scope<'_>,
    live: &[u32],
    points: &[[f64; 3]],
    st: &mut RenderStats,
) -> Vec<(f64, usize)> {
    if points.is_empty() {
        return Vec::new();
    }
    SceneBatch::new(points.len())
        .min_and_object(tr, live, points, st)
        .to_vec()
}

// Scratch for evaluating the scene at a batch of points: coordinate
// columns and one object's values.
#[derive(Clone, Debug, Default)]
struct SceneBatch {
    cols: [Vec<f64>; 3],
    values: Vec<f64>,
    best: Vec<(f64, usize)>,
    min: Vec<f64>,
}

impl SceneBatch {
    fn new(n: usize) -> SceneBatch {
        SceneBatch {
            cols: std::array::from_fn(|_| Vec::with_capacity(n)),
            values: Vec::with_capacity(n),
            best: Vec::with_capacity(n),
            min: Vec::with_capacity(n),
        }
    }

    // Loads the points and runs `each(values of object k, k)` per live
    // object, in `live` order.
    fn run(
        &mut self,
        tr: &Scope<'_>,
        live: &[u32],
        points: &[[f64; 3]],
        st: &mut RenderStats,
        mut each: impl FnMut(&[f64], usize),
    ) {
        for (c, col) in self.cols.iter_mut().enumerate() {
            col.clear();
            col.extend(points.iter().map(|p| p[c]));
        }
        self.values.clear();
        self.values.resize(points.len(), 0.0);
        for &k in live {
            let [xs, ys, zs] = &self.cols;
            tr.ctx.evals[k as usize].point_batch(xs, ys, zs, &mut self.values);
            each(&self.values, k as usize);
        }
        st.point_evals += (points.len() * live.len()) as u64;
    }

    // Per point, the smallest object value and its object, as
    // `scene_point` picks them.
    fn min_and_object(
        &mut self,
        tr: &Scope<'_>,
        live: &[u32],
        points: &[[f64; 3]],
        st: &mut RenderStats,
    ) -> &[(f64, usize)] {
        let first = live.first().copied().unwrap_or(0) as usize;
        let mut best = std::mem::take(&mut self.best);
        best.clear();
        best.resize(points.len(), (f64::INFINITY, first));
        self.run(tr, live, points, st, |v, k| {
            for (b, &vi) in best.iter_mut().zip(v) {
                if vi < b.0 {
                    *b = (vi, k);
                }
            }
        });
        self.best = best;
        &self.best
    }

    // Per point, the fold of the object values with `f64::min`, as
    // `refine`'s steps take it.
    fn min(
        &mut self,
        tr: &Scope<'_>,
        live: &[u32],
        points: &[[f64; 3]],
        st: &mut RenderStats,
    ) -> &[f64] {
        let mut min = std::mem::take(&mut self.min);
        min.clear();
        min.resize(points.len(), f64::INFINITY);
        self.run(tr, live, points, st, |v, _| {
            for (m, &vi) in min.iter_mut().zip(v) {
                *m = m.min(vi);
            }
        });
        self.min = min;
        &self.min
    }
}

#[cfg(test)]
#[path = "refine_tests.rs"]
mod tests;
