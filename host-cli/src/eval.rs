//! μ at one point by a method: the single place where the CLI turns a scene
//! and a velocity into a number (shared by `mu`, `curve`, `map --v-rel`, the
//! figures and the methods bench), and the one-line messages of the solvers'
//! failures.

use clap::ValueEnum;
use model_core::analytic::approx::{approx_mu_over_mu0, ApproxError, MAX_ERROR_OVER_A};
use model_core::analytic::{ApproxKind, CriticalVelocity};
use model_core::exact::{self, ExactError, Solution};
use model_core::fixed_step::{self, FixedStepConfig, FixedStepError, Start};
use model_core::select::{self, SelectError, Value};
use model_core::{Libm, Scene};
use serde::Serialize;

use crate::error::{CliError, CliResult};

/// How μ is computed.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
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
pub fn from_rel(vc: &CriticalVelocity<f64>, x: f64, flag: &str) -> CliResult<f64> {
    if !x.is_finite() {
        return Err(CliError::usage(format!(
            "--{flag}: must be a finite number"
        )));
    }
    let c = if x > 0.0 { vc.forward } else { vc.backward };
    if x != 0.0 && c == 0.0 {
        return Err(CliError::usage(format!(
            "--{flag}: the critical velocity in this direction is 0 (μ = ±μ0 at any speed); give --v0"
        )));
    }
    Ok(x * c)
}

/// How to compute μ: the flags shared by `mu`, `curve` and `map`.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct MethodArgs {
    /// Computation method
    #[arg(long, value_enum, default_value_t = Method::Auto)]
    pub method: Method,
    /// Steps per period for --method fixed
    #[arg(long, default_value_t = 10_000, allow_hyphen_values = true, value_parser = crate::args::count::<u32, 1>)]
    pub steps_per_period: u32,
    /// Error tolerance of --method auto, in units of μ0: the cheapest method whose guaranteed bound is within it answers (default: the exact solver's bound)
    #[arg(long, value_name = "TOL")]
    pub tol: Option<f64>,
}

impl Default for MethodArgs {
    fn default() -> Self {
        MethodArgs {
            method: Method::Auto,
            steps_per_period: 10_000,
            tol: None,
        }
    }
}

impl MethodArgs {
    /// Checks the flags that do not depend on the scene.
    pub fn validate(&self) -> CliResult {
        if let Some(t) = self.tol {
            if !(t.is_finite() && t > 0.0) {
                return Err(CliError::usage("--tol: must be a finite number > 0"));
            }
            if self.method != Method::Auto {
                return Err(CliError::usage(
                    "--tol: only --method auto chooses by tolerance (the other methods report their bound)",
                ));
            }
        }
        Ok(())
    }
}

/// μ at `v0` by the method in `m`.
///
/// Errors: bad velocity (exit 2); a method that does not apply or a
/// tolerance no method meets (exit 2); a solver failure (exit 1). A
/// fixed-step run that does not converge is *not* an error here: it returns
/// `converged: false` with `mu: null`.
pub fn mu_at(scene: &Scene<f64>, v0: f64, m: &MethodArgs) -> CliResult<MuOutcome> {
    let (method, steps) = (m.method, m.steps_per_period);
    if !v0.is_finite() {
        return Err(CliError::usage("--v0: must be a finite number"));
    }
    let vc = CriticalVelocity::of(scene);
    let mu0 = scene.mu0();
    let d = scene.drive();
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
    };
    let set = |out: &mut MuOutcome, m: f64, method: &'static str| {
        out.mu_over_mu0 = Some(m);
        out.mu = Some(m * mu0);
        out.method = method;
    };
    match method {
        Method::Auto => {
            let tol = m.tol.unwrap_or_else(|| exact::error_bound::<f64, Libm>(&d));
            let a = select::mu_within::<f64, Libm>(scene, v0, tol).map_err(|e| match e {
                SelectError::BadTolerance => CliError::usage("--tol: must be a finite number > 0"),
                SelectError::ToleranceTooTight { best } => CliError::usage(format!(
                    "--tol: {tol:e} is tighter than any method guarantees for this scene (the exact solver's bound is {best:e})"
                )),
                SelectError::Exact(e) => exact_failure(e),
                SelectError::Mdr(e) => CliError::usage(e.to_string()),
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
                    return Err(CliError::usage(
                        "--v0: the fixed-step method needs v0 != 0 (at rest the result depends on the initial state; see `fricctl static`)",
                    ))
                }
                Err(FixedStepError::TooFewSteps { min_steps }) => {
                    return Err(CliError::usage(format!(
                        "--steps-per-period: this drive needs at least {min_steps} (fewer cannot resolve its stick windows: the error bound would exceed 10 % of mu0)"
                    )))
                }
                Err(FixedStepError::PrecisionLimit { max_steps }) => {
                    return Err(CliError::usage(format!(
                        "--steps-per-period: at most {max_steps} (beyond it rounding grows faster than the discretisation error shrinks)"
                    )))
                }
                Err(FixedStepError::IllConditioned) => {
                    return Err(CliError::failure(
                        "the fixed-step method cannot resolve this drive in f64 (dux-rel too large): its error bound exceeds 1 % of mu0 at any step count",
                    ))
                }
                Err(FixedStepError::BadVelocity(e)) => {
                    return Err(CliError::usage(format!("--{e}")))
                }
                Err(e) => return Err(CliError::failure(format!("fixed-step run refused: {e}"))),
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
            Err(e) => return Err(CliError::usage(match e {
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

/// The one-line message for an exact-solver failure.
pub fn exact_failure(e: ExactError) -> CliError {
    match e {
        ExactError::BadVelocity(s) => CliError::usage(format!("--{s}")),
        ExactError::IllConditioned => CliError::failure(
            "the exact solver cannot resolve this drive in f64 (dux-rel too large): its error bound would exceed 1 % of mu0",
        ),
        other => CliError::failure(format!("exact solver failed: {other}")),
    }
}
