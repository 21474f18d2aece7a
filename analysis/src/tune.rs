//! Inverse design — the drive value (Δu_z, Δu_x or φ) that attains a target
//! μ at a sliding velocity, or that maximises the ratchet's asymmetry or the
//! forward stall force, within stated limits (model-core `model::inverse`);
//! the computation of `fricctl tune` and `fricctl.tune`.
//!
//! Search: the exact law on a scan of [`SCAN_CELLS`] cells of the adjusted
//! quantity, every local extremum refined by golden section, Illinois regula
//! falsi on each monotone piece that straddles the target. All solutions are
//! listed; the one nearest the scene's own value of the adjusted quantity is
//! reported as *the* result (the scene value is only that starting point).
//!
//! A curved profile (`--profile sphere|cone|power`) runs the same search on
//! its MDR quadrature (`model_core::mdr`; docs/guide/lift-off-and-profiles.md):
//! μ at each knob value to the tolerance [`crate::eval::profile_tol`] of that
//! drive, which is then the stated bound (the quadrature's estimate is within
//! it); the objectives from the same definitions as `fricctl static` and
//! `fricctl classify` ([`crate::eval::profile_statics`],
//! [`crate::eval::classify_scene_profile`]). The lift-off margin keeps the
//! centre of the contact pressed (`Δu_z ≤ (1 − m)·d₀`); the rim of a curved
//! contact lifts off at any drive.

use model_core::analytic::StaticFriction;
use model_core::exact;
use model_core::mdr::{self, Profile};
use model_core::model::inverse::{self, InverseError, Knob, Objective, Point, Problem};
use model_core::regime::{classify_drive, ClassifyOptions, Regime};
use model_core::{Drive, Libm, Scene};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::eval::{
    classify_scene_profile, critical_velocity, exact_failure, from_rel, mdr_failure,
    profile_statics, profile_tol_of, profile_tol_of_at_rest,
};
use crate::numbers::{short, Real};
use crate::scene::{check, check_reach, ResolvedScene};

/// Cells of the scan of the adjusted quantity (the phase: 360°/256 = 1.41° per cell).
pub const SCAN_CELLS: usize = 256;

/// Default largest Δu_x in units of W0 = μ0 k_z u_z0/k_x (`k_xΔu_x/(μ0k_z u_z0) ≤ 10`).
pub const DEFAULT_MAX_DUX_REL: f64 = 10.0;

/// Default lift-off margin m: every drive keeps Δu_z ≤ (1 − m)·u_z0.
pub const DEFAULT_LIFTOFF_MARGIN: f64 = 0.05;

/// The domain of a target μ/μ0 (the CLI's `--target-mu-rel`).
pub const TARGET_MU_REL: Real = Real::ANY
    .above(-1.0)
    .below(1.0)
    .because("mu/mu0 lies strictly inside (−1, 1): |mu| = mu0 is continuous sliding");

/// The domain of the lift-off margin (the CLI's `--liftoff-margin`).
pub const LIFTOFF_MARGIN: Real = Real::ANY.above(0.0).below(1.0);

/// The adjusted drive quantity (the CLI's `--adjust`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Adjust {
    /// Normal amplitude Δu_z, from 0 to `max_duz`.
    Duz,
    /// Tangential amplitude Δu_x, from 0 to `max_dux`.
    Dux,
    /// Phase φ, over [0°, 360°).
    Phase,
}

impl Adjust {
    /// The quantity named `name` (`duz`, `dux`, `phase`).
    ///
    /// # Errors
    /// `--adjust: invalid value '…' (one of: duz, dux, phase)`.
    pub fn from_name(name: &str) -> Result<Adjust> {
        match name {
            "duz" => Ok(Adjust::Duz),
            "dux" => Ok(Adjust::Dux),
            "phase" => Ok(Adjust::Phase),
            _ => Err(Error::usage(format!(
                "--adjust: invalid value '{name}' (one of: duz, dux, phase)"
            ))),
        }
    }
}

