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
//! and nine multiply-adds into the sums. [`LockIn`] sums in floats (any
//! [`Float`]); the board's pickups use [`LockInQ`], the same fit with a Q15
//! reference from the DDS's table and exact integer sums (issue 35: 66
//! instructions per sample for both pickups on the M4F, 103 in f32).

use super::reference::{Gram, PairSums};
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
    /// An integer window ([`LockInQ`]) took more than [`MAX_Q_SAMPLES`].
    LongWindow,
}

impl core::fmt::Display for LockInError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            LockInError::TooFewSamples => "fewer than three samples",
            LockInError::ShortWindow => "the window spans less than a quarter period",
            LockInError::LongWindow => "the window holds more samples than its integer sums allow",
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

impl Phasor<f32> {
    /// The fit `p = d + a'·cos θ + b'·sin θ` made against the phase θ,
    /// turned to the phase θ + δ of `p`'s own samples (`cos δ`, `sin δ`
    /// given): `a = a'·cos δ − b'·sin δ`, `b = a'·sin δ + b'·cos δ`, the
    /// mean unchanged — exact, since `a·cos(θ+δ) + b·sin(θ+δ)` is
    /// `a'·cos θ + b'·sin θ`. (The board's pickups are fitted against the
    /// forces' reference, [`crate::reference`], and turned by their
    /// conversion delay.)
    pub fn turned(self, cos: f32, sin: f32) -> Self {
        Phasor {
            mean: self.mean,
            in_phase: self.in_phase * cos - self.quadrature * sin,
            quadrature: self.in_phase * sin + self.quadrature * cos,
        }
    }
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

/// `v as f32`, correctly rounded (to nearest, ties to even) like it, in a
/// dozen instructions on the M4 instead of the ≈ 40 of the runtime's
/// `__aeabi_l2f` (issue 35: the solve converts seven centred sums): a
/// value within i32 converts directly; a larger one is cut to its top 32
/// bits with the bits cut off OR-ed into the lowest (a sticky bit, below
/// the rounding position of the 24-bit significand, so the rounding of the
/// 32-bit value is that of `v`), then scaled back by `2^shift`, exactly.
#[inline]
pub fn f32_of(v: i64) -> f32 {
    if let Ok(small) = i32::try_from(v) {
        return small as f32;
    }
    let a = v.unsigned_abs();
    // a ≥ 2³¹: 0 ≤ shift ≤ 32 (a = 2⁶³ for i64::MIN).
    let shift = 32 - a.leading_zeros();
    let top = (a >> shift) as u32 | u32::from(a & ((1u64 << shift) - 1) != 0);
    let m = top as f32 * f32::from_bits((127 + shift) << 23);
    if v < 0 {
        -m
    } else {
        m
    }
}

/// The most samples an integer window holds ([`LockInQ`]): `2¹⁵` keeps
/// every centred product of (LQ2) within i64 (`n·Σc² ≤ n²·2³⁰ ≤ 2⁶⁰`);
/// 65 ms at 500 kS/s, a period at 15 Hz, far below the drives' range.
pub const MAX_Q_SAMPLES: u32 = 1 << 15;

/// The sums of (L2) in integers (issue 35), for `K` signals of ADC counts
/// sampled at the same phases: the reference `(cos θ, sin θ)` as Q15
/// integers from the DDS's own Q30 table, the products summed exactly in
/// i64 (`c`, `s`: one add; `c²`, `cs`, `pc`: one multiply-accumulate), the
/// span in phase words. Nothing is rounded until the solve:
///
/// ```text
/// c_i = round(2¹⁵ cos θ_i),  s_i = round(2¹⁵ sin θ_i)  (from the Q30 table)   (LQ1)
/// S_xy = n·Σxy − Σx·Σy   (exact, i64: the centred sums of L2 times n)          (LQ2)
/// a = (S_pc S_ss − S_ps S_cs)/D,  b = (S_ps S_cc − S_pc S_cs)/D,
/// D = S_cc S_ss − S_cs²   (f32; a, b per Q15 unit, then × 2¹⁵)                (LQ3)
/// ```
///
/// The reference's error — the table's `ε_t`, the interpolation's
/// `(2π/N)²/8` and the Q15 rounding `2⁻¹⁶` — perturbs the fit by at most
/// `G·√2·A·ε_r` for a signal of amplitude `A`, `ε_r = ε_t + (2π/N)²/8 +
/// 2⁻²⁹ + 2⁻¹⁶` (2.02e-5 at N = 1024, libm table) and `G` the fit's gain from a
/// residual to a coefficient (`max_j Σ_i |((XᵀX)⁻¹Xᵀ)_ji|`, ≈ 2 over a
/// whole period); the f32 solve adds a few ulps. Derived in
/// `docs/transducers.md` ("The lock-ins in integers") and asserted in
/// `tests/tests/lockin.rs` against an f64 fit with exact cos and sin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LockInQ<const K: usize> {
    n: u32,
    c: i64,
    s: i64,
    cc: i64,
    ss: i64,
    cs: i64,
    p: [i64; K],
    pc: [i64; K],
    ps: [i64; K],
    /// Phase words travelled from the window's first sample to its last.
    span: u64,
}

