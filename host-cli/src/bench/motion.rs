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
//! The runs and what they measure are [`fric_analysis::bench::motion`]'s;
//! this module writes the CSV files, the text and the charts.

use std::fmt::Write as _;
use std::path::Path;

use clap::Args;
use fric_analysis::bench::motion::{
    drift_map as drift_cells, fig6_load_line, Comparison, Drift, ErrorCost, Fig6Line, Row, FAIL,
    FIG6_PHIS_DEG, FORCE, TOL,
};

use crate::error::{CliError, CliResult};
use crate::plot::{
    prepare_out_dir, render_figure, render_heat, Corner, Extras, Figure, Heat, HeatMap, Mark,
    Marker, Panel, Series,
};
use crate::progress::progress_bar;

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

/// Homogenised against resolved: runs the comparisons with a progress bar,
/// writes the CSV, the lines and the chart.
fn error_cost(a: &MotionArgs) -> CliResult {
    let bench = ErrorCost::new(a.full)?;
    let runs = bench.runs();
    let pb = progress_bar(
        runs.len() as u64,
        "motion {bar:40} {pos}/{len} comparisons {msg}",
    );
    let mut rows = Vec::with_capacity(runs.len());
    for run in &runs {
        pb.set_message(run.message.clone());
        rows.push(bench.measure(run)?);
        pb.inc(1);
    }
    pb.finish_and_clear();
    let csv = error_cost_text(&rows);
    let covered = rows.iter().filter(|r| r.point.covered()).count();
    println!(
        "E_h covers |H − R| in {covered} of {} comparisons; not periodic: {}",
        rows.len(),
        rows.iter().filter(|r| !r.point.periodic).count()
    );
    write_file(&a.out.join("motion_error_cost.csv"), &csv)?;
    let path = a.out.join("motion_error_cost.png");
    render_figure(
        &path,
        &error_cost_figure(&rows, &bench.inv, &bench.responses),
    )?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// The error–cost CSV, with one line per comparison printed to stdout.
fn error_cost_text(rows: &[Row]) -> String {
    let mut csv = String::from(
        "contact,sweep,omega_over_Omega,mass_rel,response_periods,mean_velocity_homogenised,mean_velocity_resolved,rel_difference,homogenisation_error_estimate,numerical_error_homogenised,numerical_error_resolved,wall_time_homogenised,wall_time_resolved,resolved_steps_per_period,periodic\n",
    );
    for Row {
        case: c,
        sweep: s,
        point: p,
    } in rows
    {
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
    csv
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

/// The comparisons of contact `c` in sweep `s`.
fn pick(rows: &[Row], c: &str, s: &str) -> Vec<Comparison> {
    rows.iter()
        .filter(|r| r.case == c && r.sweep == s)
        .map(|r| r.point)
        .collect()
}

/// Panel (a): `|H − R|/|R|` and E_h over ω/Ω.
fn over_separation(rows: &[Row], inv: &[f64], responses: &[f64]) -> Panel {
    let mut sa = Vec::new();
    let mut floor = Vec::new();
    for (k, &mn) in responses.iter().enumerate() {
        let pts = pick(rows, "flat", &format!("mnu={mn}"));
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
    let lp = pick(rows, "lift-off", "mnu=1");
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
    Panel {
        title: "(a) homogenised vs resolved over the scale separation".into(),
        x_label: "ω/Ω".into(),
        y_label: "relative difference of the drift".into(),
        x: x_a,
        y: y_a,
        series: sa,
    }
}

/// Panel (b): `|H − R|/|R|` and E_h over the body's response time at
/// ω/Ω = 10³.
fn over_response(rows: &[Row]) -> Panel {
    let mut sb = Vec::new();
    let mut floor_b = Vec::new();
    for (c, k, m) in [
        ("flat", 0usize, Marker::Circle),
        ("lift-off", 3, Marker::Triangle),
    ] {
        let pts = pick(rows, c, "mass");
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
    Panel {
        title: "(b) over the body's response time, ω/Ω = 10³".into(),
        x_label: "body response time M/(F̄z dμ/dv), ultrasonic periods".into(),
        y_label: "relative difference of the drift".into(),
        x: x_b,
        y: y_b,
        series: sb,
    }
}

/// Texts at points of a panel.
type Labels = Vec<((f64, f64), String)>;

/// Panel (c): error against wall time at MωΩ/k_x = 1 (flat), with one
/// ω/Ω label per homogenised point.
fn against_cost(rows: &[Row]) -> (Panel, Labels) {
    let pts = pick(rows, "flat", "mnu=1");
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
    let labels: Labels = pts
        .iter()
        .map(|p| ((p.h_time, p.rel()), format!("{:.0e}", p.inv_nu)))
        .collect();
    let panel = Panel {
        title:
            "(c) error against wall time, flat, MωΩ/k_x = 1 (labels: ω/Ω of the homogenised runs)"
                .into(),
        x_label: "wall time, s".into(),
        y_label: "relative error of the drift".into(),
        x: log_range(sc.iter().flat_map(|s| s.points.iter().map(|p| p.0))),
        y: log_range(sc.iter().flat_map(|s| s.points.iter().map(|p| p.1))),
        series: sc,
    };
    (panel, labels)
}

fn error_cost_figure(rows: &[Row], inv: &[f64], responses: &[f64]) -> Figure {
    let fail_note = format!(
        "homogenisation fails above {:.0} % (black dashed line)",
        100.0 * FAIL
    );
    let panel_a = over_separation(rows, inv, responses);
    let panel_b = over_response(rows);
    let (panel_c, labels) = against_cost(rows);
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

/// The quasi-static drift over (φ, ratio): the map with a progress bar, its
/// CSV, range and heat map.
fn drift_map(a: &MotionArgs) -> CliResult {
    let n = a.res;
    let pb = progress_bar((n * n) as u64, "drift map {bar:40} {pos}/{len} cells");
    let map = drift_cells(n, &mut || pb.inc(1))?;
    pb.finish_and_clear();
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
    for c in &map.cells {
        let (phi, ratio) = (c.phi_deg, c.ratio);
        cells.push(match c.drift {
            Drift::Ok {
                mean_velocity: v,
                stick_fraction,
            } => {
                let _ = writeln!(csv, "{phi},{ratio:e},{v:e},{stick_fraction},ok");
                Heat::Value(v)
            }
            Drift::NotMonotone => {
                let _ = writeln!(csv, "{phi},{ratio:e},,,not_monotone");
                Heat::Class(0)
            }
            Drift::Failed => {
                let _ = writeln!(csv, "{phi},{ratio:e},,,failed");
                Heat::Class(1)
            }
        });
    }
    let (lo, hi) = map.range();
    write_file(&a.out.join("motion_drift_map.csv"), &csv)?;
    println!("drift map: mean velocity from {lo:.4e} to {hi:.4e} ωW0");
    let m = HeatMap {
        title: format!(
            "quasi-static drift (M = 0, any Ω ≪ ω) under F = {FORCE} μ0F̄z sin Ωt (f0 = 0), Δu_z/u_z0 = 0.5"
        ),
        x_label: "phase shift φ, degrees".into(),
        y_label: "k_xΔu_x/(μ0k_zΔu_z)".into(),
        xs: map.phis_deg,
        ys: map.log_ratios,
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

/// The three series of one Fig. 6 line: force–velocity (from stall to no
/// load), output power, efficiency.
fn line_series(l: &Fig6Line, k: usize) -> [Series; 3] {
    let mut f = vec![(0.0, l.stall)];
    f.extend(l.points.iter().map(|p| (p.v, p.load)));
    f.push((l.no_load, 0.0));
    let p = l.points.iter().map(|p| (p.v, p.p_out)).collect();
    let e = l.points.iter().map(|p| (p.v, p.efficiency)).collect();
    // Backward pushers dashed: φ and φ + π mirror each other (same curves).
    let label = format!("φ = {:.0}° ({})", l.phi_deg, l.dir);
    let mark = if l.sign > 0.0 {
        Mark::Line
    } else {
        Mark::Dashed
    };
    [
        series(label.clone(), f, mark, k),
        series(label.clone(), p, mark, k),
        series(label, e, mark, k),
    ]
}

/// Load lines of the paper's Fig. 6 scenes: the CSV, a line per scene on
/// stdout, and the chart.
fn load_lines(out: &Path) -> CliResult {
    let mut csv = String::from("phi_deg,direction,v,load_over_mu0_fz,p_out,p_in,efficiency\n");
    let mut lines = Vec::new();
    for phi_deg in FIG6_PHIS_DEG {
        let l = fig6_load_line(phi_deg)?;
        println!(
            "Fig. 6, φ = {phi_deg:>3}°: pushes {}, stall {:.4} μ0F̄z, no-load {:.4e} ωW0, max power {:.4e} μ0F̄zωW0, max efficiency {:.4}",
            l.dir, l.stall, l.no_load, l.best_power, l.best_efficiency
        );
        for p in &l.points {
            let _ = writeln!(
                csv,
                "{phi_deg},{},{:e},{:e},{:e},{:e},{:e}",
                l.dir,
                l.sign * p.v,
                p.load,
                p.p_out,
                p.p_in,
                p.efficiency
            );
        }
        lines.push(l);
    }
    write_file(&out.join("motion_load_lines.csv"), &csv)?;
    let path = out.join("motion_load_lines.png");
    render_figure(&path, &load_lines_figure(&lines))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// The Fig. 6 chart: force–velocity, output power and efficiency, one
/// legend under the panels.
fn load_lines_figure(lines: &[Fig6Line]) -> Figure {
    let max = |f: &dyn Fn(&Fig6Line) -> f64| lines.iter().map(f).fold(0.0f64, f64::max);
    let vmax = max(&|l| l.no_load);
    let fmax = max(&|l| l.stall);
    let pmax = max(&|l| l.points.iter().map(|p| p.p_out).fold(0.0f64, f64::max));
    let emax = max(&|l| l.points.iter().map(|p| p.efficiency).fold(0.0f64, f64::max));
    let (mut sf, mut sp, mut se) = (Vec::new(), Vec::new(), Vec::new());
    for (k, l) in lines.iter().enumerate() {
        let [f, p, e] = line_series(l, k);
        sf.push(f);
        sp.push(p);
        se.push(e);
    }
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
    Figure {
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
    }
}
