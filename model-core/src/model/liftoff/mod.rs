//! Intermittent contact of the flat punch: the spring lifts off the plane
//! once per period (`a = Δu_z/u_z0 ≥ 1`).
//!
//! # Model (dimensionless variables of [`crate::model::scene`])
//!
//! The normal displacement is `u_z = u_z0 (1 − a cos θ)` (eq. 1), so the band
//! `w(θ) = 1 − a cos θ` is negative for `|θ| < θ_c` (mod 2π), `cos θ_c = 1/a`:
//! the spring is off the plane. There it carries no force (`f_z = k_z u_z⁺`,
//! `f_x = 0`) and, having no mass, relaxes tangentially: `s = 0`, the contact
//! point follows the top. The *contact window* is
//!
//! ```text
//! θ ∈ [θ_L, θ_R] = [θ_c, 2π − θ_c],   θ_c = atan2(√((a − 1)(a + 1)), 1)      (L1)
//! ```
//!
//! with landing at `θ_L` and lift-off at `θ_R`. Inside it the dynamics is the
//! permanent contact's: `|s| ≤ w`, `s` follows `u_x = Vθ + b cos(θ + φ)` while
//! it sticks and is dragged along `±w` while it slips. At landing `s = 0 = w`.
//!
//! **The state resets every period.** Whatever happened before, `s(θ_L) = 0`,
//! so the period from one landing to the next is the exact steady state for
//! every `V` — including `V = 0`, where the permanent contact has no unique
//! state: with lift-off the force at rest is unique.
//!
//! **Events.** On a stick arc `s = k + Vθ + X(θ)`, `X = b cos(θ + φ)`, and
//!
//! ```text
//! h⁺ = s − w = k − 1 + Vθ + (b cos φ + a) cos θ − b sin φ sin θ,   h⁺' = V − c  sin(θ + ψ)     (L2)
//! h⁻ = s + w = k + 1 + Vθ + (b cos φ − a) cos θ − b sin φ sin θ,   h⁻' = V − c' sin(θ + ψ')    (L3)
//! ```
//!
//! with `c e^{iψ} = b e^{iφ} + a`, `c' e^{iψ'} = b e^{iφ} − a` (eq. 8). Forward
//! slip (`s = +w`) persists exactly while `h⁺' ≥ 0` (the stick trial would leave
//! the band upward): on the arcs `θ + ψ ∈ [π − α, 2π + α]`, `α = asin(V/c)`,
//! where `h⁺` increases. Backward slip persists while `h⁻' ≤ 0`: on
//! `θ + ψ' ∈ [α', π − α']`, `α' = asin(V/c')` (none when `V ≥ c'`). A stick arc
//! ends at the first zero of `h⁺` on one of its increasing pieces or of `h⁻`
//! on one of its decreasing pieces (the pieces' ends are closed form; each
//! zero is a bracketed root of a monotone function, safeguarded Newton to a
//! few ulps); a slip arc ends at the end of its piece (closed form) or at
//! lift-off. At landing `h⁺ = h⁻ = 0`: the contact slips forward at once if
//! `h⁺` increases there, backward if `h⁻` decreases, and sticks otherwise.
//! In the forward convention `V ≥ 0`; `V < 0` uses the exact mirror
//! `μ(V, φ) = −μ(−V, φ + π)`.
//!
//! **Friction.** With `f_x = k_x W₀ s` and `f_z = k_z u_z0 w⁺`,
//!
//! ```text
//! μ/μ₀ = ⟨f_x⟩/(μ₀⟨f_z⟩) = ∫_window s dθ / ∫_window w dθ,
//! ∫_window w dθ = 2(π − θ_c + √(a² − 1)) = 2π⟨w⁺⟩                                (L4)
//! ```
//!
//! (stick arcs: `∫s = k Δθ + V Δ(θ²)/2 + Δ[b cos φ sin θ + b sin φ cos θ]`;
//! slip arcs: `±∫w = ±(Δθ − a Δ sin θ)`). The normalisation is the mean normal
//! force `⟨f_z⟩ = k_z⟨u_z⁺⟩ = k_z u_z0⟨w⁺⟩`, not `k_z u_z0` as with permanent
//! contact (there `⟨w⟩ = 1`); `⟨w⁺⟩ ≥ 1` grows from 1 at `a = 1` like `a/π`.
//!
//! **Critical velocity** ([`critical_velocities`]). The contact slides forward
//! through the whole window, `μ/μ₀ = 1` exactly, iff `h⁺' ≥ 0` on the window:
//!
//! ```text
//! V ≥ V_c⁺ = max_{θ ∈ [θ_L, θ_R]} c sin(θ + ψ)
//!          = c if π/2 − ψ (mod 2π) lies in the window, else the larger end value    (L5)
//! ```
//!
//! and backward iff `−V ≥ V_c⁻`, the same for the mirrored drive. It is not
//! eq. 8: the part of the period in the air does not count. `V_c⁺ ≥ 0`
//! (the window is longer than π).
//!
//! **Continuity across `a = 1`.** For `a = 1 − ε` the permanent contact's
//! band at `θ = 0` is `w(0) = ε`, so its stretch there is within `ε` of the
//! lift-off model's `s = 0`; stick (a translation) and the clamp to the band (a
//! 1-Lipschitz map) never increase the distance between two states, so the two
//! stretches stay within `2ε` over the period. The airborne arc `|θ| < θ_c ≈
//! √(2ε)` contributes `O(ε^{3/2})` and `⟨w⁺⟩ = 1 + O(ε^{3/2})`. So μ is
//! continuous at `a = 1` with `|μ(1 ± ε) − μ(1)| = O(ε)` (Lipschitz; the two
//! one-sided slopes may differ). `tests/liftoff.rs` checks this.
//!
//! **Static friction.** There is none in the permanent-contact sense: the
//! state is reset at every landing, the force at rest `μ(0)` is unique and
//! the velocity law is continuous through `V = 0`; no static interval exists
//! (a body held at rest feels the force `μ(0)·⟨f_z⟩`, whatever its history).
//! [`regime::classify`] classifies by the sign of `μ(0)` and the symmetry of
//! the law. [`crate::model::select::mu_within`] answers lift-off scenes with
//! this solver; the permanent-contact [`crate::model::regime`], the
//! [`crate::model::analytic`] formulas (critical velocity eq. 8, static
//! friction, approximations eqs. 21/24, all derived for permanent contact)
//! and [`crate::model::exact`] refuse or do not apply to lift-off drives.
//!
//! The fixed-step counterpart with exact landing is [`stepping`].

