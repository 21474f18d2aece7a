//! Charts with plotters: line/point panels and the regime map, to SVG or PNG
//! (chosen by the file extension). Text uses the embedded DejaVu Sans, so PNGs
//! look the same on every machine.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::error::{CliError, CliResult};

static FONT: Once = Once::new();

/// Registers the embedded font for the bitmap backend (idempotent).
pub fn init_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        // The font is a fixed, known-good asset: failure here is a build defect.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, bytes);
    });
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A polyline.
    Line,
    /// Dashed polyline.
    Dashed,
    /// Circles at the points.
    Points,
}

/// One data series.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// Points; a NaN y breaks the line.
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub mark: Mark,
    /// Palette index.
    pub color: usize,
}

/// One chart panel.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// x-axis label (with units or normalisation).
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// x range.
    pub x: (f64, f64),
    /// y range.
    pub y: (f64, f64),
    /// Series.
    pub series: Vec<Series>,
}

/// Axis tick text: shortest of a few fixed precisions, never "-0".
fn tick(v: f64) -> String {
    let v = if v.abs() < 1e-12 { 0.0 } else { v };
    for prec in 0..6 {
        let s = format!("{v:.prec$}");
        if let Ok(back) = s.parse::<f64>() {
            if (back - v).abs() <= 1e-9 * v.abs().max(1e-300) {
                return s;
            }
        }
    }
    format!("{v:.3e}")
}

/// The palette (colour-blind friendly, Okabe–Ito).
pub fn color(i: usize) -> RGBColor {
    const P: [RGBColor; 8] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(0, 0, 0),
        RGBColor(240, 228, 66),
    ];
    P[i % P.len()]
}

fn draw_err<E: std::fmt::Debug>(path: &Path) -> impl Fn(E) -> CliError + '_ {
    move |e| CliError::failure(format!("{}: cannot draw: {e:?}", path.display()))
}

/// Renders panels on a `rows × cols` grid into `path` (`.svg` or `.png`).
pub fn render_panels(
    path: &Path,
    panels: &[Panel],
    rows: usize,
    cols: usize,
    size: (u32, u32),
) -> CliResult<()> {
    init_font();
    match ext(path)?.as_str() {
        "svg" => {
            let root = SVGBackend::new(path, size).into_drawing_area();
            draw_panels(&root, panels, rows, cols).map_err(draw_err(path))?;
            root.present().map_err(draw_err(path))
        }
        _ => {
            let root = BitMapBackend::new(path, size).into_drawing_area();
            draw_panels(&root, panels, rows, cols).map_err(draw_err(path))?;
            root.present().map_err(draw_err(path))
        }
    }
}

/// The file type from the extension (`svg` or `png`).
pub fn ext(path: &Path) -> CliResult<String> {
    let e = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if e == "svg" || e == "png" {
        Ok(e)
    } else {
        Err(CliError::usage(format!(
            "--plot: {}: the file name must end in .svg or .png",
            path.display()
        )))
    }
}

fn draw_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: &[Panel],
    rows: usize,
    cols: usize,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let areas = root.split_evenly((rows, cols));
    for (area, p) in areas.iter().zip(panels) {
        let mut chart = ChartBuilder::on(area)
            .caption(&p.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(p.x.0..p.x.1, p.y.0..p.y.1)?;
        chart
            .configure_mesh()
            .x_desc(p.x_label.as_str())
            .y_desc(p.y_label.as_str())
            .axis_desc_style(("sans-serif", 17))
            .label_style(("sans-serif", 14))
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(210, 210, 210))
            .draw()?;
        let mut any_label = false;
        for s in &p.series {
            let c = color(s.color);
            // Split at NaN so gaps are not bridged.
            let mut segs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for &(x, y) in &s.points {
                if y.is_finite() && x.is_finite() {
                    segs.last_mut().expect("non-empty").push((x, y));
                } else if !segs.last().expect("non-empty").is_empty() {
                    segs.push(Vec::new());
                }
            }
            if s.points.is_empty() && !s.label.is_empty() {
                any_label = true;
                let mark = s.mark;
                chart
                    .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                    .label(s.label.as_str())
                    .legend(move |(x, y)| match mark {
                        Mark::Points => Circle::new((x + 10, y), 4, c.filled()).into_dyn(),
                        _ => {
                            PathElement::new(vec![(x, y), (x + 8, y)], c.stroke_width(2)).into_dyn()
                        }
                    });
            }
            let mut first = true;
            for seg in segs.into_iter().filter(|s| !s.is_empty()) {
                let anno = match s.mark {
                    Mark::Line => chart.draw_series(LineSeries::new(seg, c.stroke_width(2)))?,
                    Mark::Dashed => {
                        chart.draw_series(DashedLineSeries::new(seg, 6, 4, c.stroke_width(2)))?
                    }
                    Mark::Points => {
                        chart.draw_series(seg.into_iter().map(|p| Circle::new(p, 3, c.filled())))?
                    }
                };
                if first && !s.label.is_empty() {
                    any_label = true;
                    let mark = s.mark;
                    anno.label(s.label.as_str())
                        .legend(move |(x, y)| match mark {
                            Mark::Points => Circle::new((x + 10, y), 4, c.filled()).into_dyn(),
                            _ => PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                                .into_dyn(),
                        });
                }
                first = false;
            }
        }
        if any_label {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(160, 160, 160))
                .label_font(("sans-serif", 13))
                .draw()?;
        }
    }
    Ok(())
}

