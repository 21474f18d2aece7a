//! The messages of the protocol: the [`Frame`] and its [`Body`], every
//! [`Request`], [`Response`] and [`Telemetry`], the [`WireError`]s and the
//! structures they carry. Enums are encoded by postcard as a varint variant
//! index (declaration order) followed by the fields: new variants are only
//! ever appended. [`ENDPOINTS`] pairs every request with the response that
//! answers it.

use core::fmt;

use serde::{Deserialize, Serialize};

use crate::dds::Achieved;
use crate::estimator::Estimate;
use model_core::regime::Regime;

/// Protocol version; a frame with another version is answered with
/// [`WireError::VersionMismatch`].
pub const PROTOCOL_VERSION: u16 = 8;

/// The drive as commanded, physical units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveSetting {
    /// Drive frequency, Hz.
    pub freq_hz: f64,
    /// Normal amplitude Δu_z, m (≥ 0).
    pub amp_z_m: f32,
    /// Tangential amplitude Δu_x, m (≥ 0).
    pub amp_x_m: f32,
    /// Normal offset = mean indentation u_z0, m (> 0).
    pub offset_z_m: f32,
    /// Phase φ of the tangential drive, rad.
    pub phase_rad: f32,
}

/// The contact the device predicts with (the drive supplies u_z0, Δu_z, Δu_x, ω, φ).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Contact {
    /// μ₀.
    pub mu0: f32,
    /// k_z, N/m.
    pub kz: f32,
    /// k_x, N/m.
    pub kx: f32,
}

/// Which parameter an error names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DriveParam {
    /// 0: frequency.
    Freq,
    /// 1: normal amplitude.
    AmpZ,
    /// 2: tangential amplitude.
    AmpX,
    /// 3: normal offset.
    OffsetZ,
    /// 4: phase.
    Phase,
    /// 5: measurement (or stream) periods.
    Periods,
    /// 6: velocity of a prediction (or of the closed loop).
    Velocity,
    /// 7: the closed loop's target μ.
    TargetMu,
    /// 8: the closed loop's gain κ.
    Gain,
    /// 9: the closed loop's rate limit.
    Rate,
    /// 10 (v5): a transducer's resonance f_r.
    Resonance,
    /// 11 (v5): a transducer's quality factor Q.
    Quality,
    /// 12 (v5): a transducer's static gain.
    TransducerGain,
    /// 13 (v5): a transducer's extra phase lag.
    PhaseLag,
    /// 14 (v6): the displacement loop's voltage headroom
    /// ([`DisplacementOptions::headroom`]).
    Headroom,
}

impl DriveParam {
    /// The field's name on the wire (`freq_hz`, `amp_z_m`, …).
    pub const fn name(self) -> &'static str {
        match self {
            DriveParam::Freq => "freq_hz",
            DriveParam::AmpZ => "amp_z_m",
            DriveParam::AmpX => "amp_x_m",
            DriveParam::OffsetZ => "offset_z_m",
            DriveParam::Phase => "phase_rad",
            DriveParam::Periods => "periods",
            DriveParam::Velocity => "v0",
            DriveParam::TargetMu => "target_mu",
            DriveParam::Gain => "gain",
            DriveParam::Rate => "rate_m_per_s",
            DriveParam::Resonance => "resonance_hz",
            DriveParam::Quality => "q",
            DriveParam::TransducerGain => "gain_m_per_v",
            DriveParam::PhaseLag => "phase_lag_rad",
            DriveParam::Headroom => "headroom",
        }
    }
}

/// What a drive command achieved (exact frequency and phase of the DDS).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Applied {
    /// The DDS frequency.
    pub achieved: Achieved,
    /// Exact phase between the channels' waveforms (φ as produced), rad.
    pub phase_rad: f64,
}

