//! A profile's velocity law: μ/μ₀ at a velocity ([`mu_over_mu0`]), its
//! limits at rest, the critical velocities, the mean normal force, and the
//! per-spring means the quadrature integrates (exposed for tests).

use super::bed::curved;
use super::spring::{forward_critical, spring, Limit};
use super::{normal, MdrError, MdrResult, Profile};
use crate::model::exact::{self, precision_constant};
use crate::model::float::{Float, Math};
use crate::model::liftoff::{self, Shape};
use crate::model::scene::{ContactMode, Drive};

pub(crate) fn check<T: Float>(d: &Drive<T>, p: &Profile<T>) -> Result<(), MdrError> {
    p.validate()?;
    if !d.is_valid_with_contact(ContactMode::Intermittent) {
        return Err(MdrError::BadDrive);
    }
    if precision_constant::<T>() * (T::ONE + d.a + d.b) > T::from_f64(exact::ILL_CONDITIONED_AT) {
        return Err(MdrError::IllConditioned);
    }
    Ok(())
}

/// [`check`] for an answer at velocity `v` to tolerance `tol`: `v` finite,
/// `tol` finite and positive, and `v ≠ 0` where μ(0) is two-sided (`a < 1`).
pub(crate) fn check_moving<T: Float>(
    d: &Drive<T>,
    p: &Profile<T>,
    v: T,
    tol: T,
) -> Result<(), MdrError> {
    check(d, p)?;
    if !v.is_finite() {
        return Err(MdrError::BadVelocity);
    }
    if !(tol.is_finite() && tol > T::ZERO) {
        return Err(MdrError::BadTolerance);
    }
    if v == T::ZERO && d.a < T::ONE {
        return Err(MdrError::AtRest);
    }
    Ok(())
}

/// One spring of the foundation at band offset `d` (eq. M2) and velocity
/// `v ≥ 0` (forward convention; the quadrature mirrors `v < 0` before it
/// gets here): `(⟨s⟩, ⟨w⁺⟩)` over a period, units of `W₀` and `d₀` (eqs. M3,
/// M4). The quantity [`SPRING_PRECISION`](super::SPRING_PRECISION) bounds; exposed so that tests can
/// check it against an independent computation.
///
/// # Errors
/// [`MdrError::BadDrive`], [`MdrError::BadVelocity`] (`v` negative or not
/// finite), [`MdrError::IllConditioned`] (the spring's solver refused or
/// its window is a sliver at the rim), [`MdrError::Inconsistent`].
pub fn spring_means<T: Float, M: Math<T>>(
    drive: &Drive<T>,
    d: T,
    v: T,
) -> Result<(T, T), MdrError> {
    if !drive.is_valid_with_contact(ContactMode::Intermittent) || !d.is_finite() {
        return Err(MdrError::BadDrive);
    }
    if !(v.is_finite() && v >= T::ZERO) {
        return Err(MdrError::BadVelocity);
    }
    let s = spring::<T, M>(&Shape::of::<M>(drive, v), drive, d, v, Limit::Moving)?;
    if s.unresolved > T::ZERO {
        return Err(MdrError::IllConditioned);
    }
    Ok((s.stretch, s.band))
}

/// [`spring_means`] at rest, `V → 0⁺` (forward convention): the permanent
/// springs (`d > a`) take their one-sided limit μ(0⁺) of the flat punch
/// scaled by `d` (eq. M3), the intermittent ones their unique state. The
/// quantity [`limits_at_zero`] integrates (μ(0⁻) through the mirrored
/// drive); exposed so that tests can check it against an independent
/// computation.
///
/// # Errors
/// As [`spring_means`] except [`MdrError::BadVelocity`].
pub fn spring_means_at_rest<T: Float, M: Math<T>>(
    drive: &Drive<T>,
    d: T,
) -> Result<(T, T), MdrError> {
    if !drive.is_valid_with_contact(ContactMode::Intermittent) || !d.is_finite() {
        return Err(MdrError::BadDrive);
    }
    let s = spring::<T, M>(
        &Shape::of::<M>(drive, T::ZERO),
        drive,
        d,
        T::ZERO,
        Limit::Plus,
    )?;
    if s.unresolved > T::ZERO {
        return Err(MdrError::IllConditioned);
    }
    Ok((s.stretch, s.band))
}

/// Dimensionless critical velocities `(V_c⁺, V_c⁻)` of a profile: those of
/// the flat punch with the same drive (module docs), eq. 8 for `a < 1`,
/// eq. L5 for `a ≥ 1`. Multiply by `ωW₀` for m/s.
///
/// # Errors
/// [`MdrError::BadExponent`], [`MdrError::BadDrive`].
pub fn critical_velocities<T: Float, M: Math<T>>(
    d: &Drive<T>,
    p: &Profile<T>,
) -> Result<(T, T), MdrError> {
    p.validate()?;
    if !d.is_valid_with_contact(ContactMode::Intermittent) {
        return Err(MdrError::BadDrive);
    }
    let m = d.mirrored();
    Ok((
        forward_critical::<T, M>(&Shape::of::<M>(d, T::ZERO), d, T::ONE),
        forward_critical::<T, M>(&Shape::of::<M>(&m, T::ZERO), &m, T::ONE),
    ))
}

/// Whether a curved profile's static interval `[μ(0⁻), μ(0⁺)]` has a width
/// (docs/guide/lift-off-and-profiles.md, eq. S2): a permanent spring of band
/// offset `d > a` sticks at rest for stretches in `[c' − d, d − c]`, so
/// some spring does iff the central one (`d = 1`) does: `a < 1` and
/// `c + c' < 2` — the flat punch's own condition with the same drive. The
/// second implies the first (`c + c' = |a + z| + |a − z| ≥ 2a`), so it
/// alone is tested.
pub fn static_interval_exists<T: Float, M: Math<T>>(d: &Drive<T>) -> bool {
    d.c_forward::<M>() + d.c_backward::<M>() < T::TWO
}

