//! The exact steady-state solver: μ(v₀) with no transient and no time step.
//!
//! # Method (in the dimensionless variables of [`crate::model::scene`])
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
//!   safeguarded Newton to a few ulps.
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

use crate::model::analytic::static_friction::StaticFriction;
use crate::model::float::{Float, Libm, Math};
use crate::model::root::newton_bracketed;
use crate::model::scene::{Drive, Scene, SceneError};

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
    /// A hand-built [`Drive`] that no validated scene produces
    /// ([`Drive::is_valid`]): non-finite, `a ∉ [0, 1)` or `b < 0`.
    BadDrive,
    /// The event walk did not close the period (internal check: the state after
    /// one period must equal the start). Seen only with the micromath backend
    /// near `v_c`; reported rather than returning a wrong number.
    Inconsistent,
    /// The float type cannot resolve this drive: the precision part of
    /// [`error_bound`] exceeds [`ILL_CONDITIONED_AT`] (f32 with
    /// `b = k_xΔu_x/(μ₀k_z u_z0) ≳ 10⁴`, f64 with `b ≳ 10⁷`): the stretch swings
    /// over `±b` while μ is decided by differences of order 1.
    IllConditioned,
}

/// The verified precision constant of the exact solver: its error in `μ/μ₀`
/// is at most this times `1 + b` (plus the backend's term, [`error_bound`]).
///
/// f64: `1e-9`, the level to which the tests can check it (Richardson-
/// extrapolated fixed-step runs at N = 16 384/32 768 steps per period over
/// random scenes with `b` up to 10⁴, `tests/stability.rs`); the root finding
/// converges to a few ulps, so the true error is far smaller.
/// f32: `1e-6`, against the f64 solver (measured worst `7e-8·(1 + b)` over
/// random scenes with `b` from 10⁻⁴ to 10³).
pub fn precision_constant<T: Float>() -> T {
    if T::EPSILON < T::from_f64(1e-10) {
        T::from_f64(1e-9)
    } else {
        T::from_f64(1e-6)
    }
}

/// Above this precision part of the bound the solver refuses with
/// [`ExactError::IllConditioned`] (1 % of μ₀).
pub const ILL_CONDITIONED_AT: f64 = 1e-2;

/// The error bound of [`mu_over_mu0`] / [`solve_with`] for a drive, in units of μ₀:
/// `(precision_constant + M::MAX_REL_ERROR)·(1 + b)`. Continuous sliding
/// (`|V| ≥ c`) is exact (bound 0); this bound is for stick–slip and the
/// limits at rest.
pub fn error_bound<T: Float, M: Math<T>>(d: &Drive<T>) -> T {
    (precision_constant::<T>() + T::from_f64(M::MAX_REL_ERROR)) * (T::ONE + d.b)
}

fn check_conditioning<T: Float>(d: &Drive<T>) -> Result<(), ExactError> {
    if precision_constant::<T>() * (T::ONE + d.b) > T::from_f64(ILL_CONDITIONED_AT) {
        Err(ExactError::IllConditioned)
    } else {
        Ok(())
    }
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
    let c = dd.c_forward::<M>();
    if vv >= c {
        return Ok(Solution::Sliding { mu_over_mu0: sign });
    }
    check_conditioning(d)?;
    let m = period_forward::<T, M>(&dd, vv, c, None)?;
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
    if !d.is_valid() {
        return Err(ExactError::BadDrive);
    }
    if !v.is_finite() || v == T::ZERO {
        return Err(ExactError::BadVelocity(SceneError::NonFinite(
            crate::model::scene::Param::Velocity,
        )));
    }
    let (dd, vv, sign) = if v > T::ZERO {
        (*d, v, T::ONE)
    } else {
        (d.mirrored(), -v, -T::ONE)
    };
    let c = dd.c_forward::<M>();
    if vv >= c {
        return Ok(sign);
    }
    check_conditioning(d)?;
    Ok(sign * period_forward::<T, M>(&dd, vv, c, None)?)
}

