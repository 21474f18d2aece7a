//! The μ loop's bench over a grid of resonant transducers and on a
//! drifting plant with and without resonance tracking (`fricctl bench
//! control`): each run is a [`crate::control_bench::run`]
//! with the defaults of `fricctl device control-bench` but for the flags its
//! `command` names.
//!
//! * **Grid**: Q ∈ {100, 300, 1000} of the normal mode, the tangential
//!   mode's Q two thirds of it (the defaults' 300 : 200); the normal
//!   resonance at 20 kHz and at 40 kHz, the tangential one below it in the
//!   defaults' ratio 19 700 / 20 300 (2.96 % below); headroom 1 (no
//!   overdrive) and 2; once per noise record (seed 0 the default record):
//!   per grid point and event the median and the largest settling time over
//!   the records ([`GridRun::rows`]).
//! * **Drift**: the default transducers, the normal resonance drifting
//!   ([`DRIFTS_HZ_PER_S`]) and both self-heating [`THERMAL_HZ_PER_UM2`], the
//!   four events and then [`HOLD_S`] s of device time at the last setpoint,
//!   tracking the normal mode and not ([`DriftRun::row`]).

use board::device::Track;
use fric_analysis::numbers::short;
use serde::Serialize;

use crate::control_bench::{self, BenchConfig, BenchOut};
use crate::transducers::{TransducerSpec, LOAD_Q};
use crate::Result;

/// Q of the normal mode in the grid (the tangential mode's: two thirds).
pub const GRID_Q: [f64; 3] = [100.0, 300.0, 1000.0];
/// The normal resonance in the grid, Hz.
pub const GRID_F: [f64; 2] = [20_000.0, 40_000.0];
/// The headroom in the grid.
pub const GRID_H: [f64; 2] = [1.0, 2.0];
/// The tangential resonance over the normal one (the defaults' 19 700 /
/// 20 300).
pub const X_OVER_Z: f64 = 19_700.0 / 20_300.0;
/// The tangential mode's Q over the normal one's (the defaults' 200 / 300).
pub const QX_OVER_QZ: f64 = 2.0 / 3.0;
/// Drift of the normal resonance in the drift runs, Hz/s: the issue's
/// −20 Hz/s (1 200 Hz in 60 s, beyond the tracking range
/// `board::device::tracking::TRACK_RANGE`, ±2 % = ±406 Hz of
/// 20 300 Hz: the tracking's run ends with `loss_of_lock` near 20 s), and
/// −6 Hz/s, the largest whole rate whose 60 s (360 Hz) plus the thermal
/// shift (20 Hz) stays inside that range.
pub const DRIFTS_HZ_PER_S: [f64; 2] = [-20.0, -6.0];
/// Self-heating of the drift runs, Hz/µm² (thermal time 1 s): at the loop's
/// Δu_z ≈ 2 µm the normal resonance settles 20 Hz lower, half the
/// half-power half-band f_r/(2Q_eff) = 39 Hz of the default normal mode
/// (Q 300 loaded by the contact's Q_load 2000: Q_eff = 261); negative as a
/// piezo stack's resonance falls as it warms.
pub const THERMAL_HZ_PER_UM2: f64 = -5.0;
/// The drift runs' hold after the events, s of device time.
pub const HOLD_S: f64 = 60.0;
/// The hold with `--quick`, s.
pub const QUICK_HOLD_S: f64 = 2.0;

/// One grid run.
#[derive(Debug, Clone)]
pub struct GridRun {
    /// Q of the normal mode.
    pub q_z: f64,
    /// Q of the tangential mode.
    pub q_x: f64,
    /// Normal resonance, Hz.
    pub resonance_z_hz: f64,
    /// Tangential resonance, Hz.
    pub resonance_x_hz: f64,
    /// Headroom.
    pub headroom: f64,
    /// The command that reproduces it (seed 0; `--seed S` for the others).
    pub command: String,
    /// Its result (seed 0).
    pub out: BenchOut,
    /// The results of every seed, 0 first.
    pub seeds: Vec<BenchOut>,
}

impl GridRun {
    /// The settling times of `event` over the seeds, ms (None: never).
    fn settles(&self, event: &str) -> Vec<Option<f64>> {
        self.seeds
            .iter()
            .map(|o| {
                o.events
                    .iter()
                    .find(|e| e.event == event)
                    .and_then(|e| e.settle_ms)
            })
            .collect()
    }

