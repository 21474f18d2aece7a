//! `fricctl bench methods`: what "model no more than the scene needs" buys.
//!
//! The curve and map commands' own code paths ([`curve_rows`],
//! [`mu_cells`]) are timed, in one process, with `--method auto` (at a loose
//! tolerance and at the default, tight one), `--method exact` and
//! `--method fixed`; time is wall-clock for the whole command body (rayon on
//! all cores), the minimum over repeats, and is reported per point. The
//! fixed-step runs use fewer points (they are ~10⁴× slower) and are compared
//! per point. A last case times curved profiles ([`profile_case`]): the
//! flat punch against a sphere and a cone through the MDR quadrature
//! (`select::mu_within_profile`) at three tolerances, on fewer points.

use std::fmt::Write as _;
use std::time::Instant;

use clap::Args;
use model_core::{Groups, Scene};

use crate::args::Count;
use crate::error::{CliError, CliResult};
use crate::eval::{from_rel, Method, MethodArgs};
use crate::plot::{color, log_axis_tick, prepare_out_dir, write_chart};
use crate::sweep::{centres, curve_rows, linspace, method_mix, mix_text, mu_cells};
use model_core::analytic::CriticalVelocity;

/// Flags of `bench methods`.
#[derive(Args, Debug, Clone)]
pub struct MethodsArgs {
    /// Output directory (methods.csv, methods.svg, methods.png)
    #[arg(long, value_name = "DIR")]
    pub out: std::path::PathBuf,
    /// Velocities per curve (even, so that v0 = 0 is not among them)
    #[arg(long, default_value_t = 200_000, value_parser = Count::<usize>::at_least(2).at_most(10_000_000, "as `fricctl curve`"))]
    pub points: usize,
    /// Cells per map axis
    #[arg(long, default_value_t = 100, value_parser = Count::<usize>::at_least(2).at_most(1000, "as `fricctl map`"))]
    pub res: usize,
    /// Velocities per curve for the fixed-step runs
    #[arg(long, default_value_t = 100, value_parser = Count::<usize>::at_least(2).at_most(100_000, "the fixed-step method is slow"))]
    pub fixed_points: usize,
    /// Cells per map axis for the fixed-step runs
    #[arg(long, default_value_t = 10, value_parser = Count::<usize>::at_least(2).at_most(1000, "as `fricctl map`"))]
    pub fixed_res: usize,
    /// Steps per period of the fixed-step runs
    #[arg(long, default_value_t = 10_000, value_parser = Count::<u32>::at_least(1))]
    pub steps_per_period: u32,
    /// The loose tolerance for `auto`, units of μ0
    #[arg(long, default_value_t = 1e-2, value_parser = crate::args::Real::positive())]
    pub tol: f64,
    /// Repeats (the minimum is kept)
    #[arg(long, default_value_t = 5, value_parser = Count::<usize>::at_least(1).at_most(1000, "timing repeats"))]
    pub repeats: usize,
    /// Velocities per curve for the curved-profile (MDR) runs
    #[arg(long, default_value_t = 2_000, value_parser = Count::<usize>::at_least(2).at_most(1_000_000, "the MDR curve's largest"))]
    pub mdr_points: usize,
}

/// One timed configuration.
#[derive(Debug, Clone)]
pub struct Timing {
    /// Which command and scene.
    pub case: &'static str,
    /// Method label.
    pub method: String,
    /// Points (velocities or cells).
    pub points: usize,
    /// Seconds for all points (minimum over repeats).
    pub total_s: f64,
    /// Which computations answered, with counts.
    pub mix: String,
}

impl Timing {
    /// Seconds per point.
    pub fn per_point(&self) -> f64 {
        self.total_s / self.points as f64
    }
}

fn best_of<T>(repeats: usize, mut f: impl FnMut() -> CliResult<T>) -> CliResult<(f64, T)> {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let r = f()?;
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    // `repeats.max(1)` ≥ 1 iterations ran.
    last.map(|r| (best, r))
        .ok_or_else(|| CliError::failure("no repeat ran"))
}

