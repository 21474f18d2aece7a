//! Charts with plotters: line/point panels, the regime map and heat maps, to
//! SVG or PNG (chosen by the file extension).
//!
//! Every chart is drawn once, as SVG; a PNG is that SVG rasterised by resvg
//! (anti-aliased) at [`PNG_SCALE`] times the nominal size. Text uses the
//! embedded DejaVu Sans in both steps (plotters' layout and resvg's glyphs),
//! so a PNG is the same on every machine. Axis-aligned rectangles (map cells,
//! colour bars) are drawn with `shape-rendering="crispEdges"` so that
//! abutting cells show no anti-aliasing seams.
//!
//! **Sub-pixel curves.** plotters hands its backends whole pixels
//! (`BackendCoord = (i32, i32)`), so a smooth curve drawn through it is a
//! staircase. Curves (line and dashed series, the maps' reference lines) are
//! therefore drawn with [`fine_line`]: plotters draws the polyline in a
//! one-off marker colour (so it keeps its place in the drawing order), and
//! [`write_chart`] replaces that polyline in the SVG by one through the
//! points' exact pixel positions (same mapping as plotters, without the
//! rounding), clipped to the plotting area.

use std::cell::RefCell;
use std::fmt::Write as _;
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

/// From data coordinates of one chart to SVG pixels, without rounding: the
/// mapping of plotters' `Cartesian2d` (x from the plotting area's left pixel
/// to its right pixel − 1, y from its bottom pixel − 1 up to its top), on a
/// linear or a logarithmic axis.
#[derive(Clone, Copy, Debug)]
pub struct PixelMap {
    px: (f64, f64),
    py: (f64, f64),
    x: (f64, f64, bool),
    y: (f64, f64, bool),
}

impl PixelMap {
    /// The map of a chart whose plotting area is `area` (as
    /// `chart.plotting_area()`), axes `x` and `y` (value ranges; `true` for
    /// a logarithmic axis).
    pub fn of<DB: DrawingBackend, CT: plotters::coord::CoordTranslate>(
        area: &DrawingArea<DB, CT>,
        x: (f64, f64, bool),
        y: (f64, f64, bool),
    ) -> Self {
        let (rx, ry) = area.get_pixel_range();
        PixelMap {
            px: (f64::from(rx.start), f64::from(rx.end - 1)),
            py: (f64::from(ry.end - 1), f64::from(ry.start)),
            x,
            y,
        }
    }

