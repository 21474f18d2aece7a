//! Charts with plotters: line/point panels, the regime map and heat maps, to
//! SVG or PNG (chosen by the file extension).
//!
//! Every chart is drawn once, as SVG; a PNG is that SVG rasterised by resvg
//! (anti-aliased) at [`PNG_SCALE`] times the nominal size. Text uses the
//! embedded DejaVu Sans in both steps (plotters' layout and resvg's glyphs),
//! so a PNG is the same on every machine. Axis-aligned rectangles (map cells,
//! colour bars) are drawn with `shape-rendering="crispEdges"` so that
//! abutting cells show no anti-aliasing seams.

use std::path::Path;
use std::sync::{Arc, Once};

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters_backend::{BackendCoord, DrawingErrorKind};

use crate::error::{CliError, CliResult};

static FONT: Once = Once::new();
const FONT_BYTES: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// PNG pixels per nominal (SVG) pixel.
pub const PNG_SCALE: f32 = 2.0;

/// Registers the embedded font for plotters' text layout (idempotent).
pub fn init_font() {
    FONT.call_once(|| {
        // The font is a fixed, known-good asset: failure here is a build defect.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_BYTES);
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, FONT_BYTES);
    });
}

/// A marker shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled triangle, point up.
    Triangle,
    /// Filled square.
    Square,
    /// Filled diamond.
    Diamond,
    /// Diagonal cross (stroke).
    Cross,
    /// Open circle (stroke).
    Ring,
    /// Open square (stroke).
    OpenSquare,
    /// Open triangle (stroke).
    OpenTriangle,
    /// Open diamond (stroke).
    OpenDiamond,
    /// A large open circle around a point (marks a chosen point).
    Highlight,
}

/// How a series is drawn (the legend sample is drawn the same way).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A polyline.
    Line,
    /// Dashed polyline.
    Dashed,
    /// Filled circles at the points.
    Points,
    /// Markers of one shape at the points.
    Markers(Marker),
    /// A polyline with markers at the points.
    LineMarkers(Marker),
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

/// A corner of a panel's plotting area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corner {
    /// Upper left.
    UpperLeft,
    /// Upper right.
    #[allow(dead_code)] // the full set of corners; the figures use two so far
    UpperRight,
    /// Lower left.
    #[allow(dead_code)]
    LowerLeft,
    /// Lower right.
    LowerRight,
}

/// What a panel shows beyond its series.
#[derive(Clone, Debug)]
pub struct Extras {
    /// Lines of text in a box inside the plotting area (fixed parameters, remarks).
    pub notes: Vec<String>,
    /// Where the notes go.
    pub notes_at: Corner,
    /// Where the legend goes.
    pub legend_at: Corner,
    /// Logarithmic x axis (the range must be positive).
    pub log_x: bool,
    /// Logarithmic y axis (the range must be positive).
    pub log_y: bool,
    /// Text beside points (data coordinates), e.g. a parameter value per point.
    pub labels: Vec<((f64, f64), String)>,
}

impl Default for Extras {
    fn default() -> Self {
        Extras {
            notes: Vec::new(),
            notes_at: Corner::UpperLeft,
            legend_at: Corner::LowerRight,
            log_x: false,
            log_y: false,
            labels: Vec::new(),
        }
    }
}

/// Panels on a grid, with an optional figure-wide legend and caption lines
/// under the grid.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Panels, row-major.
    pub panels: Vec<(Panel, Extras)>,
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Nominal size, pixels.
    pub size: (u32, u32),
    /// Legend entries shared by all panels (series with no points needed).
    pub legend: Vec<Series>,
    /// Caption lines under the panels.
    pub caption: Vec<String>,
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

