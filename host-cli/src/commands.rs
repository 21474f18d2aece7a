//! The `mu`, `curve`, `static` and `classify` commands.

use std::io::Write;
use std::path::PathBuf;

use model_core::analytic::{CriticalVelocity, StaticFriction};
use model_core::exact;
use model_core::regime::{self, ClassifyOptions, Regime};
use model_core::{Libm, Scene};
use rayon::prelude::*;
use serde::Serialize;

use crate::compute::{from_rel, mu_at, v_rel, MethodArgs, MuOutcome};
use crate::error::{CliError, CliResult};
use crate::plot::{render_panels, Mark, Panel, Series};
use crate::scene_args::{ResolvedScene, SceneArgs};

fn print_json<T: Serialize>(v: &T) -> CliResult {
    let s = serde_json::to_string_pretty(v).map_err(|e| CliError::failure(format!("JSON: {e}")))?;
    println!("{s}");
    Ok(())
}

fn velocity(rs: &ResolvedScene, v0: Option<f64>, vrel: Option<f64>) -> CliResult<f64> {
    let vc = CriticalVelocity::of(&rs.scene);
    match (v0, vrel) {
        (Some(v), None) => {
            if !v.is_finite() {
                return Err(CliError::usage("--v0: must be a finite number"));
            }
            Ok(v)
        }
        (None, Some(x)) => from_rel(&vc, x, "v-rel"),
        _ => Err(CliError::usage("--v0: give either --v0 or --v-rel")),
    }
}

/// `fricctl mu`.
pub fn mu(
    args: &SceneArgs,
    v0: Option<f64>,
    vrel: Option<f64>,
    how: &MethodArgs,
    json: bool,
) -> CliResult {
    how.validate()?;
    let rs = args.resolve()?;
    let v = velocity(&rs, v0, vrel)?;
    let out = mu_at(&rs.scene, v, how)?;
    if json {
        print_json(&out)?;
    } else {
        print_mu_text(&out);
    }
    if out.converged == Some(false) {
        return Err(CliError::failure(format!(
            "the fixed-step method did not reach a steady state in {} periods (last period's mu/mu0 = {}, not a result)",
            out.periods.unwrap_or(0),
            out.last_mu_over_mu0.unwrap_or(f64::NAN)
        )));
    }
    Ok(())
}

fn print_mu_text(o: &MuOutcome) {
    println!("v0           {}", o.v0);
    match o.v_rel {
        Some(x) => println!("v0/v_c       {x}"),
        None => println!("v0/v_c       (v_c = 0 in this direction)"),
    }
    if let Some(m) = o.mu {
        println!("mu           {m}");
        println!("mu/mu0       {}", o.mu_over_mu0.unwrap_or(f64::NAN));
    }
    if let (Some(p), Some(m)) = (o.mu_0plus_over_mu0, o.mu_0minus_over_mu0) {
        println!("mu(0+)/mu0   {p}");
        println!("mu(0-)/mu0   {m}");
    }
    println!("method       {}", o.method);
    if let Some(b) = o.error_bound_over_mu0 {
        println!("error bound  {b:e} (units of mu0)");
    }
    if let Some(n) = o.steps_per_period {
        println!("steps/period {n}");
        println!("periods      {}", o.periods.unwrap_or(0));
        println!("converged    {}", o.converged.unwrap_or(false));
    }
    println!("v_c forward  {}", o.vc_forward);
    println!("v_c backward {}", o.vc_backward);
}

/// Arguments of `fricctl curve`.
pub struct CurveArgs {
    /// Scene flags.
    pub scene: SceneArgs,
    /// `(v_min, v_max)`, m/s.
    pub v_range: Option<(f64, f64)>,
    /// `(v_rel_min, v_rel_max)`.
    pub v_rel_range: Option<(f64, f64)>,
    /// Number of velocities.
    pub points: usize,
    /// Method, resolution, tolerance.
    pub how: MethodArgs,
    /// CSV file (stdout if none).
    pub csv: Option<PathBuf>,
    /// Plot file.
    pub plot: Option<PathBuf>,
}

/// One CSV row.
#[derive(Serialize, Debug, Clone, Copy)]
pub struct Row {
    /// Velocity.
    pub v0: f64,
    /// v0/v_c.
    pub v_rel: Option<f64>,
    /// μ.
    pub mu: f64,
    /// μ/μ0.
    pub mu_over_mu0: f64,
    /// Which computation answered (see `fricctl mu --json`).
    pub method: &'static str,
    /// The bound it guarantees, units of μ0.
    pub error_bound_over_mu0: f64,
}