    /// The median settling time of `event` over the seeds (a run that
    /// never settled counts as longer than any that did; None if the
    /// median is one of those), ms.
    pub fn median_settle(&self, event: &str) -> Option<f64> {
        let mut v: Vec<f64> = self
            .settles(event)
            .into_iter()
            .map(|s| s.unwrap_or(f64::INFINITY))
            .collect();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n == 0 {
            return None;
        }
        let m = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        m.is_finite().then_some(m)
    }

    /// The largest settling time of `event` over the seeds (None if one
    /// never settled), ms.
    pub fn max_settle(&self, event: &str) -> Option<f64> {
        self.settles(event)
            .into_iter()
            .try_fold(0.0f64, |m, s| s.map(|s| m.max(s)))
    }
}

/// One row of `control_grid.csv` (a grid point's event over its seeds).
#[derive(Serialize, Debug, Clone)]
pub struct GridRow {
    /// Q of the normal mode.
    pub q_z: f64,
    /// Q of the tangential mode.
    pub q_x: f64,
    /// Normal resonance, Hz.
    pub resonance_z_hz: f64,
    /// Tangential resonance, Hz.
    pub resonance_x_hz: f64,
    /// Headroom.
    pub headroom: f64,
    /// The slower mode's τ = Q/(π f_r), ms (unloaded Q: the bench's `tau_ms`).
    pub tau_ms: f64,
    /// The same with the contact's load, 1/Q_eff = 1/Q + 1/Q_load, ms.
    pub tau_eff_ms: f64,
    /// The event.
    pub event: &'static str,
    /// Noise records run (seeds 0 … seeds − 1).
    pub seeds: u32,
    /// Median settling time over the seeds, ms (empty: the median run
    /// never settled).
    pub settle_ms: Option<f64>,
    /// Largest settling time over the seeds, ms (empty: one never settled).
    pub settle_ms_max: Option<f64>,
    /// Settling time of seed 0, drive periods.
    pub settle_periods: Option<f64>,
    /// Median settling time over τ.
    pub settle_over_tau: Option<f64>,
    /// Overshoot as a fraction of the step, largest over the seeds
    /// (setpoint step only).
    pub overshoot: Option<f64>,
    /// The settling band of seed 0, absolute μ.
    pub band: f64,
    /// RMS of μ̂ − μ* over the segment's last half (seed 0).
    pub steady_rms: f64,
    /// Samples whose true normal excursion exceeded the lift-off limit, over
    /// all the seeds' runs.
    pub commands_above_limit: u64,
    /// The largest true normal excursion of the runs, m.
    pub max_excursion_m: f64,
    /// Faults that ended a run (`;`-separated, seed 0).
    pub faults: String,
    /// Wall-clock time of the runs on this host, s (all seeds).
    pub wall_s: f64,
}

/// One row of `control_drift.csv`.
#[derive(Serialize, Debug, Clone)]
pub struct DriftRow {
    /// `none` or `z`.
    pub track: &'static str,
    /// Drift of the normal resonance, Hz/s.
    pub drift_hz_per_s: f64,
    /// Self-heating, Hz/µm².
    pub thermal_hz_per_um2: f64,
    /// The hold asked for, s.
    pub hold_s: f64,
    /// The hold run, s (shorter if a fault ended it).
    pub hold_run_s: f64,
    /// RMS of μ̂ − μ* over the hold.
    pub hold_mu_error_rms: Option<f64>,
    /// Largest |μ̂ − μ*| over the hold.
    pub hold_mu_error_max: Option<f64>,
    /// Drive start to the first lock, ms.
    pub lock_ms: Option<f64>,
    /// Largest |tracking error| after the lock (the device's), Hz.
    pub tracking_error_max_hz: Option<f64>,
    /// Largest |f − true f_r| after the lock, Hz.
    pub true_offset_max_hz: Option<f64>,
    /// The drive frequency at the end, Hz.
    pub frequency_end_hz: f64,
    /// The plant's normal resonance at the end, Hz.
    pub resonance_z_end_hz: Option<f64>,
    /// Locked at the end.
    pub locked: bool,
    /// Faults that ended the run (`;`-separated).
    pub faults: String,
    /// Device time of the fault, s.
    pub fault_at_s: Option<f64>,
    /// The events' settling times, ms (switch-on, setpoint step,
    /// disturbance, velocity step; `never` if one did not settle).
    pub settle_ms: String,
    /// Samples above the lift-off limit.
    pub commands_above_limit: u64,
    /// Wall-clock time of the run on this host, s.
    pub wall_s: f64,
}

