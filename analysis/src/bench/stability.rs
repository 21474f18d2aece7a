//! The stability bench: maps of where each method stops being
//! trustworthy, and how it says so (`fricctl bench stability` writes one CSV
//! and one PNG per map).
//!
//! Every cell is one computation at one point of a parameter plane. It either
//! returns a number — judged by its error `|Δμ|/μ0` against an independent
//! reference — or an explicit failure of a kind (too few steps, precision
//! limit, not converged, ill-conditioned, out of range, …). A cell whose
//! error exceeds the method's stated bound (plus the reference's own bound)
//! would be a silently wrong number ([`Outcome::exceeds`]); the CLI draws it
//! in red and counts it, and `tests/stability.rs` asserts there are none on
//! the same planes.
//!
//! The planes ([`planes`]): fixed-step (f64, f32) over velocity `v0/v_c → 0`
//! × steps per period; the exact solver over `Δu_z/u_z0 → 1` × `v0 → v_c`,
//! over the tangential amplitude `b` (huge and tiny) × `v0 → 0`, and over
//! extreme SI magnitudes (`u_z0` × `k_z` at `k_x` = 1 GPa/m); and
//! `select::mu_within` (auto) across lift-off, `Δu_z/u_z0` from 0.5 to 3 ×
//! `v0/v_c` (the permanent-contact solver below 1, the lift-off solver from
//! 1); and a sphere through the MDR quadrature over the same plane, against a
//! brute force over its springs ([`super::springs`]).

use model_core::exact::{self, ExactError};
use model_core::fixed_step::{self, FixedStepConfig, FixedStepError, Start};
use model_core::model::liftoff::{self, stepping};
use model_core::scene::ContactMode;
use model_core::select::{self, SelectError, Value};
use model_core::{Drive, Float, Groups, Libm, Scene, SceneError, SceneParams};
use rayon::prelude::*;

use super::springs;
use super::work_precision::warm_state;
use crate::grid::centres;

/// What one cell gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// A number with its error against the reference and the allowed error
    /// (the method's stated bound plus the reference's).
    Value {
        /// `|Δμ|/μ0` against the reference.
        error: f64,
        /// Stated bound + reference bound.
        allowed: f64,
    },
    /// An explicit failure of the method.
    Failure(&'static str),
    /// The reference could not be computed: the cell is not judged.
    NoReference,
}

impl Outcome {
    /// `true` for a number outside its stated bound (a silent failure).
    pub fn exceeds(&self) -> bool {
        matches!(*self, Outcome::Value { error, allowed } if error > allowed)
    }
}

/// One cell as the map's CSV has it (`outcome,error_over_mu0,allowed_over_mu0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// `ok`, `exceeds stated bound`, `no reference` or the failure's kind.
    pub outcome: &'static str,
    /// `|Δμ|/μ0` against the reference (NaN without a number).
    pub error_over_mu0: f64,
    /// The allowed error, units of μ0 (NaN without a number).
    pub allowed_over_mu0: f64,
}

impl Outcome {
    /// The cell's [`Record`].
    pub fn record(&self) -> Record {
        let (outcome, error_over_mu0, allowed_over_mu0) = match *self {
            Outcome::Value { error, allowed } if self.exceeds() => {
                ("exceeds stated bound", error, allowed)
            }
            Outcome::Value { error, allowed } => ("ok", error, allowed),
            Outcome::Failure(k) => (k, f64::NAN, f64::NAN),
            Outcome::NoReference => ("no reference", f64::NAN, f64::NAN),
        };
        Record {
            outcome,
            error_over_mu0,
            allowed_over_mu0,
        }
    }
}

fn fixed_failure<T>(e: &FixedStepError<T>) -> &'static str {
    match e {
        FixedStepError::TooFewSteps { .. } => "too few steps",
        FixedStepError::PrecisionLimit { .. } => "precision limit",
        FixedStepError::IllConditioned => "ill-conditioned",
        FixedStepError::NotConverged { .. } => "not converged",
        FixedStepError::BadVelocity(_) => "bad velocity",
        FixedStepError::ZeroVelocity => "zero velocity",
        FixedStepError::BadStart | FixedStepError::BadConfig | FixedStepError::BadDrive => {
            "refused input"
        }
    }
}