use heapless::Vec;

use crate::model::exact::period::{root, wrap_tau, Phase};
use crate::model::exact::{precision_constant, Arc, ArcKind};
use crate::model::float::{Float, Libm, Math};
use crate::model::scene::{ContactMode, Drive, Param, Scene, SceneError};

pub mod regime;
pub mod stepping;

/// Above this precision part of the bound the solvers refuse with
/// [`LiftOffError::IllConditioned`] (1 % of μ₀), as the permanent solver.
pub const ILL_CONDITIONED_AT: f64 = 1e-2;

/// Capacity of [`window_arcs`]' list: a window shorter than 2π holds at most
/// two forward and two backward slip pieces, each slip runs to its piece's
/// end, so at most 4 slips and 5 sticks (9 arcs).
pub const MAX_ARCS: usize = 12;

/// Stick-then-slip steps of the walk (4 slips and the last stick).
const MAX_STEPS: usize = 5;

/// Why a lift-off solver gave no number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LiftOffError {
    /// The velocity is NaN, infinite, or overflows the dimensionless scale.
    BadVelocity(SceneError),
    /// A drive no validated intermittent-contact scene produces
    /// ([`Drive::is_valid_with_contact`]): non-finite, `a < 0`, `b < 0`.
    BadDrive,
    /// `a < 1`: the contact never lifts off; use the permanent-contact
    /// solvers ([`crate::model::exact`]), which are exact there.
    NoLiftOff,
    /// The float type cannot resolve this drive: the precision part of the
    /// bound, `precision_constant·(1 + a + b)`, exceeds [`ILL_CONDITIONED_AT`].
    IllConditioned,
    /// The event walk did not close the window (internal check: `s = 0` at
    /// lift-off); reported rather than returning a wrong number.
    Inconsistent,
    /// Fixed-step: fewer steps per period than the drive needs.
    TooFewSteps {
        /// The fewest accepted ([`stepping::min_steps_per_period`]).
        min_steps: u32,
    },
    /// Fixed-step: more steps per period than the float type can use.
    PrecisionLimit {
        /// The most accepted ([`crate::model::fixed_step::max_steps_per_period`]).
        max_steps: u32,
    },
}

impl core::fmt::Display for LiftOffError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            LiftOffError::BadVelocity(e) => write!(f, "{e}"),
            LiftOffError::BadDrive => write!(
                f,
                "drive: not one a valid scene produces (finite, duz-rel >= 0, dux-rel >= 0)"
            ),
            LiftOffError::NoLiftOff => write!(
                f,
                "duz: must be >= uz0 for the lift-off solver (below it the contact never lifts off)"
            ),
            LiftOffError::IllConditioned => write!(
                f,
                "duz-rel/dux-rel: too large for this number type to resolve mu (error bound > 1 % of mu0)"
            ),
            LiftOffError::Inconsistent => {
                write!(f, "lift-off solver: internal check failed (the window did not close)")
            }
            LiftOffError::TooFewSteps { min_steps } => {
                write!(f, "steps: must be >= {min_steps} per period for this drive")
            }
            LiftOffError::PrecisionLimit { max_steps } => write!(
                f,
                "steps: must be <= {max_steps} per period (beyond it rounding grows)"
            ),
        }
    }
}

