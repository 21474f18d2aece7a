//! Helpers shared by the integration tests of `fricctl`: running the binary
//! ([`cli`]), the brute-force mean normal force of a curved profile
//! ([`normal`]), the virtual device on a pty ([`sim`]) and the raw protocol of
//! the device tests (pty) and the QEMU test (TCP) (this module).
#![allow(dead_code)]

pub mod cli;
pub mod liftoff;
pub mod normal;
pub mod sim;

use std::io::Read;
use std::time::{Duration, Instant};

use board::protocol::{
    decode, encode, Body, Deframed, Deframer, Frame, Request, CRC, MAX_FRAME, PROTOCOL_VERSION,
};

/// `drive set --open-loop` (voltage mode: the tests' devices have ideal
/// transducers) with the devices tests' drive: 20 kHz, Δu_z = 2 µm,
/// Δu_x = 0.3 µm, u_z0 = 4 µm, φ = 40° (the drive of
/// [`host_mu_of_test_drive`]).
pub const DRIVE: &[&str] = &[
    "drive",
    "set",
    "--open-loop",
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

/// `device drive set --open-loop --freq FREQ --amp-z AMP_Z --amp-x AMP_X
/// --offset-z OFFSET_Z [--phase-deg PHASE_DEG]` (Hz, m, m, m, degrees).
pub fn drive_set<'a>(
    freq: &'a str,
    amp_z: &'a str,
    amp_x: &'a str,
    offset_z: &'a str,
    phase_deg: Option<&'a str>,
) -> Vec<&'a str> {
    let mut v = vec![
        "drive",
        "set",
        "--open-loop",
        "--freq",
        freq,
        "--amp-z",
        amp_z,
        "--amp-x",
        amp_x,
        "--offset-z",
        offset_z,
    ];
    if let Some(p) = phase_deg {
        v.extend(["--phase-deg", p]);
    }
    v
}

/// An encoded request frame.
pub fn req(seq: u32, r: Request) -> Vec<u8> {
    let mut b = [0u8; MAX_FRAME];
    encode(
        &Frame {
            version: PROTOCOL_VERSION,
            seq,
            body: Body::Request(r),
        },
        &mut b,
    )
    .unwrap()
    .to_vec()
}

/// A frame around hand-made payload bytes (valid CRC and COBS).
pub fn raw_frame(raw: &[u8]) -> Vec<u8> {
    let mut v = raw.to_vec();
    v.extend(CRC.checksum(raw).to_le_bytes());
    let mut out = vec![0u8; v.len() + 2];
    let n = cobs::encode(&v, &mut out);
    out.truncate(n);
    out.push(0);
    out
}

/// The same request with one CRC byte altered (COBS stays valid).
pub fn corrupt_crc(mut b: Vec<u8>) -> Vec<u8> {
    let k = b.len() - 2;
    b[k] = if b[k] == 0x55 { 0x56 } else { 0x55 };
    b
}

/// Reads up to `want` response frames (telemetry skipped) within 10 s.
pub fn read_responses<R: Read + ?Sized>(r: &mut R, want: usize) -> Vec<Frame> {
    let mut df = Deframer::default();
    let mut out = Vec::new();
    let t = Instant::now();
    let mut b = [0u8; 64];
    while out.len() < want && t.elapsed() < Duration::from_secs(10) {
        if let Ok(n) = r.read(&mut b) {
            for &x in &b[..n] {
                // Whole frames arrive within ms: the inter-byte timeout never
                // applies here, so a constant clock is fine.
                if let Deframed::Frame(f) = df.push(x, 0) {
                    if let Ok(fr) = decode(f) {
                        if matches!(fr.body, Body::Response(_)) {
                            out.push(fr);
                        }
                    }
                }
            }
        }
    }
    out
}

/// `fricctl mu --json` on the host (f64) for the scene and drive the device
/// tests set on the board (μ0 = 0.3, k_z = k_x = 1e7 N/m, u_z0 = 4 µm,
/// Δu_z = 2 µm, Δu_x = 0.3 µm, 20 kHz, φ = 40°) at v0 = 4 mm/s.
pub fn host_mu_of_test_drive() -> serde_json::Value {
    host_mu_of_drive("0.3", "20000")
}

/// `fricctl mu --json` for the test drive (k_z = k_x = 1e7 N/m, u_z0 = 4 µm,
/// Δu_z = 2 µm, Δu_x = 0.3 µm, φ = 40°, v0 = 4 mm/s) with contact `mu0` at
/// frequency `freq` (Hz).
pub fn host_mu_of_drive(mu0: &str, freq: &str) -> serde_json::Value {
    cli::json(&[
        "mu",
        "--mu0",
        mu0,
        "--kz",
        "1e7",
        "--kx",
        "1e7",
        "--uz0",
        "4e-6",
        "--duz",
        "2e-6",
        "--dux",
        "3e-7",
        "--freq",
        freq,
        "--phi-deg",
        "40",
        "--v0",
        "0.004",
        "--json",
    ])
}