fn exact_failure(e: &ExactError) -> &'static str {
    match e {
        ExactError::IllConditioned => "ill-conditioned",
        ExactError::Inconsistent => "inconsistent",
        ExactError::BadVelocity(_) => "bad velocity",
        ExactError::BadDrive => "refused input",
    }
}

fn scene_failure(e: &SceneError) -> &'static str {
    match e {
        SceneError::OutOfRange(_) => "out of range",
        SceneError::NonFinite(_) => "not representable",
        SceneError::LiftOff => "lift-off",
        SceneError::NotPositive(_) => "underflows to 0",
        _ => "refused input",
    }
}

/// Fixed-step run from rest with a step budget.
fn fixed_run<T: Float>(
    d: &Drive<T>,
    v: T,
    n: u32,
    budget: u64,
    start: Start<T>,
) -> Result<(f64, f64), FixedStepError<T>> {
    let mut cfg = FixedStepConfig::<T>::new(n);
    cfg.max_periods = (budget / u64::from(n.max(1))).clamp(3, 10_000_000) as u32;
    let r = fixed_step::run_dimensionless::<T, Libm>(d, v, &cfg, start)?;
    Ok((r.mu_over_mu0.to_f64(), r.error_bound.to_f64()))
}

/// A reference for the exact f64 solver that shares none of its code: the
/// fixed-step scheme at N and 2N steps per period (warm-started; the steady
/// state is unique and is proven by the run itself), Richardson-extrapolated
/// for display and with the N = 2N run's stated bound for judging:
/// `(Richardson μ/μ0, μ/μ0 at 2N, its stated bound)`, `None` if a run fails.
pub fn fixed_reference(d: &Drive<f64>, v: f64, budget: u64) -> Option<(f64, f64, f64)> {
    let n = fixed_step::min_steps_per_period(d)
        .saturating_mul(32)
        .clamp(4096, fixed_step::max_steps_per_period::<f64>() / 2);
    let start = warm_state::<f64, Libm>(d, v).map_or(Start::Rest, Start::State);
    let (m1, _) = fixed_run(d, v, n, budget, start).ok()?;
    let (m2, b2) = fixed_run(d, v, 2 * n, budget, start).ok()?;
    Some((m2 + (m2 - m1) / 3.0, m2, b2))
}

/// The computation of one cell at (x, y), the axis values of its plane.
pub type CellFn = Box<dyn Fn(f64, f64) -> Outcome + Send + Sync>;

/// One map: a parameter plane and the computation of its cells.
pub struct Plane {
    /// File stem of the map's CSV and PNG.
    pub name: &'static str,
    /// Title of the map.
    pub title: String,
    /// Label of the x axis.
    pub x_label: &'static str,
    /// Label of the y axis.
    pub y_label: &'static str,
    /// Range of x (log10 of the quantity where `log_x`).
    pub x: (f64, f64),
    /// Range of y (log10 of the quantity where `log_y`).
    pub y: (f64, f64),
    /// Whether x is a log10.
    pub log_x: bool,
    /// Whether y is a log10.
    pub log_y: bool,
    /// The cell at (x, y).
    pub cell: CellFn,
}

impl Plane {
    /// The cell centres of each axis, `res` cells per axis.
    pub fn axes(&self, res: usize) -> (Vec<f64>, Vec<f64>) {
        (
            centres(self.x.0, self.x.1, res),
            centres(self.y.0, self.y.1, res),
        )
    }

    /// Every cell's outcome, row-major (rows of `ys`, columns of `xs`),
    /// computed in parallel; `tick` is called after each cell.
    pub fn outcomes(&self, xs: &[f64], ys: &[f64], tick: &(dyn Fn() + Sync)) -> Vec<Outcome> {
        let n = xs.len() * ys.len();
        (0..n)
            .into_par_iter()
            .map(|i| {
                let o = (self.cell)(xs[i % xs.len()], ys[i / xs.len()]);
                tick();
                o
            })
            .collect()
    }
}

/// The x label of the planes over the velocity.
const VLOG: &str = "v0/v_c";

/// Every map of the bench, in the order it runs them; `budget` is the step
/// budget of one fixed-step run (past it: not converged).
pub fn planes(budget: u64) -> Vec<Plane> {
    let mut all = Vec::new();
    all.extend(fixed_planes(budget));
    all.extend(lift_off_planes(budget));
    all.extend(across_planes(budget));
    all.push(mdr_plane());
    all.extend(ratio_planes(budget));
    all.extend(si_planes());
    all
}

