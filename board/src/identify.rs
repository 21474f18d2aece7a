//! Identification of one transducer mode from a stepped-sine record: the
//! resonance f_r, the quality factor Q, the static gain g and the phase lag θ
//! of the measurement chain, each with a standard error and a 95 %
//! confidence interval, and a verdict that refuses a poor fit by name.
//!
//! No device code and no allocation: the caller (`fricctl device identify`)
//! collects the record and calls [`fit`]. Everything is `f64` (the host runs
//! it; the normal equations square the Jacobian's condition number, which
//! `f32`'s 6e-8 would not carry, and the crate's [`Float`](model_core::float::Float)
//! has no `exp`/`ln`); it still compiles for the firmware's target.
//!
//! # Model
//!
//! The displacement per drive voltage of one mode at the frequency f, with
//! `x(t) = Re(H(f)·U·e^{jΩt})` for a drive `u(t) = Re(U·e^{jΩt})`,
//! `Ω = 2πf` (so the phase *lag* of x behind u is `−arg H`):
//!
//! ```text
//! (1)  H(f) = g·e^{−jθ} / D(f),   D(f) = 1 − r² + j·r/Q,   r = f/f_r
//! (2)  |H| = g / √((1 − r²)² + (r/Q)²),   −arg H = θ + atan2(r/Q, 1 − r²)
//! ```
//!
//! f_r in Hz, Q > 1/2 (dimensionless), g in m/V (> 0, the response at
//! f → 0 without θ), θ in rad (a constant extra lag of the chain: pickup,
//! anti-alias filter, sample delay). This is [`resonator`](super::resonator)'s
//! transfer function with the extra lag θ.
//!
//! # Record and residuals
//!
//! N points `(f_i, H_i)` with strictly increasing `f_i > 0`; optionally the
//! standard deviation `σ_i` (m/V) of the noise on *each* of `Re H_i` and
//! `Im H_i` (independent, equal: circular complex Gaussian noise, as a
//! lock-in's I and Q give). The fit minimises the weighted sum of squares of
//! the 2N real residuals
//!
//! ```text
//! (3)  e_i = w_i·(H(f_i; p) − H_i)  (real and imaginary parts),   SSR = Σ |e_i|²
//! ```
//!
//! with `w_i = 1/σ_i` when σ is given, else `w_i = 1/max|H_i|` (a scale
//! only: the noise is then estimated from the residual, eq. 11).
//!
//! # Parameters
//!
//! The fit runs in well-scaled parameters, with the span's centre
//! `f_c = (f_1 + f_N)/2` and width `S = f_N − f_1`:
//!
//! ```text
//! (4)  p = (a, ln Q, ln g, θ),   a = (f_r − f_c)/S
//! ```
//!
//! so Q and g stay positive, a step in `ln Q`, `ln g` is a relative change,
//! and a step in `a` is a fraction of the span. The columns of the Jacobian
//! (before the weight `w_i`) are, from eq. 1:
//!
//! ```text
//! (5)  ∂H/∂a    = −S·(H/D)·(2r² − j·r/Q)/f_r
//!      ∂H/∂ln Q = H·(j·r/Q)/D
//!      ∂H/∂ln g = H
//!      ∂H/∂θ    = −j·H
//! ```
//!
//! # Start
//!
//! (6) From the record alone: the largest `|H_i|` at index k (at the first
//! or last point: [`NoResonance::PeakAtEdge`]); f_r at the vertex of the
//! parabola through `ln|H|` at k−1, k, k+1 (within their span); the
//! half-power width `f_r/Q` from the interpolated crossings of
//! `|H|² = |H|²_peak/2` on both sides (twice the one-sided width if only one
//! side is in the record; if neither, Q from the phase slope at the peak,
//! `−d(arg H)/df = 2Q/f_r` at `r = 1`); then g and θ from the complex
//! least-squares factor `c = g·e^{−jθ}` of the record on `1/D` (exact for
//! eq. 1 given f_r and Q): `c = Σ w²·conj(1/D_i)·H_i / Σ w²·|1/D_i|²`.
//!
//! # Levenberg–Marquardt
//!
//! With `A = JᵀJ` (4×4), `b = Jᵀe` and `d_k = √A_kk`, each iteration solves
//! in the correlation-scaled form (Marquardt's scaling, so λ is relative and
//! the method does not depend on the units of p)
//!
//! ```text
//! (7)  (Â + λI)·y = −D⁻¹b,   Â = D⁻¹AD⁻¹,   δ = D⁻¹y
//! ```
//!
//! by Cholesky, and accepts `p + δ` if the SSR falls; λ follows Nielsen's
//! rule on the gain ratio ρ = (actual fall)/(fall predicted by the linear
//! model, `−2δ·b − δᵀAδ`): accepted, `λ ← λ·max(1/3, 1 − (2ρ − 1)³)`;
//! rejected, `λ ← λ·ν, ν ← 2ν`. It stops when
//!
//! ```text
//! (8a) max_k |δ_k| ≤ xtol   (a step proposed, accepted or not), or
//! (8b) λ < 1, ρ > 1/4 and both the actual and the predicted fall of the
//!      SSR ≤ ftol·SSR   (an accepted step),
//! ```
//!
//! ([`FitConfig::xtol`] = 1e-10: f_r to 1e-10 of the span, Q and g to
//! 1e-10 relative, θ to 1e-10 rad; [`FitConfig::ftol`] = 1e-10). Near the
//! optimum the steps shrink at the Gauss–Newton rate κ (quadratically on a
//! noise-free record, κ ≪ 1 for a small residual), and what remains after a
//! step δ is ≤ κ/(1 − κ)·δ: within xtol of the optimum once κ ≤ 1/2. A poor
//! model (a large residual) makes κ close to 1 and the steps shrink slowly;
//! 8b stops it where the SSR is flat: the remaining distance in units of
//! the standard errors is then ≈ √(ftol·ν/(1 − κ²)), ~1e-3 at ν = 400,
//! κ = 0.92 (a two-mode record). A record on one flank lets f_r run out of
//! the span with Q unbounded, so LM does not stop or the normal matrix
//! degenerates: reported as [`NoResonance::OutsideSpan`].
//!
//! # Uncertainty
//!
//! At the optimum, with `ν = 2N − 4` degrees of freedom,
//!
//! ```text
//! (9)  C = s²·A⁻¹  (covariance of p),
//! (10) s² = 1 when σ is given (the weights are 1/σ),
//! (11) s² = SSR/ν otherwise (the noise estimated from the residual),
//! ```
//!
//! and the 95 % intervals are `p_k ± q·√C_kk` (eq. 12), with q the normal
//! quantile 1.959 964 when σ is given (the variance is known, so the
//! linearised estimator is normal) and Student's t quantile with ν degrees
//! of freedom otherwise ([`t_quantile_975`], eq. 13: the variance is itself
//! estimated, from ν squares). For f_r and θ (linear in p) the interval is
//! symmetric; for Q and g it is `exp(ln Q ± q·SE)`, positive and asymmetric,
//! and the reported standard error is the delta method's `Q·SE(ln Q)`.
//! A is inverted only if Cholesky on Â gives every pivot `L_kk² > 1e-10`
//! (eq. 14): `L_kk²` is 1 − R² of column k regressed on the columns before
//! it, so a smaller pivot means one parameter is explained by the others
//! to within 1e-10 and its variance is not determined
//! ([`FitError::SingularNormalMatrix`]).
//!
//! # Verdict
//!
//! [`fit`] refuses, in this order:
//! * [`FitError::TooFewPoints`] below [`MIN_POINTS`] = 6 (4 parameters need
//!   ≥ 4 real residuals for a solution and more for a residual check; 6
//!   complex points give ν = 8 degrees of freedom);
//! * [`FitError::SigmaLength`], [`FitError::NonFinite`],
//!   [`FitError::Frequency`], [`FitError::Sigma`] for a malformed record;
//! * [`FitError::NoResonance`] ([`NoResonance::PeakAtEdge`]) when the
//!   largest |H_i| is the first or the last point;
//! * when LM fails: [`NoResonance::OutsideSpan`] if its last f_r is outside
//!   the span, else [`FitError::NoConvergence`] or
//!   [`FitError::SingularNormalMatrix`] (eq. 14);
//! * [`NoResonance::QualityAtBound`] for a fitted `Q ≤ 1/2` (the bound of an
//!   underdamped mode), [`NoResonance::OutsideSpan`] for a fitted f_r outside
//!   the span;
//! * [`FitError::ResidualTooLarge`] when the relative RMS
//!   `(15) ρ_rms = √(Σ|H(f_i) − H_i|²/N) / max_i |H(f_i)|` (the residual
//!   relative to the largest fitted response on the record: ≈ g·Q when a
//!   point lies near f_r; not g·Q itself, which a spurious resonance far
//!   narrower than the frequency step could make as large as it likes
//!   between two points) exceeds [`FitConfig::max_rel_rms`] (5 %);
//! * [`FitError::QualityUndetermined`] when Q's 95 % interval is wider
//!   than a factor [`MAX_Q_SPREAD`] (2);
//! * [`FitError::ChiSquareTooLarge`] when σ is given and the weighted
//!   `χ² = SSR` exceeds the upper quantile of χ²_ν at the one-sided normal
//!   deviate [`FitConfig::chi2_z`] (4.753: false refusal 1e-6 when σ is
//!   right), by Wilson–Hilferty:
//!   `(16) χ²_lim = ν·(1 − 2/(9ν) + z·√(2/(9ν)))³`.
//!
//! [`fit_unchecked`] stops before the residual checks (for plotting a refused
//! fit next to its record).
//!
//! # For the caller
//!
//! The record must be quasi-static: each point measured after the mode has
//! settled (several τ = Q/(π f_r), 16 ms at Q = 1000). A resonance that
//! drifts linearly by `Δ` Hz while the sweep crosses its span S fits eq. 1
//! just as well (the residual cannot tell) with `Q' ≈ Q·(1 − Δ/S)` (17),
//! f_r where the sweep met it: a sweep up and one down give `Q(1 ∓ Δ/S)`,
//! whose mean cancels the first-order bias (`tests/tests/identify.rs`).