/// What a maximisation maximises (the CLI's `--maximize`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Maximize {
    /// Ratchet asymmetry max|μ(v)+μ(−v)|/μ0, over the drives that are not actuators.
    Asymmetry,
    /// Forward stall force −μ(0⁺)/μ0, units of μ0·kz·uz0.
    StallForce,
}

impl Maximize {
    /// The objective named `name` (`asymmetry`, `stall-force`; `stall_force` too).
    ///
    /// # Errors
    /// `--maximize: invalid value '…' (one of: asymmetry, stall-force)`.
    pub fn from_name(name: &str) -> Result<Maximize> {
        match name {
            "asymmetry" => Ok(Maximize::Asymmetry),
            "stall-force" | "stall_force" => Ok(Maximize::StallForce),
            _ => Err(Error::usage(format!(
                "--maximize: invalid value '{name}' (one of: asymmetry, stall-force)"
            ))),
        }
    }
}

/// A tune request: the CLI's flags of `fricctl tune` besides the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TuneRequest {
    /// Sliding velocity v0, m/s (units of ωW0 for a dimensionless scene); needed with a target
    /// (or `v_rel`).
    pub v0: Option<f64>,
    /// The velocity relative to v_c of the scene as given (before the adjustment):
    /// v0 = X·v_c (forward v_c for X > 0, backward for X < 0); instead of `v0`.
    pub v_rel: Option<f64>,
    /// Target μ/μ0, strictly between −1 and 1.
    pub target_mu_rel: Option<f64>,
    /// Target μ, strictly between −μ0 and μ0.
    pub target_mu: Option<f64>,
    /// Maximise an objective instead of meeting a target.
    pub maximize: Option<Maximize>,
    /// The drive quantity to adjust.
    pub adjust: Adjust,
    /// Largest Δu_z, m (default and upper limit: (1 − liftoff_margin)·uz0).
    pub max_duz: Option<f64>,
    /// Largest Δu_x, m (default 10·W0).
    pub max_dux: Option<f64>,
    /// Lift-off margin m in (0, 1).
    pub liftoff_margin: f64,
}

/// The outcome of a tune request.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum TuneOutcome {
    /// A target search.
    Target(TargetOut),
    /// A maximisation.
    Maximize(MaximizeOut),
}

/// The drive a result stands for, and the search it came from (JSON keys are
/// part of the CLI contract; shared by both kinds of result).
#[derive(Serialize, Debug, Clone)]
pub struct DriveOut {
    /// The contact's profile: `flat`, `sphere`, `cone` or `power`.
    pub profile: &'static str,
    /// The exponent n of the profile `f = c·rⁿ` (`null` for the flat punch).
    pub exponent: Option<f64>,
    /// `duz`, `dux` or `phase`.
    pub adjust: &'static str,
    /// Δu_z, m.
    pub duz: f64,
    /// Δu_x, m.
    pub dux: f64,
    /// φ, degrees in [0, 360).
    pub phi_deg: f64,
    /// Δu_z/u_z0.
    pub duz_rel: f64,
    /// k_xΔu_x/(μ0 k_z u_z0).
    pub dux_rel: f64,
    /// Lower end of the search range of the adjusted quantity (m, or deg).
    pub range_lo: f64,
    /// Upper end (m, or deg; 360 for the phase).
    pub range_hi: f64,
    /// Cells of the scan.
    pub scan_cells: usize,
}

