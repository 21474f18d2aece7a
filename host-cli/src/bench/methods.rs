//! `fricctl bench methods`: what "model no more than the scene needs" buys.
//!
//! [`fric_analysis::bench::methods`] times the curve and map commands' own
//! code paths ([`fric_analysis::grid::curve_rows`],
//! [`fric_analysis::grid::mu_cells`]) with `--method auto` (at a loose
//! tolerance and at the default, tight one), `--method exact` and `--method
//! fixed`, and curved profiles through the MDR quadrature; this module writes `methods.csv`, the table on stdout
//! and the chart (SVG + PNG).

use std::fmt::Write as _;

use clap::Args;
use fric_analysis::bench::methods::{self as bench, ratios_to_first, Config, Timing};

use crate::args::Count;
use crate::error::{CliError, CliResult};
use crate::plot::{color, log_axis_tick, prepare_out_dir, write_chart};

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

impl MethodsArgs {
    /// The bench's sizes.
    fn config(&self) -> Config {
        Config {
            points: self.points,
            res: self.res,
            fixed_points: self.fixed_points,
            fixed_res: self.fixed_res,
            steps_per_period: self.steps_per_period,
            tol: self.tol,
            repeats: self.repeats,
            mdr_points: self.mdr_points,
        }
    }
}

/// `fricctl bench methods`.
pub fn run(a: &MethodsArgs) -> CliResult {
    // Every count is in its range and --tol > 0 (the flags' parsers); the
    // curves need an even number of points (v = 0 between two of them).
    let config = a.config();
    config.check()?;
    prepare_out_dir(&a.out)?;
    let out = bench::measure(&config, &mut |stage| eprintln!("{stage}"))?;
    let csv = table(&out);
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

/// `methods.csv`, with the table printed to stdout (a heading per case).
fn table(out: &[Timing]) -> String {
    let mut csv = String::from("case,method,points,total_s,per_point_s,ratio_to_first,mix\n");
    let mut last_case = "";
    let width = out
        .iter()
        .map(|t| t.method.chars().count())
        .max()
        .unwrap_or(0);
    for (t, ratio) in out.iter().zip(ratios_to_first(out)) {
        if t.case != last_case {
            last_case = t.case;
            println!("{}", t.case);
        }
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
    csv
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
