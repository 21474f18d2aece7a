//! The paper's closed-form approximations of the velocity law for single-mode
//! oscillation (§3.1): eq. 21 (normal only, from the paper's ref. 14) and eq. 24 (tangential
//! only, for `k_xΔu_x/(μ₀k_z u_z0) ≤ 1`).
//!
//! Both have the form `μ/μ₀ ≈ 1 − A[¾(x − 1)² + ¼(x − 1)⁴]` with
//! `x = |v₀|/v_c ∈ [0, 1)`, odd in v₀, and `μ = ±μ₀` for `|v₀| ≥ v_c`; `A = Δu_z/u_z0`
//! for eq. 21 and `A = k_xΔu_x/(μ₀k_z u_z0)` for eq. 24.
//!
//! **Measured error.** The paper calls eq. 21 "accurate to within 1 %". Against
//! the exact solver the largest error over `x ∈ (0, 1)` is
//! [`MAX_ERROR_OVER_A`] · A · μ₀ (1.436 % of `μ₀A`, at `x ≈ 0.104`), for
//! every `A` in the validity domain: for normal-only and for tangential-only
//! drive with `A ≤ 1` the exact law is `1 − A·F(x)` with one universal `F`
//! (the stick dynamics scale with `A`), so the error relative to `A` is the same
//! function of `x` for all scenes. The value is checked by the test
//! `approx_error_bound` in `tests/analytic.rs`.

use crate::model::analytic::critical_velocity::CriticalVelocity;
use crate::model::float::Float;
use crate::model::scene::Scene;

/// The measured bound of `|μ_approx − μ_exact| / (μ₀ A)` for eqs. 21 and 24
/// inside their validity domain (see module docs).
pub const MAX_ERROR_OVER_A: f64 = 0.0144;

/// Which approximation applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ApproxKind {
    /// Eq. 21: purely normal oscillation (Δu_x = 0).
    NormalEq21,
    /// Eq. 24: purely tangential oscillation (Δu_z = 0) with `k_xΔu_x/(μ₀k_z u_z0) ≤ 1`.
    TangentialEq24,
}

/// Why no approximation applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ApproxError {
    /// Both oscillations are present: neither eq. 21 nor eq. 24 describes the scene.
    DualMode,
    /// Tangential only, but `k_xΔu_x/(μ₀k_z u_z0) > 1`, where eq. 24 deviates
    /// strongly at low velocity (paper Fig. 3b).
    TangentialTooLarge,
    /// v₀ = 0: the law has two one-sided limits (use the static analysis).
    ZeroVelocity,
    /// v₀ is NaN or infinite.
    NonFiniteVelocity,
}

/// The approximation that applies to a scene, if any.
///
/// # Errors
/// [`ApproxError::DualMode`] or [`ApproxError::TangentialTooLarge`].
pub fn applicable<T: Float>(scene: &Scene<T>) -> Result<ApproxKind, ApproxError> {
    let d = scene.drive();
    if d.b == T::ZERO {
        Ok(ApproxKind::NormalEq21)
    } else if d.a == T::ZERO {
        if d.b <= T::ONE {
            Ok(ApproxKind::TangentialEq24)
        } else {
            Err(ApproxError::TangentialTooLarge)
        }
    } else {
        Err(ApproxError::DualMode)
    }
}

/// `μ/μ₀` from eq. 21 or eq. 24 (whichever applies) at velocity `v0` (m/s).
///
/// # Errors
/// See [`ApproxError`].
pub fn approx_mu_over_mu0<T: Float>(
    scene: &Scene<T>,
    v0: T,
) -> Result<(ApproxKind, T), ApproxError> {
    if !v0.is_finite() {
        return Err(ApproxError::NonFiniteVelocity);
    }
    let kind = applicable(scene)?;
    if v0 == T::ZERO {
        return Err(ApproxError::ZeroVelocity);
    }
    let d = scene.drive();
    let amp = match kind {
        ApproxKind::NormalEq21 => d.a,
        ApproxKind::TangentialEq24 => d.b,
    };
    let vc = CriticalVelocity::of(scene).for_velocity(v0);
    let sign = if v0 > T::ZERO { T::ONE } else { -T::ONE };
    let speed = v0.abs();
    if speed >= vc {
        return Ok((kind, sign));
    }
    Ok((kind, sign * law(speed / vc, amp)))
}

/// `1 − A[¾(x − 1)² + ¼(x − 1)⁴]` (eqs. 21, 24) for `x = |v₀|/v_c ∈ [0, 1]`.
#[inline]
pub fn law<T: Float>(x: T, amp: T) -> T {
    let y = x - T::ONE;
    let y2 = y * y;
    let q = T::from_f64(0.75) * y2 + T::from_f64(0.25) * y2 * y2;
    T::ONE - amp * q
}
