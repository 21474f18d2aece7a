//! SysTick as the QEMU build's clock: one exception per half-buffer, the
//! wraps counted, and [`ticks`] — the core clock's ticks since [`start`]
//! (QEMU's netduinoplus2 has no DWT cycle counter). Used by the QEMU
//! plant's pacing (`qemu`) and by the DSP load's count (`cycles`); it
//! imports neither.

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::{syst::SystClkSource, SCB, SYST};

/// SysTick ticks per wrap (its reload + 1), set by [`start`].
static PERIOD: AtomicU32 = AtomicU32::new(1);
/// SysTick wraps since [`start`] (each one half-buffer).
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// SysTick on the core clock, wrapping every `period` ticks with an
/// exception.
pub fn start(syst: &mut SYST, period: u32) {
    PERIOD.store(period.max(1), Ordering::Relaxed);
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(period.max(1) - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Counts a wrap: called by the SysTick exception.
pub fn wrapped() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// SysTick ticks since [`start`], wrapping at 2³² (25.6 s of emulated time):
/// the wraps counted by the exception times the period, plus the down
/// counter's progress. A wrap whose exception is still pending (the reload
/// happened, the handler has not run) is counted too, so that the stamp
/// never steps back. Safe in any context but a handler more urgent than
/// SysTick (priority 0, the highest): none here.
pub fn ticks() -> u32 {
    let period = PERIOD.load(Ordering::Relaxed);
    loop {
        let w = WRAPS.load(Ordering::Relaxed);
        let mut c = SYST::get_current();
        let mut wraps = w;
        if SCB::is_pendst_pending() {
            // Reloaded, not yet counted: read again, after the reload.
            c = SYST::get_current();
            wraps = w.wrapping_add(1);
        }
        if WRAPS.load(Ordering::Relaxed) == w {
            return wraps
                .wrapping_mul(period)
                .wrapping_add(period - 1 - c.min(period - 1));
        }
    }
}
