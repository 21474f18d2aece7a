//! The closed loop: μ held at a setpoint μ* at a stated sliding velocity v₀
//! by adjusting the normal amplitude Δu_z, run on every finished
//! period-synchronous estimate (eq. 20, [`crate::estimator`]).
//!
//! # The control law (units: μ dimensionless, Δu_z in m, time in s)
//!
//! **Feedforward** (computed once per setpoint, [`plan`]): the device's f32
//! model (the exact law with [`FastF32`], scan and bisection) gives the
//! amplitude `u_ff` with `μ_model(u_ff; v₀) = μ*`, the solution nearest the
//! present amplitude, and the model's local gain
//!
//! `s = ∂μ_model/∂Δu_z |_{u_ff}`  (1/m, central difference over 2 % of the range),
//!
//! with `|s|` kept ≥ `S_MIN_REL · μ₀/u_z0` so that a target at an extremum of
//! the law does not make the trim gain `1/s` unbounded.
//!
//! **Integral trim** (every update `k`, [`Controller::update`]): with the
//! measured `μ̂_k` and the error `e_k = μ* − μ̂_k`,
//!
//! `I⁺ = I_k + κ·e_k/(ρ̂·s)`,  `v_k = u_ff + I⁺`                     (C1)
//!
//! `u_k = clamp(v_k, u_{k−1} − r·Δt_k, u_{k−1} + r·Δt_k)`  (rate limit r, m/s)   (C2)
//!
//! `u_k ← clamp(u_k, 0, u_max)`,  `u_max` = the lift-off limit `(1 − margin)·u_z0` (C3)
//!
//! `I_{k+1} = u_k − u_ff` if (C2) or (C3) changed the command
//! (back-calculation: the trim holds the command applied, never more than
//! the bound nor a step the rate limit did not take), else `I⁺`.     (C4)
//!
//! (C4 once kept `I_k` while only the rate limit acted, so that estimates
//! taken mid-ramp integrated nothing; since an update only ever sees an
//! estimate of the command in force ([`crate::device`], "Dead
//! time"), that made the next update undo the ramp's step: from 2 µm with
//! a 0.26 µm step allowed, 2.0 → 1.74 → 1.87 → 1.62 µm where the plant
//! needed 1.6.)
//!
//! κ ∈ (0, 1] is the fraction of the error removed per update if the plant's
//! gain were `ρ̂·s`; a plant gain `s_p = ρ·s` gives the error recursion
//! `e_{k+1} = (1 − κρ/ρ̂)·e_k` (stable for `0 < κρ/ρ̂ < 2`, monotone for
//! `κρ/ρ̂ ≤ 1`). A μ₀ mismatch of 20 % is ρ ≈ 0.6…1.25 on the bench.
//!
//! **The plant's gain, learned** (C5–C6). ρ̂ (1 at switch-on) is learned
//! from the secants between successive updates. With the command `u_k` in
//! force when `μ̂_k` was measured, the model's μ there, linearised about the
//! plan in force, is `m_k = μ* + s·(u_k − u_ff)`, and `Δ = m_k − m_{k−1}`
//! (`s·(u_k − u_{k−1})` within one plan; across a new setpoint each end
//! with its own plan). A pair with `|Δ| ≥ LEARN_MIN_REL·μ₀` and
//! `r = (μ̂_k − μ̂_{k−1})/Δ > 0` gives
//!
//! `r_k = clamp(r, max(RHO_MIN, ρ̂/2), min(RHO_MAX, 2ρ̂))`,  weight `w = Δ²`  (C5)
//!
//! `P ← λ·P + w`,  `ρ̂ ← ρ̂ + (w/P)·(r_k − ρ̂)`   (λ = [`FORGET`]; recursive least squares)   (C6)
//!
//! so a large step (a setpoint change) outweighs the small corrections of
//! the steady state, whose secants are mostly the estimates' noise. A
//! secant of the wrong sign (`r ≤ 0`: μ̂ moved against the command, a
//! disturbance) is not a gain and is not learned from, and one secant
//! moves ρ̂ by at most a factor of 2, so no single pair can raise the loop
//! gain `κ/ρ̂` beyond twice its value. A disturbance (a step of the plant's
//! μ₀, of the velocity) would pass for gain if its secant were taken: a
//! pair without a command change (`|Δ| < LEARN_MIN_REL·μ₀`) whose μ̂ moved
//! by more than that beyond the learned response (`|μ̂_k − μ̂_{k−1} − ρ̂Δ| ≥
//! LEARN_MIN_REL·μ₀`) marks the next pair as *disturbed*, and it is not
//! learned from (the disturbance may have been caught half-way by the
//! window; the pair after it is whole).
//!
//! **Switching.** On: `I₀ = u_now − u_ff`, so the first command is the
//! present amplitude (bumpless). A new setpoint keeps `I` (the learned
//! mismatch) and ρ̂, and moves by the model's step scaled by the learned gain,
//! towards `u_ff + I + (u_ff' − u_ff)/ρ̂` (C7); if the rate limit cuts the
//! move, the trim keeps the command reached (C4) and C1 does the rest. Off: the last
//! command stays applied ([`crate::device`] keeps it as the drive's
//! Δu_z). The guard (C3) is a hard constraint: no command exceeds `u_max`.

