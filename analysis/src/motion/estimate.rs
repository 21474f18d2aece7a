//! The homogenised model's error, derived (no calibrated constant).
//!
//! The homogenised body feels `μ(V)·F̄z`, the mean spring force of the
//! contact driven at the *constant* velocity `V`. The resolved body feels the
//! spring force of the contact driven by its actual position `X(τ)`. The
//! difference, per ultrasonic period, is bounded in three steps (units:
//! `τ = ωt`, lengths `W₀`, forces `μ₀k_z u_z0 = k_x W₀`):
//!
//! 1. **Memory of one period.** A slip sets the stretch to `±w`, erasing the
//!    past: when the contact slips in every ultrasonic period, the spring
//!    force over a period depends only on the drive since the last slip, at
//!    most `L = 2π` back. With lift-off the state resets at every landing
//!    (eq. L1–L5), so this holds exactly.
//! 2. **Lipschitz.** The contact point is the output of a play operator with
//!    the band `w(τ)` of the input `u = X + b cos(τ + φ)`; it preserves order
//!    and commutes with adding a constant, so two inputs within `δ` (sup
//!    norm) give contact points within `δ` and stretches `s = u − x_c` within
//!    `2δ`.
//! 3. **Curvature.** Over a window of length `L` the body's position differs
//!    from its best straight line `X̄ + Vτ` (the drive the law is evaluated
//!    for) by at most `K L²/16` (the Chebyshev minimax line of a function with
//!    `|X''| ≤ K`). With `L = 2π` the mean spring force over the window is
//!    within `2·K·4π²/16 = π²K/2` of `μ(V)·F̄z`.
//!
//! **Curved profiles** (MDR): every spring of the bed is its own play operator
//! on the same input, so step 2 holds spring by spring and the total force
//! (units `k_x W₀`, `k_x = 2G*a₀`) is `2δ·reach`-Lipschitz, `reach =
//! (1 + a)^{1/n}` the width of the springs that ever touch; step 3 gives
//! `π²K·reach/2` (`law::Law::spring_bounds`; 1 for the flat punch).
//!
//! `K = sup|d²X/dτ²|`: for a body of mass `m̃ = Mω²/k_x`, `m̃X'' = n̄g − s`
//! with `|s| ≤ s_max` (`1 + a` for the flat punch, `n/(n + 1)(1 + a)^{1+1/n}`
//! for a profile `n`) and `|g| ≤ G = |f0| + |f| + κ max|X|/n̄`, so
//! `K ≤ (n̄G + s_max)/m̃` — the ultrasonic ripple of the body against its
//! response time, and the slow acceleration with it. For the massless body
//! `X' = V(T)` follows the law's inverse, `K = ν max|dV/dT|` (the scale
//! separation), taken from the trajectory.
//!
//! A force error `δF` (units `μ₀F̄z`, i.e. `π²K/(2n̄)`) moves the quasi-static
//! velocity by `δF·dV/dμ`; the estimate uses the law's mean inverse slope on
//! each side, `S = max(c/(1 − μ(0⁺)), c'/(1 + μ(0⁻)))` (units ωW₀ per μ₀),
//! so
//!
//! ```text
//! E_slide = π² K·reach·S / (2 n̄)       (units ωW₀)
//! ```
//!
//! Steps 1–3 are bounds; the last conversion is an estimate (the local slope
//! varies along the law).
//!
//! **Sticking.** Step 1 fails where the body is stuck: the homogenised body
//! then stands rigidly, while the resolved one sits on the contact's
//! tangential stiffness, deflects with the load and rings on it (period
//! `2π√(M/k_x)`, which for a heavy body approaches the load period). While
//! the contact holds, every touching spring's stretch stays inside its band,
//! so the resolved body stays within `2·band = 2(1 + a)` (units W₀) of the
//! rigidly stuck one; it leaves rest with that offset, which the sliding
//! that follows carries along. Counting one such offset per arrival at rest
//! (`N` = [`Run::stick_onsets`] of the last load period, of length `2π/ν` in
//! `τ`) adds
//!
//! ```text
//! E_s = N · 2(1 + a) · ν / (2π)     (units ωW₀)
//! ```
//!
//! and the homogenised model's error estimate is `E_h = E_slide + E_s`.
//!
//! (0 with lift-off: μ(0) is unique and the body never sticks). It is the
//! term that covers the heavy flat body stuck and ringing (`bench motion`:
//! `Mω²/k_x = 10⁵` at `ω/Ω = 10³`, |H − R| 0.131·|R| against `E_h` = 0.674·|R|, of which `E_s` 0.56·|R|),
//! and it is below `E_h` for bodies that respond within the load period.
//! `tests/motion.rs` checks `|H − R| ≤ E_h` on a sweep and counts the
//! outcomes.

use std::f64::consts::PI;

use super::law::SpringBounds;
use super::table::MuTable;
use super::{Problem, Run};

/// `S`: the law's largest mean inverse slope (units ωW₀ per μ₀; module docs).
pub fn inverse_slope(law: &MuTable) -> f64 {
    [
        law.c_forward / (1.0 - law.mu_0plus).max(1e-12),
        law.c_backward / (1.0 + law.mu_0minus).max(1e-12),
    ]
    .into_iter()
    .fold(0.0, f64::max)
}

/// `K = sup|d²X/dτ²|` (units W₀ per unit τ², module docs); `s_max` bounds
/// the contact's spring force (units `k_x W₀`; `1 + a` for the flat punch,
/// `law::Law::spring_bounds`). `run` is a homogenised run (its trajectory
/// gives max|X| with a spring and max|dV/dT| for the massless body).
pub fn curvature(p: &Problem, s_max: f64, run: &Run) -> f64 {
    if p.mass > 0.0 {
        let x_max = run.trajectory.iter().map(|s| s.x.abs()).fold(0.0, f64::max);
        let g = p.f0.abs() + p.f.abs() + p.kappa * x_max / p.normal;
        (p.normal * g + s_max) / p.mass
    } else {
        p.nu * max_dv_dt(run)
    }
}

/// `max|dV/dT|` over a run's recorded trajectory (units ωW₀ per unit `T`).
pub fn max_dv_dt(run: &Run) -> f64 {
    run.trajectory
        .windows(2)
        .filter(|w| w[1].t > w[0].t)
        .map(|w| ((w[1].v - w[0].v) / (w[1].t - w[0].t)).abs())
        .fold(0.0, f64::max)
}

/// The homogenised model's estimated error `E_h` (units ωW₀, module docs):
/// the sliding body's `E_slide = π²K·reach·S/(2n̄)` plus the stuck body's
/// `E_s = N·(1 + a)·ν/π`, `run` a homogenised run.
pub fn homogenisation_error(p: &Problem, bounds: SpringBounds, law: &MuTable, run: &Run) -> f64 {
    let sliding = PI * PI * curvature(p, bounds.s_max, run) * bounds.reach * inverse_slope(law)
        / (2.0 * p.normal);
    sliding + sticking(p, bounds, run)
}

/// `E_s = N·2·band·ν/(2π)` (units ωW₀, module docs): one offset of the
/// stuck body's band per arrival at rest in the last load period.
pub fn sticking(p: &Problem, bounds: SpringBounds, run: &Run) -> f64 {
    f64::from(run.stick_onsets) * 2.0 * bounds.band * p.nu / (2.0 * PI)
}
