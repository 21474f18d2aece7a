//! `fricctl bench control`: the board's closed μ loop on resonant
//! transducers ([`crate::device::control`], `device control-bench`) over a
//! grid, and on a drifting plant with and without resonance tracking.
//!
//! * **Grid** (`control_grid.csv`, `.json`): Q ∈ {100, 300, 1000} of the
//!   normal mode, the tangential mode's Q two thirds of it (the defaults'
//!   300 : 200); the normal resonance at 20 kHz and at 40 kHz, the
//!   tangential one below it in the defaults' ratio 19 700 / 20 300 (2.96 %
//!   below); headroom 1 (no overdrive) and 2. Every run is `device
//!   control-bench` with these flags and its defaults otherwise (plant μ0
//!   20 % below the model, ±2 counts ADC noise, κ 0.95, `--periods auto`,
//!   fills 2 half-buffers ahead), once per noise record (`--seeds`, seed 0
//!   the default record): per grid point and event the median and the
//!   largest settling time over the records, the median overshoot, τ and
//!   the samples above the lift-off limit of all the runs.
//! * **Drift** (`control_drift.csv`, `.json`): the default transducers
//!   (20 300 Hz, Q 300; 19 700 Hz, Q 200), the normal resonance drifting
//!   ([`DRIFTS_HZ_PER_S`]) and both self-heating [`THERMAL_HZ_PER_UM2`], the
//!   four events and then [`HOLD_S`] s of device time at the last setpoint,
//!   tracking the normal mode (`--track z`) and not (`--track none`): μ
//!   error of the hold, lock time, tracking error, the fault that ended
//!   the run if one did.
//! * **Figure** `settle_vs_tau.png`: settling time against τ, log–log.
//!
//! `--quick` runs a reduced grid (Q 100 and 300 at 20 kHz, headroom 2)
//! and holds [`QUICK_HOLD_S`] s: the files and their columns, not the
//! numbers of the full grid.

use std::path::{Path, PathBuf};

use clap::{Args, Parser};
use serde::Serialize;

use crate::device::control::{bench_out, BenchArgs, BenchOut};
use crate::error::{CliError, CliResult};
use crate::plot::{
    prepare_out_dir, render_figure, Corner, Extras, Figure, Mark, Marker, Panel, Series,
};

/// Flags of `bench control`.
#[derive(Args, Debug, Clone)]
pub struct ControlArgs {
    /// Output directory (control_grid.csv/.json, control_drift.csv/.json,
    /// settle_vs_tau.png); existing files are refused without --force
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The reduced grid and a short hold (checks the files, not the numbers)
    #[arg(long)]
    pub quick: bool,
    /// Noise records per grid point (seeds 0 … N − 1 of `device
    /// control-bench --seed`): the grid reports the median and the largest
    /// settling time over them. 1 … 100
    #[arg(long, default_value_t = 5, value_parser = crate::args::Count::<u32>::at_least(1).at_most(100, "a record runs in 0.01–0.5 s"))]
    pub seeds: u32,
}

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

/// `device control-bench`'s flags from an argument list (its defaults for
/// the rest, exactly as on the command line).
#[derive(Parser, Debug)]
#[command(name = "device control-bench", no_binary_name = true)]
struct BenchOnly {
    #[command(flatten)]
    bench: BenchArgs,
}

fn bench_args(argv: &[String]) -> CliResult<BenchArgs> {
    use clap::{CommandFactory, FromArgMatches};
    // As on the command line: a number may start with `-` (a drift).
    crate::args::numbers_take_hyphens(BenchOnly::command())
        .try_get_matches_from(argv)
        .and_then(|m| BenchOnly::from_arg_matches(&m))
        .map(|b| b.bench)
        .map_err(|e| CliError::failure(format!("bench control: {}", crate::args::clap_message(&e))))
}

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

/// The grid's JSON document.
#[derive(Serialize, Debug)]
struct GridJson<'a> {
    command: String,
    runs: Vec<GridJsonRun<'a>>,
}

#[derive(Serialize, Debug)]
struct GridJsonRun<'a> {
    q_z: f64,
    q_x: f64,
    resonance_z_hz: f64,
    resonance_x_hz: f64,
    headroom: f64,
    command: &'a str,
    /// One result per seed (0 first; `--seed S` reproduces seed S).
    results: &'a [BenchOut],
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

/// The contact's load of the plant (`--plant-load-q` default).
fn load_q() -> f64 {
    crate::device::transducers::LOAD_Q
}

fn files(out: &Path) -> [PathBuf; 5] {
    [
        out.join("control_grid.csv"),
        out.join("control_grid.json"),
        out.join("control_drift.csv"),
        out.join("control_drift.json"),
        out.join("settle_vs_tau.png"),
    ]
}

