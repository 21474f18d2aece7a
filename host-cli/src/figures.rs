//! `fricctl figures`: the paper's Figs. 2–7 from the exact solver, and the
//! regime map, as SVG and PNG.

use std::f64::consts::PI;
use std::path::Path;

use model_core::analytic::approx::law;
use model_core::exact;
use model_core::regime::{classify, ClassifyOptions};
use model_core::{Drive, Groups, Libm, Scene};

use crate::cmd::map::write_map;
use crate::error::{CliError, CliResult};
use crate::plot::{render_panels, Mark, Panel, Series};
use crate::sweep::linspace;
use crate::sweep::{cells, centres};

fn mu(d: &Drive<f64>, v: f64) -> CliResult<f64> {
    exact::mu_over_mu0::<f64, Libm>(d, v).map_err(crate::eval::exact_failure)
}

fn drive(a: f64, b: f64, phi: f64) -> CliResult<Drive<f64>> {
    Scene::dimensionless(Groups {
        duz_rel: a,
        dux_rel: b,
        phi,
    })
    .map(|s| s.drive())
    .map_err(|e| CliError::failure(format!("figure scene: {e}")))
}

/// μ/μ0 against v/v_c (per-side normalisation as in the paper's Fig. 4) on
/// `xs`; both one-sided limits at 0. Where a side's v_c is 0, μ = ±1 on it.
fn normalised_curve(d: &Drive<f64>, xs: &[f64]) -> CliResult<Vec<(f64, f64)>> {
    let (cf, cb) = (d.c_forward::<Libm>(), d.c_backward::<Libm>());
    let mut pts = Vec::with_capacity(xs.len() + 2);
    for &x in xs {
        if x == 0.0 {
            let (p, m) = exact::limits_at_zero::<f64, Libm>(d)
                .map_err(|e| CliError::failure(format!("{e:?}")))?;
            pts.push((0.0, m));
            pts.push((0.0, p));
            continue;
        }
        let c = if x > 0.0 { cf } else { cb };
        let m = if c == 0.0 { x.signum() } else { mu(d, x * c)? };
        pts.push((x, m));
    }
    Ok(pts)
}

