//! The DSP handlers' time per half-buffer: what the board reports as
//! `Status.cpu_load_pct` and `cpu_load_max_pct` (protocol v8; eq. L1 of
//! `board::device::load`: `100 · c / B` with `B = f_core · HALF / f_s`).
//!
//! * On the chip: the DWT cycle counter CYCCNT (32 bits at the core clock),
//!   started by [`start`]. The difference of two reads is the cycles between
//!   them, wrapping (exact for spans under 2³² cycles, 25 s at 168 MHz).
//! * Under QEMU, where CYCCNT stays 0: SysTick, which `qemu::tick` reloads
//!   once per half-buffer, extended by its wraps to 32 bits
//!   (`systick::ticks`), and converted to instructions with a calibration of
//!   `CAL_INSNS` `nop`s taken by [`start`] (as `predict_cost` calibrates
//!   with 1 000; more here, so that the calibration is not lost in the
//!   clock's resolution when QEMU runs without `-icount`). Under
//!   `qemu-system-arm -icount shift=0` that is the instruction count (one
//!   instruction 1 ns of emulated time, 0.168 ticks: resolved to ≈ 6
//!   instructions); without `-icount` QEMU's clock follows the host's, and
//!   the figure is the host's time in units of its time per instruction at
//!   boot.
//!
//! Contexts: [`start`] in `main` before the DSP runs; [`now`], [`since`],
//! [`fill_done`] and [`record`] in the DSP handlers (level 2) on the chip,
//! in the main loop's emulated DMA work under QEMU. The refill of a half
//! and the ADC block of a half are added ([`fill_done`] then [`record`]):
//! one half-buffer's work.

use core::num::NonZeroU32;
use core::sync::atomic::{AtomicU32, Ordering};

use crate::Dev;

/// The budget per half-buffer `B`, cycles (eq. L1); 0 until [`start`].
static BUDGET: AtomicU32 = AtomicU32::new(0);
/// The last DAC refill's cycles, taken by the next [`record`].
static FILL: AtomicU32 = AtomicU32::new(0);
/// QEMU: the calibration's instructions: 16 runs of 1 000 `nop`s.
#[cfg(feature = "qemu")]
const CAL_INSNS: u64 = 16_000;
/// QEMU: SysTick ticks per `CAL_INSNS` instructions, from the boot
/// calibration (2 688 under `-icount shift=0`).
#[cfg(feature = "qemu")]
static TICKS_PER_CAL: AtomicU32 = AtomicU32::new(1);
/// QEMU: the least calibration accepted, ticks (under `-icount shift=0`
/// 2 688 ± 1).
#[cfg(feature = "qemu")]
const MIN_CAL_TICKS: u32 = 1_000;

/// Starts the count: on the chip the DWT cycle counter, under QEMU the
/// calibration (SysTick must be running: after `qemu::tick`). `sysclk_hz`:
/// the core clock in force, for the budget `B = sysclk_hz · HALF / f_s`.
pub fn start(cp: &mut cortex_m::Peripherals, sysclk_hz: u32) {
    let budget = u64::from(sysclk_hz) * crate::HALF as u64 / u64::from(crate::FS_HZ);
    BUDGET.store(u32::try_from(budget).unwrap_or(u32::MAX), Ordering::Relaxed);
    #[cfg(not(feature = "qemu"))]
    {
        cp.DCB.enable_trace();
        cp.DWT.enable_cycle_counter();
    }
    #[cfg(feature = "qemu")]
    {
        let _ = cp;
        let mut nops = [0u32; 4];
        let mut empty = u32::MAX;
        for n in nops.iter_mut() {
            let t0 = crate::systick::ticks();
            for _ in 0..CAL_INSNS / 1_000 {
                nops_1000();
            }
            *n = crate::systick::ticks().wrapping_sub(t0);
            let t0 = crate::systick::ticks();
            empty = empty.min(crate::systick::ticks().wrapping_sub(t0));
        }
        nops.sort_unstable();
        // Four runs span < 70 000 instructions, so a SysTick exception
        // (one per 128 000 under `-icount shift=0`) lands in at most one
        // of them: the two smallest are exception-free, and under
        // `-icount` equal to the tick (±1, where the runs start between
        // ticks). Without `-icount` QEMU's clock follows the host's and
        // they differ, or the clock did not move: then the count would
        // tell nothing about the chip, and nothing is recorded (the
        // Status fields stay `None`).
        let cal = nops[0].saturating_sub(empty);
        if nops[1] - nops[0] <= 1 && cal >= MIN_CAL_TICKS {
            // The loop around the `nop`s adds a few instructions per
            // 1 000: < 1 %, the measure's resolution.
            TICKS_PER_CAL.store(cal, Ordering::Relaxed);
        } else {
            BUDGET.store(0, Ordering::Relaxed);
        }
    }
}

/// Exactly 1 000 `nop`s (in their own function, so that no literal pool
/// spans them): the calibration's known instruction count.
#[cfg(feature = "qemu")]
#[inline(never)]
fn nops_1000() {
    // SAFETY: `nop` has no effect.
    unsafe { core::arch::asm!(".rept 1000", "nop", ".endr", options(nomem, nostack)) }
}

/// A time stamp for [`since`].
#[inline(always)]
pub fn now() -> u32 {
    #[cfg(not(feature = "qemu"))]
    return cortex_m::peripheral::DWT::cycle_count();
    #[cfg(feature = "qemu")]
    return crate::systick::ticks();
}

/// Cycles since the stamp `t0` (under QEMU: instructions, calibrated).
#[inline(always)]
pub fn since(t0: u32) -> u32 {
    let d = now().wrapping_sub(t0);
    #[cfg(not(feature = "qemu"))]
    return d;
    #[cfg(feature = "qemu")]
    return u32::try_from(
        u64::from(d) * CAL_INSNS / u64::from(TICKS_PER_CAL.load(Ordering::Relaxed)),
    )
    .unwrap_or(u32::MAX);
}

/// The DAC refill of a half-buffer took `cycles`.
pub fn fill_done(cycles: u32) {
    FILL.store(cycles, Ordering::Relaxed);
}

/// The ADC block of the same half-buffer took `cycles` so far: records the
/// half-buffer's DSP work (the refill's and the block's) in the device.
pub fn record(dev: &mut Dev, cycles: u32) {
    let total = cycles.saturating_add(FILL.swap(0, Ordering::Relaxed));
    if let Some(b) = NonZeroU32::new(BUDGET.load(Ordering::Relaxed)) {
        dev.record_cpu_load(total, b);
    }
}
