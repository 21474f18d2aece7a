//! `fricctl tune`: inverse design on the host — the drive value (Δu_z, Δu_x or
//! φ) that attains a target μ at a sliding velocity, or that maximises the
//! ratchet's asymmetry or the forward stall force, within stated limits
//! (model-core `model::inverse`).
//!
//! Search: the exact law on a scan of [`SCAN_CELLS`] cells of the adjusted
//! quantity, every local extremum refined by golden section, Illinois regula
//! falsi on each monotone piece that straddles the target. All solutions are
//! listed; the one nearest the scene's own value of the adjusted quantity is
//! reported as *the* result (the scene value is only that starting point).

use std::io::Write;

use clap::{ArgGroup, Args, ValueEnum};
use model_core::analytic::StaticFriction;
use model_core::exact;
use model_core::model::inverse::{self, InverseError, Knob, Objective, Point, Problem};
use model_core::regime::{classify_drive, ClassifyOptions};
use model_core::{Libm, Scene};
use serde::Serialize;

use crate::args::{short, Real, Short};
use crate::error::{CliError, CliResult};
use crate::eval::{critical_velocity, exact_failure, from_rel};
use crate::output::{stdout_error, write_json};
use crate::scene_args::{check_reach, ResolvedScene, SceneArgs};

/// The exit statuses of `fricctl tune`, shown by its `--help`.
const EXIT_STATUS: &str = "Exit status: 0 a solution (or maximum) within the solver's bound; 1 the result is printed but doubtful (its residual exceeds the solver's bound), or the solver failed; 2 bad input, including a target out of reach and a --maximize with no feasible drive (every drive in the range an actuator, or none pushes forward).";

/// Cells of the scan of the adjusted quantity (the phase: 360°/256 = 1.41° per cell).
pub const SCAN_CELLS: usize = 256;

/// Default largest Δu_x in units of W0 = μ0 k_z u_z0/k_x (`k_xΔu_x/(μ0k_z u_z0) ≤ 10`).
pub const DEFAULT_MAX_DUX_REL: f64 = 10.0;

/// The adjusted drive quantity.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Adjust {
    /// Normal amplitude Δu_z, from 0 to --max-duz
    Duz,
    /// Tangential amplitude Δu_x, from 0 to --max-dux
    Dux,
    /// Phase φ, over [0°, 360°)
    Phase,
}

/// What `--maximize` maximises.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Maximize {
    /// Ratchet asymmetry max|μ(v)+μ(−v)|/μ0 (as `fricctl classify`), over the drives that are not actuators
    Asymmetry,
    /// Forward stall force −μ(0⁺)/μ0, units of μ0·kz·uz0
    StallForce,
}

/// Flags of `fricctl tune`.
#[derive(Args, Debug, Clone)]
#[command(after_help = EXIT_STATUS)]
#[command(group(ArgGroup::new("goal").multiple(false).args(["target_mu_rel", "target_mu", "maximize"])))]
pub struct TuneCmd {
    #[command(flatten)]
    scene: SceneArgs,
    /// Sliding velocity v0, m/s (units of ωW0 for a dimensionless scene); needed with a target (or --v-rel)
    #[arg(long, value_parser = Real::ANY, conflicts_with = "v_rel")]
    v0: Option<f64>,
    /// Velocity relative to v_c of the scene as given (before the adjustment): v0 = X·v_c (forward v_c for X > 0, backward for X < 0)
    #[arg(long, value_parser = Real::ANY, value_name = "X")]
    v_rel: Option<f64>,
    /// Target μ/μ0, strictly between −1 and 1
    #[arg(long, value_name = "T", value_parser = Real::ANY.above(-1.0).below(1.0).because("mu/mu0 lies strictly inside (−1, 1): |mu| = mu0 is continuous sliding"))]
    target_mu_rel: Option<f64>,
    /// Target μ, strictly between −μ0 and μ0
    #[arg(long, value_name = "X", value_parser = Real::ANY)]
    target_mu: Option<f64>,
    /// Maximise an objective over the adjusted quantity instead of meeting a target
    #[arg(long, value_enum, value_name = "OBJECTIVE")]
    maximize: Option<Maximize>,
    /// The drive quantity to adjust (the scene's own value of it picks the reported solution: the nearest)
    #[arg(long, value_enum)]
    adjust: Adjust,
    /// Largest Δu_z, m (default and upper limit: (1 − liftoff-margin)·uz0)
    #[arg(long, value_name = "M", value_parser = Real::positive())]
    max_duz: Option<f64>,
    /// Largest Δu_x, m (default 10·W0 = 10·μ0·kz·uz0/kx)
    #[arg(long, value_name = "M", value_parser = Real::positive())]
    max_dux: Option<f64>,
    /// Lift-off margin m: every drive keeps Δu_z ≤ (1 − m)·uz0
    #[arg(
        long,
        default_value_t = 0.05,
        value_name = "M",
        value_parser = Real::ANY.above(0.0).below(1.0)
    )]
    liftoff_margin: f64,
    /// JSON output
    #[arg(long)]
    json: bool,
}

