//! Accuracy against a reference: time against error for every visibility
//! method and anti-aliasing mode.
//!
//! The reference is [`Method::Pixel`] with 16×16 regular supersampling
//! ([`REFERENCE`]): 256 guaranteed interval rays per pixel, each with the
//! depth tolerance of a 16× finer image. Every other variant is compared
//! with it pixel by pixel:
//! - `rmse`: root mean square error of linear colour over pixels and
//!   channels; `max_abs`: the largest channel error;
//! - `coverage_diff_pct`: percentage of pixels whose coverage (fraction of
//!   the pixel, by sample area, whose samples hit) differs from the
//!   reference's by more than 1/8;
//! - `missed_surface`: pixels where the reference sees surface and the
//!   variant reports pure background (coverage 0). The reference "sees
//!   surface" in a pixel when at least half of its 256 rays hit, or when
//!   the guaranteed ray through the pixel centre (`--method pixel`, no
//!   anti-aliasing) hits. (Any single hit of 256 would flag every
//!   silhouette pixel of a one-sample method, which says nothing.)
//!
//! Times are render wall times, the best of [`REPEATS`] rounds that
//! render every variant in turn (see [`sweep_scene`]), evaluators built
//! once per scene outside the timing.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::plot::plot;
use crate::eval::Evaluator;
use crate::render::{Aa, Enclosure, Method, RenderError, RenderOptions, RenderOutput, render_aa};
use crate::scene::Scene;

/// The reference: guaranteed per-pixel rays, 16×16 per pixel.
pub const REFERENCE: (Method, Aa) = (Method::Pixel, Aa::Grid(16));

/// Coverage differences above this count in `coverage_diff_pct`.
pub const COVERAGE_TOLERANCE: f64 = 1.0 / 8.0;

/// Rounds over every variant in [`run_accuracy`]; each time is the best
/// of these.
pub const REPEATS: u32 = 5;

/// Builds one evaluator per scene object.
pub type MakeEvaluators<'a> = &'a dyn Fn(&Scene) -> Result<Vec<Arc<dyn Evaluator>>, String>;

/// A series of the sweep: the reference, or one method (with one kind of
/// anti-aliasing) at several settings.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// [`REFERENCE`].
    Reference,
    /// Point sampling.
    Point,
    /// Guaranteed per-pixel rays.
    Pixel,
    /// Beams.
    Beam,
    /// Beams with regular supersampling.
    BeamGrid,
    /// Beams with interval adaptive anti-aliasing.
    BeamIaa,
}

impl Family {
    /// Its name in the CSV, the table and the plot.
    pub fn name(self) -> &'static str {
        match self {
            Family::Reference => "reference",
            Family::Point => "point",
            Family::Pixel => "pixel",
            Family::Beam => "beam",
            Family::BeamGrid => "beam+grid",
            Family::BeamIaa => "beam+iaa",
        }
    }
}

/// As in the CSV: `point`, `beam+iaa`, ...
impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One rendering configuration of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// The series it belongs to in the plot.
    pub family: Family,
    /// Its parameter within the family (`steps=64`, `t=1/64`, ...).
    pub param: String,
    /// Visibility method.
    pub method: Method,
    /// Anti-aliasing.
    pub aa: Aa,
}

impl Variant {
    fn new(family: Family, param: &str, method: Method, aa: Aa) -> Variant {
        Variant {
            family,
            param: param.to_string(),
            method,
            aa,
        }
    }
}

/// The default sweep: point sampling at 16, 64 and 256 steps, the pixel
/// and beam methods, beam + grid:2, grid:4 and grid:8, and beam + IAA at
/// depth 2 (up to 16 samples a pixel) with thresholds 1 (every included
/// pixel is smooth: geometry alone decides), 1/4, 1/16 and 1/64, and at
/// depth 3 (up to 64, grid:8's sample positions) with 1, 1/16 and 1/64.
pub fn default_variants() -> Vec<Variant> {
    let mut v = Vec::new();
    for steps in [16, 64, 256] {
        v.push(Variant::new(
            Family::Point,
            &format!("steps={steps}"),
            Method::Point { steps },
            Aa::None,
        ));
    }
    v.push(Variant::new(Family::Pixel, "", Method::Pixel, Aa::None));
    v.push(Variant::new(Family::Beam, "", Method::Beam, Aa::None));
    for n in [2, 4, 8] {
        v.push(Variant::new(
            Family::BeamGrid,
            &format!("grid:{n}"),
            Method::Beam,
            Aa::Grid(n),
        ));
    }
    for d in [1u32, 4, 16, 64] {
        v.push(Variant::new(
            Family::BeamIaa,
            &format!("t=1/{d}"),
            Method::Beam,
            Aa::Iaa {
                threshold: 1.0 / f64::from(d),
                depth: crate::render::aa::DEFAULT_DEPTH,
            },
        ));
    }
    for d in [1u32, 16, 64] {
        v.push(Variant::new(
            Family::BeamIaa,
            &format!("t=1/{d} depth=3"),
            Method::Beam,
            Aa::Iaa {
                threshold: 1.0 / f64::from(d),
                depth: 3,
            },
        ));
    }
    v
}