/// The one-sided limits `(μ(0⁺), μ(0⁻))/μ₀` of the velocity law.
///
/// # Errors
/// [`ExactError::Inconsistent`] (internal check).
pub fn limits_at_zero<T: Float, M: Math<T>>(d: &Drive<T>) -> Result<(T, T), ExactError> {
    if !d.is_valid() {
        return Err(ExactError::BadDrive);
    }
    check_conditioning(d)?;
    let c = d.c_forward::<M>();
    let plus = if c == T::ZERO {
        T::ONE
    } else {
        period_forward::<T, M>(d, T::ZERO, c, None)?
    };
    let m = d.mirrored();
    let cm = m.c_forward::<M>();
    let minus = if cm == T::ZERO {
        -T::ONE
    } else {
        -period_forward::<T, M>(&m, T::ZERO, cm, None)?
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
    if !d.is_valid() {
        return Err(ExactError::BadDrive);
    }
    if !v.is_finite() || v == T::ZERO {
        return Err(ExactError::BadVelocity(SceneError::NonFinite(
            crate::model::scene::Param::Velocity,
        )));
    }
    let (dd, vv, sign) = if v > T::ZERO {
        (*d, v, T::ONE)
    } else {
        (d.mirrored(), -v, -T::ONE)
    };
    let mut arcs: Vec<Arc<T>, MAX_ARCS> = Vec::new();
    let c = dd.c_forward::<M>();
    if vv >= c {
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
    check_conditioning(d)?;
    let mut push = |arc: Arc<T>| {
        let kind = match (arc.kind, sign > T::ZERO) {
            (ArcKind::Stick, _) => ArcKind::Stick,
            (k, true) => k,
            (ArcKind::SlipForward, false) => ArcKind::SlipBackward,
            (ArcKind::SlipBackward, false) => ArcKind::SlipForward,
        };
        let _ = arcs.push(Arc { kind, ..arc });
    };
    let m = period_forward::<T, M>(&dd, vv, c, Some(&mut push))?;
    Ok((sign * m, arcs))
}

/// A phase point `τ` with `sin τ` and `cos τ`.
#[derive(Clone, Copy, Debug)]
struct Pt<T> {
    t: T,
    s: T,
    c: T,
}

/// Rotation of a phase point's trig by an angle given as `(sin, cos)`.
#[inline(always)]
fn rot<T: Float>(s: T, c: T, sd: T, cd: T) -> (T, T) {
    (s * cd + c * sd, c * cd - s * sd)
}

/// One steady-state period for `0 ≤ V < c` (forward convention, `c` the
/// forward critical velocity of `d`), returning `⟨s⟩ = μ/μ₀`. `V = 0` gives
/// the limit `μ(0⁺)/μ₀`. `rec`, if given, sees each arc in order.
///
/// All phases are relative to the window end θ_e: τ = θ − θ_e ∈ [0, 2π]. The
/// trigonometric values at the closed-form points (window ends) come from
/// rotations of `(V/c, √(1 − V²/c²))` and the drive phasors, so the only
/// transcendental calls are two `asin`, the square roots, and one `sin_cos`
/// per Newton iteration of the stick→slip roots.
#[inline]
fn period_forward<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
    c: T,
    mut rec: Option<&mut dyn FnMut(Arc<T>)>,
) -> Result<T, ExactError> {
    let (a, bc, bs) = (d.a, d.bc, d.bs);
    let pr = a + bc; // Re(b e^{iφ} + a);  c e^{iψ} = pr + i·bs
                     // Forward window end: α = asin(V/c), θ_e = α − ψ.
    let sa = (v / c).min(T::ONE);
    let ca = M::sqrt(((T::ONE - sa) * (T::ONE + sa)).max(T::ZERO));
    let alpha = M::asin(sa);
    let (cpsi, spsi) = (pr / c, bs / c);
    let se = sa * cpsi - ca * spsi; // sin θ_e
    let ce = ca * cpsi + sa * spsi; // cos θ_e
                                    // Functions of τ:  A = a cos(τ+θ_e) = m cos τ − n sin τ,  ∫A = m sin τ + n cos τ,
                                    //                  X = b cos(τ+θ_e+φ) = p cos τ − q sin τ,  ∫X = p sin τ + q cos τ.
    let (m, n) = (a * ce, a * se);
    let p = bc * ce - bs * se;
    let q = bc * se + bs * ce;
    let p0 = Pt {
        t: T::ZERO,
        s: T::ZERO,
        c: T::ONE,
    };
    let pend = Pt {
        t: T::TAU,
        s: T::ZERO,
        c: T::ONE,
    };
    // Start of the forward window (h⁺ minimum): τ_s = π − 2α.
    let ps = Pt {
        t: T::PI - (alpha + alpha),
        s: T::TWO * sa * ca,
        c: T::TWO * sa * sa - T::ONE,
    };

    // Backward window (h⁻ decreasing) if V < c': pieces inside [0, 2π] in time order.
    let qr = bc - a; // c' e^{iψ'} = qr + i·bs
    let cb = M::hypot(qr, bs);
    let mut back = [(p0, p0); 2];
    let mut nback = 0usize;
    let mut curv_b = T::ZERO;
    if v < cb {
        let sb = (v / cb).min(T::ONE);
        let cbb = M::sqrt(((T::ONE - sb) * (T::ONE + sb)).max(T::ZERO));
        let alpha_b = M::asin(sb);
        curv_b = cb * cbb;
        // δ = ψ − ψ' = arg(P·conj P'), P·conj P' = (pr·qr + bs²) − i·2a·bs.
        let re = pr * qr + bs * bs;
        let im = -(T::TWO * a * bs);
        let delta = M::atan2(im, re);
        let cc = c * cb;
        let (sd, cd) = (im / cc, re / cc);
        // Window start σ = α' − ψ' − θ_e = α' − α + δ.
        let (s1, c1) = rot(sb, cbb, -sa, ca);
        let (s1, c1) = rot(s1, c1, sd, cd);
        let start = wrap_tau(alpha_b - alpha + delta);
        let len = T::PI - (alpha_b + alpha_b);
        let (s2, c2) = rot(s1, c1, T::TWO * sb * cbb, T::TWO * sb * sb - T::ONE);
        let end = start + len;
        let pstart = Pt {
            t: start,
            s: s1,
            c: c1,
        };
        if end > T::TAU {
            back[0] = (
                p0,
                Pt {
                    t: end - T::TAU,
                    s: s2,
                    c: c2,
                },
            );
            back[1] = (pstart, pend);
            nback = 2;
        } else {
            back[0] = (
                pstart,
                Pt {
                    t: end,
                    s: s2,
                    c: c2,
                },
            );
            nback = 1;
        }
    }

    let a_int = |x: &Pt<T>| m * x.s + n * x.c;
    let x_int = |x: &Pt<T>| p * x.s + q * x.c;
    let w_at = |x: &Pt<T>| T::ONE - (m * x.c - n * x.s);
    let x_at = |x: &Pt<T>| p * x.c - q * x.s;
    // ∫ w dτ over [x0, x1].
    let w_integral = |x0: &Pt<T>, x1: &Pt<T>| (x1.t - x0.t) - (a_int(x1) - a_int(x0));
    let mut theta_e = T::ZERO;
    if rec.is_some() {
        theta_e = alpha - M::atan2(bs, pr);
    }
    let mut emit = |kind: ArcKind, x0: &Pt<T>, x1: &Pt<T>| {
        if let Some(r) = rec.as_mut() {
            r(Arc {
                kind,
                start: x0.t + theta_e,
                end: x1.t + theta_e,
            });
        }
    };

    // Rounding level of h± (for the root finder's stopping test).
    let scale = T::ONE + d.b + a + v * T::TAU;
    let ftol = |k: T| T::from_f64(8.0) * T::EPSILON * (scale + k.abs());
    let mut total = T::ZERO;
    let mut tau0 = p0;
    // Stick: s(τ) = k + Vτ + X(τ); at τ = 0, s = w(0).
    let mut k = w_at(&p0) - x_at(&p0);
    for _ in 0..MAX_ARCS {
        // h⁺ = s − w = k − 1 + Vτ + X + A; h⁻ = s + w = k + 1 + Vτ + X − A.
        let hplus = |x: &Pt<T>| k - T::ONE + v * x.t + (p + m) * x.c - (q + n) * x.s;
        let hminus = |x: &Pt<T>| k + T::ONE + v * x.t + (p - m) * x.c - (q - n) * x.s;
        let dplus = |x: &Pt<T>| v - (p + m) * x.s - (q + n) * x.c;
        let dminus = |x: &Pt<T>| v - (p - m) * x.s - (q - n) * x.c;
        // Forward touch: first zero of h⁺ on its increasing segment [max(τ0, τ_s), 2π].
        let mut tf: Option<Pt<T>> = None;
        let l = if tau0.t >= ps.t { tau0 } else { ps };
        if l.t < pend.t {
            let fl = hplus(&l);
            if fl >= T::ZERO {
                // At the band already at the segment start (rounding only): slip now.
                tf = Some(l);
            } else {
                let fr = hplus(&pend);
                if fr > T::ZERO {
                    // Near the minimum h⁺ ≈ h_min + ½·c cos α·(τ − τ_s)².
                    let curv = c * ca;
                    let guess = if l.t == ps.t && curv > T::ZERO {
                        l.t + M::sqrt(-(fl + fl) / curv)
                    } else {
                        l.t - fl / dplus(&l)
                    };
                    tf = Some(root::<T, M>(l.t, pend.t, fl, fr, guess, ftol(k), |x| {
                        (hplus(x), dplus(x))
                    }));
                }
            }
        }
        // Backward touch before the forward one: zero of h⁻ on a decreasing piece.
        let horizon = tf.map_or(pend.t, |x| x.t);
        let mut tb: Option<(Pt<T>, Pt<T>)> = None;
        for &(pl, pr_) in back.iter().take(nback) {
            let l = if tau0.t > pl.t { tau0 } else { pl };
            if l.t >= pr_.t || l.t >= horizon {
                continue;
            }
            let fl = hminus(&l);
            if fl <= T::ZERO {
                tb = Some((l, pr_));
                break;
            }
            let fr = hminus(&pr_);
            if fr < T::ZERO {
                // Near the maximum h⁻ ≈ h_max − ½·c' cos α'·(τ − σ)².
                let guess = if l.t == pl.t && curv_b > T::ZERO {
                    l.t + M::sqrt((fl + fl) / curv_b)
                } else {
                    l.t - fl / dminus(&l)
                };
                let r = root::<T, M>(l.t, pr_.t, fl, fr, guess, ftol(k), |x| {
                    (hminus(x), dminus(x))
                });
                if r.t < horizon {
                    tb = Some((r, pr_));
                }
                break;
            }
        }
        let stick_integral = |x0: &Pt<T>, x1: &Pt<T>| {
            k * (x1.t - x0.t)
                + v * (x1.t - x0.t) * (x1.t + x0.t) * T::HALF
                + (x_int(x1) - x_int(x0))
        };
        match (tb, tf) {
            (Some((t_b, t_end_b)), _) => {
                total += stick_integral(&tau0, &t_b);
                total -= w_integral(&t_b, &t_end_b);
                emit(ArcKind::Stick, &tau0, &t_b);
                emit(ArcKind::SlipBackward, &t_b, &t_end_b);
                if t_end_b.t >= pend.t {
                    // Slipping backward at the period end: not the steady state.
                    return Err(ExactError::Inconsistent);
                }
                // Stick again from s = −w.
                k = -w_at(&t_end_b) - v * t_end_b.t - x_at(&t_end_b);
                tau0 = t_end_b;
            }
            (None, Some(t_f)) => {
                total += stick_integral(&tau0, &t_f);
                total += w_integral(&t_f, &pend);
                emit(ArcKind::Stick, &tau0, &t_f);
                emit(ArcKind::SlipForward, &t_f, &pend);
                return finish(total);
            }
            (None, None) => {
                // No forward touch: only consistent if s(2π) = w(2π) already
                // (V → 0 with pure stick; otherwise h⁺(2π) ≥ 2πV).
                let tol = T::from_f64(64.0) * T::EPSILON * (T::ONE + d.b + v * T::TAU);
                if hplus(&pend).abs() > tol {
                    return Err(ExactError::Inconsistent);
                }
                total += stick_integral(&tau0, &pend);
                emit(ArcKind::Stick, &tau0, &pend);
                return finish(total);
            }
        }
    }
    Err(ExactError::Inconsistent)
}

#[inline(always)]
fn finish<T: Float>(total: T) -> Result<T, ExactError> {
    let mu = total / T::TAU;
    // |μ/μ₀| ≤ 1 holds exactly; allow rounding, never more.
    if !mu.is_finite() || mu.abs() > T::ONE + T::from_f64(1e3) * T::EPSILON {
        return Err(ExactError::Inconsistent);
    }
    Ok(mu.max(-T::ONE).min(T::ONE))
}

/// Bracketed root of a stick→slip function, returned with its trig.
#[inline(always)]
fn root<T: Float, M: Math<T>>(
    lo: T,
    hi: T,
    f_lo: T,
    f_hi: T,
    guess: T,
    f_tol: T,
    fd: impl Fn(&Pt<T>) -> (T, T),
) -> Pt<T> {
    newton_bracketed((lo, hi, f_lo, f_hi), guess, f_tol, 100, |t| {
        let (s, c) = M::sin_cos(t);
        let x = Pt { t, s, c };
        let (f, df) = fd(&x);
        (f, df, s, c)
    })
    .into()
}

impl<T> From<(T, T, T)> for Pt<T> {
    #[inline(always)]
    fn from((t, s, c): (T, T, T)) -> Self {
        Pt { t, s, c }
    }
}

/// Wraps `x` (|x| < 8π) into `[0, 2π)`.
#[inline]
fn wrap_tau<T: Float>(mut x: T) -> T {
    if !x.is_finite() {
        return T::ZERO;
    }
    while x < T::ZERO {
        x += T::TAU;
    }
    while x >= T::TAU {
        x -= T::TAU;
    }
    x
}
