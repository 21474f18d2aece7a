//! `fricctl device identify`: the flags, text, JSON, the `--out` file and
//! the Bode plot of [`device_host::identify`] (the sweep and the fit, whose
//! documentation says how they run).

use std::path::PathBuf;

pub use device_host::identify::*;

use super::client::Client;
use super::out;
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
    let mut bar = progress_bar(json);
    let id = device_host::state::restoring(c, |c| {
        identify_with_progress(c, &a.options(), &mut |p| bar.show(p))
    });
    bar.finish();
    let id = id?;
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
    let report = super::render::identification(&id.channels, stored, id.elapsed_s);
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

/// The identification's progress on a terminal (not with `--json`): its
/// plan up front when it may take over 5 s of device time, then a bar of
/// the frequencies measured.
struct Bar {
    bar: Option<indicatif::ProgressBar>,
    said: bool,
    live: bool,
}

fn progress_bar(json: bool) -> Bar {
    Bar {
        bar: None,
        said: false,
        live: !json && std::io::IsTerminal::is_terminal(&std::io::stderr()),
    }
}

impl Bar {
    fn show(&mut self, p: Progress) {
        if !self.live {
            return;
        }
        if !self.said {
            self.said = true;
            if p.device_s_max > 5.0 {
                eprintln!(
                    "identify: {} frequencies, at most {:.0} s of device time",
                    p.points, p.device_s_max
                );
            }
            let b = indicatif::ProgressBar::new(u64::from(p.points));
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} frequencies  [{elapsed_precise}, eta {eta}]",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            self.bar = Some(b);
        }
        if let Some(b) = &self.bar {
            b.set_position(u64::from(p.done));
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
