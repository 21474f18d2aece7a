//! The host side of the friction-control board, as a library: everything
//! `fricctl device`, `fricctl sim-device`, the control benches and the
//! Python package share, with no flags, text or plots of its own.
//!
//! - [`link`]: byte links to a device — a serial port (the board, a pty),
//!   TCP (QEMU, `fricctl sim-device --tcp`), the in-process virtual device.
//! - [`client`]: the protocol's host side ([`board::protocol`], the one
//!   definition the firmware also uses): sequence numbers, time-outs,
//!   retries, telemetry kept aside.
//! - [`virtual_device`]: the board's own device logic and server
//!   ([`board::device`], [`board::server`]) on a simulated plant
//!   ([`board::plant`]), sample by sample, as the firmware runs them.
//! - [`transducers`]: the virtual plant's transducers, ideal or resonant.
//! - [`serve`]: the virtual device in real time on a pty or TCP.
//! - [`control_bench`]: the μ loop's step responses on an in-process virtual
//!   device (`fricctl device control-bench`), and [`control_grid`], the same
//!   over a grid of transducers (`fricctl bench control`); [`dac_bench`], the
//!   board's DDS: spectral purity against cost (`fricctl bench dac`).
//!
//! - [`report`]: every answer as rows of (JSON key, text label, value,
//!   unit), printed as aligned text or one flat JSON object: the one
//!   definition of the keys, for `fricctl --json` and Python.
//! - [`identify`], [`sweep`], [`measure`], [`state`]: the device commands'
//!   procedures, and what they put back on every way out.
//! - `view` (feature `view`): the live page of `fricctl device view`, an
//!   HTTP and WebSocket server with the plotting library compiled in.
//!
//! Errors are the analysis library's ([`Error`]): one line naming the
//! parameter as its `fricctl` flag, with the class as the exit status
//! (2 = bad input, 1 = the run failed).
#![deny(missing_docs)]

pub mod answers;
pub mod client;
pub mod control_bench;
pub mod control_grid;
pub mod dac_bench;
pub mod identify;
pub mod link;
pub mod measure;
pub mod names;
pub mod periods;
pub mod report;
pub mod serve;
pub mod state;
pub mod sweep;
pub mod transducers;
#[cfg(feature = "view")]
pub mod view;
pub mod virtual_device;

pub use fric_analysis::error::{Error, Result};
