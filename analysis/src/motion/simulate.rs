//! A run of the body's motion as `fricctl motion` and `fricctl.motion` make
//! it: the work plan (each refusal naming the flag that makes the run large
//! or unresolvable), the method choice of `auto` (module docs of
//! [`crate::motion`]), the run, and its result in output units.
//!
//! # Contact models
//! The law μ(v) comes from [`super::law::Law`], one interface for
//! every contact model-core offers (flat punch, lift-off; curved profiles
//! once they exist): forces are in units of `μ₀F̄z` with `F̄z` the contact's
//! mean normal force.
//!
//! # Method choice (`method auto`)
//! The homogenised model replaces the contact by its steady-state law. Its
//! error `E_h = π²K·reach·S/(2n̄) + N(1 + a)ν/π` (units ωW₀; `reach` 1 for
//! the flat punch, `N` the arrivals at rest per load period) is derived in
//! [`super::estimate`]: `K` bounds the body's acceleration in
//! ultrasonic units (its ripple within a period against its response time
//! for `M > 0`; the scale separation `ν·max|dV/dT|` for `M = 0`), `S` is the
//! law's mean inverse slope; the second term is the stuck body's offset on the
//! contact's tangential stiffness. The homogenised model always runs first (it is
//! cheap and gives `K`); `auto` keeps it when `E_h` plus its numerical error
//! is within `tol·v_ref`, and runs the resolved one otherwise (`M = 0` is
//! always homogenised: a massless body has no resolved dynamics).

use std::f64::consts::TAU;
use std::time::Instant;

use serde::Serialize;

use super::estimate;
use super::law::Law;
use super::table::MuTable;
use super::{homogenised, resolved, Problem, Run};
use crate::error::{Error, Result};
use crate::numbers::{short, Real};
use crate::scene::{check, ResolvedScene};

/// Most load periods when running until the periodic regime.
pub const MAX_PERIODS: u32 = 2000;

/// Domain of the force's mean and amplitude, units of μ0·F̄z: at most ten
/// times the largest force the contact exerts. Beyond it the load, not the
/// contact, moves the body, and the body's speed swings far beyond v_c.
pub const FORCE_REL: Real = Real::ANY
    .at_least(-10.0)
    .at_most(10.0)
    .because("ten times the contact's largest force μ0·F̄z");

/// Domain of the tolerance on the mean velocity (relative to v_ref).
pub const TOL: Real = Real::ANY.above(0.0).below(1.0);

/// Which model integrates the body (the CLI's `--method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionMethod {
    /// Homogenised where its estimated error is within `tol`, resolved otherwise.
    Auto,
    /// The averaged law μ(v) as the friction force.
    Homogenised,
    /// Body and contact together at the ultrasonic scale.
    Resolved,
}

impl MotionMethod {
    /// The method named `name` (`auto`, `homogenised`, `resolved`).
    ///
    /// # Errors
    /// `--method: invalid value '…' (one of: auto, homogenised, resolved)`.
    pub fn from_name(name: &str) -> Result<MotionMethod> {
        match name {
            "auto" => Ok(MotionMethod::Auto),
            "homogenised" => Ok(MotionMethod::Homogenised),
            "resolved" => Ok(MotionMethod::Resolved),
            _ => Err(Error::usage(format!(
                "--method: invalid value '{name}' (one of: auto, homogenised, resolved)"
            ))),
        }
    }
}

/// A motion request: the flags of `fricctl motion` besides the scene (SI
/// units; the scene's units for a dimensionless scene).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionRequest {
    /// Mass of the body M, kg (0: massless, quasi-static; units k_x/ω² for a dimensionless scene).
    pub mass: f64,
    /// Force amplitude f: F(t) = μ0·F̄z·(f0 + f·sin Ωt) (|f| ≤ 10).
    pub force_amp_rel: f64,
    /// Angular frequency Ω of the force, rad/s (units of ω for a dimensionless scene).
    pub force_omega: f64,
    /// Mean force f0, units of μ0·F̄z (|f0| ≤ 10).
    pub force_offset_rel: f64,
    /// Stiffness K of a spring tying the body to ground, N/m (units of k_x for a dimensionless scene).
    pub spring: f64,
    /// Simulated time, s: whole load periods 2π/Ω (None: until periodic, at most [`MAX_PERIODS`]).
    pub duration: Option<f64>,
    /// Model.
    pub method: MotionMethod,
    /// Tolerance on the mean velocity, relative to the larger critical velocity (0 < tol < 1).
    pub tol: f64,
}

