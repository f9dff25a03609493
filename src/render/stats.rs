//! Render counters: gathered per tile, merged in tile order at the end, so
//! every count is the same for any thread count (times are not).

use std::fmt;

/// What a render did and how long it took.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Pixels whose ray hit a surface.
    pub pixels_hit: u64,
    /// Single rays traced (interval rays for beam/pixel, marches for point).
    pub rays: u64,
    /// Pixels of included blocks, which refine a bracketed root (no ray).
    pub pixels_refined: u64,
    /// Interval (and interval-gradient) evaluations of one object.
    pub interval_evals: u64,
    /// Point (and point-gradient) evaluations of one object.
    pub point_evals: u64,
    /// Per-pixel shadow segments tested.
    pub shadow_rays: u64,
    /// Per-pixel shadow segments made unnecessary by a block shadow beam.
    pub shadow_rays_saved: u64,
    /// Shadow beams that proved a whole block lit.
    pub shadow_beams_ok: u64,
    /// Shadow beams tried.
    pub shadow_beams: u64,
    /// Mean-value tightenings of a block interval tried.
    pub mean_value_tries: u64,
    /// Mean-value tightenings that proved a sign the natural form did not.
    pub mean_value_wins: u64,
    /// Mean-value (tries, wins) per block-size class, log2 of the side;
    /// drives the per-tile choice to use the form (not in the JSON).
    pub mean_value_levels: [(u64, u64); super::MV_LEVELS],
    /// Blocks (over one pixel) whose whole ray range was rejected.
    pub blocks_rejected: u64,
    /// Blocks (over one pixel) settled by the inclusion test.
    pub blocks_included: u64,
    /// Blocks (over one pixel) split or handed to single rays.
    pub blocks_undecided: u64,
    /// Samples summed over pixels (a rejected sub-pixel cell counts as
    /// one sample, traced by no ray).
    pub aa_samples: u64,
    /// Most samples in one pixel.
    pub aa_samples_max: u64,
    /// Pixels given more than one sample.
    pub aa_pixels_split: u64,
    /// IAA pixels split only because their colour interval was too wide
    /// (their beam passed the inclusion test).
    pub aa_split_by_shading: u64,
    /// Anti-aliasing tests and extra samples, summed over threads, ms.
    pub aa_cpu_ms: f64,
    /// Live ops of the functions that were pruned to a tile, summed over
    /// tiles (see `crate::ir::prune`).
    pub pruned_ops_before: u64,
    /// Live ops of those functions after pruning, summed over tiles.
    pub pruned_ops_after: u64,
    /// Render wall time, ms (excludes parsing and compiling).
    pub time_ms: f64,
    /// Time to build the evaluators and compile their native code, ms.
    pub compile_ms: f64,
    /// Visibility (beams, rays, root refinement), summed over threads, ms.
    pub trace_cpu_ms: f64,
    /// Shading without shadows, summed over threads, ms.
    pub shade_cpu_ms: f64,
    /// Shadow tests, summed over threads, ms.
    pub shadow_cpu_ms: f64,
    /// Building the output images after tracing, wall ms.
    pub output_ms: f64,
}

impl RenderStats {
    /// Adds the counters and CPU times of `o` (a tile) into `self`.
    pub fn merge(&mut self, o: &RenderStats) {
        self.pixels_hit += o.pixels_hit;
        self.rays += o.rays;
        self.pixels_refined += o.pixels_refined;
        self.interval_evals += o.interval_evals;
        self.point_evals += o.point_evals;
        self.shadow_rays += o.shadow_rays;
        self.shadow_rays_saved += o.shadow_rays_saved;
        self.shadow_beams_ok += o.shadow_beams_ok;
        self.shadow_beams += o.shadow_beams;
        self.mean_value_tries += o.mean_value_tries;
        self.mean_value_wins += o.mean_value_wins;
        for (a, b) in self.mean_value_levels.iter_mut().zip(&o.mean_value_levels) {
            a.0 += b.0;
            a.1 += b.1;
        }
        self.blocks_rejected += o.blocks_rejected;
        self.blocks_included += o.blocks_included;
        self.blocks_undecided += o.blocks_undecided;
        self.aa_samples += o.aa_samples;
        self.aa_samples_max = self.aa_samples_max.max(o.aa_samples_max);
        self.aa_pixels_split += o.aa_pixels_split;
        self.aa_split_by_shading += o.aa_split_by_shading;
        self.aa_cpu_ms += o.aa_cpu_ms;
        self.pruned_ops_before += o.pruned_ops_before;
        self.pruned_ops_after += o.pruned_ops_after;
        self.trace_cpu_ms += o.trace_cpu_ms;
        self.shade_cpu_ms += o.shade_cpu_ms;
        self.shadow_cpu_ms += o.shadow_cpu_ms;
    }