/// The JSON document of a target search.
#[derive(Serialize, Debug, Clone)]
pub struct TargetOut {
    /// The drive it stands for.
    #[serde(flatten)]
    pub drive: DriveOut,
    /// Sliding velocity, m/s.
    pub v0: f64,
    /// Target μ.
    pub target_mu: f64,
    /// Target μ/μ0.
    pub target_mu_over_mu0: f64,
    /// μ at the reported drive (exact solver, or the profile's MDR quadrature).
    pub mu: f64,
    /// μ/μ0 at the reported drive.
    pub mu_over_mu0: f64,
    /// `mu_over_mu0 − target_mu_over_mu0`.
    pub residual_over_mu0: f64,
    /// `exact` (flat punch) or `mdr` (a curved profile's quadrature).
    pub method: &'static str,
    /// The bound on `mu_over_mu0`, units of μ0: the exact solver's, or the
    /// tolerance the quadrature met at the reported drive.
    pub error_bound_over_mu0: f64,
    /// Every solution, in the adjusted quantity's unit (m, or deg).
    pub solutions: Vec<f64>,
    /// Solutions found (more than listed if above 16).
    pub solutions_found: u32,
    /// The scene's value of the adjusted quantity (the reported solution is the nearest).
    pub start: f64,
    /// Least μ/μ0 over the range (attained).
    pub reachable_min_over_mu0: f64,
    /// Greatest μ/μ0 over the range (attained).
    pub reachable_max_over_mu0: f64,
}

/// The JSON document of a maximisation.
#[derive(Serialize, Debug, Clone)]
pub struct MaximizeOut {
    /// The drive it stands for.
    #[serde(flatten)]
    pub drive: DriveOut,
    /// `asymmetry` or `stall_force`.
    pub objective: &'static str,
    /// The objective's value at the reported drive (units of μ0, resp. μ0·F̄z).
    pub value: f64,
    /// Bound on `value`, units of μ0 (two solver bounds for the asymmetry, one for the stall force;
    /// a curved profile's are its quadrature's).
    pub error_bound_over_mu0: f64,
    /// Regime of the reported drive.
    pub regime: &'static str,
    /// max|μ(v)+μ(−v)|/μ0 at the reported drive.
    pub asymmetry: f64,
    /// −μ(0⁺)/μ0 when positive, else 0 (units μ0·kz·uz0).
    pub stall_force_forward: f64,
    /// lim μ/μ0 as v0 → 0⁺.
    pub mu_0plus_over_mu0: f64,
    /// lim μ/μ0 as v0 → 0⁻.
    pub mu_0minus_over_mu0: f64,
}

/// A validated request.
struct Setup {
    scene: Scene<f64>,
    problem: Problem<f64>,
    /// The contact's profile (`Flat`: the exact solver).
    profile: Profile<f64>,
    /// Length of one dimensionless unit of the knob: u_z0 (duz), W0 (dux), 1 rad (phase).
    unit: f64,
}

impl TargetOut {
    /// The refusal of a doubtful result: a residual above the solver's bound
    /// (the result is the best the search found, but not within the bound).
    pub fn doubtful(&self) -> Option<Error> {
        let bound = self.error_bound_over_mu0;
        (self.residual_over_mu0.abs() > bound).then(|| {
            Error::failure(format!(
                "doubtful: the residual {:e} exceeds the solver's bound {bound:e} (the law is steeper than the float type resolves here)",
                self.residual_over_mu0
            ))
        })
    }
}

/// Runs a tune request on a scene.
///
/// # Errors
/// Bad input (one line naming the flag, including a target out of reach and
/// a maximisation with no feasible drive), or the solver's failure.
pub fn tune(rs: &ResolvedScene, req: &TuneRequest) -> Result<TuneOutcome> {
    req.check()?;
    let setup = req.setup(rs)?;
    match (req.target_mu_rel, req.target_mu, req.maximize) {
        (Some(t), None, None) => req
            .target(&setup, rs, t, "target-mu-rel")
            .map(TuneOutcome::Target),
        (None, Some(x), None) => {
            let mu0 = setup.scene.mu0();
            if x.abs() >= mu0 {
                return Err(Error::usage(format!(
                    "--target-mu: {} must lie strictly inside (−{m}, {m}) (|mu| = mu0 is continuous sliding)",
                    short(x),
                    m = short(mu0)
                )));
            }
            req.target(&setup, rs, x / mu0, "target-mu")
                .map(TuneOutcome::Target)
        }
        (None, None, Some(m)) => req.maximize(&setup, m).map(TuneOutcome::Maximize),
        (None, None, None) => Err(Error::usage(
            "--target-mu-rel: missing (give --target-mu-rel, --target-mu or --maximize)",
        )),
        _ => Err(Error::usage(
            "--target-mu-rel: give one of --target-mu-rel, --target-mu and --maximize",
        )),
    }
}

