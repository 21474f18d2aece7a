//! The paper's explicit fixed-step scheme (§3), with proven steady-state
//! detection.
//!
//! Per step of `δ = 2π/N` (in the dimensionless variables of [`crate::model::scene`]):
//! advance the drive phase, add the drive increment to the spring stretch
//! (stick trial), clamp the stretch to the friction band `[−w, w]` (the contact
//! point is moved so that `|f_x| = μ₀f_z`), and accumulate `f_x` and `f_z`;
//! `μ = ⟨f_x⟩/⟨f_z⟩` over a period (eq. 20). Forces are kept in units of
//! `k_xW₀ = μ₀k_z u_z0`, which changes the arithmetic only by a constant factor
//! and keeps µm/GPa-scale inputs in range for `f32`.
//!
//! **No transcendental functions per step**: `(cos θ, sin θ)` advance by a
//! rotation recurrence and are reset to their exact start values at every
//! period boundary, so the phase stays wrapped and the rounding error cannot
//! grow beyond one period's worth (≈ N·ε) however long the run.
//!
//! **Steady state.** The discrete scheme forgets its history in the forward
//! (for `V > 0`) slip window: once the stretch is clamped to `+w` inside the
//! window it stays clamped until the window ends, whatever came before. So a
//! period that starts after a completed window with a forward clamp is exactly
//! the periodic state; that is guaranteed two periods after the first period
//! with a forward clamp. The run reports convergence only then, and only if
//! additionally `|μ_k − μ_{k−1}| ≤ tol·μ₀`. A bare tolerance test would be
//! unsafe: at low velocity the transient drifts by ≈ 2πV per period, which can
//! be below any tolerance while far from the answer. `V < 0` uses backward clamps.
//! `V = 0` has no unique steady state and is refused.

use crate::model::float::{Float, Libm, Math};
use crate::model::scene::{Drive, Scene, SceneError};

/// Settings of a fixed-step run.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedStepConfig<T> {
    /// Steps per drive period `N` (the paper uses ~10⁴); accepted from
    /// [`min_steps_per_period`] (10 for `b = 0`) to [`max_steps_per_period`].
    pub steps_per_period: u32,
    /// Consistency tolerance on `|μ_k − μ_{k−1}|/μ₀` between the last two periods (> 0).
    pub tol: T,
    /// Give up after this many periods (≥ 3).
    pub max_periods: u32,
}

impl<T: Float> FixedStepConfig<T> {
    /// `N` steps per period, tolerance 1e-9 (f64) / 1e-5 (f32), 1 000 000 periods.
    pub fn new(steps_per_period: u32) -> Self {
        let tol = if T::EPSILON < T::from_f64(1e-10) {
            1e-9
        } else {
            1e-5
        };
        FixedStepConfig {
            steps_per_period,
            tol: T::from_f64(tol),
            max_periods: 1_000_000,
        }
    }
}

/// Where a run starts.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Start<T> {
    /// The paper's start: t = 0 (θ = 0) with the contact point at the origin,
    /// i.e. stretch `s = Δu_x cos φ`, clamped to the band if it exceeds it.
    Rest,
    /// A given state.
    State(State<T>),
}

/// A state of the integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct State<T> {
    /// Drive phase θ = ωt, rad (any finite value; the grid is `θ + kδ`).
    pub phase: T,
    /// Spring stretch `s = u_x − u_x,c` in units of W₀ (|s| ≤ w(θ)).
    pub stretch: T,
}

/// A converged fixed-step result.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedStepOutcome<T> {
    /// `μ/μ₀` of the last (steady) period (eq. 20).
    pub mu_over_mu0: T,
    /// Periods integrated.
    pub periods: u32,
    /// Steps integrated (`periods · N`).
    pub steps: u64,
    /// The state at the end of the run (one period after the start phase, wrapped).
    pub end: State<T>,
    /// The stated error bound of `mu_over_mu0`, in units of μ₀ ([`error_bound`]).
    pub error_bound: T,
}