impl<const K: usize> Default for LockInQ<K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize> LockInQ<K> {
    /// An empty window.
    pub const fn new() -> Self {
        LockInQ {
            n: 0,
            c: 0,
            s: 0,
            cc: 0,
            ss: 0,
            cs: 0,
            p: [0; K],
            pc: [0; K],
            ps: [0; K],
            span: 0,
        }
    }

    /// The Q15 reference (LQ1) of phase word `p` from the DDS's table:
    /// `(round(2¹⁵ cos), round(2¹⁵ sin))`.
    #[inline(always)]
    pub fn reference<const N: usize>(t: &super::dds::SineTable<N>, p: u32) -> (i32, i32) {
        let q15 = |v: i32| (v + (1 << 14)) >> 15;
        (q15(t.sin_q30(p.wrapping_add(1 << 30))), q15(t.sin_q30(p)))
    }

    /// Adds one sample of each signal (`p`, ADC counts) at the reference
    /// `(c, s)` (Q15, [`LockInQ::reference`]); `dphase` is the phase word
    /// advanced since the previous sample. Beyond [`MAX_Q_SAMPLES`] the
    /// sample is not taken (the window is then refused by the solve).
    #[inline(always)]
    pub fn push(&mut self, c: i32, s: i32, dphase: u32, p: [u16; K]) {
        if self.n >= MAX_Q_SAMPLES {
            self.n = MAX_Q_SAMPLES + 1;
            return;
        }
        if self.n > 0 {
            self.span += u64::from(dphase);
        }
        self.n += 1;
        let (c, s) = (i64::from(c), i64::from(s));
        self.c += c;
        self.s += s;
        self.cc += c * c;
        self.ss += s * s;
        self.cs += c * s;
        for (k, &pk) in p.iter().enumerate() {
            let pk = i64::from(pk);
            self.p[k] += pk;
            self.pc[k] += pk * c;
            self.ps[k] += pk * s;
        }
    }

    /// Samples in the window.
    pub fn samples(&self) -> u32 {
        self.n
    }

    /// Whether `more` samples still fit the integer sums.
    fn room_for(&mut self, more: usize) -> bool {
        if self.n as usize + more > MAX_Q_SAMPLES as usize {
            self.n = MAX_Q_SAMPLES + 1;
            return false;
        }
        true
    }

    /// The phase the window spans, rad.
    pub fn span_rad(&self) -> f32 {
        (self.span as f64 * (core::f64::consts::TAU / 4_294_967_296.0)) as f32
    }

    /// The phase the window spans, phase words (2³² a turn).
    pub fn span_words(&self) -> u64 {
        self.span
    }

