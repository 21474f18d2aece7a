//! The scene: the physical parameters of the single-spring contact (paper §2,
//! eqs. 1–4) and its dimensionless groups (eqs. 25, 26).
//!
//! Units are SI throughout: stiffnesses in N/m, displacements in m, angular
//! frequency in rad/s, phase in rad, velocities in m/s.
//!
//! Internally every solver works in the paper's dimensionless variables:
//! lengths in units of the mean friction-band half-width
//! `W₀ = μ₀ k_z u_z0 / k_x` (the largest stretch the spring holds at the mean
//! normal force), time as the drive phase `θ = ωt`. Then the band is
//! `w(θ) = 1 − a cos θ` with `a = Δu_z/u_z0`, the tangential drive is
//! `u_x(θ) = Vθ + b cos(θ + φ)` with `b = k_xΔu_x/(μ₀ k_z u_z0)`, the velocity
//! is `V = v₀/(ω W₀)`, and `μ/μ₀ = ⟨s⟩` with `s = u_x − u_x,c` the spring stretch.
//! That `μ/μ₀` depends on `(V, a, b, φ)` only is the paper's eq. 25.
//!
//! # Contact mode
//!
//! The paper assumes permanent contact, `Δu_z < u_z0` (`a < 1`), and every
//! constructor refuses `a ≥ 1` with [`SceneError::LiftOff`] unless the scene
//! opts in with [`ContactMode::Intermittent`] ([`Scene::new_with_contact`],
//! [`Scene::from_groups_with_contact`], [`Scene::dimensionless_with_contact`]).
//! With `a ≥ 1` the spring leaves the plane for `|θ| < θ_c`, `cos θ_c = 1/a`,
//! and some quantities change meaning (see [`crate::model::liftoff`]):
//! `μ/μ₀ = ⟨s⟩/⟨w⁺⟩` is normalised by the mean normal force
//! `⟨f_z⟩ = k_z⟨u_z⁺⟩ = k_z u_z0 ⟨w⁺⟩`, not `k_z u_z0`; the critical velocity
//! is the one of the contact window, not eq. 8; and the state at rest is
//! unique (no static interval): the solvers of the permanent contact
//! ([`crate::model::exact`], [`crate::model::fixed_step`],
//! [`crate::model::analytic`], [`crate::model::regime`],
//! [`crate::model::select`]) refuse such drives ([`Drive::is_valid`] is false).

use crate::model::float::{Float, Libm, Math};

/// Which scene parameter an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Param {
    /// μ₀, the local (Coulomb) coefficient of friction.
    Mu0,
    /// k_z, normal contact stiffness.
    Kz,
    /// k_x, tangential contact stiffness.
    Kx,
    /// u_z0, mean indentation.
    Uz0,
    /// Δu_z, normal oscillation amplitude.
    Duz,
    /// Δu_x, tangential oscillation amplitude.
    Dux,
    /// ω, angular drive frequency.
    Omega,
    /// φ, phase of the tangential oscillation against the normal one.
    Phi,
    /// Δu_z/u_z0, relative normal amplitude (eq. 25).
    DuzRel,
    /// k_xΔu_x/(μ₀k_z u_z0), relative tangential amplitude (eq. 25).
    DuxRel,
    /// k_xΔu_x/(μ₀k_zΔu_z), amplitude ratio (eq. 26).
    Ratio,
    /// Sliding velocity v₀.
    Velocity,
}

impl Param {
    /// The name used on the command line and in scene files.
    pub const fn name(self) -> &'static str {
        match self {
            Param::Mu0 => "mu0",
            Param::Kz => "kz",
            Param::Kx => "kx",
            Param::Uz0 => "uz0",
            Param::Duz => "duz",
            Param::Dux => "dux",
            Param::Omega => "omega",
            Param::Phi => "phi",
            Param::DuzRel => "duz-rel",
            Param::DuxRel => "dux-rel",
            Param::Ratio => "ratio",
            Param::Velocity => "v0",
        }
    }
}