/// Rows of μ(v) for the velocities (two rows, μ(0⁻) then μ(0⁺), at v0 = 0),
/// computed in parallel.
pub fn curve_rows(scene: &Scene<f64>, vs: &[f64], how: &MethodArgs) -> CliResult<Vec<Row>> {
    let vc = CriticalVelocity::of(scene);
    let mu0 = scene.mu0();
    let rows: Vec<CliResult<Vec<Row>>> = vs
        .par_iter()
        .map(|&v| {
            let o = mu_at(scene, v, how)?;
            if let (Some(p), Some(m)) = (o.mu_0plus_over_mu0, o.mu_0minus_over_mu0) {
                let b = o.error_bound_over_mu0.unwrap_or(0.0);
                return Ok(vec![
                    Row {
                        v0: 0.0,
                        v_rel: Some(0.0),
                        mu: m * mu0,
                        mu_over_mu0: m,
                        method: o.method,
                        error_bound_over_mu0: b,
                    },
                    Row {
                        v0: 0.0,
                        v_rel: Some(0.0),
                        mu: p * mu0,
                        mu_over_mu0: p,
                        method: o.method,
                        error_bound_over_mu0: b,
                    },
                ]);
            }
            match o.mu_over_mu0 {
                Some(m) => Ok(vec![Row {
                    v0: v,
                    v_rel: v_rel(&vc, v),
                    mu: m * mu0,
                    mu_over_mu0: m,
                    method: o.method,
                    error_bound_over_mu0: o.error_bound_over_mu0.unwrap_or(f64::NAN),
                }]),
                None => Err(CliError::failure(format!(
                    "v0 = {v}: the fixed-step method did not reach a steady state in {} periods",
                    o.periods.unwrap_or(0)
                ))),
            }
        })
        .collect();
    let mut out = Vec::with_capacity(vs.len() + 1);
    for r in rows {
        out.extend(r?);
    }
    Ok(out)
}

/// How many points each method answered, in order of first appearance.
pub fn method_mix(methods: impl IntoIterator<Item = &'static str>) -> Vec<(&'static str, usize)> {
    let mut mix: Vec<(&'static str, usize)> = Vec::new();
    for m in methods {
        match mix.iter_mut().find(|(x, _)| *x == m) {
            Some(e) => e.1 += 1,
            None => mix.push((m, 1)),
        }
    }
    mix
}

/// A method mix as text: `exact 120, sliding 40` (with `sep` between entries).
pub fn mix_text(mix: &[(&'static str, usize)], sep: &str) -> String {
    mix.iter()
        .map(|(m, n)| format!("{m} {n}"))
        .collect::<Vec<_>>()
        .join(sep)
}

/// `n` evenly spaced values from `a` to `b` inclusive.
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            if i + 1 == n {
                b
            } else {
                a + (b - a) * i as f64 / (n - 1) as f64
            }
        })
        .collect()
}