impl MotionRequest {
    /// Every number in its domain (the CLI's flag parsers' checks and text).
    fn check(&self) -> Result {
        check(Real::non_negative(), self.mass, "--mass")?;
        check(FORCE_REL, self.force_amp_rel, "--force-amp-rel")?;
        check(Real::positive(), self.force_omega, "--force-omega")?;
        check(FORCE_REL, self.force_offset_rel, "--force-offset-rel")?;
        check(Real::non_negative(), self.spring, "--spring")?;
        if let Some(t) = self.duration {
            check(Real::positive(), t, "--duration")?;
        }
        check(TOL, self.tol, "--tol")?;
        Ok(())
    }
}

/// What a run reports while it integrates (the CLI's progress bar).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// A run of at most this many load periods starts.
    Start(u32),
    /// One load period integrated.
    Period,
    /// The resolved model starts over (auto chose it).
    Restart,
    /// Finished.
    Done,
}

/// The result (`--json` keys; velocities in m/s, units of ωW₀ for a dimensionless scene).
#[derive(Serialize, Debug, Clone)]
pub struct Outcome {
    /// `homogenised` or `resolved`: the model that answered.
    pub method: &'static str,
    /// Contact model: flat | lift-off | sphere | cone | power.
    pub contact: &'static str,
    /// Drift over the last load period, m/s.
    pub mean_velocity: f64,
    /// Estimated error of mean_velocity, m/s (model + numerics).
    pub error_estimate: f64,
    /// The larger critical velocity, m/s: the unit of --tol.
    pub v_ref: f64,
    /// mean_velocity/v_ref.
    pub mean_velocity_over_v_ref: f64,
    /// error_estimate/v_ref.
    pub error_estimate_over_v_ref: f64,
    /// The homogenised model's estimated error E_h, m/s (also for resolved runs: why auto chose).
    pub homogenisation_error_estimate: f64,
    /// Numerical error (step halving + period-to-period change), m/s.
    pub numerical_error: f64,
    /// Fraction of the last load period the body spends at rest.
    pub stick_fraction: f64,
    /// Arrivals at rest in the homogenised run's last load period (the N of E_h's sticking term).
    pub stick_onsets: u32,
    /// Whether a periodic regime was reached.
    pub periodic: bool,
    /// Load periods integrated.
    pub periods: u32,
    /// Steps per load period (homogenised) or per ultrasonic period (resolved).
    pub steps: u64,
    /// Springs of the resolved contact (1: flat punch; a curved profile's MDR bed after doubling); 0 for homogenised runs.
    pub springs: usize,
    /// ω/Ω.
    pub scale_separation: f64,
    /// Body's response time M/(largest slope of μ(v)·F̄z), s.
    pub response_time: f64,
    /// Mω²/k_x.
    pub mass_rel: f64,
    /// Mean normal force F̄z in units of kz·uz0 (1: permanent contact; ⟨w⁺⟩ with lift-off; D of eq. M5 for a curved profile, kz = 2E*a0).
    pub fz_mean_over_kz_uz0: f64,
    /// lim μ/μ0 as v → 0⁺ (the law's).
    pub mu_0plus_over_mu0: f64,
    /// lim μ/μ0 as v → 0⁻.
    pub mu_0minus_over_mu0: f64,
    /// Nodes of the μ(v) table.
    pub table_nodes: usize,
    /// Interpolation error of the table, units of μ0.
    pub table_error_over_mu0: f64,
    /// Wall time of the integration, s.
    pub wall_time: f64,
}

/// One point of the trajectory in output units (s, m, m/s, N; the
/// scene's units for a dimensionless one): the CLI's CSV row.
#[derive(Serialize, Debug, Clone, Copy)]
pub struct Row {
    /// s.
    pub t: f64,
    /// m.
    pub x: f64,
    /// m/s.
    pub v: f64,
    /// Applied force F(t), N.
    pub force: f64,
    /// 1 while the body is at rest on the contact.
    pub stuck: u8,
}

/// Most RK4 steps of the homogenised model in one `motion` run, over all its
/// step doublings and load periods (≈ 15 s: a step costs up to ≈ 140 ns,
/// four table look-ups or inversions). A run whose least possible cost
/// exceeds it is refused before it starts, naming the flag that makes it
/// large; the step doubling stops before a run that would exceed it
/// (`Run::stopped_at_work_bound`).
pub const HOMOGENISED_BUDGET: f64 = 1e8;

