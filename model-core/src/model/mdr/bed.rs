//! The integral over the bed of springs (eq. M8) for a curved profile: the
//! ξ-range split at the lift-off onset, at ξ* and at the kinks, each piece
//! integrated by [`super::quadrature`] with its bound.

use super::bound::spring_constant;
use super::kinks::{kink_candidates, kinks, Search, MAX_CANDIDATES, MAX_PIECES};
use super::spring::{forward_critical, spring, Limit};
use super::{normal, quadrature, solver_bound, MdrError, MdrResult, Profile, SAFETY};
use crate::model::float::{Float, Math};
use crate::model::liftoff::Shape;
use crate::model::scene::Drive;

/// A curved profile in the forward convention (`v ≥ 0`).
pub(super) fn curved<T: Float, M: Math<T>>(
    d: &Drive<T>,
    n: T,
    v: T,
    limit: Limit,
    tol: T,
) -> Result<MdrResult<T>, MdrError> {
    let a = d.a;
    // The drive's geometry at v, shared by every spring.
    let shape = Shape::of::<M>(d, v);
    if v >= forward_critical::<T, M>(&shape, d, T::ONE) {
        return Ok(MdrResult {
            mu_over_mu0: T::ONE,
            bound: T::ZERO,
            evaluations: 0,
        });
    }
    let solver = solver_bound::<T, M>(d, n);
    if solver >= tol {
        return Err(MdrError::ToleranceTooTight {
            best: solver.to_f64() * 1.01,
        });
    }
    let xi_a = if a < T::ONE {
        Profile::root(n, T::ONE - a)
    } else {
        T::ZERO
    };
    let xi_max = Profile::root(n, T::ONE + a);
    let offset = |xi: T| T::ONE - Profile::power(n, xi);
    // ξ*: V_c⁺(d(ξ)) > v on [0, ξ*), ≤ v beyond (monotone, module docs).
    let (mut lo, mut hi) = (xi_a, xi_max);
    if forward_critical::<T, M>(&shape, d, offset(hi)) > v {
        lo = hi;
    }
    while hi - lo > T::from_f64(4.0) * T::EPSILON * xi_max {
        let mid = (lo + hi) * T::HALF;
        if !(mid > lo && mid < hi) {
            break;
        }
        if forward_critical::<T, M>(&shape, d, offset(mid)) > v {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let xi_star = hi;
    let segments = [(T::ZERO, xi_a), (xi_a, xi_star), (xi_star, xi_max)];
    let closed = normal::closed_form::<T, M>(n, a);
    let sliding_segment = 2usize;
    // Pieces in ξ: each used segment, split where the springs' arc structure
    // changes (module docs, "kinks"); piece k is integrated over
    // u ∈ [kπ, (k+1)π] with its own map ξ = l + (r − l)(1 − cos t)/2, so that
    // a square-root onset at a kink is as smooth in t as one at a segment end.
    let mut pieces: heapless::Vec<(T, T, bool), MAX_PIECES> = heapless::Vec::new();
    let mut searched = 0u32;
    // Kink candidates in closed form (ξ).
    let mut candidates: heapless::Vec<T, MAX_CANDIDATES> = heapless::Vec::new();
    kink_candidates::<T, M>(d, v, |dd| {
        if dd < T::ONE && dd > -a {
            let _ = candidates.push(Profile::root(n, T::ONE - dd));
        }
    });
    for (j, &(l, r)) in segments.iter().enumerate() {
        if r <= l || (j == sliding_segment && closed.is_some()) {
            continue;
        }
        let sliding = j == sliding_segment;
        let mut left = l;
        if !sliding {
            // The extra samples next to the lift-off onset ξ_a (both sides).
            let at_onset = (a < T::ONE && j == 0, a < T::ONE && j == 1);
            // Intermittent springs: the landing-slip thresholds in closed form.
            let mut hint: heapless::Vec<T, MAX_CANDIDATES> = heapless::Vec::new();
            for &xi in candidates.iter().filter(|&&xi| xi > l && xi < r) {
                let _ = hint.push(xi);
            }
            let search = Search {
                l,
                r,
                ends: at_onset,
                hint: &hint,
                shape: &shape,
            };
            searched += kinks::<T, M>(d, v, &search, &offset, |xi| {
                if xi > left && xi < r {
                    let _ = pieces.push((left, xi, false));
                    left = xi;
                }
            });
        }
        let _ = pieces.push((left, r, sliding));
    }
    let integrand = |u: T| -> Result<[T; 3], MdrError> {
        let k = ((u / T::PI).to_f64() as usize).min(pieces.len() - 1);
        let (l, r, sliding) = pieces[k];
        let t = u - T::PI * T::from_u32(k as u32);
        let (sin_t, cos_t) = M::sin_cos(t);
        let half = (r - l) * T::HALF;
        let xi = l + half * (T::ONE - cos_t);
        let jac = half * sin_t;
        let dd = offset(xi);
        if sliding {
            return Ok([T::ZERO, normal::mean_band::<T, M>(dd, a) * jac, T::ZERO]);
        }
        let s = spring::<T, M>(&shape, d, dd, v, limit)?;
        Ok([(s.band - s.stretch) * jac, s.band * jac, s.unresolved * jac])
    };
    let mut ends: heapless::Vec<T, { MAX_PIECES + 1 }> = heapless::Vec::new();
    for k in 0..=pieces.len() {
        let _ = ends.push(T::PI * T::from_u32(k as u32));
    }
    let safety = T::from_f64(SAFETY);
    let eps_s = (spring_constant::<T>() + T::from_f64(M::MAX_REL_ERROR)) * (T::ONE + a + d.b);
    let floor = T::from_f64(64.0) * T::EPSILON;
    let bound_of = |e: [T; 3], val: [T; 3]| {
        let den = closed.unwrap_or(val[1]);
        if den.is_nan() || den <= T::ZERO {
            return T::MAX;
        }
        let ratio = (val[0] / den).abs();
        let e_den = if closed.is_some() { T::ZERO } else { e[1] };
        (safety * (e[0] + ratio * e_den) + eps_s * xi_star + val[2]) / den + floor
    };
    let out = quadrature::integrate(integrand, &ends, tol, bound_of)?;
    let den = closed.unwrap_or(out.value[1]);
    let bound = bound_of(out.error, out.value);
    if !out.converged || bound.is_nan() || bound > tol {
        return Err(MdrError::NotConverged {
            reached: bound.to_f64(),
        });
    }
    let mu = T::ONE - out.value[0] / den;
    if !mu.is_finite() || mu.abs() > T::ONE + tol {
        return Err(MdrError::Inconsistent);
    }
    Ok(MdrResult {
        mu_over_mu0: mu.max(-T::ONE).min(T::ONE),
        bound,
        evaluations: out.evaluations + searched,
    })
}