impl core::error::Error for LiftOffError {}

/// The error bound of [`mu_over_mu0`] in units of μ₀:
/// `(precision_constant + M::MAX_REL_ERROR)·(1 + a + b)` — the permanent
/// solver's form with the stretch scale `1 + a + b` (the band reaches `1 + a`).
/// The ratio to `⟨w⁺⟩ ≥ 1` only shrinks it. Continuous sliding is exact.
/// Measured (`tests/liftoff.rs`, printed by `cargo test -p integration-tests
/// --test liftoff -- --nocapture`): against an independent brute force at
/// N = 65 536 over 300 random scenes the worst gap is 1.2e-9, the brute force's
/// own O(N⁻²) error; f32 against f64 on the same inputs 9.3e-8·(1 + a + b).
pub fn error_bound<T: Float, M: Math<T>>(d: &Drive<T>) -> T {
    (precision_constant::<T>() + T::from_f64(M::MAX_REL_ERROR)) * (T::ONE + d.a + d.b)
}

/// `⟨w⁺⟩ = (π − θ_c + √(a² − 1))/π` (eq. L4): the mean normal force in units
/// of `k_z u_z0`, for `a ≥ 1` (1 at `a = 1`).
pub fn mean_band<T: Float, M: Math<T>>(a: T) -> T {
    Window::of::<M>(T::ONE, a).band_integral(T::ONE, a) / T::TAU
}

/// Checks a drive for the lift-off solvers.
fn check_drive<T: Float>(d: &Drive<T>) -> Result<(), LiftOffError> {
    if !d.is_valid_with_contact(ContactMode::Intermittent) {
        return Err(LiftOffError::BadDrive);
    }
    if d.a < T::ONE {
        return Err(LiftOffError::NoLiftOff);
    }
    if precision_constant::<T>() * (T::ONE + d.a + d.b) > T::from_f64(ILL_CONDITIONED_AT) {
        return Err(LiftOffError::IllConditioned);
    }
    Ok(())
}

fn check_velocity<T: Float>(v: T) -> Result<(), LiftOffError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(LiftOffError::BadVelocity(SceneError::NonFinite(
            Param::Velocity,
        )))
    }
}

/// The contact window `[θ_L, θ_R]` of eq. L1 with its trig.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Window<T> {
    pub(crate) landing: Phase<T>,
    pub(crate) lift_off: Phase<T>,
}

impl<T: Float> Window<T> {
    /// The window of the band `w = d − a cos θ` (`|d| ≤ a`, `a > 0`):
    /// `cos θ_c = d/a`, `θ_c = atan2(√(a² − d²), d)` — eq. L1 for `d = 1`;
    /// shorter than π for `d < 0` (a spring of a curved profile beyond the
    /// mean contact radius, [`crate::model::mdr`]).
    pub(crate) fn of<M: Math<T>>(d: T, a: T) -> Self {
        let root = M::sqrt(((a - d) * (a + d)).max(T::ZERO));
        let theta_c = M::atan2(root, d);
        let (sin_c, cos_c) = (root / a, d / a);
        Window {
            landing: Phase {
                at: theta_c,
                sin: sin_c,
                cos: cos_c,
            },
            lift_off: Phase {
                at: T::TAU - theta_c,
                sin: -sin_c,
                cos: cos_c,
            },
        }
    }

    /// `∫ w dθ` over the window of `w = d − a cos θ` (eq. L4 for `d = 1`).
    pub(crate) fn band_integral(&self, d: T, a: T) -> T {
        d * (self.lift_off.at - self.landing.at) - a * (self.lift_off.sin - self.landing.sin)
    }
}

/// Dimensionless critical velocities `(V_c⁺, V_c⁻)` of a lift-off drive
/// (eq. L5): continuous forward sliding for `V ≥ V_c⁺`, backward for
/// `V ≤ −V_c⁻` (multiply by ωW₀ for m/s).
///
/// # Errors
/// [`LiftOffError::BadDrive`], [`LiftOffError::NoLiftOff`].
pub fn critical_velocities<T: Float, M: Math<T>>(d: &Drive<T>) -> Result<(T, T), LiftOffError> {
    if !d.is_valid_with_contact(ContactMode::Intermittent) {
        return Err(LiftOffError::BadDrive);
    }
    if d.a < T::ONE {
        return Err(LiftOffError::NoLiftOff);
    }
    let window = Window::of::<M>(T::ONE, d.a);
    Ok((
        forward_critical::<T, M>(d, &window),
        forward_critical::<T, M>(&d.mirrored(), &window),
    ))
}

