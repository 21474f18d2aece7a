//! The wire protocol and the device-side server: round trips, garbage,
//! corrupted CRC, oversize and cut-off frames, unknown messages, version
//! mismatch, and refused commands that change nothing.

use board::dds::SineTable;
use board::device::{Contact, Device, DeviceConfig, DriveSetting};
use board::protocol::{
    decode, encode, self_test, Body, Deframed, Deframer, Frame, Info, Request, Response, SelfTest,
    WireError, CRC, MAX_FRAME, PROTOCOL_VERSION,
};
use board::server::Server;

/// The protocol version byte of the hand-built frames (docs/protocol.md, "Frame").
const V: u8 = 8;

fn cfg() -> DeviceConfig {
    integration_tests::board_config_1mhz()
}

fn info() -> Info {
    let mut board = [0u8; 16];
    board[..7].copy_from_slice(b"virtual");
    Info {
        firmware: [0, 1, 0],
        protocol: PROTOCOL_VERSION,
        board,
        sample_rate_hz: 1e6,
        freq_range_hz: (1e3, 1e5),
        max_amp_x_m: 2e-6,
        max_offset_z_m: 8e-6,
        liftoff_margin: 0.05,
        max_phase_rad: 1e3,
        max_velocity_m_s: 1e3,
        periods_range: (1, 1_000_000),
        byte_timeout_us: 100_000,
        retract_z_m: 0.0,
        self_test: SelfTest::NOT_RUN,
    }
}

fn req(seq: u32, r: Request) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    encode(
        &Frame {
            version: PROTOCOL_VERSION,
            seq,
            body: Body::Request(r),
        },
        &mut out,
    )
    .unwrap()
    .to_vec()
}

/// Sends bytes to a server, returns the decoded replies.
fn talk(server: &mut Server, dev: &mut Device<'_, 256>, bytes: &[u8]) -> Vec<Frame> {
    talk_at(server, dev, bytes, 0)
}

/// Sends bytes arriving at `now_us` to a server, returns the decoded replies.
fn talk_at(
    server: &mut Server,
    dev: &mut Device<'_, 256>,
    bytes: &[u8],
    now_us: u32,
) -> Vec<Frame> {
    let mut replies = Vec::new();
    let mut df = Deframer::default();
    server.receive(dev, bytes, now_us, |out| {
        for &b in out {
            if let Deframed::Frame(f) = df.push(b, 0) {
                replies.push(decode(f).unwrap());
            }
        }
    });
    replies
}

fn resp(f: &Frame) -> Response {
    match f.body {
        Body::Response(r) => r,
        other => panic!("{other:?}"),
    }
}

#[test]
fn roundtrip_every_request() {
    let reqs = [
        Request::Hello,
        Request::GetDrive,
        Request::SetDrive(DriveSetting {
            freq_hz: 40e3,
            amp_z_m: 1e-6,
            amp_x_m: 2e-7,
            offset_z_m: 3e-6,
            phase_rad: -1.0,
        }),
        Request::Start,
        Request::Stop,
        Request::GetContact,
        Request::SetContact(Contact {
            mu0: 0.3,
            kz: 1e7,
            kx: 2e7,
        }),
        Request::Predict { v0: -0.01 },
        Request::Measure { periods: 100 },
        Request::GetEstimate,
        Request::Stream {
            on: true,
            periods: 50,
        },
        Request::GetStatus,
        Request::ResetFaults,
        Request::Reset,
        Request::SetLiftOff { allow: true },
        Request::SetControl(board::protocol::ControlSetting {
            on: true,
            target_mu: 0.1,
            v0_m_s: 0.004,
            gain: 0.7,
            periods: 4,
            rate_m_per_s: 1e-3,
        }),
        Request::GetControl,
        Request::SetTransducers(Some(board::protocol::Transducers {
            z: board::protocol::TransducerModel {
                resonance_hz: 40e3,
                q: 10.0,
                gain_m_per_v: 1e-6,
                phase_lag_rad: 0.1,
            },
            x: board::protocol::TransducerModel {
                resonance_hz: 30e3,
                q: 20.0,
                gain_m_per_v: 5e-7,
                phase_lag_rad: -0.2,
            },
        })),
        Request::GetTransducers,
        Request::SetDriveMode(board::protocol::DriveMode::Displacement),
        Request::SetDisplacementOptions(board::protocol::DisplacementOptions {
            track: board::protocol::Track::X,
            headroom: 3.5,
        }),
    ];
    assert_eq!(reqs.len() as u32, board::protocol::ENDPOINTS.len() as u32);
    for (i, r) in reqs.into_iter().enumerate() {
        let mut bytes = req(i as u32 + 7, r);
        assert_eq!(*bytes.last().unwrap(), 0);
        assert!(
            !bytes[..bytes.len() - 1].contains(&0),
            "COBS leaves no zero inside"
        );
        let n = bytes.len() - 1;
        let f = decode(&mut bytes[..n]).unwrap();
        assert_eq!(
            f,
            Frame {
                version: PROTOCOL_VERSION,
                seq: i as u32 + 7,
                body: Body::Request(r)
            }
        );
    }
    // The CRC is the standard CRC-32 (check value of "123456789").
    assert_eq!(CRC.checksum(b"123456789"), 0xCBF4_3926);
}

/// The device of these tests: board configuration, μ0 = 0.3, k_z = k_x = 1e7 N/m.
fn test_device(t: &SineTable<256>) -> Device<'_, 256> {
    Device::new(
        cfg(),
        t,
        Contact {
            mu0: 0.3,
            kz: 1e7,
            kx: 1e7,
        },
    )
    .unwrap()
}

/// A drive well inside the limits (no lift-off: 1 µm < 3 µm).
fn good_drive() -> DriveSetting {
    DriveSetting {
        freq_hz: 40e3,
        amp_z_m: 1e-6,
        amp_x_m: 2e-7,
        offset_z_m: 3e-6,
        phase_rad: 0.5,
    }
}

#[test]
fn server_answers_and_survives_bad_input() {
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    // Garbage before a frame: ignored up to the delimiter, then the frame is answered.
    let mut bytes = vec![0x13, 0x37, 0xFF, 0x00];
    bytes.extend(req(1, Request::Hello));
    let r = talk(&mut s, &mut dev, &bytes);
    assert_eq!(r.len(), 2);
    assert_eq!(resp(&r[0]), Response::Error(WireError::Malformed));
    assert_eq!(r[1].seq, 1);
    assert!(matches!(resp(&r[1]), Response::Info(i) if i.protocol == PROTOCOL_VERSION));
    // Corrupted CRC: flip a payload bit (keeping COBS valid).
    let mut b = req(2, Request::GetStatus);
    let k = b.len() - 3;
    b[k] ^= 0x01;
    if b[k] == 0 {
        b[k] = 0x02;
    }
    let r = talk(&mut s, &mut dev, &b);
    assert_eq!(resp(&r[0]), Response::Error(WireError::BadCrc));
    // A frame cut off mid-way, then a good one: the cut frame merges with the
    // next bytes up to the delimiter and is rejected; the one after is answered.
    let good = req(3, Request::GetStatus);
    let mut b = good[..good.len() / 2].to_vec();
    b.extend(&good);
    b.extend(req(4, Request::GetContact));
    let r = talk(&mut s, &mut dev, &b);
    assert_eq!(r.len(), 2);
    assert!(matches!(
        resp(&r[0]),
        Response::Error(WireError::Malformed | WireError::BadCrc)
    ));
    assert_eq!(r[1].seq, 4);
    assert!(matches!(resp(&r[1]), Response::Contact(_)));
    // Oversize frame.
    let mut b = vec![0x55u8; 600];
    b.push(0);
    let r = talk(&mut s, &mut dev, &b);
    assert_eq!(resp(&r[0]), Response::Error(WireError::Oversize));
    // Unknown request variant (index 99) with a valid CRC.
    let raw = [PROTOCOL_VERSION as u8, 9, 0, 99];
    let r = talk(&mut s, &mut dev, &frame_of_raw(&raw));
    assert_eq!(r[0].seq, 9);
    assert_eq!(resp(&r[0]), Response::Error(WireError::UnknownMessage));
    // Version mismatch.
    let raw = [PROTOCOL_VERSION as u8 + 1, 10, 0, 0];
    let r = talk(&mut s, &mut dev, &frame_of_raw(&raw));
    assert_eq!(r[0].seq, 10);
    assert_eq!(
        resp(&r[0]),
        Response::Error(WireError::VersionMismatch {
            device: PROTOCOL_VERSION
        })
    );
}

fn frame_of_raw(raw: &[u8]) -> Vec<u8> {
    let mut v = raw.to_vec();
    v.extend(CRC.checksum(raw).to_le_bytes());
    let mut out = vec![0u8; v.len() + 2];
    let n = cobs::encode(&v, &mut out);
    out.truncate(n);
    out.push(0);
    out
}

