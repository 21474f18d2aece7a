//! Framing: a frame on the wire is `COBS( postcard(Frame) ‖ CRC-32 ) 0x00`.
//! The [`Frame`] is serialised with postcard, the CRC-32 (ISO-HDLC: polynomial
//! 0x04C11DB7 reflected, init 0xFFFFFFFF, final xor 0xFFFFFFFF — the zlib/PNG
//! CRC) of those bytes is appended little-endian, the whole is COBS-encoded and
//! terminated by one zero byte. At most [`MAX_FRAME`] bytes per frame on the
//! wire, including the delimiter; both ends drop longer frames.
//!
//! **Errors are values** ([`WireError`], after postcard-rpc's set): a frame that
//! is not valid COBS or not valid postcard → `Malformed`; CRC mismatch →
//! `BadCrc`; an unknown body or request variant → `UnknownMessage`; another
//! protocol version → `VersionMismatch`; a frame over [`MAX_FRAME`] →
//! `Oversize`. The receiver resynchronises at the next delimiter.

use core::fmt;

use crate::board::protocol::messages::{Frame, WireError, BODY_KINDS, ENDPOINTS, PROTOCOL_VERSION};

/// Largest frame on the wire (COBS-encoded, with CRC and delimiter), bytes.
pub const MAX_FRAME: usize = 256;

/// The CRC of the frames (CRC-32/ISO-HDLC).
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The output buffer (or [`MAX_FRAME`]) is too small.
    TooLarge,
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EncodeError::TooLarge => write!(f, "frame does not fit in {MAX_FRAME} bytes"),
        }
    }
}

impl core::error::Error for EncodeError {}

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
    // Variant indices: the body's, then a request's (counted by the tables).
    let (body, rest): (u32, &[u8]) =
        postcard::take_from_bytes(rest).map_err(|_| (WireError::Malformed, Some(seq)))?;
    if body as usize >= BODY_KINDS.len() {
        return Err((WireError::UnknownMessage, Some(seq)));
    }
    if body == 0 {
        let (r, _): (u32, &[u8]) =
            postcard::take_from_bytes(rest).map_err(|_| (WireError::Malformed, Some(seq)))?;
        if r as usize >= ENDPOINTS.len() {
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
