//! Why the device refused a command or a configuration (every refusal leaves
//! the device as it was), and how each refusal travels on the wire.

use core::fmt;

use crate::control::ControlError;
use crate::dds::DdsError;
use crate::estimator::EstimateError;
use crate::protocol::messages::{DriveParam, WireError};
use model_core::exact::ExactError;
use model_core::model::liftoff::LiftOffError;
use model_core::scene::SceneError;

/// A field of [`super::DeviceConfig`] that cannot work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// `sample_rate_hz` not finite or ≤ 0.
    SampleRate,
    /// `slew_m_per_s` / `slew_rad_per_s` not finite or ≤ 0.
    Slew,
    /// `liftoff_margin` outside `[0, 0.99]`.
    LiftoffMargin,
    /// A DAC calibration: `metres_per_code` not > 0 or `zero_code` outside `0..=4095`.
    DacCal,
    /// An ADC calibration: not finite or zero gain.
    AdcCal,
    /// `freq_range_hz` empty, not finite, or not below Nyquist.
    FreqRange,
    /// `pickup_delay_s` not finite, negative, or not below one sample period.
    PickupDelay,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ConfigError::SampleRate => "sample_rate_hz must be finite and > 0",
            ConfigError::Slew => "slew_m_per_s and slew_rad_per_s must be finite and > 0",
            ConfigError::LiftoffMargin => "liftoff_margin must be in [0, 0.99]",
            ConfigError::DacCal => {
                "a DAC calibration needs metres_per_code > 0 and zero_code in 0..=4095"
            }
            ConfigError::AdcCal => "an ADC calibration needs a finite, non-zero gain",
            ConfigError::FreqRange => {
                "freq_range_hz must be a finite, non-empty range below half the sample rate"
            }
            ConfigError::PickupDelay => {
                "pickup_delay_s must be finite, >= 0 and below one sample period"
            }
        })
    }
}

impl core::error::Error for ConfigError {}

/// Why a command was refused (nothing changed).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceError {
    /// A parameter is not finite or outside `[min, max]`.
    OutOfRange {
        /// The parameter.
        param: DriveParam,
        /// Smallest allowed value.
        min: f32,
        /// Largest allowed value.
        max: f32,
    },
    /// Δu_z would exceed `(1 − margin)·u_z0`: the contact would lift off.
    LiftOff {
        /// Commanded Δu_z, m.
        amp_z_m: f32,
        /// Largest allowed Δu_z, m.
        limit_m: f32,
    },
    /// A measurement (or stream) is already running.
    Busy,
    /// A fault is latched: reset it first.
    Faulted(u32),
    /// The contact and drive do not form a valid scene.
    Scene(SceneError),
    /// The model solver failed.
    Model(ExactError),
    /// The lift-off model failed (a lift-off drive, see `set_liftoff_allowed`).
    LiftOffModel(LiftOffError),
    /// No finished measurement.
    Estimate(EstimateError),
    /// The configuration cannot work ([`super::Device::new`] only).
    Config(ConfigError),
    /// The DDS refused a setting the device had validated (an internal
    /// inconsistency, never expected).
    Dds(DdsError),
    /// The drive is not running (the closed loop needs it).
    NotRunning,
    /// The closed loop has no plan for the setpoint.
    Control(ControlError),
    /// (v5) The displacement mode needs identified transducers.
    NotIdentified,
}

impl fmt::Display for DeviceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DeviceError::OutOfRange { param, min, max } => {
                write!(f, "{} out of range [{min}, {max}]", param.name())
            }
            DeviceError::LiftOff { amp_z_m, limit_m } => write!(
                f,
                "amp_z_m = {amp_z_m} m would lift the contact off (limit {limit_m} m)"
            ),
            DeviceError::Busy => f.write_str("busy: a measurement or stream is running"),
            DeviceError::Faulted(bits) => {
                write!(f, "a fault is latched (bits {bits:#x}): reset it first")
            }
            DeviceError::Scene(e) => write!(f, "not a valid scene: {e}"),
            DeviceError::Model(_) => f.write_str("the model solver failed"),
            DeviceError::LiftOffModel(e) => write!(f, "the lift-off model failed: {e}"),
            DeviceError::Estimate(e) => write!(f, "{e}"),
            DeviceError::Config(e) => write!(f, "bad configuration: {e}"),
            DeviceError::Dds(e) => write!(f, "internal: the DDS refused a validated setting: {e}"),
            DeviceError::NotRunning => f.write_str("the drive is not running (start it first)"),
            DeviceError::Control(e) => write!(f, "closed loop: {e}"),
            DeviceError::NotIdentified => write!(f, "{}", WireError::NotIdentified),
        }
    }
}

impl core::error::Error for DeviceError {}

impl From<DdsError> for DeviceError {
    fn from(e: DdsError) -> Self {
        DeviceError::Dds(e)
    }
}

impl From<DeviceError> for WireError {
    fn from(e: DeviceError) -> Self {
        match e {
            DeviceError::OutOfRange { param, min, max } => {
                WireError::OutOfRange { param, min, max }
            }
            DeviceError::LiftOff { amp_z_m, limit_m } => {
                WireError::LiftOffRefused { amp_z_m, limit_m }
            }
            DeviceError::Busy => WireError::Busy,
            DeviceError::Faulted(b) => WireError::Faulted(b),
            DeviceError::Scene(_) => WireError::BadScene,
            DeviceError::Model(_) | DeviceError::LiftOffModel(_) => WireError::Model,
            DeviceError::Estimate(EstimateError::NoNormalForce) => WireError::NoNormalForce,
            DeviceError::Estimate(_) => WireError::NotReady,
            DeviceError::Config(_) | DeviceError::Dds(_) => WireError::Internal,
            DeviceError::NotRunning => WireError::NotRunning,
            DeviceError::NotIdentified => WireError::NotIdentified,
            DeviceError::Control(c) => match c {
                ControlError::OutOfReach { min, max } => WireError::OutOfReach { min, max },
                // The device checks the target against ±μ₀ first (an
                // OutOfRange with the limits): never reached.
                ControlError::BadTarget => WireError::Internal,
                ControlError::BadVelocity => WireError::OutOfRange {
                    param: DriveParam::Velocity,
                    min: -super::MAX_VELOCITY_M_S,
                    max: super::MAX_VELOCITY_M_S,
                },
                ControlError::NoOffset => WireError::BadScene,
                ControlError::Model(_) => WireError::Model,
            },
        }
    }
}
