//! `fricctl figures`: the paper's Figs. 2–7 from the exact solver, the
//! regime map, and a contact the paper sets aside (the flat punch lifting
//! off, [`model_core::model::liftoff`]), as SVG and PNG.
//!
//! Every panel names its fixed parameters; the dimensionless groups are
//! those of eqs. 25/26: `Δu_z/u_z0`, `k_xΔu_x/(μ0 k_z u_z0)` and the ratio
//! `k_xΔu_x/(μ0 k_z Δu_z)`; velocities are in units of `v_c` (eq. 8) or of
//! `ωW0`, `W0 = μ0 k_z u_z0 / k_x`.

use std::f64::consts::PI;
use std::path::Path;

use model_core::analytic::approx::law;
use model_core::exact;
use model_core::model::liftoff;
use model_core::regime::{classify, Classification, ClassifyOptions, Regime};
use model_core::{Drive, Groups, Libm, Scene};

use crate::cmd::map::{classify_cells, write_map};
use crate::error::{CliError, CliResult};
use crate::plot::{
    prepare_out_dir, render_figure, Corner, Extras, Figure, Mark, Marker, Panel, Series,
};
use fric_analysis::grid::{centres, linspace};

fn mu(d: &Drive<f64>, v: f64) -> CliResult<f64> {
    exact::mu_over_mu0::<f64, Libm>(d, v).map_err(crate::eval::exact_failure)
}

fn scene(a: f64, b: f64, phi: f64) -> CliResult<Scene<f64>> {
    Scene::dimensionless(Groups {
        duz_rel: a,
        dux_rel: b,
        phi,
    })
    .map_err(|e| CliError::failure(format!("figure scene: {e}")))
}

fn drive(a: f64, b: f64, phi: f64) -> CliResult<Drive<f64>> {
    scene(a, b, phi).map(|s| s.drive())
}

fn limits(d: &Drive<f64>) -> CliResult<(f64, f64)> {
    exact::limits_at_zero::<f64, Libm>(d).map_err(crate::eval::exact_failure)
}