/// `V_c⁺` of eq. L5 (any window: the band offset enters only through it).
pub(crate) fn forward_critical<T: Float, M: Math<T>>(d: &Drive<T>, window: &Window<T>) -> T {
    Shape::of::<M>(d, T::ZERO).forward_critical(window)
}

/// What a drive's walk needs that no band offset changes, at one velocity
/// `V ≥ 0` (forward convention): the peak of `c sin(θ + ψ)` (eq. L5) and the
/// pieces where `h⁺` increases and `h⁻` decreases, before they are clipped
/// to a window. Computed once for all the springs of a curved profile
/// ([`crate::model::mdr`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shape<T> {
    drive: Drive<T>,
    v: T,
    /// `c = |a + b e^{iφ}|`.
    c: T,
    /// The phase of the peak of `c sin(θ + ψ)`, `π/2 − ψ` in `[0, 2π)`.
    peak: T,
    /// `h⁺` increases on these arcs.
    forward: Arcs<T>,
    /// `h⁻` decreases on these arcs (none if `V ≥ c'`).
    backward: Option<Arcs<T>>,
}

/// The arcs `[start + 2πj, start + 2πj + length]` with the trig of their
/// ends (the same for every `j`).
#[derive(Clone, Copy, Debug)]
struct Arcs<T> {
    start: Phase<T>,
    length: T,
    end: Phase<T>,
}

impl<T: Float> Arcs<T> {
    fn new<M: Math<T>>(start: T, length: T) -> Self {
        let (s0, c0) = M::sin_cos(start);
        let (s1, c1) = M::sin_cos(start + length);
        Arcs {
            start: Phase {
                at: start,
                sin: s0,
                cos: c0,
            },
            length,
            end: Phase {
                at: start + length,
                sin: s1,
                cos: c1,
            },
        }
    }

    /// The parts inside the window, in time order, with the trig of their
    /// ends (an end clipped by the window is its landing or lift-off).
    fn clip(&self, window: &Window<T>) -> Pieces<T> {
        let (lo, hi) = (window.landing.at, window.lift_off.at);
        let mut out = [(window.landing, window.lift_off); 2];
        let mut n = 0;
        let first = wrap_tau(self.start.at) - T::TAU;
        for j in 0..3u32 {
            let s = first + T::TAU * T::from_u32(j);
            let e = s + self.length;
            if s.max(lo) < e.min(hi) && n < 2 {
                let l = if s > lo {
                    Phase {
                        at: s,
                        ..self.start
                    }
                } else {
                    window.landing
                };
                let r = if e < hi {
                    Phase { at: e, ..self.end }
                } else {
                    window.lift_off
                };
                out[n] = (l, r);
                n += 1;
            }
        }
        (out, n)
    }
}

/// Pieces of a window (start, end) and how many.
type Pieces<T> = ([(Phase<T>, Phase<T>); 2], usize);

impl<T: Float> Shape<T> {
    /// The shape of `d` at `v ≥ 0`.
    pub(crate) fn of<M: Math<T>>(d: &Drive<T>, v: T) -> Self {
        let (a, bc, bs) = (d.a, d.bc, d.bs);
        // h⁺ increases on θ + ψ ∈ [π − α, 2π + α] (mod 2π), α = asin(V/c).
        let c = M::hypot(a + bc, bs);
        let psi = M::atan2(bs, a + bc);
        let alpha = M::asin((v / c).min(T::ONE));
        // h⁻ decreases on θ + ψ' ∈ [α', π − α'], α' = asin(V/c'), if V < c'.
        let c_back = M::hypot(bc - a, bs);
        let backward = (v < c_back).then(|| {
            let psi_b = M::atan2(bs, bc - a);
            let alpha_b = M::asin((v / c_back).min(T::ONE));
            Arcs::new::<M>(alpha_b - psi_b, T::PI - (alpha_b + alpha_b))
        });
        Shape {
            drive: *d,
            v,
            c,
            peak: wrap_tau(T::FRAC_PI_2 - psi),
            forward: Arcs::new::<M>(T::PI - alpha - psi, T::PI + alpha + alpha),
            backward,
        }
    }

