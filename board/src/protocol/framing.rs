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

use crate::protocol::messages::{Frame, WireError, BODY_KINDS, ENDPOINTS, PROTOCOL_VERSION};

/// Largest frame on the wire (COBS-encoded, with CRC and delimiter), bytes.
pub const MAX_FRAME: usize = 256;

/// The CRC of the frames (CRC-32/ISO-HDLC) with a 256-entry table (1 KB of
/// the firmware's flash): one look-up per byte. Bitwise (no table) it took
/// ≈ 40 instructions per byte, and a μ-loop update's telemetry frame cost
/// the main loop ≈ 4 700 instructions, 22 % of a half-buffer (issue 35,
/// `predict_cost`'s worst half-buffer).
pub const CRC: crc::Crc<u32, crc::Table<1>> =
    crc::Crc::<u32, crc::Table<1>>::new(&crc::CRC_32_ISO_HDLC);

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
/// In three passes over a buffer on the stack — postcard into it, the CRC
/// over it in one call, COBS from it into `out` — not byte by byte through
/// chained flavors (issue 35: each byte through the CRC's `update` and the
/// COBS flavor cost ≈ 30 instructions on the M4, a μ-loop telemetry frame
/// ≈ 2 000 of the main loop's time).
///
/// # Errors
/// [`EncodeError::TooLarge`] if it does not fit in `out` or in [`MAX_FRAME`].
pub fn encode<'a>(frame: &Frame, out: &'a mut [u8]) -> Result<&'a mut [u8], EncodeError> {
    let n = out.len().min(MAX_FRAME);
    // COBS adds at least one byte and the delimiter one more: a raw frame
    // (with its 4-byte CRC) of more than MAX_FRAME − 2 bytes cannot fit.
    let mut raw = [0u8; MAX_FRAME];
    let len = postcard::to_slice(frame, &mut raw[..MAX_FRAME - 6])
        .map_err(|_| EncodeError::TooLarge)?
        .len();
    let crc = CRC.checksum(&raw[..len]);
    raw[len..len + 4].copy_from_slice(&crc.to_le_bytes());
    let body = n.checked_sub(1).ok_or(EncodeError::TooLarge)?;
    let k =
        cobs::try_encode(&raw[..len + 4], &mut out[..body]).map_err(|_| EncodeError::TooLarge)?;
    out[k] = 0;
    Ok(&mut out[..=k])
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
        return Err((WireError::Malformed, header(raw).map(|h| h.1)));
    }
    let (payload, crc) = raw.split_at(raw.len() - 4);
    let want = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
    if CRC.checksum(payload) != want {
        // The header may itself be corrupt, but echoing it lets the host match
        // the error to its request instead of timing out.
        return Err((WireError::BadCrc, header(payload).map(|h| h.1)));
    }
    // Header first, so a version mismatch or unknown body is reported with its seq.
    let (version, seq, rest) = header(payload).ok_or((WireError::Malformed, None))?;
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

/// The header of a payload: `version` (varint u16), `seq` (varint u32) and
/// the bytes after them, if both varints are complete.
fn header(payload: &[u8]) -> Option<(u16, u32, &[u8])> {
    let (version, rest): (u16, &[u8]) = postcard::take_from_bytes(payload).ok()?;
    let (seq, rest): (u32, &[u8]) = postcard::take_from_bytes(rest).ok()?;
    Some((version, seq, rest))
}

/// The `seq` of a COBS-encoded frame's first bytes (an oversize frame keeps
/// only its start): COBS is undone block by block for the first 8 payload
/// bytes (a version and a seq varint take at most 3 + 5).
pub fn peek_seq(cobs: &[u8]) -> Option<u32> {
    let mut raw = [0u8; 8];
    let (mut n, mut i) = (0, 0);
    while n < raw.len() && i < cobs.len() {
        let code = usize::from(cobs[i]);
        if code == 0 {
            return None;
        }
        i += 1;
        for _ in 1..code {
            if i >= cobs.len() || n >= raw.len() {
                break;
            }
            raw[n] = cobs[i];
            n += 1;
            i += 1;
        }
        // A block shorter than 0xFF stands for its data and one zero.
        if code != 0xFF && n < raw.len() && i < cobs.len() {
            raw[n] = 0;
            n += 1;
        }
    }
    header(&raw[..n]).map(|h| h.1)
}

