//! The fixed-step scheme of §3 for a contact that lifts off, with the landing
//! and the lift-off on the grid.
//!
//! The state resets at every landing (`s = 0`, [parent module](super)), so
//! one contact window is the exact steady state: no transient, no
//! convergence loop, any `V` including 0. The window `[θ_L, θ_R]` is cut into
//! steps of `δ = 2π/N` starting *at the landing*, `θ_j = θ_L + jδ`, and one
//! last shorter step ends exactly at the lift-off `θ_R`. Per step: add the
//! drive increment to the stretch (stick trial) and clamp it to `[−w, w]`
//! (the paper's scheme); `∫s dθ` is the trapezoid sum of the stretches and
//! `∫w dθ` is exact (eq. L4).
//!
//! **Order 2.** The scheme's stretches are exact at the grid points during
//! stick and forward/backward slip and at the first grid point after a
//! stick→slip event (the clamp puts `s` on the band); after a slip→stick
//! event at `θ_e` between grid points the error is
//! `(w' − u_x')(θ_j − θ_e) + O(δ²) = O(δ²)` because `w' = u_x'` there. The
//! trapezoid rule on a function with a bounded number of kinks is `O(δ²)`.
//! A scheme whose grid does not start at the landing instead starts the
//! window with an `O(δ)` error in phase (an erratic 8·10⁻⁵ at
//! 7 500 steps): here the landing is exact. The measured order (least-squares
//! fit of the worst `log |Δμ|` over 400 random scenes against `log N`,
//! N = 64 … 4 096, `tests/liftoff.rs`) is 1.94.
//!
//! Bound: `|μ_N − μ|/μ₀ ≤ (1 + a + b)·(K/N² + N ε + M::MAX_REL_ERROR)` with
//! `K` = [`DISCRETISATION_K`].

use super::{check_drive, check_velocity, LiftOffError, Window};
use crate::model::fixed_step::max_steps_per_period;
use crate::model::float::{Float, Math};
use crate::model::scene::Drive;

/// Measured-bound constant of the discretisation error:
/// `|μ_N − μ|/μ₀ ≤ K·(1 + a + b)/N²` with `K` = 10, calibrated by
/// self-convergence of this scheme alone (the run at N against the same
/// scheme at 2¹⁸ steps per period, `tests/fixed_step_bound.rs`): measured
/// worst 2.16 over 400 random scenes with `a` from 1 to 4, a fifth within
/// 10⁻³ of 1, `b` from 10⁻³ to 10, `V` over ±1.2 of the critical velocities
/// and 0, N from 64 to 4 096. `tests/liftoff.rs` checks the window solver
/// against this bound, independently.
pub const DISCRETISATION_K: f64 = 10.0;

/// Largest discretisation part of the bound a run may have (10 % of μ₀).
pub const MAX_DISCRETISATION: f64 = 0.1;

/// The fewest steps per period whose discretisation bound is within
/// [`MAX_DISCRETISATION`]: `⌈√(K(1 + a + b)/0.1)⌉`, at least 8.
pub fn min_steps_per_period<T: Float>(d: &Drive<T>) -> u32 {
    let n = libm::ceil(libm::sqrt(
        DISCRETISATION_K * (1.0 + d.a.to_f64() + d.b.to_f64()) / MAX_DISCRETISATION,
    ));
    if n < 8.0 {
        8
    } else if n > u32::MAX as f64 {
        u32::MAX
    } else {
        n as u32
    }
}

/// The stated error bound of [`mu_over_mu0`] with `n` steps per period, in
/// units of μ₀: `(1 + a + b)·(K/N² + N ε + M::MAX_REL_ERROR)`.
pub fn error_bound<T: Float, M: Math<T>>(d: &Drive<T>, n: u32) -> T {
    let nn = T::from_u32(n.max(1));
    (T::ONE + d.a + d.b)
        * (T::from_f64(DISCRETISATION_K) / (nn * nn)
            + nn * T::EPSILON
            + T::from_f64(M::MAX_REL_ERROR))
}

/// A fixed-step result.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SteppedOutcome<T> {
    /// `μ/μ₀` of the steady state (one contact window).
    pub mu_over_mu0: T,
    /// Steps taken (including the last, shorter one).
    pub steps: u32,
    /// The stated error bound, units of μ₀ ([`error_bound`]).
    pub error_bound: T,
}

/// `μ/μ₀` by the fixed-step scheme with `n` steps per period, at
/// dimensionless velocity `V` (any finite value), for a drive with `a ≥ 1`.
///
/// # Errors
/// [`LiftOffError::BadDrive`], [`LiftOffError::NoLiftOff`],
/// [`LiftOffError::IllConditioned`], [`LiftOffError::BadVelocity`],
/// [`LiftOffError::TooFewSteps`], [`LiftOffError::PrecisionLimit`].
pub fn mu_over_mu0<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
    n: u32,
) -> Result<SteppedOutcome<T>, LiftOffError> {
    check_drive(d)?;
    check_velocity(v)?;
    let min_steps = min_steps_per_period(d);
    if n < min_steps {
        return Err(LiftOffError::TooFewSteps { min_steps });
    }
    let max_steps = max_steps_per_period::<T>();
    if n > max_steps {
        return Err(LiftOffError::PrecisionLimit { max_steps });
    }
    let window = Window::of::<M>(T::ONE, d.a);
    let (a, bc, bs) = (d.a, d.bc, d.bs);
    let delta = T::TAU / T::from_u32(n);
    let (sin_step, cos_step) = M::sin_cos(delta);
    let span = window.lift_off.at - window.landing.at;
    // Whole steps inside the window (span < 2π, so fewer than n).
    let mut whole = libm::floor((span / delta).to_f64()) as u32;
    let mut last = span - T::from_u32(whole) * delta;
    if last <= T::ZERO && whole > 0 {
        whole -= 1;
        last += delta;
    }
    let (mut cos_t, mut sin_t) = (window.landing.cos, window.landing.sin);
    let mut swing = bc * cos_t - bs * sin_t;
    let mut stretch = T::ZERO;
    let mut step = |cos_new: T, sin_new: T, dv: T, stretch: &mut T| {
        let swing_new = bc * cos_new - bs * sin_new;
        let band = T::ONE - a * cos_new;
        *stretch = (*stretch + dv + (swing_new - swing)).max(-band).min(band);
        swing = swing_new;
    };
    // Trapezoid: δ·(s₀/2 + s₁ + … + s_{J−1} + s_J/2) + last·(s_J + s_end)/2, s₀ = 0.
    let mut inner = T::ZERO;
    let vd = v * delta;
    for j in 0..whole {
        let c = cos_t * cos_step - sin_t * sin_step;
        let s = sin_t * cos_step + cos_t * sin_step;
        cos_t = c;
        sin_t = s;
        step(c, s, vd, &mut stretch);
        if j + 1 < whole {
            inner += stretch;
        }
    }
    let s_whole = stretch;
    let mut integral = delta * (inner + T::HALF * s_whole);
    if whole == 0 {
        integral = T::ZERO;
    }
    step(
        window.lift_off.cos,
        window.lift_off.sin,
        v * last,
        &mut stretch,
    );
    integral += last * T::HALF * (s_whole + stretch);
    let mu = integral / window.band_integral(T::ONE, a);
    Ok(SteppedOutcome {
        mu_over_mu0: mu.max(-T::ONE).min(T::ONE),
        steps: whole + 1,
        error_bound: error_bound::<T, M>(d, n),
    })
}
