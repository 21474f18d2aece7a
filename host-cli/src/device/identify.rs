//! `fricctl device identify`: a stepped-sine sweep of each transducer, the
//! fit of its mode ([`board::identify`], eq. 1: f_r, Q, static
//! gain, extra lag, with 95 % intervals), the result stored on the device
//! (`SetTransducers`, kept by `Reset`) and optionally in a file and a Bode
//! plot. Also the drive-mode choice of `drive set` ([`select_mode`]).
//!
//! **The sweep**, per channel, the other at zero amplitude, the normal
//! offset of the accepted drive (the preload the contact is identified
//! under), in voltage mode:
//! 1. a coarse pass of `--points` frequencies over `[--from, --to]`
//!    (default ±5 % around the drive's frequency) at a small amplitude:
//!    1 % of the normal channel's lift-off limit, or of the largest
//!    tangential amplitude, in the DAC calibration's metres;
//! 2. the amplitude rescaled so that the largest response of the coarse
//!    pass becomes [`PEAK_FRACTION`] of that bound (never a step beyond the
//!    DAC); a fine pass of `--fine-points` over ±2 coarse steps around the
//!    coarse peak.
//!
//! At each frequency the mode is left `--settle-ms`, then the device's
//! measured response `X/U` (`Status.measured`) of [`WINDOWS_PER_POINT`]
//! successive lock-in windows is averaged. The coarse pass settles for five
//! envelope time constants of a Q-[`Q_MAX`] mode, `5·Q/(π f)` (the transient
//! after a step of frequency is then below e⁻⁵ = 0.7 % of the step's
//! change); the fine pass for [`FINE_SETTLE_TAUS`] time constants of the
//! coarse pass's own fit (never longer than the coarse settling), unless
//! `--settle-ms` is given. Only the fine pass is fitted: a resonance that
//! drifts (heating, preload) moves between the passes, and the fine pass,
//! four times shorter at Q ≈ 300, sees the least of it (at −20 Hz/s, 12 Hz
//! over its 0.6 s; the tracking, `drive set --track`, follows the rest).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use board::device::{DriveMode, DriveSetting, TransducerModel, Transducers};
use board::identify::{self as fitid, Fit, FitConfig, Sample};
use board::protocol::{Info, Request, Response, Status};

use super::client::Client;
use super::render::Report;
use super::{expect, out, unexpected};
use crate::args::{Count, Real};
use crate::error::{CliError, CliResult};

/// The coarse pass's largest response is scaled to this fraction of the
/// channel's bound (normal: the lift-off limit; tangential: the largest
/// amplitude) for the fine pass.
pub const PEAK_FRACTION: f64 = 0.25;

/// The Q the default settling time allows for (`5·Q_MAX/(π f)`).
pub const Q_MAX: f64 = 1000.0;

/// The fine pass's settling, in envelope time constants of the coarse fit.
pub const FINE_SETTLE_TAUS: f64 = 8.0;

/// Lock-in windows averaged per point.
pub const WINDOWS_PER_POINT: u32 = 8;

