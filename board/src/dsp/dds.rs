//! Direct digital synthesis of the two phase-locked drive waveforms.
//!
//! One 32-bit phase accumulator advances by one tuning word per sample at a
//! fixed sample rate `f_s`; both channels read the *same* accumulator value
//! plus their own phase offset, so the phase between them is exact by
//! construction (integer arithmetic, no drift however long the run).
//! Each channel looks up a sine table of `N` entries (built once, with the
//! [`Libm`] or [`Micromath`] backend) with linear interpolation (or the
//! nearest entry, [`Interp`]), scales by its
//! amplitude, adds its DC offset (both in DAC codes), rounds and clamps to the
//! 12-bit range `0..=4095`. [`pack_dual`] makes the 32-bit word of the STM32
//! DAC's dual 12-bit right-aligned holding register (DHR12RD: channel 1 in bits
//! 0–11, channel 2 in bits 16–27).
//!
//! Changes never jump: amplitude, DC offset and phase offset move toward
//! their targets by at most a configurable slew per sample, and a frequency
//! change only alters the increment of the accumulator (phase-continuous).
//!
//! Frequency resolution is `f_s/2³²` (0.23 mHz at 1 MS/s); the achieved
//! frequency and phase are reported exactly ([`Achieved`]).
//!
//! **Integer arithmetic per sample** (issue 35). The table is read as Q30
//! integers (`q_i = 2³⁰·t_i`, exactly the f32 entries) and every sample is
//! formed in integers, with the channel's amplitude and DC turned into
//! integer scale factors once per fill:
//!
//! ```text
//! v(p)  = q_i + 2·⌊Δq_i · r / 2³²⌋,   i = ⌊p·N/2³²⌋, r = the next 31 bits of p (Q1)
//! k_a   = round(amp · 2¹⁸),   k_d = round(dc · 2¹⁶) + 2¹⁵                       (Q2)
//! code  = clamp(⌊(k_d·2³² + k_a·v) / 2⁴⁸⌋, 0, 4095)                           (Q3)
//! ```
//!
//! (Q3) is `round(dc + amp·v/2³⁰)`: one 32×32→64 multiply-accumulate per
//! channel and sample (SMLAL on the M4), no float. While a channel ramps its
//! scale factors follow the slew's closed form per sample (Q4, [`Dds::fill`]).
//! The error against the exact waveform, derived in `docs/transducers.md`
//! ("The DDS in integers") and asserted in `tests/tests/dds.rs` against an f64
//! computation:
//!
//! ```text
//! |code − (dc + amp·sin 2πp/2³²)| ≤ 1/2 + |amp|·(ε_t + (2π/N)²/8 + 2⁻²⁹) + 2⁻¹⁵   (Q5)
//! ```
//!
//! with `ε_t` the table entries' error (an f32 sine of an f32 argument:
//! ≤ π·2⁻²³ + 2⁻²⁴ = 4.3e-7; 2.0e-7 measured with libm; `(2π/N)²/8` the
//! linear interpolation's, 4.7e-6 at N = 1024: 0.0096 LSB at full scale).
//! With the nearest entry the middle term is `π/N` instead.
//!
//! Channel waveforms: `code = dc + amp · sin(2π·(acc + offset)/2³²)`. The drive
//! of the paper (eqs. 1, 2) uses `−cos θ` for the normal channel and
//! `cos(θ + φ)` for the tangential one; [`phase_word`] turns radians into
//! offsets (`−cos θ = sin(θ − π/2)`, `cos(θ+φ) = sin(θ + φ + π/2)`).

use crate::reference::BLOCK;
use model_core::float::{Libm, Math, Micromath};

/// Largest DAC code (12 bits).
pub const DAC_MAX: u16 = 4095;

/// DAC volts per code: 12 bits over V_REF = 3.3 V (RM0090 §14.2: DAC
/// output = V_REF · DOR / 4095).
pub const DAC_VOLTS_PER_CODE: f64 = 3.3 / 4095.0;

/// Packs two 12-bit codes into the DHR12RD word: channel 1 in bits 0–11,
/// channel 2 in bits 16–27.
#[inline(always)]
pub const fn pack_dual(ch1: u16, ch2: u16) -> u32 {
    ((ch1 & 0x0FFF) as u32) | (((ch2 & 0x0FFF) as u32) << 16)
}

/// Unpacks a DHR12RD word into `(ch1, ch2)`.
#[inline(always)]
pub const fn unpack_dual(w: u32) -> (u16, u16) {
    ((w & 0x0FFF) as u16, ((w >> 16) & 0x0FFF) as u16)
}

/// A sine table of `N` entries (`N` a power of two, 4 ≤ N ≤ 65536) plus a
/// wrap-around entry, values in `[-1, 1]`.
#[derive(Clone, Debug)]
pub struct SineTable<const N: usize> {
    t: [f32; N],
    /// `t[i+1] − t[i]` (wrapping), so interpolation is one multiply-add.
    d: [f32; N],
    /// The DDS's table (Q1), `[q_i, Δq_i]` side by side (one LDRD):
    /// `q_i = round(2³⁰·t[i])` (exact but for entries below 2⁻⁶ in
    /// magnitude, then within 2⁻³¹) and `Δq_i = q_{i+1} − q_i` (below 2³¹
    /// in magnitude for `N ≥ 4`).
    q: [[i32; 2]; N],
}

impl<const N: usize> SineTable<N> {
    const BITS: u32 = {
        assert!(
            N.is_power_of_two() && N >= 4 && N <= 65536,
            "N must be a power of two in 4..=65536"
        );
        N.trailing_zeros()
    };