/// Most spring steps (steps × springs) of the resolved model in one run
/// (≈ 25 s at ≈ 25 ns each), in the same two ways.
pub const RESOLVED_BUDGET: f64 = 1e9;

/// An estimate in messages: three significant digits (`2.24e28`).
fn approx(x: f64) -> String {
    format!("{x:.2e}")
}

/// What the run will cost and whether its integrators can resolve it,
/// estimated before it starts (the work bound): each refusal
/// names the flag that makes the run large or unresolvable.
struct WorkPlan {
    /// `ν = Ω/ω`.
    nu: f64,
    /// `m̃ = Mω²/k_x`.
    mass: f64,
    /// `κ = K/k_x`.
    kappa: f64,
    /// Load periods of `--duration` (None: until periodic).
    periods: Option<u32>,
    /// Springs of the resolved model's first bed (1: flat punch).
    springs: usize,
    /// The first steps per ultrasonic period of the resolved model.
    resolved_start: u64,
}

impl WorkPlan {
    /// The homogenised model: RK4 must be stable at its finest step for the
    /// body on the law (`λ = 2πn̄·max dμ/dV/(m̃ν)` steps, unless the
    /// quasi-static limit takes over) and on the ground spring
    /// (`2π·√(κ/m̃)/ν/2.8` steps; massless: `2πκS/(2.8n̄ν)`), and its least
    /// work, two step counts over the periods asked, within
    /// [`HOMOGENISED_BUDGET`].
    fn check_homogenised(&self, p: &Problem, law: &MuTable) -> Result {
        let max = homogenised::MAX_STEPS as f64;
        let law_steps = if self.mass > 0.0 {
            TAU * p.normal * law.max_slope() / (self.mass * self.nu)
        } else {
            0.0
        };
        let bounded = p.f0.abs() + p.f.abs() < 1.0;
        let quasi_static =
            self.mass == 0.0 || (law_steps > homogenised::STIFF_STEPS as f64 && bounded);
        if !quasi_static && law_steps > 2.5 * max {
            return Err(Error::usage(format!(
                "--mass: the body (Mω²/k_x = {}) follows the load (ω/Ω = {}) so fast that the homogenised model needs ≥ {} steps per load period (max {}); heavier body, slower load or |f0| + |f| < 1",
                short(self.mass),
                short(1.0 / self.nu),
                approx(law_steps / 2.5),
                homogenised::MAX_STEPS
            )));
        }
        let spring_steps = self.spring_steps(p, law);
        if spring_steps > max {
            return Err(Error::usage(format!(
                "--spring: K/k_x = {} is so stiff against the load (ω/Ω = {}) that the homogenised model needs ≥ {} steps per load period (max {}); softer spring or slower load",
                short(self.kappa),
                short(1.0 / self.nu),
                approx(spring_steps),
                homogenised::MAX_STEPS
            )));
        }
        let n0 = (homogenised::MIN_STEPS as f64)
            .max(law_steps.min(max / 2.0))
            .max(spring_steps);
        let periods = f64::from(self.periods.unwrap_or(2));
        let work = 3.0 * n0 * periods;
        if work > HOMOGENISED_BUDGET {
            return Err(self.too_long(
                work,
                HOMOGENISED_BUDGET,
                "the homogenised model",
                "--duration",
            ));
        }
        Ok(())
    }

    /// Steps per load period RK4 needs to stay stable on the ground spring:
    /// `2π·√(κ/m̃)/ν/2.8` for a body with mass (its ringing on the spring),
    /// `2πκS/(2.8n̄ν)` for the quasi-static body (`S` the law's mean inverse
    /// slope); 0 without a spring.
    fn spring_steps(&self, p: &Problem, law: &MuTable) -> f64 {
        let law_steps = if self.mass > 0.0 {
            TAU * p.normal * law.max_slope() / (self.mass * self.nu)
        } else {
            0.0
        };
        let bounded = p.f0.abs() + p.f.abs() < 1.0;
        let quasi_static =
            self.mass == 0.0 || (law_steps > homogenised::STIFF_STEPS as f64 && bounded);
        if self.kappa == 0.0 {
            0.0
        } else if quasi_static {
            TAU * self.kappa * estimate::inverse_slope(law) / (2.8 * p.normal * self.nu)
        } else {
            TAU * (self.kappa / self.mass).sqrt() / (2.8 * self.nu)
        }
    }

