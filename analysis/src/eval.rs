//! μ at one point by a method: the single place where a scene and a velocity
//! become a number (shared by the CLI's `mu`, `curve`, `map --v-rel`, the
//! figures, the methods bench and the Python package), and the one-line
//! messages of the solvers' failures.

use model_core::analytic::approx::{approx_mu_over_mu0, ApproxError, MAX_ERROR_OVER_A};
use model_core::analytic::{ApproxKind, CriticalVelocity};
use model_core::exact::{self, ExactError, Solution};
use model_core::fixed_step::{self, FixedStepConfig, FixedStepError, Start};
use model_core::mdr::{self, MdrError, Profile};
use model_core::model::liftoff::{self, stepping, LiftOffError};
use model_core::regime::{self, ClassifyOptions, Regime};
use model_core::select::{self, SelectError, Value};
use model_core::{Drive, Libm, Scene};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::numbers::short;

/// How μ is computed (the CLI's `--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// The cheapest method whose error bound meets --tol: ±μ0 beyond v_c, the static analysis at v0 = 0, eq. 21/24 where their bound is within --tol, the exact solver otherwise
    #[default]
    Auto,
    /// The exact event-driven steady-state solver
    Exact,
    /// The paper's fixed-step scheme from rest (§3), with proven steady-state detection
    Fixed,
    /// The closed-form approximation eq. 21 (normal only) or eq. 24 (tangential only, dux-rel ≤ 1)
    Approx,
}

impl Method {
    /// Every method, in the CLI's order.
    pub const ALL: [Method; 4] = [Method::Auto, Method::Exact, Method::Fixed, Method::Approx];

    /// Its name, as the CLI's `--method` value.
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Exact => "exact",
            Method::Fixed => "fixed",
            Method::Approx => "approx",
        }
    }

    /// The method named `name`.
    ///
    /// # Errors
    /// `--method: invalid value '…' (one of: auto, exact, fixed, approx)`.
    pub fn from_name(name: &str) -> Result<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                Error::usage(format!(
                    "--method: invalid value '{name}' (one of: auto, exact, fixed, approx)"
                ))
            })
    }
}

/// The result for one velocity (JSON keys are part of the CLI contract).
#[derive(Serialize, Debug, Clone, Copy)]
pub struct MuOutcome {
    /// Sliding velocity, m/s (in units of ωW0 for a dimensionless scene).
    pub v0: f64,
    /// v0/v_c for the direction of motion (null when that v_c is 0).
    pub v_rel: Option<f64>,
    /// μ (null at v0 = 0 or when not converged).
    pub mu: Option<f64>,
    /// μ/μ0.
    pub mu_over_mu0: Option<f64>,
    /// Which computation answered: `sliding`, `exact`, `static`, `fixed`, `approx_eq21`, `approx_eq24`.
    pub method: &'static str,
    /// The bound this method guarantees for `mu_over_mu0` (or for μ(0±) at
    /// rest), in units of μ0 (null when a fixed-step run did not converge).
    pub error_bound_over_mu0: Option<f64>,
    /// Forward critical velocity (eq. 8).
    pub vc_forward: f64,
    /// Backward critical velocity (eq. 8).
    pub vc_backward: f64,
    /// At v0 = 0: lim μ/μ0 for v0 → 0⁺.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_0plus_over_mu0: Option<f64>,
    /// At v0 = 0: lim μ/μ0 for v0 → 0⁻.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_0minus_over_mu0: Option<f64>,
    /// Fixed-step: steps per period.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps_per_period: Option<u32>,
    /// Fixed-step: periods integrated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub periods: Option<u32>,
    /// Fixed-step: whether a provably steady period was reached.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
    /// Fixed-step, not converged: μ/μ0 of the last period (not a steady-state value).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub last_mu_over_mu0: Option<f64>,
    /// Whether the contact lifts off once per period (Δu_z ≥ u_z0): μ is then
    /// normalised by the mean normal force k_z⟨u_z⁺⟩, μ at v0 = 0 is unique
    /// and v_c is the contact window's (eq. L5), not eq. 8.
    pub lifts_off: bool,
    /// The contact profile: `flat`, `sphere`, `cone`, `power`.
    pub profile: &'static str,
    /// Its exponent n (null for flat; 2 for a sphere, 1 for a cone).
    pub exponent: Option<f64>,
}

