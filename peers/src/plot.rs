//! The sphere-union plot: render time against sphere count, log-log.

use std::path::Path;

use plotters::prelude::*;

/// One sphere count's best times (None: not measured).
#[derive(Clone, Debug)]
pub struct Point {
    /// Spheres in the union.
    pub n: usize,
    /// Fidget's best render, ms.
    pub fidget_ms: Option<f64>,
    /// ibeam's best render, ms.
    pub ibeam_ms: Option<f64>,
    /// ibeam's native code compile time, ms.
    pub ibeam_compile_ms: Option<f64>,
}

const FIDGET: RGBColor = RGBColor(31, 119, 180);
const IBEAM: RGBColor = RGBColor(214, 39, 40);
const COMPILE: RGBColor = RGBColor(255, 160, 120);

/// Draws the plot into `path`; Ok(false) if there is nothing to draw.
pub fn plot_spheres(points: &[Point], size: u32, path: &Path) -> Result<bool, String> {
    type Getter = fn(&Point) -> Option<f64>;
    let series: [(&str, RGBColor, Getter); 3] = [
        ("Fidget (voxels)", FIDGET, |p| p.fidget_ms),
        ("ibeam (beam tracing)", IBEAM, |p| p.ibeam_ms),
        ("ibeam compile (once)", COMPILE, |p| p.ibeam_compile_ms),
    ];
    let all: Vec<(f64, f64)> = points
        .iter()
        .flat_map(|p| {
            series
                .iter()
                .filter_map(move |s| s.2(p).map(|v| (p.n as f64, v)))
        })
        .filter(|&(_, v)| v.is_finite() && v > 0.0)
        .collect();
    if all.is_empty() {
        return Ok(false);
    }
    let fold = |f: fn(f64, f64) -> f64, init: f64, pick: fn(&(f64, f64)) -> f64| {
        all.iter().map(pick).fold(init, f)
    };
    let (x0, x1) = (
        fold(f64::min, f64::MAX, |p| p.0),
        fold(f64::max, 0.0, |p| p.0),
    );
    let (y0, y1) = (
        fold(f64::min, f64::MAX, |p| p.1),
        fold(f64::max, 0.0, |p| p.1),
    );
    let (x0, x1) = (x0 / 1.5, x1 * 1.5);
    let (y0, y1) = (y0 / 2.0, y1 * 2.0);

    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    let (w, h) = (800u32, 560u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let err = |e: &dyn std::fmt::Display| e.to_string();
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("Union of N spheres, {size}x{size} px, depth + normals"),
                ("sans-serif", 22),
            )
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("spheres (N)")
            .y_desc("ms per frame (best of reps)")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| err(&e))?;
        for (name, color, get) in series {
            let pts: Vec<(f64, f64)> = points
                .iter()
                .filter_map(|p| get(p).map(|v| (p.n as f64, v)))
                .filter(|&(_, v)| v.is_finite() && v > 0.0)
                .collect();
            if pts.is_empty() {
                continue;
            }
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2))
                });
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, color.filled())))
                .map_err(|e| err(&e))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).ok_or("bad plot buffer")?;
    img.save(path)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(true)
}