/// Tick text on a logarithmic axis: plain numbers from 0.001 to 10 000,
/// powers of ten beyond.
pub fn log_axis_tick(v: f64) -> String {
    if v <= 0.0 {
        return String::new();
    }
    let e = v.log10();
    if (1e-3..=1e4).contains(&v) {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else if (e - e.round()).abs() < 1e-9 {
        format!("1e{}", e.round() as i64)
    } else {
        format!("{v:.0e}")
    }
}

/// The palette (colour-blind friendly: Okabe–Ito, then grey and dark red).
pub fn color(i: usize) -> RGBColor {
    const P: [RGBColor; 10] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(0, 0, 0),
        RGBColor(240, 228, 66),
        RGBColor(128, 128, 128),
        RGBColor(150, 30, 40),
    ];
    P[i % P.len()]
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

/// Checks an output directory before any work: it is created if missing, must
/// be a directory, and must accept a new file.
///
/// # Errors
/// Exit status 2 with a one-line message naming `--out`.
pub fn prepare_out_dir(out: &Path) -> CliResult {
    let bad = |what: String| CliError::usage(format!("--out: {}: {what}", out.display()));
    if out.exists() && !out.is_dir() {
        return Err(bad("exists and is not a directory".into()));
    }
    std::fs::create_dir_all(out).map_err(|e| bad(format!("cannot create the directory: {e}")))?;
    let probe = out.join(format!(".fricctl-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .map_err(|e| bad(format!("cannot write into the directory: {e}")))?;
    // The probe is ours and empty; failing to remove it leaves a harmless file.
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Draws a chart of `size` nominal pixels with `draw` and writes it to `path`
/// (`.svg` as drawn, `.png` rasterised, anti-aliased, at [`PNG_SCALE`]).
///
/// # Errors
/// A bad extension (exit 2); a drawing, rasterising or file error as one line
/// naming the file (exit 1).
pub fn write_chart<F>(path: &Path, size: (u32, u32), draw: F) -> CliResult
where
    F: FnOnce(
        &DrawingArea<SVGBackend<'_>, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<std::io::Error>>,
{
    init_font();
    let kind = ext(path)?;
    let fail = |what: &str, e: &dyn std::fmt::Display| {
        CliError::failure(format!("{}: {what}: {e}", path.display()))
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(&root).map_err(|e| fail("cannot draw", &e))?;
        root.present().map_err(|e| fail("cannot draw", &e))?;
    }
    let svg = svg.replace("<rect ", "<rect shape-rendering=\"crispEdges\" ");
    let bytes = if kind == "svg" {
        svg.into_bytes()
    } else {
        rasterise(&svg, size).map_err(|e| fail("cannot rasterise", &e))?
    };
    std::fs::write(path, bytes).map_err(|e| fail("cannot write", &e))
}

/// SVG text to PNG bytes at [`PNG_SCALE`], with only the embedded font.
fn rasterise(svg: &str, size: (u32, u32)) -> Result<Vec<u8>, String> {
    use resvg::{tiny_skia, usvg};
    let mut opt = usvg::Options::default();
    let mut db = usvg::fontdb::Database::new();
    db.load_font_data(FONT_BYTES.to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    opt.fontdb = Arc::new(db);
    let tree = usvg::Tree::from_str(svg, &opt).map_err(|e| e.to_string())?;
    let (w, h) = (
        (size.0 as f32 * PNG_SCALE).round() as u32,
        (size.1 as f32 * PNG_SCALE).round() as u32,
    );
    let mut pixmap =
        tiny_skia::Pixmap::new(w, h).ok_or_else(|| format!("bad image size {w} × {h}"))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(PNG_SCALE, PNG_SCALE),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().map_err(|e| e.to_string())
}

/// Renders panels on a `rows × cols` grid into `path` (`.svg` or `.png`).
pub fn render_panels(
    path: &Path,
    panels: &[Panel],
    rows: usize,
    cols: usize,
    size: (u32, u32),
) -> CliResult<()> {
    render_figure(
        path,
        &Figure {
            panels: panels
                .iter()
                .map(|p| (p.clone(), Extras::default()))
                .collect(),
            rows,
            cols,
            size,
            legend: Vec::new(),
            caption: Vec::new(),
        },
    )
}

/// Renders a [`Figure`] into `path` (`.svg` or `.png`).
pub fn render_figure(path: &Path, f: &Figure) -> CliResult<()> {
    write_chart(path, f.size, |root| draw_figure(root, f))
}

/// A marker of one shape at one point: an element of its own (no boxing, so
/// it is drawn the same in data and in pixel coordinates).
pub struct MarkerAt<C> {
    /// Where (data or pixel coordinates).
    pub at: C,
    /// Shape.
    pub marker: Marker,
    /// Colour.
    pub color: RGBColor,
    /// Radius, pixels.
    pub r: i32,
}

impl<'a, C> PointCollection<'a, C> for &'a MarkerAt<C> {
    type Point = &'a C;
    type IntoIter = std::iter::Once<&'a C>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<C, DB: DrawingBackend> Drawable<DB> for MarkerAt<C> {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        match pos.next() {
            Some(p) => draw_marker(backend, p, self.marker, self.color, self.r),
            None => Ok(()),
        }
    }
}

fn draw_marker<DB: DrawingBackend>(
    b: &mut DB,
    (x, y): BackendCoord,
    m: Marker,
    c: RGBColor,
    r: i32,
) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
    let (fill, stroke) = (c.filled(), c.stroke_width(2));
    let t = r + 1;
    // Equilateral triangle of circumradius t, point up, centred on (x, y).
    let tri = [
        (x, y - t),
        (x + t * 87 / 100, y + t / 2),
        (x - t * 87 / 100, y + t / 2),
    ];
    match m {
        Marker::Circle => b.draw_circle((x, y), r as u32, &fill, true),
        Marker::Triangle => b.fill_polygon(tri, &fill),
        Marker::Square => b.draw_rect((x - r, y - r), (x + r, y + r), &fill, true),
        Marker::Diamond => b.fill_polygon([(x, y - t), (x + t, y), (x, y + t), (x - t, y)], &fill),
        Marker::Cross => {
            b.draw_path([(x - r, y - r), (x + r, y + r)], &stroke)?;
            b.draw_path([(x - r, y + r), (x + r, y - r)], &stroke)
        }
        Marker::Ring => b.draw_circle((x, y), r as u32, &stroke, false),
        Marker::OpenSquare => b.draw_rect((x - r, y - r), (x + r, y + r), &stroke, false),
        Marker::OpenTriangle => b.draw_path([tri[0], tri[1], tri[2], tri[0]], &stroke),
        Marker::Highlight => b.draw_circle((x, y), 2 * r as u32 + 2, &BLACK.stroke_width(2), false),
        Marker::OpenDiamond => b.draw_path(
            [(x, y - t), (x + t, y), (x, y + t), (x - t, y), (x, y - t)],
            &stroke,
        ),
    }
}

/// Width of a legend sample, pixels.
const SAMPLE_W: i32 = 28;

/// The legend sample of a series drawn as `mark`, starting at pixel `at`:
/// the same line (solid, or dashed with the series' dash pattern) and marker.
pub struct Sample {
    /// Left end, pixels.
    pub at: BackendCoord,
    /// How the series is drawn.
    pub mark: Mark,
    /// Colour.
    pub color: RGBColor,
}

impl<'a> PointCollection<'a, BackendCoord> for &'a Sample {
    type Point = &'a BackendCoord;
    type IntoIter = std::iter::Once<&'a BackendCoord>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<DB: DrawingBackend> Drawable<DB> for Sample {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        b: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = pos.next() else {
            return Ok(());
        };
        let (c, mid) = (self.color, x + SAMPLE_W / 2);
        let stroke = c.stroke_width(2);
        match self.mark {
            Mark::Line => b.draw_path([(x, y), (x + SAMPLE_W, y)], &stroke),
            Mark::Dashed => {
                let step = (DASH.0 + DASH.1) as i32;
                let mut a = x;
                while a < x + SAMPLE_W {
                    let e = (a + DASH.0 as i32).min(x + SAMPLE_W);
                    b.draw_path([(a, y), (e, y)], &stroke)?;
                    a += step;
                }
                Ok(())
            }
            Mark::Points => draw_marker(b, (mid, y), Marker::Circle, c, 4),
            Mark::Markers(m) => draw_marker(b, (mid, y), m, c, 4),
            Mark::LineMarkers(m) => {
                b.draw_path([(x, y), (x + SAMPLE_W, y)], &stroke)?;
                draw_marker(b, (mid, y), m, c, 4)
            }
        }
    }
}

