//! The simulated plant behind the ADC: transducers, contact and force
//! sensors, driven by the DDS exactly as the board's analog side is. One
//! implementation for both simulated boards: the host's virtual device
//! (`f64`, with lag, drift, stage profile and noise) and the firmware built
//! for QEMU (`f32`, whose emulated STM32F405 has no DAC, ADC DMA or analog
//! world: its main loop runs this plant on each DAC half-buffer instead).
//!
//! **Transducers.** Ideal ones (the default) displace by the DAC level times
//! the board's calibration, optionally with a first-order amplitude lag
//! (below). Resonant ones ([`Resonant`], built on
//! [`crate::resonator::Mode`]) are two second-order modes driven by
//! the DAC channels' AC voltage ([`DAC_VOLTS_PER_CODE`] per code), each
//! advanced by its exact zero-order-hold update on every sub-step (the DAC
//! holds a sample's voltage), with a resonance drift (Hz/s), self-heating
//! (a shift per squared amplitude, filtered with [`THERMAL_TAU_S`]),
//! cross-talk between the channels, and the contact's load as damping; the
//! normal channel's DC offset stays quasi-static through the calibration.
//! The contact then sees the modes' displacements instead of the ideal
//! waveforms.
//!
//! Per half-buffer of `n` samples the plant sees the DDS channels before and
//! after the refill ([`HalfDrive`]): the transducers' amplitudes Δu_z, Δu_x,
//! the offset u_z0 and the phase offsets move linearly between the two
//! across the half (the DDS ramps its levels at the slew rate during the
//! fill, phases the shortest way round); the transducers follow the
//! amplitudes with a first-order lag
//! (`keep` = e^(−T_s/τ) per sample, exact for a constant target over one
//! sample). The normal displacement is u_z = u_z0 + Δu_z sin(θ + p₁), the
//! tangential u_x = Δu_x sin(θ + p₂) relative to the stage (the device sets
//! p₁ = −π/2, p₂ = φ + π/2, so these are eqs. 1–2 of the paper). The contact
//! is the paper's spring scheme ([`SpringContact`], eqs. 3–5) in the frame
//! of the stage's position at the start of the half-buffer: within the half
//! the stage's travel s(t) = Σ v0·dt is added to u_x (a fresh product per
//! sub-step, no growing sum of tiny increments), and at the end of the half
//! the contact point is moved into the next half's frame (u_x,c −= s). So no
//! coordinate grows with time and no per-step increment is lost to rounding:
//! an `f32` plant keeps its resolution for hours (a contact point of ~1 µm
//! has a 1e-13 m ulp, a tenth of a sub-step's travel of 1e-9 m at 4 mm/s —
//! subtracting the travel from it step by step would round it systematically). Sample `i` is taken at the phase of DAC word
//! `i − adc_lag_samples` ([`DeviceConfig::adc_lag_samples`]), converted by
//! the ADC calibrations (counts = F/gain + offset, rounded, clamped to
//! 0…full scale); the motion pickups of sample `i` are taken
//! [`DeviceConfig::pickup_delay_s`] = δ later, as the board's ADCs convert
//! them (0 ≤ δ < one sample, as the device requires): ideal transducers at
//! the drive phase advanced by `ω·δ` (the closed form, by a rotation formed
//! once per half), resonant ones by the mode's exact zero-order-hold update
//! over δ with the sample's held voltage ([`Mode::update_for`], formed once
//! per half after the retune) applied to a copy of the state (δ = 0 samples
//! at the force's instant, bitwise as before); then the plant advances to
//! the next tick in `sub` sub-steps (the paper's scheme on a finer grid: its μ error is
//! ≈ 10·(1+b)/N² for N = `sub`·f_s/f steps per period, the fixed-step bound
//! of [`model_core::fixed_step::error_bound`]).

use crate::dds::Channel;
use crate::device::{Device, DeviceConfig};
use crate::resonator::{HoldUpdate, Mode, ModeError, ModeParams};
use model_core::fixed_step::SpringContact;
use model_core::float::{Float, Math};

/// Radians per phase-accumulator unit: 2π/2³², as the DDS (f = tw·f_s/2³²).
const RAD_PER_WORD: f64 = core::f64::consts::TAU / 4_294_967_296.0;

