//! Sets of points to compute μ or the regime over: evenly spaced velocities,
//! cell centres, the rows of a curve, the cells of a map, and the count of
//! which method answered where.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use model_core::regime::Regime;
use model_core::scene::ContactMode;
use model_core::{Groups, Scene};
use rayon::prelude::*;
use serde::Serialize;

use crate::args::Short;
use crate::error::{CliError, CliResult};
use model_core::mdr::Profile;

use crate::eval::{classify_scene_profile, critical_velocity, from_rel, mu_at, v_rel, MethodArgs};

/// The `i`-th of `n` evenly spaced values from `a` to `b` inclusive (the last
/// is `b` exactly).
pub fn linspace_at(a: f64, b: f64, n: usize, i: usize) -> f64 {
    if i + 1 == n {
        b
    } else {
        a + (b - a) * i as f64 / (n - 1) as f64
    }
}

/// `n` evenly spaced values from `a` to `b` inclusive.
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n).map(|i| linspace_at(a, b, n, i)).collect()
}

/// Cell centres of `n` cells spanning `[lo, hi]`.
pub fn centres(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo + (hi - lo) * (i as f64 + 0.5) / n as f64)
        .collect()
}

/// One row of a μ(v) curve (the CSV columns of `fricctl curve`, in order).
#[derive(Serialize, Debug, Clone, Copy)]
pub struct Row {
    /// Velocity.
    pub v0: f64,
    /// v0/v_c (empty where that direction's v_c is 0).
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
    let vc = critical_velocity(scene)?;
    let mu0 = scene.mu0();
    let rows: Vec<CliResult<Vec<Row>>> = vs
        .par_iter()
        .map(|&v| {
            let o = mu_at(scene, v, how)?;
            if let (Some(p), Some(m)) = (o.mu_0plus_over_mu0, o.mu_0minus_over_mu0) {
                let b = o.error_bound_over_mu0.unwrap_or(0.0);
                let at_rest = |x: f64| Row {
                    v0: 0.0,
                    v_rel: Some(0.0),
                    mu: x * mu0,
                    mu_over_mu0: x,
                    method: o.method,
                    error_bound_over_mu0: b,
                };
                return Ok(vec![at_rest(m), at_rest(p)]);
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
#[derive(Debug, Clone, Default)]
pub struct MethodMix(Vec<(&'static str, usize)>);

impl MethodMix {
    /// Counts one more point answered by `method`.
    pub fn add(&mut self, method: &'static str) {
        match self.0.iter_mut().find(|(x, _)| *x == method) {
            Some(e) => e.1 += 1,
            None => self.0.push((method, 1)),
        }
    }

    /// The mix as text: `exact 120, sliding 40` (with `sep` between entries).
    pub fn text(&self, sep: &str) -> String {
        self.0
            .iter()
            .map(|(m, n)| format!("{m} {n}"))
            .collect::<Vec<_>>()
            .join(sep)
    }
}

/// How many points each method answered, in order of first appearance.
pub fn method_mix(methods: impl IntoIterator<Item = &'static str>) -> Vec<(&'static str, usize)> {
    let mut mix = MethodMix::default();
    for m in methods {
        mix.add(m);
    }
    mix.0
}

/// A method mix as text: `exact 120, sliding 40` (with `sep` between entries).
pub fn mix_text(mix: &[(&'static str, usize)], sep: &str) -> String {
    MethodMix(mix.to_vec()).text(sep)
}

/// The dimensionless scene of a map cell: `Δu_z/u_z0 = a` (`a ≥ 1`: the
/// contact lifts off), amplitude ratio `r` (eq. 26), phase in degrees.
pub fn cell_scene(a: f64, r: f64, phi_deg: f64) -> CliResult<Scene<f64>> {
    Scene::dimensionless_with_contact(
        Groups {
            duz_rel: a,
            dux_rel: r * a,
            phi: phi_deg.to_radians(),
        },
        ContactMode::Intermittent,
    )
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
            let vc = critical_velocity(&s)?;
            let v = from_rel(&vc, x, "v-rel")?;
            let o = mu_at(&s, v, how)
                .map_err(|e| e.with_context(&format!("ratio {}, φ {}°", Short(r), Short(phi))))?;
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

/// One cell of a regime map.
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

/// The regime of every map cell (row-major: ratio rows, phase columns), in
/// parallel, with the class index (0 active control, 1 ratchet, 2 actuator).
pub fn cells(
    a: f64,
    ratios: &[f64],
    phis_deg: &[f64],
    profile: &Profile<f64>,
    progress: bool,
) -> CliResult<(Vec<Cell>, Vec<u8>)> {
    let n = ratios.len() * phis_deg.len();
    let pb = if progress {
        progress_bar(n as u64, "classifying {bar:40} {pos}/{len} cells ({eta})")
    } else {
        ProgressBar::hidden()
    };
    let res: Vec<CliResult<(Cell, u8)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let (r, phi) = (ratios[i / phis_deg.len()], phis_deg[i % phis_deg.len()]);
            let s = cell_scene(a, r, phi)?;
            let c = classify_scene_profile(&s, profile)
                .map_err(|e| e.with_context(&format!("ratio {}, φ {}°", Short(r), Short(phi))))?;
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

/// A progress bar on stderr (drawn only when stderr is a terminal) with an
/// indicatif `template`.
pub fn progress_bar(len: u64, template: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    pb.set_style(
        ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}