#[test]
fn refused_commands_change_nothing_over_the_wire() {
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    let good = good_drive();
    let r = talk(&mut s, &mut dev, &req(1, Request::SetDrive(good)));
    assert!(matches!(resp(&r[0]), Response::Drive { .. }));
    talk(&mut s, &mut dev, &req(2, Request::Start));
    let before = talk(&mut s, &mut dev, &req(3, Request::GetDrive));
    let lift = DriveSetting {
        amp_z_m: 2.9e-6,
        ..good
    };
    let r = talk(&mut s, &mut dev, &req(4, Request::SetDrive(lift)));
    match resp(&r[0]) {
        Response::Error(WireError::LiftOffRefused { limit_m, .. }) => {
            assert!((limit_m - 2.85e-6).abs() < 1e-12)
        }
        other => panic!("{other:?}"),
    }
    let r = talk(
        &mut s,
        &mut dev,
        &req(
            5,
            Request::SetDrive(DriveSetting {
                freq_hz: 1e7,
                ..good
            }),
        ),
    );
    assert!(matches!(
        resp(&r[0]),
        Response::Error(WireError::OutOfRange { .. })
    ));
    let after = talk(&mut s, &mut dev, &req(6, Request::GetDrive));
    assert_eq!(resp(&before[0]), resp(&after[0]));
    // Prediction answers with the regime.
    let r = talk(&mut s, &mut dev, &req(7, Request::Predict { v0: 0.01 }));
    assert!(matches!(resp(&r[0]), Response::Prediction { .. }));
    // Estimate before any measurement: NotReady.
    let r = talk(&mut s, &mut dev, &req(8, Request::GetEstimate));
    assert_eq!(resp(&r[0]), Response::Error(WireError::NotReady));
}

#[test]
fn docs_protocol_examples() {
    // The annotated examples of docs/protocol.md (computed independently with
    // Python's zlib.crc32, struct.pack and a hand-written COBS encoder:
    // `python3 scripts/protocol_example.py`).
    let mut out = [0u8; MAX_FRAME];
    let req = encode(
        &Frame {
            version: 8,
            seq: 5,
            body: Body::Request(Request::GetStatus),
        },
        &mut out,
    )
    .unwrap();
    assert_eq!(
        req,
        &[0x03, 0x08, 0x05, 0x06, 0x0b, 0x90, 0xec, 0xe9, 0x75, 0x00]
    );
    let status = board::device::Status {
        running: true,
        settled: true,
        faults: 0,
        measuring: false,
        rx_overflows: 0,
        out_amp_z_m: 2e-6,
        out_amp_x_m: 3e-7,
        out_offset_z_m: 4e-6,
        liftoff_allowed: false,
        measured: Some(board::device::MeasuredDrive {
            amp_z_m: 2.2e-6,
            amp_x_m: 3.2e-7,
            phase_rad: -2.1,
            amp_z_peak_m: 3.3e-6,
            windows: 7,
            response_z_m_per_v: Some([1.5e-5, -2.5e-6]),
            response_x_m_per_v: None,
        }),
        mode: board::protocol::DriveMode::Displacement,
        frequency_hz: 20_100.0,
        options: board::device::DisplacementOptions {
            track: board::device::Track::Z,
            headroom: 2.0,
        },
        tracking_error_hz: Some(-0.5),
        locked: true,
        cpu_load_pct: Some(12.5),
        cpu_load_max_pct: Some(28.75),
    };
    let mut out = [0u8; MAX_FRAME];
    let resp = encode(
        &Frame {
            version: 8,
            seq: 5,
            body: Body::Response(Response::Status(status)),
        },
        &mut out,
    )
    .unwrap();
    assert_eq!(
        resp,
        &[
            0x07, 0x08, 0x05, 0x01, 0x06, 0x01, 0x01, 0x01, 0x01, 0x0d, 0xbd, 0x37, 0x06, 0x36,
            0xb0, 0x0f, 0xa1, 0x34, 0xbd, 0x37, 0x86, 0x36, 0x1c, 0x01, 0xb6, 0xa3, 0x13, 0x36,
            0x77, 0xcc, 0xab, 0x34, 0x66, 0x66, 0x06, 0xc0, 0x91, 0x75, 0x5d, 0x36, 0x07, 0x01,
            0x82, 0xa8, 0x7b, 0x37, 0xac, 0xc5, 0x27, 0xb6, 0x02, 0x01, 0x05, 0x08, 0x9d, 0x46,
            0x01, 0x01, 0x01, 0x03, 0x40, 0x01, 0x01, 0x01, 0x04, 0xbf, 0x01, 0x01, 0x01, 0x04,
            0x48, 0x41, 0x01, 0x01, 0x07, 0xe6, 0x41, 0x79, 0x38, 0xaf, 0xfa, 0x00
        ]
    );
    // v7, "Power-up self-test": the SelfTest bytes of the example there.
    let t = SelfTest {
        ran: self_test::ALL,
        failed: self_test::HSE_FREQUENCY | self_test::STREAMS_RUNNING,
        hse_hz: 12_000_000,
        sysclk_hz: 168_000_000,
    };
    let mut out = [0u8; MAX_FRAME];
    let w = encode(
        &Frame {
            version: 8,
            seq: 5,
            body: Body::Response(Response::Info(info().with_self_test(t))),
        },
        &mut out,
    )
    .unwrap();
    // The last field of Info, just before the CRC.
    let p = uncobs_by_hand(&w[..w.len() - 1]);
    assert_eq!(
        p[p.len() - 14..p.len() - 4],
        [0x3f, 0x22, 0x80, 0xb6, 0xdc, 0x05, 0x80, 0xf4, 0x8d, 0x50]
    );
}

#[test]
fn telemetry_reports_ramps_and_faults_with_its_own_counter() {
    use board::protocol::Telemetry;
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    let good = good_drive();
    talk(&mut s, &mut dev, &req(1, Request::SetDrive(good)));
    talk(&mut s, &mut dev, &req(2, Request::Start));
    let mut tele = Vec::new();
    let mut df = Deframer::default();
    let mut collect = |s: &mut Server, dev: &mut Device<'_, 256>| {
        s.poll(dev, |out| {
            for &b in out {
                if let Deframed::Frame(f) = df.push(b, 0) {
                    let f = decode(f).unwrap();
                    if let Body::Telemetry(t) = f.body {
                        tele.push((f.seq, t));
                    }
                }
            }
        });
    };
    collect(&mut s, &mut dev);
    // Phase ramps at 1e-4 rad/sample to 0.5 + π/2 rad: ≈ 20 700 samples.
    let mut buf = [0u32; 512];
    for _ in 0..60 {
        dev.fill_dac(0, &mut buf);
        collect(&mut s, &mut dev);
    }
    dev.fault(board::device::faults::EXTERNAL);
    collect(&mut s, &mut dev);
    assert_eq!(tele.len(), 2, "{tele:?}");
    assert_eq!(tele[0].1, Telemetry::RampDone);
    assert_eq!(tele[1].1, Telemetry::Fault(board::device::faults::EXTERNAL));
    assert_eq!(tele[1].0, tele[0].0 + 1);
}

#[test]
fn receive_overflow_is_announced_once_per_growth() {
    // Dropped receive bytes are announced once per growth of the count, with
    // the new total (never a silent drop).
    use board::protocol::Telemetry;
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    let mut df = Deframer::default();
    let mut tele = Vec::new();
    for grow in [3u32, 0, 2] {
        dev.count_rx_overflow(grow);
        s.poll(&mut dev, |out| {
            for &b in out {
                if let Deframed::Frame(f) = df.push(b, 0) {
                    if let Body::Telemetry(t) = decode(f).unwrap().body {
                        tele.push(t);
                    }
                }
            }
        });
    }
    assert_eq!(tele, [Telemetry::RxOverflow(3), Telemetry::RxOverflow(5)]);
}

// ---------------------------------------------------------------------------
// The protocol (v5), with frames built by hand from docs/protocol.md's tables
// and an independent CRC-32 (bitwise) and COBS (written here), so a spec error
// shows.