/// How far above a grid's RMSE an IAA render may be and still count as
/// reaching it: IAA's sub-samples sit where the grid's do, so where it
/// samples it matches the grid, and its RMSE differs from the grid's by
/// rounding-level amounts (0.005% on orthocircle at 256²) that a strict
/// comparison would turn into "not reached".
pub const RMSE_MATCH: f64 = 1.01;

/// IAA against one grid setting on one scene: the fastest IAA render whose
/// RMSE is at most the grid's (within [`RMSE_MATCH`]), and the ratio of
/// their times.
#[derive(Clone, Debug, PartialEq)]
pub struct IaaVersusGrid {
    /// Scene name.
    pub scene: String,
    /// The grid's parameter (`grid:4`).
    pub grid: String,
    /// The grid's time, ms, and RMSE.
    pub grid_time_ms: f64,
    /// The grid's RMSE.
    pub grid_rmse: f64,
    /// The fastest IAA at or below that RMSE (its parameter, time, RMSE),
    /// if any IAA setting reaches it.
    pub iaa: Option<(String, f64, f64)>,
}

impl IaaVersusGrid {
    /// IAA's time over the grid's, when IAA reaches the grid's error.
    pub fn ratio(&self) -> Option<f64> {
        self.iaa.as_ref().map(|(_, t, _)| t / self.grid_time_ms)
    }
}

/// For each scene and each grid setting in `rows`, what IAA costs to reach
/// the grid's error (the targets are stated this way).
pub fn iaa_versus_grid(rows: &[AccuracyRow]) -> Vec<IaaVersusGrid> {
    let mut out = Vec::new();
    for g in rows.iter().filter(|r| r.family == Family::BeamGrid) {
        let iaa = rows
            .iter()
            .filter(|r| {
                r.scene == g.scene && r.family == Family::BeamIaa && r.rmse <= g.rmse * RMSE_MATCH
            })
            .min_by(|a, b| a.time_ms.total_cmp(&b.time_ms))
            .map(|r| (r.param.clone(), r.time_ms, r.rmse));
        out.push(IaaVersusGrid {
            scene: g.scene.clone(),
            grid: g.param.clone(),
            grid_time_ms: g.time_ms,
            grid_rmse: g.rmse,
            iaa,
        });
    }
    out
}

/// One line of `accuracy.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyRow {
    /// Scene name (file stem).
    pub scene: String,
    /// Series.
    pub family: Family,
    /// Parameter within the series.
    pub param: String,
    /// The enclosure choice the render ran with (`--enclosure`).
    pub enclosure: Enclosure,
    /// Render wall time, ms (best of the repeats).
    pub time_ms: f64,
    /// RMSE of linear colour against the reference.
    pub rmse: f64,
    /// Largest absolute channel error against the reference.
    pub max_abs: f64,
    /// Percentage of pixels whose coverage differs by more than 1/8.
    pub coverage_diff_pct: f64,
    /// Pixels where the reference sees surface and the variant none.
    pub missed_surface: u64,
    /// Mean samples per pixel.
    pub samples_mean: f64,
    /// Rays traced.
    pub rays: u64,
    /// On the scene's time/RMSE Pareto front (reference excluded).
    pub pareto: bool,
}

/// The CSV header, in column order.
pub const CSV_HEADER: &str = "scene,family,param,enclosure,time_ms,rmse,max_abs,coverage_diff_pct,missed_surface,samples_mean,rays,pareto";

/// Why the sweep failed.
#[derive(Debug)]
pub enum AccuracyError {
    /// A scene could not be loaded or its evaluators built.
    Scene(String),
    /// A render failed.
    Render(RenderError),
    /// An output file could not be written.
    Io(String),
    /// The plot could not be drawn.
    Plot(String),
}

impl fmt::Display for AccuracyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AccuracyError::Scene(e) => write!(f, "{e}"),
            AccuracyError::Render(e) => write!(f, "render failed: {e}"),
            AccuracyError::Io(e) => write!(f, "{e}"),
            AccuracyError::Plot(e) => write!(f, "cannot draw the plot: {e}"),
        }
    }
}

impl std::error::Error for AccuracyError {}

