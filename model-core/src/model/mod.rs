//! **The model**: the physics of a vibrated sliding contact, independent of
//! any hardware.
//!
//! * [`float`] — the [`Float`](float::Float) abstraction (`f32` firmware,
//!   `f64` host) and the [`Math`](float::Math) backends with their error bounds;
//! * [`scene`] — parameters, validation, dimensionless groups (eqs. 1–4, 25, 26);
//! * [`analytic`] — critical velocity (eqs. 8–10), static friction
//!   (eqs. 17–19 and the exact static interval), approximations (eqs. 21, 24);
//! * [`fixed_step`] — the paper's explicit scheme (§3, eq. 20);
//! * [`exact`] — the exact event-driven steady-state solver;
//! * [`liftoff`] — intermittent contact (`Δu_z ≥ u_z0`): exact and fixed-step solvers;
//! * [`mdr`] — curved profiles (sphere, cone, power law) through the method of dimensionality reduction;
//! * [`regime`] — active control / dynamic ratchet / actuator (§3.2);
//! * [`select`] — the cheapest method whose error bound meets a tolerance;
//! * [`load_line`] — the contact as an actuator: stall forces, no-load
//!   velocities, input/output/friction power and efficiency;
//! * [`inverse`] — inverse design: the drive value that attains a target μ
//!   or maximises an objective (ratchet asymmetry, stall force).
//!
//! **Dependencies.** The model uses only itself, `libm`/`micromath` and
//! `heapless`; it never uses the `board` crate. New contact models, body
//! motion and controllers' inverse models belong here.

pub mod analytic;
pub mod exact;
pub mod fixed_step;
pub mod float;
pub mod inverse;
pub mod liftoff;
pub mod load_line;
pub mod mdr;
pub mod regime;
pub(crate) mod root;
pub mod scene;
pub mod select;
