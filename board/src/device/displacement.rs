//! The displacement mode (protocol v5, [`DriveMode::Displacement`]): the
//! identified transducers ([`Transducers`]) turn the setting's displacements
//! into DAC voltages (feed-forward), and a complex (I/Q) loop per channel on
//! the pickups' lock-ins removes what the model missed, so that the
//! *measured* amplitudes and φ hold the setting.
//!
//! **Phasors** (the convention of [`crate::identify`], eq. 1): a
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
//! [`HOLD_S`] of windows in a row (the error is averaged over
//! the windows with [`SMOOTHING_S`], as the status reports it in this
//! mode, so a single noisy window neither makes nor breaks it); once
//! holding, the drive is released only when an error leaves the twice
//! wider [`RELEASE_TOLERANCE`] (or [`RELEASE_FLOOR_M`]): hysteresis, so
//! that the smoothed error's noise never releases a held drive.
//!
//! **Transitions** (v6, eqs. D4–D6). Each mode's complex envelope (the
//! phasor in the frame of the drive, at the drive frequency ω) obeys, for a
//! voltage `U` held over a DAC fill of `T` seconds (the rotating-frame form
//! of the mode's equation, exact for the positive-frequency pole):
//!
//! ```text
//! (D4)  X(t + T) = p·X(t) + (1 − p)·H·U,   p = e^{sT},  s = −1/τ̂ + j(ω̂_r − ω)
//! (D5)  U* = (D − p·X̂) / ((1 − p)·Ĥc),     |U| ≤ h·max(|D/Ĥc|, |D_prev/Ĥc|)
//! (D6)  X̄ = Ĥc·U + (X̂ − Ĥc·U)·(p − 1)/(sT)      (the mean over the fill)
//! ```
//!
//! The device keeps the model's envelope `X̂` of each mode (D4 with Ĥc,
//! advanced at every fill with the voltage it commands) and commands the
//! dead-beat voltage U* of D5, which reaches the setting `D` at the end of
//! the fill; when `|U*|` exceeds the bound (the headroom `h` of
//! [`DisplacementOptions`] times the larger of the old and new settings'
//! steady voltages, and the DAC's room) its magnitude is cut and its
//! phase kept: the time-optimal approach for a first-order envelope. Then
//! `X̂_{k+1} = p·X̂_k + λ(D − p·X̂_k)` with `λ ∈ (0, 1]`, a point of the segment
//! from `p·X̂_k` to `D`: `|X̂|` never exceeds `max(|X̂_0|, |D|)` at a fill's
//! end, so the model's normal excursion never passes the larger of the old
//! and new amplitudes — no overshoot above the lift-off guard, whatever the
//! headroom, up to the model's error (which `c` removes). With `h = 1`
//! there is no overdrive: a step is approached as `1 − e^{−t/τ}`. The DDS
//! jumps to each fill's voltage (its slew is one sample in this mode): the
//! voltage is piecewise constant over fills, as D4 assumes.
//!
//! **Correction by the measurement.** A window of the pickups' lock-in
//! covers one ADC block, the output of one fill: it is compared with that
//! fill's mean model envelope X̄ (D6), so `c ← c·(1 + k(X − X̄)/X̄)` (D3 with
//! X̄ in place of D: the same in the steady state, and right during a
//! transition too, since a gain error scales the whole response). `|c|`
//! stays in `[1/C_MAX, C_MAX]` (beyond, the channel is `saturated`: the
//! model no longer describes the transducer and c is held), so the voltage
//! never exceeds `h·C_MAX` times the identified model's steady voltage.
//!
//! **The pole the correction places** (D8). The dead-beat step D5 is
//! exact only with the true pole `s'`; computed with `s`, a fill leaves the
//! error times `1 − s'/s`, which exceeds 1 in magnitude once the resonance
//! has moved more than a half band `f_r/(2Q)` from where the model puts it
//! (a drifting transducer without tracking: the loop would ring up to the
//! lift-off fault). Near resonance a mode answers `H ∝ −1/s` in the frame
//! of the drive, so the learned `c = H/Ĥ` is `s/s'` for a moved resonance,
//! and a gain error times a real factor. The fills therefore use the pole of
//! the model's decay rate whose angle the phase of c moves:
//!
//! ```text
//! (D8)  s'T = Re(sT)·w / Re(w),   w = sT·c̄      (sT while Re(w) ≥ 0)
//! ```
//!
//! exact for a moved resonance (`c = s/s'` gives `s'`), unchanged by a gain
//! error (c real gives `s`); `p` and D6's mean follow it at every fill.
//!
//! **An open pickup.** A driven channel whose model envelope exceeds
//! [`OPEN_FLOOR_M`] while its pickup reads less than [`OPEN_FRACTION`] of
//! it for [`OPEN_S`] of windows in a row latches
//! [`super::faults::PICKUP_OPEN`] (the safe state).

use num_complex::Complex32 as C;

use super::{Device, DeviceError, DriveParam, DriveSetting, Status};
use crate::dds::{Achieved, Level, DAC_VOLTS_PER_CODE};
pub use crate::protocol::messages::{
    DisplacementOptions, DriveMode, Track, TransducerModel, Transducers, DEFAULT_HEADROOM,
    MAX_HEADROOM,
};
use model_core::float::{FastF32, Math};