use core::fmt;

use model_core::exact::{self, ExactError};
use model_core::float::FastF32;
use model_core::scene::{Drive, Scene};

/// Scan points of the feedforward's search (23 cells over the lift-off range).
pub const SCAN_POINTS: usize = 24;

/// Smallest `|∂(μ/μ₀)/∂(Δu_z/u_z0)|` the trim uses (a target at an extremum
/// of the law gets this gain instead of an unbounded one).
pub const S_MIN_REL: f32 = 0.05;

/// A secant is learned from when the model's change of μ over it is at
/// least this fraction of μ₀ (C5): 0.003 at μ₀ = 0.3, ≥ 40 times the
/// estimates' scatter on the bench (≤ 7e-5 with 4 periods), so one secant's
/// noise is a few % of ρ.
pub const LEARN_MIN_REL: f32 = 0.01;

/// Least ρ a secant gives (C5).
pub const RHO_MIN: f32 = 0.25;

/// Greatest ρ a secant gives (C5).
pub const RHO_MAX: f32 = 4.0;

/// λ of C6: the weight of the past per learned secant.
pub const FORGET: f32 = 0.5;

/// Why a setpoint has no plan.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ControlError {
    /// The target is not finite or `|μ*| > μ₀`.
    BadTarget,
    /// v₀ is zero or not finite (μ is not unique at rest).
    BadVelocity,
    /// The drive has no normal offset (no lift-off range to search).
    NoOffset,
    /// The model cannot reach μ* with Δu_z in `[0, u_max]`: the reachable μ.
    OutOfReach {
        /// Least μ.
        min: f32,
        /// Greatest μ.
        max: f32,
    },
    /// The exact solver failed.
    Model(ExactError),
}

impl fmt::Display for ControlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ControlError::BadTarget => f.write_str("the target mu must be finite with |mu| <= mu0"),
            ControlError::BadVelocity => f.write_str("v0 must be finite and != 0"),
            ControlError::NoOffset => f.write_str("the drive has no normal offset"),
            ControlError::OutOfReach { min, max } => {
                write!(f, "out of reach of the model: mu from {min} to {max}")
            }
            ControlError::Model(_) => f.write_str("the model failed"),
        }
    }
}

impl core::error::Error for ControlError {}

/// What the controller needs from a setpoint (all from the device's model).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Plan {
    /// μ*.
    pub target_mu: f32,
    /// Feedforward amplitude `u_ff`, m.
    pub feedforward_m: f32,
    /// Model gain `s = ∂μ/∂Δu_z` at `u_ff`, 1/m (never 0).
    pub slope_per_m: f32,
    /// The bound `u_max` of the command (lift-off limit), m.
    pub limit_m: f32,
    /// The model's μ₀ (the scale of C5's threshold).
    pub mu0: f32,
}