/// `device identify` flags.
#[derive(clap::Args, Debug, Clone)]
pub struct IdentifyArgs {
    /// Lowest frequency of the sweep, Hz (default: the drive's frequency − 5 %)
    #[arg(long, value_name = "HZ", value_parser = Real::positive())]
    pub from: Option<f64>,
    /// Highest frequency of the sweep, Hz (default: the drive's frequency + 5 %)
    #[arg(long, value_name = "HZ", value_parser = Real::positive())]
    pub to: Option<f64>,
    /// Frequencies of the coarse pass (6 … 1000)
    #[arg(long, default_value_t = 21, value_parser = Count::<u32>::at_least(6).at_most(1000, "a longer sweep is a chirp's job"))]
    pub points: u32,
    /// Frequencies of the fine pass around the coarse peak (6 … 1000)
    #[arg(long, default_value_t = 31, value_parser = Count::<u32>::at_least(6).at_most(1000, "a longer sweep is a chirp's job"))]
    pub fine_points: u32,
    /// Settling time per frequency, ms (default 5·Q/(π f) for Q = 1000)
    #[arg(long, value_name = "MS", value_parser = Real::positive().at_most(10_000.0).because("ten seconds per point"))]
    pub settle_ms: Option<f64>,
    /// Which transducers: both, z or x (one channel keeps the other's stored model)
    #[arg(long, default_value = "both", value_parser = ["both", "z", "x"])]
    pub channel: String,
    /// Do not store the result on the device
    #[arg(long)]
    pub no_store: bool,
    /// Write the result (the JSON of --json) to FILE
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Bode plot (magnitude and phase, record and fit) to FILE (.png or .svg)
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

/// Switches the device to the drive mode `drive set` asks for: voltage
/// mode with `--open-loop`, else the displacement mode, which needs
/// identified transducers (one line saying to run `identify` otherwise).
///
/// # Errors
/// The refusal, as one line.
pub fn select_mode(c: &mut Client, open_loop: bool) -> CliResult {
    let mode =
        if open_loop {
            DriveMode::OpenLoop
        } else {
            match expect(c.call(Request::GetTransducers)?)? {
                Response::Transducers(Some(_)) => DriveMode::Displacement,
                Response::Transducers(None) => return Err(CliError::usage(
                    "drive set: the transducers are not identified: run `fricctl device identify` \
                     first, or pass --open-loop (voltage mode: the DAC calibration taken as the \
                     displacement)",
                )),
                other => return Err(unexpected(other)),
            }
        };
    expect(c.call(Request::SetDriveMode(mode))?)?;
    Ok(())
}

/// One channel's record and fit.
struct Channel {
    name: &'static str,
    record: Vec<Sample>,
    fit: Result<Fit, fitid::FitError>,
}

fn status(c: &mut Client) -> CliResult<Status> {
    match expect(c.call(Request::GetStatus)?)? {
        Response::Status(s) => Ok(s),
        other => Err(unexpected(other)),
    }
}

/// Waits `d` of *device* time at drive frequency `f_hz`, counted in the
/// pickups' lock-in windows (`MeasuredDrive::windows`): a window is the
/// whole 64-sample ADC blocks spanning one drive period,
/// `⌈f_s/(64 f)⌉·64/f_s` s (`device::motion`). Under QEMU, or on a loaded
/// machine, device time runs slower than the host's clock: a wall-clock
/// wait would cut the settling short.
fn wait(c: &mut Client, d: Duration, f_hz: f64, fs: f64) -> CliResult {
    let block = 64.0;
    let window_s = (fs / (block * f_hz)).ceil() * block / fs;
    let n = (d.as_secs_f64() / window_s).ceil() as u64;
    let windows = |s: &Status| s.measured.map(|m| u64::from(m.windows));
    let start = Instant::now();
    let w0 = windows(&status(c)?);
    loop {
        let s = status(c)?;
        check_faults(&s)?;
        if let (Some(a), Some(b)) = (w0, windows(&s)) {
            if b.wrapping_sub(a) & 0xffff_ffff >= n {
                return Ok(());
            }
        }
        if start.elapsed() > Duration::from_secs(30) + 20 * d {
            return Err(CliError::failure(
                "identify: the device's lock-in windows do not advance (are its pickups wired?)",
            ));
        }
        let _ = c.next_telemetry(Duration::from_millis(2))?;
    }
}

/// Waits for the drive's ramps, up to `limit`.
fn wait_settled(c: &mut Client, limit: Duration) -> CliResult<Status> {
    let start = Instant::now();
    loop {
        let s = status(c)?;
        check_faults(&s)?;
        if s.settled {
            return Ok(s);
        }
        if start.elapsed() > limit {
            return Err(CliError::failure(
                "identify: the drive did not settle within 10 s",
            ));
        }
        let _ = c.next_telemetry(Duration::from_millis(5))?;
    }
}

fn check_faults(s: &Status) -> CliResult {
    if s.faults != 0 {
        let names = super::render::fault_names(s.faults).join(", ");
        let hint = if s.faults & board::device::faults::MEASURED_LIFTOFF != 0 {
            " (the normal transducer rang beyond the offset: identify it at a larger --offset-z \
             of the drive, or with a smaller response: fewer --points near the peak)"
        } else {
            ""
        };
        return Err(CliError::failure(format!(
            "identify: a fault was latched ({names}){hint}; the drive is stopped, nothing stored"
        )));
    }
    Ok(())
}

/// The mean measured response of channel `ch` over [`WINDOWS_PER_POINT`]
/// new lock-in windows, m/V.
fn response(c: &mut Client, ch: usize) -> CliResult<(f64, f64)> {
    let mut last = None;
    let (mut re, mut im, mut n) = (0.0, 0.0, 0u32);
    let start = Instant::now();
    while n < WINDOWS_PER_POINT {
        let s = status(c)?;
        check_faults(&s)?;
        if let Some(m) = s.measured {
            let r = if ch == 0 {
                m.response_z_m_per_v
            } else {
                m.response_x_m_per_v
            };
            if last != Some(m.windows) {
                if let Some([a, b]) = r {
                    re += f64::from(a);
                    im += f64::from(b);
                    n += 1;
                }
                last = Some(m.windows);
            }
        }
        if start.elapsed() > Duration::from_secs(10) {
            return Err(CliError::failure(
                "identify: the device reports no measured motion (are its pickups wired?)",
            ));
        }
    }
    Ok((re / f64::from(n), im / f64::from(n)))
}

/// Sweeps channel `ch` over `freqs` at amplitude `amp` (m of the DAC
/// calibration), appending to `rec`; returns the largest measured
/// displacement amplitude, m.
#[allow(clippy::too_many_arguments)]
fn sweep(
    c: &mut Client,
    fs: f64,
    base: &DriveSetting,
    ch: usize,
    amp: f32,
    freqs: &[f64],
    settle: Duration,
    rec: &mut Vec<(f64, f64, f64, f64)>,
) -> CliResult<f64> {
    let mut peak = 0.0f64;
    for (i, &f) in freqs.iter().enumerate() {
        let d = DriveSetting {
            freq_hz: f,
            amp_z_m: if ch == 0 { amp } else { 0.0 },
            amp_x_m: if ch == 1 { amp } else { 0.0 },
            phase_rad: 0.0,
            ..*base
        };
        expect(c.call(Request::SetDrive(d))?)?;
        if i == 0 {
            expect(c.call(Request::Start)?)?;
            wait_settled(c, Duration::from_secs(10))?;
        }
        wait(c, settle, f, fs)?;
        let (re, im) = response(c, ch)?;
        let volts =
            f64::from(amp) / f64::from(metres_per_code(ch)) * board::dds::DAC_VOLTS_PER_CODE;
        peak = peak.max(re.hypot(im) * volts);
        rec.push((f, re, im, volts));
    }
    Ok(peak)
}

/// The board's calibration of channel `ch`, m per code (as the device's).
fn metres_per_code(ch: usize) -> f32 {
    let cfg = super::sim::config();
    if ch == 0 {
        cfg.dac_z.metres_per_code
    } else {
        cfg.dac_x.metres_per_code
    }
}

fn linspace(a: f64, b: f64, n: u32) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * f64::from(i) / f64::from(n - 1))
        .collect()
}

