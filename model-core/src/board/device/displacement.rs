//! The displacement mode (protocol v5, [`DriveMode::Displacement`]): the
//! identified transducers ([`Transducers`]) turn the setting's displacements
//! into DAC voltages (feed-forward), and a complex (I/Q) loop per channel on
//! the pickups' lock-ins removes what the model missed, so that the
//! *measured* amplitudes and φ hold the setting.
//!
//! **Phasors** (the convention of [`crate::board::identify`], eq. 1): a
//! channel's DAC wave `dc + A·sin(θ + p)` (codes, θ the DDS phase) is the
//! voltage phasor `U = A·v·e^{j(p − π/2)}`, `v` =
//! [`DAC_VOLTS_PER_CODE`]; a pickup's `A cos(θ + ψ)` is `X = A·e^{jψ}`
//! (the lock-in's `a − j b`); a mode answers `X = H(f)·U`. The setting
//! asks `u_z = −Δu_z cos θ`, `u_x = Δu_x cos(θ + φ)` (eqs. 1–2):
//!
//! ```text
//! (D1)  D_z = −Δu_z,   D_x = Δu_x·e^{jφ}                      (m)
//! (D2)  U = D / (Ĥ(f)·c)                                       (V)
//! (D3)  c ← c·(1 + k·(X − D)/D),   k = min(1/2, T_w/(4 τ̂)),   τ̂ = Q̂/(π f̂_r)
//! ```
//!
//! Ĥ is the identified model at the drive frequency, `c` a complex
//! correction per channel (1 at first, again after a new frequency or new
//! transducers) and `T_w` the lock-in window's duration. With `X = H·U`,
//! `X/D = H/(Ĥ c)`: the fixed point of D3 is `c = H/Ĥ`, where the measured
//! motion equals the setting whatever the model's error. Near it the loop
//! is an integrator of time constant `T_w/k = 4τ̂` acting through the mode's
//! envelope lag τ: `s²·τ·4τ̂ + s·4τ̂ + 1 = 0`, damping `ζ = √(τ̂/τ)`,
//! critically damped for a right τ̂ and never oscillatory for τ ≤ τ̂. The
//! learned c survives a change of amplitude or φ (the ratio H/Ĥ does not
//! depend on them), so a new setpoint is met in the mode's own τ.
//!
//! **Limits.** The voltage of D2 must fit in the DAC around the channel's
//! DC (the normal offset's codes, the tangential zero code): a setting that
//! does not is refused ([`DeviceError::OutOfRange`] with the largest
//! displacement the model gives there); a correction that would leave it is
//! not taken (the channel is `saturated`, the loop holds c: anti-windup).
//!
//! **Holding** ([`Status::settled`] in this mode): the DDS at its targets and
//! the relative error `|X − D|/|D|` of every driven channel (and `|X|` of an
//! undriven one, against [`HOLD_FLOOR_M`]) within [`HOLD_TOLERANCE`] for
//! [`HOLD_WINDOWS`] windows in a row (the error is averaged over
//! the windows with [`SMOOTHING_S`], as the status reports it in this
//! mode, so a single noisy window neither makes nor breaks it).
//!
//! **Ramps.** A change of voltage rings in a detuned mode; a new setting's
//! voltage ramps over [`RAMP_TAUS`] envelope time constants (bound there).

use num_complex::Complex32 as C;

use super::{Device, DeviceError, DriveParam, DriveSetting, Status};
use crate::board::dds::{Achieved, Level, DAC_VOLTS_PER_CODE};
pub use crate::board::protocol::messages::{DriveMode, TransducerModel, Transducers};
use crate::float::{FastF32, Math};

/// Largest relative error `|X − D|/|D|` of a held channel: 0.4 %, so the
/// amplitude is within 0.4 % and φ within 0.23° of the setting per channel
/// (0.46° between the two modes).
pub const HOLD_TOLERANCE: f32 = 0.004;

/// Windows in a row within [`HOLD_TOLERANCE`] before the drive holds.
pub const HOLD_WINDOWS: u8 = 4;

/// An undriven channel holds while its measured amplitude is below this, m
/// (cross-talk of the other channel and the pickup's noise: a few counts).
pub const HOLD_FLOOR_M: f32 = 2e-8;