/// CRC-32/ISO-HDLC, bit by bit (reflected polynomial 0xEDB88320).
fn crc32_by_hand(data: &[u8]) -> u32 {
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

/// COBS encoding, by hand (blocks of at most 254 data bytes).
fn cobs_by_hand(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut block = Vec::new();
    for &b in data {
        if b == 0 {
            out.push(block.len() as u8 + 1);
            out.append(&mut block);
        } else {
            block.push(b);
            if block.len() == 254 {
                out.push(255);
                out.append(&mut block);
            }
        }
    }
    out.push(block.len() as u8 + 1);
    out.extend(block);
    out
}

/// COBS decoding, by hand.
fn uncobs_by_hand(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < data.len() {
        let code = data[i] as usize;
        out.extend(&data[i + 1..i + code]);
        i += code;
        if code != 255 && i < data.len() {
            out.push(0);
        }
    }
    out
}

/// The wire bytes of a payload: COBS(payload ‖ CRC LE) 00.
fn wire(payload: &[u8]) -> Vec<u8> {
    let mut v = payload.to_vec();
    v.extend(crc32_by_hand(payload).to_le_bytes());
    let mut w = cobs_by_hand(&v);
    w.push(0);
    w
}

/// The payloads of the frames in `bytes` (CRC checked by hand).
fn payloads(bytes: &[u8]) -> Vec<Vec<u8>> {
    bytes
        .split(|&b| b == 0)
        .filter(|f| !f.is_empty())
        .map(|f| {
            let raw = uncobs_by_hand(f);
            let (p, crc) = raw.split_at(raw.len() - 4);
            assert_eq!(crc32_by_hand(p).to_le_bytes(), crc, "CRC of {raw:02x?}");
            p.to_vec()
        })
        .collect()
}

/// Sends bytes at `now_us`; returns the payloads of every frame sent back
/// (responses and the telemetry sent with them).
fn exchange(s: &mut Server, dev: &mut Device<'_, 256>, bytes: &[u8], now_us: u32) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    s.receive(dev, bytes, now_us, |b| out.extend_from_slice(b));
    payloads(&out)
}

/// The one payload answering a request payload.
fn ask(s: &mut Server, dev: &mut Device<'_, 256>, payload: &[u8]) -> Vec<u8> {
    let mut r = exchange(s, dev, &wire(payload), 0);
    assert_eq!(r.len(), 1, "{r:02x?}");
    r.remove(0)
}

/// Telemetry payloads produced by one `poll`.
fn polled(s: &mut Server, dev: &mut Device<'_, 256>) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    s.poll(dev, |b| out.extend_from_slice(b));
    payloads(&out)
}

/// A `SetDrive` payload: `DriveSetting` is f64 freq, f32 amp_z, amp_x, offset_z, phase.
fn set_drive_payload(seq: u8, freq: f64, amp_z: f32, amp_x: f32, off: f32, phase: f32) -> Vec<u8> {
    let mut p = vec![V, seq, 0, 2];
    p.extend(freq.to_le_bytes());
    for x in [amp_z, amp_x, off, phase] {
        p.extend(x.to_le_bytes());
    }
    p
}

fn cat(parts: &[&[u8]]) -> Vec<u8> {
    parts.concat()
}

#[test]
fn hand_built_frames_get_the_spec_answers() {
    assert_eq!(crc32_by_hand(b"123456789"), 0xCBF4_3926);
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(Info::for_config(&cfg(), "virtual", [0, 1, 0]));
    // A version-1 Hello: Error(VersionMismatch{device: V}) with its seq.
    assert_eq!(ask(&mut s, &mut dev, &[1, 5, 0, 0]), [V, 5, 1, 7, 3, V]);
    // Unknown request index 99: Error(UnknownMessage) with its seq.
    assert_eq!(ask(&mut s, &mut dev, &[V, 10, 0, 99]), [V, 10, 1, 7, 2]);
    // Bad CRC on GetStatus seq 7: Error(BadCrc) echoing seq 7.
    let mut w = wire(&[V, 7, 0, 11]);
    let k = w.len() - 2; // a CRC byte (non-zero after the change below)
    w[k] = if w[k] == 0x55 { 0x56 } else { 0x55 };
    assert_eq!(exchange(&mut s, &mut dev, &w, 0), vec![vec![V, 7, 1, 7, 1]]);
    // Oversize (300 filler bytes) with seq 8: Error(Oversize) echoing seq 8.
    let big = cat(&[&[V, 8, 0, 11], &[0x55; 300]]);
    assert_eq!(
        exchange(&mut s, &mut dev, &wire(&big), 0),
        vec![vec![V, 8, 1, 7, 4]]
    );
    // Hello: Info with every limit, field by field from the Structures table.
    let mut board = [0u8; 16];
    board[..7].copy_from_slice(b"virtual");
    let info = cat(&[
        &[V, 11, 1, 0], // version, seq, Response, Info
        &[0, 1, 0],     // firmware
        &[V],           // protocol
        &board,
        &1e6f64.to_le_bytes(),
        &1e3f64.to_le_bytes(),
        &1e5f64.to_le_bytes(),
        // max_amp_x_m = min(2048, 4095 − 2048)·1 nm; max_offset_z_m = 4095·2 nm (f32).
        &(2047.0f32 * 1e-9f32).to_le_bytes(),
        &(4095.0f32 * 2e-9f32).to_le_bytes(),
        &0.05f32.to_le_bytes(),
        &1000f32.to_le_bytes(), // max_phase_rad
        &1000f32.to_le_bytes(), // max_velocity_m_s
        &[1],                   // periods_range.0
        &[0xc0, 0x84, 0x3d],    // periods_range.1 = 1 000 000
        &[0xa0, 0x8d, 0x06],    // byte_timeout_us = 100 000
        &0f32.to_le_bytes(),    // retract_z_m = zero_code 0 · 2 nm (v3)
        &[0, 0, 0, 0],          // self_test (v7): not run (ran, failed, hse_hz, sysclk_hz)
    ]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 11, 0, 0]), info);
    // Inter-byte timeout: GetStatus seq 9 split 300 ms apart is dropped (the
    // tail is answered with an error, never with a Status) ...
    let w = wire(&[V, 9, 0, 11]);
    assert!(exchange(&mut s, &mut dev, &w[..3], 0).is_empty());
    let r = exchange(&mut s, &mut dev, &w[3..], 300_000);
    assert_eq!(r.len(), 1);
    assert_eq!(&r[0][2..4], [1, 7], "an error: {r:02x?}");
    // ... and 50 ms apart it is answered.
    assert!(exchange(&mut s, &mut dev, &w[..3], 1_000_000).is_empty());
    let r = exchange(&mut s, &mut dev, &w[3..], 1_050_000);
    assert_eq!(&r[0][..4], [V, 9, 1, 6]);
}

/// The f32 bytes of `100·c/B` %, eq. L1 of "DSP load" in docs/protocol.md,
/// computed in f64 (exact for these integers) and rounded once to f32.
fn load_pct_bytes(c: u32, b: u32) -> [u8; 4] {
    ((f64::from(c) * 100.0 / f64::from(b)) as f32).to_le_bytes()
}

#[test]
fn status_reports_the_recorded_dsp_load_and_reset_clears_its_maximum() {
    // v8: Status ends with cpu_load_pct, cpu_load_max_pct, each Option<f32>
    // (00, or 01 and the f32 LE), after `locked`.
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    let tail = |p: &[u8], n: usize| p[p.len() - n..].to_vec();
    // Nothing recorded (as on the virtual device): both None.
    let st = ask(&mut s, &mut dev, &[V, 1, 0, 11]);
    assert_eq!(&st[..4], [V, 1, 1, 6]);
    assert_eq!(tail(&st, 2), [0, 0]);
    // The STM32F405's budget: 168 MHz · 64 samples / 500 kS/s (eq. L1).
    let b = 168_000_000 / 500_000 * 64;
    assert_eq!(b, 21_504);
    let budget = std::num::NonZeroU32::new(b).unwrap();
    // 6 452 cycles: just above 30 % (6 451.2); then a lighter half-buffer.
    dev.record_cpu_load(6_452, budget);
    dev.record_cpu_load(2_000, budget);
    let st = ask(&mut s, &mut dev, &[V, 2, 0, 11]);
    let want = cat(&[
        &[1],
        &load_pct_bytes(2_000, b),
        &[1],
        &load_pct_bytes(6_452, b),
    ]);
    assert_eq!(tail(&st, 10), want);
    let max = f32::from_le_bytes(want[6..10].try_into().unwrap());
    assert!(max > 30.0 && max < 30.01, "{max}");
    // Reset (request 13) answers Ok (response 2) and clears the maximum only.
    assert_eq!(ask(&mut s, &mut dev, &[V, 3, 0, 13]), [V, 3, 1, 2]);
    let st = ask(&mut s, &mut dev, &[V, 4, 0, 11]);
    assert_eq!(tail(&st, 6), cat(&[&[1], &load_pct_bytes(2_000, b), &[0]]));
    // The next half-buffer is the new maximum, even below the old one.
    dev.record_cpu_load(1_000, budget);
    let st = ask(&mut s, &mut dev, &[V, 5, 0, 11]);
    let one = load_pct_bytes(1_000, b);
    assert_eq!(tail(&st, 10), cat(&[&[1], &one, &[1], &one]));
    // A late half-buffer (two budgets): 200 %, reported as such.
    dev.record_cpu_load(2 * b, budget);
    let st = ask(&mut s, &mut dev, &[V, 6, 0, 11]);
    assert_eq!(tail(&st, 4), 200f32.to_le_bytes());
}