/// The mean normal force `F̄z/(k_z u_z0)` of a profile at `a` with its
/// bound (units of `k_z u_z0`): `⟨w⁺⟩` of eq. L4 (1 for `a < 1`) for
/// [`Profile::Flat`], else `D` of eq. M5 ([`normal::mean_normal_force`],
/// whose doc states how the scene's `k_z` reads for a curved profile).
///
/// # Errors
/// As [`normal::mean_normal_force`].
pub fn mean_normal_force<T: Float, M: Math<T>>(
    p: &Profile<T>,
    a: T,
    tol: T,
) -> Result<(T, T), MdrError> {
    p.validate()?;
    match p.exponent() {
        None if !(a.is_finite() && a >= T::ZERO) => Err(MdrError::BadDrive),
        None if a < T::ONE => Ok((T::ONE, T::ZERO)),
        None => {
            let d = liftoff::mean_band::<T, M>(a);
            Ok((d, T::from_f64(64.0) * T::EPSILON * d))
        }
        Some(n) => normal::mean_normal_force::<T, M>(n, a, tol),
    }
}

/// `μ/μ₀` of a profile at dimensionless velocity `v` (units of `ωW₀`,
/// `W₀ = μ₀ (E*/G*) d₀`) with a bound `≤ tol` (units of μ₀). [`Profile::Flat`]
/// is the single spring ([`crate::model::exact`], or [`crate::model::liftoff`]
/// for `a ≥ 1`).
///
/// # Errors
/// [`MdrError::BadExponent`], [`MdrError::BadDrive`], [`MdrError::BadVelocity`],
/// [`MdrError::BadTolerance`], [`MdrError::IllConditioned`],
/// [`MdrError::ToleranceTooTight`], [`MdrError::NotConverged`],
/// [`MdrError::AtRest`] (`v = 0`, `a < 1`), [`MdrError::Inconsistent`].
pub fn mu_over_mu0<T: Float, M: Math<T>>(
    d: &Drive<T>,
    p: &Profile<T>,
    v: T,
    tol: T,
) -> Result<MdrResult<T>, MdrError> {
    check_moving(d, p, v, tol)?;
    let Some(n) = p.exponent() else {
        return flat::<T, M>(d, v, tol);
    };
    if v >= T::ZERO {
        curved::<T, M>(d, n, v, Limit::Moving, tol)
    } else {
        curved::<T, M>(&d.mirrored(), n, -v, Limit::Moving, tol).map(|r| MdrResult {
            mu_over_mu0: -r.mu_over_mu0,
            ..r
        })
    }
}

/// The one-sided limits `(μ(0⁺), μ(0⁻))/μ₀` of a profile's velocity law
/// (equal for `a ≥ 1`, where μ(0) is unique), each with its bound.
///
/// # Errors
/// As [`mu_over_mu0`] except [`MdrError::AtRest`] and [`MdrError::BadVelocity`].
pub fn limits_at_zero<T: Float, M: Math<T>>(
    d: &Drive<T>,
    p: &Profile<T>,
    tol: T,
) -> Result<(MdrResult<T>, MdrResult<T>), MdrError> {
    check(d, p)?;
    if !(tol.is_finite() && tol > T::ZERO) {
        return Err(MdrError::BadTolerance);
    }
    if d.a >= T::ONE {
        let r = mu_over_mu0::<T, M>(d, p, T::ZERO, tol)?;
        return Ok((r, r));
    }
    let Some(n) = p.exponent() else {
        let bound = exact::error_bound::<T, M>(d);
        if bound > tol {
            return Err(MdrError::ToleranceTooTight {
                best: bound.to_f64(),
            });
        }
        let (plus, minus) = exact::limits_at_zero::<T, M>(d).map_err(|_| MdrError::Inconsistent)?;
        let r = |m| MdrResult {
            mu_over_mu0: m,
            bound,
            evaluations: 1,
        };
        return Ok((r(plus), r(minus)));
    };
    let plus = curved::<T, M>(d, n, T::ZERO, Limit::Plus, tol)?;
    let minus = curved::<T, M>(&d.mirrored(), n, T::ZERO, Limit::Plus, tol)?;
    Ok((
        plus,
        MdrResult {
            mu_over_mu0: -minus.mu_over_mu0,
            ..minus
        },
    ))
}

/// The flat punch (no quadrature).
fn flat<T: Float, M: Math<T>>(d: &Drive<T>, v: T, tol: T) -> Result<MdrResult<T>, MdrError> {
    let (m, bound) = if d.a >= T::ONE {
        let m = liftoff::mu_over_mu0::<T, M>(d, v).map_err(|e| match e {
            liftoff::LiftOffError::IllConditioned => MdrError::IllConditioned,
            _ => MdrError::Inconsistent,
        })?;
        (m, liftoff::error_bound::<T, M>(d))
    } else {
        let m = exact::mu_over_mu0::<T, M>(d, v).map_err(|e| match e {
            exact::ExactError::IllConditioned => MdrError::IllConditioned,
            _ => MdrError::Inconsistent,
        })?;
        (m, exact::error_bound::<T, M>(d))
    };
    if m.abs() == T::ONE {
        // Continuous sliding: exact.
        return Ok(MdrResult {
            mu_over_mu0: m,
            bound: T::ZERO,
            evaluations: 1,
        });
    }
    if bound > tol {
        return Err(MdrError::ToleranceTooTight {
            best: bound.to_f64(),
        });
    }
    Ok(MdrResult {
        mu_over_mu0: m,
        bound,
        evaluations: 1,
    })
}
