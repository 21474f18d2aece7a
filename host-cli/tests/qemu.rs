//! The real firmware binary under QEMU (netduinoplus2 = STM32F405), driven
//! through `fricctl device --tcp` and through hand-built frames on the raw
//! link. Needs `qemu-system-arm` and the thumbv7em-none-eabihf target. The
//! firmware ELF is `FIRMWARE_ELF` if set, else the tests build it themselves
//! (`cargo build --release --features qemu` in `firmware/`, into
//! `firmware/target/qemu-tests`, so the hardware build is left alone), once.
//! QEMU runs one at a time whatever `--test-threads` is (a lock), so the
//! measured rate is QEMU's: `cargo test -p host-cli --test qemu -- --ignored`.
//!
//! QEMU's serial runs with `nodelay=on`: without it QEMU writes each byte on
//! a socket without TCP_NODELAY, and delayed ACKs throttle the link to tens
//! of round trips per second.

use std::collections::VecDeque;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command as StdCommand, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::{drive_set, DRIVE};

use assert_cmd::Command;
use board::link::RX_CAPACITY;
use board::protocol::{
    decode, Body, Deframed, Deframer, Frame, Request, Response, StreamEnd, Telemetry, WireError,
    PROTOCOL_VERSION,
};
use integration_tests::wire;
use serde_json::Value;

struct Qemu {
    child: Child,
    port: u16,
    /// One QEMU at a time (held until this one is dropped).
    _turn: std::sync::MutexGuard<'static, ()>,
}

/// Serialises the QEMU runs of this file.
static QEMU_TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The firmware ELF built with `feature` (`qemu`: ideal transducers in its
/// plant; `qemu-resonant`: the bench's resonant ones): the environment
/// variable `var` if set (`FIRMWARE_ELF`, `FIRMWARE_RESONANT_ELF`), else built
/// here once per feature, into `firmware/target/qemu-tests/FEATURE`.
fn firmware_elf(var: &str, feature: &str) -> String {
    static ELFS: std::sync::Mutex<Vec<(String, String)>> = std::sync::Mutex::new(Vec::new());
    let mut elfs = ELFS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, e)) = elfs.iter().find(|(f, _)| f == feature) {
        return e.clone();
    }
    let elf = match std::env::var(var) {
        Ok(p) => p,
        Err(_) => {
            let fw = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware");
            let target = fw.join("target/qemu-tests").join(feature);
            eprintln!("building the firmware with --features {feature} ({var} not set) …");
            let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
            let st = StdCommand::new(cargo)
                .current_dir(&fw)
                .args([
                    "build",
                    "--release",
                    "--locked",
                    "--features",
                    feature,
                    "--bin",
                    "firmware",
                ])
                .arg("--target-dir")
                .arg(&target)
                // The firmware's own toolchain file and config decide the target.
                .env_remove("RUSTFLAGS")
                .env_remove("CARGO_TARGET_DIR")
                .env_remove("CARGO_BUILD_TARGET")
                .status()
                .expect("cargo (to build the firmware)");
            assert!(
                st.success(),
                "building the firmware failed (needs `rustup target add thumbv7em-none-eabihf`); or set {var}"
            );
            let elf = target.join("thumbv7em-none-eabihf/release/firmware");
            assert!(elf.is_file(), "no firmware at {}", elf.display());
            elf.display().to_string()
        }
    };
    elfs.push((feature.to_string(), elf.clone()));
    elf
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn qemu() -> Qemu {
    qemu_with("FIRMWARE_ELF", "qemu")
}

/// QEMU running the firmware built with `feature` ([`firmware_elf`]).
fn qemu_with(var: &str, feature: &str) -> Qemu {
    qemu_with_args(var, feature, &[])
}

/// [`qemu_with`] and `extra` arguments for QEMU (`-icount shift=0`: one
/// instruction one nanosecond of emulated time), on a free port.
fn qemu_with_args(var: &str, feature: &str, extra: &[&str]) -> Qemu {
    let turn = QEMU_TURN.lock().unwrap_or_else(|e| e.into_inner());
    let elf = firmware_elf(var, feature);
    // The port is free when asked for, but another program (a second QEMU, a
    // second user) may take it before QEMU binds it: QEMU then exits with
    // "Address already in use", and a connection would reach the stranger.
    // Such a start is detected (QEMU gone) and retried on another port.
    for _ in 0..5 {
        if let Some((child, port)) = spawn_qemu(&elf, free_port(), extra) {
            return Qemu {
                child,
                port,
                _turn: turn,
            };
        }
    }
    panic!("QEMU could not listen on any of 5 free ports");
}