/// Fixed-step from rest over `v0/v_c → 0` × N, f64 and f32 ([`fixed_cell`]).
fn fixed_planes(budget: u64) -> [Plane; 2] {
    let plane = |name, t: &str, cell| {
        Plane {
        name,
        title: format!(
            "Fixed-step from rest ({t}): Δu_z/u_z0 = 0.5, b = 0.25, φ = 1 rad (57.3°), budget {budget:e} steps"
        ),
        x_label: VLOG,
        y_label: "steps per period N",
        x: (-5.0, -0.0005),
        y: (0.6, 6.6),
        log_x: true,
        log_y: true,
        cell,
    }
    };
    [
        plane(
            "fixed_f64",
            "f64",
            Box::new(move |x, y| fixed_cell::<f64>(x, y, budget)),
        ),
        plane(
            "fixed_f32",
            "f32",
            Box::new(move |x, y| fixed_cell::<f32>(x, y, budget)),
        ),
    ]
}

/// The exact solver near lift-off and v_c, f64 and f32 ([`lift_off_cell`]).
fn lift_off_planes(budget: u64) -> [Plane; 2] {
    let plane = |name, t: &str, cell| Plane {
        name,
        title: format!("Exact solver ({t}) near lift-off and v_c: b = 0.3, φ = 2 rad (114.6°)"),
        x_label: "1 − Δu_z/u_z0",
        y_label: "1 − v0/v_c",
        x: (-12.0, 0.0),
        y: (-12.0, 0.0),
        log_x: true,
        log_y: true,
        cell,
    };
    [
        plane(
            "exact_lift_off_f64",
            "f64, against fixed-step N, 2N Richardson",
            Box::new(move |x, y| lift_off_cell::<f64>(x, y, budget)),
        ),
        plane(
            "exact_lift_off_f32",
            "f32, against f64",
            Box::new(move |x, y| lift_off_cell::<f32>(x, y, budget)),
        ),
    ]
}

/// Auto across lift-off, f64 and f32 ([`across_lift_off_cell`]).
fn across_planes(budget: u64) -> [Plane; 2] {
    let plane = |name, t: &str, cell| Plane {
        name,
        title: format!("Auto (select::mu_within, {t}) across lift-off: b = 0.6, φ = 1 rad (57.3°)"),
        x_label: "Δu_z/u_z0 (≥ 1: the contact lifts off)",
        y_label: "v0/v_c (v_c of the direction; the contact window's from 1)",
        x: (0.5, 3.0),
        y: (-1.1, 1.1),
        log_x: false,
        log_y: false,
        cell,
    };
    [
        plane(
            "across_lift_off_f64",
            "f64, against fixed-step",
            Box::new(move |x, y| across_lift_off_cell::<f64>(x, y, budget)),
        ),
        plane(
            "across_lift_off_f32",
            "f32, against f64",
            Box::new(move |x, y| across_lift_off_cell::<f32>(x, y, budget)),
        ),
    ]
}

/// The sphere through the MDR across lift-off ([`mdr_across_lift_off_cell`]).
fn mdr_plane() -> Plane {
    let (m, n) = MDR_REFERENCE;
    Plane {
        name: "mdr_sphere_across_lift_off",
        title: format!(
            "Sphere (MDR, f64, tol {MDR_TOL:e}) vs brute force ({} springs/segment, {n} steps/period): b = 0.6, φ = 1 rad",
            4 * m
        ),
        x_label: "Δu_z/d0 (≥ 1: every spring lifts off)",
        y_label: "v0/v_c (v_c of the direction; the contact window's from 1)",
        x: (0.5, 3.0),
        y: (-1.1, 1.1),
        log_x: false,
        log_y: false,
        cell: Box::new(mdr_across_lift_off_cell),
    }
}