// `!(x > 0.0)` is deliberate: it refuses NaN too. Index loops are the
// clearest form of the 4×4 matrix algebra.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

/// One point of a stepped-sine record.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample {
    /// Drive frequency f_i, Hz (> 0; strictly increasing along the record).
    pub freq_hz: f64,
    /// Re H_i, m/V: the in-phase displacement per drive volt (eq. 1's
    /// convention, `x = Re(H·U·e^{jΩt})`).
    pub re_m_per_v: f64,
    /// Im H_i, m/V.
    pub im_m_per_v: f64,
}

/// The fewest points [`fit`] accepts: 6 (ν = 2·6 − 4 = 8 degrees of freedom).
pub const MIN_POINTS: usize = 6;

/// The mode of eq. 1: the fit's point estimates, or a model to evaluate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModeModel {
    /// Resonance f_r, Hz.
    pub resonance_hz: f64,
    /// Quality factor Q (> 1/2).
    pub q: f64,
    /// Static gain g, m/V.
    pub gain_m_per_v: f64,
    /// Extra phase lag θ of the measurement chain, rad.
    pub phase_lag_rad: f64,
}

impl ModeModel {
    /// `(Re H, Im H)` of eq. 1 at `f_hz` (Hz), m/V.
    pub fn response(&self, f_hz: f64) -> (f64, f64) {
        let h = eval_h(
            f_hz,
            self.resonance_hz,
            self.q,
            Complex::expj(-self.phase_lag_rad).scale(self.gain_m_per_v),
        )
        .0;
        (h.re, h.im)
    }

    /// `(|H|, m/V; phase lag −arg H, rad)` of eq. 2 at `f_hz` (Hz), the lag
    /// unwrapped as `θ + atan2(r/Q, 1 − r²)` (in `θ + [0, π]`).
    pub fn magnitude_lag(&self, f_hz: f64) -> (f64, f64) {
        let r = f_hz / self.resonance_hz;
        let (re, im) = (1.0 - r * r, r / self.q);
        (
            self.gain_m_per_v / libm::hypot(re, im),
            self.phase_lag_rad + libm::atan2(im, re),
        )
    }
}

/// One fitted parameter with its uncertainty (eqs. 9–12).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// The estimate (in the parameter's unit).
    pub value: f64,
    /// Its standard error (same unit; for Q and g the delta method's
    /// `value·SE(ln value)`).
    pub std_error: f64,
    /// Lower end of the 95 % confidence interval.
    pub lo: f64,
    /// Upper end of the 95 % confidence interval.
    pub hi: f64,
}

impl Estimate {
    /// `true` if `x` lies in `[lo, hi]`.
    pub fn covers(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }
}

