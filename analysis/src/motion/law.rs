//! One μ(v) for every contact model: `fricctl motion` and
//! `fricctl load-line` take the law only through [`Law`], which asks
//! model-core's [`select::mu_within`] — the function that picks the right
//! solver for the scene's contact — and nothing else.
//!
//! | contact | μ(v ≠ 0) | at rest | critical velocities | mean normal force `F̄z` |
//! |---|---|---|---|---|
//! | flat punch, permanent contact (`a < 1`) | exact solver (or eq. 21/24 when their bound fits) | the static band `[μ(0⁻), μ(0⁺)]` (`Value::AtRest`) | eq. 8 | `k_z u_z0` |
//! | flat punch with lift-off (`a ≥ 1`) | lift-off window solver | unique: `μ(0⁺) = μ(0⁻) = μ(0)` | eq. L5 | `k_z u_z0⟨w⁺⟩` (eq. L4) |
//! | curved profile (sphere, cone, power; MDR) | MDR quadrature | `[μ(0⁻), μ(0⁺)]` (`Value::Limits`; unique for `a ≥ 1`) | the flat punch's (`mdr::critical_velocities`) | `k_z u_z0·D` (eq. M5; `k_z = 2E*a₀`, `mdr::mean_normal_force`) |
//!
//! All of them are asked through one function, [`select::mu_within_profile`]
//! (the flat profile is exactly [`select::mu_within`]). The rest of the slow
//! dynamics needs nothing else from a contact model except where stated:
//! [`Law::exponent`] (the resolved model's bed of springs),
//! [`Law::powers`] (input power, friction loss: every contact),
//! [`Law::mean_normal`] (the mean normal force in units of `k_z u_z0`: every
//! contact) and [`Law::spring_bounds`] (for the error estimate).
//!
//! Every value carries the bound `select` guarantees for it (units μ₀). The
//! tolerance asked of `select` is the caller's; when no method of the contact
//! meets it, the smallest available bound is taken instead (and reported
//! through the bound).

use model_core::mdr::{self, Profile};
use model_core::model::liftoff;
use model_core::model::load_line::{self, Powers};
use model_core::select::{self, SelectError, Value};
use model_core::{Libm, Scene};

/// Bounds of the contact's tangential springs ([`Law::spring_bounds`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringBounds {
    /// Width `∫dξ` of the springs that ever touch (1 for the flat punch).
    pub reach: f64,
    /// Bound of the total spring force `|Σ s|` (units `k_x W₀`).
    pub s_max: f64,
    /// The widest band of one spring, `1 + a` (units `W₀`).
    pub band: f64,
}

/// Why the law could not be evaluated.
#[derive(Debug, Clone, PartialEq)]
pub struct LawError {
    /// The contact model's name.
    pub contact: &'static str,
    /// What failed.
    pub what: String,
}

impl std::fmt::Display for LawError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "mu(v) of the {} contact: {}", self.contact, self.what)
    }
}

impl std::error::Error for LawError {}

/// A value of the law with its guaranteed bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawValue {
    /// `μ(0⁺)/μ₀` (equal to `lower` for a moving contact or a unique μ at rest).
    pub upper: f64,
    /// `μ(0⁻)/μ₀`.
    pub lower: f64,
    /// Guaranteed bound of both, units μ₀.
    pub bound: f64,
}

/// The friction law of a scene's contact (module docs).
#[derive(Debug, Clone, Copy)]
pub struct Law {
    scene: Scene<f64>,
    profile: Profile<f64>,
}

impl Law {
    /// The law of the flat punch on `scene` (its contact mode decides
    /// permanent contact or lift-off).
    pub fn of(scene: &Scene<f64>) -> Self {
        Law::with_profile(scene, Profile::Flat)
    }

    /// The law of `profile` on `scene`.
    pub fn with_profile(scene: &Scene<f64>, profile: Profile<f64>) -> Self {
        Law {
            scene: *scene,
            profile,
        }
    }

    /// Whether the contact is the flat punch (the single spring).
    pub fn is_flat(&self) -> bool {
        self.profile == Profile::Flat
    }

