//! The device link's wire protocol, defined once for the firmware and the host.
//!
//! **Framing.** A frame on the wire is `COBS( postcard(Frame) ‖ CRC-32 ) 0x00`:
//! the [`Frame`] is serialised with postcard, the CRC-32 (ISO-HDLC: polynomial
//! 0x04C11DB7 reflected, init 0xFFFFFFFF, final xor 0xFFFFFFFF — the zlib/PNG CRC)
//! of those bytes is appended little-endian, the whole is COBS-encoded and
//! terminated by one zero byte. At most [`MAX_FRAME`] bytes per frame on the
//! wire, including the delimiter; both ends drop longer frames.
//!
//! **Frame.** `version` (varint u16, [`PROTOCOL_VERSION`]), `seq` (varint u32),
//! then a [`Body`]. A request's `seq` is echoed in its response; telemetry
//! carries its own counter in `seq` so the host can count drops. Enums are
//! encoded by postcard as a varint variant index (declaration order) followed
//! by the fields: new variants are only ever appended.
//!
//! **Errors are values** ([`WireError`], after postcard-rpc's set): a frame that
//! is not valid COBS or not valid postcard → `Malformed`; CRC mismatch →
//! `BadCrc`; an unknown request variant → `UnknownMessage`; another protocol
//! version → `VersionMismatch`; a frame over [`MAX_FRAME`] → `Oversize`; and the
//! device's refusals. The receiver resynchronises at the next delimiter.

use serde::{Deserialize, Serialize};

use crate::board::device::{
    Applied, Contact, DeviceError, DriveParam, DriveSetting, Prediction, Status,
};
use crate::board::estimator::{Estimate, EstimateError};
use crate::model::regime::Regime;

/// Protocol version; a frame with another version is answered with
/// [`WireError::VersionMismatch`].
pub const PROTOCOL_VERSION: u16 = 1;

/// Number of [`Request`] variants (indices `0..REQUEST_VARIANTS` are known).
pub const REQUEST_VARIANTS: u32 = 13;

/// Largest frame on the wire (COBS-encoded, with CRC and delimiter), bytes.
pub const MAX_FRAME: usize = 256;

/// The CRC of the frames (CRC-32/ISO-HDLC).
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

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
}

impl Info {
    /// The `Info` of a device with configuration `cfg`, board name `board`
    /// (ASCII, truncated to 16 bytes) and firmware version `firmware`.
    pub fn for_config(
        cfg: &crate::board::device::DeviceConfig,
        board: &str,
        firmware: [u8; 3],
    ) -> Self {
        let mut name = [0u8; 16];
        for (d, s) in name.iter_mut().zip(board.bytes()) {
            *d = s;
        }
        Info {
            firmware,
            protocol: PROTOCOL_VERSION,
            board: name,
            sample_rate_hz: cfg.sample_rate_hz,
            freq_range_hz: cfg.freq_range_hz,
            max_amp_x_m: cfg.dac_x.zero_code.min(4095.0 - cfg.dac_x.zero_code)
                * cfg.dac_x.metres_per_code,
            max_offset_z_m: (4095.0 - cfg.dac_z.zero_code) * cfg.dac_z.metres_per_code,
            liftoff_margin: cfg.liftoff_margin,
        }
    }
}

/// Requests (host → device).
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
    /// 2: done (`Start`, `Stop`, `SetContact`, `Measure`, `Stream`, `ResetFaults`).
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
}

/// Unsolicited telemetry (device → host).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Telemetry {
    /// 0: a streamed estimate.
    Estimate(Estimate),
    /// 1: the ramps have settled.
    RampDone,
    /// 2: a fault was latched (bits of [`crate::board::device::faults`]).
    Fault(u32),
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
    /// 4: frame longer than [`MAX_FRAME`].
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
            DeviceError::Model(_) => WireError::Model,
            DeviceError::Estimate(EstimateError::NoNormalForce) => WireError::NoNormalForce,
            DeviceError::Estimate(_) => WireError::NotReady,
        }
    }
}

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The output buffer (or [`MAX_FRAME`]) is too small.
    TooLarge,
}