    /// Builds the table with backend `M` (`sin(2πi/N)` computed in f32).
    pub fn build<M: Math<f32>>() -> Self {
        let mut t = [0.0f32; N];
        for (i, v) in t.iter_mut().enumerate() {
            // Reduce the argument to [-π, π] in the integer domain first.
            let k = if i > N / 2 {
                i as i64 - N as i64
            } else {
                i as i64
            };
            let x = core::f32::consts::TAU * (k as f32) / (N as f32);
            *v = M::sin_cos(x).0;
        }
        let mut d = [0.0f32; N];
        let mut q = [[0i32; 2]; N];
        for i in 0..N {
            d[i] = t[(i + 1) % N] - t[i];
            // 2³⁰·t is exact in f32 (a power-of-two scale) and below 2³¹ in
            // magnitude; it is an integer unless |t| < 2⁻⁶ (24 significant
            // bits), where the rounding moves it by ≤ 2⁻³¹: q = round(2³⁰ t).
            let x = t[i] * Q30_F32;
            q[i][0] = if x >= 0.0 { x + 0.5 } else { x - 0.5 } as i32;
        }
        for i in 0..N {
            q[i][1] = q[(i + 1) % N][0].wrapping_sub(q[i][0]);
        }
        SineTable { t, d, q }
    }

    /// The accurate table (libm).
    pub fn libm() -> Self {
        Self::build::<Libm>()
    }

    /// The fast table (micromath).
    pub fn micromath() -> Self {
        Self::build::<Micromath>()
    }

    /// `sin(2π·phase/2³²)` from the nearest table entry (no interpolation:
    /// the phase is rounded to `N` positions, worst error `≈ π/N`).
    #[inline(always)]
    pub fn sin_nearest(&self, phase: u32) -> f32 {
        let bits = Self::BITS;
        let idx = (phase.wrapping_add(1 << (31 - bits)) >> (32 - bits)) as usize;
        self.t[idx & (N - 1)]
    }

    /// Linearly interpolated `sin(2π·phase/2³²)` (worst error `≈ (π/N)²/2`).
    #[inline(always)]
    pub fn sin(&self, phase: u32) -> f32 {
        let bits = Self::BITS;
        let idx = (phase >> (32 - bits)) as usize;
        // The 32 − BITS low bits as a fraction in [0, 1).
        let frac_bits = phase << bits;
        let frac = (frac_bits >> 8) as f32 * (1.0 / 16_777_216.0);
        self.t[idx] + frac * self.d[idx]
    }

    /// Table entry `i` (for tests).
    pub fn entry(&self, i: usize) -> f32 {
        self.t[i % N]
    }

    /// `2³⁰·sin(2π·phase/2³²)`, linearly interpolated in integers (eq. Q1):
    /// the table's error plus at most `(2π/N)²/8` (interpolation) and
    /// `2⁻²⁹` (the floor of the halved product, two Q30 units), of 1. All
    /// of the phase's bits below the index are used (`32 − log₂N ≤ 30`).
    #[inline(always)]
    pub fn sin_q30(&self, phase: u32) -> i32 {
        let bits = Self::BITS;
        let idx = (phase >> (32 - bits)) as usize & (N - 1);
        // The next 31 bits of the phase: the fraction of the step, Q31.
        let r = (phase << bits) >> 1;
        // ⌊Δq·r/2³²⌋·2 (one SMMUL): the floor costs ≤ 2 Q30 units, 2⁻²⁹.
        let [q, dq] = self.q[idx];
        let half = (i64::from(dq) * i64::from(r)) >> 32;
        q.wrapping_add((half as i32) << 1)
    }

    /// `(2³⁰·cos, 2³⁰·sin)` of `2π·phase/2³²`: the same values as
    /// [`SineTable::sin_q30`] at `phase + 2³⁰` and at `phase` (a quarter
    /// turn is `N/4` entries: the cosine's index is the sine's plus `N/4`,
    /// its fraction the same), with one index and one fraction for both.
    #[inline(always)]
    pub fn cos_sin_q30(&self, phase: u32) -> (i32, i32) {
        let bits = Self::BITS;
        let idx = (phase >> (32 - bits)) as usize & (N - 1);
        let r = (phase << bits) >> 1;
        let read = |i: usize| {
            let [q, dq] = self.q[i & (N - 1)];
            q.wrapping_add((((i64::from(dq) * i64::from(r)) >> 32) as i32) << 1)
        };
        (read(idx + N / 4), read(idx))
    }

    /// `2³⁰·sin(2π·phase/2³²)` from the nearest entry (error `≤ π/N`).
    #[inline(always)]
    pub fn sin_q30_nearest(&self, phase: u32) -> i32 {
        let bits = Self::BITS;
        let idx = (phase.wrapping_add(1 << (31 - bits)) >> (32 - bits)) as usize;
        self.q[idx & (N - 1)][0]
    }

    /// The integer read of `interp` (eq. Q1, or the nearest entry).
    #[inline(always)]
    pub fn sin_q30_with(&self, interp: Interp, phase: u32) -> i32 {
        match interp {
            Interp::Nearest => self.sin_q30_nearest(phase),
            Interp::Linear | Interp::Reference => self.sin_q30(phase),
        }
    }
}

/// `2³⁰` as f32 (exact): the scale of the Q30 table.
const Q30_F32: f32 = 1_073_741_824.0;

/// A channel's integer scale factors (eq. Q2) and phase offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Fixed {
    /// `round(amp · 2¹⁸)`: `|amp| ≤ 4095` keeps it below 2³⁰.
    ka: i32,
    /// `round(dc · 2¹⁶) + 2¹⁵` (the half that makes (Q3)'s floor a
    /// rounding): `0 ≤ dc ≤ 4095` keeps it below 2²⁸.
    kd: i32,
    /// The phase offset word.
    ph: u32,
}

