//! The exact steady-state solver: μ(v₀) with no transient and no time step.
//!
//! # Method (in the dimensionless variables of [`crate::scene`])
//!
//! The spring stretch `s` is confined to the friction band `|s| ≤ w(θ)`,
//! `w = 1 − a cos θ`; it follows the drive `u_x = Vθ + b cos(θ + φ)` while it
//! sticks and is dragged along `±w` while it slips (the paper's scheme of §3 in
//! the limit of a vanishing step). For `V > 0`:
//!
//! * Forward slip (`s = +w`) persists exactly while
//!   `g(θ) = V − c sin(θ + ψ) ≥ 0`, where `c e^{iψ} = b e^{iφ} + a`, i.e.
//!   `c = v_c/(ωW₀)` (eq. 8). For `V < c` this *forward window* is one arc per
//!   period and ends at `θ_e = asin(V/c) − ψ` (closed form).
//! * Over a period the contact point must advance by `2πV > 0`, which only
//!   forward slip does, so every steady-state period slips forward in its
//!   window and leaves it with `s = +w(θ_e)`. Conversely, starting there, one
//!   period later `s` is again `+w` (the argument gives `s ≥ w + 2πV` otherwise),
//!   so this is the unique periodic state. We integrate one period from `θ_e`.
//! * During stick, `s − w` and `s + w` are a linear function plus a sinusoid
//!   (`K ∓ 1 + Vθ + c cos(θ+ψ)`, resp. `+ c' cos(θ+ψ')` with
//!   `c' e^{iψ'} = b e^{iφ} − a`): their critical points are in closed form, so
//!   each stick→slip event is a bracketed root of a monotone function, found by
//!   safeguarded Newton to a few ulps ([`crate::root`]).
//! * Slip→stick events are the window ends, in closed form; the integrals of
//!   `s` over stick (`K + Vθ + b cos(θ+φ)`) and slip (`±w`) arcs are closed form.
//!
//! One period has at most a stick, a backward slip, a stick and a forward slip
//! (the backward window is also one arc per period). `V < 0` uses the exact
//! mirror `μ(V, φ) = −μ(−V, φ + π)`; `|V| ≥ c` gives `±1` exactly (continuous
//! sliding, eq. 8); `V = 0` has no unique steady state, and
//! [`solve`] returns the one-sided limits μ(0±) (the same construction with
//! `V = 0`) together with the static interval.

use heapless::Vec;

use crate::analytic::static_friction::StaticFriction;
use crate::float::{Float, Libm, Math};
use crate::root::newton_bracketed;
use crate::scene::{Drive, Scene, SceneError};

/// Largest number of arcs in one steady-state period (stick, slip back,
/// stick, slip forward, with the first stick possibly split at the period start).
pub const MAX_ARCS: usize = 8;

/// What the contact point does during an arc.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ArcKind {
    /// Stuck: the spring follows the drive.
    Stick,
    /// Slipping in +x with `f_x = +μ₀ f_z`.
    SlipForward,
    /// Slipping in −x with `f_x = −μ₀ f_z`.
    SlipBackward,
}

/// One arc of the steady-state period, in drive phase θ = ωt (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Arc<T> {
    /// What happens.
    pub kind: ArcKind,
    /// Phase at the start, rad (unwrapped: `start ≤ end ≤ start + 2π` over the period).
    pub start: T,
    /// Phase at the end, rad.
    pub end: T,
}

/// Why the exact solver gave no number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ExactError {
    /// The velocity is NaN, infinite, or overflows the dimensionless scale.
    BadVelocity(SceneError),
    /// The event walk did not close the period (internal check: the state after
    /// one period must equal the start). Never observed; reported rather than
    /// returning a wrong number.
    Inconsistent,
}

/// The steady-state answer for one velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Solution<T> {
    /// `|v₀| ≥ v_c`: continuous sliding, `μ/μ₀ = ±1` exactly.
    Sliding {
        /// `±1`.
        mu_over_mu0: T,
    },
    /// `0 < |v₀| < v_c`: periodic stick–slip, μ from one exact period.
    StickSlip {
        /// `μ/μ₀ = ⟨f_x⟩/(μ₀⟨f_z⟩)` (eq. 20).
        mu_over_mu0: T,
    },
    /// `v₀ = 0`: no unique steady state. The law's one-sided limits and the
    /// static interval ([`StaticFriction`]). When a static equilibrium exists,
    /// `mu_0plus = hi` and `mu_0minus = lo`; when none exists both limits are
    /// equal (the contact "walks on the spot" with a net force).
    AtRest {
        /// `lim μ/μ₀` as `v₀ → 0⁺`.
        mu_0plus: T,
        /// `lim μ/μ₀` as `v₀ → 0⁻`.
        mu_0minus: T,
        /// The static analysis.
        statics: StaticFriction<T>,
    },
}

