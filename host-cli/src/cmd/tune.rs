//! `fricctl tune`: inverse design on the host — the flags and the output of
//! [`fric_analysis::tune`] (the drive value that attains a target μ, or that
//! maximises the ratchet's asymmetry or the forward stall force).

use std::io::Write;

use clap::{ArgGroup, Args, ValueEnum};
use fric_analysis::tune::{
    self, knob_text, DriveOut, MaximizeOut, TargetOut, TuneOutcome, TuneRequest,
};

use model_core::scene::ContactMode;

use crate::args::{round_up_sig, Real, Rounded, Short};
use crate::error::CliResult;
use crate::output::{stdout_error, write_json};
use crate::scene_args::SceneArgs;

/// The exit statuses of `fricctl tune`, shown by its `--help`.
const EXIT_STATUS: &str = "Exit status: 0 a solution (or maximum) within the solver's bound; 1 the result is printed but doubtful (its residual exceeds the solver's bound), or the solver failed; 2 bad input, including a target out of reach and a --maximize with no feasible drive (every drive in the range an actuator, or none pushes forward).";

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
    #[arg(long, value_name = "T", value_parser = Real(tune::TARGET_MU_REL))]
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
        value_parser = Real(tune::LIFTOFF_MARGIN)
    )]
    liftoff_margin: f64,
    /// JSON output
    #[arg(long)]
    json: bool,
}

impl TuneCmd {
    /// The library's request for these flags.
    fn request(&self) -> TuneRequest {
        TuneRequest {
            v0: self.v0,
            v_rel: self.v_rel,
            target_mu_rel: self.target_mu_rel,
            target_mu: self.target_mu,
            maximize: self.maximize.map(|m| match m {
                Maximize::Asymmetry => tune::Maximize::Asymmetry,
                Maximize::StallForce => tune::Maximize::StallForce,
            }),
            adjust: match self.adjust {
                Adjust::Duz => tune::Adjust::Duz,
                Adjust::Dux => tune::Adjust::Dux,
                Adjust::Phase => tune::Adjust::Phase,
            },
            max_duz: self.max_duz,
            max_dux: self.max_dux,
            liftoff_margin: self.liftoff_margin,
        }
    }

    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        // The flat punch or a curved profile (its MDR quadrature), the
        // contact pressed throughout (the centre, for a profile).
        let rs = self.scene.resolve_with(ContactMode::Permanent)?;
        let u = Units::of(rs.dimensionless);
        match tune::tune(&rs, &self.request())? {
            TuneOutcome::Target(o) => finish_target(out, &o, self.json, u),
            TuneOutcome::Maximize(o) => {
                if self.json {
                    write_json(out, &o)
                } else {
                    write_maximize_text(out, &o, u).map_err(stdout_error)
                }
            }
        }
    }
}

/// Prints a target's result, then judges it: a residual above the solver's
/// bound is reported (exit 1, the result still printed: it is the best the
/// search found, but not within the stated bound).
fn finish_target(out: &mut impl Write, o: &TargetOut, json: bool, u: Units) -> CliResult {
    if json {
        write_json(out, o)?;
    } else {
        write_target_text(out, o, u).map_err(stdout_error)?;
    }
    match o.doubtful() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Units of the text output: SI, or for a scene given by its dimensionless
/// groups (eqs. 25/26: μ0 = kz = kx = uz0 = ω = 1) the groups' own units —
/// lengths in uz0 (= W0 = μ0·kz·uz0/kx there), velocities in ωW0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Units {
    /// Whether the scene is dimensionless.
    dimensionless: bool,
}

impl Units {
    fn of(dimensionless: bool) -> Self {
        Units { dimensionless }
    }

    /// The unit of an adjusted quantity's values (after the number).
    fn knob(self, adjust: &str) -> &'static str {
        match (adjust, self.dimensionless) {
            ("phase", _) => " deg",
            ("duz", true) => " uz0",
            (_, true) => " W0",
            _ => " m",
        }
    }

    /// The unit of v0.
    fn velocity(self) -> &'static str {
        if self.dimensionless {
            "ωW0 (dimensionless scene)"
        } else {
            "m/s"
        }
    }
}

fn write_drive(out: &mut impl Write, d: &DriveOut, u: Units) -> std::io::Result<()> {
    if d.profile != "flat" {
        // uz0 is the mean indentation d0 and kz/kx is E*/G* (MDR).
        writeln!(
            out,
            "profile         {} (MDR quadrature over the springs; uz0 = mean indentation d0)",
            profile_name(d)
        )?;
    }
    if u.dimensionless {
        // duz/uz0 and kx·dux/(mu0·kz·uz0) are duz and dux themselves.
        writeln!(
            out,
            "duz             {} uz0   (duz/uz0, dimensionless)",
            Rounded(d.duz_rel)
        )?;
        writeln!(
            out,
            "dux             {} W0   (kx·dux/(mu0·kz·uz0), dimensionless)",
            Rounded(d.dux_rel)
        )?;
    } else {
        writeln!(
            out,
            "duz             {} m   (duz/uz0 = {})",
            Rounded(d.duz),
            Rounded(d.duz_rel)
        )?;
        writeln!(
            out,
            "dux             {} m   (kx·dux/(mu0·kz·uz0) = {})",
            Rounded(d.dux),
            Rounded(d.dux_rel)
        )?;
    }
    writeln!(out, "phi             {} deg", Rounded(d.phi_deg))
}