    /// The fit (L1) of each signal over the window, in ADC counts (eqs.
    /// LQ2, LQ3).
    ///
    /// # Errors
    /// [`LockInError::TooFewSamples`] below three samples,
    /// [`LockInError::ShortWindow`] below [`MIN_SPAN_RAD`] (or a singular
    /// normal matrix), [`LockInError::LongWindow`] beyond [`MAX_Q_SAMPLES`].
    pub fn solve(&self) -> Result<[Phasor<f32>; K], LockInError> {
        if self.n < 3 {
            return Err(LockInError::TooFewSamples);
        }
        if self.n > MAX_Q_SAMPLES {
            return Err(LockInError::LongWindow);
        }
        // MIN_SPAN_RAD = π/2 is 2³⁰ words.
        if self.span < 1 << 30 {
            return Err(LockInError::ShortWindow);
        }
        let n = i64::from(self.n);
        // (LQ2), exact: with n ≤ 2¹⁵, |c|, |s| ≤ 2¹⁵ and any u16 sample,
        // |n·Σxy| and |Σx·Σy| are at most 2⁶¹, their difference 2⁶².
        let centred = |sxy: i64, sx: i64, sy: i64| f32_of(n * sxy - sx * sy);
        let scc = centred(self.cc, self.c, self.c);
        let sss = centred(self.ss, self.s, self.s);
        let scs = centred(self.cs, self.c, self.s);
        let det = scc * sss - scs * scs;
        if det.is_nan() || det <= 0.0 {
            return Err(LockInError::ShortWindow);
        }
        let inv = 1.0 / det;
        let nf = self.n as f32;
        // |Σc|, |Σs| ≤ n·2¹⁵ ≤ 2³⁰ and |Σx| < n·2¹⁶ ≤ 2³¹ (n ≤ 2¹⁵): i32,
        // whose conversion is one instruction.
        let (mc, ms) = (self.c as i32 as f32 / nf, self.s as i32 as f32 / nf);
        let mut out = [Phasor {
            mean: 0.0,
            in_phase: 0.0,
            quadrature: 0.0,
        }; K];
        for (k, o) in out.iter_mut().enumerate() {
            let spc = centred(self.pc[k], self.p[k], self.c);
            let sps = centred(self.ps[k], self.p[k], self.s);
            // Per Q15 unit of the reference (LQ3).
            let a = (spc * sss - sps * scs) * inv;
            let b = (sps * scc - spc * scs) * inv;
            *o = Phasor {
                mean: self.p[k] as i32 as f32 / nf - a * mc - b * ms,
                in_phase: a * 32_768.0,
                quadrature: b * 32_768.0,
            };
        }
        Ok(out)
    }

    /// Empties the window.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}

impl LockInQ<2> {
    /// A block's sums into the window: the reference's [`Gram`] sums and a
    /// pair of signals' [`PairSums`] against the same reference words
    /// ([`crate::reference`], eq. R1: the Q15 reference clamped at
    /// `2¹⁵ − 1`), `tw` phase words per sample: the same sums as
    /// [`LockInQ::push`] per sample at that reference. A block that would
    /// pass [`MAX_Q_SAMPLES`] is not taken (the window is then refused by
    /// the solve).
    pub fn push_sums(&mut self, g: &Gram, p: &PairSums, tw: u32) {
        if g.n == 0 || !self.room_for(g.n as usize) {
            return;
        }
        // The first sample of a window adds no span (as `push`).
        let steps = if self.n == 0 { g.n - 1 } else { g.n };
        self.span += u64::from(steps) * u64::from(tw);
        self.n += g.n;
        self.c += g.c;
        self.s += g.s;
        self.cc += g.cc;
        self.ss += g.ss;
        self.cs += g.cs;
        for k in 0..2 {
            self.p[k] += p.p[k];
            self.pc[k] += p.pc[k];
            self.ps[k] += p.ps[k];
        }
    }
}
