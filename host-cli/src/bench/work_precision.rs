//! `fricctl bench work-precision`: error against time for every way the
//! project computes μ, on scenes covering the paper's regimes. The points
//! are measured by [`fric_analysis::bench::work_precision`] (the scenes, the
//! fixed-step series, the fitted orders) and
//! [`fric_analysis::bench::across_lift_off`] (the flat punch at a = 0.5 … 3
//! and a sphere through the MDR, each against its own reference); this
//! module writes `work_precision.csv`, `convergence_orders.csv` and the
//! chart (SVG + PNG), one panel per method family.

use std::fmt::Write as _;
use std::path::Path;

use clap::Args;
use fric_analysis::bench::across_lift_off;
use fric_analysis::bench::point::Point;
use fric_analysis::bench::work_precision::{
    across_orders, check_max_steps, measure_all, scene_orders, SCENES,
};

use crate::error::{CliError, CliResult};
use crate::plot::{prepare_out_dir, render_figure, Extras, Figure, Mark, Marker, Panel, Series};

/// Flags of `bench work-precision`.
#[derive(Args, Debug, Clone)]
pub struct WpArgs {
    /// Output directory
    #[arg(long, value_name = "DIR")]
    pub out: std::path::PathBuf,
    /// Largest steps per period (power of two, ≤ 65536)
    #[arg(long, default_value_t = 65536, value_parser = crate::args::Count::<u32>::at_least(8).at_most(65536, "the largest step count charted"))]
    pub max_steps: u32,
}

/// `fricctl bench work-precision`.
pub fn run(a: &WpArgs) -> CliResult {
    check_max_steps(a.max_steps)?;
    prepare_out_dir(&a.out)?;
    let all = measure_all(a.max_steps, &mut |name| eprintln!("measuring {name} …"))?;
    let csv_path = a.out.join("work_precision.csv");
    write(&csv_path, &points_csv(&all))?;
    let op = a.out.join("convergence_orders.csv");
    write(&op, &orders_csv(&all))?;
    for ext in ["svg", "png"] {
        let p = a.out.join(format!("work_precision.{ext}"));
        render(&p, &all)?;
        eprintln!("wrote {}", p.display());
    }
    eprintln!("wrote {} and {}", csv_path.display(), op.display());
    Ok(())
}

fn write(path: &Path, text: &str) -> CliResult {
    std::fs::write(path, text).map_err(|e| CliError::failure(format!("{}: {e}", path.display())))
}

/// `work_precision.csv`: one row per point.
fn points_csv(all: &[Point]) -> String {
    let mut csv = String::from(
        "scene,method,steps_per_period,error_over_mu0,time_s,error_bound_over_mu0,status\n",
    );
    for p in all {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{}",
            p.scene,
            p.method,
            p.steps.map_or(String::new(), |n| n.to_string()),
            p.error.map_or(String::new(), |e| e.to_string()),
            p.time_s,
            p.bound.map_or(String::new(), |e| e.to_string()),
            p.status
        );
    }
    csv
}

/// `convergence_orders.csv`, with each order printed to stdout: every
/// scene's fixed-step series (`-` without an order), then the flat punch
/// across lift-off (only the series with one).
fn orders_csv(all: &[Point]) -> String {
    let mut orders = String::from("scene,method,fitted_order\n");
    for o in scene_orders(all) {
        let (name, m) = (o.scene, o.method);
        let _ = writeln!(
            orders,
            "{name},{m},{}",
            o.order.map_or(String::new(), |o| format!("{o:.3}"))
        );
        println!(
            "{name:18} {m:22} order {}",
            o.order.map_or("-".to_string(), |o| format!("{o:.2}"))
        );
    }
    for o in across_orders(all) {
        let (name, m) = (o.scene, o.method);
        if let Some(o) = o.order {
            let _ = writeln!(orders, "{name},{m},{o:.3}");
            println!("{name:28} {m:22} order {o:.2}");
        }
    }
    orders
}

