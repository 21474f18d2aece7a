//! The device's answers as the host reads them: a refusal becomes one line
//! naming the flag ([`wire_error`]), an answer of the wrong kind an error
//! ([`unexpected`]), an `f32` the `f64` of the same shortest text ([`f32v`]).

use board::protocol::{Response, WireError};
use fric_analysis::numbers::short;

use crate::{Error, Result};

/// An `f32` as the `f64` with the same shortest decimal form (0.1f32 is
/// 0.1, not 0.10000000149011612).
pub fn f32v(x: f32) -> f64 {
    if x.is_finite() {
        x.to_string().parse().unwrap_or(f64::from(x))
    } else {
        f64::NAN
    }
}

/// The one line of a device's refusal, naming the `fricctl` flag of the
/// refused value and the range in the flag's units.
pub fn wire_error(e: WireError) -> Error {
    use board::device::DriveParam;
    let name = |p: DriveParam| match p {
        DriveParam::Freq => "--freq",
        DriveParam::AmpZ => "--amp-z",
        DriveParam::AmpX => "--amp-x",
        DriveParam::OffsetZ => "--offset-z",
        DriveParam::Phase => "--phase-deg",
        DriveParam::Periods => "--periods",
        DriveParam::Velocity => "--v0",
        DriveParam::TargetMu => "--target-mu",
        DriveParam::Gain => "--gain",
        DriveParam::Rate => "--rate",
        DriveParam::Resonance => "resonance_hz (of the identified transducers)",
        DriveParam::Quality => "q (of the identified transducers)",
        DriveParam::TransducerGain => "gain_m_per_v (of the identified transducers)",
        DriveParam::PhaseLag => "phase_lag_rad (of the identified transducers)",
        DriveParam::Headroom => "--headroom",
    };
    match e {
        // The device's phase limits are radians; the flag takes degrees.
        WireError::OutOfRange {
            param: DriveParam::Phase,
            min,
            max,
        } => Error::usage(format!(
            "--phase-deg: refused by the device: allowed range [{}, {}] degrees",
            short(f32v(min).to_degrees().trunc()),
            short(f32v(max).to_degrees().trunc())
        )),
        WireError::OutOfRange { param, min, max } => {
            Error::usage(format!(
                "{}: refused by the device: allowed range [{}, {}]",
                name(param),
                short(f32v(min)),
                short(f32v(max))
            ))
        }
        WireError::LiftOffRefused { amp_z_m, limit_m } => Error::usage(format!(
            "--amp-z: refused by the device: {} m would lift the contact off (limit {} m); \
             lower it, or allow lift-off on purpose with `fricctl device config --allow-liftoff`",
            short(f32v(amp_z_m)),
            short(f32v(limit_m))
        )),
        WireError::BadScene => Error::usage(
            "--offset-z: the device has no valid scene: it needs a contact (scene set) and a drive with a normal offset (drive set)"
                .to_string(),
        ),
        WireError::OutOfReach { min, max } => Error::usage(format!(
            "--target-mu: out of reach of the device's model by adjusting Δu_z up to the lift-off limit: reachable mu {} … {}",
            short(f32v(min)),
            short(f32v(max))
        )),
        WireError::NotIdentified => Error::usage(
            "the transducers are not identified: run `fricctl device identify` first, or pass \
             --open-loop (voltage mode)"
                .to_string(),
        ),
        WireError::NotRunning => Error::usage(
            "the drive is not running: `fricctl device start` first".to_string(),
        ),
        WireError::Busy => Error::failure(
            "device busy: a measurement, stream or the closed loop is running (`device control off` ends the loop)".to_string(),
        ),
        other => Error::failure(format!("device error: {other}")),
    }
}

/// The answer, or the device's refusal as an [`Error`] ([`wire_error`]).
///
/// # Errors
/// The refusal.
pub fn expect(r: Response) -> Result<Response> {
    match r {
        Response::Error(e) => Err(wire_error(e)),
        other => Ok(other),
    }
}

/// An answer of the wrong kind for the request.
pub fn unexpected(r: Response) -> Error {
    use board::protocol::Answer;
    let what = match r.answer() {
        Some(Answer::Info) => "Info",
        Some(Answer::Drive) => "Drive",
        Some(Answer::Ok) => "Ok",
        Some(Answer::Contact) => "Contact",
        Some(Answer::Prediction) => "Prediction",
        Some(Answer::Estimate) => "Estimate",
        Some(Answer::Status) => "Status",
        Some(Answer::Control) => "Control",
        Some(Answer::Transducers) => "Transducers",
        None => "an error",
    };
    Error::failure(format!("unexpected answer from the device: {what}"))
}
