//! Render counters: gathered per tile, merged in tile order at the end, so
//! every count is the same for any thread count (times are not).
//!
//! The counters are declared once, in the `counters!` list below: it
//! makes the struct, its merge and its text form, and serde makes its JSON,
//! so a new counter is one line of that list.

use std::fmt;

use serde::Serialize;

// How a field combines when tiles merge.
mod combine {
    // Work counted per tile: tiles add up.
    pub(super) fn sum<T: std::ops::AddAssign>(a: &mut T, b: T) {
        *a += b;
    }
    // A per-tile extreme: the largest wins.
    pub(super) fn max<T: PartialOrd>(a: &mut T, b: T) {
        if b > *a {
            *a = b;
        }
    }
    // Set once for the whole render (size, wall times): tiles add nothing.
    pub(super) fn once<T>(_: &mut T, _: T) {}
}

// One statistic's text form: counts as they are, times to a tenth of a ms.
trait Show {
    fn show(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result;
}

impl Show for u32 {
    fn show(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self}")
    }
}

impl Show for u64 {
    fn show(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self}")
    }
}

impl Show for f64 {
    fn show(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self:.1}")
    }
}

// Declares `RenderStats` from groups of fields, each `name: type => how`
// (`how` one of the `combine` functions), and derives from the same list
// its merge and its text form (one line per group).
macro_rules! counters {
    ($(
        $group:literal {
            $( $(#[$meta:meta])* $name:ident : $ty:ty => $how:ident, )*
        }
    )*) => {
        /// What a render did and how long it took.
        #[derive(Clone, Debug, Default, PartialEq, Serialize)]
        pub struct RenderStats {
            $($( $(#[$meta])* pub $name: $ty, )*)*
        }

        impl RenderStats {
            /// Adds the counters and CPU times of `o` (a tile) into `self`;
            /// the render-wide values (size, wall times) are left as they are.
            pub fn merge(&mut self, o: &RenderStats) {
                $($( combine::$how(&mut self.$name, o.$name); )*)*
            }
        }

        impl fmt::Display for RenderStats {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                let groups: &[(&str, &[(&str, &dyn Show)])] = &[$(
                    ($group, &[$( (stringify!($name), &self.$name as &dyn Show), )*]),
                )*];
                for (i, (group, fields)) in groups.iter().enumerate() {
                    if i > 0 {
                        writeln!(f)?;
                    }
                    write!(f, "{group}:")?;
                    for (j, (name, value)) in fields.iter().enumerate() {
                        write!(f, "{} {name} ", if j == 0 { "" } else { "," })?;
                        value.show(f)?;
                    }
                }
                Ok(())
            }
        }
    };
}

counters! {
    "image" {
        /// Image width in pixels.
        width: u32 => once,
        /// Image height in pixels.
        height: u32 => once,
        /// Pixels whose ray hit a surface.
        pixels_hit: u64 => sum,
    }
    "visibility" {
        /// Single rays traced (interval rays for beam/pixel, marches for point).
        rays: u64 => sum,
        /// Pixels of included blocks, which refine a bracketed root (no ray).
        pixels_refined: u64 => sum,
        /// Pixels of flat scenes settled by a block's batches of point and
        /// interval values (no ray).
        pixels_batched: u64 => sum,
        /// Blocks (over one pixel) whose whole ray range was rejected.
        blocks_rejected: u64 => sum,
        /// Blocks (over one pixel) settled by the inclusion test.
        blocks_included: u64 => sum,
        /// Blocks (over one pixel) split or handed to single rays.
        blocks_undecided: u64 => sum,
    }
    "evaluations" {
        /// Interval (and interval-gradient) evaluations of one object.
        interval_evals: u64 => sum,
        /// Point (and point-gradient) evaluations of one object.
        point_evals: u64 => sum,
        /// Mean-value tightenings of a block interval tried.
        mean_value_tries: u64 => sum,
        /// Mean-value tightenings that proved a sign the natural form did not.
        mean_value_wins: u64 => sum,
        /// Affine enclosures of a block tried (see `--enclosure`).
        affine_tries: u64 => sum,
        /// Affine enclosures that proved a sign the natural form did not.
        affine_wins: u64 => sum,
        /// Affine forms along a single ray's piece tried (one noise
        /// symbol, the ray parameter).
        affine_ray_tries: u64 => sum,
        /// Those that dropped an object from the piece or clipped it to
        /// at most half.
        affine_ray_wins: u64 => sum,
        /// Second-order forms along a single shadow segment's piece tried
        /// (the segment's parameter as the noise symbol).
        affine_shadow_tries: u64 => sum,
        /// Those that dropped an object from the piece or clipped it to
        /// at most half.
        affine_shadow_wins: u64 => sum,
        /// Live ops of the functions that were pruned to a tile, summed over
        /// tiles (see `crate::ir::prune`).
        pruned_ops_before: u64 => sum,
        /// Live ops of those functions after pruning, summed over tiles.
        pruned_ops_after: u64 => sum,
        /// Tiles that took tapes their group pruned ahead of time, in one
        /// batch with their siblings (flat scenes, see `render::groups`),
        /// rather than pruning their own.
        pruned_ahead: u64 => sum,
    }
    "shadows" {
        /// Per-pixel shadow segments tested.
        shadow_rays: u64 => sum,
        /// Per-pixel shadow segments made unnecessary by a block shadow beam.
        shadow_rays_saved: u64 => sum,
        /// Shadow beams that proved a whole block lit.
        shadow_beams_ok: u64 => sum,
        /// Shadow beams tried.
        shadow_beams: u64 => sum,
    }
    "anti-aliasing" {
        /// Samples summed over pixels (a rejected sub-pixel cell counts as
        /// one sample, traced by no ray); the JSON has the mean instead
        /// ([`RenderStats::aa_samples_mean`]).
        #[serde(skip)]
        aa_samples: u64 => sum,
        /// Most samples in one pixel.
        aa_samples_max: u64 => max,
        /// Pixels given more than one sample.
        aa_pixels_split: u64 => sum,
        /// IAA pixels split only because their colour interval was too wide
        /// (their beam passed the inclusion test).
        aa_split_by_shading: u64 => sum,
        /// IAA pixels proven covered by one surface in a thin piece but
        /// not smooth, sampled one level below the depth.
        aa_split_covered: u64 => sum,
    }
    "ms" {
        /// Render wall time, ms (excludes parsing and compiling).
        time_ms: f64 => once,
        /// Time to build the evaluators and compile their native code, ms.
        compile_ms: f64 => once,
        /// Wall time during the render in which a thread compiled native
        /// code it had asked for and waited on it (left out of
        /// `time_ms`), ms.
        compile_wait_ms: f64 => once,
        /// Visibility (beams, rays, root refinement), summed over threads, ms.
        trace_cpu_ms: f64 => sum,
        /// Shading without shadows, summed over threads, ms.
        shade_cpu_ms: f64 => sum,
        /// Shadow tests, summed over threads, ms.
        shadow_cpu_ms: f64 => sum,
        /// Anti-aliasing tests and extra samples, summed over threads, ms.
        aa_cpu_ms: f64 => sum,
        /// Of `aa_cpu_ms`, IAA's pixel-area tests (the rest is sub-samples), ms.
        aa_tests_cpu_ms: f64 => sum,
        /// Building the output images after tracing, wall ms.
        output_ms: f64 => once,
    }
}

/// The JSON form: every field under its own name, the sample count as a
/// per-pixel mean.
#[derive(Serialize)]
struct Json<'a> {
    #[serde(flatten)]
    stats: &'a RenderStats,
    aa_samples_mean: f64,
}

impl RenderStats {
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
        let json = Json {
            stats: self,
            aa_samples_mean: self.aa_samples_mean(),
        };
        // Numbers and strings only: nothing here can fail to serialise.
        serde_json::to_value(json).expect("render statistics serialise")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_sums_counts_keeps_the_largest_max_and_leaves_render_values() {
        let mut a = RenderStats {
            width: 8,
            rays: 2,
            aa_samples_max: 4,
            time_ms: 1.0,
            ..RenderStats::default()
        };
        let b = RenderStats {
            width: 3,
            rays: 5,
            aa_samples_max: 9,
            time_ms: 7.0,
            trace_cpu_ms: 2.5,
            ..RenderStats::default()
        };
        a.merge(&b);
        assert_eq!((a.width, a.rays, a.aa_samples_max), (8, 7, 9));
        assert_eq!((a.time_ms, a.trace_cpu_ms), (1.0, 2.5));
    }

    #[test]
    fn json_has_every_field_and_the_sample_mean() {
        let st = RenderStats {
            width: 2,
            height: 2,
            aa_samples: 10,
            rays: 3,
            ..RenderStats::default()
        };
        let json = st.to_json();
        let obj = json.as_object().unwrap();
        assert_eq!(obj.len(), 40);
        assert!(obj.get("aa_samples").is_none());
        assert_eq!(json["aa_samples_mean"], 2.5);
        assert_eq!(json["rays"], 3);
        assert_eq!(json["output_ms"], 0.0);
        assert_eq!(json["compile_wait_ms"], 0.0);
    }

    #[test]
    fn the_text_form_shows_every_field() {
        let text = RenderStats::default().to_string();
        let json = RenderStats::default().to_json();
        for key in json.as_object().unwrap().keys() {
            let name = if key == "aa_samples_mean" {
                "aa_samples"
            } else {
                key
            };
            assert!(
                text.contains(&format!(" {name} ")),
                "{name} missing from {text}"
            );
        }
    }
}
