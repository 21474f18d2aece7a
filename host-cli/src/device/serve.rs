//! `fricctl sim-device`: the virtual device in real time on a pty or TCP.
//!
//! The device's clock runs whether or not a host is connected, as a board's
//! does: over TCP it keeps simulating between connections (each `fricctl
//! device` invocation is a new connection; a soft start begun by `start`
//! must go on while no client is connected, or the next `measure` lands in
//! the ramp). While the device is quiescent — drive stopped and settled, no
//! measurement or stream — its samples reach nothing, so the plant is not
//! simulated: the clock is moved on ([`VirtualDevice::skip`]) and the loop
//! sleeps in its read for up to [`IDLE_WAIT`].

use std::io::{self, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use super::sim::{self, VirtualDevice};
use crate::error::{CliError, CliResult};

/// Read wait while the device is quiescent.
pub const IDLE_WAIT: Duration = Duration::from_millis(20);
/// Read wait while the plant is simulated.
const BUSY_WAIT: Duration = Duration::from_millis(2);

/// A byte stream to a host with a settable read wait.
pub trait Port: Read + Write {
    /// Sets how long a read waits for bytes.
    fn set_wait(&mut self, d: Duration) -> io::Result<()>;
}

impl Port for serialport::TTYPort {
    fn set_wait(&mut self, d: Duration) -> io::Result<()> {
        serialport::SerialPort::set_timeout(self, d).map_err(io::Error::other)
    }
}

impl Port for TcpStream {
    fn set_wait(&mut self, d: Duration) -> io::Result<()> {
        self.set_read_timeout(Some(d))
    }
}

/// Writes `bytes`; a host that does not read (the pty's buffer is full, a
/// write times out) loses them, counted in `lost`, instead of ending the
/// device. `Err` only when the host is gone.
fn send(p: &mut dyn Port, bytes: &[u8], lost: &mut u64) -> io::Result<()> {
    let mut rest = bytes;
    while !rest.is_empty() {
        match p.write(rest) {
            Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
            Ok(n) => rest = &rest[n..],
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut
                        | io::ErrorKind::WouldBlock
                        | io::ErrorKind::Interrupted
                ) =>
            {
                // The host's deframer resynchronises on the next delimiter.
                *lost += rest.len() as u64;
                return Ok(());
            }
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// The device's real-time clock: simulated samples owed to real time.
struct Clock {
    last: Instant,
    debt: f64,
}

impl Clock {
    fn new() -> Self {
        Clock {
            last: Instant::now(),
            debt: 0.0,
        }
    }

    /// Advances the device to now; returns the telemetry produced.
    fn tick(&mut self, dev: &mut VirtualDevice) -> Vec<u8> {
        let now = Instant::now();
        let rate = dev.sample_rate();
        self.debt += now.duration_since(self.last).as_secs_f64() * rate;
        self.last = now;
        let half = sim::HALF as f64;
        if dev.quiescent() {
            // Move the clock in whole half-buffers; nothing is simulated.
            let whole = (self.debt / half).floor();
            self.debt -= whole * half;
            return dev.skip(whole as u64 * sim::HALF as u64);
        }
        // At most 50 ms of simulation per turn, so requests stay responsive.
        let n = self.debt.min(rate / 20.0);
        let mut t = Vec::new();
        if n >= half {
            t = dev.advance(n as usize);
            self.debt -= (n as usize).div_ceil(sim::HALF) as f64 * half;
        }
        // Never owe more than 1 s (a slow machine falls behind real time).
        self.debt = self.debt.min(rate);
        t
    }
}

/// Serves on the pty master `p` until `deadline`, or until the pty fails.
pub fn serve_pty(
    dev: &mut VirtualDevice,
    p: &mut serialport::TTYPort,
    deadline: Option<Instant>,
) -> CliResult {
    let mut clock = Clock::new();
    let mut lost = 0u64;
    let r = pump(dev, p, &mut clock, deadline, &mut lost);
    report_lost(lost);
    match r {
        Ok(()) => Ok(()),
        Err(e) => Err(CliError::failure(format!("pty: {e}"))),
    }
}

/// Serves TCP clients one at a time until `deadline`; the device runs on
/// between connections.
pub fn serve_tcp(dev: &mut VirtualDevice, l: TcpListener, deadline: Option<Instant>) -> CliResult {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for s in l.incoming() {
            if tx.send(s).is_err() {
                return;
            }
        }
    });
    let mut clock = Clock::new();
    let mut lost = 0u64;
    loop {
        if deadline.is_some_and(|d| Instant::now() >= d) {
            report_lost(lost);
            return Ok(());
        }
        let wait = if dev.quiescent() {
            IDLE_WAIT
        } else {
            BUSY_WAIT
        };
        match rx.recv_timeout(wait) {
            Ok(Ok(mut s)) => {
                let peer = s.peer_addr().map(|a| a.to_string()).unwrap_or_default();
                eprintln!("client {peer}");
                let _ = s.set_nodelay(true);
                if let Err(e) = pump(dev, &mut s, &mut clock, deadline, &mut lost) {
                    eprintln!("client {peer}: {e}");
                }
            }
            Ok(Err(e)) => eprintln!("--tcp: accept: {e}"),
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(CliError::failure("--tcp: the listener stopped"))
            }
        }
        // Between clients the telemetry goes nowhere (as a board's UART with no host).
        let _ = clock.tick(dev);
    }
}

/// Moves bytes between a host and the virtual device, advancing the
/// simulation in real time; `Ok` when the host closes the connection or the
/// deadline passes.
fn pump(
    dev: &mut VirtualDevice,
    s: &mut dyn Port,
    clock: &mut Clock,
    deadline: Option<Instant>,
    lost: &mut u64,
) -> io::Result<()> {
    let mut buf = [0u8; 512];
    let mut wait = Duration::ZERO;
    loop {
        if deadline.is_some_and(|d| Instant::now() >= d) {
            return Ok(());
        }
        let want = if dev.quiescent() {
            IDLE_WAIT
        } else {
            BUSY_WAIT
        };
        if want != wait {
            s.set_wait(want)?;
            wait = want;
        }
        match s.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => {
                // The device's clock first: the bytes arrive at its "now"
                // (the inter-byte timeout is measured on it).
                let t = clock.tick(dev);
                send(s, &t, lost)?;
                let reply = dev.receive(&buf[..n]);
                send(s, &reply, lost)?;
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut
                        | io::ErrorKind::WouldBlock
                        | io::ErrorKind::Interrupted
                ) => {}
            Err(e) => return Err(e),
        }
        let t = clock.tick(dev);
        send(s, &t, lost)?;
    }
}

fn report_lost(lost: u64) {
    if lost > 0 {
        eprintln!("{lost} bytes not sent: the host did not read them");
    }
}
