//! The board's signal-processing primitives: small, each with its number
//! formats, error bounds and tests (in the spirit of quartiq's `idsp`).
//!
//! * [`dds`] — the two phase-locked DAC waveforms (direct digital synthesis);
//! * [`lockin`] — amplitude and phase of a sampled signal on the DDS's own
//!   reference, exact over any window;
//! * [`resonator`] — one transducer mode advanced by its exact
//!   zero-order-hold update;
//! * [`reference`](mod@reference) — the drive phase's Q15 cosine and sine of an ADC block,
//!   shared by every signal demodulated in it, and their integer sums;
//! * [`estimator`] — μ from sampled forces (eq. 20) with lock-in harmonics.

pub mod dds;
pub mod estimator;
pub mod lockin;
pub mod reference;
pub mod resonator;
