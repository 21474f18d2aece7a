//! The wire protocol and the device-side server: round trips, garbage,
//! corrupted CRC, oversize and cut-off frames, unknown messages, version
//! mismatch, and refused commands that change nothing.

use model_core::dds::SineTable;
use model_core::device::{Contact, Device, DeviceConfig, DriveSetting};
use model_core::protocol::{
    decode, encode, Body, Deframed, Deframer, Frame, Info, Request, Response, WireError, CRC,
    MAX_FRAME, PROTOCOL_VERSION,
};
use model_core::server::Server;

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
    let mut replies = Vec::new();
    let mut df = Deframer::default();
    server.receive(dev, bytes, |out| {
        for &b in out {
            if let Deframed::Frame(f) = df.push(b) {
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
    ];
    assert_eq!(reqs.len() as u32, model_core::protocol::REQUEST_VARIANTS);
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
    // Python's zlib.crc32 and a hand-written COBS encoder).
    let mut out = [0u8; MAX_FRAME];
    let req = encode(
        &Frame {
            version: 1,
            seq: 5,
            body: Body::Request(Request::GetStatus),
        },
        &mut out,
    )
    .unwrap();
    assert_eq!(
        req,
        &[0x03, 0x01, 0x05, 0x06, 0x0b, 0x1a, 0xa3, 0xe1, 0x08, 0x00]
    );
    let status = model_core::device::Status {
        running: true,
        settled: true,
        faults: 0,
        measuring: false,
        rx_overflows: 0,
    };
    let mut out = [0u8; MAX_FRAME];
    let resp = encode(
        &Frame {
            version: 1,
            seq: 5,
            body: Body::Response(Response::Status(status)),
        },
        &mut out,
    )
    .unwrap();
    assert_eq!(
        resp,
        &[
            0x07, 0x01, 0x05, 0x01, 0x06, 0x01, 0x01, 0x01, 0x01, 0x05, 0xf5, 0xa8, 0x60, 0x4c,
            0x00
        ]
    );
}

#[test]
fn telemetry_reports_ramps_and_faults_with_its_own_counter() {
    use model_core::protocol::Telemetry;
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
                if let Deframed::Frame(f) = df.push(b) {
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
    dev.fault(model_core::device::faults::EXTERNAL);
    collect(&mut s, &mut dev);
    assert_eq!(tele.len(), 2, "{tele:?}");
    assert_eq!(tele[0].1, Telemetry::RampDone);
    assert_eq!(
        tele[1].1,
        Telemetry::Fault(model_core::device::faults::EXTERNAL)
    );
    assert_eq!(tele[1].0, tele[0].0 + 1);
}
