//! Drawing a [`Figure`]: panels on a grid, their series, the legend placed
//! where the data is not, and the caption.

use std::path::Path;

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::CliResult;

use super::*;

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

pub(super) const CAPTION_LINE: i32 = 22;
pub(super) const LEGEND_LINE: i32 = 24;

/// Legend entries laid out in rows across `width`: (x, row) per entry.
pub(super) fn legend_layout<DB: DrawingBackend>(
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

pub(super) fn draw_figure<'a, DB: DrawingBackend + 'a>(
    root: &'a DrawingArea<DB, Shift>,
    f: &Figure,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (w, h) = root.dim_in_pixel();
    let layout = legend_layout(root, &f.legend, w as i32);
    let legend_rows = layout.last().map_or(0, |&(_, r)| r + 1);
    // The caption grows with the figure's width (15 px at 1000 px, up to
    // 1.5 times that), so that a wide figure scaled to the page keeps a
    // readable caption without its caption outgrowing the panels' titles.
    let cap_scale = (f64::from(w) / 1000.0).clamp(1.0, 1.5);
    let cap_px = (15.0 * cap_scale).round();
    let cap_line = (CAPTION_LINE as f64 * cap_scale).round() as i32;
    let footer = legend_rows * LEGEND_LINE + f.caption.len() as i32 * cap_line;
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
    let cap_font = ("sans-serif", cap_px).into_font();
    for (i, line) in f.caption.iter().enumerate() {
        let y = 8 + legend_rows * LEGEND_LINE + i as i32 * cap_line;
        foot.draw(&Text::new(line.as_str(), (16, y), cap_font.color(&BLACK)))?;
    }
    Ok(())
}

pub(super) fn text_pos_left_center() -> plotters::style::text_anchor::Pos {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    Pos::new(HPos::Left, VPos::Center)
}

/// Splits a series' points at non-finite values (gaps are not bridged).
pub(super) fn segments(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
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

pub(super) fn draw_panel<'a, DB, XR, YR>(
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
pub(super) fn occupied(p: &Panel, pm: &PixelMap, origin: (i32, i32)) -> Vec<(f64, f64)> {
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

pub(super) fn place(
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
pub(super) const LEGEND_ROW: i32 = 20;

pub(super) fn legend_size<DB: DrawingBackend>(
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
pub(super) fn draw_legend<DB: DrawingBackend>(
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
pub(super) const NOTES_LINE: i32 = 19;

pub(super) fn notes_size<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    notes: &[String],
) -> (i32, i32) {
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
pub(super) fn draw_notes<DB: DrawingBackend>(
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
