//! A figure as data: panels of series (lines, dashes, markers) with their
//! axes, legend and caption, markers, colours and tick labels. Commands
//! build a [`Figure`]; [`render_figure`] draws it.

use plotters::prelude::*;

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
pub(super) fn tick(v: f64) -> String {
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
/// The first five are told apart in print and by colour-blind readers: sky
/// blue comes fifth, orange after it (vermillion and orange side by side
/// in a five-curve figure were hard to tell apart).
pub fn color(i: usize) -> RGBColor {
    const P: [RGBColor; 10] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(86, 180, 233),
        RGBColor(230, 159, 0),
        RGBColor(0, 0, 0),
        RGBColor(240, 228, 66),
        RGBColor(128, 128, 128),
        RGBColor(150, 30, 40),
    ];
    P[i % P.len()]
}
