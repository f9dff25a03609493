//! A tile's pixels classified from the pixel-area tests, the shadow-edge
//! rule over the base samples, and the merge of sub-samples.

use super::area::*;
use super::*;
use crate::render::context::EvalSet;

/// The IAA results of one tile, row-major within the tile.
pub(crate) struct TilePixels<'a> {
    /// Linear colour of the base render, replaced by the AA average.
    pub linear: &'a mut [[f64; 3]],
    /// Ray parameter of the base hit (+inf: none), min over samples after.
    pub depth: &'a mut [f64],
    /// Fraction of the pixel's samples (by area) that hit.
    pub coverage: &'a mut [f64],
    /// Samples per pixel.
    pub samples: &'a mut [u32],
    /// Lights shadowed at each base sample (bit per light).
    pub shadowed: &'a [u64],
}

/// A tile's base samples along its four sides, which the tiles beside it
/// read for the shadow-edge rule: whether each hit, and the lights
/// shadowed there.
#[derive(Clone, Debug, Default)]
pub(crate) struct TileEdges {
    pub(super) top: Vec<(bool, u64)>,
    pub(super) bottom: Vec<(bool, u64)>,
    pub(super) left: Vec<(bool, u64)>,
    pub(super) right: Vec<(bool, u64)>,
}

impl TileEdges {
    /// The sides of a `w`×`h` tile from its base depths (+inf: no hit)
    /// and shadowed lights, row-major.
    pub(crate) fn new(w: u32, h: u32, depth: &[f64], shadowed: &[u64]) -> TileEdges {
        let at = |i: u32, j: u32| {
            let k = (j * w + i) as usize;
            (depth[k].is_finite(), shadowed[k])
        };
        let (w1, h1) = (w.saturating_sub(1), h.saturating_sub(1));
        TileEdges {
            top: (0..w).map(|i| at(i, 0)).collect(),
            bottom: (0..w).map(|i| at(i, h1)).collect(),
            left: (0..h).map(|j| at(0, j)).collect(),
            right: (0..h).map(|j| at(w1, j)).collect(),
        }
    }
}

/// The sides of the tiles around one tile (None at the image's border):
/// tiles of a row share their height and tiles of a column their width,
/// so a neighbour's side lines up with the tile's.
#[derive(Copy, Clone, Default)]
pub(crate) struct NeighbourTiles<'e> {
    /// The tile above (its bottom row is read).
    pub above: Option<&'e TileEdges>,
    /// The tile below (its top row).
    pub below: Option<&'e TileEdges>,
    /// The tile to the left (its right column).
    pub left: Option<&'e TileEdges>,
    /// The tile to the right (its left column).
    pub right: Option<&'e TileEdges>,
}

impl NeighbourTiles<'_> {
    // The base sample at tile coordinates (i, j) just outside a w×h tile.
    pub(super) fn at(&self, (i, j): (i64, i64), (w, h): (i64, i64)) -> Option<(bool, u64)> {
        let side = |e: Option<&TileEdges>, v: fn(&TileEdges) -> &Vec<(bool, u64)>, k: i64| {
            e.and_then(|e| v(e).get(usize::try_from(k).ok()?).copied())
        };
        match (i, j) {
            (-1, j) => side(self.left, |e| &e.right, j),
            (i, -1) => side(self.above, |e| &e.bottom, i),
            (i, j) if i == w => side(self.right, |e| &e.left, j),
            (i, j) if j == h => side(self.below, |e| &e.top, i),
            _ => None,
        }
    }
}

/// What a cell's beam tests decided.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) enum Cell {
    Background,
    Smooth,
    Split,
}

/// A cell's test outcome and the rejected prefix its children inherit.
pub(super) struct Decision {
    pub(super) cell: Cell,
    pub(super) floor: EmptyPrefix,
    /// The beam was included: only the colour interval was too wide.
    pub(super) by_shading: bool,
    /// Every ray of the beam is proven to hit one object inside a thin
    /// piece (see [`Sampling::Covered`]).
    pub(super) covered: bool,
    /// Where the beam was included: the bracket every one of its rays has
    /// its first root in (see [`RootBracket`]).
    pub(super) bracket: Option<RootBracket>,
}

