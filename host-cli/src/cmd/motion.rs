//! `fricctl motion`: a body of mass M driven by a slow force over the
//! vibrated contact (the physics in [`crate::motion`]).
//!
//! # Contact models
//! The law μ(v) comes from [`crate::motion::law::Law`], one interface for
//! every contact model-core offers (flat punch, lift-off; curved profiles
//! once they exist): forces are in units of `μ₀F̄z` with `F̄z` the contact's
//! mean normal force.
//!
//! # Method choice (`--method auto`)
//! The homogenised model replaces the contact by its steady-state law. Its
//! error `E_h = π²K·reach·S/(2n̄) + N(1 + a)ν/π` (units ωW₀; `reach` 1 for
//! the flat punch, `N` the arrivals at rest per load period) is derived in
//! [`crate::motion::estimate`]: `K` bounds the body's acceleration in
//! ultrasonic units (its ripple within a period against its response time
//! for `M > 0`; the scale separation `ν·max|dV/dT|` for `M = 0`), `S` is the
//! law's mean inverse slope; the second term is the stuck body's offset on the
//! contact's tangential stiffness. The homogenised model always runs first (it is
//! cheap and gives `K`); `auto` keeps it when `E_h` plus its numerical error
//! is within `--tol·v_ref`, and runs the resolved one otherwise (`M = 0` is
//! always homogenised: a massless body has no resolved dynamics).

use std::f64::consts::TAU;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use model_core::scene::ContactMode;
use serde::Serialize;

use crate::args::{short, Real};
use crate::error::{CliError, CliResult};
use crate::motion::estimate;
use crate::motion::law::Law;
use crate::motion::table::MuTable;
use crate::motion::{homogenised, resolved, Problem, Run};
use crate::output::{stdout_error, write_json, write_rows};
use crate::plot::{render_figure, Corner, Extras, Figure, Mark, Panel, Series};
use crate::scene_args::SceneArgs;
use crate::sweep::progress_bar;

/// Most load periods when running until the periodic regime.
const MAX_PERIODS: u32 = 2000;

/// Domain of the force's mean and amplitude, units of μ0·F̄z: at most ten
/// times the largest force the contact exerts. Beyond it the load, not the
/// contact, moves the body, and the body's speed swings far beyond v_c.
const FORCE_REL: Real = Real::ANY
    .at_least(-10.0)
    .at_most(10.0)
    .because("ten times the contact's largest force μ0·F̄z");

/// Which model integrates the body.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionMethod {
    /// Homogenised where its estimated error is within --tol, resolved otherwise
    Auto,
    /// The averaged law μ(v) as the friction force
    Homogenised,
    /// Body and contact together at the ultrasonic scale
    Resolved,
}

/// Flags of `fricctl motion`.
#[derive(Args, Debug, Clone)]
pub struct MotionCmd {
    #[command(flatten)]
    scene: SceneArgs,
    /// Mass of the body M, kg (0: massless, quasi-static; units k_x/ω² for a dimensionless scene)
    #[arg(long, value_parser = Real::non_negative())]
    mass: f64,
    /// Force amplitude f: F(t) = μ0·F̄z·(f0 + f·sin Ωt), F̄z the mean normal force (|f| ≤ 10)
    #[arg(long, value_parser = FORCE_REL)]
    force_amp_rel: f64,
    /// Angular frequency Ω of the force, rad/s (units of ω for a dimensionless scene)
    #[arg(long, value_parser = Real::positive())]
    force_omega: f64,
    /// Mean force f0, units of μ0·F̄z (|f0| ≤ 10)
    #[arg(long, default_value_t = 0.0, value_parser = FORCE_REL)]
    force_offset_rel: f64,
    /// Stiffness K of a spring tying the body to ground, N/m (units of k_x for a dimensionless scene)
    #[arg(long, default_value_t = 0.0, value_parser = Real::non_negative())]
    spring: f64,
    /// Simulated time, s: whole load periods 2π/Ω (default: until periodic, at most 2000 periods)
    #[arg(long, value_parser = Real::positive())]
    duration: Option<f64>,
    /// Model
    #[arg(long, value_enum, default_value_t = MotionMethod::Auto)]
    method: MotionMethod,
    /// Tolerance on the mean velocity, relative to the larger critical velocity (0 < tol < 1)
    #[arg(long, default_value_t = 1e-3, value_parser = Real::ANY.above(0.0).below(1.0))]
    tol: f64,
    /// Write the trajectory (t, x, v, force, stuck; the last ≤ 50 load periods) to FILE
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Plot velocity and force over the last three load periods to FILE.svg or FILE.png
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// JSON output
    #[arg(long)]
    json: bool,
}