/// Measured-bound constant of the discretisation error: `|μ_N − μ|/μ₀ ≤
/// K_D·(1 + b)/N²` with `K_D` = 10, calibrated by self-convergence of this
/// scheme alone (no other solver): the run at N against the same scheme at
/// 2¹⁸ steps per period, whose own error the constant bounds too
/// (`tests/tests/fixed_step_bound.rs`). Measured worst 4.75 over 1 064
/// scenes (the eight work-precision scenes, 56 scene–velocity pairs and
/// 1 000 random scenes with `a` up to `1 − 10⁻⁶`, `b` from 10⁻⁴ to 300 and
/// `|v₀|/v_c` from 10⁻³ to `1 − 10⁻⁶`, N from [`min_steps_per_period`] to
/// 4 096; 4.82 over 3 000 random scenes); the scheme is second order. The
/// comparisons with the exact solver within this bound (`tests/exact_vs_fixed.rs`,
/// the property tests in `tests/stability.rs`) are therefore independent checks.
pub const DISCRETISATION_K: f64 = 10.0;

/// Rounding constant: the rounding error of one period's stretch increments
/// is at most `K_R·N·ε·(1 + b)` with `K_R` = 1 (measured worst 0.18: the
/// scheme in f32 against the same scheme in f64 at the same N, N from
/// [`min_steps_per_period`] to the f32 limit, `tests/tests/fixed_step_bound.rs`).
pub const ROUNDING_K: f64 = 1.0;

/// Largest discretisation part of the bound a run may have (10 % of μ₀):
/// below it the steps cannot resolve the stick windows and the run is refused
/// ([`FixedStepError::TooFewSteps`]).
pub const MAX_DISCRETISATION: f64 = 0.1;

/// Largest achievable bound at which the type still counts as able to
/// resolve the drive (1 % of μ₀); beyond it [`FixedStepError::IllConditioned`].
pub const ILL_CONDITIONED_AT: f64 = 1e-2;

/// The stated error bound of a converged run with `n` steps per period, in
/// units of μ₀ (for a start from rest or from any state):
/// `(1 + b)·(K_D/N² + K_R·N·ε + M::MAX_REL_ERROR)` — discretisation
/// ([`DISCRETISATION_K`]), rounding of the stretch increments
/// ([`ROUNDING_K`]) and the math backend's set-up error.
pub fn error_bound<T: Float, M: Math<T>>(d: &Drive<T>, n: u32) -> T {
    let nn = T::from_u32(n.max(1));
    (T::ONE + d.b)
        * (T::from_f64(DISCRETISATION_K) / (nn * nn)
            + T::from_f64(ROUNDING_K) * nn * T::EPSILON
            + T::from_f64(M::MAX_REL_ERROR))
}

/// The fewest steps per period whose discretisation bound is within
/// [`MAX_DISCRETISATION`]: `⌈√(K_D(1 + b)/0.1)⌉` (10 for `b = 0`).
pub fn min_steps_per_period<T: Float>(d: &Drive<T>) -> u32 {
    let n = libm::ceil(libm::sqrt(
        DISCRETISATION_K * (1.0 + d.b.to_f64()) / MAX_DISCRETISATION,
    ));
    if n < 4.0 {
        4
    } else if n > u32::MAX as f64 {
        u32::MAX
    } else {
        n as u32
    }
}

/// The steps per period where the bound is smallest,
/// `N* = (2K_D/(K_R ε))^{1/3}` (552 for f32, 4.5·10⁵ for f64).
pub fn optimal_steps_per_period<T: Float>() -> u32 {
    libm::cbrt(2.0 * DISCRETISATION_K / (ROUNDING_K * T::EPSILON.to_f64())) as u32
}

/// The most steps per period a run accepts, `4·N*` (2 208 for f32, 1.8·10⁶
/// for f64): beyond it the rounding error grows faster than the
/// discretisation error shrinks, so more steps only make the answer worse
/// (measured: the f32 error grows with N beyond ≈ 500) and the run is
/// refused with [`FixedStepError::PrecisionLimit`].
pub fn max_steps_per_period<T: Float>() -> u32 {
    optimal_steps_per_period::<T>().saturating_mul(4)
}

