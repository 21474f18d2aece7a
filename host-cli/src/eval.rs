//! The method flags (`--method`, `--steps-per-period`, `--tol`) shared by
//! `mu`, `curve` and `map`; μ itself is computed by the analysis library
//! ([`fric_analysis::eval`], re-exported here).

use clap::ValueEnum;
use model_core::mdr::Profile;
use model_core::Scene;

use crate::args::{Count, Real};
use crate::error::CliResult;

pub use fric_analysis::eval::{
    classify_scene_profile, critical_velocity, exact_failure, from_rel, lift_off_failure,
    mean_normal_force_over_kz_uz0, profile_failure, profile_tol_at_rest, MuOutcome,
};

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

impl From<Method> for fric_analysis::eval::Method {
    fn from(m: Method) -> Self {
        use fric_analysis::eval::Method as M;
        match m {
            Method::Auto => M::Auto,
            Method::Exact => M::Exact,
            Method::Fixed => M::Fixed,
            Method::Approx => M::Approx,
        }
    }
}

/// How to compute μ: the flags shared by `mu`, `curve` and `map`.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct MethodArgs {
    /// Computation method
    #[arg(long, value_enum, default_value_t = Method::Auto)]
    pub method: Method,
    /// Steps per period for --method fixed (default 10000; refused with the other methods)
    #[arg(long, value_parser = Count::<u32>::at_least(1))]
    pub steps_per_period: Option<u32>,
    /// Error tolerance of --method auto, in units of μ0: the cheapest method whose guaranteed bound is within it answers (default: the exact solver's bound; 1e-9 for a curved --profile)
    #[arg(long, value_name = "TOL", value_parser = Real::positive())]
    pub tol: Option<f64>,
    /// The contact's shape (set from `--profile` by the command, not a flag
    /// of its own): a curved profile goes to the MDR quadrature.
    #[arg(skip = Profile::Flat)]
    pub profile: Profile<f64>,
}

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
    /// The library's options for these flags.
    pub fn options(&self) -> fric_analysis::eval::MethodArgs {
        fric_analysis::eval::MethodArgs {
            method: self.method.into(),
            steps_per_period: self.steps_per_period,
            tol: self.tol,
            profile: self.profile,
        }
    }

    /// Refuses a flag that would be ignored (library docs).
    pub fn validate(&self) -> CliResult {
        self.options().validate()
    }
}

/// μ at `v0` by the method in `m` ([`fric_analysis::eval::mu_at`]).
pub fn mu_at(scene: &Scene<f64>, v0: f64, m: &MethodArgs) -> CliResult<MuOutcome> {
    fric_analysis::eval::mu_at(scene, v0, &m.options())
}
