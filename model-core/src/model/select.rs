//! The cheapest computation of μ whose error bound meets a tolerance
//! ("model no more than the scene needs").
//!
//! In order of cost, for a scene and a velocity `v₀`:
//!
//! 1. `|v₀| ≥ v_c` (eq. 8): continuous sliding, `μ = ±μ₀` exactly (bound 0,
//!    no integration);
//! 2. `v₀ = 0`: the static analysis — the one-sided limits μ(0±) and the
//!    static interval (bound: the exact solver's);
//! 3. a closed-form approximation, eq. 21 (normal only) or eq. 24 (tangential
//!    only, `b ≤ 1`), when its measured bound
//!    `MAX_ERROR_OVER_A · A` (eqs. 21, 24: 0.0144·A) is within the tolerance;
//! 4. the exact solver ([`crate::model::exact`]), bound [`crate::model::exact::error_bound`].
//!
//! A scene that lifts off (`a ≥ 1`, [`crate::model::scene::ContactMode::Intermittent`])
//! is answered by the lift-off solver ([`crate::model::liftoff`]): continuous
//! sliding beyond the window's critical velocities ([`Method::Sliding`],
//! bound 0), otherwise [`Method::Exact`] with bound
//! [`crate::model::liftoff::error_bound`] — at `v₀ = 0` too, as a
//! [`Value::Mu`] (μ at rest is unique with lift-off). The approximations and
//! the static analysis assume permanent contact and are not used.
//!
//! A curved profile ([`mu_within_profile`]) is answered by the MDR quadrature
//! ([`crate::model::mdr`], [`Method::Mdr`]) or, beyond the critical
//! velocities (the flat punch's, for every profile), by [`Method::Sliding`];
//! [`Profile::Flat`] is exactly [`mu_within`] (the single spring, with the
//! lift-off branch only for `a ≥ 1`). At `v₀ = 0` with `a < 1` a curved
//! profile gives [`Value::Limits`] (μ(0±) without the flat punch's static
//! analysis, which does not apply to it).
//!
//! The fixed-step integrator is never chosen: it is slower than the exact
//! solver at every accuracy (`fricctl bench work-precision`) and is used only
//! when asked for.

use crate::model::analytic::approx::{approx_mu_over_mu0, ApproxKind, MAX_ERROR_OVER_A};
use crate::model::analytic::critical_velocity::CriticalVelocity;
use crate::model::analytic::static_friction::StaticFriction;
use crate::model::exact::{self, ExactError};
use crate::model::float::{Float, Math};
use crate::model::liftoff::{self, LiftOffError};
use crate::model::mdr::{self, MdrError, Profile};
use crate::model::scene::Scene;

/// Which computation answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Method {
    /// `|v₀| ≥ v_c`: `±μ₀`.
    Sliding,
    /// `v₀ = 0`: the static analysis.
    Static,
    /// An approximation (eq. 21 or 24).
    Approx(ApproxKind),
    /// The exact steady-state solver.
    Exact,
    /// The MDR quadrature over the springs of a curved profile.
    Mdr,
}

impl Method {
    /// The name used in reports: `sliding`, `static`, `approx_eq21`,
    /// `approx_eq24`, `exact`, `mdr`.
    pub const fn name(self) -> &'static str {
        match self {
            Method::Sliding => "sliding",
            Method::Static => "static",
            Method::Approx(ApproxKind::NormalEq21) => "approx_eq21",
            Method::Approx(ApproxKind::TangentialEq24) => "approx_eq24",
            Method::Exact => "exact",
            Method::Mdr => "mdr",
        }
    }
}

