//! The powers of a curved profile's steady state (the load line's powers
//! for every contact): the bed's sum of the springs' powers ([`crate::model::load_line`]).
//!
//! Per spring of band offset `d` (eq. M2 of [`super`]), per unit phase and
//! unit `ξ` (units `k_x W₀ ωW₀`, `k_x = 2G*a₀`):
//!
//! * `d > a` (permanent contact): the flat punch scaled by `d` — `s = d·s̃`
//!   with `s̃` the flat solution of `(a/d, b/d, V/d)` — so the input `⟨s X'⟩`
//!   and the friction loss are `d²` times the flat punch's
//!   ([`crate::model::load_line::powers`]) and `⟨s⟩ = d μ̃`;
//! * `|d| ≤ a` (contact window): the closed forms of
//!   [`crate::model::load_line::liftoff_powers`] on the window's arcs of the
//!   band `d − a cos θ`, from `s = 0` at landing to `s = 0` at lift-off (the
//!   same argument: nothing is lost or released at the opening);
//! * `d ≤ −a`: never touches, 0.
//!
//! Each spring balances exactly (`[s²/2] = 0` over its period or window);
//! so does the bed. The totals are `∫₀^{ξ_max} (…) dξ` over the springs that
//! ever touch, divided by `D` (eq. M5; `F̄z = k_z u_z0 D`) for the unit
//! `μ₀F̄z ωW₀`: `P_out = −V∫⟨s⟩dξ/D = −μV`. The ξ-range is split at
//! `ξ_a = (1 − a)^{1/n}` (lift-off onset) and each piece mapped
//! `ξ = l + (r − l)(1 − cos t)/2` as in [`super`]'s μ quadrature; adaptive
//! Gauss–Kronrod–Patterson ([`quadrature`]), bound `4·ΣE/D` (E the per-interval
//! estimates, [`SAFETY`] = 4; an **estimate**: the kinks of
//! the springs' arc structure are left to the bisection, not searched as
//! for μ) plus the per-spring solvers' part `ε_s(1 + a + b)ξ_max/D`.

use super::{normal, quadrature, MdrError, Profile, SAFETY};
use crate::model::exact::{self, precision_constant, ExactError};
use crate::model::float::{Float, Math};
use crate::model::liftoff::{self, LiftOffError};
use crate::model::load_line::{self, arc_work, Powers};
use crate::model::scene::Drive;

/// The powers of a profile with the bound of each power (units `μ₀F̄z ωW₀`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ProfilePowers<T> {
    /// `μ/μ₀` and the powers (module docs).
    pub powers: Powers<T>,
    /// Bound (estimate) of each power and of `μ/μ₀`.
    pub bound: T,
    /// `D = F̄z/(k_z u_z0)` used.
    pub mean_normal: T,
}

/// One spring's `[input, friction, ⟨s⟩]` per unit phase (module docs).
fn spring_powers<T: Float, M: Math<T>>(d: &Drive<T>, dd: T, v: T) -> Result<[T; 3], MdrError> {
    let a = d.a;
    if dd <= -a {
        return Ok([T::ZERO; 3]);
    }
    if dd > a {
        let s = Drive {
            a: a / dd,
            b: d.b / dd,
            bc: d.bc / dd,
            bs: d.bs / dd,
        };
        let p = load_line::powers::<T, M>(&s, v / dd).map_err(|e| match e {
            ExactError::IllConditioned => MdrError::IllConditioned,
            _ => MdrError::Inconsistent,
        })?;
        let d2 = dd * dd;
        return Ok([d2 * p.input, d2 * p.friction, dd * p.mu_over_mu0]);
    }
    // A sliver of contact at the rim: nothing a solver can resolve, and
    // nothing to count (its band's mean is below the rounding floor).
    let floor = T::from_f64(64.0) * T::EPSILON * (T::ONE + a + d.b);
    if normal::mean_band::<T, M>(dd, a) <= floor {
        return Ok([T::ZERO; 3]);
    }
    let (_, arcs) = liftoff::banded_window_arcs::<T, M>(d, dd, v).map_err(|e| match e {
        LiftOffError::IllConditioned => MdrError::IllConditioned,
        _ => MdrError::Inconsistent,
    })?;
    let w = arc_work::<T, M>(d, dd, v, &arcs, T::ZERO);
    let inv = T::ONE / T::TAU;
    Ok([w.input * inv, w.friction * inv, w.stretch * inv])
}