fn sample(mark: Mark, color: RGBColor) -> impl Fn(BackendCoord) -> Sample {
    move |at| Sample { at, mark, color }
}

fn marker_at<C>(marker: Marker, color: RGBColor) -> impl Fn(C) -> MarkerAt<C> {
    move |at| MarkerAt {
        at,
        marker,
        color,
        r: 4,
    }
}

/// Dash and gap of dashed series, pixels.
const DASH: (u32, u32) = (7, 5);

fn series_marker(mark: Mark) -> Option<Marker> {
    match mark {
        Mark::Points => Some(Marker::Circle),
        Mark::Markers(m) | Mark::LineMarkers(m) => Some(m),
        Mark::Line | Mark::Dashed => None,
    }
}

fn position(c: Corner) -> SeriesLabelPosition {
    match c {
        Corner::UpperLeft => SeriesLabelPosition::UpperLeft,
        Corner::UpperRight => SeriesLabelPosition::UpperRight,
        Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
        Corner::LowerRight => SeriesLabelPosition::LowerRight,
    }
}

const CAPTION_LINE: i32 = 22;
const LEGEND_LINE: i32 = 24;

/// Legend entries laid out in rows across `width`: (x, row) per entry.
fn legend_layout<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Series],
    width: i32,
) -> Vec<(i32, i32)> {
    let font = TextStyle::from(("sans-serif", 15).into_font());
    let (mut x, mut row) = (16, 0);
    let mut out = Vec::with_capacity(entries.len());
    for s in entries {
        let w = area
            .estimate_text_size(&s.label, &font)
            .map_or(8 * s.label.len() as i32, |(w, _)| w as i32)
            + SAMPLE_W
            + 34;
        if x + w > width && x > 16 {
            x = 16;
            row += 1;
        }
        out.push((x, row));
        x += w;
    }
    out
}