/// The result of a fit.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fit {
    /// The point estimates as a model (eq. 1), to evaluate for a plot.
    pub model: ModeModel,
    /// f_r, Hz (symmetric interval).
    pub resonance_hz: Estimate,
    /// Q (interval `exp(ln Q ± q·SE)`).
    pub q: Estimate,
    /// g, m/V (interval `exp(ln g ± q·SE)`).
    pub gain_m_per_v: Estimate,
    /// θ, rad, in (−π, π] (symmetric interval, which may reach past ±π).
    pub phase_lag_rad: Estimate,
    /// Relative residual RMS ρ_rms of eq. 15 (dimensionless).
    pub rel_rms: f64,
    /// Noise estimated from the residual, `√(Σ|H(f_i) − H_i|²/ν)`, m/V per
    /// component (unweighted; compare with the σ given, if any).
    pub noise_m_per_v: f64,
    /// The weighted `χ² = SSR` when σ was given (else `None`).
    pub chi2: Option<f64>,
    /// Number of points N.
    pub points: usize,
    /// Degrees of freedom ν = 2N − 4.
    pub dof: usize,
    /// The quantile q of the intervals: 1.959 964 (σ given) or
    /// `t_quantile_975(ν)`.
    pub quantile: f64,
    /// Levenberg–Marquardt iterations taken.
    pub iterations: u32,
    /// Covariance C of eq. 9 of the scaled parameters `p = (a, ln Q, ln g,
    /// θ)` of eq. 4 (units: span², 1, 1, rad²).
    pub covariance: [[f64; 4]; 4],
}

/// Settings of the fit and its verdict.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FitConfig {
    /// Largest accepted relative RMS ρ_rms of eq. 15 (default 0.05). A
    /// lock-in's noise is well below 1 % of the resonant response; a
    /// single-mode model that misses by 5 % RMS of its own peak is not this
    /// transducer's model (a second mode in the span, or drift through the
    /// bandwidth during the sweep) and its feed-forward would be off by more
    /// than the displacement loop is meant to trim.
    pub max_rel_rms: f64,
    /// One-sided normal deviate of the χ² test when σ is given (default
    /// 4.753 424, false refusal probability 1e-6 when σ is right: a refusal
    /// stops the user, and a wrong model gives χ²/ν ≫ 1 anyway).
    pub chi2_z: f64,
    /// Iteration limit of Levenberg–Marquardt (default 200; a fit from the
    /// start of eq. 6 takes ≈ 5–20).
    pub max_iterations: u32,
    /// Stopping step of eq. 8a, in the scaled parameters of eq. 4
    /// (default 1e-10).
    pub xtol: f64,
    /// Stopping relative fall of the SSR of eq. 8b (default 1e-10).
    pub ftol: f64,
}

impl FitConfig {
    /// The defaults (documented per field).
    pub const DEFAULT: FitConfig = FitConfig {
        max_rel_rms: 0.05,
        chi2_z: 4.753_424_308_822_899,
        max_iterations: 200,
        xtol: 1e-10,
        ftol: 1e-10,
    };
}

impl Default for FitConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why the record shows no resonance to fit.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NoResonance {
    /// The largest |H_i| is the first or the last point: the record is on
    /// one flank.
    PeakAtEdge,
    /// The fitted f_r (Hz) lies outside the record's span.
    OutsideSpan {
        /// The fitted f_r, Hz.
        resonance_hz: f64,
    },
    /// The fitted Q is at or below its bound 1/2 (no underdamped mode).
    QualityAtBound {
        /// The fitted Q.
        q: f64,
    },
}

/// A refused fit, by name.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FitError {
    /// Fewer than [`MIN_POINTS`] points.
    TooFewPoints {
        /// The number given.
        points: usize,
    },
    /// A frequency, response or σ is NaN or infinite.
    NonFinite {
        /// Index of the first such point.
        index: usize,
    },
    /// A frequency is ≤ 0 or not above the one before.
    Frequency {
        /// Index of the first such point.
        index: usize,
    },
    /// The σ slice's length is not the record's.
    SigmaLength {
        /// The record's length.
        expected: usize,
        /// The σ slice's length.
        got: usize,
    },
    /// A σ is ≤ 0.
    Sigma {
        /// Index of the first such σ.
        index: usize,
    },
    /// No resonance in the span.
    NoResonance(NoResonance),
    /// The normal matrix is singular (eq. 14).
    SingularNormalMatrix,
    /// Levenberg–Marquardt did not meet eq. 8 within the iteration limit.
    NoConvergence {
        /// Iterations taken.
        iterations: u32,
    },
    /// The relative residual RMS (eq. 15) exceeds the limit.
    ResidualTooLarge {
        /// ρ_rms.
        rel_rms: f64,
        /// The limit ([`FitConfig::max_rel_rms`]).
        limit: f64,
    },
    /// The record does not determine Q: its 95 % interval is wider than a
    /// factor [`MAX_Q_SPREAD`] (the points miss the mode's band: a mode far
    /// narrower than the frequency step).
    QualityUndetermined {
        /// Lower end of Q's interval.
        lo: f64,
        /// Upper end of Q's interval.
        hi: f64,
    },
    /// With σ given, χ² exceeds its quantile (eq. 16).
    ChiSquareTooLarge {
        /// The weighted χ².
        chi2: f64,
        /// Its limit.
        limit: f64,
        /// Degrees of freedom ν.
        dof: usize,
    },
}

impl core::fmt::Display for FitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            FitError::TooFewPoints { points } => write!(
                f,
                "too few points: {points} (the fit needs at least {MIN_POINTS})"
            ),
            FitError::NonFinite { index } => {
                write!(f, "non-finite value at point {index}")
            }
            FitError::Frequency { index } => write!(
                f,
                "frequency at point {index} is not positive or not above the one before"
            ),
            FitError::SigmaLength { expected, got } => {
                write!(f, "{got} standard deviations for {expected} points")
            }
            FitError::Sigma { index } => {
                write!(f, "standard deviation at point {index} is not positive")
            }
            FitError::NoResonance(NoResonance::PeakAtEdge) => f.write_str(
                "no resonance in the span: the largest response is at an end of the sweep",
            ),
            FitError::NoResonance(NoResonance::OutsideSpan { resonance_hz }) => write!(
                f,
                "no resonance in the span: the fit puts it at {resonance_hz} Hz, outside the sweep"
            ),
            FitError::NoResonance(NoResonance::QualityAtBound { q }) => write!(
                f,
                "no resonance in the span: the fitted Q = {q} is not above 1/2"
            ),
            FitError::SingularNormalMatrix => f.write_str(
                "singular normal matrix: the record does not determine all four parameters",
            ),
            FitError::NoConvergence { iterations } => {
                write!(f, "the fit did not converge in {iterations} iterations")
            }
            FitError::ResidualTooLarge { rel_rms, limit } => write!(
                f,
                "residual too large: RMS {:.2} % of the largest fitted response (limit {:.2} %)",
                rel_rms * 100.0,
                limit * 100.0
            ),
            FitError::QualityUndetermined { lo, hi } => write!(
                f,
                "Q is not determined by the record: its 95 % interval [{lo:.3e}, {hi:.3e}] is \
                 wider than a factor {MAX_Q_SPREAD} (a mode far narrower than the frequency step?)"
            ),
            FitError::ChiSquareTooLarge { chi2, limit, dof } => write!(
                f,
                "residual too large for the given noise: chi-square {chi2:.1} > {limit:.1} ({dof} degrees of freedom)"
            ),
        }
    }
}

