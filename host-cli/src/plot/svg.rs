//! The drawing pipeline: the embedded font, SVG text typeset with real
//! minus signs and sub/superscripts, curves through exact (sub-pixel)
//! positions ([`fine_line`]) put back into the SVG plotters wrote.

use std::cell::RefCell;
use std::fmt::Write as _;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

pub(super) static FONT: Once = Once::new();
pub(super) const FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

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
pub(super) struct FineLine {
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
    pub(super) static FINE: RefCell<Vec<FineLine>> = const { RefCell::new(Vec::new()) };
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
pub(super) fn typeset_text(t: &str, size: f64) -> String {
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
        // A superscript: `e^{iφ}`.
        if ch == '^' && c.get(i + 1) == Some(&'{') {
            if let Some(end) = c[i + 2..].iter().position(|&x| x == '}') {
                out.push_str(&format!(
                    "<tspan baseline-shift=\"{:.1}\" font-size=\"{:.1}\">{}</tspan>",
                    0.35 * size,
                    0.7 * size,
                    c[i + 2..i + 2 + end].iter().collect::<String>()
                ));
                i += end + 3;
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
pub(super) fn typeset(svg: &str) -> String {
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
pub(super) fn refine(svg: &str, lines: &[FineLine]) -> String {
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