/// How a pixel of an IAA tile is sampled after its area's beam tests.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Sampling {
    /// Background or smooth: the base sample stands.
    Base,
    /// Proven covered but not smooth: every ray of the pixel's area is
    /// outside every object up to `ta` and inside the one object that may
    /// vanish there at a cross-section `tc` at most `COVER_REACH` piece
    /// widths behind (inside the bounds), so every sub-sample hits that
    /// object within `[ta, tc]`: no silhouette and no occlusion edge
    /// between distant surfaces crosses the pixel, and its colour varies
    /// with the normal (grazing views; creases are ruled out by
    /// `ir::prune::smooth_on`). It gets one level fewer than the depth
    /// (at least 2×2), off shadow edges.
    Covered,
    /// Included (one object, hit by every ray in a proven bracket, facing
    /// the viewer), off any shadow edge, only the colour interval too
    /// wide: 2×2 sub-samples.
    Shading,
    /// Anything else (silhouettes, thin features, shadow edges):
    /// 2^depth × 2^depth sub-samples.
    Full,
}

impl Sampling {
    /// Every kind that gets sub-samples.
    pub(crate) const SPLIT: [Sampling; 3] = [Sampling::Covered, Sampling::Shading, Sampling::Full];

    /// Whether the pixel gets sub-samples.
    pub(crate) fn is_split(self) -> bool {
        self != Sampling::Base
    }

    /// Levels of 2×2 splitting below the pixel for an IAA depth `depth`
    /// (0 for the base sample).
    pub(crate) fn level(self, depth: u32) -> u32 {
        match self {
            Sampling::Base => 0,
            Sampling::Shading => depth.min(1),
            Sampling::Covered => depth.saturating_sub(1).max(depth.min(1)),
            Sampling::Full => depth,
        }
    }
}

/// Where the covered test looks for a proven-negative cross-section when
/// the inclusion test's [`probe::INCLUSION_REACH`] found none, in
/// multiples of the candidate piece's width: grazing rays go deeper
/// before the whole cross-section is inside the solid. The bound keeps
/// the piece thin (at most this many pixel footprints deep), so that the
/// covered pixel holds no edge between surfaces far apart in depth.
pub(super) const COVER_REACH: [f64; 2] = [8.0, 16.0];

/// The offsets of a pixel's eight neighbours, which the shadow-edge rule
/// compares it with.
pub(super) const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, 0),
    (1, 0),
    (0, -1),
    (0, 1),
    (-1, -1),
    (1, -1),
    (-1, 1),
    (1, 1),
];

/// How far along its ray, in pixel spacings at the base hit's depth, a
/// sub-sample's hit may lie from its pixel's base hit and still take that
/// sample's shadow state instead of tracing its own shadow segments, in a
/// pixel off shadow edges. The shadow-edge rule already lets one base
/// sample stand for the shadows over a smooth pixel; the sub-samples of a
/// split pixel that hit the same stretch of surface get the same answer,
/// while those that hit another surface behind it (a silhouette's far
/// side) trace their own. At 256², orthocircle's and metaballs' RMSE
/// against the 16×16 reference were unchanged (to four digits) with this
/// reach, and the sub-samples' shadow time fell by more than half.
pub(crate) const SHADOW_REUSE_REACH: f64 = 2.0;

/// Functions longer than this are not tested for smoothness over a pixel
/// (`ir::prune::smooth_on` walks the whole function): their pixels are
/// never sampled as covered.
pub(super) const SMOOTH_TEST_MAX_OPS: usize = 4096;