/// Encodes a frame into `out` (COBS, CRC, trailing zero); returns the bytes used.
///
/// # Errors
/// [`EncodeError::TooLarge`] if it does not fit in `out` or in [`MAX_FRAME`].
pub fn encode<'a>(frame: &Frame, out: &'a mut [u8]) -> Result<&'a mut [u8], EncodeError> {
    use postcard::ser_flavors::{crc::CrcModifier, Cobs, Slice};
    let n = out.len().min(MAX_FRAME);
    let cobs = Cobs::try_new(Slice::new(&mut out[..n])).map_err(|_| EncodeError::TooLarge)?;
    postcard::serialize_with_flavor(frame, CrcModifier::new(cobs, CRC.digest()))
        .map_err(|_| EncodeError::TooLarge)
}

/// Decodes one frame from its bytes *without* the delimiter (decoded in place).
///
/// Returns the frame, or the error to report and — when the header could be
/// read — the sequence number to echo.
///
/// # Errors
/// `Malformed`, `BadCrc`, `VersionMismatch`, `UnknownMessage`.
pub fn decode(bytes: &mut [u8]) -> Result<Frame, (WireError, Option<u32>)> {
    let n = cobs::decode_in_place(bytes).map_err(|_| (WireError::Malformed, None))?;
    let raw = &bytes[..n];
    if raw.len() < 4 {
        return Err((WireError::Malformed, None));
    }
    let (payload, crc) = raw.split_at(raw.len() - 4);
    let want = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
    if CRC.checksum(payload) != want {
        return Err((WireError::BadCrc, None));
    }
    // Header first, so a version mismatch or unknown body is reported with its seq.
    let (version, rest): (u16, &[u8]) =
        postcard::take_from_bytes(payload).map_err(|_| (WireError::Malformed, None))?;
    let (seq, rest): (u32, &[u8]) =
        postcard::take_from_bytes(rest).map_err(|_| (WireError::Malformed, None))?;
    if version != PROTOCOL_VERSION {
        return Err((
            WireError::VersionMismatch {
                device: PROTOCOL_VERSION,
            },
            Some(seq),
        ));
    }
    // Variant indices: Body (3 variants), then Request (REQUEST_VARIANTS).
    let (body, rest): (u32, &[u8]) =
        postcard::take_from_bytes(rest).map_err(|_| (WireError::Malformed, Some(seq)))?;
    if body > 2 {
        return Err((WireError::UnknownMessage, Some(seq)));
    }
    if body == 0 {
        let (r, _): (u32, &[u8]) =
            postcard::take_from_bytes(rest).map_err(|_| (WireError::Malformed, Some(seq)))?;
        if r >= REQUEST_VARIANTS {
            return Err((WireError::UnknownMessage, Some(seq)));
        }
    }
    match postcard::from_bytes::<Frame>(payload) {
        Ok(f) => Ok(f),
        Err(postcard::Error::DeserializeBadEnum) => Err((WireError::UnknownMessage, Some(seq))),
        Err(_) => Err((WireError::Malformed, Some(seq))),
    }
}

/// Splits a byte stream into frames at the zero delimiters, with a fixed
/// buffer of [`MAX_FRAME`] bytes. Garbage and oversize frames are dropped up to
/// the next delimiter and reported once.
#[derive(Debug, Clone)]
pub struct Deframer {
    buf: [u8; MAX_FRAME],
    len: usize,
    overflow: bool,
}

/// What one byte completed.
#[derive(Debug, PartialEq)]
pub enum Deframed<'a> {
    /// Nothing yet.
    Pending,
    /// A frame's bytes (without the delimiter), ready for [`decode`].
    Frame(&'a mut [u8]),
    /// A frame longer than [`MAX_FRAME`] was dropped.
    Oversize,
}

impl Default for Deframer {
    fn default() -> Self {
        Deframer {
            buf: [0; MAX_FRAME],
            len: 0,
            overflow: false,
        }
    }
}

impl Deframer {
    /// Feeds one byte.
    pub fn push(&mut self, b: u8) -> Deframed<'_> {
        if b == 0 {
            let (len, over) = (self.len, self.overflow);
            self.len = 0;
            self.overflow = false;
            if over {
                return Deframed::Oversize;
            }
            if len == 0 {
                return Deframed::Pending;
            }
            return Deframed::Frame(&mut self.buf[..len]);
        }
        // Room for the delimiter counts towards MAX_FRAME.
        if self.len + 1 >= MAX_FRAME {
            self.overflow = true;
        } else if !self.overflow {
            self.buf[self.len] = b;
            self.len += 1;
        }
        Deframed::Pending
    }
}