impl MuOutcome {
    /// The refusal of a fixed-step run that did not reach a steady state
    /// (`converged: false`: `mu` is null, the last period is not a result).
    pub fn not_converged(&self) -> Option<Error> {
        (self.converged == Some(false)).then(|| {
            Error::failure(format!(
                "the fixed-step method did not reach a steady state in {} periods (last period's mu/mu0 = {}, not a result)",
                self.periods.unwrap_or(0),
                self.last_mu_over_mu0.map_or("-".to_string(), short)
            ))
        })
    }
}

/// Critical velocities of a scene, m/s (units of ωW0 for a dimensionless
/// scene): eq. 8 for a permanent contact, the contact window's (eq. L5 of
/// `model_core::model::liftoff`) for one that lifts off.
pub fn critical_velocity(scene: &Scene<f64>) -> Result<CriticalVelocity<f64>> {
    if !scene.lifts_off() {
        return Ok(CriticalVelocity::of(scene));
    }
    let (c, cb) =
        liftoff::critical_velocities::<f64, Libm>(&scene.drive()).map_err(lift_off_failure)?;
    let unit = scene.velocity_scale();
    Ok(CriticalVelocity {
        forward: c * unit,
        backward: cb * unit,
    })
}

/// `⟨u_z⁺⟩/u_z0`, the mean normal force in units of `k_z u_z0` (eq. L4):
/// 1 for a permanent contact, `(π − θ_c + √(a² − 1))/π` with lift-off.
pub fn mean_normal_force_over_kz_uz0(scene: &Scene<f64>) -> f64 {
    if scene.lifts_off() {
        liftoff::mean_band::<f64, Libm>(scene.drive().a)
    } else {
        1.0
    }
}

/// A regime classification for either contact (the numbers `classify` and
/// the regime map show); μ as μ/μ0, velocities in units of ωW0.
#[derive(Debug, Clone, Copy)]
pub struct Classified {
    /// The class.
    pub regime: Regime,
    /// μ(0⁺)/μ0 (with lift-off: μ(0)/μ0, unique).
    pub mu_0plus: f64,
    /// μ(0⁻)/μ0 (with lift-off: μ(0)/μ0, unique).
    pub mu_0minus: f64,
    /// The forward critical velocity over ωW0 (eq. 8, or eq. L5 with lift-off).
    pub c_forward: f64,
    /// The backward critical velocity over ωW0.
    pub c_backward: f64,
    /// max |μ(v) + μ(−v)|/μ0 over the sampled velocities.
    pub asymmetry: f64,
    /// The permanent contact's static analysis (None with lift-off: there is
    /// no static interval, the force at rest is unique).
    pub statics: Option<model_core::analytic::StaticFriction<f64>>,
    /// A curved profile's limits at rest and static interval (None for the
    /// flat punch).
    pub profile_statics: Option<ProfileStatics>,
}

/// Classifies a scene: `regime::classify` for a permanent contact,
/// `liftoff::regime::classify` for one that lifts off.
pub fn classify_scene(s: &Scene<f64>) -> Result<Classified> {
    if s.lifts_off() {
        let c = liftoff::regime::classify::<f64, Libm>(&s.drive(), &ClassifyOptions::default())
            .map_err(lift_off_failure)?;
        return Ok(Classified {
            regime: c.regime,
            mu_0plus: c.mu_at_rest,
            mu_0minus: c.mu_at_rest,
            c_forward: c.c_forward,
            c_backward: c.c_backward,
            asymmetry: c.asymmetry,
            statics: None,
            profile_statics: None,
        });
    }
    let c = regime::classify(s, &ClassifyOptions::default()).map_err(exact_failure)?;
    Ok(Classified {
        regime: c.regime,
        mu_0plus: c.mu_0plus,
        mu_0minus: c.mu_0minus,
        c_forward: c.c_forward,
        c_backward: c.c_backward,
        asymmetry: c.asymmetry,
        statics: Some(c.statics),
        profile_statics: None,
    })
}

/// `v0/v_c` in the direction of motion, `None` when that `v_c` is 0.
pub fn v_rel(vc: &CriticalVelocity<f64>, v0: f64) -> Option<f64> {
    let c = vc.for_velocity(v0);
    if v0 == 0.0 {
        Some(0.0)
    } else if c > 0.0 {
        Some(v0 / c)
    } else {
        None
    }
}

