//! # board
//!
//! **The driver board's logic**, free of hardware types, so that the
//! firmware and the host's virtual device run the very same code. It uses
//! the physics of [`model_core`] (scene, solvers, regimes); nothing in the
//! model uses the board. Folders by subject:
//!
//! * [`protocol`] — the wire format shared by firmware and host (knows no
//!   device logic);
//! * [`dsp`] — small primitives: [`dds`], [`lockin`], [`reference`](mod@reference), [`resonator`],
//!   [`estimator`] (re-exported at the crate root);
//! * [`device`] — the state machine, its loops, faults and measurement, with
//!   the μ loop's arithmetic in [`control`];
//! * [`plant`] — the simulated analog side (the virtual device, the QEMU
//!   build);
//! * [`server`], [`link`], [`dma`] — the device side of the protocol, the
//!   serial link's loop, the DMA half-buffer decision; [`identify`] — the
//!   stepped-sine fit of a transducer (host side).
//!
//! In detail:
//!
//! * [`control`] — the closed loop: μ held at a setpoint by Δu_z (feedforward
//!   from the f32 inverse model, integral trim, anti-windup, rate limit, lift-off guard);
//! * [`dds`] — the two phase-locked DAC waveforms (direct digital synthesis);
//! * [`dma`] — which half of a circular DMA buffer an interrupt hands over,
//!   and whether its handler was late;
//! * [`estimator`] — μ from sampled forces (eq. 20) with lock-in harmonics;
//! * [`device`] — drive settings in physical units, the lift-off guard,
//!   start/stop ramps, faults with one path into the safe state, measurement
//!   and the model's prediction (`config`, `drive`, `fault`, `measure`,
//!   `predict`, `error`);
//! * [`protocol`] — the wire format shared by firmware and host
//!   (`messages`: the wire types and the request → response table;
//!   `framing`: CRC, COBS, deframing);
//! * [`server`] — the device side of the protocol, with the session state
//!   (idempotent `Measure`, the stream, `Reset`);
//! * [`link`] — the firmware's serial link: queues, one loop pass, sleeping
//!   without a lost wake-up;
//! * [`lockin`] — amplitude and phase of a sampled signal on the DDS's own
//!   reference, exact over any window (a least-squares fit, no 2f leak);
//! * [`resonator`] — one transducer mode (f_r, Q, static gain) advanced by
//!   its exact zero-order-hold update (the building block of the resonant
//!   plant);
//! * [`identify`] — one transducer mode's f_r, Q, static gain and phase lag
//!   fitted to a stepped-sine record (Levenberg–Marquardt on the complex
//!   response), with confidence intervals and a verdict refusing a poor fit
//!   by name (no device code: `fricctl device identify` collects and calls it);
//! * [`plant`] — the simulated analog side (transducers, contact, force
//!   sensors) of the host's virtual device and of the firmware under QEMU.
//!
//! ## Cargo features
//! - `defmt` — derive `defmt::Format` for the public types (firmware logging).
//! - `probe` — profiling marks in the handlers' work ([`probe`](mod@probe)), for
//!   `predict_cost`'s breakdown of a half-buffer; never in a shipped build.
//!
//! The crate is `no_std` and allocation-free.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![cfg_attr(not(feature = "probe"), forbid(unsafe_code))]

/// Profiling marks (feature `probe`, for `predict_cost --features probe`
/// only; no other build has them): the device calls [`probe::mark`] at the
/// borders of its handlers' parts, and a hook the firmware sets times the
/// stretch since the previous mark (issue 35's breakdown of a half-buffer).
#[cfg(feature = "probe")]
pub mod probe {
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
}

/// A profiling mark ([`probe`]); nothing without the feature.
macro_rules! probe {
    ($id:expr) => {
        #[cfg(feature = "probe")]
        $crate::probe::mark($id);
    };
}

pub mod control;
pub mod device;
pub mod dma;
pub mod dsp;
pub mod identify;
pub mod link;
pub mod plant;
pub mod protocol;
pub mod server;

pub use dsp::{dds, estimator, lockin, reference, resonator};
