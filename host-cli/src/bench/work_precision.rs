//! `fricctl bench work-precision`: error against time for every way the
//! project computes μ, on scenes covering the paper's regimes.
//!
//! Error is `|μ − μ_exact,f64|/μ0`; time is the minimum over repeated batches
//! after a warm-up (the DiffEqDevTools convention). The fixed-step scheme is
//! run for many steps per period (four per octave from 8 to 65 536: the error
//! jitters with where the events fall on the grid, so every point is kept),
//! from rest and warm-started at the exact steady state, in f64 and f32, with
//! libm and with micromath for its set-up; the convergence order of each
//! fixed-step series is fitted by least squares. The last row of the chart
//! crosses lift-off ([`super::across_lift_off`]: the flat punch at
//! a = 0.5 … 3 and a sphere through the MDR, each against its own reference).

use std::fmt::Write as _;
use std::hint::black_box;
use std::path::Path;

use clap::Args;
use model_core::analytic::approx::approx_mu_over_mu0;
use model_core::exact;
use model_core::fixed_step::{run_dimensionless, FixedStepConfig, Start, State};
use model_core::{Drive, Float, Groups, Libm, Math, Micromath, Scene};

use super::point::{refusal_kind, Point};
use super::{across_lift_off, time_min};
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

/// The scenes (dimensionless a, b, φ and v/v_c).
pub const SCENES: &[(&str, f64, f64, f64, f64)] = &[
    ("normal only", 0.5, 0.0, 0.0, 0.3),
    ("tangential small", 0.0, 0.5, 0.4, 0.3),
    ("tangential large", 0.0, 3.0, 0.4, -0.5),
    ("dual ratchet", 0.5, 0.25, 1.0, 0.4),
    ("dual actuator", 0.5, 1.0, 0.3, 0.2),
    ("near v_c", 0.5, 0.25, 1.0, 0.98),
    ("low velocity", 0.5, 0.25, 1.0, 0.02),
    ("near lift-off", 0.97, 0.3, 2.0, 0.4),
];

fn steps_list(max: u32) -> Vec<u32> {
    let mut v = Vec::new();
    let mut x = 8.0f64;
    while x <= f64::from(max) * 1.0001 {
        v.push(x.round() as u32);
        x *= 2f64.powf(0.25);
    }
    v.dedup();
    v
}

/// Warm start: the window end of the exact steady state (s = ±w there).
pub fn warm_state<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Option<State<T>> {
    let (_, arcs) = exact::steady_state::<T, M>(d, v).ok()?;
    let last = arcs.last()?;
    let (_, c) = M::sin_cos(last.end);
    let w = T::ONE - d.a * c;
    let s = if v > T::ZERO { w } else { -w };
    Some(State {
        phase: last.end,
        stretch: s,
    })
}

fn fixed_series<T: Float, M: Math<T>>(
    out: &mut Vec<Point>,
    scene: &'static str,
    (method, warm): (&str, bool),
    d: &Drive<T>,
    v: T,
    reference: f64,
    steps: &[u32],
) {
    for &n in steps {
        let mut cfg = FixedStepConfig::<T>::new(n);
        cfg.max_periods = 20_000;
        let start = if warm {
            match warm_state::<T, M>(d, v) {
                Some(s) => Start::State(s),
                None => Start::Rest,
            }
        } else {
            Start::Rest
        };
        match run_dimensionless::<T, M>(d, v, &cfg, start) {
            Ok(r) => {
                let t = time_min(|| {
                    black_box(
                        run_dimensionless::<T, M>(black_box(d), black_box(v), &cfg, start).ok(),
                    );
                });
                out.push(Point {
                    scene,
                    method: method.to_string(),
                    steps: Some(n),
                    error: Some((r.mu_over_mu0.to_f64() - reference).abs()),
                    time_s: t,
                    bound: Some(r.error_bound.to_f64()),
                    status: "ok".into(),
                });
            }
            Err(e) => out.push(Point {
                scene,
                method: method.to_string(),
                steps: Some(n),
                error: None,
                time_s: f64::NAN,
                bound: None,
                status: refusal_kind(&e).to_string(),
            }),
        }
    }
}