/// Why a scene was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SceneError {
    /// The parameter is NaN or infinite.
    NonFinite(Param),
    /// The parameter must be > 0 (μ₀, k_z, k_x, u_z0, ω).
    NotPositive(Param),
    /// An amplitude (Δu_z, Δu_x, or a relative amplitude / ratio) is negative.
    Negative(Param),
    /// Δu_z ≥ u_z0 (or Δu_z/u_z0 ≥ 1): the spring would lift off the plane at
    /// the trough of the normal oscillation, which is outside this model
    /// (the paper assumes Δu_z < u_z0, §2). Only for [`ContactMode::Permanent`]
    /// scenes; [`ContactMode::Intermittent`] accepts it.
    LiftOff,
    /// The amplitude ratio (eq. 26) needs Δu_z > 0.
    RatioNeedsNormalAmplitude,
    /// The parameters are finite but their combination overflows or
    /// underflows the float type (e.g. W₀ = μ₀k_z u_z0/k_x is 0 or ∞).
    OutOfRange(Param),
}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            SceneError::NonFinite(p) => write!(f, "{}: must be a finite number", p.name()),
            SceneError::NotPositive(p) => write!(f, "{}: must be > 0", p.name()),
            SceneError::Negative(p) => write!(f, "{}: must be >= 0", p.name()),
            SceneError::LiftOff => write!(
                f,
                "duz: must be < uz0 (the normal oscillation would lift the contact off the plane)"
            ),
            SceneError::RatioNeedsNormalAmplitude => {
                write!(f, "ratio: needs duz-rel > 0 (it is kx·dux/(mu0·kz·duz))")
            }
            SceneError::OutOfRange(Param::Velocity) => write!(
                f,
                "v0: v0/(ωW0) over- or underflows the number type, or v0 is subnormal"
            ),
            SceneError::OutOfRange(p) => write!(
                f,
                "{}: subnormal, or the scene's derived scales over- or underflow the number type",
                p.name()
            ),
        }
    }
}

/// Whether the spring may leave the plane (`Δu_z ≥ u_z0`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ContactMode {
    /// The paper's assumption `Δu_z < u_z0`: `a ≥ 1` is refused
    /// ([`SceneError::LiftOff`]). The default, and what [`Scene::new`] uses.
    #[default]
    Permanent,
    /// Any `Δu_z ≥ 0`: with `Δu_z ≥ u_z0` the contact lifts off once per
    /// period ([`crate::model::liftoff`]); with `Δu_z < u_z0` the scene is the
    /// same as a permanent one.
    Intermittent,
}

/// Unvalidated physical parameters of a scene (SI units). Turn them into a
/// [`Scene`] with [`Scene::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SceneParams<T> {
    /// μ₀, local coefficient of friction (dimensionless, > 0).
    pub mu0: T,
    /// k_z, normal contact stiffness, N/m (> 0).
    pub kz: T,
    /// k_x, tangential contact stiffness, N/m (> 0).
    pub kx: T,
    /// u_z0, mean indentation, m (> 0), eq. 1.
    pub uz0: T,
    /// Δu_z, normal oscillation amplitude, m (0 ≤ Δu_z < u_z0, or any
    /// Δu_z ≥ 0 with [`ContactMode::Intermittent`]), eq. 1.
    pub duz: T,
    /// Δu_x, tangential oscillation amplitude, m (≥ 0), eq. 2.
    pub dux: T,
    /// ω, angular frequency, rad/s (> 0).
    pub omega: T,
    /// φ, phase of the tangential oscillation, rad (any finite value), eq. 2.
    pub phi: T,
}

/// The paper's dimensionless groups (eq. 25): with these and `v₀/v_c`,
/// `μ/μ₀` is fixed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Groups<T> {
    /// `a = Δu_z/u_z0`, in `[0, 1)` (any `a ≥ 0` for [`ContactMode::Intermittent`]).
    pub duz_rel: T,
    /// `b = k_xΔu_x/(μ₀ k_z u_z0)`, `≥ 0`.
    pub dux_rel: T,
    /// φ, rad.
    pub phi: T,
}

