//! `fricctl device control-bench --plot`: the μ loop's run on the
//! mismatched virtual plant, three panels over device time — μ̂ against the
//! setpoint and its ±2 % band, the commanded Δu_z against the model's
//! feedforward, the plant's true excursion and the lift-off limit, and the
//! normal channel's voltage.

use std::path::Path;

use device_host::control_bench::{scenario, BenchOut, BenchTrace};

use crate::error::CliResult;
use crate::plot::{render_figure, Corner, Extras, Figure, Mark, Marker, Panel, Series};

/// Device time in ms from 2 ms before the loop is switched on.
struct Axis {
    t0: f64,
    end: f64,
}

impl Axis {
    fn of(run: &BenchTrace) -> Axis {
        Axis {
            t0: run.t_events[0] - 0.002,
            end: run.t_end,
        }
    }
    fn ms(&self, t: f64) -> f64 {
        (t - self.t0) * 1e3
    }
    fn range(&self) -> (f64, f64) {
        (0.0, self.ms(self.end))
    }
    /// `a` from the loop's switch-on, `b` from the setpoint step to the end.
    fn steps(&self, run: &BenchTrace, (a, b): (f64, f64)) -> Vec<(f64, f64)> {
        let (t0, t1) = (self.ms(run.t_events[0]), self.ms(run.t_events[1]));
        vec![(t0, a), (t1, a), (t1, b), (self.ms(self.end), b)]
    }
}

/// The chart of a run.
///
/// # Errors
/// The file cannot be written.
pub fn chart(path: &Path, run: &BenchTrace, o: &BenchOut) -> CliResult {
    let ax = Axis::of(run);
    let fig = Figure {
        panels: vec![
            (
                mu_panel(run, o, &ax),
                Extras {
                    notes: notes(run, o, &ax),
                    notes_at: Corner::UpperLeft,
                    legend_at: Corner::LowerRight,
                    ..Extras::default()
                },
            ),
            (
                amplitude_panel(run, o, &ax),
                Extras {
                    legend_at: Corner::UpperRight,
                    ..Extras::default()
                },
            ),
            (
                voltage_panel(run, o, &ax),
                Extras {
                    legend_at: Corner::UpperRight,
                    ..Extras::default()
                },
            ),
        ],
        rows: 3,
        cols: 1,
        size: (1200, 1250),
        legend: Vec::new(),
        caption: caption(o),
    };
    render_figure(path, &fig)
}

/// μ̂ against the setpoint and its ±2 % band.
fn mu_panel(run: &BenchTrace, o: &BenchOut, ax: &Axis) -> Panel {
    let (a, b) = (f64::from(run.targets.0), f64::from(run.targets.1));
    let band = |s: f64| {
        let mut v = ax.steps(run, (a * (1.0 + s), b * (1.0 + s)));
        // No vertical edge at the step: a gap.
        v.insert(2, (v[1].0, f64::NAN));
        v
    };
    let meas = run
        .log
        .iter()
        .map(|(t, u)| (ax.ms(*t), f64::from(u.measured_mu)))
        .collect();
    Panel {
        title: "Closed loop on the mismatched virtual plant: μ".into(),
        x_label: "device time, ms".into(),
        y_label: "μ".into(),
        x: ax.range(),
        y: if o.transducers == "resonant" {
            (0.03, 0.14)
        } else {
            (0.04, 0.17)
        },
        // The estimates first, the setpoint over them: its line stays
        // visible where the markers sit on it.
        series: vec![
            Series {
                label: "μ* ± 2 %".into(),
                points: band(0.02),
                mark: Mark::Dashed,
                color: 2,
            },
            Series {
                label: String::new(),
                points: band(-0.02),
                mark: Mark::Dashed,
                color: 2,
            },
            Series {
                label: format!(
                    "μ estimate ({} drive period{} per update)",
                    o.periods,
                    if o.periods == 1 { "" } else { "s" }
                ),
                points: meas,
                mark: Mark::LineMarkers(Marker::Ring),
                color: 0,
            },
            Series {
                label: "μ* setpoint".into(),
                points: ax.steps(run, (a, b)),
                mark: Mark::Line,
                color: 1,
            },
        ],
    }
}