/// The pixel-area tests of IAA over the tile `area` (x0, y0, w, h), before
/// any ray is traced: which pixels are proven background (no ray), which
/// lie under an included cell (their rays' first roots bracketed: the
/// base sample is refined there, with no beam of its own) and how the
/// others are sampled, with the ray parameter before which each pixel's
/// area was proven empty (where its rays may start). The shadow-edge rule,
/// which reads the base samples, is applied afterwards
/// ([`Classified::mark_shadow_edges`]).
pub(crate) fn classify_tile(
    tr: &Scope<'_>,
    (x0, y0, w, h): (u32, u32, u32, u32),
    threshold: f64,
    st: &mut TileState,
) -> Classified {
    let n = (w * h) as usize;
    let mut c = Classified {
        w,
        sampling: vec![Sampling::Base; n],
        traced: vec![true; n],
        floors: vec![EmptyPrefix::NONE; n],
        edge: vec![false; n],
        brackets: vec![None; n],
        by_shading: vec![false; n],
    };
    let all: Vec<u32> = (0..tr.ctx.evals.len() as u32).collect();
    let corners = RayGrid::of_pixel_corners(&tr.ctx.cam, (x0, y0), (w, h));
    // The tests run on the functions pruned to the tile's beam over its
    // pixels' whole area and its slices along the rays, as the tile's
    // visibility does over its pixel centres (`tile::prune_to_tile`):
    // on the whole function, a union of 400 spheres spent most of its
    // IAA render here.
    let pruned = pruned_to_area(tr, (x0, y0, w, h), &corners, st);
    let local;
    let scope = match &pruned {
        Some((set, ends)) => {
            local = tr.with_evals(set).with_slice_ends(ends.clone());
            &local
        }
        None => tr,
    };
    let ctx = PixelAreas {
        tr: scope,
        whole: tr,
        all: &all,
        threshold,
        corners: &corners,
    };
    let whole = Rect {
        x0: 0,
        y0: 0,
        x1: w,
        y1: h,
    };
    let top = FromParent {
        floor: EmptyPrefix::NONE,
        inherited: None,
    };
    ctx.block(&mut c, whole, top, st);
    c
}

// The scene's evaluators pruned to the beam of the tile `(x0, y0, w, h)`
// over its pixels' whole area (corner to corner, `corners`), from where
// that beam enters the bounds to `far_t`, with the interior ends of its
// slices; `None` where nothing prunes. The tests' boxes reach `far_t`,
// beyond which no block's rays are inside the bounds: clipped to the
// bounds, the hull of a piece past the beam's exit still overhangs the
// hull over the slab range, and a box outside the region runs the whole
// function.
fn pruned_to_area(
    tr: &Scope<'_>,
    (x0, y0, w, h): (u32, u32, u32, u32),
    corners: &RayGrid,
    st: &mut TileState,
) -> Option<(EvalSet, Vec<f64>)> {
    let xs = (f64::from(x0), f64::from(x0 + w));
    let ys = (f64::from(y0), f64::from(y0 + h));
    let slab = tr.ctx.cam.corners(xs, ys).slab_range(&tr.ctx.bounds)?;
    let far = far_t(
        &corners.corners((0, 0), (w + 1, h + 1)),
        &bounds_box(&tr.ctx.bounds),
    );
    let t = Interval::new(slab.lo, slab.hi.max(far));
    let pruned = tr.pruned_to_beam(xs, ys, t, st)?;
    Some((pruned, tr.slice_ends(xs, ys, t)))
}

/// The shadow-edge rule over a tile's base samples (`depth`: +inf where the
/// centre ray missed; `shadowed`: lights shadowed there), `beside` giving
/// those just outside it: a hit pixel whose shadow state differs from a
/// hit neighbour's (diagonals included) sits on a shadow edge.
pub(crate) fn shadow_edges(
    (w, h): (u32, u32),
    depth: &[f64],
    shadowed: &[u64],
    beside: NeighbourTiles<'_>,
) -> Vec<bool> {
    let (w, h) = (i64::from(w), i64::from(h));
    let base = |i: i64, j: i64| -> Option<(bool, u64)> {
        if (0..w).contains(&i) && (0..h).contains(&j) {
            let k = (j * w + i) as usize;
            Some((depth[k].is_finite(), shadowed[k]))
        } else {
            beside.at((i, j), (w, h))
        }
    };
    (0..(w * h) as usize)
        .map(|k| {
            let (i, j) = (k as i64 % w, k as i64 / w);
            base(i, j).is_some_and(|(hit, mine)| {
                hit && NEIGHBOURS.iter().any(|&(di, dj)| {
                    base(i + di, j + dj).is_some_and(|(nhit, theirs)| nhit && theirs != mine)
                })
            })
        })
        .collect()
}