/// All points for one scene.
pub fn measure_scene(
    name: &'static str,
    a: f64,
    b: f64,
    phi: f64,
    x: f64,
    steps: &[u32],
) -> CliResult<Vec<Point>> {
    let s = Scene::dimensionless(Groups {
        duz_rel: a,
        dux_rel: b,
        phi,
    })
    .map_err(|e| CliError::failure(e.to_string()))?;
    let d = s.drive();
    let v = x * if x > 0.0 {
        d.c_forward::<Libm>()
    } else {
        d.c_backward::<Libm>()
    };
    let reference =
        exact::mu_over_mu0::<f64, Libm>(&d, v).map_err(|e| CliError::failure(format!("{e}")))?;
    let d32 = Drive::new::<Libm>(a as f32, b as f32, phi as f32);
    let d32m = Drive::new::<Micromath>(a as f32, b as f32, phi as f32);
    let v32 = v as f32;
    let mut out = Vec::new();
    let point = |method: &str, r: Option<f64>, t: f64, bound: f64| Point {
        scene: name,
        method: method.to_string(),
        steps: None,
        error: r.map(|m| (m - reference).abs()),
        time_s: t,
        bound: Some(bound),
        status: if r.is_some() {
            "ok".into()
        } else {
            "failed".into()
        },
    };
    let r = exact::mu_over_mu0::<f64, Libm>(&d, v).ok();
    let t = time_min(|| {
        black_box(exact::mu_over_mu0::<f64, Libm>(black_box(&d), black_box(v)).ok());
    });
    out.push(point(
        "exact f64",
        r,
        t,
        exact::error_bound::<f64, Libm>(&d),
    ));
    let r = exact::mu_over_mu0::<f32, Libm>(&d32, v32)
        .ok()
        .map(f64::from);
    let t = time_min(|| {
        black_box(exact::mu_over_mu0::<f32, Libm>(black_box(&d32), black_box(v32)).ok());
    });
    out.push(point(
        "exact f32",
        r,
        t,
        exact::error_bound::<f32, Libm>(&d32).into(),
    ));
    let r = exact::mu_over_mu0::<f32, Micromath>(&d32m, v32)
        .ok()
        .map(f64::from);
    let t = time_min(|| {
        black_box(exact::mu_over_mu0::<f32, Micromath>(black_box(&d32m), black_box(v32)).ok());
    });
    out.push(point(
        "exact f32 micromath",
        r,
        t,
        exact::error_bound::<f32, Micromath>(&d32m).into(),
    ));
    if let Ok((kind, m)) = approx_mu_over_mu0(&s, v) {
        let t = time_min(|| {
            black_box(approx_mu_over_mu0(black_box(&s), black_box(v)).ok());
        });
        let (label, amp) = match kind {
            model_core::analytic::ApproxKind::NormalEq21 => ("eq. 21", a),
            model_core::analytic::ApproxKind::TangentialEq24 => ("eq. 24", b),
        };
        out.push(point(
            label,
            Some(m),
            t,
            model_core::analytic::approx::MAX_ERROR_OVER_A * amp,
        ));
    }
    fixed_series::<f64, Libm>(
        &mut out,
        name,
        ("fixed f64 from rest", false),
        &d,
        v,
        reference,
        steps,
    );
    fixed_series::<f64, Libm>(
        &mut out,
        name,
        ("fixed f64 warm", true),
        &d,
        v,
        reference,
        steps,
    );
    fixed_series::<f32, Libm>(
        &mut out,
        name,
        ("fixed f32 from rest", false),
        &d32,
        v32,
        reference,
        steps,
    );
    fixed_series::<f32, Libm>(
        &mut out,
        name,
        ("fixed f32 warm", true),
        &d32,
        v32,
        reference,
        steps,
    );
    fixed_series::<f32, Micromath>(
        &mut out,
        name,
        ("fixed f32 micromath", false),
        &d32m,
        v32,
        reference,
        steps,
    );
    Ok(out)
}

