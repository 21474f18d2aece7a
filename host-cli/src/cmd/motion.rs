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
use crate::motion::simulate::{self, MotionRequest, Outcome, Progress, Simulation};
use crate::motion::table::MuTable;
use crate::motion::Run;
use crate::output::{stdout_error, write_json, write_rows};
use crate::plot::{render_figure, Corner, Extras, Figure, Mark, Panel, Series};
use crate::progress::progress_bar;
use crate::scene_args::{ResolvedScene, SceneArgs};

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
    /// Runs the command: checks the outputs, moves the body (with a
    /// progress bar), writes text or JSON, then the CSV and the plot.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        self.check_outputs()?;
        let sim = simulate_with_progress(&rs, &self.request())?;
        let o = &sim.outcome;
        // The results first: a file that cannot be written loses nothing.
        if self.json {
            write_json(out, o)?;
        } else {
            write_text(out, o, rs.dimensionless).map_err(stdout_error)?;
        }
        if let Some(path) = &self.csv {
            write_rows(path, &sim.rows(&rs, self.force_omega))?;
        }
        if let Some(path) = &self.plot {
            let units = PlotUnits {
                big_omega: self.force_omega,
                velocity: rs.scene.velocity_scale(),
                force: sim.force_unit,
                dimensionless: rs.dimensionless,
            };
            plot(path, &sim.run, o, &sim.law, &units, self.caption(&rs, &sim))?;
        }
        sim.doubtful().map_or(Ok(()), Err)
    }

    /// The plot's extension and every output's overwrite policy, before the run.
    fn check_outputs(&self) -> CliResult {
        if let Some(p) = &self.plot {
            crate::plot::ext(p)?;
        }
        crate::output::check_outputs(&[
            (self.plot.as_deref(), "plot"),
            (self.csv.as_deref(), "csv"),
        ])
    }

    /// The library's request from the flags.
    fn request(&self) -> MotionRequest {
        MotionRequest {
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
        }
    }

    /// The plot's two caption lines: the scene, then the load.
    fn caption(&self, rs: &ResolvedScene, sim: &Simulation) -> Vec<String> {
        let (o, p) = (&sim.outcome, &sim.problem);
        let prm = *rs.scene.params();
        let (mass, f, f0, big_omega) = (
            self.mass,
            self.force_amp_rel,
            self.force_offset_rel,
            self.force_omega,
        );
        let g = rs.scene.groups();
        vec![
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
        ]
    }
}

/// Moves the body with a progress bar over the load periods.
fn simulate_with_progress(rs: &ResolvedScene, req: &MotionRequest) -> CliResult<Simulation> {
    let mut pb = None;
    simulate::simulate(rs, req, &mut |e| {
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
    })
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

/// The plot's scales: the load's angular frequency Ω (rad/s or units of
/// ω), the velocity and force units, and whether the scene is dimensionless.
struct PlotUnits {
    big_omega: f64,
    velocity: f64,
    force: f64,
    dimensionless: bool,
}

/// Velocity and applied force over the last (at most three) load periods,
/// with the drift and the static band.
fn plot(
    path: &std::path::Path,
    run: &Run,
    o: &Outcome,
    law: &MuTable,
    u: &PlotUnits,
    caption: Vec<String>,
) -> CliResult {
    let last = run.trajectory.last().map_or(0.0, |s| s.t);
    let from = last - 3.0 * TAU;
    let pts: Vec<_> = run.trajectory.iter().filter(|s| s.t >= from).collect();
    let t_of = |t: f64| t / u.big_omega;
    let (t0, t1) = (
        pts.first().map_or(0.0, |s| t_of(s.t)),
        pts.last().map_or(1.0, |s| t_of(s.t)),
    );
    let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
    let vel: Vec<(f64, f64)> = pts.iter().map(|s| (t_of(s.t), s.v * u.velocity)).collect();
    let force: Vec<(f64, f64)> = pts.iter().map(|s| (t_of(s.t), s.force * u.force)).collect();
    let stuck: Vec<(f64, f64)> = pts
        .iter()
        .filter(|s| s.stuck)
        .map(|s| (t_of(s.t), 0.0))
        .collect();
    let (tu, vu, fu) = if u.dimensionless {
        ("t, 1/ω", "v, ωW0", "F, μ0·F̄z")
    } else {
        ("t, s", "v, m/s", "F, N")
    };
    let band = [law.mu_0plus * u.force, law.mu_0minus * u.force];
    let v_series = velocity_series(vel, stuck, o, (t0, t1));
    let f_series = force_series(force, band, (t0, t1));
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

/// The data's range, with room above it for the legend.
fn span(v: &[(f64, f64)], extra: &[f64]) -> (f64, f64) {
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
}

/// The velocity, its mean (the drift) and the stuck instants.
fn velocity_series(
    vel: Vec<(f64, f64)>,
    stuck: Vec<(f64, f64)>,
    o: &Outcome,
    (t0, t1): (f64, f64),
) -> Vec<Series> {
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
    v_series
}

/// The applied force and the static band `[μ(0⁻), μ(0⁺)]·F̄z` (one line
/// where it is unique or too narrow to see).
fn force_series(force: Vec<(f64, f64)>, band: [f64; 2], (t0, t1): (f64, f64)) -> Vec<Series> {
    let f_range = force
        .iter()
        .map(|p| p.1.abs())
        .fold(band[0].abs().max(band[1].abs()), f64::max);
    let line = |label: String, y: f64, color| Series {
        label,
        points: vec![(t0, y), (t1, y)],
        mark: Mark::Dashed,
        color,
    };
    let mut f_series = vec![Series {
        label: "applied force F(t)".into(),
        points: force,
        mark: Mark::Line,
        color: 0,
    }];
    if band[0] == band[1] {
        // Lift-off: μ(0) is unique.
        f_series.push(line(
            format!("μ(0)·F̄z = {:.4e} (unique with lift-off)", band[0]),
            band[0],
            1,
        ));
    } else if (band[0] - band[1]).abs() < 1e-3 * f_range {
        // Two lines the eye cannot tell apart: one, with both values.
        f_series.push(line(
            format!("μ(0⁺)·F̄z = {:.6e} ≈ μ(0⁻)·F̄z = {:.6e}", band[0], band[1]),
            band[0],
            1,
        ));
    } else {
        f_series.push(line(format!("μ(0⁺)·F̄z = {:.4e}", band[0]), band[0], 1));
        f_series.push(line(format!("μ(0⁻)·F̄z = {:.4e}", band[1]), band[1], 3));
    }
    f_series
}
