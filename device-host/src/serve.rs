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
//!
//! Faults the virtual plant cannot raise by itself (a late DAC refill, a
//! watchdog reset, the external input, a late ADC intake) come in from a
//! host-only side channel ([`fault_listener`], `sim-device --fault-listen`):
//! one fault name or bit per line, latched at the device's next tick
//! through the board's one fault path.

use std::io::{self, BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use board::link::{self, TxRing};

use crate::virtual_device::{self as sim, VirtualDevice};
use crate::{Error, Result};

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

/// Moves what waits in the device's transmit ring to the host, as far as
/// the host takes it: bytes the port does not accept now (its buffer is
/// full, the write times out) stay in the ring for the next turn, so an
/// answer is never lost; meanwhile the device's loop serves no request whose
/// answer would not fit (the firmware's rule). Sets `blocked` when the port
/// would not take more (no further write is tried this turn). `Err` only
/// when the host is gone.
fn drain(
    p: &mut dyn Port,
    tx: &mut TxRing<{ link::TX_CAPACITY }>,
    blocked: &mut bool,
) -> io::Result<()> {
    while !*blocked {
        let front = tx.front();
        if front.is_empty() {
            break;
        }
        match p.write(front) {
            Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
            Ok(n) => tx.consume(n),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut
                        | io::ErrorKind::WouldBlock
                        | io::ErrorKind::Interrupted
                ) =>
            {
                *blocked = true;
            }
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// Fault bits to latch on the device, from [`fault_listener`].
pub type FaultSource = mpsc::Receiver<u32>;

/// The side channel that provokes faults on the virtual device: accepts
/// connections on `l` (a thread per connection), reads one fault per line —
/// a name of [`crate::names::FAULTS`] (`external`) or its bit (`8`) — sends
/// its bit to the device and answers one line: `latched NAME` or what is
/// wrong with the line. Not part of the board's protocol: a board has no
/// such input (its faults come from its hardware).
pub fn fault_listener(l: TcpListener) -> FaultSource {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for s in l.incoming().flatten() {
            let tx = tx.clone();
            std::thread::spawn(move || fault_connection(s, &tx));
        }
    });
    rx
}

/// One side-channel connection: a fault per line until the peer closes it.
fn fault_connection(s: TcpStream, tx: &mpsc::Sender<u32>) {
    let Ok(mut w) = s.try_clone() else { return };
    for line in BufReader::new(s).lines() {
        let Ok(line) = line else { return };
        if line.trim().is_empty() {
            continue;
        }
        let answer = match crate::names::fault_bit(&line) {
            Some(bit) if tx.send(bit).is_ok() => {
                eprintln!("fault side channel: latching {}", line.trim());
                format!("latched {}", crate::names::fault_names(bit).join(""))
            }
            Some(_) => "the device has stopped".to_string(),
            None => format!(
                "unknown fault '{}': one of {}",
                line.trim(),
                crate::names::FAULTS
                    .iter()
                    .map(|(b, n)| format!("{n} ({b})"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        if writeln!(w, "{answer}").is_err() {
            return;
        }
    }
}

/// The device's real-time clock: simulated samples owed to real time.
struct Clock {
    last: Instant,
    debt: f64,
    /// Faults to latch at the next tick.
    faults: Option<FaultSource>,
}

impl Clock {
    fn new(faults: Option<FaultSource>) -> Self {
        Clock {
            last: Instant::now(),
            debt: 0.0,
            faults,
        }
    }

    /// Advances the device to now, handing its transmit ring to `port`
    /// (if any) after each simulated half-buffer.
    fn tick(&mut self, dev: &mut VirtualDevice, port: Option<&mut dyn Port>) -> io::Result<()> {
        if let Some(rx) = &self.faults {
            while let Ok(bits) = rx.try_recv() {
                dev.inject_fault(bits);
            }
        }
        let now = Instant::now();
        let rate = dev.sample_rate();
        self.debt += now.duration_since(self.last).as_secs_f64() * rate;
        self.last = now;
        let half = sim::HALF as f64;
        let mut blocked = false;
        let mut result = Ok(());
        let mut to_port = |tx: &mut TxRing<{ link::TX_CAPACITY }>,
                           port: &mut Option<&mut dyn Port>| {
            match port {
                Some(p) => {
                    if result.is_ok() {
                        result = drain(&mut **p, tx, &mut blocked);
                    }
                }
                // Between clients the bytes go nowhere (a board's UART with no host).
                None => tx.consume(usize::MAX),
            }
        };
        let mut port = port;
        if dev.quiescent() {
            // Move the clock in whole half-buffers; nothing is simulated.
            let whole = (self.debt / half).floor();
            self.debt -= whole * half;
            dev.skip(whole as u64 * sim::HALF as u64);
            to_port(dev.tx(), &mut port);
            return result;
        }
        // At most 50 ms of simulation per turn, so requests stay responsive.
        let n = self.debt.min(rate / 20.0);
        if n >= half {
            dev.advance_with(n as usize, |tx| to_port(tx, &mut port));
            self.debt -= (n as usize).div_ceil(sim::HALF) as f64 * half;
        } else {
            to_port(dev.tx(), &mut port);
        }
        // Never owe more than 1 s (a slow machine falls behind real time).
        self.debt = self.debt.min(rate);
        result
    }
}

/// Serves on the pty master `p` until `deadline`, or until the pty fails,
/// latching the faults `faults` brings ([`fault_listener`]).
pub fn serve_pty(
    dev: &mut VirtualDevice,
    p: &mut serialport::TTYPort,
    deadline: Option<Instant>,
    faults: Option<FaultSource>,
) -> Result {
    let mut clock = Clock::new(faults);
    match pump(dev, p, &mut clock, deadline) {
        Ok(()) => Ok(()),
        Err(e) => Err(Error::failure(format!("pty: {e}"))),
    }
}

/// Serves TCP clients one at a time until `deadline`; the device runs on
/// between connections, latching the faults `faults` brings
/// ([`fault_listener`]).
pub fn serve_tcp(
    dev: &mut VirtualDevice,
    l: TcpListener,
    deadline: Option<Instant>,
    faults: Option<FaultSource>,
) -> Result {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for s in l.incoming() {
            if tx.send(s).is_err() {
                return;
            }
        }
    });
    let mut clock = Clock::new(faults);
    loop {
        if deadline.is_some_and(|d| Instant::now() >= d) {
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
                if let Err(e) = pump(dev, &mut s, &mut clock, deadline) {
                    eprintln!("client {peer}: {e}");
                }
            }
            Ok(Err(e)) => eprintln!("--tcp: accept: {e}"),
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(Error::failure("--tcp: the listener stopped"))
            }
        }
        // Between clients the telemetry goes nowhere (as a board's UART with no host).
        let _ = clock.tick(dev, None);
    }
}

/// Moves bytes between a host and the virtual device, advancing the
/// simulation in real time; `Ok` when the host closes the connection or the
/// deadline passes. Received bytes go into the device's receive queue as a
/// USART would put them there (a byte that does not fit is dropped and
/// counted, `Status.rx_overflows`, and announced); answers and telemetry
/// wait in its transmit ring until the host takes them.
fn pump(
    dev: &mut VirtualDevice,
    s: &mut dyn Port,
    clock: &mut Clock,
    deadline: Option<Instant>,
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
                let ticked = clock.tick(dev, Some(&mut *s));
                dev.push_rx(&buf[..n]);
                ticked?;
                dev.serve_link();
                let mut blocked = false;
                drain(s, dev.tx(), &mut blocked)?;
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
        clock.tick(dev, Some(&mut *s))?;
    }
}
