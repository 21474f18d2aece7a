//! `fricctl map`: the regime map over phase and amplitude ratio (or a μ map
//! at a fixed relative velocity), drawn with the exact active-control lines.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use model_core::regime::Regime;
use plotters::style::RGBColor;

use crate::args::{short, Count, Real};
use crate::error::{CliError, CliResult};
use crate::eval::{classify_scene_profile, Method, MethodArgs};
use crate::output::write_rows;
use crate::plot::{render_heat, render_map, Heat, HeatMap, RegimeMap};
use crate::progress::progress_bar;
use crate::scene_args::{check_reach, profile_text, ProfileArgs};
use fric_analysis::grid::{cell_scene, cells, centres, method_mix, mix_text, mu_cells, Cell};
use model_core::mdr::Profile;

/// Largest |φ| of the map's phase range, degrees: 10⁴ rad (572 957.8°,
/// rounded down), as the scene flags (`--phi-deg`) allow.
const PHI_LIMIT_DEG: f64 = 572_957.0;

/// Widest phase span, degrees: ten turns. The regimes repeat every turn, and
/// the exact active-control lines are drawn every 180° (each one 400
/// classifications), so the span bounds the map's work.
const MAX_PHI_SPAN_DEG: f64 = 3600.0;

/// The phase flags' domain.
const PHI_DEG: Real = Real::ANY
    .at_least(-PHI_LIMIT_DEG)
    .at_most(PHI_LIMIT_DEG)
    .because("≈ 10⁴ rad; give the phase within a turn");

/// Flags of `fricctl map`.
#[derive(Args, Debug, Clone)]
pub struct MapCmd {
    /// Δu_z/u_z0 (fixed for the map; ≥ 1: the contact lifts off once per period)
    #[arg(long, value_parser = Real::positive().because("the ratio needs Δu_z > 0"))]
    pub duz_rel: f64,
    /// Smallest amplitude ratio k_xΔu_x/(μ0 k_z Δu_z) [default: 0]
    #[arg(long, value_parser = Real::non_negative())]
    pub ratio_min: Option<f64>,
    /// Largest amplitude ratio [default: 3]
    #[arg(long, value_parser = Real::non_negative())]
    pub ratio_max: Option<f64>,
    /// Smallest phase, degrees [default: 0]
    #[arg(long, value_parser = PHI_DEG)]
    pub phi_min_deg: Option<f64>,
    /// Largest phase, degrees, at most ten turns above --phi-min-deg [default: 360]
    #[arg(long, value_parser = PHI_DEG)]
    pub phi_max_deg: Option<f64>,
    /// Cells per axis (2 to 1000)
    #[arg(long, default_value_t = 120, value_parser = Count::<usize>::at_least(2).at_most(1000, "a map of 10⁶ cells is the largest drawn"))]
    pub res: usize,
    /// Plot file (.svg or .png); at least one of --plot and --csv
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Write the cells as CSV; at least one of --plot and --csv
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Map μ/μ0 at v0 = X·v_c (forward v_c for X > 0, backward for X < 0) instead of the regimes
    #[arg(long, value_name = "X", value_parser = Real::ANY)]
    pub v_rel: Option<f64>,
    /// How μ is computed per cell (with --v-rel)
    #[command(flatten)]
    pub how: MethodArgs,
    /// The contact's shape
    #[command(flatten)]
    pub contact: ProfileArgs,
}