/// A regime map: cells over (x, y) coloured by class, plus reference lines.
pub struct RegimeMap {
    /// Title.
    pub title: String,
    /// x label.
    pub x_label: String,
    /// y label.
    pub y_label: String,
    /// Cell centres' x values (uniform).
    pub xs: Vec<f64>,
    /// Cell centres' y values (uniform).
    pub ys: Vec<f64>,
    /// Class index per cell, row-major over `ys` then `xs` (0, 1, 2).
    pub class: Vec<u8>,
    /// Class names and colours.
    pub classes: [(&'static str, RGBColor); 3],
    /// Reference polylines (label, points), dashed black.
    pub lines: Vec<(String, Vec<(f64, f64)>)>,
    /// Exact measure-zero sets of class 0 (active control), drawn as thick lines
    /// in its colour (they have no area, so no cell centre falls on them).
    pub class0_lines: Vec<Vec<(f64, f64)>>,
}

/// Renders a [`RegimeMap`] to `.svg` or `.png`.
pub fn render_map(path: &Path, m: &RegimeMap, size: (u32, u32)) -> CliResult<()> {
    init_font();
    match ext(path)?.as_str() {
        "svg" => {
            let root = SVGBackend::new(path, size).into_drawing_area();
            draw_map(&root, m).map_err(draw_err(path))?;
            root.present().map_err(draw_err(path))
        }
        _ => {
            let root = BitMapBackend::new(path, size).into_drawing_area();
            draw_map(&root, m).map_err(draw_err(path))?;
            root.present().map_err(draw_err(path))
        }
    }
}

fn half_step(v: &[f64]) -> f64 {
    if v.len() > 1 {
        (v[1] - v[0]) / 2.0
    } else {
        0.5
    }
}

fn draw_map<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    m: &RegimeMap,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (hx, hy) = (half_step(&m.xs), half_step(&m.ys));
    let x0 = m.xs.first().copied().unwrap_or(0.0) - hx;
    let x1 = m.xs.last().copied().unwrap_or(1.0) + hx;
    let y0 = m.ys.first().copied().unwrap_or(0.0) - hy;
    let y1 = m.ys.last().copied().unwrap_or(1.0) + hy;
    let mut chart = ChartBuilder::on(root)
        .caption(&m.title, ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(66)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(m.x_label.as_str())
        .y_desc(m.y_label.as_str())
        .axis_desc_style(("sans-serif", 17))
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()?;
    let nx = m.xs.len();
    chart.draw_series(m.class.iter().enumerate().map(|(i, &k)| {
        let (x, y) = (m.xs[i % nx], m.ys[i / nx]);
        let c = m.classes[usize::from(k.min(2))].1;
        Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], c.filled())
    }))?;
    // Legend entries for the classes (drawn as invisible series with a legend).
    for (name, c) in m.classes {
        chart
            .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())?
            .label(name)
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], c.filled()));
    }
    let c0 = m.classes[0].1;
    for pts in &m.class0_lines {
        chart.draw_series(LineSeries::new(pts.clone(), c0.stroke_width(5)))?;
    }
    for (label, pts) in &m.lines {
        let a = chart.draw_series(DashedLineSeries::new(
            pts.clone(),
            8,
            5,
            BLACK.stroke_width(2),
        ))?;
        if !label.is_empty() {
            a.label(label.as_str()).legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2))
            });
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(())
}

/// One heat-map cell: a value on the colour scale, or a named class (e.g. a
/// failure kind) drawn in its own colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Heat {
    /// A value (clamped to the colour range for drawing only).
    Value(f64),
    /// Index into [`HeatMap::classes`].
    Class(usize),
}

