//! Running `fricctl` from a test.

use assert_cmd::Command;
use serde_json::Value;

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