/// `round(x)` of a finite f32 within i32, half away from zero.
#[inline(always)]
fn round_i32(x: f32) -> i32 {
    (if x >= 0.0 { x + 0.5 } else { x - 0.5 }) as i32
}

impl Fixed {
    /// Eq. (Q2) of an amplitude, a DC level (codes) and a phase offset.
    #[inline(always)]
    fn of(amp: f32, dc: f32, ph: u32) -> Self {
        Fixed {
            ka: round_i32(amp * 262_144.0),
            kd: round_i32(dc * 65_536.0) + (1 << 15),
            ph,
        }
    }

    /// The factors one sample on by the increments `d` (wrapping).
    #[inline(always)]
    fn step(self, d: Fixed) -> Self {
        Fixed {
            ka: self.ka.wrapping_add(d.ka),
            kd: self.kd.wrapping_add(d.kd),
            ph: self.ph.wrapping_add(d.ph),
        }
    }

    /// Eq. (Q3): the code of the table value `v` (Q30).
    #[inline(always)]
    fn code(&self, v: i32) -> u16 {
        let acc = (i64::from(self.kd) << 32) + i64::from(self.ka) * i64::from(v);
        ((acc >> 48) as i32).clamp(0, DAC_MAX as i32) as u16
    }
}

/// A channel's factors for the fills formed from the drive phase's
/// reference ([`crate::reference`], eq. R1), eq. (Q6): with `(c, s)` the
/// Q15 cosine and sine of the accumulator,
///
/// ```text
/// k_c = round(8·amp·sin φ),  k_s = round(8·amp·cos φ),
/// k_d = round(2¹⁸·dc) + 2¹⁷                                                  (Q6)
/// code = clamp(⌊(k_d + c·k_c + s·k_s)/2¹⁸⌋, 0, 4095)
/// ```
///
/// (`sin(θ + φ) = sin θ cos φ + cos θ sin φ`; `sin φ`, `cos φ` the table's
/// Q30 read of the phase offset, eq. Q1). In i32: `|c·k_c + s·k_s| ≤
/// 2¹⁵·|(k_c, k_s)| ≤ 2¹⁵·(8·4095 + 1) < 2³⁰` and `k_d ≤ 2¹⁸·4095 + 2¹⁷ <
/// 2³⁰`. Two multiply-accumulates per channel and sample, on the
/// reference the ADC's lock-ins use too (one product per sample for
/// both, eq. R3: issue 35). The error against the exact waveform, with `ε_r` the
/// reference's (eq. R2) and `ε_φ` the table read's (Q1):
///
/// ```text
/// |code − (dc + amp·sin(θ + φ))| ≤ 1/2 + √2·|amp|·(ε_r + ε_φ + 3·2⁻²⁴) + √2/16 + 2⁻¹⁹   (Q7)
/// ```
///
/// (the floor with `2¹⁷` added is a rounding, ½; each `(c, s)` component
/// within `ε_r` of the exact cosine and sine and each factor's sine within
/// `ε_φ + 3·2⁻²⁴` (the table read, then two f32 roundings of the product),
/// so `amp·(e_c sin φ + e_s cos φ)` stays within `√2·|amp|·(…)`; each
/// factor's rounding to an integer, ½ of ⅛ code, adds at most
/// `½·(|c| + |s|)/2¹⁸ ≤ √2/16`; `k_d`'s, `2⁻¹⁹`): ≤ 0.70 code at
/// |amp| ≤ 2047.5, `ε_r ≤ 3.06e-5` (eq. R2) and `ε_φ = ε_t + (2π/N)²/8 +
/// 2⁻²⁹` (N = 1024).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct RefCoef {
    /// Within ±32 760 (`8·4095`): 16 bits, so that each product of eq.
    /// (Q6) is one 16-bit multiply-accumulate (`SMLABB`/`SMLATB`).
    kc: i16,
    ks: i16,
    kd: i32,
}

impl RefCoef {
    /// Eq. (Q6) of an amplitude, a DC level (codes, within `±4095` and
    /// `0..=4095`: [`Level::check`]) and a phase offset word.
    #[inline(always)]
    fn of<const N: usize>(t: &SineTable<N>, amp: f32, dc: f32, ph: u32) -> Self {
        let (c, s) = t.cos_sin_q30(ph);
        let a = amp.clamp(-4095.0, 4095.0) * (8.0 / Q30_F32);
        RefCoef {
            // |a·s| ≤ 8·4095·(1 + 2⁻²³) < 32 761: the casts are exact.
            kc: round_i32(a * s as f32) as i16,
            ks: round_i32(a * c as f32) as i16,
            kd: round_i32(dc.clamp(0.0, 4095.0) * 262_144.0) + (1 << 17),
        }
    }

    /// Eq. (Q6): the code of the packed reference word `w` (R1).
    #[inline(always)]
    fn code(&self, w: u32) -> u32 {
        let (c, s) = (crate::reference::cos_of(w), crate::reference::sin_of(w));
        let v = self.kd + c * i32::from(self.kc) + s * i32::from(self.ks);
        (v >> 18).clamp(0, DAC_MAX as i32) as u32
    }
}

/// Which equations a fill's codes follow ([`Dds::fill_path`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FillPath {
    /// From the drive phase's reference words, eq. (Q6): settled channels,
    /// or levels that reach their targets within one sample (sample 0 at
    /// the levels now, the rest at the targets').
    Reference,
    /// From the table at each channel's phase, eqs. (Q1–Q4): a ramp.
    Table,
}