/// Velocity from a relative one: `x·v_c` (forward v_c for x > 0, backward for x < 0).
/// `x` is in its domain (the flag's parser); the product must be a normal
/// number (or 0).
pub fn from_rel(vc: &CriticalVelocity<f64>, x: f64, flag: &str) -> Result<f64> {
    let c = if x > 0.0 { vc.forward } else { vc.backward };
    if x != 0.0 && c == 0.0 {
        return Err(Error::usage(format!(
            "--{flag}: the critical velocity in this direction is 0 (μ = ±μ0 at any speed); give --v0"
        )));
    }
    let v = x * c;
    if !v.is_finite() || (v != 0.0 && v.abs() < f64::MIN_POSITIVE) {
        return Err(Error::usage(format!(
            "--{flag}: {}·v_c with v_c = {} over- or underflows the number type",
            short(x),
            short(c)
        )));
    }
    Ok(v)
}

/// How to compute μ (the CLI's `--method`, `--steps-per-period`, `--tol`,
/// and the scene's profile).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MethodArgs {
    /// Computation method.
    pub method: Method,
    /// Steps per period for [`Method::Fixed`] (default [`DEFAULT_STEPS_PER_PERIOD`]; refused with the other methods).
    pub steps_per_period: Option<u32>,
    /// Error tolerance of [`Method::Auto`], in units of μ0: the cheapest method whose guaranteed bound is within it answers (default: the exact solver's bound; [`PROFILE_TOL`] for a curved profile).
    pub tol: Option<f64>,
    /// The contact's shape: a curved profile goes to the MDR quadrature.
    pub profile: Profile<f64>,
}

/// Default tolerance of the MDR quadrature for a curved profile, units of μ0
/// (the accuracy asked of a sphere's μ), raised to twice the per-spring solvers'
/// part of the bound where that is larger.
pub const PROFILE_TOL: f64 = 1e-9;

/// Steps per period of `--method fixed` when `--steps-per-period` is not given.
pub const DEFAULT_STEPS_PER_PERIOD: u32 = 10_000;

impl Default for MethodArgs {
    fn default() -> Self {
        MethodArgs {
            method: Method::Auto,
            steps_per_period: None,
            tol: None,
            profile: Profile::Flat,
        }
    }
}

impl MethodArgs {
    /// Checks the flags that do not depend on the scene: `--tol` only with
    /// `--method auto`, `--steps-per-period` only with `--method fixed`
    /// (a flag that would be ignored is refused).
    pub fn validate(&self) -> Result {
        if let Some(t) = self.tol {
            crate::scene::check(crate::numbers::Real::positive(), t, "--tol")?;
        }
        if self.steps_per_period == Some(0) {
            return Err(Error::usage("--steps-per-period: must be ≥ 1 (got 0)"));
        }
        if self.tol.is_some() && self.method != Method::Auto {
            return Err(Error::usage(
                "--tol: only --method auto chooses by tolerance (the other methods report their bound)",
            ));
        }
        if self.steps_per_period.is_some() && self.method != Method::Fixed {
            return Err(Error::usage(
                "--steps-per-period: only with --method fixed (the other methods do not step)",
            ));
        }
        Ok(())
    }

    /// Steps per period of `--method fixed`.
    pub fn steps(&self) -> u32 {
        self.steps_per_period.unwrap_or(DEFAULT_STEPS_PER_PERIOD)
    }

    /// The flag that set the step count: `--steps-per-period`, or
    /// `--method` when the default is used.
    pub fn steps_flag(&self) -> &'static str {
        if self.steps_per_period.is_some() {
            "--steps-per-period"
        } else {
            "--method"
        }
    }
}