/// `device identify`.
///
/// # Errors
/// One line: bad span, a running drive, a fault during the sweep, a fit
/// refused by name (nothing stored then).
pub fn run(c: &mut Client, a: &IdentifyArgs, json: bool) -> CliResult {
    // The overwrite policy, before the sweep (docs/guide/output-files.md).
    if let Some(p) = &a.plot {
        crate::plot::ext(p)?;
    }
    crate::output::check_outputs(&[(a.out.as_deref(), "out"), (a.plot.as_deref(), "plot")])?;
    let info = match expect(c.call(Request::Hello)?)? {
        Response::Info(i) => i,
        other => return Err(unexpected(other)),
    };
    let base = match expect(c.call(Request::GetDrive)?)? {
        Response::Drive { setting, .. } => setting,
        other => return Err(unexpected(other)),
    };
    let st = status(c)?;
    if st.running || st.measuring {
        return Err(CliError::usage(
            "identify: the drive is running: `fricctl device stop` first (identify drives each transducer alone)",
        ));
    }
    check_faults(&st)?;
    let (from, to) = span(a, &info, base.freq_hz)?;
    if base.offset_z_m <= 0.0 {
        return Err(CliError::usage(
            "identify: the drive has no normal offset: set the preload the transducers work under \
             first (`fricctl device drive set ... --offset-z M --open-loop`)",
        ));
    }
    let f_mid = 0.5 * (from + to);
    let settle = Duration::from_secs_f64(
        a.settle_ms
            .map_or(5.0 * Q_MAX / (std::f64::consts::PI * f_mid), |ms| ms * 1e-3),
    );
    let old_t = match expect(c.call(Request::GetTransducers)?)? {
        Response::Transducers(t) => t,
        other => return Err(unexpected(other)),
    };
    expect(c.call(Request::SetDriveMode(DriveMode::OpenLoop))?)?;
    let chans: &[usize] = match a.channel.as_str() {
        "z" => &[0],
        "x" => &[1],
        _ => &[0, 1],
    };
    let mut results = Vec::new();
    let t0 = Instant::now();
    for &ch in chans {
        let r = identify_channel(c, a, &info, &base, ch, (from, to), settle);
        // Stop and put the drive back whatever happened.
        let _ = c.call(Request::Stop);
        let _ = c.call(Request::SetDrive(base));
        results.push(r?);
    }
    let elapsed = t0.elapsed().as_secs_f64();
    let fits: Vec<(&Channel, &Fit)> = results
        .iter()
        .filter_map(|r| r.fit.as_ref().ok().map(|f| (r, f)))
        .collect();
    if let Some(plot) = &a.plot {
        bode(plot, &results, (from, to))?;
    }
    if let Some(bad) = results.iter().find(|r| r.fit.is_err()) {
        let e = bad
            .fit
            .as_ref()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        return Err(CliError::failure(format!(
            "identify: the {} transducer's fit was refused: {e}; nothing stored",
            bad.name
        )));
    }
    let model = |f: &Fit| TransducerModel {
        resonance_hz: f.model.resonance_hz as f32,
        q: f.model.q as f32,
        gain_m_per_v: f.model.gain_m_per_v as f32,
        phase_lag_rad: f.model.phase_lag_rad as f32,
    };
    let pick = |name: &str| {
        fits.iter()
            .find(|(r, _)| r.name == name)
            .map(|(_, f)| model(f))
    };
    let t = match (pick("normal"), pick("tangential"), old_t) {
        (Some(z), Some(x), _) => Some(Transducers { z, x }),
        (Some(z), None, Some(o)) => Some(Transducers { z, x: o.x }),
        (None, Some(x), Some(o)) => Some(Transducers { z: o.z, x }),
        _ => None,
    };
    let stored = match t {
        Some(t) if !a.no_store => {
            expect(c.call(Request::SetTransducers(Some(t)))?)?;
            true
        }
        _ => false,
    };
    let report = report(&results, stored, elapsed);
    if let Some(p) = &a.out {
        let mut f = crate::output::AtomicFile::create(p, "out")?;
        let v = report.json();
        f.write_all(
            serde_json::to_string_pretty(&v)
                .map_err(|e| CliError::failure(format!("--out: {e}")))?
                .as_bytes(),
        )?;
        f.write_all(b"\n")?;
        f.commit()?;
    }
    out(json, &report)
}

