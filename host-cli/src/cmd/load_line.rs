//! `fricctl load-line`: the contact read as an actuator — stall forces,
//! no-load velocities, the force–velocity line(s), powers and efficiency
//! (model-core [`model_core::model::load_line`], whose doc states the sign
//! conventions and the power balance).
//!
//! μ(v) comes through [`crate::motion::law::Law`], the one interface for
//! every contact model: stall forces, no-load velocities and the output
//! power `−μ(v)F̄z·v` exist for all of them, and so do the transducers' input
//! power and the efficiency: the flat punch in permanent contact
//! ([`load_line::powers`]) and with lift-off ([`load_line::liftoff_powers`]),
//! closed form; a curved profile as the bed's sum
//! ([`model_core::mdr::powers::profile_powers`], bound 1e-6).
//!
//! A scene may push forward (`μ(0⁺) < 0`: the line `0 < v < v_nl`),
//! backward (`μ(0⁻) > 0`: `−v_nl' < v < 0`), or neither. The operating
//! points of maximum power and maximum efficiency are sought over every line
//! the scene has ([`load_line::best_of`]) and reported with a signed
//! velocity, the direction, and the contact's force on the body
//! `−μ(v)F̄z` along `+x` (the external load it holds is `F = μ(v)F̄z`, the
//! opposite), so that `P_out = force·v ≥ 0` on either line.

mod csv_rows;
mod plot;

use std::io::Write;
use std::path::PathBuf;

use clap::Args;
use model_core::model::load_line::{self, best_of, load_line_of, Objective, OperatingPoint};
use model_core::scene::ContactMode;
use serde::Serialize;

use crate::args::Count;
use crate::error::{CliError, CliResult};
use crate::motion::law::{Law, LawError};
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

/// The JSON document of `fricctl load-line` (flat; SI units for an SI scene,
/// units of μ0·F̄z, ωW0 and μ0·F̄z·ωW0 for a dimensionless one). Velocities
/// of operating points are signed (negative on the backward line); forces
/// are the contact's force on the body `−μ(v)F̄z` along `+x`.
#[derive(Serialize)]
struct LoadLineOut {
    /// Contact model: flat | lift-off | sphere | cone | power.
    contact: &'static str,
    /// Which load lines the scene has: forward | backward | both | neither.
    pushes: &'static str,
    /// Forward stall force −μ(0⁺)/μ0 when positive, else 0 (units μ0·F̄z).
    stall_force_over_mu0_fz: f64,
    /// The same in newtons (μ0·F̄z·…).
    stall_force: f64,
    /// Forward no-load velocity (0 when the scene does not push forward).
    no_load_velocity: f64,
    /// Backward stall force μ(0⁻)/μ0 when positive, else 0.
    stall_force_backward_over_mu0_fz: f64,
    /// The same in newtons.
    stall_force_backward: f64,
    /// |velocity| of the backward no-load point (0 when it does not push backward).
    no_load_velocity_backward: f64,
    /// Largest output power −μ(v)·F̄z·v over both lines (0 when it pushes neither way).
    max_power: f64,
    /// forward | backward | none.
    direction_at_max_power: &'static str,
    /// Signed velocity of the maximum power point.
    velocity_at_max_power: f64,
    /// Contact's force on the body there, −μ/μ0 (units μ0·F̄z, signed).
    force_at_max_power_over_mu0_fz: f64,
    /// The same in newtons.
    force_at_max_power: f64,
    /// Input power of the two transducers there.
    input_power_at_max_power: f64,
    /// Friction loss there.
    friction_power_at_max_power: f64,
    /// Efficiency P_out/P_in there.
    efficiency_at_max_power: f64,
    /// Largest efficiency P_out/P_in over both lines (0 when it pushes neither way).
    max_efficiency: f64,
    /// forward | backward | none.
    direction_at_max_efficiency: &'static str,
    /// Signed velocity of the maximum efficiency point.
    velocity_at_max_efficiency: f64,
    /// Contact's force on the body there, −μ/μ0 (units μ0·F̄z, signed).
    force_at_max_efficiency_over_mu0_fz: f64,
    /// The same in newtons.
    force_at_max_efficiency: f64,
    /// Output power there.
    output_power_at_max_efficiency: f64,
    /// Input power of the two transducers there.
    input_power_at_max_efficiency: f64,
    /// Friction loss there.
    friction_power_at_max_efficiency: f64,
    /// Mean normal force F̄z (N; kz·uz0 in permanent contact, kz·uz0·⟨w⁺⟩ with lift-off, kz·uz0·D (eq. M5) for a curved profile whose kz is its incremental stiffness 2E*a0; in units of kz·uz0 for a dimensionless scene, whose forces and powers are in units of μ0·F̄z and μ0·F̄z·ωW0).
    fz_mean: f64,
    /// Force unit μ0·F̄z (N; 1 for a dimensionless scene).
    force_scale: f64,
    /// Velocity unit ωW0 (m/s; 1 for a dimensionless scene).
    velocity_scale: f64,
    /// Power unit μ0·F̄z·ωW0 (W; 1 for a dimensionless scene).
    power_scale: f64,
    /// Whether values are dimensionless.
    dimensionless: bool,
}