    /// The resolved model: symplectic Euler must be stable for the body on
    /// the contact's and the spring's stiffness (`π√((1 + κ)/m̃)` steps per
    /// ultrasonic period, at most [`resolved::MAX_STEPS`]), and its least
    /// work (two step counts, `n/ν` steps per load period, three periods or
    /// those of `--duration`; times the first bed's springs) within
    /// [`RESOLVED_BUDGET`].
    /// `auto` is the homogenised estimate over `v_ref` when `--method auto`
    /// chose the resolved model (it is named in the refusal).
    fn check_resolved(&self, auto: Option<f64>) -> Result {
        let subject = |model: &str| match auto {
            Some(e) => {
                format!("auto needs {model} (homogenised estimate {e:.2e} v_ref > --tol), which")
            }
            None => model.to_string(),
        };
        let stable = std::f64::consts::PI * ((1.0 + self.kappa) / self.mass).sqrt();
        if stable > resolved::MAX_STEPS as f64 {
            let flag = if self.kappa > 1.0 {
                "--spring"
            } else {
                "--mass"
            };
            return Err(Error::usage(format!(
                "{flag}: {} needs {} steps per period for this body (Mω²/k_x = {}, K/k_x = {}; max {}); try --method homogenised",
                subject("the resolved model"),
                approx(stable.ceil()),
                short(self.mass),
                short(self.kappa),
                resolved::MAX_STEPS
            )));
        }
        let per_load = self.resolved_start as f64 / self.nu * self.springs as f64;
        let work = |periods: f64| 3.0 * per_load * periods;
        let asked = work(f64::from(self.periods.unwrap_or(3)));
        if asked > RESOLVED_BUDGET {
            // The duration makes it large only if three periods would do.
            let flag = if self.periods.is_some() && work(3.0) <= RESOLVED_BUDGET {
                "--duration"
            } else {
                "--force-omega"
            };
            return Err(self.too_long(
                asked,
                RESOLVED_BUDGET,
                &subject("the resolved model"),
                flag,
            ));
        }
        Ok(())
    }

    /// The refusal of a run whose least work exceeds `budget`.
    fn too_long(&self, work: f64, budget: f64, subject: &str, flag: &str) -> Error {
        let how = if flag == "--duration" {
            "give a shorter --duration".to_string()
        } else {
            format!(
                "ω/Ω = {} sets them; try --method homogenised",
                short(1.0 / self.nu)
            )
        };
        Error::usage(format!(
            "{flag}: {subject} takes ≥ {} steps (work bound {:e}); {how}",
            approx(work),
            budget
        ))
    }
}

/// A finished run: the result, the trajectory, and what its plot needs.
pub struct Simulation {
    /// The result in output units.
    pub outcome: Outcome,
    /// The run (dimensionless).
    pub run: Run,
    /// The μ(v) table the homogenised model used.
    pub law: MuTable,
    /// The dimensionless problem.
    pub problem: Problem,
    /// Force unit of the trajectory: N (μ0·F̄z), or 1 for a dimensionless scene.
    pub force_unit: f64,
    /// Whether the homogenised model answered.
    pub homogenised: bool,
    /// The request's tolerance.
    pub tol: f64,
}

impl Simulation {
    /// The trajectory (the last ≤ 50 load periods) in output units.
    pub fn rows(&self, rs: &ResolvedScene, force_omega: f64) -> Vec<Row> {
        let vs = rs.scene.velocity_scale();
        self.run
            .trajectory
            .iter()
            .map(|s| Row {
                t: s.t / force_omega,
                x: s.x * rs.scene.w0(),
                v: s.v * vs,
                force: s.force * self.force_unit,
                stuck: u8::from(s.stuck),
            })
            .collect()
    }

    /// The refusal of a doubtful result, printed after it: no periodic
    /// regime, or an error estimate beyond the tolerance.
    pub fn doubtful(&self) -> Option<Error> {
        let run = &self.run;
        let tol = self.tol;
        if !run.periodic {
            return Some(Error::failure(format!(
                "no periodic regime after {} load periods: mean_velocity is the last period's, not the drift",
                run.periods
            )));
        }
        if self.outcome.error_estimate_over_v_ref > tol {
            return Some(Error::failure(format!(
                "estimated error {:.3e} v_ref exceeds --tol {tol:e}{}",
                self.outcome.error_estimate_over_v_ref,
                if run.stopped_at_work_bound {
                    " (the refinement stopped at the work bound)"
                } else if self.homogenised && self.problem.mass > 0.0 {
                    " (try --method resolved)"
                } else {
                    ""
                }
            )));
        }
        None
    }
}