fn span(a: &IdentifyArgs, info: &Info, f: f64) -> CliResult<(f64, f64)> {
    let (lo, hi) = info.freq_range_hz;
    let from = a.from.unwrap_or(0.95 * f).max(lo);
    let to = a.to.unwrap_or(1.05 * f).min(hi);
    if from >= to {
        return Err(CliError::usage(format!(
            "--from/--to: the span [{from}, {to}] Hz is empty (the device drives {lo} … {hi} Hz)"
        )));
    }
    Ok((from, to))
}

fn identify_channel(
    c: &mut Client,
    a: &IdentifyArgs,
    info: &Info,
    base: &DriveSetting,
    ch: usize,
    (from, to): (f64, f64),
    settle: Duration,
) -> CliResult<Channel> {
    // The bound the response is scaled to: lift-off limit or largest Δu_x.
    let bound = if ch == 0 {
        f64::from(1.0 - info.liftoff_margin) * f64::from(base.offset_z_m)
    } else {
        f64::from(info.max_amp_x_m)
    };
    let mut rec = Vec::new();
    let amp0 = (0.01 * bound) as f32;
    let coarse = linspace(from, to, a.points);
    let fs = info.sample_rate_hz;
    let peak = sweep(c, fs, base, ch, amp0, &coarse, settle, &mut rec)?;
    let k = rec
        .iter()
        .enumerate()
        .max_by(|x, y| {
            let m = |r: &(f64, f64, f64, f64)| r.1.hypot(r.2);
            m(x.1).total_cmp(&m(y.1))
        })
        .map_or(0, |(i, _)| i);
    let step = (to - from) / f64::from(a.points - 1);
    let f_pk = rec[k].0;
    // Scale to PEAK_FRACTION of the bound (the DAC's range caps it: the
    // device refuses a level beyond it, named).
    let scale = if peak > 0.0 {
        PEAK_FRACTION * bound / peak
    } else {
        1.0
    };
    let amp1 = (f64::from(amp0) * scale.min(100.0)) as f32;
    let fine = linspace(
        (f_pk - 2.0 * step).max(from),
        (f_pk + 2.0 * step).min(to),
        a.fine_points,
    );
    // The fine pass settles for FINE_SETTLE_TAUS of the coarse fit's τ̂.
    let fine_settle = match (
        a.settle_ms,
        fitid::fit(&samples(&rec), None, &FitConfig::DEFAULT),
    ) {
        (None, Ok(f)) => {
            let tau = f.model.q / (std::f64::consts::PI * f.model.resonance_hz);
            Duration::from_secs_f64(FINE_SETTLE_TAUS * tau).min(settle)
        }
        _ => settle,
    };
    expect(c.call(Request::Stop)?)?;
    let mut rec = Vec::new();
    sweep(c, fs, base, ch, amp1, &fine, fine_settle, &mut rec)?;
    rec.sort_by(|x, y| x.0.total_cmp(&y.0));
    rec.dedup_by(|x, y| x.0 == y.0);
    let record = samples(&rec);
    let fit = fitid::fit(&record, None, &FitConfig::DEFAULT);
    Ok(Channel {
        name: if ch == 0 { "normal" } else { "tangential" },
        record,
        fit,
    })
}

