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
//! Channel waveforms: `code = dc + amp · sin(2π·(acc + offset)/2³²)`. The drive
//! of the paper (eqs. 1, 2) uses `−cos θ` for the normal channel and
//! `cos(θ + φ)` for the tangential one; [`phase_word`] turns radians into
//! offsets (`−cos θ = sin(θ − π/2)`, `cos(θ+φ) = sin(θ + φ + π/2)`).

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
        for i in 0..N {
            d[i] = t[(i + 1) % N] - t[i];
        }
        SineTable { t, d }
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

    /// `sin(2π·phase/2³²)` by the chosen [`Interp`].
    #[inline(always)]
    pub fn sin_with(&self, interp: Interp, phase: u32) -> f32 {
        match interp {
            Interp::Nearest => self.sin_nearest(phase),
            Interp::Linear => self.sin(phase),
        }
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
}

/// How a [`SineTable`] is read between its entries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Interp {
    /// The nearest entry: one load per sample, error `≈ π/N` of full scale.
    Nearest,
    /// Linear between neighbouring entries: a load pair and a multiply-add,
    /// error `≈ (π/N)²/2` (the board's choice).
    #[default]
    Linear,
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
            ch: [Channel::default(); 2],
            slew,
            interp: Interp::Linear,
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
        self.tw = a.tuning_word;
        Ok(a)
    }

    /// Sets the tuning word directly (phase-continuous: the accumulator
    /// runs on), for a frequency the caller keeps inside `(0, f_s/2)`
    /// (the resonance tracking's small steps).
    pub fn set_tuning_word(&mut self, tw: u32) {
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

    /// Value of one channel for accumulator `acc`, as a real code before rounding.
    #[inline(always)]
    fn value(&self, c: &Channel, acc: u32) -> f32 {
        c.dc + c.amp * self.table.sin_with(self.interp, acc.wrapping_add(c.phase))
    }

    /// One sample: returns `(drive phase, ch1 code, ch2 code)` and advances.
    #[inline(always)]
    pub fn next_codes(&mut self) -> (u32, u16, u16) {
        let acc = self.acc;
        let a = quantise(self.value(&self.ch[0], acc));
        let b = quantise(self.value(&self.ch[1], acc));
        self.acc = acc.wrapping_add(self.tw);
        let s = self.slew;
        self.ch[0].step(&s);
        self.ch[1].step(&s);
        (acc, a, b)
    }

    /// Fills `buf` with packed DHR12RD words (what the DMA half-buffer refill
    /// does). When both channels are settled the slew steps are skipped (the
    /// output is identical, the loop about half as long).
    pub fn fill(&mut self, buf: &mut [u32]) {
        if self.settled() {
            // The interpolation is chosen once per buffer, outside the loop.
            match self.interp {
                Interp::Nearest => self.fill_settled(buf, SineTable::<N>::sin_nearest),
                Interp::Linear => self.fill_settled(buf, SineTable::<N>::sin),
            }
            return;
        }
        for w in buf.iter_mut() {
            let (_, a, b) = self.next_codes();
            *w = pack_dual(a, b);
        }
    }
}

impl<const N: usize> Dds<'_, N> {
    #[inline(always)]
    fn fill_settled(&mut self, buf: &mut [u32], sin: impl Fn(&SineTable<N>, u32) -> f32) {
        let (c0, c1) = (self.ch[0], self.ch[1]);
        let t = self.table;
        let mut acc = self.acc;
        for w in buf.iter_mut() {
            let a = quantise(c0.dc + c0.amp * sin(t, acc.wrapping_add(c0.phase)));
            let b = quantise(c1.dc + c1.amp * sin(t, acc.wrapping_add(c1.phase)));
            *w = pack_dual(a, b);
            acc = acc.wrapping_add(self.tw);
        }
        self.acc = acc;
    }
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
