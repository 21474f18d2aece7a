//! The methods bench: what "model no more than the scene needs" buys
//! (`fricctl bench methods` writes its CSV and chart).
//!
//! The curve and map commands' own code paths ([`curve_rows`], [`mu_cells`])
//! are timed, in one process, with `--method auto` (at a loose
//! tolerance and at the default, tight one), `--method exact` and
//! `--method fixed`; time is wall-clock for the whole command body (rayon on
//! all cores), the minimum over repeats, and is reported per point. The
//! fixed-step runs use fewer points (they are ~10⁴× slower) and are compared
//! per point. A last case times curved profiles: the flat punch against a
//! sphere and a cone through the MDR quadrature (`select::mu_within_profile`)
//! at three tolerances, on fewer points.

use std::time::Instant;

use model_core::analytic::CriticalVelocity;
use model_core::mdr::Profile;
use model_core::{select, Groups, Libm, Scene};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::eval::{from_rel, Method, MethodArgs};
use crate::grid::{centres, curve_rows, linspace, method_mix, mix_text, mu_cells};

/// The sizes of the bench (the CLI's flags of `bench methods`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Velocities per curve (`--points`; even, so that v0 = 0 is not among them).
    pub points: usize,
    /// Cells per map axis (`--res`).
    pub res: usize,
    /// Velocities per curve for the fixed-step runs (`--fixed-points`; even).
    pub fixed_points: usize,
    /// Cells per map axis for the fixed-step runs (`--fixed-res`).
    pub fixed_res: usize,
    /// Steps per period of the fixed-step runs (`--steps-per-period`).
    pub steps_per_period: u32,
    /// The loose tolerance for `auto`, units of μ0 (`--tol`).
    pub tol: f64,
    /// Repeats; the minimum is kept (`--repeats`).
    pub repeats: usize,
    /// Velocities per curve for the curved-profile (MDR) runs (`--mdr-points`; even).
    pub mdr_points: usize,
}

impl Config {
    /// Refuses an odd number of velocities per curve (v = 0 would be among
    /// them), then sizes below their least (2 points or cells, 1 step, 1
    /// repeat) and a `--tol` that is not a finite number > 0.
    pub fn check(&self) -> Result {
        for (n, flag) in [
            (self.points, "--points"),
            (self.fixed_points, "--fixed-points"),
            (self.mdr_points, "--mdr-points"),
        ] {
            if n % 2 == 1 {
                return Err(Error::usage(format!("{flag}: must be even (got {n})")));
            }
        }
        for (n, least, flag) in [
            (self.points, 2, "--points"),
            (self.res, 2, "--res"),
            (self.fixed_points, 2, "--fixed-points"),
            (self.fixed_res, 2, "--fixed-res"),
            (self.steps_per_period as usize, 1, "--steps-per-period"),
            (self.repeats, 1, "--repeats"),
            (self.mdr_points, 2, "--mdr-points"),
        ] {
            if n < least {
                return Err(Error::usage(format!(
                    "{flag}: must be at least {least} (got {n})"
                )));
            }
        }
        if !(self.tol.is_finite() && self.tol > 0.0) {
            return Err(Error::usage(format!(
                "--tol: must be a finite number > 0 (got {})",
                self.tol
            )));
        }
        Ok(())
    }
}

/// One timed configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    /// Which command and scene.
    pub case: &'static str,
    /// Method label.
    pub method: String,
    /// Points (velocities or cells).
    pub points: usize,
    /// Seconds for all points (minimum over repeats).
    pub total_s: f64,
    /// Which computations answered, with counts.
    pub mix: String,
}

impl Timing {
    /// Seconds per point.
    pub fn per_point(&self) -> f64 {
        self.total_s / self.points as f64
    }
}

/// Each timing's cost per point relative to the first of its case (the
/// cases in order of first appearance, as [`measure`] gives them).
pub fn ratios_to_first(timings: &[Timing]) -> Vec<f64> {
    let mut last_case = "";
    let mut first = 0.0;
    timings
        .iter()
        .map(|t| {
            if t.case != last_case {
                last_case = t.case;
                first = t.per_point();
            }
            t.per_point() / first
        })
        .collect()
}