/// Largest gap between two bytes of one frame, µs: a frame whose bytes arrive
/// further apart is dropped (its start is discarded when the late byte comes;
/// the rest is then a frame of its own and is answered `Malformed` or
/// `BadCrc`). At 115 200 Bd a whole 256-byte frame takes 22 ms.
pub const BYTE_TIMEOUT_US: u32 = 100_000;

/// Splits a byte stream into frames at the zero delimiters, with a fixed
/// buffer of [`MAX_FRAME`] bytes. Garbage and oversize frames are dropped up to
/// the next delimiter and reported once; a frame whose bytes arrive more than
/// [`BYTE_TIMEOUT_US`] apart is dropped.
#[derive(Debug, Clone)]
pub struct Deframer {
    buf: [u8; MAX_FRAME],
    len: usize,
    overflow: bool,
    last_us: u32,
}

/// What one byte completed.
#[derive(Debug, PartialEq)]
pub enum Deframed<'a> {
    /// Nothing yet.
    Pending,
    /// A frame's bytes (without the delimiter), ready for [`decode`].
    Frame(&'a mut [u8]),
    /// A frame longer than [`MAX_FRAME`] was dropped; `seq` if its first
    /// bytes held a readable header ([`peek_seq`]).
    Oversize {
        /// The dropped frame's sequence number, if readable.
        seq: Option<u32>,
    },
}

impl Default for Deframer {
    fn default() -> Self {
        Deframer {
            buf: [0; MAX_FRAME],
            len: 0,
            overflow: false,
            last_us: 0,
        }
    }
}

impl Deframer {
    /// Feeds one byte received at time `now_us` (µs, any origin, wrapping).
    pub fn push(&mut self, b: u8, now_us: u32) -> Deframed<'_> {
        let gap = now_us.wrapping_sub(self.last_us);
        self.last_us = now_us;
        if gap > BYTE_TIMEOUT_US {
            // A stale partial frame: drop it.
            self.len = 0;
            self.overflow = false;
        }
        if b == 0 {
            let (len, over) = (self.len, self.overflow);
            self.len = 0;
            self.overflow = false;
            if over {
                return Deframed::Oversize {
                    seq: peek_seq(&self.buf[..len]),
                };
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

#[cfg(test)]
mod tests {
    use super::*;

    /// COBS of `02 07 00 0b` (version 2, seq 7, Request, GetStatus) and a CRC.
    const FRAME: [u8; 9] = [0x03, 0x02, 0x07, 0x06, 0x0b, 0x11, 0x22, 0x33, 0x44];

    #[test]
    fn a_frame_split_beyond_the_byte_timeout_is_dropped() {
        let mut d = Deframer::default();
        for &b in &FRAME[..4] {
            assert_eq!(d.push(b, 1_000), Deframed::Pending);
        }
        // The rest arrives 100 ms + 1 µs later: only the rest is a frame.
        for &b in &FRAME[4..] {
            assert_eq!(d.push(b, 1_000 + BYTE_TIMEOUT_US + 1), Deframed::Pending);
        }
        match d.push(0, 1_000 + BYTE_TIMEOUT_US + 1) {
            Deframed::Frame(f) => assert_eq!(f, &FRAME[4..]),
            other => panic!("{other:?}"),
        }
        // Exactly at the timeout the frame is kept whole (the limit is inclusive).
        for &b in &FRAME[..4] {
            d.push(b, 0);
        }
        for &b in &FRAME[4..] {
            d.push(b, BYTE_TIMEOUT_US);
        }
        match d.push(0, BYTE_TIMEOUT_US) {
            Deframed::Frame(f) => assert_eq!(f, &FRAME[..]),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn peek_seq_reads_the_header_of_a_cut_frame() {
        assert_eq!(peek_seq(&FRAME[..3]), Some(7));
        // seq 300 = ac 02 (varint): COBS 04 02 ac 02 …
        assert_eq!(peek_seq(&[0x04, 0x02, 0xac, 0x02, 0x01]), Some(300));
        // A seq varint cut off: unreadable.
        assert_eq!(peek_seq(&[0x03, 0x02, 0xac]), None);
    }
}