impl core::error::Error for FitError {}

/// Fits eq. 1 to the record and gives the verdict (module docs).
///
/// `sigma_m_per_v`, if given, holds one σ_i (m/V, > 0) per point: the
/// standard deviation of the noise on each of Re H_i and Im H_i.
///
/// # Errors
/// [`FitError`], by name.
pub fn fit(
    samples: &[Sample],
    sigma_m_per_v: Option<&[f64]>,
    cfg: &FitConfig,
) -> Result<Fit, FitError> {
    let fit = fit_unchecked(samples, sigma_m_per_v, cfg)?;
    let m = fit.model;
    let (lo, hi) = (samples[0].freq_hz, samples[samples.len() - 1].freq_hz);
    if !(m.q > 0.5) {
        return Err(FitError::NoResonance(NoResonance::QualityAtBound {
            q: m.q,
        }));
    }
    if !(lo <= m.resonance_hz && m.resonance_hz <= hi) {
        return Err(FitError::NoResonance(NoResonance::OutsideSpan {
            resonance_hz: m.resonance_hz,
        }));
    }
    if !(fit.rel_rms <= cfg.max_rel_rms) {
        return Err(FitError::ResidualTooLarge {
            rel_rms: fit.rel_rms,
            limit: cfg.max_rel_rms,
        });
    }
    if let Some(chi2) = fit.chi2 {
        let limit = chi2_upper(fit.dof, cfg.chi2_z);
        if !(chi2 <= limit) {
            return Err(FitError::ChiSquareTooLarge {
                chi2,
                limit,
                dof: fit.dof,
            });
        }
    }
    let (q_lo, q_hi) = (fit.q.lo, fit.q.hi);
    if !(q_hi <= MAX_Q_SPREAD * q_lo) {
        return Err(FitError::QualityUndetermined { lo: q_lo, hi: q_hi });
    }
    Ok(fit)
}

/// The widest interval of Q a fit is accepted with, as the ratio of its
/// ends (2: Q known to about ±18 % at one standard error). A record whose
/// points straddle the mode's band gives ±0.1 %; one that misses a mode far
/// narrower than its step gives intervals over decades (seen: [0.5, 6e11]
/// for a Q-10⁵ mode swept in 13 Hz steps).
pub const MAX_Q_SPREAD: f64 = 2.0;

/// The fit of [`fit`] without its verdict on the result (the span, Q and
/// residual checks), e.g. to plot a refused fit with its record.
///
/// # Errors
/// [`FitError`] for a record that cannot be fitted: too few points,
/// malformed, peak at an edge, singular, not converged.
pub fn fit_unchecked(
    samples: &[Sample],
    sigma_m_per_v: Option<&[f64]>,
    cfg: &FitConfig,
) -> Result<Fit, FitError> {
    let n = samples.len();
    validate(samples, sigma_m_per_v)?;
    let mut peak = 0.0f64;
    for s in samples {
        peak = peak.max(libm::hypot(s.re_m_per_v, s.im_m_per_v));
    }
    if !(peak > 0.0) {
        // All-zero response: no peak anywhere, in particular not inside.
        return Err(FitError::NoResonance(NoResonance::PeakAtEdge));
    }
    let rec = Record {
        samples,
        sigma: sigma_m_per_v,
        scale: 1.0 / peak,
        fc: 0.5 * (samples[0].freq_hz + samples[n - 1].freq_hz),
        span: samples[n - 1].freq_hz - samples[0].freq_hz,
    };
    let p0 = start(&rec)?;
    let it = levenberg_marquardt(&rec, p0, cfg);
    let (p, iterations) = (it.p, it.iterations);
    let normal = rec
        .normal(&p)
        .and_then(|ne| inverse_spd(&ne.a).map(|inv| (ne, inv)));
    let failure = match (it.status, normal) {
        (Status::Converged, Some(ok)) => Ok(ok),
        (Status::NotConverged, _) => Err(FitError::NoConvergence { iterations }),
        _ => Err(FitError::SingularNormalMatrix),
    };
    let (ne, inv) = failure.map_err(|e| {
        // A record on one flank lets f_r run out of the span, with Q
        // unbounded (the flank alone does not determine it): LM then does
        // not converge or its normal matrix degenerates. Say why.
        let fr = rec.fc + rec.span * p[0];
        if !(samples[0].freq_hz <= fr && fr <= samples[n - 1].freq_hz) {
            FitError::NoResonance(NoResonance::OutsideSpan { resonance_hz: fr })
        } else {
            e
        }
    })?;

    let dof = 2 * n - 4;
    let nu = dof as f64;
    let (s2, quantile, chi2) = match sigma_m_per_v {
        Some(_) => (1.0, Z_975, Some(ne.ssr)),
        None => (ne.ssr / nu, t_quantile_975(dof), None),
    };
    let mut cov = [[0.0; 4]; 4];
    for (ci, ii) in cov.iter_mut().zip(inv.iter()) {
        for (c, x) in ci.iter_mut().zip(ii.iter()) {
            *c = s2 * x;
        }
    }
    let se = |k: usize| libm::sqrt(cov[k][k].max(0.0));
    let linear = |value: f64, se: f64| Estimate {
        value,
        std_error: se,
        lo: value - quantile * se,
        hi: value + quantile * se,
    };
    let logarithmic = |ln: f64, se: f64| {
        let value = libm::exp(ln);
        Estimate {
            value,
            std_error: value * se,
            lo: libm::exp(ln - quantile * se),
            hi: libm::exp(ln + quantile * se),
        }
    };
    let fr = rec.fc + rec.span * p[0];
    let theta = wrap_pi(p[3]);
    let model = ModeModel {
        resonance_hz: fr,
        q: libm::exp(p[1]),
        gain_m_per_v: libm::exp(p[2]),
        phase_lag_rad: theta,
    };
    // Unweighted residual (eq. 15 and the noise estimate).
    let c = Complex::expj(-theta).scale(model.gain_m_per_v);
    let (mut ss, mut largest) = (0.0, 0.0f64);
    for s in samples {
        let h = eval_h(s.freq_hz, fr, model.q, c).0;
        ss += sq(h.re - s.re_m_per_v) + sq(h.im - s.im_m_per_v);
        largest = largest.max(libm::hypot(h.re, h.im));
    }
    Ok(Fit {
        model,
        resonance_hz: linear(fr, rec.span * se(0)),
        q: logarithmic(p[1], se(1)),
        gain_m_per_v: logarithmic(p[2], se(2)),
        phase_lag_rad: linear(theta, se(3)),
        rel_rms: libm::sqrt(ss / n as f64) / largest,
        noise_m_per_v: libm::sqrt(ss / nu),
        chi2,
        points: n,
        dof,
        quantile,
        iterations,
        covariance: cov,
    })
}

