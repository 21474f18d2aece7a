//! `fricctl bench stability`: maps of where each method stops being
//! trustworthy, and how it says so.
//!
//! The planes and their cells — each one computation, judged against an
//! independent reference or failing explicitly — are
//! [`fric_analysis::bench::stability`]'s. Here every map is written as a CSV
//! (`x,y,outcome,error_over_mu0,allowed_over_mu0`) and a PNG: the error
//! `|Δμ|/μ0` in colour, each failure kind in its own, and a number outside
//! its stated bound (a silent failure) in red. The command fails if any cell
//! is red; `tests/stability.rs` asserts there are none on the same planes.

use std::fmt::Write as _;

use clap::Args;
use fric_analysis::bench::stability::{planes, Outcome, Plane};
use plotters::style::RGBColor;

use crate::error::{CliError, CliResult};
use crate::plot::{prepare_out_dir, render_heat, Heat, HeatMap};
use crate::progress::progress_bar;

/// Flags of `bench stability`.
#[derive(Args, Debug, Clone)]
pub struct StabilityArgs {
    /// Output directory (one PNG and one CSV per map)
    #[arg(long, value_name = "DIR")]
    pub out: std::path::PathBuf,
    /// Cells per map axis
    #[arg(long, default_value_t = 48, value_parser = crate::args::Count::<usize>::at_least(4).at_most(400, "the maps' largest"))]
    pub res: usize,
    /// Step budget of one fixed-step run (past it: not converged)
    #[arg(long, default_value_t = 20_000_000, value_parser = crate::args::Count::<u64>::at_least(1000).at_most(10_000_000_000, "a run's largest budget"))]
    pub budget: u64,
}

/// The colour of a failure kind.
fn class_color(name: &str) -> RGBColor {
    match name {
        "exceeds stated bound" => RGBColor(230, 0, 0),
        "too few steps" => RGBColor(150, 150, 150),
        "precision limit" => RGBColor(230, 159, 0),
        "not converged" => RGBColor(204, 121, 167),
        "ill-conditioned" => RGBColor(120, 70, 30),
        "out of range" => RGBColor(60, 60, 60),
        "not representable" => RGBColor(20, 20, 20),
        "no reference" => RGBColor(220, 220, 220),
        "inconsistent" => RGBColor(255, 0, 255),
        "lift-off" => RGBColor(86, 180, 233),
        "underflows to 0" => RGBColor(0, 0, 120),
        _ => RGBColor(0, 0, 0),
    }
}

/// Computes and writes one map; returns (cells, silent failures).
fn map(a: &StabilityArgs, p: &Plane) -> CliResult<(usize, usize)> {
    let (xs, ys) = p.axes(a.res);
    let n = xs.len() * ys.len();
    let pb = progress_bar(
        n as u64,
        &format!("{:24} {{bar:30}} {{pos}}/{{len}} ({{eta}})", p.name),
    );
    let outcomes = p.outcomes(&xs, &ys, &|| pb.inc(1));
    pb.finish_and_clear();
    let mut classes: Vec<(String, RGBColor)> = Vec::new();
    let mut class_of = |name: &str| -> usize {
        match classes.iter().position(|(c, _)| c == name) {
            Some(k) => k,
            None => {
                classes.push((name.to_string(), class_color(name)));
                classes.len() - 1
            }
        }
    };
    let mut csv = String::from("x,y,outcome,error_over_mu0,allowed_over_mu0\n");
    let mut cells = Vec::with_capacity(n);
    for (i, o) in outcomes.iter().enumerate() {
        let (x, y) = (xs[i % xs.len()], ys[i / xs.len()]);
        let r = o.record();
        cells.push(match *o {
            Outcome::Value { error, .. } if !o.exceeds() => Heat::Value(error.max(1e-17).log10()),
            _ => Heat::Class(class_of(r.outcome)),
        });
        let _ = writeln!(
            csv,
            "{x},{y},{},{},{}",
            r.outcome, r.error_over_mu0, r.allowed_over_mu0
        );
    }
    let silent = outcomes.iter().filter(|o| o.exceeds()).count();
    let csv_path = a.out.join(format!("{}.csv", p.name));
    std::fs::write(&csv_path, csv)
        .map_err(|e| CliError::failure(format!("{}: {e}", csv_path.display())))?;
    let png = a.out.join(format!("{}.png", p.name));
    render_heat(&png, &heat_map(p, xs, ys, cells, classes), (1000, 720))?;
    let bad: usize = outcomes
        .iter()
        .filter(|o| !matches!(o, Outcome::Value { .. }))
        .count();
    println!(
        "{:24} {} cells: {} explicit failures, {} outside the stated bound",
        p.name, n, bad, silent
    );
    Ok((n, silent))
}

/// The heat map of a plane's cells.
fn heat_map(
    p: &Plane,
    xs: Vec<f64>,
    ys: Vec<f64>,
    cells: Vec<Heat>,
    classes: Vec<(String, RGBColor)>,
) -> HeatMap {
    let range = crate::plot::heat_range(&cells, false).unwrap_or((-17.0, 0.0));
    HeatMap {
        title: p.title.clone(),
        x_label: p.x_label.to_string(),
        y_label: p.y_label.to_string(),
        xs,
        ys,
        log_x: p.log_x,
        log_y: p.log_y,
        range,
        cells,
        diverging: false,
        // The colour range is the data's, stated on the bar.
        value_label: format!(
            "log10 |Δμ|/μ0 ({} … {})",
            crate::plot::minus(&format!("{:.1}", range.0)),
            crate::plot::minus(&format!("{:.1}", range.1))
        ),
        classes,
    }
}

/// `fricctl bench stability`.
pub fn run(a: &StabilityArgs) -> CliResult {
    // `a.res` and `a.budget` are in their ranges (the flags' parsers).
    prepare_out_dir(&a.out)?;
    let mut silent = 0;
    for p in planes(a.budget) {
        silent += map(a, &p)?.1;
    }
    if silent > 0 {
        return Err(CliError::failure(format!(
            "{silent} cells returned a number outside the method's stated bound (red in the maps)"
        )));
    }
    eprintln!("wrote the maps to {}", a.out.display());
    Ok(())
}