/// How a fill forms its codes: from the drive phase's reference words
/// (the board's choice), or by reading a [`SineTable`] at each channel's
/// phase, between its entries or at the nearest one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Interp {
    /// The nearest entry: one load per sample, error `≈ π/N` of full scale.
    Nearest,
    /// Linear between neighbouring entries: a load pair and a multiply-add,
    /// error `≈ (π/N)²/2` (eqs. Q1–Q5).
    Linear,
    /// Settled fills, and fills whose levels all arrive within one sample,
    /// from the reference words the fill forms for the ADC anyway (eq. Q6,
    /// bound Q7: two multiply-accumulates per channel and sample); ramps
    /// as [`Interp::Linear`] (the board's choice, issue 35).
    #[default]
    Reference,
}

/// Converts a phase in radians to a 32-bit phase word (wrapping).
pub fn phase_word(rad: f64) -> u32 {
    let turns = rad / core::f64::consts::TAU;
    let frac = turns - libm::floor(turns);
    // frac ∈ [0, 1): scale to 2³²; 1.0 - ε rounds to 2³² → wraps to 0.
    let w = libm::round(frac * 4_294_967_296.0);
    if w >= 4_294_967_296.0 {
        0
    } else {
        w as u32
    }
}

/// The radians of a phase word, in `[0, 2π)`.
pub fn phase_rad(w: u32) -> f64 {
    w as f64 * (core::f64::consts::TAU / 4_294_967_296.0)
}

/// Why a DDS setting was refused (the running state is left untouched).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DdsError {
    /// Frequency not finite, ≤ 0, or ≥ f_s/2 (Nyquist).
    Frequency,
    /// Amplitude or DC offset not finite or outside the DAC range
    /// (`dc − |amp| < 0` or `dc + |amp| > 4095`).
    Level,
    /// A slew rate is not finite or not > 0.
    Slew,
    /// Sample rate not finite or ≤ 0.
    SampleRate,
}

impl core::fmt::Display for DdsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            DdsError::Frequency => "DDS frequency not finite, <= 0 or at/above Nyquist",
            DdsError::Level => "DDS amplitude/offset outside the DAC range 0..=4095",
            DdsError::Slew => "DDS slew rate not finite or <= 0",
            DdsError::SampleRate => "DDS sample rate not finite or <= 0",
        })
    }
}

impl core::error::Error for DdsError {}

/// What the DDS actually produces for a request.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Achieved {
    /// Tuning word.
    pub tuning_word: u32,
    /// Exact output frequency `tw·f_s/2³²`, Hz.
    pub freq_hz: f64,
}

/// Per-sample slew limits.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Slew {
    /// Largest change of an amplitude per sample, DAC codes.
    pub amp_per_sample: f32,
    /// Largest change of a DC offset per sample, DAC codes.
    pub dc_per_sample: f32,
    /// Largest change of a phase offset per sample, phase-word units (2³² = 1 turn).
    pub phase_per_sample: u32,
}

impl Slew {
    /// Slew limits from rates per second at sample rate `fs`: amplitude and DC
    /// in codes/s, phase in rad/s.
    ///
    /// # Errors
    /// [`DdsError::Slew`] for non-finite or non-positive rates.
    pub fn from_rates(
        fs: f32,
        amp_codes_per_s: f32,
        dc_codes_per_s: f32,
        phase_rad_per_s: f32,
    ) -> Result<Self, DdsError> {
        for r in [amp_codes_per_s, dc_codes_per_s, phase_rad_per_s] {
            if !(r.is_finite() && r > 0.0) {
                return Err(DdsError::Slew);
            }
        }
        if !(fs.is_finite() && fs > 0.0) {
            return Err(DdsError::SampleRate);
        }
        let ph = (phase_rad_per_s as f64 / fs as f64 / core::f64::consts::TAU * 4_294_967_296.0)
            .clamp(1.0, 2_147_483_647.0);
        Ok(Slew {
            amp_per_sample: amp_codes_per_s / fs,
            dc_per_sample: dc_codes_per_s / fs,
            phase_per_sample: ph as u32,
        })
    }
}

/// Target and current state of one channel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Channel {
    /// Current amplitude, codes (may be negative: inverted sine).
    pub amp: f32,
    /// Current DC offset, codes.
    pub dc: f32,
    /// Current phase offset word.
    pub phase: u32,
    /// Target amplitude.
    pub amp_target: f32,
    /// Target DC offset.
    pub dc_target: f32,
    /// Target phase offset.
    pub phase_target: u32,
}

impl Channel {
    /// Whether the channel has reached its targets.
    pub fn settled(&self) -> bool {
        self.amp == self.amp_target && self.dc == self.dc_target && self.phase == self.phase_target
    }

    /// `n` slew steps at once, in the closed form (Q4).
    fn advance(&mut self, s: &Slew, n: u32) {
        let nf = n as f32;
        self.amp = toward(self.amp, self.amp_target, s.amp_per_sample * nf);
        self.dc = toward(self.dc, self.dc_target, s.dc_per_sample * nf);
        let diff = i64::from(self.phase_target.wrapping_sub(self.phase) as i32);
        let lim = i64::from(s.phase_per_sample.min(i32::MAX as u32)) * i64::from(n);
        self.phase = self.phase.wrapping_add(diff.clamp(-lim, lim) as i32 as u32);
    }

    #[inline(always)]
    fn step(&mut self, s: &Slew) {
        self.amp = toward(self.amp, self.amp_target, s.amp_per_sample);
        self.dc = toward(self.dc, self.dc_target, s.dc_per_sample);
        if self.phase != self.phase_target {
            // Shortest way round, limited per sample.
            let diff = self.phase_target.wrapping_sub(self.phase) as i32;
            let lim = s.phase_per_sample.min(i32::MAX as u32) as i32;
            let stepv = diff.clamp(-lim, lim);
            self.phase = self.phase.wrapping_add(stepv as u32);
        }
    }
}