/// Why a fixed-step run gave no converged number.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FixedStepError<T> {
    /// Too few steps per period for this drive: the discretisation bound
    /// exceeds [`MAX_DISCRETISATION`] (the steps cannot resolve the stick windows).
    TooFewSteps {
        /// The fewest steps the drive needs ([`min_steps_per_period`]).
        min_steps: u32,
    },
    /// More steps per period than the float type can use: past
    /// [`max_steps_per_period`] rounding dominates and grows with N.
    PrecisionLimit {
        /// The most steps accepted.
        max_steps: u32,
    },
    /// The float type cannot resolve this drive at any step count: the
    /// smallest achievable bound exceeds [`ILL_CONDITIONED_AT`] (f32 with
    /// `b ≳ 100`, f64 with `b ≳ 6·10⁷`).
    IllConditioned,
    /// `tol` not finite and > 0, or `max_periods < 3`.
    BadConfig,
    /// The velocity is NaN, infinite or out of range.
    BadVelocity(SceneError),
    /// `v₀ = 0`: the steady state depends on the initial state; use the static analysis.
    ZeroVelocity,
    /// The start state is not finite or outside the friction band.
    BadStart,
    /// A hand-built drive that no validated scene produces (`Drive::is_valid`).
    BadDrive,
    /// The period limit was reached before a provably steady period.
    NotConverged {
        /// Periods integrated.
        periods: u32,
        /// `μ/μ₀` of the last period — *not* a steady-state value.
        last_mu_over_mu0: T,
        /// `|μ_k − μ_{k−1}|/μ₀` of the last two periods.
        last_change: T,
    },
}

impl<T: Float> core::fmt::Display for FixedStepError<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FixedStepError::TooFewSteps { min_steps } => {
                write!(
                    f,
                    "too few steps per period for this drive (at least {min_steps})"
                )
            }
            FixedStepError::PrecisionLimit { max_steps } => write!(
                f,
                "more steps per period than the float type can use (at most {max_steps})"
            ),
            FixedStepError::IllConditioned => f.write_str(
                "ill-conditioned: the float type cannot resolve this drive at any step count",
            ),
            FixedStepError::BadConfig => f.write_str(
                "bad configuration (tolerance not finite and > 0, or fewer than 3 periods)",
            ),
            FixedStepError::BadVelocity(e) => write!(f, "bad velocity: {e}"),
            FixedStepError::ZeroVelocity => {
                f.write_str("v0 = 0 has no unique steady state (use the static analysis)")
            }
            FixedStepError::BadStart => {
                f.write_str("start state not finite or outside the friction band")
            }
            FixedStepError::BadDrive => f.write_str("invalid drive"),
            FixedStepError::NotConverged {
                periods,
                last_mu_over_mu0,
                ..
            } => write!(
                f,
                "no steady state after {periods} periods (last period's μ/μ0 = {}, not a result)",
                last_mu_over_mu0.to_f64()
            ),
        }
    }
}

impl<T: Float> core::error::Error for FixedStepError<T> {}

/// Runs the scheme for `scene` at sliding velocity `v0` (m/s).
///
/// # Errors
/// See [`FixedStepError`]; an unconverged run is an error carrying its last value.
pub fn run<T: Float>(
    scene: &Scene<T>,
    v0: T,
    cfg: &FixedStepConfig<T>,
    start: Start<T>,
) -> Result<FixedStepOutcome<T>, FixedStepError<T>> {
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(FixedStepError::BadVelocity)?;
    run_dimensionless::<T, Libm>(&scene.drive(), v, cfg, start)
}