/// The drive a result stands for, and the search it came from (JSON keys are
/// part of the CLI contract; shared by both kinds of result).
#[derive(Serialize, Debug, Clone)]
struct DriveOut {
    /// `duz`, `dux` or `phase`.
    adjust: &'static str,
    /// Δu_z, m.
    duz: f64,
    /// Δu_x, m.
    dux: f64,
    /// φ, degrees in [0, 360).
    phi_deg: f64,
    /// Δu_z/u_z0.
    duz_rel: f64,
    /// k_xΔu_x/(μ0 k_z u_z0).
    dux_rel: f64,
    /// Lower end of the search range of the adjusted quantity (m, or deg).
    range_lo: f64,
    /// Upper end (m, or deg; 360 for the phase).
    range_hi: f64,
    /// Cells of the scan.
    scan_cells: usize,
}

/// The JSON document of a target search.
#[derive(Serialize, Debug)]
struct TargetOut {
    #[serde(flatten)]
    drive: DriveOut,
    /// Sliding velocity, m/s.
    v0: f64,
    /// Target μ.
    target_mu: f64,
    /// Target μ/μ0.
    target_mu_over_mu0: f64,
    /// μ at the reported drive (exact solver).
    mu: f64,
    /// μ/μ0 at the reported drive.
    mu_over_mu0: f64,
    /// `mu_over_mu0 − target_mu_over_mu0`.
    residual_over_mu0: f64,
    /// Always `exact`.
    method: &'static str,
    /// The exact solver's bound on `mu_over_mu0`, units of μ0.
    error_bound_over_mu0: f64,
    /// Every solution, in the adjusted quantity's unit (m, or deg).
    solutions: Vec<f64>,
    /// Solutions found (more than listed if above 16).
    solutions_found: u32,
    /// The scene's value of the adjusted quantity (the reported solution is the nearest).
    start: f64,
    /// Least μ/μ0 over the range (attained).
    reachable_min_over_mu0: f64,
    /// Greatest μ/μ0 over the range (attained).
    reachable_max_over_mu0: f64,
}

/// The JSON document of a maximisation.
#[derive(Serialize, Debug)]
struct MaximizeOut {
    #[serde(flatten)]
    drive: DriveOut,
    /// `asymmetry` or `stall_force`.
    objective: &'static str,
    /// The objective's value at the reported drive (units of μ0, resp. μ0·F̄z).
    value: f64,
    /// Bound on `value`, units of μ0 (two exact-solver bounds for the asymmetry, one for the stall force).
    error_bound_over_mu0: f64,
    /// Regime of the reported drive.
    regime: &'static str,
    /// max|μ(v)+μ(−v)|/μ0 at the reported drive.
    asymmetry: f64,
    /// −μ(0⁺)/μ0 when positive, else 0 (units μ0·kz·uz0).
    stall_force_forward: f64,
    /// lim μ/μ0 as v0 → 0⁺.
    mu_0plus_over_mu0: f64,
    /// lim μ/μ0 as v0 → 0⁻.
    mu_0minus_over_mu0: f64,
}

/// A validated request.
struct Setup {
    scene: Scene<f64>,
    problem: Problem<f64>,
    /// Length of one dimensionless unit of the knob: u_z0 (duz), W0 (dux), 1 rad (phase).
    unit: f64,
}

