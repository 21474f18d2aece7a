//! Scene input shared by every analysis: physical SI quantities, a TOML scene
//! file, or the paper's dimensionless groups, checked into a
//! `model_core::Scene` with one-line refusals naming the CLI flag that gave
//! each quantity (the CLI's `fricctl mu --mu0 …` and Python's
//! `fricctl.Scene(mu0=…)` read the same [`SceneInput`]).

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use model_core::mdr::Profile;
use model_core::scene::ContactMode;
use model_core::{Groups, Param, Scene, SceneError, SceneParams};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::numbers::{short, Real};

/// The scene as given: each field is the CLI flag of the same name
/// (`mu0` is `--mu0`, `phi_deg` is `--phi-deg`), `None` when not given.
/// Physical quantities in SI units; or the dimensionless groups of eqs. 25/26.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneInput {
    /// Scene file (TOML) with keys mu0, kz, kx, uz0, duz, dux, freq (or omega), phi_deg (or phi_rad), and optionally profile and exponent; the other fields override it.
    pub scene: Option<PathBuf>,
    /// Local coefficient of friction μ0 (> 0).
    pub mu0: Option<f64>,
    /// Normal contact stiffness k_z, N/m.
    pub kz: Option<f64>,
    /// Tangential contact stiffness k_x, N/m.
    pub kx: Option<f64>,
    /// Mean indentation u_z0, m.
    pub uz0: Option<f64>,
    /// Normal oscillation amplitude Δu_z, m (≥ uz0: the contact lifts off once per period).
    pub duz: Option<f64>,
    /// Tangential oscillation amplitude Δu_x, m.
    pub dux: Option<f64>,
    /// Drive frequency f, Hz.
    pub freq: Option<f64>,
    /// Drive angular frequency ω, rad/s (instead of `freq`).
    pub omega: Option<f64>,
    /// Phase φ of the tangential oscillation, degrees (default 0).
    pub phi_deg: Option<f64>,
    /// Phase φ, radians (instead of `phi_deg`).
    pub phi_rad: Option<f64>,
    /// Dimensionless Δu_z/u_z0 (eq. 25); with the groups μ0 = k_z = k_x = u_z0 = ω = 1.
    pub duz_rel: Option<f64>,
    /// Dimensionless k_xΔu_x/(μ0 k_z u_z0) (eq. 25).
    pub dux_rel: Option<f64>,
    /// Dimensionless k_xΔu_x/(μ0 k_z Δu_z) (eq. 26, instead of `dux_rel`).
    pub ratio: Option<f64>,
    /// The contact's shape.
    pub contact: ProfileInput,
}

/// The contact's shape (`--profile`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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

/// `--profile` and `--exponent`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ProfileInput {
    /// Contact profile (default flat). A curved profile is computed by the method of dimensionality reduction: uz0 is read as the mean indentation d0 and kz/kx as E*/G*.
    pub profile: Option<ProfileKind>,
    /// Exponent n of the power profile (f = c·rⁿ, n > 0; refused with the other profiles).
    pub exponent: Option<f64>,
}

impl ProfileInput {
    /// The profile from the flags, falling back on a scene file's `profile`
    /// and `exponent` keys (flags win).
    pub fn resolve_with_file(
        &self,
        file_profile: Option<&str>,
        file_exponent: Option<f64>,
    ) -> Result<Profile<f64>> {
        let from_file = match file_profile {
            Some(name) => Some(ProfileKind::from_name(name).ok_or_else(|| {
                Error::usage(format!(
                    "--scene: profile = \"{name}\" is not one of {}",
                    ProfileKind::NAMES.join(", ")
                ))
            })?),
            None => None,
        };
        if let Some(n) = self.exponent {
            check(domain::EXPONENT, n, "--exponent")?;
        }
        let kind = self.profile.or(from_file).unwrap_or(ProfileKind::Flat);
        // A flag exponent applies to the flag profile; the file's to the file's.
        let exponent = if self.profile.is_some() {
            self.exponent
        } else {
            self.exponent.or(file_exponent)
        };
        match (kind, exponent) {
            (ProfileKind::Power, None) => Err(Error::usage(
                "--exponent: missing (--profile power needs --exponent n > 0)",
            )),
            // In its domain: the flag's parser or the file's check.
            (ProfileKind::Power, Some(n)) => Ok(Profile::Power(n)),
            (k, Some(_)) => Err(Error::usage(format!(
                "--exponent: only with --profile power (the {} profile has {})",
                k.name(),
                match k {
                    ProfileKind::Sphere => "n = 2",
                    ProfileKind::Cone => "n = 1",
                    _ => "no exponent",
                }
            ))),
            (ProfileKind::Flat, None) => Ok(Profile::Flat),
            (ProfileKind::Sphere, None) => Ok(Profile::Sphere),
            (ProfileKind::Cone, None) => Ok(Profile::Cone),
        }
    }