/// The drive of one DAC half-buffer as the transducers receive it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfDrive {
    /// DDS channel states (codes) before the refill.
    pub before: [Channel; 2],
    /// DDS channel states after it.
    pub after: [Channel; 2],
    /// Phase accumulator at the half's first sample.
    pub acc0: u32,
    /// Tuning word (phase increment per sample).
    pub tw: u32,
    /// The DDS's slew limits during the fill (the resonant transducers
    /// follow the channels' per-sample ramps exactly: each sample's
    /// amplitude and phase are the DDS's own, `Dds::fill`).
    pub slew: crate::dds::Slew,
}

impl HalfDrive {
    /// Refills DAC half `half` through the device ([`Device::fill_dac`]) and
    /// returns what that half drives.
    pub fn fill<const N: usize>(dev: &mut Device<'_, N>, half: usize, buf: &mut [u32]) -> Self {
        let before = *dev.dds().channels();
        let acc0 = dev.dds().accumulator();
        let tw = dev.dds().tuning_word();
        dev.fill_dac(half, buf);
        HalfDrive {
            before,
            after: *dev.dds().channels(),
            acc0,
            tw,
            slew: dev.dds().slew(),
        }
    }

    /// Channel `c`'s amplitude (codes) and phase offset (word) at sample
    /// `i` of the half, as the DDS outputs it: the state before the fill
    /// moved `i` slew steps towards the fill's targets (`Dds::fill` writes a
    /// sample, then steps; the targets are the ones `after` holds).
    pub fn channel_at(&self, c: usize, i: usize) -> (f32, u32) {
        let (b, a) = (self.before[c], self.after[c]);
        let n = i as f32;
        let da = (a.amp_target - b.amp)
            .max(-self.slew.amp_per_sample * n)
            .min(self.slew.amp_per_sample * n);
        let dp = a.phase_target.wrapping_sub(b.phase) as i32 as i64;
        let lim = i64::from(self.slew.phase_per_sample.min(i32::MAX as u32)) * i as i64;
        (
            b.amp + da,
            b.phase.wrapping_add(dp.clamp(-lim, lim) as i32 as u32),
        )
    }

    /// Drive phase advance per sample, radians.
    pub fn dtheta(&self) -> f64 {
        f64::from(self.tw) * RAD_PER_WORD
    }
}

/// Uniform ADC noise: xorshift64 (Marsaglia 2003, shifts 13, 7, 17), the
/// top 24 bits of each draw as a fraction in [0, 1) (exact in `f32` and
/// `f64`, so both plants draw the same numbers from the same seed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Noise {
    state: u64,
}

impl Noise {
    /// A generator from a non-zero seed (0 is replaced by a fixed one).
    pub const fn new(seed: u64) -> Self {
        Noise {
            state: if seed == 0 {
                0x9E37_79B9_7F4A_7C15
            } else {
                seed
            },
        }
    }

    /// A draw uniform in [−`amplitude`, `amplitude`).
    pub fn uniform<F: Float>(&mut self, amplitude: F) -> F {
        self.state ^= self.state << 13;
        self.state ^= self.state >> 7;
        self.state ^= self.state << 17;
        let u = F::from_u32((self.state >> 40) as u32) * F::from_f64(1.0 / 16_777_216.0);
        (F::TWO * u - F::ONE) * amplitude
    }
}

/// What the plant meets at one sample (from the caller: time-dependent
/// friction, stage velocity, ADC noise).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleConditions<F> {
    /// True friction coefficient μ₀ of the contact.
    pub mu0: F,
    /// Stage velocity v₀, m/s.
    pub v0: F,
    /// Added to the normal-force reading, ADC counts (noise, offset error).
    pub counts_z: F,
    /// Added to the tangential-force reading, ADC counts.
    pub counts_x: F,
}

pub use crate::dds::DAC_VOLTS_PER_CODE;

