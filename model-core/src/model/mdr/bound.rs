//! The bound's constants and its per-spring part: the safety factor on the
//! quadrature's estimate, the per-spring solvers' precision, and the
//! tightest tolerance a drive allows.

use super::{normal, Profile};
use crate::model::exact::precision_constant;
use crate::model::float::{Float, Math};
use crate::model::scene::Drive;

/// Safety factor on the quadrature's estimate in the bound (module docs:
/// with the 10/21/43 rules of [`quadrature`](super::quadrature), 2 left the estimate check at
/// 0.99 of the bounds, 4 at 0.54; 0.60 with the closed-form kinks).
pub const SAFETY: f64 = 4.0;

/// The per-spring precision constant of the quadrature's bound in f64:
/// each spring's `⟨s⟩` ([`spring_means`](super::spring_means)) errs by at most this times
/// `1 + a + b` (units of `W₀`), moving and at rest (μ(0±)).
///
/// It is tighter than the flat solvers' generic constant
/// ([`precision_constant`], 10⁻⁹, the level a plain fixed-step run can
/// check): `tests/mdr_spring.rs` checks the per-spring solvers against a
/// brute force written to avoid accumulated rounding, at 2²¹ steps per
/// period, over 48 random springs at `V > 0` (permanent, intermittent, near
/// the onset and the rim) and 32 at rest ([`spring_means_at_rest`](super::spring_means_at_rest): the
/// permanent springs' one-sided limit μ(0⁺) against the brute force's orbit
/// through a forward clamp at `V = 0`), and requires `|solver − brute| +
/// brute allowance ≤ SPRING_PRECISION·(1 + a + b)` for each (worst measured
/// 4.3·10⁻¹³ and 2.8·10⁻¹³). f32 keeps its generic constant (10⁻⁶).
pub const SPRING_PRECISION: f64 = 1e-11;

/// The per-spring constant in `T` ([`SPRING_PRECISION`] in f64, the flat
/// solvers' [`precision_constant`] otherwise).
pub(super) fn spring_constant<T: Float>() -> T {
    if T::EPSILON < T::from_f64(1e-10) {
        T::from_f64(SPRING_PRECISION)
    } else {
        precision_constant::<T>()
    }
}

/// The per-spring solver part of the bound of a curved profile at `V ≠ 0`
/// (or any `V` with `a ≥ 1`), units of μ₀, before the quadrature:
/// `ε_s ξ_max / D_min` with `ε_s = (SPRING_PRECISION + backend)(1 + a + b)`
/// ([`SPRING_PRECISION`] in f64), `D ≥ n/(n + 1)` (Jensen:
/// `⟨(1 − a cos θ)₊^p⟩ ≥ ⟨1 − a cos θ⟩^p = 1`, eq. M5), or the closed form `D`.
/// The smallest tolerance [`mu_over_mu0`](super::mu_over_mu0) can meet is above it.
pub fn solver_bound<T: Float, M: Math<T>>(d: &Drive<T>, n: T) -> T {
    let eps_s = (spring_constant::<T>() + T::from_f64(M::MAX_REL_ERROR)) * (T::ONE + d.a + d.b);
    let xi_max = Profile::root(n, T::ONE + d.a);
    let dmin = normal::closed_form::<T, M>(n, d.a).unwrap_or(n / (n + T::ONE));
    eps_s * xi_max / dmin + T::from_f64(64.0) * T::EPSILON
}

/// [`solver_bound`] for the one-sided limits at rest ([`limits_at_zero`](super::limits_at_zero)):
/// the same since the springs at rest were checked at [`SPRING_PRECISION`]
/// too (before, the permanent springs' μ(0⁺) kept the flat solver's generic
/// 10⁻⁹ and this was 3–8·10⁻⁹ for a sphere with `a < 1`).
pub fn solver_bound_at_rest<T: Float, M: Math<T>>(d: &Drive<T>, n: T) -> T {
    solver_bound::<T, M>(d, n)
}