/// The marker of a method: distinct within each panel of [`PANELS`].
fn marker(method: &str) -> Marker {
    match method {
        "exact f64" => Marker::Diamond,
        "exact f32" => Marker::Circle,
        "exact f32 micromath" => Marker::Ring,
        "eq. 21" | "eq. 24" => Marker::Square,
        "fixed f64 from rest" => Marker::Triangle,
        "fixed f64 warm" => Marker::OpenTriangle,
        "fixed f32 from rest" => Marker::OpenSquare,
        "fixed f32 warm" => Marker::Cross,
        "lift-off stepping f64" => Marker::Triangle,
        "MDR f64" => Marker::Diamond,
        "MDR f32" => Marker::Square,
        "brute force over springs" => Marker::Triangle,
        _ => Marker::OpenDiamond,
    }
}

/// A method's (error, time) points in order of steps per period (the
/// family's convergence path; points without a step count keep their order).
fn by_steps<'a>(pts: impl Iterator<Item = &'a &'a Point>) -> Vec<(f64, f64)> {
    let mut v: Vec<(u32, (f64, f64))> = pts
        .map(|p| {
            (
                p.steps.unwrap_or(0),
                (p.error.unwrap_or(1.0).max(ERROR_FLOOR), p.time_s),
            )
        })
        .collect();
    v.sort_by_key(|q| q.0);
    v.into_iter().map(|q| q.1).collect()
}

/// The methods in legend order, with their legend text.
const LEGEND: &[(&str, &str)] = &[
    (
        "exact f64",
        "exact f64 = the reference (error 0 by definition; drawn at 1e-17)",
    ),
    ("exact f32", "exact f32"),
    ("exact f32 micromath", "exact f32, micromath"),
    ("eq. 21", "eq. (21) / eq. (24) (single-mode scenes)"),
    ("fixed f64 from rest", "fixed-step f64 from rest"),
    ("fixed f64 warm", "fixed-step f64 warm-started"),
    ("fixed f32 from rest", "fixed-step f32 from rest"),
    ("fixed f32 warm", "fixed-step f32 warm-started"),
    ("fixed f32 micromath", "fixed-step f32, micromath set-up"),
    (
        "lift-off stepping f64",
        "lift-off stepping f64, exact landing (a ≥ 1)",
    ),
    (
        "MDR f64",
        "sphere: MDR f64 at tol 1e-6, 1e-8, 1e-9 (vs. MDR at 2× its per-spring bound)",
    ),
    ("MDR f32", "sphere: MDR f32 at 2× its per-spring bound"),
    (
        "brute force over springs",
        "sphere: brute force over springs, (M, N) = (8, 128) … (64, 1024)",
    ),
];

/// Errors below this are drawn at it (log axis).
const ERROR_FLOOR: f64 = 1e-17;

/// The small multiples: one panel per method family (shared axes), so that
/// no method hides another; in a panel the marker tells the method and the
/// colour the scene.
const PANELS: &[(&str, &[&str])] = &[
    (
        "exact solver (f64, f32, f32 micromath) and eq. (21) / (24)",
        &["exact f64", "exact f32", "exact f32 micromath", "eq. 21"],
    ),
    ("fixed-step f64 from rest", &["fixed f64 from rest"]),
    ("fixed-step f64 warm-started", &["fixed f64 warm"]),
    ("fixed-step f32 from rest", &["fixed f32 from rest"]),
    ("fixed-step f32 warm-started", &["fixed f32 warm"]),
    ("fixed-step f32, micromath set-up", &["fixed f32 micromath"]),
    (
        "lift-off stepping f64, exact landing (flat punch, a ≥ 1)",
        &["lift-off stepping f64"],
    ),
    (
        "sphere: MDR f64, MDR f32, brute force over springs",
        &["MDR f64", "MDR f32", "brute force over springs"],
    ),
];

/// Palette index of the single scenes (in `SCENES` order); the planes
/// across lift-off share `ACROSS_COLOR`.
const SCENE_COLORS: [usize; 8] = [0, 1, 2, 3, 4, 5, 9, 8];
const ACROSS_COLOR: usize = 6;

/// The colour of a point's scene.
fn scene_color(scene: &str) -> usize {
    SCENES
        .iter()
        .position(|s| s.0 == scene)
        .map_or(ACROSS_COLOR, |i| SCENE_COLORS[i])
}

/// Whether point `p` belongs to the legend's method `m` (eq. 21 and eq. 24
/// share one entry).
fn is_method(p: &Point, m: &str) -> bool {
    p.method == m || (m == "eq. 21" && p.method == "eq. 24")
}

