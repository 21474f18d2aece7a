//! # model-core
//!
//! The single-spring model of dual-mode active friction control
//! (Popov & Li, *Multi-mode active control of friction, dynamic ratchets and
//! actuators*; equation numbers below refer to that paper), shared by the
//! `fricctl` host tool and the STM32F405 firmware. The physics only: the
//! driver board's logic, which uses it, is the `board` crate. The modules of
//! [`model`] are re-exported at the crate root:
//!
//! * [`scene`] — parameters, validation, dimensionless groups (eqs. 1–4, 25, 26);
//! * [`analytic`] — critical velocity (eq. 8–10), static friction (eqs. 17–19 and
//!   the exact static interval), approximations (eqs. 21, 24);
//! * [`fixed_step`] — the paper's explicit scheme (§3, eq. 20);
//! * [`exact`] — the exact event-driven steady-state solver;
//! * [`regime`] — active control / dynamic ratchet / actuator (§3.2);
//! * [`select`] — the cheapest method whose error bound meets a tolerance.
//!
//! Everything is generic over [`Float`] (`f32` for the firmware, `f64` for the
//! host) and, where transcendental functions matter, over a [`Math`] backend
//! ([`Libm`] accurate, [`Micromath`] fast `f32`).
//!
//! ## Cargo features
//! - `defmt` — derive `defmt::Format` for the public types (firmware logging).
//!   Off by default; never needed on the host.
//!
//! The crate is `no_std`, allocation-free and panic-free on validated input.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod model;

// The public paths used by the firmware and the host (`model_core::scene`, …).
pub use model::{analytic, exact, fixed_step, float, mdr, regime, scene, select};

pub use float::{FastF32, Float, Libm, Math, Micromath};
pub use scene::{Drive, Groups, Param, Scene, SceneError, SceneParams};
