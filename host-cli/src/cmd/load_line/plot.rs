//! `load-line --plot FILE`: the force–velocity line(s), the powers and the
//! efficiency over the signed velocity (backward line at `v < 0`), the
//! operating points of maximum power and maximum efficiency marked; the
//! legend sits under the panels and the caption names every fixed parameter
//! with its unit.

use std::path::Path;

use model_core::model::load_line::{LoadLine, OperatingPoint};

use super::{Sample, Units};
use crate::error::CliResult;
use crate::motion::law::Law;
use crate::plot::{render_figure, Extras, Figure, Mark, Marker, Panel, Series};
use crate::scene_args::ResolvedScene;

/// The fixed parameters of the scene, as caption lines.
pub(super) struct SceneText(Vec<String>);

impl SceneText {
    /// The contact, the groups a, b/a (or b), φ, and for an SI scene the
    /// physical parameters and F̄z (`fz`, N).
    pub(super) fn of(law: &Law, rs: &ResolvedScene, fz: f64) -> Self {
        let s = &rs.scene;
        let g = s.groups();
        let contact = match law.exponent() {
            Some(n) if law.name() == "power" => format!("power-law profile, n = {n}"),
            Some(_) => format!("{} profile (MDR)", law.name()),
            None if law.name() == "lift-off" => "flat punch with lift-off".into(),
            None => "flat punch, permanent contact".into(),
        };
        let ratio = s
            .ratio()
            .map_or("∞ (Δu_z = 0)".to_string(), |r| format!("{r:.4}"));
        let mut lines = vec![format!(
            "{contact}; a = Δu_z/u_z0 = {:.4}, b = k_xΔu_x/(μ0k_zu_z0) = {:.4}, ratio b/a = k_xΔu_x/(μ0k_zΔu_z) = {ratio}, φ = {:.2}°",
            g.duz_rel,
            g.dux_rel,
            g.phi.to_degrees().rem_euclid(360.0)
        )];
        if rs.dimensionless {
            lines.push(
                "dimensionless scene: v in ωW0 (W0 = μ0k_zu_z0/k_x), forces in μ0F̄z, powers in μ0F̄zωW0"
                    .into(),
            );
        } else {
            let p = s.params();
            lines.push(format!(
                "μ0 = {}, k_z = {:e} N/m, k_x = {:e} N/m, u_z0 = {:e} m, Δu_z = {:e} m, Δu_x = {:e} m, f = {:e} Hz; F̄z = {:.6e} N, ωW0 = {:.6e} m/s",
                p.mu0,
                p.kz,
                p.kx,
                p.uz0,
                p.duz,
                p.dux,
                p.omega / std::f64::consts::TAU,
                fz,
                s.velocity_scale()
            ));
        }
        lines.push(
            "force = the contact's force on the body −μ(v)F̄z along +x (the load it holds is μ(v)F̄z); P_out = force·v; P_in = P_out + P_friction (normal transducer: 0)"
                .into(),
        );
        SceneText(lines)
    }
}