/// μ at `v0` by the method in `m`.
///
/// Errors: bad velocity (exit 2); a method that does not apply or a
/// tolerance no method meets (exit 2); a solver failure (exit 1). A
/// fixed-step run that does not converge is *not* an error here: it returns
/// `converged: false` with `mu: null`.
pub fn mu_at(scene: &Scene<f64>, v0: f64, m: &MethodArgs) -> Result<MuOutcome> {
    let (method, steps) = (m.method, m.steps());
    if !v0.is_finite() {
        return Err(Error::usage("--v0: must be a finite number"));
    }
    let vc = critical_velocity(scene)?;
    let mu0 = scene.mu0();
    let d = scene.drive();
    let lifts_off = scene.lifts_off();
    let mut out = MuOutcome {
        v0,
        v_rel: v_rel(&vc, v0),
        mu: None,
        mu_over_mu0: None,
        method: "exact",
        error_bound_over_mu0: None,
        vc_forward: vc.forward,
        vc_backward: vc.backward,
        mu_0plus_over_mu0: None,
        mu_0minus_over_mu0: None,
        steps_per_period: None,
        periods: None,
        converged: None,
        last_mu_over_mu0: None,
        lifts_off,
        profile: m.profile.name(),
        exponent: m.profile.exponent(),
    };
    let set = |out: &mut MuOutcome, m: f64, method: &'static str| {
        out.mu_over_mu0 = Some(m);
        out.mu = Some(m * mu0);
        out.method = method;
    };
    if m.profile != Profile::Flat {
        profile_at(scene, v0, m, &mut out)?;
        return Ok(out);
    }
    if lifts_off && method != Method::Auto {
        lift_off_at(scene, v0, m, &mut out)?;
        return Ok(out);
    }
    match method {
        Method::Auto => {
            let tol = m.tol.unwrap_or_else(|| {
                if lifts_off {
                    liftoff::error_bound::<f64, Libm>(&d)
                } else {
                    exact::error_bound::<f64, Libm>(&d)
                }
            });
            let a = select::mu_within::<f64, Libm>(scene, v0, tol).map_err(|e| match e {
                SelectError::BadTolerance => Error::usage("--tol: must be a finite number > 0"),
                SelectError::ToleranceTooTight { best } => Error::usage(format!(
                    "--tol: {tol:e} is tighter than any method guarantees for this scene (the exact solver's bound is {best:e})"
                )),
                SelectError::Exact(e) => exact_failure(e),
                SelectError::Mdr(e) => Error::usage(e.to_string()),
            })?;
            out.error_bound_over_mu0 = Some(a.bound);
            match a.value {
                Value::Mu(x) => set(&mut out, x, a.method.name()),
                Value::AtRest {
                    mu_0plus,
                    mu_0minus,
                    ..
                }
                | Value::Limits {
                    mu_0plus,
                    mu_0minus,
                } => {
                    out.method = a.method.name();
                    out.mu_0plus_over_mu0 = Some(mu_0plus);
                    out.mu_0minus_over_mu0 = Some(mu_0minus);
                }
            }
        }
        Method::Exact => {
            let sol = exact::solve(scene, v0).map_err(exact_failure)?;
            match sol {
                Solution::Sliding { mu_over_mu0 } => {
                    set(&mut out, mu_over_mu0, "exact");
                    out.error_bound_over_mu0 = Some(0.0);
                }
                Solution::StickSlip { mu_over_mu0 } => {
                    set(&mut out, mu_over_mu0, "exact");
                    out.error_bound_over_mu0 = Some(exact::error_bound::<f64, Libm>(&d));
                }
                Solution::AtRest {
                    mu_0plus,
                    mu_0minus,
                    ..
                } => {
                    out.method = "static";
                    out.mu_0plus_over_mu0 = Some(mu_0plus);
                    out.mu_0minus_over_mu0 = Some(mu_0minus);
                    out.error_bound_over_mu0 = Some(exact::error_bound::<f64, Libm>(&d));
                }
            }
        }
        Method::Fixed => {
            // Budget: at most 2·10⁸ steps (≈ 1 s) however small v0 is; past it
            // the run reports "not converged" instead of appearing to hang.
            let mut cfg = FixedStepConfig::<f64>::new(steps);
            cfg.max_periods = (200_000_000 / steps.max(1)).clamp(3, 1_000_000);
            out.method = "fixed";
            out.steps_per_period = Some(steps);
            match fixed_step::run(scene, v0, &cfg, Start::Rest) {
                Ok(r) => {
                    set(&mut out, r.mu_over_mu0, "fixed");
                    out.periods = Some(r.periods);
                    out.converged = Some(true);
                    out.error_bound_over_mu0 = Some(r.error_bound);
                }
                Err(FixedStepError::NotConverged {
                    periods,
                    last_mu_over_mu0,
                    ..
                }) => {
                    out.periods = Some(periods);
                    out.converged = Some(false);
                    out.last_mu_over_mu0 = Some(last_mu_over_mu0);
                }
                Err(FixedStepError::ZeroVelocity) => {
                    return Err(Error::usage(
                        "--v0: the fixed-step method needs v0 != 0 (at rest the result depends on the initial state; see `fricctl static`)",
                    ))
                }
                Err(FixedStepError::TooFewSteps { min_steps }) => {
                    return Err(Error::usage(format!(
                        "{}: this drive needs at least {min_steps} steps per period (fewer cannot resolve its stick windows: the error bound would exceed 10 % of mu0)",
                        m.steps_flag()
                    )))
                }
                Err(FixedStepError::PrecisionLimit { max_steps }) => {
                    return Err(Error::usage(format!(
                        "{}: at most {max_steps} steps per period (beyond it rounding grows faster than the discretisation error shrinks)",
                        m.steps_flag()
                    )))
                }
                Err(FixedStepError::IllConditioned) => {
                    return Err(Error::failure(
                        "the fixed-step method cannot resolve this drive in f64 (kx·dux/(mu0·kz·uz0) too large): its error bound exceeds 1 % of mu0 at any step count",
                    ))
                }
                Err(FixedStepError::BadVelocity(e)) => {
                    return Err(Error::usage(format!("--{e}")))
                }
                Err(e) => return Err(Error::failure(format!("fixed-step run refused: {e}"))),
            }
        }
        Method::Approx => match approx_mu_over_mu0(scene, v0) {
            Ok((kind, m)) => {
                set(&mut out, m, select::Method::Approx(kind).name());
                let amp = match kind {
                    ApproxKind::NormalEq21 => d.a,
                    ApproxKind::TangentialEq24 => d.b,
                };
                out.error_bound_over_mu0 = Some(if m.abs() == 1.0 {
                    0.0
                } else {
                    MAX_ERROR_OVER_A * amp
                });
            }
            Err(e) => return Err(Error::usage(match e {
                ApproxError::DualMode => {
                    "--method: approx needs a single-mode scene (eq. 21: dux = 0; eq. 24: duz = 0)"
                        .to_string()
                }
                ApproxError::TangentialTooLarge => {
                    "--method: approx (eq. 24) needs kx·dux/(mu0·kz·uz0) <= 1".to_string()
                }
                ApproxError::ZeroVelocity => {
                    "--v0: approx needs v0 != 0 (see `fricctl static`)".to_string()
                }
                ApproxError::NonFiniteVelocity => "--v0: must be a finite number".to_string(),
            })),
        },
    }
    Ok(out)
}