#[inline(always)]
fn toward(x: f32, target: f32, max: f32) -> f32 {
    let d = target - x;
    if d > max {
        x + max
    } else if d < -max {
        x - max
    } else {
        target
    }
}

/// A level (amplitude, DC) request for one channel, in DAC codes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Level {
    /// Amplitude, codes (negative inverts the waveform).
    pub amp: f32,
    /// DC offset, codes.
    pub dc: f32,
}

impl Level {
    /// Checks that the waveform stays inside `0..=4095`.
    ///
    /// # Errors
    /// [`DdsError::Level`].
    pub fn check(&self) -> Result<(), DdsError> {
        if !(self.amp.is_finite() && self.dc.is_finite()) {
            return Err(DdsError::Level);
        }
        let a = self.amp.abs();
        if self.dc - a < 0.0 || self.dc + a > DAC_MAX as f32 {
            return Err(DdsError::Level);
        }
        Ok(())
    }
}

/// The two-channel DDS.
#[derive(Debug, Clone)]
pub struct Dds<'t, const N: usize> {
    table: &'t SineTable<N>,
    fs: f64,
    acc: u32,
    tw: u32,
    /// The reference's steps within a run at `tw`
    /// ([`crate::reference::RunSteps`], formed when `tw` is set, not per
    /// fill).
    steps: crate::reference::RunSteps,
    /// Channel 1 (normal transducer) and channel 2 (tangential).
    ch: [Channel; 2],
    slew: Slew,
    interp: Interp,
}