/// The value computed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Value<T> {
    /// `μ/μ₀` of a moving contact.
    Mu(T),
    /// At rest: the one-sided limits `μ(0±)/μ₀` and the static interval.
    AtRest {
        /// `lim μ/μ₀` for `v₀ → 0⁺`.
        mu_0plus: T,
        /// `lim μ/μ₀` for `v₀ → 0⁻`.
        mu_0minus: T,
        /// The static analysis.
        statics: StaticFriction<T>,
    },
    /// At rest, a curved profile with `a < 1`: the one-sided limits
    /// `μ(0±)/μ₀` of the velocity law (no static analysis).
    Limits {
        /// `lim μ/μ₀` for `v₀ → 0⁺`.
        mu_0plus: T,
        /// `lim μ/μ₀` for `v₀ → 0⁻`.
        mu_0minus: T,
    },
}

/// An answer with the method that gave it and its guaranteed bound.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Answer<T> {
    /// The value.
    pub value: Value<T>,
    /// Which computation answered.
    pub method: Method,
    /// Bound of the error of every μ/μ₀ in `value`, in units of μ₀ (≤ `tol`).
    pub bound: T,
}

/// Why no answer within the tolerance was given.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SelectError<T> {
    /// The tolerance is NaN, infinite or ≤ 0.
    BadTolerance,
    /// No method guarantees this tolerance here; `best` is the smallest bound
    /// available (the exact solver's).
    ToleranceTooTight {
        /// The smallest guaranteed bound, units of μ₀.
        best: T,
    },
    /// The exact solver failed (bad velocity, ill-conditioned drive, …).
    Exact(ExactError),
    /// The MDR of a curved profile failed (bad exponent, quadrature not
    /// converged, …).
    Mdr(MdrError),
}

/// μ of a scene whose contact has the shape `profile` (the scene's `u_z0`
/// read as the mean indentation `d₀`, `k_z/k_x` as `E*/G*`), by the cheapest
/// method within `tol` (module docs). [`Profile::Flat`] gives exactly
/// [`mu_within`].
///
/// # Errors
/// See [`SelectError`]; [`SelectError::Mdr`] for a bad exponent and the
/// quadrature's refusals.
pub fn mu_within_profile<T: Float, M: Math<T>>(
    scene: &Scene<T>,
    profile: &Profile<T>,
    v0: T,
    tol: T,
) -> Result<Answer<T>, SelectError<T>> {
    profile.validate().map_err(SelectError::Mdr)?;
    if *profile == Profile::Flat {
        return mu_within::<T, M>(scene, v0, tol);
    }
    if !(tol.is_finite() && tol > T::ZERO) {
        return Err(SelectError::BadTolerance);
    }
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(|e| SelectError::Exact(ExactError::BadVelocity(e)))?;
    let d = scene.drive();
    let as_select = |e: MdrError| match e {
        MdrError::ToleranceTooTight { best } => SelectError::ToleranceTooTight {
            best: T::from_f64(best),
        },
        MdrError::BadTolerance => SelectError::BadTolerance,
        e => SelectError::Mdr(e),
    };
    let (c_forward, c_backward) =
        mdr::critical_velocities::<T, M>(&d, profile).map_err(as_select)?;
    if (v > T::ZERO && v >= c_forward) || (v < T::ZERO && -v >= c_backward) {
        let s = if v > T::ZERO { T::ONE } else { -T::ONE };
        return Ok(Answer {
            value: Value::Mu(s),
            method: Method::Sliding,
            bound: T::ZERO,
        });
    }
    if v == T::ZERO && d.a < T::ONE {
        let (plus, minus) = mdr::limits_at_zero::<T, M>(&d, profile, tol).map_err(as_select)?;
        return Ok(Answer {
            value: Value::Limits {
                mu_0plus: plus.mu_over_mu0,
                mu_0minus: minus.mu_over_mu0,
            },
            method: Method::Mdr,
            bound: plus.bound.max(minus.bound),
        });
    }
    let r = mdr::mu_over_mu0::<T, M>(&d, profile, v, tol).map_err(as_select)?;
    Ok(Answer {
        value: Value::Mu(r.mu_over_mu0),
        method: Method::Mdr,
        bound: r.bound,
    })
}