/// Largest relative error `|X − D|/|D|` of a held channel: 0.4 %, so the
/// amplitude is within 0.4 % and φ within 0.23° of the setting per channel
/// (0.46° between the two modes).
pub const HOLD_TOLERANCE: f32 = 0.004;

/// Largest relative error `|X − D|/|D|` of a channel of a drive that
/// holds: 0.8 %, twice [`HOLD_TOLERANCE`] (hysteresis). The 1 ms-smoothed
/// error's noise is σ ≈ 0.07–0.08 % at a 0.3 µm tangential setting with
/// the virtual plant's ±1 count of pickup noise (its status over 0.4 s of
/// holding at each of 7 phases); against 0.4 % (5–6σ) a holding drive
/// was still released by noise alone about once per 30 s of device time (a
/// tail heavier than the Gaussian's `exp(−(0.4/σ)²/2)`, 1e-7–4e-6 per
/// millisecond), marking a measurement `not_settled` (3 of 20 Python lab
/// sessions' sweeps). At 10σ
/// the tail, `exp(−(0.8/0.08)²/2)` ≈ 2e-22, is nil, while a disturbance
/// beyond 0.8 % still releases the hold.
pub const RELEASE_TOLERANCE: f32 = 2.0 * HOLD_TOLERANCE;

/// An undriven channel of a drive that holds is released above this, m
/// (twice [`HOLD_FLOOR_M`], as [`RELEASE_TOLERANCE`]).
pub const RELEASE_FLOOR_M: f32 = 2.0 * HOLD_FLOOR_M;

/// Time of windows in a row within [`HOLD_TOLERANCE`] before the drive
/// holds, s (four windows of 128 µs before windows took four blocks;
/// counted in time so that the window's length does not change it).
pub const HOLD_S: f32 = 0.512e-3;

/// An undriven channel holds while its measured amplitude is below this, m
/// (cross-talk of the other channel and the pickup's noise: a few counts).
pub const HOLD_FLOOR_M: f32 = 2e-8;

/// The correction's bound: `|c|` in `[1/C_MAX, C_MAX]` (the transducer
/// within a factor of 2 of its identified model; beyond it the loop holds).
pub const C_MAX: f32 = 2.0;

/// The model's envelope counts as steady for a window (the correction c
/// learns from it) when its mean over the fill is within this fraction of
/// `Ĥc·U`, the steady envelope of the fill's voltage; otherwise the window
/// corrects the envelope itself (the observer, D7).
pub const STEADY_FRACTION: f32 = 0.02;

/// The observer's gain (D7): the fraction of a transition window's error
/// taken into the model's envelope.
pub const OBSERVER_GAIN: f32 = 0.5;

/// An open pickup: the model's envelope above this, m …
pub const OPEN_FLOOR_M: f32 = 1e-7;
/// … while the pickup reads less than this fraction of it …
pub const OPEN_FRACTION: f32 = 0.1;
/// … for this long, in windows in a row, s (eight windows of 128 µs before
/// windows took four blocks; counted in time so that the window's length
/// does not change it).
pub const OPEN_S: f32 = 1.0e-3;

/// The motion's smoothing time for the status and the holding test, s: an
/// exponential average of the windows' phasors (one window every 128 µs at
/// 20 kHz: the noise falls by ≈ √(2·1 ms/128 µs) ≈ 4).
pub const SMOOTHING_S: f32 = 1e-3;

/// The model's responses and envelope dynamics at one DDS frequency
/// (and tracked resonance): computed once per change, not per fill.
#[derive(Debug, Clone, Copy)]
pub(super) struct ModelAt {
    /// DDS tuning word and tracked resonance (f32 bits) they hold for.
    key: (u32, u32),
    /// Ĥ of each channel, m/V.
    pub(super) h: [C; 2],
    /// `sT` of D4 for one fill, the model's own pole.
    st: [C; 2],
    /// `p = e^{sT}` of D4 for one fill, with the pole the correction c
    /// places (D8; set at each fill).
    pub(super) p: [C; 2],
    /// `(p − 1)/(sT)` of D6, with the same pole.
    pub(super) mean: [C; 2],
    /// The correction c that `p` and `mean` were placed with (D8): they are
    /// formed again only when c moves (a window's D3), not at every fill
    /// (issue 35: one `expf` and one `sin_cos` per channel).
    pole_c: [C; 2],
}

/// The pole a correction `c` implies (D8): with `sT` the model's pole
/// over a fill, the pole of the same decay rate whose angle the phase of c
/// moves, `Re(sT)·w/Re(w)`, `w = sT·c̄`; the model's own pole when that
/// angle leaves the stable half-plane. Returns `(p, (p − 1)/(s'T))`.
fn pole_of(st: C, c: C) -> (C, C) {
    let w = st * c.conj();
    let se = if w.re < 0.0 && (w.re * st.re).is_finite() {
        w * (st.re / w.re)
    } else {
        st
    };
    let p = polar(libm::expf(se.re), se.im);
    (p, (p - C::new(1.0, 0.0)) / se)
}

