//! `fricctl fit`: the contact parameters that make the model reproduce a
//! measured sweep (see [`crate::fit`] for the method and its intervals).

use std::io::Write;
use std::path::PathBuf;

use clap::Args;

use crate::error::{CliError, CliResult};
use crate::fit::{fit, FitParam, FitResult, Residual};
use crate::output::{stdout_error, write_json, AtomicFile};
use crate::plot::{render_panels, Mark, Panel, Series};
use crate::sweep_file;

/// Flags of `fricctl fit`.
#[derive(Args, Debug, Clone)]
pub struct FitCmd {
    /// The sweep file written by `fricctl device sweep --csv`
    #[arg(long, value_name = "SWEEP.csv")]
    data: PathBuf,
    /// Parameters to fit, comma-separated: mu0, kx_over_kz (the others keep the device model's value)
    #[arg(long, default_value = "mu0,kx_over_kz")]
    params: String,
    /// Write the result (JSON) to FILE, for `fricctl device scene set --from-fit FILE`
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Plot the residuals (μ measured − μ fit, with ±1 standard-error bars) against the swept value to FILE.svg or FILE.png
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// JSON output
    #[arg(long)]
    json: bool,
}

impl FitCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let which = FitParam::parse_list(&self.params)?;
        crate::output::check_outputs(&[
            (self.out.as_deref(), "out"),
            (self.plot.as_deref(), "plot"),
        ])?;
        let rows = sweep_file::read(&self.data)?;
        let (r, residuals) = fit(&rows, &which)?;
        if let Some(p) = &self.out {
            let mut f = AtomicFile::create(p, "out")?;
            let s = serde_json::to_string_pretty(&r)
                .map_err(|e| CliError::failure(format!("JSON: {e}")))?;
            f.write_all(s.as_bytes())?;
            f.write_all(b"\n")?;
            f.commit()?;
        }
        if let Some(p) = &self.plot {
            let param = rows.first().map_or("value", |r| r.param.as_str());
            plot_residuals(p, param, &r, &residuals)?;
            eprintln!("wrote {}", p.display());
        }
        if self.json {
            write_json(out, &r)?;
        } else {
            write_text(out, &r).map_err(stdout_error)?;
        }
        // A χ² its distribution does not reach (analysis::fit, "Goodness of
        // fit"): the result is printed, the verdict is exit 1.
        match r.doubtful() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// The aligned text summary.
fn write_text(out: &mut impl Write, r: &FitResult) -> std::io::Result<()> {
    let held = |name: &str| !r.fitted.split(',').any(|f| f == name);
    let line = |v: f64, lo: f64, hi: f64, held: bool| {
        if held {
            format!("{v:<12.6} (held at the device model's value)")
        } else {
            format!("{v:<12.6} 95 % interval [{lo:.6}, {hi:.6}]")
        }
    };
    writeln!(
        out,
        "μ0           {}",
        line(r.mu0, r.mu0_ci95_low, r.mu0_ci95_high, held("mu0"))
    )?;
    writeln!(
        out,
        "kx/kz        {}",
        line(
            r.kx_over_kz,
            r.kx_over_kz_ci95_low,
            r.kx_over_kz_ci95_high,
            held("kx_over_kz")
        )
    )?;
    writeln!(out, "kz           {:.6e} N/m (the device model's)", r.kz)?;
    writeln!(out, "kx           {:.6e} N/m", r.kx)?;
    writeln!(
        out,
        "rows         {} used, {} skipped (invalid estimates)",
        r.rows_used, r.rows_skipped
    )?;
    writeln!(
        out,
        "χ²           {:.4} on {} degrees of freedom (χ²/ν = {:.3}){}",
        r.chi2,
        r.dof,
        r.reduced_chi2,
        if r.weighted {
            ""
        } else {
            ", unweighted: no standard errors in the data"
        }
    )?;
    if let Some(p) = r.chi2_p_value {
        writeln!(
            out,
            "p(χ²)        {} (the probability of a χ² this large if the model describes the data; below {} the fit is doubtful)",
            crate::args::Short(fric_analysis::numbers::round_sig(p, 2)),
            crate::args::Short(crate::fit::GOODNESS_P)
        )?;
    }
    writeln!(out, "rms residual {:.3e} (μ)", r.rms_residual_mu)
}

/// Residuals against the swept value, with ±1 standard-error bars.
fn plot_residuals(
    path: &std::path::Path,
    param: &str,
    r: &FitResult,
    res: &[Residual],
) -> CliResult {
    let mut bars = Vec::new();
    let mut pts = Vec::new();
    let (mut xlo, mut xhi, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for q in res {
        pts.push((q.value, q.residual_mu));
        bars.extend([
            (q.value, q.residual_mu - q.std_error),
            (q.value, q.residual_mu + q.std_error),
            (q.value, f64::NAN),
        ]);
        xlo = xlo.min(q.value);
        xhi = xhi.max(q.value);
        ymax = ymax.max(q.residual_mu.abs() + q.std_error);
    }
    let pad = if xhi > xlo { 0.05 * (xhi - xlo) } else { 1.0 };
    let ymax = if ymax > 0.0 { 1.2 * ymax } else { 1e-6 };
    let unit = match param {
        "phase-deg" => "°",
        "freq" => "Hz",
        _ => "m",
    };
    let panel = Panel {
        title: format!(
            "fit residuals: μ0 = {:.4}, kx/kz = {:.4} (fitted: {}), χ²/ν = {:.2}",
            r.mu0, r.kx_over_kz, r.fitted, r.reduced_chi2
        ),
        x_label: format!("{param} ({unit})"),
        y_label: "μ measured − μ fit".into(),
        x: (xlo - pad, xhi + pad),
        y: (-ymax, ymax),
        series: vec![
            Series {
                label: "residual".into(),
                points: pts,
                mark: Mark::Points,
                color: 0,
            },
            Series {
                label: "±1 standard error".into(),
                points: bars,
                mark: Mark::Line,
                color: 1,
            },
            Series {
                label: String::new(),
                points: vec![(xlo - pad, 0.0), (xhi + pad, 0.0)],
                mark: Mark::Dashed,
                color: 2,
            },
        ],
    };
    render_panels(path, &[panel], 1, 1, (1000, 650))
}