fn draw_figure<'a, DB: DrawingBackend + 'a>(
    root: &'a DrawingArea<DB, Shift>,
    f: &Figure,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (w, h) = root.dim_in_pixel();
    let layout = legend_layout(root, &f.legend, w as i32);
    let legend_rows = layout.last().map_or(0, |&(_, r)| r + 1);
    let footer = legend_rows * LEGEND_LINE + f.caption.len() as i32 * CAPTION_LINE;
    let footer = if footer > 0 { footer + 16 } else { 0 };
    let (grid, foot) = root.split_vertically(h as i32 - footer);
    let areas = grid.split_evenly((f.rows, f.cols));
    for (area, (p, e)) in areas.iter().zip(&f.panels) {
        let (x, y) = (p.x.0..p.x.1, p.y.0..p.y.1);
        match (e.log_x, e.log_y) {
            (false, false) => draw_panel(area, p, e, x, y)?,
            (true, false) => draw_panel(area, p, e, x.log_scale(), y)?,
            (false, true) => draw_panel(area, p, e, x, y.log_scale())?,
            (true, true) => draw_panel(area, p, e, x.log_scale(), y.log_scale())?,
        }
    }
    let font = ("sans-serif", 15).into_font();
    for (s, &(x, row)) in f.legend.iter().zip(&layout) {
        let y = 8 + row * LEGEND_LINE + LEGEND_LINE / 2;
        foot.draw(&sample(s.mark, color(s.color))((x, y)))?;
        foot.draw(&Text::new(
            s.label.as_str(),
            (x + SAMPLE_W + 8, y),
            font.color(&BLACK).pos(text_pos_left_center()),
        ))?;
    }
    let cap_font = ("sans-serif", 15).into_font();
    for (i, line) in f.caption.iter().enumerate() {
        let y = 8 + legend_rows * LEGEND_LINE + i as i32 * CAPTION_LINE;
        foot.draw(&Text::new(line.as_str(), (16, y), cap_font.color(&BLACK)))?;
    }
    Ok(())
}

fn text_pos_left_center() -> plotters::style::text_anchor::Pos {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    Pos::new(HPos::Left, VPos::Center)
}

/// Splits a series' points at non-finite values (gaps are not bridged).
fn segments(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut segs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for &(x, y) in points {
        if y.is_finite() && x.is_finite() {
            if let Some(s) = segs.last_mut() {
                s.push((x, y));
            }
        } else if segs.last().is_some_and(|s| !s.is_empty()) {
            segs.push(Vec::new());
        }
    }
    segs.retain(|s| !s.is_empty());
    segs
}