/// μ/μ0 against v/v_c (per-side normalisation as in the paper's Fig. 4) on
/// `xs`; both one-sided limits at 0. Where a side's v_c is 0, μ = ±1 on it.
fn normalised_curve(d: &Drive<f64>, xs: &[f64]) -> CliResult<Vec<(f64, f64)>> {
    let (cf, cb) = (d.c_forward::<Libm>(), d.c_backward::<Libm>());
    let mut pts = Vec::with_capacity(xs.len() + 2);
    for &x in xs {
        if x == 0.0 {
            let (p, m) = limits(d)?;
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

fn save(out: &Path, name: &str, f: &Figure) -> CliResult {
    for ext in ["svg", "png"] {
        let p = out.join(format!("{name}.{ext}"));
        render_figure(&p, f)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

const MU_AXIS: &str = "μ / μ0";
/// The group of eq. 25 for the tangential amplitude.
const B_NAME: &str = "k_xΔu_x/(μ0 k_z u_z0)";
/// The ratio of eq. 26.
const RATIO_NAME: &str = "k_xΔu_x/(μ0 k_z Δu_z)";

/// Eq. 21/24 with amplitude `amp` at `v0/v_c = x` (1 beyond v_c), as points.
fn approx_curve(xs: &[f64], amp: f64) -> Vec<(f64, f64)> {
    xs.iter()
        .map(|&x| (x, if x >= 1.0 { 1.0 } else { law(x, amp) }))
        .collect()
}

/// A legend-only entry (black sample, no points).
fn key(label: &str, mark: Mark) -> Series {
    Series {
        label: label.to_string(),
        points: Vec::new(),
        mark,
        color: 6,
    }
}

fn one_panel(panel: Panel, extras: Extras, caption: Vec<String>) -> Figure {
    Figure {
        panels: vec![(panel, extras)],
        rows: 1,
        cols: 1,
        size: (1000, 700),
        legend: Vec::new(),
        caption,
    }
}

/// Fig. 2: normal oscillation only, μ/μ0 against v0/v_c for several Δu_z/u_z0.
fn fig2(out: &Path) -> CliResult {
    let xs = linspace(0.0, 1.2, 481);
    let mut series = Vec::new();
    for (i, a) in [0.1, 0.3, 0.5, 0.7, 0.9].into_iter().enumerate() {
        let d = drive(a, 0.0, 0.0)?;
        series.push(Series {
            label: format!("Δu_z/u_z0 = {a}"),
            points: normalised_curve(&d, &xs[1..])?,
            mark: Mark::Line,
            color: i,
        });
        series.push(Series {
            label: String::new(),
            points: approx_curve(&xs, a),
            mark: Mark::Dashed,
            color: i,
        });
    }
    series.push(key("solid: exact solver", Mark::Line));
    series.push(key("dashed: eq. (21)", Mark::Dashed));
    let panel = Panel {
        title: "Fig. 2 — normal oscillation only".to_string(),
        x_label: "v0 / v_c".to_string(),
        y_label: MU_AXIS.to_string(),
        x: (0.0, 1.2),
        y: (0.0, 1.05),
        series,
    };
    let extras = Extras {
        notes: vec!["Δu_x = 0 (φ has no effect)".to_string()],
        notes_at: Corner::UpperLeft,
        ..Extras::default()
    };
    let caption = vec!["v_c = ω μ0 k_z Δu_z / k_x (eq. 8 with Δu_x = 0).".to_string()];
    save(out, "fig2", &one_panel(panel, extras, caption))
}

/// Fig. 3: tangential only; exact points, eq. (24) lines. Eq. 24 holds for
/// `k_xΔu_x/(μ0 k_z u_z0) ≤ 1`; beyond, it is drawn dashed and only where it
/// stays a friction coefficient (μ/μ0 ≥ −1), with a cross where it leaves.
fn fig3(out: &Path, name: &str, bs: &[f64], title: &str, ymin: f64) -> CliResult {
    let line_x = linspace(0.0, 1.2, 1201);
    let mut series = Vec::new();
    let mut left_domain = false;
    // Each amplitude its own marker, and its points shifted by a fraction of
    // the spacing (0.04 v_c / the number of amplitudes), so that laws that
    // nearly coincide at low velocity (ratios 5, 10, 20) stay apart.
    const MARKERS: [Marker; 5] = [
        Marker::Circle,
        Marker::Square,
        Marker::Triangle,
        Marker::Diamond,
        Marker::Ring,
    ];
    let step = 0.04;
    for (i, &b) in bs.iter().enumerate() {
        let d = drive(0.0, b, 0.0)?;
        let c = d.c_forward::<Libm>();
        let shift = step * i as f64 / bs.len() as f64;
        let mut pts = Vec::new();
        for j in 1..30 {
            let x = j as f64 * step + shift;
            pts.push((x, mu(&d, x * c)?));
        }
        series.push(Series {
            label: format!("{B_NAME} = {b}"),
            points: pts,
            mark: Mark::Markers(MARKERS[i % MARKERS.len()]),
            color: i,
        });
        let inside = b <= 1.0;
        let mut line = approx_curve(&line_x, b);
        if !inside {
            left_domain = true;
            // The first x where eq. 24 is back at μ/μ0 ≥ ymin: mark it.
            if let Some(k) = line.iter().position(|&(_, y)| y >= ymin) {
                if k > 0 {
                    series.push(Series {
                        label: String::new(),
                        points: vec![line[k]],
                        mark: Mark::Markers(crate::plot::Marker::Cross),
                        color: i,
                    });
                }
            }
            for p in &mut line {
                if p.1 < ymin {
                    p.1 = f64::NAN;
                }
            }
        }
        series.push(Series {
            label: String::new(),
            points: line,
            mark: if inside { Mark::Line } else { Mark::Dashed },
            color: i,
        });
    }
    series.push(key("markers: exact solver", Mark::Points));
    series.push(key("solid: eq. (24), inside its domain", Mark::Line));
    if left_domain {
        series.push(key("dashed: eq. (24) outside it", Mark::Dashed));
        series.push(key(
            "×: eq. (24) below μ/μ0 = −1 to the left",
            Mark::Markers(crate::plot::Marker::Cross),
        ));
    }
    let panel = Panel {
        title: title.to_string(),
        x_label: "v0 / v_c".to_string(),
        y_label: MU_AXIS.to_string(),
        x: (0.0, 1.2),
        y: (ymin, 1.05),
        series,
    };
    let extras = Extras {
        notes: vec![
            "Δu_z = 0 (φ has no effect)".to_string(),
            format!("eq. (24) holds for {B_NAME} ≤ 1"),
        ],
        notes_at: Corner::UpperLeft,
        ..Extras::default()
    };
    let caption = vec!["v_c = ωΔu_x (eq. 8 with Δu_z = 0).".to_string()];
    save(out, name, &one_panel(panel, extras, caption))
}

/// Fig. 4: φ = 0, Δu_z/u_z0 = 0 … 0.95, per-side normalised velocity. The
/// three panels are stacked, each as wide as a one-panel figure, so that
/// the text keeps its size at column width.
fn fig4(out: &Path) -> CliResult {
    let xs = linspace(-1.5, 1.5, 601);
    let mut panels = Vec::new();
    let mut zero_vc = Vec::new();
    for (tag, b) in [("a", 1.0), ("b", 2.0), ("c", 0.5)] {
        let mut series = Vec::new();
        for (i, a) in [0.0, 0.25, 0.5, 0.75, 0.95].into_iter().enumerate() {
            let d = drive(a, b, 0.0)?;
            let mut pts = normalised_curve(&d, &xs)?;
            // A direction whose v_c is 0 (here Δu_z/u_z0 = k_xΔu_x/(μ0 k_z
            // u_z0), φ = 0: v_c− = ω|Δu_x − μ0 (k_z/k_x) Δu_z| = 0) has no
            // v0/v_c axis: every velocity of it is beyond v_c, μ = ∓μ0. That
            // half is drawn dashed at ∓1, named in the legend and the caption.
            let backward_zero = d.c_backward::<Libm>() == 0.0;
            let label = if backward_zero {
                zero_vc.push(format!("4{tag}: Δu_{{z}}/u_{{z0}} = {a}"));
                format!("Δu_z/u_z0 = {a}  (v_c− = 0: dashed, μ = −μ0)")
            } else {
                format!("Δu_z/u_z0 = {a}")
            };
            if backward_zero {
                for p in pts.iter_mut().filter(|p| p.0 < 0.0) {
                    p.1 = f64::NAN;
                }
                series.push(Series {
                    label: String::new(),
                    points: vec![(-1.5, -1.0), (0.0, -1.0)],
                    mark: Mark::Dashed,
                    color: i,
                });
            }
            series.push(Series {
                label,
                points: pts,
                mark: Mark::Line,
                color: i,
            });
        }
        let panel = Panel {
            title: format!("Fig. 4{tag} — φ = 0°, {B_NAME} = {b}"),
            x_label: "v0 / v_c  (v_c of each direction)".to_string(),
            y_label: MU_AXIS.to_string(),
            x: (-1.5, 1.5),
            y: (-1.1, 1.1),
            series,
        };
        let extras = Extras {
            legend_at: Corner::UpperLeft,
            ..Extras::default()
        };
        panels.push((panel, extras));
    }
    let mut caption = vec![
        "v_{c} per direction from eq. 8: v_{c±} = ω |Δu_{x} e^{iφ} ± μ_{0} (k_{z}/k_{x}) Δu_{z}|; \
         μ(0±) are the exact one-sided limits."
            .to_string(),
    ];
    if !zero_vc.is_empty() {
        caption.push(format!(
            "{}: v_{{c−}} = 0, so backward sliding is beyond v_{{c}} at every speed (μ = −μ_{{0}}, dashed) and v_{{0}}/v_{{c}} is undefined there.",
            zero_vc.join(", ")
        ));
    }
    let f = Figure {
        panels,
        rows: 3,
        cols: 1,
        size: (1000, 1700),
        legend: Vec::new(),
        caption,
    };
    save(out, "fig4", &f)
}

/// The caption remark of a Figs. 5–7 panel: at φ = 90° without a static
/// equilibrium, why the law is not the paper's symmetric one.
fn dual_remark(phi: f64, cl: &Classification<f64>) -> Option<String> {
    ((phi - PI / 2.0).abs() < 1e-12 && !cl.statics.exists()).then(|| {
        format!(
            "φ = 90° differs from the paper (symmetric there): c = c′ = {:.3} > 1, so no static equilibrium; \
             net force at rest μ(0±)/μ_{{0}} = {} → {}.",
            cl.c_forward,
            crate::plot::minus(&format!("{:.4}", cl.mu_0plus)),
            cl.regime.name().replace('_', " ")
        )
    })
}

/// The markers of the one-sided limits μ(0±) in the combined panel of Figs. 5–7.
const LIMIT_MARKERS: [Marker; 5] = [
    Marker::Circle,
    Marker::Square,
    Marker::Triangle,
    Marker::Diamond,
    Marker::Ring,
];

/// Whether the steady period at `v` holds slip in both directions.
fn slips_both_ways(d: &Drive<f64>, v: f64) -> CliResult<bool> {
    let (_, arcs) = exact::steady_state::<f64, Libm>(d, v).map_err(crate::eval::exact_failure)?;
    let back = arcs.iter().any(|a| a.kind == exact::ArcKind::SlipBackward);
    let fwd = arcs.iter().any(|a| a.kind == exact::ArcKind::SlipForward);
    Ok(back && fwd)
}

/// The velocity range around 0 in which the period slips both ways (its
/// ends are the law's kinks), as `φ = 90°: −0.058 … 0.112`, or `None` if
/// the law has none within `±vmax`. The ends are bisected to 1e-4 ωW0 from
/// a 400-point scan on each side.
fn two_way_slip(d: &Drive<f64>, vmax: f64, phi: f64) -> CliResult<Option<String>> {
    let mut ends = [0.0f64; 2];
    for (k, sign) in [-1.0f64, 1.0].into_iter().enumerate() {
        let near = sign * 1e-6;
        if !slips_both_ways(d, near)? {
            return Ok(None);
        }
        let (mut lo, mut hi) = (near, near);
        let n = 400;
        for j in 1..=n {
            let v = sign * vmax * j as f64 / n as f64;
            if !slips_both_ways(d, v)? {
                hi = v;
                break;
            }
            lo = v;
        }
        if hi == near {
            return Ok(None);
        }
        while (hi - lo).abs() > 1e-4 {
            let mid = 0.5 * (lo + hi);
            if slips_both_ways(d, mid)? {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        ends[k] = 0.5 * (lo + hi);
    }
    Ok(Some(format!(
        "[{}, {}] at φ = {:.0}°",
        crate::plot::minus(&format!("{:.3}", ends[0])),
        crate::plot::minus(&format!("{:.3}", ends[1])),
        phi.to_degrees()
    )))
}

/// Figs. 5–7: Δu_z/u_z0 = 0.5, ratio 1, 2, 0.5, phases 0 … π; velocity in ωW0.
fn figs5_7(out: &Path) -> CliResult {
    let phases = [0.0, PI / 4.0, PI / 2.0, 3.0 * PI / 4.0, PI];
    let a = 0.5;
    for (fig, ratio) in [("5", 1.0), ("6", 2.0), ("7", 0.5)] {
        let b = ratio * a;
        let vmax = 1.25 * (a + b);
        let vs = linspace(-vmax, vmax, 801);
        let mut panels = Vec::new();
        let mut all = Vec::new();
        let mut remarks = Vec::new();
        let mut kinks = Vec::new();
        for (i, &phi) in phases.iter().enumerate() {
            let s = scene(a, b, phi)?;
            let d = s.drive();
            let cl =
                classify(&s, &ClassifyOptions::default()).map_err(crate::eval::exact_failure)?;
            let mut pts = Vec::with_capacity(vs.len() + 1);
            for &v in &vs {
                if v == 0.0 {
                    let (p, m) = limits(&d)?;
                    pts.push((0.0, m));
                    pts.push((0.0, p));
                } else {
                    pts.push((v, mu(&d, v)?));
                }
            }
            let regime = match cl.regime {
                Regime::ActiveControl => "active control",
                Regime::DynamicRatchet => "dynamic ratchet",
                Regime::Actuator => "actuator",
            };
            let panel = Panel {
                title: format!("Fig. {fig}, φ = {:.0}°: {regime}", phi.to_degrees()),
                x_label: "v0 / (ωW0),  W0 = μ0 k_z u_z0 / k_x".to_string(),
                y_label: MU_AXIS.to_string(),
                x: (-vmax, vmax),
                y: (-1.1, 1.1),
                series: vec![Series {
                    label: String::new(),
                    points: pts.clone(),
                    mark: Mark::Line,
                    color: i,
                }],
            };
            // The fixed parameters are in the caption and the phase in the
            // title: no box over the data; a remark goes to the caption.
            remarks.extend(dual_remark(phi, &cl));
            kinks.extend(two_way_slip(&d, vmax, phi)?);
            panels.push((panel, Extras::default()));
            // Together, the five jumps at v0 = 0 would lie on one another:
            // there the curves break at 0, and each one's limits μ(0±) are
            // its own marker.
            let (p0, m0) = limits(&d)?;
            let mut broken = pts;
            if let Some(k) = broken.iter().position(|p| p.0 == 0.0) {
                broken[k].1 = f64::NAN;
                broken[k + 1].1 = f64::NAN;
            }
            all.push(Series {
                label: format!("φ = {:.0}°", phi.to_degrees()),
                points: broken,
                mark: Mark::Line,
                color: i,
            });
            all.push(Series {
                label: String::new(),
                points: vec![(0.0, m0), (0.0, p0)],
                mark: Mark::Markers(LIMIT_MARKERS[i % LIMIT_MARKERS.len()]),
                color: i,
            });
        }
        // The sixth panel: the five phases together (legend where no curve
        // runs: v > 0 with μ < 0 holds no point of these laws... see below).
        let legend_at = if all
            .iter()
            .flat_map(|s| &s.points)
            .any(|&(v, m)| v > 0.3 * vmax && m < -0.2)
        {
            Corner::UpperLeft
        } else {
            Corner::LowerRight
        };
        panels.push((
            Panel {
                title: format!("Fig. {fig}: the five phases together"),
                x_label: "v_{0} / (ωW_{0})".to_string(),
                y_label: MU_AXIS.to_string(),
                x: (-vmax, vmax),
                y: (-1.1, 1.1),
                series: all,
            },
            Extras {
                legend_at,
                ..Extras::default()
            },
        ));
        let kink_note = (!kinks.is_empty()).then(|| {
            [
                "Kinks near v_{0} = 0: inside them each period slips both ways (stick, slip back, stick, slip forward), \
                 outside one way only;"
                    .to_string(),
                format!(
                    "μ is continuous there, its slope is not. Both-way slip for v_{{0}}/(ωW_{{0}}) in {}.",
                    kinks.join(", ")
                ),
            ]
        });
        let f = Figure {
            panels,
            rows: 2,
            cols: 3,
            size: (1500, 980),
            legend: Vec::new(),
            caption: [
                format!(
                    "Fig. {fig}: Δu_{{z}}/u_{{z0}} = {a}, {RATIO_NAME} = {ratio}; exact solver; \
                     W_{{0}} = μ_{{0}}k_{{z}}u_{{z0}}/k_{{x}}; regimes of §3.2, exactly from μ(0±) and the symmetry of μ(v)."
                ),
                "c, c′ = v_{c±}/(ωW_{0}) (eq. 8); a static equilibrium exists iff c + c′ ≤ 2. \
                 Last panel: the curves break at v_{0} = 0, the markers are μ(0−) and μ(0+)."
                    .to_string(),
            ]
            .into_iter()
            .chain(remarks)
            .chain(kink_note.into_iter().flatten())
            .collect(),
        };
        save(out, &format!("fig{fig}"), &f)?;
    }
    Ok(())
}

/// μ/μ0 of a flat punch at dimensionless velocity `v` for any `a ≥ 0`: the
/// permanent-contact exact solver below `a = 1`, the lift-off solver from it.
fn mu_flat_any(a: f64, b: f64, phi: f64, v: f64) -> CliResult<f64> {
    if a < 1.0 {
        mu(&drive(a, b, phi)?, v)
    } else {
        let d = Drive::new::<Libm>(a, b, phi);
        liftoff::mu_over_mu0::<f64, Libm>(&d, v).map_err(crate::eval::lift_off_failure)
    }
}

/// Normal oscillation only: μ/μ0 against Δu_z/u_z0 from 0 to 3 at fixed
/// velocities, through lift-off at Δu_z/u_z0 = 1.
fn liftoff_normal(out: &Path) -> CliResult {
    let xs = linspace(0.0, 3.0, 601);
    let mut series = Vec::new();
    for (i, v) in [0.1, 0.3, 0.6, 1.0, 1.5].into_iter().enumerate() {
        let mut pts = Vec::with_capacity(xs.len());
        for &a in &xs {
            // a = 0, b = 0: no oscillation, plain Coulomb sliding.
            let m = if a == 0.0 {
                1.0
            } else {
                mu_flat_any(a, 0.0, 0.0, v)?
            };
            pts.push((a, m));
        }
        series.push(Series {
            label: format!("v0 = {v} ωW0"),
            points: pts,
            mark: Mark::Line,
            color: i,
        });
    }
    series.push(Series {
        label: "lift-off: Δu_z = u_z0".to_string(),
        points: vec![(1.0, 0.0), (1.0, 1.05)],
        mark: Mark::Dashed,
        color: 6,
    });
    let panel = Panel {
        title: "Normal oscillation only, across lift-off (flat punch)".to_string(),
        x_label: "Δu_z / u_z0".to_string(),
        y_label: MU_AXIS.to_string(),
        x: (0.0, 3.0),
        y: (0.0, 1.05),
        series,
    };
    let extras = Extras {
        // The fixed parameters go to the caption: every corner of this
        // panel holds a curve.
        legend_at: Corner::LowerLeft,
        ..Extras::default()
    };
    let caption = vec![
        "Δu_x = 0 (φ has no effect); v0 in units of ωW0, W0 = μ0 k_z u_z0 / k_x; for Δu_z ≥ u_z0: μ = ⟨f_x⟩/⟨f_z⟩, ⟨f_z⟩ = k_z⟨u_z⁺⟩."
            .to_string(),
        "Below Δu_z/u_z0 = 1: the exact solver (eq. 8: v_c = a ωW0, μ = μ0 above it); from 1: the lift-off solver (one contact window per period, exact), continuous at 1."
            .to_string(),
    ];
    save(out, "liftoff_normal", &one_panel(panel, extras, caption))
}

/// μ/μ0 against v0/(ωW0) for a contact profile by `select::mu_within_profile`
/// (the exact or lift-off solver for the flat punch, the MDR quadrature for
/// a curved one); both one-sided limits at v0 = 0 when they differ. Returns
/// the points and the largest error bound.
fn profile_curve(
    s: &Scene<f64>,
    p: &model_core::mdr::Profile<f64>,
    vs: &[f64],
) -> CliResult<(Vec<(f64, f64)>, f64)> {
    use model_core::select::{mu_within_profile, Value};
    // The largest of the three methods' own bounds: each answers within it.
    let d = s.drive();
    let tol = crate::eval::profile_tol_at_rest(s, p)
        .max(exact::error_bound::<f64, Libm>(&d))
        .max(liftoff::error_bound::<f64, Libm>(&d));
    let mut pts = Vec::with_capacity(vs.len() + 1);
    let mut worst = 0.0f64;
    for &v in vs {
        let a = mu_within_profile::<f64, Libm>(s, p, v, tol).map_err(|e| {
            crate::eval::profile_failure(e, tol, p)
                .with_context(&format!("figure of the {} profile, v0 = {v} ωW0", p.name()))
        })?;
        worst = worst.max(a.bound);
        match a.value {
            Value::Mu(m) => pts.push((v, m)),
            Value::AtRest {
                mu_0plus,
                mu_0minus,
                ..
            }
            | Value::Limits {
                mu_0plus,
                mu_0minus,
            } => {
                pts.push((v, mu_0minus));
                pts.push((v, mu_0plus));
            }
        }
    }
    Ok((pts, worst))
}

/// μ(v) of a flat punch, a sphere and a cone with the same dimensionless
/// drive, without lift-off of the centre (a = 0.5) and with it (a = 1.5).
fn profiles(out: &Path) -> CliResult {
    use model_core::mdr::Profile;
    let (b, phi) = (0.8, PI / 6.0);
    let mut panels = Vec::new();
    let mut worst = 0.0f64;
    for a in [0.5, 1.5] {
        let s = Scene::dimensionless_with_contact(
            Groups {
                duz_rel: a,
                dux_rel: b,
                phi,
            },
            model_core::scene::ContactMode::Intermittent,
        )
        .map_err(|e| CliError::failure(format!("figure scene: {e}")))?;
        let vmax = 1.25 * (a + b);
        let vs = linspace(-vmax, vmax, 401);
        let mut series = Vec::new();
        for (i, (p, label)) in [
            (Profile::Flat, "flat punch (single spring)"),
            (Profile::Sphere, "sphere (MDR, n = 2)"),
            (Profile::Cone, "cone (MDR, n = 1)"),
        ]
        .into_iter()
        .enumerate()
        {
            let (pts, w) = profile_curve(&s, &p, &vs)?;
            worst = worst.max(w);
            series.push(Series {
                label: label.to_string(),
                points: pts,
                mark: Mark::Line,
                color: i,
            });
        }
        let panel = Panel {
            title: format!(
                "Δu_z/u_z0 = {a}{}",
                if a >= 1.0 {
                    ": the centre lifts off too"
                } else {
                    ": only the rim lifts off"
                }
            ),
            x_label: "v0 / (ωW0),  W0 = μ0 (E*/G*) d0  (flat: μ0 k_z u_z0 / k_x)".to_string(),
            y_label: MU_AXIS.to_string(),
            x: (-vmax, vmax),
            y: (-1.1, 1.1),
            series,
        };
        let extras = Extras {
            notes: vec![
                format!("Δu_z/u_z0 = {a}, {B_NAME} = {b}"),
                "φ = 30°".to_string(),
            ],
            notes_at: Corner::LowerRight,
            legend_at: Corner::UpperLeft,
            ..Extras::default()
        };
        panels.push((panel, extras));
    }
    let f = Figure {
        panels,
        rows: 1,
        cols: 2,
        size: (1800, 700),
        legend: Vec::new(),
        caption: vec![
            "Curved profiles through the method of dimensionality reduction (MDR): u_z0 read as the mean indentation d0, \
             k_z/k_x as E*/G*; μ = ΣF_x/ΣF_z over the springs."
                .to_string(),
            format!(
                "Same a, b, φ for all three; the critical velocities are the flat punch's. \
                 Largest error bound of any point on the figure: {worst:.1e} μ0 (exact solver or MDR quadrature)."
            ),
        ],
    };
    save(out, "profiles", &f)
}

/// `fricctl figures --out DIR`.
pub fn run(out: &Path, map_res: usize) -> CliResult {
    // `map_res` is in 2..=2000 (the flag's parser).
    prepare_out_dir(out)?;
    fig2(out)?;
    fig3(
        out,
        "fig3a",
        &[0.25, 0.5, 0.75, 1.0],
        "Fig. 3a — tangential only, small amplitude",
        0.0,
    )?;
    fig3(
        out,
        "fig3b",
        &[1.0, 2.0, 5.0, 10.0, 20.0],
        "Fig. 3b — tangential only, large amplitude",
        -1.0,
    )?;
    fig4(out)?;
    figs5_7(out)?;
    liftoff_normal(out)?;
    profiles(out)?;
    // The regime map at Δu_z/u_z0 = 0.5.
    let ratios = centres(0.0, 3.0, map_res);
    let phis = centres(0.0, 360.0, map_res);
    let (cs, class) = classify_cells(0.5, &ratios, &phis, &model_core::mdr::Profile::Flat, true)?;
    for ext in ["svg", "png"] {
        let p = out.join(format!("regime_map.{ext}"));
        write_map(
            0.5,
            &model_core::mdr::Profile::Flat,
            &ratios,
            &phis,
            &cs,
            class.clone(),
            Some(&p),
            None,
        )?;
    }
    Ok(())
}