impl From<RenderError> for AccuracyError {
    fn from(e: RenderError) -> Self {
        AccuracyError::Render(e)
    }
}

/// Errors of `out` against the reference (`centre`: the reference's
/// guaranteed centre-ray hit mask).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Errors {
    /// RMSE of linear colour.
    pub rmse: f64,
    /// Largest absolute channel error.
    pub max_abs: f64,
    /// Percentage of pixels with a coverage difference above 1/8.
    pub coverage_diff_pct: f64,
    /// Pixels where the reference sees surface and `out` none.
    pub missed_surface: u64,
}

/// Compares a render with the reference render of the same size.
pub fn compare(reference: &RenderOutput, centre: &[bool], out: &RenderOutput) -> Errors {
    let n = reference.linear.len().min(out.linear.len());
    let (mut sq, mut max_abs, mut cov, mut missed) = (0.0, 0.0f64, 0u64, 0u64);
    for k in 0..n {
        for c in 0..3 {
            let lin = |o: &RenderOutput| f64::from(o.linear[k][c]).clamp(0.0, 1.0);
            let e = (lin(out) - lin(reference)).abs();
            sq += e * e;
            max_abs = max_abs.max(e);
        }
        let (rc, oc) = (f64::from(reference.coverage[k]), f64::from(out.coverage[k]));
        cov += u64::from((rc - oc).abs() > COVERAGE_TOLERANCE);
        let sees = rc >= 0.5 || centre.get(k).copied().unwrap_or(false);
        missed += u64::from(sees && oc == 0.0);
    }
    let n = n.max(1) as f64;
    Errors {
        rmse: (sq / (3.0 * n)).sqrt(),
        max_abs,
        coverage_diff_pct: 100.0 * cov as f64 / n,
        missed_surface: missed,
    }
}

/// Renders `scene` with the reference and every variant at `size`² and
/// returns one row per render, the reference first, with the Pareto front
/// marked. Each variant's time is its best of `repeats` rounds, each
/// round rendering every variant once in turn: a slow spell of a shared
/// machine then costs every variant a round alike, where consecutive
/// repeats of one variant let a spell skew the ratios between variants.
pub fn sweep_scene(
    name: &str,
    scene: &Scene,
    evaluators: &[Arc<dyn Evaluator>],
    size: u32,
    variants: &[Variant],
    repeats: u32,
    enclosure: Enclosure,
) -> Result<Vec<AccuracyRow>, AccuracyError> {
    let run = |method: Method, aa: Aa| -> Result<RenderOutput, AccuracyError> {
        let mut opts = RenderOptions::new(size, size);
        opts.method = method;
        opts.enclosure = enclosure;
        Ok(render_aa(scene, evaluators, &opts, aa)?)
    };
    let reference = run(REFERENCE.0, REFERENCE.1)?;
    let centre = run(Method::Pixel, Aa::None)?.hit_mask;
    let row = |family: Family, param: &str, out: &RenderOutput| {
        let e = compare(&reference, &centre, out);
        AccuracyRow {
            scene: name.to_string(),
            family,
            param: param.to_string(),
            enclosure,
            time_ms: out.stats.time_ms,
            rmse: e.rmse,
            max_abs: e.max_abs,
            coverage_diff_pct: e.coverage_diff_pct,
            missed_surface: e.missed_surface,
            samples_mean: out.stats.aa_samples_mean(),
            rays: out.stats.rays,
            pareto: false,
        }
    };
    let mut best: Vec<Option<RenderOutput>> = variants.iter().map(|_| None).collect();
    for _ in 0..repeats.max(1) {
        for (v, b) in variants.iter().zip(&mut best) {
            let out = run(v.method, v.aa)?;
            if b.as_ref()
                .is_none_or(|b| out.stats.time_ms < b.stats.time_ms)
            {
                *b = Some(out);
            }
        }
    }
    let mut rows = vec![row(Family::Reference, "pixel+grid:16", &reference)];
    for (v, out) in variants.iter().zip(&best) {
        let out = out
            .as_ref()
            .ok_or_else(|| AccuracyError::Scene("no render".into()))?;
        rows.push(row(v.family, &v.param, out));
    }
    mark_pareto(&mut rows[1..]);
    Ok(rows)
}

/// Marks the rows no other row beats on both time and RMSE.
pub fn mark_pareto(rows: &mut [AccuracyRow]) {
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.time_ms, r.rmse)).collect();
    for (i, r) in rows.iter_mut().enumerate() {
        let (t, e) = pts[i];
        r.pareto = !pts
            .iter()
            .enumerate()
            .any(|(j, &(t2, e2))| j != i && t2 <= t && e2 <= e && (t2 < t || e2 < e));
    }
}

