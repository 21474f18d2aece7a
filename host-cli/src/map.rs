//! `fricctl map`: the regime map over phase and amplitude ratio.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use model_core::regime::{classify, ClassifyOptions, Regime};
use model_core::{Groups, Scene};
use plotters::style::RGBColor;
use rayon::prelude::*;

use crate::commands::{method_mix, mix_text};
use crate::compute::{from_rel, mu_at, Method, MethodArgs};
use crate::error::{CliError, CliResult};
use crate::plot::{render_heat, render_map, Heat, HeatMap, RegimeMap};
use model_core::analytic::CriticalVelocity;

/// Flags of `fricctl map`.
#[derive(Args, Debug, Clone)]
pub struct MapArgs {
    /// Δu_z/u_z0 (fixed for the map)
    #[arg(long, allow_hyphen_values = true)]
    pub duz_rel: f64,
    /// Smallest amplitude ratio k_xΔu_x/(μ0 k_z Δu_z)
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub ratio_min: f64,
    /// Largest amplitude ratio
    #[arg(long, default_value_t = 3.0, allow_hyphen_values = true)]
    pub ratio_max: f64,
    /// Smallest phase, degrees
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub phi_min_deg: f64,
    /// Largest phase, degrees
    #[arg(long, default_value_t = 360.0, allow_hyphen_values = true)]
    pub phi_max_deg: f64,
    /// Cells per axis
    #[arg(long, default_value_t = 120)]
    pub res: usize,
    /// Plot file (.svg or .png)
    #[arg(long, value_name = "FILE")]
    pub plot: PathBuf,
    /// Also write the cells as CSV
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Map μ/μ0 at v0 = X·v_c (forward v_c for X > 0, backward for X < 0) instead of the regimes
    #[arg(long, value_name = "X", allow_hyphen_values = true)]
    pub v_rel: Option<f64>,
    /// How μ is computed per cell (with --v-rel)
    #[command(flatten)]
    pub how: MethodArgs,
}

/// The dimensionless scene of a map cell: `Δu_z/u_z0 = a`, amplitude ratio
/// `r` (eq. 26), phase in degrees.
pub fn cell_scene(a: f64, r: f64, phi_deg: f64) -> CliResult<Scene<f64>> {
    Scene::dimensionless(Groups {
        duz_rel: a,
        dux_rel: r * a,
        phi: phi_deg.to_radians(),
    })
    .map_err(|e| CliError::usage(format!("--{e}")))
}

/// One cell of a μ map.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct MuCell {
    /// φ, degrees.
    pub phi_deg: f64,
    /// k_xΔu_x/(μ0 k_z Δu_z).
    pub ratio: f64,
    /// v0 in units of ωW0.
    pub v0: f64,
    /// μ/μ0 (empty when a fixed-step run did not converge).
    pub mu_over_mu0: Option<f64>,
    /// Which computation answered.
    pub method: &'static str,
    /// The bound it guarantees, units of μ0.
    pub error_bound_over_mu0: Option<f64>,
}

/// μ/μ0 at `v0 = x·v_c` over (ratio rows, phase columns), each cell by the
/// method choice of `how`, in parallel.
pub fn mu_cells(
    a: f64,
    ratios: &[f64],
    phis_deg: &[f64],
    x: f64,
    how: &MethodArgs,
) -> CliResult<Vec<MuCell>> {
    let n = ratios.len() * phis_deg.len();
    (0..n)
        .into_par_iter()
        .map(|i| {
            let (r, phi) = (ratios[i / phis_deg.len()], phis_deg[i % phis_deg.len()]);
            let s = cell_scene(a, r, phi)?;
            let vc = CriticalVelocity::of(&s);
            let v = from_rel(&vc, x, "v-rel")?;
            let o =
                mu_at(&s, v, how).map_err(|e| e.with_context(&format!("ratio {r}, φ {phi}°")))?;
            Ok(MuCell {
                phi_deg: phi,
                ratio: r,
                v0: v,
                mu_over_mu0: o.mu_over_mu0,
                method: o.method,
                error_bound_over_mu0: o.error_bound_over_mu0,
            })
        })
        .collect()
}

