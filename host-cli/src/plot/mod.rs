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

mod figure;
mod file;
mod heat;
mod map;
mod markers;
mod panels;
mod svg;

pub use figure::*;
pub use file::*;
pub use heat::*;
pub use map::*;
pub use markers::*;
pub use panels::*;
pub use svg::*;

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::style::RGBColor;

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
        // A superscript: raised by 0.35 of the size, at 0.7 of it.
        assert_eq!(
            typeset_text("e^{iφ}", 10.0),
            "e<tspan baseline-shift=\"3.5\" font-size=\"7.0\">iφ</tspan>"
        );
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