impl TuneRequest {
    /// Every number in its domain (the CLI's flag parsers' checks and text).
    fn check(&self) -> Result {
        let any = Real::ANY;
        if let Some(v) = self.v0 {
            check(any, v, "--v0")?;
        }
        if let Some(x) = self.v_rel {
            check(any, x, "--v-rel")?;
        }
        if let Some(t) = self.target_mu_rel {
            check(TARGET_MU_REL, t, "--target-mu-rel")?;
        }
        if let Some(t) = self.target_mu {
            check(any, t, "--target-mu")?;
        }
        if let Some(x) = self.max_duz {
            check(Real::positive(), x, "--max-duz")?;
        }
        if let Some(x) = self.max_dux {
            check(Real::positive(), x, "--max-dux")?;
        }
        check(LIFTOFF_MARGIN, self.liftoff_margin, "--liftoff-margin")?;
        Ok(())
    }

    fn setup(&self, rs: &ResolvedScene) -> Result<Setup> {
        let scene = rs.scene;
        // Every flag is in its domain (the parsers): 0 < margin < 1, limits > 0.
        let m = self.liftoff_margin;
        let p = scene.params();
        let limit = (1.0 - m) * p.uz0;
        let g = scene.groups();
        let (max_duz, max_dux) = (self.max_duz, self.max_dux);
        if self.adjust != Adjust::Duz && max_duz.is_some() {
            return Err(Error::usage("--max-duz: only with --adjust duz"));
        }
        if self.adjust != Adjust::Dux && max_dux.is_some() {
            return Err(Error::usage("--max-dux: only with --adjust dux"));
        }
        if self.adjust != Adjust::Duz && p.duz > limit {
            let (name, unit) = if rs.dimensionless {
                ("duz-rel", "")
            } else {
                ("duz", " m")
            };
            let flag = rs.given.duz;
            return Err(Error::usage(format!(
                "{flag}: {name} = {}{unit} is above the lift-off limit (1 − liftoff-margin)·uz0 = {}{unit}",
                short(p.duz),
                short(limit)
            )));
        }
        let (knob, hi, unit) = match self.adjust {
            Adjust::Duz => {
                let hi = max_duz.unwrap_or(limit);
                if hi > limit {
                    // A dimensionless scene's lengths are in units of uz0.
                    let unit = if rs.dimensionless { " uz0" } else { " m" };
                    return Err(Error::usage(format!(
                        "--max-duz: {}{unit} is above the lift-off limit (1 − liftoff-margin)·uz0 = {}{unit}",
                        short(hi),
                        short(limit)
                    )));
                }
                (Knob::Duz, hi / p.uz0, p.uz0)
            }
            Adjust::Dux => {
                let w0 = scene.w0();
                let hi = max_dux.unwrap_or(DEFAULT_MAX_DUX_REL * w0);
                // The widest drive of the search must be one the solvers resolve.
                check_reach(0.0, hi / w0, rs.given.duz, "--max-dux")?;
                (Knob::Dux, hi / w0, w0)
            }
            Adjust::Phase => (Knob::Phase, std::f64::consts::TAU, 1.0),
        };
        let problem = Problem::new::<Libm>(g, knob, 0.0, hi)
            .map_err(|e| Error::usage(format!("--max-{}: {e}", knob.name())))?;
        Ok(Setup {
            scene,
            problem,
            profile: rs.profile,
            unit,
        })
    }