#[test]
fn drive_limits_are_inclusive_checked_in_order_and_reported_with_their_values() {
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    let drive_ok = |r: &[u8], seq: u8| assert_eq!(&r[..4], [V, seq, 1, 1], "{r:02x?}");
    // Lift-off limit L = (1 − 0.05)·4 µm in f32: accepted at L, refused just above.
    let lim = (1.0f32 - 0.05f32) * 4e-6f32;
    drive_ok(
        &ask(
            &mut s,
            &mut dev,
            &set_drive_payload(1, 2e4, lim, 0.0, 4e-6, 0.0),
        ),
        1,
    );
    let above = f32::from_bits(lim.to_bits() + 1);
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &set_drive_payload(2, 2e4, above, 0.0, 4e-6, 0.0)
        ),
        cat(&[&[V, 2, 1, 7, 6], &above.to_le_bytes(), &lim.to_le_bytes()])
    );
    // DAC headroom: offset 8 µm leaves H = 4095·2 nm − 8 µm (f32) for Δu_z.
    let h = 4095.0f32 * 2e-9f32 - 8e-6f32;
    drive_ok(
        &ask(
            &mut s,
            &mut dev,
            &set_drive_payload(3, 2e4, h, 0.0, 8e-6, 0.0),
        ),
        3,
    );
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &set_drive_payload(4, 2e4, 0.5e-6, 0.0, 8e-6, 0.0)
        ),
        cat(&[&[V, 4, 1, 7, 5, 1], &0f32.to_le_bytes(), &h.to_le_bytes()])
    );
    // Several bad values: the first check in the table's order (frequency) wins.
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &set_drive_payload(5, 5e6, -1.0, 1.0, -1.0, 1e9)
        ),
        cat(&[
            &[V, 5, 1, 7, 5, 0],
            &1e3f32.to_le_bytes(),
            &1e5f32.to_le_bytes()
        ])
    );
    // Then the offset (check 2) before the amplitudes.
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &set_drive_payload(6, 2e4, -1.0, 1.0, -1.0, 1e9)
        ),
        cat(&[
            &[V, 6, 1, 7, 5, 3],
            &0f32.to_le_bytes(),
            &(4095.0f32 * 2e-9f32).to_le_bytes()
        ])
    );
    // Phase: ±1000 rad inclusive.
    drive_ok(
        &ask(
            &mut s,
            &mut dev,
            &set_drive_payload(7, 2e4, 0.0, 0.0, 4e-6, -1000.0),
        ),
        7,
    );
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &set_drive_payload(8, 2e4, 0.0, 0.0, 4e-6, 1000.001)
        ),
        cat(&[
            &[V, 8, 1, 7, 5, 4],
            &(-1000f32).to_le_bytes(),
            &1000f32.to_le_bytes()
        ])
    );
    // Predict: |v0| ≤ 1000 m/s (Velocity = 6); Measure periods 1 … 10⁶ (Periods = 5).
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &cat(&[&[V, 9, 0, 7], &1001f32.to_le_bytes()])
        ),
        cat(&[
            &[V, 9, 1, 7, 5, 6],
            &(-1000f32).to_le_bytes(),
            &1000f32.to_le_bytes()
        ])
    );
    assert_eq!(
        ask(&mut s, &mut dev, &[V, 10, 0, 8, 0]),
        cat(&[
            &[V, 10, 1, 7, 5, 5],
            &1f32.to_le_bytes(),
            &1e6f32.to_le_bytes()
        ])
    );
}

/// Reads a little-endian f32 at `at`.
fn f32_at(p: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(p[at..at + 4].try_into().unwrap())
}

#[test]
fn predict_at_rest_returns_both_one_sided_limits() {
    use model_core::exact::{solve, Solution};
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    // A drive with a static interval (φ = 0.5 rad, Δu_z/u_z0 = 1/3, Δu_x = 0.2 µm).
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(1, 4e4, 1e-6, 2e-7, 3e-6, 0.5),
    );
    assert_eq!(&r[..4], [V, 1, 1, 1]);
    let a = dev.applied();
    // Predict{v0: 0} → Prediction: mu_over_mu0, mu, vc.0, vc.1, mu_0minus_over_mu0, regime.
    let p = ask(
        &mut s,
        &mut dev,
        &cat(&[&[V, 2, 0, 7], &0f32.to_le_bytes()]),
    );
    assert_eq!(&p[..4], [V, 2, 1, 4]);
    // Five f32, liftoff: bool (v3; false: the permanent-contact solver), regime.
    assert_eq!(p.len(), 4 + 5 * 4 + 1 + 1);
    assert_eq!(p[24], 0, "liftoff = false");
    let (plus, mu, minus) = (f32_at(&p, 4), f32_at(&p, 8), f32_at(&p, 20));
    let s64 = model_core::Scene::new(model_core::SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 3e-6,
        duz: 1e-6,
        dux: 2e-7,
        omega: std::f64::consts::TAU * a.achieved.freq_hz,
        phi: a.phase_rad,
    })
    .unwrap();
    let Solution::AtRest {
        mu_0plus,
        mu_0minus,
        ..
    } = solve(&s64, 0.0).unwrap()
    else {
        panic!("v0 = 0 is at rest");
    };
    // f32 exact solver: 1e-6·(1 + b), b = k_xΔu_x/(μ0 k_z u_z0) = 0.22, plus
    // the f32 rounding of the inputs (≈ 1e-7): 1e-5 is safe.
    assert!(
        (f64::from(plus) - mu_0plus).abs() <= 1e-5,
        "{plus} vs {mu_0plus}"
    );
    assert!(
        (f64::from(minus) - mu_0minus).abs() <= 1e-5,
        "{minus} vs {mu_0minus}"
    );
    assert!((mu - 0.3 * plus).abs() <= 1e-7);
    // The two limits differ by the static interval: not the same number twice.
    assert!((mu_0plus - mu_0minus).abs() > 0.1, "{mu_0plus} {mu_0minus}");
    // Elsewhere both fields are μ(v0).
    let p = ask(
        &mut s,
        &mut dev,
        &cat(&[&[V, 3, 0, 7], &0.01f32.to_le_bytes()]),
    );
    assert_eq!(f32_at(&p, 4), f32_at(&p, 20));
}

/// Feeds the device's loop with constant forces for `halves` half-buffers.
fn run_loop(dev: &mut Device<'_, 256>, s: &mut Server, halves: usize) -> Vec<Vec<u8>> {
    let mut buf = vec![0u32; 500];
    let samples = vec![(2100u16, 2000u16); 500];
    let mut tele = Vec::new();
    for k in 0..halves {
        dev.fill_dac(k & 1, &mut buf);
        dev.adc_block(k & 1, &samples);
        tele.extend(polled(s, dev));
    }
    tele
}

