//! The analysis of dual-mode active friction control that lies above the
//! model (`model-core`) and below its users: the CLI `fricctl` and the
//! Python package `fricctl`. It knows nothing of a command line, a terminal
//! or a serial port: inputs are plain values, results plain structs, and
//! errors one line naming the parameter as its CLI flag ([`error`]).
//!
//! * [`numbers`]: the domain of every real input, numbers in messages;
//! * [`scene`]: a scene from physical quantities, a file or the groups (eqs. 25/26);
//! * [`eval`]: μ at one velocity by a method, critical velocities (eq. 8, L5), regimes;
//! * [`grid`]: evenly spaced velocities and cell centres, μ over a velocity grid (the
//!   curve's rows), μ and the regime over a map's cells, which method answered where;
//! * [`profile_curve`]: μ(v) of a curved profile along a curve, by an interpolant
//!   through MDR answers where μ(v) is smooth;
//! * [`fit`], [`sweep_file`]: identification of (μ0, kx/kz) from a measured sweep;
//! * [`tune`]: inverse design (the drive that attains a target μ, or maximises an objective);
//! * [`load_line`]: the contact as an actuator;
//! * [`motion`]: a body moved by the vibrated contact;
//! * [`bench`](mod@bench): the model benchmarks (work-precision, methods, stability,
//!   motion): their runs, references, timings and rows.

#![deny(missing_docs)]

pub mod bench;
pub mod error;
pub mod eval;
pub mod fit;
pub mod grid;
pub mod load_line;
pub mod motion;
pub mod numbers;
pub mod profile_curve;
pub mod scene;
pub mod sweep_file;
pub mod tune;

pub use error::{Error, Result};
