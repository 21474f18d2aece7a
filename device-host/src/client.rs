//! The host side of the protocol: requests with sequence numbers, timeouts,
//! retries with the same sequence number, telemetry kept aside.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use board::protocol::{
    decode, encode, Body, Deframed, Deframer, Frame, Request, Response, Telemetry, MAX_FRAME,
    PROTOCOL_VERSION,
};

use crate::link::Link;
use crate::Error;

/// A protocol client over a link.
pub struct Client {
    link: Box<dyn Link>,
    seq: u32,
    deframer: Deframer,
    /// Per-attempt timeout.
    pub timeout: Duration,
    /// Attempts per request (≥ 1).
    pub attempts: u32,
    telemetry: VecDeque<(u32, Telemetry)>,
    opened: Instant,
    /// Set by a signal handler: every request and wait then ends with
    /// [`Error::interrupted`] (see [`Client::interrupt_on`]).
    interrupt: Option<Arc<AtomicBool>>,
    /// Asked before each request and wait: true ends the procedure as the
    /// flag does (Python's pending KeyboardInterrupt).
    poll: Option<Box<dyn Fn() -> bool + Send>>,
}

impl Client {
    /// A client over `link`.
    pub fn new(link: Box<dyn Link>, timeout: Duration, attempts: u32) -> Self {
        let opened = link.now();
        Client {
            link,
            seq: session_seq(),
            deframer: Deframer::default(),
            timeout,
            attempts: attempts.max(1),
            telemetry: VecDeque::new(),
            opened,
            interrupt: None,
            poll: None,
        }
    }

    /// From now on, a request or a wait while `flag` is set ends with the
    /// error [`interrupted`] (exit status 130) instead of reaching the
    /// device: a long procedure (identify, a sweep) stops at its next
    /// request, and its caller puts the device back
    /// ([`crate::state::restoring`]) with [`Client::uninterrupted`].
    pub fn interrupt_on(&mut self, flag: Arc<AtomicBool>) {
        self.interrupt = Some(flag);
    }

    /// As [`Client::interrupt_on`], asking `poll` before each request and
    /// wait (e.g. whether Python has a `KeyboardInterrupt` pending); once it
    /// answers true the client stays interrupted.
    pub fn interrupt_when(&mut self, poll: Box<dyn Fn() -> bool + Send>) {
        if self.interrupt.is_none() {
            self.interrupt = Some(Arc::new(AtomicBool::new(false)));
        }
        self.poll = Some(poll);
    }

    /// Whether the interrupt flag is set (or the poll says so).
    pub fn interrupted(&self) -> bool {
        let Some(flag) = &self.interrupt else {
            return false;
        };
        if !flag.load(Ordering::SeqCst) && self.poll.as_ref().is_some_and(|p| p()) {
            flag.store(true, Ordering::SeqCst);
        }
        flag.load(Ordering::SeqCst)
    }

    /// Clears the interrupt flag (a new call after an interruption).
    pub fn clear_interrupt(&mut self) {
        if let Some(f) = &self.interrupt {
            f.store(false, Ordering::SeqCst);
        }
    }

    /// Runs `f` with the interrupt flag ignored (the clean-up after an
    /// interruption must reach the device).
    pub fn uninterrupted<T>(&mut self, f: impl FnOnce(&mut Client) -> T) -> T {
        let saved = self.interrupt.take();
        let r = f(self);
        self.interrupt = saved;
        r
    }

    fn check_interrupt(&self) -> Result<(), Error> {
        if self.interrupted() {
            Err(interrupted())
        } else {
            Ok(())
        }
    }

    /// What answered.
    pub fn describe(&self) -> String {
        self.link.describe()
    }

