//! The regime map: cells over (x, y) coloured by class, with reference lines.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::CliResult;

use super::*;

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

pub(super) fn half_step(v: &[f64]) -> f64 {
    if v.len() > 1 {
        (v[1] - v[0]) / 2.0
    } else {
        0.5
    }
}

pub(super) fn draw_map<'a, DB: DrawingBackend + 'a>(
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
