//! `fricctl bench control`'s `settle_vs_tau.png`: the closed μ loop's
//! settling time against the transducers' τ = Q/(π f_r), log–log, per event
//! a marker and per headroom a colour, with the events that never settled
//! in a band above the data.

use device_host::control_grid::{GridRun, X_OVER_Z};

use crate::args::short;
use crate::plot::{Corner, Extras, Figure, Mark, Marker, Panel, Series};

/// The events: name, marker, legend text.
const EVENTS: [(&str, Marker, &str); 4] = [
    ("switch_on", Marker::Circle, "switch-on"),
    ("setpoint_step", Marker::Square, "setpoint step"),
    ("disturbance", Marker::Triangle, "disturbance (μ0 × 0.9)"),
    ("velocity_step", Marker::Diamond, "velocity step"),
];

/// Headroom 1 (no overdrive): style 0, filled markers; any other: style
/// 1, open markers (the legend says so).
fn style(h: f64) -> usize {
    usize::from(h != 1.0)
}

/// The headrooms of the runs, ascending.
fn headrooms(runs: &[GridRun]) -> Vec<f64> {
    let mut h: Vec<f64> = runs.iter().map(|r| r.headroom).collect();
    h.sort_by(f64::total_cmp);
    h.dedup();
    h
}

/// An event that never settled: (τ ms, headroom's style, event index).
type Never = (f64, usize, usize);

/// Per headroom and event the median settling times ordered by τ (a run
/// that never settled breaks the line: NaN), the finite times, and the
/// events that never settled.
fn settle_series(runs: &[GridRun], heads: &[f64]) -> (Vec<Series>, Vec<f64>, Vec<Never>) {
    let mut series = Vec::new();
    let mut ys = Vec::new();
    let mut never = Vec::new();
    for &h in heads {
        let hi = style(h);
        for (k, (name, marker, _)) in EVENTS.into_iter().enumerate() {
            let mut pts: Vec<(f64, f64)> = Vec::new();
            for r in runs.iter().filter(|r| r.headroom == h) {
                let s = r.median_settle(name);
                if s.is_none() {
                    never.push((r.out.tau_ms, hi, k));
                }
                pts.push((r.out.tau_ms, s.unwrap_or(f64::NAN)));
            }
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            ys.extend(pts.iter().map(|p| p.1).filter(|y| y.is_finite()));
            series.push(Series {
                label: String::new(),
                points: pts,
                mark: if hi == 0 {
                    Mark::LineMarkers(marker)
                } else {
                    Mark::LineMarkers(open(marker))
                },
                color: hi,
            });
        }
    }
    (series, ys, never)
}

/// The axes' ranges in whole decades (the log axis's minor grid stays
/// regular): the data with a margin, the 2.5 ms and τ = 5 ms lines inside.
fn ranges(runs: &[GridRun], ys: &[f64], never: bool) -> ((f64, f64), (f64, f64)) {
    let taus: Vec<f64> = runs.iter().map(|r| r.out.tau_ms).collect();
    let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let x = (
        decade_below(lo(&taus).min(5.0) / 1.2),
        decade_above(hi(&taus).max(5.0) * 1.2),
    );
    // The events that never settled sit at their segment's length (≤ 8 τ
    // or 15 ms), inside the axis: no extra room.
    let _ = never;
    let y = (
        decade_below(lo(ys).min(2.5) / 1.2),
        decade_above(hi(ys).max(x.1) * 1.2),
    );
    (x, y)
}

/// The segment an event had to settle in, ms: the scenario's spacing of
/// the events, or 8 τ if longer (as the bench runs it).
fn segment_ms(tau_ms: f64, k: usize) -> f64 {
    use device_host::control_bench::scenario::EVENTS_MS;
    (EVENTS_MS[k + 1] - EVENTS_MS[k]).max(8.0 * tau_ms)
}

/// The events that never settled: each at the length of its segment — a
/// lower bound on its settling time — with a dotted line up to the top of
/// the axis (the time is beyond it). No height without a meaning.
fn never_marks(never: &[Never], y_top: f64, series: &mut Vec<Series>) {
    for &(tau, hs, k) in never {
        let (_, marker, _) = EVENTS[k];
        let y = segment_ms(tau, k);
        // Events of one run share τ and often their segment's length: each
        // is moved sideways by its own few per cent so that none hides another.
        let tau = tau * 1.07f64.powf(k as f64 - 1.5);
        series.push(Series {
            label: String::new(),
            points: vec![(tau, y), (tau, y_top)],
            mark: Mark::Dashed,
            color: hs,
        });
        series.push(Series {
            label: String::new(),
            points: vec![(tau, y)],
            mark: Mark::Markers(if hs == 0 { marker } else { open(marker) }),
            color: hs,
        });
    }
}