/// A sweep's record as the fit's samples.
fn samples(rec: &[(f64, f64, f64, f64)]) -> Vec<Sample> {
    rec.iter()
        .map(|&(f, re, im, _)| Sample {
            freq_hz: f,
            re_m_per_v: re,
            im_m_per_v: im,
        })
        .collect()
}

/// JSON keys and text labels of one channel's rows (normal, tangential).
const KEYS: [[(&str, &str, &str); 13]; 2] = [
    [
        ("resonance_z_hz", "normal resonance f_r", "Hz"),
        ("resonance_z_hz_lo", "  95 % interval from", "Hz"),
        ("resonance_z_hz_hi", "  95 % interval to", "Hz"),
        ("q_z", "normal Q", ""),
        ("q_z_lo", "  95 % interval from", ""),
        ("q_z_hi", "  95 % interval to", ""),
        ("gain_z_m_per_v", "normal static gain", "m/V"),
        ("gain_z_m_per_v_lo", "  95 % interval from", "m/V"),
        ("gain_z_m_per_v_hi", "  95 % interval to", "m/V"),
        ("phase_lag_z_deg", "normal extra lag", "deg"),
        ("tau_z_ms", "normal tau = Q/(pi f_r)", "ms"),
        ("fit_rms_z_pct", "normal fit residual (RMS)", "%"),
        ("points_z", "normal points", ""),
    ],
    [
        ("resonance_x_hz", "tangential resonance f_r", "Hz"),
        ("resonance_x_hz_lo", "  95 % interval from", "Hz"),
        ("resonance_x_hz_hi", "  95 % interval to", "Hz"),
        ("q_x", "tangential Q", ""),
        ("q_x_lo", "  95 % interval from", ""),
        ("q_x_hi", "  95 % interval to", ""),
        ("gain_x_m_per_v", "tangential static gain", "m/V"),
        ("gain_x_m_per_v_lo", "  95 % interval from", "m/V"),
        ("gain_x_m_per_v_hi", "  95 % interval to", "m/V"),
        ("phase_lag_x_deg", "tangential extra lag", "deg"),
        ("tau_x_ms", "tangential tau = Q/(pi f_r)", "ms"),
        ("fit_rms_x_pct", "tangential fit residual (RMS)", "%"),
        ("points_x", "tangential points", ""),
    ],
];