    /// The knob value `x` in the output unit (m, or degrees).
    fn shown(&self, s: &Setup, x: f64) -> f64 {
        match self.adjust {
            Adjust::Phase => x.to_degrees(),
            _ => x * s.unit,
        }
    }

    fn drive_out(&self, s: &Setup, x: f64) -> DriveOut {
        let g = s.problem.groups_at(x);
        let p = s.scene.params();
        let (lo, hi) = s.problem.range();
        DriveOut {
            profile: s.profile.name(),
            exponent: s.profile.exponent(),
            adjust: s.problem.knob().name(),
            duz: g.duz_rel * p.uz0,
            dux: g.dux_rel * s.scene.w0(),
            phi_deg: wrap_deg(g.phi.to_degrees()),
            duz_rel: g.duz_rel,
            dux_rel: g.dux_rel,
            range_lo: self.shown(s, lo),
            range_hi: self.shown(s, hi),
            scan_cells: SCAN_CELLS,
        }
    }

    fn target(&self, s: &Setup, rs: &ResolvedScene, t: f64, flag: &str) -> Result<TargetOut> {
        let (v0, vflag) =
            match (self.v0, self.v_rel) {
                (Some(v), None) => (v, "--v0"),
                (None, Some(x)) => (
                    from_rel(&critical_velocity(&rs.scene)?, x, "v-rel")?,
                    "--v-rel",
                ),
                (Some(_), Some(_)) => {
                    return Err(Error::usage(
                        "--v-rel: give the velocity once (--v0 or --v-rel)",
                    ))
                }
                (None, None) => return Err(Error::usage(
                    "--v0: missing (a target mu is at a sliding velocity; give --v0 or --v-rel)",
                )),
            };
        if v0 == 0.0 {
            return Err(Error::usage(format!(
                "{vflag}: must be != 0 for a target (at rest mu is not unique; see `fricctl static`)"
            )));
        }
        let mu0 = s.scene.mu0();
        let v = rs.velocity(v0, vflag)?;
        let mut scan = vec![0.0; self.scan_points()];
        let found = match s.profile {
            Profile::Flat => inverse::solve_target::<f64, Libm>(&s.problem, v, t, &mut scan),
            p => {
                if !v.is_finite() {
                    return Err(Error::usage(format!("{vflag}: must be a finite number")));
                }
                let tol = |x: f64| profile_tol_of(&s.problem.drive_at::<Libm>(x), &p);
                let mut mu = |x: f64| {
                    let d = s.problem.drive_at::<Libm>(x);
                    Ok(mdr::mu_over_mu0::<f64, Libm>(&d, &p, v, tol(x))?.mu_over_mu0)
                };
                inverse::solve_target_with(&s.problem, t, &mut scan, &mut mu, &tol)
            }
        };
        let r = match found {
            Ok(r) => r,
            Err(InverseError::OutOfReach { min, max }) => {
                let (lo, hi) = s.problem.range();
                let scale = if flag == "target-mu" { mu0 } else { 1.0 };
                let unit = if self.adjust == Adjust::Phase {
                    "deg"
                } else {
                    "m"
                };
                return Err(Error::usage(format!(
                    "--{flag}: {} is out of reach by adjusting {} at v0 = {} m/s: reachable {}…{} ({} from {} to {} {unit})",
                    short(t * scale),
                    s.problem.knob().name(),
                    short(v0),
                    short(min * scale),
                    short(max * scale),
                    s.problem.knob().name(),
                    knob_text(s.problem.knob().name(), self.shown(s, lo)),
                    knob_text(s.problem.knob().name(), self.shown(s, hi)),
                )));
            }
            Err(e) => return Err(inverse_failure(e)),
        };
        let start = self.start_value(s);
        let best = r
            .nearest(s.problem.knob(), start)
            .ok_or_else(|| Error::failure("tune: no solution kept (internal)"))?;
        let (bound, method) = match s.profile {
            Profile::Flat => (s.problem.bound_at::<Libm>(best.x), "exact"),
            p => (
                profile_tol_of(&s.problem.drive_at::<Libm>(best.x), &p),
                "mdr",
            ),
        };
        let o = TargetOut {
            drive: self.drive_out(s, best.x),
            v0,
            target_mu: t * mu0,
            target_mu_over_mu0: t,
            mu: best.value * mu0,
            mu_over_mu0: best.value,
            residual_over_mu0: best.value - t,
            method,
            error_bound_over_mu0: bound,
            solutions: r.solutions.iter().map(|q| self.shown(s, q.x)).collect(),
            solutions_found: r.found,
            start: self.shown(s, start),
            reachable_min_over_mu0: r.min.value,
            reachable_max_over_mu0: r.max.value,
        };
        Ok(o)
    }