/// Envelope time constants τ̂ a displacement-mode start or change of
/// setting lasts: the voltage ramps from 0 to its full amplitude over
/// `RAMP_TAUS·τ̂` (the slower mode's). A ramp of duration T into a mode
/// detuned by Δω leaves a ringing of relative size
/// `|1 − e^{sT}|/|sT| ≤ 2/(|s|·T)`, `s = −1/τ + jΔω` (the response to a
/// linear ramp, minus the ramp): ≈ 50 % for the DDS's own 2 ms at 300 Hz
/// detuning, ≤ 2/RAMP_TAUS·τ/T… ≈ 7 % over 4τ (τ 4 ms, 300 Hz), and never
/// more than 2/RAMP_TAUS = 50 % of the step on resonance (Δω = 0, where the
/// envelope rises monotonically: no ringing at all).
pub const RAMP_TAUS: f32 = 4.0;

/// The motion's smoothing time for the status and the holding test, s: an
/// exponential average of the windows' phasors (one window every 128 µs at
/// 20 kHz: the noise falls by ≈ √(2·1 ms/128 µs) ≈ 4).
pub const SMOOTHING_S: f32 = 1e-3;

/// The displacement loops' state.
#[derive(Debug, Clone, Copy)]
pub(super) struct Loops {
    /// The correction c of each channel (D2, D3).
    pub(super) c: [C; 2],
    /// The correction would leave the DAC range (held).
    pub(super) saturated: [bool; 2],
    /// Windows in a row within the tolerance.
    pub(super) good: u8,
    /// The smoothed measured phasors (`None` until the first window after
    /// a new setting).
    pub(super) avg: Option<[C; 2]>,
    /// The models' responses Ĥ at the DDS tuning word `.1` (computed once
    /// per frequency, not per window).
    pub(super) model_h: Option<([C; 2], u32)>,
}

impl Default for Loops {
    fn default() -> Self {
        Loops {
            c: [C::new(1.0, 0.0); 2],
            saturated: [false; 2],
            good: 0,
            avg: None,
            model_h: None,
        }
    }
}

/// |c| with the fast f32 backend (the board's: `num-complex`'s own would
/// call libm's `hypotf`, several times dearer on the M4F).
pub fn norm(c: C) -> f32 {
    FastF32::hypot(c.re, c.im)
}

/// arg c in (−π, π], fast f32 backend.
pub fn arg(c: C) -> f32 {
    FastF32::atan2(c.im, c.re)
}

/// `r·e^{jθ}`, fast f32 backend.
pub fn polar(r: f32, theta: f32) -> C {
    let (s, c) = FastF32::sin_cos(theta);
    C::new(r * c, r * s)
}

/// The DDS phase word of `rad` in f32 (`(rad/2π mod 1)·2³²`, resolution
/// 2π/2²⁴ ≈ 4e-7 rad: far below the loops' tolerance; no soft f64 on the M4F).
pub fn phase_word_f32(rad: f32) -> u32 {
    let t = rad * (1.0 / core::f32::consts::TAU);
    let frac = t - libm::floorf(t);
    // frac ∈ [0, 1]: `as` saturates 2³² to u32::MAX (one word short of 0).
    (frac * 4_294_967_296.0) as u32
}

/// The two channels' DDS levels (codes) and phase words of a voltage plan.
pub(super) type VoltagePlan = ([Level; 2], [u32; 2]);

/// Validates a transducer model: every field finite, `f_r` in `(0, 10 MHz]`,
/// `Q` in `(1/2, 10⁶]`, `g` in `(0, 1]` m/V, `|θ| ≤ 2π`.
///
/// # Errors
/// [`DeviceError::OutOfRange`] naming the field.
pub fn check_model(m: &TransducerModel) -> Result<(), DeviceError> {
    let within = |x: f32, lo: f32, hi: f32, p: DriveParam, open_lo: bool| {
        let ok = x.is_finite() && (if open_lo { x > lo } else { x >= lo }) && x <= hi;
        if ok {
            Ok(())
        } else {
            Err(DeviceError::OutOfRange {
                param: p,
                min: lo,
                max: hi,
            })
        }
    };
    within(m.resonance_hz, 0.0, 1e7, DriveParam::Resonance, true)?;
    within(m.q, 0.5, 1e6, DriveParam::Quality, true)?;
    within(m.gain_m_per_v, 0.0, 1.0, DriveParam::TransducerGain, true)?;
    let tau = core::f32::consts::TAU;
    within(m.phase_lag_rad, -tau, tau, DriveParam::PhaseLag, false)
}

