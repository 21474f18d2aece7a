//! The panic handler: where and (for a constant message) why, over defmt, then
//! a HardFault as `panic-probe` does (a debug probe stops there; without one the
//! independent watchdog resets the board).
//!
//! Unlike `panic-probe`'s `print-defmt`, it never formats the panic message
//! with `core::fmt` (≈ 2 KB of flash): a message built from arguments (a
//! bounds check, an `unwrap` on an error) is reported by its file and line
//! only; a constant one (`panic!("…")`, `expect("…")`) is printed whole.

use core::panic::PanicInfo;
use core::sync::atomic::{AtomicBool, Ordering};

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    // A panic while reporting one goes straight to the fault.
    if !PANICKED.swap(true, Ordering::Relaxed) {
        let msg = info
            .message()
            .as_str()
            .unwrap_or("(formatted message not kept)");
        match info.location() {
            Some(l) => defmt::error!("panicked at {=str}:{=u32}: {=str}", l.file(), l.line(), msg),
            None => defmt::error!("panicked: {=str}", msg),
        }
    }
    hard_fault()
}

/// `defmt::panic!` has already logged its message: fault without a second one.
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    cortex_m::interrupt::disable();
    hard_fault()
}

/// A HardFault via `udf` (UsageFault disabled first, or `udf` would raise that
/// instead; SHCSR bit 18 USGFAULTENA, ARMv7-M ARM B3.2.13) — `panic_probe::hard_fault`.
fn hard_fault() -> ! {
    const SHCSR: *mut u32 = 0xE000_ED24 as *mut u32;
    const USGFAULTENA: u32 = 1 << 18;
    // SAFETY: SHCSR is a System Control Block register, always mapped on a
    // Cortex-M4; clearing one enable bit has no other effect.
    unsafe {
        let v = core::ptr::read_volatile(SHCSR);
        core::ptr::write_volatile(SHCSR, v & !USGFAULTENA);
    }
    cortex_m::asm::udf()
}
