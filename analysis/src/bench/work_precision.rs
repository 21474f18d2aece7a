//! The work-precision bench: error against time for every way the project
//! computes μ, on scenes covering the paper's regimes (`fricctl bench
//! work-precision` writes its CSV files and chart).
//!
//! Error is `|μ − μ_exact,f64|/μ0`; time is the minimum over repeated batches
//! after a warm-up ([`super::timing`]). The fixed-step scheme is run for many
//! steps per period (four per octave from 8 to 65 536: the error jitters with
//! where the events fall on the grid, so every point is kept), from rest and
//! warm-started at the exact steady state, in f64 and f32, with libm and with
//! micromath for its set-up; the convergence order of each fixed-step series
//! is fitted by least squares ([`fitted_order`]). The points across lift-off
//! are [`super::across_lift_off`]'s (the flat punch at a = 0.5 … 3 and a
//! sphere through the MDR, each against its own reference).

use std::hint::black_box;

use model_core::analytic::approx::approx_mu_over_mu0;
use model_core::exact;
use model_core::fixed_step::{run_dimensionless, FixedStepConfig, Start, State};
use model_core::{Drive, Float, Groups, Libm, Math, Micromath, Scene};

use super::across_lift_off;
use super::point::{refusal_kind, Point};
use super::timing::time_min;
use crate::error::{Error, Result};

/// The scenes (dimensionless a = Δu_z/u_z0, b = k_xΔu_x/(μ0 k_z u_z0) (eq.
/// 25), φ in rad, and v0/v_c of the direction of motion, eq. 8).
pub const SCENES: &[(&str, f64, f64, f64, f64)] = &[
    ("normal only", 0.5, 0.0, 0.0, 0.3),
    ("tangential small", 0.0, 0.5, 0.4, 0.3),
    ("tangential large", 0.0, 3.0, 0.4, -0.5),
    ("dual ratchet", 0.5, 0.25, 1.0, 0.4),
    ("dual actuator", 0.5, 1.0, 0.3, 0.2),
    ("near v_c", 0.5, 0.25, 1.0, 0.98),
    ("low velocity", 0.5, 0.25, 1.0, 0.02),
    ("near lift-off", 0.97, 0.3, 2.0, 0.4),
];

/// The fixed-step series of each scene of [`SCENES`], in the order of the
/// orders' CSV.
pub const FIXED_METHODS: [&str; 5] = [
    "fixed f64 from rest",
    "fixed f64 warm",
    "fixed f32 from rest",
    "fixed f32 warm",
    "fixed f32 micromath",
];

/// The stepped series of each flat-punch point across lift-off.
pub const ACROSS_METHODS: [&str; 2] = ["fixed f64 from rest", "lift-off stepping f64"];

/// Refuses a largest steps per period that is not a power of two in
/// 8 ..= 65 536 (`--max-steps`).
pub fn check_max_steps(max_steps: u32) -> Result {
    if !max_steps.is_power_of_two() || !(8..=65536).contains(&max_steps) {
        return Err(Error::usage(
            "--max-steps: must be a power of two in 8..=65536",
        ));
    }
    Ok(())
}

/// Steps per period from 8 to `max`, four per octave (rounded, without
/// repeats).
pub fn steps_list(max: u32) -> Vec<u32> {
    let mut v = Vec::new();
    let mut x = 8.0f64;
    while x <= f64::from(max) * 1.0001 {
        v.push(x.round() as u32);
        x *= 2f64.powf(0.25);
    }
    v.dedup();
    v
}

/// Warm start: the window end of the exact steady state (s = ±w there).
pub fn warm_state<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Option<State<T>> {
    let (_, arcs) = exact::steady_state::<T, M>(d, v).ok()?;
    let last = arcs.last()?;
    let (_, c) = M::sin_cos(last.end);
    let w = T::ONE - d.a * c;
    let s = if v > T::ZERO { w } else { -w };
    Some(State {
        phase: last.end,
        stretch: s,
    })
}

/// Every point of the bench, in the CSV's order: the [`SCENES`] with the
/// steps per period of [`steps_list`]`(max_steps)`, then the flat punch
/// across lift-off at one steps-per-period value per octave (the series are
/// for the order, which one per octave shows), then the sphere.
/// `measuring(name)` is called before each scene.
pub fn measure_all(max_steps: u32, measuring: &mut dyn FnMut(&str)) -> Result<Vec<Point>> {
    check_max_steps(max_steps)?;
    let steps = steps_list(max_steps);
    let mut all = Vec::new();
    for &(name, aa, b, phi, x) in SCENES {
        measuring(name);
        all.extend(measure_scene(name, aa, b, phi, x, &steps)?);
    }
    let octaves: Vec<u32> = steps
        .iter()
        .copied()
        .filter(|n| n.is_power_of_two())
        .collect();
    for &(name, aa) in across_lift_off::FLAT {
        measuring(name);
        all.extend(across_lift_off::measure_flat(name, aa, &octaves)?);
    }
    for &(name, aa) in across_lift_off::SPHERE {
        measuring(name);
        all.extend(across_lift_off::measure_sphere(name, aa)?);
    }
    Ok(all)
}