/// The least wall time of `f` over `repeats` runs (at least one), with the
/// last run's result.
fn best_of<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let r = f()?;
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    // `repeats.max(1)` ≥ 1 iterations ran.
    last.map(|r| (best, r))
        .ok_or_else(|| Error::failure("no repeat ran"))
}

/// The timed methods: (label, options, whether fixed-step).
fn configs(c: &Config) -> Vec<(String, MethodArgs, bool)> {
    let m = |method, tol| MethodArgs {
        method,
        steps_per_period: Some(c.steps_per_period),
        tol,
        ..MethodArgs::default()
    };
    vec![
        (
            format!("auto --tol {:e}", c.tol),
            m(Method::Auto, Some(c.tol)),
            false,
        ),
        (
            "auto (default tol)".to_string(),
            m(Method::Auto, None),
            false,
        ),
        ("exact".to_string(), m(Method::Exact, None), false),
        (
            format!("fixed N={}", c.steps_per_period),
            m(Method::Fixed, None),
            true,
        ),
    ]
}

/// Every timing, in the CSV's order: the curve on a normal-only and a
/// dual-mode scene, the μ map, the curved profiles. `stage` is called with
/// a progress line before each group.
pub fn measure(c: &Config, stage: &mut dyn FnMut(&str)) -> Result<Vec<Timing>> {
    c.check()?;
    let mut out = Vec::new();
    stage("timing curves …");
    curve_case(
        c,
        "curve, normal only (Δu_z/u_z0 = 0.4), v/v_c in [-1.5, 1.5]",
        Groups {
            duz_rel: 0.4,
            dux_rel: 0.0,
            phi: 0.0,
        },
        &mut out,
    )?;
    curve_case(
        c,
        "curve, dual mode (Δu_z/u_z0 = 0.5, k_xΔu_x/(μ0 k_z u_z0) = 0.25, φ = 1 rad = 57.3°), v/v_c in [-1.5, 1.5]",
        Groups {
            duz_rel: 0.5,
            dux_rel: 0.25,
            phi: 1.0,
        },
        &mut out,
    )?;
    stage("timing maps …");
    map_case(c, &mut out)?;
    stage("timing curved profiles (MDR) …");
    profile_case(c, &mut out)?;
    Ok(out)
}

/// Times the curve command's body on one scene.
fn curve_case(c: &Config, case: &'static str, g: Groups<f64>, out: &mut Vec<Timing>) -> Result {
    let s = Scene::dimensionless(g).map_err(|e| Error::failure(e.to_string()))?;
    let vc = CriticalVelocity::of(&s);
    for (label, how, fixed) in configs(c) {
        let n = if fixed { c.fixed_points } else { c.points };
        let vs: Vec<f64> = linspace(-1.5, 1.5, n)
            .into_iter()
            .map(|x| from_rel(&vc, x, "v-rel"))
            .collect::<Result<_>>()?;
        let (t, rows) = best_of(c.repeats, || curve_rows(&s, &vs, &how))?;
        out.push(Timing {
            case,
            method: label,
            points: n,
            total_s: t,
            mix: mix_text(&method_mix(rows.iter().map(|r| r.method)), " + "),
        });
    }
    Ok(())
}

/// Times the μ map's body (Δu_z/u_z0 = 0.5, v0 = 0.5·v_c).
fn map_case(c: &Config, out: &mut Vec<Timing>) -> Result {
    for (label, how, fixed) in configs(c) {
        let res = if fixed { c.fixed_res } else { c.res };
        let ratios = centres(0.0, 3.0, res);
        let phis = centres(0.0, 360.0, res);
        let (t, cells) = best_of(c.repeats, || mu_cells(0.5, &ratios, &phis, 0.5, &how))?;
        out.push(Timing {
            case: "map --v-rel 0.5 (dual mode, Δu_z/u_z0 = 0.5, φ × ratio over 0…360° × 0…3)",
            method: label,
            points: cells.len(),
            total_s: t,
            mix: mix_text(&method_mix(cells.iter().map(|c| c.method)), " + "),
        });
    }
    Ok(())
}

