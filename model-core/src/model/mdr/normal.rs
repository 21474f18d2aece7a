//! The mean normal force of a profile, `D = ∫₀^{ξ_max} ⟨w⁺⟩ dξ` (units of
//! `E* d₀ a₀`, one side `x > 0`), per spring and in closed form where one
//! exists.
//!
//! Per spring (`w = d − a cos θ`, eq. M2 of [`super`]):
//!
//! ```text
//! ⟨w⁺⟩(d) = d                                       d ≥ a
//!         = (d(π − θ_c) + √(a² − d²))/π,  cos θ_c = d/a    |d| < a      (M4)
//!         = 0                                       d ≤ −a
//! ```
//!
//! Integrated over the springs first (for each θ the band is positive on
//! `ξ < (1 − a cos θ)^{1/n}`): `D = n/(n+1)·⟨(1 − a cos θ)₊^{1+1/n}⟩_θ` (M5).
//! Closed forms: the cone (`n = 1`) for every `a`,
//!
//! ```text
//! D = (1 + a²/2)/2                                              a ≤ 1
//!   = [(π − θ₁)(1 + a²/2) + 2a sin θ₁ − (a²/4) sin 2θ₁]/(2π),  cos θ₁ = 1/a,  a > 1   (M6)
//! ```
//!
//! and the sphere (`n = 2`) for `a ≤ 1` with the complete elliptic
//! integrals `K`, `E` of modulus `k² = 2a/(1 + a)`:
//!
//! ```text
//! D = (4/(9π)) (1 + a)^{3/2} [2(2 − k²) E(k) − (1 − k²) K(k)]                (M7)
//! ```
//!
//! (`θ = π − 2u` turns `1 − a cos θ` into `(1 + a)(1 − k² sin² u)` and
//! `∫₀^{π/2} (1 − k² sin² u)^{3/2} du = [2(2 − k²)E − (1 − k²)K]/3`;
//! `a = 0` gives `2/3 = ∫₀¹ (1 − ξ²) dξ`). Other cases are integrated with
//! the numerator ([`super`]).

use super::{quadrature, MdrError};
use crate::model::float::{Float, Math};

/// `⟨w⁺⟩` of a spring with band offset `d` (eq. M4), units of `d₀`.
pub fn mean_band<T: Float, M: Math<T>>(d: T, a: T) -> T {
    if d >= a {
        d
    } else if d <= -a {
        T::ZERO
    } else {
        let root = M::sqrt(((a - d) * (a + d)).max(T::ZERO));
        let theta_c = M::atan2(root, d);
        (d * (T::PI - theta_c) + root) / T::PI
    }
}

/// `D` in closed form (eqs. M6, M7), or `None` where there is none here.
pub fn closed_form<T: Float, M: Math<T>>(n: T, a: T) -> Option<T> {
    if n == T::ONE {
        let half_a2 = a * a * T::HALF;
        if a <= T::ONE {
            return Some((T::ONE + half_a2) * T::HALF);
        }
        let sin1 = M::sqrt((a - T::ONE) * (a + T::ONE)) / a;
        let cos1 = T::ONE / a;
        let theta1 = M::atan2(sin1, cos1);
        let s2 = T::TWO * sin1 * cos1;
        return Some(
            ((T::PI - theta1) * (T::ONE + half_a2) + T::TWO * a * sin1
                - a * a * s2 / T::from_f64(4.0))
                / T::TAU,
        );
    }
    if n == T::TWO && a <= T::ONE {
        let k2 = T::TWO * a / (T::ONE + a);
        let (k, e) = elliptic_ke::<T, M>(k2);
        let one_a = T::ONE + a;
        return Some(
            T::from_f64(4.0 / (9.0 * core::f64::consts::PI))
                * one_a
                * M::sqrt(one_a)
                * (T::TWO * (T::TWO - k2) * e - (T::ONE - k2) * k),
        );
    }
    None
}

/// Complete elliptic integrals `(K(k), E(k))` for `0 ≤ k² ≤ 1` by the
/// arithmetic–geometric mean (quadratic convergence; `K = π/(2 AGM(1, k'))`,
/// `E = K (1 − Σ 2^{j−1} c_j²)`, `c₀ = k`). `k² = 1` (`a = 1`) gives
/// `K = ∞`, multiplied by `1 − k² = 0` in eq. M7: handled there by
/// `(1 − k²) K → 0`, here by returning `K` finite-capped (`E(1) = 1`).
fn elliptic_ke<T: Float, M: Math<T>>(k2: T) -> (T, T) {
    if k2 >= T::ONE {
        // (1 − k²)K → 0 as k → 1; return K = 0 with E = 1 so eq. M7 is exact.
        return (T::ZERO, T::ONE);
    }
    let mut a = T::ONE;
    let mut b = M::sqrt(T::ONE - k2);
    let mut sum = k2 * T::HALF; // 2^{-1} c₀²
    let mut pow = T::HALF;
    for _ in 0..40 {
        let c = (a - b) * T::HALF;
        pow *= T::TWO;
        sum += pow * c * c;
        let an = (a + b) * T::HALF;
        b = M::sqrt(a * b);
        a = an;
        if c.abs() <= T::EPSILON * a {
            break;
        }
    }
    let k = T::FRAC_PI_2 / a;
    (k, k * (T::ONE - sum))
}