    /// `V_c⁺` of eq. L5 on `window`.
    pub(crate) fn forward_critical(&self, window: &Window<T>) -> T {
        if self.peak >= window.landing.at && self.peak <= window.lift_off.at {
            return self.c;
        }
        let (re, im) = (self.drive.a + self.drive.bc, self.drive.bs);
        let at = |x: &Phase<T>| re * x.sin + im * x.cos;
        at(&window.landing).max(at(&window.lift_off))
    }
}

/// `μ/μ₀` of a scene with lift-off at sliding velocity `v0` (m/s), any sign
/// or zero.
///
/// # Errors
/// [`LiftOffError::NoLiftOff`] for `Δu_z < u_z0` (use [`crate::model::exact`]),
/// [`LiftOffError::BadVelocity`] and the errors of [`mu_over_mu0`].
pub fn solve<T: Float>(scene: &Scene<T>, v0: T) -> Result<T, LiftOffError> {
    solve_with::<T, Libm>(scene, v0)
}

/// [`solve`] with a chosen math backend.
///
/// # Errors
/// As [`solve`].
pub fn solve_with<T: Float, M: Math<T>>(scene: &Scene<T>, v0: T) -> Result<T, LiftOffError> {
    let v = scene
        .dimensionless_velocity(v0)
        .map_err(LiftOffError::BadVelocity)?;
    mu_over_mu0::<T, M>(&scene.drive(), v)
}

/// `μ/μ₀` at dimensionless velocity `V = v₀/(ωW₀)` (any finite `V`, also 0)
/// for a drive with `a ≥ 1`: one exact contact window (module docs).
///
/// # Errors
/// [`LiftOffError::BadDrive`], [`LiftOffError::NoLiftOff`],
/// [`LiftOffError::IllConditioned`], [`LiftOffError::BadVelocity`],
/// [`LiftOffError::Inconsistent`].
pub fn mu_over_mu0<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Result<T, LiftOffError> {
    check_drive(d)?;
    check_velocity(v)?;
    let (drive, v, sign) = if v >= T::ZERO {
        (*d, v, T::ONE)
    } else {
        (d.mirrored(), -v, -T::ONE)
    };
    let window = Window::of::<M>(T::ONE, drive.a);
    let shape = Shape::of::<M>(&drive, v);
    if v >= shape.forward_critical(&window) {
        return Ok(sign);
    }
    Ok(sign * ContactWindow::on(&shape, T::ONE, window).mean_stretch::<M>(None)?)
}

/// `∫ s dθ` over the contact window of the band `w = d − a cos θ`,
/// `|d| < a` (the same walk as [`mu_over_mu0`], which is the case `d = 1`;
/// a spring of a curved profile, [`crate::model::mdr`]), with `∫ w dθ` over
/// the window, in the forward convention `V ≥ 0` of the drive's [`Shape`]
/// (the caller mirrors). The drive is not checked (the caller validated it)
/// except through the walk's internal checks.
///
/// # Errors
/// [`LiftOffError::Inconsistent`].
pub(crate) fn banded_stretch_integral<T: Float, M: Math<T>>(
    shape: &Shape<T>,
    offset: T,
) -> Result<(T, T), LiftOffError> {
    let window = Window::of::<M>(offset, shape.drive.a);
    let band = window.band_integral(offset, shape.drive.a);
    if shape.v >= shape.forward_critical(&window) {
        return Ok((band, band));
    }
    let mu = ContactWindow::on(shape, offset, window).mean_stretch::<M>(None)?;
    Ok((mu * band, band))
}

/// The contact window as a list of arcs (absolute drive phases θ = ωt in
/// `[θ_L, θ_R]`; the rest of the period is in the air) plus `μ/μ₀`.
///
/// # Errors
/// As [`mu_over_mu0`].
pub fn window_arcs<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
) -> Result<(T, Vec<Arc<T>, MAX_ARCS>), LiftOffError> {
    check_drive(d)?;
    check_velocity(v)?;
    banded_window_arcs::<T, M>(d, T::ONE, v)
}