/// An operating point in output units (SI or dimensionless).
#[derive(Debug, Clone, Copy, Default)]
struct Point {
    direction: &'static str,
    v: f64,
    force_rel: f64,
    force: f64,
    p_out: f64,
    p_in: f64,
    p_friction: f64,
    efficiency: f64,
}

/// The output units: `μ0·F̄z` (N), `ωW0` (m/s), `μ0·F̄z·ωW0` (W); all 1
/// for a dimensionless scene.
#[derive(Debug, Clone, Copy)]
struct Units {
    force: f64,
    velocity: f64,
    power: f64,
    dimensionless: bool,
}

impl Units {
    fn point(&self, o: Option<OperatingPoint<f64>>) -> Point {
        o.map_or(
            Point {
                direction: "none",
                ..Point::default()
            },
            |o| Point {
                direction: if o.v > 0.0 { "forward" } else { "backward" },
                v: o.v * self.velocity,
                force_rel: o.force,
                force: o.force * self.force,
                p_out: o.powers.output * self.power,
                p_in: o.powers.input * self.power,
                p_friction: o.powers.friction * self.power,
                efficiency: o.powers.efficiency(),
            },
        )
    }

    /// Unit names of force, velocity and power.
    fn names(&self) -> (&'static str, &'static str, &'static str) {
        if self.dimensionless {
            ("μ0·F̄z", "ωW0", "μ0·F̄z·ωW0")
        } else {
            ("N", "m/s", "W")
        }
    }
}

/// One sample of a load line: dimensionless velocity (signed) and powers.
pub(crate) type Sample = (f64, load_line::Powers<f64>);

