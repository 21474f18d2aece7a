//! `fricctl device identify --plot`: the Bode plot of the identified
//! transducers — per channel the measured response X/U of the fine pass
//! (markers) and the fitted mode of eq. 1 of `board::identify` (lines),
//! magnitude on a log axis over the phase, unwrapped from 0 down (a mode's
//! lag).

use std::path::Path;

use device_host::identify::{ChannelFit, WINDOWS_PER_POINT};

use crate::error::CliResult;
use crate::plot::{render_figure, Corner, Extras, Figure, Mark, Marker, Panel, Series};
use fric_analysis::grid::linspace;

/// Points of each fitted curve.
const CURVE_POINTS: usize = 600;

/// |H| of a response (re, im), m/V.
fn magnitude((re, im): (f64, f64)) -> f64 {
    re.hypot(im)
}

/// The phases of responses in degrees, unwrapped from 0: each within 180°
/// of the one before.
fn phases(pts: &[(f64, f64)]) -> Vec<f64> {
    let mut v: Vec<f64> = pts
        .iter()
        .map(|&(re, im)| im.atan2(re).to_degrees())
        .collect();
    for i in 0..v.len() {
        let prev = if i == 0 { 0.0 } else { v[i - 1] };
        while v[i] - prev > 180.0 {
            v[i] -= 360.0;
        }
        while v[i] - prev < -180.0 {
            v[i] += 360.0;
        }
    }
    v
}

/// The magnitude axis: the records' range, half a factor 2 below and a
/// factor 20 above (room for the legend), or 1e-9 … 1e-4 m/V without a
/// positive range.
fn magnitude_range(results: &[ChannelFit]) -> (f64, f64) {
    let m = results
        .iter()
        .flat_map(|ch| &ch.record)
        .map(|s| magnitude((s.re_m_per_v, s.im_m_per_v)));
    let (lo, hi) = m.fold((f64::INFINITY, 0.0f64), |(l, h), x| (l.min(x), h.max(x)));
    let (lo, hi) = if lo > 0.0 && hi > lo {
        (lo, hi)
    } else {
        (1e-9, 1e-4)
    };
    (lo / 2.0, hi * 20.0)
}

/// One channel's series: (magnitude, phase), measured then fitted.
fn channel_series(i: usize, ch: &ChannelFit, xs: &[f64]) -> (Vec<Series>, Vec<Series>) {
    let rec: Vec<(f64, f64)> = ch
        .record
        .iter()
        .map(|s| (s.re_m_per_v, s.im_m_per_v))
        .collect();
    let f: Vec<f64> = ch.record.iter().map(|s| s.freq_hz).collect();
    let mut mag = vec![Series {
        label: format!("{} transducer, measured", ch.name),
        points: f
            .iter()
            .zip(&rec)
            .map(|(&x, &r)| (x, magnitude(r)))
            .collect(),
        mark: Mark::Markers(Marker::Circle),
        color: i,
    }];
    let mut ph = vec![Series {
        label: String::new(),
        points: f.iter().copied().zip(phases(&rec)).collect(),
        mark: Mark::Markers(Marker::Circle),
        color: i,
    }];
    if let Ok(fit) = &ch.fit {
        let model: Vec<(f64, f64)> = xs.iter().map(|&x| fit.model.response(x)).collect();
        mag.push(Series {
            label: format!(
                "{} fit: f_r {:.1} Hz, Q {:.0}, g {:.3e} m/V",
                ch.name, fit.resonance_hz.value, fit.q.value, fit.gain_m_per_v.value
            ),
            points: xs
                .iter()
                .zip(&model)
                .map(|(&x, &r)| (x, magnitude(r)))
                .collect(),
            mark: Mark::Line,
            color: i,
        });
        ph.push(Series {
            label: String::new(),
            points: xs.iter().copied().zip(phases(&model)).collect(),
            mark: Mark::Line,
            color: i,
        });
    }
    (mag, ph)
}

/// The Bode plot of `results` over the span `(from, to)` Hz.
///
/// # Errors
/// The file cannot be written.
pub fn bode(path: &Path, results: &[ChannelFit], (from, to): (f64, f64)) -> CliResult {
    let xs = linspace(from, to, CURVE_POINTS);
    let (mut mag, mut ph) = (Vec::new(), Vec::new());
    for (i, ch) in results.iter().enumerate() {
        let (m, p) = channel_series(i, ch, &xs);
        mag.extend(m);
        ph.extend(p);
    }
    let magnitude = Panel {
        title: "Transducers: measured response X/U (points) and fitted mode (lines)".into(),
        x_label: "drive frequency, Hz".into(),
        y_label: "|H|, m/V".into(),
        x: (from, to),
        y: magnitude_range(results),
        series: mag,
    };
    let phase = Panel {
        title: "Phase of the response".into(),
        x_label: "drive frequency, Hz".into(),
        y_label: "arg H (unwrapped), deg".into(),
        x: (from, to),
        y: (-225.0, 45.0),
        series: ph,
    };
    let fig = Figure {
        panels: vec![
            (
                magnitude,
                Extras {
                    log_y: true,
                    legend_at: Corner::UpperRight,
                    ..Extras::default()
                },
            ),
            (phase, Extras::default()),
        ],
        rows: 2,
        cols: 1,
        size: (900, 800),
        legend: Vec::new(),
        caption: vec![
            format!(
                "The fine pass of the stepped-sine identification: each point the mean of {WINDOWS_PER_POINT} lock-in windows; the fit is the mode of eq. 1 (f_r, Q, static gain g, extra lag)."
            ),
            "Each transducer driven alone in voltage mode, the other at zero amplitude, under the normal offset u_z0 of the drive set before (the preload).".into(),
        ],
    };
    render_figure(path, &fig)
}