impl<T: Float> Groups<T> {
    /// Groups from eq. 26: `ratio = k_xΔu_x/(μ₀ k_zΔu_z) = b/a`, so `b = ratio · a`.
    ///
    /// # Errors
    /// Non-finite or negative inputs, `a ≥ 1` ([`SceneError::LiftOff`]),
    /// `a = 0` ([`SceneError::RatioNeedsNormalAmplitude`]).
    pub fn from_ratio(duz_rel: T, ratio: T, phi: T) -> Result<Self, SceneError> {
        check_finite(duz_rel, Param::DuzRel)?;
        check_finite(ratio, Param::Ratio)?;
        check_finite(phi, Param::Phi)?;
        if ratio < T::ZERO {
            return Err(SceneError::Negative(Param::Ratio));
        }
        if duz_rel < T::ZERO {
            return Err(SceneError::Negative(Param::DuzRel));
        }
        if duz_rel >= T::ONE {
            return Err(SceneError::LiftOff);
        }
        if duz_rel == T::ZERO {
            return Err(SceneError::RatioNeedsNormalAmplitude);
        }
        let g = Groups {
            duz_rel,
            dux_rel: ratio * duz_rel,
            phi,
        };
        g.validate()?;
        Ok(g)
    }

    /// Checks the groups: finite, `0 ≤ a < 1`, `b ≥ 0`.
    ///
    /// # Errors
    /// The first violated condition.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.validate_with_contact(ContactMode::Permanent)
    }

    /// Checks the groups for a contact mode: finite, `a ≥ 0` (and `a < 1`
    /// for [`ContactMode::Permanent`]), `b ≥ 0`, and none subnormal
    /// ([`SceneError::OutOfRange`]).
    ///
    /// # Errors
    /// The first violated condition.
    pub fn validate_with_contact(&self, contact: ContactMode) -> Result<(), SceneError> {
        check_finite(self.duz_rel, Param::DuzRel)?;
        check_finite(self.dux_rel, Param::DuxRel)?;
        check_finite(self.phi, Param::Phi)?;
        if self.duz_rel < T::ZERO {
            return Err(SceneError::Negative(Param::DuzRel));
        }
        if self.dux_rel < T::ZERO {
            return Err(SceneError::Negative(Param::DuxRel));
        }
        if self.duz_rel >= T::ONE && contact == ContactMode::Permanent {
            return Err(SceneError::LiftOff);
        }
        // Subnormal groups have lost relative precision, as subnormal inputs.
        for (x, param) in [
            (self.duz_rel, Param::DuzRel),
            (self.dux_rel, Param::DuxRel),
            (self.phi, Param::Phi),
        ] {
            if x != T::ZERO {
                check_normal(x.abs(), param)?;
            }
        }
        Ok(())
    }
}

fn check_finite<T: Float>(x: T, p: Param) -> Result<(), SceneError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(SceneError::NonFinite(p))
    }
}

fn check_positive<T: Float>(x: T, p: Param) -> Result<(), SceneError> {
    check_finite(x, p)?;
    if x > T::ZERO {
        Ok(())
    } else {
        Err(SceneError::NotPositive(p))
    }
}

fn check_normal<T: Float>(x: T, p: Param) -> Result<(), SceneError> {
    if x.is_finite() && x >= T::MIN_POSITIVE {
        Ok(())
    } else {
        Err(SceneError::OutOfRange(p))
    }
}

/// `|ln x| < |ln y|` for `x, y ≥ 0` (0 and ∞ infinitely far from 1; false
/// when both are), without a logarithm: `x < y` above 1, `x > y` below, and
/// across 1 `x < 1/y ⇔ x·y < 1`. The rounded product `p` decides unless
/// it is exactly 1 (rounding is monotone and 1 is representable: `p < 1`
/// implies `x·y < 1`, `p > 1` implies `x·y > 1`, through over- and
/// underflow); then the product in f64 does, exact for f32 operands (48
/// significant bits). So for f32 the order is the true one; for f64 a
/// product within rounding of 1 counts as 1, as a logarithm's comparison
/// would round.
fn nearer_one<T: Float>(x: T, y: T) -> bool {
    match (x >= T::ONE, y >= T::ONE) {
        (true, true) => x < y,
        (false, false) => x > y,
        (true, false) => {
            let p = x * y;
            p < T::ONE || (p == T::ONE && x.to_f64() * y.to_f64() < 1.0)
        }
        (false, true) => {
            let p = x * y;
            p > T::ONE || (p == T::ONE && x.to_f64() * y.to_f64() > 1.0)
        }
    }
}

