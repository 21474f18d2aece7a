//! Heat maps: cells on a sequential or diverging colour scale, or a named
//! class in its own colour, with a colour bar.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::CliResult;

use super::*;

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
pub(super) fn diverging(t: f64) -> RGBColor {
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

pub(super) fn viridis(t: f64) -> RGBColor {
    use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};
    ViridisRGB.get_color(t.clamp(0.0, 1.0))
}

/// Renders a [`HeatMap`] to `.svg` or `.png`.
pub fn render_heat(path: &Path, m: &HeatMap, size: (u32, u32)) -> CliResult<()> {
    write_chart(path, size, |root| draw_heat(root, m))
}

pub(super) fn log_tick(v: f64, log: bool) -> String {
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

pub(super) fn draw_heat<DB: DrawingBackend>(
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