#[test]
fn measure_is_idempotent_per_seq_and_reset_ends_every_session() {
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    let g = good_drive();
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(
            1,
            g.freq_hz,
            g.amp_z_m,
            g.amp_x_m,
            g.offset_z_m,
            g.phase_rad,
        ),
    );
    assert_eq!(&r[..4], [V, 1, 1, 1]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 2, 0, 3]), [V, 2, 1, 2]); // Start → Ok
                                                                    // Measure{100} seq 20 → Ok; its retry → Ok (not Busy); seq 21 → Busy (7).
    let m20 = [V, 20, 0, 8, 100];
    assert_eq!(ask(&mut s, &mut dev, &m20), [V, 20, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &m20), [V, 20, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 21, 0, 8, 100]), [V, 21, 1, 7, 7]);
    // Stream on while a Measure runs: Busy.
    assert_eq!(
        ask(&mut s, &mut dev, &[V, 22, 0, 10, 1, 50]),
        [V, 22, 1, 7, 7]
    );
    // Let it finish; the retry of seq 20 then starts nothing.
    run_loop(&mut dev, &mut s, 200);
    assert!(
        !dev.status().measuring,
        "{:?} {:?}",
        dev.status(),
        dev.estimate()
    );
    let e = ask(&mut s, &mut dev, &[V, 23, 0, 9]);
    assert_eq!(&e[..4], [V, 23, 1, 5]);
    assert_eq!(ask(&mut s, &mut dev, &m20), [V, 20, 1, 2]);
    assert!(!dev.status().measuring);
    assert_eq!(
        ask(&mut s, &mut dev, &[V, 24, 0, 9]),
        e[..1]
            .iter()
            .chain(&[24])
            .chain(&e[2..])
            .copied()
            .collect::<Vec<_>>(),
        "the same estimate, not a new one"
    );
    // A new measurement, then Reset (13): it ends, the drive stops (ramped).
    assert_eq!(ask(&mut s, &mut dev, &[V, 25, 0, 8, 100]), [V, 25, 1, 2]);
    assert!(dev.status().measuring);
    assert_eq!(ask(&mut s, &mut dev, &[V, 26, 0, 13]), [V, 26, 1, 2]);
    let st = dev.status();
    assert!(!st.measuring && !st.running, "{st:?}");
    assert_eq!(ask(&mut s, &mut dev, &[V, 27, 0, 9]), [V, 27, 1, 7, 11]); // NotReady
                                                                          // A stream: on (periods 40), estimates as telemetry, then off → Ok and
                                                                          // StreamStopped(Requested) = telemetry 2, variant 3, StreamEnd 0.
    assert_eq!(ask(&mut s, &mut dev, &[V, 3, 0, 3]), [V, 3, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 28, 0, 10, 1, 40]), [V, 28, 1, 2]);
    let tele = run_loop(&mut dev, &mut s, 200);
    let estimates = tele.iter().filter(|p| p[2..4] == [2, 0]).count();
    assert!(estimates >= 2, "{tele:02x?}");
    let r = exchange(&mut s, &mut dev, &wire(&[V, 29, 0, 10, 0, 40]), 0);
    assert_eq!(r.len(), 2, "{r:02x?}");
    assert_eq!(r[0], [V, 29, 1, 2]);
    assert_eq!(r[1][2..], [2, 3, 0]);
    assert!(
        !dev.status().measuring,
        "the stream's measurement is aborted"
    );
    // Reset ends a stream with StreamStopped(Reset).
    assert_eq!(ask(&mut s, &mut dev, &[V, 30, 0, 10, 1, 40]), [V, 30, 1, 2]);
    polled(&mut s, &mut dev);
    let r = exchange(&mut s, &mut dev, &wire(&[V, 31, 0, 13]), 0);
    assert_eq!(r[0], [V, 31, 1, 2]);
    assert_eq!(r[1][2..], [2, 3, 1]);
    // A fault ends a stream: Fault(8) then StreamStopped(Refused(Faulted(8))).
    assert_eq!(ask(&mut s, &mut dev, &[V, 32, 0, 10, 1, 40]), [V, 32, 1, 2]);
    dev.fault(board::device::faults::EXTERNAL);
    let tele = polled(&mut s, &mut dev);
    let kinds: Vec<&[u8]> = tele.iter().map(|p| &p[2..]).collect();
    assert!(kinds.contains(&&[2u8, 2, 8][..]), "{tele:02x?}");
    assert!(kinds.contains(&&[2u8, 3, 2, 8, 8][..]), "{tele:02x?}");
    // A latched fault refuses Measure like Start: Faulted(8).
    assert_eq!(
        ask(&mut s, &mut dev, &[V, 33, 0, 8, 100]),
        [V, 33, 1, 7, 8, 8]
    );
    assert_eq!(ask(&mut s, &mut dev, &[V, 34, 0, 3]), [V, 34, 1, 7, 8, 8]);
}

/// An `Info` payload (response to `Hello`, seq 3) built field by field from
/// the Structures table, the self-test's four varints `self_test` last (v7).
fn info_payload_by_hand(self_test: &[u8]) -> Vec<u8> {
    let mut board = [0u8; 16];
    board[..9].copy_from_slice(b"STM32F405");
    cat(&[
        &[V, 3, 1, 0], // version, seq, Response, Info
        &[0, 2, 1],    // firmware 0.2.1
        &[V],          // protocol
        &board,
        &500e3f64.to_le_bytes(),
        &1e3f64.to_le_bytes(),
        &1e5f64.to_le_bytes(),
        &2e-6f32.to_le_bytes(),
        &8e-6f32.to_le_bytes(),
        &0.05f32.to_le_bytes(),
        &1000f32.to_le_bytes(),
        &1000f32.to_le_bytes(),
        &[1],                // periods_range.0
        &[0xc0, 0x84, 0x3d], // periods_range.1 = 1 000 000
        &[0xa0, 0x8d, 0x06], // byte_timeout_us = 100 000
        &0f32.to_le_bytes(), // retract_z_m
        self_test,
    ])
}

#[test]
fn a_hand_built_v7_info_decodes_with_its_self_test() {
    // A board with a 12 MHz crystal and firmware built for 8 MHz: every check
    // but the streams' ran; the crystal's frequency and the DMA set-up
    // failed; SYSCLK ran at 12/8 of 168 MHz (the `sysclk` check not run,
    // as a firmware may skip it once the crystal is off).
    let ran = self_test::CLOCK_READY
        | self_test::HSE_FREQUENCY
        | self_test::FLASH_LATENCY
        | self_test::DMA_SETUP;
    let failed = self_test::HSE_FREQUENCY | self_test::DMA_SETUP;
    assert_eq!((ran, failed), (0x1b, 0x12));
    let st = [
        0x1b, // ran (u16 varint)
        0x12, // failed
        0x80, 0xb6, 0xdc,
        0x05, // hse_hz = 12 000 000 (u32 varint, 7 bits per byte, low first)
        0x80, 0xee, 0x94, 0x78, // sysclk_hz = 252 000 000
    ];
    let mut w = wire(&info_payload_by_hand(&st));
    let n = w.len() - 1;
    let f = decode(&mut w[..n]).unwrap();
    assert_eq!((f.version, f.seq), (PROTOCOL_VERSION, 3));
    let Body::Response(Response::Info(i)) = f.body else {
        panic!("{f:?}")
    };
    let want = SelfTest {
        ran,
        failed,
        hse_hz: 12_000_000,
        sysclk_hz: 252_000_000,
    };
    assert_eq!(i.self_test, want);
    assert_eq!(&i.board[..9], b"STM32F405");
    assert_eq!(
        (i.firmware, i.protocol, i.periods_range, i.byte_timeout_us),
        ([0, 2, 1], PROTOCOL_VERSION, (1, 1_000_000), 100_000)
    );
    assert!(!i.self_test.passed());
    assert_eq!(
        i.self_test.failed_names().collect::<Vec<_>>(),
        ["hse_frequency", "dma_setup"]
    );
    assert_eq!(
        i.self_test.ran_names().collect::<Vec<_>>(),
        ["clock_ready", "hse_frequency", "flash_latency", "dma_setup"]
    );
    // A passed test; `ran` with a bit this version does not know (0x100: a
    // two-byte u16 varint `bf 02`) decodes as sent and is not named.
    let mut w = wire(&info_payload_by_hand(&[
        0xbf, 0x02, 0x00, 0x80, 0xa4, 0xe8, 0x03, 0x80, 0xf4, 0x8d, 0x50,
    ]));
    let n = w.len() - 1;
    let Body::Response(Response::Info(i)) = decode(&mut w[..n]).unwrap().body else {
        panic!()
    };
    assert_eq!(
        i.self_test,
        SelfTest {
            ran: 0x13f,
            failed: 0,
            hse_hz: 8_000_000,
            sysclk_hz: 168_000_000,
        }
    );
    assert!(i.self_test.passed());
    assert_eq!(i.self_test.ran_names().count(), 6);
    // Not run (the virtual device): four zero bytes, what `Info::for_config` sends.
    let mut w = wire(&info_payload_by_hand(&[0, 0, 0, 0]));
    let n = w.len() - 1;
    let Body::Response(Response::Info(i)) = decode(&mut w[..n]).unwrap().body else {
        panic!()
    };
    assert_eq!(i.self_test, SelfTest::NOT_RUN);
    assert!(!i.self_test.passed());
    assert_eq!(
        Info::for_config(&cfg(), "virtual", [0, 1, 0]).self_test,
        SelfTest::NOT_RUN
    );
    // The Info without its v7 field (a v6 body) is cut short: Malformed.
    let v6 = info_payload_by_hand(&[]);
    let mut w = wire(&v6);
    let n = w.len() - 1;
    assert!(decode(&mut w[..n]).is_err());
}

