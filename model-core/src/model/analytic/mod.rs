//! Closed-form results of the paper's §2 and the §3.1 approximations.
//!
//! * [`critical_velocity`] — eq. 8 (and 9, 10, 22 as special cases);
//! * [`static_friction`] — the paper's eqs. 17–19 and the exact static stick
//!   interval with the modulus kept;
//! * [`approx`] — the velocity-law approximations eq. 21 and eq. 24.

pub mod approx;
pub mod critical_velocity;
pub mod static_friction;

pub use approx::{approx_mu_over_mu0, ApproxError, ApproxKind};
pub use critical_velocity::CriticalVelocity;
pub use static_friction::StaticFriction;