/// One fixed-step series: a point per steps-per-period value in `steps`,
/// from rest or (`warm`) from [`warm_state`], against `reference`.
fn fixed_series<T: Float, M: Math<T>>(
    out: &mut Vec<Point>,
    scene: &'static str,
    (method, warm): (&str, bool),
    d: &Drive<T>,
    v: T,
    reference: f64,
    steps: &[u32],
) {
    for &n in steps {
        let mut cfg = FixedStepConfig::<T>::new(n);
        cfg.max_periods = 20_000;
        let start = if warm {
            match warm_state::<T, M>(d, v) {
                Some(s) => Start::State(s),
                None => Start::Rest,
            }
        } else {
            Start::Rest
        };
        match run_dimensionless::<T, M>(d, v, &cfg, start) {
            Ok(r) => {
                let t = time_min(|| {
                    black_box(
                        run_dimensionless::<T, M>(black_box(d), black_box(v), &cfg, start).ok(),
                    );
                });
                out.push(Point {
                    scene,
                    method: method.to_string(),
                    steps: Some(n),
                    error: Some((r.mu_over_mu0.to_f64() - reference).abs()),
                    time_s: t,
                    bound: Some(r.error_bound.to_f64()),
                    status: "ok".into(),
                });
            }
            Err(e) => out.push(Point {
                scene,
                method: method.to_string(),
                steps: Some(n),
                error: None,
                time_s: f64::NAN,
                bound: None,
                status: refusal_kind(&e).to_string(),
            }),
        }
    }
}

/// One scene of [`SCENES`], set up: its drives in f64, f32 (libm) and f32
/// (micromath), the velocity, and the reference μ/μ0 (the exact f64 solver).
struct Setup {
    name: &'static str,
    scene: Scene<f64>,
    d: Drive<f64>,
    d32: Drive<f32>,
    d32m: Drive<f32>,
    v: f64,
    reference: f64,
}

impl Setup {
    fn new(name: &'static str, a: f64, b: f64, phi: f64, x: f64) -> Result<Self> {
        let scene = Scene::dimensionless(Groups {
            duz_rel: a,
            dux_rel: b,
            phi,
        })
        .map_err(|e| Error::failure(e.to_string()))?;
        let d = scene.drive();
        let v = x * if x > 0.0 {
            d.c_forward::<Libm>()
        } else {
            d.c_backward::<Libm>()
        };
        let reference =
            exact::mu_over_mu0::<f64, Libm>(&d, v).map_err(|e| Error::failure(format!("{e}")))?;
        Ok(Setup {
            name,
            scene,
            d,
            d32: Drive::new::<Libm>(a as f32, b as f32, phi as f32),
            d32m: Drive::new::<Micromath>(a as f32, b as f32, phi as f32),
            v,
            reference,
        })
    }

    /// A point without a step count: `r` the μ/μ0 obtained (`None`: failed).
    fn point(&self, method: &str, r: Option<f64>, t: f64, bound: f64) -> Point {
        Point {
            scene: self.name,
            method: method.to_string(),
            steps: None,
            error: r.map(|m| (m - self.reference).abs()),
            time_s: t,
            bound: Some(bound),
            status: if r.is_some() {
                "ok".into()
            } else {
                "failed".into()
            },
        }
    }

    /// The exact solver in f64, f32 and f32 with micromath.
    fn exact_points(&self, out: &mut Vec<Point>) {
        let (d, d32, d32m, v) = (&self.d, &self.d32, &self.d32m, self.v);
        let v32 = v as f32;
        let r = exact::mu_over_mu0::<f64, Libm>(d, v).ok();
        let t = time_min(|| {
            black_box(exact::mu_over_mu0::<f64, Libm>(black_box(d), black_box(v)).ok());
        });
        out.push(self.point("exact f64", r, t, exact::error_bound::<f64, Libm>(d)));
        let r = exact::mu_over_mu0::<f32, Libm>(d32, v32)
            .ok()
            .map(f64::from);
        let t = time_min(|| {
            black_box(exact::mu_over_mu0::<f32, Libm>(black_box(d32), black_box(v32)).ok());
        });
        out.push(self.point(
            "exact f32",
            r,
            t,
            exact::error_bound::<f32, Libm>(d32).into(),
        ));
        let r = exact::mu_over_mu0::<f32, Micromath>(d32m, v32)
            .ok()
            .map(f64::from);
        let t = time_min(|| {
            black_box(exact::mu_over_mu0::<f32, Micromath>(black_box(d32m), black_box(v32)).ok());
        });
        out.push(self.point(
            "exact f32 micromath",
            r,
            t,
            exact::error_bound::<f32, Micromath>(d32m).into(),
        ));
    }

