//! Scene flags shared by every model command: physical SI flags, a TOML scene
//! file, or the paper's dimensionless groups. The flags are read here; the
//! checks and the scene they build are the analysis library's
//! ([`fric_analysis::scene`]).

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use fric_analysis::scene::{self as lib, ProfileInput, SceneInput};
use model_core::mdr::Profile;
use model_core::scene::ContactMode;

use crate::error::CliResult;

pub use fric_analysis::scene::{check_reach, profile_text, ResolvedScene};

/// Scene flags (see `fricctl --help`).
#[derive(Args, Debug, Clone, Default)]
pub struct SceneArgs {
    /// Scene file (TOML) with keys mu0, kz, kx, uz0, duz, dux, freq (or omega), phi_deg (or phi_rad), and optionally profile ("flat", "sphere", "cone", "power") and exponent; flags override it
    #[arg(long, value_name = "FILE", help_heading = "Scene")]
    pub scene: Option<PathBuf>,
    /// Local coefficient of friction μ0 (> 0)
    #[arg(long, value_parser = domain::MU0, help_heading = "Scene")]
    pub mu0: Option<f64>,
    /// Normal contact stiffness k_z, N/m
    #[arg(long, value_parser = domain::KZ, help_heading = "Scene")]
    pub kz: Option<f64>,
    /// Tangential contact stiffness k_x, N/m
    #[arg(long, value_parser = domain::KX, help_heading = "Scene")]
    pub kx: Option<f64>,
    /// Mean indentation u_z0, m
    #[arg(long, value_parser = domain::UZ0, help_heading = "Scene")]
    pub uz0: Option<f64>,
    /// Normal oscillation amplitude Δu_z, m (≥ uz0: the contact lifts off once per period, where the command supports it)
    #[arg(long, value_parser = domain::DUZ, help_heading = "Scene")]
    pub duz: Option<f64>,
    /// Tangential oscillation amplitude Δu_x, m
    #[arg(long, value_parser = domain::DUX, help_heading = "Scene")]
    pub dux: Option<f64>,
    /// Drive frequency f, Hz
    #[arg(long, value_parser = domain::FREQ, help_heading = "Scene")]
    pub freq: Option<f64>,
    /// Drive angular frequency ω, rad/s (instead of --freq)
    #[arg(long, value_parser = domain::OMEGA, help_heading = "Scene")]
    pub omega: Option<f64>,
    /// Phase φ of the tangential oscillation, degrees (default 0)
    #[arg(long, value_parser = domain::PHI, help_heading = "Scene")]
    pub phi_deg: Option<f64>,
    /// Phase φ, radians (instead of --phi-deg)
    #[arg(long, value_parser = domain::PHI, help_heading = "Scene")]
    pub phi_rad: Option<f64>,
    /// Dimensionless: Δu_z/u_z0 (eq. 25; ≥ 1: lift-off); with the groups, μ0 = k_z = k_x = u_z0 = ω = 1 and --v0 is in units of ωW0 = ωμ0k_z u_z0/k_x
    #[arg(
        long,
        value_parser = domain::DUZ_REL,
        help_heading = "Scene (dimensionless, eq. 25/26)"
    )]
    pub duz_rel: Option<f64>,
    /// Dimensionless: k_xΔu_x/(μ0 k_z u_z0) (eq. 25)
    #[arg(
        long,
        value_parser = domain::DUX_REL,
        help_heading = "Scene (dimensionless, eq. 25/26)"
    )]
    pub dux_rel: Option<f64>,
    /// Dimensionless: k_xΔu_x/(μ0 k_z Δu_z) (eq. 26, instead of --dux-rel)
    #[arg(
        long,
        value_parser = domain::RATIO,
        help_heading = "Scene (dimensionless, eq. 25/26)"
    )]
    pub ratio: Option<f64>,
    #[command(flatten)]
    pub contact: ProfileArgs,
}

