//! `fricctl device view` against `fricctl sim-device --tcp`: the page and its
//! assets are served, the controls answer as the CLI does (its refusals word
//! for word), `--read-only` refuses them, `--record` writes the CLI's keys,
//! bad `--listen` values are refused by name before the device is opened;
//! and `sim-device --fault-listen` latches a named fault. The page in a real
//! browser is `scripts/view_e2e.py` (`.ci/run`).

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use assert_cmd::cargo::CommandCargoExt;
use common::cli::fricctl;
use common::sim::{spawn, Sim};

/// A running `fricctl device --tcp ADDR view …` (killed on drop) and its URL.
struct View {
    child: Child,
    url: String,
}

impl Drop for View {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn view(sim: &Sim, flags: &[&str]) -> View {
    let mut child = std::process::Command::cargo_bin("fricctl")
        .unwrap()
        .args([
            "device",
            "--tcp",
            &sim.path,
            "view",
            "--listen",
            "127.0.0.1:0",
        ])
        .args(flags)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let url = line.trim().to_string();
    assert!(url.starts_with("http://127.0.0.1:"), "{url}");
    View { child, url }
}

/// One HTTP/1.1 request (`Connection: close`): (status, body).
fn http(url: &str, method: &str, path: &str, body: Option<&str>) -> (u16, String) {
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = TcpStream::connect(host).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let body = body.unwrap_or("");
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).unwrap();
    let text = String::from_utf8_lossy(&raw).to_string();
    let status: u16 = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = text
        .split_once("\r\n\r\n")
        .map(|(_, b)| b.to_string())
        .unwrap_or_default();
    (status, body)
}

/// `POST /api/action` with the CLI's words: (status, the answer's JSON).
fn action(v: &View, words: &[&str]) -> (u16, serde_json::Value) {
    let body = serde_json::json!({ "words": words }).to_string();
    let (status, text) = http(&v.url, "POST", "/api/action", Some(&body));
    (status, serde_json::from_str(&text).unwrap())
}

/// The open-loop drive of the device tests (ideal transducers: 20 kHz,
/// Δu_z 2 µm, Δu_x 0.3 µm, u_z0 4 µm, φ 40°).
const DRIVE: &[&str] = &[
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

#[test]
fn page_assets_controls_and_refusals_as_the_cli() {
    let sim = spawn(&["--tcp", "127.0.0.1:0", "--seconds", "300"]);
    let v = view(&sim, &[]);
    let (status, page) = http(&v.url, "GET", "/", None);
    assert_eq!(status, 200);
    assert!(
        page.contains("<title>fricctl device view</title>"),
        "{page}"
    );
    assert!(page.contains("/uPlot.iife.min.js"));
    // The plotting library is served from the binary (no CDN): uPlot's
    // minified build, 51 081 bytes.
    let (status, js) = http(&v.url, "GET", "/uPlot.iife.min.js", None);
    assert_eq!(status, 200);
    assert_eq!(js.len(), 51_081);
    assert!(js.contains("uPlot"));
    assert!(
        !page.contains("https://"),
        "the page loads nothing from the network"
    );

    // The controls are the CLI's commands, with its answers.
    let (status, a) = action(&v, DRIVE);
    assert_eq!(status, 200, "{a}");
    assert_eq!(a["ok"], true);
    assert!(
        a["message"]
            .as_str()
            .unwrap()
            .contains("phi            40 deg"),
        "{a}"
    );
    let (status, a) = action(&v, &["start"]);
    assert_eq!((status, a["ok"].as_bool()), (200, Some(true)), "{a}");
    // A drive above the lift-off guard: the CLI's one line, 422.
    let mut lifting = DRIVE.to_vec();
    lifting[6] = "9e-6";
    let (status, a) = action(&v, &lifting);
    assert_eq!(status, 422);
    assert_eq!(
        a["message"],
        "--amp-z: refused by the device: 9e-6 m would lift the contact off (limit 3.7999998e-6 m); \
         lower it, or allow lift-off on purpose with `fricctl device config --allow-liftoff`"
    );
    // A bad value is refused by the flag's own parser, naming the flag.
    let mut bad = DRIVE.to_vec();
    bad[12] = "nan";
    let (status, a) = action(&v, &bad);
    assert_eq!(status, 422);
    assert!(
        a["message"].as_str().unwrap().starts_with("--phase-deg: "),
        "{a}"
    );
    // Only the view's controls.
    let (status, a) = action(&v, &["identify"]);
    assert_eq!(status, 422);
    assert!(a["message"]
        .as_str()
        .unwrap()
        .contains("not one of the view's controls"));
    // The μ loop needs the stream stopped: the view does that first.
    let (status, a) = action(&v, &["control", "--target-mu", "0.1", "--v0", "0.004"]);
    assert_eq!(status, 200, "{a}");
    assert!(a["message"].as_str().unwrap().contains("loop on"), "{a}");
    let (status, a) = action(&v, &["control", "off"]);
    assert_eq!(status, 200, "{a}");
    let (status, _) = action(&v, &["stop"]);
    assert_eq!(status, 200);
}

#[test]
fn read_only_refuses_the_controls() {
    let sim = spawn(&["--tcp", "127.0.0.1:0", "--seconds", "120"]);
    let v = view(&sim, &["--read-only"]);
    let (status, a) = action(&v, &["start"]);
    assert_eq!(status, 403);
    assert_eq!(
        a["message"],
        "read-only view (--read-only): the controls are off"
    );
    // Nothing reached the device (one TCP client at a time: the view first).
    drop(v);
    let o = fricctl()
        .args(["device", "--tcp", &sim.path, "--json", "status"])
        .output()
        .unwrap();
    let st: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(st["running"], false);
}

#[test]
fn record_writes_the_cli_keys() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("view.csv");
    let sim = spawn(&["--tcp", "127.0.0.1:0", "--seconds", "120"]);
    let v = view(&sim, &["--record", csv.to_str().unwrap()]);
    assert_eq!(action(&v, DRIVE).0, 200);
    assert_eq!(action(&v, &["start"]).0, 200);
    let t0 = Instant::now();
    let text = loop {
        let text = std::fs::read_to_string(&csv).unwrap_or_default();
        if text.lines().filter(|l| l.contains(",estimate,")).count() >= 3 {
            break text;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "{text}");
        std::thread::sleep(Duration::from_millis(200));
    };
    drop(v);
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &header[..6],
        ["t_s", "kind", "mu", "std_error", "valid", "reasons"]
    );
    for k in [
        "phi_deg",
        "phase_measured_deg",
        "amp_z_peak_m",
        "frequency_hz",
        "faults",
    ] {
        assert!(header.contains(&k), "{k} in {header:?}");
    }
    let col = |k: &str| header.iter().position(|h| *h == k).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.iter().all(|r| r.len() == header.len()));
    // A status row with the drive as set.
    let st = rows
        .iter()
        .rev()
        .find(|r| r[col("kind")] == "status")
        .unwrap();
    assert_eq!(st[col("phi_deg")], "40.0");
    assert_eq!(st[col("uz0")], "4e-6");
    assert_eq!(st[col("running")], "true");
    // The lift-off guard, (1 − 5 %)·u_z0 in f32.
    assert_eq!(st[col("liftoff_limit_m")], "3.8e-6");
    // Estimates of the running drive near the model's μ (0.1085 for this
    // drive; the first ones may be in the soft start).
    let mu: f64 = rows
        .iter()
        .rev()
        .find(|r| r[col("kind")] == "estimate")
        .unwrap()[col("mu")]
    .parse()
    .unwrap();
    assert!((mu - 0.1085).abs() < 0.01, "mu {mu}");
}