fn run_mu_map(a: &MapArgs, x: f64) -> CliResult {
    if x == 0.0 {
        return Err(CliError::usage(
            "--v-rel: must be != 0 (at rest μ has two one-sided limits; the regime map shows them)",
        ));
    }
    let ratios = centres(a.ratio_min, a.ratio_max, a.res);
    let phis = centres(a.phi_min_deg, a.phi_max_deg, a.res);
    let cells = mu_cells(a.duz_rel, &ratios, &phis, x, &a.how)?;
    let mix = method_mix(cells.iter().map(|c| c.method));
    let mix_text = mix_text(&mix, ", ");
    let worst = cells
        .iter()
        .filter_map(|c| c.error_bound_over_mu0)
        .fold(0.0f64, f64::max);
    eprintln!(
        "{} cells: {mix_text} (largest error bound {worst:e} mu0)",
        cells.len()
    );
    let heat: Vec<Heat> = cells
        .iter()
        .map(|c| match c.mu_over_mu0 {
            Some(m) => Heat::Value(m),
            None => Heat::Class(0),
        })
        .collect();
    let (lo, hi) = cells
        .iter()
        .filter_map(|c| c.mu_over_mu0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| {
            (l.min(m), h.max(m))
        });
    let m = HeatMap {
        title: format!(
            "μ/μ0 at v0 = {x}·v_c, Δu_z/u_z0 = {} ({mix_text})",
            a.duz_rel
        ),
        x_label: "phase φ, degrees".to_string(),
        y_label: "k_xΔu_x / (μ0 k_z Δu_z)".to_string(),
        xs: phis,
        ys: ratios,
        log_x: false,
        log_y: false,
        cells: heat,
        range: if lo < hi {
            (lo, hi)
        } else {
            (lo - 0.5, lo + 0.5)
        },
        value_label: "μ/μ0".to_string(),
        classes: if cells.iter().any(|c| c.mu_over_mu0.is_none()) {
            vec![("not converged".to_string(), RGBColor(200, 0, 0))]
        } else {
            Vec::new()
        },
    };
    render_heat(&a.plot, &m, (1100, 760))?;
    eprintln!("wrote {}", a.plot.display());
    if let Some(p) = a.csv.as_deref() {
        write_rows(p, &cells)?;
    }
    Ok(())
}

/// Writes serialisable rows as CSV to `p`.
pub fn write_rows<T: serde::Serialize>(p: &Path, rows: &[T]) -> CliResult {
    let f = std::fs::File::create(p)
        .map_err(|e| CliError::failure(format!("--csv: cannot create {}: {e}", p.display())))?;
    let mut w = csv::Writer::from_writer(std::io::BufWriter::new(f));
    for c in rows {
        w.serialize(c)
            .map_err(|e| CliError::failure(format!("--csv: {}: {e}", p.display())))?;
    }
    w.flush()
        .map_err(|e| CliError::failure(format!("--csv: {}: {e}", p.display())))?;
    eprintln!("wrote {}", p.display());
    Ok(())
}

/// One map cell.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Cell {
    /// φ, degrees.
    pub phi_deg: f64,
    /// k_xΔu_x/(μ0 k_z Δu_z).
    pub ratio: f64,
    /// Class name.
    pub regime: &'static str,
    /// μ(0⁺)/μ0.
    pub mu_0plus_over_mu0: f64,
    /// μ(0⁻)/μ0.
    pub mu_0minus_over_mu0: f64,
    /// max |μ(v) + μ(−v)|/μ0.
    pub asymmetry: f64,
}