    /// The profile from the flags alone.
    pub fn resolve(&self) -> Result<Profile<f64>> {
        self.resolve_with_file(None, None)
    }
}

impl ProfileKind {
    /// The kind named `name` (`flat`, `sphere`, `cone`, `power`; any case).
    pub fn from_name(name: &str) -> Option<ProfileKind> {
        [
            ProfileKind::Flat,
            ProfileKind::Sphere,
            ProfileKind::Cone,
            ProfileKind::Power,
        ]
        .into_iter()
        .find(|k| k.name().eq_ignore_ascii_case(name))
    }

    /// The kind a `--profile` value names, or the one-line refusal naming
    /// the flag and the values it takes (Python's `Scene(profile=…)`; the
    /// CLI's parser gives the same line).
    pub fn from_flag(name: &str) -> Result<ProfileKind> {
        ProfileKind::from_name(name).ok_or_else(|| {
            Error::usage(format!(
                "--profile: invalid value '{name}' (one of: {})",
                ProfileKind::NAMES.join(", ")
            ))
        })
    }

    /// Every kind's name, in the CLI's order.
    pub const NAMES: [&'static str; 4] = ["flat", "sphere", "cone", "power"];

    /// Its name, as the CLI's `--profile` value.
    pub fn name(self) -> &'static str {
        ProfileKind::NAMES[self as usize]
    }
}

/// What a profile prints: `flat`, `sphere (n = 2)`, `power (n = 3.5)`.
pub fn profile_text(p: &Profile<f64>) -> String {
    match p.exponent() {
        None => p.name().to_string(),
        Some(n) => format!("{} (n = {})", p.name(), short(n)),
    }
}

/// The domain of every scene input: one check shared by the flags (as their
/// value parsers) and the keys of a scene file ([`SceneInput::resolve_with`]),
/// on top of the magnitude every numeric input shares
/// ([`crate::numbers::MAX_MAGNITUDE`], [`crate::numbers::MIN_MAGNITUDE`]: no
/// subnormal and no absurdly large input). `model_core::Scene` then checks
/// what depends on several inputs (lift-off, the derived scales), and
/// [`check_reach`] the amplitudes the solvers resolve in `f64`.
pub mod domain {
    use crate::numbers::Real;

    /// μ0 > 0.
    pub const MU0: Real = Real::positive();
    /// k_z > 0, N/m.
    pub const KZ: Real = Real::positive();
    /// k_x > 0, N/m.
    pub const KX: Real = Real::positive();
    /// u_z0 > 0, m.
    pub const UZ0: Real = Real::positive();
    /// Δu_z ≥ 0, m.
    pub const DUZ: Real = Real::non_negative();
    /// Δu_x ≥ 0, m.
    pub const DUX: Real = Real::non_negative();
    /// f > 0, Hz.
    pub const FREQ: Real = Real::positive();
    /// ω > 0, rad/s.
    pub const OMEGA: Real = Real::positive();
    /// φ, degrees or radians (|φ| ≤ 10⁴ rad is checked with the unit).
    pub const PHI: Real = Real::ANY;
    /// Δu_z/u_z0 ≥ 0.
    pub const DUZ_REL: Real = Real::non_negative();
    /// k_xΔu_x/(μ0 k_z u_z0) ≥ 0.
    pub const DUX_REL: Real = Real::non_negative();
    /// k_xΔu_x/(μ0 k_z Δu_z) ≥ 0.
    pub const RATIO: Real = Real::non_negative();
    /// Power-law exponent n > 0.
    pub const EXPONENT: Real = Real::positive();
}