impl MapCmd {
    /// Runs the command (the map goes to files; `out` is unused).
    pub fn run(mut self, _out: &mut impl Write) -> CliResult {
        self.how.profile = self.contact.resolve()?;
        let a = &self;
        let r = Range::of(a.ratio_min, a.ratio_max, (0.0, 3.0), "ratio");
        let phi = Range::of(a.phi_min_deg, a.phi_max_deg, (0.0, 360.0), "phi");
        // Every value is in its domain (the flags' parsers); what depends
        // on two flags is checked here, before the missing-output check.
        r.check()?;
        phi.check()?;
        if phi.hi - phi.lo > MAX_PHI_SPAN_DEG {
            return Err(CliError::usage(format!(
                "{}: the phase span {}° exceeds ten turns (3600°); the regimes repeat every turn",
                phi.flag(),
                short(phi.hi - phi.lo)
            )));
        }
        // The largest drive of the map must be one the solvers resolve.
        let b_flag = if a.ratio_max.is_some() {
            "--ratio-max"
        } else {
            "--duz-rel"
        };
        check_reach(a.duz_rel, a.duz_rel * r.hi, "--duz-rel", b_flag)?;
        if let Some(p) = &a.plot {
            crate::plot::ext(p)?;
        }
        crate::output::check_outputs(&[(a.plot.as_deref(), "plot"), (a.csv.as_deref(), "csv")])?;
        a.how.validate()?;
        if a.plot.is_none() && a.csv.is_none() {
            return Err(CliError::usage(
                "--plot: missing (give --plot FILE, --csv FILE or both)",
            ));
        }
        if let Some(x) = a.v_rel {
            return run_mu_map(a, x, &r, &phi);
        }
        if a.how.method != Method::Auto || a.how.tol.is_some() {
            let flag = if a.how.method != Method::Auto {
                "--method"
            } else {
                "--tol"
            };
            return Err(CliError::usage(format!(
                "{flag}: the regime map is always exact; --method and --tol apply to a μ map (--v-rel)"
            )));
        }
        let ratios = centres(r.lo, r.hi, a.res);
        let phis = centres(phi.lo, phi.hi, a.res);
        // The CSV's asymmetry column costs a curved profile 64 more pairs
        // of quadratures per cell; the plot needs the class only.
        let (cells, class) =
            classify_cells(a.duz_rel, &ratios, &phis, &a.how.profile, a.csv.is_some())?;
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
            &a.how.profile,
            &ratios,
            &phis,
            &cells,
            class,
            a.plot.as_deref(),
            a.csv.as_deref(),
        )?;
        let _ = std::io::stderr().flush();
        Ok(())
    }
}

/// The regime of every map cell ([`cells`]) with a progress bar on stderr.
pub fn classify_cells(
    a: f64,
    ratios: &[f64],
    phis: &[f64],
    profile: &Profile<f64>,
    asymmetry: bool,
) -> CliResult<(Vec<Cell>, Vec<u8>)> {
    let n = ratios.len() * phis.len();
    estimate_up_front(a, ratios, phis, profile, asymmetry)?;
    let pb = progress_bar(n as u64, "classifying {bar:40} {pos}/{len} cells ({eta})");
    let res = cells(a, ratios, phis, profile, asymmetry, &|| pb.inc(1));
    pb.finish_and_clear();
    res
}

/// On a terminal, a map of more than 256 cells is first timed on 16 of them
/// spread over the grid (4 × 4, as the whole map runs: in parallel); when
/// the whole would take over 5 s the estimate is printed on stderr before
/// the work starts (the progress bar's own estimate follows).
fn estimate_up_front(
    a: f64,
    ratios: &[f64],
    phis: &[f64],
    profile: &Profile<f64>,
    asymmetry: bool,
) -> CliResult<()> {
    let n = ratios.len() * phis.len();
    if n <= 256 || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return Ok(());
    }
    let pick = |v: &[f64]| -> Vec<f64> { (0..4).map(|k| v[(2 * k + 1) * v.len() / 8]).collect() };
    let t0 = std::time::Instant::now();
    cells(a, &pick(ratios), &pick(phis), profile, asymmetry, &|| {})?;
    let total = t0.elapsed().as_secs_f64() * n as f64 / 16.0;
    if total > 5.0 {
        let (v, unit) = if total >= 7200.0 {
            (total / 3600.0, "h")
        } else if total >= 120.0 {
            (total / 60.0, "min")
        } else {
            (total, "s")
        };
        eprintln!("map: {n} cells, about {v:.0} {unit} (timed on 16 of them)");
    }
    Ok(())
}