/// The displacement loops' state.
#[derive(Debug, Clone, Copy)]
pub(super) struct Loops {
    /// The correction c of each channel (D2, D3).
    pub(super) c: [C; 2],
    /// The correction left its bound or the voltage the DAC (held).
    pub(super) saturated: [bool; 2],
    /// Time of windows in a row within the tolerance, s.
    pub(super) good: f32,
    /// The smoothed measured phasors (`None` until the first window after
    /// a new setting).
    pub(super) avg: Option<[C; 2]>,
    /// The model at the DDS frequency.
    pub(super) model: Option<ModelAt>,
    /// The model's envelope X̂ of each mode at the start of the next fill, m.
    pub(super) env: [C; 2],
    /// The setting the last fill aimed at (D), m.
    pub(super) last_d: [C; 2],
    /// The steady voltage of the setting before it, V (the braking bound).
    pub(super) u_prev: [f32; 2],
    /// Per fill (modulo `FILL_RING`): the mean model envelope X̄ (D6) and
    /// the voltage phasor of each channel.
    pub(super) at_fill: [([C; 2], [C; 2]); super::measure::FILL_RING],
    /// Per fill: the channel was in a transition (its voltage cut to the
    /// bound, or a new setting within the last fills).
    pub(super) moving: [[bool; 2]; super::measure::FILL_RING],
    /// Fills since each channel's setting last changed (saturating).
    pub(super) since_change: [u8; 2],
    /// Time of windows in a row with an open pickup's symptom, per channel, s.
    pub(super) open: [f32; 2],
}

impl Default for Loops {
    fn default() -> Self {
        let z = [C::new(0.0, 0.0); 2];
        Loops {
            c: [C::new(1.0, 0.0); 2],
            saturated: [false; 2],
            good: 0.0,
            avg: None,
            model: None,
            env: z,
            last_d: z,
            u_prev: [0.0; 2],
            at_fill: [(z, z); super::measure::FILL_RING],
            moving: [[false; 2]; super::measure::FILL_RING],
            since_change: [u8::MAX; 2],
            open: [0.0; 2],
        }
    }
}

impl Loops {
    /// The drive holds: [`HOLD_S`] of windows in a row within the bounds
    /// (the sum of the windows' lengths, with room for its rounding: one
    /// part in 10³ of `HOLD_S`, far below one window).
    pub(super) fn holding(&self) -> bool {
        self.good >= HOLD_S * (1.0 - 1e-3)
    }

    /// The model starts over from the motion `x` the pickups measured last
    /// (m; at rest after a stop, moving after a mode switch while running),
    /// with the voltages `u` (V) in force as the braking bound's reference.
    pub(super) fn restart(&mut self, x: [C; 2], u: [f32; 2]) {
        let z = [C::new(0.0, 0.0); 2];
        self.env = x;
        self.last_d = x;
        self.u_prev = u;
        self.at_fill = [(z, z); super::measure::FILL_RING];
        self.moving = [[false; 2]; super::measure::FILL_RING];
        self.since_change = [0; 2];
        self.open = [0.0; 2];
        self.good = 0.0;
        self.avg = None;
    }
}

/// |c| with the fast f32 backend (the board's: `num-complex`'s own would
/// call libm's `hypotf`, several times dearer on the M4F).
pub fn norm(c: C) -> f32 {
    FastF32::hypot(c.re, c.im)
}

/// `|c|²`, one multiply and one multiply-add.
#[inline]
fn norm_sq(c: C) -> f32 {
    c.re * c.re + c.im * c.im
}

/// `|a|` against `k·|b|` (`k ≥ 0`): from the squares, `|a|²` against
/// `k²·|b|²`, when both are normal f32 (no overflow, no precision lost to
/// underflow), else from [`norm`] (issue 35: a comparison needs no square
/// root, and each `norm` is a fast hypot; the loops' comparisons were
/// ≈ 900 instructions of a window's close). The two differ only by
/// rounding, a few parts in 10⁷ of the bound; `None` for NaN.
fn compare(a: C, k: f32, b: C) -> Option<core::cmp::Ordering> {
    let (a2, b2) = (norm_sq(a), k * k * norm_sq(b));
    if a2.is_normal() && b2.is_normal() {
        a2.partial_cmp(&b2)
    } else {
        norm(a).partial_cmp(&(k * norm(b)))
    }
}

/// Whether `|a| ≤ k·|b|` (`k ≥ 0`; false for NaN), without a square root
/// where the squares are normal (`compare`).
pub fn norm_le(a: C, k: f32, b: C) -> bool {
    compare(a, k, b).is_some_and(|o| o.is_le())
}

/// Whether `|a| > k·|b|` (`k ≥ 0`; false for NaN, like the comparison of
/// the norms), as [`norm_le`].
pub fn norm_gt(a: C, k: f32, b: C) -> bool {
    compare(a, k, b).is_some_and(|o| o.is_gt())
}

/// Whether `|a| ≤ bound` (`bound ≥ 0`): [`norm_le`] against a real bound.
pub fn norm_le_real(a: C, bound: f32) -> bool {
    norm_le(a, bound, C::new(1.0, 0.0))
}

/// Whether `c ≠ 0` (`|c| > 0`, without the square root).
#[inline]
pub fn nonzero(c: C) -> bool {
    c.re != 0.0 || c.im != 0.0
}

/// arg c in (−π, π], fast f32 backend.
pub fn arg(c: C) -> f32 {
    FastF32::atan2(c.im, c.re)
}