/// What makes the resonant transducers' resonances move and couple.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResonantOptions<F> {
    /// The normal (0) and tangential (1) modes at rest: f_r (Hz), Q, static
    /// gain (m per volt at the DAC pin).
    pub modes: [ModeParams<F>; 2],
    /// Drift of each resonance, Hz/s of device time.
    pub drift_hz_per_s: [F; 2],
    /// Thermal shift of each resonance per squared amplitude, Hz/µm²: the
    /// self-heating of a mode follows its amplitude² with the time constant
    /// [`THERMAL_TAU_S`].
    pub thermal_hz_per_um2: F,
    /// Cross-talk: this fraction of each channel's drive voltage also
    /// drives the other mode.
    pub crosstalk: F,
    /// The contact's load as extra damping: 1/Q_eff = 1/Q + 1/`load_q` (∞ for none).
    pub load_q: F,
}

/// The bench's transducers, the default of the virtual device and of the
/// firmware built for QEMU with `qemu-resonant`: a Langevin pair near
/// 20 kHz, normal mode 20 300 Hz, Q 300; tangential 19 700 Hz, Q 200;
/// static gains a thirtieth of the board's ideal calibration per DAC volt
/// (`metres_per_code / DAC_VOLTS_PER_CODE / 30`), so that driven at 20 kHz
/// the amplitudes come out near the calibration but the phases lag by ≈ 6°
/// and ≈ 170°; the contact's load 1/Q_load = 1/2000; no drift, heating or
/// cross-talk.
pub mod bench {
    /// Normal resonance, Hz.
    pub const RESONANCE_Z_HZ: f64 = 20_300.0;
    /// Tangential resonance, Hz.
    pub const RESONANCE_X_HZ: f64 = 19_700.0;
    /// Normal Q.
    pub const Q_Z: f64 = 300.0;
    /// Tangential Q.
    pub const Q_X: f64 = 200.0;
    /// The contact's load: 1/Q_eff = 1/Q + 1/`LOAD_Q`.
    pub const LOAD_Q: f64 = 2000.0;
    /// Static gain ÷ (ideal calibration per DAC volt).
    pub const GAIN_FRACTION: f64 = 1.0 / 30.0;

    /// Static gain of a channel with ideal calibration `metres_per_code`, m/V.
    pub fn gain(metres_per_code: f32) -> f64 {
        f64::from(metres_per_code) / super::DAC_VOLTS_PER_CODE * GAIN_FRACTION
    }
}

impl<F: Float> ResonantOptions<F> {
    /// The bench's transducers ([`bench`](mod@bench)) for the board configuration `cfg`.
    pub fn bench(cfg: &DeviceConfig) -> Self {
        let f = F::from_f64;
        ResonantOptions {
            modes: [
                ModeParams {
                    resonance_hz: f(bench::RESONANCE_Z_HZ),
                    q: f(bench::Q_Z),
                    gain_m_per_v: f(bench::gain(cfg.dac_z.metres_per_code)),
                },
                ModeParams {
                    resonance_hz: f(bench::RESONANCE_X_HZ),
                    q: f(bench::Q_X),
                    gain_m_per_v: f(bench::gain(cfg.dac_x.metres_per_code)),
                },
            ],
            drift_hz_per_s: [F::ZERO; 2],
            thermal_hz_per_um2: F::ZERO,
            crosstalk: F::ZERO,
            load_q: f(bench::LOAD_Q),
        }
    }
}

impl<F: Float> ResonantOptions<F> {
    /// What an exact identification of these transducers at rest finds
    /// (`fricctl device identify`'s model, eq. 1 of
    /// [`crate::identify`]): each mode's resonance, its Q with the
    /// contact's load, its static gain, and the phase lag of the DAC's
    /// hold, half a sample at the resonance (`θ = π f_r/f_s`); drift and
    /// heating are not in it.
    pub fn identified(&self, sample_rate_hz: f64) -> crate::device::Transducers {
        let m = |c: usize| {
            let p = Resonant::loaded(self, self.modes[c]);
            let f = p.resonance_hz.to_f64();
            crate::device::TransducerModel {
                resonance_hz: f as f32,
                q: p.q.to_f64() as f32,
                gain_m_per_v: p.gain_m_per_v.to_f64() as f32,
                phase_lag_rad: (core::f64::consts::PI * f / sample_rate_hz) as f32,
            }
        };
        crate::device::Transducers { z: m(0), x: m(1) }
    }
}