#[test]
fn ramp_done_follows_every_start_and_stop_and_status_shows_the_output() {
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(info());
    let g = good_drive();
    ask(
        &mut s,
        &mut dev,
        &set_drive_payload(
            1,
            g.freq_hz,
            g.amp_z_m,
            g.amp_x_m,
            g.offset_z_m,
            g.phase_rad,
        ),
    );
    let ramp_dones = |tele: &[Vec<u8>]| tele.iter().filter(|p| p[2..] == [2, 1]).count();
    // No RampDone before any command settles... one for SetDrive (preload ramp).
    assert_eq!(ramp_dones(&run_loop(&mut dev, &mut s, 100)), 1);
    for (seq, req) in [(2u8, 3u8), (3, 4), (4, 3), (5, 4)] {
        // Start (3) / Stop (4): exactly one RampDone each, after the ramps.
        assert_eq!(ask(&mut s, &mut dev, &[V, seq, 0, req]), [V, seq, 1, 2]);
        assert_eq!(ramp_dones(&polled(&mut s, &mut dev)), 0, "not settled yet");
        assert_eq!(ramp_dones(&run_loop(&mut dev, &mut s, 100)), 1);
    }
    // After Stop: GetDrive reports the setting, Status the output (amplitudes 0,
    // offset kept). Status: running, settled, faults, measuring, rx_overflows,
    // out_amp_z_m, out_amp_x_m, out_offset_z_m.
    let d = ask(&mut s, &mut dev, &[V, 6, 0, 1]);
    assert_eq!(f32_at(&d, 4 + 8), g.amp_z_m);
    let st = ask(&mut s, &mut dev, &[V, 7, 0, 11]);
    assert_eq!(&st[..9], [V, 7, 1, 6, 0, 1, 0, 0, 0]);
    assert_eq!(f32_at(&st, 9), 0.0);
    assert_eq!(f32_at(&st, 13), 0.0);
    // The offset kept, to f32 rounding of metres → codes → metres (2 ulp).
    assert!((f32_at(&st, 17) - g.offset_z_m).abs() <= 2.0 * f32::EPSILON * g.offset_z_m);
    // Running and settled: the output equals the setting (to f32 rounding of
    // the metres → codes → metres round trip: 2 ulp).
    ask(&mut s, &mut dev, &[V, 8, 0, 3]);
    run_loop(&mut dev, &mut s, 100);
    let st = ask(&mut s, &mut dev, &[V, 9, 0, 11]);
    assert_eq!(&st[4..6], [1, 1]);
    assert!((f32_at(&st, 9) - g.amp_z_m).abs() <= 2.0 * f32::EPSILON * g.amp_z_m);
    assert!((f32_at(&st, 13) - g.amp_x_m).abs() <= 2.0 * f32::EPSILON * g.amp_x_m);
    // v3: liftoff_allowed, false at power-up; v4: measured, None (00): this
    // loop feeds the forces only, no motion pickups; v5: the last field, mode,
    // OpenLoop (00) at power-up.
    assert_eq!((st.len(), st[21], st[22], st[23]), (37, 0, 0, 0));
    // v6: frequency_hz (f32), the DDS's: the setting to its resolution
    // f_s/2^32 = 2.3e-4 Hz and f32 rounding (half an ulp of 4e4: 2e-3 Hz);
    // options {track: None (00), headroom 2.0}; tracking_error_hz None (00);
    // locked false (00).
    assert!((f64::from(f32_at(&st, 24)) - g.freq_hz).abs() <= 1e6 / 2f64.powi(32) + 2e-3);
    assert_eq!(st[28], 0);
    assert_eq!(f32_at(&st, 29), 2.0);
    assert_eq!((st[33], st[34]), (0, 0));
    // v8: cpu_load_pct, cpu_load_max_pct None (00 00): nothing here records
    // the DSP time (the firmware does).
    assert_eq!((st[35], st[36]), (0, 0));
    // SetLiftOff (14) {allow: true} → Ok; Status shows it.
    assert_eq!(ask(&mut s, &mut dev, &[V, 10, 0, 14, 1]), [V, 10, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 11, 0, 11])[21], 1);
    // Δu_z = u_z0 (a = 1, the DAC's reach with zero_code 0) is now accepted …
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(
            12,
            g.freq_hz,
            g.offset_z_m,
            g.amp_x_m,
            g.offset_z_m,
            g.phase_rad,
        ),
    );
    assert_eq!(&r[..4], [V, 12, 1, 1]);
    // … and refusing lift-off again is refused: LiftOffRefused{Δu_z, 0.95·u_z0}.
    let lim = (1.0f32 - 0.05f32) * g.offset_z_m; // the spec's f32 product
    assert_eq!(
        ask(&mut s, &mut dev, &[V, 13, 0, 14, 0]),
        cat(&[
            &[V, 13, 1, 7, 6],
            &g.offset_z_m.to_le_bytes(),
            &lim.to_le_bytes()
        ])
    );
    assert_eq!(ask(&mut s, &mut dev, &[V, 14, 0, 11])[21], 1, "unchanged");
}

/// A `TransducerModel` on the wire: f_r, Q, g, θ (f32 LE each).
fn model_bytes(fr: f32, q: f32, g: f32, theta: f32) -> Vec<u8> {
    [fr, q, g, theta]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect()
}

/// `SetTransducers(Some{z, x})` (request 17, `01` = Some).
fn set_transducers_payload(seq: u8, z: &[u8], x: &[u8]) -> Vec<u8> {
    cat(&[&[V, seq, 0, 17, 1], z, x])
}

/// `OutOfRange{param, min, max}`: error 7, variant 5.
fn out_of_range(seq: u8, param: u8, min: f32, max: f32) -> Vec<u8> {
    cat(&[
        &[V, seq, 1, 7, 5, param],
        &min.to_le_bytes(),
        &max.to_le_bytes(),
    ])
}

#[test]
fn set_controls_target_limit_is_inclusive() {
    // docs/protocol.md, SetControl check 2: `|target_mu| ≤ μ₀` (μ₀ = 0.3 of
    // the test device), refused OutOfRange{TargetMu, −μ₀, μ₀}. The drive is
    // stopped, so a target that passes check 2 meets check 7, NotRunning.
    use board::device::DeviceError;
    use board::protocol::{ControlSetting, DriveParam};
    let t = SineTable::<256>::libm();
    let dev = test_device(&t);
    let mu0 = 0.3f32;
    let setting = |target_mu| ControlSetting {
        on: true,
        target_mu,
        v0_m_s: 0.004,
        gain: 0.7,
        periods: 4,
        rate_m_per_s: 1e-3,
    };
    let refused = DeviceError::OutOfRange {
        param: DriveParam::TargetMu,
        min: -mu0,
        max: mu0,
    };
    let up = |m: f32| f32::from_bits(m.to_bits() + 1);
    for target in [mu0, -mu0, 0.0] {
        assert_eq!(
            dev.check_control(&setting(target), false),
            Err(DeviceError::NotRunning),
            "{target} passes check 2"
        );
    }
    for target in [up(mu0), -up(mu0), f32::NAN, f32::INFINITY] {
        assert_eq!(
            dev.check_control(&setting(target), false),
            Err(refused),
            "{target}"
        );
    }
}

/// docs/protocol.md, SetControl check 3: `v0_m_s` finite, non-zero and
/// `|v0| ≤ MAX_VELOCITY_M_S` (1 000 m/s), refused
/// `OutOfRange{Velocity, −1000, 1000}`; the limit is inclusive (±1 000 and
/// a tiny velocity pass check 3 and meet check 7, NotRunning, as the drive
/// is stopped); 0, one ulp beyond the limit, ±∞ and NaN are refused.
#[test]
fn set_controls_velocity_limit_is_inclusive_and_excludes_zero() {
    use board::device::{DeviceError, MAX_VELOCITY_M_S};
    use board::protocol::{ControlSetting, DriveParam};
    let t = SineTable::<256>::libm();
    let dev = test_device(&t);
    let setting = |v0_m_s| ControlSetting {
        on: true,
        target_mu: 0.1,
        v0_m_s,
        gain: 0.7,
        periods: 4,
        rate_m_per_s: 1e-3,
    };
    assert_eq!(MAX_VELOCITY_M_S, 1_000.0);
    let refused = DeviceError::OutOfRange {
        param: DriveParam::Velocity,
        min: -1_000.0,
        max: 1_000.0,
    };
    let up = |m: f32| f32::from_bits(m.to_bits() + 1);
    for v0 in [1_000.0, -1_000.0, 1e-9, -4e-3] {
        assert_eq!(
            dev.check_control(&setting(v0), false),
            Err(DeviceError::NotRunning),
            "{v0} passes check 3"
        );
    }
    for v0 in [
        0.0,
        -0.0,
        up(1_000.0),
        -up(1_000.0),
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ] {
        assert_eq!(dev.check_control(&setting(v0), false), Err(refused), "{v0}");
    }
}