/// A model prediction for the current drive.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Prediction {
    /// μ/μ₀ at the velocity; at v₀ = 0 exactly the limit μ(0⁺)/μ₀.
    pub mu_over_mu0: f32,
    /// μ = μ₀·`mu_over_mu0`.
    pub mu: f32,
    /// Forward and backward critical velocity, m/s.
    pub vc: (f32, f32),
    /// At v₀ = 0 exactly the other one-sided limit μ(0⁻)/μ₀ (μ is
    /// discontinuous at rest); at any other v₀ equal to `mu_over_mu0`. With
    /// lift-off (`liftoff`) μ is continuous at rest: always `mu_over_mu0`.
    pub mu_0minus_over_mu0: f32,
    /// (v3) The drive lifts the contact off (`Δu_z ≥ u_z0`, allowed by
    /// [`Request::SetLiftOff`]) and the lift-off model answered
    /// ([`model_core::model::liftoff`]: μ over the contact window, its critical
    /// velocities); `false`: the permanent-contact exact solver.
    pub liftoff: bool,
}

/// Status snapshot.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Drive running (amplitudes at or ramping to the setting).
    pub running: bool,
    /// All ramps finished.
    pub settled: bool,
    /// Latched fault bits ([`crate::device::faults`]).
    pub faults: u32,
    /// A measurement is in progress.
    pub measuring: bool,
    /// Received bytes dropped because the link's receive queue was full, since
    /// power-up (saturating). Never a silent drop: a host that sees this grow
    /// pipelined more than the device can hold.
    pub rx_overflows: u32,
    /// The normal amplitude the DAC produces now, m (ramps towards the
    /// setting while running, towards 0 after `Stop`; the setting itself is
    /// what `GetDrive` reports).
    pub out_amp_z_m: f32,
    /// The tangential amplitude produced now, m.
    pub out_amp_x_m: f32,
    /// The normal offset produced now, m.
    pub out_offset_z_m: f32,
    /// (v3) Drives that lift the contact off are allowed
    /// ([`Request::SetLiftOff`]; `false` at power-up).
    pub liftoff_allowed: bool,
    /// (v4) The transducers' motion measured by the pickups' lock-ins over
    /// the last window ([`crate::device`]'s `motion`); `None` before
    /// the first window, or on a board whose pickups are not wired.
    pub measured: Option<MeasuredDrive>,
    /// (v5) The drive mode in force ([`Request::SetDriveMode`]).
    pub mode: DriveMode,
    /// (v6) The DDS frequency now, Hz (the setting's, or where the
    /// resonance tracking has moved it).
    pub frequency_hz: f32,
    /// (v6) The displacement mode's options in force.
    pub options: DisplacementOptions,
    /// (v6) While tracking: the measured resonance of the tracked mode minus
    /// the drive frequency, Hz (signed); `None` when not tracking or before
    /// the first usable window.
    pub tracking_error_hz: Option<f32>,
    /// (v6) The tracking is locked (`false` when not tracking).
    pub locked: bool,
    /// (v8) The board's DSP load in the last half-buffer, % of the
    /// half-buffer's cycles (eq. L1 of `device::load`: the DAC refill and
    /// the ADC block of one half, counted by the firmware; above 100 %: a
    /// late handler). `None` before the first half-buffer, and on a device
    /// that does not measure itself (the virtual device).
    pub cpu_load_pct: Option<f32>,
    /// (v8) The largest [`Status::cpu_load_pct`] since power-up or the
    /// last `Reset`, %; `None` when no half-buffer was measured since.
    pub cpu_load_max_pct: Option<f32>,
}

/// (v6) Which transducer's resonance the drive frequency follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Track {
    /// 0: no tracking: the drive frequency is the setting's.
    None,
    /// 1: the normal transducer.
    Z,
    /// 2: the tangential transducer.
    X,
}

/// (v6) The displacement mode's options ([`Request::SetDisplacementOptions`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DisplacementOptions {
    /// Resonance tracking (`Track::None` at power-up).
    pub track: Track,
    /// The voltage bound during a transition, in units of the identified
    /// model's steady-state voltage, in `[1, MAX_HEADROOM]` (1: no
    /// overdrive; [`DEFAULT_HEADROOM`] at power-up).
    pub headroom: f32,
}

/// (v6) The headroom at power-up.
pub const DEFAULT_HEADROOM: f32 = 2.0;
/// (v6) The largest headroom accepted.
pub const MAX_HEADROOM: f32 = 8.0;

impl Default for DisplacementOptions {
    fn default() -> Self {
        DisplacementOptions {
            track: Track::None,
            headroom: DEFAULT_HEADROOM,
        }
    }
}

