//! Sets of points to compute μ or the regime over: evenly spaced velocities,
//! cell centres, the rows of a curve (`fricctl curve`), the cells of a map
//! (`fricctl map`), and the count of which method answered where.
//!
//! Velocities are in m/s, or in units of ωW0 (`W0 = μ0 k_z u_z0 / k_x`) for a
//! dimensionless scene (eqs. 25/26); phases in degrees; μ in units of μ0
//! where the name says `_over_mu0`. The work is spread over rayon's threads;
//! the result's order is that of the input.

use model_core::mdr::Profile;
use model_core::regime::Regime;
use model_core::scene::ContactMode;
use model_core::{Groups, Scene};
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::eval::{
    classify_scene_profile, critical_velocity, from_rel, mu_at, profile_tol, regime_of_profile,
    v_rel, Method, MethodArgs,
};
use crate::numbers::Short;
use crate::profile_curve::profile_curve;

/// The `i`-th of `n` evenly spaced values from `a` to `b` inclusive (the last
/// is `b` exactly; `n` = 1 gives `b`).
pub fn linspace_at(a: f64, b: f64, n: usize, i: usize) -> f64 {
    if i + 1 == n {
        b
    } else {
        a + (b - a) * i as f64 / n.saturating_sub(1).max(1) as f64
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
    /// Velocity, m/s (units of ωW0 for a dimensionless scene).
    pub v0: f64,
    /// v0/v_c, with v_c of eq. 8 in v0's direction (empty where that
    /// direction's v_c is 0).
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

/// The `method` of a curve's row answered by the interpolant of
/// [`profile_curve`] (a curved profile; its bound is eq. C1 there).
pub const INTERPOLATED: &str = "mdr-interpolated";

/// Rows of μ(v) for the velocities `vs` (two rows, μ(0⁻) then μ(0⁺), at
/// v0 = 0), each by the method choice of `how` ([`mu_at`]), computed in
/// parallel; for a curved profile, runs of velocities where μ(v) is smooth
/// by [`profile_curve`]'s interpolant ([`INTERPOLATED`]). A velocity the method refuses is named as `--v0` (the caller
/// renames it to its own flag); a fixed-step run that reaches no steady
/// state is a failure.
pub fn curve_rows(scene: &Scene<f64>, vs: &[f64], how: &MethodArgs) -> Result<Vec<Row>> {
    curve_rows_with(scene, vs, how, true)
}

/// [`curve_rows`], with a curved profile's interpolant (`interpolate`) or
/// every velocity by its own quadrature (`fricctl curve --per-point`).
pub fn curve_rows_with(
    scene: &Scene<f64>,
    vs: &[f64],
    how: &MethodArgs,
    interpolate: bool,
) -> Result<Vec<Row>> {
    let vc = critical_velocity(scene)?;
    let mu0 = scene.mu0();
    // A curved profile: runs of smooth μ(v) from an interpolant
    // (`profile_curve`, method "mdr-interpolated"), the rest point by point.
    let tol = match (how.method, how.tol) {
        (Method::Auto, Some(t)) => Some(t),
        (Method::Auto | Method::Exact, _) => Some(profile_tol(scene, &how.profile)),
        _ => None,
    };
    let pre = match tol {
        Some(t) if interpolate && how.profile != Profile::Flat => {
            profile_curve(scene, &how.profile, vs, t)
        }
        _ => vec![None; vs.len()],
    };
    let rows: Vec<Result<Vec<Row>>> = vs
        .par_iter()
        .zip(pre)
        .map(|(&v, pre)| {
            if let Some(c) = pre {
                return Ok(vec![Row {
                    v0: v,
                    v_rel: v_rel(&vc, v),
                    mu: c.mu_over_mu0 * mu0,
                    mu_over_mu0: c.mu_over_mu0,
                    method: if c.interpolated { INTERPOLATED } else { "mdr" },
                    error_bound_over_mu0: c.bound,
                }]);
            }
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
                None => Err(Error::failure(format!(
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

/// The dimensionless scene of a map cell: `Δu_z/u_z0 = a` (eq. 25; `a ≥ 1`:
/// the contact lifts off), amplitude ratio `r = k_xΔu_x/(μ0 k_z Δu_z)`
/// (eq. 26), phase in degrees. A value out of the scene's domain is a usage
/// error naming the parameter as a flag.
pub fn cell_scene(a: f64, r: f64, phi_deg: f64) -> Result<Scene<f64>> {
    Scene::dimensionless_with_contact(
        Groups {
            duz_rel: a,
            dux_rel: r * a,
            phi: phi_deg.to_radians(),
        },
        ContactMode::Intermittent,
    )
    .map_err(|e| Error::usage(format!("--{e}")))
}

/// One cell of a μ map.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct MuCell {
    /// φ, degrees.
    pub phi_deg: f64,
    /// k_xΔu_x/(μ0 k_z Δu_z) (eq. 26).
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

/// μ/μ0 at `v0 = x·v_c` (eq. 8; the backward v_c for `x < 0`) over (ratio
/// rows, phase columns, degrees) at `Δu_z/u_z0 = a`, each cell by the
/// method choice of `how` ([`mu_at`]), in parallel, row-major. A refusal
/// names the cell (`ratio …, φ …°`); `x` is named as `--v-rel`, a velocity
/// the method refuses as `--v0`.
pub fn mu_cells(
    a: f64,
    ratios: &[f64],
    phis_deg: &[f64],
    x: f64,
    how: &MethodArgs,
) -> Result<Vec<MuCell>> {
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
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Cell {
    /// φ, degrees.
    pub phi_deg: f64,
    /// k_xΔu_x/(μ0 k_z Δu_z) (eq. 26).
    pub ratio: f64,
    /// Class name.
    pub regime: &'static str,
    /// μ(0⁺)/μ0.
    pub mu_0plus_over_mu0: f64,
    /// μ(0⁻)/μ0.
    pub mu_0minus_over_mu0: f64,
    /// max |μ(v) + μ(−v)|/μ0 (None where it was not asked for: a curved
    /// profile's map without it, [`cells`]).
    pub asymmetry: Option<f64>,
}

/// The regime of every map cell (row-major: ratio rows, phase columns,
/// degrees) at `Δu_z/u_z0 = a` for the contact `profile`, in parallel, with
/// the class index (0 active control, 1 ratchet, 2 actuator). `tick` is
/// called once per cell classified, from rayon's threads (a progress bar's
/// step). A refusal names the cell (`ratio …, φ …°`). Without `asymmetry`
/// a curved profile's cells are classified by [`regime_of_profile`] (the
/// same class, a fraction of the quadratures; `Cell::asymmetry` None).
pub fn cells(
    a: f64,
    ratios: &[f64],
    phis_deg: &[f64],
    profile: &Profile<f64>,
    asymmetry: bool,
    tick: &(dyn Fn() + Sync),
) -> Result<(Vec<Cell>, Vec<u8>)> {
    let n = ratios.len() * phis_deg.len();
    let res: Vec<Result<(Cell, u8)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let (r, phi) = (ratios[i / phis_deg.len()], phis_deg[i % phis_deg.len()]);
            let s = cell_scene(a, r, phi)?;
            let at = |e: crate::error::Error| {
                e.with_context(&format!("ratio {}, φ {}°", Short(r), Short(phi)))
            };
            let c = if asymmetry || *profile == Profile::Flat {
                let c = classify_scene_profile(&s, profile).map_err(at)?;
                (c.regime, c.mu_0plus, c.mu_0minus, Some(c.asymmetry))
            } else {
                let (regime, st) = regime_of_profile(&s, profile).map_err(at)?;
                let st =
                    st.ok_or_else(|| crate::error::Error::failure("no limits at rest (internal)"))?;
                (regime, st.mu_0plus, st.mu_0minus, None)
            };
            tick();
            let k = match c.0 {
                Regime::ActiveControl => 0,
                Regime::DynamicRatchet => 1,
                Regime::Actuator => 2,
            };
            Ok((
                Cell {
                    phi_deg: phi,
                    ratio: r,
                    regime: c.0.name(),
                    mu_0plus_over_mu0: c.1,
                    mu_0minus_over_mu0: c.2,
                    asymmetry: c.3,
                },
                k,
            ))
        })
        .collect();
    let mut cells = Vec::with_capacity(n);
    let mut class = Vec::with_capacity(n);
    for r in res {
        let (c, k) = r?;
        cells.push(c);
        class.push(k);
    }
    Ok((cells, class))
}