/// Moves the body: plans, runs and reports (module docs).
///
/// # Errors
/// Bad input (one line naming the flag, including a run beyond the work
/// bound), or a run that gave no finite drift.
pub fn simulate(
    rs: &ResolvedScene,
    req: &MotionRequest,
    progress: &mut dyn FnMut(Progress),
) -> Result<Simulation> {
    req.check()?;
    let scene = rs.scene;
    let prm = *scene.params();
    // Every value is in its domain (the flags' parsers): M, K ≥ 0,
    // Ω > 0, |f|, |f0| ≤ 10, 0 < tol < 1, duration > 0.
    let (mass, f, f0) = (req.mass, req.force_amp_rel, req.force_offset_rel);
    let (big_omega, spring, tol) = (req.force_omega, req.spring, req.tol);
    // Slow dynamics: the load period spans at least two ultrasonic
    // periods (the periodicity tests compare whole load periods; ω/Ω = 10
    // is already where homogenisation fails).
    if big_omega > 0.5 * prm.omega {
        let unit = if rs.dimensionless { "ω" } else { "rad/s" };
        return Err(Error::usage(format!(
            "--force-omega: {big_omega:e} {unit} is faster than half the vibration's ω = {:e} {unit}; a slow load needs Ω ≤ ω/2",
            prm.omega
        )));
    }
    let load_period = TAU / big_omega;
    let periods = match req.duration {
        None => None,
        Some(t) => {
            let n = (t / load_period).floor();
            if n < 1.0 {
                return Err(Error::usage(format!(
                    "--duration: shorter than one load period 2π/Ω = {load_period:e} {}",
                    if rs.dimensionless { "1/ω" } else { "s" }
                )));
            }
            if n > f64::from(u32::MAX) {
                return Err(Error::usage(format!(
                    "--duration: {} load periods of 2π/Ω are more than the {} a run can count",
                    short(n),
                    u32::MAX
                )));
            }
            Some(n as u32)
        }
    };
    let law_fn = Law::with_profile(&scene, rs.profile);
    // The mean normal force in units of k_z u_z0, every contact (a curved
    // profile's: D of eq. M5 with k_z its incremental stiffness 2E*a0).
    let normal = law_fn
        .mean_normal()
        .map_err(|e| Error::failure(e.to_string()))?;
    let p = Problem {
        f0,
        f,
        nu: big_omega / prm.omega,
        mass: mass * prm.omega * prm.omega / prm.kx,
        kappa: spring / prm.kx,
        normal,
    };
    if !p.mass.is_finite() || (mass > 0.0 && p.mass < f64::MIN_POSITIVE) {
        return Err(Error::usage("--mass: out of range for this scene"));
    }
    if mass == 0.0 && f0.abs() + f.abs() >= 1.0 {
        return Err(Error::usage(
            "--force-amp-rel: a massless body needs |f0| + |f| < 1 (beyond μ0·F̄z it would run away)",
        ));
    }
    if spring == 0.0 && f0.abs() >= 1.0 {
        return Err(Error::usage(
            "--force-offset-rel: |f0| >= 1 with no spring: the mean force exceeds μ0·F̄z and the body accelerates without bound",
        ));
    }
    let method = match (req.method, mass == 0.0) {
        (MotionMethod::Resolved, true) => {
            return Err(Error::usage(
                "--mass: the resolved model needs a body with mass > 0",
            ))
        }
        (m, _) => m,
    };
    let d = scene.drive();
    let vs = scene.velocity_scale();
    let started = Instant::now();
    let law =
        MuTable::new(&law_fn, (0.02 * tol).max(1e-9)).map_err(|e| Error::failure(e.to_string()))?;
    let plan = WorkPlan {
        nu: p.nu,
        mass: p.mass,
        kappa: p.kappa,
        periods,
        springs: if law_fn.exponent().is_some() {
            resolved::START_SPRINGS
        } else {
            1
        },
        resolved_start: resolved::start_steps(&d),
    };
    if method != MotionMethod::Resolved {
        plan.check_homogenised(&p, &law)?;
    }
    if method == MotionMethod::Resolved {
        plan.check_resolved(None)?;
    }
    let c = law.c_forward.max(law.c_backward);
    let v_ref = if c > 0.0 { c } else { 1.0 };
    let tol_v = tol * v_ref;
    // Velocity error of the table: its force error over the mean slope of each side.
    let e_table = law.interpolation_error * estimate::inverse_slope(&law);
    let total = periods.unwrap_or(MAX_PERIODS);
    progress(Progress::Start(total));
    // The homogenised run always comes first: cheap, and it gives the
    // body's acceleration bound K of the estimate.
    let relaxation = super::relaxation_per_period(&p, estimate::inverse_slope(&law));
    let hs = homogenised::Settings {
        tol: 0.1 * tol_v,
        periods,
        max_periods: MAX_PERIODS,
        relaxation,
        min_steps: plan.spring_steps(&p, &law).ceil() as u64,
        budget: HOMOGENISED_BUDGET as u64,
    };
    let h_run = homogenised::run(&p, &law, &hs, &mut || progress(Progress::Period));
    let e_h = estimate::homogenisation_error(&p, law_fn.spring_bounds(), &law, &h_run);
    let h_onsets = h_run.stick_onsets;
    let use_h = match method {
        MotionMethod::Homogenised => true,
        MotionMethod::Resolved => false,
        // A homogenised body that reaches no periodic regime is reported
        // as such (exit 1): the resolved body, the same slow dynamics at
        // a far higher cost, would not settle either.
        MotionMethod::Auto => {
            mass == 0.0 || !h_run.periodic || e_h + e_table + h_run.numerical_error <= tol_v
        }
    };
    let run: Run = if use_h {
        h_run
    } else {
        // Auto chose the resolved model: its cost and stability first.
        if method == MotionMethod::Auto {
            let estimate = (e_h + e_table + h_run.numerical_error) / v_ref;
            if let Err(e) = plan.check_resolved(Some(estimate)) {
                progress(Progress::Done);
                return Err(e);
            }
        }
        progress(Progress::Restart);
        let s = resolved::Settings {
            tol: 0.1 * tol_v,
            periods,
            max_periods: MAX_PERIODS,
            relaxation,
            budget: RESOLVED_BUDGET as u64,
        };
        resolved::run(&p, &d, law_fn.exponent(), &s, &mut || {
            progress(Progress::Period)
        })
    };
    progress(Progress::Done);
    let wall = started.elapsed().as_secs_f64();
    let numerical = run.numerical_error + if use_h { e_table } else { 0.0 };
    let error = numerical + if use_h { e_h } else { 0.0 };
    // No result is ever printed as NaN or infinite with exit 0.
    if !(run.mean_velocity.is_finite() && error.is_finite()) {
        return Err(Error::failure(format!(
            "the {} model did not give a finite drift (mean velocity {}, error estimate {}): the integration is unstable for these inputs",
            if use_h { "homogenised" } else { "resolved" },
            short(run.mean_velocity * vs),
            short(error * vs)
        )));
    }
    let slope = law.max_slope();
    let o = Outcome {
        method: if use_h { "homogenised" } else { "resolved" },
        contact: law_fn.name(),
        mean_velocity: run.mean_velocity * vs,
        error_estimate: error * vs,
        v_ref: v_ref * vs,
        mean_velocity_over_v_ref: run.mean_velocity / v_ref,
        error_estimate_over_v_ref: error / v_ref,
        homogenisation_error_estimate: e_h * vs,
        numerical_error: numerical * vs,
        stick_fraction: run.stick_fraction,
        stick_onsets: h_onsets,
        periodic: run.periodic,
        periods: run.periods,
        steps: run.steps,
        springs: run.springs,
        scale_separation: 1.0 / p.nu,
        response_time: if slope > 0.0 {
            p.mass / (p.normal * slope) / prm.omega
        } else {
            f64::INFINITY
        },
        mass_rel: p.mass,
        fz_mean_over_kz_uz0: p.normal,
        mu_0plus_over_mu0: law.mu_0plus,
        mu_0minus_over_mu0: law.mu_0minus,
        table_nodes: law.nodes(),
        table_error_over_mu0: law.interpolation_error,
        wall_time: wall,
    };
    // Forces in N (SI) or in μ0·F̄z (dimensionless, as the text output).
    let force_unit = if rs.dimensionless {
        1.0
    } else {
        prm.mu0 * prm.kz * prm.uz0 * p.normal
    };
    Ok(Simulation {
        outcome: o,
        run,
        law,
        problem: p,
        force_unit,
        homogenised: use_h,
        tol,
    })
}