impl<'t, const N: usize> Dds<'t, N> {
    /// A silent DDS (amplitudes 0, DC 0) at sample rate `fs` (Hz).
    ///
    /// # Errors
    /// [`DdsError::SampleRate`].
    pub fn new(table: &'t SineTable<N>, fs: f64, slew: Slew) -> Result<Self, DdsError> {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(DdsError::SampleRate);
        }
        Ok(Dds {
            table,
            fs,
            acc: 0,
            tw: 0,
            steps: crate::reference::RunSteps::new(table, 0),
            ch: [Channel::default(); 2],
            slew,
            interp: Interp::Reference,
        })
    }

    /// Chooses how the table is read (default [`Interp::Linear`]).
    pub fn set_interp(&mut self, interp: Interp) {
        self.interp = interp;
    }

    /// How the table is read.
    pub fn interp(&self) -> Interp {
        self.interp
    }

    /// The sample rate, Hz.
    pub fn sample_rate(&self) -> f64 {
        self.fs
    }

    /// The achieved output for a requested frequency, without applying it.
    ///
    /// # Errors
    /// [`DdsError::Frequency`] unless `0 < f < f_s/2` and the tuning word is ≥ 1.
    pub fn plan_frequency(&self, hz: f64) -> Result<Achieved, DdsError> {
        if !(hz.is_finite() && hz > 0.0 && hz < self.fs / 2.0) {
            return Err(DdsError::Frequency);
        }
        let tw = libm::round(hz / self.fs * 4_294_967_296.0);
        if tw < 1.0 {
            return Err(DdsError::Frequency);
        }
        let tw = tw as u32;
        Ok(Achieved {
            tuning_word: tw,
            freq_hz: tw as f64 * self.fs / 4_294_967_296.0,
        })
    }

    /// Sets the frequency (phase-continuous: only the increment changes).
    ///
    /// # Errors
    /// As [`Dds::plan_frequency`]; the state is unchanged on error.
    pub fn set_frequency(&mut self, hz: f64) -> Result<Achieved, DdsError> {
        let a = self.plan_frequency(hz)?;
        self.set_tuning_word(a.tuning_word);
        Ok(a)
    }

    /// Sets the tuning word directly (phase-continuous: the accumulator
    /// runs on), for a frequency the caller keeps inside `(0, f_s/2)`
    /// (the resonance tracking's small steps).
    pub fn set_tuning_word(&mut self, tw: u32) {
        if tw != self.tw {
            self.steps = crate::reference::RunSteps::new(self.table, tw);
        }
        self.tw = tw;
    }

    /// The tuning word (phase increment per sample).
    pub fn tuning_word(&self) -> u32 {
        self.tw
    }

    /// Sets a channel's target level (reached at the slew rate).
    ///
    /// # Errors
    /// [`DdsError::Level`]; the state is unchanged on error.
    pub fn set_level(&mut self, ch: usize, level: Level) -> Result<(), DdsError> {
        level.check()?;
        let c = &mut self.ch[ch & 1];
        c.amp_target = level.amp;
        c.dc_target = level.dc;
        Ok(())
    }

    /// Sets a channel's target phase offset (word; reached at the slew rate,
    /// the shortest way round). Returns the exact phase in radians.
    pub fn set_phase(&mut self, ch: usize, word: u32) -> f64 {
        self.ch[ch & 1].phase_target = word;
        phase_rad(word)
    }

    /// The slew limits in force.
    pub fn slew(&self) -> Slew {
        self.slew
    }

    /// Sets the slew limits.
    pub fn set_slew(&mut self, slew: Slew) {
        self.slew = slew;
    }

    /// Ramps every target to zero amplitude (soft stop); DC is kept.
    pub fn ramp_down(&mut self) {
        for c in &mut self.ch {
            c.amp_target = 0.0;
        }
    }

    /// Channel states.
    pub fn channels(&self) -> &[Channel; 2] {
        &self.ch
    }

    /// Whether both channels have reached their targets.
    pub fn settled(&self) -> bool {
        self.ch[0].settled() && self.ch[1].settled()
    }

    /// The phase accumulator (the drive phase of the *next* sample).
    pub fn accumulator(&self) -> u32 {
        self.acc
    }

    /// The exact phase between channel 2 and channel 1, radians in `[0, 2π)`
    /// (current offsets, not targets).
    pub fn phase_between(&self) -> f64 {
        phase_rad(self.ch[1].phase.wrapping_sub(self.ch[0].phase))
    }

    /// One sample: returns `(drive phase, ch1 code, ch2 code)` and advances
    /// (eqs. Q1–Q3 on the channels' state, then one slew step).
    #[inline(always)]
    pub fn next_codes(&mut self) -> (u32, u16, u16) {
        let acc = self.acc;
        let [a, b] = self.ch.map(|c| {
            let f = Fixed::of(c.amp, c.dc, c.phase);
            f.code(self.table.sin_q30_with(self.interp, acc.wrapping_add(f.ph)))
        });
        self.acc = acc.wrapping_add(self.tw);
        let s = self.slew;
        self.ch[0].step(&s);
        self.ch[1].step(&s);
        (acc, a, b)
    }

    /// Fills `buf` with packed DHR12RD words (what the DMA half-buffer refill
    /// does), in integers (eqs. Q1–Q3). Settled channels keep one set of
    /// scale factors for the whole fill; while a channel ramps, sample `i`
    /// of the fill uses the state `i` slew steps on, in the closed form
    ///
    /// ```text
    /// x_i = x_0 + clamp(x_target − x_0, −i·s, i·s)                      (Q4)
    /// ```
    ///
    /// for the amplitude and DC (in the units of Q2, the slew `s` rounded
    /// likewise) and the phase offset (words, the shortest way round) — the
    /// same sequence as one slew step per sample, and what
    /// `plant::HalfDrive` reconstructs. The channels' state is then moved
    /// on by `buf.len()` steps.
    pub fn fill(&mut self, buf: &mut [u32]) {
        let mut refs = [0u32; BLOCK];
        for chunk in buf.chunks_mut(BLOCK) {
            let n = chunk.len();
            self.fill_with_reference(chunk, &mut refs[..n], &mut []);
        }
    }

    /// [`Dds::fill`] that also writes the packed reference words (eq. R1)
    /// of the fill's samples — the DDS's own phases `acc + i·tw` — for the
    /// ADC block this fill drives (issue 35: one product per sample serves
    /// the DAC and the ADC's lock-ins): sample `i`'s word goes to `head[i]`
    /// for `i < head.len()`, then to `tail[i − head.len()]` (two places, so
    /// that a caller can lay them out as the ADC sees them, `L` samples
    /// late). Settled fills, and fills whose levels all arrive within one
    /// sample ([`Dds::fill_path`]), form their codes from those words (eq.
    /// Q6, bound Q7; the table's reading `interp` is then not used); a ramp
    /// reads the table (Q1–Q4).
    ///
    /// Returns `false`, with `buf` filled by [`Dds::fill`] and `head`,
    /// `tail` untouched, when they hold fewer words than `buf`.
    pub fn fill_with_reference(
        &mut self,
        buf: &mut [u32],
        head: &mut [u32],
        tail: &mut [u32],
    ) -> bool {
        let n = buf.len();
        if head.len() + tail.len() < n {
            self.fill(buf);
            return false;
        }
        let k = head.len().min(n);
        let (head, tail) = (&mut head[..k], &mut tail[..n - k]);
        let t = self.table;
        let (acc, tw) = (self.acc, self.tw);
        let steps = &self.steps;
        crate::reference::fill_steps(t, acc, steps, head);
        let acc_k = acc.wrapping_add(tw.wrapping_mul(k as u32));
        crate::reference::fill_steps(t, acc_k, steps, tail);
        if self.fill_path() == FillPath::Table {
            // The accumulator and the channels move in the table's loops.
            match self.interp {
                Interp::Nearest => self.fill_table::<false>(buf),
                Interp::Linear | Interp::Reference => self.fill_table::<true>(buf),
            }
            return true;
        }
        // Sample 0 at the levels now, the rest at the targets' (the same
        // when settled).
        let now = self.ch.map(|c| RefCoef::of(t, c.amp, c.dc, c.phase));
        let to = if self.settled() {
            now
        } else {
            self.ch
                .map(|c| RefCoef::of(t, c.amp_target, c.dc_target, c.phase_target))
        };
        let (b_head, b_tail) = buf.split_at_mut(k);
        if k > 0 {
            synthesize(b_head, head, now, to);
            synthesize(b_tail, tail, to, to);
        } else {
            synthesize(b_tail, tail, now, to);
        }
        let s = self.slew;
        for c in &mut self.ch {
            c.advance(&s, n as u32);
        }
        self.acc = acc.wrapping_add(tw.wrapping_mul(n as u32));
        true
    }

    /// Which equations the next fill's codes follow: [`FillPath::Reference`]
    /// (Q6, bound Q7) with [`Interp::Reference`] when both channels are
    /// settled or every quantity reaches its target within one sample's
    /// slew, else [`FillPath::Table`] (Q1–Q4, bound Q5 plus the ramp's
    /// rounding).
    pub fn fill_path(&self) -> FillPath {
        if self.interp == Interp::Reference && (self.settled() || self.one_step()) {
            FillPath::Reference
        } else {
            FillPath::Table
        }
    }

    /// Whether every quantity reaches its target within one sample's slew
    /// (eq. Q4 with `n ≤ 1` for all six, in the units of Q2: the
    /// displacement loops' fills, whose slew is a whole step): then sample
    /// 0 has the levels now and every later one the targets'.
    fn one_step(&self) -> bool {
        let s = &self.slew;
        let (sa, sd) = (
            step_of(s.amp_per_sample, 262_144.0),
            step_of(s.dc_per_sample, 65_536.0),
        );
        let sp = s.phase_per_sample.min(i32::MAX as u32);
        self.ch.iter().all(|c| {
            let (from, to) = (
                Fixed::of(c.amp, c.dc, c.phase),
                Fixed::of(c.amp_target, c.dc_target, c.phase_target),
            );
            // Q4's n = ⌈|dist|/step⌉ ≤ 1 (0 for no distance).
            (to.ka - from.ka).unsigned_abs() <= sa
                && (to.kd - from.kd).unsigned_abs() <= sd
                && (to.ph.wrapping_sub(from.ph) as i32).unsigned_abs() <= sp
        })
    }
}

