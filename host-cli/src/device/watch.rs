//! `fricctl device watch`: streamed estimates until `--count`, Ctrl-C, a
//! closed stdout or an invalid estimate — and on every one of those exits the
//! stream is stopped on the device, so that the next `measure` is not `Busy`.
//! While the closed loop runs it shows the loop's updates instead (setpoint,
//! measured μ, commanded Δu_z).

use std::io::{IsTerminal, Write};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use board::protocol::{Request, StreamEnd, Telemetry};

use super::client::Client;
use super::render::{self, reason_names};
use super::{check_valid, expect, open, Target};
use crate::error::{CliError, CliResult};

/// Columns of `watch --csv` (docs/device-json.md).
pub const CSV_HEADER: &str =
    "seq,dropped,mu,std_error,valid,reasons,periods,samples,saturated,fx_mean,fz_mean";

/// A flag set by Ctrl-C (SIGINT), SIGTERM (`timeout`, `kill`) or SIGHUP (the
/// terminal closed) once the handler is installed.
pub(super) fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    let _ = ctrlc::set_handler(move || f.store(true, Ordering::SeqCst));
    flag
}

/// Why the loop ended.
enum End {
    /// `--count` estimates shown.
    Count,
    /// Ctrl-C.
    Interrupted,
    /// stdout closed (e.g. `| head`).
    StdoutClosed,
    /// An error to report (the stream is stopped first).
    Failed(CliError),
}

/// Runs `watch`; the stream is stopped before returning, whatever the end.
pub fn watch(
    t: &Target,
    c: &mut Client,
    stop: &AtomicBool,
    periods: u32,
    count: Option<u64>,
    csv: Option<&Path>,
    allow_invalid: bool,
) -> CliResult {
    // The CSV exists with its header before the first request.
    let mut file = match csv {
        Some(p) => {
            // The overwrite policy of every output file (`--force`).
            crate::output::may_write(p, "csv")?;
            let mut f = std::fs::File::create(p)
                .map_err(|e| CliError::failure(format!("--csv: {}: {e}", p.display())))?;
            f.write_all(format!("{CSV_HEADER}\n").as_bytes())
                .and_then(|()| f.flush())
                .map_err(|e| CliError::failure(format!("--csv: {}: {e}", p.display())))?;
            Some(f)
        }
        None => None,
    };
    let r = watch_body(t, c, stop, periods, count, &mut file, allow_invalid);
    // A file with its header only (the command failed or was interrupted
    // before the first estimate, or the closed loop's updates were shown)
    // is removed: no header-only file is left (docs/guide/output-files.md).
    if let (Some(p), Some(f)) = (csv, file) {
        let header_only = f
            .metadata()
            .is_ok_and(|m| m.is_file() && m.len() <= CSV_HEADER.len() as u64 + 1);
        drop(f);
        // Only a regular file: never a device or FIFO (`--csv /dev/null`).
        if header_only && std::fs::symlink_metadata(p).is_ok_and(|m| m.is_file()) {
            let _ = std::fs::remove_file(p);
        }
    }
    r
}

/// `watch` after the file is created: the closed loop's updates, or the
/// stream, stopped on every way out.
fn watch_body(
    t: &Target,
    c: &mut Client,
    stop: &AtomicBool,
    periods: u32,
    count: Option<u64>,
    file: &mut Option<std::fs::File>,
    allow_invalid: bool,
) -> CliResult {
    // While the closed loop runs the estimator is the loop's: show its updates.
    if let board::protocol::Response::Control(st) = expect(c.call(Request::GetControl)?)? {
        if st.setting.on {
            return control_loop(t, c, count, stop);
        }
    }
    expect(c.call(Request::Stream { on: true, periods })?)?;
    // What came before the stream's `Ok` is an earlier session's (its
    // `StreamStopped`, a late estimate): not this stream's.
    c.discard_telemetry();
    let end = stream_loop(t, c, periods, count, file, allow_invalid, stop);
    // Stop the stream on every exit path (a failed stop is said, not hidden).
    let stopped = c.call(Request::Stream { on: false, periods });
    let stop_err = match stopped {
        Ok(r) => expect(r).err(),
        Err(e) => Some(e),
    };
    match end {
        End::Count | End::StdoutClosed => {}
        End::Interrupted => eprintln!("interrupted: stream stopped"),
        End::Failed(e) => return Err(e),
    }
    match stop_err {
        Some(e) => Err(CliError::failure(format!(
            "could not stop the stream ({}); `fricctl device reset` ends it",
            e.msg
        ))),
        None => Ok(()),
    }
}

