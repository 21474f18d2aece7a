//! Scene input shared by every model command: physical SI flags, a TOML scene
//! file, or the paper's dimensionless groups.

use std::f64::consts::TAU;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use model_core::mdr::Profile;
use model_core::scene::ContactMode;
use model_core::{Groups, Scene, SceneParams};
use serde::Deserialize;

use crate::error::{CliError, CliResult};

/// Scene flags (see `fricctl --help`).
#[derive(Args, Debug, Clone, Default)]
pub struct SceneArgs {
    /// Scene file (TOML) with keys mu0, kz, kx, uz0, duz, dux, freq (or omega), phi_deg (or phi_rad), and optionally profile ("flat", "sphere", "cone", "power") and exponent; flags override it
    #[arg(long, value_name = "FILE", help_heading = "Scene")]
    pub scene: Option<PathBuf>,
    /// Local coefficient of friction μ0 (> 0)
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub mu0: Option<f64>,
    /// Normal contact stiffness k_z, N/m
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub kz: Option<f64>,
    /// Tangential contact stiffness k_x, N/m
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub kx: Option<f64>,
    /// Mean indentation u_z0, m
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub uz0: Option<f64>,
    /// Normal oscillation amplitude Δu_z, m (≥ uz0: the contact lifts off once per period, where the command supports it)
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub duz: Option<f64>,
    /// Tangential oscillation amplitude Δu_x, m
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub dux: Option<f64>,
    /// Drive frequency f, Hz
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub freq: Option<f64>,
    /// Drive angular frequency ω, rad/s (instead of --freq)
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub omega: Option<f64>,
    /// Phase φ of the tangential oscillation, degrees (default 0)
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub phi_deg: Option<f64>,
    /// Phase φ, radians (instead of --phi-deg)
    #[arg(long, allow_hyphen_values = true, help_heading = "Scene")]
    pub phi_rad: Option<f64>,
    /// Dimensionless: Δu_z/u_z0 (eq. 25; ≥ 1: lift-off); with the groups, μ0 = k_z = k_x = u_z0 = ω = 1 and --v0 is in units of ωW0 = ωμ0k_z u_z0/k_x
    #[arg(
        long,
        allow_hyphen_values = true,
        help_heading = "Scene (dimensionless, eq. 25/26)"
    )]
    pub duz_rel: Option<f64>,
    /// Dimensionless: k_xΔu_x/(μ0 k_z u_z0) (eq. 25)
    #[arg(
        long,
        allow_hyphen_values = true,
        help_heading = "Scene (dimensionless, eq. 25/26)"
    )]
    pub dux_rel: Option<f64>,
    /// Dimensionless: k_xΔu_x/(μ0 k_z Δu_z) (eq. 26, instead of --dux-rel)
    #[arg(
        long,
        allow_hyphen_values = true,
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
    #[arg(long, allow_hyphen_values = true, help_heading = "Contact")]
    pub exponent: Option<f64>,
}