    fn axis(v: f64, (lo, hi, log): (f64, f64, bool), (p0, p1): (f64, f64)) -> f64 {
        let t = if log {
            (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            (v - lo) / (hi - lo)
        };
        p0 + (p1 - p0) * t
    }

    /// The pixel position of a data point.
    pub fn map(&self, (x, y): (f64, f64)) -> (f64, f64) {
        (
            Self::axis(x, self.x, self.px),
            Self::axis(y, self.y, self.py),
        )
    }

    /// The plotting area, pixels: (left, top, width, height).
    fn clip(&self) -> (f64, f64, f64, f64) {
        (
            self.px.0,
            self.py.1,
            self.px.1 - self.px.0 + 1.0,
            self.py.0 - self.py.1 + 1.0,
        )
    }
}

/// A curve to be written with exact pixel positions (see the module doc).
struct FineLine {
    /// The marker colour plotters drew it in (`#01xxxx`).
    marker: String,
    color: RGBColor,
    width: u32,
    dash: Option<&'static [u32]>,
    points: Vec<(f64, f64)>,
    clip: (f64, f64, f64, f64),
}

thread_local! {
    /// The curves of the chart being drawn (emptied by [`write_chart`]).
    static FINE: RefCell<Vec<FineLine>> = const { RefCell::new(Vec::new()) };
}

/// Registers the curve through `points` (data coordinates of the chart that
/// `map` describes) and returns the marker colour to draw it in with
/// plotters (a `LineSeries` of the same points and `width`).
pub fn fine_line(
    map: &PixelMap,
    points: &[(f64, f64)],
    color: RGBColor,
    width: u32,
    dash: Option<&'static [u32]>,
) -> RGBColor {
    FINE.with(|f| {
        let mut f = f.borrow_mut();
        let k = f.len();
        let marker = RGBColor(1, 0x20 + (k >> 8) as u8, (k & 0xff) as u8);
        f.push(FineLine {
            marker: format!("#{:02X}{:02X}{:02X}", marker.0, marker.1, marker.2),
            color,
            width,
            dash,
            points: points.iter().map(|&p| map.map(p)).collect(),
            clip: map.clip(),
        });
        marker
    })
}

/// A minus sign (U+2212) for each hyphen-minus of `s` that stands for one:
/// before a digit or a point, after nothing, a space, a bracket, `=`, `/`,
/// `(`, or the `e` of an exponent (`1e-3`).
pub fn minus(s: &str) -> String {
    let c: Vec<char> = s.chars().collect();
    let mut out = String::with_capacity(s.len() + 4);
    for (i, &ch) in c.iter().enumerate() {
        let next_num = c
            .get(i + 1)
            .is_some_and(|n| n.is_ascii_digit() || *n == '.');
        let prev = if i > 0 { Some(c[i - 1]) } else { None };
        let exponent = prev == Some('e') && i >= 2 && c[i - 2].is_ascii_digit();
        let after_sep = prev.is_none_or(|p| p.is_whitespace() || "([{=/,:;≤≥<>…±".contains(p));
        if ch == '-' && next_num && (after_sep || exponent) {
            out.push('−');
        } else {
            out.push(ch);
        }
    }
    out
}

/// Typesets the text content of an SVG `<text>` element: minus signs
/// ([`minus`]) and subscripts — `x_{abc}`, `x_ab` (one to three letters,
/// digits or ±), and `μ0`, `W0`, `v0` as μ₀, W₀, v₀ — as `<tspan>`s shifted
/// to the baseline's subscript position at 70 % of `size`.
fn typeset_text(t: &str, size: f64) -> String {
    let t = minus(t);
    let c: Vec<char> = t.chars().collect();
    let sub = |s: &str| {
        format!(
            "<tspan baseline-shift=\"-{:.1}\" font-size=\"{:.1}\">{s}</tspan>",
            0.22 * size,
            0.7 * size
        )
    };
    let mut out = String::with_capacity(t.len() + 32);
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        let prev_letter = i > 0 && (c[i - 1].is_alphabetic() || c[i - 1] == ')');
        if ch == '_' && prev_letter {
            if c.get(i + 1) == Some(&'{') {
                if let Some(end) = c[i + 2..].iter().position(|&x| x == '}') {
                    out.push_str(&sub(&c[i + 2..i + 2 + end].iter().collect::<String>()));
                    i += end + 3;
                    continue;
                }
            }
            let n = c[i + 1..]
                .iter()
                .take_while(|x| x.is_ascii_alphanumeric() || **x == '±')
                .count();
            if (1..=3).contains(&n) {
                out.push_str(&sub(&c[i + 1..i + 1 + n].iter().collect::<String>()));
                i += n + 1;
                continue;
            }
        }
        // μ0, W0, v0 as words of their own.
        if ch == '0'
            && i > 0
            && "μWv".contains(c[i - 1])
            && (i < 2 || !c[i - 2].is_ascii_alphanumeric())
            && c.get(i + 1)
                .is_none_or(|n| !n.is_alphanumeric() || (c[i - 1] == 'μ' && !n.is_ascii_digit()))
        {
            out.push_str(&sub("0"));
            i += 1;
            continue;
        }
        out.push(ch);
        i += 1;
    }
    out
}