/// `W₀ = μ₀k_z u_z0/k_x`, with the three operations ordered so that every
/// intermediate stays as close to 1 as possible (at each step the operation
/// whose result has the smallest |log|, decided by [`nearer_one`]; on a tie
/// the first in the order k_z, u_z0, k_x as the remaining ones are kept),
/// and every intermediate checked to be a normal number: a subnormal
/// intermediate (e.g. `k_z/k_x` = 1e-43 in f32) would carry only a few
/// significant bits and make the scene silently wrong. (Three comparisons,
/// no logarithm: ordered by six soft-float f64 `log`s, `Scene::new` cost
/// 21 994 instructions on the Cortex-M4F instead of 4 213; the order is the
/// same, `tests/tests/scene.rs`.)
fn w0_of<T: Float>(mu0: T, kz: T, kx: T, uz0: T) -> Result<T, SceneError> {
    let mut acc = mu0;
    // (value, divide?, parameter) still to apply.
    let mut ops = [
        (kz, false, Param::Kz),
        (uz0, false, Param::Uz0),
        (kx, true, Param::Kx),
    ];
    let step = |acc: T, (x, div, _): (T, bool, Param)| if div { acc / x } else { acc * x };
    let mut left = ops.len();
    while left > 0 {
        let mut best = 0;
        let mut best_r = step(acc, ops[0]);
        for (i, &op) in ops[..left].iter().enumerate().skip(1) {
            let r = step(acc, op);
            if nearer_one(r, best_r) {
                best = i;
                best_r = r;
            }
        }
        acc = best_r;
        check_normal(acc, ops[best].2)?;
        ops.swap(best, left - 1);
        left -= 1;
    }
    Ok(acc)
}

/// What [`Scene::new`] checks of the contact's own parameters μ₀, k_z, k_x
/// and of the mean indentation u_z0 — finite and > 0, then normal (not
/// subnormal), in its order — and of the length scale
/// `W₀ = μ₀k_z u_z0/k_x` they form (every intermediate normal): the error
/// [`Scene::new`] returns for them with a zero drive (`Δu_z = Δu_x = φ = 0`,
/// `ω = 1`), without forming the drive (no trigonometry, no logarithm: a
/// few comparisons and multiplications). Returns W₀.
///
/// # Errors
/// [`SceneError::NonFinite`], [`SceneError::NotPositive`],
/// [`SceneError::OutOfRange`], as [`Scene::new`].
pub fn check_contact_params<T: Float>(mu0: T, kz: T, kx: T, uz0: T) -> Result<T, SceneError> {
    // Written out, not looped over an array: at the firmware's `opt-level
    // = "z"` the loop costs an iterator call per element.
    check_positive(mu0, Param::Mu0)?;
    check_positive(kz, Param::Kz)?;
    check_positive(kx, Param::Kx)?;
    check_positive(uz0, Param::Uz0)?;
    check_normal(mu0, Param::Mu0)?;
    check_normal(kz, Param::Kz)?;
    check_normal(kx, Param::Kx)?;
    check_normal(uz0, Param::Uz0)?;
    w0_of(mu0, kz, kx, uz0)
}

/// A validated scene. Every quantity derived from it is finite.
///
/// Holds the physical parameters and the dimensionless drive the solvers use
/// (module docs). Construct with [`Scene::new`], [`Scene::from_groups`] or
/// [`Scene::dimensionless`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Scene<T> {
    params: SceneParams<T>,
    contact: ContactMode,
    /// W₀ = μ₀ k_z u_z0 / k_x, m.
    w0: T,
    drive: Drive<T>,
    /// The drive's dimensionless critical velocities `(c, c')` =
    /// `(|b e^{iφ} + a|, |b e^{iφ} − a|)` (eq. 8 divided by ωW₀), with
    /// [`Libm`]: formed once here, where they are checked, so that each
    /// prediction does not form them again.
    critical: (T, T),
}

/// The dimensionless drive of a scene: `w(θ) = 1 − a cos θ`,
/// `u_x(θ) = Vθ + b cos(θ + φ)`, stored with `b cos φ` and `b sin φ`
/// so that the mirror image (φ → φ + π) is exact.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Drive<T> {
    /// `a = Δu_z/u_z0`.
    pub a: T,
    /// `b = Δu_x/W₀`.
    pub b: T,
    /// `b cos φ`.
    pub bc: T,
    /// `b sin φ`.
    pub bs: T,
}