/// Computes the map cells (row-major: ratio rows, phase columns), in parallel.
pub fn cells(
    a: f64,
    ratios: &[f64],
    phis_deg: &[f64],
    progress: bool,
) -> CliResult<(Vec<Cell>, Vec<u8>)> {
    let n = ratios.len() * phis_deg.len();
    let pb = if progress {
        let pb = ProgressBar::with_draw_target(Some(n as u64), ProgressDrawTarget::stderr());
        pb.set_style(
            ProgressStyle::with_template("classifying {bar:40} {pos}/{len} cells ({eta})")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        pb
    } else {
        ProgressBar::hidden()
    };
    let res: Vec<CliResult<(Cell, u8)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let (r, phi) = (ratios[i / phis_deg.len()], phis_deg[i % phis_deg.len()]);
            let s = cell_scene(a, r, phi)?;
            let c = classify(&s, &ClassifyOptions::default()).map_err(|e| {
                crate::compute::exact_failure(e).with_context(&format!("ratio {r}, φ {phi}°"))
            })?;
            pb.inc(1);
            let k = match c.regime {
                Regime::ActiveControl => 0,
                Regime::DynamicRatchet => 1,
                Regime::Actuator => 2,
            };
            Ok((
                Cell {
                    phi_deg: phi,
                    ratio: r,
                    regime: c.regime.name(),
                    mu_0plus_over_mu0: c.mu_0plus,
                    mu_0minus_over_mu0: c.mu_0minus,
                    asymmetry: c.asymmetry,
                },
                k,
            ))
        })
        .collect();
    pb.finish_and_clear();
    let mut cells = Vec::with_capacity(n);
    let mut class = Vec::with_capacity(n);
    for r in res {
        let (c, k) = r?;
        cells.push(c);
        class.push(k);
    }
    Ok((cells, class))
}

/// Cell centres of `n` cells spanning `[lo, hi]`.
pub fn centres(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo + (hi - lo) * (i as f64 + 0.5) / n as f64)
        .collect()
}

/// The colours of the three classes.
pub const CLASSES: [(&str, RGBColor); 3] = [
    ("active control (I)", RGBColor(120, 190, 120)),
    ("dynamic ratchet (II)", RGBColor(110, 160, 220)),
    ("actuator (III)", RGBColor(235, 130, 90)),
];

/// Renders a map (plot and optional CSV).
/// The exact active-control set inside the map: the lines φ = 90°, 270° (mod
/// 360°) where the law is symmetric, and ratio = 0 (normal oscillation only).
pub fn active_lines(a: f64, ratios: &[f64], phis: &[f64]) -> CliResult<Vec<Vec<(f64, f64)>>> {
    let (plo, phi_hi) = (phis[0], *phis.last().unwrap_or(&phis[0]));
    let (rlo, rhi) = (ratios[0], *ratios.last().unwrap_or(&ratios[0]));
    let hx = if phis.len() > 1 {
        (phis[1] - phis[0]) / 2.0
    } else {
        0.5
    };
    let hy = if ratios.len() > 1 {
        (ratios[1] - ratios[0]) / 2.0
    } else {
        0.5
    };
    let mut out = Vec::new();
    let mut k = ((plo - hx) / 90.0).ceil() as i64;
    while (k as f64) * 90.0 <= phi_hi + hx {
        let phi = k as f64 * 90.0;
        k += 1;
        if phi.rem_euclid(180.0) != 90.0 {
            continue;
        }
        // Fine sampling along the line; keep runs classified as active control.
        let n = 400;
        let mut run: Vec<(f64, f64)> = Vec::new();
        for i in 0..=n {
            let r = (rlo - hy) + (rhi - rlo + 2.0 * hy) * i as f64 / n as f64;
            let r = r.max(0.0);
            let s = cell_scene(a, r, phi)?;
            let c =
                classify(&s, &ClassifyOptions::default()).map_err(crate::compute::exact_failure)?;
            if c.regime == Regime::ActiveControl {
                run.push((phi, r));
            } else if !run.is_empty() {
                out.push(std::mem::take(&mut run));
            }
        }
        if run.len() > 1 {
            out.push(run);
        }
    }
    if rlo - hy <= 0.0 {
        out.push(vec![(plo - hx, 0.0), (phi_hi + hx, 0.0)]);
    }
    Ok(out)
}