/// (v4) The transducers' motion as the pickups measure it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MeasuredDrive {
    /// Normal amplitude Δu_z measured, m.
    pub amp_z_m: f32,
    /// Tangential amplitude Δu_x measured, m.
    pub amp_x_m: f32,
    /// φ between the measured modes, rad in (−π, π] (`device::motion`, eq. M1).
    pub phase_rad: f32,
    /// The largest normal amplitude measured since the last accepted
    /// `SetDrive` or `Start`, m.
    pub amp_z_peak_m: f32,
    /// Lock-in windows finished since power-up (a new value: a new window).
    pub windows: u32,
    /// (v5) The normal mode's measured response to its DAC channel, m/V as
    /// `[re, im]` of `H = X/U` (eq. 1 of [`crate::identify`]: the
    /// pickup's phasor over the channel's voltage phasor at the window's
    /// end); `None` while the channel's voltage is zero.
    pub response_z_m_per_v: Option<[f32; 2]>,
    /// (v5) The tangential mode's measured response, m/V, as `response_z_m_per_v`.
    pub response_x_m_per_v: Option<[f32; 2]>,
}

/// (v5) One transducer mode as identified (eq. 1 of
/// [`crate::identify`]): `H(f) = g·e^{−jθ}/(1 − r² + j r/Q)`, `r = f/f_r`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransducerModel {
    /// Resonance f_r, Hz (> 0).
    pub resonance_hz: f32,
    /// Quality factor Q (> 1/2).
    pub q: f32,
    /// Static gain g, m/V (> 0).
    pub gain_m_per_v: f32,
    /// Constant extra lag θ of the chain (pickup, filters), rad.
    pub phase_lag_rad: f32,
}

/// (v5) Both transducers as identified (`fricctl device identify`): the
/// feed-forward of the displacement loops ([`DriveMode::Displacement`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Transducers {
    /// The normal transducer (DAC channel 1).
    pub z: TransducerModel,
    /// The tangential transducer (DAC channel 2).
    pub x: TransducerModel,
}

/// (v5) How the device turns a [`DriveSetting`] into DAC voltages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DriveMode {
    /// 0: voltage mode (the power-up state): the DAC calibration
    /// ([`crate::device::DacCal`]) is taken to be the displacement.
    OpenLoop,
    /// 1: displacement mode: the identified [`Transducers`] give the
    /// voltages (feed-forward) and a complex loop per channel on the
    /// pickups' lock-ins holds the *measured* amplitudes and φ at the
    /// setting (needs [`Request::SetTransducers`] first).
    Displacement,
}

/// What the device is (answer to [`Request::Hello`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Info {
    /// Firmware version (major, minor, patch).
    pub firmware: [u8; 3],
    /// [`PROTOCOL_VERSION`] of the device.
    pub protocol: u16,
    /// Board name, ASCII, zero-padded.
    pub board: [u8; 16],
    /// DDS / ADC sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Drive frequency range, Hz.
    pub freq_range_hz: (f64, f64),
    /// Largest tangential amplitude, m.
    pub max_amp_x_m: f32,
    /// Largest normal offset (mean indentation), m.
    pub max_offset_z_m: f32,
    /// Lift-off margin: Δu_z ≤ (1 − margin)·u_z0.
    pub liftoff_margin: f32,
    /// Largest |φ| of a drive, rad.
    pub max_phase_rad: f32,
    /// Largest |v₀| of a prediction, m/s.
    pub max_velocity_m_s: f32,
    /// Allowed periods of `Measure` and `Stream`, inclusive.
    pub periods_range: (u32, u32),
    /// A frame whose bytes arrive more than this apart is dropped, µs.
    pub byte_timeout_us: u32,
    /// (v3) How far below the surface (u_z = 0) the normal transducer
    /// reaches, m: a drive needs `amp_z_m ≤ offset_z_m + retract_z_m` (0 on
    /// the driver board: `Δu_z ≤ u_z0`; binding once lift-off is allowed).
    pub retract_z_m: f32,
    /// (v7) The board's power-up self-test ([`SelfTest::NOT_RUN`] on a
    /// board without one).
    pub self_test: SelfTest,
}

impl Info {
    /// This `Info` with the power-up self-test's result `t`.
    pub const fn with_self_test(self, t: SelfTest) -> Self {
        Info {
            self_test: t,
            ..self
        }
    }
}