impl<T: Float> Drive<T> {
    /// The drive from `a`, `b`, φ (computes `cos φ`, `sin φ` with `M`).
    pub fn new<M: Math<T>>(a: T, b: T, phi: T) -> Self {
        let (s, c) = M::sin_cos(phi);
        Drive {
            a,
            b,
            bc: b * c,
            bs: b * s,
        }
    }

    /// Whether the drive is one a validated permanent-contact scene can
    /// produce: all fields finite, `0 ≤ a < 1`, `b ≥ 0`, and `b·(cos φ, sin φ)`
    /// of length `b`. The dimensionless solver entry points refuse any other
    /// drive (its fields are public, so one can be built by hand).
    pub fn is_valid(&self) -> bool {
        self.is_valid_with_contact(ContactMode::Permanent)
    }

    /// [`Drive::is_valid`] for a contact mode: [`ContactMode::Intermittent`]
    /// also accepts any finite `a ≥ 1`.
    pub fn is_valid_with_contact(&self, contact: ContactMode) -> bool {
        let finite =
            self.a.is_finite() && self.b.is_finite() && self.bc.is_finite() && self.bs.is_finite();
        let a_ok = self.a >= T::ZERO && (self.a < T::ONE || contact == ContactMode::Intermittent);
        if !(finite && a_ok && self.b >= T::ZERO) {
            return false;
        }
        // |b e^{iφ}|² = b² (5 % slack: micromath's sin/cos are good to 1e-3),
        // and twice the largest amplitude must stay finite.
        let on_circle = if self.b == T::ZERO {
            self.bc == T::ZERO && self.bs == T::ZERO
        } else {
            let (x, y) = (self.bc / self.b, self.bs / self.b);
            (x * x + y * y - T::ONE).abs() <= T::from_f64(0.05)
        };
        on_circle && (T::TWO * (self.a + self.bc.abs() + self.bs.abs())).is_finite()
    }

    /// The mirror image `x → −x`: `φ → φ + π`, exact (`μ(v, φ) = −μ(−v, φ + π)`).
    #[inline]
    pub fn mirrored(self) -> Self {
        Drive {
            bc: -self.bc,
            bs: -self.bs,
            ..self
        }
    }

    /// Dimensionless critical velocity for forward sliding, `c = |b e^{iφ} + a|`
    /// (eq. 8 with sgn v₀ = +1, divided by ωW₀).
    #[inline]
    pub fn c_forward<M: Math<T>>(&self) -> T {
        M::hypot(self.a + self.bc, self.bs)
    }

    /// Dimensionless critical velocity for backward sliding, `c' = |b e^{iφ} − a|`
    /// (eq. 8 with sgn v₀ = −1).
    #[inline]
    pub fn c_backward<M: Math<T>>(&self) -> T {
        M::hypot(self.bc - self.a, self.bs)
    }
}

impl<T: Float> Scene<T> {
    /// Validates physical parameters.
    ///
    /// # Errors
    /// [`SceneError::NonFinite`] for NaN/∞, [`SceneError::NotPositive`] for
    /// μ₀, k_z, k_x, u_z0 or ω ≤ 0, [`SceneError::Negative`] for Δu_z or
    /// Δu_x < 0, [`SceneError::LiftOff`] for Δu_z ≥ u_z0 and
    /// [`SceneError::OutOfRange`] for a subnormal input (it has lost relative
    /// precision) or if W₀ or a dimensionless group over- or underflows.
    pub fn new(p: SceneParams<T>) -> Result<Self, SceneError> {
        Scene::new_with_contact(p, ContactMode::Permanent)
    }

