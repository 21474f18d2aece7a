//! Static friction (paper §2.2): the paper's eqs. 17–19 and the exact static
//! stick interval.
//!
//! At rest (`u_x,c` fixed) the spring stretch is `s(θ) = u_x0 + Δu_x cos(θ + φ)`
//! and the contact sticks for all time iff `|s(θ)| ≤ w(θ)` for every θ
//! (eq. 12 with the modulus kept). In units of W₀ (see [`crate::model::scene`]) that is
//!
//! ```text
//!   u_x0 ≤ min_θ [ 1 − a cos θ − b cos(θ+φ) ] = 1 − c     (upper side)
//!   u_x0 ≥ max_θ [ −1 + a cos θ − b cos(θ+φ) ] = c' − 1   (lower side)
//! ```
//!
//! with `c = |b e^{iφ} + a|` and `c' = |b e^{iφ} − a|` (the dimensionless
//! critical velocities). So the static equilibria form the interval
//! `[lo, hi] = [c' − 1, 1 − c]`, which is empty when `c + c' > 2`.
//!
//! The paper drops the modulus on the left of eq. 12 and keeps only the
//! upper side: its eq. 18 is exactly `hi` (and eq. 19 is `−lo`), but it
//! misses that the interval can be empty, in which case no force holds the
//! contact still and eq. 18/19 describe nothing physical. When the interval is
//! not empty, `hi` and `−lo` are the largest forward and backward forces (over
//! `k_z u_z0 μ₀`) that do not make it slip; `hi < 0` or `lo > 0` means that
//! holding the contact still takes a force *against* the direction it would
//! otherwise move (an actuator, see [`crate::model::regime`]).

use crate::model::float::{Float, Libm, Math};
use crate::model::scene::Scene;

/// Static analysis of a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StaticFriction<T> {
    /// Lower end of the static interval, `lo = c' − 1`, in units of W₀
    /// (also the lowest static force over `μ₀ k_z u_z0`, i.e. a `μ/μ₀`).
    pub lo: T,
    /// Upper end, `hi = 1 − c`, in units of W₀ (a `μ/μ₀`).
    pub hi: T,
    /// The paper's eq. 18, `μ_s/μ₀ = 1 − √(a² + 2ab cos φ + b²)` (forward).
    pub paper_eq18_forward: T,
    /// The paper's eq. 19 in the form of eq. 18 (backward, sign of the cross term flipped).
    pub paper_eq19_backward: T,
}

impl<T: Float> StaticFriction<T> {
    /// The static analysis of a scene (closed form, see module docs).
    pub fn of(scene: &Scene<T>) -> Self {
        Self::of_with::<Libm>(scene)
    }

    /// [`StaticFriction::of`] with a chosen math backend.
    pub fn of_with<M: Math<T>>(scene: &Scene<T>) -> Self {
        let d = scene.drive();
        let c = d.c_forward::<M>();
        let cb = d.c_backward::<M>();
        // Eq. 18 written literally (sum of squares under the root) — kept
        // separate from `hi` so the two can be compared.
        let (a, b) = (d.a, d.b);
        let cos_phi_b = d.bc; // b cos φ
        let eq18 = T::ONE - M::sqrt((a * a + T::TWO * a * cos_phi_b + b * b).max(T::ZERO));
        let eq19 = T::ONE - M::sqrt((a * a - T::TWO * a * cos_phi_b + b * b).max(T::ZERO));
        StaticFriction {
            lo: cb - T::ONE,
            hi: T::ONE - c,
            paper_eq18_forward: eq18,
            paper_eq19_backward: eq19,
        }
    }

    /// Whether a static equilibrium exists (`lo ≤ hi`).
    pub fn exists(&self) -> bool {
        self.lo <= self.hi
    }

    /// The exact forward static coefficient `μ_s+/μ₀ = hi`, or `None` when no
    /// static equilibrium exists.
    pub fn mu_s_forward_over_mu0(&self) -> Option<T> {
        self.exists().then_some(self.hi)
    }

    /// The exact backward static coefficient `μ_s−/μ₀ = −lo` (a magnitude, as
    /// eq. 19), or `None` when no static equilibrium exists.
    pub fn mu_s_backward_over_mu0(&self) -> Option<T> {
        self.exists().then_some(-self.lo)
    }

    /// The static interval in metres of equilibrium displacement `u_x0`
    /// (`[lo, hi]·W₀`), or `None` when empty.
    pub fn interval_m(&self, scene: &Scene<T>) -> Option<(T, T)> {
        self.exists()
            .then(|| (self.lo * scene.w0(), self.hi * scene.w0()))
    }
}