impl LoadLineCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        crate::output::check_outputs(&[
            (self.plot.as_deref(), "plot"),
            (self.csv.as_deref(), "csv"),
        ])?;
        let s = &rs.scene;
        let p = s.params();
        let law = Law::with_profile(s, rs.profile);
        let normal = law
            .mean_normal()
            .map_err(|e| CliError::failure(e.to_string()))?;
        let fz = p.kz * p.uz0 * normal;
        // Dimensionless scenes report forces in units of μ0·F̄z (F̄z = 1 unit).
        let force_scale = if rs.dimensionless { 1.0 } else { s.mu0() * fz };
        let vs = s.velocity_scale();
        let units = Units {
            force: force_scale,
            velocity: vs,
            power: force_scale * vs,
            dimensionless: rs.dimensionless,
        };
        let fail = |e: LawError| CliError::failure(e.to_string());
        // The solver's own tolerance: its best bound (the law retries with it).
        let tol = 1e-12;
        let zero = law.at(0.0, tol).map_err(fail)?;
        let (cf, cb) = law.critical().map_err(fail)?;
        let line = load_line_of(zero.upper, zero.lower, cf, cb, |v| {
            law.mu(v, tol).map(|m| m.0)
        })
        .map_err(fail)?;
        let best_p = best_of(&line, Objective::Power, |v| law.powers(v)).map_err(fail)?;
        let best_e = best_of(&line, Objective::Efficiency, |v| law.powers(v)).map_err(fail)?;
        let (mp, me) = (units.point(best_p), units.point(best_e));
        let pushes = match (line.no_load_forward > 0.0, line.no_load_backward > 0.0) {
            (true, true) => "both",
            (true, false) => "forward",
            (false, true) => "backward",
            (false, false) => "neither",
        };
        let o = LoadLineOut {
            contact: law.name(),
            pushes,
            stall_force_over_mu0_fz: line.stall_forward,
            stall_force: line.stall_forward * force_scale,
            no_load_velocity: line.no_load_forward * vs,
            stall_force_backward_over_mu0_fz: line.stall_backward,
            stall_force_backward: line.stall_backward * force_scale,
            no_load_velocity_backward: line.no_load_backward * vs,
            max_power: mp.p_out,
            direction_at_max_power: mp.direction,
            velocity_at_max_power: mp.v,
            force_at_max_power_over_mu0_fz: mp.force_rel,
            force_at_max_power: mp.force,
            input_power_at_max_power: mp.p_in,
            friction_power_at_max_power: mp.p_friction,
            efficiency_at_max_power: mp.efficiency,
            max_efficiency: me.efficiency,
            direction_at_max_efficiency: me.direction,
            velocity_at_max_efficiency: me.v,
            force_at_max_efficiency_over_mu0_fz: me.force_rel,
            force_at_max_efficiency: me.force,
            output_power_at_max_efficiency: me.p_out,
            input_power_at_max_efficiency: me.p_in,
            friction_power_at_max_efficiency: me.p_friction,
            fz_mean: fz,
            force_scale,
            velocity_scale: vs,
            power_scale: units.power,
            dimensionless: rs.dimensionless,
        };
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
                let samples = sample_lines(&law, &line, self.points).map_err(fail)?;
                if let Some(path) = &self.csv {
                    match csv_rows::write(path, &samples, &units) {
                        Ok(()) => eprintln!("wrote {}", path.display()),
                        Err(e) => file_error = Some(e),
                    }
                }
                if let Some(path) = &self.plot {
                    let scene = plot::SceneText::of(&law, &rs, fz);
                    let marks = [(best_p, "maximum power"), (best_e, "maximum efficiency")];
                    match plot::plot(path, &samples, &line, &marks, &units, &scene) {
                        Ok(()) => eprintln!("wrote {}", path.display()),
                        Err(e) => file_error = file_error.or(Some(e)),
                    }
                }
            }
        }
        if self.json {
            write_json(out, &o)?;
        } else {
            write_text(out, &o, &units, &mp, &me).map_err(stdout_error)?;
        }
        file_error.map_or(Ok(()), Err)
    }
}

/// Samples of every load line the scene has: `n` velocities each, at
/// `±v_nl·i/n` (`i = 1…n`, the no-load point included, `v = 0` left out:
/// the stall is the limit there), backward line first, in increasing `v`.
fn sample_lines(
    law: &Law,
    line: &load_line::LoadLine<f64>,
    n: usize,
) -> Result<Vec<Vec<Sample>>, LawError> {
    let mut lines = Vec::new();
    for (vnl, sign) in [(line.no_load_backward, -1.0), (line.no_load_forward, 1.0)] {
        if vnl <= 0.0 {
            continue;
        }
        let mut l = Vec::with_capacity(n);
        for i in 1..=n {
            let v = sign * vnl * i as f64 / n as f64;
            l.push((v, law.powers(v)?));
        }
        if sign < 0.0 {
            l.reverse();
        }
        lines.push(l);
    }
    Ok(lines)
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
    )
}