/// The scene file's keys.
#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    mu0: Option<f64>,
    kz: Option<f64>,
    kx: Option<f64>,
    uz0: Option<f64>,
    duz: Option<f64>,
    dux: Option<f64>,
    freq: Option<f64>,
    omega: Option<f64>,
    phi_deg: Option<f64>,
    phi_rad: Option<f64>,
    profile: Option<String>,
    exponent: Option<f64>,
}

impl SceneFile {
    /// Reads and checks a scene file: every key in its [`domain`] (the
    /// flags' own check), refusals naming `--scene`, the file and the key.
    fn read(p: &Path) -> Result<SceneFile> {
        if p.is_dir() {
            return Err(Error::usage(format!(
                "--scene: {} is a directory",
                p.display()
            )));
        }
        let text = std::fs::read_to_string(p)
            .map_err(|e| Error::usage(format!("--scene: cannot read {}: {e}", p.display())))?;
        let f = toml::from_str::<SceneFile>(&text).map_err(|e| {
            let m = e.message().replace('\n', " ");
            Error::usage(format!("--scene: {}: {}", p.display(), m.trim()))
        })?;
        for (key, x, d) in [
            ("mu0", f.mu0, domain::MU0),
            ("kz", f.kz, domain::KZ),
            ("kx", f.kx, domain::KX),
            ("uz0", f.uz0, domain::UZ0),
            ("duz", f.duz, domain::DUZ),
            ("dux", f.dux, domain::DUX),
            ("freq", f.freq, domain::FREQ),
            ("omega", f.omega, domain::OMEGA),
            ("phi_deg", f.phi_deg, domain::PHI),
            ("phi_rad", f.phi_rad, domain::PHI),
            ("exponent", f.exponent, domain::EXPONENT),
        ] {
            if let Some(x) = x {
                d.check(x, &short(x))
                    .map_err(|r| Error::usage(format!("--scene: {}: {key} {r}", p.display())))?;
            }
        }
        Ok(f)
    }
}

/// Which flag gave each scene quantity (`--duz`, `--duz-rel`, `--scene`, …),
/// so that an error names a flag the user gave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Given {
    /// μ0.
    pub mu0: &'static str,
    /// k_z.
    pub kz: &'static str,
    /// k_x.
    pub kx: &'static str,
    /// u_z0.
    pub uz0: &'static str,
    /// Δu_z (`--duz`, `--duz-rel` or `--scene`).
    pub duz: &'static str,
    /// Δu_x (`--dux`, `--dux-rel`, `--ratio` or `--scene`).
    pub dux: &'static str,
    /// ω (`--freq`, `--omega` or `--scene`).
    pub omega: &'static str,
    /// φ (`--phi-deg`, `--phi-rad`, `--scene`, or the default 0: `--phi-deg`).
    pub phi: &'static str,
}