/// The arcs of the window of the band `w = d − a cos θ`, `|d| ≤ a`, with
/// `∫s/∫w` over the window (signed; [`window_arcs`] is the case `d = 1`
/// with the drive checked, here the caller validated it): absolute phases,
/// kinds in the original drive's sense.
///
/// # Errors
/// [`LiftOffError::Inconsistent`].
pub(crate) fn banded_window_arcs<T: Float, M: Math<T>>(
    d: &Drive<T>,
    offset: T,
    v: T,
) -> Result<(T, Vec<Arc<T>, MAX_ARCS>), LiftOffError> {
    let (drive, v, mirrored) = if v >= T::ZERO {
        (*d, v, false)
    } else {
        (d.mirrored(), -v, true)
    };
    let sign = if mirrored { -T::ONE } else { T::ONE };
    let window = Window::of::<M>(offset, drive.a);
    let mut arcs: Vec<Arc<T>, MAX_ARCS> = Vec::new();
    let shape = Shape::of::<M>(&drive, v);
    if v >= shape.forward_critical(&window) {
        let kind = if mirrored {
            ArcKind::SlipBackward
        } else {
            ArcKind::SlipForward
        };
        let _ = arcs.push(Arc {
            kind,
            start: window.landing.at,
            end: window.lift_off.at,
        });
        return Ok((sign, arcs));
    }
    // Arcs of the mirrored problem slip the other way.
    let mut push = |arc: Arc<T>| {
        let kind = match (arc.kind, mirrored) {
            (ArcKind::SlipForward, true) => ArcKind::SlipBackward,
            (ArcKind::SlipBackward, true) => ArcKind::SlipForward,
            (kind, _) => kind,
        };
        let _ = arcs.push(Arc { kind, ..arc });
    };
    let m = ContactWindow::on(&shape, offset, window).mean_stretch::<M>(Some(&mut push))?;
    Ok((sign * m, arcs))
}

/// The sequence of arc kinds of the window of the band `w = d − a cos θ`
/// (as [`banded_stretch_integral`]), in the forward convention of the
/// drive's [`Shape`], encoded base 4 (stick 1, forward slip 2, backward slip 3; zero-length arcs
/// skipped): where it changes with `d`, the spring's `⟨s⟩` may have a kink
/// ([`crate::model::mdr`] splits its quadrature there).
pub(crate) fn banded_signature<T: Float, M: Math<T>>(shape: &Shape<T>, offset: T) -> u32 {
    let window = Window::of::<M>(offset, shape.drive.a);
    if shape.v >= shape.forward_critical(&window) {
        return 2;
    }
    let mut code = 0u32;
    let mut push = |arc: Arc<T>| {
        let digit = arc_digit(arc.kind);
        if arc.end - arc.start > T::from_f64(SIGNATURE_MIN_ARC) && code % 4 != digit {
            code = code.wrapping_mul(4).wrapping_add(digit);
        }
    };
    match ContactWindow::on(shape, offset, window).mean_stretch::<M>(Some(&mut push)) {
        Ok(_) => code,
        Err(_) => u32::MAX,
    }
}

/// Arcs shorter than this (rad) are left out of signatures: a landing's
/// stick of zero length comes and goes with rounding.
pub(crate) const SIGNATURE_MIN_ARC: f64 = 1e-6;

/// Base-4 digit of an arc kind (for signatures).
pub(crate) fn arc_digit(kind: ArcKind) -> u32 {
    match kind {
        ArcKind::Stick => 1,
        ArcKind::SlipForward => 2,
        ArcKind::SlipBackward => 3,
    }
}

/// Where an arc ends and what follows.
enum Event<T> {
    /// Forward slip from `.0` to `.1`.
    Forward(Phase<T>, Phase<T>),
    /// Backward slip from `.0` to `.1`.
    Backward(Phase<T>, Phase<T>),
}

/// First guess of the zero after `x` of a function rising from `f < 0`
/// with slope `f1 ≥ 0` and curvature `f2` at `x`: the zero of its
/// second-order Taylor polynomial, `x + 2|f|/(f1 + √(f1² + 2 f2 |f|))` (exact
/// at a minimum of a sinusoid to third order); `x` (the root finder then
/// starts from regula falsi) where that polynomial has no zero.
fn taylor_guess<T: Float, M: Math<T>>(x: T, f: T, f1: T, f2: T) -> T {
    let disc = f1 * f1 - T::TWO * f2 * f;
    if disc.is_nan() || disc < T::ZERO {
        return x;
    }
    let den = f1 + M::sqrt(disc);
    if den > T::ZERO {
        x - (f + f) / den
    } else {
        x
    }
}

/// One contact window in the forward convention (`V ≥ 0`), absolute phases.
struct ContactWindow<T> {
    /// Band offset `d` of `w = d − a cos θ` (1 for the flat punch).
    d: T,
    a: T,
    bc: T,
    bs: T,
    v: T,
    window: Window<T>,
    /// Pieces where `h⁺` increases (forward slip possible), clipped to the window.
    forward: Pieces<T>,
    /// Pieces where `h⁻` decreases (backward slip possible), clipped to the window.
    backward: Pieces<T>,
    /// Scale of the rounding of `h±` without the stick constant.
    rounding_scale: T,
}

