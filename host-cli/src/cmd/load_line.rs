//! `fricctl load-line`: the contact read as an actuator — stall forces,
//! no-load velocities, the force–velocity line, powers and efficiency
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

use std::io::Write;
use std::path::PathBuf;

use clap::Args;
use model_core::model::load_line::{
    self, best_forward_of, load_line_of, Objective, OperatingPoint,
};
use model_core::scene::ContactMode;
use serde::Serialize;

use crate::args::count;
use crate::error::{CliError, CliResult};
use crate::motion::law::{Law, LawError};
use crate::output::{stdout_error, write_json};
use crate::plot::{render_panels, Mark, Panel, Series};
use crate::scene_args::SceneArgs;

/// Flags of `fricctl load-line`.
#[derive(Args, Debug, Clone)]
pub struct LoadLineCmd {
    #[command(flatten)]
    scene: SceneArgs,
    /// Plot the force–velocity line, the powers and the efficiency to FILE.svg or FILE.png
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Points on the plotted line (≥ 2, at most 10⁵)
    #[arg(long, default_value_t = 200, value_parser = count::<usize, 2>)]
    points: usize,
    /// JSON output
    #[arg(long)]
    json: bool,
}

/// The JSON document of `fricctl load-line` (flat; SI units for an SI scene,
/// units of μ0·F̄z, ωW0 and μ0·F̄z·ωW0 for a dimensionless one).
#[derive(Serialize)]
struct LoadLineOut {
    /// Forward stall force −μ(0⁺)/μ0 when positive, else 0 (units μ0·F̄z).
    stall_force_over_mu0_fz: f64,
    /// The same in newtons (μ0·F̄z·…; F̄z = kz·uz0).
    stall_force: f64,
    /// Forward no-load velocity (0 when the scene does not push forward).
    no_load_velocity: f64,
    /// Backward stall force μ(0⁻)/μ0 when positive, else 0.
    stall_force_backward_over_mu0_fz: f64,
    /// The same in newtons.
    stall_force_backward: f64,
    /// |velocity| of the backward no-load point (0 when it does not push backward).
    no_load_velocity_backward: f64,
    /// Largest forward output power −μ(v)·F̄z·v (0 when the scene does not push forward).
    max_power: f64,
    /// Velocity of the maximum power point.
    velocity_at_max_power: f64,
    /// Load force there (units μ0·F̄z).
    force_at_max_power_over_mu0_fz: f64,
    /// Largest forward efficiency P_out/P_in (0 when the scene does not push forward).
    max_efficiency: Option<f64>,
    /// Velocity of the maximum efficiency point.
    velocity_at_max_efficiency: Option<f64>,
    /// Contact model: flat | lift-off | sphere | cone | power.
    contact: &'static str,
    /// Mean normal force F̄z (N; kz·uz0 in permanent contact, kz·uz0·⟨w⁺⟩ with lift-off, kz·uz0·D (eq. M5) for a curved profile whose kz is its incremental stiffness 2E*a0; in units of kz·uz0 for a dimensionless scene, whose forces and powers are in units of μ0·F̄z and μ0·F̄z·ωW0).
    fz_mean: f64,
    /// Velocity unit ωW0 (m/s; 1 for a dimensionless scene).
    velocity_scale: f64,
    /// Power unit μ0·F̄z·ωW0 (W; 1 for a dimensionless scene).
    power_scale: f64,
    /// Whether values are dimensionless.
    dimensionless: bool,
}