/// The power-up self-test of a board (v7): the clocks measured against the
/// internal RC oscillator and the DMA set-up checked before the drive may
/// start. A failed check the drive depends on also latches the fault
/// [`crate::device::faults::SELF_TEST`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SelfTest {
    /// Checks that ran (bits of [`self_test`]); 0 on boards without one
    /// (the virtual device, QEMU).
    pub ran: u16,
    /// Checks that failed, a subset of `ran`.
    pub failed: u16,
    /// The crystal (HSE) frequency measured against the internal 16 MHz RC
    /// oscillator (HSI, ±1 %), Hz; 0 if not measured.
    pub hse_hz: u32,
    /// The core clock (SYSCLK) measured the same way, Hz; 0 if not measured.
    pub sysclk_hz: u32,
}

/// (v7) The checks of the power-up self-test ([`SelfTest::ran`],
/// [`SelfTest::failed`]).
pub mod self_test {
    /// The crystal oscillator (HSE) and the PLL became ready within their
    /// time-outs.
    pub const CLOCK_READY: u16 = 1 << 0;
    /// The measured crystal frequency ([`super::SelfTest::hse_hz`]) is
    /// within ±3 % of the build's `HSE_HZ`.
    pub const HSE_FREQUENCY: u16 = 1 << 1;
    /// The measured core clock ([`super::SelfTest::sysclk_hz`]) is within
    /// ±3 % of 168 MHz.
    pub const SYSCLK: u16 = 1 << 2;
    /// FLASH_ACR reads back the wait states written.
    pub const FLASH_LATENCY: u16 = 1 << 3;
    /// Both DMA streams (DAC and ADC) read back the buffer address, length
    /// and peripheral address they were given.
    pub const DMA_SETUP: u16 = 1 << 4;
    /// Both DMA streams handed over their first two half-buffers within
    /// 1 ms of the sample clock's start.
    pub const STREAMS_RUNNING: u16 = 1 << 5;
    /// Every check defined above.
    pub const ALL: u16 =
        CLOCK_READY | HSE_FREQUENCY | SYSCLK | FLASH_LATENCY | DMA_SETUP | STREAMS_RUNNING;
    /// Each check's name (host output, `docs/device-json.md`), in bit order.
    pub const NAMES: [(u16, &str); 6] = [
        (CLOCK_READY, "clock_ready"),
        (HSE_FREQUENCY, "hse_frequency"),
        (SYSCLK, "sysclk"),
        (FLASH_LATENCY, "flash_latency"),
        (DMA_SETUP, "dma_setup"),
        (STREAMS_RUNNING, "streams_running"),
    ];

    /// The names of the known checks among `bits`, in bit order (bits
    /// outside [`ALL`] are not named).
    pub fn names(bits: u16) -> impl Iterator<Item = &'static str> {
        NAMES
            .into_iter()
            .filter(move |(b, _)| bits & b != 0)
            .map(|(_, n)| n)
    }
}

impl SelfTest {
    /// No self-test ran (every field 0): the virtual device, QEMU.
    pub const NOT_RUN: SelfTest = SelfTest {
        ran: 0,
        failed: 0,
        hse_hz: 0,
        sysclk_hz: 0,
    };

    /// Some check ran and none failed.
    pub const fn passed(&self) -> bool {
        self.ran != 0 && self.failed == 0
    }

    /// The names of the failed checks, in bit order ([`self_test::NAMES`]).
    pub fn failed_names(&self) -> impl Iterator<Item = &'static str> {
        self_test::names(self.failed)
    }

    /// The names of the checks that ran, in bit order.
    pub fn ran_names(&self) -> impl Iterator<Item = &'static str> {
        self_test::names(self.ran)
    }
}

