//! Running `fricctl` from a test.

use assert_cmd::Command;
use serde_json::Value;

/// The README's physical scene (`integration_tests::physical_scene`):
/// μ0 = 0.3, kz = 2e6 N/m, kx = 1.5e6 N/m, uz0 = 5 µm, Δuz = 2 µm,
/// Δux = 0.7 µm, 40 kHz, φ = 50°; W0 = μ0 kz uz0/kx = 2 µm.
pub const PHYS: &[&str] = &[
    "--mu0",
    "0.3",
    "--kz",
    "2e6",
    "--kx",
    "1.5e6",
    "--uz0",
    "5e-6",
    "--duz",
    "2e-6",
    "--dux",
    "0.7e-6",
    "--freq",
    "40e3",
    "--phi-deg",
    "50",
];

/// The `fricctl` binary of this build.
pub fn fricctl() -> Command {
    Command::cargo_bin("fricctl").unwrap()
}

/// Runs `fricctl args` and asserts it succeeded (its stderr in the failure
/// message).
pub fn run_ok(args: &[&str]) -> std::process::Output {
    let out = fricctl().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// `fricctl args --json` (`--json` added unless present), asserted to
/// succeed, its stdout parsed.
pub fn json(args: &[&str]) -> Value {
    let out = if args.contains(&"--json") {
        run_ok(args)
    } else {
        run_ok(&[args, &["--json"]].concat())
    };
    serde_json::from_slice(&out.stdout).unwrap()
}

/// One data line of a CSV file `fricctl` wrote, its cells found by the
/// header's column names (shown as the line itself).
pub struct CsvRow {
    line: String,
    header: std::rc::Rc<Vec<String>>,
}

impl CsvRow {
    /// The cell in column `k` (panics if there is none).
    pub fn get(&self, k: &str) -> &str {
        let col = self.header.iter().position(|h| h == k).unwrap();
        self.line.split(',').nth(col).unwrap()
    }

    /// The cell in column `k` as a number.
    pub fn num(&self, k: &str) -> f64 {
        self.get(k).parse().unwrap()
    }
}

impl std::fmt::Display for CsvRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.line)
    }
}

/// The data lines (after the header) of the CSV file at `path`.
pub fn csv_rows(path: &std::path::Path) -> Vec<CsvRow> {
    let body = std::fs::read_to_string(path).unwrap();
    let mut lines = body.lines();
    let header = std::rc::Rc::new(
        lines
            .next()
            .unwrap()
            .split(',')
            .map(String::from)
            .collect::<Vec<_>>(),
    );
    lines
        .map(|l| CsvRow {
            line: l.to_string(),
            header: header.clone(),
        })
        .collect()
}