/// The commanded Δu_z, the model's feedforward, the plant's true excursion
/// and the lift-off limit, µm.
fn amplitude_panel(run: &BenchTrace, o: &BenchOut, ax: &Axis) -> Panel {
    let ff = |k: usize| f64::from(run.states[k].feedforward_m) * 1e6;
    let x = ax.range();
    Panel {
        title: "Commanded normal amplitude (the loop's output)".into(),
        x_label: "device time, ms".into(),
        y_label: "Δu_z, µm".into(),
        x,
        y: (0.0, 5.5),
        series: vec![
            Series {
                label: "commanded Δu_z".into(),
                points: run
                    .log
                    .iter()
                    .map(|(t, u)| (ax.ms(*t), f64::from(u.amp_z_m) * 1e6))
                    .collect(),
                mark: Mark::LineMarkers(Marker::Circle),
                color: 0,
            },
            Series {
                label: "model feedforward".into(),
                points: ax.steps(run, (ff(0), ff(1))),
                mark: Mark::Dashed,
                color: 4,
            },
            Series {
                label: "true normal excursion (plant)".into(),
                points: run.trace.iter().map(|r| (ax.ms(r.0), r.2 * 1e6)).collect(),
                mark: Mark::Line,
                color: 2,
            },
            Series {
                label: "lift-off limit (1 − 0.05)·u_z0".into(),
                points: vec![(x.0, o.liftoff_limit * 1e6), (x.1, o.liftoff_limit * 1e6)],
                mark: Mark::Line,
                color: 3,
            },
        ],
    }
}

/// The normal channel's DAC voltage amplitude.
fn voltage_panel(run: &BenchTrace, o: &BenchOut, ax: &Axis) -> Panel {
    let vmax = run.trace.iter().map(|r| r.1).fold(0.0, f64::max);
    Panel {
        title: "Normal channel's voltage (DAC amplitude)".into(),
        x_label: "device time, ms".into(),
        y_label: "voltage amplitude, V".into(),
        x: ax.range(),
        y: (0.0, (vmax * 1.15).max(1e-3)),
        series: vec![Series {
            label: format!("voltage (headroom {} × steady)", o.headroom),
            points: run.trace.iter().map(|r| (ax.ms(r.0), r.1)).collect(),
            mark: Mark::Line,
            color: 0,
        }],
    }
}

/// The plant, the drive and the events, in the μ panel.
fn notes(run: &BenchTrace, o: &BenchOut, ax: &Axis) -> Vec<String> {
    use scenario::*;
    let te = &run.t_events;
    let plant = if o.transducers == "resonant" {
        format!(
            "resonant transducers, slower τ = Q/(π f_r) = {:.2} ms; model: exact identification",
            o.tau_ms
        )
    } else {
        format!("ideal transducers, lag {} periods", o.lag_periods)
    };
    vec![
        format!(
            "plant μ0 = {:.3} (model {}), {plant}, μ0 drift {} /s, ADC noise ±{} counts",
            run.model_mu0 * o.mu0_ratio,
            run.model_mu0,
            o.drift_per_s,
            o.noise_counts
        ),
        format!(
            "drive {:.0} Hz, u_z0 = 4 µm, Δu_x = 0.3 µm, φ = 40°, k_z = k_x = 1e7 N/m; loop v0 = {} mm/s, κ = {}",
            o.freq_hz,
            V0 * 1e3,
            o.gain
        ),
        format!(
            "events: loop on at {:.1} ms, setpoint step at {:.1} ms, μ0 × {MU0_STEP} at {:.1} ms, v0 {}→{} mm/s at {:.1} ms",
            ax.ms(te[0]),
            ax.ms(te[1]),
            ax.ms(te[2]),
            V0 * 1e3,
            V1 * 1e3,
            ax.ms(te[3])
        ),
    ]
}

/// The caption: the setpoint step's settling and the band's rule.
fn caption(o: &BenchOut) -> Vec<String> {
    let opt =
        |x: Option<f64>, prec: usize| x.map_or("never".to_string(), |v| format!("{v:.prec$}"));
    vec![
        format!(
            "The μ loop with the DAC filled {} half-buffers ahead: the setpoint step settles within ±{:.2e} in {} periods ({} ms)",
            o.fill_lead,
            o.events[1].band,
            opt(o.events[1].settle_periods, 0),
            opt(o.events[1].settle_ms, 3),
        ),
        format!(
            "(band: 2 % of the step, or 4 × the estimates' scatter over the segment's last half if wider); DAC fills {} half-buffers of {} samples ahead",
            o.fill_lead, o.half_buffer_samples
        ),
    ]
}