fn stream_loop(
    t: &Target,
    c: &mut Client,
    periods: u32,
    count: Option<u64>,
    file: &mut Option<std::fs::File>,
    allow_invalid: bool,
    stop: &AtomicBool,
) -> End {
    let live = !t.json && std::io::stdout().is_terminal();
    let mut out = std::io::stdout().lock();
    let mut last_seq: Option<u32> = None;
    let mut n = 0u64;
    let mut idle = Instant::now();
    let end = loop {
        if count.is_some_and(|k| n >= k) {
            break End::Count;
        }
        if stop.load(Ordering::SeqCst) {
            break End::Interrupted;
        }
        let got = match c.next_telemetry(Duration::from_millis(200)) {
            Ok(g) => g,
            Err(e) => {
                // The link is gone: reconnect (same target) for up to 30 s.
                eprintln!("{}; reconnecting", e.msg);
                match reconnect(t, periods, stop) {
                    Ok(new) => *c = new,
                    Err(e) => break End::Failed(e),
                }
                last_seq = None;
                idle = Instant::now();
                continue;
            }
        };
        match got {
            Some((seq, Telemetry::Estimate(e))) => {
                idle = Instant::now();
                let dropped = last_seq.map_or(0, |l| seq.wrapping_sub(l).saturating_sub(1));
                last_seq = Some(seq);
                n += 1;
                let shown = if t.json {
                    let mut v = render::estimate(&e).json();
                    if let Some(o) = v.as_object_mut() {
                        o.insert("seq".into(), seq.into());
                        o.insert("dropped".into(), dropped.into());
                    }
                    writeln!(out, "{v}")
                } else {
                    let line = text_line(seq, &e, dropped);
                    if live {
                        // One line, updated in place.
                        write!(out, "\r\x1b[2K{line}")
                    } else {
                        writeln!(out, "{line}")
                    }
                };
                if shown.and_then(|()| out.flush()).is_err() {
                    break End::StdoutClosed;
                }
                if let Some(f) = file.as_mut() {
                    // One write per row, flushed: a reader never sees half a row.
                    let row = format!(
                        "{seq},{dropped},{},{},{},{},{},{},{},{},{}\n",
                        render::f32v(e.mu),
                        render::f32v(e.std_error),
                        e.valid(),
                        reason_names(e.reasons).join(" "),
                        e.periods,
                        e.samples,
                        e.saturated,
                        render::f32v(e.fx_mean),
                        render::f32v(e.fz_mean),
                    );
                    if let Err(err) = f.write_all(row.as_bytes()).and_then(|()| f.flush()) {
                        break End::Failed(CliError::failure(format!("--csv: {err}")));
                    }
                }
                if let Err(err) = check_valid(&e, allow_invalid) {
                    break End::Failed(err);
                }
            }
            Some((_, Telemetry::StreamStopped(end))) => {
                break End::Failed(CliError::failure(match end {
                    StreamEnd::Requested => {
                        "the stream was stopped (by another request)".to_string()
                    }
                    StreamEnd::Reset => "the stream was ended by a device reset".to_string(),
                    StreamEnd::Refused(e) => format!("the device ended the stream: {e}"),
                }));
            }
            Some(_) => {}
            None => {
                if idle.elapsed() > Duration::from_secs(10) {
                    break End::Failed(CliError::failure(format!(
                        "no estimate from {} for 10 s",
                        c.describe()
                    )));
                }
            }
        }
    };
    if live {
        let _ = writeln!(out);
    }
    end
}

/// A standard error in a `watch` line: `7.94e-7`, or `n/a` for the 0 of
/// an estimate with fewer than two batches (not estimated; not an error of 0).
fn std_error_text(x: f32) -> String {
    if x > 0.0 {
        format!("{x:.2e}")
    } else {
        "n/a".to_string()
    }
}

/// One text line of `watch`.
fn text_line(seq: u32, e: &board::estimator::Estimate, dropped: u32) -> String {
    format!(
        "#{seq:<6} mu {:>10.6} ± {:<9} fx {:>9.4} N  fz {:>9.4} N  {} periods{}{}",
        e.mu,
        std_error_text(e.std_error),
        e.fx_mean,
        e.fz_mean,
        e.periods,
        if e.valid() {
            String::new()
        } else {
            format!("  INVALID ({})", reason_names(e.reasons).join(", "))
        },
        if dropped > 0 {
            format!("  ({dropped} dropped)")
        } else {
            String::new()
        }
    )
}

fn reconnect(t: &Target, periods: u32, stop: &AtomicBool) -> CliResult<Client> {
    let start = Instant::now();
    loop {
        if stop.load(Ordering::SeqCst) {
            return Err(CliError::failure("interrupted while reconnecting"));
        }
        if let Ok(mut c) = open(t) {
            if c.call(Request::Stream { on: true, periods }).is_ok() {
                c.discard_telemetry();
                eprintln!("reconnected to {}", c.describe());
                return Ok(c);
            }
        }
        if start.elapsed() > Duration::from_secs(30) {
            return Err(CliError::failure(
                "the device is gone (no reconnection within 30 s)",
            ));
        }
        std::thread::sleep(Duration::from_secs(1));
    }
}

/// `watch` while the closed loop runs: one line (or JSON object) per
/// `Control` telemetry frame — setpoint, measured μ, commanded Δu_z — until
/// `--count`, Ctrl-C or a closed stdout. Nothing to stop on the device.
fn control_loop(t: &Target, c: &mut Client, count: Option<u64>, stop: &AtomicBool) -> CliResult {
    let mut out = std::io::stdout().lock();
    let mut n = 0u64;
    let mut idle = Instant::now();
    while count.is_none_or(|k| n < k) {
        if stop.load(Ordering::SeqCst) {
            eprintln!("interrupted");
            return Ok(());
        }
        match c.next_telemetry(Duration::from_millis(200))? {
            Some((_, Telemetry::Control(u))) => {
                idle = Instant::now();
                n += 1;
                let shown = if t.json {
                    writeln!(out, "{}", render::control_update(&u).json())
                } else {
                    writeln!(
                        out,
                        "#{:<6} setpoint {:>9.6}  measured {:>9.6} ± {:<9} duz {:>11.4e} m{}{}",
                        u.update,
                        u.target_mu,
                        u.measured_mu,
                        std_error_text(u.std_error),
                        u.amp_z_m,
                        if u.saturated { "  limited" } else { "" },
                        if u.held {
                            "  HELD (estimate not usable)"
                        } else {
                            ""
                        }
                    )
                };
                if shown.and_then(|()| out.flush()).is_err() {
                    return Ok(());
                }
            }
            Some(_) => {}
            None => {
                if idle.elapsed() > Duration::from_secs(10) {
                    return Err(CliError::failure(format!(
                        "no closed-loop update from {} for 10 s (loop off?)",
                        c.describe()
                    )));
                }
            }
        }
    }
    Ok(())
}