impl<T: Float> Solution<T> {
    /// `μ/μ₀` for a moving contact; `None` at rest.
    pub fn mu_over_mu0(&self) -> Option<T> {
        match *self {
            Solution::Sliding { mu_over_mu0 } | Solution::StickSlip { mu_over_mu0 } => {
                Some(mu_over_mu0)
            }
            Solution::AtRest { .. } => None,
        }
    }
}

/// Solves the steady state of `scene` at sliding velocity `v0` (m/s).
///
/// # Errors
/// [`ExactError::BadVelocity`] for a non-finite `v0`; [`ExactError::Inconsistent`]
/// if the internal period check fails.
pub fn solve<T: Float>(scene: &Scene<T>, v0: T) -> Result<Solution<T>, ExactError> {
    solve_with::<T, Libm>(scene, v0)
}

/// [`solve`] with a chosen math backend.
///
/// # Errors
/// As [`solve`].
pub fn solve_with<T: Float, M: Math<T>>(
    scene: &Scene<T>,
    v0: T,
) -> Result<Solution<T>, ExactError> {
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(ExactError::BadVelocity)?;
    solve_dimensionless::<T, M>(&scene.drive(), v, scene)
}

fn solve_dimensionless<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
    scene: &Scene<T>,
) -> Result<Solution<T>, ExactError> {
    if v == T::ZERO {
        let (mu_0plus, mu_0minus) = limits_at_zero::<T, M>(d)?;
        return Ok(Solution::AtRest {
            mu_0plus,
            mu_0minus,
            statics: StaticFriction::of_with::<M>(scene),
        });
    }
    let (dd, vv, sign) = if v > T::ZERO {
        (*d, v, T::ONE)
    } else {
        (d.mirrored(), -v, -T::ONE)
    };
    if vv >= dd.c_forward::<M>() {
        return Ok(Solution::Sliding { mu_over_mu0: sign });
    }
    let m = period_forward::<T, M>(&dd, vv, |_| {})?;
    Ok(Solution::StickSlip {
        mu_over_mu0: sign * m,
    })
}

/// `μ/μ₀` at dimensionless velocity `V = v₀/(ωW₀) ≠ 0` — the fast path with no
/// scene validation (the drive comes from a validated [`Scene`]).
///
/// # Errors
/// [`ExactError::BadVelocity`] for `V = 0` or non-finite `V`; [`ExactError::Inconsistent`].
#[inline]
pub fn mu_over_mu0<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Result<T, ExactError> {
    if !v.is_finite() || v == T::ZERO {
        return Err(ExactError::BadVelocity(SceneError::NonFinite(
            crate::scene::Param::Velocity,
        )));
    }
    let (dd, vv, sign) = if v > T::ZERO {
        (*d, v, T::ONE)
    } else {
        (d.mirrored(), -v, -T::ONE)
    };
    if vv >= dd.c_forward::<M>() {
        return Ok(sign);
    }
    Ok(sign * period_forward::<T, M>(&dd, vv, |_| {})?)
}

/// The one-sided limits `(μ(0⁺), μ(0⁻))/μ₀` of the velocity law.
///
/// # Errors
/// [`ExactError::Inconsistent`] (internal check).
pub fn limits_at_zero<T: Float, M: Math<T>>(d: &Drive<T>) -> Result<(T, T), ExactError> {
    let plus = if d.c_forward::<M>() == T::ZERO {
        T::ONE
    } else {
        period_forward::<T, M>(d, T::ZERO, |_| {})?
    };
    let m = d.mirrored();
    let minus = if m.c_forward::<M>() == T::ZERO {
        -T::ONE
    } else {
        -period_forward::<T, M>(&m, T::ZERO, |_| {})?
    };
    Ok((plus, minus))
}