/// The model's response Ĥ(f), m/V (eq. 1 of [`crate::board::identify`]).
pub fn model_response(m: &TransducerModel, freq_hz: f32) -> C {
    let r = freq_hz / m.resonance_hz;
    let den = C::new(1.0 - r * r, r / m.q);
    polar(m.gain_m_per_v, -m.phase_lag_rad) / den
}

/// The setting's displacement phasors (D1), m.
pub fn setpoint(d: &DriveSetting) -> [C; 2] {
    [C::new(-d.amp_z_m, 0.0), polar(d.amp_x_m, d.phase_rad)]
}

/// The DDS level and phase word of a voltage phasor `u` (V) on a channel
/// with DC `dc` (codes): `A = |U|/v`, `p = arg U + π/2` (D2's convention).
fn level_of(u: C, dc: f32) -> (Level, u32) {
    let v = DAC_VOLTS_PER_CODE as f32;
    let amp = norm(u) / v;
    let word = phase_word_f32(arg(u) + core::f32::consts::FRAC_PI_2);
    (Level { amp, dc }, word)
}

impl<const N: usize> Device<'_, N> {
    /// The displacement mode is in force (stored transducers and
    /// [`DriveMode::Displacement`]).
    pub fn displacement_mode(&self) -> bool {
        self.mode == DriveMode::Displacement && self.transducers.is_some()
    }

    /// The drive mode in force.
    pub fn drive_mode(&self) -> DriveMode {
        self.mode
    }

    /// The stored transducers.
    pub fn transducers(&self) -> Option<Transducers> {
        self.transducers
    }

    /// Stores the identified transducers (validated whole), or forgets them.
    /// New transducers start the corrections c over (the accepted drive is
    /// re-planned through them while in displacement mode).
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`] naming a field of a model;
    /// [`DeviceError::NotIdentified`] for `None` in displacement mode;
    /// a re-plan's refusal (as [`Device::set_drive`]). Nothing changes on
    /// error.
    pub fn set_transducers(&mut self, t: Option<Transducers>) -> Result<(), DeviceError> {
        match t {
            Some(t) => {
                check_model(&t.z)?;
                check_model(&t.x)?;
                if self.mode == DriveMode::Displacement {
                    let old = (self.transducers, self.loops);
                    self.transducers = Some(t);
                    self.loops = Loops::default();
                    if let Err(e) = self.replan() {
                        (self.transducers, self.loops) = old;
                        return Err(e);
                    }
                } else {
                    self.transducers = Some(t);
                    self.loops = Loops::default();
                }
                Ok(())
            }
            None if self.mode == DriveMode::Displacement => Err(DeviceError::NotIdentified),
            None => {
                self.transducers = None;
                Ok(())
            }
        }
    }

    /// Switches the drive mode; the accepted drive is re-planned in the new
    /// mode (ramped while running).
    ///
    /// # Errors
    /// [`DeviceError::NotIdentified`] for the displacement mode without
    /// transducers; [`DeviceError::Busy`] while the closed μ loop runs;
    /// the drive's refusal in the new mode (e.g. a voltage beyond the DAC).
    /// Nothing changes on error.
    pub fn set_drive_mode(&mut self, mode: DriveMode) -> Result<(), DeviceError> {
        if mode == DriveMode::Displacement && self.transducers.is_none() {
            return Err(DeviceError::NotIdentified);
        }
        if mode == self.mode {
            return Ok(());
        }
        if self.control_on() {
            return Err(DeviceError::Busy);
        }
        let old = (self.mode, self.loops);
        self.mode = mode;
        self.loops = Loops::default();
        if let Err(e) = self.replan() {
            (self.mode, self.loops) = old;
            return Err(e);
        }
        Ok(())
    }

    /// Plans the accepted drive again and applies it as `set_drive` would.
    fn replan(&mut self) -> Result<(), DeviceError> {
        let d = self.drive;
        self.set_drive(d).map(|_| ())
    }

    /// The voltage plan of a drive in displacement mode (D2): the two
    /// channels' amplitudes (codes) and phase words, for DC codes `dc` and
    /// corrections `c`; `None` outside displacement mode.
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`] (`AmpZ` or `AmpX`, with the largest
    /// displacement the model reaches at this frequency) for a voltage
    /// beyond the DAC around its DC.
    pub(super) fn voltage_plan(
        &self,
        d: &DriveSetting,
        at: &Achieved,
        dc: [f32; 2],
        c: [C; 2],
    ) -> Result<Option<VoltagePlan>, DeviceError> {
        let Some(t) = self
            .transducers
            .filter(|_| self.mode == DriveMode::Displacement)
        else {
            return Ok(None);
        };
        let target = setpoint(d);
        let h_model = self.model_h_at(&t, at);
        let mut levels = [Level { amp: 0.0, dc: 0.0 }; 2];
        let mut words = [0u32; 2];
        for ch in 0..2 {
            let h = h_model[ch] * c[ch];
            let (lv, w) = level_of(target[ch] / h, dc[ch]);
            let room = dc[ch].min(f32::from(crate::board::dds::DAC_MAX) - dc[ch]);
            // NaN (a zero model response) fails the comparison: refused.
            let fits = lv.amp <= room;
            if !fits || lv.check().is_err() {
                let max = room.max(0.0) * DAC_VOLTS_PER_CODE as f32 * norm(h);
                return Err(DeviceError::OutOfRange {
                    param: if ch == 0 {
                        DriveParam::AmpZ
                    } else {
                        DriveParam::AmpX
                    },
                    min: 0.0,
                    max,
                });
            }
            // A zero displacement keeps the ideal phase (no arg of 0).
            words[ch] = if norm(target[ch]) > 0.0 {
                w
            } else {
                self.ideal_phase_word(ch, d)
            };
            levels[ch] = lv;
        }
        Ok(Some((levels, words)))
    }

    /// The closed μ loop's command Δu_z = `u` (m) on the normal channel:
    /// in voltage mode its calibration level, in displacement mode the
    /// voltage of D2 with the loop's learned correction (the displacement
    /// loop then holds it). `true` when applied (the DAC took it).
    pub(super) fn command_normal(&mut self, u: f32) -> bool {
        let (z, off) = (self.cfg.dac_z, self.drive.offset_z_m);
        let dc = z.zero_code + off / z.metres_per_code;
        if self.displacement_mode() {
            let d = DriveSetting {
                amp_z_m: u,
                ..self.drive
            };
            let at = self.applied.achieved;
            let dcx = self.dds.channels()[1].dc_target;
            match self.voltage_plan(&d, &at, [dc, dcx], self.loops.c) {
                Ok(Some((levels, words))) if self.dds.set_level(0, levels[0]).is_ok() => {
                    self.dds.set_phase(0, words[0]);
                    self.loops.good = 0;
                    true
                }
                _ => false,
            }
        } else {
            let lz = Level {
                amp: u / z.metres_per_code,
                dc,
            };
            self.dds.set_level(0, lz).is_ok()
        }
    }

    /// The models' responses Ĥ at the DDS frequency `at` (cached per tuning
    /// word: the loop's windows reuse them).
    fn model_h_at(&self, t: &Transducers, at: &Achieved) -> [C; 2] {
        match self.loops.model_h {
            Some((h, tw)) if tw == at.tuning_word => h,
            _ => {
                let f = at.freq_hz as f32;
                [model_response(&t.z, f), model_response(&t.x, f)]
            }
        }
    }

    /// One loop step (D3) at the end of a lock-in window of `window_s`
    /// seconds that measured the phasors `x` (m): updates the corrections,
    /// applies the new voltages, counts the windows within tolerance.
    pub(super) fn displacement_step(&mut self, x: [C; 2], window_s: f32) {
        if !self.displacement_mode() || !self.running || self.latch.any() {
            self.loops.good = 0;
            return;
        }
        if !self.dds.settled() {
            // A ramp (start, new setting) is under way: wait for its end.
            self.loops.good = 0;
            return;
        }
        let Some(t) = self.transducers else {
            return;
        };
        let d = self.drive;
        let target = setpoint(&d);
        let at = self.applied.achieved;
        if self
            .loops
            .model_h
            .is_none_or(|(_, tw)| tw != at.tuning_word)
        {
            self.loops.model_h = Some((self.model_h_at(&t, &at), at.tuning_word));
        }
        let alpha = (window_s / SMOOTHING_S).min(1.0);
        let avg = match self.loops.avg {
            Some(a) => [a[0] + (x[0] - a[0]) * alpha, a[1] + (x[1] - a[1]) * alpha],
            None => x,
        };
        self.loops.avg = Some(avg);
        let mut within = true;
        let mut c = self.loops.c;
        for (ch, m) in [t.z, t.x].iter().enumerate() {
            let dn = norm(target[ch]);
            if dn <= 0.0 {
                within &= norm(avg[ch]) <= HOLD_FLOOR_M;
                continue;
            }
            within &= norm((avg[ch] - target[ch]) / target[ch]) <= HOLD_TOLERANCE;
            let e = (x[ch] - target[ch]) / target[ch];
            let tau = m.q / (core::f32::consts::PI * m.resonance_hz);
            let k = (window_s / (4.0 * tau)).min(0.5);
            c[ch] *= C::new(1.0, 0.0) + e * k;
        }
        let dc = [
            self.dds.channels()[0].dc_target,
            self.dds.channels()[1].dc_target,
        ];
        match self.voltage_plan(&d, &at, dc, c) {
            Ok(Some((levels, words))) => {
                self.loops.c = c;
                self.loops.saturated = [false; 2];
                for ch in 0..2 {
                    // Validated by `voltage_plan`: neither fails.
                    let _ = self.dds.set_level(ch, levels[ch]);
                    self.dds.set_phase(ch, words[ch]);
                }
            }
            // Beyond the DAC: hold c (anti-windup).
            _ => self.loops.saturated = [true; 2],
        }
        self.loops.good = if within {
            self.loops.good.saturating_add(1)
        } else {
            0
        };
    }

    /// Whether the drive holds its setting: in displacement mode the
    /// measured motion within tolerance (module docs), else the DDS ramps
    /// finished.
    pub fn drive_settled(&self) -> bool {
        if self.displacement_mode() && self.running {
            self.loops.good >= HOLD_WINDOWS
        } else {
            self.dds.settled()
        }
    }

    /// The DDS's amplitude slew for a new setting with levels `levels`
    /// (codes): in displacement mode the full amplitude over
    /// `RAMP_TAUS·τ̂` ([`RAMP_TAUS`]), never faster than the board's slew;
    /// in voltage mode the board's slew.
    pub(super) fn ramp_slew(&mut self, levels: &[Level; 2]) {
        let Ok(base) = Self::slew(&self.cfg) else {
            return;
        };
        let mut slew = base;
        if let Some(t) = self
            .transducers
            .filter(|_| self.mode == DriveMode::Displacement)
        {
            let tau = |m: &TransducerModel| m.q / (core::f32::consts::PI * m.resonance_hz);
            let n = RAMP_TAUS * tau(&t.z).max(tau(&t.x)) * self.cfg.sample_rate_hz as f32;
            let amp = levels[0].amp.abs().max(levels[1].amp.abs());
            if n > 1.0 && amp > 0.0 {
                slew.amp_per_sample = (amp / n).min(base.amp_per_sample);
            }
        }
        self.dds.set_slew(slew);
    }

    /// The smoothed measured phasors of the displacement loop (m), `None`
    /// outside displacement mode or before a window.
    pub(super) fn smoothed_motion(&self) -> Option<[C; 2]> {
        self.loops
            .avg
            .filter(|_| self.displacement_mode() && self.running)
    }

    /// Fills the v5 fields of a status.
    pub(super) fn displacement_status(&self, s: &mut Status) {
        s.mode = self.mode;
        s.settled = self.drive_settled();
        // In displacement mode the amplitudes and φ are the smoothed ones
        // the holding test uses (the peak stays the largest raw window).
        if let (Some(m), Some(a)) = (s.measured.as_mut(), self.smoothed_motion()) {
            m.amp_z_m = norm(a[0]);
            m.amp_x_m = norm(a[1]);
            // (M1) with ψ = arg X.
            let pi = core::f32::consts::PI;
            let mut phi = arg(a[1]) - arg(a[0]) + pi;
            while phi > pi {
                phi -= 2.0 * pi;
            }
            while phi <= -pi {
                phi += 2.0 * pi;
            }
            m.phase_rad = phi;
        }
    }
}
