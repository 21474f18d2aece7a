//! One measurement of μ (`fricctl device measure`): wait for the drive's
//! ramps, open a window of a number of drive periods, wait for it to close
//! in device time, read the estimate and the motion the pickups measured.
//! An interruption or a window that never closes ends the measurement on
//! the device with `Reset` (the protocol's one request that ends a
//! measurement: streams end too and the drive ramps down, settings kept).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use board::device::MeasuredDrive;
use board::estimator::Estimate;
use board::protocol::{Request, Response, Telemetry};

use crate::answers::{expect, unexpected};
use crate::client::Client;
use crate::{Error, Result};

/// The longest wait for the ramps to settle (a full-scale ramp at the
/// slowest slew rate the device accepts takes well under this).
pub const SETTLE_LIMIT: Duration = Duration::from_secs(60);

/// A measurement's result.
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    /// The estimate (shown even when invalid: [`Estimate::valid`] says so).
    pub estimate: Estimate,
    /// The drive that ran: the pickups' measured motion at the end (the
    /// last window, or in displacement mode its 1 ms average).
    pub measured: Option<MeasuredDrive>,
}

/// Waits until the device's ramps have settled (`Status::settled`), so that
/// a measurement right after `start` or a new drive measures the drive it
/// was given. `note` hears "waiting …" after 0.5 s and "ramps settled after
/// … s" then (a wait a person notices; the ramps of a small change take
/// milliseconds). `interrupted` ends the wait (nothing to undo).
///
/// # Errors
/// Interrupted, not settled within [`SETTLE_LIMIT`], a lost link.
pub fn wait_settled(
    c: &mut Client,
    interrupted: &AtomicBool,
    note: &mut dyn FnMut(&str),
) -> Result<()> {
    let start = Instant::now();
    let mut said = false;
    loop {
        if let Response::Status(s) = expect(c.call(Request::GetStatus)?)? {
            if s.settled {
                if said {
                    note(&format!(
                        "ramps settled after {:.1} s",
                        start.elapsed().as_secs_f64()
                    ));
                }
                return Ok(());
            }
        }
        if !said && start.elapsed() > Duration::from_millis(500) {
            note("waiting for the ramps to settle (--no-wait measures at once)");
            said = true;
        }
        if interrupted.load(Ordering::SeqCst) {
            return Err(Error::failure("interrupted while waiting for the ramps"));
        }
        if start.elapsed() > SETTLE_LIMIT {
            return Err(Error::failure(format!(
                "the ramps did not settle within {} s (`fricctl device status` shows the drive)",
                SETTLE_LIMIT.as_secs()
            )));
        }
        let _ = c.next_telemetry(Duration::from_millis(20))?;
    }
}

/// Measures μ over `periods` drive periods (module documentation); with
/// `wait` the ramps are waited for first ([`wait_settled`]).
///
/// # Errors
/// The device's refusal, an interruption or a window that does not close
/// within 4 times its length plus 10 s (the measurement is then aborted on
/// the device, and the message says whether that worked), a lost link.
pub fn measure(
    c: &mut Client,
    periods: u32,
    wait: bool,
    interrupted: &AtomicBool,
    note: &mut dyn FnMut(&str),
) -> Result<Measured> {
    // The window lasts periods/f of device time: wait 4 times that plus
    // 10 s (ramps, the window opening at a wrap, a virtual device that
    // falls behind real time on a loaded machine), then give up.
    let f = match expect(c.call(Request::GetDrive)?)? {
        Response::Drive { applied, .. } => applied.achieved.freq_hz,
        other => return Err(unexpected(other)),
    };
    let window_s = f64::from(periods) / f.max(1.0);
    let was_running = match expect(c.call(Request::GetStatus)?)? {
        Response::Status(s) => s.running,
        other => return Err(unexpected(other)),
    };
    let limit = Duration::from_secs_f64(4.0 * window_s + 10.0);
    if wait {
        wait_settled(c, interrupted, note)?;
    }
    expect(c.call(Request::Measure { periods })?)?;
    // Wait for the window to close (a virtual device advances meanwhile);
    // an interruption seen by the client (its flag or poll) ends the
    // measurement on the device as the caller's flag does.
    if let Err(e) = wait_window(c, interrupted, limit) {
        let why = match e {
            Window::Interrupted => "interrupted".to_string(),
            Window::TooLong => format!(
                "no estimate within {:.0} s, though {periods} periods at {f:.3} Hz take \
                 {window_s:.3} s (is the device sampling its ADC?)",
                limit.as_secs_f64()
            ),
            Window::Failed(e) => return Err(e),
        };
        return Err(c.uninterrupted(|c| abort(c, why, was_running)));
    }
    let r = expect(c.call(Request::GetEstimate)?)?;
    let Response::Estimate(estimate) = r else {
        return Err(unexpected(r));
    };
    let measured = match expect(c.call(Request::GetStatus)?)? {
        Response::Status(st) => st.measured,
        other => return Err(unexpected(other)),
    };
    Ok(Measured { estimate, measured })
}

/// Why the wait for a window ended early.
enum Window {
    Interrupted,
    TooLong,
    Failed(Error),
}

