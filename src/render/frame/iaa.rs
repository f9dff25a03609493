//! IAA over a frame: the base render's tiles classified, split pixels
//! traced at finer resolutions, merged back.

use super::*;

// The base samples along a tile's sides, before its anti-aliasing.
pub(super) fn edges_of(t: &TileOut) -> TileEdges {
    TileEdges::new(t.w, t.h, &t.depth, &t.shadowed)
}

// Applies IAA to a tile traced by `Frame::trace_classified` (or, for the
// other modes, counts its samples): the shadow-edge rule over its base
// samples (`beside`: those around the tile), then the split pixels'
// sub-samples traced with beams on `fine`'s images, square by square
// (`trace_split`), each at its pixel's level (`aa::Sampling`).
// long-fn: the IAA pass over one tile in its order (shadow edges, then
// each level's split pixels, then the merge), over one tile's buffers.
pub(super) fn anti_alias(
    tr: &Scope<'_>,
    fine: Option<&FinerScopes<'_>>,
    opts: &RenderOptions,
    aa: Aa,
    t: &mut TileOut,
    beside: NeighbourTiles<'_>,
    bg: [f64; 3],
) {
    let (Aa::Iaa { depth, .. }, Some(fine)) = (aa, fine) else {
        let n = u64::from(t.w * t.h);
        let per = u64::from(aa.grid_factor()).pow(2);
        let st = &mut t.state.stats;
        st.aa_samples += n * per;
        st.aa_samples_max = st.aa_samples_max.max(per);
        if per > 1 {
            st.aa_pixels_split += n;
        }
        return;
    };
    let t0 = Instant::now();
    // The sub-samples carry on with the tile's own state.
    let mut st = std::mem::take(&mut t.state);
    let mut px = aa::TilePixels {
        linear: &mut t.linear,
        depth: &mut t.depth,
        coverage: &mut t.coverage,
        samples: &mut t.samples,
        shadowed: &t.shadowed,
    };
    // Traced by `Frame::trace_classified`, which always classifies.
    let Some(mut c) = t.classified.take() else {
        unreachable!("an IAA tile is classified when traced")
    };
    let edge = aa::shadow_edges((t.w, t.h), px.depth, px.shadowed, beside);
    c.mark_shadow_edges(edge, &mut st.stats);
    let area = TileArea {
        x0: t.x0,
        y0: t.y0,
        w: t.w,
        h: t.h,
    };
    // Each split pixel is sampled at its own level (see `aa::Sampling`):
    // the pixels of one level are traced together on that level's image.
    let n = c.sampling.len();
    let level: Vec<u32> = c.sampling.iter().map(|s| s.level(depth)).collect();
    let split: Vec<bool> = c.sampling.iter().map(|s| s.is_split()).collect();
    // Off shadow edges, sub-samples near their pixel's base hit take its
    // shadow state (see `aa::SHADOW_REUSE_REACH`).
    let hints: Vec<ShadowHint> = (0..n)
        .map(|k| {
            let t = px.depth[k];
            ShadowHint {
                t: if c.edge[k] { f64::NAN } else { t },
                reach: if t.is_finite() {
                    aa::SHADOW_REUSE_REACH * tr.ctx.cam.spacing(t)
                } else {
                    0.0
                },
                shadowed: px.shadowed[k],
            }
        })
        .collect();
    let mut sub: Option<SplitSamples> = None;
    for l in (1..=depth).rev() {
        let Some(fine_tr) = fine.at(l) else { continue };
        let these: Vec<bool> = level.iter().map(|&lk| lk == l).collect();
        if !these.iter().any(|&s| s) {
            continue;
        }
        let job = SplitJob {
            opts,
            area,
            split: &these,
            facts: PixelFacts {
                floors: &c.floors,
                hints: &hints,
                brackets: &c.brackets,
            },
            factor: 1 << l,
            background: bg,
        };
        let traced = trace_split(fine_tr, job, &mut st.prune, &mut st.stats);
        let all = sub.get_or_insert_with(|| SplitSamples::none(n));
        for k in (0..n).filter(|&k| these[k]) {
            all.linear[k] = traced.linear[k];
            all.coverage[k] = traced.coverage[k];
            all.depth[k] = traced.depth[k];
        }
    }
    let per: Vec<u32> = level.iter().map(|&l| 1 << (2 * l)).collect();
    aa::merge_split(&mut px, &split, sub.as_ref(), &per, &mut st.stats);
    st.stats.aa_cpu_ms += ms_since(t0);
    // The squares' cells go with the pass: a finished tile waits for its
    // row (a whole-image render holds every tile).
    st.prune = Default::default();
    t.state = st;
}