/// The exact solver over b and `v0 → 0`, f64 and f32 ([`ratio_cell`]).
fn ratio_planes(budget: u64) -> [Plane; 2] {
    let plane = |name, t: &str, cell| Plane {
        name,
        title: format!("Exact solver ({t}) over b and v0 → 0: Δu_z/u_z0 = 0.5, φ = 1 rad (57.3°)"),
        x_label: "b = k_xΔu_x/(μ0k_z u_z0)",
        y_label: VLOG,
        x: (-6.0, 9.0),
        y: (-8.0, 0.0),
        log_x: true,
        log_y: true,
        cell,
    };
    [
        plane(
            "exact_ratio_f64",
            "f64, against fixed-step",
            Box::new(move |x, y| ratio_cell::<f64>(x, y, budget)),
        ),
        plane(
            "exact_ratio_f32",
            "f32, against f64",
            Box::new(move |x, y| ratio_cell::<f32>(x, y, budget)),
        ),
    ]
}

/// SI magnitudes, f64 over ±340 decades and f32 over ±50 ([`si_cell`]).
fn si_planes() -> [Plane; 2] {
    let plane = |name, t: &str, r: f64, cell| Plane {
        name,
        title: format!(
            "SI magnitudes ({t}): k_x = 1e9 N/m, Δu_z/u_z0 = 0.4, b = 0.3, φ = 1 rad, v0 = 0.3 v_c"
        ),
        x_label: "u_z0, m",
        y_label: "k_z, N/m",
        x: (-r, r),
        y: (-r, r),
        log_x: true,
        log_y: true,
        cell,
    };
    [
        plane("si_f64", "f64", 340.0, Box::new(si_cell::<f64>)),
        plane("si_f32", "f32", 50.0, Box::new(si_cell::<f32>)),
    ]
}

/// The drive of the fixed-step and ratio planes.
const A: f64 = 0.5;

/// Cell of the fixed-step plane: x = log10(v0/v_c), y = log10 N.
pub fn fixed_cell<T: Float>(x: f64, y: f64, budget: u64) -> Outcome {
    let d64 = Drive::new::<Libm>(A, 0.25, 1.0);
    let v = 10f64.powf(x) * d64.c_forward::<Libm>();
    let n = 10f64.powf(y).round() as u32;
    let Ok(reference) = exact::mu_over_mu0::<f64, Libm>(&d64, v) else {
        return Outcome::NoReference;
    };
    let d = Drive::new::<Libm>(T::from_f64(A), T::from_f64(0.25), T::ONE);
    match fixed_run::<T>(&d, T::from_f64(v), n, budget, Start::Rest) {
        Ok((m, b)) => Outcome::Value {
            error: (m - reference).abs(),
            allowed: b + exact::error_bound::<f64, Libm>(&d64),
        },
        Err(e) => Outcome::Failure(fixed_failure(&e)),
    }
}

/// Cell of the lift-off plane: x = log10(1 − a), y = log10(1 − v0/v_c), b = 0.3, φ = 2.
pub fn lift_off_cell<T: Float>(x: f64, y: f64, budget: u64) -> Outcome {
    let a = 1.0 - 10f64.powf(x);
    let d64 = Drive::new::<Libm>(a, 0.3, 2.0);
    let v = (1.0 - 10f64.powf(y)) * d64.c_forward::<Libm>();
    exact_cell::<T>(&d64, v, budget)
}

/// Cell of the plane across lift-off: x = Δu_z/u_z0 (0.5 … 3), y = v0/v_c of
/// the direction of motion (eq. 8 below a = 1, the contact window's eq. L5
/// from 1), b = 0.6, φ = 1; `select::mu_within` in `T` at the bound of the
/// solver it uses. f32 is judged against f64; f64 against the fixed-step
/// scheme (below 1: N, 2N from a warm start as [`fixed_reference`]; from 1:
/// the lift-off stepping from the exact landing at N = 2¹⁵ with its stated
/// order-2 bound), code shared with neither solver.
pub fn across_lift_off_cell<T: Float>(x: f64, y: f64, budget: u64) -> Outcome {
    let (a, b, phi) = (x, 0.6, 1.0);
    let d64 = Drive::new::<Libm>(a, b, phi);
    let (cf, cb) = if a < 1.0 {
        (d64.c_forward::<Libm>(), d64.c_backward::<Libm>())
    } else {
        match liftoff::critical_velocities::<f64, Libm>(&d64) {
            Ok(c) => c,
            Err(_) => return Outcome::NoReference,
        }
    };
    let v = if y >= 0.0 { y * cf } else { y * cb };
    let (got, bound) = match auto_within::<T>(a, b, phi, v) {
        Ok(answer) => answer,
        Err(o) => return o,
    };
    if T::EPSILON.to_f64() > 1e-10 {
        return against_auto_f64((a, b, phi), &d64, v, got, bound);
    }
    if a >= 1.0 {
        return match stepping::mu_over_mu0::<f64, Libm>(&d64, v, 1 << 15) {
            Ok(r) => Outcome::Value {
                error: (got - r.mu_over_mu0).abs(),
                allowed: bound + r.error_bound,
            },
            Err(_) => Outcome::NoReference,
        };
    }
    if got.abs() == 1.0 {
        // Continuous sliding beyond v_c: exact (bound 0); the fixed-step
        // reference from rest would only slide too.
        return Outcome::Value {
            error: 0.0,
            allowed: 0.0,
        };
    }
    against_fixed_step(got, bound, &d64, v, budget)
}

