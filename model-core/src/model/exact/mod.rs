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

use crate::model::analytic::critical_velocity::CriticalVelocity;
use crate::model::analytic::static_friction::StaticFriction;
use crate::model::float::{Float, Libm, Math};
use crate::model::scene::{Drive, Scene, SceneError};

pub(crate) mod period;

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

impl core::fmt::Display for ExactError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ExactError::BadVelocity(e) => write!(f, "bad velocity: {e}"),
            ExactError::BadDrive => f.write_str(
                "invalid drive (non-finite, Δu_z/u_z0 outside [0, 1) or a negative amplitude)",
            ),
            ExactError::Inconsistent => f.write_str(
                "the exact solver's period did not close (internal check; a number would be wrong)",
            ),
            ExactError::IllConditioned => f.write_str(
                "ill-conditioned: the float type cannot resolve this drive (k_xΔu_x/(μ0 k_z u_z0) too large)",
            ),
        }
    }
}

impl core::error::Error for ExactError {}

/// The verified precision constant of the exact solver: its error in `μ/μ₀`
/// is at most this times `1 + b` (plus the backend's term, [`error_bound`]).
///
/// f64: `1e-9`, the level to which the tests can check it (Richardson-
/// extrapolated fixed-step runs at N = 16 384/32 768 steps per period over
/// random scenes with `b` up to 10⁴, `tests/stability.rs`); the root finding
/// converges to a few ulps, so the true error is far smaller.
/// f32: `1e-6`, against the f64 solver (measured worst `1.82e-7·(1 + b)`
/// with [`crate::model::float::FastF32`] and `1.74e-7·(1 + b)` with libm over
/// 20 000 random scenes with `b < 5`, `1.6e-7·(1 + b)` over 5 000 with
/// `b < 100`: `tests/trig.rs`, `exact_solver_mu_fast_f32_*`).
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
    let c = scene.dimensionless_critical();
    solve_dimensionless::<T, M>(&scene.drive(), v, scene, Some(c))
}

/// [`solve_with`] and the scene's [`CriticalVelocity`] (eq. 8) together, as
/// the board's prediction reports them: the scene's critical velocities
/// ([`Scene::dimensionless_critical`], formed once with [`Libm`] when the
/// scene was) serve the solver and the report, with no `hypot` per call.
/// The same numbers as [`solve_with`] and [`CriticalVelocity::of`] called
/// apart.
///
/// # Errors
/// As [`solve`].
pub fn solve_with_critical<T: Float, M: Math<T>>(
    scene: &Scene<T>,
    v0: T,
) -> Result<(Solution<T>, CriticalVelocity<T>), ExactError> {
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(ExactError::BadVelocity)?;
    let d = scene.drive();
    // The scene's own (Libm, formed once): not again per prediction.
    let c = scene.dimensionless_critical();
    let solution = solve_dimensionless::<T, M>(&d, v, scene, Some(c))?;
    Ok((
        solution,
        CriticalVelocity::of_dimensionless(scene, c.0, c.1),
    ))
}

/// `known`: the drive's `(c, c')` (`|b e^{iφ} ± a|`), when the caller has them.
fn solve_dimensionless<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
    scene: &Scene<T>,
    known: Option<(T, T)>,
) -> Result<Solution<T>, ExactError> {
    if v == T::ZERO {
        let (mu_0plus, mu_0minus) = limits_at_zero::<T, M>(d)?;
        return Ok(Solution::AtRest {
            mu_0plus,
            mu_0minus,
            statics: StaticFriction::of_with::<M>(scene),
        });
    }
    match Oriented::of_scene::<M>(d, v, known)? {
        Oriented::Sliding { sign } => Ok(Solution::Sliding { mu_over_mu0: sign }),
        Oriented::StickSlip(problem) => Ok(Solution::StickSlip {
            mu_over_mu0: problem.sign * period::mean_stretch::<T, M>(&problem, None)?,
        }),
    }
}