/// The feedforward and the gain for target μ* at velocity `v0` (m/s) on the
/// device's model `scene` (its Δu_z is ignored), searching Δu_z in
/// `[0, limit_m]`: the exact law (f32, [`FastF32`]) on a scan of
/// [`SCAN_POINTS`] amplitudes, then bisection to the f32 resolution in the
/// scan cell that straddles μ* nearest `near_m` (the law is taken to be
/// monotone inside one cell, 1/23 of the range). The reachable range
/// reported when no cell straddles μ* is the least and greatest scanned μ;
/// the range is closed: a μ* equal to a scanned μ (either end included) is
/// reached at that amplitude. A zero bound (offset at the top of the DAC
/// range) leaves the single amplitude 0 and the reach `[μ(0), μ(0)]`.
/// (A compact search rather than [`model_core::model::inverse`]: the firmware's
/// flash budget.)
///
/// # Errors
/// [`ControlError`].
pub fn plan(
    scene: &Scene<f32>,
    target_mu: f32,
    v0: f32,
    near_m: f32,
    limit_m: f32,
) -> Result<Plan, ControlError> {
    let mu0 = scene.mu0();
    let base = *scene.params();
    if !(target_mu.is_finite() && target_mu.abs() <= mu0) {
        return Err(ControlError::BadTarget);
    }
    if !(v0.is_finite() && v0 != 0.0) {
        return Err(ControlError::BadVelocity);
    }
    // (A NaN bound counts as no offset: the device's lift-off limit is ≥ 0.)
    if !(base.uz0 > 0.0 && limit_m >= 0.0) {
        return Err(ControlError::NoOffset);
    }
    // Strictly below lift-off (a < 1).
    let hi = limit_m.min(base.uz0 * (1.0 - f32::EPSILON));
    // Only `a = Δu_z/u_z0` changes with Δu_z (W₀, b, φ and V do not), so the
    // drive is formed directly, as `Scene::new` forms it (eq. 25), without
    // the scene's validation and libm `sin_cos` (≈ 22 000 instructions on
    // the M4F per call, measured by `predict_cost`).
    let d0 = scene.drive();
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(|_| ControlError::BadVelocity)?;
    let mu = |duz: f32| -> Result<f32, ControlError> {
        let d = Drive {
            a: duz / base.uz0,
            ..d0
        };
        Ok(exact::mu_over_mu0::<f32, FastF32>(&d, v).map_err(ControlError::Model)? * mu0)
    };
    // A zero bound (the offset at the top of the DAC range) leaves one
    // amplitude, 0: the reach is the single μ there.
    let n = if hi > 0.0 { SCAN_POINTS } else { 1 };
    let x_at = |j: usize| {
        if n > 1 {
            hi * j as f32 / (n - 1) as f32
        } else {
            0.0
        }
    };
    // The reach is reported as the least and greatest μ computed, and the
    // target is compared with those very f32 values: a target equal to a
    // reported end is reached (the interval is closed) at the scan point
    // that gave it.
    let (mut lo_mu, mut hi_mu) = (f32::MAX, f32::MIN);
    let mut best: Option<(f32, f32, f32, f32)> = None; // (xl, gl, xr, gr) nearest near_m
    let mut hit: Option<f32> = None; // a scan point with μ = μ* exactly, nearest near_m
    let mut prev = (0.0f32, 0.0f32);
    for j in 0..n {
        let x = x_at(j);
        let m = mu(x)?;
        let g = m - target_mu;
        lo_mu = lo_mu.min(m);
        hi_mu = hi_mu.max(m);
        if m == target_mu && hit.is_none_or(|h| (x - near_m).abs() < (h - near_m).abs()) {
            hit = Some(x);
        }
        if j > 0 && (prev.1 <= 0.0) != (g <= 0.0) {
            let mid = 0.5 * (prev.0 + x);
            let nearer =
                best.is_none_or(|b| (mid - near_m).abs() < (0.5 * (b.0 + b.2) - near_m).abs());
            if nearer {
                best = Some((prev.0, prev.1, x, g));
            }
        }
        prev = (x, g);
    }
    let (mut xl, gl, mut xr) = match (best, hit) {
        (Some((xl, gl, xr, _)), _) => (xl, gl, xr),
        (None, Some(x)) => (x, 0.0, x),
        (None, None) => {
            return Err(ControlError::OutOfReach {
                min: lo_mu,
                max: hi_mu,
            })
        }
    };
    let left_low = gl <= 0.0;
    for _ in 0..40 {
        let m = 0.5 * (xl + xr);
        if m <= xl || m >= xr {
            break;
        }
        if (mu(m)? - target_mu <= 0.0) == left_low {
            xl = m;
        } else {
            xr = m;
        }
    }
    let x = 0.5 * (xl + xr);
    // Central difference over 2 % of the range (one-sided at the ends).
    let h = 0.01 * hi;
    let (a, b) = ((x - h).max(0.0), (x + h).min(hi));
    // NaN for a zero bound (a = b = 0): replaced by the least slope below.
    let mut s = (mu(b)? - mu(a)?) / (b - a);
    let s_min = S_MIN_REL * mu0 / base.uz0;
    if !s.is_finite() || s.abs() < s_min {
        s = if s < 0.0 { -s_min } else { s_min };
    }
    Ok(Plan {
        target_mu,
        feedforward_m: x,
        slope_per_m: s,
        limit_m,
        mu0,
    })
}