impl<T: Float> ContactWindow<T> {
    /// The window of band offset `offset` for a drive's [`Shape`].
    fn on(shape: &Shape<T>, offset: T, window: Window<T>) -> Self {
        let d = &shape.drive;
        let forward = shape.forward.clip(&window);
        let backward = match shape.backward {
            Some(arcs) => arcs.clip(&window),
            None => ([(window.landing, window.lift_off); 2], 0),
        };
        ContactWindow {
            d: offset,
            a: d.a,
            bc: d.bc,
            bs: d.bs,
            v: shape.v,
            window,
            forward,
            backward,
            rounding_scale: T::ONE + d.b + d.a + shape.v * T::TAU,
        }
    }

    /// `w = d − a cos θ`.
    fn band(&self, x: &Phase<T>) -> T {
        self.d - self.a * x.cos
    }

    /// `X = b cos(θ + φ)`.
    fn drive_swing(&self, x: &Phase<T>) -> T {
        self.bc * x.cos - self.bs * x.sin
    }

    /// `∫ w dθ` over `[x0, x1]`.
    fn band_integral(&self, x0: &Phase<T>, x1: &Phase<T>) -> T {
        self.d * (x1.at - x0.at) - self.a * (x1.sin - x0.sin)
    }

    /// `∫ s dθ` over a stick arc `[x0, x1]`, `s = k + Vθ + X`.
    fn stick_integral(&self, k: T, x0: &Phase<T>, x1: &Phase<T>) -> T {
        k * (x1.at - x0.at)
            + self.v * (x1.at - x0.at) * (x1.at + x0.at) * T::HALF
            + (self.bc * (x1.sin - x0.sin) + self.bs * (x1.cos - x0.cos))
    }

    /// `h⁺ = s − w` (eq. L2) and its first two derivatives.
    fn above_upper_band(&self, k: T, x: &Phase<T>) -> (T, T, T) {
        let (p, q) = (self.bc + self.a, self.bs);
        (
            k - self.d + self.v * x.at + p * x.cos - q * x.sin,
            self.v - p * x.sin - q * x.cos,
            q * x.sin - p * x.cos,
        )
    }

    /// `h⁻ = s + w` (eq. L3) and its first two derivatives.
    fn above_lower_band(&self, k: T, x: &Phase<T>) -> (T, T, T) {
        let (p, q) = (self.bc - self.a, self.bs);
        (
            k + self.d + self.v * x.at + p * x.cos - q * x.sin,
            self.v - p * x.sin - q * x.cos,
            q * x.sin - p * x.cos,
        )
    }

    fn root_tolerance(&self, k: T) -> T {
        T::from_f64(8.0) * T::EPSILON * (self.rounding_scale + k.abs())
    }

    /// The first zero of `h⁺` on an increasing piece after `from`, with that
    /// piece's end (where forward slip ends).
    fn forward_touch<M: Math<T>>(&self, k: T, from: &Phase<T>) -> Option<(Phase<T>, Phase<T>)> {
        let f = |x: &Phase<T>| self.above_upper_band(k, x);
        for &(l, right) in &self.forward.0[..self.forward.1] {
            if right.at <= from.at {
                continue;
            }
            let left = Self::piece_start(&l, from);
            let (at_left, slope, curvature) = f(&left);
            if at_left >= T::ZERO {
                return Some((left, right));
            }
            let at_right = f(&right).0;
            if at_right > T::ZERO {
                let touch = root::<T, M>(
                    &left,
                    (left.at, right.at, at_left, at_right),
                    taylor_guess::<T, M>(left.at, at_left, slope, curvature),
                    self.root_tolerance(k),
                    f,
                );
                return Some((touch, right));
            }
        }
        None
    }

    /// The first zero of `h⁻` on a decreasing piece after `from` and
    /// strictly before `horizon` (a forward touch that comes first, if any),
    /// with that piece's end (where backward slip ends). A zero at or after
    /// `horizon` is not sought: the forward slip comes first.
    fn backward_touch<M: Math<T>>(
        &self,
        k: T,
        from: &Phase<T>,
        horizon: Option<&Phase<T>>,
    ) -> Option<(Phase<T>, Phase<T>)> {
        let f = |x: &Phase<T>| self.above_lower_band(k, x);
        for &(l, r) in &self.backward.0[..self.backward.1] {
            if r.at <= from.at {
                continue;
            }
            if horizon.is_some_and(|h| l.at.max(from.at) >= h.at) {
                return None;
            }
            let left = Self::piece_start(&l, from);
            let (at_left, slope, curvature) = f(&left);
            if at_left <= T::ZERO {
                return Some((left, r));
            }
            // The sign at the piece's end, or at the horizon inside it
            // (h⁻ decreases on the piece: no zero before a positive value).
            let cut = horizon.filter(|h| h.at < r.at);
            let right = match cut {
                Some(h) => *h,
                None => r,
            };
            let at_right = f(&right).0;
            if at_right < T::ZERO {
                let touch = root::<T, M>(
                    &left,
                    (left.at, right.at, at_left, at_right),
                    taylor_guess::<T, M>(left.at, -at_left, -slope, -curvature),
                    self.root_tolerance(k),
                    f,
                );
                return Some((touch, r));
            }
            if cut.is_some() {
                return None;
            }
        }
        None
    }

