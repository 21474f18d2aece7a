//! The transducers' measured motion: the two motion pickups (ADC channels
//! next to the force sensors, [`super::DeviceConfig::pickup_z`], `pickup_x`)
//! through the lock-in of [`crate::lockin`] on the DDS's own phases
//! of each sample (the phases the friction estimate uses, ADC lag included,
//! advanced by the drive's phase over the pickups' conversion delay δ,
//! [`super::DeviceConfig::pickup_delay_s`]: the ADCs convert each pickup
//! 0.714 µs after its force, 10.3° of a 40 kHz drive; demodulated at the
//! force's phase, every measured response would lead the true one by ω·δ,
//! which cancels in φ only). Each window of whole ADC blocks spanning at
//! least one drive period ([`WINDOW_SPAN_RAD`]) and [`WINDOW_MIN_SAMPLES`]
//! (four 64-sample blocks, 0.512 ms at 500 kS/s: at the transducers'
//! frequencies every fourth half-buffer) gives the amplitude and
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
use crate::reference::{Gram, PairSums};
use model_core::float::FastF32;
use num_complex::Complex32 as C;

/// The least drive phase a window spans, rad: a whole period, where the
/// fit's regressors are nearly orthogonal and its noise gain near the
/// textbook `√(2/N)` (a shorter window would be exact too, but its noise
/// gain grows like 1/span²: `lockin::MIN_SPAN_RAD`).
pub const WINDOW_SPAN_RAD: f32 = core::f32::consts::TAU;
/// The fewest samples a window holds: four ADC blocks (issue 35: the
/// window's fit, guard, loop step and tracking step once per four
/// half-buffers, not every one). The loops' gains per window scale with
/// the window's length (`k = t_w/4τ` of D3, `t_w/2τ` of T3), so their
/// bandwidth in time is the same; the fills' model records are averaged
/// over the window's blocks.
pub const WINDOW_MIN_SAMPLES: u32 = 256;
/// [`WINDOW_SPAN_RAD`] in phase words (2³² a turn; ≈ 2³², the f32 2π being 2.8e-8 above it).
const WINDOW_SPAN_WORDS: u64 =
    (WINDOW_SPAN_RAD as f64 / core::f64::consts::TAU * 4_294_967_296.0 + 0.5) as u64;

/// The pickups' lock-ins and the last result.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Motion {
    /// In integers (issue 35): Q15 reference, ADC counts, i64 sums.
    lock: LockInQ<2>,
    last: Option<Window>,
    /// The last window's phasors `X = A·e^{jψ}` of each mode, m.
    phasors: [C; 2],
    peak_z: f32,
    windows: u32,
    /// The pickups' delay for a tuning word, `(tw, words, cos δ, sin δ)`
    /// ([`super::config::pickup_delay_words_of`], in integers; the cosine
    /// and sine from the DDS's table, Q30): formed again only when the
    /// tuning word changes (`(0, 0, 0, 0)` at power-up: a zero tuning word
    /// spans no phase and closes no window).
    delay: (u32, u32, f32, f32),
    /// [`super::DeviceConfig::pickup_delay_factor`], formed at the first
    /// window (the configuration is fixed for the device's life).
    delay_factor: Option<u64>,
    /// The tuning word of the last block taken.
    tw: u32,
    /// ADC blocks in the open window.
    blocks: u32,
}

impl Motion {
    /// A chunk of the pickups' samples into the lock-ins, against the
    /// forces' reference words `words` (eq. R1: the pickups' own phase is
    /// δ later; [`Device::motion_window`] turns the fit by δ).
    /// Whether a pickup sample sat at an ADC rail (0 or full scale: the
    /// motion beyond the pickup's range, or its input broken), from the
    /// same pass as the sums.
    pub(super) fn push_block(&mut self, words: &[u32], pickups: &[(u16, u16)], tw: u32) -> bool {
        let g = Gram::of(words);
        let p = PairSums::of(words, pickups);
        self.lock.push_sums(&g, &p, tw);
        self.tw = tw;
        p.railed
    }
}

