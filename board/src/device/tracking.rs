//! Resonance tracking (protocol v6, [`Track`]): a phase-locked loop on the
//! measured phase of one mode moves the one DDS frequency onto that mode's
//! resonance, so φ between the modes stays defined (both channels share the
//! DDS) and the other mode is held by its displacement loop.
//!
//! **Phase detector.** A window's measured response of the tracked mode,
//! `R = X/U` (the lock-in's phasor over the fill's voltage phasor), is the
//! mode's `H(f) = g·e^{−jθ}/(1 − r² + j r/Q)`, `r = f/f_r` (eq. 1 of
//! [`crate::identify`]). With the identified θ̂ and Q̂, the
//! denominator's angle `α = −θ̂ − arg R` (π/2 on resonance) gives r exactly:
//!
//! ```text
//! (T1)  tan α = (r/Q̂)/(1 − r²)  ⇒  r = (−κ + √(κ² + 4))/2,  κ = cot α / Q̂
//! (T2)  f̂_r = f / r,   e = f̂_r − f                        (Hz, "tracking_error_hz")
//! (T3)  f ← f + k·e,   k = min(1/2, T_w/(2τ̂)),   τ̂ = Q̂/(π f̂_r)
//! ```
//!
//! T1 is monotonic over the whole `α ∈ (0, π)`: the detector's range is
//! every frequency where the mode answers above the noise; the loop's
//! range is bounded instead by [`TRACK_RANGE`] around the identified
//! resonance (beyond it the identified model no longer vouches for the
//! voltage). T3 is an integrator of time constant `T_w/k = 2τ̂` acting
//! through the mode's own envelope lag τ (the phase settles with it after a
//! frequency step): damping `ζ = ½√(2τ̂/τ) ≈ 0.71`, so the error decays in
//! a few τ̂ and a drift ḟ is followed with a lag `2τ̂·ḟ` (0.2 Hz for
//! −20 Hz/s at τ̂ = 4.8 ms). The model of the tracked mode is centred on the
//! smoothed estimate f̂_r (the displacement loop's Ĥ and envelope dynamics
//! follow the resonance; its correction c stays near 1).
//!
//! **Lock.** Locked after [`LOCK_S`] of windows in a row with
//! `|e| ≤ f̂_r/(2Q̂)` (inside the half-power band). Lost — the fault
//! [`super::faults::LOSS_OF_LOCK`] and the safe state — after
//! [`LOSS_S`] of windows in a row with `|e| > f̂_r/Q̂`, no usable
//! estimate, or the resonance outside the range; and if no lock comes
//! within [`ACQUIRE_TAUS`]·τ̂ of driving. Windows during a transition of the
//! displacement loop (the mode not in its steady state for the fill's
//! voltage) are skipped: their phase is not the resonance's.

use num_complex::Complex32 as C;

use super::displacement::{arg, nonzero, norm_gt, norm_le, HOLD_FLOOR_M, STEADY_FRACTION};
use super::{Device, TransducerModel, Transducers};
pub use crate::protocol::messages::Track;
use model_core::float::{FastF32, Math};

/// The tracked frequency stays within this fraction of the identified
/// resonance (±2 %: six half-power bandwidths at Q 300).
pub const TRACK_RANGE: f32 = 0.02;
/// Time of windows in a row inside the half-power band before the lock is
/// declared, s (eight windows of 128 µs before windows took four blocks;
/// counted in time so that the window's length does not change it).
pub const LOCK_S: f32 = 1.0e-3;
/// Time of windows in a row outside the band before the lock is lost, s
/// (longer than a transition's skipped windows, shorter than τ; sixteen
/// windows of 128 µs before windows took four blocks).
pub const LOSS_S: f32 = 2.0e-3;
/// The least amplitude of the tracked mode's setting, m: below it a
/// window's estimate is refused (`10·HOLD_FLOOR_M`, the pickup's noise), so
/// the tracking could never lock (an undriven mode) or would lose the lock
/// it had. `SetDrive` refuses a smaller setting while tracking is on
/// (`DeviceError::OutOfRange` with this as its least value).
pub const TRACK_MIN_AMP_M: f32 = 10.0 * HOLD_FLOOR_M;

/// Envelope time constants τ̂ the tracking may take to lock.
pub const ACQUIRE_TAUS: f32 = 40.0;

/// The tracker's state.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Tracker {
    /// The tracked mode's smoothed resonance estimate, Hz.
    pub(super) resonance_hz: Option<f32>,
    /// The last window's `e` (T2), Hz.
    pub(super) error_hz: Option<f32>,
    /// Locked.
    pub(super) locked: bool,
    /// Time of windows in a row inside (before the lock) or outside
    /// (after) the band, s.
    run_s: f32,
    /// Seconds of driving since tracking started, without a lock.
    acquiring_s: f32,
    /// The tracked channel is the tangential one.
    channel_is_x: bool,
}

impl Tracker {
    /// The f32 bits of the resonance estimate (0 without one): a key of the
    /// model cache.
    pub(super) fn resonance_bits(&self) -> u32 {
        self.resonance_hz.map_or(0, f32::to_bits)
    }

    /// The two modes' models, the tracked one centred on the estimate.
    pub(super) fn models(&self, t: &Transducers) -> [TransducerModel; 2] {
        let mut m = [t.z, t.x];
        if let Some(f) = self.resonance_hz {
            // Only set while tracking (reset when it stops).
            let ch = usize::from(self.channel_is_x);
            m[ch].resonance_hz = f;
        }
        m
    }
}