/// μ at `v0` (m/s) by the cheapest method whose bound is within `tol`
/// (units of μ₀), with backend `M` for the exact solver.
///
/// # Errors
/// See [`SelectError`]. A non-finite `v0` gives
/// `SelectError::Exact(ExactError::BadVelocity(_))`.
pub fn mu_within<T: Float, M: Math<T>>(
    scene: &Scene<T>,
    v0: T,
    tol: T,
) -> Result<Answer<T>, SelectError<T>> {
    if !(tol.is_finite() && tol > T::ZERO) {
        return Err(SelectError::BadTolerance);
    }
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(|e| SelectError::Exact(ExactError::BadVelocity(e)))?;
    if scene.lifts_off() {
        return lift_off_within::<T, M>(scene, v, tol);
    }
    let vc = CriticalVelocity::of(scene).for_velocity(v0);
    if v0 != T::ZERO && v0.abs() >= vc {
        let s = if v0 > T::ZERO { T::ONE } else { -T::ONE };
        return Ok(Answer {
            value: Value::Mu(s),
            method: Method::Sliding,
            bound: T::ZERO,
        });
    }
    let d = scene.drive();
    let exact_bound = exact::error_bound::<T, M>(&d);
    if v0 == T::ZERO {
        if exact_bound > tol {
            return Err(SelectError::ToleranceTooTight { best: exact_bound });
        }
        let (mu_0plus, mu_0minus) =
            exact::limits_at_zero::<T, M>(&d).map_err(SelectError::Exact)?;
        return Ok(Answer {
            value: Value::AtRest {
                mu_0plus,
                mu_0minus,
                statics: StaticFriction::of_with::<M>(scene),
            },
            method: Method::Static,
            bound: exact_bound,
        });
    }
    if let Ok((kind, m)) = approx_mu_over_mu0(scene, v0) {
        let amp = match kind {
            ApproxKind::NormalEq21 => d.a,
            ApproxKind::TangentialEq24 => d.b,
        };
        let bound = T::from_f64(MAX_ERROR_OVER_A) * amp;
        if bound <= tol {
            return Ok(Answer {
                value: Value::Mu(m),
                method: Method::Approx(kind),
                bound,
            });
        }
    }
    if exact_bound > tol {
        return Err(SelectError::ToleranceTooTight { best: exact_bound });
    }
    let m = exact::mu_over_mu0::<T, M>(&d, v).map_err(SelectError::Exact)?;
    Ok(Answer {
        value: Value::Mu(m),
        method: Method::Exact,
        bound: exact_bound,
    })
}

/// [`mu_within`] for a scene that lifts off (module docs); `v` dimensionless.
fn lift_off_within<T: Float, M: Math<T>>(
    scene: &Scene<T>,
    v: T,
    tol: T,
) -> Result<Answer<T>, SelectError<T>> {
    // The lift-off solver's errors in the exact solver's terms (the only ones
    // this path can meet: the drive comes from a validated scene with a ≥ 1).
    let as_exact = |e: LiftOffError| {
        SelectError::Exact(match e {
            LiftOffError::BadVelocity(e) => ExactError::BadVelocity(e),
            LiftOffError::IllConditioned => ExactError::IllConditioned,
            LiftOffError::Inconsistent => ExactError::Inconsistent,
            _ => ExactError::BadDrive,
        })
    };
    let d = scene.drive();
    let (c_forward, c_backward) = liftoff::critical_velocities::<T, M>(&d).map_err(as_exact)?;
    if v >= c_forward || -v >= c_backward {
        let s = if v >= c_forward { T::ONE } else { -T::ONE };
        return Ok(Answer {
            value: Value::Mu(s),
            method: Method::Sliding,
            bound: T::ZERO,
        });
    }
    let bound = liftoff::error_bound::<T, M>(&d);
    if bound > tol {
        return Err(SelectError::ToleranceTooTight { best: bound });
    }
    let m = liftoff::mu_over_mu0::<T, M>(&d, v).map_err(as_exact)?;
    Ok(Answer {
        value: Value::Mu(m),
        method: Method::Exact,
        bound,
    })
}
