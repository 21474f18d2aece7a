//! The firmware's serial link without the hardware: the receive queue (with
//! its overflow verdict), the transmit ring, one pass of the main loop over
//! them ([`serve`]), and the decision "nothing to do → sleep" taken with
//! interrupts masked ([`sleep_unless`]), so that the host tests run the very
//! logic the firmware runs.
//!
//! **Why masked.** The loop checks the queue, finds it empty and sleeps. If
//! the last byte of a request arrives between the check and the sleep, its
//! interrupt has already run when the core goes to sleep, and nothing wakes
//! the core until some later interrupt: the answer waits on an unrelated
//! event (a lost wake-up). [`sleep_unless`] runs the check *and* the sleep
//! inside one [`Core::masked`] section. An interrupt raised after the check
//! then stays pending; `WFI` returns at once on a pending interrupt even with
//! PRIMASK set (ARMv7-M ARM B1.5.19: WFI wakes on any interrupt that would
//! preempt if PRIMASK were clear), and the handler runs as soon as the
//! section ends, before the next check.
//!
//! **Pipelining.** Every byte in the receive queue belongs to a request the
//! host has sent and the device has not yet answered (the answer is queued
//! when the request's last byte leaves the queue). A host whose unanswered
//! requests never total more than [`RX_CAPACITY`] bytes on the wire can
//! therefore never overflow the queue, however slowly the device drains it;
//! since a frame is at most [`MAX_FRAME`] bytes, [`PIPELINE_DEPTH`] requests
//! of any kind always fit. Bytes beyond that are dropped and counted
//! ([`crate::device::Status::rx_overflows`]), never lost silently.

use heapless::Deque;

use crate::protocol::MAX_FRAME;
use crate::server::{DeviceAccess, Server};

/// Bytes the receive queue holds (the USART interrupt fills it, the loop
/// empties it).
pub const RX_CAPACITY: usize = 2048;
/// Bytes the transmit ring holds (the loop fills it, the USART
/// transmit-empty interrupt empties it).
pub const TX_CAPACITY: usize = 2048;
/// Requests of any kind a host may have unanswered at once without a
/// possible overflow: ⌊[`RX_CAPACITY`] / [`MAX_FRAME`]⌋ = 2048 / 256 = 8.
pub const PIPELINE_DEPTH: usize = RX_CAPACITY / MAX_FRAME;
/// Frames [`Server::poll`] may send in one call: ramp done, a new fault, a
/// streamed estimate, the stream's end and a receive-overflow notice.
pub const POLL_FRAMES: usize = 5;
/// Received bytes [`serve`] handles per call, so that the loop feeds the
/// watchdog and polls the device between bursts.
pub const SERVE_BUDGET: usize = 64;

/// A byte did not fit in the receive queue (the caller counts it, e.g. with
/// [`crate::device::Device::count_rx_overflow`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Overflow;

/// A frame did not fit in the transmit ring (nothing of it was queued).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TxFull;

impl core::fmt::Display for Overflow {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("receive queue full: byte dropped")
    }
}

impl core::fmt::Display for TxFull {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("transmit ring full: frame not queued")
    }
}

impl core::error::Error for Overflow {}
impl core::error::Error for TxFull {}

/// First-in first-out queue of received bytes of capacity `N`.
pub struct RxQueue<const N: usize> {
    q: Deque<u8, N>,
}

impl<const N: usize> RxQueue<N> {
    /// An empty queue (usable in a `static`).
    pub const fn new() -> Self {
        RxQueue { q: Deque::new() }
    }

    /// Appends a received byte; [`Overflow`] (byte dropped) when full.
    pub fn push(&mut self, b: u8) -> Result<(), Overflow> {
        self.q.push_back(b).map_err(|_| Overflow)
    }

    /// The oldest byte.
    pub fn pop(&mut self) -> Option<u8> {
        self.q.pop_front()
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// No byte waiting.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }
}

impl<const N: usize> Default for RxQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// Ring of bytes to transmit, of capacity `N`, filled a whole frame at a time.
pub struct TxRing<const N: usize> {
    q: Deque<u8, N>,
}

impl<const N: usize> TxRing<N> {
    /// An empty ring (usable in a `static`).
    pub const fn new() -> Self {
        TxRing { q: Deque::new() }
    }