fn draw_panel<'a, DB, XR, YR>(
    area: &'a DrawingArea<DB, Shift>,
    p: &Panel,
    e: &Extras,
    xr: XR,
    yr: YR,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend + 'a,
    XR: AsRangedCoord<Value = f64>,
    YR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: ValueFormatter<f64>,
    YR::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 19))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(70)
        .build_cartesian_2d(xr, yr)?;
    let (lx, ly) = (e.log_x, e.log_y);
    let fx = move |v: &f64| if lx { log_axis_tick(*v) } else { tick(*v) };
    let fy = move |v: &f64| if ly { log_axis_tick(*v) } else { tick(*v) };
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .axis_desc_style(("sans-serif", 17))
        .label_style(("sans-serif", 14))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()?;
    let mut any_label = false;
    for s in &p.series {
        let c = color(s.color);
        let mark = s.mark;
        let mut drawn = false;
        for seg in segments(&s.points) {
            let anno = match mark {
                Mark::Line => chart.draw_series(LineSeries::new(seg, c.stroke_width(2)))?,
                Mark::LineMarkers(m) => {
                    chart.draw_series(LineSeries::new(seg.clone(), c.stroke_width(2)))?;
                    chart.draw_series(seg.into_iter().map(marker_at(m, c)))?
                }
                Mark::Dashed => chart.draw_series(DashedLineSeries::new(
                    seg,
                    DASH.0,
                    DASH.1,
                    c.stroke_width(2),
                ))?,
                Mark::Points | Mark::Markers(_) => {
                    let m = series_marker(mark).unwrap_or(Marker::Circle);
                    chart.draw_series(seg.into_iter().map(marker_at(m, c)))?
                }
            };
            if !drawn && !s.label.is_empty() {
                anno.label(s.label.as_str()).legend(sample(mark, c));
                any_label = true;
            }
            drawn = true;
        }
        if !drawn && !s.label.is_empty() {
            // A legend-only entry (no points).
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                .label(s.label.as_str())
                .legend(sample(mark, c));
            any_label = true;
        }
    }
    let label_font = ("sans-serif", 13).into_font();
    for (at, text) in &e.labels {
        chart.draw_series(std::iter::once(
            EmptyElement::at(*at) + Text::new(text.clone(), (6, -16), label_font.clone()),
        ))?;
    }
    if any_label {
        chart
            .configure_series_labels()
            .position(position(e.legend_at))
            .legend_area_size(SAMPLE_W + 10)
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .label_font(("sans-serif", 14))
            .draw()?;
    }
    if !e.notes.is_empty() {
        draw_notes(
            &chart.plotting_area().strip_coord_spec(),
            &e.notes,
            e.notes_at,
        )?;
    }
    Ok(())
}

/// Lines of text in a framed box at a corner of `area`.
fn draw_notes<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    notes: &[String],
    at: Corner,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = TextStyle::from(("sans-serif", 14).into_font());
    let line = 19;
    let width = notes
        .iter()
        .map(|n| {
            area.estimate_text_size(n, &font)
                .map_or(0, |(w, _)| w as i32)
        })
        .max()
        .unwrap_or(0)
        + 16;
    let height = line * notes.len() as i32 + 10;
    let (aw, ah) = area.dim_in_pixel();
    let (aw, ah) = (aw as i32, ah as i32);
    let (x0, y0) = match at {
        Corner::UpperLeft => (8, 8),
        Corner::UpperRight => (aw - width - 8, 8),
        Corner::LowerLeft => (8, ah - height - 8),
        Corner::LowerRight => (aw - width - 8, ah - height - 8),
    };
    area.draw(&Rectangle::new(
        [(x0, y0), (x0 + width, y0 + height)],
        WHITE.mix(0.9).filled(),
    ))?;
    area.draw(&Rectangle::new(
        [(x0, y0), (x0 + width, y0 + height)],
        RGBColor(160, 160, 160),
    ))?;
    for (i, n) in notes.iter().enumerate() {
        area.draw(&Text::new(
            n.as_str(),
            (x0 + 8, y0 + 6 + line * i as i32),
            font.clone(),
        ))?;
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
    write_chart(path, size, |root| draw_map(root, m))
}

fn half_step(v: &[f64]) -> f64 {
    if v.len() > 1 {
        (v[1] - v[0]) / 2.0
    } else {
        0.5
    }
}

fn draw_map<'a, DB: DrawingBackend + 'a>(
    root: &'a DrawingArea<DB, Shift>,
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
            DASH.0,
            DASH.1,
            BLACK.stroke_width(2),
        ))?;
        if !label.is_empty() {
            a.label(label.as_str()).legend(sample(Mark::Dashed, BLACK));
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .legend_area_size(SAMPLE_W + 10)
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
    write_chart(path, size, |root| draw_heat(root, m))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_plain_in_the_middle_and_powers_outside() {
        assert_eq!(log_axis_tick(0.5), "0.5");
        assert_eq!(log_axis_tick(100.0), "100");
        assert_eq!(log_axis_tick(1e-9), "1e-9");
        assert_eq!(log_axis_tick(2e-9), "2e-9");
    }

    #[test]
    fn segments_split_at_gaps() {
        let s = segments(&[(0.0, 1.0), (1.0, f64::NAN), (2.0, 2.0), (3.0, 3.0)]);
        assert_eq!(
            s,
            vec![vec![(0.0, 1.0)], vec![(2.0, 3.0 - 1.0), (3.0, 3.0)]]
        );
    }
}