/// [`mu_at`] for a scene that lifts off, `--method exact|fixed|approx`:
/// the lift-off solver, the lift-off stepping, or a refusal.
fn lift_off_at(scene: &Scene<f64>, v0: f64, m: &MethodArgs, out: &mut MuOutcome) -> Result {
    let d = scene.drive();
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(|e| Error::usage(format!("--{e}")))?;
    let set = |out: &mut MuOutcome, x: f64, method: &'static str, bound: f64| {
        out.mu_over_mu0 = Some(x);
        out.mu = Some(x * scene.mu0());
        out.method = method;
        out.error_bound_over_mu0 = Some(bound);
    };
    match m.method {
        Method::Auto | Method::Exact => {
            let (c, cb) =
                liftoff::critical_velocities::<f64, Libm>(&d).map_err(lift_off_failure)?;
            if v >= c || -v >= cb {
                // Continuous sliding through the whole window: ±1 exactly.
                set(out, if v >= c { 1.0 } else { -1.0 }, "exact", 0.0);
            } else {
                let x = liftoff::mu_over_mu0::<f64, Libm>(&d, v).map_err(lift_off_failure)?;
                set(out, x, "exact", liftoff::error_bound::<f64, Libm>(&d));
            }
        }
        Method::Fixed => {
            let r = stepping::mu_over_mu0::<f64, Libm>(&d, v, m.steps()).map_err(|e| {
                let e = lift_off_failure(e);
                match e.msg.strip_prefix("--steps-per-period:") {
                    Some(rest) => Error::usage(format!("{}:{rest}", m.steps_flag())),
                    None => e,
                }
            })?;
            set(out, r.mu_over_mu0, "fixed", r.error_bound);
            out.steps_per_period = Some(m.steps());
            // One contact window is the exact steady state (the state resets
            // at every landing): one period, nothing to converge.
            out.periods = Some(1);
            out.converged = Some(true);
        }
        Method::Approx => {
            return Err(Error::usage(
                "--method: approx (eqs. 21/24) assumes permanent contact; this scene lifts off (duz >= uz0): use auto, exact or fixed",
            ))
        }
    }
    Ok(())
}

/// The tolerance of the MDR quadrature when none is given: [`PROFILE_TOL`],
/// or twice the per-spring solvers' part of its bound where that is larger.
pub fn profile_tol(scene: &Scene<f64>, p: &Profile<f64>) -> f64 {
    profile_tol_of(&scene.drive(), p)
}

/// [`profile_tol`] of a dimensionless drive.
pub fn profile_tol_of(d: &Drive<f64>, p: &Profile<f64>) -> f64 {
    match p.exponent() {
        Some(n) => PROFILE_TOL.max(2.0 * mdr::solver_bound::<f64, Libm>(d, n)),
        None => PROFILE_TOL,
    }
}

