//! Request frames built by hand from `docs/protocol.md` — a bitwise
//! CRC-32/ISO-HDLC, a byte-by-byte COBS encoder and postcard varints — with
//! nothing from model-core's encoder, so that tests of the device's decoder
//! do not run the code they check.

/// Protocol version written into every hand-built frame ("Frame" table of
/// docs/protocol.md). A version bump is this one line.
pub const VERSION: u16 = 8;
/// `Body::Request` (variant index).
pub const BODY_REQUEST: u8 = 0;
/// `Request::GetDrive` (variant index, "Requests" table).
pub const GET_DRIVE: u8 = 1;
/// `Request::GetStatus` (variant index, "Requests" table).
pub const GET_STATUS: u8 = 11;

/// CRC-32/ISO-HDLC, bit by bit: reflected polynomial 0xEDB88320, init and
/// final xor 0xFFFFFFFF (check value of `"123456789"`: 0xCBF43926).
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Appends the postcard varint of `v`: 7 bits per byte, least significant
/// group first, high bit = more follows.
pub fn varint(mut v: u32, out: &mut Vec<u8>) {
    loop {
        let low = (v & 0x7F) as u8;
        v >>= 7;
        if v == 0 {
            out.push(low);
            return;
        }
        out.push(low | 0x80);
    }
}

/// COBS: each block = (length + 1) then up to 254 non-zero bytes; a block
/// shorter than 254 stands for a following zero (dropped at the very end).
pub fn cobs(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + data.len() / 254 + 2);
    let mut block: Vec<u8> = Vec::new();
    for &b in data {
        if b == 0 {
            out.push(block.len() as u8 + 1);
            out.append(&mut block);
        } else {
            block.push(b);
            if block.len() == 254 {
                out.push(0xFF);
                out.append(&mut block);
            }
        }
    }
    out.push(block.len() as u8 + 1);
    out.extend(block);
    out
}

/// The wire bytes of a payload: `COBS(payload ‖ CRC little-endian) 0x00`.
pub fn frame(payload: &[u8]) -> Vec<u8> {
    let mut v = payload.to_vec();
    v.extend(crc32(payload).to_le_bytes());
    let mut w = cobs(&v);
    w.push(0);
    w
}

/// A request without fields (`variant` = its index in the "Requests" table)
/// of protocol [`VERSION`] with sequence number `seq`.
pub fn request(seq: u32, variant: u8) -> Vec<u8> {
    let mut p = Vec::new();
    varint(u32::from(VERSION), &mut p);
    varint(seq, &mut p);
    p.push(BODY_REQUEST);
    p.push(variant);
    frame(&p)
}

/// `GetStatus` with sequence number `seq`.
pub fn get_status(seq: u32) -> Vec<u8> {
    request(seq, GET_STATUS)
}