/// Requests (host → device). [`ENDPOINTS`] names the response of each.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Request {
    /// 0: identify.
    Hello,
    /// 1: the accepted drive.
    GetDrive,
    /// 2: set the drive (validated whole; refused commands change nothing).
    SetDrive(DriveSetting),
    /// 3: start (soft start).
    Start,
    /// 4: stop (ramped).
    Stop,
    /// 5: the contact parameters.
    GetContact,
    /// 6: set the contact parameters.
    SetContact(Contact),
    /// 7: model prediction at a sliding velocity (m/s).
    Predict {
        /// v₀, m/s.
        v0: f32,
    },
    /// 8: start a measurement over `periods` drive periods.
    Measure {
        /// Drive periods.
        periods: u32,
    },
    /// 9: the last finished measurement.
    GetEstimate,
    /// 10: stream estimates (each over `periods`) as telemetry, or stop.
    Stream {
        /// On or off.
        on: bool,
        /// Periods per estimate.
        periods: u32,
    },
    /// 11: status and faults.
    GetStatus,
    /// 12: clear latched faults.
    ResetFaults,
    /// 13: end every session: stop the stream (`StreamStopped(Reset)`),
    /// abort a running measurement, stop the drive (ramped), forget the
    /// `Measure` seq, clear `Status.cpu_load_max_pct` (v8); settings,
    /// contact and latched faults are kept.
    Reset,
    /// 14 (v3): allow drives with `Δu_z` above the lift-off limit
    /// `(1 − liftoff_margin)·u_z0` (intermittent contact; `Predict` then uses
    /// the lift-off model), or refuse them again (the power-up state).
    /// Refusing while the accepted drive is above the limit is itself
    /// refused with `LiftOffRefused` and changes nothing.
    SetLiftOff {
        /// Allow (`true`) or refuse (`false`).
        allow: bool,
    },
    /// 15 (v3): switch the closed loop on (or change its setpoint) or off
    /// ([`ControlSetting`]); answered with the loop's state.
    SetControl(ControlSetting),
    /// 16 (v3): the closed loop's state.
    GetControl,
    /// 17 (v5): store the identified transducers (`Some`, validated whole)
    /// or forget them (`None`; refused with `NotIdentified` while the
    /// displacement mode is in force). Kept by `Reset`, lost at power-down.
    SetTransducers(Option<Transducers>),
    /// 18 (v5): the stored transducers.
    GetTransducers,
    /// 19 (v5): switch between voltage and displacement mode
    /// ([`DriveMode`]); `Displacement` needs stored transducers
    /// (`NotIdentified`) and re-plans the accepted drive through them
    /// (its checks as `SetDrive`'s: a refusal changes nothing).
    SetDriveMode(DriveMode),
    /// 20 (v6): the displacement mode's options (tracking, headroom);
    /// validated whole, a refusal changes nothing. Tracking needs stored
    /// transducers (`NotIdentified`).
    SetDisplacementOptions(DisplacementOptions),
}

/// The closed loop as commanded ([`crate::control`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControlSetting {
    /// On (a new setpoint if already on) or off (the last command stays).
    pub on: bool,
    /// Setpoint μ*, `|μ*| < μ₀` of the device's contact.
    pub target_mu: f32,
    /// Sliding velocity v₀ the setpoint holds at, m/s (≠ 0, ≤ `max_velocity_m_s`).
    pub v0_m_s: f32,
    /// κ, the fraction of the error removed per update, in `[0.01, 1]`.
    pub gain: f32,
    /// Drive periods per estimate (one update each), in `1..=CONTROL_MAX_PERIODS`.
    pub periods: u32,
    /// Rate limit of the commanded Δu_z, m/s, in `(0, slew]` (the DDS slew).
    pub rate_m_per_s: f32,
}

/// Most drive periods per closed-loop update.
pub const CONTROL_MAX_PERIODS: u32 = 10_000;

/// One closed-loop update (also the telemetry sent per update).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControlUpdate {
    /// Updates since the loop was switched on (0: none yet).
    pub update: u32,
    /// Setpoint μ*.
    pub target_mu: f32,
    /// The estimate the update used (eq. 20).
    pub measured_mu: f32,
    /// Its standard error.
    pub std_error: f32,
    /// The commanded Δu_z, m.
    pub amp_z_m: f32,
    /// The integral trim `I`, m.
    pub integral_m: f32,
    /// The rate limit or the lift-off / zero bound changed the command.
    pub saturated: bool,
    /// The estimate was not usable (saturated ADC, fault, drive stopped):
    /// the command was held.
    pub held: bool,
}