/// [`profile_tol`] for the one-sided limits at rest (`v0 = 0` with
/// `duz < uz0`), from `mdr::solver_bound_at_rest` (now equal to
/// `mdr::solver_bound`: the springs at rest are checked at the same
/// per-spring precision).
pub fn profile_tol_at_rest(scene: &Scene<f64>, p: &Profile<f64>) -> f64 {
    profile_tol_of_at_rest(&scene.drive(), p)
}

/// [`profile_tol_at_rest`] of a dimensionless drive.
pub fn profile_tol_of_at_rest(d: &Drive<f64>, p: &Profile<f64>) -> f64 {
    match p.exponent() {
        Some(n) => PROFILE_TOL.max(2.0 * mdr::solver_bound_at_rest::<f64, Libm>(d, n)),
        None => PROFILE_TOL,
    }
}

/// [`mu_at`] for a curved profile: the MDR quadrature (`--method auto` by
/// `select::mu_within_profile`, `--method exact` the same quadrature); the
/// fixed-step scheme and the approximations are for the flat punch.
fn profile_at(scene: &Scene<f64>, v0: f64, m: &MethodArgs, out: &mut MuOutcome) -> Result {
    let p = &m.profile;
    let tol = match (m.method, m.tol) {
        (Method::Auto, Some(t)) => t,
        (Method::Auto | Method::Exact, _) if v0 == 0.0 => profile_tol_at_rest(scene, p),
        (Method::Auto | Method::Exact, _) => profile_tol(scene, p),
        (Method::Fixed | Method::Approx, _) => {
            return Err(Error::usage(format!(
                "--profile: --method {} is for the flat punch; a {} profile is computed by the MDR quadrature (--method auto or exact)",
                if m.method == Method::Fixed { "fixed" } else { "approx" },
                p.name()
            )))
        }
    };
    let a = select::mu_within_profile::<f64, Libm>(scene, p, v0, tol)
        .map_err(|e| profile_failure(e, tol, p))?;
    out.error_bound_over_mu0 = Some(a.bound);
    out.method = a.method.name();
    match a.value {
        Value::Mu(x) => {
            out.mu_over_mu0 = Some(x);
            out.mu = Some(x * scene.mu0());
        }
        Value::AtRest {
            mu_0plus,
            mu_0minus,
            ..
        }
        | Value::Limits {
            mu_0plus,
            mu_0minus,
        } => {
            out.mu_0plus_over_mu0 = Some(mu_0plus);
            out.mu_0minus_over_mu0 = Some(mu_0minus);
        }
    }
    Ok(())
}

/// The one-line message for a failure of `select::mu_within_profile`.
pub fn profile_failure(e: SelectError<f64>, tol: f64, p: &Profile<f64>) -> Error {
    match e {
        SelectError::BadTolerance => Error::usage("--tol: must be a finite number > 0"),
        SelectError::ToleranceTooTight { best } => Error::usage(format!(
            "--tol: {tol:e} is tighter than the {} profile's computation can guarantee for this scene (best {best:e})",
            p.name()
        )),
        SelectError::Exact(e) => exact_failure(e),
        SelectError::Mdr(e) => mdr_failure(e),
    }
}

/// The one-line message for an MDR failure.
pub fn mdr_failure(e: MdrError) -> Error {
    match e {
        MdrError::BadExponent
        | MdrError::BadVelocity
        | MdrError::BadTolerance
        | MdrError::ToleranceTooTight { .. }
        | MdrError::AtRest => Error::usage(format!("--{e}")),
        MdrError::NotConverged { .. } | MdrError::IllConditioned => {
            Error::failure(format!("--{e}"))
        }
        MdrError::BadDrive | MdrError::Inconsistent => Error::failure(e.to_string()),
    }
}