impl TuneCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve()?;
        let setup = self.setup(&rs)?;
        match (self.target_mu_rel, self.target_mu, self.maximize) {
            (Some(t), None, None) => self.target(out, &setup, &rs, t, "target-mu-rel"),
            (None, Some(x), None) => {
                let mu0 = setup.scene.mu0();
                if x.abs() >= mu0 {
                    return Err(CliError::usage(format!(
                        "--target-mu: {} must lie strictly inside (−{m}, {m}) (|mu| = mu0 is continuous sliding)",
                        short(x),
                        m = short(mu0)
                    )));
                }
                self.target(out, &setup, &rs, x / mu0, "target-mu")
            }
            (None, None, Some(m)) => self.maximize(out, &setup, m),
            _ => Err(CliError::usage(
                "--target-mu-rel: missing (give --target-mu-rel, --target-mu or --maximize)",
            )),
        }
    }

    fn setup(&self, rs: &ResolvedScene) -> CliResult<Setup> {
        let scene = rs.scene;
        // Every flag is in its domain (the parsers): 0 < margin < 1, limits > 0.
        let m = self.liftoff_margin;
        let p = scene.params();
        let limit = (1.0 - m) * p.uz0;
        let g = scene.groups();
        let (max_duz, max_dux) = (self.max_duz, self.max_dux);
        if self.adjust != Adjust::Duz && max_duz.is_some() {
            return Err(CliError::usage("--max-duz: only with --adjust duz"));
        }
        if self.adjust != Adjust::Dux && max_dux.is_some() {
            return Err(CliError::usage("--max-dux: only with --adjust dux"));
        }
        if self.adjust != Adjust::Duz && p.duz > limit {
            let (name, unit) = if rs.dimensionless {
                ("duz-rel", "")
            } else {
                ("duz", " m")
            };
            let flag = rs.given.duz;
            return Err(CliError::usage(format!(
                "{flag}: {name} = {}{unit} is above the lift-off limit (1 − liftoff-margin)·uz0 = {}{unit}",
                short(p.duz),
                short(limit)
            )));
        }
        let (knob, hi, unit) = match self.adjust {
            Adjust::Duz => {
                let hi = max_duz.unwrap_or(limit);
                if hi > limit {
                    return Err(CliError::usage(format!(
                        "--max-duz: {} m is above the lift-off limit (1 − liftoff-margin)·uz0 = {} m",
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
            .map_err(|e| CliError::usage(format!("--max-{}: {e}", knob.name())))?;
        Ok(Setup {
            scene,
            problem,
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

    fn target(
        &self,
        out: &mut impl Write,
        s: &Setup,
        rs: &ResolvedScene,
        t: f64,
        flag: &str,
    ) -> CliResult {
        let (v0, vflag) =
            match (self.v0, self.v_rel) {
                (Some(v), None) => (v, "--v0"),
                (None, Some(x)) => (
                    from_rel(&critical_velocity(&rs.scene)?, x, "v-rel")?,
                    "--v-rel",
                ),
                _ => return Err(CliError::usage(
                    "--v0: missing (a target mu is at a sliding velocity; give --v0 or --v-rel)",
                )),
            };
        if v0 == 0.0 {
            return Err(CliError::usage(format!(
                "{vflag}: must be != 0 for a target (at rest mu is not unique; see `fricctl static`)"
            )));
        }
        let mu0 = s.scene.mu0();
        let v = rs.velocity(v0, vflag)?;
        let mut scan = vec![0.0; self.scan_points()];
        let r = match inverse::solve_target::<f64, Libm>(&s.problem, v, t, &mut scan) {
            Ok(r) => r,
            Err(InverseError::OutOfReach { min, max }) => {
                let (lo, hi) = s.problem.range();
                let scale = if flag == "target-mu" { mu0 } else { 1.0 };
                let unit = if self.adjust == Adjust::Phase {
                    "deg"
                } else {
                    "m"
                };
                return Err(CliError::usage(format!(
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
            .ok_or_else(|| CliError::failure("tune: no solution kept (internal)"))?;
        let bound = s.problem.bound_at::<Libm>(best.x);
        let o = TargetOut {
            drive: self.drive_out(s, best.x),
            v0,
            target_mu: t * mu0,
            target_mu_over_mu0: t,
            mu: best.value * mu0,
            mu_over_mu0: best.value,
            residual_over_mu0: best.value - t,
            method: "exact",
            error_bound_over_mu0: bound,
            solutions: r.solutions.iter().map(|q| self.shown(s, q.x)).collect(),
            solutions_found: r.found,
            start: self.shown(s, start),
            reachable_min_over_mu0: r.min.value,
            reachable_max_over_mu0: r.max.value,
        };
        finish_target(out, &o, self.json)
    }

    fn maximize(&self, out: &mut impl Write, s: &Setup, m: Maximize) -> CliResult {
        if self.v0.is_some() || self.v_rel.is_some() {
            let flag = if self.v0.is_some() { "--v0" } else { "--v-rel" };
            return Err(CliError::usage(format!(
                "{flag}: not used by --maximize (the asymmetry and the stall force are properties of the whole law)"
            )));
        }
        let objective = match m {
            Maximize::Asymmetry => Objective::Asymmetry,
            Maximize::StallForce => Objective::StallForce,
        };
        let mut scan = vec![0.0; self.scan_points()];
        let best = match inverse::maximize::<f64, Libm>(&s.problem, objective, &mut scan) {
            Ok(b) => b,
            Err(InverseError::Infeasible) => {
                return Err(CliError::usage(format!(
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
            return Err(CliError::usage(format!(
                "--maximize: the contact never pushes forward with {} in its range (largest −mu(0+)/mu0 = {})",
                s.problem.knob().name(),
                short(best.value)
            )));
        }
        let o = self.maximize_out(s, best, name, m)?;
        if self.json {
            write_json(out, &o)
        } else {
            write_maximize_text(out, &o).map_err(stdout_error)
        }
    }

    fn maximize_out(
        &self,
        s: &Setup,
        best: Point<f64>,
        name: &'static str,
        m: Maximize,
    ) -> CliResult<MaximizeOut> {
        let d = s.problem.drive_at::<Libm>(best.x);
        let scene = Scene::dimensionless(s.problem.groups_at(best.x))
            .map_err(|e| CliError::failure(format!("tune: {e}")))?;
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

/// Prints a target's result, then judges it: a residual above the solver's
/// bound is reported (exit 1, the result still printed: it is the best the
/// search found, but not within the stated bound).
fn finish_target(out: &mut impl Write, o: &TargetOut, json: bool) -> CliResult {
    if json {
        write_json(out, o)?;
    } else {
        write_target_text(out, o).map_err(stdout_error)?;
    }
    let bound = o.error_bound_over_mu0;
    if o.residual_over_mu0.abs() > bound {
        return Err(CliError::failure(format!(
            "doubtful: the residual {:e} exceeds the solver's bound {bound:e} (the law is steeper than the float type resolves here)",
            o.residual_over_mu0
        )));
    }
    Ok(())
}

fn wrap_deg(d: f64) -> f64 {
    let w = d.rem_euclid(360.0);
    if w >= 360.0 {
        0.0
    } else {
        w
    }
}

fn inverse_failure(e: InverseError<f64>) -> CliError {
    match e {
        InverseError::Exact(x) => exact_failure(x),
        other => CliError::failure(format!("tune: {other}")),
    }
}

/// A value of the adjusted quantity as text: metres in `e` notation, degrees plain.
fn knob_text(adjust: &str, x: f64) -> String {
    if adjust == "phase" || x == 0.0 {
        short(x)
    } else {
        format!("{x:e}")
    }
}

fn unit_of(adjust: &str) -> &'static str {
    if adjust == "phase" {
        "deg"
    } else {
        "m"
    }
}

fn write_drive(out: &mut impl Write, d: &DriveOut) -> std::io::Result<()> {
    writeln!(
        out,
        "duz             {:e} m   (duz/uz0 = {})",
        d.duz,
        Short(d.duz_rel)
    )?;
    writeln!(
        out,
        "dux             {:e} m   (kx·dux/(mu0·kz·uz0) = {})",
        d.dux,
        Short(d.dux_rel)
    )?;
    writeln!(out, "phi             {} deg", Short(d.phi_deg))
}

fn write_target_text(out: &mut impl Write, o: &TargetOut) -> std::io::Result<()> {
    let unit = unit_of(o.drive.adjust);
    writeln!(out, "adjust          {}", o.drive.adjust)?;
    writeln!(out, "v0              {} m/s", Short(o.v0))?;
    writeln!(
        out,
        "target          mu = {}   (mu/mu0 = {})",
        Short(o.target_mu),
        Short(o.target_mu_over_mu0)
    )?;
    write_drive(out, &o.drive)?;
    writeln!(
        out,
        "mu              {}   (mu/mu0 = {})",
        Short(o.mu),
        Short(o.mu_over_mu0)
    )?;
    writeln!(
        out,
        "residual        {:e} (units of mu0)",
        o.residual_over_mu0
    )?;
    writeln!(
        out,
        "error bound     {:e} (units of mu0, method {})",
        o.error_bound_over_mu0, o.method
    )?;
    let list: Vec<String> = o
        .solutions
        .iter()
        .map(|&x| knob_text(o.drive.adjust, x))
        .collect();
    writeln!(
        out,
        "solutions       {}: {} {unit}   (reported: the nearest to the scene's {} = {} {unit})",
        o.solutions_found,
        list.join(", "),
        o.drive.adjust,
        knob_text(o.drive.adjust, o.start)
    )?;
    writeln!(
        out,
        "reachable       mu/mu0 {} … {}",
        Short(o.reachable_min_over_mu0),
        Short(o.reachable_max_over_mu0)
    )?;
    writeln!(
        out,
        "search          {} in [{}, {}] {unit}, {} cells, extrema refined",
        o.drive.adjust,
        knob_text(o.drive.adjust, o.drive.range_lo),
        knob_text(o.drive.adjust, o.drive.range_hi),
        o.drive.scan_cells
    )
}

fn write_maximize_text(out: &mut impl Write, o: &MaximizeOut) -> std::io::Result<()> {
    let unit = unit_of(o.drive.adjust);
    writeln!(out, "adjust          {}", o.drive.adjust)?;
    writeln!(out, "maximize        {}", o.objective)?;
    writeln!(
        out,
        "value           {}   (bound {:e}, units of {})",
        Short(o.value),
        o.error_bound_over_mu0,
        if o.objective == "asymmetry" {
            "mu0"
        } else {
            "mu0·kz·uz0"
        }
    )?;
    write_drive(out, &o.drive)?;
    writeln!(out, "regime          {}", o.regime)?;
    writeln!(out, "asymmetry       {}", Short(o.asymmetry))?;
    writeln!(
        out,
        "stall force     {} (units of mu0·kz·uz0, forward)",
        Short(o.stall_force_forward)
    )?;
    writeln!(out, "mu(0+)/mu0      {}", Short(o.mu_0plus_over_mu0))?;
    writeln!(out, "mu(0-)/mu0      {}", Short(o.mu_0minus_over_mu0))?;
    writeln!(
        out,
        "search          {} in [{}, {}] {unit}, {} cells, maxima refined",
        o.drive.adjust,
        knob_text(o.drive.adjust, o.drive.range_lo),
        knob_text(o.drive.adjust, o.drive.range_hi),
        o.drive.scan_cells
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A target result with `residual` against the bound 1e-9.
    fn result(residual: f64) -> TargetOut {
        TargetOut {
            drive: DriveOut {
                adjust: "duz",
                duz: 1e-6,
                dux: 7e-7,
                phi_deg: 50.0,
                duz_rel: 0.2,
                dux_rel: 0.35,
                range_lo: 0.0,
                range_hi: 4.75e-6,
                scan_cells: SCAN_CELLS,
            },
            v0: 0.01,
            target_mu: 0.15,
            target_mu_over_mu0: 0.5,
            mu: 0.15 + 0.3 * residual,
            mu_over_mu0: 0.5 + residual,
            residual_over_mu0: residual,
            method: "exact",
            error_bound_over_mu0: 1e-9,
            solutions: vec![1e-6],
            solutions_found: 1,
            start: 2e-6,
            reachable_min_over_mu0: -0.1,
            reachable_max_over_mu0: 0.7,
        }
    }

    /// Issue 24 §9: the "doubtful residual" path (never observed with the
    /// exact solver) prints the result and exits 1 with one line; a residual
    /// within the bound exits 0.
    #[test]
    fn doubtful_residual_prints_and_fails() {
        for json in [false, true] {
            let mut out = Vec::new();
            let e = finish_target(&mut out, &result(3e-9), json).unwrap_err();
            assert_eq!(e.code, 1);
            assert_eq!(
                e.msg,
                "doubtful: the residual 3e-9 exceeds the solver's bound 1e-9 (the law is steeper than the float type resolves here)"
            );
            let text = String::from_utf8(out).unwrap();
            assert!(text.contains("3e-9"), "{text}");
            let mut out = Vec::new();
            assert!(finish_target(&mut out, &result(5e-10), json).is_ok());
            assert!(!out.is_empty());
        }
    }
}
