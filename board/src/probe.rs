//! Profiling marks (feature `probe`, for `predict_cost --features probe`
//! only; no other build has them): the device calls [`mark`] at the
//! borders of its handlers' parts, and a hook the firmware sets times the
//! stretch since the previous mark (issue 35's breakdown of a half-buffer).

use core::sync::atomic::{AtomicUsize, Ordering::Relaxed};

/// The hook, a `fn(u8)` as an address (0: none).
static HOOK: AtomicUsize = AtomicUsize::new(0);

/// The marks: a part's number is the mark that ends it; 0 and 10 start
/// the DAC's and the ADC's handler.
pub const PARTS: [(u8, &str); 17] = [
    (1, "DAC: the mu loop's fill (control_fill)"),
    (30, "DAC dead-beat: the model at the frequency (cached)"),
    (31, "DAC dead-beat: the poles where c places them (D8)"),
    (2, "DAC dead-beat: the voltages (D4-D6), levels, phases"),
    (
        3,
        "DAC: the reference words and the codes (fill_with_reference)",
    ),
    (11, "ADC: the block's set-up and the rail check"),
    (12, "ADC: the pickups' sums (Gram, pair sums)"),
    (13, "ADC: the force estimator's sums"),
    (14, "ADC: the saturation check"),
    (20, "ADC window close: the delay's turn, the span check"),
    (21, "ADC window close: the fit (LockInQ::solve, turned)"),
    (22, "ADC window close: metres, amplitude, lift-off guard"),
    (23, "ADC window close: the fills' records, smoothing"),
    (24, "ADC window close: D3, open pickups, hold"),
    (25, "ADC window close: tracking (T1-T3)"),
    (15, "ADC: the rest of the window close"),
    (16, "ADC: the mu loop's block end (control_block_end)"),
];

/// Sets the hook every mark calls.
pub fn set_hook(f: fn(u8)) {
    HOOK.store(f as usize, Relaxed)
}

/// Mark `id`: calls the hook, if one is set.
#[inline(always)]
pub fn mark(id: u8) {
    let h = HOOK.load(Relaxed);
    if h != 0 {
        // SAFETY: `HOOK` only ever holds 0 or a `fn(u8)` stored by
        // `set_hook`, and fn pointers are address-sized.
        #[allow(unsafe_code)]
        let f: fn(u8) = unsafe { core::mem::transmute::<usize, fn(u8)>(h) };
        f(id)
    }
}