/// Least-squares slope of −log(error) against log(N), over points above the
/// rounding floor (1e-13 in f64, 1e-6 in f32).
pub fn fitted_order(points: &[&Point]) -> Option<f64> {
    let floor = if points.first()?.method.contains("f32") {
        1e-6
    } else {
        1e-13
    };
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|p| match (p.steps, p.error) {
            (Some(n), Some(e)) if e > floor => Some((f64::from(n).ln(), e.ln())),
            _ => None,
        })
        .collect();
    if xy.len() < 4 {
        return None;
    }
    let m = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / m,
        xy.iter().map(|p| p.1).sum::<f64>() / m,
    );
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    Some(-sxy / sxx)
}

/// `fricctl bench work-precision`.
pub fn run(a: &WpArgs) -> CliResult {
    if !a.max_steps.is_power_of_two() || !(8..=65536).contains(&a.max_steps) {
        return Err(CliError::usage(
            "--max-steps: must be a power of two in 8..=65536",
        ));
    }
    prepare_out_dir(&a.out)?;
    let steps = steps_list(a.max_steps);
    let mut all = Vec::new();
    for &(name, aa, b, phi, x) in SCENES {
        eprintln!("measuring {name} …");
        all.extend(measure_scene(name, aa, b, phi, x, &steps)?);
    }
    // Across lift-off: one steps-per-period value per octave (the series
    // are for the order, which one per octave shows).
    let octaves: Vec<u32> = steps
        .iter()
        .copied()
        .filter(|n| n.is_power_of_two())
        .collect();
    for &(name, aa) in across_lift_off::FLAT {
        eprintln!("measuring {name} …");
        all.extend(across_lift_off::measure_flat(name, aa, &octaves)?);
    }
    for &(name, aa) in across_lift_off::SPHERE {
        eprintln!("measuring {name} …");
        all.extend(across_lift_off::measure_sphere(name, aa)?);
    }
    // CSV.
    let mut csv = String::from(
        "scene,method,steps_per_period,error_over_mu0,time_s,error_bound_over_mu0,status\n",
    );
    for p in &all {
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
    let csv_path = a.out.join("work_precision.csv");
    std::fs::write(&csv_path, csv)
        .map_err(|e| CliError::failure(format!("{}: {e}", csv_path.display())))?;
    // Orders.
    let mut orders = String::from("scene,method,fitted_order\n");
    for &(name, ..) in SCENES {
        for m in [
            "fixed f64 from rest",
            "fixed f64 warm",
            "fixed f32 from rest",
            "fixed f32 warm",
            "fixed f32 micromath",
        ] {
            let pts: Vec<&Point> = all
                .iter()
                .filter(|p| p.scene == name && p.method == m)
                .collect();
            let o = fitted_order(&pts);
            let _ = writeln!(
                orders,
                "{name},{m},{}",
                o.map_or(String::new(), |o| format!("{o:.3}"))
            );
            println!(
                "{name:18} {m:22} order {}",
                o.map_or("-".to_string(), |o| format!("{o:.2}"))
            );
        }
    }
    for &(name, _) in across_lift_off::FLAT {
        for m in ["fixed f64 from rest", "lift-off stepping f64"] {
            let pts: Vec<&Point> = all
                .iter()
                .filter(|p| p.scene == name && p.method == m)
                .collect();
            if let Some(o) = fitted_order(&pts) {
                let _ = writeln!(orders, "{name},{m},{o:.3}");
                println!("{name:28} {m:22} order {o:.2}");
            }
        }
    }
    let op = a.out.join("convergence_orders.csv");
    std::fs::write(&op, orders).map_err(|e| CliError::failure(format!("{}: {e}", op.display())))?;
    for ext in ["svg", "png"] {
        let p = a.out.join(format!("work_precision.{ext}"));
        render(&p, &all)?;
        eprintln!("wrote {}", p.display());
    }
    eprintln!("wrote {} and {}", csv_path.display(), op.display());
    Ok(())
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

fn render(path: &Path, all: &[Point]) -> CliResult {
    let drawn: Vec<&Point> = all.iter().filter(|p| p.error.is_some()).collect();
    // Shared axes: every panel spans every point.
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
    // Legend: the scenes as colour swatches, then the methods as black markers.
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
    let f = Figure {
        panels,
        rows: 4,
        cols: 2,
        size: (1800, 2150),
        legend,
        caption: vec![
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
        ],
    };
    render_figure(path, &f)
}
