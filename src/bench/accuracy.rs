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
//! Times are render wall times (best of `repeats`), evaluators built once
//! per scene outside the timing.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use plotters::prelude::*;

use crate::eval::Evaluator;
use crate::render::{Aa, Method, RenderError, RenderOptions, RenderOutput, render_aa};
use crate::scene::Scene;

/// The reference: guaranteed per-pixel rays, 16×16 per pixel.
pub const REFERENCE: (Method, Aa) = (Method::Pixel, Aa::Grid(16));

/// Coverage differences above this count in `coverage_diff_pct`.
pub const COVERAGE_TOLERANCE: f64 = 1.0 / 8.0;

/// Builds one evaluator per scene object.
pub type MakeEvaluators<'a> = &'a dyn Fn(&Scene) -> Result<Vec<Arc<dyn Evaluator>>, String>;

/// One rendering configuration of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// The series it belongs to in the plot (`point`, `beam+iaa`, ...).
    pub family: String,
    /// Its parameter within the family (`steps=64`, `t=1/64`, ...).
    pub param: String,
    /// Visibility method.
    pub method: Method,
    /// Anti-aliasing.
    pub aa: Aa,
}

impl Variant {
    fn new(family: &str, param: &str, method: Method, aa: Aa) -> Variant {
        Variant {
            family: family.to_string(),
            param: param.to_string(),
            method,
            aa,
        }
    }
}

/// The default sweep: point sampling at 16, 64 and 256 steps, the pixel
/// and beam methods, beam + grid:2 and grid:4, and beam + IAA (depth 2) at
/// thresholds 1 (every included pixel is smooth: geometry alone decides),
/// 1/4, 1/16 and 1/64.
pub fn default_variants() -> Vec<Variant> {
    let mut v = Vec::new();
    for steps in [16, 64, 256] {
        v.push(Variant::new(
            "point",
            &format!("steps={steps}"),
            Method::Point { steps },
            Aa::None,
        ));
    }
    v.push(Variant::new("pixel", "", Method::Pixel, Aa::None));
    v.push(Variant::new("beam", "", Method::Beam, Aa::None));
    for n in [2, 4] {
        v.push(Variant::new(
            "beam+grid",
            &format!("grid:{n}"),
            Method::Beam,
            Aa::Grid(n),
        ));
    }
    for d in [1u32, 4, 16, 64] {
        v.push(Variant::new(
            "beam+iaa",
            &format!("t=1/{d}"),
            Method::Beam,
            Aa::Iaa {
                threshold: 1.0 / f64::from(d),
                depth: crate::render::aa::DEFAULT_DEPTH,
            },
        ));
    }
    v
}

/// One line of `accuracy.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyRow {
    /// Scene name (file stem).
    pub scene: String,
    /// Series (`reference`, `point`, `pixel`, `beam`, `beam+grid`, `beam+iaa`).
    pub family: String,
    /// Parameter within the series.
    pub param: String,
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
pub const CSV_HEADER: &str = "scene,family,param,time_ms,rmse,max_abs,coverage_diff_pct,missed_surface,samples_mean,rays,pareto";

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
            let e =
                (out.linear[k][c].clamp(0.0, 1.0) - reference.linear[k][c].clamp(0.0, 1.0)).abs();
            sq += e * e;
            max_abs = max_abs.max(e);
        }
        let (rc, oc) = (reference.coverage[k], out.coverage[k]);
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