/// Time constant of the transducers' self-heating, s (a Langevin stack's
/// thermal time is seconds to minutes; one second keeps tests short).
pub const THERMAL_TAU_S: f64 = 1.0;

/// A resonant mode whose displacement and velocity over ω are both below
/// this (m) at the start of a half-buffer is set to rest
/// ([`Mode::settle_below`](crate::dsp::resonator::Mode::settle_below)):
/// 10⁻³⁰ m is twenty decades below one ADC count of the pickups and eight
/// above `f32`'s smallest normal number, so neither precision's
/// arithmetic reaches the subnormal range through a ringing-down mode.
pub const SUBNORMAL_FLOOR_M: f64 = 1e-30;

/// Resonant transducers: two modes driven by the DAC channels' AC voltage
/// (the normal channel's DC offset acts quasi-statically through the
/// calibration, as before).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resonant<F> {
    /// The options the modes follow.
    pub opts: ResonantOptions<F>,
    /// The normal and tangential modes (state and current update).
    pub modes: [Mode<F>; 2],
    /// Device time since the plant started, s.
    pub time_s: F,
    /// Each mode's filtered amplitude², µm² (the self-heating).
    pub heat_um2: [F; 2],
}

/// Why resonant transducers cannot be formed (a mode's parameter, or a
/// coupling outside its domain).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResonantError {
    /// A mode's parameter (channel 0 normal, 1 tangential).
    Mode(usize, ModeError),
    /// A drift, the thermal shift or the cross-talk is not finite, or
    /// |cross-talk| ≥ 1.
    Coupling,
    /// The load's Q must be > 0 (∞ for none).
    LoadQ,
}

impl core::fmt::Display for ResonantError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ResonantError::Mode(c, e) => {
                let ch = if *c == 0 { "normal" } else { "tangential" };
                write!(f, "{ch} transducer: {e}")
            }
            ResonantError::Coupling => f.write_str(
                "drift and thermal shift must be finite, cross-talk finite with |c| < 1",
            ),
            ResonantError::LoadQ => f.write_str("the load's Q must be > 0"),
        }
    }
}

impl<F: Float> Resonant<F> {
    /// Transducers at rest, updated with sub-steps of `h` s.
    ///
    /// # Errors
    /// [`ResonantError`] naming what is out of its domain.
    pub fn new(opts: ResonantOptions<F>, h: F) -> Result<Self, ResonantError> {
        let ok = |x: F| x.is_finite();
        if !(opts.drift_hz_per_s.iter().all(|&d| ok(d))
            && ok(opts.thermal_hz_per_um2)
            && ok(opts.crosstalk)
            && opts.crosstalk.abs() < F::ONE)
        {
            return Err(ResonantError::Coupling);
        }
        if opts.load_q.is_nan() || opts.load_q <= F::ZERO {
            return Err(ResonantError::LoadQ);
        }
        let mode = |c: usize| {
            Mode::new(Self::loaded(&opts, opts.modes[c]), h).map_err(|e| ResonantError::Mode(c, e))
        };
        Ok(Resonant {
            opts,
            modes: [mode(0)?, mode(1)?],
            time_s: F::ZERO,
            heat_um2: [F::ZERO; 2],
        })
    }

    /// A mode's parameters with the contact's load: 1/Q_eff = 1/Q + 1/Q_load.
    fn loaded(opts: &ResonantOptions<F>, p: ModeParams<F>) -> ModeParams<F> {
        let inv = F::ONE / p.q
            + if opts.load_q.is_finite() {
                F::ONE / opts.load_q
            } else {
                F::ZERO
            };
        ModeParams {
            q: F::ONE / inv,
            ..p
        }
    }

    /// The modes' parameters now (drift, heat and load applied).
    pub fn params_now(&self) -> [ModeParams<F>; 2] {
        core::array::from_fn(|c| {
            let base = self.opts.modes[c];
            let shift = self.opts.drift_hz_per_s[c] * self.time_s
                + self.opts.thermal_hz_per_um2 * self.heat_um2[c];
            Self::loaded(
                &self.opts,
                ModeParams {
                    resonance_hz: (base.resonance_hz + shift).max(F::ONE),
                    ..base
                },
            )
        })
    }

