//! The real firmware binary under QEMU (netduinoplus2 = STM32F405), driven
//! through `fricctl device --tcp`. Needs `qemu-system-arm` and the firmware
//! built with `--features qemu`; `.ci/run` does both and runs
//! `cargo test -p host-cli --test qemu -- --ignored` with `FIRMWARE_ELF` set.

use std::io::Write;
use std::net::TcpStream;
use std::process::{Child, Command as StdCommand, Stdio};
use std::time::{Duration, Instant};

mod common;

use assert_cmd::Command;
use model_core::protocol::{Body, Request, Response, WireError, PROTOCOL_VERSION};
use serde_json::Value;

struct Qemu {
    child: Child,
    port: u16,
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
    let elf = std::env::var("FIRMWARE_ELF")
        .expect("FIRMWARE_ELF = path of the firmware built with --features qemu");
    let port = free_port();
    let child = StdCommand::new("qemu-system-arm")
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
        .arg(format!("tcp:127.0.0.1:{port},server=on,wait=off"))
        .args([
            "-semihosting-config",
            "enable=on,target=native",
            "-kernel",
            &elf,
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("qemu-system-arm");
    // Wait until QEMU listens.
    let t = Instant::now();
    while TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "QEMU did not open its serial port"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // The probe connection above was closed; give the firmware time to enable USART2
    // (bytes sent before that are dropped by the emulated USART; the CLI retries anyway).
    std::thread::sleep(Duration::from_millis(300));
    Qemu { child, port }
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
#[ignore = "needs qemu-system-arm and FIRMWARE_ELF (run by .ci/run)"]
fn real_firmware_under_qemu() {
    let q = qemu();
    let o = dev(&q, &["info"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["board"], "STM32F405");
    assert_eq!(info["protocol"], PROTOCOL_VERSION);
    let o = dev(
        &q,
        &[
            "drive",
            "set",
            "--freq",
            "20000",
            "--amp-z",
            "2e-6",
            "--amp-x",
            "3e-7",
            "--offset-z",
            "4e-6",
            "--phase-deg",
            "40",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before = dev(&q, &["drive", "get"]).stdout;
    // Lift-off refused, nothing changed.
    let o = dev(
        &q,
        &[
            "drive",
            "set",
            "--freq",
            "20000",
            "--amp-z",
            "3.9e-6",
            "--amp-x",
            "3e-7",
            "--offset-z",
            "4e-6",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("lift"));
    assert_eq!(dev(&q, &["drive", "get"]).stdout, before);
    // Prediction in f32 on the emulated M4F against the host's f64 model.
    let o = dev(&q, &["predict", "--v0", "0.004"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p: Value = serde_json::from_slice(&o.stdout).unwrap();
    let pred = p["Prediction"]["prediction"]["mu"].as_f64().unwrap();
    let host = common::host_mu_of_test_drive();
    assert!(
        (pred - host["mu"].as_f64().unwrap()).abs() <= 1e-5,
        "{pred} vs {host}"
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