/// The steady-state period as a list of arcs plus `μ/μ₀`, for `V ≠ 0`
/// (dimensionless). Phases are absolute drive phases θ = ωt.
///
/// # Errors
/// As [`mu_over_mu0`].
pub fn steady_state<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
) -> Result<(T, Vec<Arc<T>, MAX_ARCS>), ExactError> {
    if !v.is_finite() || v == T::ZERO {
        return Err(ExactError::BadVelocity(SceneError::NonFinite(
            crate::scene::Param::Velocity,
        )));
    }
    let (dd, vv, sign) = if v > T::ZERO {
        (*d, v, T::ONE)
    } else {
        (d.mirrored(), -v, -T::ONE)
    };
    let mut arcs: Vec<Arc<T>, MAX_ARCS> = Vec::new();
    if vv >= dd.c_forward::<M>() {
        let kind = if sign > T::ZERO {
            ArcKind::SlipForward
        } else {
            ArcKind::SlipBackward
        };
        let _ = arcs.push(Arc {
            kind,
            start: T::ZERO,
            end: T::TAU,
        });
        return Ok((sign, arcs));
    }
    let m = period_forward::<T, M>(&dd, vv, |arc| {
        let kind = match (arc.kind, sign > T::ZERO) {
            (ArcKind::Stick, _) => ArcKind::Stick,
            (k, true) => k,
            (ArcKind::SlipForward, false) => ArcKind::SlipBackward,
            (ArcKind::SlipBackward, false) => ArcKind::SlipForward,
        };
        let _ = arcs.push(Arc { kind, ..arc });
    })?;
    Ok((sign * m, arcs))
}

/// Wraps `x` (|x| < 8π) into `[0, 2π)`.
#[inline]
fn wrap_tau<T: Float>(mut x: T) -> T {
    while x < T::ZERO {
        x += T::TAU;
    }
    while x >= T::TAU {
        x -= T::TAU;
    }
    x
}