/// The controller's tuning.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gains {
    /// κ: fraction of the error removed per update (eq. C1), in (0, 1].
    pub kappa: f32,
    /// Rate limit r of the command, m/s (eq. C2), > 0.
    pub rate_m_per_s: f32,
}

/// The outcome of one update.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output {
    /// The command `u_k`, m (in `[0, limit_m]`).
    pub command_m: f32,
    /// The trim `I_{k+1}`, m.
    pub integral_m: f32,
    /// (C2) or (C3) changed the command.
    pub saturated: bool,
}

/// The learning of the plant's gain (C5–C6).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Learn {
    /// ρ̂.
    rho: f32,
    /// P of C6.
    weight: f32,
    /// The last update's model μ `m` at the command in force (C5) and its μ̂.
    last: Option<(f32, f32)>,
    /// The last pair moved μ̂ without a command change: the next pair is
    /// not learned from.
    disturbed: bool,
}

impl Learn {
    fn new(mu0: f32) -> Self {
        let w0 = LEARN_MIN_REL * mu0;
        Learn {
            rho: 1.0,
            weight: w0 * w0,
            last: None,
            disturbed: false,
        }
    }

    /// One measurement `mu` where the model, linearised about the plan in
    /// force, says `model_mu` (C5, C6).
    fn push(&mut self, model_mu: f32, mu: f32, mu0: f32) {
        let min = LEARN_MIN_REL * mu0;
        if let Some((m0, mu_0)) = self.last {
            let d = model_mu - m0;
            let dm = mu - mu_0;
            if !(d.is_finite() && dm.is_finite()) {
                // Nothing to judge the next pair by: it is not learned from.
                self.disturbed = true;
            } else if d.abs() >= min {
                let r = dm / d;
                if !self.disturbed && r > 0.0 {
                    let lo = RHO_MIN.max(0.5 * self.rho);
                    let hi = RHO_MAX.min(2.0 * self.rho);
                    let r = clamp(r, lo, hi);
                    let w = d * d;
                    self.weight = FORGET * self.weight + w;
                    self.rho += w / self.weight * (r - self.rho);
                }
                self.disturbed = false;
            } else {
                self.disturbed = (dm - self.rho * d).abs() >= min;
            }
        }
        self.last = Some((model_mu, mu));
    }
}