/// What IAA's pixel-area tests found, per pixel of a tile (row-major).
pub(crate) struct Classified {
    /// Tile width.
    pub(super) w: u32,
    /// How each pixel is sampled.
    pub sampling: Vec<Sampling>,
    /// Whether the pixel's centre ray is traced: false where its whole
    /// area is proven background.
    pub traced: Vec<bool>,
    /// What a pixel's area tests proved along its rays: empty up to
    /// `at`, the first candidate piece ending at `near`.
    pub floors: Vec<EmptyPrefix>,
    /// Which pixels sit on a shadow edge (after
    /// [`Classified::mark_shadow_edges`]).
    pub edge: Vec<bool>,
    /// The bracket of each pixel whose area lies under an included cell:
    /// its base sample and any sub-samples are refined there.
    pub brackets: Vec<Option<RootBracket>>,
    /// Pixels under an included cell whose colour interval was too wide.
    pub(super) by_shading: Vec<bool>,
}

impl Classified {
    /// Applies the shadow-edge rule `edge` (see [`shadow_edges`]): a hit
    /// pixel on a shadow edge gets the full depth, even where its area was
    /// smooth. Counts the split pixels' kinds.
    pub(crate) fn mark_shadow_edges(&mut self, edge: Vec<bool>, st: &mut RenderStats) {
        for (k, &e) in edge.iter().enumerate() {
            if e {
                self.sampling[k] = Sampling::Full;
            }
            let s = self.sampling[k];
            let bracketed = self.brackets[k].is_some_and(|b| b.unique) && (self.by_shading[k] || e);
            st.aa_split_by_shading += u64::from(s.is_split() && bracketed);
            st.aa_split_covered += u64::from(s == Sampling::Covered);
        }
        self.edge = edge;
    }

    pub(super) fn idx(&self, (i, j): (u32, u32)) -> usize {
        (j * self.w + i) as usize
    }
}

/// Per pixel: mean linear colour, covered fraction and nearest hit of the
/// sub-samples.
pub(crate) struct SplitSamples {
    /// Mean linear colour.
    pub linear: Vec<[f64; 3]>,
    /// Covered fraction.
    pub coverage: Vec<f64>,
    /// Nearest hit.
    pub depth: Vec<f64>,
}

impl SplitSamples {
    /// No pixel split yet: black, uncovered, nothing hit, for `n` pixels.
    pub(crate) fn none(n: usize) -> SplitSamples {
        SplitSamples {
            linear: vec![[0.0; 3]; n],
            coverage: vec![0.0; n],
            depth: vec![f64::INFINITY; n],
        }
    }
}

/// Folds the sub-samples of the split pixels (`fine`: per pixel the mean
/// linear colour, covered fraction and nearest hit of its `per[k]`
/// samples) into the tile, and counts the samples.
pub(crate) fn merge_split(
    px: &mut TilePixels<'_>,
    split: &[bool],
    fine: Option<&SplitSamples>,
    per: &[u32],
    st: &mut RenderStats,
) {
    for k in 0..split.len() {
        let centre_hit = px.depth[k].is_finite();
        match fine {
            Some(fine) if split[k] => {
                let (mut c, mut h) = (fine.linear[k], fine.coverage[k]);
                let per = per[k];
                let mut s = per;
                if h == 0.0 && centre_hit {
                    // Keep the proof of surface the centre ray gave: it
                    // joins the average with the weight of one sample.
                    let wl = 1.0 / f64::from(per);
                    let tot = 1.0 + wl;
                    c = std::array::from_fn(|i| (c[i] + wl * px.linear[k][i]) / tot);
                    h = wl / tot;
                    s += 1;
                }
                px.linear[k] = c;
                px.coverage[k] = h;
                px.depth[k] = px.depth[k].min(fine.depth[k]);
                px.samples[k] = s;
            }
            _ => {
                px.coverage[k] = if centre_hit { 1.0 } else { 0.0 };
                px.samples[k] = 1;
            }
        }
        let s = u64::from(px.samples[k]);
        st.aa_samples += s;
        st.aa_samples_max = st.aa_samples_max.max(s);
        st.aa_pixels_split += u64::from(s > 1);
    }
}