/// One quantity's ramp over a fill in the units of (Q2) (eq. Q4):
/// `x_i = x_0 + i·dx` for `i < n`, then the target `x_t` (wrapping, for
/// phase words).
#[derive(Debug, Clone, Copy)]
struct Lin {
    x0: i32,
    dx: i32,
    n: u32,
    xt: i32,
}

impl Lin {
    /// From `x0` toward `xt` by at most `step ≥ 0` per sample; `dist` is
    /// the signed distance (`xt − x0`, or the shortest way round for phase
    /// words). `n = ⌈|dist|/step⌉` samples reach the target: eq. (Q4)'s
    /// clamp in closed form, with one hardware division per fill.
    fn new(x0: i32, xt: i32, dist: i32, step: u32) -> Self {
        let d = dist.unsigned_abs();
        let n = match step {
            0 if d == 0 => 0,
            0 => u32::MAX,
            s => d.div_ceil(s),
        };
        // |dx| = step < |dist| ≤ 2³¹ whenever n > 1; otherwise unused.
        let dx = if n > 1 { step as i32 } else { 0 };
        Lin {
            x0,
            dx: if dist < 0 { dx.wrapping_neg() } else { dx },
            n,
            xt,
        }
    }

    /// The value at sample `i` and the step to the next, for a segment
    /// that starts at `i` and ends by the next breakpoint: `dx` before `n`,
    /// 0 from it.
    #[inline(always)]
    fn from(&self, i: u32) -> (i32, i32) {
        (self.at(i), if i < self.n { self.dx } else { 0 })
    }

    #[inline(always)]
    fn at(&self, i: u32) -> i32 {
        if i < self.n {
            // |i·dx| < |dist|: no overflow for amplitude and DC; phase
            // words wrap by design.
            self.x0.wrapping_add((i as i32).wrapping_mul(self.dx))
        } else {
            self.xt
        }
    }
}

/// A slew in the units of (Q2): `x·scale` truncated, at most `2³¹ − 1`
/// (a larger step reaches any target in one sample anyway).
fn step_of(per_sample: f32, scale: f32) -> u32 {
    (per_sample * scale).clamp(0.0, 2_147_483_647.0) as u32
}

/// A ramping channel's fill (eq. Q4): amplitude, DC and phase offset.
#[derive(Debug, Clone, Copy)]
struct Ramp {
    ka: Lin,
    kd: Lin,
    ph: Lin,
}

impl Ramp {
    fn of(c: &Channel, s: &Slew) -> Self {
        let (from, to) = (
            Fixed::of(c.amp, c.dc, c.phase),
            Fixed::of(c.amp_target, c.dc_target, c.phase_target),
        );
        Ramp {
            ka: Lin::new(
                from.ka,
                to.ka,
                to.ka - from.ka,
                step_of(s.amp_per_sample, 262_144.0),
            ),
            kd: Lin::new(
                from.kd,
                to.kd,
                to.kd - from.kd,
                step_of(s.dc_per_sample, 65_536.0),
            ),
            ph: Lin::new(
                from.ph as i32,
                to.ph as i32,
                to.ph.wrapping_sub(from.ph) as i32,
                s.phase_per_sample.min(i32::MAX as u32),
            ),
        }
    }

    /// The targets' scale factors (Q4 once every quantity reached it).
    fn target(&self) -> Fixed {
        Fixed {
            ka: self.ka.xt,
            kd: self.kd.xt,
            ph: self.ph.xt as u32,
        }
    }

    /// The scale factors at sample `i` (Q4) and their increments per
    /// sample up to the next breakpoint ([`Lin::from`]).
    fn from(&self, i: u32) -> (Fixed, Fixed) {
        let (ka, dka) = self.ka.from(i);
        let (kd, dkd) = self.kd.from(i);
        let (ph, dph) = self.ph.from(i);
        (
            Fixed {
                ka,
                kd,
                ph: ph as u32,
            },
            Fixed {
                ka: dka,
                kd: dkd,
                ph: dph as u32,
            },
        )
    }
}

