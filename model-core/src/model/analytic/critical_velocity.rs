//! Critical velocity of controllability (paper §2.1, eq. 8).

use crate::model::float::{Float, Libm, Math};
use crate::model::scene::Scene;

/// The two critical velocities of a scene, m/s (both ≥ 0).
///
/// Above `forward` (for v₀ > 0), resp. below `−backward` (for v₀ < 0), the
/// contact slides continuously and μ = ±μ₀ exactly.
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
    /// (the same number, without cancellation in the sum of squares).
    pub fn of(scene: &Scene<T>) -> Self {
        Self::of_with::<Libm>(scene)
    }

    /// [`CriticalVelocity::of`] with a chosen math backend.
    pub fn of_with<M: Math<T>>(scene: &Scene<T>) -> Self {
        let d = scene.drive();
        let scale = scene.velocity_scale();
        CriticalVelocity {
            forward: scale * d.c_forward::<M>(),
            backward: scale * d.c_backward::<M>(),
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
