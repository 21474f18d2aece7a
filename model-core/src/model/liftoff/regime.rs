//! Regimes (paper §3.2) of a contact that lifts off.
//!
//! The definitions of [`crate::model::regime`] hold unchanged (actuator: the
//! force points along the motion for some velocity or is non-zero at rest;
//! active control: symmetric law; dynamic ratchet: neither). With lift-off the
//! state resets at every landing, so the force at rest `μ(0)` is unique and
//! `μ(0⁺) = μ(0⁻) = μ(0)`: the scene is an actuator iff `|μ(0)| > tol`
//! (with μ(v) non-decreasing in v, as for the permanent contact, the sign of
//! μ(0) decides the sign of μ(v)·v near rest). A force-free rest needs
//! `μ(0) = 0`, which a symmetric drive gives (e.g. `b = 0`, where the law is
//! odd). `φ = ±π/2` is *not* symmetric here: the landing breaks the time
//! reversal, and at `a = 1.5, b = 0.8, φ = 90°` the exact solver and the
//! stepping both give `μ(0)/μ₀ = 0.30312` (an actuator). An asymmetric drive
//! with lift-off is generically an actuator. There is no static interval.

use super::{critical_velocities, mu_over_mu0, LiftOffError};
use crate::model::float::{Float, Math};
use crate::model::regime::{ClassifyOptions, Regime};
use crate::model::scene::Drive;

/// A lift-off classification with the numbers it rests on (μ as `μ/μ₀`,
/// velocities as multiples of ωW₀).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LiftOffClassification<T> {
    /// The class.
    pub regime: Regime,
    /// `μ(0)/μ₀`, unique with lift-off.
    pub mu_at_rest: T,
    /// `V_c⁺` of the contact window.
    pub c_forward: T,
    /// `V_c⁻` of the contact window.
    pub c_backward: T,
    /// `max |μ(V) + μ(−V)|/μ₀` over the sampled velocities and `V = 0`.
    pub asymmetry: T,
}

/// Classifies a lift-off drive (`a ≥ 1`); `opts` as for the permanent contact.
///
/// # Errors
/// The errors of [`mu_over_mu0`].
pub fn classify<T: Float, M: Math<T>>(
    d: &Drive<T>,
    opts: &ClassifyOptions<T>,
) -> Result<LiftOffClassification<T>, LiftOffError> {
    let mu_at_rest = mu_over_mu0::<T, M>(d, T::ZERO)?;
    let (c, cb) = critical_velocities::<T, M>(d)?;
    let tol = opts.tol;
    let mut asymmetry = (mu_at_rest + mu_at_rest).abs();
    let vmax = c.max(cb);
    if (c - cb).abs() > tol * (T::ONE + vmax) {
        // Different critical velocities: μ = ±1 beyond one and not the other.
        let v = c.min(cb);
        let m = if v == T::ZERO {
            T::ZERO
        } else {
            mu_over_mu0::<T, M>(d, v)?
        };
        asymmetry = asymmetry.max(T::ONE - m.abs());
    } else if vmax > T::ZERO {
        let n = opts.samples.max(1);
        for i in 1..=n {
            let v = vmax * T::from_u32(i) / T::from_u32(n + 1);
            let f = mu_over_mu0::<T, M>(d, v)?;
            let b = mu_over_mu0::<T, M>(d, -v)?;
            asymmetry = asymmetry.max((f + b).abs());
        }
    }
    let regime = if mu_at_rest.abs() > tol {
        Regime::Actuator
    } else if asymmetry <= tol {
        Regime::ActiveControl
    } else {
        Regime::DynamicRatchet
    };
    Ok(LiftOffClassification {
        regime,
        mu_at_rest,
        c_forward: c,
        c_backward: cb,
        asymmetry,
    })
}