impl Given {
    /// The flag that gave parameter `p` (a velocity: `--v0`).
    pub fn flag(&self, p: Param) -> &'static str {
        match p {
            Param::Mu0 => self.mu0,
            Param::Kz => self.kz,
            Param::Kx => self.kx,
            Param::Uz0 => self.uz0,
            Param::Duz | Param::DuzRel => self.duz,
            Param::Dux | Param::DuxRel | Param::Ratio => self.dux,
            Param::Omega => self.omega,
            Param::Phi => self.phi,
            Param::Velocity => "--v0",
        }
    }

    /// The one-line usage error of a scene refusal, naming the flag that
    /// gave the parameter (for a scene file: `--scene` and the key).
    pub fn error(&self, e: SceneError) -> Error {
        let p = match e {
            SceneError::NonFinite(p)
            | SceneError::NotPositive(p)
            | SceneError::Negative(p)
            | SceneError::OutOfRange(p) => p,
            SceneError::LiftOff => Param::Duz,
            SceneError::RatioNeedsNormalAmplitude => Param::Ratio,
        };
        let flag = self.flag(p);
        let what = match e {
            SceneError::NonFinite(_) => "must be a finite number".to_string(),
            SceneError::NotPositive(_) => "must be > 0".to_string(),
            SceneError::Negative(_) => "must be ≥ 0".to_string(),
            SceneError::LiftOff if flag == "--duz-rel" => {
                "must be < 1 for this command (Δu_z ≥ u_z0 lifts the contact off the plane)"
                    .to_string()
            }
            SceneError::LiftOff => {
                "must be < uz0 for this command (the normal oscillation would lift the contact off the plane)"
                    .to_string()
            }
            SceneError::RatioNeedsNormalAmplitude => {
                "needs --duz-rel > 0 (it is kx·dux/(mu0·kz·duz))".to_string()
            }
            SceneError::OutOfRange(Param::Velocity) => {
                "v0/(ωW0) over- or underflows the number type with this scene".to_string()
            }
            SceneError::OutOfRange(_) => {
                "with the other inputs the scene's derived scales (W0 = μ0·kz·uz0/kx, ωW0, the groups) over- or underflow the number type".to_string()
            }
        };
        if flag == "--scene" {
            Error::usage(format!("--scene: {}: {what}", p.name()))
        } else {
            Error::usage(format!("{flag}: {what}"))
        }
    }

    /// The flags of a dimensionless scene (`--duz-rel` with `--dux-rel` or
    /// `--ratio`); the unit quantities are named by `--duz-rel`.
    fn dimensionless(ratio: bool, phi: &'static str) -> Given {
        Given {
            mu0: "--duz-rel",
            kz: "--duz-rel",
            kx: "--duz-rel",
            uz0: "--duz-rel",
            duz: "--duz-rel",
            dux: if ratio { "--ratio" } else { "--dux-rel" },
            omega: "--duz-rel",
            phi,
        }
    }
}

/// A validated scene and how it was given.
#[derive(Debug, Clone, Copy)]
pub struct ResolvedScene {
    /// The scene (in dimensionless mode: μ0 = k_z = k_x = u_z0 = ω = 1).
    pub scene: Scene<f64>,
    /// Given by dimensionless groups: velocities are in units of ωW0 and must be
    /// given relative to v_c.
    pub dimensionless: bool,
    /// The contact's shape (`--profile`; flat unless asked). With a curved
    /// profile the scene's u_z0 is the mean indentation d0 and k_z/k_x is E*/G*
    /// (`model_core::mdr`); `select::mu_within_profile` computes μ for it.
    pub profile: Profile<f64>,
    /// Which flag gave each quantity (for errors).
    pub given: Given,
}

impl ResolvedScene {
    /// The dimensionless velocity `v0/(ωW0)` of a velocity given by `flag`,
    /// refused by name when it over- or underflows.
    ///
    /// # Errors
    /// One line naming `flag`.
    pub fn velocity(&self, v0: f64, flag: &str) -> Result<f64> {
        self.scene.dimensionless_velocity(v0).map_err(|_| {
            Error::usage(format!(
                "{flag}: {} over the scene's velocity scale ωW0 = {} over- or underflows the number type",
                short(v0),
                short(self.scene.velocity_scale())
            ))
        })
    }
}

/// Largest `1 + b` (`1 + a + b` with lift-off) the solvers resolve in `f64`:
/// beyond it their precision part of the error bound exceeds 1 % of μ0 and
/// they refuse the drive as ill-conditioned (`exact::ILL_CONDITIONED_AT`).
pub fn reach_limit() -> f64 {
    model_core::exact::ILL_CONDITIONED_AT / model_core::exact::precision_constant::<f64>()
}