/// Renders `scene` with the reference and every variant at `size`²
/// (best of `repeats` timings each) and returns one row per render,
/// the reference first, with the Pareto front marked.
pub fn sweep_scene(
    name: &str,
    scene: &Scene,
    evaluators: &[Arc<dyn Evaluator>],
    size: u32,
    variants: &[Variant],
    repeats: u32,
) -> Result<Vec<AccuracyRow>, AccuracyError> {
    let run = |method: Method, aa: Aa, reps: u32| -> Result<RenderOutput, AccuracyError> {
        let mut opts = RenderOptions::new(size, size);
        opts.method = method;
        let mut best: Option<RenderOutput> = None;
        for _ in 0..reps.max(1) {
            let out = render_aa(scene, evaluators, &opts, aa)?;
            if best
                .as_ref()
                .is_none_or(|b| out.stats.time_ms < b.stats.time_ms)
            {
                best = Some(out);
            }
        }
        best.ok_or_else(|| AccuracyError::Scene("no render".into()))
    };
    let reference = run(REFERENCE.0, REFERENCE.1, 1)?;
    let centre = run(Method::Pixel, Aa::None, 1)?.hit_mask;
    let row = |family: &str, param: &str, out: &RenderOutput| {
        let e = compare(&reference, &centre, out);
        AccuracyRow {
            scene: name.to_string(),
            family: family.to_string(),
            param: param.to_string(),
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
    let mut rows = vec![row("reference", "pixel+grid:16", &reference)];
    for v in variants {
        let out = run(v.method, v.aa, repeats)?;
        rows.push(row(&v.family, &v.param, &out));
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
        rows.extend(sweep_scene(&name, &scene, &evals, size, &variants, 2)?);
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
            "{},{},{},{:.3},{:.6e},{:.6},{:.3},{},{:.3},{},{}\n",
            r.scene,
            r.family,
            r.param,
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

// The plot's text uses DejaVu Sans embedded in the binary (no system
// fonts needed).
fn register_font() -> Result<(), AccuracyError> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(AccuracyError::Plot("embedded font rejected".into()))
    }
}

const FAMILIES: [(&str, RGBColor); 5] = [
    ("point", RGBColor(214, 39, 40)),
    ("pixel", RGBColor(148, 103, 189)),
    ("beam", RGBColor(31, 119, 180)),
    ("beam+grid", RGBColor(255, 127, 14)),
    ("beam+iaa", RGBColor(44, 160, 44)),
];

// Errors of exactly 0 (a variant equal to the reference) are drawn here.
const RMSE_FLOOR: f64 = 1e-6;

/// Draws time (x) against RMSE (y), log-log, one panel per scene.
pub fn plot(rows: &[AccuracyRow], path: &Path) -> Result<(), AccuracyError> {
    register_font()?;
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let n = scenes.len().max(1) as u32;
    let cols = n.min(2);
    let rows_n = n.div_ceil(cols);
    let (pw, ph) = (760u32, 560u32);
    let (w, h) = (pw * cols, ph * rows_n);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let perr = |e: &dyn fmt::Display| AccuracyError::Plot(e.to_string());
        root.fill(&WHITE).map_err(|e| perr(&e))?;
        let panels = root.split_evenly((rows_n as usize, cols as usize));
        for (scene, area) in scenes.iter().zip(panels.iter()) {
            let pts: Vec<&AccuracyRow> = rows
                .iter()
                .filter(|r| r.scene == *scene && r.family != "reference")
                .collect();
            draw_panel(scene, &pts, area).map_err(|e| perr(&e))?;
        }
        root.present().map_err(|e| perr(&e))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf)
        .ok_or_else(|| AccuracyError::Plot("bad buffer".into()))?;
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| AccuracyError::Io(format!("cannot write {}: {e}", path.display())))
}

type Panel<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn draw_panel(
    scene: &str,
    pts: &[&AccuracyRow],
    area: &Panel<'_>,
) -> Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>> {
    let xy = |r: &AccuracyRow| (r.time_ms.max(1e-3), r.rmse.max(RMSE_FLOOR));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for r in pts {
        let (x, y) = xy(r);
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if pts.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1e-3, 1e-1);
    }
    // Margins in log space so the extreme points are not on the frame.
    let (x0, x1) = (x0 / 1.6, x1 * 1.6);
    let (y0, y1) = (y0 / 1.6, y1 * 1.6);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{scene}: render time vs error against the reference"),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("render time (ms, log)")
        .y_desc("RMSE of linear colour (log)")
        .x_labels(8)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for (fam, color) in FAMILIES {
        let mut series: Vec<&&AccuracyRow> = pts.iter().filter(|r| r.family == fam).collect();
        if series.is_empty() {
            continue;
        }
        series.sort_by(|a, b| a.time_ms.total_cmp(&b.time_ms));
        let line: Vec<(f64, f64)> = series.iter().map(|r| xy(r)).collect();
        chart
            .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))?
            .label(fam)
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (22, 0)], color.stroke_width(2))
                    + Circle::new((11, 0), 4, color.filled())
            });
        chart.draw_series(line.iter().map(|&p| Circle::new(p, 5, color.filled())))?;
        chart.draw_series(
            series
                .iter()
                .zip(&line)
                .filter(|(r, _)| !r.param.is_empty())
                .map(|(r, &p)| {
                    EmptyElement::at(p)
                        + Text::new(r.param.clone(), (7, -16), ("sans-serif", 12).into_font())
                }),
        )?;
    }
    // The Pareto front: ringed points joined by a dashed grey line.
    let mut front: Vec<(f64, f64)> = pts.iter().filter(|r| r.pareto).map(|r| xy(r)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(DashedLineSeries::new(
            front.clone(),
            6,
            4,
            RGBColor(90, 90, 90).stroke_width(1),
        ))?
        .label("Pareto front")
        .legend(|(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (22, 0)], RGBColor(90, 90, 90))
                + Circle::new((11, 0), 8, BLACK.stroke_width(2))
        });
    chart.draw_series(
        front
            .iter()
            .map(|&p| Circle::new(p, 9, BLACK.stroke_width(2))),
    )?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(t: f64, e: f64) -> AccuracyRow {
        AccuracyRow {
            scene: "s".into(),
            family: "beam".into(),
            param: String::new(),
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
    fn pareto_front_keeps_only_undominated_rows() {
        let mut rows = vec![r(1.0, 0.5), r(2.0, 0.1), r(3.0, 0.2), r(4.0, 0.05)];
        mark_pareto(&mut rows);
        let p: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(p, [true, true, false, true]);
    }
}
