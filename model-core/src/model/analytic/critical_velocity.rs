//! Critical velocity of controllability (paper §2.1, eq. 8).

use crate::model::float::{Float, Math};
use crate::model::scene::Scene;

/// How many units of rounding (`ε`, the type's machine epsilon) of
/// `a + b` a computed dimensionless critical velocity may be and still count
/// as exactly zero: see [`is_zero_critical_velocity`].
pub const ZERO_TOLERANCE_ULPS: u32 = 32;

/// Whether a computed dimensionless critical velocity `c = |b e^{iφ} ± a|`
/// is zero within the rounding of its inputs: `c ≤ 32 ε (a + b)`.
///
/// `a + b` is the largest `c` over φ (eq. 9), so the rule reads "v_c is zero
/// when it is below 32 ulps of v_c,max". Derivation of the 32 for the case
/// that matters, `a = b`, `φ = π` (the paper's v_c = 0): φ reaches the model
/// rounded — degrees to radians is one rounded product with a rounded π/180,
/// `|δφ| ≤ 2ε|φ| ≤ 4πε ≈ 12.6ε` for `|φ| ≤ 2π` — so `b sin φ` is up to
/// `12.6ε b` instead of 0 (the `cos` side is second order, `δφ²/2`). `a` and
/// `b` themselves come from ratios of up to four physical parameters, each
/// rounded: `|a − b|` up to `4ε(a + b)`; `b cos φ`, the sum and `hypot` add
/// three more roundings, `3ε(a + b)`. Total ≈ `20ε(a + b)`, rounded up to
/// the next power of two. A real non-zero `v_c` that small (relative
/// 7·10⁻¹⁵ in f64) is below what any input can resolve. Example: φ = 180°,
/// ratio 1 gives `c = 1.2·10⁻¹⁶ a` in f64, which this rule counts as 0.
pub fn is_zero_critical_velocity<T: Float>(c: T, a: T, b: T) -> bool {
    c <= T::from_u32(ZERO_TOLERANCE_ULPS) * T::EPSILON * (a + b)
}

/// The two critical velocities of a scene, m/s (both ≥ 0).
///
/// Above `forward` (for v₀ > 0), resp. below `−backward` (for v₀ < 0), the
/// contact slides continuously and μ = ±μ₀ exactly. A velocity below the
/// rounding of its inputs is exactly 0 ([`is_zero_critical_velocity`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CriticalVelocity<T> {
    /// v_c for v₀ > 0, eq. 8 with sgn v₀ = +1:
    /// `ω √(Δu_x² + 2μ₀(k_z/k_x)Δu_xΔu_z cos φ + (μ₀(k_z/k_x)Δu_z)²)`, m/s.
    pub forward: T,
    /// v_c for v₀ < 0, eq. 8 with sgn v₀ = −1 (the sign of the cross term flips), m/s.
    pub backward: T,
}

impl<T: Float> CriticalVelocity<T> {
    /// Eq. 8 for both directions, computed as `ωW₀·|b e^{iφ} ± a|`
    /// (the same number, without cancellation in the sum of squares); each
    /// is exactly 0 where [`is_zero_critical_velocity`] says so.
    pub fn of(scene: &Scene<T>) -> Self {
        // The scene's own, formed with Libm when it was (the same numbers as
        // `of_with::<Libm>`).
        let (c, cb) = scene.dimensionless_critical();
        Self::of_dimensionless(scene, c, cb)
    }

    /// [`CriticalVelocity::of`] with a chosen math backend.
    pub fn of_with<M: Math<T>>(scene: &Scene<T>) -> Self {
        let d = scene.drive();
        Self::of_dimensionless(scene, d.c_forward::<M>(), d.c_backward::<M>())
    }

    /// The scene's critical velocities from its drive's dimensionless ones,
    /// `c = |b e^{iφ} + a|` and `c' = |b e^{iφ} − a|`: each times `ωW₀`, or
    /// exactly 0 where [`is_zero_critical_velocity`] says so.
    pub(crate) fn of_dimensionless(scene: &Scene<T>, c_forward: T, c_backward: T) -> Self {
        let d = scene.drive();
        let scale = scene.velocity_scale();
        let zeroed = |c: T| {
            if is_zero_critical_velocity(c, d.a, d.b) {
                T::ZERO
            } else {
                c
            }
        };
        CriticalVelocity {
            forward: scale * zeroed(c_forward),
            backward: scale * zeroed(c_backward),
        }
    }

    /// The critical velocity for the direction of `v0` (forward for `v0 ≥ 0`).
    pub fn for_velocity(&self, v0: T) -> T {
        if v0 < T::ZERO {
            self.backward
        } else {
            self.forward
        }
    }
}

/// Eq. 9: the largest forward critical velocity over φ (at φ = 0),
/// `ω(Δu_x + μ₀(k_z/k_x)Δu_z)`, m/s.
pub fn vc_max<T: Float>(scene: &Scene<T>) -> T {
    let d = scene.drive();
    scene.velocity_scale() * (d.b + d.a)
}

/// Eq. 10: the smallest forward critical velocity over φ (at φ = π),
/// `ω|Δu_x − μ₀(k_z/k_x)Δu_z|`, m/s.
pub fn vc_min<T: Float>(scene: &Scene<T>) -> T {
    let d = scene.drive();
    scene.velocity_scale() * (d.b - d.a).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::float::Libm;
    use crate::model::scene::Groups;

    fn scene<T: Float>(ratio: T, phi: T) -> Scene<T> {
        let half = T::from_f64(0.5);
        Scene::dimensionless(Groups::from_ratio(half, ratio, phi).unwrap()).unwrap()
    }

    #[test]
    fn zero_at_phi_pi_ratio_one() {
        // a = b = 1/2, φ = 180° (the paper's v_c = 0 case). The rounded π
        // makes sin φ = 1.22e-16, so the raw |b e^{iφ} + a| is 6.1e-17, far
        // below 32 ε (a + b) = 7.1e-15: counted as 0. Backward: c' = 2a = 1
        // (ωW₀ = 1 here), within one rounding of hypot.
        let s = scene(1.0f64, 180f64.to_radians());
        let raw = s.drive().c_forward::<Libm>();
        assert!(raw > 0.0 && raw < 1e-16, "{raw}");
        let vc = CriticalVelocity::of(&s);
        assert_eq!(vc.forward, 0.0);
        assert!((vc.backward - 1.0).abs() <= f64::EPSILON);
        // f32: sin of the rounded π is 8.7e-8, raw c = 4.4e-8 < 32 ε = 3.8e-6.
        let s = scene(1.0f32, 180f32.to_radians());
        assert_eq!(CriticalVelocity::of(&s).forward, 0.0);
    }

    #[test]
    fn a_real_small_critical_velocity_is_kept() {
        // φ = 180.001°: c = |b e^{iφ} + a| = 2a sin(δ/2) = sin(δ/2) with
        // δ = 0.001° — 8.7e-6, a billion times the allowance. The rounding
        // of φ (3.5e-16 rad) is 2e-11 of δ, hence the 1e-9 relative tolerance.
        let s = scene(1.0f64, 180.001f64.to_radians());
        let want = (0.001f64.to_radians() / 2.0).sin();
        let got = CriticalVelocity::of(&s).forward;
        assert!((got - want).abs() <= 1e-9 * want, "{got} vs {want}");
    }
}
