//! Axisymmetric indenter profiles `f(r) = c·rⁿ` and their MDR images.

use super::MdrError;
use crate::model::float::Float;

/// The shape of a rigid axisymmetric indenter, `f(r) = c·rⁿ`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Profile<T> {
    /// A flat-ended cylinder: the paper's single spring (no MDR needed).
    Flat,
    /// A sphere (paraboloid), `n = 2`: `f = r²/(2R)`.
    Sphere,
    /// A cone, `n = 1`: `f = r tan β`.
    Cone,
    /// A power law `f = c·rⁿ` with exponent `n > 0`, finite.
    Power(T),
}

impl<T: Float> Profile<T> {
    /// The exponent `n`: `None` for [`Profile::Flat`] (the limit `n → ∞`),
    /// 2 for a sphere, 1 for a cone.
    pub fn exponent(&self) -> Option<T> {
        match *self {
            Profile::Flat => None,
            Profile::Sphere => Some(T::TWO),
            Profile::Cone => Some(T::ONE),
            Profile::Power(n) => Some(n),
        }
    }

    /// The name used in reports and on the command line:
    /// `flat`, `sphere`, `cone`, `power`.
    pub const fn name(&self) -> &'static str {
        match self {
            Profile::Flat => "flat",
            Profile::Sphere => "sphere",
            Profile::Cone => "cone",
            Profile::Power(_) => "power",
        }
    }

    /// Checks the exponent of [`Profile::Power`]: finite and `> 0`.
    ///
    /// # Errors
    /// [`MdrError::BadExponent`].
    pub fn validate(&self) -> Result<(), MdrError> {
        match self.exponent() {
            Some(n) if !(n.is_finite() && n > T::ZERO) => Err(MdrError::BadExponent),
            _ => Ok(()),
        }
    }

    /// `ξⁿ` (exact products for the sphere and the cone).
    pub(crate) fn power(n: T, xi: T) -> T {
        if n == T::TWO {
            xi * xi
        } else if n == T::ONE {
            xi
        } else {
            powf(xi, n)
        }
    }

    /// `x^{1/n}` (the inverse of [`Profile::power`] on `x ≥ 0`).
    pub(crate) fn root(n: T, x: T) -> T {
        if n == T::TWO {
            x.libm_sqrt()
        } else if n == T::ONE {
            x
        } else {
            powf(x, T::ONE / n)
        }
    }
}

/// `xʸ` for `x ≥ 0` through `libm::pow` in f64 (the [`crate::model::float::Math`]
/// backends have no power; one rounding to `T` after it).
fn powf<T: Float>(x: T, y: T) -> T {
    T::from_f64(libm::pow(x.to_f64(), y.to_f64()))
}

/// The MDR scale factor `κₙ = √π Γ(n/2 + 1)/Γ(n/2 + 1/2)` of the profile
/// `f = c rⁿ`: the 1D foundation's profile is `g(x) = κₙ c |x|ⁿ`
/// (Popov & Heß, *Method of Dimensionality Reduction*, 2015, eq. 3.11).
/// `κ₁ = π/2`, `κ₂ = 2`. In f64 through `libm::tgamma`; a host-side helper
/// (the solvers never need it: it is absorbed in the normalisation of ξ).
pub fn kappa(n: f64) -> f64 {
    libm::sqrt(core::f64::consts::PI) * libm::tgamma(n / 2.0 + 1.0) / libm::tgamma(n / 2.0 + 0.5)
}

/// The mean contact radius `a₀ = (d₀/(κₙ c))^{1/n}` (m) of the profile
/// `f = c rⁿ` (`c` in m^{1−n}) at mean indentation `d₀` (m): the springs at
/// `|x| < a₀` touch on average, `ξ = x/a₀`. Sphere of radius R: `c = 1/(2R)`,
/// `a₀ = √(R d₀)` (Hertz).
pub fn mean_contact_radius(n: f64, c: f64, d0: f64) -> f64 {
    libm::pow(d0 / (kappa(n) * c), 1.0 / n)
}