    /// The contact model's name, as printed: `flat`, `lift-off`, or the
    /// profile's (`sphere`, `cone`, `power`).
    pub fn name(&self) -> &'static str {
        if !self.is_flat() {
            self.profile.name()
        } else if self.scene.lifts_off() {
            "lift-off"
        } else {
            "flat"
        }
    }

    fn err(&self, what: impl Into<String>) -> LawError {
        LawError {
            contact: self.name(),
            what: what.into(),
        }
    }

    /// The scene.
    pub fn scene(&self) -> &Scene<f64> {
        &self.scene
    }

    /// `(V_c⁺, V_c⁻)`, dimensionless (units ωW₀): `μ = ±μ₀` beyond.
    ///
    /// # Errors
    /// [`LawError`] when the contact model refuses the drive.
    pub fn critical(&self) -> Result<(f64, f64), LawError> {
        let d = self.scene.drive();
        if !self.is_flat() {
            mdr::critical_velocities::<f64, Libm>(&d, &self.profile)
                .map_err(|e| self.err(e.to_string()))
        } else if self.scene.lifts_off() {
            liftoff::critical_velocities::<f64, Libm>(&d).map_err(|e| self.err(e.to_string()))
        } else {
            Ok((d.c_forward::<Libm>(), d.c_backward::<Libm>()))
        }
    }

    /// The mean normal force `F̄z` in units of `k_z u_z0` (1 for permanent
    /// contact, `⟨w⁺⟩` of eq. L4 with lift-off, `D` of eq. M5 for a curved
    /// profile, whose `k_z` is its incremental stiffness `2E*a₀`:
    /// `mdr::mean_normal_force`): friction and applied forces are in units
    /// of `μ₀F̄z`, the contact's spring force in `μ₀k_z u_z0`. Relative error
    /// ≤ 1e-10 (closed forms: rounding).
    ///
    /// # Errors
    /// [`LawError`] when the profile's quadrature does not converge.
    pub fn mean_normal(&self) -> Result<f64, LawError> {
        mdr::mean_normal_force::<f64, Libm>(&self.profile, self.scene.drive().a, 1e-10)
            .map(|r| r.0)
            .map_err(|e| self.err(e.to_string()))
    }

    /// Bounds of the contact's tangential spring force for the error
    /// estimate (`motion::estimate`), units of `k_x W₀ = μ₀k_z u_z0`:
    /// `reach`, the width `∫dξ` of the springs that ever touch (the Lipschitz
    /// constant of the total force in the drive, per unit of the 2-Lipschitz
    /// stretch), `s_max ≥ |Σ s|`, and `band = 1 + a`, the widest band of one
    /// spring (units W₀). Flat punch: `(1, 1 + a, 1 + a)` (`|s| ≤ w ≤ 1 + a`);
    /// profile `n`: springs reach `ξ_max = (1 + a)^{1/n}` and `|Σs| ≤
    /// ∫₀^{ξ_max}(1 + a − ξⁿ)dξ = n/(n + 1)·(1 + a)^{1 + 1/n}` (→ the flat
    /// punch's as `n → ∞`).
    pub fn spring_bounds(&self) -> SpringBounds {
        let a = self.scene.drive().a;
        let band = 1.0 + a;
        match self.profile.exponent() {
            None => SpringBounds {
                reach: 1.0,
                s_max: band,
                band,
            },
            Some(n) => {
                let reach = band.powf(1.0 / n);
                SpringBounds {
                    reach,
                    s_max: n / (n + 1.0) * band * reach,
                    band,
                }
            }
        }
    }

    /// The profile's exponent `n` (`None` for the flat punch): the resolved
    /// model's bed of springs (`resolved::Bed`).
    pub fn exponent(&self) -> Option<f64> {
        self.profile.exponent()
    }

    /// The powers of the steady state at dimensionless velocity `v` (units
    /// `μ₀F̄z ωW₀`, `F̄z` the mean normal force of [`Law::mean_normal`]):
    /// `v ≠ 0` in permanent contact (or a curved profile with `a < 1`), any
    /// `v` with lift-off. A curved profile's quadrature is asked for a bound
    /// of 1e-6 (units μ₀F̄z ωW₀), or the one it reached when that is tighter
    /// than it can do.
    ///
    /// # Errors
    /// [`LawError`] when the solver fails.
    pub fn powers(&self, v: f64) -> Result<Powers<f64>, LawError> {
        let d = self.scene.drive();
        if !self.is_flat() {
            let mut tol = 1e-6;
            for _ in 0..2 {
                match mdr::powers::profile_powers::<f64, Libm>(&d, &self.profile, v, tol) {
                    Ok(r) => return Ok(r.powers),
                    Err(mdr::MdrError::NotConverged { reached }) if reached.is_finite() => {
                        tol = reached * 1.01;
                    }
                    Err(e) => return Err(self.err(e.to_string())),
                }
            }
            Err(self.err("the profile's power quadrature does not meet its own bound"))
        } else if self.scene.lifts_off() {
            load_line::liftoff_powers::<f64, Libm>(&d, v).map_err(|e| self.err(e.to_string()))
        } else {
            load_line::powers::<f64, Libm>(&d, v).map_err(|e| self.err(e.to_string()))
        }
    }

    /// μ/μ₀ at dimensionless velocity `v` (units ωW₀; 0 gives both one-sided
    /// limits, equal where μ at rest is unique), bound ≤ `tol` where the
    /// contact's solvers allow it.
    ///
    /// # Errors
    /// [`LawError`] when the solver fails.
    pub fn at(&self, v: f64, tol: f64) -> Result<LawValue, LawError> {
        let v0 = v * self.scene.velocity_scale();
        let mut tol = tol;
        for _ in 0..2 {
            match select::mu_within_profile::<f64, Libm>(&self.scene, &self.profile, v0, tol) {
                Ok(a) => {
                    return Ok(match a.value {
                        Value::Mu(m) => LawValue {
                            upper: m,
                            lower: m,
                            bound: a.bound,
                        },
                        Value::AtRest {
                            mu_0plus,
                            mu_0minus,
                            ..
                        }
                        | Value::Limits {
                            mu_0plus,
                            mu_0minus,
                        } => LawValue {
                            upper: mu_0plus,
                            lower: mu_0minus,
                            bound: a.bound,
                        },
                    })
                }
                Err(SelectError::ToleranceTooTight { best }) => tol = best,
                Err(SelectError::BadTolerance) => {
                    return Err(self.err(format!("bad tolerance {tol:e}")))
                }
                Err(SelectError::Exact(e)) => return Err(self.err(e.to_string())),
                Err(SelectError::Mdr(e)) => return Err(self.err(e.to_string())),
            }
        }
        Err(self.err("no solver meets its own bound"))
    }

    /// μ/μ₀ at `v ≠ 0` (the value of [`Law::at`] with its bound).
    ///
    /// # Errors
    /// As [`Law::at`].
    pub fn mu(&self, v: f64, tol: f64) -> Result<(f64, f64), LawError> {
        let x = self.at(v, tol)?;
        Ok((x.upper, x.bound))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::scene::ContactMode;
    use model_core::{exact, Groups};

    /// A wiring check, not an accuracy test: [`Law`] hands each contact to
    /// its solver (the flat law is the exact solver's, to its bound, the
    /// static band its one-sided limits; the lift-off law is the window
    /// solver's, unique at 0; a sphere's is the MDR's). The solvers' accuracy
    /// is tested against independent computations in `tests/`.
    #[test]
    fn wiring_law_dispatches_to_each_contacts_solver() {
        let g = Groups::from_ratio(0.5, 2.0, 0.7).unwrap();
        let flat = Law::of(&Scene::dimensionless(g).unwrap());
        let d = flat.scene().drive();
        let (m, b) = flat.mu(0.1, 1e-8).unwrap();
        let e = exact::mu_over_mu0::<f64, Libm>(&d, 0.1).unwrap();
        assert!((m - e).abs() <= b + 1e-15, "{m} vs {e}");
        let z = flat.at(0.0, 1e-8).unwrap();
        let (p, q) = exact::limits_at_zero::<f64, Libm>(&d).unwrap();
        assert_eq!((z.upper, z.lower), (p, q));
        assert_eq!(flat.mean_normal(), Ok(1.0));
        // Lift-off (a = 1.5): μ at rest is unique and is the window solver's.
        let g = Groups {
            duz_rel: 1.5,
            dux_rel: 0.75,
            phi: 0.3,
        };
        let lo = Law::of(&Scene::dimensionless_with_contact(g, ContactMode::Intermittent).unwrap());
        assert_eq!(lo.name(), "lift-off");
        let d = lo.scene().drive();
        let z = lo.at(0.0, 1e-8).unwrap();
        assert_eq!(z.upper, z.lower);
        let w = liftoff::mu_over_mu0::<f64, Libm>(&d, 0.0).unwrap();
        assert!((z.upper - w).abs() <= z.bound + 1e-15);
        let (m, b) = lo.mu(-0.2, 1e-8).unwrap();
        let w = liftoff::mu_over_mu0::<f64, Libm>(&d, -0.2).unwrap();
        assert!((m - w).abs() <= b + 1e-15);
        assert!(lo.mean_normal().unwrap() > 1.0);
        // A sphere: the MDR's answer, limits at rest, a bed of springs.
        let g = Groups::from_ratio(0.5, 2.0, 0.7).unwrap();
        let sp = Law::with_profile(&Scene::dimensionless(g).unwrap(), Profile::Sphere);
        assert_eq!(sp.name(), "sphere");
        let (m, b) = sp.mu(0.1, 1e-6).unwrap();
        let d = sp.scene().drive();
        let r = mdr::mu_over_mu0::<f64, Libm>(&d, &Profile::Sphere, 0.1, 1e-6).unwrap();
        assert!((m - r.mu_over_mu0).abs() <= b + r.bound);
        let z = sp.at(0.0, 1e-6).unwrap();
        let (p, q) = mdr::limits_at_zero::<f64, Libm>(&d, &Profile::Sphere, 1e-6).unwrap();
        assert!((z.upper - p.mu_over_mu0).abs() <= z.bound + p.bound);
        assert!((z.lower - q.mu_over_mu0).abs() <= z.bound + q.bound);
        assert_eq!(sp.exponent(), Some(2.0));
    }
}
