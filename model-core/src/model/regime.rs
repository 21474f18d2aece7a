//! Regime classification (paper §3.2, classes I–III), computed exactly.
//!
//! Definitions (μ as a function of the sliding velocity v, with the scene fixed):
//!
//! * **Actuator** (III): the contact pushes by itself — the force points along
//!   the motion for some velocity (`μ(v)·v < 0`) or is non-zero at rest.
//! * **Active control** (I): not an actuator and the law is symmetric,
//!   `μ(v) = −μ(−v)` for every v.
//! * **Dynamic ratchet** (II): neither — asymmetric, dissipative
//!   (`μ(v)·v ≥ 0`), and the contact can rest with zero force.
//!
//! **The exact boundary of the actuator class** is expressed through the
//! one-sided limits μ(0±) ([`crate::model::exact::limits_at_zero`]): the scene is an
//! actuator iff `μ(0⁺) < 0` or `μ(0⁻) > 0`. When a static equilibrium exists,
//! `μ(0⁺) = hi = 1 − c` and `μ(0⁻) = lo = c' − 1` (the static interval,
//! [`crate::model::analytic::StaticFriction`]), so the condition reads `0 ∉ [lo, hi]`,
//! i.e. `c > 1` or `c' > 1`: the dimensionless critical velocity of either
//! direction exceeds 1, `v_c± > ωW₀ = ωμ₀k_z u_z0/k_x`. When no equilibrium
//! exists (`c + c' > 2`), both limits are equal and are the net force at rest,
//! generally non-zero. That `μ(0±)` decide the sign of μ for all `v` rests on μ(v)
//! being non-decreasing in v, which holds for the play-type dynamics of the
//! model and is checked by a brute-force scan in the tests
//! (`tests/regime.rs`).
//!
//! **Where the paper's rules of thumb fail.** The paper states that ratchets
//! arise for `k_xΔu_x/(μ₀k_zΔu_z) < 1`, drives for `> 1`, and that φ = π/2 is
//! symmetric. Exactly, with `r` the ratio and `a = Δu_z/u_z0`:
//! `c² = a²(1 + 2r cos φ + r²)`, so the actuator condition `max(c, c') > 1` is
//! `a²(1 + 2r|cos φ| + r²) > 1` (with a static equilibrium), i.e. the boundary
//! `r* = −|cos φ| + √(cos²φ − 1 + 1/a²)`. It lies at `r* = 1` — the paper's
//! rule — exactly on the curve `a = 1/√(2 + 2|cos φ|)` (0.5 at φ = 0, π; 1/√2
//! at φ = π/2), and nowhere else (e.g. `a = 1/√3`, φ = 60°: ratchet at r = 0.99,
//! actuator at r = 1.01; checked in `tests/regime.rs`). At `a = 0.9`,
//! φ = 0 it is already `r > 0.111`: an actuator at r = 0.7. At `a = 0.2`, φ = 0
//! it needs `r > 4`: r = 3 is a ratchet. And for φ = π/2, `c = c'`, but once
//! `c > 1` the scene is an actuator (no force-free rest), however symmetric
//! its critical velocities.

use crate::model::analytic::critical_velocity::ZERO_TOLERANCE_ULPS;
use crate::model::analytic::static_friction::StaticFriction;
use crate::model::exact::{limits_at_zero, mu_over_mu0, ExactError};
use crate::model::float::{Float, Libm, Math};
use crate::model::scene::{Drive, Scene};

/// The three classes of the paper (§3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Regime {
    /// I: symmetric, dissipative law.
    ActiveControl,
    /// II: asymmetric but dissipative, force-free rest possible.
    DynamicRatchet,
    /// III: the contact drives itself (net force at rest or against the motion).
    Actuator,
}

impl Regime {
    /// Stable machine name (`active_control`, `dynamic_ratchet`, `actuator`).
    pub const fn name(self) -> &'static str {
        match self {
            Regime::ActiveControl => "active_control",
            Regime::DynamicRatchet => "dynamic_ratchet",
            Regime::Actuator => "actuator",
        }
    }
}

/// Options for [`classify`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClassifyOptions<T> {
    /// Tolerance on `μ/μ₀` for "zero" and "equal" (default 1e-9 in f64, 1e-4 in f32).
    pub tol: T,
    /// Velocities sampled in `(0, max(v_c±))` for the symmetry check (default 64).
    pub samples: u32,
}

impl<T: Float> Default for ClassifyOptions<T> {
    fn default() -> Self {
        let tol = if T::EPSILON < T::from_f64(1e-10) {
            1e-9
        } else {
            1e-4
        };
        ClassifyOptions {
            tol: T::from_f64(tol),
            samples: 64,
        }
    }
}

/// A classification with the numbers it rests on (all `μ` as `μ/μ₀`,
/// velocities as multiples of ωW₀).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Classification<T> {
    /// The class.
    pub regime: Regime,
    /// `μ(0⁺)/μ₀`.
    pub mu_0plus: T,
    /// `μ(0⁻)/μ₀`.
    pub mu_0minus: T,
    /// The static analysis.
    pub statics: StaticFriction<T>,
    /// `c = v_c+/(ωW₀)`.
    pub c_forward: T,
    /// `c' = v_c−/(ωW₀)`.
    pub c_backward: T,
    /// `max |μ(v) + μ(−v)|/μ₀` over the sampled velocities and v → 0
    /// (0 for a symmetric law).
    pub asymmetry: T,
}