    /// Sends a request and waits for its response (same `seq`), retrying on
    /// timeout with the same `seq`.
    pub fn call(&mut self, req: Request) -> Result<Response, Error> {
        self.check_interrupt()?;
        self.seq = self.seq.wrapping_add(1);
        let seq = self.seq;
        let frame = Frame {
            version: PROTOCOL_VERSION,
            seq,
            body: Body::Request(req),
        };
        let mut buf = [0u8; MAX_FRAME];
        let bytes = encode(&frame, &mut buf)
            .map_err(|_| Error::failure("request too large for one frame"))?
            .to_vec();
        for _ in 0..self.attempts {
            self.link.send(&bytes).map_err(|e| gone(&*self.link, &e))?;
            let deadline = self.link.now() + self.timeout;
            while self.link.now() < deadline {
                if let Some(f) = self.next_frame(deadline)? {
                    match f.body {
                        Body::Response(r) if f.seq == seq => return Ok(r),
                        Body::Telemetry(t) => self.telemetry.push_back((f.seq, t)),
                        // A stale response to an earlier attempt, or an error for garbage: skip.
                        _ => {}
                    }
                }
            }
        }
        let what = self.link.describe();
        // Over TCP the usual stranger is another emulator or server on the
        // same port (a second QEMU on 7777): say so.
        let hint = if what.starts_with("tcp ") {
            "; if another program (a second QEMU, an older sim-device) holds that port, start the device on a free one"
        } else {
            ""
        };
        Err(Error::failure(format!(
            "no answer from {what} after {} attempts of {} ms (device gone or not speaking protocol v{PROTOCOL_VERSION}){hint}",
            self.attempts,
            self.timeout.as_millis()
        )))
    }

    /// Forgets the telemetry received so far. The link is in order, so every
    /// telemetry frame read before the response to a request was sent before
    /// the device handled that request: called right after the request that
    /// starts a session (`Stream { on: true }`), it drops what belongs to an
    /// earlier session on the same link — the previous `watch`'s
    /// `StreamStopped`, a late estimate of its stream. Returns how many.
    pub fn discard_telemetry(&mut self) -> usize {
        let n = self.telemetry.len();
        self.telemetry.clear();
        n
    }

    /// Waits up to `timeout` for one telemetry frame.
    pub fn next_telemetry(&mut self, timeout: Duration) -> Result<Option<(u32, Telemetry)>, Error> {
        if let Some(t) = self.telemetry.pop_front() {
            return Ok(Some(t));
        }
        let deadline = self.link.now() + timeout;
        while self.link.now() < deadline {
            self.check_interrupt()?;
            if let Some(f) = self.next_frame(deadline)? {
                if let Body::Telemetry(t) = f.body {
                    return Ok(Some((f.seq, t)));
                }
            }
        }
        Ok(None)
    }

    fn next_frame(&mut self, deadline: Instant) -> Result<Option<Frame>, Error> {
        let mut b = [0u8; 1];
        let left = deadline.saturating_duration_since(self.link.now());
        let n = self
            .link
            .recv(&mut b, left)
            .map_err(|e| gone(&*self.link, &e))?;
        if n == 0 {
            return Ok(None);
        }
        // The link's clock for the inter-byte timeout: µs since the client opened.
        let now_us = self
            .link
            .now()
            .saturating_duration_since(self.opened)
            .as_micros() as u32;
        match self.deframer.push(b[0], now_us) {
            Deframed::Frame(f) => Ok(decode(f).ok()),
            _ => Ok(None),
        }
    }
}

/// The first sequence number of a session: from the clock and the process
/// id, so that a new session does not repeat the seq of an earlier one's
/// `Measure` (the device answers a repeated seq from its memory).
fn session_seq() -> u32 {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| {
            d.subsec_nanos() ^ (d.as_secs() as u32).rotate_left(16)
        });
    nanos ^ std::process::id().rotate_left(8)
}

/// The error of an interrupted procedure: exit status 130, as a shell
/// reports a command ended by SIGINT.
pub fn interrupted() -> Error {
    Error {
        code: 130,
        msg: "interrupted".to_string(),
    }
}

fn gone(link: &dyn Link, e: &std::io::Error) -> Error {
    Error::failure(format!("lost {}: {e}", link.describe()))
}