/// The contact's shape (`--profile`, `--exponent`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProfileKind {
    /// Flat-ended punch: the paper's single spring
    Flat,
    /// Sphere (paraboloid, n = 2), through MDR
    Sphere,
    /// Cone (n = 1), through MDR
    Cone,
    /// Power law f = c·rⁿ with --exponent n, through MDR
    Power,
}

/// `--profile` and `--exponent` (shared by the scene flags and `fricctl map`).
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct ProfileArgs {
    /// Contact profile (default flat). A curved profile is computed by the method of dimensionality reduction: uz0 is read as the mean indentation d0 and kz/kx as E*/G*
    #[arg(long, value_enum, help_heading = "Contact")]
    pub profile: Option<ProfileKind>,
    /// Exponent n of --profile power (f = c·rⁿ, n > 0; refused with the other profiles)
    #[arg(long, value_parser = domain::EXPONENT, help_heading = "Contact")]
    pub exponent: Option<f64>,
}

impl ProfileArgs {
    /// The library's input for these flags.
    pub fn input(&self) -> ProfileInput {
        ProfileInput {
            profile: self.profile.map(|k| match k {
                ProfileKind::Flat => lib::ProfileKind::Flat,
                ProfileKind::Sphere => lib::ProfileKind::Sphere,
                ProfileKind::Cone => lib::ProfileKind::Cone,
                ProfileKind::Power => lib::ProfileKind::Power,
            }),
            exponent: self.exponent,
        }
    }

    /// The profile from the flags alone.
    pub fn resolve(&self) -> CliResult<Profile<f64>> {
        self.input().resolve()
    }
}

/// The domain of every scene flag: the library's ([`lib::domain`]) as clap
/// value parsers.
pub mod domain {
    use crate::args::Real;
    use fric_analysis::scene::domain as lib;

    /// μ0 > 0.
    pub const MU0: Real = Real(lib::MU0);
    /// k_z > 0, N/m.
    pub const KZ: Real = Real(lib::KZ);
    /// k_x > 0, N/m.
    pub const KX: Real = Real(lib::KX);
    /// u_z0 > 0, m.
    pub const UZ0: Real = Real(lib::UZ0);
    /// Δu_z ≥ 0, m.
    pub const DUZ: Real = Real(lib::DUZ);
    /// Δu_x ≥ 0, m.
    pub const DUX: Real = Real(lib::DUX);
    /// f > 0, Hz.
    pub const FREQ: Real = Real(lib::FREQ);
    /// ω > 0, rad/s.
    pub const OMEGA: Real = Real(lib::OMEGA);
    /// φ, degrees or radians.
    pub const PHI: Real = Real(lib::PHI);
    /// Δu_z/u_z0 ≥ 0.
    pub const DUZ_REL: Real = Real(lib::DUZ_REL);
    /// k_xΔu_x/(μ0 k_z u_z0) ≥ 0.
    pub const DUX_REL: Real = Real(lib::DUX_REL);
    /// k_xΔu_x/(μ0 k_z Δu_z) ≥ 0.
    pub const RATIO: Real = Real(lib::RATIO);
    /// Power-law exponent n > 0.
    pub const EXPONENT: Real = Real(lib::EXPONENT);
}

impl SceneArgs {
    /// The library's input for these flags.
    pub fn input(&self) -> SceneInput {
        SceneInput {
            scene: self.scene.clone(),
            mu0: self.mu0,
            kz: self.kz,
            kx: self.kx,
            uz0: self.uz0,
            duz: self.duz,
            dux: self.dux,
            freq: self.freq,
            omega: self.omega,
            phi_deg: self.phi_deg,
            phi_rad: self.phi_rad,
            duz_rel: self.duz_rel,
            dux_rel: self.dux_rel,
            ratio: self.ratio,
            contact: self.contact.input(),
        }
    }

    /// Validates and builds the scene ([`SceneInput::resolve_with`]).
    pub fn resolve_with(&self, contact: ContactMode) -> CliResult<ResolvedScene> {
        self.input().resolve_with(contact)
    }
}
