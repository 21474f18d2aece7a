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
    // The regions as merged polygons ([`region_polygons`]): a few paths
    // with boundaries drawn between the cells' edges, not one square per cell.
    for (k, poly) in region_polygons(m) {
        let c = m.classes[usize::from(k.min(2))].1;
        // Filled and outlined in its own colour, so that no hairline of the
        // background shows between two anti-aliased neighbours.
        chart.draw_series(std::iter::once(Polygon::new(poly.clone(), c.filled())))?;
        let mut closed = poly;
        closed.push(closed[0]);
        let k = fine_line(&pm, &closed, c, 1, None);
        chart.draw_series(LineSeries::new(closed, k.stroke_width(1)))?;
    }
    // The active-control set has no area: wide lines in its colour, under
    // the paper's rules (drawn next, 2 px), so that both show.
    let c0 = m.classes[0].1;
    for pts in &m.class0_lines {
        let k = fine_line(&pm, pts, c0, 9, None);
        chart.draw_series(LineSeries::new(pts.clone(), k.stroke_width(9)))?;
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

/// The classes of column `i` from the bottom up as runs `(class, first row,
/// last row)`.
fn column_runs(m: &RegimeMap, i: usize) -> Vec<(u8, usize, usize)> {
    let nx = m.xs.len();
    let mut runs: Vec<(u8, usize, usize)> = Vec::new();
    for j in 0..m.ys.len() {
        let k = m.class[j * nx + i];
        match runs.last_mut() {
            Some(r) if r.0 == k => r.2 = j,
            _ => runs.push((k, j, j)),
        }
    }
    runs
}

/// The map's regions as polygons `(class, points)`. Columns with the same
/// classes in the same order form one stretch; in it each class is one
/// polygon whose lower and upper boundaries run through the cell edges
/// where the class starts and ends, at the column centres, joined by
/// straight lines (a contour at the cells' resolution, not a staircase).
/// Where the order of the classes changes from one column to the next, the
/// stretches meet at the cell edge in x.
pub(super) fn region_polygons(m: &RegimeMap) -> Vec<(u8, Vec<(f64, f64)>)> {
    let (nx, ny) = (m.xs.len(), m.ys.len());
    if nx == 0 || ny == 0 || m.class.len() != nx * ny {
        return Vec::new();
    }
    let (hx, hy) = (half_step(&m.xs), half_step(&m.ys));
    let y_bottom = m.ys[0] - hy;
    let y_top = m.ys[ny - 1] + hy;
    // The edge below row j (j = ny: the top edge).
    let edge = |j: usize| {
        if j == 0 {
            y_bottom
        } else if j >= ny {
            y_top
        } else {
            m.ys[j] - hy
        }
    };
    let runs: Vec<Vec<(u8, usize, usize)>> = (0..nx).map(|i| column_runs(m, i)).collect();
    let same = |a: &[(u8, usize, usize)], b: &[(u8, usize, usize)]| {
        a.len() == b.len() && a.iter().zip(b).all(|(p, q)| p.0 == q.0)
    };
    let mut out = Vec::new();
    let mut i0 = 0;
    while i0 < nx {
        let mut i1 = i0;
        while i1 + 1 < nx && same(&runs[i1 + 1], &runs[i0]) {
            i1 += 1;
        }
        for (r, &(k, _, _)) in runs[i0].iter().enumerate() {
            let lo = |i: usize| edge(runs[i][r].1);
            let hi = |i: usize| edge(runs[i][r].2 + 1);
            let mut pts = vec![(m.xs[i0] - hx, lo(i0))];
            pts.extend((i0..=i1).map(|i| (m.xs[i], lo(i))));
            pts.push((m.xs[i1] + hx, lo(i1)));
            pts.push((m.xs[i1] + hx, hi(i1)));
            pts.extend((i0..=i1).rev().map(|i| (m.xs[i], hi(i))));
            pts.push((m.xs[i0] - hx, hi(i0)));
            out.push((k, pts));
        }
        i0 = i1 + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(xs: usize, ys: usize, class: Vec<u8>) -> RegimeMap {
        RegimeMap {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            xs: (0..xs).map(|i| i as f64 + 0.5).collect(),
            ys: (0..ys).map(|j| j as f64 + 0.5).collect(),
            class,
            classes: [("a", BLACK), ("b", BLACK), ("c", BLACK)],
            lines: Vec::new(),
            class0_lines: Vec::new(),
        }
    }

    /// Shoelace area of a polygon.
    fn area(p: &[(f64, f64)]) -> f64 {
        let n = p.len();
        (0..n)
            .map(|i| p[i].0 * p[(i + 1) % n].1 - p[(i + 1) % n].0 * p[i].1)
            .sum::<f64>()
            .abs()
            / 2.0
    }

    #[test]
    fn regions_cover_the_map_once_with_one_polygon_per_class_and_stretch() {
        // 4 × 3 cells of unit size: class 1 below, 2 above, the boundary
        // rising from row 1 to row 2 (edges at y = 1, 1, 2, 2); column 3
        // has a third class on top, which starts a second stretch.
        #[rustfmt::skip]
        let class = vec![
            1, 1, 1, 1,
            2, 2, 1, 1,
            2, 2, 2, 0,
        ];
        let m = map(4, 3, class);
        let p = region_polygons(&m);
        // Stretch 0..=2 (classes 1, 2): two polygons; column 3 (1, 0): two.
        assert_eq!(p.iter().map(|x| x.0).collect::<Vec<_>>(), vec![1, 2, 1, 0]);
        // The areas add up to the map's 12 cells exactly (the trapezoids
        // between column centres are shared by the two regions).
        let total: f64 = p.iter().map(|(_, q)| area(q)).sum();
        assert!((total - 12.0).abs() < 1e-12, "{total}");
        // Class 1 in the first stretch: bottom edge 0, upper boundary
        // through (0.5, 1), (1.5, 1), (2.5, 2), out to x = 3 at 2:
        // 0.5 · 1 + 1 · 1 + 1 · (1 + 2)/2 + 0.5 · 2 = 4 (trapezoids).
        let a1 = area(&p[0].1);
        let want = 0.5 * 1.0 + 1.0 * 1.0 + 1.0 * 1.5 + 0.5 * 2.0;
        assert!((a1 - want).abs() < 1e-12, "{a1} vs {want}");
    }
}