/// One axis of the map: `--{name}-min` … `--{name}-max` (or `--phi-min-deg`
/// … `--phi-max-deg`), with which of them were given.
struct Range {
    lo: f64,
    hi: f64,
    lo_given: bool,
    hi_given: bool,
    name: &'static str,
}

impl Range {
    fn of(lo: Option<f64>, hi: Option<f64>, default: (f64, f64), name: &'static str) -> Range {
        Range {
            lo: lo.unwrap_or(default.0),
            hi: hi.unwrap_or(default.1),
            lo_given: lo.is_some(),
            hi_given: hi.is_some(),
            name,
        }
    }

    fn flag_of(&self, end: &str) -> String {
        if self.name == "phi" {
            format!("--phi-{end}-deg")
        } else {
            format!("--{}-{end}", self.name)
        }
    }

    /// The flag to name for the range: the upper end if it was given, else
    /// the lower one.
    fn flag(&self) -> String {
        if self.hi_given || !self.lo_given {
            self.flag_of("max")
        } else {
            self.flag_of("min")
        }
    }

    /// `lo < hi`, naming a flag that was given.
    fn check(&self) -> CliResult {
        if self.hi > self.lo {
            return Ok(());
        }
        let (max, min) = (self.flag_of("max"), self.flag_of("min"));
        let what = if self.hi_given || !self.lo_given {
            format!("{max}: must be greater than {min}")
        } else {
            format!("{min}: must be less than {max}")
        };
        Err(CliError::usage(format!(
            "{what} (got {} … {})",
            short(self.lo),
            short(self.hi)
        )))
    }
}

fn run_mu_map(a: &MapCmd, x: f64, r: &Range, phi: &Range) -> CliResult {
    if x == 0.0 && a.duz_rel < 1.0 {
        if a.how.profile != Profile::Flat {
            return Err(CliError::usage(
                "--v-rel: must be != 0 (at rest μ has two one-sided limits while duz-rel < 1; `fricctl mu --v0 0` gives them)",
            ));
        }
        return Err(CliError::usage(
            "--v-rel: must be != 0 (at rest μ has two one-sided limits; the regime map shows them)",
        ));
    }
    let ratios = centres(r.lo, r.hi, a.res);
    let phis = centres(phi.lo, phi.hi, a.res);
    let cells = mu_cells(a.duz_rel, &ratios, &phis, x, &a.how.options())
        .map_err(|e| e.renamed("--v0", "--v-rel"))?;
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
            "μ/μ0 at v0 = {}·v_c, Δu_z/u_z0 = {}, {} ({mix_text})",
            short(x),
            short(a.duz_rel),
            profile_text(&a.how.profile)
        ),
        x_label: "phase φ, degrees".to_string(),
        y_label: "k_xΔu_x / (μ0 k_z Δu_z)".to_string(),
        xs: phis,
        ys: ratios,
        log_x: false,
        log_y: false,
        // Signed μ/μ0 of both signs: diverging, white at 0.
        diverging: lo < 0.0 && hi > 0.0,
        range: crate::plot::heat_range(&heat, lo < 0.0 && hi > 0.0).unwrap_or((lo - 0.5, lo + 0.5)),
        cells: heat,
        value_label: "μ/μ0".to_string(),
        classes: if cells.iter().any(|c| c.mu_over_mu0.is_none()) {
            vec![("not converged".to_string(), RGBColor(200, 0, 0))]
        } else {
            Vec::new()
        },
    };
    if let Some(p) = &a.plot {
        render_heat(p, &m, (1100, 760))?;
        eprintln!("wrote {}", p.display());
    }
    if let Some(p) = a.csv.as_deref() {
        write_rows(p, &cells)?;
    }
    Ok(())
}

