//! The transducers' measured motion: the two motion pickups (ADC channels
//! next to the force sensors, [`super::DeviceConfig::pickup_z`], `pickup_x`)
//! through the lock-in of [`crate::lockin`] on the DDS's own phases
//! of each sample (the phases the friction estimate uses, ADC lag included,
//! advanced by the drive's phase over the pickups' conversion delay δ,
//! [`super::DeviceConfig::pickup_delay_s`]: the ADCs convert each pickup
//! 0.714 µs after its force, 10.3° of a 40 kHz drive; demodulated at the
//! force's phase, every measured response would lead the true one by ω·δ,
//! which cancels in φ only). Each window of whole ADC blocks spanning at
//! least one drive period ([`WINDOW_SPAN_RAD`]: one 64-sample block from 7.8 kHz up at
//! 500 kS/s, so every half-buffer at the transducers' frequencies) gives the amplitude and
//! phase of each mode; the phase between them is the φ the contact sees:
//! with the drive `u_z = −Δu_z cos θ`, `u_x = Δu_x cos(θ + φ)` (eqs. 1–2),
//! the pickups read `A_z cos(θ + ψ_z)` and `A_x cos(θ + ψ_x)`, and
//!
//! ```text
//! φ_measured = ψ_x − ψ_z + π   (wrapped to (−π, π])                 (M1)
//! ```
//!
//! which equals φ for ideal transducers and differs by the modes' lag
//! difference for resonant ones.

use super::Device;
use crate::lockin::LockInQ;
pub use crate::protocol::messages::MeasuredDrive;
use model_core::float::FastF32;
use num_complex::Complex32 as C;

/// The least drive phase a window spans, rad: a whole period, where the
/// fit's regressors are nearly orthogonal and its noise gain near the
/// textbook `√(2/N)` (a shorter window would be exact too, but its noise
/// gain grows like 1/span²: `lockin::MIN_SPAN_RAD`).
pub const WINDOW_SPAN_RAD: f32 = core::f32::consts::TAU;
/// [`WINDOW_SPAN_RAD`] in phase words (2³² a turn; ≈ 2³², the f32 2π being 2.8e-8 above it).
const WINDOW_SPAN_WORDS: u64 =
    (WINDOW_SPAN_RAD as f64 / core::f64::consts::TAU * 4_294_967_296.0 + 0.5) as u64;

/// The pickups' lock-ins and the last result.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Motion {
    /// In integers (issue 35): Q15 reference, ADC counts, i64 sums.
    lock: LockInQ<2>,
    last: Option<MeasuredDrive>,
    /// The last window's phasors `X = A·e^{jψ}` of each mode, m.
    phasors: [C; 2],
    peak_z: f32,
    windows: u32,
    /// The pickups' delay in phase words for a tuning word, `(tw, words)`
    /// ([`super::DeviceConfig::pickup_delay_words`], soft-float f64 on
    /// the M4): formed again only when the tuning word changes. `(0, 0)`
    /// holds at power-up (a zero word advances nothing).
    delay: (u32, u32),
}

