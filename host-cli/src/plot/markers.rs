//! Marker and legend-sample elements, drawn the same in data and in pixel
//! coordinates.

use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters_backend::{BackendCoord, DrawingErrorKind};

use super::*;

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

pub(super) fn draw_marker<DB: DrawingBackend>(
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
pub(super) const SAMPLE_W: i32 = 28;

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

pub(super) fn sample(mark: Mark, color: RGBColor) -> impl Fn(BackendCoord) -> Sample {
    move |at| Sample { at, mark, color }
}

pub(super) fn marker_at<C>(marker: Marker, color: RGBColor) -> impl Fn(C) -> MarkerAt<C> {
    move |at| MarkerAt {
        at,
        marker,
        color,
        r: 4,
    }
}

/// Dash patterns of a regime map's reference lines (dash, gap, …; pixels):
/// dashed, dotted, dash-dotted.
pub(super) const MAP_DASHES: [&[u32]; 3] = [&[9, 5], &[2, 4], &[12, 4, 2, 4]];

/// A legend sample of a black line with a dash pattern, starting at `at`.
pub(super) struct DashSample {
    pub(super) at: BackendCoord,
    pub(super) pattern: &'static [u32],
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
pub(super) const DASH: (u32, u32) = (7, 5);

pub(super) fn series_marker(mark: Mark) -> Option<Marker> {
    match mark {
        Mark::Points => Some(Marker::Circle),
        Mark::Markers(m) | Mark::LineMarkers(m) => Some(m),
        Mark::Line | Mark::Dashed => None,
    }
}