/// The colours of the three classes.
pub const CLASSES: [(&str, RGBColor); 3] = [
    ("active control (I), lines", RGBColor(120, 190, 120)),
    ("dynamic ratchet (II)", RGBColor(110, 160, 220)),
    ("actuator (III)", RGBColor(235, 130, 90)),
];

/// The exact active-control set inside the map: the lines φ = 90°, 270° (mod
/// 360°) where the law is symmetric, and ratio = 0 (normal oscillation only).
pub fn active_lines(
    a: f64,
    profile: &Profile<f64>,
    ratios: &[f64],
    phis: &[f64],
) -> CliResult<Vec<Vec<(f64, f64)>>> {
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
        // A curved profile classifies through the quadrature (128 integrals
        // per point): fewer samples along the line.
        let n = if *profile == Profile::Flat { 400 } else { 60 };
        let mut run: Vec<(f64, f64)> = Vec::new();
        for i in 0..=n {
            let r = (rlo - hy) + (rhi - rlo + 2.0 * hy) * i as f64 / n as f64;
            let r = r.max(0.0);
            let s = cell_scene(a, r, phi)?;
            let c = classify_scene_profile(&s, profile)?;
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
#[allow(clippy::too_many_arguments)]
pub fn write_map(
    a: f64,
    profile: &Profile<f64>,
    ratios: &[f64],
    phis: &[f64],
    cells: &[Cell],
    class: Vec<u8>,
    plot: Option<&Path>,
    csv_path: Option<&Path>,
) -> CliResult {
    if let Some(plot) = plot {
        draw_map(a, profile, ratios, phis, class, plot)?;
    }
    if let Some(p) = csv_path {
        write_rows(p, cells)?;
    }
    Ok(())
}

/// Draws a regime map with the paper's rules and the exact active-control lines.
fn draw_map(
    a: f64,
    profile: &Profile<f64>,
    ratios: &[f64],
    phis: &[f64],
    class: Vec<u8>,
    plot: &Path,
) -> CliResult {
    let (plo, phi_hi) = (phis[0], *phis.last().unwrap_or(&phis[0]));
    let (rlo, rhi) = (ratios[0], *ratios.last().unwrap_or(&ratios[0]));
    // The paper's rule was derived for permanent contact: not drawn with lift-off.
    let mut lines = if a < 1.0 {
        vec![(
            "paper's rule: ratio = 1 (ratchet below, drive above)".to_string(),
            vec![(plo, 1.0), (phi_hi, 1.0)],
        )]
    } else {
        vec![(String::new(), Vec::new())]
    };
    for v in [90.0, 270.0, -90.0, 450.0] {
        if v > plo && v < phi_hi {
            lines.push((String::new(), vec![(v, rlo), (v, rhi)]));
        }
    }
    if lines.len() > 1 {
        lines[1].0 = "paper's rule: φ = π/2 symmetric".to_string();
    }
    if a >= 1.0 || *profile != Profile::Flat {
        // With lift-off or a curved profile φ = 90° is not force-free at rest (μ(0) ≠ 0 in
        // general, `fricctl classify`): no paper line applies.
        lines.clear();
    }
    let m = RegimeMap {
        title: if *profile != Profile::Flat {
            format!(
                "Regimes at Δu_z/u_z0 = {}, {} (MDR quadrature)",
                short(a),
                profile_text(profile)
            )
        } else if a < 1.0 {
            format!("Regimes at Δu_z/u_z0 = {} (exact classification)", short(a))
        } else {
            format!(
                "Regimes at Δu_z/u_z0 = {} (lifts off; exact lift-off classification)",
                short(a)
            )
        },
        x_label: "phase φ, degrees".to_string(),
        y_label: "k_xΔu_x / (μ0 k_z Δu_z)".to_string(),
        xs: phis.to_vec(),
        ys: ratios.to_vec(),
        class,
        classes: CLASSES,
        lines,
        class0_lines: active_lines(a, profile, ratios, phis)?,
    };
    render_map(plot, &m, (1100, 760))?;
    eprintln!("wrote {}", plot.display());
    Ok(())
}