/// Refuses, naming the flag that gave it, a drive whose amplitudes the
/// solvers cannot resolve in `f64` ([`reach_limit`]): `a` = Δu_z/u_z0 given
/// by `flag_a`, `b` = k_xΔu_x/(μ0 k_z u_z0) given by `flag_b`.
///
/// # Errors
/// One line naming the flag of the amplitude that is too large.
pub fn check_reach(a: f64, b: f64, flag_a: &str, flag_b: &str) -> Result {
    let limit = reach_limit();
    let a_part = if a >= 1.0 { a } else { 0.0 };
    if 1.0 + a_part + b <= limit {
        return Ok(());
    }
    let (flag, what, x) = if b >= a_part {
        (flag_b, "kx·dux/(mu0·kz·uz0)", b)
    } else {
        (flag_a, "duz/uz0", a)
    };
    let flag = if flag == "--scene" {
        format!("--scene: {}", if b >= a_part { "dux" } else { "duz" })
    } else {
        flag.to_string()
    };
    Err(Error::usage(format!(
        "{flag}: gives {what} = {x:.3e}; the solvers resolve 1 + duz/uz0 + kx·dux/(mu0·kz·uz0) ≤ {} in f64 (beyond, their error bound exceeds 1 % of mu0)",
        short(limit)
    )))
}

impl SceneInput {
    /// Validates and builds a permanent-contact flat-punch scene
    /// (`Δu_z < u_z0`, the paper's assumption): for commands whose analysis
    /// needs it. A curved `--profile` is refused (one line naming it) rather
    /// than ignored; commands that handle profiles call [`SceneInput::resolve_with`].
    pub fn resolve(&self) -> Result<ResolvedScene> {
        let rs = self.resolve_with(ContactMode::Permanent)?;
        if rs.profile != Profile::Flat {
            return Err(Error::usage(format!(
                "--profile: this command computes the flat punch only (got {})",
                rs.profile.name()
            )));
        }
        Ok(rs)
    }

    /// Validates and builds the scene; [`ContactMode::Intermittent`] accepts
    /// `Δu_z ≥ u_z0` (the contact lifts off once per period,
    /// `model_core::model::liftoff`).
    pub fn resolve_with(&self, contact: ContactMode) -> Result<ResolvedScene> {
        self.check_domains()?;
        let dimless = self.duz_rel.is_some() || self.dux_rel.is_some() || self.ratio.is_some();
        let rs = if dimless {
            self.resolve_dimensionless(contact)?
        } else {
            self.resolve_physical(contact)?
        };
        let d = rs.scene.drive();
        check_reach(d.a, d.b, rs.given.duz, rs.given.dux)?;
        Ok(rs)
    }

    /// Every given quantity in its [`domain`], refused as the CLI's flag
    /// parser refuses it (`--mu0: must be > 0 (got -1)`).
    fn check_domains(&self) -> Result {
        for (flag, x, d) in [
            ("--mu0", self.mu0, domain::MU0),
            ("--kz", self.kz, domain::KZ),
            ("--kx", self.kx, domain::KX),
            ("--uz0", self.uz0, domain::UZ0),
            ("--duz", self.duz, domain::DUZ),
            ("--dux", self.dux, domain::DUX),
            ("--freq", self.freq, domain::FREQ),
            ("--omega", self.omega, domain::OMEGA),
            ("--phi-deg", self.phi_deg, domain::PHI),
            ("--phi-rad", self.phi_rad, domain::PHI),
            ("--duz-rel", self.duz_rel, domain::DUZ_REL),
            ("--dux-rel", self.dux_rel, domain::DUX_REL),
            ("--ratio", self.ratio, domain::RATIO),
            ("--exponent", self.contact.exponent, domain::EXPONENT),
        ] {
            if let Some(x) = x {
                check(d, x, flag)?;
            }
        }
        Ok(())
    }