/// The result (`--json` keys; velocities in m/s, units of ωW₀ for a dimensionless scene).
#[derive(Serialize, Debug)]
struct Outcome {
    method: &'static str,
    /// Contact model: flat | lift-off | sphere | cone | power.
    contact: &'static str,
    /// Drift over the last load period, m/s.
    mean_velocity: f64,
    /// Estimated error of mean_velocity, m/s (model + numerics).
    error_estimate: f64,
    /// The larger critical velocity, m/s: the unit of --tol.
    v_ref: f64,
    mean_velocity_over_v_ref: f64,
    error_estimate_over_v_ref: f64,
    /// The homogenised model's estimated error E_h, m/s (also for resolved runs: why auto chose).
    homogenisation_error_estimate: f64,
    /// Numerical error (step halving + period-to-period change), m/s.
    numerical_error: f64,
    stick_fraction: f64,
    /// Arrivals at rest in the homogenised run's last load period (the N of E_h's sticking term).
    stick_onsets: u32,
    periodic: bool,
    periods: u32,
    /// Steps per load period (homogenised) or per ultrasonic period (resolved).
    steps: u64,
    /// Springs of the resolved contact (1: flat punch; a curved profile's MDR bed after doubling); 0 for homogenised runs.
    springs: usize,
    /// ω/Ω.
    scale_separation: f64,
    /// Body's response time M/(largest slope of μ(v)·F̄z), s.
    response_time: f64,
    /// Mω²/k_x.
    mass_rel: f64,
    /// Mean normal force F̄z in units of kz·uz0 (1: permanent contact; ⟨w⁺⟩ with lift-off; D of eq. M5 for a curved profile, kz = 2E*a0).
    fz_mean_over_kz_uz0: f64,
    mu_0plus_over_mu0: f64,
    mu_0minus_over_mu0: f64,
    /// Nodes of the μ(v) table.
    table_nodes: usize,
    /// Interpolation error of the table, units of μ0.
    table_error_over_mu0: f64,
    /// Wall time of the integration, s.
    wall_time: f64,
}

/// One CSV row.
#[derive(Serialize)]
struct Row {
    /// s.
    t: f64,
    /// m.
    x: f64,
    /// m/s.
    v: f64,
    /// Applied force F(t), N.
    force: f64,
    /// 1 while the body is at rest on the contact.
    stuck: u8,
}

/// Most RK4 steps of the homogenised model in one `motion` run, over all its
/// step doublings and load periods (≈ 15 s: a step costs up to ≈ 140 ns,
/// four table look-ups or inversions). A run whose least possible cost
/// exceeds it is refused before it starts, naming the flag that makes it
/// large; the step doubling stops before a run that would exceed it
/// (`Run::stopped_at_work_bound`).
const HOMOGENISED_BUDGET: f64 = 1e8;

/// Most spring steps (steps × springs) of the resolved model in one run
/// (≈ 25 s at ≈ 25 ns each), in the same two ways.
const RESOLVED_BUDGET: f64 = 1e9;

/// An estimate in messages: three significant digits (`2.24e28`).
fn approx(x: f64) -> String {
    format!("{x:.2e}")
}