impl<const N: usize> Device<'_, N> {
    /// [`Device::adc_block`] with the motion pickups' samples `(z, x)` of the
    /// same ticks (on the board the same DMA transfer: ADC1 and ADC2 scan the
    /// force and the pickup input of each axis).
    pub fn adc_block_with_pickups(
        &mut self,
        half: usize,
        forces: &[(u16, u16)],
        pickups: &[(u16, u16)],
    ) {
        self.pickup_block(self.adc_blocks, pickups);
        self.adc_block(half, forces);
    }

    /// The pickups' samples of ADC block `block` into the lock-ins; closes a
    /// window once it spans enough phase.
    fn pickup_block(&mut self, block: u32, pickups: &[(u16, u16)]) {
        let slot = block as usize % super::measure::FILL_RING;
        let (acc0, tw) = self.half[slot];
        // Each pickup sample at its own instant: δ after its force sample
        // (`DeviceConfig::pickup_delay_s`), so the reference starts that
        // much further on (one rounding per block; the rest in words).
        if self.motion.delay.0 != tw {
            self.motion.delay = (tw, self.cfg.pickup_delay_words(tw));
        }
        // = `DeviceConfig::pickup_reference_word(acc0, tw)`.
        let acc = self
            .cfg
            .adc_reference_word(acc0, tw)
            .wrapping_add(self.motion.delay.1);
        // One pass in integers: the DDS's own Q30 table, counts as read.
        self.motion.lock.push_pairs(self.table, acc, tw, pickups);
        let m = &mut self.motion;
        if m.lock.span_words() < WINDOW_SPAN_WORDS {
            return;
        }
        let window_s = m.lock.samples() as f32 / self.cfg.sample_rate_hz as f32;
        let [z, x] = match m.lock.solve() {
            Ok(fit) => fit,
            // Too long for the integer sums (never within the drives'
            // range): started over.
            Err(crate::lockin::LockInError::LongWindow) => {
                m.lock.reset();
                return;
            }
            // A singular window: it grows on until it solves.
            Err(_) => return,
        };
        m.lock.reset();
        // Counts to metres: the pickups' calibrations (offset, gain).
        let (cz, cx) = (self.cfg.pickup_z, self.cfg.pickup_x);
        let metres = |p: crate::lockin::Phasor<f32>, g: f32, offset: f32| crate::lockin::Phasor {
            mean: (p.mean - offset) * g,
            in_phase: p.in_phase * g,
            quadrature: p.quadrature * g,
        };
        let (z, x) = (metres(z, cz.gain, cz.offset), metres(x, cx.gain, cx.offset));
        // X = A·e^{jψ} = a − j b (`displacement`'s phasors).
        let xz = C::new(z.in_phase, -z.quadrature);
        let xx = C::new(x.in_phase, -x.quadrature);
        let (az, ax) = (z.amplitude::<FastF32>(), x.amplitude::<FastF32>());
        let pi = core::f32::consts::PI;
        let mut phi = x.phase::<FastF32>() - z.phase::<FastF32>() + pi;
        while phi > pi {
            phi -= 2.0 * pi;
        }
        while phi <= -pi {
            phi += 2.0 * pi;
        }
        m.peak_z = m.peak_z.max(az);
        m.windows = m.windows.wrapping_add(1);
        let (rz, rx) = (self.response(0, xz), self.response(1, xx));
        self.motion.phasors = [xz, xx];
        let m = &mut self.motion;
        m.last = Some(MeasuredDrive {
            amp_z_m: az,
            amp_x_m: ax,
            phase_rad: phi,
            amp_z_peak_m: m.peak_z,
            windows: m.windows,
            response_z_m_per_v: rz,
            response_x_m_per_v: rx,
        });
        // The guard on the measured motion: Δu_z above u_z0 lifts the
        // contact off (the setting's guard keeps the margin below it).
        let lifts = az > self.drive.offset_z_m.max(super::displacement::HOLD_FLOOR_M);
        if lifts && !self.allow_liftoff {
            self.fault(super::faults::MEASURED_LIFTOFF);
            return;
        }
        self.displacement_step(block, [xz, xx], window_s);
    }

    /// The measured response `X/U` of channel `ch` (m/V, `[re, im]`) to the
    /// voltage the DDS outputs now (`None` at zero voltage).
    fn response(&self, ch: usize, x: C) -> Option<[f32; 2]> {
        let c = self.dds.channels()[ch];
        let v = c.amp * crate::dds::DAC_VOLTS_PER_CODE as f32;
        if v == 0.0 {
            return None;
        }
        // U = v·e^{j(p − π/2)} for the wave `dc + amp·sin(θ + p)`.
        let p = c.phase as f32 * (core::f32::consts::TAU / 4_294_967_296.0)
            - core::f32::consts::FRAC_PI_2;
        let h = x / super::displacement::polar(v, p);
        Some([h.re, h.im])
    }

    /// The last window's phasors of the two modes, m (0 before the first).
    pub(super) fn motion_phasors(&self) -> [C; 2] {
        self.motion.phasors
    }

    /// The last window's measured motion (`None` before the first).
    pub fn measured_drive(&self) -> Option<MeasuredDrive> {
        self.motion.last
    }

    /// Starts the peak over again (an accepted `set_drive` or `start`).
    pub(super) fn reset_motion_peak(&mut self) {
        self.motion.peak_z = 0.0;
    }
}