fn save(
    out: &Path,
    name: &str,
    panels: &[Panel],
    rows: usize,
    cols: usize,
    size: (u32, u32),
) -> CliResult {
    for ext in ["svg", "png"] {
        let p = out.join(format!("{name}.{ext}"));
        render_panels(&p, panels, rows, cols, size)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

const MU_AXIS: &str = "μ / μ0";

/// `fricctl figures --out DIR`.
/// Eq. 21/24 with amplitude `amp` at `v0/v_c = x` (1 beyond v_c), as points;
/// values below `ymin` become gaps (NaN) so they are not drawn.
fn approx_curve(xs: &[f64], amp: f64, ymin: f64) -> Vec<(f64, f64)> {
    xs.iter()
        .map(|&x| {
            let y = if x >= 1.0 { 1.0 } else { law(x, amp) };
            (x, if y >= ymin { y } else { f64::NAN })
        })
        .collect()
}

pub fn run(out: &Path, map_res: usize) -> CliResult {
    if !(2..=2000).contains(&map_res) {
        return Err(CliError::usage("--map-res: must be between 2 and 2000"));
    }
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::failure(format!("--out: cannot create {}: {e}", out.display())))?;

    // Fig. 2: normal oscillation only, μ/μ0 against v0/v_c for several Δu_z/u_z0.
    let xs = linspace(0.0, 1.2, 481);
    let mut series = Vec::new();
    for (i, a) in [0.1, 0.3, 0.5, 0.7, 0.9].into_iter().enumerate() {
        let d = drive(a, 0.0, 0.0)?;
        let pts: Vec<(f64, f64)> = normalised_curve(&d, &xs[1..])?;
        series.push(Series {
            label: format!("Δu_z/u_z0 = {a}"),
            points: pts,
            mark: Mark::Line,
            color: i,
        });
        series.push(Series {
            label: String::new(),
            points: approx_curve(&xs, a, f64::NEG_INFINITY),
            mark: Mark::Dashed,
            color: i,
        });
    }
    series.push(Series {
        label: "dashed: eq. (21)".to_string(),
        points: vec![],
        mark: Mark::Dashed,
        color: 6,
    });
    let fig2 = Panel {
        title: "Fig. 2 — normal oscillation only (Δu_x = 0), exact".to_string(),
        x_label: "v0 / v_c".to_string(),
        y_label: MU_AXIS.to_string(),
        x: (0.0, 1.2),
        y: (0.0, 1.05),
        series,
    };
    save(out, "fig2", &[fig2], 1, 1, (1000, 680))?;

    // Fig. 3: tangential only; exact points, eq. (24) lines.
    let pts_x = linspace(0.0, 1.2, 31);
    let line_x = linspace(0.0, 1.2, 241);
    let fig3 = |bs: &[f64], title: &str, ymin: f64| -> CliResult<Panel> {
        let mut series = Vec::new();
        for (i, &b) in bs.iter().enumerate() {
            let d = drive(0.0, b, 0.0)?;
            let c = d.c_forward::<Libm>();
            let mut pts = Vec::new();
            for &x in &pts_x[1..] {
                pts.push((x, mu(&d, x * c)?));
            }
            series.push(Series {
                label: format!("k_xΔu_x/(μ0k_z u_z0) = {b}"),
                points: pts,
                mark: Mark::Points,
                color: i,
            });
            series.push(Series {
                label: String::new(),
                points: approx_curve(&line_x, b, ymin),
                mark: Mark::Line,
                color: i,
            });
        }
        Ok(Panel {
            title: title.to_string(),
            x_label: "v0 / v_c  (v_c = ωΔu_x)".to_string(),
            y_label: MU_AXIS.to_string(),
            x: (0.0, 1.2),
            y: (ymin, 1.05),
            series,
        })
    };
    let a = fig3(
        &[0.25, 0.5, 0.75, 1.0],
        "Fig. 3a — tangential only, small amplitude: exact (dots), eq. (24) (lines)",
        0.0,
    )?;
    save(out, "fig3a", &[a], 1, 1, (1000, 680))?;
    let b = fig3(
        &[1.0, 2.0, 5.0, 10.0, 20.0],
        "Fig. 3b — tangential only, large amplitude: exact (dots), eq. (24) (lines)",
        -1.0,
    )?;
    save(out, "fig3b", &[b], 1, 1, (1000, 680))?;

    // Fig. 4: φ = 0, Δu_z/u_z0 = 0 … 0.95, per-side normalised velocity.
    let xs4 = linspace(-1.5, 1.5, 601);
    let mut panels = Vec::new();
    for (tag, b) in [("a", 1.0), ("b", 2.0), ("c", 0.5)] {
        let mut series = Vec::new();
        for (i, a) in [0.0, 0.25, 0.5, 0.75, 0.95].into_iter().enumerate() {
            let d = drive(a, b, 0.0)?;
            series.push(Series {
                label: format!("Δu_z/u_z0 = {a}"),
                points: normalised_curve(&d, &xs4)?,
                mark: Mark::Line,
                color: i,
            });
        }
        panels.push(Panel {
            title: format!("Fig. 4{tag} — φ = 0, k_xΔu_x/(μ0k_z u_z0) = {b}"),
            x_label: "v0 / v_c  (v_c of each direction)".to_string(),
            y_label: MU_AXIS.to_string(),
            x: (-1.5, 1.5),
            y: (-1.1, 1.1),
            series,
        });
    }
    save(out, "fig4", &panels, 1, 3, (1800, 620))?;

    // Figs. 5–7: Δu_z/u_z0 = 0.5, ratio 1, 2, 0.5, phases 0 … π; dimensional velocity.
    let phases = [0.0, PI / 4.0, PI / 2.0, 3.0 * PI / 4.0, PI];
    for (fig, ratio) in [("fig5", 1.0), ("fig6", 2.0), ("fig7", 0.5)] {
        let a = 0.5;
        let b = ratio * a;
        let vmax = 1.25 * (a + b);
        let vs = linspace(-vmax, vmax, 801);
        let mut panels = Vec::new();
        for (i, &phi) in phases.iter().enumerate() {
            let d = drive(a, b, phi)?;
            let s = Scene::dimensionless(Groups {
                duz_rel: a,
                dux_rel: b,
                phi,
            })
            .map_err(|e| CliError::failure(e.to_string()))?;
            let regime = classify(&s, &ClassifyOptions::default())
                .map_err(|e| CliError::failure(format!("{e:?}")))?
                .regime;
            let mut pts = Vec::with_capacity(vs.len() + 1);
            for &v in &vs {
                if v == 0.0 {
                    let (p, m) = exact::limits_at_zero::<f64, Libm>(&d)
                        .map_err(|e| CliError::failure(format!("{e:?}")))?;
                    pts.push((0.0, m));
                    pts.push((0.0, p));
                } else {
                    pts.push((v, mu(&d, v)?));
                }
            }
            panels.push(Panel {
                title: format!(
                    "φ = {:.0}° — {}",
                    phi.to_degrees(),
                    regime.name().replace('_', " ")
                ),
                x_label: "v0 / (ω μ0 k_z u_z0 / k_x)".to_string(),
                y_label: MU_AXIS.to_string(),
                x: (-vmax, vmax),
                y: (-1.1, 1.1),
                series: vec![Series {
                    label: String::new(),
                    points: pts,
                    mark: Mark::Line,
                    color: i,
                }],
            });
        }
        let n = fig[3..].to_string();
        for p in &mut panels {
            p.title = format!("Fig. {n}, ratio {ratio}: {}", p.title);
        }
        save(out, fig, &panels, 2, 3, (1800, 1050))?;
    }

    // The regime map at Δu_z/u_z0 = 0.5.
    let ratios = centres(0.0, 3.0, map_res);
    let phis = centres(0.0, 360.0, map_res);
    let (cs, class) = cells(0.5, &ratios, &phis, true)?;
    for ext in ["svg", "png"] {
        let p = out.join(format!("regime_map.{ext}"));
        write_map(0.5, &ratios, &phis, &cs, class.clone(), &p, None)?;
    }
    Ok(())
}
