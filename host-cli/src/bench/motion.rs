//! `fricctl bench motion --out DIR`: the slow dynamics' charts.
//!
//! * `motion_error_cost.png` (+ `.csv`): homogenised against resolved on the
//!   paper's Fig. 7 ratchet (Δu_z/u_z0 = 0.5, ratio 0.5, φ = 0) and on a
//!   lift-off scene (Δu_z/u_z0 = 1.5, Δu_x k_x/(μ0 k_z u_z0) = 0.75, φ = 34.4°),
//!   both under `F = 0.5 μ0F̄z sin Ωt`: the relative difference `|H − R|/|R|`
//!   over the scale separation ω/Ω = 10…3·10⁴ (to 10⁶ with `--full`) at three body
//!   responses `Mω Ω/k_x` (lift-off: to 10⁴), over the body's response time in ultrasonic periods
//!   at ω/Ω = 10³, and against the wall time of each model. The resolved
//!   model is the reference; where `|H − R|` is below its stated numerical
//!   error the point is marked (the difference is not resolved there).
//! * `motion_drift_map.png` (+ `.csv`): the quasi-static drift (`M = 0`,
//!   homogenised, μ⁻¹ of the force) over (φ, ratio) at Δu_z/u_z0 = 0.5 under
//!   `F = 0.5 μ0F̄z sin Ωt`, in units of ωW₀.
//! * `motion_load_lines.png` (+ `.csv`): the load lines of the paper's Fig. 6
//!   scenes (Δu_z/u_z0 = 0.5, ratio 2, φ = 0, 45°, 90°, 135°, 180°; 90° is
//!   not symmetric at this ratio and pushes backward weakly, stall force
//!   0.0348 μ0F̄z): force–velocity, output power and efficiency, each in the
//!   direction the scene pushes.
//!
//! Everything is dimensionless (velocities in ωW₀, forces in μ0F̄z, masses in
//! k_x/ω²). A run with default sizes takes well under a minute (release).

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use clap::Args;
use model_core::model::load_line::{best_forward, load_line, powers, Objective};
use model_core::scene::ContactMode;
use model_core::{Groups, Libm, Scene};

use crate::error::{CliError, CliResult};
use crate::eval::exact_failure;
use crate::motion::law::Law;
use crate::motion::table::MuTable;
use crate::motion::{estimate, homogenised, resolved, Problem};
use crate::plot::{
    prepare_out_dir, render_figure, render_heat, Corner, Extras, Figure, Heat, HeatMap, Mark,
    Marker, Panel, Series,
};
use crate::sweep::{centres, progress_bar};

/// Flags of `bench motion`.
#[derive(Args, Debug, Clone)]
pub struct MotionArgs {
    /// Output directory (PNG + CSV per chart)
    #[arg(long, value_name = "DIR")]
    pub out: std::path::PathBuf,
    /// Also run ω/Ω = 10⁶ (the resolved model then takes about a minute more)
    #[arg(long)]
    pub full: bool,
    /// Cells per axis of the drift map (φ × ratio), 4…200
    #[arg(long, default_value_t = 36, value_parser = crate::args::Count::<usize>::at_least(4).at_most(200, "the drift map's largest"))]
    pub res: usize,
}

/// Force amplitude of every chart, units μ0F̄z.
const FORCE: f64 = 0.5;
/// Tolerance of the runs, relative to the larger critical velocity.
const TOL: f64 = 1e-4;
/// Relative error above which homogenisation counts as failed.
const FAIL: f64 = 0.1;

/// A scene with its law and table.
struct Case {
    name: &'static str,
    law: Law,
    table: MuTable,
    table_time: f64,
}

impl Case {
    fn new(name: &'static str, scene: Scene<f64>) -> CliResult<Self> {
        let law = Law::of(&scene);
        let t0 = Instant::now();
        let table = MuTable::new(&law, 0.02 * TOL)
            .map_err(|e| CliError::failure(format!("{name}: {e}")))?;
        Ok(Case {
            name,
            law,
            table,
            table_time: t0.elapsed().as_secs_f64(),
        })
    }