/// The closed loop's state (answer to `SetControl` and `GetControl`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControlState {
    /// The last accepted setting (`on` is false once the loop is off,
    /// including after `Stop`, `Reset` or a fault).
    pub setting: ControlSetting,
    /// The model's feedforward Δu_z for the setpoint, m.
    pub feedforward_m: f32,
    /// The model's gain ∂μ/∂Δu_z there, 1/m.
    pub slope_per_m: f32,
    /// The command's bound (lift-off limit at the offset), m.
    pub limit_m: f32,
    /// The last update.
    pub last: ControlUpdate,
}

/// Which [`Response`] variant answers a request when it succeeds (any request
/// may instead be answered by [`Response::Error`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Answer {
    /// [`Response::Info`].
    Info,
    /// [`Response::Drive`].
    Drive,
    /// [`Response::Ok`].
    Ok,
    /// [`Response::Contact`].
    Contact,
    /// [`Response::Prediction`].
    Prediction,
    /// [`Response::Estimate`].
    Estimate,
    /// [`Response::Status`].
    Status,
    /// [`Response::Control`].
    Control,
    /// [`Response::Transducers`].
    Transducers,
}

/// One row of the request → response table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Endpoint {
    /// The request's variant index on the wire.
    pub index: u32,
    /// The request's name.
    pub request: &'static str,
    /// The response that answers it on success.
    pub answer: Answer,
}

/// The request → response table, in variant order (`ENDPOINTS[i].index == i`).
/// Its length is the number of known requests: a larger index is answered
/// with [`WireError::UnknownMessage`].
pub const ENDPOINTS: &[Endpoint] = &[
    ep(0, "Hello", Answer::Info),
    ep(1, "GetDrive", Answer::Drive),
    ep(2, "SetDrive", Answer::Drive),
    ep(3, "Start", Answer::Ok),
    ep(4, "Stop", Answer::Ok),
    ep(5, "GetContact", Answer::Contact),
    ep(6, "SetContact", Answer::Ok),
    ep(7, "Predict", Answer::Prediction),
    ep(8, "Measure", Answer::Ok),
    ep(9, "GetEstimate", Answer::Estimate),
    ep(10, "Stream", Answer::Ok),
    ep(11, "GetStatus", Answer::Status),
    ep(12, "ResetFaults", Answer::Ok),
    ep(13, "Reset", Answer::Ok),
    ep(14, "SetLiftOff", Answer::Ok),
    ep(15, "SetControl", Answer::Control),
    ep(16, "GetControl", Answer::Control),
    ep(17, "SetTransducers", Answer::Ok),
    ep(18, "GetTransducers", Answer::Transducers),
    ep(19, "SetDriveMode", Answer::Ok),
    ep(20, "SetDisplacementOptions", Answer::Ok),
];

const fn ep(index: u32, request: &'static str, answer: Answer) -> Endpoint {
    Endpoint {
        index,
        request,
        answer,
    }
}

impl Request {
    /// The variant index on the wire.
    pub const fn index(&self) -> u32 {
        match self {
            Request::Hello => 0,
            Request::GetDrive => 1,
            Request::SetDrive(_) => 2,
            Request::Start => 3,
            Request::Stop => 4,
            Request::GetContact => 5,
            Request::SetContact(_) => 6,
            Request::Predict { .. } => 7,
            Request::Measure { .. } => 8,
            Request::GetEstimate => 9,
            Request::Stream { .. } => 10,
            Request::GetStatus => 11,
            Request::ResetFaults => 12,
            Request::Reset => 13,
            Request::SetLiftOff { .. } => 14,
            Request::SetControl(_) => 15,
            Request::GetControl => 16,
            Request::SetTransducers(_) => 17,
            Request::GetTransducers => 18,
            Request::SetDriveMode(_) => 19,
            Request::SetDisplacementOptions(_) => 20,
        }
    }

    /// The request's row of [`ENDPOINTS`].
    pub const fn endpoint(&self) -> &'static Endpoint {
        &ENDPOINTS[self.index() as usize]
    }
}

