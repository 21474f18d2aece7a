//! The simulated plant behind the ADC: transducers, contact and force
//! sensors, driven by the DDS exactly as the board's analog side is. One
//! implementation for both simulated boards: the host's virtual device
//! (`f64`, with lag, drift, stage profile and noise) and the firmware built
//! for QEMU (`f32`, whose emulated STM32F405 has no DAC, ADC DMA or analog
//! world: its main loop runs this plant on each DAC half-buffer instead).
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
//! 0…full scale); then the plant advances to the next tick in `sub`
//! sub-steps (the paper's scheme on a finer grid: its μ error is
//! ≈ 10·(1+b)/N² for N = `sub`·f_s/f steps per period, the fixed-step bound
//! of [`crate::fixed_step::error_bound`]).

use crate::board::dds::Channel;
use crate::board::device::{Device, DeviceConfig};
use crate::fixed_step::SpringContact;
use crate::float::{Float, Math};

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
        }
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

/// The plant's state: the true contact and the transducers' amplitudes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plant<F> {
    /// The true contact (μ₀, k_z, k_x in N/m) and its contact point relative
    /// to the stage at the start of the next half-buffer, m.
    pub contact: SpringContact<F>,
    /// Transducer amplitudes (Δu_z, Δu_x) now, m.
    pub amp: (F, F),
}

impl<F: Float> Plant<F> {
    /// A plant at rest with the contact `μ₀, k_z, k_x` (N/m).
    pub fn new(mu0: F, kz: F, kx: F) -> Self {
        Plant {
            contact: SpringContact::new(mu0, kz, kx),
            amp: (F::ZERO, F::ZERO),
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
        mut at: impl FnMut(usize) -> SampleConditions<F>,
        out: &mut [(u16, u16)],
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
        // The sub-step rotation: (sin, cos) of θ advanced by dθ/sub.
        let (sd, cd) = M::sin_cos(F::from_f64(d.dtheta() / f64::from(sub)));
        let rad = F::from_f64(RAD_PER_WORD);
        let word0 = d.acc0.wrapping_sub(cfg.adc_lag_samples.wrapping_mul(d.tw));
        let (zg, zo) = (f(cfg.adc_z.gain), f(cfg.adc_z.offset));
        let (xg, xo) = (f(cfg.adc_x.gain), f(cfg.adc_x.offset));
        let full = F::from_u32(u32::from(cfg.adc_full_scale));
        // Rounded to the nearest count (ties up) and clamped, all in F.
        let counts = |v: F| (v.max(F::ZERO).min(full) + F::HALF).to_u32() as u16;
        // The stage's travel since the start of the half, m.
        let mut travel = F::ZERO;
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
            let (fx, fz) = self.contact.step(dux * s2 + travel, uz0 + duz * s1);
            *o = (
                counts(fx / xg + xo + c.counts_x),
                counts(fz / zg + zo + c.counts_z),
            );
            // Sub-steps to the next tick, the stage moving on meanwhile.
            let step = c.v0 * dt;
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
    }
}
