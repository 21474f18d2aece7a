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
//! - `probe` — profiling marks in the handlers' work (module `probe`), for
//!   `predict_cost`'s breakdown of a half-buffer; never in a shipped build.
//!
//! The crate is `no_std` and allocation-free.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![cfg_attr(not(feature = "probe"), forbid(unsafe_code))]

/// Profiling marks (feature `probe`).
#[cfg(feature = "probe")]
pub mod probe;

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