/// What the run will cost and whether its integrators can resolve it,
/// estimated before it starts (the work bound of issue 28): each refusal
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
    fn check_homogenised(&self, p: &Problem, law: &MuTable) -> CliResult {
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
            return Err(CliError::usage(format!(
                "--mass: the body (Mω²/k_x = {}) follows the load (ω/Ω = {}) so fast that the homogenised model needs ≥ {} steps per load period (max {}); heavier body, slower load or |f0| + |f| < 1",
                short(self.mass),
                short(1.0 / self.nu),
                approx(law_steps / 2.5),
                homogenised::MAX_STEPS
            )));
        }
        let spring_steps = self.spring_steps(p, law);
        if spring_steps > max {
            return Err(CliError::usage(format!(
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
    fn check_resolved(&self, auto: Option<f64>) -> CliResult {
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
            return Err(CliError::usage(format!(
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
    fn too_long(&self, work: f64, budget: f64, subject: &str, flag: &str) -> CliError {
        let how = if flag == "--duration" {
            "give a shorter --duration".to_string()
        } else {
            format!(
                "ω/Ω = {} sets them; try --method homogenised",
                short(1.0 / self.nu)
            )
        };
        CliError::usage(format!(
            "{flag}: {subject} takes ≥ {} steps (work bound {:e}); {how}",
            approx(work),
            budget
        ))
    }
}

impl MotionCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        let scene = rs.scene;
        let prm = *scene.params();
        // Every value is in its domain (the flags' parsers): M, K ≥ 0,
        // Ω > 0, |f|, |f0| ≤ 10, 0 < tol < 1, duration > 0.
        let (mass, f, f0) = (self.mass, self.force_amp_rel, self.force_offset_rel);
        let (big_omega, spring, tol) = (self.force_omega, self.spring, self.tol);
        // Slow dynamics: the load period spans at least two ultrasonic
        // periods (the periodicity tests compare whole load periods; ω/Ω = 10
        // is already where homogenisation fails).
        if big_omega > 0.5 * prm.omega {
            let unit = if rs.dimensionless { "ω" } else { "rad/s" };
            return Err(CliError::usage(format!(
                "--force-omega: {big_omega:e} {unit} is faster than half the vibration's ω = {:e} {unit}; a slow load needs Ω ≤ ω/2",
                prm.omega
            )));
        }
        if let Some(p) = &self.plot {
            crate::plot::ext(p)?;
        }
        crate::output::check_outputs(&[
            (self.plot.as_deref(), "plot"),
            (self.csv.as_deref(), "csv"),
        ])?;
        let load_period = TAU / big_omega;
        let periods = match self.duration {
            None => None,
            Some(t) => {
                let n = (t / load_period).floor();
                if n < 1.0 {
                    return Err(CliError::usage(format!(
                        "--duration: shorter than one load period 2π/Ω = {load_period:e} {}",
                        if rs.dimensionless { "1/ω" } else { "s" }
                    )));
                }
                if n > f64::from(u32::MAX) {
                    return Err(CliError::usage(format!(
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
            .map_err(|e| CliError::failure(e.to_string()))?;
        let p = Problem {
            f0,
            f,
            nu: big_omega / prm.omega,
            mass: mass * prm.omega * prm.omega / prm.kx,
            kappa: spring / prm.kx,
            normal,
        };
        if !p.mass.is_finite() || (mass > 0.0 && p.mass < f64::MIN_POSITIVE) {
            return Err(CliError::usage("--mass: out of range for this scene"));
        }
        if mass == 0.0 && f0.abs() + f.abs() >= 1.0 {
            return Err(CliError::usage(
                "--force-amp-rel: a massless body needs |f0| + |f| < 1 (beyond μ0·F̄z it would run away)",
            ));
        }
        if spring == 0.0 && f0.abs() >= 1.0 {
            return Err(CliError::usage(
                "--force-offset-rel: |f0| >= 1 with no spring: the mean force exceeds μ0·F̄z and the body accelerates without bound",
            ));
        }
        let method = match (self.method, mass == 0.0) {
            (MotionMethod::Resolved, true) => {
                return Err(CliError::usage(
                    "--mass: the resolved model needs a body with mass > 0",
                ))
            }
            (m, _) => m,
        };
        let d = scene.drive();
        let vs = scene.velocity_scale();
        let started = Instant::now();
        let law = MuTable::new(&law_fn, (0.02 * tol).max(1e-9))
            .map_err(|e| CliError::failure(e.to_string()))?;
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
        let pb = progress_bar(
            u64::from(total),
            "motion {bar:40} {pos} load periods integrated (runs of at most {len}, repeated while halving the step)",
        );
        let tick = || pb.inc(1);
        // The homogenised run always comes first: cheap, and it gives the
        // body's acceleration bound K of the estimate.
        let relaxation = crate::motion::relaxation_per_period(&p, estimate::inverse_slope(&law));
        let hs = homogenised::Settings {
            tol: 0.1 * tol_v,
            periods,
            max_periods: MAX_PERIODS,
            relaxation,
            min_steps: plan.spring_steps(&p, &law).ceil() as u64,
            budget: HOMOGENISED_BUDGET as u64,
        };
        let h_run = homogenised::run(&p, &law, &hs, &mut || {
            tick();
        });
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
                    pb.finish_and_clear();
                    return Err(e);
                }
            }
            pb.set_position(0);
            let s = resolved::Settings {
                tol: 0.1 * tol_v,
                periods,
                max_periods: MAX_PERIODS,
                relaxation,
                budget: RESOLVED_BUDGET as u64,
            };
            resolved::run(&p, &d, law_fn.exponent(), &s, &mut || {
                tick();
            })
        };
        pb.finish_and_clear();
        let wall = started.elapsed().as_secs_f64();
        let numerical = run.numerical_error + if use_h { e_table } else { 0.0 };
        let error = numerical + if use_h { e_h } else { 0.0 };
        // No result is ever printed as NaN or infinite with exit 0.
        if !(run.mean_velocity.is_finite() && error.is_finite()) {
            return Err(CliError::failure(format!(
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
        // The results first: a file that cannot be written loses nothing.
        if self.json {
            write_json(out, &o)?;
        } else {
            write_text(out, &o, rs.dimensionless).map_err(stdout_error)?;
        }
        // Forces in N (SI) or in μ0·F̄z (dimensionless, as the text output).
        let fz = if rs.dimensionless {
            1.0
        } else {
            prm.mu0 * prm.kz * prm.uz0 * p.normal
        };
        if let Some(path) = &self.csv {
            let rows: Vec<Row> = run
                .trajectory
                .iter()
                .map(|s| Row {
                    t: s.t / big_omega,
                    x: s.x * scene.w0(),
                    v: s.v * vs,
                    force: s.force * fz,
                    stuck: u8::from(s.stuck),
                })
                .collect();
            write_rows(path, &rows)?;
        }
        if let Some(path) = &self.plot {
            let g = scene.groups();
            let caption = vec![
                if rs.dimensionless {
                    format!(
                        "{} contact: Δu_z/u_z0 = {:.4}, k_xΔu_x/(μ0k_z u_z0) = {:.4}, φ = {:.1}°; Mω²/k_x = {:.4e}, ω/Ω = {:.4e}, K/k_x = {:.4e}",
                        o.contact, g.duz_rel, g.dux_rel, g.phi.to_degrees(), o.mass_rel, o.scale_separation, p.kappa
                    )
                } else {
                    format!(
                        "{} contact: μ0 = {}, k_z = {:e} N/m, k_x = {:e} N/m, u_z0 = {:e} m, Δu_z = {:e} m, Δu_x = {:e} m, ω/2π = {:e} Hz, φ = {:.1}°",
                        o.contact, prm.mu0, prm.kz, prm.kx, prm.uz0, prm.duz, prm.dux, prm.omega / TAU, prm.phi.to_degrees()
                    )
                },
                if rs.dimensionless {
                    format!(
                        "F = μ0F̄z·(f0 + f sin Ωt), f0 = {f0}, f = {f}; F̄z = {:.5} k_z u_z0; forces in μ0F̄z, velocities in ωW0",
                        p.normal
                    )
                } else {
                    format!(
                        "M = {mass:e} kg, Ω = {big_omega:e} rad/s, K = {:e} N/m; F = μ0F̄z·(f0 + f sin Ωt), f0 = {f0}, f = {f}, F̄z = {:.5e} N",
                        self.spring, prm.kz * prm.uz0 * p.normal
                    )
                },
            ];
            plot(
                path,
                &run,
                &o,
                big_omega,
                vs,
                fz,
                &law,
                rs.dimensionless,
                caption,
            )?;
        }
        if !run.periodic {
            return Err(CliError::failure(format!(
                "no periodic regime after {} load periods: mean_velocity is the last period's, not the drift",
                run.periods
            )));
        }
        if o.error_estimate_over_v_ref > tol {
            return Err(CliError::failure(format!(
                "estimated error {:.3e} v_ref exceeds --tol {tol:e}{}",
                o.error_estimate_over_v_ref,
                if run.stopped_at_work_bound {
                    " (the refinement stopped at the work bound)"
                } else if use_h && mass > 0.0 {
                    " (try --method resolved)"
                } else {
                    ""
                }
            )));
        }
        Ok(())
    }
}

fn write_text(out: &mut impl Write, o: &Outcome, dimless: bool) -> std::io::Result<()> {
    let (v, s) = if dimless {
        ("ωW0", "1/ω")
    } else {
        ("m/s", "s")
    };
    writeln!(out, "method                 {}", o.method)?;
    writeln!(out, "contact                {}", o.contact)?;
    writeln!(out, "mean velocity          {:.6e} {v}", o.mean_velocity)?;
    writeln!(out, "error estimate         {:.3e} {v}", o.error_estimate)?;
    writeln!(
        out,
        "  homogenisation       {:.3e} {v}",
        o.homogenisation_error_estimate
    )?;
    writeln!(out, "  numerical            {:.3e} {v}", o.numerical_error)?;
    writeln!(out, "v_ref (max v_c)        {:.6e} {v}", o.v_ref)?;
    writeln!(
        out,
        "mean velocity / v_ref  {:.6}",
        o.mean_velocity_over_v_ref
    )?;
    writeln!(out, "stick fraction         {:.4}", o.stick_fraction)?;
    writeln!(
        out,
        "arrivals at rest       {} per load period (homogenised)",
        o.stick_onsets
    )?;
    writeln!(out, "periodic               {}", o.periodic)?;
    writeln!(out, "load periods           {}", o.periods)?;
    writeln!(out, "steps                  {}", o.steps)?;
    writeln!(out, "ω/Ω                    {:.4e}", o.scale_separation)?;
    writeln!(out, "response time          {:.3e} {s}", o.response_time)?;
    writeln!(out, "Mω²/k_x                {:.4e}", o.mass_rel)?;
    writeln!(
        out,
        "static band            [{:.6}, {:.6}] μ0·F̄z",
        o.mu_0minus_over_mu0, o.mu_0plus_over_mu0
    )?;
    writeln!(
        out,
        "μ(v) table             {} nodes, error {:.2e} μ0",
        o.table_nodes, o.table_error_over_mu0
    )?;
    writeln!(out, "wall time              {:.3} s", o.wall_time)
}

#[allow(clippy::too_many_arguments)]
fn plot(
    path: &std::path::Path,
    run: &Run,
    o: &Outcome,
    big_omega: f64,
    vs: f64,
    fz: f64,
    law: &MuTable,
    dimless: bool,
    caption: Vec<String>,
) -> CliResult {
    // The last (at most three) load periods of the recorded trajectory.
    let last = run.trajectory.last().map_or(0.0, |s| s.t);
    let from = last - 3.0 * TAU;
    let pts: Vec<_> = run.trajectory.iter().filter(|s| s.t >= from).collect();
    let t_of = |t: f64| t / big_omega;
    let (t0, t1) = (
        pts.first().map_or(0.0, |s| t_of(s.t)),
        pts.last().map_or(1.0, |s| t_of(s.t)),
    );
    let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
    let vel: Vec<(f64, f64)> = pts.iter().map(|s| (t_of(s.t), s.v * vs)).collect();
    let force: Vec<(f64, f64)> = pts.iter().map(|s| (t_of(s.t), s.force * fz)).collect();
    let stuck: Vec<(f64, f64)> = pts
        .iter()
        .filter(|s| s.stuck)
        .map(|s| (t_of(s.t), 0.0))
        .collect();
    // The data's range, with room above it for the legend.
    let span = |v: &[(f64, f64)], extra: &[f64]| {
        let (lo, hi) = v
            .iter()
            .map(|p| p.1)
            .chain(extra.iter().copied())
            .filter(|y| y.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
                (a.min(y), b.max(y))
            });
        let r = (hi - lo).max(1e-300);
        (lo - 0.08 * r, hi + 0.6 * r)
    };
    let (tu, vu, fu) = if dimless {
        ("t, 1/ω", "v, ωW0", "F, μ0·F̄z")
    } else {
        ("t, s", "v, m/s", "F, N")
    };
    let band = [law.mu_0plus * fz, law.mu_0minus * fz];
    let mut v_series = vec![
        Series {
            label: "velocity".into(),
            points: vel,
            mark: Mark::Line,
            color: 0,
        },
        Series {
            label: format!("mean (drift) {:.4e}", o.mean_velocity),
            points: vec![(t0, o.mean_velocity), (t1, o.mean_velocity)],
            mark: Mark::Dashed,
            color: 1,
        },
    ];
    if !stuck.is_empty() {
        v_series.push(Series {
            label: format!("stuck ({:.1} % of a period)", 100.0 * o.stick_fraction),
            points: stuck,
            mark: Mark::Points,
            color: 2,
        });
    }
    let mut f_series = vec![Series {
        label: "applied force F(t)".into(),
        points: force,
        mark: Mark::Line,
        color: 0,
    }];
    let f_range = f_series[0]
        .points
        .iter()
        .map(|p| p.1.abs())
        .fold(band[0].abs().max(band[1].abs()), f64::max);
    if band[0] == band[1] {
        // Lift-off: μ(0) is unique.
        f_series.push(Series {
            label: format!("μ(0)·F̄z = {:.4e} (unique with lift-off)", band[0]),
            points: vec![(t0, band[0]), (t1, band[0])],
            mark: Mark::Dashed,
            color: 1,
        });
    } else if (band[0] - band[1]).abs() < 1e-3 * f_range {
        // Two lines the eye cannot tell apart: one, with both values.
        f_series.push(Series {
            label: format!("μ(0⁺)·F̄z = {:.6e} ≈ μ(0⁻)·F̄z = {:.6e}", band[0], band[1]),
            points: vec![(t0, band[0]), (t1, band[0])],
            mark: Mark::Dashed,
            color: 1,
        });
    } else {
        f_series.push(Series {
            label: format!("μ(0⁺)·F̄z = {:.4e}", band[0]),
            points: vec![(t0, band[0]), (t1, band[0])],
            mark: Mark::Dashed,
            color: 1,
        });
        f_series.push(Series {
            label: format!("μ(0⁻)·F̄z = {:.4e}", band[1]),
            points: vec![(t0, band[1]), (t1, band[1])],
            mark: Mark::Dashed,
            color: 3,
        });
    }
    let y_v = span(&v_series[0].points, &[0.0, o.mean_velocity]);
    let y_f = span(&f_series[0].points, &band);
    let extras = Extras {
        legend_at: Corner::UpperRight,
        ..Extras::default()
    };
    let panels = vec![
        (
            Panel {
                title: format!("{} body: velocity over the last load periods", o.method),
                x_label: tu.to_string(),
                y_label: vu.to_string(),
                x: (t0, t1),
                y: y_v,
                series: v_series,
            },
            extras.clone(),
        ),
        (
            Panel {
                title: "applied force and the static band".into(),
                x_label: tu.to_string(),
                y_label: fu.to_string(),
                x: (t0, t1),
                y: y_f,
                series: f_series,
            },
            extras,
        ),
    ];
    render_figure(
        path,
        &Figure {
            panels,
            rows: 2,
            cols: 1,
            size: (1100, 860),
            legend: Vec::new(),
            caption,
        },
    )?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
