//! `fricctl load-line`: the contact read as an actuator — the flags, the
//! text, the CSV and the plot of [`fric_analysis::load_line`] (stall forces,
//! no-load velocities, the force–velocity line(s), powers and efficiency;
//! its docs state the sign conventions).

mod csv_rows;
mod plot;

use std::io::Write;
use std::path::PathBuf;

use clap::Args;
use fric_analysis::load_line::{self, sample_lines, LoadLineOut, Point, Sample, Units};
use model_core::scene::ContactMode;

use crate::args::Count;
use crate::error::{CliError, CliResult};
use crate::motion::law::LawError;
use crate::output::{stdout_error, write_json};
use crate::scene_args::SceneArgs;

/// Flags of `fricctl load-line`.
#[derive(Args, Debug, Clone)]
pub struct LoadLineCmd {
    #[command(flatten)]
    scene: SceneArgs,
    /// Plot the force–velocity line(s), the powers and the efficiency to FILE.svg or FILE.png
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Write the force–velocity line(s) to FILE (CSV: v, force, p_out, p_in, p_friction, efficiency; units in the header)
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Points per line for --plot and --csv (≥ 2, at most 10⁵)
    #[arg(long, default_value_t = 200, value_parser = Count::<usize>::at_least(2).at_most(100_000, "a plot or CSV line needs no more"))]
    points: usize,
    /// JSON output
    #[arg(long)]
    json: bool,
}

impl LoadLineCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        crate::output::check_outputs(&[
            (self.plot.as_deref(), "plot"),
            (self.csv.as_deref(), "csv"),
        ])?;
        let an = load_line::analyse(&rs)?;
        let (law, line, units, fz) = (&an.law, &an.line, &an.units, an.fz);
        let (best_p, best_e) = (an.best_power, an.best_efficiency);
        let (mp, me) = (an.power_point, an.efficiency_point);
        let o = &an.out;
        let pushes = o.pushes;
        let fail = |e: LawError| CliError::failure(e.to_string());
        // Files first; their errors are reported after the results, which
        // are printed whatever happens to the files.
        let mut file_error = None;
        if self.plot.is_some() || self.csv.is_some() {
            if pushes == "neither" {
                let flag = if self.plot.is_some() {
                    "--plot"
                } else {
                    "--csv"
                };
                file_error = Some(CliError::usage(format!(
                    "{flag}: the scene pushes neither way (μ(0⁺) ≥ 0 ≥ μ(0⁻)): there is no load line"
                )));
            } else {
                let samples = sample_lines(law, line, self.points).map_err(fail)?;
                if let Some(path) = &self.csv {
                    match csv_rows::write(path, &samples, units) {
                        Ok(()) => eprintln!("wrote {}", path.display()),
                        Err(e) => file_error = Some(e),
                    }
                }
                if let Some(path) = &self.plot {
                    let scene = plot::SceneText::of(law, &rs, fz);
                    let marks = [(best_p, "maximum power"), (best_e, "maximum efficiency")];
                    let stall = o.max_efficiency_at_stall.then_some(o.max_efficiency);
                    match plot::plot(path, &samples, line, &marks, stall, units, &scene) {
                        Ok(()) => eprintln!("wrote {}", path.display()),
                        Err(e) => file_error = file_error.or(Some(e)),
                    }
                }
            }
        }
        if self.json {
            write_json(out, o)?;
        } else {
            write_text(out, o, units, &mp, &me).map_err(stdout_error)?;
        }
        file_error.map_or(Ok(()), Err)
    }
}

/// The aligned text summary.
fn write_text(
    out: &mut impl Write,
    o: &LoadLineOut,
    u: &Units,
    mp: &Point,
    me: &Point,
) -> std::io::Result<()> {
    let (fu, vu, pu) = u.names();
    writeln!(out, "contact                 {}", o.contact)?;
    writeln!(out, "pushes                  {}", o.pushes)?;
    // In newtons too for an SI scene; once for a dimensionless one.
    let stall = |rel: f64, abs: f64| {
        if u.dimensionless {
            format!("{rel:.6} μ0·F̄z")
        } else {
            format!("{rel:<12.6} μ0·F̄z = {abs:.6e} {fu}")
        }
    };
    writeln!(
        out,
        "stall force, forward    {}",
        stall(o.stall_force_over_mu0_fz, o.stall_force)
    )?;
    writeln!(
        out,
        "no-load velocity        {:.6e} {vu}",
        o.no_load_velocity
    )?;
    writeln!(
        out,
        "stall force, backward   {}",
        stall(o.stall_force_backward_over_mu0_fz, o.stall_force_backward)
    )?;
    writeln!(
        out,
        "no-load velocity, back  {:.6e} {vu} (|v|)",
        o.no_load_velocity_backward
    )?;
    if o.pushes == "neither" {
        return writeln!(
            out,
            "the scene pushes neither way (μ(0⁺) ≥ 0 ≥ μ(0⁻)): no output power, no efficiency"
        );
    }
    writeln!(out)?;
    writeln!(
        out,
        "operating point          {:>14}  {:>18}",
        "max power", "max efficiency"
    )?;
    let row = |out: &mut dyn Write, name: &str, a: String, b: String| {
        // Pad by displayed width: combining marks (the bar of F̄) take none.
        let width = name
            .chars()
            .filter(|c| !('\u{300}'..='\u{36f}').contains(c))
            .count();
        let pad = " ".repeat(24usize.saturating_sub(width));
        writeln!(out, "{name}{pad} {a:>14}  {b:>18}")
    };
    row(out, "direction", mp.direction.into(), me.direction.into())?;
    row(
        out,
        &format!("velocity ({vu})"),
        format!("{:.6e}", mp.v),
        format!("{:.6e}", me.v),
    )?;
    row(
        out,
        "force −μF̄z (μ0·F̄z)",
        format!("{:.6}", mp.force_rel),
        format!("{:.6}", me.force_rel),
    )?;
    if !u.dimensionless {
        row(
            out,
            &format!("force −μF̄z ({fu})"),
            format!("{:.6e}", mp.force),
            format!("{:.6e}", me.force),
        )?;
    }
    for (name, a, b) in [
        ("P_out", mp.p_out, me.p_out),
        ("P_in", mp.p_in, me.p_in),
        ("P_friction", mp.p_friction, me.p_friction),
    ] {
        row(
            out,
            &format!("{name} ({pu})"),
            format!("{a:.6e}"),
            format!("{b:.6e}"),
        )?;
    }
    row(
        out,
        "efficiency P_out/P_in",
        format!("{:.6}", mp.efficiency),
        format!("{:.6}", me.efficiency),
    )?;
    if o.max_efficiency_at_stall {
        writeln!(
            out,
            "max efficiency: no interior maximum; η rises towards stall, {:.6} its limit as v → 0 (no power there)",
            o.max_efficiency
        )?;
    }
    Ok(())
}