    /// [`Scene::new`] for a contact mode: [`ContactMode::Intermittent`]
    /// accepts `Δu_z ≥ u_z0` (the contact lifts off, [`crate::model::liftoff`]).
    ///
    /// # Errors
    /// As [`Scene::new`], without [`SceneError::LiftOff`] for an intermittent contact.
    pub fn new_with_contact(p: SceneParams<T>, contact: ContactMode) -> Result<Self, SceneError> {
        let permanent = contact == ContactMode::Permanent;
        check_positive(p.mu0, Param::Mu0)?;
        check_positive(p.kz, Param::Kz)?;
        check_positive(p.kx, Param::Kx)?;
        check_positive(p.uz0, Param::Uz0)?;
        check_finite(p.duz, Param::Duz)?;
        check_finite(p.dux, Param::Dux)?;
        check_positive(p.omega, Param::Omega)?;
        check_finite(p.phi, Param::Phi)?;
        if p.duz < T::ZERO {
            return Err(SceneError::Negative(Param::Duz));
        }
        if p.dux < T::ZERO {
            return Err(SceneError::Negative(Param::Dux));
        }
        if permanent && p.duz >= p.uz0 {
            return Err(SceneError::LiftOff);
        }
        // Subnormal inputs have lost relative precision (an f32 u_z0 of 1e-41 m
        // carries three significant bits): the groups formed from them would be
        // silently wrong, so they are out of range.
        for (x, param) in [
            (p.mu0, Param::Mu0),
            (p.kz, Param::Kz),
            (p.kx, Param::Kx),
            (p.uz0, Param::Uz0),
            (p.omega, Param::Omega),
        ] {
            check_normal(x, param)?;
        }
        for (x, param) in [
            (p.duz, Param::Duz),
            (p.dux, Param::Dux),
            (p.phi, Param::Phi),
        ] {
            if x != T::ZERO {
                check_normal(x.abs(), param)?;
            }
        }
        // W₀ = μ₀ (k_z/k_x) u_z0, formed so that intermediate products stay in range.
        let w0 = w0_of(p.mu0, p.kz, p.kx, p.uz0)?;
        let a = p.duz / p.uz0;
        if permanent && a >= T::ONE {
            return Err(SceneError::LiftOff);
        }
        if !a.is_finite() {
            return Err(SceneError::OutOfRange(Param::Duz));
        }
        let b = p.dux / w0;
        if !b.is_finite() {
            return Err(SceneError::OutOfRange(Param::Dux));
        }
        // ω W₀ must be a usable velocity scale.
        check_normal(p.omega * w0, Param::Omega)?;
        let drive = Drive::new::<Libm>(a, b, p.phi);
        // The critical velocities must be finite too (b ≤ MAX, a < 1 ⇒ hypot finite
        // unless b is within a factor 2 of MAX).
        let critical = (drive.c_forward::<Libm>(), drive.c_backward::<Libm>());
        if !(critical.0 * p.omega * w0).is_finite() || !(critical.1 * p.omega * w0).is_finite() {
            return Err(SceneError::OutOfRange(Param::Dux));
        }
        Ok(Scene {
            params: p,
            contact,
            w0,
            drive,
            critical,
        })
    }

    /// A scene from base quantities and the dimensionless groups (eq. 25):
    /// `Δu_z = a·u_z0`, `Δu_x = b·μ₀k_z u_z0/k_x`. Use
    /// [`Groups::from_ratio`] for eq. 26.
    ///
    /// # Errors
    /// As [`Scene::new`] and [`Groups::validate`].
    pub fn from_groups(
        mu0: T,
        kz: T,
        kx: T,
        uz0: T,
        omega: T,
        g: Groups<T>,
    ) -> Result<Self, SceneError> {
        Scene::from_groups_with_contact(mu0, kz, kx, uz0, omega, g, ContactMode::Permanent)
    }

    /// [`Scene::from_groups`] for a contact mode.
    ///
    /// # Errors
    /// As [`Scene::new_with_contact`] and [`Groups::validate_with_contact`].
    pub fn from_groups_with_contact(
        mu0: T,
        kz: T,
        kx: T,
        uz0: T,
        omega: T,
        g: Groups<T>,
        contact: ContactMode,
    ) -> Result<Self, SceneError> {
        g.validate_with_contact(contact)?;
        check_positive(mu0, Param::Mu0)?;
        check_positive(kz, Param::Kz)?;
        check_positive(kx, Param::Kx)?;
        check_positive(uz0, Param::Uz0)?;
        let w0 = w0_of(mu0, kz, kx, uz0)?;
        Scene::new_with_contact(
            SceneParams {
                mu0,
                kz,
                kx,
                uz0,
                duz: g.duz_rel * uz0,
                dux: g.dux_rel * w0,
                omega,
                phi: g.phi,
            },
            contact,
        )
    }