    /// Eq. 21 (normal only) or eq. 24 (tangential only), where one applies,
    /// with its bound `MAX_ERROR_OVER_A` × the amplitude.
    fn approx_point(&self, a: f64, b: f64, out: &mut Vec<Point>) {
        let (s, v) = (&self.scene, self.v);
        if let Ok((kind, m)) = approx_mu_over_mu0(s, v) {
            let t = time_min(|| {
                black_box(approx_mu_over_mu0(black_box(s), black_box(v)).ok());
            });
            let (label, amp) = match kind {
                model_core::analytic::ApproxKind::NormalEq21 => ("eq. 21", a),
                model_core::analytic::ApproxKind::TangentialEq24 => ("eq. 24", b),
            };
            out.push(self.point(
                label,
                Some(m),
                t,
                model_core::analytic::approx::MAX_ERROR_OVER_A * amp,
            ));
        }
    }

    /// The five fixed-step series of [`FIXED_METHODS`].
    fn fixed_points(&self, steps: &[u32], out: &mut Vec<Point>) {
        let (name, reference, v, v32) = (self.name, self.reference, self.v, self.v as f32);
        let [rest64, warm64, rest32, warm32, micro] = FIXED_METHODS;
        fixed_series::<f64, Libm>(out, name, (rest64, false), &self.d, v, reference, steps);
        fixed_series::<f64, Libm>(out, name, (warm64, true), &self.d, v, reference, steps);
        fixed_series::<f32, Libm>(out, name, (rest32, false), &self.d32, v32, reference, steps);
        fixed_series::<f32, Libm>(out, name, (warm32, true), &self.d32, v32, reference, steps);
        fixed_series::<f32, Micromath>(
            out,
            name,
            (micro, false),
            &self.d32m,
            v32,
            reference,
            steps,
        );
    }
}

/// All points for one scene (a, b, φ as [`SCENES`], `x` = v0/v_c): the exact
/// solver, the closed form where it applies, and the fixed-step series at
/// each of `steps`.
pub fn measure_scene(
    name: &'static str,
    a: f64,
    b: f64,
    phi: f64,
    x: f64,
    steps: &[u32],
) -> Result<Vec<Point>> {
    let setup = Setup::new(name, a, b, phi, x)?;
    let mut out = Vec::new();
    setup.exact_points(&mut out);
    setup.approx_point(a, b, &mut out);
    setup.fixed_points(steps, &mut out);
    Ok(out)
}

/// Least-squares slope of −log(error) against log(N), over points above the
/// rounding floor (1e-13 in f64, 1e-6 in f32); `None` with fewer than 4 such
/// points.
pub fn fitted_order(points: &[&Point]) -> Option<f64> {
    let floor = if points.first()?.method.contains("f32") {
        1e-6
    } else {
        1e-13
    };
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|p| match (p.steps, p.error) {
            (Some(n), Some(e)) if e > floor => Some((f64::from(n).ln(), e.ln())),
            _ => None,
        })
        .collect();
    if xy.len() < 4 {
        return None;
    }
    let m = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / m,
        xy.iter().map(|p| p.1).sum::<f64>() / m,
    );
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    Some(-sxy / sxx)
}

/// The fitted order of one series ([`fitted_order`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Order {
    /// Scene name.
    pub scene: &'static str,
    /// Method name.
    pub method: &'static str,
    /// The fitted order, `None` with too few points above the floor.
    pub order: Option<f64>,
}

/// The fitted order of `scene`'s `method` points in `all`.
fn order_of(all: &[Point], scene: &'static str, method: &'static str) -> Order {
    let pts: Vec<&Point> = all
        .iter()
        .filter(|p| p.scene == scene && p.method == method)
        .collect();
    Order {
        scene,
        method,
        order: fitted_order(&pts),
    }
}

/// The orders of every scene's [`FIXED_METHODS`] series, in
/// [`SCENES`] × [`FIXED_METHODS`] order.
pub fn scene_orders(all: &[Point]) -> Vec<Order> {
    SCENES
        .iter()
        .flat_map(|&(name, ..)| FIXED_METHODS.iter().map(move |&m| (name, m)))
        .map(|(name, m)| order_of(all, name, m))
        .collect()
}

/// The orders of the flat punch's [`ACROSS_METHODS`] series across lift-off,
/// only those with one (below `a = 1` only the fixed-step series has
/// points, from 1 only the lift-off stepping).
pub fn across_orders(all: &[Point]) -> Vec<Order> {
    across_lift_off::FLAT
        .iter()
        .flat_map(|&(name, _)| ACROSS_METHODS.iter().map(move |&m| (name, m)))
        .map(|(name, m)| order_of(all, name, m))
        .filter(|o| o.order.is_some())
        .collect()
}