/// The mean normal force of a profile `n` at `a = Δu_z/d₀`, `D` of eq. M5
/// (units `E* d₀ a₀` per side), with its error bound, `≤ tol·D`.
///
/// **In the scene's units.** The scene's `k_z`, `k_x` of a curved profile
/// are its incremental stiffnesses at the mean indentation, `2E*a₀` and
/// `2G*a₀` (for every axisymmetric profile the MDR's contact of radius `a₀`
/// has normal stiffness `2E*a₀`, as the flat punch of that radius; so
/// `k_z/k_x = E*/G*` as [`super`] reads them). The mean normal force of both
/// sides, `2E* d₀ a₀ D`, is then `k_z u_z0 · D` (`u_z0 = d₀`): **`D` is
/// `F̄z/(k_z u_z0)`**, as `⟨w⁺⟩` is for the flat punch (its limit `n → ∞`:
/// `ξ_max → 1`, `D → ⟨w⁺⟩`). `a = 0` gives `n/(n + 1)` (Hertz: `2/3`).
///
/// Closed form (eqs. M6, M7) where there is one (bound: rounding, 64ε·D);
/// otherwise M5 by adaptive Gauss–Kronrod–Patterson over `θ ∈ [θ₁, π]`, `cos θ₁ =
/// 1/a` for `a > 1` (0 else), mapped `θ = θ₁ + (π − θ₁)(1 − cos t)/2` so the
/// `(θ − θ₁)^{1+1/n}` onset is smooth in `t`; bound `4·ΣE` (E the per-interval estimates of [`super::quadrature`], [`super::SAFETY`])
/// (an estimate, [`super::quadrature`]) plus 64ε·D.
///
/// # Errors
/// [`MdrError::BadExponent`] (`n` not finite or ≤ 0), [`MdrError::BadDrive`]
/// (`a` negative or not finite), [`MdrError::BadTolerance`],
/// [`MdrError::NotConverged`].
pub fn mean_normal_force<T: Float, M: Math<T>>(n: T, a: T, tol: T) -> Result<(T, T), MdrError> {
    if !(n.is_finite() && n > T::ZERO) {
        return Err(MdrError::BadExponent);
    }
    if !(a.is_finite() && a >= T::ZERO) {
        return Err(MdrError::BadDrive);
    }
    if !(tol.is_finite() && tol > T::ZERO) {
        return Err(MdrError::BadTolerance);
    }
    let floor = T::from_f64(64.0) * T::EPSILON;
    if let Some(d) = closed_form::<T, M>(n, a) {
        return Ok((d, floor * d));
    }
    let theta1 = if a > T::ONE {
        M::atan2(M::sqrt((a - T::ONE) * (a + T::ONE)), T::ONE)
    } else {
        T::ZERO
    };
    let p = T::ONE + T::ONE / n;
    let half = (T::PI - theta1) * T::HALF;
    let f = |t: T| -> Result<[T; 1], MdrError> {
        let (sin_t, cos_t) = M::sin_cos(t);
        let theta = theta1 + half * (T::ONE - cos_t);
        let (_, c) = M::sin_cos(theta);
        let w = T::ONE - a * c;
        let v = if w > T::ZERO {
            T::from_f64(libm::pow(w.to_f64(), p.to_f64()))
        } else {
            T::ZERO
        };
        Ok([v * half * sin_t])
    };
    // D = n/(n+1)·(1/π)∫₀^π (1 − a cos θ)₊^p dθ.
    let scale = n / ((n + T::ONE) * T::PI);
    let safety = T::from_f64(super::SAFETY);
    let weight = |e: [T; 1], v: [T; 1]| {
        let d = (v[0] * scale).abs();
        if d > T::ZERO {
            (safety * e[0] * scale) / d + floor
        } else {
            T::MAX
        }
    };
    let out = quadrature::integrate(f, &[T::ZERO, T::PI], tol, weight)?;
    let d = out.value[0] * scale;
    let rel = weight(out.error, out.value);
    // D > 0 holds exactly (the integrand is (1 + a)^p ≥ 1 at θ = π): a
    // value that is not, or not a number, is the quadrature's failure.
    let not_positive = d.is_nan() || d <= T::ZERO;
    if !out.converged || rel.is_nan() || rel > tol || not_positive {
        return Err(MdrError::NotConverged {
            reached: rel.to_f64(),
        });
    }
    Ok((d, rel * d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::float::Libm;

    /// M5 by a fine midpoint rule in θ and M4 by one in ξ, against M6/M7.
    #[test]
    fn closed_forms_match_direct_integrals() {
        for (n, a) in [
            (1.0, 0.3),
            (1.0, 2.0),
            (2.0, 0.0),
            (2.0, 0.5),
            (2.0, 0.999),
            (2.0, 1.0),
        ] {
            let cf = closed_form::<f64, Libm>(n, a).unwrap();
            // Midpoint in θ over [0, π] of (1 − a cos θ)₊^{1+1/n}: the
            // integrand is C¹ with a bounded second derivative for a < 1 and
            // a ≤ 1 at n ≤ 2 (error ≤ π h² max|f''|/24 ~ 1e-9 at h = π/2e5,
            // except at a = 1 where f ~ θ³ near 0: still C²).
            let m = 200_000;
            let h = core::f64::consts::PI / f64::from(m);
            let mut s = 0.0;
            for i in 0..m {
                let th = (f64::from(i) + 0.5) * h;
                let w: f64 = 1.0 - a * th.cos();
                if w > 0.0 {
                    s += w.powf(1.0 + 1.0 / n);
                }
            }
            let direct = n / (n + 1.0) * s * h / core::f64::consts::PI;
            assert!((cf - direct).abs() < 1e-8, "n={n} a={a}: {cf} vs {direct}");
        }
    }
}