    /// Queues a whole frame, or nothing of it ([`TxFull`]).
    pub fn push_frame(&mut self, frame: &[u8]) -> Result<(), TxFull> {
        if frame.len() > self.free() {
            return Err(TxFull);
        }
        for &b in frame {
            // Cannot fail: the space was checked above.
            self.q.push_back(b).map_err(|_| TxFull)?;
        }
        Ok(())
    }

    /// The next byte to put on the line.
    pub fn pop(&mut self) -> Option<u8> {
        self.q.pop_front()
    }

    /// Bytes that still fit.
    pub fn free(&self) -> usize {
        N - self.q.len()
    }

    /// The oldest bytes waiting, as one contiguous run (empty when the ring
    /// is): for a writer that may take only part of them ([`TxRing::consume`]).
    pub fn front(&self) -> &[u8] {
        self.q.as_slices().0
    }

    /// Drops the `n` oldest bytes (those a writer took from [`TxRing::front`]).
    pub fn consume(&mut self, n: usize) {
        for _ in 0..n {
            if self.q.pop_front().is_none() {
                break;
            }
        }
    }

    /// Nothing left to transmit.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }
}

impl<const N: usize> Default for TxRing<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// The link as the main loop sees it (the firmware wraps its queues in
/// critical sections; tests use plain queues).
pub trait LinkIo {
    /// The oldest received byte.
    fn pop_rx(&mut self) -> Option<u8>;
    /// Bytes free in the transmit ring.
    fn tx_free(&mut self) -> usize;
    /// Queues a frame of at most [`MAX_FRAME`] bytes; [`serve`] calls it
    /// only after checking that the frame fits.
    fn send(&mut self, frame: &[u8]);
}

/// Whether the loop has work: a received byte waiting *and* room in the
/// transmit ring for the answer it may complete. With the ring nearly full
/// the loop sleeps until the transmit interrupt frees room (it cannot block).
pub fn has_work(rx_len: usize, tx_free: usize) -> bool {
    rx_len > 0 && tx_free >= MAX_FRAME
}

/// Whether the transmit ring's `tx_free` bytes hold the [`POLL_FRAMES`]
/// frames of at most [`MAX_FRAME`] bytes the server's poll may send at
/// once (its telemetry is sent whole or not at all).
pub fn poll_fits(tx_free: usize) -> bool {
    tx_free >= POLL_FRAMES * MAX_FRAME
}

/// One pass of the main loop: feeds up to [`SERVE_BUDGET`] received bytes to
/// the server while the transmit ring has room for an answer (each byte
/// completes at most one frame, answered with at most [`MAX_FRAME`] bytes),
/// then lets the server send its telemetry if [`POLL_FRAMES`] frames fit.
/// Never waits: what does not fit stays in the receive queue for later.
/// `now_us` is the device clock (µs, wrapping) for the server's inter-byte
/// timeout.
pub fn serve<const N: usize, A: DeviceAccess<N>, L: LinkIo>(
    server: &mut Server,
    dev: &mut A,
    io: &mut L,
    now_us: u32,
) {
    for _ in 0..SERVE_BUDGET {
        if io.tx_free() < MAX_FRAME {
            break;
        }
        let Some(b) = io.pop_rx() else { break };
        server.receive(dev, &[b], now_us, |f| io.send(f));
    }
    if poll_fits(io.tx_free()) {
        server.poll(dev, |f| io.send(f));
    }
}

/// What [`sleep_unless`] needs from the processor.
pub trait Core {
    /// Runs `f` with interrupts masked (PRIMASK set). An interrupt raised
    /// meanwhile stays pending and is taken as soon as `f` returns.
    fn masked<R>(&mut self, f: impl FnOnce(&mut Self) -> R) -> R;
    /// `WFI`: sleeps until an interrupt is pending, masked or not; returns
    /// at once if one already is.
    fn wait_for_interrupt(&mut self);
}

/// Sleeps unless `work` says there is work, with the check and the sleep in
/// one masked section (see the module documentation). Returns whether it
/// slept.
pub fn sleep_unless<C: Core>(core: &mut C, work: impl FnOnce(&mut C) -> bool) -> bool {
    core.masked(|c| {
        if work(c) {
            false
        } else {
            c.wait_for_interrupt();
            true
        }
    })
}