/// Sweeps every scene, then writes `out_dir/accuracy.csv` and
/// `out_dir/accuracy.png` (time against RMSE, log-log, one panel per
/// scene, Pareto front ringed).
pub fn run_accuracy(
    scenes: &[PathBuf],
    out_dir: &Path,
    size: u32,
    enclosure: Enclosure,
    make_evaluators: MakeEvaluators<'_>,
) -> Result<Vec<AccuracyRow>, AccuracyError> {
    std::fs::create_dir_all(out_dir)
        .map_err(|e| AccuracyError::Io(format!("cannot create {}: {e}", out_dir.display())))?;
    let variants = default_variants();
    let mut rows = Vec::new();
    for path in scenes {
        let scene = crate::lang::load_scene(path)
            .map_err(|e| AccuracyError::Scene(format!("{}: {e}", path.display())))?;
        let evals = make_evaluators(&scene)
            .map_err(|e| AccuracyError::Scene(format!("{}: {e}", path.display())))?;
        let name = path.file_stem().map_or_else(
            || path.display().to_string(),
            |s| s.to_string_lossy().into(),
        );
        rows.extend(sweep_scene(
            &name, &scene, &evals, size, &variants, REPEATS, enclosure,
        )?);
    }
    write_csv(&rows, &out_dir.join("accuracy.csv"))?;
    plot(&rows, &out_dir.join("accuracy.png"))?;
    Ok(rows)
}

/// Writes the rows as CSV with [`CSV_HEADER`].
pub fn write_csv(rows: &[AccuracyRow], path: &Path) -> Result<(), AccuracyError> {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{:.3},{:.6e},{:.6},{:.3},{},{:.3},{},{}\n",
            r.scene,
            r.family,
            r.param,
            r.enclosure.name(),
            r.time_ms,
            r.rmse,
            r.max_abs,
            r.coverage_diff_pct,
            r.missed_surface,
            r.samples_mean,
            r.rays,
            r.pareto
        ));
    }
    std::fs::write(path, s)
        .map_err(|e| AccuracyError::Io(format!("cannot write {}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(t: f64, e: f64) -> AccuracyRow {
        AccuracyRow {
            scene: "s".into(),
            family: Family::Beam,
            param: String::new(),
            enclosure: Enclosure::Auto,
            time_ms: t,
            rmse: e,
            max_abs: 0.0,
            coverage_diff_pct: 0.0,
            missed_surface: 0,
            samples_mean: 1.0,
            rays: 0,
            pareto: false,
        }
    }

    #[test]
    fn families_print_as_in_the_csv() {
        let names: Vec<String> = default_variants()
            .iter()
            .map(|v| v.family.to_string())
            .collect();
        let want = [
            "point",
            "point",
            "point",
            "pixel",
            "beam",
            "beam+grid",
            "beam+grid",
            "beam+grid",
            "beam+iaa",
            "beam+iaa",
            "beam+iaa",
            "beam+iaa",
            "beam+iaa",
            "beam+iaa",
            "beam+iaa",
        ];
        assert_eq!(names, want);
        assert_eq!(Family::Reference.to_string(), "reference");
    }

    // The fastest IAA at or below each grid's RMSE, none when no IAA
    // setting is that accurate.
    #[test]
    fn iaa_is_compared_at_each_grids_error() {
        let mk = |family: Family, param: &str, time_ms: f64, rmse: f64| AccuracyRow {
            family,
            param: param.into(),
            enclosure: Enclosure::Auto,
            time_ms,
            rmse,
            ..r(0.0, 0.0)
        };
        let rows = [
            mk(Family::BeamGrid, "grid:4", 100.0, 2e-3),
            mk(Family::BeamGrid, "grid:8", 400.0, 1e-3),
            mk(Family::BeamIaa, "t=1/4", 20.0, 5e-3),
            mk(Family::BeamIaa, "t=1/16", 60.0, 2.01e-3),
            mk(Family::BeamIaa, "t=1/64", 80.0, 1.5e-3),
        ];
        let c = iaa_versus_grid(&rows);
        assert_eq!(c.len(), 2);
        // 2.01e-3 is within 1% of grid:4's 2e-3: it counts.
        assert_eq!(c[0].iaa.as_ref().unwrap().0, "t=1/16");
        assert_eq!(c[0].ratio(), Some(0.6));
        assert!(c[1].iaa.is_none() && c[1].ratio().is_none());
    }

    #[test]
    fn pareto_front_keeps_only_undominated_rows() {
        let mut rows = vec![r(1.0, 0.5), r(2.0, 0.1), r(3.0, 0.2), r(4.0, 0.05)];
        mark_pareto(&mut rows);
        let p: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(p, [true, true, false, true]);
    }
}