/// Classifies a scene (see module docs for the definitions).
///
/// # Errors
/// [`ExactError::Inconsistent`] from the solver (never observed).
pub fn classify<T: Float>(
    scene: &Scene<T>,
    opts: &ClassifyOptions<T>,
) -> Result<Classification<T>, ExactError> {
    classify_drive::<T, Libm>(&scene.drive(), StaticFriction::of(scene), opts)
}

/// [`classify`] on a dimensionless drive with a chosen math backend.
///
/// # Errors
/// As [`classify`].
pub fn classify_drive<T: Float, M: Math<T>>(
    d: &Drive<T>,
    statics: StaticFriction<T>,
    opts: &ClassifyOptions<T>,
) -> Result<Classification<T>, ExactError> {
    let (mu_0plus, mu_0minus) = limits_at_zero::<T, M>(d)?;
    let c = d.c_forward::<M>();
    let cb = d.c_backward::<M>();
    let tol = opts.tol;
    let actuator = mu_0plus < -tol || mu_0minus > tol;
    let mut asymmetry = (mu_0plus + mu_0minus).abs();
    let vmax = c.max(cb);
    if (c - cb).abs() > tol * (T::ONE + vmax) {
        // Different critical velocities: μ = ±1 beyond one and not the other.
        asymmetry = asymmetry.max(T::ONE - mu_at::<T, M>(d, c.min(cb))?.abs());
    } else if vmax > T::ZERO {
        let n = opts.samples.max(1);
        for i in 1..=n {
            let v = vmax * T::from_u32(i) / T::from_u32(n + 1);
            let f = mu_over_mu0::<T, M>(d, v)?;
            let b = mu_over_mu0::<T, M>(d, -v)?;
            asymmetry = asymmetry.max((f + b).abs());
        }
    }
    let regime = if actuator {
        Regime::Actuator
    } else if asymmetry <= tol {
        Regime::ActiveControl
    } else {
        Regime::DynamicRatchet
    };
    Ok(Classification {
        regime,
        mu_0plus,
        mu_0minus,
        statics,
        c_forward: c,
        c_backward: cb,
        asymmetry,
    })
}

fn mu_at<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Result<T, ExactError> {
    if v == T::ZERO {
        return Ok(T::ZERO);
    }
    mu_over_mu0::<T, M>(d, v)
}

/// The paper's rule of thumb (§3.2 and §4), for comparison with [`classify`]:
/// a single mode (`Δu_z = 0` or `Δu_x = 0`) or φ = π/2 (mod π) is active
/// control; otherwise an amplitude ratio `k_xΔu_x/(μ₀k_zΔu_z) = b/a`
/// (eq. 26) above 1 is an actuator and at most 1 a dynamic ratchet.
///
/// `cos φ` counts as zero within the same rounding allowance as a zero
/// critical velocity, `|b cos φ| ≤ 32 ε b`
/// ([`crate::model::analytic::critical_velocity::is_zero_critical_velocity`]):
/// φ = 90° or 270° given in degrees lands within `2ε|φ|` of π/2 or 3π/2.
///
/// The rule is not exact: see the module docs for where it fails.
pub fn rule_of_thumb<T: Float>(scene: &Scene<T>) -> Regime {
    let d = scene.drive();
    let cos_zero = d.bc.abs() <= T::from_u32(ZERO_TOLERANCE_ULPS) * T::EPSILON * d.b;
    if d.a == T::ZERO || d.b == T::ZERO || cos_zero {
        Regime::ActiveControl
    } else if d.b > d.a {
        Regime::Actuator
    } else {
        Regime::DynamicRatchet
    }
}

#[cfg(test)]
mod rule_of_thumb_tests {
    use super::*;
    use crate::model::scene::Groups;

    fn rule(duz_rel: f64, ratio: f64, phi_deg: f64) -> Regime {
        let g = Groups::from_ratio(duz_rel, ratio, phi_deg.to_radians()).unwrap();
        rule_of_thumb(&Scene::dimensionless(g).unwrap())
    }

    #[test]
    fn states_the_paper_s_rule() {
        // §3.2/§4: ratio > 1 actuator, < 1 ratchet; φ = π/2 and single
        // modes symmetric (active control).
        assert_eq!(rule(0.5, 2.0, 0.0), Regime::Actuator);
        assert_eq!(rule(0.5, 0.5, 30.0), Regime::DynamicRatchet);
        assert_eq!(rule(0.5, 0.0, 30.0), Regime::ActiveControl);
        let tangential_only = Groups {
            duz_rel: 0.0,
            dux_rel: 0.3,
            phi: 0.0,
        };
        assert_eq!(
            rule_of_thumb(&Scene::dimensionless(tangential_only).unwrap()),
            Regime::ActiveControl
        );
        // 90° and 270° in degrees: cos φ = 6e-17 and 1.8e-16 after rounding,
        // inside the 32 ε allowance (7.1e-15) — counted as φ = π/2.
        assert_eq!(rule(0.5, 2.0, 90.0), Regime::ActiveControl);
        assert_eq!(rule(0.5, 2.0, 270.0), Regime::ActiveControl);
        // 0.001° away, cos φ = 1.7e-5: the ratio decides again.
        assert_eq!(rule(0.5, 2.0, 90.001), Regime::Actuator);
        // Ratio exactly 1 is not above 1: a ratchet by the rule.
        assert_eq!(rule(0.5, 1.0, 0.0), Regime::DynamicRatchet);
    }
}