    /// The purely dimensionless scene: μ₀ = k_z = k_x = u_z0 = ω = 1, so
    /// W₀ = 1, velocities are `V = v₀/(ωW₀)` and forces are `μ/μ₀`.
    ///
    /// # Errors
    /// As [`Groups::validate`].
    pub fn dimensionless(g: Groups<T>) -> Result<Self, SceneError> {
        Scene::from_groups(T::ONE, T::ONE, T::ONE, T::ONE, T::ONE, g)
    }

    /// [`Scene::dimensionless`] for a contact mode.
    ///
    /// # Errors
    /// As [`Groups::validate_with_contact`].
    pub fn dimensionless_with_contact(
        g: Groups<T>,
        contact: ContactMode,
    ) -> Result<Self, SceneError> {
        Scene::from_groups_with_contact(T::ONE, T::ONE, T::ONE, T::ONE, T::ONE, g, contact)
    }

    /// The contact mode the scene was validated with.
    #[inline]
    pub fn contact(&self) -> ContactMode {
        self.contact
    }

    /// Whether the contact lifts off the plane once per period (`a ≥ 1`,
    /// only possible with [`ContactMode::Intermittent`]).
    #[inline]
    pub fn lifts_off(&self) -> bool {
        self.drive.a >= T::ONE
    }

    /// The physical parameters as given.
    #[inline]
    pub fn params(&self) -> &SceneParams<T> {
        &self.params
    }

    /// μ₀.
    #[inline]
    pub fn mu0(&self) -> T {
        self.params.mu0
    }

    /// W₀ = μ₀ k_z u_z0 / k_x, m: the spring stretch at which the mean normal
    /// force lets the contact slip (the unit of length of the solvers).
    #[inline]
    pub fn w0(&self) -> T {
        self.w0
    }

    /// The velocity unit ωW₀, m/s: `V = v₀/(ωW₀)`.
    #[inline]
    pub fn velocity_scale(&self) -> T {
        self.params.omega * self.w0
    }

    /// The dimensionless drive.
    #[inline]
    pub fn drive(&self) -> Drive<T> {
        self.drive
    }

    /// The drive's dimensionless critical velocities `(c, c')`: eq. 8
    /// divided by ωW₀ for sliding forward and backward, `|b e^{iφ} ± a|`
    /// ([`Drive::c_forward`], [`Drive::c_backward`] with [`Libm`], formed
    /// once when the scene is).
    #[inline]
    pub fn dimensionless_critical(&self) -> (T, T) {
        self.critical
    }

    /// The dimensionless groups (eq. 25).
    pub fn groups(&self) -> Groups<T> {
        Groups {
            duz_rel: self.drive.a,
            dux_rel: self.drive.b,
            phi: self.params.phi,
        }
    }

    /// The amplitude ratio of eq. 26, `k_xΔu_x/(μ₀ k_zΔu_z) = b/a`; `None` when Δu_z = 0.
    pub fn ratio(&self) -> Option<T> {
        if self.drive.a > T::ZERO {
            Some(self.drive.b / self.drive.a)
        } else {
            None
        }
    }

    /// Dimensionless velocity `V = v₀/(ωW₀)` of a sliding velocity in m/s.
    ///
    /// # Errors
    /// [`SceneError::NonFinite`] (`Param::Velocity`) for NaN/∞;
    /// [`SceneError::OutOfRange`] (`Param::Velocity`) for a velocity so large
    /// that `V` overflows, or a non-zero one whose `V` (or `v₀` itself) is
    /// subnormal: like a subnormal scene input it has lost relative
    /// precision.
    pub fn dimensionless_velocity(&self, v0: T) -> Result<T, SceneError> {
        check_finite(v0, Param::Velocity)?;
        if v0 == T::ZERO {
            return Ok(v0);
        }
        check_normal(v0.abs(), Param::Velocity)?;
        let v = v0 / self.velocity_scale();
        check_normal(v.abs(), Param::Velocity)?;
        Ok(v)
    }
}