fn configs(a: &MethodsArgs) -> Vec<(String, MethodArgs, bool)> {
    let m = |method, tol| MethodArgs {
        method,
        steps_per_period: Some(a.steps_per_period),
        tol,
        ..MethodArgs::default()
    };
    vec![
        (
            format!("auto --tol {:e}", a.tol),
            m(Method::Auto, Some(a.tol)),
            false,
        ),
        (
            "auto (default tol)".to_string(),
            m(Method::Auto, None),
            false,
        ),
        ("exact".to_string(), m(Method::Exact, None), false),
        (
            format!("fixed N={}", a.steps_per_period),
            m(Method::Fixed, None),
            true,
        ),
    ]
}

/// Times the curve command's body on one scene.
fn curve_case(
    a: &MethodsArgs,
    case: &'static str,
    g: Groups<f64>,
    out: &mut Vec<Timing>,
) -> CliResult {
    let s = Scene::dimensionless(g).map_err(|e| CliError::failure(e.to_string()))?;
    let vc = CriticalVelocity::of(&s);
    for (label, how, fixed) in configs(a) {
        let n = if fixed { a.fixed_points } else { a.points };
        let vs: Vec<f64> = linspace(-1.5, 1.5, n)
            .into_iter()
            .map(|x| from_rel(&vc, x, "v-rel"))
            .collect::<CliResult<_>>()?;
        let (t, rows) = best_of(a.repeats, || curve_rows(&s, &vs, &how))?;
        out.push(Timing {
            case,
            method: label,
            points: n,
            total_s: t,
            mix: mix_text(&method_mix(rows.iter().map(|r| r.method)), " + "),
        });
    }
    Ok(())
}

/// Times μ over a velocity curve for the flat punch and curved profiles
/// (`select::mu_within_profile`, rayon over the points as the curve command),
/// without and with lift-off.
fn profile_case(a: &MethodsArgs, out: &mut Vec<Timing>) -> CliResult {
    for (duz_rel, case) in [
        (0.5, "curve, profiles (Δu_z/u_z0 = 0.5, k_xΔu_x/(μ0 k_z u_z0) = 0.25, φ = 1 rad = 57.3°; u_z0 read as the mean indentation), v/v_c in [-1.5, 1.5]"),
        (1.5, "curve, profiles with lift-off (Δu_z/u_z0 = 1.5, k_xΔu_x/(μ0 k_z u_z0) = 0.25, φ = 1 rad = 57.3°; u_z0 read as the mean indentation), v/v_c in [-1.5, 1.5]"),
    ] {
        profile_scene(a, duz_rel, case, out)?;
    }
    Ok(())
}

/// [`profile_case`] for one drive: the flat punch (single-spring solver
/// below `Δu_z/u_z0 = 1`, the lift-off branch from 1) and a sphere and a
/// cone through the MDR quadrature at three tolerances.
fn profile_scene(
    a: &MethodsArgs,
    duz_rel: f64,
    case: &'static str,
    out: &mut Vec<Timing>,
) -> CliResult {
    use model_core::mdr::Profile;
    use model_core::select;
    use model_core::Libm;
    use rayon::prelude::*;
    let g = Groups {
        duz_rel,
        dux_rel: 0.25,
        phi: 1.0,
    };
    let s = Scene::dimensionless_with_contact(g, model_core::scene::ContactMode::Intermittent)
        .map_err(|e| CliError::failure(e.to_string()))?;
    let vc = CriticalVelocity::of(&s);
    let vs: Vec<f64> = linspace(-1.5, 1.5, a.mdr_points)
        .into_iter()
        .map(|x| from_rel(&vc, x, "v-rel"))
        .collect::<CliResult<_>>()?;
    let flat_tol = if duz_rel < 1.0 {
        model_core::exact::error_bound::<f64, Libm>(&s.drive())
    } else {
        model_core::model::liftoff::error_bound::<f64, Libm>(&s.drive())
    };
    let configs: [(&str, Profile<f64>, f64); 7] = [
        (
            if duz_rel < 1.0 {
                "flat auto (default tol)"
            } else {
                "flat auto (default tol; lift-off solver)"
            },
            Profile::Flat,
            flat_tol,
        ),
        ("sphere mdr --tol 1e-6", Profile::Sphere, 1e-6),
        ("sphere mdr --tol 1e-8", Profile::Sphere, 1e-8),
        ("sphere mdr --tol 1e-9", Profile::Sphere, 1e-9),
        ("cone mdr --tol 1e-6", Profile::Cone, 1e-6),
        ("cone mdr --tol 1e-8", Profile::Cone, 1e-8),
        ("cone mdr --tol 1e-9", Profile::Cone, 1e-9),
    ];
    for (label, p, tol) in configs {
        let (t, methods) = best_of(a.repeats, || {
            vs.par_iter()
                .map(|&v| {
                    select::mu_within_profile::<f64, Libm>(&s, &p, v, tol)
                        .map(|ans| ans.method.name())
                        .map_err(|e| {
                            let why = match e {
                                select::SelectError::BadTolerance => {
                                    "tol: must be a finite number > 0".to_string()
                                }
                                select::SelectError::ToleranceTooTight { best } => {
                                    format!(
                                        "tol: tighter than any method guarantees (best {best:e})"
                                    )
                                }
                                select::SelectError::Exact(e) => e.to_string(),
                                select::SelectError::Mdr(e) => e.to_string(),
                            };
                            CliError::failure(format!("{label} at v0 = {v:e} m/s: {why}"))
                        })
                })
                .collect::<CliResult<Vec<_>>>()
        })?;
        out.push(Timing {
            case,
            method: label.to_string(),
            points: vs.len(),
            total_s: t,
            mix: mix_text(&method_mix(methods), " + "),
        });
    }
    Ok(())
}