#[test]
fn listen_is_checked_before_the_device_is_opened() {
    for (flags, msg) in [
        (
            ["--listen", "nonsense"],
            "--listen: 'nonsense' is not IP:PORT",
        ),
        (
            ["--listen", "0.0.0.0:0"],
            "--listen: 0.0.0.0:0 is not a loopback address",
        ),
        (["--status-ms", "5"], "--status-ms: must be ≥ 10 (got 5)"),
        (["--periods", "nan"], "--periods: 'nan' is not a number"),
    ] {
        // --tcp to a closed port: the refusal comes before any connection.
        let o = fricctl()
            .args(["device", "--tcp", "127.0.0.1:1", "view"])
            .args(flags)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.starts_with(&format!("error: {msg}")), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

#[test]
fn fault_side_channel_latches_a_named_fault() {
    let mut child = std::process::Command::cargo_bin("fricctl")
        .unwrap()
        .args(["sim-device", "--tcp", "127.0.0.1:0", "--seconds", "120"])
        .args(["--plant-ideal-transducers", "--fault-listen", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut addr = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut addr)
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    let side = line
        .strip_prefix("fault side channel on ")
        .and_then(|r| r.split_whitespace().next())
        .unwrap_or_else(|| panic!("{line}"))
        .to_string();
    let sim = Sim {
        child,
        path: addr.trim().to_string(),
    };
    let dev = |args: &[&str]| {
        let o = fricctl()
            .args(["device", "--tcp", &sim.path, "--json"])
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
    };
    dev(DRIVE);
    dev(&["start"]);
    assert_eq!(dev(&["status"])["running"], true);
    let mut s = TcpStream::connect(&side).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let mut answers = BufReader::new(s.try_clone().unwrap());
    let mut ask = |what: &str| {
        writeln!(s, "{what}").unwrap();
        let mut a = String::new();
        answers.read_line(&mut a).unwrap();
        a.trim().to_string()
    };
    assert!(
        ask("fire").starts_with("unknown fault 'fire': one of adc_saturated (1), dac_underrun (2)")
    );
    assert_eq!(ask("adc_overrun"), "latched adc_overrun");
    assert_eq!(ask("8"), "latched external");
    std::thread::sleep(Duration::from_millis(300));
    let st = dev(&["status"]);
    assert_eq!(st["faults"], serde_json::json!(["external", "adc_overrun"]));
    assert_eq!(st["running"], false);
    // The board's refusal while latched, and the way out.
    let o = fricctl()
        .args(["device", "--tcp", &sim.path, "start"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("a fault is latched (bits 0x18)"));
    dev(&["reset-faults"]);
    assert_eq!(dev(&["status"])["faults"], serde_json::json!([]));
    // Every bit the protocol cannot provoke on the virtual device (issue 41
    // §7: 2, 4, 8, 16, 128, 256), by name and by bit, each alone: it
    // latches, stops the running drive and is named by `status`; then
    // `reset-faults` clears it (self_test included: the virtual device
    // latches it once).
    for (name, bit) in [
        ("dac_underrun", 2),
        ("watchdog_reset", 4),
        ("external", 8),
        ("adc_overrun", 16),
        ("pickup_open", 128),
        ("self_test", 256),
    ] {
        dev(&["start"]);
        assert_eq!(ask(&bit.to_string()), format!("latched {name}"));
        std::thread::sleep(Duration::from_millis(300));
        let st = dev(&["status"]);
        assert_eq!(st["faults"], serde_json::json!([name]), "{name}");
        assert_eq!(st["running"], false, "{name}");
        dev(&["reset-faults"]);
        assert_eq!(dev(&["status"])["faults"], serde_json::json!([]), "{name}");
    }
}