/// The normal 0.975 quantile, for intervals with σ given (eq. 12).
pub const Z_975: f64 = 1.959_963_984_540_054;

/// Student's t 0.975 quantile with `dof` degrees of freedom (eq. 13), by
/// the Cornish–Fisher expansion about the normal quantile z (Hill 1970,
/// terms to ν⁻⁴):
///
/// ```text
/// (13) t ≈ z + g₁/ν + g₂/ν² + g₃/ν³ + g₄/ν⁴,
///      g₁ = (z³ + z)/4,  g₂ = (5z⁵ + 16z³ + 3z)/96,
///      g₃ = (3z⁷ + 19z⁵ + 17z³ − 15z)/384,
///      g₄ = (79z⁹ + 776z⁷ + 1482z⁵ − 1920z³ − 945z)/92160.
/// ```
///
/// Within 5e-5 of the exact quantile for ν ≥ 8 (the smallest ν of a fit:
/// 2.30603 against 2.30600), closer for larger ν. `dof = 0` gives +∞.
pub fn t_quantile_975(dof: usize) -> f64 {
    if dof == 0 {
        return f64::INFINITY;
    }
    let z = Z_975;
    let z2 = z * z;
    let z3 = z2 * z;
    let z5 = z3 * z2;
    let z7 = z5 * z2;
    let z9 = z7 * z2;
    let g1 = (z3 + z) / 4.0;
    let g2 = (5.0 * z5 + 16.0 * z3 + 3.0 * z) / 96.0;
    let g3 = (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / 384.0;
    let g4 = (79.0 * z9 + 776.0 * z7 + 1482.0 * z5 - 1920.0 * z3 - 945.0 * z) / 92160.0;
    let u = 1.0 / dof as f64;
    z + u * (g1 + u * (g2 + u * (g3 + u * g4)))
}

/// Upper χ²_ν quantile at the one-sided normal deviate `z` by
/// Wilson–Hilferty (eq. 16).
pub fn chi2_upper(dof: usize, z: f64) -> f64 {
    let nu = dof as f64;
    let k = 2.0 / (9.0 * nu);
    let c = 1.0 - k + z * libm::sqrt(k);
    nu * c * c * c
}

// ---------------------------------------------------------------------------

fn validate(samples: &[Sample], sigma: Option<&[f64]>) -> Result<(), FitError> {
    let n = samples.len();
    if n < MIN_POINTS {
        return Err(FitError::TooFewPoints { points: n });
    }
    if let Some(s) = sigma {
        if s.len() != n {
            return Err(FitError::SigmaLength {
                expected: n,
                got: s.len(),
            });
        }
    }
    for (i, s) in samples.iter().enumerate() {
        let sig = sigma.map_or(1.0, |v| v[i]);
        if !(s.freq_hz.is_finite()
            && s.re_m_per_v.is_finite()
            && s.im_m_per_v.is_finite()
            && sig.is_finite())
        {
            return Err(FitError::NonFinite { index: i });
        }
    }
    for (i, s) in samples.iter().enumerate() {
        if !(s.freq_hz > 0.0) || (i > 0 && !(s.freq_hz > samples[i - 1].freq_hz)) {
            return Err(FitError::Frequency { index: i });
        }
    }
    if let Some(sig) = sigma {
        if let Some(i) = sig.iter().position(|&x| !(x > 0.0)) {
            return Err(FitError::Sigma { index: i });
        }
    }
    Ok(())
}

/// The record with its weights and the scaling of eq. 4.
struct Record<'a> {
    samples: &'a [Sample],
    sigma: Option<&'a [f64]>,
    /// `1/max|H_i|`, the weight when σ is not given.
    scale: f64,
    /// f_c, Hz.
    fc: f64,
    /// S, Hz.
    span: f64,
}

/// JᵀJ, Jᵀe and SSR at one p.
struct Normal {
    a: [[f64; 4]; 4],
    b: [f64; 4],
    ssr: f64,
}

impl Record<'_> {
    fn weight(&self, i: usize) -> f64 {
        self.sigma.map_or(self.scale, |s| 1.0 / s[i])
    }

    /// `(f_r, Q, c = g·e^{−jθ})` of p, or `None` if f_r ≤ 0 or non-finite.
    fn unpack(&self, p: &[f64; 4]) -> Option<(f64, f64, Complex)> {
        let fr = self.fc + self.span * p[0];
        let q = libm::exp(p[1]);
        let c = Complex::expj(-p[3]).scale(libm::exp(p[2]));
        (fr > 0.0 && fr.is_finite() && q > 0.0 && q.is_finite() && c.is_finite())
            .then_some((fr, q, c))
    }

    /// SSR of eq. 3 at p (+∞ where the model is undefined).
    fn ssr(&self, p: &[f64; 4]) -> f64 {
        let Some((fr, q, c)) = self.unpack(p) else {
            return f64::INFINITY;
        };
        let mut ssr = 0.0;
        for (i, s) in self.samples.iter().enumerate() {
            let w = self.weight(i);
            let h = eval_h(s.freq_hz, fr, q, c).0;
            ssr += sq(w * (h.re - s.re_m_per_v)) + sq(w * (h.im - s.im_m_per_v));
        }
        if ssr.is_finite() {
            ssr
        } else {
            f64::INFINITY
        }
    }

    /// The normal equations at p (eqs. 3, 5).
    fn normal(&self, p: &[f64; 4]) -> Option<Normal> {
        let (fr, q, c) = self.unpack(p)?;
        let mut ne = Normal {
            a: [[0.0; 4]; 4],
            b: [0.0; 4],
            ssr: 0.0,
        };
        for (i, s) in self.samples.iter().enumerate() {
            let w = self.weight(i);
            let (h, d, r) = eval_h(s.freq_hz, fr, q, c);
            let h_over_d = h.div(d);
            let cols = [
                h_over_d
                    .mul(Complex::new(2.0 * r * r, -r / q))
                    .scale(-self.span / fr),
                h_over_d.mul(Complex::new(0.0, r / q)),
                h,
                Complex::new(h.im, -h.re),
            ];
            let e = Complex::new(w * (h.re - s.re_m_per_v), w * (h.im - s.im_m_per_v));
            for j in 0..4 {
                let (jr, ji) = (w * cols[j].re, w * cols[j].im);
                ne.b[j] += jr * e.re + ji * e.im;
                for k in 0..=j {
                    ne.a[j][k] += jr * w * cols[k].re + ji * w * cols[k].im;
                }
            }
            ne.ssr += e.re * e.re + e.im * e.im;
        }
        for j in 0..4 {
            for k in 0..j {
                ne.a[k][j] = ne.a[j][k];
            }
        }
        let finite = ne.ssr.is_finite()
            && ne.b.iter().all(|x| x.is_finite())
            && ne.a.iter().flatten().all(|x| x.is_finite());
        finite.then_some(ne)
    }
}