/// One steady-state period for `0 ≤ V < c` (forward convention), returning `⟨s⟩`.
/// `V = 0` gives the limit `μ(0⁺)/μ₀`. `on_arc` sees each arc in order.
#[inline]
fn period_forward<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
    mut on_arc: impl FnMut(Arc<T>),
) -> Result<T, ExactError> {
    let (a, bc, bs) = (d.a, d.bc, d.bs);
    let pr = a + bc; // Re(b e^{iφ} + a)
    let c = M::hypot(pr, bs);
    // Window end θ_e = α − ψ, α = asin(V/c) ∈ [0, π/2].
    let ratio = (v / c).min(T::ONE);
    let alpha = M::asin(ratio);
    let psi = M::atan2(bs, pr);
    let theta_e = alpha - psi;
    let (se, ce) = M::sin_cos(theta_e);
    // Functions of τ = θ − θ_e via sincos(τ) only:
    //   A(τ) = a cos(τ+θ_e) = m cos τ − n sin τ,     ∫A = m sin τ + n cos τ
    //   X(τ) = b cos(τ+θ_e+φ) = p cos τ − q sin τ,   ∫X = p sin τ + q cos τ
    let (m, n) = (a * ce, a * se);
    let p = bc * ce - bs * se;
    let q = bc * se + bs * ce;
    let tau_end = T::TAU;
    // Forward window (h⁺ increasing) inside the period: [π − 2α, 2π].
    let tau_s = T::PI - (alpha + alpha);

    // Backward window (h⁻ decreasing), if V < c'.
    let qr = bc - a; // Re(b e^{iφ} − a)
    let cb = M::hypot(qr, bs);
    // Pieces of the backward window inside [0, 2π], in time order.
    let mut back: [(T, T); 2] = [(T::ZERO, T::ZERO); 2];
    let mut nback = 0usize;
    if v < cb {
        let alpha_b = M::asin((v / cb).min(T::ONE));
        let psi_b = M::atan2(bs, qr);
        let len = T::PI - (alpha_b + alpha_b);
        let start = wrap_tau(alpha_b - psi_b - theta_e);
        let wrapped_end = start + len - T::TAU;
        if wrapped_end > T::ZERO {
            back[nback] = (T::ZERO, wrapped_end);
            nback += 1;
        }
        back[nback] = (start, (start + len).min(tau_end));
        nback += 1;
    }

    let theta = |tau: T| tau + theta_e;
    // (A(τ), X(τ), Ȧ, Ẋ) pieces.
    let trig = |tau: T| M::sin_cos(tau);
    let mut total = T::ZERO;
    let mut tau0 = T::ZERO;
    // Stick constant: s(τ) = k + Vτ + X(τ); at τ = 0, s = w(0) = 1 − A(0).
    let mut k = T::ONE - m - p;
    let mut closed = false;
    for _ in 0..MAX_ARCS {
        // h⁺(τ) = s − w = k − 1 + Vτ + X + A ;  h⁺' = V − (p+n) sinτ − (q+m) cosτ
        let hplus = |tau: T| {
            let (st, ct) = trig(tau);
            let f = k - T::ONE + v * tau + (p + m) * ct - (q + n) * st;
            let df = v - (p + m) * st - (q + n) * ct;
            (f, df)
        };
        // h⁻(τ) = s + w = k + 1 + Vτ + X − A ; h⁻' = V − (p−m) sinτ − (q−n) cosτ
        let hminus = |tau: T| {
            let (st, ct) = trig(tau);
            let f = k + T::ONE + v * tau + (p - m) * ct - (q - n) * st;
            let df = v - (p - m) * st - (q - n) * ct;
            (f, df)
        };
        // Forward touch.
        let mut tf: Option<T> = None;
        {
            let l = tau0.max(tau_s);
            if l < tau_end {
                let fl = hplus(l).0;
                if fl >= T::ZERO {
                    // Already at the upper band at the start of the increasing
                    // segment (only at the window start, by rounding): slip now.
                    tf = Some(l);
                } else {
                    let fr = hplus(tau_end).0;
                    if fr > T::ZERO {
                        tf = Some(newton_bracketed(l, tau_end, fl, fr, 100, hplus));
                    }
                }
            }
        }
        // Backward touch (only if it can come before the forward one).
        let mut tb: Option<(T, T)> = None;
        let horizon = tf.unwrap_or(tau_end);
        for &(pl, pr_) in back.iter().take(nback) {
            let l = pl.max(tau0);
            if !(l < pr_) || l >= horizon {
                continue;
            }
            let fl = hminus(l).0;
            if fl <= T::ZERO {
                tb = Some((l, pr_));
                break;
            }
            let fr = hminus(pr_).0;
            if fr < T::ZERO {
                let r = newton_bracketed(l, pr_, fl, fr, 100, hminus);
                if r < horizon {
                    tb = Some((r, pr_));
                }
                break;
            }
        }
        let stick_integral = |t0: T, t1: T| {
            let (s0, c0) = trig(t0);
            let (s1, c1) = trig(t1);
            let y = (p * s1 + q * c1) - (p * s0 + q * c0);
            k * (t1 - t0) + v * (t1 - t0) * (t1 + t0) * T::HALF + y
        };
        // ∫ w dτ over [t0, t1].
        let w_integral = |t0: T, t1: T| {
            let (s0, c0) = trig(t0);
            let (s1, c1) = trig(t1);
            (t1 - t0) - ((m * s1 + n * c1) - (m * s0 + n * c0))
        };
        match (tb, tf) {
            (Some((t_b, t_end_b)), _) => {
                total += stick_integral(tau0, t_b);
                total -= w_integral(t_b, t_end_b);
                on_arc(Arc {
                    kind: ArcKind::Stick,
                    start: theta(tau0),
                    end: theta(t_b),
                });
                on_arc(Arc {
                    kind: ArcKind::SlipBackward,
                    start: theta(t_b),
                    end: theta(t_end_b),
                });
                // Stick again from s = −w(t_end_b).
                let (s1, c1) = trig(t_end_b);
                let w1 = T::ONE - (m * c1 - n * s1);
                let x1 = p * c1 - q * s1;
                k = -w1 - v * t_end_b - x1;
                tau0 = t_end_b;
                if tau0 >= tau_end {
                    // Slipping backward at the period end: cannot be the steady state.
                    return Err(ExactError::Inconsistent);
                }
            }
            (None, Some(t_f)) => {
                total += stick_integral(tau0, t_f);
                total += w_integral(t_f, tau_end);
                on_arc(Arc {
                    kind: ArcKind::Stick,
                    start: theta(tau0),
                    end: theta(t_f),
                });
                on_arc(Arc {
                    kind: ArcKind::SlipForward,
                    start: theta(t_f),
                    end: theta(tau_end),
                });
                closed = true;
                break;
            }
            (None, None) => {
                // No forward touch: only consistent if s(2π) = w(2π) already
                // (V → 0 with pure stick; h⁺(2π) = 2πV otherwise).
                let h_end = hplus(tau_end).0;
                let tol = T::from_f64(64.0) * T::EPSILON * (T::ONE + d.b + v * T::TAU);
                if h_end.abs() > tol {
                    return Err(ExactError::Inconsistent);
                }
                total += stick_integral(tau0, tau_end);
                on_arc(Arc {
                    kind: ArcKind::Stick,
                    start: theta(tau0),
                    end: theta(tau_end),
                });
                closed = true;
                break;
            }
        }
    }
    if !closed {
        return Err(ExactError::Inconsistent);
    }
    let mu = total / T::TAU;
    // |μ/μ₀| ≤ 1 holds exactly; allow rounding.
    if !mu.is_finite() || mu.abs() > T::ONE + T::from_f64(1e3) * T::EPSILON {
        return Err(ExactError::Inconsistent);
    }
    Ok(mu.max(-T::ONE).min(T::ONE))
}