/// The scheme in dimensionless form (`V = v₀/(ωW₀)`), with a chosen math
/// backend for the per-run set-up (`cos δ`, `sin δ`, start phase).
///
/// # Errors
/// See [`FixedStepError`].
pub fn run_dimensionless<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
    cfg: &FixedStepConfig<T>,
    start: Start<T>,
) -> Result<FixedStepOutcome<T>, FixedStepError<T>> {
    if !d.is_valid() {
        return Err(FixedStepError::BadDrive);
    }
    let n = cfg.steps_per_period;
    let best = optimal_steps_per_period::<T>();
    if error_bound::<T, Libm>(d, best) > T::from_f64(ILL_CONDITIONED_AT) {
        return Err(FixedStepError::IllConditioned);
    }
    let min_steps = min_steps_per_period(d);
    if n < min_steps {
        return Err(FixedStepError::TooFewSteps { min_steps });
    }
    let max_steps = max_steps_per_period::<T>();
    if n > max_steps {
        return Err(FixedStepError::PrecisionLimit { max_steps });
    }
    if !(cfg.tol.is_finite() && cfg.tol > T::ZERO) || cfg.max_periods < 3 {
        return Err(FixedStepError::BadConfig);
    }
    if !v.is_finite() {
        return Err(FixedStepError::BadVelocity(SceneError::NonFinite(
            crate::model::scene::Param::Velocity,
        )));
    }
    if v == T::ZERO {
        return Err(FixedStepError::ZeroVelocity);
    }
    let delta = T::TAU / T::from_u32(n);
    let (sd, cd) = M::sin_cos(delta);
    let (phase0, mut s) = match start {
        Start::Rest => {
            let w = T::ONE - d.a;
            (T::ZERO, d.bc.max(-w).min(w))
        }
        Start::State(st) => {
            if !(st.phase.is_finite() && st.stretch.is_finite()) {
                return Err(FixedStepError::BadStart);
            }
            let (_, c) = M::sin_cos(st.phase);
            let w = T::ONE - d.a * c;
            if st.stretch.abs() > w {
                return Err(FixedStepError::BadStart);
            }
            (st.phase, st.stretch)
        }
    };
    let (s0, c0) = M::sin_cos(phase0);
    let (a, bc, bs) = (d.a, d.bc, d.bs);
    let vd = v * delta;
    let forward = v > T::ZERO;

    let mut prev_mu = T::ZERO;
    let mut last_change = T::MAX;
    // Index of the first period with a clamp in the direction of motion.
    let mut first_clamp: Option<u32> = None;
    for period in 1..=cfg.max_periods {
        let (mut cth, mut sth) = (c0, s0);
        let mut x_prev = bc * cth - bs * sth;
        let mut sum_s = T::ZERO;
        let mut sum_w = T::ZERO;
        let mut clamp_fwd = false;
        let mut clamp_bwd = false;
        // One step to (c, s) = (cos θ', sin θ').
        let mut step = |c_new: T, s_new: T, s: &mut T, acc_s: &mut T, acc_w: &mut T| {
            let x_new = bc * c_new - bs * s_new;
            let w_new = T::ONE - a * c_new;
            let mut st = *s + vd + (x_new - x_prev);
            if st > w_new {
                st = w_new;
                clamp_fwd = true;
            } else if st < -w_new {
                st = -w_new;
                clamp_bwd = true;
            }
            *s = st;
            x_prev = x_new;
            *acc_s += st;
            *acc_w += w_new;
        };
        // N − 1 rotated steps in blocks (pairwise-style summation), then the
        // last step lands exactly on the start phase.
        let mut remaining = n - 1;
        while remaining > 0 {
            let m = remaining.min(256);
            let (mut acc_s, mut acc_w) = (T::ZERO, T::ZERO);
            for _ in 0..m {
                let c_new = cth * cd - sth * sd;
                let s_new = sth * cd + cth * sd;
                cth = c_new;
                sth = s_new;
                step(c_new, s_new, &mut s, &mut acc_s, &mut acc_w);
            }
            sum_s += acc_s;
            sum_w += acc_w;
            remaining -= m;
        }
        let (mut acc_s, mut acc_w) = (T::ZERO, T::ZERO);
        step(c0, s0, &mut s, &mut acc_s, &mut acc_w);
        sum_s += acc_s;
        sum_w += acc_w;

        let mu = sum_s / sum_w;
        if period > 1 {
            last_change = (mu - prev_mu).abs();
        }
        prev_mu = mu;
        let clamped = if forward { clamp_fwd } else { clamp_bwd };
        if clamped && first_clamp.is_none() {
            first_clamp = Some(period);
        }
        let proven = matches!(first_clamp, Some(p) if period >= p + 2);
        if proven && last_change <= cfg.tol {
            return Ok(FixedStepOutcome {
                mu_over_mu0: mu,
                periods: period,
                steps: u64::from(period) * u64::from(n),
                end: State {
                    phase: phase0,
                    stretch: s,
                },
                error_bound: error_bound::<T, M>(d, n),
            });
        }
    }
    Err(FixedStepError::NotConverged {
        periods: cfg.max_periods,
        last_mu_over_mu0: prev_mu,
        last_change,
    })
}