    /// Moves time on by `dt` s (heat filtered toward each mode's amplitude²)
    /// and retunes the modes for sub-steps of `h` s; a retune that fails
    /// (a resonance driven below 1 Hz, say) keeps the last update.
    fn advance(&mut self, dt: F, h: F) {
        self.time_s += dt;
        let k = F::ONE - F::from_f64(libm::exp(-dt.to_f64() / THERMAL_TAU_S));
        let um = F::from_f64(1e6);
        for c in 0..2 {
            let m = &self.modes[c];
            let w = F::TAU * m.params().resonance_hz;
            let (x, v) = (m.x() * um, m.v() / w * um);
            self.heat_um2[c] += (x * x + v * v - self.heat_um2[c]) * k;
        }
        let now = self.params_now();
        for (m, p) in self.modes.iter_mut().zip(now) {
            let _ = m.retune(p, h);
            m.settle_below(F::from_f64(SUBNORMAL_FLOOR_M));
        }
    }
}

/// The plant's state: the true contact and the transducers' amplitudes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plant<F> {
    /// The true contact (μ₀, k_z, k_x in N/m) and its contact point relative
    /// to the stage at the start of the next half-buffer, m.
    pub contact: SpringContact<F>,
    /// Ideal transducers' amplitudes (Δu_z, Δu_x) now, m (unused with
    /// [`Plant::resonant`]).
    pub amp: (F, F),
    /// Resonant transducers (`None`: ideal ones, the DAC level times the
    /// calibration with an optional first-order lag).
    pub resonant: Option<Resonant<F>>,
    /// A normal excursion limit, m (∞ by default): samples whose normal AC
    /// displacement `|u_z − u_z0|` exceeds it are counted in
    /// [`Plant::samples_above`] (a bench's check of the lift-off guard on
    /// the true motion, at every sample).
    pub excursion_limit_m: F,
    /// Samples whose normal excursion exceeded [`Plant::excursion_limit_m`].
    pub samples_above: u64,
    /// The largest normal excursion of the last half-buffer, m.
    pub peak_excursion_m: F,
}

impl<F: Float> Plant<F> {
    /// A plant at rest with the contact `μ₀, k_z, k_x` (N/m) and ideal transducers.
    pub fn new(mu0: F, kz: F, kx: F) -> Self {
        Plant {
            contact: SpringContact::new(mu0, kz, kx),
            amp: (F::ZERO, F::ZERO),
            resonant: None,
            excursion_limit_m: F::from_f64(f64::INFINITY),
            samples_above: 0,
            peak_excursion_m: F::ZERO,
        }
    }

    /// Simulates one half-buffer of `out.len()` samples driven by `d`,
    /// writing the ADC readings `(f_x, f_z)` in counts. `keep` is the
    /// amplitude lag per sample (0: the transducers follow the DAC
    /// exactly); `at(i)` gives the conditions of sample `i`; `sub ≥ 1`
    /// sub-steps per sample.
    pub fn run_half<M: Math<F>>(
        &mut self,
        cfg: &DeviceConfig,
        d: &HalfDrive,
        sub: u32,
        keep: F,
        at: impl FnMut(usize) -> SampleConditions<F>,
        out: &mut [(u16, u16)],
    ) {
        self.run_half_with_pickups::<M>(cfg, d, sub, keep, at, out, &mut []);
    }