/// [`typeset_text`] on every `<text>` element of an SVG.
fn typeset(svg: &str) -> String {
    let mut out = String::with_capacity(svg.len() + svg.len() / 8);
    let mut rest = svg;
    while let Some(open) = rest.find("<text") {
        let Some(gt) = rest[open..].find('>').map(|g| open + g + 1) else {
            break;
        };
        let Some(close) = rest[gt..].find("</text>").map(|c| gt + c) else {
            break;
        };
        let tag = &rest[open..gt];
        let size = tag
            .split("font-size=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(14.0);
        out.push_str(&rest[..gt]);
        out.push_str(&typeset_text(&rest[gt..close], size));
        rest = &rest[close..];
    }
    out.push_str(rest);
    out
}

/// [`fine_line`] for a polyline given in absolute SVG pixels (e.g. the caps
/// of an error bar), clipped to `map`'s plotting area.
pub fn fine_pixels(map: &PixelMap, points: &[(f64, f64)], color: RGBColor, width: u32) -> RGBColor {
    FINE.with(|f| {
        let mut f = f.borrow_mut();
        let k = f.len();
        let marker = RGBColor(1, 0x20 + (k >> 8) as u8, (k & 0xff) as u8);
        f.push(FineLine {
            marker: format!("#{:02X}{:02X}{:02X}", marker.0, marker.1, marker.2),
            color,
            width,
            dash: None,
            points: points.to_vec(),
            clip: map.clip(),
        });
        marker
    })
}

/// Replaces each marker-coloured polyline of `svg` by its exact curve.
fn refine(svg: &str, lines: &[FineLine]) -> String {
    let mut out = svg.to_string();
    let mut defs = String::new();
    for (i, l) in lines.iter().enumerate() {
        let key = format!("stroke=\"{}\"", l.marker);
        // plotters may split a series into several polylines: replace each.
        while let Some(at) = out.find(&key) {
            let start = out[..at].rfind("<polyline").unwrap_or(at);
            let end = out[at..].find("/>").map_or(out.len(), |e| at + e + 2);
            let mut pts = String::new();
            for (x, y) in &l.points {
                let _ = write!(pts, "{x:.2},{y:.2} ");
            }
            let dash = l
                .dash
                .map(|d| {
                    let d: Vec<String> = d.iter().map(u32::to_string).collect();
                    format!(" stroke-dasharray=\"{}\"", d.join(" "))
                })
                .unwrap_or_default();
            let new = format!(
                "<polyline fill=\"none\" stroke=\"#{:02X}{:02X}{:02X}\" stroke-width=\"{}\" stroke-linejoin=\"round\"{dash} clip-path=\"url(#fine{i})\" points=\"{}\"/>",
                l.color.0,
                l.color.1,
                l.color.2,
                l.width,
                pts.trim_end()
            );
            // Only the first piece carries the curve; further pieces go.
            let new = if out[..start].contains(&format!("url(#fine{i})")) {
                String::new()
            } else {
                new
            };
            out.replace_range(start..end, &new);
        }
        let (x, y, w, h) = l.clip;
        let _ = write!(
            defs,
            "<clipPath id=\"fine{i}\"><rect x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\"/></clipPath>"
        );
    }
    if !defs.is_empty() {
        if let Some(p) = out.find('>').filter(|_| out.starts_with("<svg")) {
            out.insert_str(p + 1, &format!("\n<defs>{defs}</defs>"));
        } else if let Some(p) = out
            .find("<svg")
            .and_then(|s| out[s..].find('>').map(|e| s + e))
        {
            out.insert_str(p + 1, &format!("\n<defs>{defs}</defs>"));
        }
    }
    out
}

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
    /// Vertical error bars: (x, low y, high y, colour index).
    pub error_bars: Vec<(f64, f64, f64, usize)>,
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
            error_bars: Vec::new(),
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
    FINE.with(|f| f.borrow_mut().clear());
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(&root).map_err(|e| fail("cannot draw", &e))?;
        root.present().map_err(|e| fail("cannot draw", &e))?;
    }
    let fine = FINE.with(|f| std::mem::take(&mut *f.borrow_mut()));
    let svg = typeset(&refine(&svg, &fine));
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

/// Dash patterns of a regime map's reference lines (dash, gap, …; pixels):
/// dashed, dotted, dash-dotted.
const MAP_DASHES: [&[u32]; 3] = [&[9, 5], &[2, 4], &[12, 4, 2, 4]];

/// A legend sample of a black line with a dash pattern, starting at `at`.
struct DashSample {
    at: BackendCoord,
    pattern: &'static [u32],
}