    fn maximize(&self, s: &Setup, m: Maximize) -> Result<MaximizeOut> {
        if self.v0.is_some() || self.v_rel.is_some() {
            let flag = if self.v0.is_some() { "--v0" } else { "--v-rel" };
            return Err(Error::usage(format!(
                "{flag}: not used by --maximize (the asymmetry and the stall force are properties of the whole law)"
            )));
        }
        let objective = match m {
            Maximize::Asymmetry => Objective::Asymmetry,
            Maximize::StallForce => Objective::StallForce,
        };
        let mut scan = vec![0.0; self.scan_points()];
        let searched = match s.profile {
            Profile::Flat => inverse::maximize::<f64, Libm>(&s.problem, objective, &mut scan),
            p => {
                // The profile's objective from the one implementation of
                // each (`static`, `classify`); its first failure is kept
                // whole and stops the search.
                let mut failure = None;
                let mut f = |x: f64| -> std::result::Result<Option<f64>, InverseError<f64>> {
                    match profile_objective(&s.problem, &p, objective, x) {
                        Ok(v) => Ok(v),
                        Err(e) => {
                            failure = Some(e);
                            Err(InverseError::Infeasible)
                        }
                    }
                };
                let r = inverse::maximize_with(&s.problem, &mut scan, &mut f);
                if let Some(e) = failure {
                    return Err(e);
                }
                r
            }
        };
        let best = match searched {
            Ok(b) => b,
            Err(InverseError::Infeasible) => {
                return Err(Error::usage(format!(
                    "--maximize: every drive with {} in its range is an actuator (no force-free rest): no ratchet to optimise",
                    s.problem.knob().name()
                )))
            }
            Err(e) => return Err(inverse_failure(e)),
        };
        let name = match m {
            Maximize::Asymmetry => "asymmetry",
            Maximize::StallForce => "stall_force",
        };
        if m == Maximize::StallForce && best.value <= 0.0 {
            return Err(Error::usage(format!(
                "--maximize: the contact never pushes forward with {} in its range (largest −mu(0+)/mu0 = {})",
                s.problem.knob().name(),
                short(best.value)
            )));
        }
        self.maximize_out(s, best, name, m)
    }