/// The reference lines: settle = τ, 2.5 ms, τ = 5 ms.
fn reference_lines((x, y): ((f64, f64), (f64, f64))) -> [Series; 3] {
    let line = |points, color| Series {
        label: String::new(),
        points,
        mark: Mark::Dashed,
        color,
    };
    [
        line(vec![(x.0, x.0), (x.1, x.1)], 6),
        line(vec![(x.0, 2.5), (x.1, 2.5)], 9),
        line(vec![(5.0, y.0), (5.0, y.1)], 8),
    ]
}

/// The legend: the headrooms' styles, the events' markers, the reference lines.
fn legend(heads: &[f64]) -> Vec<Series> {
    let entry = |label: String, mark, color| Series {
        label,
        points: Vec::new(),
        mark,
        color,
    };
    let mut legend: Vec<Series> = heads
        .iter()
        .map(|h| {
            let label = if *h == 1.0 {
                "headroom 1 (no overdrive), filled markers".into()
            } else {
                format!("headroom {h}, open markers")
            };
            entry(label, Mark::Line, style(*h))
        })
        .collect();
    for (_, marker, text) in EVENTS {
        legend.push(entry(text.into(), Mark::Markers(marker), 8));
    }
    legend.push(entry("settle = τ".into(), Mark::Dashed, 6));
    legend.push(entry(
        "2.5 ms (the required settling where τ ≤ 5 ms)".into(),
        Mark::Dashed,
        9,
    ));
    legend.push(entry("τ = 5 ms".into(), Mark::Dashed, 8));
    legend
}

/// The caption: the grid, τ, the settling rule and the fixed parameters
/// (the command that reproduces it is in the docs beside the figure).
fn caption(runs: &[GridRun], heads: &[f64], never: usize) -> Vec<String> {
    let distinct = |v: Vec<f64>| {
        let mut v = v;
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let qs: Vec<String> = distinct(runs.iter().map(|r| r.q_z).collect())
        .iter()
        .map(|q| short(*q))
        .collect();
    let fs: Vec<String> = distinct(runs.iter().map(|r| r.resonance_z_hz).collect())
        .iter()
        .map(|f| format!("{:.0} kHz", f / 1e3))
        .collect();
    let mut caption = vec![
        format!(
            "Median of {} noise records per point. Grid: Q_z ∈ {{{}}}, Q_x = 2/3 Q_z; f_r ∈ {{{}}} (tangential {:.2} % below); headroom ∈ {{{}}}.",
            runs.first().map_or(1, |r| r.seeds.len()),
            qs.join(", "),
            fs.join(", "),
            100.0 * (1.0 - X_OVER_Z),
            heads.iter().map(|h| short(*h)).collect::<Vec<_>>().join(", "),
        ),
        format!(
            "τ = Q/(π f_r), normal mode, unloaded Q (the contact's load, Q_load = {}, shortens it); driven at the normal resonance.",
            short(device_host::transducers::LOAD_Q)
        ),
        "Settled: every later estimate within 2 % of the step (or 4 × the estimates' scatter if wider).".into(),
        "Fixed: plant μ0 = 0.24 (model 0.3), ADC noise ±2 counts, κ = 0.95, u_z0 = 4 µm, Δu_x = 0.3 µm, φ = 40°, v0 = 4 → 6 mm/s, μ* = 0.08 → 0.10.".into(),
    ];
    if never > 0 {
        caption.push(format!(
            "{never} event(s) never settled: marked at their segment's length (15 ms or 8 τ), a lower bound, with a dotted line up, each event a few per cent aside in τ."
        ));
    }
    caption
}

/// Settling time against τ, log–log: per event a marker, per headroom a
/// colour and a line through the runs ordered by τ.
pub fn figure(runs: &[GridRun]) -> Figure {
    let heads = headrooms(runs);
    let (mut series, ys, never) = settle_series(runs, &heads);
    let (x, y) = ranges(runs, &ys, !never.is_empty());
    never_marks(&never, y.1, &mut series);
    series.extend(reference_lines((x, y)));
    Figure {
        panels: vec![(
            Panel {
                title: "Settling time of the closed μ loop against the transducers' τ".into(),
                x_label: "τ = Q/(π f_r), ms".into(),
                y_label: "settling time, ms".into(),
                x,
                y,
                series,
            },
            Extras {
                log_x: true,
                log_y: true,
                legend_at: Corner::UpperLeft,
                ..Extras::default()
            },
        )],
        rows: 1,
        cols: 1,
        size: (1200, 1000),
        legend: legend(&heads),
        caption: caption(runs, &heads, never.len()),
    }
}

fn open(m: Marker) -> Marker {
    match m {
        Marker::Circle => Marker::Ring,
        Marker::Square => Marker::OpenSquare,
        Marker::Triangle => Marker::OpenTriangle,
        Marker::Diamond => Marker::OpenDiamond,
        other => other,
    }
}

/// The power of ten at most `v` (> 0).
fn decade_below(v: f64) -> f64 {
    10f64.powf(v.log10().floor())
}

/// The power of ten at least `v` (> 0).
fn decade_above(v: f64) -> f64 {
    10f64.powf(v.log10().ceil())
}