impl<'a> PointCollection<'a, BackendCoord> for &'a DashSample {
    type Point = &'a BackendCoord;
    type IntoIter = std::iter::Once<&'a BackendCoord>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<DB: DrawingBackend> Drawable<DB> for DashSample {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        b: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = pos.next() else {
            return Ok(());
        };
        let stroke = BLACK.stroke_width(2);
        let (mut a, mut k) = (x, 0);
        while a < x + SAMPLE_W {
            let len = self.pattern[k % self.pattern.len()] as i32;
            if k % 2 == 0 {
                b.draw_path([(a, y), ((a + len).min(x + SAMPLE_W), y)], &stroke)?;
            }
            a += len;
            k += 1;
        }
        Ok(())
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
    let pm = PixelMap::of(
        chart.plotting_area(),
        (p.x.0, p.x.1, lx),
        (p.y.0, p.y.1, ly),
    );
    let fine = |seg: &[(f64, f64)], c: RGBColor, dash| fine_line(&pm, seg, c, 2, dash);
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
    // Error bars first (under the points): x, low end, high end, colour index.
    for &(x, lo, hi, ci) in &e.error_bars {
        let k = fine_line(&pm, &[(x, lo), (x, hi)], color(ci), 1, None);
        chart.draw_series(LineSeries::new([(x, lo), (x, hi)], k.stroke_width(1)))?;
        for y in [lo, hi] {
            let (px, py) = pm.map((x, y));
            let cap = [(px - 4.0, py), (px + 4.0, py)];
            let k = fine_pixels(&pm, &cap, color(ci), 1);
            chart
                .plotting_area()
                .strip_coord_spec()
                .draw(&PathElement::new(vec![(0, 0), (1, 0)], k.stroke_width(1)))?;
        }
    }
    let any_label = p.series.iter().any(|s| !s.label.is_empty());
    for s in &p.series {
        let c = color(s.color);
        let mark = s.mark;
        for seg in segments(&s.points) {
            match mark {
                Mark::Line => {
                    let k = fine(&seg, c, None);
                    chart.draw_series(LineSeries::new(seg, k.stroke_width(2)))?
                }
                Mark::LineMarkers(m) => {
                    let k = fine(&seg, c, None);
                    chart.draw_series(LineSeries::new(seg.clone(), k.stroke_width(2)))?;
                    chart.draw_series(seg.into_iter().map(marker_at(m, c)))?
                }
                Mark::Dashed => {
                    let k = fine(&seg, c, Some(&[DASH.0, DASH.1]));
                    chart.draw_series(LineSeries::new(seg, k.stroke_width(2)))?
                }
                Mark::Points | Mark::Markers(_) => {
                    let m = series_marker(mark).unwrap_or(Marker::Circle);
                    chart.draw_series(seg.into_iter().map(marker_at(m, c)))?
                }
            };
        }
    }
    let label_font = ("sans-serif", 13).into_font();
    for (at, text) in &e.labels {
        chart.draw_series(std::iter::once(
            EmptyElement::at(*at) + Text::new(text.clone(), (6, -16), label_font.clone()),
        ))?;
    }
    // The legend and the notes: framed boxes placed where no data is (the
    // preferred corner first, then the others), so that no box hides a point.
    let area = chart.plotting_area().strip_coord_spec();
    let (rx, ry) = area.get_pixel_range();
    let dots = occupied(p, &pm, (rx.start, ry.start));
    let dims = (rx.end - rx.start, ry.end - ry.start);
    let mut taken = Vec::new();
    if any_label {
        let entries: Vec<&Series> = p.series.iter().filter(|s| !s.label.is_empty()).collect();
        let size = legend_size(&area, &entries);
        let at = place(dims, size, e.legend_at, &taken, &dots);
        draw_legend(&area, &entries, at, size)?;
        taken.push((at, size));
    }
    if !e.notes.is_empty() {
        let size = notes_size(&area, &e.notes);
        let at = place(dims, size, e.notes_at, &taken, &dots);
        draw_notes(&area, &e.notes, at, size)?;
    }
    Ok(())
}

/// Pixels (relative to the plotting area's corner `origin`) that the panel's
/// data cover: every point, and along lines every 3 px between points.
fn occupied(p: &Panel, pm: &PixelMap, origin: (i32, i32)) -> Vec<(f64, f64)> {
    let (ox, oy) = (f64::from(origin.0), f64::from(origin.1));
    let mut out = Vec::new();
    for s in &p.series {
        let line = matches!(s.mark, Mark::Line | Mark::Dashed | Mark::LineMarkers(_));
        for seg in segments(&s.points) {
            let px: Vec<(f64, f64)> = seg
                .iter()
                .map(|&q| pm.map(q))
                .map(|(x, y)| (x - ox, y - oy))
                .collect();
            for (i, &a) in px.iter().enumerate() {
                out.push(a);
                if let (true, Some(&b)) = (line, px.get(i + 1)) {
                    let d = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
                    let n = (d / 3.0).ceil().min(2000.0) as usize;
                    for k in 1..n {
                        let t = k as f64 / n as f64;
                        out.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
                    }
                }
            }
        }
    }
    out
}