/// The powers of `profile` at dimensionless velocity `v` (module docs) with
/// a bound `≤ tol`. [`Profile::Flat`] is the single spring
/// ([`load_line::powers`], or [`load_line::liftoff_powers`] for `a ≥ 1`,
/// bound: the solvers').
///
/// # Errors
/// [`MdrError::AtRest`] (`v = 0` with springs in permanent contact, `a < 1`),
/// [`MdrError::BadVelocity`], [`MdrError::BadTolerance`],
/// [`MdrError::BadExponent`], [`MdrError::BadDrive`],
/// [`MdrError::IllConditioned`], [`MdrError::NotConverged`],
/// [`MdrError::Inconsistent`].
pub fn profile_powers<T: Float, M: Math<T>>(
    d: &Drive<T>,
    p: &Profile<T>,
    v: T,
    tol: T,
) -> Result<ProfilePowers<T>, MdrError> {
    super::check_moving(d, p, v, tol)?;
    let a = d.a;
    let Some(n) = p.exponent() else {
        return flat::<T, M>(d, v);
    };
    let (den, den_bound) = normal::mean_normal_force::<T, M>(n, a, T::from_f64(1e-12))?;
    let xi_a = if a < T::ONE {
        Profile::root(n, T::ONE - a)
    } else {
        T::ZERO
    };
    let xi_max = Profile::root(n, T::ONE + a);
    let pieces = [(T::ZERO, xi_a), (xi_a, xi_max)];
    let integrand = |u: T| -> Result<[T; 3], MdrError> {
        let k = if u < T::PI { 0 } else { 1 };
        let (l, r) = pieces[k];
        if r <= l {
            return Ok([T::ZERO; 3]);
        }
        let t = u - T::PI * T::from_u32(k as u32);
        let (sin_t, cos_t) = M::sin_cos(t);
        let half = (r - l) * T::HALF;
        let xi = l + half * (T::ONE - cos_t);
        let jac = half * sin_t;
        let w = spring_powers::<T, M>(d, T::ONE - Profile::power(n, xi), v)?;
        Ok([w[0] * jac, w[1] * jac, w[2] * jac])
    };
    let eps_s = (precision_constant::<T>() + T::from_f64(M::MAX_REL_ERROR)) * (T::ONE + a + d.b);
    let solver = eps_s * (T::ONE + a + d.b + v.abs()) * xi_max / den;
    let safety = T::from_f64(SAFETY);
    let floor = T::from_f64(64.0) * T::EPSILON;
    let bound_of = |e: [T; 3], val: [T; 3]| {
        let scale = val[0].abs().max(val[1].abs()) / den;
        safety * e[0].max(e[1]).max(e[2]) / den + solver + den_bound / den * scale + floor
    };
    let ends = [T::ZERO, T::PI, T::TAU];
    let out = quadrature::integrate(integrand, &ends, tol, bound_of)?;
    let bound = bound_of(out.error, out.value);
    if !out.converged || bound.is_nan() || bound > tol {
        return Err(MdrError::NotConverged {
            reached: bound.to_f64(),
        });
    }
    let mu = out.value[2] / den;
    Ok(ProfilePowers {
        powers: Powers {
            mu_over_mu0: mu,
            input: out.value[0] / den,
            output: -mu * v,
            friction: out.value[1] / den,
        },
        bound,
        mean_normal: den,
    })
}

/// The flat punch's powers with the solvers' bound.
fn flat<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Result<ProfilePowers<T>, MdrError> {
    if d.a >= T::ONE {
        let p = load_line::liftoff_powers::<T, M>(d, v).map_err(|e| match e {
            LiftOffError::IllConditioned => MdrError::IllConditioned,
            _ => MdrError::Inconsistent,
        })?;
        let b = liftoff::error_bound::<T, M>(d) * (T::ONE + d.a + d.b + v.abs());
        return Ok(ProfilePowers {
            powers: p,
            bound: b,
            mean_normal: liftoff::mean_band::<T, M>(d.a),
        });
    }
    let p = load_line::powers::<T, M>(d, v).map_err(|e| match e {
        ExactError::IllConditioned => MdrError::IllConditioned,
        _ => MdrError::Inconsistent,
    })?;
    Ok(ProfilePowers {
        powers: p,
        bound: exact::error_bound::<T, M>(d) * (T::ONE + d.a + d.b + v.abs()),
        mean_normal: T::ONE,
    })
}
