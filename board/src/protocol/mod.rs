//! The device link's wire protocol, defined once for the firmware and the host
//! (`docs/protocol.md` is the full specification for other languages).
//!
//! * [`messages`] — what travels: the frame, requests, responses, telemetry,
//!   errors and the structures they carry, plus the request → response table
//!   [`ENDPOINTS`];
//! * [`framing`] — how it travels: postcard, CRC-32, COBS, the zero delimiter,
//!   and the receiver's [`Deframer`].
//!
//! **Dependencies.** Nothing here knows the device logic; the device
//! ([`crate::device`]) and the server ([`crate::server`]) use
//! these types.

pub mod framing;
pub mod messages;

pub use framing::*;
pub use messages::*;