impl<const N: usize> Dds<'_, N> {
    /// The table read of (Q1), linear or the nearest entry.
    #[inline(always)]
    fn read<const LINEAR: bool>(t: &SineTable<N>, phase: u32) -> i32 {
        if LINEAR {
            t.sin_q30(phase)
        } else {
            t.sin_q30_nearest(phase)
        }
    }

    /// A fill from the table (eqs. Q1–Q4): settled channels at one set of
    /// scale factors, a change within one sample's slew as sample 0 at the
    /// factors now and the rest at the targets' (Q4 with `n ≤ 1`, without
    /// the general ramp's segments), else the ramp.
    fn fill_table<const LINEAR: bool>(&mut self, buf: &mut [u32]) {
        let t = self.table;
        let now = self.ch.map(|c| Fixed::of(c.amp, c.dc, c.phase));
        if self.settled() {
            self.acc = Self::fill_fixed::<LINEAR>(t, self.tw, buf, now[0], now[1], self.acc);
        } else if self.one_step() {
            let to = self
                .ch
                .map(|c| Fixed::of(c.amp_target, c.dc_target, c.phase_target));
            let (head, tail) = buf.split_at_mut(buf.len().min(1));
            let acc = Self::fill_fixed::<LINEAR>(t, self.tw, head, now[0], now[1], self.acc);
            self.acc = Self::fill_fixed::<LINEAR>(t, self.tw, tail, to[0], to[1], acc);
            let (n, s) = (buf.len() as u32, self.slew);
            for c in &mut self.ch {
                c.advance(&s, n);
            }
        } else {
            self.fill_ramping::<LINEAR>(buf);
        }
    }

    /// `buf` at fixed scale factors from accumulator `acc`; the
    /// accumulator after it.
    #[inline(always)]
    fn fill_fixed<const LINEAR: bool>(
        t: &SineTable<N>,
        tw: u32,
        buf: &mut [u32],
        f0: Fixed,
        f1: Fixed,
        mut acc: u32,
    ) -> u32 {
        for w in buf.iter_mut() {
            let a = f0.code(Self::read::<LINEAR>(t, acc.wrapping_add(f0.ph)));
            let b = f1.code(Self::read::<LINEAR>(t, acc.wrapping_add(f1.ph)));
            *w = pack_dual(a, b);
            acc = acc.wrapping_add(tw);
        }
        acc
    }

    /// `buf` from accumulator `acc` with scale factors that start at
    /// `(f0, f1)` and step by the increments `(d0, d1)` after every sample
    /// (wrapping, as Q4's `x₀ + i·dx`); the accumulator after it.
    #[inline(always)]
    fn fill_steps<const LINEAR: bool>(
        t: &SineTable<N>,
        tw: u32,
        buf: &mut [u32],
        (mut f0, d0): (Fixed, Fixed),
        (mut f1, d1): (Fixed, Fixed),
        mut acc: u32,
    ) -> u32 {
        for w in buf.iter_mut() {
            let a = f0.code(Self::read::<LINEAR>(t, acc.wrapping_add(f0.ph)));
            let b = f1.code(Self::read::<LINEAR>(t, acc.wrapping_add(f1.ph)));
            *w = pack_dual(a, b);
            acc = acc.wrapping_add(tw);
            f0 = f0.step(d0);
            f1 = f1.step(d1);
        }
        acc
    }

    /// A channel ramps: the scale factors per sample by (Q4) while any
    /// quantity is short of its target, the targets' fixed factors after
    /// (the settled loop: a level changed by less than a slew step costs
    /// one ramping sample), then the channels' state `buf.len()` steps on.
    fn fill_ramping<const LINEAR: bool>(&mut self, buf: &mut [u32]) {
        let [r0, r1] = self.ch.map(|c| Ramp::of(&c, &self.slew));
        let t = self.table;
        let mut acc = self.acc;
        let ramping = [r0, r1]
            .iter()
            .map(|r| r.ka.n.max(r.kd.n).max(r.ph.n))
            .max()
            .unwrap_or(0)
            .min(buf.len() as u32);
        // The head in segments between the samples where a quantity reaches
        // its target: inside one, each quantity either steps by its slew
        // every sample or stays at its target (Q4), so the loop adds
        // increments instead of evaluating (Q4) per sample (issue 35: 93
        // instructions per sample while ramping, the settled loop's 41 plus
        // the adds after).
        let mut ends = [
            r0.ka.n, r0.kd.n, r0.ph.n, r1.ka.n, r1.kd.n, r1.ph.n, ramping,
        ]
        .map(|n| n.min(ramping));
        ends.sort_unstable();
        let mut start = 0u32;
        for end in ends {
            if end <= start {
                continue;
            }
            let seg = &mut buf[start as usize..end as usize];
            acc = Self::fill_steps::<LINEAR>(t, self.tw, seg, r0.from(start), r1.from(start), acc);
            start = end;
        }
        let tail = &mut buf[ramping as usize..];
        // Every quantity at its target (Q4 for i ≥ n).
        self.acc = Self::fill_fixed::<LINEAR>(t, self.tw, tail, r0.target(), r1.target(), acc);
        let n = buf.len() as u32;
        let s = self.slew;
        for c in &mut self.ch {
            c.advance(&s, n);
        }
    }
}

/// `buf[i]` = the packed codes (eq. Q6) of reference word `refs[i]`: the
/// channels' factors `first` for sample 0, `rest` after.
#[inline(always)]
fn synthesize(buf: &mut [u32], refs: &[u32], first: [RefCoef; 2], rest: [RefCoef; 2]) {
    let n = buf.len().min(refs.len());
    if n == 0 {
        return;
    }
    buf[0] = packed_codes(first[0], first[1], refs[0]);
    let [f0, f1] = rest;
    for (w, &r) in buf[1..n].iter_mut().zip(&refs[1..n]) {
        *w = packed_codes(f0, f1, r);
    }
}

/// The DHR12RD word (channel 1 low, channel 2 high) of reference word `r`
/// for the factors `f0`, `f1` (eq. Q6).
#[inline(always)]
fn packed_codes(f0: RefCoef, f1: RefCoef, r: u32) -> u32 {
    f0.code(r) | (f1.code(r) << 16)
}

/// Rounds a real code to the nearest integer and clamps it to `0..=4095`.
#[inline(always)]
pub fn quantise(x: f32) -> u16 {
    // NaN compares false everywhere and lands on 0.
    let r = x + 0.5;
    if r >= DAC_MAX as f32 {
        DAC_MAX
    } else if r >= 0.0 {
        r as u16
    } else {
        0
    }
}