/// The acceptance of a fit of `key`: within 2 % of the plant's
/// `truth`, and an interval covers it. A 95 % interval misses the truth in
/// 5 % of runs by design (the noise differs from run to run with the
/// timing), too often for a test; the check widens the fit's 95 % interval
/// (Student t, the fit's `dof`) to 99.9 %: half-width × t(0.9995)/t(0.975).
pub fn assert_fit_recovers(fr: &serde_json::Value, key: &str, truth: f64) {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let v = fr[key].as_f64().unwrap();
    assert!((v - truth).abs() < 0.02 * truth, "{key}: {fr}");
    let lo = fr[format!("{key}_ci95_low")].as_f64().unwrap();
    let hi = fr[format!("{key}_ci95_high")].as_f64().unwrap();
    let t = StudentsT::new(0.0, 1.0, fr["dof"].as_f64().unwrap()).unwrap();
    let half = 0.5 * (hi - lo) * t.inverse_cdf(0.9995) / t.inverse_cdf(0.975);
    assert!(
        (v - truth).abs() <= half,
        "{key}: 99.9 % half-width {half:e}: {fr}"
    );
}

/// How far a `measure` may be from the device's `predict` once the model is
/// the plant's fitted one, at one of the sweep's phases: the measurement is
/// μ + bias + n′ and the sweep row at that phase was μ_fit + r, with
/// r = bias − n (its residual: the plant's discretisation bias, sampled
/// estimator and sub-stepped plant against the exact solver, less the row's
/// noise n). The fit bounds every residual: Σr² = n_rows·rms², so
/// |r| ≤ √n_rows·rms. Hence |measured − predicted| ≤ 3σ′ + 3σ_row +
/// √n_rows·rms + the f32 prediction's error (< 1e-6: f32 vectors' worst
/// 5.5e-7·μ0 plus Δu rounding). `row_se` is σ_row, `n_rows` the fit's rows.
/// Returns (|measured − predicted|, tolerance).
pub fn measure_vs_predict(
    measure: &serde_json::Value,
    predict: &serde_json::Value,
    fit: &serde_json::Value,
    row_se: f64,
) -> (f64, f64) {
    let (mu_m, se) = (
        measure["mu"].as_f64().unwrap(),
        measure["std_error"].as_f64().unwrap(),
    );
    let mu_p = predict["mu"].as_f64().unwrap();
    let rms = fit["rms_residual_mu"].as_f64().unwrap();
    let n_rows = fit["rows_used"].as_f64().unwrap();
    (
        (mu_m - mu_p).abs(),
        3.0 * se + 3.0 * row_se + n_rows.sqrt() * rms + 1e-6,
    )
}

/// Sends `signal` (`kill SIGNAL PID`) to `child` and waits for it to end,
/// failing if it takes longer than `limit_s` seconds ("`what` ignored …").
pub fn signal_and_wait(
    child: &mut std::process::Child,
    signal: &str,
    limit_s: u64,
    what: &str,
) -> std::process::ExitStatus {
    let k = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let t = std::time::Instant::now();
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        assert!(
            t.elapsed() < std::time::Duration::from_secs(limit_s),
            "{what} ignored SIG{}",
            &signal[1..]
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// `fricctl fit --json --params PARAMS --data CSV --out OUT`, which must
/// give its result: exit 0, or exit 1 with the χ² verdict as its one line
/// (`error: doubtful: …`, docs/guide/fit.md: the result and `--out` are
/// written all the same, the JSON's `doubtful` holds the line). The
/// callers assert the recovered parameters; the verdict is printed.
pub fn fit(csv: &std::path::Path, params: &str, out: &std::path::Path) -> serde_json::Value {
    let o = assert_cmd::Command::cargo_bin("fricctl")
        .unwrap()
        .args(["fit", "--json", "--params", params, "--data"])
        .arg(csv)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let verdict = o.status.code() == Some(1)
        && err.trim().lines().count() == 1
        && err.starts_with("error: doubtful: ");
    assert!(o.status.success() || verdict, "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    if verdict {
        eprintln!("fit verdict: {}", err.trim());
        assert_eq!(v["doubtful"].as_str(), err.trim().strip_prefix("error: "));
    }
    v
}

/// `device sweep` of φ from 0 to 180° in `points` points of 200 periods
/// each at v0 = 4 mm/s into `csv` (the sessions of tests/sweep.rs and
/// tests/qemu.rs).
pub fn sweep_args<'a>(csv: &'a str, points: &'a str) -> Vec<&'a str> {
    vec![
        "sweep",
        "--param",
        "phase-deg",
        "--from",
        "0",
        "--to",
        "180",
        "--points",
        points,
        "--periods",
        "200",
        "--v0",
        "0.004",
        "--csv",
        csv,
    ]
}