fn report(results: &[Channel], stored: bool, elapsed: f64) -> Report {
    let mut r = Report::default();
    for ch in results {
        let Ok(f) = &ch.fit else { continue };
        let keys = &KEYS[usize::from(ch.name != "normal")];
        let tau_ms = 1e3 * f.q.value / (std::f64::consts::PI * f.resonance_hz.value);
        let vals = [
            f.resonance_hz.value,
            f.resonance_hz.lo,
            f.resonance_hz.hi,
            f.q.value,
            f.q.lo,
            f.q.hi,
            f.gain_m_per_v.value,
            f.gain_m_per_v.lo,
            f.gain_m_per_v.hi,
            f.phase_lag_rad.value.to_degrees(),
            tau_ms,
            100.0 * f.rel_rms,
            f.points as f64,
        ];
        for ((k, l, u), v) in keys.iter().zip(vals) {
            r = r.row(k, l, sig(v), u);
        }
    }
    r.row("stored", "stored on the device", stored, "").row(
        "elapsed_s",
        "elapsed",
        (elapsed * 10.0).round() / 10.0,
        "s",
    )
}

/// `x` to 7 significant digits (the fit's f32 on the device holds about as many).
fn sig(x: f64) -> f64 {
    format!("{x:.6e}").parse().unwrap_or(x)
}

