//! The virtual device served on a real pty by `fricctl sim-device --pty`, and
//! `fricctl device --port PTY --json` against it.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command as StdCommand, Stdio};

use assert_cmd::cargo::CommandCargoExt;
use serde_json::Value;

use super::cli::fricctl;

/// A running `sim-device --pty` (killed on drop).
pub struct Sim {
    /// The process.
    pub child: Child,
    /// The pty's path (the TCP address of a `--tcp` sim).
    pub path: String,
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `sim-device --pty --seconds 600` with the default plant and ideal
/// transducers ([`spawn`]). The limit is a safety net only (the device is
/// killed on drop): a loaded machine stretched a 6 s test past 120 s.
pub fn sim() -> Sim {
    sim_with(&[], 600)
}

/// `sim-device --pty --seconds SECONDS` with the plant flags `plant`.
pub fn sim_with(plant: &[&str], seconds: u32) -> Sim {
    let s = spawn(&[&["--pty", "--seconds", &seconds.to_string()][..], plant].concat());
    assert!(s.path.starts_with("/dev/"), "{}", s.path);
    s
}

/// The flags that choose resonant transducers.
const RESONANT_FLAGS: &[&str] = &[
    "--plant-resonance-z",
    "--plant-q-z",
    "--plant-resonance-x",
    "--plant-q-x",
    "--plant-gain-z",
    "--plant-gain-x",
    "--plant-resonance-drift-z",
    "--plant-resonance-drift-x",
    "--plant-thermal-shift",
    "--plant-crosstalk",
    "--plant-load-q",
];

/// `sim-device ARGS`; [`Sim::path`] is the first line it prints (the pty's
/// path, or the TCP address with `--tcp`). Ideal transducers
/// (`--plant-ideal-transducers`, the board in voltage mode is then exact)
/// unless ARGS name a resonant flag or `--resonant-default` (the
/// virtual device's own default, resonant; not passed on).
pub fn spawn(args: &[&str]) -> Sim {
    let resonant = args
        .iter()
        .any(|a| RESONANT_FLAGS.contains(a) || *a == "--resonant-default");
    let args: Vec<&str> = args
        .iter()
        .copied()
        .filter(|a| *a != "--resonant-default")
        .collect();
    let ideal: &[&str] = if resonant {
        &[]
    } else {
        &["--plant-ideal-transducers"]
    };
    let mut child = StdCommand::cargo_bin("fricctl")
        .unwrap()
        .arg("sim-device")
        .args(&args)
        .args(ideal)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let path = line.trim().to_string();
    Sim { child, path }
}

/// `fricctl device --port PTY --json ARGS`.
pub fn dev(s: &Sim, args: &[&str]) -> std::process::Output {
    fricctl()
        .args(["device", "--port", &s.path, "--json"])
        .args(args)
        .output()
        .unwrap()
}

/// [`dev`], asserted to succeed, its JSON parsed.
pub fn ok_json(s: &Sim, args: &[&str]) -> Value {
    let o = dev(s, args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}