impl<const N: usize> Device<'_, N> {
    /// Lets the tracker go: it locks anew from the running frequency.
    pub(super) fn restart_tracking(&mut self) {
        self.tracker = Tracker::default();
    }

    /// Tracking is on and the drive runs in displacement mode.
    pub fn tracking_active(&self) -> bool {
        self.options.track != Track::None && self.displacement_mode() && self.running
    }

    /// One window of the tracking (module docs, T1–T3): `x` the measured
    /// phasors, `mean` the fill's model envelopes, `u` its voltages.
    pub(super) fn tracking_step(
        &mut self,
        t: &Transducers,
        x: [C; 2],
        mean: [C; 2],
        u: [C; 2],
        window_s: f32,
    ) {
        if !self.tracking_active() {
            return;
        }
        let ch = if self.options.track == Track::X { 1 } else { 0 };
        let id = if ch == 0 { t.z } else { t.x };
        let d = super::displacement::setpoint(&self.drive)[ch];
        if !nonzero(d) {
            // Nothing to track on an undriven mode.
            return;
        }
        self.tracker.channel_is_x = ch == 1;
        let f = self.applied.achieved.freq_hz as f32;
        let fr_now = self.tracker.resonance_hz.unwrap_or(id.resonance_hz);
        let tau = id.q / (core::f32::consts::PI * fr_now);
        let half_band = fr_now / (2.0 * id.q);
        if !self.tracker.locked {
            self.tracker.acquiring_s += window_s;
            if self.tracker.acquiring_s > ACQUIRE_TAUS * tau {
                self.fault(super::faults::LOSS_OF_LOCK);
                return;
            }
        }
        // A transition of the displacement loop: not the mode's steady phase.
        let models = self.tracker.models(t);
        let h = super::displacement::model_response(&models[ch], f) * self.loops.c[ch];
        let steady = h * u[ch];
        // (Not within, or NaN.)
        if !norm_le(mean[ch] - steady, STEADY_FRACTION, steady) {
            return;
        }
        let one = C::new(1.0, 0.0);
        let usable = nonzero(u[ch]) && norm_gt(x[ch], TRACK_MIN_AMP_M, one);
        let estimate = if usable {
            resonance_of(x[ch] / u[ch], f, &id)
        } else {
            None
        };
        let lo = id.resonance_hz * (1.0 - TRACK_RANGE);
        let hi = id.resonance_hz * (1.0 + TRACK_RANGE);
        let (cfg_lo, cfg_hi) = self.cfg.freq_range_hz;
        let in_range =
            |g: f32| g >= lo && g <= hi && f64::from(g) >= cfg_lo && f64::from(g) <= cfg_hi;
        let Some(fr) = estimate.filter(|&g| in_range(g)) else {
            self.tracker.error_hz = None;
            self.lock_bad(window_s);
            return;
        };
        let e = fr - f;
        self.tracker.error_hz = Some(e);
        let k = (window_s / (2.0 * tau)).min(0.5);
        let smoothed = fr_now + k * (fr - fr_now);
        self.tracker.resonance_hz = Some(smoothed);
        // T3 on the DDS: the tuning word moves by k·e (phase-continuous).
        let fs = self.cfg.sample_rate_hz as f32;
        let words_per_hz = 4_294_967_296.0 / fs;
        // max/min, not `clamp`: its assertion would pull float formatting
        // into the firmware (lo < hi here).
        let f_new = (f + k * e).max(lo).min(hi);
        let dtw = ((f_new - f) * words_per_hz) as i32;
        if dtw != 0 {
            let tw = self.applied.achieved.tuning_word.wrapping_add(dtw as u32);
            self.dds.set_tuning_word(tw);
            self.applied.achieved = crate::dds::Achieved {
                tuning_word: tw,
                freq_hz: f64::from(tw) * self.cfg.sample_rate_hz / 4_294_967_296.0,
            };
        }
        if self.tracker.locked {
            if e.abs() > 2.0 * half_band {
                self.lock_bad(window_s);
            } else {
                self.tracker.run_s = 0.0;
            }
        } else if e.abs() <= half_band {
            self.tracker.run_s += window_s;
            if self.tracker.run_s >= LOCK_S * (1.0 - 1e-3) {
                self.tracker.locked = true;
                self.tracker.run_s = 0.0;
            }
        } else {
            self.tracker.run_s = 0.0;
        }
    }

    /// A window of `window_s` against the lock: counted after the lock, the
    /// fault after [`LOSS_S`] of them in a row.
    fn lock_bad(&mut self, window_s: f32) {
        if !self.tracker.locked {
            self.tracker.run_s = 0.0;
            return;
        }
        self.tracker.run_s += window_s;
        if self.tracker.run_s >= LOSS_S * (1.0 - 1e-3) {
            self.fault(super::faults::LOSS_OF_LOCK);
        }
    }
}

/// The resonance a measured response `r_meas` (m/V) at `f` (Hz) implies
/// for a mode with the identified phase lag and Q of `m` (T1, T2); `None`
/// when its angle leaves `(0, π)` (no resonance answers it).
pub fn resonance_of(r_meas: C, f: f32, m: &TransducerModel) -> Option<f32> {
    let pi = core::f32::consts::PI;
    let mut alpha = -m.phase_lag_rad - arg(r_meas);
    while alpha > pi {
        alpha -= 2.0 * pi;
    }
    while alpha <= -pi {
        alpha += 2.0 * pi;
    }
    if !(alpha > 0.0 && alpha < pi) {
        return None;
    }
    let (s, c) = FastF32::sin_cos(alpha);
    let kappa = c / (s * m.q);
    let r = (-kappa + libm::sqrtf(kappa * kappa + 4.0)) / 2.0;
    let fr = f / r;
    fr.is_finite().then_some(fr)
}