    /// Mean samples per pixel.
    pub fn aa_samples_mean(&self) -> f64 {
        let px = u64::from(self.width) * u64::from(self.height);
        if px == 0 {
            0.0
        } else {
            self.aa_samples as f64 / px as f64
        }
    }

    /// The statistics as a JSON object (key names = field names, and
    /// `aa_samples_mean` in place of `aa_samples`).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "width": self.width,
            "height": self.height,
            "pixels_hit": self.pixels_hit,
            "rays": self.rays,
            "pixels_refined": self.pixels_refined,
            "interval_evals": self.interval_evals,
            "point_evals": self.point_evals,
            "shadow_rays": self.shadow_rays,
            "shadow_rays_saved": self.shadow_rays_saved,
            "shadow_beams_ok": self.shadow_beams_ok,
            "shadow_beams": self.shadow_beams,
            "mean_value_tries": self.mean_value_tries,
            "mean_value_wins": self.mean_value_wins,
            "blocks_rejected": self.blocks_rejected,
            "blocks_included": self.blocks_included,
            "blocks_undecided": self.blocks_undecided,
            "aa_samples_mean": self.aa_samples_mean(),
            "aa_samples_max": self.aa_samples_max,
            "aa_pixels_split": self.aa_pixels_split,
            "aa_split_by_shading": self.aa_split_by_shading,
            "aa_cpu_ms": self.aa_cpu_ms,
            "pruned_ops_before": self.pruned_ops_before,
            "pruned_ops_after": self.pruned_ops_after,
            "time_ms": self.time_ms,
            "compile_ms": self.compile_ms,
            "trace_cpu_ms": self.trace_cpu_ms,
            "shade_cpu_ms": self.shade_cpu_ms,
            "shadow_cpu_ms": self.shadow_cpu_ms,
            "output_ms": self.output_ms,
        })
    }
}

impl fmt::Display for RenderStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let px = u64::from(self.width) * u64::from(self.height);
        writeln!(
            f,
            "{}x{}: {} of {} pixels hit in {:.1} ms (compile {:.1} ms)",
            self.width, self.height, self.pixels_hit, px, self.time_ms, self.compile_ms
        )?;
        writeln!(
            f,
            "rays {}, refined pixels {}, blocks rejected/included/undecided {}/{}/{}",
            self.rays,
            self.pixels_refined,
            self.blocks_rejected,
            self.blocks_included,
            self.blocks_undecided
        )?;
        writeln!(
            f,
            "evaluations: interval {}, point {}",
            self.interval_evals, self.point_evals
        )?;
        writeln!(
            f,
            "shadow rays {}, saved by {} of {} shadow beams {}",
            self.shadow_rays, self.shadow_beams_ok, self.shadow_beams, self.shadow_rays_saved
        )?;
        writeln!(
            f,
            "anti-aliasing: {:.2} samples per pixel (max {}), {} pixels split ({} by shading alone)",
            self.aa_samples_mean(),
            self.aa_samples_max,
            self.aa_pixels_split,
            self.aa_split_by_shading
        )?;
        if self.pruned_ops_before > 0 {
            writeln!(
                f,
                "pruned per tile: {} ops evaluated as {} ({:.1}%)",
                self.pruned_ops_before,
                self.pruned_ops_after,
                100.0 * self.pruned_ops_after as f64 / self.pruned_ops_before as f64
            )?;
        }
        write!(
            f,
            "cpu ms: trace {:.1}, shade {:.1}, shadow {:.1}, aa {:.1}; output {:.1} ms",
            self.trace_cpu_ms,
            self.shade_cpu_ms,
            self.shadow_cpu_ms,
            self.aa_cpu_ms,
            self.output_ms
        )
    }
}