/// Renders the figure to `path` (`.svg` or `.png`). `stall`: the
/// efficiency's limit at stall when it has no interior maximum (the second
/// mark is then drawn open at v = 0, the stall force, zero power and that
/// limit, and labelled as a limit).
pub(super) fn plot(
    path: &Path,
    lines: &[Vec<Sample>],
    line: &LoadLine<f64>,
    marks: &[(Option<OperatingPoint<f64>>, &str); 2],
    stall: Option<f64>,
    u: &Units,
    scene: &SceneText,
) -> CliResult {
    let (fu, vu, pu) = u.names();
    let gap = (f64::NAN, f64::NAN);
    let (mut force, mut pin, mut pout, mut pf, mut eta) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for l in lines {
        let backward = l.first().is_some_and(|s| s.0 < 0.0);
        if !backward {
            force.push((0.0, line.stall_forward * u.force));
        }
        for (v, p) in l {
            let x = v * u.velocity;
            force.push((x, -p.mu_over_mu0 * u.force));
            pin.push((x, p.input * u.power));
            pout.push((x, p.output * u.power));
            pf.push((x, p.friction * u.power));
            eta.push((x, p.efficiency()));
        }
        if backward {
            force.push((0.0, -line.stall_backward * u.force));
        }
        for s in [&mut force, &mut pin, &mut pout, &mut pf, &mut eta] {
            s.push(gap);
        }
    }
    let x = (
        -line.no_load_backward * u.velocity,
        line.no_load_forward * u.velocity,
    );
    let fmax = line.stall_forward.max(0.0) * u.force;
    let fmin = -line.stall_backward.max(0.0) * u.force;
    let finite_max = |s: &[&Vec<(f64, f64)>]| {
        s.iter()
            .flat_map(|v| v.iter())
            .map(|p| p.1)
            .filter(|y| y.is_finite())
            .fold(0.0f64, f64::max)
    };
    let pmax = finite_max(&[&pin, &pout, &pf]);
    let emax = finite_max(&[&eta]);
    // The operating points, in each panel.
    let point = |o: &OperatingPoint<f64>, which: usize, k: usize| {
        let xv = o.v * u.velocity;
        match (stall.filter(|_| k == 1), which) {
            // The stall limit: v → 0 on the point's line.
            (Some(_), 0) => (
                0.0,
                if o.v > 0.0 {
                    line.stall_forward
                } else {
                    -line.stall_backward
                } * u.force,
            ),
            (Some(_), 1) => (0.0, 0.0),
            (Some(eta), _) => (0.0, eta),
            (None, 0) => (xv, o.force * u.force),
            (None, 1) => (xv, o.powers.output * u.power),
            (None, _) => (xv, o.powers.efficiency()),
        }
    };
    let markers = [
        Marker::Circle,
        if stall.is_some() {
            Marker::Ring
        } else {
            Marker::Diamond
        },
    ];
    let mark_series = |which: usize| -> Vec<Series> {
        marks
            .iter()
            .zip(markers)
            .enumerate()
            .filter_map(|(k, ((o, _), m))| {
                o.as_ref().map(|o| Series {
                    label: String::new(),
                    points: vec![point(o, which, k)],
                    mark: Mark::Markers(m),
                    color: 6 + 3 * k,
                })
            })
            .collect()
    };
    let unlabelled = |points: Vec<(f64, f64)>, mark: Mark, color: usize| Series {
        label: String::new(),
        points,
        mark,
        color,
    };
    let pad = |lo: f64, hi: f64| {
        let h = (hi - lo).max(1e-300);
        (lo - 0.05 * h, hi + 0.05 * h)
    };
    let extras = Extras::default();
    let mut force_series = vec![unlabelled(force, Mark::Line, 4)];
    force_series.extend(mark_series(0));
    let mut power_series = vec![
        unlabelled(pin, Mark::Line, 0),
        unlabelled(pf, Mark::Dashed, 2),
        unlabelled(pout, Mark::Line, 1),
    ];
    power_series.extend(mark_series(1));
    let mut eta_series = vec![unlabelled(eta, Mark::Line, 3)];
    eta_series.extend(mark_series(2));
    let panels = vec![
        (
            Panel {
                title: "force–velocity line".into(),
                x_label: if line.no_load_backward > 0.0 {
                    format!("v ({vu}; < 0: backward line)")
                } else {
                    format!("v ({vu})")
                },
                y_label: format!("force −μ(v)F̄z ({fu})"),
                x: pad(x.0, x.1),
                y: pad(fmin, fmax),
                series: force_series,
            },
            extras.clone(),
        ),
        (
            Panel {
                title: "powers".into(),
                x_label: format!("v ({vu})"),
                y_label: format!("power ({pu})"),
                x: pad(x.0, x.1),
                y: (0.0, pmax.max(1e-300) * 1.08),
                series: power_series,
            },
            extras.clone(),
        ),
        (
            Panel {
                title: "efficiency η = P_out/P_in".into(),
                x_label: format!("v ({vu})"),
                y_label: "η".into(),
                x: pad(x.0, x.1),
                y: (0.0, emax.max(1e-12) * 1.08),
                series: eta_series,
            },
            extras,
        ),
    ];
    let legend_entry = |label: &str, mark: Mark, color: usize| Series {
        label: label.into(),
        points: Vec::new(),
        mark,
        color,
    };
    let mut legend = vec![
        legend_entry("force −μ(v)F̄z", Mark::Line, 4),
        legend_entry("P_in, tangential transducer", Mark::Line, 0),
        legend_entry("P_friction", Mark::Dashed, 2),
        legend_entry("P_out = force·v, to the body", Mark::Line, 1),
        legend_entry("η", Mark::Line, 3),
    ];
    for (k, ((o, name), m)) in marks.iter().zip(markers).enumerate() {
        if let Some(o) = o {
            let dir = if o.v > 0.0 { "forward" } else { "backward" };
            let label = match stall.filter(|_| k == 1) {
                Some(eta) => format!(
                    "{name}: none inside the line; η → {eta:.4} at stall (v → 0, no power; {dir})"
                ),
                None => format!("{name} ({dir}, v = {:.4e} {vu})", o.v * u.velocity),
            };
            legend.push(legend_entry(&label, Mark::Markers(m), 6 + 3 * k));
        }
    }
    let fig = Figure {
        panels,
        rows: 1,
        cols: 3,
        size: (1900, 720),
        legend,
        caption: scene.0.clone(),
    };
    render_figure(path, &fig)
}
