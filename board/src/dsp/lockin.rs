//! A lock-in on the DDS's own reference, exact over any window: the least-
//! squares fit of
//!
//! ```text
//! p_i ≈ d + a·cos θ_i + b·sin θ_i                                  (L1)
//! ```
//!
//! to samples `p_i` taken at the drive phases `θ_i` (the DDS accumulator of
//! each sample's tick: the reference is sample-exact). The amplitude is
//! `A = √(a² + b²)` and the phase `ψ = atan2(−b, a)` in `p = d + A cos(θ + ψ)`.
//!
//! **Why a fit and not the textbook `2/N Σ p·cos θ`.** The textbook lock-in
//! removes the 2θ term (and the DC) exactly only over a whole number of
//! periods; over a DAC half-buffer (64 samples: 2.56 periods at 20 kHz and
//! 500 kS/s) its 2θ leak is up to `1/(N sin Δθ)` of the amplitude (6 % here,
//! `Δθ` the phase step per sample). The fit (L1) solves the 3×3 normal
//! equations
//!
//! ```text
//! [ N    Σc    Σs  ] [d]   [Σp ]
//! [ Σc   Σc²   Σcs ] [a] = [Σpc]                                  (L2)
//! [ Σs   Σcs   Σs² ] [b]   [Σps]
//! ```
//!
//! whose solution is exact for a signal of the form (L1) over *any* window
//! whose phases are not all alike: no leak, no window condition. Its noise
//! gain grows as the window's phase span shrinks; [`LockIn::solve`] refuses a
//! window whose normal matrix is too close to singular ([`MIN_SPAN_RAD`]).
//!
//! Cost per sample: the reference's cos and sin (table look-ups on the board)
//! and nine multiply-adds into the sums.

use model_core::float::{Float, Math};

/// The least phase span (rad) of a window: below it the fit is refused
/// ([`LockInError::ShortWindow`]). Over a span `s` the normal matrix's
/// smallest eigenvalue falls like `N·s⁴/720` (the Taylor expansion of
/// cos and sin about the window's middle), so the noise gain grows like
/// `1/s²`; a quarter period keeps it within ≈ 10× that of a whole period.
pub const MIN_SPAN_RAD: f64 = core::f64::consts::FRAC_PI_2;

/// Why a window gives no phasor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LockInError {
    /// Fewer than three samples.
    TooFewSamples,
    /// The window spans less than [`MIN_SPAN_RAD`] of drive phase.
    ShortWindow,
}

impl core::fmt::Display for LockInError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            LockInError::TooFewSamples => "fewer than three samples",
            LockInError::ShortWindow => "the window spans less than a quarter period",
        })
    }
}

impl core::error::Error for LockInError {}

/// The fit of a window (eq. L1).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Phasor<F> {
    /// Mean level d (the signal's units).
    pub mean: F,
    /// In-phase part a (of cos θ).
    pub in_phase: F,
    /// Quadrature part b (of sin θ).
    pub quadrature: F,
}

impl<F: Float> Phasor<F> {
    /// Amplitude A = √(a² + b²).
    pub fn amplitude<M: Math<F>>(&self) -> F {
        M::hypot(self.in_phase, self.quadrature)
    }

    /// Phase ψ of `A cos(θ + ψ)`, rad in (−π, π]: `atan2(−b, a)`.
    pub fn phase<M: Math<F>>(&self) -> F {
        M::atan2(-self.quadrature, self.in_phase)
    }
}

/// The sums of (L2) over a window, for `K` signals sampled at the same
/// phases (the reference sums Σc, Σs, Σc², Σs², Σcs are shared: the two
/// pickups of the board cost one reference, not two).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LockIn<F, const K: usize> {
    n: u32,
    c: F,
    s: F,
    cc: F,
    ss: F,
    cs: F,
    p: [F; K],
    pc: [F; K],
    ps: [F; K],
    /// The phase travelled from the window's first sample to its last, rad.
    span: F,
}

impl<F: Float, const K: usize> Default for LockIn<F, K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<F: Float, const K: usize> LockIn<F, K> {
    /// An empty window.
    pub fn new() -> Self {
        LockIn {
            n: 0,
            c: F::ZERO,
            s: F::ZERO,
            cc: F::ZERO,
            ss: F::ZERO,
            cs: F::ZERO,
            p: [F::ZERO; K],
            pc: [F::ZERO; K],
            ps: [F::ZERO; K],
            span: F::ZERO,
        }
    }

    /// Adds the samples `p` (one per signal) taken at the drive phase whose
    /// cosine and sine are `(cos θ, sin θ)`; `dtheta` is the phase advanced
    /// since the previous sample (rad, ≥ 0; the DDS's tuning word), counted
    /// into the span.
    #[inline]
    pub fn push(&mut self, cos: F, sin: F, dtheta: F, p: [F; K]) {
        if self.n > 0 {
            self.span += dtheta;
        }
        self.n += 1;
        self.c += cos;
        self.s += sin;
        self.cc += cos * cos;
        self.ss += sin * sin;
        self.cs += cos * sin;
        for (k, &pk) in p.iter().enumerate() {
            self.p[k] += pk;
            self.pc[k] += pk * cos;
            self.ps[k] += pk * sin;
        }
    }

    /// Samples in the window.
    pub fn samples(&self) -> u32 {
        self.n
    }

    /// The phase the window spans, rad.
    pub fn span_rad(&self) -> F {
        self.span
    }

    /// The fit (L1) of each signal over the window (Cramer's rule on L2,
    /// with the sums centred on their means first for conditioning).
    ///
    /// # Errors
    /// [`LockInError`].
    pub fn solve(&self) -> Result<[Phasor<F>; K], LockInError> {
        if self.n < 3 {
            return Err(LockInError::TooFewSamples);
        }
        if self.span < F::from_f64(MIN_SPAN_RAD) {
            return Err(LockInError::ShortWindow);
        }
        let n = F::from_u32(self.n);
        // Eliminate d: the 2×2 system of the centred sums.
        let (mc, ms) = (self.c / n, self.s / n);
        let scc = self.cc - self.c * mc;
        let sss = self.ss - self.s * ms;
        let scs = self.cs - self.c * ms;
        let det = scc * sss - scs * scs;
        if det.is_nan() || det <= F::ZERO {
            return Err(LockInError::ShortWindow);
        }
        let inv = F::ONE / det;
        let mut out = [Phasor {
            mean: F::ZERO,
            in_phase: F::ZERO,
            quadrature: F::ZERO,
        }; K];
        for (k, o) in out.iter_mut().enumerate() {
            let mp = self.p[k] / n;
            let spc = self.pc[k] - self.p[k] * mc;
            let sps = self.ps[k] - self.p[k] * ms;
            let a = (spc * sss - sps * scs) * inv;
            let b = (sps * scc - spc * scs) * inv;
            *o = Phasor {
                mean: mp - a * mc - b * ms,
                in_phase: a,
                quadrature: b,
            };
        }
        Ok(out)
    }

    /// Empties the window.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}