/// `fricctl curve`.
pub fn curve(a: CurveArgs) -> CliResult {
    let rs = a.scene.resolve()?;
    if a.points < 2 {
        return Err(CliError::usage("--points: must be >= 2"));
    }
    if a.points > 10_000_000 {
        return Err(CliError::usage(
            "--points: at most 10000000 (write several curves for more)",
        ));
    }
    if let Some(p) = &a.plot {
        crate::plot::ext(p)?;
    }
    let vc = CriticalVelocity::of(&rs.scene);
    let (vs, relative) = match (a.v_range, a.v_rel_range) {
        (Some((lo, hi)), None) => {
            check_range(lo, hi, "v-min", "v-max")?;
            (linspace(lo, hi, a.points), false)
        }
        (None, Some((lo, hi))) => {
            check_range(lo, hi, "v-rel-min", "v-rel-max")?;
            let xs = linspace(lo, hi, a.points);
            let mut vs = Vec::with_capacity(xs.len());
            for x in xs {
                vs.push(from_rel(
                    &vc,
                    x,
                    if x < 0.0 { "v-rel-min" } else { "v-rel-max" },
                )?);
            }
            (vs, true)
        }
        (None, None) => {
            return Err(CliError::usage(
                "--v-min: missing (give --v-min/--v-max or --v-rel-min/--v-rel-max)",
            ))
        }
        _ => {
            return Err(CliError::usage(
                "--v-rel-min: cannot be used with --v-min/--v-max",
            ))
        }
    };
    a.how.validate()?;
    let rows = curve_rows(&rs.scene, &vs, &a.how)?;
    let mix = method_mix(rows.iter().map(|r| r.method));
    eprintln!(
        "methods: {} (largest error bound {:e} mu0)",
        mix_text(&mix, ", "),
        rows.iter()
            .fold(0.0f64, |b, r| b.max(r.error_bound_over_mu0))
    );
    match &a.csv {
        Some(path) => {
            let f = std::fs::File::create(path).map_err(|e| {
                CliError::failure(format!("--csv: cannot create {}: {e}", path.display()))
            })?;
            write_csv(f, &rows)
                .map_err(|e| CliError::failure(format!("--csv: {}: {e}", path.display())))?;
            eprintln!("wrote {} rows to {}", rows.len(), path.display());
        }
        None => {
            let out = std::io::stdout().lock();
            write_csv(out, &rows).map_err(|e| CliError::failure(format!("stdout: {e}")))?;
        }
    }
    if let Some(p) = &a.plot {
        let x_label = if relative {
            "v0 / v_c  (forward v_c for v0 > 0, backward for v0 < 0)".to_string()
        } else if rs.dimensionless {
            "v0 / (ω μ0 k_z u_z0 / k_x)".to_string()
        } else {
            "v0, m/s".to_string()
        };
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| {
                (
                    if relative {
                        r.v_rel.unwrap_or(f64::NAN)
                    } else {
                        r.v0
                    },
                    r.mu_over_mu0,
                )
            })
            .collect();
        let (x0, x1) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            });
        let ymin = pts.iter().fold(0.0f64, |m, p| m.min(p.1));
        let g = rs.scene.groups();
        let panel = Panel {
            title: format!(
                "μ(v): Δu_z/u_z0 = {:.3}, k_xΔu_x/(μ0k_z u_z0) = {:.3}, φ = {:.1}°",
                g.duz_rel,
                g.dux_rel,
                g.phi.to_degrees()
            ),
            x_label,
            y_label: "μ / μ0".to_string(),
            x: (x0, if x1 > x0 { x1 } else { x0 + 1.0 }),
            y: (ymin.min(-0.05) - 0.05, 1.08),
            series: vec![Series {
                label: format!("{} points: {}", rows.len(), mix_text(&mix, ", ")),
                points: pts,
                mark: Mark::Line,
                color: 0,
            }],
        };
        render_panels(p, &[panel], 1, 1, (1000, 650))?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

fn check_range(lo: f64, hi: f64, a: &str, b: &str) -> CliResult {
    if !lo.is_finite() {
        return Err(CliError::usage(format!("--{a}: must be a finite number")));
    }
    if !hi.is_finite() {
        return Err(CliError::usage(format!("--{b}: must be a finite number")));
    }
    if hi <= lo {
        return Err(CliError::usage(format!(
            "--{b}: must be greater than --{a}"
        )));
    }
    Ok(())
}

/// Writes rows as CSV with the header `v0,v_rel,mu,mu_over_mu0` (an empty
/// v_rel where that direction's v_c is 0).
pub fn write_csv<W: Write>(w: W, rows: &[Row]) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(std::io::BufWriter::with_capacity(1 << 20, w));
    for r in rows {
        wr.serialize(r)?;
    }
    wr.flush()?;
    Ok(())
}

#[derive(Serialize)]
struct StaticOut {
    vc_forward: f64,
    vc_backward: f64,
    static_exists: bool,
    /// Exact static interval of the equilibrium displacement u_x0, m (null when empty).
    interval_lo_m: Option<f64>,
    interval_hi_m: Option<f64>,
    /// The interval ends over W0 = μ0 k_z u_z0/k_x (lo = c' − 1, hi = 1 − c), also when lo > hi.
    lo_over_w0: f64,
    hi_over_w0: f64,
    mu_s_forward_over_mu0: Option<f64>,
    mu_s_backward_over_mu0: Option<f64>,
    paper_eq18_forward_over_mu0: f64,
    paper_eq19_backward_over_mu0: f64,
    mu_0plus_over_mu0: f64,
    mu_0minus_over_mu0: f64,
    w0_m: f64,
}