/// The small multiples ([`PANELS`]) on axes shared by every drawn point.
fn panels(drawn: &[&Point]) -> Vec<(Panel, Extras)> {
    let tmin = drawn
        .iter()
        .map(|p| p.time_s)
        .fold(f64::INFINITY, f64::min)
        .max(1e-9)
        / 2.0;
    let tmax = drawn
        .iter()
        .map(|p| p.time_s)
        .fold(0.0f64, f64::max)
        .max(tmin * 10.0)
        * 2.0;
    let colors: Vec<usize> = SCENE_COLORS.iter().copied().chain([ACROSS_COLOR]).collect();
    let mut panels = Vec::new();
    for &(title, methods) in PANELS {
        let mut series = Vec::new();
        for &m in methods {
            let marker = marker(m);
            for &c in &colors {
                let points = by_steps(
                    drawn
                        .iter()
                        .filter(|p| is_method(p, m) && scene_color(p.scene) == c),
                );
                if !points.is_empty() {
                    series.push(Series {
                        label: String::new(),
                        points,
                        mark: Mark::Markers(marker),
                        color: c,
                    });
                }
            }
        }
        panels.push((
            Panel {
                title: title.to_string(),
                x_label: "|μ − μ_ref| / μ0".to_string(),
                y_label: "time per μ, s".to_string(),
                x: (ERROR_FLOOR, 1.0),
                y: (tmin, tmax),
                series,
            },
            Extras {
                log_x: true,
                log_y: true,
                ..Extras::default()
            },
        ));
    }
    panels
}

/// The legend: the scenes as colour swatches, then the methods as black
/// markers.
fn legend() -> Vec<Series> {
    let (b, phi, x) = across_lift_off::DRIVE;
    let mut legend: Vec<Series> = SCENES
        .iter()
        .zip(SCENE_COLORS)
        .map(|(&(name, a, b, phi, x), c)| Series {
            label: format!(
                "{name}: a = {a}, b = {b}, φ = {:.1}°, v0/v_c = {x}",
                phi.to_degrees()
            ),
            points: Vec::new(),
            mark: Mark::Line,
            color: c,
        })
        .collect();
    let a_of = |names: &[(&str, f64)]| {
        names
            .iter()
            .map(|n| format!("{}", n.1))
            .collect::<Vec<_>>()
            .join(", ")
    };
    legend.push(Series {
        label: format!(
            "across lift-off: flat punch a = {}, sphere a = {}; b = {b}, φ = {:.1}°, v0/v_c = {x}",
            a_of(across_lift_off::FLAT),
            a_of(across_lift_off::SPHERE),
            phi.to_degrees()
        ),
        points: Vec::new(),
        mark: Mark::Line,
        color: ACROSS_COLOR,
    });
    legend.extend(LEGEND.iter().map(|&(m, text)| Series {
        label: text.to_string(),
        points: Vec::new(),
        mark: Mark::Markers(marker(m)),
        color: 6,
    }));
    legend
}

/// The caption under the chart.
fn caption() -> Vec<String> {
    vec![
        "One panel per method family, shared axes; marker: the method, colour: the scene. \
         a = Δu_z/u_z0, b = k_xΔu_x/(μ0 k_z u_z0) (eq. 25)."
            .to_string(),
        "μ_ref: the exact solver in f64 (libm) at the same scene and velocity, which agrees \
         with the paper's fixed-step scheme (Richardson, N = 65 536) to < 1e-9; across \
         lift-off the flat punch against the exact f64 solver (the lift-off solver from a = 1)."
            .to_string(),
        "Sphere against the MDR f64 at twice its per-spring bound, itself checked to lie within \
         its bound plus the error estimate of a brute force over springs ((M, N) = (48, 1024))."
            .to_string(),
        "Fixed-step: one point per N = 8 … 65 536 steps per period (4 per octave; across \
         lift-off one per octave); refusals (TooFewSteps, PrecisionLimit) are not drawn. \
         Time: minimum over repeated batches after a warm-up, this host."
            .to_string(),
    ]
}

fn render(path: &Path, all: &[Point]) -> CliResult {
    let drawn: Vec<&Point> = all.iter().filter(|p| p.error.is_some()).collect();
    let f = Figure {
        panels: panels(&drawn),
        rows: 4,
        cols: 2,
        size: (1800, 2150),
        legend: legend(),
        caption: caption(),
    };
    render_figure(path, &f)
}