/// Responses (device → host).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Response {
    /// 0: to `Hello`.
    Info(Info),
    /// 1: to `GetDrive` / `SetDrive`.
    Drive {
        /// The accepted drive.
        setting: DriveSetting,
        /// What the DDS produces.
        applied: Applied,
    },
    /// 2: done (`Start`, `Stop`, `SetContact`, `Measure`, `Stream`, `ResetFaults`, `Reset`,
    /// `SetLiftOff`).
    Ok,
    /// 3: to `GetContact`.
    Contact(Contact),
    /// 4: to `Predict`.
    Prediction {
        /// The prediction.
        prediction: Prediction,
        /// The regime of the current drive.
        regime: Regime,
    },
    /// 5: to `GetEstimate`.
    Estimate(Estimate),
    /// 6: to `GetStatus`.
    Status(Status),
    /// 7: the request failed.
    Error(WireError),
    /// 8: to `SetControl` / `GetControl`.
    Control(ControlState),
    /// 9 (v5): to `GetTransducers`.
    Transducers(Option<Transducers>),
}

impl Response {
    /// Which [`Answer`] this is (`None` for [`Response::Error`]).
    pub const fn answer(&self) -> Option<Answer> {
        Some(match self {
            Response::Info(_) => Answer::Info,
            Response::Drive { .. } => Answer::Drive,
            Response::Ok => Answer::Ok,
            Response::Contact(_) => Answer::Contact,
            Response::Prediction { .. } => Answer::Prediction,
            Response::Estimate(_) => Answer::Estimate,
            Response::Status(_) => Answer::Status,
            Response::Control(_) => Answer::Control,
            Response::Transducers(_) => Answer::Transducers,
            Response::Error(_) => return None,
        })
    }
}

/// Unsolicited telemetry (device → host).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Telemetry {
    /// 0: a streamed estimate.
    Estimate(Estimate),
    /// 1: the ramps have settled.
    RampDone,
    /// 2: a fault was latched (bits of [`crate::device::faults`]).
    Fault(u32),
    /// 3: the stream of estimates ended (no more `Estimate` telemetry).
    StreamStopped(StreamEnd),
    /// 4: received bytes were dropped because the receive queue was full;
    /// the new total of [`Status::rx_overflows`] (sent once per poll in
    /// which it grew).
    RxOverflow(u32),
    /// 5: a closed-loop update (at most one per poll: `update` counts them,
    /// so a gap shows updates not sent).
    Control(ControlUpdate),
}

/// Why a stream of estimates ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamEnd {
    /// 0: `Stream { on: false, .. }`.
    Requested,
    /// 1: `Reset`.
    Reset,
    /// 2: the next measurement was refused (e.g. a latched fault): the error.
    Refused(WireError),
}

/// A frame body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Body {
    /// 0: host → device.
    Request(Request),
    /// 1: device → host, `seq` echoes the request.
    Response(Response),
    /// 2: device → host, `seq` is the telemetry counter.
    Telemetry(Telemetry),
}

/// The names of the [`Body`] variants, in variant order (its length is the
/// number of known bodies).
pub const BODY_KINDS: &[&str] = &["Request", "Response", "Telemetry"];

/// One frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// [`PROTOCOL_VERSION`].
    pub version: u16,
    /// Sequence number.
    pub seq: u32,
    /// Contents.
    pub body: Body,
}

/// Errors on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WireError {
    /// 0: not valid COBS / postcard.
    Malformed,
    /// 1: CRC mismatch.
    BadCrc,
    /// 2: unknown request variant.
    UnknownMessage,
    /// 3: the device speaks another version.
    VersionMismatch {
        /// The device's version.
        device: u16,
    },
    /// 4: frame longer than [`crate::protocol::MAX_FRAME`].
    Oversize,
    /// 5: a parameter out of range (which one, and the limits).
    OutOfRange {
        /// The parameter.
        param: DriveParam,
        /// Smallest allowed.
        min: f32,
        /// Largest allowed.
        max: f32,
    },
    /// 6: the normal amplitude would lift the contact off.
    LiftOffRefused {
        /// Commanded Δu_z, m.
        amp_z_m: f32,
        /// Largest allowed, m.
        limit_m: f32,
    },
    /// 7: a measurement is running.
    Busy,
    /// 8: a fault is latched.
    Faulted(u32),
    /// 9: the contact/drive is not a valid scene.
    BadScene,
    /// 10: the model failed.
    Model,
    /// 11: no finished measurement yet.
    NotReady,
    /// 12: the measurement has no normal force.
    NoNormalForce,
    /// 13: an internal inconsistency of the device (never expected; report it).
    Internal,
    /// 14: the drive is not running (the closed loop needs it).
    NotRunning,
    /// 15: the closed loop's target is out of the model's reach over
    /// Δu_z in `[0, lift-off limit]`: the reachable μ.
    OutOfReach {
        /// Least reachable μ.
        min: f32,
        /// Greatest reachable μ.
        max: f32,
    },
    /// 16 (v5): the displacement mode needs identified transducers
    /// (`SetTransducers`; `fricctl device identify`).
    NotIdentified,
}