    fn maximize_out(
        &self,
        s: &Setup,
        best: Point<f64>,
        name: &'static str,
        m: Maximize,
    ) -> Result<MaximizeOut> {
        let d = s.problem.drive_at::<Libm>(best.x);
        let scene = Scene::dimensionless(s.problem.groups_at(best.x))
            .map_err(|e| Error::failure(format!("tune: {e}")))?;
        if s.profile != Profile::Flat {
            let c = classify_scene_profile(&scene, &s.profile)?;
            let st = profile_statics(&scene, &s.profile)?;
            let moving = profile_tol_of(&d, &s.profile);
            return Ok(MaximizeOut {
                drive: self.drive_out(s, best.x),
                objective: name,
                value: best.value,
                error_bound_over_mu0: match m {
                    // Each sample |μ(v) + μ(−v)| is two quadratures (or the
                    // two limits at rest).
                    Maximize::Asymmetry => 2.0 * moving.max(st.bound),
                    Maximize::StallForce => st.bound,
                },
                regime: c.regime.name(),
                asymmetry: c.asymmetry,
                stall_force_forward: (-c.mu_0plus).max(0.0),
                mu_0plus_over_mu0: c.mu_0plus,
                mu_0minus_over_mu0: c.mu_0minus,
            });
        }
        let c = classify_drive::<f64, Libm>(
            &d,
            StaticFriction::of(&scene),
            &ClassifyOptions::default(),
        )
        .map_err(exact_failure)?;
        let bound = exact::error_bound::<f64, Libm>(&d);
        Ok(MaximizeOut {
            drive: self.drive_out(s, best.x),
            objective: name,
            value: best.value,
            error_bound_over_mu0: match m {
                Maximize::Asymmetry => 2.0 * bound,
                Maximize::StallForce => bound,
            },
            regime: c.regime.name(),
            asymmetry: c.asymmetry,
            stall_force_forward: (-c.mu_0plus).max(0.0),
            mu_0plus_over_mu0: c.mu_0plus,
            mu_0minus_over_mu0: c.mu_0minus,
        })
    }

    /// Scan points: `SCAN_CELLS + 1` for an amplitude, `SCAN_CELLS` on the circle.
    fn scan_points(&self) -> usize {
        if self.adjust == Adjust::Phase {
            SCAN_CELLS
        } else {
            SCAN_CELLS + 1
        }
    }

    /// The scene's value of the adjusted quantity (dimensionless knob value).
    fn start_value(&self, s: &Setup) -> f64 {
        let g = s.scene.groups();
        match self.adjust {
            Adjust::Duz => g.duz_rel,
            Adjust::Dux => g.dux_rel,
            Adjust::Phase => g.phi.rem_euclid(std::f64::consts::TAU),
        }
    }
}

/// A curved profile's objective with the knob at `x` (`None` where
/// infeasible: an actuator for the asymmetry), from the same computations
/// as `fricctl static` and `fricctl classify`.
fn profile_objective(
    pb: &Problem<f64>,
    p: &Profile<f64>,
    objective: Objective,
    x: f64,
) -> Result<Option<f64>> {
    match objective {
        Objective::StallForce => {
            let d: Drive<f64> = pb.drive_at::<Libm>(x);
            let (plus, _) = mdr::limits_at_zero::<f64, Libm>(&d, p, profile_tol_of_at_rest(&d, p))
                .map_err(mdr_failure)?;
            Ok(Some(-plus.mu_over_mu0))
        }
        Objective::Asymmetry => {
            let scene = Scene::dimensionless(pb.groups_at(x))
                .map_err(|e| Error::failure(format!("tune: {e}")))?;
            let c = classify_scene_profile(&scene, p)?;
            Ok((c.regime != Regime::Actuator).then_some(c.asymmetry))
        }
    }
}

fn wrap_deg(d: f64) -> f64 {
    let w = d.rem_euclid(360.0);
    if w >= 360.0 {
        0.0
    } else {
        w
    }
}

fn inverse_failure(e: InverseError<f64>) -> Error {
    match e {
        InverseError::Exact(x) => exact_failure(x),
        InverseError::Mdr(x) => mdr_failure(x),
        other => Error::failure(format!("tune: {other}")),
    }
}

/// A value of the adjusted quantity as text: metres in `e` notation, degrees
/// plain; a computed value to 12 significant digits
/// ([`crate::numbers::rounded`]: no float noise).
pub fn knob_text(adjust: &str, x: f64) -> String {
    if adjust == "phase" || x == 0.0 {
        crate::numbers::rounded(x)
    } else {
        format!("{:e}", crate::numbers::round_sig(x, 12))
    }
}