fn write_target_text(out: &mut impl Write, o: &TargetOut, u: Units) -> std::io::Result<()> {
    let unit = u.knob(o.drive.adjust);
    writeln!(out, "adjust          {}", o.drive.adjust)?;
    writeln!(out, "v0              {} {}", Rounded(o.v0), u.velocity())?;
    writeln!(
        out,
        "target          mu = {}   (mu/mu0 = {})",
        Rounded(o.target_mu),
        Rounded(o.target_mu_over_mu0)
    )?;
    write_drive(out, &o.drive, u)?;
    writeln!(
        out,
        "mu              {}   (mu/mu0 = {})",
        Rounded(o.mu),
        Rounded(o.mu_over_mu0)
    )?;
    writeln!(
        out,
        "residual        {} (units of mu0)",
        Short(round_up_sig(o.residual_over_mu0.abs(), 3).copysign(o.residual_over_mu0))
    )?;
    writeln!(
        out,
        "error bound     {} (units of mu0, method {})",
        Short(round_up_sig(o.error_bound_over_mu0, 3)),
        o.method
    )?;
    let list: Vec<String> = o
        .solutions
        .iter()
        .map(|&x| knob_text(o.drive.adjust, x))
        .collect();
    writeln!(
        out,
        "solutions       {}: {}{unit}   (reported: the nearest to the scene's {} = {}{unit})",
        o.solutions_found,
        list.join(", "),
        o.drive.adjust,
        knob_text(o.drive.adjust, o.start)
    )?;
    writeln!(
        out,
        "reachable       mu/mu0 {} … {}",
        Rounded(o.reachable_min_over_mu0),
        Rounded(o.reachable_max_over_mu0)
    )?;
    writeln!(
        out,
        "search          {} in [{}, {}]{unit}, {} cells, extrema refined",
        o.drive.adjust,
        knob_text(o.drive.adjust, o.drive.range_lo),
        knob_text(o.drive.adjust, o.drive.range_hi),
        o.drive.scan_cells
    )
}

/// A profile's name with its exponent (`power n=2.5`).
fn profile_name(d: &DriveOut) -> String {
    match d.exponent {
        Some(n) if d.profile == "power" => format!("power n={}", Rounded(n)),
        _ => d.profile.to_string(),
    }
}

/// The unit of a force over μ0: the flat punch's k_z·u_z0, a curved
/// profile's mean normal force (`fricctl static`'s `mean_normal_force`).
fn force_unit(d: &DriveOut) -> &'static str {
    if d.profile == "flat" {
        "mu0·kz·uz0"
    } else {
        "mu0·(mean normal force)"
    }
}

fn write_maximize_text(out: &mut impl Write, o: &MaximizeOut, u: Units) -> std::io::Result<()> {
    let unit = u.knob(o.drive.adjust);
    writeln!(out, "adjust          {}", o.drive.adjust)?;
    writeln!(out, "maximize        {}", o.objective)?;
    writeln!(
        out,
        "value           {}   (bound {}, units of {})",
        Rounded(o.value),
        Short(round_up_sig(o.error_bound_over_mu0, 3)),
        if o.objective == "asymmetry" {
            "mu0"
        } else {
            force_unit(&o.drive)
        }
    )?;
    write_drive(out, &o.drive, u)?;
    writeln!(out, "regime          {}", o.regime)?;
    writeln!(out, "asymmetry       {}", Rounded(o.asymmetry))?;
    writeln!(
        out,
        "stall force     {} (units of {}, forward)",
        Rounded(o.stall_force_forward),
        force_unit(&o.drive)
    )?;
    writeln!(out, "mu(0+)/mu0      {}", Rounded(o.mu_0plus_over_mu0))?;
    writeln!(out, "mu(0-)/mu0      {}", Rounded(o.mu_0minus_over_mu0))?;
    writeln!(
        out,
        "search          {} in [{}, {}]{unit}, {} cells, maxima refined",
        o.drive.adjust,
        knob_text(o.drive.adjust, o.drive.range_lo),
        knob_text(o.drive.adjust, o.drive.range_hi),
        o.drive.scan_cells
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use fric_analysis::tune::SCAN_CELLS;

    /// A target result with `residual` against the bound 1e-9.
    fn result(residual: f64) -> TargetOut {
        TargetOut {
            drive: DriveOut {
                profile: "flat",
                exponent: None,
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

    /// The "doubtful residual" path (never observed with the
    /// exact solver) prints the result and exits 1 with one line; a residual
    /// within the bound exits 0.
    #[test]
    fn doubtful_residual_prints_and_fails() {
        for json in [false, true] {
            let mut out = Vec::new();
            let e = finish_target(&mut out, &result(3e-9), json, Units::of(false)).unwrap_err();
            assert_eq!(e.code, 1);
            assert_eq!(
                e.msg,
                "doubtful: the residual 3e-9 exceeds the solver's bound 1e-9 (the law is steeper than the float type resolves here)"
            );
            let text = String::from_utf8(out).unwrap();
            assert!(text.contains("3e-9"), "{text}");
            let mut out = Vec::new();
            assert!(finish_target(&mut out, &result(5e-10), json, Units::of(false)).is_ok());
            assert!(!out.is_empty());
        }
    }
}
