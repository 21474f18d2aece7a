//! Priority-ceiling locks (the stack resource policy, as RTIC's resources):
//! a value shared by contexts of at most one interrupt level is locked by
//! raising BASEPRI to that level's priority byte, which masks exactly the
//! contexts that may touch it and nothing more urgent.
//!
//! Each [`Shared`] names its ceiling, the most urgent level of the contexts
//! that access it ([`hardware::nvic`]); a context more urgent than the
//! ceiling must never touch it (each static says who does). A context
//! running *at* the ceiling locks at no cost (BASEPRI only ever rises).
//! No lock masks all interrupts: the fault input (level 0) and the link
//! (level 1) pre-empt anything the device does under its lock (level 2).

use core::cell::UnsafeCell;
use core::sync::atomic::{compiler_fence, AtomicBool, Ordering};

/// A value behind a priority-ceiling lock at level `LEVEL`.
pub struct Shared<T, const LEVEL: u8> {
    value: UnsafeCell<T>,
    /// Set while a lock is held: a second, nested lock of the same value
    /// would alias it (a bug, not a race: the ceiling excludes the others).
    held: AtomicBool,
}

// SAFETY: every access goes through `lock`, which excludes all contexts
// that may access the value (module docs).
unsafe impl<T: Send, const LEVEL: u8> Sync for Shared<T, LEVEL> {}

impl<T, const LEVEL: u8> Shared<T, LEVEL> {
    /// A shared value.
    pub const fn new(value: T) -> Self {
        Shared {
            value: UnsafeCell::new(value),
            held: AtomicBool::new(false),
        }
    }

    /// Runs `f` on the value with BASEPRI at the ceiling.
    pub fn lock<R>(&self, f: impl FnOnce(&mut T) -> R) -> R {
        // BASEPRI = 0 masks nothing: a lock at level 0 would exclude no one.
        const { assert!(LEVEL >= 1, "a Shared at level 0 cannot be locked") };
        let old = cortex_m::register::basepri::read();
        cortex_m::register::basepri_max::write(hardware::nvic::byte(LEVEL));
        compiler_fence(Ordering::SeqCst);
        if self.held.swap(true, Ordering::Relaxed) {
            defmt::panic!("a lock at level {} was taken twice", LEVEL);
        }
        // SAFETY: the ceiling masks every other context that accesses the
        // value, and `held` excludes a nested lock in this one.
        let r = f(unsafe { &mut *self.value.get() });
        self.held.store(false, Ordering::Relaxed);
        compiler_fence(Ordering::SeqCst);
        // SAFETY: restores the caller's own BASEPRI (a lower or equal mask).
        unsafe { cortex_m::register::basepri::write(old) };
        r
    }
}