/// Renders a map (plot and optional CSV).
pub fn write_map(
    a: f64,
    ratios: &[f64],
    phis: &[f64],
    cells: &[Cell],
    class: Vec<u8>,
    plot: &Path,
    csv_path: Option<&Path>,
) -> CliResult {
    let (plo, phi_hi) = (phis[0], *phis.last().unwrap_or(&phis[0]));
    let (rlo, rhi) = (ratios[0], *ratios.last().unwrap_or(&ratios[0]));
    let mut lines = vec![(
        "paper's rule: ratio = 1 (ratchet below, drive above)".to_string(),
        vec![(plo, 1.0), (phi_hi, 1.0)],
    )];
    for v in [90.0, 270.0, -90.0, 450.0] {
        if v > plo && v < phi_hi {
            lines.push((String::new(), vec![(v, rlo), (v, rhi)]));
        }
    }
    if lines.len() > 1 {
        lines[1].0 = "paper's rule: φ = π/2 symmetric".to_string();
    }
    let m = RegimeMap {
        title: format!("Regimes at Δu_z/u_z0 = {a} (exact classification)"),
        x_label: "phase φ, degrees".to_string(),
        y_label: "k_xΔu_x / (μ0 k_z Δu_z)".to_string(),
        xs: phis.to_vec(),
        ys: ratios.to_vec(),
        class,
        classes: CLASSES,
        lines,
        class0_lines: active_lines(a, ratios, phis)?,
    };
    render_map(plot, &m, (1100, 760))?;
    eprintln!("wrote {}", plot.display());
    if let Some(p) = csv_path {
        write_rows(p, cells)?;
    }
    Ok(())
}

/// `fricctl map`.
pub fn run(a: &MapArgs) -> CliResult {
    for (v, name) in [
        (a.duz_rel, "duz-rel"),
        (a.ratio_min, "ratio-min"),
        (a.ratio_max, "ratio-max"),
        (a.phi_min_deg, "phi-min-deg"),
        (a.phi_max_deg, "phi-max-deg"),
    ] {
        if !v.is_finite() {
            return Err(CliError::usage(format!(
                "--{name}: must be a finite number"
            )));
        }
    }
    if !(0.0..1.0).contains(&a.duz_rel) || a.duz_rel == 0.0 {
        return Err(CliError::usage(
            "--duz-rel: must be in (0, 1) (the ratio needs Δu_z > 0; Δu_z < u_z0)",
        ));
    }
    if a.ratio_min < 0.0 {
        return Err(CliError::usage("--ratio-min: must be >= 0"));
    }
    if a.ratio_max <= a.ratio_min {
        return Err(CliError::usage(
            "--ratio-max: must be greater than --ratio-min",
        ));
    }
    if a.phi_max_deg <= a.phi_min_deg {
        return Err(CliError::usage(
            "--phi-max-deg: must be greater than --phi-min-deg",
        ));
    }
    if a.res < 2 || a.res > 1000 {
        return Err(CliError::usage("--res: must be between 2 and 1000"));
    }
    crate::plot::ext(&a.plot)?;
    a.how.validate()?;
    if let Some(x) = a.v_rel {
        if !x.is_finite() {
            return Err(CliError::usage("--v-rel: must be a finite number"));
        }
        return run_mu_map(a, x);
    }
    if a.how.method != Method::Auto || a.how.tol.is_some() {
        return Err(CliError::usage(
            "--method: the regime map is always exact; --method and --tol apply to a μ map (--v-rel)",
        ));
    }
    let ratios = centres(a.ratio_min, a.ratio_max, a.res);
    let phis = centres(a.phi_min_deg, a.phi_max_deg, a.res);
    let (cells, class) = cells(a.duz_rel, &ratios, &phis, true)?;
    let counts = [0u8, 1, 2].map(|k| class.iter().filter(|&&c| c == k).count());
    eprintln!(
        "{} cells: {} active control, {} dynamic ratchet, {} actuator",
        class.len(),
        counts[0],
        counts[1],
        counts[2]
    );
    write_map(
        a.duz_rel,
        &ratios,
        &phis,
        &cells,
        class,
        &a.plot,
        a.csv.as_deref(),
    )?;
    let _ = std::io::stderr().flush();
    Ok(())
}