/// `fricctl static`.
pub fn statics(args: &SceneArgs, json: bool) -> CliResult {
    let rs = args.resolve()?;
    let s = &rs.scene;
    let vc = CriticalVelocity::of(s);
    let st = StaticFriction::of(s);
    let (p, m) =
        exact::limits_at_zero::<f64, Libm>(&s.drive()).map_err(crate::compute::exact_failure)?;
    let iv = st.interval_m(s);
    let out = StaticOut {
        vc_forward: vc.forward,
        vc_backward: vc.backward,
        static_exists: st.exists(),
        interval_lo_m: iv.map(|x| x.0),
        interval_hi_m: iv.map(|x| x.1),
        lo_over_w0: st.lo,
        hi_over_w0: st.hi,
        mu_s_forward_over_mu0: st.mu_s_forward_over_mu0(),
        mu_s_backward_over_mu0: st.mu_s_backward_over_mu0(),
        paper_eq18_forward_over_mu0: st.paper_eq18_forward,
        paper_eq19_backward_over_mu0: st.paper_eq19_backward,
        mu_0plus_over_mu0: p,
        mu_0minus_over_mu0: m,
        w0_m: s.w0(),
    };
    if json {
        return print_json(&out);
    }
    println!("v_c forward            {}", out.vc_forward);
    println!("v_c backward           {}", out.vc_backward);
    println!(
        "static equilibrium     {}",
        if out.static_exists {
            "exists"
        } else {
            "none (the contact cannot rest)"
        }
    );
    match iv {
        Some((lo, hi)) => println!("static interval u_x0   [{lo}, {hi}] m"),
        None => println!(
            "static interval u_x0   empty (lo = {} W0 > hi = {} W0)",
            st.lo, st.hi
        ),
    }
    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| v.to_string());
    println!("mu_s+/mu0 (exact)      {}", opt(out.mu_s_forward_over_mu0));
    println!("mu_s-/mu0 (exact)      {}", opt(out.mu_s_backward_over_mu0));
    println!("paper eq. 18 (forward) {}", out.paper_eq18_forward_over_mu0);
    println!(
        "paper eq. 19 (backward) {}",
        out.paper_eq19_backward_over_mu0
    );
    println!("mu(0+)/mu0             {p}");
    println!("mu(0-)/mu0             {m}");
    Ok(())
}

#[derive(Serialize)]
struct ClassifyOut {
    regime: &'static str,
    mu_0plus_over_mu0: f64,
    mu_0minus_over_mu0: f64,
    static_exists: bool,
    static_lo_over_w0: f64,
    static_hi_over_w0: f64,
    vc_forward: f64,
    vc_backward: f64,
    vc_forward_over_omega_w0: f64,
    vc_backward_over_omega_w0: f64,
    asymmetry: f64,
    duz_rel: f64,
    dux_rel: f64,
    ratio: Option<f64>,
    phi_deg: f64,
    rule_of_thumb: &'static str,
    rule_of_thumb_agrees: bool,
}

/// The paper's rule of thumb (§3.2 and §4): single mode or φ = π/2 symmetric;
/// otherwise ratio < 1 ratchet, > 1 actuator.
pub fn rule_of_thumb(s: &Scene<f64>) -> Regime {
    let g = s.groups();
    let cosphi = g.phi.cos();
    if g.duz_rel == 0.0 || g.dux_rel == 0.0 || cosphi.abs() < 1e-12 {
        return Regime::ActiveControl;
    }
    match s.ratio() {
        Some(r) if r > 1.0 => Regime::Actuator,
        _ => Regime::DynamicRatchet,
    }
}

/// `fricctl classify`.
pub fn classify(args: &SceneArgs, json: bool) -> CliResult {
    let rs = args.resolve()?;
    let s = &rs.scene;
    let c =
        regime::classify(s, &ClassifyOptions::default()).map_err(crate::compute::exact_failure)?;
    let vc = CriticalVelocity::of(s);
    let g = s.groups();
    let rot = rule_of_thumb(s);
    let out = ClassifyOut {
        regime: c.regime.name(),
        mu_0plus_over_mu0: c.mu_0plus,
        mu_0minus_over_mu0: c.mu_0minus,
        static_exists: c.statics.exists(),
        static_lo_over_w0: c.statics.lo,
        static_hi_over_w0: c.statics.hi,
        vc_forward: vc.forward,
        vc_backward: vc.backward,
        vc_forward_over_omega_w0: c.c_forward,
        vc_backward_over_omega_w0: c.c_backward,
        asymmetry: c.asymmetry,
        duz_rel: g.duz_rel,
        dux_rel: g.dux_rel,
        ratio: s.ratio(),
        phi_deg: g.phi.to_degrees(),
        rule_of_thumb: rot.name(),
        rule_of_thumb_agrees: rot == c.regime,
    };
    if json {
        return print_json(&out);
    }
    println!("regime                 {}", out.regime);
    println!("mu(0+)/mu0             {}", out.mu_0plus_over_mu0);
    println!("mu(0-)/mu0             {}", out.mu_0minus_over_mu0);
    println!("static equilibrium     {}", out.static_exists);
    println!("asymmetry max|mu(v)+mu(-v)|/mu0  {}", out.asymmetry);
    println!(
        "v_c forward/backward   {} / {}",
        out.vc_forward, out.vc_backward
    );
    println!(
        "paper's rule of thumb  {} ({})",
        out.rule_of_thumb,
        if out.rule_of_thumb_agrees {
            "agrees"
        } else {
            "disagrees"
        }
    );
    Ok(())
}