    fn resolve_physical(&self, contact: ContactMode) -> Result<ResolvedScene> {
        let file = match &self.scene {
            Some(p) => SceneFile::read(p)?,
            None => SceneFile::default(),
        };
        // A flag beats the file.
        let pick = |flag: Option<f64>, file: Option<f64>, name: &'static str| match (flag, file) {
            (Some(x), _) => Ok((x, name)),
            (None, Some(x)) => Ok((x, "--scene")),
            (None, None) => Err(Error::usage(format!(
                "{name}: missing (give it as a flag or in --scene FILE)"
            ))),
        };
        let (mu0, mu0_by) = pick(self.mu0, file.mu0, "--mu0")?;
        let (kz, kz_by) = pick(self.kz, file.kz, "--kz")?;
        let (kx, kx_by) = pick(self.kx, file.kx, "--kx")?;
        let (uz0, uz0_by) = pick(self.uz0, file.uz0, "--uz0")?;
        let (duz, duz_by) = pick(self.duz, file.duz, "--duz")?;
        let (dux, dux_by) = pick(self.dux, file.dux, "--dux")?;
        // Frequency: a flag beats the file; two flags conflict.
        if self.freq.is_some() && self.omega.is_some() {
            return Err(Error::usage(
                "--omega: give either --freq or --omega, not both",
            ));
        }
        let (omega, omega_by) = match (self.freq, self.omega, file.freq, file.omega) {
            (Some(f), None, _, _) => (TAU * f, "--freq"),
            (None, Some(w), _, _) => (w, "--omega"),
            (None, None, Some(_), Some(_)) => {
                return Err(Error::usage(
                    "--scene: give either freq or omega in the file, not both",
                ))
            }
            (None, None, Some(f), None) => (TAU * f, "--scene"),
            (None, None, None, Some(w)) => (w, "--scene"),
            _ => {
                return Err(Error::usage(
                    "--freq: missing (give --freq <Hz> or --omega <rad/s>)",
                ))
            }
        };
        let (phi, phi_by) = self.phi(file.phi_deg, file.phi_rad)?;
        let given = Given {
            mu0: mu0_by,
            kz: kz_by,
            kx: kx_by,
            uz0: uz0_by,
            duz: duz_by,
            dux: dux_by,
            omega: omega_by,
            phi: phi_by,
        };
        let scene = Scene::new_with_contact(
            SceneParams {
                mu0,
                kz,
                kx,
                uz0,
                duz,
                dux,
                omega,
                phi,
            },
            contact,
        )
        .map_err(|e| given.error(e))?;
        let exponent_by = if self.contact.exponent.is_some() {
            "--exponent"
        } else {
            "--scene"
        };
        let profile = self
            .contact
            .resolve_with_file(file.profile.as_deref(), file.exponent)?;
        checked_reach(
            ResolvedScene {
                scene,
                dimensionless: false,
                profile,
                given,
            },
            exponent_by,
        )
    }

    /// φ in radians from the flags or the file, and the flag that gave it.
    fn phi(&self, file_deg: Option<f64>, file_rad: Option<f64>) -> Result<(f64, &'static str)> {
        if self.phi_deg.is_some() && self.phi_rad.is_some() {
            return Err(Error::usage(
                "--phi-rad: give either --phi-deg or --phi-rad, not both",
            ));
        }
        let (phi, by) = match (self.phi_deg, self.phi_rad, file_deg, file_rad) {
            (Some(d), None, _, _) => (d.to_radians(), "--phi-deg"),
            (None, Some(r), _, _) => (r, "--phi-rad"),
            (None, None, Some(_), Some(_)) => {
                return Err(Error::usage(
                    "--scene: give either phi_deg or phi_rad in the file, not both",
                ))
            }
            (None, None, Some(d), None) => (d.to_radians(), "--scene"),
            (None, None, None, Some(r)) => (r, "--scene"),
            // The default names the flag that would change it.
            _ => (0.0, "--phi-deg"),
        };
        // An angle of a few thousand turns is certainly a mistake, and far
        // beyond it the angle's low digits are lost.
        if phi.abs() > 1e4 {
            return Err(Error::usage(format!(
                "{by}: |φ| = {:.3e} rad is beyond 10⁴ rad (≈ 1600 turns); give the phase within a turn",
                phi.abs()
            )));
        }
        Ok((phi, by))
    }

    fn resolve_dimensionless(&self, contact: ContactMode) -> Result<ResolvedScene> {
        let physical = [
            (self.scene.is_some(), "scene"),
            (self.mu0.is_some(), "mu0"),
            (self.kz.is_some(), "kz"),
            (self.kx.is_some(), "kx"),
            (self.uz0.is_some(), "uz0"),
            (self.duz.is_some(), "duz"),
            (self.dux.is_some(), "dux"),
            (self.freq.is_some(), "freq"),
            (self.omega.is_some(), "omega"),
        ];
        if let Some((_, name)) = physical.iter().find(|(set, _)| *set) {
            return Err(Error::usage(format!(
                "--{name}: cannot be combined with the dimensionless groups (--duz-rel/--dux-rel/--ratio)"
            )));
        }
        let a = self
            .duz_rel
            .ok_or_else(|| Error::usage("--duz-rel: missing (needed with --dux-rel or --ratio)"))?;
        let (phi, phi_by) = self.phi(None, None)?;
        let given = Given::dimensionless(self.ratio.is_some(), phi_by);
        let groups = match (self.dux_rel, self.ratio) {
            (Some(_), Some(_)) => {
                return Err(Error::usage(
                    "--ratio: give either --dux-rel or --ratio, not both",
                ))
            }
            (Some(b), None) => Groups {
                duz_rel: a,
                dux_rel: b,
                phi,
            },
            (None, Some(r)) => ratio_groups(a, r, phi, contact).map_err(|e| given.error(e))?,
            (None, None) => {
                return Err(Error::usage(
                    "--dux-rel: missing (give --dux-rel or --ratio)",
                ))
            }
        };
        let scene =
            Scene::dimensionless_with_contact(groups, contact).map_err(|e| given.error(e))?;
        checked_reach(
            ResolvedScene {
                scene,
                dimensionless: true,
                profile: self.contact.resolve()?,
                given,
            },
            "--exponent",
        )
    }
}