#[test]
fn check_8s_reported_maximum_is_itself_accepted() {
    // docs/protocol.md, SetDrive check 8: every limit is inclusive, tested in
    // the f32 the refusal reports. The maximum m of a refusal sent back is
    // accepted; the f32 one step above it is refused with the same m. On
    // each channel (z: 40 kHz, Q 10, 1 µm/V; x: 30 kHz, Q 20, 0.5 µm/V),
    // at 20 kHz on u_z0 = 4 µm (the normal room binds near 2.1 µm).
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(Info::for_config(&cfg(), "virtual", [0, 1, 0]));
    let z = model_bytes(40e3, 10.0, 1e-6, 0.1);
    let x = model_bytes(30e3, 20.0, 5e-7, 0.2);
    assert_eq!(
        ask(&mut s, &mut dev, &set_transducers_payload(1, &z, &x)),
        [V, 1, 1, 2]
    );
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &set_drive_payload(2, 2e4, 1e-6, 1e-7, 4e-6, 0.3)
        )[..4],
        [V, 2, 1, 1],
        "voltage mode: Applied"
    );
    assert_eq!(ask(&mut s, &mut dev, &[V, 3, 0, 19, 1]), [V, 3, 1, 2]);
    let max_of = |r: &[u8], param: u8| {
        assert_eq!(r.get(2..6), Some(&[1, 7, 5, param][..]), "{r:02x?}");
        assert_eq!((r.len(), f32_at(r, 6)), (14, 0.0));
        f32_at(r, 10)
    };
    let up = |m: f32| f32::from_bits(m.to_bits() + 1);
    // z: a drive far above the room is refused with m_z.
    let mz = max_of(
        &ask(
            &mut s,
            &mut dev,
            &set_drive_payload(4, 2e4, 3e-6, 1e-7, 4e-6, 0.3),
        ),
        1,
    );
    // m_z independently: room 2000 codes (u_z0 = 4 µm at 2 nm a code) ·
    // (3.3/4095 V) · |Ĥ(20 kHz)| of eq. 1 (c = 1), within the f32 rounding
    // of the device's evaluation (2e-6 relative, as in
    // displacement_mode_requests_get_the_spec_answers).
    let r: f64 = 2e4 / 4e4;
    let h = f64::from(1e-6f32) / ((1.0 - r * r).powi(2) + (r / 10.0).powi(2)).sqrt();
    let want = 2000.0 * (3.3 / 4095.0) * h;
    assert!(
        (f64::from(mz) - want).abs() <= 2e-6 * want,
        "{mz} vs {want}"
    );
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(5, 2e4, up(mz), 1e-7, 4e-6, 0.3),
    );
    assert_eq!(max_of(&r, 1), mz, "one f32 step above m_z");
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(6, 2e4, mz, 1e-7, 4e-6, 0.3),
    );
    assert_eq!(&r[..4], [V, 6, 1, 1], "m_z itself: {r:02x?}");
    // x: the same with the tangential channel's room (its zero code 2048,
    // room 2047 codes: m_x ≈ 1.48 µm), asked between m_x and the
    // voltage mode's `max_amp_x_m` (2047 codes · 1 nm), which check 6 reports.
    let mx = max_of(
        &ask(
            &mut s,
            &mut dev,
            &set_drive_payload(7, 2e4, 1e-6, 1.9e-6, 4e-6, 0.3),
        ),
        2,
    );
    assert!(mx > 1e-6 && mx < 1.9e-6, "{mx}");
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(8, 2e4, 1e-6, up(mx), 4e-6, 0.3),
    );
    assert_eq!(max_of(&r, 2), mx, "one f32 step above m_x");
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(9, 2e4, 1e-6, mx, 4e-6, 0.3),
    );
    assert_eq!(&r[..4], [V, 9, 1, 1], "m_x itself: {r:02x?}");
    // Over 55 frequencies (17…23.6 kHz) and offsets (3…4.1 µm; 0.85·u_z0 passes
    // checks 4 and 5, so check 8 is the one refused): the voltage
    // rounds differently each time, m is accepted every time.
    for k in 0..55u32 {
        let seq = 10 + 2 * k as u8;
        let f = 17e3 + 100.0 * f64::from(k) + 0.37 * f64::from(k * k);
        let off = 3e-6 + 2e-8 * k as f32;
        let r = ask(
            &mut s,
            &mut dev,
            &set_drive_payload(seq, f, 0.85 * off, 1e-7, off, 0.3),
        );
        let m = max_of(&r, 1);
        let r = ask(
            &mut s,
            &mut dev,
            &set_drive_payload(seq + 1, f, m, 1e-7, off, 0.3),
        );
        assert_eq!(
            &r[2..4],
            [1, 1],
            "{f} Hz, u_z0 {off:e} m: m {m:e} refused: {r:02x?}"
        );
    }
}