/// The drift run's result with its command.
#[derive(Serialize, Debug)]
pub struct DriftRun {
    /// Drift of the normal resonance, Hz/s.
    pub drift_hz_per_s: f64,
    /// The command that reproduces it.
    pub command: String,
    /// Its result.
    pub out: BenchOut,
}

impl GridRun {
    /// The rows of `control_grid.csv`: one per event, over the seeds.
    pub fn rows(&self) -> Vec<GridRow> {
        let load = |q: f64| 1.0 / (1.0 / q + 1.0 / LOAD_Q);
        let tau_eff_ms = (load(self.q_z) / (std::f64::consts::PI * self.resonance_z_hz))
            .max(load(self.q_x) / (std::f64::consts::PI * self.resonance_x_hz))
            * 1e3;
        let r = self;
        r.out
            .events
            .iter()
            .map(|e| {
                let settle = r.median_settle(e.event);
                let overshoot = r
                    .seeds
                    .iter()
                    .filter_map(|o| {
                        o.events
                            .iter()
                            .find(|x| x.event == e.event)
                            .and_then(|x| x.overshoot)
                    })
                    .reduce(f64::max);
                GridRow {
                    q_z: r.q_z,
                    q_x: r.q_x,
                    resonance_z_hz: r.resonance_z_hz,
                    resonance_x_hz: r.resonance_x_hz,
                    headroom: r.headroom,
                    tau_ms: r.out.tau_ms,
                    tau_eff_ms,
                    event: e.event,
                    seeds: r.seeds.len() as u32,
                    settle_ms: settle,
                    settle_ms_max: r.max_settle(e.event),
                    settle_periods: e.settle_periods,
                    settle_over_tau: settle.map(|s| s / r.out.tau_ms),
                    overshoot,
                    band: e.band,
                    steady_rms: e.steady_rms,
                    commands_above_limit: r.seeds.iter().map(|o| o.commands_above_limit).sum(),
                    max_excursion_m: r
                        .seeds
                        .iter()
                        .map(|o| o.max_excursion_m)
                        .fold(0.0, f64::max),
                    faults: r.out.faults.join(";"),
                    wall_s: r.seeds.iter().map(|o| o.wall_s).sum(),
                }
            })
            .collect()
    }
}

impl DriftRun {
    /// Its row of `control_drift.csv`.
    pub fn row(&self) -> DriftRow {
        let o = &self.out;
        DriftRow {
            track: o.track,
            drift_hz_per_s: self.drift_hz_per_s,
            thermal_hz_per_um2: THERMAL_HZ_PER_UM2,
            hold_s: o.hold_s,
            hold_run_s: o.hold_run_s,
            hold_mu_error_rms: o.hold_mu_error_rms,
            hold_mu_error_max: o.hold_mu_error_max,
            lock_ms: o.lock_ms,
            tracking_error_max_hz: o.tracking_error_max_hz,
            true_offset_max_hz: o.true_offset_max_hz,
            frequency_end_hz: o.frequency_end_hz,
            resonance_z_end_hz: o.resonance_z_end_hz,
            locked: o.locked,
            faults: o.faults.join(";"),
            fault_at_s: o.fault_at_s,
            settle_ms: settles(o).replace(' ', ""),
            commands_above_limit: o.commands_above_limit,
            wall_s: o.wall_s,
        }
    }
}

/// The grid of the run (`quick`: the reduced one), as `(q_z, f_z, h)`.
pub fn grid(quick: bool) -> Vec<(f64, f64, f64)> {
    let mut v = Vec::new();
    if quick {
        for q in [100.0, 300.0] {
            v.push((q, GRID_F[0], 2.0));
        }
        return v;
    }
    for &q in &GRID_Q {
        for &f in &GRID_F {
            for &h in &GRID_H {
                v.push((q, f, h));
            }
        }
    }
    v
}

/// A run of the bench and the command that reproduces it.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// The bench's configuration (seed 0).
    pub config: BenchConfig,
    /// `fricctl device control-bench … --json` with the flags that differ
    /// from its defaults.
    pub command: String,
}