/// QEMU on `port`, once it listens and still runs; `None` if it exited
/// (the port was taken: "Address already in use").
fn spawn_qemu(elf: &str, port: u16, extra: &[&str]) -> Option<(Child, u16)> {
    let mut child = StdCommand::new("qemu-system-arm")
        .args([
            "-machine",
            "netduinoplus2",
            "-display",
            "none",
            "-monitor",
            "none",
            "-serial",
            "null",
        ])
        .arg("-serial")
        .arg(format!("tcp:127.0.0.1:{port},server=on,wait=on,nodelay=on"))
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(extra)
        .args(["-kernel", elf])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("qemu-system-arm (apt-get install qemu-system-arm)");
    // Wait until QEMU listens; the first connection starts the guest (wait=on).
    let t = Instant::now();
    while TcpStream::connect(("127.0.0.1", port)).is_err() {
        if child.try_wait().ok().flatten().is_some() {
            return None;
        }
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "QEMU did not open its serial port"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // The probe connection above was closed; give the firmware time to enable USART2
    // (bytes sent before that are dropped by the emulated USART; the CLI retries anyway).
    std::thread::sleep(Duration::from_millis(300));
    // Still running: the listener that answered was QEMU's, not a stranger's.
    if child.try_wait().ok().flatten().is_some() {
        return None;
    }
    Some((child, port))
}

/// Wall 1 of issue 37: a second QEMU on a taken port. The port is held by
/// a stranger (a listener that accepts and never answers, as another
/// emulator stuck in its own session): QEMU on that port exits ("Address
/// already in use"), `fricctl device --tcp` on it fails naming the likely
/// cause, and the tests' own start ([`qemu_with_args`]) lands on a free port.
#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn a_taken_port_is_named_and_skipped() {
    let stranger = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let taken = stranger.local_addr().unwrap().port();
    let elf = firmware_elf("FIRMWARE_ELF", "qemu");
    let mut child = StdCommand::new("qemu-system-arm")
        .args(["-machine", "netduinoplus2", "-display", "none"])
        .args(["-monitor", "none", "-serial", "null", "-serial"])
        .arg(format!("tcp:127.0.0.1:{taken},server=on,wait=off"))
        .args(["-kernel", &elf])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qemu-system-arm (apt-get install qemu-system-arm)");
    let t = Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        if t.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            panic!("QEMU ran on a taken port");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(!status.success());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert!(err.contains("Address already in use"), "{err}");
    // fricctl on the taken port: the stranger accepts and stays silent.
    let addr = format!("127.0.0.1:{taken}");
    let o = Command::cargo_bin("fricctl")
        .unwrap()
        .args(["device", "--tcp", &addr, "--timeout-ms", "200", "info"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("another program"), "{e}");
    // The tests' start picks a free port: the firmware answers there.
    let q = qemu();
    assert_ne!(q.port, taken);
    let o = dev(&q, &["info"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    drop(stranger);
}

fn dev(q: &Qemu, args: &[&str]) -> std::process::Output {
    let addr = format!("127.0.0.1:{}", q.port);
    Command::cargo_bin("fricctl")
        .unwrap()
        .args(["device", "--tcp", &addr, "--json", "--timeout-ms", "1000"])
        .args(args)
        .output()
        .unwrap()
}

#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn real_firmware_under_qemu() {
    let q = qemu();
    let o = dev(&q, &["info"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["board"], "STM32F405");
    assert_eq!(info["protocol"], PROTOCOL_VERSION);
    let o = dev(&q, DRIVE);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before = dev(&q, &["drive", "get"]).stdout;
    // Lift-off refused, nothing changed.
    let o = dev(&q, &drive_set("20000", "3.9e-6", "3e-7", "4e-6", None));
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("lift"));
    assert_eq!(dev(&q, &["drive", "get"]).stdout, before);
    // Prediction in f32 on the emulated M4F against the host's f64 model.
    let o = dev(&q, &["predict", "--v0", "0.004"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p: Value = serde_json::from_slice(&o.stdout).unwrap();
    let pred = p["mu"].as_f64().unwrap();
    let host = common::host_mu_of_test_drive();
    assert!(
        (pred - host["mu"].as_f64().unwrap()).abs() <= 1e-5,
        "{pred} vs {host}"
    );
    // Lift-off on purpose: allowed, Δu_z = u_z0 accepted, the lift-off model
    // on the M4F against the f64 fixed-step reference (common::liftoff);
    // refusing again is refused while that drive is set.
    let o = dev(&q, &["config", "--allow-liftoff"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = dev(&q, &drive_set("20000", "4e-6", "3e-7", "4e-6", Some("40")));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d: Value = serde_json::from_slice(&o.stdout).unwrap();
    let o = dev(&q, &["predict", "--v0", "0.004"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(p["model"], "liftoff", "{p}");
    let (want, tol) = common::liftoff::reference(&d, 0.004);
    let got = p["mu_over_mu0"].as_f64().unwrap();
    assert!((got - want).abs() <= tol, "{got} vs {want} (tol {tol:.1e})");
    assert_eq!(
        dev(&q, &["config", "--refuse-liftoff"]).status.code(),
        Some(2)
    );

    // Garbage and a corrupted CRC on the raw link.
    let mut s = TcpStream::connect(("127.0.0.1", q.port)).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let good = common::req(41, Request::GetStatus);
    s.write_all(&[0x12, 0x34, 0x00]).unwrap();
    s.write_all(&common::corrupt_crc(good.clone())).unwrap();
    s.write_all(&good).unwrap();
    let got = common::read_responses(&mut s, 3);
    let errs: Vec<_> = got.iter().map(|f| f.body).collect();
    assert_eq!(
        errs[0],
        Body::Response(Response::Error(WireError::Malformed))
    );
    assert_eq!(errs[1], Body::Response(Response::Error(WireError::BadCrc)));
    assert_eq!(got[2].seq, 41);
    assert!(matches!(errs[2], Body::Response(Response::Status(_))));
}

/// The raw link: hand-built requests out, responses (telemetry skipped) in.
struct RawLink {
    s: TcpStream,
    df: Deframer,
    got: VecDeque<Frame>,
    /// Telemetry received so far, in order.
    tele: Vec<Telemetry>,
}

impl RawLink {
    fn connect(q: &Qemu) -> Self {
        let s = TcpStream::connect(("127.0.0.1", q.port)).unwrap();
        s.set_nodelay(true).unwrap();
        RawLink {
            s,
            df: Deframer::default(),
            got: VecDeque::new(),
            tele: Vec::new(),
        }
    }

    fn send(&mut self, bytes: &[u8]) {
        self.s.write_all(bytes).unwrap();
    }

    /// The next response, or None when `deadline` passes first.
    fn next(&mut self, deadline: Instant) -> Option<Frame> {
        let mut b = [0u8; 512];
        loop {
            if let Some(f) = self.got.pop_front() {
                return Some(f);
            }
            let left = deadline.checked_duration_since(Instant::now())?;
            self.s
                .set_read_timeout(Some(left.max(Duration::from_millis(1))))
                .unwrap();
            let n = match self.s.read(&mut b) {
                Ok(0) => panic!("QEMU closed the serial link"),
                Ok(n) => n,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    continue
                }
                Err(e) => panic!("{e}"),
            };
            for &x in &b[..n] {
                if let Deframed::Frame(f) = self.df.push(x, 0) {
                    let f = decode(f).expect("the firmware's frames decode");
                    match f.body {
                        Body::Response(_) => self.got.push_back(f),
                        Body::Telemetry(t) => self.tele.push(t),
                        Body::Request(_) => panic!("a request from the device: {f:?}"),
                    }
                }
            }
        }
    }

    /// Sends GetStatus until one is answered (the emulated USART drops
    /// bytes until the firmware enables it), then drains the link.
    fn sync(&mut self) {
        let t = Instant::now();
        loop {
            assert!(
                t.elapsed() < Duration::from_secs(10),
                "no answer from the firmware"
            );
            self.send(&[0]);
            self.send(&wire::get_status(0));
            if self
                .next(Instant::now() + Duration::from_millis(100))
                .is_some()
            {
                break;
            }
        }
        while self
            .next(Instant::now() + Duration::from_millis(200))
            .is_some()
        {}
    }

    /// `rx_overflows` from a GetStatus with `seq`.
    fn rx_overflows(&mut self, seq: u32) -> u32 {
        self.send(&wire::get_status(seq));
        let deadline = Instant::now() + Duration::from_secs(2);
        while let Some(f) = self.next(deadline) {
            if let (true, Body::Response(Response::Status(st))) = (f.seq == seq, f.body) {
                return st.rx_overflows;
            }
        }
        panic!("GetStatus {seq} not answered");
    }
}

/// Per-request timeout of the sequential test, no retries. A lost wake-up
/// is unbounded under QEMU (no DMA interrupts there: only the next byte
/// wakes the core, and it comes only after this timeout), so any finite
/// timeout catches every one (the firmware before the fix: 10 of 10 000
/// unanswered at 500 ms). 1 s is over 1000 times the median round trip
/// (0.7–0.8 ms) and ≈ 3 times the slowest answer seen with the machine's
/// load average at 13 on 2 cores (364 ms): a scheduler stall is not a failure.
const REQUEST_TIMEOUT: Duration = Duration::from_millis(1000);

#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn ten_thousand_sequential_requests_all_answered_without_retries() {
    let q = qemu();
    let mut link = RawLink::connect(&q);
    link.sync();
    let n = 10_000u32;
    let (mut unanswered, mut wrong) = (Vec::new(), 0u32);
    let mut rtt = Vec::with_capacity(n as usize);
    let t0 = Instant::now();
    for seq in 1..=n {
        let t = Instant::now();
        link.send(&wire::get_status(seq));
        let deadline = t + REQUEST_TIMEOUT;
        loop {
            match link.next(deadline) {
                None => {
                    unanswered.push(seq);
                    break;
                }
                // A late answer to an earlier, timed-out request.
                Some(f) if f.seq < seq => {}
                Some(f) => {
                    if f.seq != seq || !matches!(f.body, Body::Response(Response::Status(_))) {
                        wrong += 1;
                    }
                    rtt.push(t.elapsed());
                    break;
                }
            }
        }
    }
    let total = t0.elapsed();
    rtt.sort();
    let pct = |p: usize| rtt.get(rtt.len() * p / 100).copied().unwrap_or_default();
    eprintln!(
        "{n} sequential GetStatus (nodelay=on): {:.0} round trips/s, {} unanswered within {} ms, \
         round trip median {:.2} ms, 99 % {:.2} ms, max {:.2} ms",
        f64::from(n) / total.as_secs_f64(),
        unanswered.len(),
        REQUEST_TIMEOUT.as_millis(),
        pct(50).as_secs_f64() * 1e3,
        pct(99).as_secs_f64() * 1e3,
        rtt.last().copied().unwrap_or_default().as_secs_f64() * 1e3,
    );
    assert!(
        unanswered.is_empty(),
        "unanswered: {:?}",
        &unanswered[..unanswered.len().min(20)]
    );
    assert_eq!(wrong, 0, "answers with a wrong seq or body");
    assert_eq!(link.rx_overflows(n + 1), 0);
}

#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn pipelined_requests_no_loss_or_counted_overflow() {
    let q = qemu();
    let mut link = RawLink::connect(&q);
    link.sync();
    let before = link.rx_overflows(1);

    // Within the documented depth (docs/protocol.md, "Pipelining"): rounds of
    // as many GetStatus as fit in the receive queue, each round written at
    // once; every one must be answered, none dropped.
    let len = wire::get_status(u32::MAX).len(); // longest seq varint: 5 bytes
    let per_round = RX_CAPACITY / len;
    let mut seq = 100u32;
    for _round in 0..5 {
        let first = seq;
        let burst: Vec<u8> = (0..per_round)
            .flat_map(|_| {
                seq += 1;
                wire::get_status(seq)
            })
            .collect();
        assert!(burst.len() <= RX_CAPACITY);
        link.send(&burst);
        let deadline = Instant::now() + Duration::from_secs(5);
        let got: Vec<u32> = (0..per_round)
            .map_while(|_| link.next(deadline).map(|f| f.seq))
            .collect();
        assert_eq!(got, (first + 1..=seq).collect::<Vec<_>>());
    }
    assert_eq!(link.rx_overflows(2), before, "overflow within the depth");

    // A flood far beyond it, written at once: either every request is
    // answered, or the device reports the dropped bytes, and a lost request
    // had one of its own bytes, or its predecessor's closing 0x00, dropped
    // (at most two lost per dropped byte).
    let m = 2_000u32;
    let base = 1_000_000u32;
    let flood: Vec<u8> = (1..=m).flat_map(|i| wire::get_status(base + i)).collect();
    link.send(&flood);
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut answered = 0u32;
    let mut errors = 0u32;
    while let Some(f) = link.next(deadline) {
        match f.body {
            Body::Response(Response::Status(_)) if f.seq > base => {
                answered += 1;
                if f.seq == base + m {
                    break;
                }
            }
            Body::Response(Response::Error(_)) => errors += 1,
            other => panic!("unexpected {other:?}"),
        }
    }
    // Whatever is still in flight ends here.
    while link
        .next(Instant::now() + Duration::from_millis(300))
        .is_some()
    {}
    link.send(&[0]);
    let dropped = link.rx_overflows(3) - before;
    let lost = m - answered;
    eprintln!(
        "flood of {m} GetStatus ({} bytes) written at once: {answered} answered, {lost} lost, \
         {errors} error answers, rx_overflows +{dropped}",
        flood.len()
    );
    // Every growth of the count is announced by RxOverflow(total) telemetry:
    // the last one carries the total that GetStatus reports.
    let announced = link.tele.iter().rev().find_map(|t| match t {
        Telemetry::RxOverflow(n) => Some(*n),
        _ => None,
    });
    if dropped == 0 {
        assert_eq!(lost, 0, "requests lost without a counted overflow");
        assert_eq!(errors, 0);
        assert_eq!(announced, None);
    } else {
        assert_eq!(announced, Some(before + dropped), "{:?}", link.tele);
        assert!(
            lost <= 2 * dropped,
            "lost {lost} > 2 × {dropped} dropped bytes"
        );
    }
}

/// A request frame built by hand from docs/protocol.md: version, seq (< 128:
/// one varint byte), Body::Request (0), the request's index and its fields.
fn hand_request(seq: u8, index: u8, fields: &[u8]) -> Vec<u8> {
    let mut p = vec![wire::VERSION as u8, seq, 0, index];
    p.extend_from_slice(fields);
    wire::frame(&p)
}

impl RawLink {
    /// Sends a hand-built request and returns its response.
    fn ask(&mut self, seq: u8, index: u8, fields: &[u8]) -> Response {
        self.send(&hand_request(seq, index, fields));
        let deadline = Instant::now() + Duration::from_secs(2);
        while let Some(f) = self.next(deadline) {
            if f.seq == u32::from(seq) {
                let Body::Response(r) = f.body else {
                    unreachable!()
                };
                return r;
            }
        }
        panic!("request {index} (seq {seq}) not answered");
    }

    fn status(&mut self, seq: u8) -> board::device::Status {
        match self.ask(seq, 11, &[]) {
            Response::Status(s) => s,
            other => panic!("{other:?}"),
        }
    }
}

#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn reset_ends_the_stream_and_the_measurement_on_the_firmware() {
    let q = qemu();
    let mut link = RawLink::connect(&q);
    link.sync();
    // Stream{on: true, periods: 100} (10: bool 01, varint 64) → Ok.
    assert_eq!(link.ask(20, 10, &[1, 100]), Response::Ok);
    assert!(link.status(21).measuring);
    // A Measure (8, periods 100) while the stream runs: Busy.
    assert_eq!(link.ask(22, 8, &[100]), Response::Error(WireError::Busy));
    // Reset → Ok, then the telemetry StreamStopped(Reset).
    assert_eq!(link.ask(23, 13, &[]), Response::Ok);
    let st = link.status(24);
    assert!(!st.measuring && !st.running, "{st:?}");
    assert!(
        link.tele
            .contains(&Telemetry::StreamStopped(StreamEnd::Reset)),
        "{:?}",
        link.tele
    );
    // A short Measure (8, 32 periods = 0.8 ms of device time) closes by
    // itself on the emulated plant: the intake runs (the drive is stopped,
    // so the estimate is there but marked invalid; with no preload the
    // normal force reads 0 counts, on the rail, which latches ADC_SATURATED
    // as on a board — ResetFaults (12) clears it afterwards).
    assert_eq!(link.ask(33, 8, &[32]), Response::Ok);
    let t = Instant::now();
    while link.status(34).measuring {
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "a 32-period Measure never closed"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let Response::Estimate(e) = link.ask(35, 9, &[]) else {
        panic!("no estimate after the short Measure")
    };
    assert_eq!(e.periods, 32, "{e:?}");
    assert!(!e.valid(), "{e:?}");
    assert_eq!(link.ask(36, 12, &[]), Response::Ok);
    // A Measure of 10⁶ periods (varint C0 84 3D; 25 s of device time at
    // 40 kHz, longer in emulated time) runs …
    const MILLION: [u8; 3] = [0xC0, 0x84, 0x3D];
    assert_eq!(link.ask(25, 8, &MILLION), Response::Ok);
    assert!(link.status(26).measuring);
    assert_eq!(link.ask(27, 9, &[]), Response::Error(WireError::NotReady));
    // … until Reset aborts it: not measuring, no estimate, and a new Measure
    // is accepted (not Busy).
    assert_eq!(link.ask(28, 13, &[]), Response::Ok);
    assert!(!link.status(29).measuring);
    assert_eq!(link.ask(30, 9, &[]), Response::Error(WireError::NotReady));
    assert_eq!(link.ask(31, 8, &MILLION), Response::Ok);
    assert_eq!(link.ask(32, 13, &[]), Response::Ok);
}

/// Protocol v8 (docs/protocol.md, "DSP load"): the firmware measures the
/// time of its DSP work per half-buffer. Under `-icount shift=0` the QEMU
/// build's count is instructions (SysTick calibrated at boot): with the
/// drive running, the load is at least the settled DDS refill's — 41
/// instructions per sample (`predict_cost`), 64 samples of a 21 504-cycle
/// half-buffer: 12.2 % — and below 100 % (the work of a half-buffer fits
/// in it); the maximum is at least the last, and `Reset` (13) clears the
/// maximum only. Without `-icount` the calibration is refused (the clock
/// follows the host's) and the firmware reports none, as the virtual
/// device.
#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn the_firmware_measures_its_dsp_load_under_icount() {
    {
        let q = qemu();
        let mut link = RawLink::connect(&q);
        link.sync();
        let st = link.status(1);
        assert_eq!(
            (st.cpu_load_pct, st.cpu_load_max_pct),
            (None, None),
            "{st:?}"
        );
    }
    let q = qemu_with_args("FIRMWARE_ELF", "qemu", &["-icount", "shift=0"]);
    let mut link = RawLink::connect(&q);
    link.sync();
    // SetDrive (2): 20 kHz (f64), Δu_z 1 µm, Δu_x 0.3 µm, u_z0 3 µm, φ 0.5 rad
    // (f32 each); Start (3).
    let mut drive = 20e3f64.to_le_bytes().to_vec();
    for x in [1e-6f32, 3e-7, 3e-6, 0.5] {
        drive.extend(x.to_le_bytes());
    }
    let r = link.ask(2, 2, &drive);
    assert!(!matches!(r, Response::Error(_)), "{r:?}");
    assert_eq!(link.ask(3, 3, &[]), Response::Ok);
    std::thread::sleep(Duration::from_millis(1500));
    let refill = 41.0 * 64.0 * 100.0 / 21_504.0;
    let st = link.status(4);
    let (Some(now), Some(max)) = (st.cpu_load_pct, st.cpu_load_max_pct) else {
        panic!("no load measured under -icount: {st:?}")
    };
    println!("cpu load {now} %, max {max} % (the refill alone {refill:.1} %)");
    assert!(st.running && st.faults == 0, "{st:?}");
    assert!(now >= refill && now < 100.0, "{now} %");
    assert!(max >= now, "{max} < {now}");
    // Reset: the maximum starts over from the half-buffers measured since
    // (the drive ramps down: they are still processed).
    assert_eq!(link.ask(5, 13, &[]), Response::Ok);
    std::thread::sleep(Duration::from_millis(300));
    let st = link.status(6);
    let after = st
        .cpu_load_max_pct
        .expect("a half-buffer measured since Reset");
    assert!(after < 100.0, "{after} %");
    println!("after Reset: max {after} %");
}

/// The fields of a `ControlSetting` by hand (docs/protocol.md, Structures):
/// `on: bool`, `target_mu: f32`, `v0_m_s: f32`, `gain: f32`, `periods`
/// (varint, < 128 here), `rate_m_per_s: f32`.
fn control_fields(on: bool, target_mu: f32) -> Vec<u8> {
    let mut f = vec![u8::from(on)];
    f.extend(target_mu.to_le_bytes());
    f.extend(0.004f32.to_le_bytes()); // v0 = 4 mm/s
    f.extend(0.7f32.to_le_bytes()); // κ
    f.push(4); // periods
    f.extend(1e-3f32.to_le_bytes()); // rate = the board's slew
    f
}

#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn closed_loop_messages_on_the_firmware() {
    use model_core::select;
    use model_core::{Libm, Scene, SceneParams};
    let q = qemu();
    let mut link = RawLink::connect(&q);
    link.sync();
    // GetControl (16) at power-up: off, no update.
    let Response::Control(st) = link.ask(40, 16, &[]) else {
        panic!("GetControl: not a Control response")
    };
    assert!(!st.setting.on && st.last.update == 0, "{st:?}");
    // SetDrive (2): 40 kHz, Δu_z 1 µm, Δu_x 0.3 µm, u_z0 4 µm, φ 0.7 rad.
    let mut drive = 40e3f64.to_le_bytes().to_vec();
    for x in [1e-6f32, 0.3e-6, 4e-6, 0.7] {
        drive.extend(x.to_le_bytes());
    }
    let Response::Drive { applied, .. } = link.ask(41, 2, &drive) else {
        panic!("SetDrive refused")
    };
    // SetControl on (15) with the drive stopped: NotRunning; nothing changes.
    assert_eq!(
        link.ask(42, 15, &control_fields(true, 0.1)),
        Response::Error(WireError::NotRunning)
    );
    assert_eq!(link.ask(43, 3, &[]), Response::Ok); // Start
                                                    // The target: μ of the device's contact (μ0 0.3, k 1e7 N/m) at Δu_z = 1.5 µm
                                                    // and v0 = 4 mm/s by the host's f64 law, with the phase and frequency the
                                                    // DDS produces. The firmware's f32 search must find a Δu_z whose f64 μ is
                                                    // that target within the f32 solver's stated bound (FastF32, ≤ 1e-5 μ0
                                                    // by the f32_vectors check) plus the bisection's f32 resolution on Δu_z
                                                    // (2⁻²³·Δu_z·|∂μ/∂Δu_z|), both far below 1e-4·μ0 used here.
    let mu_of = |mu0: f64, duz: f64| {
        let scene = Scene::new(SceneParams {
            mu0,
            kz: 1e7,
            kx: 1e7,
            uz0: f64::from(4e-6f32),
            duz,
            dux: f64::from(0.3e-6f32),
            omega: std::f64::consts::TAU * applied.achieved.freq_hz,
            phi: applied.phase_rad,
        })
        .unwrap();
        match select::mu_within::<f64, Libm>(&scene, f64::from(0.004f32), 1e-8)
            .unwrap()
            .value
        {
            select::Value::Mu(m) => m * mu0,
            other => panic!("{other:?}"),
        }
    };
    let mu_at = |duz: f64| mu_of(f64::from(0.3f32), duz);
    let target = mu_at(1.5e-6) as f32;
    let Response::Control(st) = link.ask(44, 15, &control_fields(true, target)) else {
        panic!("SetControl on refused")
    };
    assert!(st.setting.on && st.setting.target_mu == target, "{st:?}");
    let ff = f64::from(st.feedforward_m);
    assert!(
        (0.0..=f64::from(st.limit_m)).contains(&ff),
        "feedforward {ff} outside [0, {}]",
        st.limit_m
    );
    // The lift-off limit (1 − 0.05)·u_z0 (docs/protocol.md, check 4).
    assert!(
        (f64::from(st.limit_m) - 0.95 * 4e-6).abs() < 1e-12,
        "{st:?}"
    );
    let got = mu_at(ff);
    assert!(
        (got - f64::from(target)).abs() <= 1e-4 * 0.3,
        "μ(feedforward {ff:e} m) = {got} against the target {target}"
    );
    // The loop runs on the emulated plant (firmware module `qemu`: μ0 = 0.24
    // where the device's model says 0.3, so the feedforward alone misses the
    // target and the integral trim must close the gap). Checked against an
    // independent computation, not against the loop's own estimate (which it
    // drives to the target by construction): the Δu_z* at which the host's
    // exact f64 solver gives the target for the *plant's* contact, found by
    // bisection. After 50 updates the mean command over 20 further updates
    // is there within (bias + noise)/|∂μ/∂Δu_z|: bias = the plant's
    // fixed-step bound 10·(1+b)/N²·μ0 (N = 8 sub-steps × 12.5 samples = 100
    // steps a period, 1 + b read off the exact solver's stated bound
    // 1e-9·(1+b)) plus the estimator's aliasing at 12.5
    // samples a period, allowed 1e-4 (3× the 2.7e-5 measured on the virtual
    // device at this drive without noise: `fricctl device --sim --sim-noise 0
    // --plant-mu0 0.24 … measure --periods 4000` against `fricctl mu`); noise
    // = 4 standard errors of one estimate (not divided by √20: successive
    // commands are correlated through the integral).
    let plant = |duz: f64| mu_of(0.24, duz);
    let (mut lo, mut hi) = (0.0, f64::from(st.limit_m));
    let f_lo = plant(lo) - f64::from(target);
    assert!(
        f_lo * (plant(hi) - f64::from(target)) < 0.0,
        "target not bracketed"
    );
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if (plant(mid) - f64::from(target)) * f_lo > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let duz_star = 0.5 * (lo + hi);
    let slope = (plant(duz_star + 1e-9) - plant(duz_star - 1e-9)) / 2e-9;
    let bound_b = {
        let scene = Scene::new(SceneParams {
            mu0: 0.24,
            kz: 1e7,
            kx: 1e7,
            uz0: f64::from(4e-6f32),
            duz: duz_star,
            dux: f64::from(0.3e-6f32),
            omega: std::f64::consts::TAU * applied.achieved.freq_hz,
            phi: applied.phase_rad,
        })
        .unwrap();
        let r = select::mu_within::<f64, Libm>(&scene, f64::from(0.004f32), 1e-8).unwrap();
        assert_eq!(r.method, select::Method::Exact, "{r:?}");
        r.bound / 1e-9
    };
    let t = Instant::now();
    let (mut cmds, mut ses, mut seen) = (Vec::new(), Vec::new(), 0);
    let last = loop {
        let Response::Control(st) = link.ask(45, 16, &[]) else {
            panic!("GetControl")
        };
        if st.last.update >= 50 && st.last.update != seen {
            seen = st.last.update;
            cmds.push(f64::from(st.last.amp_z_m));
            ses.push(f64::from(st.last.std_error));
            if cmds.len() == 20 {
                break st;
            }
        }
        assert!(
            t.elapsed() < Duration::from_secs(120),
            "the loop made {} updates in 120 s",
            st.last.update
        );
        std::thread::sleep(Duration::from_millis(5));
    };
    assert!(last.setting.on && !last.last.held, "{last:?}");
    let mean = cmds.iter().sum::<f64>() / 20.0;
    let se = ses.iter().sum::<f64>() / 20.0;
    let bias = 10.0 * bound_b / 100f64.powi(2) * 0.24 + 1e-4;
    let tol = (bias + 4.0 * se) / slope.abs();
    assert!(
        (mean - duz_star).abs() <= tol,
        "mean command {mean:e} m, exact Δu_z* {duz_star:e} m (slope {slope:e} /m), tolerance {tol:e}"
    );
    // The trim's direction is known: the plant's μ at the feedforward is below
    // the target (μ0 lower than the model's) and ∂μ/∂Δu_z < 0, so Δu_z went down.
    assert!(
        slope < 0.0 && plant(ff) < f64::from(target),
        "{slope} {}",
        plant(ff)
    );
    assert!(last.last.integral_m < 0.0, "{last:?}");
    // While the loop runs a Measure (8) is Busy; SetControl off → off.
    assert_eq!(link.ask(46, 8, &[4]), Response::Error(WireError::Busy));
    let Response::Control(st) = link.ask(47, 15, &control_fields(false, 0.0)) else {
        panic!("SetControl off")
    };
    assert!(!st.setting.on, "{st:?}");
    assert_eq!(link.ask(48, 4, &[]), Response::Ok); // Stop
}

/// The firmware's `status` as JSON.
fn status_json(q: &Qemu) -> Value {
    let o = dev(q, &["status"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `dev` that must succeed, as JSON.
fn ok(q: &Qemu, args: &[&str]) -> Value {
    let o = dev(q, args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

/// The README's lab session, typed against the firmware under QEMU, whose
/// plant (firmware module `qemu`) has μ0 = 0.24 while the device's model
/// says 0.3, k_z = k_x = 1e7 N/m, stage at 4 mm/s, ±1 count ADC noise:
/// drive set, start, measure, watch stopped with Ctrl-C, sweep, fit, scene
/// set from the fit, measure again. The drive: 2 kHz (250 samples a period,
/// where the estimator's aliasing bias is ~1e-6: README "Sweeps, fits"),
/// Δu_z = 2 µm, Δu_x = 0.3 µm, u_z0 = 4 µm, φ = 40°.
#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn lab_session_on_the_firmware() {
    let q = qemu();
    ok(&q, &drive_set("2000", "2e-6", "3e-7", "4e-6", Some("40")));
    ok(&q, &["start"]);
    let t = Instant::now();
    while status_json(&q)["settled"] != true {
        assert!(t.elapsed() < Duration::from_secs(20), "never settled");
        std::thread::sleep(Duration::from_millis(20));
    }
    // The motion pickups of the emulated plant (ideal transducers, no
    // pickup noise): the firmware's lock-ins measure the drive set, within
    // the pickups' rounding (±½ count of 5 nm per sample times the error
    // gain of a window of 4 blocks, one period at 2 kHz:
    // `integration_tests::lockin_error_gain`; that over the amplitudes on φ)
    // and the sine table's phases (< 1e-6 rad).
    let st = status_json(&q);
    let (az, ax) = (
        st["amp_z_measured_m"].as_f64().unwrap(),
        st["amp_x_measured_m"].as_f64().unwrap(),
    );
    let dtheta = std::f64::consts::TAU * 2e3 / 500e3;
    let b = 0.5 * integration_tests::lockin_error_gain(256, dtheta) * 5e-9;
    assert!(
        (az - 2e-6).abs() <= b && (ax - 3e-7).abs() <= b,
        "{st} (bound {b:e})"
    );
    let allowed = (b / 2e-6 + b / 3e-7 + 1e-6f64).to_degrees();
    let phi = st["phase_measured_deg"].as_f64().unwrap();
    assert!(
        (phi - 40.0).abs() <= allowed,
        "{st} (allowed {allowed} deg)"
    );
    // measure against the host's exact f64 solver for the *plant's* contact.
    let m = ok(&q, &["measure", "--periods", "200"]);
    assert_eq!(m["valid"], true, "{m}");
    let exact = common::host_mu_of_drive("0.24", "2000");
    let (mu, se) = (m["mu"].as_f64().unwrap(), m["std_error"].as_f64().unwrap());
    let want = exact["mu"].as_f64().unwrap();
    // 4 standard errors of the noise, plus the plant's fixed-step bound
    // 10·(1+b)/N²·μ0 with N = 8 sub-steps × 250 samples = 2000 steps a period
    // (1 + b read off the exact solver's stated bound 1e-9·(1+b), b = 0.3125
    // here): 7.9e-7; plus the estimator's aliasing at 250 samples a period,
    // allowed 2e-6 (the worst sampled-mean error over 48 sampling offsets of
    // an f64 simulation of this contact at this drive was 1.9e-6, found by
    // this test's audit; the virtual device's fit rms residual at 2 kHz is
    // 3.9e-7); plus the f32 plant: phases rounded to 24 bits (≤ 3.7e-7 rad),
    // fast-f32 sine 6.8e-8, ≤ 8 rotations of 1.2e-7 each: displacements off
    // by ≤ 1.4e-6 relative, forces by a few ulp (2.4e-7 relative), so μ ≈ 0.19
    // moves by < 1e-6.
    assert_eq!(exact["method"], "exact", "{exact}");
    let bound_b = exact["error_bound_over_mu0"].as_f64().unwrap() / 1e-9;
    assert!(
        (bound_b - (1.0 + 0.3 / (0.24 * 4.0))).abs() < 1e-9,
        "{exact}"
    );
    let fixed_step = 10.0 * bound_b / 2000f64.powi(2) * 0.24;
    let tol = 4.0 * se + fixed_step + 2e-6 + 1e-6;
    assert!(
        (mu - want).abs() <= tol,
        "firmware measured {mu} ± {se}, exact {want}, tolerance {tol}"
    );

    // watch --csv stopped with Ctrl-C: exit 0, header and whole rows, stream stopped.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("mu.csv");
    let addr = format!("127.0.0.1:{}", q.port);
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_fricctl"))
        .args(["device", "--tcp", &addr, "watch", "--periods", "200"])
        .arg("--csv")
        .arg(&csv)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    std::io::BufRead::read_line(&mut out, &mut first).unwrap();
    assert!(first.starts_with('#') && first.contains("mu"), "{first}");
    let st = common::signal_and_wait(&mut child, "-INT", 10, "watch");
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert!(st.success(), "{st:?}: {err}");
    assert!(err.contains("interrupted: stream stopped"), "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.starts_with("seq,dropped,mu,std_error,valid,"),
        "{text}"
    );
    assert!(text.lines().count() >= 2 && text.ends_with('\n'), "{text}");
    // Every row whole, valid, of 200 periods, and μ within the first
    // measurement's tolerance plus 4 of its own standard errors.
    for row in text.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!(f.len(), 11, "{row}");
        assert_eq!((f[4], f[6]), ("true", "200"), "{row}");
        let (mu_r, se_r): (f64, f64) = (f[2].parse().unwrap(), f[3].parse().unwrap());
        assert!((mu_r - want).abs() <= tol + 4.0 * se_r, "{row}");
    }
    assert_eq!(status_json(&q)["measuring"], false);

    // sweep φ over 7 points, fit μ0, apply it.
    let sweep_csv = dir.path().join("sweep.csv");
    let mut args = common::sweep_args(sweep_csv.to_str().unwrap(), "7");
    args.extend(["--settle-periods", "20"]);
    let s = ok(&q, &args);
    let rows = s["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 7);
    assert!(rows.iter().all(|r| r["valid"] == true), "{s}");
    let fit_json = dir.path().join("fit.json");
    let fr = common::fit(&sweep_csv, "mu0", &fit_json);
    common::assert_fit_recovers(&fr, "mu0", 0.24);
    let row_se = rows[1]["std_error"].as_f64().unwrap();
    // The model's μ at φ = 30° before the fit (μ0 = 0.3), from the sweep's row.
    assert_eq!(rows[1]["value"], 30.0, "{s}");
    let before = rows[1]["predicted_mu"].as_f64().unwrap();
    ok(
        &q,
        &["scene", "set", "--from-fit", fit_json.to_str().unwrap()],
    );

    // measure again, at φ = 30° (one of the sweep's phases, in stick-slip:
    // at 180° the contact slides throughout, μ = μ0, which would only compare
    // two μ0's): now the model agrees.
    ok(&q, &drive_set("2000", "2e-6", "3e-7", "4e-6", Some("30")));
    let t = Instant::now();
    while status_json(&q)["settled"] != true {
        assert!(t.elapsed() < Duration::from_secs(20), "never settled");
        std::thread::sleep(Duration::from_millis(20));
    }
    let m = ok(&q, &["measure", "--periods", "200"]);
    let p = ok(&q, &["predict", "--v0", "0.004"]);
    let (d, tol) = common::measure_vs_predict(&m, &p, &fr, row_se);
    assert!(d <= tol, "measured {m}, predicted {p}, tolerance {tol}");
    let mu_m = m["mu"].as_f64().unwrap();
    assert!((mu_m - before).abs() > 10.0 * tol, "{mu_m} {before} {tol}");
}

/// The conformance report's provocation, on the firmware: the drive at the
/// top of the offset range with no normal amplitude presses the emulated
/// contact until the normal force saturates the ADC; a stream's estimate
/// sees it. The firmware must latch ADC_SATURATED *and* enter the safe state
/// (one fault path, `board/src/device/fault.rs`): drive stopped,
/// every output ramped to 0, one `RampDone`, the stream ended by the
/// refusal, `Start` refused until `ResetFaults`.
#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_ELF is set)"]
fn adc_saturation_reaches_the_safe_state_on_the_firmware() {
    use board::device::faults;
    let q = qemu();
    let top = ok(&q, &["info"])["max_offset_z_m"].as_f64().unwrap();
    let top = format!("{top:e}");
    ok(
        &q,
        &[
            "drive",
            "set",
            "--open-loop",
            "--freq",
            "40000",
            "--amp-z",
            "0",
            "--amp-x",
            "1e-6",
            "--offset-z",
            &top,
            "--phase-deg",
            "0",
        ],
    );
    ok(&q, &["start"]);
    let mut link = RawLink::connect(&q);
    link.sync();
    link.tele.clear();
    // Stream{on: true, periods: 100}.
    assert_eq!(link.ask(40, 10, &[1, 100]), Response::Ok);
    let mut seq = 41u8;
    let t = Instant::now();
    let faulted = loop {
        let st = link.status(seq);
        seq += 1;
        if st.faults != 0 {
            break st;
        }
        assert!(t.elapsed() < Duration::from_secs(20), "no fault: {st:?}");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(faulted.faults, faults::ADC_SATURATED, "{faulted:?}");
    assert!(
        !faulted.running,
        "the fault stops the drive at once: {faulted:?}"
    );
    // The ramps to rest: 8.19 µm at 1 µm/ms ≈ 8.2 ms of device time.
    let t = Instant::now();
    let st = loop {
        let st = link.status(seq);
        seq += 1;
        if st.settled {
            break st;
        }
        assert!(
            t.elapsed() < Duration::from_secs(20),
            "never settled: {st:?}"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(
        (
            st.out_amp_z_m,
            st.out_amp_x_m,
            st.out_offset_z_m,
            st.running
        ),
        (0.0, 0.0, 0.0, false),
        "{st:?}"
    );
    // Telemetry after the fault: its Fault, the stream's end, one RampDone.
    let _ = link.status(seq);
    seq += 1;
    let after: Vec<_> = link
        .tele
        .iter()
        .skip_while(|t| !matches!(t, Telemetry::Fault(_)))
        .filter(|t| !matches!(t, Telemetry::Estimate(_)))
        .copied()
        .collect();
    assert_eq!(
        after.first(),
        Some(&Telemetry::Fault(faults::ADC_SATURATED))
    );
    assert!(
        after.contains(&Telemetry::StreamStopped(StreamEnd::Refused(
            WireError::Faulted(faults::ADC_SATURATED)
        ))),
        "{after:?}"
    );
    assert_eq!(
        after.iter().filter(|t| **t == Telemetry::RampDone).count(),
        1,
        "{after:?}"
    );
    // Start (3) refused until ResetFaults (12).
    assert_eq!(
        link.ask(seq, 3, &[]),
        Response::Error(WireError::Faulted(faults::ADC_SATURATED))
    );
    assert_eq!(link.ask(seq + 1, 12, &[]), Response::Ok);
    assert_eq!(link.ask(seq + 2, 4, &[]), Response::Ok);
}

/// The resonant bench under QEMU (the firmware built with `--features
/// qemu-resonant`, `FIRMWARE_RESONANT_ELF` or built here: the bench's modes, 20 300 Hz
/// Q 300 and 19 700 Hz Q 200 with the contact's load Q 2000, in the
/// firmware's own f32 plant): `identify` finds both resonances within
/// 0.1 % and both (loaded) Q within 10 %; the displacement mode then holds
/// the measured amplitudes within 1 % and φ within 1°, `measure` agrees
/// with `predict` within 2 % (the device's contact set to the plant's) and
/// the normal peak stays below the lift-off limit — the virtual device's
/// session (`tests/device.rs`, `identify_then_…`) on the firmware.
#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_RESONANT_ELF is set)"]
fn identify_and_the_displacement_mode_on_the_firmware() {
    let q = qemu_with("FIRMWARE_RESONANT_ELF", "qemu-resonant");
    ok(&q, &drive_set("20000", "0", "0", "4e-6", None));
    let t0 = Instant::now();
    let id = ok(&q, &["identify"]);
    eprintln!("identify under QEMU: {:.1} s", t0.elapsed().as_secs_f64());
    let loaded = |q: f64| 1.0 / (1.0 / q + 1.0 / 2000.0);
    for (key, truth, tol) in [
        ("resonance_z_hz", 20_300.0, 1e-3),
        ("resonance_x_hz", 19_700.0, 1e-3),
        ("q_z", loaded(300.0), 0.1),
        ("q_x", loaded(200.0), 0.1),
    ] {
        let v = id[key].as_f64().unwrap();
        eprintln!("{key} = {v} (truth {truth})");
        assert!((v / truth - 1.0).abs() <= tol, "{key} = {v}, truth {truth}");
    }
    ok(
        &q,
        &[
            "scene", "set", "--mu0", "0.24", "--kz", "1e7", "--kx", "1e7",
        ],
    );
    let plain: Vec<&str> = DRIVE
        .iter()
        .copied()
        .filter(|a| *a != "--open-loop")
        .collect();
    ok(&q, &plain);
    ok(&q, &["start"]);
    let t = Instant::now();
    let st = loop {
        let st = ok(&q, &["status"]);
        if st["settled"] == true {
            break st;
        }
        assert!(t.elapsed() < Duration::from_secs(30), "{st}");
        std::thread::sleep(Duration::from_millis(100));
    };
    eprintln!("{st}");
    assert_eq!(st["drive_mode"], "displacement");
    let f = |k: &str| st[k].as_f64().unwrap();
    assert!((f("amp_z_measured_m") / 2e-6 - 1.0).abs() <= 0.01, "{st}");
    assert!((f("amp_x_measured_m") / 3e-7 - 1.0).abs() <= 0.01, "{st}");
    assert!((f("phase_measured_deg") - 40.0).abs() <= 1.0, "{st}");
    assert!(f("amp_z_peak_m") < 0.95 * 4e-6, "{st}");
    let m = ok(&q, &["measure", "--periods", "4000"])["mu"]
        .as_f64()
        .unwrap();
    let p = ok(&q, &["predict", "--v0", "0.004"])["mu"]
        .as_f64()
        .unwrap();
    eprintln!("measure {m}, predict {p}");
    assert!((m / p - 1.0).abs() <= 0.02, "measure {m} vs predict {p}");
}

/// Issue 35: a whole session on the firmware with the bench's resonant
/// transducers (`qemu-resonant`) under `-icount shift=0`, where the
/// firmware times each half-buffer's DSP work in instructions (protocol
/// v8): identify, the displacement mode with `--track z`, measure, a
/// stream of estimates (`watch`), then the μ loop on — and `Status`'s
/// `cpu_load_max_pct`, the largest half-buffer since power-up, stays
/// within the deadline (100 %: `predict_cost`'s worst half-buffer with
/// everything on is 89.0 %, this session's largest 95.1 % in one run;
/// issue 35's target, 30 %, is not met yet) with no overrun or underrun
/// fault latched.
#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target (builds the firmware unless FIRMWARE_RESONANT_ELF is set)"]
fn a_whole_session_keeps_the_dsp_load_within_its_deadline() {
    let q = qemu_with_args(
        "FIRMWARE_RESONANT_ELF",
        "qemu-resonant",
        &["-icount", "shift=0"],
    );
    ok(&q, &drive_set("20000", "0", "0", "4e-6", None));
    let t0 = Instant::now();
    // Each point settles 20 ms (≈ 5 τ of these modes)
    // instead of the default's plan for a Q-2000 mode: the half-buffers'
    // work does not depend on it, and the default identify runs under
    // QEMU in `identify_and_the_displacement_mode_on_the_firmware`.
    ok(&q, &["identify", "--settle-ms", "20"]);
    eprintln!(
        "identify under -icount: {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    ok(
        &q,
        &[
            "scene", "set", "--mu0", "0.24", "--kz", "1e7", "--kx", "1e7",
        ],
    );
    let mut tracked: Vec<&str> = DRIVE
        .iter()
        .copied()
        .filter(|a| *a != "--open-loop")
        .collect();
    tracked.extend(["--track", "z"]);
    ok(&q, &tracked);
    ok(&q, &["start"]);
    let t = Instant::now();
    loop {
        let st = ok(&q, &["status"]);
        if st["settled"] == true && st["locked"] == true {
            break;
        }
        assert!(t.elapsed() < Duration::from_secs(60), "{st}");
        std::thread::sleep(Duration::from_millis(200));
    }
    ok(&q, &["measure", "--periods", "4000"]);
    let o = dev(&q, &["watch", "--count", "3", "--periods", "1000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p = ok(&q, &["predict", "--v0", "0.004"])["mu"]
        .as_f64()
        .unwrap();
    let target = format!("{}", 0.98 * p);
    ok(&q, &["control", "--target-mu", &target, "--v0", "0.004"]);
    std::thread::sleep(Duration::from_secs(3));
    let c = ok(&q, &["control", "status"]);
    eprintln!("control: {c}");
    let st = ok(&q, &["status"]);
    eprintln!("{st}");
    let (now, max) = (
        st["cpu_load_pct"].as_f64().expect("measured under -icount"),
        st["cpu_load_max_pct"]
            .as_f64()
            .expect("measured under -icount"),
    );
    println!(
        "whole session: DSP load now {now:.1} %, largest half-buffer since power-up {max:.1} %"
    );
    assert_eq!(st["faults"], serde_json::json!([]), "{st}");
    assert!(st["running"] == true, "{st}");
    assert!(max >= now && max <= 100.0, "largest half-buffer {max} %");
}

/// Issue 25's tracking scenario on the firmware (`--features qemu-drift`:
/// the normal resonance at 20 100 Hz drifting by −20 Hz per second of
/// device time): `identify` under the drift, `drive set --freq 20100 …
/// --track z`, `start`; the tracking locks and then follows 100 Hz of drift
/// (5 s of device time, read from the frequency it tracks: the drift is
/// exact), during which every status shows the lock and `|tracking_error_hz|`
/// within 0.2 % of the frequency (the bound); `measure`
/// agrees with `predict` within 2 % (the estimator's noise at 4 000
/// periods is ≈ 0.1 %, the device's f32 model a part in 10⁵).
#[test]
#[ignore = "needs qemu-system-arm; run with --ignored"]
fn tracking_on_the_firmware() {
    let q = qemu_with("FIRMWARE_DRIFT_ELF", "qemu-drift");
    ok(&q, &drive_set("20100", "0", "0", "4e-6", None));
    let t0 = Instant::now();
    // Each point settles 20 ms (≈ 5 τ of this Q-261 mode): the default
    // plans for a Q-2000 mode (160 ms a coarse point), during which the
    // resonance drifts 3 Hz a point and the fine pass, ±2 coarse steps
    // around the coarse peak, can miss it ("no resonance in the span").
    let id = ok(&q, &["identify", "--settle-ms", "20"]);
    let f_id = id["resonance_z_hz"].as_f64().unwrap();
    eprintln!(
        "identify under QEMU with drift: {:.1} s, f_r {f_id} Hz",
        t0.elapsed().as_secs_f64()
    );
    // The resonance moved during identify (device time), never upwards.
    assert!(f_id < 20_100.0 && f_id > 19_900.0, "{id}");
    ok(
        &q,
        &[
            "scene", "set", "--mu0", "0.24", "--kz", "1e7", "--kx", "1e7",
        ],
    );
    ok(
        &q,
        &[
            "drive",
            "set",
            "--freq",
            "20100",
            "--amp-z",
            "2e-6",
            "--amp-x",
            "3e-7",
            "--offset-z",
            "4e-6",
            "--phase-deg",
            "40",
            "--track",
            "z",
        ],
    );
    ok(&q, &["start"]);
    let t = Instant::now();
    let f_lock = loop {
        let st = ok(&q, &["status"]);
        assert_eq!(st["faults"], serde_json::json!([]), "{st}");
        if st["locked"] == true {
            eprintln!("locked after {:.1} s wall: {st}", t.elapsed().as_secs_f64());
            break st["frequency_hz"].as_f64().unwrap();
        }
        assert!(t.elapsed() < Duration::from_secs(60), "no lock: {st}");
        std::thread::sleep(Duration::from_millis(200));
    };
    let t = Instant::now();
    loop {
        let st = ok(&q, &["status"]);
        assert_eq!(st["faults"], serde_json::json!([]), "{st}");
        assert_eq!(st["locked"], true, "{st}");
        let f = st["frequency_hz"].as_f64().unwrap();
        let e = st["tracking_error_hz"].as_f64().unwrap();
        assert!(e.abs() <= 0.002 * f, "{st}");
        if f <= f_lock - 100.0 {
            eprintln!(
                "followed 100 Hz in {:.1} s wall: {st}",
                t.elapsed().as_secs_f64()
            );
            break;
        }
        assert!(
            t.elapsed() < Duration::from_secs(180),
            "drift not followed: {st}"
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    let m = ok(&q, &["measure", "--periods", "4000"])["mu"]
        .as_f64()
        .unwrap();
    let p = ok(&q, &["predict", "--v0", "0.004"])["mu"]
        .as_f64()
        .unwrap();
    eprintln!("measure {m}, predict {p}");
    assert!((m / p - 1.0).abs() <= 0.02, "measure {m} vs predict {p}");
}