/// The Bode plot: measured points and fitted curves of each channel.
fn bode(path: &std::path::Path, results: &[Channel], (from, to): (f64, f64)) -> CliResult {
    use plotters::prelude::*;
    crate::plot::ext(path)?;
    crate::plot::write_chart(path, (900, 700), |root| {
        root.fill(&WHITE)?;
        let (top, bottom) = root.split_vertically(350);
        let xs = linspace(from, to, 600);
        // Magnitudes and phases (unwrapped from 0 down: a mode's lag).
        let mag_of = |re: f64, im: f64| re.hypot(im);
        let unwrap = |v: &mut Vec<f64>| {
            for i in 0..v.len() {
                let prev = if i == 0 { 0.0 } else { v[i - 1] };
                while v[i] - prev > 180.0 {
                    v[i] -= 360.0;
                }
                while v[i] - prev < -180.0 {
                    v[i] += 360.0;
                }
            }
        };
        let phases = |pts: &[(f64, f64)]| {
            let mut v: Vec<f64> = pts
                .iter()
                .map(|&(re, im)| im.atan2(re).to_degrees())
                .collect();
            unwrap(&mut v);
            v
        };
        let mut top_mag = 0.0f64;
        let mut low_mag = f64::INFINITY;
        for ch in results {
            for s in &ch.record {
                let m = mag_of(s.re_m_per_v, s.im_m_per_v);
                top_mag = top_mag.max(m);
                low_mag = low_mag.min(m);
            }
        }
        if !(low_mag > 0.0 && top_mag > low_mag) {
            (low_mag, top_mag) = (1e-9, 1e-4);
        }
        let mut mag = ChartBuilder::on(&top)
            .caption(
                "Transducers: measured response X/U (points) and fitted mode (lines)",
                ("sans-serif", 20),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(80)
            .build_cartesian_2d(from..to, (low_mag / 2.0..top_mag * 20.0).log_scale())?;
        mag.configure_mesh()
            .y_desc("|H|, m/V")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| crate::plot::log_axis_tick(*v))
            .draw()?;
        let mut ph = ChartBuilder::on(&bottom)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(from..to, -225f64..45f64)?;
        ph.configure_mesh()
            .x_desc("drive frequency, Hz")
            .y_desc("arg H (unwrapped), deg")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .draw()?;
        // Curves through exact pixel positions (`plot::fine_line`: plotters
        // itself rounds to whole pixels, a staircase when zoomed).
        let (ylo, yhi) = (low_mag / 2.0, top_mag * 20.0);
        let pm_mag =
            crate::plot::PixelMap::of(mag.plotting_area(), (from, to, false), (ylo, yhi, true));
        let pm_ph =
            crate::plot::PixelMap::of(ph.plotting_area(), (from, to, false), (-225.0, 45.0, false));
        for (i, ch) in results.iter().enumerate() {
            let col = crate::plot::color(i);
            let pts: Vec<(f64, f64)> = ch
                .record
                .iter()
                .map(|s| (s.re_m_per_v, s.im_m_per_v))
                .collect();
            let pph = phases(&pts);
            mag.draw_series(ch.record.iter().map(|s| {
                Circle::new(
                    (s.freq_hz, mag_of(s.re_m_per_v, s.im_m_per_v)),
                    3,
                    col.filled(),
                )
            }))?
            .label(format!("{} transducer, measured", ch.name))
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, col.filled()));
            ph.draw_series(
                ch.record
                    .iter()
                    .zip(&pph)
                    .map(|(s, &p)| Circle::new((s.freq_hz, p), 3, col.filled())),
            )?;
            if let Ok(f) = &ch.fit {
                let model: Vec<(f64, f64)> = xs.iter().map(|&x| f.model.response(x)).collect();
                let mph = phases(&model);
                let mag_pts: Vec<(f64, f64)> = xs
                    .iter()
                    .zip(&model)
                    .map(|(&x, &(re, im))| (x, mag_of(re, im)))
                    .collect();
                let k = crate::plot::fine_line(&pm_mag, &mag_pts, col, 2, None);
                mag.draw_series(LineSeries::new(mag_pts, k.stroke_width(2)))?
                    .label(format!(
                        "{} fit: f_r {:.1} Hz, Q {:.0}, g {:.3e} m/V",
                        ch.name, f.resonance_hz.value, f.q.value, f.gain_m_per_v.value
                    ))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2))
                    });
                let ph_pts: Vec<(f64, f64)> = xs.iter().copied().zip(mph).collect();
                let k = crate::plot::fine_line(&pm_ph, &ph_pts, col, 2, None);
                ph.draw_series(LineSeries::new(ph_pts, k.stroke_width(2)))?;
            }
        }
        mag.configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    })
}