/// The top-left corner of a `size` box in a `dims` area: the first of the
/// preferred corner, the other corners and the edges' midpoints where no
/// point of `dots` (with a 4 px margin) and no `taken` box lies; if there
/// is none, the candidate covering the fewest points.
/// A box: top-left corner and size, pixels.
type PixelBox = ((i32, i32), (i32, i32));

fn place(
    dims: (i32, i32),
    size: (i32, i32),
    preferred: Corner,
    taken: &[PixelBox],
    dots: &[(f64, f64)],
) -> (i32, i32) {
    let (aw, ah) = dims;
    let (w, h) = size;
    let m = 8;
    let corner = |c: Corner| match c {
        Corner::UpperLeft => (m, m),
        Corner::UpperRight => (aw - w - m, m),
        Corner::LowerLeft => (m, ah - h - m),
        Corner::LowerRight => (aw - w - m, ah - h - m),
    };
    let mut cands = vec![corner(preferred)];
    for c in [
        Corner::UpperLeft,
        Corner::UpperRight,
        Corner::LowerRight,
        Corner::LowerLeft,
    ] {
        cands.push(corner(c));
    }
    cands.extend([
        ((aw - w) / 2, m),
        ((aw - w) / 2, ah - h - m),
        (m, (ah - h) / 2),
        (aw - w - m, (ah - h) / 2),
    ]);
    let overlaps = |(x, y): (i32, i32)| {
        taken.iter().any(|&((tx, ty), (tw, th))| {
            x < tx + tw + 4 && tx < x + w + 4 && y < ty + th + 4 && ty < y + h + 4
        })
    };
    let covered = |(x, y): (i32, i32)| {
        let (x0, y0, x1, y1) = (
            f64::from(x - 4),
            f64::from(y - 4),
            f64::from(x + w + 4),
            f64::from(y + h + 4),
        );
        dots.iter()
            .filter(|&&(px, py)| px >= x0 && px <= x1 && py >= y0 && py <= y1)
            .count()
    };
    let free: Vec<(i32, i32)> = cands.iter().copied().filter(|&c| !overlaps(c)).collect();
    free.iter()
        .copied()
        .find(|&c| covered(c) == 0)
        .or_else(|| free.iter().copied().min_by_key(|&c| covered(c)))
        .unwrap_or(cands[0])
}

/// Legend rows, pixels.
const LEGEND_ROW: i32 = 20;

fn legend_size<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[&Series],
) -> (i32, i32) {
    let font = TextStyle::from(("sans-serif", 14).into_font());
    let text = entries
        .iter()
        .map(|s| {
            area.estimate_text_size(&s.label, &font)
                .map_or(8 * s.label.chars().count() as i32, |(w, _)| w as i32)
        })
        .max()
        .unwrap_or(0);
    (text + SAMPLE_W + 26, LEGEND_ROW * entries.len() as i32 + 8)
}

/// A framed legend at `at` (top-left, relative to `area`): each entry's
/// sample (line, dashes, marker as drawn) and label.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[&Series],
    (x0, y0): (i32, i32),
    (w, h): (i32, i32),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    area.draw(&Rectangle::new(
        [(x0, y0), (x0 + w, y0 + h)],
        WHITE.mix(0.9).filled(),
    ))?;
    area.draw(&Rectangle::new(
        [(x0, y0), (x0 + w, y0 + h)],
        RGBColor(160, 160, 160),
    ))?;
    let font = ("sans-serif", 14).into_font();
    for (i, s) in entries.iter().enumerate() {
        let y = y0 + 4 + LEGEND_ROW * i as i32 + LEGEND_ROW / 2;
        area.draw(&sample(s.mark, color(s.color))((x0 + 8, y)))?;
        area.draw(&Text::new(
            s.label.as_str(),
            (x0 + 8 + SAMPLE_W + 8, y),
            font.color(&BLACK).pos(text_pos_left_center()),
        ))?;
    }
    Ok(())
}

