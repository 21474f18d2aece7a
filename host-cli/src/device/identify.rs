//! `fricctl device identify`: the flags, text, JSON, the `--out` file and
//! the Bode plot of [`device_host::identify`] (the sweep and the fit, whose
//! documentation says how they run).

use std::path::PathBuf;

pub use device_host::identify::*;

use super::client::Client;
use super::out;
use super::render::Report;
use crate::args::{Count, Real};
use crate::error::{CliError, CliResult};

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

impl IdentifyArgs {
    /// The identification the flags ask for.
    pub fn options(&self) -> IdentifyOptions {
        IdentifyOptions {
            from: self.from,
            to: self.to,
            points: self.points,
            fine_points: self.fine_points,
            settle_ms: self.settle_ms,
            channels: match self.channel.as_str() {
                "z" => Channels::Z,
                "x" => Channels::X,
                _ => Channels::Both,
            },
        }
    }
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
    // Each transducer is driven alone in voltage mode for the sweep: the
    // drive, its mode and options are put back on every way out (the end, a
    // refused fit, an error, SIGINT or SIGTERM).
    let id = device_host::state::restoring(c, |c| identify(c, &a.options()))?;
    if let Some(plot) = &a.plot {
        crate::figures::bode::bode(plot, &id.channels, id.span_hz)?;
    }
    if let Some(e) = id.refused() {
        return Err(e);
    }
    // The file is opened before the device stores anything: a file that
    // cannot be created leaves the device's transducers as they were.
    let file = match &a.out {
        Some(p) => Some(crate::output::AtomicFile::create(p, "out")?),
        None => None,
    };
    let stored = !a.no_store && id.store(c)?;
    let report = report(&id.channels, stored, id.elapsed_s);
    if let Some(mut f) = file {
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

fn report(results: &[ChannelFit], stored: bool, elapsed: f64) -> Report {
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