/// The start of eq. 6, as p of eq. 4.
fn start(rec: &Record<'_>) -> Result<[f64; 4], FitError> {
    let s = rec.samples;
    let n = s.len();
    let mag = |i: usize| libm::hypot(s[i].re_m_per_v, s[i].im_m_per_v);
    let mut k = 0;
    for i in 1..n {
        if mag(i) > mag(k) {
            k = i;
        }
    }
    if k == 0 || k == n - 1 {
        return Err(FitError::NoResonance(NoResonance::PeakAtEdge));
    }
    // Vertex of the parabola through (f, ln|H|) at k−1, k, k+1.
    let (x0, x1, x2) = (s[k - 1].freq_hz, s[k].freq_hz, s[k + 1].freq_hz);
    let (y0, y1, y2) = (
        libm::log(mag(k - 1)),
        libm::log(mag(k)),
        libm::log(mag(k + 1)),
    );
    // Newton form through x0, x1, x2 (divided differences d01, d2):
    // y = y0 + d01·(x − x0) + d2·(x − x0)(x − x1).
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let d2 = (d12 - d01) / (x2 - x0);
    let (mut f0, mut ln_peak) = (x1, y1);
    if d2 < 0.0 && d2.is_finite() {
        // y' = d01 + d2·(2x − x0 − x1) = 0 at the vertex.
        let xv = (0.5 * (x0 + x1) - d01 / (2.0 * d2)).clamp(x0, x2);
        let yv = y0 + d01 * (xv - x0) + d2 * (xv - x0) * (xv - x1);
        if xv.is_finite() && yv.is_finite() {
            f0 = xv;
            ln_peak = yv.max(y1);
        }
    }
    // Half-power crossings, interpolated linearly in |H|².
    let half = 0.5 * libm::exp(2.0 * ln_peak);
    let m2 = |i: usize| mag(i) * mag(i);
    let cross = |i: usize, j: usize| {
        let (a, b) = (m2(i), m2(j));
        s[i].freq_hz + (s[j].freq_hz - s[i].freq_hz) * (half - a) / (b - a)
    };
    let lo = (0..k)
        .rev()
        .find(|&i| m2(i) < half)
        .map(|i| cross(i, i + 1));
    let hi = (k + 1..n).find(|&i| m2(i) < half).map(|i| cross(i - 1, i));
    let width = match (lo, hi) {
        (Some(l), Some(h)) => h - l,
        (Some(l), None) => 2.0 * (f0 - l),
        (None, Some(h)) => 2.0 * (h - f0),
        (None, None) => {
            // Phase slope −d(arg H)/df = 2Q/f_r at the peak.
            let a0 = libm::atan2(s[k - 1].im_m_per_v, s[k - 1].re_m_per_v);
            let a2 = libm::atan2(s[k + 1].im_m_per_v, s[k + 1].re_m_per_v);
            let slope = -wrap_pi(a2 - a0) / (x2 - x0);
            if slope > 0.0 {
                2.0 / slope
            } else {
                rec.span
            }
        }
    };
    let width = if width > 0.0 && width.is_finite() {
        width
    } else {
        x2 - x0
    };
    let q0 = (f0 / width).max(0.75);
    // c = g·e^{−jθ} by complex least squares of H_i on 1/D_i.
    let (mut num, mut den) = (Complex::new(0.0, 0.0), 0.0);
    for (i, p) in s.iter().enumerate() {
        let w2 = sq(rec.weight(i));
        let u = eval_h(p.freq_hz, f0, q0, Complex::new(1.0, 0.0)).0;
        let h = Complex::new(p.re_m_per_v, p.im_m_per_v);
        num = num.add(u.conj().mul(h).scale(w2));
        den += w2 * (u.re * u.re + u.im * u.im);
    }
    let c = num.scale(1.0 / den);
    let g0 = libm::hypot(c.re, c.im);
    if !(g0 > 0.0 && g0.is_finite()) {
        return Err(FitError::SingularNormalMatrix);
    }
    Ok([
        (f0 - rec.fc) / rec.span,
        libm::log(q0),
        libm::log(g0),
        -libm::atan2(c.im, c.re),
    ])
}

/// Where Levenberg–Marquardt stopped.
struct Iterate {
    /// The last accepted p.
    p: [f64; 4],
    /// Iterations taken.
    iterations: u32,
    /// Why it stopped.
    status: Status,
}

/// Why Levenberg–Marquardt stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Status {
    /// Eq. 8 met.
    Converged,
    /// Iteration limit, or λ beyond 1e30 without an accepted step.
    NotConverged,
    /// The normal equations at p are not finite or have a zero column.
    Singular,
}

/// Levenberg–Marquardt (eqs. 7–8) from `p`.
fn levenberg_marquardt(rec: &Record<'_>, mut p: [f64; 4], cfg: &FitConfig) -> Iterate {
    let stop = |p, iterations, status| Iterate {
        p,
        iterations,
        status,
    };
    let Some(mut ne) = rec.normal(&p) else {
        return stop(p, 0, Status::Singular);
    };
    let (mut lambda, mut nu) = (1e-3, 2.0);
    for it in 1..=cfg.max_iterations {
        let mut d = [0.0; 4];
        for k in 0..4 {
            d[k] = libm::sqrt(ne.a[k][k]);
            if !(d[k] > 0.0) {
                return stop(p, it, Status::Singular);
            }
        }
        let mut m = [[0.0; 4]; 4];
        let mut rhs = [0.0; 4];
        for j in 0..4 {
            for k in 0..4 {
                m[j][k] = ne.a[j][k] / (d[j] * d[k]);
            }
            m[j][j] += lambda;
            rhs[j] = -ne.b[j] / d[j];
        }
        let Some(y) = cholesky(&m).map(|l| cholesky_solve(&l, &rhs)) else {
            lambda *= nu;
            nu *= 2.0;
            continue;
        };
        let mut delta = [0.0; 4];
        for k in 0..4 {
            delta[k] = y[k] / d[k];
        }
        let small = delta.iter().all(|x| x.abs() <= cfg.xtol);
        let mut trial = p;
        for k in 0..4 {
            trial[k] += delta[k];
        }
        let ssr_t = rec.ssr(&trial);
        // Fall predicted by the linear model: −2δ·b − δᵀAδ.
        let mut quad = 0.0;
        for j in 0..4 {
            for k in 0..4 {
                quad += delta[j] * ne.a[j][k] * delta[k];
            }
        }
        let bd: f64 = (0..4).map(|k| delta[k] * ne.b[k]).sum();
        let predicted = -2.0 * bd - quad;
        let actual = ne.ssr - ssr_t;
        let mut flat = false;
        if actual > 0.0 {
            let rho = if predicted > 0.0 {
                actual / predicted
            } else {
                1.0
            };
            // Eq. 8b: a near-Gauss–Newton step (λ < 1) that the linear model
            // predicts well (ρ > 1/4) and that lowers the SSR by ≤ ftol.
            flat = lambda < 1.0
                && rho > 0.25
                && actual <= cfg.ftol * ne.ssr
                && predicted <= cfg.ftol * ne.ssr;
            p = trial;
            lambda *= (1.0 - sq(2.0 * rho - 1.0) * (2.0 * rho - 1.0)).max(1.0 / 3.0);
            nu = 2.0;
            match rec.normal(&p) {
                Some(x) => ne = x,
                None => return stop(p, it, Status::Singular),
            }
        } else {
            lambda *= nu;
            nu *= 2.0;
        }
        if small || flat {
            return stop(p, it, Status::Converged);
        }
        if !(lambda < 1e30) {
            return stop(p, it, Status::NotConverged);
        }
    }
    stop(p, cfg.max_iterations, Status::NotConverged)
}