impl ProfileArgs {
    /// The profile from the flags, falling back on a scene file's `profile`
    /// and `exponent` keys (flags win).
    pub fn resolve_with_file(
        &self,
        file_profile: Option<&str>,
        file_exponent: Option<f64>,
    ) -> CliResult<Profile<f64>> {
        let from_file = match file_profile {
            Some(name) => Some(ProfileKind::from_str(name, true).map_err(|_| {
                CliError::usage(format!(
                    "--scene: profile = \"{name}\" is not one of flat, sphere, cone, power"
                ))
            })?),
            None => None,
        };
        let kind = self.profile.or(from_file).unwrap_or(ProfileKind::Flat);
        // A flag exponent applies to the flag profile; the file's to the file's.
        let exponent = if self.profile.is_some() {
            self.exponent
        } else {
            self.exponent.or(file_exponent)
        };
        match (kind, exponent) {
            (ProfileKind::Power, None) => Err(CliError::usage(
                "--exponent: missing (--profile power needs --exponent n > 0)",
            )),
            (ProfileKind::Power, Some(n)) => {
                if !(n.is_finite() && n > 0.0) {
                    return Err(CliError::usage("--exponent: must be a finite number > 0"));
                }
                Ok(Profile::Power(n))
            }
            (k, Some(_)) => Err(CliError::usage(format!(
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
    pub fn resolve(&self) -> CliResult<Profile<f64>> {
        self.resolve_with_file(None, None)
    }
}

impl ProfileKind {
    fn name(self) -> &'static str {
        match self {
            ProfileKind::Flat => "flat",
            ProfileKind::Sphere => "sphere",
            ProfileKind::Cone => "cone",
            ProfileKind::Power => "power",
        }
    }
}

/// What a profile prints: `flat`, `sphere (n = 2)`, `power (n = 3.5)`.
pub fn profile_text(p: &Profile<f64>) -> String {
    match p.exponent() {
        None => p.name().to_string(),
        Some(n) => format!("{} (n = {n})", p.name()),
    }
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
}

fn scene_err(e: model_core::SceneError) -> CliError {
    CliError::usage(format!("--{e}"))
}

impl SceneArgs {
    /// Validates and builds a permanent-contact flat-punch scene
    /// (`Δu_z < u_z0`, the paper's assumption): for commands whose analysis
    /// needs it. A curved `--profile` is refused (one line naming it) rather
    /// than ignored; commands that handle profiles call [`SceneArgs::resolve_with`].
    pub fn resolve(&self) -> CliResult<ResolvedScene> {
        let rs = self.resolve_with(ContactMode::Permanent)?;
        if rs.profile != Profile::Flat {
            return Err(CliError::usage(format!(
                "--profile: this command computes the flat punch only (got {})",
                rs.profile.name()
            )));
        }
        Ok(rs)
    }

    /// Validates and builds the scene; [`ContactMode::Intermittent`] accepts
    /// `Δu_z ≥ u_z0` (the contact lifts off once per period,
    /// `model_core::model::liftoff`).
    pub fn resolve_with(&self, contact: ContactMode) -> CliResult<ResolvedScene> {
        let dimless = self.duz_rel.is_some() || self.dux_rel.is_some() || self.ratio.is_some();
        if dimless {
            return self.resolve_dimensionless(contact);
        }
        let file = match &self.scene {
            Some(p) => {
                let text = std::fs::read_to_string(p).map_err(|e| {
                    CliError::usage(format!("--scene: cannot read {}: {e}", p.display()))
                })?;
                toml::from_str::<SceneFile>(&text).map_err(|e| {
                    let m = e.message().replace('\n', " ");
                    CliError::usage(format!("--scene: {}: {}", p.display(), m.trim()))
                })?
            }
            None => SceneFile::default(),
        };
        let pick = |flag: Option<f64>, file: Option<f64>| flag.or(file);
        let need = |v: Option<f64>, name: &str| {
            v.ok_or_else(|| {
                CliError::usage(format!(
                    "--{name}: missing (give it as a flag or in --scene FILE)"
                ))
            })
        };
        let mu0 = need(pick(self.mu0, file.mu0), "mu0")?;
        let kz = need(pick(self.kz, file.kz), "kz")?;
        let kx = need(pick(self.kx, file.kx), "kx")?;
        let uz0 = need(pick(self.uz0, file.uz0), "uz0")?;
        let duz = need(pick(self.duz, file.duz), "duz")?;
        let dux = need(pick(self.dux, file.dux), "dux")?;
        // Frequency: a flag beats the file; two flags conflict.
        if self.freq.is_some() && self.omega.is_some() {
            return Err(CliError::usage(
                "--omega: give either --freq or --omega, not both",
            ));
        }
        let omega = match (self.freq, self.omega, file.freq, file.omega) {
            (Some(f), None, _, _) => freq_to_omega(f)?,
            (None, Some(w), _, _) => w,
            (None, None, Some(_), Some(_)) => {
                return Err(CliError::usage(
                    "--scene: give either freq or omega in the file, not both",
                ))
            }
            (None, None, Some(f), None) => freq_to_omega(f)?,
            (None, None, None, Some(w)) => w,
            _ => {
                return Err(CliError::usage(
                    "--freq: missing (give --freq <Hz> or --omega <rad/s>)",
                ))
            }
        };
        let phi = self.phi(file.phi_deg, file.phi_rad)?;
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
        .map_err(scene_err)?;
        let profile = self
            .contact
            .resolve_with_file(file.profile.as_deref(), file.exponent)?;
        checked_reach(ResolvedScene {
            scene,
            dimensionless: false,
            profile,
        })
    }

    fn phi(&self, file_deg: Option<f64>, file_rad: Option<f64>) -> CliResult<f64> {
        if self.phi_deg.is_some() && self.phi_rad.is_some() {
            return Err(CliError::usage(
                "--phi-rad: give either --phi-deg or --phi-rad, not both",
            ));
        }
        let phi = match (self.phi_deg, self.phi_rad, file_deg, file_rad) {
            (Some(d), None, _, _) => finite(d, "phi-deg")?.to_radians(),
            (None, Some(r), _, _) => finite(r, "phi-rad")?,
            (None, None, Some(_), Some(_)) => {
                return Err(CliError::usage(
                    "--scene: give either phi_deg or phi_rad in the file, not both",
                ))
            }
            (None, None, Some(d), None) => finite(d, "phi-deg")?.to_radians(),
            (None, None, None, Some(r)) => finite(r, "phi-rad")?,
            _ => 0.0,
        };
        // An angle of a few thousand turns is certainly a mistake, and far
        // beyond it the angle's low digits are lost.
        if phi.abs() > 1e4 {
            let name = if self.phi_rad.is_some() || (self.phi_deg.is_none() && file_rad.is_some()) {
                "phi-rad"
            } else {
                "phi-deg"
            };
            return Err(CliError::usage(format!(
                "--{name}: |φ| = {:.3e} rad is beyond 10⁴ rad (≈ 1600 turns); give the phase within a turn",
                phi.abs()
            )));
        }
        Ok(phi)
    }

    fn resolve_dimensionless(&self, contact: ContactMode) -> CliResult<ResolvedScene> {
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
            return Err(CliError::usage(format!(
                "--{name}: cannot be combined with the dimensionless groups (--duz-rel/--dux-rel/--ratio)"
            )));
        }
        let a = self.duz_rel.ok_or_else(|| {
            CliError::usage("--duz-rel: missing (needed with --dux-rel or --ratio)")
        })?;
        let phi = self.phi(None, None)?;
        let groups = match (self.dux_rel, self.ratio) {
            (Some(_), Some(_)) => {
                return Err(CliError::usage(
                    "--ratio: give either --dux-rel or --ratio, not both",
                ))
            }
            (Some(b), None) => Groups {
                duz_rel: a,
                dux_rel: b,
                phi,
            },
            (None, Some(r)) => ratio_groups(a, r, phi, contact)?,
            (None, None) => {
                return Err(CliError::usage(
                    "--dux-rel: missing (give --dux-rel or --ratio)",
                ))
            }
        };
        let scene = Scene::dimensionless_with_contact(groups, contact).map_err(scene_err)?;
        checked_reach(ResolvedScene {
            scene,
            dimensionless: true,
            profile: self.contact.resolve()?,
        })
    }
}

/// Refuses a power-law exponent so small that the springs' reach
/// `(1 + a)^{1/n}` (the widest ξ that ever touches, `mdr`) is not a
/// representable number for this drive.
fn checked_reach(rs: ResolvedScene) -> CliResult<ResolvedScene> {
    if let Some(n) = rs.profile.exponent() {
        let a = rs.scene.drive().a;
        let reach = (1.0 + a).powf(1.0 / n);
        if !(reach.is_finite() && reach < 1e100) {
            return Err(CliError::usage(format!(
                "--exponent: n = {n:e} is too small for Δu_z/u_z0 = {a}: the springs' reach (1 + a)^(1/n) overflows (use n ≥ {:.3e})",
                (1.0 + a).ln() / 1e100f64.ln()
            )));
        }
    }
    Ok(rs)
}

/// The groups of eq. 26 (`b = ratio·a`) for a contact mode: `Groups::from_ratio`
/// checks them for permanent contact, so with lift-off the product is formed
/// here and checked by the scene.
fn ratio_groups(a: f64, r: f64, phi: f64, contact: ContactMode) -> CliResult<Groups<f64>> {
    if contact == ContactMode::Permanent || a < 1.0 {
        return Groups::from_ratio(a, r, phi).map_err(scene_err);
    }
    if !r.is_finite() {
        return Err(CliError::usage("--ratio: must be a finite number"));
    }
    if r < 0.0 {
        return Err(CliError::usage("--ratio: must be >= 0"));
    }
    Ok(Groups {
        duz_rel: a,
        dux_rel: r * a,
        phi,
    })
}

fn finite(x: f64, name: &str) -> CliResult<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(CliError::usage(format!(
            "--{name}: must be a finite number"
        )))
    }
}

fn freq_to_omega(f: f64) -> CliResult<f64> {
    if !f.is_finite() {
        return Err(CliError::usage("--freq: must be a finite number"));
    }
    if f <= 0.0 {
        return Err(CliError::usage("--freq: must be > 0"));
    }
    Ok(TAU * f)
}
