//! `fricctl device sweep --plot`: measured μ with ±1 standard-error bars
//! and the device's predicted μ at the swept values; the title names the
//! drive values the sweep held fixed, the y label the device's model.

use std::path::Path;

use fric_analysis::sweep_file::SweepRow;

use crate::error::{CliError, CliResult};
use crate::plot::{render_figure, Extras, Figure, Mark, Marker, Panel, Series};
use device_host::sweep::{fixed_columns, SweepParam};

/// Measured μ of a sweep of `param` (predictions at `v0`, m/s) with ±1 standard-error bars and the device's predicted μ
/// against the swept value.
///
/// # Errors
/// No measured point, or the file cannot be written.
pub fn plot(path: &Path, param: SweepParam, v0: f64, rows: &[SweepRow]) -> CliResult {
    let mut meas = Vec::new();
    let mut bars = Vec::new();
    let mut pred = Vec::new();
    let (mut xlo, mut xhi) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut ylo, mut yhi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in rows.iter().filter(|r| r.measured_mu.is_finite()) {
        meas.push((r.value, r.measured_mu));
        bars.push((
            r.value,
            r.measured_mu - r.std_error,
            r.measured_mu + r.std_error,
            0,
        ));
        pred.push((r.value, r.predicted_mu));
        xlo = xlo.min(r.value);
        xhi = xhi.max(r.value);
        for y in [
            r.measured_mu - r.std_error,
            r.measured_mu + r.std_error,
            r.predicted_mu,
        ] {
            ylo = ylo.min(y);
            yhi = yhi.max(y);
        }
    }
    if meas.is_empty() {
        return Err(CliError::failure("--plot: no measured point to plot"));
    }
    let xpad = if xhi > xlo { 0.05 * (xhi - xlo) } else { 1.0 };
    let ypad = if yhi > ylo { 0.1 * (yhi - ylo) } else { 0.01 };
    let r0 = &rows[0];
    let mut fixed: Vec<String> = fixed_columns(param, r0)
        .into_iter()
        .map(|(n, v)| match n {
            "freq_hz" => format!("f = {v:.1} Hz"),
            "phi_deg" => format!("φ = {v:.2}°"),
            "amp_z" => format!("Δu_z = {v:.2e} m"),
            "amp_x" => format!("Δu_x = {v:.2e} m"),
            _ => format!("u_z0 = {v:.2e} m"),
        })
        .collect();
    fixed.push(format!("v0 = {v0} m/s"));
    let panel = Panel {
        title: format!("sweep of {}: {}", param.name(), fixed.join(", ")),
        x_label: format!("{} ({})", param.name(), param.unit()),
        // The axis is μ, measured and predicted alike; the model the
        // prediction used is named in the legend and the caption.
        y_label: "μ".to_string(),
        x: (xlo - xpad, xhi + xpad),
        y: (ylo - ypad, yhi + ypad),
        // Points only: a line through the swept values would draw a curve
        // that was neither measured nor computed between them.
        series: vec![
            Series {
                label: "predicted μ at the swept values (the device's model)".into(),
                points: pred,
                mark: Mark::Markers(Marker::OpenDiamond),
                color: 1,
            },
            Series {
                label: "measured μ, ±1 standard error".into(),
                points: meas,
                mark: Mark::Points,
                color: 0,
            },
        ],
    };
    render_figure(
        path,
        &Figure {
            panels: vec![(
                panel,
                Extras {
                    error_bars: bars,
                    ..Extras::default()
                },
            )],
            rows: 1,
            cols: 1,
            size: (1100, 650),
            legend: Vec::new(),
            caption: vec![format!(
                "Prediction: the device's model with μ_{{0}} = {}, k_{{z}} = {:.3e} N/m, k_{{x}} = {:.3e} N/m, \
                 at each swept value.",
                // The device holds μ0 in f32: its shortest f32 text (0.3, not 0.300000011921).
                r0.model_mu0 as f32,
                r0.model_kz,
                r0.model_kx
            )],
        },
    )
}