/// A curved profile at rest (docs/guide/lift-off-and-profiles.md, "Curved
/// profiles at rest", eqs. S1–S4): the one-sided limits μ(0±)/μ0 of the
/// MDR quadrature with their bound, the critical velocities (the flat
/// punch's with the same drive, eq. S1) over ωW0, and whether the static
/// interval — the held forces `μ/μ0 ∈ [μ(0⁻), μ(0⁺)]` (units of μ0 times the
/// mean normal force) at which the body stays at rest on average — has a
/// width (eq. S2: the central spring is permanent, `a < 1`, and sticks,
/// `c + c' < 2`; its width is eq. S3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileStatics {
    /// μ(0⁺)/μ0 (with `a ≥ 1`: μ(0)/μ0, unique).
    pub mu_0plus: f64,
    /// μ(0⁻)/μ0 (with `a ≥ 1`: μ(0)/μ0, unique).
    pub mu_0minus: f64,
    /// The larger of the two limits' bounds, units of μ0.
    pub bound: f64,
    /// The forward critical velocity over ωW0 (eq. S1).
    pub c_forward: f64,
    /// The backward critical velocity over ωW0.
    pub c_backward: f64,
    /// The static interval has a width (eq. S2).
    pub exists: bool,
}

/// [`ProfileStatics`] of a scene with a curved profile `p`, at the
/// tolerance the CLI's `mu --v0 0` uses ([`profile_tol_at_rest`]).
///
/// # Errors
/// The MDR's refusal as one line ([`mdr_failure`]); the flat punch is
/// refused (its static analysis is `model_core::analytic::StaticFriction`).
pub fn profile_statics(s: &Scene<f64>, p: &Profile<f64>) -> Result<ProfileStatics> {
    if *p == Profile::Flat {
        return Err(Error::failure(
            "profile_statics is for a curved profile; the flat punch has StaticFriction",
        ));
    }
    let d = s.drive();
    let (c, cb) = mdr::critical_velocities::<f64, Libm>(&d, p).map_err(mdr_failure)?;
    let tol = profile_tol(s, p).max(profile_tol_at_rest(s, p));
    let (plus, minus) = mdr::limits_at_zero::<f64, Libm>(&d, p, tol).map_err(mdr_failure)?;
    Ok(ProfileStatics {
        mu_0plus: plus.mu_over_mu0,
        mu_0minus: minus.mu_over_mu0,
        bound: plus.bound.max(minus.bound),
        c_forward: c,
        c_backward: cb,
        exists: mdr::static_interval_exists::<f64, Libm>(&d),
    })
}

/// Classifies a scene with a contact profile: [`classify_scene`] for the
/// flat punch; for a curved profile the same definitions as
/// `model_core::regime` from the MDR quadrature: μ(0±) (one μ(0) for
/// `a ≥ 1`), critical velocities (the flat punch's, `mdr::critical_velocities`),
/// asymmetry max |μ(v) + μ(−v)| over 64 velocities in (0, max v_c). The
/// "zero" tolerance is the larger of 1e-9 and four times the quadrature's
/// largest bound, so a quadrature error cannot flip a class.
pub fn classify_scene_profile(s: &Scene<f64>, p: &Profile<f64>) -> Result<Classified> {
    if *p == Profile::Flat {
        return classify_scene(s);
    }
    let d = s.drive();
    let tol = profile_tol(s, p);
    let mut worst = 0.0f64;
    let mut mu = |v: f64| -> Result<f64> {
        let r = mdr::mu_over_mu0::<f64, Libm>(&d, p, v, tol).map_err(mdr_failure)?;
        worst = worst.max(r.bound);
        Ok(r.mu_over_mu0)
    };
    let st = profile_statics(s, p)?;
    let (c, cb, plus, minus) = (st.c_forward, st.c_backward, st.mu_0plus, st.mu_0minus);
    let limits_bound = st.bound;
    let mut asymmetry = (plus + minus).abs();
    let vmax = c.max(cb);
    let samples = ClassifyOptions::<f64>::default().samples.max(1);
    if vmax > 0.0 {
        for i in 1..=samples {
            let v = vmax * f64::from(i) / f64::from(samples + 1);
            let f = if v >= c { 1.0 } else { mu(v)? };
            let b = if v >= cb { -1.0 } else { mu(-v)? };
            asymmetry = asymmetry.max((f + b).abs());
        }
    }
    let zero = ClassifyOptions::<f64>::default()
        .tol
        .max(4.0 * worst.max(limits_bound));
    let regime = if plus < -zero || minus > zero {
        Regime::Actuator
    } else if asymmetry <= zero {
        Regime::ActiveControl
    } else {
        Regime::DynamicRatchet
    };
    Ok(Classified {
        regime,
        mu_0plus: plus,
        mu_0minus: minus,
        c_forward: c,
        c_backward: cb,
        asymmetry,
        statics: None,
        profile_statics: Some(st),
    })
}