    /// A piece start `l`, or `from` if later.
    fn piece_start(l: &Phase<T>, from: &Phase<T>) -> Phase<T> {
        if from.at >= l.at {
            *from
        } else {
            *l
        }
    }

    /// `∫ s / ∫ w` over the window: the walk of the module docs.
    fn mean_stretch<M: Math<T>>(
        &self,
        mut record: Option<&mut dyn FnMut(Arc<T>)>,
    ) -> Result<T, LiftOffError> {
        let mut emit = |kind: ArcKind, x0: &Phase<T>, x1: &Phase<T>| {
            if let Some(r) = record.as_mut() {
                if x1.at > x0.at {
                    r(Arc {
                        kind,
                        start: x0.at,
                        end: x1.at,
                    });
                }
            }
        };
        let end = self.window.lift_off;
        let mut total = T::ZERO;
        // Stick from landing with s = 0.
        let mut start = self.window.landing;
        let mut k = -(self.v * start.at) - self.drive_swing(&start);
        for _ in 0..MAX_STEPS {
            let forward = self.forward_touch::<M>(k, &start);
            let backward = self.backward_touch::<M>(k, &start, forward.as_ref().map(|f| &f.0));
            let event = match (forward, backward) {
                (Some(f), Some(b)) if b.0.at < f.0.at => Some(Event::Backward(b.0, b.1)),
                (Some(f), _) => Some(Event::Forward(f.0, f.1)),
                (None, Some(b)) => Some(Event::Backward(b.0, b.1)),
                (None, None) => None,
            };
            let (slip_start, slip_end, sign) = match event {
                Some(Event::Forward(s, e)) => (s, e, T::ONE),
                Some(Event::Backward(s, e)) => (s, e, -T::ONE),
                None => {
                    // Stick to lift-off: there s = w = 0, up to rounding and
                    // the backend's error (a touch its sin/cos misplaced), which
                    // the bound covers: a miss of δ changes ∫s/∫w by at most δ.
                    let s_end = k + self.v * end.at + self.drive_swing(&end);
                    let tol = T::from_f64(64.0) * T::EPSILON * (self.rounding_scale + k.abs())
                        + T::from_f64(M::MAX_REL_ERROR) * self.rounding_scale;
                    if s_end.abs() > tol {
                        return Err(LiftOffError::Inconsistent);
                    }
                    total += self.stick_integral(k, &start, &end);
                    emit(ArcKind::Stick, &start, &end);
                    return self.checked_mean::<M>(total);
                }
            };
            total += self.stick_integral(k, &start, &slip_start);
            total += sign * self.band_integral(&slip_start, &slip_end);
            emit(ArcKind::Stick, &start, &slip_start);
            let kind = if sign > T::ZERO {
                ArcKind::SlipForward
            } else {
                ArcKind::SlipBackward
            };
            emit(kind, &slip_start, &slip_end);
            if slip_end.at >= end.at {
                return self.checked_mean::<M>(total);
            }
            // Stick again from s = ±w.
            k = sign * self.band(&slip_end) - self.v * slip_end.at - self.drive_swing(&slip_end);
            start = slip_end;
        }
        Err(LiftOffError::Inconsistent)
    }

    /// `∫s / ∫w`, checked against `|μ/μ₀| ≤ 1` (exact), allowing rounding
    /// and the backend's stated error (part of the bound), and clamped to ±1.
    /// The rounding of both integrals is absolute, `~ε·scale·Δθ`; for a short
    /// window (`d → −a`) `∫w ~ Δθ³` is far smaller, so the allowance is
    /// relative to it.
    fn checked_mean<M: Math<T>>(&self, total: T) -> Result<T, LiftOffError> {
        let band = self.window.band_integral(self.d, self.a);
        let mu = total / band;
        let length = self.window.lift_off.at - self.window.landing.at;
        let slack = T::from_f64(1e3) * T::EPSILON * (T::ONE + self.rounding_scale * length / band)
            + T::from_f64(M::MAX_REL_ERROR) * self.rounding_scale;
        if !mu.is_finite() || mu.abs() > T::ONE + slack {
            return Err(LiftOffError::Inconsistent);
        }
        Ok(mu.max(-T::ONE).min(T::ONE))
    }
}