/// `μ/μ₀` at dimensionless velocity `V = v₀/(ωW₀) ≠ 0` — the fast path with no
/// scene validation (the drive comes from a validated [`Scene`]).
///
/// # Errors
/// [`ExactError::BadVelocity`] for `V = 0` or non-finite `V`; [`ExactError::Inconsistent`].
#[inline]
pub fn mu_over_mu0<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Result<T, ExactError> {
    match Oriented::of::<M>(d, v, None)? {
        Oriented::Sliding { sign } => Ok(sign),
        Oriented::StickSlip(problem) => {
            Ok(problem.sign * period::mean_stretch::<T, M>(&problem, None)?)
        }
    }
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
    // μ(0±) is the forward-convention period at V = 0 of the drive and of its mirror.
    let limit = |drive: Drive<T>, sign: T| match Forward::at_rest::<M>(drive, sign) {
        None => Ok(sign),
        Some(problem) => Ok(sign * period::mean_stretch::<T, M>(&problem, None)?),
    };
    let plus = limit(*d, T::ONE)?;
    let minus = limit(d.mirrored(), -T::ONE)?;
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
    let mut arcs: Vec<Arc<T>, MAX_ARCS> = Vec::new();
    let problem = match Oriented::of::<M>(d, v, None)? {
        Oriented::Sliding { sign } => {
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
        Oriented::StickSlip(problem) => problem,
    };
    // Arcs of the mirrored problem slip the other way.
    let backward = problem.sign < T::ZERO;
    let mut push = |arc: Arc<T>| {
        let kind = match (arc.kind, backward) {
            (ArcKind::SlipForward, true) => ArcKind::SlipBackward,
            (ArcKind::SlipBackward, true) => ArcKind::SlipForward,
            (kind, _) => kind,
        };
        let _ = arcs.push(Arc { kind, ..arc });
    };
    let m = period::mean_stretch::<T, M>(&problem, Some(&mut push))?;
    Ok((problem.sign * m, arcs))
}

/// A stick–slip problem in the forward convention (`V ≥ 0`): the drive, or its
/// mirror image when the contact slides backward (`μ(V, φ) = −μ(−V, φ + π)`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Forward<T> {
    /// The (possibly mirrored) drive.
    pub(crate) drive: Drive<T>,
    /// `|V|`, below `c`.
    pub(crate) v: T,
    /// The forward critical velocity of `drive`, `c = |b e^{iφ} + a|`.
    pub(crate) c: T,
    /// The backward critical velocity of `drive`, `c' = |b e^{iφ} − a|`
    /// (it places the backward slip window).
    pub(crate) c_back: T,
    /// `+1`, or `−1` for a mirrored problem: `μ/μ₀ = sign · ⟨s⟩`.
    pub(crate) sign: T,
}

impl<T: Float> Forward<T> {
    /// The `V → 0⁺` problem of `drive` (the period whose mean is `μ(0⁺)/μ₀`
    /// in the forward convention); `None` when `c = 0` (no stick–slip at any
    /// `V > 0`, `μ(0⁺)/μ₀ = 1`).
    pub(crate) fn at_rest<M: Math<T>>(drive: Drive<T>, sign: T) -> Option<Self> {
        let c = drive.c_forward::<M>();
        if c == T::ZERO {
            return None;
        }
        Some(Forward {
            drive,
            v: T::ZERO,
            c,
            c_back: drive.c_backward::<M>(),
            sign,
        })
    }
}

/// A validated velocity and drive, turned to the forward convention.
enum Oriented<T> {
    /// `|V| ≥ c`: continuous sliding, `μ/μ₀ = sign`.
    Sliding { sign: T },
    /// `0 < |V| < c`: one period to integrate.
    StickSlip(Forward<T>),
}

impl<T: Float> Oriented<T> {
    /// Validates the drive ([`Drive::is_valid`]: it may be built by hand) and
    /// orients the problem ([`Oriented::orient`]).
    #[inline]
    fn of<M: Math<T>>(d: &Drive<T>, v: T, known: Option<(T, T)>) -> Result<Self, ExactError> {
        if !d.is_valid() {
            return Err(ExactError::BadDrive);
        }
        Self::orient::<M>(d, v, known)
    }

    /// [`Oriented::of`] for the drive of a [`Scene`], which its constructor
    /// validated (finite, `b ≥ 0`, on its circle): only the permanent
    /// contact's `a < 1` is checked, since a scene may be an intermittent one
    /// (a ≥ 1). Saves [`Drive::is_valid`]'s divisions and tests on the
    /// board's prediction path.
    #[inline]
    fn of_scene<M: Math<T>>(d: &Drive<T>, v: T, known: Option<(T, T)>) -> Result<Self, ExactError> {
        // A scene's `a` is finite (never NaN).
        if d.a >= T::ONE {
            return Err(ExactError::BadDrive);
        }
        Self::orient::<M>(d, v, known)
    }

    /// Checks `V ≠ 0`, mirrors `V < 0` to the forward convention, and decides
    /// sliding (`|V| ≥ c`) or stick–slip (which must pass the conditioning
    /// check). `known`: `d`'s `(c_forward, c_backward)` if the caller has
    /// computed them.
    #[inline]
    fn orient<M: Math<T>>(d: &Drive<T>, v: T, known: Option<(T, T)>) -> Result<Self, ExactError> {
        if !v.is_finite() || v == T::ZERO {
            return Err(ExactError::BadVelocity(SceneError::NonFinite(
                crate::model::scene::Param::Velocity,
            )));
        }
        let (drive, v, sign) = if v > T::ZERO {
            (*d, v, T::ONE)
        } else {
            (d.mirrored(), -v, -T::ONE)
        };
        // The mirror swaps the two critical velocities.
        let known = known.map(|(f, b)| if sign > T::ZERO { (f, b) } else { (b, f) });
        let c = known.map_or_else(|| drive.c_forward::<M>(), |k| k.0);
        if v >= c {
            return Ok(Oriented::Sliding { sign });
        }
        check_conditioning(d)?;
        let c_back = known.map_or_else(|| drive.c_backward::<M>(), |k| k.1);
        Ok(Oriented::StickSlip(Forward {
            drive,
            v,
            c,
            c_back,
            sign,
        }))
    }
}