/// Times the μ map's body (Δu_z/u_z0 = 0.5, v0 = 0.5·v_c).
fn map_case(a: &MethodsArgs, out: &mut Vec<Timing>) -> CliResult {
    for (label, how, fixed) in configs(a) {
        let res = if fixed { a.fixed_res } else { a.res };
        let ratios = centres(0.0, 3.0, res);
        let phis = centres(0.0, 360.0, res);
        let (t, cells) = best_of(a.repeats, || mu_cells(0.5, &ratios, &phis, 0.5, &how))?;
        let mix = method_mix(cells.iter().map(|c| c.method));
        out.push(Timing {
            case: "map --v-rel 0.5 (dual mode, Δu_z/u_z0 = 0.5, φ × ratio over 0…360° × 0…3)",
            method: label,
            points: cells.len(),
            total_s: t,
            mix: mix_text(&mix, " + "),
        });
    }
    Ok(())
}

/// `fricctl bench methods`.
pub fn run(a: &MethodsArgs) -> CliResult {
    // Every count is in its range and --tol > 0 (the flags' parsers); the
    // curves need an even number of points (v = 0 between two of them).
    for (n, flag) in [
        (a.points, "--points"),
        (a.fixed_points, "--fixed-points"),
        (a.mdr_points, "--mdr-points"),
    ] {
        if n % 2 == 1 {
            return Err(CliError::usage(format!("{flag}: must be even (got {n})")));
        }
    }
    prepare_out_dir(&a.out)?;
    let mut out = Vec::new();
    eprintln!("timing curves …");
    curve_case(
        a,
        "curve, normal only (Δu_z/u_z0 = 0.4), v/v_c in [-1.5, 1.5]",
        Groups {
            duz_rel: 0.4,
            dux_rel: 0.0,
            phi: 0.0,
        },
        &mut out,
    )?;
    curve_case(
        a,
        "curve, dual mode (Δu_z/u_z0 = 0.5, k_xΔu_x/(μ0 k_z u_z0) = 0.25, φ = 1 rad = 57.3°), v/v_c in [-1.5, 1.5]",
        Groups {
            duz_rel: 0.5,
            dux_rel: 0.25,
            phi: 1.0,
        },
        &mut out,
    )?;
    eprintln!("timing maps …");
    map_case(a, &mut out)?;
    eprintln!("timing curved profiles (MDR) …");
    profile_case(a, &mut out)?;
    let mut csv = String::from("case,method,points,total_s,per_point_s,ratio_to_first,mix\n");
    let mut last_case = "";
    let mut first = 0.0;
    let width = out
        .iter()
        .map(|t| t.method.chars().count())
        .max()
        .unwrap_or(0);
    for t in &out {
        if t.case != last_case {
            last_case = t.case;
            first = t.per_point();
            println!("{}", t.case);
        }
        let ratio = t.per_point() / first;
        println!(
            "  {:width$} {:>8} points {:>10.3e} s/point  ×{:<10.1} {}",
            t.method,
            t.points,
            t.per_point(),
            ratio,
            t.mix
        );
        let _ = writeln!(
            csv,
            "\"{}\",{},{},{},{},{},{}",
            t.case,
            t.method,
            t.points,
            t.total_s,
            t.per_point(),
            ratio,
            t.mix
        );
    }
    let p = a.out.join("methods.csv");
    std::fs::write(&p, csv).map_err(|e| CliError::failure(format!("{}: {e}", p.display())))?;
    eprintln!("wrote {}", p.display());
    for ext in ["svg", "png"] {
        let path = a.out.join(format!("methods.{ext}"));
        chart(&path, &out)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// `x` with three significant digits (x ≥ 0.001).
fn sig3(x: f64) -> String {
    let decimals = if x >= 100.0 {
        0
    } else if x >= 10.0 {
        1
    } else if x >= 1.0 {
        2
    } else {
        3
    };
    format!("{x:.decimals$}")
}

/// Seconds as ns, µs or ms, three significant digits.
fn time_text(s: f64) -> String {
    if s < 1e-6 {
        format!("{} ns", sig3(s * 1e9))
    } else if s < 1e-3 {
        format!("{} µs", sig3(s * 1e6))
    } else {
        format!("{} ms", sig3(s * 1e3))
    }
}

/// Palette index of a method label.
fn method_color(method: &str) -> usize {
    if method.starts_with("auto --tol") {
        2
    } else if method.starts_with("auto") {
        0
    } else if method == "exact" {
        1
    } else if method.contains("mdr") {
        4
    } else {
        8
    }
}

/// A dot per case × method: time per point on a log axis (a dot, not a bar:
/// a log axis has no zero for a bar to start from), with the method, its cost
/// relative to the case's first row and the mix that answered.
fn chart(path: &std::path::Path, rows: &[Timing]) -> CliResult {
    use plotters::prelude::*;
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let mut cases: Vec<&str> = Vec::new();
    for t in rows {
        if !cases.contains(&t.case) {
            cases.push(t.case);
        }
    }
    let per: Vec<f64> = rows.iter().map(Timing::per_point).collect();
    let lo = per.iter().copied().fold(f64::INFINITY, f64::min) / 3.0;
    let hi = per.iter().copied().fold(0.0, f64::max) * 3000.0;
    let n_rows = (cases.len() + rows.len()) as f64 + 0.5 * cases.len() as f64;
    write_chart(path, (1500, 820), |root| {
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(root)
            .caption(
                "bench methods: time per point of the curve and map commands",
                ("sans-serif", 20),
            )
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(8)
            .build_cartesian_2d((lo..hi).log_scale(), 0.0..n_rows)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .disable_y_axis()
            .x_desc(
                "time per point, s (wall clock, rayon on all cores, minimum of repeats; log scale)",
            )
            .x_label_formatter(&|v| log_axis_tick(*v))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(210, 210, 210))
            .draw()?;
        let left = Pos::new(HPos::Left, VPos::Center);
        let head = TextStyle::from(("sans-serif", 16).into_font()).pos(left);
        let text = TextStyle::from(("sans-serif", 14).into_font()).pos(left);
        let mut y = n_rows - 0.7;
        for case in &cases {
            chart.draw_series(std::iter::once(Text::new(
                case.to_string(),
                (lo * 1.1, y),
                head.clone(),
            )))?;
            y -= 1.0;
            let mut first = None;
            for t in rows.iter().filter(|t| t.case == *case) {
                let v = t.per_point();
                let base = *first.get_or_insert(v);
                let c = color(method_color(&t.method));
                // A thin guide from the axis to the dot, then the dot.
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(lo, y), (v, y)],
                    RGBColor(215, 215, 215).stroke_width(1),
                )))?;
                chart.draw_series(std::iter::once(Circle::new((v, y), 6, c.filled())))?;
                chart.draw_series(std::iter::once(Text::new(
                    format!(
                        "{}: {} per point (×{}), {} points; {}",
                        t.method,
                        time_text(v),
                        sig3(v / base),
                        t.points,
                        t.mix
                    ),
                    (v * 1.6, y),
                    text.clone(),
                )))?;
                y -= 1.0;
            }
            y -= 0.5;
        }
        Ok(())
    })
}