/// `x` in the domain `d`, refused as `flag: reason` (the CLI's text for a
/// flag's value).
///
/// # Errors
/// One line naming `flag`.
pub fn check(d: Real, x: f64, flag: &str) -> Result<f64> {
    d.check(x, &short(x))
        .map_err(|r| Error::usage(format!("{flag}: {r}")))
}

/// Refuses a power-law exponent so small that the springs' reach
/// `(1 + a)^{1/n}` (the widest ξ that ever touches, `mdr`) is not a
/// representable number for this drive; `flag` gave the exponent.
fn checked_reach(rs: ResolvedScene, flag: &str) -> Result<ResolvedScene> {
    if let Some(n) = rs.profile.exponent() {
        let a = rs.scene.drive().a;
        let reach = (1.0 + a).powf(1.0 / n);
        if !(reach.is_finite() && reach < 1e100) {
            let flag = if flag == "--scene" {
                "--scene: exponent"
            } else {
                flag
            };
            return Err(Error::usage(format!(
                "{flag}: n = {} is too small for Δu_z/u_z0 = {}: the springs' reach (1 + a)^(1/n) overflows (use n ≥ {:.3e})",
                short(n),
                short(a),
                (1.0 + a).ln() / 1e100f64.ln()
            )));
        }
    }
    Ok(rs)
}

/// The groups of eq. 26 (`b = ratio·a`) for a contact mode: `Groups::from_ratio`
/// checks them for permanent contact, so with lift-off the product is formed
/// here and checked by the scene.
fn ratio_groups(a: f64, r: f64, phi: f64, contact: ContactMode) -> Result<Groups<f64>, SceneError> {
    if contact == ContactMode::Permanent || a < 1.0 {
        return Groups::from_ratio(a, r, phi);
    }
    Ok(Groups {
        duz_rel: a,
        dux_rel: r * a,
        phi,
    })
}