/// Times μ over a velocity curve for the flat punch and curved profiles
/// (`select::mu_within_profile`, rayon over the points as the curve command),
/// without and with lift-off.
fn profile_case(c: &Config, out: &mut Vec<Timing>) -> Result {
    for (duz_rel, case) in [
        (0.5, "curve, profiles (Δu_z/u_z0 = 0.5, k_xΔu_x/(μ0 k_z u_z0) = 0.25, φ = 1 rad = 57.3°; u_z0 read as the mean indentation), v/v_c in [-1.5, 1.5]"),
        (1.5, "curve, profiles with lift-off (Δu_z/u_z0 = 1.5, k_xΔu_x/(μ0 k_z u_z0) = 0.25, φ = 1 rad = 57.3°; u_z0 read as the mean indentation), v/v_c in [-1.5, 1.5]"),
    ] {
        profile_scene(c, duz_rel, case, out)?;
    }
    Ok(())
}

/// The profiles timed at one drive: the flat punch at its solver's bound
/// (the single-spring solver below `Δu_z/u_z0 = 1`, the lift-off branch
/// from 1), then a sphere and a cone through the MDR at three tolerances.
fn profile_configs(s: &Scene<f64>, duz_rel: f64) -> [(&'static str, Profile<f64>, f64); 7] {
    let flat_tol = if duz_rel < 1.0 {
        model_core::exact::error_bound::<f64, Libm>(&s.drive())
    } else {
        model_core::model::liftoff::error_bound::<f64, Libm>(&s.drive())
    };
    [
        (
            if duz_rel < 1.0 {
                "flat auto (default tol)"
            } else {
                "flat auto (default tol; lift-off solver)"
            },
            Profile::Flat,
            flat_tol,
        ),
        ("sphere mdr --tol 1e-6", Profile::Sphere, 1e-6),
        ("sphere mdr --tol 1e-8", Profile::Sphere, 1e-8),
        ("sphere mdr --tol 1e-9", Profile::Sphere, 1e-9),
        ("cone mdr --tol 1e-6", Profile::Cone, 1e-6),
        ("cone mdr --tol 1e-8", Profile::Cone, 1e-8),
        ("cone mdr --tol 1e-9", Profile::Cone, 1e-9),
    ]
}

/// The refusal of `select::mu_within_profile`, as the failure of `label`
/// at `v` (m/s).
fn profile_failure(label: &str, v: f64, e: select::SelectError<f64>) -> Error {
    let why = match e {
        select::SelectError::BadTolerance => "tol: must be a finite number > 0".to_string(),
        select::SelectError::ToleranceTooTight { best } => {
            format!("tol: tighter than any method guarantees (best {best:e})")
        }
        select::SelectError::Exact(e) => e.to_string(),
        select::SelectError::Mdr(e) => e.to_string(),
    };
    Error::failure(format!("{label} at v0 = {v:e} m/s: {why}"))
}

/// [`profile_case`] for one drive ([`profile_configs`]).
fn profile_scene(c: &Config, duz_rel: f64, case: &'static str, out: &mut Vec<Timing>) -> Result {
    let g = Groups {
        duz_rel,
        dux_rel: 0.25,
        phi: 1.0,
    };
    let s = Scene::dimensionless_with_contact(g, model_core::scene::ContactMode::Intermittent)
        .map_err(|e| Error::failure(e.to_string()))?;
    let vc = CriticalVelocity::of(&s);
    let vs: Vec<f64> = linspace(-1.5, 1.5, c.mdr_points)
        .into_iter()
        .map(|x| from_rel(&vc, x, "v-rel"))
        .collect::<Result<_>>()?;
    for (label, p, tol) in profile_configs(&s, duz_rel) {
        let (t, methods) = best_of(c.repeats, || {
            vs.par_iter()
                .map(|&v| {
                    select::mu_within_profile::<f64, Libm>(&s, &p, v, tol)
                        .map(|ans| ans.method.name())
                        .map_err(|e| profile_failure(label, v, e))
                })
                .collect::<Result<Vec<_>>>()
        })?;
        out.push(Timing {
            case,
            method: label.to_string(),
            points: vs.len(),
            total_s: t,
            mix: mix_text(&method_mix(methods), " + "),
        });
    }
    Ok(())
}