/// The loop's state (eqs. C1–C7).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Controller {
    plan: Plan,
    gains: Gains,
    integral_m: f32,
    command_m: f32,
    saturated: bool,
    learn: Learn,
}

impl Controller {
    /// A controller switched on with the amplitude `now_m` applied: its
    /// command is `now_m` clamped into `[0, limit_m]` (bumpless), its trim
    /// `I₀ = u_now − u_ff`.
    pub fn new(plan: Plan, gains: Gains, now_m: f32) -> Self {
        let u = clamp(now_m, 0.0, plan.limit_m);
        Controller {
            plan,
            gains,
            integral_m: u - plan.feedforward_m,
            command_m: u,
            saturated: u != now_m,
            learn: Learn::new(plan.mu0),
        }
    }

    /// ρ̂, the plant's gain over the model's learned so far (C6; 1 at first).
    pub fn plant_gain(&self) -> f32 {
        self.learn.rho
    }

    /// The plan.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The gains.
    pub fn gains(&self) -> &Gains {
        &self.gains
    }

    /// The last output.
    pub fn output(&self) -> Output {
        Output {
            command_m: self.command_m,
            integral_m: self.integral_m,
            saturated: self.saturated,
        }
    }

    /// A new setpoint (and gains): the trim and ρ̂ are kept; the command
    /// moves towards `u_ff + I + (u_ff' − u_ff)/ρ̂` (C7) by at most `r·dt_s`
    /// now (eqs. C2–C4 with `e = 0`).
    pub fn retarget(&mut self, plan: Plan, gains: Gains, dt_s: f32) -> Output {
        let (old, i) = (self.plan.feedforward_m, self.integral_m);
        let moved = (plan.feedforward_m - old) / self.learn.rho;
        let i = if moved.is_finite() {
            old + i + moved - plan.feedforward_m
        } else {
            i
        };
        self.plan = plan;
        self.gains = gains;
        self.step(i, dt_s)
    }

    /// The last command could not be applied (the actuator refused it):
    /// the command goes back to `applied_m`, the amplitude in force, and
    /// the trim with it (`I = u − u_ff`: back-calculation, no windup); the
    /// output is marked saturated.
    pub fn refused(&mut self, applied_m: f32) -> Output {
        self.command_m = applied_m;
        self.integral_m = applied_m - self.plan.feedforward_m;
        self.saturated = true;
        self.output()
    }

    /// One update with the measured μ̂ of the command in force (eqs. C5–C6,
    /// then C1–C4 with the gain `κ/(ρ̂·s)`); `dt_s` is the time since the
    /// last command was applied, s.
    pub fn update(&mut self, measured_mu: f32, dt_s: f32) -> Output {
        let p = self.plan;
        let model_mu = p.target_mu + p.slope_per_m * (self.command_m - p.feedforward_m);
        self.learn.push(model_mu, measured_mu, p.mu0);
        let e = p.target_mu - measured_mu;
        let di = self.gains.kappa * e / (p.slope_per_m * self.learn.rho);
        if !di.is_finite() {
            // A non-finite estimate: hold.
            return self.output();
        }
        self.step(self.integral_m + di, dt_s)
    }

    /// Eqs. C1 (with the trim `i`), C2, C3, C4.
    fn step(&mut self, i: f32, dt_s: f32) -> Output {
        let v = self.plan.feedforward_m + i;
        let step = (self.gains.rate_m_per_s * dt_s).max(0.0);
        let ramped = clamp(v, self.command_m - step, self.command_m + step);
        let u = clamp(ramped, 0.0, self.plan.limit_m);
        self.integral_m = if u != v {
            u - self.plan.feedforward_m
        } else {
            i
        };
        self.command_m = u;
        self.saturated = u != v;
        self.output()
    }
}

/// `x` clamped into `[lo, hi]` (`lo` if `hi < lo`; NaN gives `lo`).
fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    let y = if x > lo { x } else { lo };
    if y < hi {
        y
    } else if hi > lo {
        hi
    } else {
        lo
    }
}