/// `fricctl bench control`.
pub fn run(a: &ControlArgs) -> CliResult {
    prepare_out_dir(&a.out)?;
    let paths = files(&a.out);
    let named: Vec<(Option<&Path>, &str)> =
        paths.iter().map(|p| (Some(p.as_path()), "out")).collect();
    crate::output::check_outputs(&named)?;
    let g = grid(a.quick);
    let hold = if a.quick { QUICK_HOLD_S } else { HOLD_S };
    let n_seeds = if a.quick { 1 } else { a.seeds };
    let bar = indicatif::ProgressBar::new((g.len() + 2 * DRIFTS_HZ_PER_S.len()) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} runs  {msg}  [{elapsed_precise}, eta {eta}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut runs = Vec::new();
    for (q, f, h) in g {
        let (qx, fx) = (q * QX_OVER_QZ, f * X_OVER_Z);
        let flags: Vec<String> = [
            "--plant-q-z".to_string(),
            short(q),
            "--plant-q-x".into(),
            short(qx),
            "--plant-resonance-z".into(),
            short(f),
            "--plant-resonance-x".into(),
            short(fx),
            "--headroom".into(),
            short(h),
        ]
        .into();
        bar.set_message(format!("Q {q}, {f} Hz, headroom {h}"));
        let mut seeds = Vec::new();
        for seed in 0..n_seeds {
            let mut argv = flags.clone();
            argv.extend(["--seed".to_string(), seed.to_string()]);
            seeds.push(bench_out(&bench_args(&argv)?, false)?);
        }
        let run = GridRun {
            q_z: q,
            q_x: qx,
            resonance_z_hz: f,
            resonance_x_hz: fx,
            headroom: h,
            command: format!("fricctl device control-bench {} --json", flags.join(" ")),
            out: seeds[0].clone(),
            seeds,
        };
        let med = |e: &str| {
            run.median_settle(e)
                .map_or("never".into(), |s| format!("{s:.2}"))
        };
        bar.println(format!(
            "Q {q:>5}, f_r {f:>6} Hz, headroom {h}: tau {:.2} ms, median settle over {n_seeds} (ms) {} / {} / {} / {}, above limit {}, {:.1} s",
            run.out.tau_ms,
            med("switch_on"),
            med("setpoint_step"),
            med("disturbance"),
            med("velocity_step"),
            run.seeds.iter().map(|o| o.commands_above_limit).sum::<u64>(),
            run.seeds.iter().map(|o| o.wall_s).sum::<f64>()
        ));
        bar.inc(1);
        runs.push(run);
    }
    let mut drift = Vec::new();
    for (rate, track) in DRIFTS_HZ_PER_S
        .iter()
        .flat_map(|r| [(*r, "none"), (*r, "z")])
    {
        let flags: Vec<String> = [
            "--plant-resonance-drift-z".to_string(),
            short(rate),
            "--plant-thermal-shift".into(),
            short(THERMAL_HZ_PER_UM2),
            "--track".into(),
            track.into(),
            "--hold-s".into(),
            short(hold),
        ]
        .into();
        bar.set_message(format!(
            "drift {rate} Hz/s, tracking {track}, hold {hold} s"
        ));
        let out = bench_out(&bench_args(&flags)?, false)?;
        bar.println(format!(
            "drift {rate} Hz/s, tracking {track}: hold {:.2} s, mu error rms {}, lock {} ms, faults [{}], {:.1} s",
            out.hold_run_s,
            out.hold_mu_error_rms.map_or("-".into(), |x| format!("{x:.2e}")),
            out.lock_ms.map_or("-".into(), |x| format!("{x:.1}")),
            out.faults.join(", "),
            out.wall_s
        ));
        bar.inc(1);
        drift.push(DriftRun {
            drift_hz_per_s: rate,
            command: format!("fricctl device control-bench {} --json", flags.join(" ")),
            out,
        });
    }
    bar.finish_and_clear();
    write_outputs(a, &paths, &runs, &drift)?;
    // Events that never settle and faults that end a drift run are
    // measurements (the files and the figure show them); a sample of the
    // true normal excursion above the lift-off limit is a safety failure.
    let above: Vec<&str> = runs
        .iter()
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
        .collect();
    match above.first() {
        None => Ok(()),
        Some(first) => Err(CliError::failure(format!(
            "bench control: {} run(s) put samples of the true normal excursion above the lift-off limit (first: {first})",
            above.len()
        ))),
    }
}

fn short(x: f64) -> String {
    crate::args::short(x)
}

fn settles(o: &BenchOut) -> String {
    o.events
        .iter()
        .map(|e| e.settle_ms.map_or("never".into(), |s| format!("{s:.2}")))
        .collect::<Vec<_>>()
        .join(" / ")
}

fn write_outputs(
    a: &ControlArgs,
    paths: &[PathBuf; 5],
    runs: &[GridRun],
    drift: &[DriftRun],
) -> CliResult {
    let cmd = format!(
        "fricctl bench control --out {}{}",
        a.out.display(),
        if a.quick {
            " --quick".to_string()
        } else if a.seeds != 5 {
            format!(" --seeds {}", a.seeds)
        } else {
            String::new()
        }
    );
    let mut rows = Vec::new();
    for r in runs {
        let load = |q: f64| 1.0 / (1.0 / q + 1.0 / load_q());
        let tau_eff_ms = (load(r.q_z) / (std::f64::consts::PI * r.resonance_z_hz))
            .max(load(r.q_x) / (std::f64::consts::PI * r.resonance_x_hz))
            * 1e3;
        for e in &r.out.events {
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
            rows.push(GridRow {
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
            });
        }
    }
    write_file(&paths[0], &crate::output::csv_bytes(&rows, true)?)?;
    let doc = GridJson {
        command: cmd.clone(),
        runs: runs
            .iter()
            .map(|r| GridJsonRun {
                q_z: r.q_z,
                q_x: r.q_x,
                resonance_z_hz: r.resonance_z_hz,
                resonance_x_hz: r.resonance_x_hz,
                headroom: r.headroom,
                command: &r.command,
                results: &r.seeds,
            })
            .collect(),
    };
    write_file(&paths[1], &json_bytes(&doc)?)?;
    let drows: Vec<DriftRow> = drift
        .iter()
        .map(|d| {
            let o = &d.out;
            DriftRow {
                track: o.track,
                drift_hz_per_s: d.drift_hz_per_s,
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
        })
        .collect();
    write_file(&paths[2], &crate::output::csv_bytes(&drows, true)?)?;
    #[derive(Serialize)]
    struct DriftJson<'a> {
        command: String,
        runs: &'a [DriftRun],
    }
    write_file(
        &paths[3],
        &json_bytes(&DriftJson {
            command: cmd.clone(),
            runs: drift,
        })?,
    )?;
    render_figure(&paths[4], &figure(runs, &cmd))?;
    eprintln!("wrote {}", paths[4].display());
    Ok(())
}

fn json_bytes<T: Serialize>(v: &T) -> CliResult<Vec<u8>> {
    let mut s =
        serde_json::to_vec_pretty(v).map_err(|e| CliError::failure(format!("JSON: {e}")))?;
    s.push(b'\n');
    Ok(s)
}

fn write_file(p: &Path, bytes: &[u8]) -> CliResult {
    let mut f = crate::output::AtomicFile::create(p, "out")?;
    f.write_all(bytes)?;
    f.commit()?;
    eprintln!("wrote {}", p.display());
    Ok(())
}

/// The events: name, marker, legend text.
const EVENTS: [(&str, Marker, &str); 4] = [
    ("switch_on", Marker::Circle, "switch-on"),
    ("setpoint_step", Marker::Square, "setpoint step"),
    ("disturbance", Marker::Triangle, "disturbance (μ0 × 0.9)"),
    ("velocity_step", Marker::Diamond, "velocity step"),
];

/// Settling time against τ, log–log: per event a marker, per headroom a
/// colour and a line through the runs ordered by τ.
fn figure(runs: &[GridRun], cmd: &str) -> Figure {
    let heads: Vec<f64> = {
        let mut h: Vec<f64> = runs.iter().map(|r| r.headroom).collect();
        h.sort_by(f64::total_cmp);
        h.dedup();
        h
    };
    let mut series = Vec::new();
    let mut ys = Vec::new();
    // Events that never settled: (τ, headroom's style, event index), drawn
    // with the event's marker in a band at the top, one row per event;
    // their line breaks there (NaN).
    let mut never: Vec<(f64, usize, usize)> = Vec::new();
    // Headroom 1 (no overdrive): colour 0, filled markers; any other: colour
    // 1, open markers (the legend says so).
    let style = |h: f64| usize::from(h != 1.0);
    for &h in &heads {
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
    let taus: Vec<f64> = runs.iter().map(|r| r.out.tau_ms).collect();
    let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    // The data with a margin (the 2.5 ms and τ = 5 ms lines inside).
    // (Whole decades: the log axis's minor grid stays regular.)
    let x = (
        decade_below(lo(&taus).min(5.0) / 1.2),
        decade_above(hi(&taus).max(5.0) * 1.2),
    );
    // With events that never settled, room above the data for their band
    // (a separator at y_top/4.2, rows at y_top/1.4/1.3^k, k = 0…3).
    let room = if never.is_empty() { 1.2 } else { 4.5 };
    let y = (
        decade_below(lo(&ys).min(2.5) / 1.2),
        decade_above(hi(&ys).max(x.1) * room),
    );
    let sep = y.1 / 4.2;
    let mut labels = Vec::new();
    if !never.is_empty() {
        series.push(Series {
            label: String::new(),
            points: vec![(x.0, sep), (x.1, sep)],
            mark: Mark::Line,
            color: 8,
        });
        labels.push((
            (x.0 * 1.15, sep * 1.12),
            "never settled (above this line; one row per event)".to_string(),
        ));
    }
    for hs in [0, 1] {
        for (k, (_, marker, _)) in EVENTS.into_iter().enumerate() {
            series.push(Series {
                label: String::new(),
                points: never
                    .iter()
                    .filter(|n| n.1 == hs && n.2 == k)
                    .map(|n| (n.0, y.1 / 1.4 / 1.3f64.powi(k as i32)))
                    .collect(),
                mark: Mark::Markers(if hs == 0 { marker } else { open(marker) }),
                color: hs,
            });
        }
    }
    series.push(Series {
        label: String::new(),
        points: vec![(x.0, x.0), (x.1, x.1)],
        mark: Mark::Dashed,
        color: 6,
    });
    series.push(Series {
        label: String::new(),
        points: vec![(x.0, 2.5), (x.1, 2.5)],
        mark: Mark::Dashed,
        color: 9,
    });
    series.push(Series {
        label: String::new(),
        points: vec![(5.0, y.0), (5.0, y.1)],
        mark: Mark::Dashed,
        color: 8,
    });
    let mut legend: Vec<Series> = heads
        .iter()
        .map(|h| Series {
            label: if *h == 1.0 {
                "headroom 1 (no overdrive), filled markers".into()
            } else {
                format!("headroom {h}, open markers")
            },
            points: Vec::new(),
            mark: Mark::Line,
            color: style(*h),
        })
        .collect();
    for (_, marker, text) in EVENTS {
        legend.push(Series {
            label: text.into(),
            points: Vec::new(),
            mark: Mark::Markers(marker),
            color: 8,
        });
    }
    legend.push(Series {
        label: "settle = τ".into(),
        points: Vec::new(),
        mark: Mark::Dashed,
        color: 6,
    });
    legend.push(Series {
        label: "2.5 ms (the issue's bound where τ ≤ 5 ms)".into(),
        points: Vec::new(),
        mark: Mark::Dashed,
        color: 9,
    });
    legend.push(Series {
        label: "τ = 5 ms".into(),
        points: Vec::new(),
        mark: Mark::Dashed,
        color: 8,
    });
    let qs: Vec<String> = {
        let mut q: Vec<f64> = runs.iter().map(|r| r.q_z).collect();
        q.sort_by(f64::total_cmp);
        q.dedup();
        q.iter().map(|q| short(*q)).collect()
    };
    let fs: Vec<String> = {
        let mut f: Vec<f64> = runs.iter().map(|r| r.resonance_z_hz).collect();
        f.sort_by(f64::total_cmp);
        f.dedup();
        f.iter().map(|f| format!("{:.0} kHz", f / 1e3)).collect()
    };
    let mut caption = vec![
        format!(
            "{cmd}: per point the median over {} noise records of `device control-bench`.",
            runs.first().map_or(1, |r| r.seeds.len())
        ),
        format!(
            "Grid: Q_z ∈ {{{}}}, Q_x = 2/3 Q_z; normal resonance f_r ∈ {{{}}}, tangential {:.2} % below; headroom ∈ {{{}}}; the drive at the normal resonance.",
            qs.join(", "),
            fs.join(", "),
            100.0 * (1.0 - X_OVER_Z),
            heads.iter().map(|h| short(*h)).collect::<Vec<_>>().join(", ")
        ),
        format!(
            "τ = Q/(π f_r) of the slower (normal) mode with the unloaded Q (the contact's load, Q_load = {}, shortens it).",
            short(load_q())
        ),
        "Settled: every later estimate within 2 % of the step (or 4 × the estimates' scatter in the event's segment if wider); time to the end of that update's 128 µs half-buffer.".into(),
        "Fixed: plant μ0 = 0.24 (model 0.3); ADC noise ±2 counts; κ = 0.95 with the plant's gain learned; DAC fills 2 half-buffers ahead;".into(),
        "drive periods per update: as many as fit a 64-sample half-buffer (1 at 20 kHz, 4 at 40 kHz); u_z0 = 4 µm, Δu_x = 0.3 µm, φ = 40°;".into(),
        "v0 = 4 mm/s (step to 6 mm/s); setpoints μ* = 0.08, then 0.10; disturbance μ0 × 0.9.".into(),
    ];
    if !never.is_empty() {
        caption.push(format!(
            "{} event(s) never settled within their segment (≥ 15 ms and ≥ 8 τ): their markers above the grey line (one row per event); lines break there.",
            never.len()
        ));
    }
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
                labels,
                ..Extras::default()
            },
        )],
        rows: 1,
        cols: 1,
        size: (1200, 1000),
        legend,
        caption,
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