impl LoadLineCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        if self.points > 100_000 {
            return Err(CliError::usage("--points: at most 100000"));
        }
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
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
        let ps = force_scale * vs;
        let fail = |e: LawError| CliError::failure(e.to_string());
        // The solver's own tolerance: its best bound (the law retries with it).
        let tol = 1e-12;
        let zero = law.at(0.0, tol).map_err(fail)?;
        let (cf, cb) = law.critical().map_err(fail)?;
        let line = load_line_of(zero.upper, zero.lower, cf, cb, |v| {
            law.mu(v, tol).map(|m| m.0)
        })
        .map_err(fail)?;
        let best_p = best_forward_of(&line, Objective::Power, |v| law.powers(v)).map_err(fail)?;
        let best_e =
            best_forward_of(&line, Objective::Efficiency, |v| law.powers(v)).map_err(fail)?;
        let get = |b: &Option<OperatingPoint<f64>>| {
            b.map_or((0.0, 0.0, 0.0), |o| (o.v, o.force, o.powers.output))
        };
        let (vp, fp, pp) = get(&best_p);
        let eff = Some(best_e.map_or((0.0, 0.0), |o| (o.powers.efficiency(), o.v)));
        let o = LoadLineOut {
            stall_force_over_mu0_fz: line.stall_forward,
            stall_force: line.stall_forward * force_scale,
            no_load_velocity: line.no_load_forward * vs,
            stall_force_backward_over_mu0_fz: line.stall_backward,
            stall_force_backward: line.stall_backward * force_scale,
            no_load_velocity_backward: line.no_load_backward * vs,
            max_power: pp * ps,
            velocity_at_max_power: vp * vs,
            force_at_max_power_over_mu0_fz: fp,
            max_efficiency: eff.map(|e| e.0),
            velocity_at_max_efficiency: eff.map(|e| e.1 * vs),
            contact: law.name(),
            fz_mean: fz,
            velocity_scale: vs,
            power_scale: ps,
            dimensionless: rs.dimensionless,
        };
        if let Some(path) = &self.plot {
            self.plot_line(path, &law, &line, &o)?;
            eprintln!("wrote {}", path.display());
        }
        if self.json {
            return write_json(out, &o);
        }
        write_text(out, &o).map_err(stdout_error)
    }

    fn plot_line(
        &self,
        path: &std::path::Path,
        law: &Law,
        line: &load_line::LoadLine<f64>,
        o: &LoadLineOut,
    ) -> CliResult {
        if line.no_load_forward <= 0.0 {
            return Err(CliError::usage(
                "--plot: this scene does not push forward (μ(0⁺) ≥ 0): there is no forward load line to plot",
            ));
        }
        let n = self.points;
        let d = &law.scene().drive();
        let g = model_core::Groups {
            duz_rel: d.a,
            dux_rel: d.b,
            phi: 0.0,
        };
        let ratio = if g.duz_rel > 0.0 {
            format!("{:.3}", g.dux_rel / g.duz_rel)
        } else {
            "∞".into()
        };
        let scene = format!(
            "Δuz/uz0 = {:.3}, kxΔux/(μ0kzΔuz) = {ratio}, φ = {:.1}°",
            g.duz_rel,
            d.bs.atan2(d.bc).to_degrees().rem_euclid(360.0)
        );
        let (vunit, punit) = if o.dimensionless {
            ("v0 (ωW0)", "power (μ0·F̄z·ωW0)")
        } else {
            ("v0 (m/s)", "power (W)")
        };
        let (mut force, mut pin, mut pout, mut pf, mut eta) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 1..n {
            let v = line.no_load_forward * i as f64 / n as f64;
            let x = v * o.velocity_scale;
            let pw = law
                .powers(v)
                .map_err(|e| CliError::failure(e.to_string()))?;
            force.push((x, -pw.mu_over_mu0));
            pin.push((x, pw.input * o.power_scale));
            pout.push((x, pw.output * o.power_scale));
            pf.push((x, pw.friction * o.power_scale));
            eta.push((x, pw.efficiency()));
        }
        force.insert(0, (0.0, line.stall_forward));
        force.push((o.no_load_velocity, 0.0));
        let xmax = o.no_load_velocity;
        let pmax = pin
            .iter()
            .chain(pf.iter())
            .chain(pout.iter())
            .map(|p| p.1)
            .fold(0.0f64, f64::max)
            * 1.1;
        let emax = eta.iter().map(|p| p.1).fold(0.0f64, f64::max) * 1.2;
        let series = |label: &str, points: Vec<(f64, f64)>, mark: Mark, color: usize| Series {
            label: label.into(),
            points,
            mark,
            color,
        };
        let line_panel = Panel {
            title: format!("{}: {scene}", law.name()),
            x_label: vunit.into(),
            y_label: "load −μ/μ0 (units μ0·F̄z)".into(),
            x: (0.0, xmax),
            y: (0.0, line.stall_forward * 1.1),
            series: vec![series("−μ(v)/μ0", force, Mark::Line, 0)],
        };
        let panels = [
            line_panel,
            Panel {
                title: "powers: P_in = P_out + P_friction (normal transducer: 0)".into(),
                x_label: vunit.into(),
                y_label: punit.into(),
                x: (0.0, xmax),
                y: (0.0, pmax.max(1e-300)),
                series: vec![
                    series("P_in, tangential transducer", pin, Mark::Line, 0),
                    series("P_friction", pf, Mark::Dashed, 2),
                    series("P_out, to the body", pout, Mark::Line, 1),
                ],
            },
            Panel {
                title: "efficiency η = P_out/P_in".into(),
                x_label: vunit.into(),
                y_label: "η".into(),
                x: (0.0, xmax),
                y: (0.0, emax.max(1e-12)),
                series: vec![series("η", eta, Mark::Line, 3)],
            },
        ];
        render_panels(path, &panels, 1, 3, (1800, 600))
    }
}

/// The aligned text summary.
fn write_text(out: &mut impl Write, o: &LoadLineOut) -> std::io::Result<()> {
    let (fu, vu, pu) = if o.dimensionless {
        ("μ0·F̄z", "ωW0", "μ0·F̄z·ωW0")
    } else {
        ("N", "m/s", "W")
    };
    writeln!(
        out,
        "stall force, forward    {:<12.6} μ0·F̄z  = {:.6e} {fu}",
        o.stall_force_over_mu0_fz, o.stall_force
    )?;
    writeln!(
        out,
        "no-load velocity        {:.6e} {vu}",
        o.no_load_velocity
    )?;
    writeln!(
        out,
        "stall force, backward   {:<12.6} μ0·F̄z  = {:.6e} {fu}",
        o.stall_force_backward_over_mu0_fz, o.stall_force_backward
    )?;
    writeln!(
        out,
        "no-load velocity, back  {:.6e} {vu}",
        o.no_load_velocity_backward
    )?;
    if o.no_load_velocity > 0.0 {
        writeln!(
            out,
            "max power (forward)     {:.6e} {pu} at v0 = {:.6e} {vu}, load {:.6} μ0·F̄z",
            o.max_power, o.velocity_at_max_power, o.force_at_max_power_over_mu0_fz
        )?;
        match (o.max_efficiency, o.velocity_at_max_efficiency) {
            (Some(e), Some(v)) => {
                writeln!(out, "max efficiency          {e:.6} at v0 = {v:.6e} {vu}")?
            }
            _ => writeln!(
                out,
                "max efficiency          not computed ({} contact: no derived input power)",
                o.contact
            )?,
        }
    } else {
        writeln!(
            out,
            "the scene does not push forward: no forward power or efficiency"
        )?;
    }
    Ok(())
}
