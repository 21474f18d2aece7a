//! `fricctl device` against the virtual device served on a real pty by
//! `fricctl sim-device --pty`: every command, refused commands that change
//! nothing, raw protocol abuse (garbage, bad CRC, oversize, cut-off frame,
//! unknown message, version mismatch), and a device that does not answer.

use std::io::{BufRead, BufReader, Write};
use std::process::{Child, Command as StdCommand, Stdio};
use std::time::{Duration, Instant};

mod common;

use assert_cmd::cargo::CommandCargoExt;
use assert_cmd::Command;
use model_core::protocol::{Body, Frame, Request, Response, WireError, PROTOCOL_VERSION};
use serde_json::Value;
use serialport::SerialPort;

struct Sim {
    child: Child,
    path: String,
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn sim() -> Sim {
    let mut child = StdCommand::cargo_bin("fricctl")
        .unwrap()
        .args(["sim-device", "--pty", "--seconds", "120"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let path = line.trim().to_string();
    assert!(path.starts_with("/dev/"), "{path}");
    Sim { child, path }
}

fn dev(s: &Sim, args: &[&str]) -> std::process::Output {
    Command::cargo_bin("fricctl")
        .unwrap()
        .args(["device", "--port", &s.path, "--json"])
        .args(args)
        .output()
        .unwrap()
}

fn ok_json(s: &Sim, args: &[&str]) -> Value {
    let o = dev(s, args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

const DRIVE: &[&str] = &[
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
];

/// How far the virtual device's measured μ may be from its prediction (both
/// absolute μ) for [`DRIVE`] at the sim's stage velocity 4 mm/s, with the
/// contact μ₀ = 0.3, k_z = k_x = 10⁷ N/m: a = 0.5, b = k_xΔu_x/(μ₀k_z u_z0) = 0.25,
/// φ = 40°, V = v₀/(ωW₀) = 0.004/(2π·20 kHz·1.2 µm) = 0.0265. The sum of
/// * sampling: the estimator averages 25 ADC samples per period of a stretch
///   with kinks — the brute-force range over sampling offsets of a plant at
///   25 × 32 steps per period (`integration_tests::sampling_error_range`; 4e-4 μ₀);
/// * ADC rounding: ≤ 0.5 LSB per sample, so f̄_x, f̄_z are off by ≤ 0.5·g_x,
///   0.5·g_z and μ = f̄_x/f̄_z by ≤ (0.5g_x + |μ|·0.5g_z)/f̄_z (1.5e-4);
/// * the plant's scheme at 800 steps per period, (1 + b)(10/N² + Nε)·μ₀ (6e-6);
/// * the prediction's f32 solver, 1e-6·(1 + b)·μ₀.
///
/// About 2.8e-4 in all (measured agreement ≈ 6e-5).
fn measured_vs_predicted_bound(estimate: &Value) -> f64 {
    let (a, b, phi) = (0.5, 0.25, 40f64.to_radians());
    let v = 0.004 / (std::f64::consts::TAU * 20e3 * 0.3 * 4e-6);
    let (lo, hi) = integration_tests::sampling_error_range(a, b, phi, v, 25, 32);
    let cfg = model_core::device::DeviceConfig::driver_board(0);
    let (gx, gz) = (f64::from(cfg.adc_x.gain), f64::from(cfg.adc_z.gain));
    let mu = estimate["mu"].as_f64().unwrap();
    let fz = estimate["fz_mean"].as_f64().unwrap();
    let adc = (0.5 * gx + mu.abs() * 0.5 * gz) / fz;
    let n = 800.0f64;
    let scheme = (1.0 + b) * (10.0 / (n * n) + n * f64::EPSILON);
    0.3 * (lo.abs().max(hi.abs()) + scheme + 1e-6 * (1.0 + b)) + adc
}

#[test]
fn every_command_over_a_pty() {
    let s = sim();
    let info = ok_json(&s, &["info"]);
    assert_eq!(info["protocol"], PROTOCOL_VERSION);
    assert_eq!(info["board"], "virtual device");
    let d = ok_json(&s, DRIVE);
    let f = d["Drive"]["applied"]["achieved"]["freq_hz"]
        .as_f64()
        .unwrap();
    assert!((f - 20_000.0).abs() < 0.001);
    assert_eq!(ok_json(&s, &["drive", "get"]), d);
    assert_eq!(
        ok_json(
            &s,
            &["scene", "set", "--mu0", "0.3", "--kz", "1e7", "--kx", "1e7"]
        ),
        "Ok"
    );
    assert!(
        (ok_json(&s, &["scene", "get"])["Contact"]["mu0"]
            .as_f64()
            .unwrap()
            - 0.3)
            .abs()
            < 1e-7
    );
    assert_eq!(ok_json(&s, &["start"]), "Ok");
    std::thread::sleep(Duration::from_millis(300)); // ramps (≈ 2 ms of device time)
    assert_eq!(ok_json(&s, &["status"])["Status"]["running"], true);
    let p = ok_json(&s, &["predict", "--v0", "0.004"]);
    let pred = p["Prediction"]["prediction"]["mu"].as_f64().unwrap();
    // The prediction equals the host model for the same scene (f32 tolerance).
    let host = common::host_mu_of_test_drive();
    assert!(
        (pred - host["mu"].as_f64().unwrap()).abs() < 1e-5,
        "{pred} vs {host}"
    );
    // The measurement of the simulated plant (stage at 4 mm/s, the sim's default) agrees.
    let e = ok_json(&s, &["measure", "--periods", "2000"]);
    let mu = e["Estimate"]["mu"].as_f64().unwrap();
    let allowed = measured_vs_predicted_bound(&e["Estimate"]);
    println!(
        "pty sim: measured {mu}, predicted {pred}, |Δ| = {:.1e} ≤ {allowed:.1e}",
        (mu - pred).abs()
    );
    assert!(
        (mu - pred).abs() <= allowed,
        "measured {mu}, predicted {pred} (bound {allowed:e})"
    );
    assert_eq!(e["Estimate"]["saturated"], false);
    // watch: two streamed estimates, recorded to CSV.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("w.csv");
    let o = dev(
        &s,
        &[
            "watch",
            "--periods",
            "200",
            "--count",
            "2",
            "--csv",
            csv.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 2);
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 3);
    assert_eq!(ok_json(&s, &["stop"]), "Ok");
    assert_eq!(ok_json(&s, &["reset-faults"]), "Ok");
}

#[test]
fn refused_commands_leave_the_drive_unchanged() {
    let s = sim();
    ok_json(&s, DRIVE);
    let before = ok_json(&s, &["drive", "get"]);
    // Lift-off: Δu_z above (1 − 0.05)·u_z0.
    let o = dev(
        &s,
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
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--amp-z") && err.contains("lift"), "{err}");
    // Out of range frequency: named, with the limits.
    let o = dev(
        &s,
        &[
            "drive",
            "set",
            "--freq",
            "5e6",
            "--amp-z",
            "1e-6",
            "--amp-x",
            "3e-7",
            "--offset-z",
            "4e-6",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--freq") && err.contains("100000"), "{err}");
    assert_eq!(ok_json(&s, &["drive", "get"]), before);
}

fn raw_port(s: &Sim) -> Box<dyn SerialPort> {
    serialport::new(&s.path, 115_200)
        .timeout(Duration::from_millis(100))
        .open()
        .unwrap()
}

fn err_of(f: &Frame) -> WireError {
    match f.body {
        Body::Response(Response::Error(e)) => e,
        other => panic!("{other:?}"),
    }
}

#[test]
fn protocol_abuse_over_the_pty() {
    let s = sim();
    let mut p = raw_port(&s);
    // Garbage, then a good request: one Malformed, then the answer.
    p.write_all(&[0x42, 0x13, 0x99, 0x00]).unwrap();
    p.write_all(&common::req(1, Request::Hello)).unwrap();
    let f = common::read_responses(&mut *p, 2);
    assert_eq!(err_of(&f[0]), WireError::Malformed);
    assert_eq!(f[1].seq, 1);
    // Corrupted CRC.
    p.write_all(&common::corrupt_crc(common::req(2, Request::GetStatus)))
        .unwrap();
    assert_eq!(
        err_of(&common::read_responses(&mut *p, 1)[0]),
        WireError::BadCrc
    );
    // Oversize frame.
    let mut big = vec![0x11u8; 700];
    big.push(0);
    p.write_all(&big).unwrap();
    assert_eq!(
        err_of(&common::read_responses(&mut *p, 1)[0]),
        WireError::Oversize
    );
    // A frame cut off mid-way, then a good one.
    let good = common::req(3, Request::GetContact);
    p.write_all(&good[..good.len() / 2]).unwrap();
    p.write_all(&common::req(4, Request::GetStatus)).unwrap();
    let f = common::read_responses(&mut *p, 1);
    assert!(matches!(
        err_of(&f[0]),
        WireError::Malformed | WireError::BadCrc
    ));
    p.write_all(&common::req(5, Request::GetStatus)).unwrap();
    let f = common::read_responses(&mut *p, 1);
    assert_eq!(f[0].seq, 5);
    // Unknown message id, version mismatch.
    p.write_all(&common::raw_frame(&[PROTOCOL_VERSION as u8, 6, 0, 77]))
        .unwrap();
    let f = common::read_responses(&mut *p, 1);
    assert_eq!((f[0].seq, err_of(&f[0])), (6, WireError::UnknownMessage));
    p.write_all(&common::raw_frame(&[9, 7, 0, 0])).unwrap();
    let f = common::read_responses(&mut *p, 1);
    assert_eq!(
        (f[0].seq, err_of(&f[0])),
        (
            7,
            WireError::VersionMismatch {
                device: PROTOCOL_VERSION
            }
        )
    );
}

#[test]
fn a_silent_device_times_out_with_a_clear_message() {
    // A pty pair where nobody answers on the other side.
    let (_master, slave) = serialport::TTYPort::pair().unwrap();
    let path = slave.name().unwrap();
    let t = Instant::now();
    let o = Command::cargo_bin("fricctl")
        .unwrap()
        .args([
            "device",
            "--port",
            &path,
            "--timeout-ms",
            "200",
            "--attempts",
            "2",
            "info",
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no answer") && err.contains(&path), "{err}");
    assert!(t.elapsed() < Duration::from_secs(5));
}

#[test]
fn in_process_virtual_device_keeps_its_state_and_measures() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("sim.json");
    let run = |args: &[&str]| {
        Command::cargo_bin("fricctl")
            .unwrap()
            .env("FRICCTL_SIM_STATE", &state)
            .args(["device", "--sim", "--json"])
            .args(args)
            .output()
            .unwrap()
    };
    assert!(run(DRIVE).status.success());
    assert!(run(&["start"]).status.success());
    let o = run(&["measure", "--periods", "2000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e: Value = serde_json::from_slice(&o.stdout).unwrap();
    let p: Value = serde_json::from_slice(&run(&["predict", "--v0", "0.004"]).stdout).unwrap();
    let (mu, pred) = (
        e["Estimate"]["mu"].as_f64().unwrap(),
        p["Prediction"]["prediction"]["mu"].as_f64().unwrap(),
    );
    let allowed = measured_vs_predicted_bound(&e["Estimate"]);
    println!(
        "in-process sim: measured {mu}, predicted {pred}, |Δ| = {:.1e} ≤ {allowed:.1e}",
        (mu - pred).abs()
    );
    assert!(
        (mu - pred).abs() <= allowed,
        "measured {mu}, predicted {pred} (bound {allowed:e})"
    );
    // `ports` lists candidates (possibly none here) as JSON.
    let o = Command::cargo_bin("fricctl")
        .unwrap()
        .args(["device", "--json", "ports"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(serde_json::from_slice::<Value>(&o.stdout)
        .unwrap()
        .is_array());
}

#[test]
fn invalid_estimates_exit_1_naming_the_reason_unless_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("sim.json");
    let run = |args: &[&str]| {
        Command::cargo_bin("fricctl")
            .unwrap()
            .env("FRICCTL_SIM_STATE", &state)
            .args(["device", "--sim", "--json"])
            .args(args)
            .output()
            .unwrap()
    };
    // A drive set but not started: the estimate is not valid (drive not running).
    assert!(run(DRIVE).status.success());
    let o = run(&["measure", "--periods", "200"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("invalid estimate") && err.contains("not_running"),
        "{err}"
    );
    let o = run(&["measure", "--periods", "200", "--allow-invalid"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(e["Estimate"]["valid"], false);
    assert!(e["Estimate"]["reasons"]
        .as_array()
        .unwrap()
        .contains(&Value::from("not_running")));
    // Started and settled: valid, with a standard error.
    assert!(run(&["start"]).status.success());
    let o = run(&["measure", "--periods", "2000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(e["Estimate"]["valid"], true);
    assert_eq!(e["Estimate"]["reasons"], serde_json::json!([]));
    let se = e["Estimate"]["std_error"].as_f64().unwrap();
    // ±1 count of uniform ADC noise (the sim's default) on f_x at 0.01 N/count
    // over N = 2000·12.5 samples, f̄_z = 40 N: σ/(f̄_z √N) = 0.01·(1/√3)/(40·158)
    // ≈ 9e-7; the batch scatter adds the plant's slow settling, so only the
    // order of magnitude is fixed: 1e-8 < se < 1e-3 (the μ agreement bound).
    assert!(se > 1e-8 && se < 1e-3, "{e}");
}

/// Sends a hand-made payload, returns the one response frame.
fn ask(p: &mut dyn SerialPort, payload: &[u8]) -> Frame {
    p.write_all(&common::raw_frame(payload)).unwrap();
    common::read_responses(p, 1).remove(0)
}

/// `GetStatus` (index 11) with seq `seq`, written from the spec.
fn raw_status(p: &mut dyn SerialPort, seq: u8) -> model_core::device::Status {
    match ask(p, &[2, seq, 0, 11]).body {
        Body::Response(Response::Status(st)) => st,
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_retried_measure_gets_the_same_answer_and_reset_ends_everything() {
    let s = sim();
    ok_json(&s, DRIVE);
    let mut p = raw_port(&s);
    let p = &mut *p;
    // Start (index 3); the ramps take ≈ 45 ms of device time.
    assert_eq!(ask(p, &[2, 30, 0, 3]).body, Body::Response(Response::Ok));
    std::thread::sleep(Duration::from_millis(300));
    // Measure{periods: 20000} with seq 40, written from the spec: version 02,
    // seq 28 (40), Body::Request 00, Request::Measure 08, periods varint a0 9c 01.
    let measure_40 = [2, 40, 0, 8, 0xa0, 0x9c, 0x01];
    let f = ask(p, &measure_40);
    assert_eq!((f.seq, f.body), (40, Body::Response(Response::Ok)));
    // The retry (same seq) while it runs: the same answer, not Busy.
    let f = ask(p, &measure_40);
    assert_eq!((f.seq, f.body), (40, Body::Response(Response::Ok)));
    assert!(raw_status(p, 43).measuring);
    // A new seq while it runs: Busy.
    let f = ask(p, &[2, 41, 0, 8, 0xa0, 0x9c, 0x01]);
    assert_eq!((f.seq, err_of(&f)), (41, WireError::Busy));
    // Reset (index 13): ends the measurement and stops the drive.
    let f = ask(p, &[2, 42, 0, 13]);
    assert_eq!((f.seq, f.body), (42, Body::Response(Response::Ok)));
    let st = raw_status(p, 44);
    assert!(!st.measuring && !st.running, "{st:?}");
    // A measurement that finished: its retry starts nothing.
    assert_eq!(ask(p, &[2, 45, 0, 3]).body, Body::Response(Response::Ok));
    std::thread::sleep(Duration::from_millis(300));
    let measure_50 = [2, 50, 0, 8, 0xc8, 0x01]; // 200 periods = 10 ms
    assert_eq!(ask(p, &measure_50).body, Body::Response(Response::Ok));
    std::thread::sleep(Duration::from_millis(500));
    assert!(!raw_status(p, 51).measuring);
    assert_eq!(ask(p, &measure_50).body, Body::Response(Response::Ok));
    assert!(!raw_status(p, 52).measuring);
}