/// `select::mu_within` in `T` for the intermittent-contact scene (a, b, φ)
/// at `v` and the bound of the solver it uses: `(μ/μ0, bound)`, or the
/// cell's outcome when there is no number.
fn auto_within<T: Float>(a: f64, b: f64, phi: f64, v: f64) -> Result<(f64, f64), Outcome> {
    let s = Scene::dimensionless_with_contact(
        Groups {
            duz_rel: T::from_f64(a),
            dux_rel: T::from_f64(b),
            phi: T::from_f64(phi),
        },
        ContactMode::Intermittent,
    )
    .map_err(|e| Outcome::Failure(scene_failure(&e)))?;
    let d = s.drive();
    let tol = if s.lifts_off() {
        liftoff::error_bound::<T, Libm>(&d)
    } else {
        exact::error_bound::<T, Libm>(&d)
    };
    match select::mu_within::<T, Libm>(&s, T::from_f64(v), tol) {
        Ok(select::Answer {
            value: Value::Mu(m),
            bound,
            ..
        }) => Ok((m.to_f64(), bound.to_f64())),
        Ok(_) => Err(Outcome::NoReference),
        Err(SelectError::Exact(e)) => Err(Outcome::Failure(exact_failure(&e))),
        Err(SelectError::ToleranceTooTight { .. }) => Err(Outcome::Failure("ill-conditioned")),
        Err(_) => Err(Outcome::Failure("refused input")),
    }
}

/// An f32 answer `got` (within `bound`) judged against the f64 answer of
/// `select::mu_within` for the scene `(a, b, φ)` (drive `d64`) and its bound.
fn against_auto_f64(
    (a, b, phi): (f64, f64, f64),
    d64: &Drive<f64>,
    v: f64,
    got: f64,
    bound: f64,
) -> Outcome {
    let tol64 = if a >= 1.0 {
        liftoff::error_bound::<f64, Libm>(d64)
    } else {
        exact::error_bound::<f64, Libm>(d64)
    };
    let Ok(s64) = Scene::dimensionless_with_contact(
        Groups {
            duz_rel: a,
            dux_rel: b,
            phi,
        },
        ContactMode::Intermittent,
    ) else {
        return Outcome::NoReference;
    };
    match select::mu_within::<f64, Libm>(&s64, v, tol64) {
        Ok(select::Answer {
            value: Value::Mu(r),
            bound: rb,
            ..
        }) => Outcome::Value {
            error: (got - r).abs(),
            allowed: bound + rb,
        },
        _ => Outcome::NoReference,
    }
}

/// An f64 answer `got` (within `bound`) judged against [`fixed_reference`]:
/// outside the N = 2N run's bound plus its own it is judged by that
/// distance; otherwise its distance to the Richardson value is shown, not
/// judged.
fn against_fixed_step(got: f64, bound: f64, d64: &Drive<f64>, v: f64, budget: u64) -> Outcome {
    match fixed_reference(d64, v, budget) {
        Some((rich, m2, b2)) => {
            if (got - m2).abs() > bound + b2 {
                Outcome::Value {
                    error: (got - m2).abs(),
                    allowed: bound + b2,
                }
            } else {
                Outcome::Value {
                    error: (got - rich).abs(),
                    allowed: f64::INFINITY,
                }
            }
        }
        None => Outcome::NoReference,
    }
}

/// The tolerance asked of the MDR in the curved-profile plane.
pub const MDR_TOL: f64 = 1e-9;