/// A single-step integrator of the same scheme with an arbitrary phase step
/// `δ` (not necessarily `2π/N`): the plant of a simulated device, sampled at
/// an ADC rate that is not a multiple of the drive frequency.
///
/// `(cos θ, sin θ)` advance by rotation; every 1024 steps the pair is
/// renormalised to unit length (one Newton step for `1/√r²`), so the phase
/// stays wrapped and the amplitude error bounded however long it runs.
#[derive(Debug, Clone, Copy)]
pub struct Stepper<T> {
    d: Drive<T>,
    vd: T,
    cd: T,
    sd: T,
    c: T,
    s: T,
    x: T,
    stretch: T,
    count: u32,
}

impl<T: Float> Stepper<T> {
    /// A stepper at phase `θ0` with stretch `s0` (clamped into the band),
    /// dimensionless velocity `v` and phase step `delta` (rad).
    pub fn new<M: Math<T>>(d: Drive<T>, v: T, theta0: T, s0: T, delta: T) -> Self {
        let (sd, cd) = M::sin_cos(delta);
        let (s, c) = M::sin_cos(theta0);
        let w = T::ONE - d.a * c;
        Stepper {
            d,
            vd: v * delta,
            cd,
            sd,
            c,
            s,
            x: d.bc * c - d.bs * s,
            stretch: s0.max(-w).min(w),
            count: 0,
        }
    }

    /// Advances one step; returns `(cos θ, s, w)` after it: the normal force is
    /// `k_z u_z0 · w` and the tangential force `k_x W₀ · s` (`w = 1 − a cos θ`).
    #[inline]
    pub fn step(&mut self) -> (T, T, T) {
        let c = self.c * self.cd - self.s * self.sd;
        let s = self.s * self.cd + self.c * self.sd;
        let (c, s) = if self.count == 1023 {
            self.count = 0;
            let r2 = c * c + s * s;
            let k = (T::from_f64(3.0) - r2) * T::HALF;
            (c * k, s * k)
        } else {
            self.count += 1;
            (c, s)
        };
        self.c = c;
        self.s = s;
        let x = self.d.bc * c - self.d.bs * s;
        let w = T::ONE - self.d.a * c;
        let st = self.stretch + self.vd + (x - self.x);
        self.stretch = st.max(-w).min(w);
        self.x = x;
        (c, self.stretch, w)
    }
}

/// The single-spring contact of §2 in physical units for an arbitrary drive:
/// each call is one step of the paper's scheme (stick trial, clamp of the
/// contact point to the friction band), with the displacements of the upper
/// spring point given directly. This is the plant of the virtual device,
/// whose drive comes from the DDS's current (possibly ramping) levels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringContact<T> {
    /// μ₀.
    pub mu0: T,
    /// k_z, N/m.
    pub kz: T,
    /// k_x, N/m.
    pub kx: T,
    /// Contact point u_x,c, m.
    pub uxc: T,
}

impl<T: Float> SpringContact<T> {
    /// A contact at `u_x,c = 0`.
    pub fn new(mu0: T, kz: T, kx: T) -> Self {
        SpringContact {
            mu0,
            kz,
            kx,
            uxc: T::ZERO,
        }
    }

    /// Moves the upper point to `(u_x, u_z)` (m) and returns `(f_x, f_z)` (N,
    /// eqs. 3, 4). With `u_z ≤ 0` the spring is off the plane: no forces and
    /// the contact point follows (eq. 5 with f_z = 0).
    #[inline]
    pub fn step(&mut self, ux: T, uz: T) -> (T, T) {
        let uz = uz.max(T::ZERO);
        let w = self.mu0 * (self.kz / self.kx) * uz;
        let s = (ux - self.uxc).max(-w).min(w);
        self.uxc = ux - s;
        (self.kx * s, self.kz * uz)
    }
}