/// Cells over a grid coloured by value (viridis) or class, with a colour bar.
/// Axes may be logarithmic: the cell centres are then given as log10 values
/// and the ticks are written as powers of ten.
pub struct HeatMap {
    /// Title.
    pub title: String,
    /// x label.
    pub x_label: String,
    /// y label.
    pub y_label: String,
    /// Cell centres along x (uniform; log10 values if `log_x`).
    pub xs: Vec<f64>,
    /// Cell centres along y (uniform; log10 values if `log_y`).
    pub ys: Vec<f64>,
    /// Whether x is log10.
    pub log_x: bool,
    /// Whether y is log10.
    pub log_y: bool,
    /// Cells, row-major over `ys` then `xs`.
    pub cells: Vec<Heat>,
    /// Colour range of the values.
    pub range: (f64, f64),
    /// Label of the colour bar.
    pub value_label: String,
    /// Named classes with their colours (legend).
    pub classes: Vec<(String, RGBColor)>,
}

fn viridis(t: f64) -> RGBColor {
    use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};
    ViridisRGB.get_color(t.clamp(0.0, 1.0))
}

/// Renders a [`HeatMap`] to `.svg` or `.png`.
pub fn render_heat(path: &Path, m: &HeatMap, size: (u32, u32)) -> CliResult<()> {
    init_font();
    match ext(path)?.as_str() {
        "svg" => {
            let root = SVGBackend::new(path, size).into_drawing_area();
            draw_heat(&root, m).map_err(draw_err(path))?;
            root.present().map_err(draw_err(path))
        }
        _ => {
            let root = BitMapBackend::new(path, size).into_drawing_area();
            draw_heat(&root, m).map_err(draw_err(path))?;
            root.present().map_err(draw_err(path))
        }
    }
}

fn log_tick(v: f64, log: bool) -> String {
    if log {
        if (v - v.round()).abs() < 1e-9 {
            format!("1e{}", v.round() as i64)
        } else {
            String::new()
        }
    } else {
        tick(v)
    }
}

fn draw_heat<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    m: &HeatMap,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (w, _) = root.dim_in_pixel();
    let (main, bar) = root.split_horizontally(w.saturating_sub(130));
    let (hx, hy) = (half_step(&m.xs), half_step(&m.ys));
    let x0 = m.xs.first().copied().unwrap_or(0.0) - hx;
    let x1 = m.xs.last().copied().unwrap_or(1.0) + hx;
    let y0 = m.ys.first().copied().unwrap_or(0.0) - hy;
    let y1 = m.ys.last().copied().unwrap_or(1.0) + hy;
    let mut chart = ChartBuilder::on(&main)
        .caption(&m.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(66)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let (lx, ly) = (m.log_x, m.log_y);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(m.x_label.as_str())
        .y_desc(m.y_label.as_str())
        .axis_desc_style(("sans-serif", 16))
        .label_style(("sans-serif", 13))
        .x_labels(12)
        .y_labels(12)
        .x_label_formatter(&|v| log_tick(*v, lx))
        .y_label_formatter(&|v| log_tick(*v, ly))
        .draw()?;
    let nx = m.xs.len().max(1);
    let (lo, hi) = m.range;
    let span = if hi > lo { hi - lo } else { 1.0 };
    chart.draw_series(m.cells.iter().enumerate().map(|(i, h)| {
        let (x, y) = (m.xs[i % nx], m.ys[i / nx]);
        let c = match *h {
            Heat::Value(v) => viridis((v - lo) / span),
            Heat::Class(k) => m.classes.get(k).map(|c| c.1).unwrap_or(RGBColor(0, 0, 0)),
        };
        Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], c.filled())
    }))?;
    for (name, c) in &m.classes {
        let c = *c;
        chart
            .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())?
            .label(name.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], c.filled()));
    }
    if !m.classes.is_empty() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()?;
    }
    // Colour bar.
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(40)
        .margin_bottom(62)
        .margin_right(8)
        .y_label_area_size(48)
        .caption(&m.value_label, ("sans-serif", 13))
        .build_cartesian_2d(0.0..1.0, lo..lo + span)?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .label_style(("sans-serif", 12))
        .y_label_formatter(&|v| tick(*v))
        .draw()?;
    let steps = 100;
    cb.draw_series((0..steps).map(|i| {
        let a = lo + span * i as f64 / steps as f64;
        let b = lo + span * (i + 1) as f64 / steps as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            viridis(i as f64 / (steps - 1) as f64).filled(),
        )
    }))?;
    Ok(())
}