/// Waits until the device no longer measures.
fn wait_window(
    c: &mut Client,
    interrupted: &AtomicBool,
    limit: Duration,
) -> std::result::Result<(), Window> {
    let start = Instant::now();
    let step = |c: &mut Client| -> Result<bool> {
        let _ = c.next_telemetry(Duration::from_millis(20))?;
        match expect(c.call(Request::GetStatus)?)? {
            Response::Status(s) => Ok(!s.measuring),
            _ => Ok(false),
        }
    };
    loop {
        if interrupted.load(Ordering::SeqCst) {
            return Err(Window::Interrupted);
        }
        match step(c) {
            Ok(true) => return Ok(()),
            Ok(false) => {}
            Err(e) if e.code == 130 => return Err(Window::Interrupted),
            Err(e) => return Err(Window::Failed(e)),
        }
        if start.elapsed() > limit {
            return Err(Window::TooLong);
        }
    }
}

/// Ends the measurement on the device (`Reset`, which also ramps the drive
/// down), starts the drive again if it was running, and says `why`.
fn abort(c: &mut Client, why: String, was_running: bool) -> Error {
    match c.call(Request::Reset).map(expect) {
        Ok(Ok(_)) if was_running => match c.call(Request::Start).map(expect) {
            Ok(Ok(_)) => Error::failure(format!(
                "{why}; measurement aborted (device reset, the drive started again, settings kept)"
            )),
            Ok(Err(e)) | Err(e) => Error::failure(format!(
                "{why}; measurement aborted (device reset, settings kept), but the drive could not be started again ({}); `fricctl device start` starts it",
                e.msg
            )),
        },
        Ok(Ok(_)) => Error::failure(format!(
            "{why}; measurement aborted (device reset, settings kept)"
        )),
        Ok(Err(e)) | Err(e) => Error::failure(format!(
            "{why}, but the measurement could not be aborted ({}); `fricctl device reset` ends it",
            e.msg
        )),
    }
}

/// A stream of estimates on the device (`Stream`), read one at a time
/// ([`Stream::next`]) and stopped by [`Stream::stop`].
pub struct Stream {
    periods: u32,
    patience: Duration,
}

impl Stream {
    /// Starts the device's stream of estimates of `periods` periods each.
    ///
    /// # Errors
    /// The device's refusal (busy, a fault), a lost link.
    pub fn start(c: &mut Client, periods: u32) -> Result<Stream> {
        let f = match expect(c.call(Request::GetDrive)?)? {
            Response::Drive { applied, .. } => applied.achieved.freq_hz,
            other => return Err(unexpected(other)),
        };
        expect(c.call(Request::Stream { on: true, periods })?)?;
        // What came before the stream's `Ok` is an earlier session's.
        c.discard_telemetry();
        Ok(Stream {
            periods,
            patience: Duration::from_secs_f64(10.0 + 10.0 * f64::from(periods) / f.max(1.0)),
        })
    }

    /// The handle of a stream of `periods` periods already on the device
    /// (to stop it).
    pub fn for_periods(periods: u32) -> Stream {
        Stream {
            periods,
            patience: Duration::from_secs(10),
        }
    }

    /// The next estimate.
    ///
    /// # Errors
    /// A stream the device stopped (`StreamStopped` with its reason), no
    /// estimate for 10 s plus 10 windows, an interruption, a lost link.
    pub fn next(&self, c: &mut Client) -> Result<Estimate> {
        let start = Instant::now();
        loop {
            match c.next_telemetry(Duration::from_millis(20))? {
                Some((_, Telemetry::Estimate(e))) => return Ok(e),
                Some((_, Telemetry::StreamStopped(why))) => {
                    return Err(Error::failure(format!(
                        "the device stopped the stream: {why:?}"
                    )));
                }
                Some(_) => {}
                None if start.elapsed() > self.patience => {
                    return Err(Error::failure(format!(
                        "no estimate from the stream within {:.0} s",
                        self.patience.as_secs_f64()
                    )));
                }
                None => {}
            }
        }
    }

    /// Stops the stream (also after an interruption).
    ///
    /// # Errors
    /// The device did not confirm: `fricctl device reset` ends it.
    pub fn stop(&self, c: &mut Client) -> Result<()> {
        let periods = self.periods;
        c.uninterrupted(|c| {
            c.call(Request::Stream { on: false, periods })
                .and_then(expect)
        })
        .map(drop)
        .map_err(|e| {
            Error::failure(format!(
                "could not stop the stream ({}); `fricctl device reset` ends it",
                e.msg
            ))
        })
    }
}

/// `count` estimates of `periods` periods each from the device's stream,
/// the stream stopped on every way out (an error, an interruption).
///
/// # Errors
/// As [`Stream::start`] and [`Stream::next`]; a stream that could not be
/// stopped.
pub fn stream(c: &mut Client, periods: u32, count: usize) -> Result<Vec<Estimate>> {
    let s = Stream::start(c, periods)?;
    let r: Result<Vec<Estimate>> = (0..count).map(|_| s.next(c)).collect();
    let off = s.stop(c);
    let est = r?;
    off?;
    Ok(est)
}