impl fmt::Display for WireError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            WireError::Malformed => {
                f.write_str("malformed frame (not COBS or not a valid message)")
            }
            WireError::BadCrc => f.write_str("CRC mismatch"),
            WireError::UnknownMessage => f.write_str("unknown message"),
            WireError::VersionMismatch { device } => {
                write!(f, "protocol version mismatch (the device speaks v{device})")
            }
            WireError::Oversize => f.write_str("frame too long"),
            WireError::OutOfRange { param, min, max } => {
                write!(f, "{} out of range [{min}, {max}]", param.name())
            }
            WireError::LiftOffRefused { amp_z_m, limit_m } => write!(
                f,
                "amp_z_m = {amp_z_m} m would lift the contact off (limit {limit_m} m)"
            ),
            WireError::Busy => f.write_str("busy: a measurement or stream is running"),
            WireError::Faulted(bits) => {
                write!(f, "a fault is latched (bits {bits:#x}): reset it first")
            }
            WireError::BadScene => f.write_str("the contact and drive do not form a valid scene"),
            WireError::Model => f.write_str("the model solver failed"),
            WireError::NotReady => f.write_str("no finished measurement"),
            WireError::NoNormalForce => f.write_str("the measurement has no normal force"),
            WireError::Internal => f.write_str("internal device error"),
            WireError::NotRunning => f.write_str("the drive is not running (start it first)"),
            WireError::OutOfReach { min, max } => write!(
                f,
                "target_mu out of the model's reach: mu from {min} to {max} over amp_z_m in [0, lift-off limit]"
            ),
            WireError::NotIdentified => f.write_str(
                "the transducers are not identified: run `fricctl device identify` (or drive in voltage mode, --open-loop)",
            ),
        }
    }
}

impl core::error::Error for WireError {}

#[cfg(test)]
mod tests {
    use super::*;

    /// One request of every variant, in variant order.
    fn every_request() -> [Request; 21] {
        let drive = DriveSetting {
            freq_hz: 1e4,
            amp_z_m: 0.0,
            amp_x_m: 0.0,
            offset_z_m: 1e-6,
            phase_rad: 0.0,
        };
        [
            Request::Hello,
            Request::GetDrive,
            Request::SetDrive(drive),
            Request::Start,
            Request::Stop,
            Request::GetContact,
            Request::SetContact(Contact {
                mu0: 0.3,
                kz: 1.0,
                kx: 1.0,
            }),
            Request::Predict { v0: 0.0 },
            Request::Measure { periods: 1 },
            Request::GetEstimate,
            Request::Stream {
                on: false,
                periods: 1,
            },
            Request::GetStatus,
            Request::ResetFaults,
            Request::Reset,
            Request::SetLiftOff { allow: false },
            Request::SetControl(ControlSetting {
                on: false,
                target_mu: 0.1,
                v0_m_s: 0.004,
                gain: 0.5,
                periods: 8,
                rate_m_per_s: 1e-3,
            }),
            Request::GetControl,
            Request::SetTransducers(None),
            Request::GetTransducers,
            Request::SetDriveMode(DriveMode::OpenLoop),
            Request::SetDisplacementOptions(DisplacementOptions::default()),
        ]
    }

    #[test]
    fn endpoint_table_matches_the_wire_indices() {
        let reqs = every_request();
        assert_eq!(reqs.len(), ENDPOINTS.len());
        for (i, r) in reqs.iter().enumerate() {
            assert_eq!(ENDPOINTS[i].index, i as u32);
            assert_eq!(r.index(), i as u32);
            let mut buf = [0u8; 64];
            let bytes = postcard::to_slice(r, &mut buf).unwrap();
            // Indices < 128 are one varint byte.
            assert_eq!(u32::from(bytes[0]), r.index(), "{r:?}");
        }
    }
}