    fn v_ref(&self) -> f64 {
        self.table.c_forward.max(self.table.c_backward)
    }
}

/// One comparison of the two models.
#[derive(Debug, Clone, Copy)]
struct Point {
    inv_nu: f64,
    mass: f64,
    /// Body response time in ultrasonic periods, `m̃S/(2πn̄)`.
    response: f64,
    h: f64,
    h_numerical: f64,
    e_h: f64,
    h_time: f64,
    r: f64,
    r_numerical: f64,
    r_time: f64,
    r_steps: u64,
    periodic: bool,
}

impl Point {
    fn rel(&self) -> f64 {
        (self.h - self.r).abs() / self.r.abs()
    }
    /// The difference is not resolved: below the reference's numerical error.
    fn below_floor(&self) -> bool {
        (self.h - self.r).abs() <= self.r_numerical + self.h_numerical
    }
}

fn compare(c: &Case, inv_nu: f64, mass: f64, tick: &mut dyn FnMut()) -> Point {
    let p = Problem {
        f0: 0.0,
        f: FORCE,
        nu: 1.0 / inv_nu,
        mass,
        kappa: 0.0,
        normal: c.law.mean_normal().expect("flat punch: closed form"),
    };
    let tol = 0.1 * TOL * c.v_ref();
    let relaxation = crate::motion::relaxation_per_period(&p, estimate::inverse_slope(&c.table));
    let t0 = Instant::now();
    let h = homogenised::run(
        &p,
        &c.table,
        &homogenised::Settings {
            tol,
            periods: None,
            max_periods: 2000,
            relaxation,
            min_steps: 0,
            budget: u64::MAX,
        },
        tick,
    );
    let h_time = t0.elapsed().as_secs_f64() + c.table_time;
    let e_h = estimate::homogenisation_error(&p, c.law.spring_bounds(), &c.table, &h);
    let t0 = Instant::now();
    let r = resolved::run(
        &p,
        &c.law.scene().drive(),
        c.law.exponent(),
        &resolved::Settings {
            tol,
            periods: None,
            max_periods: 2000,
            relaxation,
            budget: u64::MAX,
        },
        tick,
    );
    Point {
        inv_nu,
        mass,
        response: mass * estimate::inverse_slope(&c.table) / (TAU * p.normal),
        h: h.mean_velocity,
        h_numerical: h.numerical_error
            + c.table.interpolation_error * estimate::inverse_slope(&c.table),
        e_h,
        h_time,
        r: r.mean_velocity,
        r_numerical: r.numerical_error,
        r_time: t0.elapsed().as_secs_f64(),
        r_steps: r.steps,
        periodic: h.periodic && r.periodic,
    }
}

