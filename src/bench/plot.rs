//! The accuracy sweep's plot: render time against RMSE, log-log, one
//! panel per scene, each family a line, the Pareto front ringed.

use std::fmt;
use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::accuracy::{AccuracyError, AccuracyRow, Family};

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

// The plotted families, in legend order, with their colours.
const FAMILIES: [(Family, RGBColor); 5] = [
    (Family::Point, RGBColor(214, 39, 40)),
    (Family::Pixel, RGBColor(148, 103, 189)),
    (Family::Beam, RGBColor(31, 119, 180)),
    (Family::BeamGrid, RGBColor(255, 127, 14)),
    (Family::BeamIaa, RGBColor(44, 160, 44)),
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
                .filter(|r| r.scene == *scene && r.family != Family::Reference)
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

type Chart<'a> = ChartContext<'a, BitMapBackend<'a>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

type DrawResult<T> =
    Result<T, DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

/// Where a row is drawn: time and RMSE, kept off zero for the log axes.
fn xy(r: &AccuracyRow) -> (f64, f64) {
    (r.time_ms.max(1e-3), r.rmse.max(RMSE_FLOOR))
}

/// One scene's panel: a line per family, the Pareto front, the legend.
fn draw_panel(scene: &str, pts: &[&AccuracyRow], area: &Panel<'_>) -> DrawResult<()> {
    let mut chart = axes(scene, pts, area)?;
    for (family, color) in FAMILIES {
        draw_family(&mut chart, pts, family, color)?;
    }
    draw_pareto_front(&mut chart, pts)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(())
}

/// The panel's caption and log-log axes, wide enough for every point.
fn axes<'a>(scene: &str, pts: &[&AccuracyRow], area: &Panel<'a>) -> DrawResult<Chart<'a>> {
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
    Ok(chart)
}

/// One family's points, joined in order of time and labelled with their
/// parameters.
fn draw_family(
    chart: &mut Chart<'_>,
    pts: &[&AccuracyRow],
    family: Family,
    color: RGBColor,
) -> DrawResult<()> {
    let mut series: Vec<&&AccuracyRow> = pts.iter().filter(|r| r.family == family).collect();
    if series.is_empty() {
        return Ok(());
    }
    series.sort_by(|a, b| a.time_ms.total_cmp(&b.time_ms));
    let line: Vec<(f64, f64)> = series.iter().map(|r| xy(r)).collect();
    chart
        .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))?
        .label(family.name())
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
    Ok(())
}

/// The Pareto front: ringed points joined by a dashed grey line.
fn draw_pareto_front(chart: &mut Chart<'_>, pts: &[&AccuracyRow]) -> DrawResult<()> {
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
    Ok(())
}
