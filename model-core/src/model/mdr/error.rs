//! Why the MDR gave no number ([`MdrError`]), and its answer with a bound
//! ([`MdrResult`]).

/// Why the MDR gave no number.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MdrError {
    /// The exponent of [`Profile::Power`](super::Profile::Power) is NaN, infinite or ≤ 0.
    BadExponent,
    /// A drive no validated scene produces (non-finite, `a < 0`, `b < 0`).
    BadDrive,
    /// The velocity is NaN or infinite.
    BadVelocity,
    /// The tolerance is NaN, infinite or ≤ 0.
    BadTolerance,
    /// The float type cannot resolve this drive (precision part of the
    /// bound above 1 % of μ₀).
    IllConditioned,
    /// The tolerance is below what the per-spring solvers guarantee.
    ToleranceTooTight {
        /// The smallest bound available, units of μ₀.
        best: f64,
    },
    /// The adaptive quadrature ran out of intervals before meeting the
    /// tolerance.
    NotConverged {
        /// The bound reached, units of μ₀.
        reached: f64,
    },
    /// `V = 0` with springs in permanent contact (`a < 1`): no unique μ;
    /// [`limits_at_zero`](super::limits_at_zero) gives μ(0±).
    AtRest,
    /// A spring's event walk failed its internal check.
    Inconsistent,
}

impl core::fmt::Display for MdrError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            MdrError::BadExponent => f.write_str("exponent: must be a finite number > 0"),
            MdrError::BadDrive => f.write_str(
                "drive: not one a valid scene produces (finite, duz-rel >= 0, dux-rel >= 0)",
            ),
            MdrError::BadVelocity => f.write_str("v0: must be a finite number"),
            MdrError::BadTolerance => f.write_str("tol: must be a finite number > 0"),
            MdrError::IllConditioned => f.write_str(
                "duz-rel/dux-rel: too large for this number type to resolve mu (error bound > 1 % of mu0)",
            ),
            MdrError::ToleranceTooTight { best } => write!(
                f,
                "tol: tighter than the per-spring solvers guarantee for this scene (best {best:e})"
            ),
            MdrError::NotConverged { reached } => write!(
                f,
                "tol: the profile quadrature stopped at a bound of {reached:e} (interval limit)"
            ),
            MdrError::AtRest => f.write_str(
                "v0: 0 has no unique mu while the central springs stay in contact (duz < uz0); use the limits mu(0+), mu(0-)",
            ),
            MdrError::Inconsistent => {
                f.write_str("mdr: a spring's solver failed its internal check (a number would be wrong)")
            }
        }
    }
}

impl core::error::Error for MdrError {}

/// μ/μ₀ of a profile with its bound.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MdrResult<T> {
    /// `μ/μ₀` (eq. M8).
    pub mu_over_mu0: T,
    /// Error bound, units of μ₀ (≤ the tolerance asked for; module docs
    /// say what it covers).
    pub bound: T,
    /// Springs solved: the quadrature's integrand evaluations plus the
    /// kink search's (module docs).
    pub evaluations: u32,
}
