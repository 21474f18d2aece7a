//! The power-up self-test, reported in `Info.self_test`
//! ([`board::protocol::SelfTest`]): which checks ran and which failed,
//! with the crystal and core clock as measured ([`crate::clocks`]).
//!
//! Any failed check is a board on which the drive must not start: the
//! firmware latches the `self_test` fault, and latches it again whenever it
//! is reset.

use board::protocol::{self_test as bits, SelfTest};

use crate::clocks::{within_tolerance, ClockOutcome, HSE_HZ, SYSCLK_HZ};

/// Half-buffers each stream must hand over within [`FIRST_BLOCKS_US`] of
/// the sample clock's start.
pub const FIRST_HALVES: u32 = 2;
/// The time allowed for them, µs (7.8 half-buffers of 128 µs).
pub const FIRST_BLOCKS_US: u32 = 1_000;

/// What the bring-up found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Findings {
    /// The clocks' outcome.
    pub clock: ClockOutcome,
    /// Both DMA streams read back their set-up (`None`: not set up, the
    /// clocks failed).
    pub dma_setup: Option<bool>,
    /// DAC half-transfers and ADC blocks counted [`FIRST_BLOCKS_US`] after
    /// the sample clock started (`None`: not started).
    pub first_halves: Option<(u32, u32)>,
}

/// The report of `f`.
pub fn report(f: &Findings) -> SelfTest {
    let mut t = SelfTest::NOT_RUN;
    let mut check = |bit: u16, ok: bool| {
        t.ran |= bit;
        if !ok {
            t.failed |= bit;
        }
    };
    let c = &f.clock;
    check(bits::CLOCK_READY, c.ready);
    if let Some(hse) = c.hse_hz {
        check(bits::HSE_FREQUENCY, within_tolerance(hse, HSE_HZ));
    } else if c.ready {
        // The crystal started but could not be measured.
        check(bits::HSE_FREQUENCY, false);
    }
    if c.ready && c.hse_hz.is_some_and(|h| within_tolerance(h, HSE_HZ)) {
        check(bits::FLASH_LATENCY, c.latency_ok);
    }
    if c.clocks.sysclk_hz == SYSCLK_HZ {
        check(
            bits::SYSCLK,
            c.sysclk_hz.is_some_and(|s| within_tolerance(s, SYSCLK_HZ)),
        );
    }
    if let Some(ok) = f.dma_setup {
        check(bits::DMA_SETUP, ok);
    }
    if let Some((dac, adc)) = f.first_halves {
        check(
            bits::STREAMS_RUNNING,
            dac >= FIRST_HALVES && adc >= FIRST_HALVES,
        );
    }
    t.hse_hz = c.hse_hz.unwrap_or(0);
    t.sysclk_hz = c.sysclk_hz.unwrap_or(0);
    t
}