#[test]
fn displacement_mode_requests_get_the_spec_answers() {
    // docs/protocol.md, "The displacement mode": requests 17–19, response 9,
    // error 16, DriveParam 10–13, check 8 of SetDrive, Status.mode.
    let t = SineTable::<256>::libm();
    let mut dev = test_device(&t);
    let mut s = Server::new(Info::for_config(&cfg(), "virtual", [0, 1, 0]));
    let tau = std::f32::consts::TAU;
    // z: f_r = 40 kHz, Q = 10, g = 1 µm/V, θ = 0.1 rad; x: θ at its inclusive limit 2π.
    let z = model_bytes(40e3, 10.0, 1e-6, 0.1);
    let x = model_bytes(30e3, 20.0, 5e-7, tau);
    // Nothing stored at power-up: Transducers(None); the mode needs them: NotIdentified (16).
    assert_eq!(ask(&mut s, &mut dev, &[V, 1, 0, 18]), [V, 1, 1, 9, 0]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 2, 0, 19, 1]), [V, 2, 1, 7, 16]);
    // v6, request 20 SetDisplacementOptions {track, headroom f32}: tracking
    // needs the transducers (NotIdentified); a headroom outside [1, 8] is
    // OutOfRange{Headroom (14), 1, 8}, NaN too; both leave the options as
    // they were (Status: track 00 at byte 28, headroom 2.0 at 29).
    let opts = |seq: u8, track: u8, h: f32| cat(&[&[V, seq, 0, 20, track], &h.to_le_bytes()]);
    assert_eq!(ask(&mut s, &mut dev, &opts(30, 1, 2.0)), [V, 30, 1, 7, 16]);
    for (seq, h) in [(31u8, 0.99f32), (32, 8.01), (33, f32::NAN)] {
        assert_eq!(
            ask(&mut s, &mut dev, &opts(seq, 0, h)),
            out_of_range(seq, 14, 1.0, 8.0)
        );
    }
    let st = ask(&mut s, &mut dev, &[V, 34, 0, 11]);
    assert_eq!((st[28], f32_at(&st, 29)), (0, 2.0));
    // Headroom 1 and 8 (inclusive) without tracking: Ok, shown by Status.
    assert_eq!(ask(&mut s, &mut dev, &opts(35, 0, 8.0)), [V, 35, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &opts(36, 0, 1.0)), [V, 36, 1, 2]);
    assert_eq!(f32_at(&ask(&mut s, &mut dev, &[V, 37, 0, 11]), 29), 1.0);
    assert_eq!(ask(&mut s, &mut dev, &opts(38, 0, 2.0)), [V, 38, 1, 2]);
    // Validation, z before x, fields in order: the first bad field is named.
    let bad = [
        (model_bytes(0.0, 0.5, 1e-6, 0.1), x.clone(), 10, 0.0, 1e7),
        (z.clone(), model_bytes(30e3, 0.5, 5e-7, 0.0), 11, 0.5, 1e6),
        (model_bytes(40e3, 10.0, 1.5, 0.1), x.clone(), 12, 0.0, 1.0),
        (z.clone(), model_bytes(30e3, 20.0, 5e-7, 7.0), 13, -tau, tau),
    ];
    for (k, (bz, bx, param, min, max)) in bad.iter().enumerate() {
        let seq = 3 + k as u8;
        assert_eq!(
            ask(&mut s, &mut dev, &set_transducers_payload(seq, bz, bx)),
            out_of_range(seq, *param, *min, *max)
        );
    }
    // Refused: nothing stored. None in voltage mode: Ok.
    assert_eq!(ask(&mut s, &mut dev, &[V, 7, 0, 18]), [V, 7, 1, 9, 0]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 8, 0, 17, 0]), [V, 8, 1, 2]);
    // Stored and read back as sent.
    assert_eq!(
        ask(&mut s, &mut dev, &set_transducers_payload(9, &z, &x)),
        [V, 9, 1, 2]
    );
    assert_eq!(
        ask(&mut s, &mut dev, &[V, 10, 0, 18]),
        cat(&[&[V, 10, 1, 9, 1], &z, &x])
    );
    // Voltage mode: Δu_z = 3 µm on u_z0 = 4 µm at 20 kHz, φ = 0.3 rad is
    // accepted; Applied.phase_rad is the phase the DDS words produce, within
    // one phase step 2π/2³² of φ.
    let phi = 0.3f32;
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(11, 2e4, 3e-6, 0.0, 4e-6, phi),
    );
    assert_eq!(&r[..4], [V, 11, 1, 1]);
    let applied_phase = |r: &[u8]| f64::from_le_bytes(r[r.len() - 8..].try_into().unwrap());
    let step = std::f64::consts::TAU / 4_294_967_296.0;
    assert!((applied_phase(&r) - f64::from(phi)).abs() <= step);
    // Check 8: the voltage the model needs, |D|/|Ĥ(f)| with c = 1, must fit
    // room = min(dc, 4095 − dc) codes around the normal channel's DC
    // dc = u_z0 / (2 nm per code) = 2000 codes (zero code 0): at most
    // m = room·(3.3/4095 V)·|Ĥ| with eq. 1, |Ĥ| = g/√((1 − r²)² + (r/Q)²),
    // r = 20/40: m ≈ 2.14 µm < 3 µm, so switching the mode is refused with
    // that OutOfRange{AmpZ, 0, m} and changes nothing.
    let dc = f64::from(4e-6f32) / f64::from(2e-9f32);
    let room = dc.min(4095.0 - dc);
    let ratio: f64 = 2e4 / 4e4;
    let h = f64::from(1e-6f32) / ((1.0 - ratio * ratio).powi(2) + (ratio / 10.0).powi(2)).sqrt();
    let m = room * (3.3 / 4095.0) * h;
    let refused = ask(&mut s, &mut dev, &[V, 12, 0, 19, 1]);
    assert_eq!(&refused[..6], [V, 12, 1, 7, 5, 1], "{refused:02x?}");
    assert_eq!((refused.len(), f32_at(&refused, 6)), (14, 0.0));
    // The device computes m in f32 (≈ 15 roundings of ≤ 2⁻²⁴ each: ≤ 1e-6
    // relative) at the DDS frequency (within 1e6/2³² Hz of 20 kHz: < 1e-8
    // relative in |Ĥ|): 2e-6 relative bounds both.
    let got = f64::from(f32_at(&refused, 10));
    assert!((got - m).abs() <= 2e-6 * m, "{got} vs {m}");
    assert_eq!(ask(&mut s, &mut dev, &[V, 13, 0, 11])[23], 0);
    // Δu_z = 2 µm fits (1.5 V of the 1.61 V room): the switch is accepted,
    // Status.mode = Displacement (1, byte 23; measured None here), and
    // Applied.phase_rad is exactly the setting's φ.
    let r = ask(
        &mut s,
        &mut dev,
        &set_drive_payload(14, 2e4, 2e-6, 0.0, 4e-6, phi),
    );
    assert_eq!(&r[..4], [V, 14, 1, 1]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 15, 0, 19, 1]), [V, 15, 1, 2]);
    let st = ask(&mut s, &mut dev, &[V, 16, 0, 11]);
    // v8: 35 bytes up to `locked`, then cpu_load_pct and cpu_load_max_pct None.
    assert_eq!((st.len(), st[22], st[23]), (37, 0, 1), "{st:02x?}");
    assert_eq!(st[35..], [0, 0]);
    let d = ask(&mut s, &mut dev, &[V, 17, 0, 1]);
    assert_eq!(&d[..4], [V, 17, 1, 1]);
    assert_eq!(applied_phase(&d), f64::from(phi));
    // In displacement mode SetDrive itself is refused by check 8, with the same m.
    assert_eq!(
        ask(
            &mut s,
            &mut dev,
            &set_drive_payload(18, 2e4, 3e-6, 0.0, 4e-6, phi)
        )[2..],
        refused[2..]
    );
    // Forgetting the transducers in displacement mode: NotIdentified; the
    // mode already in force: Ok.
    assert_eq!(ask(&mut s, &mut dev, &[V, 19, 0, 17, 0]), [V, 19, 1, 7, 16]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 20, 0, 19, 1]), [V, 20, 1, 2]);
    // `Reset` (13) keeps the transducers, the mode, the displacement options
    // and the lift-off permission ("Reset": settings kept): set before it
    // tracking Z (1) with headroom 3.5 (request 20) and SetLiftOff{allow:
    // true} (14); after it GetTransducers still answers Some (01 after the
    // response index 9), the status' liftoff_allowed (byte 21) is 1, mode
    // (byte 23) 1, track (28) 1, headroom (29) 3.5.
    assert_eq!(ask(&mut s, &mut dev, &opts(43, 1, 3.5)), [V, 43, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 44, 0, 14, 1]), [V, 44, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 40, 0, 13]), [V, 40, 1, 2]);
    assert_eq!(
        &ask(&mut s, &mut dev, &[V, 41, 0, 18])[..5],
        [V, 41, 1, 9, 1]
    );
    let st = ask(&mut s, &mut dev, &[V, 42, 0, 11]);
    assert_eq!((st[21], st[23], st[28], f32_at(&st, 29)), (1, 1, 1, 3.5));
    assert_eq!(ask(&mut s, &mut dev, &[V, 45, 0, 14, 0]), [V, 45, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &opts(46, 0, 2.0)), [V, 46, 1, 2]);
    // Back to voltage mode, then they can be forgotten.
    assert_eq!(ask(&mut s, &mut dev, &[V, 21, 0, 19, 0]), [V, 21, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 22, 0, 11])[23], 0);
    assert_eq!(ask(&mut s, &mut dev, &[V, 23, 0, 17, 0]), [V, 23, 1, 2]);
    assert_eq!(ask(&mut s, &mut dev, &[V, 24, 0, 18]), [V, 24, 1, 9, 0]);
}

#[test]
fn the_docs_request_table_is_the_endpoint_table() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/protocol.md"))
        .unwrap();
    let start = doc.find("| index | request |").unwrap();
    let rows: Vec<Vec<String>> = doc[start..]
        .lines()
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            l.split('|')
                .map(|c| c.trim().trim_matches('`').to_string())
                .collect()
        })
        .collect();
    let table = board::protocol::ENDPOINTS;
    assert_eq!(rows.len(), table.len());
    for (row, ep) in rows.iter().zip(table) {
        assert_eq!(row[1], ep.index.to_string());
        assert_eq!(row[2], ep.request);
        assert_eq!(row[4], format!("{:?}", ep.answer));
    }
}

#[test]
fn fault_bits_are_the_spec_values() {
    // docs/protocol.md, "Fault bits: 1 = ADC saturated …, 256 = self-test":
    // each constant is the value the spec gives its name (a constant that
    // changed — a shift the other way — would still compare equal to
    // itself everywhere else), and ALL is their union, 511.
    use board::device::faults::*;
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/protocol.md"))
        .unwrap();
    let para = &doc[doc
        .find("Fault bits: ")
        .expect("the spec's fault paragraph")..];
    let para = &para[..para.find("\n\n").unwrap_or(para.len())];
    let para = para.split_whitespace().collect::<Vec<_>>().join(" ");
    for (value, name) in [
        (ADC_SATURATED, "ADC saturated"),
        (DAC_UNDERRUN, "DAC underrun"),
        (WATCHDOG_RESET, "watchdog reset"),
        (EXTERNAL, "external"),
        (ADC_OVERRUN, "ADC overrun"),
        (MEASURED_LIFTOFF, "measured lift-off"),
        (LOSS_OF_LOCK, "loss of lock"),
        (PICKUP_OPEN, "open pickup"),
        (SELF_TEST, "self-test"),
    ] {
        assert!(
            para.contains(&format!("{value} = {name}")),
            "{name}: {value} is not the spec's bit"
        );
    }
    assert_eq!(ALL, 511);
}

/// `encode` against a frame built by hand from the spec (postcard bytes,
/// their CRC-32 little-endian, COBS, one zero): the same bytes for a
/// short request, a drive setting and the device's `Info`; and for every
/// output buffer shorter than the encoded frame `TooLarge`, for every one
/// as long or longer the frame.
#[test]
fn encode_is_the_spec_and_refuses_exactly_the_short_buffers() {
    use board::protocol::EncodeError;
    let frames = [
        Frame {
            version: PROTOCOL_VERSION,
            seq: 0,
            body: Body::Request(Request::Hello),
        },
        Frame {
            version: PROTOCOL_VERSION,
            seq: 0xFFFF_FFFF,
            body: Body::Request(Request::SetDrive(good_drive())),
        },
        Frame {
            version: PROTOCOL_VERSION,
            seq: 300,
            body: Body::Response(Response::Info(info())),
        },
    ];
    for f in &frames {
        let mut b = [0u8; MAX_FRAME];
        let raw = postcard::to_slice(f, &mut b).unwrap();
        let want = frame_of_raw(raw);
        let mut out = [0u8; MAX_FRAME];
        let got = encode(f, &mut out).unwrap().to_vec();
        assert_eq!(got, want);
        for len in 0..want.len() + 3 {
            let mut buf = vec![0u8; len];
            let r = encode(f, &mut buf).map(|b| b.to_vec());
            if len < want.len() {
                assert_eq!(r, Err(EncodeError::TooLarge), "{len} bytes");
            } else {
                assert_eq!(r.as_deref(), Ok(&want[..]), "{len} bytes");
            }
        }
    }
}
