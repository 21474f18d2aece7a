//! `fricctl motion`: a body of mass M driven by a slow force over the
//! vibrated contact (the physics and the run in [`crate::motion`],
//! [`crate::motion::simulate`]): its flags, progress bar, text, CSV and plot.

use std::f64::consts::TAU;
use std::io::Write;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use model_core::scene::ContactMode;

use crate::args::Real;
use crate::error::CliResult;
use crate::motion::simulate::{self, MotionRequest, Outcome, Progress};
use crate::motion::table::MuTable;
use crate::motion::Run;
use crate::output::{stdout_error, write_json, write_rows};
use crate::plot::{render_figure, Corner, Extras, Figure, Mark, Panel, Series};
use crate::scene_args::SceneArgs;
use crate::sweep::progress_bar;

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
    #[arg(long, value_parser = Real(simulate::FORCE_REL))]
    force_amp_rel: f64,
    /// Angular frequency Ω of the force, rad/s (units of ω for a dimensionless scene)
    #[arg(long, value_parser = Real::positive())]
    force_omega: f64,
    /// Mean force f0, units of μ0·F̄z (|f0| ≤ 10)
    #[arg(long, default_value_t = 0.0, value_parser = Real(simulate::FORCE_REL))]
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
    #[arg(long, default_value_t = 1e-3, value_parser = Real(simulate::TOL))]
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

impl MotionCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        if let Some(p) = &self.plot {
            crate::plot::ext(p)?;
        }
        crate::output::check_outputs(&[
            (self.plot.as_deref(), "plot"),
            (self.csv.as_deref(), "csv"),
        ])?;
        let req = MotionRequest {
            mass: self.mass,
            force_amp_rel: self.force_amp_rel,
            force_omega: self.force_omega,
            force_offset_rel: self.force_offset_rel,
            spring: self.spring,
            duration: self.duration,
            method: match self.method {
                MotionMethod::Auto => simulate::MotionMethod::Auto,
                MotionMethod::Homogenised => simulate::MotionMethod::Homogenised,
                MotionMethod::Resolved => simulate::MotionMethod::Resolved,
            },
            tol: self.tol,
        };
        let mut pb = None;
        let sim = simulate::simulate(&rs, &req, &mut |e| {
            match e {
            Progress::Start(total) => {
                pb = Some(progress_bar(
                    u64::from(total),
                    "motion {bar:40} {pos} load periods integrated (runs of at most {len}, repeated while halving the step)",
                ))
            }
            Progress::Period => pb.iter().for_each(|b| b.inc(1)),
            Progress::Restart => pb.iter().for_each(|b| b.set_position(0)),
            Progress::Done => pb.iter().for_each(|b| b.finish_and_clear()),
        }
        })?;
        let (o, run, law, p) = (&sim.outcome, &sim.run, &sim.law, &sim.problem);
        let (scene, prm) = (rs.scene, *rs.scene.params());
        let (mass, f, f0, big_omega) = (
            self.mass,
            self.force_amp_rel,
            self.force_offset_rel,
            self.force_omega,
        );
        let (vs, fz) = (scene.velocity_scale(), sim.force_unit);
        // The results first: a file that cannot be written loses nothing.
        if self.json {
            write_json(out, o)?;
        } else {
            write_text(out, o, rs.dimensionless).map_err(stdout_error)?;
        }
        if let Some(path) = &self.csv {
            let rows = sim.rows(&rs, big_omega);
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
                run,
                o,
                big_omega,
                vs,
                fz,
                law,
                rs.dimensionless,
                caption,
            )?;
        }
        sim.doubtful().map_or(Ok(()), Err)
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