    /// [`Plant::run_half`] that also writes the motion pickups' readings
    /// `(z, x)` in counts ([`DeviceConfig::pickup_z`], `pickup_x`: the
    /// transducers' AC displacement [`DeviceConfig::pickup_delay_s`] after
    /// each sample's forces, rounded and clamped like the forces) into
    /// `pickups` (as many samples as it holds).
    #[allow(clippy::too_many_arguments)]
    pub fn run_half_with_pickups<M: Math<F>>(
        &mut self,
        cfg: &DeviceConfig,
        d: &HalfDrive,
        sub: u32,
        keep: F,
        mut at: impl FnMut(usize) -> SampleConditions<F>,
        out: &mut [(u16, u16)],
        pickups: &mut [(u16, u16)],
    ) {
        let n = out.len().max(1);
        let sub = sub.max(1);
        let f = |x: f32| F::from_f64(f64::from(x));
        let (mz, mx) = (f(cfg.dac_z.metres_per_code), f(cfg.dac_x.metres_per_code));
        // u_z0 and the phase offsets ramp too (DC at the slew rate, phases
        // the shortest way round): interpolated across the half like Δu.
        let uz0_a = (f(d.before[0].dc) - f(cfg.dac_z.zero_code)) * mz;
        let uz0_b = (f(d.after[0].dc) - f(cfg.dac_z.zero_code)) * mz;
        let (duz_a, dux_a) = (f(d.before[0].amp) * mz, f(d.before[1].amp) * mx);
        let (duz_b, dux_b) = (f(d.after[0].amp) * mz, f(d.after[1].amp) * mx);
        let inv_n = F::ONE / F::from_u32(n as u32);
        let (ddz, ddx) = ((duz_b - duz_a) * inv_n, (dux_b - dux_a) * inv_n);
        let d_uz0 = (uz0_b - uz0_a) * inv_n;
        // Signed phase change of each channel over the half, words.
        let dp = |c: usize| d.after[c].phase.wrapping_sub(d.before[c].phase) as i32 as i64;
        let (dp1, dp2) = (dp(0), dp(1));
        let nn = n as i64;
        if keep == F::ZERO {
            self.amp = (duz_a, dux_a);
        }
        let dt = F::ONE / (F::from_f64(cfg.sample_rate_hz) * F::from_u32(sub));
        let vpc = F::from_f64(DAC_VOLTS_PER_CODE);
        if let Some(r) = self.resonant.as_mut() {
            // Drift, heat and load for this half; the modes' update for the sub-step.
            r.advance(F::from_u32(n as u32) / F::from_f64(cfg.sample_rate_hz), dt);
        }
        // The pickups δ after the forces (module docs): the drive's phase
        // advance over δ for ideal transducers, the modes' exact update over
        // δ (the sample's voltage held) for resonant ones.
        let delay = cfg.pickup_delay_s;
        let delayed = !pickups.is_empty() && delay.is_finite() && delay > 0.0;
        let turn =
            delayed.then(|| M::sin_cos(F::from_f64(d.dtheta() * delay * cfg.sample_rate_hz)));
        let ahead: Option<[HoldUpdate<F>; 2]> = match self.resonant.as_ref() {
            Some(r) if delayed => {
                let h = F::from_f64(delay);
                match (r.modes[0].update_for(h), r.modes[1].update_for(h)) {
                    (Ok(uz), Ok(ux)) => Some([uz, ux]),
                    _ => None,
                }
            }
            _ => None,
        };
        // The sub-step rotation: (sin, cos) of θ advanced by dθ/sub.
        let (sd, cd) = M::sin_cos(F::from_f64(d.dtheta() / f64::from(sub)));
        let rad = F::from_f64(RAD_PER_WORD);
        let word0 = d.acc0.wrapping_sub(cfg.adc_lag_samples.wrapping_mul(d.tw));
        let (zg, zo) = (f(cfg.adc_z.gain), f(cfg.adc_z.offset));
        let (xg, xo) = (f(cfg.adc_x.gain), f(cfg.adc_x.offset));
        let full = F::from_u32(u32::from(cfg.adc_full_scale));
        // Rounded to the nearest count (ties up) and clamped, all in F.
        let counts = |v: F| (v.max(F::ZERO).min(full) + F::HALF).to_u32() as u16;
        let (pzg, pzo) = (f(cfg.pickup_z.gain), f(cfg.pickup_z.offset));
        let (pxg, pxo) = (f(cfg.pickup_x.gain), f(cfg.pickup_x.offset));
        let mut pick = |i: usize, xz: F, xx: F| {
            if let Some(p) = pickups.get_mut(i) {
                *p = (counts(xz / pzg + pzo), counts(xx / pxg + pxo));
            }
        };
        // The stage's travel since the start of the half, m.
        let mut travel = F::ZERO;
        let mut peak = F::ZERO;
        let limit = self.excursion_limit_m;
        let mut above = 0u64;
        let mut excursion = |e: F| {
            let e = e.abs();
            peak = peak.max(e);
            if e > limit {
                above += 1;
            }
        };
        for (i, o) in out.iter_mut().enumerate() {
            let c = at(i);
            self.contact.mu0 = c.mu0;
            let (duz, dux) = self.amp;
            // Phases as accumulator words (exact, wrapping), then radians.
            let w = word0.wrapping_add((i as u32).wrapping_mul(d.tw));
            let ramp = |c: usize, dpc: i64| match dpc {
                0 => d.before[c].phase,
                _ => d.before[c]
                    .phase
                    .wrapping_add((dpc * i as i64 / nn) as i32 as u32),
            };
            let (p1, p2) = (ramp(0, dp1), ramp(1, dp2));
            let (mut s1, mut c1) = M::sin_cos(F::from_u32(w.wrapping_add(p1)) * rad);
            let (mut s2, mut c2) = M::sin_cos(F::from_u32(w.wrapping_add(p2)) * rad);
            let uz0 = uz0_a + d_uz0 * F::from_u32(i as u32);
            let step = c.v0 * dt;
            if let Some(r) = self.resonant.as_mut() {
                // The DAC holds each channel's AC voltage over the sample
                // (its waveform level at this word, the lagged ADC phase as
                // for ideal transducers; amplitude and phase the DDS's own
                // at this sample); cross-talk mixes the two.
                let (a1, q1) = d.channel_at(0, i);
                let (a2, q2) = d.channel_at(1, i);
                let (s1, _) = M::sin_cos(F::from_u32(w.wrapping_add(q1)) * rad);
                let (s2, _) = M::sin_cos(F::from_u32(w.wrapping_add(q2)) * rad);
                let (vz, vx) = (f(a1) * s1 * vpc, f(a2) * s2 * vpc);
                let k = r.opts.crosstalk;
                let (vz, vx) = (vz + k * vx, vx + k * vz);
                let [mzd, mxd] = &mut r.modes;
                match &ahead {
                    Some([uz, ux]) => pick(i, mzd.x_after(uz, vz), mxd.x_after(ux, vx)),
                    None => pick(i, mzd.x(), mxd.x()),
                }
                excursion(mzd.x());
                let (fx, fz) = self.contact.step(mxd.x() + travel, uz0 + mzd.x());
                *o = (
                    counts(fx / xg + xo + c.counts_x),
                    counts(fz / zg + zo + c.counts_z),
                );
                for j in 1..=sub {
                    let (xz, xx) = (mzd.step(vz), mxd.step(vx));
                    let x = travel + step * F::from_u32(j);
                    self.contact.step(xx + x, uz0 + xz);
                }
                travel += step * F::from_u32(sub);
                continue;
            }
            match turn {
                // sin(α + ωδ) = sin α cos ωδ + cos α sin ωδ.
                Some((sw, cw)) => pick(i, duz * (s1 * cw + c1 * sw), dux * (s2 * cw + c2 * sw)),
                None => pick(i, duz * s1, dux * s2),
            }
            excursion(duz * s1);
            let (fx, fz) = self.contact.step(dux * s2 + travel, uz0 + duz * s1);
            *o = (
                counts(fx / xg + xo + c.counts_x),
                counts(fz / zg + zo + c.counts_z),
            );
            // Sub-steps to the next tick, the stage moving on meanwhile.
            for j in 1..=sub {
                (s1, c1) = (s1 * cd + c1 * sd, c1 * cd - s1 * sd);
                (s2, c2) = (s2 * cd + c2 * sd, c2 * cd - s2 * sd);
                let x = travel + step * F::from_u32(j);
                self.contact.step(dux * s2 + x, uz0 + duz * s1);
            }
            travel += step * F::from_u32(sub);
            // The transducers move towards the DAC's amplitudes for the next sample.
            let w = F::from_u32(i as u32 + 1);
            let (tz, tx) = (duz_a + ddz * w, dux_a + ddx * w);
            self.amp = (tz + (duz - tz) * keep, tx + (dux - tx) * keep);
        }
        // Into the frame of the next half's start.
        self.contact.uxc -= travel;
        self.peak_excursion_m = peak;
        self.samples_above += above;
    }
}