fn write_file(path: &Path, text: &str) -> CliResult {
    std::fs::write(path, text)
        .map_err(|e| CliError::failure(format!("{}: {e}", path.display())))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// `fricctl bench motion`.
pub fn run(a: &MotionArgs) -> CliResult {
    if !(4..=200).contains(&a.res) {
        return Err(CliError::usage("--res: must be between 4 and 200"));
    }
    prepare_out_dir(&a.out)?;
    error_cost(a)?;
    drift_map(a)?;
    load_lines(&a.out)
}

/// Scale separations, body responses `Mω Ω/k_x`, masses of the mass sweep.
fn grids(full: bool) -> (Vec<f64>, [f64; 3], Vec<f64>) {
    let mut inv = vec![10.0, 30.0, 100.0, 300.0, 1e3, 3e3, 1e4, 3e4];
    if full {
        inv.extend([1e5, 3e5, 1e6]);
    }
    let masses = vec![3.0, 10.0, 30.0, 100.0, 300.0, 1e3, 3e3, 1e4, 1e5];
    (inv, [0.1, 1.0, 10.0], masses)
}

/// The lift-off scene's resolved runs stop at ω/Ω = 10⁴: beyond, |H − R| is
/// below the resolved model's numerical error (its grid does not land
/// exactly, a first-order error) and each run costs seconds.
const LIFT_OFF_MAX_INV_NU: f64 = 1e4;

fn error_cost(a: &MotionArgs) -> CliResult {
    let flat = Case::new(
        "flat",
        Scene::dimensionless(Groups::from_ratio(0.5, 0.5, 0.0).map_err(scene_err)?)
            .map_err(scene_err)?,
    )?;
    let lift = Case::new(
        "lift-off",
        Scene::dimensionless_with_contact(
            Groups {
                duz_rel: 1.5,
                dux_rel: 0.75,
                phi: 0.6,
            },
            ContactMode::Intermittent,
        )
        .map_err(scene_err)?,
    )?;
    let (inv, responses, masses) = grids(a.full);
    let lift_inv = inv.iter().filter(|&&i| i <= LIFT_OFF_MAX_INV_NU).count();
    let runs = (inv.len() * responses.len() + lift_inv + 2 * masses.len()) as u64;
    let pb = progress_bar(runs, "motion {bar:40} {pos}/{len} comparisons {msg}");
    let mut tick = || {};
    // (case, sweep, point)
    let mut rows: Vec<(&str, String, Point)> = Vec::new();
    for &mn in &responses {
        for &i in &inv {
            pb.set_message(format!("flat, ω/Ω = {i:.0e}, MωΩ/k_x = {mn}"));
            let p = compare(&flat, i, mn * i, &mut tick);
            rows.push((flat.name, format!("mnu={mn}"), p));
            pb.inc(1);
        }
    }
    for &i in inv.iter().filter(|&&i| i <= LIFT_OFF_MAX_INV_NU) {
        pb.set_message(format!("lift-off, ω/Ω = {i:.0e}"));
        let p = compare(&lift, i, i, &mut tick);
        rows.push((lift.name, "mnu=1".into(), p));
        pb.inc(1);
    }
    for c in [&flat, &lift] {
        for &m in &masses {
            pb.set_message(format!("{}, Mω²/k_x = {m:.0e}", c.name));
            let p = compare(c, 1e3, m, &mut tick);
            rows.push((c.name, "mass".into(), p));
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    let mut csv = String::from(
        "contact,sweep,omega_over_Omega,mass_rel,response_periods,mean_velocity_homogenised,mean_velocity_resolved,rel_difference,homogenisation_error_estimate,numerical_error_homogenised,numerical_error_resolved,wall_time_homogenised,wall_time_resolved,resolved_steps_per_period,periodic\n",
    );
    for (c, s, p) in &rows {
        let _ = writeln!(
            csv,
            "{c},{s},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{}",
            p.inv_nu,
            p.mass,
            p.response,
            p.h,
            p.r,
            p.rel(),
            p.e_h,
            p.h_numerical,
            p.r_numerical,
            p.h_time,
            p.r_time,
            p.r_steps,
            p.periodic
        );
        println!(
            "{c:8} {s:9} ω/Ω {:8.1e} Mω²/k_x {:8.1e} response {:8.2e} periods  H {:+.5e} R {:+.5e} |H−R|/|R| {:.2e} E_h/|R| {:.2e}  time H {:.1e} s R {:.1e} s{}",
            p.inv_nu,
            p.mass,
            p.response,
            p.h,
            p.r,
            p.rel(),
            p.e_h / p.r.abs(),
            p.h_time,
            p.r_time,
            if p.below_floor() {
                "  (below the numerical error)"
            } else {
                ""
            }
        );
    }
    let covered = rows
        .iter()
        .filter(|(_, _, p)| (p.h - p.r).abs() <= p.e_h + p.h_numerical + p.r_numerical)
        .count();
    println!(
        "E_h covers |H − R| in {covered} of {} comparisons; not periodic: {}",
        rows.len(),
        rows.iter().filter(|r| !r.2.periodic).count()
    );
    write_file(&a.out.join("motion_error_cost.csv"), &csv)?;
    let path = a.out.join("motion_error_cost.png");
    render_figure(&path, &error_cost_figure(&rows, &inv, &responses))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn scene_err(e: model_core::SceneError) -> CliError {
    CliError::failure(format!("bench scene: {e}"))
}

fn series(label: impl Into<String>, points: Vec<(f64, f64)>, mark: Mark, color: usize) -> Series {
    Series {
        label: label.into(),
        points,
        mark,
        color,
    }
}

fn log_range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if lo.is_finite() {
        (lo / 2.0, hi * 2.0)
    } else {
        (1e-6, 1.0)
    }
}

fn error_cost_figure(rows: &[(&str, String, Point)], inv: &[f64], responses: &[f64]) -> Figure {
    let fail_note = format!(
        "homogenisation fails above {:.0} % (black dashed line)",
        100.0 * FAIL
    );
    // (a) over ω/Ω.
    let mut sa = Vec::new();
    let pick = |c: &str, s: &str| -> Vec<Point> {
        rows.iter()
            .filter(|r| r.0 == c && r.1 == s)
            .map(|r| r.2)
            .collect()
    };
    let mut floor = Vec::new();
    for (k, &mn) in responses.iter().enumerate() {
        let pts = pick("flat", &format!("mnu={mn}"));
        sa.push(series(
            format!("|H − R|/|R|, flat, MωΩ/k_x = {mn}"),
            pts.iter().map(|p| (p.inv_nu, p.rel())).collect(),
            Mark::LineMarkers(Marker::Circle),
            k,
        ));
        sa.push(series(
            format!("E_h/|R| (derived estimate), MωΩ/k_x = {mn}"),
            pts.iter().map(|p| (p.inv_nu, p.e_h / p.r.abs())).collect(),
            Mark::Dashed,
            k,
        ));
        floor.extend(
            pts.iter()
                .filter(|p| p.below_floor())
                .map(|p| (p.inv_nu, p.rel())),
        );
    }
    let lp = pick("lift-off", "mnu=1");
    sa.push(series(
        "|H − R|/|R|, lift-off, MωΩ/k_x = 1",
        lp.iter().map(|p| (p.inv_nu, p.rel())).collect(),
        Mark::LineMarkers(Marker::Triangle),
        3,
    ));
    floor.extend(
        lp.iter()
            .filter(|p| p.below_floor())
            .map(|p| (p.inv_nu, p.rel())),
    );
    let x_a = (inv[0] / 1.5, inv[inv.len() - 1] * 1.5);
    sa.push(series(
        "",
        vec![(x_a.0, FAIL), (x_a.1, FAIL)],
        Mark::Dashed,
        6,
    ));
    sa.push(series(
        "|H − R| below the runs' numerical error",
        floor,
        Mark::Markers(Marker::Cross),
        9,
    ));
    let y_a = log_range(sa.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    let panel_a = Panel {
        title: "(a) homogenised vs resolved over the scale separation".into(),
        x_label: "ω/Ω".into(),
        y_label: "relative difference of the drift".into(),
        x: x_a,
        y: y_a,
        series: sa,
    };
    // (b) over the body's response time at ω/Ω = 10³.
    let mut sb = Vec::new();
    let mut floor_b = Vec::new();
    for (c, k, m) in [
        ("flat", 0usize, Marker::Circle),
        ("lift-off", 3, Marker::Triangle),
    ] {
        let pts = pick(c, "mass");
        sb.push(series(
            format!("|H − R|/|R|, {c}"),
            pts.iter().map(|p| (p.response, p.rel())).collect(),
            Mark::LineMarkers(m),
            k,
        ));
        sb.push(series(
            format!("E_h/|R|, {c}"),
            pts.iter()
                .map(|p| (p.response, p.e_h / p.r.abs()))
                .collect(),
            Mark::Dashed,
            k,
        ));
        floor_b.extend(
            pts.iter()
                .filter(|p| p.below_floor())
                .map(|p| (p.response, p.rel())),
        );
    }
    let x_b = log_range(sb.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    sb.push(series(
        "",
        vec![(x_b.0, FAIL), (x_b.1, FAIL)],
        Mark::Dashed,
        6,
    ));
    sb.push(series(
        "|H − R| below the runs' numerical error",
        floor_b,
        Mark::Markers(Marker::Cross),
        9,
    ));
    let y_b = log_range(sb.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    let panel_b = Panel {
        title: "(b) over the body's response time, ω/Ω = 10³".into(),
        x_label: "body response time M/(F̄z dμ/dv), ultrasonic periods".into(),
        y_label: "relative difference of the drift".into(),
        x: x_b,
        y: y_b,
        series: sb,
    };
    // (c) error against cost at MωΩ/k_x = 1 (flat).
    let pts = pick("flat", "mnu=1");
    let sc = vec![
        series(
            "homogenised: |H − R|/|R| (table + RK4)",
            pts.iter().map(|p| (p.h_time, p.rel())).collect(),
            Mark::LineMarkers(Marker::Circle),
            0,
        ),
        series(
            "resolved: its numerical error/|R|",
            pts.iter()
                .map(|p| (p.r_time, p.r_numerical / p.r.abs()))
                .collect(),
            Mark::LineMarkers(Marker::Square),
            1,
        ),
    ];
    // One label per ω/Ω, on the homogenised point only: the two series' labels
    // collided where their points are close (the resolved points follow in
    // the same order of ω/Ω, left to right).
    let labels: Vec<((f64, f64), String)> = pts
        .iter()
        .map(|p| ((p.h_time, p.rel()), format!("{:.0e}", p.inv_nu)))
        .collect();
    let panel_c = Panel {
        title:
            "(c) error against wall time, flat, MωΩ/k_x = 1 (labels: ω/Ω of the homogenised runs)"
                .into(),
        x_label: "wall time, s".into(),
        y_label: "relative error of the drift".into(),
        x: log_range(sc.iter().flat_map(|s| s.points.iter().map(|p| p.0))),
        y: log_range(sc.iter().flat_map(|s| s.points.iter().map(|p| p.1))),
        series: sc,
    };
    let ex = |notes: Vec<String>, legend_at: Corner, labels| Extras {
        notes,
        notes_at: Corner::LowerLeft,
        legend_at,
        log_x: true,
        log_y: true,
        labels,
        error_bars: Vec::new(),
    };
    Figure {
        panels: vec![
            (
                panel_a,
                ex(vec![fail_note.clone()], Corner::UpperRight, Vec::new()),
            ),
            (panel_b, ex(vec![fail_note], Corner::UpperRight, Vec::new())),
            (panel_c, ex(Vec::new(), Corner::UpperRight, labels)),
        ],
        rows: 1,
        cols: 3,
        size: (2400, 800),
        legend: Vec::new(),
        caption: vec![
            format!(
                "F = {FORCE} μ0F̄z sin Ωt, no spring; flat: Δu_z/u_z0 = 0.5, k_xΔu_x/(μ0k_zΔu_z) = 0.5, φ = 0 (Fig. 7 ratchet); lift-off: Δu_z/u_z0 = 1.5, k_xΔu_x/(μ0k_z u_z0) = 0.75, φ = 34.4°"
            ),
            format!(
                "R = resolved (body + contact at the ultrasonic scale, the reference), H = homogenised (μ(v) law); --tol {TOL:e} of v_ref; response time = Mω²/k_x·S/(2π n̄), S the law's mean inverse slope"
            ),
        ],
    }
}

/// The quasi-static drift over (φ, ratio).
fn drift_map(a: &MotionArgs) -> CliResult {
    let n = a.res;
    let phis = centres(0.0, 360.0, n);
    let lr = centres(-1.0, 1.0, n);
    let pb = progress_bar((n * n) as u64, "drift map {bar:40} {pos}/{len} cells");
    let classes = vec![
        (
            "law not monotone".to_string(),
            plotters::style::RGBColor(200, 200, 200),
        ),
        (
            "solver failed".to_string(),
            plotters::style::RGBColor(120, 0, 0),
        ),
    ];
    let mut cells = Vec::with_capacity(n * n);
    let mut csv = String::from("phi_deg,ratio,mean_velocity,stick_fraction,outcome\n");
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for &l in &lr {
        let ratio = 10f64.powf(l);
        for &phi in &phis {
            let g = Groups::from_ratio(0.5, ratio, phi.to_radians()).map_err(scene_err)?;
            let law = Law::of(&Scene::dimensionless(g).map_err(scene_err)?);
            let cell = match MuTable::new(&law, 1e-6) {
                Ok(t) => {
                    let p = Problem {
                        f0: 0.0,
                        f: FORCE,
                        nu: 1e-3,
                        mass: 0.0,
                        kappa: 0.0,
                        normal: 1.0,
                    };
                    let r = homogenised::run(
                        &p,
                        &t,
                        &homogenised::Settings {
                            tol: 1e-6,
                            periods: None,
                            max_periods: 10,
                            relaxation: 0.0,
                            min_steps: 0,
                            budget: u64::MAX,
                        },
                        &mut || {},
                    );
                    let v = r.mean_velocity;
                    lo = lo.min(v);
                    hi = hi.max(v);
                    let _ = writeln!(csv, "{phi},{ratio:e},{v:e},{},ok", r.stick_fraction);
                    Heat::Value(v)
                }
                Err(crate::motion::table::TableError::NotMonotone { .. }) => {
                    let _ = writeln!(csv, "{phi},{ratio:e},,,not_monotone");
                    Heat::Class(0)
                }
                Err(_) => {
                    let _ = writeln!(csv, "{phi},{ratio:e},,,failed");
                    Heat::Class(1)
                }
            };
            cells.push(cell);
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    write_file(&a.out.join("motion_drift_map.csv"), &csv)?;
    println!("drift map: mean velocity from {lo:.4e} to {hi:.4e} ωW0");
    let m = HeatMap {
        title: format!(
            "quasi-static drift (M = 0, any Ω ≪ ω) under F = {FORCE} μ0F̄z sin Ωt (f0 = 0), Δu_z/u_z0 = 0.5"
        ),
        x_label: "phase shift φ, degrees".into(),
        y_label: "k_xΔu_x/(μ0k_zΔu_z)".into(),
        xs: phis,
        ys: lr,
        log_x: false,
        log_y: true,
        range: crate::plot::heat_range(&cells, true).unwrap_or((lo, hi)),
        cells,
        diverging: true,
        value_label: "mean velocity, ωW0 (signed; white = 0)".into(),
        classes,
    };
    let path = a.out.join("motion_drift_map.png");
    render_heat(&path, &m, (1100, 760))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Load lines of the paper's Fig. 6 scenes.
fn load_lines(out: &Path) -> CliResult {
    let a = 0.5;
    let mut sf = Vec::new();
    let mut sp = Vec::new();
    let mut se = Vec::new();
    let mut csv = String::from("phi_deg,direction,v,load_over_mu0_fz,p_out,p_in,efficiency\n");
    let (mut vmax, mut fmax, mut pmax, mut emax) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (k, phi_deg) in [0.0f64, 45.0, 90.0, 135.0, 180.0].into_iter().enumerate() {
        let d0 = Scene::dimensionless(
            Groups::from_ratio(a, 2.0, phi_deg.to_radians()).map_err(scene_err)?,
        )
        .map_err(scene_err)?
        .drive();
        let line0 = load_line::<f64, Libm>(&d0).map_err(exact_failure)?;
        // Backward pushers: the mirrored drive's forward line (μ(−v; φ) = −μ(v; φ + π)).
        let (d, dir, sign) = if line0.no_load_forward > 0.0 {
            (d0, "forward", 1.0)
        } else {
            (d0.mirrored(), "backward", -1.0)
        };
        let line = load_line::<f64, Libm>(&d).map_err(exact_failure)?;
        let best = best_forward::<f64, Libm>(&d, &line, Objective::Power)
            .map_err(exact_failure)?
            .map_or(0.0, |o| o.powers.output);
        let best_e = best_forward::<f64, Libm>(&d, &line, Objective::Efficiency)
            .map_err(exact_failure)?
            .map_or(0.0, |o| o.powers.efficiency());
        println!(
            "Fig. 6, φ = {phi_deg:>3}°: pushes {dir}, stall {:.4} μ0F̄z, no-load {:.4e} ωW0, max power {:.4e} μ0F̄zωW0, max efficiency {:.4}",
            line.stall_forward, line.no_load_forward, best, best_e
        );
        let nl = line.no_load_forward;
        let (mut f, mut p, mut e) = (vec![(0.0, line.stall_forward)], Vec::new(), Vec::new());
        for i in 1..200 {
            let v = nl * i as f64 / 200.0;
            let pw = powers::<f64, Libm>(&d, v).map_err(exact_failure)?;
            f.push((v, -pw.mu_over_mu0));
            p.push((v, pw.output));
            e.push((v, pw.efficiency()));
            let _ = writeln!(
                csv,
                "{phi_deg},{dir},{:e},{:e},{:e},{:e},{:e}",
                sign * v,
                -pw.mu_over_mu0,
                pw.output,
                pw.input,
                pw.efficiency()
            );
            pmax = pmax.max(pw.output);
            emax = emax.max(pw.efficiency());
        }
        f.push((nl, 0.0));
        vmax = vmax.max(nl);
        fmax = fmax.max(line.stall_forward);
        // Backward pushers dashed: φ and φ + π mirror each other (same curves).
        let label = format!("φ = {phi_deg:.0}° ({dir})");
        let mark = if sign > 0.0 { Mark::Line } else { Mark::Dashed };
        sf.push(series(label.clone(), f, mark, k));
        sp.push(series(label.clone(), p, mark, k));
        se.push(series(label, e, mark, k));
    }
    write_file(&out.join("motion_load_lines.csv"), &csv)?;
    // One legend under the panels (it covers no data); the panels' series unlabelled.
    let legend: Vec<Series> = sf
        .iter()
        .map(|s| series(s.label.clone(), Vec::new(), s.mark, s.color))
        .collect();
    for s in sf.iter_mut().chain(sp.iter_mut()).chain(se.iter_mut()) {
        s.label.clear();
    }
    let panel = |title: &str, y_label: &str, y: f64, s: Vec<Series>| {
        (
            Panel {
                title: title.into(),
                x_label: "|v|, ωW0 (in the direction the scene pushes)".into(),
                y_label: y_label.into(),
                x: (0.0, vmax * 1.02),
                y: (0.0, y * 1.1),
                series: s,
            },
            Extras::default(),
        )
    };
    let fig = Figure {
        panels: vec![
            panel("force–velocity line", "load held −μ(v)F̄z, in μ0F̄z", fmax, sf),
            panel(
                "output power P_out = −μ(v)F̄z·v",
                "P_out, μ0F̄z·ωW0",
                pmax,
                sp,
            ),
            panel("efficiency η = P_out/P_in", "η", emax, se),
        ],
        rows: 1,
        cols: 3,
        size: (2100, 700),
        legend,
        caption: vec![
            "Fig. 6 scenes: flat punch, permanent contact, Δu_z/u_z0 = 0.5, k_xΔu_x/(μ0k_zΔu_z) = 2 (b = 1); φ = 90° pushes backward weakly (stall force 0.0348 μ0F̄z, no-load velocity 0.0303 ωW0: μ(0±) = 0.0348 μ0);"
                .into(),
            "φ = 180° mirrors φ = 0° exactly (dashed over solid); velocities in ωW0 (W0 = μ0k_zu_z0/k_x), forces in μ0F̄z, powers in μ0F̄zωW0".into(),
            "exact steady state; P_in = input of the tangential transducer (the normal one's is 0)".into(),
        ],
    };
    let path = out.join("motion_load_lines.png");
    render_figure(&path, &fig)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