/// Notes lines, pixels.
const NOTES_LINE: i32 = 19;

fn notes_size<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, notes: &[String]) -> (i32, i32) {
    let font = TextStyle::from(("sans-serif", 14).into_font());
    let width = notes
        .iter()
        .map(|n| {
            area.estimate_text_size(n, &font)
                .map_or(0, |(w, _)| w as i32)
        })
        .max()
        .unwrap_or(0)
        + 16;
    (width, NOTES_LINE * notes.len() as i32 + 10)
}

/// Lines of text in a framed box of `size` at `(x0, y0)` of `area`.
fn draw_notes<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    notes: &[String],
    (x0, y0): (i32, i32),
    (width, height): (i32, i32),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = TextStyle::from(("sans-serif", 14).into_font());
    let line = NOTES_LINE;
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
    // The map fills its plotting area: the legend goes under it.
    let (_, h) = root.dim_in_pixel();
    let (root, foot) = root.split_vertically(h as i32 - 40);
    let root = &root;
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
    let pm = PixelMap::of(chart.plotting_area(), (x0, x1, false), (y0, y1, false));
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
    let c0 = m.classes[0].1;
    for pts in &m.class0_lines {
        let k = fine_line(&pm, pts, c0, 5, None);
        chart.draw_series(LineSeries::new(pts.clone(), k.stroke_width(5)))?;
    }
    // Each labelled reference line its own dash pattern (the legend shows
    // it); an unlabelled line continues the labelled one before it.
    let pattern_of = |i: usize| {
        let k = m.lines[..=i].iter().filter(|(l, _)| !l.is_empty()).count();
        MAP_DASHES[k.saturating_sub(1) % MAP_DASHES.len()]
    };
    for (i, (_, pts)) in m.lines.iter().enumerate() {
        let pattern = pattern_of(i);
        let k = fine_line(&pm, pts, BLACK, 2, Some(pattern));
        chart.draw_series(LineSeries::new(pts.clone(), k.stroke_width(2)))?;
    }
    // The legend, one row under the map: the classes, then the lines.
    let font = TextStyle::from(("sans-serif", 14).into_font());
    let text_w = |s: &str| {
        foot.estimate_text_size(s, &font)
            .map_or(8 * s.chars().count() as i32, |(w, _)| w as i32)
    };
    let (mut x, y) = (16, 20);
    for (name, c) in m.classes {
        foot.draw(&Rectangle::new([(x, y - 6), (x + 16, y + 6)], c.filled()))?;
        foot.draw(&Text::new(
            name,
            (x + 22, y),
            font.color(&BLACK).pos(text_pos_left_center()),
        ))?;
        x += 22 + text_w(name) + 24;
    }
    for (i, (label, _)) in m.lines.iter().enumerate() {
        if label.is_empty() {
            continue;
        }
        let pattern = pattern_of(i);
        foot.draw(&DashSample {
            at: (x, y),
            pattern,
        })?;
        foot.draw(&Text::new(
            label.as_str(),
            (x + SAMPLE_W + 6, y),
            font.color(&BLACK).pos(text_pos_left_center()),
        ))?;
        x += SAMPLE_W + 6 + text_w(label) + 24;
    }
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
    /// Colour range of the values ([`heat_range`]: from the data).
    pub range: (f64, f64),
    /// Signed data: a diverging colour map (blue, white at 0, red) over a
    /// range symmetric about 0, instead of viridis.
    pub diverging: bool,
    /// Label of the colour bar.
    pub value_label: String,
    /// Named classes with their colours (legend).
    pub classes: Vec<(String, RGBColor)>,
}

/// The colour range of heat-map values, from the data: the values' least and
/// greatest (for `diverging`, ±their largest magnitude, so that 0 is white),
/// widened to a tenth of a unit if they are all equal; `None` if no cell
/// holds a value.
pub fn heat_range(cells: &[Heat], diverging: bool) -> Option<(f64, f64)> {
    let vals = cells.iter().filter_map(|h| match h {
        Heat::Value(v) if v.is_finite() => Some(*v),
        _ => None,
    });
    let (lo, hi) = vals.fold(None, |acc: Option<(f64, f64)>, v| {
        Some(acc.map_or((v, v), |(a, b)| (a.min(v), b.max(v))))
    })?;
    let (lo, hi) = if diverging {
        let m = lo.abs().max(hi.abs());
        (-m, m)
    } else {
        (lo, hi)
    };
    Some(if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.05, hi + 0.05)
    })
}