/// Springs per segment and steps per period of the brute-force reference
/// of the curved-profile plane ([`springs::mu_with_error`] at `M`, `2M`, `4M`
/// springs and `N`, `2N` steps).
pub const MDR_REFERENCE: (u32, u32) = (48, 1024);

/// Cell of the curved-profile plane across lift-off: a sphere through the
/// MDR, x = Δu_z/u_z0 = a (read as Δu_z/d₀, 0.5 … 3: only the rim lifts off
/// below 1, every spring from 1), y = v0/v_c of the direction of motion (the
/// flat punch's, eq. 8 below 1 and the contact window's eq. L5 from 1, which
/// the profile shares), b = 0.6, φ = 1 rad; `select::mu_within_profile` at
/// [`MDR_TOL`] (or twice the per-spring part of the bound where larger).
/// Judged against the brute force over springs ([`springs`], code shared
/// with neither the quadrature nor the per-spring solvers) with its own
/// error estimate: `allowed = MDR bound + reference allowance`.
pub fn mdr_across_lift_off_cell(x: f64, y: f64) -> Outcome {
    use model_core::mdr::{self, Profile};
    let (a, b, phi) = (x, 0.6, 1.0);
    let d = Drive::new::<Libm>(a, b, phi);
    let Ok((cf, cb)) = mdr::critical_velocities::<f64, Libm>(&d, &Profile::Sphere) else {
        return Outcome::NoReference;
    };
    let v = if y >= 0.0 { y * cf } else { y * cb };
    let s = match Scene::dimensionless_with_contact(
        Groups {
            duz_rel: a,
            dux_rel: b,
            phi,
        },
        ContactMode::Intermittent,
    ) {
        Ok(s) => s,
        Err(e) => return Outcome::Failure(scene_failure(&e)),
    };
    let tol = MDR_TOL.max(2.0 * mdr::solver_bound::<f64, Libm>(&s.drive(), 2.0));
    let (got, bound) = match select::mu_within_profile::<f64, Libm>(&s, &Profile::Sphere, v, tol) {
        Ok(select::Answer {
            value: Value::Mu(m),
            bound,
            ..
        }) => (m, bound),
        Ok(_) => return Outcome::NoReference,
        Err(SelectError::Mdr(e)) => return Outcome::Failure(mdr_failure(&e)),
        Err(SelectError::Exact(e)) => return Outcome::Failure(exact_failure(&e)),
        Err(SelectError::ToleranceTooTight { .. }) => return Outcome::Failure("ill-conditioned"),
        Err(SelectError::BadTolerance) => return Outcome::Failure("refused input"),
    };
    let (m, n) = MDR_REFERENCE;
    let (reference, allowance) = springs::mu_with_error(2.0, a, b, phi, v, m, n);
    if !reference.is_finite() {
        return Outcome::NoReference;
    }
    Outcome::Value {
        error: (got - reference).abs(),
        allowed: bound + allowance,
    }
}

fn mdr_failure(e: &model_core::mdr::MdrError) -> &'static str {
    use model_core::mdr::MdrError;
    match e {
        MdrError::NotConverged { .. } => "not converged",
        MdrError::IllConditioned | MdrError::ToleranceTooTight { .. } => "ill-conditioned",
        MdrError::Inconsistent => "inconsistent",
        _ => "refused input",
    }
}

/// Cell of the ratio plane: x = log10 b, y = log10(v0/v_c), a = 0.5, φ = 1.
pub fn ratio_cell<T: Float>(x: f64, y: f64, budget: u64) -> Outcome {
    let d64 = Drive::new::<Libm>(A, 10f64.powf(x), 1.0);
    let v = 10f64.powf(y) * d64.c_forward::<Libm>();
    exact_cell::<T>(&d64, v, budget)
}