/// The class [`classify_scene_profile`] gives, without its asymmetry
/// figure, at a fraction of its cost (a regime map's cell). The full
/// classification's "zero" is at least `z₀ = max(1e-9, 4·β₀)` (β₀ the
/// limits' bound) and at most `Z = max(1e-9, 4·tol)` (every bound is within
/// the tolerance `tol` asked for), so its class is known early:
/// an actuator when `μ(0⁺) < −Z` or `μ(0⁻) > Z`; a dynamic ratchet when it
/// is surely not an actuator (`μ(0⁺) ≥ −z₀`, `μ(0⁻) ≤ z₀`) and one of the
/// full classification's own samples `|μ(v) + μ(−v)|` (or `|μ(0⁺) +
/// μ(0⁻)|`) exceeds `Z` — tried first where one side slides freely
/// (`min(v_c) ≤ v < max(v_c)`, one quadrature). Anything else is classified
/// in full. Same class as [`classify_scene_profile`] always (tested).
///
/// Returns the class and the limits at rest (`None` for the flat punch).
///
/// # Errors
/// As [`classify_scene_profile`].
pub fn regime_of_profile(
    s: &Scene<f64>,
    p: &Profile<f64>,
) -> Result<(Regime, Option<ProfileStatics>)> {
    if *p == Profile::Flat {
        return classify_scene(s).map(|c| (c.regime, None));
    }
    let d = s.drive();
    let st = profile_statics(s, p)?;
    let early = |r| Ok((r, Some(st)));
    let tol = profile_tol(s, p);
    let floor = ClassifyOptions::<f64>::default().tol;
    let big = floor.max(4.0 * tol.max(profile_tol_at_rest(s, p)));
    let small = floor.max(4.0 * st.bound);
    let (plus, minus) = (st.mu_0plus, st.mu_0minus);
    if plus < -big || minus > big {
        return early(Regime::Actuator);
    }
    if plus >= -small && minus <= small {
        if (plus + minus).abs() > big {
            return early(Regime::DynamicRatchet);
        }
        let (c, cb) = (st.c_forward, st.c_backward);
        let vmax = c.max(cb);
        let samples = ClassifyOptions::<f64>::default().samples.max(1);
        let v_at = |i: u32| vmax * f64::from(i) / f64::from(samples + 1);
        // One side free first (one quadrature each), nearest the smaller
        // critical velocity; at most four tries before the full work.
        let tries = (1..=samples)
            .filter(|&i| {
                let v = v_at(i);
                v >= c.min(cb) && v < vmax
            })
            .take(4);
        for i in tries {
            let v = v_at(i);
            let mu = |v: f64| {
                mdr::mu_over_mu0::<f64, Libm>(&d, p, v, tol)
                    .map(|r| r.mu_over_mu0)
                    .map_err(mdr_failure)
            };
            let f = if v >= c { 1.0 } else { mu(v)? };
            let b = if v >= cb { -1.0 } else { mu(-v)? };
            if (f + b).abs() > big {
                return early(Regime::DynamicRatchet);
            }
        }
    }
    classify_scene_profile(s, p).map(|c| (c.regime, c.profile_statics))
}

/// The one-line message for a lift-off solver failure.
pub fn lift_off_failure(e: LiftOffError) -> Error {
    match e {
        LiftOffError::BadVelocity(s) => Error::usage(format!("--{s}")),
        LiftOffError::TooFewSteps { min_steps } => Error::usage(format!(
            "--steps-per-period: this lift-off drive needs at least {min_steps} steps per period (fewer: the stepping's bound 10(1 + a + b)/N^2 would exceed 10 % of mu0)"
        )),
        LiftOffError::PrecisionLimit { max_steps } => Error::usage(format!(
            "--steps-per-period: at most {max_steps} steps per period (beyond it rounding grows faster than the discretisation error shrinks)"
        )),
        LiftOffError::IllConditioned => Error::failure(
            "the lift-off solver cannot resolve this drive in f64 (duz/uz0 or kx·dux/(mu0·kz·uz0) too large): its error bound would exceed 1 % of mu0",
        ),
        other => Error::failure(format!("lift-off solver failed: {other}")),
    }
}

/// The one-line message for an exact-solver failure.
pub fn exact_failure(e: ExactError) -> Error {
    match e {
        ExactError::BadVelocity(s) => Error::usage(format!("--{s}")),
        ExactError::IllConditioned => Error::failure(
            "the exact solver cannot resolve this drive in f64 (kx·dux/(mu0·kz·uz0) too large): its error bound would exceed 1 % of mu0",
        ),
        other => Error::failure(format!("exact solver failed: {other}")),
    }
}