/// Cholesky factor L (lower) of a 4×4 SPD matrix, `None` unless every pivot
/// `L_kk² > 1e-10·M_kk` (eq. 14 when M has a unit diagonal).
fn cholesky(m: &[[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let mut l = [[0.0; 4]; 4];
    for j in 0..4 {
        let mut s = m[j][j];
        for k in 0..j {
            s -= l[j][k] * l[j][k];
        }
        if !(s > 1e-10 * m[j][j]) {
            return None;
        }
        l[j][j] = libm::sqrt(s);
        for i in j + 1..4 {
            let mut t = m[i][j];
            for k in 0..j {
                t -= l[i][k] * l[j][k];
            }
            l[i][j] = t / l[j][j];
        }
    }
    Some(l)
}

/// Solves `L·Lᵀ·x = b`.
fn cholesky_solve(l: &[[f64; 4]; 4], b: &[f64; 4]) -> [f64; 4] {
    let mut y = [0.0; 4];
    for i in 0..4 {
        let mut t = b[i];
        for k in 0..i {
            t -= l[i][k] * y[k];
        }
        y[i] = t / l[i][i];
    }
    let mut x = [0.0; 4];
    for i in (0..4).rev() {
        let mut t = y[i];
        for k in i + 1..4 {
            t -= l[k][i] * x[k];
        }
        x[i] = t / l[i][i];
    }
    x
}

/// A⁻¹ of the normal matrix through its correlation-scaled form (eq. 14),
/// `None` if singular.
fn inverse_spd(a: &[[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let mut d = [0.0; 4];
    for k in 0..4 {
        d[k] = libm::sqrt(a[k][k]);
        if !(d[k] > 0.0 && d[k].is_finite()) {
            return None;
        }
    }
    let mut m = [[0.0; 4]; 4];
    for j in 0..4 {
        for k in 0..4 {
            m[j][k] = a[j][k] / (d[j] * d[k]);
        }
    }
    let l = cholesky(&m)?;
    let mut inv = [[0.0; 4]; 4];
    for k in 0..4 {
        let mut e = [0.0; 4];
        e[k] = 1.0;
        let col = cholesky_solve(&l, &e);
        for j in 0..4 {
            inv[j][k] = col[j] / (d[j] * d[k]);
        }
    }
    Some(inv)
}

/// x².
fn sq(x: f64) -> f64 {
    x * x
}

/// Wraps an angle into (−π, π].
fn wrap_pi(x: f64) -> f64 {
    use core::f64::consts::{PI, TAU};
    let y = x - TAU * libm::round(x / TAU);
    if y <= -PI {
        y + TAU
    } else {
        y
    }
}

/// `(H, D, r)` of eq. 1 at f with `c = g·e^{−jθ}`.
fn eval_h(f: f64, fr: f64, q: f64, c: Complex) -> (Complex, Complex, f64) {
    let r = f / fr;
    let d = Complex::new(1.0 - r * r, r / q);
    (c.div(d), d, r)
}

/// The few complex operations the fit needs.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Complex {
    re: f64,
    im: f64,
}

impl Complex {
    fn new(re: f64, im: f64) -> Self {
        Complex { re, im }
    }
    fn expj(x: f64) -> Self {
        let (s, c) = libm::sincos(x);
        Complex::new(c, s)
    }
    fn scale(self, k: f64) -> Self {
        Complex::new(self.re * k, self.im * k)
    }
    fn add(self, o: Self) -> Self {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    fn mul(self, o: Self) -> Self {
        Complex::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn conj(self) -> Self {
        Complex::new(self.re, -self.im)
    }
    fn div(self, o: Self) -> Self {
        let n = o.re * o.re + o.im * o.im;
        Complex::new(
            (self.re * o.re + self.im * o.im) / n,
            (self.im * o.re - self.re * o.im) / n,
        )
    }
    fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_refuses_a_singular_matrix() {
        // Columns 0 and 1 equal: rank 3.
        let m = [
            [1.0, 1.0, 0.2, 0.1],
            [1.0, 1.0, 0.2, 0.1],
            [0.2, 0.2, 1.0, 0.3],
            [0.1, 0.1, 0.3, 1.0],
        ];
        assert!(inverse_spd(&m).is_none());
        let mut ok = m;
        ok[1][1] = 2.0;
        let inv = inverse_spd(&ok).unwrap();
        for i in 0..4 {
            for j in 0..4 {
                let prod: f64 = (0..4).map(|k| ok[i][k] * inv[k][j]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((prod - want).abs() < 1e-14, "{i} {j} {prod}");
            }
        }
    }

    /// A record of eq. 1 written out by hand (not through `eval_h`):
    /// `H = g·e^{−jθ}·conj(D)/|D|²`, `D = 1 − r² + j·r/Q`, at `lo + i·step`.
    fn exact_record(fr: f64, q: f64, lo: f64, step: f64, n: usize) -> Vec<Sample> {
        let (g, theta) = (1e-7, 0.7f64);
        (0..n)
            .map(|i| {
                let f = lo + step * i as f64;
                let r = f / fr;
                let (dr, di) = (1.0 - r * r, r / q);
                let m = dr * dr + di * di;
                let (cr, ci) = (g * theta.cos(), -g * theta.sin());
                Sample {
                    freq_hz: f,
                    re_m_per_v: (cr * dr + ci * di) / m,
                    im_m_per_v: (ci * dr - cr * di) / m,
                }
            })
            .collect()
    }

    /// The start's `(f_r, Q)` (eq. 6) for `samples`, unweighted.
    fn start_of(samples: &[Sample]) -> (f64, f64) {
        let n = samples.len();
        let peak = samples
            .iter()
            .map(|s| s.re_m_per_v.hypot(s.im_m_per_v))
            .fold(0.0, f64::max);
        let rec = Record {
            samples,
            sigma: None,
            scale: 1.0 / peak,
            fc: 0.5 * (samples[0].freq_hz + samples[n - 1].freq_hz),
            span: samples[n - 1].freq_hz - samples[0].freq_hz,
        };
        let p = start(&rec).expect("a start");
        (rec.fc + rec.span * p[0], p[1].exp())
    }

    /// Closed forms of eq. 2 for a mode `(f_r, Q)`: with `s = r²`,
    /// `|D|² = (s − s*)² + c²`, `s* = 1 − 1/(2Q²)`, `c² = 1 − s*²`, so |H|
    /// peaks at `f_p = f_r·√s*` and is at half power (|H|² = peak/2) at
    /// `f_r·√(s* ∓ c)`. Returns `(f_p, lower, upper)` half-power points.
    fn peak_and_half_power(fr: f64, q: f64) -> (f64, f64, f64) {
        let s_star = 1.0 - 0.5 / (q * q);
        let c = (1.0 - s_star * s_star).sqrt();
        (
            fr * s_star.sqrt(),
            fr * (s_star - c).sqrt(),
            fr * (s_star + c).sqrt(),
        )
    }

    /// The start of eq. 6 against the closed forms of an exact record of
    /// eq. 1 (f_r = 20 003 Hz off the 10 Hz grid, Q = 200: half-power band
    /// B = 100 Hz, grid step h = 0.2 half-bands). f_r: the peak f_p. Near
    /// the peak ln|H| = −½ ln(1 + u²) + const (u in half-bands, exact in
    /// s = r², to O(1/Q) in f); its u⁴/4 term moves the vertex of the
    /// parabola through three points h apart by ≤ 0.1·h³ half-bands
    /// (0.04 Hz here), the O(1/Q) skew by ~h²/Q half-bands (0.01 Hz):
    /// allowed 0.1 Hz = 1/100 of the grid step. Q: `f_p/(upper − lower)`
    /// of the closed forms. Linear interpolation of |H|² = 1/(1 + u²)
    /// (curvature ½, slope −½ at u = ±1) puts each crossing within h²/8
    /// half-bands: the width within h²/8 = 0.5 % relative; allowed 1 %.
    #[test]
    fn the_start_is_the_peak_and_half_power_width_of_an_exact_record() {
        let (fr, q) = (20_003.0, 200.0);
        let (f0, q0) = start_of(&exact_record(fr, q, 19_000.0, 10.0, 201));
        let (fp, lo, hi) = peak_and_half_power(fr, q);
        let want_q = fp / (hi - lo);
        println!("start: f_r {f0} (peak {fp}), Q {q0} (half-power {want_q})");
        assert!((f0 - fp).abs() <= 0.1, "start f_r {f0}, peak {fp}");
        assert!(
            (q0 / want_q - 1.0).abs() <= 0.01,
            "start Q {q0}, half-power {want_q}"
        );
    }

    /// One crossing missing: eq. 6 takes twice the one-sided width. The
    /// record ending inside the upper half-power band (last point 20 040
    /// Hz, u = 0.74: |H|² = 0.65 of the peak) keeps only the lower
    /// crossing, width `2·(f_p − lower)`; the record starting inside the
    /// lower one (first point 19 980 Hz, u = −0.46: |H|² = 0.83) keeps only
    /// the upper, `2·(upper − f_p)` — each from the closed forms above. The
    /// crossing within h²/8 half-bands as before and f_p within 0.04 Hz:
    /// ≤ 0.6 % of the width; allowed 1 %.
    #[test]
    fn the_start_takes_twice_the_one_sided_width_when_one_crossing_is_missing() {
        let (fr, q) = (20_003.0, 200.0);
        let (fp, lo, hi) = peak_and_half_power(fr, q);
        for (first, n, width) in [
            (19_000.0, 105, 2.0 * (fp - lo)),
            (19_980.0, 103, 2.0 * (hi - fp)),
        ] {
            let (f0, q0) = start_of(&exact_record(fr, q, first, 10.0, n));
            let want_q = fp / width;
            println!("one-sided start from {first} Hz: f_r {f0} (peak {fp}), Q {q0} ({want_q})");
            assert!((f0 - fp).abs() <= 0.1, "start f_r {f0}, peak {fp}");
            assert!(
                (q0 / want_q - 1.0).abs() <= 0.01,
                "from {first} Hz: start Q {q0}, one-sided half-power {want_q}"
            );
        }
    }

    /// A record inside the half-power band (19 985–20 025 Hz every 5 Hz
    /// around f_r = 20 003 Hz, Q = 200: |H|² ≥ 0.56 of the peak everywhere),
    /// so eq. 6 has no crossing and takes the width `2/slope` from the phase
    /// slope `−Δarg H/Δf` over the peak's neighbours. The closed form of that
    /// slope: `arg H = −θ − atan2(r/Q, 1 − r²)` of eq. 1, at the neighbours of
    /// the largest |H| (found here by scanning the closed form); Q is then
    /// `f_p·slope/2` with f_p as above (the start's f_r within 0.1 Hz of it:
    /// 5e-6 relative); allowed 1e-4.
    #[test]
    fn the_start_takes_the_phase_slope_when_no_crossing_is_in_the_record() {
        let (fr, q) = (20_003.0, 200.0);
        let (lo, step, n) = (19_985.0, 5.0, 9);
        let (f0, q0) = start_of(&exact_record(fr, q, lo, step, n));
        let (fp, _, _) = peak_and_half_power(fr, q);
        let f = |i: usize| lo + step * i as f64;
        let d = |i: usize| {
            let r = f(i) / fr;
            (1.0 - r * r, r / q)
        };
        let mag2 = |i: usize| {
            let (dr, di) = d(i);
            1.0 / (dr * dr + di * di)
        };
        let k = (0..n).fold(0, |k, i| if mag2(i) > mag2(k) { i } else { k });
        let peak = mag2(k);
        assert!((0..n).all(|i| mag2(i) >= 0.5 * peak), "a crossing");
        let lag = |i: usize| {
            let (dr, di) = d(i);
            di.atan2(dr)
        };
        let slope = (lag(k + 1) - lag(k - 1)) / (f(k + 1) - f(k - 1));
        let want_q = fp * slope / 2.0;
        println!("phase-slope start: f_r {f0} (peak {fp}), Q {q0} (closed form {want_q})");
        assert!((f0 - fp).abs() <= 0.1, "start f_r {f0}, peak {fp}");
        assert!(
            (q0 / want_q - 1.0).abs() <= 1e-4,
            "start Q {q0}, phase slope {want_q}"
        );
    }

    #[test]
    fn wrap_is_in_the_half_open_interval() {
        use core::f64::consts::PI;
        assert_eq!(wrap_pi(PI), PI);
        assert_eq!(wrap_pi(-PI), PI);
        assert!((wrap_pi(3.0 * PI + 0.1) - (-PI + 0.1)).abs() < 1e-12);
    }
}