/// A diverging colour map (ColorBrewer RdBu, reversed): blue at 0, white at
/// 0.5, red at 1.
fn diverging(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (33.0, 102.0, 172.0),
        (146.0, 197.0, 222.0),
        (247.0, 247.0, 247.0),
        (244.0, 165.0, 130.0),
        (178.0, 24.0, 43.0),
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
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
    let cmap = if m.diverging { diverging } else { viridis };
    chart.draw_series(m.cells.iter().enumerate().map(|(i, h)| {
        let (x, y) = (m.xs[i % nx], m.ys[i / nx]);
        let c = match *h {
            Heat::Value(v) => cmap((v - lo) / span),
            Heat::Class(k) => m.classes.get(k).map(|c| c.1).unwrap_or(RGBColor(0, 0, 0)),
        };
        Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], c.filled())
    }))?;
    // The classes' swatches under the colour bar (not over the cells).
    let (_, bh) = bar.dim_in_pixel();
    let class_rows = 18 * m.classes.len() as i32;
    let font = TextStyle::from(("sans-serif", 12).into_font());
    for (i, (name, c)) in m.classes.iter().enumerate() {
        let y = bh as i32 - 12 - class_rows + 18 * i as i32 + 9;
        bar.draw(&Rectangle::new([(4, y - 6), (18, y + 6)], c.filled()))?;
        bar.draw(&Text::new(
            name.as_str(),
            (22, y),
            font.color(&BLACK).pos(text_pos_left_center()),
        ))?;
    }
    // Colour bar, its label above it (a parenthesis on a line of its own:
    // the column is narrow).
    let (head, tail) = match m.value_label.split_once(" (") {
        Some((h, t)) => (h.to_string(), format!("({t}")),
        None => (m.value_label.clone(), String::new()),
    };
    let label_font = TextStyle::from(("sans-serif", 13).into_font());
    for (k, line) in [head, tail].iter().enumerate() {
        bar.draw(&Text::new(
            line.as_str(),
            (4, 10 + 17 * k as i32),
            label_font.color(&BLACK),
        ))?;
    }
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(52)
        .margin_bottom(62 + class_rows)
        .margin_right(8)
        .y_label_area_size(48)
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
            cmap(i as f64 / (steps - 1) as f64).filled(),
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

    /// The colour range follows the data (a fixed 0 … −17 scale drew data
    /// between −6 and −9 in one colour).
    #[test]
    fn heat_range_follows_the_data() {
        let cells = [
            Heat::Value(-6.2),
            Heat::Class(0),
            Heat::Value(-8.9),
            Heat::Value(-7.0),
        ];
        assert_eq!(heat_range(&cells, false), Some((-8.9, -6.2)));
        assert_eq!(heat_range(&cells, true), Some((-8.9, 8.9)));
        assert_eq!(heat_range(&[Heat::Value(2.0)], false), Some((1.95, 2.05)));
        assert_eq!(heat_range(&[Heat::Class(1)], false), None);
        // White at the centre of the diverging map, blue and red at the ends.
        assert_eq!(diverging(0.5), RGBColor(247, 247, 247));
        assert_eq!(diverging(0.0), RGBColor(33, 102, 172));
        assert_eq!(diverging(1.0), RGBColor(178, 24, 43));
    }

    #[test]
    fn minus_signs_and_subscripts_are_typeset() {
        assert_eq!(
            minus("-0.5 and 1e-3, lift-off, x-1"),
            "−0.5 and 1e−3, lift-off, x-1"
        );
        let t = typeset_text("μ0 k_z u_z0, v_{c±}", 10.0);
        assert!(t.starts_with("μ<tspan"), "{t}");
        assert!(
            t.contains(">z0</tspan>") && t.contains(">c±</tspan>") && !t.contains('_'),
            "{t}"
        );
        // Words with an underscore longer than three characters stay.
        assert_eq!(typeset_text("not_settled", 10.0), "not_settled");
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