impl<const N: usize> Device<'_, N> {
    /// [`Device::adc_block`] with the motion pickups' samples `(z, x)` of the
    /// same ticks (on the board the same DMA transfer: ADC1 and ADC2 scan the
    /// force and the pickup input of each axis).
    pub fn adc_block_with_pickups(
        &mut self,
        _half: usize,
        forces: &[(u16, u16)],
        pickups: &[(u16, u16)],
    ) {
        self.intake(forces, pickups);
    }

    /// After a block's pickups: closes the lock-ins' window once it spans
    /// enough phase (the fit, the guard on the measured motion, the
    /// displacement loop's step).
    pub(super) fn motion_window(&mut self, block: u32) {
        self.motion.blocks = self.motion.blocks.saturating_add(1);
        let tw = self.motion.tw;
        // Each pickup sample is taken δ after its force
        // (`DeviceConfig::pickup_delay_s`): fitted against the forces'
        // reference, its phasor leads by ω·δ; the fit is turned back by
        // δ in words (formed again only when the tuning word changes).
        if self.motion.delay.0 != tw {
            let cfg = &self.cfg;
            let k = *self
                .motion
                .delay_factor
                .get_or_insert_with(|| cfg.pickup_delay_factor());
            let d = super::config::pickup_delay_words_of(k, tw);
            let q30 = 1.0 / 1_073_741_824.0;
            let (c, s) = (
                self.table.sin_q30(d.wrapping_add(1 << 30)) as f32 * q30,
                self.table.sin_q30(d) as f32 * q30,
            );
            self.motion.delay = (tw, d, c, s);
        }
        // In a transition of the displacement loop (a channel's voltage
        // cut to its bound or a new setting within the last fills) the
        // window closes at once (one period): the observer (D7) and D3
        // compare it with the fill's own model record, which moves from
        // fill to fill while a transition lasts.
        let moving = self.loops.moving[block as usize % super::measure::FILL_RING];
        let least = if moving[0] || moving[1] {
            0
        } else {
            WINDOW_MIN_SAMPLES
        };
        let m = &mut self.motion;
        if m.lock.span_words() < WINDOW_SPAN_WORDS || m.lock.samples() < least {
            return;
        }
        let window_s = m.lock.samples() as f32 / self.cfg.sample_rate_hz as f32;
        probe!(20);
        let [z, x] = match m.lock.solve() {
            Ok(fit) => fit.map(|p| p.turned(m.delay.2, m.delay.3)),
            // Too long for the integer sums (never within the drives'
            // range): started over.
            Err(crate::lockin::LockInError::LongWindow) => {
                m.lock.reset();
                m.blocks = 0;
                return;
            }
            // A singular window: it grows on until it solves.
            Err(_) => return,
        };
        probe!(21);
        m.lock.reset();
        let blocks = core::mem::take(&mut m.blocks);
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
        // Only what the guard and the loops use now; the rest of the
        // window's report (Δu_x, φ, the responses) is formed when asked
        // (`measured_drive`, in the server's context: issue 35).
        let az = z.amplitude::<FastF32>();
        m.peak_z = m.peak_z.max(az);
        m.windows = m.windows.wrapping_add(1);
        let ch = self.dds.channels();
        let m = &mut self.motion;
        m.phasors = [xz, xx];
        m.last = Some(Window {
            amp_z_m: az,
            amp_z_peak_m: m.peak_z,
            windows: m.windows,
            voltages: [(ch[0].amp, ch[0].phase), (ch[1].amp, ch[1].phase)],
        });
        // The guard on the measured motion: Δu_z above u_z0 lifts the
        // contact off (the setting's guard keeps the margin below it).
        let lifts = az > self.drive.offset_z_m.max(super::displacement::HOLD_FLOOR_M);
        if lifts && !self.allow_liftoff {
            self.fault(super::faults::MEASURED_LIFTOFF);
            return;
        }
        probe!(22);
        self.displacement_step(block, blocks, [xz, xx], window_s);
    }

    /// The measured response `X/U` (m/V, `[re, im]`) to the voltage
    /// `(amp, phase)` (codes, phase word) the DDS put out when the window
    /// closed (`None` at zero voltage).
    fn response(x: C, (amp, phase): (f32, u32)) -> Option<[f32; 2]> {
        let v = amp * crate::dds::DAC_VOLTS_PER_CODE as f32;
        if v == 0.0 {
            return None;
        }
        // U = v·e^{j(p − π/2)} for the wave `dc + amp·sin(θ + p)`.
        let p = phase as f32 * (core::f32::consts::TAU / 4_294_967_296.0)
            - core::f32::consts::FRAC_PI_2;
        let h = x / super::displacement::polar(v, p);
        Some([h.re, h.im])
    }

    /// The last window's phasors of the two modes, m (0 before the first).
    pub(super) fn motion_phasors(&self) -> [C; 2] {
        self.motion.phasors
    }

    /// The last window's measured motion (`None` before the first): its
    /// phasors' amplitudes, the phase between them (eq. M1) and the
    /// responses to the voltages of the window's close.
    pub fn measured_drive(&self) -> Option<MeasuredDrive> {
        let w = self.motion.last?;
        let [xz, xx] = self.motion.phasors;
        Some(MeasuredDrive {
            amp_z_m: w.amp_z_m,
            amp_x_m: super::displacement::norm(xx),
            phase_rad: super::displacement::phase_between(xz, xx),
            amp_z_peak_m: w.amp_z_peak_m,
            windows: w.windows,
            response_z_m_per_v: Self::response(xz, w.voltages[0]),
            response_x_m_per_v: Self::response(xx, w.voltages[1]),
        })
    }

    /// Starts the peak over again (an accepted `set_drive` or `start`).
    pub(super) fn reset_motion_peak(&mut self) {
        self.motion.peak_z = 0.0;
    }
}

/// What a window's close keeps for its report ([`Device::measured_drive`]
/// forms the rest from the phasors when asked).
#[derive(Debug, Clone, Copy)]
struct Window {
    amp_z_m: f32,
    amp_z_peak_m: f32,
    windows: u32,
    /// Each channel's DDS amplitude (codes) and phase word at the close.
    voltages: [(f32, u32); 2],
}