/// The exact solver in `T` at a drive and velocity given in f64; f32 is
/// judged against the exact f64 solver, f64 against [`fixed_reference`].
fn exact_cell<T: Float>(d64: &Drive<f64>, v: f64, budget: u64) -> Outcome {
    // The scene is built in T from the groups, as a user of T would: its
    // validation sees what rounding to T does (a may round to 1: lift-off).
    let s = match Scene::dimensionless(Groups {
        duz_rel: T::from_f64(d64.a),
        dux_rel: T::from_f64(d64.b),
        phi: T::from_f64(d64.bs.atan2(d64.bc)),
    }) {
        Ok(s) => s,
        Err(e) => return Outcome::Failure(scene_failure(&e)),
    };
    let d = s.drive();
    let got = match exact::mu_over_mu0::<T, Libm>(&d, T::from_f64(v)) {
        Ok(m) => m.to_f64(),
        Err(e) => return Outcome::Failure(exact_failure(&e)),
    };
    let bound = exact::error_bound::<T, Libm>(&d).to_f64();
    if T::EPSILON.to_f64() > 1e-10 {
        // f32: the f64 solver is the reference. The rounding of the inputs to
        // f32 moves the answer too; it is part of the f32 bound's measurement.
        match exact::mu_over_mu0::<f64, Libm>(d64, v) {
            Ok(r) => Outcome::Value {
                error: (got - r).abs(),
                allowed: bound + exact::error_bound::<f64, Libm>(d64),
            },
            Err(_) => Outcome::NoReference,
        }
    } else {
        against_fixed_step(got, bound, d64, v, budget)
    }
}

/// Cell of the SI plane: x = log10 u_z0 (m), y = log10 k_z (N/m), k_x = 1e9 N/m,
/// μ0 = 0.3, ω = 2π·40 kHz, Δu_z = 0.4 u_z0, Δu_x = 0.3 W0, φ = 1, v0 = 0.3 v_c.
/// μ/μ0 is the same in every cell (the groups are fixed); the reference is the
/// dimensionless f64 scene.
pub fn si_cell<T: Float>(x: f64, y: f64) -> Outcome {
    let g = Groups {
        duz_rel: 0.4,
        dux_rel: 0.3,
        phi: 1.0,
    };
    let Ok(reference_scene) = Scene::dimensionless(g) else {
        return Outcome::NoReference;
    };
    let d64 = reference_scene.drive();
    let Ok(reference) = exact::mu_over_mu0::<f64, Libm>(&d64, 0.3 * d64.c_forward::<Libm>()) else {
        return Outcome::NoReference;
    };
    let (uz0, kz, kx, mu0) = (10f64.powf(x), 10f64.powf(y), 1e9, 0.3);
    let w0 = mu0 * (kz / kx) * uz0;
    let p = SceneParams {
        mu0: T::from_f64(mu0),
        kz: T::from_f64(kz),
        kx: T::from_f64(kx),
        uz0: T::from_f64(uz0),
        duz: T::from_f64(0.4 * uz0),
        dux: T::from_f64(0.3 * w0),
        omega: T::from_f64(std::f64::consts::TAU * 40e3),
        phi: T::ONE,
    };
    let s = match Scene::new(p) {
        Ok(s) => s,
        Err(e) => return Outcome::Failure(scene_failure(&e)),
    };
    let vc = model_core::analytic::CriticalVelocity::of(&s).forward;
    match exact::solve(&s, T::from_f64(0.3) * vc) {
        Ok(sol) => match sol.mu_over_mu0() {
            Some(m) => Outcome::Value {
                error: (m.to_f64() - reference).abs(),
                allowed: exact::error_bound::<T, Libm>(&s.drive()).to_f64()
                    + exact::error_bound::<f64, Libm>(&d64),
            },
            None => Outcome::Failure("bad velocity"),
        },
        Err(e) => Outcome::Failure(exact_failure(&e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The curved-profile plane on a coarse grid (12 × 12 cells over the
    /// same ranges): every cell a number within the MDR's bound plus the
    /// brute force's allowance (the map's criterion), none outside.
    #[test]
    fn mdr_plane_has_no_cell_outside_its_bound() {
        let xs = centres(0.5, 3.0, 12);
        let ys = centres(-1.1, 1.1, 12);
        let mut worst: f64 = 0.0;
        for &x in &xs {
            for &y in &ys {
                match mdr_across_lift_off_cell(x, y) {
                    Outcome::Value { error, allowed } => {
                        worst = worst.max(error / allowed.max(1e-300));
                        assert!(error <= allowed, "a={x} v/vc={y}: {error:e} > {allowed:e}");
                    }
                    o => panic!("a={x} v/vc={y}: {o:?}"),
                }
            }
        }
        println!("worst error/allowed {worst:.3}");
    }
}