/// The grid point `(q_z, f_z, h)`: the tangential mode's Q and resonance
/// in the defaults' ratios.
pub fn grid_point(q: f64, f: f64, h: f64) -> Point {
    let (qx, fx) = (q * QX_OVER_QZ, f * X_OVER_Z);
    let flags = [
        ("--plant-q-z", short(q)),
        ("--plant-q-x", short(qx)),
        ("--plant-resonance-z", short(f)),
        ("--plant-resonance-x", short(fx)),
        ("--headroom", short(h)),
    ];
    Point {
        config: BenchConfig {
            transducers: TransducerSpec {
                plant_q_z: Some(q),
                plant_q_x: Some(qx),
                plant_resonance_z: Some(f),
                plant_resonance_x: Some(fx),
                ..TransducerSpec::default()
            },
            headroom: h,
            ..BenchConfig::default()
        },
        command: command(&flags),
    }
}

/// The grid point `(q_z, f_z, h)` run over seeds `0 … seeds − 1`.
///
/// # Errors
/// A run's failure ([`control_bench::run`]).
pub fn grid_run(q: f64, f: f64, h: f64, seeds: u32) -> Result<GridRun> {
    let p = grid_point(q, f, h);
    let mut outs = Vec::new();
    for seed in 0..u64::from(seeds.max(1)) {
        let cfg = BenchConfig {
            seed,
            ..p.config.clone()
        };
        outs.push(control_bench::run(&cfg, &mut |_, _| {})?.out);
    }
    let t = &p.config.transducers;
    Ok(GridRun {
        q_z: q,
        q_x: t.plant_q_x.unwrap_or(q),
        resonance_z_hz: f,
        resonance_x_hz: t.plant_resonance_x.unwrap_or(f),
        headroom: h,
        command: p.command,
        out: outs[0].clone(),
        seeds: outs,
    })
}

/// The drift run at `rate` Hz/s of the normal resonance with the
/// self-heating [`THERMAL_HZ_PER_UM2`], tracking `track`, holding `hold_s` s.
pub fn drift_point(rate: f64, track: Track, hold_s: f64) -> Point {
    let name = match track {
        Track::None => "none",
        Track::Z => "z",
        Track::X => "x",
    };
    let flags = [
        ("--plant-resonance-drift-z", short(rate)),
        ("--plant-thermal-shift", short(THERMAL_HZ_PER_UM2)),
        ("--track", name.to_string()),
        ("--hold-s", short(hold_s)),
    ];
    Point {
        config: BenchConfig {
            transducers: TransducerSpec {
                plant_resonance_drift_z: Some(rate),
                plant_thermal_shift: Some(THERMAL_HZ_PER_UM2),
                ..TransducerSpec::default()
            },
            track,
            hold_s,
            ..BenchConfig::default()
        },
        command: command(&flags),
    }
}

/// The drift run of [`drift_point`].
///
/// # Errors
/// The run's failure ([`control_bench::run`]).
pub fn drift_run(rate: f64, track: Track, hold_s: f64) -> Result<DriftRun> {
    let p = drift_point(rate, track, hold_s);
    Ok(DriftRun {
        drift_hz_per_s: rate,
        out: control_bench::run(&p.config, &mut |_, _| {})?.out,
        command: p.command,
    })
}

/// The `fricctl device control-bench` command of a run.
fn command(flags: &[(&str, String)]) -> String {
    let f: Vec<String> = flags.iter().map(|(k, v)| format!("{k} {v}")).collect();
    format!("fricctl device control-bench {} --json", f.join(" "))
}

/// The commands of the runs that put samples of the true normal excursion
/// above the lift-off limit (a safety failure), in order.
pub fn above_limit<'a>(runs: &'a [GridRun], drift: &'a [DriftRun]) -> Vec<&'a str> {
    runs.iter()
        .map(|r| {
            (
                &r.command,
                r.seeds.iter().map(|o| o.commands_above_limit).sum::<u64>(),
            )
        })
        .chain(
            drift
                .iter()
                .map(|d| (&d.command, d.out.commands_above_limit)),
        )
        .filter(|(_, n)| *n > 0)
        .map(|(c, _)| c.as_str())
        .collect()
}

/// The events' settling times of a run, ms, ` / `-separated (`never` for
/// one that did not settle).
pub fn settles(o: &BenchOut) -> String {
    o.events
        .iter()
        .map(|e| e.settle_ms.map_or("never".into(), |s| format!("{s:.2}")))
        .collect::<Vec<_>>()
        .join(" / ")
}