/// The phase between the modes' phasors, eq. M1 (`device::motion`):
/// `φ = arg X_x − arg X_z + π`, wrapped to (−π, π] (rad; the normal
/// drive is `−cos`, hence the π). With both args in (−π, π] the
/// difference `d` lies in (−2π, 2π), so `d + π` needs one turn back
/// exactly when `d > 0`: `φ = d − π` there, `d + π` otherwise (π for two
/// parallel phasors, zero ones included).
pub fn phase_between(z: C, x: C) -> f32 {
    let pi = core::f32::consts::PI;
    let d = arg(x) - arg(z);
    if d > 0.0 {
        d - pi
    } else {
        d + pi
    }
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

/// The model's response Ĥ(f), m/V (eq. 1 of [`crate::identify`]).
pub fn model_response(m: &TransducerModel, freq_hz: f32) -> C {
    let r = freq_hz / m.resonance_hz;
    let den = C::new(1.0 - r * r, r / m.q);
    polar(m.gain_m_per_v, -m.phase_lag_rad) / den
}

/// The setting's displacement phasors (D1), m.
pub fn setpoint(d: &DriveSetting) -> [C; 2] {
    [C::new(-d.amp_z_m, 0.0), polar(d.amp_x_m, d.phase_rad)]
}

/// Whether a dead-beat voltage of magnitude `un` (V) lies beyond D5's
/// bound `min(h·max(|d/hc|, u_prev), room)`, or is not a number: beyond the
/// room, or beyond both `h·u_prev` and `h·|d/hc|` — the last compared as
/// `|u·hc| > h·|d|` (`u_hc` = u·hc; [`norm_gt`]: no division, no root;
/// issue 35).
fn beyond_bound(un: f32, room: f32, h: f32, u_prev: f32, u_hc: C, d: C) -> bool {
    un.is_nan() || un > room || (un > h * u_prev && norm_gt(u_hc, h, d))
}

/// The DDS level and phase word of a voltage phasor `u` (V) of magnitude
/// `un` ([`norm`] of `u`) on a channel with DC `dc` (codes): `A = |U|/v`,
/// `p = arg U + π/2` (D2's convention).
fn level_of(u: C, un: f32, dc: f32) -> (Level, u32) {
    let v = DAC_VOLTS_PER_CODE as f32;
    let amp = un / v;
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
                    self.loops = self.fresh_loops();
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
        self.loops = self.fresh_loops();
        if let Err(e) = self.replan() {
            (self.mode, self.loops) = old;
            return Err(e);
        }
        Ok(())
    }

    /// Loops that start from the motion in force: the model's envelope at
    /// the pickups' last phasors and the braking bound at the voltages the
    /// DDS outputs (a switch of mode or model while running must not
    /// overdrive a transducer that already moves).
    pub(super) fn fresh_loops(&self) -> Loops {
        let mut l = Loops::default();
        if self.running {
            l.restart(self.motion_phasors(), self.output_volts());
        }
        l
    }

    /// The voltage amplitude each DDS channel outputs now, V.
    pub(super) fn output_volts(&self) -> [f32; 2] {
        let v = DAC_VOLTS_PER_CODE as f32;
        let ch = self.dds.channels();
        [ch[0].amp.abs() * v, ch[1].amp.abs() * v]
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
        let wanted = [d.amp_z_m, d.amp_x_m];
        for ch in 0..2 {
            let h = h_model[ch] * c[ch];
            let u = target[ch] / h;
            let (mut lv, w) = level_of(u, norm(u), dc[ch]);
            let room = dc[ch].min(f32::from(crate::dds::DAC_MAX) - dc[ch]);
            // The largest displacement that fits, in the f32 the refusal
            // reports: the amplitude is compared with it (inclusive, so the
            // reported maximum sent back is accepted), and the level's
            // rounding past the room (an ulp or two) is the room itself.
            // NaN (a zero model response) fails the comparison: refused.
            let max = room.max(0.0) * DAC_VOLTS_PER_CODE as f32 * norm(h);
            let fits = wanted[ch] <= max;
            lv.amp = lv.amp.min(room);
            if !fits || lv.check().is_err() {
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
    /// in voltage mode its calibration level, in displacement mode a new
    /// setting of the normal mode (its steady voltage checked against the
    /// DAC; the fills' dead-beat voltages D5 then reach it). `true` when
    /// applied.
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
            let ok = matches!(
                self.voltage_plan(&d, &at, [dc, dcx], self.loops.c),
                Ok(Some(_))
            );
            if ok {
                self.loops.good = 0.0;
            }
            ok
        } else {
            let lz = Level {
                amp: u / z.metres_per_code,
                dc,
            };
            self.dds.set_level(0, lz).is_ok()
        }
    }

    /// The models' responses Ĥ at the DDS frequency `at` (the tracked
    /// channel's model centred on the tracked resonance), from the cache
    /// when it holds for them.
    fn model_h_at(&self, t: &Transducers, at: &Achieved) -> [C; 2] {
        let key = (at.tuning_word, self.tracker.resonance_bits());
        match self.loops.model {
            Some(m) if m.key == key => m.h,
            _ => {
                let f = at.freq_hz as f32;
                let [mz, mx] = self.tracker.models(t);
                [model_response(&mz, f), model_response(&mx, f)]
            }
        }
    }

    /// The model at the DDS frequency (cached), for fills of `n` samples.
    fn model_at(&mut self, t: &Transducers, n: usize) -> ModelAt {
        let at = self.applied.achieved;
        let key = (at.tuning_word, self.tracker.resonance_bits());
        if let Some(m) = self.loops.model.filter(|m| m.key == key) {
            return m;
        }
        let f = at.freq_hz as f32;
        let tf = n as f32 / self.cfg.sample_rate_hz as f32;
        let models = self.tracker.models(t);
        let mut m = ModelAt {
            key,
            h: [C::new(0.0, 0.0); 2],
            st: [C::new(0.0, 0.0); 2],
            p: [C::new(0.0, 0.0); 2],
            mean: [C::new(0.0, 0.0); 2],
            pole_c: [C::new(1.0, 0.0); 2],
        };
        for (ch, md) in models.iter().enumerate() {
            m.h[ch] = model_response(md, f);
            let tau = md.q / (core::f32::consts::PI * md.resonance_hz);
            let dw = core::f32::consts::TAU * (md.resonance_hz - f);
            let st = C::new(-tf / tau, dw * tf);
            m.st[ch] = st;
            (m.p[ch], m.mean[ch]) = pole_of(st, C::new(1.0, 0.0));
        }
        self.loops.model = Some(m);
        m
    }

    /// The dead-beat voltages of one DAC fill of `n` samples (D4–D6): sets
    /// both channels' DDS levels and phases and records the fill's model
    /// envelope and voltage under `fill`. Nothing outside displacement mode,
    /// while stopped or faulted.
    pub(super) fn displacement_fill(&mut self, fill: u32, n: usize) {
        if !self.displacement_mode() || !self.running || self.latch.any() || n == 0 {
            return;
        }
        let Some(t) = self.transducers else {
            return;
        };
        let mut m = self.model_at(&t, n);
        probe!(30);
        // D8: the envelope's pole where the learned c places it (the
        // observer's propagation uses the same, through the cache).
        for ch in 0..2 {
            if m.pole_c[ch] != self.loops.c[ch] {
                (m.p[ch], m.mean[ch]) = pole_of(m.st[ch], self.loops.c[ch]);
                m.pole_c[ch] = self.loops.c[ch];
            }
        }
        self.loops.model = Some(m);
        probe!(31);
        let d = setpoint(&self.drive);
        let v = DAC_VOLTS_PER_CODE as f32;
        let one = C::new(1.0, 0.0);
        let h_room = self.options.headroom;
        let mut rec = ([C::new(0.0, 0.0); 2], [C::new(0.0, 0.0); 2]);
        let mut moving = [false; 2];
        #[allow(clippy::needless_range_loop)] // ch indexes six arrays
        for ch in 0..2 {
            let hc = m.h[ch] * self.loops.c[ch];
            if d[ch] != self.loops.last_d[ch] {
                self.loops.u_prev[ch] = norm(self.loops.last_d[ch] / hc);
                self.loops.last_d[ch] = d[ch];
                self.loops.since_change[ch] = 0;
            } else {
                self.loops.since_change[ch] = self.loops.since_change[ch].saturating_add(1);
            }
            let env = self.loops.env[ch];
            let (p, q) = (m.p[ch], one - m.p[ch]);
            let mut u = (d[ch] - p * env) / (q * hc);
            let chn = self.dds.channels()[ch];
            let dc = chn.dc_target;
            // The DAC's room around the DC, less a part in 10⁴ (the level's
            // own check must pass after the f32 round trip).
            let room = dc.min(f32::from(crate::dds::DAC_MAX) - dc).max(0.0) * v * 0.9999;
            // The bound itself is formed only for a cut.
            let u_prev = self.loops.u_prev[ch];
            let mut un = norm(u);
            let cut = beyond_bound(un, room, h_room, u_prev, u * hc, d[ch]);
            moving[ch] =
                cut || usize::from(self.loops.since_change[ch]) < super::measure::FILL_RING;
            if cut {
                // Beyond the bound (or not finite): the magnitude cut, the
                // phase kept (NaN: no drive).
                let bound = (h_room * norm(d[ch] / hc).max(u_prev)).min(room);
                u = if un.is_finite() && un > 0.0 {
                    u * (bound / un)
                } else {
                    C::new(0.0, 0.0)
                };
                un = norm(u);
            }
            // |u| formed once per fill and channel (issue 35: each `norm` is
            // a fast hypot, ≈ 90 instructions on the M4F).
            let (lv, word) = level_of(u, un, dc);
            if self.dds.set_level(ch, lv).is_ok() {
                if un > 0.0 {
                    self.dds.set_phase(ch, word);
                }
            } else {
                // Not taken (cannot happen within the room): the model
                // advances with the voltage in force.
                u = self.loops.at_fill[(fill.wrapping_sub(1)) as usize % super::measure::FILL_RING]
                    .1[ch];
            }
            let w = hc * u;
            rec.0[ch] = w + (env - w) * m.mean[ch];
            rec.1[ch] = u;
            self.loops.env[ch] = p * env + q * w;
        }
        self.loops.at_fill[fill as usize % super::measure::FILL_RING] = rec;
        self.loops.moving[fill as usize % super::measure::FILL_RING] = moving;
    }

    /// The model's envelopes reach the setting (each driven channel within
    /// [`HOLD_TOLERANCE`], an undriven one below [`HOLD_FLOOR_M`]): a
    /// command is in force as far as the model knows (the closed μ loop's
    /// "reached").
    pub(super) fn model_reached(&self) -> bool {
        let d = setpoint(&self.drive);
        (0..2).all(|ch| {
            let e = self.loops.env[ch] - d[ch];
            if nonzero(d[ch]) {
                norm_le(e, HOLD_TOLERANCE, d[ch]) && self.loops.last_d[ch] == d[ch]
            } else {
                norm_le_real(e, HOLD_FLOOR_M)
            }
        })
    }

    /// One window (the lock-in's phasors `x`, m, over `window_s` seconds,
    /// the output of fill `block`): the corrections c (D3 against the
    /// fill's model envelope), the open-pickup check, the tracking, the
    /// holding count.
    pub(super) fn displacement_step(&mut self, block: u32, blocks: u32, x: [C; 2], window_s: f32) {
        if !self.displacement_mode() || !self.running || self.latch.any() {
            self.loops.good = 0.0;
            return;
        }
        let Some(t) = self.transducers else {
            return;
        };
        let d = self.drive;
        let target = setpoint(&d);
        let (mean, u_fill, moving) = self.window_fills(block, blocks);
        let alpha = (window_s / SMOOTHING_S).min(1.0);
        let avg = match self.loops.avg {
            Some(a) => [a[0] + (x[0] - a[0]) * alpha, a[1] + (x[1] - a[1]) * alpha],
            None => x,
        };
        self.loops.avg = Some(avg);
        let mut within = true;
        // Hysteresis: a holding drive is released only beyond the wider
        // bounds (RELEASE_TOLERANCE, RELEASE_FLOOR_M).
        let (tol, floor) = if self.loops.holding() {
            (RELEASE_TOLERANCE, RELEASE_FLOOR_M)
        } else {
            (HOLD_TOLERANCE, HOLD_FLOOR_M)
        };
        probe!(23);
        let models = self.tracker.models(&t);
        for (ch, m) in models.iter().enumerate() {
            let driven = nonzero(target[ch]);
            within &= if driven {
                norm_le(avg[ch] - target[ch], tol, target[ch])
            } else {
                norm_le_real(avg[ch], floor)
            };
            // An open pickup: the model says the mode moves, the pickup not.
            let one = C::new(1.0, 0.0);
            if norm_gt(mean[ch], OPEN_FLOOR_M, one) && norm_gt(mean[ch], 1.0 / OPEN_FRACTION, x[ch])
            {
                self.loops.open[ch] += window_s;
                if self.loops.open[ch] >= OPEN_S * (1.0 - 1e-3) {
                    self.fault(super::faults::PICKUP_OPEN);
                    return;
                }
                continue;
            }
            self.loops.open[ch] = 0.0;
            // D3 against the fill's mean envelope, from a twentieth of the
            // setting up (below, the window's noise dominates); a window of
            // a transition also corrects the model's envelope (D7: its
            // error then holds the model's dynamics error too, τ̂ and ω̂_r,
            // which the dead-beat fills would otherwise leave to die out
            // with the mode's own τ).
            if !driven || norm_gt(target[ch], 20.0, mean[ch]) {
                continue;
            }
            if moving[ch] {
                self.observe(ch, block, x[ch] - mean[ch]);
            }
            let e = (x[ch] - mean[ch]) / mean[ch];
            let tau = m.q / (core::f32::consts::PI * m.resonance_hz);
            let k = (window_s / (4.0 * tau)).min(0.5);
            let c = self.loops.c[ch] * (C::new(1.0, 0.0) + e * k);
            if norm_le(one, C_MAX, c) && norm_le_real(c, C_MAX) {
                self.loops.c[ch] = c;
                self.loops.saturated[ch] = false;
            } else {
                self.loops.saturated[ch] = true;
            }
        }
        probe!(24);
        self.tracking_step(&t, x, mean, u_fill, window_s);
        probe!(25);
        self.loops.good = if within {
            self.loops.good + window_s
        } else {
            0.0
        };
    }

    /// The fills' records over a window of `blocks` ADC blocks that ends
    /// with `block`: the mean model envelopes and voltages averaged over
    /// its blocks (equal weights: whole blocks of equal length), moving if
    /// any was — the last [`super::measure::FILL_RING`] blocks at most (a
    /// longer window, below 2 kHz, takes its last four).
    pub(super) fn window_fills(&self, block: u32, blocks: u32) -> ([C; 2], [C; 2], [bool; 2]) {
        let k = blocks.clamp(1, super::measure::FILL_RING as u32);
        let z = C::new(0.0, 0.0);
        let (mut mean, mut u, mut moving) = ([z; 2], [z; 2], [false; 2]);
        for j in 0..k {
            let slot = block.wrapping_sub(j) as usize % super::measure::FILL_RING;
            let (m, v) = self.loops.at_fill[slot];
            for ch in 0..2 {
                mean[ch] += m[ch];
                u[ch] += v[ch];
                moving[ch] |= self.loops.moving[slot][ch];
            }
        }
        let w = 1.0 / k as f32;
        (mean.map(|m| m * w), u.map(|v| v * w), moving)
    }

    /// The observer of a transition (D7): the model's envelope moves by
    /// [`OBSERVER_GAIN`] of the error `err` that fill `block`'s window
    /// measured, carried to now (and to the later fills' records) through
    /// the mode's free decay `p` per fill.
    fn observe(&mut self, ch: usize, block: u32, err: C) {
        let Some(m) = self.loops.model else {
            return;
        };
        let p = m.p[ch];
        let mut corr = err * OBSERVER_GAIN;
        let ring = super::measure::FILL_RING as u32;
        let ahead = self.fills.wrapping_sub(block).min(ring);
        for k in 1..ahead {
            corr *= p;
            let slot = block.wrapping_add(k) as usize % super::measure::FILL_RING;
            self.loops.at_fill[slot].0[ch] += corr;
        }
        self.loops.env[ch] += corr * p;
    }

    /// Whether the drive holds its setting: in displacement mode the
    /// measured motion within tolerance (module docs), else the DDS ramps
    /// finished.
    pub fn drive_settled(&self) -> bool {
        if self.displacement_mode() && self.running {
            self.loops.holding()
        } else {
            self.dds.settled()
        }
    }

    /// The DDS's slew for a new setting: in displacement mode one sample
    /// for any change (the fills' voltages are D5's, piecewise constant),
    /// in voltage mode the board's slew.
    pub(super) fn ramp_slew(&mut self) {
        let Ok(base) = Self::slew(&self.cfg) else {
            return;
        };
        if self.displacement_mode() {
            self.dds.set_slew(crate::dds::Slew {
                amp_per_sample: f32::from(crate::dds::DAC_MAX),
                dc_per_sample: base.dc_per_sample,
                phase_per_sample: 1 << 31,
            });
        } else {
            self.dds.set_slew(base);
        }
    }

    /// Sets the displacement mode's options (tracking, headroom), validated
    /// whole.
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`] naming [`DriveParam::Headroom`] outside
    /// `[1, MAX_HEADROOM]`; [`DeviceError::NotIdentified`] for tracking
    /// without stored transducers. Nothing changes on error.
    pub fn set_displacement_options(&mut self, o: DisplacementOptions) -> Result<(), DeviceError> {
        let h = o.headroom;
        if !(h.is_finite() && (1.0..=MAX_HEADROOM).contains(&h)) {
            return Err(DeviceError::OutOfRange {
                param: DriveParam::Headroom,
                min: 1.0,
                max: MAX_HEADROOM,
            });
        }
        if o.track != Track::None && self.transducers.is_none() {
            return Err(DeviceError::NotIdentified);
        }
        if o.track != self.options.track {
            self.restart_tracking();
            self.loops.model = None;
        }
        self.options = o;
        Ok(())
    }

    /// The displacement mode's options in force.
    pub fn displacement_options(&self) -> DisplacementOptions {
        self.options
    }

    /// The smoothed measured phasors of the displacement loop (m), `None`
    /// outside displacement mode or before a window.
    pub(super) fn smoothed_motion(&self) -> Option<[C; 2]> {
        self.loops
            .avg
            .filter(|_| self.displacement_mode() && self.running)
    }

    /// Fills the v5 and v6 fields of a status.
    pub(super) fn displacement_status(&self, s: &mut Status) {
        s.mode = self.mode;
        s.settled = self.drive_settled();
        s.frequency_hz = self.applied.achieved.freq_hz as f32;
        s.options = self.options;
        s.tracking_error_hz = self.tracker.error_hz.filter(|_| self.tracking_active());
        s.locked = self.tracker.locked && self.tracking_active();
        // In displacement mode the amplitudes and φ are the smoothed ones
        // the holding test uses (the peak stays the largest raw window).
        if let (Some(m), Some(a)) = (s.measured.as_mut(), self.smoothed_motion()) {
            m.amp_z_m = norm(a[0]);
            m.amp_x_m = norm(a[1]);
            m.phase_rad = phase_between(a[0], a[1]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dds::SineTable;
    use crate::device::{Contact, DeviceConfig, HALF_BUFFER};

    /// Eq. M1 against f64: for phasors at angles ψ_z, ψ_x on a grid over
    /// the circle (both sides of ±π, where the wrap acts), `phase_between`
    /// is `ψ_x − ψ_z + π` reduced to (−π, π] in f64, within the fast
    /// atan2's 2.9e-7 rad twice plus f32 rounding of angles ≤ 3π (4·2⁻²³·π):
    /// allowed 1e-6, measured on the circle (a result at −π for +π, one
    /// rounding apart, is the same phase).
    #[test]
    fn the_phase_between_the_modes_is_m1_wrapped() {
        use core::f64::consts::PI;
        let mut wrapped = 0;
        for i in 0..64 {
            for j in 0..64 {
                let (pz, px) = (
                    -PI + (i as f64 + 0.37) * PI / 32.0,
                    -PI + (j as f64 + 0.61) * PI / 32.0,
                );
                let z = C::new(2.0 * pz.cos() as f32, 2.0 * pz.sin() as f32);
                let x = C::new(0.5 * px.cos() as f32, 0.5 * px.sin() as f32);
                let raw = px - pz + PI;
                if raw > PI || raw <= -PI {
                    wrapped += 1;
                }
                let got = f64::from(phase_between(z, x));
                // In (−π, π] (to rounding), and the same phase as raw.
                assert!(got > -PI - 1e-6 && got <= PI + 1e-6, "{got}");
                let d = (got - raw).rem_euclid(2.0 * PI);
                assert!(
                    d.min(2.0 * PI - d) <= 1e-6,
                    "ψ_z {pz}, ψ_x {px}: {got} vs {raw}"
                );
            }
        }
        assert!(wrapped > 1000, "{wrapped} cases wrapped");
        // Parallel phasors (zero ones too): the end of the range, +π.
        let zero = C::new(0.0, 0.0);
        assert_eq!(phase_between(zero, zero), core::f32::consts::PI);
        let z = C::new(0.3, -0.4);
        assert_eq!(phase_between(z, z * 2.0), core::f32::consts::PI);
    }

    /// The observer's carry (D7, `observe`): a window of fill `b` read
    /// after fill `b + a − 1` (the ADC block arriving late, as it may on
    /// the board: `FILL_RING`) moves the model's envelope by the gain
    /// (0.5, docs/protocol.md) times the error, carried through the mode's
    /// free decay `p` once per fill: the records of fills `b + k` by
    /// `0.5·err·pᵏ` (k = 1 … a − 1) and the envelope now by `0.5·err·pᵃ`.
    /// p by D4 written out in f64: `p = e^{sT}`, `s = −1/τ̂ + j(ω̂_r − ω)`,
    /// `τ̂ = Q̂/(π f̂_r)`, T = 64 samples (c = 1: no window has moved the
    /// pole, D8). The device forms sT, e^{sT} and the products in f32
    /// (relative rounding ~1e-7 each, the fast sin/cos within 1e-6):
    /// allowed 1e-5 of |0.5·err|.
    #[test]
    fn the_observer_carries_its_correction_through_the_free_decay() {
        let table = SineTable::<1024>::libm();
        let cfg = DeviceConfig::driver_board(0);
        let contact = Contact {
            mu0: 0.3,
            kz: 1e7,
            kx: 1e7,
        };
        let mut dev = Device::new(cfg, &table, contact).unwrap();
        let z = TransducerModel {
            resonance_hz: 20_300.0,
            q: 273.0,
            gain_m_per_v: 8e-8,
            phase_lag_rad: 0.1,
        };
        let x = TransducerModel {
            resonance_hz: 19_700.0,
            q: 182.0,
            gain_m_per_v: 4e-8,
            phase_lag_rad: 0.1,
        };
        dev.set_transducers(Some(Transducers { z, x })).unwrap();
        dev.set_drive_mode(DriveMode::Displacement).unwrap();
        dev.set_drive(DriveSetting {
            freq_hz: 20_000.0,
            amp_z_m: 2e-6,
            amp_x_m: 0.3e-6,
            offset_z_m: 4e-6,
            phase_rad: 0.7,
        })
        .unwrap();
        dev.start().unwrap();
        let mut buf = [0u32; HALF_BUFFER];
        for h in 0..6 {
            dev.fill_dac(h % 2, &mut buf);
        }
        let f = dev.applied().achieved.freq_hz;
        let t = HALF_BUFFER as f64 / cfg.sample_rate_hz;
        let err = C::new(3e-8, -2e-8);
        let g = 0.5;
        for (ch, m) in [z, x].iter().enumerate() {
            let (fr, q) = (f64::from(m.resonance_hz), f64::from(m.q));
            let tau = q / (core::f64::consts::PI * fr);
            let (re, im) = (-t / tau, core::f64::consts::TAU * (fr - f) * t);
            let p = (re.exp() * im.cos(), re.exp() * im.sin());
            let pow = |k: i32| {
                let (mut a, mut b) = (1.0f64, 0.0f64);
                for _ in 0..k {
                    (a, b) = (a * p.0 - b * p.1, a * p.1 + b * p.0);
                }
                // 0.5·err·pᵏ
                let (er, ei) = (g * f64::from(err.re), g * f64::from(err.im));
                (er * a - ei * b, er * b + ei * a)
            };
            let zero = [C::new(0.0, 0.0); 2];
            dev.loops.at_fill = [(zero, zero); super::super::measure::FILL_RING];
            dev.loops.env = zero;
            // Six fills made (0 … 5): the window of fill 3 is three behind.
            assert_eq!(dev.fills, 6);
            dev.observe(ch, 3, err);
            let tol = 1e-5 * g * f64::from(norm(err));
            let close =
                |c: C, w: (f64, f64)| (f64::from(c.re) - w.0).hypot(f64::from(c.im) - w.1) <= tol;
            for (k, slot) in [(1, 0), (2, 1)] {
                let got = dev.loops.at_fill[slot].0[ch];
                assert!(
                    close(got, pow(k)),
                    "ch {ch} fill 3+{k}: {got} vs {:?}",
                    pow(k)
                );
            }
            let got = dev.loops.env[ch];
            assert!(
                close(got, pow(3)),
                "ch {ch} envelope: {got} vs {:?}",
                pow(3)
            );
            // The window's own fill and the other channel are left alone.
            assert_eq!(dev.loops.at_fill[3].0[ch], C::new(0.0, 0.0));
            assert_eq!(dev.loops.env[1 - ch], C::new(0.0, 0.0));
        }
    }
}
